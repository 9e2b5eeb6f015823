// Shared-AP dissimilarity and kNN (indoorloc/wifi/shared_ap_matcher.h): the index of the references
// (shared_ap_index.h) built, queries checked and split over threads; the searches are in
// shared_ap_search.cc.
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
#include "shared_ap_index.h"

namespace indoorloc::wifi {
namespace {

using internal::SharedApScratch;
using internal::Strength;
using internal::kTopEntries;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMaxAbsRssDbm = 1e3;
// Queries per parallel task: small enough to balance two threads on a walk's few hundred queries.
constexpr Eigen::Index kQueryBlock = 16;

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
  const double scale = options_.strength_scale_db;
  index->num_references = n;
  index->num_aps = k;
  index->ap_weight.assign(static_cast<size_t>(k), 1.0);
  for (Eigen::Index i = 0; i < ap_weights.size(); ++i) index->ap_weight[i] = ap_weights[i];
  index->start.assign(static_cast<size_t>(k) + 1, 0);
  index->compact = true;
  for (Eigen::Index r = 0; r < n; ++r) {
    for (Eigen::Index i = 0; i < k; ++i) {
      const double b = reference_rss_dbm(r, i);
      if (std::isnan(b)) continue;
      ++index->start[i + 1];
      if (!(b >= -128.0 && b <= 127.0 && b == std::nearbyint(b))) index->compact = false;
    }
  }
  for (Eigen::Index i = 0; i < k; ++i) index->start[i + 1] += index->start[i];
  const size_t nnz = static_cast<size_t>(index->start[k]);
  const bool compact = index->compact;
  if (compact) {
    index->strength.resize(256);
    for (int v = 0; v < 256; ++v) index->strength[static_cast<size_t>(v)] = Strength(v - 128.0, scale);
  }
  const bool narrow = n <= 65536;  // reference rows in two bytes
  (narrow ? index->ref16.resize(nnz) : index->ref.resize(nnz));
  (compact ? index->value_i8.resize(nnz) : index->value_dbm.resize(nnz));
  if (!compact) index->weight.resize(nnz);
  index->total_weight.assign(static_cast<size_t>(n), 0.0);
  index->ap_max_weight.assign(static_cast<size_t>(k), 0.0);
  index->ref_start.assign(static_cast<size_t>(n) + 1, 0);
  index->ref_ap.resize(nnz);
  (compact ? index->ref_value_i8.resize(nnz) : index->ref_value_dbm.resize(nnz));
  if (!compact) index->ref_entry_weight.resize(nnz);
  index->top_ap.assign(static_cast<size_t>(n) * kTopEntries, -1);
  index->top_weight.assign(static_cast<size_t>(n) * kTopEntries, 0.0);
  std::vector<std::int64_t> next(index->start.begin(), index->start.end() - 1);
  std::vector<std::pair<double, std::int32_t>> row;  // (-g f(b), AP) of a reference
  size_t by_ref = 0;
  for (Eigen::Index r = 0; r < n; ++r) {  // reference order within each AP's list
    row.clear();
    for (Eigen::Index i = 0; i < k; ++i) {
      const double b = reference_rss_dbm(r, i);
      if (std::isnan(b)) continue;
      const size_t e = static_cast<size_t>(next[i]++);
      // g_i f(b): in the compact storage the search recomputes it as g_i x strength[b + 128],
      // the same product of the same numbers.
      const double w = index->ap_weight[i] * Strength(b, scale);
      if (narrow) {
        index->ref16[e] = static_cast<std::uint16_t>(r);
      } else {
        index->ref[e] = static_cast<std::int32_t>(r);
      }
      index->ref_ap[by_ref] = static_cast<std::int32_t>(i);
      if (compact) {
        index->value_i8[e] = index->ref_value_i8[by_ref] = static_cast<std::int8_t>(b);
      } else {
        index->value_dbm[e] = index->ref_value_dbm[by_ref] = b;
        index->weight[e] = index->ref_entry_weight[by_ref] = w;
      }
      index->total_weight[r] += w;
      index->ap_max_weight[i] = std::max(index->ap_max_weight[i], w);
      row.emplace_back(-w, static_cast<std::int32_t>(i));
      ++by_ref;
    }
    index->ref_start[r + 1] = static_cast<std::int64_t>(by_ref);
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
Eigen::Index SharedApMatcher::num_heard() const { return static_cast<Eigen::Index>(index_->start.back()); }

namespace {

// Runs fn(query, accumulator) for every query, blocks of kQueryBlock split over threads.
template <typename Fn>
void ForEachQuery(const internal::SharedApIndex& index, Eigen::Index num_queries, int num_threads, Fn fn) {
  const Eigen::Index blocks = (num_queries + kQueryBlock - 1) / kQueryBlock;
  if (blocks == 0) return;
  ParallelForRuns(static_cast<int>(blocks), num_threads, 0, [&](int block, RandomStream&) {
    std::unique_ptr<SharedApScratch> acc;
    {
      const std::lock_guard<std::mutex> lock(index.scratch_mutex);
      if (!index.scratch.empty()) {
        acc = std::move(index.scratch.back());
        index.scratch.pop_back();
      }
    }
    if (!acc) acc = std::make_unique<SharedApScratch>(index.num_references, index.num_aps);
    const Eigen::Index end = std::min<Eigen::Index>(num_queries, (block + 1) * kQueryBlock);
    for (Eigen::Index q = block * kQueryBlock; q < end; ++q) {
      fn(q, acc.get());
      acc->Clear();
    }
    const std::lock_guard<std::mutex> lock(index.scratch_mutex);
    index.scratch.push_back(std::move(acc));
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
  ForEachQuery(index, queries_dbm.rows(), num_threads, [&](Eigen::Index q, SharedApScratch* acc) {
    const double query_weight = internal::AccumulateAll(index, queries_dbm.row(q).data(), scale, acc);
    for (std::int32_t j : acc->touched) {
      const auto [rms, u] = internal::RmsAndUnshared(index, acc->sums[j], query_weight, j);
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
  ForEachQuery(index, num_queries, num_threads, [&](Eigen::Index q, SharedApScratch* acc) {
    internal::SelectNearest(index, queries_dbm.row(q).data(), options_, k, acc);
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
