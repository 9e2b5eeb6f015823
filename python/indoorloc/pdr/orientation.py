"""Orientation of a hand-held phone from its rotation vector and gyroscope (vectorised numpy).

Headings follow :mod:`indoorloc.pdr.handheld`'s convention: the device +y axis in the east-north
frame, east = 0, north = pi/2. :func:`rotation_vector_heading` reads it from the Android rotation
vector, :func:`gyro_heading` integrates the rate about the vertical, :func:`complementary_heading`
blends the two; :func:`vertical_acceleration` is the up component of the specific force minus g.
Split out of ``handheld`` (one concept per file); every name is re-exported there.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from indoorloc._core.pdr import butterworth_sos, sos_filter

__all__ = ["GRAVITY_MPS2", "complementary_heading", "gyro_heading", "rotation_vector_heading",
           "vertical_acceleration", "wrap_angle"]

GRAVITY_MPS2 = 9.80665



def rotation_vector_heading(quat_xyzw: np.ndarray) -> np.ndarray:
    """Heading [rad] of the device +y axis in the east-north frame (east = 0, north = pi/2).

    R(q) rotates device into ENU; its second column is the +y axis in ENU:
    (2(xy - wz), 1 - 2(x^2 + z^2), 2(yz + wx)). Heading = atan2(north, east) of its horizontal part.
    """
    q = np.asarray(quat_xyzw, dtype=np.float64)
    if q.size % 4 != 0 or q.size == 0:
        raise ValueError(f"indoorloc: argument 'quat_xyzw': expected (N, 4) quaternions (x, y, z, w), got shape {q.shape}")
    q = _finite_array(q, "quat_xyzw").reshape(-1, 4)
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    east = 2.0 * (x * y - w * z)
    north = 1.0 - 2.0 * (x * x + z * z)
    return np.arctan2(north, east)


def _up_row(quat_xyzw: np.ndarray) -> np.ndarray:
    """Third row of R(q) (N, 3): the device-frame direction of ENU 'up'."""
    x, y, z, w = (quat_xyzw[:, i] for i in range(4))
    return np.column_stack([2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)])


def vertical_acceleration(acc_mps2: np.ndarray, quat_xyzw: np.ndarray) -> np.ndarray:
    """Up component of the specific force minus g [m/s^2] (N,)."""
    return np.einsum("ij,ij->i", _up_row(quat_xyzw), acc_mps2) - GRAVITY_MPS2


def gyro_heading(t_s: np.ndarray, gyro_radps: np.ndarray, quat_xyzw: np.ndarray) -> np.ndarray:
    """Heading [rad] by integrating the rate about the vertical, omega_up = R(q)[2, :] . omega (the
    rotation vector gives only the tilt here), trapezoid rule, started at the first
    rotation-vector heading. Unwrapped (continuous, not folded into (-pi, pi])."""
    w_up = np.einsum("ij,ij->i", _up_row(quat_xyzw), gyro_radps)
    dt = np.diff(t_s)
    inc = 0.5 * (w_up[1:] + w_up[:-1]) * dt
    h0 = rotation_vector_heading(quat_xyzw[:1])[0]
    return h0 + np.concatenate([[0.0], np.cumsum(inc)])


def complementary_heading(t_s: np.ndarray, heading_rv_rad: np.ndarray, heading_gyro_rad: np.ndarray,
                          tau_s: float) -> np.ndarray:
    """Gyro heading corrected towards the rotation vector: h = h_gyro + LP_tau(h_rv - h_gyro), a
    causal first-order Butterworth low-pass with cut-off 1 / (2 pi tau) started in its steady
    state (usable on line). tau -> 0 gives the rotation vector, tau -> inf the gyro (unwrapped)."""
    rate = (t_s.shape[0] - 1) / (t_s[-1] - t_s[0])
    d = np.unwrap(wrap_angle(np.asarray(heading_rv_rad) - np.asarray(heading_gyro_rad)))
    fc = 1.0 / (2.0 * np.pi * tau_s)
    if fc >= 0.45 * rate:
        return np.asarray(heading_gyro_rad) + d
    return np.asarray(heading_gyro_rad) + sos_filter(butterworth_sos(1, fc, rate), d, True)


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Angles folded into [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi



def _finite_array(values: Any, arg: str) -> np.ndarray:
    a = np.asarray(values, dtype=np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"indoorloc: argument '{arg}': values must be finite (no NaN or inf)")
    return a


