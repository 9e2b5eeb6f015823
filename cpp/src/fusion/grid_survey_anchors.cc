// Survey-anchored fix positions of the grid tracker (GridTrackerOptions::fix_survey_distance_factor,
// GridTracker::WithSurveyPositions): per cell c the survey position s(c) nearest to its centre and
// the point q(c) = s(c) + β (c - s(c)) at which the fixes are evaluated (grid_fix_factor.cc).
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "indoorloc/core/check.h"
#include "grid_ops.h"

namespace indoorloc::fusion {

namespace {

// Nearest-point search over a bucket grid that covers both the points and the queries, so that a
// query's bucket always exists: rings of buckets around the query's bucket are scanned outwards
// until the best distance found is no more than the least distance of the next ring (r b, b the
// bucket side), which makes the result exact. Ties go to the lower point index (scan order is
// fixed), so the result is deterministic.
class NearestPoint {
 public:
  NearestPoint(const std::vector<Eigen::Vector2d>& pts, const Eigen::Vector4d& query_box, double bucket_m)
      : pts_(pts), b_(bucket_m) {
    x0_ = query_box[0], y0_ = query_box[1];
    double x1 = query_box[2], y1 = query_box[3];
    for (const auto& p : pts) {
      x0_ = std::min(x0_, p.x()), y0_ = std::min(y0_, p.y());
      x1 = std::max(x1, p.x()), y1 = std::max(y1, p.y());
    }
    nx_ = std::max(1, static_cast<int>(std::floor((x1 - x0_) / b_)) + 1);
    ny_ = std::max(1, static_cast<int>(std::floor((y1 - y0_) / b_)) + 1);
    start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
    for (const auto& p : pts) ++start_[Bucket(p.x(), p.y()) + 1];
    for (std::size_t i = 1; i < start_.size(); ++i) start_[i] += start_[i - 1];
    index_.resize(pts.size());
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (int i = 0; i < static_cast<int>(pts.size()); ++i) index_[fill[Bucket(pts[i].x(), pts[i].y())]++] = i;
  }

  int Nearest(double x, double y) const {
    const int bx = Clamp(static_cast<int>(std::floor((x - x0_) / b_)), nx_);
    const int by = Clamp(static_cast<int>(std::floor((y - y0_) / b_)), ny_);
    int best = -1;
    double best_d2 = std::numeric_limits<double>::infinity();
    const int r_max = std::max(nx_, ny_);
    for (int r = 0; r <= r_max; ++r) {
      for (int j = by - r; j <= by + r; ++j) {
        if (j < 0 || j >= ny_) continue;
        const bool edge_row = j == by - r || j == by + r;
        for (int i = bx - r; i <= bx + r; i += edge_row ? 1 : 2 * std::max(r, 1)) {
          if (i < 0 || i >= nx_) continue;
          const std::size_t bucket = static_cast<std::size_t>(j) * nx_ + i;
          for (int k = start_[bucket]; k < start_[bucket + 1]; ++k) {
            const int p = index_[k];
            const double d2 = (pts_[p].x() - x) * (pts_[p].x() - x) + (pts_[p].y() - y) * (pts_[p].y() - y);
            if (d2 < best_d2 || (d2 == best_d2 && p < best)) best_d2 = d2, best = p;
          }
        }
      }
      const double reach = r * b_;
      if (best >= 0 && best_d2 <= reach * reach) break;
    }
    return best;
  }

 private:
  static int Clamp(int v, int n) { return std::min(n - 1, std::max(0, v)); }
  std::size_t Bucket(double x, double y) const {
    return static_cast<std::size_t>(Clamp(static_cast<int>(std::floor((y - y0_) / b_)), ny_)) * nx_ +
           Clamp(static_cast<int>(std::floor((x - x0_) / b_)), nx_);
  }

  const std::vector<Eigen::Vector2d>& pts_;
  double b_, x0_ = 0, y0_ = 0;
  int nx_ = 1, ny_ = 1;
  std::vector<int> start_, index_;
};

// Bilinear lattice coordinate of u (in cells from the first centre) on n centres: the lower
// centre, the step to the upper one (0 on a single centre), the weight of the upper one.
void Lattice(double u, int n, int* lower, int* step, float* weight) {
  u = std::min(static_cast<double>(n - 1), std::max(0.0, u));
  *lower = std::min(static_cast<int>(std::floor(u)), std::max(0, n - 2));
  *step = n > 1 ? 1 : 0;
  *weight = static_cast<float>(n > 1 ? u - *lower : 0.0);
}

void AnchorFloor(const std::vector<Eigen::Vector2d>& pts, double beta, double c, grid_ops::FloorGrid* g) {
  const Eigen::Vector4d box(g->x0, g->y0, g->x0 + g->nx * c, g->y0 + g->ny * c);
  const NearestPoint search(pts, box, std::max(4.0 * c, 2.0));
  const std::size_t n = g->size();
  g->fix_cell.resize(n);
  g->fix_step_x.resize(n);
  g->fix_step_y.resize(n);
  g->fix_wx.resize(n);
  g->fix_wy.resize(n);
  for (int y = 0; y < g->ny; ++y)
    for (int x = 0; x < g->nx; ++x) {
      const double cx = g->x0 + (x + 0.5) * c, cy = g->y0 + (y + 0.5) * c;
      const Eigen::Vector2d& s = pts[static_cast<std::size_t>(search.Nearest(cx, cy))];
      const double qx = s.x() + beta * (cx - s.x()), qy = s.y() + beta * (cy - s.y());
      const std::size_t i = static_cast<std::size_t>(y) * g->nx + x;
      int ix, iy, sx, sy;
      Lattice((qx - g->x0) / c - 0.5, g->nx, &ix, &sx, &g->fix_wx[i]);
      Lattice((qy - g->y0) / c - 0.5, g->ny, &iy, &sy, &g->fix_wy[i]);
      g->fix_cell[i] = iy * g->nx + ix;
      g->fix_step_x[i] = static_cast<unsigned char>(sx);
      g->fix_step_y[i] = sy * g->nx;
    }
}

}  // namespace

void grid_ops::AnchorFixesToSurvey(double beta, double cell, grid_ops::FloorGrid* g) {
  g->fix_cell.clear();
  if (beta >= 1.0 || g->survey_points.empty()) return;
  AnchorFloor(g->survey_points, beta, cell, g);
}

GridTracker GridTracker::WithSurveyPositions(const RowMatrixXd& positions_m, const Eigen::VectorXi& floor_numbers) const {
  CheckArgument(positions_m.cols() == 2, "positions_m",
                "must have 2 columns (x, y) [m], got " + std::to_string(positions_m.cols()));
  CheckArgument(floor_numbers.size() == positions_m.rows(), "floor_numbers",
                "must have one floor per position (" + std::to_string(positions_m.rows()) + "), got " +
                    std::to_string(floor_numbers.size()));
  CheckArgument(positions_m.allFinite(), "positions_m", "must be finite");
  GridTracker out;
  out.impl_.reset(new Impl(*impl_));
  const double beta = impl_->options.fix_survey_distance_factor;
  const double c = impl_->options.cell_size_m;
  for (grid_ops::FloorGrid& g : out.impl_->grids) {
    g.survey_points.clear();
    for (Eigen::Index i = 0; i < positions_m.rows(); ++i)
      if (floor_numbers[i] == g.floor_number) g.survey_points.emplace_back(positions_m(i, 0), positions_m(i, 1));
    grid_ops::AnchorFixesToSurvey(beta, c, &g);
  }
  return out;
}

}  // namespace indoorloc::fusion
