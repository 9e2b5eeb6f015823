"""Weinberg stride length (paper 002 eq. 4) and the magnetometer / gyroscope step detectors on
the Mobilise-D lower-back recordings (mobgap): :func:`evaluate_weinberg_mobgap`,
:func:`evaluate_step_detectors_mobgap`.

Protocol: K is calibrated on Test5 (a short straight walk) and tested on Test11
(simulated daily life) against the INDIP reference stride lengths. The reference strides
(initial contact to the next initial contact of the same foot) segment the signal, so the figures
measure the stride-length model alone, not a step detector. For each stride the bounce feature
is (max a~ - min a~)^(1/4) of the 3 Hz, 4th-order low-passed |acc| [m/s^2]:

- ``window="stride"`` (default): over the samples of the stride itself;
- ``window="mid"``: over +-0.15 s (the paper's w = 15 samples at 100 Hz) around the stride's
  middle sample. Note: this variant was compared with the default on Test11 itself, so its
  figures are not a clean held-out result.

K per subject is the least-squares fit on that subject's Test5 strides (a personal calibration
walk, as Weinberg's method needs); HA/002 has no Test5 reference and uses the pooled K (the fit
on every Test5 stride). The pooled K is also reported for every subject.

Errors per subject: stride-length mean absolute error, RMSE, bias (estimate - reference), and the
total-distance error (sum of estimated minus sum of reference stride lengths, in % of the latter).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Dict, List, Union

import numpy as np

from indoorloc.io.pdr_datasets import MobgapTrial, list_mobgap_files, load_mobgap_trials

PathLike = Union[str, Path]
#: Paper 002's Weinberg half-window [s] (15 samples at 100 Hz).
PAPER_WINDOW_S = 0.15
#: Paper 002 Table IV: total-distance errors of Weinberg, 0.3-1.15 % (foot, straight 120 m walks).
PAPER_TOTAL_DISTANCE_ERROR_PCT = (0.3, 1.15)


def stride_features(trial: MobgapTrial, window: str = "stride") -> np.ndarray:
    """Weinberg bounce features (S,) [(m/s^2)^(1/4)] of a trial's reference strides.

    ``window``: ``"stride"`` (the stride's own samples) or ``"mid"`` (+-0.15 s around its middle).
    """
    from indoorloc import pdr

    iv = np.asarray(trial.stride_intervals, dtype=np.int64).reshape(-1, 2)
    if iv.shape[0] == 0:
        return np.zeros(0)
    rec = trial.recording
    if window == "mid":
        w = int(round(PAPER_WINDOW_S * rec.rate_hz))
        mid = (iv[:, 0] + iv[:, 1]) // 2
        iv = np.column_stack([np.maximum(mid - w, 0), np.minimum(mid + w, rec.n_samples - 1)])
    elif window != "stride":
        raise ValueError(f"indoorloc: argument 'window': must be 'stride' or 'mid', got {window!r}")
    return pdr.weinberg_features(rec.acc_mps2, rec.rate_hz, iv)


def _errors(estimate: np.ndarray, reference: np.ndarray) -> Dict[str, float]:
    e = estimate - reference
    return {"n_strides": int(reference.size), "mae_m": float(np.mean(np.abs(e))),
            "rmse_m": float(np.sqrt(np.mean(e ** 2))), "bias_m": float(np.mean(e)),
            "reference_total_m": float(reference.sum()), "estimated_total_m": float(estimate.sum()),
            "total_error_pct": float(100.0 * (estimate.sum() - reference.sum()) / reference.sum())}


def evaluate_weinberg_mobgap(root: PathLike, window: str = "stride", train_test: str = "Test5",
                             eval_test: str = "Test11") -> Dict[str, Any]:
    """K fitted on ``train_test``, errors on ``eval_test``, for every subject under ``root``
    (``.../shared/data/pdr/mobgap_lowerback``). Returns ``{"pooled_k", "rows": [...],
    "overall": {...}}``: one row per subject with ``k`` (its own fit or the pooled one,
    ``k_source``) and the stride / total-distance errors with that K and with the pooled K.
    """
    from indoorloc import pdr

    trials: List[MobgapTrial] = [t for f in list_mobgap_files(root) for t in load_mobgap_trials(f)]
    feats = {id(t): stride_features(t, window) for t in trials}
    train = [t for t in trials if t.test == train_test and t.stride_lengths_m.size]
    if not train:
        raise ValueError(f"indoorloc: argument 'root': no {train_test} reference strides under {root}")
    pooled = pdr.calibrate_weinberg_k(np.concatenate([feats[id(t)] for t in train]),
                                      np.concatenate([t.stride_lengths_m for t in train]))["k"]
    rows = []
    all_est, all_ref = [], []
    for subject in sorted({t.subject for t in trials}):
        mine = [t for t in train if t.subject == subject]
        if mine:
            k = pdr.calibrate_weinberg_k(np.concatenate([feats[id(t)] for t in mine]),
                                         np.concatenate([t.stride_lengths_m for t in mine]))["k"]
            source = f"{subject} {train_test}"
        else:
            k, source = pooled, f"pooled {train_test} (no reference for {subject})"
        tests = [t for t in trials if t.subject == subject and t.test == eval_test and t.stride_lengths_m.size]
        if not tests:
            continue
        f = np.concatenate([feats[id(t)] for t in tests])
        ref = np.concatenate([t.stride_lengths_m for t in tests])
        row = {"subject": subject, "k": float(k), "k_source": source, **_errors(k * f, ref),
               "pooled": _errors(pooled * f, ref)}
        rows.append(row)
        all_est.append(k * f)
        all_ref.append(ref)
    overall = _errors(np.concatenate(all_est), np.concatenate(all_ref)) if rows else {}
    return {"pooled_k": float(pooled), "window": window, "rows": rows, "overall": overall}


def markdown(result: Dict[str, Any]) -> str:
    """Markdown table of :func:`evaluate_weinberg_mobgap`, with the paper's figure beside."""
    lo, hi = PAPER_TOTAL_DISTANCE_ERROR_PCT
    parts = [f"### Weinberg stride length, mobgap lower back: K on Test5, tested on Test11 "
             f"(window: {result['window']})", "",
             "| subject | K | K from | strides | MAE [m] | RMSE [m] | bias [m] | total [m] (ref) | "
             "total error | pooled-K total error |",
             "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in result["rows"]:
        parts.append(f"| {r['subject']} | {r['k']:.3f} | {r['k_source']} | {r['n_strides']} | "
                     f"{r['mae_m']:.3f} | {r['rmse_m']:.3f} | {r['bias_m']:+.3f} | "
                     f"{r['estimated_total_m']:.1f} ({r['reference_total_m']:.1f}) | "
                     f"{r['total_error_pct']:+.1f} % | {r['pooled']['total_error_pct']:+.1f} % |")
    o = result["overall"]
    if o:
        parts.append(f"| all | | | {o['n_strides']} | {o['mae_m']:.3f} | {o['rmse_m']:.3f} | "
                     f"{o['bias_m']:+.3f} | {o['estimated_total_m']:.1f} ({o['reference_total_m']:.1f}) | "
                     f"{o['total_error_pct']:+.1f} % | |")
    parts += ["", f"Pooled K = {result['pooled_k']:.3f}. Paper 002 (foot, straight walks, K = 0.364): "
              f"total-distance error {lo}-{hi} %.", ""]
    return "\n".join(parts)


def evaluate_step_detectors_mobgap(root: PathLike, gyro_threshold_radps: float = 0.5) -> Dict[str, Any]:
    """Step counts of the magnetometer and gyroscope detectors (paper 002 §III.D, default options
    of :func:`indoorloc.pdr.steps_magnetometer` / :func:`indoorloc.pdr.steps_gyro` with a 0.5
    rad/s threshold for the trunk) on the mobgap lower-back recordings, the only ones here with
    a magnetometer: detected steps inside each INDIP walking bout [Start, End] against the bout's
    reference initial contacts (both feet). Returns ``{"reference_steps", "magnetometer_abs_error",
    "gyro_abs_error", "magnetometer_pct", "gyro_pct", "n_bouts"}`` (sums of per-bout absolute
    count errors) and ``"magnetometer_pct_per_bout"`` (each bout's error in % of its reference steps)."""
    from indoorloc import pdr

    ref = mag_err = gyro_err = bouts = 0
    per_bout_mag_pct = []
    for f in list_mobgap_files(root):
        for t in load_mobgap_trials(f):
            rec = t.recording
            if t.bout_bounds_s.shape[0] == 0 or rec.mag_uT is None:
                continue
            mag_steps = np.asarray(pdr.steps_magnetometer(rec.mag_uT, rec.rate_hz)[0])
            gyro_steps = np.asarray(pdr.steps_gyro(rec.gyro_radps, rec.rate_hz,
                                                    options=pdr.GyroStepOptions(threshold_radps=gyro_threshold_radps)))
            for (a, b), contacts in zip(t.bout_bounds_s, t.bout_initial_contacts):
                lo, hi = a * rec.rate_hz, b * rec.rate_hz
                n_ref = int(len(contacts))
                ref += n_ref
                bout_mag_err = abs(int(np.sum((mag_steps >= lo) & (mag_steps <= hi))) - n_ref)
                mag_err += bout_mag_err
                if n_ref:
                    per_bout_mag_pct.append(100.0 * bout_mag_err / n_ref)
                gyro_err += abs(int(np.sum((gyro_steps >= lo) & (gyro_steps <= hi))) - n_ref)
                bouts += 1
    if ref == 0:
        raise ValueError(f"indoorloc: argument 'root': no reference walking bout with a magnetometer under {root}")
    return {"reference_steps": ref, "n_bouts": bouts, "magnetometer_abs_error": mag_err, "gyro_abs_error": gyro_err,
            "magnetometer_pct": 100.0 * mag_err / ref, "gyro_pct": 100.0 * gyro_err / ref,
            "magnetometer_pct_per_bout": per_bout_mag_pct}
