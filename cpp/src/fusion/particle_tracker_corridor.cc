// The particle tracker's corridor mode (a mapmatch::RoadNetwork is given): particles live on the
// network (segment, direction of travel, distance along) and move along it by the length of
// their sampled step s' R(o') (d + e) (uniform choice among the continuations at a junction,
// paper 000 eq. 8-10); each is weighted by the von Mises likelihood of its step's heading
// against its direction of travel β(S, d) (paper 000 eq. 11):
//   log w += κ cos(heading - β(S, d)) - log(2π I0(κ)).
// The move and the weight are mapmatch::CorridorMotion's, the model mapmatch::ParticleMapMatcher
// uses (uniform junction policy here).
#include <algorithm>
#include <cmath>

#include "particle_tracker_impl.h"

namespace indoorloc::fusion {

void ParticleTracker::Impl::MoveAlongCorridors(const StepMotion& motion) {
  const mapmatch::CorridorMotion& network_model = *corridor_motion;
  ForBlocks(n, [&](int, int begin, int end, RandomStream& block_rng) {
    for (int i = begin; i < end; ++i) {
      const Eigen::Vector2d delta = SampleStep(motion, i, block_rng);
      // Paper 000 eq. 8-10 with the step's length, eq. 11 with the step's heading.
      const double length = delta.norm();
      const double heading = std::atan2(delta.y(), delta.x());
      network_model.Move(&segment[i], &direction[i], &along[i], length, heading, block_rng);
      const Eigen::Vector2d q = corridors->point_at(segment[i], along[i]);
      x[i] = q.x();
      y[i] = q.y();
      // A step of no length has no heading: no weight.
      if (length > 1e-9) log_w[i] += network_model.LogHeadingLikelihood(segment[i], direction[i], heading);
    }
  });
}

// Particle i onto the network point nearest (px, py), with a random direction of travel.
void ParticleTracker::Impl::PlaceOnCorridors(int i, double px, double py) {
  const mapmatch::Projection p = corridors->Nearest(Eigen::Vector2d(px, py));
  segment[i] = p.segment;
  along[i] = p.along_m;
  direction[i] = rng.Uniform01() < 0.5 ? 1 : -1;
  const Eigen::Vector2d q = corridors->point_at(segment[i], along[i]);
  x[i] = q.x();
  y[i] = q.y();
}

// A point uniform along the network [m].
Eigen::Vector2d ParticleTracker::Impl::UniformOnCorridors() {
  double s = rng.Uniform01() * corridors->total_length_m();
  int seg = 0;
  while (seg + 1 < corridors->num_segments() && s >= corridors->lengths_m()[seg]) s -= corridors->lengths_m()[seg++];
  return corridors->point_at(seg, s);
}

}  // namespace indoorloc::fusion
