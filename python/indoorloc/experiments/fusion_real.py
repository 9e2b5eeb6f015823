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
"""

from __future__ import annotations

import itertools
import math
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc import fusion, wifi, wifi_crowdsource as wc, wifi_fixes as wfx
from indoorloc.fusion import site_model
from indoorloc.pdr import handheld as ph
from indoorloc.io import ilc_floor_names, load_floor_plan, read_ilc_floor

FLOORS: Tuple[str, ...] = ()  #: none named: every floor folder under the data root, in building order
METHODS = (
    "wifi_knn",
    "wifi_model",
    "pdr_only",
    "peer_costmin",
    "fusion_unknown_start",
    "fusion_known_start",
    "fusion_smoother",
    "fusion_no_walls",
    "fusion_no_wifi",
    "fusion_no_heading_offset",
    "particle_unknown_start",
    "particle_smoother",
    "particle_known_start",
)
#: Methods whose estimate comes with a covariance: the 95 % region's coverage is reported.
COVARIANCE_METHODS = ("fusion_unknown_start", "fusion_smoother", "fusion_known_start", "particle_unknown_start",
                      "particle_smoother")


@dataclass
class RealSettings:
    """Settings of ``indoorloc fusion evaluate``; each is fixed in advance (why in the comment),
    fitted per fold on the training walks (``calibrate_handheld``), or chosen by
    leave-one-floor-out cross-validation (:func:`select_settings`; marked LOFO)."""

    folds: int = 4                      #: k of the k-fold by walk (issue 15)
    seed: int = 0                       #: fold assignment and tracker seeds
    num_particles: int = 3000           #: 20000 gave the same errors on F8 (docs/fusion_real.md)
    smoother_trajectories: int = 50     #: FFBSi trajectories
    #: FFBSi cloud thinned to this many particles per step (cost O(trajectories x this x steps)).
    smoother_max_particles: int = 500
    #: Staleness limit of the WiFi-only fixes [s]: the dip of the reading-age histogram between the
    #: current scan and Android's cache (docs/fusion_data.md).
    wifi_max_age_s: float = 2.5
    grid_spacing_m: float = 2.0         #: GridPosterior spacing of the model fixes (docs/fusion_real.md)
    #: Per-step white noise of the handheld PDR given to the filter: length sd as a fraction of the
    #: stride and heading sd [rad]; the systematic parts are the filter's scale and offset states.
    step_length_sd_fraction: float = 0.15
    step_heading_sd_rad: float = math.radians(10.0)
    #: LOFO: log-weight of a step through a shop wall (-inf: the particle is dropped; log 0.02 in
    #: the grid: shops are polygons without doors and 12 of 866 waypoints lie inside one). A known
    #: start inside a shop is moved to the nearest walkable point.
    wall_log_penalty: float = field(default_factory=lambda: fusion.TrackerOptions().wall_log_penalty)
    candidate_spacing_m: float = 2.0    #: unknown start and recovery on the mall floors
    #: The WiFi as fingerprint fixes (``wifi_fixes``); k, T, σ, c: LOFO.
    fixes: wfx.FixSettings = field(default_factory=wfx.FixSettings)
    #: LOFO: ε of the fixes (the particle tracker's own default, read from TrackerOptions).
    fix_outlier_probability: float = field(default_factory=lambda: fusion.TrackerOptions().fix_outlier_probability)
    #: LOFO: τ_fix (consecutive scans share stale readings; TrackerOptions' default).
    fix_tempering: float = field(default_factory=lambda: fusion.TrackerOptions().fix_tempering)
    #: The known-start filter's own choice (LOFO on ``fusion_known_start`` over the same grid,
    #: the same point in every fold): with the start known, WiFi fixes only need to stop drift
    #: and are weighted less.
    #: "shared": the default fixes (the old choice "union" was made for single-scan fixes; with
    #: the pooled windows of wifi_matcher there is one fix source, weighted by the known start's
    #: own τ and ε below).
    known_start_fix_metric: str = "shared"
    #: (LOFO on fusion_known_start over the grid of SELECT_GRID, the same point for every held-out
    #: floor: τ 0.2 at the grid's lower edge, 0.4 within 0.02 m of it.)
    known_start_fix_tempering: float = 0.2
    known_start_fix_outlier_probability: float = 0.3
    #: The grid engine's known start: its own wall penalty and tempering mode (LOFO on
    #: fusion_known_start, like its τ and ε).
    known_start_wall_log_penalty: float = -3.0
    known_start_fix_tempering_by_variance: bool = False
    #: The known start's calibration of its returned covariance (a, b [m], g of
    #: GridTrackerOptions.filtered_covariance_*): the all-floor choice of
    #: ``experiments/fusion_uncertainty`` (LOFO coverage 0.956, 0.93-0.98 per floor).
    known_start_covariance_scale: float = 3.0
    known_start_covariance_floor_m: float = 1.5
    known_start_covariance_fix_gain: float = 0.0
    floor_identification: bool = True   #: also run the default with the floor not given
    threads: int = 2                    #: walks tracked in parallel (results do not depend on it)
    #: Engine of the fusion_* methods: "grid" (exact filter and smoother on floor cells,
    #: ``fusion.GridTracker``) or "particle" (``fusion.track``). The other engine's default runs
    #: too, as ``particle_*`` or ``grid_*`` (docs/fusion_real.md: chosen by leave-one-floor-out).
    engine: str = "grid"
    #: The grid engine's options (the heading-offset prior sd is the fold's calibrated spread).
    grid_options: Any = field(default_factory=lambda: fusion.GridTrackerOptions())
    #: Point estimate of the grid engine's unknown-start methods: "mean" or "median" (spatial
    #: median) of the posterior (LOFO).
    point_estimate: str = "mean"
    #: Also score the other point estimate (hidden keys): set by --select, which chooses it.
    score_both_point_estimates: bool = False
    #: Cells [m] and offset bins of the floor-identification pass (all floors, filter only).
    floor_identification_cell_m: float = 2.0
    floor_identification_offset_bins: int = 3

    def tracker_options(self, **overrides) -> fusion.TrackerOptions:
        settings = dict(num_particles=self.num_particles, wall_log_penalty=self.wall_log_penalty,
                        candidate_spacing_m=self.candidate_spacing_m, seed=self.seed,
                        fix_outlier_probability=self.fix_outlier_probability, fix_tempering=self.fix_tempering)
        settings.update(overrides)
        return fusion.tracker_options(**settings)

    def track_settings(self) -> site_model.TrackSettings:
        """The settings a site model's default tracker takes (``fusion.site_model``)."""
        return site_model.TrackSettings(
            step_length_sd_fraction=self.step_length_sd_fraction, step_heading_sd_rad=self.step_heading_sd_rad,
            fixes=self.fixes, grid_options=self.grid_options, point_estimate=self.point_estimate,
            identification_cell_m=self.floor_identification_cell_m,
            identification_offset_bins=self.floor_identification_offset_bins)

    def to_dict(self) -> Dict[str, Any]:
        d = asdict(self)
        d["wall_log_penalty"] = None if math.isinf(self.wall_log_penalty) else self.wall_log_penalty
        g = self.grid_options.to_dict()
        d["grid_options"] = {k: (None if isinstance(v, float) and math.isinf(v) else v) for k, v in g.items()}
        return d


@dataclass
class WalkScore:
    floor: str
    walk: str
    t_s: np.ndarray                                  #: waypoint times since the walk's first waypoint
    errors_m: Dict[str, np.ndarray] = field(default_factory=dict)
    seconds: Dict[str, float] = field(default_factory=dict)
    floor_correct: Optional[np.ndarray] = None       #: floor identification at the waypoints
    floor_free_errors_m: Optional[np.ndarray] = None  #: position error of that run
    #: Distance [m] from each waypoint to the nearest training scan of its floor (survey coverage).
    coverage_m: Optional[np.ndarray] = None
    #: Per method with a covariance: whether each waypoint lies in the estimate's 95 % ellipse.
    in_region95: Dict[str, np.ndarray] = field(default_factory=dict)
    #: Per method with a heading-offset state: final offset minus the walk's residual [rad].
    offset_error_rad: Dict[str, float] = field(default_factory=dict)
    #: The walk's heading residual measured from its waypoints [rad] (``heading_residual_rad``).
    heading_residual_rad: Optional[float] = None
    waypoint_t0: float = 0.0                          #: the first waypoint's time [s]
    waypoint_xy_m: Optional[np.ndarray] = None        #: surveyed waypoints (W, 2) [m]
    smoothed_track_m: Optional[np.ndarray] = None     #: the default's smoothed track (per step)
    #: Per grid method: what the covariance calibration is fitted on (``fusion_uncertainty``):
    #: ``error_m`` (W, 2) estimate minus truth, ``posterior_covariance_m2`` (W, 3), ``fix_distance_m`` (W,).
    calibration_inputs: Dict[str, Dict[str, np.ndarray]] = field(default_factory=dict)


@dataclass
class FloorData:
    """One floor's walks, plan and detected steps."""

    name: str
    number: int
    walks: List[Any]
    plan: Any
    steps: List[ph.HandheldSteps]
    geojson_path: Path
    outline_plan: Any = None   #: the outline without shops (the no-walls ablation keeps the extent)
    load_report: Optional[Dict[str, Any]] = None  #: walks skipped, fields dropped (IlcFloor.load_report)


@dataclass
class FoldModels:
    """What a fold's training walks give one floor: PDR calibration, crowdsourced cell map,
    fingerprint database; and the all-floor plan and database for floor identification."""

    floor: FloorData
    cal: ph.HandheldCalibration
    crowd: Optional[wc.CrowdMap]  #: None unless the wifi_model method runs
    database: wfx.FingerprintDatabase
    all_plan: Any = None
    all_database: Optional[wfx.FingerprintDatabase] = None


def default_site_root() -> Path:
    """``shared/data/fusion/ilc2020_site2`` beside the WiFi data folder."""
    from indoorloc.registry import default_data_root

    return default_data_root().parent / "fusion" / "ilc2020_site2"


def floor_number(name: str) -> int:
    """Floor number of an ILC floor folder: F3 -> 3, B1 -> -1 (digits of the name)."""
    digits = "".join(ch for ch in name if ch.isdigit())
    return int(digits or 0) * (-1 if name.upper().startswith("B") else 1)


def _peer():
    """The cost-minimisation baseline (:mod:`indoorloc.fusion.costmin_baseline`)."""
    from indoorloc.fusion import costmin_baseline

    return costmin_baseline


def _folds(n: int, k: int, seed: int) -> List[np.ndarray]:
    perm = np.random.default_rng(seed).permutation(n)
    return [np.sort(perm[i::k]) for i in range(min(k, n))]


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


def replace_options(options: fusion.TrackerOptions, **changes) -> fusion.TrackerOptions:
    """A copy of TrackerOptions with some fields changed (its bound ``replace``, which validates)."""
    return options.replace(**changes)


def _score_walk(walk, steps_raw: ph.HandheldSteps, models: FoldModels, settings: RealSettings, peer,
                methods: Sequence[str]) -> WalkScore:
    fl = models.floor
    wt = np.asarray(walk.waypoint_t_s, float)
    wxy = np.asarray(walk.waypoint_xy_m, float)
    score = WalkScore(fl.name, walk.walk_id, wt - wt[0], waypoint_t0=float(wt[0]), waypoint_xy_m=wxy)
    train_xy = models.database.positions_m[models.database.floors == fl.number]
    if train_xy.size:
        score.coverage_m = np.sqrt(((wxy[:, None, :] - train_xy[None, :, :]) ** 2).sum(axis=2)).min(axis=1)
    err = score.errors_m
    want = set(methods)

    def put(name: str, est: np.ndarray) -> None:
        err[name] = np.hypot(*(np.asarray(est) - wxy).T)

    fixes = wfx.fixes_for_walk(walk, models.database)
    centres = wfx.fix_centres(fixes) if len(fixes) else np.zeros((0, 2))
    # WiFi only: the scan nearest in time to each waypoint.
    if len(fixes) and "wifi_knn" in want:
        put("wifi_knn", _nearest_rows(wt, fixes.times_s, centres))
    if "wifi_model" in want:
        scan_t, rss_fresh, _ = wc.scan_matrix(walk, models.crowd.bssids, dedup=False, max_age_s=settings.wifi_max_age_s)
        if scan_t.size:
            q = wc.prepare(_nearest_rows(wt, scan_t, rss_fresh), models.crowd.settings.not_heard_dbm)
            grid = wifi.GridPosterior(models.crowd.model, settings.grid_spacing_m)
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
        track = peer.costmin_track(t_nodes, pdr_steps.displacements_m, fixes.times_s, centres)
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
    if settings.floor_identification and models.all_plan is not None and "fusion_smoother" in want:
        all_fixes = wfx.fixes_for_walk(walk, models.all_database)
        tic = time.perf_counter()
        plan_floors = list(models.all_plan.floors)
        step_idx = np.clip(np.searchsorted(pdr_steps.times_s, wt), 0, len(pdr_steps) - 1)
        if particle:
            result = fusion.track(pdr_steps, plan=models.all_plan, options=options, smoother=smoother, fixes=all_fixes)
            est_floor = np.asarray(plan_floors)[np.asarray(result["smoothed_floor_index"])[step_idx]]
            track_m = result["smoothed_m"]
        else:
            # All floors, filter only, coarse cells: the floor with the most evidence; then the
            # floor-given smoother on it (a walk stays on one floor in this model).
            ident = _grid_tracker(models.all_plan, _identification_options(settings, spread), fl.name + "/all")
            r = fusion.track_grid(ident, pdr_steps, fixes=all_fixes, smooth=False)
            best = int(np.argmax(r["smoothed_floor_probabilities"]))
            est_floor = np.full(wt.size, plan_floors[best])
            if plan_floors[best] == fl.number:
                track_m = score.smoothed_track_m
            else:
                track_m = np.asarray(r["mean_m"])
        score.seconds["floor_identification"] = time.perf_counter() - tic
        score.floor_correct = est_floor == fl.number
        score.floor_free_errors_m = np.where(score.floor_correct,
                                             np.hypot(*(_interp_track(wt, pdr_steps.times_s, track_m) - wxy).T),
                                             np.nan)
    return score


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


_TRACKERS: Dict[Tuple[str, Tuple], Any] = {}
_TRACKERS_LOCK = threading.Lock()


def _grid_tracker(plan, options, key: str):
    """The GridTracker of a plan and options, built once (its walkable fractions cost a batch of
    point queries) and shared by the threads (its runs are thread-safe)."""
    k = (key, tuple(sorted(options.to_dict().items())))
    with _TRACKERS_LOCK:
        tracker = _TRACKERS.get(k)
        if tracker is None or tracker[0] is not plan:
            tracker = (plan, fusion.GridTracker(plan, options))
            _TRACKERS[k] = tracker
        return tracker[1]


def _grid_options(settings: RealSettings, spread_rad: float, **changes):
    median = settings.point_estimate == "median" or settings.score_both_point_estimates
    return settings.grid_options.replace(heading_offset_sd_rad=spread_rad, spatial_median=median, **changes)


def _identification_options(settings: RealSettings, spread_rad: float):
    median = settings.point_estimate == "median" or settings.score_both_point_estimates
    return site_model.identification_grid_options(settings.track_settings(), spread_rad, median)


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
    tracker = _grid_tracker(fl.plan, base, fl.name)

    median = settings.point_estimate == "median"

    def run(name_filtered, name_smoothed, tracker_, start, fx, smooth=True):
        tic = time.perf_counter()
        r = fusion.track_grid(tracker_, pdr_steps, fixes=fx, start=start, smooth=smooth)
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
                    "fix_distance_m": np.asarray(r[prefix + "fix_distance_m"])[idx]}
        return r

    if want & {"fusion_unknown_start", "fusion_smoother"} or settings.floor_identification:
        r = run("fusion_unknown_start", "fusion_smoother", tracker, None, fixes)
        score.offset_error_rad["fusion_smoother"] = _wrap(float(r["walk_heading_offset_rad"]) - residual)
        # The offset prior's own error (its centre, 0: the training yaw offset), for comparison.
        score.offset_error_rad["fusion_no_heading_offset"] = _wrap(0.0 - residual)
        score.smoothed_track_m = np.asarray(r["smoothed_m"])
    # The known start's own choice of τ, ε, walls and tempering mode (LOFO on its own error).
    known_tracker = _grid_tracker(fl.plan, base.replace(
        fix_tempering=settings.known_start_fix_tempering,
        fix_outlier_probability=settings.known_start_fix_outlier_probability,
        wall_log_penalty=settings.known_start_wall_log_penalty,
        fix_tempering_by_variance=settings.known_start_fix_tempering_by_variance,
        filtered_covariance_scale=settings.known_start_covariance_scale,
        filtered_covariance_floor_m=settings.known_start_covariance_floor_m,
        filtered_covariance_fix_gain=settings.known_start_covariance_fix_gain), fl.name)
    if "fusion_known_start" in want:
        run("fusion_known_start", None, known_tracker, known, known_fixes, smooth=False)
    if "fusion_no_walls" in want:
        run(None, "fusion_no_walls", _grid_tracker(fl.outline_plan, base, fl.name + "/outline"), None, fixes)
    if "fusion_no_wifi" in want:
        run(None, "fusion_no_wifi", known_tracker, known, None)
    if "fusion_no_heading_offset" in want:
        run(None, "fusion_no_heading_offset", _grid_tracker(fl.plan, base.replace(heading_offset_sd_rad=0.0), fl.name),
            None, fixes)


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
        out[fl.name] = FoldModels(fl, cal, crowd, database)
        all_walks += train
        all_steps += train_steps
        all_numbers += [fl.number] * len(train)
    if all_plan is not None:
        all_database = wfx.build_database(all_walks, settings.fixes, all_steps, floors=all_numbers)
        for m in out.values():
            m.all_plan, m.all_database = all_plan, all_database
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
        jobs = [(fl.walks[i], fl.steps[i], models[fl.name]) for fl, i in jobs_idx]
        with ThreadPoolExecutor(max_workers=max(1, settings.threads)) as pool:
            futures = [pool.submit(_score_walk, w, s, m, settings, peer, methods) for w, s, m in jobs]
            for f in futures:
                scores.append(f.result())
                if progress:
                    progress()
    return scores


def _stats(errors: np.ndarray) -> Dict[str, float]:
    return {"mean_m": float(np.mean(errors)), "median_m": float(np.median(errors)),
            "p90_m": float(np.percentile(errors, 90)), "n_waypoints": int(errors.size)}


#: Survey-coverage classes: distance from a test waypoint to the nearest training scan [m].
COVERAGE_CLASSES = (("within_5m", 0.0, 5.0), ("5_to_10m", 5.0, 10.0), ("beyond_10m", 10.0, math.inf))


def _extra_stats(scores: Sequence[WalkScore], name: str) -> Dict[str, Any]:
    """The keys added beside issue 15's (docs/fusion_real.md): ``first_10s_mean_m`` (mean error
    at waypoints in the walk's first 10 s), ``by_coverage`` (stats per coverage class),
    ``region95_coverage`` (fraction of waypoints in the estimate's 95 % ellipse, methods with a
    covariance), ``offset_error_deg`` (mean and median |final heading offset - the walk's
    residual|, methods with an offset state)."""
    sel = [s for s in scores if name in s.errors_m]
    e = np.concatenate([s.errors_m[name] for s in sel])
    t = np.concatenate([s.t_s for s in sel])
    out: Dict[str, Any] = {"first_10s_mean_m": float(e[t < 10.0].mean()) if (t < 10.0).any() else None}
    cov = [s.coverage_m if s.coverage_m is not None else np.full(s.t_s.size, np.nan) for s in sel]
    c = np.concatenate(cov)
    out["by_coverage"] = {}
    for key, lo, hi in COVERAGE_CLASSES:
        m = (c >= lo) & (c < hi)
        out["by_coverage"][key] = _stats(e[m]) if m.any() else None
    inside = [s.in_region95[name] for s in sel if name in s.in_region95]
    if inside:
        out["region95_coverage"] = float(np.concatenate(inside).mean())
    off = np.array([s.offset_error_rad[name] for s in sel if name in s.offset_error_rad])
    if off.size:
        out["offset_error_deg"] = {"mean_abs": float(np.degrees(np.abs(off)).mean()),
                                   "median_abs": float(np.degrees(np.median(np.abs(off)))), "n_walks": int(off.size)}
    return out


#: Bins of the time since the walk's first waypoint for "error against time" [s].
TIME_BINS_S = (0.0, 10.0, 20.0, 30.0, 45.0, math.inf)


def summarize(scores: Sequence[WalkScore], settings: RealSettings, seconds: float) -> dict:
    """The JSON contract of ``indoorloc fusion evaluate`` (docs/fusion_real.md):
    ``{"methods": {NAME: {"mean_m", "median_m", "p90_m", "n_waypoints"}}, "waypoints": [{"floor",
    "walk", "method", "t_s", "error_m"}], "settings": {...}}`` plus informative extras:
    ``per_floor``, ``error_vs_time`` (mean error per bin of time since the walk's start),
    ``floor_identification`` (accuracy when the floor is not given), ``seconds``,
    ``mean_seconds_per_walk``."""
    methods, per_floor, rows, by_time = {}, {}, [], {}
    for name in METHODS:
        e = [s.errors_m[name] for s in scores if name in s.errors_m]
        if not e:
            continue
        methods[name] = _stats(np.concatenate(e))
        methods[name].update(_extra_stats(scores, name))
        for fl in sorted({s.floor for s in scores}):
            ef = [s.errors_m[name] for s in scores if s.floor == fl and name in s.errors_m]
            if ef:
                per_floor.setdefault(fl, {})[name] = _stats(np.concatenate(ef))
        t = np.concatenate([s.t_s for s in scores if name in s.errors_m])
        ev = np.concatenate(e)
        bins = []
        for lo, hi in zip(TIME_BINS_S[:-1], TIME_BINS_S[1:]):
            sel = (t >= lo) & (t < hi)
            bins.append({"from_s": lo, "to_s": None if math.isinf(hi) else hi, "n_waypoints": int(sel.sum()),
                         "mean_m": float(ev[sel].mean()) if sel.any() else None})
        by_time[name] = bins
    for s in scores:
        for name, e in s.errors_m.items():
            if name.startswith("_"):  # the alternatives kept for --select
                continue
            for t, v in zip(s.t_s, e):
                rows.append({"floor": s.floor, "walk": s.walk, "method": name, "t_s": round(float(t), 3),
                             "error_m": round(float(v), 4)})
    walk_seconds = {}
    for name in tuple(METHODS) + ("floor_identification",):
        v = [s.seconds[name] for s in scores if name in s.seconds]
        if v:
            walk_seconds[name] = float(np.mean(v))
    out = {"methods": methods, "waypoints": rows, "settings": settings.to_dict(), "per_floor": per_floor,
           "error_vs_time": by_time, "seconds": round(seconds, 2), "mean_seconds_per_walk": walk_seconds}
    # Per walk: the final heading offset of each method with an offset state against the walk's
    # residual measured from its waypoints (both relative to the training yaw offset) [deg].
    out["heading_offsets"] = [
        {"floor": s.floor, "walk": s.walk, "residual_deg": round(math.degrees(s.heading_residual_rad), 3),
         "final_deg": {name: round(math.degrees(_wrap(s.heading_residual_rad + err)), 3)
                       for name, err in s.offset_error_rad.items() if name != "fusion_no_heading_offset"}}
        for s in scores if s.heading_residual_rad is not None and math.isfinite(s.heading_residual_rad)]
    ident = [s for s in scores if s.floor_correct is not None]
    if ident:
        correct = np.concatenate([s.floor_correct for s in ident])
        free = np.concatenate([s.floor_free_errors_m for s in ident])
        out["floor_identification"] = {
            "accuracy": float(correct.mean()), "n_waypoints": int(correct.size),
            "walks_all_correct": int(sum(bool(s.floor_correct.all()) for s in ident)), "n_walks": len(ident),
            "per_floor": {fl: float(np.concatenate([s.floor_correct for s in ident if s.floor == fl]).mean())
                          for fl in sorted({s.floor for s in ident})},
            # Position error of that run where the floor was right (the floor-given default is fusion_smoother).
            "mean_m_where_floor_correct": float(np.nanmean(free)) if np.isfinite(free).any() else None,
        }
    return out


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
    root, (fl,) = load_site(data_root, [floor])
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
        result = dict(fusion.track_grid(_grid_tracker(fl.plan, _grid_options(settings, spread), fl.name), pdr_steps,
                                        fixes=fixes))
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
    info = read_ilc_floor(root / floor)
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


# --------------------------------------------------------------------------------------------
# Leave-one-floor-out choice of the settings

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
SELECT_OBJECTIVE = "fusion_smoother"


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
    return {"grid": grid_out,
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
    lines += ["", f"Leave-one-floor-out ({result['objective']}, settings chosen on the other floors):", "",
              "| held-out floor | chosen | mean [m] | median [m] | p90 [m] |", "|---|---|---|---|---|"]
    for f, r in result["lofo"].items():
        st = r["stats"]
        lines.append(f"| {f} | {r['chosen']} | {st['mean_m']:.2f} | {st['median_m']:.2f} | {st['p90_m']:.2f} |")
    o = result["lofo_overall"]
    lines += ["", f"Held-out floors pooled: mean {o['mean_m']:.2f} m, median {o['median_m']:.2f} m, p90 {o['p90_m']:.2f} m "
              f"({o['n_waypoints']} waypoints). Chosen on all floors: {result['best_all']}."]
    ks = result.get("known_start")
    if ks:
        lines += ["", "Leave-one-floor-out for the known-start filter (fusion_known_start):", "",
                  "| held-out floor | chosen | mean [m] | median [m] | p90 [m] |", "|---|---|---|---|---|"]
        for f, r in ks["lofo"].items():
            st = r["stats"]
            lines.append(f"| {f} | {r['chosen']} | {st['mean_m']:.2f} | {st['median_m']:.2f} | {st['p90_m']:.2f} |")
        lines += ["", f"Held-out floors pooled: mean {ks['lofo_pooled_mean_m']:.2f} m. Chosen on all floors: "
                  f"{ks['best_all']}."]
    return "\n".join(lines)


def markdown(result: dict) -> str:
    lines = ["| method | mean [m] | median [m] | p90 [m] | waypoints |", "|---|---|---|---|---|"]
    for name, m in result["methods"].items():
        lines.append(f"| {name} | {m['mean_m']:.2f} | {m['median_m']:.2f} | {m['p90_m']:.2f} | {m['n_waypoints']} |")
    lines += ["", "Per floor (mean / median / p90 [m]):", "",
              "| method | " + " | ".join(result["per_floor"]) + " |", "|---|" + "---|" * len(result["per_floor"])]
    for name in result["methods"]:
        cells = []
        for fl, m in result["per_floor"].items():
            s = m.get(name)
            cells.append(f"{s['mean_m']:.1f} / {s['median_m']:.1f} / {s['p90_m']:.1f}" if s else "-")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    bins = next(iter(result["error_vs_time"].values()), [])
    if bins:
        heads = [f"{b['from_s']:.0f}-{b['to_s']:.0f} s" if b["to_s"] is not None else f">= {b['from_s']:.0f} s" for b in bins]
        lines += ["", "Mean error [m] against time since the walk's first waypoint:", "",
                  "| method | " + " | ".join(heads) + " |", "|---|" + "---|" * len(heads)]
        for name, bs in result["error_vs_time"].items():
            lines.append(f"| {name} | " + " | ".join("-" if b["mean_m"] is None else f"{b['mean_m']:.1f}" for b in bs) + " |")
    fi = result.get("floor_identification")
    if fi:
        lines += ["", f"Floor identification (floor not given, {SELECT_OBJECTIVE} on all floors' plans and fixes): "
                  f"{100 * fi['accuracy']:.1f} % of {fi['n_waypoints']} waypoints, {fi['walks_all_correct']} of "
                  f"{fi['n_walks']} walks right throughout; per floor "
                  + ", ".join(f"{k} {100 * v:.1f} %" for k, v in fi["per_floor"].items()) + "."]
    lines.append("")
    lines.append(f"{len({(w['floor'], w['walk']) for w in result['waypoints']})} walks in {result['seconds']:.0f} s.")
    return "\n".join(lines)
