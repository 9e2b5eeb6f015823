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
#include "rss_limits.h"

namespace indoorloc::wifi {
namespace {

constexpr double kLog2Pi = 1.8378770664093453;

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
    // Candidates, interpolated values and the floor's arrays: (2 + 2 K + 3) doubles per point.
    RequireSizeLimit(static_cast<double>(options.max_points_per_floor) * (5.0 + 2.0 * model_->num_access_points()),
                     sizeof(double), "max_points_per_floor", "grid values");
    const int nx = static_cast<int>(std::floor(extent[0] / h)) + 1;
    const int ny = static_cast<int>(std::floor(extent[1] / h)) + 1;
    RowMatrixXd candidates(static_cast<Eigen::Index>(nx) * ny, 2);
    for (int iy = 0, c = 0; iy < ny; ++iy) {
      for (int ix = 0; ix < nx; ++ix, ++c) candidates.row(c) << lo[0] + ix * h, lo[1] + iy * h;
    }
    const InterpolationBatch b = model_->interpolator(static_cast<int>(f)).InterpolateBatch(candidates, true);
    FloorGrid grid;
    const Eigen::Index inside = b.inside.count();
    grid.points.resize(inside, 2);
    grid.mean.resize(inside, k);
    grid.inv_variance.resize(inside, k);
    grid.log_norm.resize(inside);
    for (Eigen::Index i = 0, g = 0; i < candidates.rows(); ++i) {
      if (!b.inside[i]) continue;  // the grid covers the convex hull only
      grid.points.row(g) = candidates.row(i);
      grid.mean.row(g) = b.values.row(i).head(k);
      double log_norm = 0.0;
      for (Eigen::Index a = 0; a < k; ++a) {
        const double v = std::max(b.values(i, k + a), variance_floor);
        grid.inv_variance(g, a) = 1.0 / v;
        log_norm += 0.5 * (kLog2Pi + std::log(v));
      }
      grid.log_norm[g] = log_norm;
      ++g;
    }
    floors_.push_back(std::move(grid));
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
  const double cap = model_->options().max_term;
  const double n = static_cast<double>(rss_dbm.rows());
  // l at every grid point of every floor, then log-sum-exp weights.
  std::vector<Eigen::VectorXd> l(floors_.size());
  double best = std::numeric_limits<double>::infinity();
  for (size_t f = 0; f < floors_.size(); ++f) {
    const FloorGrid& grid = floors_[f];
    l[f] = n * grid.log_norm;
    for (Eigen::Index g = 0; g < grid.points.rows(); ++g) {
      double sum = 0.0;
      for (Eigen::Index s = 0; s < rss_dbm.rows(); ++s) {
        for (Eigen::Index a = 0; a < k; ++a) {
          const double r = rss_dbm(s, a) - grid.mean(g, a);
          sum += std::min(0.5 * r * r * grid.inv_variance(g, a), cap);
        }
      }
      l[f][g] += sum;
      best = std::min(best, l[f][g]);
    }
  }
  WifiFix fix;
  double best_mass = -1.0, total_mass = 0.0;
  for (size_t f = 0; f < floors_.size(); ++f) {
    const FloorGrid& grid = floors_[f];
    const Eigen::ArrayXd w = (best - l[f].array()).exp();
    const double mass = w.sum();
    total_mass += mass;
    if (mass <= best_mass || mass <= 0.0) continue;
    best_mass = mass;
    const Eigen::Vector2d mean = (grid.points.transpose() * w.matrix()) / mass;
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (Eigen::Index g = 0; g < grid.points.rows(); ++g) {
      const Eigen::Vector2d d = grid.points.row(g).transpose() - mean;
      cov += w[g] * d * d.transpose();
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
  return floors_[static_cast<size_t>(floor_index)].points;
}

}  // namespace indoorloc::wifi
