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
from indoorloc.io import load_floor_plan
from indoorloc.io.survey_layout import SurveyFloor, survey_floors
from indoorloc.experiments.fusion_real_settings import (METHODS, FloorData, FoldModels, RealSettings, WalkScore,
                                                        default_site_root)
from indoorloc.experiments.fusion_real_walk import _score_walk


def _peer():
    """The cost-minimisation baseline (:mod:`indoorloc.fusion.costmin_baseline`)."""
    from indoorloc.fusion import costmin_baseline

    return costmin_baseline


def _folds(n: int, k: int, seed: int) -> List[np.ndarray]:
    perm = np.random.default_rng(seed).permutation(n)
    return [np.sort(perm[i::k]) for i in range(min(k, n))]



def load_floor(root: Path, name: str) -> FloorData:
    """Floor ``name`` of the site folder ``root`` (either competition layout,
    :func:`indoorloc.io.survey_layout.survey_floors`): see :func:`survey_floor_data`."""
    (survey,) = survey_floors(Path(root), [name], argument="data_root")
    return survey_floor_data(survey)


def survey_floor_data(survey: SurveyFloor) -> FloorData:
    """Walks, plan (origin at the outline's south-west corner, the floor frame) and detected steps."""
    floor = survey.open()
    number = survey.number
    # walks() reports and skips a walk it cannot read (docs/errors.md, "Loader rule"); what it
    # skipped or dropped goes into the evaluation's output (``loader``).
    walks = list(floor.walks())
    plan = load_floor_plan(floor.geojson_path, floors=[number], origin_lon_lat="outline_sw")
    outline = fusion.FloorPlan([fusion.FloorGeometry(number, list(plan.geometry(0).outlines), [], np.zeros((0, 4)))])
    report = floor.load_report()
    report.pop("walks_with_dropped_fields", None)
    return FloorData(survey.name, number, walks, plan, [ph.handheld_steps(w) for w in walks],
                     Path(floor.geojson_path), outline, report)


def _coverage_tree(database: wfx.FingerprintDatabase, floor: int):
    """A KD-tree of the floor's training scan positions (``survey_coverage_m``), None when empty."""
    from scipy.spatial import cKDTree

    xy = database.positions_m[database.floors == floor]
    return cKDTree(xy) if xy.size else None


class WalkTrainingCache:
    """What a training walk gives every fold it trains (its fingerprints placed by PDR, its WiFi
    readings placed for the crowdsourced map), computed once per walk instead of once per fold
    and database: a walk trains k - 1 folds of its floor's database, of the crowdsourced map and
    of the all-floor database. Values are those of ``wifi_fixes.build_database`` and
    ``crowdsourced_map.build_crowd_map`` (same functions, same arguments), so the models are the
    same bit for bit. Used from one thread (the one building the folds' models)."""

    def __init__(self) -> None:
        self._fingerprints: Dict[Tuple, object] = {}
        self._placed: Dict[Tuple, object] = {}
        self._heading_stencils: Dict[Tuple, object] = {}

    def fingerprints(self, fl: FloorData, i: int, settings: wfx.FixSettings):
        """``wifi_fixes.walk_fingerprints`` of walk i of the floor (None when none can be placed)."""
        key = (fl.name, i, repr(settings))
        if key not in self._fingerprints:
            self._fingerprints[key] = wfx.walk_fingerprints(fl.walks[i], settings, fl.steps[i])
        return self._fingerprints[key]

    def placed(self, fl: FloorData, i: int, settings: wc.CrowdMapSettings):
        """``crowdsourced_map.reading_positions`` of walk i of the floor."""
        key = (fl.name, i, repr(settings))
        if key not in self._placed:
            self._placed[key] = wc.reading_positions(fl.walks[i], settings)
        return self._placed[key]

    def heading(self, fl: FloorData, database: wfx.FingerprintDatabase, settings):
        """(grid, motion stencils) of ``wifi_heading_sequence`` on the floor: the grid anchored to the
        fold's survey positions, the stencils (which depend on the settings only) once per floor."""
        from indoorloc.fusion import wifi_heading_sequence as whs

        grid = whs.heading_grid(fl.plan, settings, database.positions_m[database.floors == fl.number])
        key = (fl.name, repr(settings))
        if key not in self._heading_stencils:
            self._heading_stencils[key] = whs.motion_stencils(settings)
        return grid, self._heading_stencils[key]

    def database(self, walks: Sequence[Tuple[FloorData, int]], settings: wfx.FixSettings) -> wfx.FingerprintDatabase:
        """``wifi_fixes.build_database`` of the walks (floor, index), each on its floor's number."""
        settings.validate()
        per_walk = []
        for j, (fl, i) in enumerate(walks):
            got = self.fingerprints(fl, i, settings)
            if got is not None:
                rss, xy, names, _ = got
                per_walk.append((rss, xy, names, np.full(xy.shape[0], fl.number), np.full(xy.shape[0], j)))
        return wfx.assemble_database(per_walk, settings)


def _propagation(fl: FloorData, database: wfx.FingerprintDatabase, settings: RealSettings):
    """(path-loss model, walkable 2 m cells, predictions) of the fold's training fingerprints
    when the propagation fixes are on (``RealSettings.propagation``), else None."""
    if settings.propagation == "off":
        return None
    from indoorloc.fusion import propagation_fixes, wifi_sequence
    from indoorloc.wifi import propagation

    own = database.floors == fl.number
    model = propagation.fit_path_loss(database.rss_dbm[own], database.positions_m[own],
                                      propagation.PathLossOptions(iterations=20))
    cells = propagation_fixes.walkable_cells(
        fusion.GridTracker(fl.plan, wifi_sequence.grid_options(wifi_sequence.SequenceSettings())), 0)
    return model, cells, model.predict(cells)


def _fold_models(floors: Sequence[FloorData], fold_of: Dict[str, List[np.ndarray]], j: int,
                 settings: RealSettings, all_plan, with_crowd_map: bool = True,
                 cache: Optional[WalkTrainingCache] = None, with_heading: bool = False) -> Dict[str, FoldModels]:
    """Fold j's training models of every floor (and the all-floor database when identifying
    floors); the crowdsourced cell map only ``with_crowd_map`` (the ``wifi_model`` method), the
    direction-persistent WiFi-only grid only ``with_heading`` (``wifi_heading_sequence``).
    ``cache``: the per-walk parts kept across folds (same models, computed once per walk)."""
    cache = cache or WalkTrainingCache()
    out: Dict[str, FoldModels] = {}
    all_walks: List[Tuple[FloorData, int]] = []
    for fl in floors:
        test = set(fold_of[fl.name][j].tolist())
        if not test and all_plan is None:  # nothing to score on this floor in this fold
            continue
        train_idx = [i for i in range(len(fl.walks)) if i not in test]
        train = [fl.walks[i] for i in train_idx]
        train_steps = [fl.steps[i] for i in train_idx]
        cal = site_model.calibrate_floor(train, train_steps)
        crowd = None
        if with_crowd_map:
            crowd_settings = wc.CrowdMapSettings()
            crowd = wc.build_crowd_map(train, crowd_settings, fl.number,
                                       placed=[cache.placed(fl, i, crowd_settings) for i in train_idx])
        # site_model.build_fingerprints of the training walks, from the cached per-walk fingerprints.
        database = cache.database([(fl, i) for i in train_idx], settings.fixes)
        crowd_grid = wifi.GridPosterior(crowd.model, settings.grid_spacing_m) if crowd is not None else None
        out[fl.name] = FoldModels(fl, cal, crowd, database, coverage_tree=_coverage_tree(database, fl.number),
                                  crowd_grid=crowd_grid, propagation=_propagation(fl, database, settings),
                                  heading=cache.heading(fl, database, settings.wifi_heading_sequence) if with_heading else None)
        all_walks += [(fl, i) for i in train_idx]
    if all_plan is not None:
        all_database = cache.database(all_walks, settings.fixes)
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
    cache = WalkTrainingCache()
    # Fold j's training models are built in this thread while earlier folds' walks are scored by the
    # pool (the models do not depend on the scheduling: the results are those of a serial run).
    with ThreadPoolExecutor(max_workers=max(1, settings.threads)) as pool:
        running: List = []
        for j in range(n_folds) if only_folds is None else only_folds:
            jobs_idx = [(fl, i) for fl in floors for i in fold_of[fl.name][j]]
            if not jobs_idx:
                continue
            # --select passes one cache for all its grid points (the models do not depend on the
            # tracker's settings); it lives as long as that call, keyed by fold, fixes and map use.
            with_heading = "wifi_heading_sequence" in methods
            key = (j, repr(settings.fixes), all_plan is None, "wifi_model" in methods,
                   repr(settings.wifi_heading_sequence) if with_heading else None)
            models = None if models_cache is None else models_cache.get(key)
            if models is None:
                models = _fold_models(floors, fold_of, j, settings, all_plan, "wifi_model" in methods, cache,
                                      with_heading)
                if models_cache is not None:
                    models_cache[key] = models
            # Fold j's walks queue behind fold j - 1's (the pool runs them in submission order), so
            # the workers never wait at a fold boundary; the scores are collected in that order.
            submitted = [pool.submit(_score_walk, fl.walks[i], fl.steps[i], models[fl.name], settings, peer, methods)
                         for fl, i in jobs_idx]
            _collect(running, scores, progress)
            running = submitted
        _collect(running, scores, progress)
    return scores


def _collect(futures: List, scores: List[WalkScore], progress) -> None:
    """The futures' walk scores appended in submission order."""
    for f in futures:
        scores.append(f.result())
        if progress:
            progress()


def site_floors(data_root: Optional[Path], floors: Sequence[str]) -> Tuple[Path, List[SurveyFloor]]:
    """The site folder (default: the shared data) and its floors, found by
    :func:`indoorloc.io.survey_layout.survey_floors` (ILC 2020 or Kaggle 2021 layout): those
    named, in the order named, or every floor with walks and a plan in building order.

    Raises FileNotFoundError (``argument 'data_root'``) when the folder does not exist, and
    ValueError as ``survey_floors`` does (a named floor absent, without walks or plan; no floor)."""
    root = Path(data_root) if data_root else default_site_root()
    if not root.is_dir():
        raise FileNotFoundError(f"indoorloc: argument 'data_root': {root} is not a folder "
                                f"(a site's survey folder, ILC 2020 or Kaggle 2021 layout)")
    found = survey_floors(root, floors, argument="data_root")
    if floors:  # the order named (the all-floor database's row order follows it)
        found.sort(key=lambda sf: list(floors).index(sf.name))
    return root, found


def load_site(data_root: Optional[Path], floors: Sequence[str]) -> Tuple[Path, List[FloorData]]:
    """The site folder and its floors' data (:func:`site_floors`, :func:`survey_floor_data`)."""
    root, found = site_floors(data_root, floors)
    return root, [survey_floor_data(sf) for sf in found]


def _all_floor_plan(floors: Sequence[FloorData]):
    return load_floor_plan([fl.geojson_path for fl in floors], floors=[fl.number for fl in floors],
                           origin_lon_lat="outline_sw")
