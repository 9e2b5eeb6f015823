// Python bindings of the grid tracker (fusion/grid_tracker.h): options, summary, the tracker.
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/fusion/grid_tracker.h"
#include "fusion_args.h"
#include "numpy_args.h"
#include "options_binding.h"

namespace indoorloc::bindings {

using namespace indoorloc::fusion;  // NOLINT: binding file

namespace {

py::dict ResultToDict(const GridTrackResult& r) {
  py::dict d;
  d["times_s"] = r.times_s;
  d["mean_m"] = r.filtered_mean_m;
  d["covariance_m2"] = r.filtered_covariance_m2;
  d["posterior_covariance_m2"] = r.filtered_posterior_covariance_m2;
  d["fix_distance_m"] = r.filtered_fix_distance_m;
  d["fix_sd_m"] = r.filtered_fix_sd_m;
  d["floor_probabilities"] = r.filtered_floor_probabilities;
  d["heading_offset_rad"] = r.filtered_heading_offset_rad;
  if (r.filtered_median_m.rows() > 0) d["median_m"] = r.filtered_median_m;
  if (r.smoothed_median_m.rows() > 0) d["smoothed_median_m"] = r.smoothed_median_m;
  if (r.smoothed_mean_m.rows() > 0) {
    d["smoothed_m"] = r.smoothed_mean_m;
    d["smoothed_covariance_m2"] = r.smoothed_covariance_m2;
    d["smoothed_posterior_covariance_m2"] = r.smoothed_posterior_covariance_m2;
    d["smoothed_fix_distance_m"] = r.smoothed_fix_distance_m;
    d["smoothed_fix_sd_m"] = r.smoothed_fix_sd_m;
  }
  d["smoothed_floor_probabilities"] = r.smoothed_floor_probabilities;
  d["heading_offset_bins_rad"] = r.heading_offset_bins_rad;
  d["heading_offset_probabilities"] = r.heading_offset_probabilities;
  d["scale_bins"] = r.scale_bins;
  d["scale_probabilities"] = r.scale_probabilities;
  d["walk_heading_offset_rad"] = r.heading_offset_rad;
  d["walk_heading_offset_sd_rad"] = r.heading_offset_sd_rad;
  d["walk_scale"] = r.scale;
  d["summary"] = r.summary;
  return d;
}

// GridTrackerOptions and GridTrackSummary.
void BindGridOptionsAndSummary(py::module_& m) {
  py::class_<GridTrackerOptions> options(m, "GridTrackerOptions", R"doc(
Options of the grid tracker (docs/fusion.md, "Grid tracker"; each default and how it was chosen
is in cpp/include/indoorloc/fusion/grid_tracker.h). Set fields by keyword:
``GridTrackerOptions(cell_size_m=1.5, wall_log_penalty=-1.0)``; ``replace``, ``to_dict``,
equality and pickling as for every Options class. The fix likelihood's ε and τ are flattened as
``fix_outlier_probability`` and ``fix_tempering``.)doc");
  options.def_readwrite("cell_size_m", &GridTrackerOptions::cell_size_m, "Side of the square cells [m].")
      .def_readwrite("walkable_subsamples", &GridTrackerOptions::walkable_subsamples,
                     "n: a cell's walkable fraction from n x n sub-samples.")
      .def_readwrite("heading_offset_bins", &GridTrackerOptions::heading_offset_bins, "Heading-offset layers.")
      .def_readwrite("heading_offset_sd_rad", &GridTrackerOptions::heading_offset_sd_rad,
                     "Prior sd of the heading offset around the start's [rad]; 0: known.")
      .def_readwrite("heading_offset_span_sd", &GridTrackerOptions::heading_offset_span_sd,
                     "The offset bins span ± this many prior sd (the circle beyond ±π).")
      .def_readwrite("scale_bins", &GridTrackerOptions::scale_bins, "Stride-scale layers (1: scale 1).")
      .def_readwrite("scale_sd", &GridTrackerOptions::scale_sd, "Prior sd of the stride scale.")
      .def_readwrite("position_noise_m", &GridTrackerOptions::position_noise_m, "Process noise per step [m].")
      .def_readwrite("wall_log_penalty", &GridTrackerOptions::wall_log_penalty,
                     "Log-weight per step outside walkable space; -inf: hard walls.")
      .def_readwrite("wall_margin_m", &GridTrackerOptions::wall_margin_m,
                     "Obstacles eroded by this margin [m]: points this close to a wall edge count as walkable.")
      .def_property("fix_outlier_probability", [](const GridTrackerOptions& o) { return o.fix.outlier_probability; },
                    [](GridTrackerOptions& o, double v) { o.fix.outlier_probability = v; }, "ε of the position fixes.")
      .def_property("fix_tempering", [](const GridTrackerOptions& o) { return o.fix.tempering; },
                    [](GridTrackerOptions& o, double v) { o.fix.tempering = v; }, "τ of the position fixes.")
      .def_readwrite("spatial_median", &GridTrackerOptions::spatial_median,
                     "Also return the spatial medians (filtered_median_m, smoothed_median_m).")
      .def_readwrite("median_block_m", &GridTrackerOptions::median_block_m,
                     "Block side of the spatial median's posterior summary [m].")
      .def_readwrite("fix_tempering_by_variance", &GridTrackerOptions::fix_tempering_by_variance,
                     "True: τ divides the fix components' variances (outlier floor kept); false: the "
                     "likelihood to the power τ.")
      .def_readwrite("fix_survey_distance_factor", &GridTrackerOptions::fix_survey_distance_factor,
                     "β: fixes evaluated at s + β (c - s), s the survey position nearest to cell c "
                     "(GridTracker.with_survey_positions); 1: the cell centres.")
      .def_readwrite("survey_walkable_radius_m", &GridTrackerOptions::survey_walkable_radius_m,
                     "Cells within this distance [m] of a survey position (GridTracker.with_survey_positions) "
                     "pay no wall penalty: the surveyors walked there; 0: the plan as drawn.")
      .def_readwrite("survey_walkable_min_walks", &GridTrackerOptions::survey_walkable_min_walks,
                     "A cell is opened only when positions of at least this many distinct survey walks lie "
                     "within survey_walkable_radius_m.")
      .def_readwrite("start_position_sd_m", &GridTrackerOptions::start_position_sd_m, "Known start: sd [m].")
      .def_readwrite("filtered_covariance_scale", &GridTrackerOptions::filtered_covariance_scale,
                     "a of the filter's returned covariance a Σ + (b² + (g d)² + (h max(0, s - s0))²) I.")
      .def_readwrite("filtered_covariance_floor_m", &GridTrackerOptions::filtered_covariance_floor_m,
                     "b [m] of the filter's returned covariance.")
      .def_readwrite("filtered_covariance_fix_gain", &GridTrackerOptions::filtered_covariance_fix_gain,
                     "g of the filter's returned covariance (d: distance to the last fix's centre [m]).")
      .def_readwrite("smoothed_covariance_scale", &GridTrackerOptions::smoothed_covariance_scale,
                     "a of the smoother's returned covariance.")
      .def_readwrite("smoothed_covariance_floor_m", &GridTrackerOptions::smoothed_covariance_floor_m,
                     "b [m] of the smoother's returned covariance.")
      .def_readwrite("smoothed_covariance_fix_gain", &GridTrackerOptions::smoothed_covariance_fix_gain,
                     "g of the smoother's returned covariance (d: distance to the nearest fix's centre [m]).")
      .def_readwrite("filtered_covariance_fix_sd_gain", &GridTrackerOptions::filtered_covariance_fix_sd_gain,
                     "h of the filter's returned covariance: (h max(0, s - s0))² added (s: the last fix's own sd [m]).")
      .def_readwrite("smoothed_covariance_fix_sd_gain", &GridTrackerOptions::smoothed_covariance_fix_sd_gain,
                     "h of the smoother's returned covariance (s: the nearest fix's own sd [m]).")
      .def_readwrite("covariance_fix_sd_knee_m", &GridTrackerOptions::covariance_fix_sd_knee_m,
                     "s0 [m] of the returned covariances: fix sds up to it add nothing.")
      .def_readwrite("max_memory_bytes", &GridTrackerOptions::max_memory_bytes, "Memory limit of a run [bytes].")
      .def_readwrite("num_threads", &GridTrackerOptions::num_threads, "Layers in parallel (<= 0: all cores).");
  BindOptionsProtocol(options, "GridTrackerOptions");

  py::class_<GridTrackSummary>(m, "GridTrackSummary", "What a grid tracker run did.")
      .def_readonly("steps", &GridTrackSummary::steps)
      .def_readonly("fixes", &GridTrackSummary::fixes)
      .def_readonly("layers", &GridTrackSummary::layers)
      .def_readonly("cells", &GridTrackSummary::cells)
      .def_readonly("dead_layers", &GridTrackSummary::dead_layers)
      .def_readonly("smoother_gap_steps", &GridTrackSummary::smoother_gap_steps,
                    "Steps where the smoother had no estimate (the filtered one stands in).")
      .def_readonly("log_evidence", &GridTrackSummary::log_evidence)
      .def_readonly("memory_bytes", &GridTrackSummary::memory_bytes)
      .def_readonly("seconds", &GridTrackSummary::seconds)
      .def("brief_report", &GridTrackSummary::BriefReport)
      .def("__repr__", [](const GridTrackSummary& s) { return "<GridTrackSummary " + s.BriefReport() + ">"; });
}

// GridTracker: construction, derived trackers, runs and the kept-memory pool.
void BindGridTrackerClass(py::module_& m) {
  py::class_<GridTracker>(m, "GridTracker", R"doc(
Exact grid filter and forward-backward smoother of a walk (unknown or known start) on a plan's
floors: cells x heading-offset bins x stride-scale bins (docs/fusion.md, "Grid tracker").
Build once per plan and options (keeps a reference to the plan); ``run`` is thread-safe.)doc")
      .def(py::init([](const FloorPlan* plan, const py::object& options) {
             if (plan == nullptr) ThrowInvalidArgument("plan", "must be a FloorPlan, got None");
             GridTrackerOptions o;
             if (!options.is_none()) {
               if (!py::isinstance<GridTrackerOptions>(options)) {
                 ThrowInvalidArgument("options", "expected None or a GridTrackerOptions, got " +
                                                     std::string(Py_TYPE(options.ptr())->tp_name));
               }
               o = options.cast<GridTrackerOptions>();
             }
             py::gil_scoped_release release;
             return new GridTracker(plan, o);
           }),
           py::arg("plan"), py::arg("options") = py::none(), py::keep_alive<1, 2>())
      .def_property_readonly("options", &GridTracker::options)
      .def("grid_geometry", &GridTracker::GridGeometry, py::arg("floor_index"),
           "(x0, y0, columns, rows): corner of the first cell [m] and the grid's size on a floor.")
      .def("walkable_fraction", &GridTracker::WalkableFraction, py::arg("floor_index"),
           "Walkable fraction of every cell (rows, columns), row 0 at the lowest y.")
      .def("wall_factors", &GridTracker::WallFactors, py::arg("floor_index"),
           "The per-step wall factor of every cell (rows, columns): a + (1 - a) e^λ, 1 where the survey "
           "walked through the cell.")
      .def(
          "fix_log_likelihood",
          [](const GridTracker& t, int floor_index, const py::object& fixes) {
            if (!py::isinstance<py::tuple>(fixes)) {
              ThrowInvalidArgument("fixes", "expected (times_s, means_m, sds_m, weights, floors) "
                                            "(indoorloc.fusion.Fixes.as_arrays()), got " +
                                                std::string(Py_TYPE(fixes.ptr())->tp_name));
            }
            const std::vector<PositionFix> fx = FixesFromArrays(fixes.cast<py::tuple>());
            py::gil_scoped_release release;
            return t.FixLogLikelihood(floor_index, fx);
          },
          py::arg("floor_index"), py::arg("fixes"),
          "log Π_j L_j(c)^τ [nats] of the fixes (Fixes.as_arrays(), all applied together) on every cell "
          "(rows, columns): the factor the tracker applies at a step with them (survey-anchored, the "
          "options' ε and τ, other floors' components ignored).")
      .def(
          "fix_log_likelihoods",
          [](const GridTracker& t, int floor_index, const py::object& fixes, const py::object& group_starts,
             const py::object& cells) {
            if (!py::isinstance<py::tuple>(fixes)) {
              ThrowInvalidArgument("fixes", "expected (times_s, means_m, sds_m, weights, floors) "
                                            "(indoorloc.fusion.Fixes.as_arrays()), got " +
                                                std::string(Py_TYPE(fixes.ptr())->tp_name));
            }
            const std::vector<PositionFix> fx = FixesFromArrays(fixes.cast<py::tuple>());
            const Eigen::VectorXi starts = ToIntVector(group_starts, "group_starts");
            const Eigen::VectorXi at = ToIntVector(cells, "cells");
            py::gil_scoped_release release;
            return t.FixLogLikelihoodGroups(floor_index, fx, starts, at);
          },
          py::arg("floor_index"), py::arg("fixes"), py::arg("group_starts"), py::arg("cells"),
          "fix_log_likelihood of several groups of fixes in one call, read at some cells: group g is fixes "
          "group_starts[g]:group_starts[g + 1] (G + 1 indices from 0 to the number of fixes), cells the "
          "row-major lattice indices (y * nx + x); returns (G, len(cells)) [nats], 0 for an empty group.")
      .def(
          "with_survey_positions",
          [](const GridTracker& t, const py::object& positions_m, const py::object& floor_numbers,
             const py::object& walk_ids) {
            // The project's checked conversions (a ValueError naming the argument for anything that
            // is not a finite (N, 2) array / N integers), not pybind11's Eigen caster.
            const MatrixArg positions = ToMatrix(positions_m, "positions_m", -1, 2);
            const Eigen::VectorXi floors = ToIntVector(floor_numbers, "floor_numbers");
            const Eigen::VectorXi walks = walk_ids.is_none() ? Eigen::VectorXi() : ToIntVector(walk_ids, "walk_ids");
            const RowMatrixXd p = positions.map;
            py::gil_scoped_release release;
            return t.WithSurveyPositions(p, floors, walks);
          },
          py::arg("positions_m"), py::arg("floor_numbers"), py::arg("walk_ids") = py::none(), py::keep_alive<0, 1>(),
          R"doc(
A tracker on the same grids whose fixes are evaluated at survey-anchored positions
(options.fix_survey_distance_factor β) and whose cells near the survey are open
(options.survey_walkable_radius_m): positions_m (N, 2) [m] the survey (fingerprint reference)
positions, floor_numbers (N,) their floors, walk_ids (N,) or None the survey walk of each
(options.survey_walkable_min_walks; None: each position a walk of its own; negative: a position
that anchors fixes but opens no cell, e.g. a walk placed by the tracker). β = 1 or a floor
without positions: the cell centres.)doc")
      .def(
          "with_options",
          [](const GridTracker& t, const py::object& options) {
            // Checked here, not by pybind11's overload resolution: a wrong type given to the
            // reference parameter crashed the interpreter instead of raising.
            if (!py::isinstance<GridTrackerOptions>(options)) {
              ThrowInvalidArgument("options", "expected a GridTrackerOptions, got " +
                                                  std::string(Py_TYPE(options.ptr())->tp_name));
            }
            const GridTrackerOptions o = options.cast<GridTrackerOptions>();
            py::gil_scoped_release release;
            return t.WithOptions(o);
          },
          py::arg("options"), py::keep_alive<0, 1>(), R"doc(
A tracker on the same plan and grid with other options (GridTrackerOptions): the same results,
bit for bit, as GridTracker(plan, options) (and its with_survey_positions with this tracker's
survey positions), without recomputing the walkable fractions or the survey anchors unless
wall_log_penalty or fix_survey_distance_factor changed. ValueError for options whose grid differs
(cell_size_m, walkable_subsamples, wall_margin_m).)doc")
      .def_static("release_kept_memory", &GridTracker::ReleaseKeptMemory, R"doc(
Free the memory that runs keep for later runs (the smoother's stored forward grids and the
layers' output slots, at most kept_memory_limit_bytes for the whole process: a batch of walks
reuses them instead of paging in fresh memory every run). Buffers of runs in progress are kept
until those runs end. Returns the bytes freed. Thread-safe; results never depend on it.)doc")
      .def_static("kept_memory_bytes", &GridTracker::KeptMemoryBytes,
                  "Bytes kept now for later runs (release_kept_memory frees them).")
      .def_property_readonly_static("kept_memory_limit_bytes",
                                    [](const py::object&) { return GridTracker::kept_memory_limit_bytes; },
                                    "Largest memory kept for later runs, for the whole process [bytes].")
      .def("run",
           [](const GridTracker& t, const py::object& step_times_s, const py::object& displacements_m,
              const py::object& covariances_m2, const py::object& fixes, const py::object& start, bool smooth,
              bool filtered) {
             const std::vector<StepInput> steps = StepsFromArrays(step_times_s, displacements_m, covariances_m2);
             std::vector<PositionFix> fx;
             if (!fixes.is_none()) {
               if (!py::isinstance<py::tuple>(fixes)) {
                 ThrowInvalidArgument("fixes", "expected None or (times_s, means_m, sds_m, weights, floors) "
                                               "(indoorloc.fusion.Fixes.as_arrays()), got " +
                                                   std::string(Py_TYPE(fixes.ptr())->tp_name));
               }
               fx = FixesFromArrays(fixes.cast<py::tuple>());
             }
             const TrackStart st = StartFromDict(start, steps.empty() ? 0.0 : steps.front().time_s);
             GridTrackResult r;
             {
               py::gil_scoped_release release;
               r = t.Run(steps, fx, st, smooth, filtered);
             }
             return ResultToDict(r);
           },
           py::arg("step_times_s"), py::arg("displacements_m"), py::arg("covariances_m2"), py::arg("fixes") = py::none(),
           py::arg("start") = py::none(), py::arg("smooth") = true, py::arg("filtered") = true, R"doc(
Track one walk (GIL released). Steps as arrays: step_times_s (M,) [s], displacements_m (M, 2) [m]
in the PDR frame, covariances_m2 (M, 3) = (xx, xy, yy) [m²]; fixes: None or
indoorloc.fusion.Fixes.as_arrays(); start: None (unknown) or {"position_m", "floor",
"heading_offset_rad", "time_s"} (its heading offset is also the centre of the offset prior).
Returns a dict: per step times_s (M,), mean_m (M, 2), covariance_m2 (M, 3) (causal filter),
floor_probabilities (M, F), heading_offset_rad (M,), posterior_covariance_m2 (M, 3) and
fix_distance_m (M,) and fix_sd_m (M,) (covariance_m2 is the calibrated one, options); with smooth, smoothed_m (M, 2),
smoothed_covariance_m2 (M, 3), smoothed_posterior_covariance_m2, smoothed_fix_distance_m and smoothed_fix_sd_m; given the whole walk smoothed_floor_probabilities (F,),
heading_offset_bins_rad / heading_offset_probabilities (H,), scale_bins / scale_probabilities
(S,), walk_heading_offset_rad, walk_heading_offset_sd_rad, walk_scale; summary. filtered=False
with smooth: the causal filter's position estimates are not computed (mean_m, the covariances
and fix_distance_m NaN after a known start, no median_m), everything else unchanged bit for bit.)doc");
}

}  // namespace

void BindFusionGrid(py::module_& m) {
  BindGridOptionsAndSummary(m);
  BindGridTrackerClass(m);
}

}  // namespace indoorloc::bindings
