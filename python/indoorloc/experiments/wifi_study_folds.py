"""The folds of ``indoorloc fusion evaluate`` as the WiFi studies see them
(:mod:`~indoorloc.experiments.wifi_sequence_study`,
:mod:`~indoorloc.experiments.wifi_propagation_study`): per floor and fold the training fingerprint
database and the test walks with their waypoints and survey coverage; and the studies' common
Markdown table of a leave-one-floor-out choice."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Sequence

import numpy as np


@dataclass
class FoldWalk:
    """One test walk of a fold: the walk, its waypoints' times [s] (W,) and positions [m] (W, 2),
    and their distance to the nearest training reference of the floor [m] (W,)."""

    walk: Any
    waypoint_t_s: np.ndarray
    waypoint_xy_m: np.ndarray
    coverage_m: np.ndarray


@dataclass
class Fold:
    """Fold ``index`` of a floor: its training ``database`` (``wifi_fixes.FingerprintDatabase``)
    and its test walks."""

    index: int
    database: Any
    walks: List[FoldWalk]


def floor_folds(data_root: Path, floor: str, seed: int) -> Iterator[tuple]:
    """Yields ``(floor_data, fold)`` for each fold of ``floor``, as ``fusion evaluate --seed seed``
    splits its walks (4-fold by walk, the default settings' fixes)."""
    from indoorloc.experiments.fusion_real_folds import WalkTrainingCache, _folds, load_floor
    from indoorloc.experiments.fusion_real_settings import RealSettings
    from indoorloc.experiments.fusion_real_walk import survey_coverage_m

    settings = RealSettings(seed=seed)
    fl = load_floor(data_root, floor)
    cache = WalkTrainingCache()
    for j, test_idx in enumerate(_folds(len(fl.walks), settings.folds, seed)):
        test = set(test_idx.tolist())
        db = cache.database([(fl, i) for i in range(len(fl.walks)) if i not in test], settings.fixes)
        train_xy = db.positions_m[db.floors == fl.number]
        walks = []
        for i in test_idx:
            w = fl.walks[i]
            wt, wxy = np.asarray(w.waypoint_t_s, float), np.asarray(w.waypoint_xy_m, float)
            walks.append(FoldWalk(w, wt, wxy, survey_coverage_m(wxy, train_xy)))
        yield fl, Fold(j, db, walks)


def floor_cases(data_root: Path, floors: Sequence[str], seed: int, fold_record: Callable[[Any, Fold], dict],
                log=print) -> Dict[str, Any]:
    """Per floor ``{"geojson_path", "number", "folds": [fold_record(floor_data, fold) per fold]}``
    over the folds of :func:`floor_folds`; ``log`` gets a line per floor (walks, seconds)."""
    out = {}
    for name in floors:
        tic = time.perf_counter()
        folds = []
        for fl, fold in floor_folds(data_root, name, seed):
            folds.append(fold_record(fl, fold))
        out[name] = {"geojson_path": str(fl.geojson_path), "number": fl.number, "folds": folds}
        log(f"{name}: {len(fl.walks)} walks, {time.perf_counter() - tic:.0f} s")
    return out


def lofo_markdown(r: Dict[str, Any], title: str, columns: Sequence[tuple],
                  held_out_head: str = "held out (LOFO)") -> str:
    """The table of a leave-one-floor-out study result ``r`` (``seed``, ``lofo`` with
    ``all_floor_choice`` and ``held_out_pooled``, ``per_floor``: floor -> column key -> mean /
    median / p90 [m]): a row per floor with the ``columns`` (header, key) given, then the held-out
    figure and the choice made for that floor; last the pooled held-out figure."""
    fmt = lambda s: f"{s['mean_m']:.2f} / {s['median_m']:.2f} / {s['p90_m']:.1f}"  # noqa: E731
    heads = [h for h, _ in columns]
    lines = [f"{title}; all-floor choice: `{r['lofo']['all_floor_choice']}`", "",
             "| floor | " + " | ".join(heads) + f" | {held_out_head} | LOFO choice |",
             "|---|" + "---|" * (len(heads) + 2)]
    for f, p in r["per_floor"].items():
        cells = " | ".join(fmt(p[k]) for _, k in columns)
        lines.append(f"| {f} | {cells} | {fmt(p['held_out'])} | `{p['held_out']['chosen']}` |")
    lines.append("| pooled (held out) |" + " |" * len(heads) + f" {fmt(r['lofo']['held_out_pooled'])} | |")
    return "\n".join(lines) + "\n"
