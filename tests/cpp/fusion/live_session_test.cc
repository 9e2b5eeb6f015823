// Tests of the live session: raw events of a synthetic hand-held walk across a hall (IMU at 50 Hz,
// WiFi scans every 2 s from a fingerprint map of the hall) give steps and fixes, and the estimate
// follows the walk; the session equals a GridFilterSession fed the causal steps and the scans'
// fixes (the batch formulation) bit for bit; events out of time order and malformed events are
// refused naming the event, the session unchanged; a user standing still (no step) is located
// from WiFi alone through standing steps.
#include "indoorloc/fusion/live_session.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace indoorloc::fusion {
namespace {

constexpr double kPi = 3.14159265358979323846;

RowMatrixXd Box(double x0, double y0, double x1, double y1) {
  RowMatrixXd r(4, 2);
  r << x0, y0, x1, y0, x1, y1, x0, y1;
  return r;
}

// Fingerprints every 2 m on a grid over the 60 x 40 m hall; six APs spread over it, each heard
// within 25 m with a log-distance RSS.
struct Hall {
  FloorPlan plan;
  FingerprintMap map;
};

double Rss(const Eigen::Vector2d& p, int ap) {
  static const double kAp[6][2] = {{5, 5}, {15, 30}, {25, 12}, {35, 35}, {45, 8}, {55, 25}};
  const double d = std::hypot(p.x() - kAp[ap][0], p.y() - kAp[ap][1]);
  return d < 25.0 ? -40.0 - 25.0 * std::log10(std::max(d, 1.0)) : std::nan("");
}

Hall MakeHall() {
  FloorGeometry g;
  g.floor = 0;
  g.outlines.push_back(Box(0, 0, 60, 40));
  Hall h{FloorPlan({g}), FingerprintMap()};
  const int aps = 6;
  for (int j = 0; j < aps; ++j) h.map.bssids.push_back("ap" + std::to_string(j));
  std::vector<Eigen::Vector2d> pts;
  for (double x = 1; x < 60; x += 2)
    for (double y = 1; y < 40; y += 2) pts.emplace_back(x, y);
  const Eigen::Index n = static_cast<Eigen::Index>(pts.size());
  h.map.rss_dbm.resize(n, aps);
  h.map.positions_m.resize(n, 2);
  h.map.floors = Eigen::VectorXi::Zero(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    h.map.positions_m.row(i) = pts[static_cast<std::size_t>(i)].transpose();
    for (int j = 0; j < aps; ++j) h.map.rss_dbm(i, j) = Rss(pts[static_cast<std::size_t>(i)], j);
  }
  return h;
}

// A WiFi scan at time t of the APs heard at p, each last seen 0.5 s before; `with_unknown`: one
// reading of a BSSID the map does not know.
void Scan(LiveSession* session, double t, const Eigen::Vector2d& p, bool with_unknown) {
  std::vector<std::string> names;
  std::vector<double> rss;
  for (int j = 0; j < 6; ++j) {
    if (std::isnan(Rss(p, j))) continue;
    names.push_back("ap" + std::to_string(j));
    rss.push_back(Rss(p, j));
  }
  if (with_unknown) {
    names.push_back("unknown");
    rss.push_back(-70.0);
  }
  const Eigen::VectorXd r = Eigen::Map<Eigen::VectorXd>(rss.data(), static_cast<Eigen::Index>(rss.size()));
  session->AddWifiScan(t, names, r, Eigen::VectorXd::Constant(r.size(), t - 0.5));
}

// Feeds a walk east along y = 10 from x = 5 at 2 steps/s (0.7 m steps with K chosen so) to
// `session`, up to `seconds`; returns the true position at the end.
void Walk(LiveSession* session, double seconds, std::vector<double>* step_times = nullptr) {
  const double rate = 50.0, t0 = 1000.0;
  const Eigen::Vector4d q(0, 0, std::sin(-kPi / 4), std::cos(-kPi / 4));  // device +y towards east
  Eigen::VectorXd rv(4);
  rv << q[0], q[1], q[2], q[3];
  for (int i = 0; i < static_cast<int>(seconds * rate); ++i) {
    const double t = t0 + i / rate;
    session->AddGyroscope(t, Eigen::Vector3d::Zero());
    session->AddRotationVector(t, rv);
    session->AddAccelerometer(t, Eigen::Vector3d(0, 0, 9.80665 + 2.0 * std::sin(2 * kPi * 2.0 * (i / rate))));
    if (i % 100 == 50) {  // a scan every 2 s: readings last seen now, at the true position
      Scan(session, t, Eigen::Vector2d(5.0 + 1.4 * (i / rate), 10.0), true);
    }
    if (step_times && session->HasEstimate() &&
        (step_times->empty() || step_times->back() != session->Estimate().time_s)) {
      step_times->push_back(session->Estimate().time_s);
    }
  }
}

LiveSessionOptions Options() {
  LiveSessionOptions o;
  o.step_length_k = 0.7 / std::pow(4.0, 0.25);  // feature of |a| swinging +-2 m/s² ≈ 4^(1/4)
  return o;
}

TEST(LiveSession, TracksRawEventsWithStepsAndFixes) {
  const Hall h = MakeHall();
  GridTrackerOptions go;
  go.heading_offset_sd_rad = 0.05;
  const GridTracker tracker(&h.plan, go);
  // A short pooling window: the default 16 s max-pools the stretch walked (a lag of metres).
  FingerprintFixOptions fo;
  fo.query_window_s = 3.0;
  LiveSession s(&tracker, &h.map, Options(), fo);
  EXPECT_FALSE(s.HasEstimate());
  Walk(&s, 30.0);
  const LiveSessionSummary u = s.Summary();
  EXPECT_NEAR(u.steps, 60, 3);
  EXPECT_EQ(u.scans, 15);
  EXPECT_GE(u.fixes, 13);
  EXPECT_EQ(u.events, 30 * 50 * 3 + 15);
  const Eigen::Vector2d truth(5.0 + 1.4 * s.Estimate().time_s - 1.4 * 1000.0, 10.0);
  EXPECT_LT((s.Estimate().mean_m - truth).norm(), 3.0) << s.Estimate().mean_m.transpose();
  // BSSIDs the map does not know are counted and dropped.
  const long long unknown = u.unknown_wifi_readings;
  s.AddWifiScan(1031.0, {"not-in-the-map", "nor-this"}, Eigen::Vector2d(-50, -60), Eigen::Vector2d::Constant(1030.5));
  EXPECT_EQ(s.Summary().unknown_wifi_readings, unknown + 2);
}

TEST(LiveSession, RefusesEventsOutOfOrderNamingThemAndStaysUnchanged) {
  const Hall h = MakeHall();
  const GridTracker tracker(&h.plan, GridTrackerOptions());
  LiveSession s(&tracker, &h.map, Options());
  Walk(&s, 6.0);
  ASSERT_TRUE(s.HasEstimate());
  const LiveSessionSummary before = s.Summary();
  const Eigen::Vector2d mean = s.Estimate().mean_m;
  try {
    s.AddGyroscope(1000.5, Eigen::Vector3d::Zero());
    FAIL() << "accepted an event out of time order";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("event " + std::to_string(before.events) + " (gyroscope at t = 1000.5 s) is out of time order"),
              std::string::npos) << m;
    EXPECT_NE(m.find("(accelerometer at t = 1005.98 s)"), std::string::npos) << m;
  }
  EXPECT_THROW(s.AddWifiScan(std::nan(""), {}, Eigen::VectorXd(0), Eigen::VectorXd(0)), std::invalid_argument);
  EXPECT_THROW(s.AddWifiScan(1010.0, {"ap0", "ap1"}, Eigen::VectorXd::Zero(1), Eigen::VectorXd::Zero(2)),
               std::invalid_argument);
  EXPECT_THROW(s.AddAccelerometer(1010.0, Eigen::Vector3d(0, NAN, 9.8)), std::invalid_argument);
  EXPECT_THROW(s.AddRotationVector(1010.0, Eigen::VectorXd::Zero(2)), std::invalid_argument);
  const LiveSessionSummary after = s.Summary();
  EXPECT_EQ(after.events, before.events);
  EXPECT_EQ(after.steps, before.steps);
  EXPECT_EQ(s.Estimate().mean_m, mean);
  // A second session fed the same events gives the same estimate (no hidden state).
  LiveSession again(&tracker, &h.map, Options());
  Walk(&again, 6.0);
  EXPECT_EQ(again.Estimate().mean_m, mean);
  EXPECT_THROW(LiveSession(nullptr, &h.map, Options()), std::invalid_argument);
  LiveSessionOptions bad = Options();
  bad.step_length_k = -1;
  EXPECT_THROW(LiveSession(&tracker, nullptr, bad), std::invalid_argument);
}

// A user standing still at `p` (flat accelerometer: no step) for `seconds`, a scan every 2 s.
void Stand(LiveSession* session, double seconds, const Eigen::Vector2d& p, std::vector<bool>* had_estimate) {
  const double rate = 50.0, t0 = 1000.0;
  Eigen::VectorXd rv(4);
  rv << 0, 0, 0, 1;
  for (int i = 0; i < static_cast<int>(seconds * rate); ++i) {
    const double t = t0 + i / rate;
    session->AddGyroscope(t, Eigen::Vector3d::Zero());
    session->AddRotationVector(t, rv);
    session->AddAccelerometer(t, Eigen::Vector3d(0, 0, 9.80665));
    if (i % 100 == 50) Scan(session, t, p, false);
    had_estimate->push_back(session->HasEstimate());
  }
}

TEST(LiveSession, LocatesAUserStandingStillFromWifiAlone) {
  const Hall h = MakeHall();
  const GridTracker tracker(&h.plan, GridTrackerOptions());
  FingerprintFixOptions fo;
  fo.query_window_s = 3.0;
  const Eigen::Vector2d where(40.0, 20.0);
  // Default: a fix no step has applied standing_after_s (1 s) after its scan is applied at a
  // standing step at the scan's time.
  LiveSession s(&tracker, &h.map, Options(), fo);
  std::vector<bool> had;
  Stand(&s, 10.0, where, &had);
  const LiveSessionSummary u = s.Summary();
  EXPECT_EQ(u.steps, 0);
  EXPECT_EQ(u.scans, 5);
  EXPECT_EQ(u.standing_steps, 4);  // the last scan (t0 + 9 s) is not 1 s old at t0 + 9.98 s
  EXPECT_EQ(u.fixes, 4);
  EXPECT_EQ(u.pending_fixes, 1);
  EXPECT_EQ(u.late_steps, 0);
  // First estimate at the first event 1 s after the first scan (sample 100 at t0 + 2 s).
  ASSERT_EQ(had.size(), 500u);
  EXPECT_FALSE(had[99]);
  EXPECT_TRUE(had[100]);
  ASSERT_TRUE(s.HasEstimate());
  EXPECT_TRUE(s.Estimate().located);
  EXPECT_EQ(s.Estimate().time_s, 1007.0);  // the latest standing step is at its scan's time
  EXPECT_LT((s.Estimate().mean_m - where).norm(), 3.0) << s.Estimate().mean_m.transpose();
  // Off: fixes wait for a step that never comes; no estimate at all.
  LiveSessionOptions wait = Options();
  wait.standing_after_s = 0.0;
  LiveSession off(&tracker, &h.map, wait, fo);
  had.clear();
  Stand(&off, 10.0, where, &had);
  EXPECT_FALSE(off.HasEstimate());
  EXPECT_EQ(off.Summary().pending_fixes, 5);
  // A standing wait at or below the detector's latency could order a standing step after a later
  // detected step: refused, naming the option.
  LiveSessionOptions bad = Options();
  bad.standing_after_s = bad.detector.min_step_interval_s;
  try {
    LiveSession refused(&tracker, &h.map, bad, fo);
    FAIL() << "accepted standing_after_s at the detector's latency";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("standing_after_s"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace indoorloc::fusion
