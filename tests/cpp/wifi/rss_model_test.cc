#include "indoorloc/wifi/rss_model.h"

#include <cmath>
#include <limits>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "indoorloc/core/random.h"
#include "test_maps.h"

namespace indoorloc::wifi {
namespace {

RowMatrixXd Scan(const RssModel& model, const Eigen::Vector2d& z, RandomStream& rng) {
  Eigen::VectorXd mean, var;
  int hint = -1;
  model.MeanAndVariance(z, 0, &mean, &var, &hint);
  RowMatrixXd scan(1, mean.size());
  for (Eigen::Index i = 0; i < mean.size(); ++i) scan(0, i) = rng.Normal(mean[i], std::sqrt(var[i]));
  return scan;
}

TEST(RssModel, GradientMatchesNumericalDifferentiation) {
  const RssModel model(testing::LatticeMap());
  RandomStream rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector2d z(rng.Uniform(0.3, 9.7), rng.Uniform(0.3, 9.7));
    const RowMatrixXd scans = Scan(model, Eigen::Vector2d(rng.Uniform(0, 10), rng.Uniform(0, 10)), rng);
    int hint = -1;
    const RssLikelihood at = model.Evaluate(scans, z, 0, &hint);
    const double h = 1e-6;
    for (int axis = 0; axis < 2; ++axis) {
      Eigen::Vector2d dz = Eigen::Vector2d::Zero();
      dz[axis] = h;
      int h1 = hint, h2 = hint;
      const double lp = model.Evaluate(scans, z + dz, 0, &h1).neg_log_likelihood;
      const double lm = model.Evaluate(scans, z - dz, 0, &h2).neg_log_likelihood;
      // Skip the rare case of z within h of a triangle edge (l is only piecewise smooth).
      if (h1 != hint || h2 != hint) continue;
      EXPECT_NEAR(at.gradient[axis], (lp - lm) / (2 * h), 1e-5 * std::max(1.0, std::abs(at.gradient[axis])));
    }
  }
}

TEST(RssModel, NegLogLikelihoodIsTheGaussianDensity) {
  const RssModel model(testing::LatticeMap());
  RandomStream rng(2);
  const Eigen::Vector2d z(3.3, 4.1);
  const RowMatrixXd scan = Scan(model, z, rng);
  Eigen::VectorXd mean, var;
  int hint = -1;
  model.MeanAndVariance(z, 0, &mean, &var, &hint);
  double expected = 0.0;
  for (Eigen::Index i = 0; i < mean.size(); ++i) {
    const double r = scan(0, i) - mean[i];
    expected += 0.5 * std::log(2 * M_PI * var[i]) + 0.5 * r * r / var[i];
  }
  EXPECT_NEAR(model.Evaluate(scan, z, 0, &hint).neg_log_likelihood, expected, 1e-10);
}

TEST(RssModel, FisherInformationMatchesBruteForceExpectation) {
  // I(z) = E[∇l ∇lᵀ] over scans drawn from the model at z (brute-force Monte Carlo).
  const RssModel model(testing::LatticeMap());
  const Eigen::Vector2d z(4.7, 2.9);
  RandomStream rng(3);
  Eigen::Matrix2d mc = Eigen::Matrix2d::Zero();
  const int n = 200000;
  int hint = -1;
  for (int s = 0; s < n; ++s) {
    const Eigen::Vector2d g = model.Evaluate(Scan(model, z, rng), z, 0, &hint).gradient;
    mc += g * g.transpose() / n;
  }
  const Eigen::Matrix2d fisher = model.FisherInformation(z, 0, &hint);
  EXPECT_LT((mc - fisher).norm() / fisher.norm(), 0.02) << "MC\n" << mc << "\nformula\n" << fisher;
  // Proposition 1: det I >= 0.
  EXPECT_GT(fisher.determinant(), 0.0);
}

TEST(RssModel, CapLimitsEachAccessPointsTerm) {
  RssModelOptions options;
  options.max_term = 2.0;
  const RssModel capped(testing::LatticeMap(), options);
  const RssModel plain(testing::LatticeMap());
  RowMatrixXd scan = RowMatrixXd::Constant(1, 4, -60.0);
  scan(0, 0) = 0.0;  // absurd reading of AP 0
  int h1 = -1, h2 = -1;
  const Eigen::Vector2d z(5, 5);
  EXPECT_LT(capped.Evaluate(scan, z, 0, &h1).neg_log_likelihood,
            plain.Evaluate(scan, z, 0, &h2).neg_log_likelihood);
  EXPECT_THROW(plain.Evaluate(RowMatrixXd::Zero(1, 3), z, 0, &h1), std::invalid_argument);
  options.max_term = -1;
  EXPECT_THROW(RssModel(testing::LatticeMap(), options), std::invalid_argument);
}

// Evaluate interpolates only the APs off their background in z's triangle; it must give what
// the every-AP reference gives (to rounding) everywhere, inside and outside the hull, with
// heard and not-heard readings, one or several scans, with and without the cap.
TEST(RssModel, SparseEvaluateMatchesEveryAccessPoint) {
  for (const double cap : {std::numeric_limits<double>::infinity(), 3.0}) {
    RssModelOptions options;
    options.max_term = cap;
    const RssModel model(testing::PartlyHeardMap(), options);
    RandomStream rng(11);
    for (int trial = 0; trial < 200; ++trial) {
      const Eigen::Vector2d truth(rng.Uniform(0, 30), rng.Uniform(0, 20));
      const int n = trial % 3 + 1;
      RowMatrixXd scans(n, model.num_access_points());
      for (int s = 0; s < n; ++s) scans.row(s) = Scan(model, truth, rng);
      for (Eigen::Index a = 0; a < scans.cols(); ++a) {  // not heard below -80 dBm, as in the map
        for (int s = 0; s < n; ++s) scans(s, a) = scans(s, a) > -80.0 ? scans(s, a) : -105.0;
      }
      const Eigen::Vector2d z(rng.Uniform(-3, 33), rng.Uniform(-3, 23));
      int h1 = -1, h2 = -1;
      const RssLikelihood fast = model.Evaluate(scans, z, 0, &h1);
      const RssLikelihood every = model.EvaluateEveryAccessPoint(scans, z, 0, &h2);
      const double l = std::abs(every.neg_log_likelihood);
      EXPECT_NEAR(fast.neg_log_likelihood, every.neg_log_likelihood, 1e-12 * std::max(1.0, l));
      EXPECT_LT((fast.gradient - every.gradient).norm(), 1e-10 * std::max(1.0, every.gradient.norm()));
      EXPECT_LT((fast.fisher - every.fisher).norm(), 1e-10 * std::max(1.0, every.fisher.norm()));
      EXPECT_EQ(fast.inside, every.inside);
      EXPECT_EQ(fast.evaluated_at_m, every.evaluated_at_m);
    }
  }
}

TEST(RssModel, ReferencePointScoresMatchEvaluateAtThePoints) {
  RssModelOptions options;
  options.max_term = 4.0;
  const RssModel model(testing::PartlyHeardMap(30, 3), options);
  RandomStream rng(5);
  RowMatrixXd scans(2, model.num_access_points());
  scans.row(0) = Scan(model, Eigen::Vector2d(12, 7), rng);
  scans.row(1) = Scan(model, Eigen::Vector2d(12.5, 7), rng);
  scans = (scans.array() > -80.0).select(scans, -105.0);
  Eigen::VectorXd l;
  model.ReferencePointNegLogLikelihood(scans, 0, &l);
  ASSERT_EQ(l.size(), model.map().num_points());
  for (int i = 0; i < model.map().num_points(); ++i) {
    int hint = -1;
    const double every =
        model.EvaluateEveryAccessPoint(scans, model.map().positions_m().row(i).transpose(), 0, &hint).neg_log_likelihood;
    EXPECT_NEAR(l[i], every, 1e-12 * std::max(1.0, std::abs(every)));
  }
}

}  // namespace
}  // namespace indoorloc::wifi
