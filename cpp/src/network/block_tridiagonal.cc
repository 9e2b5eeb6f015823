#include "indoorloc/network/block_tridiagonal.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <Eigen/Cholesky>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"

namespace indoorloc::network {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// The factor of a run of consecutive blocks [first, first + L.size()).
struct Segment {
  int first = 0;
  std::vector<MatrixXd> L;  // lower-triangular diagonal blocks L_i
  std::vector<MatrixXd> C;  // sub-diagonal blocks C_i = A_{i,i-1} L_{i-1}^{-T} (zero for i = 0)
  std::vector<VectorXd> y;  // forward-substituted right-hand side
};

// Forward recursion state at the end of a block: what the next block needs.
struct Carry {
  MatrixXd L;
  VectorXd y;
  bool valid = false;
};

class ForwardPass {
 public:
  ForwardPass(int block_size, const BlockRowAssembler& assemble, const BlockTridiagonalOptions& options,
              BlockTridiagonalSummary* summary)
      : b_(block_size), assemble_(assemble), options_(options), summary_(summary),
        diagonal_(block_size, block_size), lower_(block_size, block_size), rhs_(block_size) {}

  const VectorXd& last_rhs() const { return rhs_; }

  // Factors block i given the carry of block i-1; writes L_i, C_i, y_i.
  void Step(int i, const Carry& previous, MatrixXd* L, MatrixXd* C, VectorXd* y) {
    diagonal_.setZero();
    lower_.setZero();
    rhs_.setZero();
    assemble_(i, &diagonal_, &lower_, &rhs_);
    ++summary_->assembler_calls;
    if (diagonal_.rows() != b_ || diagonal_.cols() != b_ || lower_.rows() != b_ || lower_.cols() != b_ || rhs_.size() != b_) {
      ThrowInvalidArgument("assemble", "block " + std::to_string(i) + ": the assembler resized its outputs");
    }
    if (!diagonal_.allFinite() || !rhs_.allFinite() || (i > 0 && !lower_.allFinite())) {
      ThrowInvalidArgument("assemble", "block " + std::to_string(i) + " has a NaN or infinite entry");
    }
    MatrixXd S = diagonal_;
    if (i > 0) {
      // C_i = A_{i,i-1} L_{i-1}^{-T}  <=>  C_iᵀ = L_{i-1}^{-1} A_{i,i-1}ᵀ.
      *C = previous.L.triangularView<Eigen::Lower>().solve(lower_.transpose()).transpose();
      // Lower triangle only (all the LLT below reads): half the flops of the full product.
      S.selfadjointView<Eigen::Lower>().rankUpdate(*C, -1.0);
    } else {
      C->setZero(b_, b_);
    }
    // Rank test, invariant to the units of each unknown: the conditional information of unknown k
    // given the unknowns before it (pivot L_kk²) against its information alone (A_kk). A ratio
    // near zero means the unknown is (numerically) determined by the others: a rank defect.
    Eigen::LLT<MatrixXd> llt(S);
    double min_ratio = -1.0;
    if (llt.info() == Eigen::Success) {
      min_ratio = 1.0;
      for (int k = 0; k < b_; ++k) {
        const double info = std::max(diagonal_(k, k), 1e-300);
        min_ratio = std::min(min_ratio, llt.matrixLLT()(k, k) * llt.matrixLLT()(k, k) / info);
      }
    }
    if (llt.info() != Eigen::Success || !(min_ratio > options_.pivot_tolerance)) {
      std::ostringstream msg;
      msg << "indoorloc: the normal matrix is not positive definite at block " << i
          << " (rank-deficient network: a datum defect or an unobservable parameter there; relative pivot "
          << std::max(min_ratio, 0.0) << " < tolerance " << options_.pivot_tolerance << ")";
      throw std::runtime_error(msg.str());
    }
    summary_->min_relative_pivot = std::min(summary_->min_relative_pivot, min_ratio);
    *L = llt.matrixL();
    VectorXd r = rhs_;
    if (i > 0) r.noalias() -= (*C) * previous.y;
    *y = L->triangularView<Eigen::Lower>().solve(r);
  }

 private:
  int b_;
  const BlockRowAssembler& assemble_;
  const BlockTridiagonalOptions& options_;
  BlockTridiagonalSummary* summary_;
  MatrixXd diagonal_, lower_;
  VectorXd rhs_;
};

MatrixXd Restrict(const MatrixXd& m, const std::vector<int>& idx) {
  MatrixXd out(idx.size(), idx.size());
  for (size_t r = 0; r < idx.size(); ++r)
    for (size_t c = 0; c < idx.size(); ++c) out(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = m(idx[r], idx[c]);
  return out;
}

}  // namespace

bool BlockTridiagonalOptions::IsValid(std::string* error) const {
  if (checkpoint_interval < 0) {
    *error = "checkpoint_interval must be >= 0 (0: keep the whole factor)";
    return false;
  }
  if (!(pivot_tolerance >= 0.0 && pivot_tolerance < 1.0)) {
    *error = "pivot_tolerance must be in [0, 1)";
    return false;
  }
  std::vector<int> sorted = selected;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
    *error = "selected has repeated indices";
    return false;
  }
  return true;
}

std::string BlockTridiagonalSummary::BriefReport() const {
  std::ostringstream s;
  s << "block-tridiagonal: " << num_blocks << " blocks of " << block_size << ", factor " << factor_seconds
    << " s, backward " << backward_seconds << " s, " << assembler_calls << " assembler calls, factor memory "
    << stored_factor_bytes / (1024.0 * 1024.0) << " MiB, min relative pivot " << min_relative_pivot;
  return s.str();
}

BlockTridiagonalSolution SolveBlockTridiagonal(int num_blocks, int block_size, const BlockRowAssembler& assemble,
                                               const BlockTridiagonalOptions& options) {
  ValidateOptions(options);
  CheckArgument(num_blocks >= 1, "num_blocks", "must be >= 1, got " + std::to_string(num_blocks));
  CheckArgument(block_size >= 1, "block_size", "must be >= 1, got " + std::to_string(block_size));
  CheckArgument(static_cast<bool>(assemble), "assemble", "is empty");
  for (int s : options.selected) {
    CheckArgument(s >= 0 && s < block_size, "selected",
                  "index " + std::to_string(s) + " is outside the block (size " + std::to_string(block_size) + ")");
  }
  const int n = num_blocks, b = block_size;
  const int k = (options.checkpoint_interval <= 0 || options.checkpoint_interval >= n) ? n : options.checkpoint_interval;
  const bool keep_all = k == n;
  const bool invert = !options.selected.empty();

  BlockTridiagonalSolution out;
  BlockTridiagonalSummary& summary = out.summary;
  summary.num_blocks = n;
  summary.block_size = b;
  summary.min_relative_pivot = 1.0;
  out.x.resize(static_cast<Eigen::Index>(n) * b);
  if (invert) out.covariance.resize(static_cast<size_t>(n));
  if (invert && options.neighbour_covariances) out.neighbour_covariance.resize(static_cast<size_t>(n - 1));

  ForwardPass forward(b, assemble, options, &summary);
  const double block_bytes = 8.0 * (2.0 * b * b + b);
  const int num_segments = (n + k - 1) / k;

  // Forward pass: keep everything (one segment), or only the carry entering each segment.
  WallTimer timer;
  Segment all;
  std::vector<Carry> checkpoints(static_cast<size_t>(num_segments));
  {
    Carry carry;
    MatrixXd L, C;
    VectorXd y;
    if (keep_all) {
      all.L.resize(static_cast<size_t>(n));
      all.C.resize(static_cast<size_t>(n));
      all.y.resize(static_cast<size_t>(n));
    }
    for (int i = 0; i < n; ++i) {
      if (i % k == 0) checkpoints[static_cast<size_t>(i / k)] = carry;
      forward.Step(i, carry, &L, &C, &y);
      if (keep_all) {
        all.L[static_cast<size_t>(i)] = L;
        all.C[static_cast<size_t>(i)] = C;
        all.y[static_cast<size_t>(i)] = y;
      }
      carry.L.swap(L);
      carry.y.swap(y);
      carry.valid = true;
    }
  }
  summary.factor_seconds = timer.ElapsedSeconds();
  summary.stored_factor_bytes = keep_all ? n * block_bytes : num_segments * 8.0 * (b * b + b) + k * block_bytes;

  // Backward pass, one segment at a time from the last.
  timer.Reset();
  VectorXd x_next;               // x_{i+1}
  MatrixXd C_next;               // C_{i+1}
  MatrixXd sigma_next;           // Σ_{i+1,i+1} (full b x b)
  MatrixXd Linv, sigma_off, sigma_ii;
  Segment seg;
  for (int sidx = num_segments - 1; sidx >= 0; --sidx) {
    const int first = sidx * k, last = std::min(n, first + k);  // [first, last)
    const Segment* s = &all;
    int offset = 0;
    if (!keep_all) {
      seg.first = first;
      const size_t len = static_cast<size_t>(last - first);
      seg.L.resize(len);
      seg.C.resize(len);
      seg.y.resize(len);
      Carry carry = checkpoints[static_cast<size_t>(sidx)];
      for (int i = first; i < last; ++i) {
        const size_t j = static_cast<size_t>(i - first);
        forward.Step(i, carry, &seg.L[j], &seg.C[j], &seg.y[j]);
        carry.L = seg.L[j];
        carry.y = seg.y[j];
      }
      s = &seg;
      offset = first;
    }
    for (int i = last - 1; i >= first; --i) {
      const size_t j = static_cast<size_t>(i - offset);
      const MatrixXd& L = s->L[j];
      const auto Lt = L.triangularView<Eigen::Lower>();
      VectorXd r = s->y[j];
      if (i < n - 1) r.noalias() -= C_next.transpose() * x_next;
      VectorXd x = Lt.transpose().solve(r);
      out.x.segment(static_cast<Eigen::Index>(i) * b, b) = x;
      if (invert) {
        Linv = Lt.solve(MatrixXd::Identity(b, b));
        if (i == n - 1) {
          sigma_ii.noalias() = Linv.transpose() * Linv;
        } else {
          const MatrixXd CL = C_next * Linv;  // C_{i+1} L_i^{-1}
          sigma_off.noalias() = -sigma_next * CL;  // Σ_{i+1,i}
          sigma_ii.noalias() = Linv.transpose() * Linv;
          sigma_ii.noalias() -= sigma_off.transpose() * CL;
          if (options.neighbour_covariances) out.neighbour_covariance[static_cast<size_t>(i)] = Restrict(sigma_off, options.selected);
        }
        sigma_ii = 0.5 * (sigma_ii + sigma_ii.transpose()).eval();
        out.covariance[static_cast<size_t>(i)] = Restrict(sigma_ii, options.selected);
        sigma_next.swap(sigma_ii);
      }
      x_next.swap(x);
      C_next = s->C[j];
    }
  }
  summary.backward_seconds = timer.ElapsedSeconds();
  return out;
}

BlockTridiagonalFactor::BlockTridiagonalFactor(int num_blocks, int block_size, const BlockRowAssembler& assemble,
                                               double pivot_tolerance)
    : n_(num_blocks), b_(block_size) {
  CheckArgument(num_blocks >= 1, "num_blocks", "must be >= 1, got " + std::to_string(num_blocks));
  CheckArgument(block_size >= 1, "block_size", "must be >= 1, got " + std::to_string(block_size));
  CheckArgument(static_cast<bool>(assemble), "assemble", "is empty");
  BlockTridiagonalOptions options;
  options.pivot_tolerance = pivot_tolerance;
  ValidateOptions(options);
  BlockTridiagonalSummary summary;
  summary.min_relative_pivot = 1.0;
  ForwardPass forward(b_, assemble, options, &summary);
  L_.resize(static_cast<size_t>(n_));
  C_.resize(static_cast<size_t>(n_));
  rhs_.resize(static_cast<Eigen::Index>(n_) * b_);
  Carry carry;
  VectorXd y;
  for (int i = 0; i < n_; ++i) {
    forward.Step(i, carry, &L_[static_cast<size_t>(i)], &C_[static_cast<size_t>(i)], &y);
    rhs_.segment(static_cast<Eigen::Index>(i) * b_, b_) = forward.last_rhs();
    carry.L = L_[static_cast<size_t>(i)];
    carry.y = y;
    carry.valid = true;
  }
}

VectorXd BlockTridiagonalFactor::Solve(const VectorXd& rhs) const {
  CheckArgument(rhs.size() == static_cast<Eigen::Index>(n_) * b_, "rhs", "must have num_blocks * block_size entries");
  // In place, no allocation per block: forward L y = rhs, then back Lᵀ x = y.
  VectorXd x = rhs;
  VectorXd tmp(b_);
  for (int i = 0; i < n_; ++i) {
    auto xi = x.segment(static_cast<Eigen::Index>(i) * b_, b_);
    if (i > 0) xi.noalias() -= C_[static_cast<size_t>(i)] * x.segment(static_cast<Eigen::Index>(i - 1) * b_, b_);
    L_[static_cast<size_t>(i)].triangularView<Eigen::Lower>().solveInPlace(xi);
  }
  for (int i = n_ - 1; i >= 0; --i) {
    auto xi = x.segment(static_cast<Eigen::Index>(i) * b_, b_);
    if (i < n_ - 1) {
      tmp.noalias() = C_[static_cast<size_t>(i + 1)].transpose() * x.segment(static_cast<Eigen::Index>(i + 1) * b_, b_);
      xi -= tmp;
    }
    L_[static_cast<size_t>(i)].triangularView<Eigen::Lower>().transpose().solveInPlace(xi);
  }
  return x;
}

VectorXd BlockTridiagonalFactor::Multiply(const VectorXd& x) const {
  CheckArgument(x.size() == static_cast<Eigen::Index>(n_) * b_, "x", "must have num_blocks * block_size entries");
  // y = Lᵀ x: y_i = L_iᵀ x_i + C_{i+1}ᵀ x_{i+1};  z = L y: z_i = C_i y_{i-1} + L_i y_i.
  VectorXd y(x.size()), z(x.size());
  for (int i = 0; i < n_; ++i) {
    auto yi = y.segment(static_cast<Eigen::Index>(i) * b_, b_);
    yi.noalias() = L_[static_cast<size_t>(i)].triangularView<Eigen::Lower>().transpose() * x.segment(static_cast<Eigen::Index>(i) * b_, b_);
    if (i < n_ - 1) yi.noalias() += C_[static_cast<size_t>(i + 1)].transpose() * x.segment(static_cast<Eigen::Index>(i + 1) * b_, b_);
  }
  for (int i = 0; i < n_; ++i) {
    auto zi = z.segment(static_cast<Eigen::Index>(i) * b_, b_);
    zi.noalias() = L_[static_cast<size_t>(i)].triangularView<Eigen::Lower>() * y.segment(static_cast<Eigen::Index>(i) * b_, b_);
    if (i > 0) zi.noalias() += C_[static_cast<size_t>(i)] * y.segment(static_cast<Eigen::Index>(i - 1) * b_, b_);
  }
  return z;
}

}  // namespace indoorloc::network
