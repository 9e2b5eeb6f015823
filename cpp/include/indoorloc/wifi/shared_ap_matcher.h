// Shared-access-point fingerprint matcher: a dissimilarity built on the APs two fingerprints both
// heard plus the RSS difference there, and the k nearest references under it.
//
// When to use: matching sparse WiFi fingerprints (a query hears a few per cent of a building's
// APs; "not heard" is NaN, not a floor value) against many references, e.g. crowdsourced
// fingerprints pooled along survey walks (python indoorloc.wifi_matcher, the fusion tracker's
// WiFi fixes) or the training scans of a public fingerprint dataset (`indoorloc wifi evaluate`,
// method "shared_knn"). One matcher serves both (issue 25).
//
// With A, B the APs heard by a query a and a reference b, per-AP reliability weights g_i
// (given; python wifi_matcher.ap_reliability) and strength weights
// f(x) = exp((x - (-40 dBm)) / beta) (1 when beta = 0: off), in dB:
//
//     w_i       = g_i f(a_i)                                   (the query's weight of AP i)
//     rms(a, b) = sqrt( sum_{A^B} w_i (a_i - b_i)^2 / sum_{A^B} w_i )
//     u(a, b)   = 1 - sum_{A^B} w_i / ( sum_A g_i f(a_i) + sum_{B\A} g_i f(b_i) )
//     d(a, b)   = rms(a, b) + c u(a, b)                         (eq. 1)
//
// u is the weighted fraction of the APs heard by only one of the two (0: same set; clipped to
// [0, 1]); where no AP with w_i > 0 is shared, d = +inf (rms = +inf, u = 1). The strength pivot
// -40 dBm only scales every f by one constant (it cancels in rms and u); it keeps f finite.
// The k nearest references get weights exp(-(d_j - d_min) / T) (0 where d_j = inf), eq. (2).
//
// Cost: Nearest reads the posting lists (per AP, the references that heard it) of the query's
// strongest APs only (the fewest, by weight per list entry, that leave at most a fifth of its
// weight sum_A g f(a) to the rest),
// bounds every reference's d from below with them, and computes d exactly, from the reference's
// own entries, only for references whose bound is below the k-th best d found so far (a
// threshold search: the result is the full computation's, bit for bit: same sums in the same
// order, same ranking). Parts and Dissimilarity read every query AP's posting list (a sparse
// product, never the dense Q x N x K). Per-query scratch is reused across calls. References of
// whole dBm in [-128, 127] (phones' readings) are stored in one byte per heard entry, a
// reference row in two (N <= 65,536): 3 bytes per entry instead of 20, with the same results.
// Queries are split over threads in fixed blocks; each query's result is computed by the same
// code on the same data whatever the thread count, so results do not depend on it. Neighbours
// at equal d are ordered by reference index.
//
// References: the Kaggle "Indoor Location & Navigation" 2021 winners' WiFi features (shared-AP
// counts with the RSS difference); Bahl & Padmanabhan, RADAR (INFOCOM 2000) for kNN matching.
#pragma once

#include <memory>
#include <string>

#include <Eigen/Core>

namespace indoorloc::wifi {

namespace internal {
struct SharedApIndex;  // the references' per-AP posting lists (shared_ap_matcher.cc)
}  // namespace internal

/// Options of SharedApMatcher. Defaults are the fusion tracker's WiFi fix settings
/// (python indoorloc.wifi_fixes.FixSettings), chosen there by leave-one-floor-out cross-validation
/// over six floors of the ILC 2020 site (docs/fusion_real.md, "WiFi as fixes").
struct SharedApMatcherOptions {
  /// c of eq. (1): cost of a fully unshared AP set [dB]. Finite, in [0, 1e4]. Default 160.
  double penalty_db = 160.0;
  /// beta of the strength weights f [dB]; 0 turns them off, else >= 1 (finite, <= 1e4). Default 5.
  double strength_scale_db = 5.0;
  /// Neighbours returned by Nearest (>= 1; clamped to the number of references). Default 20.
  int k = 20;
  /// T of eq. (2) [dB], finite and > 0. Default 3.
  double temperature_db = 3.0;

  /// True if the options are usable; otherwise false with the reason in *error.
  bool IsValid(std::string* error) const;
};

using SharedApRowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using SharedApRowMatrixXi =
    Eigen::Matrix<Eigen::Index, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// rms and u of eq. (1) for Q queries against N references (Q x N each); d = rms + c u.
struct SharedApParts {
  SharedApRowMatrixXd rms_db;
  SharedApRowMatrixXd unshared;
};

/// The k nearest references of Q queries, best first (Q x k each).
struct SharedApNeighbours {
  /// Reference rows. Where fewer than k references share an AP with the query, the rest are the
  /// lowest-numbered other references, at d = +inf and weight 0 (every index is a valid row).
  SharedApRowMatrixXi index;
  SharedApRowMatrixXd distance_db; ///< d of eq. (1) [dB]; +inf where nothing is shared
  SharedApRowMatrixXd weight;      ///< eq. (2) in [0, 1], 1 for the best; 0 where d = inf
};

/// Matches fingerprints against fixed references with the shared-AP dissimilarity (file comment).
class SharedApMatcher {
 public:
  /// reference_rss_dbm (N x K) RSS [dBm], NaN = not heard, any other entry finite within
  /// +-1000 dBm; ap_weights (K) g_i >= 0 finite, or empty for all 1. Throws
  /// std::invalid_argument naming the argument on bad input or invalid options.
  SharedApMatcher(const Eigen::Ref<const SharedApRowMatrixXd>& reference_rss_dbm,
                  const Eigen::Ref<const Eigen::VectorXd>& ap_weights,
                  const SharedApMatcherOptions& options = SharedApMatcherOptions());
  ~SharedApMatcher();
  SharedApMatcher(SharedApMatcher&&) noexcept;
  SharedApMatcher& operator=(SharedApMatcher&&) noexcept;

  /// rms and u of every query (Q x K, same columns and conventions as the references) against
  /// every reference. num_threads <= 0: every hardware thread.
  SharedApParts Parts(const Eigen::Ref<const SharedApRowMatrixXd>& queries_dbm,
                      int num_threads = 1) const;
  /// d of eq. (1) with options().penalty_db (Q x N) [dB].
  SharedApRowMatrixXd Dissimilarity(const Eigen::Ref<const SharedApRowMatrixXd>& queries_dbm,
                                    int num_threads = 1) const;
  /// The min(k, N) nearest references of every query with eq. (2)'s weights, without forming
  /// the Q x N matrix.
  SharedApNeighbours Nearest(const Eigen::Ref<const SharedApRowMatrixXd>& queries_dbm,
                             int num_threads = 1) const;

  const SharedApMatcherOptions& options() const { return options_; }
  Eigen::Index num_references() const;
  Eigen::Index num_access_points() const;
  /// Entries heard in the references (the posting lists' total length).
  Eigen::Index num_heard() const;

 private:
  SharedApMatcherOptions options_;
  std::unique_ptr<const internal::SharedApIndex> index_;
};

}  // namespace indoorloc::wifi
