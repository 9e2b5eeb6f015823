#include "indoorloc/mapmatch/corridor_motion.h"

#include <array>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace indoorloc::mapmatch {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A plus-shaped junction at the origin: four 10 m arms, each from the centre outwards, plus a
// 10 m lead-in (-20, 0) -> (-10, 0) ending at the west arm's far end.
RoadNetwork Plus() {
  RowMatrixXd m(5, 4);
  m << 0, 0, 10, 0,   // 0: east arm
      0, 0, 0, 10,    // 1: north arm
      0, 0, -10, 0,   // 2: west arm
      0, 0, 0, -10,   // 3: south arm
      -20, 0, -10, 0; // 4: lead-in onto the west arm's end B
  return RoadNetwork(m, Eigen::VectorXi());
}

TEST(CorridorMotionOptions, ValidatesKappaAndJunctionKappa) {
  std::string error;
  EXPECT_TRUE(CorridorMotionOptions().IsValid(&error)) << error;
  CorridorMotionOptions o;
  o.kappa = kMaxCorridorKappa;
  EXPECT_TRUE(o.IsValid(&error)) << error;
  o.kappa = kMaxCorridorKappa + 1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("kappa"), std::string::npos) << error;
  o.kappa = -0.1;
  EXPECT_FALSE(o.IsValid(&error));
  o.kappa = std::nan("");
  EXPECT_FALSE(o.IsValid(&error));
  o = CorridorMotionOptions();
  o.junction_kappa = 1e300;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("junction_kappa"), std::string::npos) << error;
  const RoadNetwork net = Plus();
  EXPECT_THROW(CorridorMotion(net, o), std::invalid_argument);
}

TEST(CorridorMotion, MovesWithinASegmentWithoutDrawing) {
  const RoadNetwork net = Plus();
  const CorridorMotion motion(net, CorridorMotionOptions());
  RandomStream rng(1), copy(1);
  int s = 0;
  signed char d = 1;
  double u = 2.0;
  EXPECT_EQ(motion.Move(&s, &d, &u, 3.5, 0.0, rng), 1.0);
  EXPECT_EQ(s, 0);
  EXPECT_EQ(d, 1);
  EXPECT_DOUBLE_EQ(u, 5.5);
  d = -1;  // backward travel decreases u
  motion.Move(&s, &d, &u, 1.5, 0.0, rng);
  EXPECT_DOUBLE_EQ(u, 4.0);
  EXPECT_EQ(rng(), copy());  // no junction: no random draw
}

TEST(CorridorMotion, CarriesTheLeftoverOntoAConnectedSegment) {
  const RoadNetwork net = Plus();
  const CorridorMotion motion(net, CorridorMotionOptions());
  std::map<int, int> reached;
  for (std::uint64_t seed = 0; seed < 200; ++seed) {
    RandomStream rng(seed);
    // East arm travelled backward (towards the centre), 1 m from it; move 4 m: 3 m past the centre.
    int s = 0;
    signed char d = -1;
    double u = 1.0;
    EXPECT_EQ(motion.Move(&s, &d, &u, 4.0, 0.0, rng), 1.0);  // uniform policy: no correction
    ASSERT_GE(s, 1);
    ASSERT_LE(s, 3);  // another arm, entered at the centre (its end A): travelling outwards
    EXPECT_EQ(d, 1);
    EXPECT_NEAR(u, 3.0, 1e-12);
    ++reached[s];
  }
  EXPECT_EQ(reached.size(), 3u);
  for (const auto& [segment, count] : reached) EXPECT_GT(count, 40) << "segment " << segment;  // ~67 each
}

TEST(CorridorMotion, ANegativeDistanceStopsAtTheEndBehind) {
  const RoadNetwork net = Plus();
  const CorridorMotion motion(net, CorridorMotionOptions());
  RandomStream rng(3);
  int s = 4;
  signed char d = 1;
  double u = 2.0;
  EXPECT_EQ(motion.Move(&s, &d, &u, -5.0, 0.0, rng), 1.0);
  EXPECT_EQ(s, 4);
  EXPECT_EQ(d, 1);
  EXPECT_EQ(u, 0.0);
}

TEST(CorridorMotion, HeadingAwareJunctionsFollowTheProposalAndAreImportanceCorrected) {
  const RoadNetwork net = Plus();
  CorridorMotionOptions o;
  o.junction_policy = JunctionPolicy::kHeadingAware;
  o.junction_kappa = 2.0;
  const CorridorMotion motion(net, o);
  const double heading = kPi / 2;  // north
  // Proposal over the continuations of the east arm's end A: north, west, south arms outwards.
  const std::array<double, 3> headings = {kPi / 2, kPi, -kPi / 2};
  std::array<double, 3> q{};
  double total = 0.0;
  for (int j = 0; j < 3; ++j) total += q[j] = std::exp(2.0 * (std::cos(heading - headings[j]) - 1.0));
  const int draws = 20000;
  std::array<int, 3> count{};
  double mean_importance = 0.0;
  RandomStream rng(9);
  for (int k = 0; k < draws; ++k) {
    int s = 0;
    signed char d = -1;
    double u = 0.5;
    const double w = motion.Move(&s, &d, &u, 1.0, heading, rng);
    ASSERT_GE(s, 1);
    ++count[static_cast<size_t>(s - 1)];
    EXPECT_NEAR(w, (total / q[static_cast<size_t>(s - 1)]) / 3.0, 1e-12);
    mean_importance += w / draws;
  }
  for (int j = 0; j < 3; ++j) EXPECT_NEAR(count[j] / double(draws), q[j] / total, 0.015) << "arm " << j + 1;
  // E_q[prior / proposal] = 1: the correction leaves the posterior unchanged.
  EXPECT_NEAR(mean_importance, 1.0, 0.03);
}

TEST(CorridorMotion, HeadingLikelihoodIsANormalisedVonMisesDensity) {
  const RoadNetwork net = Plus();
  for (double kappa : {0.0, 1.0, 50.0, kMaxCorridorKappa}) {
    CorridorMotionOptions o;
    o.kappa = kappa;
    const CorridorMotion motion(net, o);
    // Trapezoid rule over the circle (exact to rounding for a smooth periodic integrand).
    const int n = 20000;
    double integral = 0.0;
    for (int k = 0; k < n; ++k) integral += std::exp(motion.LogHeadingLikelihood(1, -1, -kPi + 2 * kPi * k / n));
    EXPECT_NEAR(integral * 2 * kPi / n, 1.0, 1e-9) << "kappa " << kappa;
    // The mode is the direction of travel: north arm backward = south.
    EXPECT_NEAR(motion.LogHeadingLikelihood(1, -1, -kPi / 2), kappa - motion.log_normaliser(), 1e-9);
    // The tables are the same density relative to its maximum.
    std::vector<double> factor(2 * 5), disagreement(2 * 5);
    motion.HeadingTables(0.3, factor.data(), disagreement.data());
    for (int s = 0; s < 5; ++s) {
      for (int d : {-1, 1}) {
        const size_t key = static_cast<size_t>(2 * s + (d > 0));
        EXPECT_NEAR(std::log(factor[key]), motion.LogHeadingLikelihood(s, d, 0.3) + motion.log_normaliser() - kappa,
                    1e-9 * (1 + kappa));
        EXPECT_GE(disagreement[key], 0.0);
        EXPECT_LE(disagreement[key], 2.0);
      }
    }
  }
}

}  // namespace
}  // namespace indoorloc::mapmatch
