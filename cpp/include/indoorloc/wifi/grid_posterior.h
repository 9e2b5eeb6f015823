// Posterior-mean (MMSE) position from the interpolated RSS likelihood, on a grid (beyond paper
// 004, which only follows the likelihood's gradient).
//
// With a uniform prior over the mapped area, the posterior of the position given scans v_1..v_n
// at one place is p(z | v) ∝ Π_j p(v_j | z) = exp(-Σ_j l(z, v_j)). The maximum-likelihood fix
// (LocateMaximumLikelihood) takes its mode; this class takes its mean and covariance, which
// minimise the expected squared error and average over the ambiguous, multi-modal likelihoods
// that single scans give on real maps. The integral is a sum over a uniform grid of spacing h
// covering each floor's convex hull; the interpolated means and variances of the grid points
// are computed once. A query costs one pass over the grid entries of the APs the scan hears
// (each AP is heard over a part of a building; see src/wifi/point_likelihood_table.h), not
// over G x K numbers (G grid points, K APs); the fixes are the dense sum's to rounding.
// The floor is the one with the largest posterior mass.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/wifi/gradient_tracker.h"
#include "indoorloc/wifi/rss_model.h"

namespace indoorloc::wifi {

struct GridPosteriorOptions {
  /// Grid spacing [m]; <= 0 picks a third of the median spacing of the reference points.
  double spacing_m = 0.0;
  /// Upper bound on grid points per floor (the spacing grows to respect it).
  int max_points_per_floor = 20000;

  bool IsValid(std::string* error) const;
};

class GridPosterior {
 public:
  GridPosterior(std::shared_ptr<const RssModel> model, GridPosteriorOptions options = GridPosteriorOptions());

  /// Posterior mean (position_m), posterior covariance (covariance_m2), floor of the largest
  /// mass, and neg_log_likelihood = -log of the summed likelihood mass (up to a constant), for
  /// scans (n x K, prepared) all taken at one position.
  WifiFix Locate(const Eigen::Ref<const RowMatrixXd>& rss_dbm) const;

  /// Grid points of a floor (G x 2) [m]; floor_index in [0, number of floors), else
  /// std::out_of_range (Python: IndexError).
  const RowMatrixXd& grid(int floor_index) const;
  int num_floors() const { return static_cast<int>(floors_.size()); }
  double spacing_m() const { return spacing_m_; }

 private:
  struct FloorGrid;  // grid points and their likelihood table (defined in the source)
  std::shared_ptr<const RssModel> model_;
  double spacing_m_ = 0.0;
  std::vector<std::shared_ptr<const FloorGrid>> floors_;
};

}  // namespace indoorloc::wifi
