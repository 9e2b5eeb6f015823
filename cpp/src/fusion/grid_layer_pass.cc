// One layer of the grid tracker's batch run: the forward filter over the steps and the
// forward-backward smoother (grid_tracker.h for the model, grid_run.h for the run's pieces).
// A layer (floor, heading-offset bin, scale bin) is an independent hidden Markov model on its
// floor's cells; its forward grid alpha is filtered step by step, and the backward pass runs
// beta_{k-1} = Shift_kᵀ Blur_k (E_k ⊙ beta_k) with gamma_k ∝ alpha_k ⊙ beta_k.
#include <algorithm>
#include <cmath>

#include "grid_run.h"

namespace indoorloc::fusion::grid_run {

using namespace grid_ops;  // NOLINT: the operators shared with the streaming session

namespace {

class LayerPass {
 public:
  LayerPass(const RunPlan& plan, int layer_index, StoreBuffer* store, LayerRun* out)
      : p_(plan),
        o_(plan.impl->options),
        layer_(plan.layer_set.layers[layer_index]),
        fg_(plan.impl->grids[layer_.floor_index]),
        c_(o_.cell_size_m),
        n_(fg_.size()),
        store_(store),
        out_(out),
        layer_factor_(out->fix_factors) {
    const double off = p_.layer_set.offsets[layer_.offset_bin];
    sc_ = p_.layer_set.scales[layer_.scale_bin];
    co_ = std::cos(off);
    so_ = std::sin(off);
  }

  void Run() {
    out_->Clear();
    out_->filtered.assign(p_.m_steps, LayerStep());
    if (p_.smooth) out_->smoothed.assign(p_.m_steps, LayerStep());
    if (!StartPrior()) {
      out_->dead = true;
      return;
    }
    ops_.resize(p_.m_steps);
    if (layer_factor_.size() < static_cast<std::size_t>(p_.m_steps)) layer_factor_.resize(p_.m_steps);
    nb_ = p_.BlocksOf(layer_.floor_index);
    if (o_.spatial_median) {
      block_sums_.resize(nb_ * 3);
      if (p_.filtered) out_->filtered_blocks.assign(static_cast<std::size_t>(p_.m_steps) * nb_ * 3, 0.0f);
      if (p_.smooth) out_->smoothed_blocks.assign(static_cast<std::size_t>(p_.m_steps) * nb_ * 3, 0.0f);
    }
    if (!Filter()) {
      out_->dead = true;
      return;
    }
    if (p_.smooth) Smooth();
  }

 private:
  // Prior: uniform over the walkable cells, or a Gaussian around the known start; false when
  // nothing is left (a known start entirely inside obstacles with hard walls).
  bool StartPrior() {
    scratch_.resize(n_);
    FillStartPrior(fg_, *p_.start, o_.start_position_sd_m, c_, &alpha_);
    for (std::size_t i = 0; i < n_; ++i) alpha_[i] *= fg_.wall_factor[i];
    double s = 0;
    for (float v : alpha_) s += v;
    if (!(s > 0)) return false;
    for (float& v : alpha_) v = static_cast<float>(v / s);
    if (p_.window) {
      windows_.resize(static_cast<std::size_t>(p_.m_steps) + 1);
      windows_[p_.k0] = NonzeroExtent(alpha_, fg_.nx, fg_.ny, CellWindow::Full(fg_.nx, fg_.ny));
    }
    return true;
  }

  // One forward step; false when the layer dies. `ops_[k]` is filled on the first pass
  // (record) and replayed on recomputation, so both passes are identical.
  bool Forward(int k, bool record) {
    StepOps& op = ops_[k];
    if (record) {
      op = PlanStep((*p_.steps)[k], sc_, co_, so_, c_, o_.position_noise_m, p_.layer_set.bin_width, p_.has_fix(k),
                    &rx_, &ry_, &pending_);
    }
    // With a window (known start): the step's passes on the cells that can be nonzero (null: all).
    const CellWindow* win = p_.window ? StepWindow(k) : nullptr;
    if (win) {
      ShiftInWindow(alpha_, fg_.nx, shift_window_, op.shift_x, op.shift_y);
    } else {
      Shift(alpha_, fg_.nx, fg_.ny, op.shift_x, op.shift_y);
    }
    if (op.blur_var_cells2 > 1e-6) Blur(alpha_, scratch_, fg_.nx, fg_.ny, op.blur_var_cells2, win);
    const bool has_fix = p_.has_fix(k);
    const grid_ops::TrackerGrids::FixFactor* fix = has_fix ? &p_.factor[k][layer_.floor_index] : nullptr;
    // The smoother's backward pass reads the whole fix factor; the filter alone only the window's.
    if (has_fix && record) {
      ResampleAt(fix->factor, layer_factor_[k], scratch_, fg_.nx, fg_.ny, op.rx / c_, op.ry / c_,
                 p_.smooth ? nullptr : win);
    }
    const double s =
        MultiplyAndSum(alpha_, fg_.wall_factor, has_fix ? layer_factor_[k].data() : nullptr, fg_.nx, fg_.ny, win);
    if (!(s > 0)) return false;
    float* store = record && p_.store_all ? stored_ + static_cast<std::size_t>(k - p_.k0) * n_ : nullptr;
    if (record && !p_.filtered) {
      // No filtered estimate asked: normalise, and the smoother's copy.
      NormaliseAndFlush(alpha_, 1.0 / s, fg_.nx, win);
      if (store) std::copy(alpha_.begin(), alpha_.end(), store);
    } else if (record && !o_.spatial_median) {
      // The filtered estimate (and the smoother's copy) in the normalising pass; with a window the
      // copy of the whole grid after it (zero outside the window).
      filtered_moments_ = NormaliseMomentsAndStore(alpha_, 1.0 / s, fg_, c_, win ? nullptr : store, win);
      if (win && store) std::copy(alpha_.begin(), alpha_.end(), store);
    } else {
      NormaliseAndFlush(alpha_, 1.0 / s, fg_.nx, win);
      if (record) filtered_moments_ = GridMoments(alpha_.data(), nullptr, fg_, c_, p_.q, BlockSums());
    }
    if (record) log_z_ += std::log(s) + (has_fix ? fix->log_scale : 0.0);
    // The nonzero cells after the step (the flush leaves the posterior's support small).
    if (win && record) windows_[k + 1] = NonzeroExtent(alpha_, fg_.nx, fg_.ny, *win);
    return true;
  }

  // Known start, step k: from the window of the nonzero cells before it (windows_[k]), the window
  // its shift moves within (shift_window_) and the one its blur can reach (returned), clipped to
  // the grid (grid_window.h).
  const CellWindow* StepWindow(int k) {
    const StepOps& op = ops_[k];
    const CellWindow& before = windows_[k];
    const CellWindow moved = MovedWindow(before, op.shift_x, op.shift_y, 0, fg_.nx, fg_.ny);
    shift_window_ = CellWindow{std::min(before.x0, moved.x0), std::max(before.x1, moved.x1),
                               std::min(before.y0, moved.y0), std::max(before.y1, moved.y1)};
    const int grow = op.blur_var_cells2 > 1e-6 ? KernelRadius(op.blur_var_cells2) : 0;
    step_window_ = MovedWindow(before, op.shift_x, op.shift_y, grow, fg_.nx, fg_.ny);
    return &step_window_;
  }

  // The block sums, zeroed, when spatial medians are asked, else null.
  double* BlockSums() {
    if (!o_.spatial_median) return nullptr;
    std::fill(block_sums_.begin(), block_sums_.end(), 0.0);
    return block_sums_.data();
  }

  // Stores the step's block summaries (spatial medians) from block_sums_ and the moments' mass.
  void StoreBlocks(std::vector<float>* blocks, double mass, int k) {
    if (!(mass > 0)) return;
    float* out = blocks->data() + static_cast<std::size_t>(k) * nb_ * 3;
    for (std::size_t b = 0; b < nb_; ++b) {
      const double m = block_sums_[3 * b];
      if (!(m > 0)) continue;
      out[3 * b] = static_cast<float>(m / mass);
      out[3 * b + 1] = static_cast<float>(fg_.x0 + (block_sums_[3 * b + 1] / m + 0.5) * c_ + ops_[k].rx);
      out[3 * b + 2] = static_cast<float>(fg_.y0 + (block_sums_[3 * b + 2] / m + 0.5) * c_ + ops_[k].ry);
    }
  }

  // The smoother's estimate at step k from alpha ⊙ beta; with spatial medians also the step's
  // block summaries.
  LayerStep SmoothedEstimate(const float* alpha, const std::vector<float>& beta, int k) {
    // alpha is zero outside its window (known start): the product too.
    const CellWindow* win = p_.window ? &windows_[k + 1] : nullptr;
    const Moments mo = GridMoments(alpha, beta.data(), fg_, c_, p_.q, BlockSums(), false, win);
    if (!(mo.mass > 0)) {
      // alpha and beta share no cell (each is flushed below 1e-30 of its scale): what the walk
      // says before step k and after it cannot be joined by the motion model (steps lost, a fix
      // far off). The product has no estimate; the filtered one stands in, and the run says so
      // (GridTrackSummary::smoother_gap_steps) rather than returning the grid's origin.
      out_->smoother_gaps.push_back(k);
      // Without the filtered estimates, that of step k (and its blocks) from the forward grid:
      // the forward pass's own operations on the same grid, so the same bits as a full run's.
      if (!p_.filtered) {
        const Moments mo_f = GridMoments(alpha, nullptr, fg_, c_, p_.q, BlockSums());
        if (o_.spatial_median) StoreBlocks(&out_->smoothed_blocks, mo_f.mass, k);
        const double log_evidence = out_->filtered[k].log_evidence;
        out_->filtered[k] = FilteredLayerEstimate(mo_f, ops_[k], c_);
        out_->filtered[k].log_evidence = log_evidence;
        return out_->filtered[k];
      }
      if (o_.spatial_median) {
        const std::size_t off = static_cast<std::size_t>(k) * nb_ * 3;
        std::copy(out_->filtered_blocks.begin() + static_cast<std::ptrdiff_t>(off),
                  out_->filtered_blocks.begin() + static_cast<std::ptrdiff_t>(off + nb_ * 3),
                  out_->smoothed_blocks.begin() + static_cast<std::ptrdiff_t>(off));
      }
      return out_->filtered[k];
    }
    if (o_.spatial_median) StoreBlocks(&out_->smoothed_blocks, mo.mass, k);
    // Positions of the layer are cell centres + the remainder; within-cell spread c²/12.
    return FilteredLayerEstimate(mo, ops_[k], c_);
  }

  // The forward pass over every step: filtered estimates, and what the smoother needs (every
  // grid in the store, or the checkpoints before each segment). False when the layer dies.
  bool Filter() {
    const int k0 = p_.k0;
    if (p_.store_all) stored_ = store_->Reserve(static_cast<std::size_t>(p_.m_steps - k0) * n_);
    for (int k = k0; k < p_.m_steps; ++k) {
      if (p_.smooth && !p_.store_all && (k - k0) % p_.segment == 0) checkpoints_.push_back(alpha_);
      if (!Forward(k, true)) return false;
      if (!p_.filtered) {
        out_->filtered[k].log_evidence = log_z_;
        continue;
      }
      if (o_.spatial_median) {
        StoreBlocks(&out_->filtered_blocks, filtered_moments_.mass, k);
        if (p_.store_all) {
          std::copy(alpha_.begin(), alpha_.end(), stored_ + static_cast<std::size_t>(k - k0) * n_);
        }
      }
      out_->filtered[k] = FilteredLayerEstimate(filtered_moments_, ops_[k], c_);
      out_->filtered[k].log_evidence = log_z_;
    }
    if (p_.store_all) checkpoints_.emplace_back();  // one segment, nothing to recompute
    return true;
  }

  // Backward: per segment (last first) recompute alpha from its checkpoint, then the smoothed
  // estimate from alpha ⊙ beta and beta one step back.
  void Smooth() {
    const int k0 = p_.k0;
    std::vector<float> beta(n_, 1.0f);
    std::vector<std::vector<float>> seg_alpha;
    const int n_seg = static_cast<int>(checkpoints_.size());
    for (int sidx = n_seg - 1; sidx >= 0; --sidx) {
      const int k_begin = k0 + sidx * p_.segment, k_end = std::min(p_.m_steps, k_begin + p_.segment);
      if (!p_.store_all) {
        alpha_ = checkpoints_[sidx];
        seg_alpha.clear();
        for (int k = k_begin; k < k_end; ++k) {
          Forward(k, false);
          seg_alpha.push_back(alpha_);
        }
      }
      for (int k = k_end - 1; k >= k_begin; --k) {
        const float* a = p_.store_all ? stored_ + static_cast<std::size_t>(k - k0) * n_ : seg_alpha[k - k_begin].data();
        out_->smoothed[k] = SmoothedEstimate(a, beta, k);
        BackwardStep(k, &beta);
      }
    }
  }

  // beta_{k-1} from beta_k, rescaled by its maximum.
  void BackwardStep(int k, std::vector<float>* beta) {
    Multiply(*beta, fg_.wall_factor, p_.has_fix(k) ? layer_factor_[k].data() : nullptr);
    if (ops_[k].blur_var_cells2 > 1e-6) Blur(*beta, scratch_, fg_.nx, fg_.ny, ops_[k].blur_var_cells2);
    Shift(*beta, fg_.nx, fg_.ny, -ops_[k].shift_x, -ops_[k].shift_y);
    // Rescale by the maximum.
    const float mx = MaxOf(*beta);
    if (mx > 0) NormaliseAndFlush(*beta, 1.0 / static_cast<double>(mx));
  }

  const RunPlan& p_;
  const GridTrackerOptions& o_;
  const GridLayer& layer_;
  const FloorGrid& fg_;
  const double c_;
  const std::size_t n_;
  StoreBuffer* store_;
  float* stored_ = nullptr;                         // the store's grids (store_all), step k0 first
  LayerRun* out_;
  double sc_ = 1, co_ = 1, so_ = 0;                 // the layer's scale and offset (cos, sin)
  double log_z_ = 0, rx_ = 0, ry_ = 0, pending_ = 0;  // evidence, remainder [m], pending variance [m²]
  std::size_t nb_ = 0;                              // spatial-median blocks of the floor
  std::vector<float> alpha_, scratch_;
  std::vector<StepOps> ops_;
  // Known start (p_.window): per step the window holding every nonzero cell before it (entry
  // m_steps: after the last), and the current step's windows (StepWindow).
  std::vector<CellWindow> windows_;
  CellWindow shift_window_, step_window_;
  // Fix factors at the layer's positions, per step with a fix (entries of other steps are stale,
  // never read; the slot's vectors are reused across runs).
  std::vector<std::vector<float>>& layer_factor_;
  std::vector<double> block_sums_;
  Moments filtered_moments_;                        // of the latest recorded forward step
  std::vector<std::vector<float>> checkpoints_;     // alpha before steps k0, k0 + segment, ...
};

}  // namespace

void RunLayer(const RunPlan& plan, int layer_index, StoreBuffer* store, LayerRun* out) {
  LayerPass(plan, layer_index, store, out).Run();
}

}  // namespace indoorloc::fusion::grid_run
