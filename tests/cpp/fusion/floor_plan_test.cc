#include "indoorloc/fusion/floor_plan.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "expect_invalid.h"

#include "indoorloc/core/random.h"

namespace indoorloc::fusion {
namespace {

RowMatrixXd Ring(std::initializer_list<std::array<double, 2>> vertices) {
  RowMatrixXd m(static_cast<Eigen::Index>(vertices.size()), 2);
  Eigen::Index r = 0;
  for (const auto& v : vertices) m.row(r++) << v[0], v[1];
  return m;
}

RowMatrixXd Box(double x0, double y0, double x1, double y1, bool clockwise = false) {
  return clockwise ? Ring({{x0, y0}, {x0, y1}, {x1, y1}, {x1, y0}})
                   : Ring({{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}});
}

RowMatrixXd Walls(std::initializer_list<std::array<double, 4>> rows) {
  RowMatrixXd m(static_cast<Eigen::Index>(rows.size()), 4);
  Eigen::Index r = 0;
  for (const auto& w : rows) m.row(r++) << w[0], w[1], w[2], w[3];
  return m;
}

FloorGeometry SquareWithHole() {
  FloorGeometry g;
  g.floor = 2;
  g.outlines.push_back(Box(0, 0, 10, 10, /*clockwise=*/true));  // orientation is normalised
  g.obstacles.push_back(Box(4, 4, 6, 6));
  return g;
}


// ---- brute-force references ---------------------------------------------------------------

// Orientation in plain double arithmetic: exact for the small integer (and half-integer)
// coordinates of the lattice tests, correct with probability one for random reals.
int NaiveOrient(double ax, double ay, double bx, double by, double cx, double cy) {
  const double d = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
  return (d > 0) - (d < 0);
}

bool NaiveIntersect(const Eigen::Vector4d& s, const Eigen::Vector4d& e) {
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
bool InRing(const RowMatrixXd& ring, double x, double y) {
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

// A plan with many edges: a 200 x 100 m outline, `polygons` random convex polygons (overlapping
// each other and the outline's border) and `walls` random wall segments.
FloorGeometry RandomPlan(int polygons, int walls, std::uint64_t seed) {
  RandomStream rng(seed);
  FloorGeometry g;
  g.outlines.push_back(Box(0, 0, 200, 100));
  for (int k = 0; k < polygons; ++k) {
    const double cx = rng.Uniform(-2, 202), cy = rng.Uniform(-2, 102), r = rng.Uniform(0.3, 3);
    const int n = 3 + static_cast<int>(rng.UniformInt(6));
    std::vector<double> angles(static_cast<size_t>(n));
    for (double& a : angles) a = rng.Uniform(0, 2 * M_PI);
    std::sort(angles.begin(), angles.end());
    RowMatrixXd ring(n, 2);
    for (int m = 0; m < n; ++m) {
      ring.row(m) << cx + r * std::cos(angles[static_cast<size_t>(m)]),
          cy + r * std::sin(angles[static_cast<size_t>(m)]);
    }
    if (k % 2 == 1) ring = ring.colwise().reverse().eval();  // both orientations
    g.obstacles.push_back(ring);
  }
  g.walls.resize(walls, 4);
  for (int w = 0; w < walls; ++w) {
    const double x = rng.Uniform(0, 200), y = rng.Uniform(0, 100), a = rng.Uniform(0, 2 * M_PI);
    const double len = rng.Uniform(0.5, 8);
    g.walls.row(w) << x, y, x + len * std::cos(a), y + len * std::sin(a);
  }
  return g;
}

// ---- hand-made cases ----------------------------------------------------------------------

TEST(FloorPlan, SquareWithAHole) {
  FloorPlan plan({SquareWithHole()});
  EXPECT_EQ(plan.num_floors(), 1);
  EXPECT_EQ(plan.FloorIndex(2), 0);
  EXPECT_EQ(plan.num_edges(0), 8);
  EXPECT_NEAR(plan.WalkableArea(0), 96.0, 1e-9);
  EXPECT_EQ(plan.Bounds(0), Eigen::Vector4d(0, 0, 10, 10));
  // Walkability.
  EXPECT_TRUE(plan.IsWalkable(1, 1, 0));
  EXPECT_TRUE(plan.IsWalkable(9.99, 5, 0));
  EXPECT_FALSE(plan.IsWalkable(5, 5, 0));
  EXPECT_FALSE(plan.IsWalkable(-1, 5, 0));
  EXPECT_FALSE(plan.IsWalkable(10.01, 5, 0));
  EXPECT_FALSE(plan.IsWalkable(1e9, -1e9, 0));
  // Wall crossings.
  EXPECT_FALSE(plan.CrossesWall(1, 1, 2, 2, 0));
  EXPECT_TRUE(plan.CrossesWall(1, 5, 9, 5, 0));    // through the hole
  EXPECT_TRUE(plan.CrossesWall(1, 1, 11, 1, 0));   // out of the outline
  EXPECT_TRUE(plan.CrossesWall(-5, 5, 15, 5, 0));  // from outside to outside through everything
  EXPECT_FALSE(plan.CrossesWall(-5, -5, 15, -5, 0));  // outside, passes no wall
  EXPECT_FALSE(plan.CrossesWall(3, 3, 3, 3, 0));      // a point step
  // Touching counts as crossing: ending on an edge, at a vertex, sliding along an edge.
  EXPECT_TRUE(plan.CrossesWall(1, 5, 4, 5, 0));
  EXPECT_TRUE(plan.CrossesWall(3, 3, 4, 4, 0));
  EXPECT_TRUE(plan.CrossesWall(3, 4, 5, 4, 0));
  EXPECT_TRUE(plan.CrossesWall(4, 5, 4, 5, 0));   // a point on an edge
  EXPECT_FALSE(plan.CrossesWall(1, 4, 3.9, 4, 0));  // on the edge's line, short of it
  EXPECT_TRUE(plan.CrossesWall(2, 6, 6, 2, 0));     // through the hole's corner (4, 4)
  // Distances.
  EXPECT_NEAR(plan.DistanceToWall(2, 2, 0), 2.0, 1e-12);
  EXPECT_NEAR(plan.DistanceToWall(5, 3, 0), 1.0, 1e-12);
  EXPECT_NEAR(plan.DistanceToWall(3, 3, 0), std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(plan.DistanceToWall(-3, 14, 0), 5.0, 1e-12);  // outside: to the corner (0, 10)
  // The stored geometry keeps the given orientation, without a closing vertex.
  EXPECT_EQ(plan.geometry(0).outlines[0].rows(), 4);
  EXPECT_EQ(plan.geometry(0).outlines[0], Box(0, 0, 10, 10, true));
  EXPECT_NE(plan.Report().find("8 edges"), std::string::npos) << plan.Report();
}

TEST(FloorPlan, AThinWall) {
  FloorGeometry g;
  g.outlines.push_back(Box(0, 0, 10, 10));
  g.walls = Walls({{5, 0, 5, 8}});
  FloorPlan plan({g});
  EXPECT_EQ(plan.num_edges(0), 5);
  EXPECT_TRUE(plan.CrossesWall(4, 1, 6, 1, 0));
  EXPECT_TRUE(plan.CrossesWall(4.9, 7.99, 5.1, 7.99, 0));
  EXPECT_FALSE(plan.CrossesWall(4, 9, 6, 9, 0));       // around its end
  EXPECT_TRUE(plan.CrossesWall(4, 8, 6, 8, 0));        // touches its end point
  EXPECT_FALSE(plan.CrossesWall(4, 8.001, 6, 8.001, 0));
  EXPECT_TRUE(plan.CrossesWall(5, 9, 5, 7, 0));        // along it, overlapping
  EXPECT_FALSE(plan.CrossesWall(5, 9, 5, 8.5, 0));     // along its line, short of it
  // A wall does not change walkability; the distance to it counts.
  EXPECT_TRUE(plan.IsWalkable(5.0001, 1, 0));
  EXPECT_NEAR(plan.DistanceToWall(5.25, 4, 0), 0.25, 1e-12);
  EXPECT_NEAR(plan.WalkableArea(0), 100.0, 1e-9);
}

TEST(FloorPlan, OverlappingRingsUseUnionSemantics) {
  FloorGeometry g;
  g.outlines.push_back(Box(0, 0, 6, 4));
  g.outlines.push_back(Box(4, 0, 10, 4, true));
  g.obstacles.push_back(Box(1, 1, 3, 3));
  g.obstacles.push_back(Box(2, 2, 5, 3.5, true));
  FloorPlan plan({g});
  EXPECT_TRUE(plan.IsWalkable(5, 0.5, 0));   // in both outlines
  EXPECT_TRUE(plan.IsWalkable(8, 2, 0));
  EXPECT_FALSE(plan.IsWalkable(2.5, 2.5, 0));  // in both obstacles
  EXPECT_FALSE(plan.IsWalkable(1.5, 1.5, 0));
  EXPECT_FALSE(plan.IsWalkable(4.5, 3.2, 0));
  EXPECT_TRUE(plan.IsWalkable(4.5, 1.5, 0));
  // Union: 40 m^2 of outlines; obstacles 4 + 4.5 - overlap 1 x 1 = 7.5.
  EXPECT_NEAR(plan.WalkableArea(0), 40.0 - 7.5, 1e-9);
  // Walls inside an overlap are walls all the same.
  EXPECT_TRUE(plan.CrossesWall(3.5, 2, 4.5, 2, 0));
}

TEST(FloorPlan, ObstacleCoveringTheOutlineBorderAndHolesInHoles) {
  FloorGeometry g;
  g.outlines.push_back(Box(0, 0, 10, 10));
  g.obstacles.push_back(Box(-1, -1, 3, 3));  // sticks out of the outline
  g.outlines.push_back(Box(20, 0, 30, 10));  // a second, separate outline
  FloorPlan plan({g});
  EXPECT_FALSE(plan.IsWalkable(1, 1, 0));
  EXPECT_FALSE(plan.IsWalkable(-0.5, -0.5, 0));
  EXPECT_TRUE(plan.IsWalkable(25, 5, 0));
  EXPECT_FALSE(plan.IsWalkable(15, 5, 0));
  EXPECT_NEAR(plan.WalkableArea(0), 200.0 - 9.0, 1e-9);
  // Horizontal edges between the scanlines of a fixed spacing: the area stays exact.
  FloorGeometry h;
  h.outlines.push_back(Box(0, 0, 40, 30));
  h.obstacles.push_back(Box(18, 12, 22, 16));
  h.obstacles.push_back(Box(30, 20.003, 36, 28.001));
  EXPECT_NEAR(FloorPlan({h}).WalkableArea(0), 1200.0 - 16.0 - 6 * 7.998, 1e-9);
}

TEST(FloorPlan, TriangleAndCircleAreas) {
  FloorGeometry g;
  g.outlines.push_back(Ring({{0, 0}, {10, 0}, {0, 10}, {0, 0}}));  // closing vertex repeated
  FloorPlan tri({g});
  EXPECT_EQ(tri.geometry(0).outlines[0].rows(), 3);
  EXPECT_NEAR(tri.WalkableArea(0), 50.0, 1e-3);
  FloorGeometry c;
  const int n = 720;
  RowMatrixXd ring(n, 2);
  for (int k = 0; k < n; ++k) ring.row(k) << 5 * std::cos(2 * M_PI * k / n), 5 * std::sin(2 * M_PI * k / n);
  c.outlines.push_back(ring);
  FloorPlan circle({c});
  const double polygon_area = 0.5 * n * 25 * std::sin(2 * M_PI / n);
  EXPECT_NEAR(circle.WalkableArea(0), polygon_area, 1e-4 * polygon_area);
}

TEST(FloorPlan, MultiFloorQueriesUseTheirOwnFloor) {
  FloorGeometry a = SquareWithHole();
  a.floor = 3;
  FloorGeometry b;
  b.floor = 7;
  b.outlines.push_back(Box(0, 0, 4, 4));
  b.walls = Walls({{2, 0, 2, 3}});
  FloorPlan plan({a, b});
  EXPECT_EQ(plan.num_floors(), 2);
  EXPECT_EQ(plan.floors(), std::vector<int>({3, 7}));
  EXPECT_EQ(plan.FloorIndex(7), 1);
  ExpectInvalid([&] { plan.FloorIndex(4); }, {"floor", "no floor number 4"});
  EXPECT_TRUE(plan.IsWalkable(5, 1, 0));
  EXPECT_FALSE(plan.IsWalkable(5, 1, 1));
  EXPECT_FALSE(plan.IsWalkable(5, 5, 0));
  EXPECT_TRUE(plan.IsWalkable(3, 3, 1));
  RowMatrixXd pts(3, 2);
  pts << 5, 5, 3, 3, 1, 1;
  Eigen::VectorXi floors(3);
  floors << 0, 1, 1;
  const VectorXb w = plan.IsWalkableBatch(pts, floors);
  EXPECT_FALSE(w[0]);
  EXPECT_TRUE(w[1]);
  EXPECT_TRUE(w[2]);
  RowMatrixXd segs(2, 4);
  segs << 1, 1, 3, 1, 1, 3.5, 3, 3.5;
  Eigen::VectorXi one(1);
  one << 1;
  const VectorXb c = plan.CrossesWallBatch(segs, one);  // one floor index for all queries
  EXPECT_TRUE(c[0]);
  EXPECT_FALSE(c[1]);
  const Eigen::VectorXd d = plan.DistanceToWallBatch(pts, floors);
  EXPECT_NEAR(d[0], 1.0, 1e-12);
  EXPECT_NEAR(d[1], 1.0, 1e-12);
  EXPECT_NEAR(d[2], 1.0, 1e-12);
  EXPECT_NEAR(plan.WalkableArea(1), 16.0, 1e-9);
}

// ---- exactness on degenerate inputs -------------------------------------------------------

TEST(FloorPlan, OrientationIsExactWhereDoubleArithmeticFails) {
  // Kettner et al.'s classroom example: points within a few ulps of the line y = x, with the
  // wall's ends far away, so that the differences taken by a naive test are rounded. The step
  // from p to (1.5, -0.5) meets the wall iff p lies on or above the line, i.e. iff j >= i.
  FloorGeometry g;
  g.outlines.push_back(Box(-20, -20, 20, 20));
  g.walls = Walls({{12, 12, -12, -12}});
  FloorPlan plan({g});
  const double u = std::ldexp(1.0, -53);
  int naive_wrong = 0;
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 40; ++j) {
      const double px = 0.5 + i * u, py = 0.5 + j * u;
      EXPECT_EQ(plan.CrossesWall(px, py, 1.5, -0.5, 0), j >= i) << i << " " << j;
      const int naive = NaiveOrient(12, 12, -12, -12, px, py);
      if (naive != (j > i ? -1 : (j < i ? 1 : 0))) ++naive_wrong;
    }
  }
  EXPECT_GT(naive_wrong, 0);  // the example does defeat plain double arithmetic
}

// Integer vertices and half-integer queries: segments through vertices, points on the lines of
// edges and collinear overlaps happen all the time. The index must agree with an exact
// brute force (plain doubles are exact on such small numbers).
TEST(FloorPlan, LatticePlanMatchesExactBruteForceOnDegenerateQueries) {
  RandomStream rng(11);
  FloorGeometry g;
  g.outlines.push_back(Box(0, 0, 40, 30));
  g.outlines.push_back(Box(38, 10, 50, 20));
  for (int k = 0; k < 60; ++k) {
    const double x = static_cast<double>(rng.UniformInt(44)), y = static_cast<double>(rng.UniformInt(28));
    const double w = 1.0 + static_cast<double>(rng.UniformInt(5)), h = 1.0 + static_cast<double>(rng.UniformInt(5));
    g.obstacles.push_back(Box(x, y, x + w, y + h, k % 3 == 0));
  }
  for (int k = 0; k < 40; ++k) {
    Eigen::Vector2d a, b, c;
    do {
      a << static_cast<double>(rng.UniformInt(48)), static_cast<double>(rng.UniformInt(30));
      b = a + Eigen::Vector2d(static_cast<double>(rng.UniformInt(7)) - 3.0, static_cast<double>(rng.UniformInt(7)) - 3.0);
      c = a + Eigen::Vector2d(static_cast<double>(rng.UniformInt(7)) - 3.0, static_cast<double>(rng.UniformInt(7)) - 3.0);
    } while (NaiveOrient(a[0], a[1], b[0], b[1], c[0], c[1]) == 0);
    g.obstacles.push_back(Ring({{a[0], a[1]}, {b[0], b[1]}, {c[0], c[1]}}));
  }
  RowMatrixXd walls(30, 4);
  for (int k = 0; k < 30; ++k) {
    double x0, y0, x1, y1;
    do {
      x0 = static_cast<double>(rng.UniformInt(50));
      y0 = static_cast<double>(rng.UniformInt(30));
      x1 = static_cast<double>(rng.UniformInt(50));
      y1 = static_cast<double>(rng.UniformInt(30));
    } while (x0 == x1 && y0 == y1);
    walls.row(k) << x0, y0, x1, y1;
  }
  g.walls = walls;
  for (double cell : {0.0, 1.0, 2.0, 0.5, 3.0, 7.0}) {
    FloorPlanOptions options;
    options.cell_size_m = cell;
    FloorPlan plan({g}, options);
    const BruteForce brute(plan, 0);
    int on_edge = 0, walkable = 0, crossing = 0;
    for (int q = 0; q < 4000; ++q) {
      const double x = 0.5 * static_cast<double>(rng.UniformInt(106)) - 1.0;
      const double y = 0.5 * static_cast<double>(rng.UniformInt(66)) - 1.0;
      if (brute.OnEdge(x, y)) {
        ++on_edge;  // the boundary itself: either answer is allowed
      } else {
        const bool expected = brute.Walkable(x, y);
        walkable += expected;
        ASSERT_EQ(plan.IsWalkable(x, y, 0), expected) << "cell " << cell << " at " << x << ", " << y;
      }
      const Eigen::Vector4d s(x, y, x + 0.5 * (static_cast<double>(rng.UniformInt(13)) - 6.0),
                              y + 0.5 * (static_cast<double>(rng.UniformInt(13)) - 6.0));
      const bool expected_cross = brute.Crosses(s);
      crossing += expected_cross;
      ASSERT_EQ(plan.CrossesWall(s[0], s[1], s[2], s[3], 0), expected_cross)
          << "cell " << cell << " segment " << s.transpose();
      ASSERT_NEAR(plan.DistanceToWall(x, y, 0), brute.Distance(x, y), 1e-12);
    }
    EXPECT_GT(on_edge, 100);
    EXPECT_GT(walkable, 500);
    EXPECT_GT(crossing, 500);
  }
}

// ---- random plans against brute force -----------------------------------------------------

TEST(FloorPlan, RandomPlanWithManyEdgesMatchesBruteForce) {
  const FloorGeometry g = RandomPlan(1500, 1000, 5);
  FloorPlan plan({g}, FloorPlanOptions());
  ASSERT_GT(plan.num_edges(0), 9000);
  const BruteForce brute(plan, 0);
  RandomStream rng(6);
  int crossings = 0, walkable = 0;
  for (int q = 0; q < 3000; ++q) {
    const double x = rng.Uniform(-10, 210), y = rng.Uniform(-10, 110);
    const double len = q % 10 == 0 ? rng.Uniform(0, 60) : rng.Uniform(0, 2);
    const double a = rng.Uniform(0, 2 * M_PI);
    const Eigen::Vector4d s(x, y, x + len * std::cos(a), y + len * std::sin(a));
    const bool expected = brute.Crosses(s);
    crossings += expected;
    ASSERT_EQ(plan.CrossesWall(s[0], s[1], s[2], s[3], 0), expected) << s.transpose();
    const bool w = brute.Walkable(x, y);
    walkable += w;
    ASSERT_EQ(plan.IsWalkable(x, y, 0), w) << x << ", " << y;
    ASSERT_DOUBLE_EQ(plan.DistanceToWall(x, y, 0), brute.Distance(x, y)) << x << ", " << y;
  }
  EXPECT_GT(crossings, 300);
  EXPECT_GT(walkable, 300);
  // Other cell sizes (many cells per step; one cell for many edges) give the same answers.
  for (double cell : {0.25, 1.7, 25.0}) {
    FloorPlanOptions options;
    options.cell_size_m = cell;
    FloorPlan other({g}, options);
    EXPECT_DOUBLE_EQ(other.CellSize(0), cell);
    RandomStream r2(7);
    for (int q = 0; q < 2000; ++q) {
      const double x = r2.Uniform(-10, 210), y = r2.Uniform(-10, 110);
      const double len = r2.Uniform(0, 30), a = r2.Uniform(0, 2 * M_PI);
      const double x1 = x + len * std::cos(a), y1 = y + len * std::sin(a);
      ASSERT_EQ(other.CrossesWall(x, y, x1, y1, 0), plan.CrossesWall(x, y, x1, y1, 0));
      ASSERT_EQ(other.IsWalkable(x, y, 0), plan.IsWalkable(x, y, 0));
      ASSERT_DOUBLE_EQ(other.DistanceToWall(x, y, 0), plan.DistanceToWall(x, y, 0));
    }
  }
}

TEST(FloorPlan, DistanceInASparseHallSkipsEmptyRings) {
  FloorGeometry g;
  g.outlines.push_back(Box(0, 0, 300, 200));
  g.walls = Walls({{150, 100, 151, 101}, {20, 180, 20, 181}});
  FloorPlan plan({g});
  EXPECT_DOUBLE_EQ(plan.CellSize(0), 1.0);
  const BruteForce brute(plan, 0);
  RandomStream rng(21);
  for (int q = 0; q < 500; ++q) {
    const double x = rng.Uniform(-50, 350), y = rng.Uniform(-50, 250);
    ASSERT_DOUBLE_EQ(plan.DistanceToWall(x, y, 0), brute.Distance(x, y)) << x << ", " << y;
  }
}

TEST(FloorPlan, WalkableAreaMatchesPointCounting) {
  const FloorGeometry g = RandomPlan(400, 0, 8);
  FloorPlan plan({g});
  // Count walkable points of a fine lattice (IsWalkable is checked against brute force above).
  const int nx = 2000, ny = 1000;
  long count = 0;
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      count += plan.IsWalkable((i + 0.5) * 200.0 / nx, (j + 0.5) * 100.0 / ny, 0);
    }
  }
  const double counted = static_cast<double>(count) * 200.0 * 100.0 / (nx * ny);
  EXPECT_NEAR(plan.WalkableArea(0), counted, 0.002 * counted);
}

TEST(FloorPlan, BatchResultsDoNotDependOnTheThreadCount) {
  FloorPlan plan({RandomPlan(300, 200, 9)});
  RandomStream rng(10);
  const int q = 20000;
  RowMatrixXd pts(q, 2), segs(q, 4);
  for (int k = 0; k < q; ++k) {
    const double x = rng.Uniform(0, 200), y = rng.Uniform(0, 100), a = rng.Uniform(0, 6.3);
    pts.row(k) << x, y;
    segs.row(k) << x, y, x + 0.7 * std::cos(a), y + 0.7 * std::sin(a);
  }
  const Eigen::VectorXi floor = Eigen::VectorXi::Zero(1);
  const VectorXb w1 = plan.IsWalkableBatch(pts, floor, 1);
  const VectorXb c1 = plan.CrossesWallBatch(segs, floor, 1);
  const Eigen::VectorXd d1 = plan.DistanceToWallBatch(pts, floor, 1);
  for (int threads : {2, 3, 0}) {
    EXPECT_EQ(plan.IsWalkableBatch(pts, floor, threads), w1);
    EXPECT_EQ(plan.CrossesWallBatch(segs, floor, threads), c1);
    EXPECT_EQ(plan.DistanceToWallBatch(pts, floor, threads), d1);
  }
  for (int k = 0; k < q; k += 97) {
    EXPECT_EQ(w1[k], plan.IsWalkable(pts(k, 0), pts(k, 1), 0));
    EXPECT_EQ(c1[k], plan.CrossesWall(segs(k, 0), segs(k, 1), segs(k, 2), segs(k, 3), 0));
    EXPECT_EQ(d1[k], plan.DistanceToWall(pts(k, 0), pts(k, 1), 0));
  }
}

TEST(FloorPlan, SampleWalkableDrawsWalkablePointsReproducibly) {
  FloorPlan plan({RandomPlan(300, 0, 12)});
  RandomStream a(3), b(3);
  const RowMatrixXd s = plan.SampleWalkable(5000, 0, a);
  ASSERT_EQ(s.rows(), 5000);
  EXPECT_EQ(s, plan.SampleWalkable(5000, 0, b));
  const VectorXb w = plan.IsWalkableBatch(s, Eigen::VectorXi::Zero(1));
  EXPECT_TRUE(w.all());
  // Uniform over the walkable area: the two halves of the box get shares near their areas.
  EXPECT_GT(s.col(0).minCoeff(), 0.0);
  EXPECT_LT(s.col(0).maxCoeff(), 200.0);
  EXPECT_EQ(plan.SampleWalkable(0, 0, a).rows(), 0);
  ExpectInvalid([&] { plan.SampleWalkable(-1, 0, a); }, {"'n'"});
  ExpectInvalid([&] { plan.SampleWalkable(3, 1, a); }, {"floor_index"});
  // A walkable fraction of the box below 1e-6 is refused.
  FloorGeometry corners;  // two 0.5 m squares at opposite corners of a 1 km box
  corners.outlines.push_back(Box(0, 0, 0.5, 0.5));
  corners.outlines.push_back(Box(999.5, 999.5, 1000, 1000));
  FloorPlan thin({corners});
  EXPECT_NEAR(thin.WalkableArea(0), 0.5, 1e-9);
  EXPECT_THROW(thin.SampleWalkable(1, 0, a), std::runtime_error);
}

// ---- validation ---------------------------------------------------------------------------

TEST(FloorPlan, BadInputGivesClearErrors) {
  auto build = [](std::vector<FloorGeometry> floors, FloorPlanOptions options = FloorPlanOptions()) {
    FloorPlan plan(std::move(floors), options);
  };
  ExpectInvalid([&] { build({}); }, {"'floors'", "at least one floor"});
  FloorGeometry ok = SquareWithHole();
  ExpectInvalid([&] { build({ok, ok}); }, {"floors[1].floor", "repeated"});
  FloorGeometry g = ok;
  g.outlines.clear();
  ExpectInvalid([&] { build({g}); }, {"floors[0].outlines", "at least one outline"});
  g = ok;
  g.floor = 5;
  g.obstacles.push_back(Box(1, 1, 2, 2));
  g.obstacles.push_back(Ring({{1, 1}, {2, 2}, {1, 1}, {2, 2}}));
  ExpectInvalid([&] { build({ok, g}); }, {"floors[1].obstacles[2]", "3 distinct vertices, got 2"});
  g = ok;
  g.obstacles.push_back(Ring({{1, 1}, {2, 2}, {3, 3}}));
  ExpectInvalid([&] { build({g}); }, {"floors[0].obstacles[1]", "zero area"});
  g = ok;
  g.outlines[0](2, 1) = std::nan("");
  ExpectInvalid([&] { build({g}); }, {"floors[0].outlines[0]", "NaN"});
  g = ok;
  g.obstacles.push_back(RowMatrixXd::Ones(4, 3));
  ExpectInvalid([&] { build({g}); }, {"floors[0].obstacles[1]", "shape (M, 2)"});
  g = ok;
  g.walls = Walls({{1, 1, 2, 2}, {1, 1, INFINITY, 2}});
  ExpectInvalid([&] { build({g}); }, {"floors[0].walls", "infinite"});
  g.walls = Walls({{1, 1, 2, 2}, {3, 3, 3, 3}});
  ExpectInvalid([&] { build({g}); }, {"floors[0].walls", "row 1 has zero length"});
  g.walls = RowMatrixXd::Ones(2, 3);
  ExpectInvalid([&] { build({g}); }, {"floors[0].walls", "(W, 4)"});
  // Self-intersections: a bow tie, a ring folding back on itself, a ring pinched at a vertex.
  g = ok;
  g.obstacles.push_back(Ring({{1, 1}, {3, 3}, {3, 1}, {1, 2}}));
  ExpectInvalid([&] { build({g}); }, {"floors[0].obstacles[1]", "self-intersecting"});
  FloorPlanOptions unchecked;
  unchecked.check_self_intersection = false;
  EXPECT_NO_THROW(build({g}, unchecked));
  g = ok;
  g.obstacles.push_back(Ring({{1, 1}, {3, 1}, {2, 1}, {2, 3}}));
  ExpectInvalid([&] { build({g}); }, {"floors[0].obstacles[1]", "self-intersecting"});
  g = ok;
  g.outlines[0] = Ring({{0, 0}, {2, 0}, {1, 1}, {2, 2}, {0, 2}, {1, 1}});
  ExpectInvalid([&] { build({g}); }, {"floors[0].outlines[0]", "self-intersecting"});
  // A long ring through many cells crossing itself far from its start.
  g = ok;
  g.outlines[0] = Ring({{0, 0}, {100, 0}, {100, 10}, {50, 10}, {50, -5}, {40, -5}, {40, 10}, {0, 10}});
  ExpectInvalid([&] { build({g}); }, {"floors[0].outlines[0]", "self-intersecting"});
  // No walkable area.
  g = ok;
  g.obstacles.push_back(Box(-1, -1, 11, 11));
  ExpectInvalid([&] { build({g}); }, {"floors[0]", "no walkable area"});
  // Options.
  FloorPlanOptions bad;
  bad.target_edges_per_cell = 0;
  ExpectInvalid([&] { build({ok}, bad); }, {"options", "target_edges_per_cell"});
  bad = FloorPlanOptions();
  bad.max_cells = 0;
  ExpectInvalid([&] { build({ok}, bad); }, {"options", "max_cells"});
  bad = FloorPlanOptions();
  bad.cell_size_m = 1e-4;
  ExpectInvalid([&] { build({ok}, bad); }, {"options.cell_size_m", "max_cells"});
  bad.cell_size_m = NAN;
  ExpectInvalid([&] { build({ok}, bad); }, {"options", "cell_size_m"});
  // The automatic cell size respects max_cells.
  bad = FloorPlanOptions();
  bad.max_cells = 10;
  FloorPlan coarse({ok}, bad);
  EXPECT_GE(coarse.CellSize(0), 10.0 / 3.0);
  EXPECT_TRUE(coarse.CrossesWall(1, 5, 9, 5, 0));
}

TEST(FloorPlan, BatchArgumentsAreChecked) {
  FloorPlan plan({SquareWithHole()});
  const Eigen::VectorXi zero = Eigen::VectorXi::Zero(1);
  ExpectInvalid([&] { plan.IsWalkableBatch(RowMatrixXd::Zero(3, 3), zero); }, {"points_m", "(any, 2)"});
  ExpectInvalid([&] { plan.CrossesWallBatch(RowMatrixXd::Zero(3, 2), zero); }, {"segments_m", "(any, 4)"});
  RowMatrixXd pts = RowMatrixXd::Ones(3, 2);
  pts(1, 0) = NAN;
  ExpectInvalid([&] { plan.DistanceToWallBatch(pts, zero); }, {"points_m", "entry (1, 0) is NaN"});
  pts(1, 0) = 1;
  Eigen::VectorXi bad_floor(3);
  bad_floor << 0, 1, 0;
  ExpectInvalid([&] { plan.IsWalkableBatch(pts, bad_floor); }, {"floor_indices", "entry 1 = 1", "out of range"});
  ExpectInvalid([&] { plan.IsWalkableBatch(pts, Eigen::VectorXi::Zero(2)); }, {"floor_indices", "one entry per query"});
  EXPECT_EQ(plan.IsWalkableBatch(RowMatrixXd::Zero(0, 2), zero).size(), 0);
  ExpectInvalid([&] { plan.Edges(-1); }, {"floor_index"});
  ExpectInvalid([&] { plan.geometry(1); }, {"floor_index"});
}

// ---- Issue 28: construction cost and memory bounds ---------------------------------------

// A comb of `teeth` teeth within 1 m (x in [0, 1], teeth 0.9 m tall): about 4 edges per tooth,
// thousands of edges per cell. The old per-cell self-intersection test was quadratic in them.
RowMatrixXd Comb(int teeth) {
  const double w = 1.0 / (2.0 * teeth);
  std::vector<std::array<double, 2>> pts{{0.0, 0.0}};
  for (int t = 0; t < teeth; ++t) {
    const double x0 = 2 * t * w, x1 = (2 * t + 1) * w;
    if (t > 0) pts.push_back({x0, 0.1});
    pts.push_back({x0, 1.0});
    pts.push_back({x1, 1.0});
    pts.push_back({x1, 0.1});
  }
  pts.push_back({1.0, 0.1});
  pts.push_back({1.0, 0.0});
  RowMatrixXd m(static_cast<Eigen::Index>(pts.size()), 2);
  for (size_t k = 0; k < pts.size(); ++k) m.row(static_cast<Eigen::Index>(k)) << pts[k][0], pts[k][1];
  return m;
}

// A star of n vertices alternating between radii r_out and r_in: n long edges through the
// centre's cells.
RowMatrixXd Star(int n, double r_out, double r_in) {
  RowMatrixXd m(n, 2);
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * M_PI * k / n, r = k % 2 == 0 ? r_out : r_in;
    m.row(k) << r * std::cos(a), r * std::sin(a);
  }
  return m;
}

FloorGeometry OneRing(const RowMatrixXd& ring) {
  FloorGeometry g;
  g.outlines.push_back(ring);
  return g;
}

TEST(FloorPlan, SelfIntersectionWorkIsOrderELogE) {
  // Work is counted, not timed: exact predicate evaluations of the sweep. A quadratic test
  // of the pairs within a cell would do ~E^2 / cells; the sweep does O(E log E).
  std::vector<double> edges, work;
  for (int teeth : {2500, 10000}) {
    const FloorPlan plan({OneRing(Comb(teeth))});
    const FloorBuildStatistics& s = plan.BuildStatistics(0);
    edges.push_back(static_cast<double>(s.edges));
    work.push_back(static_cast<double>(s.self_intersection_work));
    // At most a few comparisons per level of the balanced tree per edge.
    EXPECT_LE(work.back(), 6.0 * edges.back() * std::log2(edges.back())) << teeth;
    EXPECT_GT(work.back(), 0.0);
  }
  // 4x the edges: n log n gives ~4.6x, a quadratic test 16x.
  EXPECT_LT(work[1] / work[0], 6.0);
  // Also for a star (long edges all meeting near the centre).
  const FloorPlan star({OneRing(Star(4000, 20.0, 1.0))});
  const FloorBuildStatistics& s = star.BuildStatistics(0);
  EXPECT_LE(static_cast<double>(s.self_intersection_work), 6.0 * 4000 * std::log2(4000.0));
}

TEST(FloorPlan, SweepFindsExactlyTheSelfIntersectingRingsOfABruteForce) {
  // Random rings on a 4 x 4 lattice: repeated vertices, collinear overlaps, vertices on edges,
  // folds back along an edge: the sweep's verdict equals the test of every pair.
  RandomStream rng(28);
  int simple = 0, crossing = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const int n = 3 + static_cast<int>(rng.UniformInt(6));
    RowMatrixXd ring(n, 2);
    for (int k = 0; k < n; ++k) {
      ring.row(k) << static_cast<double>(rng.UniformInt(4)), static_cast<double>(rng.UniformInt(4));
    }
    // The ring as FloorPlan cleans it: consecutive repeats (and the closing repeat) dropped.
    std::vector<Eigen::Vector2d> v;
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector2d p = ring.row(k).transpose();
      if (v.empty() || p != v.back()) v.push_back(p);
    }
    while (v.size() > 1 && v.back() == v.front()) v.pop_back();
    const int m = static_cast<int>(v.size());
    bool bad = false;
    for (int a = 0; a < m && !bad; ++a) {
      for (int b = a + 1; b < m && !bad; ++b) {
        const Eigen::Vector4d sa(v[a].x(), v[a].y(), v[(a + 1) % m].x(), v[(a + 1) % m].y());
        const Eigen::Vector4d sb(v[b].x(), v[b].y(), v[(b + 1) % m].x(), v[(b + 1) % m].y());
        if (b == a + 1 || (a == 0 && b == m - 1)) {
          // Neighbours share a vertex; they are bad if they fold back along a line.
          const Eigen::Vector4d& first = b == a + 1 ? sa : sb;
          const Eigen::Vector4d& second = b == a + 1 ? sb : sa;
          bad = NaiveOrient(first[0], first[1], first[2], first[3], second[2], second[3]) == 0 &&
                (first[2] - first[0]) * (second[2] - second[0]) + (first[3] - first[1]) * (second[3] - second[1]) < 0;
        } else {
          bad = NaiveIntersect(sa, sb);
        }
      }
    }
    try {
      const FloorPlan plan({OneRing(ring)});
      EXPECT_FALSE(bad) << "accepted a self-intersecting ring, trial " << trial << ":\n" << ring;
      ++simple;
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      if (what.find("self-intersecting") != std::string::npos) {
        EXPECT_TRUE(bad) << "refused a simple ring, trial " << trial << ":\n" << ring << "\n" << what;
        ++crossing;
      }
      // Other refusals (fewer than 3 distinct vertices, zero area) are not the sweep's.
    }
  }
  EXPECT_GT(simple, 100);
  EXPECT_GT(crossing, 100);
}

TEST(FloorPlan, CombAndStarBuildWithinTheirBudgets) {
  const FloorPlan comb({OneRing(Comb(10000))});
  EXPECT_NEAR(comb.WalkableArea(0), 0.1 + 0.9 * 0.5, 1e-6);
  // Long edges on small cells: the automatic cell size grows until the index fits in
  // max(64 MB, 1 kB per edge) instead of registering every edge in hundreds of cells.
  const FloorPlan star({OneRing(Star(8000, 400.0, 1.0))});
  const FloorBuildStatistics& s = star.BuildStatistics(0);
  EXPECT_LE(s.index_bytes, 64e6);
  EXPECT_GT(star.CellSize(0), 1.0);  // grown beyond the usual [0.25, 1] m
  EXPECT_EQ(s.edges, 8000);
  // The area (exact whether the scanlines or, over their budget, the shoelace formula gave it).
  const RowMatrixXd v = Star(8000, 400.0, 1.0);
  double area2 = 0.0;
  for (Eigen::Index k = 0; k < v.rows(); ++k) {
    const Eigen::Index j = (k + 1) % v.rows();
    area2 += v(k, 0) * v(j, 1) - v(j, 0) * v(k, 1);
  }
  EXPECT_NEAR(star.WalkableArea(0), 0.5 * area2, 1e-9 * 0.5 * area2);
}

TEST(FloorPlan, IndexMemoryIsRefusedBeforeAllocating) {
  // A 1 km square with 0.1 m cells and max_cells = 1e8: 1e8 cells, ~7.6 GB of index.
  FloorPlanOptions o;
  o.cell_size_m = 0.1;
  o.max_cells = 100000000;
  FloorGeometry g;
  g.outlines.push_back(Box(0, 0, 999.8, 999.8));
  ExpectInvalid([&] { FloorPlan({g}, o); }, {"options.cell_size_m", "GB", "limit 4 GB"});
  // Long edges on explicit small cells: refused by their registrations (a star whose 2e4
  // edges of 250 m would each be listed in ~3000 cells of 0.1 m: 2.5e7 cells and 6e7+
  // registrations, over 4 GB).
  ExpectInvalid([&] { FloorPlan({OneRing(Star(20000, 250.0, 1.0))}, o); },
                {"options.cell_size_m", "edge-cell registrations", "would need at least"});
  // The same plan with the automatic cell size builds.
  EXPECT_NO_THROW(FloorPlan({OneRing(Star(2000, 250.0, 1.0))}));
}

// The wall test's fast path (sub-cell masks, floor_plan_index.h) against brute force on a hall of
// pillars whose sides lie on cell and sub-cell boundaries, with short steps starting and ending
// on those boundaries and on the pillars' corners; and the span form equal to the single form.
TEST(FloorPlan, PillarHallFastPathAndSpanMatchBruteForce) {
  FloorGeometry g;
  g.outlines.push_back(Box(0, 0, 40, 40));
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) g.obstacles.push_back(Box(4 * i + 1.5, 4 * j + 1.5, 4 * i + 2.5, 4 * j + 2.5));
  }
  FloorGeometry upper = g;
  upper.floor = 1;
  upper.obstacles.resize(50);
  for (double cell : {0.0, 1.0, 0.5}) {
    FloorPlanOptions options;
    options.cell_size_m = cell;
    const FloorPlan plan({g, upper}, options);
    const BruteForce brute0(plan, 0), brute1(plan, 1);
    RandomStream rng(12);
    const int count = 3000;
    std::vector<double> x0(count), y0(count), x1(count), y1(count);
    std::vector<int> floor(count);
    int crossing = 0;
    for (int q = 0; q < count; ++q) {
      // Coordinates on a 1/16 m lattice (every sub-cell boundary of a 1 m or 0.5 m grid).
      x0[q] = static_cast<double>(rng.UniformInt(40 * 16)) / 16.0;
      y0[q] = static_cast<double>(rng.UniformInt(40 * 16)) / 16.0;
      x1[q] = x0[q] + (static_cast<double>(rng.UniformInt(25)) - 12.0) / 16.0;
      y1[q] = y0[q] + (static_cast<double>(rng.UniformInt(25)) - 12.0) / 16.0;
      floor[q] = static_cast<int>(rng.UniformInt(2));
      const bool expected = (floor[q] == 0 ? brute0 : brute1).Crosses(Eigen::Vector4d(x0[q], y0[q], x1[q], y1[q]));
      crossing += expected;
      ASSERT_EQ(plan.CrossesWall(x0[q], y0[q], x1[q], y1[q], floor[q]), expected)
          << "cell " << cell << " floor " << floor[q] << ": " << x0[q] << ", " << y0[q] << " -> " << x1[q] << ", " << y1[q];
    }
    EXPECT_GT(crossing, 200);
    std::unique_ptr<bool[]> out(new bool[count]);
    plan.CrossesWallSpan(count, x0.data(), y0.data(), x1.data(), y1.data(), floor.data(), out.get());
    for (int q = 0; q < count; ++q) ASSERT_EQ(out[q], plan.CrossesWall(x0[q], y0[q], x1[q], y1[q], floor[q])) << q;
  }
}

}  // namespace
}  // namespace indoorloc::fusion
