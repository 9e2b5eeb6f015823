#include "indoorloc/pdr/zero_velocity.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>
#include <limits>
#include <vector>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "imu_timing.h"
#include "median.h"

namespace indoorloc::pdr {

bool ShoeOptions::IsValid(std::string* error) const {
  // The statistic divides by the squared sds: 1e-290 passed "> 0" and gave inf/NaN.
  return Validator(error)
      .IntInRange(window, 1, 1000000, "window")
      .Positive(threshold, "threshold")
      .Scale(sigma_acc_mps2, "sigma_acc_mps2")
      .Scale(sigma_gyro_radps, "sigma_gyro_radps")
      .InRange(gravity_mps2, 0.1, 100.0, "gravity_mps2");
}

namespace {
void CheckImu(const Eigen::Ref<const RowMatrixXd>& acc, const Eigen::Ref<const RowMatrixXd>& gyro, int window) {
  CheckShape(acc, -1, 3, "acc_mps2");
  CheckShape(gyro, acc.rows(), 3, "gyro_radps");
  CheckFinite(acc, "acc_mps2");
  CheckFinite(gyro, "gyro_radps");
  internal::CheckAccRange(acc);
  internal::CheckGyroRange(gyro);
  CheckArgument(acc.rows() >= window, "acc_mps2",
                "the recording (" + std::to_string(acc.rows()) + " samples) is shorter than one window (window = " +
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
  auto fail = [&](const char* why) {
    *error = why;
    return false;
  };
  if (!shoe.IsValid(error)) {
    *error = "shoe: " + *error;
    return false;
  }
  if (!(min_stance_fraction >= 0.0 && min_stance_fraction < 1.0)) return fail("min_stance_fraction must be in [0, 1)");
  if (!(max_threshold > shoe.threshold) || !std::isfinite(max_threshold)) return fail("max_threshold must be finite and > shoe.threshold");
  if (!(max_swing_s > 0.0) || !std::isfinite(max_swing_s)) return fail("max_swing_s must be > 0");
  if (!(max_swing_ratio > 1.0) || !std::isfinite(max_swing_ratio)) return fail("max_swing_ratio must be > 1");
  if (!(ladder_step_decades > 0.0 && ladder_step_decades <= 2.0)) return fail("ladder_step_decades must be in (0, 2]");
  if (!(min_stance_s >= 0.0) || !std::isfinite(min_stance_s)) return fail("min_stance_s must be >= 0");
  if (!(min_stance_share >= 0.0 && min_stance_share < 1.0)) return fail("min_stance_share must be in [0, 1)");
  if (!(min_plausible_swing_s >= 0.0 && min_plausible_swing_s < max_swing_s)) return fail("min_plausible_swing_s must be in [0, max_swing_s)");
  if (!(low_motion_min_stance_s >= 0.0) || !std::isfinite(low_motion_min_stance_s)) return fail("low_motion_min_stance_s must be >= 0");
  return true;
}

std::string ZeroVelocitySummary::BriefReport() const {
  std::ostringstream s;
  s.precision(3);
  s << "SHOE threshold " << threshold << (guard_raised ? " (raised by the guard from " : " (base ") << base_threshold;
  if (ladder_rungs > 0) s << ", " << ladder_rungs << " rungs";
  s << "), stance " << 100.0 * stance_fraction << " % of the recording, " << 100.0 * walking_stance_fraction
    << " % of the walking span [" << walking_begin << ", " << walking_end << ")";
  if (max_swing_s > 0.0) s << ", swings median " << median_swing_s << " s / max " << max_swing_s << " s";
  if (low_motion_rule) s << "; low-motion rule (stance shorter than " << flicker_s << " s inside a swing ignored)";
  if (!guard_satisfied) s << "; the guard found no threshold with a plausible gait (swings neither overlong nor shorter than a human swing)";
  return s.str();
}

namespace {

// Swings [samples] of T < threshold: runs of non-stance between two stance runs, and the runs
// before the first and after the last stance (a recording that ends while the foot "moves" has
// lost its stances), stance runs shorter than min_stance samples inside a swing counted as swing.
// Returns (max, median); (0, 0) when there is no swing.
std::pair<double, double> SwingStats(const Eigen::VectorXd& t, double threshold, Eigen::Index min_stance) {
  const Eigen::Index n = t.size();
  std::vector<double> swings;
  Eigen::Index last_stance_end = 0;  // end of the previous (long enough) stance run, 0 at the start
  for (Eigen::Index k = 0; k < n;) {
    if (!(t[k] < threshold)) {
      ++k;
      continue;
    }
    Eigen::Index e = k;
    while (e < n && t[e] < threshold) ++e;
    const bool interior_flicker = e - k < min_stance && k > 0 && e < n;
    if (!interior_flicker) {
      if (k > last_stance_end) swings.push_back(static_cast<double>(k - last_stance_end));
      last_stance_end = e;
    }
    k = e;
  }
  if (n > last_stance_end) swings.push_back(static_cast<double>(n - last_stance_end));
  if (swings.empty()) return {0.0, 0.0};
  return {*std::max_element(swings.begin(), swings.end()), internal::Median(swings)};
}

// Stance runs shorter than min_stance samples that lie inside the recording (flicker the swing
// guard ignored: SHOE's blind spot in mid-swing, where a steady acceleration leaves ||f|| near g)
// turned into swing, so that the filter receives the stance the guard judged.
BoolVector WithoutStanceFlicker(BoolVector stance, Eigen::Index min_stance) {
  const Eigen::Index n = stance.size();
  for (Eigen::Index k = 0; k < n;) {
    if (!stance[k]) {
      ++k;
      continue;
    }
    Eigen::Index e = k;
    while (e < n && stance[e]) ++e;
    if (e - k < min_stance && k > 0 && e < n) stance.segment(k, e - k).setConstant(false);
    k = e;
  }
  return stance;
}

struct Rung {
  double threshold = 0.0;
  int index = 0;
  double longest = 0.0;  // [samples]
  double median = 0.0;   // [samples]
};

// One climb of the swing guard's ladder with flicker length min_stance [samples]. Returns true
// with the first accepted rung in *accepted; rungs whose median swing is shorter than the
// plausible floor are never accepted (a threshold that high has eaten the swings). *best_plausible
// receives the plausible rung with the most regular swings (least longest / median; chosen over
// "no overlong swing first" by the low-motion study: docs/pdr.md).
bool ClimbLadder(const Eigen::VectorXd& t, const ZeroVelocityOptions& options, double rate_hz, Eigen::Index min_stance,
                 Rung* accepted, Rung* best_plausible) {
  const double max_swing = options.max_swing_s * rate_hz;
  const double floor = options.min_plausible_swing_s * rate_hz;
  const double n = static_cast<double>(std::max<Eigen::Index>(t.size(), 1));
  double best = std::numeric_limits<double>::infinity();  // least longest / median so far
  for (int j = 0;; ++j) {
    const double gamma = std::min(options.shoe.threshold * std::pow(10.0, j * options.ladder_step_decades), options.max_threshold);
    const auto [longest, median] = SwingStats(t, gamma, min_stance);
    const Rung rung{gamma, j, longest, median};
    if (median >= floor && median > 0.0) {
      if (longest / median < best) {
        best = longest / median;
        *best_plausible = rung;
      }
      const double share = static_cast<double>((t.array() < gamma).count()) / n;
      if (longest <= max_swing && longest <= options.max_swing_ratio * median && share >= options.min_stance_share) {
        *accepted = rung;
        return true;
      }
    }
    if (gamma >= options.max_threshold) return false;
  }
}

}  // namespace

ZeroVelocityOutput DetectZeroVelocity(const Eigen::Ref<const RowMatrixXd>& acc, const Eigen::Ref<const RowMatrixXd>& gyro,
                                      double rate_hz, const ZeroVelocityOptions& options) {
  ValidateOptions(options);
  CheckArgument(std::isfinite(rate_hz) && rate_hz > 0.0, "rate_hz", "must be a positive finite rate [Hz]");
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
  Eigen::Index flicker = 0;  // stance runs shorter than this inside a swing are dropped (swing guard)
  if (options.rule == ZeroVelocityRule::kSwingGuard) {
    // The guard's ladder, then the low-motion rule: a walk whose swings are slow and flat has
    // mid-swing dips of T below any threshold that finds its stances, so the plain ladder either
    // climbs until the "swings" are tens of ms (stance 98 %, no stride) or never settles. Its
    // second climb ignores stance shorter than low_motion_min_stance_s; when neither climb finds
    // a rung, the most regular plausible rung is used and guard_satisfied stays false (the
    // health check then reports the result implausible).
    const Eigen::Index normal = std::max<Eigen::Index>(1, std::lround(options.min_stance_s * rate_hz));
    const Eigen::Index low = std::max<Eigen::Index>(1, std::lround(options.low_motion_min_stance_s * rate_hz));
    Rung chosen{options.shoe.threshold, 0, 0.0, 0.0}, best_normal = chosen, best_low = chosen;
    bool have_best = false;
    flicker = normal;
    s.guard_satisfied = ClimbLadder(t, options, rate_hz, normal, &chosen, &best_normal);
    if (!s.guard_satisfied) {
      s.low_motion_rule = true;
      flicker = low;
      best_low.median = -1.0;
      s.guard_satisfied = ClimbLadder(t, options, rate_hz, low, &chosen, &best_low);
      have_best = best_low.median > 0.0;
      if (!s.guard_satisfied) chosen = have_best ? best_low : Rung{options.shoe.threshold, 0, 0.0, 0.0};
    }
    if (chosen.median <= 0.0) {  // no plausible rung at all: the base threshold, described
      const auto [longest, median] = SwingStats(t, chosen.threshold, flicker);
      chosen.longest = longest;
      chosen.median = median;
    }
    s.threshold = chosen.threshold;
    s.ladder_rungs = chosen.index;
    s.max_swing_s = chosen.longest / rate_hz;
    s.median_swing_s = chosen.median / rate_hz;
    s.flicker_s = static_cast<double>(flicker) / rate_hz;
    s.guard_raised = s.threshold > options.shoe.threshold;
  }
  out.stance = (t.array() < s.threshold).matrix();
  if (flicker > 1) out.stance = WithoutStanceFlicker(std::move(out.stance), flicker);
  const Eigen::Index count = out.stance.count();
  s.stance_fraction = n > 0 ? static_cast<double>(count) / static_cast<double>(n) : 0.0;
  s.walking_stance_fraction = static_cast<double>(out.stance.segment(begin, end - begin).count()) / static_cast<double>(end - begin);
  return out;
}

}  // namespace indoorloc::pdr
