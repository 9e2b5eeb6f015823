#include "indoorloc/pdr/attitude_filter.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "indoorloc/core/random.h"

namespace indoorloc::pdr {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Rotation {
  Eigen::VectorXd time;
  RowMatrixXd acc, gyro, mag;
  std::vector<Eigen::Quaterniond, Eigen::aligned_allocator<Eigen::Quaterniond>> truth;
};

// A sensor turning with a smooth body rate (about all axes, up to ~0.7 rad/s) for 60 s at 100 Hz,
// specific force = Rᵀ (0, 0, g) (no linear acceleration), field (20, 0, −40) uT in the
// navigation frame (x magnetic north), gyro bias (0.01, −0.02, 0.015) rad/s, white noise.
Rotation MakeRotation(std::uint64_t seed, bool disturb_mag) {
  const double rate = 100.0;
  const int n = 6000;
  Rotation r;
  r.time.resize(n);
  r.acc.resize(n, 3);
  r.gyro.resize(n, 3);
  r.mag.resize(n, 3);
  RandomStream rng(seed);
  // Start tilted (roll 10°, pitch −5°) with yaw 0 so that the filter's levelled start is right.
  Eigen::Quaterniond q = Eigen::AngleAxisd(-5 * kPi / 180, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(10 * kPi / 180, Eigen::Vector3d::UnitX());
  const Eigen::Vector3d bias(0.01, -0.02, 0.015), field(20.0, 0.0, -40.0);
  for (int k = 0; k < n; ++k) {
    const double t = k / rate;
    const Eigen::Vector3d w = t < 2.0 ? Eigen::Vector3d::Zero()
                                      : Eigen::Vector3d(0.3 * std::sin(0.5 * t), 0.25 * std::cos(0.3 * t), 0.6 * std::sin(0.2 * t));
    if (k > 0) q = (q * Eigen::Quaterniond(Eigen::AngleAxisd(w.norm() / rate, w.norm() > 0 ? w.normalized() : Eigen::Vector3d::UnitZ()))).normalized();
    r.time[k] = t;
    r.truth.push_back(q);
    const Eigen::Matrix3d rt = q.toRotationMatrix().transpose();
    r.acc.row(k) = (rt * Eigen::Vector3d(0, 0, 9.81)).transpose();
    Eigen::Vector3d m = rt * field;
    if (disturb_mag && t > 30.0 && t < 40.0) m += Eigen::Vector3d(60.0, -40.0, 10.0);  // a steel door
    r.mag.row(k) = m.transpose();
    r.gyro.row(k) = (w + bias).transpose();
    for (int c = 0; c < 3; ++c) {
      r.acc(k, c) += 0.02 * rng.Normal();
      r.gyro(k, c) += 0.002 * rng.Normal();
      r.mag(k, c) += 0.2 * rng.Normal();
    }
  }
  return r;
}

double AngleError(const AttitudeOutput& out, const Rotation& r, Eigen::Index k) {
  const Eigen::Quaterniond q(out.quaternions_wxyz(k, 0), out.quaternions_wxyz(k, 1), out.quaternions_wxyz(k, 2), out.quaternions_wxyz(k, 3));
  return q.angularDistance(r.truth[static_cast<size_t>(k)]);
}

double TiltError(const AttitudeOutput& out, const Rotation& r, Eigen::Index k) {
  const Eigen::Quaterniond q(out.quaternions_wxyz(k, 0), out.quaternions_wxyz(k, 1), out.quaternions_wxyz(k, 2), out.quaternions_wxyz(k, 3));
  const Eigen::Vector3d up_est = q.toRotationMatrix().transpose().col(2), up = r.truth[static_cast<size_t>(k)].toRotationMatrix().transpose().col(2);
  return std::acos(std::clamp(up_est.dot(up), -1.0, 1.0));
}

TEST(Mahony, TracksASyntheticRotationWithMagnetometer) {
  const Rotation r = MakeRotation(1, false);
  const AttitudeOutput out = RunMahony(r.time, r.acc, r.gyro, r.mag);
  double worst = 0;
  // After 20 s the bias has converged (time constant kp / ki = 20 s): within 1.5° throughout.
  for (Eigen::Index k = 2000; k < r.time.size(); ++k) worst = std::max(worst, AngleError(out, r, k));
  EXPECT_LT(worst, 1.5 * kPi / 180) << "worst attitude error " << worst * 180 / kPi << " deg";
  EXPECT_EQ(out.mag_rejected, 0);
  // The integral term learns the gyro bias.
  EXPECT_LT((out.gyro_bias_radps.bottomRows(1).transpose() - Eigen::Vector3d(0.01, -0.02, 0.015)).norm(), 0.005)
      << out.gyro_bias_radps.bottomRows(1);
}

TEST(Mahony, WithoutMagnetometerKeepsTheTilt) {
  const Rotation r = MakeRotation(2, false);
  const AttitudeOutput out = RunMahony(r.time, r.acc, r.gyro, RowMatrixXd(0, 3));
  double worst = 0;
  for (Eigen::Index k = 0; k < r.time.size(); ++k) worst = std::max(worst, TiltError(out, r, k));
  EXPECT_LT(worst, 2.0 * kPi / 180);
}

TEST(Mahony, DisturbanceTestRejectsADisturbedField) {
  const Rotation r = MakeRotation(3, true);
  const AttitudeOutput gated = RunMahony(r.time, r.acc, r.gyro, r.mag);
  MahonyOptions loose;
  loose.mag_norm_tolerance = 10.0;
  loose.mag_dip_tolerance_rad = 10.0;
  const AttitudeOutput ungated = RunMahony(r.time, r.acc, r.gyro, r.mag, loose);
  double worst_gated = 0, worst_ungated = 0;
  for (Eigen::Index k = 1000; k < r.time.size(); ++k) {
    worst_gated = std::max(worst_gated, AngleError(gated, r, k));
    worst_ungated = std::max(worst_ungated, AngleError(ungated, r, k));
  }
  EXPECT_GT(gated.mag_rejected, 900);  // the 10 s (1000 samples) of disturbance
  EXPECT_LT(worst_gated, 3.0 * kPi / 180);
  EXPECT_GT(worst_ungated, 2.0 * worst_gated);
}

TEST(Mahony, BadInputGivesClearErrors) {
  const Rotation r = MakeRotation(4, false);
  RowMatrixXd bad = r.gyro;
  bad(5, 2) = std::nan("");
  EXPECT_THROW(RunMahony(r.time, r.acc, bad, RowMatrixXd(0, 3)), std::invalid_argument);
  EXPECT_THROW(RunMahony(r.time, r.acc / 9.81 / 100.0, r.gyro, RowMatrixXd(0, 3)), std::invalid_argument);
  EXPECT_THROW(RunMahony(r.time.head(10), r.acc, r.gyro, RowMatrixXd(0, 3)), std::invalid_argument);
  EXPECT_THROW(RunMahony(r.time, r.acc, r.gyro, r.mag.topRows(10)), std::invalid_argument);
}

// Issue 17: gains of inf passed ">= 0" and made every quaternion NaN.
TEST(Mahony, NonFiniteGainsAreRefusedNamingTheGain) {
  const Rotation r = MakeRotation(2, false);
  for (const char* name : {"kp", "ki", "kp_mag", "gravity_mps2"}) {
    MahonyOptions o;
    if (std::string(name) == "kp") o.kp = INFINITY;
    if (std::string(name) == "ki") o.ki = INFINITY;
    if (std::string(name) == "kp_mag") o.kp_mag = INFINITY;
    if (std::string(name) == "gravity_mps2") o.gravity_mps2 = INFINITY;
    try {
      RunMahony(r.time, r.acc, r.gyro, RowMatrixXd(0, 3), o);
      ADD_FAILURE() << name << ": no exception";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("'options': ") + name + " "), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace indoorloc::pdr
