"""Loader for the Indoor Location Competition 2.0 walk format (numpy + json only).

The Microsoft / XYZ10 Indoor Location Competition 2.0 published smartphone recordings as one
text file per walk, under ``<site>/<floor>/path_data_files/<walk id>.txt``, beside
``<site>/<floor>/floor_info.json`` and ``geojson_map.json`` (the Kaggle 2021 edition keeps the
walks in the floor folder itself, ``<site>/<floor>/<walk id>.txt``). Every data line is
tab-separated ``unix_ms  TYPE_...  values...``; ``#`` lines carry the header. This module reads
any folder in that layout into numpy arrays:

- :func:`read_ilc_walk`: one walk file -> :class:`IlcWalk` (sensor streams with their own
  times, WiFi readings, iBeacon readings, waypoints, header metadata);
- :func:`read_ilc_floor`: one floor folder -> :class:`IlcFloor` (floor extent, GeoJSON path,
  the walk files, loaded on demand, and a floor-level BSSID vocabulary,
  :class:`BssidVocabulary`);
- :func:`read_ilc_site`: a site folder -> ``{floor name: IlcFloor}`` in building order
  (:func:`ilc_floor_names`: B2, B1, F1, F2, ...);
- :func:`ilc_floor_names`: the floor folders of a site in building order (what
  ``indoorloc fusion evaluate`` evaluates when no ``--floors`` is given);
- :func:`ilc_floor_origin_lonlat`: the (lon, lat) of the floor frame's origin (the south-west
  corner of the first GeoJSON feature's bounding box). The floor polygons themselves are read
  by :mod:`indoorloc.io.floor_plan`.

Records
-------
=========================================  ====================================================
``TYPE_ACCELEROMETER`` / ``_GYROSCOPE`` /   x, y, z, accuracy (m/s^2, rad/s, uT; Android
``_MAGNETIC_FIELD``                         device frame)
``..._UNCALIBRATED``                        x, y, z, bias x, y, z, accuracy
``TYPE_ROTATION_VECTOR``                    x, y, z, [w], accuracy (unit-quaternion parts)
``TYPE_WIFI``                               ssid, bssid, rssi [dBm], frequency [MHz],
                                            last-seen time [unix ms]; one scan is the group
                                            of rows with the same first column
``TYPE_BEACON``                             uuid, major, minor, tx power [dBm], rssi [dBm],
                                            distance [m], mac, [time, unix ms]
``TYPE_WAYPOINT``                           x, y [m] in the floor frame (the ground truth)
=========================================  ====================================================

Every other record type (``TYPE_BLUE``, ``TYPE_BLU4``, ``TYPE_DIST1``, ``TYPE_DIST2``,
``TYPE_SENSOR_MAGNETIC_FIELD_ACCURACY_CHANGED``, ...) is skipped and counted in
:attr:`IlcWalk.unknown_type_counts`.

Times
-----
Each stream keeps its own times, in seconds since the walk's first record
(:attr:`IlcWalk.t0_unix_ms`, the smallest time stamp of the parsed records); WiFi last-seen
times are on the same clock and can be negative (an access point last seen before the walk
started). Times must be non-decreasing within each record type (true of every file of the
shared site); otherwise :func:`read_ilc_walk` raises, or sorts when ``allow_unsorted=True``
and says so in :attr:`IlcWalk.notes`.

Errors: nothing is lost
-----------------------
One rule (docs/errors.md, "Loader rule: nothing is lost"): only damage to what the methods need
rejects a walk. Needed are the time stamp and record type of every line read, the x, y, z of the
sensor streams, the BSSID and RSSI of a WiFi reading, and the waypoints. A damaged needed field
(not a finite number, a non-integer time stamp, an empty BSSID) or a field count that does not
match the type raises ``FormatError("indoorloc: argument 'path': <file>, line <n>: ...")`` with
the 1-based line number and what is wrong.

A damaged *optional* field (not a number, ``Infinity``/``NaN``, empty, or not an integer where
one belongs) is dropped for that line only and the line is kept, with a fallback value:

=====================================  ==================================================
sensor ``accuracy``                    -1 (no usable status, as Android's NO_CONTACT)
``_UNCALIBRATED`` bias x, y, z         NaN
rotation vector ``w``                  NaN (completed as when the file has no w)
WiFi ``frequency``                     NaN
WiFi ``last_seen_unix_ms``             the scan time (the reading looks fresh, age 0:
                                       flagged in :attr:`IlcWifi.last_seen_fallback`)
iBeacon tx power, RSSI, distance       NaN
iBeacon major, minor                   -1
=====================================  ==================================================

An iBeacon line with a wrong field count is dropped (no method reads iBeacons). The file's last
line, when it is a data line cut short (an interrupted recording: no record type or a record
type cut short, fewer fields than its type needs, or a last field that is an incomplete number
such as ``""``, ``"-"`` or ``"1e"``), is dropped. Whatever is dropped is counted in
:attr:`IlcWalk.dropped_fields` (``"<TYPE> <field>"`` -> lines), described in
:attr:`IlcWalk.notes`, and reported by ONE :class:`~indoorloc.io.errors.RecordingWarning` per
walk naming the file. Floor readers (:meth:`IlcFloor.walks`, :meth:`IlcFloor.bssid_vocabulary`,
:func:`describe_ilc_floor`) skip a walk that cannot be read, with a RecordingWarning naming the
file and the reason, and list it in :attr:`IlcFloor.skipped_walks` and
:meth:`IlcFloor.load_report`.

Speed
-----
Lines are classified by record type with numpy on the raw bytes (no Python loop per line);
the numeric fields of each type are gathered into one buffer and parsed by ``np.loadtxt``. Only
lines holding a byte that cannot be part of a number (or an empty field) are parsed in Python,
one field at a time (the slow path: e.g. the 341 ``Infinity`` distances of the shared F1).
A file of 1.3 MB loads in about 40 ms; the 119 walks of the shared site (160 MB) in about 5 s
on one core.

Examples
--------
>>> from indoorloc.io import read_ilc_site
>>> site = read_ilc_site("../shared/data/fusion/ilc2020_site2")  # doctest: +SKIP
>>> floor = site["F3"]; walk = floor.walk(0)  # doctest: +SKIP
>>> walk.accelerometer.values.shape, walk.wifi.n_scans, walk.waypoint_xy_m.shape  # doctest: +SKIP
((1403, 3), 10, (6, 2))
"""

from __future__ import annotations

import io
import json
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterable, Iterator, List, Optional, Sequence, Set, Tuple, Union

import numpy as np

from indoorloc.io.errors import RecordingWarning, reads_file

PathLike = Union[str, Path]

_TAB = 9
_NL = 10
_CR = 13

#: Record types read into :class:`IlcSensor` streams: type -> (IlcWalk attribute, unit,
#: names of the value fields after the type, accuracy excluded).
ILC_SENSOR_TYPES: Dict[str, Tuple[str, str, Tuple[str, ...]]] = {
    "TYPE_ACCELEROMETER": ("accelerometer", "m/s^2", ("x", "y", "z")),
    "TYPE_GYROSCOPE": ("gyroscope", "rad/s", ("x", "y", "z")),
    "TYPE_MAGNETIC_FIELD": ("magnetometer", "uT", ("x", "y", "z")),
    "TYPE_ROTATION_VECTOR": ("rotation_vector", "1", ("x", "y", "z")),
    "TYPE_ACCELEROMETER_UNCALIBRATED": ("accelerometer_uncalibrated", "m/s^2",
                                        ("x", "y", "z", "bias x", "bias y", "bias z")),
    "TYPE_GYROSCOPE_UNCALIBRATED": ("gyroscope_uncalibrated", "rad/s",
                                    ("x", "y", "z", "bias x", "bias y", "bias z")),
    "TYPE_MAGNETIC_FIELD_UNCALIBRATED": ("magnetometer_uncalibrated", "uT",
                                         ("x", "y", "z", "bias x", "bias y", "bias z")),
}

_WIFI = "TYPE_WIFI"
_BEACON = "TYPE_BEACON"
_WAYPOINT = "TYPE_WAYPOINT"
_TYPE_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
#: Bytes that may appear in a tab-separated row of numbers; a row with any other byte (a letter
#: as in "Infinity", a space) goes to the slow path.
_NUMBER_BYTES = np.zeros(256, dtype=bool)
_NUMBER_BYTES[np.frombuffer(b"0123456789+-.eE\t\n", dtype=np.uint8)] = True

#: Field layouts of the record types read: type -> the allowed layouts (field names, the time
#: and the type included).
_LAYOUTS: Dict[str, Tuple[Tuple[str, ...], ...]] = {
    t: (("unix_ms", "type") + names + ("accuracy",),) for t, (_, _, names) in ILC_SENSOR_TYPES.items()}
_LAYOUTS["TYPE_ROTATION_VECTOR"] += (("unix_ms", "type", "x", "y", "z", "w", "accuracy"),)
_LAYOUTS[_WIFI] = (("unix_ms", "type", "ssid", "bssid", "rssi", "frequency", "last_seen_unix_ms"),)
_LAYOUTS[_BEACON] = (("unix_ms", "type", "uuid", "major", "minor", "tx_power", "rssi", "distance",
                      "mac"),
                     ("unix_ms", "type", "uuid", "major", "minor", "tx_power", "rssi", "distance",
                      "mac", "time_unix_ms"))
_LAYOUTS[_WAYPOINT] = (("unix_ms", "type", "x", "y"),)
_TEXT_FIELDS = frozenset({"type", "ssid", "bssid", "uuid", "mac"})

#: Optional fields: (record type or "*" for every sensor type, field) -> what replaces a damaged
#: value. Every other numeric field is needed: damage to it rejects the walk.
_OPTIONAL: Dict[Tuple[str, str], str] = {
    ("*", "accuracy"): "-1 (unknown)",
    ("*", "bias x"): "NaN", ("*", "bias y"): "NaN", ("*", "bias z"): "NaN",
    ("TYPE_ROTATION_VECTOR", "w"): "NaN (w completed from x, y, z)",
    (_WIFI, "frequency"): "NaN",
    (_WIFI, "last_seen_unix_ms"): "the scan time",
    (_BEACON, "major"): "-1", (_BEACON, "minor"): "-1",
    (_BEACON, "tx_power"): "NaN", (_BEACON, "rssi"): "NaN", (_BEACON, "distance"): "NaN",
}


def _fallback(type_name: str, name: str) -> Optional[str]:
    """What replaces a damaged value of field ``name`` of ``type_name``; None if it is needed."""
    hit = _OPTIONAL.get((type_name, name))
    if hit is None and type_name in ILC_SENSOR_TYPES:
        hit = _OPTIONAL.get(("*", name))
    return hit


# --------------------------------------------------------------------------------------------
# Containers


@dataclass
class IlcSensor:
    """One Android sensor stream of a walk: N samples with their own times.

    Attributes
    ----------
    type_name : str
        The record type, e.g. ``"TYPE_ACCELEROMETER"``.
    unit : str
        Unit of ``values`` and ``bias``: ``"m/s^2"``, ``"rad/s"``, ``"uT"`` or ``"1"`` (rotation
        vector).
    t_s : numpy.ndarray, shape (N,), float64
        Sample times [s] since the walk's first record, non-decreasing.
    values : numpy.ndarray, shape (N, 3) or (N, 4), float64
        x, y, z in the Android device frame as stored (calibrated values for the calibrated
        types, raw values for the ``_UNCALIBRATED`` ones). The rotation vector has a 4th column
        w only when the file stores it (NaN in rows that lack it); see
        :meth:`IlcWalk.rotation_quaternion_xyzw`.
    accuracy : numpy.ndarray, shape (N,), int64
        Android accuracy status (0 unreliable ... 3 high); -1 where the file's value was
        damaged (dropped, see :attr:`IlcWalk.dropped_fields`).
    bias : numpy.ndarray, shape (N, 3), float64, or None
        Estimated bias of the ``_UNCALIBRATED`` types (NaN where the file's value was damaged);
        None for the calibrated ones.
    """

    type_name: str
    unit: str
    t_s: np.ndarray
    values: np.ndarray
    accuracy: np.ndarray
    bias: Optional[np.ndarray] = None

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.t_s.shape[0])

    @property
    def rate_hz(self) -> float:
        """1 / median time step [Hz] over the steps > 0; NaN with fewer than two samples."""
        dt = np.diff(self.t_s)
        dt = dt[dt > 0]
        return float(1.0 / np.median(dt)) if dt.size else float("nan")


@dataclass
class IlcWifi:
    """The WiFi readings of one walk as parallel arrays; R readings in S scans, V BSSIDs.

    One scan is the group of consecutive readings with the same scan time (the first column
    of the file). A reading's RSSI was measured at its ``last_seen_s``, which can be many
    seconds before the scan time: Android reports cached results, and a later scan can repeat
    an earlier measurement (see :meth:`new_measurement_mask`). One BSSID can appear twice in
    a scan (e.g. on two channels, or once with an empty SSID); every reading is kept.

    Attributes
    ----------
    scan_time_s : numpy.ndarray, shape (R,), float64
        Scan time [s] since the walk's first record, non-decreasing.
    bssid_index : numpy.ndarray, shape (R,), int64
        Index of the reading's BSSID in :attr:`bssids`.
    rssi_dbm : numpy.ndarray, shape (R,), float64
        Received signal strength [dBm].
    frequency_mhz : numpy.ndarray, shape (R,), float64
        Channel centre frequency [MHz].
    last_seen_s : numpy.ndarray, shape (R,), float64
        Time [s] since the walk's first record when the access point was last seen (the time of
        the RSSI measurement); negative when that was before the walk's first record.
    bssids : list of str, length V
        The walk's BSSID vocabulary, sorted.
    ssids : list of str, length V
        SSID of each BSSID: the first non-empty SSID among its readings, else ``""``.
    scan_starts : numpy.ndarray, shape (S,), int64
        Index of each scan's first reading; scan s holds readings
        ``scan_starts[s]:scan_starts[s + 1]`` (the last one up to R).
    last_seen_fallback : numpy.ndarray, shape (R,), bool
        True where the file's last-seen time was empty or damaged and ``last_seen_s`` is the
        scan time instead (all False normally). Such a reading looks fresh (age 0) although
        Android may have measured it seconds earlier: a method that relies on the age can drop
        these readings (``wifi.rssi_dbm[~wifi.last_seen_fallback]``).
    """

    scan_time_s: np.ndarray
    bssid_index: np.ndarray
    rssi_dbm: np.ndarray
    frequency_mhz: np.ndarray
    last_seen_s: np.ndarray
    bssids: List[str]
    ssids: List[str]
    scan_starts: np.ndarray
    last_seen_fallback: Optional[np.ndarray] = None

    def __post_init__(self) -> None:
        if self.last_seen_fallback is None:
            self.last_seen_fallback = np.zeros(self.scan_time_s.shape[0], dtype=bool)

    @property
    def n_readings(self) -> int:
        """Number of readings R."""
        return int(self.scan_time_s.shape[0])

    @property
    def n_scans(self) -> int:
        """Number of scans S."""
        return int(self.scan_starts.shape[0])

    @property
    def scan_times_s(self) -> np.ndarray:
        """(S,) time [s] of each scan."""
        return self.scan_time_s[self.scan_starts]

    @property
    def scan_index(self) -> np.ndarray:
        """(R,) int64: the scan each reading belongs to."""
        counts = np.diff(np.append(self.scan_starts, self.n_readings))
        return np.repeat(np.arange(self.n_scans, dtype=np.int64), counts)

    @property
    def age_s(self) -> np.ndarray:
        """(R,) scan time minus last-seen time [s]: how stale each reading is."""
        return self.scan_time_s - self.last_seen_s

    def new_measurement_mask(self) -> np.ndarray:
        """(R,) bool: True for the first reading of each (BSSID, last-seen time) pair.

        Android repeats cached results: a later scan can report the same measurement again
        (same BSSID, last-seen time and RSSI; about half of the readings of the shared site).
        Using only the first report of each measurement avoids counting it several times.
        """
        mask = np.zeros(self.n_readings, dtype=bool)
        if self.n_readings:
            key = np.stack([self.bssid_index, np.round(self.last_seen_s * 1000.0)
                            .astype(np.int64)], axis=1)
            first = np.unique(key, axis=0, return_index=True)[1]
            mask[first] = True
        return mask

    def scan_slice(self, s: int) -> slice:
        """The readings of scan ``s`` (0 <= s < S) as a slice of the (R,) arrays."""
        if not 0 <= s < self.n_scans:
            raise IndexError(f"indoorloc: argument 's': scan {s} outside 0..{self.n_scans - 1}")
        stop = self.scan_starts[s + 1] if s + 1 < self.n_scans else self.n_readings
        return slice(int(self.scan_starts[s]), int(stop))


@dataclass
class IlcBeacons:
    """The iBeacon readings of one walk (sparse); B readings.

    No method of indoorloc reads them: every field but the time is optional, so a damaged value
    is dropped (-1 for major and minor, NaN for the float fields), e.g. the distance
    ``Infinity`` that the phone wrote on 341 lines of the shared F1.

    Attributes
    ----------
    t_s : numpy.ndarray, shape (B,), float64
        Time [s] since the walk's first record.
    uuid : list of str
        iBeacon proximity UUID.
    major, minor : numpy.ndarray, shape (B,), int64
        iBeacon major and minor numbers (-1 where damaged).
    tx_power_dbm, rssi_dbm : numpy.ndarray, shape (B,), float64
        Calibrated power at 1 m and received strength [dBm] (NaN where damaged).
    distance_m : numpy.ndarray, shape (B,), float64
        The phone's distance estimate [m]; NaN where the file's value was not a finite number.
    mac : list of str
        Beacon MAC address.
    """

    t_s: np.ndarray
    uuid: List[str]
    major: np.ndarray
    minor: np.ndarray
    tx_power_dbm: np.ndarray
    rssi_dbm: np.ndarray
    distance_m: np.ndarray
    mac: List[str]

    @property
    def n_readings(self) -> int:
        """Number of readings B."""
        return int(self.t_s.shape[0])


@dataclass
class IlcWalk:
    """One walk file of the Indoor Location Competition 2.0 format.

    Attributes
    ----------
    path : pathlib.Path
        The file read.
    walk_id : str
        The file name without ``.txt`` (the path id of the competition).
    t0_unix_ms : int
        Unix time [ms] of the walk's first record: the zero of every ``*_s`` time.
    accelerometer, gyroscope, magnetometer, rotation_vector : IlcSensor
        The calibrated streams (N may be 0 when the file has none).
    accelerometer_uncalibrated, gyroscope_uncalibrated, magnetometer_uncalibrated : IlcSensor
        The ``_UNCALIBRATED`` streams, with ``bias``.
    wifi : IlcWifi
        The WiFi readings.
    beacons : IlcBeacons
        The iBeacon readings.
    waypoint_t_s : numpy.ndarray, shape (W,), float64
        Waypoint times [s] since the walk's first record.
    waypoint_xy_m : numpy.ndarray, shape (W, 2), float64
        Waypoint x, y [m] in the floor frame (east and north of the floor's origin).
    metadata : dict
        The ``#`` header lines: ``key: value`` strings as stored (``startTime``, ``SiteID``,
        ``SiteName``, ``FloorId``, ``FloorName``, ``Brand``, ``Model``, ``AndroidName``,
        ``APILevel``, ``VersionName``, ``endTime``, ... where present) and ``"sensors"``, a
        list of one dict per sensor line (``type``, ``name``, ``vendor``, ``resolution``,
        ``power``, ``maximumRange``, ...; numbers converted).
    unknown_type_counts : dict of str to int
        Lines skipped per record type not read by this loader.
    notes : list of str
        What the loader changed, one sentence each: damaged optional fields dropped (with the
        count, the first line and value, and the fallback), a truncated last line dropped,
        streams sorted with ``allow_unsorted=True``; empty normally.
    dropped_fields : dict of str to int
        Lines whose field was dropped, per ``"<TYPE> <field>"`` (e.g. ``"TYPE_BEACON
        distance"``), plus ``"TYPE_BEACON line"`` (iBeacon lines with a wrong field count) and
        ``"truncated last line"``; empty normally. A non-empty dict came with one
        RecordingWarning.
    """

    path: Path
    walk_id: str
    t0_unix_ms: int
    accelerometer: IlcSensor
    gyroscope: IlcSensor
    magnetometer: IlcSensor
    rotation_vector: IlcSensor
    accelerometer_uncalibrated: IlcSensor
    gyroscope_uncalibrated: IlcSensor
    magnetometer_uncalibrated: IlcSensor
    wifi: IlcWifi
    beacons: IlcBeacons
    waypoint_t_s: np.ndarray
    waypoint_xy_m: np.ndarray
    metadata: Dict[str, Any]
    unknown_type_counts: Dict[str, int] = field(default_factory=dict)
    notes: List[str] = field(default_factory=list)
    dropped_fields: Dict[str, int] = field(default_factory=dict)

    @property
    def sensors(self) -> Dict[str, IlcSensor]:
        """The seven sensor streams keyed by record type."""
        return {t: getattr(self, attr) for t, (attr, _, _) in ILC_SENSOR_TYPES.items()}

    @property
    def n_waypoints(self) -> int:
        """Number of waypoints W."""
        return int(self.waypoint_t_s.shape[0])

    @property
    def duration_s(self) -> float:
        """Time of the walk's last parsed record [s] (the first is at 0)."""
        ends = [s.t_s[-1] for s in self.sensors.values() if s.n_samples]
        for t in (self.wifi.scan_time_s, self.beacons.t_s, self.waypoint_t_s):
            if t.size:
                ends.append(t[-1])
        return float(max(ends)) if ends else 0.0

    @property
    def site_id(self) -> str:
        """``SiteID`` of the header, or ``""``."""
        return str(self.metadata.get("SiteID", ""))

    @property
    def floor_name(self) -> str:
        """``FloorName`` of the header, or ``""``."""
        return str(self.metadata.get("FloorName", ""))

    @property
    def device(self) -> str:
        """``"Brand Model"`` of the header (e.g. ``"OPPO PBCM10"``), or ``""``."""
        return " ".join(str(self.metadata[k]) for k in ("Brand", "Model") if k in self.metadata)

    def rotation_quaternion_xyzw(self) -> np.ndarray:
        """(N, 4) unit quaternions (x, y, z, w) of the rotation vector stream.

        Android's rotation vector is the vector part of the unit quaternion rotating the device
        frame into the east-north-up frame; w is taken from the file where stored and otherwise
        completed as ``sqrt(max(0, 1 - x^2 - y^2 - z^2))`` (Android's
        ``SensorManager.getQuaternionFromVector``), then every row is normalised.
        """
        v = self.rotation_vector.values
        q = np.empty((v.shape[0], 4), dtype=np.float64)
        q[:, :3] = v[:, :3]
        w = np.sqrt(np.maximum(0.0, 1.0 - np.sum(v[:, :3] ** 2, axis=1)))
        if v.shape[1] == 4:
            w = np.where(np.isnan(v[:, 3]), w, v[:, 3])
        q[:, 3] = w
        norm = np.linalg.norm(q, axis=1, keepdims=True)
        return q / np.where(norm > 0, norm, 1.0)


# --------------------------------------------------------------------------------------------
# Parsing


def _err(message: str) -> ValueError:
    return ValueError(f"indoorloc: argument 'path': {message}")


def _gather_ranges(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Concatenation of ``arange(a[i], b[i])`` over i (vectorised); b >= a."""
    lens = b - a
    total = int(lens.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    ends = np.cumsum(lens)
    return np.arange(total, dtype=np.int64) + np.repeat(a - (ends - lens), lens)


class _WalkText:
    """The raw bytes of one walk file with line and tab positions (all numpy).

    A last data line cut short (an interrupted recording, see :func:`_truncation`) is taken out
    of the data lines and kept in :attr:`truncated` as (line number, text, reason).
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        raw = path.read_bytes()
        self.raw = raw
        buf = np.frombuffer(raw, dtype=np.uint8)
        # Two sentinel bytes after the text: a tab and a newline, used as field separators when
        # gathering fields of many lines into one buffer (see _fields_bytes).
        self.bufx = np.concatenate([buf, np.array([_TAB, _NL], dtype=np.uint8)])
        self.tab_pos = len(raw)
        self.nl_pos = len(raw) + 1
        nl = np.flatnonzero(buf == _NL)
        starts = np.concatenate([[0], nl + 1]).astype(np.int64)
        ends = np.concatenate([nl, [len(raw)]]).astype(np.int64)
        if raw.startswith(b"\xef\xbb\xbf"):  # UTF-8 byte-order mark
            starts[0] = min(3, int(ends[0]))
        line_no = np.arange(1, starts.size + 1, dtype=np.int64)
        if buf.size:  # a CR before the LF (Windows line ends) is not part of the line
            ends = ends - ((ends > starts) & (buf[np.maximum(ends - 1, 0)] == _CR))
        nonempty = ends > starts
        starts, ends, line_no = starts[nonempty], ends[nonempty], line_no[nonempty]
        header = buf[starts] == ord("#")
        self.header_lines = [self.line_text(int(s), int(e))
                             for s, e in zip(starts[header], ends[header])]
        data = ~header
        # The file's last line, when a data line cut short, is an interrupted recording.
        self.truncated: Optional[Tuple[int, str, str]] = None
        if starts.size and data[-1]:
            last = self.line_text(int(starts[-1]), int(ends[-1]))
            reason = _truncation(last)
            if reason is not None:
                self.truncated = (int(line_no[-1]), last, reason)
                data[-1] = False
        self.starts, self.ends, self.line_no = starts[data], ends[data], line_no[data]
        self.tabs = np.flatnonzero(buf == _TAB).astype(np.int64)
        self.first_tab_index = np.searchsorted(self.tabs, self.starts)
        self.n_tabs = np.searchsorted(self.tabs, self.ends) - self.first_tab_index

    # -- helpers -----------------------------------------------------------------------------

    def line_text(self, start: int, end: int) -> str:
        return self.raw[start:end].decode("utf-8", errors="replace")

    def where(self, i: int) -> str:
        """``"<file>, line <n>"`` of data line i."""
        return f"{self.path}, line {int(self.line_no[i])}"

    def shown(self, i: int, limit: int = 120) -> str:
        return _shown(self.line_text(int(self.starts[i]), int(self.ends[i])), limit)

    def field_bounds(self, sel: np.ndarray, j: int) -> Tuple[np.ndarray, np.ndarray]:
        """Byte range [a, b) of field j (0 = time, 1 = type, ...) of the data lines ``sel``.

        The lines must have more than j - 1 tabs; the last field runs to the end of the line.
        """
        i0 = self.first_tab_index[sel]
        ntab = self.n_tabs[sel]
        if j == 0:
            a = self.starts[sel]
        else:
            a = self.tabs[i0 + j - 1] + 1
        last = j >= ntab
        b = np.where(last, self.ends[sel], self.tabs[np.minimum(i0 + j, self.tabs.size - 1)]
                     if self.tabs.size else self.ends[sel])
        return a, b

    def field_str(self, i: int, j: int) -> str:
        """Field j of data line i as text (Python, for a few lines only)."""
        a, b = self.field_bounds(np.array([i]), j)
        return self.line_text(int(a[0]), int(b[0]))

    def fields_bytes(self, sel: np.ndarray, fields: Sequence[int]) -> bytes:
        """Fields ``fields`` (increasing) of the lines ``sel``, tab-separated, one line per row."""
        runs: List[List[int]] = []  # consecutive fields are copied as one byte range
        for j in fields:
            if runs and j == runs[-1][-1] + 1:
                runs[-1].append(j)
            else:
                runs.append([j])
        a_parts, b_parts = [], []
        for k, run in enumerate(runs):
            a, _ = self.field_bounds(sel, run[0])
            _, b = self.field_bounds(sel, run[-1])
            sep = self.nl_pos if k == len(runs) - 1 else self.tab_pos
            a_parts += [a, np.full_like(a, sep)]
            b_parts += [b, np.full_like(a, sep + 1)]
        a = np.stack(a_parts, axis=1).ravel()
        b = np.stack(b_parts, axis=1).ravel()
        return self.bufx[_gather_ranges(a, b)].tobytes()

    # -- record types ------------------------------------------------------------------------

    def classify(self) -> Tuple[List[str], np.ndarray]:
        """Record type of every data line: (type names, (L,) index into them)."""
        if self.starts.size == 0:
            return [], np.zeros(0, dtype=np.int64)
        no_tab = self.n_tabs == 0
        if np.any(no_tab):
            i = int(np.argmax(no_tab))
            raise _err(f"{self.where(i)}: not a record (expected 'unix_ms<TAB>TYPE_...<TAB>"
                       f"values', found no tab): {self.shown(i)}")
        a, b = self.field_bounds(np.arange(self.starts.size), 1)
        length = b - a
        names: List[str] = []
        type_index = np.empty(self.starts.size, dtype=np.int64)
        buf = self.bufx
        for n in np.unique(length):
            rows = np.flatnonzero(length == n)
            if n == 0:
                raise _err(f"{self.where(int(rows[0]))}: empty record type: "
                           f"{self.shown(int(rows[0]))}")
            tokens = buf[a[rows, None] + np.arange(n)].view(f"S{n}").ravel()
            uniq, inverse = np.unique(tokens, return_inverse=True)
            type_index[rows] = inverse.reshape(-1) + len(names)
            names += [t.decode("utf-8", errors="replace") for t in uniq]
        for k, name in enumerate(names):
            if not _TYPE_NAME.fullmatch(name):
                i = int(np.argmax(type_index == k))
                raise _err(f"{self.where(i)}: record type {name!r} is not a type name "
                           f"(expected e.g. TYPE_ACCELEROMETER): {self.shown(i)}")
        return names, type_index

    def check_field_count(self, sel: np.ndarray, type_name: str,
                          allowed: Sequence[Tuple[str, ...]],
                          drops: Optional["_Drops"] = None) -> np.ndarray:
        """The lines of ``sel`` with an allowed field count. A line with another count raises,
        or, when ``drops`` is given (a record type no method needs), is dropped and counted."""
        counts = self.n_tabs[sel] + 1
        ok = np.isin(counts, [len(f) for f in allowed])
        if np.all(ok):
            return sel
        i = int(sel[np.argmax(~ok)])
        expected = " or ".join(f"{len(f)} ({', '.join(f)})" for f in allowed)
        problem = (f"{type_name} has {int(self.n_tabs[i]) + 1} tab-separated fields, expected "
                   f"{expected}")
        if drops is None:
            raise _err(f"{self.where(i)}: {problem}: {self.shown(i)}")
        drops.add(f"{type_name} line", int(np.sum(~ok)), "with a wrong field count",
                  int(self.line_no[i]), f"{problem}: {self.shown(i)}", "the lines dropped")
        return sel[ok]

    def numbers(self, sel: np.ndarray, fields: Sequence[int], names: Sequence[str],
                type_name: str, integer: Sequence[bool],
                drops: Optional["_Drops"] = None) -> Tuple[np.ndarray, np.ndarray]:
        """Numeric fields of the lines ``sel``: ``(values, dropped)``, both (len(sel),
        len(fields)); ``values`` float64, ``dropped`` True where an optional field was damaged
        (NaN in ``values``; counted in ``drops``). Damage to a needed field raises, naming the
        first such line.

        Fast path: one ``np.loadtxt`` over the fields of all the lines (``Infinity`` and
        ``NaN`` parse there, and are then dropped or refused as non-finite). Only when it
        refuses the text: the lines holding a byte that cannot be part of a number, or an empty
        field, are parsed in Python one field at a time, the others by ``np.loadtxt`` again
        (split in halves until the lines it refuses are isolated, should it refuse more).
        """
        n, k = sel.size, len(fields)
        if n == 0:
            return np.zeros((0, k), dtype=np.float64), np.zeros((0, k), dtype=bool)
        text = self.fields_bytes(sel, fields)
        values = _loadtxt(text, n, k)
        slow = np.zeros(n, dtype=bool)
        if values is None:
            values = np.full((n, k), np.nan)
            buf = np.frombuffer(text, dtype=np.uint8)
            sep = (buf == _NL) | (buf == _TAB)
            empty_field = sep & np.concatenate([[True], sep[:-1]])
            odd = np.flatnonzero(~_NUMBER_BYTES[buf] | empty_field)
            slow[np.searchsorted(np.flatnonzero(buf == _NL), odd)] = True
            pending = [np.flatnonzero(~slow)] if not np.all(slow) else []
            while pending:
                rows = pending.pop()
                parsed = _loadtxt(self.fields_bytes(sel[rows], fields), rows.size, k)
                if parsed is not None:
                    values[rows] = parsed
                elif rows.size == 1:
                    slow[rows] = True  # e.g. "1e" or "1.2.3": number bytes, not a number
                else:
                    pending += [rows[: rows.size // 2], rows[rows.size // 2:]]
        for r in np.flatnonzero(slow):  # the slow path: only the lines that need it
            for c, j in enumerate(fields):
                values[r, c] = _number(self.field_str(int(sel[r]), j))
        bad = ~np.isfinite(values)
        ints = np.asarray(integer, dtype=bool)
        if np.any(ints):
            v = values[:, ints]
            bad[:, ints] |= np.isfinite(v) & (v != np.round(v))
        if not np.any(bad):
            return values, bad
        fallbacks = [_fallback(type_name, name) for name in names]
        needed = np.array([f is None for f in fallbacks])
        if np.any(bad[:, needed]):
            r = int(np.argmax(np.any(bad[:, needed], axis=1)))
            c = int(np.flatnonzero(bad[r] & needed)[0])
            raise _err(f"{self.where(int(sel[r]))}: "
                       + _field_problem(self.field_str(int(sel[r]), fields[c]),
                                        f"{type_name} field {fields[c] + 1} ({names[c]})",
                                        bool(ints[c])))
        values[bad] = np.nan
        if drops is not None:
            for c in np.flatnonzero(np.any(bad, axis=0)):
                r = int(np.argmax(bad[:, c]))
                first = _field_problem(self.field_str(int(sel[r]), fields[c]),
                                       f"field {fields[c] + 1}", bool(ints[c]))
                drops.add(f"{type_name} {names[c]}", int(np.sum(bad[:, c])),
                          "with a damaged value", int(self.line_no[sel[r]]), first,
                          f"replaced by {fallbacks[c]}")
        return values, bad


def _loadtxt(text: bytes, n: int, k: int) -> Optional[np.ndarray]:
    """(n, k) float64 of tab-separated rows of numbers, or None when np.loadtxt refuses them."""
    try:
        values = np.loadtxt(io.BytesIO(text), delimiter="\t", comments=None, dtype=np.float64,
                            ndmin=2, encoding="utf-8")
    except ValueError:
        return None
    return values if values.shape == (n, k) else None


def _shown(text: str, limit: int = 120) -> str:
    return repr(text if len(text) <= limit else text[:limit] + "...")


def _number(s: str) -> float:
    """float(s) when s is a number in the file's notation (``Infinity``, ``nan``, ``1_0`` are
    not), else NaN."""
    s = s.strip()
    return float(s) if _NUMBER.fullmatch(s) else float("nan")


def _field_problem(s: str, what: str, integer: bool) -> str:
    """``"<what> is not a number: '...'"`` (or "is not finite", "must be an integer")."""
    if not _NUMBER.fullmatch(s.strip()):
        return f"{what} is not a number: {s!r}"
    if not np.isfinite(float(s)):
        return f"{what} is not finite: {s!r}"
    if integer:
        return f"{what} must be an integer: {s!r}"
    return f"{what} is damaged: {s!r}"


def _truncation(line: str) -> Optional[str]:
    """Why the file's last line looks cut short by an interrupted recording, or None.

    Cut short: no tab (a time stamp alone), an empty record type or one that is the beginning
    of a known type's name, fewer fields than the type's shortest layout, or a last field that
    is not a complete number where a number belongs (``""``, ``"-"``, ``"1e"``).
    """
    parts = line.split("\t")
    if len(parts) < 2 or not parts[1]:
        return "no record type"
    type_name = parts[1]
    layouts = _LAYOUTS.get(type_name)
    if layouts is None:
        if any(t.startswith(type_name) for t in _LAYOUTS):
            return f"record type {type_name!r} cut short"
        return None  # another record type: skipped and counted like every unknown type
    shortest = min(len(f) for f in layouts)
    if len(parts) < shortest:
        return f"{len(parts)} fields, {type_name} has at least {shortest}"
    layout = next((f for f in layouts if len(f) == len(parts)), None)
    if (layout is not None and layout[-1] not in _TEXT_FIELDS
            and not _NUMBER.fullmatch(parts[-1].strip())):
        return f"its last field ({layout[-1]}) is not a complete number: {parts[-1]!r}"
    return None


class _Drops:
    """What the reader dropped from one walk: counts per field and one sentence each."""

    def __init__(self) -> None:
        self.counts: Dict[str, int] = {}
        self.notes: List[str] = []

    def __bool__(self) -> bool:
        return bool(self.counts)

    def add(self, key: str, count: int, what: str, line: int, first: str, action: str) -> None:
        """``count`` lines ``what`` (e.g. "with a damaged value"), the first at ``line``
        (``first``: what was wrong there); ``action``: what the reader did."""
        self.counts[key] = self.counts.get(key, 0) + count
        self.notes.append(f"{key}: {count} line(s) {what}, first at line {line} ({first}): "
                          f"{action}")

    def warning(self, path: Path) -> str:
        what = ", ".join(f"{k} x{v}" for k, v in self.counts.items())
        return (f"indoorloc: {path}: the walk is kept, damaged data that no method needs was "
                f"dropped: {what} (lines in walk.notes, counts in walk.dropped_fields)")


def _check_sorted(text: _WalkText, sel: np.ndarray, t_ms: np.ndarray, what: str,
                  allow_unsorted: bool, notes: List[str]) -> np.ndarray:
    """Order (indices into sel) that makes t_ms non-decreasing; raise if needed and not allowed."""
    back = np.diff(t_ms) < 0
    if not np.any(back):
        return np.arange(t_ms.size)
    k = int(np.argmax(back))
    n_back = int(back.sum())
    message = (f"{what} times decrease {n_back} time(s), first at line "
               f"{int(text.line_no[sel[k + 1]])} ({int(t_ms[k + 1])} ms after "
               f"{int(t_ms[k])} ms at line {int(text.line_no[sel[k]])})")
    if not allow_unsorted:
        raise _err(f"{text.path}: {message}; pass allow_unsorted=True to sort them")
    notes.append(f"{message}: sorted by time (stable)")
    return np.argsort(t_ms, kind="stable")


def _parse_header(lines: Sequence[str]) -> Dict[str, Any]:
    meta: Dict[str, Any] = {}
    sensors: List[Dict[str, Any]] = []
    for line in lines:
        parts = [p for p in line.lstrip("#").split("\t") if p.strip()]
        pairs = [(p.split(":", 1) + [""])[:2] for p in parts]
        pairs = [(k.strip(), v.strip()) for k, v in pairs]
        if pairs and pairs[0][0] == "type":
            sensors.append({k: _header_value(v) for k, v in pairs})
        else:
            for k, v in pairs:
                meta.setdefault(k, v)
    meta["sensors"] = sensors
    return meta


def _header_value(v: str) -> Any:
    for convert in (int, float):
        try:
            return convert(v)
        except ValueError:
            pass
    return v


def _empty_sensor(type_name: str) -> IlcSensor:
    _, unit, names = ILC_SENSOR_TYPES[type_name]
    z = np.zeros(0, dtype=np.float64)
    return IlcSensor(type_name=type_name, unit=unit, t_s=z, values=np.zeros((0, 3)),
                     accuracy=np.zeros(0, dtype=np.int64),
                     bias=np.zeros((0, 3)) if len(names) == 6 else None)


def _int_or(values: np.ndarray, missing: int = -1) -> np.ndarray:
    """int64 of whole-number floats, ``missing`` where NaN (a dropped field)."""
    return np.where(np.isnan(values), missing, values).astype(np.int64)


@reads_file("path")  # a damaged walk or floor folder is a FormatError, as for every reader
def read_ilc_walk(path: PathLike, *, allow_unsorted: bool = False) -> IlcWalk:
    """Read one walk file (``path_data_files/<walk id>.txt``) into numpy arrays.

    Parameters
    ----------
    path : str or pathlib.Path
        The walk file.
    allow_unsorted : bool, default False
        When a record type's times decrease somewhere, sort that stream by time (stable) and
        say so in :attr:`IlcWalk.notes` instead of raising.

    Returns
    -------
    IlcWalk
        Sensor streams, WiFi and iBeacon readings, waypoints and header metadata; every time in
        seconds since the walk's first record (``t0_unix_ms``). Damaged optional fields (see
        the module's "Errors: nothing is lost") are dropped for their line only, with ONE
        :class:`~indoorloc.io.errors.RecordingWarning` and the counts in
        :attr:`IlcWalk.dropped_fields`; a truncated last line is dropped the same way.

    Raises
    ------
    FormatError
        (a ValueError) ``indoorloc: argument 'path': <file>, line <n>: ...`` for damage to what
        the methods need: a line with no record type, a record type that is not a name, a
        field count that does not match the type (iBeacon lines are dropped instead), a time
        stamp, sensor x/y/z, WiFi RSSI or waypoint that is not a finite number, a time stamp
        that is not an integer, an empty BSSID; and for times that decrease within a record
        type (unless ``allow_unsorted``); ``... file not found`` when there is no file.
    """
    p = Path(path)
    if not p.is_file():
        raise _err(f"file not found: {p}")
    text = _WalkText(p)
    drops = _Drops()
    if text.truncated is not None:
        line, shown, reason = text.truncated
        drops.add("truncated last line", 1, "cut short (an interrupted recording)", line,
                  f"{reason}: {_shown(shown)}", "dropped")
    names, type_index = text.classify()
    by_type = {name: np.flatnonzero(type_index == k) for k, name in enumerate(names)}
    unknown = {name: int(sel.size) for name, sel in by_type.items() if name not in _LAYOUTS}
    empty = np.zeros(0, dtype=np.int64)
    notes: List[str] = []

    def numbers(sel: np.ndarray, layout: Tuple[str, ...], fields: Sequence[int],
                type_name: str) -> np.ndarray:
        field_names = [layout[j] for j in fields]
        integer = [name in ("unix_ms", "accuracy", "major", "minor", "last_seen_unix_ms")
                   for name in field_names]
        return text.numbers(sel, fields, field_names, type_name, integer, drops)[0]

    # Numeric parse of every known type, times still in unix ms.
    parsed: Dict[str, Tuple[np.ndarray, np.ndarray]] = {}  # type -> (line indices, values)
    for type_name, (_, _, value_names) in ILC_SENSOR_TYPES.items():
        sel = by_type.get(type_name, empty)
        layouts = _LAYOUTS[type_name]
        text.check_field_count(sel, type_name, layouts)
        if type_name == "TYPE_ROTATION_VECTOR":
            layout, with_w = layouts
            has_w = text.n_tabs[sel] + 1 == len(with_w)
            rows = np.full((sel.size, len(with_w) - 1), np.nan)
            for mask, lay in ((~has_w, layout), (has_w, with_w)):
                fields = [0] + list(range(2, len(lay)))
                cols = [0, 1, 2, 3, 5] if len(lay) == len(layout) else [0, 1, 2, 3, 4, 5]
                rows[np.ix_(mask, cols)] = numbers(sel[mask], lay, fields, type_name)
            if not np.any(has_w):
                rows = rows[:, [0, 1, 2, 3, 5]]
            parsed[type_name] = (sel, rows)
        else:
            layout = layouts[0]
            parsed[type_name] = (sel, numbers(sel, layout, [0] + list(range(2, len(layout))),
                                              type_name))

    wifi_layout = _LAYOUTS[_WIFI][0]
    wifi_sel = by_type.get(_WIFI, empty)
    text.check_field_count(wifi_sel, _WIFI, (wifi_layout,))
    wifi_num = numbers(wifi_sel, wifi_layout, [0, 4, 5, 6], _WIFI)
    # A damaged last-seen time: the scan time (flagged in a 5th column, kept through sorting).
    fallback = np.isnan(wifi_num[:, 3])
    wifi_num[fallback, 3] = wifi_num[fallback, 0]
    parsed[_WIFI] = (wifi_sel, np.column_stack([wifi_num, fallback]))

    wp_layout = _LAYOUTS[_WAYPOINT][0]
    wp_sel = by_type.get(_WAYPOINT, empty)
    text.check_field_count(wp_sel, _WAYPOINT, (wp_layout,))
    parsed[_WAYPOINT] = (wp_sel, numbers(wp_sel, wp_layout, [0, 2, 3], _WAYPOINT))

    beacon_layout = _LAYOUTS[_BEACON][0]
    beacon_sel = text.check_field_count(by_type.get(_BEACON, empty), _BEACON, _LAYOUTS[_BEACON],
                                        drops)
    parsed[_BEACON] = (beacon_sel, numbers(beacon_sel, beacon_layout, [0, 3, 4, 5, 6, 7],
                                           _BEACON))

    # The walk's clock: t = 0 at its first parsed record.
    firsts = [int(v[:, 0].min()) for _, v in parsed.values() if v.shape[0]]
    if not firsts:
        raise _err(f"{p}: no sensor, WiFi, iBeacon or waypoint record")
    t0 = min(firsts)

    def seconds(ms: np.ndarray) -> np.ndarray:
        return (ms - float(t0)) / 1000.0

    def ordered(type_name: str, what: str) -> Tuple[np.ndarray, np.ndarray]:
        sel, values = parsed[type_name]
        order = _check_sorted(text, sel, values[:, 0], what, allow_unsorted, notes)
        return sel[order], values[order]

    sensors: Dict[str, IlcSensor] = {}
    for type_name, (attr, unit, value_names) in ILC_SENSOR_TYPES.items():
        _, values = ordered(type_name, type_name)
        if values.shape[0] == 0:
            sensors[attr] = _empty_sensor(type_name)
            continue
        uncal = len(value_names) == 6
        n_xyz = values.shape[1] - 2 if not uncal else 3
        sensors[attr] = IlcSensor(
            type_name=type_name, unit=unit, t_s=seconds(values[:, 0]),
            values=np.ascontiguousarray(values[:, 1:1 + n_xyz]),
            accuracy=_int_or(values[:, -1]),
            bias=np.ascontiguousarray(values[:, 4:7]) if uncal else None)

    wifi_sel, wifi_num = ordered(_WIFI, _WIFI + " scan")
    wifi = _wifi_arrays(text, wifi_sel, wifi_num, seconds)

    beacon_sel, beacon_num = ordered(_BEACON, _BEACON)
    beacons = IlcBeacons(
        t_s=seconds(beacon_num[:, 0]),
        uuid=[text.field_str(int(i), 2) for i in beacon_sel],
        major=_int_or(beacon_num[:, 1]), minor=_int_or(beacon_num[:, 2]),
        tx_power_dbm=beacon_num[:, 3], rssi_dbm=beacon_num[:, 4], distance_m=beacon_num[:, 5],
        mac=[text.field_str(int(i), 8) for i in beacon_sel])

    _, wp = ordered(_WAYPOINT, _WAYPOINT)
    if drops:
        # One warning per walk; stacklevel 3: the caller of read_ilc_walk (through reads_file).
        warnings.warn(drops.warning(p), RecordingWarning, stacklevel=3)
    return IlcWalk(
        path=p, walk_id=p.stem if p.suffix == ".txt" else p.name, t0_unix_ms=t0,
        wifi=wifi, beacons=beacons, waypoint_t_s=seconds(wp[:, 0]),
        waypoint_xy_m=np.ascontiguousarray(wp[:, 1:3]),
        metadata=_parse_header(text.header_lines), unknown_type_counts=unknown,
        notes=drops.notes + notes, dropped_fields=dict(drops.counts), **sensors)


def _wifi_arrays(text: _WalkText, sel: np.ndarray, num: np.ndarray, seconds) -> IlcWifi:
    """WiFi readings of the lines ``sel`` (scan order) with their numbers (R, 5): time, rssi,
    frequency, last seen, last-seen fallback flag."""
    if sel.size == 0:
        z = np.zeros(0, dtype=np.float64)
        return IlcWifi(scan_time_s=z, bssid_index=np.zeros(0, dtype=np.int64), rssi_dbm=z,
                       frequency_mhz=z, last_seen_s=z, bssids=[], ssids=[],
                       scan_starts=np.zeros(0, dtype=np.int64),
                       last_seen_fallback=np.zeros(0, dtype=bool))
    a, b = text.field_bounds(sel, 3)
    length = b - a
    if np.any(length == 0):
        i = int(sel[np.argmax(length == 0)])
        raise _err(f"{text.where(i)}: TYPE_WIFI field 4 (bssid) is empty: {text.shown(i)}")
    width = int(length.max())
    idx = a[:, None] + np.arange(width)
    keep = idx < b[:, None]
    gathered = np.where(keep, text.bufx[np.minimum(idx, text.bufx.size - 1)], 0)
    keys = np.ascontiguousarray(gathered.astype(np.uint8)).view(f"S{width}").ravel()
    uniq, inverse = np.unique(keys, return_inverse=True)
    bssid_index = inverse.reshape(-1).astype(np.int64)
    bssids = [u.decode("utf-8", errors="replace") for u in uniq]

    # SSID per BSSID: the first reading with a non-empty SSID (Python per BSSID, not per line).
    sa, sb = text.field_bounds(sel, 2)
    ssids = [""] * len(bssids)
    named = np.flatnonzero(sb > sa)
    if named.size:
        first_bssid, first_pos = np.unique(bssid_index[named], return_index=True)
        for v, r in zip(first_bssid, named[first_pos]):
            ssids[int(v)] = text.line_text(int(sa[r]), int(sb[r]))

    scan_ms = num[:, 0]
    scan_starts = np.flatnonzero(np.concatenate([[True], scan_ms[1:] != scan_ms[:-1]]))
    return IlcWifi(scan_time_s=seconds(scan_ms), bssid_index=bssid_index, rssi_dbm=num[:, 1],
                   frequency_mhz=num[:, 2], last_seen_s=seconds(num[:, 3]), bssids=bssids,
                   ssids=ssids, scan_starts=scan_starts.astype(np.int64),
                   last_seen_fallback=num[:, 4] > 0)


# --------------------------------------------------------------------------------------------
# BSSID vocabulary of a floor


@dataclass
class BssidVocabulary:
    """BSSIDs heard over a set of walks (e.g. a floor, or the training walks of a fold).

    Attributes
    ----------
    bssids : list of str, length V
        Sorted BSSIDs.
    ssids : list of str, length V
        First non-empty SSID seen with each BSSID, else ``""``.
    n_readings : numpy.ndarray, shape (V,), int64
        Readings of each BSSID.
    n_scans : numpy.ndarray, shape (V,), int64
        Scans in which each BSSID appears (at least once).
    n_walks : numpy.ndarray, shape (V,), int64
        Walks in which each BSSID appears.
    total_scans : int
        Scans over all the walks.
    total_walks : int
        Number of walks.
    """

    bssids: List[str]
    ssids: List[str]
    n_readings: np.ndarray
    n_scans: np.ndarray
    n_walks: np.ndarray
    total_scans: int
    total_walks: int

    def __post_init__(self) -> None:
        self._index = {b: k for k, b in enumerate(self.bssids)}

    @classmethod
    def from_walks(cls, walks: Iterable[IlcWalk]) -> "BssidVocabulary":
        """The union of the walks' BSSIDs with reading, scan and walk counts."""
        per_walk = []
        ssid_of: Dict[str, str] = {}
        total_scans = 0
        for w in walks:
            wf = w.wifi
            readings = np.bincount(wf.bssid_index, minlength=len(wf.bssids))
            pairs = np.unique(wf.scan_index * max(1, len(wf.bssids)) + wf.bssid_index)
            scans = np.bincount(pairs % max(1, len(wf.bssids)), minlength=len(wf.bssids))
            per_walk.append((wf.bssids, readings, scans))
            for b, s in zip(wf.bssids, wf.ssids):
                if s and not ssid_of.get(b):
                    ssid_of[b] = s
                ssid_of.setdefault(b, "")
            total_scans += wf.n_scans
        bssids = sorted(ssid_of)
        index = {b: k for k, b in enumerate(bssids)}
        n = len(bssids)
        n_readings = np.zeros(n, dtype=np.int64)
        n_scans = np.zeros(n, dtype=np.int64)
        n_walks = np.zeros(n, dtype=np.int64)
        for names, readings, scans in per_walk:
            lut = np.array([index[b] for b in names], dtype=np.int64)
            np.add.at(n_readings, lut, readings)
            np.add.at(n_scans, lut, scans)
            np.add.at(n_walks, lut, 1)
        return cls(bssids=bssids, ssids=[ssid_of[b] for b in bssids], n_readings=n_readings,
                   n_scans=n_scans, n_walks=n_walks, total_scans=total_scans,
                   total_walks=len(per_walk))

    @property
    def size(self) -> int:
        """Number of BSSIDs V."""
        return len(self.bssids)

    @property
    def scan_fraction(self) -> np.ndarray:
        """(V,) fraction of all scans in which each BSSID appears."""
        return self.n_scans / max(1, self.total_scans)

    def indices(self, bssids: Sequence[str]) -> np.ndarray:
        """(len(bssids),) int64 index of each BSSID in this vocabulary, -1 when absent."""
        return np.array([self._index.get(b, -1) for b in bssids], dtype=np.int64)

    def map_walk(self, walk: IlcWalk) -> np.ndarray:
        """(R,) int64: the index of each of the walk's WiFi readings' BSSID in this vocabulary,
        -1 for a BSSID it does not hold (e.g. a test walk against a training vocabulary)."""
        lut = self.indices(walk.wifi.bssids)
        return lut[walk.wifi.bssid_index] if lut.size else np.zeros(0, dtype=np.int64)

    def frequent(self, min_scan_fraction: float) -> np.ndarray:
        """Indices of the BSSIDs heard in at least ``min_scan_fraction`` of the scans."""
        return np.flatnonzero(self.scan_fraction >= min_scan_fraction)


# --------------------------------------------------------------------------------------------
# Floors and sites


class UnknownWalkError(KeyError):
    """No walk with the id asked for on a floor (a KeyError whose message reads plainly)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class IlcFloor:
    """One floor folder: ``floor_info.json``, ``geojson_map.json`` and the walk files.

    The walks are ``path_data_files/*.txt`` (the competition's 2020 layout) or, when that folder
    is absent, ``*.txt`` in the floor folder itself (the Kaggle 2021 layout). They are read on
    demand (:meth:`walk`, :meth:`walks`) and kept when ``cache`` is True.

    :meth:`walk` raises for a walk that cannot be read; the readers that iterate over walks
    (:meth:`walks`, :meth:`bssid_vocabulary`, :func:`describe_ilc_floor`) skip it instead, with a
    :class:`~indoorloc.io.errors.RecordingWarning` naming the file and the reason, and list it in
    :attr:`skipped_walks`. :meth:`load_report` counts what was skipped or dropped.

    Attributes
    ----------
    name : str
        Floor folder name (e.g. ``"F3"``).
    floor_dir : pathlib.Path
        The floor folder.
    width_m, height_m : float or None
        ``map_info.width`` / ``map_info.height`` of ``floor_info.json`` [m] (the floor frame's
        extent); None when the file is absent.
    geojson_path : pathlib.Path or None
        ``geojson_map.json`` (read it with :mod:`indoorloc.io.floor_plan`); None when absent.
    image_path : pathlib.Path or None
        ``floor_image.png`` when present.
    walk_paths : list of pathlib.Path
        The walk files, sorted by name.
    """

    def __init__(self, floor_dir: PathLike, *, cache: bool = True,
                 allow_unsorted: bool = False) -> None:
        d = Path(floor_dir)
        walk_dir = d / "path_data_files"
        if not d.is_dir():
            raise ValueError(f"indoorloc: argument 'floor_dir': no folder {d}")
        if not walk_dir.is_dir():
            walk_dir = d
        self.name = d.name
        self.floor_dir = d
        self.walk_paths = sorted(p for p in walk_dir.glob("*.txt") if p.is_file())
        if not self.walk_paths:
            where = (f"{d} (and no folder {d / 'path_data_files'})" if walk_dir == d
                     else str(walk_dir))
            raise ValueError(f"indoorloc: argument 'floor_dir': no *.txt walk file in {where}")
        self.width_m: Optional[float] = None
        self.height_m: Optional[float] = None
        info = d / "floor_info.json"
        if info.is_file():
            self.width_m, self.height_m = _floor_info(info)
        geo = d / "geojson_map.json"
        self.geojson_path: Optional[Path] = geo if geo.is_file() else None
        image = d / "floor_image.png"
        self.image_path: Optional[Path] = image if image.is_file() else None
        self._cache = cache
        self._allow_unsorted = allow_unsorted
        self._walks: Dict[int, IlcWalk] = {}
        self._vocabulary: Optional[BssidVocabulary] = None
        self._skipped: Dict[int, str] = {}       # walk index -> why it could not be read
        self._dropped: Dict[int, Dict[str, int]] = {}  # walk index -> IlcWalk.dropped_fields
        self._read: Set[int] = set()             # walk indices read at least once

    def __repr__(self) -> str:
        return (f"IlcFloor({self.name!r}, {self.n_walks} walks, width_m={self.width_m}, "
                f"height_m={self.height_m})")

    @property
    def n_walks(self) -> int:
        """Number of walk files (readable or not)."""
        return len(self.walk_paths)

    @property
    def walk_ids(self) -> List[str]:
        """Walk ids (file names without ``.txt``), in :attr:`walk_paths` order."""
        return [p.stem for p in self.walk_paths]

    @property
    def skipped_walks(self) -> Dict[str, str]:
        """``{walk id: reason}`` of the walks the iterating readers skipped so far (in walk
        order): files that cannot be read (the reason is the FormatError's message)."""
        ids = self.walk_ids
        return {ids[k]: self._skipped[k] for k in sorted(self._skipped)}

    def _index(self, key: Union[int, str]) -> int:
        if isinstance(key, str):
            ids = self.walk_ids
            if key not in ids:
                raise UnknownWalkError(
                    f"indoorloc: argument 'key': no walk {key!r} on floor {self.name} (its "
                    f"{self.n_walks} walks are the *.txt files of {self.walk_paths[0].parent}; "
                    f"IlcFloor.walk_ids lists them)")
            return ids.index(key)
        if isinstance(key, bool) or not isinstance(key, (int, np.integer)):
            raise TypeError(f"indoorloc: argument 'key': a walk index (int) or walk id (str), "
                            f"got {key!r} ({type(key).__name__})")
        k = int(key)
        if not 0 <= k < self.n_walks:
            raise IndexError(f"indoorloc: argument 'key': walk {k} outside "
                             f"0..{self.n_walks - 1} (floor {self.name} has {self.n_walks} walks)")
        return k

    def _load(self, k: int) -> IlcWalk:
        if k in self._walks:
            return self._walks[k]
        w = read_ilc_walk(self.walk_paths[k], allow_unsorted=self._allow_unsorted)
        self._read.add(k)
        self._skipped.pop(k, None)
        if w.dropped_fields:
            self._dropped[k] = dict(w.dropped_fields)
        if self._cache:
            self._walks[k] = w
        return w

    def walk(self, key: Union[int, str]) -> IlcWalk:
        """Walk number ``key`` (in :attr:`walk_paths` order) or the walk with id ``key``.

        Raises
        ------
        TypeError
            ``key`` is neither an int nor a str (``1.5``, ``True``).
        IndexError
            An index outside ``0 .. n_walks - 1``.
        KeyError
            (:class:`UnknownWalkError`) no walk has the id ``key``; the message names it and
            says how many walks the floor has.
        FormatError
            The walk file cannot be read (damage to what the methods need): the file and line.
        """
        return self._load(self._index(key))

    def walks(self, keys: Optional[Iterable[Union[int, str]]] = None) -> Iterator[IlcWalk]:
        """Iterate over the walks (all, or those of ``keys``), reading each on demand.

        A walk that cannot be read (a FormatError) is skipped with a RecordingWarning naming the
        file and the reason (once per walk) and listed in :attr:`skipped_walks`; a wrong key
        raises as in :meth:`walk`.
        """
        indices = range(self.n_walks) if keys is None else [self._index(k) for k in keys]
        for k in indices:
            if k in self._skipped:
                continue
            try:
                w = self._load(k)
            except ValueError as exc:  # FormatError: the file's fault, not the caller's
                self._skipped[k] = str(exc)
                self._read.add(k)
                warnings.warn(f"indoorloc: floor {self.name}: walk {self.walk_paths[k]} skipped: "
                              f"{exc}", RecordingWarning, stacklevel=2)
                continue
            yield w

    def load_report(self) -> Dict[str, Any]:
        """What reading the walks so far skipped or dropped (all of them after :meth:`walks`).

        Returns ``{"floor", "n_walks" (files), "n_read", "n_loaded", "n_skipped",
        "skipped_walks": {walk id: reason}, "n_walks_with_dropped_fields",
        "dropped_fields": {"<TYPE> <field>": lines, summed over the walks},
        "walks_with_dropped_fields": {walk id: {field: lines}}, "n_warnings"}``:
        ``n_warnings`` is the number of RecordingWarnings those reads gave (one per walk with
        dropped fields, one per skipped walk).
        """
        ids = self.walk_ids
        total: Dict[str, int] = {}
        for counts in self._dropped.values():
            for key, n in counts.items():
                total[key] = total.get(key, 0) + n
        return {
            "floor": self.name,
            "n_walks": self.n_walks,
            "n_read": len(self._read),
            "n_loaded": len(self._read) - len(self._skipped),
            "n_skipped": len(self._skipped),
            "skipped_walks": self.skipped_walks,
            "n_walks_with_dropped_fields": len(self._dropped),
            "dropped_fields": total,
            "walks_with_dropped_fields": {ids[k]: dict(self._dropped[k])
                                          for k in sorted(self._dropped)},
            "n_warnings": len(self._dropped) + len(self._skipped),
        }

    def bssid_vocabulary(self, keys: Optional[Iterable[Union[int, str]]] = None
                         ) -> BssidVocabulary:
        """The BSSID vocabulary of all the floor's walks (cached) or of the walks ``keys``;
        walks that cannot be read are skipped as in :meth:`walks`."""
        if keys is not None:
            return BssidVocabulary.from_walks(self.walks(keys))
        if self._vocabulary is None:
            self._vocabulary = BssidVocabulary.from_walks(self.walks())
        return self._vocabulary

    def map_wifi(self, walk: IlcWalk) -> np.ndarray:
        """(R,) int64: the walk's readings' BSSIDs as indices into the floor vocabulary (-1 if
        the floor's walks never heard it)."""
        return self.bssid_vocabulary().map_walk(walk)

    def origin_lonlat(self) -> Tuple[float, float]:
        """(lon, lat) [deg] of the floor frame's origin: see :func:`ilc_floor_origin_lonlat`."""
        if self.geojson_path is None:
            raise ValueError(f"indoorloc: argument 'floor_dir': no geojson_map.json in "
                             f"{self.floor_dir}")
        return ilc_floor_origin_lonlat(self.geojson_path)


def _floor_info(path: Path) -> Tuple[float, float]:
    try:
        info = json.loads(path.read_text(encoding="utf-8"))
        width, height = float(info["map_info"]["width"]), float(info["map_info"]["height"])
    except (ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"indoorloc: argument 'floor_dir': {path}: expected "
                         f"{{'map_info': {{'width': ..., 'height': ...}}}} ({exc})") from None
    if not (np.isfinite(width) and np.isfinite(height) and width > 0 and height > 0):
        raise ValueError(f"indoorloc: argument 'floor_dir': {path}: width and height must be "
                         f"positive, got {width}, {height}")
    return width, height


@reads_file("floor_dir")  # a damaged walk or floor folder is a FormatError, as for every reader
def read_ilc_floor(floor_dir: PathLike, *, cache: bool = True,
                   allow_unsorted: bool = False) -> IlcFloor:
    """Open one floor folder (``<floor>/path_data_files/*.txt`` or ``<floor>/*.txt``,
    ``floor_info.json``, ``geojson_map.json``); walks are read on demand. See :class:`IlcFloor`.

    Raises
    ------
    ValueError
        ``indoorloc: argument 'floor_dir': ...`` when the folder does not exist or holds no
        walk file, or ``floor_info.json`` is malformed.
    """
    return IlcFloor(floor_dir, cache=cache, allow_unsorted=allow_unsorted)


_FLOOR_LEVEL = (  # (pattern of a floor name, sign of its level)
    (re.compile(r"B(\d+)|(\d+)B", re.IGNORECASE), -1),
    (re.compile(r"[FL](\d+)|(\d+)F", re.IGNORECASE), 1),
)


def ilc_floor_level(name: str) -> Optional[int]:
    """Building level of a floor folder name: ``B2`` / ``2B`` -> -2, ``G`` / ``GF`` -> 0,
    ``F3`` / ``3F`` / ``L3`` -> 3; None for another name."""
    if name.upper() in ("G", "GF"):
        return 0
    for pattern, sign in _FLOOR_LEVEL:
        m = pattern.fullmatch(name)
        if m:
            return sign * int(m.group(1) or m.group(2))
    return None


def _is_floor_dir(d: Path, with_plan: bool) -> bool:
    if not d.is_dir() or (with_plan and not (d / "geojson_map.json").is_file()):
        return False
    if (d / "path_data_files").is_dir():
        return True
    return any(p.is_file() for p in d.glob("*.txt"))


def ilc_floor_names(site_dir: PathLike, *, with_plan: bool = False,
                    argument: str = "site_dir") -> List[str]:
    """The floor folders of a site folder, in building order (B2, B1, G, F1, F2, ...; names
    that are not levels (:func:`ilc_floor_level`) last, by name).

    A floor folder is a sub-folder holding ``path_data_files/`` or ``*.txt`` walk files, and,
    with ``with_plan=True`` (what a tracker needs), ``geojson_map.json``. ``argument`` is the
    name the error messages give the folder (a caller's own parameter, e.g. ``data_root``).

    Raises
    ------
    ValueError
        ``indoorloc: argument '<argument>': ...`` when the folder does not exist or holds no
        floor folder.
    """
    d = Path(site_dir)
    if not d.is_dir():
        raise ValueError(f"indoorloc: argument '{argument}': folder not found: {d}")
    names = [f.name for f in d.iterdir() if _is_floor_dir(f, with_plan)]
    if not names:
        need = " and geojson_map.json" if with_plan else ""
        raise ValueError(f"indoorloc: argument '{argument}': no floor folder with "
                         f"path_data_files/ or *.txt walk files{need} in {d}")

    def order(name: str) -> Tuple[int, int, str]:
        level = ilc_floor_level(name)
        return (0, level, name) if level is not None else (1, 0, name)

    return sorted(names, key=order)


@reads_file("site_dir")  # a damaged walk or floor folder is a FormatError, as for every reader
def read_ilc_site(site_dir: PathLike, *, cache: bool = True,
                  allow_unsorted: bool = False) -> Dict[str, IlcFloor]:
    """Open every floor of a site folder: ``{floor folder name: IlcFloor}`` in building order
    (:func:`ilc_floor_names`: B2, B1, F1, F2, ...).

    A floor is any sub-folder holding ``path_data_files/`` or ``*.txt`` walk files.

    Raises
    ------
    ValueError
        ``indoorloc: argument 'site_dir': ...`` when the folder does not exist or has no floor.
    """
    d = Path(site_dir)
    return {name: IlcFloor(d / name, cache=cache, allow_unsorted=allow_unsorted)
            for name in ilc_floor_names(d)}


def _lonlat_points(coords: Any) -> Iterator[Tuple[float, float]]:
    if (isinstance(coords, (list, tuple)) and len(coords) >= 2
            and all(isinstance(c, (int, float)) for c in coords[:2])):
        yield float(coords[0]), float(coords[1])
        return
    if isinstance(coords, (list, tuple)):
        for c in coords:
            yield from _lonlat_points(c)


@reads_file("geojson_path")  # a damaged geojson_map.json is a FormatError, as for every reader
def ilc_floor_origin_lonlat(geojson_path: PathLike) -> Tuple[float, float]:
    """(min lon, min lat) [deg] of the first feature's bounding box in ``geojson_map.json``.

    The competition's floor frame is metres east and north of this south-west corner of the
    floor outline's bounding box (the first feature).

    Raises
    ------
    ValueError
        ``indoorloc: argument 'geojson_path': ...`` when the file is missing, not JSON, or its
        first feature has no coordinates or a coordinate that is not a finite number (NaN,
        Infinity: JSON readers accept them).
    """
    p = Path(geojson_path)
    if not p.is_file():
        raise ValueError(f"indoorloc: argument 'geojson_path': file not found: {p}")
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
        coords = doc["features"][0]["geometry"]["coordinates"]
    except (ValueError, KeyError, IndexError, TypeError) as exc:
        raise ValueError(f"indoorloc: argument 'geojson_path': {p}: expected a FeatureCollection "
                         f"whose first feature has geometry coordinates ({exc!r})") from None
    points = list(_lonlat_points(coords))
    if not points:
        raise ValueError(f"indoorloc: argument 'geojson_path': {p}: the first feature has no "
                         f"coordinates")
    bad = [pt for pt in points if not (np.isfinite(pt[0]) and np.isfinite(pt[1]))]
    if bad:
        raise ValueError(f"indoorloc: argument 'geojson_path': {p}: the first feature has "
                         f"{len(bad)} coordinate(s) that are not finite numbers, first "
                         f"{list(bad[0])} (the origin would be NaN)")
    lon = min(pt[0] for pt in points)
    lat = min(pt[1] for pt in points)
    return lon, lat


# --------------------------------------------------------------------------------------------
# Data facts


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
