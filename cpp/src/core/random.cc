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

// Ziggurat tables for N(0, 1) (Doornik 2005, "An improved ziggurat method to generate normal
// random samples", ZIGNOR): 128 layers of equal area V = 9.91256303526217e-3 with the base
// strip's tail from R = 3.442619855899. x_0 = V / f(R) (the base strip, tail included, as a
// rectangle of area V), x_1 = R, x_{i+1} = f⁻¹(V / x_i + f(x_i)) (layer i + 1 sits on layer i with
// the same area), x_128 = 0, f(x) = exp(-x²/2); ratio_i = x_{i+1} / x_i. Written out as literals
// (17 significant digits, computed once with that recurrence) so that they are constant-initialised
// and identical on every platform.
namespace {
constexpr double kR = 3.442619855899;
}  // namespace

const double RandomStream::kZigguratX[129] = {
    3.7130862467425505, 3.442619855899, 3.2230849845811416, 3.0832288582168683, 2.9786962526477803,
    2.894344007021529, 2.8231253505489105, 2.761169372387177, 2.7061135731218195,
    2.6564064112613597, 2.6109722484318474, 2.569033625924938, 2.5300096723888275,
    2.493454522095372, 2.4590181774118305, 2.42642064553375, 2.3954342780110625, 2.3658713701176386,
    2.3375752413392368, 2.310413683698763, 2.2842740596774718, 2.2590595738691985,
    2.2346863955909795, 2.2110814088787034, 2.188180432076049, 2.165926793748922,
    2.1442701823603953, 2.1231657086739766, 2.1025731351892385, 2.082456237992017,
    2.0627822745083084, 2.0435215366550676, 2.0246469733773855, 2.006133869963472, 1.98795957412762,
    1.9701032608543265, 1.9525457295535567, 1.9352692282966228, 1.9182573008645099,
    1.901494653105151, 1.884967035707759, 1.8686611409944887, 1.8525645117280911, 1.836665460258446,
    1.8209529965961255, 1.8054167642192285, 1.7900469825998586, 1.7748343955860695,
    1.7597702248995934, 1.7448461281138004, 1.7300541605637305, 1.7153867407136676,
    1.7008366185699169, 1.6863968467791681, 1.672060754097601, 1.6578219209540241,
    1.6436741568628686, 1.6296114794706347, 1.615628095043161, 1.6017183802213781,
    1.5878768648905761, 1.5740982160230008, 1.560377222366169, 1.5467087798599104,
    1.5330878776740433, 1.5195095847659401, 1.5059690368632033, 1.492461423781354,
    1.4789819769899242, 1.4655259573427108, 1.4520886428892246, 1.4386653166845635,
    1.42525125451406, 1.4118417124470577, 1.3984319141310053, 1.3850170377326518,
    1.3715922024273426, 1.3581524543301435, 1.344692751753547, 1.3312079496656273,
    1.317692783209414, 1.3041418501286168, 1.2905495919261964, 1.2769102735601556,
    1.263217961454621, 1.2494664995730682, 1.2356494832633627, 1.2217602305399964,
    1.2077917504159497, 1.1937367078331287, 1.1795873846639882, 1.1653356361647524,
    1.1509728421488674, 1.1364898520131608, 1.1218769225825422, 1.107123647534036,
    1.0922188769072774, 1.0771506248928957, 1.0619059636948243, 1.0464709007640454,
    1.0308302360681956, 1.0149673952513305, 0.9988642334929836, 0.982500803515429,
    0.9658550794011499, 0.9489026255113064, 0.9316161966151508, 0.9139652510230323,
    0.8959153525809377, 0.8774274291129234, 0.8584568431938132, 0.8389522142975774,
    0.8188539067003573, 0.7980920606440569, 0.7765839878947599, 0.7542306644540556,
    0.7309119106424888, 0.7064796113354365, 0.6807479186691546, 0.6534786387399752,
    0.6243585973360507, 0.5929629424714483, 0.5586921784081852, 0.5206560387620606,
    0.4774378372966898, 0.4265479863554235, 0.36287143109703196, 0.27232086481396467, 0.0,
};

const double RandomStream::kZigguratRatio[128] = {
    0.9271586026096681, 0.9362302895738892, 0.9566079929529229, 0.9660963845448882,
    0.971681487982781, 0.9753938521821022, 0.9780541171685178, 0.980060694640489,
    0.9816315315239645, 0.9828963811271866, 0.9839375456663325, 0.9848098704733534,
    0.9855513792328944, 0.9861893030819736, 0.9867436799867864, 0.9872295978111943,
    0.9876586437103296, 0.9880398701570176, 0.9883804563121089, 0.9886861715693078,
    0.9889617072428545, 0.9892109183130244, 0.9894370025436909, 0.9896426351781105,
    0.9898300715969688, 0.9900012265183524, 0.9901577357834697, 0.9903010050508025,
    0.9904322485336944, 0.9905525200843218, 0.9906627383358567, 0.9907637071892196,
    0.9908561326209719, 0.9909406365607181, 0.991017768416579, 0.9910880146997187,
    0.991151807102165, 0.991209529308185, 0.9912615227624552, 0.9913080915739614,
    0.9913495066999154, 0.9913860095266759, 0.9914178149430195, 0.9914451139838447,
    0.9914680761085329, 0.9914868511670121, 0.9915015710974835, 0.9915123513923666,
    0.9915192923629307, 0.9915224802280646, 0.9915219880484646, 0.9915178765240442,
    0.9915101946694387, 0.9914989803800052, 0.9914842608986051, 0.9914660531916395,
    0.9914443642412228, 0.9914191912590011, 0.9913905218258715, 0.9913583339607497,
    0.9913225961204966, 0.9912832671321499, 0.9912402960576856, 0.991193621990624,
    0.991143173782899, 0.991088869699481, 0.9910306169972894, 0.9909683114239041,
    0.9909018366304913, 0.9908310634921467, 0.9907558493275227, 0.9906760370080955,
    0.9905914539457294, 0.9905019109452362, 0.9904072009063883, 0.990307097357238,
    0.990201352797563, 0.9900896968277136, 0.9899718340339569, 0.9898474415964779,
    0.9897161665803526, 0.9895776228628198, 0.9894313876418468, 0.9892769974609422,
    0.9891139436730952, 0.9889416672520418, 0.9887595528412437, 0.9885669219091597,
    0.9883630248526034, 0.9881470318569457, 0.9879180222809051, 0.987674972282531,
    0.9874167403388364, 0.9871420502305995, 0.9868494709610887, 0.9865373929461655,
    0.986203999644239, 0.9858472335755389, 0.98546475539409, 0.9850538942989907, 0.9846115875710347,
    0.9841343063494573, 0.9836179638544746, 0.9830578010168337, 0.9824482427525728,
    0.9817827157061126, 0.9810534148544756, 0.9802510014227667, 0.9793642073274506,
    0.9783793105963312, 0.9772794298852922, 0.9760435609386315, 0.9746452378300764,
    0.9730506368752245, 0.9712158326862985, 0.9690827290502092, 0.9665728537853818,
    0.9635775863118795, 0.959942176565901, 0.9554384188286962, 0.9497153478809163,
    0.9422042060159378, 0.9319193267489506, 0.9169927970716931, 0.8934105197245976,
    0.8507165493794344, 0.7504610213889943, 0.0,
};

double RandomStream::NormalZigguratOutside(double u, int layer) {
  if (layer == 0) {
    // Base strip outside the rectangle: the normal tail beyond R (Marsaglia 1964).
    double x, y;
    do {
      x = std::log(UniformOpen01()) / kR;
      y = std::log(UniformOpen01());
    } while (-2.0 * y < x * x);
    return u < 0.0 ? x - kR : kR - x;
  }
  // The wedge between the layer's inner rectangle and the curve.
  const double x = u * kZigguratX[layer];
  const double x0 = kZigguratX[layer], x1 = kZigguratX[layer + 1];
  const double f0 = std::exp(-0.5 * (x0 * x0 - x * x));
  const double f1 = std::exp(-0.5 * (x1 * x1 - x * x));
  if (f1 + Uniform01() * (f0 - f1) < 1.0) return x;
  return NormalZiggurat();  // rejected: a new draw (fast path first); rare, so no deep recursion
}

double RandomStream::Normal(double mean, double sd) { return mean + sd * Normal(); }

double RandomStream::Exponential() { return -std::log(UniformOpen01()); }

double RandomStream::VonMises(double mu_rad, double kappa) {
  if (!(kappa >= 0.0) || !std::isfinite(kappa)) {
    throw std::invalid_argument("indoorloc: argument 'kappa': must be finite and >= 0, got " +
                                std::to_string(kappa));
  }
  if (!std::isfinite(mu_rad)) {
    throw std::invalid_argument("indoorloc: argument 'mu_rad': must be finite, got " + std::to_string(mu_rad));
  }
  if (kappa < 1e-8) return WrapAngle(Uniform(-kPi, kPi));
  // Large κ: the closed-form limit, a normal of variance 1/κ (the error is O(1/κ) in the
  // kurtosis, below double precision here). Algorithm VM cannot be used there: r = 1 + 1/(2κ)
  // rounds to 1 above κ ≈ 3e16, c becomes 0 and the rejection loop never accepts.
  if (kappa > kVonMisesNormalKappa) return WrapAngle(mu_rad + Normal() / std::sqrt(kappa));
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
