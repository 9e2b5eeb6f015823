// The grid tracker's wall factor per cell, with the cells the survey walked through opened
// (GridTrackerOptions::survey_walkable_radius_m, survey_walkable_min_walks): m(c) = a(c) +
// (1 - a(c)) e^λ from the plan, and m(c) = 1 where survey positions of enough distinct walks lie
// within the radius of the cell's centre.
#include <algorithm>
#include <cmath>
#include <utility>
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
  // (cell, walk) for every cell whose centre is within the radius of a point; a point without a
  // walk id is a walk of its own.
  const bool ids = g->survey_walks.size() == g->survey_points.size();
  std::vector<std::pair<std::size_t, long long>> hits;
  for (std::size_t k = 0; k < g->survey_points.size(); ++k) {
    const Eigen::Vector2d& p = g->survey_points[k];
    const long long walk = ids ? g->survey_walks[k] : -1 - static_cast<long long>(k);
    const int px = static_cast<int>(std::floor((p.x() - g->x0) / cell));
    const int py = static_cast<int>(std::floor((p.y() - g->y0) / cell));
    for (int y = std::max(0, py - reach); y <= std::min(g->ny - 1, py + reach); ++y)
      for (int x = std::max(0, px - reach); x <= std::min(g->nx - 1, px + reach); ++x) {
        const double dx = g->x0 + (x + 0.5) * cell - p.x(), dy = g->y0 + (y + 0.5) * cell - p.y();
        if (dx * dx + dy * dy <= r2) hits.emplace_back(static_cast<std::size_t>(y) * g->nx + x, walk);
      }
  }
  std::sort(hits.begin(), hits.end());
  hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
  for (std::size_t a = 0; a < hits.size();) {
    std::size_t b = a;
    while (b < hits.size() && hits[b].first == hits[a].first) ++b;
    if (static_cast<int>(b - a) >= min_walks) g->wall_factor[hits[a].first] = 1.0f;
    a = b;
  }
}

}  // namespace indoorloc::fusion
