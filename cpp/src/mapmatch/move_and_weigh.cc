#include "move_and_weigh.h"

#include <algorithm>
#include <cstdint>
#include <cstring>

#include <immintrin.h>

#include "indoorloc/core/simd_dispatch.h"

namespace indoorloc::mapmatch::detail {
namespace {

constexpr int kSumLanes = 4;
// Particles per block of the fused pass: a multiple of kSumLanes (every particle keeps its
// accumulator i mod 4) small enough for the block's arrays to stay in L1 between the move and
// the update (512 x 26 bytes).
constexpr int kBlock = 512;
static_assert(kBlock % kSumLanes == 0, "blocks of whole groups");

struct LaneSums {
  double sum[kSumLanes] = {}, sum_sq[kSumLanes] = {}, sx[kSumLanes] = {}, sy[kSumLanes] = {}, sxx[kSumLanes] = {},
         syy[kSumLanes] = {}, dis[kSumLanes] = {}, max_w[kSumLanes] = {};
};

// The junction uniforms, drawn from the lanes one round (eight) at a time: k draws consume
// ceil(k / 8) rounds, as one FillUniform01(k) would.
class JunctionDraws {
 public:
  explicit JunctionDraws(RandomLanes& lanes) : lanes_(lanes) {}
  double Next() {
    if (next_ == RandomLanes::kLanes) {
      lanes_.FillUniform01(buffer_, RandomLanes::kLanes);
      next_ = 0;
    }
    return buffer_[next_++];
  }

 private:
  RandomLanes& lanes_;
  double buffer_[RandomLanes::kLanes] = {};
  int next_ = RandomLanes::kLanes;
};

// The in-segment pass over particles [0, count) of a block: along += d · distance where
// 0 <= along + d · distance <= limit; the others keep their along and are listed in at_end, in
// index order (portable version, branch-free). Returns how many were listed. As
// CorridorMotion::MoveWithinSegments, with the segment length read from the particle's own limit
// (one load instead of an index load and a table load per particle).
int MoveWithinLimitsScalar(int begin, int count, const double* distance, const signed char* direction,
                           double* along_m, const double* limit, int* at_end, int listed) {
  for (int i = begin; i < count; ++i) {
    const double along = along_m[i];
    const double u = along + direction[i] * distance[i];
    const bool inside = (u >= 0.0) & (u <= limit[i]);
    along_m[i] = inside ? u : along;
    at_end[listed] = i;
    listed += !inside;
  }
  return listed;
}

// The same pass with AVX2, four particles at a time (the same multiply and add, no FMA), the
// listed indices compressed by a 16-entry shuffle table. Sets *done to the first particle not
// done; returns how many were listed.
__attribute__((target("avx2"))) int MoveWithinLimitsAvx2(int count, const double* distance,
                                                         const signed char* direction, double* along_m,
                                                         const double* limit, int* at_end, int* done) {
  // kCompress[m]: the lanes j whose bit is 0 in the "inside" mask m, in order, then padding.
  static const std::int32_t kCompress[16][4] = {
      {0, 1, 2, 3}, {1, 2, 3, 0}, {0, 2, 3, 0}, {2, 3, 0, 0}, {0, 1, 3, 0}, {1, 3, 0, 0}, {0, 3, 0, 0}, {3, 0, 0, 0},
      {0, 1, 2, 0}, {1, 2, 0, 0}, {0, 2, 0, 0}, {2, 0, 0, 0}, {0, 1, 0, 0}, {1, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}};
  const __m256d zero = _mm256_setzero_pd();
  int listed = 0;
  int i = 0;
  for (; i + 4 <= count; i += 4) {
    std::int32_t packed;
    std::memcpy(&packed, direction + i, sizeof(packed));
    const __m256d dir = _mm256_cvtepi32_pd(_mm_cvtepi8_epi32(_mm_cvtsi32_si128(packed)));
    const __m256d along = _mm256_loadu_pd(along_m + i);
    const __m256d u = _mm256_add_pd(along, _mm256_mul_pd(dir, _mm256_loadu_pd(distance + i)));
    const __m256d inside =
        _mm256_and_pd(_mm256_cmp_pd(u, zero, _CMP_GE_OQ), _mm256_cmp_pd(u, _mm256_loadu_pd(limit + i), _CMP_LE_OQ));
    _mm256_storeu_pd(along_m + i, _mm256_blendv_pd(along, u, inside));
    const int mask = _mm256_movemask_pd(inside);
    const __m128i lanes = _mm_loadu_si128(reinterpret_cast<const __m128i*>(kCompress[mask]));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(at_end + listed), _mm_add_epi32(lanes, _mm_set1_epi32(i)));
    listed += 4 - __builtin_popcount(static_cast<unsigned>(mask));
  }
  *done = i;
  return listed;
}

// The update of particles [begin, end), particle i into lane i mod kSumLanes (portable version).
void WeighScalar(const CorridorMotion& motion, const MoveWeighInputs& in, int begin, int end, LaneSums* acc) {
  const double* origin_x = motion.origin_x_m();
  const double* origin_y = motion.origin_y_m();
  const double* unit_x = motion.unit_x();
  const double* unit_y = motion.unit_y();
  for (int i = begin; i < end; ++i) {
    const int j = i % kSumLanes;
    const int si = in.seg[i];
    const int key = 2 * si + (in.dir[i] > 0);
    const double w = in.weight[i] * in.scale * in.factor[key];
    in.weight[i] = w;
    const double x = origin_x[si] + in.along[i] * unit_x[si];
    const double y = origin_y[si] + in.along[i] * unit_y[si];
    acc->sum[j] += w;
    acc->sum_sq[j] += w * w;
    acc->sx[j] += w * x;
    acc->sy[j] += w * y;
    acc->sxx[j] += w * x * x;
    acc->syy[j] += w * y * y;
    if (in.disagree != nullptr) acc->dis[j] += w * in.disagree[key];
    acc->max_w[j] = acc->max_w[j] > w ? acc->max_w[j] : w;
  }
}

// Four table entries t[i0..i3] by scalar loads: faster than vgatherdpd on the machines measured
// (docs/performance.md).
#define INDOORLOC_GATHER4(t, i0, i1, i2, i3) _mm256_set_pd((t)[i3], (t)[i2], (t)[i1], (t)[i0])

// The update of the whole groups of four in [begin, end) (begin a multiple of 4) with AVX2,
// continuing the sums in acc: the same operations in the same order as WeighScalar (no FMA).
// Returns the first particle not done.
template <bool kDisagreement>
__attribute__((target("avx2"))) int WeighAvx2(const CorridorMotion& motion, const MoveWeighInputs& in, int begin,
                                              int end, LaneSums* acc) {
  // Locals (restrict) so that the weight stores do not force reloads of the inputs.
  const int* __restrict seg = in.seg;
  const signed char* __restrict dir = in.dir;
  const double* __restrict along_m = in.along;
  double* __restrict weight = in.weight;
  const double* __restrict factor = in.factor;
  const double* __restrict disagree = in.disagree;
  const double* __restrict geometry = motion.geometry_rows();
  __m256d sum = _mm256_loadu_pd(acc->sum), sum_sq = _mm256_loadu_pd(acc->sum_sq), sx = _mm256_loadu_pd(acc->sx),
          sy = _mm256_loadu_pd(acc->sy), sxx = _mm256_loadu_pd(acc->sxx), syy = _mm256_loadu_pd(acc->syy),
          dis = _mm256_loadu_pd(acc->dis), max_w = _mm256_loadu_pd(acc->max_w);
  const __m256d scale = _mm256_set1_pd(in.scale);
  int i = begin;
  for (; i + kSumLanes <= end; i += kSumLanes) {
    const int s0 = seg[i], s1 = seg[i + 1], s2 = seg[i + 2], s3 = seg[i + 3];
    const int k0 = 2 * s0 + (dir[i] > 0), k1 = 2 * s1 + (dir[i + 1] > 0), k2 = 2 * s2 + (dir[i + 2] > 0),
              k3 = 2 * s3 + (dir[i + 3] > 0);
    const __m256d w =
        _mm256_mul_pd(_mm256_mul_pd(_mm256_loadu_pd(weight + i), scale), INDOORLOC_GATHER4(factor, k0, k1, k2, k3));
    _mm256_storeu_pd(weight + i, w);
    const __m256d along = _mm256_loadu_pd(along_m + i);
    // The four particles' geometry rows, transposed: 4 vector loads and 8 shuffles instead of 16
    // scalar loads.
    const __m256d r0 = _mm256_loadu_pd(geometry + 4 * s0), r1 = _mm256_loadu_pd(geometry + 4 * s1);
    const __m256d r2 = _mm256_loadu_pd(geometry + 4 * s2), r3 = _mm256_loadu_pd(geometry + 4 * s3);
    const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);  // ox oy / ux uy of 0, 1
    const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
    const __m256d origin_x = _mm256_permute2f128_pd(t0, t2, 0x20), unit_x = _mm256_permute2f128_pd(t0, t2, 0x31);
    const __m256d origin_y = _mm256_permute2f128_pd(t1, t3, 0x20), unit_y = _mm256_permute2f128_pd(t1, t3, 0x31);
    const __m256d x = _mm256_add_pd(origin_x, _mm256_mul_pd(along, unit_x));
    const __m256d y = _mm256_add_pd(origin_y, _mm256_mul_pd(along, unit_y));
    const __m256d wx = _mm256_mul_pd(w, x), wy = _mm256_mul_pd(w, y);
    sum = _mm256_add_pd(sum, w);
    sum_sq = _mm256_add_pd(sum_sq, _mm256_mul_pd(w, w));
    sx = _mm256_add_pd(sx, wx);
    sy = _mm256_add_pd(sy, wy);
    sxx = _mm256_add_pd(sxx, _mm256_mul_pd(wx, x));
    syy = _mm256_add_pd(syy, _mm256_mul_pd(wy, y));
    if (kDisagreement) dis = _mm256_add_pd(dis, _mm256_mul_pd(w, INDOORLOC_GATHER4(disagree, k0, k1, k2, k3)));
    max_w = _mm256_max_pd(max_w, w);  // max_w > w ? max_w : w, as the portable version
  }
  _mm256_storeu_pd(acc->sum, sum);
  _mm256_storeu_pd(acc->sum_sq, sum_sq);
  _mm256_storeu_pd(acc->sx, sx);
  _mm256_storeu_pd(acc->sy, sy);
  _mm256_storeu_pd(acc->sxx, sxx);
  _mm256_storeu_pd(acc->syy, syy);
  _mm256_storeu_pd(acc->dis, dis);
  _mm256_storeu_pd(acc->max_w, max_w);
  return i;
}
#undef INDOORLOC_GATHER4

}  // namespace

WeightSums MoveAndWeigh(const CorridorMotion& motion, const MoveWeighInputs& in, RandomLanes& lanes,
                        RandomStream& rng) {
  LaneSums acc;
  JunctionDraws draws(lanes);
  const bool avx2 = UseAvx2();
  const double* lengths = motion.lengths_m();
  int at_end[kBlock + 4];  // + 4: the vectorised move stores whole groups
  for (int begin = 0; begin < in.n; begin += kBlock) {
    const int end = std::min(in.n, begin + kBlock);
    // The move: in-segment moves of the block, then its particles at a segment end in index order.
    const int count = end - begin;
    int moved = 0, num_at_end = 0;
    if (avx2) {
      num_at_end = MoveWithinLimitsAvx2(count, in.distance + begin, in.dir + begin, in.along + begin,
                                        in.limit + begin, at_end, &moved);
    }
    num_at_end = MoveWithinLimitsScalar(moved, count, in.distance + begin, in.dir + begin, in.along + begin,
                                        in.limit + begin, at_end, num_at_end);
    for (int k = 0; k < num_at_end; ++k) {
      const int i = begin + at_end[k];
      const double importance = motion.MoveFromEnd(&in.seg[i], &in.dir[i], &in.along[i], in.distance[i], draws.Next(),
                                                   in.heading_rad, rng);
      if (importance != 1.0) in.weight[i] *= importance;
      in.limit[i] = lengths[in.seg[i]];
    }
    // The update of the block, its arrays still in L1.
    int done = begin;
    if (avx2) {
      done = in.disagree != nullptr ? WeighAvx2<true>(motion, in, begin, end, &acc)
                                    : WeighAvx2<false>(motion, in, begin, end, &acc);
    }
    WeighScalar(motion, in, done, end, &acc);
  }
  auto reduce = [](const double* v) { return (v[0] + v[1]) + (v[2] + v[3]); };
  WeightSums out;
  out.sum = reduce(acc.sum);
  out.sum_sq = reduce(acc.sum_sq);
  out.sx = reduce(acc.sx);
  out.sy = reduce(acc.sy);
  out.sxx = reduce(acc.sxx);
  out.syy = reduce(acc.syy);
  out.disagreement = reduce(acc.dis);
  out.max_w = std::max(std::max(acc.max_w[0], acc.max_w[1]), std::max(acc.max_w[2], acc.max_w[3]));
  return out;
}

}  // namespace indoorloc::mapmatch::detail
