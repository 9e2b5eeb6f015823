// Tests of the site file reader: a small site written here with the SQLite C API in the layout of
// python/indoorloc/fusion/site_store.py is read back (floor, plan, calibration, tracker options,
// fingerprints) and tracked on; a text file, another application's SQLite file, another format
// version and an unknown floor give errors naming the file or floor.
#include "indoorloc/fusion/site_file.h"

#include <sqlite3.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace indoorloc::fusion {
namespace {

std::string TempPath(const std::string& name) {
  return (testing::TempDir().empty() ? std::string("/tmp/") : testing::TempDir()) + name;
}

void Exec(sqlite3* db, const std::string& sql) {
  char* err = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string msg = err ? err : "?";
    sqlite3_free(err);
    throw std::runtime_error(msg);
  }
}

void InsertRing(sqlite3* db, const std::string& role, int ring, const std::vector<double>& xy) {
  sqlite3_stmt* s = nullptr;
  sqlite3_prepare_v2(db, "INSERT INTO plan_rings VALUES ('F1', ?, ?, ?)", -1, &s, nullptr);
  sqlite3_bind_text(s, 1, role.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_int(s, 2, ring);
  sqlite3_bind_blob(s, 3, xy.data(), static_cast<int>(xy.size() * sizeof(double)), SQLITE_TRANSIENT);
  ASSERT_EQ(sqlite3_step(s), SQLITE_DONE);
  sqlite3_finalize(s);
}

// A one-floor site: a 60 x 40 m hall with a 10 x 10 m shop, two fingerprints, a calibration.
std::string WriteSmallSite(const std::string& name, int application_id = SiteFile::kApplicationId,
                           int version = SiteFile::kFormatVersion) {
  const std::string path = TempPath(name);
  std::remove(path.c_str());
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  Exec(db, "PRAGMA application_id = " + std::to_string(application_id) + "; PRAGMA user_version = " +
               std::to_string(version) + ";");
  Exec(db,
       "CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);"
       "CREATE TABLE floors (name TEXT PRIMARY KEY, number INTEGER, geojson TEXT, origin_lon REAL, origin_lat REAL,"
       " walkable_area_m2 REAL, width_m REAL, height_m REAL, source TEXT);"
       "CREATE TABLE plan_rings (floor TEXT, role TEXT, ring INTEGER, xy_m BLOB);"
       "CREATE TABLE walks (id TEXT PRIMARY KEY, seq INTEGER, floor TEXT);"
       "CREATE TABLE fingerprints (id INTEGER PRIMARY KEY, floor TEXT, walk TEXT, t_s REAL, x_m REAL, y_m REAL,"
       " weight REAL, ap_ids BLOB, rss_dbm BLOB);"
       "CREATE TABLE pdr_calibration (floor TEXT PRIMARY KEY, k REAL, yaw_offset_rad REAL,"
       " yaw_offset_spread_rad REAL, length_sd_fraction REAL, heading_sd_rad REAL, k_rms_residual_m REAL,"
       " n_intervals INTEGER, options TEXT);"
       "CREATE TABLE grid_options (name TEXT PRIMARY KEY, value REAL);"
       "INSERT INTO meta VALUES ('format', 'indoorloc.site'), ('library_version', 'test');"
       "INSERT INTO floors VALUES ('F1', 1, '{}', 120.1, 30.3, 2300.0, 60, 40, 'test');"
       "INSERT INTO walks VALUES ('w1', 0, 'F1'), ('w2', 1, 'F1');"
       "INSERT INTO fingerprints (floor, walk, t_s, x_m, y_m, weight, ap_ids, rss_dbm) VALUES"
       " ('F1', 'w1', 1.0, 5.0, 5.0, 1.0, x'', x''), ('F1', 'w2', 2.0, 40.0, 10.0, 1.0, x'', x'');"
       "INSERT INTO pdr_calibration VALUES ('F1', 0.4, 0.1, 0.05, 0.15, 0.2, 0.5, 10, '{}');"
       "INSERT INTO grid_options VALUES ('cell_size_m', 2.0), ('heading_offset_bins', 3), ('wall_log_penalty', -2.0),"
       " ('fix_tempering', 0.5), ('spatial_median', 1);");
  InsertRing(db, "outline", 0, {0, 0, 60, 0, 60, 40, 0, 40});
  InsertRing(db, "obstacle", 0, {20, 20, 30, 20, 30, 30, 20, 30});
  sqlite3_close(db);
  return path;
}

TEST(SiteFile, ReadsFloorPlanCalibrationAndOptions) {
  const SiteFile site(WriteSmallSite("site_ok.db"));
  EXPECT_EQ(site.FloorNames(), std::vector<std::string>{"F1"});
  EXPECT_EQ(site.Meta("format"), "indoorloc.site");
  EXPECT_EQ(site.Meta("absent"), "");
  EXPECT_EQ(site.WalkCount(), 2);
  EXPECT_EQ(site.WalkCount("F1"), 2);
  const SiteFloor f = site.Floor("F1");
  EXPECT_EQ(f.number, 1);
  EXPECT_DOUBLE_EQ(f.origin_lon_deg, 120.1);
  ASSERT_EQ(f.geometry.outlines.size(), 1u);
  ASSERT_EQ(f.geometry.obstacles.size(), 1u);
  EXPECT_EQ(f.geometry.outlines[0].rows(), 4);
  EXPECT_DOUBLE_EQ(f.geometry.obstacles[0](2, 0), 30.0);
  const SitePdrCalibration cal = site.Calibration("F1");
  EXPECT_DOUBLE_EQ(cal.k, 0.4);
  EXPECT_DOUBLE_EQ(cal.yaw_offset_rad, 0.1);
  const GridTrackerOptions o = site.TrackerOptions("F1");
  EXPECT_DOUBLE_EQ(o.cell_size_m, 2.0);
  EXPECT_EQ(o.heading_offset_bins, 3);
  EXPECT_DOUBLE_EQ(o.wall_log_penalty, -2.0);
  EXPECT_DOUBLE_EQ(o.fix.tempering, 0.5);
  EXPECT_TRUE(o.spatial_median);
  EXPECT_DOUBLE_EQ(o.heading_offset_sd_rad, 0.05);  // the floor's calibrated spread
  EXPECT_DOUBLE_EQ(o.position_noise_m, GridTrackerOptions().position_noise_m);  // not stored: default
  const RowMatrixXd fp = site.FingerprintPositions("F1");
  ASSERT_EQ(fp.rows(), 2);
  EXPECT_DOUBLE_EQ(fp(1, 0), 40.0);
}

TEST(SiteFile, TracksStepsOnTheStoredPlan) {
  const SiteFile site(WriteSmallSite("site_track.db"));
  const FloorPlan plan({site.Floor("F1").geometry});
  const GridTracker tracker(&plan, site.TrackerOptions("F1"));
  std::vector<StepInput> steps;
  for (int k = 0; k < 10; ++k) steps.push_back(StepFromPolar(0.5 * (k + 1), 0.7, 0.0, 0.05, 0.05));
  TrackStart start;
  start.known = true;
  start.position_m = Eigen::Vector2d(5.0, 5.0);
  start.floor = 1;
  const GridTrackResult r = tracker.Run(steps, {}, start, /*smooth=*/true);
  ASSERT_EQ(r.smoothed_mean_m.rows(), 10);
  EXPECT_NEAR(r.smoothed_mean_m(9, 0), 12.0, 1.5);
  EXPECT_NEAR(r.smoothed_mean_m(9, 1), 5.0, 1.5);
}

// The live tracker's inputs: the fingerprint map (columns and AP reliabilities from the stored
// table, fingerprints in survey order, unknown APs dropped, weights, AP weights g^power), the fix
// settings and the live session's options from the JSON the Python side writes.
TEST(SiteFile, ReadsTheFingerprintMapAndTheLiveOptions) {
  const std::string path = WriteSmallSite("site_live.db");
  {
    const SiteFile site(path);
    try {
      site.Fingerprints("F1");
      FAIL() << "a file without fingerprint_columns gave a map";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("fingerprint_columns"), std::string::npos) << e.what();
    }
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  Exec(db,
       "CREATE TABLE access_points (id INTEGER PRIMARY KEY, bssid TEXT);"
       "INSERT INTO access_points VALUES (1, 'aa'), (2, 'bb'), (3, 'cc');"
       "CREATE TABLE fingerprint_columns (floor TEXT, col INTEGER, bssid TEXT, ap_ratio REAL);"
       "INSERT INTO fingerprint_columns VALUES ('F1', 0, 'aa', 1.0), ('F1', 1, 'bb', 4.0);"
       // w1 heard aa -60, bb -70; w2 heard cc -60 (not a column) and bb -60, weight 0.5.
       "UPDATE fingerprints SET ap_ids = x'0100000002000000', rss_dbm = x'000070C200008CC2' WHERE walk = 'w1';"
       "UPDATE fingerprints SET ap_ids = x'0300000002000000', rss_dbm = x'000070C2000070C2', weight = 0.5 "
       " WHERE walk = 'w2';"
       "CREATE TABLE tracker_settings (name TEXT PRIMARY KEY, settings TEXT);"
       "INSERT INTO tracker_settings VALUES ('default', '{\"step_length_sd_fraction\": 0.2, "
       "\"step_heading_sd_rad\": 0.3, \"fixes\": {\"pooling\": \"window\", \"query_align\": \"end\", "
       "\"metric\": \"shared\", \"beacons\": false, \"k\": 7, \"penalty_db\": 100.0, "
       "\"ap_weight_power\": 0.5, \"sd_m\": 2.5, \"sd_per_db\": 0.1, \"query_window_s\": 12.0, "
       "\"min_aps\": 2}}');"
       "UPDATE pdr_calibration SET options = '{\"method\": \"peaks\", \"signal\": \"magnitude\", "
       "\"lowpass_hz\": 2.5, \"k\": 0.45, \"heading_source\": \"gyro\"}';");
  sqlite3_close(db);
  const SiteFile site(path);
  const FingerprintMap map = site.Fingerprints("F1");
  EXPECT_EQ(map.bssids, (std::vector<std::string>{"aa", "bb"}));
  ASSERT_EQ(map.rss_dbm.rows(), 2);
  EXPECT_EQ(map.rss_dbm(0, 0), -60.0);
  EXPECT_EQ(map.rss_dbm(0, 1), -70.0);
  EXPECT_TRUE(std::isnan(map.rss_dbm(1, 0)));
  EXPECT_EQ(map.rss_dbm(1, 1), -60.0);
  EXPECT_EQ(map.positions_m(1, 0), 40.0);
  EXPECT_EQ(map.floors, Eigen::Vector2i(1, 1));
  EXPECT_EQ(map.weights, Eigen::Vector2d(1.0, 0.5));
  EXPECT_EQ(map.ap_weights, Eigen::Vector2d(1.0, 2.0));
  const FingerprintFixOptions fo = site.FixOptions();
  EXPECT_EQ(fo.matcher.k, 7);
  EXPECT_EQ(fo.matcher.penalty_db, 100.0);
  EXPECT_EQ(fo.matcher.temperature_db, wifi::SharedApMatcherOptions().temperature_db);  // absent: default
  EXPECT_EQ(fo.sd_m, 2.5);
  EXPECT_EQ(fo.sd_per_db, 0.1);
  EXPECT_EQ(fo.query_window_s, 12.0);
  EXPECT_EQ(fo.min_aps, 2);
  const LiveSessionOptions lo = site.LiveOptions("F1");
  EXPECT_EQ(lo.detector.lowpass_hz, 2.5);
  EXPECT_EQ(lo.detector.highpass_hz, pdr::StreamingStepOptions().highpass_hz);
  EXPECT_EQ(lo.step_length_k, 0.45);
  EXPECT_EQ(lo.heading_source, StepHeadingSource::kGyro);
  EXPECT_EQ(lo.yaw_offset_rad, 0.1);
  EXPECT_EQ(lo.step_length_sd_fraction, 0.2);
  EXPECT_EQ(lo.step_heading_sd_rad, 0.3);
  // A live session runs on them.
  const FloorPlan plan({site.Floor("F1").geometry});
  const GridTracker tracker(&plan, site.TrackerOptions("F1"));
  LiveSession live(&tracker, &map, lo, fo);
  EXPECT_FALSE(live.AddWifiScan(1.0, {"aa", "bb"}, Eigen::Vector2d(-60, -70), Eigen::Vector2d(0.5, 0.5)));
  EXPECT_EQ(live.Summary().pending_fixes, 1);
}

TEST(SiteFile, ClearErrors) {
  const std::string text = TempPath("site_text.db");
  std::ofstream(text) << "not a database\n";
  try {
    SiteFile bad(text);
    FAIL() << "a text file was opened";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("site_text.db: not an SQLite file"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SiteFile(TempPath("site_missing.db")), std::runtime_error);
  try {
    SiteFile foreign(WriteSmallSite("site_foreign.db", /*application_id=*/7));
    FAIL() << "a foreign file was opened";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("another application"), std::string::npos) << e.what();
  }
  try {
    SiteFile old(WriteSmallSite("site_v99.db", SiteFile::kApplicationId, 99));
    FAIL() << "a version-99 file was opened";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("format version 99"), std::string::npos) << e.what();
  }
  const SiteFile site(WriteSmallSite("site_floor.db"));
  try {
    site.Floor("F9");
    FAIL() << "an unknown floor was read";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'F9' is not in site"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace indoorloc::fusion
