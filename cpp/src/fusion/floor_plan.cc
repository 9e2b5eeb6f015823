// Implementation of FloorPlan: a uniform grid of edges per floor (CSR layout, edge coordinates
// stored contiguously per cell), exact orientation predicates (a floating-point filter with an
// exact expansion-arithmetic fallback, after Shewchuk 1997), Amanatides & Woo cell traversal for
// wall crossings, per-cell anchors with precomputed winding counts for point location, and
// expanding rings of cells for the distance to the nearest wall. See docs/fusion.md, "Floor plan".
#include "indoorloc/fusion/floor_plan.h"

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

#include "indoorloc/core/check.h"
#include "indoorloc/core/interrupt.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"

namespace indoorloc::fusion {
namespace {

// ------------------------------------------------------------------------------------------
// Exact orientation predicate.
//
// Orient(a, b, c) = sign of (b - a) x (c - a): +1 if c lies left of the directed line a -> b,
// -1 if right, 0 if the three points are collinear. It is computed as Shewchuk's orient2d
// (detleft - detright with the differences taken at c = a) and is certified by his static error
// bound; uncertain cases are decided exactly: each coordinate difference becomes a two-term
// expansion (TwoDiff), the products four two-term expansions each (TwoProduct by fma), and the
// sign of the exact sum of the 16 terms is read from a non-overlapping expansion (GrowExpansion
// with zero elimination). The result is the exact sign for the given doubles.

constexpr double kEpsilon = 0x1p-53;  // half an ulp of 1
constexpr double kOrientBound = (3.0 + 16.0 * kEpsilon) * kEpsilon;

inline void TwoSum(double a, double b, double* s, double* e) {
  *s = a + b;
  const double bv = *s - a;
  const double av = *s - bv;
  *e = (a - av) + (b - bv);
}

inline void TwoProduct(double a, double b, double* p, double* e) {
  *p = a * b;
  *e = std::fma(a, b, -*p);
}

// Sign of the exact sum of n doubles (n <= 32).
int ExactSumSign(const double* terms, int n) {
  double h[32];
  int m = 0;
  for (int k = 0; k < n; ++k) {
    double q = terms[k];
    int mm = 0;
    for (int i = 0; i < m; ++i) {
      double s, e;
      TwoSum(q, h[i], &s, &e);
      if (e != 0.0) h[mm++] = e;
      q = s;
    }
    if (q != 0.0) h[mm++] = q;
    m = mm;
  }
  // Components are non-overlapping and increasing in magnitude: the last one has the sign.
  return m == 0 ? 0 : (h[m - 1] > 0.0 ? 1 : -1);
}

[[gnu::noinline]] int ExactOrient(double ax, double ay, double bx, double by, double cx,
                                  double cy) {
  // (bx - ax) (cy - ay) - (by - ay) (cx - ax), every difference and product kept exactly.
  double d[4][2];
  TwoSum(bx, -ax, &d[0][0], &d[0][1]);
  TwoSum(cy, -ay, &d[1][0], &d[1][1]);
  TwoSum(by, -ay, &d[2][0], &d[2][1]);
  TwoSum(cx, -ax, &d[3][0], &d[3][1]);
  double terms[16];
  int n = 0;
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      TwoProduct(d[0][i], d[1][j], &terms[n], &terms[n + 1]);
      n += 2;
      TwoProduct(-d[2][i], d[3][j], &terms[n], &terms[n + 1]);
      n += 2;
    }
  }
  return ExactSumSign(terms, n);
}

inline int Orient(double ax, double ay, double bx, double by, double cx, double cy) {
  const double detleft = (bx - ax) * (cy - ay);
  const double detright = (by - ay) * (cx - ax);
  const double det = detleft - detright;
  const double bound = kOrientBound * (std::abs(detleft) + std::abs(detright));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return ExactOrient(ax, ay, bx, by, cx, cy);
}

struct Segment {
  double x0, y0, x1, y1;
};

// Closed segments p-q and u-v intersect (touching counts), exactly.
bool SegmentsIntersect(double px, double py, double qx, double qy, const Segment& e) {
  const int o1 = Orient(px, py, qx, qy, e.x0, e.y0);
  const int o2 = Orient(px, py, qx, qy, e.x1, e.y1);
  if (o1 == o2 && o1 != 0) return false;
  const int o3 = Orient(e.x0, e.y0, e.x1, e.y1, px, py);
  const int o4 = Orient(e.x0, e.y0, e.x1, e.y1, qx, qy);
  if (o3 == o4 && o3 != 0) return false;
  if (o1 == 0 && o2 == 0) {
    // All four points on one line (or p == q on the line of u-v): the segments meet iff their
    // bounding boxes do.
    return std::max(std::min(px, qx), std::min(e.x0, e.x1)) <=
               std::min(std::max(px, qx), std::max(e.x0, e.x1)) &&
           std::max(std::min(py, qy), std::min(e.y0, e.y1)) <=
               std::min(std::max(py, qy), std::max(e.y0, e.y1));
  }
  return true;
}

// Change of the winding number of a counter-clockwise ring along a -> p caused by its edge
// u -> v: +1 entering (u -> v seen from outside to inside), -1 leaving, 0 otherwise. Vertices on
// the line a -> p count as lying on its right (symbolic perturbation), so that a ring vertex on
// the segment is counted once. `a` must not lie on the edge. A point p on the edge counts as
// inside when `closed` (obstacles: conservative) and outside otherwise (outlines).
int SignedCrossing(double ax, double ay, double px, double py, const Segment& e, bool closed) {
  const bool su = Orient(ax, ay, px, py, e.x0, e.y0) > 0;
  const bool sv = Orient(ax, ay, px, py, e.x1, e.y1) > 0;
  if (su == sv) return 0;
  const bool inside_a = Orient(e.x0, e.y0, e.x1, e.y1, ax, ay) > 0;
  const int op = Orient(e.x0, e.y0, e.x1, e.y1, px, py);
  const bool inside_p = closed ? op >= 0 : op > 0;
  if (inside_a == inside_p) return 0;
  return inside_p ? 1 : -1;
}

// A segment query p -> q = p + d against edges u -> v = u + e, with the floating-point filter
// of the hot loops. Per edge it computes, with one rounding per operation,
//   o1 = dx uy - dy ux          (Orient(p, q, u); ux = x0 - px, uy = y0 - py)
//   c  = dx ey - dy ex          (d x e; ex = x1 - x0, ey = y1 - y0)
//   o2 = o1 + c                 (Orient(p, q, v))
//   o3 = ey ux - ex uy          (Orient(u, v, p))
//   o4 = o3 - c                 (Orient(u, v, q))
// Each difference and product carries a relative error of at most eps = 2^-53, so with
// A = |dx| max|uy| + |dy| max|ux|, C = |dx| max|ey| + |dy| max|ex|, D = max|ey| max|ux| +
// max|ex| max|uy| the errors are at most 5 eps A (o1), 5 eps C (c), 6 eps (A + C) (o2),
// 5 eps D (o3) and 6 eps (D + C) (o4). The bounds used, b12 = 8 eps (A + C) and
// b34 = 8 eps (D + C), certify the signs of o1, o2 and o3, o4. Every edge coordinate lies in
// the grid's box (W x H): for p and q inside it A, C, D <= 2 W H, so one constant per floor
// (`inside_bound` = 32 eps W H) serves; for ends outside it the maxima are the distances to the
// far sides of the box. A bound larger than necessary is still a certificate; it only sends
// more near-degenerate cases (|orientation| below ~1e-15 W H) to the exact predicates.
struct SegmentQuery {
  double px, py, qx, qy, dx, dy;
  double b12, b34;

  // Both ends inside the grid's box.
  SegmentQuery(double px_, double py_, double qx_, double qy_, double inside_bound)
      : px(px_), py(py_), qx(qx_), qy(qy_), dx(qx_ - px_), dy(qy_ - py_), b12(inside_bound),
        b34(inside_bound) {}

  // Any ends; (gx, gy, w, h) is the grid's box.
  SegmentQuery(double px_, double py_, double qx_, double qy_, double gx, double gy, double w,
               double h)
      : px(px_), py(py_), qx(qx_), qy(qy_), dx(qx_ - px_), dy(qy_ - py_) {
    const double mx = std::max(std::abs(px - gx), std::abs(gx + w - px));
    const double my = std::max(std::abs(py - gy), std::abs(gy + h - py));
    const double a = std::abs(dx) * my + std::abs(dy) * mx;
    const double c = std::abs(dx) * h + std::abs(dy) * w;
    const double d = h * mx + w * my;
    b12 = kSlack * 8.0 * kEpsilon * (a + c);
    b34 = kSlack * 8.0 * kEpsilon * (d + c);
  }

  static constexpr double kSlack = 1.0 + 1e-10;  // covers rounding of the bounds themselves
  static double InsideBound(double w, double h) { return kSlack * 32.0 * kEpsilon * w * h; }
};

// The filter's outcome for one edge: 0 the closed segments certainly do not meet (one pair of
// points certainly strictly on one side of the other segment's line), 1 they certainly cross
// properly, 2 undecided (touching, or degenerate within rounding: the exact predicates decide).
// The first test is almost always decisive, so its branch predicts well.
inline int FilterIntersect(const SegmentQuery& q, const Segment& e) {
  const double ux = e.x0 - q.px, uy = e.y0 - q.py;
  const double ex = e.x1 - e.x0, ey = e.y1 - e.y0;
  const double o1 = q.dx * uy - q.dy * ux;
  const double c = q.dx * ey - q.dy * ex;
  const double o2 = o1 + c;
  const double o3 = ey * ux - ex * uy;
  const double o4 = o3 - c;
  const double lo12 = std::min(o1, o2), hi12 = std::max(o1, o2);
  const double lo34 = std::min(o3, o4), hi34 = std::max(o3, o4);
  if ((lo12 > q.b12) | (hi12 < -q.b12) | (lo34 > q.b34) | (hi34 < -q.b34)) return 0;
  const bool proper = (lo12 < -q.b12) & (hi12 > q.b12) & (lo34 < -q.b34) & (hi34 > q.b34);
  return proper ? 1 : 2;
}

double PointSegmentDistanceSq(double x, double y, const Segment& e) {
  const double ux = e.x1 - e.x0, uy = e.y1 - e.y0;
  const double wx = x - e.x0, wy = y - e.y0;
  const double len_sq = ux * ux + uy * uy;
  double t = (wx * ux + wy * uy) / len_sq;
  t = std::clamp(t, 0.0, 1.0);
  const double rx = wx - t * ux, ry = wy - t * uy;
  return rx * rx + ry * ry;
}

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

std::string RingName(int floor_index, const Ring& ring) {
  return "floors[" + std::to_string(floor_index) + "]." +
         (ring.kind == RingKind::kOutline ? "outlines[" : "obstacles[") +
         std::to_string(ring.index) + "]";
}

std::string FormatNumber(double v) {
  std::ostringstream out;
  out.precision(6);
  out << v;
  return out.str();
}

// ------------------------------------------------------------------------------------------
// Self-intersection of one ring by a sweep line (Shamos & Hoey 1976), O(E log E).
//
// The sweep visits the ring's vertices in lexicographic (x, then y) order, which tilts the sweep
// line infinitesimally so that vertical edges need no special case. An edge is active between
// its lexicographically smaller ("left") and larger ("right") vertex; the active edges are kept
// in a balanced tree ordered from below to above along the sweep line. A ring is simple iff no
// two edges meet except consecutive edges at their shared vertex (consecutive edges that fold
// back onto each other along a line also meet). If some pair meets, the pair meeting at the
// lexicographically smallest point is adjacent in the tree just before that point (edges
// between them would meet one of them there too), so testing only pairs that become adjacent
// (on insertion, and on removal for the neighbours of the removed edge) finds a meeting pair.
// Every decision uses the exact orientation predicate, so the verdict is exact for the given
// doubles and equals that of a test of all pairs. Repeated vertices (two vertices at one
// point) are found first by sorting.
struct SweepEdge {
  double lx, ly, rx, ry;  // left (lexicographically smaller) and right end
};

inline bool LexLess(double ax, double ay, double bx, double by) {
  return ax < bx || (ax == bx && ay < by);
}

struct RingSweepResult {
  bool found = false;
  int a = -1, b = -1;  // positions of two meeting edges in the ring
  double x = 0.0, y = 0.0;  // about where they meet
  std::int64_t work = 0;  // predicate evaluations: tree comparisons + pair tests
};

// Closed edges a -> b of a ring of n edges (edge m runs from vertex m to vertex m + 1): do they
// meet where a simple ring would not?
bool RingEdgesMeet(const Segment* edges, int n, int a, int b) {
  const int gap = std::abs(a - b);
  if (gap == 1 || gap == n - 1) {
    // Consecutive edges x -> w -> y share w; bad only if they overlap along a line.
    const bool a_first = (a + 1) % n == b;
    const Segment& first = edges[a_first ? a : b];
    const Segment& second = edges[a_first ? b : a];
    return Orient(first.x0, first.y0, first.x1, first.y1, second.x1, second.y1) == 0 &&
           (first.x1 - first.x0) * (second.x1 - second.x0) +
                   (first.y1 - first.y0) * (second.y1 - second.y0) <
               0.0;
  }
  const Segment& s = edges[a];
  return SegmentsIntersect(s.x0, s.y0, s.x1, s.y1, edges[b]);
}

// A point where two meeting edges meet (for the message only).
void MeetingPoint(const Segment& s, const Segment& e, double* x, double* y) {
  const double dx = s.x1 - s.x0, dy = s.y1 - s.y0, ex = e.x1 - e.x0, ey = e.y1 - e.y0;
  const double den = dx * ey - dy * ex;
  if (den != 0.0) {
    const double t = std::clamp(((e.x0 - s.x0) * ey - (e.y0 - s.y0) * ex) / den, 0.0, 1.0);
    *x = s.x0 + t * dx;
    *y = s.y0 + t * dy;
    return;
  }
  // Parallel (overlapping): an end of one inside the other's box.
  for (const auto& p : {std::array<double, 2>{e.x0, e.y0}, std::array<double, 2>{e.x1, e.y1},
                        std::array<double, 2>{s.x0, s.y0}}) {
    if (p[0] >= std::min(s.x0, s.x1) && p[0] <= std::max(s.x0, s.x1) &&
        p[1] >= std::min(s.y0, s.y1) && p[1] <= std::max(s.y0, s.y1) &&
        p[0] >= std::min(e.x0, e.x1) && p[0] <= std::max(e.x0, e.x1) &&
        p[1] >= std::min(e.y0, e.y1) && p[1] <= std::max(e.y0, e.y1)) {
      *x = p[0];
      *y = p[1];
      return;
    }
  }
  *x = s.x1;
  *y = s.y1;
}

RingSweepResult FindRingSelfIntersection(const Segment* edges, int n) {
  RingSweepResult result;
  auto report = [&](int a, int b) {
    if (result.found) return;
    result.found = true;
    result.a = std::min(a, b);
    result.b = std::max(a, b);
    MeetingPoint(edges[a], edges[b], &result.x, &result.y);
  };
  // Vertex m is edges[m]'s start. Repeated vertices first.
  std::vector<int> order(static_cast<size_t>(n));
  for (int m = 0; m < n; ++m) order[static_cast<size_t>(m)] = m;
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return LexLess(edges[a].x0, edges[a].y0, edges[b].x0, edges[b].y0) ||
           (edges[a].x0 == edges[b].x0 && edges[a].y0 == edges[b].y0 && a < b);
  });
  for (size_t k = 1; k < order.size(); ++k) {
    const Segment& p = edges[order[k - 1]];
    const Segment& q = edges[order[k]];
    if (p.x0 == q.x0 && p.y0 == q.y0) {
      report(order[k - 1], order[k]);  // both edges start at one point
      return result;
    }
  }
  std::vector<SweepEdge> sweep(static_cast<size_t>(n));
  for (int m = 0; m < n; ++m) {
    const Segment& g = edges[m];
    const bool forward = LexLess(g.x0, g.y0, g.x1, g.y1);
    sweep[static_cast<size_t>(m)] = forward ? SweepEdge{g.x0, g.y0, g.x1, g.y1}
                                            : SweepEdge{g.x1, g.y1, g.x0, g.y0};
  }
  // a below b along the sweep line where both are active. The later-starting edge's left end
  // is located against the other edge's line; edges starting at one vertex (consecutive edges)
  // are ordered by their right ends. A left end exactly on the other edge means they meet.
  auto below = [&](int a, int b) {
    if (a == b) return false;
    ++result.work;
    const SweepEdge& A = sweep[static_cast<size_t>(a)];
    const SweepEdge& B = sweep[static_cast<size_t>(b)];
    int o;
    bool a_below_if_positive;
    if (A.lx == B.lx && A.ly == B.ly) {
      o = Orient(B.lx, B.ly, B.rx, B.ry, A.rx, A.ry);  // > 0: A's right end above B
      a_below_if_positive = false;
    } else if (LexLess(A.lx, A.ly, B.lx, B.ly)) {
      o = Orient(A.lx, A.ly, A.rx, A.ry, B.lx, B.ly);  // > 0: B starts above A
      a_below_if_positive = true;
    } else {
      o = Orient(B.lx, B.ly, B.rx, B.ry, A.lx, A.ly);  // > 0: A starts above B
      a_below_if_positive = false;
    }
    if (o == 0) {
      report(a, b);
      return a < b;  // any order; the sweep stops after this insertion
    }
    return (o > 0) == a_below_if_positive;
  };
  std::set<int, decltype(below)> active(below);
  std::vector<std::set<int, decltype(below)>::iterator> where(static_cast<size_t>(n),
                                                               active.end());
  auto test = [&](int a, int b) {
    ++result.work;
    if (RingEdgesMeet(edges, n, a, b)) report(a, b);
  };
  for (const int v : order) {
    // Vertex v ends edge v - 1 and starts edge v.
    const int incident[2] = {(v + n - 1) % n, v};
    const double vx = edges[v].x0, vy = edges[v].y0;
    for (const int e : incident) {  // removals first
      const SweepEdge& s = sweep[static_cast<size_t>(e)];
      if (!(s.rx == vx && s.ry == vy)) continue;
      auto it = where[static_cast<size_t>(e)];
      assert(it != active.end());
      auto next = std::next(it);
      if (it != active.begin() && next != active.end()) test(*std::prev(it), *next);
      active.erase(it);
      where[static_cast<size_t>(e)] = active.end();
      if (result.found) return result;
    }
    for (const int e : incident) {
      const SweepEdge& s = sweep[static_cast<size_t>(e)];
      if (!(s.lx == vx && s.ly == vy)) continue;
      const auto it = active.insert(e).first;
      if (result.found) return result;
      where[static_cast<size_t>(e)] = it;
      if (it != active.begin()) test(*std::prev(it), e);
      if (std::next(it) != active.end()) test(e, *std::next(it));
      if (result.found) return result;
    }
  }
  return result;
}

}  // namespace

bool FloorPlanOptions::IsValid(std::string* error) const {
  // A tiny positive cell size is refused when the plan is built, against max_cells (the message
  // then gives the number of cells it would take).
  return Validator(error)
      .Finite(cell_size_m, "cell_size_m")
      .Check(cell_size_m <= 1e6, "cell_size_m",
             "must be <= 0 (automatic) or in (0, 1e+06] m, got " + FormatValue(cell_size_m))
      .InRange(target_edges_per_cell, 1e-3, 1e6, "target_edges_per_cell")
      .IntInRange(max_cells, 1, 100000000, "max_cells");
}

namespace {

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

  bool CrossesWall(double px, double py, double qx, double qy) const {
    const double wx = static_cast<double>(nx), wy = static_cast<double>(ny);
    const double fx0 = (px - gx) * inv_h, fy0 = (py - gy) * inv_h;
    const double fx1 = (qx - gx) * inv_h, fy1 = (qy - gy) * inv_h;
    // Fast path: both ends inside the grid; one cell, two neighbouring cells, or a traversal.
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
}  // namespace

struct FloorPlan::Impl {
  std::vector<FloorData> floors;
  std::vector<int> floor_numbers;
  FloorPlanOptions options;
};

namespace {

// Plan coordinates [m] within +-1e7 (any building, also in projected coordinates such as Web
// Mercator): an outline at 1e300 made the grid registration walk ~1e150 cells (a hang).
constexpr double kMaxPlanCoordinate = 1e7;

// Ring as given -> vertices without closing or consecutive repeated vertices; checks shape,
// finiteness, distinct vertices and area. Returns the signed area.
std::vector<Eigen::Vector2d> CleanRing(const RowMatrixXd& ring, const std::string& name,
                                       double* signed_area) {
  CheckArgument(ring.cols() == 2, name,
                "expected shape (M, 2), got (" + std::to_string(ring.rows()) + ", " +
                    std::to_string(ring.cols()) + ")");
  CheckFinite(ring, name);
  RequireAllInRange(ring, -kMaxPlanCoordinate, kMaxPlanCoordinate, name);
  std::vector<Eigen::Vector2d> v;
  v.reserve(static_cast<size_t>(ring.rows()));
  for (Eigen::Index r = 0; r < ring.rows(); ++r) {
    const Eigen::Vector2d p(ring(r, 0), ring(r, 1));
    if (v.empty() || p != v.back()) v.push_back(p);
  }
  while (v.size() > 1 && v.back() == v.front()) v.pop_back();
  // Distinct vertices (not only consecutive ones).
  std::vector<Eigen::Vector2d> sorted = v;
  std::sort(sorted.begin(), sorted.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]);
  });
  const size_t distinct = static_cast<size_t>(
      std::unique(sorted.begin(), sorted.end()) - sorted.begin());
  CheckArgument(distinct >= 3, name,
                "needs at least 3 distinct vertices, got " + std::to_string(distinct));
  // Collinear vertices enclose no area (exact test against the vertex farthest from v[0]).
  size_t far = 1;
  double far_d = 0.0;
  for (size_t k = 1; k < v.size(); ++k) {
    const double d = (v[k] - v[0]).squaredNorm();
    if (d > far_d) {
      far_d = d;
      far = k;
    }
  }
  bool collinear = true;
  for (size_t k = 1; k < v.size() && collinear; ++k) {
    collinear = Orient(v[0][0], v[0][1], v[far][0], v[far][1], v[k][0], v[k][1]) == 0;
  }
  CheckArgument(!collinear, name, "has zero area (all vertices lie on one line)");
  double area2 = 0.0;  // shoelace about v[0] (smaller rounding than about the origin)
  for (size_t k = 1; k + 1 < v.size(); ++k) {
    area2 += (v[k][0] - v[0][0]) * (v[k + 1][1] - v[0][1]) -
             (v[k + 1][0] - v[0][0]) * (v[k][1] - v[0][1]);
  }
  CheckArgument(area2 != 0.0, name, "has zero area");
  *signed_area = 0.5 * area2;
  return v;
}

RowMatrixXd ToMatrix(const std::vector<Eigen::Vector2d>& v) {
  RowMatrixXd m(static_cast<Eigen::Index>(v.size()), 2);
  for (size_t k = 0; k < v.size(); ++k) m.row(static_cast<Eigen::Index>(k)) = v[k].transpose();
  return m;
}

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
                                   sizeof(std::int32_t);
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

void CheckFloorIndex(const std::vector<FloorData>& floors, int floor_index, const char* name) {
  if (floor_index < 0 || floor_index >= static_cast<int>(floors.size())) {
    ThrowInvalidArgument(name, "floor index " + std::to_string(floor_index) +
                                   " out of range [0, " + std::to_string(floors.size()) + ")");
  }
}

// Checks a batch's floor indices (one per query, or a single one for all) and returns a
// function of the query index.
struct FloorIndices {
  const Eigen::Ref<const Eigen::VectorXi>& v;
  int operator()(Eigen::Index q) const { return v.size() == 1 ? v[0] : v[q]; }
};

void CheckBatch(const std::vector<FloorData>& floors, Eigen::Index queries,
                const Eigen::Ref<const Eigen::VectorXi>& floor_indices) {
  if (!(floor_indices.size() == queries || floor_indices.size() == 1)) {
    ThrowInvalidArgument("floor_indices", "expected one entry per query (" +
                                              std::to_string(queries) +
                                              ") or a single entry, got " +
                                              std::to_string(floor_indices.size()));
  }
  const int n = static_cast<int>(floors.size());
  for (Eigen::Index k = 0; k < floor_indices.size(); ++k) {
    if (floor_indices[k] < 0 || floor_indices[k] >= n) {
      ThrowInvalidArgument("floor_indices", DescribeEntry(k, 0, true) + " = " +
                                                std::to_string(floor_indices[k]) +
                                                " is out of range [0, " + std::to_string(n) + ")");
    }
  }
}

// Runs fn(begin, end) over fixed blocks of queries on up to num_threads threads. Every query's
// result depends on the query only, so the output does not depend on the thread count.
template <typename Fn>
void ForBlocks(Eigen::Index queries, int num_threads, const Fn& fn) {
  constexpr Eigen::Index kBlock = 2048;
  const Eigen::Index blocks = (queries + kBlock - 1) / kBlock;
  const int threads = ResolveThreadCount(num_threads);
  if (threads <= 1 || blocks <= 1) {
    fn(Eigen::Index{0}, queries);
    return;
  }
  ParallelForRuns(static_cast<int>(blocks), threads, 0, [&](int block, RandomStream&) {
    const Eigen::Index begin = block * kBlock;
    fn(begin, std::min(queries, begin + kBlock));
  });
}

}  // namespace

FloorPlan::FloorPlan(std::vector<FloorGeometry> floors, const FloorPlanOptions& options)
    : impl_(std::make_unique<Impl>()) {
  ValidateOptions(options);
  impl_->options = options;
  CheckArgument(!floors.empty(), "floors", "a floor plan needs at least one floor");
  for (size_t f = 0; f < floors.size(); ++f) {
    for (size_t g = 0; g < f; ++g) {
      if (floors[g].floor == floors[f].floor) {
        ThrowInvalidArgument("floors[" + std::to_string(f) + "].floor",
                             "floor number " + std::to_string(floors[f].floor) +
                                 " is repeated (also floors[" + std::to_string(g) + "])");
      }
    }
  }
  for (size_t f = 0; f < floors.size(); ++f) {
    impl_->floors.push_back(BuildFloor(floors[f], static_cast<int>(f), options));
    impl_->floor_numbers.push_back(floors[f].floor);
  }
}

FloorPlan::~FloorPlan() = default;
FloorPlan::FloorPlan(FloorPlan&&) noexcept = default;
FloorPlan& FloorPlan::operator=(FloorPlan&&) noexcept = default;

int FloorPlan::num_floors() const { return static_cast<int>(impl_->floors.size()); }

const std::vector<int>& FloorPlan::floors() const { return impl_->floor_numbers; }

int FloorPlan::FloorIndex(int floor) const {
  for (size_t f = 0; f < impl_->floor_numbers.size(); ++f) {
    if (impl_->floor_numbers[f] == floor) return static_cast<int>(f);
  }
  ThrowInvalidArgument("floor", "the floor plan has no floor number " + std::to_string(floor));
}

const FloorGeometry& FloorPlan::geometry(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  return impl_->floors[static_cast<size_t>(floor_index)].geometry;
}

int FloorPlan::num_edges(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  return static_cast<int>(impl_->floors[static_cast<size_t>(floor_index)].edges.size());
}

RowMatrixXd FloorPlan::Edges(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  const FloorData& d = impl_->floors[static_cast<size_t>(floor_index)];
  RowMatrixXd out(static_cast<Eigen::Index>(d.edges.size()), 4);
  for (size_t e = 0; e < d.edges.size(); ++e) {
    const Segment& g = d.edges[e];
    out.row(static_cast<Eigen::Index>(e)) << g.x0, g.y0, g.x1, g.y1;
  }
  return out;
}

Eigen::Vector4d FloorPlan::Bounds(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  return impl_->floors[static_cast<size_t>(floor_index)].bounds;
}

double FloorPlan::WalkableArea(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  return impl_->floors[static_cast<size_t>(floor_index)].walkable_area;
}

const FloorBuildStatistics& FloorPlan::BuildStatistics(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  return impl_->floors[static_cast<size_t>(floor_index)].statistics;
}

double FloorPlan::CellSize(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  return impl_->floors[static_cast<size_t>(floor_index)].h;
}

bool FloorPlan::IsWalkable(double x_m, double y_m, int floor_index) const {
  assert(floor_index >= 0 && floor_index < num_floors());
  return impl_->floors[static_cast<size_t>(floor_index)].IsWalkable(x_m, y_m);
}

bool FloorPlan::CrossesWall(double x0_m, double y0_m, double x1_m, double y1_m,
                            int floor_index) const {
  assert(floor_index >= 0 && floor_index < num_floors());
  return impl_->floors[static_cast<size_t>(floor_index)].CrossesWall(x0_m, y0_m, x1_m, y1_m);
}

double FloorPlan::DistanceToWall(double x_m, double y_m, int floor_index) const {
  assert(floor_index >= 0 && floor_index < num_floors());
  return impl_->floors[static_cast<size_t>(floor_index)].DistanceToWall(x_m, y_m);
}

VectorXb FloorPlan::IsWalkableBatch(const Eigen::Ref<const RowMatrixXd>& points_m,
                                    const Eigen::Ref<const Eigen::VectorXi>& floor_indices,
                                    int num_threads) const {
  CheckShape(points_m, -1, 2, "points_m");
  CheckFinite(points_m, "points_m");
  CheckBatch(impl_->floors, points_m.rows(), floor_indices);
  VectorXb out(points_m.rows());
  const FloorIndices floor_of{floor_indices};
  ForBlocks(points_m.rows(), num_threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index q = begin; q < end; ++q) {
      out[q] = impl_->floors[static_cast<size_t>(floor_of(q))].IsWalkable(points_m(q, 0),
                                                                           points_m(q, 1));
    }
  });
  return out;
}

VectorXb FloorPlan::CrossesWallBatch(const Eigen::Ref<const RowMatrixXd>& segments_m,
                                     const Eigen::Ref<const Eigen::VectorXi>& floor_indices,
                                     int num_threads) const {
  CheckShape(segments_m, -1, 4, "segments_m");
  CheckFinite(segments_m, "segments_m");
  CheckBatch(impl_->floors, segments_m.rows(), floor_indices);
  VectorXb out(segments_m.rows());
  const FloorIndices floor_of{floor_indices};
  ForBlocks(segments_m.rows(), num_threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index q = begin; q < end; ++q) {
      out[q] = impl_->floors[static_cast<size_t>(floor_of(q))].CrossesWall(
          segments_m(q, 0), segments_m(q, 1), segments_m(q, 2), segments_m(q, 3));
    }
  });
  return out;
}

Eigen::VectorXd FloorPlan::DistanceToWallBatch(const Eigen::Ref<const RowMatrixXd>& points_m,
                                               const Eigen::Ref<const Eigen::VectorXi>& floor_indices,
                                               int num_threads) const {
  CheckShape(points_m, -1, 2, "points_m");
  CheckFinite(points_m, "points_m");
  CheckBatch(impl_->floors, points_m.rows(), floor_indices);
  Eigen::VectorXd out(points_m.rows());
  const FloorIndices floor_of{floor_indices};
  ForBlocks(points_m.rows(), num_threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index q = begin; q < end; ++q) {
      out[q] = impl_->floors[static_cast<size_t>(floor_of(q))].DistanceToWall(points_m(q, 0),
                                                                               points_m(q, 1));
    }
  });
  return out;
}

RowMatrixXd FloorPlan::SampleWalkable(int n, int floor_index, RandomStream& rng) const {
  CheckArgument(n >= 0, "n", "must be >= 0, got " + std::to_string(n));
  RequireSizeLimit(static_cast<double>(n), 2.0 * sizeof(double), "n", "points");
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  const FloorData& d = impl_->floors[static_cast<size_t>(floor_index)];
  const double box_area = (d.bounds[2] - d.bounds[0]) * (d.bounds[3] - d.bounds[1]);
  const double fraction = d.walkable_area / box_area;
  if (!(fraction >= 1e-6)) {
    throw std::runtime_error("indoorloc: FloorPlan::SampleWalkable: the walkable area of floor " +
                             std::to_string(d.floor) + " is only " + FormatNumber(fraction) +
                             " of its bounding box; rejection sampling would not finish");
  }
  RowMatrixXd out(n, 2);
  // Far more attempts than needed (expected n / fraction); the limit only guards against an
  // area estimate that is far too large.
  const double max_attempts = 100.0 * (static_cast<double>(n) + 10.0) / fraction;
  double attempts = 0.0;
  for (int k = 0; k < n;) {
    const double x = rng.Uniform(d.bounds[0], d.bounds[2]);
    const double y = rng.Uniform(d.bounds[1], d.bounds[3]);
    if (d.IsWalkable(x, y)) {
      out(k, 0) = x;
      out(k, 1) = y;
      ++k;
    }
    // Up to 4 GB of points is allowed work: poll Ctrl-C every 2^20 draws.
    if ((static_cast<std::uint64_t>(attempts) & 0xFFFFF) == 0xFFFFF) CheckInterrupt();
    if (++attempts > max_attempts) {
      throw std::runtime_error("indoorloc: FloorPlan::SampleWalkable: too many rejected draws on "
                               "floor " + std::to_string(d.floor));
    }
  }
  return out;
}

std::string FloorPlan::Report() const {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  const Impl& s = *impl_;
  size_t edges = 0, cells = 0, entries = 0;
  double area = 0.0;
  for (const FloorData& d : s.floors) {
    edges += d.edges.size();
    cells += d.cells.size();
    entries += d.entries.size();
    area += d.walkable_area;
  }
  out << "FloorPlan: " << s.floors.size() << (s.floors.size() == 1 ? " floor" : " floors")
      << " (";
  for (size_t f = 0; f < s.floors.size(); ++f) out << (f ? ", " : "") << s.floors[f].floor;
  out << "), " << edges << " edges, " << cells << " cells (";
  out.precision(2);
  for (size_t f = 0; f < s.floors.size(); ++f) out << (f ? "/" : "") << s.floors[f].h;
  out << " m), " << static_cast<double>(entries) / static_cast<double>(std::max<size_t>(cells, 1))
      << " edges/cell, walkable area ";
  out.precision(1);
  out << area << " m^2";
  return out.str();
}

}  // namespace indoorloc::fusion
