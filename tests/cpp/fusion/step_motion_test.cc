// Tests of the step motion model (step_motion.h): a polar step's covariance is the Jacobian
// propagation, samples have the model's mean and covariance, the transition density is the
// model's Gaussian, bad steps are refused.
#include "indoorloc/fusion/step_motion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "expect_invalid.h"
#include "room_fixture.h"

#include "indoorloc/core/random.h"

namespace indoorloc::fusion {
namespace {

TEST(StepMotion, PolarStepMatchesJacobianPropagation) {
  const StepInput s = StepFromPolar(1.0, 0.7, 0.5, 0.05, 0.1);
  EXPECT_NEAR(s.displacement_m.x(), 0.7 * std::cos(0.5), 1e-12);
  EXPECT_NEAR(s.displacement_m.y(), 0.7 * std::sin(0.5), 1e-12);
  // Variance along the heading is σ_L², across it (L σ_h)².
  const Eigen::Vector2d along(std::cos(0.5), std::sin(0.5)), across(-std::sin(0.5), std::cos(0.5));
  EXPECT_NEAR(along.dot(s.covariance_m2 * along), 0.05 * 0.05, 1e-12);
  EXPECT_NEAR(across.dot(s.covariance_m2 * across), 0.07 * 0.07, 1e-12);
}

TEST(StepMotion, SamplesHaveTheModelMeanAndCovariance) {
  StepMotionOptions o;
  o.heading_offset_walk_rad = 1e-9;
  o.scale_walk = 1e-9;
  o.position_noise_m = 0.05;
  const StepInput s = Step(0.0, 0.7, 0.0, 0.1);
  const StepMotion motion(s, o);
  RandomStream rng(3);
  const int n = 200000;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  std::vector<Eigen::Vector2d> draws(n);
  for (int i = 0; i < n; ++i) {
    double no, ns;
    motion.Sample(M_PI / 2, 1.2, rng, &no, &ns, &draws[i]);
    mean += draws[i] / n;
  }
  for (const auto& d : draws) cov += (d - mean) * (d - mean).transpose() / n;
  // Rotated by 90 degrees and scaled by 1.2: mean (0, 0.84), covariance 1.44 (0.1² + 0.05²) I.
  EXPECT_NEAR(mean.x(), 0.0, 2e-3);
  EXPECT_NEAR(mean.y(), 0.84, 2e-3);
  const double v = 1.44 * (0.01 + 0.0025);
  EXPECT_NEAR(cov(0, 0), v, 0.03 * v);
  EXPECT_NEAR(cov(1, 1), v, 0.03 * v);
}

TEST(StepMotion, TransitionDensityIsTheGaussianOfTheModel) {
  StepMotionOptions o;
  const StepInput s = Step(0.0, 0.6, 0.2, 0.1);
  const StepMotion motion(s, o);
  const Eigen::Vector2d from(1.0, 2.0);
  const double off = 0.3, sc = 1.1;
  // The mean successor has the highest density among successors with the same (o', s').
  const Eigen::Matrix2d r = Eigen::Rotation2Dd(off).toRotationMatrix();
  const Eigen::Vector2d to = from + sc * r * s.displacement_m;
  const double at_mean = motion.TransitionLogDensity(from, off, sc, to, off, sc);
  EXPECT_NEAR(at_mean, 0.0, 1e-12);
  // Off by one standard deviation along x of the step frame: -1/2.
  const double sd = std::sqrt(0.01 + o.position_noise_m * o.position_noise_m);
  const Eigen::Vector2d to1 = from + sc * r * (s.displacement_m + Eigen::Vector2d(sd, 0.0));
  EXPECT_NEAR(motion.TransitionLogDensity(from, off, sc, to1, off, sc), -0.5, 1e-9);
  // The offset walk: one σ_o of offset change costs -1/2 (position term evaluated at o').
  const Eigen::Matrix2d r2 = Eigen::Rotation2Dd(off + o.heading_offset_walk_rad).toRotationMatrix();
  const Eigen::Vector2d to2 = from + sc * r2 * s.displacement_m;
  EXPECT_NEAR(motion.TransitionLogDensity(from, off, sc, to2, off + o.heading_offset_walk_rad, sc), -0.5, 1e-9);
}

TEST(StepMotion, RejectsBadSteps) {
  StepInput s = Step(0.0, std::nan(""), 0.0);
  EXPECT_THROW(CheckStepInput(s, "step"), std::invalid_argument);
  s = Step(0.0, 0.5, 0.0);
  s.covariance_m2(0, 1) = 1.0;
  EXPECT_THROW(CheckStepInput(s, "step"), std::invalid_argument);  // not symmetric
  s.covariance_m2 << 1.0, 2.0, 2.0, 1.0;
  EXPECT_THROW(CheckStepInput(s, "step"), std::invalid_argument);  // indefinite
}

}  // namespace
}  // namespace indoorloc::fusion
