// Private parts of the linearised INS network (linear_ins_network.cc) that its orthogonal solve
// (linear_ins_network_qr.cc) shares: the error dynamics, the row weights, the dynamic equation
// stencil, the GPS epochs and the scorer against the noise-free truth. Not installed.
#ifndef INDOORLOC_SRC_NETWORK_LINEAR_INS_NETWORK_INTERNAL_H_
#define INDOORLOC_SRC_NETWORK_LINEAR_INS_NETWORK_INTERNAL_H_

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/network/linear_ins_network.h"

namespace indoorloc::network::internal {

constexpr int kP = 18;  // unknowns per epoch
using Mat18 = Eigen::Matrix<double, kP, kP>;
using Vec18 = Eigen::Matrix<double, kP, 1>;

// Continuous error dynamics ẋ = F x (see the header).
Mat18 Dynamics(const LinearInsNetworkOptions& o);

// Per-row weights δt / density² of the dynamic equations (unknown order of the header).
Vec18 RowWeights(const LinearInsNetworkOptions& o);

// One dynamic equation type: coefficient blocks on epochs n + offset[k].
struct Stencil {
  std::vector<int> offsets;
  std::vector<Mat18> J;
  int first_center = 0;  // valid centres n: first_center .. E - 2
};

Stencil MakeStencil(const LinearInsNetworkOptions& o);

// IMU epochs between GPS fixes (>= 1).
long long GpsStep(const LinearInsNetworkOptions& o);

// GPS epoch k (alternating parity for an even step, see linear_ins_network.cc).
long long GpsEpoch(long long k, long long step);

bool IsGpsEpoch(long long n, long long step);

// Scores a solution against the noise-free truth (LinearInsTruth), epoch by epoch in any order:
// the largest error of any unknown (and its epoch), the largest per unknown, the δg RMSE; keeps
// the δg estimate when asked. One scorer for every solver of the linearised network.
class TruthScore {
 public:
  TruthScore(long long epochs, double imu_rate_hz, Eigen::MatrixXd* gravity_estimate)
      : epochs_(epochs), imu_rate_hz_(imu_rate_hz), gravity_estimate_(gravity_estimate) {
    if (gravity_estimate_ != nullptr) gravity_estimate_->resize(epochs, 3);
  }
  void Add(long long epoch, const Eigen::Ref<const Vec18>& x) {
    const Vec18 error = (x - LinearInsTruth(epoch, imu_rate_hz_)).cwiseAbs();
    if (error.maxCoeff() > max_error_) {
      max_error_ = error.maxCoeff();
      max_error_epoch_ = epoch;
    }
    by_unknown_ = by_unknown_.cwiseMax(error);
    gravity_sq_ += error.tail<3>().squaredNorm();
    if (gravity_estimate_ != nullptr) gravity_estimate_->row(epoch) = x.tail<3>().transpose();
  }
  double max_error() const { return max_error_; }
  double gravity_rmse() const { return std::sqrt(gravity_sq_ / (3.0 * static_cast<double>(epochs_))); }
  void Write(LinearInsNetworkResult* result) const {
    result->max_abs_error = max_error_;
    result->max_abs_error_epoch = max_error_epoch_;
    result->max_abs_error_by_unknown = by_unknown_;
    result->gravity_rmse = gravity_rmse();
  }

 private:
  long long epochs_;
  double imu_rate_hz_;
  Eigen::MatrixXd* gravity_estimate_;
  double max_error_ = 0.0, gravity_sq_ = 0.0;
  long long max_error_epoch_ = -1;
  Vec18 by_unknown_ = Vec18::Zero();
};

}  // namespace indoorloc::network::internal

#endif  // INDOORLOC_SRC_NETWORK_LINEAR_INS_NETWORK_INTERNAL_H_
