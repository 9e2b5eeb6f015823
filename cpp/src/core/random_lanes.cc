#include "indoorloc/core/random_lanes.h"

#include <algorithm>
#include <cstring>

#include <immintrin.h>

#include "indoorloc/core/random.h"
#include "indoorloc/core/simd_dispatch.h"

namespace indoorloc {
namespace {

inline std::uint64_t RotateLeft(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

// The eight lanes' state copied out of the generator (so that the compiler keeps it in registers
// or on the stack, not behind the generator's pointer) and copied back.
struct ScalarLanes {
  std::uint64_t s0[RandomLanes::kLanes], s1[RandomLanes::kLanes], s2[RandomLanes::kLanes], s3[RandomLanes::kLanes];
};

inline ScalarLanes LoadScalarLanes(const std::uint64_t (&state)[4][RandomLanes::kLanes]) {
  ScalarLanes l;
  std::memcpy(l.s0, state[0], sizeof(l.s0));
  std::memcpy(l.s1, state[1], sizeof(l.s1));
  std::memcpy(l.s2, state[2], sizeof(l.s2));
  std::memcpy(l.s3, state[3], sizeof(l.s3));
  return l;
}

inline void StoreScalarLanes(const ScalarLanes& l, std::uint64_t (&state)[4][RandomLanes::kLanes]) {
  std::memcpy(state[0], l.s0, sizeof(l.s0));
  std::memcpy(state[1], l.s1, sizeof(l.s1));
  std::memcpy(state[2], l.s2, sizeof(l.s2));
  std::memcpy(state[3], l.s3, sizeof(l.s3));
}

// One xoshiro256++ step of lane j (Blackman & Vigna 2019, as RandomStream::operator()): its output.
inline std::uint64_t NextScalar(ScalarLanes& l, int j) {
  const std::uint64_t result = RotateLeft(l.s0[j] + l.s3[j], 23) + l.s0[j];
  const std::uint64_t t = l.s1[j] << 17;
  l.s2[j] ^= l.s0[j];
  l.s3[j] ^= l.s1[j];
  l.s1[j] ^= l.s2[j];
  l.s0[j] ^= l.s3[j];
  l.s2[j] ^= t;
  l.s3[j] = RotateLeft(l.s3[j], 45);
  return result;
}

// The eight lanes' state in registers (two 4 x 64-bit registers per state word) and the same step
// on four lanes at once: integer operations only, bit-identical to NextScalar.
struct LaneRegisters {
  __m256i s0[2], s1[2], s2[2], s3[2];
};

__attribute__((target("avx2"))) inline __m256i RotateLeftAvx2(__m256i x, int k) {
  return _mm256_or_si256(_mm256_slli_epi64(x, k), _mm256_srli_epi64(x, 64 - k));
}

__attribute__((target("avx2"))) inline LaneRegisters LoadLanes(const std::uint64_t (&state)[4][RandomLanes::kLanes]) {
  LaneRegisters r;
  for (int h = 0; h < 2; ++h) {
    r.s0[h] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(state[0] + 4 * h));
    r.s1[h] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(state[1] + 4 * h));
    r.s2[h] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(state[2] + 4 * h));
    r.s3[h] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(state[3] + 4 * h));
  }
  return r;
}

__attribute__((target("avx2"))) inline void StoreLanes(const LaneRegisters& r, std::uint64_t (&state)[4][RandomLanes::kLanes]) {
  for (int h = 0; h < 2; ++h) {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(state[0] + 4 * h), r.s0[h]);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(state[1] + 4 * h), r.s1[h]);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(state[2] + 4 * h), r.s2[h]);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(state[3] + 4 * h), r.s3[h]);
  }
}

__attribute__((target("avx2"))) inline __m256i NextAvx2(LaneRegisters& r, int h) {
  const __m256i result = _mm256_add_epi64(RotateLeftAvx2(_mm256_add_epi64(r.s0[h], r.s3[h]), 23), r.s0[h]);
  const __m256i t = _mm256_slli_epi64(r.s1[h], 17);
  r.s2[h] = _mm256_xor_si256(r.s2[h], r.s0[h]);
  r.s3[h] = _mm256_xor_si256(r.s3[h], r.s1[h]);
  r.s1[h] = _mm256_xor_si256(r.s1[h], r.s2[h]);
  r.s0[h] = _mm256_xor_si256(r.s0[h], r.s3[h]);
  r.s2[h] = _mm256_xor_si256(r.s2[h], t);
  r.s3[h] = RotateLeftAvx2(r.s3[h], 45);
  return result;
}

// The outputs of the fills: the uniform u in [0, 1) itself, or mean + (2a · u − a) (FillCentred).
struct Affine {
  double mean = 0.0, two_a = 0.0, a = 0.0;
};

// Rounds of the eight lanes into out[0, rounds * kLanes), portable version.
template <bool kCentred>
void FillRoundsScalar(std::uint64_t (&state)[4][RandomLanes::kLanes], double* out, int rounds, Affine f) {
  constexpr int kLanes = RandomLanes::kLanes;
  ScalarLanes lanes = LoadScalarLanes(state);
  for (int r = 0; r < rounds; ++r) {
    std::uint64_t bits[kLanes];
    for (int j = 0; j < kLanes; ++j) {
      bits[j] = (NextScalar(lanes, j) >> 12) | 0x3FF0000000000000ULL;  // a double in [1, 2)
    }
    double unit[kLanes];
    std::memcpy(unit, bits, sizeof(unit));
    for (int j = 0; j < kLanes; ++j) {
      const double u = unit[j] - 1.0;
      out[r * kLanes + j] = kCentred ? f.mean + (f.two_a * u - f.a) : u;
    }
  }
  StoreScalarLanes(lanes, state);
}

// The same rounds with AVX2: each state word of the eight lanes is two 4 x 64-bit registers.
// Integer operations and one exact subtraction: bit-identical to FillRoundsScalar.
template <bool kCentred>
__attribute__((target("avx2"))) void FillRoundsAvx2(std::uint64_t (&state)[4][RandomLanes::kLanes], double* out,
                                                     int rounds, Affine f) {
  static_assert(RandomLanes::kLanes == 8, "two registers of four lanes");
  LaneRegisters lanes = LoadLanes(state);
  const __m256i one_exponent = _mm256_set1_epi64x(0x3FF0000000000000LL);
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d mean = _mm256_set1_pd(f.mean), two_a = _mm256_set1_pd(f.two_a), a = _mm256_set1_pd(f.a);
  for (int r = 0; r < rounds; ++r) {
    for (int h = 0; h < 2; ++h) {
      const __m256i bits = _mm256_or_si256(_mm256_srli_epi64(NextAvx2(lanes, h), 12), one_exponent);
      const __m256d u = _mm256_sub_pd(_mm256_castsi256_pd(bits), one);
      // No FMA: the same two roundings as the portable version.
      _mm256_storeu_pd(out + r * 8 + 4 * h,
                       kCentred ? _mm256_add_pd(mean, _mm256_sub_pd(_mm256_mul_pd(two_a, u), a)) : u);
    }
  }
  StoreLanes(lanes, state);
}

template <bool kCentred>
void FillRounds(std::uint64_t (&state)[4][RandomLanes::kLanes], double* out, int rounds, Affine f) {
  if (UseAvx2()) {
    FillRoundsAvx2<kCentred>(state, out, rounds, f);
  } else {
    FillRoundsScalar<kCentred>(state, out, rounds, f);
  }
}

template <bool kCentred>
void Fill(std::uint64_t (&state)[4][RandomLanes::kLanes], double* out, int count, Affine f) {
  constexpr int kLanes = RandomLanes::kLanes;
  if (count <= 0) return;
  const int full = count / kLanes;
  FillRounds<kCentred>(state, out, full, f);
  const int rest = count - full * kLanes;
  if (rest > 0) {
    double tail[kLanes];
    FillRounds<kCentred>(state, tail, 1, f);
    std::memcpy(out + full * kLanes, tail, static_cast<size_t>(rest) * sizeof(double));
  }
}

// ---- the ziggurat (FillNormal)

// One raw draw -> (u, layer): u = 2 v - 3 on [-1, 1) with v in [1, 2) from the top 52 bits
// (both operations exact), the layer from the low 7 bits (independent of the top 52).
inline double ZigguratU(std::uint64_t bits) {
  const std::uint64_t v_bits = (bits >> 12) | 0x3FF0000000000000ULL;
  double v;
  std::memcpy(&v, &v_bits, sizeof(v));
  return 2.0 * v - 3.0;
}

// Rounds of the eight lanes into normals out[0, rounds * kLanes), portable version: fast path
// u x_layer; the outputs k < valid that fail it are resolved in order by the fallback stream
// (outputs at or beyond `valid` are discarded by the caller and never touch the fallback).
void NormalRoundsScalar(std::uint64_t (&state)[4][RandomLanes::kLanes], double* out, int rounds, int valid,
                        const double* table_x, const double* table_ratio, RandomStream& fallback) {
  constexpr int kLanes = RandomLanes::kLanes;
  ScalarLanes lanes = LoadScalarLanes(state);
  for (int r = 0; r < rounds; ++r) {
    for (int j = 0; j < kLanes; ++j) {
      const std::uint64_t bits = NextScalar(lanes, j);
      const double u = ZigguratU(bits);
      const int layer = static_cast<int>(bits & 0x7F);
      const int k = r * kLanes + j;
      out[k] = u * table_x[layer];
      if (!((u < 0 ? -u : u) < table_ratio[layer]) && k < valid) {
        out[k] = fallback.NormalZigguratOutside(u, layer);
      }
    }
  }
  StoreScalarLanes(lanes, state);
}

// The same with AVX2: the layer's table entries by gathers, the fast test on four lanes at once;
// the rare rejected lanes in order of k (as above). Bit-identical to NormalRoundsScalar.
// At most kMaxNormalRounds rounds per call (the caller splits longer fills).
constexpr int kMaxNormalRounds = 128;
__attribute__((target("avx2"))) void NormalRoundsAvx2(std::uint64_t (&state)[4][RandomLanes::kLanes], double* out,
                                                      int rounds, int valid, const double* table_x,
                                                      const double* table_ratio, RandomStream& fallback) {
  unsigned char accepted[2 * kMaxNormalRounds];
  std::uint64_t raw[8 * kMaxNormalRounds];
  LaneRegisters lanes = LoadLanes(state);
  const __m256i one_exponent = _mm256_set1_epi64x(0x3FF0000000000000LL);
  const __m256i layer_bits = _mm256_set1_epi64x(0x7F);
  const __m256d two = _mm256_set1_pd(2.0), three = _mm256_set1_pd(3.0);
  const __m256d sign = _mm256_set1_pd(-0.0);
  for (int r = 0; r < rounds; ++r) {
    for (int h = 0; h < 2; ++h) {
      const __m256i bits = NextAvx2(lanes, h);
      const __m256d v = _mm256_castsi256_pd(_mm256_or_si256(_mm256_srli_epi64(bits, 12), one_exponent));
      const __m256d u = _mm256_sub_pd(_mm256_mul_pd(two, v), three);  // no FMA: two roundings, both exact
      const __m256i layer = _mm256_and_si256(bits, layer_bits);
      const __m256d ratio = _mm256_i64gather_pd(table_ratio, layer, 8);
      const __m256d x = _mm256_i64gather_pd(table_x, layer, 8);
      const __m256d accept = _mm256_cmp_pd(_mm256_andnot_pd(sign, u), ratio, _CMP_LT_OQ);
      const int k0 = r * 8 + 4 * h;
      _mm256_storeu_pd(out + k0, _mm256_mul_pd(u, x));
      // Rejected lanes (about one vector in ten) are resolved after the loop: no call and no
      // mispredicted branch inside it. Their u and layer are kept in the raw bits.
      accepted[r * 2 + h] = static_cast<unsigned char>(_mm256_movemask_pd(accept));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(raw + k0), bits);
    }
  }
  for (int v = 0; v < 2 * rounds; ++v) {
    if (accepted[v] == 0xF) continue;
    for (int j = 0; j < 4; ++j) {
      const int k = 4 * v + j;
      if (!((accepted[v] >> j) & 1) && k < valid) {
        out[k] = fallback.NormalZigguratOutside(ZigguratU(raw[k]), static_cast<int>(raw[k] & 0x7F));
      }
    }
  }
  StoreLanes(lanes, state);
}

}  // namespace

void RandomLanes::FillNormal(double* out, int count, RandomStream& fallback) {
  if (count <= 0) return;
  const int full = count / kLanes;
  const int rest = count - full * kLanes;
  const double* table_x = RandomStream::kZigguratX;
  const double* table_ratio = RandomStream::kZigguratRatio;
  auto rounds = [&](double* dst, int n_rounds, int valid) {
    if (UseAvx2()) {
      NormalRoundsAvx2(state_, dst, n_rounds, valid, table_x, table_ratio, fallback);
    } else {
      NormalRoundsScalar(state_, dst, n_rounds, valid, table_x, table_ratio, fallback);
    }
  };
  for (int begin = 0; begin < full; begin += kMaxNormalRounds) {
    const int n_rounds = std::min(kMaxNormalRounds, full - begin);
    rounds(out + begin * kLanes, n_rounds, n_rounds * kLanes);
  }
  if (rest > 0) {
    double tail[kLanes];
    rounds(tail, 1, rest);
    std::memcpy(out + full * kLanes, tail, static_cast<size_t>(rest) * sizeof(double));
  }
}

RandomLanes::RandomLanes(std::uint64_t seed, std::uint64_t stream) {
  const std::uint64_t family = DeriveSeed(seed, stream);
  for (int j = 0; j < kLanes; ++j) {
    // The same SplitMix64 fill as RandomStream's constructor.
    std::uint64_t x = DeriveSeed(family, static_cast<std::uint64_t>(j));
    for (int w = 0; w < 4; ++w) {
      x += 0x9E3779B97F4A7C15ULL;
      state_[w][j] = SplitMix64(x);
    }
  }
}

void RandomLanes::FillUniform01(double* out, int count) { Fill<false>(state_, out, count, Affine()); }

void RandomLanes::FillCentred(double* out, int count, double mean, double halfwidth) {
  Fill<true>(state_, out, count, Affine{mean, 2.0 * halfwidth, halfwidth});
}

}  // namespace indoorloc
