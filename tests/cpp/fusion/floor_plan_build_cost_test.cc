// Tests of the floor plan's construction cost and memory bounds: the self-intersection sweep is
// O(E log E) and finds exactly the rings a brute force finds, combs and stars with thousands of
// edges per cell build within their budgets, the grid index refuses memory it would exceed before
// allocating, and the pillar hall's fast path agrees with the brute force.
#include "indoorloc/fusion/floor_plan.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "expect_invalid.h"
#include "floor_plan_reference.h"

#include "indoorloc/core/random.h"

namespace indoorloc::fusion {
namespace {

using namespace floor_plan_reference;  // NOLINT: the test helpers

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
