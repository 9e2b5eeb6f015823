#include "indoorloc/mapmatch/particle_map_matcher.h"

#include <array>
#include <cmath>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "indoorloc/mapmatch/monte_carlo.h"
#include "indoorloc/mapmatch/trajectory_simulator.h"

namespace indoorloc::mapmatch {
namespace {

// A 3 x 2 grid of 10 m cells, split at every node (17 segments), plus one diagonal.
RoadNetwork Grid() {
  std::vector<std::array<double, 4>> rows;
  for (int y = 0; y <= 20; y += 10)
    for (int x = 0; x < 30; x += 10) rows.push_back({double(x), double(y), double(x + 10), double(y)});
  for (int x = 0; x <= 30; x += 10)
    for (int y = 0; y < 20; y += 10) rows.push_back({double(x), double(y), double(x), double(y + 10)});
  rows.push_back({10, 0, 20, 10});
  RowMatrixXd m(static_cast<Eigen::Index>(rows.size()), 4);
  for (size_t r = 0; r < rows.size(); ++r) m.row(static_cast<Eigen::Index>(r)) << rows[r][0], rows[r][1], rows[r][2], rows[r][3];
  return RoadNetwork(m, Eigen::VectorXi());
}

bool OnNetwork(const RoadNetwork& net, const ParticleMapMatcher& pf) {
  for (size_t i = 0; i < pf.particle_segments().size(); ++i) {
    const int s = pf.particle_segments()[i];
    const double u = pf.particle_along_m()[i];
    if (s < 0 || s >= net.num_segments() || u < 0.0 || u > net.lengths_m()[s]) return false;
  }
  return true;
}

// One particle, no step noise and no recovery: its move is the motion model's alone.
FilterOptions OneNoiselessParticle() {
  FilterOptions options;
  options.num_particles = 1;
  options.noise_halfwidth_m = 0.0;
  options.recovery_disagreement = 0.0;
  return options;
}

TEST(ParticleMapMatcher, PropagationKeepsParticlesOnTheNetwork) {
  const RoadNetwork net = Grid();
  FilterOptions options;
  options.num_particles = 3000;
  options.noise_halfwidth_m = 3.0;  // large moves cross several junctions
  ParticleMapMatcher pf(net, options);
  EXPECT_TRUE(OnNetwork(net, pf));
  for (int k = 0; k < 100; ++k) {
    pf.Step(7.0, 0.3 * k, 1.0);
    ASSERT_TRUE(OnNetwork(net, pf)) << "step " << k;
  }
}

TEST(ParticleMapMatcher, ConservesDistanceAcrossJunctionsAndUsesOnlyConnectedSegments) {
  const RoadNetwork net = Grid();
  FilterOptions options = OneNoiselessParticle();
  std::set<int> reached;
  for (std::uint64_t seed = 0; seed < 40; ++seed) {
    options.seed = seed;
    ParticleMapMatcher pf(net, options);
    // Segment 0 = (0,0)-(10,0), forward, 2 m before its end B at (10, 0); move 5 m.
    pf.SetParticles({0}, {1}, {8.0});
    pf.Step(5.0, 0.0, 1.0);
    const int s = pf.particle_segments()[0];
    const double u = pf.particle_along_m()[0];
    const int d = pf.particle_directions()[0];
    bool connected = false;
    for (const Continuation& c : net.continuations(0, 1)) connected |= c.segment == s;
    ASSERT_TRUE(connected) << "moved onto segment " << s;
    // 3 m travelled on the new segment from the junction end it entered.
    const double from_entry = d > 0 ? u : net.lengths_m()[s] - u;
    EXPECT_NEAR(from_entry, 3.0, 1e-12);
    EXPECT_NEAR((net.point_at(s, u) - Eigen::Vector2d(10, 0)).norm(), 3.0, 1e-9);
    reached.insert(s);
  }
  EXPECT_GE(reached.size(), 2u);  // several continuations were chosen
}

// Eq. 8-9 have no floor: a negative step v Δt + η moves a particle back within its segment (a
// floor at 0 biased the filter forward); it stops at the end behind it, same segment and direction.
TEST(ParticleMapMatcher, NegativeStepMovesBackAndStopsAtTheEndBehind) {
  const RoadNetwork net = Grid();
  FilterOptions options = OneNoiselessParticle();
  ParticleMapMatcher pf(net, options);
  pf.SetParticles({1}, {-1}, {2.0});  // segment (10,0)-(20,0), facing A
  pf.Step(-3.0, 0.0, 1.0);
  EXPECT_EQ(pf.particle_segments()[0], 1);
  EXPECT_EQ(pf.particle_directions()[0], -1);
  EXPECT_NEAR(pf.particle_along_m()[0], 5.0, 1e-12);
  for (int d : {1, -1}) {
    pf.SetParticles({1}, {static_cast<signed char>(d)}, {d > 0 ? 2.0 : 8.0});  // 2 m past the end behind
    pf.Step(-5.0, 0.0, 1.0);
    EXPECT_EQ(pf.particle_segments()[0], 1);
    EXPECT_EQ(pf.particle_directions()[0], d);
    EXPECT_EQ(pf.particle_along_m()[0], d > 0 ? 0.0 : 10.0);
  }
}

TEST(ParticleMapMatcher, WeightsNeverNaNWhenEveryLikelihoodUnderflows) {
  const RoadNetwork net = Grid();
  FilterOptions options;
  options.num_particles = 500;
  options.kappa = 300.0;  // exp(-600) per mismatching step
  ParticleMapMatcher pf(net, options);
  // Everyone moves east on an east-west corridor, but the compass says "north-west" forever.
  for (int k = 0; k < 50; ++k) {
    const StepEstimate e = pf.Step(1.0, 2.3, 0.5);
    ASSERT_TRUE(std::isfinite(e.log_likelihood));
    ASSERT_TRUE(e.position_m.allFinite());
    const Eigen::VectorXd w = pf.ParticleWeights();
    ASSERT_TRUE(w.allFinite());
    ASSERT_NEAR(w.sum(), 1.0, 1e-9);
  }
  EXPECT_NEAR(pf.SegmentPosterior().sum(), 1.0, 1e-9);
}

TEST(ParticleMapMatcher, EstimateLiesOnTheNetworkAndTracksASimulatedRun) {
  const RoadNetwork net = Grid();
  TrajectoryOptions to;
  to.duration_s = 120.0;
  to.dt_s = 0.1;
  to.heading_kappa = 5.0;
  RandomStream rng(5);
  const Trajectory t = SimulateTrajectory(net, to, rng);
  FilterOptions options;
  options.num_particles = 4000;
  options.kappa = 2.0;
  options.noise_halfwidth_m = 0.27;
  options.estimate_speed_bias = true;
  ParticleMapMatcher pf(net, options);
  const std::vector<StepEstimate> e = RunFilter(pf, t.speed_mps, t.heading_rad, to.dt_s);
  double late_error = 0.0;
  int late = 0;
  for (size_t k = 0; k < e.size(); ++k) {
    ASSERT_LT(net.Nearest(e[k].position_m).distance_m, 1e-9);  // on a segment
    if (k >= e.size() - 200) {
      late_error += (e[k].position_m - t.positions_m.row(static_cast<Eigen::Index>(k)).transpose()).norm();
      ++late;
    }
  }
  EXPECT_LT(late_error / late, 3.0);
}

TEST(ParticleMapMatcher, BadInputGivesClearErrors) {
  const RoadNetwork net = Grid();
  FilterOptions options;
  options.num_particles = 0;
  EXPECT_THROW(ParticleMapMatcher(net, options), std::invalid_argument);
  options.num_particles = 10;
  ParticleMapMatcher pf(net, options);
  EXPECT_THROW(pf.Step(std::nan(""), 0.0, 0.1), std::invalid_argument);
  EXPECT_THROW(pf.Step(1.0, std::nan(""), 0.1), std::invalid_argument);
  EXPECT_THROW(pf.Step(1.0, 0.0, -0.1), std::invalid_argument);
  EXPECT_THROW(pf.SetParticles({0}, {1}, {0.0}), std::invalid_argument);  // wrong count
}

TEST(MonteCarlo, SameSeedSameResultsWhateverTheThreadCount) {
  const RoadNetwork net = Grid();
  TrajectoryOptions to;
  to.duration_s = 20.0;
  FilterOptions options;
  options.num_particles = 300;
  const auto one = RunMonteCarlo(net, to, options, 6, 11, 1);
  const auto two = RunMonteCarlo(net, to, options, 6, 11, 2);
  ASSERT_EQ(one.size(), two.size());
  for (size_t r = 0; r < one.size(); ++r) {
    EXPECT_EQ(one[r].error_m, two[r].error_m);
    EXPECT_EQ(one[r].correct_segment, two[r].correct_segment);
  }
}

// Issue 17: a huge heading_kappa reached the von Mises rejection loop, which never returned
// above about 3e16; infinite noise passed ">= 0" and gave inf positions.
TEST(TrajectorySimulator, HugeKappaIsFastAndNonFiniteNoiseIsRefused) {
  const RoadNetwork net = Grid();
  TrajectoryOptions t;
  t.duration_s = 20.0;
  t.heading_kappa = 1e300;
  RandomStream rng(3);
  const Trajectory tr = SimulateTrajectory(net, t, rng);
  EXPECT_TRUE(tr.heading_rad.allFinite());
  for (Eigen::Index k = 0; k < tr.heading_rad.size(); ++k) {
    const double d = tr.heading_rad[k] - tr.heading_true_rad[k];
    EXPECT_LT(std::abs(std::atan2(std::sin(d), std::cos(d))), 1e-9) << k;
  }
  for (const double bad : {double(INFINITY), std::nan(""), 1e300}) {
    TrajectoryOptions o;
    o.speed_noise_sd_mps = bad;
    std::string error;
    EXPECT_FALSE(o.IsValid(&error)) << bad;
    EXPECT_EQ(error.rfind("speed_noise_sd_mps must be in [0, 1e+06], got ", 0), 0u) << error;
  }
}

// Issue 17: junction_kappa = 1e300 was reported as "'heading_rad' gives zero likelihood".
TEST(ParticleMapMatcher, HugeJunctionKappaIsRefusedByName) {
  FilterOptions o;
  o.junction_kappa = 1e300;
  std::string error;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "junction_kappa must be in [0, 300], got 1e+300");
}

}  // namespace
}  // namespace indoorloc::mapmatch
