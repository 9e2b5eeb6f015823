// The batch API of the fusion tracker: a whole recording (steps and WiFi observations) in,
// per-step estimates and optionally the backward-smoothed track out.
//
// Events are processed in time order; a WiFi observation or fix at the same time as a step comes
// after it, and at equal times WiFi observations come before fixes. The estimate reported for step k is causal: after step k and every observation with time
// <= t_k. Unknown start: the cloud starts uniform over the walkable area and is re-drawn from
// the first observation that has readings (steps before it therefore carry little
// information: their estimates are those of a uniform cloud).
// Known start: before the start's time the walker is taken to stand at the start. Steps with
// time_s < start.time_s (a prefix: a recording usually begins before its first surveyed
// position) do not move the cloud; their estimates, filtered and smoothed, are the start
// cloud's (after any observation up to the step's time). WiFi observations and fixes before
// the start weigh the start cloud. The streaming ParticleTracker instead refuses any event
// before the previous one or the start.
#pragma once
#include <vector>
#include <Eigen/Core>

#include "indoorloc/fusion/backward_smoother.h"
#include "indoorloc/fusion/particle_tracker.h"

namespace indoorloc::fusion {

/// A whole recording.
struct Recording {
  std::vector<StepInput> steps;                ///< sorted by time
  std::vector<WifiObservation> observations;   ///< sorted by time (MakeWifiObservations)
  std::vector<PositionFix> fixes;              ///< sorted by time (position_fix.h); may be empty
};

/// Known or unknown start.
struct TrackStart {
  bool known = false;
  double time_s = 0.0;                                   ///< known start: its time [s]
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();  ///< known start position [m]
  int floor = 0;                                         ///< known start floor number
  double heading_offset_rad = 0.0;                       ///< known PDR-to-floor yaw [rad]
};

struct TrackResult {
  std::vector<TrackerEstimate> estimates;   ///< one per step
  SmoothedTrack smoothed;                   ///< empty unless smoothing was asked
  TrackerSummary summary;
};

/// Runs a ParticleTracker over `recording`; smoothing when smoother.num_trajectories > 0.
/// Throws std::invalid_argument on unsorted steps or observations (naming which).
TrackResult Track(const FloorPlan* plan, const wifi::RssModel* wifi_model,
                  const mapmatch::RoadNetwork* corridors, const Recording& recording,
                  const TrackStart& start, const TrackerOptions& options,
                  const SmootherOptions& smoother, bool smooth);

}  // namespace indoorloc::fusion
