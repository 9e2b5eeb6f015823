// Grid filter session: the batch forward pass of GridTracker::Run (grid_tracker.cc) cut at step
// boundaries. Every per-layer operation is the batch's own (grid_ops.h) in the same order, and the
// layers are combined per step exactly as the batch combines them.
#include "indoorloc/fusion/grid_filter_session.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "indoorloc/core/validate.h"
#include "grid_ops.h"

namespace indoorloc::fusion {

using namespace grid_ops;  // NOLINT: the batch's operators

namespace {

std::string Seconds(double t) { return FormatValue(t) + " s"; }

// The estimate at a step before a known start: the walker stands at the start (the batch's
// estimate there), located, with `fixes` applied so far.
void AtKnownStart(const TrackStart& start, int floor_index, int n_floors, double start_sd_m, int fixes,
                  GridFilterEstimate* e) {
  const double var = start_sd_m * start_sd_m;
  e->mean_m = start.position_m;
  e->covariance_m2 << var, 0.0, var;
  e->posterior_covariance_m2 = e->covariance_m2;
  e->fix_distance_m = 0.0;
  e->fix_sd_m = 0.0;
  e->floor_probabilities = Eigen::VectorXd::Zero(n_floors);
  e->floor_probabilities[floor_index] = 1.0;
  e->heading_offset_rad = start.heading_offset_rad;
  e->log_evidence = 0.0;
  e->fixes = fixes;
  e->located = true;
}

}  // namespace

struct GridFilterSession::State {
  const GridTracker* tracker = nullptr;
  TrackStart start;
  int start_floor_index = -1;
  GridLayers layer_set;
  // Per layer: the forward grid alpha, the sub-cell remainder, the pending process variance, the
  // cumulative log evidence, the latest estimate, whether it was ruled out.
  std::vector<std::vector<float>> alpha;
  std::vector<double> rx, ry, pending, log_z;
  std::vector<LayerStep> estimate;
  std::vector<char> dead;
  std::vector<PositionFix> pending_fixes;   // time order, waiting for a step at or after them
  int steps = 0;                            // steps added
  bool started = false;                     // a step after the known start's time was processed
  bool failed = false;                      // every layer ruled out
  double last_step_time = -std::numeric_limits<double>::infinity();
  double last_fix_time = -std::numeric_limits<double>::infinity();
  bool has_fix_centre = false;              // a fix was added (the calibration's d measures from it)
  Eigen::Vector2d fix_centre = Eigen::Vector2d::Zero();
  double fix_sd = 0.0;                       // the same fix's own sd [m] (grid_ops.h FixSd)
  GridFilterEstimate current;
  GridTrackSummary summary;
};

GridFilterSession::GridFilterSession(const GridTracker* tracker, const TrackStart& start) : state_(new State) {
  CheckArgument(tracker != nullptr, "tracker", "must not be null");
  State& s = *state_;
  s.tracker = tracker;
  s.start = start;
  const GridTracker::Impl& im = *tracker->impl_;
  const GridTrackerOptions& o = im.options;
  if (start.known) {
    RequireFinite(start.time_s, "start.time_s");
    RequireFinite(start.position_m.x(), "start.position_m");
    RequireFinite(start.position_m.y(), "start.position_m");
    RequireFinite(start.heading_offset_rad, "start.heading_offset_rad");
    s.start_floor_index = im.plan->FloorIndex(start.floor);
  }
  const int n_floors = static_cast<int>(im.grids.size());
  s.layer_set = MakeGridLayers(o, *im.plan, n_floors, im.total_area_m2, start, s.start_floor_index);
  const std::vector<GridLayer>& layers = s.layer_set.layers;
  const int n_layers = static_cast<int>(layers.size());
  // Memory: a grid per layer, and per floor in use the fix factor of a step with fixes.
  double bytes = 0;
  for (const GridLayer& l : layers) bytes += 4.0 * static_cast<double>(im.grids[l.floor_index].size());
  for (int f = 0; f < n_floors; ++f)
    if (!start.known || f == s.start_floor_index) bytes += 8.0 * static_cast<double>(im.grids[f].size());
  CheckArgument(bytes <= o.max_memory_bytes, "tracker",
                "a session on this grid needs " + FormatBytes(bytes) + ", above options.max_memory_bytes = " +
                    FormatBytes(o.max_memory_bytes) + " (use larger cells or fewer offset bins)");
  s.alpha.resize(n_layers);
  s.rx.assign(n_layers, 0.0);
  s.ry.assign(n_layers, 0.0);
  s.pending.assign(n_layers, 0.0);
  s.log_z.assign(n_layers, 0.0);
  s.estimate.assign(n_layers, LayerStep());
  s.dead.assign(n_layers, 0);
  const double c = o.cell_size_m;
  for (int li = 0; li < n_layers; ++li) {  // the prior, as the batch's
    const FloorGrid& fg = im.grids[layers[li].floor_index];
    std::vector<float>& alpha = s.alpha[li];
    grid_ops::FillStartPrior(fg, start, o.start_position_sd_m, c, &alpha);
    for (std::size_t i = 0; i < alpha.size(); ++i) alpha[i] *= fg.wall_factor[i];
    double sum = 0;
    for (float v : alpha) sum += v;
    if (!(sum > 0)) {  // a known start entirely inside obstacles with hard walls
      s.dead[li] = 1;
      std::vector<float>().swap(alpha);
      continue;
    }
    for (float& v : alpha) v = static_cast<float>(v / sum);
  }
  s.summary.layers = n_layers;
  for (int f = 0; f < n_floors; ++f)
    if (!start.known || f == s.start_floor_index) s.summary.cells += static_cast<long long>(im.grids[f].size());
  for (char d : s.dead) s.summary.dead_layers += d;
  s.summary.memory_bytes = bytes;
  if (s.summary.dead_layers == n_layers) {
    throw std::invalid_argument(
        "indoorloc: GridFilterSession: argument 'start': the known start lies inside obstacles with hard walls "
        "(every hypothesis is ruled out): use a finite options.wall_log_penalty");
  }
  s.current.floor_probabilities = Eigen::VectorXd::Zero(n_floors);
}

GridFilterSession::~GridFilterSession() = default;
GridFilterSession::GridFilterSession(GridFilterSession&&) noexcept = default;
GridFilterSession& GridFilterSession::operator=(GridFilterSession&&) noexcept = default;

void GridFilterSession::AddFix(const PositionFix& fix) {
  State& s = *state_;
  CheckPositionFix(fix, "fix");
  CheckArgument(fix.time_s >= s.last_fix_time, "fix",
                "out of time order: its time " + Seconds(fix.time_s) + " is before the previous fix's " +
                    Seconds(s.last_fix_time));
  CheckArgument(fix.time_s > s.last_step_time, "fix",
                "out of time order: its time " + Seconds(fix.time_s) + " is not after the latest step's " +
                    Seconds(s.last_step_time) +
                    " (a fix at a step's time belongs to that step: add it before the step)");
  s.last_fix_time = fix.time_s;
  // The batch's calibration measures from the last fix at or before a step, whatever it is.
  s.has_fix_centre = true;
  s.fix_centre = FixCentre(fix);
  s.fix_sd = FixSd(fix);
  if (fix.empty()) return;
  if (s.start.known && fix.time_s < s.start.time_s) return;  // the batch ignores fixes before a known start
  s.pending_fixes.push_back(fix);
}

GridFilterEstimate GridFilterSession::AddStep(const StepInput& step) {
  State& s = *state_;
  CheckStepInput(step, "step");
  if (s.failed) {
    throw std::runtime_error("indoorloc: GridFilterSession: every hypothesis was ruled out at an earlier step");
  }
  CheckArgument(step.time_s >= s.last_step_time, "step",
                "out of time order: its time " + Seconds(step.time_s) + " is before the previous step's " +
                    Seconds(s.last_step_time));
  CheckArgument(step.time_s >= s.last_fix_time, "step",
                "out of time order: its time " + Seconds(step.time_s) + " is before the latest fix's " +
                    Seconds(s.last_fix_time));
  WallTimer timer;
  const GridTracker::Impl& im = *s.tracker->impl_;
  const GridTrackerOptions& o = im.options;
  const double c = o.cell_size_m;
  s.last_step_time = step.time_s;
  ++s.steps;
  s.summary.steps = s.steps;
  const int n_floors = static_cast<int>(im.grids.size());
  GridFilterEstimate& e = s.current;
  e.time_s = step.time_s;
  e.steps = s.steps;
  if (s.start.known && !s.started && step.time_s <= s.start.time_s) {
    AtKnownStart(s.start, s.start_floor_index, n_floors, o.start_position_sd_m, s.summary.fixes, &e);
    s.summary.seconds += timer.ElapsedSeconds();
    return e;
  }
  s.started = true;

  // The fixes of this step (those at or before its time), their factor per floor in use.
  std::vector<const PositionFix*> fixes_here;
  std::size_t n_used = 0;
  while (n_used < s.pending_fixes.size() && s.pending_fixes[n_used].time_s <= step.time_s) {
    fixes_here.push_back(&s.pending_fixes[n_used]);
    ++n_used;
  }
  const bool has_fix = !fixes_here.empty();
  std::vector<GridTracker::Impl::FixFactor> factor(has_fix ? n_floors : 0);
  if (has_fix) {
    for (int f = 0; f < n_floors; ++f) {
      if (s.start.known && f != s.start_floor_index) continue;
      factor[f] = im.ComputeFixFactor(fixes_here, im.grids[f]);
    }
  }

  const std::vector<GridLayer>& layers = s.layer_set.layers;
  const int n_layers = static_cast<int>(layers.size());
  const int threads = std::min(ResolveThreadCount(o.num_threads), std::max(1, n_layers));
  const int q = std::max(1, static_cast<int>(std::lround(o.median_block_m / c)));
  ParallelForRuns(n_layers, threads, 0, [&](int li, RandomStream&) {
    if (s.dead[li]) return;
    const GridLayer& layer = layers[li];
    const FloorGrid& fg = im.grids[layer.floor_index];
    const double off = s.layer_set.offsets[layer.offset_bin], sc = s.layer_set.scales[layer.scale_bin];
    const double co = std::cos(off), so = std::sin(off);
    std::vector<float>& alpha = s.alpha[li];
    thread_local std::vector<float> scratch, layer_factor;
    thread_local std::vector<double> block_sums;
    scratch.resize(alpha.size());
    const StepOps op = PlanStep(step, sc, co, so, c, o.position_noise_m, s.layer_set.bin_width, has_fix, &s.rx[li],
                                &s.ry[li], &s.pending[li]);
    Shift(alpha, fg.nx, fg.ny, op.shift_x, op.shift_y);
    if (op.blur_var_cells2 > 1e-6) Blur(alpha, scratch, fg.nx, fg.ny, op.blur_var_cells2);
    if (has_fix) ResampleAt(factor[layer.floor_index].factor, layer_factor, scratch, fg.nx, fg.ny, op.rx / c, op.ry / c);
    const double sum = MultiplyAndSum(alpha, fg.wall_factor, has_fix ? layer_factor.data() : nullptr, fg.nx, fg.ny);
    if (!(sum > 0)) {
      s.dead[li] = 1;
      std::vector<float>().swap(alpha);
      return;
    }
    NormaliseAndFlush(alpha, 1.0 / sum);
    s.log_z[li] += std::log(sum) + (has_fix ? factor[layer.floor_index].log_scale : 0.0);
    // The batch's moments: with spatial medians asked, through the block summaries (double sums).
    double* blocks = nullptr;
    if (o.spatial_median) {
      block_sums.assign(static_cast<std::size_t>((fg.nx + q - 1) / q) * ((fg.ny + q - 1) / q) * 3, 0.0);
      blocks = block_sums.data();
    }
    const Moments mo = GridMoments(alpha.data(), nullptr, fg, c, q, blocks);
    s.estimate[li] = FilteredLayerEstimate(mo, op, c);
    s.estimate[li].log_evidence = s.log_z[li];
  });
  s.pending_fixes.erase(s.pending_fixes.begin(), s.pending_fixes.begin() + static_cast<std::ptrdiff_t>(n_used));
  s.summary.fixes += static_cast<int>(n_used);
  s.summary.dead_layers = 0;
  for (char d : s.dead) s.summary.dead_layers += d;
  if (s.summary.dead_layers == n_layers) {
    s.failed = true;
    throw std::runtime_error(
        "indoorloc: GridFilterSession: every hypothesis was ruled out (hard walls with no walkable continuation "
        "of the steps, or a known start inside an obstacle): use a finite options.wall_log_penalty");
  }

  // Combine the layers as the batch does at one step: weights from prior x evidence, the mixture's
  // moments, the floor and heading-offset posteriors.
  std::vector<double> w(n_layers, 0.0);
  double mx = -std::numeric_limits<double>::infinity();
  for (int l = 0; l < n_layers; ++l)
    if (!s.dead[l]) mx = std::max(mx, layers[l].log_prior + s.estimate[l].log_evidence);
  double total = 0;
  for (int l = 0; l < n_layers; ++l)
    if (!s.dead[l]) total += w[l] = std::exp(layers[l].log_prior + s.estimate[l].log_evidence - mx);
  for (double& v : w) v /= total;
  double m_x = 0, m_y = 0, sxx = 0, sxy = 0, syy = 0;
  for (int l = 0; l < n_layers; ++l) {
    if (w[l] <= 0) continue;
    const LayerStep& le = s.estimate[l];
    m_x += w[l] * le.mx;
    m_y += w[l] * le.my;
    sxx += w[l] * (le.cxx + le.mx * le.mx);
    sxy += w[l] * (le.cxy + le.mx * le.my);
    syy += w[l] * (le.cyy + le.my * le.my);
  }
  e.mean_m << m_x, m_y;
  e.posterior_covariance_m2 << sxx - m_x * m_x, sxy - m_x * m_y, syy - m_y * m_y;
  // The batch's calibration (grid_ops.h CalibratedCovariance, from the latest fix as the batch's
  // filter measures it).
  const Eigen::Vector2d m = e.mean_m;
  e.fix_distance_m = s.has_fix_centre ? (m - s.fix_centre).norm() : 0.0;
  e.fix_sd_m = s.has_fix_centre ? s.fix_sd : 0.0;
  e.covariance_m2 = CalibratedCovariance(e.posterior_covariance_m2, e.fix_distance_m, e.fix_sd_m,
                                         o.filtered_covariance_scale, o.filtered_covariance_floor_m,
                                         o.filtered_covariance_fix_gain, o.filtered_covariance_fix_sd_gain,
                                         o.covariance_fix_sd_knee_m);
  e.floor_probabilities = Eigen::VectorXd::Zero(n_floors);
  double cs = 0, sn = 0;
  for (int l = 0; l < n_layers; ++l) {
    e.floor_probabilities[layers[l].floor_index] += w[l];
    cs += w[l] * std::cos(s.layer_set.offsets[layers[l].offset_bin]);
    sn += w[l] * std::sin(s.layer_set.offsets[layers[l].offset_bin]);
  }
  e.heading_offset_rad = std::atan2(sn, cs);
  e.log_evidence = mx + std::log(total);
  e.fixes = s.summary.fixes;
  e.located = s.start.known || e.fixes > 0;
  s.summary.log_evidence = e.log_evidence;
  s.summary.seconds += timer.ElapsedSeconds();
  return e;
}

GridFilterEstimate GridFilterSession::Estimate() const {
  if (state_->steps == 0) throw std::logic_error("indoorloc: GridFilterSession::Estimate: no step added yet");
  return state_->current;
}

int GridFilterSession::steps() const { return state_->steps; }
int GridFilterSession::pending_fixes() const { return static_cast<int>(state_->pending_fixes.size()); }
double GridFilterSession::latest_time_s() const { return std::max(state_->last_step_time, state_->last_fix_time); }
GridTrackSummary GridFilterSession::Summary() const { return state_->summary; }
const GridTracker& GridFilterSession::tracker() const { return *state_->tracker; }
std::vector<int> GridFilterSession::floors() const { return state_->tracker->impl_->plan->floors(); }

}  // namespace indoorloc::fusion
