#include "indoorloc/wifi/rss_model.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "point_likelihood_table.h"

namespace indoorloc::wifi {

// What Evaluate and ReferencePointNegLogLikelihood need beyond the interpolators: each AP's
// background pair (point_likelihood_table.h), and per floor the APs that leave it at some vertex
// of each triangle ("active"), the background log-normaliser of the rest, and the table of l
// at the reference points.
struct RssModel::SparseTerms {
  struct Floor {
    std::vector<int> active_start;            // T + 1 (CSR over triangles)
    std::vector<int> active_ap;               // AP indices, ascending per triangle
    std::vector<double> background_log_norm;  // T: Σ_{a not active} ½ log(2π δ_a)
    internal::PointLikelihoodTable reference_points;
  };
  internal::ApBackground background;
  Eigen::VectorXd background_inv_var;  // K
  std::vector<Floor> floors;
};

thread_local Eigen::VectorXd RssModel::values_;
thread_local RowMatrixXd RssModel::gradients_;

namespace {
constexpr double kLog2Pi = 1.8378770664093453;

// One access point's variance δ floored at `floor` (locally constant there, so its gradient
// vanishes), and the Fisher information of n scans added to *fisher:
// n (∇m ∇mᵀ / δ + ∇δ ∇δᵀ / (2 δ²)). Returns 1 / δ.
inline double FloorVarianceAddFisher(double floor, double n, const Eigen::Vector2d& grad_mean, double* variance,
                                     Eigen::Vector2d* grad_variance, Eigen::Matrix2d* fisher) {
  if (*variance < floor) {
    *variance = floor;
    grad_variance->setZero();
  }
  const double inv_var = 1.0 / *variance;
  *fisher += n * (inv_var * grad_mean * grad_mean.transpose() +
                  0.5 * inv_var * inv_var * *grad_variance * grad_variance->transpose());
  return inv_var;
}
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
  BuildSparseTerms();
}

void RssModel::BuildSparseTerms() {
  auto sparse = std::make_shared<SparseTerms>();
  const Eigen::Index k = map_.num_access_points();
  const double floor_db2 = options_.variance_floor_db2;
  sparse->background = internal::FindBackground(map_.mean_dbm(), map_.variance_db2(), floor_db2);
  sparse->background_inv_var = sparse->background.variance_db2.cwiseInverse();
  Eigen::VectorXd log_norm(k), variance(k);
  for (Eigen::Index a = 0; a < k; ++a) log_norm[a] = 0.5 * (kLog2Pi + std::log(sparse->background.variance_db2[a]));
  for (size_t f = 0; f < interpolators_.size(); ++f) {
    SparseTerms::Floor floor;
    const std::vector<int>& rows = points_on_floor_[f];
    // Per point of this floor: does AP a leave its background there?
    const Eigen::Index n = static_cast<Eigen::Index>(rows.size());
    Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> active(n, k);
    floor.reference_points = internal::PointLikelihoodTable(sparse->background, options_.max_term);
    for (Eigen::Index i = 0; i < n; ++i) {
      const int row = rows[static_cast<size_t>(i)];
      for (Eigen::Index a = 0; a < k; ++a) {
        variance[a] = std::max(map_.variance_db2()(row, a), floor_db2);
        active(i, a) = !internal::IsBackground(sparse->background, a, map_.mean_dbm()(row, a), variance[a]);
      }
      floor.reference_points.AddPoint(map_.mean_dbm().row(row).data(), variance.data());
    }
    floor.reference_points.Finish();
    const Eigen::MatrixXi triangles = interpolators_[f].Triangles();
    floor.active_start.assign(1, 0);
    for (Eigen::Index t = 0; t < triangles.rows(); ++t) {
      double background_log_norm = 0.0;
      for (Eigen::Index a = 0; a < k; ++a) {
        if (active(triangles(t, 0), a) || active(triangles(t, 1), a) || active(triangles(t, 2), a)) {
          floor.active_ap.push_back(static_cast<int>(a));
        } else {
          background_log_norm += log_norm[a];
        }
      }
      floor.active_start.push_back(static_cast<int>(floor.active_ap.size()));
      floor.background_log_norm.push_back(background_log_norm);
    }
    sparse->floors.push_back(std::move(floor));
  }
  sparse_ = std::move(sparse);
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

RssLikelihood RssModel::EvaluateEveryAccessPoint(const Eigen::Ref<const RowMatrixXd>& rss_dbm,
                                                 const Eigen::Vector2d& z_m, int floor_index, int* hint) const {
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
    const double inv_var = FloorVarianceAddFisher(options_.variance_floor_db2, n, grad_mean, &variance,
                                                  &grad_variance, &out.fisher);
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

RssLikelihood RssModel::Evaluate(const Eigen::Ref<const RowMatrixXd>& rss_dbm, const Eigen::Vector2d& z_m,
                                 int floor_index, int* hint) const {
  const Eigen::Index k = map_.num_access_points();
  if (rss_dbm.cols() != k) {  // (messages built only on failure: this runs per tracker step)
    ThrowInvalidArgument("rss_dbm", "has " + std::to_string(rss_dbm.cols()) + " AP columns, the map has " +
                                        std::to_string(k) + " (K mismatch between map and scan)");
  }
  CheckArgument(rss_dbm.rows() > 0, "rss_dbm", "no scan");
  const DelaunayInterpolator& interp = interpolator(floor_index);
  const FaceLocation loc = interp.LocateFace(z_m, hint);
  RssLikelihood out;
  out.inside = loc.inside;
  out.evaluated_at_m = loc.inside ? z_m : interp.ClampToHull(z_m);
  const SparseTerms& sparse = *sparse_;
  const SparseTerms::Floor& floor = sparse.floors[static_cast<size_t>(floor_index)];
  const Eigen::Index n_scans = rss_dbm.rows();
  const double n = static_cast<double>(n_scans);
  const double* bg_mean = sparse.background.mean_dbm.data();
  const double* bg_inv_var = sparse.background_inv_var.data();
  const double cap = options_.max_term;
  // Every AP at its background: n Σ ½ log(2π δ_a) + Σ_s Σ_a c_a(v_sa); active APs replace
  // their share below by their interpolated terms.
  double l = n * floor.background_log_norm[static_cast<size_t>(loc.triangle)];
  for (Eigen::Index s = 0; s < n_scans; ++s) {
    for (Eigen::Index a = 0; a < k; ++a) {
      const double r0 = rss_dbm(s, a) - bg_mean[a];
      l += std::min(0.5 * r0 * r0 * bg_inv_var[a], cap);
    }
  }
  const RowMatrixXd& fields = interp.fields();
  const double* f0 = fields.row(loc.vertices[0]).data();
  const double* f1 = fields.row(loc.vertices[1]).data();
  const double* f2 = fields.row(loc.vertices[2]).data();
  const double* b = loc.weights;
  const int begin = floor.active_start[static_cast<size_t>(loc.triangle)];
  const int end = floor.active_start[static_cast<size_t>(loc.triangle) + 1];
  for (int e = begin; e < end; ++e) {
    const Eigen::Index i = floor.active_ap[static_cast<size_t>(e)];
    const Eigen::Index j = k + i;
    // As DelaunayInterpolator::Interpolate computes each field and its gradient.
    const double mean = b[0] * f0[i] + b[1] * f1[i] + b[2] * f2[i];
    double variance = b[0] * f0[j] + b[1] * f1[j] + b[2] * f2[j];
    const double dm1 = f1[i] - f0[i], dm2 = f2[i] - f0[i];
    const double dv1 = f1[j] - f0[j], dv2 = f2[j] - f0[j];
    const Eigen::Vector2d grad_mean(dm1 * loc.grad_b1[0] + dm2 * loc.grad_b2[0], dm1 * loc.grad_b1[1] + dm2 * loc.grad_b2[1]);
    Eigen::Vector2d grad_variance(dv1 * loc.grad_b1[0] + dv2 * loc.grad_b2[0],
                                  dv1 * loc.grad_b1[1] + dv2 * loc.grad_b2[1]);
    const double inv_var = FloorVarianceAddFisher(options_.variance_floor_db2, n, grad_mean, &variance,
                                                  &grad_variance, &out.fisher);
    for (Eigen::Index s = 0; s < n_scans; ++s) {
      const double v = rss_dbm(s, i);
      const double r0 = v - bg_mean[i];
      l -= std::min(0.5 * r0 * r0 * bg_inv_var[i], cap);  // its background share, added above
      const double r = v - mean;
      const double term = 0.5 * r * r * inv_var;
      l += 0.5 * (kLog2Pi + std::log(variance));
      out.gradient += 0.5 * inv_var * grad_variance;  // from ½ log δ
      if (term <= cap) {
        l += term;
        out.gradient += -0.5 * r * r * inv_var * inv_var * grad_variance - r * inv_var * grad_mean;
      } else {
        l += cap;
      }
    }
  }
  out.neg_log_likelihood = l;
  return out;
}

void RssModel::ReferencePointNegLogLikelihood(const Eigen::Ref<const RowMatrixXd>& rss_dbm, int floor_index,
                                              Eigen::VectorXd* neg_log_likelihood) const {
  CheckArgument(rss_dbm.cols() == map_.num_access_points(), "rss_dbm", "has the wrong number of AP columns");
  CheckArgument(floor_index >= 0 && floor_index < static_cast<int>(floors_.size()), "floor_index", "out of range");
  sparse_->floors[static_cast<size_t>(floor_index)].reference_points.NegLogLikelihood(rss_dbm, neg_log_likelihood);
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
