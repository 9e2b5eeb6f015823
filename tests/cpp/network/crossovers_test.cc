// Tests of the cross-over finder (network_adjustment.h, FindCrossovers): two perpendicular lines
// cross once (and not when their heights differ), the indexed finder gives exactly the pairs of
// the all-pairs reference, and a huge search radius is refused.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "indoorloc/network/network_adjustment.h"

namespace indoorloc::network {
namespace {

TEST(Crossovers, TwoPerpendicularLinesCrossOnce) {
  // East line at y = 0 for t in [0, 100), then North line at x = 500 from y = -500.
  const int n = 2000;
  Eigen::VectorXd t(n);
  RowMatrixXd p(n, 3);
  for (int i = 0; i < n; ++i) {
    t[i] = 0.1 * i;
    if (i < 1000) p.row(i) << i * 1.0, 0.0, 100.0;
    else p.row(i) << 500.0, -500.0 + (i - 1000) * 1.0, 101.0;
  }
  CrossoverOptions co;
  co.radius_m = 3.0;
  const RowMatrixX2i x = FindCrossovers(t, p, co);
  ASSERT_EQ(x.rows(), 1);
  EXPECT_EQ(x(0, 0), 500);
  EXPECT_EQ(x(0, 1), 1500);
  co.max_height_difference_m = 0.5;
  EXPECT_EQ(FindCrossovers(t, p, co).rows(), 0);
}

// The pre-index cross-over finder (all pairs, then a scan of every accepted pair per candidate):
// the spatial/time index must give exactly its pairs.
RowMatrixX2i BruteForceCrossovers(const Eigen::VectorXd& t, const RowMatrixXd& p, const CrossoverOptions& o) {
  struct C {
    double d2;
    int a, b;
  };
  std::vector<C> c;
  const Eigen::Index n = t.size();
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      if (t[j] - t[i] < o.min_separation_s) continue;
      const double ex = p(j, 0) - p(i, 0), ey = p(j, 1) - p(i, 1), d2 = ex * ex + ey * ey;
      if (d2 > o.radius_m * o.radius_m || std::abs(p(j, 2) - p(i, 2)) > o.max_height_difference_m) continue;
      c.push_back({d2, i, j});
    }
  std::sort(c.begin(), c.end(), [](const C& x, const C& y) {
    return x.d2 < y.d2 || (x.d2 == y.d2 && (x.a < y.a || (x.a == y.a && x.b < y.b)));
  });
  const double window = std::max(o.min_separation_s, 1e-9), near2 = 4.0 * o.radius_m * o.radius_m;
  auto close = [&](int i, int j) {
    const double ex = p(i, 0) - p(j, 0), ey = p(i, 1) - p(j, 1);
    return std::abs(t[i] - t[j]) < window && ex * ex + ey * ey < near2;
  };
  std::vector<std::pair<int, int>> acc;
  for (const C& x : c) {
    bool same = false;
    for (const auto& [a, b] : acc) same = same || (close(x.a, a) && close(x.b, b));
    if (!same) acc.emplace_back(x.a, x.b);
  }
  std::sort(acc.begin(), acc.end());
  RowMatrixX2i out(static_cast<Eigen::Index>(acc.size()), 2);
  for (size_t k = 0; k < acc.size(); ++k) out.row(static_cast<Eigen::Index>(k)) << acc[k].first, acc[k].second;
  return out;
}

// A lawn-mower flight over a 60 m square with 1 m jitter: many passes cross each other.
void LawnMower(int n, Eigen::VectorXd* t, RowMatrixXd* p) {
  std::mt19937 rng(5);
  std::normal_distribution<double> jitter(0.0, 1.0);
  t->resize(n);
  p->resize(n, 3);
  for (int i = 0; i < n; ++i) {
    (*t)[i] = 0.5 * i;
    const double s = std::fmod(i * 1.3, 120.0);
    const double along = s < 60.0 ? s : 120.0 - s;
    const int leg = static_cast<int>(i * 1.3 / 60.0);
    if (leg % 4 < 2) p->row(i) << along + jitter(rng), 15.0 * (leg % 3) + jitter(rng), 100.0;
    else p->row(i) << 15.0 * (leg % 3) + jitter(rng), along + jitter(rng), 100.0;
  }
}

TEST(Crossovers, IndexedFinderMatchesTheBruteForceReference) {
  Eigen::VectorXd t;
  RowMatrixXd p;
  LawnMower(500, &t, &p);
  for (const double sep : {0.0, 5.0, 30.0})
    for (const double radius : {2.0, 5.0, 40.0}) {
      CrossoverOptions o;
      o.min_separation_s = sep;
      o.radius_m = radius;
      const RowMatrixX2i fast = FindCrossovers(t, p, o), slow = BruteForceCrossovers(t, p, o);
      ASSERT_EQ(fast.rows(), slow.rows()) << sep << " " << radius;
      EXPECT_TRUE(fast == slow) << sep << " " << radius;
    }
}

// Issue 17: 800 epochs with min_separation_s = 0 took 29 s (every candidate scanned every
// accepted pair); a radius covering everything made the candidate list grow without bound.
TEST(Crossovers, NoSeparationIsFastAndAHugeRadiusIsRefused) {
  Eigen::VectorXd t;
  RowMatrixXd p;
  LawnMower(800, &t, &p);
  CrossoverOptions o;
  o.min_separation_s = 0.0;
  o.radius_m = 30.0;
  const auto start = std::chrono::steady_clock::now();
  const RowMatrixX2i x = FindCrossovers(t, p, o);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GT(x.rows(), 0);
  EXPECT_LT(seconds, 3.0);
  LawnMower(4600, &t, &p);  // 10.6 million pairs within a 1e9 m radius: above the candidate limit
  o.radius_m = 1e9;
  o.max_height_difference_m = 1e9;
  try {
    FindCrossovers(t, p, o);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("radius_m"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace indoorloc::network
