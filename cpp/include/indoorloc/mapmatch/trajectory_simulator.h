// Vehicle trajectories on a road network with odometer and compass measurements (paper 000,
// §III): constant speed, a random continuation (left, right or straight where allowed) at every
// segment end (left or right; straight only where no turn exists, unless allow_straight),
// unknown start; odometer speed = true speed + a per-run bias + Gaussian noise;
// compass heading = true heading + von Mises noise.
#pragma once

#include <string>

#include <Eigen/Core>

#include "indoorloc/core/random.h"
#include "indoorloc/mapmatch/road_network.h"

namespace indoorloc::mapmatch {

struct TrajectoryOptions {
  double duration_s = 200.0;            ///< paper: 200 s
  double dt_s = 0.5;                    ///< sample period of both sensors (2 Hz)
  double speed_mps = 2.0;               ///< paper: constant 2 m/s
  double speed_noise_sd_mps = 0.6;      ///< paper: Gaussian odometer error, sd 0.6 m/s
  double speed_bias_halfwidth_mps = 0.5;  ///< paper: per-run bias ~ U(-0.5, 0.5) m/s
  double heading_kappa = 2.0;           ///< compass von Mises concentration (ours: the paper gives none)
  /// Paper: "when it reaches the end of a segment, it chooses randomly to turn left or right".
  /// false: straight continuations (heading change below 30°) are taken only when no turn
  /// exists; true: every continuation is equally likely.
  bool allow_straight = false;

  bool IsValid(std::string* error) const;
};

/// A simulated run: T = duration / dt samples, sample k at time (k + 1) dt.
struct Trajectory {
  RowMatrixXd positions_m;          ///< T x 2 true positions
  Eigen::VectorXi segments;         ///< T true segment indices
  Eigen::VectorXd heading_true_rad; ///< T true direction of travel
  Eigen::VectorXd speed_mps;        ///< T odometer readings
  Eigen::VectorXd heading_rad;      ///< T compass readings, in (-π, π]
  double speed_bias_mps = 0.0;      ///< the run's odometer bias
  Eigen::Vector2d start_m = Eigen::Vector2d::Zero();
};

/// Simulates one run with its own random stream.
Trajectory SimulateTrajectory(const RoadNetwork& network, const TrajectoryOptions& options, RandomStream& rng);

/// Heading of travel on `segment` in direction `direction` (+1: A to B, -1: B to A) [rad].
double TravelHeading(const RoadNetwork& network, int segment, int direction);

}  // namespace indoorloc::mapmatch
