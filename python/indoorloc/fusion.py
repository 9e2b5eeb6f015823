"""Particle-filter fusion of PDR steps, WiFi scans and a floor plan (issue 14).

The floor plan (C++ core, ``indoorloc._core.fusion``; see docs/fusion.md, "Floor plan"):

- :class:`FloorGeometry`: one floor's outline rings, obstacle rings and thin wall segments,
  in metres in the floor frame;
- :class:`FloorPlan`: the indexed walkable space of one or more floors with batched queries
  (``is_walkable``, ``crosses_wall``, ``distance_to_wall``, ``sample_walkable``), built once and
  queried from the particle filter's inner loop;
- :class:`FloorPlanOptions`: the index's cell size and the self-intersection check;
- :func:`floor_plan_from_polygons`: a one-floor plan from rings (numpy arrays, lists, or objects
  with shapely's ``exterior`` / ``interiors`` / ``geoms`` interface).

Floor plans stored as GeoJSON (metres, or WGS84 longitude/latitude with a local origin) are read
by :func:`indoorloc.io.read_geojson_floor` and :func:`indoorloc.io.load_floor_plan`.

Examples
--------
>>> import numpy as np
>>> from indoorloc.fusion import floor_plan_from_polygons
>>> plan = floor_plan_from_polygons([[0, 0], [10, 0], [10, 10], [0, 10]],
...                                 obstacles=[[[4, 4], [6, 4], [6, 6], [4, 6]]])
>>> plan.is_walkable([[1, 1], [5, 5]]).tolist()
[True, False]
>>> plan.crosses_wall([[1, 5, 9, 5]]).tolist()
[True]
>>> round(plan.walkable_area(), 6)
96.0
"""

from __future__ import annotations

from typing import Any, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc._core.fusion import FloorGeometry, FloorPlan, FloorPlanOptions


def _error(arg: str, msg: str) -> ValueError:
    return ValueError(f"indoorloc: argument '{arg}': {msg}")


def _ring_array(obj: Any, name: str) -> np.ndarray:
    try:
        ring = np.asarray(obj, dtype=float)
    except (TypeError, ValueError):
        raise _error(name, "cannot be converted to an (M, 2) float array") from None
    if ring.ndim != 2 or ring.shape[1] < 2:
        raise _error(name, f"expected an (M, 2) array of vertices, got shape {ring.shape}")
    return np.ascontiguousarray(ring[:, :2])  # a third coordinate (altitude) is dropped


def _coords(obj: Any) -> Any:
    return getattr(obj, "coords", obj)


def _is_single_ring(obj: Any) -> bool:
    """True for an (M, 2) array-like (a ring), False for a list of rings or polygons."""
    if hasattr(obj, "exterior") or hasattr(obj, "geoms"):
        return False
    try:
        arr = np.asarray(_coords(obj), dtype=float)
    except (TypeError, ValueError):
        return False
    return arr.ndim == 2


def _split_polygons(obj: Any, name: str) -> Tuple[List[np.ndarray], List[np.ndarray]]:
    """Rings and holes of a ring, a polygon-like object, or a list of them."""
    if obj is None:
        return [], []
    if hasattr(obj, "geoms"):  # MultiPolygon-like
        obj = list(obj.geoms)
    if hasattr(obj, "exterior"):  # Polygon-like
        holes = [_ring_array(_coords(h), f"{name}.interiors[{k}]") for k, h in enumerate(obj.interiors)]
        return [_ring_array(_coords(obj.exterior), f"{name}.exterior")], holes
    if _is_single_ring(obj):
        return [_ring_array(_coords(obj), name)], []
    rings: List[np.ndarray] = []
    holes: List[np.ndarray] = []
    try:
        items = list(obj)
    except TypeError:
        raise _error(name, "expected a ring (M, 2), a polygon, or a list of them") from None
    for k, item in enumerate(items):
        r, h = _split_polygons(item, f"{name}[{k}]")
        rings += r
        holes += h
    return rings, holes


def floor_geometry(
    outlines: Any,
    obstacles: Any = (),
    walls: Optional[Any] = None,
    *,
    floor: int = 0,
) -> FloorGeometry:
    """One floor's :class:`FloorGeometry` from rings or polygon-like objects.

    Parameters
    ----------
    outlines : (M, 2) array-like, polygon-like, or a list of them [m]
        The floor's area (union of the rings). Holes of polygon-like outlines (``interiors``)
        become obstacles.
    obstacles : list of (M, 2) array-likes or polygon-likes [m], optional
        Areas removed from the floor. An obstacle is its exterior ring; holes of obstacles are
        ignored (a hole inside an obstacle cannot be walkable in this model).
    walls : (W, 4) array-like [m], optional
        Thin wall segments, rows (x0, y0, x1, y1).
    floor : int, default 0
        Floor number.
    """
    outline_rings, holes = _split_polygons(outlines, "outlines")
    obstacle_rings, _ = _split_polygons(obstacles, "obstacles")
    if walls is not None:
        walls = np.asarray(walls, dtype=float)
        if walls.size == 0:
            walls = None
    return FloorGeometry(floor=int(floor), outlines=outline_rings, obstacles=obstacle_rings + holes,
                         walls=walls)


def floor_plan_from_polygons(
    outlines: Any,
    obstacles: Any = (),
    walls: Optional[Any] = None,
    *,
    floor: int = 0,
    options: Optional[FloorPlanOptions] = None,
    **option_values: Any,
) -> FloorPlan:
    """A one-floor :class:`FloorPlan` from rings (see :func:`floor_geometry` for the arguments).

    ``options`` or keyword arguments of :class:`FloorPlanOptions` (``cell_size_m=0.5``, ...)
    configure the index. Raises ``ValueError`` naming the bad ring (``floors[0].obstacles[3]``)
    for NaN coordinates, fewer than 3 distinct vertices, zero area, self-intersection or an
    empty walkable area.
    """
    if options is not None and option_values:
        raise _error("options", "give either an options object or option keywords, not both")
    if options is None:
        options = FloorPlanOptions(**option_values)
    return FloorPlan([floor_geometry(outlines, obstacles, walls, floor=floor)], options)


__all__ = [
    "FloorGeometry",
    "FloorPlan",
    "FloorPlanOptions",
    "floor_geometry",
    "floor_plan_from_polygons",
]
