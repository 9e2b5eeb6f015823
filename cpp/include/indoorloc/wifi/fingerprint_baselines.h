// Fingerprinting baselines: locate a WiFi scan by matching it against reference fingerprints.
//
// These are the deterministic and probabilistic "matching" methods that paper 004 (§1.2) cites
// as the state of the art it compares against. All four share one interface, FingerprintLocator:
// build it once from R reference fingerprints (R x K RSS matrix, positions, floors, and for Horus
// per-entry variances), then Locate() a batch of Q scans (Q x K).
//
// Let s be a scan and r_i the i-th reference row; d_i = ||s - r_i||_2 is the Euclidean signal
// distance [dB].
//
//  - kNnss, "nearest neighbour in signal space" (RADAR; P. Bahl and V. N. Padmanabhan, "RADAR:
//    an in-building RF-based user location and tracking system", IEEE INFOCOM 2000, pp. 775-784,
//    paper 004's ref. [4]): the estimate is the position of argmin_i d_i. `k` is ignored.
//  - kNnssAvg, "NNSS-AVG" (RADAR's k-nearest-neighbours-in-signal-space variant, Bahl &
//    Padmanabhan 2000; paper 004 §1.2): the unweighted mean position of the k reference rows with
//    the smallest d_i.
//  - kWeightedKnn, weighted k nearest neighbours: the mean of the k nearest positions weighted
//    by w_i = 1 / (d_i + distance_epsilon_db). Usually run on raw training scans (one reference
//    row per scan) rather than on per-point means.
//  - kHorus, probabilistic (M. Youssef and A. Agrawala, "The Horus WLAN location determination
//    system", ACM MobiSys 2005): each reference point i is a Gaussian with mean r_i and diagonal
//    covariance diag(v_i) (APs independent, the same model as paper 004 §1.3 and SignalMap),
//    v_ik floored at variance_floor_db2. The log-likelihood is
//        log p(s | i) = -1/2 sum_k [ (s_k - r_ik)^2 / v_ik + log(2 pi v_ik) ],
//    and with a uniform prior the estimate is the posterior-weighted mean of the k most likely
//    points, weights w_i = exp(log p(s | i) - max_j log p(s | j)) normalised over those k
//    (computed in log space, so no underflow). Horus' "center of mass" of the top-k candidates.
//
// Floors. kNnss and kHorus return the floor of the best match. kNnssAvg and kWeightedKnn take a
// vote among the k neighbours (each counts 1, resp. w_i; a tie goes to the floor of the
// best-ranked neighbour among the tied floors). In every method the position is then averaged
// only over the k neighbours on the chosen floor.
//
// Inputs are "prepared" RSS: not-heard readings already replaced by a floor value (see
// SignalMap::PrepareScans), so every entry must be finite. Neighbours at equal cost are ordered
// by reference row index, so results are deterministic. k larger than R is clamped to R.
//
// Cost: O(Q R K) for the signal distances (computed directly as sums of squared differences, not
// by the |a|^2 - 2ab + |b|^2 expansion, so an identical row has distance exactly 0), plus
// O(Q (R + k log k)) for the selection. Queries are processed in blocks of a few rows per pass
// over the reference matrix (cache reuse), and the blocks are split over threads; results do
// not depend on the thread count.
#pragma once

#include <string>
#include <string_view>

#include <Eigen/Core>

#include "indoorloc/wifi/signal_map.h"  // RowMatrixXd

namespace indoorloc::wifi {

/// The matching rule of a FingerprintLocator.
enum class FingerprintMethod {
  kNnss,         ///< nearest neighbour in signal space (RADAR)
  kNnssAvg,      ///< unweighted mean of the k nearest neighbours
  kWeightedKnn,  ///< mean of the k nearest weighted by 1 / (distance + epsilon)
  kHorus,        ///< posterior-weighted mean of the k most likely points (Gaussian model)
};

/// "nnss", "nnss_avg", "wknn" or "horus".
std::string_view ToString(FingerprintMethod method);
/// Inverse of ToString; throws std::invalid_argument naming `argument` for an unknown name.
FingerprintMethod ParseFingerprintMethod(std::string_view name,
                                         std::string_view argument = "method");

/// Options of FingerprintLocator.
struct FingerprintOptions {
  /// Matching rule.
  FingerprintMethod method = FingerprintMethod::kWeightedKnn;
  /// Number of neighbours (nnss_avg, wknn) or most likely points (horus) averaged; ignored by
  /// nnss. Must be >= 1; clamped to the number of reference rows.
  int k = 4;
  /// wknn only: epsilon [dB] in the weight 1 / (d + epsilon), which keeps an exact match
  /// (d = 0) finite. Must be finite and > 0. An exact match then outweighs a neighbour at 1 dB
  /// by a factor of about 1000.
  double distance_epsilon_db = 1e-3;
  /// horus only: lower bound [dB^2] on every reference variance. Must be finite and > 0.
  /// 4 dB^2 (a 2 dB standard deviation) matches SignalMapOptions::variance_floor_db2.
  double variance_floor_db2 = 4.0;

  /// True if the options are usable; otherwise false with the reason in *error.
  bool IsValid(std::string* error) const;
};

/// Estimates for a batch of Q scans.
struct FingerprintEstimates {
  /// Q x 2 estimated positions [m], in the frame of the reference positions.
  RowMatrixXd positions_m;
  /// Q estimated floor numbers.
  Eigen::VectorXi floors;
  /// Q match scores: Euclidean signal distance [dB] to the best match (nnss, nnss_avg, wknn),
  /// or the negative log-likelihood [nats] of the most likely point (horus). Lower is better.
  Eigen::VectorXd score;
};

/// Locates scans by fingerprint matching against fixed reference rows (see the file comment).
class FingerprintLocator {
 public:
  /// reference_rss_dbm (R x K) prepared RSS [dBm]: per-point means of a signal map (nnss,
  /// nnss_avg, horus) or every raw training scan (wknn on raw scans);
  /// reference_positions_m (R x 2) [m]; reference_floors (R) integer floor numbers;
  /// reference_variance_db2 (R x K) RSS variances [dB^2], or a 0 x 0 matrix when not available
  /// (then horus is invalid; other methods ignore it). Throws std::invalid_argument on invalid
  /// options, R = 0, K = 0, a shape mismatch, a non-finite entry or a negative variance.
  FingerprintLocator(const Eigen::Ref<const RowMatrixXd>& reference_rss_dbm,
                     const Eigen::Ref<const RowMatrixXd>& reference_positions_m,
                     const Eigen::VectorXi& reference_floors,
                     const Eigen::Ref<const RowMatrixXd>& reference_variance_db2,
                     const FingerprintOptions& options = FingerprintOptions());

  /// Locates each row of scans_dbm (Q x K, prepared RSS [dBm], finite). num_threads <= 0 uses
  /// every hardware thread. Throws std::invalid_argument naming 'scans_dbm' on a column count
  /// other than K or a non-finite entry. Q = 0 gives empty estimates.
  FingerprintEstimates Locate(const Eigen::Ref<const RowMatrixXd>& scans_dbm,
                              int num_threads = 1) const;

  const FingerprintOptions& options() const { return options_; }
  FingerprintMethod method() const { return options_.method; }
  /// k as given in the options.
  int k() const { return options_.k; }
  /// Number of neighbours actually used: 1 for nnss, else min(k, R).
  int effective_k() const;
  /// R.
  int num_references() const { return static_cast<int>(reference_rss_dbm_.rows()); }
  /// K.
  int num_access_points() const { return static_cast<int>(reference_rss_dbm_.cols()); }
  /// True if reference variances were given.
  bool has_variances() const { return has_variances_; }

  const RowMatrixXd& reference_rss_dbm() const { return reference_rss_dbm_; }
  const RowMatrixXd& reference_positions_m() const { return reference_positions_m_; }
  const Eigen::VectorXi& reference_floors() const { return reference_floors_; }

 private:
  struct Workspace;  // per-thread scratch buffers, defined in the .cc

  // Locates scans [begin, end) into the (already sized) rows of *out.
  void LocateRange(const Eigen::Ref<const RowMatrixXd>& scans_dbm, Eigen::Index begin,
                   Eigen::Index end, Workspace* workspace, FingerprintEstimates* out) const;
  // Fills row `q` of *out from the costs of one scan against every reference row (squared
  // signal distance, or negative log-likelihood for horus).
  void EstimateFromCosts(const double* cost, Eigen::Index q, Workspace* workspace,
                         FingerprintEstimates* out) const;

  FingerprintOptions options_;
  bool has_variances_ = false;
  RowMatrixXd reference_rss_dbm_;
  RowMatrixXd reference_positions_m_;
  Eigen::VectorXi reference_floors_;
  // Dense index in [0, num_distinct_floors_) of each reference row's floor (for the vote).
  Eigen::VectorXi floor_index_;
  int num_distinct_floors_ = 0;
  // horus only: 1 / max(v, floor) (R x K) and 1/2 sum_k log(2 pi max(v_k, floor)) (R).
  RowMatrixXd inverse_variance_;
  Eigen::VectorXd log_normalizer_;
};

}  // namespace indoorloc::wifi
