// Fingerprint fixes, live (fingerprint_fixes.h): the incremental "window" query pooler and the
// fix of a query. The pooling keeps the order of python wifi_matcher.pool_windows' sums, so a
// live query equals the batch one bit for bit.
#include "indoorloc/fusion/fingerprint_fixes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::fusion {

bool FingerprintFixOptions::IsValid(std::string* error) const {
  std::string matcher_error;
  const bool matcher_ok = matcher.IsValid(&matcher_error);
  return Validator(error)
      .Check(matcher_ok, "matcher", matcher_error)
      .Positive(query_window_s, "query_window_s")
      .AtLeast(min_aps, 1, "min_aps")
      .Positive(sd_m, "sd_m")
      .NonNegative(sd_per_db, "sd_per_db");
}

struct FingerprintFixer::State {
  FingerprintFixOptions options;
  RowMatrixXd positions_m;
  Eigen::VectorXi floors;
  Eigen::VectorXd weights;
  Eigen::Index columns = 0;
  std::unique_ptr<wifi::SharedApMatcher> matcher;
  // The map's BSSIDs and their columns, the only ids kept: a BSSID the map does not know is
  // counted and dropped (a long live run meets ever more of them; memory stays the map's).
  std::unordered_map<std::string, int> id_of;
  long long unknown_readings = 0;
  // Measurements met, to drop repeats: per map column, (last-seen ms, last-seen s) of its recent
  // measurements (a short list scanned per reading: no allocation, no hashing per reading);
  // entries older than the window are dropped whenever a list reaches kSeenPerAp.
  static constexpr std::size_t kSeenPerAp = 16;
  std::vector<std::vector<std::pair<long long, double>>> seen;
  // Kept measurements of known APs, sorted by last-seen time (stably: equal times keep their
  // arrival order, the order of pool_windows' stable sort, so the mean time sums alike).
  struct Measurement {
    double t;    // last seen [s]
    int col;
    double rss;  // [dBm]
  };
  std::vector<Measurement> kept;
  std::vector<Measurement> fresh;  // reused buffer
  double latest_s = -std::numeric_limits<double>::infinity();
};

FingerprintFixer::FingerprintFixer(const FingerprintMap& map, const FingerprintFixOptions& options)
    : state_(std::make_unique<State>()) {
  std::string error;
  if (!options.IsValid(&error)) ThrowInvalidArgument("options", error);
  const Eigen::Index n = map.rss_dbm.rows(), k = map.rss_dbm.cols();
  CheckArgument(static_cast<Eigen::Index>(map.bssids.size()) == k, "map.bssids",
                "expected one BSSID per column of map.rss_dbm (" + std::to_string(k) + "), got " +
                    std::to_string(map.bssids.size()));
  CheckShape(map.positions_m, n, 2, "map.positions_m");
  CheckFinite(map.positions_m, "map.positions_m");
  CheckArgument(map.floors.size() == n, "map.floors", "expected one floor per fingerprint (" + std::to_string(n) + ")");
  CheckArgument(map.weights.size() == 0 || map.weights.size() == n, "map.weights",
                "expected one weight per fingerprint or none");
  for (Eigen::Index i = 0; i < map.weights.size(); ++i) {
    CheckArgument(map.weights[i] > 0.0 && map.weights[i] <= 1.0, "map.weights", "entries must be in (0, 1]");
  }
  CheckArgument(n > 0, "map.rss_dbm", "the map has no fingerprint");
  State& s = *state_;
  s.options = options;
  s.positions_m = map.positions_m;
  s.floors = map.floors;
  s.weights = map.weights;
  s.columns = k;
  s.seen.resize(static_cast<std::size_t>(k));
  for (Eigen::Index j = 0; j < k; ++j) {
    if (!s.id_of.emplace(map.bssids[static_cast<std::size_t>(j)], static_cast<int>(j)).second) {
      ThrowInvalidArgument("map.bssids", "'" + map.bssids[static_cast<std::size_t>(j)] + "' appears twice");
    }
  }
  s.matcher = std::make_unique<wifi::SharedApMatcher>(map.rss_dbm, map.ap_weights, options.matcher);
}

FingerprintFixer::~FingerprintFixer() = default;
FingerprintFixer::FingerprintFixer(FingerprintFixer&&) noexcept = default;
FingerprintFixer& FingerprintFixer::operator=(FingerprintFixer&&) noexcept = default;

const FingerprintFixOptions& FingerprintFixer::options() const { return state_->options; }
int FingerprintFixer::num_fingerprints() const { return static_cast<int>(state_->positions_m.rows()); }
int FingerprintFixer::num_access_points() const { return static_cast<int>(state_->columns); }
long long FingerprintFixer::unknown_readings() const { return state_->unknown_readings; }
std::size_t FingerprintFixer::num_known_ids() const { return state_->id_of.size(); }
std::size_t FingerprintFixer::num_remembered_measurements() const {
  std::size_t n = 0;
  for (const auto& met : state_->seen) n += met.size();
  return n;
}

void FingerprintFixer::CheckScan(double time_s, const std::vector<std::string>& bssids,
                                 const Eigen::Ref<const Eigen::VectorXd>& rssi_dbm,
                                 const Eigen::Ref<const Eigen::VectorXd>& last_seen_s) {
  const std::size_t m = bssids.size();
  if (static_cast<std::size_t>(rssi_dbm.size()) != m || static_cast<std::size_t>(last_seen_s.size()) != m) {
    ThrowInvalidArgument("bssids", "bssids, rssi_dbm and last_seen_s must have one entry per reading, got " +
                                       std::to_string(m) + ", " + std::to_string(rssi_dbm.size()) + ", " +
                                       std::to_string(last_seen_s.size()));
  }
  CheckArgument(std::isfinite(time_s), "time_s", "must be finite");
  CheckFinite(rssi_dbm, "rssi_dbm");
  CheckFinite(last_seen_s, "last_seen_s");
  CheckArgument(last_seen_s.size() == 0 || last_seen_s.cwiseAbs().maxCoeff() < 1e12, "last_seen_s",
                "must be within +-1e12 s");
}

bool FingerprintFixer::AddScan(double time_s, const std::vector<std::string>& bssids,
                               const Eigen::Ref<const Eigen::VectorXd>& rssi_dbm,
                               const Eigen::Ref<const Eigen::VectorXd>& last_seen_s, ScanQuery* query) {
  State& s = *state_;
  const std::size_t m = bssids.size();
  CheckScan(time_s, bssids, rssi_dbm, last_seen_s);
  CheckArgument(time_s >= s.latest_s, "time_s", "scans must come in non-decreasing time");
  s.latest_s = time_s;
  const double lo = time_s - s.options.query_window_s;
  s.fresh.clear();
  for (std::size_t j = 0; j < m; ++j) {
    // The measurement key of python IlcWifi.new_measurement_mask: last-seen time in whole ms
    // (rounded half to even, as numpy's round).
    const auto known = s.id_of.find(bssids[j]);  // a look-up: no string built per reading
    if (known == s.id_of.end()) {
      ++s.unknown_readings;
      continue;
    }
    const int id = known->second;
    const double seen = last_seen_s[static_cast<Eigen::Index>(j)];
    const long long ms = static_cast<long long>(std::nearbyint(seen * 1000.0));
    auto& met = s.seen[static_cast<std::size_t>(id)];
    if (std::any_of(met.begin(), met.end(), [ms](const auto& x) { return x.first == ms; })) continue;
    if (met.size() >= State::kSeenPerAp) {  // forget what no later window can hold
      met.erase(std::remove_if(met.begin(), met.end(), [lo](const auto& x) { return x.second < lo; }), met.end());
    }
    met.emplace_back(ms, seen);
    s.fresh.push_back({seen, id, rssi_dbm[static_cast<Eigen::Index>(j)]});
  }
  auto by_time = [](const State::Measurement& a, const State::Measurement& b) { return a.t < b.t; };
  std::stable_sort(s.fresh.begin(), s.fresh.end(), by_time);
  const std::size_t old = s.kept.size();
  s.kept.insert(s.kept.end(), s.fresh.begin(), s.fresh.end());
  std::inplace_merge(s.kept.begin(), s.kept.begin() + static_cast<std::ptrdiff_t>(old), s.kept.end(), by_time);
  // Forget what no later window can hold (windows only move forward).
  const auto first = std::find_if(s.kept.begin(), s.kept.end(), [lo](const State::Measurement& x) { return x.t >= lo; });
  s.kept.erase(s.kept.begin(), first);
  // Max-pool the measurements last seen by now (a prefix), summing their times in time order.
  Eigen::VectorXd q = Eigen::VectorXd::Constant(s.columns, std::numeric_limits<double>::quiet_NaN());
  int heard = 0;
  std::size_t used = 0;
  double total = 0.0;
  for (; used < s.kept.size() && s.kept[used].t <= time_s; ++used) {
    const State::Measurement& x = s.kept[used];
    double& v = q[x.col];
    if (std::isnan(v)) {
      v = x.rss;
      ++heard;
    } else if (x.rss > v) {
      v = x.rss;
    }
    total += x.t;
  }
  if (heard < s.options.min_aps) return false;
  if (query) {
    query->rss_dbm = std::move(q);
    query->described_time_s = total / static_cast<double>(std::max<std::size_t>(used, 1));
  }
  return true;
}

PositionFix FingerprintFixer::Fix(const ScanQuery& query, double time_s, const Eigen::Vector2d& shift_m) const {
  const State& s = *state_;
  CheckArgument(query.rss_dbm.size() == s.columns, "query", "expected one RSS per column of the map");
  const wifi::SharedApNeighbours nb = s.matcher->Nearest(query.rss_dbm.transpose());
  const Eigen::Index k = nb.index.cols();
  const double d_min = k > 0 ? nb.distance_db(0, 0) : std::numeric_limits<double>::infinity();
  const double sd = std::isfinite(d_min) ? s.options.sd_m + s.options.sd_per_db * d_min : s.options.sd_m;
  PositionFix::Means candidates(k, 2);
  Eigen::VectorXd weights(k);
  Eigen::VectorXi floors(k);
  for (Eigen::Index j = 0; j < k; ++j) {
    const Eigen::Index r = nb.index(0, j);
    candidates(j, 0) = s.positions_m(r, 0) + shift_m[0];
    candidates(j, 1) = s.positions_m(r, 1) + shift_m[1];
    weights[j] = s.weights.size() ? nb.weight(0, j) * s.weights[r] : nb.weight(0, j);
    floors[j] = s.options.with_floors ? s.floors[r] : PositionFix::kAnyFloor;
  }
  return FixFromCandidates(time_s, candidates, Eigen::VectorXd::Constant(k, sd), weights, floors);
}

}  // namespace indoorloc::fusion
