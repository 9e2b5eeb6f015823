// Tests of the WiFi likelihood (wifi_likelihood.h): it equals the RSS model's interpolated
// Gaussian inside and outside the hull; observations built from scans drop stale readings or
// retime them, and bad input is refused.
#include "indoorloc/fusion/wifi_likelihood.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "expect_invalid.h"
#include "room_fixture.h"

#include "indoorloc/core/random.h"

namespace indoorloc::fusion {
namespace {

TEST(WifiLikelihood, EqualsTheRssModelsInterpolatedGaussianInsideAndOutsideTheHull) {
  const wifi::RssModel model(RoomMap());
  WifiLikelihoodOptions o;
  o.tempering = 0.3;
  o.max_term = 5.0;
  const WifiLikelihood likelihood(model, o);
  WifiObservation obs;
  obs.access_points = {0, 2, 3};
  obs.rss_dbm = {-55.0, -70.0, -62.0};
  RandomStream rng(9);
  for (int q = 0; q < 200; ++q) {
    const double x = rng.Uniform(-5.0, 25.0), y = rng.Uniform(-5.0, 15.0);
    Eigen::VectorXd mean, var;
    int hint = -1;
    model.MeanAndVariance(Eigen::Vector2d(x, y), 0, &mean, &var, &hint);
    double expected = 0.0;
    for (size_t i = 0; i < obs.access_points.size(); ++i) {
      const int a = obs.access_points[i];
      const double r = obs.rss_dbm[i] - mean[a];
      expected -= 0.5 * std::log(2.0 * M_PI * var[a]) + std::min(0.5 * r * r / var[a], 5.0);
    }
    EXPECT_NEAR(likelihood.LogLikelihood(x, y, 0, obs), 0.3 * expected, 1e-9) << x << ", " << y;
  }
  EXPECT_EQ(likelihood.LogLikelihood(1.0, 1.0, 0, WifiObservation()), 0.0);
}

TEST(WifiObservations, ScanTimeModeDropsStaleReadings) {
  Eigen::VectorXd t(2);
  t << 1.0, 3.0;
  RowMatrixXd rss(2, 3), ages(2, 3);
  rss << -50, std::nan(""), -60, -55, -65, std::nan("");
  ages << 0.5, std::nan(""), 9.0, 0.0, 1.0, std::nan("");
  WifiLikelihoodOptions o;
  o.max_age_s = 4.0;
  WifiReadingCounts c;
  const auto obs = MakeWifiObservations(t, rss, ages, o, /*at_own_time=*/false, &c);
  ASSERT_EQ(obs.size(), 2u);
  EXPECT_EQ(c.dropped_stale, 1);
  EXPECT_EQ(c.heard, 3);
  EXPECT_EQ(c.not_heard, 2);
  EXPECT_EQ(obs[0].num_heard, 1);  // -60 (9 s old) dropped; AP 1 not heard
  EXPECT_EQ(obs[0].access_points.size(), 2u);
}

TEST(WifiObservations, OwnTimeModeRetimesReadings) {
  Eigen::VectorXd t(1);
  t << 10.0;
  RowMatrixXd rss(1, 3), ages(1, 3);
  rss << -50, -60, std::nan("");
  ages << 0.0, 6.0, std::nan("");
  WifiLikelihoodOptions o;
  o.use_not_heard = false;
  const auto obs = MakeWifiObservations(t, rss, ages, o, /*at_own_time=*/true);
  ASSERT_EQ(obs.size(), 2u);
  EXPECT_DOUBLE_EQ(obs[0].time_s, 4.0);
  EXPECT_EQ(obs[0].access_points, std::vector<int>({1}));
  EXPECT_DOUBLE_EQ(obs[1].time_s, 10.0);
  EXPECT_EQ(obs[1].access_points, std::vector<int>({0}));
}

TEST(WifiObservations, RejectsBadInput) {
  Eigen::VectorXd t(2);
  t << 2.0, 1.0;
  RowMatrixXd rss = RowMatrixXd::Constant(2, 2, -50.0);
  WifiLikelihoodOptions o;
  EXPECT_THROW(MakeWifiObservations(t, rss, RowMatrixXd(0, 0), o, false), std::invalid_argument);  // time goes back
  t << 1.0, 2.0;
  RowMatrixXd ages = RowMatrixXd::Constant(2, 2, -1.0);
  EXPECT_THROW(MakeWifiObservations(t, rss, ages, o, false), std::invalid_argument);  // negative age
  rss(0, 0) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(MakeWifiObservations(t, rss, RowMatrixXd(0, 0), o, false), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::fusion
