// Motion of a particle along a road or corridor network, weighted by the von Mises likelihood
// of its direction of travel (paper 000, §II.C, eq. 8-11): the one corridor model shared by
// mapmatch::ParticleMapMatcher and the corridor mode of fusion::ParticleTracker.
//
// A particle is (segment S, travel direction d = ±1, distance u from end A [m]).
//  - Move (eq. 8-10): u advances by d · distance. Past the end ahead, the remaining distance is
//    carried onto a continuation of that end, chosen uniformly (the paper) or, with
//    JunctionPolicy::kHeadingAware, with probabilities q_j ∝ exp(κ_J cos(φ − heading_j)); Move
//    then returns the importance factor (1/n) / q_j (prior over proposal) that keeps the
//    filter's posterior unchanged. A negative distance moves the particle back within its
//    segment and stops it at the end behind it (it never backs onto another segment: the
//    particle keeps no history of where it came from; docs/mapmatch.md).
//  - Heading weight (eq. 11): log f_vM(φ; β(S, d), κ) = κ cos(φ − β(S, d)) − log(2π I0(κ)),
//    β(S, +1) = β_S, β(S, −1) = β_S + π. The normaliser is computed as log 2π + κ + log(I0(κ) e^−κ),
//    finite for any κ (log(2π I0(κ)) overflows above κ ≈ 713).
//  - The concentration is capped at kMaxCorridorKappa = 300: the factor relative to its maximum,
//    e^{κ (cos − 1)} >= e^{−2κ}, then stays a normal double (>= e^{−600}), so a filter may keep
//    linear weights (the map matcher does). κ = 300 is a heading sd of 3.3°, tighter than any
//    compass or PDR heading.
//
// Thread safety: every method is const and uses no scratch, so particle blocks on several
// threads may share one CorridorMotion (each with its own RandomStream).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/core/random.h"
#include "indoorloc/core/random_lanes.h"
#include "indoorloc/mapmatch/road_network.h"

namespace indoorloc::mapmatch {

/// How a particle reaching a segment end chooses among several continuations.
enum class JunctionPolicy {
  kUniform,       ///< each continuation with probability 1/n (paper 000)
  kHeadingAware,  ///< proposal ∝ exp(κ_J cos(φ − heading_j)), importance-corrected
};

/// Largest accepted von Mises concentration (see the header comment).
inline constexpr double kMaxCorridorKappa = 300.0;

struct CorridorMotionOptions {
  /// κ, concentration of the von Mises heading likelihood (eq. 11), in [0, kMaxCorridorKappa].
  double kappa = 1.0;
  JunctionPolicy junction_policy = JunctionPolicy::kUniform;
  /// κ_J of the heading-aware junction proposal, in [0, kMaxCorridorKappa].
  double junction_kappa = 2.0;

  bool IsValid(std::string* error) const;
};

class CorridorMotion {
 public:
  /// Keeps a reference to `network`, which must outlive the model. Throws std::invalid_argument
  /// for invalid options.
  CorridorMotion(const RoadNetwork& network, const CorridorMotionOptions& options);

  /// Moves one particle by `distance_m` along its direction of travel (eq. 8-10), crossing
  /// junctions as needed; `heading_rad` (φ, the measured heading) is used by the heading-aware
  /// junction policy only. Returns the importance-weight factor of the junction proposal (1 for
  /// the uniform policy). Draws from `rng` only at junctions with several continuations.
  double Move(int* segment, signed char* direction, double* along_m, double distance_m, double heading_rad,
              RandomStream& rng) const {
    const double u = *along_m + *direction * distance_m;
    if (u >= 0.0 && u <= lengths_[*segment]) {  // the common case: no segment end reached
      *along_m = u;
      return 1.0;
    }
    return MoveAcrossEnds(segment, direction, along_m, distance_m, heading_rad, rng);
  }

  /// Caller-owned scratch of MoveAll (so that the model stays const and shareable).
  struct MoveScratch {
    std::vector<int> at_end;         ///< particles that reached a segment end
    std::vector<double> uniforms;    ///< one junction draw per such particle
  };
  /// Moves particles [0, count) by distance_m[i] each, as Move: first every in-segment move in
  /// one branch-free (vectorised) pass that also lists the particles reaching a segment end
  /// (a few percent per step), then those in index order. Each listed particle takes one
  /// uniform from `lanes`; with the uniform policy a single forward hop onto a continuation that
  /// contains the rest of the move (the common case) picks continuation floor(U n) directly.
  /// Every other case (several hops, a move backwards, the heading-aware policy) goes through
  /// Move's general path with its draws from `rng`. Where a junction proposal's importance
  /// factor is not 1 it multiplies weight[i] (`weight` may be null with the uniform policy).
  void MoveAll(int count, const double* distance_m, int* segment, signed char* direction, double* along_m,
               double heading_rad, RandomLanes& lanes, RandomStream& rng, double* weight, MoveScratch* scratch) const;

  /// The in-segment pass of MoveAll over particles [0, count): along_m[i] += d · distance_m[i]
  /// where the particle stays on its segment (vectorised, branch-free); the others are left
  /// unchanged and listed in at_end (count + 4 entries: whole groups are stored) in index order.
  /// Returns how many were listed; finish each with MoveFromEnd.
  int MoveWithinSegments(int count, const double* distance_m, const int* segment, const signed char* direction,
                         double* along_m, int* at_end) const;
  /// The junction part of MoveAll for one particle whose move u = along + d · distance_m leaves
  /// its segment: with the uniform policy a single forward hop picks continuation
  /// floor(junction_uniform · n) (junction_uniform in [0, 1)); every other case goes through
  /// Move's general path with its draws from `rng`. Returns the importance factor (1 for the
  /// uniform policy). Exposed so that a filter can fuse it into its own per-particle pass.
  double MoveFromEnd(int* segment, signed char* direction, double* along_m, double distance_m,
                     double junction_uniform, double heading_rad, RandomStream& rng) const {
    // The common case: forward over the end ahead, one hop, the rest of the move within the
    // continuation. Selections by arithmetic and table lookups rather than branches: the travel
    // direction is a coin toss per particle, a mispredicted branch cost more than the rest.
    const int s = *segment;
    const int d = *direction;
    const double u = *along_m + d * distance_m;
    const int forward = d > 0;
    const double leftover = d * u - lengths_[s] * forward;  // u - length forward, -u backward (exact)
    if (options_.junction_policy == JunctionPolicy::kUniform && leftover > 0.0) {
      const int first = continuation_begin_[static_cast<size_t>(2 * s + forward)];
      const int n_choices = continuation_begin_[static_cast<size_t>(2 * s + forward + 1)] - first;
      const int pick = std::min(n_choices - 1, static_cast<int>(junction_uniform * n_choices));
      const int next = continuation_segment_[static_cast<size_t>(first + pick)];
      const double next_length = lengths_[next];
      if (leftover <= next_length) {
        const int enter_b = continuation_enter_end_[static_cast<size_t>(first + pick)];  // 0: enter at end A
        const double base[2] = {0.0, next_length}, sign[2] = {1.0, -1.0};
        *segment = next;
        *direction = static_cast<signed char>(1 - 2 * enter_b);
        *along_m = base[enter_b] + sign[enter_b] * leftover;  // leftover or length - leftover (exact)
        return 1.0;
      }
    }
    return MoveAcrossEnds(segment, direction, along_m, distance_m, heading_rad, rng);
  }

  /// log f_vM(φ; β(S, d), κ) = κ cos(φ − β(S, d)) − log(2π I0(κ)) [nats] (eq. 11), with
  /// β(S, d) = β_S (d > 0) or β_S + π (d < 0).
  double LogHeadingLikelihood(int segment, int direction, double heading_rad) const {
    const double beta = headings_[segment] + (direction > 0 ? 0.0 : kPi);
    return options_.kappa * std::cos(heading_rad - beta) - log_normaliser_;
  }
  /// Per-step tables over the 2M (segment, direction) pairs, index 2 S + (d > 0): the heading
  /// likelihood relative to its maximum, exp(κ (d cos(φ − β_S) − 1)) in [e^{−2κ}, 1], and the
  /// disagreement 1 − d cos(φ − β_S) in [0, 2]. Both arrays hold 2 num_segments() entries.
  void HeadingTables(double heading_rad, double* factor, double* disagreement) const;

  /// log(2π I0(κ)).
  double log_normaliser() const { return log_normaliser_; }
  const CorridorMotionOptions& options() const { return options_; }
  const RoadNetwork& network() const { return network_; }
  int num_segments() const { return network_.num_segments(); }

  /// Segment geometry as flat arrays (M entries each): length [m], end A [m] and the unit
  /// vector from A to B, so that a point is origin + along · unit.
  const double* lengths_m() const { return lengths_.data(); }
  const double* origin_x_m() const { return origin_x_.data(); }
  const double* origin_y_m() const { return origin_y_.data(); }
  const double* unit_x() const { return unit_x_.data(); }
  const double* unit_y() const { return unit_y_.data(); }
  /// The same geometry as rows of four (origin x, origin y, unit x, unit y), M x 4, 32-byte
  /// aligned rows: one vector load per particle in the filters' vectorised loops.
  const double* geometry_rows() const { return geometry_rows_.data(); }

 private:
  static constexpr double kPi = 3.14159265358979323846;
  // The slow path of Move: one or more segment ends reached.
  double MoveAcrossEnds(int* segment, signed char* direction, double* along_m, double distance_m,
                        double heading_rad, RandomStream& rng) const;

  const RoadNetwork& network_;
  CorridorMotionOptions options_;
  double log_normaliser_ = 0.0;
  Eigen::VectorXd lengths_, headings_, origin_x_, origin_y_, unit_x_, unit_y_;
  Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> geometry_rows_;
  // The network's continuations as flat arrays: those of end e of segment s are entries
  // [continuation_begin_[2 s + e], continuation_begin_[2 s + e + 1]).
  std::vector<int> continuation_begin_, continuation_segment_, continuation_enter_end_;
};

}  // namespace indoorloc::mapmatch
