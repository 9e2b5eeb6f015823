// Tests that a known start's forward pass on the window of its nonzero cells (grid_window.h)
// gives the whole grid's results bit for bit: every output of GridTracker::Run, with walls, fixes,
// spatial medians, heading-offset and scale bins, near the grid's edge and with the smoother.
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "indoorloc/fusion/grid_tracker.h"
#include "indoorloc/fusion/step_motion.h"

#include "grid_fixtures.h"
#include "grid_window.h"  // test_hooks (internal)

namespace indoorloc::fusion {
namespace {

// East along y = 10 past the shop of Hall(true), north, then west into the hall's west wall (x = 0):
// the window is clipped at the grid's edge, and the shifts go both ways.
// `inside`: the first 70 steps only (east and north: inside the hall).
std::vector<StepInput> Walk(bool inside = false) {
  std::vector<StepInput> steps;
  double t = 0;
  for (int k = 0; k < 50; ++k) steps.push_back(StepFromPolar(t += 0.5, 0.7, 0.0, 0.05, 0.05));
  for (int k = 0; k < 20; ++k) steps.push_back(StepFromPolar(t += 0.5, 0.7, M_PI / 2, 0.05, 0.05));
  if (inside) return steps;
  for (int k = 0; k < 70; ++k) steps.push_back(StepFromPolar(t += 0.5, 0.8, M_PI, 0.05, 0.05));
  return steps;
}
// Fixes on the way, one far off (the filter's support jumps; the smoother may find gaps).
const std::vector<PositionFix> kFixes = {Fix(5.0, 5.0, 10.0, 3.0), Fix(15.0, 20.0, 12.0, 2.0),
                                         Fix(24.0, 36.0, 22.0, 3.0), Fix(40.0, 55.0, 35.0, 1.0),
                                         Fix(60.0, 8.0, 24.0, 3.0)};

GridTrackResult RunWith(bool window, const GridTracker& tracker, const std::vector<PositionFix>& fixes,
                        bool smooth, bool filtered, bool inside = false) {
  TrackStart start;
  start.known = true;
  start.position_m = Eigen::Vector2d(1.2, 10.0);
  start.time_s = 0.2;
  test_hooks::SetKnownStartWindow(window);
  GridTrackResult r = tracker.Run(Walk(inside), fixes, start, smooth, filtered);
  test_hooks::SetKnownStartWindow(true);
  return r;
}

// Equal bit for bit (NaN where the other has the same NaN: the fix distances without fixes).
template <typename M>
::testing::AssertionResult SameBits(const M& a, const M& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return ::testing::AssertionFailure() << "sizes differ";
  if (a.size() > 0 && std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) != 0)
    return ::testing::AssertionFailure() << "values differ:\n" << a << "\nvs\n" << b;
  return ::testing::AssertionSuccess();
}

void ExpectBitIdentical(const GridTrackResult& x, const GridTrackResult& y, const std::string& what) {
  EXPECT_TRUE(SameBits(x.times_s, y.times_s)) << what;
  EXPECT_TRUE(SameBits(x.filtered_mean_m, y.filtered_mean_m)) << what;
  EXPECT_TRUE(SameBits(x.filtered_covariance_m2, y.filtered_covariance_m2)) << what;
  EXPECT_TRUE(SameBits(x.filtered_posterior_covariance_m2, y.filtered_posterior_covariance_m2)) << what;
  EXPECT_TRUE(SameBits(x.filtered_fix_distance_m, y.filtered_fix_distance_m)) << what;
  EXPECT_TRUE(SameBits(x.filtered_fix_sd_m, y.filtered_fix_sd_m)) << what;
  EXPECT_TRUE(SameBits(x.filtered_floor_probabilities, y.filtered_floor_probabilities)) << what;
  EXPECT_TRUE(SameBits(x.filtered_heading_offset_rad, y.filtered_heading_offset_rad)) << what;
  EXPECT_TRUE(SameBits(x.filtered_median_m, y.filtered_median_m)) << what;
  EXPECT_TRUE(SameBits(x.smoothed_mean_m, y.smoothed_mean_m)) << what;
  EXPECT_TRUE(SameBits(x.smoothed_median_m, y.smoothed_median_m)) << what;
  EXPECT_TRUE(SameBits(x.smoothed_covariance_m2, y.smoothed_covariance_m2)) << what;
  EXPECT_TRUE(SameBits(x.smoothed_posterior_covariance_m2, y.smoothed_posterior_covariance_m2)) << what;
  EXPECT_TRUE(SameBits(x.smoothed_fix_distance_m, y.smoothed_fix_distance_m)) << what;
  EXPECT_TRUE(SameBits(x.smoothed_fix_sd_m, y.smoothed_fix_sd_m)) << what;
  EXPECT_TRUE(SameBits(x.smoothed_floor_probabilities, y.smoothed_floor_probabilities)) << what;
  EXPECT_TRUE(SameBits(x.heading_offset_probabilities, y.heading_offset_probabilities)) << what;
  EXPECT_TRUE(SameBits(x.scale_probabilities, y.scale_probabilities)) << what;
  EXPECT_EQ(x.heading_offset_rad, y.heading_offset_rad) << what;
  EXPECT_EQ(x.heading_offset_sd_rad, y.heading_offset_sd_rad) << what;
  EXPECT_EQ(x.scale, y.scale) << what;
  EXPECT_EQ(x.summary.log_evidence, y.summary.log_evidence) << what;
  EXPECT_EQ(x.summary.dead_layers, y.summary.dead_layers) << what;
  EXPECT_EQ(x.summary.smoother_gap_steps, y.summary.smoother_gap_steps) << what;
}

TEST(GridKnownStartWindowTest, EveryOutputEqualsTheWholeGridsBitForBit) {
  const FloorPlan plan = Hall(true, 2);
  for (bool median : {false, true})
    for (double cell : {1.0, 0.7}) {
      GridTrackerOptions o;
      o.cell_size_m = cell;  // 0.7: 86 columns, not a multiple of the 8 lanes
      o.heading_offset_sd_rad = 0.1;
      o.heading_offset_bins = 3;
      o.scale_bins = 3;
      o.spatial_median = median;
      const GridTracker tracker(&plan, o);
      for (const auto& fixes : {kFixes, std::vector<PositionFix>()})
        for (bool smooth : {false, true})
          for (bool filtered : {false, true}) {
            if (!smooth && !filtered) continue;  // the filter always gives its estimates
            const std::string what = "median " + std::to_string(median) + " cell " + std::to_string(cell) +
                                     " fixes " + std::to_string(fixes.size()) + " smooth " +
                                     std::to_string(smooth) + " filtered " + std::to_string(filtered);
            const GridTrackResult full = RunWith(false, tracker, fixes, smooth, filtered);
            const GridTrackResult window = RunWith(true, tracker, fixes, smooth, filtered);
            ASSERT_EQ(full.filtered_mean_m.rows(), static_cast<Eigen::Index>(Walk().size())) << what;
            EXPECT_TRUE((filtered ? full.filtered_mean_m : full.smoothed_mean_m).allFinite()) << what;
            ExpectBitIdentical(full, window, what);
          }
    }
}

// Hard walls (wall_log_penalty -inf): cells ruled out inside the window, and the window's passes
// must still agree with the whole grid's.
TEST(GridKnownStartWindowTest, HardWallsEqualTheWholeGridsBitForBit) {
  const FloorPlan plan = Hall(true);
  GridTrackerOptions o;
  o.wall_log_penalty = -std::numeric_limits<double>::infinity();
  const GridTracker tracker(&plan, o);
  ExpectBitIdentical(RunWith(false, tracker, kFixes, true, true, true), RunWith(true, tracker, kFixes, true, true, true),
                     "hard walls");
}

// A smoother too large to keep every forward grid (more than 256 MB of steps x cells): it keeps
// checkpoints and recomputes each segment's forward grids on the windows recorded the first time.
TEST(GridKnownStartWindowTest, CheckpointedSmootherEqualsTheWholeGridsBitForBit) {
  const FloorPlan plan = Hall(true);
  GridTrackerOptions o;
  o.cell_size_m = 0.2;  // 300 x 200 cells, x 1,100 steps: 66 M floats
  const GridTracker tracker(&plan, o);
  std::vector<StepInput> steps;
  double t = 0;
  for (int k = 0; k < 1100; ++k) {
    const double heading = (k / 100) % 2 == 0 ? 0.0 : M_PI;  // to and fro along y = 10 (x 1 .. 8 m)
    steps.push_back(StepFromPolar(t += 0.5, 0.07, heading, 0.05, 0.05));
  }
  TrackStart start;
  start.known = true;
  start.position_m = Eigen::Vector2d(1.2, 10.0);
  start.time_s = 0.2;
  const std::vector<PositionFix> fixes = {Fix(100.0, 4.0, 10.0, 2.0), Fix(400.0, 5.0, 9.0, 2.0)};
  test_hooks::SetKnownStartWindow(false);
  const GridTrackResult full = tracker.Run(steps, fixes, start, true, false);
  test_hooks::SetKnownStartWindow(true);
  const GridTrackResult window = tracker.Run(steps, fixes, start, true, false);
  EXPECT_GT(full.summary.memory_bytes, 0.0);
  EXPECT_LT(full.summary.memory_bytes, 256e6);  // checkpoints, not every grid
  EXPECT_TRUE(full.smoothed_mean_m.allFinite());
  ExpectBitIdentical(full, window, "checkpointed smoother");
}

}  // namespace
}  // namespace indoorloc::fusion
