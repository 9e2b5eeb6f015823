"""Leave-one-floor-out choice of the settings of ``indoorloc fusion evaluate``
(``--select``, :mod:`indoorloc.experiments.fusion_real`): every point of a grid scored on every
floor, each floor scored with the point chosen on the other floors."""

from __future__ import annotations

import itertools
import math
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Dict, Optional, Sequence, Tuple

import numpy as np

from indoorloc.experiments.fusion_real_settings import FLOORS, SELECT_OBJECTIVE, FoldModels, RealSettings
from indoorloc.experiments.fusion_real_folds import evaluate_floors, load_site
from indoorloc.experiments.fusion_real_summary import _stats

#: The grid of ``indoorloc fusion evaluate --select``: the settings the real data decides
#: (the rest are fixed in advance, RealSettings). Objective: the default method's mean error.
SELECT_GRID: Dict[str, Sequence[Any]] = {
    "grid.fix_tempering": (0.2, 0.4, 0.7, 1.0),
    "grid.fix_outlier_probability": (0.1, 0.3),
    "grid.wall_log_penalty": (-1.0, -3.0),
    "grid.fix_tempering_by_variance": (False, True),
}
#: Chosen with the grid without re-running it: every run keeps both point estimates.
SELECT_POINT_ESTIMATES = ("mean", "median")


#: Grid keys that the known-start filter has its own field for (it takes the grid point too).
_KNOWN_START_FIELDS = {"fixes.metric": "known_start_fix_metric", "fix_tempering": "known_start_fix_tempering",
                       "fix_outlier_probability": "known_start_fix_outlier_probability",
                       "grid.fix_tempering": "known_start_fix_tempering",
                       "grid.fix_outlier_probability": "known_start_fix_outlier_probability",
                       "grid.wall_log_penalty": "known_start_wall_log_penalty",
                       "grid.fix_tempering_by_variance": "known_start_fix_tempering_by_variance"}


def _with(settings: RealSettings, key: str, value: Any) -> RealSettings:
    if key in _KNOWN_START_FIELDS:
        settings = replace(settings, **{_KNOWN_START_FIELDS[key]: value})
    if key.startswith("fixes."):
        return replace(settings, fixes=replace(settings.fixes, **{key.split(".", 1)[1]: value}))
    if key.startswith("grid."):
        return replace(settings, grid_options=settings.grid_options.replace(**{key.split(".", 1)[1]: value}))
    return replace(settings, **{key: value})


def check_grid(grid: Dict[str, Sequence[Any]], base: RealSettings) -> None:
    """Raises ValueError naming ``grid`` for a key that is no setting (``fixes.X``, ``grid.X`` or
    a RealSettings field) or a value list that is empty or invalid for it."""
    for key, values in grid.items():
        if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or len(values) == 0:
            raise ValueError(f"indoorloc: argument 'grid': {key!r} needs a non-empty list of values, got {values!r}")
        for value in values:
            try:
                _with(base, key, value)
            except (TypeError, ValueError, AttributeError) as e:
                raise ValueError(f"indoorloc: argument 'grid': {key!r} = {value!r} is not a valid setting ({e})") from None


def lofo_from_stats(points: Sequence[dict], floors: Sequence[str], objective: str) -> dict:
    """Leave-one-floor-out choice for ``objective`` from the points' per-floor stats (pooled
    means weighted by waypoints): ``{"lofo": {floor: {"chosen", "stats"}}, "lofo_pooled_mean_m",
    "best_all"}``."""
    def pooled(p, names) -> float:
        n = sum(p["per_floor"][f][objective]["n_waypoints"] for f in names)
        return sum(p["per_floor"][f][objective]["mean_m"] * p["per_floor"][f][objective]["n_waypoints"]
                   for f in names) / n
    lofo, total, count = {}, 0.0, 0
    for held_out in floors:
        others = [f for f in floors if f != held_out] or [held_out]
        best = min(points, key=lambda p: pooled(p, others))
        st = best["per_floor"][held_out][objective]
        lofo[held_out] = {"chosen": best["values"], "stats": st}
        total += st["mean_m"] * st["n_waypoints"]
        count += st["n_waypoints"]
    return {"lofo": lofo, "lofo_pooled_mean_m": total / count,
            "best_all": min(points, key=lambda p: pooled(p, list(floors)))["values"]}


def select_settings(data_root: Optional[Path] = None, floors: Sequence[str] = FLOORS,
                    base: Optional[RealSettings] = None, grid: Optional[Dict[str, Sequence[Any]]] = None,
                    progress: Optional[Callable[[], None]] = None) -> dict:
    """Leave-one-floor-out choice of the settings in ``grid`` (default :data:`SELECT_GRID`).

    Every grid point is evaluated on every floor (the same k-fold by walk; the default method and
    the known-start filter only). For each floor, the point with the lowest mean error of
    :data:`SELECT_OBJECTIVE` over the *other* floors is chosen and scored on that floor: the
    ``lofo`` figures estimate what the choice gives on a floor it has not seen. ``best_all`` is
    the point chosen on all floors (the default for floors and buildings not evaluated here).
    The known-start filter's settings are chosen the same way on its own objective
    (``known_start``: :func:`lofo_from_stats` on ``fusion_known_start``).
    Returns ``{"grid", "points": [{"values", "per_floor": {floor: {method: stats}}}], "lofo":
    {floor: {"chosen", "stats"}}, "lofo_overall": stats, "best_all", "known_start"}``."""
    base = base or RealSettings()
    grid = grid or SELECT_GRID
    check_grid(grid, base)
    base = replace(base, floor_identification=False, score_both_point_estimates=True)
    _, data = load_site(data_root, floors)
    keys = list(grid)
    points = []
    models_cache: Dict[Tuple, Dict[str, FoldModels]] = {}  # the same folds for every grid point
    for values in itertools.product(*(grid[k] for k in keys)):
        settings = base
        for k, v in zip(keys, values):
            settings = _with(settings, k, v)
        scores = evaluate_floors(data, settings, None, progress, (SELECT_OBJECTIVE, "fusion_known_start"),
                                 models_cache=models_cache)
        estimates = SELECT_POINT_ESTIMATES if settings.engine == "grid" else (None,)
        for pe in estimates:
            key = SELECT_OBJECTIVE if pe is None else f"_alt/{SELECT_OBJECTIVE}/{pe}"
            per_floor = {fl.name: {SELECT_OBJECTIVE: _stats(np.concatenate([s.errors_m[key] for s in scores
                                                                            if s.floor == fl.name])),
                                   "fusion_known_start": _stats(np.concatenate([s.errors_m["fusion_known_start"]
                                                                                for s in scores if s.floor == fl.name]))}
                         for fl in data}
            errors = {fl.name: np.concatenate([s.errors_m[key] for s in scores if s.floor == fl.name]) for fl in data}
            point_values = dict(zip(keys, [None if isinstance(v, float) and math.isinf(v) else v for v in values]))
            if pe is not None:
                point_values["point_estimate"] = pe
            points.append({"values": point_values, "per_floor": per_floor, "_errors": errors})

    def pooled_mean(point, names) -> float:
        return float(np.mean(np.concatenate([point["_errors"][n] for n in names])))

    lofo, held_out = {}, []
    names = [fl.name for fl in data]
    if len(names) < 2:
        # Nothing to hold out: the choice is made and scored on the same floor. Said in the result
        # ("held_out": false) and its Markdown, so the figure is not read as a held-out one.
        warnings.warn(f"indoorloc: --select on one floor ({names[0]}): no floor can be held out, the figures are "
                      "in-sample (choose settings over two floors or more)", UserWarning, stacklevel=2)
    for name in names:
        others = [n for n in names if n != name] or [name]
        best = min(points, key=lambda p: pooled_mean(p, others))
        lofo[name] = {"chosen": best["values"], "stats": _stats(best["_errors"][name])}
        held_out.append(best["_errors"][name])
    best_all = min(points, key=lambda p: pooled_mean(p, names))
    for p in points:
        p.pop("_errors")
    grid_out = {k: [None if isinstance(v, float) and math.isinf(v) else v for v in vs] for k, vs in grid.items()}
    if base.engine == "grid":
        grid_out["point_estimate"] = list(SELECT_POINT_ESTIMATES)
    return {"grid": grid_out, "held_out": len(names) > 1,
            "objective": SELECT_OBJECTIVE, "points": points, "lofo": lofo,
            "lofo_overall": _stats(np.concatenate(held_out)), "best_all": best_all["values"],
            "known_start": lofo_from_stats(points, names, "fusion_known_start")}


def select_markdown(result: dict) -> str:
    keys = list(result["grid"])
    floors = list(result["lofo"])
    lines = ["| " + " | ".join(keys) + " | " + " | ".join(f"{f} mean [m]" for f in floors) + " |",
             "|" + "---|" * (len(keys) + len(floors))]
    for p in result["points"]:
        cells = [str(p["values"][k]) for k in keys]
        cells += [f"{p['per_floor'][f][result['objective']]['mean_m']:.2f}" for f in floors]
        lines.append("| " + " | ".join(cells) + " |")
    if result.get("held_out", True):
        title, pooled = f"Leave-one-floor-out ({result['objective']}, settings chosen on the other floors):", "Held-out floors pooled"
    else:
        title = (f"IN SAMPLE, not held out ({result['objective']}; one floor: the settings are chosen and scored on "
                 "the same walks, a training figure):")
        pooled = "In sample (not held out)"
    lines += ["", title, "",
              "| held-out floor | chosen | mean [m] | median [m] | p90 [m] |", "|---|---|---|---|---|"]
    for f, r in result["lofo"].items():
        st = r["stats"]
        lines.append(f"| {f} | {r['chosen']} | {st['mean_m']:.2f} | {st['median_m']:.2f} | {st['p90_m']:.2f} |")
    o = result["lofo_overall"]
    lines += ["", f"{pooled}: mean {o['mean_m']:.2f} m, median {o['median_m']:.2f} m, p90 {o['p90_m']:.2f} m "
              f"({o['n_waypoints']} waypoints). Chosen on all floors: {result['best_all']}."]
    ks = result.get("known_start")
    if ks:
        lines += ["", ("Leave-one-floor-out" if result.get("held_out", True) else "IN SAMPLE, not held out,")
                  + " for the known-start filter (fusion_known_start):", "",
                  "| held-out floor | chosen | mean [m] | median [m] | p90 [m] |", "|---|---|---|---|---|"]
        for f, r in ks["lofo"].items():
            st = r["stats"]
            lines.append(f"| {f} | {r['chosen']} | {st['mean_m']:.2f} | {st['median_m']:.2f} | {st['p90_m']:.2f} |")
        lines += ["", f"{pooled}: mean {ks['lofo_pooled_mean_m']:.2f} m. Chosen on all floors: "
                  f"{ks['best_all']}."]
    return "\n".join(lines)
