#include "indoorloc/core/random.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace indoorloc {
namespace {

TEST(RandomStream, SameSeedSameSequenceDifferentStreamsDiffer) {
  RandomStream a(42, 3), b(42, 3), c(42, 4), d(43, 3);
  int equal_c = 0, equal_d = 0;
  for (int k = 0; k < 1000; ++k) {
    const auto x = a();
    EXPECT_EQ(x, b());
    equal_c += x == c();
    equal_d += x == d();
  }
  EXPECT_EQ(equal_c, 0);
  EXPECT_EQ(equal_d, 0);
}

TEST(RandomStream, KnownFirstOutputIsStableAcrossBuilds) {
  // Guards against accidental changes of the generator or the seeding: results published with
  // a seed must stay reproducible across versions.
  RandomStream r(0, 0);
  const auto first = r();
  RandomStream again(0, 0);
  EXPECT_EQ(first, again());
  EXPECT_NE(first, 0u);
}

TEST(RandomStream, UniformMomentsAndRange) {
  RandomStream r(1);
  const int n = 200000;
  double sum = 0.0, sum_sq = 0.0;
  for (int k = 0; k < n; ++k) {
    const double u = r.Uniform01();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
    sum_sq += u * u;
  }
  EXPECT_NEAR(sum / n, 0.5, 5 * std::sqrt(1.0 / 12 / n));
  EXPECT_NEAR(sum_sq / n - std::pow(sum / n, 2), 1.0 / 12, 2e-3);
  for (int k = 0; k < 1000; ++k) EXPECT_GT(r.UniformOpen01(), 0.0);
}

TEST(RandomStream, NormalMoments) {
  RandomStream r(2);
  const int n = 200000;
  double sum = 0.0, sum_sq = 0.0, sum_4 = 0.0;
  for (int k = 0; k < n; ++k) {
    const double z = r.Normal(1.5, 2.0);
    sum += z;
    sum_sq += (z - 1.5) * (z - 1.5);
    sum_4 += std::pow((z - 1.5) / 2.0, 4);
  }
  EXPECT_NEAR(sum / n, 1.5, 5 * 2.0 / std::sqrt(n));
  EXPECT_NEAR(sum_sq / n, 4.0, 0.05);
  EXPECT_NEAR(sum_4 / n, 3.0, 0.1);  // kurtosis of a Gaussian
}

TEST(RandomStream, ZigguratNormalMatchesTheNormalDistribution) {
  RandomStream rng(17);
  const int n = 1000000;
  std::vector<double> x(n);
  double mean = 0.0, m2 = 0.0, m4 = 0.0;
  for (double& v : x) {
    v = rng.NormalZiggurat();
    mean += v / n;
  }
  for (double v : x) {
    m2 += (v - mean) * (v - mean) / n;
    m4 += std::pow(v - mean, 4) / n;
  }
  EXPECT_NEAR(mean, 0.0, 0.005);
  EXPECT_NEAR(m2, 1.0, 0.005);
  EXPECT_NEAR(m4, 3.0, 0.03);
  // Kolmogorov-Smirnov against the normal CDF: D < 1.63 / sqrt(n) at the 1 % level.
  std::sort(x.begin(), x.end());
  double d = 0.0;
  for (int i = 0; i < n; ++i) {
    const double cdf = 0.5 * std::erfc(-x[i] / std::sqrt(2.0));
    d = std::max({d, std::abs(cdf - static_cast<double>(i) / n), std::abs(cdf - static_cast<double>(i + 1) / n)});
  }
  EXPECT_LT(d, 1.63 / std::sqrt(static_cast<double>(n)));
  // The tail beyond R = 3.44 has the right mass (2.88e-4 on each side), to 10 %.
  const double tail = static_cast<double>(std::count_if(x.begin(), x.end(), [](double v) { return v > 3.442619855899; })) / n;
  EXPECT_NEAR(tail, 0.5 * std::erfc(3.442619855899 / std::sqrt(2.0)), 0.1 * 2.88e-4 + 5e-5);
}

TEST(RandomStream, UniformIntIsUniformAndInRange) {
  RandomStream r(3);
  std::vector<int> counts(7, 0);
  const int n = 70000;
  for (int k = 0; k < n; ++k) ++counts[r.UniformInt(7)];
  for (int c : counts) EXPECT_NEAR(c, n / 7.0, 5 * std::sqrt(n / 7.0));
  EXPECT_THROW(r.UniformInt(0), std::invalid_argument);
}

TEST(RandomStream, VonMisesMeanResultantLength) {
  // For von Mises(mu, kappa), E[cos(theta - mu)] = I1(kappa) / I0(kappa).
  const double kPi = 3.14159265358979323846;
  for (double kappa : {0.5, 2.0, 10.0}) {
    RandomStream r(4);
    const double mu = 1.0;
    const int n = 100000;
    double c = 0.0, s = 0.0;
    for (int k = 0; k < n; ++k) {
      const double theta = r.VonMises(mu, kappa);
      ASSERT_GT(theta, -kPi - 1e-12);
      ASSERT_LE(theta, kPi + 1e-12);
      c += std::cos(theta - mu);
      s += std::sin(theta - mu);
    }
    const double expected = std::cyl_bessel_i(1.0, kappa) / std::cyl_bessel_i(0.0, kappa);
    EXPECT_NEAR(c / n, expected, 0.01) << "kappa " << kappa;
    EXPECT_NEAR(s / n, 0.0, 0.01) << "kappa " << kappa;
  }
  RandomStream r(5);
  EXPECT_THROW(r.VonMises(0.0, -1.0), std::invalid_argument);
}

TEST(RandomStream, SplitGivesIndependentReproducibleChildren) {
  RandomStream a(9), b(9);
  RandomStream ca = a.Split(1), cb = b.Split(1);
  for (int k = 0; k < 100; ++k) EXPECT_EQ(ca(), cb());
  RandomStream parent(9);
  RandomStream c1 = parent.Split(1);
  RandomStream parent2(9);
  RandomStream c2 = parent2.Split(2);
  EXPECT_NE(c1(), c2());
}

TEST(RandomStream, WorksWithStdShuffle) {
  std::vector<int> v(20);
  for (int k = 0; k < 20; ++k) v[k] = k;
  std::vector<int> w = v;
  RandomStream r1(11), r2(11);
  std::shuffle(v.begin(), v.end(), r1);
  std::shuffle(w.begin(), w.end(), r2);
  EXPECT_EQ(v, w);
}

// Issue 17: κ above about 3e16 made algorithm VM loop forever (r = 1 + 1/(2κ) rounds to 1).
// Above kVonMisesNormalKappa the draw is the normal limit, variance 1/κ.
TEST(RandomStream, VonMisesHugeKappaReturnsTheNormalLimit) {
  RandomStream r(1);
  // sd 1/sqrt(κ) relative to the mean 0.5 must stay above double precision for the variance
  // to be measurable: 1e300 (sd 1e-150) returns the mean itself.
  EXPECT_EQ(r.VonMises(0.5, 1e300), 0.5);
  for (const double kappa : {1e11, 1e17, 1e24}) {
    const int n = 20000;
    double sum = 0.0, sum2 = 0.0;
    for (int k = 0; k < n; ++k) {
      const double x = r.VonMises(0.5, kappa);
      ASSERT_TRUE(std::isfinite(x));
      sum += x - 0.5;
      sum2 += (x - 0.5) * (x - 0.5);
    }
    const double var = sum2 / n - (sum / n) * (sum / n);
    EXPECT_NEAR(var * kappa, 1.0, 0.05) << kappa;
  }
  // Both sides of the switch give the same spread.
  double below = 0.0, above = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const double a = r.VonMises(0.0, 0.99 * kVonMisesNormalKappa), b = r.VonMises(0.0, 1.01 * kVonMisesNormalKappa);
    below += a * a;
    above += b * b;
  }
  EXPECT_NEAR(below / above, 1.02, 0.05);
}

TEST(RandomStream, VonMisesRejectsANonFiniteMean) {
  RandomStream r(1);
  EXPECT_THROW(r.VonMises(std::nan(""), 1.0), std::invalid_argument);
  EXPECT_THROW(r.VonMises(INFINITY, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc
