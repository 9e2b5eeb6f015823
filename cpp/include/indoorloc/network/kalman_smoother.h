// State-space approach (SSA) baseline of paper 003: an error-state extended Kalman filter with the
// same state, model and noise densities as the network adjustment (network_adjustment.h), and a
// Rauch-Tung-Striebel smoother over its error states. Cross-overs (XOVER) cannot enter a
// sequential filter: they tie epochs far apart in time (the paper's argument for NA).
//
// Mechanisation from epoch k to k+1 (trapezoidal, the same rule as the NA's trapezoidal option):
//   R[k+1] = Exp(-ω_ie δt) R[k] Exp((ω[k] + ω[k+1]) / 2 - o) δt)
//   a[k] = R[k] (f[k] - a) - 2 ω_ie × v[k] + g(h[k], δg),   v[k+1] = v[k] + δt (a[k] + a[k+1]) / 2
//   r[k+1] = r[k] + δt (v[k] + v[k+1]) / 2;  δg constant, biases constant (random walks) or
//   b[k+1] = φ b[k] (Gauss-Markov, NetworkOptions::*_correlation_time_s).
// Error state δx = (δr, δv, ε, δa, δo, δδg) (16), R_true = Exp(ε) R̂:
//   δṙ = δv,  δv̇ = -[R̂(f - a)]× ε - R̂ δa - 2 [ω_ie]× δv - e_up (γ'(h) δh + δδg),
//   ε̇ = -ω_ie × ε - R̂ δo;  Φ = I + F δt + (F δt)² / 2,
//   Q = δt diag(0, N_a² I, N_ω² I, q_a² I, q_o² I, q_g²)  (same densities as NetworkOptions).
// Updates: CUPT (position, extrapolated with v over the time since the last epoch), ZUPT, GUPT
// (Joseph form). Smoother: with C_k = P⁺_k Φᵀ (P⁻_{k+1})⁻¹ and u_{k+1} the error-state correction
// the updates applied at k+1, δ_k = C_k (δ_{k+1} + u_{k+1}), δ_N = 0, x_k^s = x_k^+ ⊞ δ_k.
// Memory: one 16 x 16 gain per epoch.
#pragma once

#include <string>

#include <Eigen/Core>

#include "indoorloc/network/network_adjustment.h"

namespace indoorloc::network {

struct KalmanSmootherOptions {
  double init_sigma_position_m = 0.05;
  double init_sigma_velocity_mps = 0.01;
  double init_sigma_level_rad = 1e-3;    ///< roll, pitch (about East, North)
  double init_sigma_heading_rad = 1e-2;  ///< about Up
  double init_sigma_acc_bias_mps2 = 1e-3;
  double init_sigma_gyro_bias_radps = 1e-5;
  double init_sigma_gravity_mps2 = 5e-4;  ///< 50 mGal
  bool smooth = true;                     ///< run the RTS smoother (else: filter output)
  bool IsValid(std::string* error) const;
};

struct KalmanSmootherSummary {
  int num_epochs = 0;
  int num_updates = 0;
  int num_xover_ignored = 0;   ///< XOVER rows in the observations (not usable by a filter)
  double seconds_filter = 0.0;
  double seconds_smoother = 0.0;
  std::string BriefReport() const;
};

/// Runs the filter (and smoother) over `observations` starting from row 0 of `initial` (all
/// other rows are ignored). The model constants and noise densities come from `model`
/// (discretisation and solver fields are not used). Returns all epochs; `filtered` (optional)
/// receives the forward filter's states.
NetworkState RunKalmanSmoother(const NetworkObservations& observations, const NetworkState& initial,
                               const NetworkOptions& model, const KalmanSmootherOptions& options,
                               KalmanSmootherSummary* summary = nullptr, NetworkState* filtered = nullptr);

}  // namespace indoorloc::network
