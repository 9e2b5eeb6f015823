#include "indoorloc/analog/analog_hmm.h"

#include <cmath>
#include <limits>
#include <map>
#include <memory>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "indoorloc/core/random.h"

namespace indoorloc::analog {
namespace {

// A noisy circle, sampled on several laps: a simple deterministic dynamical system.
RowMatrixXd Circle(int n, double phase, double noise, std::uint64_t seed) {
  RandomStream rng(seed);
  RowMatrixXd x(n, 2);
  for (int t = 0; t < n; ++t) {
    const double a = phase + 0.1 * t;
    x.row(t) << std::cos(a) + noise * rng.Normal(), std::sin(a) + noise * rng.Normal();
  }
  return x;
}

// An analog HMM on a noisy circle catalog of n states (seed 3) with k analogs, observing x only
// with variance 0.01.
AnalogHMM CircleHmm(int n, int k) {
  auto catalog = std::make_shared<Catalog>(std::vector<RowMatrixXd>{Circle(n, 0.0, 0.01, 3)});
  AnalogHmmOptions o;
  o.k = k;
  o.observed = {0};
  o.R = Eigen::MatrixXd::Constant(1, 1, 0.01);
  return AnalogHMM(catalog, o);
}

TEST(Catalog, PairsLagAndStride) {
  RowMatrixXd a(5, 1), b(3, 1);
  a << 0, 1, 2, 3, 4;
  b << 10, 11, 12;
  CatalogOptions o;
  o.lag = 2;
  o.stride = 1;
  const Catalog c({a, b}, o);
  EXPECT_EQ(c.num_states(), 4 + 2);
  EXPECT_EQ(c.dim(), 2);
  EXPECT_EQ(c.states()(0, 0), 1);  // (x_1, x_0)
  EXPECT_EQ(c.states()(0, 1), 0);
  EXPECT_EQ(c.num_analogs(), 3 + 1);
  EXPECT_EQ(c.successors()[0], 1);
  EXPECT_EQ(c.analogs()[3], 4);  // first state of b
  EXPECT_EQ(c.successors()[3], 5);
  RowMatrixXd short_traj(1, 1);
  short_traj << 1;
  EXPECT_THROW(Catalog({short_traj}), std::invalid_argument);
}

TEST(KnnTransitions, MatchBruteForceAndRowsSumToOne) {
  auto catalog = std::make_shared<Catalog>(std::vector<RowMatrixXd>{Circle(400, 0.0, 0.05, 1)});
  const int k = 7;
  const SparseTransitions tr = BuildKnnTransitions(*catalog, k);
  EXPECT_NO_THROW(tr.Validate());
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> nn;
  RowMatrixXd d2;
  RandomStream rng(2);
  RowMatrixXd q(50, 2);
  for (int i = 0; i < 50; ++i) q.row(i) << rng.Uniform(-1.5, 1.5), rng.Uniform(-1.5, 1.5);
  KnnAnalogs(*catalog, q, k, &nn, &d2);
  for (int i = 0; i < 50; ++i) {
    std::vector<double> all;
    for (int a : catalog->analogs()) all.push_back((catalog->states().row(a) - q.row(i)).squaredNorm());
    std::sort(all.begin(), all.end());
    for (int j = 0; j < k; ++j) EXPECT_NEAR(d2(i, j), all[static_cast<size_t>(j)], 1e-12);
  }
}

TEST(KnnTransitions, NarrowerKernelFavoursTheNearestAnalogsSuccessor) {
  auto catalog = std::make_shared<Catalog>(std::vector<RowMatrixXd>{Circle(400, 0.0, 0.05, 1)});
  const SparseTransitions paper = BuildKnnTransitions(*catalog, 7);
  const SparseTransitions narrow = BuildKnnTransitions(*catalog, 7, 0.5);
  for (int i = 0; i < paper.num_states; ++i) {
    const size_t first = static_cast<size_t>(i) * 7u;  // the nearest analog comes first
    EXPECT_EQ(paper.next[first], narrow.next[first]);
    EXPECT_GE(narrow.prob[first], paper.prob[first] - 1e-12) << "state " << i;
  }
  EXPECT_NO_THROW(narrow.Validate());
  EXPECT_THROW(BuildKnnTransitions(*catalog, 7, 0.0), std::invalid_argument);
  EXPECT_THROW(BuildKnnTransitions(*catalog, 7, std::nan("")), std::invalid_argument);
}

TEST(KnnTransitions, IncrementalRuleMapsAStraightLineToItsOwnSuccessors) {
  // A straight line sampled at unit steps: every analog's increment is +1, so from any state the
  // incremental target is the state's own successor, whichever neighbours it has; the catalog
  // rule instead sends state i to i-2 .. i+3 (the successors of its time neighbours).
  RowMatrixXd line(60, 2);
  for (int t = 0; t < 60; ++t) line.row(t) << t, 0.5 * t;
  const Catalog catalog({line});
  const int k = 5;
  const SparseTransitions inc = BuildKnnTransitions(catalog, k, 1.0, SuccessorRule::kIncremental);
  const SparseTransitions cat = BuildKnnTransitions(catalog, k, 1.0, SuccessorRule::kCatalog);
  EXPECT_NO_THROW(inc.Validate());
  int catalog_rule_spread = 0;
  for (int i = 0; i + 1 < inc.num_states; ++i) {
    double to_successor = 0.0;
    for (int j = 0; j < k; ++j) {
      const size_t e = static_cast<size_t>(i) * k + static_cast<size_t>(j);
      if (inc.next[e] == i + 1) to_successor += inc.prob[e];
      else EXPECT_EQ(inc.prob[e], 0.0) << "state " << i << " slot " << j;
      catalog_rule_spread += cat.next[e] != i + 1;
    }
    EXPECT_NEAR(to_successor, 1.0, 1e-12) << "state " << i;
  }
  EXPECT_GT(catalog_rule_spread, 0);
}

TEST(KnnTransitions, IncrementalRuleOnACircleMatchesBruteForce) {
  const Catalog catalog({Circle(300, 0.0, 0.05, 4)});
  const int k = 6;
  const SparseTransitions tr = BuildKnnTransitions(catalog, k, 0.7, SuccessorRule::kIncremental);
  const SparseTransitions base = BuildKnnTransitions(catalog, k, 0.7, SuccessorRule::kCatalog);
  EXPECT_NO_THROW(tr.Validate());
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> nn;
  RowMatrixXd d2;
  KnnAnalogs(catalog, catalog.states(), k, &nn, &d2);
  const RowMatrixXd& s = catalog.states();
  for (int i = 0; i < catalog.num_states(); ++i) {
    std::map<int, double> expected;  // brute-force target -> summed weight
    for (int j = 0; j < k; ++j) {
      const size_t a = static_cast<size_t>(nn(i, j));
      const Eigen::RowVectorXd q = s.row(i) + s.row(catalog.successors()[a]) - s.row(catalog.analogs()[a]);
      Eigen::Index target = 0;
      (s.rowwise() - q).rowwise().squaredNorm().minCoeff(&target);
      expected[static_cast<int>(target)] += base.prob[static_cast<size_t>(i) * k + static_cast<size_t>(j)];
    }
    std::map<int, double> got;
    for (int j = 0; j < k; ++j) {
      const size_t e = static_cast<size_t>(i) * k + static_cast<size_t>(j);
      got[tr.next[e]] += tr.prob[e];
    }
    ASSERT_EQ(got.size(), expected.size()) << "state " << i;
    for (const auto& [target, w] : expected) EXPECT_NEAR(got[target], w, 1e-12) << "state " << i;
  }
}

TEST(AnalogHMM, ReconstructsAHiddenComponentAndHandlesMissingValues) {
  const AnalogHMM hmm = CircleHmm(3000, 8);
  const RowMatrixXd truth = Circle(200, 0.35, 0.0, 4);
  RowMatrixXd obs(200, 1);
  RandomStream rng(5);
  for (int t = 0; t < 200; ++t) obs(t, 0) = (t % 5 == 0) ? truth(t, 0) + 0.1 * rng.Normal() : std::nan("");
  const SmoothingOutput exact = hmm.Smooth(obs, 0);
  const SmoothingOutput beam = hmm.Smooth(obs, 300);
  // The unobserved y = sin is recovered from the dynamics (up to the sign ambiguity the first
  // observation resolves through the direction of motion).
  EXPECT_LT((exact.mean.col(1) - truth.col(1)).norm() / std::sqrt(200.0), 0.2);
  EXPECT_LT((beam.mean - exact.mean).cwiseAbs().maxCoeff(), 0.1);
  EXPECT_TRUE(std::isfinite(exact.log_likelihood));
  const ViterbiResult map = hmm.MapSequence(obs, 300);
  EXPECT_EQ(map.states.size(), 200u);
}

TEST(AnalogHMM, BadInputGivesClearErrors) {
  auto catalog = std::make_shared<Catalog>(std::vector<RowMatrixXd>{Circle(10, 0.0, 0.0, 1)});
  AnalogHmmOptions o;
  o.k = 20;  // more than the 9 analogs
  o.observed = {0};
  o.R = Eigen::MatrixXd::Identity(1, 1);
  EXPECT_THROW(AnalogHMM(catalog, o), std::invalid_argument);
  o.k = std::numeric_limits<int>::max();  // K + 1 overflowed int (UBSan, issue 17)
  EXPECT_THROW(AnalogHMM(catalog, o), std::invalid_argument);
  o.k = 3;
  o.R(0, 0) = -1.0;
  EXPECT_THROW(AnalogHMM(catalog, o), std::invalid_argument);  // R not positive definite
  o.R(0, 0) = 1.0;
  o.k = 0;
  EXPECT_THROW(AnalogHMM(catalog, o), std::invalid_argument);
  o.k = 3;
  const AnalogHMM hmm(catalog, o);
  EXPECT_THROW(hmm.Smooth(RowMatrixXd::Zero(5, 2), 0), std::invalid_argument);  // dimension mismatch
  SmoothOptions so;
  so.beam = 2;
  so.max_dropped_mass = -0.1;
  EXPECT_THROW(hmm.Smooth(RowMatrixXd::Zero(5, 1), so), std::invalid_argument);
  so.max_dropped_mass = 1.0;
  so.initial = Eigen::VectorXd::Ones(3);  // the catalog has 10 states
  EXPECT_THROW(hmm.Smooth(RowMatrixXd::Zero(5, 1), so), std::invalid_argument);
  so.initial = Eigen::VectorXd::Ones(hmm.catalog().num_states());
  so.initial[2] = -1.0;
  EXPECT_THROW(hmm.Smooth(RowMatrixXd::Zero(5, 1), so), std::invalid_argument);
  o.sigma_scale = -1.0;
  EXPECT_THROW(AnalogHMM(catalog, o), std::invalid_argument);
}

TEST(AnalogHMM, InitialPriorIsUsedAndUniformIsTheDefault) {
  const AnalogHMM hmm = CircleHmm(400, 6);
  RowMatrixXd obs = RowMatrixXd::Constant(20, 1, std::nan(""));
  obs(0, 0) = 0.5;  // x = cos = 0.5: two equally likely phases (y = +-0.87) under a uniform prior
  SmoothOptions so;
  const SmoothingOutput uniform = hmm.Smooth(obs, so);
  SmoothOptions given = so;
  given.initial = Eigen::VectorXd::Ones(hmm.catalog().num_states());
  const SmoothingOutput explicit_uniform = hmm.Smooth(obs, given);
  EXPECT_LT((uniform.mean - explicit_uniform.mean).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT(std::abs(uniform.filtering_mean(0, 1)), 0.15);  // the two phases cancel
  // A prior on the upper half (y > 0) picks the phase y = +0.87.
  for (int i = 0; i < hmm.catalog().num_states(); ++i) given.initial[i] = hmm.catalog().states()(i, 1) > 0.0 ? 1.0 : 0.0;
  const SmoothingOutput upper = hmm.Smooth(obs, given);
  EXPECT_NEAR(upper.filtering_mean(0, 1), std::sqrt(0.75), 0.1);
}

}  // namespace
}  // namespace indoorloc::analog
