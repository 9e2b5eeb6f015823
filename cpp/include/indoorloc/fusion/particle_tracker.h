// The fusion tracker: one particle filter that tracks a walking person from PDR steps, a WiFi
// signal map and a floor plan (the "future work" of papers 000 §IV and 002 §VI).
//
// Particle state: position p (x, y) [m], floor, heading offset o [rad] between the PDR frame and
// the floor frame, stride-length scale s; in corridor mode also the mapmatch state (segment,
// direction, distance along). Per event:
//  - Step (StepMotion): every particle moves by s' R(o') (d + e) (step_motion.h). With a floor
//    plan, a particle whose step p -> p' crosses a wall gets log w += wall_log_penalty (-inf:
//    dropped) and stays at p, so no particle ever ends inside an obstacle. If every particle is
//    blocked the step is ignored (weights and positions kept, counted in the Summary); after
//    `respread_after_blocked_steps` such steps in a row the cloud is re-spread around its mean.
//  - Corridor mode (a RoadNetwork is given): particles move along the network by the step's
//    length times s' (uniform choice at junctions, paper 000 eq. 8-10) and are weighted by the
//    von Mises likelihood of the measured heading h + o' against their direction of travel
//    (paper 000 eq. 11): log w += κ cos(h + o' - β(S, d)) - log(2π I0(κ)).
//  - WiFi (WifiLikelihood): log w += τ log p(v | p) on the particle's floor.
//  - Position fix (FixLikelihood, position_fix.h): log w += τ_fix log p(fix | p), a Gaussian
//    mixture with an outlier floor from any external locator (fingerprint kNN, BLE, UWB).
//  - Log-weights are normalised (log-sum-exp); resampling when ESS < threshold N (paper 000
//    eq. 14), all state arrays gathered together.
// Start: known (Gaussian prior on position, heading offset and scale on one floor, truncated to
// the walkable area) or unknown (drawn from the first scan's WiFi likelihood, or the first fix's,
// over candidate points of the walkable area on every floor: the short seeking phase paper 000
// §IV asks for).
// Recovery: when the filter's predictive likelihood of a scan (or fix) stays more than
// `recovery_log_ratio` nats below the best candidate's for `recovery_scans` scans in a row, a
// fraction of the particles is re-drawn from the scan's likelihood over the candidates.
// Outputs per step: weighted mean and covariance, floor probabilities, ESS, log-likelihood
// increments; a fixed-lag smoother (per-particle position history gathered at resampling) and,
// with `record_history`, the per-step particle clouds for the backward smoother
// (backward_smoother.h).
//
// Randomness: particles are processed in fixed blocks of kBlockSize, block b of event e drawing
// from RandomStream(DeriveSeed(seed, e), b) (in free space the block's normals come from eight
// RandomLanes seeded by that stream's first draw, the ziggurat's rare slow path from the stream
// itself); resampling uses the tracker's own stream. Results are therefore identical for any
// num_threads, and with or without AVX2.
#pragma once
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>
#include <Eigen/Core>

#include "indoorloc/core/random.h"
#include "indoorloc/core/resampling.h"
#include "indoorloc/fusion/floor_plan.h"
#include "indoorloc/fusion/position_fix.h"
#include "indoorloc/fusion/step_motion.h"
#include "indoorloc/fusion/wifi_likelihood.h"
#include "indoorloc/mapmatch/road_network.h"
#include "indoorloc/wifi/rss_model.h"

namespace indoorloc::fusion {

struct TrackerOptions {
  int num_particles = 5000;
  StepMotionOptions motion;
  WifiLikelihoodOptions wifi;
  FixLikelihoodOptions fix;
  ResamplingOptions resampling;
  /// Added to the log-weight of a particle whose step crosses a wall; -inf drops it.
  double wall_log_penalty = -std::numeric_limits<double>::infinity();
  /// Re-spread the cloud (Gaussian around its mean, sd respread_sd_m, on walkable space) after
  /// this many consecutive steps in which every particle was blocked.
  int respread_after_blocked_steps = 3;
  double respread_sd_m = 3.0;
  /// Known start: sd of the position [m], heading offset [rad] and scale priors.
  double start_position_sd_m = 1.0;
  double start_heading_offset_sd_rad = 5.0 * M_PI / 180.0;
  double start_scale_sd = 0.1;
  /// Unknown start and recovery: the heading offset is drawn uniformly on the circle (+inf), or
  /// from N(0, sd²) [rad] when the PDR heading is already nearly in the floor frame (a phone's
  /// rotation vector: docs/pdr_handheld.md).
  double unknown_start_heading_sd_rad = std::numeric_limits<double>::infinity();
  /// Unknown start and recovery: spacing of the candidate grid over the walkable area [m].
  double candidate_spacing_m = 1.0;
  /// Recovery: log-ratio threshold [nats, tempered], scans in a row, fraction re-drawn;
  /// recovery_log_ratio <= 0 disables recovery.
  double recovery_log_ratio = 6.0;
  int recovery_scans = 3;
  double recovery_fraction = 0.2;
  /// Probability per step that a particle changes floor (to a uniformly chosen other floor of
  /// the plan; stairs and lifts are not modelled). 0: floors only from the start.
  double floor_change_probability = 0.0;
  /// Corridor mode: κ of the von Mises heading likelihood (paper 000 eq. 11), in
  /// [0, mapmatch::kMaxCorridorKappa = 300] (the shared corridor model's limit).
  double corridor_kappa = 2.0;
  /// Fixed-lag smoother: also report the position `smoothing_lag_steps` steps back (0: off).
  int smoothing_lag_steps = 0;
  /// Keep every step's particle cloud for the backward smoother (memory: about 40 bytes per
  /// particle per step).
  bool record_history = false;
  int num_threads = 1;
  std::uint64_t seed = 0;
  bool IsValid(std::string* error) const;
};

/// The filter's output after one event.
struct TrackerEstimate {
  double time_s = 0.0;
  Eigen::Vector2d mean_m = Eigen::Vector2d::Zero();           ///< weighted mean position [m]
  Eigen::Matrix2d covariance_m2 = Eigen::Matrix2d::Zero();    ///< weighted covariance [m²]
  Eigen::VectorXd floor_probabilities;  ///< per floor of the tracker (plan or map floors)
  int floor_index = 0;                  ///< most probable floor (index into floors())
  double heading_offset_rad = 0.0;      ///< weighted circular mean of o
  double scale = 1.0;                   ///< weighted mean of s
  double ess = 0.0;                     ///< effective sample size before resampling
  double log_likelihood = 0.0;          ///< log-likelihood increment of the event
  double blocked_fraction = 0.0;        ///< weight fraction blocked by walls (step events)
  bool resampled = false;
  bool recovered = false;
  /// Fixed-lag smoothed position of the step `smoothing_lag_steps` back (NaN until available).
  Eigen::Vector2d lagged_m = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
};

struct TrackerSummary {
  int steps = 0;
  int wifi_updates = 0;
  int empty_wifi_updates = 0;   ///< observations without usable readings (no-ops)
  int fix_updates = 0;          ///< position fixes applied (empty fixes are no-ops, not counted)
  int resamplings = 0;
  int recoveries = 0;
  int all_blocked_steps = 0;    ///< steps in which every particle was blocked (ignored)
  int respreads = 0;
  double mean_ess = 0.0;        ///< over all events
  double total_log_likelihood = 0.0;
  double seconds = 0.0;
  std::string BriefReport() const;
};

/// Particle clouds recorded for the backward smoother: after step k and every WiFi update up to
/// the next step (the filtering distribution of the state after step k).
struct ParticleHistory {
  std::vector<double> times_s;               ///< per recorded step
  std::vector<StepInput> steps;              ///< the step that led to each cloud
  std::vector<RowMatrixXd> states;           ///< N x 4: x, y, heading offset, scale
  std::vector<Eigen::VectorXi> floor_indices;
  std::vector<Eigen::VectorXd> log_weights;  ///< normalised
};

class ParticleTracker {
 public:
  static constexpr int kBlockSize = 1024;
  /// Any of plan, wifi_model, corridors may be null (that source is not used). They must
  /// outlive the tracker. Throws std::invalid_argument if the signal map has a floor that the
  /// plan lacks (and vice versa), or if corridors are given together with several floors.
  ParticleTracker(const FloorPlan* plan, const wifi::RssModel* wifi_model,
                  const mapmatch::RoadNetwork* corridors, const TrackerOptions& options);
  ~ParticleTracker();
  ParticleTracker(ParticleTracker&&) noexcept;
  ParticleTracker& operator=(ParticleTracker&&) noexcept;

  /// Floor numbers the tracker knows (the plan's, else the map's, else {0}).
  const std::vector<int>& floors() const;

  /// Known start at `position_m` on floor number `floor` with PDR-to-floor heading offset
  /// `heading_offset_rad`. With hard walls (wall_log_penalty = -inf) throws
  /// std::invalid_argument if the position is not walkable and truncates the position prior to
  /// walkable points not behind a wall; with soft walls neither.
  void InitializeKnown(double time_s, const Eigen::Vector2d& position_m, int floor,
                       double heading_offset_rad);
  /// Unknown start from a WiFi observation (needs a signal map): particles drawn from its
  /// likelihood over the candidate grid on every floor, heading offsets uniform on the circle.
  /// With an empty observation, uniform over the walkable area (needs a plan or map).
  void InitializeUnknown(const WifiObservation& observation);
  bool initialized() const;

  /// One detected step. Throws std::invalid_argument on NaN/inf or a negative time step.
  TrackerEstimate Step(const StepInput& step);
  /// One WiFi observation (no-op estimate if it has no readings).
  TrackerEstimate Wifi(const WifiObservation& observation);
  /// One position fix (no-op estimate if it has no component). Before any start, or after an
  /// unknown start that no scan or fix has placed yet, the fix places the cloud (unknown start).
  /// Throws std::invalid_argument on a malformed fix (CheckPositionFix).
  TrackerEstimate Fix(const PositionFix& fix);
  /// Walkable area [m²] of each tracker floor (the plan's walkable area; without a plan,
  /// candidate points x spacing²; with neither, 1e4 m²); a fix's outlier density is ε / their sum.
  const std::vector<double>& floor_areas_m2() const;
  /// The current estimate without an update.
  TrackerEstimate Estimate() const;

  /// Current particles: N x 4 (x, y, heading offset, scale), floor indices, normalised weights.
  RowMatrixXd ParticleStates() const;
  Eigen::VectorXi ParticleFloorIndices() const;
  Eigen::VectorXd ParticleWeights() const;
  /// Replaces the particle states (N x 4) and floor indices; weights become uniform.
  void SetParticles(const Eigen::Ref<const RowMatrixXd>& states, const Eigen::Ref<const Eigen::VectorXi>& floor_indices);

  const ParticleHistory& history() const;
  const TrackerSummary& summary() const;
  const TrackerOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace indoorloc::fusion
