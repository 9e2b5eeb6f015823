"""The fusion tracker on real phone recordings: ``indoorloc fusion evaluate`` (issue 15).

Data: the Indoor Location Competition 2.0 site-2 walks (``shared/data/fusion/ilc2020_site2``,
docs/fusion_data.md) or any folder in that layout. Per floor, k-fold by walk (fixed seed): the
training walks give the handheld-PDR calibration (Weinberg K, the yaw offset between the phone's
rotation-vector heading and the floor frame, its spread over walks: ``indoorloc.pdr.handheld``) and the
crowdsourced signal map (``wifi_crowdsource``); each test walk is then tracked from its own IMU
and WiFi and the floor plan, and scored at its surveyed waypoints. Methods, side by side on the
same folds:

``wifi_knn``, ``wifi_model``
    WiFi only, from the scan nearest in time to each waypoint (readings older than the staleness
    limit dropped): kNN on the placed training scans with the union dissimilarity
    (``wifi_fixes``: the centre of the scan's fix) / the posterior mean of paper 004's model on
    the crowdsourced cell map.
``wifi_sequence``
    WiFi only, as a sequence: the walk's fixes and their times on the walkable grid with a
    random-walk motion, smoothed over the whole walk (:mod:`indoorloc.fusion.wifi_sequence`; no PDR).
``wifi_heading_sequence``
    WiFi only, the same fixes with a direction-persistent motion prior: the walker wanders or walks
    on in one of 8 directions (:mod:`indoorloc.fusion.wifi_heading_sequence`; no PDR).
``pdr_only``
    handheld PDR from the first waypoint, headings rotated by the training yaw offset.
``peer_costmin``
    the cost-minimisation post-processing of the 2021 competition's public solutions
    (:mod:`indoorloc.fusion.costmin_baseline`): the kNN WiFi fixes (``wifi_knn``) at every scan plus
    the PDR displacements by robust least squares with a per-walk rotation. Only when run from a source
    tree (the peer is not part of the package); otherwise absent from the table.
``fusion_unknown_start``, ``fusion_known_start``, ``fusion_smoother``
    the tracker (floor given) with the WiFi as fingerprint fixes (``wifi_fixes``: Gaussian
    mixtures with an outlier floor); the smoother runs from the unknown start and is the
    library's recommended default.
``fusion_no_walls``, ``fusion_no_wifi``, ``fusion_no_heading_offset``
    ablations of the default (unknown start + smoother): no floor plan; no WiFi (then the start
    must be known: it is); the heading offset fixed at the training offset (no offset state).

Floor identification: the default (unknown start + smoother) once more with the floor not given,
on the plan of every floor evaluated and fixes from the training scans of every floor (same
fold); its floor accuracy at the waypoints is ``floor_identification`` in the JSON.

Every setting is either fixed in advance (``RealSettings``, with the reason), fitted on the
training walks of the fold, or chosen by leave-one-floor-out cross-validation
(:func:`select_settings`, ``indoorloc fusion evaluate --select``); nothing is chosen on the test
walks. Estimates at step times are interpolated linearly to the waypoint times.

The code is split by concept: ``fusion_real_settings`` (methods, settings, records),
``fusion_real_walk`` (one walk scored by every method), ``fusion_real_folds`` (loading, the k-fold
and its training models), ``fusion_real_summary`` (JSON and Markdown), ``fusion_real_select``
(leave-one-floor-out choice); every name stays importable from this module.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from indoorloc import fusion
from indoorloc.fusion import site_model, wifi_fixes as wfx
from indoorloc.pdr import handheld as ph
from indoorloc.experiments.fusion_real_settings import (  # noqa: F401  (re-exported)
    COVARIANCE_METHODS, FLOORS, METHODS, SELECT_OBJECTIVE, FloorData, FoldModels, RealSettings, WalkScore,
    default_site_root)
from indoorloc.io.survey_layout import floor_number  # noqa: F401  (re-exported)
from indoorloc.experiments.fusion_real_walk import (  # noqa: F401  (re-exported)
    _TRACKERS, _TRACKERS_LOCK, _grid_options, _grid_tracker, _identification_options, _interp_track, _nearest_rows,
    _score_walk, _score_walk_grid, _walkable_start, _wrap, heading_residual_rad, replace_options)
from indoorloc.experiments.fusion_real_folds import (  # noqa: F401  (re-exported)
    _all_floor_plan, _fold_models, _folds, _peer, evaluate_floors, load_floor, load_site, site_floors,
    survey_floor_data)
from indoorloc.experiments.fusion_real_summary import (  # noqa: F401  (re-exported)
    COVERAGE_CLASSES, TIME_BINS_S, _extra_stats, _stats, markdown, summarize)
from indoorloc.experiments.fusion_real_select import (  # noqa: F401  (re-exported)
    SELECT_GRID, SELECT_POINT_ESTIMATES, _KNOWN_START_FIELDS, _with, lofo_from_stats, select_markdown,
    select_settings)


def evaluate_folds(data_root: Optional[Path], floors: Sequence[str], settings: RealSettings,
                   folds: Optional[Sequence[int]] = None, progress=None) -> List[WalkScore]:
    """The walk scores of the given folds (all by default): what one process or one Dask task does."""
    _, data = load_site(data_root, floors)
    all_plan = _all_floor_plan(data) if settings.floor_identification and len(data) > 1 else None
    return evaluate_floors(data, settings, _peer(), progress, METHODS, all_plan, folds)


def fold_task(params: Dict[str, Any], seed: int, data_root: str, floors: List[str],
              settings: RealSettings) -> Dict[str, Any]:
    """The Dask task of ``evaluate(..., scheduler=...)``: the walk scores of fold ``params["fold"]``
    (the worker reads the site from ``data_root``)."""
    return {"scores": evaluate_folds(data_root, floors, settings, [int(params["fold"])])}


def evaluate(data_root: Optional[Path] = None, floors: Sequence[str] = FLOORS, settings: Optional[RealSettings] = None,
             progress=None, scheduler: Any = None) -> dict:
    """``indoorloc fusion evaluate``: every method on every floor; the JSON dict of :func:`summarize`.

    ``scheduler`` (a Dask scheduler address or ``distributed.Client``): one task per fold on the
    cluster, each worker reading the site from ``data_root`` (a path the workers see); the result
    equals the in-process one (the ``seconds`` fields aside)."""
    settings = settings or RealSettings()
    tic = time.perf_counter()
    root, data = load_site(data_root, floors)
    floors = [fl.name for fl in data]
    if scheduler is None:
        all_plan = _all_floor_plan(data) if settings.floor_identification and len(data) > 1 else None
        scores = evaluate_floors(data, settings, _peer(), progress, METHODS, all_plan, None)
    else:
        from indoorloc import sweep

        grid = {"fold": list(range(settings.folds if settings.folds > 0 else max(len(fl.walks) for fl in data)))}
        result = sweep.run_sweep(fold_task, grid, scheduler=scheduler,
                                 shared={"data_root": str(root), "floors": list(floors), "settings": settings},
                                 progress=progress)
        if result.failed:
            raise RuntimeError(f"indoorloc: fold {result.failed[0]['params']['fold']} failed: {result.failed[0]['error']}")
        scores = [s for row in result.rows for s in row["scores"]]
    out = summarize(scores, settings, time.perf_counter() - tic)
    # What the loader skipped or dropped, per floor (docs/errors.md, "Loader rule").
    out["loader"] = {fl.name: fl.load_report for fl in data}
    return out


def walk_snapshot(data_root: Optional[Path], floor: str, walk_index: int = 0,
                  settings: Optional[RealSettings] = None) -> dict:
    """Everything :func:`indoorloc.plots.fusion_real_walk` draws for one walk, the walk tracked as
    a test walk of its own fold (models from the other folds' walks of its floor): the floor image
    and its extent [m], plan edges, surveyed waypoints, WiFi fix centres, PDR from the first
    waypoint, the smoothed track from the unknown start and its FFBSi trajectories."""
    settings = replace(settings or RealSettings(), floor_identification=False)
    _, (survey,) = site_floors(data_root, [floor])
    fl = survey_floor_data(survey)
    if not 0 <= walk_index < len(fl.walks):
        raise ValueError(f"indoorloc: argument 'walk_index': {walk_index} is not in [0, {len(fl.walks)})")
    k = settings.folds if settings.folds > 0 else len(fl.walks)
    fold_of = {fl.name: (_folds(len(fl.walks), k, settings.seed) + [np.zeros(0, int)] * k)[:k]}
    j = next(k for k, f in enumerate(fold_of[fl.name]) if walk_index in f)
    models = _fold_models([fl], fold_of, j, settings, None)[fl.name]
    walk = fl.walks[walk_index]
    wt = np.asarray(walk.waypoint_t_s, float)
    wxy = np.asarray(walk.waypoint_xy_m, float)
    fixes = wfx.fixes_for_walk(walk, models.database)
    steps = ph.rescale(fl.steps[walk_index], models.cal.options)
    pdr_steps = fusion.Steps.from_polar(steps.t_s, steps.length_m, steps.heading_rad + models.cal.yaw_offset_rad,
                                        settings.step_length_sd_fraction * steps.length_m, settings.step_heading_sd_rad)
    spread = max(models.cal.yaw_offset_spread_rad, 1e-3)
    if settings.engine == "grid":  # the default's engine; a grid has no trajectories to draw
        # The default as the site model tracks (its smoother's second pass included).
        base = _grid_options(settings, spread)
        second = (_grid_tracker(fl.plan, site_model.second_pass_options(base, settings.track_settings()), fl.name,
                                models.database) if settings.second_pass_start_sd_m > 0 else None)
        result = site_model.run_default(_grid_tracker(fl.plan, base, fl.name, models.database), pdr_steps, fixes,
                                        second_pass=second, floor=fl.number,
                                        median=settings.point_estimate == "median")
        if settings.point_estimate == "median":
            result["smoothed_m"], result["mean_m"] = result["smoothed_median_m"], result["median_m"]
        result["smoothed_trajectories_m"] = np.zeros((0, 2))
    else:
        options = settings.tracker_options(unknown_start_heading_sd_rad=spread, start_heading_offset_sd_rad=spread)
        result = fusion.track(pdr_steps, plan=fl.plan, options=options, fixes=fixes,
                              smoother=fusion.SmootherOptions(num_trajectories=settings.smoother_trajectories,
                                                              max_particles=settings.smoother_max_particles,
                                                              seed=settings.seed))
    t_pdr = np.r_[wt[0], steps.t_s]
    pdr = ph.pdr_track(steps, wxy[0], t_pdr, yaw_offset_rad=models.cal.yaw_offset_rad)
    info = survey.open()
    extent = (0.0, info.width_m, 0.0, info.height_m) if info.width_m and info.height_m else None
    return {"floor": floor, "walk": walk.walk_id, "image_path": str(info.image_path) if info.image_path else None,
            "extent_m": extent, "edges_m": np.asarray(fl.plan.edges(0)), "waypoints_m": wxy, "waypoint_t_s": wt - wt[0],
            "fix_centres_m": wfx.fix_centres(fixes) if len(fixes) else np.zeros((0, 2)), "pdr_m": pdr,
            "smoothed_m": np.asarray(result["smoothed_m"]), "filter_m": np.asarray(result["mean_m"]),
            "trajectories_m": np.asarray(result["smoothed_trajectories_m"]),
            # For the track viewer: the track's times (since the first waypoint, as waypoint_t_s) [s],
            # its smoothed covariances (xx, xy, yy) [m²] (None where the engine gives none) and the fixes' times.
            "track_t_s": np.asarray(pdr_steps.times_s, float) - wt[0],
            "smoothed_covariance_m2": (np.asarray(result["smoothed_covariance_m2"])
                                       if "smoothed_covariance_m2" in result else None),
            "fix_t_s": (np.asarray(fixes.times_s, float) - wt[0]) if len(fixes) else np.zeros(0),
            "errors": {"pdr_only": np.hypot(*(ph.pdr_track(steps, wxy[0], wt, yaw_offset_rad=models.cal.yaw_offset_rad) - wxy).T),
                       "fusion_smoother": np.hypot(*(_interp_track(wt, pdr_steps.times_s, result["smoothed_m"]) - wxy).T),
                       "wifi_knn": np.hypot(*(_nearest_rows(wt, fixes.times_s, wfx.fix_centres(fixes)) - wxy).T)
                       if len(fixes) else np.full(wt.size, np.nan)}}
