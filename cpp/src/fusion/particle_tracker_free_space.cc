// The particle tracker's free-space mode: every particle moves by the step motion model
// (step_motion.h) and is tested against the floor plan's walls. A particle whose step p -> p'
// crosses a wall gets log w += wall_log_penalty (-inf: dropped, and it stays at p), so with hard
// walls no particle ever ends inside an obstacle; with floor_change_probability a particle may
// move to another floor instead (then only p' must be walkable). When a whole cloud keeps being
// blocked it is re-spread around its mean (Respread).
#include <cmath>
#include <cstdint>
#include <vector>

#include "particle_tracker_impl.h"

namespace indoorloc::fusion {

// Moves every particle by one step; blocked_mass[b] receives the weight (normalised before the
// step) blocked by walls in particle block b. Per block in three passes: the motion of every
// particle into block-local end points, the wall test of the block's steps in one call, then
// blocked particles penalised (and, with hard walls, left where they were) and the others moved.
void ParticleTracker::Impl::MoveFreeSpace(const StepMotion& motion, std::vector<double>* blocked_mass) {
  const int num_floors = static_cast<int>(floors.size());
  if (num_floors > 1 && options.floor_change_probability > 0.0) {
    MoveFreeSpaceChangingFloors(motion, blocked_mass);
    return;
  }
  const double penalty = options.wall_log_penalty;
  const bool drop = std::isinf(penalty);
  ForBlocks(n, [&](int b, int begin, int end, RandomStream& block_rng) {
    const int count = end - begin;
    double qx[kBlockSize], qy[kBlockSize];
    bool hit[kBlockSize];
    // The block's normals from eight lanes seeded by the block's stream (which also serves the
    // ziggurat's rare slow path): depends on (seed, event, block) only.
    RandomLanes lanes(block_rng(), tracker_detail::kMotionLanesStream);
    motion.SampleBlock(count, offset.data() + begin, cos_offset.data() + begin, sin_offset.data() + begin,
                       scale.data() + begin, lanes, block_rng, qx, qy);
    for (int k = 0; k < count; ++k) {
      qx[k] = x[begin + k] + qx[k];
      qy[k] = y[begin + k] + qy[k];
    }
    if (!plan) {
      for (int k = 0; k < count; ++k) {
        x[begin + k] = qx[k];
        y[begin + k] = qy[k];
      }
      return;
    }
    // Tracker floor index f is plan floor index f whenever there is a plan.
    plan->CrossesWallSpan(count, x.data() + begin, y.data() + begin, qx, qy, floor.data() + begin, hit);
    double blocked = 0.0;
    // Most blocked particles share one log-weight (equal weights since the last resampling):
    // its exp is kept (the same bits as calling exp again).
    double last_log_w = 0.0, last_w = 1.0;
    for (int k = 0; k < count; ++k) {
      const int i = begin + k;
      if (hit[k]) {
        if (log_w[i] != last_log_w) {
          last_log_w = log_w[i];
          last_w = std::exp(last_log_w);
        }
        blocked += last_w;
        log_w[i] += penalty;
        if (drop) continue;  // dropped: stays where it was
      }
      x[i] = qx[k];
      y[i] = qy[k];
    }
    (*blocked_mass)[b] = blocked;
  });
}

// MoveFreeSpace with floor changes: a particle may move to another floor (uniformly chosen) with
// probability floor_change_probability, and then only its end point must be walkable there.
void ParticleTracker::Impl::MoveFreeSpaceChangingFloors(const StepMotion& motion, std::vector<double>* blocked_mass) {
  const double penalty = options.wall_log_penalty;
  const int num_floors = static_cast<int>(floors.size());
  const double p_change = options.floor_change_probability;
  ForBlocks(n, [&](int b, int begin, int end, RandomStream& block_rng) {
    double blocked = 0.0;
    for (int i = begin; i < end; ++i) {
      const Eigen::Vector2d delta = SampleStep(motion, i, block_rng);
      const double qx = x[i] + delta.x(), qy = y[i] + delta.y();
      int f = floor[i];
      bool is_blocked;
      if (block_rng.Uniform01() < p_change) {
        int g = static_cast<int>(block_rng.UniformInt(static_cast<std::uint64_t>(num_floors - 1)));
        if (g >= f) ++g;
        f = g;
        is_blocked = !Walkable(qx, qy, f);
      } else {
        is_blocked = Blocked(x[i], y[i], qx, qy, f);
      }
      if (is_blocked) {
        blocked += std::exp(log_w[i]);
        log_w[i] += penalty;
        if (std::isinf(penalty)) continue;  // dropped: stays where it was
      }
      x[i] = qx;
      y[i] = qy;
      floor[i] = f;
    }
    (*blocked_mass)[b] = blocked;
  });
}

// Gaussian cloud (sd respread_sd_m) around the current mean on its most probable floor, kept
// on walkable points; heading offsets and scales are kept, weights become uniform.
void ParticleTracker::Impl::Respread() {
  TrackerEstimate est;
  FillEstimate(&est);
  const int f = est.floor_index;
  for (int i = 0; i < n; ++i) {
    double px = est.mean_m.x(), py = est.mean_m.y();
    for (int attempt = 0; attempt < 50; ++attempt) {
      const double qx = est.mean_m.x() + options.respread_sd_m * rng.Normal();
      const double qy = est.mean_m.y() + options.respread_sd_m * rng.Normal();
      if (Walkable(qx, qy, f)) {
        px = qx;
        py = qy;
        break;
      }
    }
    int pf = f;
    if (!Walkable(px, py, f)) {  // the mean itself is inside an obstacle: keep the particle
      px = x[i];
      py = y[i];
      pf = floor[i];
    }
    const double o = offset[i];
    const double s = scale[i];
    PlaceFree(i, px, py, pf, o);
    scale[i] = s;
  }
  log_w.setConstant(-std::log(static_cast<double>(n)));
  ++summary.respreads;
}

}  // namespace indoorloc::fusion
