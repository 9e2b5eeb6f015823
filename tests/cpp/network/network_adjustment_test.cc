// The network adjustment on noise-free flights that satisfy its discrete equations exactly,
// datum defects, the leap-frog parity decoupling and the Kalman smoother. The cross-over finder
// has its own tests (crossovers_test.cc).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <initializer_list>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

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

namespace indoorloc::network {
namespace {

Eigen::VectorXi Ints(std::initializer_list<int> values) {
  Eigen::VectorXi v(static_cast<Eigen::Index>(values.size()));
  Eigen::Index i = 0;
  for (int x : values) v[i++] = x;
  return v;
}

// Slow parameters (paper §4): biases and δg carried once per `stride` IMU epochs. The fixture's
// biases and δg are constant, so the piecewise-constant slow blocks represent the truth exactly
// and the noise-free flight is still recovered; the unknowns drop from 16 N to 9 N + 7 ⌈N/s⌉.
TEST(NetworkSlowParameters, NoiseFreeFlightIsRecoveredWithFewerUnknowns) {
  for (const Discretization d : {Discretization::kTrapezoidal, Discretization::kLeapFrog}) {
    NetworkOptions o = TightOptions(d);
    const auto fl = MakeFlight(o, 300, 0.1);
    for (const int stride : {10, 7}) {
      o.slow_parameter_stride = stride;
      NetworkSummary s;
      const NetworkState est = SolveNetwork(fl.obs, Perturb(fl.truth), o, &s);
      EXPECT_EQ(s.termination, Termination::kConverged) << s.message;
      const int m = (300 + stride - 1) / stride;
      EXPECT_EQ(s.num_slow_nodes, m);
      EXPECT_EQ(s.num_parameters, 9L * 300 + 7L * m);
      ExpectRecovered(est, fl.truth);
      // Epochs of one interval share the block's value.
      EXPECT_EQ(est.gravity_disturbance_mps2[0], est.gravity_disturbance_mps2[stride - 1]);
      EXPECT_EQ(est.acc_bias_mps2(stride, 2), est.acc_bias_mps2(2 * stride - 1, 2));
    }
  }
}

// XOVER and GUPT refer to the δg block of their epoch's interval; a tie inside one interval holds
// identically and is dropped. The dense δg covariance and ceres::Covariance agree and are equal
// within an interval.
TEST(NetworkSlowParameters, CrossoverGuptAndCovarianceUseTheIntervalBlock) {
  NetworkOptions o = TightOptions(Discretization::kTrapezoidal);
  auto fl = MakeFlight(o, 120, 0.1, 10, 0);
  fl.obs.xover_epochs.resize(2, 2);
  fl.obs.xover_epochs << 5, 95, 31, 38;  // the second is inside the interval [30, 40)
  o.slow_parameter_stride = 10;
  o.gravity_covariance = NetworkOptions::Covariance::kDense;
  NetworkSummary s;
  const NetworkState dense = SolveNetwork(fl.obs, Perturb(fl.truth), o, &s);
  EXPECT_EQ(s.num_xover, 1);
  ExpectRecovered(dense, fl.truth);
  o.gravity_covariance = NetworkOptions::Covariance::kCeres;
  const NetworkState sparse = SolveNetwork(fl.obs, fl.truth, o);
  for (int i = 0; i < 120; ++i) {
    EXPECT_NEAR(sparse.gravity_disturbance_sd_mps2[i], dense.gravity_disturbance_sd_mps2[i],
                1e-6 * dense.gravity_disturbance_sd_mps2[i]);
    EXPECT_EQ(dense.gravity_disturbance_sd_mps2[i], dense.gravity_disturbance_sd_mps2[10 * (i / 10)]);
  }
  // The GUPT at epoch 60 pins the block [60, 70): the smallest sd.
  Eigen::Index k;
  dense.gravity_disturbance_sd_mps2.minCoeff(&k);
  EXPECT_EQ(k / 10, 6);
  // The cross-over ties δg of the blocks of epochs 5 and 95: their sds fall below those without it.
  fl.obs.xover_epochs.resize(0, 2);
  o.gravity_covariance = NetworkOptions::Covariance::kDense;
  const NetworkState no_xover = SolveNetwork(fl.obs, fl.truth, o);
  EXPECT_LT(dense.gravity_disturbance_sd_mps2[5], no_xover.gravity_disturbance_sd_mps2[5]);
  EXPECT_LT(dense.gravity_disturbance_sd_mps2[95], no_xover.gravity_disturbance_sd_mps2[95]);
}

// The datum check names the epoch of a slow block: the level flight without GUPT cannot separate
// δg from the vertical accelerometer bias, with slow parameters too.
TEST(NetworkSlowParameters, DatumCheckNamesSlowBlocks) {
  NetworkOptions o = TightOptions(Discretization::kTrapezoidal);
  o.slow_parameter_stride = 5;
  auto fl = MakeFlight(o, 60, 0.1, 5, 0, /*level=*/true);
  fl.obs.gupt_epochs.resize(0);
  fl.obs.gupt_gravity_mps2.resize(0);
  try {
    SolveNetwork(fl.obs, fl.truth, o);
    ADD_FAILURE() << "no datum defect reported";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'observations'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("datum defect"), std::string::npos) << e.what();
  }
}

// VUPT (paper §3.4: v0 + w_v = v[n]): at the truth the noise-free network still fits exactly; a
// tight VUPT with a velocity 5 cm/s off pulls v[n] to it, a loose one barely moves it.
TEST(NetworkStaticObservations, VuptIsFittedWithItsOwnSigma) {
  NetworkOptions o = TightOptions(Discretization::kTrapezoidal);
  auto fl = MakeFlight(o, 200, 0.1, 10, 0);
  fl.obs.vupt_epochs = Eigen::VectorXi::LinSpaced(4, 20, 170);
  fl.obs.vupt_velocity_mps.resize(4, 3);
  for (int i = 0; i < 4; ++i) fl.obs.vupt_velocity_mps.row(i) = fl.truth.velocity_mps.row(fl.obs.vupt_epochs[i]);
  NetworkSummary s;
  ExpectRecovered(SolveNetwork(fl.obs, Perturb(fl.truth), o, &s), fl.truth);
  EXPECT_EQ(s.num_vupt, 4);
  const int e = fl.obs.vupt_epochs[1];
  fl.obs.vupt_velocity_mps(1, 0) += 0.05;
  fl.obs.vupt_sd_mps = Eigen::VectorXd::Constant(4, 1e-6);
  const double tight = SolveNetwork(fl.obs, fl.truth, o).velocity_mps(e, 0) - fl.truth.velocity_mps(e, 0);
  fl.obs.vupt_sd_mps.setConstant(10.0);
  const double loose = SolveNetwork(fl.obs, fl.truth, o).velocity_mps(e, 0) - fl.truth.velocity_mps(e, 0);
  EXPECT_NEAR(tight, 0.05, 1e-3);
  EXPECT_LT(std::abs(loose), 1e-4);
  // Without vupt_sd_mps the options' sigma_vupt_mps applies.
  fl.obs.vupt_sd_mps.resize(0);
  o.sigma_vupt_mps = 1e-6;
  EXPECT_NEAR(SolveNetwork(fl.obs, fl.truth, o).velocity_mps(e, 0) - fl.truth.velocity_mps(e, 0), 0.05, 1e-3);
}

// SGUPT (paper §3.2): gravity constant over a static period, ties δg[n] = δg[n0]. The fixture
// flight moves, so the "static" epochs carry ZUPTs with a huge sd (no information, but formally
// static); the δg of that flight varies (30 mGal sine), and the tight SGUPT holds it constant over
// the period; with slow parameters the ties are per block.
TEST(NetworkStaticObservations, SguptHoldsGravityConstantOverAStaticPeriod) {
  NetworkOptions o = TightOptions(Discretization::kTrapezoidal);
  o.sigma_zupt_mps = 1e6;
  o.sigma_sgupt_mps2 = 1e-9;
  // mm GPS at every epoch and a loose δg random walk: without SGUPT the estimate follows the truth.
  o.sigma_gps_m = 1e-5;
  o.gravity_walk_mps2_rts = 1e-2;
  auto fl = MakeFlight(o, 200, 0.1, 1, 0, false, /*vary_gravity=*/true);
  fl.obs.zupt_epochs = Eigen::VectorXi::LinSpaced(51, 100, 150);
  fl.obs.sgupt_epochs = fl.obs.zupt_epochs;
  NetworkSummary s;
  const NetworkState est = SolveNetwork(fl.obs, fl.truth, o, &s);
  EXPECT_EQ(s.num_sgupt, 50);
  const Eigen::VectorXd period = est.gravity_disturbance_mps2.segment(100, 51);
  EXPECT_LT(period.maxCoeff() - period.minCoeff(), 1e-7);
  const Eigen::VectorXd truth = fl.truth.gravity_disturbance_mps2.segment(100, 51);
  EXPECT_GT(truth.maxCoeff() - truth.minCoeff(), 1e-5);  // the truth varies by > 1 mGal there
  // Without SGUPT the estimate follows the varying truth.
  fl.obs.sgupt_epochs.resize(0);
  const Eigen::VectorXd free = SolveNetwork(fl.obs, fl.truth, o).gravity_disturbance_mps2.segment(100, 51);
  EXPECT_GT(free.maxCoeff() - free.minCoeff(), 1e-5);
  // Slow parameters: blocks [100, 110), ..., [150, 160): 5 ties to the first.
  fl.obs.sgupt_epochs = fl.obs.zupt_epochs;
  o.slow_parameter_stride = 10;
  SolveNetwork(fl.obs, fl.truth, o, &s);
  EXPECT_EQ(s.num_sgupt, 5);
}

TEST(NetworkStaticObservations, BadVuptSguptAndSlowOptionsNameTheArgument) {
  const NetworkOptions o;
  auto good = MakeFlight(o, 30, 0.1);
  good.obs.vupt_epochs = Eigen::VectorXi::Constant(2, 3);
  good.obs.vupt_epochs[1] = 4;
  good.obs.vupt_velocity_mps = good.truth.velocity_mps.middleRows(3, 2);
  auto expect_throw = [&](auto mutate, const std::string& name) {
    auto fl = good;
    NetworkOptions opt = o;
    mutate(fl, opt);
    try {
      SolveNetwork(fl.obs, fl.truth, opt);
      ADD_FAILURE() << "no exception for " << name;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("'" + name + "'"), std::string::npos) << e.what();
    }
  };
  using F = testing::Flight;
  expect_throw([](F& f, NetworkOptions&) { f.obs.vupt_epochs[1] = 30; }, "vupt_epochs");
  expect_throw([](F& f, NetworkOptions&) { f.obs.vupt_epochs[1] = -1; }, "vupt_epochs");
  expect_throw([](F& f, NetworkOptions&) { f.obs.vupt_velocity_mps(1, 2) = std::nan(""); }, "vupt_velocity_mps");
  expect_throw([](F& f, NetworkOptions&) { f.obs.vupt_velocity_mps.resize(1, 3); }, "vupt_velocity_mps");
  expect_throw([](F& f, NetworkOptions&) { f.obs.vupt_sd_mps = Eigen::Vector2d(0.1, 0.0); }, "vupt_sd_mps");
  expect_throw([](F& f, NetworkOptions&) { f.obs.vupt_sd_mps = Eigen::Vector2d(0.1, std::nan("")); }, "vupt_sd_mps");
  expect_throw([](F& f, NetworkOptions&) { f.obs.vupt_sd_mps = Eigen::Vector3d(0.1, 0.1, 0.1); }, "vupt_sd_mps");
  // SGUPT at a moving epoch (the VUPT velocities are not zero), out of range, not increasing.
  expect_throw([](F& f, NetworkOptions&) { f.obs.sgupt_epochs = Ints({3, 4}); }, "sgupt_epochs");
  expect_throw([](F& f, NetworkOptions&) { f.obs.sgupt_epochs = Ints({3, 40}); }, "sgupt_epochs");
  expect_throw(
      [](F& f, NetworkOptions&) {
        f.obs.zupt_epochs = Ints({3, 4});
        f.obs.sgupt_epochs = Ints({4, 3});
      },
      "sgupt_epochs");
  expect_throw([](F&, NetworkOptions& p) { p.sigma_vupt_mps = 0.0; }, "options");
  expect_throw([](F&, NetworkOptions& p) { p.sigma_sgupt_mps2 = -1.0; }, "options");
  expect_throw([](F&, NetworkOptions& p) { p.slow_parameter_stride = 0; }, "options");
  // A VUPT with zero velocity makes an epoch static too.
  const NetworkOptions trap = TightOptions(Discretization::kTrapezoidal);
  auto fl = MakeFlight(trap, 120, 0.1, 10, 0);
  fl.obs.vupt_epochs = good.obs.vupt_epochs;
  fl.obs.vupt_velocity_mps = RowMatrixXd::Zero(2, 3);
  fl.obs.vupt_sd_mps = Eigen::Vector2d(1e6, 1e6);
  fl.obs.sgupt_epochs = Ints({3, 4});
  NetworkSummary s;
  SolveNetwork(fl.obs, fl.truth, trap, &s);
  EXPECT_EQ(s.num_sgupt, 1);
}

// Issue 17: a stride near 2**31 overflowed ⌈n / stride⌉ and aborted inside Ceres ("Check failed:
// values != nullptr"). Any stride >= N is one slow node for the whole flight.
TEST(NetworkSlowParameters, HugeStrideIsOneSlowNode) {
  NetworkOptions o = TightOptions(Discretization::kTrapezoidal);
  const auto fl = MakeFlight(o, 120, 0.1);
  for (const int stride : {120, 1000, 2147483647}) {
    o.slow_parameter_stride = stride;
    NetworkSummary s;
    EXPECT_NO_THROW(SolveNetwork(fl.obs, Perturb(fl.truth), o, &s)) << stride;
    EXPECT_EQ(s.num_slow_nodes, 1) << stride;
  }
}


}  // namespace
}  // namespace indoorloc::network
