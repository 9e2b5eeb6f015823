#include "indoorloc/pdr/step_positioning.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "imu_timing.h"

namespace indoorloc::pdr {
namespace {

void CheckQuaternions(const Eigen::Ref<const RowMatrixXd>& q, Eigen::Index n) {
  CheckShape(q, n, 4, "quaternions_wxyz");
  CheckFinite(q, "quaternions_wxyz");
  for (Eigen::Index k = 0; k < q.rows(); ++k) {
    const double norm = q.row(k).norm();
    CheckArgument(std::abs(norm - 1.0) < 1e-3, "quaternions_wxyz",
                  "row " + std::to_string(k) + " is not a unit quaternion (norm " + std::to_string(norm) + ")");
  }
}

void CheckSteps(const std::vector<int>& steps, Eigen::Index n) {
  for (size_t k = 0; k < steps.size(); ++k) {
    CheckArgument(steps[k] >= 0 && steps[k] < n, "step_indices",
                  "entry " + std::to_string(k) + " = " + std::to_string(steps[k]) + " is outside [0, N) for N = " +
                      std::to_string(n) + " samples (rows of the sample arrays)");
    CheckArgument(k == 0 || steps[k] > steps[k - 1], "step_indices", "must be strictly increasing");
  }
}

Eigen::Matrix3d Rotation(const Eigen::Ref<const RowMatrixXd>& q, Eigen::Index k) {
  return Eigen::Quaterniond(q(k, 0), q(k, 1), q(k, 2), q(k, 3)).normalized().toRotationMatrix();
}

}  // namespace

bool StepCovarianceOptions::IsValid(std::string* error) const {
  // The sds are squared into the covariances: bounded so they stay finite.
  return Validator(error)
      .InRange(sigma_stride_length_m, 0.0, 1e6, "sigma_stride_length_m")
      .InRange(stride_length_sd_fraction, 0.0, 1e6, "stride_length_sd_fraction")
      .InRange(sigma_heading_step_rad, 0.0, 1e6, "sigma_heading_step_rad")
      .InRange(sigma_heading_initial_rad, 0.0, 1e6, "sigma_heading_initial_rad");
}

bool InsZuptOptions::IsValid(std::string* error) const {
  return Validator(error).InRange(window_s, 0.0, 1e6, "window_s").InRange(gravity_mps2, 0.1, 100.0, "gravity_mps2");
}

StepTrack PositionsFromStrides(const Eigen::Ref<const Eigen::VectorXd>& sl, const Eigen::Ref<const Eigen::VectorXd>& heading,
                               const Eigen::Vector2d& start_xy, const StepCovarianceOptions& options) {
  ValidateOptions(options);
  CheckArgument(heading.size() == sl.size(), "headings_rad", "must have one entry per stride length");
  CheckFinite(sl, "stride_lengths_m");
  RequireAllInRange(sl, 0.0, 1e4, "stride_lengths_m");  // squared in the covariance: 1e300 gave inf
  CheckFinite(heading, "headings_rad");
  CheckFinite(start_xy, "start_xy");
  RequireAllInRange(start_xy, -1e9, 1e9, "start_xy");
  CheckArgument((sl.array() >= 0.0).all(), "stride_lengths_m", "must be >= 0");
  const Eigen::Index m = sl.size();
  StepTrack out;
  out.positions_m.resize(m, 2);
  out.covariances.resize(m, 9);
  out.stride_lengths_m = sl;
  out.headings_rad = heading;
  Eigen::Vector2d p = start_xy;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  cov(2, 2) = options.sigma_heading_initial_rad * options.sigma_heading_initial_rad;
  const double qpsi = options.sigma_heading_step_rad * options.sigma_heading_step_rad;
  for (Eigen::Index k = 0; k < m; ++k) {
    const double c = std::cos(heading[k]), s = std::sin(heading[k]), l = sl[k];
    p += l * Eigen::Vector2d(c, s);  // eq. 8
    cov(2, 2) += qpsi;               // heading random walk
    Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
    F(0, 2) = -l * s;
    F(1, 2) = l * c;
    const Eigen::Vector3d G(c, s, 0.0);
    const double sd = options.sigma_stride_length_m + options.stride_length_sd_fraction * l;
    cov = F * cov * F.transpose() + sd * sd * G * G.transpose();
    cov = 0.5 * (cov + cov.transpose());
    out.positions_m.row(k) = p.transpose();
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) out.covariances(k, 3 * i + j) = cov(i, j);
    }
  }
  return out;
}

StepTrack PositionsFromIncrements(const Eigen::Ref<const RowMatrixXd>& inc, const Eigen::Vector2d& start_xy,
                                  const StepCovarianceOptions& options) {
  CheckArgument(inc.cols() == 2 || inc.cols() == 3, "increments_m", "must have 2 or 3 columns");
  CheckFinite(inc, "increments_m");
  RequireAllInRange(inc, -1e4, 1e4, "increments_m");
  Eigen::VectorXd sl(inc.rows()), heading(inc.rows());
  for (Eigen::Index k = 0; k < inc.rows(); ++k) {
    sl[k] = std::hypot(inc(k, 0), inc(k, 1));           // eq. 6
    heading[k] = std::atan2(inc(k, 1), inc(k, 0));      // then eq. 9 = eq. 8 with this heading
  }
  StepTrack out = PositionsFromStrides(sl, heading, start_xy, options);
  // Sum the increments directly so that positions are exactly eq. 9 (no cos/sin round trip).
  Eigen::Vector2d p = start_xy;
  for (Eigen::Index k = 0; k < inc.rows(); ++k) {
    p += inc.row(k).head<2>().transpose();
    out.positions_m.row(k) = p.transpose();
  }
  return out;
}

Eigen::VectorXd StanceHeadings(const Eigen::Ref<const RowMatrixXd>& q, const std::vector<int>& steps) {
  CheckQuaternions(q, -1);
  CheckSteps(steps, q.rows());
  Eigen::VectorXd out(static_cast<Eigen::Index>(steps.size()));
  for (size_t k = 0; k < steps.size(); ++k) {
    const Eigen::Matrix3d r = Rotation(q, steps[k]);
    out[static_cast<Eigen::Index>(k)] = std::atan2(r(1, 0), r(0, 0));  // eq. 7: X^G = R e_x
  }
  return out;
}

InsZuptIncrements ComputeInsZuptIncrements(const Eigen::Ref<const Eigen::VectorXd>& time_s, const Eigen::Ref<const RowMatrixXd>& acc,
                                           const Eigen::Ref<const RowMatrixXd>& q, const std::vector<int>& steps,
                                           const InsZuptOptions& options) {
  ValidateOptions(options);
  CheckShape(acc, -1, 3, "acc_mps2");
  const Eigen::Index n = acc.rows();
  CheckArgument(time_s.size() == n, "time_s", "must have one entry per sample");
  CheckFinite(time_s, "time_s");
  CheckFinite(acc, "acc_mps2");
  internal::CheckTimeRange(time_s);
  internal::CheckAccRange(acc);
  CheckQuaternions(q, n);
  CheckArgument(steps.size() >= 2, "step_indices", "needs at least 2 steps");
  CheckSteps(steps, n);
  const double median_dt = internal::MedianSamplePeriod(time_s);
  auto dt_at = [&](Eigen::Index k) { return time_s[k] > time_s[k - 1] ? time_s[k] - time_s[k - 1] : median_dt; };
  const int w = internal::SampleCount(options.window_s / median_dt);
  const Eigen::Vector3d g(0.0, 0.0, options.gravity_mps2);
  // Steps 1-2: a^G = R f − g, integrated from the first step sample (v = 0 there).
  RowMatrixXd v = RowMatrixXd::Zero(n, 3);
  const Eigen::Index first = steps.front(), last = steps.back();
  for (Eigen::Index k = first + 1; k <= std::min<Eigen::Index>(n - 1, last + w); ++k) {
    const Eigen::Vector3d a = Rotation(q, k) * acc.row(k).transpose() - g;
    v.row(k) = v.row(k - 1) + a.transpose() * dt_at(k);
  }
  // Step 3a: μ_k = mean velocity over [i(k) − w, i(k) + w] (clamped to the integrated span).
  const size_t m = steps.size();
  std::vector<Eigen::Vector3d> mu(m);
  for (size_t k = 0; k < m; ++k) {
    const Eigen::Index lo = std::max<Eigen::Index>(first, steps[k] - w), hi = std::min<Eigen::Index>(std::min<Eigen::Index>(n - 1, last + w), steps[k] + w);
    mu[k] = v.middleRows(lo, hi - lo + 1).colwise().mean().transpose();
  }
  InsZuptIncrements out;
  out.velocities_mps = RowMatrixXd::Zero(n, 3);
  out.increments_m.resize(static_cast<Eigen::Index>(m - 1), 3);
  out.stride_lengths_m.resize(static_cast<Eigen::Index>(m - 1));
  for (size_t k = 1; k < m; ++k) {
    const Eigen::Index a = steps[k - 1], b = steps[k];
    const double mk = static_cast<double>(b - a);
    Eigen::Vector3d dp = Eigen::Vector3d::Zero();
    for (Eigen::Index i = a; i <= b; ++i) {
      // Step 3b: linear interpolation of the drift between the two stance events.
      const Eigen::Vector3d corr = (mu[k] * static_cast<double>(i - a) + mu[k - 1] * static_cast<double>(b - i)) / mk;
      const Eigen::Vector3d vt = v.row(i).transpose() - corr;
      out.velocities_mps.row(i) = vt.transpose();
      if (i > a) dp += vt * dt_at(i);  // eq. 5 (rectangle rule over the step)
    }
    out.increments_m.row(static_cast<Eigen::Index>(k - 1)) = dp.transpose();
    out.stride_lengths_m[static_cast<Eigen::Index>(k - 1)] = dp.head<2>().norm();  // eq. 6
  }
  return out;
}

}  // namespace indoorloc::pdr
