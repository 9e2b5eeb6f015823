// Tests of the grid filter session: after every step its estimate equals the batch run's filtered
// output bit for bit (unknown start on two floors with a shop, fixes between and at step times;
// known start with steps before it; several fixes at one step; scale bins; spatial-median option;
// calibrated covariances),
// whatever the thread count; events out of time order are refused with both times named and
// leave the session unchanged.
#include "indoorloc/fusion/grid_filter_session.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "indoorloc/core/validate.h"
#include "grid_fixtures.h"

namespace indoorloc::fusion {
namespace {

// A wandering walk: steps every ~0.5 s with slowly turning headings.
std::vector<StepInput> Walk(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> turn(0.0, 0.15), len(0.7, 0.05);
  std::vector<StepInput> s;
  double h = 0.3, t = 1.0;
  for (int k = 0; k < n; ++k) {
    h += turn(rng);
    t += 0.45 + 0.1 * (k % 3);
    s.push_back(StepFromPolar(t, len(rng), h, 0.1, 0.15));
  }
  return s;
}

// Fixes every ~2 s, two components (one on floor 0, one on floor 1), one at a step's exact time.
std::vector<PositionFix> Fixes(const std::vector<StepInput>& steps) {
  std::vector<PositionFix> out;
  for (std::size_t k = 2; k < steps.size(); k += 4) {
    PositionFix f;
    f.time_s = (k % 8 == 2) ? steps[k].time_s : steps[k].time_s - 0.2;
    f.means_m.resize(2, 2);
    const double kd = static_cast<double>(k);
    f.means_m << 10.0 + 0.5 * kd, 12.0 + 0.2 * kd, 40.0, 8.0;
    f.sds_m = Eigen::Vector2d(3.0, 5.0);
    f.weights = Eigen::Vector2d(0.8, 0.2);
    f.floors = Eigen::Vector2i(0, 1);
    out.push_back(f);
    if (k == 10) {  // a second fix applied at the same step
      PositionFix g = f;
      g.time_s = f.time_s + 0.05;
      out.push_back(g);
    }
  }
  return out;
}

// Feeds steps and fixes in the batch's order (a fix before the first step at or after its time;
// fixes after the last step left out) and checks every estimate against the batch's.
void ExpectSessionEqualsBatch(const GridTracker& tracker, const std::vector<StepInput>& steps,
                              const std::vector<PositionFix>& fixes, const TrackStart& start) {
  const GridTrackResult batch = tracker.Run(steps, fixes, start, false);
  GridFilterSession session(&tracker, start);
  std::size_t j = 0;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    while (j < fixes.size() && fixes[j].time_s <= steps[k].time_s) session.AddFix(fixes[j++]);
    const GridFilterEstimate e = session.AddStep(steps[k]);
    ASSERT_EQ(e.steps, static_cast<int>(k + 1));
    EXPECT_EQ(e.time_s, batch.times_s[k]);
    // Exact equality: the same operations in the same order.
    EXPECT_EQ(e.mean_m.x(), batch.filtered_mean_m(k, 0)) << "step " << k;
    EXPECT_EQ(e.mean_m.y(), batch.filtered_mean_m(k, 1)) << "step " << k;
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(e.covariance_m2[i], batch.filtered_covariance_m2(k, i)) << "step " << k;
      EXPECT_EQ(e.posterior_covariance_m2[i], batch.filtered_posterior_covariance_m2(k, i)) << "step " << k;
    }
    EXPECT_EQ(e.fix_distance_m, batch.filtered_fix_distance_m[k]) << "step " << k;
    EXPECT_EQ(e.fix_sd_m, batch.filtered_fix_sd_m[k]) << "step " << k;
    ASSERT_EQ(e.floor_probabilities.size(), batch.filtered_floor_probabilities.cols());
    for (int f = 0; f < e.floor_probabilities.size(); ++f)
      EXPECT_EQ(e.floor_probabilities[f], batch.filtered_floor_probabilities(k, f)) << "step " << k;
    EXPECT_EQ(e.heading_offset_rad, batch.filtered_heading_offset_rad[k]) << "step " << k;
  }
  EXPECT_EQ(session.Estimate().mean_m, session.Estimate().mean_m);
  EXPECT_EQ(session.Summary().log_evidence, batch.summary.log_evidence);
  EXPECT_EQ(session.Summary().fixes, batch.summary.fixes);
}

TEST(GridFilterSessionTest, UnknownStartEqualsBatchFilterOnTwoFloors) {
  const FloorPlan plan = Hall(/*shop=*/true, 2);
  GridTrackerOptions o;
  o.heading_offset_bins = 5;
  o.heading_offset_sd_rad = 0.2;
  for (int threads : {1, 3}) {
    o.num_threads = threads;
    const GridTracker tracker(&plan, o);
    const auto steps = Walk(60, 7);
    ExpectSessionEqualsBatch(tracker, steps, Fixes(steps), TrackStart());
  }
}

TEST(GridFilterSessionTest, KnownStartScaleBinsAndMediansEqualBatch) {
  const FloorPlan plan = Hall(/*shop=*/true, 2);
  GridTrackerOptions o;
  o.heading_offset_bins = 3;
  o.scale_bins = 3;
  o.spatial_median = true;  // the batch then sums the moments in double: the session follows
  o.wall_log_penalty = -3.0;
  o.filtered_covariance_scale = 1.7;  // the returned covariance calibrated as the batch's
  o.filtered_covariance_floor_m = 2.0;
  o.filtered_covariance_fix_gain = 0.3;
  o.filtered_covariance_fix_sd_gain = 0.8;  // the fixes' sd is 3.4 m: above the knee
  o.covariance_fix_sd_knee_m = 2.0;
  const GridTracker tracker(&plan, o);
  const auto steps = Walk(40, 11);
  TrackStart start;
  start.known = true;
  start.floor = 1;
  start.position_m = Eigen::Vector2d(8, 10);
  start.time_s = steps[3].time_s + 0.1;  // four steps before the start
  start.heading_offset_rad = 0.1;
  ExpectSessionEqualsBatch(tracker, steps, Fixes(steps), start);
}

TEST(GridFilterSessionTest, TrailingFixWaitsForTheNextStep) {
  const FloorPlan plan = Hall(/*shop=*/true, 1);
  const GridTracker tracker(&plan, GridTrackerOptions());
  const auto steps = Walk(10, 3);
  GridFilterSession session(&tracker);
  for (const auto& s : steps) session.AddStep(s);
  PositionFix f = Fixes(steps)[0];
  f.time_s = steps.back().time_s + 0.3;
  f.floors = Eigen::Vector2i(0, 0);
  session.AddFix(f);
  EXPECT_EQ(session.pending_fixes(), 1);
  EXPECT_EQ(session.Summary().fixes, 0);
}

TEST(GridFilterSessionTest, RefusesEventsOutOfTimeOrder) {
  const FloorPlan plan = Hall(/*shop=*/true, 1);
  const GridTracker tracker(&plan, GridTrackerOptions());
  GridFilterSession session(&tracker);
  EXPECT_THROW(session.Estimate(), std::logic_error);
  const auto steps = Walk(4, 5);
  session.AddStep(steps[1]);
  const GridFilterEstimate before = session.Estimate();
  try {
    session.AddStep(steps[0]);
    FAIL() << "a step back in time was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("'step'"), std::string::npos) << m;
    EXPECT_NE(m.find("out of time order"), std::string::npos) << m;
    EXPECT_NE(m.find(FormatValue(steps[0].time_s)), std::string::npos) << m;
    EXPECT_NE(m.find(FormatValue(steps[1].time_s)), std::string::npos) << m;
  }
  PositionFix f = Fixes(Walk(20, 5))[0];
  f.floors = Eigen::Vector2i(0, 0);
  f.time_s = steps[1].time_s;  // at the latest step's time: belongs to that step, refused
  try {
    session.AddFix(f);
    FAIL() << "a fix at the latest step's time was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("'fix'"), std::string::npos) << m;
    EXPECT_NE(m.find("add it before the step"), std::string::npos) << m;
  }
  f.time_s = steps[2].time_s + 1.0;
  session.AddFix(f);
  EXPECT_THROW(session.AddStep(steps[2]), std::invalid_argument);  // before the latest fix
  f.time_s -= 0.5;
  EXPECT_THROW(session.AddFix(f), std::invalid_argument);          // before the previous fix
  EXPECT_EQ(session.steps(), 1);
  EXPECT_EQ(session.pending_fixes(), 1);
  EXPECT_EQ(session.Estimate().mean_m, before.mean_m);
  StepInput bad = steps[3];
  bad.time_s = std::nan("");
  EXPECT_THROW(session.AddStep(bad), std::invalid_argument);
  EXPECT_THROW(GridFilterSession(nullptr), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::fusion
