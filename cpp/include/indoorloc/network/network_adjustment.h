// INS/GPS network adjustment for strapdown inertial kinematic gravimetry (NA): the whole flight
// as one sparse least-squares network, after Térmens & Colomina, "Network approach versus
// state-space approach for strapdown inertial kinematic gravimetry" (paper 003, §3).
//
// Parameters per IMU epoch n (paper §3.1: x = (r, v, R, δg, a, o)): position r[n] [m] and
// velocity v[n] [m/s] in the local Earth-fixed ENU frame of gravity.h, attitude quaternion q[n]
// (body -> ENU, on its manifold: 3 degrees of freedom), accelerometer bias a[n] [m/s^2], gyro bias
// o[n] [rad/s] (body frame), vertical gravity disturbance δg[n] [m/s^2] (scalar; see gravity.h).
//
// Dynamic observation equations (paper §3.3), with f[n], ω[n] the IMU samples, Λ the difference
// operator and g(r, δg) = (0, 0, -(γ(h) + δg)):
//   VEL:  0    = v - Λ(r)
//   FB:   f[n] = R(q)ᵀ (Λ(v) + 2 ω_ie × v - g(r, δg)) + a
//   WIB:  ω[n] = R(q)ᵀ ω_ie + Λ_q + o,   Λ_q = Log(q[n-1]⁻¹ q[n+1]) / 2δt  (leap-frog; this is the
//               paper's 2 M_q(q)ᵀ Λ(q) written on the rotation manifold)
//   AB, OB, GDT: 0 = Λ(a), Λ(o), Λ(δg)   (random walks; biases optionally Gauss-Markov)
// Leap-frog (paper): Λ(x, n) = (x[n+1] - x[n-1]) / 2δt, the other terms at epoch n, for
// n = 1..N-2. It couples only epochs of the same parity: apart from the weak Coriolis and
// normal-gravity-gradient terms, the network splits into two interleaved chains (the "weak
// stability" of §3.3). Trapezoidal: Λ(x, n+½) = (x[n+1] - x[n]) / δt with the other terms the mean
// of epochs n and n+1 (Λ_q = Log(q[n]⁻¹ q[n+1]) / δt), for n = 0..N-2; no parity decoupling.
//
// Static observation equations (paper §3.2, §3.4): CUPT r(t_gps) = p_gps (linear interpolation
// between the two epochs around t_gps), VUPT v[n] = v0 (known velocity, σ per observation or
// sigma_vupt_mps), ZUPT v[n] = 0 (a VUPT with v0 = 0), GUPT g0 = γ(h[n]) + δg[n], XOVER
// δg[n] = δg[k] (equal disturbance at two epochs that coincide horizontally; the paper equates
// total gravity, which differs by the normal-gravity height gradient: see docs/network.md), and
// SGUPT (paper §3.2: "for every ZUPT equation, gravity can be considered as a constant function.
// It can be seen as a XOVER observation"): during a static period (a run of consecutive epochs
// that carry a ZUPT, or a VUPT with v0 = 0) the platform does not move, so gravity is the same at
// every epoch of the period: δg[n] = δg[n0] for every epoch n of the run, n0 its first epoch
// (XOVER ties to the period's first epoch, σ = sigma_sgupt_mps2). SGUPT does not make gravity
// known (that is a GUPT); it makes it constant while static.
//
// Slow parameters (paper §4: "a^b, o^b, δg^e at Hz(GPS) frequency and r^e, v^e and q at
// Hz(IMU)"): with slow_parameter_stride s > 1 the biases and δg are carried by one block per
// interval of s IMU epochs, [ks, (k+1)s) ("subsets of them grouped in a single one": piecewise
// constant). The dynamic equations at epoch n (FB, WIB; trapezoidal: the two epochs of the
// interval) use the block of the interval containing n; AB, OB, GDT link consecutive blocks over
// the time between the interval centres, Δt = s δt (the random-walk sd q √Δt grows accordingly);
// GUPT, XOVER and SGUPT refer to the block of their epoch's interval. Unknowns: 9 N + 7 ⌈N/s⌉
// instead of 16 N. The state in and out keeps one row per epoch (the epochs of an interval share
// the block's value; initial values are averaged over the interval).
//
// Weights come from noise densities: an IMU sample with white-noise density N [unit/√Hz] has
// σ = N / √δt; a random walk with density q [unit/√s] over a step Δt has σ = q √Δt.
//
// Datum: before Solve the network is checked for defects (no CUPT; CUPTs only on one parity
// chain under leap-frog) and, optionally, numerically: the normal matrix JᵀJ at the initial
// values, scaled to a unit diagonal, is factorised (sparse LDLᵀ, AMD ordering) and a pivot below
// datum_pivot_tolerance names the undetermined parameter and epoch.
// Either throws std::invalid_argument naming the observation argument responsible.
#pragma once

#include <string>

#include <Eigen/Core>

#include "indoorloc/core/options.h"

namespace indoorloc::network {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMatrixX2i = Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor>;

enum class Discretization {
  kLeapFrog,     ///< paper §3.3: (x[n+1] - x[n-1]) / 2δt; decouples even and odd epochs
  kTrapezoidal,  ///< (x[n+1] - x[n]) / δt = mean of the right-hand side at n and n+1
};

struct NetworkOptions {
  Discretization discretization = Discretization::kLeapFrog;
  double latitude_rad = 0.7223;        ///< latitude of the frame origin (41.4 deg)
  double origin_height_m = 0.0;        ///< ellipsoidal height of the frame origin
  double earth_rate_radps = 7.292115e-5;  ///< set 0 to drop Earth rotation (tests)
  // Noise densities (weights).
  double acc_noise_mps2_rthz = 5e-4;       ///< accelerometer white noise [m/s^2/√Hz]
  double gyro_noise_radps_rthz = 1e-5;     ///< gyro white noise [rad/s/√Hz]
  double acc_bias_walk_mps2_rts = 1e-6;    ///< accelerometer bias random walk [m/s^2/√s]
  double gyro_bias_walk_radps_rts = 1e-7;  ///< gyro bias random walk [rad/s/√s]
  double gravity_walk_mps2_rts = 2e-5;     ///< GDT: δg random walk along time [m/s^2/√s]
  /// Bias models (F_acc, F_gyr of the paper): 0 = random walk (default); τ > 0 = first-order
  /// Gauss-Markov ḃ = -b/τ + w with the same driving density q: b[k+1] = φ b[k] + w,
  /// φ = exp(-Δt/τ), var(w) = q² τ/2 (1 - φ²) (steady-state sd q √(τ/2)).
  double acc_bias_correlation_time_s = 0.0;
  double gyro_bias_correlation_time_s = 0.0;
  /// VEL pseudo-observation sd [m/s]: a kinematic identity, so tight; a loose VEL lets v absorb
  /// the FB noise (the accelerometer group then has no redundancy, see variance components).
  double sigma_vel_mps = 1e-5;
  double sigma_gps_m = 0.02;               ///< CUPT sd per axis [m]
  double sigma_zupt_mps = 1e-3;            ///< ZUPT sd per axis [m/s]
  double sigma_gupt_mps2 = 1e-5;           ///< GUPT sd [m/s^2] (1 mGal)
  double sigma_xover_mps2 = 1e-5;          ///< XOVER sd [m/s^2] (1 mGal)
  /// VUPT sd per axis [m/s] for the observations without their own (vupt_sd_mps empty).
  double sigma_vupt_mps = 0.01;
  /// SGUPT sd [m/s^2] of each tie δg[n] - δg[n0] inside a static period (0.1 mGal: gravity does
  /// not change while the platform stands still; the sd absorbs the model's own approximations).
  double sigma_sgupt_mps2 = 1e-6;
  /// Slow parameters (paper §4): one accelerometer-bias, gyro-bias and δg block per
  /// slow_parameter_stride IMU epochs (1: every epoch). E.g. IMU rate / GPS rate.
  int slow_parameter_stride = 1;
  /// Huber loss on CUPT residuals with this threshold in units of sigma_gps_m (0: plain least
  /// squares) against GPS outliers.
  double gps_huber_threshold = 0.0;
  // Solver.
  int max_iterations = 20;
  /// Levenberg-Marquardt's initial trust region. Large: the network is nearly linear around
  /// filter-quality initial values, so Gauss-Newton-like first steps converge in a few
  /// iterations (Ceres' default 1e4 needs ~15 iterations to grow the region).
  double initial_trust_region_radius = 1e12;
  double function_tolerance = 1e-12;
  double gradient_tolerance = 1e-14;
  double parameter_tolerance = 1e-12;
  int num_threads = 1;
  /// Factorise JᵀJ at the initial values and reject rank-deficient networks (see above).
  bool check_datum = true;
  double datum_pivot_tolerance = 1e-12;  ///< on the Jacobi-scaled JᵀJ
  /// Selected covariances (paper §3.5, small problems): the standard deviation of every δg[n]
  /// from (JᵀJ)⁻¹ at the solution (whitened residuals: no variance factor applied).
  enum class Covariance { kNone, kCeres, kDense };
  /// kCeres: ceres::Covariance (SPARSE_QR, only the δg diagonal blocks); kDense: the full dense
  /// inverse (the brute-force reference; refused above 8,000 unknowns).
  Covariance gravity_covariance = Covariance::kNone;
  /// Variance components of the accelerometer (FB), gyro (WIB) and GPS (CUPT) groups at the
  /// solution (Förstner: σ̂²_g = v_gᵀ v_g / r_g, redundancy r_g = m_g - tr(N⁻¹ J_gᵀ J_g)), from
  /// the dense inverse of N = JᵀJ: small problems only (refused above 8,000 unknowns).
  bool variance_components = false;

  bool IsValid(std::string* error) const;
};

/// The observations of one flight. IMU samples on a uniform time grid.
struct NetworkObservations {
  Eigen::VectorXd imu_time_s;        ///< N, strictly increasing, uniform step (rel. 1e-6)
  RowMatrixXd acc_body_mps2;         ///< N x 3 specific force f[n] (body frame)
  RowMatrixXd gyro_body_radps;       ///< N x 3 angular rate ω_ib[n] (body frame)
  Eigen::VectorXd gps_time_s;        ///< M, strictly increasing, inside the IMU span
  RowMatrixXd gps_position_m;        ///< M x 3 ENU positions of the IMU centre
  Eigen::VectorXi zupt_epochs;       ///< epochs with v = 0
  Eigen::VectorXi gupt_epochs;       ///< epochs with known gravity
  Eigen::VectorXd gupt_gravity_mps2; ///< total gravity g0 at those epochs (magnitude)
  RowMatrixX2i xover_epochs;         ///< K x 2 epoch pairs with equal δg (see FindCrossovers)
  Eigen::VectorXi vupt_epochs;       ///< V epochs with known velocity
  RowMatrixXd vupt_velocity_mps;     ///< V x 3 known ENU velocities v0 [m/s]
  Eigen::VectorXd vupt_sd_mps;       ///< V sds per axis [m/s] (> 0), or empty: sigma_vupt_mps
  /// Static epochs with constant gravity (SGUPT), strictly increasing; each must carry a ZUPT or a
  /// VUPT with v0 = 0. Each run of consecutive epochs is one static period.
  Eigen::VectorXi sgupt_epochs;
};

/// Parameters of all epochs (initial values in, estimates out).
struct NetworkState {
  RowMatrixXd position_m;            ///< N x 3 ENU
  RowMatrixXd velocity_mps;          ///< N x 3 ENU
  RowMatrixXd attitude_wxyz;         ///< N x 4 unit quaternion body -> ENU (w, x, y, z)
  RowMatrixXd acc_bias_mps2;         ///< N x 3 body (slow stride s: equal within an interval)
  RowMatrixXd gyro_bias_radps;       ///< N x 3 body (slow stride s: equal within an interval)
  Eigen::VectorXd gravity_disturbance_mps2;  ///< N vertical δg (positive: stronger gravity)
  /// N standard deviations of δg (output only, when options.gravity_covariance != kNone).
  Eigen::VectorXd gravity_disturbance_sd_mps2;
};

struct NetworkSummary {
  Termination termination = Termination::kFailure;
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  double seconds_total = 0.0;
  double seconds_solve = 0.0;       ///< Ceres Solve only
  double seconds_datum_check = 0.0;
  int num_epochs = 0;
  long num_parameters = 0;          ///< tangent-space unknowns (16 N, or 9 N + 7 num_slow_nodes)
  long num_residuals = 0;
  int num_slow_nodes = 0;           ///< bias / δg blocks: ⌈N / slow_parameter_stride⌉
  int num_xover = 0;                ///< XOVER residuals (ties inside one slow interval are dropped)
  int num_vupt = 0;
  int num_sgupt = 0;                ///< SGUPT residuals (ties δg[n] - δg[n0])
  double min_pivot_ratio = 0.0;     ///< smallest LDLᵀ pivot / diagonal (datum check; 0 if off)
  /// A-posteriori variance factor 2 F / (m - n): about 1 when the stated noise densities are right.
  double variance_factor = 0.0;
  double seconds_covariance = 0.0;
  /// Variance factors of the groups relative to the stated densities (options.variance_components;
  /// 0 otherwise) and their redundancy numbers.
  double variance_factor_acc = 0.0, variance_factor_gyro = 0.0, variance_factor_gps = 0.0;
  double redundancy_acc = 0.0, redundancy_gyro = 0.0, redundancy_gps = 0.0;
  std::string message;              ///< Ceres' message

  std::string BriefReport() const;
};

/// Solves the network from `initial` (for example a Kalman filter's output). Throws
/// std::invalid_argument naming the argument for bad shapes, NaN, non-monotonic or non-uniform
/// IMU times, GPS times outside the IMU span, epoch indices out of range, and datum defects.
NetworkState SolveNetwork(const NetworkObservations& observations, const NetworkState& initial,
                          const NetworkOptions& options, NetworkSummary* summary = nullptr);

/// Iterated variance component estimation (small networks): solves, rescales
/// acc_noise_mps2_rthz, gyro_noise_radps_rthz and sigma_gps_m by the square roots of their groups'
/// variance factors, and repeats until every factor is within `tolerance` of 1 or `iterations`
/// solves. `estimated` receives the rescaled options; `summary` the last solve's Summary.
NetworkState EstimateVarianceComponents(const NetworkObservations& observations, const NetworkState& initial,
                                        const NetworkOptions& options, NetworkOptions* estimated,
                                        NetworkSummary* summary = nullptr, int iterations = 10,
                                        double tolerance = 1e-3);

/// Checks shapes and values of `observations` and `state` for N epochs (throws as SolveNetwork).
void CheckNetworkInput(const NetworkObservations& observations, const NetworkState& state);

/// Cross-over finder options.
struct CrossoverOptions {
  double radius_m = 5.0;                 ///< horizontal distance below which two epochs coincide
  double max_height_difference_m = 50.0; ///< allowed |Δh|
  double min_separation_s = 30.0;        ///< epochs closer in time are the same pass
  bool IsValid(std::string* error) const;
};

/// Cross-overs of a trajectory: pairs (n, k), n < k, of epochs at most radius_m apart
/// horizontally, |Δh| within bounds and at least min_separation_s apart in time; one pair (the
/// closest) per crossing of two passes (candidates within min_separation_s and 2 radius_m of an
/// accepted pair on both passes are the same crossing; a line flown twice gives a tie every
/// ~2 radius_m). Grid hashing, O(N + candidates x crossings).
RowMatrixX2i FindCrossovers(const Eigen::Ref<const Eigen::VectorXd>& time_s,
                            const Eigen::Ref<const RowMatrixXd>& position_m, const CrossoverOptions& options);

}  // namespace indoorloc::network
