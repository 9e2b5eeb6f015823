"""GeoJSON road networks (:func:`read_geojson_segments`, :func:`write_geojson_segments`); the format
is described in :mod:`indoorloc.io.road_network`."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from indoorloc.io.errors import reads_file
from indoorloc.io.road_network_segments import (
    PathLike,
    _INT64_MAX,
    _as_segments,
    _check_segment,
    _error,
    _finish,
    _is_int,
    _is_number,
    _path_error,
    _read_text,
)

# Piece j of a feature with id i and k > 1 pieces gets id PIECE_ID_FACTOR * i + j, j = 1..k.
_PIECE_ID_FACTOR = 100
_MAX_PIECES = _PIECE_ID_FACTOR - 1


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
