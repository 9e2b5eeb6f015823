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

namespace {
// Ziggurat tables for N(0, 1) (Doornik 2005, "An improved ziggurat method to generate normal
// random samples", ZIGNOR): 128 layers of equal area V with the base strip's tail from R.
struct ZigguratTables {
  static constexpr int kLayers = 128;
  static constexpr double kR = 3.442619855899;
  static constexpr double kV = 9.91256303526217e-3;
  double x[kLayers + 1];
  double ratio[kLayers];
  ZigguratTables() {
    double f = std::exp(-0.5 * kR * kR);
    x[0] = kV / f;  // the base strip, tail included, as a rectangle of area V
    x[1] = kR;
    x[kLayers] = 0.0;
    // Layer i + 1 sits on layer i with the same area V: x_{i+1} = f⁻¹(V / x_i + f(x_i)).
    for (int i = 2; i < kLayers; ++i) {
      x[i] = std::sqrt(-2.0 * std::log(kV / x[i - 1] + f));
      f = std::exp(-0.5 * x[i] * x[i]);
    }
    for (int i = 0; i < kLayers; ++i) ratio[i] = x[i + 1] / x[i];
  }
};
const ZigguratTables& Tables() {
  static const ZigguratTables tables;
  return tables;
}
}  // namespace

double RandomStream::NormalZiggurat() {
  const ZigguratTables& t = Tables();
  for (;;) {
    const std::uint64_t bits = (*this)();
    // Top 53 bits: u uniform on (-1, 1); low 7 bits: the layer (independent bits).
    const double u = 2.0 * (static_cast<double>(bits >> 11) + 0.5) * 0x1.0p-53 - 1.0;
    const int i = static_cast<int>(bits & 0x7F);
    if (std::abs(u) < t.ratio[i]) return u * t.x[i];  // inside the layer's inner rectangle
    if (i == 0) {
      // Base strip outside the rectangle: the normal tail beyond R (Marsaglia 1964).
      double x, y;
      do {
        x = std::log(UniformOpen01()) / ZigguratTables::kR;
        y = std::log(UniformOpen01());
      } while (-2.0 * y < x * x);
      return u < 0.0 ? x - ZigguratTables::kR : ZigguratTables::kR - x;
    }
    const double x = u * t.x[i];
    const double f0 = std::exp(-0.5 * (t.x[i] * t.x[i] - x * x));
    const double f1 = std::exp(-0.5 * (t.x[i + 1] * t.x[i + 1] - x * x));
    if (f1 + Uniform01() * (f0 - f1) < 1.0) return x;
  }
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
