// The particle tracker's corridor mode (a mapmatch::RoadNetwork is given): particles live on the
// network (segment, direction of travel, distance along) and move along it by the length of
// their sampled step s' R(o') (d + e) (uniform choice among the continuations at a junction,
// paper 000 eq. 8-10); each is weighted by the von Mises likelihood of its step's heading
// against its direction of travel β(S, d) (paper 000 eq. 11):
//   log w += κ cos(heading - β(S, d)) - log(2π I0(κ)).
// The same model is written in mapmatch/particle_map_matcher.cc; both are to be replaced by one
// shared corridor motion model.
#include <algorithm>
#include <cmath>

#include "particle_tracker_impl.h"

namespace indoorloc::fusion {

void ParticleTracker::Impl::MoveAlongCorridors(const StepMotion& motion) {
  const double kappa = options.corridor_kappa;
  const double log_vm_norm = std::log(2.0 * M_PI * std::cyl_bessel_i(0.0, kappa));
  ForBlocks(n, [&](int, int begin, int end, RandomStream& block_rng) {
    for (int i = begin; i < end; ++i) {
      double o, sc;
      Eigen::Vector2d delta;
      motion.Sample(offset[i], &cos_offset[i], &sin_offset[i], scale[i], block_rng, &o, &sc, &delta);
      offset[i] = o;
      scale[i] = sc;
      // Paper 000 eq. 8-10 with the step's length, eq. 11 with the step's heading.
      const double length = delta.norm();
      const double heading = std::atan2(delta.y(), delta.x());
      const Eigen::VectorXd& lengths = corridors->lengths_m();
      int seg = segment[i];
      int d = direction[i];
      double u = along[i] + d * length;
      for (int guard = 0; guard < 10000; ++guard) {
        int e;
        double left;
        if (d > 0 && u > lengths[seg]) {
          e = 1;
          left = u - lengths[seg];
        } else if (d < 0 && u < 0.0) {
          e = 0;
          left = -u;
        } else {
          break;
        }
        const auto& choices = corridors->continuations(seg, e);
        const auto& c = choices[choices.size() > 1 ? block_rng.UniformInt(choices.size()) : 0];
        seg = c.segment;
        d = c.enter_end == 0 ? 1 : -1;
        u = c.enter_end == 0 ? left : lengths[seg] - left;
      }
      u = std::clamp(u, 0.0, lengths[seg]);
      segment[i] = seg;
      direction[i] = static_cast<signed char>(d);
      along[i] = u;
      const Eigen::Vector2d q = corridors->point_at(seg, u);
      x[i] = q.x();
      y[i] = q.y();
      const double beta = corridors->headings_rad()[seg] + (d > 0 ? 0.0 : M_PI);
      if (length > 1e-9) log_w[i] += kappa * std::cos(heading - beta) - log_vm_norm;
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
