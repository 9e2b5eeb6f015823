// Tests of the streaming step detector: on a hand-held gait (vertical acceleration at 2 steps/s,
// heading known) it finds the steps with the right heading; fed sample by sample it equals
// CausalSteps, and a prefix of the samples gives the first steps of the whole run (causal);
// samples out of order and bad options are refused, the detector unchanged.
#include "indoorloc/pdr/streaming_step_detector.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace indoorloc::pdr {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A phone held flat, pointing (its +y axis) along `heading_rad` (east = 0, counter-clockwise),
// walking at `cadence_hz` steps per second: |a| = g + 2 sin(2 pi f t), 50 Hz, no rotation.
struct HandGait {
  Eigen::VectorXd t;
  Eigen::MatrixXd acc, gyro, quat;
};

HandGait MakeHandGait(double seconds, double cadence_hz, double heading_rad) {
  const double rate = 50.0;
  const int n = static_cast<int>(seconds * rate);
  HandGait g;
  g.t.resize(n);
  g.acc.resize(n, 3);
  g.gyro = Eigen::MatrixXd::Zero(n, 3);
  g.quat.resize(n, 4);
  // Rotation about the vertical by (heading - pi/2) puts the device +y axis at `heading`.
  const double yaw = heading_rad - kPi / 2;
  for (int i = 0; i < n; ++i) {
    g.t[i] = 100.0 + i / rate;
    g.acc.row(i) << 0.0, 0.0, 9.80665 + 2.0 * std::sin(2 * kPi * cadence_hz * (i / rate));
    g.quat.row(i) << 0.0, 0.0, std::sin(yaw / 2), std::cos(yaw / 2);
  }
  return g;
}

TEST(StreamingStepDetector, FindsTheStepsAndTheirHeading) {
  const HandGait g = MakeHandGait(20.0, 2.0, 0.7);
  const std::vector<StreamingStep> steps = CausalSteps(g.t, g.acc, g.gyro, g.quat);
  EXPECT_NEAR(static_cast<double>(steps.size()), 40.0, 2.0);
  for (std::size_t k = 1; k < steps.size(); ++k) {
    EXPECT_NEAR(steps[k].time_s - steps[k - 1].time_s, 0.5, 0.03);
    EXPECT_NEAR(steps[k].heading_rotation_vector_rad, 0.7, 1e-9);
    EXPECT_NEAR(steps[k].heading_gyro_rad, 0.7, 1e-9);
    EXPECT_GT(steps[k].feature, 0.5);
  }
}

TEST(StreamingStepDetector, SampleBySampleEqualsTheBatchAndIsCausal) {
  const HandGait g = MakeHandGait(12.0, 1.8, -2.0);
  const std::vector<StreamingStep> all = CausalSteps(g.t, g.acc, g.gyro, g.quat);
  StreamingStepDetector d;
  std::vector<StreamingStep> got;
  const Eigen::Index cut = g.t.size() / 2;
  for (Eigen::Index i = 0; i < g.t.size(); ++i) {
    d.AddSample(g.t[i], g.acc.row(i).transpose(), g.gyro.row(i).transpose(), g.quat.row(i).transpose(), &got);
    if (i == cut - 1) {
      ASSERT_GT(got.size(), 0u);
      ASSERT_LT(got.size(), all.size());
      EXPECT_LE(got.back().time_s, g.t[i] - d.options().min_step_interval_s + 1e-9);
    }
  }
  ASSERT_EQ(got.size(), all.size());
  for (std::size_t k = 0; k < all.size(); ++k) {
    EXPECT_EQ(got[k].time_s, all[k].time_s);
    EXPECT_EQ(got[k].feature, all[k].feature);
    EXPECT_EQ(got[k].heading_complementary_rad, all[k].heading_complementary_rad);
  }
  EXPECT_NEAR(d.rate_hz(), 50.0, 1e-6);
}

TEST(StreamingStepDetector, RefusesBadInputAndStaysUnchanged) {
  StreamingStepDetector d;
  const Eigen::Vector3d a(0, 0, 9.8), w = Eigen::Vector3d::Zero();
  const Eigen::Vector4d q(0, 0, 0, 1);
  d.AddSample(1.0, a, w, q, nullptr);
  EXPECT_THROW(d.AddSample(1.0, a, w, q, nullptr), std::invalid_argument);
  EXPECT_THROW(d.AddSample(2.0, Eigen::Vector3d(0, NAN, 9.8), w, q, nullptr), std::invalid_argument);
  EXPECT_EQ(d.latest_time_s(), 1.0);
  StreamingStepOptions bad;
  bad.highpass_hz = 5.0;
  try {
    StreamingStepDetector x(bad);
    FAIL() << "accepted highpass_hz above lowpass_hz";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("highpass_hz"), std::string::npos);
  }
  Eigen::VectorXd rv(3);
  rv << 0.0, 0.0, std::sin(0.25);
  const Eigen::Vector4d qq = QuaternionFromRotationVector(rv);
  EXPECT_NEAR(qq[3], std::cos(0.25), 1e-15);
  EXPECT_NEAR(qq.norm(), 1.0, 1e-15);
}

}  // namespace
}  // namespace indoorloc::pdr
