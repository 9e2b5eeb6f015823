#include "indoorloc/fusion/track.h"

#include <cmath>
#include <limits>
#include <string>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::fusion {

TrackResult Track(const FloorPlan* plan, const wifi::RssModel* wifi_model, const mapmatch::RoadNetwork* corridors,
                  const Recording& recording, const TrackStart& start, const TrackerOptions& options,
                  const SmootherOptions& smoother, bool smooth) {
  ValidateOptions(options, "options");
  if (smooth) {
    ValidateOptions(smoother, "smoother");
    CheckArgument(corridors == nullptr, "smoother", "the backward smoother supports free-space mode only (no corridors)");
  }
  const auto& steps = recording.steps;
  const auto& obs = recording.observations;
  for (size_t k = 0; k < steps.size(); ++k) {
    CheckStepInput(steps[k], ("recording.steps[" + std::to_string(k) + "]").c_str());
    if (k > 0 && steps[k].time_s < steps[k - 1].time_s) {
      ThrowInvalidArgument("recording.steps", "times must be non-decreasing (step " + std::to_string(k) + " goes back in time)");
    }
  }
  for (size_t k = 1; k < obs.size(); ++k) {
    if (obs[k].time_s < obs[k - 1].time_s) {
      ThrowInvalidArgument("recording.observations",
                           "times must be non-decreasing (observation " + std::to_string(k) + " goes back in time)");
    }
  }
  const auto& fixes = recording.fixes;
  for (size_t k = 0; k < fixes.size(); ++k) {
    CheckPositionFix(fixes[k], ("recording.fixes[" + std::to_string(k) + "]").c_str());
    if (k > 0 && fixes[k].time_s < fixes[k - 1].time_s) {
      ThrowInvalidArgument("recording.fixes", "times must be non-decreasing (fix " + std::to_string(k) + " goes back in time)");
    }
  }
  CheckArgument(!obs.empty() ? wifi_model != nullptr : true, "recording.observations",
                "WiFi observations given but no signal map (wifi_model)");
  // Before a known start's time the walker is taken to stand at the start: steps before it do
  // not move the cloud (a prefix, as steps are sorted), observations and fixes before it weigh
  // the start cloud.
  size_t skipped = 0;
  if (start.known) {
    CheckArgument(std::isfinite(start.time_s), "start['time_s']", "must be finite");
    while (skipped < steps.size() && steps[skipped].time_s < start.time_s) ++skipped;
  }
  if (smooth) {
    // The recorded clouds (states, floor, log-weight: 44 B per particle and step), checked
    // before the run instead of failing to allocate in its middle.
    RequireSizeLimit(static_cast<double>(options.num_particles) * static_cast<double>(steps.size() - skipped), 44.0,
                     "options", "recorded particles (num_particles x " + std::to_string(steps.size() - skipped) +
                                    " steps, for the smoother)");
  }
  TrackerOptions tracker_options = options;
  tracker_options.record_history = smooth;
  ParticleTracker tracker(plan, wifi_model, corridors, tracker_options);
  if (wifi_model) {
    const WifiLikelihood check(*wifi_model, options.wifi);
    for (size_t k = 0; k < obs.size(); ++k) check.CheckObservation(obs[k], ("recording.observations[" + std::to_string(k) + "]").c_str());
  }
  if (start.known) {
    double t0 = start.time_s;
    if (!obs.empty()) t0 = std::min(t0, obs.front().time_s);
    if (!fixes.empty()) t0 = std::min(t0, fixes.front().time_s);
    tracker.InitializeKnown(t0, start.position_m, start.floor, start.heading_offset_rad);
  } else {
    WifiObservation none;
    none.time_s = steps.empty() ? (obs.empty() ? 0.0 : obs.front().time_s) : steps.front().time_s;
    none.time_s = obs.empty() ? none.time_s : std::min(none.time_s, obs.front().time_s);
    none.time_s = fixes.empty() ? none.time_s : std::min(none.time_s, fixes.front().time_s);
    tracker.InitializeUnknown(none);
  }
  TrackResult result;
  result.estimates.reserve(steps.size());
  size_t next_obs = 0, next_fix = 0;
  // Applies every WiFi observation and fix with time < t (strict) or <= t, in time order (WiFi
  // first at equal times); returns whether any was applied and the last estimate.
  auto apply_until = [&](double t, bool inclusive, TrackerEstimate* last) {
    auto due = [&](double u) { return inclusive ? u <= t : u < t; };
    bool any = false;
    for (;;) {
      const bool obs_due = next_obs < obs.size() && due(obs[next_obs].time_s);
      const bool fix_due = next_fix < fixes.size() && due(fixes[next_fix].time_s);
      if (!obs_due && !fix_due) return any;
      if (obs_due && (!fix_due || obs[next_obs].time_s <= fixes[next_fix].time_s)) {
        *last = tracker.Wifi(obs[next_obs++]);
      } else {
        *last = tracker.Fix(fixes[next_fix++]);
      }
      any = true;
    }
  };
  const double kInf = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < skipped; ++k) {
    TrackerEstimate est;
    apply_until(steps[k].time_s, true, &est);
    est = tracker.Estimate();
    est.time_s = steps[k].time_s;
    result.estimates.push_back(std::move(est));
  }
  for (size_t k = skipped; k < steps.size(); ++k) {
    const StepInput& step = steps[k];
    TrackerEstimate est;
    apply_until(step.time_s, false, &est);
    est = tracker.Step(step);
    apply_until(step.time_s, true, &est);
    est.time_s = step.time_s;
    result.estimates.push_back(std::move(est));
  }
  TrackerEstimate rest;
  apply_until(kInf, true, &rest);
  result.summary = tracker.summary();
  if (smooth && skipped < steps.size()) {
    result.smoothed = SmoothBackward(tracker.history(), plan, tracker_options, smoother);
  }
  if (smooth && skipped > 0) {
    // Steps before the known start: their smoothed values are the filtered ones (the start
    // cloud), every trajectory at its mean.
    SmoothedTrack& t = result.smoothed;
    const Eigen::Index before = static_cast<Eigen::Index>(skipped);
    const Eigen::Index after = static_cast<Eigen::Index>(steps.size() - skipped);
    const Eigen::Index m = smoother.num_trajectories;
    SmoothedTrack full;
    full.positions_m.resize(before + after, 2);
    full.covariances_m2.resize(before + after, 3);
    full.floor_indices.resize(before + after);
    full.trajectories_m.resize(before + after, 2 * m);
    for (Eigen::Index k = 0; k < before; ++k) {
      const TrackerEstimate& e = result.estimates[static_cast<size_t>(k)];
      full.positions_m.row(k) = e.mean_m.transpose();
      full.covariances_m2.row(k) << e.covariance_m2(0, 0), e.covariance_m2(0, 1), e.covariance_m2(1, 1);
      full.floor_indices[k] = e.floor_index;
      for (Eigen::Index j = 0; j < m; ++j) full.trajectories_m.block(k, 2 * j, 1, 2) = e.mean_m.transpose();
    }
    if (after > 0) {
      full.positions_m.bottomRows(after) = t.positions_m;
      full.covariances_m2.bottomRows(after) = t.covariances_m2;
      full.floor_indices.tail(after) = t.floor_indices;
      full.trajectories_m.bottomRows(after) = t.trajectories_m;
    }
    full.seconds = t.seconds;
    t = std::move(full);
  }
  return result;
}

}  // namespace indoorloc::fusion
