"""The k-fold by walk of ``indoorloc fusion evaluate`` (:mod:`indoorloc.experiments.fusion_real`):
loading a site's floors, each fold's training models (PDR calibration, crowdsourced map,
fingerprint database, the all-floor database of floor identification) and every test walk
scored with the models of its fold."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc import fusion, wifi
from indoorloc.fusion import crowdsourced_map as wc, wifi_fixes as wfx
from indoorloc.fusion import site_model
from indoorloc.pdr import handheld as ph
from indoorloc.io import ilc_floor_names, load_floor_plan, read_ilc_floor
from indoorloc.experiments.fusion_real_settings import (METHODS, FloorData, FoldModels, RealSettings, WalkScore,
                                                        default_site_root, floor_number)
from indoorloc.experiments.fusion_real_walk import _score_walk


def _peer():
    """The cost-minimisation baseline (:mod:`indoorloc.fusion.costmin_baseline`)."""
    from indoorloc.fusion import costmin_baseline

    return costmin_baseline


def _folds(n: int, k: int, seed: int) -> List[np.ndarray]:
    perm = np.random.default_rng(seed).permutation(n)
    return [np.sort(perm[i::k]) for i in range(min(k, n))]



def load_floor(root: Path, name: str) -> FloorData:
    """Walks, plan (origin at the outline's south-west corner, the floor frame) and detected steps."""
    floor = read_ilc_floor(Path(root) / name)
    number = floor_number(name)
    # walks() reports and skips a walk it cannot read (docs/errors.md, "Loader rule"); what it
    # skipped or dropped goes into the evaluation's output (``loader``).
    walks = list(floor.walks())
    plan = load_floor_plan(floor.geojson_path, floors=[number], origin_lon_lat="outline_sw")
    outline = fusion.FloorPlan([fusion.FloorGeometry(number, list(plan.geometry(0).outlines), [], np.zeros((0, 4)))])
    report = floor.load_report()
    report.pop("walks_with_dropped_fields", None)
    return FloorData(name, number, walks, plan, [ph.handheld_steps(w) for w in walks], Path(floor.geojson_path),
                     outline, report)


def _coverage_tree(database: wfx.FingerprintDatabase, floor: int):
    """A KD-tree of the floor's training scan positions (``survey_coverage_m``), None when empty."""
    from scipy.spatial import cKDTree

    xy = database.positions_m[database.floors == floor]
    return cKDTree(xy) if xy.size else None


def _fold_models(floors: Sequence[FloorData], fold_of: Dict[str, List[np.ndarray]], j: int,
                 settings: RealSettings, all_plan, with_crowd_map: bool = True) -> Dict[str, FoldModels]:
    """Fold j's training models of every floor (and the all-floor database when identifying
    floors); the crowdsourced cell map only ``with_crowd_map`` (the ``wifi_model`` method)."""
    out: Dict[str, FoldModels] = {}
    all_walks, all_steps, all_numbers = [], [], []
    for fl in floors:
        test = set(fold_of[fl.name][j].tolist())
        if not test and all_plan is None:  # nothing to score on this floor in this fold
            continue
        train = [w for i, w in enumerate(fl.walks) if i not in test]
        train_steps = [s for i, s in enumerate(fl.steps) if i not in test]
        cal = site_model.calibrate_floor(train, train_steps)
        crowd = wc.build_crowd_map(train, wc.CrowdMapSettings(), fl.number) if with_crowd_map else None
        database = site_model.build_fingerprints(train, train_steps, fl.number, settings.fixes)
        crowd_grid = wifi.GridPosterior(crowd.model, settings.grid_spacing_m) if crowd is not None else None
        out[fl.name] = FoldModels(fl, cal, crowd, database, coverage_tree=_coverage_tree(database, fl.number),
                                  crowd_grid=crowd_grid)
        all_walks += train
        all_steps += train_steps
        all_numbers += [fl.number] * len(train)
    if all_plan is not None:
        all_database = wfx.build_database(all_walks, settings.fixes, all_steps, floors=all_numbers)
        all_rates = site_model.ap_floor_rates(all_database, list(all_plan.floors), settings.track_settings())
        all_cals = [out[fl.name].cal for fl in floors]
        for m in out.values():
            m.all_plan, m.all_database, m.all_ap_rates = all_plan, all_database, all_rates
            m.all_calibrations = all_cals
    return out


def evaluate_floors(floors: Sequence[FloorData], settings: RealSettings, peer=None, progress=None,
                    methods: Sequence[str] = METHODS, all_plan=None,
                    only_folds: Optional[Sequence[int]] = None,
                    models_cache: Optional[Dict[Tuple, Dict[str, FoldModels]]] = None) -> List[WalkScore]:
    """Every method on every walk of the floors, k-fold by walk within each floor (fold j of
    every floor shares the all-floor database of floor identification); ``only_folds``: score
    the test walks of these folds only (one Dask task per fold)."""
    # Fold lists padded with empty folds where a floor has fewer walks than folds; folds <= 0:
    # leave one walk out (as many folds as the floor has walks).
    n_folds = settings.folds if settings.folds > 0 else max(len(fl.walks) for fl in floors)
    fold_of = {fl.name: (_folds(len(fl.walks), n_folds, settings.seed) + [np.zeros(0, int)] * n_folds)[:n_folds]
               for fl in floors}
    scores: List[WalkScore] = []
    # Fold j's training models are built in this thread while fold j - 1's walks are scored by the
    # pool (the models do not depend on the scheduling: the results are those of a serial run).
    with ThreadPoolExecutor(max_workers=max(1, settings.threads)) as pool:
        running: List = []
        for j in range(n_folds) if only_folds is None else only_folds:
            jobs_idx = [(fl, i) for fl in floors for i in fold_of[fl.name][j]]
            if not jobs_idx:
                continue
            # --select passes one cache for all its grid points (the models do not depend on the
            # tracker's settings); it lives as long as that call, keyed by fold, fixes and map use.
            key = (j, repr(settings.fixes), all_plan is None, "wifi_model" in methods)
            models = None if models_cache is None else models_cache.get(key)
            if models is None:
                models = _fold_models(floors, fold_of, j, settings, all_plan, "wifi_model" in methods)
                if models_cache is not None:
                    models_cache[key] = models
            _collect(running, scores, progress)
            running = [pool.submit(_score_walk, fl.walks[i], fl.steps[i], models[fl.name], settings, peer, methods)
                       for fl, i in jobs_idx]
        _collect(running, scores, progress)
    return scores


def _collect(futures: List, scores: List[WalkScore], progress) -> None:
    """The futures' walk scores appended in submission order."""
    for f in futures:
        scores.append(f.result())
        if progress:
            progress()


def load_site(data_root: Optional[Path], floors: Sequence[str]) -> Tuple[Path, List[FloorData]]:
    """The site folder (default: the shared data) and its floors; clear errors for a missing folder."""
    root = Path(data_root) if data_root else default_site_root()
    if not root.is_dir():
        raise FileNotFoundError(f"indoorloc: argument 'data_root': {root} is not a folder of ILC floors")
    floors = floors or ilc_floor_names(root, with_plan=True, argument="data_root")
    for name in floors:
        if not (root / name).is_dir():
            raise FileNotFoundError(f"indoorloc: argument 'floors': {root / name} is not a floor folder")
    return root, [load_floor(root, name) for name in floors]


def _all_floor_plan(floors: Sequence[FloorData]):
    return load_floor_plan([fl.geojson_path for fl in floors], floors=[fl.number for fl in floors],
                           origin_lon_lat="outline_sw")
