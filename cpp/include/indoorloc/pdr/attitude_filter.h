// Attitude (sensor orientation R_GS) from gyro + gravity, magnetometer optional, for recordings
// that do not give the orientation (paper 002 used the Xsens' own R_GS).
//
// Mahony's nonlinear complementary filter (Mahony, Hamel, Pflimlin, IEEE TAC 2008, "explicit
// complementary filter", eq. 32), quaternion form, q rotating body -> navigation (z up):
//   v̂ = R(q)ᵀ e_z                      predicted direction of the specific force at rest
//   e  = â × v̂  (+ with the magnetometer a heading-only term −atan2(h_y, h_x) R(q)ᵀ e_z,
//        h = R(q) m̂: the field's horizontal part should lie on +x; unlike Mahony's m̂ × ŵ it
//        leaves roll and pitch to gravity and does not weaken with a steep dip)
//   b  <- b − k_i e Δt                  gyro bias estimate (the integral term)
//   q  <- q ⊗ exp((ω − b + k_p e) Δt / 2)
// The gravity term is applied only when | |f| − g | < acc_gate_mps2 (the foot or body is not
// accelerating much). Magnetometer disturbance test: a sample corrects the heading only when its
// field norm is within mag_norm_tolerance (relative) of the recording's median norm and its dip
// angle (from the current attitude) is within mag_dip_tolerance_rad of the reference dip
// measured over the first init_samples; other samples are rejected (counted in the output).
// Initial attitude: roll and pitch level the mean specific force of the first init_samples; yaw
// 0 (navigation x = the sensor x heading at start), or with the magnetometer yaw puts the
// horizontal field on +x (x magnetic north, y west, z up).
#pragma once

#include <string>

#include <Eigen/Core>

#include "indoorloc/pdr/zero_velocity.h"

namespace indoorloc::pdr {

struct MahonyOptions {
  double kp = 1.0;                 ///< proportional gain on the gravity error [rad/s]
  double ki = 0.05;                ///< integral gain (gyro bias) [rad/s^2]; bias time constant ~ kp / ki
  double kp_mag = 0.5;             ///< proportional gain on the heading error [rad/s per rad]
  double gravity_mps2 = 9.81;
  double acc_gate_mps2 = 2.0;      ///< gravity correction only when ||f| − g| below this [m/s^2]
  double mag_norm_tolerance = 0.1; ///< accepted relative deviation of |m| from its median
  double mag_dip_tolerance_rad = 10.0 * 3.14159265358979323846 / 180.0;  ///< accepted dip deviation
  int init_samples = 20;           ///< samples averaged for the initial attitude and reference dip
  bool IsValid(std::string* error) const;
};

struct AttitudeOutput {
  RowMatrixXd quaternions_wxyz;    ///< N x 4, body -> navigation, w first
  RowMatrixXd gyro_bias_radps;     ///< N x 3 bias estimate
  BoolVector mag_used;             ///< N, magnetometer passed the disturbance test (all false without it)
  double reference_field_norm = 0.0;  ///< median |m| [magnetometer units], 0 without it
  double reference_dip_rad = 0.0;
  int mag_rejected = 0;            ///< samples refused by the disturbance test
  double seconds = 0.0;
};

/// Runs the filter. time_s (N) increasing (repeats get the median period), acc_mps2 and
/// gyro_radps N x 3 finite, mag N x 3 (any unit, e.g. uT) or 0 rows for none.
AttitudeOutput RunMahony(const Eigen::Ref<const Eigen::VectorXd>& time_s, const Eigen::Ref<const RowMatrixXd>& acc_mps2,
                         const Eigen::Ref<const RowMatrixXd>& gyro_radps, const Eigen::Ref<const RowMatrixXd>& mag,
                         const MahonyOptions& options = MahonyOptions());

}  // namespace indoorloc::pdr
