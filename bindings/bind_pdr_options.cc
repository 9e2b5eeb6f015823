// Python bindings of the pdr subsystem's Options: each struct bound once (options_binding.h:
// keyword constructor from the C++ defaults, replace, to_dict, validate, repr, ==, pickling), so
// that a default is written in the C++ header only. The functions that take them are bound in
// bind_pdr.cc (`options=`), which calls BindPdrOptions first.
#include <string>

#include "indoorloc/core/check.h"
#include "indoorloc/pdr/attitude_filter.h"
#include "indoorloc/pdr/step_detection.h"
#include "indoorloc/pdr/step_positioning.h"
#include "indoorloc/pdr/stride_count.h"
#include "indoorloc/pdr/stride_length.h"
#include "indoorloc/pdr/zero_velocity.h"
#include "indoorloc/pdr/zupt_ekf.h"
#include "options_binding.h"

namespace indoorloc::bindings {

namespace {

/// The name a ZeroVelocityRule has in Python (ZeroVelocityOptions.rule).
const char* ZeroVelocityRuleName(pdr::ZeroVelocityRule rule) {
  switch (rule) {
    case pdr::ZeroVelocityRule::kFixed: return "fixed";
    case pdr::ZeroVelocityRule::kStanceGuard: return "stance_guard";
    case pdr::ZeroVelocityRule::kSwingGuard: break;
  }
  return "swing_guard";
}

pdr::ZeroVelocityRule ParseZeroVelocityRule(const std::string& rule) {
  if (rule == "fixed") return pdr::ZeroVelocityRule::kFixed;
  if (rule == "stance_guard") return pdr::ZeroVelocityRule::kStanceGuard;
  if (rule != "swing_guard") {
    ThrowInvalidArgument("rule", "must be 'swing_guard', 'stance_guard' or 'fixed', got '" + rule + "'");
  }
  return pdr::ZeroVelocityRule::kSwingGuard;
}

/// A field of the nested ShoeOptions of ZeroVelocityOptions, flattened (`threshold` is
/// `shoe.threshold`), as zero_velocity's keywords always named them.
template <typename V>
void ShoeField(py::class_<pdr::ZeroVelocityOptions>& cls, const char* name, V pdr::ShoeOptions::*field, const char* doc) {
  cls.def_property(
      name, [field](const pdr::ZeroVelocityOptions& o) { return o.shoe.*field; },
      [field](pdr::ZeroVelocityOptions& o, V v) { o.shoe.*field = v; }, doc);
}

void BindStanceOptions(py::module_& m) {
  using pdr::ShoeOptions;
  py::class_<ShoeOptions> shoe(m, "ShoeOptions", "SHOE detector (shoe_statistic, shoe_detector); fields by keyword.");
  shoe.def_readwrite("window", &ShoeOptions::window, "W [samples], centred on each sample.")
      .def_readwrite("threshold", &ShoeOptions::threshold, "γ: stance where the statistic is below it.")
      .def_readwrite("sigma_acc_mps2", &ShoeOptions::sigma_acc_mps2, "Accelerometer noise sd [m/s^2].")
      .def_readwrite("sigma_gyro_radps", &ShoeOptions::sigma_gyro_radps, "Gyroscope noise sd [rad/s].")
      .def_readwrite("gravity_mps2", &ShoeOptions::gravity_mps2, "g [m/s^2].");
  BindOptionsProtocol(shoe, "ShoeOptions");

  using pdr::ZeroVelocityOptions;
  py::class_<ZeroVelocityOptions> zv(m, "ZeroVelocityOptions",
                                     "Adaptive zero-velocity detection (zero_velocity); fields by keyword. The SHOE "
                                     "fields (window, threshold = γ₀, noise sds, gravity) are its nested ShoeOptions.");
  zv.def_property("rule", [](const ZeroVelocityOptions& o) { return std::string(ZeroVelocityRuleName(o.rule)); },
                  [](ZeroVelocityOptions& o, const std::string& s) { o.rule = ParseZeroVelocityRule(s); },
                  "'swing_guard', 'stance_guard' or 'fixed'.")
      .def_readwrite("max_swing_s", &ZeroVelocityOptions::max_swing_s, "Longest accepted swing [s].")
      .def_readwrite("max_swing_ratio", &ZeroVelocityOptions::max_swing_ratio, "... and at most this x the median swing.")
      .def_readwrite("ladder_step_decades", &ZeroVelocityOptions::ladder_step_decades, "Threshold ladder step [decades].")
      .def_readwrite("min_stance_s", &ZeroVelocityOptions::min_stance_s, "Shorter stance inside a swing is flicker [s].")
      .def_readwrite("min_stance_share", &ZeroVelocityOptions::min_stance_share, "A rung needs this share of stance.")
      .def_readwrite("min_plausible_swing_s", &ZeroVelocityOptions::min_plausible_swing_s, "Median swing floor [s].")
      .def_readwrite("low_motion_min_stance_s", &ZeroVelocityOptions::low_motion_min_stance_s,
                     "Flicker of the low-motion rule [s].")
      .def_readwrite("min_stance_fraction", &ZeroVelocityOptions::min_stance_fraction, "'stance_guard' quantile.")
      .def_readwrite("max_threshold", &ZeroVelocityOptions::max_threshold, "Top of the threshold ladder.");
  ShoeField(zv, "threshold", &ShoeOptions::threshold, "γ₀, the base SHOE threshold.");
  ShoeField(zv, "window", &ShoeOptions::window, "SHOE window W [samples].");
  ShoeField(zv, "sigma_acc_mps2", &ShoeOptions::sigma_acc_mps2, "SHOE accelerometer noise sd [m/s^2].");
  ShoeField(zv, "sigma_gyro_radps", &ShoeOptions::sigma_gyro_radps, "SHOE gyroscope noise sd [rad/s].");
  ShoeField(zv, "gravity_mps2", &ShoeOptions::gravity_mps2, "g [m/s^2].");
  BindOptionsProtocol(zv, "ZeroVelocityOptions");

  using pdr::StrideCountOptions;
  py::class_<StrideCountOptions> strides(m, "StrideCountOptions", "Stride counting (count_strides); fields by keyword.");
  strides.def_readwrite("min_stance_s", &StrideCountOptions::min_stance_s, "Shorter stance in a swing is flicker [s].")
      .def_readwrite("min_swing_s", &StrideCountOptions::min_swing_s, "Shorter swing is always flicker [s].")
      .def_readwrite("min_swing_fraction", &StrideCountOptions::min_swing_fraction, "... or below this x the median.")
      .def_readwrite("long_swing_factor", &StrideCountOptions::long_swing_factor, "Longer swings are split; 0: never.");
  BindOptionsProtocol(strides, "StrideCountOptions");
}

void BindStepOptions(py::module_& m) {
  using pdr::AccelerationStepOptions;
  py::class_<AccelerationStepOptions> acc(m, "AccelerationStepOptions",
                                          "Acceleration-variance step detector (steps_acceleration); fields by keyword.");
  acc.def_readwrite("window_s", &AccelerationStepOptions::window_s, "Half-window w [s].")
      .def_readwrite("adaptive", &AccelerationStepOptions::adaptive, "Thresholds from the recording's σ.")
      .def_readwrite("swing_threshold_mps2", &AccelerationStepOptions::swing_threshold_mps2, "T1 [m/s^2], fixed.")
      .def_readwrite("stance_threshold_mps2", &AccelerationStepOptions::stance_threshold_mps2, "T2 [m/s^2], fixed.")
      .def_readwrite("swing_fraction", &AccelerationStepOptions::swing_fraction, "Adaptive T1 / 95th pct of σ.")
      .def_readwrite("stance_fraction", &AccelerationStepOptions::stance_fraction, "Adaptive T2 / 95th pct of σ.")
      .def_readwrite("min_step_interval_s", &AccelerationStepOptions::min_step_interval_s, "[s].");
  BindOptionsProtocol(acc, "AccelerationStepOptions");

  using pdr::GyroStepOptions;
  py::class_<GyroStepOptions> gyro(m, "GyroStepOptions", "Gyroscope step detector (steps_gyro); fields by keyword.");
  gyro.def_readwrite("threshold_radps", &GyroStepOptions::threshold_radps, "|ω| above it is motion [rad/s].")
      .def_readwrite("median_window_s", &GyroStepOptions::median_window_s, "Median filter length [s].")
      .def_readwrite("min_swing_s", &GyroStepOptions::min_swing_s, "Shorter motion is no step [s].");
  BindOptionsProtocol(gyro, "GyroStepOptions");

  using pdr::MagneticStepOptions;
  py::class_<MagneticStepOptions> mag(m, "MagneticStepOptions",
                                      "Magnetometer step detector (steps_magnetometer); fields by keyword.");
  mag.def_readwrite("highpass_order", &MagneticStepOptions::highpass_order, "Butterworth high-pass order.")
      .def_readwrite("highpass_hz", &MagneticStepOptions::highpass_hz, "High-pass cut-off [Hz].")
      .def_readwrite("threshold_fraction", &MagneticStepOptions::threshold_fraction, "x 95th pct of |m_hp|.")
      .def_readwrite("median_window_s", &MagneticStepOptions::median_window_s, "Median filter length [s].")
      .def_readwrite("min_swing_s", &MagneticStepOptions::min_swing_s, "Shorter motion is no step [s].")
      .def_readwrite("min_rest_s", &MagneticStepOptions::min_rest_s, "Shorter rests are merged [s].");
  BindOptionsProtocol(mag, "MagneticStepOptions");

  using pdr::WeinbergOptions;
  py::class_<WeinbergOptions> weinberg(m, "WeinbergOptions",
                                       "Weinberg stride length (weinberg_features, weinberg_stride_lengths); fields "
                                       "by keyword.");
  weinberg.def_readwrite("k", &WeinbergOptions::k, "K of eq. 4 [m / (m/s^2)^(1/4)].")
      .def_readwrite("filter_order", &WeinbergOptions::filter_order, "Low-pass order.")
      .def_readwrite("cutoff_hz", &WeinbergOptions::cutoff_hz, "Low-pass cut-off [Hz].")
      .def_readwrite("window_s", &WeinbergOptions::window_s, "Half-window around each step [s].")
      .def_readwrite("steady_state_start", &WeinbergOptions::steady_state_start, "Filter starts in steady state.");
  BindOptionsProtocol(weinberg, "WeinbergOptions");
}

void BindInsOptions(py::module_& m) {
  using pdr::MahonyOptions;
  py::class_<MahonyOptions> mahony(m, "MahonyOptions", "Mahony attitude filter (attitude_mahony); fields by keyword.");
  mahony.def_readwrite("kp", &MahonyOptions::kp, "Gain on the gravity error [rad/s].")
      .def_readwrite("ki", &MahonyOptions::ki, "Integral gain (gyro bias) [rad/s^2].")
      .def_readwrite("kp_mag", &MahonyOptions::kp_mag, "Gain on the heading error [rad/s per rad].")
      .def_readwrite("gravity_mps2", &MahonyOptions::gravity_mps2, "g [m/s^2].")
      .def_readwrite("acc_gate_mps2", &MahonyOptions::acc_gate_mps2, "Gravity used when ||f| - g| below it.")
      .def_readwrite("mag_norm_tolerance", &MahonyOptions::mag_norm_tolerance, "Accepted relative |m| deviation.")
      .def_readwrite("mag_dip_tolerance_rad", &MahonyOptions::mag_dip_tolerance_rad, "Accepted dip deviation [rad].")
      .def_readwrite("init_samples", &MahonyOptions::init_samples, "Samples of the initial attitude.");
  BindOptionsProtocol(mahony, "MahonyOptions");

  using pdr::StepCovarianceOptions;
  py::class_<StepCovarianceOptions> cov(m, "StepCovarianceOptions",
                                        "Per-step covariance (positions_from_strides, positions_from_increments); "
                                        "fields by keyword.");
  cov.def_readwrite("sigma_stride_length_m", &StepCovarianceOptions::sigma_stride_length_m, "Stride sd, constant [m].")
      .def_readwrite("stride_length_sd_fraction", &StepCovarianceOptions::stride_length_sd_fraction,
                     "Stride sd, proportional part.")
      .def_readwrite("sigma_heading_step_rad", &StepCovarianceOptions::sigma_heading_step_rad,
                     "Heading random walk per step [rad].")
      .def_readwrite("sigma_heading_initial_rad", &StepCovarianceOptions::sigma_heading_initial_rad,
                     "Initial heading sd [rad].");
  BindOptionsProtocol(cov, "StepCovarianceOptions");

  using pdr::InsZuptOptions;
  py::class_<InsZuptOptions> ins(m, "InsZuptOptions", "INS-ZUPT increments (ins_zupt_increments); fields by keyword.");
  ins.def_readwrite("window_s", &InsZuptOptions::window_s, "Half-window of the stance mean velocity [s].")
      .def_readwrite("gravity_mps2", &InsZuptOptions::gravity_mps2, "g [m/s^2].");
  BindOptionsProtocol(ins, "InsZuptOptions");

  using pdr::ZuptEkfOptions;
  py::class_<ZuptEkfOptions> ekf(m, "ZuptEkfOptions", "ZUPT-aided INS (zupt_ekf); fields by keyword.");
  ekf.def_readwrite("sigma_acc_mps2", &ZuptEkfOptions::sigma_acc_mps2, "Accelerometer process noise [m/s^2].")
      .def_readwrite("sigma_gyro_radps", &ZuptEkfOptions::sigma_gyro_radps, "Gyroscope process noise [rad/s].")
      .def_readwrite("sigma_zupt_mps", &ZuptEkfOptions::sigma_zupt_mps, "Zero-velocity measurement sd [m/s].")
      .def_readwrite("gravity_mps2", &ZuptEkfOptions::gravity_mps2, "g [m/s^2].")
      .def_readwrite("init_samples", &ZuptEkfOptions::init_samples, "Samples of the initial attitude.")
      .def_readwrite("sigma_stance_heading_rad", &ZuptEkfOptions::sigma_stance_heading_rad,
                     "> 0: stance heading update with this sd [rad].")
      .def_readwrite("smooth", &ZuptEkfOptions::smooth, "Add the RTS smoother.")
      .def_readwrite("min_stance_fraction", &ZuptEkfOptions::min_stance_fraction, "Health: flag less stance.")
      .def_readwrite("max_plausible_swing_s", &ZuptEkfOptions::max_plausible_swing_s, "Health: longest swing [s].")
      .def_readwrite("max_plausible_stride_m", &ZuptEkfOptions::max_plausible_stride_m, "Health: longest stride [m].")
      .def_readwrite("max_median_stride_m", &ZuptEkfOptions::max_median_stride_m, "Health: median stride [m].")
      .def_readwrite("max_stance_speed_mps", &ZuptEkfOptions::max_stance_speed_mps, "Health: |v| at stance [m/s].")
      .def_readwrite("speed_rise_factor", &ZuptEkfOptions::speed_rise_factor, "Health: rise of that speed.")
      .def_readwrite("min_rising_speed_mps", &ZuptEkfOptions::min_rising_speed_mps, "Health: ... above it [m/s].");
  BindOptionsProtocol(ekf, "ZuptEkfOptions");
}

}  // namespace

/// Every Options struct the pdr functions take.
void BindPdrOptions(py::module_& m) {
  BindStanceOptions(m);
  BindStepOptions(m);
  BindInsOptions(m);
}

}  // namespace indoorloc::bindings
