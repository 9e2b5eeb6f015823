// One pass of a map-matching step over the particles: the move (eq. 8-10) and the update
// (eq. 11) with the weighted sums, fused so that each particle's arrays are read once and a
// particle reaching a segment end is handled while its data is in L1.
#pragma once

#include "indoorloc/core/random.h"
#include "indoorloc/core/random_lanes.h"
#include "indoorloc/mapmatch/corridor_motion.h"

namespace indoorloc::mapmatch::detail {

/// The sums of the update pass, for the normalisation, ESS, estimate, spread and disagreement.
struct WeightSums {
  double sum = 0, sum_sq = 0, sx = 0, sy = 0, sxx = 0, syy = 0, disagreement = 0, max_w = 0;
};

/// The particles (N entries each; segment, direction, along and weight updated in place) and
/// the step's inputs.
struct MoveWeighInputs {
  int n;
  const double* distance;  ///< the step's signed distances [m]
  int* seg;
  signed char* dir;
  double* along;           ///< [m] from end A
  double* limit;           ///< the length of each particle's segment [m] (kept up to date here)
  double* weight;          ///< linear weights, multiplied by scale · factor
  double scale;            ///< pending rescale of the weights (1 / previous maximum)
  const double* factor;    ///< 2M: heading likelihood per (segment, direction), index 2 S + (d > 0)
  const double* disagree;  ///< 2M, or null: no disagreement sum (recovery off)
  double heading_rad;      ///< for the heading-aware junction policy
};

/// Moves every particle by distance[i] as CorridorMotion::MoveAll would (the particles reaching
/// a segment end take one junction uniform each from `lanes`, in index order, drawn in rounds of
/// eight: the same draws as MoveAll's single fill; the general path draws from `rng`, also in
/// index order), then weighs it, w <- w · scale · factor[2 S + (d > 0)], and adds it to the sums
/// (particle i into accumulator i mod 4, the four added pairwise at the end). The AVX2 and
/// portable versions do the same IEEE operations in the same order: the same bits on any machine.
WeightSums MoveAndWeigh(const CorridorMotion& motion, const MoveWeighInputs& in, RandomLanes& lanes,
                        RandomStream& rng);

}  // namespace indoorloc::mapmatch::detail
