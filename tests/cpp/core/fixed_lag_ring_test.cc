#include "indoorloc/core/fixed_lag_ring.h"

#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace indoorloc {
namespace {

// Position of particle i at step k in the tests below.
double X(int i, int k) { return 100.0 * i + k; }
double Y(int i, int k) { return -1000.0 * i - 2.0 * k; }

TEST(FixedLagRing, OffWithoutALag) {
  FixedLagRing ring;
  ring.Reset(10, 0);
  EXPECT_FALSE(ring.enabled());
  ring.Advance();
  EXPECT_FALSE(ring.has_lagged());
  EXPECT_EQ(FixedLagRing::BytesPerParticle(0), 0.0);
  EXPECT_EQ(FixedLagRing::BytesPerParticle(3), 128.0);
}

TEST(FixedLagRing, ReturnsThePositionsLagStepsBack) {
  const int n = 4, lag = 3;
  FixedLagRing ring;
  ring.Reset(n, lag);
  const std::vector<double> w = {0.1, 0.2, 0.3, 0.4};
  for (int k = 0; k < 11; ++k) {
    for (int i = 0; i < n; ++i) ring.Record(i, X(i, k), Y(i, k));
    ring.Advance();
    EXPECT_EQ(ring.steps_recorded(), k + 1);
    ASSERT_EQ(ring.has_lagged(), k >= lag) << "step " << k;
    if (!ring.has_lagged()) continue;
    // Brute force: Σ w_i p_i(k - lag).
    double sx = 0.0, sy = 0.0;
    for (int i = 0; i < n; ++i) {
      sx += w[i] * X(i, k - lag);
      sy += w[i] * Y(i, k - lag);
    }
    const Eigen::Vector2d got = ring.WeightedSum(w.data());
    EXPECT_DOUBLE_EQ(got.x(), sx) << "step " << k;
    EXPECT_DOUBLE_EQ(got.y(), sy) << "step " << k;
  }
}

TEST(FixedLagRing, GatherGivesEachParticleItsAncestorsHistory) {
  const int n = 3, lag = 2;
  FixedLagRing ring;
  ring.Reset(n, lag);
  for (int k = 0; k < 5; ++k) {
    for (int i = 0; i < n; ++i) ring.Record(i, X(i, k), Y(i, k));
    ring.Advance();
  }
  ring.Gather({2, 2, 0});
  // Particle 1 now carries particle 2's history: its lagged position is particle 2's at step 2.
  const std::vector<double> one_hot = {0.0, 1.0, 0.0};
  EXPECT_EQ(ring.WeightedSum(one_hot.data()), Eigen::Vector2d(X(2, 2), Y(2, 2)));
  const std::vector<double> last = {0.0, 0.0, 1.0};
  EXPECT_EQ(ring.WeightedSum(last.data()), Eigen::Vector2d(X(0, 2), Y(0, 2)));
  // The next steps keep the gathered rows.
  for (int i = 0; i < n; ++i) ring.Record(i, X(i, 5), Y(i, 5));
  ring.Advance();
  EXPECT_EQ(ring.WeightedSum(one_hot.data()), Eigen::Vector2d(X(2, 3), Y(2, 3)));
}

TEST(FixedLagRing, RejectsBadSizesAndAncestors) {
  FixedLagRing ring;
  EXPECT_THROW(ring.Reset(-1, 2), std::invalid_argument);
  EXPECT_THROW(ring.Reset(3, -2), std::invalid_argument);
  ring.Reset(3, 2);
  EXPECT_THROW(ring.Gather({0, 1}), std::invalid_argument);
  EXPECT_THROW(ring.Gather({0, 1, 3}), std::invalid_argument);
  EXPECT_THROW(ring.Gather({0, -1, 2}), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc
