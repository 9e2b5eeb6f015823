// An outside application: uses the installed indoorloc package through find_package(indoorloc).
//  1. core: weight 1000 particles by a Gaussian likelihood, resample when ESS < N/2;
//  2. fusion: a small floor plan (a room with a pillar) and a few steps of the particle tracker
//     from a known start: fusion is usable embedded, without Python.
#include <cmath>
#include <cstdio>
#include <vector>

#include <indoorloc/core.h>
#include <indoorloc/fusion/floor_plan.h>
#include <indoorloc/fusion/particle_tracker.h>

int main() {
  indoorloc::RandomStream rng(/*seed=*/42);
  Eigen::VectorXd log_w(1000);
  for (auto& lw : log_w) lw = -0.5 * std::pow((rng.Normal() - 0.5) / 0.3, 2);
  std::vector<int> ancestors;
  auto summary = indoorloc::ResampleIfNeeded(log_w, indoorloc::ResamplingOptions(), rng, &ancestors);
  std::printf("indoorloc %s: %s\n", indoorloc::kVersion, summary.BriefReport().c_str());
  if (!summary.resampled || ancestors.size() != 1000) return 1;

  namespace fusion = indoorloc::fusion;
  fusion::FloorGeometry room;
  room.outlines.push_back((fusion::RowMatrixXd(4, 2) << 0, 0, 10, 0, 10, 6, 0, 6).finished());
  room.obstacles.push_back((fusion::RowMatrixXd(4, 2) << 4, 2, 6, 2, 6, 4, 4, 4).finished());
  const fusion::FloorPlan plan({room});
  fusion::TrackerOptions options;
  options.num_particles = 500;
  options.seed = 1;
  fusion::ParticleTracker tracker(&plan, /*wifi_model=*/nullptr, /*corridors=*/nullptr, options);
  tracker.InitializeKnown(0.0, Eigen::Vector2d(1.0, 1.0), /*floor=*/0, /*heading_offset_rad=*/0.0);
  fusion::TrackerEstimate estimate;
  for (int k = 1; k <= 8; ++k) {  // eight 0.7 m steps east along y = 1
    estimate = tracker.Step(fusion::StepFromPolar(0.5 * k, 0.7, 0.0, 0.05, 0.05));
  }
  std::printf("fusion: after 8 steps at (%.2f, %.2f) m (truth (6.60, 1.00)); %s\n", estimate.mean_m.x(),
              estimate.mean_m.y(), tracker.summary().BriefReport().c_str());
  return std::hypot(estimate.mean_m.x() - 6.6, estimate.mean_m.y() - 1.0) < 1.0 ? 0 : 1;
}
