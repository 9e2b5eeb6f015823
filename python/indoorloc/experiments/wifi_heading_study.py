"""Study: the direction-persistent WiFi-only tracker (``indoorloc.fusion.wifi_heading_sequence``)
against ``wifi_sequence`` and ``wifi_knn`` (issue 25; docs/fusion_real.md, "WiFi only: a
direction-persistent motion prior").

``python -m indoorloc.experiments.wifi_heading_study --cache FILE [--seed 0] [--grid JSON]
[--workers 2] [--json FILE]``

The cases (per floor and fold: the training database's survey positions and the test walks with
their fixes, waypoints and coverage) are ``wifi_sequence_study``'s, read from its ``--cache``
pickle (built there when missing). Every grid point is scored at every test waypoint of the six
floors; the point is chosen by leave-one-floor-out (``wifi_sequence_study.lofo``: for each
held-out floor the point with the lowest pooled mean over the other five).
"""

from __future__ import annotations

import argparse
import itertools
import json
import pickle
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from indoorloc.experiments import wifi_sequence_study as wss
from indoorloc.fusion import wifi_heading_sequence as whs
from indoorloc.fusion import wifi_sequence as ws
from indoorloc.io.atomic_file import write_text_atomic

#: The final grid (docs/fusion_real.md lists the three grids before it): the LOFO choice is read
#: from it; headings 0 is wifi_sequence's random walk.
GRID: Dict[str, Sequence[Any]] = {
    "headings": (0, 8, 16),
    "speed_m_per_s": (1.0, 1.2),
    "heading_blur_sd_m": (0.5, 1.0),
    "keep_heading_probability": (0.9, 0.97),
    "fix_sd_scale": (0.25, 0.35),
    "fix_survey_distance_factor": (0.15, 0.25),
    "fix_outlier_probability": (0.001,),
    "to_wander_probability": (0.02,),
    "wall_log_penalty": (-1.0,),
}

#: Fields whose change needs new motion stencils (the rest reuse them).
MOTION_KEYS = ("tick_s", "cell_size_m", "headings", "speed_m_per_s", "heading_blur_sd_m", "wander_sd_m_per_sqrt_s",
               "margin_cells")


#: Fields that do not matter without headings (points with headings=0 differing only there are one).
HEADING_ONLY = ("speed_m_per_s", "heading_blur_sd_m", "keep_heading_probability", "neighbour_turn_share",
                "to_wander_probability", "from_wander_probability")


def _points(grid: Dict[str, Sequence[Any]]) -> List[Dict[str, Any]]:
    """The grid's points (a JSON list of grids: their union), headings=0 once per other setting."""
    grids = grid if isinstance(grid, list) else [grid]
    out: List[Dict[str, Any]] = []
    for g in grids:
        names = list(g)
        for v in itertools.product(*(g[k] for k in names)):
            p = dict(zip(names, v))
            if p.get("headings", 1) == 0:
                p = {k: x for k, x in p.items() if k not in HEADING_ONLY}
            if p not in out:
                out.append(p)
    return out


def _key(p: Dict[str, Any]) -> str:
    return ",".join(f"{k}={v}" for k, v in p.items())


def fold_errors(job) -> Dict[str, np.ndarray]:
    """One fold of one floor: errors[point key] at its test waypoints (case order), plus "wifi_knn"."""
    case, fold, points = job
    from indoorloc.io import load_floor_plan

    plan = load_floor_plan(case["geojson_path"], floors=[case["number"]], origin_lon_lat="outline_sw")
    f = case["folds"][fold]
    walks = [w if isinstance(w, wss.TestWalk) else wss.TestWalk(**w) for w in f["walks"]]
    if not walks:
        return {"wifi_knn": np.zeros(0), **{_key(p): np.zeros(0) for p in points}}
    out = {"wifi_knn": np.concatenate([wss.knn_errors(w, "") for w in walks])}
    stencil_cache: Dict[str, Any] = {}
    for p in points:
        s = replace(whs.HeadingSequenceSettings(), **p)
        grid = whs.heading_grid(plan, s, np.asarray(f["database"].positions_m))
        mk = _key({k: getattr(s, k) for k in MOTION_KEYS})
        if mk not in stencil_cache:
            stencil_cache[mk] = whs.motion_stencils(s)
        errs = []
        for w in walks:
            tr = whs.track_fixes(grid, w.fixes[""], 0.0, w.duration_s, s, stencil_cache[mk])
            errs.append(np.hypot(*(ws.at_times(tr, w.waypoint_t_s) - w.waypoint_xy_m).T))
        out[_key(p)] = np.concatenate(errs)
    return out


def load_cases(cache: Path, seed: int, data_root: Optional[Path], log=print):
    """wifi_sequence_study's cases of ``seed`` (built into ``cache`` when it is missing)."""
    if not Path(cache).exists():
        from indoorloc.experiments.fusion_real_settings import default_site_root
        from indoorloc.io.survey_layout import survey_floors

        root = data_root or default_site_root()
        floors = [sf.name for sf in survey_floors(root, None, argument="data_root")]
        variants = wss._fix_variants(dict(wss.GRID))
        cases = wss.build_cases(root, floors, seed, variants, log)
        tmp = Path(str(cache) + ".tmp")
        with open(tmp, "wb") as fh:
            pickle.dump({"seed": seed, "variants": variants, "floors": cases}, fh)
        tmp.replace(cache)
    with open(cache, "rb") as fh:
        d = pickle.load(fh)
    if d.get("seed") != seed:
        raise ValueError(f"indoorloc: argument 'cache': holds seed {d.get('seed')}, not {seed}")
    return d["floors"]


def run(cases, grid: Dict[str, Sequence[Any]], workers: int = 2, log=print) -> Dict[str, Any]:
    points = _points(grid)
    tic = time.perf_counter()
    # Jobs by (floor, fold), largest first, so that two workers finish together.
    jobs = [(f, i) for f, c in cases.items() for i in range(len(c["folds"]))]
    jobs.sort(key=lambda j: -sum(w["duration_s"] if isinstance(w, dict) else w.duration_s
                                 for w in cases[j[0]]["folds"][j[1]]["walks"]))
    with ProcessPoolExecutor(max_workers=workers) as pool:
        done = dict(zip(jobs, pool.map(fold_errors, [(cases[f], i, points) for f, i in jobs])))
    errors = {f: {k: np.concatenate([done[(f, i)][k] for i in range(len(c["folds"]))]) for k in done[(f, 0)]}
              for f, c in cases.items()}
    log(f"{len(points)} points, {time.perf_counter() - tic:.0f} s")
    choice = wss.lofo(errors)
    best = choice["all_floor_choice"]
    per_floor = {}
    for f, case in cases.items():
        cov = np.concatenate([np.asarray(w["coverage_m"] if isinstance(w, dict) else w.coverage_m)
                              for fo in case["folds"] for w in fo["walks"]])
        per_floor[f] = {"wifi_knn": wss._stats(errors[f]["wifi_knn"]), "all_floor_choice": wss._stats(errors[f][best]),
                        "held_out": choice["held_out"][f],
                        "by_coverage": {"wifi_knn": wss.coverage_split(errors[f]["wifi_knn"], cov),
                                        "all_floor_choice": wss.coverage_split(errors[f][best], cov),
                                        "held_out": wss.coverage_split(errors[f][choice["held_out"][f]["chosen"]], cov)},
                        "points": {k: wss._stats(v) for k, v in errors[f].items()}}
    return {"grid": grid, "lofo": choice, "per_floor": per_floor}


def markdown(r: Dict[str, Any], seed: int) -> str:
    from indoorloc.experiments.wifi_study_folds import lofo_markdown

    lines = [lofo_markdown(r, f"Seed {seed}", [("wifi_knn", "wifi_knn"), ("heading, all-floor choice", "all_floor_choice")],
                           held_out_head="heading, held out (LOFO)"), "", "By coverage (mean m, waypoints), held out:", "",
             "| floor | <= 5 m | 5-10 m | > 10 m |", "|---|---|---|---|"]
    for f, pf in r["per_floor"].items():
        cells = [f"{v['mean_m']:.2f} ({v['n']})" if v else "-" for v in pf["by_coverage"]["held_out"].values()]
        lines.append(f"| {f} | " + " | ".join(cells) + " |")
    lines += ["", "Top points (pooled mean over the six floors):", ""]
    lines += [f"- {t['pooled_mean_m']:.2f} `{t['point']}`" for t in r["lofo"]["top"]]
    return "\n".join(lines)


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", type=Path, required=True)
    ap.add_argument("--data-root", type=Path, default=None)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--floors", nargs="*", default=None)
    ap.add_argument("--grid", default=None, help="JSON object overriding entries of GRID, or a list of them (the union)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", type=Path, default=None)
    a = ap.parse_args(argv)
    grid: Any = dict(GRID)
    if a.grid:
        given = json.loads(a.grid)
        grid = [{**GRID, **g} for g in given] if isinstance(given, list) else {**GRID, **given}
    log = lambda m: print(m, file=sys.stderr)  # noqa: E731
    cases = load_cases(a.cache, a.seed, a.data_root, log)
    if a.floors:
        cases = {f: cases[f] for f in a.floors}
    r = run(cases, grid, a.workers, log)
    r["seed"] = a.seed
    print(markdown(r, a.seed))
    if a.json:
        write_text_atomic(a.json, json.dumps(r, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
