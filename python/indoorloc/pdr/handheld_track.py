"""Positions from hand-held steps (:mod:`indoorloc.pdr.handheld`): each step's displacement
(:func:`step_displacements`), sums accrued over time (:func:`cumulative_at`) and the dead-reckoned
track from a known start (:func:`pdr_track`)."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from indoorloc.pdr.handheld_types import HandheldSteps
from indoorloc.pdr.orientation import _finite_array


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
