"""Study: the WiFi-only sequence tracker (``indoorloc.fusion.wifi_sequence``) against ``wifi_knn``
(issue 25, "the best WiFi-only method <= 0.8x today's wifi_knn on every floor";
docs/fusion_real.md, "WiFi only: the sequence of fixes").

``python -m indoorloc.experiments.wifi_sequence_study [--data-root DIR] [--floors B1 F1 ...]
[--seed 0] [--cache FILE] [--grid JSON] [--json FILE] [--markdown FILE]``

Per floor, 4-fold by walk (``--seed``; seed 0 gives the folds of ``indoorloc fusion evaluate``).
Per fold, the fingerprint database of the training walks and the test walks' fixes are those of
``fusion evaluate`` (same functions, same defaults), cached in ``--cache`` (pickle). Each test
waypoint is scored with ``wifi_knn`` (the fix nearest in time) and with the sequence tracker at
every point of the grid; the grid point is chosen by leave-one-floor-out (for each held-out floor
the point with the lowest pooled mean over the other floors' waypoints is scored on it); the
defaults are the point chosen on all floors.
"""

from __future__ import annotations

import argparse
import itertools
import json
import pickle
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from indoorloc.fusion import wifi_sequence as ws
from indoorloc.io.atomic_file import write_text_atomic

#: The final grid (docs/fusion_real.md lists the four grids before it and the check grid after).
GRID: Dict[str, Sequence[Any]] = {
    "fix_sd_scale": (0.35, 0.5),
    "speed_sd_m_per_sqrt_s": (1.5, 2.0),
    "fix_tempering": (1.0,),
    "fix_outlier_probability": (0.001, 0.01),
    "fix_survey_distance_factor": (0.5, 0.25, 0.15, 0.0),
    "wall_log_penalty": (-1.0,),
    "point_estimate": ("mean", "median"),   # both from one run
}
#: Grid keys that are the fixes' (``wifi_fixes.FixSettings``; each value a separate set of fixes
#: from the same database), not the sequence tracker's.
FIX_KEYS = ("query_window_s", "temperature_db", "k")


@dataclass
class TestWalk:
    floor: str
    walk_id: str
    fold: int
    duration_s: float
    waypoint_t_s: np.ndarray
    waypoint_xy_m: np.ndarray
    coverage_m: np.ndarray     #: waypoint to the nearest training scan [m]
    fixes: Dict[str, Any]      #: fix-settings key -> indoorloc.fusion.Fixes of the fold's database


def _fix_variants(grid: Dict[str, Sequence[Any]]) -> List[Dict[str, Any]]:
    names = [k for k in FIX_KEYS if k in grid]
    return [dict(zip(names, v)) for v in itertools.product(*(grid[k] for k in names))]


def build_cases(data_root: Path, floors: Sequence[str], seed: int, variants: Sequence[Dict[str, Any]], log=print):
    """Per floor: its plan, per fold the training database, and the test walks (``TestWalk``)
    with their fixes for each variant of the fix settings."""
    from indoorloc.experiments.fusion_real_settings import RealSettings
    from indoorloc.experiments.wifi_study_folds import floor_cases
    from indoorloc.fusion import wifi_fixes as wfx

    settings = RealSettings(seed=seed)

    def record(fl, fold):
        db = fold.database
        # "": the default fixes (wifi_knn's); one more set per variant of the fix settings.
        dbs = {"": db, **{_point_key(v): db.with_settings(replace(settings.fixes, **v)) for v in variants}}
        walks = [TestWalk(fl.name, fw.walk.walk_id, fold.index, float(fw.walk.duration_s), fw.waypoint_t_s,
                          fw.waypoint_xy_m, fw.coverage_m,
                          {k: wfx.fixes_for_walk(fw.walk, d) for k, d in dbs.items()}).__dict__
                 for fw in fold.walks]
        # What the anchoring needs of the database (picklable; the matcher index is not).
        return {"database": SimpleNamespace(positions_m=np.asarray(db.positions_m), floors=np.asarray(db.floors),
                                            walk_index=np.asarray(db.walk_index)),
                "walks": walks}

    return floor_cases(data_root, floors, seed, record, log)


def knn_errors(w: TestWalk, variant: str = "") -> np.ndarray:
    """wifi_knn at the walk's waypoints: the centre of the fix nearest in time."""
    from indoorloc.experiments.fusion_real_walk import _nearest_rows
    from indoorloc.fusion import wifi_fixes as wfx

    fixes = w.fixes[variant]
    if len(fixes) == 0:
        return np.full(w.waypoint_t_s.size, np.nan)
    est = _nearest_rows(w.waypoint_t_s, fixes.times_s, wfx.fix_centres(fixes))
    return np.hypot(*(est - w.waypoint_xy_m).T)


def _point_key(p: Dict[str, Any]) -> str:
    return ",".join(f"{k}={v}" for k, v in p.items())


def evaluate(cases, grid: Dict[str, Sequence[Any]], smooth: bool = True, threads: int = 2, log=print
             ) -> Dict[str, Dict[str, np.ndarray]]:
    """errors[floor][point key] (waypoints of the floor in case order), plus "wifi_knn"."""
    from indoorloc.io import load_floor_plan

    names = [k for k in grid if k != "point_estimate" and k not in FIX_KEYS]
    estimates = grid.get("point_estimate", ("median",))
    variants = _fix_variants(grid)
    errors: Dict[str, Dict[str, List[np.ndarray]]] = {}
    for floor, case in cases.items():
        plan = load_floor_plan(case["geojson_path"], floors=[case["number"]], origin_lon_lat="outline_sw")
        e = errors.setdefault(floor, {})
        e["wifi_knn"] = [knn_errors(w, "") for f in case["folds"] for w in f["walks"]]
        tic = time.perf_counter()
        for variant, values in itertools.product(variants, itertools.product(*(grid[k] for k in names))):
            point = dict(zip(names, values))
            vkey = _point_key(variant)
            s = replace(ws.SequenceSettings(smooth=smooth), point_estimate="median", **point)
            per_est: Dict[str, List[np.ndarray]] = {pe: [] for pe in estimates}
            for f in case["folds"]:
                tracker = ws.sequence_tracker(plan, s, f["database"])

                def one(w: TestWalk):
                    tr = ws.track_fixes(tracker, w.fixes[vkey], 0.0, w.duration_s, s)
                    return {pe: np.hypot(*(ws.at_times(tr, w.waypoint_t_s, pe + "_m") - w.waypoint_xy_m).T)
                            for pe in estimates}

                with ThreadPoolExecutor(max_workers=threads) as pool:
                    for res in pool.map(one, f["walks"]):
                        for pe in estimates:
                            per_est[pe].append(res[pe])
            for pe in estimates:
                e[_point_key({**variant, **point, "point_estimate": pe})] = per_est[pe]
        log(f"  {floor}: {time.perf_counter() - tic:.0f} s")
    return {f: {k: np.concatenate(v) for k, v in e.items()} for f, e in errors.items()}


def _stats(e: np.ndarray) -> Dict[str, float]:
    e = e[np.isfinite(e)]
    return {"mean_m": float(e.mean()), "median_m": float(np.median(e)), "p90_m": float(np.percentile(e, 90)),
            "n": int(e.size)}


def lofo(errors: Dict[str, Dict[str, np.ndarray]]) -> Dict[str, Any]:
    """Per held-out floor the grid point with the lowest pooled mean over the other floors."""
    floors = list(errors)
    keys = [k for k in errors[floors[0]] if k != "wifi_knn"]
    sums = {f: np.array([np.nansum(errors[f][k]) for k in keys]) for f in floors}
    counts = {f: np.array([np.isfinite(errors[f][k]).sum() for k in keys]) for f in floors}
    out = {}
    for f in floors:
        others = [g for g in floors if g != f]
        mean = sum(sums[g] for g in others) / np.maximum(sum(counts[g] for g in others), 1)
        best = keys[int(np.argmin(mean))]
        out[f] = {"chosen": best, **_stats(errors[f][best])}
    mean_all = sum(sums.values()) / np.maximum(sum(counts.values()), 1)
    order = np.argsort(mean_all)
    pooled = np.concatenate([errors[f][out[f]["chosen"]] for f in floors])
    return {"held_out": out, "held_out_pooled": _stats(pooled), "all_floor_choice": keys[int(order[0])],
            "top": [{"point": keys[i], "pooled_mean_m": float(mean_all[i])} for i in order[:10]]}


def coverage_split(errors: np.ndarray, coverage_m: np.ndarray) -> Dict[str, Any]:
    out = {}
    for name, lo, hi in (("within_5m", -1, 5), ("5_to_10m", 5, 10), ("beyond_10m", 10, np.inf)):
        m = (coverage_m > lo) & (coverage_m <= hi)
        out[name] = _stats(errors[m]) if np.isfinite(errors[m]).any() else None
    return out


def run(data_root: Path, floors: Sequence[str], seed: int, cache: Optional[Path], grid, smooth: bool = True,
        threads: int = 2, log=print) -> Dict[str, Any]:
    cases = None
    variants = _fix_variants(grid)
    if cache is not None and Path(cache).exists():
        with open(cache, "rb") as fh:
            cases = pickle.load(fh)
        if (cases.get("seed") != seed or not set(floors) <= set(cases.get("floors", {}))
                or cases.get("variants") != variants):
            cases = None
        else:
            cases = cases["floors"]
    if cases is None:
        cases = build_cases(data_root, floors, seed, variants, log)
        if cache is not None:
            tmp = Path(str(cache) + ".tmp")
            with open(tmp, "wb") as fh:
                pickle.dump({"seed": seed, "variants": variants, "floors": cases}, fh)
            tmp.replace(cache)
    cases = {f: cases[f] for f in floors}
    for case in cases.values():  # the cache holds plain dicts (picklable whatever runs this module)
        for fo in case["folds"]:
            fo["walks"] = [w if isinstance(w, TestWalk) else TestWalk(**w) for w in fo["walks"]]
    errors = evaluate(cases, grid, smooth, threads, log)
    choice = lofo(errors)
    best = choice["all_floor_choice"]
    per_floor = {}
    for f in floors:
        cov = np.concatenate([w.coverage_m for fo in cases[f]["folds"] for w in fo["walks"]])
        per_floor[f] = {"wifi_knn": _stats(errors[f]["wifi_knn"]), "all_floor_choice": _stats(errors[f][best]),
                        "held_out": choice["held_out"][f],
                        "by_coverage": {"wifi_knn": coverage_split(errors[f]["wifi_knn"], cov),
                                        "all_floor_choice": coverage_split(errors[f][best], cov)}}
    return {"seed": seed, "smooth": smooth, "grid": {k: list(v) for k, v in grid.items()}, "lofo": choice,
            "per_floor": per_floor}


def markdown(r: Dict[str, Any]) -> str:
    from indoorloc.experiments.wifi_study_folds import lofo_markdown

    title = f"Seed {r['seed']}, {'smoothed' if r['smooth'] else 'causal filter'}"
    return lofo_markdown(r, title, [("wifi_knn", "wifi_knn"), ("sequence, all-floor choice", "all_floor_choice")],
                         held_out_head="sequence, held out (LOFO)")


def main(argv: Optional[Sequence[str]] = None) -> int:
    from indoorloc.experiments.fusion_real_settings import default_site_root
    from indoorloc.io.survey_layout import survey_floors

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data-root", type=Path, default=None)
    ap.add_argument("--floors", nargs="*", default=None)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--cache", type=Path, default=None)
    ap.add_argument("--grid", default=None, help="JSON object overriding entries of GRID")
    ap.add_argument("--filter", action="store_true", help="score the causal filter instead of the smoother")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--markdown", type=Path, default=None)
    a = ap.parse_args(argv)
    root = a.data_root or default_site_root()
    floors = [sf.name for sf in survey_floors(root, a.floors, argument="data_root")]
    grid = dict(GRID)
    if a.grid:
        grid.update({k: tuple(v) for k, v in json.loads(a.grid).items()})
    r = run(root, floors, a.seed, a.cache, grid, not a.filter, a.threads, log=lambda m: print(m, file=sys.stderr))
    md = markdown(r)
    print(md)
    if a.json:
        write_text_atomic(a.json, json.dumps(r, indent=1))
    if a.markdown:
        write_text_atomic(a.markdown, md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
