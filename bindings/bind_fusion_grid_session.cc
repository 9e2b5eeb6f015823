// Python bindings of the grid filter session (fusion/grid_filter_session.h): the grid tracker's
// forward filter one event at a time, numpy in and out, the GIL released around the C++ work.
#include <cmath>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/fusion/grid_filter_session.h"
#include "fusion_args.h"
#include "numpy_args.h"

namespace indoorloc::bindings {

using namespace indoorloc::fusion;  // NOLINT: binding file

namespace {


// One fix as the one-row tuple FixesFromArrays takes (the batch's own conversion and checks).
PositionFix OneFix(const py::object& time_s, const py::object& means_m, const py::object& sds_m,
                   const py::object& weights, const py::object& floors) {
  const py::module_ np = py::module_::import("numpy");
  const py::object sds = np.attr("asarray")(sds_m, "float64").attr("reshape")(1, -1);
  const py::ssize_t k = sds.attr("shape").cast<py::tuple>()[1].cast<py::ssize_t>();
  const py::object w = weights.is_none() ? np.attr("ones")(py::make_tuple(1, k))
                                         : np.attr("asarray")(weights, "float64").attr("reshape")(1, -1);
  const py::object fl = floors.is_none() ? np.attr("full")(py::make_tuple(1, k), PositionFix::kAnyFloor, "float64")
                                         : np.attr("asarray")(floors, "float64").attr("reshape")(1, -1);
  const py::tuple arrays = py::make_tuple(np.attr("atleast_1d")(np.attr("asarray")(time_s, "float64")),
                                          np.attr("asarray")(means_m, "float64").attr("reshape")(1, -1), sds, w, fl);
  std::vector<PositionFix> fx = FixesFromArrays(arrays);
  if (fx.size() != 1) ThrowInvalidArgument("time_s", "expected one time (a single fix)");
  return fx.front();
}

}  // namespace

void BindFusionGridSession(py::module_& m) {
  py::class_<GridFilterSession>(m, "GridFilterSession", R"doc(
The grid tracker's forward filter run live, one event at a time (docs/fusion.md, "Live
tracking"). After each step its estimate equals ``GridTracker.run``'s causal filter output at that
step, bit for bit, for the same steps and fixes (fixes in time order, each added before the first
step at or after its time). Keeps a reference to the tracker; one session per walk.

``GridFilterSession(tracker, start=None)``: start None (unknown) or {"position_m", "floor",
"heading_offset_rad", "time_s"} as for ``GridTracker.run``. Events out of time order raise
ValueError naming the event and both times; the session is then unchanged.)doc")
      .def(py::init([](const GridTracker* tracker, const py::object& start) {
             if (tracker == nullptr) ThrowInvalidArgument("tracker", "must be a GridTracker, got None");
             const TrackStart st = StartFromDict(start, 0.0);
             if (st.known && (start.cast<py::dict>().contains("time_s") == false)) {
               ThrowInvalidArgument("start", "a known start of a live session needs 'time_s'");
             }
             py::gil_scoped_release release;
             return new GridFilterSession(tracker, st);
           }),
           py::arg("tracker"), py::arg("start") = py::none(), py::keep_alive<1, 2>())
      .def(
          "add_fix",
          [](GridFilterSession& s, const py::object& time_s, const py::object& means_m, const py::object& sds_m,
             const py::object& weights, const py::object& floors) {
            const PositionFix fix = OneFix(time_s, means_m, sds_m, weights, floors);
            py::gil_scoped_release release;
            s.AddFix(fix);
          },
          py::arg("time_s"), py::arg("means_m"), py::arg("sds_m"), py::arg("weights") = py::none(),
          py::arg("floors") = py::none(), R"doc(
Add a position fix (a Gaussian mixture of K components): time_s [s], means_m (K, 2) [m], sds_m (K,)
[m], weights (K,) (default equal), floors (K,) floor numbers (default: any floor). Applied at the
first step with time >= time_s. ValueError for a malformed fix, or one before the previous fix or
not after the latest step.)doc")
      .def(
          "add_fixes",
          [](GridFilterSession& s, const py::tuple& arrays) {
            const std::vector<PositionFix> fx = FixesFromArrays(arrays);
            py::gil_scoped_release release;
            for (const PositionFix& f : fx) s.AddFix(f);
          },
          py::arg("fixes"),
          "Add several fixes in time order: indoorloc.fusion.Fixes.as_arrays() (stops at the first refused).")
      .def(
          "add_step",
          [](GridFilterSession& s, const py::object& time_s, const py::object& displacement_m,
             const py::object& covariance_m2) {
            const py::module_ np = py::module_::import("numpy");
            const std::vector<StepInput> st =
                StepsFromArrays(np.attr("atleast_1d")(np.attr("asarray")(time_s, "float64")),
                                np.attr("asarray")(displacement_m, "float64").attr("reshape")(1, 2),
                                np.attr("asarray")(covariance_m2, "float64").attr("reshape")(1, 3));
            if (st.size() != 1) ThrowInvalidArgument("time_s", "expected one time (a single step)");
            py::gil_scoped_release release;
            return s.AddStep(st.front());
          },
          py::arg("time_s"), py::arg("displacement_m"), py::arg("covariance_m2"), R"doc(
Add a step: time_s [s], displacement_m (2,) [m] in the PDR frame, covariance_m2 (3,) = (xx, xy, yy)
[m²]; applies the pending fixes with time <= time_s. Returns the estimate after it: a GridFilterEstimate with
time_s, steps, mean_m (2,) [m], covariance_m2 (3,) [m²] (calibrated as GridTracker.run's),
posterior_covariance_m2 (3,), fix_distance_m, fix_sd_m, floor_probabilities (F,), heading_offset_rad,
log_evidence, fixes (applied so far), located (a known start or a fix applied: else the unknown start's
prior, not a position). ValueError for a step before the previous step or fix;
RuntimeError when every hypothesis is ruled out (hard walls).)doc")
      .def(
          "add_steps",
          [](GridFilterSession& s, const py::object& times_s, const py::object& displacements_m,
             const py::object& covariances_m2) {
            const std::vector<StepInput> st = StepsFromArrays(times_s, displacements_m, covariances_m2);
            const Eigen::Index m = static_cast<Eigen::Index>(st.size());
            RowMatrixXd mean(m, 2), cov(m, 3), posterior(m, 3), floors;
            Eigen::VectorXd heading(m);
            std::vector<bool> located(static_cast<std::size_t>(m));
            {
              py::gil_scoped_release release;
              for (Eigen::Index k = 0; k < m; ++k) {
                const GridFilterEstimate e = s.AddStep(st[static_cast<std::size_t>(k)]);
                if (k == 0) floors.resize(m, e.floor_probabilities.size());
                mean.row(k) = e.mean_m.transpose();
                cov.row(k) = e.covariance_m2.transpose();
                posterior.row(k) = e.posterior_covariance_m2.transpose();
                floors.row(k) = e.floor_probabilities.transpose();
                heading[k] = e.heading_offset_rad;
                located[static_cast<std::size_t>(k)] = e.located;
              }
            }
            py::dict d;
            d["mean_m"] = mean;
            d["covariance_m2"] = cov;
            d["posterior_covariance_m2"] = posterior;
            d["floor_probabilities"] = floors;
            d["heading_offset_rad"] = heading;
            py::array_t<bool> located_out(static_cast<py::ssize_t>(m));
            for (Eigen::Index k = 0; k < m; ++k) located_out.mutable_at(k) = located[static_cast<std::size_t>(k)];
            d["located"] = located_out;
            return d;
          },
          py::arg("step_times_s"), py::arg("displacements_m"), py::arg("covariances_m2"),
          "Add several steps (arrays as GridTracker.run); returns per step mean_m (M, 2), covariance_m2 (M, 3), "
          "floor_probabilities (M, F), heading_offset_rad (M,), located (M,) bool (GridFilterEstimate.located).")
      .def(
          "estimate",
          [](const GridFilterSession& s) -> py::object {
            if (s.steps() == 0) return py::none();
            return py::cast(s.Estimate());
          },
          "The estimate after the latest step (a GridFilterEstimate, as add_step returns), None before the first step.")
      .def_property_readonly("steps", &GridFilterSession::steps, "Steps added.")
      .def_property_readonly("floors", &GridFilterSession::floors,
                             "Floor numbers of the plan, the order of floor_probabilities.")
      .def_property_readonly("pending_fixes", &GridFilterSession::pending_fixes,
                             "Fixes waiting for a step at or after their time.")
      .def_property_readonly("latest_time_s", &GridFilterSession::latest_time_s,
                             "Latest event time [s] (-inf before the first).")
      .def_property_readonly("summary", &GridFilterSession::Summary, "GridTrackSummary of the session so far.");
}

}  // namespace indoorloc::bindings
