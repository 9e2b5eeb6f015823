// Private helper of the pdr algorithms that summarise gait phases (stride counting, the swing
// guard of the zero-velocity detector, the ZUPT EKF health check): the median of a sample.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace indoorloc::pdr::internal {

/// Median of `values` (the mean of the two middle values for an even count); 0 when empty, which
/// every caller reads as "no phase of this kind". Takes a copy: nth_element reorders it.
inline double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  double m = *mid;
  if (values.size() % 2 == 0) m = 0.5 * (m + *std::max_element(values.begin(), mid));
  return m;
}

}  // namespace indoorloc::pdr::internal
