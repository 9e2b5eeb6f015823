// A synthetic foot-mounted gait with known steps, positions and attitudes, shared by the pdr tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "indoorloc/core/random.h"
#include "indoorloc/pdr/zero_velocity.h"

namespace indoorloc::pdr::synthetic {

constexpr double kPi = 3.14159265358979323846;

// A synthetic gait at 200 Hz: 0.5 s stance, then a 0.6 s swing that moves the foot 1.4 m along
// the heading with a raised-cosine speed profile, a 10 cm lift and a pitch of the foot of up to
// 30° (the rotation a detector sees in real swings), repeated `steps` times, ending with a stance.
// The sensor is mounted upside down (body z down), as on PyShoe's foot.
struct Gait {
  Eigen::VectorXd time;
  RowMatrixXd acc, gyro, position;
  RowMatrixXd quaternions;  ///< N x 4 body -> nav (w, x, y, z)
  std::vector<int> mid_stance;  ///< the middle sample of each stance phase (steps + 1)
  int steps;
};

inline Gait MakeGait(int steps, double heading_rad, double noise, std::uint64_t seed) {
  const double rate = 200.0, stance = 0.5, swing = 0.6, stride = 1.4, lift = 0.1;
  const int n_stance = static_cast<int>(stance * rate), n_swing = static_cast<int>(swing * rate);
  const int n = steps * (n_stance + n_swing) + n_stance;
  Gait g;
  g.steps = steps;
  g.time.resize(n);
  g.acc.resize(n, 3);
  g.gyro = RowMatrixXd::Zero(n, 3);
  g.position.resize(n, 3);
  g.quaternions.resize(n, 4);
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
    const Eigen::Quaterniond qt(body_to_nav(pitch));
    g.quaternions.row(k) << qt.w(), qt.x(), qt.y(), qt.z();
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
    g.mid_stance.push_back(k + n_stance / 2);
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

}  // namespace indoorloc::pdr::synthetic
