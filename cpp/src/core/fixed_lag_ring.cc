#include "indoorloc/core/fixed_lag_ring.h"

#include <algorithm>
#include <limits>
#include <string>

#include "indoorloc/core/check.h"

namespace indoorloc {

void FixedLagRing::Reset(int num_particles, int lag_steps) {
  CheckArgument(num_particles >= 0, "num_particles", "must be >= 0");
  CheckArgument(lag_steps >= 0, "lag_steps", "must be >= 0");
  num_particles_ = num_particles;
  lag_steps_ = lag_steps;
  steps_ = 0;
  slot_ = 0;
  const size_t size = lag_steps > 0 ? static_cast<size_t>(num_particles) * slots() * 2 : 0;
  data_.assign(size, std::numeric_limits<double>::quiet_NaN());
  scratch_.clear();
  scratch_.shrink_to_fit();
}

Eigen::Vector2d FixedLagRing::WeightedSum(const double* weights) const {
  // The slot written L steps before the last one is the one the next step will overwrite.
  const size_t oldest = slot_;
  const size_t stride = slots() * 2;
  double sx = 0.0, sy = 0.0;
  for (int i = 0; i < num_particles_; ++i) {
    const double* p = data_.data() + static_cast<size_t>(i) * stride + oldest * 2;
    sx += weights[i] * p[0];
    sy += weights[i] * p[1];
  }
  return Eigen::Vector2d(sx, sy);
}

void FixedLagRing::Gather(const std::vector<int>& ancestors) {
  if (!enabled()) return;
  CheckArgument(ancestors.size() == static_cast<size_t>(num_particles_), "ancestors",
                "needs one entry per particle (" + std::to_string(num_particles_) + ")");
  const size_t stride = slots() * 2;
  scratch_.resize(data_.size());
  for (int i = 0; i < num_particles_; ++i) {
    const int a = ancestors[static_cast<size_t>(i)];
    if (a < 0 || a >= num_particles_) {
      ThrowInvalidArgument("ancestors", "entry " + std::to_string(i) + " is not a particle index");
    }
    std::copy_n(data_.begin() + static_cast<std::ptrdiff_t>(static_cast<size_t>(a) * stride), stride,
                scratch_.begin() + static_cast<std::ptrdiff_t>(static_cast<size_t>(i) * stride));
  }
  data_.swap(scratch_);
}

}  // namespace indoorloc
