"""Road-network files for ``indoorloc.mapmatch``: GeoJSON and CSV segment lists (json, csv, numpy).

Like all of :mod:`indoorloc.io`, this module imports nothing from indoorloc but the compiled
``indoorloc._core`` (``load_road_network`` builds ``indoorloc._core.mapmatch.RoadNetwork``, the
class :mod:`indoorloc.mapmatch` re-exports); the facade imports it, never the other way.

A road network is a list of M straight segments, each ``[x_A, y_A, x_B, y_B]`` in metres, with an
integer id per segment (paper 000, §II.B: "a set of linear segments identified by their identity
index, the coordinates of their ends and their direction"). This module only reads and writes
those arrays; connectivity, splitting at junctions and nearest-segment queries are the business
of :class:`indoorloc.mapmatch.RoadNetwork`, which :func:`load_road_network` builds from a file.

Coordinates are **planar, in metres**, in the site's own frame (x east / y north or any
right-handed frame). No geographic projection is done: a GeoJSON file written by GIS software in
WGS 84 longitude/latitude (the RFC 7946 default) must be projected to a local metric frame
before it is read here. A ``"crs"`` member (GeoJSON 2008) is ignored; it is neither checked nor
converted. A third coordinate of a position (altitude) is ignored.

GeoJSON format (:func:`read_geojson_segments`, :func:`write_geojson_segments`)
---------------------------------------------------------------------------
A ``FeatureCollection`` whose features have ``LineString`` or ``MultiLineString`` geometry.
Every consecutive vertex pair of a line string becomes one segment (a polyline with n vertices
gives n - 1 *pieces*; the parts of a MultiLineString are taken in order and their pieces counted
together). Segment ids:

- a feature's id is its integer property ``"id"`` (``properties.id``), or else its integer
  top-level ``"id"`` member (RFC 7946 §3.2);
- features with neither get sequential ids ``max_id + 1, max_id + 2, ...`` in file order, where
  ``max_id`` is the largest id given in the file (0 when none is given);
- a feature with a single piece gives its segment the feature id; a feature with k > 1 pieces
  gives piece j (j = 1..k, in vertex order) the id ``100 * id + j``. At most 99 pieces per
  feature are accepted, so that the piece number never carries into the feature id.

The final segment ids must be unique. :func:`write_geojson_segments` writes one two-vertex
LineString feature per segment with ``properties.id``, so reading its output returns the same
arrays exactly (floats are written with Python's shortest round-trip representation).

CSV format (:func:`read_csv_segments`)
-------------------------------------
::

    # warehouse aisles, metres
    id,x_a,y_a,x_b,y_b,name
    1,0,0,10,0,dock
    2,10,0,20,0,

One header row naming at least the columns ``id, x_a, y_a, x_b, y_b`` (any order, case and
surrounding blanks ignored; further columns are allowed and ignored), then one segment per row.
Lines whose first non-blank character is ``#`` and blank lines are skipped (before and after the
header); ``#`` elsewhere is not a comment. Ids are integers, coordinates decimal numbers [m].

Errors
------
Every reader raises ``ValueError("indoorloc: argument 'path': <file>: ...")`` naming the file
(and the feature or line) for a missing or unreadable file, invalid JSON, a geometry that is not
a (Multi)LineString, a line string with fewer than 2 vertices, a non-finite (NaN, inf) or
non-numeric coordinate, a zero-length segment, a non-integer id and duplicate ids.

Examples
--------
>>> from indoorloc.io import load_road_network, warehouse_segments, write_geojson_segments
>>> segments_m, ids = warehouse_segments()
>>> segments_m.shape, int(ids.min()), int(ids.max())
((26, 4), 1, 26)
>>> write_geojson_segments("/tmp/warehouse.geojson", segments_m, ids)  # doctest: +SKIP
>>> net = load_road_network("/tmp/warehouse.geojson")  # doctest: +SKIP
"""

from __future__ import annotations

import csv
import io
import json
import math
import numbers
import os
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from indoorloc.io.errors import FormatError, reads_file
from indoorloc.validate import real_array
PathLike = Union[str, os.PathLike]

#: Name of the packaged warehouse network in ``indoorloc.data`` (see docs/mapmatch_warehouse.md).
WAREHOUSE_RESOURCE = "warehouse.geojson"

#: Columns a road-network CSV file must have (header names, case-insensitive).
CSV_COLUMNS = ("id", "x_a", "y_a", "x_b", "y_b")

# Piece j of a feature with id i and k > 1 pieces gets id PIECE_ID_FACTOR * i + j, j = 1..k.
_PIECE_ID_FACTOR = 100
_MAX_PIECES = _PIECE_ID_FACTOR - 1

_INT32_MIN, _INT32_MAX = -(2**31), 2**31 - 1


_INT64_MAX = 2**63 - 1


def _error(arg: str, msg: str) -> ValueError:
    return ValueError(f"indoorloc: argument '{arg}': {msg}")


def _path_error(label: str, msg: str) -> ValueError:
    return FormatError(f"indoorloc: argument 'path': {label}: {msg}", path=label)


def _read_text(path: PathLike) -> Tuple[str, str]:
    """Text of ``path`` (UTF-8, BOM tolerated) and the label used in error messages."""
    if not isinstance(path, (str, os.PathLike)):
        raise _error("path", f"expected a str or os.PathLike, got {type(path).__name__}")
    p = Path(path)
    label = str(p)
    if not p.exists():
        raise _path_error(label, "file not found")
    if not p.is_file():
        raise _path_error(label, "not a regular file")
    try:
        return p.read_text(encoding="utf-8-sig"), label
    except (OSError, UnicodeDecodeError) as exc:
        raise _path_error(label, f"cannot read file ({exc})") from None


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _check_unique_ids(ids: np.ndarray, label: str, arg: str = "path") -> None:
    values, counts = np.unique(ids, return_counts=True)
    dup = values[counts > 1]
    if dup.size:
        shown = ", ".join(str(int(v)) for v in dup[:10])
        more = f" (and {dup.size - 10} more)" if dup.size > 10 else ""
        prefix = f"{label}: " if label else ""
        raise _error(arg, f"{prefix}duplicate segment id(s) {shown}{more}")


def _check_segment(seg: Sequence[float], where: str, label: str) -> None:
    if seg[0] == seg[2] and seg[1] == seg[3]:
        raise _path_error(label, f"{where}: zero-length segment at ({seg[0]!r}, {seg[1]!r})")


def _finish(rows: List[List[float]], ids: List[int], label: str) -> Tuple[np.ndarray, np.ndarray]:
    if not rows:
        raise _path_error(label, "no segments in file")
    segments_m = np.asarray(rows, dtype=np.float64).reshape(-1, 4)
    ids_arr = np.asarray(ids, dtype=np.int64)
    _check_unique_ids(ids_arr, label)
    return segments_m, ids_arr


# ---------------------------------------------------------------------------------------------
# GeoJSON


def _parse_position(pos: Any, where: str, label: str) -> Tuple[float, float]:
    if not isinstance(pos, (list, tuple)) or len(pos) < 2:
        raise _path_error(label, f"{where}: a position must be an array [x, y] (got {pos!r})")
    x, y = pos[0], pos[1]
    if not (_is_number(x) and _is_number(y)):
        raise _path_error(label, f"{where}: coordinates must be numbers (got {pos!r})")
    if not (math.isfinite(x) and math.isfinite(y)):
        raise _path_error(label, f"{where}: coordinate is NaN or infinite ({pos!r})")
    return float(x), float(y)


def _line_pieces(coords: Any, where: str, label: str) -> List[List[float]]:
    if not isinstance(coords, list):
        raise _path_error(label, f"{where}: 'coordinates' must be an array of positions")
    if len(coords) < 2:
        raise _path_error(label, f"{where}: a LineString needs at least 2 vertices "
                                 f"(got {len(coords)})")
    pts = [_parse_position(p, f"{where}, vertex {v}", label) for v, p in enumerate(coords)]
    pieces = []
    for j in range(len(pts) - 1):
        seg = [pts[j][0], pts[j][1], pts[j + 1][0], pts[j + 1][1]]
        _check_segment(seg, f"{where}, vertices {j}-{j + 1}", label)
        pieces.append(seg)
    return pieces


def _feature_pieces(feature: Any, where: str, label: str) -> List[List[float]]:
    if not isinstance(feature, dict) or feature.get("type") != "Feature":
        raise _path_error(label, f"{where}: not a GeoJSON Feature object")
    geom = feature.get("geometry")
    if not isinstance(geom, dict):
        raise _path_error(label, f"{where}: geometry is missing or null; expected a LineString "
                                 "or MultiLineString")
    gtype = geom.get("type")
    coords = geom.get("coordinates")
    if gtype == "LineString":
        return _line_pieces(coords, where, label)
    if gtype == "MultiLineString":
        if not isinstance(coords, list) or not coords:
            raise _path_error(label, f"{where}: a MultiLineString needs at least one line string")
        pieces = []
        for part, line in enumerate(coords):
            pieces.extend(_line_pieces(line, f"{where}, part {part}", label))
        return pieces
    raise _path_error(label, f"{where}: geometry type {gtype!r} is not a LineString or "
                             "MultiLineString")


def _feature_id(feature: Dict[str, Any], where: str, label: str) -> Optional[int]:
    props = feature.get("properties")
    if props is not None and not isinstance(props, dict):
        raise _path_error(label, f"{where}: 'properties' must be an object or null")
    if props and "id" in props:
        value = props["id"]
        source = "property 'id'"
    elif "id" in feature:
        value = feature["id"]
        source = "member 'id'"
    else:
        return None
    if value is None:
        return None
    if not _is_int(value):
        raise _path_error(label, f"{where}: {source} must be an integer (got {value!r})")
    if not -_INT64_MAX - 1 <= int(value) <= _INT64_MAX:
        raise _path_error(label, f"{where}: {source} {int(value)} does not fit in int64")
    return int(value)


def _parse_geojson(text: str, label: str) -> Tuple[np.ndarray, np.ndarray]:
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise _path_error(label, f"invalid JSON ({exc})") from None
    if not isinstance(doc, dict) or doc.get("type") != "FeatureCollection":
        raise _path_error(label, "expected a GeoJSON FeatureCollection")
    features = doc.get("features")
    if not isinstance(features, list):
        raise _path_error(label, "FeatureCollection has no 'features' array")

    parsed = []
    for f, feature in enumerate(features):
        where = f"feature {f}"
        pieces = _feature_pieces(feature, where, label)
        if len(pieces) > _MAX_PIECES:
            raise _path_error(label, f"{where}: {len(pieces)} pieces; at most {_MAX_PIECES} "
                                     "vertex pairs per feature are supported")
        parsed.append((_feature_id(feature, where, label), pieces))

    given = [fid for fid, _ in parsed if fid is not None]
    next_id = max(max(given), 0) + 1 if given else 1
    rows: List[List[float]] = []
    ids: List[int] = []
    for fid, pieces in parsed:
        if fid is None:
            fid, next_id = next_id, next_id + 1
        if len(pieces) == 1:
            ids.append(fid)
        else:
            ids.extend(_PIECE_ID_FACTOR * fid + j for j in range(1, len(pieces) + 1))
        rows.extend(pieces)
    return _finish(rows, ids, label)


@reads_file("path")
def read_geojson_segments(path: PathLike) -> Tuple[np.ndarray, np.ndarray]:
    """Read the segments of a GeoJSON FeatureCollection of (Multi)LineString features.

    Each consecutive vertex pair of a line string is one segment; ids follow the feature's
    ``properties.id`` (see the module docstring for pieces of polylines and missing ids).
    Coordinates are taken as planar metres: no geographic projection is done.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.geojson`` / ``.json`` file (UTF-8).

    Returns
    -------
    segments_m : numpy.ndarray, shape (M, 4), float64
        ``x_A, y_A, x_B, y_B`` [m] of each segment, in file order (feature, then vertex order).
    ids : numpy.ndarray, shape (M,), int64
        Unique segment ids.

    Raises
    ------
    ValueError
        ``indoorloc: argument 'path': ...`` for a missing file, invalid JSON, a geometry that is
        not a (Multi)LineString, fewer than 2 vertices, a NaN/inf or non-numeric coordinate, a
        zero-length segment, a non-integer id or duplicate ids.
    """
    text, label = _read_text(path)
    return _parse_geojson(text, label)


def _as_segments(segments_m: Any, ids: Any) -> Tuple[np.ndarray, np.ndarray]:
    seg = real_array(segments_m, "segments_m")  # strings, complex, NaN, inf: refused by name
    if seg.ndim != 2 or seg.shape[1] != 4 or seg.shape[0] == 0:
        raise _error("segments_m", f"expected shape (M, 4) with M >= 1, got {seg.shape}")
    bad = np.flatnonzero(~np.isfinite(seg).all(axis=1))
    if bad.size:
        raise _error("segments_m", f"row {int(bad[0])} has a NaN or infinite coordinate")
    if ids is None:
        ids_arr = np.arange(1, seg.shape[0] + 1, dtype=np.int64)
    else:
        try:
            raw = np.asarray(ids)
        except ValueError as exc:  # ragged nested lists
            raise _error("ids", f"cannot be converted to an array ({exc})") from None
        if raw.shape != (seg.shape[0],):
            raise _error("ids", f"expected shape ({seg.shape[0]},), got {raw.shape}")
        if raw.size and not np.issubdtype(raw.dtype, np.integer):
            raise _error("ids", f"expected integers, got dtype {raw.dtype}")
        # uint64 ids above 2**63 - 1 would wrap to negative int64 (2**64 - 1 became -1).
        if raw.size and raw.dtype.kind == "u" and int(raw.max()) > _INT64_MAX:
            k = int(np.argmax(raw > _INT64_MAX))
            raise _error("ids", f"entry {k} = {int(raw[k])} does not fit in int64 "
                                f"(the readers' id type)")
        ids_arr = raw.astype(np.int64)
        _check_unique_ids(ids_arr, "", arg="ids")
    return seg, ids_arr


def write_geojson_segments(path: PathLike, segments_m: Any, ids: Any = None) -> None:
    """Write segments as a GeoJSON FeatureCollection, one LineString feature per segment.

    Each feature has two vertices, ``[[x_A, y_A], [x_B, y_B]]``, and ``properties.id``; one
    feature per line. :func:`read_geojson_segments` returns the same arrays exactly.

    Parameters
    ----------
    path : str or os.PathLike
        Output file (overwritten); its folder must exist.
    segments_m : array_like, shape (M, 4)
        ``x_A, y_A, x_B, y_B`` [m], finite.
    ids : array_like of int, shape (M,), optional
        Unique segment ids; default ``1..M``.

    Raises
    ------
    ValueError
        For a wrong shape, a non-finite coordinate, non-integer or duplicate ids
        (``argument 'segments_m'`` / ``'ids'``), or a path that cannot be written
        (``argument 'path'``).
    """
    seg, ids_arr = _as_segments(segments_m, ids)
    # What the readers refuse is refused here too, so that every file written reads back.
    zero = np.flatnonzero((seg[:, 0] == seg[:, 2]) & (seg[:, 1] == seg[:, 3]))
    if zero.size:
        raise _error("segments_m", f"row {int(zero[0])} is a zero-length segment")
    if not isinstance(path, (str, os.PathLike)):
        raise _error("path", f"expected a str or os.PathLike, got {type(path).__name__}")
    lines = []
    for row, sid in zip(seg.tolist(), ids_arr.tolist()):
        feature = {
            "type": "Feature",
            "properties": {"id": int(sid)},
            "geometry": {"type": "LineString",
                         "coordinates": [[row[0], row[1]], [row[2], row[3]]]},
        }
        lines.append(json.dumps(feature, allow_nan=False))
    text = ('{"type": "FeatureCollection", "features": [\n' + ",\n".join(lines) + "\n]}\n")
    try:
        Path(path).write_text(text, encoding="utf-8")
    except OSError as exc:
        raise _path_error(str(path), f"cannot write file ({exc})") from None


# ---------------------------------------------------------------------------------------------
# CSV


def _parse_csv(text: str, label: str) -> Tuple[np.ndarray, np.ndarray]:
    # Keep physical line numbers for messages: filter comment/blank lines, remember their number.
    kept = [(n, line) for n, line in enumerate(text.splitlines(), start=1)
            if line.strip() and not line.lstrip().startswith("#")]
    if not kept:
        raise _path_error(label, "empty CSV file (no header row)")
    reader = csv.reader(io.StringIO("\n".join(line for _, line in kept)))
    rows_raw = list(reader)
    header = [h.strip().lower() for h in rows_raw[0]]
    missing = [c for c in CSV_COLUMNS if c not in header]
    if missing:
        raise _path_error(label, f"line {kept[0][0]}: header {rows_raw[0]} lacks column(s) "
                                 f"{missing}; expected {','.join(CSV_COLUMNS)}")
    for c in CSV_COLUMNS:
        if header.count(c) > 1:
            raise _path_error(label, f"line {kept[0][0]}: column {c!r} appears twice")
    col = {c: header.index(c) for c in CSV_COLUMNS}
    width = max(col.values()) + 1

    rows: List[List[float]] = []
    ids: List[int] = []
    for (lineno, _), fields in zip(kept[1:], rows_raw[1:]):
        where = f"line {lineno}"
        if len(fields) < width:
            raise _path_error(label, f"{where}: {len(fields)} fields, expected at least {width}")
        try:
            sid = int(fields[col["id"]].strip())
        except ValueError:
            raise _path_error(label, f"{where}: id {fields[col['id']]!r} is not an integer") \
                from None
        if not -_INT64_MAX - 1 <= sid <= _INT64_MAX:
            raise _path_error(label, f"{where}: id {sid} does not fit in int64")
        seg = []
        for c in CSV_COLUMNS[1:]:
            cell = fields[col[c]].strip()
            try:
                v = float(cell)
            except ValueError:
                raise _path_error(label, f"{where}: {c} {cell!r} is not a number") from None
            if not math.isfinite(v):
                raise _path_error(label, f"{where}: {c} is NaN or infinite ({cell!r})")
            seg.append(v)
        _check_segment(seg, where, label)
        rows.append(seg)
        ids.append(sid)
    return _finish(rows, ids, label)


@reads_file("path")
def read_csv_segments(path: PathLike) -> Tuple[np.ndarray, np.ndarray]:
    """Read segments from a CSV file with header ``id,x_a,y_a,x_b,y_b``.

    Columns may come in any order and further columns are ignored; lines starting with ``#``
    and blank lines are skipped (format in the module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.csv`` file (UTF-8).

    Returns
    -------
    segments_m : numpy.ndarray, shape (M, 4), float64
        ``x_A, y_A, x_B, y_B`` [m] of each row, in file order.
    ids : numpy.ndarray, shape (M,), int64
        Unique segment ids.

    Raises
    ------
    ValueError
        ``indoorloc: argument 'path': ...`` for a missing file, a header without the required
        columns, a short row, a non-integer id, a non-numeric or NaN/inf coordinate, a
        zero-length segment or duplicate ids.
    """
    text, label = _read_text(path)
    return _parse_csv(text, label)


# ---------------------------------------------------------------------------------------------
# RoadNetwork construction and packaged / generated networks


def _read_segments_by_suffix(path: PathLike) -> Tuple[np.ndarray, np.ndarray]:
    if not isinstance(path, (str, os.PathLike)):
        raise _error("path", f"expected a str or os.PathLike, got {type(path).__name__}")
    suffix = Path(path).suffix.lower()
    if suffix in (".geojson", ".json"):
        return read_geojson_segments(path)
    if suffix == ".csv":
        return read_csv_segments(path)
    raise _path_error(str(path), f"unknown suffix {suffix!r}; expected .geojson, .json or .csv")


@reads_file("path")
def load_road_network(path: PathLike, **options: Any) -> Any:
    """Read a road-network file and build an :class:`indoorloc.mapmatch.RoadNetwork`.

    Parameters
    ----------
    path : str or os.PathLike
        ``.geojson`` / ``.json`` (:func:`read_geojson_segments`) or ``.csv``
        (:func:`read_csv_segments`); the suffix is case-insensitive.
    **options
        Passed to ``RoadNetwork``: ``snap_tolerance_m`` [m] (default 1e-6) and
        ``split_at_intersections`` (default False).

    Returns
    -------
    indoorloc.mapmatch.RoadNetwork
        The network built from the file's segments and ids.

    Raises
    ------
    ValueError
        For an unknown suffix or a malformed file (``argument 'path'``), ids outside the 32-bit
        range of the C++ core, and whatever ``RoadNetwork`` rejects (zero-length segments,
        invalid options).
    ImportError
        If ``indoorloc.mapmatch.RoadNetwork`` is not available in this build.
    """
    segments_m, ids = _read_segments_by_suffix(path)
    if ids.min() < _INT32_MIN or ids.max() > _INT32_MAX:
        raise _path_error(str(path), "segment ids must fit in 32 bits for RoadNetwork "
                                     f"(range {int(ids.min())}..{int(ids.max())})")
    # The compiled class itself (indoorloc.mapmatch re-exports it): io imports no facade, so that
    # the facade may use io (mapmatch.warehouse_network) without an import cycle.
    from indoorloc._core import mapmatch as _mapmatch

    road_network = getattr(_mapmatch, "RoadNetwork", None)
    if road_network is None:
        raise ImportError("indoorloc.mapmatch.RoadNetwork is not available in this build")
    return road_network(segments_m, ids.astype(np.int32), **options)


def warehouse_segments() -> Tuple[np.ndarray, np.ndarray]:
    """The packaged warehouse road network (re-digitised from paper 000, Fig. 2).

    A 60 m x 36 m hall: horizontal corridors at y = 0, 18, 36 m (x = 0..60), vertical aisles at
    x = 0, 20, 40, 60 (y = 0..36) and x = 10, 30, 50 (y = 0..18), split at every junction into
    26 axis-aligned segments with ids 1..26 and total length 378 m; one connected component, no
    dangling end. Layout, numbering and assumptions: ``docs/mapmatch_warehouse.md``.

    Returns
    -------
    segments_m : numpy.ndarray, shape (26, 4), float64
        ``x_A, y_A, x_B, y_B`` [m]; A is the end with the smaller x (horizontal) or y (vertical).
    ids : numpy.ndarray, shape (26,), int64
        1..26: bottom corridor (y = 0) left to right 1-6, middle (y = 18) 7-12, top (y = 36)
        13-15, then the vertical aisles left to right, each bottom to top, 16-26.
    """
    from importlib import resources

    resource = resources.files("indoorloc.data").joinpath(WAREHOUSE_RESOURCE)
    label = f"indoorloc.data/{WAREHOUSE_RESOURCE}"
    try:
        text = resource.read_text(encoding="utf-8")
    except OSError as exc:  # pragma: no cover - broken installation
        raise _path_error(label, f"packaged file missing ({exc})") from None
    return _parse_geojson(text, label)


_MAX_GRID_CELLS = 10**6


def grid_with_diagonals_segments(nx: int = 4, ny: int = 3,
                                 spacing_m: float = 10.0) -> Tuple[np.ndarray, np.ndarray]:
    """A grid road network with diagonals in every other cell (a test network).

    Nodes are ``(i * spacing_m, j * spacing_m)`` for i = 0..nx, j = 0..ny. Every grid line is
    split at every node, and the cells (i, j) with i + j even (a checkerboard) get one diagonal
    between opposite corners: ``/`` (lower-left to upper-right) in even rows j, ``\\``
    (upper-left to lower-right) in odd rows. Diagonals therefore meet the grid and each other only
    at nodes; the network has no crossing and no T-junction, so ``split_at_intersections``
    changes nothing. Headings present: 0, 90, 45 and -45 degrees.

    Parameters
    ----------
    nx, ny : int
        Number of cells along x and y (>= 1).
    spacing_m : float
        Cell size [m] (> 0).

    Returns
    -------
    segments_m : numpy.ndarray, shape (M, 4), float64
        ``x_A, y_A, x_B, y_B`` [m], M = (ny + 1) nx + (nx + 1) ny + ceil(nx ny / 2). Order:
        horizontals row by row (bottom to top, left to right, A = west end), verticals column by
        column (left to right, bottom to top, A = south end), then diagonals row by row
        (A = west end).
    ids : numpy.ndarray, shape (M,), int64
        1..M in that order.
    """
    for name, value in (("nx", nx), ("ny", ny)):
        if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < 1:
            raise _error(name, f"expected an integer >= 1, got {value!r}")
    if not isinstance(spacing_m, numbers.Real) or isinstance(spacing_m, bool) \
            or not math.isfinite(spacing_m) or spacing_m <= 0:
        raise _error("spacing_m", f"expected a finite number > 0, got {spacing_m!r}")
    nx, ny, h = int(nx), int(ny), float(spacing_m)
    # The rows are built in Python: bound the size so a typo (10**5 x 10**5) fails at once.
    if nx * ny > _MAX_GRID_CELLS:
        raise _error("nx", f"nx * ny = {nx * ny} cells exceeds the limit of {_MAX_GRID_CELLS} "
                           f"(about {2.5 * nx * ny * 32 / 1e9:.3g} GB of segments)")
    if not math.isfinite(max(nx, ny) * h):
        raise _error("spacing_m", f"max(nx, ny) * spacing_m = {max(nx, ny)} * {h!r} is not finite")
    rows: List[List[float]] = []
    for j in range(ny + 1):
        rows.extend([i * h, j * h, (i + 1) * h, j * h] for i in range(nx))
    for i in range(nx + 1):
        rows.extend([i * h, j * h, i * h, (j + 1) * h] for j in range(ny))
    for j in range(ny):
        for i in range(nx):
            if (i + j) % 2:
                continue
            if j % 2 == 0:
                rows.append([i * h, j * h, (i + 1) * h, (j + 1) * h])
            else:
                rows.append([i * h, (j + 1) * h, (i + 1) * h, j * h])
    segments_m = np.asarray(rows, dtype=np.float64)
    return segments_m, np.arange(1, len(rows) + 1, dtype=np.int64)


__all__ = [
    "CSV_COLUMNS",
    "WAREHOUSE_RESOURCE",
    "grid_with_diagonals_segments",
    "load_road_network",
    "read_csv_segments",
    "read_geojson_segments",
    "warehouse_segments",
    "write_geojson_segments",
]
