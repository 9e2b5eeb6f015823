#include "indoorloc/fusion/track.h"

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
    tracker.InitializeUnknown(none);
  }
  TrackResult result;
  result.estimates.reserve(steps.size());
  size_t next_obs = 0;
  for (const StepInput& step : steps) {
    while (next_obs < obs.size() && obs[next_obs].time_s < step.time_s) tracker.Wifi(obs[next_obs++]);
    TrackerEstimate est = tracker.Step(step);
    while (next_obs < obs.size() && obs[next_obs].time_s <= step.time_s) est = tracker.Wifi(obs[next_obs++]);
    est.time_s = step.time_s;
    result.estimates.push_back(std::move(est));
  }
  while (next_obs < obs.size()) tracker.Wifi(obs[next_obs++]);
  result.summary = tracker.summary();
  if (smooth && !steps.empty()) result.smoothed = SmoothBackward(tracker.history(), plan, tracker_options, smoother);
  return result;
}

}  // namespace indoorloc::fusion
