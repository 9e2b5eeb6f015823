// Python bindings of the pdr subsystem: zero-velocity detection and the ZUPT-aided EKF.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/core/options.h"
#include "indoorloc/pdr/step_detection.h"
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
