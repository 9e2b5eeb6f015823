#include "indoorloc/wifi/gradient_tracker.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "rss_limits.h"

namespace indoorloc::wifi {
namespace {

// Covariance of a fix: I^{-1}, or a large isotropic covariance when I is singular.
Eigen::Matrix2d CovarianceFromFisher(const Eigen::Matrix2d& fisher) {
  const double det = fisher.determinant();
  if (!(det > 1e-18 * std::max(1.0, fisher.squaredNorm()))) return 1e6 * Eigen::Matrix2d::Identity();
  return fisher.inverse();
}

struct Step {
  Eigen::Vector2d z;
  RssLikelihood at;
  bool fallback = false;
  bool inside_raw = true;
  double length = 0.0;
};

// One Fisher-scoring step z <- z - I^{-1} ∇l with the step control of GradientTrackerOptions.
Step FisherStep(const RssModel& model, const Eigen::Ref<const RowMatrixXd>& scans,
                const Eigen::Vector2d& z, const RssLikelihood& here, int floor_index, int* hint,
                const GradientTrackerOptions& options, bool paper_mode) {
  Step out;
  const Eigen::Matrix2d& fisher = here.fisher;
  const Eigen::Vector2d& gradient = here.gradient;
  // Eigenvalues of the symmetric 2x2 I in closed form (this runs at every tracker step).
  const double half_trace = 0.5 * (fisher(0, 0) + fisher(1, 1));
  const double det = fisher(0, 0) * fisher(1, 1) - fisher(0, 1) * fisher(1, 0);
  const double spread = std::sqrt(std::max(0.0, half_trace * half_trace - det));
  const double lmax = half_trace + spread, lmin = half_trace - spread;
  Eigen::Vector2d delta;
  if (lmax > 0.0 && lmin / lmax >= options.min_reciprocal_condition) {
    // -I^{-1} ∇l with the adjugate inverse of the 2x2 I.
    delta << -(fisher(1, 1) * gradient[0] - fisher(0, 1) * gradient[1]) / det,
        -(-fisher(1, 0) * gradient[0] + fisher(0, 0) * gradient[1]) / det;
  } else if (lmax > 0.0) {
    // Proposition 1: I is (nearly) singular when all field gradients are parallel; a ridge
    // keeps the step along the informative direction finite.
    out.fallback = true;
    const Eigen::Matrix2d ridged =
        fisher + lmax * options.min_reciprocal_condition * Eigen::Matrix2d::Identity();
    delta = -ridged.ldlt().solve(gradient);
    const double n = delta.norm();
    if (n > options.fallback_step_m) delta *= options.fallback_step_m / n;
  } else {
    out.fallback = true;  // flat fields: a plain gradient step
    const double n = gradient.norm();
    delta = n > 0 ? Eigen::Vector2d(-gradient * (options.fallback_step_m / n)) : Eigen::Vector2d::Zero();
  }
  if (!delta.allFinite()) delta.setZero();
  if (!paper_mode) {
    const double n = delta.norm();
    if (n > options.max_step_m) delta *= options.max_step_m / n;
  }
  for (int halvings = 0;; ++halvings) {
    const Eigen::Vector2d candidate = z + delta;
    RssLikelihood at = model.Evaluate(scans, candidate, floor_index, hint);
    out.inside_raw = at.inside;
    // Keep on the mesh: outside the hull the model is evaluated at the projection; move there.
    out.z = at.evaluated_at_m;
    out.at = std::move(at);
    const bool worse = out.at.neg_log_likelihood > here.neg_log_likelihood;
    if (paper_mode || !options.backtracking || !worse || halvings >= 6) break;
    delta *= 0.5;
  }
  out.length = (out.z - z).norm();
  return out;
}

// Fisher-scoring iterations from a start until the step is below tolerance.
WifiFix Refine(const RssModel& model, const Eigen::Ref<const RowMatrixXd>& scans, Eigen::Vector2d z,
               int floor_index, const GradientTrackerOptions& options, int iterations) {
  int hint = -1;
  RssLikelihood here = model.Evaluate(scans, z, floor_index, &hint);
  z = here.evaluated_at_m;
  WifiFix fix;
  fix.inside = here.inside;
  for (int it = 0; it < iterations; ++it) {
    Step step = FisherStep(model, scans, z, here, floor_index, &hint, options, false);
    ++fix.iterations;
    fix.fallback_steps += step.fallback;
    if (step.at.neg_log_likelihood > here.neg_log_likelihood) break;  // no progress
    z = step.z;
    here = std::move(step.at);
    if (step.length < options.tolerance_m) break;
  }
  fix.position_m = z;
  fix.neg_log_likelihood = here.neg_log_likelihood;
  fix.covariance_m2 = CovarianceFromFisher(here.fisher);
  fix.floor = model.floors()[static_cast<size_t>(floor_index)];
  return fix;
}

void CheckScans(const RssModel& model, const Eigen::Ref<const RowMatrixXd>& scans) {
  CheckArgument(scans.rows() > 0, "rss_dbm", "no scan");
  CheckArgument(scans.cols() == model.num_access_points(), "rss_dbm",
                "has " + std::to_string(scans.cols()) + " AP columns, the map has " +
                    std::to_string(model.num_access_points()) + " (K mismatch between map and scan)");
  CheckFinite(scans, "rss_dbm");
  internal::CheckRss(scans, "rss_dbm");
}

}  // namespace

bool GradientTrackerOptions::IsValid(std::string* error) const {
  // Iteration counts are bounded so one call cannot run for hours (2**31 iterations per scan).
  Validator v(error);
  v.Scale(max_step_m, "max_step_m")
      .Check(min_reciprocal_condition > 0.0 && min_reciprocal_condition < 1.0, "min_reciprocal_condition",
             "must be in (0, 1), got " + FormatValue(min_reciprocal_condition))
      .Scale(fallback_step_m, "fallback_step_m")
      .IntInRange(iterations_per_scan, 1, 10000, "iterations_per_scan")
      .IntInRange(num_starts, 1, 10000, "num_starts")
      .IntInRange(start_iterations, 0, 100000, "start_iterations")
      .NonNegative(tolerance_m, "tolerance_m")
      .Check(relocalize_threshold_nats > 0.0, "relocalize_threshold_nats",
             "must be > 0 (inf: off), got " + FormatValue(relocalize_threshold_nats));
  return v.ok();
}

WifiFix LocateMaximumLikelihood(const RssModel& model, const Eigen::Ref<const RowMatrixXd>& rss_dbm,
                                const GradientTrackerOptions& options, int floor_index) {
  ValidateOptions(options);
  CheckScans(model, rss_dbm);
  const int num_floors = static_cast<int>(model.floors().size());
  CheckArgument(floor_index < num_floors, "floor_index", "out of range");
  // Score every reference point (of every floor, or of the given floor) by l at its position.
  struct Start {
    double l;
    int floor_index;
    Eigen::Vector2d z;
  };
  std::vector<Start> starts;
  for (int f = 0; f < num_floors; ++f) {
    if (floor_index >= 0 && f != floor_index) continue;
    // l at the reference points, as Evaluate gives it there (to rounding), from the table of
    // the heard APs' entries (not one interpolation of K APs per point).
    Eigen::VectorXd l;
    model.ReferencePointNegLogLikelihood(rss_dbm, f, &l);
    const std::vector<int>& rows = model.points_on_floor(f);
    for (size_t i = 0; i < rows.size(); ++i) {
      const Eigen::Vector2d z = model.map().positions_m().row(rows[i]).transpose();
      starts.push_back({l[static_cast<Eigen::Index>(i)], f, z});
    }
  }
  const size_t keep = std::min(starts.size(), static_cast<size_t>(options.num_starts));
  std::partial_sort(starts.begin(), starts.begin() + static_cast<std::ptrdiff_t>(keep), starts.end(),
                    [](const Start& a, const Start& b) { return a.l < b.l; });
  WifiFix best;
  best.neg_log_likelihood = std::numeric_limits<double>::infinity();
  for (size_t s = 0; s < keep; ++s) {
    WifiFix fix = Refine(model, rss_dbm, starts[s].z, starts[s].floor_index, options, options.start_iterations);
    if (fix.neg_log_likelihood < best.neg_log_likelihood) best = fix;
  }
  return best;
}

GradientTracker::GradientTracker(std::shared_ptr<const RssModel> model, GradientTrackerOptions options)
    : model_(std::move(model)), options_(options) {
  CheckArgument(model_ != nullptr, "model", "is null");
  ValidateOptions(options_);
  scan_.resize(1, model_->num_access_points());
}

void GradientTracker::Reset() {
  initialized_ = false;
  hint_ = -1;
}

void GradientTracker::ResetTo(const Eigen::Vector2d& position_m, int floor) {
  CheckArgument(position_m.allFinite(), "position_m", "is not finite");
  floor_index_ = model_->FloorIndex(floor);
  hint_ = -1;
  last_ = WifiFix();
  last_.position_m = position_m;
  last_.floor = floor;
  initialized_ = true;
}

WifiFix GradientTracker::Update(const Eigen::Ref<const Eigen::VectorXd>& rss_dbm) {
  if (rss_dbm.size() != model_->num_access_points()) {
    ThrowInvalidArgument("rss_dbm", "has " + std::to_string(rss_dbm.size()) + " values, the map has " +
                                        std::to_string(model_->num_access_points()) + " access points (K mismatch)");
  }
  scan_.row(0) = rss_dbm.transpose();
  CheckFinite(scan_, "rss_dbm");
  internal::CheckRss(scan_, "rss_dbm");
  if (!initialized_) {
    last_ = LocateMaximumLikelihood(*model_, scan_, options_);
    floor_index_ = model_->FloorIndex(last_.floor);
    hint_ = -1;
    initialized_ = true;
    return last_;
  }
  Eigen::Vector2d z = last_.position_m;
  RssLikelihood here = model_->Evaluate(scan_, z, floor_index_, &hint_);
  z = here.evaluated_at_m;
  WifiFix fix;
  fix.floor = last_.floor;
  fix.inside = here.inside;
  const int iterations = options_.paper_mode ? 1 : options_.iterations_per_scan;
  for (int it = 0; it < iterations; ++it) {
    Step step = FisherStep(*model_, scan_, z, here, floor_index_, &hint_, options_, options_.paper_mode);
    ++fix.iterations;
    fix.fallback_steps += step.fallback;
    fix.inside = fix.inside && step.inside_raw;
    z = step.z;
    here = std::move(step.at);
  }
  fix.position_m = z;
  fix.neg_log_likelihood = here.neg_log_likelihood;
  fix.covariance_m2 = CovarianceFromFisher(here.fisher);
  if (std::isfinite(options_.relocalize_threshold_nats)) {
    WifiFix global = LocateMaximumLikelihood(*model_, scan_, options_);
    if (fix.neg_log_likelihood - global.neg_log_likelihood > options_.relocalize_threshold_nats) {
      global.relocalized = true;
      global.iterations += fix.iterations;
      fix = global;
      floor_index_ = model_->FloorIndex(fix.floor);
      hint_ = -1;
    }
  }
  last_ = fix;
  return fix;
}

}  // namespace indoorloc::wifi
