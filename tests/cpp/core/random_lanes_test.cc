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

}  // namespace
}  // namespace indoorloc
