#include "indoorloc/wifi/fingerprint_baselines.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <sstream>
#include <thread>
#include <vector>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "rss_limits.h"

namespace indoorloc::wifi {
namespace {

// Scans matched together in one pass over the reference rows: each reference row (K doubles)
// stays in L1 while the kBlock scans (154 kB for K = 600) stay in L2, so the reference matrix
// is read from memory once per block instead of once per scan. Measured on R = 10^4, K = 600
// (one core, SSE2): 1.5 ms/scan with 8, 1.2 with 16, 1.1 with 32 or 64. Block boundaries are
// global (multiples of kBlock), not per thread.
constexpr Eigen::Index kBlock = 32;

constexpr double kLogTwoPi = 1.8378770664093454836;  // log(2 pi)

std::string FormatValue(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

}  // namespace

std::string_view ToString(FingerprintMethod method) {
  switch (method) {
    case FingerprintMethod::kNnss: return "nnss";
    case FingerprintMethod::kNnssAvg: return "nnss_avg";
    case FingerprintMethod::kWeightedKnn: return "wknn";
    case FingerprintMethod::kHorus: return "horus";
  }
  return "unknown";
}

FingerprintMethod ParseFingerprintMethod(std::string_view name, std::string_view argument) {
  for (FingerprintMethod m : {FingerprintMethod::kNnss, FingerprintMethod::kNnssAvg,
                              FingerprintMethod::kWeightedKnn, FingerprintMethod::kHorus}) {
    if (name == ToString(m)) return m;
  }
  ThrowInvalidArgument(argument, "unknown fingerprint method '" + std::string(name) +
                                     "' (expected nnss, nnss_avg, wknn or horus)");
}

bool FingerprintOptions::IsValid(std::string* error) const {
  auto fail = [error](const std::string& reason) {
    if (error != nullptr) *error = reason;
    return false;
  };
  switch (method) {
    case FingerprintMethod::kNnss:
    case FingerprintMethod::kNnssAvg:
    case FingerprintMethod::kWeightedKnn:
    case FingerprintMethod::kHorus:
      break;
    default:
      return fail("method is not a FingerprintMethod");
  }
  if (k < 1) return fail("k must be >= 1, got " + std::to_string(k));
  if (!(std::isfinite(distance_epsilon_db) && distance_epsilon_db > 0.0)) {
    return fail("distance_epsilon_db must be finite and > 0, got " +
                FormatValue(distance_epsilon_db));
  }
  if (!(std::isfinite(variance_floor_db2) && variance_floor_db2 > 0.0)) {
    return fail("variance_floor_db2 must be finite and > 0, got " +
                FormatValue(variance_floor_db2));
  }
  return true;
}

struct FingerprintLocator::Workspace {
  std::vector<double> cost;   // kBlock x R, row j = costs of scan j of the block
  std::vector<int> order;     // R: reference rows, best first after the selection
  std::vector<double> votes;  // num_distinct_floors_: floor vote totals, all zero between uses
};

FingerprintLocator::FingerprintLocator(const Eigen::Ref<const RowMatrixXd>& reference_rss_dbm,
                                       const Eigen::Ref<const RowMatrixXd>& reference_positions_m,
                                       const Eigen::VectorXi& reference_floors,
                                       const Eigen::Ref<const RowMatrixXd>& reference_variance_db2,
                                       const FingerprintOptions& options)
    : options_(options) {
  ValidateOptions(options_);
  const Eigen::Index num_rows = reference_rss_dbm.rows();
  const Eigen::Index num_aps = reference_rss_dbm.cols();
  CheckArgument(num_rows > 0, "reference_rss_dbm",
                "has no rows (at least one reference fingerprint is needed)");
  CheckArgument(num_aps > 0, "reference_rss_dbm",
                "has no columns (at least one access point is needed)");
  CheckArgument(num_rows <= Eigen::Index{std::numeric_limits<int>::max()}, "reference_rss_dbm",
                "has too many rows");
  CheckFinite(reference_rss_dbm, "reference_rss_dbm");
  internal::CheckRss(reference_rss_dbm, "reference_rss_dbm");
  CheckShape(reference_positions_m, num_rows, 2, "reference_positions_m");
  CheckFinite(reference_positions_m, "reference_positions_m");
  CheckArgument(reference_floors.size() == num_rows, "reference_floors",
                "expected length " + std::to_string(num_rows) + " (the rows of reference_rss_dbm), got " +
                    std::to_string(reference_floors.size()));

  has_variances_ = !(reference_variance_db2.rows() == 0 && reference_variance_db2.cols() == 0);
  if (has_variances_) {
    CheckShape(reference_variance_db2, num_rows, num_aps, "reference_variance_db2");
    CheckFinite(reference_variance_db2, "reference_variance_db2");
    for (Eigen::Index i = 0; i < num_rows; ++i) {
      for (Eigen::Index j = 0; j < num_aps; ++j) {
        const double v = reference_variance_db2(i, j);
        if (v < 0.0) {
          ThrowInvalidArgument("reference_variance_db2", DescribeEntry(i, j, false) +
                                                             " is negative (" + FormatValue(v) +
                                                             ")");
        }
      }
    }
  }
  if (options_.method == FingerprintMethod::kHorus && !has_variances_) {
    ThrowInvalidArgument("reference_variance_db2",
                         "is required by method 'horus' (got a 0 x 0 matrix: no variances)");
  }

  reference_rss_dbm_ = reference_rss_dbm;
  reference_positions_m_ = reference_positions_m;
  reference_floors_ = reference_floors;

  // Dense floor indices for the vote.
  std::map<int, int> floor_to_index;
  for (Eigen::Index i = 0; i < num_rows; ++i) floor_to_index.emplace(reference_floors_[i], 0);
  int next = 0;
  for (auto& entry : floor_to_index) entry.second = next++;
  num_distinct_floors_ = next;
  floor_index_.resize(num_rows);
  for (Eigen::Index i = 0; i < num_rows; ++i) {
    floor_index_[i] = floor_to_index.at(reference_floors_[i]);
  }

  if (options_.method == FingerprintMethod::kHorus) {
    const RowMatrixXd floored = reference_variance_db2.cwiseMax(options_.variance_floor_db2);
    inverse_variance_ = floored.cwiseInverse();
    // log_normalizer_i = 1/2 sum_k log(2 pi v_ik): the Gaussian's normalising constant.
    log_normalizer_ =
        0.5 * (floored.array().log() + kLogTwoPi).rowwise().sum().matrix();
  }
}

int FingerprintLocator::effective_k() const {
  if (options_.method == FingerprintMethod::kNnss) return 1;
  return std::min(options_.k, num_references());
}

FingerprintEstimates FingerprintLocator::Locate(const Eigen::Ref<const RowMatrixXd>& scans_dbm,
                                                int num_threads) const {
  const Eigen::Index num_aps = reference_rss_dbm_.cols();
  if (scans_dbm.cols() != num_aps) {
    ThrowInvalidArgument("scans_dbm",
                         "has " + std::to_string(scans_dbm.cols()) +
                             " columns but the reference fingerprints have " +
                             std::to_string(num_aps) + " access points (expected shape (any, " +
                             std::to_string(num_aps) + "), got (" +
                             std::to_string(scans_dbm.rows()) + ", " +
                             std::to_string(scans_dbm.cols()) + "))");
  }
  CheckFinite(scans_dbm, "scans_dbm");
  internal::CheckRss(scans_dbm, "scans_dbm");

  const Eigen::Index num_scans = scans_dbm.rows();
  FingerprintEstimates out;
  out.positions_m.resize(num_scans, 2);
  out.floors.resize(num_scans);
  out.score.resize(num_scans);
  if (num_scans == 0) return out;

  const Eigen::Index num_blocks = (num_scans + kBlock - 1) / kBlock;
  const int threads = static_cast<int>(
      std::min<Eigen::Index>(ResolveThreadCount(num_threads), num_blocks));
  const size_t num_rows = static_cast<size_t>(num_references());
  const size_t block_rows = static_cast<size_t>(std::min(kBlock, num_scans));

  // All scratch memory is allocated here, in the caller's thread: the workers do not allocate.
  std::vector<Workspace> workspaces(static_cast<size_t>(threads));
  for (Workspace& ws : workspaces) {
    ws.cost.resize(block_rows * num_rows);
    ws.order.resize(num_rows);
    ws.votes.assign(static_cast<size_t>(num_distinct_floors_), 0.0);
  }

  // Thread t handles the contiguous blocks [t B / T, (t + 1) B / T). Every scan is processed by
  // the same code on the same data whatever T is, so the results do not depend on T.
  auto run = [&](int t) {
    const Eigen::Index first_block = num_blocks * t / threads;
    const Eigen::Index last_block = num_blocks * (t + 1) / threads;
    LocateRange(scans_dbm, first_block * kBlock, std::min(last_block * kBlock, num_scans),
                &workspaces[static_cast<size_t>(t)], &out);
  };

  if (threads == 1) {
    run(0);
    return out;
  }
  std::exception_ptr first_error;
  std::mutex error_mutex;
  std::vector<std::thread> pool;
  pool.reserve(static_cast<size_t>(threads));
  auto guarded = [&](int t) {
    try {
      run(t);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!first_error) first_error = std::current_exception();
    }
  };
  try {
    for (int t = 0; t < threads; ++t) pool.emplace_back(guarded, t);
  } catch (...) {
    for (std::thread& th : pool) th.join();
    throw;
  }
  for (std::thread& th : pool) th.join();
  if (first_error) std::rethrow_exception(first_error);
  return out;
}

void FingerprintLocator::LocateRange(const Eigen::Ref<const RowMatrixXd>& scans_dbm,
                                     Eigen::Index begin, Eigen::Index end, Workspace* workspace,
                                     FingerprintEstimates* out) const {
  const Eigen::Index num_rows = reference_rss_dbm_.rows();
  const bool horus = options_.method == FingerprintMethod::kHorus;
  double* cost = workspace->cost.data();
  for (Eigen::Index block = begin; block < end; block += kBlock) {
    const Eigen::Index n = std::min(kBlock, end - block);
    // Reference row outer, scans inner: row r is read from memory once per block.
    for (Eigen::Index r = 0; r < num_rows; ++r) {
      const auto mean = reference_rss_dbm_.row(r).array();
      if (horus) {
        // Negative log-likelihood: 1/2 sum_k (s_k - m_rk)^2 / v_rk + 1/2 sum_k log(2 pi v_rk).
        const auto inverse_variance = inverse_variance_.row(r).array();
        const double log_normalizer = log_normalizer_[r];
        for (Eigen::Index j = 0; j < n; ++j) {
          cost[j * num_rows + r] =
              0.5 * ((scans_dbm.row(block + j).array() - mean).square() * inverse_variance)
                        .sum() +
              log_normalizer;
        }
      } else {
        // Squared Euclidean signal distance, summed directly (exactly 0 for an identical row).
        for (Eigen::Index j = 0; j < n; ++j) {
          cost[j * num_rows + r] = (scans_dbm.row(block + j).array() - mean).square().sum();
        }
      }
    }
    for (Eigen::Index j = 0; j < n; ++j) {
      EstimateFromCosts(cost + j * num_rows, block + j, workspace, out);
    }
  }
}

void FingerprintLocator::EstimateFromCosts(const double* cost, Eigen::Index q,
                                           Workspace* workspace,
                                           FingerprintEstimates* out) const {
  const int num_rows = num_references();
  const int k = effective_k();
  int* order = workspace->order.data();

  // Selection of the k lowest costs, best first; equal costs are ordered by row index.
  if (k == 1) {
    int best = 0;
    for (int r = 1; r < num_rows; ++r) {
      if (cost[r] < cost[best]) best = r;
    }
    order[0] = best;
  } else {
    auto better = [cost](int a, int b) {
      return cost[a] < cost[b] || (cost[a] == cost[b] && a < b);
    };
    std::iota(order, order + num_rows, 0);
    if (k < num_rows) std::nth_element(order, order + (k - 1), order + num_rows, better);
    std::sort(order, order + k, better);
  }
  const double best_cost = cost[order[0]];

  // Weight of the neighbour of rank j.
  const FingerprintMethod method = options_.method;
  const double epsilon = options_.distance_epsilon_db;
  auto weight = [&](int j) {
    switch (method) {
      case FingerprintMethod::kWeightedKnn:
        return 1.0 / (std::sqrt(cost[order[j]]) + epsilon);
      case FingerprintMethod::kHorus:
        // Normalised likelihood, in log space: exp(log p_j - max log p) in (0, 1].
        return std::exp(best_cost - cost[order[j]]);
      case FingerprintMethod::kNnss:
      case FingerprintMethod::kNnssAvg:
        break;
    }
    return 1.0;
  };

  // Floor: of the best match (nnss, horus) or by weighted vote (nnss_avg, wknn); a tie goes to
  // the tied floor whose best neighbour ranks first.
  int floor_index = floor_index_[order[0]];
  if (k > 1 && num_distinct_floors_ > 1 &&
      (method == FingerprintMethod::kNnssAvg || method == FingerprintMethod::kWeightedKnn)) {
    double* votes = workspace->votes.data();
    for (int j = 0; j < k; ++j) votes[floor_index_[order[j]]] += weight(j);
    double best_votes = -1.0;
    for (int j = 0; j < k; ++j) {
      const int f = floor_index_[order[j]];
      if (votes[f] > best_votes) {
        best_votes = votes[f];
        floor_index = f;
      }
    }
    for (int j = 0; j < k; ++j) votes[floor_index_[order[j]]] = 0.0;
  }

  // Position: weighted mean over the neighbours on the chosen floor (at least one exists).
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  double total_weight = 0.0;
  for (int j = 0; j < k; ++j) {
    if (floor_index_[order[j]] != floor_index) continue;
    const double w = weight(j);
    sum += w * reference_positions_m_.row(order[j]).transpose();
    total_weight += w;
  }
  out->positions_m.row(q) = (sum / total_weight).transpose();

  // The chosen floor's number: any neighbour on it has it.
  int floor_number = 0;
  for (int j = 0; j < k; ++j) {
    if (floor_index_[order[j]] == floor_index) {
      floor_number = reference_floors_[order[j]];
      break;
    }
  }
  out->floors[q] = floor_number;
  out->score[q] = method == FingerprintMethod::kHorus ? best_cost : std::sqrt(best_cost);
}

}  // namespace indoorloc::wifi
