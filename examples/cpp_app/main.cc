#include <cmath>
#include <cstdio>
#include <vector>
#include <indoorloc/core.h>

int main() {  // Weight 1000 particles by a Gaussian likelihood, resample when ESS < N/2.
  indoorloc::RandomStream rng(/*seed=*/42);
  Eigen::VectorXd log_w(1000);
  for (auto& lw : log_w) lw = -0.5 * std::pow((rng.Normal() - 0.5) / 0.3, 2);
  std::vector<int> ancestors;
  auto summary = indoorloc::ResampleIfNeeded(log_w, indoorloc::ResamplingOptions(), rng, &ancestors);
  std::printf("indoorloc %s: %s\n", indoorloc::kVersion, summary.BriefReport().c_str());
  return summary.resampled && ancestors.size() == 1000 ? 0 : 1;
}
