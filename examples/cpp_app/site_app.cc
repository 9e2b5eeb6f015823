// An outside application that tracks a walk on a site model written by the Python side
// (`indoorloc site build`), through the installed package only: the site file gives the floor's
// plan and the default tracker's options; the walk's steps and WiFi fixes come from
// walk_events.txt (examples/cpp_app/export_walk.py, which also gives Python's track of the same
// walk from the same file). Exit 0 when the C++ track equals Python's.
//   site_app SITE.db walk_events.txt
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <indoorloc/fusion/floor_plan.h>
#include <indoorloc/fusion/grid_tracker.h>
#include <indoorloc/fusion/site_file.h>

namespace fusion = indoorloc::fusion;

namespace {

void Expect(std::istream& in, const std::string& word) {
  std::string got;
  if (!(in >> got) || got != word) throw std::runtime_error("walk_events.txt: expected '" + word + "', got '" + got + "'");
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
    std::printf("site %s: %zu floor(s), %d walks, written by indoorloc %s; floor %s: %zu outline(s), %zu obstacles\n",
                argv[1], site.FloorNames().size(), site.WalkCount(), site.Meta("library_version").c_str(),
                floor.c_str(), f.geometry.outlines.size(), f.geometry.obstacles.size());
    int m = 0;
    Expect(in, "steps");
    in >> m;
    std::vector<fusion::StepInput> steps(m);
    for (auto& s : steps) {
      double cxx, cxy, cyy;
      in >> s.time_s >> s.displacement_m.x() >> s.displacement_m.y() >> cxx >> cxy >> cyy;
      s.covariance_m2 << cxx, cxy, cxy, cyy;
    }
    int n = 0;
    Expect(in, "fixes");
    in >> n;
    std::vector<fusion::PositionFix> fixes(n);
    for (auto& fx : fixes) {
      int k = 0;
      in >> fx.time_s >> k;
      fx.means_m.resize(k, 2);
      fx.sds_m.resize(k);
      fx.weights.resize(k);
      fx.floors.resize(k);
      for (int j = 0; j < k; ++j) in >> fx.means_m(j, 0) >> fx.means_m(j, 1) >> fx.sds_m(j) >> fx.weights(j) >> fx.floors(j);
    }
    int e = 0;
    Expect(in, "expected");
    in >> e;
    fusion::RowMatrixXd expected(e, 2);
    for (int i = 0; i < e; ++i) in >> expected(i, 0) >> expected(i, 1);
    if (!in) throw std::runtime_error("walk_events.txt: truncated");

    const fusion::FloorPlan plan({f.geometry});
    const fusion::GridTracker tracker(&plan, site.TrackerOptions(floor));
    const fusion::GridTrackResult r = tracker.Run(steps, fixes, fusion::TrackStart(), /*smooth=*/true);
    const fusion::RowMatrixXd& xy = site.TrackerOptions(floor).spatial_median ? r.smoothed_median_m : r.smoothed_mean_m;
    double worst = 0.0;
    for (int i = 0; i < e && i < xy.rows(); ++i) {
      worst = std::max(worst, std::hypot(xy(i, 0) - expected(i, 0), xy(i, 1) - expected(i, 1)));
    }
    std::printf("tracked %d steps and %d WiFi fixes from an unknown start: last position (%.2f, %.2f) m; "
                "largest difference to Python's track %.3g m; %s\n",
                m, n, xy(xy.rows() - 1, 0), xy(xy.rows() - 1, 1), worst, r.summary.BriefReport().c_str());
    return (xy.rows() == e && worst < 1e-6) ? 0 : 1;
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "site_app: %s\n", ex.what());
    return 1;
  }
}
