// RSS signal map: per reference point and access point (AP), the mean and variance of the
// received signal strength (paper 004, §1.3 and §5.4).
//
// The model (paper 004, §1.3 and §4): at a position z the RSS vector v is Gaussian with mean
// m(z) and a diagonal covariance diag(δ_1(z), ..., δ_K(z)) (APs independent). The map stores
// m and δ at N reference points; DelaunayInterpolator extends them to the whole plane.
//
// "Not heard" readings. A scan lists an RSS for every AP; an AP the receiver did not hear is
// coded by a sentinel (+100 dBm in UJI/SURIMI, -200 in RSS/RTT) or NaN. indoorloc uses the
// floor-value model: every not-heard reading is replaced by `not_heard_dbm` (default -105 dBm,
// below every real reading) before the statistics are taken, both when the map is built and
// when a scan is located (ReplaceNotHeard). Thus an AP heard at some points and not at others
// gets a low mean and a large variance where it fades, which the likelihood weighs correctly.
// The detection probability per point and AP is stored too (for AP selection and diagnostics).
//
// Variance. The paper estimates λ = (N - 1) / (N δ) with δ the (biased) variance of the N
// samples, i.e. 1/λ is the unbiased sample variance; indoorloc stores that unbiased variance,
// floored at `variance_floor_db2` (a point with identical readings would otherwise have zero
// variance and an infinite weight).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace indoorloc::wifi {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// How raw scans become a signal map.
struct SignalMapOptions {
  /// Readings equal to this value mean "AP not heard" (NaN always means not heard).
  double not_heard_sentinel = 100.0;
  /// RSS [dBm] that replaces a not-heard reading (floor-value model).
  double not_heard_dbm = -105.0;
  /// Minimum variance [dB^2] of any map entry.
  double variance_floor_db2 = 4.0;
  /// Keep an AP only if it is heard (in at least one scan) at >= this fraction of the
  /// reference points. 0 keeps every AP heard anywhere; APs never heard are always dropped.
  double min_point_fraction = 0.0;

  bool IsValid(std::string* error) const;
};

/// Replaces not-heard readings (sentinel or NaN) of `rss_dbm` by `not_heard_dbm`, in a copy.
RowMatrixXd ReplaceNotHeard(const Eigen::Ref<const RowMatrixXd>& rss_dbm,
                            double not_heard_sentinel, double not_heard_dbm);

/// Reference positions with per-AP RSS mean and variance.
class SignalMap {
 public:
  /// A map from statistics. positions_m (N x 2) [m]; floors (N) integer floor numbers (all 0
  /// for a single floor); mean_dbm and variance_db2 (N x K). Throws std::invalid_argument on
  /// shape mismatch, NaN, non-positive variance, N = 0 or K = 0.
  SignalMap(const Eigen::Ref<const RowMatrixXd>& positions_m, const Eigen::VectorXi& floors,
            const Eigen::Ref<const RowMatrixXd>& mean_dbm,
            const Eigen::Ref<const RowMatrixXd>& variance_db2);

  /// Builds the map from raw scans: rows of rss_dbm (S x K_all) are scans taken at
  /// scan_positions_m (S x 2) on scan_floors (S). Scans at the same (x, y, floor) form one
  /// reference point (positions compared exactly). Applies the not-heard model, the variance
  /// floor and AP selection (the kept AP columns are access_point_indices()).
  static SignalMap FromScans(const Eigen::Ref<const RowMatrixXd>& scan_positions_m,
                             const Eigen::VectorXi& scan_floors,
                             const Eigen::Ref<const RowMatrixXd>& rss_dbm,
                             const SignalMapOptions& options = SignalMapOptions());

  int num_points() const { return static_cast<int>(positions_m_.rows()); }
  int num_access_points() const { return static_cast<int>(mean_dbm_.cols()); }
  const RowMatrixXd& positions_m() const { return positions_m_; }
  const Eigen::VectorXi& floors() const { return floors_; }
  const RowMatrixXd& mean_dbm() const { return mean_dbm_; }
  const RowMatrixXd& variance_db2() const { return variance_db2_; }
  /// Fraction of the scans at each point in which each AP was heard (N x K); all ones for a map
  /// built from statistics.
  const RowMatrixXd& detection_rate() const { return detection_rate_; }
  /// Number of scans behind each point (N); zeros for a map built from statistics.
  const Eigen::VectorXi& scan_counts() const { return scan_counts_; }
  /// Columns of the raw scan matrix kept as this map's APs (identity if built from statistics).
  const Eigen::VectorXi& access_point_indices() const { return access_point_indices_; }
  /// Distinct floors, ascending.
  std::vector<int> distinct_floors() const;

  /// Selects the columns of a raw scan matrix (S x K_all) that this map kept, in map order,
  /// and applies the not-heard model: the input of every locator.
  RowMatrixXd PrepareScans(const Eigen::Ref<const RowMatrixXd>& rss_dbm,
                           double not_heard_sentinel, double not_heard_dbm) const;

  /// Writes the map as text (format in docs/wifi.md: a header line, then one line per point:
  /// x y floor scans mean_1..mean_K variance_1..variance_K detection_1..detection_K).
  void Save(const std::string& path) const;
  /// Reads a map written by Save. Throws std::runtime_error on a malformed file.
  static SignalMap Load(const std::string& path);

 private:
  SignalMap() = default;
  void Validate() const;

  RowMatrixXd positions_m_;
  Eigen::VectorXi floors_;
  RowMatrixXd mean_dbm_;
  RowMatrixXd variance_db2_;
  RowMatrixXd detection_rate_;
  Eigen::VectorXi scan_counts_;
  Eigen::VectorXi access_point_indices_;
};

}  // namespace indoorloc::wifi
