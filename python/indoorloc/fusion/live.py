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
  fix is applied at the first step at or after its time; one that no step has applied
  ``standing_after_s`` (1 s) after its time is applied at a **standing step** (no displacement)
  at its time, so a user standing still is located and followed by WiFi alone. ``delay_compensation`` (off by
  default) moves each component of the fix by the PDR displacement (calibrated, nominal heading
  offset) of the steps between its measurements' mean last-seen time and the step that applies
  it. Measured on the six shared floors it does not help (10.90 m pooled without, 10.98 m with:
  benchmarks/results/fusion_live_accuracy.md): a max-pooled 16 s query describes the whole stretch
  walked, not one point of it.
- **Beacons**: accepted and ignored (the site has no beacon map yet).

Every method returns the current estimate (a ``fusion.LiveEstimate``, read-only attributes:
``time_s``, ``steps``, ``mean_m`` (2,), ``covariance_m2`` (3,) = (xx, xy, yy),
``floor_probabilities`` (F,), ``floors`` (F,) floor numbers, ``floor``, ``heading_offset_rad``,
``fixes`` (applied so far), ``located``, ...; ``to_dict()`` gives them as a dict), or None before the
first step (detected or standing). **``located`` is False until the first fix is applied** (unknown start): the estimate is
then the prior's, the mean of the floor's walkable area with a covariance the size of the floor, not
a position; an app shows "locating" rather than that point. On the shared site the first fix comes
2.2 s (median; p90 2.7 s) after a walk's first waypoint (`indoorloc fusion evaluate`, ``fusion_live``). Events must come in
non-decreasing time: otherwise ValueError naming the event's index, type and both times, and the
tracker is unchanged.

Exactness: :func:`causal_track` is the same filter in one batch call (causal steps of the whole
walk with the session's standing steps, fixes at their scan times, ``GridTracker.run`` without
smoothing). A walk replayed event by
event (:func:`walk_events` with ``beacons=True``) gives its track bit for bit (tests/python/test_fusion_live.py).
"""

from __future__ import annotations

import math
from typing import Any, Iterator, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc._core.fusion import (FingerprintFixOptions, GridFilterSession, GridTracker, LiveEstimate, LiveSession,
                                    LiveSessionOptions)
from indoorloc.io.ilc2020.walk_types import quaternion_from_rotation_vector
from indoorloc.pdr import handheld as ph
from indoorloc.pdr import streaming as ps
from indoorloc.fusion import wifi_fixes as wfx
from indoorloc.wifi import matcher as wifi_matcher

#: Per-step white noise given to the filter (the defaults of ``indoorloc fusion evaluate``,
#: RealSettings.step_length_sd_fraction and step_heading_sd_rad): length sd as a fraction of the
#: stride, heading sd [rad]; the systematic parts are the filter's offset and scale layers.
STEP_LENGTH_SD_FRACTION = LiveSessionOptions().step_length_sd_fraction
STEP_HEADING_SD_RAD = LiveSessionOptions().step_heading_sd_rad
#: A fix still waiting for a step this long after its time [s] is applied at a standing step (the
#: C++ LiveSessionOptions.standing_after_s; 0: fixes wait for a detected step).
STANDING_AFTER_S = LiveSessionOptions().standing_after_s

#: Event kinds of :meth:`LiveTracker.add_event` and :func:`walk_events`, in their order at equal
#: times (the held IMU streams before the accelerometer sample that uses them).
EVENT_KINDS = ("gyroscope", "rotation_vector", "accelerometer", "wifi", "beacon")


def _step_arrays(steps: ph.HandheldSteps, yaw_offset_rad: float, length_sd_fraction: float,
                 heading_sd_rad: float):
    """fusion.Steps of detected steps (headings rotated by the calibration's yaw offset)."""
    from indoorloc.fusion.steps import Steps

    return Steps.from_polar(steps.t_s, steps.length_m, steps.heading_rad + yaw_offset_rad,
                            length_sd_fraction * steps.length_m, heading_sd_rad)


def _with_standing_steps(steps, confirmed_s: np.ndarray, fix_times_s: np.ndarray, wait_s: float,
                         last_event_s: float):
    """The filter's steps of a live session: the detected ``steps`` (fusion.Steps, confirmed at
    ``confirmed_s`` (M,) [s]) with a standing step (zero displacement and covariance) at the time of
    every fix (times ``fix_times_s``, sorted) that no step has applied ``wait_s`` after its time,
    when some event comes that late (``last_event_s``). Replays LiveSession's rule (live_session.cc,
    ApplyStanding: due standing steps go first at an event, then the step it confirms; a step
    earlier than the filter's latest step is moved to that time)."""
    from indoorloc.fusion.steps import Steps

    fix_t = np.asarray(fix_times_s, float)
    times: List[float] = []
    source: List[int] = []      # index of the detected step, -1 for a standing step
    state = {"fix": 0, "last": -math.inf}

    def add(t: float, src: int) -> None:
        t = max(t, state["last"])
        times.append(t)
        source.append(src)
        state["last"] = t
        while state["fix"] < fix_t.size and fix_t[state["fix"]] <= t:  # the fixes this step applies
            state["fix"] += 1

    def standing_until(now_s: float) -> None:
        while wait_s > 0 and state["fix"] < fix_t.size and fix_t[state["fix"]] + wait_s <= now_s:
            add(float(fix_t[state["fix"]]), -1)

    for i in range(len(steps)):
        standing_until(float(confirmed_s[i]))
        add(float(steps.times_s[i]), i)
    standing_until(last_event_s)
    if not times or min(source) >= 0:
        return steps
    src = np.asarray(source)
    real = src >= 0
    disp = np.zeros((src.size, 2))
    cov = np.zeros((src.size, 3))
    disp[real] = steps.displacements_m[src[real]]
    cov[real] = steps.covariances_m2[src[real]]
    return Steps(np.asarray(times, float), disp, cov)


def _last_event_s(walk: Any) -> float:
    """The time of a recorded walk's last live event [s] (:func:`walk_events` with its beacons:
    a phone sends every event it has)."""
    streams = [walk.gyroscope.t_s, walk.rotation_vector.t_s, walk.accelerometer.t_s, walk.wifi.scan_times_s]
    if getattr(walk, "beacons", None) is not None:
        streams.append(walk.beacons.t_s)
    ends = [float(np.max(np.asarray(x, float))) for x in streams if np.asarray(x).size]
    return max(ends) if ends else -math.inf


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
    alignment, the "shared" metric, WiFi columns only)."""
    s = database.settings
    if s.pooling != "window" or s.query_align != "end" or s.metric != "shared" or getattr(s, "beacons", False):
        raise ValueError("indoorloc: argument 'database': live tracking needs settings.pooling == 'window', "
                         "query_align == 'end', metric == 'shared' and beacons off (got "
                         f"{s.pooling!r}, {s.query_align!r}, {s.metric!r}, beacons={getattr(s, 'beacons', False)!r})")


def causal_queries(walk: Any, database: wfx.FingerprintDatabase) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The query fingerprints of a walk's scans timed at the scan: ``(t_s (Q,), described_s (Q,),
    rss_dbm (Q, K))``, the fingerprints of ``wifi_fixes.walk_queries`` ("window" pooling, causal
    alignment) with the time at which each exists and the mean last-seen time of its
    measurements (the time it describes, walk_queries' timestamp). Raises ValueError for other
    pooling settings."""
    _check_live_settings(database)
    s = database.settings
    meas = wifi_matcher.walk_measurements(walk)
    cols = meas.columns({b: i for i, b in enumerate(database.bssids)})
    scan_t = np.unique(np.asarray(walk.wifi.scan_times_s, float))
    rss, mean_t, _ = wifi_matcher.pool_windows(meas.t_s, cols, meas.rssi_dbm, len(database.bssids), scan_t,
                                               s.query_window_s, 0.0, meas.reported_s)
    ok = np.isfinite(rss).sum(axis=1) >= s.min_aps
    return scan_t[ok], mean_t[ok], rss[ok]


def causal_inputs(walk: Any, calibration: Optional[ph.HandheldCalibration] = None,
                  database: Optional[wfx.FingerprintDatabase] = None, *,
                  step_length_sd_fraction: float = STEP_LENGTH_SD_FRACTION,
                  step_heading_sd_rad: float = STEP_HEADING_SD_RAD, with_floors: bool = True,
                  delay_compensation: bool = False, standing_after_s: float = STANDING_AFTER_S):
    """The steps (fusion.Steps) and fixes (fusion.Fixes or None) a live tracker derives from a
    recorded walk: causal steps (``pdr.streaming.causal_handheld_steps`` with the calibration's
    options) and the live session's standing steps (a fix no step has applied ``standing_after_s``
    [s] after its time is applied at a standing step at its time; 0: none), fixes of the scans
    timed at the scans, those after the last step dropped (a live filter has not applied them
    yet). ``delay_compensation``: each fix's components moved by the PDR displacement from the
    time the fix describes (its measurements' mean last-seen time) to the step that applies it
    (module docstring)."""
    options = calibration.options if calibration is not None else ph.HandheldOptions()
    yaw = calibration.yaw_offset_rad if calibration is not None else 0.0
    detected = ps.causal_handheld_steps(walk, options)
    steps = _step_arrays(detected, yaw, step_length_sd_fraction, step_heading_sd_rad)
    fixes = None
    if database is not None:
        t, described, rss = causal_queries(walk, database)
        steps = _with_standing_steps(steps, detected.confirmed_t_s, t, float(standing_after_s), _last_event_s(walk))
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
                 delay_compensation: bool = False, standing_after_s: float = STANDING_AFTER_S) -> dict:
    """The live tracker's track of a recorded walk in one batch call: ``GridTracker.run`` (no
    smoothing) on :func:`causal_inputs`. Returns run's dict (``times_s``, ``mean_m``,
    ``covariance_m2``, ``floor_probabilities``, ``heading_offset_rad`` per filter step, detected or
    standing; empty arrays for a walk without either)."""
    steps, fixes = causal_inputs(walk, calibration, database, step_length_sd_fraction=step_length_sd_fraction,
                                 step_heading_sd_rad=step_heading_sd_rad, with_floors=with_floors,
                                 delay_compensation=delay_compensation, standing_after_s=standing_after_s)
    if len(steps) == 0:
        return {"times_s": np.zeros(0), "mean_m": np.zeros((0, 2)), "covariance_m2": np.zeros((0, 3)),
                "located": np.zeros(0, bool)}
    arrays = None if fixes is None or len(fixes) == 0 else fixes.as_arrays()
    out = tracker.run(steps.times_s, steps.displacements_m, steps.covariances_m2, arrays, start, False)
    # LiveEstimate.located per step: a known start, or a fix applied (a fix at time t is applied at
    # the first step at or after t).
    if start is not None:
        out["located"] = np.ones(len(steps), bool)
    elif arrays is None:
        out["located"] = np.zeros(len(steps), bool)
    else:
        out["located"] = np.asarray(steps.times_s) >= float(np.min(fixes.times_s))
    return out


def session_options(calibration: Optional[ph.HandheldCalibration] = None, *,
                    step_length_sd_fraction: float = STEP_LENGTH_SD_FRACTION,
                    step_heading_sd_rad: float = STEP_HEADING_SD_RAD, delay_compensation: bool = False,
                    standing_after_s: float = STANDING_AFTER_S):
    """The C++ live session's options (``_core.fusion.LiveSessionOptions``) of a calibration (None:
    ``HandheldOptions()`` defaults, yaw offset 0), the per-step noise and the standing wait [s]."""
    options = calibration.options if calibration is not None else ph.HandheldOptions()
    return LiveSessionOptions(detector=ps.detector_options(options), step_length_k=options.k,
                              heading_source=options.heading_source,
                              yaw_offset_rad=calibration.yaw_offset_rad if calibration is not None else 0.0,
                              step_length_sd_fraction=float(step_length_sd_fraction),
                              step_heading_sd_rad=float(step_heading_sd_rad), delay_compensation=bool(delay_compensation),
                              standing_after_s=float(standing_after_s))


def fingerprint_map(database: wfx.FingerprintDatabase) -> Tuple:
    """A fingerprint database as the C++ live session's map tuple ``(bssids, rss_dbm, positions_m,
    floors, weights, ap_weights)`` (the AP weights of its "shared" matcher) and the fix options
    (``_core.fusion.FingerprintFixOptions``)."""
    s = database.settings
    index = database.index
    m = index.matcher(s.penalty_db, s.k, s.temperature_db)
    fix = FingerprintFixOptions(matcher=m.options, query_window_s=float(s.query_window_s), min_aps=int(s.min_aps),
                                sd_m=float(s.sd_m), sd_per_db=float(s.sd_per_db))
    return (list(database.bssids), database.rss_dbm, database.positions_m, database.floors, database.weights, index.g), fix


class LiveTracker:
    """Raw sensor events in, the grid filter's current estimate out (module docstring): the C++
    live session (``_core.fusion.LiveSession``, ``cpp/include/indoorloc/fusion/live_session.h``).

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
    standing_after_s : float
        A fix no step has applied this long after its time [s] is applied at a standing step
        (zero displacement) at its time, so that a user standing still is located and updated
        (module docstring); 0: fixes wait for a detected step.
    """

    def __init__(self, tracker: GridTracker, calibration: Optional[ph.HandheldCalibration] = None,
                 database: Optional[wfx.FingerprintDatabase] = None, *, start: Optional[dict] = None,
                 step_length_sd_fraction: float = STEP_LENGTH_SD_FRACTION,
                 step_heading_sd_rad: float = STEP_HEADING_SD_RAD, with_floors: bool = True,
                 delay_compensation: bool = False, standing_after_s: float = STANDING_AFTER_S):
        if not isinstance(tracker, GridTracker):
            raise TypeError(f"indoorloc: argument 'tracker': expected a fusion.GridTracker, got {type(tracker).__name__}")
        options = session_options(calibration, step_length_sd_fraction=step_length_sd_fraction,
                                  step_heading_sd_rad=step_heading_sd_rad, delay_compensation=delay_compensation,
                                  standing_after_s=standing_after_s)
        arrays, fix = None, None
        if database is not None:
            _check_live_settings(database)
            arrays, fix = fingerprint_map(database)
            fix = fix.replace(with_floors=bool(with_floors))
        self._live = LiveSession(tracker, options, arrays, fix, start)
        self._estimate: Optional[LiveEstimate] = None

    def _keep(self, estimate: Optional[LiveEstimate]) -> Optional[LiveEstimate]:
        self._estimate = estimate
        return estimate

    # ------------------------------------------------------------------ events
    def add_accelerometer(self, t_s: float, acc_mps2: Sequence[float]) -> Optional[LiveEstimate]:
        """Accelerometer sample: specific force (3,) [m/s²], device frame."""
        return self._keep(self._live.add_accelerometer(t_s, _vector(acc_mps2, "acc_mps2", 3)))

    def add_gyroscope(self, t_s: float, gyro_radps: Sequence[float]) -> Optional[LiveEstimate]:
        """Gyroscope sample: angular rate (3,) [rad/s], device frame."""
        return self._keep(self._live.add_gyroscope(t_s, _vector(gyro_radps, "gyro_radps", 3)))

    def add_rotation_vector(self, t_s: float, values: Sequence[float]) -> Optional[LiveEstimate]:
        """Android rotation vector (x, y, z[, w]) of the device -> east-north-up rotation."""
        v = np.asarray(values, dtype=np.float64).reshape(-1)
        if v.size not in (3, 4, 5) or not np.all(np.isfinite(v[:3])):
            raise ValueError(f"indoorloc: argument 'values': expected 3 or 4 finite rotation-vector values, got {v}")
        return self._keep(self._live.add_rotation_vector(t_s, v))

    def add_wifi_scan(self, t_s: float, bssids: Sequence[str], rssi_dbm: Sequence[float],
                      last_seen_s: Sequence[float]) -> Optional[LiveEstimate]:
        """One WiFi scan reported at t_s: per reading its BSSID, RSSI [dBm] and last-seen time [s]
        (on the events' clock). The scan's fix waits for the first step at or after t_s."""
        return self._keep(self._live.add_wifi_scan(t_s, list(bssids), rssi_dbm, last_seen_s))

    def add_beacon(self, t_s: float, *values: Any) -> Optional[LiveEstimate]:
        """An iBeacon reading: accepted (time order checked) and ignored."""
        return self._keep(self._live.add_beacon(t_s))

    def add_event(self, kind: str, t_s: float, *values: Any) -> Optional[LiveEstimate]:
        """Dispatch by kind (``EVENT_KINDS``): ``("accelerometer", t, xyz)``, ``("gyroscope", t, xyz)``,
        ``("rotation_vector", t, values)``, ``("wifi", t, bssids, rssi_dbm, last_seen_s)``,
        ``("beacon", t, ...)``."""
        method = {"accelerometer": self.add_accelerometer, "gyroscope": self.add_gyroscope,
                  "rotation_vector": self.add_rotation_vector, "wifi": self.add_wifi_scan,
                  "beacon": self.add_beacon}.get(kind)
        if method is None:
            raise ValueError(f"indoorloc: LiveTracker.add_event: event {self.events} has unknown kind {kind!r} "
                             f"(expected one of {EVENT_KINDS})")
        return method(t_s, *values)

    def estimate(self) -> Optional[LiveEstimate]:
        """The current estimate (module docstring), None before the first step."""
        return self._estimate

    @property
    def events(self) -> int:
        """Events accepted so far."""
        return self._live.events

    @property
    def session(self) -> GridFilterSession:
        """The C++ filter session (steps, pending fixes, summary)."""
        return self._live.filter

    @property
    def live_session(self) -> LiveSession:
        """The C++ live session (summary: events, IMU samples, steps detected and standing, scans,
        fixes applied and pending)."""
        return self._live


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


__all__ = ["EVENT_KINDS", "LiveEstimate", "LiveTracker", "STANDING_AFTER_S", "STEP_HEADING_SD_RAD", "STEP_LENGTH_SD_FRACTION", "causal_inputs",
           "causal_queries", "causal_track", "fingerprint_map", "quaternion_from_rotation_vector", "session_options",
           "walk_events"]
