// Tests of the cells the survey opens (GridTrackerOptions::survey_walkable_radius_m,
// survey_walkable_min_walks): the wall factor against a brute force, a walk along the survey
// through a drawn obstacle, radius 0 is the plan as drawn, one walk does not open where two are
// needed, WithOptions equals a fresh tracker, and the options' checks.
#include <cmath>
#include <set>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "indoorloc/core/random.h"
#include "indoorloc/fusion/grid_tracker.h"

#include "grid_fixtures.h"
#include "grid_ops.h"

namespace indoorloc::fusion {
namespace {

// A survey line through the hall's shop (x 20..30, y 20..30) at y = 25, every metre from x 10 to 40.
RowMatrixXd SurveyThroughShop() {
  RowMatrixXd p(31, 2);
  for (int i = 0; i <= 30; ++i) p.row(i) << 10.0 + i, 25.0;
  return p;
}

GridTrackerOptions Options(double radius_m) {
  GridTrackerOptions o;
  o.heading_offset_sd_rad = 0.0;
  o.wall_log_penalty = -3.0;
  o.fix_survey_distance_factor = 1.0;  // fixes at the cell centres: only the walls differ
  o.survey_walkable_radius_m = radius_m;
  return o;
}

TEST(GridSurveyWalkableTest, WallFactorIsThatOfABruteForce) {
  // Random walkable fractions and survey points of 6 walks (or none given: each point its own
  // walk); every cell against a count of the distinct walks within the radius of its centre.
  RandomStream rng(11);
  for (const double c : {1.0, 0.5, 2.0}) {
    for (const double r : {0.0, 0.7, 1.5, 3.0}) {
      for (const int min_walks : {1, 2, 3}) {
        for (const bool ids : {true, false}) {
          grid_ops::FloorGrid g;
          g.x0 = -2.0;
          g.y0 = 1.0;
          g.nx = static_cast<int>(40 / c);
          g.ny = static_cast<int>(30 / c);
          const int n_sub = 3;
          for (std::size_t i = 0; i < g.size(); ++i)
            g.walkable_fraction.push_back(static_cast<float>(static_cast<int>(rng.Uniform(0.0, 10.0)) % 10) / 9.0f);
          for (int i = 0; i < 120; ++i) {
            g.survey_points.emplace_back(rng.Uniform(-8.0, 45.0), rng.Uniform(-5.0, 38.0));
            if (ids) g.survey_walks.push_back(static_cast<int>(rng.Uniform(-1.0, 6.0)));  // -1: opens nothing
          }
          // Far off the grid (no cell within reach; no integer overflow).
          g.survey_points.emplace_back(1e12, -3e15);
          if (ids) g.survey_walks.push_back(2);
          const double penalty = std::exp(-1.0);
          grid_ops::ComputeWallFactors(penalty, n_sub, r, min_walks, c, &g);
          ASSERT_EQ(g.wall_factor.size(), g.size());
          for (int y = 0; y < g.ny; ++y)
            for (int x = 0; x < g.nx; ++x) {
              const std::size_t i = static_cast<std::size_t>(y) * g.nx + x;
              std::set<int> walks;
              for (std::size_t k = 0; k < g.survey_points.size(); ++k) {
                const Eigen::Vector2d& p = g.survey_points[k];
                const double dx = g.x0 + (x + 0.5) * c - p.x(), dy = g.y0 + (y + 0.5) * c - p.y();
                if (ids && g.survey_walks[k] < 0) continue;
                if (r > 0 && dx * dx + dy * dy <= r * r) walks.insert(ids ? g.survey_walks[k] : -1 - static_cast<int>(k));
              }
              const float plan = grid_ops::WallFactor(static_cast<int>(std::lround(g.walkable_fraction[i] * 9.0f)),
                                                      n_sub, penalty);
              const bool open = static_cast<int>(walks.size()) >= min_walks && !walks.empty();
              ASSERT_EQ(g.wall_factor[i], open ? 1.0f : plan)
                  << "cell " << x << ", " << y << ", c " << c << ", r " << r << ", min walks " << min_walks;
            }
        }
      }
    }
  }
}

TEST(GridSurveyWalkableTest, OneWalkDoesNotOpenWhereTwoAreNeeded) {
  // The same survey line through the shop, from one walk or from two: with min_walks 2 only the
  // two walks' line opens the shop (the walk's evidence rises as with min_walks 1).
  const FloorPlan plan = Hall(/*shop=*/true);
  std::vector<StepInput> steps;
  for (int k = 0; k < 20; ++k) steps.push_back(StepFromPolar(0.5 * (k + 1), 1.0, 0.0, 0.05, 0.05));
  const std::vector<PositionFix> fixes = {Fix(0.4, 15.0, 25.0, 1.0), Fix(10.1, 35.0, 25.0, 1.0)};
  RowMatrixXd twice(62, 2);
  twice << SurveyThroughShop(), SurveyThroughShop();
  const Eigen::VectorXi floors = Eigen::VectorXi::Zero(62);
  Eigen::VectorXi one_walk = Eigen::VectorXi::Zero(62), two_walks = Eigen::VectorXi::Zero(62);
  two_walks.tail(31).setOnes();
  GridTrackerOptions o = Options(1.0);
  o.survey_walkable_min_walks = 2;
  const GridTracker t(&plan, o);
  const double one = t.WithSurveyPositions(twice, floors, one_walk).Run(steps, fixes, TrackStart(), true).summary.log_evidence;
  const double two = t.WithSurveyPositions(twice, floors, two_walks).Run(steps, fixes, TrackStart(), true).summary.log_evidence;
  const double drawn = GridTracker(&plan, Options(0.0)).Run(steps, fixes, TrackStart(), true).summary.log_evidence;
  const double open1 = GridTracker(&plan, Options(1.0)).WithSurveyPositions(twice, floors, one_walk)
                           .Run(steps, fixes, TrackStart(), true).summary.log_evidence;
  EXPECT_EQ(one, drawn);
  EXPECT_EQ(two, open1);
  EXPECT_GT(two, one + 10.0);
  // walk_ids of another length: an error naming it.
  try {
    t.WithSurveyPositions(twice, floors, Eigen::VectorXi::Zero(5));
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("walk_ids"), std::string::npos) << e.what();
  }
}

TEST(GridSurveyWalkableTest, AWalkAlongTheSurveyThroughADrawnShop) {
  // The walker crosses the shop along the survey line (y = 25), seen by fixes at both ends.
  // Drawn as is, the shop costs λ = -3 a step: the smoother bends the walk around it. Opened by
  // the survey, it crosses.
  const FloorPlan plan = Hall(/*shop=*/true);
  std::vector<StepInput> steps;
  for (int k = 0; k < 20; ++k) steps.push_back(StepFromPolar(0.5 * (k + 1), 1.0, 0.0, 0.05, 0.05));
  const std::vector<PositionFix> fixes = {Fix(0.4, 15.0, 25.0, 1.0), Fix(10.1, 35.0, 25.0, 1.0)};
  const RowMatrixXd survey = SurveyThroughShop();
  const Eigen::VectorXi floors = Eigen::VectorXi::Zero(survey.rows());
  const GridTrackResult drawn =
      GridTracker(&plan, Options(0.0)).WithSurveyPositions(survey, floors).Run(steps, fixes, TrackStart(), true);
  const GridTrackResult opened =
      GridTracker(&plan, Options(1.0)).WithSurveyPositions(survey, floors).Run(steps, fixes, TrackStart(), true);
  const GridTrackResult plain = GridTracker(&plan, Options(0.0)).Run(steps, fixes, TrackStart(), true);
  // Radius 0: the plan as drawn, bit for bit.
  EXPECT_EQ(drawn.smoothed_mean_m, plain.smoothed_mean_m);
  EXPECT_EQ(drawn.summary.log_evidence, plain.summary.log_evidence);
  // Mid-walk (x about 25): opened, on the line; drawn, pushed off it towards a shop side.
  const int mid = 10;
  EXPECT_NEAR(opened.smoothed_mean_m(mid, 1), 25.0, 1.0);
  EXPECT_GT(std::abs(drawn.smoothed_mean_m(mid, 1) - 25.0), std::abs(opened.smoothed_mean_m(mid, 1) - 25.0) + 1.0);
  EXPECT_GT(opened.summary.log_evidence, drawn.summary.log_evidence + 10.0);
}

TEST(GridSurveyWalkableTest, WithOptionsEqualsAFreshTracker) {
  const FloorPlan plan = Hall(/*shop=*/true);
  std::vector<StepInput> steps;
  for (int k = 0; k < 12; ++k) steps.push_back(StepFromPolar(0.5 * (k + 1), 1.0, 0.3, 0.05, 0.05));
  const std::vector<PositionFix> fixes = {Fix(0.4, 18.0, 25.0, 2.0), Fix(6.1, 27.0, 27.0, 2.0)};
  const RowMatrixXd survey = SurveyThroughShop();
  const Eigen::VectorXi floors = Eigen::VectorXi::Zero(survey.rows());
  const GridTracker base = GridTracker(&plan, Options(0.0)).WithSurveyPositions(survey, floors);
  for (const double r : {0.0, 1.0, 2.5}) {
    for (const double lambda : {-3.0, -1.0}) {
      GridTrackerOptions o = Options(r);
      o.wall_log_penalty = lambda;
      o.survey_walkable_min_walks = r > 2 ? 2 : 1;
      const GridTrackResult a = base.WithOptions(o).Run(steps, fixes, TrackStart(), true);
      const GridTrackResult b = GridTracker(&plan, o).WithSurveyPositions(survey, floors).Run(steps, fixes, TrackStart(), true);
      EXPECT_EQ(a.smoothed_mean_m, b.smoothed_mean_m) << r << " " << lambda;
      EXPECT_EQ(a.summary.log_evidence, b.summary.log_evidence) << r << " " << lambda;
    }
  }
}

TEST(GridSurveyWalkableTest, TheRadiusIsChecked) {
  const FloorPlan plan = Hall();
  for (const double bad : {-1.0, std::nan(""), 1e6}) {
    try {
      GridTracker(&plan, Options(bad));
      ADD_FAILURE() << "no error for " << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("survey_walkable_radius_m"), std::string::npos) << e.what();
    }
  }
  GridTrackerOptions o = Options(1.0);
  o.survey_walkable_min_walks = 0;
  try {
    GridTracker(&plan, o);
    ADD_FAILURE() << "no error for min walks 0";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("survey_walkable_min_walks"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace indoorloc::fusion
