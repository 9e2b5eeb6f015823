#include "indoorloc/fusion/mode_sequence_smoother.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <new>
#include <string>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "indoorloc/core/check.h"
#include "indoorloc/core/simd_dispatch.h"
#include "indoorloc/core/validate.h"
#include "mode_sequence_smoother_passes.h"

namespace indoorloc::fusion {

std::string ModeSequenceSummary::BriefReport() const {
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "ModeSequenceSmoother: %d ticks, %d states x %d modes, %d fix ticks, %d restarts, "
                "log evidence %.6g, %.3f s",
                ticks, states, modes, fix_ticks, restarts, log_evidence, seconds);
  return buf;
}

namespace {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// ---------------------------------------------------------------------------------------------
// Argument checks (the public boundary).

void CheckNonNegativeEntries(const double* v, Eigen::Index n, Eigen::Index cols, const char* name) {
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!(std::isfinite(v[i]) && v[i] >= 0.0)) {
      const std::string where =
          cols > 1 ? DescribeEntry(i / cols, i % cols, false) : DescribeEntry(i, 0, true);
      ThrowInvalidArgument(name, where + " must be finite and >= 0, got " + FormatValue(v[i]));
    }
  }
}

void CheckModel(const ModeSequenceModel& model) {
  const auto& index = model.state_index;
  CheckArgument(index.rows() > 0 && index.cols() > 0, "state_index", "must be a non-empty (ny, nx) lattice");
  const Eigen::Index n = model.cells_m.rows();
  CheckArgument(n > 0, "cells_m", "must hold at least one state, got shape (0, 2)");
  CheckFinite(model.cells_m, "cells_m");
  std::vector<char> seen(static_cast<std::size_t>(n), 0);
  for (Eigen::Index r = 0; r < index.rows(); ++r) {
    for (Eigen::Index c = 0; c < index.cols(); ++c) {
      const int s = index(r, c);
      if (s == -1) continue;
      if (s < -1 || s >= n) {
        ThrowInvalidArgument("state_index", DescribeEntry(r, c, false) + " must be -1 or a state index in [0, " +
                                                std::to_string(n) + "), got " + std::to_string(s));
      }
      if (seen[static_cast<std::size_t>(s)]) {
        ThrowInvalidArgument("state_index", DescribeEntry(r, c, false) + ": state " + std::to_string(s) +
                                                " appears more than once");
      }
      seen[static_cast<std::size_t>(s)] = 1;
    }
  }
  const auto missing = std::find(seen.begin(), seen.end(), 0);
  if (missing != seen.end()) {
    ThrowInvalidArgument("state_index", "state " + std::to_string(missing - seen.begin()) +
                                            " of the " + std::to_string(n) + " rows of cells_m is on no lattice cell");
  }
  const Eigen::Index m = static_cast<Eigen::Index>(model.stencils.size());
  CheckArgument(m > 0, "stencils", "need at least one mode");
  for (Eigen::Index i = 0; i < m; ++i) {
    const LatticeStencil& st = model.stencils[static_cast<std::size_t>(i)];
    const std::string name = "stencils[" + std::to_string(i) + "]";
    if (st.weights.size() != st.offsets_cells.rows()) {
      ThrowInvalidArgument(name, "offsets have " + std::to_string(st.offsets_cells.rows()) + " rows but weights " +
                                     std::to_string(st.weights.size()) + " entries");
    }
    CheckNonNegativeEntries(st.weights.data(), st.weights.size(), 1, name.c_str());
  }
  if (model.mode_transition.rows() != m || model.mode_transition.cols() != m) {
    ThrowInvalidArgument("mode_transition", "expected shape (" + std::to_string(m) + ", " + std::to_string(m) +
                                                ") (one row and column per stencil), got (" +
                                                std::to_string(model.mode_transition.rows()) + ", " +
                                                std::to_string(model.mode_transition.cols()) + ")");
  }
  CheckNonNegativeEntries(model.mode_transition.data(), m * m, m, "mode_transition");
}

void CheckEvidence(const ModeSequenceEvidence& ev, Eigen::Index n, Eigen::Index m, bool keep_posterior) {
  CheckArgument(ev.num_ticks >= 1, "num_ticks", "must be >= 1, got " + std::to_string(ev.num_ticks));
  const double t = ev.num_ticks;
  RequireSizeLimit(t * static_cast<double>(m) * static_cast<double>(n), 4.0, "num_ticks",
                   "forward-pass floats (ticks x modes x states)");
  if (keep_posterior) {
    RequireSizeLimit(t * static_cast<double>(n), 8.0, "num_ticks", "posterior doubles (ticks x states)");
  }
  if (ev.wall_factor.size() != n) {
    ThrowInvalidArgument("wall_factor", "expected " + std::to_string(n) + " entries (one per state), got " +
                                            std::to_string(ev.wall_factor.size()));
  }
  CheckNonNegativeEntries(ev.wall_factor.data(), n, 1, "wall_factor");
  CheckArgument(ev.wall_factor.sum() > 0.0, "wall_factor", "is zero on every state (no tick would have a posterior)");
  const Eigen::Index f = ev.fix_ticks.size();
  if (ev.fix_factors.rows() != f || ev.fix_factors.cols() != n) {
    ThrowInvalidArgument("fix_factors", "expected shape (" + std::to_string(f) + ", " + std::to_string(n) +
                                            ") (one row per fix tick, one column per state), got (" +
                                            std::to_string(ev.fix_factors.rows()) + ", " +
                                            std::to_string(ev.fix_factors.cols()) + ")");
  }
  for (Eigen::Index j = 0; j < f; ++j) {
    const int k = ev.fix_ticks(j);
    if (k < 0 || k >= ev.num_ticks || (j > 0 && k <= ev.fix_ticks(j - 1))) {
      ThrowInvalidArgument("fix_ticks", DescribeEntry(j, 0, true) + " must be in [0, num_ticks = " +
                                            std::to_string(ev.num_ticks) + ") and above the entry before, got " +
                                            std::to_string(k));
    }
  }
  CheckNonNegativeEntries(ev.fix_factors.data(), f * n, n, "fix_factors");
  for (Eigen::Index j = 0; j < f; ++j) {
    if (!(ev.fix_factors.row(j).dot(ev.wall_factor) > 0.0)) {
      ThrowInvalidArgument("fix_factors", "row " + std::to_string(j) + " (tick " + std::to_string(ev.fix_ticks(j)) +
                                              ") times wall_factor is zero on every state: that tick has no posterior");
    }
  }
}

// ---------------------------------------------------------------------------------------------
// The lattice: the states' runs, each mode's taps, the zero-padded buffer the moves read.

using mode_ops::MixRow;
using mode_ops::MixTerm;
using mode_ops::Run;
using mode_ops::Tap;

struct Lattice {
  explicit Lattice(const ModeSequenceModel& model) {
    const Eigen::Index ny = model.state_index.rows(), nx = model.state_index.cols();
    // Offsets that leave the lattice from every cell lose all their mass: drop them, so that the
    // padding (the largest kept shift) stays within the lattice's size.
    auto kept = [&](long dx, long dy, double w) { return std::labs(dx) < nx && std::labs(dy) < ny && w != 0.0; };
    long pad_x = 0, pad_y = 0;
    for (const LatticeStencil& st : model.stencils) {
      for (Eigen::Index i = 0; i < st.weights.size(); ++i) {
        if (!kept(st.offsets_cells(i, 0), st.offsets_cells(i, 1), st.weights(i))) continue;
        pad_x = std::max(pad_x, std::labs(st.offsets_cells(i, 0)));
        pad_y = std::max(pad_y, std::labs(st.offsets_cells(i, 1)));
      }
    }
    const std::ptrdiff_t width = nx + 2 * pad_x;
    // Zero everywhere but at the states' cells, which each pass overwrites before its move reads.
    buffer.assign(static_cast<std::size_t>((ny + 2 * pad_y) * width), 0.0);
    for (const LatticeStencil& st : model.stencils) {
      std::vector<Tap> mode_taps;
      for (Eigen::Index i = 0; i < st.weights.size(); ++i) {
        const long dx = st.offsets_cells(i, 0), dy = st.offsets_cells(i, 1);
        if (kept(dx, dy, st.weights(i))) {
          mode_taps.push_back({static_cast<std::ptrdiff_t>(dy) * width + dx, st.weights(i)});
        }
      }
      taps.push_back(std::move(mode_taps));
    }
    for (Eigen::Index r = 0; r < ny; ++r) {
      for (Eigen::Index c = 0; c < nx; ++c) {
        const int s = model.state_index(r, c);
        if (s < 0) continue;
        const std::ptrdiff_t pad = (r + pad_y) * width + (c + pad_x);
        const bool extends = !runs.empty() && runs.back().pad + runs.back().length == pad &&
                             runs.back().state + runs.back().length == s;
        if (extends) {
          ++runs.back().length;
        } else {
          runs.push_back({pad, s, 1});
        }
      }
    }
  }

  std::vector<Run> runs;
  std::vector<std::vector<Tap>> taps;  // per mode
  std::vector<double> buffer;
};

// The mode mixing as base · Σ x + a few non-negative terms per output mode: forward, mode m' from
// T's column m' (Σ_m T(m, m') x_m); backward, mode m from T's row m (Σ_m' T(m, m') x_m').
std::vector<MixRow> MixRows(const RowMatrixXd& trans, bool forward) {
  std::vector<MixRow> rows;
  for (Eigen::Index out = 0; out < trans.rows(); ++out) {
    const Eigen::VectorXd coef =
        forward ? Eigen::VectorXd(trans.col(out)) : Eigen::VectorXd(trans.row(out).transpose());
    MixRow row{coef.minCoeff(), {}};
    for (Eigen::Index in = 0; in < coef.size(); ++in) {
      if (coef(in) > row.base) row.terms.push_back({static_cast<int>(in), coef(in) - row.base});
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

// The stored forward pass (up to T M N floats, hundreds of MB): asked for in huge pages where the
// kernel grants them (madvise), which saves most of the page faults of touching it the first time
// (they cost about a fifth of the run on 4 kB pages).
class HugePageBuffer {
 public:
  void resize(std::size_t floats) {
    constexpr std::size_t kHuge = std::size_t{2} << 20;
    const std::size_t bytes = (floats * sizeof(float) + kHuge - 1) / kHuge * kHuge;
    data_.reset(static_cast<float*>(std::aligned_alloc(kHuge, std::max(bytes, kHuge))));
    if (!data_) throw std::bad_alloc();
#if defined(MADV_HUGEPAGE)
    madvise(data_.get(), std::max(bytes, kHuge), MADV_HUGEPAGE);  // a hint: ignored where not granted
#endif
  }
  float* data() { return data_.get(); }

 private:
  struct Free {
    void operator()(float* p) const { std::free(p); }
  };
  std::unique_ptr<float, Free> data_;
};

// ---------------------------------------------------------------------------------------------
// The forward-backward.

class Smoother {
 public:
  Smoother(const ModeSequenceModel& model, const ModeSequenceEvidence& ev)
      : model_(model), ev_(ev), lattice_(model), n_(model.cells_m.rows()), m_(model.mode_transition.rows()),
        passes_(UseAvx2() ? mode_ops::Avx2Passes() : mode_ops::PortablePasses()),
        fix_row_(static_cast<std::size_t>(ev.num_ticks), -1) {
    for (Eigen::Index j = 0; j < ev.fix_ticks.size(); ++j) {
      fix_row_[static_cast<std::size_t>(ev.fix_ticks(j))] = static_cast<int>(j);
    }
  }

  ModeSequenceResult Smooth(bool keep_posterior) {
    const int t_count = ev_.num_ticks;
    alpha_.resize(static_cast<std::size_t>(t_count) * m_ * n_);
    ModeSequenceResult out;
    out.mean_m.resize(t_count, 2);
    out.posterior.resize(keep_posterior ? t_count : 0, n_);
    out.summary.ticks = t_count;
    out.summary.states = static_cast<int>(n_);
    out.summary.modes = static_cast<int>(m_);
    out.summary.fix_ticks = static_cast<int>(ev_.fix_ticks.size());
    const RowMatrixXd last = Forward(&out.summary);
    Backward(last, &out);
    return out;
  }

 private:
  // e_k = wall ⊙ fix_k (the wall factor alone on ticks without a fix).
  void Emission(int k, Eigen::VectorXd* e) const {
    const int row = fix_row_[static_cast<std::size_t>(k)];
    if (row < 0) {
      *e = ev_.wall_factor;
    } else {
      *e = ev_.wall_factor.cwiseProduct(ev_.fix_factors.row(row).transpose());
    }
  }

  float* Alpha(int k) { return alpha_.data() + static_cast<std::size_t>(k) * m_ * n_; }

  // The normalised forward pass α̂_k, stored as float32 per tick; returns the last tick's in double.
  RowMatrixXd Forward(ModeSequenceSummary* summary) {
    Eigen::VectorXd e;
    Emission(0, &e);
    RowMatrixXd a = (e.transpose() / static_cast<double>(m_ * n_)).replicate(m_, 1);
    RowMatrixXd prev(m_, n_);
    Eigen::VectorXd mode_sum(n_);  // Σ_m α̂_{k-1}(m, ·)
    double s = a.sum();
    summary->log_evidence = std::log(s);
    passes_.normalise_store_and_sum(a.data(), m_, n_, s, Alpha(0), mode_sum.data());
    const std::vector<MixRow> mixing = MixRows(model_.mode_transition, true);
    for (int k = 1; k < ev_.num_ticks; ++k) {
      prev.swap(a);
      Emission(k, &e);
      for (Eigen::Index i = 0; i < m_; ++i) {
        // Σ_m T(m, i) α̂_{k-1}(m, ·) into the lattice, then e_k ⊙ K_i^T of it.
        passes_.mix_into_lattice(mixing[static_cast<std::size_t>(i)], prev.data(), mode_sum.data(), n_,
                                 lattice_.runs, lattice_.buffer.data());
        passes_.stencil(lattice_.runs, lattice_.taps[static_cast<std::size_t>(i)], lattice_.buffer.data(),
                        a.row(i).data(), -1, e.data());
      }
      s = a.sum();
      if (!(s > 0.0)) {  // everything walled off: restart from the tick's evidence
        a = e.transpose().replicate(m_, 1);
        s = a.sum();
        ++summary->restarts;
      }
      summary->log_evidence += std::log(s);
      passes_.normalise_store_and_sum(a.data(), m_, n_, s, Alpha(k), mode_sum.data());
    }
    return a;
  }

  // The posterior of tick k from p = Σ_m α̂_k ⊙ β_k (or Σ_m α̂_k alone when p vanishes): its mean
  // and, when kept, its row.
  void Posterior(int k, Eigen::VectorXd& p, ModeSequenceResult* out) {
    const double s = p.sum();
    if (s > 0.0) {
      p /= s;
    } else {
      p = Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(Alpha(k), m_, n_)
              .cast<double>()
              .colwise()
              .sum()
              .transpose();
    }
    out->mean_m.row(k) = p.transpose() * model_.cells_m;
    if (out->posterior.rows() > 0) out->posterior.row(k) = p.transpose();
  }

  void Backward(const RowMatrixXd& last, ModeSequenceResult* out) {
    const int t_count = ev_.num_ticks;
    Eigen::VectorXd p = last.colwise().sum().transpose();
    Posterior(t_count - 1, p, out);
    RowMatrixXd b = RowMatrixXd::Ones(m_, n_), moved(m_, n_);
    Eigen::VectorXd e, mode_sum(mode_ops::kMixBlock);
    const std::vector<MixRow> mixing = MixRows(model_.mode_transition, false);
    for (int k = t_count - 2; k >= 0; --k) {
      Emission(k + 1, &e);
      for (Eigen::Index i = 0; i < m_; ++i) {
        // K_i (e_{k+1} ⊙ β_{k+1}(i, ·))
        passes_.scatter_product(b.row(i).data(), e.data(), lattice_.runs, lattice_.buffer.data());
        passes_.stencil(lattice_.runs, lattice_.taps[static_cast<std::size_t>(i)], lattice_.buffer.data(),
                        moved.row(i).data(), 1, nullptr);
      }
      passes_.mix(mixing, moved.data(), b.data(), n_, mode_sum.data());  // Σ_m' T(m, m') K_m'(...)
      const double mx = b.maxCoeff();
      passes_.scale_and_posterior(b.data(), m_, n_, mx, Alpha(k), p.data());  // β_k /= max, p = Σ_m α̂_k β_k
      Posterior(k, p, out);
    }
  }

  const ModeSequenceModel& model_;
  const ModeSequenceEvidence& ev_;
  Lattice lattice_;
  Eigen::Index n_, m_;
  const mode_ops::Passes& passes_;
  std::vector<int> fix_row_;
  HugePageBuffer alpha_;
};

}  // namespace

ModeSequenceResult SmoothModeSequence(const ModeSequenceModel& model, const ModeSequenceEvidence& evidence,
                                      bool keep_posterior) {
  const auto tic = std::chrono::steady_clock::now();
  CheckModel(model);
  CheckEvidence(evidence, model.cells_m.rows(), model.mode_transition.rows(), keep_posterior);
  Smoother smoother(model, evidence);
  ModeSequenceResult out = smoother.Smooth(keep_posterior);
  out.summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - tic).count();
  return out;
}

}  // namespace indoorloc::fusion
