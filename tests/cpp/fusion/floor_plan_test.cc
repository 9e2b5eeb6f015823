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
#include "floor_plan_reference.h"

#include "indoorloc/core/random.h"

namespace indoorloc::fusion {
namespace {

using namespace floor_plan_reference;  // NOLINT: the test helpers

FloorGeometry SquareWithHole() {
  FloorGeometry g;
  g.floor = 2;
  g.outlines.push_back(Box(0, 0, 10, 10, /*clockwise=*/true));  // orientation is normalised
  g.obstacles.push_back(Box(4, 4, 6, 6));
  return g;
}

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

// The wall test's fast paths (free quarter blocks, sub-cell masks) on the case they are built
// for: a lattice of square pillars whose sides lie on cell boundaries (every side registered in
// two cells), short steps in random directions from walkable points, some grazing the pillars
// and some running along their sides; CrossesWallSpan equals the brute force.
TEST(FloorPlan, PillarLatticeOnCellBoundariesMatchesBruteForceForShortSteps) {
  FloorGeometry g;
  g.outlines.push_back(Box(0, 0, 40, 40));
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) g.obstacles.push_back(Box(4 * i + 1.5, 4 * j + 1.5, 4 * i + 2.5, 4 * j + 2.5));
  }
  FloorPlanOptions options;
  options.cell_size_m = 1.0;
  const FloorPlan plan({g}, options);
  const BruteForce brute(plan, 0);
  RandomStream rng(21);
  const int n = 6000;
  std::vector<double> x0, y0, x1, y1;
  while (static_cast<int>(x0.size()) < n) {
    // Half of the starts on the 1/8 m lattice of the sub-cells (boundaries of the fast paths).
    double x = rng.Uniform(0.0, 40.0), y = rng.Uniform(0.0, 40.0);
    if (x0.size() % 2 == 0) {
      x = std::round(8.0 * x) / 8.0;
      y = std::round(8.0 * y) / 8.0;
    }
    if (!brute.Walkable(x, y) || brute.OnEdge(x, y)) continue;
    const double len = rng.Uniform(0.0, 2.0), a = rng.Uniform(-M_PI, M_PI);
    const bool axis = x0.size() % 5 == 0;  // some along the axes (parallel to the sides)
    x0.push_back(x);
    y0.push_back(y);
    x1.push_back(x + (axis ? len * (a > 0 ? 1 : -1) : len * std::cos(a)));
    y1.push_back(y + (axis ? 0.0 : len * std::sin(a)));
  }
  std::vector<int> floors(n, 0);
  std::unique_ptr<bool[]> out(new bool[n]);
  plan.CrossesWallSpan(n, x0.data(), y0.data(), x1.data(), y1.data(), floors.data(), out.get());
  int crossing = 0;
  for (int k = 0; k < n; ++k) {
    const bool expected = brute.Crosses(Eigen::Vector4d(x0[k], y0[k], x1[k], y1[k]));
    crossing += expected;
    ASSERT_EQ(out[k], expected) << x0[k] << ", " << y0[k] << " -> " << x1[k] << ", " << y1[k];
  }
  EXPECT_GT(crossing, 300);
  EXPECT_LT(crossing, n - 3000);
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

}  // namespace
}  // namespace indoorloc::fusion
