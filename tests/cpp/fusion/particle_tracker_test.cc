// Tests of the fusion tracker: walls, degenerate weights, determinism, recovery of a path with
// perfect inputs, corridor mode, the fixed-lag and backward smoothers. The motion model and the
// WiFi likelihood have their own tests (step_motion_test.cc, wifi_likelihood_test.cc).
#include "indoorloc/fusion/particle_tracker.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "expect_invalid.h"
#include "room_fixture.h"

#include "indoorloc/fusion/backward_smoother.h"
#include "indoorloc/fusion/floor_plan.h"
#include "indoorloc/fusion/step_motion.h"
#include "indoorloc/fusion/track.h"
#include "indoorloc/fusion/wifi_likelihood.h"
#include "indoorloc/mapmatch/corridor_motion.h"
#include "indoorloc/mapmatch/road_network.h"
#include "indoorloc/wifi/rss_model.h"

namespace indoorloc::fusion {
namespace {

TrackerOptions SmallOptions(int n = 2000) {
  TrackerOptions o;
  o.num_particles = n;
  o.seed = 7;
  o.start_position_sd_m = 0.2;
  o.start_heading_offset_sd_rad = 0.01;
  o.start_scale_sd = 0.01;
  return o;
}

// A tracker on `plan` alone (no WiFi model, no corridors) started at a known position [m] on floor
// 0 at t = 0 s, heading offset 0.
ParticleTracker KnownStartTracker(const FloorPlan& plan, const TrackerOptions& o, const Eigen::Vector2d& start_m) {
  ParticleTracker tracker(&plan, nullptr, nullptr, o);
  tracker.InitializeKnown(0.0, start_m, 0, 0.0);
  return tracker;
}

// The room of room_fixture.h (one floor) and its four APs' RSS model, built for each test.
class ParticleTrackerInRoom : public ::testing::Test {
 protected:
  const FloorPlan plan = RoomPlan();
  const wifi::RssModel model{RoomMap()};
};
class TrackInRoom : public ParticleTrackerInRoom {};

TEST_F(ParticleTrackerInRoom, PerfectStepsRecoverThePath) {
  TrackerOptions o = SmallOptions();
  ParticleTracker tracker = KnownStartTracker(plan, o, Eigen::Vector2d(2.0, 1.5));
  Eigen::Vector2d truth(2.0, 1.5);
  // East along y = 1.5 to x = 18 (through the door region below? no: the wall at x = 16 spans
  // y 0..7, so go north first to y = 8.5, then east, then south-east).
  std::vector<Eigen::Vector2d> moves;
  for (int k = 0; k < 10; ++k) moves.emplace_back(0.0, 0.7);
  for (int k = 0; k < 22; ++k) moves.emplace_back(0.7, 0.0);
  double t = 0.0;
  double worst = 0.0;
  for (const auto& d : moves) {
    t += 0.5;
    truth += d;
    const TrackerEstimate e = tracker.Step(Step(t, d.x(), d.y()));
    worst = std::max(worst, (e.mean_m - truth).norm());
    EXPECT_FALSE(std::isnan(e.mean_m.x()));
  }
  EXPECT_LT(worst, 1.0);
  EXPECT_LT((tracker.Estimate().mean_m - truth).norm(), 1.0);
}

TEST_F(ParticleTrackerInRoom, NoParticleEverEndsInsideAnObstacle) {
  TrackerOptions o = SmallOptions(3000);
  o.start_position_sd_m = 3.0;
  o.start_heading_offset_sd_rad = 1.0;
  ParticleTracker tracker = KnownStartTracker(plan, o, Eigen::Vector2d(6.0, 5.0));
  RandomStream rng(11);
  for (int k = 0; k < 40; ++k) {
    const double h = rng.Uniform(-M_PI, M_PI);
    tracker.Step(Step(0.5 * (k + 1), 0.8 * std::cos(h), 0.8 * std::sin(h), 0.2));
    const RowMatrixXd p = tracker.ParticleStates();
    for (Eigen::Index i = 0; i < p.rows(); ++i) {
      ASSERT_TRUE(plan.IsWalkable(p(i, 0), p(i, 1), 0)) << "particle " << i << " at step " << k;
    }
    ASSERT_TRUE(tracker.ParticleWeights().allFinite());
  }
}

TEST_F(ParticleTrackerInRoom, EveryParticleBlockedIsIgnoredThenRespread) {
  TrackerOptions o = SmallOptions(500);
  o.start_position_sd_m = 0.0;
  o.respread_after_blocked_steps = 2;
  ParticleTracker tracker = KnownStartTracker(plan, o, Eigen::Vector2d(15.5, 2.0));
  // A 3 m step east crosses the thin wall at x = 16 for every particle.
  TrackerEstimate e = tracker.Step(Step(0.5, 3.0, 0.0));
  EXPECT_EQ(tracker.summary().all_blocked_steps, 1);
  EXPECT_NEAR(e.blocked_fraction, 1.0, 1e-12);
  EXPECT_TRUE(tracker.ParticleWeights().allFinite());
  EXPECT_NEAR(e.mean_m.x(), 15.5, 1e-9);
  e = tracker.Step(Step(1.0, 3.0, 0.0));
  EXPECT_EQ(tracker.summary().all_blocked_steps, 2);
  EXPECT_EQ(tracker.summary().respreads, 1);
  EXPECT_TRUE(tracker.ParticleWeights().allFinite());
  EXPECT_TRUE(e.mean_m.allFinite());
}

TEST_F(ParticleTrackerInRoom, UnderflowingWifiLikelihoodsStayFinite) {
  TrackerOptions o = SmallOptions(1000);
  o.wifi.max_term = std::numeric_limits<double>::infinity();
  o.wifi.tempering = 1.0;
  ParticleTracker tracker(&plan, &model, nullptr, o);
  tracker.InitializeKnown(0.0, Eigen::Vector2d(3.0, 3.0), 0, 0.0);
  WifiObservation absurd;
  absurd.time_s = 0.1;
  absurd.access_points = {0, 1, 2, 3};
  absurd.rss_dbm = {40.0, 40.0, 40.0, 40.0};  // about 1e4 nats below every particle's
  absurd.num_heard = 4;
  const TrackerEstimate e = tracker.Wifi(absurd);
  EXPECT_TRUE(std::isfinite(e.log_likelihood));
  EXPECT_LT(e.log_likelihood, -1000.0);
  EXPECT_TRUE(tracker.ParticleWeights().allFinite());
  EXPECT_NEAR(tracker.ParticleWeights().sum(), 1.0, 1e-9);
}

TEST_F(ParticleTrackerInRoom, SoftWallsAcceptAStartInsideAnObstacleAndPenaliseCrossings) {
  TrackerOptions o = SmallOptions(400);
  o.wall_log_penalty = std::log(0.1);
  ParticleTracker tracker(&plan, nullptr, nullptr, o);
  tracker.InitializeKnown(0.0, Eigen::Vector2d(10.0, 5.0), 0, 0.0);  // inside the block: accepted
  const TrackerEstimate e = tracker.Step(Step(0.5, 3.0, 0.0));      // crosses the block's edge
  EXPECT_GT(e.blocked_fraction, 0.95);
  EXPECT_NEAR(e.log_likelihood, std::log(0.1), 0.1);   // (nearly) every particle paid the penalty once
  EXPECT_NEAR(e.mean_m.x(), 13.0, 0.3);                // and moved through
  EXPECT_EQ(tracker.summary().all_blocked_steps, 0);
}

TEST_F(ParticleTrackerInRoom, RecoveryRedrawsWhenTheWifiKeepsDisagreeing) {
  TrackerOptions o = SmallOptions(1000);
  o.wifi.tempering = 0.5;
  o.recovery_scans = 2;
  ParticleTracker tracker(&plan, &model, nullptr, o);
  tracker.InitializeKnown(0.0, Eigen::Vector2d(3.0, 3.0), 0, 0.0);  // wrong: the walker is at (18, 8.5)
  TrackerEstimate e;
  for (int k = 1; k <= 12; ++k) {
    e = tracker.Step(Step(0.5 * k, 0.0, 0.0, 0.02));  // standing still
    e = tracker.Wifi(ScanAt(model, 0.5 * k, 18.0, 8.5));
  }
  EXPECT_GE(tracker.summary().recoveries, 1);
  EXPECT_LT((e.mean_m - Eigen::Vector2d(18.0, 8.5)).norm(), 2.0);
}

TEST_F(ParticleTrackerInRoom, EmptyScanIsANoOp) {
  ParticleTracker tracker(&plan, &model, nullptr, SmallOptions(300));
  tracker.InitializeKnown(0.0, Eigen::Vector2d(3.0, 3.0), 0, 0.0);
  const Eigen::VectorXd before = tracker.ParticleWeights();
  WifiObservation none;
  none.time_s = 1.0;
  tracker.Wifi(none);
  EXPECT_EQ(tracker.summary().empty_wifi_updates, 1);
  EXPECT_EQ(tracker.ParticleWeights(), before);
}

TEST_F(ParticleTrackerInRoom, RejectsBadInput) {
  ParticleTracker tracker(&plan, &model, nullptr, SmallOptions(100));
  EXPECT_THROW(tracker.Step(Step(0.0, 0.5, 0.0)), std::invalid_argument);  // not initialised
  EXPECT_THROW(tracker.InitializeKnown(0.0, Eigen::Vector2d(10.0, 5.0), 0, 0.0), std::invalid_argument);  // in the block
  EXPECT_THROW(tracker.InitializeKnown(0.0, Eigen::Vector2d(30.0, 5.0), 0, 0.0), std::invalid_argument);  // outside
  EXPECT_THROW(tracker.InitializeKnown(0.0, Eigen::Vector2d(3.0, 3.0), 5, 0.0), std::invalid_argument);   // no floor 5
  tracker.InitializeKnown(1.0, Eigen::Vector2d(3.0, 3.0), 0, 0.0);
  EXPECT_THROW(tracker.Step(Step(2.0, std::nan(""), 0.0)), std::invalid_argument);
  EXPECT_THROW(tracker.Step(Step(0.5, 0.5, 0.0)), std::invalid_argument);  // negative time step
  WifiObservation bad;
  bad.time_s = 2.0;
  bad.access_points = {7};
  bad.rss_dbm = {-50.0};
  EXPECT_THROW(tracker.Wifi(bad), std::invalid_argument);  // AP column out of range
  // A map on floor 3 with a plan on floor 0.
  RowMatrixXd pos(3, 2);
  pos << 0, 0, 1, 0, 0, 1;
  const wifi::SignalMap other(pos, Eigen::VectorXi::Constant(3, 3), RowMatrixXd::Constant(3, 1, -50.0),
                              RowMatrixXd::Constant(3, 1, 4.0));
  const wifi::RssModel other_model(other);
  EXPECT_THROW(ParticleTracker(&plan, &other_model, nullptr, SmallOptions(10)), std::invalid_argument);
  TrackerOptions bad_options;
  bad_options.num_particles = 0;
  EXPECT_THROW(ParticleTracker(&plan, nullptr, nullptr, bad_options), std::invalid_argument);
}

TEST_F(ParticleTrackerInRoom, SameSeedSameResultForAnyThreadCount) {
  std::vector<RowMatrixXd> results;
  for (int threads : {1, 2, 3}) {
    TrackerOptions o = SmallOptions(3 * ParticleTracker::kBlockSize + 17);
    o.num_threads = threads;
    o.start_position_sd_m = 1.0;
    ParticleTracker tracker(&plan, &model, nullptr, o);
    tracker.InitializeKnown(0.0, Eigen::Vector2d(3.0, 2.0), 0, 0.0);
    for (int k = 0; k < 12; ++k) {
      tracker.Step(Step(0.5 * (k + 1), 0.7, 0.1, 0.1));
      if (k % 3 == 2) tracker.Wifi(ScanAt(model, 0.5 * (k + 1), 3.0 + 0.7 * (k + 1), 2.0 + 0.1 * (k + 1)));
    }
    results.push_back(tracker.ParticleStates());
  }
  EXPECT_EQ(results[0], results[1]);
  EXPECT_EQ(results[0], results[2]);
}

TEST_F(ParticleTrackerInRoom, UnknownStartFindsTheWalkerFromWifiAndSteps) {
  TrackerOptions o = SmallOptions(4000);
  ParticleTracker tracker(&plan, &model, nullptr, o);
  Eigen::Vector2d truth(2.0, 8.5);
  tracker.InitializeUnknown(ScanAt(model, 0.0, truth.x(), truth.y()));
  TrackerEstimate e;
  // PDR heading offset unknown (uniform prior): walk east along y = 8.5, scan every 4 steps.
  for (int k = 0; k < 24; ++k) {
    truth.x() += 0.7;
    e = tracker.Step(Step(0.5 * (k + 1), 0.7, 0.0, 0.05));
    if (k % 4 == 3) e = tracker.Wifi(ScanAt(model, 0.5 * (k + 1), truth.x(), truth.y()));
  }
  EXPECT_LT((e.mean_m - truth).norm(), 1.5);
  EXPECT_LT(std::abs(e.heading_offset_rad), 0.3);
}

TEST_F(ParticleTrackerInRoom, CorridorModeFollowsTheNetworkAndTheHeading) {
  // An L of corridors: (2, 1.5) -> (2, 8.5) -> (18, 8.5), plus a dead-end spur (2, 8.5) -> (2, 9.5).
  RowMatrixXd segments(3, 4);
  segments << 2, 1.5, 2, 8.5, 2, 8.5, 18, 8.5, 2, 8.5, 2, 9.5;
  const mapmatch::RoadNetwork corridors(segments, Eigen::VectorXi(), mapmatch::RoadNetworkOptions());
  TrackerOptions o = SmallOptions(2000);
  o.corridor_kappa = 4.0;
  ParticleTracker tracker(&plan, &model, &corridors, o);
  tracker.InitializeKnown(0.0, Eigen::Vector2d(2.0, 1.5), 0, 0.0);
  Eigen::Vector2d truth(2.0, 1.5);
  TrackerEstimate e;
  for (int k = 0; k < 30; ++k) {
    const Eigen::Vector2d d = k < 10 ? Eigen::Vector2d(0.0, 0.7) : Eigen::Vector2d(0.7, 0.0);
    truth += d;
    e = tracker.Step(Step(0.5 * (k + 1), d.x(), d.y(), 0.03));
    // Every particle is on the network.
    const RowMatrixXd p = tracker.ParticleStates();
    for (Eigen::Index i = 0; i < p.rows(); i += 97) {
      ASSERT_LT(corridors.Nearest(p.row(i).head<2>().transpose()).distance_m, 1e-9);
    }
    if (k % 5 == 4) e = tracker.Wifi(ScanAt(model, 0.5 * (k + 1), truth.x(), truth.y()));
  }
  EXPECT_LT((e.mean_m - truth).norm(), 1.0);
  // Without corridors, SetParticles is available; in corridor mode it is refused.
  EXPECT_THROW(tracker.SetParticles(tracker.ParticleStates(), tracker.ParticleFloorIndices()), std::invalid_argument);
}

TEST(ParticleTracker, CorridorModeWithoutPlanOrMapStartsUniformlyAlongTheNetwork) {
  // Corridors only: the unknown start spreads the particles along the network (it used to index
  // the empty candidate list and crash).
  RowMatrixXd segments(2, 4);
  segments << 0, 0, 10, 0, 10, 0, 10, 30;
  const mapmatch::RoadNetwork corridors(segments, Eigen::VectorXi(), mapmatch::RoadNetworkOptions());
  TrackerOptions o = SmallOptions(4000);
  ParticleTracker tracker(nullptr, nullptr, &corridors, o);
  tracker.InitializeUnknown(WifiObservation());
  const RowMatrixXd p = tracker.ParticleStates();
  int on_long_segment = 0;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    ASSERT_LT(corridors.Nearest(p.row(i).head<2>().transpose()).distance_m, 1e-9);
    on_long_segment += p(i, 0) == 10.0 && p(i, 1) > 0.0;
  }
  EXPECT_NEAR(on_long_segment / 4000.0, 0.75, 0.03);  // 30 m of the 40 m
  const TrackerEstimate e = tracker.Step(Step(0.5, 0.0, 0.7, 0.01));
  EXPECT_TRUE(std::isfinite(e.mean_m.x()));
}

TEST(ParticleTracker, CorridorKappaHasTheSharedCorridorModelsLimit) {
  TrackerOptions o = SmallOptions(10);
  std::string error;
  o.corridor_kappa = mapmatch::kMaxCorridorKappa;
  EXPECT_TRUE(o.IsValid(&error)) << error;
  o.corridor_kappa = mapmatch::kMaxCorridorKappa + 1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("corridor_kappa"), std::string::npos) << error;
}

TEST_F(ParticleTrackerInRoom, FixedLagSmootherReportsThePositionLagStepsBack) {
  TrackerOptions o = SmallOptions(500);
  o.smoothing_lag_steps = 3;
  ParticleTracker tracker = KnownStartTracker(plan, o, Eigen::Vector2d(2.0, 1.5));
  std::vector<Eigen::Vector2d> means;
  for (int k = 0; k < 8; ++k) {
    const TrackerEstimate e = tracker.Step(Step(0.5 * (k + 1), 0.0, 0.7, 0.01));
    means.push_back(e.mean_m);
    if (k < 3) {
      EXPECT_TRUE(std::isnan(e.lagged_m.x()));
    } else {
      // No WiFi and no walls hit: the lagged estimate is the filter's estimate 3 steps back.
      EXPECT_NEAR((e.lagged_m - means[static_cast<size_t>(k - 3)]).norm(), 0.0, 0.05);
    }
  }
}

TEST_F(TrackInRoom, SmootherIsCloserToTheTruthThanTheFilterOnAverage) {
  TrackerOptions o = SmallOptions(2000);
  o.start_position_sd_m = 1.5;
  o.wifi.tempering = 0.3;
  Recording rec;
  std::vector<Eigen::Vector2d> truth;
  Eigen::Vector2d p(2.0, 1.5);
  RandomStream rng(5);
  for (int k = 0; k < 30; ++k) {
    const Eigen::Vector2d d = k < 10 ? Eigen::Vector2d(0.0, 0.7) : Eigen::Vector2d(0.7, 0.0);
    p += d;
    truth.push_back(p);
    rec.steps.push_back(Step(0.5 * (k + 1), d.x() + 0.05 * rng.Normal(), d.y() + 0.05 * rng.Normal(), 0.07));
    if (k % 3 == 0) {
      WifiObservation w = ScanAt(model, 0.5 * (k + 1), p.x(), p.y());
      for (double& v : w.rss_dbm) v += 3.0 * rng.Normal();
      rec.observations.push_back(w);
    }
  }
  TrackStart start;
  start.known = true;
  start.position_m = Eigen::Vector2d(2.0, 1.5);
  SmootherOptions so;
  so.num_trajectories = 50;
  const TrackResult r = Track(&plan, &model, nullptr, rec, start, o, so, /*smooth=*/true);
  ASSERT_EQ(r.estimates.size(), truth.size());
  ASSERT_EQ(r.smoothed.positions_m.rows(), static_cast<Eigen::Index>(truth.size()));
  double filter_error = 0.0, smoother_error = 0.0;
  for (size_t k = 0; k < truth.size(); ++k) {
    filter_error += (r.estimates[k].mean_m - truth[k]).norm() / static_cast<double>(truth.size());
    smoother_error += (r.smoothed.positions_m.row(static_cast<Eigen::Index>(k)).transpose() - truth[k]).norm() / static_cast<double>(truth.size());
    // Every smoothed trajectory point is walkable.
    for (int j = 0; j < so.num_trajectories; ++j) {
      ASSERT_TRUE(plan.IsWalkable(r.smoothed.trajectories_m(static_cast<Eigen::Index>(k), 2 * j),
                                  r.smoothed.trajectories_m(static_cast<Eigen::Index>(k), 2 * j + 1), 0));
    }
  }
  EXPECT_LT(filter_error, 1.0);
  EXPECT_LT(smoother_error, filter_error * 1.05);
}

// ---- Reliability: memory refused by size, events in time order, absurd states ----


TEST_F(ParticleTrackerInRoom, MemoryIsRefusedBySizeBeforeAllocating) {
  // 5e7 particles: ~4.8 GB of state (the smoother's history would come on top).
  TrackerOptions o = SmallOptions();
  o.num_particles = 50000000;
  o.record_history = true;
  ExpectInvalid([&] { ParticleTracker(&plan, nullptr, nullptr, o); }, {"'options'", "particles", "GB", "limit 4 GB"});
  // A fixed lag of 1e4 steps with 5e6 particles: 1.6 TB of lag ring.
  o.num_particles = 5000000;
  o.record_history = false;
  o.smoothing_lag_steps = 10000;
  ExpectInvalid([&] { ParticleTracker(&plan, nullptr, nullptr, o); }, {"smoothing_lag_steps = 10000", "TB"});
  // Track with the smoother: num_particles x steps of recorded clouds, before the run.
  o = SmallOptions();
  o.num_particles = 40000000;
  Recording rec;
  for (int k = 0; k < 10; ++k) rec.steps.push_back(Step(0.5 * (k + 1), 0.5, 0.0));
  TrackStart start;
  start.known = true;
  start.position_m = Eigen::Vector2d(2.0, 2.0);
  ExpectInvalid([&] { Track(&plan, nullptr, nullptr, rec, start, o, SmootherOptions(), true); },
                    {"recorded particles", "GB"});
  // 1e8 readings for MakeWifiObservations: refused from the shape alone (the bindings check the
  // array's shape before converting it).
  ExpectInvalid([] { RequireWifiReadingsMemory(1e4, 1e4); }, {"'rss_dbm'", "1e+08 readings", "GB"});
  EXPECT_NO_THROW(RequireWifiReadingsMemory(1e4, 100));
}

TEST_F(ParticleTrackerInRoom, EventsBeforeThePreviousOneAreRefusedWhateverTheirKind) {
  ParticleTracker tracker(&plan, &model, nullptr, SmallOptions(200));
  EXPECT_THROW(tracker.Estimate(), std::runtime_error);  // not initialised
  try {
    tracker.Estimate();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not initialised"), std::string::npos);
  }
  tracker.InitializeKnown(1.0, Eigen::Vector2d(3.0, 3.0), 0, 0.0);
  EXPECT_EQ(tracker.Estimate().time_s, 1.0);
  // Before the start.
  ExpectInvalid([&] { tracker.Wifi(ScanAt(model, 0.5, 3.0, 3.0)); }, {"observation.time_s", "back in time"});
  PositionFix fix;
  fix.time_s = 0.5;
  fix.means_m = RowMatrixXd::Constant(1, 2, 3.0);
  fix.sds_m = Eigen::VectorXd::Constant(1, 1.0);
  fix.weights = Eigen::VectorXd::Constant(1, 1.0);
  ExpectInvalid([&] { tracker.Fix(fix); }, {"fix.time_s", "back in time"});
  // After a scan at 3 s, neither a step nor a fix at 2 s.
  tracker.Step(Step(2.0, 0.5, 0.0));
  tracker.Wifi(ScanAt(model, 3.0, 3.5, 3.0));
  ExpectInvalid([&] { tracker.Step(Step(2.5, 0.5, 0.0)); }, {"step.time_s"});
  fix.time_s = 2.5;
  ExpectInvalid([&] { tracker.Fix(fix); }, {"fix.time_s"});
  fix.time_s = 3.0;  // equal times are fine
  EXPECT_NO_THROW(tracker.Fix(fix));
  EXPECT_EQ(tracker.Estimate().time_s, 3.0);
}

TEST_F(ParticleTrackerInRoom, SetParticlesRefusesAbsurdStates) {
  ParticleTracker tracker(&plan, nullptr, nullptr, SmallOptions(10));
  RowMatrixXd states(2, 4);
  states << 3.0, 3.0, 0.0, 1.0, 4.0, 3.0, 0.1, 1.0;
  const Eigen::VectorXi floors = Eigen::VectorXi::Zero(2);
  EXPECT_NO_THROW(tracker.SetParticles(states, floors));
  RowMatrixXd bad = states;
  bad(1, 0) = 1e300;
  ExpectInvalid([&] { tracker.SetParticles(bad, floors); }, {"'states'", "entry (1, 0)", "1e+300"});
  bad = states;
  bad(0, 2) = 1e300;
  ExpectInvalid([&] { tracker.SetParticles(bad, floors); }, {"'states'", "entry (0, 2)", "heading offset"});
  bad = states;
  bad(1, 3) = 1e6;  // scale outside [min_scale, max_scale]
  ExpectInvalid([&] { tracker.SetParticles(bad, floors); }, {"'states'", "entry (1, 3)", "scale"});
  bad = states;
  bad.row(0) << 10.0, 5.0, 0.0, 1.0;  // inside the block, hard walls
  ExpectInvalid([&] { tracker.SetParticles(bad, floors); }, {"'states'", "row 0", "not walkable"});
  // With soft walls a particle inside an obstacle is only unlikely.
  TrackerOptions soft = SmallOptions(10);
  soft.wall_log_penalty = -5.0;
  ParticleTracker soft_tracker(&plan, nullptr, nullptr, soft);
  EXPECT_NO_THROW(soft_tracker.SetParticles(bad, floors));
}

TEST_F(TrackInRoom, StepsBeforeAKnownStartDoNotMoveTheCloud) {
  Recording rec;
  for (int k = 0; k < 10; ++k) rec.steps.push_back(Step(0.5 * (k + 1), 0.5, 0.0));
  TrackStart start;
  start.known = true;
  start.time_s = 2.2;  // after the first four steps
  start.position_m = Eigen::Vector2d(3.0, 5.0);
  TrackerOptions o = SmallOptions(500);
  SmootherOptions so;
  so.num_trajectories = 20;
  const TrackResult r = Track(&plan, nullptr, nullptr, rec, start, o, so, true);
  ASSERT_EQ(r.estimates.size(), 10u);
  ASSERT_EQ(r.smoothed.positions_m.rows(), 10);
  ASSERT_EQ(r.smoothed.trajectories_m.rows(), 10);
  EXPECT_EQ(r.summary.steps, 6);  // four skipped
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(r.estimates[k].mean_m.x(), 3.0, 0.1) << k;  // the start cloud
    EXPECT_EQ(r.estimates[k].time_s, 0.5 * (k + 1));
    EXPECT_NEAR(r.smoothed.positions_m(k, 0), r.estimates[k].mean_m.x(), 1e-12);
  }
  EXPECT_NEAR(r.estimates[9].mean_m.x(), 3.0 + 6 * 0.5, 0.3);  // six steps taken
  // Every step before the start: nothing to smooth, the start cloud throughout.
  start.time_s = 100.0;
  const TrackResult all = Track(&plan, nullptr, nullptr, rec, start, o, so, true);
  EXPECT_EQ(all.summary.steps, 0);
  EXPECT_EQ(all.smoothed.positions_m.rows(), 10);
}

}  // namespace
}  // namespace indoorloc::fusion
