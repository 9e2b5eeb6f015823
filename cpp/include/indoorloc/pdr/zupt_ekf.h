// Zero-velocity-aided strapdown INS for a foot-mounted IMU: a 9-state error-state extended
// Kalman filter (position, velocity, attitude errors), as in OpenShoe (Nilsson et al. 2012) and
// PyShoe (Wagstaff et al. 2018).
//
// Navigation frame: x, y horizontal, z up; gravity (0, 0, -g). Mechanisation per sample:
// q <- q ⊗ exp(ω Δt / 2), f_n = R(q) f_b, v <- v + (f_n + g_n) Δt, p <- p + v Δt. Error state
// δx = (δp, δv, ε) with R_true = (I + [ε]×) R̂, so δv' = -[f_n]× ε:
//   F = [[I, I Δt, 0], [0, I, -[f_n]× Δt], [0, 0, I]],  Q = diag(0, σ_a² Δt² I, σ_ω² Δt² I).
// At every stance sample a zero-velocity pseudo-measurement z = 0 - v̂ with H = [0 I 0] and
// covariance σ_v² I corrects the state (Joseph-form covariance update). The initial attitude
// levels the mean specific force of the first samples (roll, pitch); the yaw is 0.
// Non-increasing timestamps (repeated rows in some loggers) get the median sample period.
#pragma once

#include <string>

#include <Eigen/Core>

#include "indoorloc/pdr/zero_velocity.h"

namespace indoorloc::pdr {

struct ZuptEkfOptions {
  double sigma_acc_mps2 = 0.5;      ///< process noise of the accelerometer [m/s^2]
  double sigma_gyro_radps = 0.5 * 3.14159265358979323846 / 180.0;  ///< process noise of the gyro [rad/s]
  double sigma_zupt_mps = 0.01;     ///< zero-velocity pseudo-measurement sd [m/s]
  double gravity_mps2 = 9.81;
  int init_samples = 20;            ///< samples averaged for the initial attitude

  bool IsValid(std::string* error) const;
};

struct ZuptEkfOutput {
  RowMatrixXd positions_m;      ///< N x 3
  RowMatrixXd velocities_mps;   ///< N x 3
  Eigen::VectorXd headings_rad; ///< N yaw
  RowMatrixXd position_sd_m;    ///< N x 3 square roots of the position covariance diagonal
  double seconds = 0.0;
};

/// Runs the filter over a recording: time_s (N, increasing; repeats handled as above),
/// acc_mps2 and gyro_radps (N x 3, sensor frame), stance (N) from a detector.
ZuptEkfOutput RunZuptEkf(const Eigen::Ref<const Eigen::VectorXd>& time_s, const Eigen::Ref<const RowMatrixXd>& acc_mps2,
                         const Eigen::Ref<const RowMatrixXd>& gyro_radps, const BoolVector& stance,
                         const ZuptEkfOptions& options = ZuptEkfOptions());

}  // namespace indoorloc::pdr
