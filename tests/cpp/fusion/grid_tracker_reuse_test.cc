// Tests of what the grid tracker reuses between trackers and runs: GridTracker::WithOptions (a
// tracker with other options on the same grid, equal bit for bit to one built afresh) and the
// buffers runs keep for later runs (GridTracker::ReleaseKeptMemory, KeptMemoryBytes).
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "indoorloc/fusion/grid_tracker.h"

#include "grid_fixtures.h"

namespace indoorloc::fusion {
namespace {

// A walk east along y = 10 past the shop of Hall(true), with three fixes.
std::vector<StepInput> Walk() {
  std::vector<StepInput> steps;
  for (int k = 0; k < 40; ++k) steps.push_back(StepFromPolar(0.5 * (k + 1), 0.7, 0.0, 0.05, 0.05));
  return steps;
}
const std::vector<PositionFix> kFixes = {Fix(0.4, 5.0, 10.0, 3.0), Fix(9.0, 17.0, 10.0, 3.0),
                                         Fix(19.0, 31.0, 11.0, 3.0)};

// Survey positions every 3 m over x <= 24 (the fixes beyond are anchored to its edge).
RowMatrixXd Survey() {
  std::vector<Eigen::Vector2d> p;
  for (double x = 1.5; x <= 24.0; x += 3.0)
    for (double y = 1.5; y < 40.0; y += 3.0) p.emplace_back(x, y);
  RowMatrixXd out(static_cast<Eigen::Index>(p.size()), 2);
  for (std::size_t i = 0; i < p.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = p[i].transpose();
  return out;
}

GridTrackerOptions Base() {
  GridTrackerOptions o;
  o.cell_size_m = 0.7;        // cells across the shop's walls: fractions strictly between 0 and 1
  o.walkable_subsamples = 3;  // fractions n / 9: not exact in float, recovered exactly
  o.heading_offset_sd_rad = 0.1;
  o.heading_offset_bins = 3;
  o.fix_survey_distance_factor = 0.75;
  o.spatial_median = true;
  return o;
}

void ExpectSameRun(const GridTracker& a, const GridTracker& b, const char* what) {
  for (bool known : {false, true}) {
    TrackStart start;
    if (known) {
      start.known = true;
      start.position_m = Eigen::Vector2d(1.0, 10.0);
      start.time_s = 0.0;
    }
    const GridTrackResult x = a.Run(Walk(), kFixes, start, true), y = b.Run(Walk(), kFixes, start, true);
    EXPECT_EQ(x.filtered_mean_m, y.filtered_mean_m) << what;
    EXPECT_EQ(x.filtered_covariance_m2, y.filtered_covariance_m2) << what;
    EXPECT_EQ(x.filtered_median_m, y.filtered_median_m) << what;
    EXPECT_EQ(x.smoothed_mean_m, y.smoothed_mean_m) << what;
    EXPECT_EQ(x.smoothed_median_m, y.smoothed_median_m) << what;
    EXPECT_EQ(x.heading_offset_probabilities, y.heading_offset_probabilities) << what;
    EXPECT_EQ(x.summary.log_evidence, y.summary.log_evidence) << what;
  }
}

TEST(GridTrackerReuseTest, WithOptionsEqualsATrackerBuiltAfresh) {
  const FloorPlan plan = Hall(true);
  const RowMatrixXd survey = Survey();
  const Eigen::VectorXi floors = Eigen::VectorXi::Zero(survey.rows());
  const GridTracker base = GridTracker(&plan, Base()).WithSurveyPositions(survey, floors);
  GridTrackerOptions walls = Base(), beta = Base(), layers = Base(), none = Base();
  walls.wall_log_penalty = -1.5;         // the wall factors recomputed
  beta.fix_survey_distance_factor = 0.3;  // the anchors recomputed
  layers.heading_offset_bins = 5;         // nothing recomputed
  layers.spatial_median = false;
  none.fix_survey_distance_factor = 1.0;  // no anchors: the cell centres
  for (const auto& [o, what] : {std::pair{walls, "walls"}, std::pair{beta, "beta"}, std::pair{layers, "layers"},
                                std::pair{none, "none"}}) {
    const GridTracker fresh = GridTracker(&plan, o).WithSurveyPositions(survey, floors);
    const GridTracker derived = base.WithOptions(o);
    EXPECT_EQ(derived.options().wall_log_penalty, o.wall_log_penalty);
    EXPECT_EQ(derived.WalkableFraction(0), fresh.WalkableFraction(0)) << what;
    ExpectSameRun(derived, fresh, what);
  }
  // Back from β = 1 to 0.75: the survey positions were kept, so the anchors come back.
  ExpectSameRun(base.WithOptions(none).WithOptions(Base()), base, "back");
}

TEST(GridTrackerReuseTest, WithOptionsRefusesAnotherGridAndInvalidOptions) {
  const FloorPlan plan = Hall(true);
  const GridTracker base(&plan, Base());
  auto message = [&](const GridTrackerOptions& o) {
    try {
      base.WithOptions(o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  GridTrackerOptions cells = Base(), sub = Base(), margin = Base(), bad = Base();
  cells.cell_size_m = 2.0;
  sub.walkable_subsamples = 4;
  margin.wall_margin_m = 0.5;
  bad.fix_survey_distance_factor = 2.0;
  for (const GridTrackerOptions& o : {cells, sub, margin}) EXPECT_NE(message(o).find("grid"), std::string::npos);
  EXPECT_NE(message(bad).find("fix_survey_distance_factor"), std::string::npos);
}

TEST(GridTrackerReuseTest, KeptMemoryIsReleasedAndResultsDoNotDependOnIt) {
  const FloorPlan plan = Hall(true);
  const GridTracker tracker(&plan, Base());
  GridTracker::ReleaseKeptMemory();
  const GridTrackResult first = tracker.Run(Walk(), kFixes, TrackStart(), true);
  const double kept = GridTracker::KeptMemoryBytes();
  EXPECT_GT(kept, 0.0);  // the smoother's store and the layers' slots, kept for the next run
  EXPECT_LE(kept, GridTracker::kept_memory_limit_bytes);
  const GridTrackResult reused = tracker.Run(Walk(), kFixes, TrackStart(), true);  // on the kept buffers
  const double before = GridTracker::KeptMemoryBytes();
  EXPECT_GE(before, kept);
  EXPECT_EQ(GridTracker::ReleaseKeptMemory(), before);
  EXPECT_EQ(GridTracker::KeptMemoryBytes(), 0.0);
  EXPECT_EQ(GridTracker::ReleaseKeptMemory(), 0.0);
  const GridTrackResult fresh = tracker.Run(Walk(), kFixes, TrackStart(), true);  // on fresh buffers
  for (const GridTrackResult* r : {&reused, &fresh}) {
    EXPECT_EQ(r->filtered_mean_m, first.filtered_mean_m);
    EXPECT_EQ(r->smoothed_mean_m, first.smoothed_mean_m);
    EXPECT_EQ(r->smoothed_median_m, first.smoothed_median_m);
  }
  // With layers on several threads, the workers' stores come from (and go back to) the same pool.
  GridTrackerOptions threaded = Base();
  threaded.num_threads = 3;
  const GridTrackResult parallel = GridTracker(&plan, threaded).Run(Walk(), kFixes, TrackStart(), true);
  EXPECT_EQ(parallel.smoothed_mean_m, first.smoothed_mean_m);
  EXPECT_GT(GridTracker::KeptMemoryBytes(), 0.0);
  GridTracker::ReleaseKeptMemory();
}

}  // namespace
}  // namespace indoorloc::fusion
