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
// query's bucket always exists. Queries come in small boxes (tiles of cells): the candidates of a
// box are found once by scanning rings of buckets outwards (Candidates), then each query's
// nearest among them; ties go to the lower point index, so the result is deterministic and is
// that of a brute-force search over all points.
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

  // Every point that can be the nearest to some query in the axis-aligned box [x0, x1] x [y0, y1]
  // (ascending index): the points whose distance to the box is at most U, U the least distance
  // from any point to the box's farthest corner (a query's nearest point is no farther than U,
  // and no nearer than its distance to the box). Bucket rings around the box's buckets are
  // scanned until the next ring lies beyond U. A relative margin keeps rounding on the safe side
  // (a few extra candidates).
  void Candidates(double x0, double y0, double x1, double y1, std::vector<int>* out) const {
    out->clear();
    const int bx0 = Clamp(static_cast<int>(std::floor((x0 - x0_) / b_)), nx_);
    const int bx1 = Clamp(static_cast<int>(std::floor((x1 - x0_) / b_)), nx_);
    const int by0 = Clamp(static_cast<int>(std::floor((y0 - y0_) / b_)), ny_);
    const int by1 = Clamp(static_cast<int>(std::floor((y1 - y0_) / b_)), ny_);
    double upper = std::numeric_limits<double>::infinity();
    scanned_.clear();
    const int r_max = std::max(nx_, ny_);
    for (int r = 0; r <= r_max; ++r) {
      for (int j = by0 - r; j <= by1 + r; ++j) {
        if (j < 0 || j >= ny_) continue;
        const bool edge_row = j == by0 - r || j == by1 + r;
        for (int i = bx0 - r; i <= bx1 + r; ++i) {
          if (r > 0 && !edge_row && i > bx0 - r && i < bx1 + r) i = bx1 + r;  // inside: the ring's sides only
          if (i < 0 || i >= nx_) continue;
          const std::size_t bucket = static_cast<std::size_t>(j) * nx_ + i;
          for (int k = start_[bucket]; k < start_[bucket + 1]; ++k) {
            const int p = index_[k];
            const double px = pts_[p].x(), py = pts_[p].y();
            const double fx = std::max(std::abs(px - x0), std::abs(px - x1));
            const double fy = std::max(std::abs(py - y0), std::abs(py - y1));
            upper = std::min(upper, std::sqrt(fx * fx + fy * fy));
            scanned_.push_back(p);
          }
        }
      }
      // Points of ring r + 1 and beyond lie at least r b from the box.
      if (upper * (1.0 + 1e-9) + 1e-9 < r * b_) break;
    }
    const double reach = upper * (1.0 + 1e-9) + 1e-9;
    for (int p : scanned_) {
      const double px = pts_[p].x(), py = pts_[p].y();
      const double dx = std::max({0.0, x0 - px, px - x1}), dy = std::max({0.0, y0 - py, py - y1});
      if (std::sqrt(dx * dx + dy * dy) <= reach) out->push_back(p);
    }
    std::sort(out->begin(), out->end());
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
  mutable std::vector<int> scanned_;
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
  // Cells in tiles of kTile x kTile: the tile's candidate points once (NearestPoint::Candidates),
  // then each cell's nearest among them, ties to the lower index (the result of Nearest, without
  // a ring search per cell).
  constexpr int kTile = 4;
  std::vector<int> cand;
  for (int ty = 0; ty < g->ny; ty += kTile)
    for (int tx = 0; tx < g->nx; tx += kTile) {
      const int x_end = std::min(g->nx, tx + kTile), y_end = std::min(g->ny, ty + kTile);
      search.Candidates(g->x0 + (tx + 0.5) * c, g->y0 + (ty + 0.5) * c, g->x0 + (x_end - 1 + 0.5) * c,
                        g->y0 + (y_end - 1 + 0.5) * c, &cand);
      for (int y = ty; y < y_end; ++y)
        for (int x = tx; x < x_end; ++x) {
          const double cx = g->x0 + (x + 0.5) * c, cy = g->y0 + (y + 0.5) * c;
          int best = -1;
          double best_d2 = std::numeric_limits<double>::infinity();
          for (int p : cand) {
            const double d2 = (pts[p].x() - cx) * (pts[p].x() - cx) + (pts[p].y() - cy) * (pts[p].y() - cy);
            if (d2 < best_d2) best_d2 = d2, best = p;  // ascending index: the first of equals stays
          }
          const Eigen::Vector2d& s = pts[static_cast<std::size_t>(best)];
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
}

}  // namespace

void grid_ops::AnchorFixesToSurvey(double beta, double cell, grid_ops::FloorGrid* g) {
  g->fix_cell.clear();
  if (beta >= 1.0 || g->survey_points.empty()) return;
  AnchorFloor(g->survey_points, beta, cell, g);
}

GridTracker GridTracker::WithSurveyPositions(const RowMatrixXd& positions_m, const Eigen::VectorXi& floor_numbers,
                                             const Eigen::VectorXi& walk_ids) const {
  CheckArgument(positions_m.cols() == 2, "positions_m",
                "must have 2 columns (x, y) [m], got " + std::to_string(positions_m.cols()));
  CheckArgument(floor_numbers.size() == positions_m.rows(), "floor_numbers",
                "must have one floor per position (" + std::to_string(positions_m.rows()) + "), got " +
                    std::to_string(floor_numbers.size()));
  CheckArgument(positions_m.allFinite(), "positions_m", "must be finite");
  CheckArgument(walk_ids.size() == 0 || walk_ids.size() == positions_m.rows(), "walk_ids",
                "must be empty or have one walk per position (" + std::to_string(positions_m.rows()) + "), got " +
                    std::to_string(walk_ids.size()));
  GridTracker out;
  out.impl_.reset(new Impl(*impl_));
  const double beta = impl_->options.fix_survey_distance_factor;
  const double c = impl_->options.cell_size_m;
  for (grid_ops::FloorGrid& g : out.impl_->grids) {
    g.survey_points.clear();
    g.survey_walks.clear();
    for (Eigen::Index i = 0; i < positions_m.rows(); ++i)
      if (floor_numbers[i] == g.floor_number) {
        g.survey_points.emplace_back(positions_m(i, 0), positions_m(i, 1));
        if (walk_ids.size()) g.survey_walks.push_back(walk_ids[i]);
      }
    grid_ops::AnchorFixesToSurvey(beta, c, &g);
    if (impl_->options.survey_walkable_radius_m > 0)
      grid_ops::ComputeWallFactors(grid_ops::WallPenalty(impl_->options.wall_log_penalty), impl_->options.walkable_subsamples,
                                   impl_->options.survey_walkable_radius_m, impl_->options.survey_walkable_min_walks,
                                   c, &g);
  }
  return out;
}

}  // namespace indoorloc::fusion
