// Shared-AP dissimilarity and kNN (indoorloc/wifi/shared_ap_matcher.h): per-AP posting lists of
// the references, one sparse accumulation per query.
#include "indoorloc/wifi/shared_ap_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
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
  explicit Accumulator(Eigen::Index n) : sums(static_cast<size_t>(n)) {}
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
  std::vector<std::int64_t> next(index->start.begin(), index->start.end() - 1);
  for (Eigen::Index r = 0; r < n; ++r) {  // reference order within each AP's list
    for (Eigen::Index i = 0; i < k; ++i) {
      const double b = reference_rss_dbm(r, i);
      if (std::isnan(b)) continue;
      const size_t e = static_cast<size_t>(next[i]++);
      index->ref[e] = static_cast<std::int32_t>(r);
      index->value_dbm[e] = b;
      index->weight[e] = index->ap_weight[i] * Strength(b, options_.strength_scale_db);
      index->total_weight[r] += index->weight[e];
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

// rms and u of eq. (1) for reference j after Accumulate; (inf, 1) when nothing is shared.
std::pair<double, double> RmsAndUnshared(const internal::SharedApIndex& index, const Accumulator& acc,
                                         double query_weight, std::int32_t j) {
  const Accumulator::Sums& sj = acc.sums[j];
  const double sw = sj.w;
  if (!(sw > 0.0)) return {kInf, 1.0};
  const double rms = std::sqrt(std::max(sj.sq / sw, 0.0));
  const double total = query_weight + index.total_weight[j] - sj.ref_w;  // sum_A + sum_{B\A}
  const double u = std::clamp(1.0 - sw / total, 0.0, 1.0);
  return {rms, u};
}

// Runs fn(query, accumulator) for every query, blocks of kQueryBlock split over threads.
template <typename Fn>
void ForEachQuery(const internal::SharedApIndex& index, Eigen::Index num_queries, int num_threads, Fn fn) {
  const Eigen::Index blocks = (num_queries + kQueryBlock - 1) / kQueryBlock;
  if (blocks == 0) return;
  ParallelForRuns(static_cast<int>(blocks), num_threads, 0, [&](int block, RandomStream&) {
    Accumulator acc(index.num_references);
    const Eigen::Index end = std::min<Eigen::Index>(num_queries, (block + 1) * kQueryBlock);
    for (Eigen::Index q = block * kQueryBlock; q < end; ++q) {
      fn(q, &acc);
      acc.Clear();
    }
  });
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
  const double scale = options_.strength_scale_db;
  const double penalty = options_.penalty_db;
  const double temperature = options_.temperature_db;
  ForEachQuery(index, num_queries, num_threads, [&](Eigen::Index q, Accumulator* acc) {
    const double query_weight = Accumulate(index, queries_dbm.row(q).data(), scale, acc);
    std::vector<std::pair<double, std::int32_t>> candidates;  // (d, reference) with d finite
    candidates.reserve(acc->touched.size());
    for (std::int32_t j : acc->touched) {
      const auto [rms, u] = RmsAndUnshared(index, *acc, query_weight, j);
      if (std::isfinite(rms)) candidates.emplace_back(rms + penalty * u, j);
    }
    const auto found = static_cast<Eigen::Index>(std::min<size_t>(candidates.size(), static_cast<size_t>(k)));
    // (d, reference) order: ties go to the lower reference index.
    std::partial_sort(candidates.begin(), candidates.begin() + found, candidates.end());
    for (Eigen::Index m = 0; m < found; ++m) {
      out.index(q, m) = candidates[static_cast<size_t>(m)].second;
      out.distance_db(q, m) = candidates[static_cast<size_t>(m)].first;
      // eq. (2): w_j = exp(-(d_j - d_min) / T)
      out.weight(q, m) = std::exp(-(candidates[static_cast<size_t>(m)].first - candidates[0].first) / temperature);
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
