// Building the network adjustment's Ceres problem: the GPS ties, the unknowns in the Jacobian's
// column order, the dynamics (leap-frog or trapezoidal) and the static observations (CUPT, ZUPT,
// VUPT, GUPT, XOVER, SGUPT). See docs/network.md.
#include <algorithm>
#include <string>

#include "indoorloc/network/gravity.h"
#include "network_problem.h"

namespace indoorloc::network::adjustment {

/// Ties every GPS time to the IMU epochs (n epochs dt [s] apart); with leap-frog, throws when
/// the CUPTs leave one parity chain without a position datum.
std::vector<GpsTie> TieGpsToEpochs(const NetworkObservations& obs, int n, double dt, bool leap) {
  std::vector<GpsTie> ties;
  bool parity_has_cupt[2] = {false, false};
  for (Eigen::Index i = 0; i < obs.gps_time_s.size(); ++i) {
    const double u = (obs.gps_time_s[i] - obs.imu_time_s[0]) / dt;
    int a = std::clamp(static_cast<int>(std::floor(u)), 0, n - 2);
    double alpha = u - a;
    if (alpha < 1e-9) alpha = 0.0;
    if (alpha > 1.0 - 1e-9) {
      a += 1;
      alpha = 0.0;
      if (a == n - 1) {  // the last epoch: tie as (n-2, α = 1)
        a = n - 2;
        alpha = 1.0;
      }
    }
    ties.push_back({a, alpha});
    if (alpha < 1.0) parity_has_cupt[a % 2] = true;
    if (alpha > 0.0) parity_has_cupt[(a + 1) % 2] = true;
  }
  if (leap)
    CheckArgument(parity_has_cupt[0] && parity_has_cupt[1], "gps_time_s",
                  std::string("datum defect of the leap-frog network: every CUPT falls on ") +
                      (parity_has_cupt[0] ? "even" : "odd") + " epochs, so the " +
                      (parity_has_cupt[0] ? "odd" : "even") +
                      "-epoch chain has no position datum (leap-frog couples only epochs of equal parity); "
                      "use the trapezoidal discretisation or GPS times on both parities");
  return ties;
}

/// Earth rate and normal gravity at the options' latitude and origin height.
internal::ModelConstants MakeModelConstants(const NetworkOptions& options) {
  internal::ModelConstants model;
  model.earth_rate_enu = EarthRateEnu(options.latitude_rad) * (options.earth_rate_radps / kEarthRateRadps);
  const Eigen::Vector3d gc = NormalGravityCoefficients(options.latitude_rad);
  model.gamma0 = gc[0];
  model.c1 = gc[1];
  model.c2 = gc[2];
  model.origin_height_m = options.origin_height_m;
  return model;
}


ParameterLayout AddParameterBlocks(Blocks& b, int n, ceres::Manifold* quaternion_manifold, ceres::Problem& problem) {
  const int stride = b.stride, m_slow = b.m;
  ParameterLayout layout;
  std::vector<double*>& ordered_blocks = layout.ordered_blocks;
  std::vector<ColumnLabel>& labels = layout.labels;
  std::vector<int>& gravity_column = layout.gravity_column;
  ordered_blocks.reserve(3 * n + 3 * m_slow);
  labels.reserve(9 * n + 7 * m_slow);
  gravity_column.resize(static_cast<size_t>(m_slow));
  for (int i = 0; i < n; ++i) {
    problem.AddParameterBlock(b.R(i), 3);
    problem.AddParameterBlock(b.V(i), 3);
    problem.AddParameterBlock(b.Q(i), 4, quaternion_manifold);
    for (double* p : {b.R(i), b.V(i), b.Q(i)}) ordered_blocks.push_back(p);
    for (const char* name : {"position", "velocity", "attitude"})
      for (int c = 0; c < 3; ++c) labels.push_back({name, i});
    if (i % stride == 0) {
      const int k = b.Slow(i);
      problem.AddParameterBlock(b.A(k), 3);
      problem.AddParameterBlock(b.O(k), 3);
      problem.AddParameterBlock(b.G(k), 1);
      for (double* p : {b.A(k), b.O(k), b.G(k)}) ordered_blocks.push_back(p);
      for (const char* name : {"acc_bias", "gyro_bias"})
        for (int c = 0; c < 3; ++c) labels.push_back({name, i});
      gravity_column[static_cast<size_t>(k)] = static_cast<int>(labels.size());
      labels.push_back({"gravity_disturbance", i});
    }
  }
  return layout;
}


/// The dynamics: velocity, specific-force and angular-rate conditions between epochs (leap-frog
/// or trapezoidal) and the random walks of the biases and δg.
void AddDynamics(const NetworkObservations& obs, const NetworkOptions& options, const internal::ModelConstants& model,
                 double dt, Blocks& b, ceres::Problem& problem, ResidualGroups* groups) {
  const int n = static_cast<int>(obs.imu_time_s.size());
  const int stride = b.stride, m_slow = b.m;
  const bool leap = options.discretization == Discretization::kLeapFrog;
  std::vector<ceres::ResidualBlockId>& acc_ids = groups->acc;
  std::vector<ceres::ResidualBlockId>& gyro_ids = groups->gyro;
  const double sigma_f = options.acc_noise_mps2_rthz / std::sqrt(dt);
  const double sigma_w = options.gyro_noise_radps_rthz / std::sqrt(dt);
  auto f_at = [&](int i) { return Eigen::Vector3d(obs.acc_body_mps2.row(i).transpose()); };
  auto w_at = [&](int i) { return Eigen::Vector3d(obs.gyro_body_radps.row(i).transpose()); };
  // AB, OB, GDT between two slow nodes (or epochs) over `step` seconds.
  auto add_random_walks = [&](int ka, int kb, double step) {
    problem.AddResidualBlock(BiasModel(options.acc_bias_walk_mps2_rts, options.acc_bias_correlation_time_s, step),
                             nullptr, b.A(ka), b.A(kb));
    problem.AddResidualBlock(BiasModel(options.gyro_bias_walk_radps_rts, options.gyro_bias_correlation_time_s, step),
                             nullptr, b.O(ka), b.O(kb));
    problem.AddResidualBlock(
        Auto<internal::RandomWalk<1>, 1, 1, 1>({1.0 / (options.gravity_walk_mps2_rts * std::sqrt(step))}), nullptr,
        b.G(ka), b.G(kb));
  };
  if (leap) {
    const double step = 2.0 * dt;
    for (int i = 1; i + 1 < n; ++i) {
      const int k = b.Slow(i);
      problem.AddResidualBlock(Auto<internal::VelLeapFrog, 3, 3, 3, 3>({step, 1.0 / options.sigma_vel_mps}), nullptr,
                               b.R(i - 1), b.R(i + 1), b.V(i));
      acc_ids.push_back(problem.AddResidualBlock(
          Auto<internal::FbLeapFrog, 3, 3, 3, 3, 4, 3, 3, 1>({model, f_at(i), step, 1.0 / sigma_f}), nullptr,
          b.V(i - 1), b.V(i + 1), b.V(i), b.Q(i), b.R(i), b.A(k), b.G(k)));
      gyro_ids.push_back(problem.AddResidualBlock(
          Auto<internal::WibLeapFrog, 3, 4, 4, 4, 3>({model.earth_rate_enu, w_at(i), step, 1.0 / sigma_w}), nullptr,
          b.Q(i - 1), b.Q(i + 1), b.Q(i), b.O(k)));
      // Stride 1: the paper's Λ(a, n) = (a[n+1] - a[n-1]) / 2δt (two interleaved bias chains).
      if (stride == 1) add_random_walks(i - 1, i + 1, step);
    }
  } else {
    for (int i = 0; i + 1 < n; ++i) {
      const int ka = b.Slow(i), kb = b.Slow(i + 1);
      problem.AddResidualBlock(Auto<internal::VelTrapezoidal, 3, 3, 3, 3, 3>({dt, 1.0 / options.sigma_vel_mps}),
                               nullptr, b.R(i), b.R(i + 1), b.V(i), b.V(i + 1));
      const internal::FbTrapezoidal fb{model, f_at(i), f_at(i + 1), dt, 1.0 / sigma_f};
      const internal::WibTrapezoidal wib{model.earth_rate_enu, 0.5 * (w_at(i) + w_at(i + 1)), dt, 1.0 / sigma_w};
      if (ka == kb) {  // both epochs in one slow interval: one a, o, δg block
        acc_ids.push_back(problem.AddResidualBlock(
            Auto<internal::FbTrapezoidalShared, 3, 3, 3, 4, 4, 3, 3, 3, 1>({fb}), nullptr, b.V(i), b.V(i + 1),
            b.Q(i), b.Q(i + 1), b.R(i), b.R(i + 1), b.A(ka), b.G(ka)));
        gyro_ids.push_back(problem.AddResidualBlock(Auto<internal::WibTrapezoidalShared, 3, 4, 4, 3>({wib}), nullptr,
                                                    b.Q(i), b.Q(i + 1), b.O(ka)));
      } else {
        acc_ids.push_back(problem.AddResidualBlock(Auto<internal::FbTrapezoidal, 3, 3, 3, 4, 4, 3, 3, 3, 3, 1, 1>(fb),
                                                   nullptr, b.V(i), b.V(i + 1), b.Q(i), b.Q(i + 1), b.R(i),
                                                   b.R(i + 1), b.A(ka), b.A(kb), b.G(ka), b.G(kb)));
        gyro_ids.push_back(problem.AddResidualBlock(Auto<internal::WibTrapezoidal, 3, 4, 4, 3, 3>(wib), nullptr,
                                                    b.Q(i), b.Q(i + 1), b.O(ka), b.O(kb)));
      }
      if (stride == 1) add_random_walks(i, i + 1, dt);
    }
  }
  // Slow parameters: random walks between consecutive slow nodes over the time between the
  // centres of their intervals (s δt for full intervals; the last one may be shorter).
  if (stride > 1)
    for (int k = 0; k + 1 < m_slow; ++k) {
      const double centre_a = 0.5 * (b.First(k) + b.End(k) - 1), centre_b = 0.5 * (b.First(k + 1) + b.End(k + 1) - 1);
      add_random_walks(k, k + 1, (centre_b - centre_a) * dt);
    }
}


/// The static observations: CUPT (GPS), ZUPT, VUPT, GUPT, XOVER and SGUPT.
StaticCounts AddStaticObservations(const NetworkObservations& obs, const NetworkOptions& options,
                                   const internal::ModelConstants& model, const std::vector<GpsTie>& ties, Blocks& b,
                                   ceres::Problem& problem, ResidualGroups* groups) {
  std::vector<ceres::ResidualBlockId>& gps_ids = groups->gps;
  const bool huber = options.gps_huber_threshold > 0.0;  // the Problem owns each loss
  for (Eigen::Index i = 0; i < obs.gps_time_s.size(); ++i) {
    const Eigen::Vector3d p = obs.gps_position_m.row(i).transpose();
    const GpsTie& t = ties[static_cast<size_t>(i)];
    ceres::LossFunction* loss = huber ? new ceres::HuberLoss(options.gps_huber_threshold) : nullptr;
    if (t.alpha == 0.0)
      gps_ids.push_back(
          problem.AddResidualBlock(Auto<internal::Cupt, 3, 3>({p, 1.0 / options.sigma_gps_m}), loss, b.R(t.a)));
    else
      gps_ids.push_back(problem.AddResidualBlock(
          Auto<internal::CuptInterpolated, 3, 3, 3>({p, t.alpha, 1.0 / options.sigma_gps_m}), loss, b.R(t.a),
          b.R(t.a + 1)));
  }
  for (Eigen::Index i = 0; i < obs.zupt_epochs.size(); ++i)
    problem.AddResidualBlock(Auto<internal::Zupt, 3, 3>({1.0 / options.sigma_zupt_mps}), nullptr,
                             b.V(obs.zupt_epochs[i]));
  for (Eigen::Index i = 0; i < obs.vupt_epochs.size(); ++i) {
    const Eigen::Vector3d v0 = obs.vupt_velocity_mps.row(i).transpose();
    const double sd = obs.vupt_sd_mps.size() > 0 ? obs.vupt_sd_mps[i] : options.sigma_vupt_mps;
    problem.AddResidualBlock(Auto<internal::Vupt, 3, 3>({v0, 1.0 / sd}), nullptr, b.V(obs.vupt_epochs[i]));
  }
  for (Eigen::Index i = 0; i < obs.gupt_epochs.size(); ++i) {
    const int e = obs.gupt_epochs[i];
    problem.AddResidualBlock(
        Auto<internal::Gupt, 1, 3, 1>({model, obs.gupt_gravity_mps2[i], 1.0 / options.sigma_gupt_mps2}), nullptr,
        b.R(e), b.G(b.Slow(e)));
  }
  int num_xover = 0;
  for (Eigen::Index i = 0; i < obs.xover_epochs.rows(); ++i) {
    const int ka = b.Slow(obs.xover_epochs(i, 0)), kb = b.Slow(obs.xover_epochs(i, 1));
    if (ka == kb) continue;  // both epochs share one δg block: the tie holds identically
    problem.AddResidualBlock(Auto<internal::Xover, 1, 1, 1>({1.0 / options.sigma_xover_mps2}), nullptr, b.G(ka),
                             b.G(kb));
    ++num_xover;
  }
  // SGUPT: in each run of consecutive static epochs, δg[n] = δg[n0] (n0 the run's first epoch),
  // once per slow block of the run other than n0's.
  int num_sgupt = 0;
  for (Eigen::Index i = 0; i < obs.sgupt_epochs.size();) {
    Eigen::Index j = i + 1;
    while (j < obs.sgupt_epochs.size() && obs.sgupt_epochs[j] == obs.sgupt_epochs[j - 1] + 1) ++j;
    const int k0 = b.Slow(obs.sgupt_epochs[i]);
    int last = k0;
    for (Eigen::Index e = i + 1; e < j; ++e) {
      const int k = b.Slow(obs.sgupt_epochs[e]);
      if (k == last) continue;  // epochs of one slow block: one tie
      last = k;
      problem.AddResidualBlock(Auto<internal::Sgupt, 1, 1, 1>({1.0 / options.sigma_sgupt_mps2}), nullptr, b.G(k0),
                               b.G(k));
      ++num_sgupt;
    }
    i = j;
  }
  return {num_xover, num_sgupt};
}

}  // namespace indoorloc::network::adjustment
