#include "indoorloc/core/random.h"

#include <cmath>
#include <stdexcept>

namespace indoorloc {
namespace {

constexpr double kPi = 3.14159265358979323846;

// GCC/Clang extension, marked so -Wpedantic accepts it: 64x64 -> 128-bit product.
__extension__ typedef unsigned __int128 Uint128;


// Wraps an angle to (-pi, pi].
inline double WrapAngle(double a) {
  a = std::remainder(a, 2.0 * kPi);
  return a <= -kPi ? a + 2.0 * kPi : a;
}

}  // namespace

std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

std::uint64_t DeriveSeed(std::uint64_t seed, std::uint64_t stream) {
  // Two rounds so that neighbouring (seed, stream) pairs land far apart.
  return SplitMix64(SplitMix64(seed) ^ SplitMix64(stream ^ 0xD1B54A32D192ED03ULL));
}

RandomStream::RandomStream(std::uint64_t seed, std::uint64_t stream) {
  // Fill the 256-bit state from a SplitMix64 sequence, as the xoshiro authors recommend; the
  // state can never be all zero because SplitMix64 is a bijection of distinct counters.
  std::uint64_t x = DeriveSeed(seed, stream);
  for (std::uint64_t& word : state_) {
    x += 0x9E3779B97F4A7C15ULL;
    word = SplitMix64(x);
  }
}

RandomStream RandomStream::Split(std::uint64_t child) { return RandomStream((*this)(), child); }

std::uint64_t RandomStream::UniformInt(std::uint64_t n) {
  if (n == 0) throw std::invalid_argument("indoorloc: argument 'n': must be > 0");
  // Lemire (2019), "Fast random integer generation in an interval".
  Uint128 m = static_cast<Uint128>((*this)()) * n;
  std::uint64_t low = static_cast<std::uint64_t>(m);
  if (low < n) {
    const std::uint64_t threshold = (0 - n) % n;
    while (low < threshold) {
      m = static_cast<Uint128>((*this)()) * n;
      low = static_cast<std::uint64_t>(m);
    }
  }
  return static_cast<std::uint64_t>(m >> 64);
}

double RandomStream::Normal() {
  if (has_spare_normal_) {
    has_spare_normal_ = false;
    return spare_normal_;
  }
  double u, v, s;
  do {
    u = 2.0 * Uniform01() - 1.0;
    v = 2.0 * Uniform01() - 1.0;
    s = u * u + v * v;
  } while (s >= 1.0 || s == 0.0);
  const double factor = std::sqrt(-2.0 * std::log(s) / s);
  spare_normal_ = v * factor;
  has_spare_normal_ = true;
  return u * factor;
}

double RandomStream::Normal(double mean, double sd) { return mean + sd * Normal(); }

double RandomStream::Exponential() { return -std::log(UniformOpen01()); }

double RandomStream::VonMises(double mu_rad, double kappa) {
  if (!(kappa >= 0.0) || !std::isfinite(kappa)) {
    throw std::invalid_argument("indoorloc: argument 'kappa': must be finite and >= 0");
  }
  if (kappa < 1e-8) return WrapAngle(Uniform(-kPi, kPi));
  // Best & Fisher (1979), Applied Statistics 28(2):152-157, algorithm VM.
  const double tau = 1.0 + std::sqrt(1.0 + 4.0 * kappa * kappa);
  const double rho = (tau - std::sqrt(2.0 * tau)) / (2.0 * kappa);
  const double r = (1.0 + rho * rho) / (2.0 * rho);
  double f;
  while (true) {
    const double u1 = Uniform01();
    const double z = std::cos(kPi * u1);
    f = (1.0 + r * z) / (r + z);
    const double c = kappa * (r - f);
    const double u2 = UniformOpen01();
    if (c * (2.0 - c) - u2 > 0.0 || std::log(c / u2) + 1.0 - c >= 0.0) break;
  }
  const double u3 = Uniform01();
  const double theta = (u3 > 0.5 ? 1.0 : -1.0) * std::acos(std::fmin(1.0, std::fmax(-1.0, f)));
  return WrapAngle(mu_rad + theta);
}

}  // namespace indoorloc
