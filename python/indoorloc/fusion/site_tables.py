"""Conversions between a site file's tables (:mod:`indoorloc.fusion.site_store`) and the models
of :class:`indoorloc.fusion.site.Site`: a floor and its plan rings, a survey walk's rows (walk,
calibration intervals, fingerprints, beacon sightings), and back: the plan, the PDR calibration
and the fingerprint database of floors, each derived from what is stored per walk."""

from __future__ import annotations

import datetime as _dt
import json
import sqlite3
from dataclasses import asdict
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np

from indoorloc.pdr import handheld as ph
from indoorloc.fusion import crowdsourced_map
from indoorloc.fusion import wifi_fixes
from indoorloc._core.fusion import FloorPlan
from indoorloc.fusion import site_model
from indoorloc.fusion import site_store as store
from indoorloc.io.floor_plan import load_floor_plan, read_geojson_floor
from indoorloc.io.survey_layout import floor_info_size_m


def now() -> str:
    """The current UTC time, ISO 8601 to the second (the walks' and meta's time stamps)."""
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


# ---- writing ---------------------------------------------------------------------------------
def insert_floor(con: sqlite3.Connection, fl) -> None:
    """Insert a survey floor (``survey_layout.SurveyFloor``): its GeoJSON, origin, walkable area [m²] and plan rings [m]."""
    text = Path(fl.geojson_path).read_text()
    g = read_geojson_floor(json.loads(text), floor=fl.number, origin_lon_lat="outline_sw")
    plan = load_floor_plan(json.loads(text), floors=[fl.number], origin_lon_lat=g.origin_lon_lat)
    size = floor_info_size_m(fl.floor_info_path)
    con.execute("INSERT INTO floors VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (fl.name, fl.number, text, g.origin_lon_lat[0], g.origin_lon_lat[1], float(plan.walkable_area(0)),
                 size[0] if size else None, size[1] if size else None, str(fl.geojson_path)))
    geom = plan.geometry(0)
    for role, rings in (("outline", geom.outlines), ("obstacle", geom.obstacles)):
        for i, ring in enumerate(rings):
            con.execute("INSERT INTO plan_rings VALUES (?, ?, ?, ?)", (fl.name, role, i, store.f8(ring)))


def ap_ids(con: sqlite3.Connection, bssids: Sequence[str]) -> np.ndarray:
    """The access-point ids of BSSIDs, inserting the new ones."""
    con.executemany("INSERT OR IGNORE INTO access_points (bssid) VALUES (?)", [(b,) for b in bssids])
    ids = dict(con.execute(f"SELECT bssid, id FROM access_points WHERE bssid IN ({','.join('?' * len(bssids))})",
                           list(bssids)).fetchall()) if bssids else {}
    return np.array([ids[b] for b in bssids], dtype=np.int64)


def check_survey_waypoints(walk: Any, source: str) -> np.ndarray:
    """The walk's waypoint times [s]; ValueError naming ``source`` when it has fewer than two
    (a survey walk places its readings between waypoints)."""
    wt = np.asarray(walk.waypoint_t_s, float)
    if wt.size < 2:
        raise ValueError(f"indoorloc: walk {source}: {wt.size} waypoint(s); a survey walk needs at least 2 "
                         f"(a walk without waypoints can be tracked, not surveyed)")
    return wt


def insert_survey_walk(con: sqlite3.Connection, walk: Any, floor: str, seq: int,
                        settings: site_model.TrackSettings, source: str) -> None:
    """Insert a survey walk (waypoints required): its row, PDR intervals, fingerprints, beacon sightings."""
    wt = check_survey_waypoints(walk, source)
    if con.execute("SELECT 1 FROM walks WHERE id = ?", (walk.walk_id,)).fetchone():
        raise ValueError(f"indoorloc: walk {source}: walk id {walk.walk_id} is already in the site")
    wxy = np.asarray(walk.waypoint_xy_m, float).reshape(-1, 2)
    steps = ph.handheld_steps(walk)
    con.execute("INSERT INTO walks VALUES (?, ?, ?, ?, 'survey', 1.0, ?, ?, ?)",
                (walk.walk_id, seq, floor, source, now(), int(wt.size), float(walk.duration_s)))
    iv = ph.waypoint_intervals(steps, wt, wxy)
    con.execute(f"INSERT INTO calibration_intervals VALUES (?, ?, {', '.join('?' * len(store.INTERVAL_FIELDS))})",
                (walk.walk_id, floor, *[store.f8(getattr(iv, f)) for f in store.INTERVAL_FIELDS]))
    insert_fingerprints(con, floor, walk.walk_id, wifi_fixes.walk_fingerprints(walk, settings.fixes, steps), 1.0)
    b = walk.beacons
    if b.n_readings:
        pos = crowdsourced_map.walk_positions(walk, b.t_s, None, steps)
        keep = np.flatnonzero(pos.valid & np.isfinite(b.rssi_dbm))
        con.executemany("INSERT INTO beacons VALUES (?, ?, ?, ?, ?, ?, ?)",
                        [(floor, walk.walk_id, float(b.t_s[i]), float(pos.xy_m[i, 0]), float(pos.xy_m[i, 1]),
                          f"{b.uuid[i]}:{b.major[i]}:{b.minor[i]}", float(b.rssi_dbm[i])) for i in keep])


def calibrate(con: sqlite3.Connection, floor: str, exclude_walk: Optional[str] = None) -> ph.HandheldCalibration:
    """The floor's PDR calibration from the stored intervals of its survey walks (all but ``exclude_walk``)."""
    rows = con.execute(f"SELECT c.walk, {', '.join(store.INTERVAL_FIELDS)} FROM calibration_intervals c JOIN walks w "
                       f"ON w.id = c.walk WHERE c.floor = ? AND w.kind = 'survey' ORDER BY w.seq", (floor,)).fetchall()
    intervals = [ph.WaypointIntervals(*[store.from_f8(v, 2 if f.startswith("disp") else 1)
                                        for f, v in zip(store.INTERVAL_FIELDS, row[1:])])
                 for row in rows if row[0] != exclude_walk]
    try:
        return ph.calibrate_from_intervals(intervals)
    except ValueError as exc:
        raise ValueError(f"indoorloc: floor {floor}: cannot calibrate the PDR from its survey walks ({exc})") from None


def insert_fingerprints(con: sqlite3.Connection, floor: str, walk_id: str, got, weight: float) -> int:
    """Insert a walk's fingerprints (``wifi_fixes.walk_fingerprints``' tuple or None); their number."""
    if got is None:
        return 0
    rss, xy, names, t_s = got
    ids = ap_ids(con, names)
    heard = np.isfinite(rss)
    rows = []
    for i in range(rss.shape[0]):
        cols = np.flatnonzero(heard[i])
        rows.append((floor, walk_id, float(t_s[i]), float(xy[i, 0]), float(xy[i, 1]), float(weight),
                     ids[cols].astype("<i4").tobytes(), rss[i, cols].astype("<f4").tobytes()))
    con.executemany("INSERT INTO fingerprints (floor, walk, t_s, x_m, y_m, weight, ap_ids, rss_dbm) "
                    "VALUES (?, ?, ?, ?, ?, ?, ?, ?)", rows)
    return len(rows)


def recalibrate(con: sqlite3.Connection, floor: str) -> None:
    """Recompute and store the floor's PDR calibration from its survey walks' intervals."""
    cal = calibrate(con, floor)
    con.execute("INSERT OR REPLACE INTO pdr_calibration VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (floor, cal.k, cal.yaw_offset_rad, cal.yaw_offset_spread_rad, cal.length_sd_fraction,
                 cal.heading_sd_rad, cal.k_rms_residual_m, cal.n_intervals, json.dumps(asdict(cal.options))))


def store_fingerprint_columns(con: sqlite3.Connection, floor: str, settings: wfx.FixSettings) -> None:
    """Store the floor's fingerprint-map columns and AP reliabilities as :func:`database` derives
    them (the C++ reader, ``SiteFile::Fingerprints``, reads them instead of recomputing the
    reliabilities: one implementation). Call after every change of the floor's fingerprints."""
    con.execute(store.FINGERPRINT_COLUMNS_SCHEMA)
    con.execute("DELETE FROM fingerprint_columns WHERE floor = ?", (floor,))
    if not con.execute("SELECT 1 FROM fingerprints WHERE floor = ? LIMIT 1", (floor,)).fetchone():
        return
    db = database(con, [floor], settings)
    ratio = db.ap_ratio if db.ap_ratio is not None else np.ones(len(db.bssids))
    con.executemany("INSERT INTO fingerprint_columns VALUES (?, ?, ?, ?)",
                    [(floor, j, b, float(r)) for j, (b, r) in enumerate(zip(db.bssids, ratio))])


# ---- reading ---------------------------------------------------------------------------------
def plan(con: sqlite3.Connection, name: str, number: int, origin: tuple) -> FloorPlan:
    """The floor's walkable plan from its stored GeoJSON, in the floor frame of ``origin`` (lon, lat) [deg]."""
    text = con.execute("SELECT geojson FROM floors WHERE name = ?", (name,)).fetchone()[0]
    return load_floor_plan(json.loads(text), floors=[number], origin_lon_lat=origin)


def calibration(con: sqlite3.Connection, name: str) -> ph.HandheldCalibration:
    """The floor's stored PDR calibration."""
    row = con.execute("SELECT k, yaw_offset_rad, yaw_offset_spread_rad, length_sd_fraction, heading_sd_rad, "
                      "k_rms_residual_m, n_intervals, options FROM pdr_calibration WHERE floor = ?", (name,)).fetchone()
    if row is None:
        raise store.SiteFileError(f"indoorloc: floor {name}: no PDR calibration in the site file")
    k, yaw, spread, f, s, rms, n, options = row
    return ph.HandheldCalibration(ph.HandheldOptions(**json.loads(options)), k, rms, n, yaw, spread, f, s)


def database(con: sqlite3.Connection, floors: Sequence[str], settings: wifi_fixes.FixSettings,
              exclude_walk: Optional[str] = None) -> wifi_fixes.FingerprintDatabase:
    """The fingerprint database of the floors, as ``wifi_fixes.build_database`` of their walks
    (all but ``exclude_walk``)."""
    bssid = dict(con.execute("SELECT id, bssid FROM access_points").fetchall())
    number = dict(con.execute("SELECT name, number FROM floors").fetchall())
    per_walk, weights, current, rows = [], [], None, []

    def flush():
        if not rows:
            return
        ids = sorted({int(a) for r in rows for a in np.frombuffer(r[3], "<i4")})
        col = {a: j for j, a in enumerate(ids)}
        rss = np.full((len(rows), len(ids)), np.nan)
        for i, r in enumerate(rows):
            a = np.frombuffer(r[3], "<i4")
            rss[i, [col[int(x)] for x in a]] = np.frombuffer(r[4], "<f4")
        xy = np.array([(r[1], r[2]) for r in rows], float)
        per_walk.append((rss, xy, [bssid[a] for a in ids], np.full(len(rows), number[rows[0][5]]),
                         np.full(len(rows), rows[0][6])))
        weights.append(np.array([r[7] for r in rows], float))

    marks = ",".join("?" * len(floors))
    for r in con.execute(f"SELECT f.walk, f.x_m, f.y_m, f.ap_ids, f.rss_dbm, f.floor, w.seq, f.weight FROM fingerprints f "
                         f"JOIN walks w ON w.id = f.walk WHERE f.floor IN ({marks}) ORDER BY w.seq, f.id",
                         list(floors)):
        if r[0] == exclude_walk:
            continue
        if r[0] != current:
            flush()
            current, rows = r[0], []
        rows.append(tuple(r))
    flush()
    return wifi_fixes.assemble_database(per_walk, settings, weights)



__all__ = ["calibrate", "calibration", "database", "insert_fingerprints", "insert_floor", "insert_survey_walk", "now", "plan", "recalibrate",
           "store_fingerprint_columns"]
