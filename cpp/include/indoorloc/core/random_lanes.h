// Several independent xoshiro256++ streams advanced in lock-step ("lanes"), for particle loops
// that need uniform numbers (the map matcher) or standard normals (the fusion tracker's motion,
// FillNormal: a ziggurat, Marsaglia & Tsang 2000 in Doornik's 2005 ZIGNOR form) per particle.
//
// One RandomStream's draws form a serial chain (each state update needs the previous one), which
// bounds a particle loop at a few cycles per draw whatever the vector width. Eight lanes updated
// side by side are independent: with AVX2 (chosen at run time, simd_dispatch.h) each state word
// of the eight lanes is two 4 x 64-bit registers; elsewhere a portable loop gives the same numbers. Output k of FillUniform01 comes from lane k mod kLanes, round
// k / kLanes: the numbers depend only on the seed and the sequence of calls, never on the vector
// width, the machine or the thread count. Lane j is seeded like RandomStream(DeriveSeed(seed,
// stream), j), so the lanes are independent streams of the same family.
//
// Uniforms are built from the top 52 bits by the exponent trick (bits | 1.0's exponent, minus
// 1.0): exact, in [0, 1), on a grid of 2^-52; no integer-to-double conversion (which SSE2 and
// AVX2 lack for 64-bit integers). The normals use u = 2 v - 3 on [-1, 1) from the same 52 bits
// and the ziggurat layer from the low 7 (RandomStream's tables); the rare draws that fail the
// fast test are finished by a RandomStream in the order of the outputs.
#pragma once

#include <cstdint>

#include "indoorloc/core/random.h"

namespace indoorloc {

class RandomLanes {
 public:
  static constexpr int kLanes = 8;

  /// Lanes of the family identified by (seed, stream).
  explicit RandomLanes(std::uint64_t seed = 0, std::uint64_t stream = 0);

  /// Fills out[0, count) with uniforms on [0, 1). Every call advances all lanes by
  /// ceil(count / kLanes) rounds (the unused outputs of a last partial round are discarded).
  void FillUniform01(double* out, int count);
  /// The same draws u as FillUniform01(out, count), written as mean + (2 halfwidth · u −
  /// halfwidth), uniform on [mean − halfwidth, mean + halfwidth), computed with exactly those
  /// two roundings (no FMA): the same bits as transforming FillUniform01's output.
  void FillCentred(double* out, int count, double mean, double halfwidth);
  /// Fills out[0, count) with standard normals by the ziggurat (RandomStream::NormalZiggurat's
  /// tables, Doornik's ZIGNOR): output k takes raw draw k (lanes and rounds as FillUniform01),
  /// u = 2 v - 3 from its top 52 bits (v in [1, 2) by the exponent trick) and the layer from its
  /// low 7 bits; the fast path u x_layer is taken in about 98.8 % of outputs, the others are
  /// resolved in order of k by fallback.NormalZigguratOutside (which draws from `fallback`).
  /// Same numbers with or without AVX2.
  void FillNormal(double* out, int count, RandomStream& fallback);

 private:
  alignas(64) std::uint64_t state_[4][kLanes];
};

}  // namespace indoorloc
