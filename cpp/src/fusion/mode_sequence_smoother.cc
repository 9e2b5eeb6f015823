#include "indoorloc/fusion/mode_sequence_smoother.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"

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
  if (keep_posterior) RequireSizeLimit(t * static_cast<double>(n), 8.0, "num_ticks", "posterior doubles (ticks x states)");
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
// The moves: shift-and-add on a zero-padded lattice.

// A run of lattice cells in one row whose states are consecutive: cells pad .. pad+length-1 of the
// padded lattice hold states state .. state+length-1.
struct Run {
  std::ptrdiff_t pad;
  int state;
  int length;
};

// One stencil entry: the padded-lattice shift (dy W + dx) and its weight.
struct Tap {
  std::ptrdiff_t delta;
  double weight;
};

class LatticeMoves {
 public:
  explicit LatticeMoves(const ModeSequenceModel& model) {
    const Eigen::Index ny = model.state_index.rows(), nx = model.state_index.cols();
    // Offsets that leave the lattice from every cell lose all their mass: drop them, so that the
    // padding (the largest kept shift) stays within the lattice's size.
    int pad_x = 0, pad_y = 0;
    for (const LatticeStencil& st : model.stencils) {
      for (Eigen::Index i = 0; i < st.weights.size(); ++i) {
        const long dx = std::labs(st.offsets_cells(i, 0)), dy = std::labs(st.offsets_cells(i, 1));
        if (dx >= nx || dy >= ny || st.weights(i) == 0.0) continue;
        pad_x = std::max(pad_x, static_cast<int>(dx));
        pad_y = std::max(pad_y, static_cast<int>(dy));
      }
    }
    width_ = nx + 2 * pad_x;
    lattice_.assign(static_cast<std::size_t>((ny + 2 * pad_y) * width_), 0.0);
    for (const LatticeStencil& st : model.stencils) {
      std::vector<Tap> taps;
      for (Eigen::Index i = 0; i < st.weights.size(); ++i) {
        const long dx = st.offsets_cells(i, 0), dy = st.offsets_cells(i, 1);
        if (std::labs(dx) >= nx || std::labs(dy) >= ny || st.weights(i) == 0.0) continue;
        taps.push_back({static_cast<std::ptrdiff_t>(dy) * width_ + dx, st.weights(i)});
      }
      taps_.push_back(std::move(taps));
    }
    for (Eigen::Index r = 0; r < ny; ++r) {
      for (Eigen::Index c = 0; c < nx; ++c) {
        const int s = model.state_index(r, c);
        if (s < 0) continue;
        const std::ptrdiff_t pad = (r + pad_y) * width_ + (c + pad_x);
        if (!runs_.empty() && runs_.back().pad + runs_.back().length == pad &&
            runs_.back().state + runs_.back().length == s) {
          ++runs_.back().length;
        } else {
          runs_.push_back({pad, s, 1});
        }
      }
    }
  }

  // out = K_m^T x (forward: the mass arriving at each state) when `forward`, else out = K_m x
  // (backward: the expectation over each state's moves). x, out: N entries.
  void Apply(std::size_t mode, const double* x, double* out, bool forward) {
    Scatter(x);
    const double* lat = lattice_.data();
    for (const Run& run : runs_) {
      double* __restrict o = out + run.state;
      std::fill(o, o + run.length, 0.0);
      for (const Tap& tap : taps_[mode]) {
        // Forward: state j receives from the cell j - o; backward: it sends to the cell j + o.
        const double* __restrict src = lat + run.pad + (forward ? -tap.delta : tap.delta);
        const double w = tap.weight;
        for (int t = 0; t < run.length; ++t) o[t] += w * src[t];
      }
    }
  }

 private:
  // Writes x into the states' cells; the other cells stay zero from construction.
  void Scatter(const double* x) {
    double* lat = lattice_.data();
    for (const Run& run : runs_) std::copy(x + run.state, x + run.state + run.length, lat + run.pad);
  }

  std::ptrdiff_t width_ = 0;
  std::vector<double> lattice_;
  std::vector<std::vector<Tap>> taps_;
  std::vector<Run> runs_;
};

// ---------------------------------------------------------------------------------------------
// The forward-backward.

class Smoother {
 public:
  Smoother(const ModeSequenceModel& model, const ModeSequenceEvidence& ev)
      : model_(model), ev_(ev), moves_(model), n_(model.cells_m.rows()), m_(model.mode_transition.rows()),
        fix_row_(static_cast<std::size_t>(ev.num_ticks), -1) {
    for (Eigen::Index j = 0; j < ev.fix_ticks.size(); ++j) fix_row_[static_cast<std::size_t>(ev.fix_ticks(j))] = static_cast<int>(j);
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
    RowMatrixXd last = Forward(&out.summary);
    Backward(std::move(last), &out);
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

  void Store(int k, const RowMatrixXd& a) {
    float* dst = alpha_.data() + static_cast<std::size_t>(k) * m_ * n_;
    const double* src = a.data();
    for (Eigen::Index i = 0; i < m_ * n_; ++i) dst[i] = static_cast<float>(src[i]);
  }

  // The normalised forward pass, stored as float32 per tick; returns the last tick's in double.
  RowMatrixXd Forward(ModeSequenceSummary* summary) {
    Eigen::VectorXd e;
    Emission(0, &e);
    RowMatrixXd a = (e.transpose() / static_cast<double>(m_ * n_)).replicate(m_, 1);
    double s = a.sum();
    summary->log_evidence = std::log(s);
    RowMatrixXd prev = a / s;
    Store(0, prev);
    const RowMatrixXd trans_t = model_.mode_transition.transpose();
    RowMatrixXd mixed(m_, n_);
    for (int k = 1; k < ev_.num_ticks; ++k) {
      mixed.noalias() = trans_t * prev;  // Σ_m T(m, m') α̂_{k-1}(m, ·)
      Emission(k, &e);
      for (Eigen::Index i = 0; i < m_; ++i) {
        moves_.Apply(static_cast<std::size_t>(i), mixed.row(i).data(), a.row(i).data(), true);
        a.row(i).array() *= e.transpose().array();
      }
      s = a.sum();
      if (!(s > 0.0)) {  // everything walled off: restart from the tick's evidence
        a = e.transpose().replicate(m_, 1);
        s = a.sum();
        ++summary->restarts;
      }
      summary->log_evidence += std::log(s);
      prev = a / s;
      Store(k, prev);
    }
    return prev;
  }

  // Posterior of tick k from g = α̂_k ⊙ β_k (or α̂_k alone when g vanishes): its mean, and its row.
  void Posterior(int k, const RowMatrixXd& g, ModeSequenceResult* out) {
    const double s = g.sum();
    Eigen::RowVectorXd p;
    if (s > 0.0) {
      p = g.colwise().sum() / s;
    } else {
      const float* a = alpha_.data() + static_cast<std::size_t>(k) * m_ * n_;
      p = Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(a, m_, n_)
              .cast<double>()
              .colwise()
              .sum();
    }
    out->mean_m.row(k) = p * model_.cells_m;
    if (out->posterior.rows() > 0) out->posterior.row(k) = p;
  }

  void Backward(RowMatrixXd last, ModeSequenceResult* out) {
    const int t_count = ev_.num_ticks;
    Posterior(t_count - 1, last, out);
    RowMatrixXd b = RowMatrixXd::Ones(m_, n_), moved(m_, n_), g(m_, n_);
    Eigen::VectorXd e;
    Eigen::RowVectorXd be(n_);
    for (int k = t_count - 2; k >= 0; --k) {
      Emission(k + 1, &e);
      for (Eigen::Index i = 0; i < m_; ++i) {
        be = b.row(i).cwiseProduct(e.transpose());
        moves_.Apply(static_cast<std::size_t>(i), be.data(), moved.row(i).data(), false);
      }
      b.noalias() = model_.mode_transition * moved;  // Σ_m' T(m, m') K_m'(e_{k+1} ⊙ β_{k+1}(m', ·))
      const double mx = b.maxCoeff();
      if (mx > 0.0) b /= mx;
      const float* a = alpha_.data() + static_cast<std::size_t>(k) * m_ * n_;
      g = Eigen::Map<const Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(a, m_, n_)
              .cast<double>()
              .cwiseProduct(b);
      Posterior(k, g, out);
    }
  }

  const ModeSequenceModel& model_;
  const ModeSequenceEvidence& ev_;
  LatticeMoves moves_;
  Eigen::Index n_, m_;
  std::vector<int> fix_row_;
  std::vector<float> alpha_;
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
