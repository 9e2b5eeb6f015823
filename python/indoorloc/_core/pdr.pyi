# Stubs of indoorloc._core.pdr: zero-velocity detection and the ZUPT-aided EKF.
from typing import Any, Dict, Iterator, List, Optional, Tuple

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

def shoe_statistic(
    acc_mps2: _ArrayLike,
    gyro_radps: _ArrayLike,
    window: int = 5,
    sigma_acc_mps2: float = 0.01,
    sigma_gyro_radps: float = ...,
    gravity_mps2: float = 9.81,
) -> _F64: ...
def shoe_detector(
    acc_mps2: _ArrayLike,
    gyro_radps: _ArrayLike,
    window: int = 5,
    threshold: float = 3e4,
    sigma_acc_mps2: float = 0.01,
    sigma_gyro_radps: float = ...,
    gravity_mps2: float = 9.81,
) -> npt.NDArray[np.bool_]: ...
def zupt_ekf(
    time_s: _ArrayLike,
    acc_mps2: _ArrayLike,
    gyro_radps: _ArrayLike,
    stance: _ArrayLike,
    sigma_acc_mps2: float = 0.5,
    sigma_gyro_radps: float = ...,
    sigma_zupt_mps: float = 0.01,
    gravity_mps2: float = 9.81,
    init_samples: int = 20,
    smooth: bool = False,
    sigma_stance_heading_rad: float = 0.0,
    min_stance_fraction: float = 0.02,
    max_plausible_swing_s: float = 5.0,
    max_plausible_stride_m: float = 4.0,
    max_median_stride_m: float = 2.5,
    max_stance_speed_mps: float = 4.0,
    speed_rise_factor: float = 3.0,
    min_rising_speed_mps: float = 1.0,
) -> ZuptEkfOutput: ...
def zero_velocity(
    acc_mps2: _ArrayLike,
    gyro_radps: _ArrayLike,
    rate_hz: float,
    rule: str = "swing_guard",
    threshold: float = 1e4,
    max_swing_s: float = 2.0,
    max_swing_ratio: float = 1.5,
    ladder_step_decades: float = 0.25,
    min_stance_s: float = 0.02,
    min_stance_share: float = 0.15,
    min_stance_fraction: float = 0.3,
    max_threshold: float = 1e7,
    min_plausible_swing_s: float = 0.2,
    low_motion_min_stance_s: float = 0.08,
    window: int = 5,
    sigma_acc_mps2: float = 0.01,
    sigma_gyro_radps: float = ...,
    gravity_mps2: float = 9.81,
) -> ZeroVelocityOutput: ...
def count_strides(
    stance: _ArrayLike,
    rate_hz: float,
    min_stance_s: float = 0.02,
    min_swing_s: float = 0.1,
    min_swing_fraction: float = 0.5,
    long_swing_factor: float = 1.7,
) -> StrideCountOutput: ...
def steps_acceleration(
    acc_mps2: _ArrayLike,
    rate_hz: float,
    window_s: float = 0.1,
    adaptive: bool = True,
    swing_threshold_mps2: float = 2.0,
    stance_threshold_mps2: float = 1.0,
    swing_fraction: float = 0.35,
    stance_fraction: float = 0.15,
    min_step_interval_s: float = 0.4,
) -> Tuple[List[int], _F64]: ...
def steps_gyro(
    gyro_radps: _ArrayLike,
    rate_hz: float,
    threshold_radps: float = 1.0,
    median_window_s: float = 0.1,
    min_swing_s: float = 0.2,
) -> List[int]: ...
def butterworth_sos(order: int, cutoff_hz: float, rate_hz: float, highpass: bool = False) -> _F64: ...
def sos_filter(sos: _ArrayLike, x: _ArrayLike, steady_state_start: bool = False) -> _F64: ...
def weinberg_features(
    acc_mps2: _ArrayLike,
    rate_hz: float,
    intervals: _ArrayLike,
    filter_order: int = 4,
    cutoff_hz: float = 3.0,
    steady_state_start: bool = True,
) -> _F64: ...
def weinberg_stride_lengths(
    acc_mps2: _ArrayLike,
    rate_hz: float,
    step_indices: _ArrayLike,
    k: float = 0.364,
    window_s: float = 0.15,
    filter_order: int = 4,
    cutoff_hz: float = 3.0,
    steady_state_start: bool = True,
) -> _F64: ...
def calibrate_weinberg_k(features: _ArrayLike, lengths_m: _ArrayLike) -> WeinbergCalibration: ...
def calibrate_weinberg_k_from_distance(features: _ArrayLike, distance_m: float) -> WeinbergCalibration: ...
def steps_magnetometer(
    mag: _ArrayLike,
    rate_hz: float,
    highpass_order: int = 2,
    highpass_hz: float = 0.5,
    threshold_fraction: float = 0.3,
    median_window_s: float = 0.1,
    min_swing_s: float = 0.2,
    min_rest_s: float = 0.15,
) -> Tuple[List[int], _F64]: ...
def attitude_mahony(
    time_s: _ArrayLike,
    acc_mps2: _ArrayLike,
    gyro_radps: _ArrayLike,
    mag: Optional[_ArrayLike] = None,
    kp: float = 1.0,
    ki: float = 0.05,
    kp_mag: float = 0.5,
    gravity_mps2: float = 9.81,
    acc_gate_mps2: float = 2.0,
    mag_norm_tolerance: float = 0.1,
    mag_dip_tolerance_rad: float = ...,
    init_samples: int = 20,
) -> AttitudeOutput: ...
def stance_headings(quaternions_wxyz: _ArrayLike, step_indices: _ArrayLike) -> _F64: ...
def positions_from_strides(
    stride_lengths_m: _ArrayLike,
    headings_rad: _ArrayLike,
    start_xy: _ArrayLike = ...,
    sigma_stride_length_m: float = 0.1,
    stride_length_sd_fraction: float = 0.1,
    sigma_heading_step_rad: float = ...,
    sigma_heading_initial_rad: float = 0.0,
) -> StepTrack: ...
def positions_from_increments(
    increments_m: _ArrayLike,
    start_xy: _ArrayLike = ...,
    sigma_stride_length_m: float = 0.1,
    stride_length_sd_fraction: float = 0.1,
    sigma_heading_step_rad: float = ...,
    sigma_heading_initial_rad: float = 0.0,
) -> StepTrack: ...
def ins_zupt_increments(
    time_s: _ArrayLike,
    acc_mps2: _ArrayLike,
    quaternions_wxyz: _ArrayLike,
    step_indices: _ArrayLike,
    window_s: float = 0.05,
    gravity_mps2: float = 9.81,
) -> InsZuptIncrements: ...

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
                   quat_xyzw: _ArrayLike) -> List[Tuple[float, int, float, float, float, float, float]]: ...
    @property
    def rate_hz(self) -> float: ...
    @property
    def first_time_s(self) -> float: ...
    @property
    def options(self) -> StreamingStepOptions: ...

def causal_steps(t_s: _ArrayLike, acc_mps2: _ArrayLike, gyro_radps: _ArrayLike, quat_xyzw: _ArrayLike,
                 options: StreamingStepOptions = ...) -> _F64: ...
def quaternion_from_rotation_vector(values: _ArrayLike) -> _F64: ...
