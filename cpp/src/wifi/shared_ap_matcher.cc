// Shared-AP dissimilarity and kNN (indoorloc/wifi/shared_ap_matcher.h): per-AP posting lists of
// the references, one sparse accumulation per query.
#include "indoorloc/wifi/shared_ap_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::wifi {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// f(x) = exp((x - kStrengthPivotDbm) / beta): the pivot scales every f by one constant.
constexpr double kStrengthPivotDbm = -40.0;
constexpr double kMaxAbsRssDbm = 1e3;
// Queries per parallel task: small enough to balance two threads on a walk's few hundred queries.
constexpr Eigen::Index kQueryBlock = 16;
// Nearest's first pass reads the posting lists of the query's strongest APs only: the fewest that
// leave at most this fraction of its weight sum_A g f(a) to the rest (a speed setting only: the
// result is exact whatever it is; 0.1 was the fastest of {0.05, 0.1, 0.2, 0.3} on the live
// benchmark's 200-AP scans and on noisy training fingerprints, floors B1 F1 F7 of the shared site).
constexpr double kRestFraction = 0.1;
// Relative allowance for rounding in the pruning bounds (sums of up to ~1e6 terms carry relative
// errors below 1e6 x 2^-53 ~ 1e-10): a bound is lowered by this much so that it stays below the
// computed d of every reference it prunes.
constexpr double kCushion = 1e-8;
// Per reference, its strongest entries (largest g f(b)) kept for the bound on what it heard and
// the query did not (LowerBound's ref_only); 8 tightened the bounds most per byte (of 4, 8, 16).
constexpr int kTopEntries = 8;

double Strength(double rss_dbm, double scale_db) {
  return scale_db > 0.0 ? std::exp((rss_dbm - kStrengthPivotDbm) / scale_db) : 1.0;
}

// Every entry NaN (not heard) or finite within +-1000 dBm.
void CheckRssEntries(const Eigen::Ref<const SharedApRowMatrixXd>& x, const char* argument) {
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    for (Eigen::Index j = 0; j < x.cols(); ++j) {
      const double v = x(i, j);
      if (std::isnan(v)) continue;
      if (!(std::abs(v) <= kMaxAbsRssDbm)) {
        ThrowInvalidArgument(argument, DescribeEntry(i, j, false) + " is " + FormatValue(v) +
                                           ": expected NaN (not heard) or an RSS within +-1000 dBm");
      }
    }
  }
}

}  // namespace

bool SharedApMatcherOptions::IsValid(std::string* error) const {
  auto fail = [error](const std::string& reason) {
    if (error != nullptr) *error = reason;
    return false;
  };
  if (!(std::isfinite(penalty_db) && penalty_db >= 0.0 && penalty_db <= 1e4)) {
    return fail("penalty_db must be finite and in [0, 1e4], got " + FormatValue(penalty_db));
  }
  if (!(std::isfinite(strength_scale_db) && (strength_scale_db == 0.0 ||
                                             (strength_scale_db >= 1.0 && strength_scale_db <= 1e4)))) {
    return fail("strength_scale_db must be 0 (off) or in [1, 1e4] dB, got " +
                FormatValue(strength_scale_db));
  }
  if (k < 1) return fail("k must be >= 1, got " + std::to_string(k));
  if (!(std::isfinite(temperature_db) && temperature_db > 0.0)) {
    return fail("temperature_db must be finite and > 0, got " + FormatValue(temperature_db));
  }
  return true;
}

namespace {
struct Accumulator;
}  // namespace

// The references as per-AP posting lists (compressed by AP: entries of AP i in
// [start[i], start[i + 1]), in reference order).
struct internal::SharedApIndex {
  Eigen::Index num_references = 0;
  Eigen::Index num_aps = 0;
  std::vector<std::int64_t> start;   // K + 1
  std::vector<std::int32_t> ref;     // reference row of each entry
  std::vector<double> value_dbm;     // b_i
  std::vector<double> weight;        // g_i f(b_i)
  std::vector<double> total_weight;  // per reference: sum_B g_i f(b_i)
  std::vector<double> ap_weight;     // g (K)
  std::vector<double> ap_max_weight; // per AP: max over its entries of g_i f(b_i)
  // The same entries by reference (compressed by reference, APs ascending): the exact sums of one
  // reference in the order the posting-list pass adds them.
  std::vector<std::int64_t> ref_start;  // N + 1
  std::vector<std::int32_t> ref_ap;
  std::vector<double> ref_value_dbm;
  std::vector<double> ref_entry_weight;
  // Per reference its kTopEntries strongest entries (fewer where it heard fewer APs; AP -1 and
  // weight 0 pad): AP and g f(b).
  std::vector<std::int32_t> top_ap;
  std::vector<double> top_weight;
  // Accumulators reused across calls (one is ~32 B per reference: allocating and zeroing it per
  // call cost as much as a live query's search), taken and given back under the mutex.
  mutable std::mutex scratch_mutex;
  mutable std::vector<std::unique_ptr<Accumulator>> scratch;
};

namespace {

// Per-query sums over the references that share an AP with it, and the list of those. The three
// sums of a reference sit side by side (one cache line per reference touched: the posting-list
// loop below is bound by these scattered updates; live fixes, benchmarks/bench_fusion_live.py).
struct Accumulator {
  struct Sums {
    double w = 0.0;      // sum_{A^B} w_i
    double sq = 0.0;     // sum_{A^B} w_i (a_i - b_i)^2
    double ref_w = 0.0;  // sum_{A^B} g_i f(b_i)
    double seen = 0.0;   // 1 once touched (a double: the entry stays 32 bytes, aligned)
  };
  std::vector<Sums> sums;
  std::vector<std::int32_t> touched;
  // Nearest's scratch (SelectPruned). The query by AP for the exact sums without a branch:
  // (a, w, 1) where heard, (0, 0, 0) not; its APs by weight; the first pass's APs (then the
  // seeds); the seeds' shared weights; the references' lower bounds; the best k so far.
  struct QueryEntry {
    double a, w, heard;
  };
  std::vector<QueryEntry> dense;
  std::vector<std::pair<double, std::int32_t>> by_weight;
  std::vector<std::int32_t> first_pass;
  std::vector<double> seed_w;
  std::vector<std::pair<double, std::int32_t>> bounds;
  std::vector<std::pair<double, std::int32_t>> best;
  Accumulator(Eigen::Index n, Eigen::Index k) : sums(static_cast<size_t>(n)), dense(static_cast<size_t>(k)) {}
  void Clear() {
    for (std::int32_t j : touched) sums[j] = Sums();
    touched.clear();
  }
};

}  // namespace

SharedApMatcher::SharedApMatcher(const Eigen::Ref<const SharedApRowMatrixXd>& reference_rss_dbm,
                                 const Eigen::Ref<const Eigen::VectorXd>& ap_weights,
                                 const SharedApMatcherOptions& options)
    : options_(options) {
  ValidateOptions(options_);
  const Eigen::Index n = reference_rss_dbm.rows();
  const Eigen::Index k = reference_rss_dbm.cols();
  CheckArgument(n <= std::numeric_limits<std::int32_t>::max(), "reference_rss_dbm",
                "has too many rows (more than 2^31 - 1)");
  CheckRssEntries(reference_rss_dbm, "reference_rss_dbm");
  if (ap_weights.size() != 0) {
    CheckArgument(ap_weights.size() == k, "ap_weights",
                  "expected " + std::to_string(k) + " entries (one per column of 'reference_rss_dbm'), got " +
                      std::to_string(ap_weights.size()));
    for (Eigen::Index i = 0; i < k; ++i) {
      CheckArgument(std::isfinite(ap_weights[i]) && ap_weights[i] >= 0.0, "ap_weights",
                    DescribeEntry(i, 0, true) + " must be finite and >= 0, got " + FormatValue(ap_weights[i]));
    }
  }
  auto index = std::make_unique<internal::SharedApIndex>();
  index->num_references = n;
  index->num_aps = k;
  index->ap_weight.assign(static_cast<size_t>(k), 1.0);
  for (Eigen::Index i = 0; i < ap_weights.size(); ++i) index->ap_weight[i] = ap_weights[i];
  index->start.assign(static_cast<size_t>(k) + 1, 0);
  for (Eigen::Index r = 0; r < n; ++r) {
    for (Eigen::Index i = 0; i < k; ++i) {
      if (!std::isnan(reference_rss_dbm(r, i))) ++index->start[i + 1];
    }
  }
  for (Eigen::Index i = 0; i < k; ++i) index->start[i + 1] += index->start[i];
  const size_t nnz = static_cast<size_t>(index->start[k]);
  index->ref.resize(nnz);
  index->value_dbm.resize(nnz);
  index->weight.resize(nnz);
  index->total_weight.assign(static_cast<size_t>(n), 0.0);
  index->ap_max_weight.assign(static_cast<size_t>(k), 0.0);
  index->ref_start.assign(static_cast<size_t>(n) + 1, 0);
  index->ref_ap.resize(nnz);
  index->ref_value_dbm.resize(nnz);
  index->ref_entry_weight.resize(nnz);
  std::vector<std::int64_t> next(index->start.begin(), index->start.end() - 1);
  size_t by_ref = 0;
  for (Eigen::Index r = 0; r < n; ++r) {  // reference order within each AP's list
    for (Eigen::Index i = 0; i < k; ++i) {
      const double b = reference_rss_dbm(r, i);
      if (std::isnan(b)) continue;
      const size_t e = static_cast<size_t>(next[i]++);
      index->ref[e] = static_cast<std::int32_t>(r);
      index->value_dbm[e] = b;
      index->weight[e] = index->ap_weight[i] * Strength(b, options_.strength_scale_db);
      index->total_weight[r] += index->weight[e];
      index->ap_max_weight[i] = std::max(index->ap_max_weight[i], index->weight[e]);
      index->ref_ap[by_ref] = static_cast<std::int32_t>(i);
      index->ref_value_dbm[by_ref] = b;
      index->ref_entry_weight[by_ref] = index->weight[e];
      ++by_ref;
    }
    index->ref_start[r + 1] = static_cast<std::int64_t>(by_ref);
  }
  index->top_ap.assign(static_cast<size_t>(n) * kTopEntries, -1);
  index->top_weight.assign(static_cast<size_t>(n) * kTopEntries, 0.0);
  std::vector<std::pair<double, std::int32_t>> row;
  for (Eigen::Index r = 0; r < n; ++r) {
    row.clear();
    for (std::int64_t e = index->ref_start[r]; e < index->ref_start[r + 1]; ++e) {
      row.emplace_back(-index->ref_entry_weight[e], index->ref_ap[e]);
    }
    const size_t top = std::min<size_t>(row.size(), kTopEntries);
    std::partial_sort(row.begin(), row.begin() + static_cast<std::ptrdiff_t>(top), row.end());
    for (size_t m = 0; m < top; ++m) {
      index->top_ap[static_cast<size_t>(r) * kTopEntries + m] = row[m].second;
      index->top_weight[static_cast<size_t>(r) * kTopEntries + m] = -row[m].first;
    }
  }
  index_ = std::move(index);
}

SharedApMatcher::~SharedApMatcher() = default;
SharedApMatcher::SharedApMatcher(SharedApMatcher&&) noexcept = default;
SharedApMatcher& SharedApMatcher::operator=(SharedApMatcher&&) noexcept = default;

Eigen::Index SharedApMatcher::num_references() const { return index_->num_references; }
Eigen::Index SharedApMatcher::num_access_points() const { return index_->num_aps; }
Eigen::Index SharedApMatcher::num_heard() const { return static_cast<Eigen::Index>(index_->ref.size()); }

namespace {

// Sums of eq. (1) for one query over its APs' posting lists; returns sum_A g f(a).
double Accumulate(const internal::SharedApIndex& index, const double* query, double scale_db,
                  Accumulator* acc) {
  double query_weight = 0.0;
  for (Eigen::Index i = 0; i < index.num_aps; ++i) {
    const double a = query[i];
    if (std::isnan(a)) continue;
    const double w = index.ap_weight[static_cast<size_t>(i)] * Strength(a, scale_db);  // w_i = g_i f(a_i)
    query_weight += w;
    for (std::int64_t e = index.start[i]; e < index.start[i + 1]; ++e) {
      const std::int32_t j = index.ref[e];
      Accumulator::Sums& sj = acc->sums[j];
      if (sj.seen == 0.0) {
        sj.seen = 1.0;
        acc->touched.push_back(j);
      }
      const double diff = a - index.value_dbm[e];
      sj.w += w;                        // sum_{A^B} w_i
      sj.sq += w * diff * diff;         // sum_{A^B} w_i (a_i - b_i)^2
      sj.ref_w += index.weight[e];      // sum_{A^B} g_i f(b_i)
    }
  }
  return query_weight;
}

// rms and u of eq. (1) for reference j from its sums; (inf, 1) when nothing is shared.
std::pair<double, double> RmsAndUnshared(const internal::SharedApIndex& index, const Accumulator::Sums& sj,
                                         double query_weight, std::int32_t j) {
  const double sw = sj.w;
  if (!(sw > 0.0)) return {kInf, 1.0};
  const double rms = std::sqrt(std::max(sj.sq / sw, 0.0));
  const double total = query_weight + index.total_weight[j] - sj.ref_w;  // sum_A + sum_{B\A}
  const double u = std::clamp(1.0 - sw / total, 0.0, 1.0);
  return {rms, u};
}

// rms and u of eq. (1) for reference j after Accumulate.
std::pair<double, double> RmsAndUnshared(const internal::SharedApIndex& index, const Accumulator& acc,
                                         double query_weight, std::int32_t j) {
  return RmsAndUnshared(index, acc.sums[j], query_weight, j);
}

// Runs fn(query, accumulator) for every query, blocks of kQueryBlock split over threads.
template <typename Fn>
void ForEachQuery(const internal::SharedApIndex& index, Eigen::Index num_queries, int num_threads, Fn fn) {
  const Eigen::Index blocks = (num_queries + kQueryBlock - 1) / kQueryBlock;
  if (blocks == 0) return;
  ParallelForRuns(static_cast<int>(blocks), num_threads, 0, [&](int block, RandomStream&) {
    std::unique_ptr<Accumulator> acc;
    {
      const std::lock_guard<std::mutex> lock(index.scratch_mutex);
      if (!index.scratch.empty()) {
        acc = std::move(index.scratch.back());
        index.scratch.pop_back();
      }
    }
    if (!acc) acc = std::make_unique<Accumulator>(index.num_references, index.num_aps);
    const Eigen::Index end = std::min<Eigen::Index>(num_queries, (block + 1) * kQueryBlock);
    for (Eigen::Index q = block * kQueryBlock; q < end; ++q) {
      fn(q, acc.get());
      acc->Clear();
    }
    const std::lock_guard<std::mutex> lock(index.scratch_mutex);
    index.scratch.push_back(std::move(acc));
  });
}

// The k best (d, reference) of a query by the full pass over all its APs' posting lists, best
// first, in acc->best (d finite only; ties by reference index).
void SelectFull(const internal::SharedApIndex& index, const double* query, const SharedApMatcherOptions& o,
                Eigen::Index k, Accumulator* acc) {
  const double query_weight = Accumulate(index, query, o.strength_scale_db, acc);
  acc->best.clear();
  for (std::int32_t j : acc->touched) {
    const auto [rms, u] = RmsAndUnshared(index, *acc, query_weight, j);
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
void ExactSums(const internal::SharedApIndex& index, const Accumulator::QueryEntry* query,
               const std::int32_t* refs, Accumulator::Sums* out) {
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
    const Accumulator::QueryEntry& q = query[index.ref_ap[x]];
    const double diff = q.a - index.ref_value_dbm[x];
    sw[c] += q.w;
    sq[c] += q.w * diff * diff;
    rw[c] += index.ref_entry_weight[x] * q.heard;
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
void SelectPruned(const internal::SharedApIndex& index, const double* query, const SharedApMatcherOptions& o,
                  Eigen::Index k, Accumulator* acc) {
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
    acc->by_weight.emplace_back(-w, static_cast<std::int32_t>(i));
  }
  if (!(query_weight > 0.0) || !std::isfinite(query_weight)) return SelectFull(index, query, o, k, acc);
  std::sort(acc->by_weight.begin(), acc->by_weight.end());  // strongest first
  size_t s = 0;
  for (double left = query_weight; s < acc->by_weight.size() && left > kRestFraction * query_weight; ++s) {
    left += acc->by_weight[s].first;
  }
  double rest_w = 0.0, rest_max = 0.0;
  for (size_t m = s; m < acc->by_weight.size(); ++m) {
    rest_w -= acc->by_weight[m].first;
    rest_max += index.ap_max_weight[static_cast<size_t>(acc->by_weight[m].second)];
  }
  acc->first_pass.clear();
  for (size_t m = 0; m < s; ++m) acc->first_pass.push_back(acc->by_weight[m].second);
  std::sort(acc->first_pass.begin(), acc->first_pass.end());
  // First pass: partial sums over S.
  for (std::int32_t i : acc->first_pass) {
    const double a = query[i];
    const double w = acc->dense[static_cast<size_t>(i)].w;
    for (std::int64_t e = index.start[i]; e < index.start[i + 1]; ++e) {
      const std::int32_t j = index.ref[e];
      Accumulator::Sums& sj = acc->sums[j];
      if (sj.seen == 0.0) {
        sj.seen = 1.0;
        acc->touched.push_back(j);
      }
      const double diff = a - index.value_dbm[e];
      sj.w += w;
      sj.sq += w * diff * diff;
      sj.ref_w += index.weight[e];
    }
  }
  acc->best.clear();
  const auto kk = static_cast<size_t>(k);
  auto consider = [&](std::int32_t j, const Accumulator::Sums& sums) {
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
    Accumulator::Sums sums[kLanes];
    ExactSums(index, acc->dense.data(), refs, sums);
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
    const Accumulator::Sums& sj = acc->sums[j];
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
    return SelectFull(index, query, o, k, acc);
  }
  std::sort_heap(acc->best.begin(), acc->best.end());
}

}  // namespace

SharedApParts SharedApMatcher::Parts(const Eigen::Ref<const SharedApRowMatrixXd>& queries_dbm,
                                     int num_threads) const {
  const internal::SharedApIndex& index = *index_;
  CheckShape(queries_dbm, -1, index.num_aps, "queries_dbm");
  CheckRssEntries(queries_dbm, "queries_dbm");
  SharedApParts out;
  out.rms_db.setConstant(queries_dbm.rows(), index.num_references, kInf);
  out.unshared.setConstant(queries_dbm.rows(), index.num_references, 1.0);
  const double scale = options_.strength_scale_db;
  ForEachQuery(index, queries_dbm.rows(), num_threads, [&](Eigen::Index q, Accumulator* acc) {
    const double query_weight = Accumulate(index, queries_dbm.row(q).data(), scale, acc);
    for (std::int32_t j : acc->touched) {
      const auto [rms, u] = RmsAndUnshared(index, *acc, query_weight, j);
      out.rms_db(q, j) = rms;
      out.unshared(q, j) = u;
    }
  });
  return out;
}

SharedApRowMatrixXd SharedApMatcher::Dissimilarity(const Eigen::Ref<const SharedApRowMatrixXd>& queries_dbm,
                                                   int num_threads) const {
  SharedApParts parts = Parts(queries_dbm, num_threads);
  // inf + c u stays inf: d = +inf where nothing is shared.
  parts.rms_db += options_.penalty_db * parts.unshared;
  return std::move(parts.rms_db);
}

SharedApNeighbours SharedApMatcher::Nearest(const Eigen::Ref<const SharedApRowMatrixXd>& queries_dbm,
                                            int num_threads) const {
  const internal::SharedApIndex& index = *index_;
  CheckShape(queries_dbm, -1, index.num_aps, "queries_dbm");
  CheckRssEntries(queries_dbm, "queries_dbm");
  const Eigen::Index num_queries = queries_dbm.rows();
  const Eigen::Index k = std::min<Eigen::Index>(options_.k, index.num_references);
  SharedApNeighbours out;
  out.index.setZero(num_queries, k);
  out.distance_db.setConstant(num_queries, k, kInf);
  out.weight.setZero(num_queries, k);
  if (k == 0) return out;
  const double temperature = options_.temperature_db;
  ForEachQuery(index, num_queries, num_threads, [&](Eigen::Index q, Accumulator* acc) {
    SelectPruned(index, queries_dbm.row(q).data(), options_, k, acc);
    const std::vector<std::pair<double, std::int32_t>>& best = acc->best;
    const auto found = static_cast<Eigen::Index>(best.size());
    for (Eigen::Index m = 0; m < found; ++m) {
      out.index(q, m) = best[static_cast<size_t>(m)].second;
      out.distance_db(q, m) = best[static_cast<size_t>(m)].first;
      // eq. (2): w_j = exp(-(d_j - d_min) / T)
      out.weight(q, m) = std::exp(-(best[static_cast<size_t>(m)].first - best[0].first) / temperature);
    }
    if (found < k) {  // fill with the lowest-numbered references sharing nothing (d = inf, w = 0)
      std::vector<char> taken(static_cast<size_t>(index.num_references), 0);
      for (Eigen::Index m = 0; m < found; ++m) taken[static_cast<size_t>(out.index(q, m))] = 1;
      Eigen::Index m = found;
      for (Eigen::Index j = 0; j < index.num_references && m < k; ++j) {
        if (!taken[static_cast<size_t>(j)]) out.index(q, m++) = j;
      }
    }
  });
  return out;
}

}  // namespace indoorloc::wifi
