#include "indoorloc/pdr/step_positioning.h"

#include <cmath>

#include <gtest/gtest.h>

#include "indoorloc/core/random.h"
#include "synthetic_gait.h"

namespace indoorloc::pdr {
namespace {

using synthetic::Gait;
using synthetic::MakeGait;

TEST(StepPositioning, InsZuptIncrementsRecoverTheStridesAndEq8AndEq9ThePath) {
  const double heading = 0.7;
  const Gait g = MakeGait(10, heading, 0.0, 1);
  const InsZuptIncrements inc = ComputeInsZuptIncrements(g.time, g.acc, g.quaternions, g.mid_stance);
  ASSERT_EQ(inc.increments_m.rows(), g.steps);
  for (Eigen::Index k = 0; k < inc.increments_m.rows(); ++k) {
    EXPECT_NEAR(inc.stride_lengths_m[k], 1.4, 0.01) << k;
    EXPECT_NEAR(std::atan2(inc.increments_m(k, 1), inc.increments_m(k, 0)), heading, 0.01) << k;
  }
  // Eq. 9 ends where the foot ends; eq. 8 with the stance headings (eq. 7) too.
  const Eigen::Vector2d start(1.0, -2.0);
  const StepTrack t9 = PositionsFromIncrements(inc.increments_m, start);
  const Eigen::Vector2d end = g.position.bottomRows(1).leftCols(2).transpose() + start;
  EXPECT_LT((t9.positions_m.bottomRows(1).transpose() - end).norm(), 0.05);
  const std::vector<int> after(g.mid_stance.begin() + 1, g.mid_stance.end());
  const Eigen::VectorXd headings = StanceHeadings(g.quaternions, after);
  for (Eigen::Index k = 0; k < headings.size(); ++k) EXPECT_NEAR(headings[k], heading, 1e-9);
  const StepTrack t8 = PositionsFromStrides(inc.stride_lengths_m, headings, start);
  EXPECT_LT((t8.positions_m.bottomRows(1).transpose() - end).norm(), 0.05);
}

TEST(StepPositioning, CovarianceGrowsAndMatchesAMonteCarloOfTheModel) {
  StepCovarianceOptions o;
  o.sigma_stride_length_m = 0.05;
  o.stride_length_sd_fraction = 0.0;
  o.sigma_heading_step_rad = 0.02;
  const int m = 30;
  const Eigen::VectorXd sl = Eigen::VectorXd::Constant(m, 0.8);
  Eigen::VectorXd heading(m);
  for (int k = 0; k < m; ++k) heading[k] = 0.1 * k;  // a gentle curve
  const StepTrack t = PositionsFromStrides(sl, heading, Eigen::Vector2d::Zero(), o);
  for (Eigen::Index k = 1; k < m; ++k) {
    EXPECT_GT(t.covariances(k, 0) + t.covariances(k, 4), t.covariances(k - 1, 0) + t.covariances(k - 1, 4));
  }
  // Brute force: sample SL and the heading random walk, accumulate eq. 8, compare the final
  // 2 x 2 covariance (the linearisation is accurate for these small angles).
  RandomStream rng(7);
  const int runs = 20000;
  Eigen::Matrix2d acc = Eigen::Matrix2d::Zero();
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> ends;
  for (int r = 0; r < runs; ++r) {
    double dpsi = 0.0;
    Eigen::Vector2d p = Eigen::Vector2d::Zero();
    for (int k = 0; k < m; ++k) {
      dpsi += o.sigma_heading_step_rad * rng.Normal();
      const double l = sl[k] + o.sigma_stride_length_m * rng.Normal();
      p += l * Eigen::Vector2d(std::cos(heading[k] + dpsi), std::sin(heading[k] + dpsi));
    }
    ends.push_back(p);
    mean += p / runs;
  }
  for (const auto& p : ends) acc += (p - mean) * (p - mean).transpose() / (runs - 1);
  Eigen::Matrix2d model;
  model << t.covariances(m - 1, 0), t.covariances(m - 1, 1), t.covariances(m - 1, 3), t.covariances(m - 1, 4);
  EXPECT_LT((acc - model).norm(), 0.1 * model.norm()) << "Monte Carlo\n" << acc << "\nmodel\n" << model;
}

TEST(StepPositioning, BadInputGivesClearErrors) {
  const Gait g = MakeGait(3, 0.0, 0.0, 2);
  EXPECT_THROW(ComputeInsZuptIncrements(g.time, g.acc, g.quaternions, {400, 100}), std::invalid_argument);  // unsorted
  EXPECT_THROW(ComputeInsZuptIncrements(g.time, g.acc, g.quaternions, {100}), std::invalid_argument);       // one step
  EXPECT_THROW(ComputeInsZuptIncrements(g.time, g.acc, 2.0 * g.quaternions, {10, 300}), std::invalid_argument);
  RowMatrixXd nan_acc = g.acc;
  nan_acc(0, 0) = std::nan("");
  EXPECT_THROW(ComputeInsZuptIncrements(g.time, nan_acc, g.quaternions, {10, 300}), std::invalid_argument);
  EXPECT_THROW(PositionsFromStrides(Eigen::VectorXd::Constant(2, -1.0), Eigen::VectorXd::Zero(2), Eigen::Vector2d::Zero()),
               std::invalid_argument);
  EXPECT_THROW(PositionsFromStrides(Eigen::VectorXd::Ones(2), Eigen::VectorXd::Zero(3), Eigen::Vector2d::Zero()),
               std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::pdr
