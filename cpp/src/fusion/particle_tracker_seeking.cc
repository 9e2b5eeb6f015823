// Placing the particle tracker's particles without a known start (the seeking phase of paper
// 000 §IV) and at recovery: a grid of candidate points over the walkable area of every floor
// (candidate_spacing_m), draws from an absolute observation's likelihood over the candidates
// with jitter inside a candidate's cell, or a uniform cloud over the walkable area (the network
// in corridor mode). Heading offsets of such particles are uniform on the circle, or N(0, sd²)
// when the PDR heading is nearly absolute (unknown_start_heading_sd_rad).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "indoorloc/core/check.h"
#include "particle_tracker_impl.h"

namespace indoorloc::fusion {

void ParticleTracker::Impl::BuildCandidates() {
  const double h = options.candidate_spacing_m;
  candidates.assign(floors.size(), RowMatrixXd());
  for (size_t f = 0; f < floors.size(); ++f) {
    std::vector<double> pts;
    if (plan) {
      const Eigen::Vector4d b = plan->Bounds(plan_floor[f]);
      const int nx = static_cast<int>(std::floor((b[2] - b[0]) / h)) + 1;
      const int ny = static_cast<int>(std::floor((b[3] - b[1]) / h)) + 1;
      CheckArgument(static_cast<double>(nx) * ny <= 2e7, "options.candidate_spacing_m",
                    "gives more than 2e7 candidate points on floor " + std::to_string(floors[f]) + ": use a larger spacing");
      for (int j = 0; j < ny; ++j) {
        for (int i = 0; i < nx; ++i) {
          const double px = b[0] + (i + 0.5) * h, py = b[1] + (j + 0.5) * h;
          if (px <= b[2] && py <= b[3] && plan->IsWalkable(px, py, plan_floor[f])) {
            pts.push_back(px);
            pts.push_back(py);
          }
        }
      }
    } else if (model) {
      const int mf = model_floor[f];
      for (int row : model->points_on_floor(mf)) {
        pts.push_back(model->map().positions_m()(row, 0));
        pts.push_back(model->map().positions_m()(row, 1));
      }
    }
    candidates[f] = Eigen::Map<RowMatrixXd>(pts.data(), static_cast<Eigen::Index>(pts.size() / 2), 2);
  }
}

// Log-likelihood point_ll(x, y, tracker floor) at every candidate of every floor (concatenated).
Eigen::VectorXd ParticleTracker::Impl::CandidateLogLikelihoods(const PointLogLikelihood& point_ll,
                                                               std::vector<int>* candidate_floor,
                                                               std::vector<int>* candidate_row) {
  int total = 0;
  for (const auto& c : candidates) total += static_cast<int>(c.rows());
  candidate_floor->resize(total);
  candidate_row->resize(total);
  int k = 0;
  for (size_t f = 0; f < candidates.size(); ++f) {
    for (Eigen::Index r = 0; r < candidates[f].rows(); ++r, ++k) {
      (*candidate_floor)[k] = static_cast<int>(f);
      (*candidate_row)[k] = static_cast<int>(r);
    }
  }
  Eigen::VectorXd ll(total);
  ForBlocks(total, [&](int, int begin, int end, RandomStream&) {
    for (int i = begin; i < end; ++i) {
      const int f = (*candidate_floor)[i];
      ll[i] = point_ll(candidates[f]((*candidate_row)[i], 0), candidates[f]((*candidate_row)[i], 1), f);
    }
  });
  return ll;
}

// Replaces the particles in `slots` by draws from the candidates' likelihood point_ll (with
// uniform jitter within a candidate cell, kept walkable), heading offsets as UnknownOffset.
void ParticleTracker::Impl::DrawFromCandidates(const PointLogLikelihood& point_ll, const std::vector<int>& slots) {
  std::vector<int> cf, cr;
  const Eigen::VectorXd ll = CandidateLogLikelihoods(point_ll, &cf, &cr);
  if (ll.size() == 0) ThrowInvalidArgument("plan", "has no candidate point (walkable area smaller than the candidate grid)");
  std::vector<int> picks;
  Resample(ll, ResamplingScheme::kSystematic, rng, &picks, static_cast<int>(slots.size()));
  const double h = options.candidate_spacing_m;
  for (size_t j = 0; j < slots.size(); ++j) {
    const int c = picks[j];
    const int f = cf[c];
    const double cx = candidates[f](cr[c], 0), cy = candidates[f](cr[c], 1);
    double px = cx, py = cy;
    if (plan) {
      for (int attempt = 0; attempt < 20; ++attempt) {
        const double qx = cx + rng.Uniform(-0.5 * h, 0.5 * h), qy = cy + rng.Uniform(-0.5 * h, 0.5 * h);
        if (plan->IsWalkable(qx, qy, plan_floor[f])) {
          px = qx;
          py = qy;
          break;
        }
      }
    } else {
      px += rng.Uniform(-0.5 * h, 0.5 * h);
      py += rng.Uniform(-0.5 * h, 0.5 * h);
    }
    PlaceFree(slots[j], px, py, f, UnknownOffset());
  }
}

// Heading offset of a particle placed without a known start.
double ParticleTracker::Impl::UnknownOffset() {
  const double sd = options.unknown_start_heading_sd_rad;
  return std::isinf(sd) ? rng.Uniform(-M_PI, M_PI) : sd * rng.Normal();
}

// Sets particle i at (px, py) on tracker floor f with offset o and a scale from the prior (in
// corridor mode projected onto the network).
void ParticleTracker::Impl::PlaceFree(int i, double px, double py, int f, double o) {
  x[i] = px;
  y[i] = py;
  floor[i] = f;
  offset[i] = tracker_detail::WrapAngle(o);
  cos_offset[i] = std::cos(offset[i]);
  sin_offset[i] = std::sin(offset[i]);
  scale[i] = std::clamp(1.0 + options.start_scale_sd * rng.Normal(), options.motion.min_scale, options.motion.max_scale);
  if (corridor_mode()) PlaceOnCorridors(i, px, py);
}

// Uniform cloud: floor in proportion to its walkable area (or candidate count without a plan),
// then a point uniform on it (on the network in corridor mode); uniform weights.
void ParticleTracker::Impl::UniformCloud() {
  std::vector<double> mass(floors.size());
  for (size_t f = 0; f < floors.size(); ++f) {
    if (corridor_mode()) {
      // One floor (checked at construction); without a plan or a map there are no candidates.
      mass[f] = corridors->total_length_m();
    } else {
      mass[f] = plan ? plan->WalkableArea(plan_floor[f]) : static_cast<double>(candidates[f].rows());
    }
  }
  double total = 0.0;
  for (double m : mass) total += m;
  CheckArgument(total > 0.0, "plan", "no walkable area or candidate point to start from");
  for (int i = 0; i < n; ++i) {
    double u = rng.Uniform01() * total;
    size_t f = 0;
    while (f + 1 < mass.size() && u >= mass[f]) u -= mass[f++];
    double px, py;
    if (corridor_mode()) {
      const Eigen::Vector2d q = UniformOnCorridors();
      px = q.x();
      py = q.y();
    } else if (plan) {
      const RowMatrixXd p = plan->SampleWalkable(1, plan_floor[f], rng);
      px = p(0, 0);
      py = p(0, 1);
    } else {
      const int r = static_cast<int>(rng.UniformInt(static_cast<std::uint64_t>(candidates[f].rows())));
      px = candidates[f](r, 0) + rng.Uniform(-0.5, 0.5) * options.candidate_spacing_m;
      py = candidates[f](r, 1) + rng.Uniform(-0.5, 0.5) * options.candidate_spacing_m;
    }
    PlaceFree(i, px, py, static_cast<int>(f), UnknownOffset());
  }
  log_w.setConstant(-std::log(static_cast<double>(n)));
}

}  // namespace indoorloc::fusion
