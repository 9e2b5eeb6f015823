"""Step detection of hand-held PDR (:mod:`indoorloc.pdr.handheld`): the band-passed bounce
signal (:func:`step_signal`), its peaks (:func:`detect_steps_handheld`) and the steps with their
Weinberg lengths and per-step headings (:func:`handheld_steps`)."""

from __future__ import annotations

from typing import Any, Optional

import numpy as np
from scipy.signal import find_peaks

from indoorloc._core.pdr import (
    AccelerationStepOptions,
    butterworth_sos,
    sos_filter,
    steps_acceleration,
    weinberg_features,
)
from indoorloc.pdr.handheld_types import HandheldArrays, HandheldOptions, HandheldSteps, as_arrays
from indoorloc.pdr.orientation import (
    GRAVITY_MPS2,
    complementary_heading,
    gyro_heading,
    rotation_vector_heading,
    vertical_acceleration,
    wrap_angle,
)


def step_headings(t_s: np.ndarray, heading_rad: np.ndarray, steps: "HandheldSteps") -> np.ndarray:
    """Per-step mean of a per-sample (unwrapped) heading over [t_{k-1}, t_k], wrapped (M,)."""
    if steps.n_steps == 0:
        return np.zeros(0)
    prev_t = np.concatenate([[steps.start_t_s], steps.t_s[:-1]])
    return wrap_angle(_interval_mean(np.asarray(t_s), np.asarray(heading_rad), prev_t, steps.t_s))


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
        idx, _ = steps_acceleration(arrays.acc_mps2, rate,
                                    AccelerationStepOptions(min_step_interval_s=options.min_step_interval_s))
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
