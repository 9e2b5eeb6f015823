#include "indoorloc/pdr/stride_count.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "median.h"

namespace indoorloc::pdr {

bool StrideCountOptions::IsValid(std::string* error) const {
  auto fail = [&](const char* why) {
    *error = why;
    return false;
  };
  if (!(min_stance_s >= 0.0) || !std::isfinite(min_stance_s)) return fail("min_stance_s must be >= 0");
  if (!(min_swing_s >= 0.0) || !std::isfinite(min_swing_s)) return fail("min_swing_s must be >= 0");
  if (!(min_swing_fraction >= 0.0 && min_swing_fraction < 1.0)) return fail("min_swing_fraction must be in [0, 1)");
  if (!(long_swing_factor == 0.0 || (long_swing_factor > 1.0 && std::isfinite(long_swing_factor))))
    return fail("long_swing_factor must be > 1 (or 0 to disable)");
  return true;
}

std::string StrideCountSummary::BriefReport() const {
  std::ostringstream s;
  s.precision(3);
  s << n_strides << " strides (" << n_split_strides << " from split long swings), " << n_flicker_stances
    << " flicker stances and " << n_flicker_swings << " flicker swings merged, median swing " << median_swing_s
    << " s, median stance " << median_stance_s << " s";
  return s.str();
}

namespace {

struct Run {
  Eigen::Index begin, end;  // [begin, end)
  bool value;
};

std::vector<Run> Runs(const BoolVector& s) {
  std::vector<Run> runs;
  for (Eigen::Index k = 0; k < s.size();) {
    Eigen::Index e = k;
    while (e < s.size() && s[e] == s[k]) ++e;
    runs.push_back({k, e, s[k]});
    k = e;
  }
  return runs;
}


}  // namespace

StrideCountOutput CountStrides(const BoolVector& stance, double rate_hz, const StrideCountOptions& options) {
  ValidateOptions(options);
  CheckArgument(std::isfinite(rate_hz) && rate_hz > 0.0, "rate_hz", "must be a positive finite rate [Hz]");
  StrideCountOutput out;
  BoolVector s = stance;
  const Eigen::Index n = s.size();
  out.cleaned_stance = s;
  if (n == 0) return out;
  const Eigen::Index min_stance = std::max<Eigen::Index>(1, std::lround(options.min_stance_s * rate_hz));
  const Eigen::Index swing_floor = std::max<Eigen::Index>(1, std::lround(options.min_swing_s * rate_hz));
  // 1. Interior stance runs shorter than min_stance become swing.
  for (const Run& r : Runs(s)) {
    if (r.value && r.end - r.begin < min_stance && r.begin > 0 && r.end < n) {
      s.segment(r.begin, r.end - r.begin).setConstant(false);
      ++out.summary.n_flicker_stances;
    }
  }
  // 2. The rhythm: median of the interior swings above the floor; shorter swings become stance.
  std::vector<double> swings;
  for (const Run& r : Runs(s)) {
    if (!r.value && r.begin > 0 && r.end < n && r.end - r.begin >= swing_floor) swings.push_back(static_cast<double>(r.end - r.begin));
  }
  const double rhythm = internal::Median(swings);
  const double min_swing = std::max(static_cast<double>(swing_floor), options.min_swing_fraction * rhythm);
  for (const Run& r : Runs(s)) {
    if (!r.value && r.begin > 0 && r.end < n && static_cast<double>(r.end - r.begin) < min_swing) {
      s.segment(r.begin, r.end - r.begin).setConstant(true);
      ++out.summary.n_flicker_swings;
    }
  }
  out.cleaned_stance = s;
  // Stance onsets and the swing before each (from the previous stance's end, or the start).
  std::vector<std::pair<Eigen::Index, Eigen::Index>> onsets;  // (onset, swing length)
  std::vector<double> stances;
  Eigen::Index swing_start = 0;
  for (const Run& r : Runs(s)) {
    if (r.value) {
      if (r.begin > 0) onsets.emplace_back(r.begin, r.begin - swing_start);
      if (r.begin > 0 && r.end < n) stances.push_back(static_cast<double>(r.end - r.begin));
    } else {
      swing_start = r.begin;
    }
  }
  std::vector<double> lengths;
  for (const auto& o : onsets) lengths.push_back(static_cast<double>(o.second));
  const double median = internal::Median(lengths);
  out.summary.median_swing_s = median / rate_hz;
  out.summary.median_stance_s = internal::Median(stances) / rate_hz;
  // 3. Long swings hold missed stances.
  for (const auto& [onset, length] : onsets) {
    if (options.long_swing_factor > 0.0 && median > 0.0 && static_cast<double>(length) > options.long_swing_factor * median) {
      const int m = static_cast<int>(std::lround(static_cast<double>(length) / median));
      for (int j = 1; j < m; ++j) {
        out.stride_indices.push_back(static_cast<int>(onset - length + std::lround(j * static_cast<double>(length) / m)));
        ++out.summary.n_split_strides;
      }
    }
    out.stride_indices.push_back(static_cast<int>(onset));
  }
  out.summary.n_strides = static_cast<int>(out.stride_indices.size());
  return out;
}

}  // namespace indoorloc::pdr
