# Stubs of indoorloc._core.pdr: zero-velocity detection and the ZUPT-aided EKF.
from typing import Any, Dict, Iterator, List, Optional, Tuple, TypeVar

import numpy as np
import numpy.typing as npt

_ArrayLike = npt.ArrayLike
_F64 = npt.NDArray[np.float64]


# Result types: typed read-only objects (fields listed as annotations; they cannot be set) that also
# read as the former dicts (result["key"], keys(), items(), get(), to_dict(); they pickle as that dict).

class _Result:
    """The read-only mapping protocol every result type has (bindings/result_binding.h)."""
    def __getitem__(self, key: str) -> Any: ...
    def keys(self) -> List[str]: ...
    def values(self) -> List[Any]: ...
    def items(self) -> List[Tuple[str, Any]]: ...
    def get(self, key: str, default: Any = None) -> Any: ...
    def __contains__(self, key: object) -> bool: ...
    def __iter__(self) -> Iterator[str]: ...
    def __len__(self) -> int: ...
    def to_dict(self) -> Dict[str, Any]: ...


class StepTrack(_Result):
    positions_m: _F64
    covariances: _F64
    stride_lengths_m: _F64
    headings_rad: _F64

class WeinbergCalibration(_Result):
    k: float
    rms_residual_m: float
    n_strides: int
    report: str

class ZuptEkfSummary(_Result):
    n_samples: int
    n_stance_samples: int
    n_stance_phases: int
    stance_fraction: float
    walking_stance_fraction: float
    swing_median_s: float
    swing_max_s: float
    speed_at_stance_median_mps: float
    speed_at_stance_max_mps: float
    speed_at_stance_rise: float
    longest_stride_m: float
    median_stride_m: float
    implausible: bool
    reasons: List[str]
    seconds: float
    report: str

class ZeroVelocityOutput(_Result):
    stance: npt.NDArray[np.bool_]
    statistic: _F64
    threshold: float
    base_threshold: float
    guard_raised: bool
    guard_satisfied: bool
    low_motion_rule: bool
    flicker_s: float
    ladder_rungs: int
    max_swing_s: float
    median_swing_s: float
    stance_fraction: float
    walking_stance_fraction: float
    walking_span: Tuple[int, int]
    report: str

class StrideCountOutput(_Result):
    stride_indices: npt.NDArray[np.int64]
    cleaned_stance: npt.NDArray[np.bool_]
    n_strides: int
    n_flicker_stances: int
    n_flicker_swings: int
    n_split_strides: int
    median_swing_s: float
    median_stance_s: float
    report: str

class AttitudeOutput(_Result):
    quaternions_wxyz: _F64
    gyro_bias_radps: _F64
    mag_used: npt.NDArray[np.bool_]
    mag_rejected: int
    reference_field_norm: float
    reference_dip_rad: float
    seconds: float

class InsZuptIncrements(_Result):
    increments_m: _F64
    stride_lengths_m: _F64
    velocities_mps: _F64

class ZuptEkfOutput(_Result):
    positions_m: _F64
    filtered_positions_m: _F64
    velocities_mps: _F64
    headings_rad: _F64
    quaternions_wxyz: _F64
    position_sd_m: _F64
    seconds: float
    health: ZuptEkfSummary

# Options: fields listed as annotations, defaults not restated (read them from the compiled struct,
# ``ZuptEkfOptions().to_dict()``). Every function below takes one as ``options=`` (None: the
# defaults); the fields as separate keywords (``zupt_ekf(..., smooth=True)``) still work, with a
# DeprecationWarning, for one release (docs/api_changes.md).

_O = TypeVar("_O", bound="_Options")

class _Options:
    """The protocol every bound Options class has (bindings/options_binding.h)."""
    def __init__(self, **fields: Any) -> None: ...
    def replace(self: _O, **fields: Any) -> _O: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def validate(self) -> None: ...


class ShoeOptions(_Options):
    window: int
    threshold: float
    sigma_acc_mps2: float
    sigma_gyro_radps: float
    gravity_mps2: float

class ZeroVelocityOptions(_Options):
    rule: str
    threshold: float
    window: int
    sigma_acc_mps2: float
    sigma_gyro_radps: float
    gravity_mps2: float
    max_swing_s: float
    max_swing_ratio: float
    ladder_step_decades: float
    min_stance_s: float
    min_stance_share: float
    min_plausible_swing_s: float
    low_motion_min_stance_s: float
    min_stance_fraction: float
    max_threshold: float

class StrideCountOptions(_Options):
    min_stance_s: float
    min_swing_s: float
    min_swing_fraction: float
    long_swing_factor: float

class AccelerationStepOptions(_Options):
    window_s: float
    adaptive: bool
    swing_threshold_mps2: float
    stance_threshold_mps2: float
    swing_fraction: float
    stance_fraction: float
    min_step_interval_s: float

class GyroStepOptions(_Options):
    threshold_radps: float
    median_window_s: float
    min_swing_s: float

class MagneticStepOptions(_Options):
    highpass_order: int
    highpass_hz: float
    threshold_fraction: float
    median_window_s: float
    min_swing_s: float
    min_rest_s: float

class WeinbergOptions(_Options):
    k: float
    filter_order: int
    cutoff_hz: float
    window_s: float
    steady_state_start: bool

class MahonyOptions(_Options):
    kp: float
    ki: float
    kp_mag: float
    gravity_mps2: float
    acc_gate_mps2: float
    mag_norm_tolerance: float
    mag_dip_tolerance_rad: float
    init_samples: int

class StepCovarianceOptions(_Options):
    sigma_stride_length_m: float
    stride_length_sd_fraction: float
    sigma_heading_step_rad: float
    sigma_heading_initial_rad: float

class InsZuptOptions(_Options):
    window_s: float
    gravity_mps2: float

class ZuptEkfOptions(_Options):
    sigma_acc_mps2: float
    sigma_gyro_radps: float
    sigma_zupt_mps: float
    gravity_mps2: float
    init_samples: int
    sigma_stance_heading_rad: float
    smooth: bool
    min_stance_fraction: float
    max_plausible_swing_s: float
    max_plausible_stride_m: float
    max_median_stride_m: float
    max_stance_speed_mps: float
    speed_rise_factor: float
    min_rising_speed_mps: float


def shoe_statistic(acc_mps2: _ArrayLike, gyro_radps: _ArrayLike, options: Optional[ShoeOptions] = None,
                   **deprecated_fields: Any) -> _F64: ...
def shoe_detector(acc_mps2: _ArrayLike, gyro_radps: _ArrayLike, options: Optional[ShoeOptions] = None,
                  **deprecated_fields: Any) -> npt.NDArray[np.bool_]: ...
def zupt_ekf(time_s: _ArrayLike, acc_mps2: _ArrayLike, gyro_radps: _ArrayLike, stance: _ArrayLike,
             options: Optional[ZuptEkfOptions] = None, **deprecated_fields: Any) -> ZuptEkfOutput: ...
def zero_velocity(acc_mps2: _ArrayLike, gyro_radps: _ArrayLike, rate_hz: float,
                  options: Optional[ZeroVelocityOptions] = None, **deprecated_fields: Any) -> ZeroVelocityOutput: ...
def count_strides(stance: _ArrayLike, rate_hz: float, options: Optional[StrideCountOptions] = None,
                  **deprecated_fields: Any) -> StrideCountOutput: ...
def steps_acceleration(acc_mps2: _ArrayLike, rate_hz: float, options: Optional[AccelerationStepOptions] = None,
                       **deprecated_fields: Any) -> Tuple[List[int], _F64]: ...
def steps_gyro(gyro_radps: _ArrayLike, rate_hz: float, options: Optional[GyroStepOptions] = None,
               **deprecated_fields: Any) -> List[int]: ...
def butterworth_sos(order: int, cutoff_hz: float, rate_hz: float, highpass: bool = False) -> _F64: ...
def sos_filter(sos: _ArrayLike, x: _ArrayLike, steady_state_start: bool = False) -> _F64: ...
def weinberg_features(acc_mps2: _ArrayLike, rate_hz: float, intervals: _ArrayLike,
                      options: Optional[WeinbergOptions] = None, **deprecated_fields: Any) -> _F64: ...
def weinberg_stride_lengths(acc_mps2: _ArrayLike, rate_hz: float, step_indices: _ArrayLike,
                            options: Optional[WeinbergOptions] = None, **deprecated_fields: Any) -> _F64: ...
def calibrate_weinberg_k(features: _ArrayLike, lengths_m: _ArrayLike) -> WeinbergCalibration: ...
def calibrate_weinberg_k_from_distance(features: _ArrayLike, distance_m: float) -> WeinbergCalibration: ...
def steps_magnetometer(mag: _ArrayLike, rate_hz: float, options: Optional[MagneticStepOptions] = None,
                       **deprecated_fields: Any) -> Tuple[List[int], _F64]: ...
def attitude_mahony(time_s: _ArrayLike, acc_mps2: _ArrayLike, gyro_radps: _ArrayLike,
                    mag: Optional[_ArrayLike] = None, options: Optional[MahonyOptions] = None,
                    **deprecated_fields: Any) -> AttitudeOutput: ...
def stance_headings(quaternions_wxyz: _ArrayLike, step_indices: _ArrayLike) -> _F64: ...
def positions_from_strides(stride_lengths_m: _ArrayLike, headings_rad: _ArrayLike, start_xy: _ArrayLike = ...,
                           options: Optional[StepCovarianceOptions] = None, **deprecated_fields: Any) -> StepTrack: ...
def positions_from_increments(increments_m: _ArrayLike, start_xy: _ArrayLike = ...,
                              options: Optional[StepCovarianceOptions] = None,
                              **deprecated_fields: Any) -> StepTrack: ...
def ins_zupt_increments(time_s: _ArrayLike, acc_mps2: _ArrayLike, quaternions_wxyz: _ArrayLike,
                        step_indices: _ArrayLike, options: Optional[InsZuptOptions] = None,
                        **deprecated_fields: Any) -> InsZuptIncrements: ...

class StreamingStepOptions:
    """Options of the streaming (causal) hand-held step detector. Fields and defaults: read them
    from the compiled struct (``StreamingStepOptions().to_dict()``); they equal
    ``pdr.handheld.HandheldOptions``' and are not restated here."""
    lowpass_hz: float
    highpass_hz: float
    filter_order: int
    rms_window_s: float
    threshold_fraction: float
    min_peak_mps2: float
    min_step_interval_s: float
    max_step_half_window_s: float
    complementary_tau_s: float
    rate_samples: int
    def __init__(self, **fields: Any) -> None: ...
    def replace(self, **fields: Any) -> "StreamingStepOptions": ...
    def to_dict(self) -> Dict[str, Any]: ...
    def validate(self) -> None: ...

class StreamingStepDetector:
    """Causal hand-held step detector, one IMU sample at a time."""
    def __init__(self, options: StreamingStepOptions = ...) -> None: ...
    def add_sample(self, t_s: float, acc_mps2: _ArrayLike, gyro_radps: _ArrayLike,
                   quat_xyzw: _ArrayLike) -> List[Tuple[float, int, float, float, float, float, float, float]]: ...
    @property
    def rate_hz(self) -> float: ...
    @property
    def first_time_s(self) -> float: ...
    @property
    def options(self) -> StreamingStepOptions: ...

def causal_steps(t_s: _ArrayLike, acc_mps2: _ArrayLike, gyro_radps: _ArrayLike, quat_xyzw: _ArrayLike,
                 options: StreamingStepOptions = ...) -> _F64: ...
def quaternion_from_rotation_vector(values: _ArrayLike) -> _F64: ...
