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

namespace indoorloc::network {
namespace {

constexpr int kP = 18;  // unknowns per epoch
using Mat18 = Eigen::Matrix<double, kP, kP>;
using Vec18 = Eigen::Matrix<double, kP, 1>;

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

// One dynamic equation type: coefficient blocks on epochs n + offset[k].
struct Stencil {
  std::vector<int> offsets;
  std::vector<Mat18> J;
  int first_center = 0;  // valid centres n: first_center .. E - 2
};

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

}  // namespace

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

namespace {

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

}  // namespace

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

// ---------------------------------------------------------------------------------------------
// Orthogonal (square-root information) solve: the same network, factored from its whitened
// observation equations by Householder QR instead of from the normal matrix by Cholesky.

namespace {

// The whitened observation rows of block j: every row whose lowest epoch lies in block j, as
// [coefficients on block j | coefficients on block j+1 | right-hand side] (b + b + 1 columns; the
// last block's rows touch it alone). Static rows (prior, CUPT, GUPT) of the block's epochs and the
// dynamic rows whose stencil starts in it: every row of the network belongs to exactly one block.
class ObservationRows {
 public:
  explicit ObservationRows(const LinearInsNetworkOptions& o)
      : o_(o), size_(LinearInsNetworkSize(o)), st_(MakeStencil(o)), sqrt_w_(RowWeights(o).cwiseSqrt()),
        gps_step_(GpsStep(o)), g_(o.rule == Discretisation::kLeapFrog ? 2 : 1) {}
  int block_size() const { return size_.block_size; }
  int num_blocks() const { return size_.num_blocks; }
  const NetworkSize& size() const { return size_; }

  // Fills rows 0 .. count-1 of *M (resized to at least max_rows() x (2b + 1)), returns count.
  int Fill(int j, Eigen::MatrixXd* M) const {
    const int b = size_.block_size;
    const long long E = size_.imu_epochs, first = static_cast<long long>(g_) * j;
    const int max_rows = kP * (g_ + 1) + g_ * (kP + 6);
    if (M->rows() < max_rows || M->cols() != 2 * b + 1) M->resize(max_rows, 2 * b + 1);
    M->setZero();
    int r = 0;
    const double s_gps = 1.0 / o_.sigma_gps_m, s_prior = 1.0 / o_.sigma_prior, s_gupt = 1.0 / o_.sigma_gupt_mps2;
    for (int e = 0; e < g_; ++e) {
      const long long n = first + e;
      const Vec18 xs = LinearInsTruth(n, o_.imu_rate_hz);
      if (n < o_.prior_epochs) {
        for (int c = 0; c < kP; ++c, ++r) {
          (*M)(r, e * kP + c) = s_prior;
          (*M)(r, 2 * b) = s_prior * xs[c];
        }
      }
      if (IsGpsEpoch(n, gps_step_)) {
        for (int c = 0; c < 3; ++c, ++r) {
          (*M)(r, e * kP + c) = s_gps;
          (*M)(r, 2 * b) = s_gps * xs[c];
        }
      }
      if (n >= E - o_.gupt_end_epochs) {
        for (int c = 15; c < 18; ++c, ++r) {
          (*M)(r, e * kP + c) = s_gupt;
          (*M)(r, 2 * b) = s_gupt * xs[c];
        }
      }
    }
    const int m = static_cast<int>(st_.offsets.size());
    for (long long n = first - st_.offsets.front(); n < first + g_ - st_.offsets.front(); ++n) {
      if (n < st_.first_center || n > E - 2) continue;
      Vec18 l = Vec18::Zero();
      for (int a = 0; a < m; ++a) {
        const long long p = n + st_.offsets[static_cast<size_t>(a)];
        l.noalias() += st_.J[static_cast<size_t>(a)] * LinearInsTruth(p, o_.imu_rate_hz);  // noise-free
        M->block<kP, kP>(r, static_cast<int>(p - first) * kP) = sqrt_w_.asDiagonal() * st_.J[static_cast<size_t>(a)];
      }
      M->block<kP, 1>(r, 2 * b) = sqrt_w_.cwiseProduct(l);
      r += kP;
    }
    return r;
  }

 private:
  LinearInsNetworkOptions o_;
  NetworkSize size_;
  Stencil st_;
  Vec18 sqrt_w_;
  long long gps_step_;
  int g_;
};

// What the QR of block j passes to block j+1: the square-root information R (b x b, upper) and
// z of block j+1 given the rows of blocks <= j, and the squared column norms of block j's rows on
// block j+1 (half of block j+1's A_kk, for the relative pivot).
struct SqrtCarry {
  Eigen::MatrixXd R;
  Eigen::VectorXd z, colnorm2;
};

}  // namespace

LinearInsNetworkResult SolveLinearInsNetworkQr(const LinearInsNetworkOptions& o, bool gravity_covariance,
                                               int checkpoint_interval, bool keep_gravity_estimate,
                                               double pivot_tolerance) {
  CheckArgument(checkpoint_interval >= 0, "checkpoint_interval", "must be >= 0");
  CheckArgument(pivot_tolerance >= 0.0 && pivot_tolerance < 1.0, "pivot_tolerance",
                "must be in [0, 1), got " + FormatValue(pivot_tolerance));
  WallTimer total;
  const ObservationRows rows(o);
  LinearInsNetworkResult result;
  result.size = rows.size();
  const int n = rows.num_blocks(), b = rows.block_size();
  const int g = o.rule == Discretisation::kLeapFrog ? 2 : 1;
  const long long E = result.size.imu_epochs;
  const int k = (checkpoint_interval <= 0 || checkpoint_interval >= n) ? n : checkpoint_interval;
  const int segments = (n + k - 1) / k;
  BlockTridiagonalSummary& summary = result.solver;
  summary.num_blocks = n;
  summary.block_size = b;
  summary.min_relative_pivot = 1.0;

  // Factor of one position: R_jj (b x b), R_{j,j+1} (b x b), z_j (b).
  const size_t stride = 2 * static_cast<size_t>(b) * b + b;
  std::vector<double> store(static_cast<size_t>(k) * stride);
  std::vector<SqrtCarry> checkpoints(static_cast<size_t>(segments));
  Eigen::MatrixXd M, S;

  // QR of [carry; rows of block j]: Householder on the stacked whitened equations, so that the
  // normal matrix (whose condition is the square of theirs) is never formed.
  auto step = [&](int j, SqrtCarry* carry, double* out, bool record) {
    CheckInterrupt();
    ++summary.assembler_calls;
    const int count = rows.Fill(j, &M);
    const bool last = j == n - 1;
    const int width = last ? b + 1 : 2 * b + 1;
    const int carried = j > 0 ? b : 0;
    const int height = std::max(carried + count, width);
    S.setZero(height, width);
    if (j > 0) {
      S.topLeftCorner(b, b) = carry->R.triangularView<Eigen::Upper>();
      S.block(0, width - 1, b, 1) = carry->z;
    }
    S.block(carried, 0, count, last ? b : 2 * b) = M.topLeftCorner(count, last ? b : 2 * b);
    S.block(carried, width - 1, count, 1) = M.block(0, 2 * b, count, 1);
    // A_kk of block j: its own rows plus the previous block's rows on it.
    Eigen::VectorXd a_kk = M.topLeftCorner(count, b).colwise().squaredNorm().transpose();
    if (j > 0) a_kk += carry->colnorm2;
    Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(S);
    // Rank test: R_kk² is the Cholesky pivot of the same unknown (A = RᵀR), here computed
    // without the squaring; against A_kk as in SolveBlockTridiagonal.
    for (int c = 0; c < b; ++c) {
      const double ratio = S(c, c) * S(c, c) / std::max(a_kk[c], 1e-300);
      if (record && ratio < summary.min_relative_pivot) {
        summary.min_relative_pivot = ratio;
        summary.min_relative_pivot_block = j;
        summary.min_relative_pivot_unknown = c;
      }
      if (!(ratio > pivot_tolerance)) {
        std::ostringstream msg;
        msg << "indoorloc: the observation equations are rank-deficient at block " << j << ", unknown " << c
            << " of the block (rank-deficient network: a datum defect or an unobservable parameter there; relative "
               "pivot R_kk²/A_kk "
            << ratio << " < tolerance " << pivot_tolerance << ")";
        throw std::runtime_error(msg.str());
      }
    }
    Eigen::Map<Eigen::MatrixXd>(out, b, b) = S.topLeftCorner(b, b).triangularView<Eigen::Upper>();
    Eigen::Map<Eigen::VectorXd>(out + 2 * static_cast<size_t>(b) * b, b) = S.block(0, width - 1, b, 1);
    if (!last) {
      Eigen::Map<Eigen::MatrixXd>(out + static_cast<size_t>(b) * b, b, b) = S.block(0, b, b, b);
      carry->R = S.block(b, b, b, b).triangularView<Eigen::Upper>();
      carry->z = S.block(b, 2 * b, b, 1);
      carry->colnorm2 = M.block(0, b, count, b).colwise().squaredNorm().transpose();
    } else {
      Eigen::Map<Eigen::MatrixXd>(out + static_cast<size_t>(b) * b, b, b).setZero();
    }
  };

  WallTimer timer;
  {
    SqrtCarry carry;
    for (int j = 0; j < n; ++j) {
      if (j % k == 0) checkpoints[static_cast<size_t>(j / k)] = carry;
      step(j, &carry, store.data() + static_cast<size_t>(j % k) * stride, true);
    }
  }
  summary.factor_seconds = timer.ElapsedSeconds();
  timer.Reset();

  std::vector<int> selected;
  if (gravity_covariance)
    for (int e = 0; e < g; ++e)
      for (int c = 15; c < 18; ++c) selected.push_back(e * kP + c);
  TruthScore score(E, o.imu_rate_hz, keep_gravity_estimate ? &result.gravity_estimate : nullptr);
  if (gravity_covariance) result.gravity_sigma.resize(E, 3);
  Eigen::VectorXd x_next, x, r;
  Eigen::MatrixXd sigma_next, sigma_ii, sigma_off, Rinv, CL, R_next_off;
  for (int s = segments - 1; s >= 0; --s) {
    const int begin = s * k, end = std::min(n, begin + k);
    if (s != segments - 1 || segments > 1) {
      // Refactor the segment from its checkpoint (the last segment is still in store when there
      // is only one; otherwise every segment is recomputed, the same operations in the same order).
      SqrtCarry carry = checkpoints[static_cast<size_t>(s)];
      for (int j = begin; j < end; ++j) step(j, &carry, store.data() + static_cast<size_t>(j - begin) * stride, false);
    }
    for (int j = end - 1; j >= begin; --j) {
      const double* at = store.data() + static_cast<size_t>(j - begin) * stride;
      const Eigen::Map<const Eigen::MatrixXd> R(at, b, b), Roff(at + static_cast<size_t>(b) * b, b, b);
      const Eigen::Map<const Eigen::VectorXd> z(at + 2 * static_cast<size_t>(b) * b, b);
      r = z;
      if (j < n - 1) r.noalias() -= Roff * x_next;
      x = R.triangularView<Eigen::Upper>().solve(r);
      if (gravity_covariance) {
        // Takahashi with L_j = R_jjᵀ, C_{j+1} = R_{j,j+1}ᵀ (A = RᵀR):
        // Σ_{j+1,j} = -Σ_{j+1,j+1} R_{j,j+1}ᵀ R_jj^{-T},  Σ_jj = R_jj^{-1} R_jj^{-T} - Σ_{j+1,j}ᵀ R_{j,j+1}ᵀ R_jj^{-T}.
        Rinv.setIdentity(b, b);
        R.triangularView<Eigen::Upper>().solveInPlace(Rinv);
        sigma_ii.noalias() = Rinv * Rinv.transpose();
        if (j < n - 1) {
          CL.noalias() = Roff.transpose() * Rinv.transpose();
          sigma_off.noalias() = -sigma_next * CL;
          sigma_ii.noalias() -= sigma_off.transpose() * CL;
        }
        sigma_ii = 0.5 * (sigma_ii + sigma_ii.transpose()).eval();
        sigma_next.swap(sigma_ii);
      }
      for (int e = 0; e < g; ++e) {
        const long long ep = static_cast<long long>(g) * j + e;
        score.Add(ep, x.segment<kP>(e * kP));
        if (gravity_covariance)
          for (int c = 0; c < 3; ++c)
            result.gravity_sigma(ep, c) = std::sqrt(std::max(0.0, sigma_next(e * kP + 15 + c, e * kP + 15 + c)));
      }
      x_next.swap(x);
    }
  }
  summary.backward_seconds = timer.ElapsedSeconds();
  summary.stored_factor_bytes = 8.0 * (static_cast<double>(store.size()) + segments * (b * b + 2.0 * b));
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
