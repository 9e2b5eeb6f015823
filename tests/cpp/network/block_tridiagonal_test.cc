#include "indoorloc/network/block_tridiagonal.h"

#include <cmath>
#include <stdexcept>
#include <string>

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

TEST(BlockTridiagonal, MatchesDenseSolveAndInverseForEveryCheckpointInterval) {
  const int n = 9, b = 4;
  const auto [A, rhs] = testing::RandomBlockSystem(n, b, 3);
  const VectorXd x_dense = A.llt().solve(rhs);
  const MatrixXd inverse = A.inverse();
  BlockTridiagonalOptions o;
  o.selected = {3, 1};
  o.neighbour_covariances = true;
  const BlockTridiagonalSolution reference = SolveBlockTridiagonal(n, b, FromDense(A, rhs, b), o);
  EXPECT_LT((reference.x - x_dense).cwiseAbs().maxCoeff(), 1e-9);
  ASSERT_EQ(reference.covariance.size(), static_cast<size_t>(n));
  ASSERT_EQ(reference.neighbour_covariance.size(), static_cast<size_t>(n - 1));
  for (int i = 0; i < n; ++i) {
    for (int r = 0; r < 2; ++r) {
      for (int c = 0; c < 2; ++c) {
        const int gr = i * b + o.selected[static_cast<size_t>(r)], gc = i * b + o.selected[static_cast<size_t>(c)];
        EXPECT_NEAR(reference.covariance[static_cast<size_t>(i)](r, c), inverse(gr, gc), 1e-10) << "block " << i;
        if (i < n - 1) {
          EXPECT_NEAR(reference.neighbour_covariance[static_cast<size_t>(i)](r, c), inverse(gr + b, gc), 1e-10) << "block " << i;
        }
      }
    }
  }
  EXPECT_EQ(reference.summary.assembler_calls, n);
  for (int interval : {1, 2, 4, 8, 9, 50}) {
    BlockTridiagonalOptions oc = o;
    oc.checkpoint_interval = interval;
    const BlockTridiagonalSolution s = SolveBlockTridiagonal(n, b, FromDense(A, rhs, b), oc);
    // The same operations in the same order: identical results.
    EXPECT_EQ((s.x - reference.x).cwiseAbs().maxCoeff(), 0.0) << "interval " << interval;
    for (int i = 0; i < n; ++i) EXPECT_EQ(s.covariance[static_cast<size_t>(i)], reference.covariance[static_cast<size_t>(i)]);
    // Two chains of 4 blocks (0..3 and 8..5) around the middle block 4: a chain longer than the
    // interval is assembled twice, the middle once.
    EXPECT_EQ(s.summary.assembler_calls, interval >= n / 2 ? n : 2 * (n - 1) + 1) << "interval " << interval;
  }
}

TEST(BlockTridiagonal, TwoThreadsGiveBitIdenticalResultsForEverySize) {
  // The twisted order does not depend on the thread count: the same operations in the same order.
  for (int n : {1, 2, 3, 4, 7, 10}) {
    const int b = 3;
    const auto [A, rhs] = testing::RandomBlockSystem(n, b, 20 + n);
    const MatrixXd inverse = A.inverse();
    for (int interval : {0, 1, 2}) {
      BlockTridiagonalOptions o;
      o.selected = {0, 2};
      o.neighbour_covariances = true;
      o.checkpoint_interval = interval;
      o.num_threads = 1;
      const BlockTridiagonalSolution one = SolveBlockTridiagonal(n, b, FromDense(A, rhs, b), o);
      o.num_threads = 2;
      const BlockTridiagonalSolution two = SolveBlockTridiagonal(n, b, FromDense(A, rhs, b), o);
      EXPECT_LT((one.x - A.llt().solve(rhs)).cwiseAbs().maxCoeff(), 1e-9) << "n " << n;
      EXPECT_EQ(one.x, two.x) << "n " << n << " interval " << interval;
      ASSERT_EQ(two.covariance.size(), static_cast<size_t>(n));
      for (int i = 0; i < n; ++i) {
        EXPECT_EQ(one.covariance[static_cast<size_t>(i)], two.covariance[static_cast<size_t>(i)]);
        EXPECT_NEAR(two.covariance[static_cast<size_t>(i)](1, 0), inverse(i * b + 2, i * b), 1e-10) << "n " << n << " block " << i;
        if (i < n - 1) {
          EXPECT_EQ(one.neighbour_covariance[static_cast<size_t>(i)], two.neighbour_covariance[static_cast<size_t>(i)]);
          EXPECT_NEAR(two.neighbour_covariance[static_cast<size_t>(i)](0, 1), inverse((i + 1) * b, i * b + 2), 1e-10)
              << "n " << n << " block " << i;
        }
      }
    }
  }
}

TEST(BlockTridiagonal, DefectOfTheWholeNetworkShowsAtTheMiddleBlockOnAnyThreadCount) {
  // A direction shared by every block (a datum defect): each chain alone is still positive
  // definite, the defect shows where the two chains meet.
  const int n = 6, b = 2;
  MatrixXd A = MatrixXd::Zero(n * b, n * b);
  for (int i = 0; i < n; ++i) {
    A(i * b + 1, i * b + 1) = 2.0;  // the second unknown of each block is determined
    A(i * b, i * b) += 1.0;         // the first: only differences between neighbours
    if (i > 0) {
      A((i - 1) * b, (i - 1) * b) += 1.0;
      A(i * b, (i - 1) * b) -= 1.0;
      A((i - 1) * b, i * b) -= 1.0;
    }
  }
  A(0, 0) -= 1.0;  // no absolute level: A has the constant vector of first unknowns as null space
  const VectorXd rhs = VectorXd::Ones(n * b);
  for (int threads : {1, 2}) {
    BlockTridiagonalOptions o;
    o.num_threads = threads;
    try {
      SolveBlockTridiagonal(n, b, FromDense(A, rhs, b), o);
      FAIL() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("block 3"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("whole network"), std::string::npos) << e.what();
    }
  }
}

TEST(BlockTridiagonal, SingleBlockAndNoSelection) {
  const auto [A, rhs] = testing::RandomBlockSystem(1, 5, 7);
  const BlockTridiagonalSolution s = SolveBlockTridiagonal(1, 5, FromDense(A, rhs, 5));
  EXPECT_LT((s.x - A.llt().solve(rhs)).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_TRUE(s.covariance.empty());
}

TEST(BlockTridiagonal, RankDeficiencyIsReportedWithItsBlock) {
  const int n = 5, b = 3;
  auto [A, rhs] = testing::RandomBlockSystem(n, b, 11);
  // Block 2 loses one direction entirely (an unobservable parameter): row/column zero.
  A.row(2 * b + 1).setZero();
  A.col(2 * b + 1).setZero();
  try {
    SolveBlockTridiagonal(n, b, FromDense(A, rhs, b));
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("block 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("rank-deficient"), std::string::npos) << e.what();
  }
}

TEST(BlockTridiagonal, BadInputGivesClearErrors) {
  const auto [A, rhs] = testing::RandomBlockSystem(3, 2, 1);
  EXPECT_THROW(SolveBlockTridiagonal(0, 2, FromDense(A, rhs, 2)), std::invalid_argument);
  EXPECT_THROW(SolveBlockTridiagonal(3, 0, FromDense(A, rhs, 2)), std::invalid_argument);
  EXPECT_THROW(SolveBlockTridiagonal(3, 2, BlockRowAssembler()), std::invalid_argument);
  BlockTridiagonalOptions o;
  o.selected = {2};
  EXPECT_THROW(SolveBlockTridiagonal(3, 2, FromDense(A, rhs, 2), o), std::invalid_argument);
  o.selected = {1, 1};
  EXPECT_THROW(SolveBlockTridiagonal(3, 2, FromDense(A, rhs, 2), o), std::invalid_argument);
  o.selected = {};
  o.checkpoint_interval = -1;
  EXPECT_THROW(SolveBlockTridiagonal(3, 2, FromDense(A, rhs, 2), o), std::invalid_argument);
  VectorXd bad = rhs;
  bad[3] = std::nan("");
  EXPECT_THROW(SolveBlockTridiagonal(3, 2, FromDense(A, bad, 2)), std::invalid_argument);
}

TEST(BlockTridiagonalFactor, SolveAndMultiplyMatchDense) {
  const int n = 8, b = 3;
  const auto [A, rhs] = testing::RandomBlockSystem(n, b, 4);
  const BlockTridiagonalFactor f(n, b, FromDense(A, rhs, b));
  EXPECT_LT((f.Solve(rhs) - A.llt().solve(rhs)).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT((f.Multiply(rhs) - A * rhs).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_EQ(f.rhs(), rhs);
}

}  // namespace
}  // namespace indoorloc::network
