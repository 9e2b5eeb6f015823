// Live session: raw phone sensor events in time order (accelerometer, gyroscope, rotation vector,
// WiFi scans with last-seen times, beacons) in, the grid filter's current estimate out after each.
//
// When to use: a phone app, or the replay of a recorded walk, on a surveyed floor (a site file:
// fusion/site_file.h gives the plan, the PDR calibration, the fingerprint map and the tracker's
// options). Python's indoorloc.fusion.live.LiveTracker is this class (docs/fusion.md, "Live tracking").
//
// What happens to each event:
//  - gyroscope, rotation vector: held at their latest sample (send them first at equal times);
//  - accelerometer: with the held gyroscope and rotation quaternion, one sample of the causal step
//    detector (pdr/streaming_step_detector.h); a confirmed step (min_step_interval_s after its
//    peak) becomes a polar step: length K x feature, heading (of heading_source) + yaw offset, sds
//    step_length_sd_fraction x length and step_heading_sd_rad (StepFromPolar), and goes to the
//    grid filter session (fusion/grid_filter_session.h) after the fixes it must see first;
//  - WiFi scan: pooled and matched into a fix timed at the scan (fusion/fingerprint_fixes.h),
//    applied at the first step at or after its time; a second scan at the same time replaces the
//    first's fix. A walker who stands still takes no step: a fix still waiting when an event
//    comes standing_after_s or more after its time is applied at a standing step (no
//    displacement) at its own time, so a standing user is located and followed by WiFi alone.
//    delay_compensation (off: it did not help on the shared floors) moves each fix by
//    the PDR displacement of the steps after the time its measurements describe;
//  - beacon: accepted (time order checked) and ignored (no beacon map yet).
// Every event returns whether an estimate exists (after the first step, detected or standing);
// Estimate() gives it.
//
// Time order: events must come in non-decreasing time (accelerometer samples strictly
// increasing); otherwise std::invalid_argument naming the event's index, kind and time and the
// previous event's, and the session is unchanged. Malformed values: std::invalid_argument naming
// the argument, session unchanged.
//
// Exactness: a recorded walk replayed event by event equals, bit for bit, the grid filter run in
// one batch on the walk's causal steps (pdr::CausalSteps) and its scans' fixes at their scan
// times (python indoorloc.fusion.live.causal_track; tests/python/test_fusion_live.py), with the
// standing steps inserted where the session inserts them (from each step's confirmation time).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/fusion/fingerprint_fixes.h"
#include "indoorloc/fusion/grid_filter_session.h"
#include "indoorloc/fusion/grid_tracker.h"
#include "indoorloc/pdr/streaming_step_detector.h"

namespace indoorloc::fusion {

/// Which of the detector's headings a step takes.
enum class StepHeadingSource { kRotationVector, kGyro, kComplementary };

/// Options of LiveSession: the PDR calibration and per-step noise. The defaults of the noise are
/// `indoorloc fusion evaluate`'s (python fusion.site_model.TrackSettings; a test keeps them equal).
struct LiveSessionOptions {
  pdr::StreamingStepOptions detector;  ///< the step detector's settings (calibration's options)
  double step_length_k = 0.41;         ///< Weinberg K of the calibration [m / (m/s²)^(1/4)], > 0
  StepHeadingSource heading_source = StepHeadingSource::kRotationVector;
  double yaw_offset_rad = 0.0;         ///< floor-frame minus phone heading (calibration) [rad]
  double step_length_sd_fraction = 0.15;             ///< length sd / length, > 0
  /// Per-step heading sd [rad], > 0: 20 deg, chosen by leave-one-floor-out over {10, 20, 30} deg
  /// with the grid tracker on the competition site (docs/fusion_real.md, "Second round"); the
  /// Python settings (fusion.site_model.TrackSettings, fusion_real.RealSettings) read it from here.
  double step_heading_sd_rad = 0.3490658503988659;
  bool delay_compensation = false;     ///< move fixes by the PDR since the time they describe
  /// A fix still waiting for a step this long after its time [s] is applied at a standing step
  /// (zero displacement) at its time; 0: fixes wait for a detected step however long. Must exceed
  /// the detector's latency (detector.min_step_interval_s), so that a step detected later is
  /// later than the standing step (one that is not, after a gap in the samples, is moved to the
  /// standing step's time: LiveSessionSummary::late_steps). 1 s, 2.5 times the default latency:
  /// on the six shared floors 1, 1.5 and 3 s give the same live accuracy (10.90 / 10.92 / 10.93 m
  /// against 10.93 m without) and 1 s the earliest first position (p90 2.7 s after a walk's
  /// first waypoint, 3.5 s without; docs/fusion_real.md, "The live tracker").
  double standing_after_s = 1.0;

  bool IsValid(std::string* error) const;
};

/// What a LiveSession has done so far.
struct LiveSessionSummary {
  long long events = 0;       ///< events accepted
  long long imu_samples = 0;  ///< accelerometer samples given to the detector
  int steps = 0;              ///< steps detected
  int standing_steps = 0;     ///< standing steps (the filter's steps = steps + standing_steps)
  int late_steps = 0;         ///< detected steps before a standing step's time, moved to it
  int scans = 0;              ///< WiFi scans accepted
  int fixes = 0;              ///< fixes given to the filter
  int pending_fixes = 0;      ///< fixes waiting for a step at or after their time
  long long unknown_wifi_readings = 0;  ///< WiFi readings of BSSIDs not in the map (dropped)
};

class LiveSession {
 public:
  /// `tracker` (and `map` when given) must outlive the session; `map` null: WiFi scans are
  /// accepted and ignored. Throws std::invalid_argument naming the argument for a null tracker,
  /// invalid options or a malformed map (as GridFilterSession for the start).
  LiveSession(const GridTracker* tracker, const FingerprintMap* map, const LiveSessionOptions& options,
              const FingerprintFixOptions& fix_options = FingerprintFixOptions(),
              const TrackStart& start = TrackStart());
  ~LiveSession();
  LiveSession(LiveSession&&) noexcept;
  LiveSession& operator=(LiveSession&&) noexcept;

  /// Accelerometer sample: specific force (3) [m/s²], device frame. Returns HasEstimate().
  bool AddAccelerometer(double time_s, const Eigen::Vector3d& acc_mps2);
  /// Gyroscope sample: angular rate (3) [rad/s], device frame.
  bool AddGyroscope(double time_s, const Eigen::Vector3d& gyro_radps);
  /// Android rotation vector (x, y, z[, w]) (3 or more values; a 5th, the accuracy, is ignored).
  bool AddRotationVector(double time_s, const Eigen::Ref<const Eigen::VectorXd>& values);
  /// One WiFi scan reported at time_s: per reading its BSSID, RSSI [dBm], last-seen time [s].
  bool AddWifiScan(double time_s, const std::vector<std::string>& bssids,
                   const Eigen::Ref<const Eigen::VectorXd>& rssi_dbm, const Eigen::Ref<const Eigen::VectorXd>& last_seen_s);
  /// An iBeacon reading: accepted and ignored.
  bool AddBeacon(double time_s);

  bool HasEstimate() const;
  /// The estimate after the latest (detected or standing) step; std::logic_error before the first.
  const GridFilterEstimate& Estimate() const;
  LiveSessionSummary Summary() const;
  const GridFilterSession& filter() const;
  const LiveSessionOptions& options() const;
  /// Floor numbers of the plan (the order of Estimate().floor_probabilities).
  std::vector<int> floors() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace indoorloc::fusion
