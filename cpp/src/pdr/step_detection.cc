#include "indoorloc/pdr/step_detection.h"

#include <algorithm>
#include <cmath>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/pdr/stride_length.h"
#include "imu_timing.h"

namespace indoorloc::pdr {
namespace {

void CheckRate(double rate_hz) { RequireScale(rate_hz, "rate_hz"); }

int Samples(double seconds, double rate_hz) { return std::max(1, internal::SampleCount(seconds * rate_hz)); }

// Median filter of binary motion flags (window 2 half + 1), then a step at each transition to
// motionless after a motion run of at least min_swing samples. Rest gaps shorter than min_rest
// samples between two motion runs are closed first (0: none).
std::vector<int> StepsFromMotion(const std::vector<char>& moving, int half, int min_swing, int min_rest = 0) {
  const Eigen::Index n = static_cast<Eigen::Index>(moving.size());
  // Median filter of a binary signal = majority vote over the window.
  std::vector<char> filtered(static_cast<size_t>(n));
  int count = 0;
  for (Eigen::Index i = 0; i < std::min<Eigen::Index>(n, half); ++i) count += moving[static_cast<size_t>(i)];
  for (Eigen::Index i = 0; i < n; ++i) {
    if (i + half < n) count += moving[static_cast<size_t>(i + half)];
    if (i - half - 1 >= 0) count -= moving[static_cast<size_t>(i - half - 1)];
    const Eigen::Index lo = std::max<Eigen::Index>(0, i - half), hi = std::min<Eigen::Index>(n - 1, i + half);
    filtered[static_cast<size_t>(i)] = 2 * count > (hi - lo + 1);
  }
  if (min_rest > 0) {
    Eigen::Index last_motion = -1;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!filtered[static_cast<size_t>(i)]) continue;
      if (last_motion >= 0 && i - last_motion - 1 > 0 && i - last_motion - 1 < min_rest) {
        for (Eigen::Index j = last_motion + 1; j < i; ++j) filtered[static_cast<size_t>(j)] = 1;
      }
      last_motion = i;
    }
  }
  // A step at each transition to motionless after a motion run of at least min_swing_s.
  std::vector<int> steps;
  int run = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (filtered[static_cast<size_t>(i)]) {
      ++run;
    } else {
      if (run >= min_swing && i > 0) steps.push_back(static_cast<int>(i));
      run = 0;
    }
  }
  return steps;
}

}  // namespace

bool AccelerationStepOptions::IsValid(std::string* error) const {
  Validator v(error);
  v.InRange(window_s, 1e-9, 1e6, "window_s").InRange(min_step_interval_s, 0.0, 1e6, "min_step_interval_s");
  if (!v) return false;
  if (!(swing_threshold_mps2 > stance_threshold_mps2 && stance_threshold_mps2 > 0.0 && std::isfinite(swing_threshold_mps2))) {
    return (*error = "need swing_threshold_mps2 > stance_threshold_mps2 > 0 (finite), got " + FormatValue(swing_threshold_mps2) +
                     " and " + FormatValue(stance_threshold_mps2), false);
  }
  if (!(swing_fraction > stance_fraction && stance_fraction > 0.0 && swing_fraction < 1.0)) {
    return (*error = "need 1 > swing_fraction > stance_fraction > 0, got " + FormatValue(swing_fraction) + " and " +
                     FormatValue(stance_fraction), false);
  }
  return true;
}

bool GyroStepOptions::IsValid(std::string* error) const {
  return Validator(error)
      .Scale(threshold_radps, "threshold_radps")
      .InRange(median_window_s, 1e-9, 1e6, "median_window_s")
      .InRange(min_swing_s, 0.0, 1e6, "min_swing_s");
}

std::vector<int> DetectStepsAcceleration(double rate_hz, const Eigen::Ref<const RowMatrixXd>& acc,
                                         const AccelerationStepOptions& options, Eigen::VectorXd* sigma_out) {
  ValidateOptions(options);
  CheckRate(rate_hz);
  internal::CheckAccSamples(acc);
  const Eigen::Index n = acc.rows();
  const int w = Samples(options.window_s, rate_hz);
  CheckArgument(n >= 2 * Eigen::Index{w} + 1, "acc_mps2",
                "the recording (" + std::to_string(n) + " samples) is shorter than one window (" +
                    std::to_string(2 * Eigen::Index{w} + 1) + " samples from window_s x rate_hz)");
  const Eigen::VectorXd a = acc.rowwise().norm();  // eq. 1
  // eq. 2 with prefix sums: σ²_i = mean(a²) - mean(a)² over [i - w, i + w] (clamped at the ends).
  Eigen::VectorXd s1(n + 1), s2(n + 1);
  s1[0] = s2[0] = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    s1[i + 1] = s1[i] + a[i];
    s2[i + 1] = s2[i] + a[i] * a[i];
  }
  Eigen::VectorXd sigma(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index lo = std::max<Eigen::Index>(0, i - w), hi = std::min<Eigen::Index>(n, i + w + 1);
    const double m = static_cast<double>(hi - lo);
    const double mean = (s1[hi] - s1[lo]) / m;
    sigma[i] = std::sqrt(std::max(0.0, (s2[hi] - s2[lo]) / m - mean * mean));
  }
  double t1 = options.swing_threshold_mps2, t2 = options.stance_threshold_mps2;
  if (options.adaptive) {
    std::vector<double> sorted(sigma.data(), sigma.data() + n);
    const size_t q = static_cast<size_t>(0.95 * static_cast<double>(n - 1));
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(q), sorted.end());
    const double p95 = sorted[q];
    t1 = options.swing_fraction * p95;
    t2 = options.stance_fraction * p95;
  }
  // eq. 3 and step 4: a swing ends (σ falls below T1 after being above it) and σ < T2 follows
  // within w samples.
  const Eigen::Index min_interval = options.min_step_interval_s > 0 ? Samples(options.min_step_interval_s, rate_hz) : 0;
  std::vector<int> steps;
  for (Eigen::Index i = 1; i < n; ++i) {
    const bool swing_end = sigma[i - 1] > t1 && !(sigma[i] > t1);
    if (!swing_end) continue;
    bool stance_ahead = false;
    for (Eigen::Index j = i; j < std::min<Eigen::Index>(n, i + w + 1) && !stance_ahead; ++j) stance_ahead = sigma[j] < t2;
    if (!stance_ahead) continue;
    if (!steps.empty() && i - steps.back() < min_interval) continue;  // same stride
    steps.push_back(static_cast<int>(i));
  }
  if (sigma_out != nullptr) *sigma_out = sigma;
  return steps;
}

std::vector<int> DetectStepsGyro(double rate_hz, const Eigen::Ref<const RowMatrixXd>& gyro, const GyroStepOptions& options) {
  ValidateOptions(options);
  CheckRate(rate_hz);
  internal::CheckGyroSamples(gyro);
  const Eigen::Index n = gyro.rows();
  const int half = Samples(options.median_window_s, rate_hz) / 2;
  CheckArgument(n >= 2 * Eigen::Index{half} + 1, "gyro_radps",
                "the recording (" + std::to_string(n) + " samples) is shorter than one median window (median_window_s x rate_hz)");
  std::vector<char> moving(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) moving[static_cast<size_t>(i)] = gyro.row(i).norm() > options.threshold_radps;
  return StepsFromMotion(moving, half, Samples(options.min_swing_s, rate_hz));
}

bool MagneticStepOptions::IsValid(std::string* error) const {
  return Validator(error)
      .IntInRange(highpass_order, 1, 8, "highpass_order")
      .Scale(highpass_hz, "highpass_hz")
      .Check(threshold_fraction > 0.0 && threshold_fraction < 1.0, "threshold_fraction",
             "must be in (0, 1), got " + FormatValue(threshold_fraction))
      .InRange(median_window_s, 1e-9, 1e6, "median_window_s")
      .InRange(min_swing_s, 0.0, 1e6, "min_swing_s")
      .InRange(min_rest_s, 0.0, 1e6, "min_rest_s");
}

std::vector<int> DetectStepsMagnetometer(double rate_hz, const Eigen::Ref<const RowMatrixXd>& mag, const MagneticStepOptions& options,
                                         Eigen::VectorXd* magnitude) {
  ValidateOptions(options);
  CheckRate(rate_hz);
  CheckShape(mag, -1, 3, "mag");
  CheckFinite(mag, "mag");
  RequireAllInRange(mag, -internal::kMaxAbsMag, internal::kMaxAbsMag, "mag");
  CheckArgument(options.highpass_hz < 0.5 * rate_hz, "options", "highpass_hz must be below half of rate_hz");
  const Eigen::Index n = mag.rows();
  const int half = Samples(options.median_window_s, rate_hz) / 2;
  CheckArgument(n >= std::max<Eigen::Index>(2 * Eigen::Index{half} + 1, 3), "mag",
                "the recording (" + std::to_string(n) + " samples) is shorter than one median window (median_window_s x rate_hz)");
  const RowMatrixXd sos = ButterworthSos(options.highpass_order, options.highpass_hz, rate_hz, true);
  Eigen::VectorXd sq = Eigen::VectorXd::Zero(n);
  for (int c = 0; c < 3; ++c) {
    const Eigen::VectorXd hp = FilterSos(sos, mag.col(c), true);  // starts at 0: no DC transient
    sq += hp.cwiseAbs2();
  }
  const Eigen::VectorXd m = sq.cwiseSqrt();
  std::vector<double> sorted(m.data(), m.data() + n);
  const size_t q = static_cast<size_t>(0.95 * static_cast<double>(n - 1));
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(q), sorted.end());
  const double threshold = options.threshold_fraction * sorted[q];
  std::vector<char> moving(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) moving[static_cast<size_t>(i)] = m[i] > threshold && threshold > 0.0;
  if (magnitude != nullptr) *magnitude = m;
  const int min_rest = options.min_rest_s > 0.0 ? Samples(options.min_rest_s, rate_hz) : 0;
  return StepsFromMotion(moving, half, Samples(options.min_swing_s, rate_hz), min_rest);
}

}  // namespace indoorloc::pdr
