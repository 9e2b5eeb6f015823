// Test helpers of the grid tracker tests (grid tracker, grid session, survey anchors): the 60 x 40 m
// hall they walk in, the axis-aligned boxes rings are made of, and position fixes of one or K components.
#pragma once

#include <vector>

#include "indoorloc/fusion/floor_plan.h"
#include "indoorloc/fusion/position_fix.h"

namespace indoorloc::fusion {

/// The ring (4, 2) [m] of the box [x0, x1] x [y0, y1], counter-clockwise.
inline RowMatrixXd Box(double x0, double y0, double x1, double y1) {
  RowMatrixXd r(4, 2);
  r << x0, y0, x1, y0, x1, y1, x0, y1;
  return r;
}

/// A 60 x 40 m hall on `floors` floors (0, 1, ...); with `shop`, a 10 x 10 m shop (an obstacle)
/// at x 20..30, y 20..30 m.
inline FloorPlan Hall(bool shop = false, int floors = 1) {
  std::vector<FloorGeometry> g;
  for (int f = 0; f < floors; ++f) {
    FloorGeometry fg;
    fg.floor = f;
    fg.outlines.push_back(Box(0, 0, 60, 40));
    if (shop) fg.obstacles.push_back(Box(20, 20, 30, 30));
    g.push_back(fg);
  }
  return FloorPlan(g);
}

/// A fix at (x, y) [m] with sd [m] at time t [s]: one component of weight 1, on `floor` (any by
/// default).
inline PositionFix Fix(double t, double x, double y, double sd, int floor = PositionFix::kAnyFloor) {
  PositionFix f;
  f.time_s = t;
  f.means_m.resize(1, 2);
  f.means_m << x, y;
  f.sds_m = Eigen::VectorXd::Constant(1, sd);
  f.weights = Eigen::VectorXd::Ones(1);
  f.floors = Eigen::VectorXi::Constant(1, floor);
  return f;
}

/// A fix at time t [s] with K components on any floor: means (K, 2) [m], sds (K) [m], weights (K).
inline PositionFix MixtureFix(double t, const RowMatrixXd& means_m, const Eigen::VectorXd& sds_m,
                              const Eigen::VectorXd& weights) {
  PositionFix f;
  f.time_s = t;
  f.means_m = means_m;
  f.sds_m = sds_m;
  f.weights = weights;
  f.floors = Eigen::VectorXi::Constant(means_m.rows(), PositionFix::kAnyFloor);
  return f;
}

}  // namespace indoorloc::fusion
