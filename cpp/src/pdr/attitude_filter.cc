#include "indoorloc/pdr/attitude_filter.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "imu_timing.h"

namespace indoorloc::pdr {
namespace {

Eigen::Quaterniond ExpQ(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  if (angle < 1e-12) return Eigen::Quaterniond(1.0, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, phi / angle));
}

double Yaw(const Eigen::Matrix3d& r) { return std::atan2(r(1, 0), r(0, 0)); }

}  // namespace

bool MahonyOptions::IsValid(std::string* error) const {
  // Gains multiply rates and errors every step: inf would make every quaternion NaN.
  return Validator(error)
      .InRange(kp, 0.0, 1e6, "kp")
      .InRange(ki, 0.0, 1e6, "ki")
      .InRange(kp_mag, 0.0, 1e6, "kp_mag")
      .InRange(gravity_mps2, 0.1, 100.0, "gravity_mps2")
      .Scale(acc_gate_mps2, "acc_gate_mps2")
      .Scale(mag_norm_tolerance, "mag_norm_tolerance")
      .Scale(mag_dip_tolerance_rad, "mag_dip_tolerance_rad")
      .IntInRange(init_samples, 1, 1000000000, "init_samples");
}

AttitudeOutput RunMahony(const Eigen::Ref<const Eigen::VectorXd>& time_s, const Eigen::Ref<const RowMatrixXd>& acc,
                         const Eigen::Ref<const RowMatrixXd>& gyro, const Eigen::Ref<const RowMatrixXd>& mag,
                         const MahonyOptions& options) {
  ValidateOptions(options);
  const auto start = std::chrono::steady_clock::now();
  CheckShape(acc, -1, 3, "acc_mps2");
  const Eigen::Index n = acc.rows();
  CheckShape(gyro, n, 3, "gyro_radps");
  CheckArgument(time_s.size() == n, "time_s", "must have one entry per sample");
  const bool use_mag = mag.rows() > 0;
  if (use_mag) CheckShape(mag, n, 3, "mag");
  internal::CheckImuSamples(time_s, acc, gyro);
  if (use_mag) CheckFinite(mag, "mag");
  if (use_mag) RequireAllInRange(mag, -internal::kMaxAbsMag, internal::kMaxAbsMag, "mag");
  const double median_dt = internal::MedianSamplePeriod(time_s);

  const Eigen::Vector3d mean_f = internal::InitialSpecificForce(acc, options.init_samples, options.gravity_mps2);
  // Level: rotate the mean specific force onto +z, then remove the yaw that introduces.
  Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(mean_f.normalized(), Eigen::Vector3d::UnitZ());
  q = (Eigen::Quaterniond(Eigen::AngleAxisd(-Yaw(q.toRotationMatrix()), Eigen::Vector3d::UnitZ())) * q).normalized();

  AttitudeOutput out;
  out.quaternions_wxyz.resize(n, 4);
  out.gyro_bias_radps.resize(n, 3);
  out.mag_used = BoolVector::Constant(n, false);
  if (use_mag) {
    std::vector<double> norms(static_cast<size_t>(n));
    for (Eigen::Index k = 0; k < n; ++k) norms[static_cast<size_t>(k)] = mag.row(k).norm();
    std::nth_element(norms.begin(), norms.begin() + static_cast<std::ptrdiff_t>(n / 2), norms.end());
    out.reference_field_norm = norms[static_cast<size_t>(n / 2)];
    CheckArgument(out.reference_field_norm > 0.0, "mag", "is zero");
    const Eigen::Vector3d mean_m = mag.topRows(std::min<Eigen::Index>(options.init_samples, n)).colwise().mean().transpose();
    const Eigen::Vector3d h = q * mean_m;  // levelled field
    CheckArgument(h.head<2>().norm() > 1e-9 * h.norm(), "mag", "the initial field is vertical: no heading");
    out.reference_dip_rad = std::atan2(h.z(), h.head<2>().norm());
    // Yaw so that the horizontal field points along +x.
    q = (Eigen::Quaterniond(Eigen::AngleAxisd(-std::atan2(h.y(), h.x()), Eigen::Vector3d::UnitZ())) * q).normalized();
  }
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  for (Eigen::Index k = 0; k < n; ++k) {
    if (k > 0) {
      const double dt = time_s[k] > time_s[k - 1] ? time_s[k] - time_s[k - 1] : median_dt;
      const Eigen::Matrix3d r = q.toRotationMatrix();
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      const Eigen::Vector3d f = acc.row(k).transpose();
      const double fn = f.norm();
      if (std::abs(fn - options.gravity_mps2) < options.acc_gate_mps2 && fn > 0.0) {
        const Eigen::Vector3d v_hat = r.transpose().col(2);  // Rᵀ e_z
        e += (f / fn).cross(v_hat);
      }
      Eigen::Vector3d e_mag = Eigen::Vector3d::Zero();
      if (use_mag) {
        const Eigen::Vector3d m = mag.row(k).transpose();
        const double mn = m.norm();
        bool ok = mn > 0.0 && std::abs(mn - out.reference_field_norm) < options.mag_norm_tolerance * out.reference_field_norm;
        if (ok) {
          const Eigen::Vector3d h = r * (m / mn);
          const double hxy = h.head<2>().norm();
          const double dip = std::atan2(h.z(), hxy);
          ok = std::abs(dip - out.reference_dip_rad) < options.mag_dip_tolerance_rad && hxy > 1e-9;
          if (ok) {
            // Heading-only correction (the gravity term owns roll and pitch): the predicted field
            // has no y component in the navigation frame, so the yaw error is atan2(h_y, h_x);
            // rotate back about the navigation z axis, i.e. about Rᵀ e_z in the body frame.
            e_mag = -std::atan2(h.y(), h.x()) * r.transpose().col(2);
          }
        }
        out.mag_used[k] = ok;
        if (!ok) ++out.mag_rejected;
      }
      bias += options.ki * (e + e_mag) * dt;  // integral term: the correction is −(bias estimate)
      const Eigen::Vector3d w = gyro.row(k).transpose() + bias + options.kp * e + options.kp_mag * e_mag;
      q = (q * ExpQ(w * dt)).normalized();
    }
    out.quaternions_wxyz.row(k) << q.w(), q.x(), q.y(), q.z();
    out.gyro_bias_radps.row(k) = -bias.transpose();
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace indoorloc::pdr
