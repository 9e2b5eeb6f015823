// The WiFi observation model of the fusion tracker: the tempered log-likelihood of a WiFi scan
// at a particle's position, from the interpolated mean and variance fields of paper 004's RSS
// model (wifi::RssModel, eq. 6: v_i ~ N(m_i(z), δ_i(z)), APs independent).
//
//   log p(v | z) ≈ τ Σ_{i ∈ A} [ -½ log(2π δ_i(z)) - min(r_i² / (2 δ_i(z)), c) ],   r_i = v_i - m_i(z)
//
// τ ∈ (0, 1] tempers the product over APs, which in reality are not independent (shared
// shadowing by the body and the walls, correlated fading): without it a scan of 100 APs acts
// like 100 independent measurements and the posterior collapses onto wrong places. c caps each
// AP's residual term (a moved or blocked AP cannot veto a position). A is the set of APs used:
//  - a reading of an AP that the map does not know is ignored (the caller maps BSSIDs to the
//    map's columns; unknown ones simply are not passed);
//  - a reading older than its scan (Android's "last seen") is either applied at its own time
//    (the batch API re-times it) or dropped when older than `max_age_s`;
//  - an AP in the map but not heard in the scan contributes at `not_heard_dbm` when
//    `use_not_heard` (the floor-value model the SignalMap was built with), else nothing.
// A scan with no usable reading is a no-op (log-likelihood 0 everywhere), never an error.
#pragma once
#include <limits>
#include <string>
#include <vector>
#include <Eigen/Core>

#include "indoorloc/wifi/rss_model.h"

namespace indoorloc::fusion {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct WifiLikelihoodOptions {
  /// τ: tempering exponent of the scan likelihood (0, 1] (chosen by `indoorloc fusion tune` on
  /// synthetic tuning seeds; docs/fusion.md).
  double tempering = 0.1;
  /// c: cap on each AP's residual term r²/(2δ) (nats before tempering); +inf disables.
  double max_term = 8.0;
  /// Readings older than this relative to their scan are dropped [s] (streaming use; the batch
  /// API applies readings at their own time when `readings_at_own_time`).
  double max_age_s = 4.0;
  /// Use the map's APs not heard in a scan at `not_heard_dbm`.
  bool use_not_heard = true;
  /// RSS of a not-heard AP [dBm]; must match the SignalMap's `not_heard_dbm`.
  double not_heard_dbm = -105.0;
  bool IsValid(std::string* error) const;
};

/// The usable readings of one scan (or of one group of readings sharing a time): AP columns of
/// the signal map and their RSS [dBm] (not-heard APs already given `not_heard_dbm`).
struct WifiObservation {
  double time_s = 0.0;
  std::vector<int> access_points;
  std::vector<double> rss_dbm;
  int num_heard = 0;        ///< readings actually heard (the rest are not-heard entries)
  bool empty() const { return access_points.empty(); }
};

/// What became of the readings when scans were turned into observations.
struct WifiReadingCounts {
  int heard = 0;            ///< heard readings used
  int not_heard = 0;        ///< not-heard entries used (floor value)
  int dropped_stale = 0;    ///< heard readings older than max_age_s (scan-time mode)
  int scans_without_readings = 0;
};

/// Turns scans into observations. rss_dbm (S x K): one row per scan, columns = the map's APs,
/// NaN = not heard; ages_s (S x K) [s] >= 0: scan time minus the reading's last-seen time (NaN
/// where not heard; pass a 0 x 0 matrix for "all fresh"); scan_times_s (S) non-decreasing.
/// With `at_own_time`, heard readings are grouped by their own time t - age (one observation
/// per distinct time, readings at the same instant merged) and the not-heard entries stay with
/// their scan; otherwise each scan is one observation at its time and readings older than
/// max_age_s are dropped. Output sorted by time (stable). Throws std::invalid_argument naming
/// the argument on shape mismatch, infinite RSS, negative or infinite ages, or decreasing times.
/// Throws std::invalid_argument naming 'rss_dbm' with the bytes it would take if `scans` x
/// `access_points` readings do not fit MakeWifiObservations' memory limit (4 GB; about 64 B
/// per reading and 200 B per scan). Checked from the shapes before anything is converted.
void RequireWifiReadingsMemory(double scans, double access_points);

std::vector<WifiObservation> MakeWifiObservations(const Eigen::Ref<const Eigen::VectorXd>& scan_times_s,
                                                  const Eigen::Ref<const RowMatrixXd>& rss_dbm,
                                                  const Eigen::Ref<const RowMatrixXd>& ages_s,
                                                  const WifiLikelihoodOptions& options, bool at_own_time,
                                                  WifiReadingCounts* counts = nullptr);

/// Evaluates the tempered scan log-likelihood at positions on a floor of the RSS model.
class WifiLikelihood {
 public:
  /// Keeps a reference to `model`, which must outlive this object.
  WifiLikelihood(const wifi::RssModel& model, const WifiLikelihoodOptions& options);
  const wifi::RssModel& model() const { return model_; }
  const WifiLikelihoodOptions& options() const { return options_; }
  /// Tempered log-likelihood of `observation` at (x, y) [m] on the model's floor
  /// `model_floor_index`: one point location (DelaunayInterpolator::Locate) and the fields of the
  /// observation's APs only. Thread-safe. Empty observation: 0.
  double LogLikelihood(double x_m, double y_m, int model_floor_index, const WifiObservation& observation) const;
  /// Checks that every AP index of `observation` is a column of the model and every RSS finite.
  void CheckObservation(const WifiObservation& observation, const char* argument) const;

 private:
  const wifi::RssModel& model_;
  WifiLikelihoodOptions options_;
};

}  // namespace indoorloc::fusion
