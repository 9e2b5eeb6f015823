#include "indoorloc/core/log_weights.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

namespace indoorloc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(LogWeights, LogSumExpMatchesDirectSumAndSurvivesUnderflow) {
  Eigen::VectorXd lw(3);
  lw << std::log(0.2), std::log(0.3), std::log(0.5);
  EXPECT_NEAR(LogSumExp(lw), 0.0, 1e-15);
  // exp(-1000) underflows to 0 in linear space; log-sum-exp stays exact.
  lw << -1000.0, -1000.0, -kInf;
  EXPECT_NEAR(LogSumExp(lw), -1000.0 + std::log(2.0), 1e-12);
  EXPECT_EQ(LogSumExp(Eigen::VectorXd::Constant(2, -kInf)), -kInf);
  EXPECT_EQ(LogSumExp(Eigen::VectorXd()), -kInf);
}

TEST(LogWeights, RejectsNanAndPlusInf) {
  Eigen::VectorXd lw(2);
  lw << 0.0, std::nan("");
  EXPECT_THROW(LogSumExp(lw), std::invalid_argument);
  lw << 0.0, kInf;
  EXPECT_THROW(EffectiveSampleSize(lw), std::invalid_argument);
}

TEST(LogWeights, NormalizeReturnsLogNormalizer) {
  Eigen::VectorXd lw(4);
  lw << 1.0, 2.0, 3.0, -kInf;
  const double expected = std::log(std::exp(1.0) + std::exp(2.0) + std::exp(3.0));
  EXPECT_NEAR(NormalizeLogWeights(lw), expected, 1e-14);
  EXPECT_NEAR(lw.array().exp().sum(), 1.0, 1e-14);
  EXPECT_EQ(lw[3], -kInf);
  Eigen::VectorXd dead = Eigen::VectorXd::Constant(3, -kInf);
  EXPECT_THROW(NormalizeLogWeights(dead), std::invalid_argument);
  Eigen::VectorXd empty;
  EXPECT_THROW(NormalizeLogWeights(empty), std::invalid_argument);
}

TEST(LogWeights, EffectiveSampleSizeBounds) {
  EXPECT_NEAR(EffectiveSampleSize(Eigen::VectorXd::Constant(50, -7.0)), 50.0, 1e-9);
  Eigen::VectorXd one_hot = Eigen::VectorXd::Constant(50, -kInf);
  one_hot[17] = 3.0;
  EXPECT_NEAR(EffectiveSampleSize(one_hot), 1.0, 1e-12);
  Eigen::VectorXd lw(2);
  lw << std::log(0.25), std::log(0.75);
  EXPECT_NEAR(EffectiveSampleSize(lw), 1.0 / (0.25 * 0.25 + 0.75 * 0.75), 1e-12);
}

TEST(LogWeights, NormalizedWeightsSumToOne) {
  Eigen::VectorXd lw = Eigen::VectorXd::LinSpaced(100, -500.0, -400.0);
  const Eigen::VectorXd w = NormalizedWeights(lw);
  EXPECT_NEAR(w.sum(), 1.0, 1e-12);
  EXPECT_GT(w[99], w[0]);
}

}  // namespace
}  // namespace indoorloc
