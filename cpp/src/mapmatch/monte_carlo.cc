#include "indoorloc/mapmatch/monte_carlo.h"

#include <cmath>

#include "indoorloc/core/interrupt.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::mapmatch {

RunResult RunOnce(const RoadNetwork& network, const TrajectoryOptions& trajectory, const FilterOptions& filter,
                  std::uint64_t seed, int run) {
  RandomStream trajectory_rng(seed, 2 * static_cast<std::uint64_t>(run));
  const Trajectory t = SimulateTrajectory(network, trajectory, trajectory_rng);
  FilterOptions options = filter;
  options.seed = DeriveSeed(seed, 2 * static_cast<std::uint64_t>(run) + 1);
  ParticleMapMatcher pf(network, options);
  const Eigen::Index steps = t.speed_mps.size();
  RunResult out;
  out.error_m.resize(steps);
  out.correct_segment.resize(steps);
  out.tracking.resize(steps);
  out.smoothed_error_m = Eigen::VectorXd::Constant(steps, std::nan(""));
  out.speed_bias_mps = t.speed_bias_mps;
  const int lag = options.smoothing_lag_steps;
  for (Eigen::Index k = 0; k < steps; ++k) {
    CheckInterrupt();  // a run may be 1e8 steps long: Ctrl-C must not wait for its end
    const StepEstimate e = pf.Step(t.speed_mps[k], t.heading_rad[k], trajectory.dt_s);
    out.error_m[k] = (e.position_m - t.positions_m.row(k).transpose()).norm();
    out.correct_segment[k] = e.segment == t.segments[k];
    out.tracking[k] = e.tracking;
    if (lag > 0 && k >= lag && std::isfinite(e.smoothed_m[0])) {
      out.smoothed_error_m[k - lag] = (e.smoothed_m - t.positions_m.row(k - lag).transpose()).norm();
    }
  }
  out.summary = pf.summary();
  return out;
}

std::vector<RunResult> RunMonteCarlo(const RoadNetwork& network, const TrajectoryOptions& trajectory,
                                     const FilterOptions& filter, int n_runs, std::uint64_t seed, int n_threads) {
  ValidateOptions(trajectory, "trajectory");
  ValidateOptions(filter, "filter");
  // The filter's recovery window is sized from the trajectory's step: refuse it here, before
  // any run simulates its trajectory (the same bound the filter checks at its first step).
  if (filter.recovery_disagreement > 0.0) {
    RequireSizeLimit(filter.recovery_window_s / trajectory.dt_s, sizeof(double), "dt_s",
                     "recovery-window slots (recovery_window_s / dt_s)", 1e9);
  }
  std::vector<RunResult> results(static_cast<size_t>(std::max(0, n_runs)));
  ParallelForRuns(n_runs, n_threads, seed, [&](int run, RandomStream&) {
    results[static_cast<size_t>(run)] = RunOnce(network, trajectory, filter, seed, run);
  });
  return results;
}

}  // namespace indoorloc::mapmatch
