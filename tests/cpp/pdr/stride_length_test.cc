#include "indoorloc/pdr/stride_length.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

namespace indoorloc::pdr {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Product of the sections' numerator (b) or denominator (a) polynomials in z^-1.
Eigen::VectorXd Polynomial(const RowMatrixXd& sos, int offset) {
  Eigen::VectorXd p = Eigen::VectorXd::Ones(1);
  for (Eigen::Index s = 0; s < sos.rows(); ++s) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(p.size() + 2);
    for (Eigen::Index i = 0; i < p.size(); ++i) {
      for (int j = 0; j < 3; ++j) q[i + j] += p[i] * sos(s, offset + j);
    }
    p = q;
  }
  return p;
}

TEST(Butterworth, MatchesScipyButterCoefficients) {
  // scipy.signal.butter(4, 3, fs=100) (scipy 1.x), the paper's Weinberg filter at 100 Hz.
  const double b_ref[] = {6.238698354847940e-05, 2.495479341939176e-04, 3.743219012908764e-04, 2.495479341939176e-04,
                          6.238698354847940e-05};
  const double a_ref[] = {1.0, -3.5077862073907826, 4.640902412686707, -2.7426528211203727, 0.6105348075612237};
  const RowMatrixXd sos = ButterworthSos(4, 3.0, 100.0);
  ASSERT_EQ(sos.rows(), 2);
  const Eigen::VectorXd b = Polynomial(sos, 0), a = Polynomial(sos, 3);
  for (int i = 0; i < 5; ++i) {
    EXPECT_NEAR(b[i], b_ref[i], 1e-12 * std::abs(b_ref[i]) + 1e-15) << i;
    EXPECT_NEAR(a[i], a_ref[i], 1e-10) << i;
  }
  // scipy.signal.butter(3, 0.5, fs=100, btype='high'): an odd order and a high-pass.
  const double hb_ref[] = {0.969071174031813, -2.907213522095439, 2.907213522095439, -0.969071174031813};
  const double ha_ref[] = {1.0, -2.9371707284498907, 2.8762997234793315, -0.939098940325283};
  const RowMatrixXd hp = ButterworthSos(3, 0.5, 100.0, true);
  const Eigen::VectorXd hb = Polynomial(hp, 0), ha = Polynomial(hp, 3);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(hb[i], hb_ref[i], 1e-10) << i;
    EXPECT_NEAR(ha[i], ha_ref[i], 1e-10) << i;
  }
  EXPECT_THROW(ButterworthSos(4, 60.0, 100.0), std::invalid_argument);  // above Nyquist
  EXPECT_THROW(ButterworthSos(0, 3.0, 100.0), std::invalid_argument);
}

TEST(Butterworth, SteadyStateStartPassesAConstantAndUnitDcGain) {
  const RowMatrixXd sos = ButterworthSos(4, 3.0, 100.0);
  const Eigen::VectorXd x = Eigen::VectorXd::Constant(300, 9.81);
  const Eigen::VectorXd y = FilterSos(sos, x, true);
  EXPECT_LT((y.array() - 9.81).abs().maxCoeff(), 1e-9);
  const Eigen::VectorXd y0 = FilterSos(sos, x, false);  // zero state: rises to 9.81
  EXPECT_LT(y0[0], 0.01);
  EXPECT_NEAR(y0[299], 9.81, 1e-3);
}

TEST(Weinberg, BounceFeatureAndCalibrationRecoverK) {
  // Vertical bounce of amplitude A at 1 Hz (below the 3 Hz cut-off): max − min of |acc| ≈ 2A.
  const double rate = 100.0;
  const int n = 1000;
  RowMatrixXd acc = RowMatrixXd::Zero(n, 3);
  std::vector<int> steps;
  for (int i = 0; i < n; ++i) acc(i, 2) = 9.81 + 2.0 * std::sin(2 * kPi * 1.0 * i / rate);
  for (int i = 125; i < n - 50; i += 100) steps.push_back(i);  // the sine's troughs: |window| covers ±0.5 s
  WeinbergOptions o;
  o.window_s = 0.5;
  const Eigen::VectorXd sl = WeinbergStrideLengths(rate, acc, steps, o);
  // The 3 Hz filter attenuates 1 Hz by ~0.1 %; (2 · 2)^{1/4} = 1.414.
  for (Eigen::Index k = 1; k < sl.size(); ++k) EXPECT_NEAR(sl[k], 0.364 * std::pow(4.0, 0.25), 0.005) << k;
  const Eigen::VectorXd features = sl / 0.364;
  const Eigen::VectorXd truth = 0.5 * features;
  const WeinbergCalibration c = CalibrateWeinbergK(features, truth);
  EXPECT_NEAR(c.k, 0.5, 1e-12);
  EXPECT_NEAR(c.rms_residual_m, 0.0, 1e-12);
  EXPECT_NEAR(CalibrateWeinbergKFromDistance(features, truth.sum()).k, 0.5, 1e-12);
}

TEST(Weinberg, BadInputGivesClearErrors) {
  RowMatrixXd acc = RowMatrixXd::Constant(200, 3, 5.0);
  EXPECT_THROW(WeinbergStrideLengths(100.0, acc, {50, 40}, WeinbergOptions()), std::invalid_argument);  // unsorted
  EXPECT_THROW(WeinbergStrideLengths(100.0, acc, {250}, WeinbergOptions()), std::invalid_argument);     // outside
  EXPECT_THROW(WeinbergStrideLengths(100.0, acc.topRows(10), {5}, WeinbergOptions()), std::invalid_argument);
  EXPECT_THROW(WeinbergStrideLengths(5.0, acc, {50}, WeinbergOptions()), std::invalid_argument);  // 3 Hz > Nyquist
  acc(3, 0) = std::nan("");
  EXPECT_THROW(WeinbergStrideLengths(100.0, acc, {50}, WeinbergOptions()), std::invalid_argument);
  EXPECT_THROW(CalibrateWeinbergK(Eigen::VectorXd::Zero(3), Eigen::VectorXd::Ones(3)), std::invalid_argument);
  EXPECT_THROW(CalibrateWeinbergKFromDistance(Eigen::VectorXd::Ones(3), -1.0), std::invalid_argument);
}

// Issue 17: rate_hz = 1e300 squared to inf and gave NaN sections; an unstable section (or one
// with a pole at z = 1, whose steady-state start divides by 0) filled the output with inf/NaN.
TEST(Butterworth, AbsurdRatesAndUnstableSectionsAreRefused) {
  EXPECT_THROW(ButterworthSos(4, 3.0, 1e300), std::invalid_argument);
  RowMatrixXd unstable(1, 6);
  unstable << 1.0, 0.0, 0.0, 1.0, 0.0, -1.5;  // poles at +-sqrt(1.5)
  const Eigen::VectorXd x = Eigen::VectorXd::Ones(2000);
  EXPECT_THROW(FilterSos(unstable, x, false), std::invalid_argument);
  RowMatrixXd integrator(1, 6);
  integrator << 1.0, 1.0, 1.0, 1.0, -2.0, 1.0;  // double pole at z = 1
  EXPECT_THROW(FilterSos(integrator, x, true), std::invalid_argument);
  // Stable but huge input: the output overflows and is reported, not returned.
  RowMatrixXd gain(1, 6);
  gain << 1e10, 0.0, 0.0, 1.0, 0.0, 0.0;
  EXPECT_THROW(FilterSos(gain, Eigen::VectorXd::Constant(3, 1e300), false), std::invalid_argument);
}

}  // namespace
}  // namespace indoorloc::pdr
