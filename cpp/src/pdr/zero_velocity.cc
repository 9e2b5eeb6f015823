#include "indoorloc/pdr/zero_velocity.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <limits>
#include <vector>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"

namespace indoorloc::pdr {

bool ShoeOptions::IsValid(std::string* error) const {
  auto fail = [&](const char* why) {
    *error = why;
    return false;
  };
  if (window < 1) return fail("window must be >= 1");
  if (!(threshold > 0.0)) return fail("threshold must be > 0");
  if (!(sigma_acc_mps2 > 0.0) || !(sigma_gyro_radps > 0.0)) return fail("noise sds must be > 0");
  if (!(gravity_mps2 > 0.0)) return fail("gravity_mps2 must be > 0");
  return true;
}

namespace {
void CheckImu(const Eigen::Ref<const RowMatrixXd>& acc, const Eigen::Ref<const RowMatrixXd>& gyro, int window) {
  CheckShape(acc, -1, 3, "acc_mps2");
  CheckShape(gyro, acc.rows(), 3, "gyro_radps");
  CheckFinite(acc, "acc_mps2");
  CheckFinite(gyro, "gyro_radps");
  CheckArgument(acc.rows() >= window, "acc_mps2",
                "the recording (" + std::to_string(acc.rows()) + " samples) is shorter than one window (" +
                    std::to_string(window) + ")");
}
}  // namespace

Eigen::VectorXd ShoeStatistic(const Eigen::Ref<const RowMatrixXd>& acc, const Eigen::Ref<const RowMatrixXd>& gyro,
                              const ShoeOptions& options) {
  ValidateOptions(options);
  CheckImu(acc, gyro, options.window);
  const Eigen::Index n = acc.rows();
  const int w = options.window;
  const double inv_a = 1.0 / (options.sigma_acc_mps2 * options.sigma_acc_mps2);
  const double inv_g = 1.0 / (options.sigma_gyro_radps * options.sigma_gyro_radps);
  Eigen::VectorXd out(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    // Window of w samples centred on k, shifted inside the recording at its ends.
    Eigen::Index start = std::clamp<Eigen::Index>(k - w / 2, 0, n - w);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (Eigen::Index j = start; j < start + w; ++j) mean += acc.row(j).transpose();
    mean /= w;
    const double norm = mean.norm();
    const Eigen::Vector3d gdir = norm > 0 ? Eigen::Vector3d(options.gravity_mps2 * mean / norm) : Eigen::Vector3d::Zero();
    double t = 0.0;
    for (Eigen::Index j = start; j < start + w; ++j) {
      t += inv_a * (acc.row(j).transpose() - gdir).squaredNorm() + inv_g * gyro.row(j).squaredNorm();
    }
    out[k] = t / w;
  }
  return out;
}

BoolVector ShoeDetector(const Eigen::Ref<const RowMatrixXd>& acc, const Eigen::Ref<const RowMatrixXd>& gyro,
                        const ShoeOptions& options) {
  return (ShoeStatistic(acc, gyro, options).array() < options.threshold).matrix();
}

bool ZeroVelocityOptions::IsValid(std::string* error) const {
  if (!shoe.IsValid(error)) {
    *error = "shoe: " + *error;
    return false;
  }
  if (!(min_stance_fraction >= 0.0 && min_stance_fraction < 1.0)) {
    *error = "min_stance_fraction must be in [0, 1)";
    return false;
  }
  if (!(max_threshold > shoe.threshold) || !std::isfinite(max_threshold)) {
    *error = "max_threshold must be finite and > shoe.threshold";
    return false;
  }
  return true;
}

std::string ZeroVelocitySummary::BriefReport() const {
  std::ostringstream s;
  s.precision(3);
  s << "SHOE threshold " << threshold << (guard_raised ? " (raised by the stance guard from " : " (base ") << base_threshold
    << "), stance " << 100.0 * stance_fraction << " % of the recording, " << 100.0 * walking_stance_fraction
    << " % of the walking span [" << walking_begin << ", " << walking_end << ")";
  return s.str();
}

ZeroVelocityOutput DetectZeroVelocity(const Eigen::Ref<const RowMatrixXd>& acc, const Eigen::Ref<const RowMatrixXd>& gyro,
                                      const ZeroVelocityOptions& options) {
  ValidateOptions(options);
  ZeroVelocityOutput out;
  out.statistic = ShoeStatistic(acc, gyro, options.shoe);
  const Eigen::VectorXd& t = out.statistic;
  const Eigen::Index n = t.size();
  ZeroVelocitySummary& s = out.summary;
  s.base_threshold = s.threshold = options.shoe.threshold;
  // Walking span: first to last sample the base threshold calls moving.
  Eigen::Index begin = n, end = 0;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (t[k] >= options.shoe.threshold) {
      begin = std::min(begin, k);
      end = k + 1;
    }
  }
  if (begin >= end) begin = 0, end = n;  // never moving: the whole recording
  s.walking_begin = begin;
  s.walking_end = end;
  if (options.rule == ZeroVelocityRule::kStanceGuard && options.min_stance_fraction > 0.0) {
    // Q_f(T) over the span: the order statistic at floor(f (m - 1)) (lower quantile).
    std::vector<double> span(t.data() + begin, t.data() + end);
    const auto pos = static_cast<std::ptrdiff_t>(std::floor(options.min_stance_fraction * static_cast<double>(span.size() - 1)));
    std::nth_element(span.begin(), span.begin() + pos, span.end());
    // T < γ must hold for that sample too: step just above it.
    const double q = std::nextafter(span[static_cast<size_t>(pos)], std::numeric_limits<double>::infinity());
    if (q > s.threshold) {
      s.threshold = std::min(q, options.max_threshold);
      s.guard_raised = true;
    }
  }
  out.stance = (t.array() < s.threshold).matrix();
  const Eigen::Index count = out.stance.count();
  s.stance_fraction = n > 0 ? static_cast<double>(count) / static_cast<double>(n) : 0.0;
  s.walking_stance_fraction = static_cast<double>(out.stance.segment(begin, end - begin).count()) / static_cast<double>(end - begin);
  return out;
}

}  // namespace indoorloc::pdr
