// Fingerprint fixes, live: WiFi scans (BSSID, RSSI, last-seen time per reading) pooled into the
// query fingerprint of each scan, matched against a floor's fingerprint map, and turned into a
// position fix (a Gaussian mixture of the k best fingerprints' positions).
//
// When to use: inside LiveSession (fusion/live_session.h), or an app that wants WiFi fixes one
// scan at a time. It is python indoorloc.wifi_fixes' "window" pooling with causal alignment
// (walk_queries, fixes_for_walk), made incremental (docs/fusion.md, "Live tracking"):
//   - each distinct (BSSID, last-seen ms) is one measurement, at its first report; a BSSID the
//     map does not know is counted (unknown_readings) and dropped, so memory stays bounded;
//   - the query of the scan at time t max-pools the measurements of known APs last seen in
//     [t - query_window_s, t] (NaN: not heard); fewer than min_aps APs: no query;
//   - its k best fingerprints under the shared-AP dissimilarity (wifi/shared_ap_matcher.h) are the
//     components: mean = the fingerprint's position, weight = exp(-(d - d_min)/T) x the
//     fingerprint's own weight (grown fingerprints count less), sd = sd_m + sd_per_db d_min
//     (sd_m when d_min = inf), floor = the fingerprint's floor (or any floor).
// The fix is timed at the scan: a live filter cannot apply a fix before it is made.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/fusion/position_fix.h"
#include "indoorloc/fusion/track.h"
#include "indoorloc/wifi/shared_ap_matcher.h"

namespace indoorloc::fusion {

/// A floor's (or site's) WiFi fingerprint map: python wifi_fixes.FingerprintDatabase's arrays.
struct FingerprintMap {
  std::vector<std::string> bssids;  ///< K column names
  RowMatrixXd rss_dbm;              ///< N x K [dBm], NaN = not heard
  RowMatrixXd positions_m;          ///< N x 2 [m] in the floor frame
  Eigen::VectorXi floors;           ///< N floor numbers
  Eigen::VectorXd weights;          ///< N weights in (0, 1]; empty = all 1
  Eigen::VectorXd ap_weights;       ///< K per-AP reliability weights g_i >= 0; empty = all 1
};

/// How scans become fixes. Defaults are python wifi_fixes.FixSettings' (where they were chosen by
/// cross-validation; a test keeps the two equal).
struct FingerprintFixOptions {
  wifi::SharedApMatcherOptions matcher;  ///< c, beta, k, T of the matcher
  double query_window_s = 16.0;          ///< pooling window before the scan [s], > 0
  int min_aps = 3;                       ///< a query needs this many known APs (>= 1)
  double sd_m = 3.0;                     ///< component sd at d_min = 0 [m], > 0
  double sd_per_db = 0.3;                ///< growth of the sd with d_min [m/dB], >= 0
  bool with_floors = true;               ///< components on their fingerprint's floor (else any)

  bool IsValid(std::string* error) const;
};

/// A scan's pooled query: the fingerprint (K) and the mean last-seen time it describes [s].
struct ScanQuery {
  Eigen::VectorXd rss_dbm;
  double described_time_s = 0;
};

class FingerprintFixer {
 public:
  /// Copies the map. Throws std::invalid_argument naming the field for a malformed map (shapes,
  /// RSS outside +-1000 dBm, weights outside (0, 1]) or invalid options.
  FingerprintFixer(const FingerprintMap& map, const FingerprintFixOptions& options = FingerprintFixOptions());
  ~FingerprintFixer();
  FingerprintFixer(FingerprintFixer&&) noexcept;
  FingerprintFixer& operator=(FingerprintFixer&&) noexcept;

  /// Checks a scan's readings as AddScan does (one entry per reading, finite values, time_s finite,
  /// last-seen times within ±1e12 s) without adding them: std::invalid_argument naming the argument.
  static void CheckScan(double time_s, const std::vector<std::string>& bssids,
                        const Eigen::Ref<const Eigen::VectorXd>& rssi_dbm,
                        const Eigen::Ref<const Eigen::VectorXd>& last_seen_s);

  /// Adds a scan's readings (bssids, rssi_dbm, last_seen_s: one entry per reading, finite) reported
  /// at time_s (non-decreasing over calls) and returns its query; false when it has fewer than
  /// min_aps known APs. Throws std::invalid_argument naming the argument on bad input (state unchanged).
  bool AddScan(double time_s, const std::vector<std::string>& bssids, const Eigen::Ref<const Eigen::VectorXd>& rssi_dbm,
               const Eigen::Ref<const Eigen::VectorXd>& last_seen_s, ScanQuery* query);

  /// The fix of a query, timed at time_s, every component moved by shift_m [m]. Components of
  /// weight 0 (no AP shared) are left out; a fix with none is empty (ignored by the filter).
  PositionFix Fix(const ScanQuery& query, double time_s,
                  const Eigen::Vector2d& shift_m = Eigen::Vector2d::Zero()) const;

  const FingerprintFixOptions& options() const;
  int num_fingerprints() const;
  int num_access_points() const;
  /// Readings of BSSIDs the map does not know, dropped so far (nothing of them is kept).
  long long unknown_readings() const;
  /// BSSIDs with an id: the map's, whatever the scans brought (memory bound of a long run).
  std::size_t num_known_ids() const;
  /// Measurements remembered to drop repeats: per map AP those of the last window (+1), or up to 16.
  std::size_t num_remembered_measurements() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace indoorloc::fusion
