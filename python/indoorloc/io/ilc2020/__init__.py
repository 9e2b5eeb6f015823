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
  :class:`BssidVocabulary`); ``plan_dir=`` when the plan files are elsewhere (Kaggle 2021);
- :func:`read_ilc_site`: a site folder -> ``{floor name: IlcFloor}`` in building order
  (:func:`ilc_floor_names`: B2, B1, F1, F2, ...);
- :func:`ilc_floor_names`: the floor folders of a site in the ILC 2020 layout in building
  order (a survey folder of either competition layout, with each floor's walk and plan
  folders: :func:`indoorloc.io.survey_layout.survey_floors`, what ``indoorloc site build`` and
  ``indoorloc fusion evaluate`` read);
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

# The package keeps every name of the former module indoorloc/io/ilc2020.py importable from here.
from indoorloc.io.ilc2020.walk_types import (  # noqa: F401
    ILC_SENSOR_TYPES,
    IlcBeacons,
    IlcSensor,
    IlcWalk,
    IlcWifi,
    PathLike,
    _BEACON,
    _CR,
    _LAYOUTS,
    _NL,
    _NUMBER,
    _NUMBER_BYTES,
    _OPTIONAL,
    _TAB,
    _TEXT_FIELDS,
    _TYPE_NAME,
    _WAYPOINT,
    _WIFI,
    _fallback,
)
from indoorloc.io.ilc2020.walk_reader import (  # noqa: F401
    _Drops,
    _WalkText,
    _check_sorted,
    _empty_sensor,
    _err,
    _field_problem,
    _gather_ranges,
    _header_value,
    _int_or,
    _loadtxt,
    _number,
    _parse_header,
    _shown,
    _truncation,
    _wifi_arrays,
    read_ilc_walk,
)
from indoorloc.io.ilc2020.vocabulary import (  # noqa: F401
    BssidVocabulary,
)
from indoorloc.io.ilc2020.floor import (  # noqa: F401
    IlcFloor,
    UnknownWalkError,
    _FLOOR_LEVEL,
    _floor_info,
    _is_floor_dir,
    _lonlat_points,
    ilc_floor_level,
    ilc_floor_names,
    ilc_floor_origin_lonlat,
    read_ilc_floor,
    read_ilc_site,
)
from indoorloc.io.ilc2020.report import (  # noqa: F401
    _spread,
    describe_ilc_floor,
)

__all__ = [
    "BssidVocabulary",
    "ILC_SENSOR_TYPES",
    "IlcBeacons",
    "IlcFloor",
    "IlcSensor",
    "IlcWalk",
    "IlcWifi",
    "UnknownWalkError",
    "describe_ilc_floor",
    "ilc_floor_level",
    "ilc_floor_names",
    "ilc_floor_origin_lonlat",
    "read_ilc_floor",
    "read_ilc_site",
    "read_ilc_walk",
]
