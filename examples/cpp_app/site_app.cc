// An outside application that tracks a walk live on a site model written by the Python side
// (`indoorloc site build`), through the installed package only: the site file gives the floor's
// plan, the PDR calibration, the WiFi fingerprint map and the tracker's options; the walk's RAW
// sensor events (accelerometer, gyroscope, rotation vector, WiFi scans with last-seen times,
// beacons) come from walk_events.txt (examples/cpp_app/export_walk.py, which also gives Python's
// causal track of the same walk on the same file). Each event goes to a LiveSession; the estimate
// after each new step is compared with Python's. Exit 0 when the two tracks are equal.
//   site_app SITE.db walk_events.txt
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <indoorloc/fusion/floor_plan.h>
#include <indoorloc/fusion/grid_tracker.h>
#include <indoorloc/fusion/live_session.h>
#include <indoorloc/fusion/site_file.h>

namespace fusion = indoorloc::fusion;

namespace {

void Expect(std::istream& in, const std::string& word) {
  std::string got;
  if (!(in >> got) || got != word) throw std::runtime_error("walk_events.txt: expected '" + word + "', got '" + got + "'");
}

// Reads one event line and feeds it to the session.
void FeedEvent(std::istream& in, fusion::LiveSession* session) {
  std::string kind;
  double t = 0;
  in >> kind >> t;
  if (kind == "acc" || kind == "gyro") {
    Eigen::Vector3d v;
    in >> v[0] >> v[1] >> v[2];
    if (kind == "acc") session->AddAccelerometer(t, v);
    else session->AddGyroscope(t, v);
  } else if (kind == "rv") {
    int n = 0;
    in >> n;
    Eigen::VectorXd v(n);
    for (int i = 0; i < n; ++i) in >> v[i];
    session->AddRotationVector(t, v);
  } else if (kind == "wifi") {
    int n = 0;
    in >> n;
    std::vector<std::string> bssids(static_cast<std::size_t>(n));
    Eigen::VectorXd rssi(n), seen(n);
    for (int i = 0; i < n; ++i) in >> bssids[static_cast<std::size_t>(i)] >> rssi[i] >> seen[i];
    session->AddWifiScan(t, bssids, rssi, seen);
  } else if (kind == "beacon") {
    session->AddBeacon(t);
  } else {
    throw std::runtime_error("walk_events.txt: unknown event kind '" + kind + "'");
  }
  if (!in) throw std::runtime_error("walk_events.txt: truncated event");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: site_app SITE.db walk_events.txt\n");
    return 2;
  }
  try {
    const fusion::SiteFile site(argv[1]);
    std::ifstream in(argv[2]);
    if (!in) throw std::runtime_error(std::string("cannot read ") + argv[2]);
    std::string floor;
    Expect(in, "floor");
    in >> floor;
    const fusion::SiteFloor f = site.Floor(floor);
    const fusion::FingerprintMap map = site.Fingerprints(floor);
    std::printf("site %s: %zu floor(s), %d walks, written by indoorloc %s; floor %s: %zu outline(s), %zu obstacles, "
                "%ld fingerprints of %zu APs\n",
                argv[1], site.FloorNames().size(), site.WalkCount(), site.Meta("library_version").c_str(),
                floor.c_str(), f.geometry.outlines.size(), f.geometry.obstacles.size(),
                static_cast<long>(map.rss_dbm.rows()), map.bssids.size());
    const fusion::FloorPlan plan({f.geometry});
    const fusion::GridTracker tracker = site.Tracker(&plan, floor);
    fusion::LiveSession session(&tracker, &map, site.LiveOptions(floor), site.FixOptions());

    long events = 0;
    Expect(in, "events");
    in >> events;
    std::vector<fusion::GridFilterEstimate> track;
    double worst_event_s = 0.0;
    for (long i = 0; i < events; ++i) {
      const auto start = std::chrono::steady_clock::now();
      FeedEvent(in, &session);
      worst_event_s = std::max(worst_event_s, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      if (session.HasEstimate() && (track.empty() || track.back().steps != session.Estimate().steps)) {
        track.push_back(session.Estimate());
      }
    }
    int e = 0;
    Expect(in, "expected");
    in >> e;
    double worst = 0.0, worst_t = 0.0;
    for (int i = 0; i < e; ++i) {
      double t, x, y;
      in >> t >> x >> y;
      if (i < static_cast<int>(track.size())) {
        const fusion::GridFilterEstimate& k = track[static_cast<std::size_t>(i)];
        worst = std::max({worst, std::hypot(k.mean_m.x() - x, k.mean_m.y() - y)});
        worst_t = std::max(worst_t, std::abs(k.time_s - t));
      }
    }
    if (!in) throw std::runtime_error("walk_events.txt: truncated");
    const fusion::LiveSessionSummary u = session.Summary();
    // Before its first fix an unknown start's estimate is the prior's mean, not a position.
    std::size_t first_located = 0;
    while (first_located < track.size() && !track[first_located].located) ++first_located;
    std::printf("tracked %ld raw events live (%lld IMU samples, %d scans): %d steps (and %d standing), %d WiFi "
                "fixes; located from step %zu; last position (%.2f, %.2f) m; largest difference to Python's causal track %.3g m (step "
                "times %.3g s) over %d steps; slowest event %.3f ms\n",
                events, u.imu_samples, u.scans, u.steps, u.standing_steps, u.fixes, first_located + 1,
                track.empty() ? 0.0 : track.back().mean_m.x(), track.empty() ? 0.0 : track.back().mean_m.y(), worst,
                worst_t, e, 1e3 * worst_event_s);
    return (static_cast<int>(track.size()) == e && e > 0 && worst == 0.0 && worst_t == 0.0) ? 0 : 1;
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "site_app: %s\n", ex.what());
    return 1;
  }
}
