// The orthogonal (square-root information) solve of the linearised INS network
// (SolveLinearInsNetworkQr, indoorloc/network/linear_ins_network.h): the same network as
// SolveLinearInsNetwork, factored from its whitened observation equations by Householder QR block
// by block instead of from the normal matrix by Cholesky, so that the condition of weak modes of
// long chains is not squared (docs/network_scale.md, "Case 3").
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/QR>

#include "indoorloc/core/check.h"
#include "indoorloc/core/interrupt.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/network/linear_ins_network.h"
#include "linear_ins_network_internal.h"

namespace indoorloc::network {

using namespace internal;  // NOLINT(build/namespaces): the network's private parts


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

}  // namespace indoorloc::network
