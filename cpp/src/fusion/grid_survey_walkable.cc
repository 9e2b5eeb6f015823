// The grid tracker's wall factor per cell, with the cells the survey walked through opened
// (GridTrackerOptions::survey_walkable_radius_m, survey_walkable_min_walks): m(c) = a(c) +
// (1 - a(c)) e^λ from the plan, and m(c) = 1 where survey positions of enough distinct walks lie
// within the radius of the cell's centre.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "grid_ops.h"

namespace indoorloc::fusion {

void grid_ops::ComputeWallFactors(double penalty, int n_sub, double radius_m, int min_walks, double cell,
                                  FloorGrid* g) {
  g->wall_factor.resize(g->size());
  // The walkable fraction is n / n_sub² stored in float: the count n is recovered exactly.
  for (std::size_t i = 0; i < g->size(); ++i)
    g->wall_factor[i] = WallFactor(
        static_cast<int>(std::lround(g->walkable_fraction[i] * static_cast<float>(n_sub * n_sub))), n_sub, penalty);
  if (!(radius_m > 0)) return;
  const double r2 = radius_m * radius_m;
  const int reach = static_cast<int>(std::ceil(radius_m / cell));
  // Points in order of their walk (a point without a walk id is a walk of its own), so that a
  // cell counts each walk once with a stamp of the last walk that reached it: memory of one
  // counter per cell, whatever the radius.
  const bool ids = g->survey_walks.size() == g->survey_points.size();
  std::vector<std::size_t> order(g->survey_points.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  if (ids)
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return g->survey_walks[a] < g->survey_walks[b]; });
  std::vector<long long> stamp(g->size(), std::numeric_limits<long long>::min());
  std::vector<int> walks(g->size(), 0);
  for (std::size_t k : order) {
    const Eigen::Vector2d& p = g->survey_points[k];
    // A negative walk id: a position that anchors fixes but opens no cell (a walk placed by the
    // tracker, not surveyed).
    if (ids && g->survey_walks[k] < 0) continue;
    const long long walk = ids ? g->survey_walks[k] : -1 - static_cast<long long>(k);
    const double fx = std::floor((p.x() - g->x0) / cell), fy = std::floor((p.y() - g->y0) / cell);
    if (fx < -reach - 1.0 || fx > g->nx + reach + 1.0 || fy < -reach - 1.0 || fy > g->ny + reach + 1.0) continue;
    const int px = static_cast<int>(fx), py = static_cast<int>(fy);
    for (int y = std::max(0, py - reach); y <= std::min(g->ny - 1, py + reach); ++y)
      for (int x = std::max(0, px - reach); x <= std::min(g->nx - 1, px + reach); ++x) {
        const double dx = g->x0 + (x + 0.5) * cell - p.x(), dy = g->y0 + (y + 0.5) * cell - p.y();
        const std::size_t i = static_cast<std::size_t>(y) * g->nx + x;
        if (dx * dx + dy * dy <= r2 && stamp[i] != walk) {
          stamp[i] = walk;
          if (++walks[i] >= min_walks) g->wall_factor[i] = 1.0f;
        }
      }
  }
}

}  // namespace indoorloc::fusion
