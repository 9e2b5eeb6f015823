// Small synthetic signal maps shared by the wifi tests.
#pragma once

#include <cmath>

#include "indoorloc/wifi/signal_map.h"

namespace indoorloc::wifi::testing {

/// Log-distance path loss [dBm] of an AP at (ax, ay) heard at (x, y): -40 - 20 log10(d + 0.5).
inline double PathLoss(double ax, double ay, double x, double y) {
  return -40.0 - 20.0 * std::log10(std::hypot(x - ax, y - ay) + 0.5);
}

/// A nx x ny lattice with spacing (dx, dy) and 4 APs at the corners of a 10 m square. The
/// variance grows with distance (variance_slope dB^2/m) so that both means and variances carry
/// position information; with variance_slope = 0 it is constant, and a scan equal to the mean
/// m(z*) then has its likelihood maximum exactly at z* (otherwise ½ log δ biases it).
inline SignalMap LatticeMap(int nx = 6, int ny = 6, double dx = 2.0, double dy = 2.0,
                            double variance_slope = 0.3) {
  const double aps[4][2] = {{-1, -1}, {11, -1}, {-1, 11}, {11, 11}};
  RowMatrixXd positions(nx * ny, 2), mean(nx * ny, 4), variance(nx * ny, 4);
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      const int r = i * ny + j;
      positions(r, 0) = i * dx;
      positions(r, 1) = j * dy;
      for (int a = 0; a < 4; ++a) {
        mean(r, a) = PathLoss(aps[a][0], aps[a][1], i * dx, j * dy);
        variance(r, a) = 4.0 + variance_slope * std::hypot(i * dx - aps[a][0], j * dy - aps[a][1]);
      }
    }
  }
  return SignalMap(positions, Eigen::VectorXi::Zero(nx * ny), mean, variance);
}

}  // namespace indoorloc::wifi::testing
