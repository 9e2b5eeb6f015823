// One floor's index of the floor plan (FloorData): its rings and edges, the uniform grid of edges
// (CSR), per-cell anchors with winding counts, and the queries on them (point location, wall
// crossing, distance to the nearest wall); and the steps that build it. Private to cpp/src/fusion.
#pragma once

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/core/check.h"
#include "indoorloc/core/interrupt.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "indoorloc/fusion/floor_plan.h"
#include "floor_plan_predicates.h"

namespace indoorloc::fusion::floor_plan_internal {

struct CellInfo {
  double anchor_x, anchor_y;  // a point of the cell on no ring edge
  std::int32_t outline_count;  // number of outlines containing the anchor
  std::int32_t obstacle_count; // number of obstacles containing the anchor
};

enum class RingKind { kOutline, kObstacle };

struct EdgeInfo {
  int ring;      // index into rings (outlines first, then obstacles); -1 for a wall
  int position;  // edge index within its ring
};

struct Ring {
  RingKind kind;
  int index;  // index within its kind (for messages)
  int first_edge, num_edges;
};

inline std::string RingName(int floor_index, const Ring& ring) {
  return "floors[" + std::to_string(floor_index) + "]." +
         (ring.kind == RingKind::kOutline ? "outlines[" : "obstacles[") +
         std::to_string(ring.index) + "]";
}

inline std::string FormatNumber(double v) {
  std::ostringstream out;
  out.precision(6);
  out << v;
  return out.str();
}

/// Whether a ring crosses itself, and where (FindRingSelfIntersection).
struct RingSweepResult {
  bool found = false;
  int a = -1, b = -1;  // positions of two meeting edges in the ring
  double x = 0.0, y = 0.0;  // about where they meet
  std::int64_t work = 0;  // predicate evaluations: tree comparisons + pair tests
};

// Plan coordinates [m] within +-1e7 (any building, also in projected coordinates such as Web
// Mercator): an outline at 1e300 made the grid registration walk ~1e150 cells (a hang).
constexpr double kMaxPlanCoordinate = 1e7;

// One floor's index.
struct FloorData {
  int floor = 0;
  FloorGeometry geometry;       // as given, closing and repeated consecutive vertices dropped
  std::vector<Segment> edges;   // outline edges, obstacle edges (all rings counter-clockwise), walls
  std::vector<EdgeInfo> edge_info;
  std::vector<Ring> rings;
  int num_outline_edges = 0, num_ring_edges = 0;
  Eigen::Vector4d bounds = Eigen::Vector4d::Zero();  // outlines' box
  double walkable_area = 0.0;
  FloorBuildStatistics statistics;

  // Grid: cell (i, j) covers [gx + i h, gx + (i + 1) h) x [gy + j h, gy + (j + 1) h).
  double gx = 0, gy = 0, h = 1, inv_h = 1;
  double inside_bound = 0;  // SegmentQuery's filter bound for ends inside the grid
  int nx = 1, ny = 1;
  // CSR: the entries of cell c are [cell_begin[c], cell_begin[c + 1]): outline edges, then
  // obstacle edges from obstacle_begin[c], then walls from wall_begin[c].
  std::vector<std::int32_t> cell_begin, obstacle_begin, wall_begin;
  std::vector<Segment> entries;
  std::vector<std::int32_t> entry_edge;
  std::vector<CellInfo> cells;
  // Chebyshev distance (in cells) from each cell to the nearest cell with an entry: the rings
  // DistanceToWall may skip.
  std::vector<std::int32_t> empty_rings;
  // Per cell, 8 x 8 sub-cells (bit 8 r + c: sub-row r, sub-column c) that the bounding box of one
  // of the cell's entries reaches (BuildSubcellMasks): a segment whose box reaches no marked
  // sub-cell meets no edge, which decides most wall tests without touching an edge.
  std::vector<std::uint64_t> subcell_masks;
  static constexpr int kSubcells = 8;
  // Quarter cells (4 x 4 sub-cells, h / 2 on a side; 2 nx x 2 ny of them): bit 4 a + b of
  // free_quarter_blocks[q] says that the block of (a + 1) x (b + 1) quarters (a, b in 0..3) whose
  // lowest corner is quarter q holds no marked sub-cell (BuildFreeQuarterBlocks). A step whose
  // box lies in such a block meets no edge: the cheapest decision of the wall test, one 16-bit
  // load per step, for steps up to about a cell and a half (a box within 4 x 4 quarters).
  std::vector<std::uint16_t> free_quarter_blocks;

  int CellOf(double x, double y, int* i, int* j) const {
    const double fx = (x - gx) * inv_h, fy = (y - gy) * inv_h;
    *i = static_cast<int>(std::clamp(std::floor(fx), 0.0, static_cast<double>(nx - 1)));
    *j = static_cast<int>(std::clamp(std::floor(fy), 0.0, static_cast<double>(ny - 1)));
    return *j * nx + *i;
  }

  bool TestCell(int c, const SegmentQuery& q) const {
    const Segment* e = entries.data() + cell_begin[static_cast<size_t>(c)];
    const Segment* end = entries.data() + cell_begin[static_cast<size_t>(c) + 1];
    for (; e != end; ++e) {
      const int f = FilterIntersect(q, *e);
      if (f != 0 && (f == 1 || SegmentsIntersect(q.px, q.py, q.qx, q.qy, *e))) return true;
    }
    return false;
  }

  // Sub-cell index of a grid coordinate f = (x - gx) inv_h >= 0 (scaling by 8 is exact, so
  // index >> 3 is the cell of the point as CellOf and CrossesWall compute it).
  static int SubcellOf(double f) { return static_cast<int>(f * kSubcells); }

  // Marks, in each cell, the sub-cells reached by the bounding box of each of its entries.
  // Exactness: the sub-cell index is a monotone function of the coordinate (each rounding is),
  // so any point X of an entry lies in a sub-cell inside the entry's marked box; if X is also on
  // a query segment, that sub-cell lies in the segment's box too, and the entry is registered in
  // X's cell (registration covers every cell an edge meets, with margin). Hence a segment whose
  // box reaches no marked sub-cell meets no entry: BoxIsFree never hides a crossing.
  void BuildSubcellMasks() {
    subcell_masks.assign(static_cast<size_t>(nx) * static_cast<size_t>(ny), 0);
    const int max_sx = kSubcells * nx - 1, max_sy = kSubcells * ny - 1;
    auto sub = [](double f, int hi) {
      const double s = std::floor(f * kSubcells);
      return static_cast<int>(std::clamp(s, -1.0, static_cast<double>(hi) + 1.0));
    };
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const size_t c = static_cast<size_t>(j) * nx + i;
        std::uint64_t mask = 0;
        for (std::int32_t m = cell_begin[c]; m < cell_begin[c + 1]; ++m) {
          const Segment& e = entries[static_cast<size_t>(m)];
          const int x_lo = std::max(sub((std::min(e.x0, e.x1) - gx) * inv_h, max_sx), kSubcells * i);
          const int x_hi = std::min(sub((std::max(e.x0, e.x1) - gx) * inv_h, max_sx), kSubcells * i + 7);
          const int y_lo = std::max(sub((std::min(e.y0, e.y1) - gy) * inv_h, max_sy), kSubcells * j);
          const int y_hi = std::min(sub((std::max(e.y0, e.y1) - gy) * inv_h, max_sy), kSubcells * j + 7);
          if (x_lo > x_hi || y_lo > y_hi) continue;  // the box only grazes the cell within margin
          mask |= BoxMask(x_lo - kSubcells * i, x_hi - kSubcells * i, y_lo - kSubcells * j, y_hi - kSubcells * j);
        }
        subcell_masks[c] = mask;
      }
    }
  }

  // The free-block bits of every quarter cell from the sub-cell masks (quarters beyond the grid
  // count as marked). Exactness: a block without a marked sub-cell contains no sub-cell that the
  // masks would find marked (BuildSubcellMasks), so a box inside it reaches no marked sub-cell.
  void BuildFreeQuarterBlocks() {
    const int qx = 2 * nx, qy = 2 * ny;
    std::vector<std::uint8_t> marked(static_cast<size_t>(qx) * static_cast<size_t>(qy), 0);
    for (int j = 0; j < qy; ++j) {
      for (int i = 0; i < qx; ++i) {
        const std::uint64_t mask = subcell_masks[static_cast<size_t>(j >> 1) * nx + (i >> 1)];
        const int c0 = 4 * (i & 1), r0 = 4 * (j & 1);
        marked[static_cast<size_t>(j) * qx + i] = (mask & BoxMask(c0, c0 + 3, r0, r0 + 3)) != 0;
      }
    }
    auto is_marked = [&](int i, int j) { return i >= qx || j >= qy || marked[static_cast<size_t>(j) * qx + i]; };
    free_quarter_blocks.assign(marked.size(), 0);
    for (int j = 0; j < qy; ++j) {
      for (int i = 0; i < qx; ++i) {
        std::uint16_t bits = 0;
        for (int a = 0; a < 4; ++a) {
          for (int b = 0; b < 4; ++b) {
            bool free = true;
            for (int di = 0; di <= a && free; ++di) {
              for (int dj = 0; dj <= b && free; ++dj) free = !is_marked(i + di, j + dj);
            }
            if (free) bits = static_cast<std::uint16_t>(bits | (1u << (4 * a + b)));
          }
        }
        free_quarter_blocks[static_cast<size_t>(j) * qx + i] = bits;
      }
    }
  }

  // Bits of sub-columns c0..c1 in sub-rows r0..r1 of a cell's mask (all within 0..7).
  static std::uint64_t BoxMask(int c0, int c1, int r0, int r1) {
    const std::uint64_t columns = (0xFFULL >> (7 - c1)) & (0xFFULL << c0);
    const std::uint64_t rows = (~0ULL >> (8 * (7 - r1))) & (~0ULL << (8 * r0));
    return columns * 0x0101010101010101ULL & rows;
  }

  // Whether the box of sub-cells [sx0, sx1] x [sy0, sy1] (inside the grid, spanning at most
  // 2 x 2 cells) reaches no marked sub-cell. Branch-free: always four cells, the masks of those
  // the box does not reach being empty (which cells it reaches varies from step to step).
  bool BoxIsFree(int sx0, int sx1, int sy0, int sy1) const {
    const int i0 = sx0 >> 3, i1 = sx1 >> 3, j0 = sy0 >> 3, j1 = sy1 >> 3;
    const std::uint64_t to_c1 = 0xFFULL >> (7 - (sx1 & 7)), from_c0 = 0xFFULL << (sx0 & 7);
    const std::uint64_t cols_a = from_c0 & (i1 == i0 ? to_c1 : 0xFFULL) & 0xFFULL;
    const std::uint64_t cols_b = i1 == i0 ? 0 : to_c1;
    const std::uint64_t to_r1 = ~0ULL >> (8 * (7 - (sy1 & 7))), from_r0 = ~0ULL << (8 * (sy0 & 7));
    const std::uint64_t rows_a = from_r0 & (j1 == j0 ? to_r1 : ~0ULL);
    const std::uint64_t rows_b = j1 == j0 ? 0 : to_r1;
    constexpr std::uint64_t kEveryRow = 0x0101010101010101ULL;
    const std::uint64_t* row0 = subcell_masks.data() + static_cast<size_t>(j0) * nx;
    const std::uint64_t* row1 = subcell_masks.data() + static_cast<size_t>(j1) * nx;
    const std::uint64_t hit = (row0[i0] & cols_a * kEveryRow & rows_a) | (row0[i1] & cols_b * kEveryRow & rows_a) |
                              (row1[i0] & cols_a * kEveryRow & rows_b) | (row1[i1] & cols_b * kEveryRow & rows_b);
    return hit == 0;
  }

  // Starts loading the sub-cell mask of the cell of (x, y) (clamped to the grid): the wall test
  // of a block of particles reads masks in random order, mostly from beyond the L2 cache.
  void PrefetchMask(double x, double y) const {
    const double fx = std::clamp((x - gx) * inv_h, 0.0, static_cast<double>(nx - 1));
    const double fy = std::clamp((y - gy) * inv_h, 0.0, static_cast<double>(ny - 1));
    __builtin_prefetch(subcell_masks.data() + static_cast<size_t>(fy) * nx + static_cast<size_t>(fx));
  }

  // The wall test: the common case of a short step inside the grid whose box reaches no marked
  // sub-cell is decided here without touching an edge; the rest by CrossesWallExact.
  bool CrossesWall(double px, double py, double qx, double qy) const {
    const double fx0 = (px - gx) * inv_h, fy0 = (py - gy) * inv_h;
    const double fx1 = (qx - gx) * inv_h, fy1 = (qy - gy) * inv_h;
    const double lo_x = std::min(fx0, fx1), hi_x = std::max(fx0, fx1);
    const double lo_y = std::min(fy0, fy1), hi_y = std::max(fy0, fy1);
    if (lo_x >= 0 && hi_x < static_cast<double>(nx) && lo_y >= 0 && hi_y < static_cast<double>(ny)) {
      const int sx0 = SubcellOf(lo_x), sx1 = SubcellOf(hi_x);
      const int sy0 = SubcellOf(lo_y), sy1 = SubcellOf(hi_y);
      // The quarters of the box's corners (4 sub-cells each way).
      const int a = (sx1 >> 2) - (sx0 >> 2), b = (sy1 >> 2) - (sy0 >> 2);
      if (a <= 3 && b <= 3 &&
          ((free_quarter_blocks[static_cast<size_t>(sy0 >> 2) * (2 * nx) + (sx0 >> 2)] >> (4 * a + b)) & 1)) {
        return false;
      }
      if ((sx1 >> 3) - (sx0 >> 3) <= 1 && (sy1 >> 3) - (sy0 >> 3) <= 1 && BoxIsFree(sx0, sx1, sy0, sy1)) {
        return false;
      }
    }
    return CrossesWallExact(px, py, qx, qy);
  }

  // The exact wall test: the edges of the cells the segment crosses (grid walk).
  [[gnu::noinline]] bool CrossesWallExact(double px, double py, double qx, double qy) const {
    const double wx = static_cast<double>(nx), wy = static_cast<double>(ny);
    const double fx0 = (px - gx) * inv_h, fy0 = (py - gy) * inv_h;
    const double fx1 = (qx - gx) * inv_h, fy1 = (qy - gy) * inv_h;
    // Both ends inside the grid: one cell, two neighbouring cells, or a traversal.
    if (fx0 >= 0 && fx0 < wx && fy0 >= 0 && fy0 < wy && fx1 >= 0 && fx1 < wx && fy1 >= 0 &&
        fy1 < wy) {
      const SegmentQuery query(px, py, qx, qy, inside_bound);
      const int i0 = static_cast<int>(fx0), j0 = static_cast<int>(fy0);
      const int i1 = static_cast<int>(fx1), j1 = static_cast<int>(fy1);
      const int c0 = j0 * nx + i0, c1 = j1 * nx + i1;
      const int cells_apart = std::abs(i1 - i0) + std::abs(j1 - j0);
      if (cells_apart <= 1) return TestCell(c0, query) || (c1 != c0 && TestCell(c1, query));
      return Traverse(query, i0, j0, i1, j1);
    }
    const SegmentQuery query(px, py, qx, qy, gx, gy, wx * h, wy * h);
    // Clip the segment to the grid's box (Liang & Barsky); no edge lies outside it.
    const double dx = query.dx, dy = query.dy;
    double t0 = 0.0, t1 = 1.0;
    auto clip = [&](double den, double num) {  // keep t with den * t <= num
      if (den == 0.0) return num >= 0.0;
      const double t = num / den;
      if (den > 0.0) {
        t1 = std::min(t1, t);
      } else {
        t0 = std::max(t0, t);
      }
      return t0 <= t1;
    };
    const double x_max = gx + wx * h, y_max = gy + wy * h;
    if (!(clip(-dx, px - gx) && clip(dx, x_max - px) && clip(-dy, py - gy) &&
          clip(dy, y_max - py))) {
      return false;
    }
    const double sx = t0 == 0.0 ? px : px + t0 * dx, sy = t0 == 0.0 ? py : py + t0 * dy;
    const double ex = t1 == 1.0 ? qx : px + t1 * dx, ey = t1 == 1.0 ? qy : py + t1 * dy;
    int i0, j0, i1, j1;
    CellOf(sx, sy, &i0, &j0);
    CellOf(ex, ey, &i1, &j1);
    return Traverse(query, i0, j0, i1, j1);
  }

  // Amanatides & Woo: the 4-connected chain of cells from (i0, j0) to (i1, j1) along the
  // segment. Rounding can only swap the order of an x and a y step where the segment passes
  // within rounding of a cell corner; the cells' registration margin covers that.
  bool Traverse(const SegmentQuery& q, int i0, int j0, int i1, int j1) const {
    int i = i0, j = j0;
    if (TestCell(j * nx + i, q)) return true;
    const int step_i = i1 > i0 ? 1 : -1, step_j = j1 > j0 ? 1 : -1;
    const int n = std::abs(i1 - i0) + std::abs(j1 - j0);
    const double adx = std::abs(q.dx), ady = std::abs(q.dy);
    for (int k = 0; k < n; ++k) {
      bool step_x;
      if (i == i1) {
        step_x = false;
      } else if (j == j1) {
        step_x = true;
      } else {
        // The next x boundary comes first iff its parameter along p -> q is smaller:
        // bx / |dx| < by / |dy| with bx, by the distances to the boundaries (no division).
        const double bx = step_i > 0 ? gx + (i + 1) * h - q.px : q.px - (gx + i * h);
        const double by = step_j > 0 ? gy + (j + 1) * h - q.py : q.py - (gy + j * h);
        step_x = bx * ady < by * adx;
      }
      if (step_x) {
        i += step_i;
      } else {
        j += step_j;
      }
      if (TestCell(j * nx + i, q)) return true;
    }
    return false;
  }

  bool IsWalkable(double x, double y) const {
    const double fx = (x - gx) * inv_h, fy = (y - gy) * inv_h;
    if (!(fx >= 0 && fx < static_cast<double>(nx) && fy >= 0 && fy < static_cast<double>(ny))) {
      return false;  // outside the grid, hence outside every outline
    }
    const size_t c = static_cast<size_t>(static_cast<int>(fy) * nx + static_cast<int>(fx));
    const CellInfo& cell = cells[c];
    int outline = cell.outline_count, obstacle = cell.obstacle_count;
    const double ax = cell.anchor_x, ay = cell.anchor_y;
    const SegmentQuery q(ax, ay, x, y, inside_bound);
    const Segment* e = entries.data() + cell_begin[c];
    const Segment* obstacles = entries.data() + obstacle_begin[c];
    const Segment* walls = entries.data() + wall_begin[c];
    for (; e != obstacles; ++e) {
      if (FilterIntersect(q, *e) != 0) {
        outline += SignedCrossing(ax, ay, x, y, *e, false);
      }
    }
    for (; e != walls; ++e) {
      if (FilterIntersect(q, *e) != 0) {
        obstacle += SignedCrossing(ax, ay, x, y, *e, true);
      }
    }
    return outline > 0 && obstacle == 0;
  }

  double DistanceToWall(double x, double y) const {
    int ci, cj;
    CellOf(x, y, &ci, &cj);
    double best = std::numeric_limits<double>::infinity();
    for (int k = empty_rings[static_cast<size_t>(cj * nx + ci)];; ++k) {
      // Cells at Chebyshev index distance exactly k from (ci, cj).
      const int i_lo = ci - k, i_hi = ci + k, j_lo = cj - k, j_hi = cj + k;
      auto visit = [&](int i, int j) {
        if (i < 0 || i >= nx || j < 0 || j >= ny) return;
        // Skip a cell whose box is farther than the best distance so far.
        const double cx0 = gx + i * h, cy0 = gy + j * h;
        const double ox = std::max({0.0, cx0 - x, x - (cx0 + h)});
        const double oy = std::max({0.0, cy0 - y, y - (cy0 + h)});
        if (ox * ox + oy * oy > best) return;
        const size_t c = static_cast<size_t>(j * nx + i);
        for (std::int32_t m = cell_begin[c]; m < cell_begin[c + 1]; ++m) {
          best = std::min(best, PointSegmentDistanceSq(x, y, entries[static_cast<size_t>(m)]));
        }
      };
      if (k == 0) {
        visit(ci, cj);
      } else {
        for (int i = i_lo; i <= i_hi; ++i) {
          visit(i, j_lo);
          visit(i, j_hi);
        }
        for (int j = j_lo + 1; j < j_hi; ++j) {
          visit(i_lo, j);
          visit(i_hi, j);
        }
      }
      // Every cell not yet visited lies beyond one side of the box of visited cells: its points
      // are at least that side's distance from (x, y) away (sides with no cells beyond are
      // skipped). Stop once the best distance cannot be beaten.
      double bound = std::numeric_limits<double>::infinity();
      bool remaining = false;
      if (i_lo > 0) {
        remaining = true;
        bound = std::min(bound, std::max(0.0, x - (gx + i_lo * h)));
      }
      if (i_hi < nx - 1) {
        remaining = true;
        bound = std::min(bound, std::max(0.0, gx + (i_hi + 1) * h - x));
      }
      if (j_lo > 0) {
        remaining = true;
        bound = std::min(bound, std::max(0.0, y - (gy + j_lo * h)));
      }
      if (j_hi < ny - 1) {
        remaining = true;
        bound = std::min(bound, std::max(0.0, gy + (j_hi + 1) * h - y));
      }
      if (!remaining || best <= bound * bound) break;
    }
    return std::sqrt(best);
  }
};

// Ring cleaning (floor_plan_rings.cc).

/// Self-intersection of one ring of n edges by a sweep line, O(n log n), exact.
RingSweepResult FindRingSelfIntersection(const Segment* edges, int n);
/// Ring as given -> vertices without closing or consecutive repeated vertices; checks shape,
/// finiteness, distinct vertices and area; *signed_area [m^2].
std::vector<Eigen::Vector2d> CleanRing(const RowMatrixXd& ring, const std::string& name, double* signed_area);
/// Vertices as an (n, 2) matrix.
RowMatrixXd ToMatrix(const std::vector<Eigen::Vector2d>& v);

// Building a floor's index (floor_plan_build.cc, floor_plan_area.cc).

/// One floor's index; throws naming floors[floor_index] and the problem.
FloorData BuildFloor(const FloorGeometry& input, int floor_index, const FloorPlanOptions& options);
/// d.walkable_area [m^2] by horizontal scanlines.
void ComputeWalkableArea(const FloorPlanOptions& options, FloorData& d);

}  // namespace indoorloc::fusion::floor_plan_internal
