// Tests of the grid tracker's survey-anchored fixes (GridTrackerOptions::fix_survey_distance_factor,
// GridTracker::WithSurveyPositions): a survey everywhere changes nothing, a fix at the edge of the
// survey lets the walker be beyond it, β = 1 is the plain tracker, and the errors it promises.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "indoorloc/core/random.h"

#include <gtest/gtest.h>

#include "indoorloc/fusion/grid_tracker.h"

#include "grid_fixtures.h"
#include "grid_ops.h"

namespace indoorloc::fusion {
namespace {

FloorPlan NarrowHall() {  // 60 x 20 m, floor 0
  FloorGeometry g;
  g.floor = 0;
  g.outlines.push_back(Box(0, 0, 60, 20));
  return FloorPlan({g});
}

// Survey positions on a regular lattice over x in [x0, x1] (every `step` metres, y 0.5..19.5).
RowMatrixXd Survey(double x0, double x1, double step) {
  std::vector<Eigen::Vector2d> p;
  for (double x = x0; x <= x1 + 1e-9; x += step)
    for (double y = 0.5; y < 20; y += step) p.emplace_back(x, y);
  RowMatrixXd out(static_cast<Eigen::Index>(p.size()), 2);
  for (std::size_t i = 0; i < p.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = p[i].transpose();
  return out;
}

GridTrackerOptions Options(double beta) {
  GridTrackerOptions o;
  o.heading_offset_sd_rad = 0.0;
  o.fix.outlier_probability = 1e-6;
  o.fix_survey_distance_factor = beta;
  return o;
}

const std::vector<StepInput> kStill = {StepFromPolar(0.5, 0.0, 0.0, 0.01, 0.01)};

// Brute force of the anchors: per cell the survey point nearest to its centre (ties: the lower
// index), q = s + β (c - s), and the bilinear lattice coordinates of q.
void BruteForceAnchors(const grid_ops::FloorGrid& g, double beta, double c, std::vector<int>* cell,
                       std::vector<float>* wx, std::vector<float>* wy) {
  const auto lattice = [](double u, int n, int* lower, float* weight) {
    u = std::min(static_cast<double>(n - 1), std::max(0.0, u));
    *lower = std::min(static_cast<int>(std::floor(u)), std::max(0, n - 2));
    *weight = static_cast<float>(n > 1 ? u - *lower : 0.0);
  };
  const std::vector<Eigen::Vector2d>& pts = g.survey_points;
  for (int y = 0; y < g.ny; ++y)
    for (int x = 0; x < g.nx; ++x) {
      const double cx = g.x0 + (x + 0.5) * c, cy = g.y0 + (y + 0.5) * c;
      int best = -1;
      double best_d2 = std::numeric_limits<double>::infinity();
      for (int p = 0; p < static_cast<int>(pts.size()); ++p) {
        const double d2 = (pts[p].x() - cx) * (pts[p].x() - cx) + (pts[p].y() - cy) * (pts[p].y() - cy);
        if (d2 < best_d2) best_d2 = d2, best = p;
      }
      const double qx = pts[best].x() + beta * (cx - pts[best].x()), qy = pts[best].y() + beta * (cy - pts[best].y());
      int ix, iy;
      float fx, fy;
      lattice((qx - g.x0) / c - 0.5, g.nx, &ix, &fx);
      lattice((qy - g.y0) / c - 0.5, g.ny, &iy, &fy);
      cell->push_back(iy * g.nx + ix);
      wx->push_back(fx);
      wy->push_back(fy);
    }
}

TEST(GridSurveyAnchorsTest, TheNearestSurveyPointIsThatOfABruteForceSearch) {
  // Clusters along "corridors", isolated points, duplicates (ties), points outside the grid, and
  // a lattice whose points are equidistant from cell centres (more ties).
  RandomStream rng(7);
  for (const double c : {1.0, 0.5, 2.0}) {
    grid_ops::FloorGrid g;
    g.x0 = -3.0;
    g.y0 = 2.0;
    g.nx = static_cast<int>(61 / c);
    g.ny = static_cast<int>(37 / c);
    for (int i = 0; i < 300; ++i) g.survey_points.emplace_back(rng.Uniform(5.0, 50.0), rng.Uniform(10.0, 12.0));
    for (int i = 0; i < 20; ++i) g.survey_points.emplace_back(rng.Uniform(-10.0, 70.0), rng.Uniform(-5.0, 45.0));
    for (int i = 0; i < 10; ++i) g.survey_points.push_back(g.survey_points[static_cast<std::size_t>(3 * i)]);
    for (double x = 20.0; x < 30.0; x += 2.0) g.survey_points.emplace_back(x, 30.0);
    std::vector<int> cell;
    std::vector<float> wx, wy;
    BruteForceAnchors(g, 0.75, c, &cell, &wx, &wy);
    grid_ops::AnchorFixesToSurvey(0.75, c, &g);
    ASSERT_EQ(g.fix_cell.size(), cell.size());
    for (std::size_t i = 0; i < cell.size(); ++i) {
      ASSERT_EQ(g.fix_cell[i], cell[i]) << "cell " << i << ", c " << c;
      ASSERT_EQ(g.fix_wx[i], wx[i]) << "cell " << i;
      ASSERT_EQ(g.fix_wy[i], wy[i]) << "cell " << i;
    }
  }
}

TEST(GridSurveyAnchorsTest, ASurveyAtEveryCellCentreChangesNothing) {
  const FloorPlan plan = NarrowHall();
  const GridTracker plain(&plan, Options(0.5));
  const RowMatrixXd survey = Survey(0.5, 59.5, 1.0);  // the 1 m cells' centres
  const GridTracker anchored = plain.WithSurveyPositions(survey, Eigen::VectorXi::Zero(survey.rows()));
  const std::vector<PositionFix> fixes = {Fix(0.5, 31.2, 9.7, 3.0)};
  const GridTrackResult a = plain.Run(kStill, fixes, TrackStart(), false);
  const GridTrackResult b = anchored.Run(kStill, fixes, TrackStart(), false);
  EXPECT_NEAR(a.filtered_mean_m(0, 0), b.filtered_mean_m(0, 0), 1e-6);
  EXPECT_NEAR(a.filtered_mean_m(0, 1), b.filtered_mean_m(0, 1), 1e-6);
  EXPECT_NEAR(a.filtered_posterior_covariance_m2(0, 0), b.filtered_posterior_covariance_m2(0, 0), 1e-5);
}

TEST(GridSurveyAnchorsTest, AFixAtTheSurveyEdgeReachesBeyondIt) {
  // Surveyed only at x <= 20; a fix at the survey's edge (x = 20). Plain, the walker is at the
  // fix; anchored with β = 0, every cell beyond the edge reads as its nearest surveyed place,
  // so the posterior spreads over x > 20 (where a walker seen at the edge may well be).
  const FloorPlan plan = NarrowHall();
  const RowMatrixXd survey = Survey(0.5, 20.0, 1.0);
  const Eigen::VectorXi floors = Eigen::VectorXi::Zero(survey.rows());
  const std::vector<PositionFix> fixes = {Fix(0.5, 20.0, 10.0, 2.0)};
  const GridTrackResult plain = GridTracker(&plan, Options(1.0)).Run(kStill, fixes, TrackStart(), false);
  const GridTrackResult beta1 =
      GridTracker(&plan, Options(1.0)).WithSurveyPositions(survey, floors).Run(kStill, fixes, TrackStart(), false);
  const GridTrackResult half =
      GridTracker(&plan, Options(0.5)).WithSurveyPositions(survey, floors).Run(kStill, fixes, TrackStart(), false);
  const GridTrackResult zero =
      GridTracker(&plan, Options(0.0)).WithSurveyPositions(survey, floors).Run(kStill, fixes, TrackStart(), false);
  // β = 1: the plain tracker, bit for bit.
  EXPECT_EQ(plain.filtered_mean_m(0, 0), beta1.filtered_mean_m(0, 0));
  EXPECT_NEAR(plain.filtered_mean_m(0, 0), 20.0, 0.1);
  // The smaller β, the further the posterior reaches beyond the survey, the wider it is in x.
  EXPECT_GT(half.filtered_mean_m(0, 0), plain.filtered_mean_m(0, 0) + 1.0);
  EXPECT_GT(zero.filtered_mean_m(0, 0), half.filtered_mean_m(0, 0) + 5.0);
  EXPECT_GT(zero.filtered_posterior_covariance_m2(0, 0), 4.0 * plain.filtered_posterior_covariance_m2(0, 0));
  // Across x the fix still says y = 10.
  EXPECT_NEAR(zero.filtered_mean_m(0, 1), 10.0, 0.1);
}

TEST(GridSurveyAnchorsTest, SameResultForAnyThreadCount) {
  const FloorPlan plan = NarrowHall();
  const RowMatrixXd survey = Survey(0.5, 25.0, 2.0);
  std::vector<StepInput> steps;
  for (int k = 0; k < 30; ++k) steps.push_back(StepFromPolar(0.5 * (k + 1), 0.7, 0.0, 0.05, 0.05));
  const std::vector<PositionFix> fixes = {Fix(0.4, 5.0, 10.0, 3.0), Fix(7.0, 20.0, 10.0, 3.0),
                                          Fix(12.0, 24.0, 9.0, 3.0)};
  GridTrackerOptions o = Options(0.5);
  o.heading_offset_sd_rad = 0.1;
  o.heading_offset_bins = 5;
  GridTrackResult ref;
  for (int threads : {1, 2, 3}) {
    o.num_threads = threads;
    const GridTracker t = GridTracker(&plan, o).WithSurveyPositions(survey, Eigen::VectorXi::Zero(survey.rows()));
    const GridTrackResult r = t.Run(steps, fixes, TrackStart(), true);
    if (threads == 1) {
      ref = r;
      continue;
    }
    EXPECT_EQ(r.filtered_mean_m, ref.filtered_mean_m) << threads;
    EXPECT_EQ(r.smoothed_mean_m, ref.smoothed_mean_m) << threads;
  }
}

TEST(GridSurveyAnchorsTest, ErrorsNameTheArgument) {
  const FloorPlan plan = NarrowHall();
  const GridTracker t(&plan, Options(0.5));
  auto message = [&](const RowMatrixXd& p, const Eigen::VectorXi& f) {
    try {
      t.WithSurveyPositions(p, f);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  RowMatrixXd three(2, 3);
  three.setZero();
  EXPECT_NE(message(three, Eigen::VectorXi::Zero(2)).find("positions_m"), std::string::npos);
  EXPECT_NE(message(RowMatrixXd::Zero(2, 2), Eigen::VectorXi::Zero(3)).find("floor_numbers"), std::string::npos);
  RowMatrixXd nan = RowMatrixXd::Zero(2, 2);
  nan(1, 0) = std::nan("");
  EXPECT_NE(message(nan, Eigen::VectorXi::Zero(2)).find("finite"), std::string::npos);
  GridTrackerOptions bad = Options(1.5);
  EXPECT_THROW(GridTracker(&plan, bad), std::invalid_argument);
  // No survey position on the floor: the cell centres, as the plain tracker.
  const std::vector<PositionFix> fixes = {Fix(0.5, 30.0, 10.0, 3.0)};
  const GridTracker other = t.WithSurveyPositions(RowMatrixXd::Zero(1, 2), Eigen::VectorXi::Constant(1, 7));
  EXPECT_EQ(other.Run(kStill, fixes, TrackStart(), false).filtered_mean_m,
            t.Run(kStill, fixes, TrackStart(), false).filtered_mean_m);
}

}  // namespace
}  // namespace indoorloc::fusion
