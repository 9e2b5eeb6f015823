// Building one floor's index of the floor plan: the rings and walls checked and collected, the
// grid's cell size chosen within the memory budget, every edge registered in the cells it meets
// (CSR), the empty-ring distances, the cell anchors and their winding counts, then the walkable
// area (floor_plan_area.cc). See docs/fusion.md, "Floor plan".
#include "floor_plan_index.h"

namespace indoorloc::fusion::floor_plan_internal {
namespace {


// Cell side chosen so that a cell holds about `target` edge references on average: an edge of
// extent (|dx|, |dy|) overlaps about 1 + (|dx| + |dy|) / h cells, so with E edges and S the sum
// of |dx| + |dy| over them, E h^2 + S h = target * W * H.
double AutoCellSize(const std::vector<Segment>& edges, double width, double height,
                    const FloorPlanOptions& options) {
  const double e = static_cast<double>(edges.size());
  double s = 0.0;
  for (const Segment& g : edges) s += std::abs(g.x1 - g.x0) + std::abs(g.y1 - g.y0);
  const double area = std::max(width * height, 1e-12);
  const double t = options.target_edges_per_cell;
  double h = (-s + std::sqrt(s * s + 4.0 * e * t * area)) / (2.0 * e);
  // At most 1 m: queries happen in walkable space, where the walls of rooms and shops gather
  // more edges per cell than the average over the box, and a pedestrian step (~0.7 m) then
  // visits one to three cells. Measured on the ILC 2020 mall floor (2413 edges), 1 m cells
  // halve the cost of CrossesWall and IsWalkable against the average rule's 3.9 m.
  h = std::clamp(h, 0.25, 1.0);
  return h;
}

/// Calls fn(cell) for every cell of d's grid whose box, grown by `margin` [m], the segment meets
/// (conservative segment-box overlap: box test, then the four corners not all strictly on one
/// side of the segment's line).
template <typename Fn>
void ForEachCellOfSegment(const FloorData& d, double margin, const Segment& g, Fn&& fn) {
  const double hh = d.h;
  const int i_lo = std::max(0, static_cast<int>(std::floor((std::min(g.x0, g.x1) - margin - d.gx) * d.inv_h)));
  const int i_hi = std::min(d.nx - 1, static_cast<int>(std::floor((std::max(g.x0, g.x1) + margin - d.gx) * d.inv_h)));
  const int j_lo = std::max(0, static_cast<int>(std::floor((std::min(g.y0, g.y1) - margin - d.gy) * d.inv_h)));
  const int j_hi = std::min(d.ny - 1, static_cast<int>(std::floor((std::max(g.y0, g.y1) + margin - d.gy) * d.inv_h)));
  const double ux = g.x1 - g.x0, uy = g.y1 - g.y0;
  for (int j = j_lo; j <= j_hi; ++j) {
    for (int i = i_lo; i <= i_hi; ++i) {
      const double bx0 = d.gx + i * hh - margin, bx1 = d.gx + (i + 1) * hh + margin;
      const double by0 = d.gy + j * hh - margin, by1 = d.gy + (j + 1) * hh + margin;
      const double c0 = ux * (by0 - g.y0) - uy * (bx0 - g.x0);
      const double c1 = ux * (by0 - g.y0) - uy * (bx1 - g.x0);
      const double c2 = ux * (by1 - g.y0) - uy * (bx0 - g.x0);
      const double c3 = ux * (by1 - g.y0) - uy * (bx1 - g.x0);
      const bool all_pos = c0 > 0 && c1 > 0 && c2 > 0 && c3 > 0;
      const bool all_neg = c0 < 0 && c1 < 0 && c2 < 0 && c3 < 0;
      if (!all_pos && !all_neg) fn(j * d.nx + i);
    }
  }
}

/// The CSR index: every edge copied into the cells it meets (margin [m] as ForEachCellOfSegment),
/// `num_entries` registrations in all.
void FillCellEntries(double margin, double num_entries, FloorData& d) {
  const size_t num_cells = static_cast<size_t>(d.nx) * static_cast<size_t>(d.ny);
  auto for_each_cell = [&](const Segment& g, auto&& fn) { ForEachCellOfSegment(d, margin, g, fn); };
  // Three classes in order (outline edges, obstacle edges, walls), so a cell's entries come
  // grouped by class when edges are added in index order.
  std::vector<std::int64_t> count(num_cells * 3, 0);
  auto edge_class = [&](size_t e) {
    return e < static_cast<size_t>(d.num_outline_edges) ? 0
           : e < static_cast<size_t>(d.num_ring_edges)  ? 1
                                                        : 2;
  };
  for (size_t e = 0; e < d.edges.size(); ++e) {
    const size_t cls = static_cast<size_t>(edge_class(e));
    for_each_cell(d.edges[e], [&](int c) { ++count[static_cast<size_t>(c) * 3 + cls]; });
  }
  std::int64_t total = 0;
  for (std::int64_t n : count) total += n;
  assert(static_cast<double>(total) == num_entries);
  (void)total;
  d.cell_begin.assign(num_cells + 1, 0);
  d.obstacle_begin.assign(num_cells, 0);
  d.wall_begin.assign(num_cells, 0);
  std::vector<std::int32_t> fill(num_cells * 3);
  std::int32_t offset = 0;
  for (size_t c = 0; c < num_cells; ++c) {
    d.cell_begin[c] = offset;
    fill[c * 3] = offset;
    offset += static_cast<std::int32_t>(count[c * 3]);
    d.obstacle_begin[c] = offset;
    fill[c * 3 + 1] = offset;
    offset += static_cast<std::int32_t>(count[c * 3 + 1]);
    d.wall_begin[c] = offset;
    fill[c * 3 + 2] = offset;
    offset += static_cast<std::int32_t>(count[c * 3 + 2]);
  }
  d.cell_begin[num_cells] = offset;
  d.entries.resize(static_cast<size_t>(offset));
  d.entry_edge.resize(static_cast<size_t>(offset));
  for (size_t e = 0; e < d.edges.size(); ++e) {
    const size_t cls = static_cast<size_t>(edge_class(e));
    for_each_cell(d.edges[e], [&](int c) {
      const size_t slot = static_cast<size_t>(fill[static_cast<size_t>(c) * 3 + cls]++);
      d.entries[slot] = d.edges[e];
      d.entry_edge[slot] = static_cast<std::int32_t>(e);
    });
  }
  (void)num_entries;
}

/// The outline and obstacle rings of `input`, cleaned, their edges counter-clockwise into d.
void AddRings(const FloorGeometry& input, const std::string& prefix, FloorData& d) {
  // Rings: cleaned, then their edges counter-clockwise.
  for (int kind = 0; kind < 2; ++kind) {
    const auto& rings = kind == 0 ? input.outlines : input.obstacles;
    auto& out = kind == 0 ? d.geometry.outlines : d.geometry.obstacles;
    for (size_t k = 0; k < rings.size(); ++k) {
      const std::string name =
          prefix + (kind == 0 ? ".outlines[" : ".obstacles[") + std::to_string(k) + "]";
      double area = 0.0;
      std::vector<Eigen::Vector2d> v = CleanRing(rings[k], name, &area);
      out.push_back(ToMatrix(v));
      if (area < 0.0) std::reverse(v.begin(), v.end());
      Ring ring;
      ring.kind = kind == 0 ? RingKind::kOutline : RingKind::kObstacle;
      ring.index = static_cast<int>(k);
      ring.first_edge = static_cast<int>(d.edges.size());
      ring.num_edges = static_cast<int>(v.size());
      const int ring_id = static_cast<int>(d.rings.size());
      d.rings.push_back(ring);
      for (size_t m = 0; m < v.size(); ++m) {
        const Eigen::Vector2d& a = v[m];
        const Eigen::Vector2d& b = v[(m + 1) % v.size()];
        d.edges.push_back({a[0], a[1], b[0], b[1]});
        d.edge_info.push_back({ring_id, static_cast<int>(m)});
      }
    }
    if (kind == 0) d.num_outline_edges = static_cast<int>(d.edges.size());
  }
  d.num_ring_edges = static_cast<int>(d.edges.size());
}

/// The wall segments of `input` (checked) after the ring edges.
void AddWalls(const FloorGeometry& input, const std::string& prefix, FloorData& d) {
  // Walls.
  const std::string walls_name = prefix + ".walls";
  if (input.walls.size() == 0) {
    d.geometry.walls = RowMatrixXd::Zero(0, 4);
  } else {
    CheckArgument(input.walls.cols() == 4, walls_name,
                  "expected shape (W, 4) rows (x0, y0, x1, y1), got (" +
                      std::to_string(input.walls.rows()) + ", " +
                      std::to_string(input.walls.cols()) + ")");
    CheckFinite(input.walls, walls_name);
    RequireAllInRange(input.walls, -kMaxPlanCoordinate, kMaxPlanCoordinate, walls_name);
    d.geometry.walls = input.walls;
    for (Eigen::Index r = 0; r < input.walls.rows(); ++r) {
      const Segment w{input.walls(r, 0), input.walls(r, 1), input.walls(r, 2), input.walls(r, 3)};
      CheckArgument(w.x0 != w.x1 || w.y0 != w.y1, walls_name,
                    "row " + std::to_string(r) + " has zero length");
      d.edges.push_back(w);
      d.edge_info.push_back({-1, static_cast<int>(r)});
    }
  }
}

/// Throws naming the ring and the edges when a ring crosses itself.
void CheckRingsDoNotSelfIntersect(int floor_index, const FloorPlanOptions& options, FloorData& d) {
  // Self-intersection, ring by ring, by a sweep line: O(E log E), before any index memory.
  if (options.check_self_intersection) {
    for (const Ring& ring : d.rings) {
      const RingSweepResult r =
          FindRingSelfIntersection(d.edges.data() + ring.first_edge, ring.num_edges);
      d.statistics.self_intersection_work += r.work;
      if (r.found) {
        ThrowInvalidArgument(RingName(floor_index, ring),
                             "is self-intersecting: edges " + std::to_string(r.a) + " and " +
                                 std::to_string(r.b) + " meet near (" + FormatNumber(r.x) +
                                 ", " + FormatNumber(r.y) + ")");
      }
    }
  }
}

/// d.empty_rings: Chebyshev distance in cells to the nearest cell with an entry.
void ComputeEmptyRings(FloorData& d) {
  const size_t num_cells = static_cast<size_t>(d.nx) * static_cast<size_t>(d.ny);
  // Chebyshev distance transform of the non-empty cells (two passes over the 8-neighbourhood).
  {
    constexpr std::int32_t kFar = std::numeric_limits<std::int32_t>::max() / 2;
    d.empty_rings.assign(num_cells, kFar);
    for (size_t c = 0; c < num_cells; ++c) {
      if (d.cell_begin[c + 1] > d.cell_begin[c]) d.empty_rings[c] = 0;
    }
    auto relax = [&](int i, int j, int di, int dj) {
      const int a = i + di, b = j + dj;
      if (a < 0 || a >= d.nx || b < 0 || b >= d.ny) return;
      std::int32_t& here = d.empty_rings[static_cast<size_t>(j * d.nx + i)];
      here = std::min(here, d.empty_rings[static_cast<size_t>(b * d.nx + a)] + 1);
    };
    for (int j = 0; j < d.ny; ++j) {
      for (int i = 0; i < d.nx; ++i) {
        relax(i, j, -1, 0);
        relax(i, j, -1, -1);
        relax(i, j, 0, -1);
        relax(i, j, 1, -1);
      }
    }
    for (int j = d.ny - 1; j >= 0; --j) {
      for (int i = d.nx - 1; i >= 0; --i) {
        relax(i, j, 1, 0);
        relax(i, j, 1, 1);
        relax(i, j, 0, 1);
        relax(i, j, -1, 1);
      }
    }
  }
}

/// d.cells[c].anchor: a point of each cell on no ring edge, with a clearance where possible.
void PlaceAnchors(const std::string& prefix, FloorData& d) {
  const size_t num_cells = static_cast<size_t>(d.nx) * static_cast<size_t>(d.ny);
  const double h = d.h;
  // Anchors: per cell a point on no ring edge, preferring the centre, then points of a fixed
  // pattern inside the cell, choosing the first with a comfortable clearance from the cell's
  // ring edges (or else the one with the largest clearance that is on no edge, exactly).
  d.cells.resize(num_cells);
  static constexpr double kPattern[][2] = {
      {0.5, 0.5},    {0.31, 0.37},  {0.67, 0.29}, {0.29, 0.71}, {0.73, 0.63}, {0.5, 0.19},
      {0.19, 0.5},   {0.81, 0.47},  {0.47, 0.83}, {0.13, 0.13}, {0.87, 0.11}, {0.11, 0.89},
      {0.89, 0.87},  {0.41, 0.59},  {0.59, 0.43}, {0.23, 0.23}, {0.77, 0.79}, {0.37, 0.91},
      {0.93, 0.33},  {0.07, 0.61}};
  for (int j = 0; j < d.ny; ++j) {
    for (int i = 0; i < d.nx; ++i) {
      const size_t c = static_cast<size_t>(j * d.nx + i);
      const std::int32_t begin = d.cell_begin[c], end = d.wall_begin[c];
      double best_x = 0.0, best_y = 0.0, best_clearance = -1.0;
      for (const auto& offsets : kPattern) {
        const double x = d.gx + (i + offsets[0]) * h, y = d.gy + (j + offsets[1]) * h;
        double clearance_sq = std::numeric_limits<double>::infinity();
        bool on_edge = false;
        for (std::int32_t m = begin; m < end; ++m) {
          const Segment& g = d.entries[static_cast<size_t>(m)];
          clearance_sq = std::min(clearance_sq, PointSegmentDistanceSq(x, y, g));
          if (SegmentsIntersect(x, y, x, y, g)) on_edge = true;
        }
        if (on_edge) continue;
        const double clearance = std::sqrt(clearance_sq);
        if (clearance > best_clearance) {
          best_clearance = clearance;
          best_x = x;
          best_y = y;
        }
        if (clearance >= 0.05 * h) break;
      }
      if (best_clearance < 0.0) {
        throw std::runtime_error("indoorloc: FloorPlan: no anchor point found in a cell of " +
                                 prefix + "; try another cell size");
      }
      d.cells[c].anchor_x = best_x;
      d.cells[c].anchor_y = best_y;
    }
  }
}

/// The outline and obstacle winding counts of every anchor.
void CountAnchorWindings(FloorData& d) {
  const double h = d.h;
  // Winding counts of the anchors, propagated from a point outside the grid (count 0) along a
  // chain of anchors of adjacent cells: the segment between two anchors lies in the union of
  // their two cells, so the ring edges it crosses are listed there (counted once each).
  {
    std::vector<std::int32_t> stamp(d.edges.size(), -1);
    std::int32_t stamp_id = 0;
    auto accumulate = [&](double ax, double ay, double bx, double by, size_t c0, size_t c1,
                          std::int32_t* outline, std::int32_t* obstacle) {
      ++stamp_id;
      for (size_t c : {c0, c1}) {
        for (std::int32_t m = d.cell_begin[c]; m < d.wall_begin[c]; ++m) {
          const size_t e = static_cast<size_t>(d.entry_edge[static_cast<size_t>(m)]);
          if (stamp[e] == stamp_id) continue;
          stamp[e] = stamp_id;
          const int s = SignedCrossing(ax, ay, bx, by, d.edges[e], false);
          if (e < static_cast<size_t>(d.num_outline_edges)) {
            *outline += s;
          } else {
            *obstacle += s;
          }
        }
      }
    };
    std::int32_t outline = 0, obstacle = 0;
    // From (gx - h, gy - h): the segment to the anchor of cell (0, 0) meets the grid in that
    // cell only.
    accumulate(d.gx - h, d.gy - h, d.cells[0].anchor_x, d.cells[0].anchor_y, 0, 0, &outline,
               &obstacle);
    d.cells[0].outline_count = outline;
    d.cells[0].obstacle_count = obstacle;
    for (int j = 0; j < d.ny; ++j) {
      const size_t row = static_cast<size_t>(j * d.nx);
      if (j > 0) {
        const size_t below = row - static_cast<size_t>(d.nx);
        outline = d.cells[below].outline_count;
        obstacle = d.cells[below].obstacle_count;
        accumulate(d.cells[below].anchor_x, d.cells[below].anchor_y, d.cells[row].anchor_x,
                   d.cells[row].anchor_y, below, row, &outline, &obstacle);
        d.cells[row].outline_count = outline;
        d.cells[row].obstacle_count = obstacle;
      }
      for (int i = 1; i < d.nx; ++i) {
        const size_t c = row + static_cast<size_t>(i);
        outline = d.cells[c - 1].outline_count;
        obstacle = d.cells[c - 1].obstacle_count;
        accumulate(d.cells[c - 1].anchor_x, d.cells[c - 1].anchor_y, d.cells[c].anchor_x,
                   d.cells[c].anchor_y, c - 1, c, &outline, &obstacle);
        d.cells[c].outline_count = outline;
        d.cells[c].obstacle_count = obstacle;
      }
    }
  }
}

}  // namespace

FloorData BuildFloor(const FloorGeometry& input, int floor_index, const FloorPlanOptions& options) {
  const std::string prefix = "floors[" + std::to_string(floor_index) + "]";
  FloorData d;
  d.floor = input.floor;
  d.geometry.floor = input.floor;
  CheckArgument(!input.outlines.empty(), prefix + ".outlines",
                "a floor needs at least one outline ring");

  AddRings(input, prefix, d);

  AddWalls(input, prefix, d);
  CheckRingsDoNotSelfIntersect(floor_index, options, d);

  // Boxes: the outlines' (Bounds) and all edges' (the grid).
  double ox0 = std::numeric_limits<double>::infinity(), oy0 = ox0, ox1 = -ox0, oy1 = -ox0;
  for (const auto& ring : d.geometry.outlines) {
    ox0 = std::min(ox0, ring.col(0).minCoeff());
    ox1 = std::max(ox1, ring.col(0).maxCoeff());
    oy0 = std::min(oy0, ring.col(1).minCoeff());
    oy1 = std::max(oy1, ring.col(1).maxCoeff());
  }
  d.bounds << ox0, oy0, ox1, oy1;
  double ex0 = ox0, ey0 = oy0, ex1 = ox1, ey1 = oy1;
  double max_abs = 0.0;
  for (const Segment& g : d.edges) {
    ex0 = std::min({ex0, g.x0, g.x1});
    ex1 = std::max({ex1, g.x0, g.x1});
    ey0 = std::min({ey0, g.y0, g.y1});
    ey1 = std::max({ey1, g.y0, g.y1});
    max_abs = std::max({max_abs, std::abs(g.x0), std::abs(g.x1), std::abs(g.y0), std::abs(g.y1)});
  }
  const double width = ex1 - ex0, height = ey1 - ey0;

  // Grid: cell size, then half a cell of margin around the edges' box (every edge lies strictly
  // inside the grid, so the grid's border cells hold no edge near the border).
  double h = options.cell_size_m > 0.0 ? options.cell_size_m
                                       : AutoCellSize(d.edges, width, height, options);
  auto cells_for = [&](double side) {
    return std::ceil(width / side + 1.0) * std::ceil(height / side + 1.0);
  };
  if (cells_for(h) > static_cast<double>(options.max_cells)) {
    CheckArgument(options.cell_size_m <= 0.0, "options.cell_size_m",
                  "cell size " + FormatNumber(h) + " m gives " + FormatNumber(cells_for(h)) +
                      " cells for " + prefix + ", more than options.max_cells = " +
                      std::to_string(options.max_cells));
    // Grow h until the grid fits.
    h = std::max(h, std::sqrt(width * height / static_cast<double>(options.max_cells)));
    while (cells_for(h) > static_cast<double>(options.max_cells)) h *= 1.05;
  }

  // Registration: an edge goes into every cell whose box, grown by a margin far above rounding
  // of the traversal, it meets (conservative segment-box overlap: box test, then the four
  // corners not all strictly on one side of the edge's line).
  auto set_grid = [&](double side) {
    d.h = side;
    d.inv_h = 1.0 / side;
    d.nx = static_cast<int>(std::ceil(width / side + 1.0));
    d.ny = static_cast<int>(std::ceil(height / side + 1.0));
    d.gx = ex0 - 0.5 * (d.nx * side - width);
    d.gy = ey0 - 0.5 * (d.ny * side - height);
  };
  auto margin_for = [&](double side) { return 1e-6 * side + 64.0 * kEpsilon * max_abs; };
  auto for_each_cell = [&](const Segment& g, auto&& fn) { ForEachCellOfSegment(d, margin_for(d.h), g, fn); };

  // Memory of the index, checked before anything is allocated: per cell the registration
  // counts and fill pointers (construction only), the CSR offsets, the anchor with its winding
  // counts and the empty-ring distance; per registration the edge's copy and its id. A given
  // cell size is refused beyond kMaxBytes; an automatic one grows until the index fits in
  // max(64 MB, 1 kB per edge) (long edges on small cells: a star of 2e5 spikes 100 m long
  // registered 8e7 times, 3 GB, with 0.25 m cells).
  constexpr double kBytesPerCell = 3 * sizeof(std::int64_t) + 3 * sizeof(std::int32_t) +
                                   3 * sizeof(std::int32_t) + sizeof(CellInfo) +
                                   sizeof(std::int32_t) + sizeof(std::uint64_t) +  // + the sub-cell mask
                                   4 * (sizeof(std::uint16_t) + 1);  // + 4 quarters' free-block words (and marks)
  constexpr double kBytesPerEntry = sizeof(Segment) + sizeof(std::int32_t);
  const bool automatic = options.cell_size_m <= 0.0;
  const double num_edges = static_cast<double>(d.edges.size());
  const double byte_limit =
      automatic ? std::min(kMaxBytes, std::max(64e6, 1024.0 * num_edges)) : kMaxBytes;
  // Registrations, counted without storing them; stops once past `limit`.
  auto count_entries = [&](double limit) {
    double n = 0.0;
    for (const Segment& g : d.edges) {
      for_each_cell(g, [&](int) { n += 1.0; });
      if (n > limit) break;
    }
    return n;
  };
  // A lower bound without visiting cells: a segment spanning a columns and b rows of cells
  // passes through at least a + b - 1 of them.
  auto entries_lower_bound = [&]() {
    double n = 0.0;
    for (const Segment& g : d.edges) {
      n += std::abs(std::floor((g.x1 - d.gx) * d.inv_h) - std::floor((g.x0 - d.gx) * d.inv_h)) +
           std::abs(std::floor((g.y1 - d.gy) * d.inv_h) - std::floor((g.y0 - d.gy) * d.inv_h)) +
           1.0;
    }
    return n;
  };
  double num_entries = 0.0;
  for (;;) {
    set_grid(h);
    const double cell_bytes = cells_for(h) * kBytesPerCell;
    const double max_entries = std::min(
        std::floor((byte_limit - cell_bytes) / kBytesPerEntry),
        static_cast<double>(std::numeric_limits<std::int32_t>::max()));
    double counted = -1.0;
    const double lower = entries_lower_bound();
    if (max_entries >= 0.0) {
      if (lower <= max_entries) {
        counted = count_entries(max_entries);
        if (counted <= max_entries) {
          num_entries = counted;
          break;
        }
      }
    }
    if (!automatic) {
      const double at_least = std::max(lower, counted);
      ThrowInvalidArgument(
          "options.cell_size_m",
          "cell size " + FormatNumber(h) + " m gives " + FormatNumber(cells_for(h)) +
              " cells and at least " + FormatNumber(at_least) + " edge-cell registrations for " +
              prefix + ": the index would need at least " +
              FormatBytes(cell_bytes + at_least * kBytesPerEntry) + " (limit " +
              FormatBytes(byte_limit) + "); choose a larger cell size or a smaller options.max_cells");
    }
    CheckInterrupt();
    h *= 1.25;
  }
  d.inside_bound = SegmentQuery::InsideBound(d.nx * h, d.ny * h);
  const size_t num_cells = static_cast<size_t>(d.nx) * static_cast<size_t>(d.ny);
  d.statistics.edges = static_cast<std::int64_t>(d.edges.size());
  d.statistics.cells = static_cast<std::int64_t>(num_cells);
  d.statistics.edge_cell_entries = static_cast<std::int64_t>(num_entries);
  d.statistics.index_bytes =
      static_cast<double>(num_cells) * kBytesPerCell + num_entries * kBytesPerEntry;

  FillCellEntries(margin_for(d.h), num_entries, d);

  ComputeEmptyRings(d);
  PlaceAnchors(prefix, d);
  CountAnchorWindings(d);
  ComputeWalkableArea(options, d);
  CheckArgument(d.walkable_area > 0.0, prefix,
                "has no walkable area (its outlines are covered by obstacles)");
  return d;
}

}  // namespace indoorloc::fusion::floor_plan_internal
