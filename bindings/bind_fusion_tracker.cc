// Python bindings of the fusion tracker: options, WiFi observations, the streaming
// ParticleTracker and the batch track() with the backward smoother.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/fusion/backward_smoother.h"
#include "indoorloc/fusion/floor_plan.h"
#include "indoorloc/fusion/particle_tracker.h"
#include "indoorloc/fusion/step_motion.h"
#include "indoorloc/fusion/track.h"
#include "indoorloc/fusion/wifi_likelihood.h"
#include "fusion_args.h"
#include "numpy_args.h"
#include "options_binding.h"

namespace indoorloc::bindings {

using namespace indoorloc::fusion;  // NOLINT: binding file

namespace {

template <typename T>
py::array_t<T> VectorToArray(const std::vector<T>& v) {
  py::array_t<T> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

// One tracker update run with the GIL released; its estimate (a TrackerEstimate object).
template <typename Update>
TrackerEstimate UpdateWithoutGil(const Update& update) {
  py::gil_scoped_release release;
  return update();
}

template <typename T>
const T* OptionalPointer(const py::object& obj, const char* argument, const char* type) {
  if (obj.is_none()) return nullptr;
  try {
    return obj.cast<const T*>();
  } catch (const py::cast_error&) {
    ThrowInvalidArgument(argument, std::string("must be None or a ") + type + " object, got " +
                                       std::string(Py_TYPE(obj.ptr())->tp_name));
  }
}

/// The tracker's and the smoother's options (the generic Options protocol).
void BindTrackerOptions(py::module_& m) {
  py::class_<TrackerOptions> tracker_options(m, "TrackerOptions", R"doc(
Options of the fusion particle tracker (see docs/fusion.md for each constant and how its
default was chosen). Set fields by keyword: ``TrackerOptions(num_particles=2000, tempering=0.3)``;
the nested motion (heading_offset_walk_rad, scale_walk, min_scale, max_scale, position_noise_m),
WiFi (tempering, max_term, max_age_s, use_not_heard, not_heard_dbm), resampling (resampling,
ess_threshold) and fix (fix_outlier_probability, fix_tempering) options are flattened.
``replace``, ``to_dict``, equality and pickling as for every Options class.)doc");
  tracker_options
      .def_readwrite("num_particles", &TrackerOptions::num_particles)
      .def_property("heading_offset_walk_rad", [](const TrackerOptions& o) { return o.motion.heading_offset_walk_rad; },
                    [](TrackerOptions& o, double v) { o.motion.heading_offset_walk_rad = v; },
                    "σ_o: heading-offset random walk per step [rad].")
      .def_property("scale_walk", [](const TrackerOptions& o) { return o.motion.scale_walk; },
                    [](TrackerOptions& o, double v) { o.motion.scale_walk = v; }, "σ_s: stride-scale random walk per step.")
      .def_property("min_scale", [](const TrackerOptions& o) { return o.motion.min_scale; },
                    [](TrackerOptions& o, double v) { o.motion.min_scale = v; })
      .def_property("max_scale", [](const TrackerOptions& o) { return o.motion.max_scale; },
                    [](TrackerOptions& o, double v) { o.motion.max_scale = v; })
      .def_property("position_noise_m", [](const TrackerOptions& o) { return o.motion.position_noise_m; },
                    [](TrackerOptions& o, double v) { o.motion.position_noise_m = v; }, "σ_p: process noise per step [m].")
      .def_property("tempering", [](const TrackerOptions& o) { return o.wifi.tempering; },
                    [](TrackerOptions& o, double v) { o.wifi.tempering = v; }, "τ: WiFi likelihood exponent in (0, 1].")
      .def_property("max_term", [](const TrackerOptions& o) { return o.wifi.max_term; },
                    [](TrackerOptions& o, double v) { o.wifi.max_term = v; }, "Cap of each AP's residual term [nats].")
      .def_property("max_age_s", [](const TrackerOptions& o) { return o.wifi.max_age_s; },
                    [](TrackerOptions& o, double v) { o.wifi.max_age_s = v; }, "Staleness limit of a reading [s].")
      .def_property("use_not_heard", [](const TrackerOptions& o) { return o.wifi.use_not_heard; },
                    [](TrackerOptions& o, bool v) { o.wifi.use_not_heard = v; })
      .def_property("not_heard_dbm", [](const TrackerOptions& o) { return o.wifi.not_heard_dbm; },
                    [](TrackerOptions& o, double v) { o.wifi.not_heard_dbm = v; })
      .def_property("resampling", [](const TrackerOptions& o) { return std::string(ToString(o.resampling.scheme)); },
                    [](TrackerOptions& o, const std::string& v) { o.resampling.scheme = ParseResamplingScheme(v, "resampling"); })
      .def_property("ess_threshold", [](const TrackerOptions& o) { return o.resampling.ess_threshold; },
                    [](TrackerOptions& o, double v) { o.resampling.ess_threshold = v; })
      .def_property("fix_outlier_probability", [](const TrackerOptions& o) { return o.fix.outlier_probability; },
                    [](TrackerOptions& o, double v) { o.fix.outlier_probability = v; },
                    "ε: probability that a position fix is unrelated to the position, in (0, 1).")
      .def_property("fix_tempering", [](const TrackerOptions& o) { return o.fix.tempering; },
                    [](TrackerOptions& o, double v) { o.fix.tempering = v; }, "τ_fix: position-fix likelihood exponent in (0, 1].")
      .def_readwrite("wall_log_penalty", &TrackerOptions::wall_log_penalty)
      .def_readwrite("respread_after_blocked_steps", &TrackerOptions::respread_after_blocked_steps)
      .def_readwrite("respread_sd_m", &TrackerOptions::respread_sd_m)
      .def_readwrite("start_position_sd_m", &TrackerOptions::start_position_sd_m)
      .def_readwrite("start_heading_offset_sd_rad", &TrackerOptions::start_heading_offset_sd_rad)
      .def_readwrite("start_scale_sd", &TrackerOptions::start_scale_sd)
      .def_readwrite("unknown_start_heading_sd_rad", &TrackerOptions::unknown_start_heading_sd_rad)
      .def_readwrite("candidate_spacing_m", &TrackerOptions::candidate_spacing_m)
      .def_readwrite("recovery_log_ratio", &TrackerOptions::recovery_log_ratio)
      .def_readwrite("recovery_scans", &TrackerOptions::recovery_scans)
      .def_readwrite("recovery_fraction", &TrackerOptions::recovery_fraction)
      .def_readwrite("floor_change_probability", &TrackerOptions::floor_change_probability)
      .def_readwrite("corridor_kappa", &TrackerOptions::corridor_kappa)
      .def_readwrite("smoothing_lag_steps", &TrackerOptions::smoothing_lag_steps)
      .def_readwrite("num_threads", &TrackerOptions::num_threads)
      .def_readwrite("seed", &TrackerOptions::seed);
  BindOptionsProtocol(tracker_options, "TrackerOptions");

  py::class_<SmootherOptions> smoother_options(m, "SmootherOptions",
                                               "Forward-filter backward-simulation smoother options; fields by keyword.");
  smoother_options
      .def_readwrite("num_trajectories", &SmootherOptions::num_trajectories, "Backward trajectories drawn.")
      .def_readwrite("max_particles", &SmootherOptions::max_particles,
                     "Particles kept per stored step (a subsample of the filter's).")
      .def_readwrite("seed", &SmootherOptions::seed)
      .def_readwrite("num_threads", &SmootherOptions::num_threads);
  BindOptionsProtocol(smoother_options, "SmootherOptions", {"num_trajectories", "max_particles", "seed", "num_threads"});

}

/// What a tracker run did.
void BindTrackerSummary(py::module_& m) {
  py::class_<TrackerSummary>(m, "TrackerSummary", "What a tracker run did.")
      .def_readonly("steps", &TrackerSummary::steps)
      .def_readonly("wifi_updates", &TrackerSummary::wifi_updates)
      .def_readonly("empty_wifi_updates", &TrackerSummary::empty_wifi_updates)
      .def_readonly("fix_updates", &TrackerSummary::fix_updates)
      .def_readonly("resamplings", &TrackerSummary::resamplings)
      .def_readonly("recoveries", &TrackerSummary::recoveries)
      .def_readonly("all_blocked_steps", &TrackerSummary::all_blocked_steps)
      .def_readonly("respreads", &TrackerSummary::respreads)
      .def_readonly("mean_ess", &TrackerSummary::mean_ess)
      .def_readonly("total_log_likelihood", &TrackerSummary::total_log_likelihood)
      .def_readonly("seconds", &TrackerSummary::seconds)
      .def("brief_report", &TrackerSummary::BriefReport)
      .def("__repr__", [](const TrackerSummary& s) { return "<TrackerSummary " + s.BriefReport() + ">"; });

}

/// WiFi observations and the steps given to the tracker.
void BindWifiObservations(py::module_& m) {
  py::class_<WifiObservation>(m, "WifiObservation", R"doc(
Usable readings of one scan (or of readings sharing their own time): AP columns of the signal
map and RSS [dBm]. Build them with make_wifi_observations.)doc")
      .def(py::init([](double time_s, const std::vector<int>& access_points, const std::vector<double>& rss_dbm) {
             CheckArgument(access_points.size() == rss_dbm.size(), "rss_dbm", "must have one entry per access point");
             RequireFinite(time_s, "time_s");
             for (size_t k = 0; k < rss_dbm.size(); ++k) {
               if (!(rss_dbm[k] >= -300.0 && rss_dbm[k] <= 50.0)) {
                 ThrowInvalidArgument("rss_dbm", DescribeEntry(static_cast<Eigen::Index>(k), 0, true) + " = " +
                                                     FormatValue(rss_dbm[k]) + " is not an RSS in [-300, 50] dBm");
               }
               if (access_points[k] < 0) {
                 ThrowInvalidArgument("access_points", DescribeEntry(static_cast<Eigen::Index>(k), 0, true) + " = " +
                                                           std::to_string(access_points[k]) + " is not an AP column (>= 0)");
               }
             }
             WifiObservation o;
             o.time_s = time_s;
             o.access_points = access_points;
             o.rss_dbm = rss_dbm;
             o.num_heard = static_cast<int>(rss_dbm.size());
             return o;
           }),
           py::arg("time_s"), py::arg("access_points"), py::arg("rss_dbm"))
      .def_readonly("time_s", &WifiObservation::time_s)
      .def_readonly("access_points", &WifiObservation::access_points)
      .def_readonly("rss_dbm", &WifiObservation::rss_dbm)
      .def_readonly("num_heard", &WifiObservation::num_heard)
      .def("__len__", [](const WifiObservation& o) { return o.access_points.size(); })
      .def("__repr__", [](const WifiObservation& o) {
        return "<WifiObservation t=" + std::to_string(o.time_s) + " s, " + std::to_string(o.access_points.size()) +
               " readings (" + std::to_string(o.num_heard) + " heard)>";
      });

  m.def("make_wifi_observations",
        [](const py::object& scan_times_s, const py::object& rss_dbm, const py::object& ages_s,
           const TrackerOptions& options, bool at_own_time) {
          // The memory bound from the array's shape, before converting (copying) it.
          const py::object shape = py::getattr(rss_dbm, "shape", py::none());
          if (py::isinstance<py::tuple>(shape) && py::len(shape) == 2) {
            const py::tuple dims = shape.cast<py::tuple>();
            if (py::isinstance<py::int_>(dims[0]) && py::isinstance<py::int_>(dims[1])) {
              RequireWifiReadingsMemory(dims[0].cast<double>(), dims[1].cast<double>());
            }
          }
          VectorArg t = ToVector(scan_times_s, "scan_times_s");
          MatrixArg r = ToMatrix(rss_dbm, "rss_dbm", t.map.size(), -1, Finiteness::kAny);
          RowMatrixXd ages(0, 0);
          if (!ages_s.is_none()) {
            MatrixArg a = ToMatrix(ages_s, "ages_s", t.map.size(), r.map.cols(), Finiteness::kAny);
            ages = a.map;
          }
          WifiReadingCounts counts;
          std::vector<WifiObservation> out;
          {
            py::gil_scoped_release release;
            out = MakeWifiObservations(t.map, r.map, ages, options.wifi, at_own_time, &counts);
          }
          py::dict c;
          c["heard"] = counts.heard;
          c["not_heard"] = counts.not_heard;
          c["dropped_stale"] = counts.dropped_stale;
          c["scans_without_readings"] = counts.scans_without_readings;
          return py::make_tuple(out, c);
        },
        py::arg("scan_times_s"), py::arg("rss_dbm"), py::arg("ages_s") = py::none(),
        py::arg("options") = TrackerOptions(), py::arg("at_own_time") = true, R"doc(
Scans to observations. scan_times_s (S,) [s] non-decreasing; rss_dbm (S, K) with the signal map's
AP columns, NaN = not heard; ages_s (S, K) [s] scan time minus last-seen time (None: all fresh).
at_own_time: heard readings re-timed to t - age and grouped; else readings older than
options.max_age_s are dropped. Returns (list of WifiObservation sorted by time, counts dict).)doc");

  m.def("steps_from_polar",
        [](const py::object& lengths_m, const py::object& headings_rad, const py::object& length_sd_m,
           const py::object& heading_sd_rad) {
          VectorArg l = ToVector(lengths_m, "lengths_m");
          const Eigen::Index n = l.map.size();
          VectorArg h = ToVector(headings_rad, "headings_rad", n);
          VectorArg ls = ToVector(length_sd_m, "length_sd_m", n);
          VectorArg hs = ToVector(heading_sd_rad, "heading_sd_rad", n);
          RowMatrixXd disp(n, 2), cov(n, 3);
          for (Eigen::Index k = 0; k < n; ++k) {
            // Bounded so that the propagated covariance stays a step's (sd <= 100 m): 1e300
            // gave an inf covariance.
            CheckArgument(l.map[k] >= 0.0 && l.map[k] <= 100.0, "lengths_m",
                          DescribeEntry(k, 0, true) + " must be in [0, 100] m, got " + FormatValue(l.map[k]));
            CheckArgument(ls.map[k] >= 0.0 && ls.map[k] <= 100.0, "length_sd_m",
                          DescribeEntry(k, 0, true) + " must be in [0, 100] m, got " + FormatValue(ls.map[k]));
            CheckArgument(hs.map[k] >= 0.0 && hs.map[k] <= 1e3, "heading_sd_rad",
                          DescribeEntry(k, 0, true) + " must be in [0, 1000] rad, got " + FormatValue(hs.map[k]));
            const StepInput s = StepFromPolar(0.0, l.map[k], h.map[k], ls.map[k], hs.map[k]);
            disp.row(k) = s.displacement_m.transpose();
            cov.row(k) << s.covariance_m2(0, 0), s.covariance_m2(0, 1), s.covariance_m2(1, 1);
          }
          return py::make_tuple(disp, cov);
        },
        py::arg("lengths_m"), py::arg("headings_rad"), py::arg("length_sd_m"), py::arg("heading_sd_rad"), R"doc(
Polar steps (length [m], heading [rad], their sd; each (M,)) to displacements (M, 2) [m] and
covariances (M, 3) = (xx, xy, yy) [m²] by first-order propagation.)doc");

}

/// The streaming ParticleTracker.
void BindParticleTracker(py::module_& m) {
  py::class_<ParticleTracker>(m, "ParticleTracker", R"doc(
Streaming fusion particle filter (PDR steps + WiFi + floor plan, optional corridor network).
Keeps references to plan, wifi_model and corridors (kept alive by this object).

Parameters
----------
plan : FloorPlan or None
wifi_model : indoorloc.wifi.RssModel or None
corridors : indoorloc.mapmatch.RoadNetwork or None
    Corridor mode: particles live on the network (paper 000) instead of free space.
options : TrackerOptions)doc")
      .def(py::init([](const py::object& plan, const py::object& wifi_model, const py::object& corridors,
                       const TrackerOptions& options) {
             return std::make_unique<ParticleTracker>(OptionalPointer<FloorPlan>(plan, "plan", "FloorPlan"),
                                                      OptionalPointer<wifi::RssModel>(wifi_model, "wifi_model", "RssModel"),
                                                      OptionalPointer<mapmatch::RoadNetwork>(corridors, "corridors", "RoadNetwork"),
                                                      options);
           }),
           py::arg("plan") = py::none(), py::arg("wifi_model") = py::none(), py::arg("corridors") = py::none(),
           py::arg("options") = TrackerOptions(), py::keep_alive<1, 2>(), py::keep_alive<1, 3>(), py::keep_alive<1, 4>())
      .def_property_readonly("floors", &ParticleTracker::floors)
      .def_property_readonly("initialized", &ParticleTracker::initialized)
      .def_property_readonly("summary", &ParticleTracker::summary)
      .def("initialize_known", [](ParticleTracker& t, double time_s, const py::object& position_m, int floor,
                                  double heading_offset_rad) {
             VectorArg p = ToVector(position_m, "position_m", 2);
             RequireAllInRange(p.map, -kMaxScale, kMaxScale, "position_m");
             RequireFinite(time_s, "time_s");
             RequireFinite(heading_offset_rad, "heading_offset_rad");
             t.InitializeKnown(time_s, p.map, floor, heading_offset_rad);
           },
           py::arg("time_s"), py::arg("position_m"), py::arg("floor") = 0, py::arg("heading_offset_rad") = 0.0,
           "Known start: position (2,) [m] on floor number `floor`, PDR-to-floor yaw [rad].")
      .def("initialize_unknown", [](ParticleTracker& t, const py::object& observation) {
             WifiObservation none;
             if (!observation.is_none() && !py::isinstance<WifiObservation>(observation)) {
               ThrowInvalidArgument("observation", "expected None or a WifiObservation, got " +
                                                       std::string(Py_TYPE(observation.ptr())->tp_name));
             }
             const WifiObservation& o = observation.is_none() ? none : observation.cast<const WifiObservation&>();
             py::gil_scoped_release release;
             t.InitializeUnknown(o);
           },
           py::arg("observation") = py::none(),
           "Unknown start: from a WifiObservation's likelihood over the walkable area, or uniform (None).")
      .def("step", [](ParticleTracker& t, double time_s, const py::object& displacement_m, const py::object& covariance_m2) {
             VectorArg d = ToVector(displacement_m, "displacement_m", 2);
             MatrixArg c = ToMatrix(covariance_m2, "covariance_m2", 2, 2);
             StepInput s;
             s.time_s = time_s;
             s.displacement_m = d.map;
             s.covariance_m2 = c.map;
             return UpdateWithoutGil([&] { return t.Step(s); });
           },
           py::arg("time_s"), py::arg("displacement_m"), py::arg("covariance_m2"),
           "One step: displacement (2,) [m] in the PDR frame and its covariance (2, 2) [m²]. Returns a TrackerEstimate.")
      .def("wifi", [](ParticleTracker& t, const WifiObservation& o) {
             return UpdateWithoutGil([&] { return t.Wifi(o); });
           },
           py::arg("observation"), "One WiFi observation. Returns a TrackerEstimate.")
      .def("fix", [](ParticleTracker& t, double time_s, const py::object& means_m, const py::object& sds_m,
                     const py::object& weights, const py::object& floors) {
             MatrixArg m = ToMatrix(means_m, "means_m", -1, 2);
             VectorArg sd = ToVector(sds_m, "sds_m", m.map.rows());
             VectorArg w = ToVector(weights, "weights", m.map.rows());
             PositionFix fix;
             fix.time_s = time_s;
             if (!floors.is_none()) fix.floors = ToIntVector(floors, "floors", m.map.rows());
             fix.means_m = m.map;
             fix.sds_m = sd.map;
             fix.weights = w.map;
             return UpdateWithoutGil([&] { return t.Fix(fix); });
           },
           py::arg("time_s"), py::arg("means_m"), py::arg("sds_m"), py::arg("weights"), py::arg("floors") = py::none(),
           "One position fix: a Gaussian mixture with component means (K, 2) [m], isotropic sds (K,) [m], "
           "weights (K,) and floor numbers (K,) (None or ANY_FLOOR: any floor), plus the outlier floor of "
           "TrackerOptions.fix_outlier_probability. Returns a TrackerEstimate.")
      .def_property_readonly("floor_areas_m2", &ParticleTracker::floor_areas_m2,
                             "Walkable area [m²] per tracker floor (the outlier density of a fix is 1 / area).")
      .def("estimate", &ParticleTracker::Estimate, "The estimate after the latest update (a TrackerEstimate).")
      .def("particles", [](const ParticleTracker& t) {
             return py::make_tuple(t.ParticleStates(), t.ParticleFloorIndices(), t.ParticleWeights());
           },
           "(states (N, 4): x [m], y [m], heading offset [rad], scale; floor indices (N,); weights (N,)).")
      .def("set_particles", [](ParticleTracker& t, const py::object& states, const py::object& floor_indices) {
             MatrixArg s = ToMatrix(states, "states", -1, 4);
             t.SetParticles(s.map, ToIntVector(floor_indices, "floor_indices", s.map.rows()));
           },
           py::arg("states"), py::arg("floor_indices"));

}

/// track(): a whole walk, with the backward smoother.
void BindBatchTrack(py::module_& m) {
  m.def("track",
        [](const py::object& plan, const py::object& wifi_model, const py::object& corridors, const py::object& step_times_s,
           const py::object& displacements_m, const py::object& covariances_m2, const std::vector<WifiObservation>& observations,
           const py::object& start, const TrackerOptions& options, const py::object& smoother, const py::object& fixes) {
          Recording rec;
          rec.steps = StepsFromArrays(step_times_s, displacements_m, covariances_m2);
          rec.observations = observations;
          if (!fixes.is_none()) {
            if (!py::isinstance<py::tuple>(fixes)) {
              ThrowInvalidArgument("fixes", "expected None or (times_s, means_m, sds_m, weights, floors) "
                                            "(indoorloc.fusion.Fixes.as_arrays()), got " +
                                                std::string(Py_TYPE(fixes.ptr())->tp_name));
            }
            rec.fixes = FixesFromArrays(fixes.cast<py::tuple>());
          }
          const TrackStart st = StartFromDict(start, rec.steps.empty() ? 0.0 : rec.steps.front().time_s);
          SmootherOptions so;
          const bool smooth = !smoother.is_none();
          if (smooth) {
            if (!py::isinstance<SmootherOptions>(smoother)) {
              ThrowInvalidArgument("smoother", "expected None or a SmootherOptions, got " +
                                                   std::string(Py_TYPE(smoother.ptr())->tp_name));
            }
            so = smoother.cast<SmootherOptions>();
          }
          const FloorPlan* p = OptionalPointer<FloorPlan>(plan, "plan", "FloorPlan");
          const wifi::RssModel* w = OptionalPointer<wifi::RssModel>(wifi_model, "wifi_model", "RssModel");
          const mapmatch::RoadNetwork* c = OptionalPointer<mapmatch::RoadNetwork>(corridors, "corridors", "RoadNetwork");
          TrackResult r;
          {
            py::gil_scoped_release release;
            r = Track(p, w, c, rec, st, options, so, smooth);
          }
          const Eigen::Index n = static_cast<Eigen::Index>(r.estimates.size());
          const Eigen::Index nf = n > 0 ? r.estimates.front().floor_probabilities.size() : 0;
          RowMatrixXd mean(n, 2), cov(n, 3), lagged(n, 2), floor_p(n, nf);
          Eigen::VectorXd times(n), offset(n), scale(n), ess(n), loglik(n), blocked(n);
          std::vector<std::int64_t> floor_index(static_cast<size_t>(n));
          py::array_t<bool> resampled(n), recovered(n);
          for (Eigen::Index k = 0; k < n; ++k) {
            const TrackerEstimate& e = r.estimates[static_cast<size_t>(k)];
            times[k] = e.time_s;
            mean.row(k) = e.mean_m.transpose();
            cov.row(k) << e.covariance_m2(0, 0), e.covariance_m2(0, 1), e.covariance_m2(1, 1);
            lagged.row(k) = e.lagged_m.transpose();
            floor_p.row(k) = e.floor_probabilities.transpose();
            floor_index[static_cast<size_t>(k)] = e.floor_index;
            offset[k] = e.heading_offset_rad;
            scale[k] = e.scale;
            ess[k] = e.ess;
            loglik[k] = e.log_likelihood;
            blocked[k] = e.blocked_fraction;
            resampled.mutable_data()[k] = e.resampled;
            recovered.mutable_data()[k] = e.recovered;
          }
          py::dict d;
          d["times_s"] = times;
          d["mean_m"] = mean;
          d["covariance_m2"] = cov;
          d["floor_probabilities"] = floor_p;
          d["floor_index"] = VectorToArray(floor_index);
          d["heading_offset_rad"] = offset;
          d["scale"] = scale;
          d["ess"] = ess;
          d["log_likelihood"] = loglik;
          d["blocked_fraction"] = blocked;
          d["resampled"] = resampled;
          d["recovered"] = recovered;
          d["lagged_m"] = lagged;
          d["summary"] = r.summary;
          if (smooth) {
            d["smoothed_m"] = r.smoothed.positions_m;
            d["smoothed_covariance_m2"] = r.smoothed.covariances_m2;
            d["smoothed_floor_index"] = r.smoothed.floor_indices;
            d["smoothed_trajectories_m"] = r.smoothed.trajectories_m;
            d["smoother_seconds"] = r.smoothed.seconds;
          }
          return d;
        },
        py::arg("plan"), py::arg("wifi_model"), py::arg("corridors"), py::arg("step_times_s"), py::arg("displacements_m"),
        py::arg("covariances_m2"), py::arg("observations"), py::arg("start") = py::none(),
        py::arg("options") = TrackerOptions(), py::arg("smoother") = py::none(), py::arg("fixes") = py::none(), R"doc(
Batch tracking of one recording (GIL released). Steps as arrays: step_times_s (M,) [s],
displacements_m (M, 2) [m] in the PDR frame, covariances_m2 (M, 3) = (xx, xy, yy) [m²];
observations: list of WifiObservation sorted by time. start: None (unknown start) or a dict
{"position_m", "floor", "heading_offset_rad", "time_s"}. smoother: SmootherOptions or None.
fixes: None or (times_s (F,), means_m (F, 2K), sds_m (F, K), weights (F, K), floors (F, K)),
weight-0 components being padding, floor ANY_FLOOR for any floor (see Fixes in indoorloc.fusion).
Returns a dict of per-step arrays (times_s, mean_m (M, 2), covariance_m2 (M, 3),
floor_probabilities (M, F), floor_index, heading_offset_rad, scale, ess, log_likelihood,
blocked_fraction, resampled, recovered, lagged_m), the TrackerSummary, and with a smoother
smoothed_m (M, 2), smoothed_covariance_m2 (M, 3), smoothed_floor_index (M,),
smoothed_trajectories_m (M, 2T), smoother_seconds.)doc");
}

}  // namespace

void BindFusionTracker(py::module_& m) {
  m.attr("ANY_FLOOR") = PositionFix::kAnyFloor;
  BindTrackerOptions(m);
  BindTrackerSummary(m);
  BindWifiObservations(m);
  BindParticleTracker(m);
  BindBatchTrack(m);
}

}  // namespace indoorloc::bindings
