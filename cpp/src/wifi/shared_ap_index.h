// The shared-AP matcher's reference index and per-query scratch (indoorloc/wifi/shared_ap_matcher.h):
// built by shared_ap_matcher.cc, searched by shared_ap_search.cc.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/wifi/shared_ap_matcher.h"

namespace indoorloc::wifi::internal {

// f(x) = exp((x - kStrengthPivotDbm) / beta): the pivot scales every f by one constant.
constexpr double kStrengthPivotDbm = -40.0;
// Per reference, its strongest entries (largest g f(b)) kept for the bound on what it heard and
// the query did not (shared_ap_search.cc); 8 tightened the bounds most per byte (of 4, 8, 16).
constexpr int kTopEntries = 8;

inline double Strength(double rss_dbm, double scale_db) {
  return scale_db > 0.0 ? std::exp((rss_dbm - kStrengthPivotDbm) / scale_db) : 1.0;
}

// Per-query sums over the references that share an AP with it, the list of those, and the
// pruned search's scratch. Kept in a pool and reused (SharedApIndex::scratch).
struct SharedApScratch {
  struct Sums {
    double w = 0.0;      // sum_{A^B} w_i
    double sq = 0.0;     // sum_{A^B} w_i (a_i - b_i)^2
    double ref_w = 0.0;  // sum_{A^B} g_i f(b_i)
    double seen = 0.0;   // 1 once touched, 2 once computed exactly (a double: 32-byte entries)
  };
  // The query by AP for the exact sums without a branch: (a, w, 1) where heard, (0, 0, 0) not.
  struct QueryEntry {
    double a, w, heard;
  };
  std::vector<Sums> sums;
  std::vector<std::int32_t> touched;
  std::vector<QueryEntry> dense;
  std::vector<std::pair<double, std::int32_t>> by_weight;  // the query's APs, strongest first
  std::vector<std::int32_t> first_pass;                    // the first pass's APs, then the seeds
  std::vector<double> seed_w;
  std::vector<std::pair<double, std::int32_t>> bounds;     // (lower bound of d, reference)
  std::vector<std::pair<double, std::int32_t>> best;       // (d, reference), the best k so far
  SharedApScratch(Eigen::Index n, Eigen::Index k) : sums(static_cast<size_t>(n)), dense(static_cast<size_t>(k)) {}
  void Clear() {
    for (std::int32_t j : touched) sums[j] = Sums();
    touched.clear();
  }
};

// The references' heard entries, stored twice: by AP (posting lists: entries of AP i in
// [start[i], start[i + 1]), in reference order) and by reference (entries of reference r in
// [ref_start[r], ref_start[r + 1]), APs ascending: the exact sums of one reference in the order
// the posting-list pass adds them). RSS storage: "compact" when every heard RSS is an integer dBm
// in [-128, 127] (phones report whole dBm): one byte per entry, and an entry's weight g_i f(b)
// recomputed as g_i x strength[b + 128], the same product of the same numbers, hence the same
// bits (a fifth of the memory read per query: the search is bound by it); else doubles.
struct SharedApIndex {
  Eigen::Index num_references = 0;
  Eigen::Index num_aps = 0;
  std::vector<double> ap_weight;      // g (K)
  std::vector<double> ap_max_weight;  // per AP: max over its entries of g_i f(b_i)
  std::vector<double> total_weight;   // per reference: sum_B g_i f(b_i)
  bool compact = false;
  std::vector<double> strength;       // compact: f(v - 128) for v in [0, 256)
  std::vector<std::int64_t> start;    // K + 1
  std::vector<std::uint16_t> ref16;   // reference row of each entry when N <= 65,536 (two bytes) ...
  std::vector<std::int32_t> ref;      // ... else here
  std::vector<std::int8_t> value_i8;  // compact: b_i
  std::vector<double> value_dbm;      // otherwise: b_i ...
  std::vector<double> weight;         // ... and g_i f(b_i)
  std::vector<std::int64_t> ref_start;  // N + 1
  std::vector<std::int32_t> ref_ap;
  std::vector<std::int8_t> ref_value_i8;
  std::vector<double> ref_value_dbm;
  std::vector<double> ref_entry_weight;
  // Per reference its kTopEntries strongest entries (AP -1 and weight 0 pad): AP and g f(b).
  std::vector<std::int32_t> top_ap;
  std::vector<double> top_weight;
  // Scratch reused across calls (one is ~32 B per reference: allocating and zeroing it per call
  // cost as much as a live query's search), taken and given back under the mutex.
  mutable std::mutex scratch_mutex;
  mutable std::vector<std::unique_ptr<SharedApScratch>> scratch;
};

/// Sums of eq. (1) for one query over every heard AP's posting list (scratch->sums, touched);
/// returns sum_A g f(a).
double AccumulateAll(const SharedApIndex& index, const double* query, double scale_db, SharedApScratch* acc);
/// rms and u of eq. (1) for reference j from its sums; (inf, 1) when nothing is shared.
std::pair<double, double> RmsAndUnshared(const SharedApIndex& index, const SharedApScratch::Sums& sums,
                                         double query_weight, std::int32_t j);
/// The min(k, N) best (d, reference) of a query with d finite, best first (ties by reference), in
/// acc->best: the pruned search, equal bit for bit to the full one (shared_ap_search.cc).
void SelectNearest(const SharedApIndex& index, const double* query, const SharedApMatcherOptions& options,
                   Eigen::Index k, SharedApScratch* acc);

}  // namespace indoorloc::wifi::internal
