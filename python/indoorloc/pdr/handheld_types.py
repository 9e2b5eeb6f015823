"""The records of hand-held PDR (:mod:`indoorloc.pdr.handheld`): the phone's sensor streams
(:class:`HandheldArrays`, built from a walk by :func:`as_arrays`), the settings
(:class:`HandheldOptions`) and the detected steps (:class:`HandheldSteps`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from indoorloc.pdr.orientation import _check_time_base, _quaternions
from indoorloc.validate import real_array

HEADING_SOURCES = ("rotation_vector", "gyro", "complementary")

#: Largest sensor sample accepted by :class:`HandheldArrays`: phone accelerometers saturate
#: below about 2000 m/s^2 (200 g) and gyroscopes below about 70 rad/s, so larger values are unit
#: or parsing errors; the bounds also keep |a|^2 and the step filters finite (1e160 m/s^2 used to
#: reach the filter and be reported under its internal argument name 'x').
MAX_ACC_MPS2 = 1e4
MAX_GYRO_RADPS = 1e3


def _real_array(values: Any, arg: str) -> np.ndarray:
    """float64 array of ``values``; None, complex, string, object and ragged input refused by name."""
    return real_array(values, arg, finite=False)


@dataclass
class HandheldArrays:
    """Phone sensor streams on one time base (the ILC files share the time stamps of all streams).

    t_s (N,) s increasing; acc_mps2 (N, 3) device-frame specific force; gyro_radps (N, 3) device
    frame; quat_xyzw (N, 4) unit quaternions rotating the device frame into east-north-up
    (Android rotation vector with w completed).
    """

    t_s: np.ndarray
    acc_mps2: np.ndarray
    gyro_radps: np.ndarray
    quat_xyzw: np.ndarray

    def __post_init__(self) -> None:
        self.t_s = _real_array(self.t_s, "t_s")
        if self.t_s.ndim != 1:
            raise ValueError(f"indoorloc: argument 't_s': need a 1-D array of times, got shape {self.t_s.shape}")
        n = self.t_s.shape[0]
        if self.t_s.ndim != 1 or n < 2:
            raise ValueError("indoorloc: argument 't_s': need a 1-D array of at least 2 times")
        if not np.all(np.isfinite(self.t_s)) or np.any(np.diff(self.t_s) <= 0):
            raise ValueError("indoorloc: argument 't_s': times must be finite and increasing")
        _check_time_base(self.t_s, "t_s")
        for name, cols, bound in (("acc_mps2", 3, MAX_ACC_MPS2), ("gyro_radps", 3, MAX_GYRO_RADPS),
                                  ("quat_xyzw", 4, None)):
            a = np.ascontiguousarray(_real_array(getattr(self, name), name))
            if a.shape != (n, cols):
                raise ValueError(f"indoorloc: argument '{name}': shape {a.shape}, expected ({n}, {cols})")
            if not np.all(np.isfinite(a)):
                raise ValueError(f"indoorloc: argument '{name}': values must be finite")
            if bound is not None and np.any(np.abs(a) > bound):
                r, c = np.argwhere(np.abs(a) > bound)[0]
                raise ValueError(f"indoorloc: argument '{name}': entry ({r}, {c}) = {a[r, c]:g} is beyond "
                                 f"±{bound:g} (no phone sensor measures that: a unit or parsing error)")
            setattr(self, name, a)
        _quaternions(self.quat_xyzw, "quat_xyzw")

    @property
    def rate_hz(self) -> float:
        return (self.t_s.shape[0] - 1) / (self.t_s[-1] - self.t_s[0])


def as_arrays(walk_or_arrays: Any) -> HandheldArrays:
    """:class:`HandheldArrays` from an ``IlcWalk`` (duck-typed) or a HandheldArrays."""
    if isinstance(walk_or_arrays, HandheldArrays):
        return walk_or_arrays
    try:
        acc = walk_or_arrays.accelerometer
        gyro = walk_or_arrays.gyroscope
        quat = walk_or_arrays.rotation_quaternion_xyzw()
    except AttributeError as e:
        raise ValueError("indoorloc: argument 'walk_or_arrays': need an IlcWalk or HandheldArrays") from e
    n = min(acc.values.shape[0], gyro.values.shape[0], quat.shape[0])
    if n < 2:
        raise ValueError("indoorloc: argument 'walk_or_arrays': fewer than 2 sensor samples")
    if not (np.array_equal(acc.t_s[:n], gyro.t_s[:n]) and np.array_equal(acc.t_s[:n], walk_or_arrays.rotation_vector.t_s[:n])):
        # Streams on different clocks: resample gyro and rotation vector onto the accelerometer times.
        t = acc.t_s
        g = np.column_stack([np.interp(t, gyro.t_s, gyro.values[:, i]) for i in range(3)])
        qt = walk_or_arrays.rotation_vector.t_s
        q = np.column_stack([np.interp(t, qt, quat[:, i]) for i in range(4)])
        q /= np.linalg.norm(q, axis=1, keepdims=True)
        return HandheldArrays(t, acc.values[:, :3], g, q)
    return HandheldArrays(acc.t_s[:n], acc.values[:n, :3], gyro.values[:n, :3], quat[:n])


#: Longest window or time constant :class:`HandheldOptions` accepts [s] (one day).
MAX_WINDOW_S = 86400.0


@dataclass
class HandheldOptions:
    """Settings of :func:`handheld_steps`. Defaults were chosen by cross-validation on the ILC 2020
    site-2 walks (docs/pdr_handheld.md); :func:`calibrate_handheld` refits the data-driven ones
    (``k``, ``yaw_offset_rad``, ``length_sd_fraction``, ``heading_sd_rad``) on training walks."""

    method: str = "peaks"               #: "peaks" (this module) or "variance" (paper 002's detector, pdr.steps_acceleration)
    signal: str = "magnitude"           #: "magnitude" |a| or "vertical" a_up (rotation vector) for the peak detector
    lowpass_hz: float = 3.0             #: band-pass upper edge [Hz] (steps at 1.5-2.2 Hz)
    highpass_hz: float = 0.5            #: band-pass lower edge [Hz] (removes gravity / slow tilt)
    filter_order: int = 2               #: Butterworth order of each edge (run forward and backward)
    rms_window_s: float = 2.0           #: running RMS window (centred) for the adaptive threshold [s]
    threshold_fraction: float = 0.5     #: peak must exceed this x running RMS
    min_peak_mps2: float = 1.0          #: ... and this absolute level (a phone held still gives no steps) [m/s^2]
    min_step_interval_s: float = 0.4    #: at most one step per this interval [s]
    max_step_half_window_s: float = 0.4 #: Weinberg window: half-way to the neighbour steps, at most this [s]
    k: float = 0.41                     #: Weinberg K [m / (m/s^2)^(1/4)] (refit by calibrate_handheld)
    heading_source: str = "rotation_vector"  #: "rotation_vector", "gyro" or "complementary" for HandheldSteps.heading_rad
    complementary_tau_s: float = 10.0   #: time constant of the complementary heading (gyro below, rotation vector above) [s]
    yaw_offset_rad: float = 0.0         #: mean floor-frame minus phone-frame heading on training walks (not applied to heading_rad)
    length_sd_fraction: float = 0.42    #: length_sd_m = this x length (refit from CV residuals)
    heading_sd_rad: float = 0.87        #: per-step heading sd, 50 deg (refit from CV residuals; see docs)

    def validate(self) -> None:
        """Raises ValueError naming the first invalid field."""
        def bad(name: str, why: str) -> None:
            raise ValueError(f"indoorloc: HandheldOptions.{name}: {why}")
        if self.method not in ("peaks", "variance"):
            bad("method", f"{self.method!r} is not 'peaks' or 'variance'")
        if self.signal not in ("magnitude", "vertical"):
            bad("signal", f"{self.signal!r} is not 'magnitude' or 'vertical'")
        if self.heading_source not in HEADING_SOURCES:
            bad("heading_source", f"{self.heading_source!r} is not one of {HEADING_SOURCES}")
        if not 0 < self.highpass_hz < self.lowpass_hz:
            bad("highpass_hz", "need 0 < highpass_hz < lowpass_hz")
        if not 1 <= int(self.filter_order) <= 8:
            bad("filter_order", "need 1..8")
        for name in ("rms_window_s", "min_step_interval_s", "max_step_half_window_s", "k", "complementary_tau_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                bad(name, f"must be finite and > 0, got {v}")
        # Windows become sample counts (int(window x rate)): beyond a day they overflow or exceed
        # any recording, so they are refused here with their name rather than as an OverflowError.
        for name in ("rms_window_s", "min_step_interval_s", "max_step_half_window_s", "complementary_tau_s"):
            v = getattr(self, name)
            if v > MAX_WINDOW_S:
                bad(name, f"must be at most {MAX_WINDOW_S:g} s, got {v}")
        for name in ("threshold_fraction", "min_peak_mps2", "length_sd_fraction", "heading_sd_rad"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                bad(name, f"must be finite and >= 0, got {v}")
        if not math.isfinite(self.yaw_offset_rad):
            bad("yaw_offset_rad", "must be finite")


@dataclass
class HandheldSteps:
    """Per detected step (M): time on the walk's time base, length, heading (phone +y axis, east =
    0, north = pi/2, i.e. the floor frame up to a yaw offset) and their 1-sigma uncertainties."""

    t_s: np.ndarray                 #: (M,) step time (peak of the bounce) [s]
    index: np.ndarray               #: (M,) sample index of the step
    length_m: np.ndarray            #: (M,) Weinberg length [m]
    heading_rad: np.ndarray         #: (M,) heading of options.heading_source, mean over the step interval [rad]
    length_sd_m: np.ndarray         #: (M,) 1-sigma length [m]
    heading_sd_rad: np.ndarray      #: (M,) 1-sigma heading [rad]
    feature: np.ndarray             #: (M,) Weinberg feature (max - min of LP|a|)^(1/4)
    heading_rotation_vector_rad: np.ndarray  #: (M,) heading from the rotation vector
    heading_gyro_rad: np.ndarray    #: (M,) heading from gyro integration
    heading_complementary_rad: np.ndarray  #: (M,) complementary heading (options.complementary_tau_s)
    start_t_s: float                #: time at which the first step's motion starts [s]
    options: HandheldOptions = field(repr=False, default_factory=HandheldOptions)
    #: (M,) time of the sample that confirmed each step [s]: the causal (streaming) detector's
    #: steps only (``pdr.streaming``); None for the whole-walk detector's.
    confirmed_t_s: Optional[np.ndarray] = field(default=None, repr=False)

    @property
    def n_steps(self) -> int:
        return int(self.t_s.shape[0])

    def brief_report(self) -> str:
        if self.n_steps == 0:
            return "handheld PDR: 0 steps"
        cad = 1.0 / np.median(np.diff(self.t_s)) if self.n_steps > 1 else float("nan")
        return (f"handheld PDR: {self.n_steps} steps, {self.length_m.sum():.1f} m, median stride "
                f"{np.median(self.length_m):.2f} m, cadence {cad:.2f} Hz, K {self.options.k:.3f}")
