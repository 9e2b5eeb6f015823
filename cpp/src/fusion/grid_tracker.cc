// Grid tracker: exact forward filter and forward-backward smoother on floor cells (see the
// header for the model). Each layer (floor, heading-offset bin, scale bin) is an independent
// hidden Markov model; a layer is filtered and smoothed in one task, the layers in parallel.
#include "indoorloc/fusion/grid_tracker.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <sstream>
#include <stdexcept>

#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::fusion {

namespace {

constexpr double kTwoPi = 2.0 * M_PI;

double WrapAngle(double a) { return std::remainder(a, kTwoPi); }

// One floor's grid: cells of side c over the floor's bounding box, row-major from the lowest y.
struct FloorGrid {
  double x0 = 0, y0 = 0;   // corner of cell (0, 0) [m]
  int nx = 0, ny = 0;
  int floor_number = 0;
  std::vector<float> walkable_fraction;  // a(c)
  std::vector<float> wall_factor;        // m(c) = a + (1 - a) e^λ
  std::size_t size() const { return static_cast<std::size_t>(nx) * ny; }
};

// What the forward pass did at one step of a layer, so that the backward pass can apply the
// transposed operators and the recomputation of a segment repeats the forward pass exactly.
struct StepOps {
  int shift_x = 0, shift_y = 0;  // whole-cell shift applied
  double blur_var_cells2 = 0;    // variance of the blur applied [cells²] (0: none)
  double pending_var_m2 = 0;     // process variance not yet applied after this step [m²]
  double rx = 0, ry = 0;         // sub-cell remainder after this step [m]
};

// Discrete Gaussian kernel of variance var [cells²], normalised, radius ceil(3 sd).
std::vector<float> GaussianKernel(double var_cells2) {
  const double sd = std::sqrt(var_cells2);
  const int radius = std::max(1, static_cast<int>(std::ceil(3.0 * sd)));
  std::vector<double> k(2 * radius + 1);
  double sum = 0;
  for (int j = -radius; j <= radius; ++j) sum += k[j + radius] = std::exp(-0.5 * j * j / var_cells2);
  std::vector<float> out(k.size());
  for (std::size_t j = 0; j < k.size(); ++j) out[j] = static_cast<float>(k[j] / sum);
  return out;
}

// Separable blur with zero outside the grid: a symmetric operator (its own transpose).
void Blur(std::vector<float>& g, std::vector<float>& scratch, int nx, int ny, double var_cells2) {
  const std::vector<float> k = GaussianKernel(var_cells2);
  const int r = static_cast<int>(k.size() / 2);
  scratch.assign(g.size(), 0.0f);
  // Along y: whole rows at a time (vectorises).
  for (int y = 0; y < ny; ++y) {
    float* out = scratch.data() + static_cast<std::size_t>(y) * nx;
    for (int j = -r; j <= r; ++j) {
      const int ys = y + j;
      if (ys < 0 || ys >= ny) continue;
      const float w = k[j + r];
      const float* in = g.data() + static_cast<std::size_t>(ys) * nx;
      for (int x = 0; x < nx; ++x) out[x] += w * in[x];
    }
  }
  // Along x.
  for (int y = 0; y < ny; ++y) {
    const float* in = scratch.data() + static_cast<std::size_t>(y) * nx;
    float* out = g.data() + static_cast<std::size_t>(y) * nx;
    for (int x = 0; x < nx; ++x) {
      const int lo = std::max(-r, -x), hi = std::min(r, nx - 1 - x);
      float acc = 0.0f;
      for (int j = lo; j <= hi; ++j) acc += k[j + r] * in[x + j];
      out[x] = acc;
    }
  }
}

// g(x, y) <- g(x - sx, y - sy), zero where the source is outside the grid; in place (rows moved
// in the order that never overwrites a row still to be read, only the vacated cells zeroed).
void Shift(std::vector<float>& g, int nx, int ny, int sx, int sy) {
  if (sx == 0 && sy == 0) return;
  float* d = g.data();
  const std::size_t row = static_cast<std::size_t>(nx);
  if (std::abs(sx) >= nx || std::abs(sy) >= ny) {
    std::fill(g.begin(), g.end(), 0.0f);
    return;
  }
  const int x_lo = std::max(0, sx), x_hi = std::min(nx, nx + sx);  // destination columns
  const int width = x_hi - x_lo;
  auto move_row = [&](int y) {
    float* dst = d + y * row;
    const float* src = d + (y - sy) * row + (x_lo - sx);
    std::memmove(dst + x_lo, src, static_cast<std::size_t>(width) * sizeof(float));
    std::fill(dst, dst + x_lo, 0.0f);
    std::fill(dst + x_hi, dst + nx, 0.0f);
  };
  if (sy > 0) {
    for (int y = ny - 1; y >= sy; --y) move_row(y);
    std::fill(d, d + sy * row, 0.0f);
  } else {
    for (int y = 0; y < ny + sy; ++y) move_row(y);
    std::fill(d + (ny + sy) * row, d + ny * row, 0.0f);
  }
}

// out(x, y) = g at (x + fx, y + fy) cells by bilinear interpolation, |fx|, |fy| <= 1, edges
// clamped: the fix factor of a layer whose positions are the cell centres plus a remainder.
void ResampleAt(const std::vector<float>& g, std::vector<float>& out, std::vector<float>& scratch, int nx, int ny,
                double fx, double fy) {
  scratch.resize(g.size());
  out.resize(g.size());
  const int dx = fx >= 0 ? 1 : -1, dy = fy >= 0 ? 1 : -1;
  const float ax = static_cast<float>(std::abs(fx)), ay = static_cast<float>(std::abs(fy));
  for (int y = 0; y < ny; ++y) {
    const float* in = g.data() + static_cast<std::size_t>(y) * nx;
    float* o = scratch.data() + static_cast<std::size_t>(y) * nx;
    for (int x = 0; x < nx; ++x) {
      const int x2 = std::min(nx - 1, std::max(0, x + dx));
      o[x] = (1.0f - ax) * in[x] + ax * in[x2];
    }
  }
  for (int y = 0; y < ny; ++y) {
    const int y2 = std::min(ny - 1, std::max(0, y + dy));
    const float* a = scratch.data() + static_cast<std::size_t>(y) * nx;
    const float* b = scratch.data() + static_cast<std::size_t>(y2) * nx;
    float* o = out.data() + static_cast<std::size_t>(y) * nx;
    for (int x = 0; x < nx; ++x) o[x] = (1.0f - ay) * a[x] + ay * b[x];
  }
}

// g *= scale (in double: the result is at most 1 and never overflows a float), and entries below
// 1e-30 set to 0: they are negligible beside the sum or maximum of 1, and float denormals would
// slow every later pass and let a normalisation overflow.
void NormaliseAndFlush(std::vector<float>& g, double scale) {
  if (scale < 1e30) {  // the common case, in float (vectorises): v * scale <= 1 cannot overflow
    const float f = static_cast<float>(scale);
    for (float& v : g) {
      const float x = v * f;
      v = x < 1e-30f ? 0.0f : x;
    }
    return;
  }
  for (float& v : g) {
    const double x = static_cast<double>(v) * scale;
    v = x < 1e-30 ? 0.0f : static_cast<float>(x);
  }
}

// g *= wall (and *= fix when given); returns the sum (float per row, double over rows).
double MultiplyAndSum(std::vector<float>& g, const std::vector<float>& wall, const float* fix, int nx, int ny) {
  double total = 0;
  for (int y = 0; y < ny; ++y) {
    float* row = g.data() + static_cast<std::size_t>(y) * nx;
    const float* w = wall.data() + static_cast<std::size_t>(y) * nx;
    float sum = 0.0f;
    if (fix) {
      const float* f = fix + static_cast<std::size_t>(y) * nx;
      for (int x = 0; x < nx; ++x) {
        row[x] *= w[x] * f[x];
        sum += row[x];
      }
    } else {
      for (int x = 0; x < nx; ++x) {
        row[x] *= w[x];
        sum += row[x];
      }
    }
    total += sum;
  }
  return total;
}

// Mean and second moments of a grid about the cell centres (double accumulation).
struct Moments {
  double mass = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
};

// Of g, or of the product g * weight (the smoother's alpha * beta, formed in double: both are
// flushed at 1e-30, so the product stays far above double's underflow).
// With `coarse` (nqx * nqy * 3 doubles, zeroed by the caller), also the mass and the mass-weighted
// cell indices of every block of q x q cells (the summary the spatial median is computed from).
Moments GridMoments(const float* g, const float* weight, const FloorGrid& fg, double cell, int q = 1,
                    double* coarse = nullptr, bool force_double = false) {
  Moments m;
  const int nqx = (fg.nx + q - 1) / q;
  for (int y = 0; y < fg.ny; ++y) {
    const float* row = g + static_cast<std::size_t>(y) * fg.nx;
    const float* wrow = weight ? weight + static_cast<std::size_t>(y) * fg.nx : nullptr;
    double r_mass = 0, r_sx = 0, r_sxx = 0;
    double* crow = coarse ? coarse + static_cast<std::size_t>(y / q) * nqx * 3 : nullptr;
    const bool in_float = !crow && (!wrow || !force_double);
    if (in_float) {  // the common case: float accumulators along the row (vectorises)
      float f_mass = 0.0f, f_sx = 0.0f, f_sxx = 0.0f;
      if (wrow) {
        for (int x = 0; x < fg.nx; ++x) {
          const float v = row[x] * wrow[x], fx = static_cast<float>(x);
          f_mass += v;
          f_sx += v * fx;
          f_sxx += v * fx * fx;
        }
      } else {
        for (int x = 0; x < fg.nx; ++x) {
          const float v = row[x], fx = static_cast<float>(x);
          f_mass += v;
          f_sx += v * fx;
          f_sxx += v * fx * fx;
        }
      }
      r_mass = f_mass;
      r_sx = f_sx;
      r_sxx = f_sxx;
    } else {
      // The row's values (the product alpha * beta in double), then its sums and block sums.
      thread_local std::vector<double> v;
      v.resize(static_cast<std::size_t>(fg.nx));
      if (wrow) {
        for (int x = 0; x < fg.nx; ++x) v[x] = static_cast<double>(row[x]) * wrow[x];
      } else {
        for (int x = 0; x < fg.nx; ++x) v[x] = row[x];
      }
      for (int x = 0; x < fg.nx; ++x) {
        r_mass += v[x];
        r_sx += v[x] * x;
        r_sxx += v[x] * x * static_cast<double>(x);
      }
      if (crow) {
        for (int bx = 0; bx < nqx; ++bx) {
          double bm = 0, bsx = 0;
          for (int x = bx * q; x < std::min(fg.nx, bx * q + q); ++x) {
            bm += v[x];
            bsx += v[x] * x;
          }
          double* b = crow + static_cast<std::size_t>(bx) * 3;
          b[0] += bm;
          b[1] += bsx;
          b[2] += bm * y;
        }
      }
    }
    m.mass += r_mass;
    m.sx += r_sx;
    m.sy += r_mass * y;
    m.sxx += r_sxx;
    m.sxy += r_sx * y;
    m.syy += r_mass * y * static_cast<double>(y);
  }
  // The smoother's product alpha * beta in float can underflow where both are small: when its
  // total is that small, redo the sums in double.
  if (weight && !coarse && !force_double && m.mass < 1e-20) return GridMoments(g, weight, fg, cell, q, coarse, true);
  // Cell indices -> metres (centres).
  Moments out;
  out.mass = m.mass;
  if (m.mass <= 0) return out;
  const double mx = m.sx / m.mass, my = m.sy / m.mass;
  out.sx = fg.x0 + (mx + 0.5) * cell;
  out.sy = fg.y0 + (my + 0.5) * cell;
  out.sxx = (m.sxx / m.mass - mx * mx) * cell * cell;
  out.sxy = (m.sxy / m.mass - mx * my) * cell * cell;
  out.syy = (m.syy / m.mass - my * my) * cell * cell;
  return out;  // sx, sy: mean [m]; sxx, sxy, syy: covariance [m²]
}

// A layer's per-step estimate: mean, covariance, cumulative log evidence.
struct LayerStep {
  double mx = 0, my = 0, cxx = 0, cxy = 0, cyy = 0;
  double log_evidence = 0;
};

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

}  // namespace

bool GridTrackerOptions::IsValid(std::string* error) const {
  std::string fix_error;
  const bool fix_ok = fix.IsValid(&fix_error);
  return Validator(error)
      .InRange(cell_size_m, 0.05, 100.0, "cell_size_m")
      .IntInRange(walkable_subsamples, 1, 16, "walkable_subsamples")
      .IntInRange(heading_offset_bins, 1, 720, "heading_offset_bins")
      .InRange(heading_offset_sd_rad, 0.0, 100.0, "heading_offset_sd_rad")
      .InRange(heading_offset_span_sd, 0.1, 100.0, "heading_offset_span_sd")
      .IntInRange(scale_bins, 1, 101, "scale_bins")
      .InRange(scale_sd, 0.0, 0.2, "scale_sd")
      .InRange(position_noise_m, 0.0, 100.0, "position_noise_m")
      .Check(wall_log_penalty <= 0.0 && !std::isnan(wall_log_penalty), "wall_log_penalty",
             "must be <= 0 or -inf, got " + FormatValue(wall_log_penalty))
      .Check(fix_ok, "fix", fix_error)
      .InRange(median_block_m, 0.1, 100.0, "median_block_m")
      .InRange(start_position_sd_m, 0.01, 1e4, "start_position_sd_m")
      .InRange(filtered_covariance_scale, 1e-6, 1e6, "filtered_covariance_scale")
      .InRange(filtered_covariance_floor_m, 0.0, 1e4, "filtered_covariance_floor_m")
      .InRange(filtered_covariance_fix_gain, 0.0, 1e3, "filtered_covariance_fix_gain")
      .InRange(smoothed_covariance_scale, 1e-6, 1e6, "smoothed_covariance_scale")
      .InRange(smoothed_covariance_floor_m, 0.0, 1e4, "smoothed_covariance_floor_m")
      .InRange(smoothed_covariance_fix_gain, 0.0, 1e3, "smoothed_covariance_fix_gain")
      .InRange(max_memory_bytes, 1e6, 1e13, "max_memory_bytes")
      .IntInRange(num_threads, -1, 4096, "num_threads");
}

std::string GridTrackSummary::BriefReport() const {
  std::ostringstream out;
  out << steps << " steps, " << fixes << " fixes, " << layers << " layers (" << dead_layers << " ruled out), "
      << cells << " cells, log-evidence " << log_evidence << ", " << FormatBytes(memory_bytes) << ", " << seconds
      << " s";
  return out.str();
}

namespace {

// Weighted mean of a fix's components [m].
Eigen::Vector2d FixCentre(const PositionFix& f) {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double total = 0;
  for (Eigen::Index i = 0; i < f.means_m.rows(); ++i) {
    centre += f.weights[i] * f.means_m.row(i).transpose();
    total += f.weights[i];
  }
  return total > 0 ? Eigen::Vector2d(centre / total) : centre;
}

// Σ' = a Σ + (b² + (g d)²) I per step k >= k0 (GridTrackerOptions, "Calibration of the returned
// covariances"); the posterior's own Σ is kept beside it.
void CalibrateRows(const RowMatrixXd& mean, double a, double b, double g,
                   const std::function<int(int, const Eigen::Vector2d&)>& fix_of, const std::vector<Eigen::Vector2d>& centres,
                   int k0, RowMatrixXd* cov, RowMatrixXd* posterior, Eigen::VectorXd* distance) {
  *posterior = *cov;
  distance->setZero(cov->rows());
  for (Eigen::Index k = k0; k < cov->rows(); ++k) {
    const Eigen::Vector2d m = mean.row(k).transpose();
    const int j = fix_of(static_cast<int>(k), m);
    const double d = j >= 0 ? (m - centres[j]).norm() : 0.0;
    (*distance)[k] = d;
    const double iso = b * b + (g * d) * (g * d);
    (*cov)(k, 0) = a * (*cov)(k, 0) + iso;
    (*cov)(k, 1) = a * (*cov)(k, 1);
    (*cov)(k, 2) = a * (*cov)(k, 2) + iso;
  }
}

void CalibrateCovariances(const std::vector<StepInput>& steps, const std::vector<PositionFix>& fixes, int k0,
                          const GridTrackerOptions& o, GridTrackResult* r) {
  std::vector<Eigen::Vector2d> centres;
  std::vector<double> times;
  centres.reserve(fixes.size());
  for (const PositionFix& f : fixes) {
    centres.push_back(FixCentre(f));
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
  CalibrateRows(r->filtered_mean_m, o.filtered_covariance_scale, o.filtered_covariance_floor_m,
                o.filtered_covariance_fix_gain, last_applied, centres, k0, &r->filtered_covariance_m2,
                &r->filtered_posterior_covariance_m2, &r->filtered_fix_distance_m);
  if (r->smoothed_mean_m.rows() > 0) {
    CalibrateRows(r->smoothed_mean_m, o.smoothed_covariance_scale, o.smoothed_covariance_floor_m,
                  o.smoothed_covariance_fix_gain, nearest, centres, k0, &r->smoothed_covariance_m2,
                  &r->smoothed_posterior_covariance_m2, &r->smoothed_fix_distance_m);
  }
}

}  // namespace

struct GridTracker::Impl {
  const FloorPlan* plan = nullptr;
  GridTrackerOptions options;
  std::vector<FloorGrid> grids;
  double total_area_m2 = 0;

  // Per step with fixes: per floor the factor Π_j L_j(c)^τ / max and the log of that max.
  struct FixFactor {
    std::vector<float> factor;
    double log_scale = 0;
  };

  FixFactor ComputeFixFactor(const std::vector<const PositionFix*>& fixes, const FloorGrid& fg) const {
    const double c = options.cell_size_m;
    const double eps = options.fix.outlier_probability, tau = options.fix.tempering;
    const double floor_density = eps / total_area_m2;
    std::vector<double> log_l(fg.size(), 0.0), acc(fg.size());
    for (const PositionFix* fix : fixes) {
      std::fill(acc.begin(), acc.end(), 0.0);
      const double wsum = fix->weights.sum();
      for (Eigen::Index k = 0; k < fix->means_m.rows(); ++k) {
        const double w = fix->weights[k] / wsum;
        if (w <= 0) continue;
        const int f = fix->floors.size() ? fix->floors[k] : PositionFix::kAnyFloor;
        if (f != PositionFix::kAnyFloor && f != fg.floor_number) continue;
        const double sd = options.fix_tempering_by_variance ? fix->sds_m[k] / std::sqrt(tau) : fix->sds_m[k];
        const double inv2v = 0.5 / (sd * sd);
        const double scale = (1.0 - eps) * w / (kTwoPi * sd * sd);
        // 6 sd: beyond it the Gaussian is below 1e-8 of its peak, far under ε / A on any floor.
        const double reach = 6.0 * sd;
        const double mx = fix->means_m(k, 0), my = fix->means_m(k, 1);
        const int x_lo = std::max(0, static_cast<int>(std::floor((mx - reach - fg.x0) / c)));
        const int x_hi = std::min(fg.nx - 1, static_cast<int>(std::floor((mx + reach - fg.x0) / c)));
        const int y_lo = std::max(0, static_cast<int>(std::floor((my - reach - fg.y0) / c)));
        const int y_hi = std::min(fg.ny - 1, static_cast<int>(std::floor((my + reach - fg.y0) / c)));
        for (int y = y_lo; y <= y_hi; ++y) {
          const double dy = fg.y0 + (y + 0.5) * c - my;
          for (int x = x_lo; x <= x_hi; ++x) {
            const double dx = fg.x0 + (x + 0.5) * c - mx;
            acc[static_cast<std::size_t>(y) * fg.nx + x] += scale * std::exp(-(dx * dx + dy * dy) * inv2v);
          }
        }
      }
      const double power = options.fix_tempering_by_variance ? 1.0 : tau;
      for (std::size_t i = 0; i < acc.size(); ++i) log_l[i] += power * std::log(floor_density + acc[i]);
    }
    FixFactor out;
    out.log_scale = *std::max_element(log_l.begin(), log_l.end());
    out.factor.resize(fg.size());
    for (std::size_t i = 0; i < log_l.size(); ++i) out.factor[i] = static_cast<float>(std::exp(log_l[i] - out.log_scale));
    return out;
  }
};

GridTracker::GridTracker(const FloorPlan* plan, const GridTrackerOptions& options) : impl_(new Impl) {
  CheckArgument(plan != nullptr, "plan", "must not be None");
  ValidateOptions(options);
  impl_->plan = plan;
  impl_->options = options;
  const double c = options.cell_size_m;
  const int n_sub = options.walkable_subsamples;
  double cells = 0;
  for (int f = 0; f < plan->num_floors(); ++f) {
    const Eigen::Vector4d b = plan->Bounds(f);
    cells += std::ceil((b[2] - b[0]) / c) * std::ceil((b[3] - b[1]) / c);
  }
  // The walkable fractions and, per run, about ten grids per thread: refuse before allocating.
  const double bytes = cells * (8.0 + n_sub * n_sub * 17.0);
  CheckArgument(bytes <= options.max_memory_bytes, "options",
                "the grid of " + FormatValue(cells) + " cells needs " + FormatBytes(bytes) +
                    " to build, above max_memory_bytes = " + FormatBytes(options.max_memory_bytes) +
                    " (use larger cells)");
  const double penalty = std::isinf(options.wall_log_penalty) ? 0.0 : std::exp(options.wall_log_penalty);
  for (int f = 0; f < plan->num_floors(); ++f) {
    const Eigen::Vector4d b = plan->Bounds(f);
    FloorGrid g;
    g.x0 = b[0];
    g.y0 = b[1];
    g.nx = std::max(1, static_cast<int>(std::ceil((b[2] - b[0]) / c)));
    g.ny = std::max(1, static_cast<int>(std::ceil((b[3] - b[1]) / c)));
    g.floor_number = plan->floors()[f];
    RowMatrixXd pts(static_cast<Eigen::Index>(g.size()) * n_sub * n_sub, 2);
    Eigen::Index row = 0;
    for (int y = 0; y < g.ny; ++y)
      for (int x = 0; x < g.nx; ++x)
        for (int j = 0; j < n_sub; ++j)
          for (int i = 0; i < n_sub; ++i) {
            pts(row, 0) = g.x0 + (x + (i + 0.5) / n_sub) * c;
            pts(row, 1) = g.y0 + (y + (j + 0.5) / n_sub) * c;
            ++row;
          }
    const VectorXb walk = plan->IsWalkableBatch(pts, Eigen::VectorXi::Constant(1, f), options.num_threads);
    g.walkable_fraction.resize(g.size());
    g.wall_factor.resize(g.size());
    for (std::size_t i = 0; i < g.size(); ++i) {
      int n = 0;
      for (int s = 0; s < n_sub * n_sub; ++s) n += walk[static_cast<Eigen::Index>(i) * n_sub * n_sub + s];
      const double a = static_cast<double>(n) / (n_sub * n_sub);
      g.walkable_fraction[i] = static_cast<float>(a);
      g.wall_factor[i] = static_cast<float>(a + (1.0 - a) * penalty);
    }
    impl_->grids.push_back(std::move(g));
    impl_->total_area_m2 += plan->WalkableArea(f);
  }
}

GridTracker::~GridTracker() = default;
GridTracker::GridTracker(GridTracker&&) noexcept = default;
GridTracker& GridTracker::operator=(GridTracker&&) noexcept = default;

const GridTrackerOptions& GridTracker::options() const { return impl_->options; }

Eigen::Vector4d GridTracker::GridGeometry(int floor_index) const {
  RequireIntInRange(floor_index, 0, static_cast<int>(impl_->grids.size()) - 1, "floor_index");
  const FloorGrid& g = impl_->grids[floor_index];
  return Eigen::Vector4d(g.x0, g.y0, g.nx, g.ny);
}

RowMatrixXd GridTracker::WalkableFraction(int floor_index) const {
  RequireIntInRange(floor_index, 0, static_cast<int>(impl_->grids.size()) - 1, "floor_index");
  const FloorGrid& g = impl_->grids[floor_index];
  RowMatrixXd out(g.ny, g.nx);
  for (int y = 0; y < g.ny; ++y)
    for (int x = 0; x < g.nx; ++x) out(y, x) = g.walkable_fraction[static_cast<std::size_t>(y) * g.nx + x];
  return out;
}

GridTrackResult GridTracker::Run(const std::vector<StepInput>& steps, const std::vector<PositionFix>& fixes,
                                 const TrackStart& start, bool smooth) const {
  WallTimer timer;
  const Impl& im = *impl_;
  const GridTrackerOptions& o = im.options;
  const double c = o.cell_size_m;
  CheckArgument(!steps.empty(), "steps", "must hold at least one step");
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const std::string name = "steps[" + std::to_string(k) + "]";
    CheckStepInput(steps[k], name.c_str());
    CheckArgument(k == 0 || steps[k].time_s >= steps[k - 1].time_s, "steps",
                  "times must be non-decreasing (step " + std::to_string(k) + " goes back in time)");
  }
  for (std::size_t j = 0; j < fixes.size(); ++j) {
    const std::string name = "fixes[" + std::to_string(j) + "]";
    CheckPositionFix(fixes[j], name.c_str());
    CheckArgument(j == 0 || fixes[j].time_s >= fixes[j - 1].time_s, "fixes",
                  "times must be non-decreasing (fix " + std::to_string(j) + " goes back in time)");
  }
  int start_floor_index = -1;
  if (start.known) {
    RequireFinite(start.time_s, "start.time_s");
    RequireFinite(start.position_m.x(), "start.position_m");
    RequireFinite(start.position_m.y(), "start.position_m");
    RequireFinite(start.heading_offset_rad, "start.heading_offset_rad");
    start_floor_index = im.plan->FloorIndex(start.floor);
  }
  const int m_steps = static_cast<int>(steps.size());
  // With a known start, steps up to its time are before the start: estimates there are the start.
  int k0 = 0;
  if (start.known) {
    while (k0 < m_steps && steps[k0].time_s <= start.time_s) ++k0;
  }

  // Layers: floors x heading-offset bins x scale bins, with log prior weights.
  const double o_sd = o.heading_offset_sd_rad;
  std::vector<double> offsets, offset_log_prior;
  double bin_width = 0;
  if (o.heading_offset_bins == 1 || o_sd <= 0) {
    offsets = {start.heading_offset_rad};
    offset_log_prior = {0.0};
  } else {
    const int h = o.heading_offset_bins;
    const double span = o.heading_offset_span_sd * o_sd;
    if (span >= M_PI) {  // the whole circle, prior weights of the wrapped distance
      bin_width = kTwoPi / h;
      for (int i = 0; i < h; ++i) {
        const double d = -M_PI + (i + 0.5) * bin_width;
        offsets.push_back(WrapAngle(start.heading_offset_rad + d));
        offset_log_prior.push_back(-0.5 * d * d / (o_sd * o_sd));
      }
    } else {
      bin_width = 2.0 * span / h;
      for (int i = 0; i < h; ++i) {
        const double d = -span + (i + 0.5) * bin_width;
        offsets.push_back(start.heading_offset_rad + d);
        offset_log_prior.push_back(-0.5 * d * d / (o_sd * o_sd));
      }
    }
  }
  std::vector<double> scales, scale_log_prior;
  if (o.scale_bins == 1 || o.scale_sd <= 0) {
    scales = {1.0};
    scale_log_prior = {0.0};
  } else {
    const double w = 4.0 * o.scale_sd / o.scale_bins;
    for (int i = 0; i < o.scale_bins; ++i) {
      const double d = -2.0 * o.scale_sd + (i + 0.5) * w;
      scales.push_back(1.0 + d);
      scale_log_prior.push_back(-0.5 * d * d / (o.scale_sd * o.scale_sd));
    }
  }
  struct Layer {
    int floor_index, offset_bin, scale_bin;
    double log_prior;
  };
  std::vector<Layer> layers;
  const int n_floors = static_cast<int>(im.grids.size());
  for (int f = 0; f < n_floors; ++f) {
    if (start.known && f != start_floor_index) continue;
    // Unknown start: uniform over the walkable area of all floors, so a floor's prior is its area.
    const double floor_log_prior = start.known ? 0.0 : std::log(im.plan->WalkableArea(f) / im.total_area_m2);
    for (std::size_t h = 0; h < offsets.size(); ++h)
      for (std::size_t s = 0; s < scales.size(); ++s)
        layers.push_back({f, static_cast<int>(h), static_cast<int>(s),
                          floor_log_prior + offset_log_prior[h] + scale_log_prior[s]});
  }
  {  // normalise the layer prior
    double mx = -std::numeric_limits<double>::infinity();
    for (const Layer& l : layers) mx = std::max(mx, l.log_prior);
    double sum = 0;
    for (const Layer& l : layers) sum += std::exp(l.log_prior - mx);
    for (Layer& l : layers) l.log_prior -= mx + std::log(sum);
  }

  // Fixes attached to steps: the first step at or after the fix (the last step for later fixes);
  // with a known start, fixes before it are not used.
  std::vector<std::vector<const PositionFix*>> fixes_at(m_steps);
  int n_fixes = 0;
  for (const PositionFix& fix : fixes) {
    if (fix.empty()) continue;
    if (start.known && fix.time_s < start.time_s) continue;
    int k = static_cast<int>(std::lower_bound(steps.begin(), steps.end(), fix.time_s,
                                              [](const StepInput& s, double t) { return s.time_s < t; }) -
                             steps.begin());
    k = std::min(std::max(k, k0), m_steps - 1);
    if (k < k0) continue;
    fixes_at[k].push_back(&fix);
    ++n_fixes;
  }

  // Memory: fix factors (shared) and per thread the live grids and the smoother's checkpoints.
  const int threads = std::min(ResolveThreadCount(o.num_threads), std::max(1, static_cast<int>(layers.size())));
  const int m_run = m_steps - k0;
  double max_cells = 0, fix_cells = 0, fix_steps = 0;
  for (int k = 0; k < m_steps; ++k) fix_steps += fixes_at[k].empty() ? 0 : 1;
  for (int f = 0; f < n_floors; ++f) {
    if (start.known && f != start_floor_index) continue;
    max_cells = std::max(max_cells, static_cast<double>(im.grids[f].size()));
    fix_cells += fix_steps * static_cast<double>(im.grids[f].size());
  }
  // The smoother keeps every forward grid of a layer while that fits in 256 MB per thread (a walk
  // of minutes on a mall floor), else about sqrt(M) checkpoints and recomputes each segment once.
  const bool store_all = smooth && static_cast<double>(m_run) * max_cells * 4.0 <= 256e6;
  const int segment = store_all ? std::max(1, m_run)
                                : std::max(1, static_cast<int>(std::ceil(std::sqrt(std::max(1, m_run)))));
  // Per thread: alpha, beta, scratch, the layer's fix factors, the checkpoints and a segment.
  const double per_thread =
      max_cells * 4.0 * (4.0 + fix_steps + (smooth ? (store_all ? m_run : m_run / segment + 1 + segment) : 0));
  // Spatial medians: per layer and step the block summaries (mass, centroid).
  const int q = std::max(1, static_cast<int>(std::lround(o.median_block_m / c)));
  double max_blocks = 0;
  for (int f = 0; f < n_floors; ++f)
    max_blocks = std::max(max_blocks, std::ceil(im.grids[f].nx / static_cast<double>(q)) *
                                          std::ceil(im.grids[f].ny / static_cast<double>(q)));
  const double median_bytes =
      o.spatial_median ? static_cast<double>(layers.size()) * m_run * max_blocks * 12.0 * (smooth ? 2 : 1) : 0.0;
  const double bytes = fix_cells * 4.0 + threads * per_thread + median_bytes;
  CheckArgument(bytes <= o.max_memory_bytes, "steps",
                std::to_string(m_run) + " steps on this grid need " + FormatBytes(bytes) +
                    ", above options.max_memory_bytes = " + FormatBytes(o.max_memory_bytes) +
                    " (use larger cells or fewer offset bins)");

  // Fix factors per (step, floor), computed once and shared by the layers of a floor.
  std::vector<std::vector<Impl::FixFactor>> factor(m_steps);
  for (int k = 0; k < m_steps; ++k) {
    if (fixes_at[k].empty()) continue;
    factor[k].resize(n_floors);
    for (int f = 0; f < n_floors; ++f) {
      if (start.known && f != start_floor_index) continue;
      factor[k][f] = im.ComputeFixFactor(fixes_at[k], im.grids[f]);
    }
  }

  // Per layer and step: filtered and smoothed estimates.
  const int n_layers = static_cast<int>(layers.size());
  std::vector<std::vector<LayerStep>> filtered(n_layers, std::vector<LayerStep>(m_steps));
  std::vector<std::vector<LayerStep>> smoothed(smooth ? n_layers : 0, std::vector<LayerStep>(m_steps));
  std::vector<char> dead(n_layers, 0);
  // Block summaries per layer: step-major, (mass, x [m], y [m]) per block.
  std::vector<std::vector<float>> filtered_blocks(o.spatial_median ? n_layers : 0);
  std::vector<std::vector<float>> smoothed_blocks(o.spatial_median && smooth ? n_layers : 0);
  auto blocks_of = [&](int floor_index) {
    const FloorGrid& g = im.grids[floor_index];
    return static_cast<std::size_t>((g.nx + q - 1) / q) * static_cast<std::size_t>((g.ny + q - 1) / q);
  };

  // The smoother's stored forward grids: with one thread, one buffer serves every layer in turn
  // (its pages are touched once per run, not once per layer).
  std::vector<float> single_thread_store;
  ParallelForRuns(n_layers, threads, 0, [&](int li, RandomStream&) {
    const Layer& layer = layers[li];
    const FloorGrid& fg = im.grids[layer.floor_index];
    const double off = offsets[layer.offset_bin], sc = scales[layer.scale_bin];
    const double co = std::cos(off), so = std::sin(off);
    const std::size_t n = fg.size();
    std::vector<float> alpha(n), scratch(n);
    // Prior: uniform over the walkable cells, or a Gaussian around the known start.
    if (start.known) {
      const double sd = o.start_position_sd_m;
      for (int y = 0; y < fg.ny; ++y)
        for (int x = 0; x < fg.nx; ++x) {
          const double dx = fg.x0 + (x + 0.5) * c - start.position_m.x();
          const double dy = fg.y0 + (y + 0.5) * c - start.position_m.y();
          alpha[static_cast<std::size_t>(y) * fg.nx + x] = static_cast<float>(std::exp(-0.5 * (dx * dx + dy * dy) / (sd * sd)));
        }
    } else {
      std::fill(alpha.begin(), alpha.end(), 1.0f);
    }
    for (std::size_t i = 0; i < n; ++i) alpha[i] *= fg.wall_factor[i];
    {
      double s = 0;
      for (float v : alpha) s += v;
      if (!(s > 0)) {  // a known start entirely inside obstacles with hard walls
        dead[li] = 1;
        return;
      }
      for (float& v : alpha) v = static_cast<float>(v / s);
    }
    std::vector<StepOps> ops(m_steps);
    double log_z = 0, rx = 0, ry = 0, pending = 0;
    // The fix factors at this layer's positions (cell centres + remainder), per step with fixes.
    std::vector<std::vector<float>> layer_factor(m_steps);

    // One forward step; returns false when the layer dies. `ops[k]` is filled on the first pass
    // and replayed on recomputation (record = false), so both passes are identical.
    auto forward = [&](int k, bool record) -> bool {
      StepOps& op = ops[k];
      if (record) {
        const StepInput& st = steps[k];
        const Eigen::Vector2d d = st.displacement_m;
        rx += sc * (co * d.x() - so * d.y());
        ry += sc * (so * d.x() + co * d.y());
        const double len = sc * d.norm();
        pending += sc * sc * 0.5 * st.covariance_m2.trace() + o.position_noise_m * o.position_noise_m +
                   len * len * bin_width * bin_width / 12.0;
        op.shift_x = static_cast<int>(std::lround(rx / c));
        op.shift_y = static_cast<int>(std::lround(ry / c));
        rx -= op.shift_x * c;
        ry -= op.shift_y * c;
        op.blur_var_cells2 = 0;
        if (pending >= 0.25 * c * c || !fixes_at[k].empty()) {
          op.blur_var_cells2 = pending / (c * c);
          pending = 0;
        }
        op.pending_var_m2 = pending;
        op.rx = rx;
        op.ry = ry;
      }
      Shift(alpha, fg.nx, fg.ny, op.shift_x, op.shift_y);
      if (op.blur_var_cells2 > 1e-6) Blur(alpha, scratch, fg.nx, fg.ny, op.blur_var_cells2);
      const bool has_fix = !fixes_at[k].empty();
      if (has_fix && record) {
        ResampleAt(factor[k][layer.floor_index].factor, layer_factor[k], scratch, fg.nx, fg.ny, op.rx / c, op.ry / c);
      }
      const double s = MultiplyAndSum(alpha, fg.wall_factor, has_fix ? layer_factor[k].data() : nullptr, fg.nx, fg.ny);
      if (!(s > 0)) return false;
      NormaliseAndFlush(alpha, 1.0 / s);
      if (record) log_z += std::log(s) + (has_fix ? factor[k][layer.floor_index].log_scale : 0.0);
      return true;
    };
    const std::size_t nb = blocks_of(layer.floor_index);
    std::vector<double> block_sums(o.spatial_median ? nb * 3 : 0);
    if (o.spatial_median) {
      filtered_blocks[li].assign(static_cast<std::size_t>(m_steps) * nb * 3, 0.0f);
      if (smooth) smoothed_blocks[li].assign(static_cast<std::size_t>(m_steps) * nb * 3, 0.0f);
    }
    auto estimate = [&](const float* g, const std::vector<float>* weight, int k) {
      std::vector<float>* blocks = o.spatial_median ? (weight ? &smoothed_blocks[li] : &filtered_blocks[li]) : nullptr;
      if (blocks) std::fill(block_sums.begin(), block_sums.end(), 0.0);
      const Moments mo = GridMoments(g, weight ? weight->data() : nullptr, fg, c, q, blocks ? block_sums.data() : nullptr);
      if (blocks && mo.mass > 0) {
        float* out = blocks->data() + static_cast<std::size_t>(k) * nb * 3;
        for (std::size_t b = 0; b < nb; ++b) {
          const double m = block_sums[3 * b];
          if (!(m > 0)) continue;
          out[3 * b] = static_cast<float>(m / mo.mass);
          out[3 * b + 1] = static_cast<float>(fg.x0 + (block_sums[3 * b + 1] / m + 0.5) * c + ops[k].rx);
          out[3 * b + 2] = static_cast<float>(fg.y0 + (block_sums[3 * b + 2] / m + 0.5) * c + ops[k].ry);
        }
      }
      LayerStep e;
      // Positions of the layer are cell centres + the remainder; within-cell spread c²/12.
      e.mx = mo.sx + ops[k].rx;
      e.my = mo.sy + ops[k].ry;
      const double extra = ops[k].pending_var_m2 + c * c / 12.0;
      e.cxx = mo.sxx + extra;
      e.cxy = mo.sxy;
      e.cyy = mo.syy + extra;
      return e;
    };

    std::vector<std::vector<float>> checkpoints;  // alpha before steps k0, k0 + segment, ...
    std::vector<float> own_store;                  // store_all: alpha after every step, step-major
    std::vector<float>& stored = threads == 1 ? single_thread_store : own_store;
    if (store_all) stored.resize(static_cast<std::size_t>(m_run) * n);
    for (int k = k0; k < m_steps; ++k) {
      if (smooth && !store_all && (k - k0) % segment == 0) checkpoints.push_back(alpha);
      if (!forward(k, true)) {
        dead[li] = 1;
        return;
      }
      filtered[li][k] = estimate(alpha.data(), nullptr, k);
      filtered[li][k].log_evidence = log_z;
      if (store_all) std::copy(alpha.begin(), alpha.end(), stored.begin() + static_cast<std::ptrdiff_t>((k - k0) * n));
    }
    if (store_all) checkpoints.emplace_back();  // one segment, nothing to recompute
    if (!smooth) return;

    // Backward: per segment (last first) recompute alpha from its checkpoint, then
    // beta_{k-1} = Shift_kᵀ Blur_k (E_k ⊙ beta_k) and gamma_k ∝ alpha_k ⊙ beta_k.
    std::vector<float> beta(n, 1.0f);
    std::vector<std::vector<float>> seg_alpha;
    const int n_seg = static_cast<int>(checkpoints.size());
    for (int sidx = n_seg - 1; sidx >= 0; --sidx) {
      const int k_begin = k0 + sidx * segment, k_end = std::min(m_steps, k_begin + segment);
      if (!store_all) {
        alpha = checkpoints[sidx];
        seg_alpha.clear();
        for (int k = k_begin; k < k_end; ++k) {
          forward(k, false);
          seg_alpha.push_back(alpha);
        }
      }
      for (int k = k_end - 1; k >= k_begin; --k) {
        const float* a = store_all ? stored.data() + static_cast<std::size_t>(k - k0) * n : seg_alpha[k - k_begin].data();
        smoothed[li][k] = estimate(a, &beta, k);
        // beta_{k-1}
        MultiplyAndSum(beta, fg.wall_factor, fixes_at[k].empty() ? nullptr : layer_factor[k].data(), fg.nx, fg.ny);
        if (ops[k].blur_var_cells2 > 1e-6) Blur(beta, scratch, fg.nx, fg.ny, ops[k].blur_var_cells2);
        Shift(beta, fg.nx, fg.ny, -ops[k].shift_x, -ops[k].shift_y);
        // Rescale by the maximum (a branch-free loop that vectorises).
        float mx = 0.0f;
        for (const float v : beta) mx = v > mx ? v : mx;
        if (mx > 0) NormaliseAndFlush(beta, 1.0 / static_cast<double>(mx));
      }
    }
  });

  // Combine the layers.
  GridTrackResult r;
  GridTrackSummary& sum = r.summary;
  sum.steps = m_steps;
  sum.fixes = n_fixes;
  sum.layers = n_layers;
  for (int f = 0; f < n_floors; ++f)
    if (!start.known || f == start_floor_index) sum.cells += static_cast<long long>(im.grids[f].size());
  for (char d : dead) sum.dead_layers += d;
  sum.memory_bytes = bytes;
  if (sum.dead_layers == n_layers) {
    throw std::runtime_error(
        "indoorloc: GridTracker: every hypothesis was ruled out (hard walls with no walkable continuation of "
        "the steps, or a known start inside an obstacle): use a finite options.wall_log_penalty");
  }
  r.times_s.resize(m_steps);
  for (int k = 0; k < m_steps; ++k) r.times_s[k] = steps[k].time_s;
  r.heading_offset_bins_rad = Eigen::Map<const Eigen::VectorXd>(offsets.data(), offsets.size());
  r.scale_bins = Eigen::Map<const Eigen::VectorXd>(scales.data(), scales.size());

  // Layer weights from prior x evidence up to step k (filtered) or the whole walk (smoothed).
  auto layer_weights = [&](int k) {
    std::vector<double> w(n_layers, 0.0);
    double mx = -std::numeric_limits<double>::infinity();
    for (int l = 0; l < n_layers; ++l)
      if (!dead[l]) mx = std::max(mx, layers[l].log_prior + (k >= k0 ? filtered[l][k].log_evidence : 0.0));
    double s = 0;
    for (int l = 0; l < n_layers; ++l)
      if (!dead[l]) s += w[l] = std::exp(layers[l].log_prior + (k >= k0 ? filtered[l][k].log_evidence : 0.0) - mx);
    for (double& v : w) v /= s;
    return std::make_pair(w, mx + std::log(s));
  };
  auto mixture = [&](const std::vector<double>& w, const std::vector<std::vector<LayerStep>>& est, int k,
                     double* out_mean, double* out_cov) {
    double mx = 0, my = 0, sxx = 0, sxy = 0, syy = 0;
    for (int l = 0; l < n_layers; ++l) {
      if (w[l] <= 0) continue;
      const LayerStep& e = est[l][k];
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
  };
  r.filtered_mean_m.resize(m_steps, 2);
  r.filtered_covariance_m2.resize(m_steps, 3);
  r.filtered_floor_probabilities = RowMatrixXd::Zero(m_steps, n_floors);
  r.filtered_heading_offset_rad.resize(m_steps);
  const double start_var = o.start_position_sd_m * o.start_position_sd_m;
  for (int k = 0; k < m_steps; ++k) {
    if (k < k0) {  // before a known start
      r.filtered_mean_m.row(k) << start.position_m.x(), start.position_m.y();
      r.filtered_covariance_m2.row(k) << start_var, 0.0, start_var;
      r.filtered_floor_probabilities(k, start_floor_index) = 1.0;
      r.filtered_heading_offset_rad[k] = start.heading_offset_rad;
      continue;
    }
    const auto [w, log_total] = layer_weights(k);
    double mean[2], cov[3];
    mixture(w, filtered, k, mean, cov);
    r.filtered_mean_m.row(k) << mean[0], mean[1];
    r.filtered_covariance_m2.row(k) << cov[0], cov[1], cov[2];
    double cs = 0, sn = 0;
    for (int l = 0; l < n_layers; ++l) {
      r.filtered_floor_probabilities(k, layers[l].floor_index) += w[l];
      cs += w[l] * std::cos(offsets[layers[l].offset_bin]);
      sn += w[l] * std::sin(offsets[layers[l].offset_bin]);
    }
    r.filtered_heading_offset_rad[k] = std::atan2(sn, cs);
    if (k == m_steps - 1) sum.log_evidence = log_total;
  }
  // Posterior of the layers given the whole walk.
  const auto [w_all, log_total_all] = layer_weights(m_steps - 1);
  (void)log_total_all;
  r.smoothed_floor_probabilities = Eigen::VectorXd::Zero(n_floors);
  r.heading_offset_probabilities = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(offsets.size()));
  r.scale_probabilities = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(scales.size()));
  double cs = 0, sn = 0, scale_mean = 0;
  for (int l = 0; l < n_layers; ++l) {
    r.smoothed_floor_probabilities[layers[l].floor_index] += w_all[l];
    r.heading_offset_probabilities[layers[l].offset_bin] += w_all[l];
    r.scale_probabilities[layers[l].scale_bin] += w_all[l];
    cs += w_all[l] * std::cos(offsets[layers[l].offset_bin]);
    sn += w_all[l] * std::sin(offsets[layers[l].offset_bin]);
    scale_mean += w_all[l] * scales[layers[l].scale_bin];
  }
  r.heading_offset_rad = std::atan2(sn, cs);
  const double resultant = std::min(1.0, std::hypot(cs, sn));
  r.heading_offset_sd_rad = std::sqrt(std::max(0.0, -2.0 * std::log(std::max(resultant, 1e-300))));
  r.scale = scale_mean;
  if (smooth) {
    r.smoothed_mean_m.resize(m_steps, 2);
    r.smoothed_covariance_m2.resize(m_steps, 3);
    for (int k = 0; k < m_steps; ++k) {
      if (k < k0) {
        r.smoothed_mean_m.row(k) = r.filtered_mean_m.row(k);
        r.smoothed_covariance_m2.row(k) = r.filtered_covariance_m2.row(k);
        continue;
      }
      double mean[2], cov[3];
      mixture(w_all, smoothed, k, mean, cov);
      r.smoothed_mean_m.row(k) << mean[0], mean[1];
      r.smoothed_covariance_m2.row(k) << cov[0], cov[1], cov[2];
    }
  }
  CalibrateCovariances(steps, fixes, k0, o, &r);
  if (o.spatial_median) {
    // Per step: the blocks of the most probable floor's layers, weighted, then Weiszfeld.
    auto median_at = [&](const std::vector<double>& w, const std::vector<std::vector<float>>& blocks, int k) {
      std::vector<double> floor_p(n_floors, 0.0);
      for (int l = 0; l < n_layers; ++l) floor_p[layers[l].floor_index] += w[l];
      const int f = static_cast<int>(std::max_element(floor_p.begin(), floor_p.end()) - floor_p.begin());
      const std::size_t nb = blocks_of(f);
      std::vector<double> acc(nb * 3, 0.0);
      for (int l = 0; l < n_layers; ++l) {
        if (layers[l].floor_index != f || !(w[l] > 0) || dead[l]) continue;
        const float* b = blocks[l].data() + static_cast<std::size_t>(k) * nb * 3;
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
      return SpatialMedian(points, 0.5 * q * c);
    };
    r.filtered_median_m.resize(m_steps, 2);
    if (smooth) r.smoothed_median_m.resize(m_steps, 2);
    for (int k = 0; k < m_steps; ++k) {
      if (k < k0) {
        r.filtered_median_m.row(k) = r.filtered_mean_m.row(k);
        if (smooth) r.smoothed_median_m.row(k) = r.smoothed_mean_m.row(k);
        continue;
      }
      r.filtered_median_m.row(k) = median_at(layer_weights(k).first, filtered_blocks, k).transpose();
      if (smooth) r.smoothed_median_m.row(k) = median_at(w_all, smoothed_blocks, k).transpose();
    }
  }
  sum.seconds = timer.ElapsedSeconds();
  return r;
}

}  // namespace indoorloc::fusion
