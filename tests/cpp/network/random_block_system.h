// Test helpers shared by the block-tridiagonal and cross-over PCG tests: a random symmetric
// positive definite block-tridiagonal system, and an assembler that serves it block row by row.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "indoorloc/core/random.h"
#include "indoorloc/network/block_tridiagonal.h"

namespace indoorloc::network::testing {

/// A random system A x = rhs of n blocks of b unknowns.
struct BlockSystem {
  Eigen::MatrixXd A;
  Eigen::VectorXd rhs;
};

/// A = Jᵀ J + 0.1 I with J block lower-bidiagonal (n blocks of b): symmetric positive definite
/// and block-tridiagonal; rhs standard normal. The same seed gives the same system.
inline BlockSystem RandomBlockSystem(int n, int b, std::uint64_t seed) {
  RandomStream rng(seed);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n * b, n * b);
  for (int i = 0; i < n; ++i)
    for (int r = 0; r < b; ++r)
      for (int c = 0; c < b; ++c) {
        J(i * b + r, i * b + c) = rng.Normal();
        if (i > 0) J(i * b + r, (i - 1) * b + c) = rng.Normal();
      }
  BlockSystem system;
  system.A = J.transpose() * J + 0.1 * Eigen::MatrixXd::Identity(n * b, n * b);
  system.rhs.resize(n * b);
  for (int i = 0; i < n * b; ++i) system.rhs[i] = rng.Normal();
  return system;
}

/// Block row i of a dense matrix A (blocks of b) and of rhs.
inline BlockRowAssembler FromDense(const Eigen::MatrixXd& A, const Eigen::VectorXd& rhs, int b) {
  return [A, rhs, b](int i, Eigen::MatrixXd* diagonal, Eigen::MatrixXd* lower, Eigen::VectorXd* r) {
    *diagonal = A.block(i * b, i * b, b, b);
    if (i > 0) *lower = A.block(i * b, (i - 1) * b, b, b);
    *r = rhs.segment(i * b, b);
  };
}

}  // namespace indoorloc::network::testing
