"""The records of one Indoor Location Competition 2.0 walk: sensor streams (IlcSensor), WiFi
readings (IlcWifi), iBeacon readings (IlcBeacons) and the walk (IlcWalk), with the record types
and their fields.

Part of :mod:`indoorloc.io.ilc2020` (the format is described there)."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np

from indoorloc.io.errors import RecordingWarning


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
        return quaternion_from_rotation_vector(self.rotation_vector.values)


# --------------------------------------------------------------------------------------------
# Parsing


def quaternion_from_rotation_vector(values: np.ndarray) -> np.ndarray:
    """(N, 4) unit quaternions (x, y, z, w) from Android rotation-vector values (N, 3 or 4): w
    taken from the values where stored and not NaN, otherwise completed as
    ``sqrt(max(0, 1 - x^2 - y^2 - z^2))`` (Android's ``SensorManager.getQuaternionFromVector``),
    then every row normalised (:meth:`IlcWalk.rotation_quaternion_xyzw`, the live tracker)."""
    v = np.asarray(values, dtype=np.float64)
    q = np.empty((v.shape[0], 4), dtype=np.float64)
    q[:, :3] = v[:, :3]
    w = np.sqrt(np.maximum(0.0, 1.0 - np.sum(v[:, :3] ** 2, axis=1)))
    if v.shape[1] == 4:
        w = np.where(np.isnan(v[:, 3]), w, v[:, 3])
    q[:, 3] = w
    norm = np.linalg.norm(q, axis=1, keepdims=True)
    return q / np.where(norm > 0, norm, 1.0)
