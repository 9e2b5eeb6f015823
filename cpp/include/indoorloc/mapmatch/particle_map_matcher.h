// Circular particle filter for map matching from speed and heading only (paper 000, §II.C,
// Algorithm 1).
//
// Particles live on the network: (segment S, travel direction d = ±1, distance u from end A).
//  - Initialisation: equal spacing over all segments, both directions (unknown start).
//  - Prediction (eq. 8-10): u advances by d (v Δt + η), η ~ U(-a, a) (a = noise_halfwidth_m);
//    past a segment end the remaining distance is carried onto a continuation chosen uniformly
//    (paper) or, optionally, with probabilities favouring the measured heading (with the
//    importance-weight correction that keeps the filter exact). A negative v Δt + η moves the
//    particle back within its segment (no floor at 0, which would bias the move forward); it
//    stops at the end behind it (never backs onto another segment).
//  - Update (eq. 1, 11): log w += κ_P cos(φ - β(S, d)) - log(2π I0(κ_P)), with β(S, -1) = β_S + π,
//    so the von Mises likelihood compares the compass heading with the particle's direction of
//    travel on its corridor.
//  - Normalisation (eq. 12) in log space; resampling when N_eff < ess_threshold N (eq. 14).
//  - Estimate (eq. 13): weighted mean of the particle positions, projected on the nearest segment.
//  - Seeking/tracking flag: tracking when the weighted spread of the particles is below
//    tracking_spread_m. Recovery ("switch back to the seeking phase"): when the posterior
//    disagrees with the compass for a sustained time (windowed mean of the weighted
//    1 - cos(φ - β) above recovery_disagreement), a fraction of the particles is re-spread
//    over the whole network.
// Beyond the paper, each optional and measured in docs/mapmatch.md: a per-particle odometer
// bias state; heading-aware junction choice; fixed-lag smoothing of the position.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/core/fixed_lag_ring.h"
#include "indoorloc/core/random.h"
#include "indoorloc/core/random_lanes.h"
#include "indoorloc/core/resampling.h"
#include "indoorloc/mapmatch/corridor_motion.h"
#include "indoorloc/mapmatch/road_network.h"

namespace indoorloc::mapmatch {

struct FilterOptions {
  int num_particles = 10000;
  /// κ_P, concentration of the von Mises heading likelihood (eq. 11), at most kMaxCorridorKappa.
  double kappa = 1.0;
  /// Half-width a of the uniform propagation noise η ~ U(-a, a) per step [m] (eq. 8-9).
  double noise_halfwidth_m = 0.6;
  /// Resampling scheme and threshold N_T = ess_threshold * N (eq. 14).
  ResamplingOptions resampling;
  JunctionPolicy junction_policy = JunctionPolicy::kUniform;
  /// Concentration used by the heading-aware junction proposal.
  double junction_kappa = 2.0;
  /// Per-particle odometer bias b: distance = (v - b) Δt + η; b ~ U(-bias_halfwidth, +) at start,
  /// random walk of sd bias_jitter_mps per step.
  bool estimate_speed_bias = false;
  double bias_halfwidth_mps = 0.5;
  double bias_jitter_mps = 0.02;
  /// Tracking flag when the weighted particle spread (sqrt of the trace of the covariance) is
  /// below this [m].
  double tracking_spread_m = 2.0;
  /// Recovery: re-spread when the windowed mean disagreement exceeds this (0 = perfect
  /// agreement, 1 = unrelated headings, 2 = opposite); <= 0 disables recovery.
  double recovery_disagreement = 0.9;
  double recovery_window_s = 20.0;
  /// Fraction of the particles re-spread by a recovery.
  double recovery_fraction = 0.5;
  /// Fixed-lag smoother: also estimate the position `smoothing_lag_steps` steps back (0: off).
  int smoothing_lag_steps = 0;
  std::uint64_t seed = 0;

  bool IsValid(std::string* error) const;
  /// The corridor motion model's part of these options (kappa, junction policy and kappa).
  CorridorMotionOptions corridor_motion() const { return {kappa, junction_policy, junction_kappa}; }
};

/// One filter step's output.
struct StepEstimate {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();      ///< projected on the network
  Eigen::Vector2d weighted_mean_m = Eigen::Vector2d::Zero(); ///< eq. 13 before projection
  int segment = -1;                ///< index of the nearest segment to the weighted mean
  double spread_m = 0.0;           ///< weighted sqrt(trace(covariance)) of the particles
  bool tracking = false;
  double ess = 0.0;                ///< before resampling
  double log_likelihood = 0.0;     ///< log p(φ_k | φ_{1:k-1}) increment
  bool resampled = false;
  bool recovered = false;
  /// Smoothed position of step k - lag (valid when the filter has run lag + 1 steps).
  Eigen::Vector2d smoothed_m = Eigen::Vector2d::Constant(std::nan(""));
};

/// Whole-run Summary.
struct FilterSummary {
  int steps = 0;
  int resamplings = 0;
  int recoveries = 0;
  double total_log_likelihood = 0.0;
  double mean_ess = 0.0;
  double seconds = 0.0;
  std::string BriefReport() const;
};

class ParticleMapMatcher {
 public:
  /// Keeps a reference to `network`, which must outlive the filter.
  ParticleMapMatcher(const RoadNetwork& network, const FilterOptions& options);

  /// Re-initialises the particles (equal spacing, both directions) and the random stream.
  void Reset();
  /// Replaces the particles (e.g. from a prior on the start): segment indices, directions (±1)
  /// and distances from end A [m], one entry per particle; weights become uniform.
  void SetParticles(const std::vector<int>& segments, const std::vector<signed char>& directions,
                    const std::vector<double>& along_m);
  /// One step with odometer speed v [m/s], compass heading φ [rad] and time step Δt [s].
  StepEstimate Step(double speed_mps, double heading_rad, double dt_s);

  /// Posterior probability of each segment (sum of the weights of its particles).
  Eigen::VectorXd SegmentPosterior() const;
  /// Current particles: positions (N x 2), segment indices, directions, weights (normalised).
  RowMatrixXd ParticlePositions() const;
  const std::vector<int>& particle_segments() const { return segment_; }
  const std::vector<signed char>& particle_directions() const { return direction_; }
  const std::vector<double>& particle_along_m() const { return along_; }
  Eigen::VectorXd ParticleWeights() const;
  const FilterSummary& summary() const { return summary_; }
  const FilterOptions& options() const { return options_; }

 private:
  void Spread(int first, int count, double offset_fraction);
  /// Replaces every particle's state by its ancestor's (ancestors_, after ResampleLinear).
  void TakeAncestorsStates(int n);

  const RoadNetwork& network_;
  FilterOptions options_;
  // The network move, the von Mises heading weight and the junction policy (shared with the
  // fusion tracker's corridor mode).
  CorridorMotion motion_;
  RandomStream rng_;     // junction choices, resampling, recovery
  RandomLanes lanes_;    // the per-particle uniform draws of the prediction
  std::vector<int> segment_;
  std::vector<signed char> direction_;
  std::vector<double> along_;
  std::vector<double> limit_;  // the length of each particle's segment [m]: one load in the move pass
  std::vector<double> bias_;
  // Linear weights, rescaled every step so that the largest is 1 (times weight_scale_, applied
  // at the next update): no exp() per particle; likelihood factors come from a per-step table of
  // the 2M (segment, direction) values.
  std::vector<double> weights_;
  double weight_scale_ = 1.0;
  double weight_sum_ = 1.0;  // Σ w after the last step (before the pending rescale)
  std::vector<int> ancestors_;
  // Scratch for resampling gathers and per-segment cos(φ - β).
  std::vector<int> segment_tmp_;
  std::vector<signed char> direction_tmp_;
  std::vector<double> along_tmp_, limit_tmp_, bias_tmp_;
  std::vector<double> factor_;        // 2M: exp(κ (d cos(φ - β_s) - 1)), index 2 s + (d > 0)
  std::vector<double> disagree_;      // 2M: 1 - d cos(φ - β_s)
  std::vector<double> uniform_, distance_;  // N: a step's draws and distances
  CorridorMotion::MoveScratch move_scratch_;
  // Recovery window of per-step disagreements.
  std::vector<double> disagreement_window_;
  size_t window_pos_ = 0;
  size_t window_filled_ = 0;
  bool was_tracking_ = false;
  // Fixed-lag smoothing: per particle the last L + 1 positions.
  FixedLagRing lag_ring_;
  FilterSummary summary_;
};

/// Runs the filter over a whole trajectory from its current state (no Reset: call Reset() first to
/// start from the initial grid); returns per-step estimates.
std::vector<StepEstimate> RunFilter(ParticleMapMatcher& filter, const Eigen::Ref<const Eigen::VectorXd>& speed_mps,
                                    const Eigen::Ref<const Eigen::VectorXd>& heading_rad, double dt_s);

}  // namespace indoorloc::mapmatch
