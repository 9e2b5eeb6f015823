#include "indoorloc/network/crossover_pcg.h"

#include <cstdint>
#include <stdexcept>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "random_block_system.h"

#include "indoorloc/core/random.h"

namespace indoorloc::network {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

using testing::FromDense;

// `count` ties between an unknown of the first half of `num_unknowns` and one of the second (far
// apart, as cross-overs are), weights in [1, 101), values standard normal; the same seed gives
// the same ties.
std::vector<Tie> FarApartTies(int num_unknowns, int count, std::uint64_t seed) {
  RandomStream rng(seed);
  const int half = num_unknowns / 2;
  std::vector<Tie> ties;
  for (int k = 0; k < count; ++k) {
    Tie t;
    t.a = static_cast<long long>(rng.UniformInt(static_cast<std::uint64_t>(half)));
    t.b = half + static_cast<long long>(rng.UniformInt(static_cast<std::uint64_t>(half)));
    t.weight = 100.0 * rng.Uniform01() + 1.0;
    t.value = rng.Normal();
    ties.push_back(t);
  }
  return ties;
}

// The brute-force reference: each tie adds w u uᵀ to the matrix and w v u to the right-hand side
// (u = e_a - e_b: w to A_aa and A_bb, -w to A_ab and A_ba), the dense system solved by Cholesky.
VectorXd DenseTiedSolution(const MatrixXd& A, const VectorXd& rhs, const std::vector<Tie>& ties) {
  MatrixXd tied = A;
  VectorXd tied_rhs = rhs;
  for (const Tie& t : ties) {
    tied(t.a, t.a) += t.weight;
    tied(t.b, t.b) += t.weight;
    tied(t.a, t.b) -= t.weight;
    tied(t.b, t.a) -= t.weight;
    tied_rhs[t.a] += t.weight * t.value;
    tied_rhs[t.b] -= t.weight * t.value;
  }
  return tied.llt().solve(tied_rhs);
}

TEST(CrossoverPcg, MatchesTheDenseTiedSolution) {
  const int n = 30, b = 4;
  const auto [A, rhs] = testing::RandomBlockSystem(n, b, 9);
  const std::vector<Tie> ties = FarApartTies(n * b, 40, 10);
  const BlockTridiagonalFactor f(n, b, FromDense(A, rhs, b));
  const TiedSolution s = SolveWithTies(f, rhs, ties);
  EXPECT_EQ(s.summary.termination, Termination::kConverged) << s.summary.BriefReport();
  EXPECT_LE(s.summary.iterations, 81);  // CG: at most 1 + rank of the tie update, here 40
  EXPECT_LT((s.x - DenseTiedSolution(A, rhs, ties)).cwiseAbs().maxCoeff(), 1e-7);
  // No ties: the band solution, zero iterations.
  EXPECT_EQ(SolveWithTies(f, rhs, {}).summary.iterations, 0);
}

TEST(CrossoverPcg, BadTiesGiveClearErrors) {
  const auto [A, rhs] = testing::RandomBlockSystem(3, 2, 1);
  const BlockTridiagonalFactor f(3, 2, FromDense(A, rhs, 2));
  EXPECT_THROW(SolveWithTies(f, rhs, {Tie{0, 6, 1.0, 0.0}}), std::invalid_argument);  // outside
  EXPECT_THROW(SolveWithTies(f, rhs, {Tie{1, 1, 1.0, 0.0}}), std::invalid_argument);  // a == b
  EXPECT_THROW(SolveWithTies(f, rhs, {Tie{0, 1, -1.0, 0.0}}), std::invalid_argument);  // weight
  EXPECT_THROW(SolveWithTies(f, VectorXd::Zero(5), {}), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::network
