#include "indoorloc/pdr/stride_length.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <sstream>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "imu_timing.h"

namespace indoorloc::pdr {
namespace {
constexpr double kPi = 3.14159265358979323846;
}

RowMatrixXd ButterworthSos(int order, double cutoff_hz, double rate_hz, bool highpass) {
  CheckArgument(order >= 1 && order <= 16, "order", "must be in [1, 16]");
  RequireScale(rate_hz, "rate_hz");  // (2 rate_hz)^2 must stay finite (1e300 gave NaN sections)
  CheckArgument(std::isfinite(cutoff_hz) && cutoff_hz > 0.0 && cutoff_hz < 0.5 * rate_hz, "cutoff_hz",
                "must be in (0, rate_hz / 2)");
  const double c = 2.0 * rate_hz;                                // bilinear s = c (z - 1) / (z + 1)
  const double wc = c * std::tan(kPi * cutoff_hz / rate_hz);     // pre-warped analog cut-off [rad/s]
  const int pairs = order / 2;
  RowMatrixXd sos(pairs + order % 2, 6);
  for (int k = 0; k < pairs; ++k) {
    // Prototype pole p = exp(iπ(2k + 1 + order) / (2 order)) (left half plane), |p| = 1; the
    // section's analog denominator is s² + a1 s + a0 with a1 = −2 wc Re p, a0 = wc².
    const double re = std::cos(kPi * (2.0 * k + 1.0 + order) / (2.0 * order));
    const double a1 = -2.0 * wc * re, a0 = wc * wc;
    const double d0 = c * c + a1 * c + a0, d1 = 2.0 * (a0 - c * c), d2 = c * c - a1 * c + a0;
    if (highpass) {  // s² / (s² + a1 s + a0)
      sos.row(k) << c * c / d0, -2.0 * c * c / d0, c * c / d0, 1.0, d1 / d0, d2 / d0;
    } else {  // wc² / (s² + a1 s + a0)
      sos.row(k) << a0 / d0, 2.0 * a0 / d0, a0 / d0, 1.0, d1 / d0, d2 / d0;
    }
  }
  if (order % 2 == 1) {  // real pole −wc: wc / (s + wc) or s / (s + wc)
    const double d0 = c + wc, d1 = wc - c;
    if (highpass) {
      sos.row(pairs) << c / d0, -c / d0, 0.0, 1.0, d1 / d0, 0.0;
    } else {
      sos.row(pairs) << wc / d0, wc / d0, 0.0, 1.0, d1 / d0, 0.0;
    }
  }
  // A cut-off far below the rate rounds the poles onto z = 1 (a1 = -2, a2 = 1): unstable.
  bool stable = sos.allFinite();
  for (Eigen::Index k = 0; k < sos.rows() && stable; ++k)
    stable = std::abs(sos(k, 5)) < 1.0 && std::abs(sos(k, 4)) < 1.0 + sos(k, 5);
  CheckArgument(stable, "cutoff_hz", "cutoff_hz / rate_hz = " + FormatValue(cutoff_hz / rate_hz) +
                                         " is too small for a stable filter in double precision");
  return sos;
}

Eigen::VectorXd FilterSos(const Eigen::Ref<const RowMatrixXd>& sos, const Eigen::Ref<const Eigen::VectorXd>& x,
                          bool steady_state_start) {
  CheckShape(sos, -1, 6, "sos");
  CheckFinite(sos, "sos");
  CheckFinite(x, "x");
  for (Eigen::Index s = 0; s < sos.rows(); ++s) {
    CheckArgument(sos(s, 3) != 0.0, "sos", "a0 of section " + std::to_string(s) + " is 0");
    // Jury's test for z^2 + a1 z + a2: poles inside the unit circle iff |a2| < 1 and
    // |a1| < 1 + a2. An unstable section grows without bound (inf/NaN on long inputs), and the
    // steady-state start divides by 1 + a1 + a2, which is 0 for a pole at z = 1.
    const double a1 = sos(s, 4) / sos(s, 3), a2 = sos(s, 5) / sos(s, 3);
    CheckArgument(std::abs(a2) < 1.0 && std::abs(a1) < 1.0 + a2, "sos",
                  "section " + std::to_string(s) + " is not stable (a1/a0 = " + FormatValue(a1) + ", a2/a0 = " +
                      FormatValue(a2) + "; poles must lie inside the unit circle)");
  }
  const Eigen::Index n = x.size(), m = sos.rows();
  Eigen::VectorXd y = x;
  if (n == 0) return y;
  for (Eigen::Index s = 0; s < m; ++s) {
    const double a0 = sos(s, 3);
    const double b0 = sos(s, 0) / a0, b1 = sos(s, 1) / a0, b2 = sos(s, 2) / a0, a1 = sos(s, 4) / a0, a2 = sos(s, 5) / a0;
    double z1 = 0.0, z2 = 0.0;
    if (steady_state_start) {
      // Constant input u: output g u with DC gain g = Σb / Σa; then z2 = (b2 − a2 g) u and
      // z1 = (g − b0) u keep the section in steady state.
      const double u = y[0];
      const double g = (b0 + b1 + b2) / (1.0 + a1 + a2);
      z2 = (b2 - a2 * g) * u;
      z1 = (g - b0) * u;
    }
    for (Eigen::Index i = 0; i < n; ++i) {
      const double u = y[i];
      const double out = b0 * u + z1;
      z1 = b1 * u - a1 * out + z2;
      z2 = b2 * u - a2 * out;
      y[i] = out;
    }
  }
  CheckArgument(y.allFinite(), "x", "the filtered output overflows (inputs too large for this filter)");
  return y;
}

bool WeinbergOptions::IsValid(std::string* error) const {
  return Validator(error)
      .Scale(k, "k")
      .IntInRange(filter_order, 1, 16, "filter_order")
      .Scale(cutoff_hz, "cutoff_hz")
      .InRange(window_s, 1e-9, 1e6, "window_s");
}

Eigen::VectorXd WeinbergFilteredMagnitude(double rate_hz, const Eigen::Ref<const RowMatrixXd>& acc,
                                          const WeinbergOptions& options) {
  ValidateOptions(options);
  RequireScale(rate_hz, "rate_hz");  // (2 rate_hz)^2 must stay finite (1e300 gave NaN sections)
  CheckShape(acc, -1, 3, "acc_mps2");
  CheckFinite(acc, "acc_mps2");
  internal::CheckAccRange(acc);  // else the filter's overflow would be blamed on its input 'x'
  CheckArgument(options.cutoff_hz < 0.5 * rate_hz, "options",
                "cutoff_hz must be below half of rate_hz (" + std::to_string(0.5 * rate_hz) + " Hz)");
  CheckArgument(acc.rows() >= 2, "acc_mps2", "needs at least 2 samples");
  const Eigen::VectorXd a = acc.rowwise().norm();  // eq. 1
  return FilterSos(ButterworthSos(options.filter_order, options.cutoff_hz, rate_hz), a, options.steady_state_start);
}

Eigen::VectorXd WeinbergFeatures(double rate_hz, const Eigen::Ref<const RowMatrixXd>& acc,
                                 const Eigen::Ref<const Eigen::MatrixXi>& intervals, const WeinbergOptions& options) {
  const Eigen::VectorXd f = WeinbergFilteredMagnitude(rate_hz, acc, options);
  CheckShape(intervals, -1, 2, "intervals");
  const Eigen::Index n = acc.rows();
  Eigen::VectorXd out(intervals.rows());
  for (Eigen::Index r = 0; r < intervals.rows(); ++r) {
    const int lo = intervals(r, 0), hi = intervals(r, 1);
    CheckArgument(lo >= 0 && lo <= hi && hi < n, "intervals",
                  "row " + std::to_string(r) + " = [" + std::to_string(lo) + ", " + std::to_string(hi) +
                      "] must satisfy 0 <= start <= end < N = " + std::to_string(n));
    const auto seg = f.segment(lo, hi - lo + 1);
    out[r] = std::pow(std::max(0.0, seg.maxCoeff() - seg.minCoeff()), 0.25);  // eq. 4 without K
  }
  return out;
}

Eigen::VectorXd WeinbergStrideLengths(double rate_hz, const Eigen::Ref<const RowMatrixXd>& acc,
                                      const std::vector<int>& step_indices, const WeinbergOptions& options) {
  ValidateOptions(options);
  RequireScale(rate_hz, "rate_hz");  // (2 rate_hz)^2 must stay finite (1e300 gave NaN sections)
  const Eigen::Index n = acc.rows();
  const int w = std::max(1, internal::SampleCount(options.window_s * rate_hz));
  CheckArgument(n >= 2 * Eigen::Index{w} + 1, "acc_mps2",
                "the recording (" + std::to_string(n) + " samples) is shorter than one window (" + std::to_string(2 * w + 1) + ")");
  Eigen::MatrixXi intervals(static_cast<Eigen::Index>(step_indices.size()), 2);
  for (size_t k = 0; k < step_indices.size(); ++k) {
    const int i = step_indices[k];
    CheckArgument(i >= 0 && i < n, "step_indices", "entry " + std::to_string(k) + " is outside [0, N)");
    CheckArgument(k == 0 || i > step_indices[k - 1], "step_indices", "must be strictly increasing");
    intervals(static_cast<Eigen::Index>(k), 0) = std::max(0, i - w);
    intervals(static_cast<Eigen::Index>(k), 1) = std::min<int>(static_cast<int>(n) - 1, i + w);
  }
  return options.k * WeinbergFeatures(rate_hz, acc, intervals, options);
}

std::string WeinbergCalibration::BriefReport() const {
  std::ostringstream s;
  s << "Weinberg K = " << k << " from " << n_strides << " strides, RMS residual " << rms_residual_m << " m";
  return s.str();
}

WeinbergCalibration CalibrateWeinbergK(const Eigen::Ref<const Eigen::VectorXd>& f, const Eigen::Ref<const Eigen::VectorXd>& l) {
  CheckArgument(f.size() == l.size(), "lengths_m", "must have one entry per feature");
  CheckArgument(f.size() >= 1, "features", "is empty");
  CheckFinite(f, "features");
  CheckFinite(l, "lengths_m");
  CheckArgument((f.array() >= 0.0).all(), "features", "must be >= 0");
  CheckArgument((l.array() > 0.0).all(), "lengths_m", "must be > 0");
  // Squared in the fit: bounded so the residual stays finite (1e300 gave an inf RMS).
  RequireAllInRange(f, 0.0, 1e100, "features");
  RequireAllInRange(l, 0.0, 1e4, "lengths_m");
  const double ff = f.squaredNorm();
  CheckArgument(ff > 0.0, "features", "are all 0 (no bounce: is the sensor still?)");
  WeinbergCalibration c;
  c.k = f.dot(l) / ff;
  c.n_strides = static_cast<int>(f.size());
  c.rms_residual_m = std::sqrt((c.k * f - l).squaredNorm() / static_cast<double>(f.size()));
  return c;
}

WeinbergCalibration CalibrateWeinbergKFromDistance(const Eigen::Ref<const Eigen::VectorXd>& f, double distance_m) {
  CheckArgument(f.size() >= 1, "features", "is empty");
  CheckFinite(f, "features");
  RequireAllInRange(f, 0.0, 1e100, "features");
  RequirePositive(distance_m, "distance_m");
  const double sum = f.sum();
  CheckArgument(sum > 0.0, "features", "sum to 0 (no bounce: is the sensor still?)");
  WeinbergCalibration c;
  c.k = distance_m / sum;
  c.n_strides = static_cast<int>(f.size());
  return c;
}

}  // namespace indoorloc::pdr
