// Stance (zero-velocity) detection for a foot-mounted IMU.
//
// SHOE, the stance hypothesis optimal detector (Skog, Händel, Nilsson, Rantakokko, "Zero-velocity
// detection: an algorithm evaluation", IEEE TBME 2010, eq. 13): over a window of W samples around
// sample k,
//   T_k = (1/W) Σ_j [ ||f_j - g ā/||ā|| ||² / σ_a² + ||ω_j||² / σ_ω² ],
// with ā the window's mean specific force; the foot is still when T_k < γ. Also the
// acceleration-moving-variance and angular-rate-energy detectors of the same paper, and the
// two-threshold acceleration-variance detector of paper 002 (eq. 1-3) with windows in samples.
//
// DetectZeroVelocity (issue 16) adapts the SHOE threshold to the recording: a fixed threshold γ₀
// (rule kFixed), or γ = min(γ_max, max(γ₀, Q_f(T))) (rule kStanceGuard), Q_f the f-quantile of
// T over the walking span (first to last sample with T ≥ γ₀), so that at least the fraction f of
// that span is stance. A foot at walking or running pace rests for a good part of each stride
// (about 25-40 % of the time here); when γ₀ finds much less (a run whose stance is never still, a
// walk whose rest is noisier than γ₀ expects), the guard raises γ until it does, and a rule can
// never hand the filter a walk with 9 % stance. Every constant was chosen by leave-one-trial-out
// cross-validation over the PyShoe trials (docs/pdr.md; python/indoorloc/experiments/pdr_zupt_cv.py).
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

enum class ZeroVelocityRule {
  kFixed,        ///< T_k < shoe.threshold
  kStanceGuard,  ///< threshold raised (up to max_threshold) until min_stance_fraction of the walking span is stance
};

struct ZeroVelocityOptions {
  /// SHOE window and noise sds; shoe.threshold is the base threshold γ₀.
  ShoeOptions shoe;
  ZeroVelocityRule rule = ZeroVelocityRule::kStanceGuard;
  /// Guard: the least stance fraction f of the walking span [0..1).
  double min_stance_fraction = 0.3;
  /// Guard: the threshold is never raised above this (γ_max > γ₀).
  double max_threshold = 1e7;

  bool IsValid(std::string* error) const;
};

struct ZeroVelocitySummary {
  double base_threshold = 0.0;          ///< γ₀
  double threshold = 0.0;               ///< the threshold used
  bool guard_raised = false;            ///< the guard raised γ above γ₀
  double stance_fraction = 0.0;         ///< over the recording [0..1]
  double walking_stance_fraction = 0.0; ///< over the walking span [0..1]
  Eigen::Index walking_begin = 0;       ///< walking span [begin, end) in samples
  Eigen::Index walking_end = 0;
  std::string BriefReport() const;
};

struct ZeroVelocityOutput {
  BoolVector stance;           ///< N stance flags
  Eigen::VectorXd statistic;   ///< N SHOE statistic T_k
  ZeroVelocitySummary summary;
};

/// The SHOE statistic and stance flags with the threshold of options.rule (see the header comment).
ZeroVelocityOutput DetectZeroVelocity(const Eigen::Ref<const RowMatrixXd>& acc_mps2, const Eigen::Ref<const RowMatrixXd>& gyro_radps,
                                      const ZeroVelocityOptions& options = ZeroVelocityOptions());

}  // namespace indoorloc::pdr
