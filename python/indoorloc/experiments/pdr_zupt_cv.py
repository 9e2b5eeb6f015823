"""Leave-one-trial-out cross-validation of zero-velocity (ZUPT) detection rules.

Every candidate rule has a small grid of settings. For each setting the SHOE stance of every
PyShoe trial is computed, the ZUPT EKF + RTS smoother run on it, and the trial scored (2-D ARMSE
after the start / initial-heading alignment of :func:`pdr_evaluate.score_pyshoe_trial`, strides
counted with :func:`indoorloc.pdr.count_strides`). Then, for each trial i in turn, the setting
with the lowest mean ARMSE over the *other* trials is chosen and trial i is scored with it: the
held-out figure of the rule family, the number a re-run on new trials of the same protocol
should reproduce. Reported per family: the held-out median / mean / worst ARMSE, the trials
over 0.4 m, the held-out strides off, and how often each setting was chosen (its spread).

Candidates (``CANDIDATES``):

- ``fixed``: one SHOE threshold for every recording (log10 gamma on a grid);
- ``p99_classes``: motion classes by the recording's 99th percentile of log10 T (slow walk vs
  fast walk / run, the earlier per-class rule that overfitted), a threshold per class;
- ``cadence_classes``: motion classes by the stride period (the autocorrelation peak of log10 T
  between 0.4 and 2.5 s: running strides are shorter), a threshold per class;
- ``swing_guard``: a base threshold raised on a ladder (0.25 decade) until no swing is longer
  than max_swing_s or than max_swing_ratio x the median swing (missed stances make long
  swings; :func:`indoorloc.pdr.zero_velocity`, rule ``"swing_guard"``, the C++ code itself);
- ``stance_guard``: a base threshold raised until at least a fraction f of the walking span is
  stance (:func:`indoorloc.pdr.zero_velocity`, rule ``"stance_guard"``);
- ``quantile``: the threshold is the f-quantile of T over the walking span (pure distribution);
- ``vote``: SHOE, angular-rate energy (ARE) and acceleration moving variance (AMV) of Skog et
  al. 2010, each with its own base threshold and the same stance guard; stance when 2 of 3 agree.

The statistics are computed once per trial and cached (``cache_dir``); the per-setting rows are
cached too, so a re-run only computes new settings. Run ``python -m
indoorloc.experiments.pdr_zupt_cv --data-root ../shared/data/pdr`` (about a minute per family on
one core).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections import Counter
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc.experiments import pdr_evaluate as pe
from indoorloc.io.pdr_datasets import ImuRecording, list_pyshoe_trials, load_pyshoe_trial
from indoorloc.pdr import metrics, recommended
from indoorloc.progress import progress
from indoorloc.io.atomic_file import write_text_atomic

Stats = Dict[str, np.ndarray]
StanceRule = Callable[[ImuRecording, Stats, Dict[str, float]], np.ndarray]


def _sliding_mean(x: np.ndarray, w: int) -> np.ndarray:
    """Mean over a centred window of w samples, shifted inside the recording at its ends (the
    window of the C++ SHOE)."""
    n = x.shape[0]
    c = np.concatenate([np.zeros((1,) + x.shape[1:]), np.cumsum(x, axis=0)])
    start = np.clip(np.arange(n) - w // 2, 0, n - w)
    return (c[start + w] - c[start]) / w


def detector_statistics(recording: ImuRecording, window: int = recommended.SHOE_WINDOW) -> Stats:
    """log10 of the SHOE, ARE and AMV statistics (Skog et al. 2010 eq. 13, 11, 10) of a recording,
    with the noise sds of :mod:`pdr_evaluate` (``SHOE_SIGMA_*``): ARE = mean |w|^2 / s_w^2, AMV =
    mean |f - mean f|^2 / s_a^2 over the window. SHOE comes from the C++ detector."""
    from indoorloc import pdr

    sa, sg = recommended.SHOE_SIGMA_ACC_MPS2, recommended.SHOE_SIGMA_GYRO_RADPS
    options = pdr.ShoeOptions(window=window, sigma_acc_mps2=sa, sigma_gyro_radps=sg)
    shoe = np.asarray(pdr.shoe_statistic(recording.acc_mps2, recording.gyro_radps, options=options))
    are = _sliding_mean(np.sum(recording.gyro_radps ** 2, axis=1), window) / sg ** 2
    a = recording.acc_mps2
    amv = (_sliding_mean(np.sum(a ** 2, axis=1), window) - np.sum(_sliding_mean(a, window) ** 2, axis=1)) / sa ** 2
    tiny = 1e-300
    return {"shoe": np.log10(np.maximum(shoe, tiny)), "are": np.log10(np.maximum(are, tiny)),
            "amv": np.log10(np.maximum(amv, tiny))}


def guarded_log_threshold(log_t: np.ndarray, log_base: float, min_fraction: float,
                          log_max: float = 7.0) -> float:
    """The stance guard of ``indoorloc.pdr.zero_velocity`` on log10 T: the walking span is the
    first to last sample with log T >= log_base; the threshold is raised to the min_fraction
    lower quantile of log T over it (capped at log_max). Mirrors the C++ rule (tested)."""
    moving = np.flatnonzero(log_t >= log_base)
    span = log_t[moving[0]:moving[-1] + 1] if moving.size else log_t
    if min_fraction <= 0:
        return log_base
    pos = int(math.floor(min_fraction * (span.size - 1)))  # the lower quantile, as the C++
    q = float(np.nextafter(np.partition(span, pos)[pos], np.inf))  # T < threshold holds for it too
    return min(q, log_max) if q > log_base else log_base


def _fixed(rec: ImuRecording, st: Stats, p: Dict[str, float]) -> np.ndarray:
    return st["shoe"] < p["log_gamma"]


def _p99_classes(rec: ImuRecording, st: Stats, p: Dict[str, float]) -> np.ndarray:
    slow = np.percentile(st["shoe"], 99) < p["p99_cut"]
    return st["shoe"] < (p["log_low"] if slow else p["log_high"])


def stride_period_s(log_t: np.ndarray, rate_hz: float, lo_s: float = 0.4, hi_s: float = 2.5) -> float:
    """The gait's stride period [s]: the lag of the highest local maximum of the autocorrelation
    of the mean-removed log10 T between lo_s and hi_s (FFT autocorrelation); NaN if none."""
    x = log_t - log_t.mean()
    n = x.size
    f = np.fft.rfft(x, 2 * n)
    ac = np.fft.irfft(f * np.conj(f))[:n]
    lo, hi = int(lo_s * rate_hz), min(n - 1, int(hi_s * rate_hz))
    if hi <= lo + 1:
        return float("nan")
    k = np.arange(max(lo, 1), hi)
    peaks = k[(ac[k] > ac[k - 1]) & (ac[k] >= ac[k + 1])]
    if peaks.size == 0:
        return float("nan")
    return float(peaks[int(np.argmax(ac[peaks]))] / rate_hz)


def _cadence_classes(rec: ImuRecording, st: Stats, p: Dict[str, float]) -> np.ndarray:
    run = bool(stride_period_s(st["shoe"], rec.rate_hz) < p["period_cut_s"])  # NaN: a walk
    return st["shoe"] < (p["log_run"] if run else p["log_walk"])


def _stance_guard(rec: ImuRecording, st: Stats, p: Dict[str, float]) -> np.ndarray:
    return st["shoe"] < guarded_log_threshold(st["shoe"], p["log_gamma"], p["min_fraction"], p.get("log_max", 7.0))


def _quantile(rec: ImuRecording, st: Stats, p: Dict[str, float]) -> np.ndarray:
    x = st["shoe"]
    moving = np.flatnonzero(x >= p["log_span"])
    span = x[moving[0]:moving[-1] + 1] if moving.size else x
    return x < np.quantile(span, p["fraction"])


def _swing_guard(rec: ImuRecording, st: Stats, p: Dict[str, float]) -> np.ndarray:
    from indoorloc import pdr

    options = pdr.ZeroVelocityOptions(
        rule="swing_guard", threshold=10.0 ** p["log_gamma"], max_swing_s=p["max_swing_s"],
        max_swing_ratio=p["max_swing_ratio"], window=recommended.SHOE_WINDOW,
        sigma_acc_mps2=recommended.SHOE_SIGMA_ACC_MPS2, sigma_gyro_radps=recommended.SHOE_SIGMA_GYRO_RADPS)
    det = pdr.zero_velocity(rec.acc_mps2, rec.gyro_radps, rec.rate_hz, options=options)
    return np.asarray(det["stance"], dtype=bool)


def _vote(rec: ImuRecording, st: Stats, p: Dict[str, float]) -> np.ndarray:
    votes = np.zeros(st["shoe"].size, dtype=np.int64)
    for key in ("shoe", "are", "amv"):
        votes += st[key] < guarded_log_threshold(st[key], p["log_" + key], p["min_fraction"], 99.0)
    return votes >= 2


def _grid(**axes: Sequence[float]) -> List[Dict[str, float]]:
    keys = list(axes)
    out = [{}]
    for k in keys:
        out = [dict(d, **{k: float(v)}) for d in out for v in axes[k]]
    return out


#: Candidate families: name -> (stance rule, grid of settings). Grids span the plausible range
#: of each setting (log10 T is about 2-3 at rest and 6-7.8 in swing on the PyShoe sensor).
CANDIDATES: Dict[str, Tuple[StanceRule, List[Dict[str, float]]]] = {
    "fixed": (_fixed, _grid(log_gamma=np.arange(4.0, 7.01, 0.25))),
    "p99_classes": (_p99_classes, _grid(p99_cut=[7.2, 7.3, 7.4, 7.45, 7.5, 7.55], log_low=[4.0, 4.5, 5.0],
                                        log_high=[5.0, 5.5, 6.0])),
    "cadence_classes": (_cadence_classes, _grid(period_cut_s=[0.8, 0.9, 1.0], log_walk=[4.0, 4.5, 5.0],
                                                log_run=[5.0, 5.5, 6.0])),
    "swing_guard": (_swing_guard, _grid(log_gamma=[4.0, 4.25, 4.5], max_swing_s=[1.25, 1.5, 2.0, 3.0],
                                        max_swing_ratio=[1.3, 1.5, 1.75, 2.0])),
    "stance_guard": (_stance_guard, _grid(log_gamma=np.arange(4.0, 6.01, 0.25),
                                          min_fraction=[0.0, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45])),
    "quantile": (_quantile, _grid(log_span=[5.0], fraction=np.arange(0.2, 0.61, 0.05))),
    "vote": (_vote, _grid(log_shoe=[4.5, 5.5], log_are=[4.0, 5.0], log_amv=[4.0, 5.0],
                          min_fraction=[0.0, 0.3, 0.4])),
}


def _key(params: Dict[str, float]) -> str:
    return json.dumps({k: round(v, 4) for k, v in sorted(params.items())})


def load_trials(root: Path) -> List[ImuRecording]:
    """The PyShoe trials under ``root`` (the ``pyshoe_vicon`` folder)."""
    return [load_pyshoe_trial(p) for p in list_pyshoe_trials(root)]


def score_setting(recs: Sequence[ImuRecording], stats: Sequence[Stats], rule: StanceRule,
                  params: Dict[str, float], smooth: bool = True) -> List[Dict[str, Any]]:
    """Per-trial rows (armse_m, stride_error, stance_fraction, implausible) of one setting."""
    from indoorloc import pdr

    rows = []
    for rec, st in zip(recs, stats):
        stance = np.asarray(rule(rec, st, params), dtype=bool)
        out = pdr.zupt_ekf(rec.time_s, rec.acc_mps2, rec.gyro_radps, stance, options=pdr.ZuptEkfOptions(smooth=smooth))
        strides = np.asarray(pdr.count_strides(stance, rec.rate_hz)["stride_indices"])
        r = pe.score_pyshoe_trial(rec, (np.asarray(out["positions_m"]), strides))
        rows.append({"trial": rec.name, "armse_m": r["armse_m"], "stride_error": r["stride_count_error"],
                     "strides_truth": r["strides_truth"], "stance_fraction": float(stance.mean()),
                     "implausible": bool(out["health"]["implausible"])})
    return rows


def sweep(recs: Sequence[ImuRecording], stats: Sequence[Stats], family: str,
          cache_file: Optional[Path] = None, smooth: bool = True) -> Dict[str, List[Dict[str, Any]]]:
    """{setting key: per-trial rows} for every setting of ``family``, cached in ``cache_file``."""
    rule, grid = CANDIDATES[family]
    res: Dict[str, List[Dict[str, Any]]] = {}
    if cache_file is not None and cache_file.is_file():
        res = json.loads(cache_file.read_text())
    todo = [p for p in grid if _key(p) not in res]
    for p in progress(todo, total=len(todo), desc=family):
        res[_key(p)] = score_setting(recs, stats, rule, p, smooth)
        if cache_file is not None:
            write_text_atomic(cache_file, json.dumps(res))
    return {_key(p): res[_key(p)] for p in grid}


def session_of(trial: str) -> str:
    """The recording day of a PyShoe trial (``2017-11-22-11-22-03`` -> ``2017-11-22``)."""
    return trial[:10]


def leave_one_out(res: Dict[str, List[Dict[str, Any]]], by_session: bool = False) -> Dict[str, Any]:
    """Held-out scores: for each trial, the setting with the lowest mean ARMSE on the others.

    ``by_session``: hold out a whole recording day at a time (4 days: 11, 5, 4 and 1 trials),
    a harder test of transfer to recordings made on another day.

    Returns ``{"armse_m": [...], "stride_error": [...], "chosen": [...], "median_armse_m",
    "mean_armse_m", "worst_armse_m", "n_over_0_4_m", "strides_off", "strides_truth",
    "strides_off_pct", "chosen_counts", "implausible_flags"}``.
    """
    keys = list(res)
    a = np.array([[r["armse_m"] for r in res[k]] for k in keys])
    s = np.array([[r["stride_error"] for r in res[k]] for k in keys])
    flag = np.array([[r["implausible"] for r in res[k]] for k in keys])
    n = a.shape[1]
    names = [r["trial"] for r in res[keys[0]]]
    held, strides, chosen, flags = [], [], [], []
    for i in range(n):
        if by_session:
            others = [j for j in range(n) if session_of(names[j]) != session_of(names[i])]
        else:
            others = [j for j in range(n) if j != i]
        best = int(np.argmin(a[:, others].mean(axis=1)))
        held.append(float(a[best, i]))
        strides.append(int(s[best, i]))
        chosen.append(keys[best])
        flags.append(bool(flag[best, i]))
    held_a = np.array(held)
    truth = int(sum(r["strides_truth"] for r in res[keys[0]]))
    off = int(np.sum(np.abs(strides)))
    return {"trials": [r["trial"] for r in res[keys[0]]], "armse_m": held, "stride_error": strides,
            "chosen": chosen, "implausible": flags,
            "median_armse_m": float(np.median(held_a)), "mean_armse_m": float(held_a.mean()),
            "worst_armse_m": float(held_a.max()), "n_over_0_4_m": int(np.sum(held_a > 0.4)),
            "strides_off": off, "strides_truth": truth, "strides_off_pct": 100.0 * off / max(truth, 1),
            "chosen_counts": Counter(chosen).most_common()}


def held_out_paper_tables(recs: Sequence[ImuRecording], res: Dict[str, List[Dict[str, Any]]],
                          by_session: bool = False) -> Dict[str, Any]:
    """Paper 002's Table III (SHOE stride count) and Table IV (travelled distance) per trial, each
    trial scored with the swing-guard setting chosen without it (:func:`leave_one_out` on ``res``,
    the ``swing_guard`` sweep): the held-out counterpart of the ``indoorloc reproduce`` rows,
    which use the library's default setting, chosen on all 21 trials. Errors as in
    ``pdr_reproduce`` (count: |detected - (annotated - 1)| / (annotated - 1); distance: path over
    the annotated stance samples, ZUPT EKF + RTS) [%]."""
    loo = leave_one_out(res, by_session=by_session)
    count_pct, distance_pct = [], []
    for rec, key in zip(recs, loo["chosen"]):
        p = json.loads(key)
        # The library's pipeline (run_recommended: its other detector settings, EKF + RTS) with the
        # fold's choice: with the default choice on every trial it gives the reproduce rows exactly.
        out = recommended.run_recommended(rec, threshold=10.0 ** p["log_gamma"], max_swing_s=p["max_swing_s"],
                                          max_swing_ratio=p["max_swing_ratio"])
        truth = max(1, int(rec.stride_indices.size) - 1)
        count_pct.append(100.0 * abs(int(out["stride_indices"].size) - truth) / truth)
        idx = np.asarray(rec.stride_indices, dtype=np.int64)
        est = out["positions_m"][idx, :2]
        true_len = metrics.path_length(np.asarray(rec.truth_xy_m)[idx])
        distance_pct.append(100.0 * abs(metrics.path_length(est) - true_len) / true_len)
    return {"trials": loo["trials"], "chosen": loo["chosen"], "count_error_pct": count_pct,
            "distance_error_pct": distance_pct}


#: The rules compared by :func:`stress_noise`, each at the setting the CV folds chose.
STRESS_RULES = {
    "fixed 10^5.25": ("fixed", {"log_gamma": 5.25}),
    "per-class (cut 7.45, 1e4 / 10^5.5)": ("p99_classes", {"p99_cut": 7.45, "log_low": 4.0, "log_high": 5.5}),
    "swing guard (defaults)": ("swing_guard", {"log_gamma": 4.0, "max_swing_s": 2.0, "max_swing_ratio": 1.5}),
}


def stress_noise(recs: Sequence[ImuRecording], noise: Sequence[Tuple[float, float]] = ((0.1, 0.02), (0.3, 0.05)),
                 seed: int = 0) -> Dict[str, Dict[str, Any]]:
    """A noisier sensor: white noise (acc sd [m/s^2], gyro sd [rad/s]) added to every trial (seeded
    per trial), then each rule of :data:`STRESS_RULES` at its CV-chosen setting, EKF + RTS.
    Nothing is re-tuned: how a rule transfers to a sensor it was not tuned on. Returns
    ``{f"{rule} @ acc {a}, gyro {g}": {"median_armse_m", "mean_armse_m", "worst_armse_m",
    "strides_off", "strides_truth"}}``."""
    from dataclasses import replace

    out: Dict[str, Dict[str, Any]] = {}
    for a_sd, g_sd in noise:
        noisy = []
        for i, rec in enumerate(recs):
            rng = np.random.default_rng([seed, i])
            noisy.append(replace(rec, acc_mps2=rec.acc_mps2 + a_sd * rng.standard_normal(rec.acc_mps2.shape),
                                 gyro_radps=rec.gyro_radps + g_sd * rng.standard_normal(rec.gyro_radps.shape)))
        stats = [detector_statistics(r) for r in noisy]
        for label, (family, params) in STRESS_RULES.items():
            rows = score_setting(noisy, stats, CANDIDATES[family][0], params)
            a = np.array([r["armse_m"] for r in rows])
            out[f"{label} @ acc {a_sd:g} m/s^2, gyro {g_sd:g} rad/s"] = {
                "median_armse_m": float(np.median(a)), "mean_armse_m": float(a.mean()), "worst_armse_m": float(a.max()),
                "strides_off": int(sum(abs(r["stride_error"]) for r in rows)),
                "strides_truth": int(sum(r["strides_truth"] for r in rows))}
    return out


def markdown(results: Dict[str, Dict[str, Any]]) -> str:
    """The CV table: one row per family."""
    lines = ["| candidate | settings | held-out median [m] | mean [m] | worst [m] | trials > 0.4 m | "
             "strides off | settings chosen (folds) |", "|---|---:|---:|---:|---:|---:|---:|---|"]
    for name, r in results.items():
        chosen = "; ".join(f"{k} x{c}" for k, c in r["chosen_counts"][:3])
        lines.append(f"| {name} | {r['n_settings']} | {r['median_armse_m']:.3f} | {r['mean_armse_m']:.3f} | "
                     f"{r['worst_armse_m']:.3f} | {r['n_over_0_4_m']} | {r['strides_off']} / {r['strides_truth']} "
                     f"({r['strides_off_pct']:.2f} %) | {chosen} |")
    return "\n".join(lines)


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data-root", default=None, help="the pdr data folder (default ../shared/data/pdr)")
    ap.add_argument("--families", nargs="*", default=list(CANDIDATES))
    ap.add_argument("--cache-dir", default=None, help="cache of per-setting rows (default: none)")
    ap.add_argument("--json", default=None, help="write the CV results here")
    ap.add_argument("--quiet", action="store_true", help="no progress bars")
    ap.add_argument("--stress", action="store_true", help="also the added-noise transfer test (stress_noise)")
    ap.add_argument("--paper-tables", action="store_true",
                    help="also paper 002's Tables III/IV per trial at the held-out swing-guard choice")
    args = ap.parse_args(argv)
    from indoorloc import progress as _progress

    _progress.set_quiet(args.quiet)
    from indoorloc.registry import default_pdr_root

    root = Path(args.data_root) if args.data_root else default_pdr_root()
    recs = load_trials(root / "pyshoe_vicon")
    stats = [detector_statistics(r) for r in recs]
    cache = Path(args.cache_dir) if args.cache_dir else None
    if cache is not None:
        cache.mkdir(parents=True, exist_ok=True)
    results, by_day = {}, {}
    for fam in args.families:
        res = sweep(recs, stats, fam, None if cache is None else cache / f"{fam}.json")
        r = leave_one_out(res)
        r["n_settings"] = len(res)
        results[fam] = r
        d = leave_one_out(res, by_session=True)
        d["n_settings"] = len(res)
        by_day[fam] = d
        print(f"{fam}: held-out median {r['median_armse_m']:.3f} mean {r['mean_armse_m']:.3f} worst "
              f"{r['worst_armse_m']:.3f} m, strides off {r['strides_off']}/{r['strides_truth']}", file=sys.stderr)
    print("Leave one trial out (21 folds)\n")
    print(markdown(results))
    print("\nLeave one recording day out (4 folds)\n")
    print(markdown(by_day))
    doc: Dict[str, Any] = {"leave_one_trial_out": results, "leave_one_day_out": by_day}
    if args.stress:
        doc["stress_noise"] = stress_noise(recs)
        print("\nAdded sensor noise, settings as chosen by the CV (not re-tuned)\n")
        print("| rule @ noise | median [m] | mean [m] | worst [m] | strides off |\n|---|---:|---:|---:|---:|")
        for k, v in doc["stress_noise"].items():
            print(f"| {k} | {v['median_armse_m']:.3f} | {v['mean_armse_m']:.3f} | {v['worst_armse_m']:.3f} | "
                  f"{v['strides_off']} / {v['strides_truth']} |")
    if args.paper_tables:
        res = sweep(recs, stats, "swing_guard", None if cache is None else cache / "swing_guard.json")
        print("\nPaper 002 Tables III/IV at the held-out swing-guard setting [%]\n")
        print("| folds | SHOE stride count error: mean | distance error: mean | median | IQR |\n|---|---:|---:|---:|---|")
        for label, by_session in (("one trial out (21)", False), ("one recording day out (4)", True)):
            h = held_out_paper_tables(recs, res, by_session=by_session)
            doc[f"paper_tables_{'day' if by_session else 'trial'}"] = h
            d = np.asarray(h["distance_error_pct"])
            print(f"| {label} | {np.mean(h['count_error_pct']):.2f} | {d.mean():.2f} | {np.median(d):.2f} | "
                  f"{np.percentile(d, 25):.2f}-{np.percentile(d, 75):.2f} |")
    if args.json:
        write_text_atomic(args.json, json.dumps(doc, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
