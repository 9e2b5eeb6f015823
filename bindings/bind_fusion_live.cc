// Python bindings of live tracking: the streaming step detector (pdr/streaming_step_detector.h,
// in indoorloc._core.pdr), the fingerprint fix options and the live session
// (fusion/fingerprint_fixes.h, fusion/live_session.h, in indoorloc._core.fusion). numpy in and out,
// the GIL released around the C++ work, errors as ValueError naming the argument.
#include <cmath>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/core/check.h"
#include "indoorloc/fusion/live_session.h"
#include "indoorloc/pdr/streaming_step_detector.h"
#include "fusion_args.h"
#include "fusion_estimates.h"
#include "numpy_args.h"
#include "options_binding.h"

namespace indoorloc::bindings {

using namespace indoorloc::fusion;  // NOLINT: binding file
using pdr::StreamingStep;
using pdr::StreamingStepDetector;
using pdr::StreamingStepOptions;

namespace {

py::tuple StepTuple(const StreamingStep& s) {
  return py::make_tuple(s.time_s, s.index, s.feature, s.heading_rotation_vector_rad, s.heading_gyro_rad,
                        s.heading_complementary_rad, s.start_time_s, s.confirmed_time_s);
}

Eigen::Vector3d Vector3(const py::handle& obj, const char* name) {
  const VectorArg v = ToVector(obj, name);
  if (v.map.size() < 3) ThrowInvalidArgument(name, "expected 3 finite values, got " + std::to_string(v.map.size()));
  return v.map.head<3>();
}

double Time(const py::handle& obj, const char* name) {
  if (py::isinstance<py::str>(obj) || !(py::isinstance<py::float_>(obj) || py::isinstance<py::int_>(obj) ||
                                        py::hasattr(obj, "__float__"))) {
    ThrowInvalidArgument(name, "must be a number, got " + std::string(Py_TYPE(obj.ptr())->tp_name));
  }
  return obj.cast<double>();
}

const char* SourceName(StepHeadingSource s) {
  return s == StepHeadingSource::kGyro ? "gyro" : s == StepHeadingSource::kComplementary ? "complementary"
                                                                                        : "rotation_vector";
}

// A fingerprint map from the tuple (bssids, rss_dbm (N, K), positions_m (N, 2), floors (N,),
// weights (N,) or None, ap_weights (K,) or None) (python wifi_fixes.FingerprintDatabase's arrays).
FingerprintMap MapFromTuple(const py::tuple& t) {
  if (t.size() != 6) ThrowInvalidArgument("map", "must be (bssids, rss_dbm, positions_m, floors, weights, ap_weights)");
  FingerprintMap map;
  map.bssids = t[0].cast<std::vector<std::string>>();
  map.rss_dbm = ToMatrix(t[1], "map.rss_dbm", -1, static_cast<Eigen::Index>(map.bssids.size()), Finiteness::kAny).map;
  const Eigen::Index n = map.rss_dbm.rows();
  map.positions_m = ToMatrix(t[2], "map.positions_m", n, 2).map;
  map.floors = ToIntVector(t[3], "map.floors", n);
  if (!t[4].is_none()) map.weights = ToVector(t[4], "map.weights", n).map;
  if (!t[5].is_none()) map.ap_weights = ToVector(t[5], "map.ap_weights", map.rss_dbm.cols()).map;
  return map;
}

// The current estimate (a LiveEstimate: the grid filter's, the floors and the most probable floor),
// None before the first step.
py::object EstimateOrNone(const LiveSession& s) {
  if (!s.HasEstimate()) return py::none();
  return py::cast(MakeLiveEstimate(s.Estimate(), s.floors()));
}

// A live session with the GridTracker it reads kept alive by the Python object (keep_alive) and
// its own copy of the map.
struct PyLiveSession {
  std::unique_ptr<FingerprintMap> map;
  std::unique_ptr<LiveSession> session;
};

}  // namespace

void BindPdrStreaming(py::module_& m) {
  py::class_<StreamingStepOptions> opt(m, "StreamingStepOptions", R"doc(
Options of the streaming (causal) step detector. The defaults equal python
``indoorloc.pdr.handheld.HandheldOptions``' (where they are chosen; a test keeps them equal).)doc");
  opt.def_readwrite("lowpass_hz", &StreamingStepOptions::lowpass_hz, "Band-pass upper edge [Hz].")
      .def_readwrite("highpass_hz", &StreamingStepOptions::highpass_hz, "Band-pass lower edge [Hz].")
      .def_readwrite("filter_order", &StreamingStepOptions::filter_order, "Butterworth order of each edge.")
      .def_readwrite("rms_window_s", &StreamingStepOptions::rms_window_s, "Trailing RMS window [s].")
      .def_readwrite("threshold_fraction", &StreamingStepOptions::threshold_fraction, "Peak > this x RMS.")
      .def_readwrite("min_peak_mps2", &StreamingStepOptions::min_peak_mps2, "... and > this [m/s²].")
      .def_readwrite("min_step_interval_s", &StreamingStepOptions::min_step_interval_s,
                     "At most one step per this [s]; also the latency.")
      .def_readwrite("max_step_half_window_s", &StreamingStepOptions::max_step_half_window_s,
                     "Weinberg window half-width cap [s].")
      .def_readwrite("complementary_tau_s", &StreamingStepOptions::complementary_tau_s,
                     "Complementary heading time constant [s].")
      .def_readwrite("rate_samples", &StreamingStepOptions::rate_samples,
                     "Accelerometer intervals whose median gives the rate.");
  BindOptionsProtocol(opt, "StreamingStepOptions");

  py::class_<StreamingStepDetector>(m, "StreamingStepDetector", R"doc(
Causal hand-held step detector fed one IMU sample at a time (docs/pdr_handheld.md; python
``indoorloc.pdr.streaming`` wraps it). ``add_sample(t_s, acc_mps2, gyro_radps, quat_xyzw)`` returns
the steps the sample confirms: tuples ``(t_s, index, feature, heading_rv_rad, heading_gyro_rad,
heading_complementary_rad, start_t_s, confirmed_t_s)``.)doc")
      .def(py::init<const StreamingStepOptions&>(), py::arg("options") = StreamingStepOptions())
      .def(
          "add_sample",
          [](StreamingStepDetector& d, const py::object& t_s, const py::object& acc, const py::object& gyro,
             const py::object& quat) {
            const double t = Time(t_s, "t_s");
            const Eigen::Vector3d a = Vector3(acc, "acc_mps2"), g = Vector3(gyro, "gyro_radps");
            const VectorArg q = ToVector(quat, "quat_xyzw", 4);
            std::vector<StreamingStep> steps;
            d.AddSample(t, a, g, q.map, &steps);
            py::list out;
            for (const StreamingStep& s : steps) out.append(StepTuple(s));
            return out;
          },
          py::arg("t_s"), py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("quat_xyzw"),
          "One sample: time [s], force (3,) [m/s²], rate (3,) [rad/s], quaternion (x, y, z, w); the steps it confirms.")
      .def_property_readonly("rate_hz", &StreamingStepDetector::rate_hz, "Filter rate [Hz]; NaN until known.")
      .def_property_readonly("first_time_s", &StreamingStepDetector::first_time_s,
                             "Time of the first filtered sample [s]; NaN until the rate is known.")
      .def_property_readonly("options", &StreamingStepDetector::options);

  m.def(
      "causal_steps",
      [](const py::object& t_s, const py::object& acc, const py::object& gyro, const py::object& quat,
         const StreamingStepOptions& options) {
        const VectorArg t = ToVector(t_s, "t_s");
        const Eigen::Index n = t.map.size();
        const MatrixArg a = ToMatrix(acc, "acc_mps2", n, 3), g = ToMatrix(gyro, "gyro_radps", n, 3),
                        q = ToMatrix(quat, "quat_xyzw", n, 4);
        std::vector<StreamingStep> steps;
        {
          py::gil_scoped_release release;
          steps = pdr::CausalSteps(t.map, a.map, g.map, q.map, options);
        }
        RowMatrixXd out(static_cast<Eigen::Index>(steps.size()), 8);
        for (std::size_t k = 0; k < steps.size(); ++k) {
          const StreamingStep& s = steps[k];
          out.row(static_cast<Eigen::Index>(k)) << s.time_s, static_cast<double>(s.index), s.feature,
              s.heading_rotation_vector_rad, s.heading_gyro_rad, s.heading_complementary_rad, s.start_time_s,
              s.confirmed_time_s;
        }
        return out;
      },
      py::arg("t_s"), py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("quat_xyzw"),
      py::arg("options") = StreamingStepOptions(), R"doc(
The causal steps of a recorded walk (N samples on one time base): every sample through one
StreamingStepDetector. Returns (M, 8): t_s, index, feature, heading_rv_rad, heading_gyro_rad,
heading_complementary_rad, start_t_s, confirmed_t_s (the sample that confirmed it) per step.)doc");
  m.def(
      "quaternion_from_rotation_vector",
      [](const py::object& values) {
        return Eigen::VectorXd(pdr::QuaternionFromRotationVector(ToVector(values, "values", -1, Finiteness::kAny).map));
      },
      py::arg("values"), "Android rotation vector (x, y, z[, w]) -> unit quaternion (x, y, z, w).");
}

void BindFusionLive(py::module_& m) {
  py::class_<FingerprintFixOptions> fo(m, "FingerprintFixOptions", R"doc(
How WiFi scans become fixes live (fusion/fingerprint_fixes.h). Defaults equal python
``wifi_fixes.FixSettings``' (where they are chosen by cross-validation; a test keeps them equal).)doc");
  fo.def_readwrite("matcher", &FingerprintFixOptions::matcher, "wifi.SharedApMatcherOptions (c, beta, k, T).")
      .def_readwrite("query_window_s", &FingerprintFixOptions::query_window_s, "Pooling window before the scan [s].")
      .def_readwrite("min_aps", &FingerprintFixOptions::min_aps, "A query needs this many known APs.")
      .def_readwrite("sd_m", &FingerprintFixOptions::sd_m, "Component sd at d_min = 0 [m].")
      .def_readwrite("sd_per_db", &FingerprintFixOptions::sd_per_db, "Growth of the sd with d_min [m/dB].")
      .def_readwrite("with_floors", &FingerprintFixOptions::with_floors,
                     "Components on their fingerprint's floor (else any floor).");
  BindOptionsProtocol(fo, "FingerprintFixOptions");

  py::class_<LiveSessionOptions> lo(m, "LiveSessionOptions", R"doc(
Options of LiveSession: the PDR calibration (detector options, K, heading source, yaw offset) and
the per-step noise (defaults: ``indoorloc fusion evaluate``'s).)doc");
  lo.def_readwrite("detector", &LiveSessionOptions::detector, "pdr.StreamingStepOptions.")
      .def_readwrite("step_length_k", &LiveSessionOptions::step_length_k, "Weinberg K [m / (m/s²)^(1/4)].")
      .def_property(
          "heading_source", [](const LiveSessionOptions& o) { return std::string(SourceName(o.heading_source)); },
          [](LiveSessionOptions& o, const std::string& v) {
            if (v == "rotation_vector") o.heading_source = StepHeadingSource::kRotationVector;
            else if (v == "gyro") o.heading_source = StepHeadingSource::kGyro;
            else if (v == "complementary") o.heading_source = StepHeadingSource::kComplementary;
            else ThrowInvalidArgument("heading_source", "must be 'rotation_vector', 'gyro' or 'complementary', got '" + v + "'");
          },
          "'rotation_vector', 'gyro' or 'complementary'.")
      .def_readwrite("yaw_offset_rad", &LiveSessionOptions::yaw_offset_rad, "Floor minus phone heading [rad].")
      .def_readwrite("step_length_sd_fraction", &LiveSessionOptions::step_length_sd_fraction, "Length sd / length.")
      .def_readwrite("step_heading_sd_rad", &LiveSessionOptions::step_heading_sd_rad, "Per-step heading sd [rad].")
      .def_readwrite("delay_compensation", &LiveSessionOptions::delay_compensation,
                     "Move fixes by the PDR since the time they describe (off: it did not help).")
      .def_readwrite("standing_after_s", &LiveSessionOptions::standing_after_s,
                     "A fix still waiting for a step this long after its time [s] is applied at a standing "
                     "step (no displacement) at its time; 0: fixes wait for a step.");
  BindOptionsProtocol(lo, "LiveSessionOptions");

  py::class_<PyLiveSession>(m, "LiveSession", R"doc(
Raw sensor events in time order in, the grid filter's current estimate out after each
(docs/fusion.md, "Live tracking"; python ``indoorloc.fusion.live.LiveTracker`` wraps it).

``LiveSession(tracker, options, map=None, fix_options=None, start=None)``: ``map`` None (WiFi
ignored) or ``(bssids, rss_dbm (N, K), positions_m (N, 2), floors (N,), weights (N,) or None,
ap_weights (K,) or None)``; ``start`` as for GridFilterSession. Every ``add_*`` returns the
current estimate (a LiveEstimate: time_s, steps, mean_m, covariance_m2, floor_probabilities, floors,
floor, heading_offset_rad, ...) or None before the first step. Events out of time order raise ValueError
naming the event's index, kind and time and the previous event's; the session is then unchanged.)doc")
      .def(py::init([](const GridTracker* tracker, const LiveSessionOptions& options, const py::object& map,
                       const py::object& fix_options, const py::object& start) {
             if (tracker == nullptr) ThrowInvalidArgument("tracker", "must be a GridTracker, got None");
             const TrackStart st = StartFromDict(start, 0.0);
             if (st.known && !start.cast<py::dict>().contains("time_s")) {
               ThrowInvalidArgument("start", "a known start of a live session needs 'time_s'");
             }
             auto out = std::make_unique<PyLiveSession>();
             if (!map.is_none()) out->map = std::make_unique<FingerprintMap>(MapFromTuple(map.cast<py::tuple>()));
             const FingerprintFixOptions fo = fix_options.is_none() ? FingerprintFixOptions()
                                                                    : fix_options.cast<FingerprintFixOptions>();
             py::gil_scoped_release release;
             out->session = std::make_unique<LiveSession>(tracker, out->map.get(), options, fo, st);
             return out;
           }),
           py::arg("tracker"), py::arg("options"), py::arg("map") = py::none(), py::arg("fix_options") = py::none(),
           py::arg("start") = py::none(), py::keep_alive<1, 2>())
      .def(
          "add_accelerometer",
          [](PyLiveSession& s, const py::object& t_s, const py::object& acc) {
            const double t = Time(t_s, "t_s");
            const Eigen::Vector3d a = Vector3(acc, "acc_mps2");
            {
              py::gil_scoped_release release;
              s.session->AddAccelerometer(t, a);
            }
            return EstimateOrNone(*s.session);
          },
          py::arg("t_s"), py::arg("acc_mps2"), "Accelerometer sample: specific force (3,) [m/s²], device frame.")
      .def(
          "add_gyroscope",
          [](PyLiveSession& s, const py::object& t_s, const py::object& gyro) {
            s.session->AddGyroscope(Time(t_s, "t_s"), Vector3(gyro, "gyro_radps"));
            return EstimateOrNone(*s.session);
          },
          py::arg("t_s"), py::arg("gyro_radps"), "Gyroscope sample: angular rate (3,) [rad/s], device frame.")
      .def(
          "add_rotation_vector",
          [](PyLiveSession& s, const py::object& t_s, const py::object& values) {
            const VectorArg v = ToVector(values, "values", -1, Finiteness::kAny);
            s.session->AddRotationVector(Time(t_s, "t_s"), v.map);
            return EstimateOrNone(*s.session);
          },
          py::arg("t_s"), py::arg("values"), "Android rotation vector (x, y, z[, w[, accuracy]]).")
      .def(
          "add_wifi_scan",
          [](PyLiveSession& s, const py::object& t_s, const std::vector<std::string>& bssids, const py::object& rssi,
             const py::object& last_seen) {
            const double t = Time(t_s, "t_s");
            const VectorArg r = ToVector(rssi, "rssi_dbm", -1, Finiteness::kAny);
            const VectorArg l = ToVector(last_seen, "last_seen_s", -1, Finiteness::kAny);
            {
              py::gil_scoped_release release;
              s.session->AddWifiScan(t, bssids, r.map, l.map);
            }
            return EstimateOrNone(*s.session);
          },
          py::arg("t_s"), py::arg("bssids"), py::arg("rssi_dbm"), py::arg("last_seen_s"),
          "One WiFi scan reported at t_s: per reading its BSSID, RSSI [dBm] and last-seen time [s].")
      .def(
          "add_beacon",
          [](PyLiveSession& s, const py::object& t_s) {
            s.session->AddBeacon(Time(t_s, "t_s"));
            return EstimateOrNone(*s.session);
          },
          py::arg("t_s"), "An iBeacon reading: accepted (time order checked) and ignored.")
      .def("estimate", [](const PyLiveSession& s) { return EstimateOrNone(*s.session); },
           "The current estimate, None before the first step.")
      .def_property_readonly("events", [](const PyLiveSession& s) { return s.session->Summary().events; },
                             "Events accepted.")
      .def_property_readonly(
          "summary",
          [](const PyLiveSession& s) {
            const LiveSessionSummary u = s.session->Summary();
            py::dict d;
            d["events"] = u.events;
            d["imu_samples"] = u.imu_samples;
            d["steps"] = u.steps;
            d["standing_steps"] = u.standing_steps;
            d["late_steps"] = u.late_steps;
            d["scans"] = u.scans;
            d["fixes"] = u.fixes;
            d["pending_fixes"] = u.pending_fixes;
            d["unknown_wifi_readings"] = u.unknown_wifi_readings;
            return d;
          },
          "Events, IMU samples, steps detected, standing steps, detected steps moved to a standing "
          "step's later time, scans, fixes applied and pending, WiFi readings of BSSIDs not in the map "
          "(dropped).")
      .def_property_readonly(
          "filter", [](const PyLiveSession& s) -> const GridFilterSession& { return s.session->filter(); },
          py::return_value_policy::reference_internal, "The GridFilterSession inside (steps, summary).")
      .def_property_readonly("floors", [](const PyLiveSession& s) { return s.session->floors(); },
                             "Floor numbers of the plan (the order of floor_probabilities).")
      .def_property_readonly("options", [](const PyLiveSession& s) { return s.session->options(); });
}

}  // namespace indoorloc::bindings
