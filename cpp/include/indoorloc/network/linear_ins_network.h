// The linearised (error-state) strapdown INS/GPS network of paper 003 at any size, assembled
// block by block straight into the block-tridiagonal solver: the scale test of the network
// approach (Table 2 sizes: 200 Hz x 10,800 s = 2.16 M epochs x 18 unknowns = 38.9 M unknowns).
//
// Unknowns per IMU epoch n (18): δr (3, m), δv (3, m/s), attitude error ψ (3, rad), accelerometer
// bias a (3, m/s²), gyro bias ω (3, rad/s), gravity disturbance δg (3, m/s²).
// Error dynamics (local-level frame, specific force f constant, Earth rotation neglected at the
// error level; the full nonlinear model lives in the network adjustment):
//     δṙ = δv,   δv̇ = -[f×] ψ + a + δg,   ψ̇ = -ω,   ȧ = 0,   ω̇ = 0,   δġ = 0   (+ noise)
// i.e. ẋ = F x + w. Each IMU epoch contributes 18 dynamic observation equations (VEL, FB, WIB,
// AB, OB, GDT of the paper), discretised by
//     leap-frog (paper §3.3):  (x[n+1] - x[n-1]) / 2δt = F x[n] + w[n],      n = 1 .. E-2
//     trapezoidal:             (x[n+1] - x[n])   / δt  = F (x[n] + x[n+1])/2 + w[n], n = 0 .. E-2
// Static equations: CUPT δr[n] = l_gps at the GPS epochs (3 rows each, so N_eq = 18 N_IMU +
// 3 N_GPS as in the paper's Table 2 up to the boundary epochs), an initial-alignment prior on
// every unknown of the first `prior_epochs` epochs and GUPT (δg known) on the last epochs. The leap-frog rule leaves even and odd epochs
// coupled only through F x[n]: ψ_z, for one, is tied to its own parity chain alone, so a prior on
// one epoch leaves the other chain without datum (the paper's weak stability) and the solver
// reports the rank defect; two prior epochs (or the trapezoidal rule) fix it.
//
// Blocks: leap-frog equations span epochs n-1 .. n+1, so two epochs per block (b = 36) make the
// normal matrix block-tridiagonal; trapezoidal equations span n, n+1: one epoch per block (b = 18).
// Observations are synthesised from a known smooth truth x*(t) (noise-free: l = J x*), so the
// solution must return x* exactly; the noise enters through the weights only.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/network/block_tridiagonal.h"
#include "indoorloc/network/crossover_pcg.h"

namespace indoorloc::network {

enum class Discretisation { kLeapFrog, kTrapezoidal };

struct LinearInsNetworkOptions {
  double imu_rate_hz = 200.0;
  double duration_s = 60.0;
  double gps_rate_hz = 1.0;
  Discretisation rule = Discretisation::kLeapFrog;
  int prior_epochs = 2;               ///< epochs at the start with an alignment prior on every unknown
  double specific_force_mps2[3] = {0.3, -0.2, 9.81};
  // Noise densities of the dynamic equation groups. A white-noise density d [unit/√Hz] gives one
  // discretised-derivative row the standard deviation d / √δt, so the weights scale with the rate
  // as they should (constant per-row sigmas would make the normal matrix stiffer as 1/δt², and
  // at 200 Hz x 3 h the Cholesky broke down on the last block).
  double velocity_density = 1e-3;     ///< VEL: δṙ - δv [m/s/√Hz]
  double accel_density = 1e-3;        ///< FB: accelerometer white noise [m/s²/√Hz] (100 µg/√Hz)
  double gyro_density = 1e-4;         ///< WIB: angular random walk [rad/s/√Hz] (0.34 °/√h)
  double accel_bias_density = 1e-4;   ///< AB: accelerometer bias random walk [m/s³/√Hz]
  double gyro_bias_density = 1e-5;    ///< OB: gyro bias random walk [rad/s²/√Hz]
  double gravity_density = 1e-4;      ///< GDT: δg random walk along the track [m/s³/√Hz]
  double sigma_gps_m = 0.05;          ///< CUPT
  /// Alignment prior (all units). Tight on purpose: modes that only the prior sees (the split
  /// of accelerometer bias and δg, which enter δv̇ as a sum) are otherwise determined with a
  /// relative pivot near 1e-12 against the random-walk weights, and the normal equations lose
  /// every digit (measured: max error 0.03-0.15 with σ = 1, 1e-7 with σ = 1e-3).
  double sigma_prior = 1e-3;
  int gupt_end_epochs = 2;            ///< GUPT (known δg) on the last epochs (landing at a known gravity point)
  double sigma_gupt_mps2 = 1e-5;      ///< 1 mGal
  bool IsValid(std::string* error) const;
};

/// Sizes of the network, as in the paper's Table 2.
struct NetworkSize {
  long long imu_epochs = 0;
  long long gps_epochs = 0;
  long long unknowns = 0;        ///< 18 per IMU epoch
  long long equations = 0;       ///< dynamic + CUPT + prior rows
  int block_size = 0;            ///< 36 (leap-frog) or 18 (trapezoidal)
  int num_blocks = 0;
};

NetworkSize LinearInsNetworkSize(const LinearInsNetworkOptions& options);

/// The known truth x*(t) of epoch n (18 values), used to synthesise the observations.
Eigen::Matrix<double, 18, 1> LinearInsTruth(long long epoch, double imu_rate_hz);

/// The network's normal equations, block row by block row (blocks of LinearInsNetworkSize().
/// block_size), for SolveBlockTridiagonal or for assembling the sparse matrix elsewhere.
BlockRowAssembler LinearInsAssembler(const LinearInsNetworkOptions& options);

/// The network's observation equations, for building it in other solvers (benchmarks):
/// dynamic equation i centred at epoch centres[i] reads Σ_a J[a] x[centres[i] + offsets[a]] =
/// dynamic_l.row(i) with row standard deviations row_sigma; CUPT δr[gps_epochs[k]] =
/// gps_l.row(k) (σ sigma_gps); prior x[n] = prior_l.row(n), n < prior_epochs (σ sigma_prior);
/// GUPT δg[gupt_epochs[k]] = gupt_l.row(k) (σ sigma_gupt).
struct LinearInsEquations {
  std::vector<int> offsets;
  std::vector<Eigen::MatrixXd> J;  ///< 18 x 18 each
  Eigen::VectorXd row_sigma;       ///< 18
  std::vector<long long> centres;
  Eigen::MatrixXd dynamic_l;       ///< centres.size() x 18
  std::vector<long long> gps_epochs;
  Eigen::MatrixXd gps_l;           ///< x 3
  Eigen::MatrixXd prior_l;         ///< prior_epochs x 18
  std::vector<long long> gupt_epochs;
  Eigen::MatrixXd gupt_l;          ///< x 3
  double sigma_gps = 0, sigma_prior = 0, sigma_gupt = 0;
  long long imu_epochs = 0;
};
LinearInsEquations LinearInsNetworkEquations(const LinearInsNetworkOptions& options);

struct LinearInsNetworkResult {
  NetworkSize size;
  BlockTridiagonalSummary solver;
  double max_abs_error = 0.0;             ///< max |x - x*| over every unknown
  /// 18: max |x - x*| per unknown of an epoch (δr 0-2, δv 3-5, ψ 6-8, a 9-11, ω 12-14, δg 15-17),
  /// each in its own unit: which unknown the round-off of a long chain reaches.
  Eigen::VectorXd max_abs_error_by_unknown;
  long long max_abs_error_epoch = -1;     ///< the epoch of max_abs_error
  double gravity_rmse = 0.0;              ///< δg error RMSE [m/s²] (≈ 0: noise-free)
  Eigen::MatrixXd gravity_sigma;          ///< E x 3: sqrt of the diagonal of Σ_δg per epoch [m/s²]
  Eigen::MatrixXd gravity_estimate;       ///< E x 3 [m/s²]; empty unless keep_gravity_estimate
  double total_seconds = 0.0;
};

/// Builds the network of `options` block by block and solves it with SolveBlockTridiagonal
/// (`solver.selected` is overridden to the δg components of every epoch in the block when
/// `gravity_covariance` is true), on `num_threads` threads (1 or 2 are used; <= 0: the hardware's;
/// bit-identical results on any count). Throws std::runtime_error on a rank-deficient network.
LinearInsNetworkResult SolveLinearInsNetwork(const LinearInsNetworkOptions& options, bool gravity_covariance,
                                             int checkpoint_interval, bool keep_gravity_estimate = false,
                                             int num_threads = 1, double pivot_tolerance = 1e-12);

/// The same network solved from its whitened observation equations by a streaming block
/// Householder QR (square-root information form: A = RᵀR, R block upper-bidiagonal, built block by
/// block as [R_j carried; rows of block j] = Q [R_jj R_{j,j+1}; 0 R_{j+1}]), then back substitution
/// and the Takahashi recursion on R for the δg covariances. The normal matrix is never formed, so
/// round-off acts on the condition number of the equations, the square root of the normal
/// matrix's: the long 200 Hz chains whose normal-equation Cholesky breaks down (Table 2 case 3)
/// stay resolvable. One-way order (one thread), about 2-3x the Cholesky's time. Rank test:
/// R_kk² / A_kk (the same quantity as the Cholesky's relative pivot, computed without squaring)
/// below `pivot_tolerance` throws std::runtime_error naming the block and unknown. With
/// checkpoint_interval k > 0 one carry per k blocks is kept and segments are refactored
/// backwards (memory O((n/k + k) b²)); 0 keeps the whole factor (2 n b² doubles).
LinearInsNetworkResult SolveLinearInsNetworkQr(const LinearInsNetworkOptions& options, bool gravity_covariance,
                                               int checkpoint_interval, bool keep_gravity_estimate = false,
                                               double pivot_tolerance = 1e-20);

/// Cross-over ties (XOVER) of a survey flown as `lines` East-West lines then `cross_lines`
/// North-South lines of equal duration: every EW line crosses every NS line once, half-way
/// between consecutive crossings, and the three δg unknowns of the two epochs are tied with
/// standard deviation sigma_xover_mps2. The tie values are the truth's differences (the
/// noise-free network stays consistent, so its solution is still the truth).
std::vector<Tie> LinearInsCrossoverTies(const LinearInsNetworkOptions& options, int lines, int cross_lines,
                                        double sigma_xover_mps2);

struct CrossoverNetworkResult {
  NetworkSize size;
  long long crossings = 0;
  long long ties = 0;
  double factor_seconds = 0.0;
  double factor_bytes = 0.0;
  TiedSolveSummary pcg;
  double max_abs_error = 0.0;   ///< over every unknown, against the truth
  double gravity_rmse = 0.0;    ///< [m/s²]
  double total_seconds = 0.0;
};

/// The network of `options` plus the cross-over ties above, solved by conjugate gradients
/// preconditioned with the stored banded factor (crossover_pcg.h). Memory: the whole factor,
/// 2 n b² doubles (leap-frog b = 36: 20.7 kB per pair of epochs).
CrossoverNetworkResult SolveLinearInsNetworkWithCrossovers(const LinearInsNetworkOptions& options, int lines,
                                                           int cross_lines, double sigma_xover_mps2,
                                                           const TiedSolveOptions& pcg = TiedSolveOptions());

}  // namespace indoorloc::network
