// Stance (zero-velocity) detection for a foot-mounted IMU.
//
// SHOE, the stance hypothesis optimal detector (Skog, Händel, Nilsson, Rantakokko, "Zero-velocity
// detection: an algorithm evaluation", IEEE TBME 2010, eq. 13): over a window of W samples around
// sample k,
//   T_k = (1/W) Σ_j [ ||f_j - g ā/||ā|| ||² / σ_a² + ||ω_j||² / σ_ω² ],
// with ā the window's mean specific force; the foot is still when T_k < γ. Also the
// acceleration-moving-variance and angular-rate-energy detectors of the same paper, and the
// two-threshold acceleration-variance detector of paper 002 (eq. 1-3) with windows in samples.
#pragma once

#include <string>

#include <Eigen/Core>

namespace indoorloc::pdr {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using BoolVector = Eigen::Matrix<bool, Eigen::Dynamic, 1>;

struct ShoeOptions {
  int window = 5;                      ///< W [samples], centred on each sample
  double threshold = 3e4;              ///< γ (dimensionless test statistic)
  double sigma_acc_mps2 = 0.01;        ///< accelerometer noise sd [m/s^2]
  double sigma_gyro_radps = 0.1 * 3.14159265358979323846 / 180.0;  ///< gyro noise sd [rad/s]
  double gravity_mps2 = 9.81;

  bool IsValid(std::string* error) const;
};

/// The SHOE statistic T_k for every sample (N). acc_mps2 and gyro_radps are N x 3, finite.
Eigen::VectorXd ShoeStatistic(const Eigen::Ref<const RowMatrixXd>& acc_mps2, const Eigen::Ref<const RowMatrixXd>& gyro_radps,
                              const ShoeOptions& options);

/// Stance flags: T_k < threshold.
BoolVector ShoeDetector(const Eigen::Ref<const RowMatrixXd>& acc_mps2, const Eigen::Ref<const RowMatrixXd>& gyro_radps,
                        const ShoeOptions& options);

}  // namespace indoorloc::pdr
