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

namespace indoorloc::wifi::testing {

/// A survey where each of `num_aps` APs is heard within about 8 m only: elsewhere its points
/// hold the not-heard value (-105 dBm) and the variance floor (4 dB^2), the structure real
/// building maps have and that Evaluate's sparse path exploits. Points on a jittered 1.5 m
/// lattice of a 30 m x 20 m floor; `seed` moves the jitter and the APs.
inline SignalMap PartlyHeardMap(int num_aps = 25, unsigned seed = 7) {
  unsigned state = seed;
  auto uniform = [&state]() {  // small LCG: the map must not depend on the library's RNG
    state = state * 1664525u + 1013904223u;
    return (state >> 8) / static_cast<double>(1u << 24);
  };
  const int nx = 21, ny = 14;
  RowMatrixXd positions(nx * ny, 2), mean(nx * ny, num_aps), variance(nx * ny, num_aps);
  Eigen::MatrixXd aps(num_aps, 2);
  for (int a = 0; a < num_aps; ++a) aps.row(a) << 30.0 * uniform(), 20.0 * uniform();
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      const int r = i * ny + j;
      positions(r, 0) = 1.5 * i + 0.3 * uniform();
      positions(r, 1) = 1.5 * j + 0.3 * uniform();
      for (int a = 0; a < num_aps; ++a) {
        const double m = PathLoss(aps(a, 0), aps(a, 1), positions(r, 0), positions(r, 1)) - 20.0;
        const bool heard = m > -80.0;
        mean(r, a) = heard ? m : -105.0;
        variance(r, a) = heard ? 4.0 + 20.0 * uniform() : 4.0;
      }
    }
  }
  return SignalMap(positions, Eigen::VectorXi::Zero(nx * ny), mean, variance);
}

}  // namespace indoorloc::wifi::testing
