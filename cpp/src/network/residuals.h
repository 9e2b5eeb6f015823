// Residual functors of the INS/GPS network (private: Ceres types). Each is templated for
// automatic differentiation and tested against numerical differentiation
// (tests/cpp/network/residuals_test.cc). Quaternion blocks are stored as Eigen does
// (x, y, z, w) and live on ceres::EigenQuaternionManifold. Every residual is already divided by
// its standard deviation (whitened). Equations: network_adjustment.h and docs/network.md.
#pragma once

#include <ceres/rotation.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace indoorloc::network::internal {

/// Model constants shared by the dynamic residuals.
struct ModelConstants {
  Eigen::Vector3d earth_rate_enu = Eigen::Vector3d::Zero();  ///< ω_ie [rad/s]
  double gamma0 = 9.80;   ///< γ(h) = gamma0 (1 - c1 h + c2 h^2)
  double c1 = 0.0;
  double c2 = 0.0;
  double origin_height_m = 0.0;

  template <typename T>
  T Gamma(const T& up_m) const {
    const T h = up_m + T(origin_height_m);
    return T(gamma0) * (T(1.0) - T(c1) * h + T(c2) * h * h);
  }
  /// g = (0, 0, -(γ(h) + δg))
  template <typename T>
  Eigen::Matrix<T, 3, 1> Gravity(const T& up_m, const T& dg) const {
    return Eigen::Matrix<T, 3, 1>(T(0.0), T(0.0), -(Gamma(up_m) + dg));
  }
};

template <typename T>
Eigen::Matrix<T, 3, 1> Cross(const Eigen::Vector3d& a, const Eigen::Matrix<T, 3, 1>& b) {
  return a.cast<T>().cross(b);
}

/// Log(qa⁻¹ qb) as a rotation vector (quaternions in Eigen's x, y, z, w storage).
template <typename T>
Eigen::Matrix<T, 3, 1> RelativeRotationVector(const T* qa_xyzw, const T* qb_xyzw) {
  Eigen::Map<const Eigen::Quaternion<T>> qa(qa_xyzw), qb(qb_xyzw);
  const Eigen::Quaternion<T> d = qa.conjugate() * qb;
  const T wxyz[4] = {d.w(), d.x(), d.y(), d.z()};
  Eigen::Matrix<T, 3, 1> aa;
  ceres::QuaternionToAngleAxis(wxyz, aa.data());
  return aa;
}

/// VEL, leap-frog at epoch n: (v[n] - (r[n+1] - r[n-1]) / 2δt) / σ.
struct VelLeapFrog {
  double two_dt, inv_sigma;
  template <typename T>
  bool operator()(const T* r_prev, const T* r_next, const T* v, T* res) const {
    for (int i = 0; i < 3; ++i) res[i] = (v[i] - (r_next[i] - r_prev[i]) / T(two_dt)) * T(inv_sigma);
    return true;
  }
};

/// VEL, trapezoidal on [n, n+1]: ((v[n] + v[n+1]) / 2 - (r[n+1] - r[n]) / δt) / σ.
struct VelTrapezoidal {
  double dt, inv_sigma;
  template <typename T>
  bool operator()(const T* r0, const T* r1, const T* v0, const T* v1, T* res) const {
    for (int i = 0; i < 3; ++i) res[i] = (T(0.5) * (v0[i] + v1[i]) - (r1[i] - r0[i]) / T(dt)) * T(inv_sigma);
    return true;
  }
};

/// FB, leap-frog at epoch n (body frame):
/// (R(q[n])ᵀ (Λ(v) + 2 ω_ie × v[n] - g(r[n], δg[n])) + a[n] - f[n]) / σ_f.
struct FbLeapFrog {
  ModelConstants model;
  Eigen::Vector3d f_body;
  double two_dt, inv_sigma;
  template <typename T>
  bool operator()(const T* v_prev, const T* v_next, const T* v, const T* q, const T* r, const T* ab, const T* dg,
                  T* res) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    Eigen::Map<const V3> vp(v_prev), vn(v_next), vc(v), a(ab);
    Eigen::Map<const Eigen::Quaternion<T>> qb(q);
    const V3 lambda_v = (vn - vp) / T(two_dt);
    const V3 rhs_enu = lambda_v + T(2.0) * Cross(model.earth_rate_enu, V3(vc)) - model.Gravity(r[2], dg[0]);
    const V3 e = qb.conjugate() * rhs_enu + a - f_body.cast<T>();
    for (int i = 0; i < 3; ++i) res[i] = e[i] * T(inv_sigma);
    return true;
  }
};

/// FB, trapezoidal on [n, n+1] (ENU frame):
/// (½ Σ_i R(q_i)(f_i - a_i) - (Λ(v) + ω_ie × (v0 + v1) - ½ (g0 + g1))) / σ_f.
struct FbTrapezoidal {
  ModelConstants model;
  Eigen::Vector3d f0_body, f1_body;
  double dt, inv_sigma;
  template <typename T>
  bool operator()(const T* v0, const T* v1, const T* q0, const T* q1, const T* r0, const T* r1, const T* a0,
                  const T* a1, const T* dg0, const T* dg1, T* res) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    Eigen::Map<const V3> va(v0), vb(v1), ba0(a0), ba1(a1);
    Eigen::Map<const Eigen::Quaternion<T>> qa(q0), qb(q1);
    const V3 sf = T(0.5) * (qa * V3(f0_body.cast<T>() - ba0) + qb * V3(f1_body.cast<T>() - ba1));
    const V3 lambda_v = (vb - va) / T(dt);
    const V3 rhs = lambda_v + Cross(model.earth_rate_enu, V3(va + vb)) -
                   T(0.5) * (model.Gravity(r0[2], dg0[0]) + model.Gravity(r1[2], dg1[0]));
    const V3 e = sf - rhs;
    for (int i = 0; i < 3; ++i) res[i] = e[i] * T(inv_sigma);
    return true;
  }
};

/// FB, trapezoidal on [n, n+1] with slow parameters (slow_parameter_stride > 1) when both epochs
/// fall in one slow interval: a[n] = a[n+1] = a, δg[n] = δg[n+1] = δg share one block (Ceres
/// forbids passing a block twice to one residual).
struct FbTrapezoidalShared {
  FbTrapezoidal fb;
  template <typename T>
  bool operator()(const T* v0, const T* v1, const T* q0, const T* q1, const T* r0, const T* r1, const T* a,
                  const T* dg, T* res) const {
    return fb(v0, v1, q0, q1, r0, r1, a, a, dg, dg, res);
  }
};

/// WIB, leap-frog at epoch n (body frame):
/// (Log(q[n-1]⁻¹ q[n+1]) / 2δt + R(q[n])ᵀ ω_ie + o[n] - ω[n]) / σ_ω.
struct WibLeapFrog {
  Eigen::Vector3d earth_rate_enu, w_body;
  double two_dt, inv_sigma;
  template <typename T>
  bool operator()(const T* q_prev, const T* q_next, const T* q, const T* ob, T* res) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    Eigen::Map<const Eigen::Quaternion<T>> qc(q);
    Eigen::Map<const V3> o(ob);
    const V3 e = RelativeRotationVector(q_prev, q_next) / T(two_dt) + qc.conjugate() * V3(earth_rate_enu.cast<T>()) +
                 o - w_body.cast<T>();
    for (int i = 0; i < 3; ++i) res[i] = e[i] * T(inv_sigma);
    return true;
  }
};

/// WIB, trapezoidal on [n, n+1]:
/// (Log(q[n]⁻¹ q[n+1]) / δt + ½ (R0ᵀ + R1ᵀ) ω_ie + ½ (o0 + o1) - ½ (ω0 + ω1)) / σ_ω.
struct WibTrapezoidal {
  Eigen::Vector3d earth_rate_enu, w_mean_body;
  double dt, inv_sigma;
  template <typename T>
  bool operator()(const T* q0, const T* q1, const T* o0, const T* o1, T* res) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    Eigen::Map<const Eigen::Quaternion<T>> qa(q0), qb(q1);
    Eigen::Map<const V3> oa(o0), ob(o1);
    const V3 wie = earth_rate_enu.cast<T>();
    const V3 e = RelativeRotationVector(q0, q1) / T(dt) + T(0.5) * (qa.conjugate() * wie + qb.conjugate() * wie) +
                 T(0.5) * (oa + ob) - w_mean_body.cast<T>();
    for (int i = 0; i < 3; ++i) res[i] = e[i] * T(inv_sigma);
    return true;
  }
};

/// WIB, trapezoidal, both epochs in one slow interval: o[n] = o[n+1] = o (see FbTrapezoidalShared).
struct WibTrapezoidalShared {
  WibTrapezoidal wib;
  template <typename T>
  bool operator()(const T* q0, const T* q1, const T* o, T* res) const {
    return wib(q0, q1, o, o, res);
  }
};

/// AB, OB, GDT: random walk (x_b - x_a) / (q √Δt).
template <int kDim>
struct RandomWalk {
  double inv_sigma;
  template <typename T>
  bool operator()(const T* xa, const T* xb, T* res) const {
    for (int i = 0; i < kDim; ++i) res[i] = (xb[i] - xa[i]) * T(inv_sigma);
    return true;
  }
};

/// AB, OB as first-order Gauss-Markov: (x_b - φ x_a) / σ, φ = exp(-Δt/τ).
template <int kDim>
struct GaussMarkov {
  double phi, inv_sigma;
  template <typename T>
  bool operator()(const T* xa, const T* xb, T* res) const {
    for (int i = 0; i < kDim; ++i) res[i] = (xb[i] - T(phi) * xa[i]) * T(inv_sigma);
    return true;
  }
};

/// CUPT between two epochs: ((1 - α) r[a] + α r[b] - p_gps) / σ.
struct CuptInterpolated {
  Eigen::Vector3d p_gps;
  double alpha, inv_sigma;
  template <typename T>
  bool operator()(const T* ra, const T* rb, T* res) const {
    for (int i = 0; i < 3; ++i)
      res[i] = ((T(1.0) - T(alpha)) * ra[i] + T(alpha) * rb[i] - T(p_gps[i])) * T(inv_sigma);
    return true;
  }
};

/// CUPT at an epoch: (r[n] - p_gps) / σ.
struct Cupt {
  Eigen::Vector3d p_gps;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* r, T* res) const {
    for (int i = 0; i < 3; ++i) res[i] = (r[i] - T(p_gps[i])) * T(inv_sigma);
    return true;
  }
};

/// ZUPT: v[n] / σ.
struct Zupt {
  double inv_sigma;
  template <typename T>
  bool operator()(const T* v, T* res) const {
    for (int i = 0; i < 3; ++i) res[i] = v[i] * T(inv_sigma);
    return true;
  }
};

/// VUPT: (v[n] - v0) / σ (paper §3.4: v0 + w_v = v^e[n]).
struct Vupt {
  Eigen::Vector3d v0;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* v, T* res) const {
    for (int i = 0; i < 3; ++i) res[i] = (v[i] - T(v0[i])) * T(inv_sigma);
    return true;
  }
};

/// SGUPT: (δg[n] - δg[n0]) / σ, n0 the first epoch of the static period containing n (paper
/// §3.2: constant gravity during a ZUPT period, "seen as a XOVER observation").
struct Sgupt {
  double inv_sigma;
  template <typename T>
  bool operator()(const T* dg_first, const T* dg, T* res) const {
    res[0] = (dg[0] - dg_first[0]) * T(inv_sigma);
    return true;
  }
};

/// GUPT: (γ(h[n]) + δg[n] - g0) / σ.
struct Gupt {
  ModelConstants model;
  double g0, inv_sigma;
  template <typename T>
  bool operator()(const T* r, const T* dg, T* res) const {
    res[0] = (model.Gamma(r[2]) + dg[0] - T(g0)) * T(inv_sigma);
    return true;
  }
};

/// XOVER: (δg[n] - δg[k]) / σ.
struct Xover {
  double inv_sigma;
  template <typename T>
  bool operator()(const T* dga, const T* dgb, T* res) const {
    res[0] = (dga[0] - dgb[0]) * T(inv_sigma);
    return true;
  }
};

}  // namespace indoorloc::network::internal
