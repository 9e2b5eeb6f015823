"""Live tracking: raw phone sensor events in, the grid filter's current estimate out after each.

When to use: a phone app, or a replay of a recorded walk, that feeds accelerometer, gyroscope,
rotation-vector and WiFi-scan events as they happen and wants where the phone is now. The pieces
are those of a site: the grid tracker of the floor plan (``fusion.GridTracker``), the WiFi
fingerprint database (``wifi_fixes.FingerprintDatabase``) and the hand-held PDR calibration
(``pdr.handheld.HandheldCalibration``).

What happens to each event (docs/fusion.md, "Live tracking"):

- **IMU**: the accelerometer drives the causal step detector (:mod:`indoorloc.pdr.streaming`); the
  gyroscope and rotation vector are held at their latest sample (send them first at equal times).
  A step is confirmed ``min_step_interval_s`` (0.4 s) after its peak; it becomes a
  ``fusion.Steps.from_polar`` step (calibrated length, heading + the calibration's yaw offset,
  sds as ``indoorloc fusion evaluate``) and goes to the C++ session (``GridFilterSession``).
- **WiFi scan** (BSSIDs, RSSI, last-seen times): each distinct (BSSID, last-seen time) is one
  measurement at its first report; the query of the scan at time t max-pools the measurements last
  seen in [t - query_window_s, t] (exactly ``wifi_fixes.walk_queries``, incrementally); its ``k``
  best fingerprints make a fix **timed at the scan** (when it exists, not at the mean last-seen time
  that ``walk_queries`` stamps it with: a live filter cannot apply a fix before it is made). The
  fix is applied at the first step at or after its time. ``delay_compensation`` (off by
  default) moves each component of the fix by the PDR displacement (calibrated, nominal heading
  offset) of the steps between its measurements' mean last-seen time and the step that applies
  it. Measured on four shared floors it does not help (mean error +0.6, +0.7, -0.9 m on F8, F3,
  F4, ...: benchmarks/results/fusion_live_accuracy.md): a max-pooled 16 s query describes the
  whole stretch walked, not one point of it.
- **Beacons**: accepted and ignored (the site has no beacon map yet).

Every method returns the current estimate (a dict: ``time_s``, ``steps``, ``mean_m`` (2,),
``covariance_m2`` (3,) = (xx, xy, yy), ``floor_probabilities`` (F,), ``floors`` (F,) floor numbers,
``floor``, ``heading_offset_rad``), or None before the first step. Events must come in
non-decreasing time: otherwise ValueError naming the event's index, type and both times, and the
tracker is unchanged.

Exactness: :func:`causal_track` is the same filter in one batch call (causal steps of the whole
walk, fixes at their scan times, ``GridTracker.run`` without smoothing). A walk replayed event by
event (:func:`walk_events`) gives its track bit for bit (tests/python/test_fusion_live.py).
"""

from __future__ import annotations

import math
from collections import deque
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc._core.fusion import GridFilterSession, GridTracker
from indoorloc.io.ilc2020.walk_types import quaternion_from_rotation_vector
from indoorloc.pdr import handheld as ph
from indoorloc.pdr import streaming as ps
from indoorloc.fusion import wifi_fixes as wfx
from indoorloc import wifi_matcher as wm

#: Per-step white noise given to the filter (the defaults of ``indoorloc fusion evaluate``,
#: RealSettings.step_length_sd_fraction and step_heading_sd_rad): length sd as a fraction of the
#: stride, heading sd [rad]; the systematic parts are the filter's offset and scale layers.
STEP_LENGTH_SD_FRACTION = 0.15
STEP_HEADING_SD_RAD = math.radians(10.0)

#: Event kinds of :meth:`LiveTracker.add_event` and :func:`walk_events`, in their order at equal
#: times (the held IMU streams before the accelerometer sample that uses them).
EVENT_KINDS = ("gyroscope", "rotation_vector", "accelerometer", "wifi", "beacon")


def _step_arrays(steps: ph.HandheldSteps, yaw_offset_rad: float, length_sd_fraction: float,
                 heading_sd_rad: float):
    """fusion.Steps of detected steps (headings rotated by the calibration's yaw offset)."""
    from indoorloc.fusion.steps import Steps

    return Steps.from_polar(steps.t_s, steps.length_m, steps.heading_rad + yaw_offset_rad,
                            length_sd_fraction * steps.length_m, heading_sd_rad)


def _fixes_of_queries(times_s: np.ndarray, rss_dbm: np.ndarray, database: wfx.FingerprintDatabase,
                      with_floors: bool, shifts_m: Optional[np.ndarray] = None):
    """Fixes (fusion.Fixes) of query fingerprints (Q, K) at the given times (``fixes_for_walk``'s
    rule), every component of fix q moved by ``shifts_m[q]`` (Q, 2) [m] when given."""
    from indoorloc.fusion.fixes import Fixes

    s = database.settings
    k = min(s.k, database.n_scans)
    if times_s.size == 0:
        return Fixes.from_arrays(np.zeros(0), np.zeros((0, k, 2)), np.zeros((0, k)), np.zeros((0, k)))
    best, d_best, weights = wfx.nearest(rss_dbm, database)  # fixes_for_walk's matcher
    if database.weights is not None:  # grown fingerprints count less (as fixes_for_walk)
        weights = weights * database.weights[best]
    floors = database.floors[best] if with_floors else None
    means = database.positions_m[best]
    if shifts_m is not None:
        means = means + shifts_m[:, None, :]
    return Fixes.from_arrays(times_s, means, wfx.fix_sds(d_best[:, 0], s), weights, floors)


def _delay_shift(step_times_s: np.ndarray, displacements_m: np.ndarray, described_s: float, k: int) -> np.ndarray:
    """The PDR displacement (2,) [m] from the time a fix describes to step k: the sum of the
    displacements of the steps j with described_s < t_j <= t_k (zero when none)."""
    lo = int(np.searchsorted(step_times_s, described_s, side="right"))
    if lo > k:
        return np.zeros(2)
    return np.sum(displacements_m[lo:k + 1], axis=0)


def _check_live_settings(database: wfx.FingerprintDatabase) -> None:
    """ValueError unless the database's fixes can be reproduced live ("window" pooling, causal
    alignment, WiFi columns only)."""
    s = database.settings
    if s.pooling != "window" or s.query_align != "end" or getattr(s, "beacons", False):
        raise ValueError("indoorloc: argument 'database': live tracking needs settings.pooling == 'window', "
                         f"query_align == 'end' and beacons off (got {s.pooling!r}, {s.query_align!r}, "
                         f"beacons={getattr(s, 'beacons', False)!r})")


def causal_queries(walk: Any, database: wfx.FingerprintDatabase) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The query fingerprints of a walk's scans timed at the scan: ``(t_s (Q,), described_s (Q,),
    rss_dbm (Q, K))``, the fingerprints of ``wifi_fixes.walk_queries`` ("window" pooling, causal
    alignment) with the time at which each exists and the mean last-seen time of its
    measurements (the time it describes, walk_queries' timestamp). Raises ValueError for other
    pooling settings."""
    _check_live_settings(database)
    s = database.settings
    meas = wm.walk_measurements(walk)
    cols = meas.columns({b: i for i, b in enumerate(database.bssids)})
    scan_t = np.unique(np.asarray(walk.wifi.scan_times_s, float))
    rss, mean_t, _ = wm.pool_windows(meas.t_s, cols, meas.rssi_dbm, len(database.bssids), scan_t, s.query_window_s,
                                     0.0, meas.reported_s)
    ok = np.isfinite(rss).sum(axis=1) >= s.min_aps
    return scan_t[ok], mean_t[ok], rss[ok]


def causal_inputs(walk: Any, calibration: Optional[ph.HandheldCalibration] = None,
                  database: Optional[wfx.FingerprintDatabase] = None, *,
                  step_length_sd_fraction: float = STEP_LENGTH_SD_FRACTION,
                  step_heading_sd_rad: float = STEP_HEADING_SD_RAD, with_floors: bool = True,
                  delay_compensation: bool = False):
    """The steps (fusion.Steps) and fixes (fusion.Fixes or None) a live tracker derives from a
    recorded walk: causal steps (``pdr.streaming.causal_handheld_steps`` with the calibration's
    options), fixes of the scans timed at the scans, those after the last step dropped (a live
    filter has not applied them yet). ``delay_compensation``: each fix's components moved by the
    PDR displacement from the time the fix describes (its measurements' mean last-seen time) to
    the step that applies it (module docstring)."""
    options = calibration.options if calibration is not None else ph.HandheldOptions()
    yaw = calibration.yaw_offset_rad if calibration is not None else 0.0
    steps = _step_arrays(ps.causal_handheld_steps(walk, options), yaw, step_length_sd_fraction, step_heading_sd_rad)
    fixes = None
    if database is not None:
        t, described, rss = causal_queries(walk, database)
        last = steps.times_s[-1] if len(steps) else -math.inf
        keep = t <= last
        t, described, rss = t[keep], described[keep], rss[keep]
        shifts = None
        if delay_compensation:
            at = np.searchsorted(steps.times_s, t, side="left")   # the step that applies each fix
            shifts = np.array([_delay_shift(steps.times_s, steps.displacements_m, described[q], int(at[q]))
                               for q in range(t.size)]).reshape(-1, 2)
        fixes = _fixes_of_queries(t, rss, database, with_floors, shifts)
    return steps, fixes


def causal_track(tracker: GridTracker, walk: Any, calibration: Optional[ph.HandheldCalibration] = None,
                 database: Optional[wfx.FingerprintDatabase] = None, *, start: Optional[dict] = None,
                 step_length_sd_fraction: float = STEP_LENGTH_SD_FRACTION,
                 step_heading_sd_rad: float = STEP_HEADING_SD_RAD, with_floors: bool = True,
                 delay_compensation: bool = False) -> dict:
    """The live tracker's track of a recorded walk in one batch call: ``GridTracker.run`` (no
    smoothing) on :func:`causal_inputs`. Returns run's dict (``times_s``, ``mean_m``,
    ``covariance_m2``, ``floor_probabilities``, ``heading_offset_rad`` per step; empty arrays for a
    walk without steps)."""
    steps, fixes = causal_inputs(walk, calibration, database, step_length_sd_fraction=step_length_sd_fraction,
                                 step_heading_sd_rad=step_heading_sd_rad, with_floors=with_floors,
                                 delay_compensation=delay_compensation)
    if len(steps) == 0:
        return {"times_s": np.zeros(0), "mean_m": np.zeros((0, 2)), "covariance_m2": np.zeros((0, 3))}
    arrays = None if fixes is None or len(fixes) == 0 else fixes.as_arrays()
    return tracker.run(steps.times_s, steps.displacements_m, steps.covariances_m2, arrays, start, False)


class _QueryPooler:
    """The "window" query of each scan, built incrementally (``causal_queries`` one scan at a time):
    distinct (BSSID, last-seen ms) measurements at their first report, those last seen within the
    window kept (arrays), max-pooled per database column."""

    def __init__(self, database: wfx.FingerprintDatabase):
        self.database = database
        self.column = {b: i for i, b in enumerate(database.bssids)}
        self.window_s = float(database.settings.query_window_s)
        self.seen: Dict[Tuple[str, int], float] = {}         # key -> last-seen time
        self.t = np.zeros(0)                                 # kept measurements of known APs: last seen [s]
        self.col = np.zeros(0, np.int64)                     # ... their column
        self.rss = np.zeros(0)                               # ... their RSSI [dBm]

    def query(self, t_s: float, bssids: Sequence[str], rssi_dbm: np.ndarray, last_seen_s: np.ndarray
              ) -> Optional[Tuple[np.ndarray, float]]:
        """Adds a scan's readings; returns the query fingerprint (K,) of time t_s and the mean
        last-seen time of its measurements [s] (summed in pool_windows' order), or None when it
        has fewer than ``min_aps`` known APs."""
        lo = t_s - self.window_s
        ms = np.round(last_seen_s * 1000.0).astype(np.int64).tolist()   # the key of new_measurement_mask
        new = []
        for j, (b, key_ms) in enumerate(zip(bssids, ms)):
            key = (b, key_ms)
            if key in self.seen:
                continue
            self.seen[key] = last_seen_s[j]
            col = self.column.get(b, -1)
            if col >= 0:
                new.append((j, col))
        if new:
            j, c = np.array(new, dtype=np.int64).T
            self.t = np.concatenate([self.t, last_seen_s[j]])
            self.col = np.concatenate([self.col, c])
            self.rss = np.concatenate([self.rss, rssi_dbm[j]])
        # Forget what no later window can hold (windows only move forward).
        keep = self.t >= lo
        if not keep.all():
            self.t, self.col, self.rss = self.t[keep], self.col[keep], self.rss[keep]
        if len(self.seen) > 4096:
            self.seen = {k: v for k, v in self.seen.items() if v >= lo}
        q = np.full(len(self.column), np.nan)
        now = self.t <= t_s
        np.fmax.at(q, self.col[now], self.rss[now])   # max-pool (NaN: not heard)
        if np.count_nonzero(~np.isnan(q)) < self.database.settings.min_aps:
            return None
        t_used = np.sort(self.t[now], kind="stable")
        total = np.bincount(np.zeros(t_used.size, np.int64), weights=t_used, minlength=1)[0]
        return q, total / max(t_used.size, 1)


class LiveTracker:
    """Raw sensor events in, the grid filter's current estimate out (module docstring).

    Parameters
    ----------
    tracker : fusion.GridTracker
        Built once per site and options (its grids are shared by every live session).
    calibration : pdr.handheld.HandheldCalibration or None
        K, yaw offset and detector settings (fit on causal steps of the survey walks:
        ``calibrate_handheld(walks, steps_cache=[causal_handheld_steps(w) for w in walks])``).
        None: ``HandheldOptions()`` defaults, yaw offset 0.
    database : wifi_fixes.FingerprintDatabase or None
        The WiFi map ("window" pooling); None: WiFi events are ignored.
    start : dict or None
        None: unknown start; else {"position_m", "floor", "heading_offset_rad", "time_s"}.
    delay_compensation : bool
        Move each fix by the PDR displacement from the time it describes to the step that
        applies it (module docstring; off: it did not help on the shared floors).
    """

    def __init__(self, tracker: GridTracker, calibration: Optional[ph.HandheldCalibration] = None,
                 database: Optional[wfx.FingerprintDatabase] = None, *, start: Optional[dict] = None,
                 step_length_sd_fraction: float = STEP_LENGTH_SD_FRACTION,
                 step_heading_sd_rad: float = STEP_HEADING_SD_RAD, with_floors: bool = True,
                 delay_compensation: bool = False):
        if not isinstance(tracker, GridTracker):
            raise TypeError(f"indoorloc: argument 'tracker': expected a fusion.GridTracker, got {type(tracker).__name__}")
        self._session = GridFilterSession(tracker, start)
        options = calibration.options if calibration is not None else ph.HandheldOptions()
        self._yaw = calibration.yaw_offset_rad if calibration is not None else 0.0
        self._detector = ps.StreamingStepDetector(options)
        self._length_sd_fraction = float(step_length_sd_fraction)
        self._heading_sd = float(step_heading_sd_rad)
        self._with_floors = with_floors
        self._pooler = None
        if database is not None:
            _check_live_settings(database)
            self._pooler = _QueryPooler(database)
            database.index  # noqa: B018: build the matcher's index now, not at the first scan
        self._database = database
        self._floors = np.asarray(self._session.floors, dtype=np.int64)
        self._delay = bool(delay_compensation)
        self._step_t: List[float] = []          # recent steps: times [s] and displacements (2,) [m]
        self._step_d: List[np.ndarray] = []
        self._gyro: Optional[np.ndarray] = None
        self._quat: Optional[np.ndarray] = None
        self._fixes: deque = deque()   # (time, fix arrays) waiting for a step at or after them
        self._events = 0
        self._last = (-math.inf, None)  # (time, kind) of the latest event
        self._estimate: Optional[dict] = None

    # ------------------------------------------------------------------ events
    def add_accelerometer(self, t_s: float, acc_mps2: Sequence[float]) -> Optional[dict]:
        """Accelerometer sample: specific force (3,) [m/s²], device frame."""
        acc = _vector(acc_mps2, "acc_mps2", 3)
        t = self._check("accelerometer", t_s)
        if self._gyro is not None and self._quat is not None:
            for step in self._detector.add_sample(t, acc, self._gyro, self._quat):
                self._add_step(step)
        return self._estimate

    def add_gyroscope(self, t_s: float, gyro_radps: Sequence[float]) -> Optional[dict]:
        """Gyroscope sample: angular rate (3,) [rad/s], device frame."""
        gyro = _vector(gyro_radps, "gyro_radps", 3)
        self._check("gyroscope", t_s)
        self._gyro = gyro
        return self._estimate

    def add_rotation_vector(self, t_s: float, values: Sequence[float]) -> Optional[dict]:
        """Android rotation vector (x, y, z[, w]) of the device -> east-north-up rotation."""
        v = np.asarray(values, dtype=np.float64).reshape(1, -1)
        if v.shape[1] not in (3, 4, 5) or not np.all(np.isfinite(v[:, :3])):
            raise ValueError(f"indoorloc: argument 'values': expected 3 or 4 finite rotation-vector values, got {v.ravel()}")
        self._check("rotation_vector", t_s)
        self._quat = quaternion_from_rotation_vector(v[:, :4])[0]
        return self._estimate

    def add_wifi_scan(self, t_s: float, bssids: Sequence[str], rssi_dbm: Sequence[float],
                      last_seen_s: Sequence[float]) -> Optional[dict]:
        """One WiFi scan reported at t_s: per reading its BSSID, RSSI [dBm] and last-seen time [s]
        (on the events' clock). The scan's fix waits for the first step at or after t_s."""
        rssi = np.asarray(rssi_dbm, dtype=np.float64).reshape(-1)
        seen = np.asarray(last_seen_s, dtype=np.float64).reshape(-1)
        if not (len(bssids) == rssi.size == seen.size):
            raise ValueError(f"indoorloc: LiveTracker.add_wifi_scan: bssids, rssi_dbm and last_seen_s must have one "
                             f"entry per reading, got {len(bssids)}, {rssi.size}, {seen.size}")
        if not (np.all(np.isfinite(rssi)) and np.all(np.isfinite(seen))):
            raise ValueError("indoorloc: LiveTracker.add_wifi_scan: rssi_dbm and last_seen_s must be finite")
        t = self._check("wifi", t_s)
        if self._pooler is None:
            return self._estimate
        got = self._pooler.query(t, list(bssids), rssi, seen)
        if self._fixes and self._fixes[-1][0] == t:  # a second scan at the same time: its pooled query replaces
            self._fixes.pop()
        if got is not None:
            q, described = got
            # The fix is matched now; with delay compensation at the step that applies it (its
            # shift needs the steps up to there).
            fix = None if self._delay else _fixes_of_queries(np.array([t]), q[None, :], self._database,
                                                              self._with_floors).as_arrays()
            self._fixes.append((t, described, q, fix))
        return self._estimate

    def add_beacon(self, t_s: float, *values: Any) -> Optional[dict]:
        """An iBeacon reading: accepted (time order checked) and ignored."""
        self._check("beacon", t_s)
        return self._estimate

    def add_event(self, kind: str, t_s: float, *values: Any) -> Optional[dict]:
        """Dispatch by kind (``EVENT_KINDS``): ``("accelerometer", t, xyz)``, ``("gyroscope", t, xyz)``,
        ``("rotation_vector", t, values)``, ``("wifi", t, bssids, rssi_dbm, last_seen_s)``,
        ``("beacon", t, ...)``."""
        method = {"accelerometer": self.add_accelerometer, "gyroscope": self.add_gyroscope,
                  "rotation_vector": self.add_rotation_vector, "wifi": self.add_wifi_scan,
                  "beacon": self.add_beacon}.get(kind)
        if method is None:
            raise ValueError(f"indoorloc: LiveTracker.add_event: event {self._events} has unknown kind {kind!r} "
                             f"(expected one of {EVENT_KINDS})")
        return method(t_s, *values)

    def estimate(self) -> Optional[dict]:
        """The current estimate (module docstring), None before the first step."""
        return self._estimate

    @property
    def events(self) -> int:
        """Events accepted so far."""
        return self._events

    @property
    def session(self) -> GridFilterSession:
        """The C++ filter session (steps, pending fixes, summary)."""
        return self._session

    # ------------------------------------------------------------------ internals
    def _check(self, kind: str, t_s: Any) -> float:
        try:
            t = float(t_s)
        except (TypeError, ValueError):
            raise ValueError(f"indoorloc: LiveTracker: event {self._events} ({kind}): time must be a number, "
                             f"got {t_s!r}") from None
        if not math.isfinite(t):
            raise ValueError(f"indoorloc: LiveTracker: event {self._events} ({kind}): time must be finite, got {t}")
        if t < self._last[0]:
            raise ValueError(f"indoorloc: LiveTracker: event {self._events} ({kind} at t = {t} s) is out of time "
                             f"order: before event {self._events - 1} ({self._last[1]} at t = {self._last[0]} s)")
        self._events += 1
        self._last = (t, kind)
        return t

    def _add_step(self, step: Tuple) -> None:
        t = step[0]
        one = ps._assemble([step], self._detector.options, step[6])
        st = _step_arrays(one, self._yaw, self._length_sd_fraction, self._heading_sd)
        self._step_t.append(float(st.times_s[0]))
        self._step_d.append(st.displacements_m[0])
        if self._fixes and self._fixes[0][0] <= t:
            times, disp = np.array(self._step_t), np.array(self._step_d)
            while self._fixes and self._fixes[0][0] <= t:
                c, described, q, fix = self._fixes.popleft()
                if fix is None:
                    shift = _delay_shift(times, disp, described, times.size - 1)[None, :]
                    fix = _fixes_of_queries(np.array([c]), q[None, :], self._database, self._with_floors,
                                            shift).as_arrays()
                self._session.add_fixes(fix)
        # Keep the steps a later fix can still reach back to (a scan describes at most its window).
        cutoff = min([self._last[0] - self._pooler.window_s] + [f[1] for f in self._fixes]) if self._pooler else t
        while len(self._step_t) > 1 and self._step_t[0] < cutoff - 1.0:
            self._step_t.pop(0)
            self._step_d.pop(0)
        e = self._session.add_step(st.times_s[0], st.displacements_m[0], st.covariances_m2[0])
        e["floors"] = self._floors
        e["floor"] = int(self._floors[int(np.argmax(e["floor_probabilities"]))])
        self._estimate = e


def _vector(values: Any, name: str, n: int) -> np.ndarray:
    v = np.asarray(values, dtype=np.float64).reshape(-1)
    if v.size < n or not np.all(np.isfinite(v[:n])):
        raise ValueError(f"indoorloc: argument '{name}': expected {n} finite values, got {v}")
    return v[:n]


def walk_events(walk: Any, beacons: bool = False) -> Iterator[Tuple]:
    """A recorded walk (``IlcWalk``) as the live tracker's events in time order (``EVENT_KINDS``
    order at equal times): ``(kind, t_s, *values)`` for :meth:`LiveTracker.add_event`. One WiFi
    event per scan (its readings in file order)."""
    rows: List[Tuple[float, int, int, Tuple]] = []
    g, r, a = walk.gyroscope, walk.rotation_vector, walk.accelerometer
    for k, t in enumerate(np.asarray(g.t_s, float)):
        rows.append((t, 0, k, ("gyroscope", t, g.values[k, :3])))
    for k, t in enumerate(np.asarray(r.t_s, float)):
        rows.append((t, 1, k, ("rotation_vector", t, r.values[k])))
    for k, t in enumerate(np.asarray(a.t_s, float)):
        rows.append((t, 2, k, ("accelerometer", t, a.values[k, :3])))
    wf = walk.wifi
    for s in range(wf.n_scans):
        sl = wf.scan_slice(s)
        t = float(wf.scan_time_s[sl.start])
        names = [wf.bssids[i] for i in wf.bssid_index[sl]]
        rows.append((t, 3, s, ("wifi", t, names, wf.rssi_dbm[sl], wf.last_seen_s[sl])))
    if beacons and getattr(walk, "beacons", None) is not None:
        for k, t in enumerate(np.asarray(walk.beacons.t_s, float)):
            rows.append((t, 4, k, ("beacon", t)))
    rows.sort(key=lambda x: (x[0], x[1], x[2]))
    for row in rows:
        yield row[3]


__all__ = ["EVENT_KINDS", "LiveTracker", "STEP_HEADING_SD_RAD", "STEP_LENGTH_SD_FRACTION", "causal_inputs",
           "causal_queries", "causal_track", "quaternion_from_rotation_vector", "walk_events"]
