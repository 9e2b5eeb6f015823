#include "indoorloc/network/block_tridiagonal.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <functional>
#include <memory>
#include <new>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <Eigen/Cholesky>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "indoorloc/core/check.h"
#include "indoorloc/core/interrupt.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "indoorloc/core/random.h"

namespace indoorloc::network {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// An eliminated neighbour of the block being eliminated: the coupling A_{i,j} (b x b) and the
// neighbour's factor L_j and forward-substituted right-hand side y_j.
struct Neighbour {
  const MatrixXd* coupling = nullptr;
  const MatrixXd* L = nullptr;
  const VectorXd* y = nullptr;
};

// Eliminates one block against up to two eliminated neighbours (one in a chain, two at the
// middle of the twisted order), in scratch it owns so that the inner loop does not allocate:
//     C_k = A_{i,j_k} L_{j_k}^{-T},  S = A_ii - Σ_k C_k C_kᵀ,  L_i = chol(S),  y_i = L_i^{-1} (b_i - Σ_k C_k y_{j_k}).
class BlockEliminator {
 public:
  BlockEliminator(int block_size, double pivot_tolerance)
      : b_(block_size), tolerance_(pivot_tolerance), r_(block_size) {}

  // Returns the smallest relative pivot (see BlockTridiagonalOptions::pivot_tolerance); throws
  // std::runtime_error naming `block` when S is not (numerically) positive definite.
  double Eliminate(int block, const MatrixXd& diagonal, const VectorXd& rhs, const Neighbour* first, MatrixXd* C_first,
                   const Neighbour* second, MatrixXd* C_second, MatrixXd* L, VectorXd* y, int* min_unknown = nullptr) {
    *L = diagonal;
    r_ = rhs;
    for (auto [n, C] : {std::pair<const Neighbour*, MatrixXd*>{first, C_first}, {second, C_second}}) {
      if (n == nullptr) continue;
      // C L_jᵀ = A_{i,j}  <=>  C = A_{i,j} L_j^{-T}.
      *C = *n->coupling;
      n->L->transpose().triangularView<Eigen::Upper>().solveInPlace<Eigen::OnTheRight>(*C);
      // Lower triangle only (all the factorisation reads): half the flops of the full product.
      L->selfadjointView<Eigen::Lower>().rankUpdate(*C, -1.0);
      r_.noalias() -= (*C) * (*n->y);
    }
    // In place: L's lower triangle becomes the factor of S.
    Eigen::LLT<Eigen::Ref<MatrixXd>> llt(*L);
    // Rank test, invariant to the units of each unknown: the conditional information of unknown k
    // given the unknowns before it (pivot L_kk²) against its information alone (A_kk). A ratio
    // near zero means the unknown is (numerically) determined by the others: a rank defect.
    double min_ratio = -1.0;
    int argmin = 0;
    if (llt.info() == Eigen::Success) {
      min_ratio = 1.0;
      for (int k = 0; k < b_; ++k) {
        const double info = std::max(diagonal(k, k), 1e-300);
        const double ratio = (*L)(k, k) * (*L)(k, k) / info;
        if (ratio < min_ratio) {
          min_ratio = ratio;
          argmin = k;
        }
      }
    }
    if (min_unknown != nullptr) *min_unknown = argmin;
    if (llt.info() != Eigen::Success || !(min_ratio > tolerance_)) {
      std::ostringstream msg;
      msg << "indoorloc: the normal matrix is not positive definite at block " << block;
      if (llt.info() == Eigen::Success) msg << ", unknown " << argmin << " of the block";
      msg << " (rank-deficient network: a datum defect or an unobservable parameter there; relative pivot "
          << std::max(min_ratio, 0.0) << " < tolerance " << tolerance_ << ")";
      throw std::runtime_error(msg.str());
    }
    L->triangularView<Eigen::StrictlyUpper>().setZero();
    L->triangularView<Eigen::Lower>().solveInPlace(r_);
    *y = r_;
    return min_ratio;
  }

 private:
  int b_;
  double tolerance_;
  VectorXd r_;
};

// Calls `assemble` for block i and checks what it returned.
void AssembleChecked(const BlockRowAssembler& assemble, int i, int b, MatrixXd* diagonal, MatrixXd* lower, VectorXd* rhs) {
  // Every pass over the band assembles block by block: Ctrl-C is polled here (networks of
  // millions of epochs run for minutes).
  CheckInterrupt();
  diagonal->setZero(b, b);
  lower->setZero(b, b);
  rhs->setZero(b);
  assemble(i, diagonal, lower, rhs);
  if (diagonal->rows() != b || diagonal->cols() != b || lower->rows() != b || lower->cols() != b || rhs->size() != b) {
    ThrowInvalidArgument("assemble", "block " + std::to_string(i) + ": the assembler resized its outputs");
  }
  if (!diagonal->allFinite() || !rhs->allFinite() || (i > 0 && !lower->allFinite())) {
    ThrowInvalidArgument("assemble", "block " + std::to_string(i) + " has a NaN or infinite entry");
  }
}

MatrixXd Restrict(const MatrixXd& m, const std::vector<int>& idx, bool transpose = false) {
  MatrixXd out(idx.size(), idx.size());
  for (size_t r = 0; r < idx.size(); ++r)
    for (size_t c = 0; c < idx.size(); ++c)
      out(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = transpose ? m(idx[c], idx[r]) : m(idx[r], idx[c]);
  return out;
}

// The factor of a run of consecutive positions of a chain (L_i, C_i, y_i) in one contiguous buffer:
// one allocation instead of three per block, so that storing a long factor costs the first touch of
// its pages and no allocator traffic (which, with two chains allocating at once, cost more than the
// arithmetic). The buffer is 2 MiB aligned and, on Linux, advised to use transparent huge pages:
// a case-size factor is about a GiB, and faulting it in 4 KiB pages took as long as factoring it.
// Not zeroed: Put writes every position before it is read.
class FactorStore {
 public:
  void Resize(int positions, int block_size) {
    b_ = block_size;
    stride_ = 2 * static_cast<size_t>(b_) * b_ + b_;
    constexpr size_t kHugePage = size_t{2} << 20;
    const size_t bytes = std::max<size_t>(1, static_cast<size_t>(positions) * stride_) * sizeof(double);
    const size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
    data_.reset(static_cast<double*>(std::aligned_alloc(kHugePage, rounded)));
    if (!data_) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    madvise(data_.get(), rounded, MADV_HUGEPAGE);  // a hint: without it the kernel uses 4 KiB pages
#endif
  }
  void Put(int j, const MatrixXd& L, const MatrixXd& C, const VectorXd& y) {
    double* at = data_.get() + static_cast<size_t>(j) * stride_;
    const size_t bb = static_cast<size_t>(b_) * b_;
    std::copy(L.data(), L.data() + bb, at);
    std::copy(C.data(), C.data() + bb, at + bb);
    std::copy(y.data(), y.data() + b_, at + 2 * bb);
  }
  Eigen::Map<const MatrixXd> L(int j) const { return Eigen::Map<const MatrixXd>(At(j), b_, b_); }
  Eigen::Map<const MatrixXd> C(int j) const { return Eigen::Map<const MatrixXd>(At(j) + static_cast<size_t>(b_) * b_, b_, b_); }
  Eigen::Map<const VectorXd> y(int j) const { return Eigen::Map<const VectorXd>(At(j) + 2 * static_cast<size_t>(b_) * b_, b_); }

 private:
  struct Free {
    void operator()(double* p) const { std::free(p); }
  };
  const double* At(int j) const { return data_.get() + static_cast<size_t>(j) * stride_; }
  int b_ = 0;
  size_t stride_ = 0;
  std::unique_ptr<double[], Free> data_;
};

// What the elimination of one block passes to the next: its factor and forward-substituted
// right-hand side, and (bottom chain) the assembler's `lower` of the block, A_{i,i-1}, which is
// the transposed coupling of the block eliminated after it.
struct Carry {
  MatrixXd L;
  VectorXd y;
  MatrixXd lower;
};

// One chain of the twisted order: `length` blocks first, first + step, .., each eliminated against
// the one before it (step +1: the top chain, coupled to its predecessor by the assembler's lower
// block; step -1: the bottom chain, coupled by the transpose of its predecessor's lower block).
class Chain {
 public:
  Chain(int first, int length, int step, int block_size, const BlockRowAssembler& assemble,
        const BlockTridiagonalOptions& options)
      : first_(first), length_(length), step_(step), b_(block_size), assemble_(assemble), options_(options),
        eliminator_(block_size, options.pivot_tolerance) {
    const int ci = options.checkpoint_interval;
    k_ = (ci <= 0 || ci >= length_) ? std::max(length_, 1) : ci;
    keep_all_ = k_ >= length_;
    num_segments_ = (length_ + k_ - 1) / k_;
  }

  int length() const { return length_; }
  int block(int p) const { return first_ + step_ * p; }
  // After Forward: the last block's factor, y and (bottom chain) lower block.
  const Carry& last() const { return last_; }
  long long assembler_calls() const { return assembler_calls_; }
  double min_relative_pivot() const { return min_ratio_; }
  int min_relative_pivot_block() const { return min_block_; }
  int min_relative_pivot_unknown() const { return min_unknown_; }
  double stored_bytes() const {
    const double block_bytes = 8.0 * (2.0 * b_ * b_ + b_);
    // Stored factor, or one checkpoint (L, y and the bottom chain's lower block) per segment plus
    // one refactored segment.
    return keep_all_ ? length_ * block_bytes : (num_segments_ + k_) * block_bytes;
  }

  void Forward() {
    if (keep_all_) store_.Resize(length_, b_);
    checkpoints_.resize(static_cast<size_t>(num_segments_));
    Carry carry;
    MatrixXd L, C;
    VectorXd y;
    for (int p = 0; p < length_; ++p) {
      if (p % k_ == 0) checkpoints_[static_cast<size_t>(p / k_)] = carry;
      Step(p, &carry, &L, &C, &y);
      if (keep_all_) store_.Put(p, L, C, y);
    }
    last_ = std::move(carry);
    if (!keep_all_) checkpoints_.shrink_to_fit();
  }

  // Back substitution and selected inversion from the chain's last block to its first, given the
  // block eliminated after the chain (the middle): its solution x, its coupling factor C to the
  // chain's last block and, when inverting, its full covariance Σ.
  void Backward(const VectorXd& x_after, const MatrixXd& C_after, const MatrixXd* sigma_after,
                BlockTridiagonalSolution* out) {
    const bool invert = !options_.selected.empty();
    VectorXd x_next = x_after, x, r;
    MatrixXd C_next = C_after, sigma_next, Linv, CL, sigma_off, sigma_ii;
    if (invert) sigma_next = *sigma_after;
    FactorStore segment;  // the refactored segment when checkpointed
    if (!keep_all_) segment.Resize(k_, b_);
    MatrixXd L_step, C_step;
    VectorXd y_step;
    for (int s = num_segments_ - 1; s >= 0; --s) {
      const int begin = s * k_, end = std::min(length_, begin + k_);  // positions [begin, end)
      const FactorStore* store = &store_;
      int offset = 0;
      if (!keep_all_) {
        Carry carry = checkpoints_[static_cast<size_t>(s)];
        for (int p = begin; p < end; ++p) {
          Step(p, &carry, &L_step, &C_step, &y_step);
          segment.Put(p - begin, L_step, C_step, y_step);
        }
        store = &segment;
        offset = begin;
      }
      for (int p = end - 1; p >= begin; --p) {
        const int j = p - offset;
        const Eigen::Map<const MatrixXd> L = store->L(j);
        const auto Lt = L.triangularView<Eigen::Lower>();
        r = store->y(j);
        r.noalias() -= C_next.transpose() * x_next;
        x = Lt.transpose().solve(r);
        const int i = block(p);
        out->x.segment(static_cast<Eigen::Index>(i) * b_, b_) = x;
        if (invert) {
          // Σ_{next,i} = -Σ_next C_next L_i^{-1},  Σ_ii = L_i^{-T} L_i^{-1} - Σ_{next,i}ᵀ C_next L_i^{-1}.
          Linv.setIdentity(b_, b_);
          Lt.solveInPlace(Linv);
          CL.noalias() = C_next * Linv;
          sigma_off.noalias() = -sigma_next * CL;
          sigma_ii.noalias() = Linv.transpose() * Linv;
          sigma_ii.noalias() -= sigma_off.transpose() * CL;
          sigma_ii = 0.5 * (sigma_ii + sigma_ii.transpose()).eval();
          if (options_.neighbour_covariances) {
            // Σ_{i+1,i} is stored at i: the top chain's next block is i+1, the bottom chain's i-1.
            if (step_ > 0) {
              out->neighbour_covariance[static_cast<size_t>(i)] = Restrict(sigma_off, options_.selected);
            } else {
              out->neighbour_covariance[static_cast<size_t>(i - 1)] = Restrict(sigma_off, options_.selected, true);
            }
          }
          out->covariance[static_cast<size_t>(i)] = Restrict(sigma_ii, options_.selected);
          sigma_next.swap(sigma_ii);
        }
        x_next.swap(x);
        C_next = store->C(j);
      }
    }
  }

 private:
  // Assembles and eliminates position p; `carry` holds position p-1 on entry and p on return.
  void Step(int p, Carry* carry, MatrixXd* L, MatrixXd* C, VectorXd* y) {
    const int i = block(p);
    AssembleChecked(assemble_, i, b_, &diagonal_, &lower_, &rhs_);
    ++assembler_calls_;
    Neighbour previous;
    if (p > 0) {
      if (step_ > 0) {
        previous.coupling = &lower_;
      } else {
        coupling_ = carry->lower.transpose();  // A_{i,i+1} = A_{i+1,i}ᵀ
        previous.coupling = &coupling_;
      }
      previous.L = &carry->L;
      previous.y = &carry->y;
    }
    int unknown = 0;
    const double ratio =
        eliminator_.Eliminate(i, diagonal_, rhs_, p > 0 ? &previous : nullptr, C, nullptr, nullptr, L, y, &unknown);
    if (p == 0) C->setZero(b_, b_);
    if (ratio < min_ratio_) {
      min_ratio_ = ratio;
      min_block_ = i;
      min_unknown_ = unknown;
    }
    carry->L = *L;
    carry->y = *y;
    if (step_ < 0) carry->lower.swap(lower_);
  }

  int first_, length_, step_, b_;
  const BlockRowAssembler& assemble_;
  const BlockTridiagonalOptions& options_;
  BlockEliminator eliminator_;
  int k_ = 1, num_segments_ = 0;
  bool keep_all_ = true;
  FactorStore store_;  // every position's factor when keep_all_
  std::vector<Carry> checkpoints_;
  Carry last_;
  MatrixXd diagonal_, lower_, coupling_;
  VectorXd rhs_;
  long long assembler_calls_ = 0;
  double min_ratio_ = 1.0;
  int min_block_ = -1, min_unknown_ = -1;
};

// Runs top() and bottom() on two threads (or one after the other). Each chain's exception is kept
// in its own slot and the top's is rethrown first, so that the error does not depend on the
// thread count or on which chain failed first in time.
void RunChains(int threads, const std::function<void()>& top, const std::function<void()>& bottom) {
  std::exception_ptr errors[2];
  const std::function<void()>* work[2] = {&top, &bottom};
  ParallelForRuns(2, threads, 0, [&](int c, RandomStream&) {
    try {
      (*work[c])();
    } catch (...) {
      errors[c] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace

bool BlockTridiagonalOptions::IsValid(std::string* error) const {
  std::vector<int> sorted = selected;
  std::sort(sorted.begin(), sorted.end());
  return Validator(error)
      .AtLeast(checkpoint_interval, 0, "checkpoint_interval")
      .Check(pivot_tolerance >= 0.0 && pivot_tolerance < 1.0, "pivot_tolerance",
             "must be in [0, 1), got " + FormatValue(pivot_tolerance))
      .Check(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end(), "selected",
             "must not repeat an index");
}

std::string BlockTridiagonalSummary::BriefReport() const {
  std::ostringstream s;
  s << "block-tridiagonal: " << num_blocks << " blocks of " << block_size << ", factor " << factor_seconds
    << " s, backward " << backward_seconds << " s, " << assembler_calls << " assembler calls, factor memory "
    << stored_factor_bytes / (1024.0 * 1024.0) << " MiB, min relative pivot " << min_relative_pivot << " (block "
    << min_relative_pivot_block << ", unknown " << min_relative_pivot_unknown << ")";
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
  const bool invert = !options.selected.empty();
  const int threads = std::min(2, ResolveThreadCount(options.num_threads));

  BlockTridiagonalSolution out;
  BlockTridiagonalSummary& summary = out.summary;
  summary.num_blocks = n;
  summary.block_size = b;
  out.x.resize(static_cast<Eigen::Index>(n) * b);
  if (invert) out.covariance.resize(static_cast<size_t>(n));
  if (invert && options.neighbour_covariances) out.neighbour_covariance.resize(static_cast<size_t>(n - 1));

  // Twisted order: top chain 0..m-1, bottom chain n-1..m+1, then the middle m.
  const int m = n / 2;
  Chain top(0, m, +1, b, assemble, options);
  Chain bottom(n - 1, n - 1 - m, -1, b, assemble, options);

  WallTimer timer;
  RunChains(threads, [&] { top.Forward(); }, [&] { bottom.Forward(); });
  MatrixXd diagonal, lower, L_mid, C_top, C_bottom, coupling_bottom;
  VectorXd rhs, y_mid;
  AssembleChecked(assemble, m, b, &diagonal, &lower, &rhs);
  Neighbour from_top, from_bottom;
  if (top.length() > 0) from_top = Neighbour{&lower, &top.last().L, &top.last().y};
  if (bottom.length() > 0) {
    coupling_bottom = bottom.last().lower.transpose();  // A_{m,m+1} = A_{m+1,m}ᵀ
    from_bottom = Neighbour{&coupling_bottom, &bottom.last().L, &bottom.last().y};
  }
  BlockEliminator eliminator(b, options.pivot_tolerance);
  double mid_ratio = 1.0;
  int mid_unknown = 0;
  try {
    mid_ratio = eliminator.Eliminate(m, diagonal, rhs, top.length() > 0 ? &from_top : nullptr, &C_top,
                                     bottom.length() > 0 ? &from_bottom : nullptr, &C_bottom, &L_mid, &y_mid,
                                     &mid_unknown);
  } catch (const std::runtime_error& e) {
    if (n == 1) throw;
    // Each chain alone can be regular while the whole is not: say so, the block number alone
    // would suggest a local defect.
    throw std::runtime_error(std::string(e.what()) +
                             "; this is the middle block, where the two elimination chains meet, so the defect may "
                             "belong to the whole network (e.g. a datum missing everywhere)");
  }
  summary.factor_seconds = timer.ElapsedSeconds();
  summary.assembler_calls = top.assembler_calls() + bottom.assembler_calls() + 1;
  // Where the smallest pivot is (ties: top chain, bottom chain, middle; independent of the threads).
  summary.min_relative_pivot = mid_ratio;
  summary.min_relative_pivot_block = m;
  summary.min_relative_pivot_unknown = mid_unknown;
  for (const Chain* c : {&bottom, &top}) {
    if (c->length() > 0 && c->min_relative_pivot() <= summary.min_relative_pivot) {
      summary.min_relative_pivot = c->min_relative_pivot();
      summary.min_relative_pivot_block = c->min_relative_pivot_block();
      summary.min_relative_pivot_unknown = c->min_relative_pivot_unknown();
    }
  }

  // Outwards from the middle: x_m = L_m^{-T} y_m, Σ_mm = L_m^{-T} L_m^{-1}.
  timer.Reset();
  const MatrixXd& L_mid_const = L_mid;  // a view of a const matrix: its transpose() is usable
  const auto Lt = L_mid_const.triangularView<Eigen::Lower>();
  const VectorXd x_mid = Lt.transpose().solve(y_mid);
  out.x.segment(static_cast<Eigen::Index>(m) * b, b) = x_mid;
  MatrixXd sigma_mid;
  if (invert) {
    MatrixXd Linv = MatrixXd::Identity(b, b);
    Lt.solveInPlace(Linv);
    sigma_mid.noalias() = Linv.transpose() * Linv;
    out.covariance[static_cast<size_t>(m)] = Restrict(sigma_mid, options.selected);
  }
  RunChains(
      threads, [&] { if (top.length() > 0) top.Backward(x_mid, C_top, invert ? &sigma_mid : nullptr, &out); },
      [&] { if (bottom.length() > 0) bottom.Backward(x_mid, C_bottom, invert ? &sigma_mid : nullptr, &out); });
  summary.assembler_calls = top.assembler_calls() + bottom.assembler_calls() + 1;
  summary.stored_factor_bytes = top.stored_bytes() + bottom.stored_bytes() + 8.0 * (b * b + b);
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
  BlockEliminator eliminator(b_, pivot_tolerance);
  L_.resize(static_cast<size_t>(n_));
  C_.resize(static_cast<size_t>(n_));
  rhs_.resize(static_cast<Eigen::Index>(n_) * b_);
  MatrixXd diagonal, lower;
  VectorXd rhs, y, y_previous;
  for (int i = 0; i < n_; ++i) {
    AssembleChecked(assemble, i, b_, &diagonal, &lower, &rhs);
    const Neighbour previous{&lower, i > 0 ? &L_[static_cast<size_t>(i - 1)] : nullptr, &y_previous};
    eliminator.Eliminate(i, diagonal, rhs, i > 0 ? &previous : nullptr, &C_[static_cast<size_t>(i)], nullptr, nullptr,
                         &L_[static_cast<size_t>(i)], &y);
    if (i == 0) C_[0].setZero(b_, b_);
    rhs_.segment(static_cast<Eigen::Index>(i) * b_, b_) = rhs;
    y_previous.swap(y);
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
