// Conversion of the fusion subsystem's Python arguments (fusion_args.h).
#include "fusion_args.h"

#include <cmath>
#include <string>

#include <pybind11/eigen.h>

#include "indoorloc/core/validate.h"
#include "numpy_args.h"

namespace indoorloc::bindings {

using namespace indoorloc::fusion;  // NOLINT: binding file

// Steps from arrays: times (M), displacements (M, 2), covariances (M, 3) = (xx, xy, yy).
std::vector<StepInput> StepsFromArrays(const py::object& times_s, const py::object& displacements_m,
                                       const py::object& covariances_m2) {
  VectorArg t = ToVector(times_s, "step_times_s");
  MatrixArg d = ToMatrix(displacements_m, "displacements_m", t.map.size(), 2);
  MatrixArg c = ToMatrix(covariances_m2, "covariances_m2", t.map.size(), 3);
  std::vector<StepInput> steps(static_cast<size_t>(t.map.size()));
  // The rules of CheckStepInput, named by the array the user passed (it names "steps[k]").
  for (Eigen::Index k = 1; k < t.map.size(); ++k) {
    if (t.map[k] < t.map[k - 1]) {
      ThrowInvalidArgument("step_times_s", "must be non-decreasing: entry " + std::to_string(k) + " = " +
                                               FormatValue(t.map[k]) + " < " + FormatValue(t.map[k - 1]));
    }
  }
  for (Eigen::Index k = 0; k < t.map.size(); ++k) {
    if (d.map.row(k).norm() > 100.0) {
      ThrowInvalidArgument("displacements_m", "row " + std::to_string(k) + " is longer than 100 m (not a step), got " +
                                                  FormatValue(d.map.row(k).norm()) + " m");
    }
    const double xx = c.map(k, 0), xy = c.map(k, 1), yy = c.map(k, 2);
    if (!(std::abs(xx) <= 1e4 && std::abs(xy) <= 1e4 && std::abs(yy) <= 1e4 && xx >= 0.0 && yy >= 0.0 &&
          xx * yy - xy * xy >= -1e-12 * std::max(1.0, xx * yy))) {
      ThrowInvalidArgument("covariances_m2", "row " + std::to_string(k) +
                                                 " (xx, xy, yy) must be a positive semi-definite covariance with "
                                                 "entries within +-1e4 m^2");
    }
  }
  for (Eigen::Index k = 0; k < t.map.size(); ++k) {
    StepInput& s = steps[static_cast<size_t>(k)];
    s.time_s = t.map[k];
    s.displacement_m = d.map.row(k).transpose();
    s.covariance_m2 << c.map(k, 0), c.map(k, 1), c.map(k, 1), c.map(k, 2);
    CheckStepInput(s, ("steps[" + std::to_string(k) + "]").c_str());
  }
  return steps;
}

// Position fixes from arrays: times (F,), means (F, 2K) = per fix K (x, y) pairs, sds (F, K),
// weights (F, K), floors (F, K) per component (PositionFix::kAnyFloor = any). Components of weight 0 are padding
// and dropped (their mean and sd may be NaN), so fixes may have different component counts.
std::vector<PositionFix> FixesFromArrays(const py::tuple& arrays) {
  if (arrays.size() != 5) ThrowInvalidArgument("fixes", "must be (times_s, means_m, sds_m, weights, floors)");
  VectorArg t = ToVector(arrays[0], "fixes.times_s");
  const Eigen::Index f = t.map.size();
  MatrixArg sds = ToMatrix(arrays[2], "fixes.sds_m", f);
  const Eigen::Index k = sds.map.cols();
  MatrixArg means = ToMatrix(arrays[1], "fixes.means_m", f, 2 * k);
  MatrixArg weights = ToMatrix(arrays[3], "fixes.weights", f, k);
  MatrixArg floors = ToMatrix(arrays[4], "fixes.floors", f, k);
  std::vector<PositionFix> out(static_cast<size_t>(f));
  Eigen::VectorXi component_floors(k);
  for (Eigen::Index i = 0; i < f; ++i) {
    for (Eigen::Index j = 0; j < k; ++j) {
      const double fl = floors.map(i, j);
      if (weights.map(i, j) != 0.0 && (fl != std::floor(fl) || std::abs(fl) > 2e9)) {
        ThrowInvalidArgument("fixes.floors", "entry (" + std::to_string(i) + ", " + std::to_string(j) + ") is not an integer");
      }
      component_floors[j] = weights.map(i, j) != 0.0 ? static_cast<int>(fl) : PositionFix::kAnyFloor;
    }
    // Row i holds K (x, y) pairs: a K x 2 row-major block.
    const Eigen::Map<const PositionFix::Means> candidates(means.map.data() + i * 2 * k, k, 2);
    out[static_cast<size_t>(i)] = FixFromCandidates(t.map[i], candidates, sds.map.row(i).transpose(),
                                                    weights.map.row(i).transpose(), component_floors);
    CheckPositionFix(out[static_cast<size_t>(i)], ("fixes[" + std::to_string(i) + "]").c_str());
  }
  return out;
}

// A real number given to a dict entry or a tuple (pybind11's own cast would raise RuntimeError
// "Unable to cast Python instance ..."): finite, named.
double ToFiniteDouble(const py::handle& obj, const std::string& name) {
  if (py::isinstance<py::bool_>(obj) || !(py::isinstance<py::float_>(obj) || py::isinstance<py::int_>(obj) ||
                                         py::hasattr(obj, "__float__")) || py::isinstance<py::str>(obj)) {
    ThrowInvalidArgument(name, "expected a real number, got " + std::string(Py_TYPE(obj.ptr())->tp_name));
  }
  if (PyComplex_Check(obj.ptr())) ThrowInvalidArgument(name, "expected a real number, got complex");
  const double v = PyFloat_AsDouble(obj.ptr());
  if (v == -1.0 && PyErr_Occurred()) {
    PyErr_Clear();
    ThrowInvalidArgument(name, "expected a real number");
  }
  RequireFinite(v, name);
  return v;
}

// The known start of track(): {"position_m": (2,), "floor": int, "heading_offset_rad": float,
// "time_s": float}; unknown keys are refused (a misspelt key would otherwise be ignored).
TrackStart StartFromDict(const py::object& start, double first_step_time_s) {
  TrackStart st;
  if (start.is_none()) return st;
  if (!py::isinstance<py::dict>(start)) {
    ThrowInvalidArgument("start", "expected None or a dict with position_m, floor, heading_offset_rad, time_s; got " +
                                      std::string(Py_TYPE(start.ptr())->tp_name));
  }
  const py::dict s = start.cast<py::dict>();
  for (const auto& item : s) {
    const std::string key = py::str(item.first);
    if (key != "position_m" && key != "floor" && key != "heading_offset_rad" && key != "time_s") {
      ThrowInvalidArgument("start", "unknown key '" + key + "' (expected position_m, floor, heading_offset_rad, time_s)");
    }
  }
  if (!s.contains("position_m")) ThrowInvalidArgument("start", "a known start needs 'position_m'");
  st.known = true;
  VectorArg p = ToVector(s["position_m"], "start['position_m']", 2);
  RequireAllInRange(p.map, -kMaxScale, kMaxScale, "start['position_m']");
  st.position_m = p.map;
  st.time_s = s.contains("time_s") ? ToFiniteDouble(s["time_s"], "start['time_s']") : first_step_time_s;
  st.floor = s.contains("floor") ? ToInt(s["floor"], "start['floor']", -1000000, 1000000) : 0;
  st.heading_offset_rad =
      s.contains("heading_offset_rad") ? ToFiniteDouble(s["heading_offset_rad"], "start['heading_offset_rad']") : 0.0;
  return st;
}

}  // namespace indoorloc::bindings
