// Python bindings of the pdr subsystem: zero-velocity detection and the ZUPT-aided EKF.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/core/options.h"
#include "indoorloc/pdr/attitude_filter.h"
#include "indoorloc/pdr/step_detection.h"
#include "indoorloc/pdr/step_positioning.h"
#include "indoorloc/pdr/stride_count.h"
#include "indoorloc/pdr/stride_length.h"
#include "indoorloc/pdr/zero_velocity.h"
#include "indoorloc/pdr/zupt_ekf.h"
#include "numpy_args.h"
#include "result_binding.h"

namespace indoorloc::bindings {

// The result types of the pdr functions (bind_pdr_results.cc).
void BindPdrResults(py::module_& m);

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

pdr::StepCovarianceOptions MakeStepCov(double sd_sl, double sd_frac, double sd_psi, double sd_psi0) {
  pdr::StepCovarianceOptions o;
  o.sigma_stride_length_m = sd_sl;
  o.stride_length_sd_fraction = sd_frac;
  o.sigma_heading_step_rad = sd_psi;
  o.sigma_heading_initial_rad = sd_psi0;
  return o;
}

Eigen::Vector2d ToStart(const py::object& start) {
  VectorArg v = ToVector(start, "start_xy", 2);
  return Eigen::Vector2d(v.map[0], v.map[1]);
}

/// The name zero_velocity's `rule` argument gives a rule.
const char* ZeroVelocityRuleName(pdr::ZeroVelocityRule rule) {
  switch (rule) {
    case pdr::ZeroVelocityRule::kFixed: return "fixed";
    case pdr::ZeroVelocityRule::kStanceGuard: return "stance_guard";
    case pdr::ZeroVelocityRule::kSwingGuard: break;
  }
  return "swing_guard";
}

}  // namespace

/// Stance detection (SHOE and the adaptive detector) and stride counting.
static void BindZeroVelocity(py::module_& m) {
  const pdr::ShoeOptions shoe;
  const pdr::ZeroVelocityOptions zero_velocity;
  const pdr::StrideCountOptions stride_count;
  m.def("shoe_statistic", [](const py::object& acc, const py::object& gyro, int window, double sigma_acc, double sigma_gyro,
                             double gravity) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          MatrixArg g = ToMatrix(gyro, "gyro_radps", a.map.rows(), 3);
          const pdr::ShoeOptions o = MakeShoe(window, 1.0, sigma_acc, sigma_gyro, gravity);
          py::gil_scoped_release release;
          return pdr::ShoeStatistic(a.map, g.map, o);
        },
        py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("window") = shoe.window, py::arg("sigma_acc_mps2") = shoe.sigma_acc_mps2,
        py::arg("sigma_gyro_radps") = shoe.sigma_gyro_radps, py::arg("gravity_mps2") = shoe.gravity_mps2,
        "SHOE test statistic (N,) of specific force (N, 3) [m/s^2] and angular rate (N, 3) [rad/s].");
  m.def("shoe_detector", [](const py::object& acc, const py::object& gyro, int window, double threshold, double sigma_acc,
                            double sigma_gyro, double gravity) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          MatrixArg g = ToMatrix(gyro, "gyro_radps", a.map.rows(), 3);
          const pdr::ShoeOptions o = MakeShoe(window, threshold, sigma_acc, sigma_gyro, gravity);
          py::gil_scoped_release release;
          return pdr::ShoeDetector(a.map, g.map, o);
        },
        py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("window") = shoe.window, py::arg("threshold") = shoe.threshold,
        py::arg("sigma_acc_mps2") = shoe.sigma_acc_mps2, py::arg("sigma_gyro_radps") = shoe.sigma_gyro_radps, py::arg("gravity_mps2") = shoe.gravity_mps2, R"doc(
Stance flags (N,) bool of the SHOE zero-velocity detector (Skog et al. 2010): statistic < threshold.
acc_mps2, gyro_radps: (N, 3) in the sensor frame [m/s^2], [rad/s]; window in samples.)doc");
  m.def("zero_velocity", [](const py::object& acc, const py::object& gyro, double rate_hz, const std::string& rule,
                            double threshold, double max_swing_s, double max_swing_ratio, double ladder_step_decades,
                            double min_stance_s, double min_stance_share, double min_stance_fraction, double max_threshold,
                            double min_plausible_swing_s, double low_motion_min_stance_s, int window, double sigma_acc,
                            double sigma_gyro, double gravity) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          MatrixArg g = ToMatrix(gyro, "gyro_radps", a.map.rows(), 3);
          pdr::ZeroVelocityOptions o;
          o.shoe = MakeShoe(window, threshold, sigma_acc, sigma_gyro, gravity);
          if (rule == "fixed") {
            o.rule = pdr::ZeroVelocityRule::kFixed;
          } else if (rule == "swing_guard") {
            o.rule = pdr::ZeroVelocityRule::kSwingGuard;
          } else if (rule == "stance_guard") {
            o.rule = pdr::ZeroVelocityRule::kStanceGuard;
          } else {
            ThrowInvalidArgument("rule", "must be 'swing_guard', 'stance_guard' or 'fixed', got '" + rule + "'");
          }
          o.max_swing_s = max_swing_s;
          o.max_swing_ratio = max_swing_ratio;
          o.ladder_step_decades = ladder_step_decades;
          o.min_stance_s = min_stance_s;
          o.min_stance_share = min_stance_share;
          o.min_stance_fraction = min_stance_fraction;
          o.max_threshold = max_threshold;
          o.min_plausible_swing_s = min_plausible_swing_s;
          o.low_motion_min_stance_s = low_motion_min_stance_s;
          ValidateOptions(o);
          pdr::ZeroVelocityOutput out;
          {
            py::gil_scoped_release release;
            out = pdr::DetectZeroVelocity(a.map, g.map, rate_hz, o);
          }
          return out;
        },
        py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("rate_hz"), py::arg("rule") = std::string(ZeroVelocityRuleName(zero_velocity.rule)),
        py::arg("threshold") = zero_velocity.shoe.threshold, py::arg("max_swing_s") = zero_velocity.max_swing_s, py::arg("max_swing_ratio") = zero_velocity.max_swing_ratio,
        py::arg("ladder_step_decades") = zero_velocity.ladder_step_decades, py::arg("min_stance_s") = zero_velocity.min_stance_s, py::arg("min_stance_share") = zero_velocity.min_stance_share,
        py::arg("min_stance_fraction") = zero_velocity.min_stance_fraction,
        py::arg("max_threshold") = zero_velocity.max_threshold,
        py::arg("min_plausible_swing_s") = zero_velocity.min_plausible_swing_s,
        py::arg("low_motion_min_stance_s") = zero_velocity.low_motion_min_stance_s, py::arg("window") = zero_velocity.shoe.window, py::arg("sigma_acc_mps2") = zero_velocity.shoe.sigma_acc_mps2,
        py::arg("sigma_gyro_radps") = zero_velocity.shoe.sigma_gyro_radps, py::arg("gravity_mps2") = zero_velocity.shoe.gravity_mps2, R"doc(
Zero-velocity detection with the SHOE threshold adapted to the recording (C++ DetectZeroVelocity).
acc_mps2, gyro_radps: (N, 3) sensor frame [m/s^2], [rad/s]; rate_hz [Hz]; window in samples.
rule "swing_guard" (default, chosen by cross-validation): the threshold climbs the ladder
threshold * 10^(j * ladder_step_decades) up to max_threshold and stops at the first rung where
no swing (non-stance between two stance phases; stance flicker shorter than min_stance_s [s]
ignored) is longer than max_swing_s [s] or than max_swing_ratio times the median swing, and at
least min_stance_share of all samples are stance, and the median swing lasts at least
min_plausible_swing_s [s] (shorter swings are no human gait: such rungs are refused). Stance
runs shorter than min_stance_s inside a swing are dropped from the returned stance. When no rung
is accepted, the low-motion rule climbs again ignoring stance shorter than
low_motion_min_stance_s [s]; failing that the most regular plausible rung is used and
guard_satisfied is False.
"stance_guard": raised to the min_stance_fraction-quantile of the statistic over the walking
span. "fixed": statistic < threshold. Returns a ZeroVelocityOutput (reads as a dict): stance (N,) bool, statistic (N,),
threshold (used), base_threshold, guard_raised, guard_satisfied, low_motion_rule, flicker_s [s],
ladder_rungs, max_swing_s,
median_swing_s [s], stance_fraction, walking_stance_fraction [0..1], walking_span, report.)doc");
  m.def("count_strides", [](const py::object& stance, double rate_hz, double min_stance_s, double min_swing_s,
                            double min_swing_fraction, double long_swing_factor) {
          VectorArg s = ToVector(stance, "stance");
          const pdr::BoolVector st = (s.map.array() != 0.0).matrix();
          pdr::StrideCountOptions o;
          o.min_stance_s = min_stance_s;
          o.min_swing_s = min_swing_s;
          o.min_swing_fraction = min_swing_fraction;
          o.long_swing_factor = long_swing_factor;
          ValidateOptions(o);
          pdr::StrideCountOutput out = pdr::CountStrides(st, rate_hz, o);
          return out;
        },
        py::arg("stance"), py::arg("rate_hz"), py::arg("min_stance_s") = stride_count.min_stance_s, py::arg("min_swing_s") = stride_count.min_swing_s,
        py::arg("min_swing_fraction") = stride_count.min_swing_fraction, py::arg("long_swing_factor") = stride_count.long_swing_factor, R"doc(
Strides of the instrumented foot from stance flags (N,) sampled at rate_hz [Hz] (C++ CountStrides):
stance runs shorter than min_stance_s [s] inside a swing are flicker; swing runs shorter than
max(min_swing_s [s], min_swing_fraction x the recording's median swing) inside a stance are
flicker; a swing longer than long_swing_factor x the median swing (0 disables) counts as
round(length / median) strides. Returns a StrideCountOutput (reads as a dict): stride_indices (S,) int64 stance onsets,
cleaned_stance (N,) bool, n_strides, n_flicker_stances, n_flicker_swings, n_split_strides,
median_swing_s, median_stance_s [s], report.)doc");
}

/// Step detectors, filters and the Weinberg stride length.
static void BindStepDetection(py::module_& m) {
  const pdr::AccelerationStepOptions acceleration_steps;
  const pdr::GyroStepOptions gyro_steps;
  const pdr::WeinbergOptions weinberg;
  const pdr::MagneticStepOptions magnetic_steps;
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
        py::arg("acc_mps2"), py::arg("rate_hz"), py::arg("window_s") = acceleration_steps.window_s, py::arg("adaptive") = acceleration_steps.adaptive,
        py::arg("swing_threshold_mps2") = acceleration_steps.swing_threshold_mps2, py::arg("stance_threshold_mps2") = acceleration_steps.stance_threshold_mps2, py::arg("swing_fraction") = acceleration_steps.swing_fraction,
        py::arg("stance_fraction") = acceleration_steps.stance_fraction, py::arg("min_step_interval_s") = acceleration_steps.min_step_interval_s, R"doc(
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
        py::arg("gyro_radps"), py::arg("rate_hz"), py::arg("threshold_radps") = gyro_steps.threshold_radps, py::arg("median_window_s") = gyro_steps.median_window_s,
        py::arg("min_swing_s") = gyro_steps.min_swing_s, "Gyroscope step detector (paper 002 §III.D): step sample indices.");
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
        py::arg("acc_mps2"), py::arg("rate_hz"), py::arg("intervals"), py::arg("filter_order") = weinberg.filter_order, py::arg("cutoff_hz") = weinberg.cutoff_hz,
        py::arg("steady_state_start") = weinberg.steady_state_start, R"doc(
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
        py::arg("acc_mps2"), py::arg("rate_hz"), py::arg("step_indices"), py::arg("k") = weinberg.k, py::arg("window_s") = weinberg.window_s,
        py::arg("filter_order") = weinberg.filter_order, py::arg("cutoff_hz") = weinberg.cutoff_hz, py::arg("steady_state_start") = weinberg.steady_state_start, R"doc(
Weinberg stride lengths [m] (paper 002 eq. 4), one per step: K (max - min)^(1/4) of the 3 Hz
low-passed |acc| [m/s^2] over +-window_s [s] around each step sample (strictly increasing
indices into acc_mps2 (N, 3)). K [m/(m/s^2)^(1/4)]: 0.364 in the paper (foot); calibrate it with
calibrate_weinberg_k.)doc");
  m.def("calibrate_weinberg_k", [](const py::object& features, const py::object& lengths) {
          VectorArg f = ToVector(features, "features");
          VectorArg l = ToVector(lengths, "lengths_m", f.map.size());
          return pdr::CalibrateWeinbergK(f.map, l.map);
        },
        py::arg("features"), py::arg("lengths_m"), R"doc(
Least-squares Weinberg K = sum(f L) / sum(f^2) from bounce features f (M,) and known stride
lengths L (M,) [m]. Returns a WeinbergCalibration (reads as a dict): k, rms_residual_m, n_strides, report.)doc");
  m.def("calibrate_weinberg_k_from_distance", [](const py::object& features, double distance_m) {
          VectorArg f = ToVector(features, "features");
          return pdr::CalibrateWeinbergKFromDistance(f.map, distance_m);
        },
        py::arg("features"), py::arg("distance_m"), R"doc(
Weinberg K = D / sum(f) from the bounce features (M,) of a walk of known length D [m].
Returns a WeinbergCalibration (reads as a dict): k, rms_residual_m (0), n_strides, report.)doc");
  m.def("steps_magnetometer", [](const py::object& mag, double rate_hz, int order, double highpass_hz, double fraction,
                                 double median_window_s, double min_swing_s, double min_rest_s) {
          MatrixArg g = ToMatrix(mag, "mag", -1, 3);
          pdr::MagneticStepOptions o;
          o.highpass_order = order;
          o.highpass_hz = highpass_hz;
          o.threshold_fraction = fraction;
          o.median_window_s = median_window_s;
          o.min_swing_s = min_swing_s;
          o.min_rest_s = min_rest_s;
          Eigen::VectorXd magnitude;
          const std::vector<int> steps = pdr::DetectStepsMagnetometer(rate_hz, g.map, o, &magnitude);
          return py::make_tuple(steps, magnitude);
        },
        py::arg("mag"), py::arg("rate_hz"), py::arg("highpass_order") = magnetic_steps.highpass_order, py::arg("highpass_hz") = magnetic_steps.highpass_hz,
        py::arg("threshold_fraction") = magnetic_steps.threshold_fraction, py::arg("median_window_s") = magnetic_steps.median_window_s, py::arg("min_swing_s") = magnetic_steps.min_swing_s,
        py::arg("min_rest_s") = magnetic_steps.min_rest_s, R"doc(
Magnetometer step detector (paper 002 §III.D): Butterworth high-pass (order, highpass_hz [Hz])
per axis of mag (N, 3) (any unit, e.g. uT), |m_hp| thresholded at threshold_fraction x its 95th
percentile, median filter (median_window_s [s]), rests shorter than min_rest_s [s] merged, a step at
each transition to rest after at least min_swing_s [s] of motion. Returns (step sample indices,
|m_hp| (N,) in the unit of mag).)doc");
}

/// Attitude, stance headings and positions from strides or increments.
static void BindAttitudeAndPositions(py::module_& m) {
  const pdr::MahonyOptions mahony;
  const pdr::StepCovarianceOptions step_covariance;
  const pdr::InsZuptOptions ins_zupt;
  m.def("attitude_mahony", [](const py::object& time_s, const py::object& acc, const py::object& gyro, const py::object& mag,
                              double kp, double ki, double kp_mag, double gravity, double acc_gate, double norm_tol,
                              double dip_tol, int init_samples) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          MatrixArg g = ToMatrix(gyro, "gyro_radps", a.map.rows(), 3);
          VectorArg t = ToVector(time_s, "time_s", a.map.rows());
          RowMatrixXd m(0, 3);
          if (!mag.is_none()) {
            MatrixArg mm = ToMatrix(mag, "mag", a.map.rows(), 3);
            m = mm.map;
          }
          pdr::MahonyOptions o;
          o.kp = kp;
          o.ki = ki;
          o.kp_mag = kp_mag;
          o.gravity_mps2 = gravity;
          o.acc_gate_mps2 = acc_gate;
          o.mag_norm_tolerance = norm_tol;
          o.mag_dip_tolerance_rad = dip_tol;
          o.init_samples = init_samples;
          pdr::AttitudeOutput out;
          {
            py::gil_scoped_release release;
            out = pdr::RunMahony(t.map, a.map, g.map, m, o);
          }
          return out;
        },
        py::arg("time_s"), py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("mag") = py::none(), py::arg("kp") = mahony.kp,
        py::arg("ki") = mahony.ki, py::arg("kp_mag") = mahony.kp_mag, py::arg("gravity_mps2") = mahony.gravity_mps2, py::arg("acc_gate_mps2") = mahony.acc_gate_mps2,
        py::arg("mag_norm_tolerance") = mahony.mag_norm_tolerance, py::arg("mag_dip_tolerance_rad") = mahony.mag_dip_tolerance_rad, py::arg("init_samples") = mahony.init_samples, R"doc(
Mahony complementary attitude filter (gyro + gravity, magnetometer optional, heading-only and
gated by a disturbance test on the field norm and dip). time_s (N,) [s], acc_mps2 (N, 3) [m/s^2],
gyro_radps (N, 3) [rad/s], mag (N, 3) any unit or None. Gains kp, kp_mag [rad/s], ki [rad/s^2].
Returns an AttitudeOutput (reads as a dict): quaternions_wxyz (N, 4) body -> navigation (z up; x = initial heading, or
magnetic north with mag), gyro_bias_radps (N, 3), mag_used (N,) bool, mag_rejected,
reference_field_norm, reference_dip_rad, seconds.)doc");
  m.def("stance_headings", [](const py::object& quaternions, const py::object& step_indices) {
          MatrixArg q = ToMatrix(quaternions, "quaternions_wxyz", -1, 4);
          return pdr::StanceHeadings(q.map, ToIndices(step_indices, "step_indices"));
        },
        py::arg("quaternions_wxyz"), py::arg("step_indices"), R"doc(
Paper 002 eq. 7: heading [rad] of the sensor x axis, atan2(X_y, X_x) with X = R e_x, at each
step sample; quaternions_wxyz (N, 4) body -> navigation (z up).)doc");
  m.def("positions_from_strides", [](const py::object& sl, const py::object& headings, const py::object& start,
                                     double sd_sl, double sd_frac, double sd_psi, double sd_psi0) {
          VectorArg l = ToVector(sl, "stride_lengths_m");
          VectorArg h = ToVector(headings, "headings_rad", l.map.size());
          return (pdr::PositionsFromStrides(l.map, h.map, ToStart(start), MakeStepCov(sd_sl, sd_frac, sd_psi, sd_psi0)));
        },
        py::arg("stride_lengths_m"), py::arg("headings_rad"), py::arg("start_xy") = std::vector<double>{0.0, 0.0},
        py::arg("sigma_stride_length_m") = step_covariance.sigma_stride_length_m, py::arg("stride_length_sd_fraction") = step_covariance.stride_length_sd_fraction,
        py::arg("sigma_heading_step_rad") = step_covariance.sigma_heading_step_rad, py::arg("sigma_heading_initial_rad") = step_covariance.sigma_heading_initial_rad, R"doc(
Paper 002 eq. 8: P_k = P_{k-1} + SL_k (cos th_k, sin th_k) from stride lengths (M,) [m] and
headings (M,) [rad], starting at start_xy [m]. Each step carries the 3 x 3 covariance of
(x [m], y [m], heading error [rad]) under a heading random walk (sigma_heading_step_rad per step)
and stride-length noise (sigma_stride_length_m + stride_length_sd_fraction x SL). Returns a
StepTrack (reads as a dict): positions_m (M, 2), covariances (M, 3, 3), stride_lengths_m, headings_rad.)doc");
  m.def("positions_from_increments", [](const py::object& inc, const py::object& start, double sd_sl, double sd_frac,
                                        double sd_psi, double sd_psi0) {
          MatrixArg d = ToMatrix(inc, "increments_m");
          return (pdr::PositionsFromIncrements(d.map, ToStart(start), MakeStepCov(sd_sl, sd_frac, sd_psi, sd_psi0)));
        },
        py::arg("increments_m"), py::arg("start_xy") = std::vector<double>{0.0, 0.0}, py::arg("sigma_stride_length_m") = step_covariance.sigma_stride_length_m,
        py::arg("stride_length_sd_fraction") = step_covariance.stride_length_sd_fraction, py::arg("sigma_heading_step_rad") = step_covariance.sigma_heading_step_rad,
        py::arg("sigma_heading_initial_rad") = step_covariance.sigma_heading_initial_rad, R"doc(
Paper 002 eq. 9: P_k = P_{k-1} + dP_k(x, y) from INS-ZUPT increments (M, 2) or (M, 3) [m], with
the per-step covariance of positions_from_strides (SL = |dP_xy|, heading = atan2(dP_y, dP_x)).)doc");
  m.def("ins_zupt_increments", [](const py::object& time_s, const py::object& acc, const py::object& quaternions,
                                  const py::object& step_indices, double window_s, double gravity) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          VectorArg t = ToVector(time_s, "time_s", a.map.rows());
          MatrixArg q = ToMatrix(quaternions, "quaternions_wxyz", a.map.rows(), 4);
          const std::vector<int> steps = ToIndices(step_indices, "step_indices");
          pdr::InsZuptOptions o;
          o.window_s = window_s;
          o.gravity_mps2 = gravity;
          pdr::InsZuptIncrements out;
          {
            py::gil_scoped_release release;
            out = pdr::ComputeInsZuptIncrements(t.map, a.map, q.map, steps, o);
          }
          return out;
        },
        py::arg("time_s"), py::arg("acc_mps2"), py::arg("quaternions_wxyz"), py::arg("step_indices"), py::arg("window_s") = ins_zupt.window_s,
        py::arg("gravity_mps2") = ins_zupt.gravity_mps2, R"doc(
Paper 002 §IV.B (steps 1-5, eq. 5-6): rotate acc_mps2 (N, 3) [m/s^2] by quaternions_wxyz (N, 4)
(body -> navigation, z up), remove gravity, integrate from the first step, remove the drift by
the mean velocity over +-window_s [s] around each step sample, linearly interpolated between
steps, and sum each step. step_indices: M >= 2 strictly increasing stance samples. Returns an
InsZuptIncrements (reads as a dict): increments_m (M-1, 3), stride_lengths_m (M-1,) (eq. 6), velocities_mps (N, 3).)doc");
}

/// The ZUPT-aided INS.
static void BindZuptEkf(py::module_& m) {
  const pdr::ZuptEkfOptions zupt_ekf;
  m.def("zupt_ekf", [](const py::object& time_s, const py::object& acc, const py::object& gyro, const py::object& stance,
                       double sigma_acc, double sigma_gyro, double sigma_zupt, double gravity, int init_samples, bool smooth,
                       double sigma_stance_heading, double min_stance_fraction, double max_plausible_swing_s,
                       double max_plausible_stride_m, double max_median_stride_m, double max_stance_speed_mps,
                       double speed_rise_factor, double min_rising_speed_mps) {
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
          o.sigma_stance_heading_rad = sigma_stance_heading;
          o.min_stance_fraction = min_stance_fraction;
          o.max_plausible_swing_s = max_plausible_swing_s;
          o.max_plausible_stride_m = max_plausible_stride_m;
          o.max_median_stride_m = max_median_stride_m;
          o.min_rising_speed_mps = min_rising_speed_mps;
          o.max_stance_speed_mps = max_stance_speed_mps;
          o.speed_rise_factor = speed_rise_factor;
          pdr::ZuptEkfOutput out;
          {
            py::gil_scoped_release release;
            out = pdr::RunZuptEkf(t.map, a.map, g.map, st, o);
          }
          return out;
        },
        py::arg("time_s"), py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("stance"), py::arg("sigma_acc_mps2") = zupt_ekf.sigma_acc_mps2,
        py::arg("sigma_gyro_radps") = zupt_ekf.sigma_gyro_radps, py::arg("sigma_zupt_mps") = zupt_ekf.sigma_zupt_mps, py::arg("gravity_mps2") = zupt_ekf.gravity_mps2,
        py::arg("init_samples") = zupt_ekf.init_samples, py::arg("smooth") = zupt_ekf.smooth, py::arg("sigma_stance_heading_rad") = zupt_ekf.sigma_stance_heading_rad,
        py::arg("min_stance_fraction") = zupt_ekf.min_stance_fraction, py::arg("max_plausible_swing_s") = zupt_ekf.max_plausible_swing_s, py::arg("max_plausible_stride_m") = zupt_ekf.max_plausible_stride_m,
        py::arg("max_median_stride_m") = zupt_ekf.max_median_stride_m, py::arg("max_stance_speed_mps") = zupt_ekf.max_stance_speed_mps, py::arg("speed_rise_factor") = zupt_ekf.speed_rise_factor, py::arg("min_rising_speed_mps") = zupt_ekf.min_rising_speed_mps, R"doc(
Zero-velocity-aided strapdown INS (9-state error-state EKF, OpenShoe/PyShoe style) over a
recording: time_s (N,) [s], acc_mps2 and gyro_radps (N, 3) sensor frame, stance (N,) bool.
smooth=True adds the RTS smoother (positions_m smoothed, filtered_positions_m the EKF's).
sigma_stance_heading_rad > 0 adds a stance heading update (yaw held at its stance-onset value).
Returns a ZuptEkfOutput (reads as a dict): positions_m (N, 3) (z up, start at 0, initial yaw 0), velocities_mps (N, 3),
headings_rad (N,), quaternions_wxyz (N, 4) body -> nav, position_sd_m (N, 3), seconds, and
health: the health check (a ZuptEkfSummary, read like a dict): stance_fraction and walking_stance_fraction
[0..1], n_stance_phases, swing_median_s / swing_max_s [s], speed_at_stance_median_mps /
speed_at_stance_max_mps (|v| the filter had integrated when each stance began, before its update)
[m/s], speed_at_stance_rise (last third / first third of the onsets), longest_stride_m and
median_stride_m [m],
implausible (bool), reasons (list of str), report (one line). The limits min_stance_fraction,
max_plausible_swing_s [s], max_plausible_stride_m and max_median_stride_m [m], max_stance_speed_mps [m/s],
speed_rise_factor and min_rising_speed_mps [m/s] only flag (defaults calibrated in docs/pdr.md).)doc");
}

void BindPdr(py::module_& m) {
  BindPdrResults(m);
  // The keyword defaults of these functions are read from default-constructed Options structs
  // (CONVENTIONS rule 13): the C++ header is the only place a default is written.
  BindZeroVelocity(m);
  BindStepDetection(m);
  BindAttitudeAndPositions(m);
  BindZuptEkf(m);
}

}  // namespace indoorloc::bindings
