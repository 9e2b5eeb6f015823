#include "indoorloc/wifi/rss_model.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::wifi {

thread_local Eigen::VectorXd RssModel::values_;
thread_local RowMatrixXd RssModel::gradients_;

namespace {
constexpr double kLog2Pi = 1.8378770664093453;
}  // namespace

bool RssModelOptions::IsValid(std::string* error) const {
  return Validator(error)
      .Scale(variance_floor_db2, "variance_floor_db2")  // divides every squared residual
      .Check(max_term > 0.0, "max_term", "must be > 0 (use inf for no cap), got " + FormatValue(max_term));
}

RssModel::RssModel(SignalMap map, RssModelOptions options)
    : map_(std::move(map)), options_(options) {
  ValidateOptions(options_);
  floors_ = map_.distinct_floors();
  const Eigen::Index k = map_.num_access_points();
  for (int floor : floors_) {
    std::vector<int> rows;
    for (int i = 0; i < map_.num_points(); ++i) {
      if (map_.floors()[i] == floor) rows.push_back(i);
    }
    RowMatrixXd positions(static_cast<Eigen::Index>(rows.size()), 2);
    RowMatrixXd fields(static_cast<Eigen::Index>(rows.size()), 2 * k);
    for (size_t r = 0; r < rows.size(); ++r) {
      positions.row(static_cast<Eigen::Index>(r)) = map_.positions_m().row(rows[r]);
      fields.row(static_cast<Eigen::Index>(r)).head(k) = map_.mean_dbm().row(rows[r]);
      fields.row(static_cast<Eigen::Index>(r)).tail(k) = map_.variance_db2().row(rows[r]);
    }
    try {
      interpolators_.emplace_back(positions, fields);
    } catch (const std::invalid_argument& e) {
      ThrowInvalidArgument("map", "floor " + std::to_string(floor) + ": " + e.what());
    }
    points_on_floor_.push_back(std::move(rows));
  }
}

int RssModel::FloorIndex(int floor) const {
  const auto it = std::find(floors_.begin(), floors_.end(), floor);
  if (it == floors_.end()) ThrowInvalidArgument("floor", "floor " + std::to_string(floor) + " is not in the map");
  return static_cast<int>(it - floors_.begin());
}

const DelaunayInterpolator& RssModel::interpolator(int floor_index) const {
  CheckArgument(floor_index >= 0 && floor_index < static_cast<int>(floors_.size()), "floor_index",
                "out of range");
  return interpolators_[static_cast<size_t>(floor_index)];
}

const std::vector<int>& RssModel::points_on_floor(int floor_index) const {
  CheckArgument(floor_index >= 0 && floor_index < static_cast<int>(floors_.size()), "floor_index",
                "out of range");
  return points_on_floor_[static_cast<size_t>(floor_index)];
}

void RssModel::EvaluateFields(const Eigen::Vector2d& z_m, int floor_index, int* hint, bool* inside,
                              Eigen::Vector2d* at) const {
  const DelaunayInterpolator& interp = interpolator(floor_index);
  const Eigen::Index k = map_.num_access_points();
  Eigen::VectorXd& values = values_;
  RowMatrixXd& gradients = gradients_;
  if (values.size() != 2 * k) values.resize(2 * k);
  if (gradients.cols() != 2 * k) gradients.resize(2, 2 * k);
  *inside = interp.Interpolate(z_m, values, gradients, hint);
  *at = *inside ? z_m : interp.ClampToHull(z_m);
}

RssLikelihood RssModel::Evaluate(const Eigen::Ref<const RowMatrixXd>& rss_dbm, const Eigen::Vector2d& z_m,
                                 int floor_index, int* hint) const {
  const Eigen::Index k = map_.num_access_points();
  if (rss_dbm.cols() != k) {  // (messages built only on failure: this runs per tracker step)
    ThrowInvalidArgument("rss_dbm", "has " + std::to_string(rss_dbm.cols()) + " AP columns, the map has " +
                                        std::to_string(k) + " (K mismatch between map and scan)");
  }
  CheckArgument(rss_dbm.rows() > 0, "rss_dbm", "no scan");
  RssLikelihood out;
  EvaluateFields(z_m, floor_index, hint, &out.inside, &out.evaluated_at_m);
  // One thread-local lookup each, not one per access (global-dynamic TLS in a shared module).
  const Eigen::VectorXd& values = values_;
  const RowMatrixXd& gradients = gradients_;
  const double n = static_cast<double>(rss_dbm.rows());
  for (Eigen::Index i = 0; i < k; ++i) {
    const double mean = values[i];
    double variance = values[k + i];
    Eigen::Vector2d grad_mean(gradients(0, i), gradients(1, i));
    Eigen::Vector2d grad_variance(gradients(0, k + i), gradients(1, k + i));
    if (variance < options_.variance_floor_db2) {  // floored: locally constant
      variance = options_.variance_floor_db2;
      grad_variance.setZero();
    }
    const double inv_var = 1.0 / variance;
    // Fisher information of n scans: n (∇m ∇mᵀ / δ + ∇δ ∇δᵀ / (2 δ²)).
    out.fisher += n * (inv_var * grad_mean * grad_mean.transpose() +
                       0.5 * inv_var * inv_var * grad_variance * grad_variance.transpose());
    for (Eigen::Index s = 0; s < rss_dbm.rows(); ++s) {
      const double r = rss_dbm(s, i) - mean;
      const double term = 0.5 * r * r * inv_var;
      out.neg_log_likelihood += 0.5 * (kLog2Pi + std::log(variance));
      out.gradient += 0.5 * inv_var * grad_variance;  // from ½ log δ
      if (term <= options_.max_term) {
        out.neg_log_likelihood += term;
        out.gradient += -0.5 * r * r * inv_var * inv_var * grad_variance - r * inv_var * grad_mean;
      } else {
        out.neg_log_likelihood += options_.max_term;
      }
    }
  }
  return out;
}

bool RssModel::MeanAndVariance(const Eigen::Vector2d& z_m, int floor_index, Eigen::VectorXd* mean_dbm,
                               Eigen::VectorXd* variance_db2, int* hint) const {
  bool inside;
  Eigen::Vector2d at;
  EvaluateFields(z_m, floor_index, hint, &inside, &at);
  const Eigen::Index k = map_.num_access_points();
  *mean_dbm = values_.head(k);
  *variance_db2 = values_.tail(k).cwiseMax(options_.variance_floor_db2);
  return inside;
}

Eigen::Matrix2d RssModel::FisherInformation(const Eigen::Vector2d& z_m, int floor_index, int* hint) const {
  Eigen::VectorXd mean, variance;
  MeanAndVariance(z_m, floor_index, &mean, &variance, hint);
  // The scan does not enter I: evaluate with the mean as a dummy scan.
  RowMatrixXd scan = mean.transpose();
  return Evaluate(scan, z_m, floor_index, hint).fisher;
}

}  // namespace indoorloc::wifi
