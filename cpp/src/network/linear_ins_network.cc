#include "indoorloc/network/linear_ins_network.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/QR>

#include "indoorloc/core/check.h"
#include "indoorloc/core/interrupt.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "linear_ins_network_internal.h"

namespace indoorloc::network {
namespace internal {

// Continuous error dynamics ẋ = F x (see the header).
Mat18 Dynamics(const LinearInsNetworkOptions& o) {
  Mat18 F = Mat18::Zero();
  const double fx = o.specific_force_mps2[0], fy = o.specific_force_mps2[1], fz = o.specific_force_mps2[2];
  Eigen::Matrix3d fcross;
  fcross << 0, -fz, fy, fz, 0, -fx, -fy, fx, 0;
  F.block<3, 3>(0, 3).setIdentity();          // δṙ = δv
  F.block<3, 3>(3, 6) = -fcross;              // δv̇ = -[f×] ψ
  F.block<3, 3>(3, 9).setIdentity();          //       + a
  F.block<3, 3>(3, 15).setIdentity();         //       + δg
  F.block<3, 3>(6, 12) = -Eigen::Matrix3d::Identity();  // ψ̇ = -ω
  return F;
}

Vec18 RowWeights(const LinearInsNetworkOptions& o) {
  const double density[6] = {o.velocity_density, o.accel_density, o.gyro_density,
                             o.accel_bias_density, o.gyro_bias_density, o.gravity_density};
  Vec18 w;
  // Row sigma = density / √δt, weight = 1 / sigma² = δt / density².
  const double dt = 1.0 / o.imu_rate_hz;
  for (int g = 0; g < 6; ++g) w.segment<3>(3 * g).setConstant(dt / (density[g] * density[g]));
  return w;
}

Stencil MakeStencil(const LinearInsNetworkOptions& o) {
  const Mat18 F = Dynamics(o);
  const double dt = 1.0 / o.imu_rate_hz;
  const Mat18 I = Mat18::Identity();
  Stencil s;
  if (o.rule == Discretisation::kLeapFrog) {
    s.offsets = {-1, 0, 1};
    s.J = {-I / (2.0 * dt), -F, I / (2.0 * dt)};
    s.first_center = 1;
  } else {
    s.offsets = {0, 1};
    s.J = {-I / dt - 0.5 * F, I / dt - 0.5 * F};
    s.first_center = 0;
  }
  return s;
}

long long GpsStep(const LinearInsNetworkOptions& o) {
  return std::max<long long>(1, std::llround(o.imu_rate_hz / o.gps_rate_hz));
}

// GPS epoch k. With an even step every k·step is even and the odd leap-frog chain would see no
// position, so every other fix moves one epoch later (alternating parity); an odd step
// alternates by itself.
long long GpsEpoch(long long k, long long step) { return k * step + (step % 2 == 0 ? k % 2 : 0); }

bool IsGpsEpoch(long long n, long long step) {
  const long long k1 = n / step;
  if (n == GpsEpoch(k1, step)) return true;
  if (n < 1) return false;
  return n == GpsEpoch((n - 1) / step, step);
}

}  // namespace internal

using namespace internal;  // NOLINT(build/namespaces): this file's own private parts

Eigen::Matrix<double, 18, 1> LinearInsTruth(long long epoch, double imu_rate_hz) {
  const double t = static_cast<double>(epoch) / imu_rate_hz;
  Vec18 x;
  for (int c = 0; c < kP; ++c) {
    const double amplitude = (c >= 15) ? 3e-4 : 0.01 * (1 + c % 3);  // δg: 30 mGal
    x[c] = amplitude * std::sin(0.013 * (c + 1) * t + 0.7 * c);
  }
  return x;
}

bool LinearInsNetworkOptions::IsValid(std::string* error) const {
  const std::pair<const char*, double> sigmas[] = {
      {"velocity_density", velocity_density},     {"accel_density", accel_density},
      {"gyro_density", gyro_density},             {"accel_bias_density", accel_bias_density},
      {"gyro_bias_density", gyro_bias_density},   {"gravity_density", gravity_density},
      {"sigma_gps_m", sigma_gps_m},               {"sigma_prior", sigma_prior},
      {"sigma_gupt_mps2", sigma_gupt_mps2}};
  Validator v(error);
  for (const auto& [name, value] : sigmas) v.Scale(value, name);  // enter as 1/sigma^2
  // Rates and durations as Scales: 1e300 Hz made every block NaN (reported as 'assemble').
  v.Scale(imu_rate_hz, "imu_rate_hz").Scale(gps_rate_hz, "gps_rate_hz").Scale(duration_s, "duration_s");
  if (!v) return false;
  v.Check(gps_rate_hz <= imu_rate_hz, "gps_rate_hz", "must be <= imu_rate_hz, got " + FormatValue(gps_rate_hz))
      .IntInRange(prior_epochs, 0, 1000000, "prior_epochs")
      .IntInRange(gupt_end_epochs, 0, 1000000, "gupt_end_epochs")
      .Check(duration_s * imu_rate_hz <= 2e9, "duration_s",
             "x imu_rate_hz must be <= 2e9 epochs, got " + FormatValue(duration_s * imu_rate_hz));
  for (int k = 0; k < 3; ++k) v.InRange(specific_force_mps2[k], -1e4, 1e4, "specific_force_mps2");
  return v.ok();
}

NetworkSize LinearInsNetworkSize(const LinearInsNetworkOptions& o) {
  ValidateOptions(o);
  NetworkSize s;
  const int g = o.rule == Discretisation::kLeapFrog ? 2 : 1;
  long long epochs = std::max<long long>(3, std::llround(o.duration_s * o.imu_rate_hz) + 1);
  epochs = (epochs + g - 1) / g * g;
  s.imu_epochs = epochs;
  s.block_size = kP * g;
  s.num_blocks = static_cast<int>(epochs / g);
  const long long step = GpsStep(o);
  for (long long k = 0;; ++k) {
    const long long n = GpsEpoch(k, step);
    if (n >= epochs) break;
    ++s.gps_epochs;
  }
  s.unknowns = kP * epochs;
  const long long first = o.rule == Discretisation::kLeapFrog ? 1 : 0;
  s.equations = kP * (epochs - 1 - first) + 3 * s.gps_epochs + kP * std::min<long long>(o.prior_epochs, epochs) +
                3 * std::min<long long>(o.gupt_end_epochs, epochs);
  return s;
}

BlockRowAssembler LinearInsAssembler(const LinearInsNetworkOptions& options) {
  const NetworkSize size = LinearInsNetworkSize(options);
  struct Model {
    LinearInsNetworkOptions o;
    long long E;
    int g;
    Stencil st;
    Vec18 w;
    long long gps_step;
    double w_gps, w_prior, w_gupt;
    std::vector<Mat18> P;  // P_ac = J_aᵀ W J_c, the normal-matrix contribution between stencil epochs a, c
  };
  auto model = std::make_shared<Model>();
  Model& init = *model;
  init.o = options;
  init.E = size.imu_epochs;
  init.g = options.rule == Discretisation::kLeapFrog ? 2 : 1;
  init.st = MakeStencil(options);
  init.w = RowWeights(options);
  init.gps_step = GpsStep(options);
  init.w_gps = 1.0 / (options.sigma_gps_m * options.sigma_gps_m);
  init.w_prior = 1.0 / (options.sigma_prior * options.sigma_prior);
  init.w_gupt = 1.0 / (options.sigma_gupt_mps2 * options.sigma_gupt_mps2);
  const int stencil_size = static_cast<int>(init.st.offsets.size());
  init.P.resize(static_cast<size_t>(stencil_size * stencil_size));
  for (int a = 0; a < stencil_size; ++a)
    for (int c = 0; c < stencil_size; ++c)
      init.P[static_cast<size_t>(a * stencil_size + c)] = init.st.J[static_cast<size_t>(a)].transpose() * init.w.asDiagonal() * init.st.J[static_cast<size_t>(c)];

  return [model](int j, Eigen::MatrixXd* D, Eigen::MatrixXd* Lo, Eigen::VectorXd* r) {
    const Model& M = *model;
    const LinearInsNetworkOptions& o = M.o;
    const Stencil& st = M.st;
    const int g = M.g, m = static_cast<int>(st.offsets.size());
    const long long E = M.E;
    auto is_gps = [&](long long n) { return IsGpsEpoch(n, M.gps_step); };
    const long long first_epoch = static_cast<long long>(g) * j;
    const int max_offset = st.offsets.back(), min_offset = st.offsets.front();
    // Dynamic equations whose stencil touches an epoch of block j.
    for (long long n = first_epoch - max_offset; n <= first_epoch + g - 1 - min_offset; ++n) {
      if (n < st.first_center || n > E - 2) continue;
      Vec18 l = Vec18::Zero();
      for (int a = 0; a < m; ++a) {
        l.noalias() += st.J[static_cast<size_t>(a)] * LinearInsTruth(n + st.offsets[static_cast<size_t>(a)], o.imu_rate_hz);  // noise-free
      }
      const Vec18 wl = M.w.cwiseProduct(l);
      for (int a = 0; a < m; ++a) {
        const long long p = n + st.offsets[static_cast<size_t>(a)];
        if (p / g != j) continue;
        const int pi = static_cast<int>(p - first_epoch) * kP;
        r->segment<kP>(pi).noalias() += st.J[static_cast<size_t>(a)].transpose() * wl;
        for (int c = 0; c < m; ++c) {
          const long long q = n + st.offsets[static_cast<size_t>(c)];
          const Mat18& Pac = M.P[static_cast<size_t>(a * m + c)];
          if (q / g == j) {
            D->block<kP, kP>(pi, static_cast<int>(q - first_epoch) * kP) += Pac;
          } else if (q / g == j - 1) {
            Lo->block<kP, kP>(pi, static_cast<int>(q - (first_epoch - g)) * kP) += Pac;
          }
        }
      }
    }
    // Static equations of the epochs of block j.
    for (int e = 0; e < g; ++e) {
      const long long n = first_epoch + e;
      if (is_gps(n)) {
        D->block<3, 3>(e * kP, e * kP).diagonal().array() += M.w_gps;
        r->segment<3>(e * kP) += M.w_gps * LinearInsTruth(n, o.imu_rate_hz).head<3>();
      }
      if (n >= E - o.gupt_end_epochs) {
        D->block<3, 3>(e * kP + 15, e * kP + 15).diagonal().array() += M.w_gupt;
        r->segment<3>(e * kP + 15) += M.w_gupt * LinearInsTruth(n, o.imu_rate_hz).tail<3>();
      }
      if (n < o.prior_epochs) {
        D->block<kP, kP>(e * kP, e * kP).diagonal().array() += M.w_prior;
        r->segment<kP>(e * kP) += M.w_prior * LinearInsTruth(n, o.imu_rate_hz);
      }
    }
  };
}

LinearInsEquations LinearInsNetworkEquations(const LinearInsNetworkOptions& options) {
  const NetworkSize size = LinearInsNetworkSize(options);
  const Stencil st = MakeStencil(options);
  const Vec18 w = RowWeights(options);
  LinearInsEquations eq;
  eq.imu_epochs = size.imu_epochs;
  eq.offsets = st.offsets;
  for (const Mat18& j : st.J) eq.J.emplace_back(j);
  eq.row_sigma = w.cwiseSqrt().cwiseInverse();
  const long long E = size.imu_epochs;
  for (long long n = st.first_center; n <= E - 2; ++n) eq.centres.push_back(n);
  eq.dynamic_l.resize(static_cast<Eigen::Index>(eq.centres.size()), kP);
  for (size_t i = 0; i < eq.centres.size(); ++i) {
    Vec18 l = Vec18::Zero();
    for (size_t a = 0; a < st.offsets.size(); ++a) l.noalias() += st.J[a] * LinearInsTruth(eq.centres[i] + st.offsets[a], options.imu_rate_hz);
    eq.dynamic_l.row(static_cast<Eigen::Index>(i)) = l.transpose();
  }
  const long long step = GpsStep(options);
  for (long long k = 0;; ++k) {
    const long long n = GpsEpoch(k, step);
    if (n >= E) break;
    eq.gps_epochs.push_back(n);
  }
  eq.gps_l.resize(static_cast<Eigen::Index>(eq.gps_epochs.size()), 3);
  for (size_t k = 0; k < eq.gps_epochs.size(); ++k) eq.gps_l.row(static_cast<Eigen::Index>(k)) = LinearInsTruth(eq.gps_epochs[k], options.imu_rate_hz).head<3>().transpose();
  const long long priors = std::min<long long>(options.prior_epochs, E);
  eq.prior_l.resize(priors, kP);
  for (long long n = 0; n < priors; ++n) eq.prior_l.row(n) = LinearInsTruth(n, options.imu_rate_hz).transpose();
  for (long long n = std::max<long long>(0, E - options.gupt_end_epochs); n < E; ++n) eq.gupt_epochs.push_back(n);
  eq.gupt_l.resize(static_cast<Eigen::Index>(eq.gupt_epochs.size()), 3);
  for (size_t k = 0; k < eq.gupt_epochs.size(); ++k) eq.gupt_l.row(static_cast<Eigen::Index>(k)) = LinearInsTruth(eq.gupt_epochs[k], options.imu_rate_hz).tail<3>().transpose();
  eq.sigma_gps = options.sigma_gps_m;
  eq.sigma_prior = options.sigma_prior;
  eq.sigma_gupt = options.sigma_gupt_mps2;
  return eq;
}

LinearInsNetworkResult SolveLinearInsNetwork(const LinearInsNetworkOptions& o, bool gravity_covariance,
                                             int checkpoint_interval, bool keep_gravity_estimate, int num_threads,
                                             double pivot_tolerance) {
  WallTimer total;
  LinearInsNetworkResult result;
  result.size = LinearInsNetworkSize(o);
  const long long E = result.size.imu_epochs;
  const int g = o.rule == Discretisation::kLeapFrog ? 2 : 1;
  const int b = result.size.block_size;
  const BlockRowAssembler assemble = LinearInsAssembler(o);

  BlockTridiagonalOptions so;
  so.checkpoint_interval = checkpoint_interval;
  so.num_threads = num_threads;
  so.pivot_tolerance = pivot_tolerance;
  if (gravity_covariance) {
    for (int e = 0; e < g; ++e)
      for (int c = 15; c < 18; ++c) so.selected.push_back(e * kP + c);
  }
  BlockTridiagonalSolution sol;
  try {
    sol = SolveBlockTridiagonal(result.size.num_blocks, b, assemble, so);
  } catch (const std::runtime_error& e) {
    // Long 200 Hz chains break the normal equations down by round-off where the network is
    // regular (docs/network_scale.md, "Case 3"): say what tells the two apart.
    throw std::runtime_error(std::string(e.what()) +
                             "; if the network has a datum, this can also be round-off: the normal equations square "
                             "the condition of weak modes of long chains, and SolveLinearInsNetworkQr (method='qr') "
                             "does not (it separates a defect, relative pivot ~1e-30, from weak information)");
  }
  result.solver = sol.summary;

  TruthScore score(E, o.imu_rate_hz, keep_gravity_estimate ? &result.gravity_estimate : nullptr);
  if (gravity_covariance) result.gravity_sigma.resize(E, 3);
  for (long long n = 0; n < E; ++n) {
    score.Add(n, sol.x.segment<kP>(n * kP));
    if (gravity_covariance) {
      const Eigen::MatrixXd& cov = sol.covariance[static_cast<size_t>(n / g)];
      const int e = static_cast<int>(n % g);
      for (int c = 0; c < 3; ++c) result.gravity_sigma(n, c) = std::sqrt(std::max(0.0, cov(3 * e + c, 3 * e + c)));
    }
  }
  score.Write(&result);
  result.total_seconds = total.ElapsedSeconds();
  return result;
}

std::vector<Tie> LinearInsCrossoverTies(const LinearInsNetworkOptions& options, int lines, int cross_lines,
                                        double sigma_xover_mps2) {
  const NetworkSize size = LinearInsNetworkSize(options);
  CheckArgument(lines >= 1 && cross_lines >= 1, "lines",
                "need at least one line and one cross line, got lines = " + std::to_string(lines) +
                    ", cross_lines = " + std::to_string(cross_lines));
  CheckArgument(std::isfinite(sigma_xover_mps2) && sigma_xover_mps2 > 0.0, "sigma_xover_mps2", "must be finite and > 0");
  const long long E = size.imu_epochs;
  const long long per_line = E / (lines + cross_lines);
  CheckArgument(per_line >= 2 * std::max(lines, cross_lines), "lines",
                "too many lines (and cross_lines) for the flight of duration_s x imu_rate_hz epochs: each line "
                "needs at least two epochs per crossing");
  const double w = 1.0 / (sigma_xover_mps2 * sigma_xover_mps2);
  std::vector<Tie> ties;
  ties.reserve(static_cast<size_t>(3LL * lines * cross_lines));
  for (int i = 0; i < lines; ++i) {
    for (int j = 0; j < cross_lines; ++j) {
      // EW line i meets NS line j at the (j + ½)-th of its stretches, and vice versa.
      // Integer form of (j + ½) · per_line / cross_lines.
      const long long ew = i * per_line + ((2LL * j + 1) * per_line) / (2LL * cross_lines);
      const long long ns = (lines + j) * per_line + ((2LL * i + 1) * per_line) / (2LL * lines);
      const Vec18 xa = LinearInsTruth(ew, options.imu_rate_hz), xb = LinearInsTruth(ns, options.imu_rate_hz);
      for (int c = 15; c < 18; ++c) ties.push_back(Tie{ew * kP + c, ns * kP + c, w, xa[c] - xb[c]});
    }
  }
  return ties;
}

CrossoverNetworkResult SolveLinearInsNetworkWithCrossovers(const LinearInsNetworkOptions& options, int lines,
                                                           int cross_lines, double sigma_xover_mps2,
                                                           const TiedSolveOptions& pcg) {
  WallTimer total;
  CrossoverNetworkResult out;
  out.size = LinearInsNetworkSize(options);
  const std::vector<Tie> ties = LinearInsCrossoverTies(options, lines, cross_lines, sigma_xover_mps2);
  out.crossings = static_cast<long long>(lines) * cross_lines;
  out.ties = static_cast<long long>(ties.size());
  WallTimer timer;
  const BlockTridiagonalFactor factor(out.size.num_blocks, out.size.block_size, LinearInsAssembler(options));
  out.factor_seconds = timer.ElapsedSeconds();
  out.factor_bytes = factor.bytes();
  const TiedSolution sol = SolveWithTies(factor, factor.rhs(), ties, pcg);
  out.pcg = sol.summary;
  TruthScore score(out.size.imu_epochs, options.imu_rate_hz, nullptr);
  for (long long n = 0; n < out.size.imu_epochs; ++n) score.Add(n, sol.x.segment<kP>(n * kP));
  out.max_abs_error = score.max_error();
  out.gravity_rmse = score.gravity_rmse();
  out.total_seconds = total.ElapsedSeconds();
  return out;
}

}  // namespace indoorloc::network
