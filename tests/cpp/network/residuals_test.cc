// Each residual of the network: automatic-differentiation Jacobians (on the quaternion manifold)
// against central numerical differentiation (tangent-space central differences), at random points.
#include <algorithm>
#include <random>
#include <vector>

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include "indoorloc/network/gravity.h"
#include "residuals.h"

namespace indoorloc::network::internal {
namespace {

ModelConstants Model() {
  ModelConstants m;
  m.earth_rate_enu = EarthRateEnu(0.72);
  const Eigen::Vector3d c = NormalGravityCoefficients(0.72);
  m.gamma0 = c[0];
  m.c1 = c[1];
  m.c2 = c[2];
  m.origin_height_m = 300.0;
  return m;
}

/// Random parameter blocks; sizes 4 are unit quaternions (x, y, z, w).
struct Params {
  std::vector<std::vector<double>> values;
  std::vector<const ceres::Manifold*> manifolds;
  std::vector<double*> pointers;
};

Params Make(const std::vector<int>& sizes, std::mt19937& rng, const ceres::Manifold* quaternion) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector4d base = Eigen::Vector4d(0.3, -0.5, 0.2, 0.8).normalized();
  Params p;
  for (int s : sizes) {
    std::vector<double> v(static_cast<size_t>(s));
    for (double& x : v) x = n(rng);
    if (s == 4) {
      // Attitudes of neighbouring epochs: a common rotation and small differences (the log map
      // of the relative rotation is smooth away from 180 degrees).
      Eigen::Map<Eigen::Vector4d> q(v.data());
      q = base + 0.05 * q;
      q.normalize();
      p.manifolds.push_back(quaternion);
    } else {
      p.manifolds.push_back(nullptr);
    }
    p.values.push_back(v);
  }
  for (auto& v : p.values) p.pointers.push_back(v.data());
  return p;
}

// Central differences in the tangent space (quaternions: ceres::EigenQuaternionManifold::Plus,
// vectors: x + δ) against the automatic-differentiation Jacobian times the manifold's
// PlusJacobian, relative to the largest entry of the residual's Jacobian.
void Check(const ceres::CostFunction& cost, const std::vector<int>& sizes, const char* name) {
  std::mt19937 rng(7);
  ceres::EigenQuaternionManifold quaternion;
  const int m = cost.num_residuals();
  for (int trial = 0; trial < 5; ++trial) {
    Params p = Make(sizes, rng, &quaternion);
    const size_t nb = sizes.size();
    std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> ambient(nb);
    std::vector<double*> jac(nb);
    for (size_t b = 0; b < nb; ++b) {
      ambient[b].resize(m, sizes[b]);
      jac[b] = ambient[b].data();
    }
    Eigen::VectorXd r0(m);
    ASSERT_TRUE(cost.Evaluate(p.pointers.data(), r0.data(), jac.data())) << name;
    std::vector<Eigen::MatrixXd> analytic(nb), numeric(nb);
    double scale = 0.0;
    for (size_t b = 0; b < nb; ++b) {
      const bool is_q = sizes[b] == 4;
      const int t = is_q ? 3 : sizes[b];
      Eigen::MatrixXd plus_jacobian = Eigen::MatrixXd::Identity(sizes[b], t);
      if (is_q) {
        Eigen::Matrix<double, 4, 3, Eigen::RowMajor> pj;
        quaternion.PlusJacobian(p.values[b].data(), pj.data());
        plus_jacobian = pj;
      }
      analytic[b] = ambient[b] * plus_jacobian;
      numeric[b].resize(m, t);
      const std::vector<double> x0 = p.values[b];
      for (int k = 0; k < t; ++k) {
        Eigen::VectorXd rp(m), rm(m);
        for (int sign : {1, -1}) {
          Eigen::VectorXd delta = Eigen::VectorXd::Zero(t);
          delta[k] = sign * 1e-6;
          if (is_q) quaternion.Plus(x0.data(), delta.data(), p.values[b].data());
          else for (int i = 0; i < t; ++i) p.values[b][i] = x0[i] + delta[i];
          ASSERT_TRUE(cost.Evaluate(p.pointers.data(), (sign > 0 ? rp : rm).data(), nullptr));
        }
        p.values[b] = x0;
        numeric[b].col(k) = (rp - rm) / 2e-6;
      }
      scale = std::max(scale, numeric[b].cwiseAbs().maxCoeff());
    }
    ASSERT_GT(scale, 0.0) << name;
    for (size_t b = 0; b < nb; ++b) {
      const double err = (analytic[b] - numeric[b]).cwiseAbs().maxCoeff();
      EXPECT_LT(err, 1e-6 * scale) << name << " block " << b << "\n" << analytic[b] << "\nvs\n" << numeric[b];
    }
  }
}

template <typename F, int kRes, int... kSizes>
void CheckFunctor(const F& f, const char* name) {
  ceres::AutoDiffCostFunction<F, kRes, kSizes...> cost(new F(f));
  Check(cost, {kSizes...}, name);
}

TEST(NetworkResiduals, JacobiansMatchNumericalDifferentiation) {
  const ModelConstants m = Model();
  const Eigen::Vector3d f(0.3, -0.2, 9.9), w(0.01, -0.02, 0.05);
  CheckFunctor<VelLeapFrog, 3, 3, 3, 3>({0.04, 100.0}, "VelLeapFrog");
  CheckFunctor<VelTrapezoidal, 3, 3, 3, 3, 3>({0.02, 100.0}, "VelTrapezoidal");
  CheckFunctor<FbLeapFrog, 3, 3, 3, 3, 4, 3, 3, 1>({m, f, 0.04, 10.0}, "FbLeapFrog");
  CheckFunctor<FbTrapezoidal, 3, 3, 3, 4, 4, 3, 3, 3, 3, 1, 1>({m, f, f + w, 0.02, 10.0}, "FbTrapezoidal");
  CheckFunctor<WibLeapFrog, 3, 4, 4, 4, 3>({m.earth_rate_enu, w, 0.04, 100.0}, "WibLeapFrog");
  CheckFunctor<WibTrapezoidal, 3, 4, 4, 3, 3>({m.earth_rate_enu, w, 0.02, 100.0}, "WibTrapezoidal");
  CheckFunctor<RandomWalk<3>, 3, 3, 3>({1e3}, "RandomWalk<3>");
  CheckFunctor<RandomWalk<1>, 1, 1, 1>({1e3}, "RandomWalk<1>");
  CheckFunctor<GaussMarkov<3>, 3, 3, 3>({0.99, 1e3}, "GaussMarkov<3>");
  CheckFunctor<Cupt, 3, 3>({Eigen::Vector3d(1, 2, 3), 50.0}, "Cupt");
  CheckFunctor<CuptInterpolated, 3, 3, 3>({Eigen::Vector3d(1, 2, 3), 0.3, 50.0}, "CuptInterpolated");
  CheckFunctor<Zupt, 3, 3>({1e3}, "Zupt");
  CheckFunctor<Gupt, 1, 3, 1>({m, 9.8, 1e5}, "Gupt");
  CheckFunctor<Xover, 1, 1, 1>({1e5}, "Xover");
  CheckFunctor<Vupt, 3, 3>({Eigen::Vector3d(50, -3, 0.5), 1e2}, "Vupt");
  CheckFunctor<Sgupt, 1, 1, 1>({1e6}, "Sgupt");
  CheckFunctor<FbTrapezoidalShared, 3, 3, 3, 4, 4, 3, 3, 3, 1>({FbTrapezoidal{m, f, f + w, 0.02, 10.0}},
                                                                 "FbTrapezoidalShared");
  CheckFunctor<WibTrapezoidalShared, 3, 4, 4, 3>({WibTrapezoidal{m.earth_rate_enu, w, 0.02, 100.0}},
                                                   "WibTrapezoidalShared");
}

TEST(NetworkResiduals, RelativeRotationIsTheLogOfTheRelativeQuaternion) {
  const Eigen::Quaterniond a = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  const Eigen::Vector3d phi(0.01, -0.02, 0.03);
  const Eigen::Quaterniond b = a * Eigen::Quaterniond(Eigen::AngleAxisd(phi.norm(), phi.normalized()));
  const Eigen::Vector3d got = RelativeRotationVector(a.coeffs().data(), b.coeffs().data());
  EXPECT_LT((got - phi).norm(), 1e-12);
  // -b is the same rotation.
  const Eigen::Quaterniond nb(-b.w(), -b.x(), -b.y(), -b.z());
  EXPECT_LT((RelativeRotationVector(a.coeffs().data(), nb.coeffs().data()) - phi).norm(), 1e-12);
}

}  // namespace
}  // namespace indoorloc::network::internal
