// Grid filter session: the grid tracker's forward filter run live, one event at a time.
//
// When to use: a phone app (or a replay) that receives steps and position fixes as they happen
// and wants the current position after each step. GridTracker::Run needs the whole walk; a
// session holds the filter's state (per layer its grid, sub-cell remainder, pending process
// variance and log evidence) between calls, on the grids of a GridTracker built once per site
// and options (see grid_tracker.h for the model). Many sessions may share one tracker.
//
// Exactness: the session runs the same per-step code as the batch forward pass (grid_ops.h), so
// after each step its estimate equals GridTracker::Run's filtered output at that step, bit for
// bit, for the same steps and fixes, provided that
//   - fixes come in time order and a fix at time t is added before the first step with
//     time >= t (the batch applies it at that step; the session keeps it pending until then);
//   - fixes after the last step are not compared (the batch applies them to the last step);
//   - no layer is ruled out (hard walls only): the batch drops a layer that dies at step k from
//     the filtered estimates of every step, the session (causally) from step k on.
// The spatial median (options.spatial_median) is not returned by the session.
//
// Time order: events must come in non-decreasing time; a fix at exactly the last step's time
// belongs to that step (the batch's rule) and is refused once the step has been added. Every
// refusal is a std::invalid_argument naming the event and both times, and leaves the session
// unchanged.
//
// Usage (C++):
//   indoorloc::fusion::GridTracker tracker(&plan, options);        // once per site
//   indoorloc::fusion::GridFilterSession session(&tracker);         // once per walk, unknown start
//   session.AddFix(fix);                                            // WiFi fix at its time
//   GridFilterEstimate e = session.AddStep(StepFromPolar(t, 0.7, heading, 0.1, 0.17));
//   // e.mean_m, e.covariance_m2, e.floor_probabilities, e.heading_offset_rad
#pragma once
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/fusion/grid_tracker.h"
#include "indoorloc/fusion/position_fix.h"
#include "indoorloc/fusion/step_motion.h"
#include "indoorloc/fusion/track.h"

namespace indoorloc::fusion {

/// The filter's estimate after the latest step (causal: steps and fixes up to that step).
struct GridFilterEstimate {
  double time_s = 0;                       ///< time of the latest step [s]
  int steps = 0;                           ///< steps added so far
  Eigen::Vector2d mean_m = Eigen::Vector2d::Zero();               ///< posterior mean [m]
  /// (xx, xy, yy) [m²], calibrated as the batch's (GridTrackerOptions::filtered_covariance_*)
  Eigen::Vector3d covariance_m2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d posterior_covariance_m2 = Eigen::Vector3d::Zero();  ///< the posterior's own [m²]
  double fix_distance_m = 0;               ///< d of the calibration: to the latest fix's centre [m]
  double fix_sd_m = 0;                     ///< s of the calibration: the latest fix's own sd [m]
  Eigen::VectorXd floor_probabilities;     ///< per floor of the plan (F)
  double heading_offset_rad = 0;           ///< posterior circular mean of the heading offset
  double log_evidence = 0;                 ///< log p(fixes so far | steps so far), over all layers
  int fixes = 0;                           ///< fixes applied so far
  /// Whether the estimate rests on evidence of where the walker is: a known start, or at least one
  /// fix applied. Before that an unknown start's estimate is the prior's (the mean of the walkable
  /// area, a covariance the size of the floor): not a position, and an app should not show it.
  bool located = false;
};

class GridFilterSession {
 public:
  /// `tracker` must outlive the session. `start.known`: a known start (position, floor, heading
  /// offset, time) as in GridTracker::Run; steps up to its time do not move the walker and fixes
  /// before it are ignored. Throws std::invalid_argument for a null tracker, a start floor not in
  /// the plan, a non-finite start, or grids above options.max_memory_bytes.
  explicit GridFilterSession(const GridTracker* tracker, const TrackStart& start = TrackStart());
  ~GridFilterSession();
  GridFilterSession(GridFilterSession&&) noexcept;
  GridFilterSession& operator=(GridFilterSession&&) noexcept;

  /// Adds a position fix, applied at the first step with time >= fix.time_s. An empty fix (no
  /// component) is ignored. Throws std::invalid_argument for a malformed fix (CheckPositionFix)
  /// or one out of time order (before the latest fix, or not after the latest step).
  void AddFix(const PositionFix& fix);

  /// Adds a step (CheckStepInput), applies the pending fixes with time <= its time, and returns
  /// the estimate after it. Throws std::invalid_argument for a malformed step or one before the
  /// latest step or fix; std::runtime_error when every layer is ruled out (hard walls with no
  /// walkable continuation; the session then refuses further steps).
  GridFilterEstimate AddStep(const StepInput& step);

  /// The estimate after the latest step; std::logic_error before the first step.
  GridFilterEstimate Estimate() const;

  int steps() const;
  int pending_fixes() const;        ///< fixes waiting for a step at or after their time
  /// Latest event time (step or fix) [s]; -inf before the first event.
  double latest_time_s() const;
  /// What the session has done so far: steps, fixes applied, layers, dead layers, log evidence,
  /// memory of the grids, seconds spent in AddStep.
  GridTrackSummary Summary() const;
  const GridTracker& tracker() const;
  /// Floor numbers of the tracker's plan: the order of GridFilterEstimate::floor_probabilities.
  std::vector<int> floors() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace indoorloc::fusion
