// The grid tracker's result from its layers (grid_run.h): the layers' weights are prior x
// evidence (up to step k for the filter, the whole walk for the smoother), and per step the
// mixture's mean and covariance, the floor and heading-offset posteriors, the spatial medians of
// the blocks, and the calibration of the returned covariances (GridTrackerOptions).
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <utility>

#include "grid_run.h"

namespace indoorloc::fusion::grid_run {

using namespace grid_ops;  // NOLINT

namespace {

// The spatial median argmin_x Σ m_i |x - p_i| of weighted points (Weiszfeld's iteration from the
// weighted mean; the objective is convex, so the start only sets the speed). Distances are floored
// at `floor_m` (the points are block centroids, a block's own spread is of that order).
Eigen::Vector2d SpatialMedian(const std::vector<Eigen::Vector3d>& points, double floor_m) {
  double mass = 0;
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  for (const auto& p : points) {
    mass += p[0];
    x += p[0] * p.tail<2>();
  }
  if (!(mass > 0)) return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  x /= mass;
  for (int it = 0; it < 100; ++it) {
    Eigen::Vector2d num = Eigen::Vector2d::Zero();
    double den = 0;
    for (const auto& p : points) {
      const double w = p[0] / std::max(floor_m, (p.tail<2>() - x).norm());
      num += w * p.tail<2>();
      den += w;
    }
    const Eigen::Vector2d next = num / den;
    const double moved = (next - x).norm();
    x = next;
    if (moved < 1e-3) break;
  }
  return x;
}

// The calibration of one estimator's rows.
struct Calibration {
  double a, b, g, h, s0;
};

// Σ' = a Σ + (b² + (g d)² + (h max(0, s - s0))²) I per step k >= k0 (GridTrackerOptions,
// "Calibration of the returned covariances"; grid_ops.h CalibratedCovariance); the posterior's own
// Σ, the fix distance d and the fix sd s are kept beside it.
void CalibrateRows(const RowMatrixXd& mean, const Calibration& cal,
                   const std::function<int(int, const Eigen::Vector2d&)>& fix_of, const std::vector<Eigen::Vector2d>& centres,
                   const std::vector<double>& sds, int k0, RowMatrixXd* cov, RowMatrixXd* posterior,
                   Eigen::VectorXd* distance, Eigen::VectorXd* fix_sd) {
  *posterior = *cov;
  distance->setZero(cov->rows());
  fix_sd->setZero(cov->rows());
  for (Eigen::Index k = k0; k < cov->rows(); ++k) {
    const Eigen::Vector2d m = mean.row(k).transpose();
    const int j = fix_of(static_cast<int>(k), m);
    const double d = j >= 0 ? (m - centres[j]).norm() : 0.0;
    const double s = j >= 0 ? sds[j] : 0.0;
    (*distance)[k] = d;
    (*fix_sd)[k] = s;
    cov->row(k) = CalibratedCovariance(Eigen::Vector3d(cov->row(k).transpose()), d, s, cal.a, cal.b, cal.g, cal.h,
                                       cal.s0)
                      .transpose();
  }
}

void CalibrateCovariances(const std::vector<StepInput>& steps, const std::vector<PositionFix>& fixes, int k0,
                          const GridTrackerOptions& o, GridTrackResult* r) {
  std::vector<Eigen::Vector2d> centres;
  std::vector<double> times, sds;
  centres.reserve(fixes.size());
  for (const PositionFix& f : fixes) {
    centres.push_back(FixCentre(f));
    sds.push_back(FixSd(f));
    times.push_back(f.time_s);
  }
  // Filtered: the last fix applied by step k (a fix applies at the first step at or after it).
  const auto last_applied = [&](int k, const Eigen::Vector2d&) {
    return static_cast<int>(std::upper_bound(times.begin(), times.end(), steps[k].time_s) - times.begin()) - 1;
  };
  // Smoothed: the fix nearest in time.
  const auto nearest = [&](int k, const Eigen::Vector2d&) {
    if (times.empty()) return -1;
    const double t = steps[k].time_s;
    const auto it = std::lower_bound(times.begin(), times.end(), t);
    int j = static_cast<int>(it - times.begin());
    if (j == static_cast<int>(times.size()) || (j > 0 && t - times[j - 1] <= times[j] - t)) --j;
    return j;
  };
  const Calibration filtered{o.filtered_covariance_scale, o.filtered_covariance_floor_m, o.filtered_covariance_fix_gain,
                             o.filtered_covariance_fix_sd_gain, o.covariance_fix_sd_knee_m};
  CalibrateRows(r->filtered_mean_m, filtered, last_applied, centres, sds, k0, &r->filtered_covariance_m2,
                &r->filtered_posterior_covariance_m2, &r->filtered_fix_distance_m, &r->filtered_fix_sd_m);
  if (r->smoothed_mean_m.rows() > 0) {
    const Calibration smoothed{o.smoothed_covariance_scale, o.smoothed_covariance_floor_m,
                               o.smoothed_covariance_fix_gain, o.smoothed_covariance_fix_sd_gain,
                               o.covariance_fix_sd_knee_m};
    CalibrateRows(r->smoothed_mean_m, smoothed, nearest, centres, sds, k0, &r->smoothed_covariance_m2,
                  &r->smoothed_posterior_covariance_m2, &r->smoothed_fix_distance_m, &r->smoothed_fix_sd_m);
  }
}

// Combines the layers of one run.
class Combiner {
 public:
  Combiner(const RunPlan& plan, const std::vector<LayerRun>& runs)
      : p_(plan), runs_(runs), layers_(plan.layer_set.layers), n_layers_(static_cast<int>(layers_.size())) {}

  // Layer weights from prior x evidence up to step k (the last step: the whole walk), and the
  // log of their normaliser (the evidence of the run up to k).
  std::pair<std::vector<double>, double> LayerWeights(int k) const {
    std::vector<double> w(n_layers_, 0.0);
    double mx = -std::numeric_limits<double>::infinity();
    for (int l = 0; l < n_layers_; ++l)
      if (!runs_[l].dead) mx = std::max(mx, layers_[l].log_prior + (k >= p_.k0 ? runs_[l].filtered[k].log_evidence : 0.0));
    double s = 0;
    for (int l = 0; l < n_layers_; ++l)
      if (!runs_[l].dead) s += w[l] = std::exp(layers_[l].log_prior + (k >= p_.k0 ? runs_[l].filtered[k].log_evidence : 0.0) - mx);
    for (double& v : w) v /= s;
    return std::make_pair(w, mx + std::log(s));
  }

  // The mixture's mean [m] and covariance (xx, xy, yy) [m²] at step k.
  void Mixture(const std::vector<double>& w, bool smoothed, int k, double* out_mean, double* out_cov) const {
    double mx = 0, my = 0, sxx = 0, sxy = 0, syy = 0;
    for (int l = 0; l < n_layers_; ++l) {
      if (w[l] <= 0) continue;
      const LayerStep& e = smoothed ? runs_[l].smoothed[k] : runs_[l].filtered[k];
      mx += w[l] * e.mx;
      my += w[l] * e.my;
      sxx += w[l] * (e.cxx + e.mx * e.mx);
      sxy += w[l] * (e.cxy + e.mx * e.my);
      syy += w[l] * (e.cyy + e.my * e.my);
    }
    out_mean[0] = mx;
    out_mean[1] = my;
    out_cov[0] = sxx - mx * mx;
    out_cov[1] = sxy - mx * my;
    out_cov[2] = syy - my * my;
  }

  // Per step: the causal filter's mixture, floor probabilities and heading offset.
  void Filtered(GridTrackResult* r) const {
    const int m_steps = p_.m_steps, n_floors = p_.num_floors();
    const GridTrackerOptions& o = p_.impl->options;
    const TrackStart& start = *p_.start;
    const std::vector<double>& offsets = p_.layer_set.offsets;
    r->filtered_mean_m.resize(m_steps, 2);
    r->filtered_covariance_m2.resize(m_steps, 3);
    r->filtered_floor_probabilities = RowMatrixXd::Zero(m_steps, n_floors);
    r->filtered_heading_offset_rad.resize(m_steps);
    const double start_var = o.start_position_sd_m * o.start_position_sd_m;
    for (int k = 0; k < m_steps; ++k) {
      if (k < p_.k0) {  // before a known start
        r->filtered_mean_m.row(k) << start.position_m.x(), start.position_m.y();
        r->filtered_covariance_m2.row(k) << start_var, 0.0, start_var;
        r->filtered_floor_probabilities(k, p_.start_floor_index) = 1.0;
        r->filtered_heading_offset_rad[k] = start.heading_offset_rad;
        continue;
      }
      const auto [w, log_total] = LayerWeights(k);
      double mean[2], cov[3];
      Mixture(w, false, k, mean, cov);
      r->filtered_mean_m.row(k) << mean[0], mean[1];
      r->filtered_covariance_m2.row(k) << cov[0], cov[1], cov[2];
      double cs = 0, sn = 0;
      for (int l = 0; l < n_layers_; ++l) {
        r->filtered_floor_probabilities(k, layers_[l].floor_index) += w[l];
        cs += w[l] * std::cos(offsets[layers_[l].offset_bin]);
        sn += w[l] * std::sin(offsets[layers_[l].offset_bin]);
      }
      r->filtered_heading_offset_rad[k] = std::atan2(sn, cs);
      if (k == m_steps - 1) r->summary.log_evidence = log_total;
    }
  }

  // Posterior of the layers given the whole walk: floor, heading offset and scale.
  void WalkPosterior(const std::vector<double>& w_all, GridTrackResult* r) const {
    const std::vector<double>& offsets = p_.layer_set.offsets;
    const std::vector<double>& scales = p_.layer_set.scales;
    r->smoothed_floor_probabilities = Eigen::VectorXd::Zero(p_.num_floors());
    r->heading_offset_probabilities = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(offsets.size()));
    r->scale_probabilities = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(scales.size()));
    double cs = 0, sn = 0, scale_mean = 0;
    for (int l = 0; l < n_layers_; ++l) {
      r->smoothed_floor_probabilities[layers_[l].floor_index] += w_all[l];
      r->heading_offset_probabilities[layers_[l].offset_bin] += w_all[l];
      r->scale_probabilities[layers_[l].scale_bin] += w_all[l];
      cs += w_all[l] * std::cos(offsets[layers_[l].offset_bin]);
      sn += w_all[l] * std::sin(offsets[layers_[l].offset_bin]);
      scale_mean += w_all[l] * scales[layers_[l].scale_bin];
    }
    r->heading_offset_rad = std::atan2(sn, cs);
    const double resultant = std::min(1.0, std::hypot(cs, sn));
    r->heading_offset_sd_rad = std::sqrt(std::max(0.0, -2.0 * std::log(std::max(resultant, 1e-300))));
    r->scale = scale_mean;
  }

  // Per step: the smoother's mixture (the filter's estimate before a known start).
  void Smoothed(const std::vector<double>& w_all, GridTrackResult* r) const {
    r->smoothed_mean_m.resize(p_.m_steps, 2);
    r->smoothed_covariance_m2.resize(p_.m_steps, 3);
    for (int k = 0; k < p_.m_steps; ++k) {
      if (k < p_.k0) {
        r->smoothed_mean_m.row(k) = r->filtered_mean_m.row(k);
        r->smoothed_covariance_m2.row(k) = r->filtered_covariance_m2.row(k);
        continue;
      }
      double mean[2], cov[3];
      Mixture(w_all, true, k, mean, cov);
      r->smoothed_mean_m.row(k) << mean[0], mean[1];
      r->smoothed_covariance_m2.row(k) << cov[0], cov[1], cov[2];
    }
  }

  // Spatial median at step k: the blocks of the most probable floor's layers, weighted, then Weiszfeld.
  Eigen::Vector2d MedianAt(const std::vector<double>& w, bool smoothed, int k) const {
    const int n_floors = p_.num_floors();
    std::vector<double> floor_p(n_floors, 0.0);
    for (int l = 0; l < n_layers_; ++l) floor_p[layers_[l].floor_index] += w[l];
    const int f = static_cast<int>(std::max_element(floor_p.begin(), floor_p.end()) - floor_p.begin());
    const std::size_t nb = p_.BlocksOf(f);
    std::vector<double> acc(nb * 3, 0.0);
    for (int l = 0; l < n_layers_; ++l) {
      if (layers_[l].floor_index != f || !(w[l] > 0) || runs_[l].dead) continue;
      const std::vector<float>& blocks = smoothed ? runs_[l].smoothed_blocks : runs_[l].filtered_blocks;
      const float* b = blocks.data() + static_cast<std::size_t>(k) * nb * 3;
      for (std::size_t i = 0; i < nb; ++i) {
        const double m = w[l] * b[3 * i];
        if (!(m > 0)) continue;
        acc[3 * i] += m;
        acc[3 * i + 1] += m * b[3 * i + 1];
        acc[3 * i + 2] += m * b[3 * i + 2];
      }
    }
    std::vector<Eigen::Vector3d> points;
    for (std::size_t i = 0; i < nb; ++i)
      if (acc[3 * i] > 1e-12) points.emplace_back(acc[3 * i], acc[3 * i + 1] / acc[3 * i], acc[3 * i + 2] / acc[3 * i]);
    return SpatialMedian(points, 0.5 * p_.q * p_.impl->options.cell_size_m);
  }

  void Medians(const std::vector<double>& w_all, GridTrackResult* r) const {
    if (p_.filtered) r->filtered_median_m.resize(p_.m_steps, 2);
    if (p_.smooth) r->smoothed_median_m.resize(p_.m_steps, 2);
    for (int k = 0; k < p_.m_steps; ++k) {
      if (k < p_.k0) {
        if (p_.filtered) r->filtered_median_m.row(k) = r->filtered_mean_m.row(k);
        if (p_.smooth) r->smoothed_median_m.row(k) = r->smoothed_mean_m.row(k);
        continue;
      }
      if (p_.filtered) r->filtered_median_m.row(k) = MedianAt(LayerWeights(k).first, false, k).transpose();
      if (p_.smooth) r->smoothed_median_m.row(k) = MedianAt(w_all, true, k).transpose();
    }
  }

 private:
  const RunPlan& p_;
  const std::vector<LayerRun>& runs_;
  const std::vector<GridLayer>& layers_;
  const int n_layers_;
};

}  // namespace

GridTrackResult CombineLayers(const RunPlan& plan, const std::vector<LayerRun>& runs) {
  const int n_layers = static_cast<int>(plan.layer_set.layers.size());  // runs may hold more (a pool)
  GridTrackResult r;
  GridTrackSummary& sum = r.summary;
  sum.steps = plan.m_steps;
  sum.fixes = plan.n_fixes;
  sum.layers = n_layers;
  for (int f = 0; f < plan.num_floors(); ++f)
    if (!plan.start->known || f == plan.start_floor_index) sum.cells += static_cast<long long>(plan.impl->grids[f].size());
  for (int l = 0; l < n_layers; ++l) sum.dead_layers += runs[l].dead ? 1 : 0;
  sum.memory_bytes = plan.bytes;
  if (sum.dead_layers == n_layers) {
    throw std::runtime_error(
        "indoorloc: GridTracker: every hypothesis was ruled out (hard walls with no walkable continuation of "
        "the steps, or a known start inside an obstacle): use a finite options.wall_log_penalty");
  }
  r.times_s.resize(plan.m_steps);
  for (int k = 0; k < plan.m_steps; ++k) r.times_s[k] = (*plan.steps)[k].time_s;
  const std::vector<double>& offsets = plan.layer_set.offsets;
  const std::vector<double>& scales = plan.layer_set.scales;
  r.heading_offset_bins_rad = Eigen::Map<const Eigen::VectorXd>(offsets.data(), offsets.size());
  r.scale_bins = Eigen::Map<const Eigen::VectorXd>(scales.data(), scales.size());

  const Combiner combine(plan, runs);
  combine.Filtered(&r);
  const std::vector<double> w_all = combine.LayerWeights(plan.m_steps - 1).first;
  combine.WalkPosterior(w_all, &r);
  std::vector<char> gap(static_cast<std::size_t>(plan.m_steps), 0);
  for (int l = 0; l < n_layers; ++l)
    if (w_all[l] > 0)
      for (int k : runs[l].smoother_gaps) gap[static_cast<std::size_t>(k)] = 1;
  for (char g : gap) sum.smoother_gap_steps += g;
  if (plan.smooth) combine.Smoothed(w_all, &r);
  CalibrateCovariances(*plan.steps, *plan.fixes, plan.k0, plan.impl->options, &r);
  if (!plan.filtered) {  // not computed (GridTracker::Run, filtered_estimates)
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const Eigen::Index rows = plan.m_steps - plan.k0;
    r.filtered_mean_m.bottomRows(rows).setConstant(nan);
    r.filtered_covariance_m2.bottomRows(rows).setConstant(nan);
    r.filtered_posterior_covariance_m2.bottomRows(rows).setConstant(nan);
    r.filtered_fix_distance_m.tail(rows).setConstant(nan);
  }
  if (plan.impl->options.spatial_median) combine.Medians(w_all, &r);
  return r;
}

}  // namespace indoorloc::fusion::grid_run
