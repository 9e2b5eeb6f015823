// Stride length from acceleration: Weinberg's hip-bounce rule, paper 002 §IV.A, eq. 4.
//
//   SL_k = K · ( max_{j ∈ window_k} ã_j − min_{j ∈ window_k} ã_j )^{1/4},
//
// with ã = LP(|acc|) (eq. 1, then a 4th-order Butterworth low-pass at 3 Hz) and window_k the
// 2w + 1 samples around the k-th stance sample (or, for body-worn sensors with a reference stride
// segmentation, the samples of the stride itself). K depends on the person and the sensor
// placement: calibrate it on a walk of known length (CalibrateWeinbergK: per-stride least squares,
// or CalibrateWeinbergKFromDistance: one known total distance). The paper found K = 0.364 for its
// foot-mounted Xsens with |acc| in m/s^2.
//
// The Butterworth filter is designed here (analog prototype poles on the unit circle, frequency
// pre-warped, bilinear transform per conjugate pole pair) as second-order sections in scipy's
// layout [b0 b1 b2 a0 a1 a2]; it is the same transfer function as scipy.signal.butter(order,
// cutoff_hz, fs=rate_hz), and FilterSos equals scipy.signal.sosfilt (zero initial state) or
// sosfilt with zi = sosfilt_zi(sos) * x[0] (steady_state_start = true).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/pdr/zero_velocity.h"

namespace indoorloc::pdr {

/// Butterworth design as second-order sections (ceil(order/2) x 6, rows [b0 b1 b2 a0 a1 a2], a0 = 1;
/// an odd order ends with a first-order section, b2 = a2 = 0). Low-pass, or high-pass when
/// `highpass`. Throws std::invalid_argument unless 1 <= order <= 16 and 0 < cutoff_hz < rate_hz / 2.
RowMatrixXd ButterworthSos(int order, double cutoff_hz, double rate_hz, bool highpass = false);

/// Runs a cascade of second-order sections (transposed direct form II) over x. With
/// steady_state_start the state starts as if x[0] had been applied forever (scipy's
/// sosfilt_zi(sos) * x[0]), which avoids the start-up transient of a zero state.
Eigen::VectorXd FilterSos(const Eigen::Ref<const RowMatrixXd>& sos, const Eigen::Ref<const Eigen::VectorXd>& x,
                          bool steady_state_start = false);

struct WeinbergOptions {
  double k = 0.364;            ///< K of eq. 4 [m / (m/s^2)^{1/4}] (paper 002: 0.364, foot-mounted)
  int filter_order = 4;        ///< low-pass order (paper: 4)
  double cutoff_hz = 3.0;      ///< low-pass cut-off [Hz] (paper: 3)
  double window_s = 0.15;      ///< half-window w around each stance sample [s] (paper: 15 samples at 100 Hz)
  bool steady_state_start = true;  ///< start the filter in its steady state for the first |acc|
  bool IsValid(std::string* error) const;
};

/// ã = LP(|acc|) (N), acc_mps2 N x 3 finite [m/s^2].
Eigen::VectorXd WeinbergFilteredMagnitude(double rate_hz, const Eigen::Ref<const RowMatrixXd>& acc_mps2,
                                          const WeinbergOptions& options);

/// The bounce feature (max ã − min ã)^{1/4} over each interval [start, end] (inclusive sample
/// indices, M x 2, 0 <= start <= end < N) [(m/s^2)^{1/4}]. Multiply by K for stride lengths.
Eigen::VectorXd WeinbergFeatures(double rate_hz, const Eigen::Ref<const RowMatrixXd>& acc_mps2,
                                 const Eigen::Ref<const Eigen::MatrixXi>& intervals, const WeinbergOptions& options);

/// Eq. 4: SL_k [m] for each stance sample index (increasing, inside [0, N)), window ±window_s.
Eigen::VectorXd WeinbergStrideLengths(double rate_hz, const Eigen::Ref<const RowMatrixXd>& acc_mps2,
                                      const std::vector<int>& step_indices, const WeinbergOptions& options);

struct WeinbergCalibration {
  double k = 0.0;                ///< fitted K
  double rms_residual_m = 0.0;   ///< RMS of K f_i − L_i over the strides (0 for the distance fit)
  int n_strides = 0;
  std::string BriefReport() const;
};

/// Least squares K = Σ f_i L_i / Σ f_i² from features f (M) and known stride lengths L (M) [m].
WeinbergCalibration CalibrateWeinbergK(const Eigen::Ref<const Eigen::VectorXd>& features,
                                       const Eigen::Ref<const Eigen::VectorXd>& lengths_m);

/// K = D / Σ f_i from a walk of known total length D [m] (the paper's calibration).
WeinbergCalibration CalibrateWeinbergKFromDistance(const Eigen::Ref<const Eigen::VectorXd>& features, double distance_m);

}  // namespace indoorloc::pdr
