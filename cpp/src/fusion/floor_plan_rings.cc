// Ring cleaning of the floor plan: the rings as given become vertex lists without closing or
// repeated vertices, checked for shape, finiteness and area (CleanRing), and are tested for
// self-intersection by an exact sweep line (FindRingSelfIntersection).
#include "floor_plan_index.h"

namespace indoorloc::fusion::floor_plan_internal {
namespace {

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
}  // namespace

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

}  // namespace indoorloc::fusion::floor_plan_internal
