"""A description of one floor's walks for a report (describe_ilc_floor): counts, durations,
scan rates and spreads.

Part of :mod:`indoorloc.io.ilc2020` (the format is described there)."""

from __future__ import annotations

from dataclasses import field
from typing import Any, Dict, List, Sequence, TYPE_CHECKING

import numpy as np

from indoorloc.io.ilc2020.walk_types import ILC_SENSOR_TYPES, IlcWifi

if TYPE_CHECKING:
    from indoorloc.io.ilc2020.floor import IlcFloor


def _spread(x: Sequence[float], q: Sequence[float] = (0, 10, 50, 90, 100)) -> Dict[str, float]:
    a = np.asarray(x, dtype=np.float64)
    if a.size == 0:
        return {f"p{int(p)}": float("nan") for p in q}
    return {f"p{int(p)}": float(v) for p, v in zip(q, np.percentile(a, q))}


def describe_ilc_floor(floor: IlcFloor, min_scan_fraction: float = 0.10,
                       fresh_age_s: float = 2.0) -> Dict[str, Any]:
    """Measured facts of a floor's walks (reads every walk): the numbers behind the choice of a
    staleness limit, an AP selection and the evaluation times.

    Returns a dict of plain numbers; distributions as ``{"p0", "p10", "p50", "p90", "p100"}``
    percentiles (``p0`` / ``p100`` are the minimum / maximum):

    - ``n_walks``, ``duration_s`` (per walk: last record time), ``total_duration_s``;
    - ``scans_per_walk``, ``scan_interval_s`` (between consecutive scans of a walk),
      ``readings_per_scan``, ``scans_with_repeated_bssid`` (fraction of scans where one BSSID
      appears twice or more);
    - ``n_bssids``, ``n_bssids_frequent`` (heard in at least ``min_scan_fraction`` of the
      floor's scans), ``n_bssids_frequent_fresh`` (the same counting only readings at most
      ``fresh_age_s`` old), ``n_bssids_in_one_walk`` (heard in one walk only),
      ``bssids_per_walk``, ``fresh_readings_per_scan`` (readings at most ``fresh_age_s`` old);
    - ``age_s``: reading age (scan time - last seen) percentiles 1, 5, 10, 25, 50, 75, 90, 95,
      99 and the extremes, ``age_fraction_over_s``: fraction of readings older than 1, 2, 3, 5,
      10, 20 s; ``age_histogram``: fractions of readings between the edges ``age_bins_s``
      (the last bin: 30 s or more); ``repeated_measurement_fraction``: readings that repeat
      an earlier report of the same measurement (:meth:`IlcWifi.new_measurement_mask`);
      ``negative_age_fraction``; ``rssi_dbm`` percentiles;
    - ``waypoints_per_walk``, ``waypoint_spacing_m`` and ``waypoint_interval_s`` (consecutive
      waypoints of a walk), ``first_waypoint_s`` (time of a walk's first waypoint),
      ``after_last_waypoint_s`` (walk end - last waypoint);
    - ``rate_hz``: per sensor type, the spread of the walks' rates; ``wifi_scan_rate_hz``;
      ``max_gap_s``: per sensor type, the longest gap between samples over all walks;
    - ``n_beacon_readings``, ``unknown_type_counts``;
    - ``load_report``: :meth:`IlcFloor.load_report` after reading every walk (walks skipped
      because they cannot be read, with the reason; optional fields dropped, per field).
      ``n_walks`` counts the walks read.
    """
    if not (hasattr(floor, "walks") and hasattr(floor, "bssid_vocabulary")):  # was an AttributeError
        raise TypeError(f"indoorloc: argument 'floor': expected an IlcFloor (read_ilc_floor(folder)), "
                        f"got {type(floor).__name__}")
    walks = list(floor.walks())
    voc = floor.bssid_vocabulary()
    ages: List[np.ndarray] = []
    rssi: List[np.ndarray] = []
    durations, scans, intervals, per_scan, repeated = [], [], [], [], []
    n_wp, spacing, wp_dt, first_wp, after_wp, bssids_per_walk = [], [], [], [], [], []
    rates: Dict[str, List[float]] = {t: [] for t in ILC_SENSOR_TYPES}
    gaps: Dict[str, float] = {t: 0.0 for t in ILC_SENSOR_TYPES}
    unknown: Dict[str, int] = {}
    n_beacons = 0
    fresh_per_scan: List[int] = []
    n_repeated = 0
    fresh_scans = np.zeros(voc.size, dtype=np.int64)
    for w in walks:
        wf = w.wifi
        durations.append(w.duration_s)
        scans.append(wf.n_scans)
        intervals.extend(np.diff(wf.scan_times_s))
        counts = np.diff(np.append(wf.scan_starts, wf.n_readings))
        per_scan.extend(counts)
        if wf.n_readings:
            v = len(wf.bssids)
            pair, n_pair = np.unique(wf.scan_index * v + wf.bssid_index, return_counts=True)
            repeated.append(np.unique(pair[n_pair > 1] // v).size)
        ages.append(wf.age_s)
        n_repeated += int(np.sum(~wf.new_measurement_mask()))
        fresh = wf.age_s <= fresh_age_s
        fresh_per_scan.extend(np.bincount(wf.scan_index[fresh], minlength=wf.n_scans))
        fresh_pairs = np.unique(wf.scan_index[fresh] * max(1, voc.size) + voc.map_walk(w)[fresh])
        np.add.at(fresh_scans, fresh_pairs % max(1, voc.size), 1)
        rssi.append(wf.rssi_dbm)
        bssids_per_walk.append(len(wf.bssids))
        n_wp.append(w.n_waypoints)
        spacing.extend(np.linalg.norm(np.diff(w.waypoint_xy_m, axis=0), axis=1))
        wp_dt.extend(np.diff(w.waypoint_t_s))
        if w.n_waypoints:
            first_wp.append(w.waypoint_t_s[0])
            after_wp.append(w.duration_s - w.waypoint_t_s[-1])
        for t, s in w.sensors.items():
            if s.n_samples > 1:
                rates[t].append(s.rate_hz)
                gaps[t] = max(gaps[t], float(np.max(np.diff(s.t_s))))
        for k, v in w.unknown_type_counts.items():
            unknown[k] = unknown.get(k, 0) + v
        n_beacons += w.beacons.n_readings
    age = np.concatenate(ages) if ages else np.zeros(0)
    age_q = (0, 1, 5, 10, 25, 50, 75, 90, 95, 99, 100)
    age_bins = [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 10.0, 20.0, 30.0]
    age_hist = np.histogram(age, bins=age_bins + [np.inf])[0] / max(1, age.size)
    return {
        "floor": floor.name,
        "n_walks": len(walks),
        "duration_s": _spread(durations),
        "total_duration_s": float(np.sum(durations)),
        "scans_per_walk": _spread(scans),
        "total_scans": int(np.sum(scans)),
        "scan_interval_s": _spread(intervals),
        "wifi_scan_rate_hz": float(1.0 / np.median(intervals)) if intervals else float("nan"),
        "readings_per_scan": _spread(per_scan),
        "scans_with_repeated_bssid": float(np.sum(repeated) / max(1, np.sum(scans))),
        "n_readings": int(age.size),
        "repeated_measurement_fraction": float(n_repeated / max(1, age.size)),
        "n_bssids": voc.size,
        "n_bssids_frequent": int(voc.frequent(min_scan_fraction).size),
        "min_scan_fraction": float(min_scan_fraction),
        "n_bssids_frequent_fresh": int(np.sum(fresh_scans >= min_scan_fraction
                                              * max(1, voc.total_scans))),
        "fresh_age_s": float(fresh_age_s),
        "fresh_readings_per_scan": _spread(fresh_per_scan),
        "n_bssids_in_one_walk": int(np.sum(voc.n_walks == 1)),
        "bssids_per_walk": _spread(bssids_per_walk),
        "age_s": _spread(age, age_q),
        "age_fraction_over_s": {str(s): float(np.mean(age > s)) if age.size else float("nan")
                                for s in (1, 2, 3, 5, 10, 20)},
        "age_bins_s": age_bins,
        "age_histogram": [float(h) for h in age_hist],
        "negative_age_fraction": float(np.mean(age < 0)) if age.size else float("nan"),
        "rssi_dbm": _spread(np.concatenate(rssi) if rssi else []),
        "waypoints_per_walk": _spread(n_wp),
        "total_waypoints": int(np.sum(n_wp)),
        "waypoint_spacing_m": _spread(spacing),
        "waypoint_interval_s": _spread(wp_dt),
        "first_waypoint_s": _spread(first_wp),
        "after_last_waypoint_s": _spread(after_wp),
        "rate_hz": {t: _spread(r) for t, r in rates.items()},
        "max_gap_s": gaps,
        "n_beacon_readings": n_beacons,
        "unknown_type_counts": unknown,
        "load_report": floor.load_report(),
    }
