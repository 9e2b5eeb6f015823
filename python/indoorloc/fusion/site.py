"""A site model in one file: built once from survey walks with waypoints, grown walk by walk,
used to track new walks (docs/your_building.md).

Per floor it keeps the walkable plan, the WiFi fingerprints (iBeacon sightings where present),
the handheld-PDR calibration and the tracker settings, with provenance (walk ids and files,
library version, build time). The file format is :mod:`indoorloc.fusion.site_store` (SQLite).

What is stored is per walk (fingerprints before any vocabulary filter, the PDR between
waypoints), and what depends on all walks of a floor (AP vocabulary and reliabilities, the
calibration) is derived from it, so :meth:`Site.add` of a walk gives the same site as a build
that included it. Example::

    from indoorloc.fusion.site import Site
    site = Site.build("ilc2020_site2", "site2.db", floors=["F8"])
    track = Site.open("site2.db").track("walk.txt", floor="auto")
    track.xy_m, track.errors_m
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Union

import numpy as np

from indoorloc import _core
from indoorloc.pdr import handheld as ph
from indoorloc.fusion import wifi_fixes
from indoorloc._core.fusion import FloorPlan, FloorPlanOptions
from indoorloc.fusion import site_model
from indoorloc.fusion import site_settings
from indoorloc.fusion import site_store as store
from indoorloc.fusion import site_tables as tables
from indoorloc.fusion.grid import GridTracker
from indoorloc.io.errors import FormatError, RecordingWarning
from indoorloc.io.ilc2020 import read_ilc_walk
from indoorloc.io.survey_layout import survey_floors

WalkLike = Union[str, os.PathLike, Any]


@dataclass
class FloorModels:
    """One floor of a site, ready to track: plan, calibration, fingerprints, grid tracker."""

    name: str
    number: int
    origin_lon_lat: tuple
    plan: FloorPlan
    calibration: ph.HandheldCalibration
    database: wifi_fixes.FingerprintDatabase
    tracker: GridTracker
    #: The smoother's second pass (``site_model.second_pass_options``), None when the settings
    #: have one pass (``TrackSettings.second_pass_start_sd_m`` 0).
    second_pass_tracker: Optional[GridTracker] = None


@dataclass
class WalkTrack:
    """A walk tracked on a site: per step (M) times [s since the walk's first record], position
    (M, 2) [m, floor frame] and covariance (M, 3) = (xx, xy, yy) [m²]; the floor and its
    probability (calibrated when the floor was identified: ``fusion.floor_evidence.FloorCalibration``;
    1 when it was given); the waypoints and the errors at them [m] when the walk has waypoints."""

    walk_id: str
    source: str
    floor: str
    floor_number: int
    floor_probability: float
    floor_probabilities: Dict[str, float]
    smoothed: bool
    t0_unix_ms: int
    times_s: np.ndarray
    xy_m: np.ndarray
    covariance_m2: np.ndarray
    origin_lon_lat: tuple
    waypoint_t_s: np.ndarray
    waypoint_xy_m: np.ndarray
    errors_m: Optional[np.ndarray]
    header_floor: str = ""   #: the walk header's FloorName ("" when absent)
    #: The posterior's own covariance (M, 3) [m²]; ``covariance_m2`` is the calibrated one
    #: (GridTrackerOptions, "Calibration of the returned covariances").
    posterior_covariance_m2: Optional[np.ndarray] = None
    #: The WiFi fixes' centres (the kNN estimate of each pooled scan): times [s] and (F, 2) [m].
    fix_t_s: Optional[np.ndarray] = None
    fix_xy_m: Optional[np.ndarray] = None


#: Site.grow: largest posterior sd [m] of a smoothed position used to place a fingerprint. Chosen
#: by leave-one-floor-out over {2, 4, 8, 16, 32} m on the shared site (experiments/site_growth.py,
#: docs/your_building.md "Growing the map"): 8 m for five of six held-out floors (4 m for B1) and
#: on all six floors pooled.
GROW_MAX_SD_M = 8.0
#: Weight of a grown fingerprint's fix component relative to a surveyed one: fixed in advance
#: (not cross-validated).
GROW_WEIGHT = 0.5


def _confident_positions(track: "WalkTrack", max_sd_m: float):
    """t (Q,) [s] -> (xy (Q, 2), valid (Q,)): the smoothed track interpolated at t, valid inside
    the track's span where the largest sd of the interpolated posterior covariance (the model's own
    spread, on which GROW_MAX_SD_M was chosen) is at most max_sd_m."""
    c = track.posterior_covariance_m2 if track.posterior_covariance_m2 is not None else track.covariance_m2
    t_tr, xy, c = track.times_s, track.xy_m, np.asarray(c, float)
    half = 0.5 * (c[:, 0] + c[:, 2])
    largest_sd = np.sqrt(np.maximum(half + np.sqrt((0.5 * (c[:, 0] - c[:, 2])) ** 2 + c[:, 1] ** 2), 0.0))

    def at(t):
        t = np.asarray(t, float)
        pos = np.c_[np.interp(t, t_tr, xy[:, 0]), np.interp(t, t_tr, xy[:, 1])]
        ok = (t >= t_tr[0]) & (t <= t_tr[-1]) & (np.interp(t, t_tr, largest_sd) <= max_sd_m)
        return pos, ok
    return at


def _read_walk(walk: WalkLike):
    return read_ilc_walk(walk) if isinstance(walk, (str, os.PathLike)) else walk


class Site:
    """A site file opened for tracking and growing (:meth:`open`, :meth:`build`)."""

    def __init__(self, path: Path):
        self.path = Path(path)
        con = store.connect(self.path)
        try:
            self.meta = store.meta(con)
            row = con.execute("SELECT settings FROM tracker_settings WHERE name = 'default'").fetchone()
            if row is None:
                raise store.SiteFileError(f"indoorloc: site file {self.path}: no tracker settings")
            # A file written before part of floor identification keeps the evidence it was saved
            # with (and warns): site_settings.
            try:
                self.settings = site_settings.stored_track_settings(json.loads(row[0]), str(self.path))
                self.settings.validate()
            except (ValueError, TypeError) as exc:  # a damaged value: say which file and which setting
                raise store.SiteFileError(f"indoorloc: site file {self.path}: its tracker settings are not "
                                          f"usable: {exc}") from None
            self._floors = {name: (int(num), (lon, lat)) for name, num, lon, lat in con.execute(
                "SELECT name, number, origin_lon, origin_lat FROM floors ORDER BY number")}
        finally:
            con.close()
        self._models: Dict[str, FloorModels] = {}
        self._all: Optional[tuple] = None

    # ---- opening and building -------------------------------------------------------------
    @classmethod
    def open(cls, path: Union[str, os.PathLike]) -> "Site":
        """Open a site file; SiteFileError (a ValueError) naming the file when it is not one of
        this format version or is damaged."""
        return cls(Path(path))

    @classmethod
    def build(cls, survey_dir: Union[str, os.PathLike], path: Union[str, os.PathLike],
              floors: Optional[Sequence[str]] = None, settings: Optional[site_model.TrackSettings] = None,
              progress: Optional[Callable[[str], None]] = None) -> "Site":
        """Build a site file from a survey folder (ILC 2020 or Kaggle 2021 layout,
        :func:`indoorloc.io.survey_layout.survey_floors`), all floors by default (a floor folder
        with walks but no plan is then skipped with a RecordingWarning; named in ``floors``, it
        is a ValueError). A walk file that
        cannot be read, or has fewer than two waypoints (e.g. cut short), is skipped with a
        RecordingWarning and listed in the meta table (``skipped_walks``); a floor left without
        any survey walk is a ValueError naming the floor and the reasons. Written to a temporary file and renamed: an existing
        ``path`` is replaced only when the build succeeded. ``progress(walk_id)`` after each walk."""
        settings = settings or site_model.TrackSettings()
        settings.validate()
        survey = survey_floors(Path(survey_dir), floors)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent)
        os.close(fd)
        os.unlink(tmp)
        try:
            con = store.create(Path(tmp))
            built = tables.now()
            for key, value in (("format", "indoorloc.site"), ("format_version", str(store.FORMAT_VERSION)),
                               ("library_version", _core.__version__), ("built", built),
                               ("modified", built), ("survey_dir", str(Path(survey_dir).resolve()))):
                con.execute("INSERT INTO meta VALUES (?, ?)", (key, value))
            con.execute("INSERT INTO tracker_settings VALUES ('default', ?)", (json.dumps(settings.to_dict()),))
            grid = settings.grid_options.replace(spatial_median=settings.point_estimate == "median").to_dict()
            con.executemany("INSERT INTO grid_options VALUES (?, ?)", [(k, float(v)) for k, v in sorted(grid.items())])
            for fl in survey:
                tables.insert_floor(con, fl)
            seq, skipped = 0, {}
            for fl in survey:
                surveyed = 0
                for wp in fl.walk_paths:
                    try:
                        walk = read_ilc_walk(wp)
                        tables.check_survey_waypoints(walk, str(wp))
                    except (FormatError, ValueError) as exc:
                        # The loader rule: a walk that cannot be read, or cannot be a survey walk
                        # (fewer than two waypoints, e.g. a file cut short), is skipped, said, listed.
                        warnings.warn(f"indoorloc: walk {wp} skipped: {exc}", RecordingWarning, stacklevel=2)
                        skipped[str(wp)] = str(exc)
                        continue
                    tables.insert_survey_walk(con, walk, fl.name, seq, settings, str(wp))
                    seq += 1
                    surveyed += 1
                    if progress:
                        progress(wp.stem)
                if not surveyed:
                    reasons = "; ".join(skipped[str(wp)] for wp in fl.walk_paths if str(wp) in skipped)
                    raise ValueError(f"indoorloc: argument 'survey_dir': floor {fl.name} has no survey walk "
                                     f"with waypoints to build from ({reasons or 'no walk file'})")
                tables.recalibrate(con, fl.name)
                tables.store_fingerprint_columns(con, fl.name, settings.fixes)
            con.execute("INSERT INTO meta VALUES ('skipped_walks', ?)", (json.dumps(skipped),))
            con.execute("COMMIT")
            con.close()
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise
        return cls(path)

    def add(self, walks: Sequence[WalkLike], floor: Optional[str] = None,
            progress: Optional[Callable[[str], None]] = None) -> List[str]:
        """Add survey walks (with waypoints) to the site, in one transaction: if any walk fails,
        the file keeps its old content. The floor of each walk is ``floor`` or the walk's
        ``FloorName`` header. Returns the walk ids added."""
        added = []
        with self._write_transaction() as con:
            seq = con.execute("SELECT COALESCE(MAX(seq) + 1, 0) FROM walks").fetchone()[0]
            touched = set()
            for w in walks:
                walk = _read_walk(w)
                name = self._walk_floor(walk, floor)
                tables.insert_survey_walk(con, walk, name, seq, self.settings, str(getattr(walk, "path", w)))
                seq += 1
                touched.add(name)
                added.append(walk.walk_id)
                if progress:
                    progress(walk.walk_id)
            for name in sorted(touched):
                tables.recalibrate(con, name)
                tables.store_fingerprint_columns(con, name, self.settings.fixes)
        return added

    @contextlib.contextmanager
    def _write_transaction(self):
        """One write transaction on the file (BEGIN IMMEDIATE ... COMMIT, with the modified time):
        on any exception it is rolled back and the file keeps its old content. The models read
        from the file are dropped afterwards."""
        con = store.connect(self.path, write=True)
        try:
            con.execute("BEGIN IMMEDIATE")
            yield con
            con.execute("INSERT OR REPLACE INTO meta VALUES ('modified', ?)", (tables.now(),))
            con.execute("COMMIT")
        except BaseException:
            if con.in_transaction:
                con.execute("ROLLBACK")
            raise
        finally:
            con.close()
            self._models.clear()
            self._all = None

    def grow(self, walks: Sequence[WalkLike], floor: Optional[str] = None, max_sd_m: Optional[float] = None,
             weight: Optional[float] = None, progress: Optional[Callable[[str], None]] = None) -> Dict[str, int]:
        """Add walks *without* waypoints: each tracked (default tracker, smoothed; floor as in
        :meth:`track`) on the current site, and its WiFi fingerprints placed at the smoothed
        positions where the posterior is confident (largest sd of the smoothed covariance at most
        ``max_sd_m`` [m], default :data:`GROW_MAX_SD_M`), stored with weight ``weight`` (default
        :data:`GROW_WEIGHT`; a fix component from them counts that much relative to a surveyed
        one). All walks are tracked on the site as it was, then written in one transaction.
        Returns ``{walk id: fingerprints added}``."""
        max_sd_m = GROW_MAX_SD_M if max_sd_m is None else float(max_sd_m)
        weight = GROW_WEIGHT if weight is None else float(weight)
        if not (max_sd_m > 0 and math.isfinite(max_sd_m)):
            raise ValueError(f"indoorloc: argument 'max_sd_m': must be finite and > 0, got {max_sd_m!r}")
        if not 0 < weight <= 1:
            raise ValueError(f"indoorloc: argument 'weight': must be in (0, 1], got {weight!r}")
        placed = []
        for w in walks:
            walk = _read_walk(w)
            tr = self.track(walk, floor=floor)
            placed.append((walk, tr, wifi_fixes.walk_fingerprints(walk, self.settings.fixes,
                                                           positions_at=_confident_positions(tr, max_sd_m),
                                                           span_s=(tr.times_s[0], tr.times_s[-1]))))
            if progress:
                progress(walk.walk_id)
        out = {}
        with self._write_transaction() as con:
            seq = con.execute("SELECT COALESCE(MAX(seq) + 1, 0) FROM walks").fetchone()[0]
            for walk, tr, got in placed:
                if con.execute("SELECT 1 FROM walks WHERE id = ?", (walk.walk_id,)).fetchone():
                    raise ValueError(f"indoorloc: walk {tr.source}: walk id {walk.walk_id} is already in the site")
                con.execute("INSERT INTO walks VALUES (?, ?, ?, ?, 'grown', ?, ?, ?, ?)",
                            (walk.walk_id, seq, tr.floor, tr.source, weight, tables.now(), int(np.size(walk.waypoint_t_s)),
                             float(walk.duration_s)))
                seq += 1
                out[walk.walk_id] = tables.insert_fingerprints(con, tr.floor, walk.walk_id, got, weight)
            for name in sorted({tr.floor for _, tr, _ in placed}):
                tables.store_fingerprint_columns(con, name, self.settings.fixes)
        return out

    # ---- reading ------------------------------------------------------------------------
    @property
    def floors(self) -> List[str]:
        """Floor names in building order."""
        return list(self._floors)

    def _walk_floor(self, walk: Any, floor: Optional[str]) -> str:
        name = floor or walk.metadata.get("FloorName") or ""
        if not name:
            raise ValueError(f"indoorloc: walk {getattr(walk, 'path', walk.walk_id)}: no FloorName in its header; "
                             f"name the floor (one of {self.floors})")
        if name not in self._floors:
            raise ValueError(f"indoorloc: walk {getattr(walk, 'path', walk.walk_id)}: floor {name!r} is not in site "
                             f"{self.path} (floors: {self.floors})")
        return name

    def floor_models(self, name: str) -> FloorModels:
        """The models of one floor, read from the file once."""
        if name not in self._floors:
            raise ValueError(f"indoorloc: argument 'floor': {name!r} is not in site {self.path} (floors: {self.floors})")
        if name not in self._models:
            con = store.connect(self.path)
            try:
                number, origin = self._floors[name]
                plan = tables.plan(con, name, number, origin)
                cal = tables.calibration(con, name)
                database = tables.database(con, [name], self.settings.fixes)
            finally:
                con.close()
            tracker = site_model.survey_anchored(GridTracker(plan, site_model.floor_grid_options(self.settings, cal)),
                                                 plan, database)
            # The same grid and survey anchors with the second pass's options.
            second = (tracker.with_options(site_model.second_pass_options(tracker.options, self.settings))
                      if self.settings.second_pass_start_sd_m > 0 else None)
            self._models[name] = FloorModels(name, number, origin, plan, cal, database, tracker, second)
        return self._models[name]

    def _all_floors(self) -> tuple:
        """(all-floor identification tracker, floor numbers, database, its per-floor AP rates) for --floor auto."""
        if self._all is None:
            models = [self.floor_models(n) for n in self.floors]
            plan = FloorPlan([m.plan.geometry(0) for m in models], FloorPlanOptions())
            # The walk's floor is unknown: the widest calibrated offset spread of the floors.
            _, spread = site_model.identification_calibration([m.calibration for m in models])
            tracker = GridTracker(plan, site_model.identification_grid_options(self.settings, spread))
            con = store.connect(self.path)
            try:
                database = tables.database(con, self.floors, self.settings.fixes)
            finally:
                con.close()
            numbers = [m.number for m in models]
            self._all = (tracker, numbers, database, site_model.ap_floor_rates(database, numbers, self.settings))
        return self._all

    def track(self, walk: WalkLike, floor: Optional[str] = None, smooth: bool = True) -> WalkTrack:
        """Track one walk (a walk file or an ``IlcWalk``) with the default tracker.

        ``floor``: a floor name, ``"auto"`` (identified from the walk's WiFi and motion over all
        floors: the floor with the most evidence, then the floor-given tracker on it), or None
        (the walk header's ``FloorName``; ``auto`` when it has none). ValueError naming the walk
        and floor when that floor is not in the site."""
        walk = _read_walk(walk)
        src = str(getattr(walk, "path", walk.walk_id))
        if floor is None:
            floor = walk.metadata.get("FloorName") or "auto"
            if floor != "auto" and floor not in self._floors:
                raise ValueError(f"indoorloc: walk {src}: its floor {floor!r} is not in site {self.path} "
                                 f"(floors: {self.floors}); pass floor='auto' or one of them")
        steps_raw = ph.handheld_steps(walk)
        probabilities = {}
        if floor == "auto":
            tracker_all, numbers, database, rates = self._all_floors()
            # Steps rotated with the first floor's calibration for identification; then the floor's own.
            # The same code as ``fusion evaluate``'s floor identification (site_model.identify_floor).
            first_cal, _ = site_model.identification_calibration([self.floor_models(n).calibration
                                                                  for n in self.floors])
            weight = self.settings.identification_ap_weight
            queries = wifi_fixes.walk_queries(walk, database)  # for the AP evidence and the fixes
            evidence = site_model.walk_floor_evidence(walk, database, rates, self.settings, queries)
            ident = site_model.identify_floor(tracker_all, numbers, site_model.tracker_steps(
                steps_raw, first_cal, self.settings), wifi_fixes.fixes_for_walk(walk, database, queries=queries),
                evidence["ap_log_likelihood"], weight, self.settings.floor_calibration(), evidence["match_distance_db"],
                evidence["classifier_log_likelihood"], self.settings.identification_classifier_weight)
            by_number = {n: name for name, (n, _) in self._floors.items()}
            floor = by_number[ident["floor"]]
            if evidence["floor_changes"]:
                # The trackers keep a walk on one floor; say so when its WiFi suggests otherwise.
                seq = [by_number[int(n)] for n in evidence["query_floors"]]
                at = [f"{seq[k]} -> {seq[k + 1]} at {evidence['query_t_s'][k + 1]:.0f} s"
                      for k in range(len(seq) - 1) if seq[k] != seq[k + 1]]
                warnings.warn(f"indoorloc: walk {src}: its WiFi suggests it changes floor ({', '.join(at)}); "
                              f"it is tracked on one floor, {floor}", RecordingWarning, stacklevel=2)
            probabilities = {by_number[n]: p for n, p in ident["probabilities"].items()}
        m = self.floor_models(floor) if floor in self._floors else self._walk_floor(walk, floor)
        steps = site_model.tracker_steps(steps_raw, m.calibration, self.settings)
        if len(steps) == 0:
            raise ValueError(f"indoorloc: walk {src}: no step detected, nothing to track")
        fixes = wifi_fixes.fixes_for_walk(walk, m.database)
        median = self.settings.point_estimate == "median"
        r = site_model.run_default(m.tracker, steps, fixes, smooth=smooth, second_pass=m.second_pass_tracker,
                                   floor=m.number, median=median)
        gaps = int(getattr(r.get("summary"), "smoother_gap_steps", 0) or 0) if smooth else 0
        if gaps:
            warnings.warn(f"indoorloc: walk {src}: at {gaps} of {len(steps)} steps the walk before and after cannot "
                          "be joined by the motion model (steps lost, or fixes far off); the smoothed track uses the "
                          "causal filter's estimate there and is less reliable", RuntimeWarning, stacklevel=2)
        key = ("smoothed_median_m" if median else "smoothed_m") if smooth else ("median_m" if median else "mean_m")
        cov = np.asarray(r["smoothed_covariance_m2" if smooth else "covariance_m2"], float)
        posterior = np.asarray(r["smoothed_posterior_covariance_m2" if smooth else "posterior_covariance_m2"], float)
        wt = np.asarray(walk.waypoint_t_s, float)
        wxy = np.asarray(walk.waypoint_xy_m, float).reshape(-1, 2)
        # Waypoints are in their own floor's frame: errors only when the walk is on the tracked floor.
        header_floor = str(walk.metadata.get("FloorName") or "")
        comparable = wt.size and header_floor in ("", floor)
        errors = site_model.walk_errors_m(steps.times_s, r[key], wt, wxy) if comparable else None
        return WalkTrack(walk.walk_id, src, floor, m.number, probabilities.get(floor, 1.0), probabilities or {floor: 1.0},
                         bool(smooth), int(walk.t0_unix_ms), np.asarray(steps.times_s, float),
                         np.asarray(r[key], float), cov, m.origin_lon_lat, wt, wxy, errors, header_floor, posterior,
                         np.asarray(fixes.times_s, float), wifi_fixes.fix_centres(fixes) if len(fixes) else np.zeros((0, 2)))

    def live(self, floor: str, start: Optional[dict] = None, standing_after_s: Optional[float] = None):
        """A live tracker on one floor of the site (:class:`indoorloc.fusion.live.LiveTracker`):
        raw sensor events in time order (accelerometer, gyroscope, rotation vector, WiFi scans) in,
        the causal filter's estimate after each out; a recorded walk replayed event by event gives
        the track of :func:`indoorloc.fusion.live.causal_track` on the same models. ``start``: None
        (unknown start) or a known start as in :func:`indoorloc.fusion.track_grid`.
        ``standing_after_s`` [s]: a fix no step has applied this long after its scan is applied at
        a standing step (None: ``live.STANDING_AFTER_S``, 1 s; 0: fixes wait for a step)."""
        from indoorloc.fusion.live import STANDING_AFTER_S, LiveTracker

        m = self.floor_models(floor)
        return LiveTracker(m.tracker, m.calibration, m.database, start=start,
                           step_length_sd_fraction=self.settings.step_length_sd_fraction,
                           step_heading_sd_rad=self.settings.step_heading_sd_rad,
                           standing_after_s=STANDING_AFTER_S if standing_after_s is None else float(standing_after_s))

    def write_viewer_html(self, path: Union[str, os.PathLike], tracks: Sequence[WalkTrack],
                          title: str = "indoorloc track") -> Path:
        """The browser viewer (:mod:`indoorloc.fusion.viewer`) of tracks from :meth:`track`: each
        track on its floor's plan with its 95 % region, waypoints and WiFi fix centres; one
        self-contained offline HTML file, written atomically."""
        from indoorloc.fusion import viewer

        floors = [viewer.viewer_floor_from_plan(self.floor_models(name).plan, 0, name)
                  for name in dict.fromkeys(t.floor for t in tracks)]
        views = []
        for t in tracks:
            c = np.asarray(t.covariance_m2, float)
            sd = np.sqrt(np.maximum(c[:, [0, 2]], 0.0))
            with np.errstate(invalid="ignore", divide="ignore"):
                rho = np.clip(np.nan_to_num(c[:, 1] / (sd[:, 0] * sd[:, 1])), -1.0, 1.0)
            on_floor = t.errors_m is not None and t.waypoint_t_s.size > 0
            views.append(viewer.ViewerTrack(
                name=t.walk_id, floor=t.floor, t_s=t.times_s, xy_m=t.xy_m, sd_m=sd, xy_correlation=rho,
                waypoints_t_s=t.waypoint_t_s if on_floor else None, waypoints_xy_m=t.waypoint_xy_m if on_floor else None,
                fixes_t_s=t.fix_t_s if t.fix_t_s is not None and t.fix_t_s.size else None,
                fixes_xy_m=t.fix_xy_m if t.fix_t_s is not None and t.fix_t_s.size else None))
        return viewer.write_viewer_html(path, floors, views, title=title)

    def leave_one_walk_out(self, name: str, progress: Optional[Callable[[str], None]] = None) -> Dict[str, Any]:
        """The expected error on a floor: each survey walk tracked (default tracker, floor given)
        on the floor's models without it (calibration and fingerprints rebuilt from the others),
        re-read from its source file. Returns ``{"points": (W, 3) x, y [m] of every waypoint and
        its error [m], "stats": mean/median/p90, "walks": n, "missing": [walk files not found]}``."""
        m = self.floor_models(name)
        con = store.connect(self.path)
        try:
            walks = con.execute("SELECT id, source FROM walks WHERE floor = ? AND kind = 'survey' ORDER BY seq",
                                (name,)).fetchall()
            points, missing = [], []
            for walk_id, source in walks:
                if not Path(source).is_file():
                    missing.append(source)
                    continue
                walk = read_ilc_walk(source)
                cal = tables.calibrate(con, name, exclude_walk=walk_id)
                database = tables.database(con, [name], self.settings.fixes, exclude_walk=walk_id)
                tracker = site_model.survey_anchored(
                    GridTracker(m.plan, site_model.floor_grid_options(self.settings, cal)), m.plan, database)
                steps = site_model.tracker_steps(ph.handheld_steps(walk), cal, self.settings)
                if len(steps):
                    r = site_model.run_default(tracker, steps, wifi_fixes.fixes_for_walk(walk, database))
                    key = "smoothed_median_m" if self.settings.point_estimate == "median" else "smoothed_m"
                    e = site_model.walk_errors_m(steps.times_s, r[key], walk.waypoint_t_s, walk.waypoint_xy_m)
                    points.append(np.c_[np.asarray(walk.waypoint_xy_m, float).reshape(-1, 2), e])
                if progress:
                    progress(walk_id)
        finally:
            con.close()
        p = np.vstack(points) if points else np.zeros((0, 3))
        stats = None if not p.size else {"mean_m": float(p[:, 2].mean()), "median_m": float(np.median(p[:, 2])),
                                         "p90_m": float(np.percentile(p[:, 2], 90)), "n_waypoints": int(p.shape[0])}
        return {"points": p, "stats": stats, "walks": len(points), "missing": missing}

    def info(self) -> Dict[str, Any]:
        """Provenance and a per-floor summary: walks, fingerprints, access points, beacons,
        walkable area [m²], survey coverage (fraction of the walkable area within 5 m of a
        fingerprint), the fraction of the surveyed fingerprints (weight 1) that the plan puts
        inside an obstacle or outside the outline (where the survey contradicts the plan; the
        tracker opens those cells, ``GridTrackerOptions.survey_walkable_radius_m``) and the PDR
        calibration."""
        con = store.connect(self.path)
        try:
            out = {"path": str(self.path), "size_bytes": self.path.stat().st_size, "meta": store.meta(con),
                   "settings": self.settings.to_dict(), "floors": {}}
            for name, (number, origin) in self._floors.items():
                area = con.execute("SELECT walkable_area_m2 FROM floors WHERE name = ?", (name,)).fetchone()[0]
                n_walks = con.execute("SELECT COUNT(*) FROM walks WHERE floor = ?", (name,)).fetchone()[0]
                n_fp = con.execute("SELECT COUNT(*) FROM fingerprints WHERE floor = ?", (name,)).fetchone()[0]
                n_b = con.execute("SELECT COUNT(DISTINCT beacon) FROM beacons WHERE floor = ?", (name,)).fetchone()[0]
                ids = set()
                for (blob,) in con.execute("SELECT ap_ids FROM fingerprints WHERE floor = ?", (name,)):
                    ids.update(np.frombuffer(blob, "<i4").tolist())
                cal = con.execute("SELECT k, yaw_offset_rad, yaw_offset_spread_rad FROM pdr_calibration WHERE floor = ?",
                                  (name,)).fetchone()
                out["floors"][name] = {
                    "number": number, "origin_lon_lat": list(origin), "walks": n_walks, "fingerprints": n_fp,
                    "access_points": len(ids), "beacons": n_b, "walkable_area_m2": round(area, 1),
                    "survey_coverage": round(self.coverage(name)["fraction_within_5m"], 4),
                    "survey_off_plan": round(self._survey_off_plan(con, name), 4),
                    "pdr_calibration": None if cal is None else {
                        "k": cal[0], "yaw_offset_deg": math.degrees(cal[1]), "yaw_offset_spread_deg": math.degrees(cal[2])}}
            out["walks"] = [dict(zip(("id", "floor", "source", "kind", "weight", "added"), r)) for r in con.execute(
                "SELECT id, floor, source, kind, weight, added FROM walks ORDER BY seq")]
        finally:
            con.close()
        return out

    def _survey_off_plan(self, con, name: str) -> float:
        """Fraction of the floor's surveyed fingerprints (weight 1) that are not walkable on the plan
        as drawn (0 when there is none)."""
        number, origin = self._floors[name]
        xy = np.array(con.execute("SELECT x_m, y_m FROM fingerprints WHERE floor = ? AND weight = 1", (name,)).fetchall(),
                      float).reshape(-1, 2)
        if xy.shape[0] == 0:
            return 0.0
        plan = tables.plan(con, name, number, origin)
        return float(np.mean(~np.asarray(plan.is_walkable(xy, 0), bool)))

    def coverage(self, name: str, cell_m: float = 2.0) -> Dict[str, Any]:
        """Survey coverage of a floor: on a grid of ``cell_m`` cells over the plan, the distance
        [m] from each walkable cell centre to the nearest fingerprint (NaN: not walkable), and
        the fraction of walkable cells within 5 m."""
        from scipy.spatial import cKDTree

        if name not in self._floors:
            raise ValueError(f"indoorloc: argument 'floor': {name!r} is not in site {self.path}")
        con = store.connect(self.path)
        try:
            number, origin = self._floors[name]
            plan = tables.plan(con, name, number, origin)
            xy = np.array(con.execute("SELECT x_m, y_m FROM fingerprints WHERE floor = ?", (name,)).fetchall(),
                          float).reshape(-1, 2)
        finally:
            con.close()
        b = np.asarray(plan.bounds(0), float).ravel()
        xs = np.arange(b[0] + cell_m / 2, b[2], cell_m)
        ys = np.arange(b[1] + cell_m / 2, b[3], cell_m)
        gx, gy = np.meshgrid(xs, ys)
        pts = np.c_[gx.ravel(), gy.ravel()]
        walkable = np.asarray(plan.is_walkable(pts, 0), bool)
        dist = np.full(pts.shape[0], np.nan)
        if xy.shape[0] and walkable.any():
            dist[walkable] = cKDTree(xy).query(pts[walkable])[0]
        frac = float(np.mean(dist[walkable] <= 5.0)) if walkable.any() else 0.0
        return {"extent_m": (b[0], b[2], b[1], b[3]), "distance_m": dist.reshape(gx.shape), "fingerprints_m": xy,
                "fraction_within_5m": frac, "edges_m": np.asarray(plan.edges(0))}


__all__ = ["FloorModels", "Site", "WalkTrack"]
