// Streaming block-tridiagonal Cholesky with selected inversion: the linear-algebra engine that
// lets the INS/GPS network adjustment (paper 003) scale to the paper's Table 2 sizes.
//
// Why this shape: the leap-frog rule Λ(x, n) = (x[n+1] - x[n-1]) / 2δt links epochs n-1, n, n+1,
// so the normal matrix of a network of E epochs with p unknowns each is block-pentadiagonal;
// grouping two consecutive epochs into one block of size b = 2p makes it block-TRIdiagonal (the
// trapezoidal rule gives tridiagonal blocks of size p directly). A general sparse Cholesky does
// not know this and pays for it in fill and memory (the issue measured CHOLMOD out of 24 GiB at
// 18 M unknowns); the block recursion below needs O(b³) work per block and, with checkpoints,
// memory independent of the number of blocks.
//
// The matrix is never stored: the caller's assembler returns block row i (A_ii, A_{i,i-1}, b_i)
// on demand, so a network is assembled from its observation equations while it is factored.
//
// Factorisation A = L Lᵀ, L block lower-bidiagonal with diagonal blocks L_i and sub-diagonal
// blocks C_i = A_{i,i-1} L_{i-1}^{-T}:
//     S_i = A_ii - C_i C_iᵀ,   L_i = chol(S_i),   y_i = L_i^{-1} (b_i - C_i y_{i-1})
// Back substitution: x_{n-1} = L_{n-1}^{-T} y_{n-1},  x_i = L_i^{-T} (y_i - C_{i+1}ᵀ x_{i+1}).
// Selected inversion (Takahashi recursion) from Σ = A^{-1} = L^{-T} L^{-1}, i.e. Σ L = L^{-T}
// (upper triangular with diagonal blocks L_i^{-T}); block column i, rows i+1 and i:
//     Σ_{i+1,i} = -Σ_{i+1,i+1} C_{i+1} L_i^{-1}
//     Σ_ii      = L_i^{-T} L_i^{-1} - Σ_{i+1,i}ᵀ C_{i+1} L_i^{-1}
// so every diagonal block of A^{-1} (and the block beside it) costs O(b³) without forming A^{-1}.
//
// Twisted order (two chains meeting in the middle, "burn at both ends"): SolveBlockTridiagonal
// eliminates blocks 0, 1, .., m-1 (top chain, the recursion above) and n-1, n-2, .., m+1 (bottom
// chain, the same recursion run backwards: U_i = chol(A_ii - D_i D_iᵀ), D_i = A_{i,i+1}
// U_{i+1}^{-T}) independently, then the middle block m = ⌊n/2⌋ against both:
//     S_m = A_mm - C_m C_mᵀ - D_m D_mᵀ,  x_m = S_m^{-1} (b_m - C_m y_{m-1} - D_m z_{m+1}),  Σ_mm = S_m^{-1},
// and substitutes (and inverts, with the recursion above in each chain's own direction) outwards
// from m. This is the Cholesky factorisation of A in the order 0..m-1, n-1..m+1, m, which creates
// no fill (each block still has one eliminated neighbour, the middle two), so it costs the same
// flops as the one-way recursion; the two chains are independent and run on two threads
// (num_threads >= 2). The order does not depend on the thread count: the results are identical
// (bit for bit) on one thread or two.
//
// Checkpoints: with checkpoint_interval = k > 0 only (L_{i-1}, y_{i-1}) at every k-th block of a
// chain is kept in the forward pass; the backward pass refactors one segment of k blocks at a time
// from its checkpoint (the assembler is called twice per block of a chain longer than k). Memory
// O((n/k + k) b²) instead of O(n b²), time about 1.5x. The results are identical (same operations in
// the same order).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace indoorloc::network {

/// Fills block row i of a symmetric positive definite block-tridiagonal system: `diagonal` A_ii
/// (b x b, symmetric), `lower` A_{i,i-1} (b x b; not read for i = 0) and `rhs` b_i (b). The
/// outputs arrive sized and zeroed. Must be deterministic: it may be called twice per block. With
/// num_threads >= 2 it is called from two threads at once (for different blocks): it must not
/// write to shared state.
using BlockRowAssembler =
    std::function<void(int block, Eigen::MatrixXd* diagonal, Eigen::MatrixXd* lower, Eigen::VectorXd* rhs)>;

struct BlockTridiagonalOptions {
  /// 0: keep the whole factor (fastest; memory about 2 n b² doubles). k > 0: keep one
  /// checkpoint every k blocks and refactor segments in the backward pass.
  int checkpoint_interval = 0;
  /// Indices within a block (0 .. b-1) whose covariances are wanted (e.g. the gravity
  /// disturbance). Empty: no selected inversion.
  std::vector<int> selected;
  /// Also return Σ_{i+1,i} restricted to `selected` (the covariance with the next block).
  bool neighbour_covariances = false;
  /// Relative pivot tolerance: an unknown whose Cholesky pivot² (its information given the
  /// unknowns eliminated before it) is below tolerance · A_kk (its information alone) is a rank
  /// defect (datum defect of the network). Invariant to the units of each unknown.
  double pivot_tolerance = 1e-12;
  /// Threads for the two chains of the twisted order (1 or 2 are used; <= 0: the hardware's).
  /// The results do not depend on it.
  int num_threads = 1;
  bool IsValid(std::string* error) const;
};

struct BlockTridiagonalSummary {
  int num_blocks = 0;
  int block_size = 0;
  double factor_seconds = 0.0;     ///< forward pass (factor + forward substitution)
  double backward_seconds = 0.0;   ///< back substitution + selected inversion (+ refactoring)
  long long assembler_calls = 0;
  double stored_factor_bytes = 0;  ///< peak bytes of factor blocks held at once
  double min_relative_pivot = 0;   ///< smallest pivot² / A_kk seen (conditioning hint; 1 = independent unknowns)
  int min_relative_pivot_block = -1;    ///< the block where it was seen
  int min_relative_pivot_unknown = -1;  ///< its index within the block (0 .. b-1)
  std::string BriefReport() const;
};

struct BlockTridiagonalSolution {
  Eigen::VectorXd x;  ///< n·b: the solution, block i at x.segment(i·b, b)
  /// Per block i: Σ_ii restricted to `selected` (s x s); empty when `selected` is empty.
  std::vector<Eigen::MatrixXd> covariance;
  /// Per block i < n-1: Σ_{i+1,i} restricted to `selected` (s x s), if requested.
  std::vector<Eigen::MatrixXd> neighbour_covariance;
  BlockTridiagonalSummary summary;
};

/// Solves A x = b for a symmetric positive definite block-tridiagonal A given block row by block
/// row, with the selected blocks of A^{-1}, in the twisted order above. Throws std::runtime_error
/// naming the block where A is not positive definite (rank-deficient network: datum defect,
/// unobservable parameter; a defect of the whole network shows at the middle block, where the two
/// chains meet) and std::invalid_argument on bad sizes or non-finite blocks.
BlockTridiagonalSolution SolveBlockTridiagonal(int num_blocks, int block_size, const BlockRowAssembler& assemble,
                                               const BlockTridiagonalOptions& options = BlockTridiagonalOptions());

/// The whole factor A = L Lᵀ kept in memory (2 n b² doubles) for repeated solves, e.g. as the
/// preconditioner of conjugate gradients when cross-over ties break the band
/// (crossover_pcg.h). Same recursion and rank test as SolveBlockTridiagonal.
class BlockTridiagonalFactor {
 public:
  /// Factors A (rows from `assemble`, whose right-hand side is ignored). Throws as
  /// SolveBlockTridiagonal on a rank-deficient A.
  BlockTridiagonalFactor(int num_blocks, int block_size, const BlockRowAssembler& assemble,
                         double pivot_tolerance = 1e-12);
  int num_blocks() const { return n_; }
  int block_size() const { return b_; }
  /// A^{-1} rhs (rhs of size n·b).
  Eigen::VectorXd Solve(const Eigen::VectorXd& rhs) const;
  /// A x = L (Lᵀ x), without A.
  Eigen::VectorXd Multiply(const Eigen::VectorXd& x) const;
  double bytes() const { return 8.0 * (2.0 * b_ * b_) * n_; }
  /// The right-hand side b the assembler returned, gathered during the factorisation.
  const Eigen::VectorXd& rhs() const { return rhs_; }

 private:
  int n_ = 0, b_ = 0;
  std::vector<Eigen::MatrixXd> L_, C_;
  Eigen::VectorXd rhs_;
};

}  // namespace indoorloc::network
