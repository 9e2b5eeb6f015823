// Plausibility bound on RSS inputs (private to the wifi subsystem).
#pragma once

#include "indoorloc/core/validate.h"

namespace indoorloc::wifi::internal {

/// |RSS| above this many dB is not a measurement: 1e300 dBm passed the finite check and gave
/// inf likelihoods. Real values lie within about [-200, 100] (sentinels included).
inline constexpr double kMaxAbsRssDb = 1e4;

template <typename Derived>
void CheckRss(const Eigen::DenseBase<Derived>& rss, std::string_view name) {
  RequireAllInRange(rss, -kMaxAbsRssDb, kMaxAbsRssDb, name);
}

}  // namespace indoorloc::wifi::internal
