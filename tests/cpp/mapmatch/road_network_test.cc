#include "indoorloc/mapmatch/road_network.h"

#include <cmath>
#include <array>
#include <limits>

#include <gtest/gtest.h>

#include "indoorloc/core/random.h"

namespace indoorloc::mapmatch {
namespace {

RowMatrixXd Segments(std::initializer_list<std::array<double, 4>> rows) {
  RowMatrixXd m(static_cast<Eigen::Index>(rows.size()), 4);
  Eigen::Index r = 0;
  for (const auto& row : rows) m.row(r++) << row[0], row[1], row[2], row[3];
  return m;
}

TEST(RoadNetwork, ConnectivityAtSharedEndsAndDeadEnds) {
  // A T: 0 = (0,0)-(10,0), 1 = (10,0)-(20,0), 2 = (10,0)-(10,10) (end B of 2 is a dead end).
  RoadNetwork net(Segments({{0, 0, 10, 0}, {10, 0, 20, 0}, {10, 0, 10, 10}}), Eigen::VectorXi());
  EXPECT_EQ(net.num_segments(), 3);
  EXPECT_NEAR(net.total_length_m(), 30.0, 1e-12);
  EXPECT_NEAR(net.headings_rad()[2], M_PI / 2, 1e-12);
  const auto& at_junction = net.continuations(0, 1);
  ASSERT_EQ(at_junction.size(), 2u);
  EXPECT_EQ(at_junction[0].segment, 1);
  EXPECT_EQ(at_junction[0].enter_end, 0);
  EXPECT_EQ(at_junction[1].segment, 2);
  // Dead ends turn back onto the same segment.
  ASSERT_EQ(net.continuations(2, 1).size(), 1u);
  EXPECT_EQ(net.continuations(2, 1)[0].segment, 2);
  EXPECT_EQ(net.dangling_ends().size(), 3u);  // (0,A), (1,B), (2,B)
  EXPECT_EQ(net.num_components(), 1);
  EXPECT_NE(net.Report().find("3 dangling end"), std::string::npos);
}

TEST(RoadNetwork, ComponentsAndSplitting) {
  RoadNetwork two(Segments({{0, 0, 1, 0}, {5, 5, 6, 5}}), Eigen::VectorXi());
  EXPECT_EQ(two.num_components(), 2);
  EXPECT_NE(two.Report().find("disconnected"), std::string::npos);
  // A cross and a T-junction, split on request.
  RoadNetworkOptions options;
  options.split_at_intersections = true;
  RoadNetwork cross(Segments({{0, 5, 10, 5}, {5, 0, 5, 10}, {10, 0, 10, 5}}), Eigen::VectorXi(), options);
  EXPECT_EQ(cross.num_segments(), 5);  // horizontal split at x = 5; vertical split at y = 5
  EXPECT_EQ(cross.num_components(), 1);
  EXPECT_EQ(cross.ids()[0], 1);
  EXPECT_EQ(cross.ids()[1], 1);  // pieces keep the id of their segment
}

TEST(RoadNetwork, NearestMatchesBruteForce) {
  RowMatrixXd segs(60, 4);
  RandomStream rng(3);
  for (int i = 0; i < 60; ++i) {
    const double x = rng.Uniform(0, 100), y = rng.Uniform(0, 50);
    segs.row(i) << x, y, x + rng.Uniform(1, 10), y + rng.Uniform(-5, 5);
  }
  RoadNetwork net(segs, Eigen::VectorXi());
  for (int q = 0; q < 500; ++q) {
    const Eigen::Vector2d p(rng.Uniform(-20, 120), rng.Uniform(-20, 70));
    double best = std::numeric_limits<double>::infinity();
    for (int s = 0; s < net.num_segments(); ++s) best = std::min(best, net.ProjectOnto(s, p).distance_m);
    EXPECT_NEAR(net.Nearest(p).distance_m, best, 1e-9);
  }
}

TEST(RoadNetwork, BadInputGivesClearErrors) {
  EXPECT_THROW(RoadNetwork(RowMatrixXd(0, 4), Eigen::VectorXi()), std::invalid_argument);
  try {
    Eigen::VectorXi ids(2);
    ids << 7, 9;
    RoadNetwork(Segments({{0, 0, 1, 0}, {3, 3, 3, 3}}), ids);
    FAIL() << "zero-length segment accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("segment id 9"), std::string::npos);
  }
  Eigen::VectorXi dup(2);
  dup << 4, 4;
  EXPECT_THROW(RoadNetwork(Segments({{0, 0, 1, 0}, {1, 0, 2, 0}}), dup), std::invalid_argument);
  EXPECT_THROW(RoadNetwork(Segments({{0, 0, std::nan(""), 0}}), Eigen::VectorXi()), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::mapmatch
