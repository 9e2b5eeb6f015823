#include "indoorloc/core/resampling.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "indoorloc/core/log_weights.h"

namespace indoorloc {
namespace {

constexpr ResamplingScheme kSchemes[] = {ResamplingScheme::kMultinomial,
                                         ResamplingScheme::kStratified,
                                         ResamplingScheme::kSystematic,
                                         ResamplingScheme::kResidual};

class ResamplingSchemeTest : public ::testing::TestWithParam<ResamplingScheme> {};

// Unbiasedness: over R independent resamplings, the mean offspring count of particle i is
// N_out * w_i. Each count has variance at most N_out w_i (1 - w_i) (multinomial, the worst
// scheme), so the mean over R runs is within 5 standard errors with overwhelming probability.
TEST_P(ResamplingSchemeTest, MeanOffspringCountIsNTimesWeight) {
  const int n = 12;
  Eigen::VectorXd lw(n);
  for (int i = 0; i < n; ++i) lw[i] = 0.3 * i - 0.02 * i * i;  // uneven weights
  lw[5] = -std::numeric_limits<double>::infinity();            // one weight zero
  const Eigen::VectorXd w = NormalizedWeights(lw);
  const int runs = 20000;
  std::vector<double> mean_count(n, 0.0);
  RandomStream rng(77);
  std::vector<int> ancestors;
  for (int r = 0; r < runs; ++r) {
    Resample(lw, GetParam(), rng, &ancestors);
    ASSERT_EQ(static_cast<int>(ancestors.size()), n);
    ASSERT_TRUE(std::is_sorted(ancestors.begin(), ancestors.end()));
    for (int a : ancestors) {
      ASSERT_GE(a, 0);
      ASSERT_LT(a, n);
      ASSERT_NE(a, 5) << "a zero-weight particle was drawn";
      mean_count[a] += 1.0 / runs;
    }
  }
  for (int i = 0; i < n; ++i) {
    const double expected = n * w[i];
    const double se = std::sqrt(n * w[i] * (1.0 - w[i]) / runs);
    EXPECT_NEAR(mean_count[i], expected, 5 * se + 1e-12) << ToString(GetParam()) << " i=" << i;
  }
}

TEST_P(ResamplingSchemeTest, DegenerateAndOutputSize) {
  Eigen::VectorXd lw = Eigen::VectorXd::Constant(10, -std::numeric_limits<double>::infinity());
  lw[3] = -5000.0;  // the only particle with weight, far below exp() range
  RandomStream rng(1);
  const std::vector<int> a = Resample(lw, GetParam(), rng, 25);
  ASSERT_EQ(a.size(), 25u);
  for (int x : a) EXPECT_EQ(x, 3);
  EXPECT_TRUE(Resample(lw, GetParam(), rng, 0).empty());
}

TEST_P(ResamplingSchemeTest, SameSeedSameAncestors) {
  Eigen::VectorXd lw = Eigen::VectorXd::LinSpaced(1000, -3.0, 0.0);
  RandomStream a(5), b(5);
  EXPECT_EQ(Resample(lw, GetParam(), a), Resample(lw, GetParam(), b));
}

INSTANTIATE_TEST_SUITE_P(AllSchemes, ResamplingSchemeTest, ::testing::ValuesIn(kSchemes),
                         [](const ::testing::TestParamInfo<ResamplingScheme>& scheme_info) {
                           return std::string(ToString(scheme_info.param));
                         });

TEST(Resampling, LowVarianceSchemesKeepCountsWithinOneOfExpectation) {
  // Systematic and residual-free schemes put floor(N w_i) or ceil(N w_i) copies for systematic.
  Eigen::VectorXd lw = Eigen::VectorXd::LinSpaced(50, -2.0, 1.0);
  const Eigen::VectorXd w = NormalizedWeights(lw);
  RandomStream rng(3);
  for (int r = 0; r < 200; ++r) {
    std::vector<int> counts(50, 0);
    for (int a : Resample(lw, ResamplingScheme::kSystematic, rng)) ++counts[a];
    for (int i = 0; i < 50; ++i) {
      EXPECT_GE(counts[i], std::floor(50 * w[i]) - 1e-9);
      EXPECT_LE(counts[i], std::ceil(50 * w[i]) + 1e-9);
    }
  }
}

TEST(Resampling, BadInputGivesClearErrors) {
  RandomStream rng(0);
  std::vector<int> out;
  EXPECT_THROW(Resample(Eigen::VectorXd(), ResamplingScheme::kSystematic, rng, &out),
               std::invalid_argument);
  Eigen::VectorXd lw(3);
  lw << 0.0, std::nan(""), 1.0;
  try {
    Resample(lw, ResamplingScheme::kSystematic, rng, &out);
    FAIL() << "NaN accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "indoorloc: argument 'log_weights': entry 1 is NaN");
  }
  EXPECT_THROW(ParseResamplingScheme("bootstrap"), std::invalid_argument);
  EXPECT_EQ(ParseResamplingScheme("residual"), ResamplingScheme::kResidual);
}

TEST(ResampleIfNeeded, ResamplesOnlyBelowThreshold) {
  RandomStream rng(8);
  std::vector<int> ancestors;
  ResamplingOptions options;
  options.ess_threshold = 0.5;

  Eigen::VectorXd even = Eigen::VectorXd::Constant(100, -2.0);
  ResamplingSummary s = ResampleIfNeeded(even, options, rng, &ancestors);
  EXPECT_FALSE(s.resampled);
  EXPECT_NEAR(s.ess_before, 100.0, 1e-9);
  EXPECT_NEAR(s.log_normalizer, -2.0 + std::log(100.0), 1e-12);
  EXPECT_EQ(ancestors.front(), 0);
  EXPECT_EQ(ancestors.back(), 99);
  EXPECT_NEAR(even.array().exp().sum(), 1.0, 1e-12);

  Eigen::VectorXd skewed = Eigen::VectorXd::LinSpaced(100, -50.0, 0.0);
  s = ResampleIfNeeded(skewed, options, rng, &ancestors);
  EXPECT_TRUE(s.resampled);
  EXPECT_LT(s.ess_before, 50.0);
  EXPECT_LT(s.num_unique_ancestors, 100);
  EXPECT_NEAR(skewed[0], -std::log(100.0), 1e-12);
  EXPECT_FALSE(s.BriefReport().empty());

  options.ess_threshold = 1.5;
  EXPECT_THROW(ResampleIfNeeded(skewed, options, rng, &ancestors), std::invalid_argument);
}

// Issue 17: num_out = -2 silently drew N samples; only -1 means "as many as there are weights".
TEST(Resample, NumOutBelowMinusOneIsRejected) {
  RandomStream rng(3);
  const Eigen::VectorXd lw = Eigen::VectorXd::Zero(5);
  EXPECT_EQ(Resample(lw, ResamplingScheme::kSystematic, rng, -1).size(), 5u);
  EXPECT_EQ(Resample(lw, ResamplingScheme::kSystematic, rng, 0).size(), 0u);
  try {
    Resample(lw, ResamplingScheme::kSystematic, rng, -2);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'num_out'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("got -2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace indoorloc
