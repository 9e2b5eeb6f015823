"""The fusion tracker on real phone recordings: ``indoorloc fusion evaluate`` (issue 15).

Data: the Indoor Location Competition 2.0 site-2 walks (``shared/data/fusion/ilc2020_site2``,
docs/fusion_data.md) or any folder in that layout. Per floor, k-fold by walk (fixed seed): the
training walks give the handheld-PDR calibration (Weinberg K, the yaw offset between the phone's
rotation-vector heading and the floor frame, its spread over walks: ``pdr_handheld``) and the
crowdsourced signal map (``wifi_crowdsource``); each test walk is then tracked from its own IMU
and WiFi and the floor plan, and scored at its surveyed waypoints. Methods, side by side on the
same folds:

``wifi_knn``, ``wifi_model``
    WiFi only: the scan nearest in time to each waypoint (readings older than the staleness limit
    dropped), weighted kNN on the map's cells / the posterior mean of paper 004's model.
``pdr_only``
    handheld PDR from the first waypoint, headings rotated by the training yaw offset.
``peer_costmin``
    the cost-minimisation post-processing of the 2021 competition's public solutions
    (``benchmarks/ilc_costmin_peer.py``): WiFi-model fixes at every scan plus the PDR
    displacements by robust least squares with a per-walk rotation. Only when run from a source
    tree (the peer is not part of the package); otherwise absent from the table.
``fusion_unknown_start``, ``fusion_known_start``, ``fusion_smoother``
    the tracker (floor given); the smoother runs from the unknown start and is the library's
    recommended default.
``fusion_no_walls``, ``fusion_no_wifi``, ``fusion_no_heading_offset``
    ablations of the default (unknown start + smoother): no floor plan; no WiFi (then the start
    must be known: it is); the heading offset fixed at the training offset (no offset state).

Every setting is either fixed in advance (``RealSettings``, with the reason) or fitted on the
training walks of the fold; nothing is chosen on the test walks. Estimates at step times are
interpolated linearly to the waypoint times.
"""

from __future__ import annotations

import math
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from indoorloc import fusion, pdr_handheld as ph, wifi, wifi_crowdsource as wc
from indoorloc.io import load_floor_plan, read_ilc_floor

FLOORS = ("F3", "F4", "F7", "F8")
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
)


@dataclass
class RealSettings:
    """Settings of ``indoorloc fusion evaluate``; each is fixed in advance (why in the comment)
    or fitted per fold on the training walks (``calibrate_handheld``)."""

    folds: int = 4                      #: k of the k-fold by walk (issue 15)
    seed: int = 0                       #: fold assignment
    num_particles: int = 3000           #: enough for a 237 x 219 m floor (the candidate grid seeds the cloud)
    smoother_trajectories: int = 50     #: FFBSi trajectories
    #: Staleness limit of the WiFi-only fixes [s]: the dip of the reading-age histogram between the
    #: current scan and Android's cache (docs/fusion_data.md); the tracker re-times readings instead.
    wifi_max_age_s: float = 2.5
    knn_k: int = 3                      #: the inner-CV choice of docs/fusion_real.md
    grid_spacing_m: float = 2.0         #: GridPosterior spacing of the model fixes (docs/fusion_real.md)
    #: Per-step white noise of the handheld PDR given to the filter: length sd as a fraction of the
    #: stride and heading sd [rad]; the systematic parts are the filter's scale and offset states.
    step_length_sd_fraction: float = 0.15
    step_heading_sd_rad: float = math.radians(10.0)
    #: Shops are polygons without doors and surveyors do walk into them (12 of 866 waypoints lie
    #: inside one): crossing an obstacle edge costs this log-weight instead of dropping the particle.
    wall_log_penalty: float = math.log(0.02)
    #: The crowdsourced map is built from heard readings only, and deduplicated scans do not say
    #: which APs were not heard: use heard readings only.
    use_not_heard: bool = False
    candidate_spacing_m: float = 2.0    #: unknown start and recovery on the mall floors
    #: τ of the WiFi likelihood; None: the library default (chosen on the synthetic building)
    tempering: Optional[float] = None
    threads: int = 2                    #: walks tracked in parallel (results do not depend on it)

    def tracker_options(self, **overrides) -> fusion.TrackerOptions:
        settings = dict(num_particles=self.num_particles, wall_log_penalty=self.wall_log_penalty,
                        use_not_heard=self.use_not_heard, candidate_spacing_m=self.candidate_spacing_m, seed=self.seed)
        if self.tempering is not None:
            settings["tempering"] = self.tempering
        settings.update(overrides)
        return fusion.tracker_options(**settings)


@dataclass
class WalkScore:
    floor: str
    walk: str
    t_s: np.ndarray                                  #: waypoint times since the walk's first waypoint
    errors_m: Dict[str, np.ndarray] = field(default_factory=dict)
    seconds: Dict[str, float] = field(default_factory=dict)


def default_site_root() -> Path:
    """``shared/data/fusion/ilc2020_site2`` beside the WiFi data folder."""
    from indoorloc.registry import default_data_root

    return default_data_root().parent / "fusion" / "ilc2020_site2"


def _peer():
    """The cost-minimisation peer from benchmarks/ (source tree only), or None."""
    here = Path(__file__).resolve()
    for parent in here.parents:
        candidate = parent / "benchmarks" / "ilc_costmin_peer.py"
        if candidate.is_file():
            if str(candidate.parent) not in sys.path:
                sys.path.insert(0, str(candidate.parent))
            import ilc_costmin_peer  # noqa: E402

            return ilc_costmin_peer
    return None


def _folds(n: int, k: int, seed: int) -> List[np.ndarray]:
    perm = np.random.default_rng(seed).permutation(n)
    return [np.sort(perm[i::k]) for i in range(min(k, n))]


def _nearest_scan_rows(times_s: np.ndarray, scan_t: np.ndarray, rss: np.ndarray) -> np.ndarray:
    idx = np.clip(np.searchsorted(scan_t, times_s), 0, len(scan_t) - 1)
    prev = np.clip(idx - 1, 0, len(scan_t) - 1)
    use_prev = np.abs(scan_t[prev] - times_s) < np.abs(scan_t[idx] - times_s)
    return rss[np.where(use_prev, prev, idx)]


def _interp_track(t_query: np.ndarray, t_steps: np.ndarray, xy: np.ndarray) -> np.ndarray:
    if t_steps.size == 0:
        return np.full((t_query.size, 2), np.nan)
    return np.stack([np.interp(t_query, t_steps, xy[:, 0]), np.interp(t_query, t_steps, xy[:, 1])], axis=1)


def _score_walk(walk, floor_name: str, floor_number: int, plan, crowd: wc.CrowdMap, cal: ph.HandheldCalibration,
                steps_raw: ph.HandheldSteps, settings: RealSettings, peer) -> WalkScore:
    wt = np.asarray(walk.waypoint_t_s, float)
    wxy = np.asarray(walk.waypoint_xy_m, float)
    score = WalkScore(floor_name, walk.walk_id, wt - wt[0])
    err = score.errors_m

    def put(name: str, est: np.ndarray) -> None:
        err[name] = np.hypot(*(np.asarray(est) - wxy).T)

    # WiFi only: the scan nearest in time to each waypoint, stale readings dropped.
    scan_t, rss_fresh, _ = wc.scan_matrix(walk, crowd.bssids, dedup=False, max_age_s=settings.wifi_max_age_s)
    nh = crowd.settings.not_heard_dbm
    if scan_t.size:
        q = wc.prepare(_nearest_scan_rows(wt, scan_t, rss_fresh), nh)
        m = crowd.signal_map
        knn = wifi.FingerprintLocator(m.mean_dbm, m.positions_m, m.floors, method="wknn", k=settings.knn_k)
        put("wifi_knn", np.asarray(knn.locate(q)[0]))
        grid = wifi.GridPosterior(crowd.model, settings.grid_spacing_m)
        put("wifi_model", np.asarray(grid.locate(q)["positions_m"]))
        all_fixes = np.asarray(grid.locate(wc.prepare(rss_fresh, nh))["positions_m"])
        heard = np.isfinite(rss_fresh).any(axis=1)
    # PDR: calibrated steps, headings rotated into the floor frame by the training yaw offset.
    steps = ph.rescale(steps_raw, cal.options)
    heading = steps.heading_rad + cal.yaw_offset_rad
    length_sd = settings.step_length_sd_fraction * steps.length_m
    pdr_steps = fusion.Steps.from_polar(steps.t_s, steps.length_m, heading, length_sd, settings.step_heading_sd_rad)
    put("pdr_only", ph.pdr_track(steps, wxy[0], wt, yaw_offset_rad=cal.yaw_offset_rad))
    if peer is not None and scan_t.size and heard.sum() >= 1 and len(pdr_steps) >= 1:
        tic = time.perf_counter()
        # Positions before the first step and after each step: M + 1 times, M displacements.
        t_nodes = np.r_[min(float(wt[0]), float(pdr_steps.times_s[0]) - 0.5), pdr_steps.times_s]
        track = peer.costmin_track(t_nodes, pdr_steps.displacements_m, scan_t[heard], all_fixes[heard])
        score.seconds["peer_costmin"] = time.perf_counter() - tic
        put("peer_costmin", peer.evaluate_at(wt, t_nodes, track))
    if len(pdr_steps) == 0:
        return score
    # The tracker: WiFi readings re-timed to their last-seen time, each measurement once.
    t_all, rss_all, ages_all = wc.scan_matrix(walk, crowd.bssids, dedup=True, max_age_s=None)
    options = settings.tracker_options(unknown_start_heading_sd_rad=max(cal.yaw_offset_spread_rad, 1e-3),
                                       start_heading_offset_sd_rad=max(cal.yaw_offset_spread_rad, 1e-3))
    observations, _ = fusion.make_wifi_observations(t_all, rss_all, ages_all, options, at_own_time=True)
    known = {"position_m": wxy[0], "floor": floor_number, "heading_offset_rad": 0.0, "time_s": float(wt[0])}
    smoother = fusion.SmootherOptions(num_trajectories=settings.smoother_trajectories, seed=settings.seed)
    runs = {
        "fusion_unknown_start": dict(start=None, smoother=smoother, keys=("fusion_unknown_start", "fusion_smoother")),
        "fusion_known_start": dict(start=known, smoother=None, keys=("fusion_known_start",)),
        "fusion_no_walls": dict(start=None, smoother=smoother, plan=None, keys=(None, "fusion_no_walls")),
        "fusion_no_wifi": dict(start=known, smoother=smoother, observations=[], model=None, keys=(None, "fusion_no_wifi")),
        "fusion_no_heading_offset": dict(start=None, smoother=smoother, keys=(None, "fusion_no_heading_offset"),
                                         options=replace_options(options, heading_offset_walk_rad=0.0,
                                                                 unknown_start_heading_sd_rad=0.0)),
    }
    for name, run in runs.items():
        tic = time.perf_counter()
        result = fusion.track(pdr_steps, run.get("observations", observations), plan=run.get("plan", plan),
                              wifi_model=run.get("model", crowd.model), start=run["start"],
                              options=run.get("options", options), smoother=run["smoother"])
        seconds = time.perf_counter() - tic
        filtered, smoothed = run["keys"][0], run["keys"][-1] if len(run["keys"]) > 1 else None
        if filtered:
            put(filtered, _interp_track(wt, pdr_steps.times_s, result["mean_m"]))
            score.seconds[filtered] = seconds
        if smoothed:
            put(smoothed, _interp_track(wt, pdr_steps.times_s, result["smoothed_m"]))
            score.seconds[smoothed] = seconds
    return score


def replace_options(options: fusion.TrackerOptions, **changes) -> fusion.TrackerOptions:
    """A copy of TrackerOptions with some fields changed."""
    names = [n for n in dir(options) if not n.startswith("_") and not callable(getattr(options, n))]
    values = {n: getattr(options, n) for n in names}
    values.update(changes)
    return fusion.tracker_options(**values)


def evaluate_floor(floor_dir: Path, floor_number: int, settings: RealSettings, peer=None, progress=None) -> List[WalkScore]:
    """Every method on every walk of one floor, k-fold by walk."""
    floor = read_ilc_floor(floor_dir)
    walks = [floor.walk(i) for i in range(floor.n_walks)]
    plan = load_floor_plan(floor.geojson_path, floors=[floor_number], origin_lon_lat="outline_sw")
    steps = [ph.handheld_steps(w) for w in walks]
    scores: List[WalkScore] = []
    for test_idx in _folds(len(walks), settings.folds, settings.seed):
        test = set(test_idx.tolist())
        train = [w for i, w in enumerate(walks) if i not in test]
        train_steps = [s for i, s in enumerate(steps) if i not in test]
        cal = ph.calibrate_handheld(train, steps_cache=train_steps)
        crowd = wc.build_crowd_map(train, wc.CrowdMapSettings(), floor_number)
        jobs = [(walks[i], steps[i]) for i in test_idx]
        with ThreadPoolExecutor(max_workers=max(1, settings.threads)) as pool:
            futures = [pool.submit(_score_walk, w, floor.name, floor_number, plan, crowd, cal, s, settings, peer)
                       for w, s in jobs]
            for f in futures:
                scores.append(f.result())
                if progress:
                    progress()
    return scores


def _stats(errors: np.ndarray) -> Dict[str, float]:
    return {"mean_m": float(np.mean(errors)), "median_m": float(np.median(errors)),
            "p90_m": float(np.percentile(errors, 90)), "n_waypoints": int(errors.size)}


def summarize(scores: Sequence[WalkScore], settings: RealSettings, seconds: float) -> dict:
    """The JSON contract of ``indoorloc fusion evaluate`` (docs/fusion_real.md):
    ``{"methods": {NAME: {"mean_m", "median_m", "p90_m", "n_waypoints"}}, "waypoints": [{"floor",
    "walk", "method", "t_s", "error_m"}], "settings": {...}}`` plus informative extras
    (``per_floor``, ``seconds``)."""
    methods, per_floor, rows = {}, {}, []
    for name in METHODS:
        e = [s.errors_m[name] for s in scores if name in s.errors_m]
        if not e:
            continue
        methods[name] = _stats(np.concatenate(e))
        for fl in sorted({s.floor for s in scores}):
            ef = [s.errors_m[name] for s in scores if s.floor == fl and name in s.errors_m]
            if ef:
                per_floor.setdefault(fl, {})[name] = _stats(np.concatenate(ef))
    for s in scores:
        for name, e in s.errors_m.items():
            for t, v in zip(s.t_s, e):
                rows.append({"floor": s.floor, "walk": s.walk, "method": name, "t_s": round(float(t), 3),
                             "error_m": round(float(v), 4)})
    walk_seconds = {}
    for name in METHODS:
        v = [s.seconds[name] for s in scores if name in s.seconds]
        if v:
            walk_seconds[name] = float(np.mean(v))
    return {"methods": methods, "waypoints": rows, "settings": asdict(settings), "per_floor": per_floor,
            "seconds": round(seconds, 2), "mean_seconds_per_walk": walk_seconds}


def evaluate(data_root: Optional[Path] = None, floors: Sequence[str] = FLOORS, settings: Optional[RealSettings] = None,
             progress=None) -> dict:
    """``indoorloc fusion evaluate``: every method on every floor; the JSON dict of :func:`summarize`."""
    settings = settings or RealSettings()
    root = Path(data_root) if data_root else default_site_root()
    if not root.is_dir():
        raise FileNotFoundError(f"indoorloc: argument 'data_root': {root} is not a folder of ILC floors")
    peer = _peer()
    tic = time.perf_counter()
    scores: List[WalkScore] = []
    for name in floors:
        number = int("".join(ch for ch in name if ch.isdigit()) or 0) * (-1 if name.upper().startswith("B") else 1)
        scores += evaluate_floor(root / name, number, settings, peer, progress)
    return summarize(scores, settings, time.perf_counter() - tic)


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
    lines.append("")
    lines.append(f"{len({(w['floor'], w['walk']) for w in result['waypoints']})} walks in {result['seconds']:.0f} s.")
    return "\n".join(lines)
