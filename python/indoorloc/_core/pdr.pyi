# Stubs of indoorloc._core.pdr: zero-velocity detection and the ZUPT-aided EKF.
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

_ArrayLike = npt.ArrayLike
_F64 = npt.NDArray[np.float64]

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
) -> Dict[str, Any]: ...
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
) -> Dict[str, Any]: ...
def count_strides(
    stance: _ArrayLike,
    rate_hz: float,
    min_stance_s: float = 0.02,
    min_swing_s: float = 0.1,
    min_swing_fraction: float = 0.5,
    long_swing_factor: float = 1.7,
) -> Dict[str, Any]: ...
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
def calibrate_weinberg_k(features: _ArrayLike, lengths_m: _ArrayLike) -> Dict[str, Any]: ...
def calibrate_weinberg_k_from_distance(features: _ArrayLike, distance_m: float) -> Dict[str, Any]: ...
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
) -> Dict[str, Any]: ...
def stance_headings(quaternions_wxyz: _ArrayLike, step_indices: _ArrayLike) -> _F64: ...
def positions_from_strides(
    stride_lengths_m: _ArrayLike,
    headings_rad: _ArrayLike,
    start_xy: _ArrayLike = ...,
    sigma_stride_length_m: float = 0.1,
    stride_length_sd_fraction: float = 0.1,
    sigma_heading_step_rad: float = ...,
    sigma_heading_initial_rad: float = 0.0,
) -> Dict[str, np.ndarray]: ...
def positions_from_increments(
    increments_m: _ArrayLike,
    start_xy: _ArrayLike = ...,
    sigma_stride_length_m: float = 0.1,
    stride_length_sd_fraction: float = 0.1,
    sigma_heading_step_rad: float = ...,
    sigma_heading_initial_rad: float = 0.0,
) -> Dict[str, np.ndarray]: ...
def ins_zupt_increments(
    time_s: _ArrayLike,
    acc_mps2: _ArrayLike,
    quaternions_wxyz: _ArrayLike,
    step_indices: _ArrayLike,
    window_s: float = 0.05,
    gravity_mps2: float = 9.81,
) -> Dict[str, np.ndarray]: ...
