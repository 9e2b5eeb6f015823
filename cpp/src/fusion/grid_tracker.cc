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
#include "grid_ops.h"

namespace indoorloc::fusion {

using namespace grid_ops;  // NOLINT: the operators shared with the streaming session

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

namespace grid_ops {

GridLayers MakeGridLayers(const GridTrackerOptions& o, const FloorPlan& plan, int n_floors, double total_area_m2,
                          const TrackStart& start, int start_floor_index) {
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
  std::vector<GridLayer> layers;
  for (int f = 0; f < n_floors; ++f) {
    if (start.known && f != start_floor_index) continue;
    // Unknown start: uniform over the walkable area of all floors, so a floor's prior is its area.
    const double floor_log_prior = start.known ? 0.0 : std::log(plan.WalkableArea(f) / total_area_m2);
    for (std::size_t h = 0; h < offsets.size(); ++h)
      for (std::size_t s = 0; s < scales.size(); ++s)
        layers.push_back({f, static_cast<int>(h), static_cast<int>(s),
                          floor_log_prior + offset_log_prior[h] + scale_log_prior[s]});
  }
  {  // normalise the layer prior
    double mx = -std::numeric_limits<double>::infinity();
    for (const GridLayer& l : layers) mx = std::max(mx, l.log_prior);
    double sum = 0;
    for (const GridLayer& l : layers) sum += std::exp(l.log_prior - mx);
    for (GridLayer& l : layers) l.log_prior -= mx + std::log(sum);
  }

  GridLayers out;
  out.offsets = std::move(offsets);
  out.scales = std::move(scales);
  out.bin_width = bin_width;
  out.layers = std::move(layers);
  return out;
}

}  // namespace grid_ops

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

  const int n_floors = static_cast<int>(im.grids.size());
  const GridLayers layer_set = MakeGridLayers(o, *im.plan, n_floors, im.total_area_m2, start, start_floor_index);
  const std::vector<double>& offsets = layer_set.offsets;
  const std::vector<double>& scales = layer_set.scales;
  const double bin_width = layer_set.bin_width;
  const std::vector<GridLayer>& layers = layer_set.layers;

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
    const GridLayer& layer = layers[li];
    const FloorGrid& fg = im.grids[layer.floor_index];
    const double off = offsets[layer.offset_bin], sc = scales[layer.scale_bin];
    const double co = std::cos(off), so = std::sin(off);
    const std::size_t n = fg.size();
    std::vector<float> alpha(n), scratch(n);
    // Prior: uniform over the walkable cells, or a Gaussian around the known start.
    grid_ops::FillStartPrior(fg, start, o.start_position_sd_m, c, &alpha);
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
        op = PlanStep(steps[k], sc, co, so, c, o.position_noise_m, bin_width, !fixes_at[k].empty(), &rx, &ry, &pending);
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
      // Positions of the layer are cell centres + the remainder; within-cell spread c²/12.
      return FilteredLayerEstimate(mo, ops[k], c);
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
