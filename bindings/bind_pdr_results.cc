// Python bindings of the pdr subsystem's results: typed read-only objects (StepTrack,
// WeinbergCalibration, ZuptEkfSummary, ZeroVelocityOutput, StrideCountOutput, AttitudeOutput,
// InsZuptIncrements, ZuptEkfOutput) that also read as the dicts they replace (result_binding.h).
// The functions returning them are bound in bind_pdr.cc, which calls BindPdrResults first.
#include <cstdint>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/pdr/attitude_filter.h"
#include "indoorloc/pdr/step_positioning.h"
#include "indoorloc/pdr/stride_count.h"
#include "indoorloc/pdr/stride_length.h"
#include "indoorloc/pdr/zero_velocity.h"
#include "indoorloc/pdr/zupt_ekf.h"
#include "numpy_args.h"
#include "result_binding.h"

namespace indoorloc::bindings {

namespace {

/// (M, 3, 3) covariances from the (M, 9) rows of a StepTrack.
py::array_t<double> CovarianceArray(const pdr::StepTrack& t) {
  py::array_t<double> cov({static_cast<py::ssize_t>(t.covariances.rows()), py::ssize_t{3}, py::ssize_t{3}});
  auto c = cov.mutable_unchecked<3>();
  for (Eigen::Index k = 0; k < t.covariances.rows(); ++k) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) c(k, i, j) = t.covariances(k, 3 * i + j);
    }
  }
  return cov;
}

}  // namespace

/// The result types of the pdr functions: typed read-only objects that also read as the dicts
/// they replace (result_binding.h).
void BindPdrResults(py::module_& m) {
  using pdr::StepTrack;
  ResultBinder<StepTrack>(m, "StepTrack", "Positions from strides or increments, with per-step covariances.")
      .Field("positions_m", [](const StepTrack& t) { return RowMatrixXd(t.positions_m); }, "(M, 2) [m].")
      .Field("covariances", &CovarianceArray, "(M, 3, 3) of (x [m], y [m], heading error [rad]).")
      .Field("stride_lengths_m", [](const StepTrack& t) { return Eigen::VectorXd(t.stride_lengths_m); }, "(M,) [m].")
      .Field("headings_rad", [](const StepTrack& t) { return Eigen::VectorXd(t.headings_rad); }, "(M,) [rad].")
      .Finish();
  using pdr::WeinbergCalibration;
  ResultBinder<WeinbergCalibration>(m, "WeinbergCalibration", "A calibrated Weinberg K.")
      .Field("k", [](const WeinbergCalibration& c) { return c.k; }, "K [m / (m/s^2)^(1/4)].")
      .Field("rms_residual_m", [](const WeinbergCalibration& c) { return c.rms_residual_m; })
      .Field("n_strides", [](const WeinbergCalibration& c) { return c.n_strides; })
      .Field("report", [](const WeinbergCalibration& c) { return c.BriefReport(); })
      .Finish();
  using pdr::ZuptEkfSummary;
  ResultBinder<ZuptEkfSummary>(m, "ZuptEkfSummary", "Health of a ZUPT EKF run (divergence is reported, never silent).")
      .Field("n_samples", [](const ZuptEkfSummary& h) { return h.n_samples; })
      .Field("n_stance_samples", [](const ZuptEkfSummary& h) { return h.n_stance_samples; })
      .Field("n_stance_phases", [](const ZuptEkfSummary& h) { return h.n_stance_phases; })
      .Field("stance_fraction", [](const ZuptEkfSummary& h) { return h.stance_fraction; })
      .Field("walking_stance_fraction", [](const ZuptEkfSummary& h) { return h.walking_stance_fraction; })
      .Field("swing_median_s", [](const ZuptEkfSummary& h) { return h.swing_median_s; })
      .Field("swing_max_s", [](const ZuptEkfSummary& h) { return h.swing_max_s; })
      .Field("speed_at_stance_median_mps", [](const ZuptEkfSummary& h) { return h.speed_at_stance_median_mps; })
      .Field("speed_at_stance_max_mps", [](const ZuptEkfSummary& h) { return h.speed_at_stance_max_mps; })
      .Field("speed_at_stance_rise", [](const ZuptEkfSummary& h) { return h.speed_at_stance_rise; })
      .Field("longest_stride_m", [](const ZuptEkfSummary& h) { return h.longest_stride_m; })
      .Field("median_stride_m", [](const ZuptEkfSummary& h) { return h.median_stride_m; })
      .Field("implausible", [](const ZuptEkfSummary& h) { return h.implausible; })
      .Field("reasons", [](const ZuptEkfSummary& h) { return h.reasons; })
      .Field("seconds", [](const ZuptEkfSummary& h) { return h.seconds; })
      .Field("report", [](const ZuptEkfSummary& h) { return h.BriefReport(); })
      .Finish();
  using pdr::ZeroVelocityOutput;
  ResultBinder<ZeroVelocityOutput>(m, "ZeroVelocityOutput", "Stance detection of a recording and how its threshold was set.")
      .Field("stance", [](const ZeroVelocityOutput& o) { return pdr::BoolVector(o.stance); }, "(N,) bool.")
      .Field("statistic", [](const ZeroVelocityOutput& o) { return Eigen::VectorXd(o.statistic); }, "(N,) SHOE statistic.")
      .Field("threshold", [](const ZeroVelocityOutput& o) { return o.summary.threshold; })
      .Field("base_threshold", [](const ZeroVelocityOutput& o) { return o.summary.base_threshold; })
      .Field("guard_raised", [](const ZeroVelocityOutput& o) { return o.summary.guard_raised; })
      .Field("guard_satisfied", [](const ZeroVelocityOutput& o) { return o.summary.guard_satisfied; })
      .Field("low_motion_rule", [](const ZeroVelocityOutput& o) { return o.summary.low_motion_rule; })
      .Field("flicker_s", [](const ZeroVelocityOutput& o) { return o.summary.flicker_s; })
      .Field("ladder_rungs", [](const ZeroVelocityOutput& o) { return o.summary.ladder_rungs; })
      .Field("max_swing_s", [](const ZeroVelocityOutput& o) { return o.summary.max_swing_s; })
      .Field("median_swing_s", [](const ZeroVelocityOutput& o) { return o.summary.median_swing_s; })
      .Field("stance_fraction", [](const ZeroVelocityOutput& o) { return o.summary.stance_fraction; })
      .Field("walking_stance_fraction", [](const ZeroVelocityOutput& o) { return o.summary.walking_stance_fraction; })
      .Field("walking_span", [](const ZeroVelocityOutput& o) {
               return py::make_tuple(o.summary.walking_begin, o.summary.walking_end);
             }, "(begin, end) sample indices of the walking span.")
      .Field("report", [](const ZeroVelocityOutput& o) { return o.summary.BriefReport(); })
      .Finish();
  using pdr::StrideCountOutput;
  ResultBinder<StrideCountOutput>(m, "StrideCountOutput", "Strides counted from a stance sequence.")
      .Field("stride_indices", [](const StrideCountOutput& o) {
               return Eigen::Map<const Eigen::VectorXi>(o.stride_indices.data(),
                                                       static_cast<Eigen::Index>(o.stride_indices.size()))
                   .cast<std::int64_t>()
                   .eval();
             }, "(S,) int64 stance-onset samples.")
      .Field("cleaned_stance", [](const StrideCountOutput& o) { return pdr::BoolVector(o.cleaned_stance); })
      .Field("n_strides", [](const StrideCountOutput& o) { return o.summary.n_strides; })
      .Field("n_flicker_stances", [](const StrideCountOutput& o) { return o.summary.n_flicker_stances; })
      .Field("n_flicker_swings", [](const StrideCountOutput& o) { return o.summary.n_flicker_swings; })
      .Field("n_split_strides", [](const StrideCountOutput& o) { return o.summary.n_split_strides; })
      .Field("median_swing_s", [](const StrideCountOutput& o) { return o.summary.median_swing_s; })
      .Field("median_stance_s", [](const StrideCountOutput& o) { return o.summary.median_stance_s; })
      .Field("report", [](const StrideCountOutput& o) { return o.summary.BriefReport(); })
      .Finish();
  using pdr::AttitudeOutput;
  ResultBinder<AttitudeOutput>(m, "AttitudeOutput", "Attitude of a recording by the Mahony filter.")
      .Field("quaternions_wxyz", [](const AttitudeOutput& o) { return RowMatrixXd(o.quaternions_wxyz); }, "(N, 4).")
      .Field("gyro_bias_radps", [](const AttitudeOutput& o) { return RowMatrixXd(o.gyro_bias_radps); }, "(N, 3).")
      .Field("mag_used", [](const AttitudeOutput& o) { return pdr::BoolVector(o.mag_used); }, "(N,) bool.")
      .Field("mag_rejected", [](const AttitudeOutput& o) { return o.mag_rejected; })
      .Field("reference_field_norm", [](const AttitudeOutput& o) { return o.reference_field_norm; })
      .Field("reference_dip_rad", [](const AttitudeOutput& o) { return o.reference_dip_rad; })
      .Field("seconds", [](const AttitudeOutput& o) { return o.seconds; })
      .Finish();
  using pdr::InsZuptIncrements;
  ResultBinder<InsZuptIncrements>(m, "InsZuptIncrements", "Per-step INS-ZUPT increments (paper 002 eq. 5-6).")
      .Field("increments_m", [](const InsZuptIncrements& o) { return RowMatrixXd(o.increments_m); }, "(M-1, 3) [m].")
      .Field("stride_lengths_m", [](const InsZuptIncrements& o) { return Eigen::VectorXd(o.stride_lengths_m); })
      .Field("velocities_mps", [](const InsZuptIncrements& o) { return RowMatrixXd(o.velocities_mps); }, "(N, 3).")
      .Finish();
  using pdr::ZuptEkfOutput;
  ResultBinder<ZuptEkfOutput>(m, "ZuptEkfOutput", "A ZUPT-aided INS run over a recording.")
      .Field("positions_m", [](const ZuptEkfOutput& o) { return RowMatrixXd(o.positions_m); }, "(N, 3) [m].")
      .Field("filtered_positions_m", [](const ZuptEkfOutput& o) { return RowMatrixXd(o.filtered_positions_m); })
      .Field("velocities_mps", [](const ZuptEkfOutput& o) { return RowMatrixXd(o.velocities_mps); })
      .Field("headings_rad", [](const ZuptEkfOutput& o) { return Eigen::VectorXd(o.headings_rad); })
      .Field("quaternions_wxyz", [](const ZuptEkfOutput& o) { return RowMatrixXd(o.quaternions_wxyz); })
      .Field("position_sd_m", [](const ZuptEkfOutput& o) { return RowMatrixXd(o.position_sd_m); })
      .Field("seconds", [](const ZuptEkfOutput& o) { return o.seconds; })
      .Field("health", [](const ZuptEkfOutput& o) { return o.summary; }, "A ZuptEkfSummary.")
      .Finish();
}

}  // namespace indoorloc::bindings
