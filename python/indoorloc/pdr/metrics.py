"""Accuracy measures of a dead-reckoning track against ground truth (PyShoe's ARMSE).

A dead-reckoning track has an arbitrary origin and an unobservable initial heading:
:func:`align_2d` removes both (start position and the heading of the first samples, as PyShoe
does), :func:`armse` is then the absolute RMS error over every sample, :func:`path_length` the
distance travelled. Used by the PDR evaluations (``indoorloc pdr evaluate``) and the health
check of :mod:`indoorloc.pdr.recommended`.
"""

from __future__ import annotations

import math
from typing import Any, Tuple, Union

import numpy as np

__all__ = ["align_2d", "armse", "path_length"]


def _xy(a: Any, name: str) -> np.ndarray:
    arr = np.asarray(a, dtype=float)
    if arr.ndim != 2 or arr.shape[1] < 2 or arr.shape[0] == 0:
        raise ValueError(f"indoorloc: argument '{name}': expected an (N, 2) or (N, 3) array, "
                         f"got shape {arr.shape}")
    return arr[:, :2]


def align_2d(estimate_xy: Any, truth_xy: Any, n_align: int, *,
             return_angle: bool = False) -> Union[np.ndarray, Tuple[np.ndarray, float]]:
    """Align an estimated 2-D track with the truth by start position and initial heading.

    The usual PyShoe-style alignment: a dead-reckoning track has an arbitrary origin and an
    unobservable initial heading, so the estimate is translated so that its first sample equals
    the truth's first sample, then rotated about that point by the angle that best aligns the
    first ``n_align`` samples in least squares. With ``a_i = e_i - e_0`` and ``b_i = t_i - t_0``
    the angle minimising ``sum_i ||R(theta) a_i - b_i||^2`` is, in closed form,

        theta = atan2( sum_i (a_i x b_i), sum_i (a_i . b_i) )

    (2-D cross product ``a_x b_y - a_y b_x``). Nothing else (no scale, no later sample) is fitted.

    Parameters
    ----------
    estimate_xy, truth_xy : (N, 2) or (N, 3) float
        Estimated and true positions [m]; only x, y are used.
    n_align : int
        Number of leading samples used for the heading (2 <= n_align <= N). When those samples
        do not move (all at the start point) the angle is 0.
    return_angle : bool
        Also return theta [rad].

    Returns
    -------
    aligned : (N, 2) float
        The aligned estimate (and theta when ``return_angle``).
    """
    e = _xy(estimate_xy, "estimate_xy")
    t = _xy(truth_xy, "truth_xy")
    if e.shape != t.shape:
        raise ValueError(f"indoorloc: argument 'truth_xy': {t.shape[0]} rows but estimate_xy has "
                         f"{e.shape[0]}")
    n = int(n_align)
    if not 2 <= n <= e.shape[0]:
        raise ValueError(f"indoorloc: argument 'n_align': must be in [2, {e.shape[0]}], got {n_align}")
    a = e[:n] - e[0]
    b = t[:n] - t[0]
    cross = float(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]))
    dot = float(np.sum(a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1]))
    theta = math.atan2(cross, dot) if (cross != 0.0 or dot != 0.0) else 0.0
    c, s = math.cos(theta), math.sin(theta)
    rot = np.array([[c, -s], [s, c]])
    aligned = (e - e[0]) @ rot.T + t[0]
    return (aligned, theta) if return_angle else aligned


def armse(estimate_xy: Any, truth_xy: Any) -> float:
    """Absolute root-mean-square error [m]: ``sqrt( (1/N) sum_k ||e_k - t_k||^2 )``.

    Over all N samples, 2-D (x, y) Euclidean error, estimate and truth already in the same frame
    (align first with :func:`align_2d`). This is PyShoe's ARMSE.
    """
    e = _xy(estimate_xy, "estimate_xy")
    t = _xy(truth_xy, "truth_xy")
    if e.shape != t.shape:
        raise ValueError(f"indoorloc: argument 'truth_xy': {t.shape[0]} rows but estimate_xy has "
                         f"{e.shape[0]}")
    return float(np.sqrt(np.mean(np.sum((e - t) ** 2, axis=1))))


def path_length(positions: Any) -> float:
    """Sum of the distances between consecutive positions [m] ((N, 2) or (N, 3))."""
    p = np.asarray(positions, dtype=float)
    return float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))
