// The shared-AP matcher's searches (indoorloc/wifi/shared_ap_matcher.h): the full pass over the
// query's posting lists (Parts, and Nearest's fallback) and the pruned k-nearest search, each
// for both RSS storages of the index (shared_ap_index.h). SelectPruned is 152 lines (the house's
// limit: 150 lines): one search whose phases (weights, first pass, bounds, exact sums) share the query's
// scratch; it is left whole while the matcher's speed work goes on (splitting it is pending).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "shared_ap_index.h"

namespace indoorloc::wifi::internal {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Nearest's first pass reads the posting lists of the query's strongest APs only: the fewest that
// leave at most this fraction of its weight sum_A g f(a) to the rest (a speed setting only: the
// result is exact whatever it is). Of {0.1, 0.2, 0.3, 0.5}, 0.2 was fastest on F1's pooled 200-AP
// scans (the slowest floor of the live benchmark: 375 -> 326 us cold, exp/fixer_bench.cc) and
// within 10 % of 0.1 on single 200-AP scans and noisy fingerprints of B1 and F1.
constexpr double kRestFraction = 0.2;
// When the first pass would read more than this fraction of the query's posting-list entries,
// the full pass runs instead (of 0.7 and 0.95, 0.95 was faster on F1's pooled 200-AP scans: with
// even weights the first pass is most of the full one, but its bounds still spare most of the
// exact work).
constexpr double kFullPassFraction = 0.95;
// Relative allowance for rounding in the pruning bounds (sums of up to ~1e6 terms carry relative
// errors below 1e6 x 2^-53 ~ 1e-10): a bound is lowered by this much so that it stays below the
// computed d of every reference it prunes.
constexpr double kCushion = 1e-8;

// An entry's RSS b and weight g f(b) (g: its AP's reliability), in the two storages.
struct WideEntries {
  const double* value;
  const double* weight;
  double Value(std::int64_t e) const { return value[e]; }
  double Weight(std::int64_t e, double /*g*/) const { return weight[e]; }
};
struct CompactEntries {
  const std::int8_t* value;
  const double* strength;  // f(v - 128)
  double Value(std::int64_t e) const { return value[e]; }
  double Weight(std::int64_t e, double g) const { return g * strength[value[e] + 128]; }
};

// The references a pass touched (seen = 1), in index order: one sequential sweep of the sums
// after the pass costs less than a branch and a push per entry inside it.
void ListTouched(const SharedApIndex& index, SharedApScratch* acc) {
  acc->touched.clear();
  for (Eigen::Index j = 0; j < index.num_references; ++j) {
    if (acc->sums[static_cast<size_t>(j)].seen != 0.0) acc->touched.push_back(static_cast<std::int32_t>(j));
  }
}

// Sums of eq. (1) for one query over its APs' posting lists; returns sum_A g f(a).
template <typename RefT, typename Entries>
double Accumulate(const SharedApIndex& index, const RefT* entry_ref, const Entries& entries, const double* query,
                  double scale_db, SharedApScratch* acc) {
  double query_weight = 0.0;
  for (Eigen::Index i = 0; i < index.num_aps; ++i) {
    const double a = query[i];
    if (std::isnan(a)) continue;
    const double g = index.ap_weight[static_cast<size_t>(i)];
    const double w = g * Strength(a, scale_db);  // w_i = g_i f(a_i)
    query_weight += w;
    for (std::int64_t e = index.start[i]; e < index.start[i + 1]; ++e) {
      const std::int32_t j = entry_ref[e];
      SharedApScratch::Sums& sj = acc->sums[j];
      sj.seen = 1.0;  // no branch here: the touched are listed after the pass (ListTouched)
      const double diff = a - entries.Value(e);
      sj.w += w;                        // sum_{A^B} w_i
      sj.sq += w * diff * diff;         // sum_{A^B} w_i (a_i - b_i)^2
      sj.ref_w += entries.Weight(e, g);  // sum_{A^B} g_i f(b_i)
    }
  }
  ListTouched(index, acc);
  return query_weight;
}

// The k best (d, reference) of a query by the full pass over all its APs' posting lists, best
// first, in acc->best (d finite only; ties by reference index).
template <typename RefT, typename Entries>
void SelectFull(const SharedApIndex& index, const RefT* entry_ref, const Entries& postings, const double* query,
                const SharedApMatcherOptions& o, Eigen::Index k, SharedApScratch* acc) {
  const double query_weight = Accumulate(index, entry_ref, postings, query, o.strength_scale_db, acc);
  acc->best.clear();
  for (std::int32_t j : acc->touched) {
    const auto [rms, u] = RmsAndUnshared(index, acc->sums[j], query_weight, j);
    if (std::isfinite(rms)) acc->best.emplace_back(rms + o.penalty_db * u, j);
  }
  acc->Clear();
  const auto found = static_cast<std::ptrdiff_t>(std::min<size_t>(acc->best.size(), static_cast<size_t>(k)));
  std::partial_sort(acc->best.begin(), acc->best.begin() + found, acc->best.end());
  acc->best.resize(static_cast<size_t>(found));
}

// Exact sums of eq. (1) for kLanes references at once (four independent chains hide the adds'
// latency), each from its own entries in AP order: the same terms added in the same order as
// Accumulate adds them, hence the same bits. An AP the query did not hear adds +0 to each sum
// (w = 0, heard = 0; every term is >= 0, so a sum is never -0 and x + 0 = x exactly).
constexpr int kLanes = 4;
template <typename Entries>
void ExactSums(const SharedApIndex& index, const Entries& by_ref, const SharedApScratch::QueryEntry* query,
               const std::int32_t* refs, SharedApScratch::Sums* out) {
  std::int64_t e[kLanes], end[kLanes];
  double sw[kLanes], sq[kLanes], rw[kLanes];
  std::int64_t common = std::numeric_limits<std::int64_t>::max();
  for (int c = 0; c < kLanes; ++c) {
    e[c] = index.ref_start[refs[c]];
    end[c] = index.ref_start[refs[c] + 1];
    common = std::min(common, end[c] - e[c]);
    sw[c] = sq[c] = rw[c] = 0.0;
  }
  auto add = [&](int c, std::int64_t x) {
    const std::int32_t i = index.ref_ap[x];
    const SharedApScratch::QueryEntry& q = query[i];
    const double diff = q.a - by_ref.Value(x);
    sw[c] += q.w;
    sq[c] += q.w * diff * diff;
    rw[c] += by_ref.Weight(x, index.ap_weight[static_cast<size_t>(i)]) * q.heard;
  };
  for (std::int64_t t = 0; t < common; ++t) {
    for (int c = 0; c < kLanes; ++c) add(c, e[c] + t);
  }
  for (int c = 0; c < kLanes; ++c) {
    for (std::int64_t x = e[c] + common; x < end[c]; ++x) add(c, x);
    out[c].w = sw[c];
    out[c].sq = sq[c];
    out[c].ref_w = rw[c];
  }
}

// Lower bound of d (eq. 1) for a reference from sums over the first pass's APs S only. With
// W_rest = sum_{A\S} w_i and M_rest = sum_{A\S} max_b g_i f(b) (the rest of the query's weight
// and the most the reference can have heard of it):
//   sum_{A^B} w <= sw_S + W_rest,   sum_{A^B} w (a-b)^2 >= sq_S,
//   sum_{B\A} g f(b) >= max(total_B - ref_w_S - M_rest, the same sum over B's strongest entries),
// so rms >= sqrt(sq_S / (sw_S + W_rest)) and u >= 1 - (sw_S + W_rest) / (sum_A + that), each
// loosened by kCushion against rounding.
double LowerBound(double sw_s, double sq_s, double ref_w_s, double total_b, double top_only, double query_weight,
                  double rest_w, double rest_max, double penalty) {
  const double sw_hi = (sw_s + rest_w) * (1.0 + kCushion);
  const double ref_only = std::max({0.0, top_only * (1.0 - kCushion),
                                    total_b - ref_w_s - rest_max - kCushion * (total_b + ref_w_s + rest_max + query_weight)});
  const double total = (query_weight + ref_only) * (1.0 - kCushion);
  const double u = total > 0.0 ? std::max(0.0, 1.0 - sw_hi / total) : 0.0;
  const double rms = sw_hi > 0.0 ? std::sqrt(std::max(0.0, sq_s * (1.0 - kCushion) / sw_hi)) : 0.0;
  return (rms + penalty * u) * (1.0 - kCushion) - kCushion;
}

// The k best (d, reference) of a query, exactly SelectFull's (same d bits, same order), in
// acc->best. A first pass over the posting lists of the query's strongest APs S bounds every
// reference's d from below (LowerBound); references are then computed exactly (ExactSums) in the
// order of their bounds until the next bound exceeds the k-th best d found. References that share
// no AP of S are bounded as a group; when that bound cannot exclude them, the full pass runs.
template <typename RefT, typename Entries>
void SelectPruned(const SharedApIndex& index, const RefT* entry_ref, const Entries& postings, const Entries& by_ref,
                  const double* query, const SharedApMatcherOptions& o, Eigen::Index k, SharedApScratch* acc) {
  acc->by_weight.clear();
  double query_weight = 0.0;  // in AP order, as Accumulate sums it
  for (Eigen::Index i = 0; i < index.num_aps; ++i) {
    const double a = query[i];
    if (std::isnan(a)) {
      acc->dense[static_cast<size_t>(i)] = {0.0, 0.0, 0.0};
      continue;
    }
    const double w = index.ap_weight[static_cast<size_t>(i)] * Strength(a, o.strength_scale_db);
    acc->dense[static_cast<size_t>(i)] = {a, w, 1.0};
    query_weight += w;
    // Most weight per posting-list entry first: the cheapest first pass for a given rest.
    const double entries = static_cast<double>(std::max<std::int64_t>(1, index.start[i + 1] - index.start[i]));
    acc->by_weight.emplace_back(-w / entries, static_cast<std::int32_t>(i));
  }
  if (!(query_weight > 0.0) || !std::isfinite(query_weight)) return SelectFull(index, entry_ref, postings, query, o, k, acc);
  std::sort(acc->by_weight.begin(), acc->by_weight.end());
  size_t s = 0;
  for (double left = query_weight; s < acc->by_weight.size() && left > kRestFraction * query_weight; ++s) {
    left -= acc->dense[static_cast<size_t>(acc->by_weight[s].second)].w;
  }
  double rest_w = 0.0, rest_max = 0.0;
  std::int64_t entries_all = 0, entries_first = 0;
  for (size_t m = 0; m < acc->by_weight.size(); ++m) {
    const std::int32_t i = acc->by_weight[m].second;
    entries_all += index.start[i + 1] - index.start[i];
    if (m < s) {
      entries_first += index.start[i + 1] - index.start[i];
    } else {
      rest_w += acc->dense[static_cast<size_t>(i)].w;
      rest_max += index.ap_max_weight[static_cast<size_t>(i)];
    }
  }
  // Weights even (a long pooled query of equally strong APs): the first pass would be the full one.
  if (static_cast<double>(entries_first) > kFullPassFraction * static_cast<double>(entries_all)) return SelectFull(index, entry_ref, postings, query, o, k, acc);
  acc->first_pass.clear();
  for (size_t m = 0; m < s; ++m) acc->first_pass.push_back(acc->by_weight[m].second);
  std::sort(acc->first_pass.begin(), acc->first_pass.end());
  // First pass: partial sums over S.
  for (std::int32_t i : acc->first_pass) {
    const double a = query[i];
    const double g = index.ap_weight[static_cast<size_t>(i)];
    const double w = acc->dense[static_cast<size_t>(i)].w;
    for (std::int64_t e = index.start[i]; e < index.start[i + 1]; ++e) {
      const std::int32_t j = entry_ref[e];
      SharedApScratch::Sums& sj = acc->sums[j];
      sj.seen = 1.0;  // no branch here: the touched are listed after the pass (ListTouched)
      const double diff = a - postings.Value(e);
      sj.w += w;
      sj.sq += w * diff * diff;
      sj.ref_w += postings.Weight(e, g);
    }
  }
  ListTouched(index, acc);
  acc->best.clear();
  const auto kk = static_cast<size_t>(k);
  auto consider = [&](std::int32_t j, const SharedApScratch::Sums& sums) {
    const auto [rms, u] = RmsAndUnshared(index, sums, query_weight, j);
    if (!std::isfinite(rms)) return;
    const std::pair<double, std::int32_t> cand(rms + o.penalty_db * u, j);
    if (acc->best.size() < kk) {
      acc->best.push_back(cand);
      std::push_heap(acc->best.begin(), acc->best.end());
    } else if (cand < acc->best.front()) {
      std::pop_heap(acc->best.begin(), acc->best.end());
      acc->best.back() = cand;
      std::push_heap(acc->best.begin(), acc->best.end());
    }
  };
  auto evaluate = [&](std::int32_t* refs, int count) {  // count in [1, kLanes]; pads with repeats
    for (int c = count; c < kLanes; ++c) refs[c] = refs[count - 1];
    SharedApScratch::Sums sums[kLanes];
    ExactSums(index, by_ref, acc->dense.data(), refs, sums);
    for (int c = 0; c < count; ++c) consider(refs[c], sums[c]);
  };
  // Seeds: the k references with the most shared weight sw_S, computed exactly; the k-th best of
  // them bounds the final k-th best d from above, so a reference whose bound exceeds it is dropped
  // before its full bound is computed.
  acc->seed_w.clear();
  for (std::int32_t j : acc->touched) acc->seed_w.push_back(acc->sums[j].w);
  const size_t seeds = std::min(kk, acc->seed_w.size());
  double seed_min = kInf;
  if (seeds > 0) {
    std::nth_element(acc->seed_w.begin(), acc->seed_w.begin() + static_cast<std::ptrdiff_t>(seeds - 1),
                     acc->seed_w.end(), std::greater<double>());
    seed_min = acc->seed_w[seeds - 1];
  }
  acc->first_pass.clear();  // reused: the seeds
  for (size_t t = 0; t < acc->touched.size() && acc->first_pass.size() < seeds; ++t) {
    if (acc->sums[acc->touched[t]].w >= seed_min) acc->first_pass.push_back(acc->touched[t]);
  }
  for (size_t m = 0; m < acc->first_pass.size(); m += kLanes) {
    std::int32_t refs[kLanes];
    int count = 0;
    for (; count < kLanes && m + static_cast<size_t>(count) < acc->first_pass.size(); ++count) {
      refs[count] = acc->first_pass[m + static_cast<size_t>(count)];
      acc->sums[refs[count]].seen = 2.0;  // evaluated
    }
    evaluate(refs, count);
  }
  const double threshold = acc->best.size() == kk ? acc->best.front().first : kInf;
  // LowerBound >= c (1 - (sw_S + W_rest) / sum_A) > threshold when sw_S < sw_min: one comparison
  // drops most references (sw_min lowered by 1e-6 of its terms: a safe side for rounding).
  double sw_min = -kInf;
  if (std::isfinite(threshold) && o.penalty_db > 0.0) {
    sw_min = query_weight * (1.0 - (threshold + 1e-6) / o.penalty_db) * (1.0 - 1e-6) - rest_w * (1.0 + 1e-6);
  }
  acc->bounds.clear();
  for (std::int32_t j : acc->touched) {
    const SharedApScratch::Sums& sj = acc->sums[j];
    if (sj.seen == 2.0 || sj.w < sw_min) continue;
    const double tw = index.total_weight[j];
    double top_only = 0.0;  // what the reference's strongest entries heard and the query did not
    for (size_t m = static_cast<size_t>(j) * kTopEntries, end = m + kTopEntries; m < end; ++m) {
      const std::int32_t i = index.top_ap[m];
      if (i >= 0 && std::isnan(query[i])) top_only += index.top_weight[m];
    }
    const double bound = LowerBound(sj.w, sj.sq, sj.ref_w, tw, top_only, query_weight, rest_w, rest_max, o.penalty_db);
    if (bound <= threshold) acc->bounds.emplace_back(bound, j);
  }
  acc->Clear();
  // References sharing no AP of S: sw_S = sq_S = 0 and sum_{B\A} >= 0; none can share anything
  // when S is every AP of the query.
  const double untouched = s == acc->by_weight.size()
                               ? kInf
                               : LowerBound(0.0, 0.0, 0.0, 0.0, 0.0, query_weight, rest_w, 0.0, o.penalty_db);
  // The rest exactly in the order of their bounds (a min-heap), kLanes at a time, until the next
  // bound exceeds the k-th best d; the best k are kept in a max-heap of (d, j).
  auto greater = std::greater<std::pair<double, std::int32_t>>();
  std::make_heap(acc->bounds.begin(), acc->bounds.end(), greater);
  bool done = false;
  while (!done && !acc->bounds.empty()) {
    std::int32_t refs[kLanes];
    int count = 0;
    while (count < kLanes && !acc->bounds.empty()) {
      if (acc->best.size() == kk && acc->bounds.front().first > acc->best.front().first) {
        done = true;
        break;
      }
      std::pop_heap(acc->bounds.begin(), acc->bounds.end(), greater);
      refs[count++] = acc->bounds.back().second;
      acc->bounds.pop_back();
    }
    if (count > 0) evaluate(refs, count);
  }
  if (acc->best.size() < kk ? std::isfinite(untouched) : untouched <= acc->best.front().first) {
    return SelectFull(index, entry_ref, postings, query, o, k, acc);
  }
  std::sort_heap(acc->best.begin(), acc->best.end());
}

}  // namespace

// rms and u of eq. (1) for reference j from its sums; (inf, 1) when nothing is shared.
std::pair<double, double> RmsAndUnshared(const SharedApIndex& index, const SharedApScratch::Sums& sj,
                                         double query_weight, std::int32_t j) {
  const double sw = sj.w;
  if (!(sw > 0.0)) return {kInf, 1.0};
  const double rms = std::sqrt(std::max(sj.sq / sw, 0.0));
  const double total = query_weight + index.total_weight[j] - sj.ref_w;  // sum_A + sum_{B\A}
  const double u = std::clamp(1.0 - sw / total, 0.0, 1.0);
  return {rms, u};
}

// Calls fn(refs, postings, by_ref) with the index's storage: reference rows in two or four
// bytes, RSS in one byte or a double.
template <typename Fn>
void WithStorage(const SharedApIndex& index, Fn fn) {
  auto values = [&](const auto* entry_ref) {
    if (index.compact) {
      fn(entry_ref, CompactEntries{index.value_i8.data(), index.strength.data()},
         CompactEntries{index.ref_value_i8.data(), index.strength.data()});
    } else {
      fn(entry_ref, WideEntries{index.value_dbm.data(), index.weight.data()},
         WideEntries{index.ref_value_dbm.data(), index.ref_entry_weight.data()});
    }
  };
  if (index.ref.empty()) {
    values(index.ref16.data());
  } else {
    values(index.ref.data());
  }
}

double AccumulateAll(const SharedApIndex& index, const double* query, double scale_db, SharedApScratch* acc) {
  double query_weight = 0.0;
  WithStorage(index, [&](const auto* entry_ref, const auto& postings, const auto&) {
    query_weight = Accumulate(index, entry_ref, postings, query, scale_db, acc);
  });
  return query_weight;
}

void SelectNearest(const SharedApIndex& index, const double* query, const SharedApMatcherOptions& options,
                   Eigen::Index k, SharedApScratch* acc) {
  WithStorage(index, [&](const auto* entry_ref, const auto& postings, const auto& by_ref) {
    SelectPruned(index, entry_ref, postings, by_ref, query, options, k, acc);
  });
}

}  // namespace indoorloc::wifi::internal
