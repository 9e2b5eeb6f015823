// Private helpers shared by the pdr algorithms that integrate IMU samples (ZUPT EKF, Mahony,
// INS-ZUPT increments): the checks of their samples, the sample period used where timestamps
// repeat or go backwards, and the gravity check on the first samples.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::pdr::internal {

/// Plausibility bounds of raw samples: beyond them a finite input (1e300) still overflows the
/// integration or the squared norms to inf. MEMS sensors saturate far below (16 g, 35 rad/s).
inline constexpr double kMaxAbsAccMps2 = 1e4;
inline constexpr double kMaxAbsGyroRadps = 1e4;
inline constexpr double kMaxAbsMag = 1e7;  // any unit in use (uT, mG, raw counts)

/// Times beyond ±1e15 s (30 million years) make differences overflow or lose all precision.
template <typename Vector>
void CheckTimeRange(const Vector& time_s, const char* name = "time_s") {
  RequireAllInRange(time_s, -1e15, 1e15, name);
}

template <typename Matrix>
void CheckAccRange(const Matrix& acc, const char* name = "acc_mps2") {
  RequireAllInRange(acc, -kMaxAbsAccMps2, kMaxAbsAccMps2, name);
}
template <typename Matrix>
void CheckGyroRange(const Matrix& gyro, const char* name = "gyro_radps") {
  RequireAllInRange(gyro, -kMaxAbsGyroRadps, kMaxAbsGyroRadps, name);
}

/// (N, 3) samples of one sensor as the detectors need them: any N, three columns, finite, within
/// the plausibility bounds above.
template <typename Matrix>
void CheckAccSamples(const Matrix& acc, const char* name = "acc_mps2") {
  CheckShape(acc, -1, 3, name);
  CheckFinite(acc, name);
  CheckAccRange(acc, name);
}
template <typename Matrix>
void CheckGyroSamples(const Matrix& gyro, const char* name = "gyro_radps") {
  CheckShape(gyro, -1, 3, name);
  CheckFinite(gyro, name);
  CheckGyroRange(gyro, name);
}

/// The samples of an IMU recording as every integrating algorithm (ZUPT EKF, Mahony) needs
/// them, once their shapes are checked: at least 2 samples, finite, within the bounds above.
template <typename Vector, typename Matrix>
void CheckImuSamples(const Vector& time_s, const Matrix& acc, const Matrix& gyro) {
  CheckArgument(acc.rows() >= 2, "acc_mps2", "needs at least 2 samples");
  CheckFinite(time_s, "time_s");
  CheckFinite(acc, "acc_mps2");
  CheckFinite(gyro, "gyro_radps");
  CheckTimeRange(time_s);
  CheckAccRange(acc);
  CheckGyroRange(gyro);
}

/// A sample count computed in double (a window in seconds times a rate), rounded and clamped
/// to [0, 1e9], beyond any recording: casting 3.6e16 to int is undefined behaviour (it crashed
/// ins_zupt_increments), and NaN counts as 0. Counts below 1e9 are unchanged.
inline int SampleCount(double samples) {
  if (!(samples > 0.0)) return 0;
  return static_cast<int>(std::lround(std::min(samples, 1e9)));
}

/// Median of the positive differences of time_s [s]; throws (naming time_s) if it never increases.
inline double MedianSamplePeriod(const Eigen::Ref<const Eigen::VectorXd>& time_s) {
  std::vector<double> dts;
  for (Eigen::Index k = 1; k < time_s.size(); ++k) {
    if (time_s[k] > time_s[k - 1]) dts.push_back(time_s[k] - time_s[k - 1]);
  }
  CheckArgument(!dts.empty(), "time_s", "does not increase");
  std::nth_element(dts.begin(), dts.begin() + static_cast<std::ptrdiff_t>(dts.size() / 2), dts.end());
  return dts[dts.size() / 2];
}

/// Mean specific force of the first `init_samples` rows of acc [m/s²]; throws (naming acc_mps2)
/// if it is far below gravity, the usual sign of data in g instead of m/s².
template <typename Matrix>
Eigen::Vector3d InitialSpecificForce(const Matrix& acc, Eigen::Index init_samples, double gravity_mps2) {
  const Eigen::Index init = std::min<Eigen::Index>(init_samples, acc.rows());
  const Eigen::Vector3d mean_f = acc.topRows(init).colwise().mean().transpose();
  CheckArgument(mean_f.norm() > 0.1 * gravity_mps2, "acc_mps2",
                "the first samples do not measure gravity (is the unit g instead of m/s^2?)");
  return mean_f;
}

}  // namespace indoorloc::pdr::internal
