// Private helpers shared by the pdr algorithms that integrate IMU samples (ZUPT EKF, Mahony,
// INS-ZUPT increments): the sample period used where timestamps repeat or go backwards, and
// the gravity check on the first samples.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/core/check.h"

namespace indoorloc::pdr::internal {

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
