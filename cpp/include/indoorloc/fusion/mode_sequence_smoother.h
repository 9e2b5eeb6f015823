// Forward-backward smoother of a hidden Markov chain whose state is (lattice cell, motion mode):
// the engine of the direction-persistent WiFi-only tracker (python/indoorloc/fusion/
// wifi_heading_sequence.py; docs/fusion_real.md, "WiFi only: a direction-persistent motion
// prior"). The model is defined in Python (the stencils and the mode transition); this file only
// runs it, so that the per-tick loop is not a Python loop over sparse products.
//
// The chain, per tick k = 1 .. T-1 (state (c, m): cell c of N, mode m of M):
//   mode:  P(m' | m) = mode_transition(m, m')
//   move:  p(c' | c, m') = Σ_i w_i [c' = c + o_i] over the stencil (o_i, w_i) of mode m'; a move
//          onto a lattice cell that is not a state (or off the lattice) is lost mass (a wall)
//   emit:  e_k(c) = wall_factor(c) · fix_factor_k(c) (the fix factor only on ticks with fixes)
// with the uniform prior 1 / (M N) at tick 0. The forward pass is normalised every tick,
//   α_k(m', ·) = e_k ⊙ K_m'^T (Σ_m T(m, m') α̂_{k-1}(m, ·)),   α̂_k = α_k / s_k,  s_k = Σ α_k,
// and, when every path is walled off (s_k = 0), restarts from the tick's evidence
// (α_k(m, ·) = e_k for every m). The backward pass, normalised by its maximum,
//   β_k(m, ·) = Σ_m' T(m, m') K_m' (e_{k+1} ⊙ β_{k+1}(m', ·)),
// gives the posterior of the cell p_k(c) ∝ Σ_m α̂_k(m, c) β_k(m, c) (Rabiner 1989, eqs. 18-27,
// with per-step scaling) and its mean Σ_c p_k(c) centre(c).
//
// The moves are shift-and-add on the lattice (a gather over runs of consecutive states from a
// zero-padded copy of the lattice), O(K N) per mode and tick; the mode mixing is each output
// mode's smallest transition entry times the sum over modes plus its larger entries' excess
// (non-negative terms: a transition with a uniform part costs a few terms per mode, not M). The
// forward pass is kept in float32 (T M N · 4 bytes: 600 ticks x 9 modes x 30 k cells = 0.65 GB),
// everything else in double. Single-threaded; the element-wise passes have AVX2 and portable
// builds with the same operations per entry (mode_sequence_smoother_passes.h): the same bits whatever the
// machine and its thread count. No Options struct: the whole model is in the arguments.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace indoorloc::fusion {

/// One motion mode's move per tick: from lattice cell (column x, row y) to (x + dx, y + dy) with
/// probability `weights(i)` for offset i = (dx, dy) = `offsets_cells.row(i)`. Duplicate offsets
/// add up. Weights summing to less than one lose the rest (as does every move off the states).
struct LatticeStencil {
  Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> offsets_cells;  ///< (K, 2) (dx, dy) [cells]
  Eigen::VectorXd weights;                                              ///< (K,) finite, >= 0
};

/// The chain: the states on the lattice, each mode's move, the mode transition.
struct ModeSequenceModel {
  /// (ny, nx): the state index of lattice cell (row y, column x), or -1 (not a state); each of
  /// 0 .. N-1 exactly once.
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> state_index;
  /// (N, 2): the states' centres [m] (the posterior mean is taken over them).
  Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor> cells_m;
  /// Per mode m = 0 .. M-1, its move.
  std::vector<LatticeStencil> stencils;
  /// (M, M): P(m' | m) in row m, column m'; finite, >= 0.
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> mode_transition;
};

/// What is seen per tick: the wall factor every tick, a fix factor on some ticks.
struct ModeSequenceEvidence {
  int num_ticks = 0;            ///< T >= 1
  Eigen::VectorXd wall_factor;  ///< (N,) finite, >= 0, positive somewhere
  Eigen::VectorXi fix_ticks;    ///< (F,) strictly increasing, in [0, T)
  /// (F, N): the fix factor at tick fix_ticks(j) in row j; finite, >= 0, and wall_factor ⊙ row
  /// positive somewhere (a tick whose evidence is zero everywhere has no posterior).
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> fix_factors;
};

/// Diagnostics of one smoothing run.
struct ModeSequenceSummary {
  int ticks = 0;
  int states = 0;
  int modes = 0;
  int fix_ticks = 0;
  /// Ticks at which the forward mass vanished (everything walled off) and the forward pass
  /// restarted from the tick's evidence.
  int restarts = 0;
  /// Σ_k log s_k: the log-likelihood of the emissions (as scaled by the caller) when no restart
  /// happened; with restarts, that of the pieces between them.
  double log_evidence = 0.0;
  double seconds = 0.0;
  /// One line: "ModeSequenceSmoother: T ticks, N states x M modes, F fix ticks, R restarts, ...".
  std::string BriefReport() const;
};

/// The smoothed track.
struct ModeSequenceResult {
  Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor> mean_m;  ///< (T, 2) posterior mean [m]
  /// (T, N) the posterior of the cell (summed over modes) when asked for, else (0, N).
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> posterior;
  ModeSequenceSummary summary;
};

/// Forward-backward over `evidence.num_ticks` ticks of `model` (see the file comment). Throws
/// std::invalid_argument naming the argument ("state_index", "cells_m", "stencils",
/// "mode_transition", "wall_factor", "fix_ticks", "fix_factors", "num_ticks") for a wrong shape,
/// a non-finite or negative entry, a state index out of range or repeated, or a tick whose
/// evidence is zero on every state; and when the forward pass (T M N floats) or the posterior
/// would exceed the memory budget (kMaxBytes). `keep_posterior`: also return the (T, N) posterior.
ModeSequenceResult SmoothModeSequence(const ModeSequenceModel& model, const ModeSequenceEvidence& evidence,
                                      bool keep_posterior = false);

}  // namespace indoorloc::fusion
