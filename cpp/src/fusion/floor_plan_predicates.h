// Exact geometric predicates of the floor plan: the orientation sign (Shewchuk's orient2d with an
// exact expansion fallback), segment intersection, signed ring crossings, the filtered segment
// query and the point-segment distance. Private to cpp/src/fusion (floor_plan*.cc); every file
// that includes it is compiled with -ffp-contract=off (cpp/CMakeLists.txt): the error terms
// assume each product is rounded on its own.
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

namespace indoorloc::fusion::floor_plan_internal {

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
inline int ExactSumSign(const double* terms, int n) {
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

[[gnu::noinline]] inline int ExactOrient(double ax, double ay, double bx, double by, double cx,
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
inline bool SegmentsIntersect(double px, double py, double qx, double qy, const Segment& e) {
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
inline int SignedCrossing(double ax, double ay, double px, double py, const Segment& e, bool closed) {
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

inline double PointSegmentDistanceSq(double x, double y, const Segment& e) {
  const double ux = e.x1 - e.x0, uy = e.y1 - e.y0;
  const double wx = x - e.x0, wy = y - e.y0;
  const double len_sq = ux * ux + uy * uy;
  double t = (wx * ux + wy * uy) / len_sq;
  t = std::clamp(t, 0.0, 1.0);
  const double rx = wx - t * ux, ry = wy - t * uy;
  return rx * rx + ry * ry;
}

}  // namespace indoorloc::fusion::floor_plan_internal
