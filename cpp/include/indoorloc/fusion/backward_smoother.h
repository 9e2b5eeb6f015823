// Full-track smoothing of the fusion tracker by forward-filter backward-simulation (FFBSi;
// Godsill, Doucet & West 2004): from the recorded filtering clouds {x_k^i, w_k^i}, draw M
// trajectories backwards, x̃_M ~ w_M, then for k = M-1 .. 0
//
//   P(x̃_k = x_k^i | x̃_{k+1}) ∝ w_k^i p(x̃_{k+1} | x_k^i),
//
// with the exact transition density of the step motion model (StepMotion::TransitionLogDensity)
// times zero when the straight step x_k^i -> x̃_{k+1} crosses a wall (or exp(wall_log_penalty))
// or changes floor (or the floor-change probability). The smoothed position at step k is the
// mean of the M trajectories; their spread gives its covariance. Cost O(M N) per step, with N
// thinned to `max_particles` by systematic resampling of the cloud when larger.
#pragma once
#include <cstdint>
#include <string>
#include <Eigen/Core>

#include "indoorloc/fusion/floor_plan.h"
#include "indoorloc/fusion/particle_tracker.h"

namespace indoorloc::fusion {

struct SmootherOptions {
  /// Number of backward trajectories M.
  int num_trajectories = 100;
  /// The backward kernel runs over at most this many particles per step.
  int max_particles = 2000;
  std::uint64_t seed = 1;
  int num_threads = 1;
  bool IsValid(std::string* error) const;
};

struct SmoothedTrack {
  RowMatrixXd positions_m;       ///< K x 2: mean of the trajectories at each recorded step
  RowMatrixXd covariances_m2;    ///< K x 3: (xx, xy, yy) over the trajectories
  Eigen::VectorXi floor_indices; ///< K: most frequent floor among the trajectories
  /// K x M x 2 flattened to K x 2M: every trajectory (x_1, y_1, x_2, y_2, ...), for plots.
  RowMatrixXd trajectories_m;
  double seconds = 0.0;
};

/// Backward simulation over `history` (recorded by a ParticleTracker with record_history).
/// `plan` may be null (no wall test). Throws std::invalid_argument on an empty history.
SmoothedTrack SmoothBackward(const ParticleHistory& history, const FloorPlan* plan,
                             const TrackerOptions& tracker_options, const SmootherOptions& options);

}  // namespace indoorloc::fusion
