"""Calibration of hand-held PDR on training walks with waypoints (:mod:`indoorloc.pdr.handheld`):
the steps summed between waypoints (:func:`waypoint_intervals`), the fit of Weinberg's K, the yaw
offset and the per-step sds (:func:`calibrate_handheld`, :func:`calibrate_from_intervals`), and the
same steps under refitted options (:func:`rescale`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Iterable, List, Optional, Sequence

import numpy as np

from indoorloc._core.pdr import calibrate_weinberg_k
from indoorloc.pdr.handheld_detection import handheld_steps
from indoorloc.pdr.handheld_track import _heading_of, cumulative_at, step_displacements
from indoorloc.pdr.handheld_types import HandheldOptions, HandheldSteps
from indoorloc.pdr.orientation import _finite_array, wrap_angle


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
