// Streaming (causal) hand-held step detector: one IMU sample at a time in, the steps it confirms
// out, with their Weinberg feature and three headings (rotation vector, gyro, complementary).
//
// When to use: live tracking of a phone held in the hand (fusion/live_session.h), or the causal
// steps of a recorded walk (CausalSteps). The whole-walk detector of python
// indoorloc.pdr.handheld (zero-phase band-pass, centred RMS, largest peaks first) looks at
// samples after t; this one uses the past only, so a walk replayed sample by sample gives exactly
// the steps of CausalSteps (both are this code). Python's indoorloc.pdr.streaming calls it.
//
// The method, per accelerometer sample (gyroscope and rotation quaternion held at their latest
// sample at or before it):
//  1. Rate: 1 / median of the first `rate_samples` accelerometer intervals (the filters need one;
//     the samples until then are kept and filtered once it is known).
//  2. Signal: |a| - g through the Butterworth low-pass (lowpass_hz) then high-pass (highpass_hz),
//     run forward only (transposed direct form II, started in the steady state of the first sample).
//  3. Threshold: max(threshold_fraction x RMS over the trailing rms_window_s, min_peak_mps2).
//  4. Peaks: a local maximum above the threshold at least min_step_interval_s after the previous
//     step becomes the candidate unless a larger candidate is pending; a candidate no larger
//     maximum displaced for min_step_interval_s is a step (the detector's latency).
//  5. Feature (Weinberg, length = K feature): (max - min of the low-passed |a|)^(1/4) over
//     [t - h, t + h], h = min(max_step_half_window_s, half the interval to the previous step).
//  6. Heading: per step the mean over [previous step, this step] (the first step: the
//     2 max_step_half_window_s before it) of the unwrapped rotation-vector heading (phone +y axis,
//     east = 0, counter-clockwise), the gyro heading (rate about the vertical integrated from the
//     first rotation-vector heading) and the complementary blend (a causal first-order low-pass of
//     their difference, time constant complementary_tau_s).
// Weinberg, "Using the ADXL202 in pedometer and personal navigation applications", Analog Devices
// AN-602 (2002), for the feature.
#pragma once

#include <deque>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace indoorloc::pdr {

/// Options of StreamingStepDetector. The defaults are python indoorloc.pdr.handheld.HandheldOptions'
/// (the Python dataclass is where they are chosen and documented; a test keeps the two equal).
struct StreamingStepOptions {
  double lowpass_hz = 3.0;             ///< band-pass upper edge [Hz] (clamped to 0.45 x rate)
  double highpass_hz = 0.5;            ///< band-pass lower edge [Hz]
  int filter_order = 2;                ///< Butterworth order of each edge (1..8)
  double rms_window_s = 2.0;           ///< trailing RMS window of the threshold [s]
  double threshold_fraction = 0.5;     ///< a peak must exceed this x RMS ...
  double min_peak_mps2 = 1.0;          ///< ... and this [m/s²]
  double min_step_interval_s = 0.4;    ///< at most one step per this [s]; also the latency
  double max_step_half_window_s = 0.4; ///< Weinberg window half-width cap [s]
  double complementary_tau_s = 10.0;   ///< complementary heading time constant [s]
  int rate_samples = 25;               ///< intervals whose median gives the rate (>= 1)

  /// True if usable; otherwise false with the reason (naming the field) in *error.
  bool IsValid(std::string* error) const;
};

/// One confirmed step.
struct StreamingStep {
  double time_s = 0;                   ///< time of the peak [s]
  long long index = 0;                 ///< index of the peak's sample (0 = first sample)
  double feature = 0;                  ///< Weinberg feature (max - min of low-passed |a|)^(1/4)
  double heading_rotation_vector_rad = 0;  ///< in [-pi, pi)
  double heading_gyro_rad = 0;
  double heading_complementary_rad = 0;
  double start_time_s = 0;             ///< start of the interval the headings average [s]
  double confirmed_time_s = 0;         ///< time of the sample that confirmed it [s] (>= time_s)
};

/// Android rotation-vector values (x, y, z[, w]) -> unit quaternion (x, y, z, w): w completed as
/// sqrt(max(0, 1 - x² - y² - z²)) when absent or NaN, then normalised (zero stays zero).
Eigen::Vector4d QuaternionFromRotationVector(const Eigen::Ref<const Eigen::VectorXd>& values);

class StreamingStepDetector {
 public:
  /// Throws std::invalid_argument naming the field for invalid options.
  explicit StreamingStepDetector(const StreamingStepOptions& options = StreamingStepOptions());
  ~StreamingStepDetector();
  StreamingStepDetector(StreamingStepDetector&&) noexcept;
  StreamingStepDetector& operator=(StreamingStepDetector&&) noexcept;

  /// One IMU sample: time [s] (strictly after the previous sample's), specific force (3) [m/s²]
  /// and angular rate (3) [rad/s] in the device frame, unit quaternion (x, y, z, w) device ->
  /// east-north-up. Appends the steps it confirms (usually none) to *steps and returns their
  /// number. Throws std::invalid_argument (detector unchanged) for a non-finite value or a time
  /// not after the previous sample's.
  int AddSample(double time_s, const Eigen::Vector3d& acc_mps2, const Eigen::Vector3d& gyro_radps,
                const Eigen::Vector4d& quat_xyzw, std::vector<StreamingStep>* steps);

  /// Rate used by the filters [Hz]; NaN until rate_samples + 1 samples have come.
  double rate_hz() const;
  /// Time of the first filtered sample [s]; NaN until the rate is known.
  double first_time_s() const;
  /// Time of the latest sample [s]; -inf before the first.
  double latest_time_s() const;
  const StreamingStepOptions& options() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// The causal steps of a recorded walk: every sample (N rows: t_s, acc (N x 3), gyro (N x 3),
/// quat (N x 4)) through one StreamingStepDetector. Throws std::invalid_argument naming the
/// argument for mismatched shapes, non-finite values or times not increasing.
std::vector<StreamingStep> CausalSteps(const Eigen::Ref<const Eigen::VectorXd>& time_s,
                                       const Eigen::Ref<const Eigen::MatrixXd>& acc_mps2,
                                       const Eigen::Ref<const Eigen::MatrixXd>& gyro_radps,
                                       const Eigen::Ref<const Eigen::MatrixXd>& quat_xyzw,
                                       const StreamingStepOptions& options = StreamingStepOptions());

}  // namespace indoorloc::pdr
