// Step (stride) detection from a foot-mounted IMU, paper 002 §III.C-D.
//
// Acceleration detector (eq. 1-3): a_i = |acc_i| (eq. 1); local variance σ²_i over the window
// [i - w, i + w] around the window's own mean (eq. 2); B1_i = T1 where σ_i > T1 (swing), B2_i = T2
// where σ_i < T2 (stance) (eq. 3); a step at sample i when a swing ends (B1 drops: B1_{i-1} >
// B1_i; the text copy prints "<", which would be a swing start) and a stance follows within w
// samples (max B2_{i..i+w} = T2). Windows are given in seconds so that any rate works.
// Thresholds: the paper's fixed T1 = 2, T2 = 1 m/s² miscount PyShoe strides by about a third, so
// by default they adapt to the recording: T1 = swing_fraction and T2 = stance_fraction times the
// 95th percentile of σ (the typical swing peak).
//
// Gyroscope detector (§III.D, after Feliz et al. 2009): |ω| thresholded (default 1 rad/s),
// median-filtered, a step at each transition to the motionless state.
//
// Magnetometer detector (§III.D, paper 002's own): a high-pass filter removes the DC field (the
// Earth's field and hard-iron offsets), then the same processing as the gyroscope detector on
// the magnitude of the high-passed field. The field's unit and strength vary between sensors
// and places, so the threshold is a fraction of the recording's 95th percentile of that
// magnitude (units cancel).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/pdr/zero_velocity.h"

namespace indoorloc::pdr {

struct AccelerationStepOptions {
  double window_s = 0.1;              ///< half-window w [s] (paper: 15 samples = 0.15 s at 100 Hz; 0.1 s chosen on PyShoe)
  bool adaptive = true;               ///< thresholds from the recording's σ distribution
  double swing_threshold_mps2 = 2.0;  ///< T1 when not adaptive
  double stance_threshold_mps2 = 1.0; ///< T2 when not adaptive
  double swing_fraction = 0.35;       ///< adaptive T1 = fraction x 95th percentile of σ
  double stance_fraction = 0.15;      ///< adaptive T2
  /// Beyond the paper: a swing end closer than this to the previous step is the same stride
  /// (σ oscillates inside a swing); 0 disables.
  double min_step_interval_s = 0.4;
  bool IsValid(std::string* error) const;
};

struct GyroStepOptions {
  double threshold_radps = 1.0;   ///< |ω| above this is motion
  double median_window_s = 0.1;   ///< median filter length [s]
  double min_swing_s = 0.2;       ///< motion shorter than this is not a step
  bool IsValid(std::string* error) const;
};

struct MagneticStepOptions {
  int highpass_order = 2;          ///< Butterworth high-pass order per axis
  double highpass_hz = 0.5;        ///< high-pass cut-off [Hz] (below the step rate of ~1 Hz per foot)
  double threshold_fraction = 0.3; ///< motion where |m_hp| > fraction x 95th percentile of |m_hp|
  double median_window_s = 0.1;    ///< median filter length [s]
  double min_swing_s = 0.2;        ///< motion shorter than this is not a step [s]
  /// Beyond the paper: rest shorter than this between two motion runs is merged into one swing
  /// (|m_hp| crosses zero inside a swing where the high-passed field changes sign) [s]; 0 disables.
  double min_rest_s = 0.15;
  bool IsValid(std::string* error) const;
};

/// Sample indices of the detected steps (stance onsets of one foot); optionally σ (N).
std::vector<int> DetectStepsAcceleration(double rate_hz, const Eigen::Ref<const RowMatrixXd>& acc_mps2,
                                         const AccelerationStepOptions& options, Eigen::VectorXd* sigma = nullptr);

std::vector<int> DetectStepsGyro(double rate_hz, const Eigen::Ref<const RowMatrixXd>& gyro_radps,
                                 const GyroStepOptions& options);

/// Step sample indices from a magnetometer (N x 3, any unit); optionally |m_hp| (N).
std::vector<int> DetectStepsMagnetometer(double rate_hz, const Eigen::Ref<const RowMatrixXd>& mag,
                                         const MagneticStepOptions& options, Eigen::VectorXd* magnitude = nullptr);

}  // namespace indoorloc::pdr
