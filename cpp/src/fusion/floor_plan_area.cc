// The walkable area of one floor of the floor plan [m^2], by horizontal scanlines over the grid's
// rows (exact crossings with winding counts, midpoint rule per slab).
#include "floor_plan_index.h"

namespace indoorloc::fusion::floor_plan_internal {

/// d.walkable_area [m^2] by horizontal scanlines.
void ComputeWalkableArea(const FloorPlanOptions& options, FloorData& d) {
  const double oy0 = d.bounds[1], oy1 = d.bounds[3];
  // Walkable area by horizontal scanlines. Between consecutive vertex ordinates ("slabs") the
  // walkable length L(y) of a horizontal line is linear (no vertex inside) except where edges of
  // overlapping rings cross, so the midpoint rule per slab is exact for simple non-overlapping
  // rings; slabs taller than height / 1000 are split so that the error at such crossings stays
  // second order. L(y) itself is exact: sorted crossings of the ring edges with winding counts.
  // A line in grid row j meets only ring edges listed in that row's cells.
  {
    std::vector<double> ys{oy0, oy1};
    for (int e = 0; e < d.num_ring_edges; ++e) {
      const double y = d.edges[static_cast<size_t>(e)].y0;
      if (y > oy0 && y < oy1) ys.push_back(y);
    }
    std::sort(ys.begin(), ys.end());
    ys.erase(std::unique(ys.begin(), ys.end()), ys.end());
    double max_slab = (oy1 - oy0) / 1000.0;
    std::vector<std::int32_t> stamp(d.edges.size(), -1);
    std::vector<std::int32_t> row_edges;
    int row = -1;
    struct Crossing {
      double x;
      int outline, obstacle;
    };
    std::vector<Crossing> crossings;
    auto walkable_length = [&](double y) {
      const int j = static_cast<int>(std::clamp(std::floor((y - d.gy) * d.inv_h), 0.0,
                                                static_cast<double>(d.ny - 1)));
      if (j != row) {
        row = j;
        row_edges.clear();
        for (int i = 0; i < d.nx; ++i) {
          const size_t c = static_cast<size_t>(j * d.nx + i);
          for (std::int32_t m = d.cell_begin[c]; m < d.wall_begin[c]; ++m) {
            const std::int32_t e = d.entry_edge[static_cast<size_t>(m)];
            if (stamp[static_cast<size_t>(e)] == j) continue;
            stamp[static_cast<size_t>(e)] = j;
            row_edges.push_back(e);
          }
        }
      }
      crossings.clear();
      d.statistics.area_edge_visits += static_cast<std::int64_t>(row_edges.size());
      for (const std::int32_t e : row_edges) {
        const Segment& g = d.edges[static_cast<size_t>(e)];
        if ((g.y0 <= y) == (g.y1 <= y)) continue;  // half-open rule at vertices
        const double x = g.x0 + (y - g.y0) * (g.x1 - g.x0) / (g.y1 - g.y0);
        const int w = g.y1 > g.y0 ? -1 : 1;  // counter-clockwise: upward edges are left behind
        if (e < d.num_outline_edges) {
          crossings.push_back({x, w, 0});
        } else {
          crossings.push_back({x, 0, w});
        }
      }
      std::sort(crossings.begin(), crossings.end(),
                [](const Crossing& a, const Crossing& b) { return a.x < b.x; });
      int outline = 0, obstacle = 0;
      double length = 0.0;
      for (size_t m = 0; m < crossings.size(); ++m) {
        outline += crossings[m].outline;
        obstacle += crossings[m].obstacle;
        if (m + 1 < crossings.size() && outline > 0 && obstacle == 0) {
          length += crossings[m + 1].x - crossings[m].x;
        }
      }
      return length;
    };
    // The work of that rule is bounded before it runs: a line in grid row j visits the ring
    // entries of that row. Beyond kMaxAreaVisits (a star of 1e5 spikes: 2e5 slabs whose lines
    // each cross ~1e5 edges) the midpoint rule runs on evenly spaced slabs, as many as the
    // budget allows (at least 100).
    constexpr double kMaxAreaVisits = 2e7;
    std::vector<double> row_entries(static_cast<size_t>(d.ny), 0.0);
    for (int j = 0; j < d.ny; ++j) {
      for (int i = 0; i < d.nx; ++i) {
        const size_t c = static_cast<size_t>(j * d.nx + i);
        row_entries[static_cast<size_t>(j)] += d.wall_begin[c] - d.cell_begin[c];
      }
    }
    auto row_of = [&](double y) {
      return static_cast<size_t>(
          std::clamp(std::floor((y - d.gy) * d.inv_h), 0.0, static_cast<double>(d.ny - 1)));
    };
    double planned = 0.0;
    for (size_t k = 0; k + 1 < ys.size() && planned <= kMaxAreaVisits; ++k) {
      const double a = ys[k], b = ys[k + 1];
      const int pieces = std::max(1, static_cast<int>(std::ceil((b - a) / max_slab)));
      const double step = (b - a) / pieces;
      for (int m = 0; m < pieces; ++m) planned += row_entries[row_of(a + (m + 0.5) * step)];
    }
    const bool one_simple_ring = d.rings.size() == 1 && options.check_self_intersection;
    if (planned > kMaxAreaVisits && one_simple_ring) {
      // One outline, checked simple, no obstacle: the shoelace formula is exact (about v[0]).
      d.statistics.area_subsampled = true;
      const Segment* e = d.edges.data();
      double area2 = 0.0;
      for (int k = 1; k + 1 < d.num_ring_edges; ++k) {
        area2 += (e[k].x0 - e[0].x0) * (e[k + 1].y0 - e[0].y0) - (e[k + 1].x0 - e[0].x0) * (e[k].y0 - e[0].y0);
      }
      ys.clear();  // no scanline
      d.walkable_area = 0.5 * std::abs(area2);
    } else if (planned > kMaxAreaVisits) {
      d.statistics.area_subsampled = true;
      const double busiest = *std::max_element(row_entries.begin(), row_entries.end());
      const double slabs = std::max(100.0, std::floor(kMaxAreaVisits / std::max(busiest, 1.0)));
      ys = {oy0, oy1};
      // One slab of height (oy1 - oy0) / slabs split in `slabs` pieces below.
      max_slab = (oy1 - oy0) / slabs * (1.0 + 1e-12);
    }
    double area = 0.0;
    for (size_t k = 0; k + 1 < ys.size(); ++k) {
      const double a = ys[k], b = ys[k + 1];
      const int pieces = std::max(1, static_cast<int>(std::ceil((b - a) / max_slab)));
      const double step = (b - a) / pieces;
      double length_sum = 0.0;
      for (int m = 0; m < pieces; ++m) {
        length_sum += walkable_length(a + (m + 0.5) * step);
        if ((++d.statistics.area_scanlines & 0xFFF) == 0) CheckInterrupt();
      }
      area += length_sum * (b - a) / pieces;
    }
    if (!ys.empty()) d.walkable_area = area;
  }
}

}  // namespace indoorloc::fusion::floor_plan_internal
