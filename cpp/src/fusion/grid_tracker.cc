// Grid tracker: exact forward filter and forward-backward smoother on floor cells (see the
// header for the model). Each layer (floor, heading-offset bin, scale bin) is an independent
// hidden Markov model; a layer is filtered and smoothed in one task, the layers in parallel.
// This file: the options' check, the grid's construction, and Run (input checks, the run plan,
// the layers in parallel); the pieces are listed in grid_run.h.
#include "indoorloc/fusion/grid_tracker.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>

#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "indoorloc/core/validate.h"
#include "grid_ops.h"
#include "grid_run.h"

namespace indoorloc::fusion {

using namespace grid_ops;  // NOLINT: the operators shared with the streaming session

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
      .InRange(wall_margin_m, 0.0, 100.0, "wall_margin_m")
      .Check(fix_ok, "fix", fix_error)
      .InRange(fix_survey_distance_factor, 0.0, 1.0, "fix_survey_distance_factor")
      .InRange(survey_walkable_radius_m, 0.0, 100.0, "survey_walkable_radius_m")
      .IntInRange(survey_walkable_min_walks, 1, 1000000, "survey_walkable_min_walks")
      .InRange(median_block_m, 0.1, 100.0, "median_block_m")
      .InRange(start_position_sd_m, 0.01, 1e4, "start_position_sd_m")
      .InRange(filtered_covariance_scale, 1e-6, 1e6, "filtered_covariance_scale")
      .InRange(filtered_covariance_floor_m, 0.0, 1e4, "filtered_covariance_floor_m")
      .InRange(filtered_covariance_fix_gain, 0.0, 1e3, "filtered_covariance_fix_gain")
      .InRange(smoothed_covariance_scale, 1e-6, 1e6, "smoothed_covariance_scale")
      .InRange(smoothed_covariance_floor_m, 0.0, 1e4, "smoothed_covariance_floor_m")
      .InRange(smoothed_covariance_fix_gain, 0.0, 1e3, "smoothed_covariance_fix_gain")
      .InRange(filtered_covariance_fix_sd_gain, 0.0, 1e3, "filtered_covariance_fix_sd_gain")
      .InRange(smoothed_covariance_fix_sd_gain, 0.0, 1e3, "smoothed_covariance_fix_sd_gain")
      .InRange(covariance_fix_sd_knee_m, 0.0, 1e4, "covariance_fix_sd_knee_m")
      .InRange(max_memory_bytes, 1e6, 1e13, "max_memory_bytes")
      .IntInRange(num_threads, -1, 4096, "num_threads");
}

std::string GridTrackSummary::BriefReport() const {
  std::ostringstream out;
  out << steps << " steps, " << fixes << " fixes, " << layers << " layers (" << dead_layers << " ruled out), "
      << (smoother_gap_steps ? std::to_string(smoother_gap_steps) + " smoother gap steps, " : std::string())
      << cells << " cells, log-evidence " << log_evidence << ", " << FormatBytes(memory_bytes) << ", " << seconds
      << " s";
  return out.str();
}

namespace {

// Marks as walkable the points not walkable as drawn but within `margin_m` of a wall edge (the
// obstacles eroded by the margin; only those points are queried for their distance).
void ErodeObstacles(const FloorPlan& plan, int floor_index, const RowMatrixXd& pts, double margin_m, int threads,
                    VectorXb* walk) {
  std::vector<Eigen::Index> blocked;
  for (Eigen::Index i = 0; i < walk->size(); ++i)
    if (!(*walk)[i]) blocked.push_back(i);
  if (blocked.empty()) return;
  RowMatrixXd q(static_cast<Eigen::Index>(blocked.size()), 2);
  for (std::size_t j = 0; j < blocked.size(); ++j) q.row(static_cast<Eigen::Index>(j)) = pts.row(blocked[j]);
  const Eigen::VectorXd d = plan.DistanceToWallBatch(q, Eigen::VectorXi::Constant(1, floor_index), threads);
  for (std::size_t j = 0; j < blocked.size(); ++j)
    if (d[static_cast<Eigen::Index>(j)] <= margin_m) (*walk)[blocked[j]] = true;
}

// The grid of `plan` with `options`' cells, checked against max_memory_bytes (the walkable
// fractions and, per run, about ten grids per thread): refuse before allocating.
void CheckGridMemory(const FloorPlan& plan, const GridTrackerOptions& options) {
  const double c = options.cell_size_m;
  const int n_sub = options.walkable_subsamples;
  double cells = 0;
  for (int f = 0; f < plan.num_floors(); ++f) {
    const Eigen::Vector4d b = plan.Bounds(f);
    cells += std::ceil((b[2] - b[0]) / c) * std::ceil((b[3] - b[1]) / c);
  }
  const double bytes = cells * (8.0 + n_sub * n_sub * 17.0);
  CheckArgument(bytes <= options.max_memory_bytes, "options",
                "the grid of " + FormatValue(cells) + " cells needs " + FormatBytes(bytes) +
                    " to build, above max_memory_bytes = " + FormatBytes(options.max_memory_bytes) +
                    " (use larger cells)");
}

}  // namespace

GridTracker::GridTracker(const FloorPlan* plan, const GridTrackerOptions& options) : impl_(new Impl) {
  CheckArgument(plan != nullptr, "plan", "must not be None");
  ValidateOptions(options);
  CheckGridMemory(*plan, options);
  impl_->plan = plan;
  impl_->options = options;
  const double c = options.cell_size_m;
  const int n_sub = options.walkable_subsamples;
  const double penalty = WallPenalty(options.wall_log_penalty);
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
    VectorXb walk = plan->IsWalkableBatch(pts, Eigen::VectorXi::Constant(1, f), options.num_threads);
    if (options.wall_margin_m > 0) ErodeObstacles(*plan, f, pts, options.wall_margin_m, options.num_threads, &walk);
    g.walkable_fraction.resize(g.size());
    g.wall_factor.resize(g.size());
    for (std::size_t i = 0; i < g.size(); ++i) {
      int n = 0;
      for (int s = 0; s < n_sub * n_sub; ++s) n += walk[static_cast<Eigen::Index>(i) * n_sub * n_sub + s];
      g.walkable_fraction[i] = static_cast<float>(static_cast<double>(n) / (n_sub * n_sub));
      g.wall_factor[i] = WallFactor(n, n_sub, penalty);
    }
    impl_->grids.push_back(std::move(g));
    impl_->total_area_m2 += plan->WalkableArea(f);
  }
}

GridTracker::~GridTracker() = default;
GridTracker::GridTracker(GridTracker&&) noexcept = default;
GridTracker& GridTracker::operator=(GridTracker&&) noexcept = default;

const GridTrackerOptions& GridTracker::options() const { return impl_->options; }

GridTracker GridTracker::WithOptions(const GridTrackerOptions& options) const {
  ValidateOptions(options);
  const GridTrackerOptions& own = impl_->options;
  CheckArgument(options.cell_size_m == own.cell_size_m && options.walkable_subsamples == own.walkable_subsamples &&
                    options.wall_margin_m == own.wall_margin_m,
                "options",
                "must keep this tracker's grid (cell_size_m " + FormatValue(own.cell_size_m) +
                    ", walkable_subsamples " + std::to_string(own.walkable_subsamples) + ", wall_margin_m " +
                    FormatValue(own.wall_margin_m) + "); build a new GridTracker for another grid");
  CheckGridMemory(*impl_->plan, options);
  GridTracker out;
  out.impl_.reset(new Impl(*impl_));
  out.impl_->options = options;
  const int n_sub = options.walkable_subsamples;
  const bool walls = options.wall_log_penalty != own.wall_log_penalty ||
                     options.survey_walkable_radius_m != own.survey_walkable_radius_m ||
                     options.survey_walkable_min_walks != own.survey_walkable_min_walks;
  const bool anchors = options.fix_survey_distance_factor != own.fix_survey_distance_factor;
  const double penalty = WallPenalty(options.wall_log_penalty);
  for (grid_ops::FloorGrid& g : out.impl_->grids) {
    if (walls) grid_ops::ComputeWallFactors(penalty, n_sub, options.survey_walkable_radius_m,
                                            options.survey_walkable_min_walks, options.cell_size_m, &g);
    if (anchors) grid_ops::AnchorFixesToSurvey(options.fix_survey_distance_factor, options.cell_size_m, &g);
  }
  return out;
}

Eigen::Vector4d GridTracker::GridGeometry(int floor_index) const {
  RequireIntInRange(floor_index, 0, static_cast<int>(impl_->grids.size()) - 1, "floor_index");
  const FloorGrid& g = impl_->grids[floor_index];
  return Eigen::Vector4d(g.x0, g.y0, g.nx, g.ny);
}

namespace {
// A per-cell vector of a floor's grid (row-major, row 0 at the lowest y) as rows x columns.
RowMatrixXd AsLattice(const grid_ops::FloorGrid& g, const std::vector<float>& v) {
  RowMatrixXd out(g.ny, g.nx);
  for (int y = 0; y < g.ny; ++y)
    for (int x = 0; x < g.nx; ++x) out(y, x) = v[static_cast<std::size_t>(y) * g.nx + x];
  return out;
}
}  // namespace

RowMatrixXd GridTracker::WalkableFraction(int floor_index) const {
  RequireIntInRange(floor_index, 0, static_cast<int>(impl_->grids.size()) - 1, "floor_index");
  return AsLattice(impl_->grids[floor_index], impl_->grids[floor_index].walkable_fraction);
}

RowMatrixXd GridTracker::WallFactors(int floor_index) const {
  RequireIntInRange(floor_index, 0, static_cast<int>(impl_->grids.size()) - 1, "floor_index");
  return AsLattice(impl_->grids[floor_index], impl_->grids[floor_index].wall_factor);
}

RowMatrixXd GridTracker::FixLogLikelihood(int floor_index, const std::vector<PositionFix>& fixes) const {
  RequireIntInRange(floor_index, 0, static_cast<int>(impl_->grids.size()) - 1, "floor_index");
  const FloorGrid& g = impl_->grids[floor_index];
  const Eigen::VectorXi all_cells = Eigen::VectorXi::LinSpaced(g.ny * g.nx, 0, g.ny * g.nx - 1);
  const Eigen::VectorXi one_group = (Eigen::VectorXi(2) << 0, static_cast<int>(fixes.size())).finished();
  const RowMatrixXd row = FixLogLikelihoodGroups(floor_index, fixes, one_group, all_cells);
  return Eigen::Map<const RowMatrixXd>(row.data(), g.ny, g.nx);  // row-major: cell y * nx + x
}

RowMatrixXd GridTracker::FixLogLikelihoodGroups(int floor_index, const std::vector<PositionFix>& fixes,
                                                const Eigen::VectorXi& group_starts,
                                                const Eigen::VectorXi& cells) const {
  RequireIntInRange(floor_index, 0, static_cast<int>(impl_->grids.size()) - 1, "floor_index");
  const FloorGrid& g = impl_->grids[floor_index];
  const int n_fixes = static_cast<int>(fixes.size());
  if (group_starts.size() < 1 || group_starts(0) != 0 || group_starts(group_starts.size() - 1) != n_fixes) {
    ThrowInvalidArgument("group_starts", "must run from 0 to the number of fixes (" + std::to_string(n_fixes) +
                                             ") with one more entry than groups");
  }
  for (Eigen::Index k = 1; k < group_starts.size(); ++k) {
    if (group_starts(k) < group_starts(k - 1)) {
      ThrowInvalidArgument("group_starts", "must be non-decreasing (entry " + std::to_string(k) + ")");
    }
  }
  const long long n_cells = static_cast<long long>(g.ny) * g.nx;
  for (Eigen::Index i = 0; i < cells.size(); ++i) {
    if (cells(i) < 0 || cells(i) >= n_cells) {
      ThrowInvalidArgument("cells", "entry " + std::to_string(i) + " = " + std::to_string(cells(i)) +
                                        " is not a lattice cell of floor " + std::to_string(floor_index) + " (0 .. " +
                                        std::to_string(n_cells - 1) + ")");
    }
  }
  for (int j = 0; j < n_fixes; ++j) {
    const std::string name = "fixes[" + std::to_string(j) + "]";
    CheckPositionFix(fixes[j], name.c_str());
  }
  const Eigen::Index n_groups = group_starts.size() - 1;
  RequireSizeLimit(static_cast<double>(n_groups) * static_cast<double>(cells.size()), 8.0, "cells",
                   "log-likelihoods (groups x cells)");
  RowMatrixXd out = RowMatrixXd::Zero(n_groups, cells.size());
  std::vector<const PositionFix*> ptrs;
  for (Eigen::Index k = 0; k < n_groups; ++k) {
    if (group_starts(k + 1) == group_starts(k)) continue;
    ptrs.clear();
    for (int j = group_starts(k); j < group_starts(k + 1); ++j) ptrs.push_back(&fixes[j]);
    const grid_ops::TrackerGrids::FixFactor f = impl_->ComputeFixFactor(ptrs, g);
    for (Eigen::Index i = 0; i < cells.size(); ++i) {  // as FixLogLikelihood, at the cells asked for
      const float v = f.factor[static_cast<std::size_t>(cells(i))];
      out(k, i) = v > 0 ? std::log(static_cast<double>(v)) + f.log_scale : -std::numeric_limits<double>::infinity();
    }
  }
  return out;
}

namespace {

// Buffers kept between runs (GridTracker::Run): a run takes its layers' output slots and, per
// layer, a smoother store from here and gives them back when done; idle buffers are kept while
// their total stays within GridTracker::kept_memory_limit_bytes (a batch of walks then reuses
// them instead of paying a page fault per 4 KB of fresh memory on every run), and
// GridTracker::ReleaseKeptMemory frees them. What a buffer holds never reaches a result (every
// entry is written before it is read), so results do not depend on which buffer a run gets.
class KeptBuffers {
 public:
  static KeptBuffers& Instance() {
    static KeptBuffers* pool = new KeptBuffers;  // never destroyed: no order problem at exit
    return *pool;
  }
  std::unique_ptr<grid_run::StoreBuffer> TakeStore() { return Take(&stores_); }
  std::unique_ptr<grid_run::RunSlots> TakeSlots() { return Take(&slots_); }
  void Give(std::unique_ptr<grid_run::StoreBuffer> b) { Keep(std::move(b), &stores_); }
  void Give(std::unique_ptr<grid_run::RunSlots> b) { Keep(std::move(b), &slots_); }
  double Bytes() {
    std::lock_guard<std::mutex> lock(mutex_);
    return bytes_;
  }
  double Release() {
    std::vector<std::unique_ptr<grid_run::StoreBuffer>> stores;
    std::vector<std::unique_ptr<grid_run::RunSlots>> slots;
    double freed;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stores.swap(stores_);
      slots.swap(slots_);
      freed = bytes_;
      bytes_ = 0;
    }
    return freed;  // the buffers are freed here, outside the lock
  }

 private:
  template <class T>
  std::unique_ptr<T> Take(std::vector<std::unique_ptr<T>>* idle) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (idle->empty()) return std::make_unique<T>();
    // The largest idle buffer: a run then rarely grows one (fresh pages) while a larger one idles.
    auto largest = std::max_element(idle->begin(), idle->end(),
                                    [](const auto& a, const auto& b) { return a->Bytes() < b->Bytes(); });
    std::unique_ptr<T> b = std::move(*largest);
    idle->erase(largest);
    bytes_ -= b->Bytes();
    return b;
  }
  template <class T>
  void Keep(std::unique_ptr<T> b, std::vector<std::unique_ptr<T>>* idle) {
    const double bytes = b->Bytes();
    std::lock_guard<std::mutex> lock(mutex_);
    if (bytes_ + bytes > GridTracker::kept_memory_limit_bytes) return;  // b is freed (under the lock: rare)
    bytes_ += bytes;
    idle->push_back(std::move(b));
  }

  std::mutex mutex_;
  std::vector<std::unique_ptr<grid_run::StoreBuffer>> stores_;
  std::vector<std::unique_ptr<grid_run::RunSlots>> slots_;
  double bytes_ = 0;
};

// The public boundary's checks of Run's arguments; returns the known start's floor index (-1).
int CheckRunInputs(const TrackerGrids& im, const std::vector<StepInput>& steps,
                   const std::vector<PositionFix>& fixes, const TrackStart& start) {
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
  if (!start.known) return -1;
  RequireFinite(start.time_s, "start.time_s");
  RequireFinite(start.position_m.x(), "start.position_m");
  RequireFinite(start.position_m.y(), "start.position_m");
  RequireFinite(start.heading_offset_rad, "start.heading_offset_rad");
  return im.plan->FloorIndex(start.floor);
}

// Fixes attached to steps: the first step at or after the fix (the last step for later fixes);
// with a known start, fixes before it are not used.
void AttachFixes(grid_run::RunPlan* p) {
  const std::vector<StepInput>& steps = *p->steps;
  p->fixes_at.assign(p->m_steps, {});
  for (const PositionFix& fix : *p->fixes) {
    if (fix.empty()) continue;
    if (p->start->known && fix.time_s < p->start->time_s) continue;
    int k = static_cast<int>(std::lower_bound(steps.begin(), steps.end(), fix.time_s,
                                              [](const StepInput& s, double t) { return s.time_s < t; }) -
                             steps.begin());
    k = std::min(std::max(k, p->k0), p->m_steps - 1);
    if (k < p->k0) continue;
    p->fixes_at[k].push_back(&fix);
    ++p->n_fixes;
  }
}

// Threads, the smoother's storage (every forward grid, or checkpoints) and the memory check.
void PlanMemory(grid_run::RunPlan* p) {
  const TrackerGrids& im = *p->impl;
  const GridTrackerOptions& o = im.options;
  const double c = o.cell_size_m;
  const int n_floors = p->num_floors();
  const int n_layers = static_cast<int>(p->layer_set.layers.size());
  // Memory: fix factors (shared) and per thread the live grids and the smoother's checkpoints.
  p->threads = std::min(ResolveThreadCount(o.num_threads), std::max(1, n_layers));
  const int m_run = p->m_steps - p->k0;
  double max_cells = 0, fix_cells = 0, fix_steps = 0;
  for (int k = 0; k < p->m_steps; ++k) fix_steps += p->has_fix(k) ? 1 : 0;
  for (int f = 0; f < n_floors; ++f) {
    if (p->start->known && f != p->start_floor_index) continue;
    max_cells = std::max(max_cells, static_cast<double>(im.grids[f].size()));
    fix_cells += fix_steps * static_cast<double>(im.grids[f].size());
  }
  // The smoother keeps every forward grid of a layer while that fits in 256 MB per thread (a walk
  // of minutes on a mall floor), else about sqrt(M) checkpoints and recomputes each segment once.
  p->store_all = p->smooth && static_cast<double>(m_run) * max_cells * 4.0 <= 256e6;
  p->segment = p->store_all ? std::max(1, m_run)
                            : std::max(1, static_cast<int>(std::ceil(std::sqrt(std::max(1, m_run)))));
  // Per thread: alpha, beta, scratch, the layer's fix factors, the checkpoints and a segment.
  const double per_thread = max_cells * 4.0 *
                            (4.0 + fix_steps + (p->smooth ? (p->store_all ? m_run : m_run / p->segment + 1 + p->segment) : 0));
  // Spatial medians: per layer and step the block summaries (mass, centroid).
  p->q = std::max(1, static_cast<int>(std::lround(o.median_block_m / c)));
  double max_blocks = 0;
  for (int f = 0; f < n_floors; ++f)
    max_blocks = std::max(max_blocks, std::ceil(im.grids[f].nx / static_cast<double>(p->q)) *
                                          std::ceil(im.grids[f].ny / static_cast<double>(p->q)));
  const double median_bytes =
      o.spatial_median ? static_cast<double>(n_layers) * m_run * max_blocks * 12.0 * ((p->smooth ? 1 : 0) + (p->filtered ? 1 : 0)) : 0.0;
  p->bytes = fix_cells * 4.0 + p->threads * per_thread + median_bytes;
  CheckArgument(p->bytes <= o.max_memory_bytes, "steps",
                std::to_string(m_run) + " steps on this grid need " + FormatBytes(p->bytes) +
                    ", above options.max_memory_bytes = " + FormatBytes(o.max_memory_bytes) +
                    " (use larger cells or fewer offset bins)");
}

// Fix factors per (step, floor), computed once and shared by the layers of a floor.
void ComputeFixFactors(grid_run::RunPlan* p) {
  p->factor.assign(p->m_steps, {});
  for (int k = 0; k < p->m_steps; ++k) {
    if (!p->has_fix(k)) continue;
    p->factor[k].resize(p->num_floors());
    for (int f = 0; f < p->num_floors(); ++f) {
      if (p->start->known && f != p->start_floor_index) continue;
      p->factor[k][f] = p->impl->ComputeFixFactor(p->fixes_at[k], p->impl->grids[f]);
    }
  }
}

}  // namespace

namespace {
// Whether a known start's forward pass runs on its window of nonzero cells (test_hooks::SetKnownStartWindow).
std::atomic<bool>& KnownStartWindow() {
  static std::atomic<bool> on{true};
  return on;
}
}  // namespace

GridTrackResult GridTracker::Run(const std::vector<StepInput>& steps, const std::vector<PositionFix>& fixes,
                                 const TrackStart& start, bool smooth, bool filtered_estimates) const {
  WallTimer timer;
  const Impl& im = *impl_;
  grid_run::RunPlan plan;
  plan.impl = &im;
  plan.steps = &steps;
  plan.fixes = &fixes;
  plan.start = &start;
  plan.smooth = smooth;
  plan.filtered = filtered_estimates || !smooth;
  plan.start_floor_index = CheckRunInputs(im, steps, fixes, start);
  plan.m_steps = static_cast<int>(steps.size());
  // With a known start, steps up to its time are before the start: estimates there are the start.
  if (start.known) {
    while (plan.k0 < plan.m_steps && steps[plan.k0].time_s <= start.time_s) ++plan.k0;
  }
  plan.window = start.known && KnownStartWindow().load(std::memory_order_relaxed);
  plan.layer_set = MakeGridLayers(im.options, *im.plan, plan.num_floors(), im.total_area_m2, start, plan.start_floor_index);
  AttachFixes(&plan);
  PlanMemory(&plan);
  ComputeFixFactors(&plan);

  // The layers in parallel, each into its own slot. The layers' outputs (blocks of the spatial
  // medians, the fix factors: megabytes per layer) and the smoother's stored forward grids (tens
  // of MB per walk; each layer takes a store and gives it back for the next layer) come from the
  // kept buffers of earlier runs: fresh memory costs a page fault per 4 KB page, and about 7 % of
  // a fusion evaluate's CPU time went to the kernel for them.
  const int n_layers = static_cast<int>(plan.layer_set.layers.size());
  KeptBuffers& kept = KeptBuffers::Instance();
  std::unique_ptr<grid_run::RunSlots> slots = kept.TakeSlots();
  std::vector<grid_run::LayerRun>& runs = slots->runs;
  if (runs.size() < static_cast<std::size_t>(n_layers)) runs.resize(static_cast<std::size_t>(n_layers));
  ParallelForRuns(n_layers, plan.threads, 0, [&](int li, RandomStream&) {
    std::unique_ptr<grid_run::StoreBuffer> store = plan.store_all ? kept.TakeStore() : nullptr;
    grid_run::RunLayer(plan, li, store.get(), &runs[static_cast<std::size_t>(li)]);
    if (store) kept.Give(std::move(store));
  });
  GridTrackResult r = grid_run::CombineLayers(plan, runs);
  kept.Give(std::move(slots));
  r.summary.seconds = timer.ElapsedSeconds();
  return r;
}

namespace test_hooks {
void SetKnownStartWindow(bool on) { KnownStartWindow().store(on, std::memory_order_relaxed); }
}  // namespace test_hooks

double GridTracker::ReleaseKeptMemory() { return KeptBuffers::Instance().Release(); }

double GridTracker::KeptMemoryBytes() { return KeptBuffers::Instance().Bytes(); }

}  // namespace indoorloc::fusion
