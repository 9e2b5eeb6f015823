#include "indoorloc/wifi/shared_ap_matcher.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace indoorloc::wifi {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// Sparse random fingerprints: each entry heard with probability `heard` at -95..-30 dBm.
SharedApRowMatrixXd RandomFingerprints(Eigen::Index rows, Eigen::Index aps, double heard, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  SharedApRowMatrixXd x(rows, aps);
  for (Eigen::Index i = 0; i < rows; ++i) {
    for (Eigen::Index j = 0; j < aps; ++j) x(i, j) = unit(rng) < heard ? -95.0 + 65.0 * unit(rng) : kNaN;
  }
  return x;
}

// Eq. (1) of the header written out per pair, straight from the definition.
std::pair<double, double> BruteForce(const SharedApRowMatrixXd& q, Eigen::Index qi, const SharedApRowMatrixXd& r,
                                     Eigen::Index ri, const Eigen::VectorXd& g, double beta) {
  auto f = [beta](double x) { return beta > 0 ? std::exp((x + 40.0) / beta) : 1.0; };
  double shared_w = 0, sq = 0, query_total = 0, ref_only = 0;
  for (Eigen::Index i = 0; i < q.cols(); ++i) {
    const bool a_heard = !std::isnan(q(qi, i)), b_heard = !std::isnan(r(ri, i));
    if (a_heard) query_total += g[i] * f(q(qi, i));
    if (b_heard && !a_heard) ref_only += g[i] * f(r(ri, i));
    if (a_heard && b_heard) {
      const double w = g[i] * f(q(qi, i));
      shared_w += w;
      sq += w * (q(qi, i) - r(ri, i)) * (q(qi, i) - r(ri, i));
    }
  }
  if (!(shared_w > 0)) return {kInf, 1.0};
  return {std::sqrt(sq / shared_w), std::clamp(1.0 - shared_w / (query_total + ref_only), 0.0, 1.0)};
}

Eigen::VectorXd RandomWeights(Eigen::Index aps, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.2, 2.0);
  Eigen::VectorXd g(aps);
  for (Eigen::Index i = 0; i < aps; ++i) g[i] = unit(rng);
  return g;
}

// Nearest(queries) must be, to the bit, the first k of each query's finite row of the full
// Dissimilarity sorted by (d, reference index). `context` names the case in a failure; `compared`
// grows by the (query, rank) pairs checked (fewer than k where a query has fewer finite d).
void ExpectNearestIsTheSortedDissimilarity(const SharedApMatcher& matcher, const SharedApRowMatrixXd& queries, int k,
                                           const std::string& context, int* compared) {
  const SharedApNeighbours nn = matcher.Nearest(queries);
  const SharedApRowMatrixXd d = matcher.Dissimilarity(queries);
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    std::vector<std::pair<double, Eigen::Index>> all;
    for (Eigen::Index j = 0; j < d.cols(); ++j) {
      if (std::isfinite(d(q, j))) all.emplace_back(d(q, j), j);
    }
    std::sort(all.begin(), all.end());
    for (Eigen::Index m = 0; m < k && m < static_cast<Eigen::Index>(all.size()); ++m) {
      ASSERT_EQ(nn.index(q, m), all[m].second) << context << " query " << q << " rank " << m;
      ASSERT_EQ(nn.distance_db(q, m), all[m].first) << context << " query " << q << " rank " << m;  // the same bits
      ++*compared;
    }
  }
}

TEST(SharedApMatcher, DefaultsAreTheFusionFixSettings) {
  const SharedApMatcherOptions o;
  EXPECT_EQ(o.penalty_db, 160.0);
  EXPECT_EQ(o.strength_scale_db, 5.0);
  EXPECT_EQ(o.k, 20);
  EXPECT_EQ(o.temperature_db, 3.0);
  std::string error;
  EXPECT_TRUE(o.IsValid(&error)) << error;
}

TEST(SharedApMatcher, PartsMatchBruteForce) {
  const SharedApRowMatrixXd refs = RandomFingerprints(60, 25, 0.25, 1);
  const SharedApRowMatrixXd queries = RandomFingerprints(17, 25, 0.3, 2);
  const Eigen::VectorXd g = RandomWeights(25, 3);
  for (double beta : {0.0, 5.0}) {
    SharedApMatcherOptions options;
    options.strength_scale_db = beta;
    options.penalty_db = 37.0;
    const SharedApMatcher matcher(refs, g, options);
    const SharedApParts parts = matcher.Parts(queries);
    const SharedApRowMatrixXd d = matcher.Dissimilarity(queries);
    int shared = 0, unshared = 0;
    for (Eigen::Index q = 0; q < queries.rows(); ++q) {
      for (Eigen::Index j = 0; j < refs.rows(); ++j) {
        const auto [rms, u] = BruteForce(queries, q, refs, j, g, beta);
        if (std::isinf(rms)) {
          ++unshared;
          EXPECT_TRUE(std::isinf(parts.rms_db(q, j)));
          EXPECT_EQ(parts.unshared(q, j), 1.0);
          EXPECT_TRUE(std::isinf(d(q, j)));
        } else {
          ++shared;
          EXPECT_NEAR(parts.rms_db(q, j), rms, 1e-9);
          EXPECT_NEAR(parts.unshared(q, j), u, 1e-12);
          EXPECT_NEAR(d(q, j), rms + 37.0 * u, 1e-9);
        }
      }
    }
    EXPECT_GT(shared, 100);  // both cases occur in the random data
    EXPECT_GT(unshared, 10);
  }
}

TEST(SharedApMatcher, NearestMatchesSortedBruteForce) {
  const SharedApRowMatrixXd refs = RandomFingerprints(80, 30, 0.2, 4);
  const SharedApRowMatrixXd queries = RandomFingerprints(40, 30, 0.2, 5);
  const Eigen::VectorXd g = RandomWeights(30, 6);
  SharedApMatcherOptions options;
  options.k = 7;
  options.temperature_db = 4.0;
  const SharedApMatcher matcher(refs, g, options);
  const SharedApNeighbours nn = matcher.Nearest(queries);
  ASSERT_EQ(nn.index.rows(), 40);
  ASSERT_EQ(nn.index.cols(), 7);
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    std::vector<std::pair<double, Eigen::Index>> all;
    for (Eigen::Index j = 0; j < refs.rows(); ++j) {
      const auto [rms, u] = BruteForce(queries, q, refs, j, g, options.strength_scale_db);
      if (std::isfinite(rms)) all.emplace_back(rms + options.penalty_db * u, j);
    }
    std::sort(all.begin(), all.end());
    for (Eigen::Index m = 0; m < 7; ++m) {
      if (m < static_cast<Eigen::Index>(all.size())) {
        EXPECT_EQ(nn.index(q, m), all[m].second) << "query " << q << " rank " << m;
        EXPECT_NEAR(nn.distance_db(q, m), all[m].first, 1e-9);
        EXPECT_NEAR(nn.weight(q, m), std::exp(-(all[m].first - all[0].first) / 4.0), 1e-12);
      } else {
        EXPECT_TRUE(std::isinf(nn.distance_db(q, m)));
        EXPECT_EQ(nn.weight(q, m), 0.0);
        EXPECT_GE(nn.index(q, m), 0);
        EXPECT_LT(nn.index(q, m), refs.rows());
      }
    }
  }
}

// Nearest prunes (a first pass over the query's strongest APs bounds every reference's d, exact d
// only where the bound can beat the k-th best): it must equal, bit for bit, the k smallest
// (d, reference) of the full Dissimilarity matrix, which adds every term in the same order.
TEST(SharedApMatcher, NearestIsTheFullComputationBitForBit) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  SharedApRowMatrixXd refs = RandomFingerprints(400, 60, 0.3, 22);
  for (Eigen::Index j = 0; j < 40; ++j) refs.row(300 + j) = refs.row(j);  // ties: equal d, order by index
  Eigen::VectorXd g = RandomWeights(60, 23);
  g[3] = g[17] = 0.0;  // unreliable APs: shared, yet no weight
  SharedApRowMatrixXd queries(120, 60);
  for (Eigen::Index q = 0; q < 120; ++q) {
    if (q < 40) {  // a reference with noise, some readings lost
      for (Eigen::Index i = 0; i < 60; ++i) {
        const double b = refs(q * 7 % 400, i);
        queries(q, i) = std::isnan(b) || unit(rng) < 0.2 ? kNaN : b + 8.0 * (unit(rng) - 0.5);
      }
    } else if (q < 80) {  // random, many APs
      for (Eigen::Index i = 0; i < 60; ++i) queries(q, i) = unit(rng) < 0.6 ? -95.0 + 65.0 * unit(rng) : kNaN;
    } else {  // a few APs, one far stronger than the rest (a first pass of one AP)
      queries.row(q).setConstant(kNaN);
      for (int m = 0; m < 4; ++m) queries(q, static_cast<Eigen::Index>(unit(rng) * 60)) = -90.0 + 10.0 * unit(rng);
      queries(q, q % 60) = -35.0;
    }
  }
  int compared = 0;
  // Whole dBm (as phones report) take the index's one-byte storage; fractions the double one.
  SharedApRowMatrixXd whole = refs.array().round();
  for (const SharedApRowMatrixXd* references : {&refs, &whole})
  for (double beta : {0.0, 5.0}) {
    for (double penalty : {0.0, 160.0}) {
      for (int k : {1, 7, 20}) {
        SharedApMatcherOptions options;
        options.strength_scale_db = beta;
        options.penalty_db = penalty;
        options.k = k;
        const SharedApMatcher matcher(*references, g, options);
        const std::string context =
            "beta " + std::to_string(beta) + " c " + std::to_string(penalty) + " k " + std::to_string(k);
        ASSERT_NO_FATAL_FAILURE(ExpectNearestIsTheSortedDissimilarity(matcher, queries, k, context, &compared));
      }
    }
  }
  EXPECT_GT(compared, 20000);
  // The one-byte storage gives the doubles' bits: the same whole-dBm references with one more
  // reference at a fraction of a dB (which forces the double storage) give the same d.
  SharedApRowMatrixXd mixed(whole.rows() + 1, whole.cols());
  mixed.topRows(whole.rows()) = whole;
  mixed.bottomRows(1).setConstant(kNaN);
  mixed(whole.rows(), 5) = -50.5;
  const SharedApRowMatrixXd d_compact = SharedApMatcher(whole, g).Dissimilarity(queries);
  const SharedApRowMatrixXd d_double = SharedApMatcher(mixed, g).Dissimilarity(queries);
  EXPECT_TRUE((d_compact.array() == d_double.leftCols(whole.rows()).array()).all());
}

// More than 65,536 references: reference rows take four bytes in the index instead of two.
TEST(SharedApMatcher, NearestIsTheFullComputationWithManyReferences) {
  const SharedApRowMatrixXd refs = RandomFingerprints(70000, 12, 0.3, 31).array().round();
  const SharedApRowMatrixXd queries = RandomFingerprints(12, 12, 0.6, 32);
  SharedApMatcherOptions options;
  options.k = 9;
  const SharedApMatcher matcher(refs, RandomWeights(12, 33), options);
  int compared = 0;
  ASSERT_NO_FATAL_FAILURE(ExpectNearestIsTheSortedDissimilarity(matcher, queries, 9, "", &compared));
  EXPECT_EQ(compared, 12 * 9);  // every query has at least 9 finite distances
}

TEST(SharedApMatcher, QueryHearingNothingKnownGetsInfiniteDistancesAndDistinctFillers) {
  SharedApRowMatrixXd refs(3, 2);
  refs << -50, kNaN, -60, kNaN, -70, kNaN;
  SharedApRowMatrixXd queries(2, 2);
  queries << kNaN, -40, kNaN, kNaN;
  SharedApMatcherOptions options;
  options.k = 5;  // clamped to 3
  const SharedApMatcher matcher(refs, Eigen::VectorXd(), options);
  const SharedApNeighbours nn = matcher.Nearest(queries);
  ASSERT_EQ(nn.index.cols(), 3);
  for (Eigen::Index q = 0; q < 2; ++q) {
    for (Eigen::Index m = 0; m < 3; ++m) {
      EXPECT_EQ(nn.index(q, m), m);
      EXPECT_TRUE(std::isinf(nn.distance_db(q, m)));
      EXPECT_EQ(nn.weight(q, m), 0.0);
    }
  }
}

TEST(SharedApMatcher, IdenticalFingerprintIsAtZero) {
  const SharedApRowMatrixXd refs = RandomFingerprints(20, 12, 0.5, 7);
  const SharedApMatcher matcher(refs, Eigen::VectorXd());
  const SharedApRowMatrixXd d = matcher.Dissimilarity(refs);
  for (Eigen::Index j = 0; j < refs.rows(); ++j) {
    if (refs.row(j).array().isNaN().all()) continue;
    EXPECT_NEAR(d(j, j), 0.0, 1e-9);
  }
}

TEST(SharedApMatcher, ResultsDoNotDependOnThreadCount) {
  const SharedApRowMatrixXd refs = RandomFingerprints(300, 40, 0.15, 8);
  const SharedApRowMatrixXd queries = RandomFingerprints(150, 40, 0.15, 9);
  const SharedApMatcher matcher(refs, RandomWeights(40, 10));
  const SharedApNeighbours one = matcher.Nearest(queries, 1);
  const SharedApRowMatrixXd d1 = matcher.Dissimilarity(queries, 1);
  for (int threads : {2, 3, 8}) {
    const SharedApNeighbours many = matcher.Nearest(queries, threads);
    EXPECT_TRUE((one.index.array() == many.index.array()).all()) << threads;
    // Bitwise equal (inf == inf holds), not merely close.
    EXPECT_TRUE((one.distance_db.array() == many.distance_db.array()).all()) << threads;
    EXPECT_TRUE((one.weight.array() == many.weight.array()).all()) << threads;
    EXPECT_TRUE((d1.array() == matcher.Dissimilarity(queries, threads).array()).all()) << threads;
  }
}

TEST(SharedApMatcher, RejectsBadInputNamingTheArgument) {
  const SharedApRowMatrixXd refs = RandomFingerprints(5, 4, 0.5, 11);
  auto message = [](auto fn) {
    try {
      fn();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  SharedApMatcherOptions bad;
  bad.temperature_db = 0.0;
  EXPECT_NE(message([&] { SharedApMatcher m(refs, Eigen::VectorXd(), bad); }).find("temperature_db"),
            std::string::npos);
  bad = SharedApMatcherOptions();
  bad.strength_scale_db = 0.5;
  EXPECT_NE(message([&] { SharedApMatcher m(refs, Eigen::VectorXd(), bad); }).find("strength_scale_db"),
            std::string::npos);
  bad = SharedApMatcherOptions();
  bad.k = 0;
  EXPECT_NE(message([&] { SharedApMatcher m(refs, Eigen::VectorXd(), bad); }).find("k must be"),
            std::string::npos);
  SharedApRowMatrixXd inf_refs = refs;
  inf_refs(2, 1) = kInf;
  EXPECT_NE(message([&] { SharedApMatcher m(inf_refs, Eigen::VectorXd()); }).find("reference_rss_dbm"),
            std::string::npos);
  EXPECT_NE(message([&] { SharedApMatcher m(refs, Eigen::VectorXd::Ones(3)); }).find("ap_weights"),
            std::string::npos);
  EXPECT_NE(message([&] { SharedApMatcher m(refs, -Eigen::VectorXd::Ones(4)); }).find("ap_weights"),
            std::string::npos);
  const SharedApMatcher matcher(refs, Eigen::VectorXd());
  EXPECT_NE(message([&] { matcher.Nearest(SharedApRowMatrixXd::Zero(2, 3)); }).find("queries_dbm"),
            std::string::npos);
  SharedApRowMatrixXd q = SharedApRowMatrixXd::Constant(1, 4, -50.0);
  q(0, 3) = 5000.0;
  EXPECT_NE(message([&] { matcher.Parts(q); }).find("queries_dbm"), std::string::npos);
}

TEST(SharedApMatcher, EmptyInputs) {
  const SharedApMatcher no_refs(SharedApRowMatrixXd(0, 3), Eigen::VectorXd());
  const SharedApNeighbours nn = no_refs.Nearest(SharedApRowMatrixXd::Constant(2, 3, -50.0));
  EXPECT_EQ(nn.index.rows(), 2);
  EXPECT_EQ(nn.index.cols(), 0);
  const SharedApMatcher matcher(RandomFingerprints(4, 3, 0.5, 12), Eigen::VectorXd());
  EXPECT_EQ(matcher.Dissimilarity(SharedApRowMatrixXd(0, 3)).rows(), 0);
  EXPECT_EQ(matcher.Nearest(SharedApRowMatrixXd(0, 3)).index.rows(), 0);
}

}  // namespace
}  // namespace indoorloc::wifi
