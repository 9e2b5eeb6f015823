"""What live tracking costs in accuracy, and which live variants help: the live filter (causal
steps, each WiFi fix applied when its scan exists) against the batch filter of ``indoorloc fusion
evaluate`` (whole-walk steps, fixes at the mean last-seen time of their readings), on the same folds
and models as the evaluation (``fusion_real_folds``: per floor, k folds by walk, the fold's
calibration, fingerprint database and survey-anchored default tracker).

Per test walk, the errors at its waypoints of

- ``batch_filter``: the evaluation's ``fusion_unknown_start`` (its point estimate);
- ``live``: the evaluation's ``fusion_live`` (``fusion.live.causal_track``, equal to a
  ``LiveTracker`` replay), scored from its first located estimate
  (``fusion_real_walk.located_track_at``: before the first fix an unknown start's estimate is the
  prior's mean, not a position);
- ``live_delay_compensation``: the same with each fix moved by the PDR displacement since the time
  its readings describe (the option ``delay_compensation``);
- ``live_window_Ws``: the live filter with a query window of W s instead of 16 s (a shorter window
  lags less); the window is then chosen by leave-one-floor-out over {W..., 16} (``lofo_window``);
- ``live_backdated_fixes``: causal steps with the evaluation's fix times (not realisable live: the
  reference that isolates the fixes' timing; scored over every step, as the batch).

Usage: ``python -m indoorloc.experiments.fusion_live_accuracy [--floors ...] [--seed N ...] [--json F]
[--markdown F]`` (``study_cli``); the committed results are benchmarks/results/fusion_live_accuracy.{json,md}.
"""

from __future__ import annotations

import sys
from dataclasses import replace
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from indoorloc import fusion, progress
from indoorloc.experiments import fusion_real_folds as ff
from indoorloc.experiments import fusion_real_walk as fw
from indoorloc.experiments.fusion_real_settings import RealSettings
from indoorloc.experiments.study_cli import run_study
from indoorloc.fusion import live, site_model
from indoorloc.fusion import wifi_fixes as wfx

#: Query windows [s] tried for the live filter (the default, 16 s, was chosen with backdated fixes).
LIVE_WINDOWS_S = (4.0, 8.0)
METHODS = ("batch_filter", "live", "live_delay_compensation") + tuple(
    f"live_window_{w:g}s" for w in LIVE_WINDOWS_S) + ("live_backdated_fixes",)


def _walk_errors(fl, i: int, models, settings: RealSettings, errors: Dict[str, List[float]],
                 first_position_s: List[float]) -> None:
    """Appends walk i's waypoint errors [m] per method (a method that never located it: none)."""
    walk = fl.walks[i]
    wt = np.asarray(walk.waypoint_t_s, float)
    wxy = np.asarray(walk.waypoint_xy_m, float)
    pdr = site_model.tracker_steps(fl.steps[i], models.cal, settings.track_settings())
    if len(pdr) == 0:
        return
    tracker = fw._grid_tracker(fl.plan, fw._grid_options(settings, max(models.cal.yaw_offset_spread_rad, 1e-3)),
                               fl.name, models.database)
    fixes = wfx.fixes_for_walk(walk, models.database)
    r = fusion.track_grid(tracker, pdr, fixes=fixes, smooth=False)
    key = "median_m" if settings.point_estimate == "median" and "median_m" in r else "mean_m"
    errors["batch_filter"] += np.hypot(*(fw._interp_track(wt, pdr.times_s, r[key]) - wxy).T).tolist()
    noise = dict(step_length_sd_fraction=settings.step_length_sd_fraction,
                 step_heading_sd_rad=settings.step_heading_sd_rad)
    variants = {"live": (models.database, False), "live_delay_compensation": (models.database, True)}
    for w in LIVE_WINDOWS_S:
        variants[f"live_window_{w:g}s"] = (
            models.database.with_settings(replace(models.database.settings, query_window_s=w)), False)
    for name, (database, compensate) in variants.items():
        run = live.causal_track(tracker, walk, models.cal, database, delay_compensation=compensate, **noise)
        at = fw.located_track_at(wt, run)
        if at is None:
            continue
        errors[name] += np.hypot(*(at[0] - wxy).T).tolist()
        if name == "live":
            first_position_s.append(at[1] - float(wt[0]))
    steps, _ = live.causal_inputs(walk, models.cal, None, **noise)
    if len(steps):
        b = fusion.track_grid(tracker, steps, fixes=fixes, smooth=False)
        errors["live_backdated_fixes"] += np.hypot(*(fw._interp_track(wt, steps.times_s, b["mean_m"]) - wxy).T).tolist()


def _stats(e: Sequence[float]) -> Dict[str, Any]:
    a = np.asarray(e, float)
    return {"n": int(a.size), "mean_m": float(a.mean()), "median_m": float(np.median(a)),
            "p90_m": float(np.percentile(a, 90))} if a.size else {"n": 0}


def compute(data_root: Optional[str], floors: Sequence[str], seeds: List[int]) -> Dict[str, Any]:
    """Per floor and pooled: each method's waypoint errors over the fold seeds' partitions; the live
    tracker's first-position delay; the live window by leave-one-floor-out."""
    _, data = ff.load_site(data_root, floors)
    names = [fl.name for fl in data]
    per_floor: Dict[str, Dict[str, List[float]]] = {n: {m: [] for m in METHODS} for n in names}
    first_position_s: List[float] = []
    ticker = progress.Ticker(desc="fusion_live_accuracy: folds", total=len(seeds) * RealSettings().folds)
    for seed in seeds:
        settings = RealSettings(seed=seed, floor_identification=False)
        fold_of = {fl.name: ff._folds(len(fl.walks), settings.folds, seed) for fl in data}
        for j in range(settings.folds):
            models = ff._fold_models(data, fold_of, j, settings, None, with_crowd_map=False)
            for fl in data:
                for i in fold_of[fl.name][j]:
                    _walk_errors(fl, int(i), models[fl.name], settings, per_floor[fl.name], first_position_s)
            ticker.tick()
    ticker.close()
    result: Dict[str, Any] = {"floors": {n: {m: _stats(v) for m, v in e.items()} for n, e in per_floor.items()}}
    result["pooled"] = {m: _stats(np.concatenate([per_floor[n][m] for n in names])) for m in METHODS}
    fp = np.asarray(first_position_s, float)
    result["live_first_position_s"] = {"median": float(np.median(fp)), "p90": float(np.percentile(fp, 90)),
                                       "max": float(fp.max()), "walks": int(fp.size)} if fp.size else None
    # Leave one floor out: the window with the lowest mean error on the other floors' waypoints.
    candidates = {16.0: "live", **{w: f"live_window_{w:g}s" for w in LIVE_WINDOWS_S}}
    lofo = {}
    for held in names if len(names) > 1 else []:  # one floor: nothing to choose on
        others = {w: float(np.mean(np.concatenate([per_floor[f][m] for f in names if f != held])))
                  for w, m in candidates.items()}
        best = min(others, key=others.get)
        lofo[held] = {"window_s": best, "held_out_mean_m": float(np.mean(per_floor[held][candidates[best]]))}
    result["lofo_window"] = lofo
    return result


def markdown(result: Dict[str, Any]) -> str:
    """The tables of the study (mean / median / p90 [m] per floor and pooled, the LOFO window)."""
    lines = ["| floor | " + " | ".join(METHODS) + " |", "|---" * (len(METHODS) + 1) + "|"]
    for name, per in list(result["floors"].items()) + [("pooled", result["pooled"])]:
        lines.append(f"| {name} | " + " | ".join(
            f"{per[m]['mean_m']:.2f} / {per[m]['median_m']:.2f} / {per[m]['p90_m']:.2f}" if per[m]["n"] else "-"
            for m in METHODS) + " |")
    fp = result["live_first_position_s"]
    text = (f"Waypoint errors [m], mean / median / p90, the folds of `indoorloc fusion evaluate` (fold seeds "
            f"{result.get('seeds', [0])}; python -m indoorloc.experiments.fusion_live_accuracy).\n\n" + "\n".join(lines))
    if fp:
        text += (f"\n\nThe live tracker's first position: {fp['median']:.1f} s after the walk's first waypoint "
                 f"(median; p90 {fp['p90']:.1f} s, max {fp['max']:.1f} s, {fp['walks']} walks); the waypoints "
                 "before it are scored with that first position.")
    if result["lofo_window"]:
        text += "\n\nLive query window by leave-one-floor-out (chosen on the other floors; held-out mean error):\n\n"
        text += "\n".join(f"- {f}: {v['window_s']:g} s, {v['held_out_mean_m']:.2f} m"
                           for f, v in result["lofo_window"].items())
    if "seconds" in result:
        text += f"\n\n{result['seconds']:.0f} s."
    return text


def main(argv: Optional[Sequence[str]] = None) -> int:
    return run_study(argv, __doc__.split("\n\n")[0], compute, markdown)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
