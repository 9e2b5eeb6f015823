#include "indoorloc/mapmatch/corridor_motion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <immintrin.h>

#include "indoorloc/core/options.h"
#include "indoorloc/core/simd_dispatch.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/mapmatch/trajectory_simulator.h"

namespace indoorloc::mapmatch {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Junction hops allowed in one move: a move longer than this many (tiny) segments is a bug in
// the caller (a distance of 1e300), not a walk; the particle stops where it got to.
constexpr int kMaxHopsPerMove = 100000;

// log(2π I0(κ)) without overflow: I0(κ) = e^κ I0e(κ).
double LogVonMisesNormaliser(double kappa) {
  return std::log(2.0 * kPi) + kappa + std::log(std::cyl_bessel_i(0.0, kappa) * std::exp(-kappa));
}

}  // namespace

bool CorridorMotionOptions::IsValid(std::string* error) const {
  return Validator(error)
      .InRange(kappa, 0.0, kMaxCorridorKappa, "kappa")
      .Check(junction_policy == JunctionPolicy::kUniform || junction_policy == JunctionPolicy::kHeadingAware,
             "junction_policy", "must be kUniform or kHeadingAware")
      .InRange(junction_kappa, 0.0, kMaxCorridorKappa, "junction_kappa");
}

CorridorMotion::CorridorMotion(const RoadNetwork& network, const CorridorMotionOptions& options)
    : network_(network), options_(options) {
  ValidateOptions(options_);
  log_normaliser_ = LogVonMisesNormaliser(options_.kappa);
  const int m = network_.num_segments();
  lengths_ = network_.lengths_m();
  headings_ = network_.headings_rad();
  origin_x_.resize(m);
  origin_y_.resize(m);
  unit_x_.resize(m);
  unit_y_.resize(m);
  const RowMatrixXd& ends = network_.segments_m();
  for (int k = 0; k < m; ++k) {
    origin_x_[k] = ends(k, 0);
    origin_y_[k] = ends(k, 1);
    unit_x_[k] = (ends(k, 2) - ends(k, 0)) / lengths_[k];
    unit_y_[k] = (ends(k, 3) - ends(k, 1)) / lengths_[k];
  }
  geometry_rows_.resize(m, 4);
  for (int k = 0; k < m; ++k) geometry_rows_.row(k) << origin_x_[k], origin_y_[k], unit_x_[k], unit_y_[k];
  continuation_begin_.assign(1, 0);
  for (int k = 0; k < m; ++k) {
    for (int end = 0; end < 2; ++end) {
      for (const Continuation& c : network_.continuations(k, end)) {
        continuation_segment_.push_back(c.segment);
        continuation_enter_end_.push_back(c.enter_end);
      }
      continuation_begin_.push_back(static_cast<int>(continuation_segment_.size()));
    }
  }
}

namespace {

// The in-segment pass of MoveAll for particles [begin, count): along += d · distance where the
// particle stays on its segment; appends the others to at_end[*num_at_end...] (portable
// version, branch-free).
void MoveWithinSegmentsScalar(int begin, int count, const double* distance_m, const int* segment,
                              const signed char* direction, double* along_m, const double* lengths_m, int* at_end,
                              int* num_at_end) {
  int listed = *num_at_end;
  for (int i = begin; i < count; ++i) {
    const double along = along_m[i];
    const double u = along + direction[i] * distance_m[i];
    const bool inside = (u >= 0.0) & (u <= lengths_m[segment[i]]);
    along_m[i] = inside ? u : along;
    at_end[listed] = i;
    listed += !inside;
  }
  *num_at_end = listed;
}

// The same pass with AVX2, four particles at a time (the same multiply and add as the portable
// version, no FMA: bit-identical), the listed indices compressed by a 16-entry shuffle table.
// Returns the first particle not done.
__attribute__((target("avx2"))) int MoveWithinSegmentsAvx2(int count, const double* distance_m, const int* segment,
                                                           const signed char* direction, double* along_m,
                                                           const double* lengths_m, int* at_end, int* num_at_end) {
  // kCompress[m]: the lanes j whose bit is 0 in the "inside" mask m, in order, then padding.
  static const std::int32_t kCompress[16][4] = {
      {0, 1, 2, 3}, {1, 2, 3, 0}, {0, 2, 3, 0}, {2, 3, 0, 0}, {0, 1, 3, 0}, {1, 3, 0, 0}, {0, 3, 0, 0}, {3, 0, 0, 0},
      {0, 1, 2, 0}, {1, 2, 0, 0}, {0, 2, 0, 0}, {2, 0, 0, 0}, {0, 1, 0, 0}, {1, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}};
  const __m256d zero = _mm256_setzero_pd();
  int listed = *num_at_end;
  int i = 0;
  for (; i + 4 <= count; i += 4) {
    // Scalar loads rather than vgatherdpd: faster on the machines measured (docs/performance.md).
    const __m256d length =
        _mm256_set_pd(lengths_m[segment[i + 3]], lengths_m[segment[i + 2]], lengths_m[segment[i + 1]], lengths_m[segment[i]]);
    std::int32_t packed;
    std::memcpy(&packed, direction + i, sizeof(packed));
    const __m256d dir = _mm256_cvtepi32_pd(_mm_cvtepi8_epi32(_mm_cvtsi32_si128(packed)));
    const __m256d along = _mm256_loadu_pd(along_m + i);
    const __m256d u = _mm256_add_pd(along, _mm256_mul_pd(dir, _mm256_loadu_pd(distance_m + i)));
    const __m256d inside = _mm256_and_pd(_mm256_cmp_pd(u, zero, _CMP_GE_OQ), _mm256_cmp_pd(u, length, _CMP_LE_OQ));
    _mm256_storeu_pd(along_m + i, _mm256_blendv_pd(along, u, inside));
    const int mask = _mm256_movemask_pd(inside);
    const __m128i lanes = _mm_loadu_si128(reinterpret_cast<const __m128i*>(kCompress[mask]));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(at_end + listed), _mm_add_epi32(lanes, _mm_set1_epi32(i)));
    listed += 4 - __builtin_popcount(static_cast<unsigned>(mask));
  }
  *num_at_end = listed;
  return i;
}

}  // namespace

int CorridorMotion::MoveWithinSegments(int count, const double* distance_m, const int* segment,
                                       const signed char* direction, double* along_m, int* at_end) const {
  int num_at_end = 0;
  const int done = UseAvx2() ? MoveWithinSegmentsAvx2(count, distance_m, segment, direction, along_m, lengths_.data(),
                                                      at_end, &num_at_end)
                             : 0;
  MoveWithinSegmentsScalar(done, count, distance_m, segment, direction, along_m, lengths_.data(), at_end, &num_at_end);
  return num_at_end;
}

void CorridorMotion::MoveAll(int count, const double* distance_m, int* segment, signed char* direction,
                             double* along_m, double heading_rad, RandomLanes& lanes, RandomStream& rng,
                             double* weight, MoveScratch* scratch) const {
  if (count <= 0) return;
  scratch->at_end.resize(static_cast<size_t>(count) + 4);  // + 4: the AVX2 pass stores whole groups
  int* at_end = scratch->at_end.data();
  const int num_at_end = MoveWithinSegments(count, distance_m, segment, direction, along_m, at_end);
  scratch->uniforms.resize(static_cast<size_t>(num_at_end));
  lanes.FillUniform01(scratch->uniforms.data(), num_at_end);
  for (int k = 0; k < num_at_end; ++k) {
    const int i = at_end[k];
    const double importance = MoveFromEnd(&segment[i], &direction[i], &along_m[i], distance_m[i],
                                          scratch->uniforms[static_cast<size_t>(k)], heading_rad, rng);
    if (importance != 1.0) weight[i] *= importance;
  }
}

void CorridorMotion::HeadingTables(double heading_rad, double* factor, double* disagreement) const {
  const double kappa = options_.kappa;
  for (int s = 0; s < network_.num_segments(); ++s) {
    const double c = std::cos(heading_rad - headings_[s]);
    factor[2 * s + 1] = std::exp(kappa * (c - 1.0));
    factor[2 * s] = std::exp(kappa * (-c - 1.0));
    disagreement[2 * s + 1] = 1.0 - c;
    disagreement[2 * s] = 1.0 + c;
  }
}

double CorridorMotion::MoveAcrossEnds(int* segment, signed char* direction, double* along_m, double distance_m,
                                      double heading_rad, RandomStream& rng) const {
  int s = *segment;
  int d = *direction;
  double u = *along_m + d * distance_m;
  double importance = 1.0;
  for (int hop = 0; hop < kMaxHopsPerMove; ++hop) {
    int end;
    double leftover;
    if (u > lengths_[s]) {
      end = 1;
      leftover = u - lengths_[s];
    } else if (u < 0.0) {
      end = 0;
      leftover = -u;
    } else {
      break;
    }
    // Backwards (a negative distance): stop at the end behind, never back onto a continuation
    // (it would put the particle on a branch it never came from; 7 m of error at κ_P = 5 in the
    // §III experiment, docs/mapmatch.md).
    if ((end == 1) != (d > 0)) {
      u = end == 1 ? lengths_[s] : 0.0;
      break;
    }
    const int first = continuation_begin_[static_cast<size_t>(2 * s + end)];
    const size_t n_choices = static_cast<size_t>(continuation_begin_[static_cast<size_t>(2 * s + end + 1)] - first);
    const int* choice_segment = continuation_segment_.data() + first;
    const int* choice_enter_end = continuation_enter_end_.data() + first;
    size_t pick = 0;
    if (n_choices > 1) {
      if (options_.junction_policy == JunctionPolicy::kUniform) {
        pick = static_cast<size_t>(rng.UniformInt(n_choices));
      } else {
        // Proposal q_j ∝ exp(κ_J (cos(φ − heading_j) − 1)); the weight is multiplied by
        // prior / proposal = (1 / n) / (q_j / Σq). The q_j are computed twice (total, then the
        // pick) rather than kept in scratch, so that the model stays const and thread-safe.
        auto q = [&](size_t j) {
          const double h = TravelHeading(network_, choice_segment[j], choice_enter_end[j] == 0 ? 1 : -1);
          return std::exp(options_.junction_kappa * (std::cos(heading_rad - h) - 1.0));
        };
        double total = 0.0;
        for (size_t j = 0; j < n_choices; ++j) total += q(j);
        double r = rng.Uniform01() * total;
        double q_pick = q(0);
        while (pick + 1 < n_choices && r >= q_pick) {
          r -= q_pick;
          q_pick = q(++pick);
        }
        importance *= (total / q_pick) / static_cast<double>(n_choices);
      }
    }
    s = choice_segment[pick];
    d = choice_enter_end[pick] == 0 ? 1 : -1;
    u = choice_enter_end[pick] == 0 ? leftover : lengths_[s] - leftover;
  }
  *segment = s;
  *direction = static_cast<signed char>(d);
  *along_m = std::clamp(u, 0.0, lengths_[s]);
  return importance;
}

}  // namespace indoorloc::mapmatch
