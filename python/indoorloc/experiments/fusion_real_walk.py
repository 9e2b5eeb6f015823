"""One test walk scored by every method of ``indoorloc fusion evaluate``
(:mod:`indoorloc.experiments.fusion_real`): WiFi only, PDR, the peer, the trackers of both
engines and their ablations, and floor identification; each scored at the walk's waypoints."""

from __future__ import annotations

import math
import threading
import time
from dataclasses import replace
from typing import Any, Dict, Sequence, Tuple

import numpy as np

from indoorloc import fusion, wifi
from indoorloc.fusion import crowdsourced_map as wc, wifi_fixes as wfx
from indoorloc.fusion import live, site_model, wifi_heading_sequence, wifi_sequence
from indoorloc.pdr import handheld as ph
from indoorloc.experiments.fusion_real_settings import COVARIANCE_METHODS, FoldModels, RealSettings, WalkScore


def _nearest_rows(times_s: np.ndarray, row_t: np.ndarray, rows: np.ndarray) -> np.ndarray:
    idx = np.clip(np.searchsorted(row_t, times_s), 0, len(row_t) - 1)
    prev = np.clip(idx - 1, 0, len(row_t) - 1)
    use_prev = np.abs(row_t[prev] - times_s) < np.abs(row_t[idx] - times_s)
    return rows[np.where(use_prev, prev, idx)]


def _interp_track(t_query: np.ndarray, t_steps: np.ndarray, xy: np.ndarray) -> np.ndarray:
    if t_steps.size == 0:
        return np.full((t_query.size, 2), np.nan)
    return np.stack([np.interp(t_query, t_steps, xy[:, 0]), np.interp(t_query, t_steps, xy[:, 1])], axis=1)


def _walkable_start(plan, xy: np.ndarray, floor_index: int = 0) -> np.ndarray:
    """The surveyed start, or with hard walls the nearest walkable point on rings around it
    (a few starts lie inside a shop polygon; the tracker refuses those with hard walls)."""
    if plan.is_walkable(np.asarray(xy, float)[None, :], floor_index)[0]:
        return np.asarray(xy, float)
    angles = np.linspace(0.0, 2.0 * np.pi, 32, endpoint=False)
    for r in np.arange(0.25, 30.0, 0.25):
        ring = np.asarray(xy, float) + r * np.c_[np.cos(angles), np.sin(angles)]
        ok = plan.is_walkable(ring, floor_index)
        if ok.any():
            return ring[np.flatnonzero(ok)[0]]
    return np.asarray(xy, float)


def survey_coverage_m(waypoints_xy_m: np.ndarray, train_xy_m: np.ndarray, tree=None) -> np.ndarray:
    """Distance [m] from each waypoint (W, 2) to the nearest training scan position (N, 2), N > 0.

    With ``tree`` (a ``scipy.spatial.cKDTree`` of ``train_xy_m``, built once per fold) only the
    scans within the tree's nearest distance (plus a rounding margin) are measured, by the same
    formula as the brute-force minimum over all N, so the values equal it bit for bit."""
    wxy = np.asarray(waypoints_xy_m, float)
    if tree is None:
        return np.sqrt(((wxy[:, None, :] - train_xy_m[None, :, :]) ** 2).sum(axis=2)).min(axis=1)
    d_tree, _ = tree.query(wxy, k=1)
    out = np.empty(wxy.shape[0])
    for i, near in enumerate(tree.query_ball_point(wxy, d_tree * (1.0 + 1e-9) + 1e-9)):
        cand = train_xy_m[np.asarray(near, dtype=np.intp)]
        out[i] = np.sqrt(((wxy[i][None, None, :] - cand[None, :, :]) ** 2).sum(axis=2)).min()
    return out


def replace_options(options: fusion.TrackerOptions, **changes) -> fusion.TrackerOptions:
    """A copy of TrackerOptions with some fields changed (its bound ``replace``, which validates)."""
    return options.replace(**changes)


def _with_propagation(walk, knn_fixes, models: FoldModels, settings: RealSettings):
    """The kNN fixes with the propagation-model fixes (``RealSettings.propagation``)."""
    if settings.propagation == "off" or models.propagation is None or len(knn_fixes) == 0:
        return knn_fixes
    if settings.propagation not in ("product", "mixture"):
        raise ValueError(f"indoorloc: RealSettings.propagation: expected 'off', 'product' or 'mixture', "
                         f"got {settings.propagation!r}")
    from indoorloc.fusion import propagation_fixes
    from indoorloc.wifi import propagation

    model, cells, mu = models.propagation
    t, q = wfx.walk_queries(walk, models.database)
    ll = propagation.scan_log_likelihood(model, q, mu, huber_sd=settings.propagation_huber_sd)
    mf = propagation_fixes.model_fixes(t, ll, cells, settings.propagation_fixes or propagation_fixes.ModelFixSettings(),
                                       models.floor.number)
    if settings.propagation == "product":
        return propagation_fixes.stack_fixes(knn_fixes, mf)
    return propagation_fixes.mix_fixes(knn_fixes, mf, settings.propagation_weight)


def _score_walk(walk, steps_raw: ph.HandheldSteps, models: FoldModels, settings: RealSettings, peer,
                methods: Sequence[str]) -> WalkScore:
    fl = models.floor
    wt = np.asarray(walk.waypoint_t_s, float)
    wxy = np.asarray(walk.waypoint_xy_m, float)
    score = WalkScore(fl.name, walk.walk_id, wt - wt[0], waypoint_t0=float(wt[0]), waypoint_xy_m=wxy)
    train_xy = models.database.positions_m[models.database.floors == fl.number]
    if train_xy.size:
        score.coverage_m = survey_coverage_m(wxy, train_xy, models.coverage_tree)
    err = score.errors_m
    want = set(methods)

    def put(name: str, est: np.ndarray) -> None:
        err[name] = np.hypot(*(np.asarray(est) - wxy).T)

    knn_fixes = wfx.fixes_for_walk(walk, models.database)
    centres = wfx.fix_centres(knn_fixes) if len(knn_fixes) else np.zeros((0, 2))
    fixes = _with_propagation(walk, knn_fixes, models, settings)
    # WiFi only: the scan nearest in time to each waypoint.
    if len(fixes) and "wifi_knn" in want:
        put("wifi_knn", _nearest_rows(wt, knn_fixes.times_s, centres))
    if len(fixes) and "wifi_sequence" in want:
        # WiFi only, as a sequence: the walk's fixes (and their times) on the walkable grid with a
        # random-walk motion, forward-backward over the whole walk; no PDR, no IMU.
        tic = time.perf_counter()
        seq = settings.wifi_sequence
        tracker = _grid_tracker(fl.plan, wifi_sequence.grid_options(seq, settings.grid_options),
                                fl.name, models.database)
        track = wifi_sequence.track_fixes(tracker, fixes, 0.0, float(walk.duration_s), seq)
        put("wifi_sequence", wifi_sequence.at_times(track, wt))
        score.seconds["wifi_sequence"] = time.perf_counter() - tic
    if len(fixes) and "wifi_heading_sequence" in want and models.heading is not None:
        # WiFi only, the same fixes with a direction-persistent motion prior (wander or walk on in
        # one of 8 directions); no PDR, no IMU.
        tic = time.perf_counter()
        grid, stencils = models.heading
        track = wifi_heading_sequence.track_fixes(grid, fixes, 0.0, float(walk.duration_s),
                                                  settings.wifi_heading_sequence, stencils)
        put("wifi_heading_sequence", wifi_sequence.at_times(track, wt))
        score.seconds["wifi_heading_sequence"] = time.perf_counter() - tic
    if "wifi_model" in want:
        scan_t, rss_fresh, _ = wc.scan_matrix(walk, models.crowd.bssids, dedup=False, max_age_s=settings.wifi_max_age_s)
        if scan_t.size:
            q = wc.prepare(_nearest_rows(wt, scan_t, rss_fresh), models.crowd.settings.not_heard_dbm)
            grid = (models.crowd_grid if models.crowd_grid is not None
                    else wifi.GridPosterior(models.crowd.model, settings.grid_spacing_m))
            put("wifi_model", np.asarray(grid.locate(q)["positions_m"]))
    # PDR: calibrated steps, headings rotated into the floor frame by the training yaw offset.
    cal = models.cal
    steps = ph.rescale(steps_raw, cal.options)
    pdr_steps = site_model.tracker_steps(steps_raw, cal, settings.track_settings())
    if "pdr_only" in want:
        put("pdr_only", ph.pdr_track(steps, wxy[0], wt, yaw_offset_rad=cal.yaw_offset_rad))
    if peer is not None and "peer_costmin" in want and len(fixes) and len(pdr_steps):
        tic = time.perf_counter()
        # Positions before the first step and after each step: M + 1 times, M displacements.
        t_nodes = np.r_[min(float(wt[0]), float(pdr_steps.times_s[0]) - 0.5), pdr_steps.times_s]
        track = peer.costmin_track(t_nodes, pdr_steps.displacements_m, knn_fixes.times_s, centres)
        score.seconds["peer_costmin"] = time.perf_counter() - tic
        put("peer_costmin", peer.evaluate_at(wt, t_nodes, track))
    if len(pdr_steps) == 0:
        return score
    spread = max(cal.yaw_offset_spread_rad, 1e-3)
    residual = heading_residual_rad(steps, cal.yaw_offset_rad, wt, wxy)
    score.heading_residual_rad = residual
    options = settings.tracker_options(unknown_start_heading_sd_rad=spread, start_heading_offset_sd_rad=spread)
    start_xy = wxy[0] if not math.isinf(settings.wall_log_penalty) else _walkable_start(fl.plan, wxy[0])
    known = {"position_m": start_xy, "floor": fl.number, "heading_offset_rad": 0.0, "time_s": float(wt[0])}
    smoother = fusion.SmootherOptions(num_trajectories=settings.smoother_trajectories,
                                      max_particles=settings.smoother_max_particles, seed=settings.seed)
    known_options = replace_options(options, fix_tempering=settings.known_start_fix_tempering,
                                    fix_outlier_probability=settings.known_start_fix_outlier_probability)
    known_fixes = fixes
    if settings.known_start_fix_metric != models.database.settings.metric and "fusion_known_start" in want:
        known_db = models.database.with_settings(replace(models.database.settings, metric=settings.known_start_fix_metric))
        known_fixes = wfx.fixes_for_walk(walk, known_db)
    particle = settings.engine == "particle"
    # The particle engine's runs: the fusion_* methods when it is the engine, else particle_*.
    p_unknown, p_smoother, p_known = (("fusion_unknown_start", "fusion_smoother", "fusion_known_start") if particle
                                      else ("particle_unknown_start", "particle_smoother", "particle_known_start"))
    runs = {
        "unknown": dict(start=None, smoother=smoother, keys=(p_unknown, p_smoother)),
        "known": dict(start=known, smoother=None, keys=(p_known,), options=known_options, fixes=known_fixes),
    }
    if particle:
        runs.update({
            "fusion_no_walls": dict(start=None, smoother=smoother, keys=(None, "fusion_no_walls")),
            "fusion_no_wifi": dict(start=known, smoother=smoother, fixes=None, keys=(None, "fusion_no_wifi")),
            "fusion_no_heading_offset": dict(start=None, smoother=smoother, keys=(None, "fusion_no_heading_offset"),
                                             options=replace_options(options, heading_offset_walk_rad=0.0,
                                                                     unknown_start_heading_sd_rad=0.0)),
        })
    for name, run in runs.items():
        if not want.intersection(k for k in run["keys"] if k):
            continue
        tic = time.perf_counter()
        # No walls: the outline without its shops, so that the start and the fixes' outlier
        # density still cover the building's extent.
        run_plan = fl.outline_plan if name == "fusion_no_walls" else fl.plan
        result = fusion.track(pdr_steps, plan=run_plan, start=run["start"], options=run.get("options", options),
                              smoother=run["smoother"], fixes=run.get("fixes", fixes))
        seconds = time.perf_counter() - tic
        filtered, smoothed = run["keys"][0], run["keys"][-1] if len(run["keys"]) > 1 else None
        idx = np.clip(np.searchsorted(pdr_steps.times_s, wt), 0, len(pdr_steps) - 1)
        if filtered:
            put(filtered, _interp_track(wt, pdr_steps.times_s, result["mean_m"]))
            score.seconds[filtered] = seconds
            if filtered in COVARIANCE_METHODS:
                score.in_region95[filtered] = fusion.region95_contains(
                    _interp_track(wt, pdr_steps.times_s, result["mean_m"]), np.asarray(result["covariance_m2"])[idx], wxy)
        if smoothed:
            put(smoothed, _interp_track(wt, pdr_steps.times_s, result["smoothed_m"]))
            score.seconds[smoothed] = seconds
            if smoothed in COVARIANCE_METHODS:
                score.in_region95[smoothed] = fusion.region95_contains(
                    _interp_track(wt, pdr_steps.times_s, result["smoothed_m"]),
                    np.asarray(result["smoothed_covariance_m2"])[idx], wxy)
        if name == "unknown" and smoothed:
            score.offset_error_rad[smoothed] = _wrap(float(np.asarray(result["heading_offset_rad"])[-1]) - residual)
    if not particle:
        _score_walk_grid(score, put, pdr_steps, fixes, known_fixes, known, models, settings, want, residual)
        if "fusion_live" in want:
            _score_walk_live(score, put, walk, models, settings)
    if settings.floor_identification and models.all_plan is not None and "fusion_smoother" in want:
        _identify_floor(score, walk, steps_raw, pdr_steps, models, settings, options, smoother)
    return score


def _identify_floor(score: WalkScore, walk, steps_raw, pdr_steps, models: FoldModels, settings: RealSettings, options,
                    smoother) -> None:
    """Floor identification of one walk (``score.floor_correct``, ``score.floor_free_errors_m``):
    the default with the floor not given, on the all-floor plan and database of the fold; the
    steps rotated by ``site_model.identification_calibration`` (not by the walk's own floor's
    calibration, which a walk of unknown floor does not have), as ``track --floor auto``."""
    fl = models.floor
    wt = score.t_s + score.waypoint_t0
    wxy = score.waypoint_xy_m
    # The walk's queries in the all-floor database's columns, for its fixes and its AP evidence.
    all_queries = wfx.walk_queries(walk, models.all_database)
    all_fixes = wfx.fixes_for_walk(walk, models.all_database, queries=all_queries)
    tic = time.perf_counter()
    plan_floors = list(models.all_plan.floors)
    step_idx = np.clip(np.searchsorted(pdr_steps.times_s, wt), 0, len(pdr_steps) - 1)
    if settings.engine == "particle":
        result = fusion.track(pdr_steps, plan=models.all_plan, options=options, smoother=smoother, fixes=all_fixes)
        est_floor = np.asarray(plan_floors)[np.asarray(result["smoothed_floor_index"])[step_idx]]
        track_m = result["smoothed_m"]
    else:
        # All floors, filter only, coarse cells, plus the APs' evidence: the floor with the most
        # evidence (site_model.identify_floor, the code of ``indoorloc track --floor auto``);
        # then the floor-given smoother on it (a walk stays on one floor in this model).
        ts = settings.track_settings()
        id_cal, id_spread = site_model.identification_calibration(models.all_calibrations)
        id_steps = site_model.tracker_steps(steps_raw, id_cal, ts)
        ident = _grid_tracker(models.all_plan, _identification_options(settings, id_spread), "all")
        evidence = (site_model.walk_floor_evidence(walk, models.all_database, models.all_ap_rates, ts, all_queries)
                    if models.all_ap_rates is not None else {"ap_log_likelihood": None, "match_distance_db": None})
        found = site_model.identify_floor(ident, plan_floors, id_steps, all_fixes, evidence["ap_log_likelihood"],
                                          ts.identification_ap_weight, ts.floor_calibration(),
                                          evidence["match_distance_db"], evidence.get("classifier_log_likelihood"),
                                          ts.identification_classifier_weight)
        est_floor = np.full(wt.size, found["floor"])
        score.floor_probability = found["probabilities"][found["floor"]]
        track_m = score.smoothed_track_m if found["floor"] == fl.number else np.asarray(found["result"]["mean_m"])
    score.seconds["floor_identification"] = time.perf_counter() - tic
    score.floor_correct = est_floor == fl.number
    score.floor_free_errors_m = np.where(score.floor_correct,
                                         np.hypot(*(_interp_track(wt, pdr_steps.times_s, track_m) - wxy).T), np.nan)


def _wrap(angle_rad: float) -> float:
    return float(math.remainder(angle_rad, 2.0 * math.pi))


def heading_residual_rad(steps: ph.HandheldSteps, yaw_offset_rad: float, waypoint_t_s: np.ndarray,
                         waypoint_xy_m: np.ndarray) -> float:
    """The walk's residual heading offset [rad]: the rotation that best maps the PDR displacements
    between consecutive waypoints (headings already rotated by ``yaw_offset_rad``) onto the
    surveyed ones, in the least-squares sense (Procrustes angle). The truth the trackers' learnt
    offset is compared with."""
    pdr = ph.pdr_track(steps, waypoint_xy_m[0], waypoint_t_s, yaw_offset_rad=yaw_offset_rad)
    p, w = np.diff(pdr, axis=0), np.diff(waypoint_xy_m, axis=0)
    return float(math.atan2(np.sum(p[:, 0] * w[:, 1] - p[:, 1] * w[:, 0]), np.sum(p * w)))


_TRACKERS: Dict[Tuple, Any] = {}
_TRACKERS_LOCK = threading.Lock()


def _grid_key(options) -> Tuple:
    """The options that define a tracker's grid (``GridTracker.with_options`` keeps them)."""
    return options.cell_size_m, options.walkable_subsamples, options.wall_margin_m


def _grid_tracker(plan, options, key: str, database=None):
    """The GridTracker of a plan and options, built once and shared by the threads (its runs are
    thread-safe). With a fingerprint ``database``: that tracker anchored to the database's survey
    positions (``site_model.survey_anchored``; one per fold). A tracker of the same plan, grid
    (and database) with other options is derived from one built before
    (``GridTracker.with_options``: the same tracker bit for bit, without recomputing the walkable
    fractions, a batch of point queries, or the survey anchors, a nearest search per cell)."""
    k = (key, tuple(sorted(options.to_dict().items())))
    same_grid = ("grid", key, _grid_key(options))
    with _TRACKERS_LOCK:
        tracker = _TRACKERS.get(k)
        if tracker is None or tracker[0] is not plan:
            sibling = _TRACKERS.get(same_grid)
            tracker = (plan, sibling[1].with_options(options) if sibling is not None and sibling[0] is plan
                       else fusion.GridTracker(plan, options))
            _TRACKERS[k] = _TRACKERS[same_grid] = tracker
        if database is None or not site_model.uses_survey_positions(options):
            return tracker[1]
        anchored = _TRACKERS.get(k + (id(database),))
        if anchored is None or anchored[0] is not database:
            sibling = _TRACKERS.get(same_grid + (id(database),))
            anchored = (database, sibling[1].with_options(options) if sibling is not None and sibling[0] is database
                        and site_model.uses_survey_positions(sibling[1].options)
                        else site_model.survey_anchored(tracker[1], plan, database))
            _TRACKERS[k + (id(database),)] = _TRACKERS[same_grid + (id(database),)] = anchored
        return anchored[1]


def _grid_options(settings: RealSettings, spread_rad: float, **changes):
    median = settings.point_estimate == "median" or settings.score_both_point_estimates
    return settings.grid_options.replace(heading_offset_sd_rad=spread_rad, spatial_median=median, **changes)


def _identification_options(settings: RealSettings, spread_rad: float):
    # Only the run's evidence per floor is scored (its track is used where the floor is wrong, and
    # such waypoints are not scored): no spatial median, whose double sums cost as much as the run.
    return site_model.identification_grid_options(settings.track_settings(), spread_rad, False)


def _second_pass(score: WalkScore, put, first: dict, pdr_steps, fixes, models: FoldModels, settings: RealSettings,
                 base) -> None:
    """fusion_smoother as the site model tracks: the second smoother pass from the first pass's
    located start (``site_model.run_second_pass``). Its mean replaces the first pass's estimates
    (for --select, one second pass from each of the first pass's point estimates); the 95 % region keeps the first pass's calibrated
    covariance (``site_model.SECOND_PASS_KEYS``)."""
    fl = models.floor
    wt = score.t_s + score.waypoint_t0
    wxy = score.waypoint_xy_m
    tic = time.perf_counter()
    tracker = _grid_tracker(fl.plan, site_model.second_pass_options(base, settings.track_settings()), fl.name,
                            models.database)
    # The point estimate says where the second pass starts: the first pass's mean or spatial median
    # at the first step (site_model.located_start); the second pass's own estimate is its mean
    # (site_model.SECOND_PASS_KEYS). --select scores both starts, each with its own second pass.
    starts = ("mean", "median") if settings.score_both_point_estimates else (settings.point_estimate,)
    for pe in starts:
        r2 = site_model.run_second_pass(tracker, first, pdr_steps, fixes, fl.number, pe == "median")
        est_pe = _interp_track(wt, pdr_steps.times_s, r2["smoothed_m"])
        if settings.score_both_point_estimates:
            put(f"_alt/fusion_smoother/{pe}", est_pe)
        if pe == settings.point_estimate:
            est = est_pe
    put("fusion_smoother", est)
    score.seconds["fusion_smoother"] = score.seconds.get("fusion_smoother", 0.0) + time.perf_counter() - tic
    idx = np.clip(np.searchsorted(pdr_steps.times_s, wt), 0, len(pdr_steps) - 1)
    score.in_region95["fusion_smoother"] = fusion.region95_contains(
        est, np.asarray(first["smoothed_covariance_m2"])[idx], wxy)
    if "fusion_smoother" in score.calibration_inputs:
        score.calibration_inputs["fusion_smoother"]["error_m"] = est - wxy
    score.smoothed_track_m = np.asarray(r2["smoothed_m"])


def _score_walk_live(score: WalkScore, put, walk, models: FoldModels, settings: RealSettings) -> None:
    """fusion_live: the live tracker (``Site.live()``) replayed, i.e. ``fusion.live.causal_track`` on
    the fold's models and the default's tracker: causal steps, each WiFi fix applied when its scan
    exists (not at the earlier mean last-seen time of its readings, as fusion_unknown_start). Its
    estimates from the first located one on (``LiveEstimate.located``: before the first fix an unknown
    start's estimate is the prior's mean, not a position); waypoints before it are scored with that
    first position and counted (``live_waypoints_before_position``). A walk never located is not
    scored."""
    fl = models.floor
    wt = score.t_s + score.waypoint_t0
    wxy = score.waypoint_xy_m
    tic = time.perf_counter()
    tracker = _grid_tracker(fl.plan, _grid_options(settings, max(models.cal.yaw_offset_spread_rad, 1e-3)),
                            fl.name, models.database)
    r = live.causal_track(tracker, walk, models.cal, models.database,
                          step_length_sd_fraction=settings.step_length_sd_fraction,
                          step_heading_sd_rad=settings.step_heading_sd_rad)
    at = located_track_at(wt, r)
    if at is None:
        return
    est, first_t, cov = at
    put("fusion_live", est)
    score.seconds["fusion_live"] = time.perf_counter() - tic
    score.live_first_position_s = float(first_t - wt[0])
    score.live_waypoints_before_position = int(np.sum(wt < first_t))
    score.in_region95["fusion_live"] = fusion.region95_contains(est, cov, wxy)


def located_track_at(t_query_s: np.ndarray, run: dict):
    """A live run's track (``fusion.live.causal_track``) at the query times [s], from its first
    located estimate on: ``(positions (W, 2) [m] interpolated between the located steps and held at
    the first one before it, the first located step's time [s], the covariance (W, 3) [m²] of the
    step at or after each query)``; None when the run never located the walker."""
    located = np.asarray(run["located"], bool)
    if not located.any():
        return None
    k0 = int(np.argmax(located))
    t = np.asarray(run["times_s"], float)[k0:]
    est = _interp_track(t_query_s, t, np.asarray(run["mean_m"], float)[k0:])
    idx = np.clip(np.searchsorted(t, t_query_s), 0, t.size - 1)
    return est, float(t[0]), np.asarray(run["covariance_m2"])[k0:][idx]


def _score_walk_grid(score: WalkScore, put, pdr_steps, fixes, known_fixes, known: dict, models: FoldModels,
                     settings: RealSettings, want, residual: float) -> None:
    """The fusion_* methods on the grid engine (unknown start: filter and smoother; known start;
    the ablations)."""
    fl = models.floor
    wt = score.t_s + score.waypoint_t0
    wxy = score.waypoint_xy_m
    idx = np.clip(np.searchsorted(pdr_steps.times_s, wt), 0, len(pdr_steps) - 1)
    spread = max(models.cal.yaw_offset_spread_rad, 1e-3)
    base = _grid_options(settings, spread)
    tracker = _grid_tracker(fl.plan, base, fl.name, models.database)

    median = settings.point_estimate == "median"

    def run(name_filtered, name_smoothed, tracker_, start, fx, smooth=True):
        tic = time.perf_counter()
        # A run scored by its smoother alone skips the filter's position estimates (same smoother).
        r = fusion.track_grid(tracker_, pdr_steps, fixes=fx, start=start, smooth=smooth, filtered=bool(name_filtered))
        seconds = time.perf_counter() - tic
        for name, key, cov_key in ((name_filtered, "mean_m", "covariance_m2"),
                                   (name_smoothed, "smoothed_m", "smoothed_covariance_m2")):
            if not name or key not in r:
                continue
            # Both point estimates are kept (hidden keys) for the leave-one-floor-out choice.
            median_key = "median_m" if key == "mean_m" else "smoothed_median_m"
            alternatives = {"mean": _interp_track(wt, pdr_steps.times_s, r[key])}
            if median_key in r and start is None:
                alternatives["median"] = _interp_track(wt, pdr_steps.times_s, r[median_key])
            for pe, est_pe in alternatives.items():
                put(f"_alt/{name}/{pe}", est_pe)
            est = alternatives["median"] if median and "median" in alternatives else alternatives["mean"]
            put(name, est)
            score.seconds[name] = seconds
            if name in COVARIANCE_METHODS:
                score.in_region95[name] = fusion.region95_contains(est, np.asarray(r[cov_key])[idx], wxy)
                prefix = "" if key == "mean_m" else "smoothed_"
                score.calibration_inputs[name] = {
                    "error_m": est - wxy,
                    "posterior_covariance_m2": np.asarray(r[prefix + "posterior_covariance_m2"])[idx],
                    "fix_distance_m": np.asarray(r[prefix + "fix_distance_m"])[idx],
                    "fix_sd_m": np.asarray(r[prefix + "fix_sd_m"])[idx]}
        return r

    if want & {"fusion_unknown_start", "fusion_smoother"} or settings.floor_identification:
        r = run("fusion_unknown_start", "fusion_smoother", tracker, None, fixes)
        score.offset_error_rad["fusion_smoother"] = _wrap(float(r["walk_heading_offset_rad"]) - residual)
        # The offset prior's own error (its centre, 0: the training yaw offset), for comparison.
        score.offset_error_rad["fusion_no_heading_offset"] = _wrap(0.0 - residual)
        score.smoothed_track_m = np.asarray(r["smoothed_m"])
        if settings.second_pass_start_sd_m > 0:
            _second_pass(score, put, r, pdr_steps, fixes, models, settings, base)
    # The known start's own choice of τ, ε, walls and tempering mode (LOFO on its own error). Its
    # runs are scored by their means (run() reads medians only from an unknown start): no spatial
    # median, whose double sums cost about 40 % of such a run (the means then come from the float
    # sums: within 1e-5 m of the double ones).
    known_tracker = _grid_tracker(fl.plan, base.replace(
        spatial_median=False,
        fix_tempering=settings.known_start_fix_tempering,
        fix_outlier_probability=settings.known_start_fix_outlier_probability,
        wall_log_penalty=settings.known_start_wall_log_penalty,
        fix_tempering_by_variance=settings.known_start_fix_tempering_by_variance,
        filtered_covariance_scale=settings.known_start_covariance_scale,
        filtered_covariance_floor_m=settings.known_start_covariance_floor_m,
        filtered_covariance_fix_gain=settings.known_start_covariance_fix_gain,
        filtered_covariance_fix_sd_gain=settings.known_start_covariance_fix_sd_gain,
        covariance_fix_sd_knee_m=settings.known_start_covariance_fix_sd_knee_m), fl.name, models.database)
    if "fusion_known_start" in want:
        run("fusion_known_start", None, known_tracker, known, known_fixes, smooth=False)
    if "fusion_no_walls" in want:
        run(None, "fusion_no_walls", _grid_tracker(fl.outline_plan, base, fl.name + "/outline", models.database),
            None, fixes)
    if "fusion_no_wifi" in want:
        run(None, "fusion_no_wifi", known_tracker, known, None)
    if "fusion_no_heading_offset" in want:
        run(None, "fusion_no_heading_offset",
            _grid_tracker(fl.plan, base.replace(heading_offset_sd_rad=0.0), fl.name, models.database), None, fixes)
