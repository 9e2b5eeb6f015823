// Tests of the fingerprint fixer (the live session's WiFi): a scan that reads exactly one stored
// fingerprint gives a fix whose heaviest component sits on that fingerprint; readings are pooled
// over the query window by their last-seen times (older ones leave the query); a scan with too few
// known APs gives no query; malformed maps and scans are refused naming the field.
#include "indoorloc/fusion/fingerprint_fixes.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace indoorloc::fusion {
namespace {

// Fingerprints every 4 m over a 40 x 20 m floor; four APs in the corners, log-distance RSS.
FingerprintMap MakeMap() {
  FingerprintMap map;
  const double ap[4][2] = {{0, 0}, {40, 0}, {0, 20}, {40, 20}};
  for (int j = 0; j < 4; ++j) map.bssids.push_back("ap" + std::to_string(j));
  std::vector<Eigen::Vector2d> pts;
  for (double x = 2; x < 40; x += 4)
    for (double y = 2; y < 20; y += 4) pts.emplace_back(x, y);
  const Eigen::Index n = static_cast<Eigen::Index>(pts.size());
  map.rss_dbm.resize(n, 4);
  map.positions_m.resize(n, 2);
  map.floors = Eigen::VectorXi::Zero(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector2d p = pts[static_cast<std::size_t>(i)];
    map.positions_m.row(i) = p.transpose();
    for (int j = 0; j < 4; ++j) {
      map.rss_dbm(i, j) = -40.0 - 25.0 * std::log10(std::max(1.0, std::hypot(p.x() - ap[j][0], p.y() - ap[j][1])));
    }
  }
  return map;
}

TEST(FingerprintFixer, AScanReadingAFingerprintIsFixedOnIt) {
  const FingerprintMap map = MakeMap();
  FingerprintFixer fixer(map);
  EXPECT_EQ(fixer.num_fingerprints(), map.rss_dbm.rows());
  EXPECT_EQ(fixer.num_access_points(), 4);
  const Eigen::Index target = 17;
  ScanQuery q;
  ASSERT_TRUE(fixer.AddScan(10.0, map.bssids, map.rss_dbm.row(target).transpose(), Eigen::VectorXd::Constant(4, 9.5), &q));
  EXPECT_DOUBLE_EQ(q.described_time_s, 9.5);
  const PositionFix fix = fixer.Fix(q, q.described_time_s);
  ASSERT_FALSE(fix.empty());
  Eigen::Index best = 0;
  fix.weights.maxCoeff(&best);
  EXPECT_NEAR((fix.means_m.row(best) - map.positions_m.row(target)).norm(), 0.0, 1e-9);
  // An exact match has d_min = 0: every component's sd is sd_m.
  EXPECT_NEAR(fix.sds_m.maxCoeff(), fixer.options().sd_m, 1e-9);
  // The shift moves every component.
  const PositionFix moved = fixer.Fix(q, q.described_time_s, Eigen::Vector2d(1.0, -2.0));
  EXPECT_NEAR(moved.means_m(best, 0) - fix.means_m(best, 0), 1.0, 1e-12);
  EXPECT_NEAR(moved.means_m(best, 1) - fix.means_m(best, 1), -2.0, 1e-12);
}

TEST(FingerprintFixer, PoolsOverTheWindowAndNeedsEnoughAps) {
  const FingerprintMap map = MakeMap();
  FingerprintFixOptions o;
  o.query_window_s = 16.0;
  FingerprintFixer fixer(map, o);
  ScanQuery q;
  // Two known APs only (and one unknown): no query.
  EXPECT_FALSE(fixer.AddScan(1.0, {"ap0", "ap1", "other"}, Eigen::Vector3d(-60, -70, -50), Eigen::Vector3d(1, 1, 1), &q));
  // A later scan hears the other two: pooled with the first, four known APs.
  ASSERT_TRUE(fixer.AddScan(3.0, {"ap2", "ap3"}, Eigen::Vector2d(-65, -75), Eigen::Vector2d(3, 3), &q));
  EXPECT_EQ((q.rss_dbm.array().isNaN() == false).count(), 4);
  // 20 s later the first readings have left the window: two APs, no query.
  EXPECT_FALSE(fixer.AddScan(21.0, {"ap2"}, Eigen::VectorXd::Constant(1, -66), Eigen::VectorXd::Constant(1, 21), &q));
}

// A long live run meets ever new BSSIDs (phones, hotspots): only the map's get an id; the rest are
// counted and dropped, so memory stays bounded, and the queries are those of the known readings.
TEST(FingerprintFixer, UnknownBssidsAreCountedAndDroppedWithBoundedMemory) {
  const FingerprintMap map = MakeMap();
  FingerprintFixer mixed(map), known_only(map);
  long long unknown = 0;
  for (int scan = 0; scan < 2000; ++scan) {
    const double t = 1.0 * scan;
    const Eigen::Index row = scan % map.rss_dbm.rows();
    std::vector<std::string> names;
    std::vector<double> rssi, seen;
    for (int m = 0; m < 50; ++m) {  // 50 BSSIDs never met before in every scan: 100,000 in all
      names.push_back("stranger-" + std::to_string(scan) + "-" + std::to_string(m));
      rssi.push_back(-60.0);
      seen.push_back(t - 0.5);
    }
    for (int j = 0; j < 4; ++j) {
      names.push_back(map.bssids[static_cast<std::size_t>(j)]);
      rssi.push_back(map.rss_dbm(row, j));
      seen.push_back(t - 0.25 * j);
    }
    unknown += 50;
    ScanQuery a, b;
    const bool got_a = mixed.AddScan(t, names, Eigen::Map<Eigen::VectorXd>(rssi.data(), 54),
                                     Eigen::Map<Eigen::VectorXd>(seen.data(), 54), &a);
    const bool got_b = known_only.AddScan(t, map.bssids, Eigen::Map<Eigen::VectorXd>(rssi.data() + 50, 4),
                                          Eigen::Map<Eigen::VectorXd>(seen.data() + 50, 4), &b);
    ASSERT_EQ(got_a, got_b);
    ASSERT_TRUE(got_a);
    for (Eigen::Index j = 0; j < 4; ++j) ASSERT_EQ(a.rss_dbm[j], b.rss_dbm[j]) << "scan " << scan;
    ASSERT_EQ(a.described_time_s, b.described_time_s);
  }
  EXPECT_EQ(mixed.unknown_readings(), unknown);
  EXPECT_EQ(known_only.unknown_readings(), 0);
  EXPECT_EQ(mixed.num_known_ids(), map.bssids.size());  // not 100,004
  EXPECT_LE(mixed.num_remembered_measurements(), 4u * 17u);  // 16 s window, a scan a second
}

TEST(FingerprintFixer, RefusesMalformedInputNamingIt) {
  FingerprintMap map = MakeMap();
  FingerprintFixer fixer(map);
  ScanQuery q;
  EXPECT_THROW(fixer.AddScan(5.0, {"ap0"}, Eigen::Vector2d(-60, -61), Eigen::VectorXd::Constant(1, 5), &q),
               std::invalid_argument);
  EXPECT_THROW(fixer.AddScan(5.0, {"ap0"}, Eigen::VectorXd::Constant(1, std::nan("")), Eigen::VectorXd::Constant(1, 5), &q),
               std::invalid_argument);
  map.positions_m.conservativeResize(map.positions_m.rows() - 1, 2);
  try {
    FingerprintFixer bad(map);
    FAIL() << "a map whose positions and fingerprints disagree was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("positions_m"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace indoorloc::fusion
