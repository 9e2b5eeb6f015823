#include "indoorloc/wifi/grid_posterior.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "point_likelihood_table.h"
#include "rss_limits.h"

namespace indoorloc::wifi {

struct GridPosterior::FloorGrid {
  RowMatrixXd points;                    // G x 2
  internal::PointLikelihoodTable table;  // l at the G points
};

namespace {

// Median distance from each reference point to its nearest other point (O(N^2) on a subset),
// ignoring near-duplicates closer than 1 cm (surveys often repeat a point with tiny offsets).
double MedianSpacing(const RowMatrixXd& p) {
  const Eigen::Index n = p.rows();
  const Eigen::Index step = std::max<Eigen::Index>(1, n / 500);
  std::vector<double> nearest;
  for (Eigen::Index i = 0; i < n; i += step) {
    double best = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j < n; ++j) {
      const double d2 = (p.row(i) - p.row(j)).squaredNorm();
      if (j != i && d2 > 1e-4) best = std::min(best, d2);
    }
    if (std::isfinite(best)) nearest.push_back(std::sqrt(best));
  }
  if (nearest.empty()) return 1.0;
  std::nth_element(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(nearest.size() / 2), nearest.end());
  return std::max(nearest[nearest.size() / 2], 1e-3);
}

}  // namespace

bool GridPosteriorOptions::IsValid(std::string* error) const {
  // spacing_m <= 0 picks it automatically; max_points_per_floor bounds the memory (G x K doubles).
  return Validator(error)
      .InRange(spacing_m, -kMaxScale, kMaxScale, "spacing_m")
      .IntInRange(max_points_per_floor, 16, 10000000, "max_points_per_floor");
}

GridPosterior::GridPosterior(std::shared_ptr<const RssModel> model, GridPosteriorOptions options)
    : model_(std::move(model)) {
  CheckArgument(model_ != nullptr, "model", "is null");
  ValidateOptions(options);
  spacing_m_ = options.spacing_m > 0 ? options.spacing_m : MedianSpacing(model_->map().positions_m()) / 3.0;
  const Eigen::Index k = model_->num_access_points();
  const double variance_floor = model_->options().variance_floor_db2;
  const internal::ApBackground background =
      internal::FindBackground(model_->map().mean_dbm(), model_->map().variance_db2(), variance_floor);
  for (size_t f = 0; f < model_->floors().size(); ++f) {
    const std::vector<int>& rows = model_->points_on_floor(static_cast<int>(f));
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector2d hi = -lo;
    for (int r : rows) {
      lo = lo.cwiseMin(model_->map().positions_m().row(r).transpose());
      hi = hi.cwiseMax(model_->map().positions_m().row(r).transpose());
    }
    double h = spacing_m_;
    const Eigen::Vector2d extent = (hi - lo).cwiseMax(1e-9);
    while ((extent[0] / h + 1) * (extent[1] / h + 1) > options.max_points_per_floor) h *= 1.25;
    // The table's worst case (no AP at its background anywhere): 3.5 K doubles per point.
    RequireSizeLimit(static_cast<double>(options.max_points_per_floor) * (5.0 + 3.5 * model_->num_access_points()),
                     sizeof(double), "max_points_per_floor", "grid values");
    const int nx = static_cast<int>(std::floor(extent[0] / h)) + 1;
    const int ny = static_cast<int>(std::floor(extent[1] / h)) + 1;
    RowMatrixXd candidates(static_cast<Eigen::Index>(nx) * ny, 2);
    for (int iy = 0, c = 0; iy < ny; ++iy) {
      for (int ix = 0; ix < nx; ++ix, ++c) candidates.row(c) << lo[0] + ix * h, lo[1] + iy * h;
    }
    auto grid_ptr = std::make_shared<FloorGrid>();
    FloorGrid& grid = *grid_ptr;
    grid.table = internal::PointLikelihoodTable(background, model_->options().max_term);
    std::vector<double> inside_xy;
    Eigen::VectorXd variance(k);
    // Interpolated in blocks: the fields and gradients of K APs for every candidate at once
    // would take G x 6K doubles.
    constexpr Eigen::Index kBlock = 1024;
    for (Eigen::Index b0 = 0; b0 < candidates.rows(); b0 += kBlock) {
      const Eigen::Index block_rows = std::min(kBlock, candidates.rows() - b0);
      const InterpolationBatch b =
          model_->interpolator(static_cast<int>(f)).InterpolateBatch(candidates.middleRows(b0, block_rows), true);
      for (Eigen::Index i = 0; i < block_rows; ++i) {
        if (!b.inside[i]) continue;  // the grid covers the convex hull only
        inside_xy.push_back(candidates(b0 + i, 0));
        inside_xy.push_back(candidates(b0 + i, 1));
        for (Eigen::Index a = 0; a < k; ++a) variance[a] = std::max(b.values(i, k + a), variance_floor);
        grid.table.AddPoint(b.values.row(i).data(), variance.data());
      }
    }
    grid.table.Finish();
    grid.points = Eigen::Map<const RowMatrixXd>(inside_xy.data(), static_cast<Eigen::Index>(inside_xy.size() / 2), 2);
    floors_.push_back(std::move(grid_ptr));
  }
}

WifiFix GridPosterior::Locate(const Eigen::Ref<const RowMatrixXd>& rss_dbm) const {
  const Eigen::Index k = model_->num_access_points();
  if (rss_dbm.cols() != k) {
    ThrowInvalidArgument("rss_dbm", "has " + std::to_string(rss_dbm.cols()) + " AP columns, the map has " +
                                        std::to_string(k) + " (K mismatch between map and scan)");
  }
  CheckArgument(rss_dbm.rows() > 0, "rss_dbm", "no scan");
  CheckFinite(rss_dbm, "rss_dbm");
  internal::CheckRss(rss_dbm, "rss_dbm");
  // l at every grid point of every floor (PointLikelihoodTable), then log-sum-exp weights.
  std::vector<Eigen::VectorXd> l(floors_.size());
  double best = std::numeric_limits<double>::infinity();
  for (size_t f = 0; f < floors_.size(); ++f) {
    floors_[f]->table.NegLogLikelihood(rss_dbm, &l[f]);
    if (l[f].size() > 0) best = std::min(best, l[f].minCoeff());
  }
  WifiFix fix;
  double best_mass = -1.0, total_mass = 0.0;
  std::vector<int> support;
  // Only points with exp(best - l) > e^-cutoff are weighted: the best point weighs 1, so the
  // points left out, at most G of them, change every sum by less than G e^-cutoff = 1e-17 of
  // its value (below double rounding); on a large map they are most of the grid.
  Eigen::Index total_points = 0;
  for (const auto& grid : floors_) total_points += grid->points.rows();
  const double cutoff = 39.2 + std::log(static_cast<double>(std::max<Eigen::Index>(total_points, 1)));
  for (size_t f = 0; f < floors_.size(); ++f) {
    const FloorGrid& grid = *floors_[f];
    support.clear();
    const double* lf = l[f].data();
    for (Eigen::Index g = 0; g < l[f].size(); ++g) {
      if (lf[g] - best < cutoff) support.push_back(static_cast<int>(g));
    }
    Eigen::ArrayXd w(static_cast<Eigen::Index>(support.size()));
    for (size_t j = 0; j < support.size(); ++j) w[static_cast<Eigen::Index>(j)] = best - lf[support[j]];
    w = w.exp();  // vectorised, as the dense pass's exp over the whole grid was
    const double mass = w.sum();
    total_mass += mass;
    if (mass <= best_mass || mass <= 0.0) continue;
    best_mass = mass;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (size_t j = 0; j < support.size(); ++j) mean += w[static_cast<Eigen::Index>(j)] * grid.points.row(support[j]).transpose();
    mean /= mass;
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (size_t j = 0; j < support.size(); ++j) {
      const Eigen::Vector2d d = grid.points.row(support[j]).transpose() - mean;
      cov += w[static_cast<Eigen::Index>(j)] * d * d.transpose();
    }
    fix.position_m = mean;
    // Grid quantisation adds h^2/12 per axis; it keeps the covariance positive definite.
    fix.covariance_m2 = cov / mass + (spacing_m_ * spacing_m_ / 12.0) * Eigen::Matrix2d::Identity();
    fix.floor = model_->floors()[f];
  }
  fix.neg_log_likelihood = best - std::log(total_mass);
  return fix;
}

const RowMatrixXd& GridPosterior::grid(int floor_index) const {
  if (floor_index < 0 || floor_index >= num_floors()) {
    throw std::out_of_range("indoorloc: argument 'floor_index': must be in [0, " + std::to_string(num_floors()) +
                            "), got " + std::to_string(floor_index));
  }
  return floors_[static_cast<size_t>(floor_index)]->points;
}

}  // namespace indoorloc::wifi
