#include "indoorloc/fusion/position_fix.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "indoorloc/core/check.h"
#include "indoorloc/core/log_weights.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::fusion {

bool FixLikelihoodOptions::IsValid(std::string* error) const {
  return Validator(error)
      .Check(outlier_probability > 0.0 && outlier_probability < 1.0, "outlier_probability",
             "must be in (0, 1), got " + FormatValue(outlier_probability))
      .Check(tempering > 0.0 && tempering <= 1.0, "tempering", "must be in (0, 1], got " + FormatValue(tempering));
}

PositionFix FixFromCandidates(double time_s, const Eigen::Ref<const PositionFix::Means>& means_m,
                              const Eigen::Ref<const Eigen::VectorXd>& sds_m,
                              const Eigen::Ref<const Eigen::VectorXd>& weights,
                              const Eigen::Ref<const Eigen::VectorXi>& floors) {
  const Eigen::Index k = weights.size();
  CheckArgument(means_m.rows() == k && sds_m.size() == k && floors.size() == k, "candidates",
                "means_m, sds_m, weights and floors must have one entry per candidate");
  PositionFix fix;
  fix.time_s = time_s;
  const Eigen::Index used = (weights.array() != 0.0).count();
  fix.means_m.resize(used, 2);
  fix.sds_m.resize(used);
  fix.weights.resize(used);
  fix.floors.resize(used);
  Eigen::Index c = 0;
  for (Eigen::Index j = 0; j < k; ++j) {
    if (weights[j] == 0.0) continue;
    fix.means_m.row(c) = means_m.row(j);
    fix.sds_m[c] = sds_m[j];
    fix.weights[c] = weights[j];
    fix.floors[c] = floors[j];
    ++c;
  }
  return fix;
}

// The messages below are built only for a fix that fails its check (every fix of every run is
// checked: formatting the bounds eagerly took a few per cent of an evaluation).
void CheckPositionFix(const PositionFix& fix, const char* argument) {
  const std::string arg(argument);
  CheckArgument(std::isfinite(fix.time_s), arg + ".time_s", "must be finite");
  const Eigen::Index k = fix.means_m.rows();
  if (fix.sds_m.size() != k) {
    CheckArgument(false, arg + ".sds_m",
                  "has " + std::to_string(fix.sds_m.size()) + " entries, means_m has " + std::to_string(k) + " rows");
  }
  if (fix.weights.size() != k) {
    CheckArgument(false, arg + ".weights",
                  "has " + std::to_string(fix.weights.size()) + " entries, means_m has " + std::to_string(k) + " rows");
  }
  if (!(fix.floors.size() == 0 || fix.floors.size() == k)) {
    CheckArgument(false, arg + ".floors",
                  "has " + std::to_string(fix.floors.size()) + " entries, means_m has " + std::to_string(k) +
                      " rows (or pass none: any floor)");
  }
  if (k == 0) return;
  CheckFinite(fix.means_m, (arg + ".means_m").c_str());
  RequireAllInRange(fix.means_m, -kMaxScale, kMaxScale, arg + ".means_m");
  double total = 0.0;
  for (Eigen::Index i = 0; i < k; ++i) {
    // A Scale: 1e-300 passed "> 0" but 1 / (2 sd²) is inf and the estimate became NaN.
    if (!(fix.sds_m[i] >= kMinScale && fix.sds_m[i] <= kMaxScale)) {
      CheckArgument(false, arg + ".sds_m",
                    "entry " + std::to_string(i) + " must be finite and in [" + FormatValue(kMinScale) + ", " +
                        FormatValue(kMaxScale) + "] m, got " + FormatValue(fix.sds_m[i]));
    }
    if (!(std::isfinite(fix.weights[i]) && fix.weights[i] >= 0.0)) {
      CheckArgument(false, arg + ".weights",
                    "entry " + std::to_string(i) + " = " + std::to_string(fix.weights[i]) + " must be finite and >= 0");
    }
    total += fix.weights[i];
  }
  CheckArgument(total > 0.0, arg + ".weights", "sum to 0 (a fix needs at least one component with weight > 0)");
}

FixLikelihood::FixLikelihood(const PositionFix& fix, const FixLikelihoodOptions& options)
    : fix_(fix), options_(options) {
  const Eigen::Index k = fix.means_m.rows();
  log_component_scale_.resize(k);
  inv_two_var_.resize(k);
  const double total = fix.weights.sum();
  const double log_inlier = std::log1p(-options.outlier_probability);
  for (Eigen::Index i = 0; i < k; ++i) {
    const double var = fix.sds_m[i] * fix.sds_m[i];
    inv_two_var_[i] = 0.5 / var;
    log_component_scale_[i] = fix.weights[i] > 0.0
                                  ? log_inlier + std::log(fix.weights[i] / total) - std::log(2.0 * M_PI * var)
                                  : -std::numeric_limits<double>::infinity();
  }
}

double FixLikelihood::LogLikelihood(double x_m, double y_m, int floor, double area_m2) const {
  if (fix_.empty()) return 0.0;
  // log(ε / A) is the same for every particle of a cloud: kept per thread for the last (ε, A).
  thread_local double last_ratio = std::numeric_limits<double>::quiet_NaN(), last_log_outlier = 0.0;
  const double ratio = options_.outlier_probability / area_m2;
  if (!(ratio == last_ratio)) {
    last_ratio = ratio;
    last_log_outlier = std::log(ratio);
  }
  const double log_outlier = last_log_outlier;
  double best = log_outlier;
  const Eigen::Index k = fix_.means_m.rows();
  const bool any_floor = fix_.floors.size() == 0;
  // Log-sum-exp over the outlier term and the components on this floor, in two passes.
  thread_local Eigen::VectorXd terms;
  terms.resize(k);
  for (Eigen::Index i = 0; i < k; ++i) {
    if (!any_floor && fix_.floors[i] != PositionFix::kAnyFloor && fix_.floors[i] != floor) {
      terms[i] = -std::numeric_limits<double>::infinity();
      continue;
    }
    const double dx = x_m - fix_.means_m(i, 0), dy = y_m - fix_.means_m(i, 1);
    terms[i] = log_component_scale_[i] - (dx * dx + dy * dy) * inv_two_var_[i];
    best = std::max(best, terms[i]);
  }
  double sum = ExpOfLogDifference(log_outlier - best);
  for (Eigen::Index i = 0; i < k; ++i) sum += ExpOfLogDifference(terms[i] - best);
  return options_.tempering * (best + std::log(sum));
}

}  // namespace indoorloc::fusion
