"""The site file: one SQLite database per site, a table per concept (docs/your_building.md,
"The site file"). This module owns the schema, the format check on opening and the array blobs;
:mod:`indoorloc.fusion.site` builds and reads the models.

Why SQLite: a site grows walk by walk without a rebuild, is inspected with ordinary tools
(``sqlite3 SITE.db .tables``), survives a crash mid-write (every change is one transaction: the
old content stays until COMMIT) and is read from C++ without Python (``cpp/include/indoorloc/
fusion/site_file.h``, Debian's libsqlite3).

Arrays are little-endian blobs: float64 (``<f8``) unless said; a fingerprint keeps only the APs it
heard, as AP ids (``<i4``) and RSS [dBm] (``<f4``; the competition's RSS are integers).
"""

from __future__ import annotations

import sqlite3
from pathlib import Path
from typing import Any

import numpy as np

FORMAT_VERSION = 1
#: PRAGMA application_id of a site file ("ILOC"): a foreign SQLite file is told apart from an old site.
APPLICATION_ID = 0x494C4F43

SCHEMA = """
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE floors (
  name TEXT PRIMARY KEY, number INTEGER NOT NULL UNIQUE,
  geojson TEXT NOT NULL,              -- the floor's geojson_map.json as surveyed (WGS84)
  origin_lon REAL NOT NULL, origin_lat REAL NOT NULL,  -- floor frame origin: metres east/north of it
  walkable_area_m2 REAL NOT NULL, width_m REAL, height_m REAL, source TEXT NOT NULL);
CREATE TABLE plan_rings (             -- the walkable plan in the floor frame (what C++ reads)
  floor TEXT NOT NULL REFERENCES floors(name), role TEXT NOT NULL CHECK (role IN ('outline', 'obstacle')),
  ring INTEGER NOT NULL, xy_m BLOB NOT NULL, PRIMARY KEY (floor, role, ring));
CREATE TABLE walks (
  id TEXT PRIMARY KEY, seq INTEGER NOT NULL UNIQUE, floor TEXT NOT NULL REFERENCES floors(name),
  source TEXT NOT NULL, kind TEXT NOT NULL CHECK (kind IN ('survey', 'grown')), weight REAL NOT NULL,
  added TEXT NOT NULL, n_waypoints INTEGER NOT NULL, duration_s REAL NOT NULL);
CREATE TABLE access_points (id INTEGER PRIMARY KEY, bssid TEXT NOT NULL UNIQUE);
CREATE TABLE fingerprints (
  id INTEGER PRIMARY KEY, floor TEXT NOT NULL REFERENCES floors(name), walk TEXT NOT NULL REFERENCES walks(id),
  t_s REAL NOT NULL, x_m REAL NOT NULL, y_m REAL NOT NULL, weight REAL NOT NULL,
  ap_ids BLOB NOT NULL, rss_dbm BLOB NOT NULL);
CREATE INDEX fingerprints_floor ON fingerprints (floor, walk);
CREATE TABLE beacons (                -- iBeacon sightings placed like the fingerprints
  floor TEXT NOT NULL REFERENCES floors(name), walk TEXT NOT NULL REFERENCES walks(id),
  t_s REAL NOT NULL, x_m REAL NOT NULL, y_m REAL NOT NULL, beacon TEXT NOT NULL, rssi_dbm REAL NOT NULL);
CREATE TABLE calibration_intervals (  -- per survey walk: PDR between waypoints (pdr_handheld.WaypointIntervals)
  walk TEXT PRIMARY KEY REFERENCES walks(id), floor TEXT NOT NULL REFERENCES floors(name),
  distance_m BLOB, direction_rad BLOB, n_steps BLOB, feature_sum BLOB, path_m BLOB, length_sq_sum BLOB,
  disp_rv_m BLOB, disp_gyro_m BLOB, disp_comp_m BLOB);
CREATE TABLE pdr_calibration (
  floor TEXT PRIMARY KEY REFERENCES floors(name), k REAL NOT NULL, yaw_offset_rad REAL NOT NULL,
  yaw_offset_spread_rad REAL NOT NULL, length_sd_fraction REAL NOT NULL, heading_sd_rad REAL NOT NULL,
  k_rms_residual_m REAL NOT NULL, n_intervals INTEGER NOT NULL, options TEXT NOT NULL);
CREATE TABLE tracker_settings (name TEXT PRIMARY KEY, settings TEXT NOT NULL);
CREATE TABLE fingerprint_columns (   -- per floor the fingerprint map's columns as the Python side builds them
  floor TEXT NOT NULL REFERENCES floors(name), col INTEGER NOT NULL, bssid TEXT NOT NULL,
  ap_ratio REAL NOT NULL,             -- the AP's reliability (wifi_matcher.ap_reliability, power 1)
  PRIMARY KEY (floor, col));         -- derived from the fingerprints: rewritten whenever a floor's change
CREATE TABLE grid_options (           -- fusion::GridTrackerOptions by field name (booleans 0/1, fix.* as fix_*)
  name TEXT PRIMARY KEY, value REAL NOT NULL);  -- per floor heading_offset_sd_rad = max(yaw_offset_spread_rad, 1e-3)
"""

#: The derived table added after format version 1 was released (files without it are still read;
#: the C++ reader needs it for live tracking; the next write of a floor adds it).
FINGERPRINT_COLUMNS_SCHEMA = SCHEMA[SCHEMA.index("CREATE TABLE fingerprint_columns"):].split(";")[0].replace(
    "CREATE TABLE", "CREATE TABLE IF NOT EXISTS", 1)

INTERVAL_FIELDS = ("distance_m", "direction_rad", "n_steps", "feature_sum", "path_m", "length_sq_sum",
                   "disp_rv_m", "disp_gyro_m", "disp_comp_m")


def f8(a: Any) -> bytes:
    """float64 little-endian blob."""
    return np.ascontiguousarray(np.asarray(a, dtype="<f8")).tobytes()


def from_f8(b: bytes, cols: int = 1) -> np.ndarray:
    a = np.frombuffer(b, dtype="<f8").astype(np.float64)
    return a.reshape(-1, cols) if cols > 1 else a


class SiteFileError(ValueError):
    """A file that is not a readable site file of this format (names the file)."""


def create(path: Path) -> sqlite3.Connection:
    """A new site database at ``path`` (which must not exist), schema in place, not committed."""
    con = sqlite3.connect(str(path), isolation_level=None)
    con.execute("PRAGMA foreign_keys = ON")
    con.execute("BEGIN")
    for statement in SCHEMA.split(";"):
        if statement.strip():
            con.execute(statement)
    con.execute(f"PRAGMA application_id = {APPLICATION_ID}")
    con.execute(f"PRAGMA user_version = {FORMAT_VERSION}")
    return con


def connect(path: Path, write: bool = False) -> sqlite3.Connection:
    """Open an existing site file, checking that it is one, of this format version, and intact.

    Raises SiteFileError naming the file: not found, not SQLite, another application's SQLite
    file, another format version, or damaged (``PRAGMA quick_check``)."""
    path = Path(path)
    if not path.is_file():
        raise SiteFileError(f"indoorloc: site file {path}: not found")
    with open(path, "rb") as fh:
        head = fh.read(100)
    if not head.startswith(b"SQLite format 3\x00"):
        raise SiteFileError(f"indoorloc: site file {path}: not an SQLite file (not a site built by "
                            f"'indoorloc site build')")
    try:
        # Read-write when the file allows it, so that SQLite can roll back the hot journal of a
        # writer killed mid-transaction (the old content comes back); read-only otherwise.
        con = sqlite3.connect(str(path), isolation_level=None)
        app = con.execute("PRAGMA application_id").fetchone()[0]
        version = con.execute("PRAGMA user_version").fetchone()[0]
        if app != APPLICATION_ID:
            con.close()
            raise SiteFileError(f"indoorloc: site file {path}: an SQLite file of another application "
                                f"(application_id {app:#x}), not an indoorloc site")
        if version != FORMAT_VERSION:
            con.close()
            raise SiteFileError(f"indoorloc: site file {path}: format version {version}, this indoorloc reads "
                                f"version {FORMAT_VERSION} (rebuild it with 'indoorloc site build')")
        check = con.execute("PRAGMA quick_check").fetchone()[0]
        if check != "ok":
            con.close()
            raise SiteFileError(f"indoorloc: site file {path}: damaged ({check})")
    except sqlite3.DatabaseError as exc:
        raise SiteFileError(f"indoorloc: site file {path}: damaged or truncated ({exc})") from None
    con.execute("PRAGMA foreign_keys = ON")
    return con


def meta(con: sqlite3.Connection) -> dict:
    return dict(con.execute("SELECT key, value FROM meta").fetchall())


__all__ = ["APPLICATION_ID", "FINGERPRINT_COLUMNS_SCHEMA", "FORMAT_VERSION", "INTERVAL_FIELDS", "SCHEMA", "SiteFileError", "connect", "create",
           "f8", "from_f8", "meta"]
