// Noise-free flights that satisfy the network's discrete equations exactly: the IMU inputs are
// smooth functions of time and the true states follow from them by the leap-frog or the
// (implicit, iterated to convergence) trapezoidal recursion of network_adjustment.h.
#pragma once

#include <cmath>

#include <Eigen/Geometry>

#include "indoorloc/network/gravity.h"
#include "indoorloc/network/network_adjustment.h"

namespace indoorloc::network::testing {

inline Eigen::Quaterniond ExpQ(const Eigen::Vector3d& phi) {
  const double a = phi.norm();
  if (a < 1e-14) return Eigen::Quaterniond(1.0, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(a, phi / a));
}

struct Flight {
  NetworkObservations obs;
  NetworkState truth;
};

inline NetworkState AllocateState(int n) {
  NetworkState s;
  s.position_m = RowMatrixXd::Zero(n, 3);
  s.velocity_mps = RowMatrixXd::Zero(n, 3);
  s.attitude_wxyz = RowMatrixXd::Zero(n, 4);
  s.acc_bias_mps2 = RowMatrixXd::Zero(n, 3);
  s.gyro_bias_radps = RowMatrixXd::Zero(n, 3);
  s.gravity_disturbance_mps2 = Eigen::VectorXd::Zero(n);
  return s;
}

/// A flight of n epochs at step dt. `level`: no rotation at all (f = (0, 0, γ + δg), ω = Earth
/// rate), for datum-defect tests. GPS at every `gps_every`-th epoch starting at `gps_offset`.
/// Biases are constant and δg is constant unless `vary_gravity` (a 30 mGal sine): then every
/// random-walk residual is zero at the truth, which is the exact least-squares solution.
inline Flight MakeFlight(const NetworkOptions& o, int n, double dt, int gps_every = 1, int gps_offset = 0,
                         bool level = false, bool vary_gravity = false) {
  Flight fl;
  fl.obs.imu_time_s.resize(n);
  fl.obs.acc_body_mps2.resize(n, 3);
  fl.obs.gyro_body_radps.resize(n, 3);
  fl.truth = AllocateState(n);
  const Eigen::Vector3d wie = EarthRateEnu(o.latitude_rad) * (o.earth_rate_radps / kEarthRateRadps);
  const Eigen::Vector3d ab = level ? Eigen::Vector3d(0, 0, 2e-3) : Eigen::Vector3d(1e-3, -2e-3, 5e-4);
  const Eigen::Vector3d ob = level ? Eigen::Vector3d::Zero() : Eigen::Vector3d(1e-5, -2e-5, 3e-5);
  auto g = [&](double up, double dg) { return Eigen::Vector3d(0, 0, -(NormalGravity(o.latitude_rad, up + o.origin_height_m) + dg)); };
  std::vector<Eigen::Vector3d> r(n), v(n), f(n), w(n);
  std::vector<Eigen::Quaterniond> q(n);
  std::vector<double> dg(n);
  for (int i = 0; i < n; ++i) {
    const double t = i * dt;
    fl.obs.imu_time_s[i] = 100.0 + t;
    dg[i] = (vary_gravity ? 3e-4 * std::sin(0.05 * t) : 0.0) + 1e-4;
  }
  if (level) {
    // Straight and level at 50 m/s East; IMU reads exactly what the model predicts.
    for (int i = 0; i < n; ++i) {
      v[i] = Eigen::Vector3d(50, 0, 0);
      r[i] = Eigen::Vector3d(50 * i * dt, 0, 0);
      q[i] = Eigen::Quaterniond::Identity();
      f[i] = (2.0 * wie.cross(v[i]) - g(0.0, dg[i])) + ab;
      w[i] = wie + ob;
    }
  } else {
    for (int i = 0; i < n; ++i) {
      const double t = i * dt;
      f[i] = Eigen::Vector3d(0.3 * std::sin(0.4 * t), 0.2 * std::cos(0.3 * t),
                             NormalGravity(o.latitude_rad, o.origin_height_m) + 0.4 * std::sin(0.5 * t)) + ab;
      w[i] = Eigen::Vector3d(0.02 * std::sin(0.7 * t), 0.015 * std::cos(0.6 * t), 0.05 + 0.02 * std::sin(0.2 * t)) + ob;
    }
    r[0] = Eigen::Vector3d(10, 20, 0);
    v[0] = Eigen::Vector3d(50, 5, 0);
    q[0] = Eigen::Quaterniond::Identity();
    if (o.discretization == Discretization::kLeapFrog) {
      // Epoch 1 from a small explicit step, then x[n+1] = x[n-1] + 2δt rhs(n).
      q[1] = q[0] * ExpQ((w[0] - ob - q[0].conjugate() * wie) * dt);
      v[1] = v[0] + dt * (q[0] * (f[0] - ab) - 2.0 * wie.cross(v[0]) + g(r[0].z(), dg[0]));
      r[1] = r[0] + dt * v[0];
      for (int i = 1; i + 1 < n; ++i) {
        r[i + 1] = r[i - 1] + 2 * dt * v[i];
        v[i + 1] = v[i - 1] + 2 * dt * (q[i] * (f[i] - ab) - 2.0 * wie.cross(v[i]) + g(r[i].z(), dg[i]));
        q[i + 1] = (q[i - 1] * ExpQ(2 * dt * (w[i] - ob - q[i].conjugate() * wie))).normalized();
      }
      // VEL at the ends is not an equation; keep v consistent anyway (only n = 1..N-2 enter).
    } else {
      for (int i = 0; i + 1 < n; ++i) {
        Eigen::Quaterniond q1 = q[i];
        Eigen::Vector3d v1 = v[i], r1 = r[i];
        for (int it = 0; it < 50; ++it) {
          q1 = (q[i] * ExpQ(dt * (0.5 * (w[i] + w[i + 1]) - ob -
                                  0.5 * (q[i].conjugate() * wie + q1.conjugate() * wie)))).normalized();
          const Eigen::Vector3d sf = 0.5 * (q[i] * (f[i] - ab) + q1 * (f[i + 1] - ab));
          v1 = v[i] + dt * (sf - wie.cross(v[i] + v1) + 0.5 * (g(r[i].z(), dg[i]) + g(r1.z(), dg[i + 1])));
          r1 = r[i] + 0.5 * dt * (v[i] + v1);
        }
        q[i + 1] = q1;
        v[i + 1] = v1;
        r[i + 1] = r1;
      }
    }
  }
  for (int i = 0; i < n; ++i) {
    fl.obs.acc_body_mps2.row(i) = f[i].transpose();
    fl.obs.gyro_body_radps.row(i) = w[i].transpose();
    fl.truth.position_m.row(i) = r[i].transpose();
    fl.truth.velocity_mps.row(i) = v[i].transpose();
    fl.truth.attitude_wxyz.row(i) << q[i].w(), q[i].x(), q[i].y(), q[i].z();
    fl.truth.acc_bias_mps2.row(i) = ab.transpose();
    fl.truth.gyro_bias_radps.row(i) = ob.transpose();
    fl.truth.gravity_disturbance_mps2[i] = dg[i];
  }
  std::vector<int> gps;
  for (int i = gps_offset; i < n; i += gps_every) gps.push_back(i);
  fl.obs.gps_time_s.resize(static_cast<Eigen::Index>(gps.size()));
  fl.obs.gps_position_m.resize(static_cast<Eigen::Index>(gps.size()), 3);
  for (size_t k = 0; k < gps.size(); ++k) {
    fl.obs.gps_time_s[static_cast<Eigen::Index>(k)] = fl.obs.imu_time_s[gps[k]];
    fl.obs.gps_position_m.row(static_cast<Eigen::Index>(k)) = r[static_cast<size_t>(gps[k])].transpose();
  }
  // One GUPT in the middle (total gravity).
  fl.obs.gupt_epochs = Eigen::VectorXi::Constant(1, n / 2);
  fl.obs.gupt_gravity_mps2 =
      Eigen::VectorXd::Constant(1, NormalGravity(o.latitude_rad, r[static_cast<size_t>(n / 2)].z() + o.origin_height_m) + dg[static_cast<size_t>(n / 2)]);
  fl.obs.zupt_epochs.resize(0);
  fl.obs.xover_epochs.resize(0, 2);
  return fl;
}

/// The truth with deterministic perturbations (initial values for the solver).
inline NetworkState Perturb(const NetworkState& s, double scale = 1.0) {
  NetworkState p = s;
  for (Eigen::Index i = 0; i < s.position_m.rows(); ++i) {
    const double a = std::sin(0.37 * static_cast<double>(i)), b = std::cos(0.23 * static_cast<double>(i));
    p.position_m.row(i) += scale * Eigen::RowVector3d(0.5 * a, -0.3 * b, 0.2 * a * b);
    p.velocity_mps.row(i) += scale * Eigen::RowVector3d(0.1 * b, 0.05 * a, -0.02);
    Eigen::Quaterniond q(s.attitude_wxyz(i, 0), s.attitude_wxyz(i, 1), s.attitude_wxyz(i, 2), s.attitude_wxyz(i, 3));
    q = q * ExpQ(scale * Eigen::Vector3d(2e-3 * a, -2e-3 * b, 5e-3));
    p.attitude_wxyz.row(i) << q.w(), q.x(), q.y(), q.z();
    p.acc_bias_mps2.row(i).setZero();
    p.gyro_bias_radps.row(i).setZero();
    p.gravity_disturbance_mps2[i] = 0.0;
  }
  return p;
}

}  // namespace indoorloc::network::testing
