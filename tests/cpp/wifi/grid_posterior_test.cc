#include "indoorloc/wifi/grid_posterior.h"

#include <cmath>
#include <memory>
#include <stdexcept>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "indoorloc/core/random.h"
#include "test_maps.h"

namespace indoorloc::wifi {
namespace {

// Brute-force reference: the posterior mean from RssModel::Evaluate at every grid point.
TEST(GridPosterior, MatchesBruteForcePosteriorFromTheModel) {
  RssModelOptions model_options;
  model_options.max_term = 6.0;  // the cap must be honoured identically
  auto model = std::make_shared<const RssModel>(testing::LatticeMap(), model_options);
  GridPosteriorOptions options;
  options.spacing_m = 0.25;
  const GridPosterior posterior(model, options);
  RandomStream rng(4);
  RowMatrixXd scans(3, 4);
  Eigen::VectorXd mean, var;
  int hint = -1;
  model->MeanAndVariance(Eigen::Vector2d(3.1, 6.4), 0, &mean, &var, &hint);
  for (int s = 0; s < 3; ++s) {
    for (int a = 0; a < 4; ++a) scans(s, a) = rng.Normal(mean[a], std::sqrt(var[a]) * 2.0);
  }
  const RowMatrixXd& grid = posterior.grid(0);
  Eigen::VectorXd l(grid.rows());
  for (Eigen::Index g = 0; g < grid.rows(); ++g) {
    l[g] = model->Evaluate(scans, grid.row(g).transpose(), 0, &hint).neg_log_likelihood;
  }
  const Eigen::ArrayXd w = (l.minCoeff() - l.array()).exp();
  const Eigen::Vector2d expected = grid.transpose() * w.matrix() / w.sum();
  const WifiFix fix = posterior.Locate(scans);
  EXPECT_LT((fix.position_m - expected).norm(), 1e-9);
  EXPECT_GT(fix.covariance_m2.determinant(), 0.0);
  EXPECT_EQ(fix.floor, 0);
  EXPECT_THROW(posterior.Locate(scans.leftCols(3)), std::invalid_argument);
  GridPosteriorOptions bad;
  bad.max_points_per_floor = 1;
  EXPECT_THROW(GridPosterior(model, bad), std::invalid_argument);
}

// On a map whose APs are heard over parts of the floor the posterior sums only the heard APs'
// entries; it must equal the dense sum of every AP's term (EvaluateEveryAccessPoint).
TEST(GridPosterior, PartlyHeardMapMatchesEveryAccessPointSum) {
  RssModelOptions model_options;
  model_options.max_term = 5.0;
  auto model = std::make_shared<const RssModel>(testing::PartlyHeardMap(), model_options);
  GridPosteriorOptions options;
  options.spacing_m = 0.7;
  const GridPosterior posterior(model, options);
  RandomStream rng(9);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd mean, var;
    int hint = -1;
    model->MeanAndVariance(Eigen::Vector2d(rng.Uniform(2, 28), rng.Uniform(2, 18)), 0, &mean, &var, &hint);
    RowMatrixXd scans(2, mean.size());
    for (int s = 0; s < 2; ++s) {
      for (Eigen::Index a = 0; a < mean.size(); ++a) {
        const double v = rng.Normal(mean[a], std::sqrt(var[a]));
        scans(s, a) = mean[a] > -104.0 && v > -80.0 ? v : -105.0;
      }
    }
    const RowMatrixXd& grid = posterior.grid(0);
    Eigen::VectorXd l(grid.rows());
    for (Eigen::Index g = 0; g < grid.rows(); ++g) {
      l[g] = model->EvaluateEveryAccessPoint(scans, grid.row(g).transpose(), 0, &hint).neg_log_likelihood;
    }
    const Eigen::ArrayXd w = (l.minCoeff() - l.array()).exp();
    const Eigen::Vector2d expected = grid.transpose() * w.matrix() / w.sum();
    const WifiFix fix = posterior.Locate(scans);
    EXPECT_LT((fix.position_m - expected).norm(), 1e-9);
    EXPECT_NEAR(fix.neg_log_likelihood, l.minCoeff() - std::log(w.sum()), 1e-9 * std::abs(l.minCoeff()));
  }
}

// Issue 17: grid(floor_index) had no bounds check (grid(100000) segfaulted, grid(-1) read garbage).
TEST(GridPosterior, GridIndexOutsideTheFloorsThrowsOutOfRange) {
  auto model = std::make_shared<const RssModel>(testing::LatticeMap(), RssModelOptions());
  const GridPosterior posterior(model, GridPosteriorOptions());
  ASSERT_EQ(posterior.num_floors(), 1);
  EXPECT_GT(posterior.grid(0).rows(), 0);
  for (const int bad : {-1, 1, 100000}) EXPECT_THROW(posterior.grid(bad), std::out_of_range) << bad;
}

}  // namespace
}  // namespace indoorloc::wifi
