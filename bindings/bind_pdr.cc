// Python bindings of the pdr subsystem: zero-velocity detection and the ZUPT-aided EKF.
//
// Every function takes its settings as one `options=` argument, an Options struct bound once in
// bind_pdr_options.cc (None: the C++ defaults, which are written in the headers only). The option
// fields each function once took as separate keywords still work for one release, with a
// DeprecationWarning (OptionsArgument in options_binding.h; docs/api_changes.md).
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
#include "options_binding.h"
#include "result_binding.h"

namespace indoorloc::bindings {

// The result types of the pdr functions (bind_pdr_results.cc) and their Options (bind_pdr_options.cc).
void BindPdrResults(py::module_& m);
void BindPdrOptions(py::module_& m);

namespace {

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

Eigen::Vector2d ToStart(const py::object& start) {
  VectorArg v = ToVector(start, "start_xy", 2);
  return Eigen::Vector2d(v.map[0], v.map[1]);
}

/// `options=None` and the deprecated field keywords of every function below.
py::arg_v NoOptions() { return py::arg("options") = py::none(); }

/// Binds a step detector `detect(rate_hz, samples (N, 3), options, &signal)` as
/// `name(samples, rate_hz, options=None)` returning (step sample indices, its per-sample signal (N,)).
template <typename Options, typename Detect>
void BindDetectorWithSignal(py::module_& m, const char* name, const char* samples_arg, Detect detect, const char* doc) {
  m.def(name, [name, samples_arg, detect](const py::object& samples, double rate_hz, const py::object& options,
                                          const py::kwargs& fields) {
          MatrixArg x = ToMatrix(samples, samples_arg, -1, 3);
          const auto o = OptionsArgument<Options>(options, fields, name);
          Eigen::VectorXd signal;
          const std::vector<int> steps = detect(rate_hz, x.map, o, &signal);
          return py::make_tuple(steps, signal);
        },
        py::arg(samples_arg), py::arg("rate_hz"), NoOptions(), doc);
}

}  // namespace

/// Binds `shoe(acc (N, 3), gyro (N, 3), ShoeOptions)` (the SHOE statistic or its stance flags) as
/// `name(acc_mps2, gyro_radps, options=None)`.
template <typename Shoe>
static void BindShoe(py::module_& m, const char* name, Shoe shoe, const char* doc) {
  m.def(name, [name, shoe](const py::object& acc, const py::object& gyro, const py::object& options,
                           const py::kwargs& fields) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          MatrixArg g = ToMatrix(gyro, "gyro_radps", a.map.rows(), 3);
          const auto o = OptionsArgument<pdr::ShoeOptions>(options, fields, name);
          return WithoutGil([&] { return shoe(a.map, g.map, o); });
        },
        py::arg("acc_mps2"), py::arg("gyro_radps"), NoOptions(), doc);
}

/// Stance detection (SHOE and the adaptive detector) and stride counting.
static void BindZeroVelocity(py::module_& m) {
  BindShoe(m, "shoe_statistic", &pdr::ShoeStatistic,
           "SHOE test statistic (N,) of specific force (N, 3) [m/s^2] and angular rate (N, 3) [rad/s]; options: a "
           "ShoeOptions (its threshold is not used).");
  BindShoe(m, "shoe_detector", &pdr::ShoeDetector, R"doc(
Stance flags (N,) bool of the SHOE zero-velocity detector (Skog et al. 2010): statistic < threshold.
acc_mps2, gyro_radps: (N, 3) in the sensor frame [m/s^2], [rad/s]; options: a ShoeOptions (window in
samples).)doc");
  m.def("zero_velocity", [](const py::object& acc, const py::object& gyro, double rate_hz, const py::object& options,
                            const py::kwargs& fields) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          MatrixArg g = ToMatrix(gyro, "gyro_radps", a.map.rows(), 3);
          const auto o = OptionsArgument<pdr::ZeroVelocityOptions>(options, fields, "zero_velocity");
          return WithoutGil([&] { return pdr::DetectZeroVelocity(a.map, g.map, rate_hz, o); });
        },
        py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("rate_hz"), NoOptions(), R"doc(
Zero-velocity detection with the SHOE threshold adapted to the recording (C++ DetectZeroVelocity).
acc_mps2, gyro_radps: (N, 3) sensor frame [m/s^2], [rad/s]; rate_hz [Hz]; options: a
ZeroVelocityOptions (window in samples).
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
  m.def("count_strides", [](const py::object& stance, double rate_hz, const py::object& options,
                            const py::kwargs& fields) {
          VectorArg s = ToVector(stance, "stance");
          const pdr::BoolVector st = (s.map.array() != 0.0).matrix();
          const auto o = OptionsArgument<pdr::StrideCountOptions>(options, fields, "count_strides");
          return pdr::CountStrides(st, rate_hz, o);
        },
        py::arg("stance"), py::arg("rate_hz"), NoOptions(), R"doc(
Strides of the instrumented foot from stance flags (N,) sampled at rate_hz [Hz] (C++ CountStrides;
options: a StrideCountOptions): stance runs shorter than min_stance_s [s] inside a swing are
flicker; swing runs shorter than max(min_swing_s [s], min_swing_fraction x the recording's median
swing) inside a stance are flicker; a swing longer than long_swing_factor x the median swing (0
disables) counts as round(length / median) strides. Returns a StrideCountOutput (reads as a dict):
stride_indices (S,) int64 stance onsets, cleaned_stance (N,) bool, n_strides, n_flicker_stances,
n_flicker_swings, n_split_strides, median_swing_s, median_stance_s [s], report.)doc");
}

/// Step detectors, filters and the Weinberg stride length.
static void BindStepDetection(py::module_& m) {
  BindDetectorWithSignal<pdr::AccelerationStepOptions>(m, "steps_acceleration", "acc_mps2", &pdr::DetectStepsAcceleration,
                                                      R"doc(
Paper 002's acceleration-variance step detector (eq. 1-3; options: an AccelerationStepOptions).
Returns (step sample indices, σ (N,) [m/s^2]). adaptive=True: thresholds = fractions of the 95th
percentile of σ; False: the fixed T1, T2 [m/s^2] (paper: 2 and 1 at 100 Hz).)doc");
  m.def("steps_gyro", [](const py::object& gyro, double rate_hz, const py::object& options, const py::kwargs& fields) {
          MatrixArg g = ToMatrix(gyro, "gyro_radps", -1, 3);
          const auto o = OptionsArgument<pdr::GyroStepOptions>(options, fields, "steps_gyro");
          return pdr::DetectStepsGyro(rate_hz, g.map, o);
        },
        py::arg("gyro_radps"), py::arg("rate_hz"), NoOptions(),
        "Gyroscope step detector (paper 002 §III.D; options: a GyroStepOptions): step sample indices.");
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
  m.def("weinberg_features", [](const py::object& acc, double rate_hz, const py::object& intervals,
                                const py::object& options, const py::kwargs& fields) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          const Eigen::MatrixXi iv = ToIndexPairs(intervals, "intervals");
          const auto o = OptionsArgument<pdr::WeinbergOptions>(options, fields, "weinberg_features");
          py::gil_scoped_release release;
          return pdr::WeinbergFeatures(rate_hz, a.map, iv, o);
        },
        py::arg("acc_mps2"), py::arg("rate_hz"), py::arg("intervals"), NoOptions(), R"doc(
Weinberg bounce feature (max a~ - min a~)^(1/4) [(m/s^2)^(1/4)] over each interval (M, 2) of
inclusive sample indices [start, end], with a~ the Butterworth low-pass (options: a WeinbergOptions,
its filter_order, cutoff_hz [Hz] and steady_state_start; k and window_s are not used) of
|acc_mps2| (N, 3) [m/s^2] sampled at rate_hz [Hz]. Stride length = K x feature (eq. 4).)doc");
  m.def("weinberg_stride_lengths", [](const py::object& acc, double rate_hz, const py::object& step_indices,
                                      const py::object& options, const py::kwargs& fields) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          const std::vector<int> steps = ToIndices(step_indices, "step_indices");
          const auto o = OptionsArgument<pdr::WeinbergOptions>(options, fields, "weinberg_stride_lengths");
          py::gil_scoped_release release;
          return pdr::WeinbergStrideLengths(rate_hz, a.map, steps, o);
        },
        py::arg("acc_mps2"), py::arg("rate_hz"), py::arg("step_indices"), NoOptions(), R"doc(
Weinberg stride lengths [m] (paper 002 eq. 4), one per step: K (max - min)^(1/4) of the 3 Hz
low-passed |acc| [m/s^2] over +-window_s [s] around each step sample (strictly increasing
indices into acc_mps2 (N, 3)); options: a WeinbergOptions. K [m/(m/s^2)^(1/4)]: 0.364 in the paper
(foot); calibrate it with calibrate_weinberg_k.)doc");
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
  BindDetectorWithSignal<pdr::MagneticStepOptions>(m, "steps_magnetometer", "mag", &pdr::DetectStepsMagnetometer, R"doc(
Magnetometer step detector (paper 002 §III.D; options: a MagneticStepOptions): Butterworth
high-pass (highpass_order, highpass_hz [Hz]) per axis of mag (N, 3) (any unit, e.g. uT), |m_hp|
thresholded at threshold_fraction x its 95th percentile, median filter (median_window_s [s]),
rests shorter than min_rest_s [s] merged, a step at each transition to rest after at least
min_swing_s [s] of motion. Returns (step sample indices, |m_hp| (N,) in the unit of mag).)doc");
}

/// Attitude, stance headings and positions from strides or increments.
static void BindAttitudeAndPositions(py::module_& m) {
  m.def("attitude_mahony", [](const py::object& time_s, const py::object& acc, const py::object& gyro, const py::object& mag,
                              const py::object& options, const py::kwargs& fields) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          MatrixArg g = ToMatrix(gyro, "gyro_radps", a.map.rows(), 3);
          VectorArg t = ToVector(time_s, "time_s", a.map.rows());
          RowMatrixXd m(0, 3);
          if (!mag.is_none()) {
            MatrixArg mm = ToMatrix(mag, "mag", a.map.rows(), 3);
            m = mm.map;
          }
          const auto o = OptionsArgument<pdr::MahonyOptions>(options, fields, "attitude_mahony");
          return WithoutGil([&] { return pdr::RunMahony(t.map, a.map, g.map, m, o); });
        },
        py::arg("time_s"), py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("mag") = py::none(), NoOptions(), R"doc(
Mahony complementary attitude filter (gyro + gravity, magnetometer optional, heading-only and
gated by a disturbance test on the field norm and dip). time_s (N,) [s], acc_mps2 (N, 3) [m/s^2],
gyro_radps (N, 3) [rad/s], mag (N, 3) any unit or None; options: a MahonyOptions (gains kp,
kp_mag [rad/s], ki [rad/s^2]).
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
                                     const py::object& options, const py::kwargs& fields) {
          VectorArg l = ToVector(sl, "stride_lengths_m");
          VectorArg h = ToVector(headings, "headings_rad", l.map.size());
          const auto o = OptionsArgument<pdr::StepCovarianceOptions>(options, fields, "positions_from_strides");
          return pdr::PositionsFromStrides(l.map, h.map, ToStart(start), o);
        },
        py::arg("stride_lengths_m"), py::arg("headings_rad"), py::arg("start_xy") = std::vector<double>{0.0, 0.0},
        NoOptions(), R"doc(
Paper 002 eq. 8: P_k = P_{k-1} + SL_k (cos th_k, sin th_k) from stride lengths (M,) [m] and
headings (M,) [rad], starting at start_xy [m]. Each step carries the 3 x 3 covariance of
(x [m], y [m], heading error [rad]) under a heading random walk (sigma_heading_step_rad per step)
and stride-length noise (sigma_stride_length_m + stride_length_sd_fraction x SL); options: a
StepCovarianceOptions. Returns a StepTrack (reads as a dict): positions_m (M, 2), covariances
(M, 3, 3), stride_lengths_m, headings_rad.)doc");
  m.def("positions_from_increments", [](const py::object& inc, const py::object& start, const py::object& options,
                                        const py::kwargs& fields) {
          MatrixArg d = ToMatrix(inc, "increments_m");
          const auto o = OptionsArgument<pdr::StepCovarianceOptions>(options, fields, "positions_from_increments");
          return pdr::PositionsFromIncrements(d.map, ToStart(start), o);
        },
        py::arg("increments_m"), py::arg("start_xy") = std::vector<double>{0.0, 0.0}, NoOptions(), R"doc(
Paper 002 eq. 9: P_k = P_{k-1} + dP_k(x, y) from INS-ZUPT increments (M, 2) or (M, 3) [m], with
the per-step covariance of positions_from_strides (SL = |dP_xy|, heading = atan2(dP_y, dP_x));
options: a StepCovarianceOptions.)doc");
  m.def("ins_zupt_increments", [](const py::object& time_s, const py::object& acc, const py::object& quaternions,
                                  const py::object& step_indices, const py::object& options, const py::kwargs& fields) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          VectorArg t = ToVector(time_s, "time_s", a.map.rows());
          MatrixArg q = ToMatrix(quaternions, "quaternions_wxyz", a.map.rows(), 4);
          const std::vector<int> steps = ToIndices(step_indices, "step_indices");
          const auto o = OptionsArgument<pdr::InsZuptOptions>(options, fields, "ins_zupt_increments");
          return WithoutGil([&] { return pdr::ComputeInsZuptIncrements(t.map, a.map, q.map, steps, o); });
        },
        py::arg("time_s"), py::arg("acc_mps2"), py::arg("quaternions_wxyz"), py::arg("step_indices"), NoOptions(), R"doc(
Paper 002 §IV.B (steps 1-5, eq. 5-6): rotate acc_mps2 (N, 3) [m/s^2] by quaternions_wxyz (N, 4)
(body -> navigation, z up), remove gravity, integrate from the first step, remove the drift by
the mean velocity over +-window_s [s] around each step sample, linearly interpolated between
steps, and sum each step (options: an InsZuptOptions). step_indices: M >= 2 strictly increasing
stance samples. Returns an InsZuptIncrements (reads as a dict): increments_m (M-1, 3),
stride_lengths_m (M-1,) (eq. 6), velocities_mps (N, 3).)doc");
}

/// The ZUPT-aided INS.
static void BindZuptEkf(py::module_& m) {
  m.def("zupt_ekf", [](const py::object& time_s, const py::object& acc, const py::object& gyro, const py::object& stance,
                       const py::object& options, const py::kwargs& fields) {
          MatrixArg a = ToMatrix(acc, "acc_mps2", -1, 3);
          MatrixArg g = ToMatrix(gyro, "gyro_radps", a.map.rows(), 3);
          VectorArg t = ToVector(time_s, "time_s", a.map.rows());
          VectorArg s = ToVector(stance, "stance", a.map.rows());
          const pdr::BoolVector st = (s.map.array() != 0.0).matrix();
          const auto o = OptionsArgument<pdr::ZuptEkfOptions>(options, fields, "zupt_ekf");
          return WithoutGil([&] { return pdr::RunZuptEkf(t.map, a.map, g.map, st, o); });
        },
        py::arg("time_s"), py::arg("acc_mps2"), py::arg("gyro_radps"), py::arg("stance"), NoOptions(), R"doc(
Zero-velocity-aided strapdown INS (9-state error-state EKF, OpenShoe/PyShoe style) over a
recording: time_s (N,) [s], acc_mps2 and gyro_radps (N, 3) sensor frame, stance (N,) bool;
options: a ZuptEkfOptions. smooth=True adds the RTS smoother (positions_m smoothed,
filtered_positions_m the EKF's). sigma_stance_heading_rad > 0 adds a stance heading update (yaw
held at its stance-onset value).
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
  BindPdrOptions(m);
  BindZeroVelocity(m);
  BindStepDetection(m);
  BindAttitudeAndPositions(m);
  BindZuptEkf(m);
}

}  // namespace indoorloc::bindings
