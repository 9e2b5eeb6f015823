// Fixed-lag ring of particle positions: the last L + 1 positions of every particle, reordered
// with the particles at resampling, so that a particle filter can report the position L steps
// back from today's weights (the fixed-lag smoother of Kitagawa 1996, §4.2: the ancestors'
// positions weighted by the descendants' weights). Used by mapmatch::ParticleMapMatcher and
// fusion::ParticleTracker.
//
// Use: for every step, Record(i, x, y) for each particle, then Advance(); after resampling,
// Gather(ancestors). Once has_lagged(), WeightedSum(w) is Σ_i w_i p_i(k − L) over the positions
// recorded L steps before the last one. Memory: particle-major rows of (L + 1) (x, y) pairs, so
// that resampling copies one contiguous row per particle.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace indoorloc {

class FixedLagRing {
 public:
  /// Bytes per particle of a ring with `lag_steps` (ring and its copy at resampling).
  static double BytesPerParticle(int lag_steps) { return lag_steps > 0 ? 32.0 * (lag_steps + 1.0) : 0.0; }

  /// Empties the ring for `num_particles` particles and a lag of `lag_steps` steps (0: off, no
  /// memory). Slots start as NaN. Throws std::invalid_argument for negative sizes.
  void Reset(int num_particles, int lag_steps);

  bool enabled() const { return lag_steps_ > 0; }
  int lag_steps() const { return lag_steps_; }
  int num_particles() const { return num_particles_; }
  /// Steps recorded (Advance calls) since the last Reset.
  std::int64_t steps_recorded() const { return steps_; }

  /// Position [m] of particle i at the step being recorded (0 <= i < num_particles; unchecked).
  void Record(int i, double x_m, double y_m) {
    double* p = data_.data() + (static_cast<size_t>(i) * slots() + slot_) * 2;
    p[0] = x_m;
    p[1] = y_m;
  }
  /// Closes the step being recorded.
  void Advance() {
    ++steps_;
    slot_ = static_cast<size_t>(steps_ % static_cast<std::int64_t>(slots()));
  }
  /// True once L + 1 steps were recorded: the positions L steps before the last one exist.
  bool has_lagged() const { return enabled() && steps_ > lag_steps_; }
  /// Σ_i w_i p_i over the positions recorded L steps before the last recorded step, summed in
  /// particle order; `weights` holds num_particles entries (any normalisation). Requires
  /// has_lagged().
  Eigen::Vector2d WeightedSum(const double* weights) const;
  /// After resampling: particle i takes the history of particle ancestors[i] (num_particles
  /// entries, each in [0, num_particles)).
  void Gather(const std::vector<int>& ancestors);

 private:
  size_t slots() const { return static_cast<size_t>(lag_steps_) + 1; }

  int num_particles_ = 0;
  int lag_steps_ = 0;
  std::int64_t steps_ = 0;
  size_t slot_ = 0;  // slot of the step being recorded: steps_ mod (L + 1)
  std::vector<double> data_, scratch_;
};

}  // namespace indoorloc
