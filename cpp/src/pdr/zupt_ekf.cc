#include "indoorloc/pdr/zupt_ekf.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "imu_timing.h"
#include "median.h"

namespace indoorloc::pdr {
namespace {

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

// Rotation vector -> quaternion.
Eigen::Quaterniond Exp(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  if (angle < 1e-12) return Eigen::Quaterniond(1.0, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, phi / angle));
}

// The rotation (body -> nav) that maps the measured mean specific force onto +z (level), yaw 0.
Eigen::Quaterniond LevelAttitude(const Eigen::Vector3d& mean_f) {
  const Eigen::Vector3d u = mean_f.normalized();
  const Eigen::Vector3d z(0, 0, 1);
  Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(u, z);
  // Remove the yaw this rotation happens to introduce, so that the initial heading is 0.
  const Eigen::Matrix3d r = q.toRotationMatrix();
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  return (Eigen::Quaterniond(Eigen::AngleAxisd(-yaw, z)) * q).normalized();
}

}  // namespace

bool ZuptEkfOptions::IsValid(std::string* error) const {
  // Sds enter the covariances squared: a scale keeps them finite (1e-300 or inf would not).
  return Validator(error)
      .Scale(sigma_acc_mps2, "sigma_acc_mps2")
      .Scale(sigma_gyro_radps, "sigma_gyro_radps")
      .Scale(sigma_zupt_mps, "sigma_zupt_mps")
      .InRange(gravity_mps2, 0.1, 100.0, "gravity_mps2")
      .IntInRange(init_samples, 1, 1000000000, "init_samples")
      .ZeroOrScale(sigma_stance_heading_rad, "sigma_stance_heading_rad")
      // Health-check limits (divergence is reported, never silent: see zupt_ekf.h).
      .Check(min_stance_fraction >= 0.0 && min_stance_fraction < 1.0, "min_stance_fraction", "must be in [0, 1)")
      .Scale(max_plausible_stride_m, "max_plausible_stride_m")
      .Scale(max_stance_speed_mps, "max_stance_speed_mps")
      .Check(speed_rise_factor > 1.0 && std::isfinite(speed_rise_factor), "speed_rise_factor", "must be finite and > 1")
      .Scale(max_plausible_swing_s, "max_plausible_swing_s")
      .Scale(max_median_stride_m, "max_median_stride_m")
      .NonNegative(min_rising_speed_mps, "min_rising_speed_mps");
}

std::string ZuptEkfSummary::BriefReport() const {
  std::ostringstream s;
  s.precision(3);
  s << "ZUPT EKF: " << n_samples << " samples, stance " << 100.0 * stance_fraction << " % (walking span "
    << 100.0 * walking_stance_fraction << " %), " << n_stance_phases << " stance phases, swing median " << swing_median_s
    << " s / max " << swing_max_s << " s, speed at stance median " << speed_at_stance_median_mps << " / max "
    << speed_at_stance_max_mps << " m/s (rise x" << speed_at_stance_rise << "), stride median " << median_stride_m << " m / longest " << longest_stride_m << " m: "
    << (implausible ? "IMPLAUSIBLE" : "plausible");
  for (const std::string& r : reasons) s << "; " << r;
  return s.str();
}

ZuptEkfSummary CheckZuptHealth(const Eigen::Ref<const Eigen::VectorXd>& time_s, const Eigen::Ref<const RowMatrixXd>& positions_m,
                               const BoolVector& stance, const std::vector<double>& speed_at_onset_mps,
                               const ZuptEkfOptions& options) {
  ValidateOptions(options);
  const Eigen::Index n = stance.size();
  CheckArgument(time_s.size() == n, "time_s", "must have one entry per stance flag");
  CheckShape(positions_m, n, 3, "positions_m");
  ZuptEkfSummary h;
  h.n_samples = static_cast<int>(n);
  // Runs of stance: [start, end) pairs.
  std::vector<std::pair<Eigen::Index, Eigen::Index>> runs;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (!stance[k]) continue;
    Eigen::Index e = k;
    while (e < n && stance[e]) ++e;
    runs.emplace_back(k, e);
    h.n_stance_samples += static_cast<int>(e - k);
    k = e;
  }
  h.n_stance_phases = static_cast<int>(runs.size());
  CheckArgument(speed_at_onset_mps.size() == runs.size(), "speed_at_onset_mps", "must have one entry per stance run");
  h.stance_fraction = n > 0 ? static_cast<double>(h.n_stance_samples) / static_cast<double>(n) : 0.0;
  // Walking span: first to last swing sample.
  Eigen::Index first_swing = -1, last_swing = -1;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (!stance[k]) {
      if (first_swing < 0) first_swing = k;
      last_swing = k;
    }
  }
  if (first_swing < 0) {
    h.walking_stance_fraction = 1.0;
  } else {
    int in_span = 0;
    for (Eigen::Index k = first_swing; k <= last_swing; ++k) in_span += stance[k] ? 1 : 0;
    h.walking_stance_fraction = static_cast<double>(in_span) / static_cast<double>(last_swing - first_swing + 1);
  }
  // Swings between consecutive stance runs.
  std::vector<double> swings;
  for (size_t i = 1; i < runs.size(); ++i) swings.push_back(time_s[runs[i].first] - time_s[runs[i - 1].second - 1]);
  // The motion before the first and after the last stance counts too (all stances lost).
  if (runs.empty() && n > 1) swings.push_back(time_s[n - 1] - time_s[0]);
  if (!runs.empty() && runs.front().first > 0) swings.push_back(time_s[runs.front().first] - time_s[0]);
  if (!runs.empty() && runs.back().second < n) swings.push_back(time_s[n - 1] - time_s[runs.back().second - 1]);
  h.swing_median_s = internal::Median(swings);
  h.swing_max_s = swings.empty() ? 0.0 : *std::max_element(swings.begin(), swings.end());
  // Speeds at stance onsets (the initial rest has no swing before it: skipped when it starts at 0).
  std::vector<double> speeds;
  for (size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].first == 0) continue;
    if (std::isfinite(speed_at_onset_mps[i])) speeds.push_back(speed_at_onset_mps[i]);
  }
  h.speed_at_stance_median_mps = internal::Median(speeds);
  h.speed_at_stance_max_mps = speeds.empty() ? 0.0 : *std::max_element(speeds.begin(), speeds.end());
  if (speeds.size() >= 6) {
    const size_t third = speeds.size() / 3;
    const double first = internal::Median(std::vector<double>(speeds.begin(), speeds.begin() + static_cast<std::ptrdiff_t>(third)));
    const double last = internal::Median(std::vector<double>(speeds.end() - static_cast<std::ptrdiff_t>(third), speeds.end()));
    h.speed_at_stance_rise = first > 0 ? last / first : 1.0;
    if (h.speed_at_stance_rise > options.speed_rise_factor && last > options.min_rising_speed_mps) {
      h.reasons.push_back("the speed at stance rises over the recording (x" + std::to_string(h.speed_at_stance_rise) +
                          "): the velocity error grows, the filter diverges");
    }
  }
  std::vector<double> strides;
  for (size_t i = 1; i < runs.size(); ++i) {
    const Eigen::Index a = runs[i - 1].first, b = runs[i].first;
    const double d = (positions_m.row(b).head<2>() - positions_m.row(a).head<2>()).norm();
    h.longest_stride_m = std::max(h.longest_stride_m, d);
    strides.push_back(d);
  }
  h.median_stride_m = internal::Median(strides);
  if (first_swing >= 0 && h.walking_stance_fraction < options.min_stance_fraction) {
    h.reasons.push_back("only " + std::to_string(100.0 * h.walking_stance_fraction) +
                        " % of the walking span is stance: zero-velocity updates are missing");
  }
  // A measured value above its limit: "<what><value> <unit><where> (limit <limit> <unit>)<consequence>".
  const auto above = [&h](double value, double limit, const char* what, const char* unit, const char* where,
                          const char* consequence) {
    if (value > limit) {
      h.reasons.push_back(what + std::to_string(value) + " " + unit + where + " (limit " + std::to_string(limit) +
                          " " + unit + ")" + consequence);
    }
  };
  above(h.swing_max_s, options.max_plausible_swing_s, "a swing of ", "s", " between stances", ": stances are missing");
  above(h.longest_stride_m, options.max_plausible_stride_m, "a stride of ", "m", "", "");
  above(h.median_stride_m, options.max_median_stride_m, "the median stride is ", "m", "", ": the path is stretched");
  above(h.speed_at_stance_max_mps, options.max_stance_speed_mps, "a speed of ", "m/s", " at a stance onset", "");
  h.implausible = !h.reasons.empty();
  return h;
}

ZuptEkfOutput RunZuptEkf(const Eigen::Ref<const Eigen::VectorXd>& time_s, const Eigen::Ref<const RowMatrixXd>& acc,
                         const Eigen::Ref<const RowMatrixXd>& gyro, const BoolVector& stance, const ZuptEkfOptions& options) {
  ValidateOptions(options);
  const auto start = std::chrono::steady_clock::now();
  const Eigen::Index n = acc.rows();
  CheckShape(acc, -1, 3, "acc_mps2");
  CheckShape(gyro, n, 3, "gyro_radps");
  CheckArgument(time_s.size() == n, "time_s", "must have one entry per sample");
  CheckArgument(stance.size() == n, "stance", "must have one entry per sample");
  internal::CheckImuSamples(time_s, acc, gyro);
  // Median positive sample period, used where timestamps repeat or go backwards.
  const double median_dt = internal::MedianSamplePeriod(time_s);

  const Eigen::Vector3d mean_f = internal::InitialSpecificForce(acc, options.init_samples, options.gravity_mps2);
  Eigen::Quaterniond q = LevelAttitude(mean_f);
  Eigen::Vector3d p = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
  const Eigen::Vector3d g(0, 0, -options.gravity_mps2);
  using Mat9 = Eigen::Matrix<double, 9, 9>;
  Mat9 P = Mat9::Zero();
  P.block<3, 3>(6, 6) = (1e-4) * Eigen::Matrix3d::Identity();  // small initial attitude uncertainty
  const double qa = options.sigma_acc_mps2 * options.sigma_acc_mps2;
  const double qg = options.sigma_gyro_radps * options.sigma_gyro_radps;
  const double rz = options.sigma_zupt_mps * options.sigma_zupt_mps;
  const double rh = options.sigma_stance_heading_rad * options.sigma_stance_heading_rad;
  double stance_yaw = 0.0;

  ZuptEkfOutput out;
  out.positions_m.resize(n, 3);
  // Smoother storage: gain C_k (row k) and update u_k per sample; the nominal attitudes too.
  std::vector<Eigen::Matrix<double, 9, 9>, Eigen::aligned_allocator<Eigen::Matrix<double, 9, 9>>> gains;
  std::vector<Eigen::Matrix<double, 9, 1>, Eigen::aligned_allocator<Eigen::Matrix<double, 9, 1>>> updates;
  std::vector<Eigen::Quaterniond, Eigen::aligned_allocator<Eigen::Quaterniond>> attitudes;
  if (options.smooth) {
    gains.resize(static_cast<size_t>(n));
    updates.assign(static_cast<size_t>(n), Eigen::Matrix<double, 9, 1>::Zero());
    attitudes.resize(static_cast<size_t>(n));
  }
  Mat9 P_post_prev = P;
  out.velocities_mps.resize(n, 3);
  out.headings_rad.resize(n);
  out.quaternions_wxyz.resize(n, 4);
  out.position_sd_m.resize(n, 3);
  std::vector<double> speed_at_onset;  // |v̂⁻| at the first sample of each stance run
  for (Eigen::Index k = 0; k < n; ++k) {
    if (k > 0) {
      const double dt = time_s[k] > time_s[k - 1] ? time_s[k] - time_s[k - 1] : median_dt;
      const Eigen::Vector3d w = gyro.row(k).transpose();
      q = (q * Exp(w * dt)).normalized();
      const Eigen::Matrix3d r = q.toRotationMatrix();
      const Eigen::Vector3d f_n = r * acc.row(k).transpose();
      v += (f_n + g) * dt;
      p += v * dt;
      Mat9 F = Mat9::Identity();
      F.block<3, 3>(0, 3) = Eigen::Matrix3d::Identity() * dt;
      const Eigen::Matrix3d B = -Skew(f_n) * dt;
      F.block<3, 3>(3, 6) = B;
      // P <- F P Fᵀ using F's block structure (I + two off-diagonal blocks): M = F P by rows,
      // then M Fᵀ by columns; about 4x fewer flops than two dense 9 x 9 products.
      Mat9 M = P;
      M.middleRows<3>(0) += dt * P.middleRows<3>(3);
      M.middleRows<3>(3).noalias() += B * P.middleRows<3>(6);
      P = M;
      P.middleCols<3>(0) += dt * M.middleCols<3>(3);
      P.middleCols<3>(3).noalias() += M.middleCols<3>(6) * B.transpose();
      P.block<3, 3>(3, 3) += qa * dt * dt * Eigen::Matrix3d::Identity();
      P.block<3, 3>(6, 6) += qg * dt * dt * Eigen::Matrix3d::Identity();
      if (options.smooth) {
        // C_{k-1} = P⁺_{k-1} Fᵀ (P⁻_k)^{-1}. The position block of P⁻ is 0 until the first
        // velocity uncertainty has propagated into it: a tiny jitter keeps the solve regular
        // (those directions carry no correlation, so their gain is 0 either way).
        const Mat9 prior = P + 1e-12 * Mat9::Identity();
        gains[static_cast<size_t>(k - 1)] = (prior.ldlt().solve(F * P_post_prev)).transpose();
      }
    }
    if (stance[k] && (k == 0 || !stance[k - 1])) speed_at_onset.push_back(v.norm());
    if (stance[k]) {
      // Zero-velocity update: z = 0 - v̂, H = [0 I 0].
      const Eigen::Matrix3d S = P.block<3, 3>(3, 3) + rz * Eigen::Matrix3d::Identity();
      const Eigen::Matrix<double, 9, 3> K = P.block<9, 3>(0, 3) * S.inverse();
      const Eigen::Matrix<double, 9, 1> dx = K * (-v);
      p += dx.segment<3>(0);
      v += dx.segment<3>(3);
      q = (Exp(dx.segment<3>(6)) * q).normalized();  // R <- (I + [ε]×) R
      Mat9 IKH = Mat9::Identity();
      IKH.block<9, 3>(0, 3) -= K;
      P = IKH * P * IKH.transpose() + rz * K * K.transpose();
      if (options.smooth) updates[static_cast<size_t>(k)] = dx;
      // Stance heading update (heuristic drift elimination): the foot does not turn while it
      // rests, so the yaw keeps its value from the stance onset. z = ψ_onset − ψ̂ with H = e_9ᵀ
      // (the navigation-frame z attitude error is the yaw error for a level foot).
      if (options.sigma_stance_heading_rad > 0.0) {
        const Eigen::Matrix3d r_now = q.toRotationMatrix();
        const double yaw = std::atan2(r_now(1, 0), r_now(0, 0));
        if (k == 0 || !stance[k - 1]) {
          stance_yaw = yaw;
        } else {
          const double innovation = std::remainder(stance_yaw - yaw, 2.0 * 3.14159265358979323846);
          const double s_yaw = P(8, 8) + rh;
          const Eigen::Matrix<double, 9, 1> K_yaw = P.col(8) / s_yaw;
          const Eigen::Matrix<double, 9, 1> dy = K_yaw * innovation;
          p += dy.segment<3>(0);
          v += dy.segment<3>(3);
          q = (Exp(dy.segment<3>(6)) * q).normalized();
          Mat9 IKH_yaw = Mat9::Identity();
          IKH_yaw.col(8) -= K_yaw;
          P = IKH_yaw * P * IKH_yaw.transpose() + rh * K_yaw * K_yaw.transpose();
          if (options.smooth) updates[static_cast<size_t>(k)] += dy;
        }
      }
    }
    P_post_prev = P;
    if (options.smooth) attitudes[static_cast<size_t>(k)] = q;
    out.positions_m.row(k) = p.transpose();
    out.velocities_mps.row(k) = v.transpose();
    const Eigen::Matrix3d r = q.toRotationMatrix();
    out.headings_rad[k] = std::atan2(r(1, 0), r(0, 0));
    out.quaternions_wxyz.row(k) << q.w(), q.x(), q.y(), q.z();
    out.position_sd_m.row(k) = P.diagonal().head<3>().cwiseMax(0.0).cwiseSqrt().transpose();
  }
  out.filtered_positions_m = out.positions_m;
  if (options.smooth) {
    // Backward pass: δ_k = C_k (δ_{k+1} + u_{k+1}), δ_{N-1} = 0.
    Eigen::Matrix<double, 9, 1> delta = Eigen::Matrix<double, 9, 1>::Zero();
    for (Eigen::Index k = n - 2; k >= 0; --k) {
      delta = gains[static_cast<size_t>(k)] * (delta + updates[static_cast<size_t>(k + 1)]);
      out.positions_m.row(k) += delta.segment<3>(0).transpose();
      out.velocities_mps.row(k) += delta.segment<3>(3).transpose();
      const Eigen::Quaterniond qs = (Exp(delta.segment<3>(6)) * attitudes[static_cast<size_t>(k)]).normalized();
      const Eigen::Matrix3d r = qs.toRotationMatrix();
      out.headings_rad[k] = std::atan2(r(1, 0), r(0, 0));
      out.quaternions_wxyz.row(k) << qs.w(), qs.x(), qs.y(), qs.z();
    }
  }
  out.summary = CheckZuptHealth(time_s, out.positions_m, stance, speed_at_onset, options);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.summary.seconds = out.seconds;
  return out;
}

}  // namespace indoorloc::pdr
