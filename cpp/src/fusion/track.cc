#include "indoorloc/fusion/track.h"

#include <limits>
#include <string>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"

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
  TrackerOptions tracker_options = options;
  tracker_options.record_history = smooth;
  ParticleTracker tracker(plan, wifi_model, corridors, tracker_options);
  if (wifi_model) {
    const WifiLikelihood check(*wifi_model, options.wifi);
    for (size_t k = 0; k < obs.size(); ++k) check.CheckObservation(obs[k], ("recording.observations[" + std::to_string(k) + "]").c_str());
  }
  if (start.known) {
    const double t0 = steps.empty() ? start.time_s : std::min(start.time_s, steps.front().time_s);
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
  for (const StepInput& step : steps) {
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
  if (smooth && !steps.empty()) result.smoothed = SmoothBackward(tracker.history(), plan, tracker_options, smoother);
  return result;
}

}  // namespace indoorloc::fusion
