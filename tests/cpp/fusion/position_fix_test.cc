// Tests of position fixes: the mixture-with-outlier likelihood against its formula, validation,
// and the tracker with fixes (unknown start placed by a fix, an outlier fix that cannot pull the
// cloud away, the batch API's event order, determinism for any thread count).
#include "indoorloc/fusion/position_fix.h"

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "indoorloc/fusion/floor_plan.h"
#include "indoorloc/fusion/particle_tracker.h"
#include "indoorloc/fusion/track.h"

namespace indoorloc::fusion {
namespace {

// A 40 x 10 m hall.
FloorPlan HallPlan() {
  FloorGeometry g;
  g.floor = 0;
  RowMatrixXd ring(4, 2);
  ring << 0, 0, 40, 0, 40, 10, 0, 10;
  g.outlines.push_back(ring);
  return FloorPlan({g});
}

PositionFix TwoComponentFix(double t, double x0, double y0, double x1, double y1, double w0 = 0.7) {
  PositionFix f;
  f.time_s = t;
  f.means_m.resize(2, 2);
  f.means_m << x0, y0, x1, y1;
  f.sds_m = Eigen::Vector2d(2.0, 3.0);
  f.weights = Eigen::Vector2d(w0, 1.0 - w0);
  return f;
}

// Default tracker options with n particles and the given seed.
TrackerOptions ParticlesAndSeed(int num_particles, std::uint64_t seed) {
  TrackerOptions o;
  o.num_particles = num_particles;
  o.seed = seed;
  return o;
}

StepInput EastStep(double t, double length = 0.7, double sd = 0.05) {
  StepInput s;
  s.time_s = t;
  s.displacement_m = Eigen::Vector2d(length, 0.0);
  s.covariance_m2 = sd * sd * Eigen::Matrix2d::Identity();
  return s;
}

TEST(FixLikelihood, IsTheMixtureWithTheOutlierFloor) {
  PositionFix fix = TwoComponentFix(0.0, 5.0, 5.0, 30.0, 2.0);
  fix.weights = Eigen::Vector2d(3.0, 1.0);  // normalised on use to 0.75, 0.25
  FixLikelihoodOptions o;
  o.outlier_probability = 0.1;
  o.tempering = 0.5;
  const FixLikelihood like(fix, o);
  const double area = 400.0;
  for (const auto& p : std::vector<Eigen::Vector2d>{{5, 5}, {7, 4}, {30, 2}, {18, 9}, {-50, 80}}) {
    auto normal = [&](int k) {
      const double var = fix.sds_m[k] * fix.sds_m[k];
      return std::exp(-(p - fix.means_m.row(k).transpose()).squaredNorm() / (2 * var)) / (2 * M_PI * var);
    };
    const double density = 0.1 / area + 0.9 * (0.75 * normal(0) + 0.25 * normal(1));
    EXPECT_NEAR(like.LogLikelihood(p.x(), p.y(), 0, area), 0.5 * std::log(density), 1e-12);
  }
  // A fix on floor 3 gives particles on other floors the outlier density only.
  fix.floors = Eigen::Vector2i(3, 3);
  const FixLikelihood on3(fix, o);
  EXPECT_NEAR(on3.LogLikelihood(5.0, 5.0, 2, area), 0.5 * std::log(0.1 / area), 1e-12);
  EXPECT_GT(on3.LogLikelihood(5.0, 5.0, 3, area), on3.LogLikelihood(5.0, 5.0, 2, area));
  // Components on two floors: each floor sees its own components only.
  fix.floors = Eigen::Vector2i(1, PositionFix::kAnyFloor);
  const FixLikelihood split(fix, o);
  auto normal1 = [&](const Eigen::Vector2d& p) {
    const double var = fix.sds_m[1] * fix.sds_m[1];
    return std::exp(-(p - fix.means_m.row(1).transpose()).squaredNorm() / (2 * var)) / (2 * M_PI * var);
  };
  const Eigen::Vector2d q(29.0, 3.0);
  EXPECT_NEAR(split.LogLikelihood(q.x(), q.y(), 2, area), 0.5 * std::log(0.1 / area + 0.9 * 0.25 * normal1(q)), 1e-12);
}

TEST(FixLikelihood, FarFromEveryComponentItIsTheOutlierFloorNotMinusInfinity) {
  PositionFix fix = TwoComponentFix(0.0, 0.0, 0.0, 1.0, 0.0);
  FixLikelihoodOptions o;
  const FixLikelihood like(fix, o);
  const double far = like.LogLikelihood(1e6, -1e6, 0, 1000.0);
  EXPECT_TRUE(std::isfinite(far));
  EXPECT_NEAR(far, o.tempering * std::log(o.outlier_probability / 1000.0), 1e-12);
}

TEST(PositionFix, FromCandidatesDropsThePaddingOfWeightZeroWithoutReadingIt) {
  PositionFix::Means means(3, 2);
  means << 1, 2, std::nan(""), std::nan(""), 5, 6;
  const Eigen::Vector3d sds(1.5, std::nan(""), 2.5);
  const Eigen::Vector3d weights(0.25, 0.0, 0.75);
  const Eigen::Vector3i floors(2, 9, PositionFix::kAnyFloor);
  const PositionFix fix = FixFromCandidates(4.0, means, sds, weights, floors);
  EXPECT_EQ(fix.time_s, 4.0);
  ASSERT_EQ(fix.means_m.rows(), 2);
  EXPECT_EQ(fix.means_m(0, 0), 1.0);
  EXPECT_EQ(fix.means_m(1, 1), 6.0);
  EXPECT_EQ(fix.sds_m, Eigen::Vector2d(1.5, 2.5));
  EXPECT_EQ(fix.weights, Eigen::Vector2d(0.25, 0.75));
  EXPECT_EQ(fix.floors, Eigen::Vector2i(2, PositionFix::kAnyFloor));
  CheckPositionFix(fix, "fix");  // a valid fix: the NaN padding is gone
  EXPECT_THROW(FixFromCandidates(0.0, means, sds, Eigen::Vector2d(1.0, 1.0), floors), std::invalid_argument);
}

TEST(PositionFix, RejectsMalformedFixesNamingTheField) {
  auto message = [](const PositionFix& f) {
    try {
      CheckPositionFix(f, "fix");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  PositionFix f = TwoComponentFix(0.0, 1, 1, 2, 2);
  EXPECT_EQ(message(f), "");
  PositionFix bad = f;
  bad.sds_m[1] = 0.0;
  EXPECT_NE(message(bad).find("fix.sds_m"), std::string::npos);
  bad = f;
  bad.weights = Eigen::Vector2d(0.0, 0.0);
  EXPECT_NE(message(bad).find("fix.weights"), std::string::npos);
  bad = f;
  bad.weights[0] = -1.0;
  EXPECT_NE(message(bad).find("fix.weights"), std::string::npos);
  bad = f;
  bad.means_m(0, 1) = std::nan("");
  EXPECT_NE(message(bad).find("fix.means_m"), std::string::npos);
  bad = f;
  bad.sds_m.resize(3);
  bad.sds_m.setOnes();
  EXPECT_NE(message(bad).find("fix.sds_m"), std::string::npos);
  bad = f;
  bad.floors = Eigen::Vector3i(0, 0, 0);
  EXPECT_NE(message(bad).find("fix.floors"), std::string::npos);
  bad = f;
  bad.time_s = INFINITY;
  EXPECT_NE(message(bad).find("fix.time_s"), std::string::npos);
  FixLikelihoodOptions o;
  std::string why;
  o.outlier_probability = 0.0;
  EXPECT_FALSE(o.IsValid(&why));
  o.outlier_probability = 0.5;
  o.tempering = 1.5;
  EXPECT_FALSE(o.IsValid(&why));
}

TEST(ParticleTracker, AnUnknownStartIsPlacedByTheFirstFixAndFollowsTheSteps) {
  const FloorPlan plan = HallPlan();
  TrackerOptions o = ParticlesAndSeed(3000, 3);
  o.unknown_start_heading_sd_rad = 0.05;
  ParticleTracker tracker(&plan, nullptr, nullptr, o);
  EXPECT_NEAR(tracker.floor_areas_m2()[0], 400.0, 1e-9);
  Eigen::Vector2d truth(5.0, 5.0);
  TrackerEstimate e = tracker.Fix(TwoComponentFix(0.0, truth.x(), truth.y(), 35.0, 5.0, 0.8));
  EXPECT_TRUE(e.recovered);
  for (int k = 0; k < 20; ++k) {
    truth.x() += 0.7;
    e = tracker.Step(EastStep(0.5 * (k + 1)));
    if (k % 4 == 3) e = tracker.Fix(TwoComponentFix(0.5 * (k + 1), truth.x(), truth.y(), 35.0, 5.0, 0.8));
  }
  EXPECT_LT((e.mean_m - truth).norm(), 1.0);
  EXPECT_EQ(tracker.summary().fix_updates, 6);
}

TEST(ParticleTracker, OneOutlierFixCannotPullAConfidentCloudAcrossTheHall) {
  const FloorPlan plan = HallPlan();
  TrackerOptions o = ParticlesAndSeed(2000, 5);
  o.start_position_sd_m = 0.3;
  o.fix.outlier_probability = 0.2;
  ParticleTracker tracker(&plan, nullptr, nullptr, o);
  tracker.InitializeKnown(0.0, Eigen::Vector2d(5.0, 5.0), 0, 0.0);
  PositionFix wrong;
  wrong.time_s = 0.1;
  wrong.means_m.resize(1, 2);
  wrong.means_m << 35.0, 5.0;
  wrong.sds_m = Eigen::VectorXd::Constant(1, 1.0);
  wrong.weights = Eigen::VectorXd::Ones(1);
  const TrackerEstimate e = tracker.Fix(wrong);
  EXPECT_LT((e.mean_m - Eigen::Vector2d(5.0, 5.0)).norm(), 0.5);
  EXPECT_TRUE(std::isfinite(e.log_likelihood));
}

TEST(Track, FixesAndStepsAreMergedInTimeAndTheResultIsTheSameForAnyThreadCount) {
  const FloorPlan plan = HallPlan();
  Recording rec;
  for (int k = 0; k < 30; ++k) rec.steps.push_back(EastStep(0.5 * (k + 1)));
  for (int k = 0; k < 8; ++k) {
    const double t = 2.0 * k;  // some at the same time as a step (t = 2, 4, ...)
    rec.fixes.push_back(TwoComponentFix(t, 5.0 + 0.7 * 2.0 * t, 5.0, 38.0, 8.0, 0.9));
  }
  std::vector<Eigen::Vector2d> means;
  for (int threads : {1, 2, 3}) {
    TrackerOptions o = ParticlesAndSeed(2 * ParticleTracker::kBlockSize + 100, 11);
    o.num_threads = threads;
    o.unknown_start_heading_sd_rad = 0.05;
    const TrackResult r = Track(&plan, nullptr, nullptr, rec, TrackStart(), o, SmootherOptions(), false);
    EXPECT_EQ(r.summary.fix_updates, 8);
    EXPECT_EQ(r.estimates.size(), 30u);
    means.push_back(r.estimates.back().mean_m);
  }
  EXPECT_EQ(means[0], means[1]);
  EXPECT_EQ(means[0], means[2]);
  EXPECT_LT((means[0] - Eigen::Vector2d(5.0 + 0.7 * 30, 5.0)).norm(), 1.5);
  // Unsorted fixes are rejected, naming the argument.
  std::swap(rec.fixes[1], rec.fixes[2]);
  EXPECT_THROW(Track(&plan, nullptr, nullptr, rec, TrackStart(), TrackerOptions(), SmootherOptions(), false),
               std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::fusion
