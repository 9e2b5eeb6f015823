// GRS80 normal gravity (Moritz 1980, Geodetic Reference System 1980) with the height correction.
#include "indoorloc/network/gravity.h"

#include <cmath>

namespace indoorloc::network {

namespace {
constexpr double kA = 6378137.0;                 // semi-major axis [m]
constexpr double kF = 1.0 / 298.257222101;       // flattening
constexpr double kM = 0.00344978600308;          // ω² a² b / GM
constexpr double kGammaE = 9.7803267715;         // normal gravity at the equator [m/s^2]
constexpr double kK = 0.001931851353;            // Somigliana constant
constexpr double kE2 = 0.00669438002290;         // first eccentricity squared
}  // namespace

Eigen::Vector3d NormalGravityCoefficients(double latitude_rad) {
  const double s2 = std::sin(latitude_rad) * std::sin(latitude_rad);
  const double gamma0 = kGammaE * (1.0 + kK * s2) / std::sqrt(1.0 - kE2 * s2);
  const double c1 = 2.0 / kA * (1.0 + kF + kM - 2.0 * kF * s2);
  const double c2 = 3.0 / (kA * kA);
  return {gamma0, c1, c2};
}

double NormalGravity(double latitude_rad, double height_m) {
  const Eigen::Vector3d c = NormalGravityCoefficients(latitude_rad);
  return c[0] * (1.0 - c[1] * height_m + c[2] * height_m * height_m);
}

double NormalGravityHeightGradient(double latitude_rad, double height_m) {
  const Eigen::Vector3d c = NormalGravityCoefficients(latitude_rad);
  return c[0] * (-c[1] + 2.0 * c[2] * height_m);
}

Eigen::Vector3d EarthRateEnu(double latitude_rad) {
  return {0.0, kEarthRateRadps * std::cos(latitude_rad), kEarthRateRadps * std::sin(latitude_rad)};
}

}  // namespace indoorloc::network
