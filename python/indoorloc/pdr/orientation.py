"""Orientation of a hand-held phone from its rotation vector and gyroscope (vectorised numpy).

Headings follow :mod:`indoorloc.pdr.handheld`'s convention: the device +y axis in the east-north
frame, east = 0, north = pi/2. :func:`rotation_vector_heading` reads it from the Android rotation
vector, :func:`gyro_heading` integrates the rate about the vertical, :func:`complementary_heading`
blends the two; :func:`vertical_acceleration` is the up component of the specific force minus g.
Split out of ``handheld`` (one concept per file); every name is re-exported there.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from indoorloc._core.pdr import butterworth_sos, sos_filter
from indoorloc.validate import real_array

__all__ = ["GRAVITY_MPS2", "complementary_heading", "gyro_heading", "rotation_vector_heading",
           "vertical_acceleration", "wrap_angle"]

GRAVITY_MPS2 = 9.80665



def rotation_vector_heading(quat_xyzw: np.ndarray) -> np.ndarray:
    """Heading [rad] of the device +y axis in the east-north frame (east = 0, north = pi/2).

    R(q) rotates device into ENU; its second column is the +y axis in ENU:
    (2(xy - wz), 1 - 2(x^2 + z^2), 2(yz + wx)). Heading = atan2(north, east) of its horizontal part.
    """
    q = _quaternions(quat_xyzw, "quat_xyzw")
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    east = 2.0 * (x * y - w * z)
    north = 1.0 - 2.0 * (x * x + z * z)
    return np.arctan2(north, east)


def _up_row(quat_xyzw: np.ndarray) -> np.ndarray:
    """Third row of R(q) (N, 3): the device-frame direction of ENU 'up'."""
    x, y, z, w = (quat_xyzw[:, i] for i in range(4))
    return np.column_stack([2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)])


def vertical_acceleration(acc_mps2: np.ndarray, quat_xyzw: np.ndarray) -> np.ndarray:
    """Up component of the specific force minus g [m/s^2] (N,). ``acc_mps2`` (N, 3) and
    ``quat_xyzw`` (N, 4) finite (NaN is refused by name, not passed on)."""
    acc, q = _rows(acc_mps2, 3, "acc_mps2"), _quaternions(quat_xyzw, "quat_xyzw")
    _same_length(q, "quat_xyzw", acc.shape[0], "acc_mps2")
    return np.einsum("ij,ij->i", _up_row(q), acc) - GRAVITY_MPS2


def gyro_heading(t_s: np.ndarray, gyro_radps: np.ndarray, quat_xyzw: np.ndarray) -> np.ndarray:
    """Heading [rad] by integrating the rate about the vertical, omega_up = R(q)[2, :] . omega (the
    rotation vector gives only the tilt here), trapezoid rule, started at the first
    rotation-vector heading. Unwrapped (continuous, not folded into (-pi, pi]).
    ``t_s`` (N,) [s] finite and increasing, ``gyro_radps`` (N, 3), ``quat_xyzw`` (N, 4) finite."""
    t_s = _times(t_s, "t_s")
    gyro, q = _rows(gyro_radps, 3, "gyro_radps"), _quaternions(quat_xyzw, "quat_xyzw")
    _same_length(gyro, "gyro_radps", t_s.shape[0], "t_s")
    _same_length(q, "quat_xyzw", t_s.shape[0], "t_s")
    w_up = np.einsum("ij,ij->i", _up_row(q), gyro)
    dt = np.diff(t_s)
    inc = 0.5 * (w_up[1:] + w_up[:-1]) * dt
    h0 = rotation_vector_heading(q[:1])[0]
    return h0 + np.concatenate([[0.0], np.cumsum(inc)])


def complementary_heading(t_s: np.ndarray, heading_rv_rad: np.ndarray, heading_gyro_rad: np.ndarray,
                          tau_s: float) -> np.ndarray:
    """Gyro heading corrected towards the rotation vector: h = h_gyro + LP_tau(h_rv - h_gyro), a
    causal first-order Butterworth low-pass with cut-off 1 / (2 pi tau) started in its steady
    state (usable on line). tau -> 0 gives the rotation vector, tau -> inf the gyro (unwrapped).
    ``t_s`` (N,) [s] finite and increasing, the headings (N,) [rad] finite, ``tau_s`` [s] > 0."""
    t_s = _times(t_s, "t_s")
    heading_rv_rad = _headings(heading_rv_rad, "heading_rv_rad", t_s.shape[0])
    heading_gyro_rad = _headings(heading_gyro_rad, "heading_gyro_rad", t_s.shape[0])
    if isinstance(tau_s, bool) or not isinstance(tau_s, (int, float, np.integer, np.floating)) or not (
            0 < float(tau_s) <= 86400.0):  # one day, as HandheldOptions.complementary_tau_s
        raise ValueError(f"indoorloc: argument 'tau_s': must be a time constant in (0, 86400] s, got {tau_s!r}")
    rate = (t_s.shape[0] - 1) / (t_s[-1] - t_s[0])
    d = np.unwrap(wrap_angle(np.asarray(heading_rv_rad) - np.asarray(heading_gyro_rad)))
    fc = 1.0 / (2.0 * np.pi * float(tau_s))
    if fc >= 0.45 * rate:
        return np.asarray(heading_gyro_rad) + d
    return np.asarray(heading_gyro_rad) + sos_filter(butterworth_sos(1, fc, rate), d, True)


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Angles folded into [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi



def _rows(values: Any, cols: int, arg: str) -> np.ndarray:
    """(N, cols) finite float64 array, or ValueError naming ``arg``."""
    a = _finite_array(values, arg)
    if a.ndim != 2 or a.shape[1] != cols:
        raise ValueError(f"indoorloc: argument '{arg}': expected shape (N, {cols}), got {a.shape}")
    return a


def _same_length(a: np.ndarray, arg: str, n: int, other: str) -> None:
    if a.shape[0] != n:
        raise ValueError(f"indoorloc: argument '{arg}': {a.shape[0]} rows, {other} has {n}")


def _headings(values: Any, arg: str, n: int) -> np.ndarray:
    """(n,) finite headings [rad], or ValueError naming ``arg``."""
    h = _finite_array(values, arg)
    if h.shape != (n,):
        raise ValueError(f"indoorloc: argument '{arg}': expected shape ({n},) to match t_s, got {h.shape}")
    return h


def _times(values: Any, arg: str) -> np.ndarray:
    """(N,) finite, increasing times, N >= 2 (a sample rate is derived from them)."""
    t = _finite_array(values, arg)
    if t.ndim != 1 or t.shape[0] < 2 or np.any(np.diff(t) <= 0):
        raise ValueError(f"indoorloc: argument '{arg}': expected at least 2 increasing times (N,), "
                         f"got shape {t.shape}" + (" not increasing" if t.ndim == 1 and t.shape[0] >= 2 else ""))
    _check_time_base(t, arg)
    return t


#: Time stamps [s] beyond this are refused (the ILC walks count from the recording's start;
#: Unix seconds are 1.6e9), and the mean sample interval must lie in [1e-6, 1000] s: the filters'
#: rate is derived from it (times at 1e300 used to be reported as the internal 'rate_hz').
MAX_TIME_S = 1e10
MIN_SAMPLE_INTERVAL_S = 1e-6
MAX_SAMPLE_INTERVAL_S = 1e3


def _check_time_base(t_s: np.ndarray, arg: str) -> None:
    """ValueError naming ``arg`` when increasing finite times are absurd for a sensor stream."""
    if np.abs(t_s).max() > MAX_TIME_S:
        raise ValueError(f"indoorloc: argument '{arg}': times must be within ±{MAX_TIME_S:g} s, "
                         f"got {t_s[np.argmax(np.abs(t_s))]:g}")
    mean_dt = (t_s[-1] - t_s[0]) / (t_s.shape[0] - 1)
    if not MIN_SAMPLE_INTERVAL_S <= mean_dt <= MAX_SAMPLE_INTERVAL_S:
        raise ValueError(f"indoorloc: argument '{arg}': the mean sample interval must be in "
                         f"[{MIN_SAMPLE_INTERVAL_S:g}, {MAX_SAMPLE_INTERVAL_S:g}] s, got {mean_dt:g} s")


def _quaternions(values: Any, arg: str) -> np.ndarray:
    """(N, 4) quaternions (x, y, z, w) of norm in [0.5, 2] (a (4,) array is one row), or
    ValueError naming ``arg``: other norms are no rotation, and 1e300 entries overflowed the
    heading formulas into NaN."""
    q = _finite_array(values, arg)
    if q.ndim not in (1, 2) or q.shape[-1] != 4 or q.size == 0:
        raise ValueError(f"indoorloc: argument '{arg}': expected (N, 4) quaternions (x, y, z, w), got shape {q.shape}")
    q = q.reshape(-1, 4)
    norm = np.sqrt(np.sum((q / 2.0) ** 2, axis=1)) * 2.0  # halved: no overflow before the test
    off = np.flatnonzero(~((norm >= 0.5) & (norm <= 2.0)))
    if off.size:
        raise ValueError(f"indoorloc: argument '{arg}': row {off[0]} has norm {norm[off[0]]:g}: not a "
                         f"rotation (unit quaternions (x, y, z, w) expected)")
    return q


def _finite_array(values: Any, arg: str) -> np.ndarray:
    """float64 array, finite; None, strings, objects, complex and ragged lists refused by name."""
    real_array(values, arg, finite=False)  # the shared wording for what is not an array of numbers
    a = np.asarray(values, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"indoorloc: argument '{arg}': values must be finite (no NaN or inf)")
    return a


