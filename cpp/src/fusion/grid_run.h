// Internal to the grid tracker's batch run (not installed): the pieces of GridTracker::Run,
// one concept per file.
//   grid_tracker.cc      the tracker (grid construction) and Run: input checks, the run plan
//                        (fixes attached to steps, fix factors, memory), the layers in parallel
//   grid_layers.cc       the layer set: floors x heading-offset bins x scale bins and their prior
//   grid_layer_pass.cc   one layer's forward filter and forward-backward smoother
//   grid_combine.cc      the layers' mixture per step: means, covariances, floor and offset
//                        posteriors, spatial medians, the covariance calibration
// The model is in cpp/include/indoorloc/fusion/grid_tracker.h; the operators in grid_ops.h.
#pragma once
#include <cstddef>
#include <memory>
#include <vector>

#include "grid_ops.h"

namespace indoorloc::fusion::grid_run {

// What Run decided before the layers run; read-only while they do.
struct RunPlan {
  const grid_ops::TrackerGrids* impl = nullptr;
  const std::vector<StepInput>* steps = nullptr;
  const std::vector<PositionFix>* fixes = nullptr;
  const TrackStart* start = nullptr;
  int start_floor_index = -1;                    // known start: its floor's index
  int m_steps = 0;
  int k0 = 0;                                    // first step after a known start (0: unknown)
  bool smooth = false;
  // Known start: the forward pass runs on the window of the grid holding its nonzero cells
  // (grid_window.h; the same bits as the whole grid's passes).
  bool window = false;
  bool filtered = true;    // the filter's per-step position estimates (always without smoothing)
  grid_ops::GridLayers layer_set;
  std::vector<std::vector<const PositionFix*>> fixes_at;  // per step: the fixes applied there
  int n_fixes = 0;
  // Per step with fixes, per floor in use: the fix factor (shared by the layers of a floor).
  std::vector<std::vector<grid_ops::TrackerGrids::FixFactor>> factor;
  int threads = 1;
  bool store_all = false;  // the smoother keeps every forward grid (else checkpoints)
  int segment = 1;         // steps per checkpointed segment
  int q = 1;               // cells per side of a spatial-median block
  double bytes = 0;        // memory at the peak (the summary's)

  int num_floors() const { return static_cast<int>(impl->grids.size()); }
  bool has_fix(int k) const { return !fixes_at[k].empty(); }
  // Blocks of q x q cells of a floor's grid.
  std::size_t BlocksOf(int floor_index) const {
    const grid_ops::FloorGrid& g = impl->grids[floor_index];
    return static_cast<std::size_t>((g.nx + q - 1) / q) * static_cast<std::size_t>((g.ny + q - 1) / q);
  }
};

// One layer's outputs per step (steps before k0 left default). Reused by later runs
// (grid_tracker.cc, KeptBuffers): RunLayer clears it first, keeping the vectors' memory.
struct LayerRun {
  std::vector<grid_ops::LayerStep> filtered, smoothed;
  // Spatial medians: per step the block summaries (mass fraction, x [m], y [m]), step-major.
  std::vector<float> filtered_blocks, smoothed_blocks;
  bool dead = false;  // every cell ruled out (hard walls)
  // Steps at which alpha ⊙ beta vanished (grid_layer_pass.cc, SmoothedEstimate): the filtered
  // estimate stands in for the smoothed one there.
  std::vector<int> smoother_gaps;
  // Pages of this layer's fix factors (the fix factor resampled at the layer's positions, per step
  // with a fix), kept with the slot so that the next run reuses them.
  std::vector<std::vector<float>> fix_factors;
  void Clear() {
    filtered.clear();
    smoothed.clear();
    filtered_blocks.clear();
    smoothed_blocks.clear();
    smoother_gaps.clear();
    dead = false;
  }
  // Bytes held (capacity).
  double Bytes() const {
    double b = static_cast<double>((filtered.capacity() + smoothed.capacity()) * sizeof(grid_ops::LayerStep) +
                                   (filtered_blocks.capacity() + smoothed_blocks.capacity()) * sizeof(float));
    for (const auto& f : fix_factors) b += static_cast<double>(f.capacity() * sizeof(float));
    return b;
  }
};

// The output slots of a run's layers (reused by later runs: grid_tracker.cc).
struct RunSlots {
  std::vector<LayerRun> runs;
  double Bytes() const {
    double b = static_cast<double>(runs.capacity() * sizeof(LayerRun));
    for (const LayerRun& run : runs) b += run.Bytes();
    return b;
  }
};

// The smoother's stored forward grids (plan.store_all): every entry is written by the forward
// pass before the backward pass reads it, so the buffer is never zero-filled, and one buffer
// serves layers and runs in turn (grid_tracker.cc, KeptBuffers).
class StoreBuffer {
 public:
  // At least n floats (contents unspecified).
  float* Reserve(std::size_t n) {
    if (n > capacity_) {
      data_.reset();  // free before allocating the larger one
      data_.reset(new float[n]);
      capacity_ = n;
    }
    return data_.get();
  }
  std::size_t capacity() const { return capacity_; }
  double Bytes() const { return static_cast<double>(capacity_ * sizeof(float)); }
  void Release() {
    data_.reset();
    capacity_ = 0;
  }

 private:
  std::unique_ptr<float[]> data_;
  std::size_t capacity_ = 0;
};

// Filters (and with plan.smooth smooths) layer `layer_index` into *out. `store` holds the
// smoother's forward grids when plan.store_all.
void RunLayer(const RunPlan& plan, int layer_index, StoreBuffer* store, LayerRun* out);

// The result of the run from its layers runs[0 .. layers) (the summary's counts filled; its
// seconds not).
GridTrackResult CombineLayers(const RunPlan& plan, const std::vector<LayerRun>& runs);

}  // namespace indoorloc::fusion::grid_run
