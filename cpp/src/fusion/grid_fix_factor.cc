// The position fixes' factor on a floor's grid (grid_tracker.h, "fixes"): per cell
//   F(c) = Π_j L_j(c)^p / max_c Π_j L_j(c)^p,   L_j(c) = ε / A + (1 - ε) Σ_k w_k N(x_c; μ_k, σ_k² I),
// p = τ (or 1 when τ divides the variances instead), returned with log max. Shared by the batch
// run and the streaming session (grid_ops.h), so both apply the same factor.
//
// Cost: a fix's components are Gaussians with isotropic covariance, so each is separable:
// N(x_c) ∝ exp(-dx²/2σ²) exp(-dy²/2σ²), two short vectors of exponentials per component instead
// of one exponential per cell. Survey-anchored positions (GridTracker::WithSurveyPositions) read
// that density at each cell's own point q(c) by bilinear interpolation between the cell centres
// (the components' sd, >= 1 m, is well above the 1 m cells). With one fix at the step (the common case) the normalised factor
// is (L / max L)^p, without a logarithm and an exponential per cell.
#include <algorithm>
#include <cmath>

#include "grid_ops.h"

namespace indoorloc::fusion::grid_ops {

namespace {

// acc(c) = Σ_k (1 - ε) w_k N(x_c; μ_k, σ_k² I) over the components of `fix` on this floor.
void AddFixDensity(const PositionFix& fix, const FloorGrid& fg, const GridTrackerOptions& options,
                   std::vector<double>* acc, std::vector<double>* ex, std::vector<double>* anchored) {
  const double c = options.cell_size_m;
  const double eps = options.fix.outlier_probability, tau = options.fix.tempering;
  std::fill(acc->begin(), acc->end(), 0.0);
  const double wsum = fix.weights.sum();
  for (Eigen::Index k = 0; k < fix.means_m.rows(); ++k) {
    const double w = fix.weights[k] / wsum;
    if (w <= 0) continue;
    const int f = fix.floors.size() ? fix.floors[k] : PositionFix::kAnyFloor;
    if (f != PositionFix::kAnyFloor && f != fg.floor_number) continue;
    const double sd = options.fix_tempering_by_variance ? fix.sds_m[k] / std::sqrt(tau) : fix.sds_m[k];
    const double inv2v = 0.5 / (sd * sd);
    const double scale = (1.0 - eps) * w / (kTwoPi * sd * sd);
    // 6 sd: beyond it the Gaussian is below 1e-8 of its peak, far under ε / A on any floor.
    const double reach = 6.0 * sd;
    const double mx = fix.means_m(k, 0), my = fix.means_m(k, 1);
    const int x_lo = std::max(0, static_cast<int>(std::floor((mx - reach - fg.x0) / c)));
    const int x_hi = std::min(fg.nx - 1, static_cast<int>(std::floor((mx + reach - fg.x0) / c)));
    const int y_lo = std::max(0, static_cast<int>(std::floor((my - reach - fg.y0) / c)));
    const int y_hi = std::min(fg.ny - 1, static_cast<int>(std::floor((my + reach - fg.y0) / c)));
    if (x_lo > x_hi || y_lo > y_hi) continue;
    ex->resize(static_cast<std::size_t>(x_hi - x_lo + 1));
    for (int x = x_lo; x <= x_hi; ++x) {
      const double dx = fg.x0 + (x + 0.5) * c - mx;
      (*ex)[x - x_lo] = std::exp(-dx * dx * inv2v);
    }
    const double* e = ex->data();
    for (int y = y_lo; y <= y_hi; ++y) {
      const double dy = fg.y0 + (y + 0.5) * c - my;
      const double sy = scale * std::exp(-dy * dy * inv2v);
      double* row = acc->data() + static_cast<std::size_t>(y) * fg.nx + x_lo;
      for (int x = 0; x <= x_hi - x_lo; ++x) row[x] += sy * e[x];
    }
  }
  if (fg.fix_cell.empty()) return;
  // The density at the survey-anchored points: bilinear between the four cell centres around each.
  anchored->resize(acc->size());
  const std::vector<double>& a = *acc;
  for (std::size_t i = 0; i < fg.size(); ++i) {
    const std::size_t j = static_cast<std::size_t>(fg.fix_cell[i]);
    const std::size_t dx = fg.fix_step_x[i], dy = fg.fix_step_y[i];
    const double wx = fg.fix_wx[i], wy = fg.fix_wy[i];
    const double lo = a[j] + wx * (a[j + dx] - a[j]);
    const double hi = a[j + dy] + wx * (a[j + dy + dx] - a[j + dy]);
    (*anchored)[i] = lo + wy * (hi - lo);
  }
  acc->swap(*anchored);
}

}  // namespace

TrackerGrids::FixFactor TrackerGrids::ComputeFixFactor(const std::vector<const PositionFix*>& fixes,
                                                       const FloorGrid& fg) const {
  const double floor_density = options.fix.outlier_probability / total_area_m2;
  const double power = options.fix_tempering_by_variance ? 1.0 : options.fix.tempering;
  const std::size_t n = fg.size();
  std::vector<double> acc(n), ex, anchored;
  FixFactor out;
  out.factor.resize(n);
  if (fixes.size() == 1) {  // F = (L / max L)^p
    AddFixDensity(*fixes[0], fg, options, &acc, &ex, &anchored);
    const double l_max = floor_density + *std::max_element(acc.begin(), acc.end());
    out.log_scale = power * std::log(l_max);
    const double inv = 1.0 / l_max;
    if (power == 1.0) {
      for (std::size_t i = 0; i < n; ++i) out.factor[i] = static_cast<float>((floor_density + acc[i]) * inv);
    } else {
      // Cells beyond every component's reach (density exactly 0, also after the bilinear
      // anchoring) share one value: the library's pow once for all of them, the same bits.
      const float outlier_only = static_cast<float>(std::pow(floor_density * inv, power));
      for (std::size_t i = 0; i < n; ++i) {
        out.factor[i] = acc[i] == 0.0 ? outlier_only : static_cast<float>(std::pow((floor_density + acc[i]) * inv, power));
      }
    }
    return out;
  }
  std::vector<double> log_l(n, 0.0);
  const double log_outlier_only = std::log(floor_density);  // log(floor_density + 0), as above
  for (const PositionFix* fix : fixes) {
    AddFixDensity(*fix, fg, options, &acc, &ex, &anchored);
    for (std::size_t i = 0; i < n; ++i)
      log_l[i] += power * (acc[i] == 0.0 ? log_outlier_only : std::log(floor_density + acc[i]));
  }
  out.log_scale = *std::max_element(log_l.begin(), log_l.end());
  for (std::size_t i = 0; i < n; ++i) out.factor[i] = static_cast<float>(std::exp(log_l[i] - out.log_scale));
  return out;
}

}  // namespace indoorloc::fusion::grid_ops
