#include "indoorloc/core/random_lanes.h"

#include <cmath>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include "indoorloc/core/random.h"

namespace indoorloc {
namespace {

TEST(RandomLanes, EachLaneIsAnXoshiroStreamOfTheFamily) {
  RandomLanes lanes(42, 7);
  std::vector<double> out(3 * RandomLanes::kLanes);
  lanes.FillUniform01(out.data(), static_cast<int>(out.size()));
  for (int j = 0; j < RandomLanes::kLanes; ++j) {
    RandomStream reference(DeriveSeed(42, 7), static_cast<std::uint64_t>(j));
    for (int r = 0; r < 3; ++r) {
      const std::uint64_t bits = (reference() >> 12) | 0x3FF0000000000000ULL;
      double unit;
      std::memcpy(&unit, &bits, sizeof(unit));
      EXPECT_EQ(out[static_cast<size_t>(r * RandomLanes::kLanes + j)], unit - 1.0) << "lane " << j << " round " << r;
    }
  }
}

TEST(RandomLanes, SameSeedSameNumbersAndPartialRoundsAreDiscarded) {
  RandomLanes a(1), b(1), c(2);
  std::vector<double> x(13), y(16), z(13);
  a.FillUniform01(x.data(), 13);
  b.FillUniform01(y.data(), 16);
  c.FillUniform01(z.data(), 13);
  for (int k = 0; k < 13; ++k) EXPECT_EQ(x[k], y[k]);
  EXPECT_NE(x, z);
  // a discarded the last 3 outputs of its second round: both are now at round 2.
  a.FillUniform01(x.data(), 8);
  b.FillUniform01(y.data(), 8);
  for (int k = 0; k < 8; ++k) EXPECT_EQ(x[k], y[k]);
}

TEST(RandomLanes, FillCentredIsTheTransformOfTheSameDraws) {
  // 21 outputs: two whole rounds and a partial one (its last 3 outputs discarded by both).
  RandomLanes a(9, 1), b(9, 1);
  const double mean = 1.25, halfwidth = 0.6;
  std::vector<double> u(21), d(21);
  a.FillUniform01(u.data(), 21);
  b.FillCentred(d.data(), 21, mean, halfwidth);
  for (int k = 0; k < 21; ++k) {
    EXPECT_EQ(d[k], mean + (2.0 * halfwidth * u[k] - halfwidth)) << "output " << k;  // the same bits
    EXPECT_GE(d[k], mean - halfwidth);
    EXPECT_LT(d[k], mean + halfwidth);
  }
  // Both streams are at the same round afterwards.
  a.FillUniform01(u.data(), 8);
  b.FillUniform01(d.data(), 8);
  for (int k = 0; k < 8; ++k) EXPECT_EQ(u[k], d[k]);
}

TEST(RandomLanes, UniformMomentsAndRange) {
  RandomLanes lanes(3);
  const int n = 400000;
  std::vector<double> u(n);
  lanes.FillUniform01(u.data(), n);
  double mean = 0.0, second = 0.0, lag_product = 0.0;
  for (int k = 0; k < n; ++k) {
    ASSERT_GE(u[k], 0.0);
    ASSERT_LT(u[k], 1.0);
    mean += u[k] / n;
    second += u[k] * u[k] / n;
    if (k > 0) lag_product += (u[k] - 0.5) * (u[k - 1] - 0.5) / (n - 1);
  }
  // Standard errors: mean 0.00046, E[u^2] 0.00047, neighbour covariance 0.00013.
  EXPECT_NEAR(mean, 0.5, 0.003);
  EXPECT_NEAR(second, 1.0 / 3.0, 0.003);
  EXPECT_NEAR(lag_product, 0.0, 0.001);  // neighbours come from different lanes: uncorrelated
}

// The vectorised ziggurat: a standard normal (moments, tail mass, the distribution function at a
// few points within a few standard errors), reproducible, and its slow path drawing from the
// fallback stream only (the lanes advance by whole rounds, as FillUniform01).
TEST(RandomLanes, FillNormalIsStandardNormalAndReproducible) {
  RandomLanes lanes(5, 2);
  RandomStream fallback(6);
  const int n = 800000;
  std::vector<double> z(n);
  lanes.FillNormal(z.data(), n, fallback);
  double mean = 0.0, second = 0.0, fourth = 0.0;
  int beyond3 = 0, below_m1 = 0, below_half = 0;
  for (int k = 0; k < n; ++k) {
    ASSERT_TRUE(std::isfinite(z[k]));
    mean += z[k] / n;
    second += z[k] * z[k] / n;
    fourth += z[k] * z[k] * z[k] * z[k] / n;
    beyond3 += std::abs(z[k]) > 3.0;
    below_m1 += z[k] < -1.0;
    below_half += z[k] < 0.5;
  }
  // Standard errors: mean 0.0011, E[z^2] 0.0016, E[z^4] 0.011; P(|z| > 3) = 0.0027 (se 5.8e-5);
  // Phi(-1) = 0.158655 (se 0.00041), Phi(0.5) = 0.691462 (se 0.00052).
  EXPECT_NEAR(mean, 0.0, 0.006);
  EXPECT_NEAR(second, 1.0, 0.008);
  EXPECT_NEAR(fourth, 3.0, 0.06);
  EXPECT_NEAR(static_cast<double>(beyond3) / n, 0.0026998, 0.0003);
  EXPECT_NEAR(static_cast<double>(below_m1) / n, 0.158655, 0.002);
  EXPECT_NEAR(static_cast<double>(below_half) / n, 0.691462, 0.0026);

  // Same seeds, same numbers, also in pieces of whole rounds (the slow path's draws from the
  // fallback come in the order of the outputs).
  RandomLanes a(5, 2), b(5, 2);
  RandomStream fa(6), fb(6);
  std::vector<double> whole(16), part(16);
  a.FillNormal(whole.data(), 16, fa);
  b.FillNormal(part.data(), 8, fb);
  b.FillNormal(part.data() + 8, 8, fb);
  for (int k = 0; k < 16; ++k) EXPECT_EQ(whole[k], part[k]);
}

}  // namespace
}  // namespace indoorloc
