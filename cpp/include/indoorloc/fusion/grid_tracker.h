// Grid tracker: the exact forward filter and forward-backward smoother of the fusion model on a
// grid of floor cells, for a walk whose start is unknown (or known).
//
// Why a grid beside the particle tracker: with an unknown start the particle filter must first
// find the walker from WiFi fixes whose components are spread over the building; a finite cloud
// re-drawn from the first fix loses the truth more often than not on a crowdsourced map
// (docs/fusion_real.md), and FFBSi then collapses to a few trajectories. On a grid nothing is
// sampled: every cell of every floor keeps its probability, so the posterior holds every mode
// until motion, walls and later fixes resolve it, and the smoother is the exact forward-backward
// recursion, whose spread is the posterior's own.
//
// State: (cell c, floor f, heading offset bin h, stride scale bin s). The offset o_h and scale
// s_s are constant over a walk (a walk lasts minutes; the white part of heading and length errors
// is in each step's covariance), so each (f, h, s) is one layer: an independent hidden Markov
// model over the cells of floor f whose steps are the PDR steps rotated by o_h and scaled by s_s.
// The layers' posterior weights are their prior times their evidence, so the mixture over layers
// is exact for this model, and the heading offset and scale posteriors come out of it.
//
// One step k of layer (f, h, s), with d_k, Σ_k the step's displacement and covariance:
//   predict:  p_k(c) = Σ_c' N(x_c - x_c'; s R(o_h) d_k, v_k I) α_{k-1}(c')
//             v_k = s² tr(Σ_k)/2 + σ_p² + (s |d_k| δ_h)² / 12     (δ_h: the offset bins' width)
//   update:   α_k(c) ∝ p_k(c) · m(c) · Π_{fixes j at k} L_j(c)^τ
//   walls:    m(c) = a(c) + (1 - a(c)) e^{λ}, a(c) the walkable fraction of the cell, λ the
//             wall log-penalty (-inf: hard walls, shops never entered); m(c) = 1 where the survey
//             walked through the cell (survey_walkable_radius_m, WithSurveyPositions)
//   fixes:    L_j(c) = ε / A + (1 - ε) Σ_k w_k N(x_c; μ_k, σ_k² I)  (position_fix.h)
// The displacement is applied exactly: each layer carries its sub-cell remainder r (|r| < one
// cell) and shifts by whole cells, so the grid adds no numerical diffusion to the motion; the
// Gaussian part is applied as a separable blur once its accumulated variance reaches a quarter
// of a cell² (and before every fix). Positions of a layer are its cell centres plus r.
//
// Timing: a fix at time t is applied at the first step with time >= t (at most one step late);
// fixes before the first step and after the last apply to the first and last step. Estimates:
// `filtered` after each step (causal: fixes up to that step); `smoothed` given the whole walk.
//
// Floors: a walk stays on one floor (no stairs or lifts are modelled); the floor posterior is
// then the layers' evidence summed per floor. Memory: the smoother keeps a layer's forward grids
// (float32) while they fit in 256 MB per thread, else about sqrt(M) checkpoints of the M steps,
// recomputing each segment once (same results either way). A run takes these buffers from a
// process-wide pool and returns them when it ends; the pool keeps at most kept_memory_limit_bytes
// idle (512 MiB) and ReleaseKeptMemory() frees them (grid_tracker.cc).
#pragma once
#include <limits>
#include <memory>
#include <string>
#include <vector>
#include <Eigen/Core>

#include "indoorloc/fusion/floor_plan.h"
#include "indoorloc/fusion/position_fix.h"
#include "indoorloc/fusion/step_motion.h"
#include "indoorloc/fusion/track.h"

namespace indoorloc::fusion {

// Defaults of λ, ε, τ and the tempering mode: the leave-one-floor-out choice on the six floors of
// the competition mall with the pooled shared-AP WiFi fixes (docs/fusion_real.md, "Settings by
// leave-one-floor-out"): τ = 1 (no tempering) was chosen for every held-out floor, λ = -1 for five
// of six; ε = 0.01 in a second round (with the PDR's heading sd, 20 deg) for five of six. The cell
// size (1 m), the offset bins (9 over ±2.5 sd) and the process noise (0.1 m; 0.3 m was worse in the
// second round) were fixed in advance (a cell well below the fixes' spread and the waypoints' 5 m
// spacing).
struct GridTrackerOptions {
  /// Side of the grid's square cells [m].
  double cell_size_m = 1.0;
  /// Walkable fraction of a cell: the fraction of walkable points among n x n sub-samples.
  int walkable_subsamples = 3;
  /// Heading-offset layers: `heading_offset_bins` centres spread evenly over the prior's
  /// ±`heading_offset_span_sd` sd around the start's offset (the whole circle when that exceeds
  /// ±π), prior weights N(o; o_start, sd²). sd <= 0 or bins == 1: the offset is known.
  int heading_offset_bins = 9;
  double heading_offset_sd_rad = 0.15;
  double heading_offset_span_sd = 2.5;
  /// Stride-scale layers: bins spread over 1 ± 2 sd with weights N(s; 1, sd²); 1 bin: s = 1.
  int scale_bins = 1;
  double scale_sd = 0.1;
  /// σ_p: isotropic process noise per step [m] (added to the step's own covariance).
  double position_noise_m = 0.1;
  /// λ: log-weight per step of a cell outside walkable space; -inf: hard walls.
  double wall_log_penalty = -1.0;
  /// Obstacles eroded by this margin [m]: a point inside an obstacle (or outside the outline)
  /// closer than this to its boundary counts as walkable. Why: surveyors and shoppers walk
  /// within a metre of shop fronts, and a path that grazes a front would otherwise pay λ at
  /// every step, which a fix bounded by ε cannot outweigh. 0: the plan as drawn.
  double wall_margin_m = 0.0;
  /// ε and τ of the position fixes (position_fix.h). ε: leave-one-floor-out over {0.01, 0.02,
  /// 0.05, 0.1, 0.3} with the PDR heading sd (docs/fusion_real.md, "Second round"): 0.01 for
  /// five of six held-out floors, the grid's lower edge (0.02 within 0.04 m).
  FixLikelihoodOptions fix{/*outlier_probability=*/0.01, /*tempering=*/1.0};
  /// How τ weakens a fix: false, the whole likelihood to the power τ (position_fix.h, as the
  /// particle tracker); true, the components' variances divided by τ with the outlier floor kept
  /// at ε / A (a tempered Gaussian is the Gaussian with variance σ² / τ), so that one fix still
  /// outweighs the uniform prior of an unknown start.
  bool fix_tempering_by_variance = false;
  /// β: where the site's survey positions are known (GridTracker::WithSurveyPositions), a fix is
  /// evaluated at q(c) = s(c) + β (c - s(c)) rather than at the cell centre c, s(c) the survey
  /// position nearest to c. Why: a fingerprint fix can only point at surveyed places, so a walker
  /// d metres from the survey is seen at its nearest surveyed neighbour; β = 1 (the plan as is)
  /// pulls every walk onto the survey, β = 0 reads the fingerprint field as constant over each
  /// survey position's Voronoi cell (nearest-neighbour extrapolation) and leaves the steps and
  /// walls to place the walker there. Cells at the survey are unchanged whatever β. Default:
  /// leave-one-floor-out over {1, 0.75, 0.5, 0.25, 0} on the six floors of the competition mall
  /// chose 0.75 for three held-out floors and 0.5 for the other three (within 0.06 m of each
  /// other on every floor); 0.75 is the all-floor choice (docs/fusion_real.md, "Survey-anchored
  /// fixes").
  double fix_survey_distance_factor = 0.75;
  /// Cells whose centre lies within this distance [m] of a survey position
  /// (GridTracker::WithSurveyPositions) pay no wall penalty, whatever the plan says there. Why:
  /// the surveyors walked there, so where the plan draws an obstacle the plan is wrong (a shop
  /// row drawn over an open area, an obstacle drawn a metre too wide), and a walk that follows
  /// the survey through it should not pay λ at every step. 0: the plan as drawn. Default: the
  /// lowest mean over the six floors of the competition mall and fold seeds 0-3 among {0, 0.75,
  /// 1, 1.25} x min walks 1 and {0.75, 1, 1.5} x min walks 2 (1: 3 walks): 0.75 m (with 1 m cells,
  /// about the cells the survey path passed through; larger radii erode the walls next to
  /// surveyed corridors like a wall margin); held out by floor it is level with 0 (docs/fusion_real.md,
  /// "Walls the survey walked through").
  double survey_walkable_radius_m = 0.75;
  /// A cell is opened only when positions of at least this many distinct survey walks lie within
  /// the radius (walk ids given to WithSurveyPositions; without them each position counts as a
  /// walk of its own). Why: a plan error is walked by every surveyor who passes there, while one
  /// walk's positions placed between waypoints can cut a corner through a wall.
  int survey_walkable_min_walks = 1;
  /// Also return the spatial median of the filtered and smoothed posteriors (the point that
  /// minimises the expected distance to the walker; robust where the posterior has a far minor
  /// mode), computed from blocks of about `median_block_m` [m] (each at its mass centroid).
  bool spatial_median = false;
  double median_block_m = 4.0;
  /// Known start: sd of the start position [m] (the offset prior is heading_offset_sd_rad).
  double start_position_sd_m = 1.0;
  /// Calibration of the returned covariances. The posterior's own spread is that of the model,
  /// which knows nothing of its own misfits (a wrong mode held with confidence, a fingerprint map
  /// that is absent where the walker is); returned is
  ///   Σ' = a Σ + (b² + (g d)² + (h max(0, s - s0))²) I,
  /// Σ the posterior covariance (also returned as is), d [m] the distance from the estimate to
  /// the centre of the fix nearest in time (filtered: the last fix applied; 0 before any fix) and
  /// s [m] that fix's own sd (the weighted mean of its components' sds; a WiFi fingerprint fix's
  /// sd grows with its best match's dissimilarity, so s is large where the scan resembles no
  /// surveyed fingerprint: there the tracker is lost more often than its posterior says, e.g. on
  /// a sparsely surveyed floor). a, b [m], g, h for the causal filter and for the smoother, the
  /// knee s0 [m] shared; a = 1, b = g = h = 0: the posterior's.
  /// Defaults: the choice on all six floors of the competition mall with its WiFi fingerprint
  /// fixes (unknown start, survey-anchored fixes), the smallest median 95 % region covering
  /// >= 95 % of the waypoints pooled and >= 90 % on each floor. Chosen per held-out floor the
  /// same way, coverage was 0.945 (filter) and 0.936 (smoother) pooled, 0.89-0.97 (filter) and
  /// 0.83-0.99 (smoother) per floor; with h = 0 (d only) 0.82-0.99 and 0.83-1.00, F4 the low one
  /// (experiments/fusion_uncertainty.py, docs/fusion_real.md, "Honest uncertainty"). g = 0 was
  /// chosen for both: with the fix-sd term the distance adds nothing. The smoother's (a 1, b 4 m,
  /// h 6) were re-chosen the same way with the site model's second smoother pass ("Locate, then
  /// track"), whose estimate they describe: held out per floor 0.86-0.99. Other fixes (BLE, UWB)
  /// or a known start want their own.
  double filtered_covariance_scale = 3.0;
  double filtered_covariance_floor_m = 4.0;
  double filtered_covariance_fix_gain = 0.0;
  double filtered_covariance_fix_sd_gain = 12.0;
  double smoothed_covariance_scale = 1.0;
  double smoothed_covariance_floor_m = 4.0;
  double smoothed_covariance_fix_gain = 0.0;
  double smoothed_covariance_fix_sd_gain = 6.0;
  double covariance_fix_sd_knee_m = 8.0;
  /// Refuse (std::invalid_argument quoting the bytes) a run whose grids would exceed this.
  double max_memory_bytes = 4e9;
  /// Layers run in parallel; results do not depend on the thread count.
  int num_threads = 1;
  bool IsValid(std::string* error) const;
};

struct GridTrackSummary {
  int steps = 0;
  int fixes = 0;            ///< fixes applied
  int layers = 0;           ///< floors x offset bins x scale bins actually run
  long long cells = 0;      ///< grid cells summed over floors
  int dead_layers = 0;      ///< layers whose every cell was ruled out (hard walls)
  /// Steps at which the smoother had no estimate in some layer of the walk's posterior: the
  /// forward and backward messages shared no cell (each flushed below 1e-30 of its scale), i.e.
  /// the walk before and after the step cannot be joined by the motion model (steps lost, a fix
  /// far off). The filtered estimate stands in there; > 0 says the smoothed track is unreliable.
  int smoother_gap_steps = 0;
  double log_evidence = 0;  ///< log p(fixes | steps), tempered fixes, over all layers
  double memory_bytes = 0;  ///< grids kept at the peak
  double seconds = 0;
  std::string BriefReport() const;
};

/// Per-step output of a run (M steps, F floors, H offset bins, S scale bins).
struct GridTrackResult {
  Eigen::VectorXd times_s;                        ///< M
  RowMatrixXd filtered_mean_m;                    ///< M x 2
  RowMatrixXd filtered_covariance_m2;             ///< M x 3 (xx, xy, yy), calibrated (options)
  RowMatrixXd filtered_posterior_covariance_m2;   ///< M x 3, the posterior's own
  Eigen::VectorXd filtered_fix_distance_m;        ///< M, d of the calibration
  Eigen::VectorXd filtered_fix_sd_m;              ///< M, s of the calibration
  RowMatrixXd filtered_floor_probabilities;       ///< M x F
  Eigen::VectorXd filtered_heading_offset_rad;    ///< M, posterior circular mean after step k
  RowMatrixXd filtered_median_m;                  ///< M x 2 spatial median (empty unless asked)
  RowMatrixXd smoothed_mean_m;                    ///< M x 2 (empty unless smoothing)
  RowMatrixXd smoothed_median_m;                  ///< M x 2 (empty unless smoothing and asked)
  RowMatrixXd smoothed_covariance_m2;             ///< M x 3, calibrated (options)
  RowMatrixXd smoothed_posterior_covariance_m2;   ///< M x 3, the posterior's own
  Eigen::VectorXd smoothed_fix_distance_m;        ///< M, d of the calibration
  Eigen::VectorXd smoothed_fix_sd_m;              ///< M, s of the calibration
  Eigen::VectorXd smoothed_floor_probabilities;   ///< F (constant over the walk)
  Eigen::VectorXd heading_offset_bins_rad;        ///< H
  Eigen::VectorXd heading_offset_probabilities;   ///< H, given the whole walk
  Eigen::VectorXd scale_bins;                     ///< S
  Eigen::VectorXd scale_probabilities;            ///< S, given the whole walk
  double heading_offset_rad = 0;                  ///< posterior circular mean given the walk
  double heading_offset_sd_rad = 0;               ///< posterior circular sd given the walk
  double scale = 1;                               ///< posterior mean given the walk
  GridTrackSummary summary;
};

/// The grid over a plan's floors (cells and their walkable fractions) and the runs on it. Build
/// once per plan and options (the walkable fractions cost one batch of point queries); Run is
/// const and thread-safe.
class GridTracker {
 public:
  /// `plan` must outlive the tracker. Throws std::invalid_argument for invalid options or a
  /// grid above max_memory_bytes.
  GridTracker(const FloorPlan* plan, const GridTrackerOptions& options);
  ~GridTracker();
  GridTracker(GridTracker&&) noexcept;
  GridTracker& operator=(GridTracker&&) noexcept;

  /// Tracks one walk. `steps` sorted by time (at least one), `fixes` sorted by time (may be
  /// empty), `start.known`: a known start (position, floor, heading offset, time). Throws
  /// std::invalid_argument naming the argument for unsorted or malformed input, a start floor
  /// not in the plan, or memory above the limit; std::runtime_error when every layer was ruled
  /// out (hard walls with no walkable continuation: use a finite wall_log_penalty).
  /// `filtered_estimates` false (with `smooth`): for a caller that reads the smoother only, the
  /// causal filter's per-step position estimates are not computed (about a quarter of a
  /// smoothing run's work with spatial medians): filtered_mean_m and its covariances are NaN from
  /// the first tracked step, filtered_median_m is empty. Everything else (smoothed estimates,
  /// floor, offset and scale posteriors, evidence, summary) is bit for bit that of a full run.
  GridTrackResult Run(const std::vector<StepInput>& steps, const std::vector<PositionFix>& fixes,
                      const TrackStart& start, bool smooth, bool filtered_estimates = true) const;

  const GridTrackerOptions& options() const;
  /// A tracker on the same grids (shared plan, options) whose fixes are evaluated at survey-
  /// anchored positions (options.fix_survey_distance_factor): `positions_m` (N x 2) [m] the
  /// survey (fingerprint reference) positions, `floor_numbers` (N) their floors (floor numbers of
  /// the plan; positions on other floors are ignored). A floor with no survey position, or β = 1,
  /// keeps the cell centres. With options.survey_walkable_radius_m > 0 the cells within that
  /// radius of a survey position also pay no wall penalty. Throws std::invalid_argument for
  /// non-finite positions or sizes that differ.
  /// `walk_ids` (N, or empty): the survey walk of each position, for survey_walkable_min_walks; a
  /// negative id marks a position that anchors fixes but opens no cell (a walk placed by the
  /// tracker rather than surveyed: where it crossed an obstacle is the tracker's choice, not
  /// evidence against the plan).
  GridTracker WithSurveyPositions(const RowMatrixXd& positions_m, const Eigen::VectorXi& floor_numbers,
                                  const Eigen::VectorXi& walk_ids = Eigen::VectorXi()) const;
  /// A tracker on the same plan and grid with other options: the same results, bit for bit, as
  /// GridTracker(plan, options) (and its WithSurveyPositions with this tracker's survey
  /// positions), without recomputing the walkable fractions (a batch of point-in-polygon queries)
  /// or the survey anchors (a nearest search per cell) unless wall_log_penalty,
  /// survey_walkable_radius_m or fix_survey_distance_factor changed. Throws std::invalid_argument
  /// for invalid options, or
  /// options whose grid differs (cell_size_m, walkable_subsamples, wall_margin_m).
  GridTracker WithOptions(const GridTrackerOptions& options) const;
  /// Frees the memory that runs keep for later runs (the smoother's stored forward grids and the
  /// layers' output slots, kept so that a batch of walks does not page-fault on fresh memory every
  /// run; at most kept_memory_limit_bytes for the whole process); buffers of runs in progress are
  /// kept until those runs end. Returns the bytes freed. Thread-safe.
  static double ReleaseKeptMemory();
  /// Bytes kept for later runs now (see ReleaseKeptMemory). Thread-safe.
  static double KeptMemoryBytes();
  /// Largest memory kept for later runs, for the whole process [bytes].
  static constexpr double kept_memory_limit_bytes = 512.0 * 1024 * 1024;
  /// Grid of a floor: origin (x, y of the first cell's corner) [m], columns, rows.
  Eigen::Vector4d GridGeometry(int floor_index) const;
  /// Walkable fraction of every cell of a floor, rows x columns (row 0 at the lowest y).
  RowMatrixXd WalkableFraction(int floor_index) const;
  /// The per-step wall factor m(c) of every cell of a floor (rows x columns, as WalkableFraction):
  /// a + (1 - a) e^λ, 1 where the survey walked through the cell (survey_walkable_radius_m).
  RowMatrixXd WallFactors(int floor_index) const;
  /// log Π_j L_j(c)^τ of the fixes on every cell of a floor (rows x columns) [nats]: the fix
  /// factor the tracker applies at a step with these fixes (grid_fix_factor.cc; survey-anchored
  /// positions, components of other floors ignored, the options' ε, τ). For other trackers on the
  /// same grid (fusion.wifi_heading_sequence), so that the fix model exists once. Throws
  /// std::invalid_argument naming the argument for a bad floor index or fix.
  RowMatrixXd FixLogLikelihood(int floor_index, const std::vector<PositionFix>& fixes) const;
  /// FixLogLikelihood of several groups of fixes at once, read at some cells: group g is
  /// fixes[group_starts(g) .. group_starts(g + 1)) (group_starts: G + 1 non-decreasing indices
  /// from 0 to fixes.size()), cell i the lattice cell cells(i) (row-major, y * nx + x). Returns
  /// (G, cells.size()) [nats]; an empty group gives 0. One call for a walk's fix ticks instead of
  /// one per tick. Throws std::invalid_argument naming "floor_index", "fixes[j]", "group_starts"
  /// or "cells".
  RowMatrixXd FixLogLikelihoodGroups(int floor_index, const std::vector<PositionFix>& fixes,
                                     const Eigen::VectorXi& group_starts, const Eigen::VectorXi& cells) const;

 private:
  friend class GridFilterSession;  // the streaming forward filter (grid_filter_session.h) runs on these grids
  GridTracker() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace indoorloc::fusion
