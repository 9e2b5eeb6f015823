// Test helper of the particle tracker tests: a 20 x 10 m room with a block and a thin wall, four
// corner APs over it, scans at a point and steps.
#pragma once

#include <cmath>
#include <initializer_list>
#include <utility>
#include <vector>

#include "indoorloc/fusion/floor_plan.h"
#include "indoorloc/fusion/step_motion.h"
#include "indoorloc/fusion/wifi_likelihood.h"
#include "indoorloc/wifi/rss_model.h"

namespace indoorloc::fusion {

inline RowMatrixXd Ring(std::initializer_list<std::pair<double, double>> pts) {
  RowMatrixXd r(static_cast<Eigen::Index>(pts.size()), 2);
  Eigen::Index i = 0;
  for (const auto& p : pts) {
    r(i, 0) = p.first;
    r(i, 1) = p.second;
    ++i;
  }
  return r;
}

// A 20 x 10 m room with a 4 x 4 m block in the middle (x 8..12, y 3..7) and a thin wall at
// x = 16 from y = 0 to y = 7 (a door above it).
inline FloorPlan RoomPlan(int floors = 1) {
  std::vector<FloorGeometry> geometry;
  for (int f = 0; f < floors; ++f) {
    FloorGeometry g;
    g.floor = f;
    g.outlines.push_back(Ring({{0, 0}, {20, 0}, {20, 10}, {0, 10}}));
    g.obstacles.push_back(Ring({{8, 3}, {12, 3}, {12, 7}, {8, 7}}));
    g.walls = RowMatrixXd(1, 4);
    g.walls << 16, 0, 16, 7;
    geometry.push_back(g);
  }
  return FloorPlan(geometry);
}

// Four APs at the room's corners, log-distance means on a 1 m lattice.
inline wifi::SignalMap RoomMap() {
  const double aps[4][2] = {{0, 0}, {20, 0}, {0, 10}, {20, 10}};
  const int nx = 21, ny = 11;
  RowMatrixXd pos(nx * ny, 2), mean(nx * ny, 4), var(nx * ny, 4);
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      const int r = i * ny + j;
      pos.row(r) << i, j;
      for (int a = 0; a < 4; ++a) {
        mean(r, a) = -40.0 - 25.0 * std::log10(std::hypot(i - aps[a][0], j - aps[a][1]) + 1.0);
        var(r, a) = 4.0;
      }
    }
  }
  return wifi::SignalMap(pos, Eigen::VectorXi::Zero(nx * ny), mean, var);
}

inline WifiObservation ScanAt(const wifi::RssModel& model, double t, double x, double y) {
  Eigen::VectorXd mean, var;
  int hint = -1;
  model.MeanAndVariance(Eigen::Vector2d(x, y), 0, &mean, &var, &hint);
  WifiObservation o;
  o.time_s = t;
  for (int a = 0; a < mean.size(); ++a) {
    o.access_points.push_back(a);
    o.rss_dbm.push_back(mean[a]);
  }
  o.num_heard = static_cast<int>(mean.size());
  return o;
}

inline StepInput Step(double t, double dx, double dy, double sd = 0.02) {
  StepInput s;
  s.time_s = t;
  s.displacement_m = Eigen::Vector2d(dx, dy);
  s.covariance_m2 = sd * sd * Eigen::Matrix2d::Identity();
  return s;
}

}  // namespace indoorloc::fusion
