#include "indoorloc/fusion/step_motion.h"

#include <cmath>
#include <string>

#include <Eigen/LU>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::fusion {

namespace {
double WrapAngle(double a) {
  a = std::remainder(a, 2.0 * M_PI);
  return a;
}
}  // namespace

StepInput StepFromPolar(double time_s, double length_m, double heading_rad, double length_sd_m,
                        double heading_sd_rad) {
  CheckArgument(std::isfinite(time_s), "time_s", "must be finite");
  CheckNonNegative(length_m, "length_m");
  CheckArgument(std::isfinite(heading_rad), "heading_rad", "must be finite");
  CheckNonNegative(length_sd_m, "length_sd_m");
  CheckNonNegative(heading_sd_rad, "heading_sd_rad");
  StepInput step;
  step.time_s = time_s;
  const double c = std::cos(heading_rad), s = std::sin(heading_rad);
  step.displacement_m = Eigen::Vector2d(length_m * c, length_m * s);
  Eigen::Matrix2d jacobian;
  jacobian << c, -length_m * s, s, length_m * c;
  const Eigen::Vector2d variances(length_sd_m * length_sd_m, heading_sd_rad * heading_sd_rad);
  step.covariance_m2 = jacobian * variances.asDiagonal() * jacobian.transpose();
  return step;
}

bool StepMotionOptions::IsValid(std::string* error) const {
  // The position noise enters the smoother's Gaussian density as 1/σ²: a lower bound of
  // kMinScale keeps it finite (1e-300 passed "> 0").
  return Validator(error)
      .InRange(heading_offset_walk_rad, 0.0, M_PI, "heading_offset_walk_rad")
      .InRange(scale_walk, 0.0, 1.0, "scale_walk")
      .InRange(min_scale, kMinScale, 100.0, "min_scale")
      .InRange(max_scale, kMinScale, 100.0, "max_scale")
      .Check(min_scale <= max_scale, "min_scale",
             "must be <= max_scale = " + FormatValue(max_scale) + ", got " + FormatValue(min_scale))
      .InRange(position_noise_m, kMinScale, 100.0, "position_noise_m");
}

void CheckStepInput(const StepInput& step, const char* argument) {
  const std::string name(argument);
  CheckArgument(std::isfinite(step.time_s), name + ".time_s", "must be finite");
  CheckFinite(step.displacement_m, name + ".displacement_m");
  CheckFinite(step.covariance_m2, name + ".covariance_m2");
  const Eigen::Matrix2d& c = step.covariance_m2;
  // A step's sd beyond 100 m is no step (and 1e300 entries overflowed the determinant).
  CheckArgument(c.cwiseAbs().maxCoeff() <= 1e4, name + ".covariance_m2",
                "entries must be within +-1e4 m^2 (sd <= 100 m), got " + FormatValue(c.cwiseAbs().maxCoeff()));
  const double scale = std::max(1.0, c.cwiseAbs().maxCoeff());
  CheckArgument(std::abs(c(0, 1) - c(1, 0)) <= 1e-9 * scale, name + ".covariance_m2", "must be symmetric");
  CheckArgument(c(0, 0) >= 0.0 && c(1, 1) >= 0.0 && c(0, 0) * c(1, 1) - c(0, 1) * c(1, 0) >= -1e-12 * scale * scale,
                name + ".covariance_m2", "must be positive semi-definite");
  CheckArgument(step.displacement_m.norm() <= 100.0, name + ".displacement_m",
                "is longer than 100 m (not a step)");
}

StepMotion::StepMotion(const StepInput& step, const StepMotionOptions& options) : step_(step), options_(options) {
  const double var_p = options.position_noise_m * options.position_noise_m;
  const Eigen::Matrix2d noise = step.covariance_m2 + var_p * Eigen::Matrix2d::Identity();
  // 2 x 2 Cholesky by hand (noise is positive definite: var_p > 0).
  const double l00 = std::sqrt(noise(0, 0));
  const double l10 = noise(1, 0) / l00;
  const double l11 = std::sqrt(std::max(noise(1, 1) - l10 * l10, 1e-18));
  chol_ << l00, 0.0, l10, l11;
  noise_inverse_ = noise.inverse();
}

double StepMotion::TransitionLogDensity(const Eigen::Vector2d& from_m, double from_offset_rad, double from_scale,
                                        const Eigen::Vector2d& to_m, double to_offset_rad, double to_scale) const {
  double log_density = 0.0;
  const double d_offset = WrapAngle(to_offset_rad - from_offset_rad);
  if (options_.heading_offset_walk_rad > 0.0) {
    const double z = d_offset / options_.heading_offset_walk_rad;
    log_density -= 0.5 * z * z;
  } else if (std::abs(d_offset) > 1e-12) {
    return -std::numeric_limits<double>::infinity();
  }
  const double d_scale = to_scale - from_scale;
  if (options_.scale_walk > 0.0) {
    const double z = d_scale / options_.scale_walk;
    log_density -= 0.5 * z * z;
  } else if (std::abs(d_scale) > 1e-12) {
    return -std::numeric_limits<double>::infinity();
  }
  // r = R(o')ᵀ (p' - p) / s' - d ~ N(0, Σ_d + σ_p² I); the Jacobian 1/s'² depends on the
  // successor only and cancels in the backward kernel.
  const double c = std::cos(to_offset_rad), s = std::sin(to_offset_rad);
  const Eigen::Vector2d delta = to_m - from_m;
  const Eigen::Vector2d r(( c * delta.x() + s * delta.y()) / to_scale - step_.displacement_m.x(),
                          (-s * delta.x() + c * delta.y()) / to_scale - step_.displacement_m.y());
  log_density -= 0.5 * r.dot(noise_inverse_ * r);
  return log_density;
}

}  // namespace indoorloc::fusion
