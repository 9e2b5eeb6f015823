// The interpolated Gaussian RSS model of paper 004 and its likelihood, gradient and Fisher
// information (eq. 6/22 for the gradient, eq. 16/23-25 for R_z = -I(z)).
//
// A SignalMap's means m_i and variances δ_i are interpolated linearly over a Delaunay
// triangulation of each floor's reference points (DelaunayInterpolator). For a scan v (K values,
// not-heard readings already replaced, see SignalMap::PrepareScans) at position z:
//
//   l(z, v)  = Σ_i ½ log(2π δ_i) + r_i² / (2 δ_i),     r_i = v_i - m_i(z)      (-log p)
//   ∇l(z, v) = Σ_i ½ (1/δ_i - r_i²/δ_i²) ∇δ_i - (r_i/δ_i) ∇m_i                 (eq. 22)
//   I(z)     = Σ_i ∇m_i ∇m_iᵀ / δ_i + ∇δ_i ∇δ_iᵀ / (2 δ_i²)   = -R_z          (eq. 23-25)
//
// derived again in docs/wifi_derivations.md (the text copy garbles them). For n scans taken at
// the same position, l and ∇l are sums over the scans and I is multiplied by n.
//
// Robustness options (beyond the paper): interpolated variances are floored, and each AP's
// residual term r²/(2δ) may be capped (`max_term`), so that one AP that disagrees with the map
// (moved, blocked) cannot dominate l; a capped term contributes no gradient.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/wifi/delaunay_interpolator.h"
#include "indoorloc/wifi/signal_map.h"

namespace indoorloc::wifi {

struct RssModelOptions {
  /// Minimum interpolated variance [dB^2].
  double variance_floor_db2 = 4.0;
  /// Cap on each AP's residual term r²/(2δ) (dimensionless); +inf = the paper's model.
  double max_term = std::numeric_limits<double>::infinity();

  bool IsValid(std::string* error) const;
};

/// l, ∇l and I at one position (for one scan or a group of scans at that position).
struct RssLikelihood {
  double neg_log_likelihood = 0.0;              ///< l(z, v), nats
  Eigen::Vector2d gradient = Eigen::Vector2d::Zero();  ///< ∇l [1/m]
  Eigen::Matrix2d fisher = Eigen::Matrix2d::Zero();    ///< I(z) [1/m^2]
  bool inside = true;                           ///< z inside the floor's convex hull
  Eigen::Vector2d evaluated_at_m = Eigen::Vector2d::Zero();  ///< z, or its projection on the hull
};

class RssModel {
 public:
  /// Triangulates each floor of `map` (every floor needs 3 non-collinear points).
  explicit RssModel(SignalMap map, RssModelOptions options = RssModelOptions());

  const SignalMap& map() const { return map_; }
  const RssModelOptions& options() const { return options_; }
  int num_access_points() const { return map_.num_access_points(); }
  /// Distinct floors, ascending; `floor_index` arguments index into this list.
  const std::vector<int>& floors() const { return floors_; }
  /// Index of floor number `floor` in floors(); throws std::invalid_argument if absent.
  int FloorIndex(int floor) const;
  /// Interpolator of a floor: fields are the K means then the K variances.
  const DelaunayInterpolator& interpolator(int floor_index) const;
  /// Reference point rows of `map()` on a floor.
  const std::vector<int>& points_on_floor(int floor_index) const;

  /// l, ∇l and I for the scans `rss_dbm` (n x K, all taken at z) on a floor. `hint` carries the
  /// last triangle between calls (start at -1; one hint per floor). Interpolates only the APs
  /// that differ from their background (not-heard) pair at some vertex of z's triangle; the
  /// others add a constant per triangle and no gradient: EvaluateEveryAccessPoint to rounding.
  RssLikelihood Evaluate(const Eigen::Ref<const RowMatrixXd>& rss_dbm, const Eigen::Vector2d& z_m,
                         int floor_index, int* hint) const;

  /// Evaluate's reference: interpolates every AP at z and sums all K terms (O(K) per call).
  RssLikelihood EvaluateEveryAccessPoint(const Eigen::Ref<const RowMatrixXd>& rss_dbm, const Eigen::Vector2d& z_m,
                                         int floor_index, int* hint) const;

  /// l (neg_log_likelihood of Evaluate) at each reference point of a floor, in
  /// points_on_floor(floor_index) order, for the scans rss_dbm (n x K, prepared); O(entries of
  /// the heard APs) instead of O(points x K). Resizes *neg_log_likelihood.
  void ReferencePointNegLogLikelihood(const Eigen::Ref<const RowMatrixXd>& rss_dbm, int floor_index,
                                      Eigen::VectorXd* neg_log_likelihood) const;

  /// Interpolated mean [dBm] and floored variance [dB^2] of every AP at z (for simulation).
  bool MeanAndVariance(const Eigen::Vector2d& z_m, int floor_index, Eigen::VectorXd* mean_dbm,
                       Eigen::VectorXd* variance_db2, int* hint) const;

  /// Fisher information of one scan at z (no scan needed): the inverse of the Cramér-Rao bound.
  Eigen::Matrix2d FisherInformation(const Eigen::Vector2d& z_m, int floor_index, int* hint) const;

 private:
  void BuildSparseTerms();
  void EvaluateFields(const Eigen::Vector2d& z_m, int floor_index, int* hint, bool* inside,
                      Eigen::Vector2d* at) const;

  SignalMap map_;
  RssModelOptions options_;
  std::vector<int> floors_;
  std::vector<std::vector<int>> points_on_floor_;
  std::vector<DelaunayInterpolator> interpolators_;
  struct SparseTerms;  // backgrounds, per-triangle active APs, reference-point tables (source)
  std::shared_ptr<const SparseTerms> sparse_;
  // Scratch buffers (per thread) for fields and gradients.
  static thread_local Eigen::VectorXd values_;
  static thread_local RowMatrixXd gradients_;
};

}  // namespace indoorloc::wifi
