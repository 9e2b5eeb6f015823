// Repeated passes folded into the band: cross-over ties of a survey re-flown in reverse over the
// same track, solved EXACTLY by the streaming block-tridiagonal Cholesky (paper 003, Térmens &
// Colomina, Table 2 case 4: Rockies'95, 50 Hz x 11,301 s, 332,150 XOVER, 1,907 GUPT).
//
// When to use: the cross-overs are ties between repeated passes of one line (the flight goes out
// and comes back over the same track). A dense 2-D grid of crossings (every East-West line
// crosses every North-South line) does not fold: use crossover_pcg.h there (see
// docs/network_scale.md for what that costs).
//
// The ordering. Let the band have n base blocks (pair-blocks of two epochs for leap-frog, b = 36;
// single epochs for the trapezoidal rule, b = 18), coupled only to their neighbours. Fold the
// sequence at its midpoint: super-block k = {base block h-1-k, base block h+k} for n = 2h, and for
// odd n = 2h+1 super-block 0 = {base block h, padding} and super-block k >= 1 = {h-k, h+k}. The
// padding is b unknowns decoupled from everything with A = I, b = 0 (solution 0, discarded).
// Then
//   * the band coupling j <-> j+1 joins super-blocks |k - k'| <= 1 (the midpoint coupling
//     h-1 <-> h falls inside super-block 0);
//   * epoch t and its mirror E-1-t (E = g n epochs, g per base block) lie in base blocks j and
//     n-1-j, i.e. in the same super-block; t and E-2-t in the same or the adjacent one;
// so the tied network is block-tridiagonal again with blocks of 2b (72 for leap-frog), and the
// tie x_a - x_b = l with weight w adds w to A_aa and A_bb, -w to A_ab, w l and -w l to the
// right-hand side, all inside one diagonal super-block or its sub-diagonal block. The cost is
// (2b)³ / b³ = 8x per block on half as many blocks: 4x the banded solve, exact, with the
// selected inversion of every δg.
//
// The alignment prior (first epochs) and the landing GUPT (last epochs) both fall in the last
// super-block; GUPT anywhere is a diagonal term and folds trivially.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/network/block_tridiagonal.h"
#include "indoorloc/network/crossover_pcg.h"
#include "indoorloc/network/linear_ins_network.h"

namespace indoorloc::network {

/// The folded order of a band of `base_blocks` blocks of `base_block_size` unknowns.
class FoldedOrdering {
 public:
  FoldedOrdering(int base_blocks, int base_block_size);
  int base_blocks() const { return n_; }
  int base_block_size() const { return b_; }
  int num_blocks() const { return h_ + (n_ % 2); }  ///< super-blocks
  int block_size() const { return 2 * b_; }         ///< unknowns per super-block
  bool padded() const { return n_ % 2 == 1; }        ///< super-block 0, slot 1 is padding
  /// Super-block and slot (0 = outbound half, 1 = return half) of base block j.
  int SuperBlock(int j) const;
  int Slot(int j) const;
  /// Base block in slot s of super-block k, or -1 for the padding.
  int BaseBlock(int k, int s) const;
  /// Index in the folded vector of unknown u of the original (unfolded) order.
  long long FoldedIndex(long long u) const;

 private:
  int n_ = 0, b_ = 0, h_ = 0;
};

/// Folds the block rows of `base` (a block-tridiagonal band in the original order) and adds the
/// ties x[a] - x[b] = value (weight w; a, b unknown indices of the original order). Every tie must
/// join the same or adjacent super-blocks, else std::invalid_argument naming 'ties' (a tie that
/// does not fold). The base assembler is called once for each base block of the super-block and
/// once for a neighbour whose coupling lands in the sub-diagonal block.
BlockRowAssembler FoldedAssembler(const FoldedOrdering& ordering, BlockRowAssembler base, const std::vector<Tie>& ties);

/// XOVER (paper Table 1, linearised): δg_c[epoch_a] - δg_c[epoch_b] = the truth's difference
/// (noise-free synthesis), standard deviation sigma_mps2. component: 0, 1, 2 of δg (2 is the
/// third local-level axis, used as the scalar gravity of the paper's ‖δg + γ‖ equations).
struct GravityTie {
  long long epoch_a = 0;
  long long epoch_b = 0;
  int component = 2;
  double sigma_mps2 = 1e-5;
};

/// GUPT (paper Table 1): δg_c[epoch] = the truth's value, standard deviation sigma_mps2.
struct GravityUpdate {
  long long epoch = 0;
  int component = 2;
  double sigma_mps2 = 1e-5;
};

/// The case-4 layout of a flight re-flown in reverse over its own track (epoch t of the outbound
/// half is over the same ground as its mirror E-1-t).
///   ties: scalar ties on δg_component. With num_ties <= P = ⌊E/2⌋ at mirror pairs (t, E-1-t),
///         t = ⌊i P / num_ties⌋; beyond P, every mirror pair plus num_ties - P ties from t to the
///         mirror's neighbour E-2-t (the return pass is not epoch-synchronous: the nearest return
///         epoch is the mirror or the one before it), t = ⌊i Q / (num_ties - P)⌋, Q = ⌊(E-1)/2⌋.
///         At most P + Q ties.
///   gupts: scalar GUPT on δg_component at num_gupts epochs evenly spread over the flight,
///         n_i = ⌊(i + ½) E / num_gupts⌋ (upward-continued ground gravity along the track).
/// Throws std::invalid_argument naming num_ties / num_gupts / a sigma when out of range.
struct RepeatedPassLayout {
  std::vector<GravityTie> ties;
  std::vector<GravityUpdate> gupts;
};
RepeatedPassLayout MakeRepeatedPassLayout(const LinearInsNetworkOptions& network, long long num_ties,
                                          long long num_gupts, double sigma_xover_mps2, double sigma_gupt_mps2,
                                          int component = 2);

struct FoldedNetworkOptions {
  bool gravity_covariance = true;   ///< selected inversion of every δg (3 per epoch)
  int checkpoint_interval = 2048;   ///< 0: keep the whole factor (2 K (2b)² doubles)
  bool keep_gravity_estimate = false;
  /// Threads for the two chains of the twisted elimination (1 or 2; <= 0: the hardware's). The
  /// results are bit-identical on any count.
  int num_threads = 1;
  bool IsValid(std::string* error) const;
};

struct FoldedNetworkResult {
  NetworkSize size;                 ///< the base network (unknowns, equations without ties/GUPT)
  long long ties = 0;               ///< XOVER equations
  long long gupts = 0;              ///< GUPT equations (besides the base network's landing GUPT)
  long long equations = 0;          ///< size.equations + ties + gupts
  int folded_blocks = 0;
  int folded_block_size = 0;
  BlockTridiagonalSummary solver;
  double max_abs_error = 0.0;       ///< max |x - x*| over every unknown
  double gravity_rmse = 0.0;        ///< δg error RMSE [m/s²]
  Eigen::MatrixXd gravity_sigma;    ///< E x 3: sqrt of the diagonal of Σ_δg [m/s²]
  Eigen::MatrixXd gravity_estimate; ///< E x 3 [m/s²]; empty unless keep_gravity_estimate
  double total_seconds = 0.0;
  std::string BriefReport() const;
};

/// The assembler of the linearised network of `network` with the ties and GUPTs, in the folded
/// order (FoldedOrdering(size.num_blocks, size.block_size)). Validates as the solve below.
BlockRowAssembler FoldedLinearInsAssembler(const LinearInsNetworkOptions& network,
                                           const std::vector<GravityTie>& ties,
                                           const std::vector<GravityUpdate>& gupts);

/// Solves the linearised INS/GPS network with cross-over ties and GUPTs exactly (no iteration)
/// in the folded order. Throws std::invalid_argument naming 'ties' or 'gupts' for an epoch
/// outside the network, a component outside 0..2, a tie of an epoch to itself, a sigma that is
/// not finite and > 0, or a tie that does not fold (super-blocks not adjacent);
/// std::runtime_error on a rank-deficient network.
FoldedNetworkResult SolveFoldedLinearInsNetwork(const LinearInsNetworkOptions& network,
                                                const std::vector<GravityTie>& ties,
                                                const std::vector<GravityUpdate>& gupts,
                                                const FoldedNetworkOptions& options = FoldedNetworkOptions());

}  // namespace indoorloc::network
