// The fusion trackers' estimates as Python objects (bind_fusion_estimates.cc): TrackerEstimate,
// GridFilterEstimate and the live session's LiveEstimate, which the bindings of the particle
// tracker, the grid filter session and the live session return.
#pragma once

#include <vector>

#include <pybind11/pybind11.h>

#include "indoorloc/fusion/grid_filter_session.h"
#include "indoorloc/fusion/particle_tracker.h"

namespace indoorloc::bindings {

namespace py = pybind11;

/// The live session's estimate: the grid filter's, the plan's floor numbers (the order of
/// grid.floor_probabilities) and the most probable floor's number.
struct LiveEstimate {
  fusion::GridFilterEstimate grid;
  std::vector<int> floors;
  int floor = 0;
};

/// `grid` with the plan's `floors`; floor: the floor of the largest probability (0 without floors).
LiveEstimate MakeLiveEstimate(const fusion::GridFilterEstimate& grid, std::vector<int> floors);

/// Binds TrackerEstimate, GridFilterEstimate and LiveEstimate (before the functions returning them).
void BindFusionEstimates(py::module_& m);

}  // namespace indoorloc::bindings
