// Test helper of the fusion tests: the 60 x 40 m hall the grid tracker and grid session tests
// walk in, and the axis-aligned boxes its rings are made of.
#pragma once

#include <vector>

#include "indoorloc/fusion/floor_plan.h"

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

}  // namespace indoorloc::fusion
