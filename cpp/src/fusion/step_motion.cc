#include "indoorloc/fusion/step_motion.h"

#include <cmath>
#include <string>

#include <Eigen/LU>

#include "indoorloc/core/check.h"
#include "indoorloc/core/simd_dispatch.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::fusion {

namespace {
// remainder(a, 2 pi) is a itself when |a| <= pi (the quotient rounds to 0, a tie to the even 0):
// the common case of the smoother's offset differences, without the library call.
double WrapAngle(double a) {
  if (std::abs(a) <= M_PI) return a;
  return std::remainder(a, 2.0 * M_PI);
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

namespace {
// The per-step constants of the block motion.
struct BlockMotion {
  double offset_walk, scale_walk, min_scale, max_scale;
  double d_x, d_y, l00, l10, l11;  // step displacement [m], Cholesky factor of its noise
};

// The motion of particles 0..m-1 given their normals z (offset walk z[k], scale walk z[m + k],
// step noise z[2m + k], z[3m + k]): StepMotion::Move written without branches (the Taylor
// rotation for every particle; the few with |delta| >= 0.1 are redone by FixLargeTurns) so that
// it compiles to one vector loop. Elementwise IEEE operations only: the same bits at any width.
[[gnu::always_inline]] inline void MoveChunkBody(int m, const double* __restrict z, double* __restrict offset,
                                                 double* __restrict co, double* __restrict so,
                                                 double* __restrict scale, double* __restrict dx_m,
                                                 double* __restrict dy_m, const BlockMotion& c) {
  for (int k = 0; k < m; ++k) {
    const double delta = c.offset_walk * z[k];
    double o = offset[k] + delta;
    const double d2 = delta * delta;
    const double cd = 1.0 - d2 * (0.5 - d2 * (1.0 / 24.0 - d2 * (1.0 / 720.0)));
    const double sd = delta * (1.0 - d2 * (1.0 / 6.0 - d2 * (1.0 / 120.0 - d2 * (1.0 / 5040.0))));
    const double cn = co[k] * cd - so[k] * sd;
    const double sn = so[k] * cd + co[k] * sd;
    // Both wraps computed unconditionally, then selected: a select without arithmetic in its
    // arms is what lets the compiler turn the loop into vector code.
    const double o_down = o - 2.0 * M_PI;
    o = o > M_PI ? o_down : o;
    const double o_up = o + 2.0 * M_PI;
    o = o <= -M_PI ? o_up : o;
    double sc = scale[k] + c.scale_walk * z[m + k];
    sc = sc < c.min_scale ? c.min_scale : sc;
    sc = sc > c.max_scale ? c.max_scale : sc;
    const double ex = c.d_x + c.l00 * z[2 * m + k];
    const double ey = c.d_y + c.l10 * z[2 * m + k] + c.l11 * z[3 * m + k];
    offset[k] = o;
    scale[k] = sc;
    co[k] = cn;
    so[k] = sn;
    dx_m[k] = sc * (cn * ex - sn * ey);
    dy_m[k] = sc * (sn * ex + cn * ey);
  }
}

void MoveChunkPortable(int m, const double* z, double* offset, double* co, double* so, double* scale, double* dx_m,
                       double* dy_m, const BlockMotion& c) {
  MoveChunkBody(m, z, offset, co, so, scale, dx_m, dy_m, c);
}

__attribute__((target("avx2"))) void MoveChunkAvx2(int m, const double* z, double* offset, double* co, double* so,
                                                   double* scale, double* dx_m, double* dy_m, const BlockMotion& c) {
  MoveChunkBody(m, z, offset, co, so, scale, dx_m, dy_m, c);
}

// The particles whose offset increment |delta| >= 0.1 rad (beyond the Taylor series' accuracy):
// cos o', sin o' from the library and the displacement again.
void FixLargeTurns(int m, const double* z, const double* offset, double* co, double* so, const double* scale,
                   double* dx_m, double* dy_m, const BlockMotion& c) {
  for (int k = 0; k < m; ++k) {
    if (!(std::abs(c.offset_walk * z[k]) >= 0.1)) continue;
    const double cn = std::cos(offset[k]), sn = std::sin(offset[k]);
    const double ex = c.d_x + c.l00 * z[2 * m + k];
    const double ey = c.d_y + c.l10 * z[2 * m + k] + c.l11 * z[3 * m + k];
    co[k] = cn;
    so[k] = sn;
    dx_m[k] = scale[k] * (cn * ex - sn * ey);
    dy_m[k] = scale[k] * (sn * ex + cn * ey);
  }
}
}  // namespace

void StepMotion::SampleBlock(int count, double* offset_rad, double* cos_offset, double* sin_offset, double* scale,
                             RandomLanes& lanes, RandomStream& fallback, double* dx_m, double* dy_m) const {
  const BlockMotion c{options_.heading_offset_walk_rad,
                      options_.scale_walk,
                      options_.min_scale,
                      options_.max_scale,
                      step_.displacement_m.x(),
                      step_.displacement_m.y(),
                      chol_(0, 0),
                      chol_(1, 0),
                      chol_(1, 1)};
  const bool avx2 = UseAvx2();
  constexpr int kChunk = 256;
  double z[4 * kChunk];
  for (int begin = 0; begin < count; begin += kChunk) {
    const int m = std::min(kChunk, count - begin);
    lanes.FillNormal(z, 4 * m, fallback);
    double* o = offset_rad + begin;
    double* co = cos_offset + begin;
    double* so = sin_offset + begin;
    double* sc = scale + begin;
    if (avx2) {
      MoveChunkAvx2(m, z, o, co, so, sc, dx_m + begin, dy_m + begin, c);
    } else {
      MoveChunkPortable(m, z, o, co, so, sc, dx_m + begin, dy_m + begin, c);
    }
    FixLargeTurns(m, z, o, co, so, sc, dx_m + begin, dy_m + begin, c);
  }
}

StepMotion::Successor StepMotion::SuccessorOf(const Eigen::Vector2d& to_m, double to_offset_rad, double to_scale) {
  return Successor{to_m, to_offset_rad, to_scale, std::cos(to_offset_rad), std::sin(to_offset_rad)};
}

double StepMotion::TransitionLogDensity(const Eigen::Vector2d& from_m, double from_offset_rad, double from_scale,
                                        const Eigen::Vector2d& to_m, double to_offset_rad, double to_scale) const {
  return TransitionLogDensity(from_m, from_offset_rad, from_scale, SuccessorOf(to_m, to_offset_rad, to_scale));
}

double StepMotion::TransitionLogDensity(const Eigen::Vector2d& from_m, double from_offset_rad, double from_scale,
                                        const Successor& to) const {
  double log_density = 0.0;
  const double d_offset = WrapAngle(to.offset_rad - from_offset_rad);
  if (options_.heading_offset_walk_rad > 0.0) {
    const double z = d_offset / options_.heading_offset_walk_rad;
    log_density -= 0.5 * z * z;
  } else if (std::abs(d_offset) > 1e-12) {
    return -std::numeric_limits<double>::infinity();
  }
  const double d_scale = to.scale - from_scale;
  if (options_.scale_walk > 0.0) {
    const double z = d_scale / options_.scale_walk;
    log_density -= 0.5 * z * z;
  } else if (std::abs(d_scale) > 1e-12) {
    return -std::numeric_limits<double>::infinity();
  }
  // r = R(o')ᵀ (p' - p) / s' - d ~ N(0, Σ_d + σ_p² I); the Jacobian 1/s'² depends on the
  // successor only and cancels in the backward kernel.
  const double c = to.cos_offset, s = to.sin_offset;
  const Eigen::Vector2d delta = to.position_m - from_m;
  const Eigen::Vector2d r(( c * delta.x() + s * delta.y()) / to.scale - step_.displacement_m.x(),
                          (-s * delta.x() + c * delta.y()) / to.scale - step_.displacement_m.y());
  log_density -= 0.5 * r.dot(noise_inverse_ * r);
  return log_density;
}

}  // namespace indoorloc::fusion
