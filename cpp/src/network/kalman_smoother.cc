// Error-state EKF + RTS smoother (SSA baseline of paper 003). See the header for the equations.
#include "indoorloc/network/kalman_smoother.h"

#include <cmath>
#include <sstream>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/network/gravity.h"

namespace indoorloc::network {

namespace {

using Mat16 = Eigen::Matrix<double, 16, 16>;
using Vec16 = Eigen::Matrix<double, 16, 1>;
enum : int { kP = 0, kV = 3, kE = 6, kA = 9, kO = 12, kG = 15 };

Eigen::Matrix3d Skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return s;
}

Eigen::Quaterniond ExpQ(const Eigen::Vector3d& phi) {
  const double a = phi.norm();
  if (a < 1e-12) return Eigen::Quaterniond(1.0, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(a, phi / a));
}

struct Nominal {
  Eigen::Vector3d r, v, a, o;
  Eigen::Quaterniond q;
  double dg = 0.0;
};

void Inject(Nominal& x, const Vec16& d) {
  x.r += d.segment<3>(kP);
  x.v += d.segment<3>(kV);
  x.q = (ExpQ(d.segment<3>(kE)) * x.q).normalized();
  x.a += d.segment<3>(kA);
  x.o += d.segment<3>(kO);
  x.dg += d[kG];
}

void Store(const Nominal& x, int i, NetworkState& s) {
  s.position_m.row(i) = x.r.transpose();
  s.velocity_mps.row(i) = x.v.transpose();
  s.attitude_wxyz.row(i) << x.q.w(), x.q.x(), x.q.y(), x.q.z();
  s.acc_bias_mps2.row(i) = x.a.transpose();
  s.gyro_bias_radps.row(i) = x.o.transpose();
  s.gravity_disturbance_mps2[i] = x.dg;
}

NetworkState Allocate(int n) {
  NetworkState s;
  s.position_m.resize(n, 3);
  s.velocity_mps.resize(n, 3);
  s.attitude_wxyz.resize(n, 4);
  s.acc_bias_mps2.resize(n, 3);
  s.gyro_bias_radps.resize(n, 3);
  s.gravity_disturbance_mps2.resize(n);
  return s;
}

/// Joseph-form update of (x, P) with z - h(x) = innovation, H, R; returns the error correction.
template <int kM>
Vec16 Update(Mat16& p, const Eigen::Matrix<double, kM, 1>& innovation, const Eigen::Matrix<double, kM, 16>& h,
             const Eigen::Matrix<double, kM, kM>& r) {
  const Eigen::Matrix<double, kM, kM> s = h * p * h.transpose() + r;
  const Eigen::Matrix<double, 16, kM> k = p * h.transpose() * s.inverse();
  const Mat16 ikh = Mat16::Identity() - k * h;
  p = ikh * p * ikh.transpose() + k * r * k.transpose();
  p = 0.5 * (p + p.transpose()).eval();
  return k * innovation;
}

/// The nominal state of row `k` of `s` (the inverse of Store).
Nominal Load(const NetworkState& s, int k) {
  Nominal x;
  x.r = s.position_m.row(k).transpose();
  x.v = s.velocity_mps.row(k).transpose();
  x.q = Eigen::Quaterniond(s.attitude_wxyz(k, 0), s.attitude_wxyz(k, 1), s.attitude_wxyz(k, 2), s.attitude_wxyz(k, 3));
  x.a = s.acc_bias_mps2.row(k).transpose();
  x.o = s.gyro_bias_radps.row(k).transpose();
  x.dg = s.gravity_disturbance_mps2[k];
  return x;
}

/// The network checks of shapes and values, with the initial row broadcast to every epoch.
void CheckInput(const NetworkObservations& obs, const NetworkState& initial) {
  const int n = static_cast<int>(obs.imu_time_s.size());
  CheckArgument(initial.position_m.rows() >= 1, "initial", "needs at least one row (the initial state)");
  NetworkState probe = Allocate(n);
  for (int i = 0; i < n; ++i) {
    probe.position_m.row(i) = initial.position_m.row(0);
    probe.velocity_mps.row(i) = initial.velocity_mps.row(0);
    probe.attitude_wxyz.row(i) = initial.attitude_wxyz.row(0);
    probe.acc_bias_mps2.row(i) = initial.acc_bias_mps2.row(0);
    probe.gyro_bias_radps.row(i) = initial.gyro_bias_radps.row(0);
    probe.gravity_disturbance_mps2[i] = initial.gravity_disturbance_mps2[0];
  }
  CheckNetworkInput(obs, probe);
}

/// The initial error covariance: the options' sds squared on the diagonal.
Mat16 InitialCovariance(const KalmanSmootherOptions& options) {
  Mat16 p = Mat16::Zero();
  p.block<3, 3>(kP, kP).diagonal().setConstant(options.init_sigma_position_m * options.init_sigma_position_m);
  p.block<3, 3>(kV, kV).diagonal().setConstant(options.init_sigma_velocity_mps * options.init_sigma_velocity_mps);
  p(kE, kE) = p(kE + 1, kE + 1) = options.init_sigma_level_rad * options.init_sigma_level_rad;
  p(kE + 2, kE + 2) = options.init_sigma_heading_rad * options.init_sigma_heading_rad;
  p.block<3, 3>(kA, kA).diagonal().setConstant(options.init_sigma_acc_bias_mps2 * options.init_sigma_acc_bias_mps2);
  p.block<3, 3>(kO, kO).diagonal().setConstant(options.init_sigma_gyro_bias_radps * options.init_sigma_gyro_bias_radps);
  p(kG, kG) = options.init_sigma_gravity_mps2 * options.init_sigma_gravity_mps2;
  return p;
}

/// The discrete process noise of one step (diagonal `qd`) and the bias decay factors.
struct ProcessNoise {
  Vec16 qd = Vec16::Zero();
  double phi_a = 1.0, phi_o = 1.0;  ///< b[k+1] = φ b[k] of the accelerometer and gyro biases
};

ProcessNoise MakeProcessNoise(const NetworkOptions& model, double dt) {
  ProcessNoise noise;
  Vec16& qd = noise.qd;
  qd.segment<3>(kV).setConstant(model.acc_noise_mps2_rthz * model.acc_noise_mps2_rthz * dt);
  qd.segment<3>(kE).setConstant(model.gyro_noise_radps_rthz * model.gyro_noise_radps_rthz * dt);
  // Bias models: random walk (τ = 0) or Gauss-Markov with φ = exp(-δt/τ), var = q² τ/2 (1 - φ²).
  auto bias_model = [dt](double q, double tau, double* phi, double* var) {
    if (tau <= 0.0) {
      *phi = 1.0;
      *var = q * q * dt;
    } else {
      *phi = std::exp(-dt / tau);
      *var = q * q * 0.5 * tau * (1.0 - *phi * *phi);
    }
  };
  double var_a = 0.0, var_o = 0.0;
  bias_model(model.acc_bias_walk_mps2_rts, model.acc_bias_correlation_time_s, &noise.phi_a, &var_a);
  bias_model(model.gyro_bias_walk_radps_rts, model.gyro_bias_correlation_time_s, &noise.phi_o, &var_o);
  qd.segment<3>(kA).setConstant(var_a);
  qd.segment<3>(kO).setConstant(var_o);
  qd[kG] = model.gravity_walk_mps2_rts * model.gravity_walk_mps2_rts * dt;
  return noise;
}

/// The RTS pass on the error states: from the last epoch back, δ_k = G_k (δ_{k+1} + u_{k+1})
/// (gains G_k, filter corrections u_k), injected into the filtered nominal states of `out`.
void SmoothBackward(const std::vector<Mat16>& gains, const std::vector<Vec16>& corrections, NetworkState& out) {
  const int n = static_cast<int>(out.position_m.rows());
  Vec16 delta = Vec16::Zero();
  for (int k = n - 2; k >= 0; --k) {
    delta = gains[static_cast<size_t>(k)] * (delta + corrections[static_cast<size_t>(k + 1)]);
    Nominal xs = Load(out, k);
    Inject(xs, delta);
    Store(xs, k, out);
  }
}

}  // namespace

bool KalmanSmootherOptions::IsValid(std::string* error) const {
  const std::pair<const char*, double> sds[] = {
      {"init_sigma_position_m", init_sigma_position_m},       {"init_sigma_velocity_mps", init_sigma_velocity_mps},
      {"init_sigma_level_rad", init_sigma_level_rad},         {"init_sigma_heading_rad", init_sigma_heading_rad},
      {"init_sigma_acc_bias_mps2", init_sigma_acc_bias_mps2}, {"init_sigma_gyro_bias_radps", init_sigma_gyro_bias_radps},
      {"init_sigma_gravity_mps2", init_sigma_gravity_mps2}};
  Validator v(error);
  for (const auto& [name, value] : sds) v.Scale(value, name);  // squared into the covariance
  // Attitude sds beyond 10 rad mean "unknown" and overflowed the error-state filter (NaN).
  return v.InRange(init_sigma_level_rad, kMinScale, 10.0, "init_sigma_level_rad")
      .InRange(init_sigma_heading_rad, kMinScale, 10.0, "init_sigma_heading_rad")
      .ok();
}

std::string KalmanSmootherSummary::BriefReport() const {
  std::ostringstream s;
  s << "kalman smoother: " << num_epochs << " epochs, " << num_updates << " updates, " << num_xover_ignored
    << " cross-overs ignored, filter " << seconds_filter << " s, smoother " << seconds_smoother << " s";
  return s.str();
}

NetworkState RunKalmanSmoother(const NetworkObservations& obs, const NetworkState& initial, const NetworkOptions& model,
                               const KalmanSmootherOptions& options, KalmanSmootherSummary* summary,
                               NetworkState* filtered) {
  ValidateOptions(model, "model");
  ValidateOptions(options);
  CheckInput(obs, initial);
  const int n = static_cast<int>(obs.imu_time_s.size());
  WallTimer timer;
  const double dt = (obs.imu_time_s[n - 1] - obs.imu_time_s[0]) / (n - 1);
  const Eigen::Vector3d wie = EarthRateEnu(model.latitude_rad) * (model.earth_rate_radps / kEarthRateRadps);
  const Eigen::Vector3d gc = NormalGravityCoefficients(model.latitude_rad);
  auto gamma = [&](double up) {
    const double h = up + model.origin_height_m;
    return gc[0] * (1.0 - gc[1] * h + gc[2] * h * h);
  };
  auto dgamma = [&](double up) {
    const double h = up + model.origin_height_m;
    return gc[0] * (-gc[1] + 2.0 * gc[2] * h);
  };
  auto gravity = [&](double up, double dg) { return Eigen::Vector3d(0.0, 0.0, -(gamma(up) + dg)); };

  // Events per epoch.
  std::vector<std::vector<int>> gps_at(static_cast<size_t>(n)), gupt_at(static_cast<size_t>(n));
  std::vector<char> zupt_at(static_cast<size_t>(n), 0);
  for (Eigen::Index i = 0; i < obs.gps_time_s.size(); ++i) {
    int k = static_cast<int>(std::floor((obs.gps_time_s[i] - obs.imu_time_s[0]) / dt + 1e-9));
    k = std::clamp(k, 0, n - 1);
    gps_at[static_cast<size_t>(k)].push_back(static_cast<int>(i));
  }
  for (Eigen::Index i = 0; i < obs.zupt_epochs.size(); ++i) zupt_at[static_cast<size_t>(obs.zupt_epochs[i])] = 1;
  for (Eigen::Index i = 0; i < obs.gupt_epochs.size(); ++i)
    gupt_at[static_cast<size_t>(obs.gupt_epochs[i])].push_back(static_cast<int>(i));

  Nominal x = Load(initial, 0);
  x.q.normalize();
  Mat16 p = InitialCovariance(options);
  const ProcessNoise noise = MakeProcessNoise(model, dt);
  const Vec16& qd = noise.qd;
  const double phi_a = noise.phi_a, phi_o = noise.phi_o;

  NetworkState out = Allocate(n);
  std::vector<Mat16> gains(options.smooth ? static_cast<size_t>(n) : 0);
  std::vector<Vec16> corrections(options.smooth ? static_cast<size_t>(n) : 0, Vec16::Zero());
  int num_updates = 0;

  auto apply_updates = [&](int k) {
    Vec16 total = Vec16::Zero();
    for (int gi : gps_at[static_cast<size_t>(k)]) {
      const double tau = obs.gps_time_s[gi] - obs.imu_time_s[k];
      Eigen::Matrix<double, 3, 16> h = Eigen::Matrix<double, 3, 16>::Zero();
      h.block<3, 3>(0, kP).setIdentity();
      h.block<3, 3>(0, kV) = tau * Eigen::Matrix3d::Identity();
      const Eigen::Vector3d z = obs.gps_position_m.row(gi).transpose() - (x.r + tau * x.v);
      const Eigen::Matrix3d r = model.sigma_gps_m * model.sigma_gps_m * Eigen::Matrix3d::Identity();
      const Vec16 d = Update<3>(p, z, h, r);
      Inject(x, d);
      total += d;
      ++num_updates;
    }
    if (zupt_at[static_cast<size_t>(k)]) {
      Eigen::Matrix<double, 3, 16> h = Eigen::Matrix<double, 3, 16>::Zero();
      h.block<3, 3>(0, kV).setIdentity();
      const Eigen::Vector3d z = -x.v;
      const Eigen::Matrix3d r = model.sigma_zupt_mps * model.sigma_zupt_mps * Eigen::Matrix3d::Identity();
      const Vec16 d = Update<3>(p, z, h, r);
      Inject(x, d);
      total += d;
      ++num_updates;
    }
    for (int gi : gupt_at[static_cast<size_t>(k)]) {
      Eigen::Matrix<double, 1, 16> h = Eigen::Matrix<double, 1, 16>::Zero();
      h(0, kP + 2) = dgamma(x.r.z());
      h(0, kG) = 1.0;
      Eigen::Matrix<double, 1, 1> z, r;
      z(0) = obs.gupt_gravity_mps2[gi] - (gamma(x.r.z()) + x.dg);
      r(0) = model.sigma_gupt_mps2 * model.sigma_gupt_mps2;
      const Vec16 d = Update<1>(p, z, h, r);
      Inject(x, d);
      total += d;
      ++num_updates;
    }
    return total;
  };

  Vec16 u0 = apply_updates(0);
  if (options.smooth) corrections[0] = u0;
  Store(x, 0, out);
  if (filtered) *filtered = Allocate(n);
  if (filtered) Store(x, 0, *filtered);
  for (int k = 0; k + 1 < n; ++k) {
    const Eigen::Vector3d f0 = obs.acc_body_mps2.row(k).transpose(), f1 = obs.acc_body_mps2.row(k + 1).transpose();
    const Eigen::Vector3d w0 = obs.gyro_body_radps.row(k).transpose(), w1 = obs.gyro_body_radps.row(k + 1).transpose();
    // Error-state transition at the nominal state of epoch k.
    const Eigen::Matrix3d rot = x.q.toRotationMatrix();
    const Eigen::Vector3d fn = rot * (f0 - x.a);
    Mat16 fc = Mat16::Zero();
    fc.block<3, 3>(kP, kV).setIdentity();
    fc.block<3, 3>(kV, kV) = -2.0 * Skew(wie);
    fc.block<3, 3>(kV, kE) = -Skew(fn);
    fc.block<3, 3>(kV, kA) = -rot;
    fc(kV + 2, kP + 2) = -dgamma(x.r.z());
    fc(kV + 2, kG) = -1.0;
    fc.block<3, 3>(kE, kE) = -Skew(wie);
    fc.block<3, 3>(kE, kO) = -rot;
    const Mat16 fdt = fc * dt;
    Mat16 phi = Mat16::Identity() + fdt + 0.5 * fdt * fdt;
    // Gauss-Markov biases decay exactly: b[k+1] = φ b[k] (the bias rows have no other terms).
    phi.block<3, 3>(kA, kA) = phi_a * Eigen::Matrix3d::Identity();
    phi.block<3, 3>(kO, kO) = phi_o * Eigen::Matrix3d::Identity();
    // Nominal mechanisation (trapezoidal).
    const Eigen::Vector3d a0 = fn - 2.0 * wie.cross(x.v) + gravity(x.r.z(), x.dg);
    const Eigen::Quaterniond q1 =
        (ExpQ(-wie * dt) * x.q * ExpQ((0.5 * (w0 + w1) - x.o) * dt)).normalized();
    const Eigen::Vector3d v_pred = x.v + a0 * dt;
    const Eigen::Vector3d a1 =
        q1 * (f1 - x.a) - 2.0 * wie.cross(v_pred) + gravity(x.r.z() + x.v.z() * dt, x.dg);
    const Eigen::Vector3d v1 = x.v + 0.5 * dt * (a0 + a1);
    x.r += 0.5 * dt * (x.v + v1);
    x.v = v1;
    x.q = q1;
    x.a *= phi_a;
    x.o *= phi_o;
    const Mat16 p_prior = phi * p * phi.transpose() + Mat16(qd.asDiagonal());
    if (options.smooth) gains[static_cast<size_t>(k)] = p_prior.ldlt().solve(phi * p).transpose();
    p = 0.5 * (p_prior + p_prior.transpose());
    const Vec16 u = apply_updates(k + 1);
    if (options.smooth) corrections[static_cast<size_t>(k + 1)] = u;
    Store(x, k + 1, out);
    if (filtered) Store(x, k + 1, *filtered);
  }
  const double seconds_filter = timer.ElapsedSeconds();
  WallTimer smoother_timer;
  if (options.smooth) SmoothBackward(gains, corrections, out);
  if (summary) {
    summary->num_epochs = n;
    summary->num_updates = num_updates;
    summary->num_xover_ignored = static_cast<int>(obs.xover_epochs.rows());
    summary->seconds_filter = seconds_filter;
    summary->seconds_smoother = smoother_timer.ElapsedSeconds();
  }
  return out;
}

}  // namespace indoorloc::network
