#include "indoorloc/pdr/zero_velocity.h"

#include <algorithm>
#include <cmath>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "imu_timing.h"

namespace indoorloc::pdr {

bool ShoeOptions::IsValid(std::string* error) const {
  // The statistic divides by the squared sds: 1e-290 passed "> 0" and gave inf/NaN.
  return Validator(error)
      .IntInRange(window, 1, 1000000, "window")
      .Positive(threshold, "threshold")
      .Scale(sigma_acc_mps2, "sigma_acc_mps2")
      .Scale(sigma_gyro_radps, "sigma_gyro_radps")
      .InRange(gravity_mps2, 0.1, 100.0, "gravity_mps2");
}

namespace {
void CheckImu(const Eigen::Ref<const RowMatrixXd>& acc, const Eigen::Ref<const RowMatrixXd>& gyro, int window) {
  CheckShape(acc, -1, 3, "acc_mps2");
  CheckShape(gyro, acc.rows(), 3, "gyro_radps");
  CheckFinite(acc, "acc_mps2");
  CheckFinite(gyro, "gyro_radps");
  internal::CheckAccRange(acc);
  internal::CheckGyroRange(gyro);
  CheckArgument(acc.rows() >= window, "acc_mps2",
                "the recording (" + std::to_string(acc.rows()) + " samples) is shorter than one window (window = " +
                    std::to_string(window) + ")");
}
}  // namespace

Eigen::VectorXd ShoeStatistic(const Eigen::Ref<const RowMatrixXd>& acc, const Eigen::Ref<const RowMatrixXd>& gyro,
                              const ShoeOptions& options) {
  ValidateOptions(options);
  CheckImu(acc, gyro, options.window);
  const Eigen::Index n = acc.rows();
  const int w = options.window;
  const double inv_a = 1.0 / (options.sigma_acc_mps2 * options.sigma_acc_mps2);
  const double inv_g = 1.0 / (options.sigma_gyro_radps * options.sigma_gyro_radps);
  Eigen::VectorXd out(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    // Window of w samples centred on k, shifted inside the recording at its ends.
    Eigen::Index start = std::clamp<Eigen::Index>(k - w / 2, 0, n - w);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (Eigen::Index j = start; j < start + w; ++j) mean += acc.row(j).transpose();
    mean /= w;
    const double norm = mean.norm();
    const Eigen::Vector3d gdir = norm > 0 ? Eigen::Vector3d(options.gravity_mps2 * mean / norm) : Eigen::Vector3d::Zero();
    double t = 0.0;
    for (Eigen::Index j = start; j < start + w; ++j) {
      t += inv_a * (acc.row(j).transpose() - gdir).squaredNorm() + inv_g * gyro.row(j).squaredNorm();
    }
    out[k] = t / w;
  }
  return out;
}

BoolVector ShoeDetector(const Eigen::Ref<const RowMatrixXd>& acc, const Eigen::Ref<const RowMatrixXd>& gyro,
                        const ShoeOptions& options) {
  return (ShoeStatistic(acc, gyro, options).array() < options.threshold).matrix();
}

}  // namespace indoorloc::pdr
