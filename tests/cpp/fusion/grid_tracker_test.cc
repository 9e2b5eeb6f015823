// Tests of the grid tracker: dead reckoning from a known start, a single fix placing an unknown
// start, the smoother carrying a late fix back along the walk, the heading-offset posterior,
// determinism over thread counts, walls, and the errors it promises.
#include "indoorloc/fusion/grid_tracker.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "grid_fixtures.h"

namespace indoorloc::fusion {
namespace {

// Steps of length L every 0.5 s along heading h [rad] in the PDR frame.
std::vector<StepInput> Straight(int n, double length_m, double heading_rad, double t0 = 0.0) {
  std::vector<StepInput> s;
  for (int k = 0; k < n; ++k) s.push_back(StepFromPolar(t0 + 0.5 * (k + 1), length_m, heading_rad, 0.05, 0.05));
  return s;
}

// Options whose returned covariances are the posterior's own (scale 1, no floor, no fix-distance
// or fix-sd term), heading offset known: the reference the calibration tests compare against.
GridTrackerOptions PosteriorCovarianceOptions() {
  GridTrackerOptions o;
  o.heading_offset_sd_rad = 0.0;
  o.filtered_covariance_scale = o.smoothed_covariance_scale = 1.0;
  o.filtered_covariance_floor_m = o.smoothed_covariance_floor_m = 0.0;
  o.filtered_covariance_fix_gain = o.smoothed_covariance_fix_gain = 0.0;
  o.filtered_covariance_fix_sd_gain = o.smoothed_covariance_fix_sd_gain = 0.0;
  return o;
}

// The same steps and fixes from an unknown start, smoothed, run with the `raw` and the
// `calibrated` options: the pair (raw result, calibrated result).
std::pair<GridTrackResult, GridTrackResult> RunRawAndCalibrated(const FloorPlan& plan, const GridTrackerOptions& raw,
                                                                const GridTrackerOptions& calibrated,
                                                                const std::vector<StepInput>& steps,
                                                                const std::vector<PositionFix>& fixes) {
  return {GridTracker(&plan, raw).Run(steps, fixes, TrackStart(), true),
          GridTracker(&plan, calibrated).Run(steps, fixes, TrackStart(), true)};
}

TEST(GridTrackerTest, KnownStartFollowsTheSteps) {
  const FloorPlan plan = Hall();
  GridTrackerOptions o;
  o.heading_offset_sd_rad = 0.0;  // offset known
  const GridTracker tracker(&plan, o);
  TrackStart start;
  start.known = true;
  start.position_m = Eigen::Vector2d(10, 20);
  start.time_s = 0.0;
  const auto steps = Straight(20, 0.7, 0.0);
  const GridTrackResult r = tracker.Run(steps, {}, start, true);
  ASSERT_EQ(r.filtered_mean_m.rows(), 20);
  for (int k = 0; k < 20; ++k) {
    EXPECT_NEAR(r.filtered_mean_m(k, 0), 10 + 0.7 * (k + 1), 0.05) << k;
    EXPECT_NEAR(r.filtered_mean_m(k, 1), 20, 0.05) << k;
    EXPECT_NEAR(r.smoothed_mean_m(k, 0), r.filtered_mean_m(k, 0), 0.05) << k;
  }
  // The spread grows with the steps' noise (no fixes).
  EXPECT_GT(r.filtered_posterior_covariance_m2(19, 0), r.filtered_posterior_covariance_m2(0, 0));
  EXPECT_NEAR(r.smoothed_floor_probabilities[0], 1.0, 1e-12);
}

TEST(GridTrackerTest, UnknownStartPlacedByOneFix) {
  const FloorPlan plan = Hall();
  GridTrackerOptions o;
  o.heading_offset_sd_rad = 0.0;
  o.fix.tempering = 1.0;
  o.fix.outlier_probability = 1e-6;  // the Gaussian part alone (the uniform part adds its own spread)
  const GridTracker tracker(&plan, o);
  const auto steps = Straight(4, 0.7, 0.0);
  const GridTrackResult r = tracker.Run(steps, {Fix(0.5, 30, 15, 3.0)}, TrackStart(), true);
  // After the fix (attached to the first step) the posterior is the fix's Gaussian, its variance
  // that of the fix plus the within-cell spread (1/12 m²) and the first step's noise.
  EXPECT_NEAR(r.filtered_mean_m(0, 0), 30, 0.05);
  EXPECT_NEAR(r.filtered_mean_m(0, 1), 15, 0.05);
  EXPECT_NEAR(r.filtered_posterior_covariance_m2(0, 0), 9.0 + 1.0 / 12.0, 0.3);
  EXPECT_NEAR(r.filtered_posterior_covariance_m2(0, 1), 0.0, 0.05);
  // Later steps move the mean by the steps.
  EXPECT_NEAR(r.filtered_mean_m(3, 0) - r.filtered_mean_m(0, 0), 2.1, 0.1);
}

TEST(GridTrackerTest, SmootherCarriesALateFixBack) {
  const FloorPlan plan = Hall();
  GridTrackerOptions o;
  o.heading_offset_sd_rad = 0.0;
  o.fix.tempering = 1.0;
  const GridTracker tracker(&plan, o);
  const auto steps = Straight(30, 0.7, M_PI / 2);  // north, 21 m
  const GridTrackResult r = tracker.Run(steps, {Fix(15.0, 40, 30, 1.0)}, TrackStart(), true);
  // Before the fix the filter knows nothing: its mean is near the hall's centre.
  EXPECT_GT(r.filtered_posterior_covariance_m2(5, 0), 50.0);
  // The smoother puts the first step 20.3 m south of the fix (29 steps of 0.7 m back).
  EXPECT_NEAR(r.smoothed_mean_m(0, 0), 40, 0.5);
  EXPECT_NEAR(r.smoothed_mean_m(0, 1), 30 - 0.7 * 29, 0.7);
  EXPECT_NEAR(r.smoothed_mean_m(29, 1), 30, 0.5);
}

TEST(GridTrackerTest, ReturnedCovarianceIsCalibratedByTheFixDistance) {
  const FloorPlan plan = Hall();
  GridTrackerOptions raw = PosteriorCovarianceOptions();
  raw.fix.tempering = 1.0;
  GridTrackerOptions o = raw;
  o.filtered_covariance_scale = 2.0;
  o.filtered_covariance_floor_m = 1.5;
  o.filtered_covariance_fix_gain = 0.5;
  o.smoothed_covariance_scale = 3.0;
  o.smoothed_covariance_floor_m = 0.5;
  o.smoothed_covariance_fix_gain = 0.25;
  const auto steps = Straight(30, 0.7, M_PI / 2);
  // Two fixes 10 m apart (weights 1 and 3: centre 7.5 m along) at 3 s, one at 12 s.
  RowMatrixXd two_means(2, 2);
  two_means << 20, 10, 30, 10;
  const PositionFix two = MixtureFix(3.0, two_means, Eigen::VectorXd::Constant(2, 2.0), Eigen::Vector2d(1.0, 3.0));
  const std::vector<PositionFix> fixes = {two, Fix(12.0, 25, 25, 2.0)};
  const auto [a, b] = RunRawAndCalibrated(plan, raw, o, steps, fixes);
  // Estimates and the posterior's own spread do not change; d is 0 before the first fix.
  EXPECT_EQ(a.filtered_mean_m, b.filtered_mean_m);
  EXPECT_EQ(a.filtered_covariance_m2, b.filtered_posterior_covariance_m2);
  EXPECT_EQ(a.smoothed_covariance_m2, b.smoothed_posterior_covariance_m2);
  EXPECT_EQ(a.filtered_covariance_m2, a.filtered_posterior_covariance_m2);
  const Eigen::Vector2d c1(27.5, 10), c2(25, 25);
  for (int k = 0; k < 30; ++k) {
    const double t = steps[k].time_s;
    const Eigen::Vector2d fm = b.filtered_mean_m.row(k).transpose();
    const double df = t < 3.0 ? 0.0 : ((t < 12.0 ? c1 : c2) - fm).norm();
    EXPECT_NEAR(b.filtered_fix_distance_m[k], df, 1e-9) << k;
    const double iso_f = 1.5 * 1.5 + 0.25 * df * df;
    EXPECT_NEAR(b.filtered_covariance_m2(k, 0), 2.0 * a.filtered_covariance_m2(k, 0) + iso_f, 1e-9) << k;
    EXPECT_NEAR(b.filtered_covariance_m2(k, 1), 2.0 * a.filtered_covariance_m2(k, 1), 1e-9) << k;
    const Eigen::Vector2d sm = b.smoothed_mean_m.row(k).transpose();
    const double ds = ((std::abs(t - 3.0) <= std::abs(t - 12.0) ? c1 : c2) - sm).norm();
    EXPECT_NEAR(b.smoothed_fix_distance_m[k], ds, 1e-9) << k;
    EXPECT_NEAR(b.smoothed_covariance_m2(k, 2),
                3.0 * a.smoothed_covariance_m2(k, 2) + 0.25 + 0.0625 * ds * ds, 1e-9) << k;
  }
  GridTrackerOptions bad;
  bad.smoothed_covariance_scale = 0.0;
  std::string error;
  EXPECT_FALSE(bad.IsValid(&error));
  EXPECT_NE(error.find("smoothed_covariance_scale"), std::string::npos) << error;
}

TEST(GridTrackerTest, ReturnedCovarianceGrowsWithTheFixSdAboveTheKnee) {
  const FloorPlan plan = Hall();
  const GridTrackerOptions raw = PosteriorCovarianceOptions();
  GridTrackerOptions o = raw;  // only the fix-sd term
  o.filtered_covariance_fix_sd_gain = 0.5;
  o.smoothed_covariance_fix_sd_gain = 2.0;
  o.covariance_fix_sd_knee_m = 4.0;
  const auto steps = Straight(30, 0.7, M_PI / 2);
  // A sharp fix (sd 2 m, below the knee: adds nothing) at 3 s; at 12 s a poor one whose
  // components have sds 6 and 12 m (weights 3 and 1: s = 7.5 m) and a padding component
  // (weight 0, sd 100 m) that must not count.
  RowMatrixXd poor_means(3, 2);
  poor_means << 25, 25, 27, 25, 0, 0;
  const PositionFix poor =
      MixtureFix(12.0, poor_means, Eigen::Vector3d(6.0, 12.0, 100.0), Eigen::Vector3d(3.0, 1.0, 0.0));
  const std::vector<PositionFix> fixes = {Fix(3.0, 20, 10, 2.0), poor};
  const auto [a, b] = RunRawAndCalibrated(plan, raw, o, steps, fixes);
  EXPECT_EQ(a.filtered_mean_m, b.filtered_mean_m);
  EXPECT_EQ(a.smoothed_mean_m, b.smoothed_mean_m);
  int poor_steps = 0;
  for (int k = 0; k < 30; ++k) {
    const double t = steps[k].time_s;
    const double sf = t < 3.0 ? 0.0 : (t < 12.0 ? 2.0 : 7.5);  // the last fix applied
    const double ss = std::abs(t - 3.0) <= std::abs(t - 12.0) ? 2.0 : 7.5;  // the nearest in time
    EXPECT_NEAR(b.filtered_fix_sd_m[k], sf, 1e-12) << k;
    EXPECT_NEAR(b.smoothed_fix_sd_m[k], ss, 1e-12) << k;
    const double ef = 0.5 * std::max(0.0, sf - 4.0), es = 2.0 * std::max(0.0, ss - 4.0);
    EXPECT_NEAR(b.filtered_covariance_m2(k, 0), a.filtered_covariance_m2(k, 0) + ef * ef, 1e-9) << k;
    EXPECT_NEAR(b.filtered_covariance_m2(k, 1), a.filtered_covariance_m2(k, 1), 1e-9) << k;
    EXPECT_NEAR(b.smoothed_covariance_m2(k, 2), a.smoothed_covariance_m2(k, 2) + es * es, 1e-9) << k;
    if (sf > 4.0) {
      ++poor_steps;
      EXPECT_GT(b.filtered_covariance_m2(k, 0), a.filtered_covariance_m2(k, 0) + 3.0) << k;
    } else {
      EXPECT_EQ(b.filtered_covariance_m2(k, 0), a.filtered_covariance_m2(k, 0)) << k;
    }
  }
  EXPECT_GT(poor_steps, 0);
  GridTrackerOptions bad;
  bad.covariance_fix_sd_knee_m = -1.0;
  std::string error;
  EXPECT_FALSE(bad.IsValid(&error));
  EXPECT_NE(error.find("covariance_fix_sd_knee_m"), std::string::npos) << error;
}

TEST(GridTrackerTest, HeadingOffsetLearntFromFixes) {
  const FloorPlan plan = Hall();
  GridTrackerOptions o;
  o.heading_offset_bins = 21;
  o.heading_offset_sd_rad = 0.3;
  o.fix.tempering = 1.0;
  const GridTracker tracker(&plan, o);
  // PDR says east; the truth is 0.3 rad to the left of it: fixes along the true line.
  const double truth = 0.3;
  const auto steps = Straight(40, 0.7, 0.0);
  std::vector<PositionFix> fixes;
  for (int k = 4; k <= 40; k += 4) {
    const double d = 0.7 * k;
    fixes.push_back(Fix(0.5 * k, 10 + d * std::cos(truth), 10 + d * std::sin(truth), 1.5));
  }
  const GridTrackResult r = tracker.Run(steps, fixes, TrackStart(), true);
  EXPECT_NEAR(r.heading_offset_rad, truth, 0.06);
  EXPECT_LT(r.heading_offset_sd_rad, 0.1);
  EXPECT_NEAR(r.heading_offset_probabilities.sum(), 1.0, 1e-9);
}

TEST(GridTrackerTest, SameResultForAnyThreadCount) {
  const FloorPlan plan = Hall(true, 2);
  GridTrackerOptions o;
  o.heading_offset_bins = 5;
  o.scale_bins = 3;
  std::vector<PositionFix> fixes = {Fix(1.0, 10, 10, 4.0, 1), Fix(3.0, 12, 10, 4.0, 1)};
  const auto steps = Straight(10, 0.7, 0.0);
  o.num_threads = 1;
  const GridTrackResult a = GridTracker(&plan, o).Run(steps, fixes, TrackStart(), true);
  o.num_threads = 3;
  const GridTrackResult b = GridTracker(&plan, o).Run(steps, fixes, TrackStart(), true);
  EXPECT_EQ(a.filtered_mean_m, b.filtered_mean_m);
  EXPECT_EQ(a.smoothed_mean_m, b.smoothed_mean_m);
  EXPECT_EQ(a.smoothed_floor_probabilities, b.smoothed_floor_probabilities);
  // The fixes name floor 1: it must win.
  EXPECT_GT(a.smoothed_floor_probabilities[1], 0.95);
}

TEST(GridTrackerTest, WallsKeepTheTrackOutOfTheShop) {
  const FloorPlan plan = Hall(true);
  GridTrackerOptions o;
  o.heading_offset_sd_rad = 0.0;
  o.wall_log_penalty = -std::numeric_limits<double>::infinity();
  o.fix.tempering = 1.0;
  const GridTracker tracker(&plan, o);
  // A fix in the middle of the shop: the posterior mass lies outside it.
  const GridTrackResult r = tracker.Run(Straight(2, 0.7, 0.0), {Fix(0.5, 25, 25, 3.0)}, TrackStart(), false);
  const double x = r.filtered_mean_m(0, 0), y = r.filtered_mean_m(0, 1);
  const double spread = std::sqrt(r.filtered_posterior_covariance_m2(0, 0) + r.filtered_posterior_covariance_m2(0, 2));
  EXPECT_GT(spread, 4.0);  // the mass is around the shop, not at its centre
  (void)x;
  (void)y;
  const RowMatrixXd a = tracker.WalkableFraction(0);
  EXPECT_EQ(a(25, 25), 0.0);
  EXPECT_EQ(a(5, 5), 1.0);
  // A known start inside the shop with hard walls cannot have worked: it says so.
  TrackStart start;
  start.known = true;
  start.position_m = Eigen::Vector2d(25, 25);
  GridTrackerOptions narrow = o;
  narrow.start_position_sd_m = 0.1;  // e^-1250 at the shop's edge: nothing walkable
  EXPECT_THROW(GridTracker(&plan, narrow).Run(Straight(2, 0.7, 0.0), {}, start, false), std::runtime_error);
}

TEST(GridTrackerTest, SmootherGapsFallBackToTheFilterAndAreCounted) {
  // A walker standing still, seen by ten tight fixes at x = 10 and then ten at x = 50: the
  // fixes' outlier floors multiply, so the forward message keeps nothing near x = 50 before the
  // switch and the backward message nothing near x = 10 after it. Where they share no cell the
  // smoother has no estimate: the filtered one stands in (finite, not the grid's origin), and the
  // summary counts those steps.
  const FloorPlan plan = Hall();
  GridTrackerOptions o;
  o.heading_offset_sd_rad = 0.0;
  o.fix.outlier_probability = 1e-3;
  const GridTracker tracker(&plan, o);
  std::vector<StepInput> steps;
  std::vector<PositionFix> fixes;
  for (int k = 0; k < 20; ++k) {
    const double t = 0.5 * (k + 1);
    fixes.push_back(Fix(t - 0.1, k < 10 ? 10.0 : 50.0, 20.0, 1.0));
    steps.push_back(StepFromPolar(t, 0.0, 0.0, 0.01, 0.01));
  }
  const GridTrackResult r = tracker.Run(steps, fixes, TrackStart(), true);
  EXPECT_GT(r.summary.smoother_gap_steps, 0);
  EXPECT_NE(r.summary.BriefReport().find("smoother gap steps"), std::string::npos);
  for (int k = 0; k < 20; ++k) {
    ASSERT_TRUE(std::isfinite(r.smoothed_mean_m(k, 0))) << k;
    EXPECT_GT(r.smoothed_mean_m(k, 0), 5.0) << k;  // never the grid's origin
  }
  // A consistent walk has none.
  std::vector<PositionFix> same;
  for (const PositionFix& f : fixes) same.push_back(Fix(f.time_s, 30.0, 20.0, 1.0));
  EXPECT_EQ(tracker.Run(steps, same, TrackStart(), true).summary.smoother_gap_steps, 0);
}

TEST(GridTrackerTest, ErrorsNameTheArgument) {
  const FloorPlan plan = Hall();
  GridTrackerOptions o;
  o.cell_size_m = -1;
  EXPECT_THROW(GridTracker(&plan, o), std::invalid_argument);
  o = GridTrackerOptions();
  o.cell_size_m = 0.05;
  o.max_memory_bytes = 1e6;
  try {
    GridTracker(&plan, o);
    FAIL() << "a grid above the memory limit was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_memory_bytes"), std::string::npos) << e.what();
  }
  const GridTracker tracker(&plan, GridTrackerOptions());
  EXPECT_THROW(tracker.Run({}, {}, TrackStart(), false), std::invalid_argument);
  auto steps = Straight(3, 0.7, 0.0);
  steps[2].time_s = 0.1;
  EXPECT_THROW(tracker.Run(steps, {}, TrackStart(), false), std::invalid_argument);
  TrackStart start;
  start.known = true;
  start.floor = 7;
  EXPECT_THROW(tracker.Run(Straight(3, 0.7, 0.0), {}, start, false), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::fusion
