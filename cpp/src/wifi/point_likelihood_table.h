// The interpolated RSS likelihood l(z, v) at a fixed set of points (reference points, an MMSE
// grid), evaluated for a scan in time proportional to the entries of the heard APs only.
//
// On a building-sized map each AP is heard over a part of the building; elsewhere every
// reference point holds the same "background" pair, the not-heard value and the variance
// floor (SignalMap's floor-value model). The background of AP a, (m_a, δ_a), is the pair most
// reference points share. Writing u_a(p) = min(½ (m_a - m_a(p))² / δ_a(p), cap), the background
// term at point p, and c_a(v) = min(½ (v - m_a)² / δ_a, cap) the term of a reading v where the
// AP sits at its background,
//
//   l(p, v) = Σ_a ½ log(2π δ_a(p)) + Σ_a u_a(p)
//           + Σ_{a: v_a ≠ m_a} [ c_a(v_a) + Σ_{p active for a} (t_a(p, v_a) - u_a(p) - c_a(v_a)) ],
//
// exactly (up to rounding) the dense sum over every AP (GridPosterior's and the reference
// points' score before this table): the first two sums are stored per point, and a scan's
// not-heard readings (v_a = m_a) cost nothing. An entry is "active" unless its mean and floored
// variance equal the background to rounding (relative 1e-12), so the dense answer is kept on
// any map; maps without background structure simply have every entry active.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "indoorloc/wifi/signal_map.h"

namespace indoorloc::wifi::internal {

/// Each AP's background: the (mean [dBm], floored variance [dB^2]) pair that most rows of a
/// map share (ties: the first such pair in row order).
struct ApBackground {
  Eigen::VectorXd mean_dbm;
  Eigen::VectorXd variance_db2;
};
ApBackground FindBackground(const RowMatrixXd& mean_dbm, const RowMatrixXd& variance_db2, double variance_floor_db2);

/// True if (mean, floored variance) equal AP a's background to rounding.
bool IsBackground(const ApBackground& background, Eigen::Index a, double mean_dbm, double variance_db2);

class PointLikelihoodTable {
 public:
  PointLikelihoodTable() = default;
  /// background: of every AP (K); max_term: the cap on each residual term (inf: none).
  PointLikelihoodTable(const ApBackground& background, double max_term);

  /// Appends a point from its interpolated means and floored variances (K each).
  void AddPoint(const double* mean_dbm, const double* variance_db2);
  /// Freezes the per-AP entry lists (call once after the last AddPoint).
  void Finish();

  Eigen::Index num_points() const { return point_term_.size(); }
  /// l(p, v) summed over the scans (n x K, prepared) at every point, into *l (resized).
  void NegLogLikelihood(const Eigen::Ref<const RowMatrixXd>& scans, Eigen::VectorXd* l) const;

 private:
  ApBackground background_;
  Eigen::VectorXd bg_mean_, bg_inv_var_;
  Eigen::VectorXd bg_log_var_;  // log of the background variances (AddPoint: most points' variances)
  double cap_ = 0.0;
  std::vector<double> log_norm_acc_, base_acc_;  // while adding points
  Eigen::VectorXd point_term_;  // Σ_a ½ log(2π δ_a(p)) + u_a(p), one scan's share without heard APs
  // Active entries, grouped by AP and cut into runs of consecutive point indices (a grid row
  // or part of one), so that the scan's pass adds into contiguous l values (vectorised): run r
  // of AP a (runs [ap_run_[a], ap_run_[a + 1])) covers entries [run_entry_[r], run_entry_[r + 1])
  // at points run_point_[r], run_point_[r] + 1, ...
  std::vector<std::vector<int>> building_points_;
  std::vector<std::vector<double>> building_values_;
  std::vector<int> ap_run_, run_point_, run_entry_;
  std::vector<double> mean_, inv_var_, background_term_;
};

}  // namespace indoorloc::wifi::internal
