// The network adjustment's Ceres problem (private to cpp/src/network): the parameter storage of
// the whole network (Blocks), the Jacobian's column layout, and the steps that build the problem
// (network_problem.cc) before network_adjustment.cc checks its datum, solves it and computes the
// precision.
#pragma once

#include <cmath>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/Dense>

#include "indoorloc/core/check.h"
#include "indoorloc/network/network_adjustment.h"
#include "residuals.h"

namespace indoorloc::network::adjustment {

/// Parameter storage of the whole network: r, v, q per IMU epoch; a, o, δg per slow node
/// (one per `stride` epochs; stride 1: per epoch).
struct Blocks {
  int n = 0;       // IMU epochs
  int stride = 1;  // slow_parameter_stride
  int m = 0;       // slow nodes ⌈n / stride⌉
  std::vector<double> r, v, q, a, o, dg;  // q in x, y, z, w
  int Slow(int epoch) const { return epoch / stride; }
  double* R(int i) { return &r[3 * i]; }
  double* V(int i) { return &v[3 * i]; }
  double* Q(int i) { return &q[4 * i]; }
  double* A(int k) { return &a[3 * k]; }  // slow node k
  double* O(int k) { return &o[3 * k]; }
  double* G(int k) { return &dg[k]; }
  /// First and one-past-last epoch of slow node k.
  int First(int k) const { return k * stride; }
  // In 64 bits: a stride near 2**31 would overflow (and abort inside Ceres).
  int End(int k) const { return static_cast<int>(std::min<long long>((k + 1LL) * stride, n)); }
};

inline Blocks FromState(const NetworkState& s, int stride) {
  Blocks b;
  b.n = static_cast<int>(s.position_m.rows());
  b.stride = stride;
  b.m = b.n == 0 ? 0 : 1 + (b.n - 1) / stride;  // ⌈n / stride⌉ without overflowing n + stride
  b.r.resize(3 * b.n);
  b.v.resize(3 * b.n);
  b.q.resize(4 * b.n);
  b.a.assign(3 * b.m, 0.0);
  b.o.assign(3 * b.m, 0.0);
  b.dg.assign(b.m, 0.0);
  for (int i = 0; i < b.n; ++i) {
    for (int k = 0; k < 3; ++k) {
      b.r[3 * i + k] = s.position_m(i, k);
      b.v[3 * i + k] = s.velocity_mps(i, k);
    }
    Eigen::Quaterniond q(s.attitude_wxyz(i, 0), s.attitude_wxyz(i, 1), s.attitude_wxyz(i, 2), s.attitude_wxyz(i, 3));
    q.normalize();
    b.q[4 * i + 0] = q.x();
    b.q[4 * i + 1] = q.y();
    b.q[4 * i + 2] = q.z();
    b.q[4 * i + 3] = q.w();
  }
  // Slow blocks: the mean of the initial values over the interval.
  for (int k = 0; k < b.m; ++k) {
    const int first = b.First(k), count = b.End(k) - first;
    for (int c = 0; c < 3; ++c) {
      b.a[3 * k + c] = s.acc_bias_mps2.col(c).segment(first, count).mean();
      b.o[3 * k + c] = s.gyro_bias_radps.col(c).segment(first, count).mean();
    }
    b.dg[k] = s.gravity_disturbance_mps2.segment(first, count).mean();
  }
  return b;
}

inline NetworkState ToState(const Blocks& b) {
  NetworkState s;
  s.position_m.resize(b.n, 3);
  s.velocity_mps.resize(b.n, 3);
  s.attitude_wxyz.resize(b.n, 4);
  s.acc_bias_mps2.resize(b.n, 3);
  s.gyro_bias_radps.resize(b.n, 3);
  s.gravity_disturbance_mps2.resize(b.n);
  for (int i = 0; i < b.n; ++i) {
    const int k = b.Slow(i);
    for (int c = 0; c < 3; ++c) {
      s.position_m(i, c) = b.r[3 * i + c];
      s.velocity_mps(i, c) = b.v[3 * i + c];
      s.acc_bias_mps2(i, c) = b.a[3 * k + c];
      s.gyro_bias_radps(i, c) = b.o[3 * k + c];
    }
    s.attitude_wxyz(i, 0) = b.q[4 * i + 3];
    s.attitude_wxyz(i, 1) = b.q[4 * i + 0];
    s.attitude_wxyz(i, 2) = b.q[4 * i + 1];
    s.attitude_wxyz(i, 3) = b.q[4 * i + 2];
    s.gravity_disturbance_mps2[i] = b.dg[k];
  }
  return s;
}

/// What a column of the (tangent-space) Jacobian is: block name and epoch (slow blocks: the
/// first epoch of their interval), for the datum-defect message.
struct ColumnLabel {
  const char* name;
  int epoch;
};

template <typename Functor, int kRes, int... kSizes>
inline ceres::CostFunction* Auto(Functor f) {
  return new ceres::AutoDiffCostFunction<Functor, kRes, kSizes...>(new Functor(f));
}

/// AB / OB residual over a step dt: random walk (tau = 0) or Gauss-Markov.
inline ceres::CostFunction* BiasModel(double q, double tau, double step) {
  if (tau <= 0.0)
    return new ceres::AutoDiffCostFunction<internal::RandomWalk<3>, 3, 3, 3>(
        new internal::RandomWalk<3>{1.0 / (q * std::sqrt(step))});
  const double phi = std::exp(-step / tau);
  const double sigma = q * std::sqrt(0.5 * tau * (1.0 - phi * phi));
  return new ceres::AutoDiffCostFunction<internal::GaussMarkov<3>, 3, 3, 3>(
      new internal::GaussMarkov<3>{phi, 1.0 / sigma});
}

inline void CheckEpochs(const Eigen::VectorXi& epochs, int n, const char* name) {
  for (Eigen::Index i = 0; i < epochs.size(); ++i)
    CheckArgument(epochs[i] >= 0 && epochs[i] < n, name,
                  "entry " + std::to_string(i) + " = " + std::to_string(epochs[i]) + " is not an epoch in [0, " +
                      std::to_string(n) + ")");
}


/// A CUPT (GPS) epoch tied to the IMU epochs: p(t) = (1 - alpha) r[a] + alpha r[a + 1].
struct GpsTie {
  int a;
  double alpha;
};
/// The unknowns of the network, in the Jacobian's column order (datum check, dense inverse): per
/// epoch r, v, q and, at the first epoch of each slow interval, that interval's a, o, δg.
struct ParameterLayout {
  std::vector<double*> ordered_blocks;
  std::vector<ColumnLabel> labels;  ///< names each tangent column
  std::vector<int> gravity_column;  ///< per slow node: the column of its δg
};
/// The residual blocks of the three groups whose variance factors the summary can report.
struct ResidualGroups {
  std::vector<ceres::ResidualBlockId> acc, gyro, gps;
};
/// Counts of the observations that become residuals only for some inputs.
struct StaticCounts {
  int num_xover = 0;
  int num_sgupt = 0;
};

/// Ties every GPS time to the IMU epochs (n epochs dt [s] apart); with leap-frog, throws when
/// the CUPTs leave one parity chain without a position datum.
std::vector<GpsTie> TieGpsToEpochs(const NetworkObservations& obs, int n, double dt, bool leap);
/// Earth rate and normal gravity at the options' latitude and origin height.
internal::ModelConstants MakeModelConstants(const NetworkOptions& options);
/// Adds every unknown to the problem in the Jacobian's column order.
ParameterLayout AddParameterBlocks(Blocks& b, int n, ceres::Manifold* quaternion_manifold, ceres::Problem& problem);
/// The dynamics: velocity, specific-force and angular-rate conditions between epochs (leap-frog
/// or trapezoidal) and the random walks of the biases and δg.
void AddDynamics(const NetworkObservations& obs, const NetworkOptions& options, const internal::ModelConstants& model,
                 double dt, Blocks& b, ceres::Problem& problem, ResidualGroups* groups);
/// The static observations: CUPT (GPS), ZUPT, VUPT, GUPT, XOVER and SGUPT.
StaticCounts AddStaticObservations(const NetworkObservations& obs, const NetworkOptions& options,
                                   const internal::ModelConstants& model, const std::vector<GpsTie>& ties, Blocks& b,
                                   ceres::Problem& problem, ResidualGroups* groups);

}  // namespace indoorloc::network::adjustment
