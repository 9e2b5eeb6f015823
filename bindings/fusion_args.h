// Conversion of the fusion subsystem's Python arguments (steps, position fixes, a known start)
// to their C++ types, shared by the particle tracker's and the grid tracker's bindings. Every
// conversion names the argument the user passed in its ValueError.
#pragma once

#include <string>
#include <vector>

#include <pybind11/pybind11.h>

#include "indoorloc/fusion/position_fix.h"
#include "indoorloc/fusion/step_motion.h"
#include "indoorloc/fusion/track.h"

namespace indoorloc::bindings {

namespace py = pybind11;

/// Steps from arrays: times (M) [s], displacements (M, 2) [m], covariances (M, 3) = (xx, xy, yy) [m²].
std::vector<fusion::StepInput> StepsFromArrays(const py::object& times_s, const py::object& displacements_m,
                                               const py::object& covariances_m2);

/// Position fixes from (times_s (F,), means_m (F, 2K), sds_m (F, K), weights (F, K), floors (F, K));
/// components of weight 0 are padding and dropped.
std::vector<fusion::PositionFix> FixesFromArrays(const py::tuple& arrays);

/// A real number from a dict entry or a tuple: finite, else ValueError naming `name`.
double ToFiniteDouble(const py::handle& obj, const std::string& name);

/// The known start {"position_m", "floor", "heading_offset_rad", "time_s"} or None (unknown start).
fusion::TrackStart StartFromDict(const py::object& start, double first_step_time_s);

}  // namespace indoorloc::bindings
