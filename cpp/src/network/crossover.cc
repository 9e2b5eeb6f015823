// Cross-over finder (paper 003 §3.2 XOVER): epochs of a trajectory that coincide horizontally.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/network/network_adjustment.h"

namespace indoorloc::network {
namespace {
constexpr size_t kMaxCandidates = 10000000;  // 16 bytes each: 160 MB
}  // namespace

RowMatrixX2i FindCrossovers(const Eigen::Ref<const Eigen::VectorXd>& time_s, const Eigen::Ref<const RowMatrixXd>& position_m,
                            const CrossoverOptions& options) {
  ValidateOptions(options);
  const Eigen::Index n = time_s.size();
  CheckFinite(time_s, "time_s");
  CheckShape(position_m, n, 3, "position_m");
  CheckFinite(position_m, "position_m");
  for (Eigen::Index i = 1; i < n; ++i)
    CheckArgument(time_s[i] > time_s[i - 1], "time_s", "not strictly increasing at entry " + std::to_string(i));
  // Grid hashing with cell size = radius: candidates lie in the 3 x 3 neighbouring cells.
  const double cell = options.radius_m;
  auto key = [](int64_t ix, int64_t iy) {
    return static_cast<int64_t>((static_cast<uint64_t>(ix) << 32) ^ (static_cast<uint64_t>(iy) & 0xffffffffULL));
  };
  std::unordered_map<int64_t, std::vector<int>> grid;
  grid.reserve(static_cast<size_t>(n));
  std::vector<int64_t> cx(static_cast<size_t>(n)), cy(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    CheckArgument(std::abs(position_m(i, 0)) / cell < 1e15 && std::abs(position_m(i, 1)) / cell < 1e15, "position_m",
                  "row " + std::to_string(i) + " is too far from the origin for radius_m");
    cx[static_cast<size_t>(i)] = static_cast<int64_t>(std::floor(position_m(i, 0) / cell));
    cy[static_cast<size_t>(i)] = static_cast<int64_t>(std::floor(position_m(i, 1) / cell));
    grid[key(cx[static_cast<size_t>(i)], cy[static_cast<size_t>(i)])].push_back(static_cast<int>(i));
  }
  struct Candidate {
    double d2;
    int a, b;
  };
  std::vector<Candidate> candidates;
  const double r2 = options.radius_m * options.radius_m;
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy) {
        auto it = grid.find(key(cx[static_cast<size_t>(i)] + dx, cy[static_cast<size_t>(i)] + dy));
        if (it == grid.end()) continue;
        for (int j : it->second) {
          if (j <= i || time_s[j] - time_s[i] < options.min_separation_s) continue;
          const double ex = position_m(j, 0) - position_m(i, 0), ey = position_m(j, 1) - position_m(i, 1);
          const double d2 = ex * ex + ey * ey;
          if (d2 > r2 || std::abs(position_m(j, 2) - position_m(i, 2)) > options.max_height_difference_m) continue;
          // A radius covering the whole trajectory makes every pair a candidate: stop with a
          // clear error instead of filling the memory.
          if (candidates.size() >= kMaxCandidates)
            ThrowInvalidArgument("options", "radius_m = " + FormatValue(options.radius_m) + " gives more than " +
                                                FormatValue(static_cast<double>(kMaxCandidates)) +
                                                " candidate pairs (" +
                                                FormatBytes(static_cast<double>(kMaxCandidates) * sizeof(Candidate)) +
                                                "); use a smaller radius_m or a larger min_separation_s");
          candidates.push_back({d2, static_cast<int>(i), j});
        }
      }
  }
  // One pair per crossing of two passes: the closest. A candidate belongs to an accepted crossing
  // when, on both passes, its epoch is within min_separation_s (same pass) and within 2 radius_m
  // horizontally (same place) of the accepted pair's epoch.
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    return x.d2 < y.d2 || (x.d2 == y.d2 && (x.a < y.a || (x.a == y.a && x.b < y.b)));
  });
  std::vector<std::pair<int, int>> accepted;
  const double window = std::max(options.min_separation_s, 1e-9);
  const double near2 = 4.0 * r2;
  auto close = [&](int i, int j) {
    const double ex = position_m(i, 0) - position_m(j, 0), ey = position_m(i, 1) - position_m(j, 1);
    return std::abs(time_s[i] - time_s[j]) < window && ex * ex + ey * ey < near2;
  };
  // Accepted pairs indexed by the time buckets (of width `window`) of both epochs: a candidate
  // can only match a pair in the 3 x 3 neighbouring buckets (|Δt| < window on both passes), so
  // the test no longer scans every accepted pair (it was quadratic: 800 epochs with
  // min_separation_s = 0 took 29 s). The same pairs are tested in the same order as before.
  const double t0 = n > 0 ? time_s[0] : 0.0;
  auto bucket = [&](int i) {
    const double b = std::floor((time_s[i] - t0) / window);
    return static_cast<int64_t>(std::clamp(b, -4e18, 4e18));  // clamping merges buckets: still exact
  };
  std::unordered_map<int64_t, std::vector<int>> by_bucket;  // key -> indices into `accepted`
  for (const Candidate& c : candidates) {
    const int64_t ba = bucket(c.a), bb = bucket(c.b);
    bool same = false;
    for (int64_t da = -1; da <= 1 && !same; ++da)
      for (int64_t db = -1; db <= 1 && !same; ++db) {
        auto it = by_bucket.find(key(ba + da, bb + db));
        if (it == by_bucket.end()) continue;
        for (int k : it->second) {
          const auto& [a, b] = accepted[static_cast<size_t>(k)];
          if (close(c.a, a) && close(c.b, b)) {
            same = true;
            break;
          }
        }
      }
    if (!same) {
      by_bucket[key(ba, bb)].push_back(static_cast<int>(accepted.size()));
      accepted.emplace_back(c.a, c.b);
    }
  }
  std::sort(accepted.begin(), accepted.end());
  RowMatrixX2i out(static_cast<Eigen::Index>(accepted.size()), 2);
  for (size_t i = 0; i < accepted.size(); ++i) {
    out(static_cast<Eigen::Index>(i), 0) = accepted[i].first;
    out(static_cast<Eigen::Index>(i), 1) = accepted[i].second;
  }
  return out;
}

}  // namespace indoorloc::network
