#include "indoorloc/pdr/zupt_ekf.h"

#include <cmath>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "indoorloc/core/random.h"
#include "indoorloc/pdr/step_detection.h"
#include "indoorloc/pdr/zero_velocity.h"

namespace indoorloc::pdr {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A synthetic gait at 200 Hz: 0.5 s stance, then a 0.6 s swing that moves the foot 1.4 m along
// the heading with a raised-cosine speed profile, a 10 cm lift and a pitch of the foot of up to
// 30° (the rotation a detector sees in real swings), repeated `steps` times, ending with a stance.
// The sensor is mounted upside down (body z down), as on PyShoe's foot.
struct Gait {
  Eigen::VectorXd time;
  RowMatrixXd acc, gyro, position;
  int steps;
};

Gait MakeGait(int steps, double heading_rad, double noise, std::uint64_t seed) {
  const double rate = 200.0, stance = 0.5, swing = 0.6, stride = 1.4, lift = 0.1;
  const int n_stance = static_cast<int>(stance * rate), n_swing = static_cast<int>(swing * rate);
  const int n = steps * (n_stance + n_swing) + n_stance;
  Gait g;
  g.steps = steps;
  g.time.resize(n);
  g.acc.resize(n, 3);
  g.gyro = RowMatrixXd::Zero(n, 3);
  g.position.resize(n, 3);
  // body_to_nav(t) = Rz(heading) Ry(pitch(t)) Rx(π); the body rate is then pitch'(t) Rx(π)ᵀ e_y.
  auto body_to_nav = [&](double pitch) {
    return (Eigen::AngleAxisd(heading_rad, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
            Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX())).toRotationMatrix();
  };
  const double max_pitch = 30.0 * kPi / 180.0;
  const Eigen::Vector3d dir(std::cos(heading_rad), std::sin(heading_rad), 0.0);
  RandomStream rng(seed);
  int k = 0;
  Eigen::Vector3d base = Eigen::Vector3d::Zero();
  auto emit = [&](const Eigen::Vector3d& pos, const Eigen::Vector3d& a_nav, double pitch, double pitch_rate) {
    g.time[k] = k / rate;
    g.position.row(k) = pos.transpose();
    const Eigen::Vector3d f_nav = a_nav + Eigen::Vector3d(0, 0, 9.81);
    g.acc.row(k) = (body_to_nav(pitch).transpose() * f_nav).transpose();
    g.gyro.row(k) = (pitch_rate * (Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()).toRotationMatrix().transpose() *
                                   Eigen::Vector3d::UnitY())).transpose();
    for (int c = 0; c < 3; ++c) {
      g.acc(k, c) += noise * rng.Normal();
      g.gyro(k, c) += 0.1 * noise * rng.Normal();
    }
    ++k;
  };
  for (int s = 0; s <= steps; ++s) {
    for (int i = 0; i < n_stance; ++i) emit(base, Eigen::Vector3d::Zero(), 0.0, 0.0);
    if (s == steps) break;
    for (int i = 0; i < n_swing; ++i) {
      const double u = (i + 1) / static_cast<double>(n_swing);  // 0..1
      // Horizontal: s(u) = stride (u - sin(2πu)/(2π)); vertical: lift (1 - cos 2πu)/2.
      const double horizontal = stride * (u - std::sin(2 * kPi * u) / (2 * kPi));
      // Second derivatives in time (t = u * swing): d²s/dt² = stride * 2π sin(2πu) / swing²,
      // d²z/dt² = lift * (2π)² cos(2πu) / (2 swing²).
      const double acc_h = stride * 2 * kPi * std::sin(2 * kPi * u) / (swing * swing);
      const double acc_z = lift * (2 * kPi) * (2 * kPi) * std::cos(2 * kPi * u) / (2 * swing * swing);
      const Eigen::Vector3d pos = base + horizontal * dir + Eigen::Vector3d(0, 0, lift * (1 - std::cos(2 * kPi * u)) / 2);
      // Pitch (1 - cos 2πu)/2 * max: zero with zero rate at both ends of the swing.
      const double pitch = max_pitch * (1 - std::cos(2 * kPi * u)) / 2;
      const double pitch_rate = max_pitch * kPi * std::sin(2 * kPi * u) / swing;
      emit(pos, acc_h * dir + Eigen::Vector3d(0, 0, acc_z), pitch, pitch_rate);
    }
    base += stride * dir;
  }
  return g;
}

int CountStanceBlocks(const BoolVector& stance) {
  int blocks = 0;
  for (Eigen::Index k = 0; k < stance.size(); ++k) blocks += stance[k] && (k == 0 || !stance[k - 1]);
  return blocks;
}

TEST(ShoeDetector, FindsEveryStancePhaseOfASyntheticGait) {
  const Gait g = MakeGait(12, 0.3, 0.0, 1);
  ShoeOptions o;
  const BoolVector stance = ShoeDetector(g.acc, g.gyro, o);
  EXPECT_EQ(CountStanceBlocks(stance), g.steps + 1);
}

TEST(StepDetection, AccelerationAndGyroDetectorsFindEveryStep) {
  for (double noise : {0.0, 0.02}) {
    const Gait g = MakeGait(15, 1.0, noise, 6);
    const std::vector<int> acc_steps = DetectStepsAcceleration(200.0, g.acc, AccelerationStepOptions());
    EXPECT_EQ(static_cast<int>(acc_steps.size()), g.steps) << "noise " << noise;
    GyroStepOptions gyro_options;
    gyro_options.threshold_radps = 0.5;  // the synthetic foot pitches at most ~1.6 rad/s
    const std::vector<int> gyro_steps = DetectStepsGyro(200.0, g.gyro, gyro_options);
    EXPECT_EQ(static_cast<int>(gyro_steps.size()), g.steps) << "noise " << noise;
  }
  EXPECT_THROW(DetectStepsAcceleration(200.0, RowMatrixXd::Zero(10, 3), AccelerationStepOptions()), std::invalid_argument);
  EXPECT_THROW(DetectStepsGyro(-1.0, RowMatrixXd::Zero(100, 3), GyroStepOptions()), std::invalid_argument);
}

TEST(ZuptEkf, RecoversTheWalkedPathAndZeroesVelocityAtStance) {
  const Gait g = MakeGait(12, 0.0, 0.0, 2);
  const BoolVector stance = ShoeDetector(g.acc, g.gyro, ShoeOptions());
  const ZuptEkfOutput out = RunZuptEkf(g.time, g.acc, g.gyro, stance);
  const Eigen::Index last = g.time.size() - 1;
  // First-order mechanisation at 200 Hz: within 1 % of the 16.8 m walked.
  EXPECT_LT((out.positions_m.row(last) - g.position.row(last)).norm(), 0.01 * 12 * 1.4) << out.positions_m.row(last);
  for (Eigen::Index k = 0; k <= last; ++k) {
    if (stance[k]) {
      ASSERT_LT(out.velocities_mps.row(k).norm(), 0.05) << "sample " << k;
    }
  }
}

TEST(ZuptEkf, NoisySensorsStayWithinAFewPercentOfTheDistance) {
  const Gait g = MakeGait(20, 0.0, 0.02, 3);
  ShoeOptions so;
  so.sigma_acc_mps2 = 0.02;
  so.sigma_gyro_radps = 0.002;
  so.threshold = 30.0;  // E[T] = 6 (6 degrees of freedom) at rest with matched noise sds
  const BoolVector stance = ShoeDetector(g.acc, g.gyro, so);
  EXPECT_EQ(CountStanceBlocks(stance), g.steps + 1);
  const ZuptEkfOutput out = RunZuptEkf(g.time, g.acc, g.gyro, stance);
  const Eigen::Index last = g.time.size() - 1;
  EXPECT_LT((out.positions_m.row(last) - g.position.row(last)).norm(), 0.03 * 20 * 1.4);
}

TEST(ZuptEkf, SmootherKeepsTheEndAndImprovesTheMiddle) {
  const Gait g = MakeGait(20, 0.4, 0.02, 5);
  ShoeOptions so;
  so.sigma_acc_mps2 = 0.02;
  so.sigma_gyro_radps = 0.002;
  so.threshold = 30.0;
  const BoolVector stance = ShoeDetector(g.acc, g.gyro, so);
  ZuptEkfOptions o;
  o.smooth = true;
  const ZuptEkfOutput out = RunZuptEkf(g.time, g.acc, g.gyro, stance, o);
  const Eigen::Index last = g.time.size() - 1;
  // The last sample has no future: smoothed = filtered there.
  EXPECT_LT((out.positions_m.row(last) - out.filtered_positions_m.row(last)).norm(), 1e-12);
  double filtered = 0, smoothed = 0;
  for (Eigen::Index k = 0; k <= last; ++k) {
    filtered += (out.filtered_positions_m.row(k) - g.position.row(k)).squaredNorm();
    smoothed += (out.positions_m.row(k) - g.position.row(k)).squaredNorm();
  }
  EXPECT_TRUE(out.positions_m.allFinite());
  EXPECT_LE(smoothed, filtered * 1.05);
}

TEST(ZuptEkf, BadInputGivesClearErrors) {
  const Gait g = MakeGait(2, 0.0, 0.0, 4);
  const BoolVector stance = ShoeDetector(g.acc, g.gyro, ShoeOptions());
  RowMatrixXd nan_acc = g.acc;
  nan_acc(10, 1) = std::nan("");
  EXPECT_THROW(RunZuptEkf(g.time, nan_acc, g.gyro, stance), std::invalid_argument);
  EXPECT_THROW(RunZuptEkf(g.time.head(5), g.acc, g.gyro, stance), std::invalid_argument);
  EXPECT_THROW(ShoeDetector(g.acc.topRows(3), g.gyro.topRows(3), ShoeOptions()), std::invalid_argument);  // shorter than a window
  RowMatrixXd in_g = g.acc / 9.81;  // accelerometer in g declared as m/s^2
  EXPECT_THROW(RunZuptEkf(g.time, in_g / 100.0, g.gyro, stance), std::invalid_argument);
  Eigen::VectorXd repeated = g.time;
  repeated[7] = repeated[6];  // a repeated timestamp is handled (median period)
  EXPECT_NO_THROW(RunZuptEkf(repeated, g.acc, g.gyro, stance));
}

}  // namespace
}  // namespace indoorloc::pdr
