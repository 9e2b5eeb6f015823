#include "indoorloc/network/linear_ins_ceres.h"

#include <gtest/gtest.h>

namespace indoorloc::network {
namespace {

// Ceres on the same equations must reach the block-tridiagonal solution (and so the truth).
TEST(LinearInsCeres, SameSolutionAsTheBlockTridiagonalSolver) {
  for (Discretisation rule : {Discretisation::kLeapFrog, Discretisation::kTrapezoidal}) {
    LinearInsNetworkOptions o;
    o.imu_rate_hz = 50.0;
    o.duration_s = 10.0;
    o.rule = rule;
    const LinearInsNetworkResult ours = SolveLinearInsNetwork(o, false, 0, true);
    const LinearInsCeresResult ceres = SolveLinearInsNetworkWithCeres(o, true);
    ASSERT_EQ(ceres.x.rows(), ours.size.imu_epochs);
    EXPECT_EQ(ceres.size.unknowns, ours.size.unknowns);
    EXPECT_LT(ceres.max_abs_error, 1e-6) << ceres.report;
    EXPECT_LT((ceres.x.rightCols<3>() - ours.gravity_estimate).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_EQ(ceres.iterations, 1);
    EXPECT_NE(ceres.linear_solver.find("SPARSE_NORMAL_CHOLESKY"), std::string::npos) << ceres.linear_solver;
  }
}

TEST(LinearInsCeres, DefaultSettingsAlsoConvergeToTheTruth) {
  LinearInsNetworkOptions o;
  o.imu_rate_hz = 50.0;
  o.duration_s = 10.0;
  const LinearInsCeresResult r = SolveLinearInsNetworkWithCeres(o, false);
  EXPECT_GE(r.iterations, 1);
  EXPECT_LT(r.max_abs_error, 1e-4) << r.report;
}

TEST(LinearInsCeres, InvalidOptionsAreRejectedBeforeCeresSeesThem) {
  LinearInsNetworkOptions o;
  o.duration_s = -1.0;
  EXPECT_THROW(SolveLinearInsNetworkWithCeres(o), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::network
