// The network adjustment on noise-free flights that satisfy its discrete equations exactly,
// datum defects, the leap-frog parity decoupling, the cross-over finder and the Kalman smoother.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "flight_fixture.h"
#include "indoorloc/network/kalman_smoother.h"
#include "indoorloc/network/network_adjustment.h"

namespace indoorloc::network {
namespace {

using testing::MakeFlight;
using testing::Perturb;

double MaxAbs(const Eigen::Ref<const RowMatrixXd>& a) { return a.cwiseAbs().maxCoeff(); }

void ExpectRecovered(const NetworkState& est, const NetworkState& truth) {
  EXPECT_LT(MaxAbs(est.position_m - truth.position_m), 1e-6);
  EXPECT_LT(MaxAbs(est.velocity_mps - truth.velocity_mps), 1e-6);
  EXPECT_LT(MaxAbs(est.acc_bias_mps2 - truth.acc_bias_mps2), 1e-8);
  EXPECT_LT(MaxAbs(est.gyro_bias_radps - truth.gyro_bias_radps), 1e-10);
  EXPECT_LT((est.gravity_disturbance_mps2 - truth.gravity_disturbance_mps2).cwiseAbs().maxCoeff(), 1e-8);  // 1 µGal
  for (Eigen::Index i = 0; i < truth.attitude_wxyz.rows(); ++i) {
    const double dot = std::abs(est.attitude_wxyz.row(i).dot(truth.attitude_wxyz.row(i)));
    EXPECT_GT(dot, 1.0 - 1e-14) << "epoch " << i;
  }
}

NetworkOptions TightOptions(Discretization d) {
  NetworkOptions o;
  o.discretization = d;
  o.max_iterations = 30;
  return o;
}

TEST(NetworkAdjustment, NoiseFreeLeapFrogFlightIsRecoveredExactly) {
  const NetworkOptions o = TightOptions(Discretization::kLeapFrog);
  const auto fl = MakeFlight(o, 300, 0.1);
  NetworkSummary s;
  const NetworkState est = SolveNetwork(fl.obs, Perturb(fl.truth), o, &s);
  EXPECT_EQ(s.termination, Termination::kConverged) << s.message;
  EXPECT_EQ(s.num_parameters, 16L * 300);
  EXPECT_GT(s.min_pivot_ratio, o.datum_pivot_tolerance);
  // Epochs 0 and N-1 enter only through leap-frog neighbours; compare 1..N-2 for q, o, a.
  ExpectRecovered(est, fl.truth);
  EXPECT_NE(s.BriefReport().find("converged"), std::string::npos);
}

TEST(NetworkAdjustment, NoiseFreeTrapezoidalFlightIsRecoveredExactly) {
  const NetworkOptions o = TightOptions(Discretization::kTrapezoidal);
  const auto fl = MakeFlight(o, 300, 0.1);
  NetworkSummary s;
  const NetworkState est = SolveNetwork(fl.obs, Perturb(fl.truth), o, &s);
  EXPECT_EQ(s.termination, Termination::kConverged) << s.message;
  ExpectRecovered(est, fl.truth);
}

TEST(NetworkAdjustment, NoGpsIsADatumDefect) {
  const NetworkOptions o = TightOptions(Discretization::kTrapezoidal);
  auto fl = MakeFlight(o, 50, 0.1);
  fl.obs.gps_time_s.resize(0);
  fl.obs.gps_position_m.resize(0, 3);
  try {
    SolveNetwork(fl.obs, fl.truth, o);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'gps_position_m'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("datum defect"), std::string::npos) << e.what();
  }
}

// The leap-frog rule couples epochs of equal parity only: GPS on even epochs leaves the odd
// chain without a position datum. The trapezoidal rule solves the same data.
TEST(NetworkAdjustment, LeapFrogDecouplesEvenAndOddEpochs) {
  NetworkOptions o = TightOptions(Discretization::kLeapFrog);
  auto fl = MakeFlight(o, 200, 0.1, /*gps_every=*/10, /*gps_offset=*/0);
  try {
    SolveNetwork(fl.obs, Perturb(fl.truth), o);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'gps_time_s'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("odd-epoch chain"), std::string::npos) << e.what();
  }
  // The numerical check sees the same defect when the structural one is bypassed: shift every
  // GPS time by a hair so that each CUPT touches both parities with a negligible weight.
  auto shifted = fl;
  shifted.obs.gps_time_s.array() += 1e-8;
  try {
    SolveNetwork(shifted.obs, Perturb(fl.truth), o);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'observations'"), std::string::npos) << e.what();
  }
  o.discretization = Discretization::kTrapezoidal;
  fl = MakeFlight(o, 200, 0.1, 10, 0);
  NetworkSummary s;
  const NetworkState est = SolveNetwork(fl.obs, Perturb(fl.truth), o, &s);
  EXPECT_EQ(s.termination, Termination::kConverged);
  EXPECT_LT(MaxAbs(est.position_m - fl.truth.position_m), 1e-5);
}

// Effect on a noisy flight with GPS on both parities: the two leap-frog chains see different
// noise and drift apart, an even/odd saw-tooth in the estimates that the trapezoidal rule has not.
TEST(NetworkAdjustment, LeapFrogShowsEvenOddSawToothUnderNoise) {
  double sawtooth[2];
  for (int k = 0; k < 2; ++k) {
    NetworkOptions o;
    o.discretization = k == 0 ? Discretization::kLeapFrog : Discretization::kTrapezoidal;
    auto fl = MakeFlight(o, 400, 0.1, 5, 0);  // GPS every 5th epoch: both parities
    std::mt19937 rng(3);
    std::normal_distribution<double> nd(0.0, 1.0);
    const double sf = o.acc_noise_mps2_rthz / std::sqrt(0.1), sw = o.gyro_noise_radps_rthz / std::sqrt(0.1);
    for (Eigen::Index i = 0; i < fl.obs.acc_body_mps2.rows(); ++i)
      for (int c = 0; c < 3; ++c) {
        fl.obs.acc_body_mps2(i, c) += sf * nd(rng);
        fl.obs.gyro_body_radps(i, c) += sw * nd(rng);
      }
    for (Eigen::Index i = 0; i < fl.obs.gps_position_m.rows(); ++i)
      for (int c = 0; c < 3; ++c) fl.obs.gps_position_m(i, c) += o.sigma_gps_m * nd(rng);
    const NetworkState est = SolveNetwork(fl.obs, Perturb(fl.truth, 0.2), o);
    // Second difference of the vertical velocity error: dominated by an even/odd alternation.
    const Eigen::VectorXd e = est.velocity_mps.col(2) - fl.truth.velocity_mps.col(2);
    double acc = 0.0;
    for (Eigen::Index i = 1; i + 1 < e.size(); ++i) acc += std::pow(e[i] - 0.5 * (e[i - 1] + e[i + 1]), 2);
    sawtooth[k] = std::sqrt(acc / static_cast<double>(e.size() - 2));
  }
  EXPECT_GT(sawtooth[0], 3.0 * sawtooth[1]) << "leap-frog " << sawtooth[0] << " trapezoidal " << sawtooth[1];
}

// A straight, level, unaccelerated flight without GUPT: δg and the vertical accelerometer bias
// (and the heading) are not separable; the numerical datum check finds the defect.
TEST(NetworkAdjustment, LevelFlightWithoutGuptIsRankDeficient) {
  NetworkOptions o = TightOptions(Discretization::kTrapezoidal);
  auto fl = MakeFlight(o, 100, 0.1, 1, 0, /*level=*/true);
  fl.obs.gupt_epochs.resize(0);
  fl.obs.gupt_gravity_mps2.resize(0);
  try {
    SolveNetwork(fl.obs, fl.truth, o);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'observations'"), std::string::npos) << what;
    EXPECT_NE(what.find("datum defect"), std::string::npos) << what;
  }
}

TEST(NetworkAdjustment, BadInputNamesTheArgument) {
  const NetworkOptions o;
  const auto good = MakeFlight(o, 30, 0.1);
  auto expect_throw = [&](auto mutate, const std::string& name) {
    auto fl = good;
    mutate(fl);
    try {
      SolveNetwork(fl.obs, fl.truth, o);
      ADD_FAILURE() << "no exception for " << name;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("'" + name + "'"), std::string::npos) << e.what();
    }
  };
  expect_throw([](testing::Flight& f) { f.obs.acc_body_mps2(3, 1) = std::nan(""); }, "acc_body_mps2");
  expect_throw([](testing::Flight& f) { f.obs.imu_time_s[5] = f.obs.imu_time_s[4]; }, "imu_time_s");
  expect_throw([](testing::Flight& f) { f.obs.gps_time_s[f.obs.gps_time_s.size() - 1] += 10.0; }, "gps_time_s");
  expect_throw([](testing::Flight& f) { f.obs.zupt_epochs = Eigen::VectorXi::Constant(1, 30); }, "zupt_epochs");
  expect_throw([](testing::Flight& f) { f.obs.gps_position_m(0, 0) = INFINITY; }, "gps_position_m");
  NetworkOptions bad;
  bad.sigma_gps_m = -1.0;
  EXPECT_THROW(SolveNetwork(good.obs, good.truth, bad), std::invalid_argument);
}

TEST(Crossovers, TwoPerpendicularLinesCrossOnce) {
  // East line at y = 0 for t in [0, 100), then North line at x = 500 from y = -500.
  const int n = 2000;
  Eigen::VectorXd t(n);
  RowMatrixXd p(n, 3);
  for (int i = 0; i < n; ++i) {
    t[i] = 0.1 * i;
    if (i < 1000) p.row(i) << i * 1.0, 0.0, 100.0;
    else p.row(i) << 500.0, -500.0 + (i - 1000) * 1.0, 101.0;
  }
  CrossoverOptions co;
  co.radius_m = 3.0;
  const RowMatrixX2i x = FindCrossovers(t, p, co);
  ASSERT_EQ(x.rows(), 1);
  EXPECT_EQ(x(0, 0), 500);
  EXPECT_EQ(x(0, 1), 1500);
  co.max_height_difference_m = 0.5;
  EXPECT_EQ(FindCrossovers(t, p, co).rows(), 0);
}

TEST(KalmanSmoother, TracksANoiseFreeFlight) {
  NetworkOptions o;
  o.discretization = Discretization::kTrapezoidal;
  const auto fl = MakeFlight(o, 300, 0.1, 10, 0);
  KalmanSmootherOptions ko;
  KalmanSmootherSummary ks;
  NetworkState filtered;
  const NetworkState est = RunKalmanSmoother(fl.obs, fl.truth, o, ko, &ks, &filtered);
  EXPECT_EQ(ks.num_epochs, 300);
  EXPECT_LT(MaxAbs(est.position_m - fl.truth.position_m), 1e-3);
  EXPECT_LT(MaxAbs(est.velocity_mps - fl.truth.velocity_mps), 1e-3);
  EXPECT_LT((est.gravity_disturbance_mps2 - fl.truth.gravity_disturbance_mps2).cwiseAbs().maxCoeff(), 1e-4);
}

}  // namespace
}  // namespace indoorloc::network

namespace indoorloc::network {
namespace {

// Selected covariances: ceres::Covariance on the δg diagonal blocks equals the corresponding
// entries of the dense inverse of JᵀJ (the brute-force reference) on a small network.
TEST(NetworkCovariance, CeresMatchesTheDenseInverse) {
  NetworkOptions o;
  o.discretization = Discretization::kTrapezoidal;
  const auto fl = testing::MakeFlight(o, 120, 0.1, 10, 0);
  o.gravity_covariance = NetworkOptions::Covariance::kDense;
  const NetworkState dense = SolveNetwork(fl.obs, fl.truth, o);
  o.gravity_covariance = NetworkOptions::Covariance::kCeres;
  NetworkSummary s;
  const NetworkState sparse = SolveNetwork(fl.obs, fl.truth, o, &s);
  ASSERT_EQ(dense.gravity_disturbance_sd_mps2.size(), 120);
  ASSERT_EQ(sparse.gravity_disturbance_sd_mps2.size(), 120);
  for (int i = 0; i < 120; ++i) {
    EXPECT_GT(dense.gravity_disturbance_sd_mps2[i], 0.0);
    EXPECT_NEAR(sparse.gravity_disturbance_sd_mps2[i], dense.gravity_disturbance_sd_mps2[i],
                1e-6 * dense.gravity_disturbance_sd_mps2[i])
        << "epoch " << i;
  }
  // The GUPT pins δg at the middle epoch: its sd is close to sigma_gupt and the smallest.
  const int mid = 60;
  EXPECT_LT(dense.gravity_disturbance_sd_mps2[mid], 1.01 * o.sigma_gupt_mps2);
  EXPECT_EQ(Eigen::Index(mid), [&] {
    Eigen::Index k;
    dense.gravity_disturbance_sd_mps2.minCoeff(&k);
    return k;
  }());
  o.gravity_covariance = NetworkOptions::Covariance::kNone;
  EXPECT_EQ(SolveNetwork(fl.obs, fl.truth, o).gravity_disturbance_sd_mps2.size(), 0);
}

}  // namespace
}  // namespace indoorloc::network

namespace indoorloc::network {
namespace {

// One GPS fix 5 m off: plain least squares bends the trajectory towards it; the Huber loss on
// CUPT (threshold 3 sigma) keeps the noise-free solution.
TEST(NetworkAdjustment, HuberLossResistsAGpsOutlier) {
  NetworkOptions o;
  o.discretization = Discretization::kTrapezoidal;
  auto fl = testing::MakeFlight(o, 200, 0.1, 10, 0);
  fl.obs.gps_position_m(10, 0) += 5.0;
  const NetworkState plain = SolveNetwork(fl.obs, fl.truth, o);
  o.gps_huber_threshold = 3.0;
  const NetworkState robust = SolveNetwork(fl.obs, fl.truth, o);
  const double err_plain = (plain.position_m - fl.truth.position_m).cwiseAbs().maxCoeff();
  const double err_robust = (robust.position_m - fl.truth.position_m).cwiseAbs().maxCoeff();
  EXPECT_GT(err_plain, 0.05);
  EXPECT_LT(err_robust, 0.2 * err_plain);
}

}  // namespace
}  // namespace indoorloc::network

namespace indoorloc::network {
namespace {

// Variance component estimation: accelerometer, gyro and GPS noise simulated at 2x, 1x and 3x
// the stated standard deviations; the iterated estimate recovers the variance factors 4, 1, 9.
// Leap-frog: each FB / WIB residual holds one IMU sample, so the residuals of a group are
// independent as Förstner's estimator assumes. With the trapezoidal rule neighbouring residuals
// share a sample (correlated); the same data then give 3.5, 2.2 and 7.9: the gyro factor is
// biased (docs/network.md).
TEST(NetworkVarianceComponents, RecoversKnownVarianceFactors) {
  NetworkOptions o;
  o.discretization = Discretization::kLeapFrog;
  // A noisy IMU against precise GPS, so that the GPS tests the IMU groups within 15 s (each
  // group needs redundancy: with a navigation-grade IMU the GPS absorbs all of it).
  o.acc_noise_mps2_rthz = 0.05;
  o.gyro_noise_radps_rthz = 0.02;
  o.sigma_gps_m = 0.002;
  // With this IMU the accelerometer bias is weakly determined in 15 s (pivot ratio ~3e-13, below
  // the conservative default tolerance), though not a defect.
  o.check_datum = false;
  const double dt = 0.1;
  auto fl = testing::MakeFlight(o, 150, dt, 1, 0);
  std::mt19937 rng(11);
  std::normal_distribution<double> nd(0.0, 1.0);
  const double sf = o.acc_noise_mps2_rthz / std::sqrt(dt), sw = o.gyro_noise_radps_rthz / std::sqrt(dt);
  for (Eigen::Index i = 0; i < fl.obs.acc_body_mps2.rows(); ++i)
    for (int c = 0; c < 3; ++c) {
      fl.obs.acc_body_mps2(i, c) += 2.0 * sf * nd(rng);
      fl.obs.gyro_body_radps(i, c) += 1.0 * sw * nd(rng);
    }
  for (Eigen::Index i = 0; i < fl.obs.gps_position_m.rows(); ++i)
    for (int c = 0; c < 3; ++c) fl.obs.gps_position_m(i, c) += 3.0 * o.sigma_gps_m * nd(rng);
  NetworkOptions estimated;
  NetworkSummary s;
  EstimateVarianceComponents(fl.obs, fl.truth, o, &estimated, &s, 10, 1e-3);
  const double f_acc = std::pow(estimated.acc_noise_mps2_rthz / o.acc_noise_mps2_rthz, 2);
  const double f_gyro = std::pow(estimated.gyro_noise_radps_rthz / o.gyro_noise_radps_rthz, 2);
  const double f_gps = std::pow(estimated.sigma_gps_m / o.sigma_gps_m, 2);
  // Redundancies 166 (acc), 123 (gyro), 133 (GPS): relative sd sqrt(2 / r) of 11-13 %.
  // Measured: 3.90, 1.06, 7.11.
  EXPECT_NEAR(f_acc, 4.0, 0.25 * 4.0);
  EXPECT_NEAR(f_gyro, 1.0, 0.25 * 1.0);
  EXPECT_NEAR(f_gps, 9.0, 0.25 * 9.0);
  EXPECT_NEAR(s.variance_factor_acc, 1.0, 0.05);
  EXPECT_GT(s.redundancy_acc, 50.0);
  EXPECT_GT(s.redundancy_gyro, 50.0);
  EXPECT_GT(s.redundancy_gps, 50.0);
}

}  // namespace
}  // namespace indoorloc::network
