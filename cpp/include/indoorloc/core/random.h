// Seeded random streams: explicit, reproducible, independent of the number of threads.
//
// There is no global generator in indoorloc. Every algorithm takes a seed (in its Options) or a
// RandomStream. Independent streams are derived from one seed by hashing (seed, stream index)
// with SplitMix64, so run r of a Monte Carlo study always draws the same numbers whether it runs
// on thread 0 of 1 or thread 5 of 8 (see parallel.h).
//
// The generator is xoshiro256++ (Blackman & Vigna 2019): 256-bit state, period 2^256 - 1,
// passes BigCrush, a few ns per draw. Distributions are implemented here rather than taken from
// <random> because std::normal_distribution & co. differ between standard libraries, which would
// break "same seed, same result" across platforms.
#pragma once

#include <cstdint>
#include <limits>

namespace indoorloc {

/// SplitMix64 finaliser: a bijective 64-bit hash with good avalanche (Steele et al. 2014).
std::uint64_t SplitMix64(std::uint64_t x);

/// Seed of stream `stream` derived from the user `seed`. Distinct (seed, stream) pairs give
/// statistically independent streams.
std::uint64_t DeriveSeed(std::uint64_t seed, std::uint64_t stream);

/// A seeded xoshiro256++ stream with the distributions indoorloc needs. Satisfies the C++
/// UniformRandomBitGenerator requirements, so it also works with <algorithm> (std::shuffle).
/// Above this concentration VonMises draws from its normal limit N(mu, 1/kappa).
inline constexpr double kVonMisesNormalKappa = 1e10;

class RandomStream {
 public:
  using result_type = std::uint64_t;

  /// Stream number `stream` of the family identified by `seed`.
  explicit RandomStream(std::uint64_t seed = 0, std::uint64_t stream = 0);

  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return std::numeric_limits<result_type>::max(); }

  /// Next raw 64-bit output (inline: it sits in every particle filter's inner loop).
  result_type operator()() {
    // xoshiro256++ (Blackman & Vigna, 2019).
    const std::uint64_t result = RotateLeft(state_[0] + state_[3], 23) + state_[0];
    const std::uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = RotateLeft(state_[3], 45);
    return result;
  }

  /// An independent child stream (e.g. one per particle block), derived deterministically from
  /// this stream's current state and `child`; this stream advances by one draw.
  RandomStream Split(std::uint64_t child);

  /// Uniform on [0, 1), 53 random bits.
  double Uniform01() { return static_cast<double>((*this)() >> 11) * 0x1.0p-53; }
  /// Uniform on (0, 1): never returns 0, safe for log().
  double UniformOpen01() { return (static_cast<double>((*this)() >> 11) + 0.5) * 0x1.0p-53; }
  /// Uniform on [lo, hi).
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform01(); }
  /// Uniform integer in [0, n), unbiased (Lemire's multiply-and-reject). Requires n > 0.
  std::uint64_t UniformInt(std::uint64_t n);
  /// Standard normal N(0, 1) (Marsaglia polar method; the spare draw is cached).
  double Normal();
  /// Standard normal N(0, 1) by the ziggurat method (Marsaglia & Tsang 2000, in Doornik's 2005
  /// ZIGNOR form with 128 layers): about 4x faster than Normal() (one raw draw and no log in
  /// 98.8 % of the calls), for particle filters' inner loops. Same distribution as Normal(),
  /// different values.
  double NormalZiggurat() {
    // Fast path inline (the particle filters' inner loops): one raw draw, no log, 98.8 % of calls.
    const std::uint64_t bits = (*this)();
    // Top 53 bits: u uniform on (-1, 1); low 7 bits: the layer (independent bits).
    const double u = 2.0 * (static_cast<double>(bits >> 11) + 0.5) * 0x1.0p-53 - 1.0;
    const int layer = static_cast<int>(bits & 0x7F);
    if ((u < 0 ? -u : u) < kZigguratRatio[layer]) return u * kZigguratX[layer];
    return NormalZigguratOutside(u, layer);
  }
  /// Normal with mean `mean` and standard deviation `sd` (sd >= 0).
  double Normal(double mean, double sd);
  /// Exponential with rate 1.
  double Exponential();
  /// Von Mises on (-pi, pi] with mean direction `mu_rad` and concentration `kappa` >= 0
  /// (Best & Fisher 1979). kappa = 0 gives the uniform circle; kappa > kVonMisesNormalKappa
  /// gives the limiting normal of variance 1/kappa. Throws std::invalid_argument for a
  /// non-finite mu_rad or a negative / non-finite kappa.
  double VonMises(double mu_rad, double kappa);
  /// The ziggurat's slow path for a draw (u on [-1, 1), layer in [0, 128)) that failed the fast
  /// test |u| < kZigguratRatio[layer]: the tail, the wedge test, or a new draw, all from this
  /// stream. RandomLanes::FillNormal resolves its rare rejected lanes with it.
  double NormalZigguratOutside(double u, int layer);

 private:
  friend class RandomLanes;  // the vectorised ziggurat reads the tables
  static std::uint64_t RotateLeft(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  // The ziggurat's layer edges x_i and ratios x_{i+1} / x_i (random.cc).
  static const double kZigguratX[129];
  static const double kZigguratRatio[128];
  static const double kZigguratF[129];  // exp(-x_i² / 2)

  std::uint64_t state_[4];
  double spare_normal_ = 0.0;
  bool has_spare_normal_ = false;
};

}  // namespace indoorloc
