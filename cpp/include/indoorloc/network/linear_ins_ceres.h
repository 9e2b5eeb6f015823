// The linearised INS/GPS network (linear_ins_network.h) solved by Ceres with SuiteSparse: the
// general-purpose sparse least-squares solver the issue names as a peer, on exactly the equations
// the block-tridiagonal solver sees, in the same process. It is a reference (tests check that both
// give the same solution on small networks) and the Ceres column of benchmarks/bench_network_scale.py.
//
// Each dynamic equation (18 rows centred at epoch n, stencil offsets of the discretisation) is one
// residual block r = W^{1/2} (Σ_a J_a x[n + o_a] - l) on the parameter blocks x[n + o_a] (18 each);
// CUPT, the alignment prior and GUPT are residual blocks on one epoch. Starting point x = 0. With
// `one_gauss_newton_step` the trust region starts huge and one iteration is allowed: for a linear
// problem that is the exact solve (Ceres' best case); otherwise Ceres' default Solver::Options.
#pragma once

#include <string>

#include <Eigen/Core>

#include "indoorloc/network/linear_ins_network.h"

namespace indoorloc::network {

struct LinearInsCeresResult {
  NetworkSize size;
  Eigen::MatrixXd x;                 ///< E x 18 solution (δr m, δv m/s, ψ rad, a m/s², ω rad/s, δg m/s²)
  double build_seconds = 0.0;        ///< creating the ceres::Problem
  double solve_seconds = 0.0;        ///< ceres::Solve
  int iterations = 0;                ///< Ceres steps (successful + unsuccessful), not counting iteration 0
  bool converged = false;            ///< Ceres termination CONVERGENCE
  double max_abs_error = 0.0;        ///< max |x - x*| over every unknown (noise-free truth)
  std::string linear_solver;         ///< what Ceres used, e.g. SPARSE_NORMAL_CHOLESKY (SUITE_SPARSE)
  std::string report;                ///< ceres::Solver::Summary::BriefReport()
};

/// Solves the linearised network of `options` with Ceres (single thread). Throws
/// std::invalid_argument on invalid options and std::runtime_error if Ceres fails.
LinearInsCeresResult SolveLinearInsNetworkWithCeres(const LinearInsNetworkOptions& options,
                                                    bool one_gauss_newton_step = false);

}  // namespace indoorloc::network
