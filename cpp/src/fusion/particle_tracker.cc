// The particle tracker's public face (particle_tracker.h): options check, construction (the
// tracker's floors from the plan, the map or neither; candidate grid; floor areas), the starts,
// the event entry points (Step, Wifi, Fix) and access to the particles. The filter's parts live
// beside it by concept (map in particle_tracker_impl.h): free-space and corridor motion, seeking
// and recovery, the cloud (weights, estimate, lag ring, history).
#include "indoorloc/fusion/particle_tracker.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/core/log_weights.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "particle_tracker_impl.h"

namespace indoorloc::fusion {

namespace {
using tracker_detail::kMaxCoordinate;
using tracker_detail::kNegInf;
using tracker_detail::WrapAngle;

// Memory of the particle state, checked before it is allocated: per particle six doubles of
// state, the floor, log-weight, linear weight, ancestor and the temporaries of an update and of
// resampling (96 B; corridor mode 16 B more), and the fixed-lag ring of (lag + 1) positions with
// its copy at resampling (32 B per slot).
void RequireParticleMemory(double num_particles, const TrackerOptions& options, bool corridor_mode,
                           std::string_view name) {
  const double lag = options.smoothing_lag_steps;
  const double per_particle = 96.0 + (corridor_mode ? 16.0 : 0.0) + FixedLagRing::BytesPerParticle(static_cast<int>(lag));
  RequireSizeLimit(num_particles, per_particle, name,
                   "particles (with smoothing_lag_steps = " + std::to_string(options.smoothing_lag_steps) + ")");
}
}  // namespace

bool TrackerOptions::IsValid(std::string* error) const {
  // Nested options are reported by the flattened names of the Python TrackerOptions (the motion,
  // WiFi and resampling fields keep their names; the fix fields carry a "fix_" prefix).
  auto nested = [&](bool ok, const std::string& prefix, const std::string& sub) {
    if (!ok && error) *error = prefix + sub;
    return ok;
  };
  Validator v(error);
  v.IntInRange(num_particles, 1, 50000000, "num_particles");
  if (!v) return false;
  std::string sub;
  if (!nested(motion.IsValid(&sub), "", sub)) return false;
  if (!nested(wifi.IsValid(&sub), "", sub)) return false;
  if (!nested(fix.IsValid(&sub), "fix_", sub)) return false;
  if (!nested(resampling.IsValid(&sub), "", sub)) return false;
  const double inf = std::numeric_limits<double>::infinity();
  return v
      .Check(wall_log_penalty <= 0.0, "wall_log_penalty",
             "must be <= 0 (-inf drops the particle), got " + FormatValue(wall_log_penalty))
      .IntInRange(respread_after_blocked_steps, 1, 1000000, "respread_after_blocked_steps")
      .Scale(respread_sd_m, "respread_sd_m")
      .ZeroOrScale(start_position_sd_m, "start_position_sd_m")
      .InRange(start_heading_offset_sd_rad, 0.0, 1e3, "start_heading_offset_sd_rad")
      .InRange(start_scale_sd, 0.0, 100.0, "start_scale_sd")
      .Check(unknown_start_heading_sd_rad >= 0.0 && (unknown_start_heading_sd_rad <= 1e3 ||
                                                     unknown_start_heading_sd_rad == inf),
             "unknown_start_heading_sd_rad",
             "must be in [0, 1000] or +inf (uniform on the circle), got " + FormatValue(unknown_start_heading_sd_rad))
      .InRange(candidate_spacing_m, 0.05, 1000.0, "candidate_spacing_m")
      .InRange(recovery_log_ratio, -1e6, 1e6, "recovery_log_ratio")
      .IntInRange(recovery_scans, 1, 1000000, "recovery_scans")
      .Check(recovery_fraction > 0.0 && recovery_fraction <= 1.0, "recovery_fraction",
             "must be in (0, 1], got " + FormatValue(recovery_fraction))
      .InRange(floor_change_probability, 0.0, 1.0, "floor_change_probability")
      .InRange(corridor_kappa, 0.0, mapmatch::kMaxCorridorKappa, "corridor_kappa")
      .IntInRange(smoothing_lag_steps, 0, 10000, "smoothing_lag_steps")
      .IntInRange(num_threads, 0, 1024, "num_threads");
}

std::string TrackerSummary::BriefReport() const {
  std::ostringstream out;
  out << steps << " steps, " << wifi_updates << " WiFi updates (" << empty_wifi_updates << " empty), " << fix_updates
      << " fixes, " << resamplings
      << " resamplings, " << recoveries << " recoveries, " << all_blocked_steps << " all-blocked steps, " << respreads
      << " re-spreads, mean ESS " << std::round(mean_ess * 10.0) / 10.0 << ", log-lik " << total_log_likelihood
      << ", " << seconds << " s";
  return out.str();
}

// Every event (step, WiFi observation, fix) at or after the previous one (or the start).
void ParticleTracker::Impl::CheckTime(double time_s, const char* name) const {
  if (time_s < last_time) {
    ThrowInvalidArgument(name, FormatValue(time_s) + " s is before the previous event or the start (" +
                                   FormatValue(last_time) + " s): negative time step (events must not go back in time)");
  }
}

ParticleTracker::ParticleTracker(const FloorPlan* plan, const wifi::RssModel* wifi_model,
                                 const mapmatch::RoadNetwork* corridors, const TrackerOptions& options)
    : impl_(std::make_unique<Impl>()) {
  ValidateOptions(options, "options");
  Impl& s = *impl_;
  s.plan = plan;
  s.model = wifi_model;
  s.corridors = corridors;
  s.options = options;
  s.rng = RandomStream(options.seed, tracker_detail::kTrackerStream);
  if (plan) {
    s.floors = plan->floors();
  } else if (wifi_model) {
    s.floors = wifi_model->floors();
  } else {
    s.floors = {0};
  }
  s.plan_floor.assign(s.floors.size(), -1);
  s.model_floor.assign(s.floors.size(), -1);
  for (size_t f = 0; f < s.floors.size(); ++f) {
    if (plan) s.plan_floor[f] = static_cast<int>(f);
    if (wifi_model) {
      const auto& mf = wifi_model->floors();
      const auto it = std::find(mf.begin(), mf.end(), s.floors[f]);
      if (it == mf.end()) {
        ThrowInvalidArgument("wifi_model", "the signal map has no reference point on floor " + std::to_string(s.floors[f]) +
                                               " of the floor plan (the map's floors must be the plan's floors)");
      }
      s.model_floor[f] = static_cast<int>(it - mf.begin());
    }
  }
  if (plan && wifi_model) {
    for (int mf : wifi_model->floors()) {
      if (std::find(s.floors.begin(), s.floors.end(), mf) == s.floors.end()) {
        ThrowInvalidArgument("wifi_model", "the signal map has floor " + std::to_string(mf) +
                                               ", which the floor plan does not have");
      }
    }
  }
  if (corridors) {
    CheckArgument(s.floors.size() == 1, "corridors", "corridor mode supports one floor only (the plan or map has " +
                                                         std::to_string(s.floors.size()) + ")");
    CheckArgument(corridors->num_segments() > 0 && corridors->total_length_m() > 0.0, "corridors", "is empty");
    mapmatch::CorridorMotionOptions corridor_options;
    corridor_options.kappa = options.corridor_kappa;
    s.corridor_motion = std::make_unique<mapmatch::CorridorMotion>(*corridors, corridor_options);
  }
  if (wifi_model) s.wifi = std::make_unique<WifiLikelihood>(*wifi_model, options.wifi);
  if (plan || wifi_model) s.BuildCandidates();
  s.floor_area.assign(s.floors.size(), 1e4);
  for (size_t f = 0; f < s.floors.size(); ++f) {
    if (plan) {
      s.floor_area[f] = plan->WalkableArea(s.plan_floor[f]);
    } else if (wifi_model && s.candidates[f].rows() > 0) {
      s.floor_area[f] = static_cast<double>(s.candidates[f].rows()) * options.candidate_spacing_m * options.candidate_spacing_m;
    }
  }
  for (double a : s.floor_area) s.total_area += a;
  RequireParticleMemory(options.num_particles, options, corridors != nullptr, "options");
  s.Resize(options.num_particles);
}

ParticleTracker::~ParticleTracker() = default;
ParticleTracker::ParticleTracker(ParticleTracker&&) noexcept = default;
ParticleTracker& ParticleTracker::operator=(ParticleTracker&&) noexcept = default;

const std::vector<int>& ParticleTracker::floors() const { return impl_->floors; }
bool ParticleTracker::initialized() const { return impl_->initialized; }
const ParticleHistory& ParticleTracker::history() const { return impl_->history; }
const TrackerSummary& ParticleTracker::summary() const { return impl_->summary; }
const TrackerOptions& ParticleTracker::options() const { return impl_->options; }

void ParticleTracker::InitializeKnown(double time_s, const Eigen::Vector2d& position_m, int floor_number,
                                      double heading_offset_rad) {
  Impl& s = *impl_;
  CheckArgument(std::isfinite(time_s), "time_s", "must be finite");
  CheckFinite(position_m, "position_m");
  CheckArgument(std::isfinite(heading_offset_rad), "heading_offset_rad", "must be finite");
  const auto it = std::find(s.floors.begin(), s.floors.end(), floor_number);
  if (it == s.floors.end()) ThrowInvalidArgument("floor", "the tracker has no floor " + std::to_string(floor_number));
  const int f = static_cast<int>(it - s.floors.begin());
  // With soft walls (a finite wall_log_penalty) obstacles are only unlikely, not forbidden: a start
  // inside one (a shop without a door in the plan) is accepted and the prior is not truncated.
  const bool hard_walls = std::isinf(s.options.wall_log_penalty);
  if (hard_walls && !s.Walkable(position_m.x(), position_m.y(), f)) {
    ThrowInvalidArgument("position_m", "(" + std::to_string(position_m.x()) + ", " + std::to_string(position_m.y()) +
                                           ") is not walkable on floor " + std::to_string(floor_number) +
                                           " (outside the outline or inside an obstacle)");
  }
  const TrackerOptions& o = s.options;
  for (int i = 0; i < s.n; ++i) {
    double px = position_m.x(), py = position_m.y();
    for (int attempt = 0; attempt < 50 && o.start_position_sd_m > 0.0; ++attempt) {
      const double qx = position_m.x() + o.start_position_sd_m * s.rng.Normal();
      const double qy = position_m.y() + o.start_position_sd_m * s.rng.Normal();
      // Behind a wall from the known start is not a possible start.
      if (!hard_walls || (s.Walkable(qx, qy, f) && !s.Blocked(position_m.x(), position_m.y(), qx, qy, f))) {
        px = qx;
        py = qy;
        break;
      }
    }
    s.PlaceFree(i, px, py, f, heading_offset_rad + o.start_heading_offset_sd_rad * s.rng.Normal());
  }
  s.log_w.setConstant(-std::log(static_cast<double>(s.n)));
  s.initialized = true;
  s.awaiting_first_fix = false;
  s.last_time = time_s;
}

void ParticleTracker::InitializeUnknown(const WifiObservation& observation) {
  Impl& s = *impl_;
  CheckArgument(s.plan || s.model || s.corridors, "plan", "an unknown start needs a floor plan, a signal map or corridors");
  if (s.model) s.wifi->CheckObservation(observation, "observation");
  if (observation.empty() || !s.model) {
    s.UniformCloud();
    // The first scan with readings, or the first fix, places the cloud.
    s.awaiting_first_fix = true;
  } else {
    std::vector<int> all(static_cast<size_t>(s.n));
    for (int i = 0; i < s.n; ++i) all[i] = i;
    s.DrawFromCandidates(s.WifiPointLL(observation), all);
    s.log_w.setConstant(-std::log(static_cast<double>(s.n)));
    s.awaiting_first_fix = false;
  }
  s.initialized = true;
  s.last_time = observation.time_s;
}

TrackerEstimate ParticleTracker::Step(const StepInput& step) {
  Impl& s = *impl_;
  WallTimer timer;
  CheckArgument(s.initialized, "step", "the tracker is not initialised (InitializeKnown or InitializeUnknown first)");
  CheckStepInput(step, "step");
  s.CheckTime(step.time_s, "step.time_s");
  s.last_time = step.time_s;
  const StepMotion motion(step, s.options.motion);
  const Eigen::VectorXd old_log_w = s.log_w;  // normalised (the invariant between events)
  const int blocks = (s.n + kBlockSize - 1) / kBlockSize;
  std::vector<double> blocked_mass(static_cast<size_t>(blocks), 0.0);
  if (s.corridor_mode()) {
    s.MoveAlongCorridors(motion);
  } else {
    s.MoveFreeSpace(motion, &blocked_mass);
  }

  ++s.summary.steps;
  TrackerEstimate est;
  est.time_s = step.time_s;
  double blocked_total = 0.0;
  for (double m : blocked_mass) blocked_total += m;
  est.blocked_fraction = std::min(1.0, blocked_total);
  const double max_log_w = s.log_w.maxCoeff();
  if (!(max_log_w > kNegInf)) {
    // Every particle blocked: the step contradicts the plan (an unmapped door, a wrong heading
    // offset). Ignore it rather than lose the cloud (a dropped particle stayed where it was);
    // re-spread if it keeps happening.
    s.log_w = old_log_w;
    ++s.summary.all_blocked_steps;
    if (++s.consecutive_blocked >= s.options.respread_after_blocked_steps) {
      s.Respread();
      s.consecutive_blocked = 0;
    }
    est.ess = EffectiveSampleSize(s.log_w);
    est.log_likelihood = 0.0;
    s.PushLag();
    s.FillEstimate(&est);
  } else {
    s.consecutive_blocked = 0;
    s.PushLag();
    // log-likelihood increment: log Σ w_old,i · (wall factor), the old weights normalised.
    est.log_likelihood = s.FinishUpdate(max_log_w, &est);
    s.summary.total_log_likelihood += est.log_likelihood;
  }
  if (s.options.record_history) {
    s.history.times_s.push_back(step.time_s);
    s.history.steps.push_back(step);
    s.Snapshot(false);
  }
  s.summary.seconds += timer.ElapsedSeconds();
  return est;
}

TrackerEstimate ParticleTracker::Wifi(const WifiObservation& observation) {
  Impl& s = *impl_;
  WallTimer timer;
  CheckArgument(s.model != nullptr, "observation", "the tracker has no signal map (wifi_model is None)");
  s.wifi->CheckObservation(observation, "observation");
  if (!s.initialized) {
    InitializeUnknown(observation);
    TrackerEstimate est = Estimate();
    est.time_s = observation.time_s;
    return est;
  }
  // Events go forward in time, whatever their kind (a reading re-timed to its own time is
  // placed in time order by MakeWifiObservations and Track).
  s.CheckTime(observation.time_s, "observation.time_s");
  s.last_time = observation.time_s;
  if (observation.empty()) {
    TrackerEstimate est;
    est.time_s = observation.time_s;
    ++s.summary.empty_wifi_updates;
    s.FillEstimate(&est);
    est.ess = EffectiveSampleSize(s.log_w);
    return est;
  }
  ++s.summary.wifi_updates;
  TrackerEstimate est = s.Observe(observation.time_s, observation.num_heard > 0, s.WifiPointLL(observation));
  s.summary.seconds += timer.ElapsedSeconds();
  return est;
}

TrackerEstimate ParticleTracker::Fix(const PositionFix& fix) {
  Impl& s = *impl_;
  WallTimer timer;
  CheckPositionFix(fix, "fix");
  if (s.initialized) {
    s.CheckTime(fix.time_s, "fix.time_s");
    s.last_time = fix.time_s;
  } else {
    CheckArgument(s.plan || s.model || s.corridors, "fix", "an unknown start needs a floor plan, a signal map or corridors");
    s.UniformCloud();
    s.initialized = true;
    s.awaiting_first_fix = true;
    s.last_time = fix.time_s;
  }

  if (fix.empty()) {
    TrackerEstimate est;
    est.time_s = fix.time_s;
    s.FillEstimate(&est);
    est.ess = EffectiveSampleSize(s.log_w);
    return est;
  }
  ++s.summary.fix_updates;
  const FixLikelihood likelihood(fix, s.options.fix);
  TrackerEstimate est = s.Observe(fix.time_s, true, [&](double px, double py, int f) {
    return likelihood.LogLikelihood(px, py, s.floors[f], s.total_area);
  });
  s.summary.seconds += timer.ElapsedSeconds();
  return est;
}

const std::vector<double>& ParticleTracker::floor_areas_m2() const { return impl_->floor_area; }

TrackerEstimate ParticleTracker::Estimate() const {
  if (!impl_->initialized) {
    throw std::runtime_error(
        "indoorloc: ParticleTracker.estimate: the tracker is not initialised (no start, step, scan, fix or "
        "set_particles yet)");
  }
  TrackerEstimate est;
  est.time_s = impl_->last_time;
  impl_->FillEstimate(&est);
  est.ess = EffectiveSampleSize(impl_->log_w);
  return est;
}

RowMatrixXd ParticleTracker::ParticleStates() const {
  const Impl& s = *impl_;
  RowMatrixXd out(s.n, 4);
  for (int i = 0; i < s.n; ++i) out.row(i) << s.x[i], s.y[i], s.offset[i], s.scale[i];
  return out;
}

Eigen::VectorXi ParticleTracker::ParticleFloorIndices() const {
  return Eigen::Map<const Eigen::VectorXi>(impl_->floor.data(), impl_->n);
}

Eigen::VectorXd ParticleTracker::ParticleWeights() const { return NormalizedWeights(impl_->log_w); }

void ParticleTracker::SetParticles(const Eigen::Ref<const RowMatrixXd>& states,
                                   const Eigen::Ref<const Eigen::VectorXi>& floor_indices) {
  Impl& s = *impl_;
  CheckShape(states, -1, 4, "states");
  CheckArgument(states.rows() > 0, "states", "has no particle");
  CheckShape(floor_indices, states.rows(), 1, "floor_indices");
  CheckFinite(states, "states");
  CheckArgument(!s.corridor_mode(), "states", "SetParticles is not available in corridor mode");
  const int num_floors = static_cast<int>(s.floors.size());
  for (Eigen::Index i = 0; i < states.rows(); ++i) {
    const int f = floor_indices[i];
    if (f < 0 || f >= num_floors) {
      ThrowInvalidArgument("floor_indices", "entry " + std::to_string(i) + " = " + std::to_string(f) +
                                                " is not a floor index (0.." + std::to_string(num_floors - 1) + ")");
    }
    for (int c = 0; c < 2; ++c) {
      if (!(std::abs(states(i, c)) <= kMaxCoordinate)) {
        ThrowInvalidArgument("states", DescribeEntry(i, c, false) + std::string(c == 0 ? " (x" : " (y") +
                                           ") must be in [-1e+07, 1e+07] m, got " + FormatValue(states(i, c)));
      }
    }
    if (!(std::abs(states(i, 2)) <= 1e6)) {
      ThrowInvalidArgument("states", DescribeEntry(i, 2, false) + " (heading offset) must be in [-1e+06, 1e+06] rad, got " +
                                         FormatValue(states(i, 2)));
    }
    const double lo = s.options.motion.min_scale, hi = s.options.motion.max_scale;
    if (!(states(i, 3) >= lo && states(i, 3) <= hi)) {
      ThrowInvalidArgument("states", DescribeEntry(i, 3, false) + " (scale) must be in [min_scale, max_scale] = [" +
                                         FormatValue(lo) + ", " + FormatValue(hi) + "], got " + FormatValue(states(i, 3)));
    }
    // With hard walls no particle may stand outside walkable space (the filter's invariant: a
    // step never ends inside an obstacle); with soft walls it is only unlikely.
    if (s.plan && std::isinf(s.options.wall_log_penalty) &&
        !s.plan->IsWalkable(states(i, 0), states(i, 1), s.plan_floor[static_cast<size_t>(f)])) {
      ThrowInvalidArgument("states", "row " + std::to_string(i) + ": (" + FormatValue(states(i, 0)) + ", " +
                                         FormatValue(states(i, 1)) + ") is not walkable on floor " +
                                         std::to_string(s.floors[static_cast<size_t>(f)]) +
                                         " (hard walls: wall_log_penalty = -inf)");
    }
  }
  RequireParticleMemory(static_cast<double>(states.rows()), s.options, false, "states");
  s.options.num_particles = static_cast<int>(states.rows());
  s.Resize(static_cast<int>(states.rows()));
  for (int i = 0; i < s.n; ++i) {
    s.x[i] = states(i, 0);
    s.y[i] = states(i, 1);
    s.offset[i] = WrapAngle(states(i, 2));
    s.cos_offset[i] = std::cos(s.offset[i]);
    s.sin_offset[i] = std::sin(s.offset[i]);
    s.scale[i] = states(i, 3);
    s.floor[i] = floor_indices[i];
  }
  s.initialized = true;
  s.awaiting_first_fix = false;
}

}  // namespace indoorloc::fusion
