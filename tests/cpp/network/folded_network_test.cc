#include "indoorloc/network/folded_network.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include "same_gravity.h"

namespace indoorloc::network {
namespace {

LinearInsNetworkOptions Small(Discretisation rule, double duration_s) {
  LinearInsNetworkOptions o;
  o.imu_rate_hz = 50.0;
  o.gps_rate_hz = 2.0;
  o.duration_s = duration_s;
  o.rule = rule;
  return o;
}

// The dense normal matrix of a band given by `assemble` (n blocks of b) in the original order.
void DenseBand(int n, int b, const BlockRowAssembler& assemble, Eigen::MatrixXd* A, Eigen::VectorXd* rhs) {
  A->setZero(static_cast<Eigen::Index>(n) * b, static_cast<Eigen::Index>(n) * b);
  rhs->setZero(static_cast<Eigen::Index>(n) * b);
  Eigen::MatrixXd D(b, b), L(b, b);
  Eigen::VectorXd r(b);
  for (int j = 0; j < n; ++j) {
    D.setZero();
    L.setZero();
    r.setZero();
    assemble(j, &D, &L, &r);
    A->block(j * b, j * b, b, b) += D;
    rhs->segment(j * b, b) += r;
    if (j > 0) {
      A->block(j * b, (j - 1) * b, b, b) += L;
      A->block((j - 1) * b, j * b, b, b) += L.transpose();
    }
  }
}

void AddTie(const Tie& t, Eigen::MatrixXd* A, Eigen::VectorXd* rhs) {
  (*A)(t.a, t.a) += t.weight;
  (*A)(t.b, t.b) += t.weight;
  (*A)(t.a, t.b) -= t.weight;
  (*A)(t.b, t.a) -= t.weight;
  (*rhs)[t.a] += t.weight * t.value;
  (*rhs)[t.b] -= t.weight * t.value;
}

TEST(FoldedOrdering, BandCouplingsAndMirrorsStayWithinAdjacentSuperBlocks) {
  for (int n : {1, 2, 5, 6, 51, 52}) {
    const FoldedOrdering ord(n, 3);
    EXPECT_EQ(ord.num_blocks(), (n + 1) / 2);
    std::vector<int> seen(static_cast<size_t>(ord.num_blocks()) * 2, 0);
    for (int j = 0; j < n; ++j) {
      const int k = ord.SuperBlock(j), s = ord.Slot(j);
      ASSERT_GE(k, 0);
      ASSERT_LT(k, ord.num_blocks());
      EXPECT_EQ(ord.BaseBlock(k, s), j);
      ++seen[static_cast<size_t>(2 * k + s)];
      if (j + 1 < n) {
        EXPECT_LE(std::abs(ord.SuperBlock(j + 1) - k), 1) << "n " << n << " j " << j;
      }
      EXPECT_EQ(ord.SuperBlock(n - 1 - j), k) << "mirror, n " << n << " j " << j;
    }
    for (size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], (ord.padded() && i == 1) ? 0 : 1);
    if (ord.padded()) {
      EXPECT_EQ(ord.BaseBlock(0, 1), -1);
    }
  }
}

// The folded tied solve equals the dense solve of the same tied network in the original order,
// and its selected inversion equals the dense inverse. Tie values are random, so the solution is
// NOT the truth: the comparison is not trivially satisfied.
TEST(FoldedNetwork, FoldedTiedSolveEqualsTheDenseReference) {
  struct Case {
    Discretisation rule;
    double duration_s;
  };
  // Leap-frog: 102 epochs = 51 pair-blocks (odd, padded), 104 = 52 (even). Trapezoidal: 101
  // epochs (odd), 102 (even).
  for (const Case c : {Case{Discretisation::kLeapFrog, 2.0}, Case{Discretisation::kLeapFrog, 2.04},
                       Case{Discretisation::kTrapezoidal, 2.0}, Case{Discretisation::kTrapezoidal, 2.02}}) {
    const LinearInsNetworkOptions o = Small(c.rule, c.duration_s);
    const NetworkSize size = LinearInsNetworkSize(o);
    const long long E = size.imu_epochs;
    const int n = size.num_blocks, b = size.block_size;
    const FoldedOrdering ord(n, b);
    std::mt19937 rng(7);
    std::normal_distribution<double> normal(0.0, 1e-3);
    std::vector<Tie> ties;
    for (long long t = 0; t + t < E - 1; t += 3) {
      for (int comp = 15; comp < 18; ++comp) ties.push_back(Tie{t * 18 + comp, (E - 1 - t) * 18 + comp, 1e8, normal(rng)});
      if (E - 2 - t > t) {  // the mirror's neighbour: same or adjacent super-block, both orientations
        ties.push_back(Tie{(E - 2 - t) * 18 + 17, t * 18 + 17, 1e8, normal(rng)});
        ties.push_back(Tie{t * 18 + 16, (E - 2 - t) * 18 + 16, 1e8, normal(rng)});
      }
    }
    const BlockRowAssembler base = LinearInsAssembler(o);
    Eigen::MatrixXd A;
    Eigen::VectorXd rhs;
    DenseBand(n, b, base, &A, &rhs);
    for (const Tie& t : ties) AddTie(t, &A, &rhs);
    const Eigen::LLT<Eigen::MatrixXd> llt(A);
    ASSERT_EQ(llt.info(), Eigen::Success);
    const Eigen::VectorXd x_dense = llt.solve(rhs);
    const Eigen::MatrixXd inverse = llt.solve(Eigen::MatrixXd::Identity(A.rows(), A.cols()));

    BlockTridiagonalOptions so;
    for (int s = 0; s < 2 * b; ++s)
      if (s % 18 >= 15) so.selected.push_back(s);
    const BlockTridiagonalSolution sol =
        SolveBlockTridiagonal(ord.num_blocks(), ord.block_size(), FoldedAssembler(ord, base, ties), so);
    double max_dx = 0.0, max_rel_var = 0.0;
    for (long long u = 0; u < A.rows(); ++u) {
      const long long f = ord.FoldedIndex(u);
      max_dx = std::max(max_dx, std::abs(sol.x[f] - x_dense[u]) / std::max(1.0, std::abs(x_dense[u])));
      if (u % 18 >= 15) {
        const long long k = f / ord.block_size();
        const long long within = f % ord.block_size();
        const int sel = static_cast<int>((within / 18) * 3 + (within % 18 - 15));
        const double v = sol.covariance[static_cast<size_t>(k)](sel, sel);
        max_rel_var = std::max(max_rel_var, std::abs(v - inverse(u, u)) / inverse(u, u));
      }
    }
    EXPECT_LT(max_dx, 1e-7) << "rule " << static_cast<int>(c.rule) << " E " << E;
    EXPECT_LT(max_rel_var, 1e-7) << "rule " << static_cast<int>(c.rule) << " E " << E;
    // The ties moved the solution away from the untied one (the test is not vacuous).
    const Eigen::VectorXd x_untied = SolveBlockTridiagonal(n, b, base).x;
    EXPECT_GT((x_untied - x_dense).cwiseAbs().maxCoeff(), 1e-6);
  }
}

TEST(FoldedNetwork, NoiseFreeTiedNetworkReturnsTheTruthWithDenseVariances) {
  for (Discretisation rule : {Discretisation::kLeapFrog, Discretisation::kTrapezoidal}) {
    LinearInsNetworkOptions o = Small(rule, 2.0);
    o.gupt_end_epochs = 0;  // the GUPTs come from the layout
    const NetworkSize size = LinearInsNetworkSize(o);
    const long long E = size.imu_epochs;
    const RepeatedPassLayout layout = MakeRepeatedPassLayout(o, E - 5, 7, 1e-5, 1e-5);
    FoldedNetworkOptions fo;
    fo.keep_gravity_estimate = true;
    fo.checkpoint_interval = 0;
    const FoldedNetworkResult r = SolveFoldedLinearInsNetwork(o, layout.ties, layout.gupts, fo);
    EXPECT_LT(r.max_abs_error, 1e-6) << r.BriefReport();
    EXPECT_LT(r.gravity_rmse, 1e-9);
    EXPECT_EQ(r.ties, E - 5);
    EXPECT_EQ(r.gupts, 7);
    EXPECT_EQ(r.equations, size.equations + E - 5 + 7);
    EXPECT_EQ(r.folded_block_size, 2 * size.block_size);
    // Dense reference of the same tied network (independent construction, original order).
    Eigen::MatrixXd A;
    Eigen::VectorXd rhs;
    DenseBand(size.num_blocks, size.block_size, LinearInsAssembler(o), &A, &rhs);
    for (const GravityTie& t : layout.ties) {
      const long long c = 15 + t.component;
      AddTie(Tie{t.epoch_a * 18 + c, t.epoch_b * 18 + c, 1.0 / (t.sigma_mps2 * t.sigma_mps2), 0.0}, &A, &rhs);
    }
    for (const GravityUpdate& u : layout.gupts) A(u.epoch * 18 + 15 + u.component, u.epoch * 18 + 15 + u.component) += 1e10;
    const Eigen::MatrixXd inverse = A.llt().solve(Eigen::MatrixXd::Identity(A.rows(), A.cols()));
    double max_rel = 0.0;
    for (long long e = 0; e < E; ++e)
      for (int c = 0; c < 3; ++c) {
        const double s = std::sqrt(inverse(e * 18 + 15 + c, e * 18 + 15 + c));
        max_rel = std::max(max_rel, std::abs(r.gravity_sigma(e, c) - s) / s);
      }
    EXPECT_LT(max_rel, 1e-7);
    // Checkpointed: the same numbers.
    fo.checkpoint_interval = 4;
    const FoldedNetworkResult c = SolveFoldedLinearInsNetwork(o, layout.ties, layout.gupts, fo);
    testing::ExpectSameGravity(c, r);
  }
}

TEST(FoldedNetwork, Case4CountsMatchThePapersTable2) {
  LinearInsNetworkOptions o;
  o.imu_rate_hz = 50.0;
  o.gps_rate_hz = 2.0;
  o.duration_s = 565049.0 / 50.0;  // 565,049 intervals: 565,050 epochs (paper: 50 Hz x 11,301 s)
  o.gupt_end_epochs = 0;
  const NetworkSize s = LinearInsNetworkSize(o);
  EXPECT_EQ(s.imu_epochs, 565050);
  EXPECT_EQ(s.gps_epochs, 22602);
  EXPECT_EQ(s.unknowns, 10170900);  // paper N_par
  EXPECT_EQ(s.num_blocks, 282525);  // odd: the middle pair-block sits alone in super-block 0
  const RepeatedPassLayout layout = MakeRepeatedPassLayout(o, 332150, 1907, 1e-5, 1e-5);
  ASSERT_EQ(layout.ties.size(), 332150u);
  ASSERT_EQ(layout.gupts.size(), 1907u);
  long long mirror = 0;
  for (const GravityTie& t : layout.ties) mirror += (t.epoch_a + t.epoch_b == 565049);
  EXPECT_EQ(mirror, 282525);  // every mirror pair, plus 49,625 ties to the mirror's neighbour
  // 18 (E - 2) leap-frog + 3 N_GPS + 36 prior + XOVER + GUPT = the paper's N*_eq.
  EXPECT_EQ(s.equations + 332150 + 1907, 10572763);
  const FoldedOrdering ord(s.num_blocks, s.block_size);
  EXPECT_EQ(ord.num_blocks(), 141263);
  EXPECT_EQ(ord.block_size(), 72);
  EXPECT_NO_THROW(FoldedLinearInsAssembler(o, layout.ties, layout.gupts));  // every tie folds
}

TEST(FoldedNetwork, BadInputsNameTheArgument) {
  LinearInsNetworkOptions o = Small(Discretisation::kLeapFrog, 2.0);
  const long long E = LinearInsNetworkSize(o).imu_epochs;
  auto message = [&](const std::vector<GravityTie>& ties, const std::vector<GravityUpdate>& gupts) {
    try {
      SolveFoldedLinearInsNetwork(o, ties, gupts);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_NE(message({GravityTie{0, E, 2, 1e-5}}, {}).find("'ties': tie 0 joins epochs 0 and 102: outside"),
            std::string::npos)
      << message({GravityTie{0, E, 2, 1e-5}}, {});
  EXPECT_NE(message({GravityTie{0, E - 1, 2, 1e-5}, GravityTie{1, E - 2, 2, std::nan("")}}, {}).find(
                "'ties': tie 1: sigma_mps2 must be finite"),
            std::string::npos);
  EXPECT_NE(message({GravityTie{3, 3, 2, 1e-5}}, {}).find("to itself"), std::string::npos);
  EXPECT_NE(message({GravityTie{0, E - 1, 3, 1e-5}}, {}).find("component"), std::string::npos);
  EXPECT_NE(message({GravityTie{0, E / 2, 2, 1e-5}}, {}).find("not adjacent"), std::string::npos);
  EXPECT_NE(message({}, {GravityUpdate{-1, 2, 1e-5}}).find("'gupts': GUPT 0 at epoch -1"), std::string::npos);
  EXPECT_NE(message({}, {GravityUpdate{5, 2, 0.0}}).find("'gupts'"), std::string::npos);
  EXPECT_THROW(MakeRepeatedPassLayout(o, E, 0, 1e-5, 1e-5), std::invalid_argument);  // > P + Q
  EXPECT_THROW(MakeRepeatedPassLayout(o, 10, 0, std::nan(""), 1e-5), std::invalid_argument);
  FoldedNetworkOptions fo;
  fo.checkpoint_interval = -1;
  EXPECT_THROW(SolveFoldedLinearInsNetwork(o, {}, {}, fo), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::network
