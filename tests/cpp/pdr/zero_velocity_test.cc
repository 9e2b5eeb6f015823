// DetectZeroVelocity (fixed and stance-guard rules) and CountStrides on synthetic gaits.
#include "indoorloc/pdr/zero_velocity.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "indoorloc/pdr/stride_count.h"
#include "synthetic_gait.h"

namespace indoorloc::pdr {
namespace {

using synthetic::Gait;
using synthetic::MakeGait;

// The gait with the foot rocking at `rate_radps` about its x axis through every stance (a rest
// that is never fully still, as when running): the SHOE statistic of stance is then about
// rate² / σ_ω² (3e4 at 0.3 rad/s with the default σ_ω of 0.1°/s).
Gait RockingGait(double rate_radps) {
  Gait g = MakeGait(10, 0.0, 0.0, 3);
  for (Eigen::Index k = 0; k < g.time.size(); ++k) {
    if (g.gyro.row(k).norm() == 0.0 && k > 150) g.gyro(k, 0) = rate_radps;  // stance after the first rest
  }
  return g;
}

TEST(ZeroVelocity, FixedRuleIsTheShoeDetector) {
  const Gait g = MakeGait(6, 0.2, 0.01, 1);
  ZeroVelocityOptions o;
  o.rule = ZeroVelocityRule::kFixed;
  const ZeroVelocityOutput out = DetectZeroVelocity(g.acc, g.gyro, 200.0, o);
  EXPECT_EQ(out.stance, ShoeDetector(g.acc, g.gyro, o.shoe));
  EXPECT_DOUBLE_EQ(out.summary.threshold, o.shoe.threshold);
  EXPECT_FALSE(out.summary.guard_raised);
}

TEST(ZeroVelocity, GuardRaisesTheThresholdWhenTheStanceIsNeverStill) {
  const Gait g = RockingGait(0.3);
  ZeroVelocityOptions fixed;
  fixed.rule = ZeroVelocityRule::kFixed;
  fixed.shoe.threshold = 1e4;
  const ZeroVelocityOutput lost = DetectZeroVelocity(g.acc, g.gyro, 200.0, fixed);
  EXPECT_LT(lost.summary.walking_stance_fraction, 0.05);  // the failure: almost no stance
  ZeroVelocityOptions guard = fixed;  // base 1e4
  guard.rule = ZeroVelocityRule::kStanceGuard;
  guard.min_stance_fraction = 0.3;
  const ZeroVelocityOutput found = DetectZeroVelocity(g.acc, g.gyro, 200.0, guard);
  EXPECT_TRUE(found.summary.guard_raised);
  EXPECT_GT(found.summary.threshold, 1e4);
  EXPECT_GE(found.summary.walking_stance_fraction, 0.3);
  // On a still stance the guard has nothing to do.
  const Gait still = MakeGait(10, 0.0, 0.0, 3);
  EXPECT_FALSE(DetectZeroVelocity(still.acc, still.gyro, 200.0, guard).summary.guard_raised);
  // The cap holds.
  guard.max_threshold = 2e4;
  EXPECT_DOUBLE_EQ(DetectZeroVelocity(g.acc, g.gyro, 200.0, guard).summary.threshold, 2e4);
}

TEST(ZeroVelocity, SwingGuardClimbsUntilNoStanceIsMissed) {
  // Stance never still (0.3 rad/s tremor: T ~ 3e4 in stance): at 1e4 every stance is missed
  // and the walk is one long swing; the guard climbs the ladder until each stance is found.
  const Gait g = RockingGait(0.3);
  ZeroVelocityOptions o;  // swing guard, base 1e4
  ASSERT_EQ(o.rule, ZeroVelocityRule::kSwingGuard);
  const ZeroVelocityOutput out = DetectZeroVelocity(g.acc, g.gyro, 200.0, o);
  EXPECT_TRUE(out.summary.guard_raised);
  EXPECT_TRUE(out.summary.guard_satisfied);
  EXPECT_GT(out.summary.threshold, 2.95e4);
  EXPECT_LE(out.summary.threshold, 1e4 * std::pow(10.0, 0.25 * out.summary.ladder_rungs) * (1 + 1e-12));
  EXPECT_LE(out.summary.max_swing_s, 1.0);
  EXPECT_NEAR(out.summary.median_swing_s, 0.6, 0.1);
  // A still gait keeps the base threshold.
  const Gait still = MakeGait(10, 0.0, 0.0, 3);
  const ZeroVelocityOutput base = DetectZeroVelocity(still.acc, still.gyro, 200.0, o);
  EXPECT_FALSE(base.summary.guard_raised);
  EXPECT_EQ(base.summary.ladder_rungs, 0);
  // With a cap below the stance level no rung is accepted: the guard says so, the low-motion
  // rule was tried, and the threshold stays within the cap.
  o.max_threshold = 2e4;
  const ZeroVelocityOutput capped = DetectZeroVelocity(g.acc, g.gyro, 200.0, o);
  EXPECT_FALSE(capped.summary.guard_satisfied);
  EXPECT_TRUE(capped.summary.low_motion_rule);
  EXPECT_LE(capped.summary.threshold, 2e4);
  EXPECT_THROW(DetectZeroVelocity(g.acc, g.gyro, 0.0, o), std::invalid_argument);
}

TEST(ZeroVelocity, OptionsAreChecked) {
  const Gait g = MakeGait(2, 0.0, 0.0, 1);
  ZeroVelocityOptions o;
  o.min_stance_fraction = 1.0;
  EXPECT_THROW(DetectZeroVelocity(g.acc, g.gyro, 200.0, o), std::invalid_argument);
  o = ZeroVelocityOptions();
  o.max_threshold = o.shoe.threshold;
  EXPECT_THROW(DetectZeroVelocity(g.acc, g.gyro, 200.0, o), std::invalid_argument);
  o = ZeroVelocityOptions();
  o.shoe.window = 0;
  EXPECT_THROW(DetectZeroVelocity(g.acc, g.gyro, 200.0, o), std::invalid_argument);
  o = ZeroVelocityOptions();
  o.max_swing_ratio = 1.0;
  EXPECT_THROW(DetectZeroVelocity(g.acc, g.gyro, 200.0, o), std::invalid_argument);
  o = ZeroVelocityOptions();
  o.max_swing_s = 0.0;
  EXPECT_THROW(DetectZeroVelocity(g.acc, g.gyro, 200.0, o), std::invalid_argument);
}

// A recording whose SHOE statistic is the given piecewise-constant T (W = 5, σ_ω = 0.1°/s):
// gravity on z, the body turning about x at ω = sqrt(T) σ_ω. Blocks are (T, samples).
Gait StatisticBlocks(const std::vector<std::pair<double, int>>& blocks) {
  int n = 0;
  for (const auto& b : blocks) n += b.second;
  Gait g;
  g.acc = RowMatrixXd::Zero(n, 3);
  g.acc.col(2).setConstant(9.81);
  g.gyro = RowMatrixXd::Zero(n, 3);
  const double sigma = ShoeOptions().sigma_gyro_radps;
  int k = 0;
  for (const auto& [t, length] : blocks) {
    for (int i = 0; i < length; ++i) g.gyro(k++, 0) = std::sqrt(t) * sigma;
  }
  return g;
}

TEST(ZeroVelocity, RefusesRungsWhoseSwingsAreShorterThanAnyHumanSwing) {
  // 200 Hz, 12 strides: stances of 1 s alternately still (T = 3e4) and rocking hard (3e6),
  // swings of 0.7 s at T = 1e6 with a 30 ms peak (2e7) in the middle: the statistic of a slow
  // shuffle. The old ladder stops where only the peaks remain "swing" (30 ms swings, stance
  // ~98 %): a walk traded for a standstill.
  std::vector<std::pair<double, int>> blocks{{1e2, 400}};
  for (int i = 0; i < 12; ++i) {
    blocks.push_back({1e6, 67});
    blocks.push_back({2e7, 6});
    blocks.push_back({1e6, 67});
    blocks.push_back({i % 2 == 0 ? 3e4 : 3e6, 200});
  }
  blocks.push_back({1e2, 400});
  const Gait g = StatisticBlocks(blocks);
  ZeroVelocityOptions old_rule;
  old_rule.min_plausible_swing_s = 0.0;
  const ZeroVelocityOutput old_out = DetectZeroVelocity(g.acc, g.gyro, 200.0, old_rule);
  EXPECT_TRUE(old_out.summary.guard_satisfied);
  EXPECT_LE(old_out.summary.median_swing_s, 0.05);  // 10 samples: the peak widened by the window
  EXPECT_GT(old_out.summary.stance_fraction, 0.95);
  const ZeroVelocityOutput out = DetectZeroVelocity(g.acc, g.gyro, 200.0, ZeroVelocityOptions());
  EXPECT_GE(out.summary.median_swing_s, 0.2);
  EXPECT_LT(out.summary.stance_fraction, 0.9);
  EXPECT_LT(out.summary.threshold, old_out.summary.threshold);
}

TEST(ZeroVelocity, StanceFlickerInsideASwingIsDroppedFromTheOutput) {
  // Stances alternately still (3e4) and trembling (3e5): the guard climbs to >= 3e5. Each swing
  // (T = 1e6) has two 5-sample dips to 5e3 (SHOE's mid-swing blind spot), 3 samples below the
  // threshold after the window: flicker for the guard, and now no zero-velocity update for the
  // filter either.
  std::vector<std::pair<double, int>> blocks{{1e2, 400}};
  for (int i = 0; i < 8; ++i) {
    blocks.push_back({1e6, 44});
    blocks.push_back({5e3, 5});
    blocks.push_back({1e6, 44});
    blocks.push_back({5e3, 5});
    blocks.push_back({1e6, 42});
    blocks.push_back({i % 2 == 0 ? 3e4 : 3e5, 200});
  }
  blocks.push_back({1e2, 400});
  const Gait g = StatisticBlocks(blocks);
  const ZeroVelocityOutput out = DetectZeroVelocity(g.acc, g.gyro, 200.0, ZeroVelocityOptions());
  EXPECT_TRUE(out.summary.guard_satisfied);
  EXPECT_FALSE(out.summary.low_motion_rule);
  EXPECT_GT(out.summary.threshold, 3e5);
  EXPECT_NEAR(out.summary.median_swing_s, 0.7, 0.05);
  EXPECT_EQ(CountStrides(out.stance, 200.0).summary.n_flicker_stances, 0);
  const Eigen::Index raw = (out.statistic.array() < out.summary.threshold).count();
  EXPECT_EQ(raw - out.stance.count(), 8 * 2 * 3);  // exactly the dips were dropped
}

BoolVector Pattern(const std::vector<std::pair<bool, int>>& runs) {
  int n = 0;
  for (const auto& r : runs) n += r.second;
  BoolVector s(n);
  int k = 0;
  for (const auto& [value, length] : runs) {
    for (int i = 0; i < length; ++i) s[k++] = value;
  }
  return s;
}

TEST(CountStrides, MergesFlickerAndKeepsShortSwingsOfASlowWalk) {
  // 100 Hz: rest, then swings of 0.6 s with stance flicker inside one swing and a swing flicker
  // (0.05 s) inside one stance.
  const BoolVector s = Pattern({{true, 100}, {false, 30}, {true, 1}, {false, 29}, {true, 40}, {false, 5}, {true, 40},
                                {false, 60}, {true, 40}, {false, 60}, {true, 100}});
  const StrideCountOutput out = CountStrides(s, 100.0);
  EXPECT_EQ(out.summary.n_strides, 3);
  EXPECT_EQ(out.summary.n_flicker_stances, 1);
  EXPECT_EQ(out.summary.n_flicker_swings, 1);
  EXPECT_NEAR(out.summary.median_swing_s, 0.6, 1e-9);
  // A slow walk whose swings are above the detector's threshold for 0.15 s only: all kept.
  const BoolVector slow = Pattern({{true, 100}, {false, 15}, {true, 80}, {false, 15}, {true, 80}, {false, 15}, {true, 80},
                                   {false, 14}, {true, 100}});
  EXPECT_EQ(CountStrides(slow, 100.0).summary.n_strides, 4);
}

TEST(CountStrides, SplitsASwingThatHidesMissedStances) {
  const BoolVector s = Pattern({{true, 50}, {false, 40}, {true, 10}, {false, 40}, {true, 10}, {false, 120}, {true, 10},
                                {false, 40}, {true, 50}});
  const StrideCountOutput out = CountStrides(s, 100.0);
  EXPECT_EQ(out.summary.n_strides, 6);  // the 120-sample swing holds 3 strides
  EXPECT_EQ(out.summary.n_split_strides, 2);
  StrideCountOptions o;
  o.long_swing_factor = 0.0;
  EXPECT_EQ(CountStrides(s, 100.0, o).summary.n_strides, 4);
  o.long_swing_factor = 0.5;
  EXPECT_THROW(CountStrides(s, 100.0, o), std::invalid_argument);
  EXPECT_THROW(CountStrides(s, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::pdr
