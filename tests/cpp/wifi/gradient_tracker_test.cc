#include "indoorloc/wifi/gradient_tracker.h"

#include <cmath>
#include <memory>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "indoorloc/core/random.h"
#include "test_maps.h"

namespace indoorloc::wifi {
namespace {

Eigen::VectorXd MeanAt(const RssModel& model, const Eigen::Vector2d& z) {
  Eigen::VectorXd mean, var;
  int hint = -1;
  model.MeanAndVariance(z, 0, &mean, &var, &hint);
  return mean;
}

TEST(GradientTracker, GlobalFixOfANoiselessScanIsExact) {
  const RssModel model(testing::LatticeMap(6, 6, 2.0, 2.0, /*variance_slope=*/0.0));
  GradientTrackerOptions options;
  for (const Eigen::Vector2d& z : {Eigen::Vector2d(3.3, 7.1), Eigen::Vector2d(8.9, 1.2)}) {
    const RowMatrixXd scan = MeanAt(model, z).transpose();
    const WifiFix fix = LocateMaximumLikelihood(model, scan, options);
    EXPECT_LT((fix.position_m - z).norm(), 1e-3) << fix.position_m.transpose();
    EXPECT_GT(fix.covariance_m2.determinant(), 0.0);
  }
}

TEST(GradientTracker, ConvergesAlongAPathOnANoiselessMap) {
  auto model = std::make_shared<const RssModel>(testing::LatticeMap(6, 6, 2.0, 2.0, 0.0));
  GradientTracker tracker(model, GradientTrackerOptions());
  tracker.ResetTo(Eigen::Vector2d(1.0, 1.0), 0);
  double last_error = 0;
  for (int t = 0; t < 40; ++t) {
    const Eigen::Vector2d z(1.0 + 0.18 * t, 1.0 + 0.1 * t);
    const WifiFix fix = tracker.Update(MeanAt(*model, z));
    last_error = (fix.position_m - z).norm();
  }
  EXPECT_LT(last_error, 0.02);
}

TEST(GradientTracker, PaperModeStaysNearTheTruthWithNoise) {
  auto model = std::make_shared<const RssModel>(testing::LatticeMap());
  GradientTrackerOptions options;
  options.paper_mode = true;
  GradientTracker tracker(model, options);
  RandomStream rng(3);
  tracker.ResetTo(Eigen::Vector2d(5.0, 1.0), 0);
  double sum_error = 0;
  int hint = -1;
  for (int t = 0; t < 30; ++t) {
    const Eigen::Vector2d z(5.0, 1.0 + 0.18 * t);
    Eigen::VectorXd mean, var;
    model->MeanAndVariance(z, 0, &mean, &var, &hint);
    for (Eigen::Index i = 0; i < mean.size(); ++i) mean[i] += std::sqrt(var[i]) * rng.Normal();
    const WifiFix fix = tracker.Update(mean);
    sum_error += (fix.position_m - z).norm();
    EXPECT_TRUE(fix.position_m.allFinite());
  }
  EXPECT_LT(sum_error / 30, 3.0);  // bounded: the estimate stays on the 10 m map and near z
}

TEST(GradientTracker, FirstUpdateIsAGlobalFixAndBadInputThrows) {
  auto model = std::make_shared<const RssModel>(testing::LatticeMap(6, 6, 2.0, 2.0, 0.0));
  GradientTracker tracker(model, GradientTrackerOptions());
  EXPECT_FALSE(tracker.initialized());
  const Eigen::Vector2d z(6.2, 6.6);
  const WifiFix fix = tracker.Update(MeanAt(*model, z));
  EXPECT_TRUE(tracker.initialized());
  EXPECT_LT((fix.position_m - z).norm(), 1e-3);
  EXPECT_THROW(tracker.Update(Eigen::VectorXd::Zero(3)), std::invalid_argument);
  Eigen::VectorXd nan_scan = MeanAt(*model, z);
  nan_scan[1] = std::nan("");
  EXPECT_THROW(tracker.Update(nan_scan), std::invalid_argument);
  GradientTrackerOptions bad;
  bad.max_step_m = 0;
  EXPECT_THROW(GradientTracker(model, bad), std::invalid_argument);
  EXPECT_THROW(tracker.ResetTo(z, 7), std::invalid_argument);  // floor not in map
}

}  // namespace
}  // namespace indoorloc::wifi
