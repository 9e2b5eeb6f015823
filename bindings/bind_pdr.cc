// Python bindings of the pdr subsystem: zero-velocity detection and the ZUPT-aided EKF.
#include <cmath>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/core/options.h"
#include "indoorloc/pdr/step_detection.h"
#include "indoorloc/pdr/stride_length.h"
#include "indoorloc/pdr/zero_velocity.h"
#include "indoorloc/pdr/zupt_ekf.h"
#include "numpy_args.h"

namespace indoorloc::bindings {

namespace {
pdr::ShoeOptions MakeShoe(int window, double threshold, double sigma_acc, double sigma_gyro, double gravity) {
  pdr::ShoeOptions o;
  o.window = window;
  o.threshold = threshold;
  o.sigma_acc_mps2 = sigma_acc;
  o.sigma_gyro_radps = sigma_gyro;
  o.gravity_mps2 = gravity;
  ValidateOptions(o);
  return o;
}
constexpr double kDeg = 3.14159265358979323846 / 180.0;

// An (M, 2) array of integer sample indices, given as any numeric array.
Eigen::MatrixXi ToIndexPairs(const py::object& obj, const char* name) {
  MatrixArg m = ToMatrix(obj, name, -1, 2);
  Eigen::MatrixXi out(m.map.rows(), 2);
  for (Eigen::Index i = 0; i < m.map.rows(); ++i) {
    for (int j = 0; j < 2; ++j) {
      const double v = m.map(i, j);
      CheckArgument(v == std::floor(v) && std::abs(v) < 2e9, name, "entries must be integer sample indices");
      out(i, j) = static_cast<int>(v);
    }
  }
  return out;
}

std::vector<int> ToIndices(const py::object& obj, const char* name) {
  VectorArg v = ToVector(obj, name);
  std::vector<int> out(static_cast<size_t>(v.map.size()));
  for (Eigen::Index i = 0; i < v.map.size(); ++i) {
    const double x = v.map[i];
    CheckArgument(x == std::floor(x) && std::abs(x) < 2e9, name, "entries must be integer sample indices");
    out[static_cast<size_t>(i)] = static_cast<int>(x);
  }
  return out;
}

pdr::WeinbergOptions MakeWeinberg(double k, int order, double cutoff_hz, double window_s, bool steady) {
  pdr::WeinbergOptions o;
  o.k = k;
  o.filter_order = order;
  o.cutoff_hz = cutoff_hz;
  o.window_s = window_s;
  o.steady_state_start = steady;
  return o;
}

py::dict CalibrationDict(const pdr::WeinbergCalibration& c) {
  py::dict d;
  d["k"] = c.k;
  d["rms_residual_m"] = c.rms_residual_m;
  d["n_strides"] = c.n_strides;
  d["report"] = c.BriefReport();
  return d;
}
}  // namespace

void BindPdr(py::module_& m) {
  m.def("shoe_statistic", [](const py::object& acc, const py::object& gyro, int window, double sigma_acc, double sigma_gyro,
                             double gravity) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          MatrixArg g = ToMatrix(gyro, "gyro_radps", a.map.rows(), 3);
          const pdr::ShoeOptions o = MakeShoe(window, 1.0, sigma_acc, sigma_gyro, gravity);
          py::gil_scoped_release release;
          return pdr::ShoeStatistic(a.map, g.map, o);
        },
        py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("window") = 5, py::arg("sigma_acc_mps2") = 0.01,
        py::arg("sigma_gyro_radps") = 0.1 * kDeg, py::arg("gravity_mps2") = 9.81,
        "SHOE test statistic (N,) of specific force (N, 3) [m/s^2] and angular rate (N, 3) [rad/s].");
  m.def("shoe_detector", [](const py::object& acc, const py::object& gyro, int window, double threshold, double sigma_acc,
                            double sigma_gyro, double gravity) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          MatrixArg g = ToMatrix(gyro, "gyro_radps", a.map.rows(), 3);
          const pdr::ShoeOptions o = MakeShoe(window, threshold, sigma_acc, sigma_gyro, gravity);
          py::gil_scoped_release release;
          return pdr::ShoeDetector(a.map, g.map, o);
        },
        py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("window") = 5, py::arg("threshold") = 3e4,
        py::arg("sigma_acc_mps2") = 0.01, py::arg("sigma_gyro_radps") = 0.1 * kDeg, py::arg("gravity_mps2") = 9.81, R"doc(
Stance flags (N,) bool of the SHOE zero-velocity detector (Skog et al. 2010): statistic < threshold.
acc_mps2, gyro_radps: (N, 3) in the sensor frame [m/s^2], [rad/s]; window in samples.)doc");
  m.def("steps_acceleration", [](const py::object& acc, double rate_hz, double window_s, bool adaptive, double swing_threshold,
                                 double stance_threshold, double swing_fraction, double stance_fraction, double min_step_interval_s) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          pdr::AccelerationStepOptions o;
          o.window_s = window_s;
          o.adaptive = adaptive;
          o.swing_threshold_mps2 = swing_threshold;
          o.stance_threshold_mps2 = stance_threshold;
          o.swing_fraction = swing_fraction;
          o.stance_fraction = stance_fraction;
          o.min_step_interval_s = min_step_interval_s;
          Eigen::VectorXd sigma;
          const std::vector<int> steps = pdr::DetectStepsAcceleration(rate_hz, a.map, o, &sigma);
          return py::make_tuple(steps, sigma);
        },
        py::arg("acc_mps2"), py::arg("rate_hz"), py::arg("window_s") = 0.1, py::arg("adaptive") = true,
        py::arg("swing_threshold_mps2") = 2.0, py::arg("stance_threshold_mps2") = 1.0, py::arg("swing_fraction") = 0.35,
        py::arg("stance_fraction") = 0.15, py::arg("min_step_interval_s") = 0.4, R"doc(
Paper 002's acceleration-variance step detector (eq. 1-3). Returns (step sample indices, σ (N,)
[m/s^2]). adaptive=True: thresholds = fractions of the 95th percentile of σ; False: the fixed
T1, T2 [m/s^2] (paper: 2 and 1 at 100 Hz).)doc");
  m.def("steps_gyro", [](const py::object& gyro, double rate_hz, double threshold, double median_window_s, double min_swing_s) {
          MatrixArg g = ToMatrix(gyro, "gyro_radps", -1, 3);
          pdr::GyroStepOptions o;
          o.threshold_radps = threshold;
          o.median_window_s = median_window_s;
          o.min_swing_s = min_swing_s;
          return pdr::DetectStepsGyro(rate_hz, g.map, o);
        },
        py::arg("gyro_radps"), py::arg("rate_hz"), py::arg("threshold_radps") = 1.0, py::arg("median_window_s") = 0.1,
        py::arg("min_swing_s") = 0.2, "Gyroscope step detector (paper 002 §III.D): step sample indices.");
  m.def("butterworth_sos", &pdr::ButterworthSos, py::arg("order"), py::arg("cutoff_hz"), py::arg("rate_hz"),
        py::arg("highpass") = false, R"doc(
Butterworth filter as second-order sections, shape (ceil(order/2), 6), rows [b0 b1 b2 a0 a1 a2]
(scipy's sos layout; the same transfer function as scipy.signal.butter(order, cutoff_hz,
fs=rate_hz)). cutoff_hz and rate_hz in Hz, 0 < cutoff_hz < rate_hz / 2.)doc");
  m.def("sos_filter", [](const py::object& sos, const py::object& x, bool steady_state_start) {
          MatrixArg s = ToMatrix(sos, "sos", -1, 6);
          VectorArg v = ToVector(x, "x");
          return pdr::FilterSos(s.map, v.map, steady_state_start);
        },
        py::arg("sos"), py::arg("x"), py::arg("steady_state_start") = false, R"doc(
Runs second-order sections (M, 6) over x (N,) (transposed direct form II). Equals
scipy.signal.sosfilt(sos, x), or with steady_state_start=True sosfilt(sos, x,
zi=sosfilt_zi(sos) * x[0]).)doc");
  m.def("weinberg_features", [](const py::object& acc, double rate_hz, const py::object& intervals, int order, double cutoff_hz,
                                bool steady) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          const Eigen::MatrixXi iv = ToIndexPairs(intervals, "intervals");
          const pdr::WeinbergOptions o = MakeWeinberg(1.0, order, cutoff_hz, 0.15, steady);
          py::gil_scoped_release release;
          return pdr::WeinbergFeatures(rate_hz, a.map, iv, o);
        },
        py::arg("acc_mps2"), py::arg("rate_hz"), py::arg("intervals"), py::arg("filter_order") = 4, py::arg("cutoff_hz") = 3.0,
        py::arg("steady_state_start") = true, R"doc(
Weinberg bounce feature (max a~ - min a~)^(1/4) [(m/s^2)^(1/4)] over each interval (M, 2) of
inclusive sample indices [start, end], with a~ the Butterworth low-pass (order, cutoff_hz [Hz])
of |acc_mps2| (N, 3) [m/s^2] sampled at rate_hz [Hz]. Stride length = K x feature (eq. 4).)doc");
  m.def("weinberg_stride_lengths", [](const py::object& acc, double rate_hz, const py::object& step_indices, double k,
                                      double window_s, int order, double cutoff_hz, bool steady) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          const std::vector<int> steps = ToIndices(step_indices, "step_indices");
          const pdr::WeinbergOptions o = MakeWeinberg(k, order, cutoff_hz, window_s, steady);
          py::gil_scoped_release release;
          return pdr::WeinbergStrideLengths(rate_hz, a.map, steps, o);
        },
        py::arg("acc_mps2"), py::arg("rate_hz"), py::arg("step_indices"), py::arg("k") = 0.364, py::arg("window_s") = 0.15,
        py::arg("filter_order") = 4, py::arg("cutoff_hz") = 3.0, py::arg("steady_state_start") = true, R"doc(
Weinberg stride lengths [m] (paper 002 eq. 4), one per step: K (max - min)^(1/4) of the 3 Hz
low-passed |acc| [m/s^2] over +-window_s [s] around each step sample (strictly increasing
indices into acc_mps2 (N, 3)). K [m/(m/s^2)^(1/4)]: 0.364 in the paper (foot); calibrate it with
calibrate_weinberg_k.)doc");
  m.def("calibrate_weinberg_k", [](const py::object& features, const py::object& lengths) {
          VectorArg f = ToVector(features, "features");
          VectorArg l = ToVector(lengths, "lengths_m", f.map.size());
          return CalibrationDict(pdr::CalibrateWeinbergK(f.map, l.map));
        },
        py::arg("features"), py::arg("lengths_m"), R"doc(
Least-squares Weinberg K = sum(f L) / sum(f^2) from bounce features f (M,) and known stride
lengths L (M,) [m]. Returns a dict: k, rms_residual_m, n_strides, report.)doc");
  m.def("calibrate_weinberg_k_from_distance", [](const py::object& features, double distance_m) {
          VectorArg f = ToVector(features, "features");
          return CalibrationDict(pdr::CalibrateWeinbergKFromDistance(f.map, distance_m));
        },
        py::arg("features"), py::arg("distance_m"), R"doc(
Weinberg K = D / sum(f) from the bounce features (M,) of a walk of known length D [m].
Returns a dict: k, rms_residual_m (0), n_strides, report.)doc");
  m.def("zupt_ekf", [](const py::object& time_s, const py::object& acc, const py::object& gyro, const py::object& stance,
                       double sigma_acc, double sigma_gyro, double sigma_zupt, double gravity, int init_samples, bool smooth) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          MatrixArg g = ToMatrix(gyro, "gyro_radps", a.map.rows(), 3);
          VectorArg t = ToVector(time_s, "time_s", a.map.rows());
          VectorArg s = ToVector(stance, "stance", a.map.rows());
          const pdr::BoolVector st = (s.map.array() != 0.0).matrix();
          pdr::ZuptEkfOptions o;
          o.sigma_acc_mps2 = sigma_acc;
          o.sigma_gyro_radps = sigma_gyro;
          o.sigma_zupt_mps = sigma_zupt;
          o.gravity_mps2 = gravity;
          o.init_samples = init_samples;
          o.smooth = smooth;
          pdr::ZuptEkfOutput out;
          {
            py::gil_scoped_release release;
            out = pdr::RunZuptEkf(t.map, a.map, g.map, st, o);
          }
          py::dict d;
          d["positions_m"] = out.positions_m;
          d["filtered_positions_m"] = out.filtered_positions_m;
          d["velocities_mps"] = out.velocities_mps;
          d["headings_rad"] = out.headings_rad;
          d["position_sd_m"] = out.position_sd_m;
          d["seconds"] = out.seconds;
          return d;
        },
        py::arg("time_s"), py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("stance"), py::arg("sigma_acc_mps2") = 0.5,
        py::arg("sigma_gyro_radps") = 0.5 * kDeg, py::arg("sigma_zupt_mps") = 0.01, py::arg("gravity_mps2") = 9.81,
        py::arg("init_samples") = 20, py::arg("smooth") = false, R"doc(
Zero-velocity-aided strapdown INS (9-state error-state EKF, OpenShoe/PyShoe style) over a
recording: time_s (N,) [s], acc_mps2 and gyro_radps (N, 3) sensor frame, stance (N,) bool.
smooth=True adds the RTS smoother (positions_m smoothed, filtered_positions_m the EKF's).
Returns a dict: positions_m (N, 3) (z up, start at 0, initial yaw 0), velocities_mps (N, 3),
headings_rad (N,), position_sd_m (N, 3), seconds.)doc");
}

}  // namespace indoorloc::bindings
