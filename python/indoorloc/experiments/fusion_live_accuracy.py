"""What live tracking costs in accuracy: the live filter (causal steps, WiFi fixes at their scan
times) against the batch filter and smoother of ``indoorloc fusion evaluate`` (whole-walk steps,
fixes at the mean last-seen time of their measurements), on the shared competition floors.

Per floor, 4 folds by walk: models from the other folds (PDR calibration on batch steps for the
batch methods and on causal steps for the live ones; one fingerprint database), then per test walk
the errors at its waypoints of

- ``batch_filter`` / ``batch_smoother``: ``fusion.track_grid`` on ``handheld_steps`` and
  ``fixes_for_walk`` (the fusion_unknown_start / fusion_smoother methods of fusion evaluate);
- ``live``: ``fusion.live.causal_track`` (equal to a LiveTracker replay, tests/python/test_fusion_live.py):
  fixes at their scan times;
- ``live_delay_compensation``: the same with each fix moved by the PDR displacement since the
  time it describes (the option ``delay_compensation``);
- ``live_backdated_fixes``: causal steps with fusion evaluate's fix times (not realisable live: the
  reference that isolates the effect of the fix timing);
- ``live_window_Ws``: the live filter with a query window of W s instead of 16 s (a shorter window
  lags less); the window is then chosen by leave-one-floor-out over {W..., 16} (``lofo_window``).

Estimates at a waypoint time are interpolated between the step estimates, as fusion evaluate does,
for every method. Usage: ``python -m indoorloc.experiments.fusion_live_accuracy [FLOOR ...]``;
writes benchmarks/results/fusion_live_accuracy.{json,md}.
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import replace
from pathlib import Path
from typing import Dict, List

import numpy as np

from indoorloc import fusion
from indoorloc.pdr import handheld as ph
from indoorloc.pdr import streaming as ps
from indoorloc.fusion import wifi_fixes
from indoorloc.fusion import live
from indoorloc.io import load_floor_plan, read_ilc_floor
from indoorloc.io.atomic_file import write_text_atomic

ROOT = Path(__file__).resolve().parents[4] / "shared" / "data" / "fusion" / "ilc2020_site2"
#: Query windows [s] tried for the live filter (the batch's 16 s was chosen with backdated fixes).
LIVE_WINDOWS_S = (4.0, 8.0)
METHODS = ("batch_filter", "batch_smoother", "live", "live_delay_compensation", "live_backdated_fixes") + tuple(
    f"live_window_{w:g}s" for w in LIVE_WINDOWS_S)


def _number(name: str) -> int:
    return -int(name[1:]) if name.startswith("B") else int(name[1:])


def _at(t_query, t, xy):
    return np.column_stack([np.interp(t_query, t, xy[:, 0]), np.interp(t_query, t, xy[:, 1])])


def floor_errors(name: str, folds: int = 4) -> Dict[str, List[float]]:
    number = _number(name)
    floor = read_ilc_floor(ROOT / name)
    walks = list(floor.walks())
    plan = load_floor_plan(floor.geojson_path, floors=[number], origin_lon_lat="outline_sw")
    batch_steps = [ph.handheld_steps(w) for w in walks]
    causal_steps = [ps.causal_handheld_steps(w) for w in walks]
    errors: Dict[str, List[float]] = {m: [] for m in METHODS}
    for test in np.array_split(np.arange(len(walks)), folds):
        tset = set(test.tolist())
        train = [i for i in range(len(walks)) if i not in tset]
        tw = [walks[i] for i in train]
        cal_b = ph.calibrate_handheld(tw, steps_cache=[batch_steps[i] for i in train])
        cal_c = ph.calibrate_handheld(tw, steps_cache=[causal_steps[i] for i in train])
        db = wifi_fixes.build_database(tw, wifi_fixes.FixSettings(), [batch_steps[i] for i in train], floors=[number] * len(tw))
        trk_b = fusion.GridTracker(plan, fusion.GridTrackerOptions(heading_offset_sd_rad=max(cal_b.yaw_offset_spread_rad, 1e-3)))
        trk_c = fusion.GridTracker(plan, fusion.GridTrackerOptions(heading_offset_sd_rad=max(cal_c.yaw_offset_spread_rad, 1e-3)))
        for i in test:
            w = walks[i]
            wt, wxy = np.asarray(w.waypoint_t_s, float), np.asarray(w.waypoint_xy_m, float)
            st = ph.rescale(batch_steps[i], cal_b.options)
            steps = fusion.Steps.from_polar(st.t_s, st.length_m, st.heading_rad + cal_b.yaw_offset_rad,
                                            live.STEP_LENGTH_SD_FRACTION * st.length_m, live.STEP_HEADING_SD_RAD)
            fixes = wifi_fixes.fixes_for_walk(w, db)
            if len(steps) == 0:
                continue
            r = fusion.track_grid(trk_b, steps, fixes=fixes)
            errors["batch_filter"] += np.hypot(*(_at(wt, steps.times_s, r["mean_m"]) - wxy).T).tolist()
            errors["batch_smoother"] += np.hypot(*(_at(wt, steps.times_s, r["smoothed_m"]) - wxy).T).tolist()
            c = live.causal_track(trk_c, w, cal_c, db)
            if len(c["times_s"]) == 0:
                continue
            errors["live"] += np.hypot(*(_at(wt, c["times_s"], c["mean_m"]) - wxy).T).tolist()
            n = live.causal_track(trk_c, w, cal_c, db, delay_compensation=True)
            errors["live_delay_compensation"] += np.hypot(*(_at(wt, n["times_s"], n["mean_m"]) - wxy).T).tolist()
            for win in LIVE_WINDOWS_S:
                dbw = db.with_settings(replace(db.settings, query_window_s=win))
                cw = live.causal_track(trk_c, w, cal_c, dbw)
                errors[f"live_window_{win:g}s"] += np.hypot(*(_at(wt, cw["times_s"], cw["mean_m"]) - wxy).T).tolist()
            csteps, _ = live.causal_inputs(w, cal_c, None)
            cb = fusion.track_grid(trk_c, csteps, fixes=fixes, smooth=False)
            errors["live_backdated_fixes"] += np.hypot(*(_at(wt, csteps.times_s, cb["mean_m"]) - wxy).T).tolist()
    return errors


def _stats(e: List[float]) -> Dict[str, float]:
    a = np.asarray(e, float)
    return {"n": int(a.size), "mean_m": float(a.mean()), "median_m": float(np.median(a)),
            "p90_m": float(np.percentile(a, 90))} if a.size else {"n": 0}


def main(argv: List[str]) -> int:
    floors = argv or ["F8", "F3", "F4", "F7"]
    result = {"floors": {}}
    pooled: Dict[str, List[float]] = {m: [] for m in METHODS}
    all_errors = {}
    for name in floors:
        e = floor_errors(name)
        all_errors[name] = e
        result["floors"][name] = {m: _stats(v) for m, v in e.items()}
        for m in METHODS:
            pooled[m] += e[m]
        print(name, {m: round(result["floors"][name][m].get("mean_m", math.nan), 2) for m in METHODS}, flush=True)
    result["pooled"] = {m: _stats(v) for m, v in pooled.items()}
    # Leave one floor out: the window with the lowest mean error on the other floors' waypoints.
    cand = {16.0: "live", **{w: f"live_window_{w:g}s" for w in LIVE_WINDOWS_S}}
    per_floor = {name: floor_errs for name, floor_errs in all_errors.items()}
    lofo = {}
    for held in floors:
        others = {w: np.mean(np.concatenate([per_floor[f][m] for f in floors if f != held])) for w, m in cand.items()}
        best = min(others, key=others.get)
        lofo[held] = {"window_s": best, "held_out_mean_m": float(np.mean(per_floor[held][cand[best]]))}
    result["lofo_window"] = lofo
    lines = ["| floor | " + " | ".join(METHODS) + " |", "|---" * (len(METHODS) + 1) + "|"]
    for name, per in list(result["floors"].items()) + [("pooled", result["pooled"])]:
        lines.append(f"| {name} | " + " | ".join(
            f"{per[m]['mean_m']:.2f} / {per[m]['median_m']:.2f} / {per[m]['p90_m']:.2f}" for m in METHODS) + " |")
    lines += ["", "Live query window by leave-one-floor-out (chosen on the other floors; held-out mean error):", ""]
    lines += [f"- {f}: {v['window_s']:g} s, {v['held_out_mean_m']:.2f} m" for f, v in lofo.items()]
    md = ("Waypoint errors [m], mean / median / p90, 4 folds by walk per floor (python -m "
          "indoorloc.experiments.fusion_live_accuracy " + " ".join(floors) + ").\n\n" + "\n".join(lines) + "\n")
    out = Path(__file__).resolve().parents[3] / "benchmarks" / "results"
    write_text_atomic(out / "fusion_live_accuracy.json", json.dumps(result, indent=2))
    write_text_atomic(out / "fusion_live_accuracy.md", md)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
