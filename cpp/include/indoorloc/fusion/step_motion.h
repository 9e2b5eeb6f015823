// The motion model of the fusion tracker: one detected step moves a particle.
//
// A step arrives from PDR (handheld step detection + stride length + heading, or foot-mounted
// ZUPT increments, paper 002 eq. 8-9) as a displacement d (2) [m] in the PDR frame with its
// covariance Σ_d (2 x 2) [m²]. The PDR frame differs from the floor frame by an unknown,
// slowly drifting yaw (heading offset o), and the stride length by an unknown scale s. With
// particle state (p, o, s) the model is
//
//   o' = wrap(o + w_o),        w_o ~ N(0, σ_o²)               heading-offset random walk
//   s' = s + w_s,              w_s ~ N(0, σ_s²), s' kept in [s_min, s_max]
//   p' = p + s' R(o') (d + e), e   ~ N(0, Σ_d + σ_p² I)        step noise + process noise
//
// R(o) the rotation by o. Given (o', s') the position transition is Gaussian with mean
// p + s' R(o') d and covariance s'² R(o') (Σ_d + σ_p² I) R(o')ᵀ, which the backward smoother
// evaluates exactly (TransitionLogDensity). The process noise σ_p is expressed in the step
// frame (scaled by s') so that the transition stays exactly Gaussian.
//
// A polar step (length L with sd σ_L, heading h with sd σ_h) becomes d = L (cos h, sin h),
// Σ_d = J diag(σ_L², σ_h²) Jᵀ, J = [[cos h, -L sin h], [sin h, L cos h]] (first-order
// propagation, adequate for per-step heading noise of a few degrees).
#pragma once
#include <algorithm>
#include <cmath>
#include <string>
#include <Eigen/Core>

#include "indoorloc/core/random.h"
#include "indoorloc/core/random_lanes.h"

namespace indoorloc::fusion {

/// One detected step: time [s], displacement in the PDR frame [m], its covariance [m²].
struct StepInput {
  double time_s = 0.0;
  Eigen::Vector2d displacement_m = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance_m2 = Eigen::Matrix2d::Zero();
};

/// A step given as length and heading with standard deviations (see the header comment).
StepInput StepFromPolar(double time_s, double length_m, double heading_rad, double length_sd_m,
                        double heading_sd_rad);

/// Process noise of the motion model. σ_o, σ_s and σ_p were chosen by `indoorloc fusion tune`
/// (two grid rounds on synthetic tuning seeds 1000-1019, never on the scored seeds; docs/fusion.md).
struct StepMotionOptions {
  /// σ_o: random walk of the heading offset per step [rad] (gyro / compass heading drift).
  double heading_offset_walk_rad = 1.0 * M_PI / 180.0;
  /// σ_s: random walk of the stride-length scale per step (dimensionless).
  double scale_walk = 0.01;
  /// Bounds of the scale s.
  double min_scale = 0.5;
  double max_scale = 1.8;
  /// σ_p: isotropic process noise added to each step's covariance [m] (unmodelled motion,
  /// sway, detection timing).
  double position_noise_m = 0.3;
  bool IsValid(std::string* error) const;
};

/// Throws std::invalid_argument naming `argument` unless the step is usable: finite time,
/// displacement and covariance, covariance symmetric and positive semi-definite.
void CheckStepInput(const StepInput& step, const char* argument);

/// Sampling and density of the model for one step (the Cholesky factor is computed once per
/// step and shared by all particles).
class StepMotion {
 public:
  StepMotion(const StepInput& step, const StepMotionOptions& options);
  /// Draws (o', s') and the displacement Δ = s' R(o') (d + e) for a particle with (o, s).
  void Sample(double offset_rad, double scale, RandomStream& rng, double* new_offset_rad,
              double* new_scale, Eigen::Vector2d* displacement_m) const {
    double c = std::cos(offset_rad), sn = std::sin(offset_rad);
    Sample(offset_rad, &c, &sn, scale, rng, new_offset_rad, new_scale, displacement_m);
  }
  /// As above for a particle that also carries cos o and sin o (updated in place to cos o' and
  /// sin o'): the tracker's inner loop. The rotation by the small offset increment δ uses
  /// cos δ, sin δ from their Taylor series (|δ| < 0.1 rad: error below 1e-13) instead of a
  /// sincos call; normal draws by the ziggurat method (RandomStream::NormalZiggurat).
  void Sample(double offset_rad, double* cos_offset, double* sin_offset, double scale, RandomStream& rng,
              double* new_offset_rad, double* new_scale, Eigen::Vector2d* displacement_m) const {
    const double z_offset = rng.NormalZiggurat();
    const double z_scale = rng.NormalZiggurat();
    const double z1 = rng.NormalZiggurat();
    const double z2 = rng.NormalZiggurat();
    double dx, dy;
    Move(z_offset, z_scale, z1, z2, offset_rad, cos_offset, sin_offset, scale, new_offset_rad, new_scale, &dx, &dy);
    *displacement_m = Eigen::Vector2d(dx, dy);
  }
  /// Sample for particles 0..count-1 of structure-of-arrays state, in place: offset_rad,
  /// cos_offset, sin_offset and scale become o', cos o', sin o', s'; the displacements go to
  /// dx_m, dy_m. The normals come from `lanes` (RandomLanes::FillNormal, its rare slow-path
  /// draws from `fallback`), four blocks of them per chunk of particles (offset walk, scale walk,
  /// step noise 1 and 2), and the arithmetic runs as one vector loop per chunk (AVX2 where the
  /// CPU has it, same bits). Same model as Sample, different draws.
  void SampleBlock(int count, double* offset_rad, double* cos_offset, double* sin_offset, double* scale,
                   RandomLanes& lanes, RandomStream& fallback, double* dx_m, double* dy_m) const;
  /// log p(p', o', s' | p, o, s) up to the constant common to all pairs (the backward smoother
  /// only needs ratios over the predecessor (p, o, s)).
  double TransitionLogDensity(const Eigen::Vector2d& from_m, double from_offset_rad, double from_scale,
                              const Eigen::Vector2d& to_m, double to_offset_rad, double to_scale) const;
  /// A successor (p', o', s') with cos o' and sin o' computed once (SuccessorOf), for the
  /// backward smoother's many predecessors of one successor.
  struct Successor {
    Eigen::Vector2d position_m;
    double offset_rad, scale, cos_offset, sin_offset;
  };
  static Successor SuccessorOf(const Eigen::Vector2d& to_m, double to_offset_rad, double to_scale);
  /// TransitionLogDensity to a successor of SuccessorOf: the same operations, so the same bits.
  double TransitionLogDensity(const Eigen::Vector2d& from_m, double from_offset_rad, double from_scale,
                              const Successor& to) const;
  const StepInput& step() const { return step_; }
  /// Lower Cholesky factor of Σ_d + σ_p² I.
  const Eigen::Matrix2d& cholesky() const { return chol_; }

 private:
  // The motion given the four standard normal draws (offset walk, scale walk, step noise 1, 2).
  void Move(double z_offset, double z_scale, double z1, double z2, double offset_rad, double* cos_offset,
            double* sin_offset, double scale, double* new_offset_rad, double* new_scale, double* dx_m,
            double* dy_m) const {
    const double delta = options_.heading_offset_walk_rad * z_offset;
    double o = offset_rad + delta;
    double c, sn;
    if (std::abs(delta) < 0.1) {
      const double d2 = delta * delta;
      const double cd = 1.0 - d2 * (0.5 - d2 * (1.0 / 24.0 - d2 * (1.0 / 720.0)));
      const double sd = delta * (1.0 - d2 * (1.0 / 6.0 - d2 * (1.0 / 120.0 - d2 * (1.0 / 5040.0))));
      c = *cos_offset * cd - *sin_offset * sd;
      sn = *sin_offset * cd + *cos_offset * sd;
    } else {
      c = std::cos(o);
      sn = std::sin(o);
    }
    if (o > M_PI) o -= 2.0 * M_PI;
    if (o <= -M_PI) o += 2.0 * M_PI;
    double s = scale + options_.scale_walk * z_scale;
    s = s < options_.min_scale ? options_.min_scale : (s > options_.max_scale ? options_.max_scale : s);
    // e = L n with L the lower Cholesky factor of Σ_d + σ_p² I.
    const double dx = step_.displacement_m.x() + chol_(0, 0) * z1;
    const double dy = step_.displacement_m.y() + chol_(1, 0) * z1 + chol_(1, 1) * z2;
    *new_offset_rad = o;
    *new_scale = s;
    *cos_offset = c;
    *sin_offset = sn;
    *dx_m = s * (c * dx - sn * dy);
    *dy_m = s * (sn * dx + c * dy);
  }

  StepInput step_;
  StepMotionOptions options_;
  Eigen::Matrix2d chol_;
  Eigen::Matrix2d noise_inverse_;  // (Σ_d + σ_p² I)⁻¹
};

}  // namespace indoorloc::fusion
