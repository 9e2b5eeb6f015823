#include "indoorloc/core/log_weights.h"

#include <cmath>
#include <limits>

#include "indoorloc/core/check.h"

namespace indoorloc {
namespace {

constexpr double kMinusInf = -std::numeric_limits<double>::infinity();

// Names the first NaN or +inf entry (slow path, only when the vectorised checks failed).
[[noreturn]] void ThrowBadLogWeight(const Eigen::Ref<const Eigen::VectorXd>& log_weights) {
  for (Eigen::Index i = 0; i < log_weights.size(); ++i) {
    const double v = log_weights[i];
    if (std::isnan(v)) ThrowInvalidArgument("log_weights", DescribeEntry(i, 0, true) + " is NaN");
    if (v == std::numeric_limits<double>::infinity()) {
      ThrowInvalidArgument("log_weights", DescribeEntry(i, 0, true) + " is +inf");
    }
  }
  ThrowInvalidArgument("log_weights", "holds NaN or +inf");
}

}  // namespace

double CheckedMaxLogWeight(const Eigen::Ref<const Eigen::VectorXd>& log_weights) {
  CheckArgument(log_weights.size() > 0, "log_weights", "is empty");
  if (log_weights.hasNaN()) ThrowBadLogWeight(log_weights);
  const double max = log_weights.maxCoeff();
  if (max == std::numeric_limits<double>::infinity()) ThrowBadLogWeight(log_weights);
  CheckArgument(max != kMinusInf, "log_weights", "all weights are zero (every log-weight is -inf)");
  return max;
}

double LogSumExp(const Eigen::Ref<const Eigen::VectorXd>& log_weights) {
  if (log_weights.size() == 0) return kMinusInf;
  if (log_weights.hasNaN()) ThrowBadLogWeight(log_weights);
  const double max = log_weights.maxCoeff();
  if (max == std::numeric_limits<double>::infinity()) ThrowBadLogWeight(log_weights);
  if (max == kMinusInf) return kMinusInf;
  return max + std::log((log_weights.array() - max).exp().sum());
}

double NormalizeLogWeights(Eigen::Ref<Eigen::VectorXd> log_weights) {
  const double max = CheckedMaxLogWeight(log_weights);
  const double log_sum = max + std::log((log_weights.array() - max).exp().sum());
  log_weights.array() -= log_sum;
  return log_sum;
}

Eigen::VectorXd NormalizedWeights(const Eigen::Ref<const Eigen::VectorXd>& log_weights) {
  Eigen::VectorXd w = log_weights;
  NormalizeLogWeights(w);
  return w.array().exp();
}

double EffectiveSampleSize(const Eigen::Ref<const Eigen::VectorXd>& log_weights) {
  const double max = CheckedMaxLogWeight(log_weights);
  const Eigen::ArrayXd w = (log_weights.array() - max).exp();
  const double sum = w.sum();
  return sum * sum / w.square().sum();
}

}  // namespace indoorloc
