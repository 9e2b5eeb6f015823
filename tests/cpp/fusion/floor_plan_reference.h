// Test helper of the floor plan tests: rings and wall rows written as lists, and the brute-force
// references the floor plan's answers are checked against (every edge tried, plain double
// orientation, crossing-number point in polygon).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <limits>

#include "indoorloc/fusion/floor_plan.h"

namespace indoorloc::fusion::floor_plan_reference {

inline RowMatrixXd Ring(std::initializer_list<std::array<double, 2>> vertices) {
  RowMatrixXd m(static_cast<Eigen::Index>(vertices.size()), 2);
  Eigen::Index r = 0;
  for (const auto& v : vertices) m.row(r++) << v[0], v[1];
  return m;
}

inline RowMatrixXd Box(double x0, double y0, double x1, double y1, bool clockwise = false) {
  return clockwise ? Ring({{x0, y0}, {x0, y1}, {x1, y1}, {x1, y0}})
                   : Ring({{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}});
}

inline RowMatrixXd Walls(std::initializer_list<std::array<double, 4>> rows) {
  RowMatrixXd m(static_cast<Eigen::Index>(rows.size()), 4);
  Eigen::Index r = 0;
  for (const auto& w : rows) m.row(r++) << w[0], w[1], w[2], w[3];
  return m;
}

// Orientation in plain double arithmetic: exact for the small integer (and half-integer)
// coordinates of the lattice tests, correct with probability one for random reals.
inline int NaiveOrient(double ax, double ay, double bx, double by, double cx, double cy) {
  const double d = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
  return (d > 0) - (d < 0);
}

inline bool NaiveIntersect(const Eigen::Vector4d& s, const Eigen::Vector4d& e) {
  const int o1 = NaiveOrient(s[0], s[1], s[2], s[3], e[0], e[1]);
  const int o2 = NaiveOrient(s[0], s[1], s[2], s[3], e[2], e[3]);
  const int o3 = NaiveOrient(e[0], e[1], e[2], e[3], s[0], s[1]);
  const int o4 = NaiveOrient(e[0], e[1], e[2], e[3], s[2], s[3]);
  if (o1 * o2 > 0 || o3 * o4 > 0) return false;
  if (o1 == 0 && o2 == 0) {
    return std::max(std::min(s[0], s[2]), std::min(e[0], e[2])) <=
               std::min(std::max(s[0], s[2]), std::max(e[0], e[2])) &&
           std::max(std::min(s[1], s[3]), std::min(e[1], e[3])) <=
               std::min(std::max(s[1], s[3]), std::max(e[1], e[3]));
  }
  return true;
}

// Crossing-number point-in-polygon (W. R. Franklin's pnpoly).
inline bool InRing(const RowMatrixXd& ring, double x, double y) {
  bool inside = false;
  const Eigen::Index n = ring.rows();
  for (Eigen::Index i = 0, j = n - 1; i < n; j = i++) {
    const double xi = ring(i, 0), yi = ring(i, 1), xj = ring(j, 0), yj = ring(j, 1);
    if ((yi > y) != (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi) inside = !inside;
  }
  return inside;
}

struct BruteForce {
  RowMatrixXd edges;
  FloorGeometry geometry;

  BruteForce(const FloorPlan& plan, int f) : edges(plan.Edges(f)), geometry(plan.geometry(f)) {}

  bool Crosses(const Eigen::Vector4d& s) const {
    for (Eigen::Index e = 0; e < edges.rows(); ++e) {
      if (NaiveIntersect(s, edges.row(e).transpose())) return true;
    }
    return false;
  }
  bool OnEdge(double x, double y) const { return Crosses(Eigen::Vector4d(x, y, x, y)); }
  bool Walkable(double x, double y) const {
    bool in_outline = false;
    for (const auto& r : geometry.outlines) in_outline = in_outline || InRing(r, x, y);
    if (!in_outline) return false;
    for (const auto& r : geometry.obstacles) {
      if (InRing(r, x, y)) return false;
    }
    return true;
  }
  double Distance(double x, double y) const {
    double best = std::numeric_limits<double>::infinity();
    for (Eigen::Index e = 0; e < edges.rows(); ++e) {
      const double ux = edges(e, 2) - edges(e, 0), uy = edges(e, 3) - edges(e, 1);
      const double wx = x - edges(e, 0), wy = y - edges(e, 1);
      const double t = std::clamp((wx * ux + wy * uy) / (ux * ux + uy * uy), 0.0, 1.0);
      best = std::min(best, std::hypot(wx - t * ux, wy - t * uy));
    }
    return best;
  }
};

}  // namespace indoorloc::fusion::floor_plan_reference
