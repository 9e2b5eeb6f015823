#include "indoorloc/pdr/zupt_ekf.h"

#include <cmath>
#include <string>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "indoorloc/core/random.h"
#include "indoorloc/pdr/step_detection.h"
#include "indoorloc/pdr/zero_velocity.h"
#include "synthetic_gait.h"

namespace indoorloc::pdr {
namespace {

constexpr double kPi = 3.14159265358979323846;
using synthetic::Gait;
using synthetic::MakeGait;

int CountStanceBlocks(const BoolVector& stance) {
  int blocks = 0;
  for (Eigen::Index k = 0; k < stance.size(); ++k) blocks += stance[k] && (k == 0 || !stance[k - 1]);
  return blocks;
}

TEST(ShoeDetector, FindsEveryStancePhaseOfASyntheticGait) {
  const Gait g = MakeGait(12, 0.3, 0.0, 1);
  ShoeOptions o;
  const BoolVector stance = ShoeDetector(g.acc, g.gyro, o);
  EXPECT_EQ(CountStanceBlocks(stance), g.steps + 1);
}

TEST(StepDetection, AccelerationAndGyroDetectorsFindEveryStep) {
  for (double noise : {0.0, 0.02}) {
    const Gait g = MakeGait(15, 1.0, noise, 6);
    const std::vector<int> acc_steps = DetectStepsAcceleration(200.0, g.acc, AccelerationStepOptions());
    EXPECT_EQ(static_cast<int>(acc_steps.size()), g.steps) << "noise " << noise;
    GyroStepOptions gyro_options;
    gyro_options.threshold_radps = 0.5;  // the synthetic foot pitches at most ~1.6 rad/s
    const std::vector<int> gyro_steps = DetectStepsGyro(200.0, g.gyro, gyro_options);
    EXPECT_EQ(static_cast<int>(gyro_steps.size()), g.steps) << "noise " << noise;
  }
  EXPECT_THROW(DetectStepsAcceleration(200.0, RowMatrixXd::Zero(10, 3), AccelerationStepOptions()), std::invalid_argument);
  EXPECT_THROW(DetectStepsGyro(-1.0, RowMatrixXd::Zero(100, 3), GyroStepOptions()), std::invalid_argument);
}

TEST(StepDetection, MagnetometerDetectorFindsEveryStep) {
  // The field seen by the foot changes as the foot pitches in each swing.
  for (double noise : {0.0, 0.3}) {
    const Gait g = MakeGait(15, 1.0, 0.0, 8);
    RandomStream rng(9);
    RowMatrixXd mag(g.time.size(), 3);
    const Eigen::Vector3d field(20.0, -5.0, -40.0);  // uT, navigation frame
    for (Eigen::Index k = 0; k < g.time.size(); ++k) {
      const Eigen::Quaterniond q(g.quaternions(k, 0), g.quaternions(k, 1), g.quaternions(k, 2), g.quaternions(k, 3));
      mag.row(k) = (q.toRotationMatrix().transpose() * field).transpose() + Eigen::RowVector3d(3.0, -7.0, 11.0);  // hard iron
      for (int c = 0; c < 3; ++c) mag(k, c) += noise * rng.Normal();
    }
    Eigen::VectorXd magnitude;
    const std::vector<int> steps = DetectStepsMagnetometer(200.0, mag, MagneticStepOptions(), &magnitude);
    EXPECT_EQ(static_cast<int>(steps.size()), g.steps) << "noise " << noise;
    EXPECT_EQ(magnitude.size(), g.time.size());
  }
  EXPECT_THROW(DetectStepsMagnetometer(200.0, RowMatrixXd::Zero(5, 3), MagneticStepOptions()), std::invalid_argument);
  RowMatrixXd nan_mag = RowMatrixXd::Ones(400, 3);
  nan_mag(7, 0) = std::nan("");
  EXPECT_THROW(DetectStepsMagnetometer(200.0, nan_mag, MagneticStepOptions()), std::invalid_argument);
}

TEST(ZuptEkf, RecoversTheWalkedPathAndZeroesVelocityAtStance) {
  const Gait g = MakeGait(12, 0.0, 0.0, 2);
  const BoolVector stance = ShoeDetector(g.acc, g.gyro, ShoeOptions());
  const ZuptEkfOutput out = RunZuptEkf(g.time, g.acc, g.gyro, stance);
  const Eigen::Index last = g.time.size() - 1;
  // First-order mechanisation at 200 Hz: within 1 % of the 16.8 m walked.
  EXPECT_LT((out.positions_m.row(last) - g.position.row(last)).norm(), 0.01 * 12 * 1.4) << out.positions_m.row(last);
  for (Eigen::Index k = 0; k <= last; ++k) {
    if (stance[k]) {
      ASSERT_LT(out.velocities_mps.row(k).norm(), 0.05) << "sample " << k;
    }
  }
  // The attitude output is the truth (a yaw of 0 at the start here).
  ASSERT_EQ(out.quaternions_wxyz.rows(), g.time.size());
  for (Eigen::Index k = 0; k <= last; k += 50) {
    const Eigen::Quaterniond qe(out.quaternions_wxyz(k, 0), out.quaternions_wxyz(k, 1), out.quaternions_wxyz(k, 2), out.quaternions_wxyz(k, 3));
    const Eigen::Quaterniond qt(g.quaternions(k, 0), g.quaternions(k, 1), g.quaternions(k, 2), g.quaternions(k, 3));
    ASSERT_LT(qe.angularDistance(qt), 0.01) << "sample " << k;
  }
}

TEST(ZuptEkf, HealthCheckPassesAWalkAndFlagsLostStance) {
  const Gait g = MakeGait(12, 0.0, 0.0, 2);
  const BoolVector stance = ShoeDetector(g.acc, g.gyro, ShoeOptions());
  const ZuptEkfSummary ok = RunZuptEkf(g.time, g.acc, g.gyro, stance).summary;
  EXPECT_FALSE(ok.implausible) << ok.BriefReport();
  EXPECT_EQ(ok.n_stance_phases, g.steps + 1);
  EXPECT_NEAR(ok.walking_stance_fraction, 0.5 / 1.1, 0.05);
  EXPECT_NEAR(ok.swing_median_s, 0.6, 0.05);
  EXPECT_NEAR(ok.longest_stride_m, 1.4, 0.05);
  EXPECT_LT(ok.speed_at_stance_max_mps, 0.2);
  // Keep one stance phase in six: swings of 6.6 s, the filter drifts between the updates.
  BoolVector sparse = stance;
  int phase = -1;
  for (Eigen::Index k = 0; k < sparse.size(); ++k) {
    if (stance[k] && (k == 0 || !stance[k - 1])) ++phase;
    if (phase % 6 != 0) sparse[k] = false;
  }
  const ZuptEkfSummary bad = RunZuptEkf(g.time, g.acc, g.gyro, sparse).summary;
  EXPECT_TRUE(bad.implausible) << bad.BriefReport();
  EXPECT_GT(bad.swing_max_s, 5.0);
  ASSERT_FALSE(bad.reasons.empty());
  EXPECT_NE(bad.BriefReport().find("IMPLAUSIBLE"), std::string::npos);
  // Only the stance before the first swing: no onset after a swing, the drift shows as a long stride.
  BoolVector none = BoolVector::Constant(stance.size(), false);
  none.head(50).setConstant(true);
  const ZuptEkfSummary lost = RunZuptEkf(g.time, g.acc, g.gyro, none).summary;
  EXPECT_TRUE(lost.implausible);
  ZuptEkfOptions o;
  o.max_plausible_stride_m = 0.0;
  EXPECT_THROW(RunZuptEkf(g.time, g.acc, g.gyro, stance, o), std::invalid_argument);
}

TEST(ZuptEkf, NoisySensorsStayWithinAFewPercentOfTheDistance) {
  const Gait g = MakeGait(20, 0.0, 0.02, 3);
  ShoeOptions so;
  so.sigma_acc_mps2 = 0.02;
  so.sigma_gyro_radps = 0.002;
  so.threshold = 30.0;  // E[T] = 6 (6 degrees of freedom) at rest with matched noise sds
  const BoolVector stance = ShoeDetector(g.acc, g.gyro, so);
  EXPECT_EQ(CountStanceBlocks(stance), g.steps + 1);
  const ZuptEkfOutput out = RunZuptEkf(g.time, g.acc, g.gyro, stance);
  const Eigen::Index last = g.time.size() - 1;
  EXPECT_LT((out.positions_m.row(last) - g.position.row(last)).norm(), 0.03 * 20 * 1.4);
}

TEST(ZuptEkf, SmootherKeepsTheEndAndImprovesTheMiddle) {
  const Gait g = MakeGait(20, 0.4, 0.02, 5);
  ShoeOptions so;
  so.sigma_acc_mps2 = 0.02;
  so.sigma_gyro_radps = 0.002;
  so.threshold = 30.0;
  const BoolVector stance = ShoeDetector(g.acc, g.gyro, so);
  ZuptEkfOptions o;
  o.smooth = true;
  const ZuptEkfOutput out = RunZuptEkf(g.time, g.acc, g.gyro, stance, o);
  const Eigen::Index last = g.time.size() - 1;
  // The last sample has no future: smoothed = filtered there.
  EXPECT_LT((out.positions_m.row(last) - out.filtered_positions_m.row(last)).norm(), 1e-12);
  double filtered = 0, smoothed = 0;
  for (Eigen::Index k = 0; k <= last; ++k) {
    filtered += (out.filtered_positions_m.row(k) - g.position.row(k)).squaredNorm();
    smoothed += (out.positions_m.row(k) - g.position.row(k)).squaredNorm();
  }
  EXPECT_TRUE(out.positions_m.allFinite());
  EXPECT_LE(smoothed, filtered * 1.05);
}

TEST(ZuptEkf, StanceHeadingUpdateRemovesTheYawDriftOfStance) {
  // A gyro bias about the vertical turns the estimated heading during every stance; the stance
  // heading update holds the yaw there, so the final heading error shrinks (stance is ~45 % of
  // the gait cycle here: 0.22 rad -> 0.14 rad).
  Gait g = MakeGait(20, 0.0, 0.0, 10);
  for (Eigen::Index k = 0; k < g.gyro.rows(); ++k) g.gyro(k, 2) += 0.01;  // rad/s (body z = down here)
  const BoolVector stance = ShoeDetector(g.acc, g.gyro, ShoeOptions());
  ZuptEkfOptions plain, hde;
  hde.sigma_stance_heading_rad = 0.001;
  const ZuptEkfOutput a = RunZuptEkf(g.time, g.acc, g.gyro, stance, plain);
  const ZuptEkfOutput b = RunZuptEkf(g.time, g.acc, g.gyro, stance, hde);
  const Eigen::Index last = g.time.size() - 1;
  EXPECT_LT(std::abs(b.headings_rad[last]), 0.75 * std::abs(a.headings_rad[last]))
      << "with " << b.headings_rad[last] << " without " << a.headings_rad[last];
  EXPECT_TRUE(b.positions_m.allFinite());
  hde.sigma_stance_heading_rad = -1.0;
  EXPECT_THROW(RunZuptEkf(g.time, g.acc, g.gyro, stance, hde), std::invalid_argument);
}

TEST(ZuptEkf, BadInputGivesClearErrors) {
  const Gait g = MakeGait(2, 0.0, 0.0, 4);
  const BoolVector stance = ShoeDetector(g.acc, g.gyro, ShoeOptions());
  RowMatrixXd nan_acc = g.acc;
  nan_acc(10, 1) = std::nan("");
  EXPECT_THROW(RunZuptEkf(g.time, nan_acc, g.gyro, stance), std::invalid_argument);
  EXPECT_THROW(RunZuptEkf(g.time.head(5), g.acc, g.gyro, stance), std::invalid_argument);
  EXPECT_THROW(ShoeDetector(g.acc.topRows(3), g.gyro.topRows(3), ShoeOptions()), std::invalid_argument);  // shorter than a window
  RowMatrixXd in_g = g.acc / 9.81;  // accelerometer in g declared as m/s^2
  EXPECT_THROW(RunZuptEkf(g.time, in_g / 100.0, g.gyro, stance), std::invalid_argument);
  Eigen::VectorXd repeated = g.time;
  repeated[7] = repeated[6];  // a repeated timestamp is handled (median period)
  EXPECT_NO_THROW(RunZuptEkf(repeated, g.acc, g.gyro, stance));
}

// Issue 17: inf or 1e-300 passed "> 0" and turned every state into NaN; the message named no field.
TEST(ZuptEkf, NonFiniteOrAbsurdOptionsAreRefusedNamingTheField) {
  const auto field_of = [](ZuptEkfOptions o) {
    std::string error;
    EXPECT_FALSE(o.IsValid(&error));
    return error;
  };
  ZuptEkfOptions o;
  o.sigma_acc_mps2 = INFINITY;
  EXPECT_EQ(field_of(o), "sigma_acc_mps2 must be finite and in [1e-12, 1e+12], got inf");
  o = ZuptEkfOptions();
  o.sigma_gyro_radps = 1e-300;
  EXPECT_EQ(field_of(o).rfind("sigma_gyro_radps", 0), 0u);
  o = ZuptEkfOptions();
  o.sigma_zupt_mps = std::nan("");
  EXPECT_EQ(field_of(o).rfind("sigma_zupt_mps", 0), 0u);
  o = ZuptEkfOptions();
  o.gravity_mps2 = INFINITY;
  EXPECT_EQ(field_of(o), "gravity_mps2 must be in [0.1, 100], got inf");
  EXPECT_TRUE(ZuptEkfOptions().IsValid(nullptr));
}

}  // namespace
}  // namespace indoorloc::pdr
