"""Scoring foot-mounted PDR on real recordings (paper 002 context): the PyShoe Vicon trials
(per-sample truth: :func:`score_pyshoe_trial`, :func:`evaluate_pyshoe`) and the closed loops of
x-io and OpenShoe (:func:`score_closed_loop`, :func:`evaluate_closed_loops`), the threshold search
:func:`tune_threshold`, and the consistency of the per-step covariances
(:func:`step_covariance_coverage`). A method is a callable of :mod:`indoorloc.experiments.pdr_methods`.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from indoorloc.experiments.pdr_methods import (
    Method,
    MethodOutput,
    _per_sample,
    default_threshold,
    shoe_stance,
    stance_step_samples,
    with_threshold,
)
from indoorloc.io.pdr_datasets import (
    ImuRecording,
    list_pyshoe_trials,
    load_openshoe,
    load_pyshoe_trial,
    load_xio,
)
from indoorloc.pdr import metrics as _metrics
from indoorloc.progress import progress

PathLike = Union[str, Path]

#: Peer figures quoted in ../shared/data/pdr/README.md.
PEER_CLOSED_LOOP_FINAL_ERROR_M = {
    "short_walk": ("x-io Gait-Tracking", 0.082),
    "long_walk": ("x-io Gait-Tracking", 0.421),
    "OpenShoeDataSet": ("OpenShoe EKF / RTS smoother", (0.45, 0.37)),
}
PEER_PYSHOE = {"method": "PyShoe ESKF + SHOE (42 trials)", "median_armse_m": 0.08,
               "mean_armse_m": 0.38, "worst_armse_m": 10.0, "samples_per_s": 4200.0}


def _split_output(out: MethodOutput, n: int, name: str) -> Tuple[np.ndarray, Optional[np.ndarray]]:
    strides = None
    if isinstance(out, tuple):
        if len(out) != 2:
            raise ValueError(f"indoorloc: argument 'method': must return positions or "
                             f"(positions, stride_indices), got a tuple of {len(out)}")
        out, strides = out
        strides = None if strides is None else np.asarray(strides).ravel()
    pos = np.asarray(out, dtype=float)
    if pos.ndim != 2 or pos.shape[0] != n or pos.shape[1] not in (2, 3):
        raise ValueError(f"indoorloc: argument 'method': returned positions of shape {pos.shape} "
                         f"for {name}, expected ({n}, 3)")
    if not np.all(np.isfinite(pos)):
        raise ValueError(f"indoorloc: argument 'method': returned NaN/inf positions for {name}")
    return pos, strides


def pyshoe_alignment_samples(recording: ImuRecording, n_strides: int = 2) -> int:
    """Samples used for the heading alignment of a PyShoe trial: up to the ``n_strides``-th
    annotated stride end after the initial rest (the first two strides by default), or the first
    10 % of the trial when there are no stride annotations."""
    si = recording.stride_indices
    n = recording.n_samples
    if si is not None and si.size > n_strides:
        return int(min(n, max(2, si[n_strides] + 1)))
    return max(2, n // 10)


#: The PyShoe/Vicon ground truth lives in PyShoe's navigation frame, which is z-down (NED-like):
#: its (x, y) are (x, -y) of a right-handed z-up frame such as indoorloc's. A rotation cannot
#: undo that reflection, so estimates are converted before the (rotation-only) alignment.
PYSHOE_TRUTH_FROM_Z_UP = np.array([1.0, -1.0])


def score_pyshoe_trial(recording: ImuRecording, output: MethodOutput,
                       n_align_strides: int = 2, z_up_estimate: bool = True) -> Dict[str, Any]:
    """ARMSE (after :func:`align_2d`) and stride-count error of one method output on one trial.

    ``z_up_estimate``: the estimate is in a z-up frame (indoorloc's EKF); it is mirrored into the
    truth's z-down frame first (see :data:`PYSHOE_TRUTH_FROM_Z_UP`).
    """
    if recording.truth_xy_m is None:
        raise ValueError(f"indoorloc: argument 'recording': {recording.name} has no truth_xy_m")
    pos, strides = _split_output(output, recording.n_samples, recording.name)
    if z_up_estimate:
        pos = pos.copy()
        pos[:, :2] = pos[:, :2] * PYSHOE_TRUTH_FROM_Z_UP
    n_align = pyshoe_alignment_samples(recording, n_align_strides)
    aligned = _metrics.align_2d(pos[:, :2], recording.truth_xy_m, n_align)
    row: Dict[str, Any] = {"trial": recording.name, "n_samples": recording.n_samples,
                           "armse_m": _metrics.armse(aligned, recording.truth_xy_m),
                           "final_error_m": float(np.linalg.norm(aligned[-1] - recording.truth_xy_m[-1])),
                           "distance_m": recording.distance_m}
    truth_strides = (None if recording.stride_indices is None
                     else max(0, int(recording.stride_indices.size) - 1))
    row["strides_truth"] = truth_strides
    row["strides_detected"] = None if strides is None else int(strides.size)
    row["stride_count_error"] = (None if strides is None or truth_strides is None
                                 else int(strides.size) - truth_strides)
    return row


def _summary(rows: List[Dict[str, Any]], seconds: float) -> Dict[str, Any]:
    errs = np.array([r["armse_m"] for r in rows])
    worst = int(np.argmax(errs))
    out: Dict[str, Any] = {
        "trials": rows,
        "n_trials": len(rows),
        "median_armse_m": float(np.median(errs)),
        "mean_armse_m": float(np.mean(errs)),
        "worst_armse_m": float(errs[worst]),
        "worst_trial": rows[worst]["trial"],
        "seconds": seconds,
        "samples_per_s": float(sum(r["n_samples"] for r in rows) / seconds) if seconds > 0 else float("nan"),
    }
    sc = [r["stride_count_error"] for r in rows if r["stride_count_error"] is not None]
    if sc:
        truth = sum(r["strides_truth"] for r in rows if r["stride_count_error"] is not None)
        out["stride_count_abs_error_total"] = int(sum(abs(v) for v in sc))
        out["stride_count_abs_error_pct"] = 100.0 * sum(abs(v) for v in sc) / max(truth, 1)
    return out


def evaluate_recordings(recordings: Sequence[ImuRecording], method: Method,
                        n_align_strides: int = 2) -> Dict[str, Any]:
    """:func:`evaluate_pyshoe` on recordings already loaded (with ``truth_xy_m``)."""
    rows = []
    seconds = 0.0
    for rec in progress(recordings, total=len(recordings), desc="pdr trials"):
        t0 = time.perf_counter()
        out = method(rec)
        seconds += time.perf_counter() - t0
        rows.append(score_pyshoe_trial(rec, out, n_align_strides))
    if not rows:
        raise ValueError("indoorloc: argument 'recordings': empty")
    return _summary(rows, seconds)


def evaluate_pyshoe(root: PathLike, method: Method, n_align_strides: int = 2) -> Dict[str, Any]:
    """Run ``method`` on every PyShoe trial in ``root``; align and score each.

    Each estimate is aligned with :func:`align_2d` on the samples up to the second annotated
    stride end (``n_align_strides``), then scored by :func:`armse` against the per-sample Vicon
    truth. Returns a dict: ``trials`` (per-trial rows: ``trial``, ``armse_m``, ``final_error_m``,
    ``strides_truth``, ``strides_detected``, ``stride_count_error`` = detected - truth, None when
    the method returns no strides), ``median_armse_m``, ``mean_armse_m``, ``worst_armse_m``,
    ``worst_trial``, ``samples_per_s`` (method time only) and, when strides were returned,
    ``stride_count_abs_error_total`` / ``_pct``.
    """
    recs = [load_pyshoe_trial(p) for p in list_pyshoe_trials(root)]
    return evaluate_recordings(recs, method, n_align_strides)


def closed_loop_recordings(root: PathLike) -> List[ImuRecording]:
    """The closed-loop recordings under the pdr data folder ``root`` (``.../shared/data/pdr``):
    x-io short and long walks, OpenShoe figure-8 (those present)."""
    r = Path(root)
    recs = []
    for rel, loader in (("xio_gait_tracking/short_walk.csv", load_xio),
                        ("xio_gait_tracking/long_walk.csv", load_xio),
                        ("openshoe_figure8/OpenShoeDataSet.txt", load_openshoe)):
        if (r / rel).is_file():
            recs.append(loader(r / rel))
    if not recs:
        raise ValueError(f"indoorloc: argument 'root': no closed-loop recording under {r}")
    return recs


def score_closed_loop(recording: ImuRecording, output: MethodOutput) -> Dict[str, Any]:
    """Final position error of a closed loop: ||p_last - p_first|| in 2-D (x, y) and 3-D, and as a
    percentage of the estimate's own path length (2-D and 3-D respectively)."""
    pos, strides = _split_output(output, recording.n_samples, recording.name)
    if pos.shape[1] == 2:
        pos = np.column_stack([pos, np.zeros(pos.shape[0])])
    d = pos[-1] - pos[0]
    len2, len3 = _metrics.path_length(pos[:, :2]), _metrics.path_length(pos)
    e2, e3 = float(np.linalg.norm(d[:2])), float(np.linalg.norm(d))
    peer = PEER_CLOSED_LOOP_FINAL_ERROR_M.get(recording.name)
    return {"recording": recording.name, "n_samples": recording.n_samples,
            "final_error_2d_m": e2, "final_error_3d_m": e3,
            "path_length_2d_m": len2, "path_length_3d_m": len3,
            "final_error_2d_pct": 100.0 * e2 / len2 if len2 > 0 else float("nan"),
            "final_error_3d_pct": 100.0 * e3 / len3 if len3 > 0 else float("nan"),
            "nominal_distance_m": recording.distance_m,
            "strides_detected": None if strides is None else int(strides.size),
            "peer": peer}


def evaluate_closed_loops(root: PathLike, method: Method) -> Dict[str, Any]:
    """Run ``method`` on the x-io short / long walks and the OpenShoe figure-8 under ``root``
    (the ``shared/data/pdr`` folder) and score each with :func:`score_closed_loop`.

    Returns ``{"recordings": [rows], "seconds": ..., "samples_per_s": ...}``.
    """
    rows = []
    seconds = 0.0
    n = 0
    recs = closed_loop_recordings(root)
    for rec in progress(recs, total=len(recs), desc="closed loops"):
        t0 = time.perf_counter()
        out = method(rec)
        seconds += time.perf_counter() - t0
        n += rec.n_samples
        rows.append(score_closed_loop(rec, out))
    return {"recordings": rows, "seconds": seconds,
            "samples_per_s": n / seconds if seconds > 0 else float("nan")}


def tune_threshold(recordings: Sequence[ImuRecording], method: Callable[..., MethodOutput],
                   candidates: Sequence[float], n_align_strides: int = 2
                   ) -> Tuple[float, Dict[float, float]]:
    """Pick the SHOE threshold with the lowest mean ARMSE on training ``recordings``.

    ``method(recording, threshold=...)`` is run for every candidate on every recording (which
    must have ``truth_xy_m``). Returns ``(best_threshold, {candidate: mean_armse_m})``; a
    candidate for which the method fails (raises) scores inf. Evaluate on *other* trials with
    the chosen value fixed: one parameter set for all test recordings.
    """
    if not candidates:
        raise ValueError("indoorloc: argument 'candidates': empty")
    if not recordings:
        raise ValueError("indoorloc: argument 'recordings': empty")
    scores: Dict[float, float] = {}
    for gamma in progress(list(candidates), total=len(candidates), desc="thresholds"):
        try:
            res = evaluate_recordings(recordings, with_threshold(method, gamma), n_align_strides)
            scores[float(gamma)] = res["mean_armse_m"]
        except (ValueError, RuntimeError, np.linalg.LinAlgError):
            scores[float(gamma)] = float("inf")
    best = min(scores, key=lambda g: scores[g])
    return best, scores


def step_covariance_coverage(recording: ImuRecording, threshold: Optional[float] = None,
                             n_align_strides: int = 2, **covariance: float) -> Dict[str, Any]:
    """How well the per-step covariances of eq. 9 (:func:`step_positioning_method` with
    ``heading="increments"``, Mahony attitude) describe the real error on a PyShoe trial.

    The track is aligned as in :func:`score_pyshoe_trial` (mirror, start, initial heading), the
    2 x 2 position covariance of each step rotated the same way, and the squared Mahalanobis
    distance d² = eᵀ Σ⁻¹ e of the error at each step sample computed (steps after the alignment
    window only). A consistent covariance has d² ~ chi²(2): 95 % of the steps inside d² < 5.99,
    mean d² = 2. ``covariance`` keywords are fields of ``pdr.StepCovarianceOptions``. Returns ``{"trial",
    "n_steps", "inside_95_pct", "mean_d2", "final_error_m", "final_sd_m"}`` (final_sd_m =
    sqrt(trace) of the last 2 x 2 covariance).
    """
    from indoorloc import pdr

    if recording.truth_xy_m is None:
        raise ValueError(f"indoorloc: argument 'recording': {recording.name} has no truth_xy_m")
    gamma = default_threshold(recording) if threshold is None else float(threshold)
    stance = shoe_stance(recording, gamma)
    steps = stance_step_samples(stance, recording.rate_hz)
    quats = pdr.attitude_mahony(recording.time_s, recording.acc_mps2, recording.gyro_radps)["quaternions_wxyz"]
    inc = pdr.ins_zupt_increments(recording.time_s, recording.acc_mps2, quats, steps)
    track = pdr.positions_from_increments(inc["increments_m"], options=pdr.StepCovarianceOptions(**covariance))
    xy = np.vstack([[0.0, 0.0], track["positions_m"]])
    pos = _per_sample(steps, xy, recording.n_samples)[:, :2] * PYSHOE_TRUTH_FROM_Z_UP
    n_align = pyshoe_alignment_samples(recording, n_align_strides)
    aligned, theta = _metrics.align_2d(pos, recording.truth_xy_m, n_align, return_angle=True)
    c, s_ = math.cos(theta), math.sin(theta)
    rot = np.array([[c, -s_], [s_, c]]) @ np.diag(PYSHOE_TRUTH_FROM_Z_UP)
    d2 = []
    for k, sample in enumerate(steps[1:]):
        if sample < n_align:
            continue
        cov = rot @ track["covariances"][k][:2, :2] @ rot.T
        e = aligned[sample] - recording.truth_xy_m[sample]
        d2.append(float(e @ np.linalg.solve(cov + 1e-12 * np.eye(2), e)))
    d2a = np.asarray(d2)
    last = track["covariances"][-1][:2, :2]
    return {"trial": recording.name, "n_steps": int(d2a.size),
            "inside_95_pct": float(100.0 * np.mean(d2a < 5.991)) if d2a.size else float("nan"),
            "mean_d2": float(np.mean(d2a)) if d2a.size else float("nan"),
            "final_error_m": float(np.linalg.norm(aligned[steps[-1]] - recording.truth_xy_m[steps[-1]])),
            "final_sd_m": float(np.sqrt(np.trace(last)))}
