// Cross-over ties on top of a banded network: preconditioned conjugate gradients with the
// network's own block-tridiagonal factor as preconditioner (paper 003 §3.4 XOVER at scale).
//
// A cross-over equates an unknown at two epochs that may be hours apart (δg where the flight
// crosses itself). Each tie adds w (e_a - e_b)(e_a - e_b)ᵀ to the normal matrix: a rank-one term
// far off the band. A dense 2-D grid of crossings (the paper's Table 2 case 4: 332,150) would
// fill a direct factor; here the band A is factored once (BlockTridiagonalFactor) and the tied
// system (A + Σ w u uᵀ) x = b + Σ w l u is solved by conjugate gradients preconditioned with
// A^{-1}. The preconditioned operator is I + A^{-1} Σ w u uᵀ: the identity plus the ties'
// influence, so the iteration count grows with how much the ties change the solution, not with
// the size of the network. Ties between repeated passes of one line and ties of a grid cost the
// same per iteration (one multiply and one solve with the band, plus O(#ties)).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/core/options.h"
#include "indoorloc/network/block_tridiagonal.h"

namespace indoorloc::network {

/// Observation x[a] - x[b] = value with weight 1/σ² (a, b: indices into the unknown vector).
struct Tie {
  long long a = 0;
  long long b = 0;
  double weight = 1.0;
  double value = 0.0;
};

struct TiedSolveOptions {
  int max_iterations = 1000;
  /// Stop when ‖r‖_{A^{-1}} <= tolerance ‖b'‖_{A^{-1}} (r = b' - A' x; the norm of the
  /// preconditioner, in which the stiff rows do not dominate).
  double relative_tolerance = 1e-8;
  bool IsValid(std::string* error) const;
};

struct TiedSolveSummary {
  Termination termination = Termination::kFailure;
  int iterations = 0;
  double relative_residual = 0.0;
  double seconds = 0.0;
  std::string BriefReport() const;
};

struct TiedSolution {
  Eigen::VectorXd x;
  TiedSolveSummary summary;
};

/// Solves (A + Σ w u uᵀ) x = band_rhs + Σ w l u with A given by its factor. Throws
/// std::invalid_argument on tie indices outside the unknowns, a == b, or non-positive weights.
TiedSolution SolveWithTies(const BlockTridiagonalFactor& band, const Eigen::VectorXd& band_rhs,
                           const std::vector<Tie>& ties, const TiedSolveOptions& options = TiedSolveOptions());

}  // namespace indoorloc::network
