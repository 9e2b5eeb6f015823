// Live session (live_session.h): the event loop around the step detector, the fingerprint fixer
// and the grid filter session.
#include "indoorloc/fusion/live_session.h"

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/fusion/step_motion.h"

namespace indoorloc::fusion {
namespace {

// A time as Python prints a float (shortest round trip, "5.0" not "5"): the messages read the
// same from C++ and from the Python wrapper.
std::string FormatTime(double t) {
  if (!std::isfinite(t)) return std::isnan(t) ? "nan" : (t > 0 ? "inf" : "-inf");
  char buf[40];
  for (int p = 1; p <= 17; ++p) {
    std::snprintf(buf, sizeof buf, "%.*g", p, t);
    if (std::strtod(buf, nullptr) == t) break;
  }
  std::string s(buf);
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

const char* const kKinds[] = {"accelerometer", "gyroscope", "rotation_vector", "wifi", "beacon"};
enum Kind { kAccelerometer, kGyroscope, kRotationVector, kWifi, kBeacon };

struct PendingFix {
  double time_s;
  double described_s;
  ScanQuery query;
  std::optional<PositionFix> fix;  // matched at the scan, or (delay compensation) at its step
};

}  // namespace

bool LiveSessionOptions::IsValid(std::string* error) const {
  std::string detector_error;
  const bool detector_ok = detector.IsValid(&detector_error);
  return Validator(error)
      .Check(detector_ok, "detector", detector_error)
      .Check(step_length_k > 0 && step_length_k < 100, "step_length_k",
             "must be finite and in (0, 100), got " + FormatValue(step_length_k))
      .Finite(yaw_offset_rad, "yaw_offset_rad")
      .Check(step_length_sd_fraction > 0 && step_length_sd_fraction <= 10, "step_length_sd_fraction",
             "must be finite and in (0, 10], got " + FormatValue(step_length_sd_fraction))
      .Check(step_heading_sd_rad > 0 && step_heading_sd_rad <= 1e3, "step_heading_sd_rad",
             "must be finite and in (0, 1000], got " + FormatValue(step_heading_sd_rad))
      .Check(standing_after_s == 0.0 || (standing_after_s > detector.min_step_interval_s && standing_after_s <= 3600.0),
             "standing_after_s",
             "must be 0 (off) or above detector.min_step_interval_s = " + FormatValue(detector.min_step_interval_s) +
                 " s (the detector's latency) and at most 3600 s, got " + FormatValue(standing_after_s));
}

struct LiveSession::State {
  LiveSessionOptions options;
  GridFilterSession filter;
  pdr::StreamingStepDetector detector;
  std::unique_ptr<FingerprintFixer> fixer;
  std::optional<Eigen::Vector3d> gyro;
  std::optional<Eigen::Vector4d> quat;
  std::deque<PendingFix> fixes;          // waiting for a step at or after their time
  std::deque<double> step_t;             // recent steps (delay compensation): times [s] ...
  std::deque<Eigen::Vector2d> step_d;    // ... and displacements [m]
  GridFilterEstimate estimate;
  bool has_estimate = false;
  double last_step_t = -std::numeric_limits<double>::infinity();  // the filter's latest step
  LiveSessionSummary summary;
  double last_t = -std::numeric_limits<double>::infinity();
  int last_kind = -1;
  std::vector<pdr::StreamingStep> confirmed;  // reused buffer

  State(const GridTracker* tracker, const LiveSessionOptions& o, const TrackStart& start)
      : options(o), filter(tracker, start), detector(o.detector) {}

  // Checks an event's time (finite, not before the latest event's) before anything changes.
  void CheckTime(int kind, double t) const {
    const std::string who = "indoorloc: live session: event " + std::to_string(summary.events) + " (" + kKinds[kind];
    if (!std::isfinite(t)) throw std::invalid_argument(who + "): time must be finite, got " + FormatTime(t));
    if (t < last_t) {
      throw std::invalid_argument(who + " at t = " + FormatTime(t) + " s) is out of time order: before event " +
                                  std::to_string(summary.events - 1) + " (" + kKinds[last_kind] + " at t = " +
                                  FormatTime(last_t) + " s)");
    }
  }
  void Accept(int kind, double t) {
    ++summary.events;
    last_t = t;
    last_kind = kind;
  }
  PositionFix MakeFix(const PendingFix& p) const {
    Eigen::Vector2d shift = Eigen::Vector2d::Zero();
    if (options.delay_compensation && !step_t.empty()) {
      // The PDR displacement from the time the fix describes to the latest step: the steps j
      // with described < t_j (python live._delay_shift).
      std::size_t lo = 0;
      while (lo < step_t.size() && !(step_t[lo] > p.described_s)) ++lo;
      if (lo < step_t.size()) {
        shift = step_d[lo];
        for (std::size_t j = lo + 1; j < step_d.size(); ++j) shift = shift + step_d[j];
      }
    }
    return fixer->Fix(p.query, p.time_s, shift);
  }
  void AddStep(const pdr::StreamingStep& s);
  void ApplyFixesUpTo(double time_s);
  void ApplyStanding(double now_s);
};

// The pending fixes with time <= time_s, in order, before the filter's step at time_s.
void LiveSession::State::ApplyFixesUpTo(double time_s) {
  while (!fixes.empty() && fixes.front().time_s <= time_s) {
    const PendingFix p = std::move(fixes.front());
    fixes.pop_front();
    filter.AddFix(p.fix ? *p.fix : MakeFix(p));
    ++summary.fixes;
  }
}

// Called at each event before it is processed (an accelerometer sample confirming a step at
// now_s comes after the standing steps due by now_s; python live.causal_inputs does the same).
void LiveSession::State::ApplyStanding(double now_s) {
  const double wait = options.standing_after_s;
  if (!(wait > 0)) return;
  while (!fixes.empty() && fixes.front().time_s + wait <= now_s) {
    StepInput standing;
    standing.time_s = std::max(fixes.front().time_s, last_step_t);
    standing.displacement_m.setZero();
    standing.covariance_m2.setZero();
    ApplyFixesUpTo(standing.time_s);
    estimate = filter.AddStep(standing);
    last_step_t = standing.time_s;
    has_estimate = true;
    ++summary.standing_steps;
  }
}

void LiveSession::State::AddStep(const pdr::StreamingStep& s) {
  const LiveSessionOptions& o = options;
  const double heading = o.heading_source == StepHeadingSource::kGyro            ? s.heading_gyro_rad
                         : o.heading_source == StepHeadingSource::kComplementary ? s.heading_complementary_rad
                                                                                 : s.heading_rotation_vector_rad;
  const double length = o.step_length_k * s.feature;
  StepInput step = StepFromPolar(s.time_s, length, heading + o.yaw_offset_rad, o.step_length_sd_fraction * length,
                                 o.step_heading_sd_rad);
  step.covariance_m2(1, 0) = step.covariance_m2(0, 1);  // as the (xx, xy, yy) rows of the batch
  if (step.time_s < last_step_t) {  // confirmed after a standing step later than its peak
    step.time_s = last_step_t;
    ++summary.late_steps;
  }
  step_t.push_back(step.time_s);
  step_d.push_back(step.displacement_m);
  ApplyFixesUpTo(step.time_s);
  // Keep the steps a later fix can still reach back to (a scan describes at most its window).
  double cutoff = step.time_s;
  if (fixer) {
    cutoff = last_t - fixer->options().query_window_s;
    for (const PendingFix& p : fixes) cutoff = std::min(cutoff, p.described_s);
  }
  while (step_t.size() > 1 && step_t.front() < cutoff - 1.0) {
    step_t.pop_front();
    step_d.pop_front();
  }
  estimate = filter.AddStep(step);
  last_step_t = step.time_s;
  has_estimate = true;
  ++summary.steps;
}

LiveSession::LiveSession(const GridTracker* tracker, const FingerprintMap* map, const LiveSessionOptions& options,
                         const FingerprintFixOptions& fix_options, const TrackStart& start) {
  if (tracker == nullptr) ThrowInvalidArgument("tracker", "must not be null");
  std::string error;
  if (!options.IsValid(&error)) ThrowInvalidArgument("options", error);
  state_ = std::make_unique<State>(tracker, options, start);
  if (map != nullptr) state_->fixer = std::make_unique<FingerprintFixer>(*map, fix_options);
}

LiveSession::~LiveSession() = default;
LiveSession::LiveSession(LiveSession&&) noexcept = default;
LiveSession& LiveSession::operator=(LiveSession&&) noexcept = default;

bool LiveSession::AddAccelerometer(double time_s, const Eigen::Vector3d& acc_mps2) {
  State& s = *state_;
  CheckArgument(acc_mps2.allFinite(), "acc_mps2", "expected 3 finite values");
  s.CheckTime(kAccelerometer, time_s);
  const bool to_detector = s.gyro && s.quat;
  if (to_detector && !(time_s > s.detector.latest_time_s())) {
    throw std::invalid_argument("indoorloc: live session: event " + std::to_string(s.summary.events) +
                                " (accelerometer at t = " + FormatTime(time_s) +
                                " s): not after the previous accelerometer sample (t = " +
                                FormatTime(s.detector.latest_time_s()) + " s)");
  }
  s.Accept(kAccelerometer, time_s);
  s.ApplyStanding(time_s);
  if (to_detector) {
    s.confirmed.clear();
    s.detector.AddSample(time_s, acc_mps2, *s.gyro, *s.quat, &s.confirmed);
    ++s.summary.imu_samples;
    for (const pdr::StreamingStep& step : s.confirmed) s.AddStep(step);
  }
  return s.has_estimate;
}

bool LiveSession::AddGyroscope(double time_s, const Eigen::Vector3d& gyro_radps) {
  State& s = *state_;
  CheckArgument(gyro_radps.allFinite(), "gyro_radps", "expected 3 finite values");
  s.CheckTime(kGyroscope, time_s);
  s.Accept(kGyroscope, time_s);
  s.ApplyStanding(time_s);
  s.gyro = gyro_radps;
  return s.has_estimate;
}

bool LiveSession::AddRotationVector(double time_s, const Eigen::Ref<const Eigen::VectorXd>& values) {
  State& s = *state_;
  CheckArgument(values.size() >= 3 && values.size() <= 5 && values.head(3).allFinite(), "values",
                "expected 3 to 5 rotation-vector values, the first 3 finite");
  const Eigen::Vector4d q = pdr::QuaternionFromRotationVector(values.head(std::min<Eigen::Index>(values.size(), 4)));
  s.CheckTime(kRotationVector, time_s);
  s.Accept(kRotationVector, time_s);
  s.ApplyStanding(time_s);
  s.quat = q;
  return s.has_estimate;
}

bool LiveSession::AddWifiScan(double time_s, const std::vector<std::string>& bssids,
                              const Eigen::Ref<const Eigen::VectorXd>& rssi_dbm,
                              const Eigen::Ref<const Eigen::VectorXd>& last_seen_s) {
  State& s = *state_;
  s.CheckTime(kWifi, time_s);
  FingerprintFixer::CheckScan(time_s, bssids, rssi_dbm, last_seen_s);  // before the scan is accepted
  s.Accept(kWifi, time_s);
  s.ApplyStanding(time_s);
  ++s.summary.scans;
  if (!s.fixer) return s.has_estimate;
  PendingFix p{time_s, 0.0, ScanQuery(), std::nullopt};
  const bool got = s.fixer->AddScan(time_s, bssids, rssi_dbm, last_seen_s, &p.query);
  // A second scan at the same time: its pooled query replaces the first's.
  if (!s.fixes.empty() && s.fixes.back().time_s == time_s) s.fixes.pop_back();
  if (got) {
    p.described_s = p.query.described_time_s;
    if (!s.options.delay_compensation) {  // matched now; the query is then no longer needed
      p.fix = s.fixer->Fix(p.query, time_s);
      p.query.rss_dbm.resize(0);
    }
    s.fixes.push_back(std::move(p));
  }
  return s.has_estimate;
}

bool LiveSession::AddBeacon(double time_s) {
  State& s = *state_;
  s.CheckTime(kBeacon, time_s);
  s.Accept(kBeacon, time_s);
  s.ApplyStanding(time_s);
  return s.has_estimate;
}

bool LiveSession::HasEstimate() const { return state_->has_estimate; }

const GridFilterEstimate& LiveSession::Estimate() const {
  if (!state_->has_estimate) throw std::logic_error("indoorloc: LiveSession::Estimate: no step (detected or standing) yet");
  return state_->estimate;
}

LiveSessionSummary LiveSession::Summary() const {
  LiveSessionSummary out = state_->summary;
  out.pending_fixes = static_cast<int>(state_->fixes.size());
  out.unknown_wifi_readings = state_->fixer ? state_->fixer->unknown_readings() : 0;
  return out;
}

const GridFilterSession& LiveSession::filter() const { return state_->filter; }
const LiveSessionOptions& LiveSession::options() const { return state_->options; }
std::vector<int> LiveSession::floors() const { return state_->filter.floors(); }

}  // namespace indoorloc::fusion
