"""Pedestrian dead reckoning with a hand-held phone (held flat in front, portrait).

The foot-mounted methods of :mod:`indoorloc.pdr` (paper 002) rely on the foot's stance; a phone in
the hand sees the body's vertical bounce instead, one oscillation per step. This module adapts them:

1. **Steps** (:func:`detect_steps_handheld`): the specific-force magnitude |a| (or its vertical
   component a_up, rotated into the east-north-up frame by the rotation vector), band-passed by a
   Butterworth low-pass and high-pass (:func:`indoorloc.pdr.butterworth_sos`,
   :func:`indoorloc.pdr.sos_filter`, run forward and backward for zero phase). A step is a local
   maximum above ``max(threshold_fraction x running RMS, min_peak_mps2)`` (the running RMS over
   ``rms_window_s`` makes the threshold follow the walker; the absolute floor keeps a phone held
   still from producing steps) and at least ``min_step_interval_s`` after the previous one
   (``scipy.signal.find_peaks``, largest peaks first).
2. **Length**: Weinberg's rule L_k = K (max ã - min ã)^(1/4) (paper 002 eq. 4) on the 3 Hz
   low-pass of |a| over the step's own interval (half-way to the neighbouring steps), through
   :func:`indoorloc.pdr.weinberg_features`; K from training walks by least squares of the waypoint
   distances on the feature sums between waypoints (:func:`calibrate_handheld`, which calls
   :func:`indoorloc.pdr.calibrate_weinberg_k`).
3. **Heading** of the phone's +y axis in the east-north frame (east = 0, north = pi/2), either from
   the rotation vector (Android TYPE_ROTATION_VECTOR: unit quaternion device -> ENU,
   :func:`rotation_vector_heading`) or from the gyroscope's rate about the vertical, integrated
   from the first rotation-vector heading (:func:`gyro_heading`), or the complementary blend of
   the two (:func:`complementary_heading`: gyro below 1 / (2 pi tau), rotation vector above).
   Per step, the mean heading over
   the step's interval. The floor frame differs from this frame by a yaw offset (map orientation,
   magnetic declination, how the phone is held) that a fusion filter estimates; its mean over the
   training walks is :attr:`HandheldOptions.yaw_offset_rad`.
4. **Uncertainty** per step, from cross-validation residuals on the training walks
   (:func:`calibrate_handheld`): with independent per-step length errors of sd ``f L_k``, the
   residual r_j of the path length between waypoints j, j+1 has variance ``f^2 sum L_k^2``, so
   ``f^2 = mean_j r_j^2 / sum_{k in j} L_k^2``; with independent per-step heading errors of sd
   s, the direction error d_j of an interval of n_j steps (after the walk's best yaw offset) has
   variance s^2 / n_j, so ``s^2 = mean_j n_j d_j^2``. Both assume independence; the real errors
   are partly systematic (per-walk scale, slowly varying magnetic disturbance), see
   docs/pdr_handheld.md.

Everything takes a walk of :mod:`indoorloc.io` (``IlcWalk``: ``accelerometer``, ``gyroscope``,
``rotation_quaternion_xyzw()``) or :class:`HandheldArrays`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np
from scipy.signal import find_peaks

from indoorloc._core.pdr import (
    butterworth_sos,
    calibrate_weinberg_k,
    sos_filter,
    steps_acceleration,
    weinberg_features,
)
from indoorloc.pdr.orientation import (  # noqa: F401  (re-exported: part of this module's API)
    GRAVITY_MPS2,
    _check_time_base,
    _finite_array,
    _quaternions,
    _up_row,
    complementary_heading,
    gyro_heading,
    rotation_vector_heading,
    vertical_acceleration,
    wrap_angle,
)
from indoorloc.validate import real_array

HEADING_SOURCES = ("rotation_vector", "gyro", "complementary")

# --------------------------------------------------------------------------------------------
# Inputs, options, outputs


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

    @property
    def n_steps(self) -> int:
        return int(self.t_s.shape[0])

    def brief_report(self) -> str:
        if self.n_steps == 0:
            return "handheld PDR: 0 steps"
        cad = 1.0 / np.median(np.diff(self.t_s)) if self.n_steps > 1 else float("nan")
        return (f"handheld PDR: {self.n_steps} steps, {self.length_m.sum():.1f} m, median stride "
                f"{np.median(self.length_m):.2f} m, cadence {cad:.2f} Hz, K {self.options.k:.3f}")


# --------------------------------------------------------------------------------------------
# Orientation (the helpers live in indoorloc.pdr.orientation and are re-exported here)


def step_headings(t_s: np.ndarray, heading_rad: np.ndarray, steps: "HandheldSteps") -> np.ndarray:
    """Per-step mean of a per-sample (unwrapped) heading over [t_{k-1}, t_k], wrapped (M,)."""
    if steps.n_steps == 0:
        return np.zeros(0)
    prev_t = np.concatenate([[steps.start_t_s], steps.t_s[:-1]])
    return wrap_angle(_interval_mean(np.asarray(t_s), np.asarray(heading_rad), prev_t, steps.t_s))


# --------------------------------------------------------------------------------------------
# Step detection


def _zero_phase(sos: np.ndarray, x: np.ndarray) -> np.ndarray:
    y = sos_filter(sos, x, True)
    return sos_filter(sos, y[::-1].copy(), True)[::-1].copy()


def step_signal(arrays: HandheldArrays, options: HandheldOptions) -> np.ndarray:
    """The band-passed signal the peak detector runs on (N,) [m/s^2]."""
    rate = arrays.rate_hz
    if options.highpass_hz >= 0.45 * rate:
        raise ValueError(f"indoorloc: argument 'options': HandheldOptions.highpass_hz = {options.highpass_hz:g} Hz "
                         f"needs a sample rate above {options.highpass_hz / 0.45:g} Hz; the walk's times (t_s) "
                         f"give {rate:g} Hz")
    if options.signal == "vertical":
        s = vertical_acceleration(arrays.acc_mps2, arrays.quat_xyzw)
    else:
        s = np.linalg.norm(arrays.acc_mps2, axis=1) - GRAVITY_MPS2
    order = int(options.filter_order)
    lp = butterworth_sos(order, min(options.lowpass_hz, 0.45 * rate), rate)
    hp = butterworth_sos(order, options.highpass_hz, rate, True)
    return _zero_phase(hp, _zero_phase(lp, s))


def detect_steps_handheld(arrays: HandheldArrays, options: HandheldOptions) -> np.ndarray:
    """Sample indices of the steps (increasing)."""
    rate = arrays.rate_hz
    if options.method == "variance":
        idx, _ = steps_acceleration(arrays.acc_mps2, rate, min_step_interval_s=options.min_step_interval_s)
        return np.asarray(idx, dtype=np.int64)
    s = step_signal(arrays, options)
    n = s.shape[0]
    half = max(1, int(round(0.5 * options.rms_window_s * rate)))
    c = np.concatenate([[0.0], np.cumsum(s * s)])
    lo = np.clip(np.arange(n) - half, 0, n)
    hi = np.clip(np.arange(n) + half + 1, 0, n)
    rms = np.sqrt((c[hi] - c[lo]) / (hi - lo))
    thr = np.maximum(options.threshold_fraction * rms, options.min_peak_mps2)
    distance = max(1, int(round(options.min_step_interval_s * rate)))
    idx, _ = find_peaks(s, height=thr, distance=distance)
    return idx.astype(np.int64)


def _interval_mean(t_s: np.ndarray, y: np.ndarray, a_s: np.ndarray, b_s: np.ndarray) -> np.ndarray:
    """Mean of y(t) (piecewise linear) over [a, b] per row, via the cumulative trapezoid integral."""
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(t_s))])
    ia = np.interp(a_s, t_s, integral)
    ib = np.interp(b_s, t_s, integral)
    width = b_s - a_s
    mid = np.interp(0.5 * (a_s + b_s), t_s, y)
    out = mid.copy()
    ok = width > 1e-9
    out[ok] = (ib[ok] - ia[ok]) / width[ok]
    return out


def handheld_steps(walk_or_arrays: Any, options: Optional[HandheldOptions] = None) -> HandheldSteps:
    """Steps of a hand-held phone walk: time, Weinberg length, heading and their sds.

    Parameters
    ----------
    walk_or_arrays : IlcWalk or HandheldArrays
        Accelerometer (N, 3) m/s^2, gyroscope (N, 3) rad/s and rotation vector on one time base.
    options : HandheldOptions, optional
        Defaults as documented there (K etc. from :func:`calibrate_handheld` on training walks).

    Returns
    -------
    HandheldSteps
        (M,) arrays per step. The heading of step k is the mean heading over [t_{k-1}, t_k]
        (the first step: the median step interval before t_0), the motion the step stands for.
    """
    options = options or HandheldOptions()
    options.validate()
    arrays = as_arrays(walk_or_arrays)
    t, rate = arrays.t_s, arrays.rate_hz
    n = t.shape[0]
    idx = detect_steps_handheld(arrays, options)
    m = idx.shape[0]
    h_rv = np.unwrap(rotation_vector_heading(arrays.quat_xyzw))
    h_gy = gyro_heading(t, arrays.gyro_radps, arrays.quat_xyzw)
    if m == 0:
        e = np.zeros(0)
        return HandheldSteps(e, idx, e, e, e, e, e, e, e, e, float(t[0]), options)
    ts = t[idx]
    gap = float(np.median(np.diff(ts))) if m > 1 else 0.5
    gap = min(max(gap, options.min_step_interval_s), 2 * options.max_step_half_window_s)
    start = max(float(t[0]), ts[0] - gap)
    prev_t = np.concatenate([[start], ts[:-1]])
    # Weinberg interval: half-way to the neighbouring steps, at most max_step_half_window_s.
    hw = int(round(options.max_step_half_window_s * rate))
    left = np.concatenate([[idx[0] - hw], (idx[:-1] + idx[1:]) // 2])
    right = np.concatenate([(idx[:-1] + idx[1:]) // 2, [idx[-1] + hw]])
    left = np.clip(np.maximum(left, idx - hw), 0, n - 1)
    right = np.clip(np.minimum(right, idx + hw), 0, n - 1)
    intervals = np.column_stack([left, right]).astype(np.int32)
    feat = np.asarray(weinberg_features(arrays.acc_mps2, rate, intervals), dtype=np.float64)
    length = options.k * feat
    hr = _interval_mean(t, h_rv, prev_t, ts)
    hg = _interval_mean(t, h_gy, prev_t, ts)
    hc = _interval_mean(t, complementary_heading(t, h_rv, h_gy, options.complementary_tau_s), prev_t, ts)
    heading = {"rotation_vector": hr, "gyro": hg, "complementary": hc}[options.heading_source]
    return HandheldSteps(
        t_s=ts, index=idx, length_m=length, heading_rad=wrap_angle(heading),
        length_sd_m=options.length_sd_fraction * length,
        heading_sd_rad=np.full(m, options.heading_sd_rad), feature=feat,
        heading_rotation_vector_rad=wrap_angle(hr), heading_gyro_rad=wrap_angle(hg),
        heading_complementary_rad=wrap_angle(hc),
        start_t_s=start, options=options)


# --------------------------------------------------------------------------------------------
# Between waypoints


def cumulative_at(steps: HandheldSteps, values: np.ndarray, t_query: np.ndarray) -> np.ndarray:
    """Cumulative sum of per-step values (M,) or (M, d) at the query times, each step's value
    accrued linearly over [t_{k-1}, t_k] (the first from ``start_t_s``); constant outside."""
    t_query = np.asarray(t_query, dtype=np.float64)
    v = np.asarray(values, dtype=np.float64)
    one_d = v.ndim == 1
    if v.ndim not in (1, 2) or v.shape[0] != steps.n_steps:
        raise ValueError(f"indoorloc: argument 'values': expected shape ({steps.n_steps},) or "
                         f"({steps.n_steps}, d), one row per step, got {v.shape}")
    v = v[:, None] if one_d else v  # not reshape(n, -1): a walk without steps has n = 0
    if steps.n_steps == 0:
        out = np.zeros((t_query.shape[0], v.shape[1]))
        return out[:, 0] if one_d else out
    knots_t = np.concatenate([[steps.start_t_s], steps.t_s])
    knots_v = np.vstack([np.zeros((1, v.shape[1])), np.cumsum(v, axis=0)])
    out = np.column_stack([np.interp(t_query, knots_t, knots_v[:, i]) for i in range(v.shape[1])])
    return out[:, 0] if one_d else out


def step_displacements(steps: HandheldSteps, heading: str = "selected", yaw_offset_rad: float = 0.0) -> np.ndarray:
    """(M, 2) east/north displacement of each step, heading source ``"selected"``,
    ``"rotation_vector"``, ``"gyro"`` or ``"complementary"``, rotated by ``yaw_offset_rad`` [rad]
    (finite)."""
    if not (isinstance(yaw_offset_rad, (int, float, np.integer, np.floating)) and math.isfinite(yaw_offset_rad)):
        raise ValueError(f"indoorloc: argument 'yaw_offset_rad': must be a finite angle [rad], got {yaw_offset_rad!r}")
    _check_finite_steps(steps)
    h = _heading_of(steps, heading) + yaw_offset_rad
    return steps.length_m[:, None] * np.column_stack([np.cos(h), np.sin(h)])


@dataclass
class WaypointIntervals:
    """PDR against the waypoints of one walk, per interval j = (waypoint j, waypoint j+1) (J)."""

    distance_m: np.ndarray          #: (J,) straight distance between the waypoints (the truth)
    direction_rad: np.ndarray       #: (J,) direction of the straight line (floor frame)
    n_steps: np.ndarray             #: (J,) fractional step count in the interval
    feature_sum: np.ndarray         #: (J,) sum of Weinberg features (fractional at the ends)
    path_m: np.ndarray              #: (J,) PDR path length (sum of step lengths)
    length_sq_sum: np.ndarray       #: (J,) sum of squared step lengths (for the length sd fit)
    disp_rv_m: np.ndarray           #: (J, 2) PDR displacement, rotation-vector heading (phone frame)
    disp_gyro_m: np.ndarray         #: (J, 2) same, gyro heading
    disp_comp_m: np.ndarray         #: (J, 2) same, complementary heading

    def displacement(self, heading: str) -> np.ndarray:
        """(J, 2) PDR displacement with the heading source's per-step headings."""
        return {"rotation_vector": self.disp_rv_m, "gyro": self.disp_gyro_m, "complementary": self.disp_comp_m}[heading]


def waypoint_intervals(steps: HandheldSteps, waypoint_t_s: np.ndarray, waypoint_xy_m: np.ndarray) -> WaypointIntervals:
    """Per-interval sums of the steps between consecutive waypoints (fractional at the ends).
    ``waypoint_t_s`` (W,) [s] finite and non-decreasing, ``waypoint_xy_m`` (W, 2) [m] finite."""
    wt = _finite_array(waypoint_t_s, "waypoint_t_s").ravel()
    wxy = _finite_array(waypoint_xy_m, "waypoint_xy_m")
    if wxy.ndim != 2 or wxy.shape != (wt.size, 2):
        raise ValueError(f"indoorloc: argument 'waypoint_xy_m': expected shape ({wt.size}, 2) to match waypoint_t_s, "
                         f"got {wxy.shape}")
    if wt.size and np.any(np.diff(wt) < 0):
        raise ValueError("indoorloc: argument 'waypoint_t_s': times must be non-decreasing")
    d = np.diff(wxy, axis=0)
    vals = np.column_stack([np.ones(steps.n_steps), steps.feature, steps.length_m, steps.length_m ** 2,
                            step_displacements(steps, "rotation_vector"), step_displacements(steps, "gyro"),
                            step_displacements(steps, "complementary")])
    c = np.diff(cumulative_at(steps, vals, wt), axis=0)
    return WaypointIntervals(
        distance_m=np.hypot(d[:, 0], d[:, 1]), direction_rad=np.arctan2(d[:, 1], d[:, 0]),
        n_steps=c[:, 0], feature_sum=c[:, 1], path_m=c[:, 2], length_sq_sum=c[:, 3],
        disp_rv_m=c[:, 4:6], disp_gyro_m=c[:, 6:8], disp_comp_m=c[:, 8:10])


def best_yaw_offset(truth_dir_rad: np.ndarray, pdr_disp_m: np.ndarray, weights: Optional[np.ndarray] = None) -> float:
    """The constant rotation (floor minus phone frame) that best aligns the PDR displacements
    with the true directions: the argument of sum_j w_j exp(i (truth_j - pdr_j)) |pdr_j|."""
    pd = np.arctan2(pdr_disp_m[:, 1], pdr_disp_m[:, 0])
    w = np.hypot(pdr_disp_m[:, 0], pdr_disp_m[:, 1]) if weights is None else np.asarray(weights)
    z = np.sum(w * np.exp(1j * (truth_dir_rad - pd)))
    return float(np.angle(z)) if abs(z) > 0 else 0.0


# --------------------------------------------------------------------------------------------
# Calibration on training walks


@dataclass
class HandheldCalibration:
    """What :func:`calibrate_handheld` fitted, with the options carrying it."""

    options: HandheldOptions
    k: float
    k_rms_residual_m: float         #: RMS of K F_j - D_j over the training intervals
    n_intervals: int
    yaw_offset_rad: float           #: circular mean over training walks of the best per-walk offset
    yaw_offset_spread_rad: float    #: circular sd of those per-walk offsets
    length_sd_fraction: float
    heading_sd_rad: float

    def brief_report(self) -> str:
        return (f"K {self.k:.3f} (RMS {self.k_rms_residual_m:.2f} m over {self.n_intervals} intervals), "
                f"yaw offset {math.degrees(self.yaw_offset_rad):.1f} deg (spread "
                f"{math.degrees(self.yaw_offset_spread_rad):.1f}), length sd {self.length_sd_fraction:.3f} L, "
                f"heading sd {math.degrees(self.heading_sd_rad):.1f} deg")


def calibrate_handheld(walks: Iterable[Any], options: Optional[HandheldOptions] = None,
                       min_distance_m: float = 1.0,
                       steps_cache: Optional[Sequence[HandheldSteps]] = None) -> HandheldCalibration:
    """Fit K, the yaw offset and the per-step sds on training walks with waypoints.

    K: least squares of the straight waypoint distances D_j on the feature sums F_j of the steps
    between them (:func:`indoorloc.pdr.calibrate_weinberg_k`), intervals with D_j >= min_distance_m.
    Then, with that K: the per-walk best yaw offset (its circular mean is ``yaw_offset_rad``), the
    length sd fraction ``f^2 = mean r_j^2 / sum L_k^2`` and the heading sd ``s^2 = mean n_j d_j^2``
    (d_j the direction error after the walk's own offset, intervals >= 2 m). The sds use the heading
    of ``options.heading_source``. ``steps_cache`` (same order as walks) skips step detection.
    """
    options = options or HandheldOptions()
    options.validate()
    walks = list(walks)
    if not walks:
        raise ValueError("indoorloc: argument 'walks': no walk to calibrate on (need at least one walk with waypoints)")
    if steps_cache is not None and len(steps_cache) != len(walks):
        raise ValueError(f"indoorloc: argument 'steps_cache': {len(steps_cache)} entries for {len(walks)} walks")
    intervals: List[WaypointIntervals] = []
    for i, w in enumerate(walks):
        st = steps_cache[i] if steps_cache is not None else handheld_steps(w, options)
        intervals.append(waypoint_intervals(st, w.waypoint_t_s, w.waypoint_xy_m))
    return calibrate_from_intervals(intervals, options, min_distance_m)


def calibrate_from_intervals(intervals: Sequence[WaypointIntervals], options: Optional[HandheldOptions] = None,
                             min_distance_m: float = 1.0) -> HandheldCalibration:
    """:func:`calibrate_handheld` from each walk's :func:`waypoint_intervals` (steps detected with
    ``options``): what a site file keeps per survey walk, so that adding a walk recalibrates the
    floor without re-reading the others."""
    options = options or HandheldOptions()
    options.validate()
    per_walk = [(None, iv) for iv in intervals]
    if not per_walk:
        raise ValueError("indoorloc: argument 'intervals': no walk to calibrate on (need at least one walk with "
                         "waypoints)")
    F = np.concatenate([iv.feature_sum for _, iv in per_walk])
    D = np.concatenate([iv.distance_m for _, iv in per_walk])
    keep = D >= min_distance_m
    if keep.sum() < 1 or not np.any(F[keep] > 0):
        raise ValueError("indoorloc: calibrate_handheld: no waypoint interval with steps")
    cal = calibrate_weinberg_k(F[keep], D[keep])
    k = float(cal["k"])
    scale = k / options.k  # steps were computed with options.k
    r2_over = []
    offsets, off_w = [], []
    dir_terms = []
    for _, iv in per_walk:
        path = iv.path_m * scale
        ok = (iv.distance_m >= min_distance_m) & (iv.length_sq_sum > 0)
        r2_over.append((path[ok] - iv.distance_m[ok]) ** 2 / (iv.length_sq_sum[ok] * scale * scale))
        disp = iv.displacement(options.heading_source) * scale
        okd = (iv.distance_m >= 2.0) & (np.hypot(disp[:, 0], disp[:, 1]) > 0)
        if okd.sum() >= 1:
            off = best_yaw_offset(iv.direction_rad[okd], disp[okd])
            offsets.append(off)
            off_w.append(float(iv.distance_m[okd].sum()))
            if okd.sum() >= 2:  # one interval fits its own offset exactly
                err = wrap_angle(iv.direction_rad[okd] - np.arctan2(disp[okd, 1], disp[okd, 0]) - off)
                dir_terms.append(iv.n_steps[okd] * err ** 2 * okd.sum() / (okd.sum() - 1))
    r2 = np.concatenate(r2_over) if r2_over else np.zeros(0)
    f = float(np.sqrt(np.mean(r2))) if r2.size else options.length_sd_fraction
    z = np.sum(np.asarray(off_w) * np.exp(1j * np.asarray(offsets))) if offsets else 0j
    yaw = float(np.angle(z)) if offsets else 0.0
    R = abs(z) / max(sum(off_w), 1e-12) if offsets else 0.0
    spread = float(np.sqrt(-2.0 * np.log(max(R, 1e-12)))) if offsets else float("nan")
    dt = np.concatenate(dir_terms) if dir_terms else np.zeros(0)
    s = float(np.sqrt(np.mean(dt))) if dt.size else options.heading_sd_rad
    new = replace(options, k=k, yaw_offset_rad=yaw, length_sd_fraction=f, heading_sd_rad=s)
    return HandheldCalibration(new, k, float(cal["rms_residual_m"]), int(keep.sum()), yaw, spread, f, s)


def rescale(steps: HandheldSteps, options: HandheldOptions) -> HandheldSteps:
    """The same steps under new K / sds / heading source (no re-detection; detector settings must
    be equal). ``options`` is validated (a NaN ``k`` raises ValueError)."""
    if not isinstance(options, HandheldOptions):
        raise ValueError(f"indoorloc: argument 'options': need a HandheldOptions, got {type(options).__name__}")
    options.validate()
    length = options.k * steps.feature
    heading = _heading_of(steps, options.heading_source)
    return replace(steps, length_m=length, length_sd_m=options.length_sd_fraction * length,
                   heading_rad=heading.copy(), heading_sd_rad=np.full(steps.n_steps, options.heading_sd_rad),
                   options=options)


def _heading_of(steps: HandheldSteps, source: str, arg: str = "heading") -> np.ndarray:
    table = {"selected": steps.heading_rad, "rotation_vector": steps.heading_rotation_vector_rad,
             "gyro": steps.heading_gyro_rad, "complementary": steps.heading_complementary_rad}
    if not isinstance(source, str) or source not in table:
        raise ValueError(f"indoorloc: argument '{arg}': {source!r} is not one of {', '.join(table)}")
    return table[source]


def _check_finite_steps(steps: HandheldSteps) -> None:
    """ValueError naming the field of ``steps`` that holds NaN or inf (times, lengths, headings)."""
    for name in ("t_s", "length_m", "heading_rad", "feature", "heading_rotation_vector_rad", "heading_gyro_rad",
                 "heading_complementary_rad"):
        v = np.asarray(getattr(steps, name), dtype=np.float64)
        if not np.all(np.isfinite(v)):
            raise ValueError(f"indoorloc: argument 'steps': steps.{name} holds NaN or inf")
    if not math.isfinite(float(steps.start_t_s)):
        raise ValueError("indoorloc: argument 'steps': steps.start_t_s must be finite")


def pdr_track(steps: HandheldSteps, start_xy_m: Sequence[float], t_query: np.ndarray, heading: str = "selected",
              yaw_offset_rad: float = 0.0) -> np.ndarray:
    """(Q, 2) PDR positions [m] at the query times ``t_query`` (Q,) [s] from a known start
    ``start_xy_m`` (2,) [m], headings of source ``heading`` rotated by ``yaw_offset_rad`` [rad].
    Everything must be finite: NaN steps, times or offsets raise ValueError naming the argument."""
    start = _finite_array(start_xy_m, "start_xy_m").ravel()
    if start.shape != (2,):
        raise ValueError(f"indoorloc: argument 'start_xy_m': expected (x, y), got shape {start.shape}")
    tq = _finite_array(t_query, "t_query")
    if tq.ndim > 1:
        raise ValueError(f"indoorloc: argument 't_query': expected a 1-D array of times, got shape {tq.shape}")
    disp = step_displacements(steps, heading, yaw_offset_rad)
    return start[None, :] + cumulative_at(steps, disp, np.atleast_1d(tq))


__all__ = [
    "HandheldArrays",
    "HandheldCalibration",
    "HandheldOptions",
    "HandheldSteps",
    "WaypointIntervals",
    "as_arrays",
    "best_yaw_offset",
    "calibrate_from_intervals",
    "calibrate_handheld",
    "complementary_heading",
    "cumulative_at",
    "detect_steps_handheld",
    "gyro_heading",
    "handheld_steps",
    "pdr_track",
    "rescale",
    "rotation_vector_heading",
    "step_displacements",
    "step_headings",
    "step_signal",
    "vertical_acceleration",
    "waypoint_intervals",
    "wrap_angle",
]
