#include "indoorloc/wifi/signal_map.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <gtest/gtest.h>

#include "test_maps.h"

namespace indoorloc::wifi {
namespace {

TEST(SignalMap, FromScansGroupsPointsAndUsesThePapersVarianceEstimator) {
  // Two points, 4 scans each, 3 AP columns: AP 0 always heard, AP 1 heard once at point 0,
  // AP 2 never heard (dropped).
  RowMatrixXd pos(8, 2), rss(8, 3);
  Eigen::VectorXi floors = Eigen::VectorXi::Zero(8);
  const double a0[4] = {-50, -52, -54, -56};
  for (int s = 0; s < 4; ++s) {
    pos.row(s) << 0, 0;
    pos.row(4 + s) << 1, 0;
    rss.row(s) << a0[s], s == 0 ? -80.0 : 100.0, 100.0;
    rss.row(4 + s) << -60, std::nan(""), 100.0;
  }
  SignalMapOptions options;
  options.variance_floor_db2 = 1.0;
  const SignalMap map = SignalMap::FromScans(pos, floors, rss, options);
  ASSERT_EQ(map.num_points(), 2);
  ASSERT_EQ(map.num_access_points(), 2);
  EXPECT_EQ(map.access_point_indices()[0], 0);
  EXPECT_EQ(map.access_point_indices()[1], 1);
  EXPECT_NEAR(map.mean_dbm()(0, 0), -53.0, 1e-12);
  // Unbiased variance = 1/λ with λ = (N-1)/(N δ): values -50..-56 -> 20/3.
  EXPECT_NEAR(map.variance_db2()(0, 0), 20.0 / 3.0, 1e-12);
  EXPECT_NEAR(map.variance_db2()(1, 0), 1.0, 1e-12);  // constant readings -> the floor
  // AP 1 at point 0: one -80 and three not-heard (-105): mean -98.75.
  EXPECT_NEAR(map.mean_dbm()(0, 1), (-80.0 - 3 * 105.0) / 4, 1e-12);
  EXPECT_NEAR(map.detection_rate()(0, 1), 0.25, 1e-12);
  EXPECT_NEAR(map.detection_rate()(1, 1), 0.0, 1e-12);
  EXPECT_EQ(map.scan_counts()[0], 4);

  options.min_point_fraction = 1.0;  // AP 1 heard at one point of two: dropped
  EXPECT_EQ(SignalMap::FromScans(pos, floors, rss, options).num_access_points(), 1);

  const RowMatrixXd prepared = map.PrepareScans(rss.topRows(2), 100.0, -105.0);
  EXPECT_EQ(prepared.cols(), 2);
  EXPECT_EQ(prepared(1, 1), -105.0);
  EXPECT_THROW(map.PrepareScans(rss.leftCols(1), 100.0, -105.0), std::invalid_argument);
}

TEST(SignalMap, SaveLoadRoundTrip) {
  const SignalMap map = testing::LatticeMap(3, 4);
  const std::string path = ::testing::TempDir() + "/map.txt";
  map.Save(path);
  const SignalMap back = SignalMap::Load(path);
  EXPECT_EQ(back.positions_m(), map.positions_m());
  EXPECT_EQ(back.mean_dbm(), map.mean_dbm());
  EXPECT_EQ(back.variance_db2(), map.variance_db2());
  EXPECT_EQ(back.floors(), map.floors());
  std::ofstream(path) << "not a map\n";
  EXPECT_THROW(SignalMap::Load(path), std::runtime_error);
  EXPECT_THROW(SignalMap::Load(path + ".missing"), std::runtime_error);
}

TEST(SignalMap, BadInputGivesClearErrors) {
  RowMatrixXd pos(2, 2), mean(2, 3), var(2, 3);
  pos << 0, 0, 1, 1;
  mean.setConstant(-50);
  var.setConstant(4);
  EXPECT_NO_THROW(SignalMap(pos, Eigen::VectorXi::Zero(2), mean, var));
  var(1, 2) = 0.0;
  EXPECT_THROW(SignalMap(pos, Eigen::VectorXi::Zero(2), mean, var), std::invalid_argument);
  var(1, 2) = 4.0;
  mean(0, 1) = std::nan("");
  EXPECT_THROW(SignalMap(pos, Eigen::VectorXi::Zero(2), mean, var), std::invalid_argument);
  mean(0, 1) = -50;
  EXPECT_THROW(SignalMap(pos, Eigen::VectorXi::Zero(3), mean, var), std::invalid_argument);
  EXPECT_THROW(SignalMap(RowMatrixXd(0, 2), Eigen::VectorXi(), RowMatrixXd(0, 3), RowMatrixXd(0, 3)),
               std::invalid_argument);
  RowMatrixXd rss = RowMatrixXd::Constant(2, 3, 100.0);  // nothing heard anywhere
  EXPECT_THROW(SignalMap::FromScans(pos, Eigen::VectorXi::Zero(2), rss), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::wifi
