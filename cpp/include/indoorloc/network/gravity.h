// Normal gravity and the local Earth-fixed navigation frame of the network subsystem.
//
// Frame (stated model, docs/network.md): a local-level East-North-Up frame tangent to the
// ellipsoid at latitude φ0, fixed to the Earth (a rotated, translated ECEF frame). The Earth
// rotation rate in it is ω_ie = Ω (0, cos φ0, sin φ0). Normal gravity is taken along -Up with
// the GRS80 Somigliana magnitude at φ0 and the second-order height correction
//   γ0(φ) = γe (1 + k sin²φ) / sqrt(1 - e² sin²φ),
//   γ(φ, h) = γ0(φ) [1 - 2/a (1 + f + m - 2 f sin²φ) h + 3 h² / a²]   (Heiskanen & Moritz 2-124).
// The curvature of the survey area (a few tens of km) is neglected: γ depends on the height h
// (the Up coordinate plus the height of the frame origin) only. Gravity disturbance δg is its
// vertical component, positive when gravity is stronger than normal: g = (0, 0, -(γ(h) + δg)).
#pragma once

#include <Eigen/Core>

namespace indoorloc::network {

constexpr double kEarthRateRadps = 7.292115e-5;  ///< GRS80 ω [rad/s]
constexpr double kMgal = 1e-5;                   ///< 1 mGal in m/s^2

/// GRS80 normal gravity magnitude [m/s^2] at geodetic latitude `latitude_rad` and ellipsoidal
/// height `height_m` (Somigliana + second-order height term).
double NormalGravity(double latitude_rad, double height_m);

/// d γ / d h [1/s^2] at (latitude, height).
double NormalGravityHeightGradient(double latitude_rad, double height_m);

/// Earth rotation vector in the local ENU frame at `latitude_rad` [rad/s].
Eigen::Vector3d EarthRateEnu(double latitude_rad);

/// Coefficients (γ0, c1, c2) with γ(h) = γ0 (1 - c1 h + c2 h²) at `latitude_rad`.
Eigen::Vector3d NormalGravityCoefficients(double latitude_rad);

}  // namespace indoorloc::network
