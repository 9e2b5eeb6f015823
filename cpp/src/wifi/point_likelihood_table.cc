#include "point_likelihood_table.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace indoorloc::wifi::internal {
namespace {
constexpr double kLog2Pi = 1.8378770664093453;
constexpr double kBackgroundTolerance = 1e-12;  // relative; interpolation of equal vertices rounds
}  // namespace

ApBackground FindBackground(const RowMatrixXd& mean_dbm, const RowMatrixXd& variance_db2, double variance_floor_db2) {
  const Eigen::Index n = mean_dbm.rows(), k = mean_dbm.cols();
  ApBackground out;
  out.mean_dbm.resize(k);
  out.variance_db2.resize(k);
  std::vector<std::pair<std::pair<double, double>, Eigen::Index>> pairs(static_cast<size_t>(n));
  for (Eigen::Index a = 0; a < k; ++a) {
    for (Eigen::Index i = 0; i < n; ++i) {
      pairs[static_cast<size_t>(i)] = {{mean_dbm(i, a), std::max(variance_db2(i, a), variance_floor_db2)}, i};
    }
    std::sort(pairs.begin(), pairs.end());
    // Longest run of equal pairs; ties go to the run whose first row comes first.
    size_t best_begin = 0, best_count = 0;
    Eigen::Index best_row = n;
    for (size_t b = 0; b < pairs.size();) {
      size_t e = b;
      Eigen::Index first_row = n;
      while (e < pairs.size() && pairs[e].first == pairs[b].first) first_row = std::min(first_row, pairs[e++].second);
      if (e - b > best_count || (e - b == best_count && first_row < best_row)) {
        best_begin = b;
        best_count = e - b;
        best_row = first_row;
      }
      b = e;
    }
    out.mean_dbm[a] = pairs[best_begin].first.first;
    out.variance_db2[a] = pairs[best_begin].first.second;
  }
  return out;
}

bool IsBackground(const ApBackground& background, Eigen::Index a, double mean_dbm, double variance_db2) {
  const double m = background.mean_dbm[a], v = background.variance_db2[a];
  return std::abs(mean_dbm - m) <= kBackgroundTolerance * std::max(1.0, std::abs(m)) &&
         std::abs(variance_db2 - v) <= kBackgroundTolerance * v;
}

PointLikelihoodTable::PointLikelihoodTable(const ApBackground& background, double max_term)
    : bg_mean_(background.mean_dbm),
      bg_inv_var_(background.variance_db2.cwiseInverse()),
      cap_(max_term),
      building_points_(static_cast<size_t>(background.mean_dbm.size())),
      building_values_(static_cast<size_t>(background.mean_dbm.size())) {
  background_ = background;
  bg_log_var_.resize(background.variance_db2.size());
  for (Eigen::Index a = 0; a < bg_log_var_.size(); ++a) bg_log_var_[a] = std::log(background.variance_db2[a]);
}

void PointLikelihoodTable::AddPoint(const double* mean_dbm, const double* variance_db2) {
  const Eigen::Index k = bg_mean_.size();
  const int p = static_cast<int>(log_norm_acc_.size());
  double log_norm = 0.0, base = 0.0;
  for (Eigen::Index a = 0; a < k; ++a) {
    const double v = variance_db2[a];
    // Most of a point's APs are at their background variance: its log computed once.
    log_norm += 0.5 * (kLog2Pi + (v == background_.variance_db2[a] ? bg_log_var_[a] : std::log(v)));
    if (IsBackground(background_, a, mean_dbm[a], v)) continue;  // u_a(p) = 0 to rounding
    const double inv_var = 1.0 / v;
    const double r = bg_mean_[a] - mean_dbm[a];
    const double u = std::min(0.5 * r * r * inv_var, cap_);
    base += u;
    building_points_[static_cast<size_t>(a)].push_back(p);
    std::vector<double>& values = building_values_[static_cast<size_t>(a)];
    values.push_back(mean_dbm[a]);
    values.push_back(inv_var);
    values.push_back(u);
  }
  log_norm_acc_.push_back(log_norm);
  base_acc_.push_back(base);
}

void PointLikelihoodTable::Finish() {
  point_term_.resize(static_cast<Eigen::Index>(log_norm_acc_.size()));
  for (size_t p = 0; p < log_norm_acc_.size(); ++p) point_term_[static_cast<Eigen::Index>(p)] = log_norm_acc_[p] + base_acc_[p];
  std::vector<double>().swap(log_norm_acc_);
  std::vector<double>().swap(base_acc_);
  ap_run_.assign(1, 0);
  run_entry_.assign(1, 0);
  for (size_t a = 0; a < building_points_.size(); ++a) {
    const std::vector<int>& pts = building_points_[a];
    const std::vector<double>& values = building_values_[a];
    for (size_t e = 0; e < pts.size(); ++e) {
      if (e == 0 || pts[e] != pts[e - 1] + 1) {  // a new run
        if (e > 0) run_entry_.push_back(static_cast<int>(mean_.size()));
        run_point_.push_back(pts[e]);
      }
      mean_.push_back(values[3 * e]);
      inv_var_.push_back(values[3 * e + 1]);
      background_term_.push_back(values[3 * e + 2]);
    }
    if (!pts.empty()) run_entry_.push_back(static_cast<int>(mean_.size()));
    ap_run_.push_back(static_cast<int>(run_point_.size()));
    std::vector<int>().swap(building_points_[a]);
    std::vector<double>().swap(building_values_[a]);
  }
}

void PointLikelihoodTable::NegLogLikelihood(const Eigen::Ref<const RowMatrixXd>& scans, Eigen::VectorXd* l) const {
  const Eigen::Index k = bg_mean_.size();
  double constant = 0.0;  // Σ c_a(v_a) over the heard readings of every scan
  for (Eigen::Index s = 0; s < scans.rows(); ++s) {
    for (Eigen::Index a = 0; a < k; ++a) {
      const double r0 = scans(s, a) - bg_mean_[a];
      constant += std::min(0.5 * r0 * r0 * bg_inv_var_[a], cap_);
    }
  }
  l->resize(point_term_.size());
  l->array() = static_cast<double>(scans.rows()) * point_term_.array() + constant;
  double* out = l->data();
  const double* mean = mean_.data();
  const double* inv_var = inv_var_.data();
  const double* background_term = background_term_.data();
  const double cap = cap_;
  for (Eigen::Index s = 0; s < scans.rows(); ++s) {
    for (Eigen::Index a = 0; a < k; ++a) {
      const double v = scans(s, a);
      if (v == bg_mean_[a]) continue;  // the background reading: its terms are in point_term_
      const double r0 = v - bg_mean_[a];
      const double c = std::min(0.5 * r0 * r0 * bg_inv_var_[a], cap);
      for (int run = ap_run_[static_cast<size_t>(a)]; run < ap_run_[static_cast<size_t>(a) + 1]; ++run) {
        const int begin = run_entry_[static_cast<size_t>(run)], end = run_entry_[static_cast<size_t>(run) + 1];
        double* dst = out + run_point_[static_cast<size_t>(run)] - begin;
        for (int e = begin; e < end; ++e) {
          const double r = v - mean[e];
          const double t = std::min(0.5 * r * r * inv_var[e], cap);
          dst[e] += t - background_term[e] - c;
        }
      }
    }
  }
}

}  // namespace indoorloc::wifi::internal
