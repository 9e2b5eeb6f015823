"""Study: position fixes from a per-AP path-loss model (``indoorloc.wifi.propagation``,
``indoorloc.fusion.propagation_fixes``) fed to the WiFi-only sequence tracker
(``indoorloc.fusion.wifi_sequence``), alone or mixed with the kNN fixes (issue 25, "the best
WiFi-only method <= 0.8x today's wifi_knn on every floor"; docs/fusion_real.md, "A propagation
model that extrapolates").

``python -m indoorloc.experiments.wifi_propagation_study [--data-root DIR] [--floors ...] [--seed 0]
[--cache-dir DIR] [--grid JSON] [--options JSON] [--huber-sd 1.5] [--json FILE]``;
``... --merge A.json B.json``: the LOFO over the union of runs' grid points.

Per floor, 4-fold by walk (seed 0: the folds of ``indoorloc fusion evaluate``; the databases and
kNN fixes are those of ``fusion evaluate``, :mod:`wifi_propagation_cases`). Per fold the model is
fitted to the training fingerprints; each test walk's queries get a likelihood over the walkable
2 m cells. Every grid point (model-fix settings, mixture weight, the sequence tracker's β) is
scored at the test waypoints; the point is chosen by leave-one-floor-out
(:func:`wifi_sequence_study.lofo`).
"""

from __future__ import annotations

import argparse
import hashlib
import itertools
import json
import pickle
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from indoorloc.fusion import propagation_fixes as pf
from indoorloc.fusion.wifi_fixes import FixSettings
from indoorloc.fusion import wifi_sequence as ws
from indoorloc.wifi import propagation as pr

#: model_weight w: 0 is the kNN fixes alone (today's wifi_sequence when β = 0.15); w in (0, 1]
#: the mixture (1 - w) kNN + w model; w in [-1, 0) the product of the kNN fix and the mixture of
#: weight |w| (both as separate fixes at the same times, ``propagation_fixes.stack_fixes``).
#: Grid 4 of docs/fusion_real.md (six floors); grid 5 is GRID_5; the LOFO of the docs is over
#: their union (``--merge``).
GRID: Dict[str, Sequence[Any]] = {
    "model_weight": (0.0, -1.0),
    "temperature": (1.0, 3.0, 10.0),
    "k": (20,),
    "sd_m": (3.0, 6.0),
    "block_m": (6.0, 10.0),
    "fix_survey_distance_factor": (0.15, 0.35, 0.5, 0.75),
    "fix_sd_scale": (0.35, 0.5),
}
GRID_5: Dict[str, Sequence[Any]] = {
    "model_weight": (-1.0, -0.8, -0.5),
    "temperature": (3.0,),
    "k": (20,),
    "sd_m": (6.0, 10.0),
    "block_m": (10.0, 15.0),
    "fix_survey_distance_factor": (0.35, 0.5, 0.75),
    "fix_sd_scale": (0.5, 0.7),
}
FIT_KEYS = ("miss_weight",)


def fitted_models(case: Dict[str, Any], floor: str, seed: int, cache_dir: Optional[Path],
                  options: pr.PathLossOptions, log=print) -> List[pr.PathLossModel]:
    """The path-loss model of each fold's training database (pickled in ``cache_dir``)."""
    path = None if cache_dir is None else Path(cache_dir) / f"propagation_models_{floor}_seed{seed}_{hashlib.sha1(repr(options).encode()).hexdigest()[:10]}.pkl"
    if path is not None and path.exists():
        with open(path, "rb") as fh:
            return pickle.load(fh)
    models = []
    for fo in case["folds"]:
        tic = time.perf_counter()
        db = fo["database"]
        models.append(pr.fit_path_loss(np.asarray(db.rss_dbm, float), db.positions_m, options))
        log(f"  {floor} fold fit {time.perf_counter() - tic:.1f} s")
    if path is not None:
        tmp = Path(str(path) + ".tmp")
        with open(tmp, "wb") as fh:
            pickle.dump(models, fh)
        tmp.replace(path)
    return models


def evaluate_floor(floor: str, case: Dict[str, Any], models: List[pr.PathLossModel], grid, threads: int = 2,
                   miss_weight: float = 0.0, huber_sd: float = 0.0, cap_sd: float = 0.0) -> Dict[str, np.ndarray]:
    """errors[point key] (the floor's waypoints in case order), plus "wifi_knn"."""
    from indoorloc.experiments.wifi_sequence_study import TestWalk, _point_key, knn_errors  # noqa: F401
    from indoorloc.io import load_floor_plan
    from indoorloc.fusion.grid import GridTracker

    plan = load_floor_plan(case["geojson_path"], floors=[case["number"]], origin_lon_lat="outline_sw")
    base = ws.SequenceSettings()
    cells = pf.walkable_cells(GridTracker(plan, ws.grid_options(base)), 0)
    lls = []
    for fo, m in zip(case["folds"], models):
        mu = m.predict(cells)
        lls.append([pr.scan_log_likelihood(m, np.asarray(w["query_rss_dbm"], float), mu, miss_weight,
                                           huber_sd, cap_sd)
                    for w in fo["walks"]])
    out: Dict[str, List[np.ndarray]] = {"wifi_knn": [], "model_centre": []}
    for fo, ll_f in zip(case["folds"], lls):
        for w, ll in zip(fo["walks"], ll_f):
            from indoorloc.experiments.fusion_real_walk import _nearest_rows
            from indoorloc.fusion import wifi_fixes as wfx
            kf = w["knn_fixes"]
            if len(kf):
                est = _nearest_rows(w["waypoint_t_s"], kf.times_s, wfx.fix_centres(kf))
                out["wifi_knn"].append(np.hypot(*(est - w["waypoint_xy_m"]).T))
            else:
                out["wifi_knn"].append(np.full(w["waypoint_t_s"].size, np.nan))
            if ll.shape[0]:
                est = _nearest_rows(w["waypoint_t_s"], w["query_t_s"], cells[np.argmax(ll, axis=1)])
                out["model_centre"].append(np.hypot(*(est - w["waypoint_xy_m"]).T))
            else:
                out["model_centre"].append(np.full(w["waypoint_t_s"].size, np.nan))
    fix_names = [k for k in ("model_weight", "temperature", "k", "sd_m", "block_m", "gate_db") if k in grid]
    seq_names = [k for k in grid if k not in fix_names]
    for fvals in itertools.product(*(grid[k] for k in fix_names)):
        fp = dict(zip(fix_names, fvals))
        if fp["model_weight"] == 0 and (fp["temperature"] != grid["temperature"][0] or fp["k"] != grid["k"][0]
                                        or fp["sd_m"] != grid["sd_m"][0] or fp["block_m"] != grid["block_m"][0]
                                        or fp.get("gate_db", 0) != grid.get("gate_db", (0,))[0]):
            continue  # the kNN fixes alone do not depend on the model-fix settings
        ms = pf.ModelFixSettings(k=int(fp["k"]), temperature=float(fp["temperature"]), sd_m=float(fp["sd_m"]),
                                 block_m=float(fp["block_m"]))
        fixes = []
        for fo, ll_f in zip(case["folds"], lls):
            fl = []
            for w, ll in zip(fo["walks"], ll_f):
                kf = w["knn_fixes"]
                if fp["model_weight"] == 0 or len(kf) == 0:
                    fl.append(kf)
                    continue
                mf = pf.model_fixes(w["query_t_s"], ll, cells, ms, case["number"])
                if fp.get("gate_db", 0) > 0:
                    # The model fix counts where the kNN's best match is poor: g from 0 at gate_db to 1
                    # at gate_db + 20 dB of the kNN fix's best dissimilarity (read back from its sd).
                    fs = FixSettings()
                    d_min = (kf.sds_m[:, 0] - fs.sd_m) / fs.sd_per_db
                    mf = pf.gate_fixes(mf, np.clip((d_min - fp["gate_db"]) / 20.0, 0.0, 1.0))
                if fp["model_weight"] < 0:  # a product: the kNN fix times the mixture of weight |w| on the model
                    w_m = -fp["model_weight"]
                    fl.append(pf.stack_fixes(kf, mf if w_m == 1 else pf.mix_fixes(kf, mf, w_m)))
                else:
                    fl.append(mf if fp["model_weight"] == 1 else pf.mix_fixes(kf, mf, fp["model_weight"]))
            fixes.append(fl)
        for svals in itertools.product(*(grid[k] for k in seq_names)):
            sp = dict(zip(seq_names, svals))
            s = replace(base, **sp)
            errs = []
            for fo, fl in zip(case["folds"], fixes):
                tracker = ws.sequence_tracker(plan, s, fo["database"])

                def one(args):
                    w, f = args
                    tr = ws.track_fixes(tracker, f, 0.0, w["duration_s"], s)
                    return np.hypot(*(ws.at_times(tr, w["waypoint_t_s"]) - w["waypoint_xy_m"]).T)

                with ThreadPoolExecutor(max_workers=threads) as pool:
                    errs += list(pool.map(one, zip(fo["walks"], fl)))
            out[_point_key({**fp, **sp})] = errs
    return {k: np.concatenate(v) for k, v in out.items()}


def run(data_root: Path, floors: Sequence[str], seed: int, cache_dir: Optional[Path], grid,
        options: pr.PathLossOptions, miss_weight: float = 0.0, huber_sd: float = 0.0, threads: int = 2,
        log=print, cap_sd: float = 0.0) -> Dict[str, Any]:
    from indoorloc.experiments.wifi_propagation_cases import load_cases
    from indoorloc.experiments.wifi_sequence_study import _stats, coverage_split, lofo

    errors, coverage = {}, {}
    for f in floors:
        case = load_cases(data_root, [f], seed, cache_dir, log)[f]
        models = fitted_models(case, f, seed, cache_dir, options, log)
        tic = time.perf_counter()
        errors[f] = evaluate_floor(f, case, models, grid, threads, miss_weight, huber_sd, cap_sd)
        coverage[f] = np.concatenate([w["coverage_m"] for fo in case["folds"] for w in fo["walks"]])
        log(f"{f}: {time.perf_counter() - tic:.0f} s")
    lofo_errors = {f: {k: v for k, v in e.items() if k not in ("wifi_knn", "model_centre")} for f, e in errors.items()}
    choice = lofo(lofo_errors)
    best = choice["all_floor_choice"]
    per_floor = {}
    for f in floors:
        per_floor[f] = {"wifi_knn": _stats(errors[f]["wifi_knn"]), "model_centre": _stats(errors[f]["model_centre"]),
                        "all_floor_choice": _stats(errors[f][best]), "held_out": choice["held_out"][f],
                        "points": {k: float(np.nanmean(v)) for k, v in errors[f].items()},
                        "by_coverage": {k: coverage_split(errors[f][k], coverage[f])
                                        for k in ("wifi_knn", "model_centre", best)}}
    return {"seed": seed, "grid": {k: list(v) for k, v in grid.items()}, "options": repr(options),
            "miss_weight": miss_weight, "huber_sd": huber_sd, "cap_sd": cap_sd, "lofo": choice, "per_floor": per_floor}


def lofo_from_means(results: Sequence[Dict[str, Any]]) -> Dict[str, Any]:
    """Leave-one-floor-out over the union of several runs' grid points (their per-floor means
    times the floor's waypoint count: the pooled means of :func:`wifi_sequence_study.lofo`)."""
    floors = list(results[0]["per_floor"])
    n = np.array([results[0]["per_floor"][f]["all_floor_choice"]["n"] for f in floors], float)
    points: Dict[str, Dict[str, float]] = {}
    for r in results:
        for f in floors:
            for k, v in r["per_floor"][f]["points"].items():
                if k not in ("wifi_knn", "model_centre"):
                    points.setdefault(k, {})[f] = v
    keys = [k for k, v in points.items() if len(v) == len(floors)]
    means = np.array([[points[k][f] for f in floors] for k in keys])
    pooled = means @ n / n.sum()
    held = {}
    for j, f in enumerate(floors):
        o = np.arange(len(floors)) != j
        b = int(np.argmin(means[:, o] @ n[o] / n[o].sum()))
        held[f] = {"chosen": keys[b], "mean_m": float(means[b, j])}
    best = int(np.argmin(pooled))
    return {"points": len(keys), "all_floor_choice": keys[best],
            "all_floor_means": dict(zip(floors, means[best].tolist())), "all_floor_pooled_m": float(pooled[best]),
            "held_out": held, "held_out_pooled_m": float(sum(held[f]["mean_m"] * n[j] for j, f in enumerate(floors))
                                                      / n.sum())}


def markdown(r: Dict[str, Any]) -> str:
    from indoorloc.experiments.wifi_study_folds import lofo_markdown

    return lofo_markdown(r, f"Seed {r['seed']}", [("wifi_knn", "wifi_knn"), ("model argmax", "model_centre"),
                                                   ("all-floor choice", "all_floor_choice")])


def main(argv: Optional[Sequence[str]] = None) -> int:
    from indoorloc.experiments.fusion_real_settings import default_site_root
    from indoorloc.io.survey_layout import survey_floors
    from indoorloc.io.atomic_file import write_text_atomic

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data-root", type=Path, default=None)
    ap.add_argument("--floors", nargs="*", default=None)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--cache-dir", type=Path, default=None)
    ap.add_argument("--grid", default=None, help="JSON object overriding entries of GRID")
    ap.add_argument("--options", default=None, help="JSON object of PathLossOptions fields")
    ap.add_argument("--miss-weight", type=float, default=0.0)
    ap.add_argument("--huber-sd", type=float, default=0.0)
    ap.add_argument("--cap-sd", type=float, default=0.0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--merge", type=Path, nargs="+", default=None,
                    help="print the LOFO over the union of these --json outputs' grid points (no run)")
    a = ap.parse_args(argv)
    if a.merge:
        print(json.dumps(lofo_from_means([json.loads(Path(p).read_text()) for p in a.merge]), indent=1))
        return 0
    root = a.data_root or default_site_root()
    floors = [sf.name for sf in survey_floors(root, a.floors, argument="data_root")]
    grid = dict(GRID)
    if a.grid:
        grid.update({k: tuple(v) for k, v in json.loads(a.grid).items()})
    options = pr.PathLossOptions(**(json.loads(a.options) if a.options else {}))
    r = run(root, floors, a.seed, a.cache_dir, grid, options, a.miss_weight, a.huber_sd, a.threads,
            log=lambda m: print(m, file=sys.stderr), cap_sd=a.cap_sd)
    md = markdown(r)
    print(md)
    if a.json:
        write_text_atomic(a.json, json.dumps(r, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
