// Zero-velocity-aided strapdown INS for a foot-mounted IMU: a 9-state error-state extended
// Kalman filter (position, velocity, attitude errors), as in OpenShoe (Nilsson et al. 2012) and
// PyShoe (Wagstaff et al. 2018).
//
// Navigation frame: x, y horizontal, z up; gravity (0, 0, -g). Mechanisation per sample:
// q <- q ⊗ exp(ω Δt / 2), f_n = R(q) f_b, v <- v + (f_n + g_n) Δt, p <- p + v Δt. Error state
// δx = (δp, δv, ε) with R_true = (I + [ε]×) R̂, so δv' = -[f_n]× ε:
//   F = [[I, I Δt, 0], [0, I, -[f_n]× Δt], [0, 0, I]],  Q = diag(0, σ_a² Δt² I, σ_ω² Δt² I).
// At every stance sample a zero-velocity pseudo-measurement z = 0 - v̂ with H = [0 I 0] and
// covariance σ_v² I corrects the state (Joseph-form covariance update). Optionally a stance
// heading pseudo-measurement follows: the yaw keeps its stance-onset value (H = e_9ᵀ, sd
// sigma_stance_heading_rad), a heuristic drift elimination for the unobservable yaw. The initial attitude
// levels the mean specific force of the first samples (roll, pitch); the yaw is 0.
// Non-increasing timestamps (repeated rows in some loggers) get the median sample period.
//
// Smoother (optional): the linear RTS recursion written on the error states. With P⁺_k the
// posterior covariance, F_{k+1} the transition and P⁻_{k+1} the prior covariance of the next
// step, C_k = P⁺_k F_{k+1}ᵀ (P⁻_{k+1})^{-1}; the smoothed state minus the forward posterior is
// δ_k = C_k (δ_{k+1} + u_{k+1}), where u_{k+1} is the correction the ZUPT update applied at k+1
// (x⁺_{k+1} - x⁻_{k+1}), and δ_N = 0. Only C_k and u_k are stored (9 x 9 + 9 numbers per sample).
//
// Health check (divergence must be reported, never silent). The Summary describes the
// stance the filter was given and what the filter made of it: the stance fraction over the
// walking span (first swing to last swing), the swing durations, the speed |v̂⁻| the filter had
// integrated when each stance began (before its zero-velocity update: the velocity error of one
// swing), the longest horizontal stride between consecutive stance onsets, and a flag with the
// reasons when the path is implausible: too little stance, strides longer than
// max_plausible_stride_m, speeds at stance that rise over the recording or exceed
// max_stance_speed_mps.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/pdr/zero_velocity.h"

namespace indoorloc::pdr {

struct ZuptEkfOptions {
  double sigma_acc_mps2 = 0.5;      ///< process noise of the accelerometer [m/s^2]
  double sigma_gyro_radps = 0.5 * 3.14159265358979323846 / 180.0;  ///< process noise of the gyro [rad/s]
  double sigma_zupt_mps = 0.01;     ///< zero-velocity pseudo-measurement sd [m/s]
  double gravity_mps2 = 9.81;
  int init_samples = 20;            ///< samples averaged for the initial attitude
  /// Stance heading update (beyond OpenShoe): within a stance phase the yaw is observed equal to
  /// its value at the stance onset, with this sd [rad]; 0 disables (heuristic drift elimination).
  double sigma_stance_heading_rad = 0.0;
  /// Also run the Rauch-Tung-Striebel smoother backwards over the error states (OpenShoe's
  /// smoother): positions_m then holds the smoothed path and filtered_positions_m the EKF's.
  bool smooth = false;

  // Health check limits (they flag, they never change the estimate). Calibrated on the 273 runs
  // of the PyShoe trials with fixed thresholds 1e4-1e7 (EKF + RTS; docs/pdr.md "Health check"):
  // no run with ARMSE < 0.4 m is flagged, and all 28 runs that diverged because stances were
  // missed (ARMSE > 1 m at thresholds <= 10^5.5) are. The 2.5 m stride limit would flag 11
  // of the 141 good runs (a run with one missed stance has a 3-3.6 m gap between detected
  // stances yet an ARMSE of 0.1-0.3 m), hence 4 m.
  double min_stance_fraction = 0.02;      ///< flag when the walking span has less stance [0..1]
  double max_plausible_swing_s = 5.0;     ///< flag a swing (stance to stance) longer than this [s]
  double max_plausible_stride_m = 4.0;    ///< flag a stride (stance onset to onset) longer than this [m]
  /// Flag when the median stride exceeds this [m] (the 2.5 m): the whole path is
  /// stretched (a diverging filter whose path is 2-3x the walk), not one stance missed.
  double max_median_stride_m = 2.5;
  double max_stance_speed_mps = 4.0;      ///< flag when |v̂⁻| at a stance onset exceeds this [m/s]
  /// Flag when the median |v̂⁻| at stance onsets in the last third of the recording exceeds this
  /// factor times the median in the first third and min_rising_speed_mps: the velocity at ZUPT rises.
  double speed_rise_factor = 3.0;
  double min_rising_speed_mps = 1.0;      ///< see speed_rise_factor [m/s]

  bool IsValid(std::string* error) const;
};

/// Diagnostics of one RunZuptEkf call (the health check above).
struct ZuptEkfSummary {
  int n_samples = 0;
  int n_stance_samples = 0;
  int n_stance_phases = 0;               ///< runs of stance samples
  double stance_fraction = 0.0;          ///< over the whole recording
  double walking_stance_fraction = 0.0;  ///< over the walking span (first to last swing sample); 1 if no swing
  double swing_median_s = 0.0;           ///< median duration of the swings (motion between stance phases, and before the first / after the last) [s]
  double swing_max_s = 0.0;              ///< longest such swing [s]
  double speed_at_stance_median_mps = 0.0;  ///< median |v̂⁻| at stance onsets [m/s]
  double speed_at_stance_max_mps = 0.0;     ///< largest |v̂⁻| at a stance onset [m/s]
  double speed_at_stance_rise = 1.0;     ///< median |v̂⁻| over the last third of onsets / first third
  double longest_stride_m = 0.0;         ///< longest horizontal displacement between consecutive stance onsets [m]
  double median_stride_m = 0.0;          ///< median of those displacements [m]
  bool implausible = false;              ///< true when any check below failed
  std::vector<std::string> reasons;      ///< one sentence per failed check
  double seconds = 0.0;
  std::string BriefReport() const;
};

/// The health check of a path: computed by RunZuptEkf; public so that other ZUPT paths (or a
/// smoothed path) can be checked the same way. positions_m N x 3, stance N, speed_at_onset_mps
/// one entry per stance run (|v̂⁻| at its first sample; NaN where unknown), time_s N.
ZuptEkfSummary CheckZuptHealth(const Eigen::Ref<const Eigen::VectorXd>& time_s, const Eigen::Ref<const RowMatrixXd>& positions_m,
                               const BoolVector& stance, const std::vector<double>& speed_at_onset_mps,
                               const ZuptEkfOptions& options);

struct ZuptEkfOutput {
  RowMatrixXd positions_m;      ///< N x 3 (smoothed when options.smooth)
  RowMatrixXd filtered_positions_m;  ///< N x 3 forward EKF positions
  RowMatrixXd velocities_mps;   ///< N x 3
  Eigen::VectorXd headings_rad; ///< N yaw
  RowMatrixXd quaternions_wxyz; ///< N x 4 attitude body -> nav (w, x, y, z), smoothed when options.smooth
  RowMatrixXd position_sd_m;    ///< N x 3 square roots of the position covariance diagonal
  double seconds = 0.0;
  ZuptEkfSummary summary;       ///< health check and timing
};

/// Runs the filter over a recording: time_s (N, increasing; repeats handled as above),
/// acc_mps2 and gyro_radps (N x 3, sensor frame), stance (N) from a detector.
ZuptEkfOutput RunZuptEkf(const Eigen::Ref<const Eigen::VectorXd>& time_s, const Eigen::Ref<const RowMatrixXd>& acc_mps2,
                         const Eigen::Ref<const RowMatrixXd>& gyro_radps, const BoolVector& stance,
                         const ZuptEkfOptions& options = ZuptEkfOptions());

}  // namespace indoorloc::pdr
