// Site file reader (site_file.h): SQLite C API, read-only, one prepared statement per query.
#include "indoorloc/fusion/site_file.h"

#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>
#include <utility>

#include "indoorloc/core/check.h"

namespace indoorloc::fusion {
namespace {

// A prepared statement, finalized on scope exit.
class Statement {
 public:
  Statement(sqlite3* db, const std::string& sql, const std::string& path) : db_(db) {
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt_, nullptr) != SQLITE_OK) {
      throw std::runtime_error("indoorloc: site file " + path + ": damaged or not a site (" + sqlite3_errmsg(db) +
                               ")");
    }
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  void Bind(int i, const std::string& v) { sqlite3_bind_text(stmt_, i, v.c_str(), -1, SQLITE_TRANSIENT); }
  bool Step() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw std::runtime_error(std::string("indoorloc: site file: read failed (") + sqlite3_errmsg(db_) + ")");
  }
  double Double(int c) const {
    return sqlite3_column_type(stmt_, c) == SQLITE_NULL ? std::numeric_limits<double>::quiet_NaN()
                                                        : sqlite3_column_double(stmt_, c);
  }
  int Int(int c) const { return sqlite3_column_int(stmt_, c); }
  std::string Text(int c) const {
    const unsigned char* t = sqlite3_column_text(stmt_, c);
    return t ? std::string(reinterpret_cast<const char*>(t)) : std::string();
  }
  const void* Blob(int c, int* bytes) const {
    *bytes = sqlite3_column_bytes(stmt_, c);
    return sqlite3_column_blob(stmt_, c);
  }
  // A blob of little-endian float64 as rows x cols (the hosts we build for are little-endian).
  RowMatrixXd Matrix(int c, int cols) const {
    const int bytes = sqlite3_column_bytes(stmt_, c);
    const void* data = sqlite3_column_blob(stmt_, c);
    const int n = bytes / static_cast<int>(sizeof(double));
    if (bytes % (sizeof(double) * cols) != 0) throw std::runtime_error("indoorloc: site file: malformed array blob");
    RowMatrixXd m(n / cols, cols);
    if (n) std::memcpy(m.data(), data, static_cast<size_t>(n) * sizeof(double));
    return m;
  }

 private:
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

// The value after "key": in a flat JSON object (the settings the Python side wrote with
// json.dumps: numbers, strings, booleans). Empty when absent.
std::string JsonValue(const std::string& json, const std::string& key) {
  const std::string pattern = "\"" + key + "\":";
  const std::size_t at = json.find(pattern);
  if (at == std::string::npos) return std::string();
  std::size_t b = at + pattern.size();
  while (b < json.size() && json[b] == ' ') ++b;
  if (b < json.size() && json[b] == '"') {
    const std::size_t e = json.find('"', b + 1);
    return json.substr(b, e == std::string::npos ? std::string::npos : e - b + 1);
  }
  std::size_t e = b;
  while (e < json.size() && json[e] != ',' && json[e] != '}') ++e;
  return json.substr(b, e - b);
}

double JsonNumber(const std::string& json, const std::string& key, double fallback, const std::string& path) {
  const std::string v = JsonValue(json, key);
  if (v.empty()) return fallback;
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (end == v.c_str()) throw std::runtime_error("indoorloc: site file " + path + ": setting '" + key + "' is not a number");
  return x;
}

// The nested object of `key` in a JSON text ("{...}"), brace-matched (strings hold no braces here).
std::string JsonObject(const std::string& json, const std::string& key) {
  const std::size_t at = json.find("\"" + key + "\": {");
  if (at == std::string::npos) return std::string();
  const std::size_t b = json.find('{', at);
  int depth = 0;
  for (std::size_t i = b; i < json.size(); ++i) {
    depth += json[i] == '{' ? 1 : json[i] == '}' ? -1 : 0;
    if (depth == 0) return json.substr(b, i - b + 1);
  }
  return std::string();
}

}  // namespace

struct SiteFile::Impl {
  std::string path;
  sqlite3* db = nullptr;
  ~Impl() {
    if (db) sqlite3_close(db);
  }
  int Pragma(const std::string& name) {
    Statement s(db, "PRAGMA " + name, path);
    return s.Step() ? s.Int(0) : 0;
  }
  std::string Settings() const {
    Statement s(db, "SELECT settings FROM tracker_settings WHERE name = 'default'", path);
    if (!s.Step()) throw std::runtime_error("indoorloc: site file " + path + ": no tracker settings");
    return s.Text(0);
  }
  bool HasTable(const std::string& name) const {
    Statement s(db, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?", path);
    s.Bind(1, name);
    return s.Step();
  }
  void RequireFloor(const std::string& floor) const {
    Statement s(db, "SELECT 1 FROM floors WHERE name = ?", path);
    s.Bind(1, floor);
    if (!s.Step()) {
      throw std::invalid_argument("indoorloc: argument 'floor': '" + floor + "' is not in site " + path);
    }
  }
};

SiteFile::SiteFile(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("indoorloc: site file " + path + ": not found");
    char head[16] = {0};
    in.read(head, 16);
    if (in.gcount() < 16 || std::memcmp(head, "SQLite format 3", 16) != 0) {
      throw std::runtime_error("indoorloc: site file " + path + ": not an SQLite file");
    }
  }
  if (sqlite3_open_v2(path.c_str(), &impl_->db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    throw std::runtime_error("indoorloc: site file " + path + ": cannot open (" + sqlite3_errmsg(impl_->db) + ")");
  }
  const int app = impl_->Pragma("application_id");
  if (app != kApplicationId) {
    throw std::runtime_error("indoorloc: site file " + path + ": an SQLite file of another application, not an "
                             "indoorloc site");
  }
  const int version = impl_->Pragma("user_version");
  if (version != kFormatVersion) {
    throw std::runtime_error("indoorloc: site file " + path + ": format version " + std::to_string(version) +
                             ", this reader reads version " + std::to_string(kFormatVersion));
  }
  Statement check(impl_->db, "PRAGMA quick_check", path);
  if (!check.Step() || check.Text(0) != "ok") {
    throw std::runtime_error("indoorloc: site file " + path + ": damaged (" + check.Text(0) + ")");
  }
}

SiteFile::~SiteFile() = default;
SiteFile::SiteFile(SiteFile&&) noexcept = default;
SiteFile& SiteFile::operator=(SiteFile&&) noexcept = default;

const std::string& SiteFile::path() const { return impl_->path; }

std::vector<std::string> SiteFile::FloorNames() const {
  Statement s(impl_->db, "SELECT name FROM floors ORDER BY number", impl_->path);
  std::vector<std::string> out;
  while (s.Step()) out.push_back(s.Text(0));
  return out;
}

std::string SiteFile::Meta(const std::string& key) const {
  Statement s(impl_->db, "SELECT value FROM meta WHERE key = ?", impl_->path);
  s.Bind(1, key);
  return s.Step() ? s.Text(0) : std::string();
}

SiteFloor SiteFile::Floor(const std::string& name) const {
  impl_->RequireFloor(name);
  SiteFloor f;
  {
    Statement s(impl_->db, "SELECT name, number, origin_lon, origin_lat, walkable_area_m2 FROM floors WHERE name = ?",
                impl_->path);
    s.Bind(1, name);
    s.Step();
    f.name = s.Text(0);
    f.number = s.Int(1);
    f.origin_lon_deg = s.Double(2);
    f.origin_lat_deg = s.Double(3);
    f.walkable_area_m2 = s.Double(4);
  }
  f.geometry.floor = f.number;
  Statement s(impl_->db, "SELECT role, xy_m FROM plan_rings WHERE floor = ? ORDER BY role, ring", impl_->path);
  s.Bind(1, name);
  while (s.Step()) {
    (s.Text(0) == "outline" ? f.geometry.outlines : f.geometry.obstacles).push_back(s.Matrix(1, 2));
  }
  if (f.geometry.outlines.empty()) {
    throw std::runtime_error("indoorloc: site file " + impl_->path + ": floor " + name + " has no outline");
  }
  return f;
}

SitePdrCalibration SiteFile::Calibration(const std::string& floor) const {
  impl_->RequireFloor(floor);
  Statement s(impl_->db,
              "SELECT k, yaw_offset_rad, yaw_offset_spread_rad, length_sd_fraction, heading_sd_rad FROM "
              "pdr_calibration WHERE floor = ?",
              impl_->path);
  s.Bind(1, floor);
  if (!s.Step()) throw std::runtime_error("indoorloc: site file " + impl_->path + ": floor " + floor + " has no PDR calibration");
  return {s.Double(0), s.Double(1), s.Double(2), s.Double(3), s.Double(4)};
}

GridTrackerOptions SiteFile::TrackerOptions(const std::string& floor) const {
  const SitePdrCalibration cal = Calibration(floor);
  GridTrackerOptions o;
  std::map<std::string, double> v;
  Statement s(impl_->db, "SELECT name, value FROM grid_options", impl_->path);
  while (s.Step()) v[s.Text(0)] = s.Double(1);
  auto get = [&](const char* key, double fallback) {
    auto it = v.find(key);
    return it == v.end() ? fallback : it->second;
  };
  o.cell_size_m = get("cell_size_m", o.cell_size_m);
  o.walkable_subsamples = static_cast<int>(get("walkable_subsamples", o.walkable_subsamples));
  o.heading_offset_bins = static_cast<int>(get("heading_offset_bins", o.heading_offset_bins));
  o.heading_offset_span_sd = get("heading_offset_span_sd", o.heading_offset_span_sd);
  o.scale_bins = static_cast<int>(get("scale_bins", o.scale_bins));
  o.scale_sd = get("scale_sd", o.scale_sd);
  o.position_noise_m = get("position_noise_m", o.position_noise_m);
  o.wall_log_penalty = get("wall_log_penalty", o.wall_log_penalty);
  o.wall_margin_m = get("wall_margin_m", o.wall_margin_m);
  o.fix_survey_distance_factor = get("fix_survey_distance_factor", o.fix_survey_distance_factor);
  // A file written before the survey's open cells existed tracked with the walls as drawn
  // (python fusion.site_settings.LEGACY_GRID_VALUES).
  o.survey_walkable_radius_m = get("survey_walkable_radius_m", 0.0);
  o.survey_walkable_min_walks = static_cast<int>(get("survey_walkable_min_walks", 1.0));
  o.fix.outlier_probability = get("fix_outlier_probability", o.fix.outlier_probability);
  o.fix.tempering = get("fix_tempering", o.fix.tempering);
  o.fix_tempering_by_variance = get("fix_tempering_by_variance", o.fix_tempering_by_variance) != 0.0;
  o.spatial_median = get("spatial_median", o.spatial_median) != 0.0;
  o.median_block_m = get("median_block_m", o.median_block_m);
  o.start_position_sd_m = get("start_position_sd_m", o.start_position_sd_m);
  o.filtered_covariance_scale = get("filtered_covariance_scale", o.filtered_covariance_scale);
  o.filtered_covariance_floor_m = get("filtered_covariance_floor_m", o.filtered_covariance_floor_m);
  o.filtered_covariance_fix_gain = get("filtered_covariance_fix_gain", o.filtered_covariance_fix_gain);
  o.smoothed_covariance_scale = get("smoothed_covariance_scale", o.smoothed_covariance_scale);
  o.smoothed_covariance_floor_m = get("smoothed_covariance_floor_m", o.smoothed_covariance_floor_m);
  o.smoothed_covariance_fix_gain = get("smoothed_covariance_fix_gain", o.smoothed_covariance_fix_gain);
  o.filtered_covariance_fix_sd_gain = get("filtered_covariance_fix_sd_gain", o.filtered_covariance_fix_sd_gain);
  o.smoothed_covariance_fix_sd_gain = get("smoothed_covariance_fix_sd_gain", o.smoothed_covariance_fix_sd_gain);
  o.covariance_fix_sd_knee_m = get("covariance_fix_sd_knee_m", o.covariance_fix_sd_knee_m);
  o.max_memory_bytes = get("max_memory_bytes", o.max_memory_bytes);
  o.num_threads = static_cast<int>(get("num_threads", o.num_threads));
  const double spread = std::isfinite(cal.yaw_offset_spread_rad) ? cal.yaw_offset_spread_rad : 0.0;
  o.heading_offset_sd_rad = std::max(spread, 1e-3);
  return o;
}

GridTracker SiteFile::Tracker(const FloorPlan* plan, const std::string& floor) const {
  CheckArgument(plan != nullptr && plan->num_floors() == 1, "plan", "must be the floor's one-floor plan");
  GridTracker tracker(plan, TrackerOptions(floor));
  const RowMatrixXd positions = FingerprintPositions(floor);
  if (positions.rows() == 0) return tracker;
  // The survey walk of each fingerprint (for the cells the survey opens), numbered in order of
  // appearance: the same partition as the Python site's database.
  // Fingerprints of walks placed by the tracker (weight < 1, `site grow`) anchor but open no cell.
  Statement s(impl_->db, "SELECT walk, weight FROM fingerprints WHERE floor = ? ORDER BY id", impl_->path);
  s.Bind(1, floor);
  std::map<std::string, int> number;
  Eigen::VectorXi walks(positions.rows());
  for (Eigen::Index i = 0; s.Step() && i < walks.size(); ++i)
    walks[i] = s.Double(1) < 1.0 ? -1 : number.emplace(s.Text(0), static_cast<int>(number.size())).first->second;
  return tracker.WithSurveyPositions(positions, Eigen::VectorXi::Constant(positions.rows(), plan->floors()[0]), walks);
}

RowMatrixXd SiteFile::FingerprintPositions(const std::string& floor) const {
  impl_->RequireFloor(floor);
  Statement s(impl_->db, "SELECT x_m, y_m FROM fingerprints WHERE floor = ? ORDER BY id", impl_->path);
  s.Bind(1, floor);
  std::vector<double> xy;
  while (s.Step()) {
    xy.push_back(s.Double(0));
    xy.push_back(s.Double(1));
  }
  RowMatrixXd m(static_cast<Eigen::Index>(xy.size() / 2), 2);
  if (!xy.empty()) std::memcpy(m.data(), xy.data(), xy.size() * sizeof(double));
  return m;
}

FingerprintFixOptions SiteFile::FixOptions() const {
  const std::string fixes = JsonObject(impl_->Settings(), "fixes");
  const std::string& path = impl_->path;
  if (JsonValue(fixes, "pooling") != "\"window\"" || JsonValue(fixes, "query_align") != "\"end\"" ||
      JsonValue(fixes, "metric") != "\"shared\"" || JsonValue(fixes, "beacons") == "true") {
    throw std::runtime_error("indoorloc: site file " + path + ": live tracking needs the fix settings pooling "
                             "'window', query_align 'end', metric 'shared' and beacons off");
  }
  FingerprintFixOptions o;
  o.matcher.penalty_db = JsonNumber(fixes, "penalty_db", o.matcher.penalty_db, path);
  o.matcher.strength_scale_db = JsonNumber(fixes, "strength_scale_db", o.matcher.strength_scale_db, path);
  o.matcher.k = static_cast<int>(JsonNumber(fixes, "k", o.matcher.k, path));
  o.matcher.temperature_db = JsonNumber(fixes, "temperature_db", o.matcher.temperature_db, path);
  o.query_window_s = JsonNumber(fixes, "query_window_s", o.query_window_s, path);
  o.min_aps = static_cast<int>(JsonNumber(fixes, "min_aps", o.min_aps, path));
  o.sd_m = JsonNumber(fixes, "sd_m", o.sd_m, path);
  o.sd_per_db = JsonNumber(fixes, "sd_per_db", o.sd_per_db, path);
  return o;
}

FingerprintMap SiteFile::Fingerprints(const std::string& floor) const {
  impl_->RequireFloor(floor);
  const std::string& path = impl_->path;
  if (!impl_->HasTable("fingerprint_columns")) {
    throw std::runtime_error("indoorloc: site file " + path + ": has no fingerprint_columns table (written by an "
                             "older indoorloc: rebuild it with 'indoorloc site build')");
  }
  FingerprintMap map;
  std::vector<double> ratio;
  std::map<int, int> column_of_ap;  // access_points.id -> column
  {
    Statement s(impl_->db,
                "SELECT c.bssid, c.ap_ratio, a.id FROM fingerprint_columns c JOIN access_points a ON a.bssid = c.bssid "
                "WHERE c.floor = ? ORDER BY c.col",
                path);
    s.Bind(1, floor);
    while (s.Step()) {
      column_of_ap[s.Int(2)] = static_cast<int>(map.bssids.size());
      map.bssids.push_back(s.Text(0));
      ratio.push_back(s.Double(1));
    }
  }
  if (map.bssids.empty()) throw std::runtime_error("indoorloc: site file " + path + ": floor " + floor + " has no WiFi map");
  int number = 0;
  {
    Statement s(impl_->db, "SELECT number FROM floors WHERE name = ?", path);
    s.Bind(1, floor);
    s.Step();
    number = s.Int(0);
  }
  // Survey order (python site_tables.database): walks by seq, fingerprints by id.
  Statement s(impl_->db,
              "SELECT f.x_m, f.y_m, f.weight, f.ap_ids, f.rss_dbm FROM fingerprints f JOIN walks w ON w.id = f.walk "
              "WHERE f.floor = ? ORDER BY w.seq, f.id",
              path);
  s.Bind(1, floor);
  std::vector<double> rows, xy, weights;
  const std::size_t k = map.bssids.size();
  while (s.Step()) {
    xy.push_back(s.Double(0));
    xy.push_back(s.Double(1));
    weights.push_back(s.Double(2));
    int id_bytes = 0, rss_bytes = 0;
    const auto* ids = static_cast<const unsigned char*>(s.Blob(3, &id_bytes));
    const auto* rss = static_cast<const unsigned char*>(s.Blob(4, &rss_bytes));
    if (id_bytes != rss_bytes || id_bytes % 4 != 0) throw std::runtime_error("indoorloc: site file " + path + ": malformed fingerprint");
    const std::size_t at = rows.size();
    rows.resize(at + k, std::numeric_limits<double>::quiet_NaN());
    for (int b = 0; b < id_bytes; b += 4) {
      std::int32_t id;
      float v;
      std::memcpy(&id, ids + b, 4);  // little-endian <i4 and <f4 (the hosts we build for)
      std::memcpy(&v, rss + b, 4);
      const auto it = column_of_ap.find(id);
      if (it != column_of_ap.end()) rows[at + static_cast<std::size_t>(it->second)] = static_cast<double>(v);
    }
  }
  const Eigen::Index n = static_cast<Eigen::Index>(weights.size());
  if (n == 0) throw std::runtime_error("indoorloc: site file " + path + ": floor " + floor + " has no fingerprint");
  map.rss_dbm = Eigen::Map<const RowMatrixXd>(rows.data(), n, static_cast<Eigen::Index>(k));
  map.positions_m = Eigen::Map<const RowMatrixXd>(xy.data(), n, 2);
  map.floors = Eigen::VectorXi::Constant(n, number);
  map.weights = Eigen::Map<const Eigen::VectorXd>(weights.data(), n);
  if ((map.weights.array() == 1.0).all()) map.weights.resize(0);
  const double power = JsonNumber(JsonObject(impl_->Settings(), "fixes"), "ap_weight_power", 1.0, path);
  if (power != 0.0) {
    map.ap_weights.resize(static_cast<Eigen::Index>(k));
    for (std::size_t j = 0; j < k; ++j) map.ap_weights[static_cast<Eigen::Index>(j)] = std::pow(ratio[j], power);
  }
  return map;
}

LiveSessionOptions SiteFile::LiveOptions(const std::string& floor) const {
  impl_->RequireFloor(floor);
  const std::string& path = impl_->path;
  Statement s(impl_->db, "SELECT k, yaw_offset_rad, options FROM pdr_calibration WHERE floor = ?", path);
  s.Bind(1, floor);
  if (!s.Step()) throw std::runtime_error("indoorloc: site file " + path + ": floor " + floor + " has no PDR calibration");
  LiveSessionOptions o;
  const std::string opts = s.Text(2);
  if (JsonValue(opts, "method") != "\"peaks\"" || JsonValue(opts, "signal") != "\"magnitude\"") {
    throw std::runtime_error("indoorloc: site file " + path + ": floor " + floor + ": live tracking needs the "
                             "calibration's detector method 'peaks' and signal 'magnitude'");
  }
  pdr::StreamingStepOptions& d = o.detector;
  d.lowpass_hz = JsonNumber(opts, "lowpass_hz", d.lowpass_hz, path);
  d.highpass_hz = JsonNumber(opts, "highpass_hz", d.highpass_hz, path);
  d.filter_order = static_cast<int>(JsonNumber(opts, "filter_order", d.filter_order, path));
  d.rms_window_s = JsonNumber(opts, "rms_window_s", d.rms_window_s, path);
  d.threshold_fraction = JsonNumber(opts, "threshold_fraction", d.threshold_fraction, path);
  d.min_peak_mps2 = JsonNumber(opts, "min_peak_mps2", d.min_peak_mps2, path);
  d.min_step_interval_s = JsonNumber(opts, "min_step_interval_s", d.min_step_interval_s, path);
  d.max_step_half_window_s = JsonNumber(opts, "max_step_half_window_s", d.max_step_half_window_s, path);
  d.complementary_tau_s = JsonNumber(opts, "complementary_tau_s", d.complementary_tau_s, path);
  o.step_length_k = JsonNumber(opts, "k", s.Double(0), path);  // the calibration's options carry its K
  const std::string source = JsonValue(opts, "heading_source");
  o.heading_source = source == "\"gyro\""            ? StepHeadingSource::kGyro
                     : source == "\"complementary\"" ? StepHeadingSource::kComplementary
                                                     : StepHeadingSource::kRotationVector;
  o.yaw_offset_rad = s.Double(1);
  const std::string settings = impl_->Settings();
  o.step_length_sd_fraction = JsonNumber(settings, "step_length_sd_fraction", o.step_length_sd_fraction, path);
  o.step_heading_sd_rad = JsonNumber(settings, "step_heading_sd_rad", o.step_heading_sd_rad, path);
  return o;
}

int SiteFile::WalkCount(const std::string& floor) const {
  if (floor.empty()) {
    Statement s(impl_->db, "SELECT COUNT(*) FROM walks", impl_->path);
    return s.Step() ? s.Int(0) : 0;
  }
  impl_->RequireFloor(floor);
  Statement s(impl_->db, "SELECT COUNT(*) FROM walks WHERE floor = ?", impl_->path);
  s.Bind(1, floor);
  return s.Step() ? s.Int(0) : 0;
}

}  // namespace indoorloc::fusion
