#include "indoorloc/wifi/fingerprint_baselines.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "invalid_argument_message.h"

namespace indoorloc::wifi {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Irregular AP layout around a 5 x 5 grid (no symmetric ties between grid points).
const Eigen::Vector2d kAccessPoints[4] = {
    {-1.3, -0.7}, {9.4, 0.6}, {3.1, 9.8}, {10.2, 8.9}};

// Log-distance path loss: RSS = -40 - 20 log10(distance) [dBm].
RowMatrixXd PathLossRss(const RowMatrixXd& positions_m) {
  RowMatrixXd rss(positions_m.rows(), 4);
  for (Eigen::Index i = 0; i < positions_m.rows(); ++i) {
    for (int a = 0; a < 4; ++a) {
      const double d = (positions_m.row(i).transpose() - kAccessPoints[a]).norm();
      rss(i, a) = -40.0 - 20.0 * std::log10(d);
    }
  }
  return rss;
}

// 5 x 5 grid, 2 m spacing, x and y in {0, 2, 4, 6, 8}.
RowMatrixXd GridPositions() {
  RowMatrixXd positions(25, 2);
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) positions.row(5 * i + j) << 2.0 * i, 2.0 * j;
  }
  return positions;
}

const RowMatrixXd kNoVariances;  // 0 x 0

FingerprintOptions Options(FingerprintMethod method, int k = 4) {
  FingerprintOptions options;
  options.method = method;
  options.k = k;
  return options;
}

// Scans at random off-grid positions with Gaussian noise.
RowMatrixXd RandomScans(int count, unsigned seed, double noise_db) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> position(-0.5, 8.5);
  std::normal_distribution<double> noise(0.0, noise_db);
  RowMatrixXd positions(count, 2);
  for (int i = 0; i < count; ++i) positions.row(i) << position(rng), position(rng);
  RowMatrixXd scans = PathLossRss(positions);
  for (Eigen::Index i = 0; i < scans.size(); ++i) scans.data()[i] += noise(rng);
  return scans;
}

// Rows sorted by (cost, index), the first k kept.
std::vector<int> BruteForceBest(const std::vector<double>& cost, int k) {
  std::vector<std::pair<double, int>> pairs;
  for (size_t i = 0; i < cost.size(); ++i) pairs.emplace_back(cost[i], static_cast<int>(i));
  std::sort(pairs.begin(), pairs.end());
  std::vector<int> best;
  for (int j = 0; j < k; ++j) best.push_back(pairs[static_cast<size_t>(j)].second);
  return best;
}

TEST(FingerprintMethod, NamesRoundTrip) {
  for (FingerprintMethod m : {FingerprintMethod::kNnss, FingerprintMethod::kNnssAvg,
                              FingerprintMethod::kWeightedKnn, FingerprintMethod::kHorus}) {
    EXPECT_EQ(ParseFingerprintMethod(ToString(m)), m);
  }
  EXPECT_EQ(ToString(FingerprintMethod::kNnssAvg), "nnss_avg");
  EXPECT_EQ(ToString(FingerprintMethod::kWeightedKnn), "wknn");
  EXPECT_EQ(MessageOf([] { ParseFingerprintMethod("knn"); }),
            "indoorloc: argument 'method': unknown fingerprint method 'knn' (expected nnss, "
            "nnss_avg, wknn or horus)");
}

TEST(FingerprintOptions, Validity) {
  std::string error;
  EXPECT_TRUE(FingerprintOptions().IsValid(&error));
  FingerprintOptions o;
  o.k = 0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "k must be >= 1, got 0");
  o = FingerprintOptions();
  o.distance_epsilon_db = 0.0;
  EXPECT_FALSE(o.IsValid(&error));
  o = FingerprintOptions();
  o.variance_floor_db2 = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(o.IsValid(&error));
}

TEST(FingerprintLocator, NnssLocatesReferenceRowsExactly) {
  const RowMatrixXd positions = GridPositions();
  const RowMatrixXd rss = PathLossRss(positions);
  const FingerprintLocator locator(rss, positions, Eigen::VectorXi::Zero(25), kNoVariances,
                                   Options(FingerprintMethod::kNnss));
  EXPECT_EQ(locator.effective_k(), 1);
  const FingerprintEstimates e = locator.Locate(rss);
  EXPECT_EQ(e.positions_m, positions);
  EXPECT_EQ(e.floors, Eigen::VectorXi::Zero(25));
  EXPECT_EQ(e.score, Eigen::VectorXd::Zero(25));
}

TEST(FingerprintLocator, WeightedKnnLocatesReferenceRows) {
  const RowMatrixXd positions = GridPositions();
  const RowMatrixXd rss = PathLossRss(positions);
  // k = 1: exactly.
  const FingerprintLocator k1(rss, positions, Eigen::VectorXi::Zero(25), kNoVariances,
                              Options(FingerprintMethod::kWeightedKnn, 1));
  const FingerprintEstimates e1 = k1.Locate(rss);
  EXPECT_EQ(e1.positions_m, positions);
  EXPECT_EQ(e1.score, Eigen::VectorXd::Zero(25));
  // k = 4: the exact match has weight 1 / epsilon = 1000 against about 1 / (a few dB) for the
  // other three, so the estimate is within a few millimetres of the reference point.
  const FingerprintLocator k4(rss, positions, Eigen::VectorXi::Zero(25), kNoVariances,
                              Options(FingerprintMethod::kWeightedKnn, 4));
  const FingerprintEstimates e4 = k4.Locate(rss);
  EXPECT_LT((e4.positions_m - positions).rowwise().norm().maxCoeff(), 5e-3);
  EXPECT_EQ(e4.score, Eigen::VectorXd::Zero(25));
}

// nnss_avg and wknn against a brute-force sort of all distances.
TEST(FingerprintLocator, KnnMethodsMatchBruteForce) {
  const RowMatrixXd positions = GridPositions();
  const RowMatrixXd rss = PathLossRss(positions);
  const RowMatrixXd scans = RandomScans(20, 7, 2.0);
  for (FingerprintMethod method : {FingerprintMethod::kNnssAvg, FingerprintMethod::kWeightedKnn}) {
    for (int k : {1, 2, 4, 7}) {
      const FingerprintLocator locator(rss, positions, Eigen::VectorXi::Zero(25), kNoVariances,
                                       Options(method, k));
      const FingerprintEstimates e = locator.Locate(scans);
      for (Eigen::Index q = 0; q < scans.rows(); ++q) {
        std::vector<double> distance(25);
        for (int r = 0; r < 25; ++r) distance[static_cast<size_t>(r)] = (scans.row(q) - rss.row(r)).norm();
        const std::vector<int> best = BruteForceBest(distance, k);
        Eigen::Vector2d sum = Eigen::Vector2d::Zero();
        double total = 0.0;
        for (int r : best) {
          const double w = method == FingerprintMethod::kNnssAvg
                               ? 1.0
                               : 1.0 / (distance[static_cast<size_t>(r)] + 1e-3);
          sum += w * positions.row(r).transpose();
          total += w;
        }
        const Eigen::Vector2d expected = sum / total;
        EXPECT_NEAR(e.positions_m(q, 0), expected.x(), 1e-12) << ToString(method) << " k=" << k;
        EXPECT_NEAR(e.positions_m(q, 1), expected.y(), 1e-12) << ToString(method) << " k=" << k;
        EXPECT_NEAR(e.score[q], distance[static_cast<size_t>(best[0])], 1e-12);
        EXPECT_EQ(e.floors[q], 0);
      }
    }
  }
}

TEST(FingerprintLocator, NnssAvgWithKFourIsMeanOfFourNearest) {
  const RowMatrixXd positions = GridPositions();
  const RowMatrixXd rss = PathLossRss(positions);
  // A scan generated halfway between four grid points, (3, 3), without noise: the four nearest
  // in signal space are its four surrounding grid points.
  RowMatrixXd at(1, 2);
  at << 3.0, 3.0;
  const FingerprintLocator locator(rss, positions, Eigen::VectorXi::Zero(25), kNoVariances,
                                   Options(FingerprintMethod::kNnssAvg, 4));
  const FingerprintEstimates e = locator.Locate(PathLossRss(at));
  std::vector<double> distance(25);
  const RowMatrixXd scan = PathLossRss(at);
  for (int r = 0; r < 25; ++r) distance[static_cast<size_t>(r)] = (scan.row(0) - rss.row(r)).norm();
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int r : BruteForceBest(distance, 4)) mean += positions.row(r).transpose() / 4.0;
  EXPECT_NEAR(e.positions_m(0, 0), mean.x(), 1e-12);
  EXPECT_NEAR(e.positions_m(0, 1), mean.y(), 1e-12);
}

TEST(FingerprintLocator, KIsClampedToReferenceCount) {
  const RowMatrixXd positions = GridPositions();
  const RowMatrixXd rss = PathLossRss(positions);
  const FingerprintLocator locator(rss, positions, Eigen::VectorXi::Zero(25), kNoVariances,
                                   Options(FingerprintMethod::kNnssAvg, 100));
  EXPECT_EQ(locator.k(), 100);
  EXPECT_EQ(locator.effective_k(), 25);
  const FingerprintEstimates e = locator.Locate(RandomScans(3, 1, 1.0));
  for (int q = 0; q < 3; ++q) {
    EXPECT_NEAR(e.positions_m(q, 0), 4.0, 1e-12);  // the mean of the whole grid
    EXPECT_NEAR(e.positions_m(q, 1), 4.0, 1e-12);
  }
}

TEST(FingerprintLocator, HorusPicksGeneratingPoint) {
  const RowMatrixXd positions = GridPositions();
  const RowMatrixXd rss = PathLossRss(positions);
  const RowMatrixXd variance = RowMatrixXd::Constant(25, 4, 9.0);
  const FingerprintLocator locator(rss, positions, Eigen::VectorXi::Zero(25), variance,
                                   Options(FingerprintMethod::kHorus, 1));
  const FingerprintEstimates e = locator.Locate(rss);
  EXPECT_EQ(e.positions_m, positions);
  // Score at the mean: the normaliser 1/2 sum_k log(2 pi v_k) only.
  const double expected_score = 0.5 * 4.0 * std::log(2.0 * kPi * 9.0);
  for (int q = 0; q < 25; ++q) EXPECT_NEAR(e.score[q], expected_score, 1e-12);
}

// horus against an explicit likelihood over all points, with varied (and partly floored)
// variances.
TEST(FingerprintLocator, HorusMatchesBruteForceLikelihood) {
  const RowMatrixXd positions = GridPositions();
  const RowMatrixXd rss = PathLossRss(positions);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uniform(0.0, 20.0);
  RowMatrixXd variance(25, 4);
  for (Eigen::Index i = 0; i < variance.size(); ++i) variance.data()[i] = uniform(rng);
  const double floor_db2 = 4.0;
  const RowMatrixXd scans = RandomScans(15, 11, 3.0);
  for (int k : {1, 3, 6}) {
    const FingerprintLocator locator(rss, positions, Eigen::VectorXi::Zero(25), variance,
                                     Options(FingerprintMethod::kHorus, k));
    const FingerprintEstimates e = locator.Locate(scans);
    for (Eigen::Index q = 0; q < scans.rows(); ++q) {
      std::vector<double> neg_log_lik(25);
      for (int r = 0; r < 25; ++r) {
        double log_lik = 0.0;
        for (int a = 0; a < 4; ++a) {
          const double v = std::max(variance(r, a), floor_db2);
          const double d = scans(q, a) - rss(r, a);
          log_lik += -0.5 * d * d / v - 0.5 * std::log(2.0 * kPi * v);
        }
        neg_log_lik[static_cast<size_t>(r)] = -log_lik;
      }
      const std::vector<int> best = BruteForceBest(neg_log_lik, k);
      Eigen::Vector2d sum = Eigen::Vector2d::Zero();
      double total = 0.0;
      for (int r : best) {
        const double w = std::exp(neg_log_lik[static_cast<size_t>(best[0])] -
                                  neg_log_lik[static_cast<size_t>(r)]);
        sum += w * positions.row(r).transpose();
        total += w;
      }
      EXPECT_NEAR(e.positions_m(q, 0), sum.x() / total, 1e-10) << "k=" << k;
      EXPECT_NEAR(e.positions_m(q, 1), sum.y() / total, 1e-10) << "k=" << k;
      EXPECT_NEAR(e.score[q], neg_log_lik[static_cast<size_t>(best[0])], 1e-10);
    }
  }
}

TEST(FingerprintLocator, TwoFloorMapReturnsMatchingFloor) {
  const RowMatrixXd grid = GridPositions();
  const RowMatrixXd grid_rss = PathLossRss(grid);
  RowMatrixXd positions(50, 2);
  positions << grid, grid;
  RowMatrixXd rss(50, 4);
  // Floor 1 sees the same APs through a 15 dB floor loss.
  rss << grid_rss, grid_rss.array() - 15.0;
  Eigen::VectorXi floors(50);
  floors << Eigen::VectorXi::Zero(25), Eigen::VectorXi::Ones(25);
  const RowMatrixXd variance = RowMatrixXd::Constant(50, 4, 4.0);
  RowMatrixXd scans = RandomScans(10, 5, 1.0).array() - 15.0;  // all on floor 1
  for (FingerprintMethod method : {FingerprintMethod::kNnss, FingerprintMethod::kNnssAvg,
                                   FingerprintMethod::kWeightedKnn, FingerprintMethod::kHorus}) {
    const FingerprintLocator locator(rss, positions, floors, variance, Options(method, 4));
    const FingerprintEstimates e = locator.Locate(scans);
    EXPECT_EQ(e.floors, Eigen::VectorXi::Ones(10)) << ToString(method);
  }
}

// One AP; a floor-0 point is the nearest, but three floor-1 points follow.
TEST(FingerprintLocator, FloorVoteAndAveragingOverChosenFloor) {
  RowMatrixXd rss(5, 1);
  rss << -50.0, -51.0, -52.0, -50.5, -70.0;
  RowMatrixXd positions(5, 2);
  positions << 0, 0, 1, 0, 2, 0, 10, 10, 20, 20;
  Eigen::VectorXi floors(5);
  floors << 1, 1, 1, 0, 0;
  RowMatrixXd scan(1, 1);
  scan << -50.6;  // distances 0.6, 0.4, 1.4, 0.1, 19.4
  auto locate = [&](FingerprintMethod method, int k) {
    const FingerprintLocator locator(rss, positions, floors, RowMatrixXd::Ones(5, 1),
                                     Options(method, k));
    return locator.Locate(scan);
  };
  // nnss: the nearest, on floor 0.
  FingerprintEstimates e = locate(FingerprintMethod::kNnss, 4);
  EXPECT_EQ(e.floors[0], 0);
  EXPECT_DOUBLE_EQ(e.positions_m(0, 0), 10.0);
  EXPECT_NEAR(e.score[0], 0.1, 1e-12);
  // nnss_avg, k = 4: floor 1 wins 3 to 1; the position averages the three floor-1 points only.
  e = locate(FingerprintMethod::kNnssAvg, 4);
  EXPECT_EQ(e.floors[0], 1);
  EXPECT_NEAR(e.positions_m(0, 0), 1.0, 1e-12);
  EXPECT_NEAR(e.positions_m(0, 1), 0.0, 1e-12);
  // nnss_avg, k = 2: a 1 to 1 tie goes to the floor of the best-ranked neighbour.
  e = locate(FingerprintMethod::kNnssAvg, 2);
  EXPECT_EQ(e.floors[0], 0);
  EXPECT_DOUBLE_EQ(e.positions_m(0, 0), 10.0);
  // wknn, k = 4: weights 1/0.101 for floor 0 against 1/0.401 + 1/0.601 + 1/1.401 for floor 1.
  e = locate(FingerprintMethod::kWeightedKnn, 4);
  EXPECT_EQ(e.floors[0], 0);
  EXPECT_DOUBLE_EQ(e.positions_m(0, 0), 10.0);
  EXPECT_DOUBLE_EQ(e.positions_m(0, 1), 10.0);
  // horus: the floor of the most likely point.
  e = locate(FingerprintMethod::kHorus, 4);
  EXPECT_EQ(e.floors[0], 0);
  EXPECT_DOUBLE_EQ(e.positions_m(0, 0), 10.0);
}

TEST(FingerprintLocator, RejectsBadInput) {
  const RowMatrixXd positions = GridPositions();
  const RowMatrixXd rss = PathLossRss(positions);
  const Eigen::VectorXi floors = Eigen::VectorXi::Zero(25);
  const FingerprintLocator locator(rss, positions, floors, kNoVariances, FingerprintOptions());

  RowMatrixXd scans = rss.topRows(2);
  scans(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(MessageOf([&] { locator.Locate(scans); }),
            "indoorloc: argument 'scans_dbm': entry (1, 2) is NaN");
  scans(1, 2) = -std::numeric_limits<double>::infinity();
  EXPECT_EQ(MessageOf([&] { locator.Locate(scans); }),
            "indoorloc: argument 'scans_dbm': entry (1, 2) is infinite");
  EXPECT_EQ(MessageOf([&] { locator.Locate(RowMatrixXd::Zero(2, 3)); }),
            "indoorloc: argument 'scans_dbm': has 3 columns but the reference fingerprints "
            "have 4 access points (expected shape (any, 4), got (2, 3))");

  FingerprintOptions bad_k;
  bad_k.k = 0;
  EXPECT_EQ(MessageOf([&] { FingerprintLocator(rss, positions, floors, kNoVariances, bad_k); }),
            "indoorloc: argument 'options': k must be >= 1, got 0");
  bad_k.k = -3;
  EXPECT_THROW(FingerprintLocator(rss, positions, floors, kNoVariances, bad_k),
               std::invalid_argument);

  EXPECT_EQ(MessageOf([&] {
              FingerprintLocator(RowMatrixXd(0, 4), RowMatrixXd(0, 2), Eigen::VectorXi(0),
                                 kNoVariances, FingerprintOptions());
            }),
            "indoorloc: argument 'reference_rss_dbm': has no rows (at least one reference "
            "fingerprint is needed)");
  EXPECT_THROW(FingerprintLocator(RowMatrixXd(25, 0), positions, floors, kNoVariances,
                                  FingerprintOptions()),
               std::invalid_argument);

  EXPECT_EQ(MessageOf([&] {
              FingerprintLocator(rss, positions, floors, kNoVariances,
                                 Options(FingerprintMethod::kHorus));
            }),
            "indoorloc: argument 'reference_variance_db2': is required by method 'horus' (got "
            "a 0 x 0 matrix: no variances)");

  RowMatrixXd bad_rss = rss;
  bad_rss(3, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(MessageOf([&] {
              FingerprintLocator(bad_rss, positions, floors, kNoVariances, FingerprintOptions());
            }),
            "indoorloc: argument 'reference_rss_dbm': entry (3, 1) is NaN");
  EXPECT_EQ(MessageOf([&] {
              FingerprintLocator(rss, positions.leftCols(1), floors, kNoVariances,
                                 FingerprintOptions());
            }),
            "indoorloc: argument 'reference_positions_m': expected shape (25, 2), got (25, 1)");
  EXPECT_EQ(MessageOf([&] {
              FingerprintLocator(rss, positions, Eigen::VectorXi::Zero(24), kNoVariances,
                                 FingerprintOptions());
            }),
            "indoorloc: argument 'reference_floors': expected length 25 (the rows of "
            "reference_rss_dbm), got 24");
  RowMatrixXd variance = RowMatrixXd::Constant(25, 4, 4.0);
  variance(2, 3) = -1.0;
  EXPECT_EQ(MessageOf([&] {
              FingerprintLocator(rss, positions, floors, variance,
                                 Options(FingerprintMethod::kHorus));
            }),
            "indoorloc: argument 'reference_variance_db2': entry (2, 3) is negative (-1)");
  EXPECT_THROW(FingerprintLocator(rss, positions, floors, RowMatrixXd::Ones(25, 3),
                                  Options(FingerprintMethod::kHorus)),
               std::invalid_argument);
  // Variances are optional for the distance methods, and zero variances are floored.
  EXPECT_NO_THROW(FingerprintLocator(rss, positions, floors, RowMatrixXd::Zero(25, 4),
                                     Options(FingerprintMethod::kHorus)));
}

TEST(FingerprintLocator, EmptyBatch) {
  const RowMatrixXd positions = GridPositions();
  const FingerprintLocator locator(PathLossRss(positions), positions, Eigen::VectorXi::Zero(25),
                                   kNoVariances, FingerprintOptions());
  const FingerprintEstimates e = locator.Locate(RowMatrixXd(0, 4), 4);
  EXPECT_EQ(e.positions_m.rows(), 0);
  EXPECT_EQ(e.floors.size(), 0);
  EXPECT_EQ(e.score.size(), 0);
}

TEST(FingerprintLocator, ResultsDoNotDependOnThreadCount) {
  // Two floors so that the vote is exercised too.
  const RowMatrixXd grid = GridPositions();
  RowMatrixXd positions(50, 2);
  positions << grid, grid;
  RowMatrixXd rss(50, 4);
  rss << PathLossRss(grid), PathLossRss(grid).array() - 6.0;
  Eigen::VectorXi floors(50);
  floors << Eigen::VectorXi::Constant(25, 2), Eigen::VectorXi::Constant(25, 3);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> uniform(1.0, 12.0);
  RowMatrixXd variance(50, 4);
  for (Eigen::Index i = 0; i < variance.size(); ++i) variance.data()[i] = uniform(rng);
  const RowMatrixXd scans = RandomScans(101, 13, 4.0).array() - 3.0;  // 4 blocks of 32, ragged
  for (FingerprintMethod method : {FingerprintMethod::kNnss, FingerprintMethod::kNnssAvg,
                                   FingerprintMethod::kWeightedKnn, FingerprintMethod::kHorus}) {
    const FingerprintLocator locator(rss, positions, floors, variance, Options(method, 5));
    const FingerprintEstimates one = locator.Locate(scans, 1);
    for (int threads : {3, 0, 64}) {
      const FingerprintEstimates many = locator.Locate(scans, threads);
      EXPECT_EQ(one.positions_m, many.positions_m) << ToString(method) << " threads=" << threads;
      EXPECT_EQ(one.floors, many.floors) << ToString(method) << " threads=" << threads;
      EXPECT_EQ(one.score, many.score) << ToString(method) << " threads=" << threads;
    }
    // Row by row gives the same as the batch (block position does not matter either).
    for (Eigen::Index q = 0; q < scans.rows(); q += 17) {
      const FingerprintEstimates single = locator.Locate(scans.row(q));
      EXPECT_EQ(single.positions_m.row(0), one.positions_m.row(q)) << ToString(method);
      EXPECT_EQ(single.floors[0], one.floors[q]);
      EXPECT_EQ(single.score[0], one.score[q]);
    }
  }
}

}  // namespace
}  // namespace indoorloc::wifi
