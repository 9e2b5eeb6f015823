// Monte Carlo evaluation of the map-matching filter (paper 000, §III): simulate a run, filter
// it, score it. RunOnce is a pure function of (network, options, seed, run), so runs can be
// distributed over threads or machines; run r draws its trajectory from stream (seed, 2r) and
// seeds its filter from stream (seed, 2r + 1).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/mapmatch/particle_map_matcher.h"
#include "indoorloc/mapmatch/trajectory_simulator.h"

namespace indoorloc::mapmatch {

struct RunResult {
  Eigen::VectorXd error_m;           ///< T: ||estimate - truth|| per step
  Eigen::VectorXi correct_segment;   ///< T: 1 when the estimated segment is the true one
  Eigen::VectorXi tracking;          ///< T: the filter's own tracking flag
  Eigen::VectorXd smoothed_error_m;  ///< T: fixed-lag smoothed error at step k - lag (NaN before)
  double speed_bias_mps = 0.0;
  FilterSummary summary;
};

/// One simulated run filtered and scored.
RunResult RunOnce(const RoadNetwork& network, const TrajectoryOptions& trajectory, const FilterOptions& filter,
                  std::uint64_t seed, int run);

/// n_runs runs on n_threads threads (0: all cores); results do not depend on n_threads.
std::vector<RunResult> RunMonteCarlo(const RoadNetwork& network, const TrajectoryOptions& trajectory,
                                     const FilterOptions& filter, int n_runs, std::uint64_t seed, int n_threads);

}  // namespace indoorloc::mapmatch
