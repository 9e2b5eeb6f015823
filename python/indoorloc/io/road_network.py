"""Road-network files for ``indoorloc.mapmatch``: GeoJSON and CSV segment lists (json, csv, numpy).

The formats live in :mod:`~indoorloc.io.road_network_geojson` and
:mod:`~indoorloc.io.road_network_csv` (shared checks: :mod:`~indoorloc.io.road_network_segments`);
every name stays importable from here.

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

import math
import numbers
import os
from pathlib import Path
from typing import Any, List, Tuple

import numpy as np

from indoorloc.io.errors import reads_file
from indoorloc.io.road_network_segments import PathLike, _error, _path_error
from indoorloc.io.road_network_csv import CSV_COLUMNS, read_csv_segments
from indoorloc.io.road_network_geojson import _parse_geojson, read_geojson_segments, write_geojson_segments

#: Name of the packaged warehouse network in ``indoorloc.data`` (see docs/mapmatch_warehouse.md).
WAREHOUSE_RESOURCE = "warehouse.geojson"

_INT32_MIN, _INT32_MAX = -(2**31), 2**31 - 1


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
