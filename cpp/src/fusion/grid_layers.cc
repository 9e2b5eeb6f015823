// The grid tracker's layer set (grid_run.h): one layer per floor in use x heading-offset bin x
// stride-scale bin, each with its log prior (floor: its share of the walkable area for an unknown
// start; offset and scale: the Gaussian priors of GridTrackerOptions), normalised over the layers.
// Shared by the batch run and the streaming session (grid_ops.h).
#include <cmath>
#include <limits>

#include "grid_ops.h"

namespace indoorloc::fusion {
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

}  // namespace indoorloc::fusion
