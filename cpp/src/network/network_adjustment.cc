// INS/GPS network adjustment (paper 003 §3): builds the Ceres problem from the residuals of
// residuals.h and solves it with SPARSE_NORMAL_CHOLESKY (SuiteSparse). See the header.
#include "indoorloc/network/network_adjustment.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/SparseCholesky>
#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/network/gravity.h"
#include "network_problem.h"
#include "residuals.h"

namespace indoorloc::network {

using namespace adjustment;  // NOLINT: the problem's parts (network_problem.h)


bool NetworkOptions::IsValid(std::string* error) const {
  Validator v(error);
  v.InRange(latitude_rad, -1.5707963267948966, 1.5707963267948966, "latitude_rad")
      .Finite(origin_height_m, "origin_height_m")
      .InRange(earth_rate_radps, 0.0, 1.0, "earth_rate_radps");
  // Noise densities and sds enter as 1/sigma: a scale keeps their squares finite.
  const std::pair<const char*, double> scales[] = {
      {"acc_noise_mps2_rthz", acc_noise_mps2_rthz},       {"gyro_noise_radps_rthz", gyro_noise_radps_rthz},
      {"acc_bias_walk_mps2_rts", acc_bias_walk_mps2_rts}, {"gyro_bias_walk_radps_rts", gyro_bias_walk_radps_rts},
      {"gravity_walk_mps2_rts", gravity_walk_mps2_rts},   {"sigma_vel_mps", sigma_vel_mps},
      {"sigma_gps_m", sigma_gps_m},                       {"sigma_zupt_mps", sigma_zupt_mps},
      {"sigma_gupt_mps2", sigma_gupt_mps2},               {"sigma_xover_mps2", sigma_xover_mps2},
      {"sigma_vupt_mps", sigma_vupt_mps},                 {"sigma_sgupt_mps2", sigma_sgupt_mps2}};
  for (const auto& [name, value] : scales) v.Scale(value, name);
  // Angular noise beyond 10 rad/s/sqrt(Hz) randomises the attitude within one epoch: the filter's
  // covariance then overflowed (2**31 gave NaN positions in kalman_smoother).
  v.InRange(gyro_noise_radps_rthz, kMinScale, 10.0, "gyro_noise_radps_rthz")
      .InRange(gyro_bias_walk_radps_rts, kMinScale, 10.0, "gyro_bias_walk_radps_rts");
  const std::pair<const char*, double> positive[] = {
      {"function_tolerance", function_tolerance},   {"gradient_tolerance", gradient_tolerance},
      {"parameter_tolerance", parameter_tolerance}, {"datum_pivot_tolerance", datum_pivot_tolerance},
      {"initial_trust_region_radius", initial_trust_region_radius}};
  for (const auto& [name, value] : positive) v.Positive(value, name);
  v.NonNegative(acc_bias_correlation_time_s, "acc_bias_correlation_time_s")
      .NonNegative(gyro_bias_correlation_time_s, "gyro_bias_correlation_time_s")
      .NonNegative(gps_huber_threshold, "gps_huber_threshold")
      .IntInRange(max_iterations, 0, 1000000, "max_iterations")
      .IntInRange(num_threads, 1, 1024, "num_threads")
      .AtLeast(slow_parameter_stride, 1, "slow_parameter_stride");
  return v.ok();
}

NetworkState EstimateVarianceComponents(const NetworkObservations& observations, const NetworkState& initial,
                                        const NetworkOptions& options, NetworkOptions* estimated,
                                        NetworkSummary* summary, int iterations, double tolerance) {
  CheckArgument(iterations >= 1, "iterations", "must be >= 1");
  CheckArgument(std::isfinite(tolerance) && tolerance > 0.0, "tolerance", "must be finite and > 0");
  NetworkOptions o = options;
  o.variance_components = true;
  o.gps_huber_threshold = 0.0;
  NetworkState state = initial;
  NetworkSummary s;
  for (int k = 0; k < iterations; ++k) {
    state = SolveNetwork(observations, state, o, &s);
    o.check_datum = false;  // checked on the first solve; reweighting does not change the rank
    if (s.variance_factor_acc > 0.0) o.acc_noise_mps2_rthz *= std::sqrt(s.variance_factor_acc);
    if (s.variance_factor_gyro > 0.0) o.gyro_noise_radps_rthz *= std::sqrt(s.variance_factor_gyro);
    if (s.variance_factor_gps > 0.0) o.sigma_gps_m *= std::sqrt(s.variance_factor_gps);
    if (std::abs(s.variance_factor_acc - 1.0) < tolerance && std::abs(s.variance_factor_gyro - 1.0) < tolerance &&
        std::abs(s.variance_factor_gps - 1.0) < tolerance)
      break;
  }
  o.variance_components = options.variance_components;
  o.check_datum = options.check_datum;
  if (estimated) *estimated = o;
  if (summary) *summary = s;
  return state;
}

bool CrossoverOptions::IsValid(std::string* error) const {
  return Validator(error)
      .Scale(radius_m, "radius_m")
      .Scale(max_height_difference_m, "max_height_difference_m")
      .NonNegative(min_separation_s, "min_separation_s");
}

std::string NetworkSummary::BriefReport() const {
  std::ostringstream s;
  s << "network: " << ToString(termination) << ", " << iterations << " iterations, cost " << initial_cost << " -> "
    << final_cost << ", " << num_epochs << " epochs, " << num_parameters << " unknowns, " << num_residuals
    << " residuals, " << num_slow_nodes << " slow nodes, " << num_xover << " cross-overs, " << seconds_total << " s (solve " << seconds_solve
    << " s, datum check " << seconds_datum_check << " s, covariance " << seconds_covariance
    << " s), variance factor " << variance_factor;
  return s.str();
}

void CheckNetworkInput(const NetworkObservations& obs, const NetworkState& state) {
  const Eigen::Index n = obs.imu_time_s.size();
  CheckArgument(n >= 3, "imu_time_s", "needs at least 3 epochs, got " + std::to_string(n));
  CheckFinite(obs.imu_time_s, "imu_time_s");
  // Finite but absurd times (1e300) overflow the propagation to inf/NaN without an error.
  RequireAllInRange(obs.imu_time_s, -1e10, 1e10, "imu_time_s");
  const double dt = (obs.imu_time_s[n - 1] - obs.imu_time_s[0]) / static_cast<double>(n - 1);
  CheckArgument(dt <= 1e3, "imu_time_s",
                "mean sample interval " + std::to_string(dt) + " s is longer than 1000 s (not an IMU's rate)");
  for (Eigen::Index i = 1; i < n; ++i) {
    const double step = obs.imu_time_s[i] - obs.imu_time_s[i - 1];
    CheckArgument(step > 0.0, "imu_time_s",
                  "not strictly increasing at entry " + std::to_string(i));
    CheckArgument(std::abs(step - dt) <= 1e-6 * dt + 1e-9, "imu_time_s",
                  "not uniformly sampled at entry " + std::to_string(i) + " (step " + std::to_string(step) +
                      " s, mean " + std::to_string(dt) + " s)");
  }
  CheckShape(obs.acc_body_mps2, n, 3, "acc_body_mps2");
  CheckFinite(obs.acc_body_mps2, "acc_body_mps2");
  CheckShape(obs.gyro_body_radps, n, 3, "gyro_body_radps");
  CheckFinite(obs.gyro_body_radps, "gyro_body_radps");
  // Plausibility bounds: finite but absurd samples (1e300) overflow the residuals to inf/NaN
  // inside Ceres, or show up as a "datum defect" far from their cause.
  RequireAllInRange(obs.acc_body_mps2, -1e4, 1e4, "acc_body_mps2");
  RequireAllInRange(obs.gyro_body_radps, -1e4, 1e4, "gyro_body_radps");
  const Eigen::Index m = obs.gps_time_s.size();
  CheckShape(obs.gps_position_m, m, 3, "gps_position_m");
  CheckFinite(obs.gps_time_s, "gps_time_s");
  CheckFinite(obs.gps_position_m, "gps_position_m");
  RequireAllInRange(obs.gps_position_m, -1e9, 1e9, "gps_position_m");
  for (Eigen::Index i = 0; i < m; ++i) {
    const double t = obs.gps_time_s[i];
    CheckArgument(t >= obs.imu_time_s[0] - 1e-9 && t <= obs.imu_time_s[n - 1] + 1e-9, "gps_time_s",
                  "entry " + std::to_string(i) + " = " + std::to_string(t) + " s is outside the IMU span [" +
                      std::to_string(obs.imu_time_s[0]) + ", " + std::to_string(obs.imu_time_s[n - 1]) + "] s");
    if (i > 0)
      CheckArgument(t > obs.gps_time_s[i - 1], "gps_time_s", "not strictly increasing at entry " + std::to_string(i));
  }
  CheckEpochs(obs.zupt_epochs, static_cast<int>(n), "zupt_epochs");
  CheckEpochs(obs.gupt_epochs, static_cast<int>(n), "gupt_epochs");
  CheckShape(obs.gupt_gravity_mps2, obs.gupt_epochs.size(), 1, "gupt_gravity_mps2");
  CheckFinite(obs.gupt_gravity_mps2, "gupt_gravity_mps2");
  for (Eigen::Index i = 0; i < obs.xover_epochs.rows(); ++i) {
    for (int k = 0; k < 2; ++k)
      CheckArgument(obs.xover_epochs(i, k) >= 0 && obs.xover_epochs(i, k) < n, "xover_epochs",
                    "row " + std::to_string(i) + " has an epoch outside [0, " + std::to_string(n) + ")");
    CheckArgument(obs.xover_epochs(i, 0) != obs.xover_epochs(i, 1), "xover_epochs",
                  "row " + std::to_string(i) + " ties an epoch to itself");
  }
  CheckEpochs(obs.vupt_epochs, static_cast<int>(n), "vupt_epochs");
  const Eigen::Index nv = obs.vupt_epochs.size();
  if (nv > 0 || obs.vupt_velocity_mps.size() > 0) CheckShape(obs.vupt_velocity_mps, nv, 3, "vupt_velocity_mps");
  CheckFinite(obs.vupt_velocity_mps, "vupt_velocity_mps");
  if (obs.vupt_sd_mps.size() > 0) {
    CheckShape(obs.vupt_sd_mps, nv, 1, "vupt_sd_mps");
    for (Eigen::Index i = 0; i < nv; ++i)
      CheckArgument(std::isfinite(obs.vupt_sd_mps[i]) && obs.vupt_sd_mps[i] > 0.0, "vupt_sd_mps",
                    "entry " + std::to_string(i) + " = " + std::to_string(obs.vupt_sd_mps[i]) +
                        " must be finite and > 0");
  }
  CheckEpochs(obs.sgupt_epochs, static_cast<int>(n), "sgupt_epochs");
  if (obs.sgupt_epochs.size() > 0) {
    // SGUPT needs a static platform: a ZUPT or a VUPT with v0 = 0 at each of its epochs.
    std::vector<char> is_static(static_cast<size_t>(n), 0);
    for (Eigen::Index i = 0; i < obs.zupt_epochs.size(); ++i) is_static[static_cast<size_t>(obs.zupt_epochs[i])] = 1;
    for (Eigen::Index i = 0; i < nv; ++i)
      if (obs.vupt_velocity_mps.row(i).isZero(0.0)) is_static[static_cast<size_t>(obs.vupt_epochs[i])] = 1;
    for (Eigen::Index i = 0; i < obs.sgupt_epochs.size(); ++i) {
      const int e = obs.sgupt_epochs[i];
      if (i > 0)
        CheckArgument(e > obs.sgupt_epochs[i - 1], "sgupt_epochs",
                      "not strictly increasing at entry " + std::to_string(i));
      CheckArgument(is_static[static_cast<size_t>(e)] != 0, "sgupt_epochs",
                    "entry " + std::to_string(i) + " = epoch " + std::to_string(e) +
                        " is not static: SGUPT (constant gravity) needs a ZUPT or a VUPT with zero velocity there");
    }
  }
  CheckShape(state.position_m, n, 3, "initial position_m");
  CheckShape(state.velocity_mps, n, 3, "initial velocity_mps");
  CheckShape(state.attitude_wxyz, n, 4, "initial attitude_wxyz");
  CheckShape(state.acc_bias_mps2, n, 3, "initial acc_bias_mps2");
  CheckShape(state.gyro_bias_radps, n, 3, "initial gyro_bias_radps");
  CheckShape(state.gravity_disturbance_mps2, n, 1, "initial gravity_disturbance_mps2");
  CheckFinite(state.position_m, "initial position_m");
  CheckFinite(state.velocity_mps, "initial velocity_mps");
  CheckFinite(state.attitude_wxyz, "initial attitude_wxyz");
  CheckFinite(state.acc_bias_mps2, "initial acc_bias_mps2");
  CheckFinite(state.gyro_bias_radps, "initial gyro_bias_radps");
  CheckFinite(state.gravity_disturbance_mps2, "initial gravity_disturbance_mps2");
  for (Eigen::Index i = 0; i < n; ++i)
    CheckArgument(state.attitude_wxyz.row(i).norm() > 0.5, "initial attitude_wxyz",
                  "row " + std::to_string(i) + " is not a unit quaternion");
}

namespace {

/// (JᵀJ)⁻¹ as a dense matrix: sparse LDLᵀ (AMD) of JᵀJ, then n solves (O(n nnz(L)), n² memory).
template <typename Jacobian>
Eigen::MatrixXd DenseInverseOfNormal(const Jacobian& jac) {
  const Eigen::SparseMatrix<double> normal = Eigen::SparseMatrix<double>(jac.transpose()) * jac;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt(normal);
  if (ldlt.info() != Eigen::Success)
    throw std::runtime_error("indoorloc: network: the normal matrix at the solution is singular");
  return ldlt.solve(Eigen::MatrixXd::Identity(normal.rows(), normal.cols()));
}

constexpr long kMaxDenseUnknowns = 8000;  // n² doubles: 0.5 GB

/// Numerical datum check: LDLᵀ of the Jacobi-scaled JᵀJ at the initial values; throws naming the
/// first undetermined parameter when a pivot ratio falls below options.datum_pivot_tolerance.
void CheckDatum(const NetworkOptions& options, const ParameterLayout& layout, ceres::Problem& problem,
                NetworkSummary* summary) {
  NetworkSummary& s = *summary;
  const std::vector<double*>& ordered_blocks = layout.ordered_blocks;
  const std::vector<ColumnLabel>& labels = layout.labels;
  WallTimer datum_timer;
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = ordered_blocks;
  eo.apply_loss_function = false;
  eo.num_threads = options.num_threads;
  ceres::CRSMatrix crs;
  double cost = 0.0;
  if (!problem.Evaluate(eo, &cost, nullptr, nullptr, &crs))
    throw std::runtime_error("indoorloc: network: evaluating the Jacobian at the initial values failed");
  Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor, int>> jac(
      crs.num_rows, crs.num_cols, static_cast<Eigen::Index>(crs.values.size()), crs.rows.data(), crs.cols.data(),
      crs.values.data());
  Eigen::SparseMatrix<double> normal = Eigen::SparseMatrix<double>(jac.transpose()) * jac;
  // Jacobi scaling to a unit diagonal: the pivots are then the ratios pivot / diagonal entry,
  // and the factorisation does not suffer from the units of the parameters.
  Eigen::VectorXd scale = normal.diagonal();
  for (Eigen::Index i = 0; i < scale.size(); ++i) scale[i] = scale[i] > 0.0 ? 1.0 / std::sqrt(scale[i]) : 1.0;
  normal = scale.asDiagonal() * normal * scale.asDiagonal();
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt;
  ldlt.analyzePattern(normal);
  ldlt.factorize(normal);
  const Eigen::VectorXd diag = normal.diagonal();
  const Eigen::VectorXd d = ldlt.vectorD();
  const auto& perm = ldlt.permutationP().indices();
  double worst = std::numeric_limits<double>::infinity();
  int worst_col = -1;
  const bool failed = ldlt.info() != Eigen::Success;
  std::vector<int> inverse(static_cast<size_t>(normal.cols()));
  for (int col = 0; col < normal.cols(); ++col) inverse[static_cast<size_t>(perm[col])] = col;
  if (failed) {
    // Eigen stops at the first exactly zero pivot; later entries of D are not computed.
    worst = 0.0;
    for (int k = 0; k < d.size(); ++k)
      if (d[k] == 0.0) {
        worst_col = inverse[static_cast<size_t>(k)];
        break;
      }
  } else {
    for (int col = 0; col < normal.cols(); ++col) {
      const double ratio = diag[col] > 0.0 ? d[perm[col]] : 0.0;
      if (ratio < worst) {
        worst = ratio;
        worst_col = col;
      }
    }
  }
  s.min_pivot_ratio = worst;
  s.seconds_datum_check = datum_timer.ElapsedSeconds();
  if (failed || worst < options.datum_pivot_tolerance) {
    std::ostringstream m;
    m << "datum defect: the normal matrix is rank deficient (smallest pivot ratio " << worst << " < "
      << options.datum_pivot_tolerance << ")";
    if (worst_col >= 0)
      m << "; first undetermined parameter: " << labels[static_cast<size_t>(worst_col)].name << " at epoch "
        << labels[static_cast<size_t>(worst_col)].epoch;
    m << ". Add observations (CUPT for position, GUPT or XOVER for gravity vs accelerometer bias)";
    // A defect can also be numerical: weights spanning many orders of magnitude. Name the
    // extreme sds of the options so that a mistyped one is found.
    const std::pair<const char*, double> sds[] = {
        {"acc_noise_mps2_rthz", options.acc_noise_mps2_rthz}, {"gyro_noise_radps_rthz", options.gyro_noise_radps_rthz},
        {"sigma_gps_m", options.sigma_gps_m},                 {"sigma_zupt_mps", options.sigma_zupt_mps},
        {"sigma_gupt_mps2", options.sigma_gupt_mps2},         {"sigma_xover_mps2", options.sigma_xover_mps2},
        {"sigma_vel_mps", options.sigma_vel_mps}};
    const auto* lo = &sds[0];
    const auto* hi = &sds[0];
    for (const auto& e : sds) {
      if (e.second < lo->second) lo = &e;
      if (e.second > hi->second) hi = &e;
    }
    m << ", or check the sds in 'options' (from " << lo->first << " = " << lo->second << " to " << hi->first
      << " = " << hi->second << ")";
    ThrowInvalidArgument("observations", m.str());
  }
}

/// Runs Ceres (sparse normal Cholesky) and records its iterations, costs and termination.
void RunSolver(const NetworkOptions& options, ceres::Problem& problem, NetworkSummary* summary) {
  NetworkSummary& s = *summary;
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  so.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  so.max_num_iterations = options.max_iterations;
  so.initial_trust_region_radius = options.initial_trust_region_radius;
  so.max_trust_region_radius = std::max(1e16, options.initial_trust_region_radius);
  so.function_tolerance = options.function_tolerance;
  so.gradient_tolerance = options.gradient_tolerance;
  so.parameter_tolerance = options.parameter_tolerance;
  so.num_threads = options.num_threads;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  if (!ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE))
    so.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
  std::string error;
  if (!so.IsValid(&error)) throw std::runtime_error("indoorloc: network: invalid Ceres options: " + error);
  ceres::Solver::Summary cs;
  WallTimer solve_timer;
  ceres::Solve(so, &problem, &cs);
  s.seconds_solve = solve_timer.ElapsedSeconds();
  s.iterations = static_cast<int>(cs.iterations.size()) - 1;
  s.initial_cost = cs.initial_cost;
  s.final_cost = cs.final_cost;
  s.message = cs.message;
  switch (cs.termination_type) {
    case ceres::CONVERGENCE: s.termination = Termination::kConverged; break;
    case ceres::NO_CONVERGENCE: s.termination = Termination::kMaxIterations; break;
    default: s.termination = Termination::kFailure; break;
  }
  const double redundancy = static_cast<double>(s.num_residuals) - static_cast<double>(s.num_parameters);
  s.variance_factor = redundancy > 0.0 ? 2.0 * s.final_cost / redundancy : 0.0;
}

/// After the solve: the variance components of the acc, gyro and GPS groups and the sd of every
/// δg, as the options ask.
void ComputePrecision(const NetworkOptions& options, const ParameterLayout& layout, const ResidualGroups& groups,
                      Blocks& b, int n, ceres::Problem& problem, NetworkState* state, NetworkSummary* summary) {
  NetworkSummary& s = *summary;
  NetworkState& out = *state;
  const int m_slow = b.m;
  const std::vector<double*>& ordered_blocks = layout.ordered_blocks;
  const std::vector<int>& gravity_column = layout.gravity_column;
  const std::vector<ceres::ResidualBlockId>& acc_ids = groups.acc;
  const std::vector<ceres::ResidualBlockId>& gyro_ids = groups.gyro;
  const std::vector<ceres::ResidualBlockId>& gps_ids = groups.gps;
  // (JᵀJ)⁻¹ at the solution, dense (small networks only): shared by the variance components and
  // the dense δg covariance, computed at most once.
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = ordered_blocks;
  eo.apply_loss_function = false;
  Eigen::MatrixXd dense_inverse;
  auto inverse_at_solution = [&]() -> const Eigen::MatrixXd& {
    if (dense_inverse.size() == 0) {
      ceres::CRSMatrix crs;
      double cost = 0.0;
      if (!problem.Evaluate(eo, &cost, nullptr, nullptr, &crs))
        throw std::runtime_error("indoorloc: network: evaluating the Jacobian at the solution failed");
      Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor, int>> jac(
          crs.num_rows, crs.num_cols, static_cast<Eigen::Index>(crs.values.size()), crs.rows.data(), crs.cols.data(),
          crs.values.data());
      dense_inverse = DenseInverseOfNormal(jac);
    }
    return dense_inverse;
  };
  if (options.variance_components) {
    WallTimer vc_timer;
    const Eigen::MatrixXd& inverse = inverse_at_solution();
    auto group = [&](const std::vector<ceres::ResidualBlockId>& ids, double* factor, double* group_redundancy) {
      if (ids.empty()) return;
      ceres::Problem::EvaluateOptions ge = eo;
      ge.residual_blocks = ids;
      std::vector<double> v;
      ceres::CRSMatrix jg;
      double c = 0.0;
      if (!problem.Evaluate(ge, &c, &v, nullptr, &jg))
        throw std::runtime_error("indoorloc: network: evaluating a residual group failed");
      // tr(N⁻¹ J_gᵀ J_g) = Σ_rows j_r N⁻¹ j_rᵀ over the few non-zeros of each row.
      double trace = 0.0;
      for (int r = 0; r < jg.num_rows; ++r)
        for (int a = jg.rows[r]; a < jg.rows[r + 1]; ++a)
          for (int bb = jg.rows[r]; bb < jg.rows[r + 1]; ++bb)
            trace += jg.values[a] * jg.values[bb] * inverse(jg.cols[a], jg.cols[bb]);
      double vtv = 0.0;
      for (double x : v) vtv += x * x;
      *group_redundancy = static_cast<double>(v.size()) - trace;
      *factor = *group_redundancy > 0.0 ? vtv / *group_redundancy : 0.0;
    };
    group(acc_ids, &s.variance_factor_acc, &s.redundancy_acc);
    group(gyro_ids, &s.variance_factor_gyro, &s.redundancy_gyro);
    group(gps_ids, &s.variance_factor_gps, &s.redundancy_gps);
    s.seconds_covariance += vc_timer.ElapsedSeconds();
  }
  if (options.gravity_covariance != NetworkOptions::Covariance::kNone) {
    WallTimer cov_timer;
    out.gravity_disturbance_sd_mps2.resize(n);
    if (options.gravity_covariance == NetworkOptions::Covariance::kDense) {
      const Eigen::MatrixXd& inverse = inverse_at_solution();
      for (int i = 0; i < n; ++i) {
        const int col = gravity_column[static_cast<size_t>(b.Slow(i))];
        const double v = inverse(col, col);
        out.gravity_disturbance_sd_mps2[i] = v > 0.0 ? std::sqrt(v) : std::numeric_limits<double>::quiet_NaN();
      }
    } else {
      ceres::Covariance::Options co;
      co.algorithm_type = ceres::SPARSE_QR;
      co.num_threads = options.num_threads;
      ceres::Covariance covariance(co);
      std::vector<std::pair<const double*, const double*>> blocks;
      blocks.reserve(static_cast<size_t>(m_slow));
      for (int k = 0; k < m_slow; ++k) blocks.emplace_back(b.G(k), b.G(k));
      if (!covariance.Compute(blocks, &problem))
        throw std::runtime_error("indoorloc: network: ceres::Covariance failed (rank-deficient network?)");
      for (int k = 0; k < m_slow; ++k) {
        double v = 0.0;
        covariance.GetCovarianceBlock(b.G(k), b.G(k), &v);
        out.gravity_disturbance_sd_mps2.segment(b.First(k), b.End(k) - b.First(k)).setConstant(std::sqrt(std::max(v, 0.0)));
      }
    }
    s.seconds_covariance += cov_timer.ElapsedSeconds();
  }
}

}  // namespace

NetworkState SolveNetwork(const NetworkObservations& obs, const NetworkState& initial, const NetworkOptions& options,
                          NetworkSummary* summary) {
  WallTimer total;
  ValidateOptions(options);
  CheckNetworkInput(obs, initial);
  const int n = static_cast<int>(obs.imu_time_s.size());
  const double dt = (obs.imu_time_s[n - 1] - obs.imu_time_s[0]) / (n - 1);
  const bool leap = options.discretization == Discretization::kLeapFrog;

  // Structural datum checks (cheap, before any work).
  CheckArgument(obs.gps_time_s.size() > 0, "gps_position_m",
                "datum defect: no CUPT (GPS) observations, the position of the network is not determined");
  const std::vector<GpsTie> ties = TieGpsToEpochs(obs, n, dt, leap);

  Blocks b = FromState(initial, options.slow_parameter_stride);
  const internal::ModelConstants model = MakeModelConstants(options);
  ceres::Problem::Options popts;
  popts.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::EigenQuaternionManifold quaternion_manifold;
  ceres::Problem problem(popts);
  const ParameterLayout layout = AddParameterBlocks(b, n, &quaternion_manifold, problem);
  ResidualGroups groups;
  AddDynamics(obs, options, model, dt, b, problem, &groups);
  const StaticCounts counts = AddStaticObservations(obs, options, model, ties, b, problem, &groups);

  NetworkSummary s;
  s.num_epochs = n;
  s.num_parameters = static_cast<long>(problem.NumParameters()) - n;  // quaternion: 4 stored, 3 free
  s.num_residuals = problem.NumResiduals();
  s.num_slow_nodes = b.m;
  s.num_xover = counts.num_xover;
  s.num_vupt = static_cast<int>(obs.vupt_epochs.size());
  s.num_sgupt = counts.num_sgupt;

  CheckArgument(!options.variance_components || s.num_parameters <= kMaxDenseUnknowns, "options",
                "variance_components is limited to " + std::to_string(kMaxDenseUnknowns) + " unknowns (got " +
                    std::to_string(s.num_parameters) + ")");
  if (options.gravity_covariance == NetworkOptions::Covariance::kDense && s.num_parameters > kMaxDenseUnknowns)
    ThrowInvalidArgument("options", "gravity_covariance = dense is limited to " + std::to_string(kMaxDenseUnknowns) +
                                        " unknowns (got " +
                                        std::to_string(s.num_parameters) + "); use ceres");
  if (options.check_datum) CheckDatum(options, layout, problem, &s);
  RunSolver(options, problem, &s);
  NetworkState out = ToState(b);
  ComputePrecision(options, layout, groups, b, n, problem, &out, &s);
  s.seconds_total = total.ElapsedSeconds();
  if (summary) *summary = s;
  return out;
}

}  // namespace indoorloc::network
