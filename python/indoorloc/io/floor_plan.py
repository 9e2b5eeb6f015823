"""Floor plans as GeoJSON for ``indoorloc.fusion``: read, convert longitude/latitude, write.

A floor plan file is a GeoJSON ``FeatureCollection`` whose features are ``Polygon`` or
``MultiPolygon`` areas and ``LineString`` or ``MultiLineString`` walls. Each feature has a
*role*:

- ``"outline"``: its polygons' exterior rings are the floor's area (a union); their interior
  rings (holes) become obstacles;
- ``"obstacle"``: its polygons' exterior rings are removed from the area (shops, rooms,
  columns); interior rings of obstacles are ignored (a hole inside an obstacle cannot be
  walkable in this model);
- ``"wall"``: every consecutive vertex pair of its lines (or of its polygons' rings) is a thin
  wall segment;
- ``"ignore"``: skipped.

Roles come from the ``roles`` argument (a list with one role per feature, a mapping from feature
index to role, or a function ``(index, feature) -> role``); without it, from the features'
``properties.role`` when every feature has one (the files :func:`write_geojson_floor` writes);
otherwise feature 0 is the outline and every other feature an obstacle (polygons) or a wall
(lines). The last rule matches the ILC 2020 site files (``shared/data/fusion/README.md``): the
first feature is the floor outline, the others are shops.

Coordinates are metres in the floor frame, or WGS84 longitude/latitude (RFC 7946) converted to
metres east and north of an origin with the local metres-per-degree of the WGS84 ellipsoid at
the origin's latitude (meridian radius M and prime-vertical radius N):
``east = (lon - lon0) * pi/180 * N cos(lat0)``, ``north = (lat - lat0) * pi/180 * M``. Over a
building (a few hundred metres) this differs from a proper map projection by millimetres. The
origin is given as ``(lon0, lat0)``, or as ``"outline_sw"``: the south-west corner of the outline
features' longitude/latitude bounding box (the ILC 2020 floor frame). A third coordinate of a
position (altitude) is ignored; a ``"crs"`` member is ignored.

Errors: every reader raises ``ValueError("indoorloc: argument 'path': <file>: feature <k>: ...")``
naming the file and the feature for an unreadable file, invalid JSON, a feature that is not an
object, a missing or unsupported geometry, malformed, non-numeric or non-finite coordinates, a
ring with fewer than 3 distinct vertices, a line with fewer than 2 vertices, a zero-length
wall piece and an unknown role. :func:`load_floor_plan` also maps the floor plan's own checks
(self-intersection, zero area, no walkable area) back to the file and feature.

Examples
--------
>>> from indoorloc.io import floor_geometry_to_geojson, read_geojson_floor
>>> from indoorloc.fusion import FloorGeometry, FloorPlan
>>> g = FloorGeometry(outlines=[[[0, 0], [10, 0], [10, 10], [0, 10]]])
>>> doc = floor_geometry_to_geojson(g)
>>> floor = read_geojson_floor(doc)
>>> FloorPlan(floor.geometry).walkable_area()
100.0
"""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from indoorloc.io.errors import FormatError, reads_file
from indoorloc.validate import integer, real_array, real_scalar
from indoorloc._core.fusion import FloorGeometry, FloorPlan, FloorPlanOptions  # io sits below the facades

PathLike = Union[str, os.PathLike]
Source = Union[PathLike, Mapping[str, Any]]
Roles = Union[None, Sequence[str], Mapping[int, str], Callable[[int, Mapping[str, Any]], str]]
Origin = Union[None, str, Tuple[float, float]]

#: WGS84 ellipsoid: semi-major axis [m] and flattening.
WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563
_E2 = WGS84_F * (2.0 - WGS84_F)

ROLES = ("outline", "obstacle", "wall", "ignore")
_POLYGONAL = ("Polygon", "MultiPolygon")
_LINEAR = ("LineString", "MultiLineString")


# ---- local metric frame ------------------------------------------------------------------

def metres_per_degree(lat_deg: float) -> Tuple[float, float]:
    """Metres per degree of longitude and of latitude at latitude ``lat_deg`` (WGS84).

    ``(pi/180 * N cos(lat), pi/180 * M)`` with the prime-vertical radius
    ``N = a / sqrt(1 - e^2 sin^2 lat)`` and the meridian radius ``M = a (1 - e^2) /
    (1 - e^2 sin^2 lat)^(3/2)``. ``lat_deg`` in [-90, 90].
    """
    phi = math.radians(real_scalar(lat_deg, "lat_deg", lo=-90.0, hi=90.0))
    w2 = 1.0 - _E2 * math.sin(phi) ** 2
    n = WGS84_A_M / math.sqrt(w2)
    m = WGS84_A_M * (1.0 - _E2) / w2**1.5
    return math.radians(1.0) * n * math.cos(phi), math.radians(1.0) * m


def _origin(origin_lon_lat: Any) -> Tuple[float, float]:
    """A (lon, lat) origin [deg]; the poles are refused (no east direction there)."""
    o = real_array(origin_lon_lat, "origin_lon_lat", shape=(2,))
    lon = real_scalar(float(o[0]), "origin_lon_lat", lo=-540.0, hi=540.0)
    lat = real_scalar(float(o[1]), "origin_lon_lat", lo=-89.999, hi=89.999)
    return lon, lat


def _points2(value: Any, name: str, max_abs: float) -> np.ndarray:
    """A finite float array of shape (..., 2) with entries within +-max_abs."""
    a = real_array(value, name, max_abs=max_abs)
    if a.ndim == 0 or a.shape[-1] != 2:
        raise ValueError(f"indoorloc: argument '{name}': expected shape (..., 2), got {a.shape}")
    return a


def lonlat_to_local(lon_lat_deg: Any, origin_lon_lat: Tuple[float, float]) -> np.ndarray:
    """(N, 2) longitude/latitude [deg] -> (N, 2) east/north [m] of the origin (local frame)."""
    ll = _points2(lon_lat_deg, "lon_lat_deg", 1e3)
    lon0, lat0 = _origin(origin_lon_lat)
    kx, ky = metres_per_degree(lat0)
    out = np.empty_like(ll)
    out[..., 0] = (ll[..., 0] - lon0) * kx
    out[..., 1] = (ll[..., 1] - lat0) * ky
    return out


def local_to_lonlat(east_north_m: Any, origin_lon_lat: Tuple[float, float]) -> np.ndarray:
    """Inverse of :func:`lonlat_to_local`: (N, 2) east/north [m] -> longitude/latitude [deg]."""
    en = _points2(east_north_m, "east_north_m", 1e9)
    lon0, lat0 = _origin(origin_lon_lat)
    kx, ky = metres_per_degree(lat0)
    out = np.empty_like(en)
    out[..., 0] = lon0 + en[..., 0] / kx
    out[..., 1] = lat0 + en[..., 1] / ky
    return out


# ---- reading -----------------------------------------------------------------------------

@dataclass
class GeoJsonFloor:
    """A floor read from GeoJSON: its geometry and where each ring and wall came from."""

    geometry: FloorGeometry
    #: Feature index of each outline ring, obstacle ring and wall row of ``geometry``.
    outline_features: List[int] = field(default_factory=list)
    obstacle_features: List[int] = field(default_factory=list)
    wall_features: List[int] = field(default_factory=list)
    #: The origin used for longitude/latitude input, or None for metres.
    origin_lon_lat: Optional[Tuple[float, float]] = None
    #: The file (or "<dict>") for messages.
    label: str = ""
    #: Role of every feature, in file order.
    roles: List[str] = field(default_factory=list)


def _error(arg: str, msg: str) -> ValueError:
    return ValueError(f"indoorloc: argument '{arg}': {msg}")


def _check_source(source: Any, name: str) -> None:
    """A path or an already parsed GeoJSON dict (named before any file is opened)."""
    if not isinstance(source, (str, os.PathLike, Mapping)):
        raise TypeError(f"indoorloc: argument '{name}': expected a path or a GeoJSON dict, "
                        f"got {type(source).__name__}")


def _check_roles(roles: Any) -> None:
    if not (roles is None or callable(roles) or isinstance(roles, (Mapping, list, tuple))):
        raise TypeError(f"indoorloc: argument 'roles': expected None, a list, a dict or a callable, "
                        f"got {type(roles).__name__}")


def _load(source: Source) -> Tuple[Any, str]:
    if isinstance(source, Mapping):
        return source, "<dict>"
    if not isinstance(source, (str, os.PathLike)):
        raise _error("path", f"expected a path or a GeoJSON dict, got {type(source).__name__}")
    p = Path(source)
    label = str(p)
    if not p.is_file():
        raise _error("path", f"{label}: file not found" if not p.exists() else f"{label}: not a regular file")
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise _error("path", f"{label}: cannot read file ({exc})") from None
    try:
        return json.loads(text), label
    except json.JSONDecodeError as exc:
        raise _error("path", f"{label}: invalid JSON ({exc})") from None


def _features(doc: Any, label: str) -> List[Any]:
    if not isinstance(doc, Mapping) or doc.get("type") != "FeatureCollection":
        raise _error("path", f"{label}: expected a GeoJSON FeatureCollection")
    features = doc.get("features")
    if not isinstance(features, list):
        raise _error("path", f"{label}: 'features' must be a list")
    return features


def _positions(coords: Any, where: str, label: str) -> np.ndarray:
    """A GeoJSON position list -> (N, 2) float array (altitude dropped), finite numbers only."""
    if not isinstance(coords, list) or not coords:
        raise _error("path", f"{label}: {where}: expected a non-empty list of positions")
    out = np.empty((len(coords), 2))
    for k, pos in enumerate(coords):
        if (not isinstance(pos, list) or len(pos) < 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in pos[:2])):
            raise _error("path", f"{label}: {where}: position {k} is not a list of numbers")
        x, y = float(pos[0]), float(pos[1])
        if not (math.isfinite(x) and math.isfinite(y)):
            raise _error("path", f"{label}: {where}: position {k} is not finite ({pos[0]!r}, {pos[1]!r})")
        out[k] = (x, y)
    return out


def _ring(coords: Any, where: str, label: str) -> np.ndarray:
    ring = _positions(coords, where, label)
    if len(np.unique(ring, axis=0)) < 3:
        raise _error("path", f"{label}: {where}: a ring needs at least 3 distinct vertices")
    if len(ring) > 1 and np.array_equal(ring[0], ring[-1]):
        ring = ring[:-1]
    return ring


def _polygons(geom: Mapping[str, Any], where: str, label: str) -> List[List[np.ndarray]]:
    """Polygon / MultiPolygon -> list of polygons, each [exterior, hole, ...]."""
    coords = geom.get("coordinates")
    polys = [coords] if geom["type"] == "Polygon" else coords
    if not isinstance(polys, list) or not polys:
        raise _error("path", f"{label}: {where}: expected polygon coordinates")
    out = []
    for p, poly in enumerate(polys):
        pw = where if geom["type"] == "Polygon" else f"{where}: polygon {p}"
        if not isinstance(poly, list) or not poly:
            raise _error("path", f"{label}: {pw}: expected a list of rings")
        out.append([_ring(r, f"{pw}: ring {k}", label) for k, r in enumerate(poly)])
    return out


def _lines(geom: Mapping[str, Any], where: str, label: str) -> List[np.ndarray]:
    coords = geom.get("coordinates")
    lines = [coords] if geom["type"] == "LineString" else coords
    if not isinstance(lines, list) or not lines:
        raise _error("path", f"{label}: {where}: expected line coordinates")
    out = []
    for k, line in enumerate(lines):
        lw = where if geom["type"] == "LineString" else f"{where}: line {k}"
        pts = _positions(line, lw, label)
        if len(pts) < 2:
            raise _error("path", f"{label}: {lw}: a line needs at least 2 vertices")
        out.append(pts)
    return out


def _default_roles(features: List[Any]) -> List[str]:
    props = [f.get("properties") if isinstance(f, Mapping) else None for f in features]
    if features and all(isinstance(p, Mapping) and p.get("role") in ROLES for p in props):
        return [p["role"] for p in props]
    roles = []
    for k, f in enumerate(features):
        geom = f.get("geometry") if isinstance(f, Mapping) else None
        linear = isinstance(geom, Mapping) and geom.get("type") in _LINEAR
        roles.append("outline" if k == 0 else ("wall" if linear else "obstacle"))
    return roles


def _resolve_roles(roles: Roles, features: List[Any], label: str) -> List[str]:
    if roles is None:
        return _default_roles(features)
    if callable(roles):
        out = [roles(k, f) for k, f in enumerate(features)]
    elif isinstance(roles, Mapping):
        default = _default_roles(features)
        for k in roles:
            if not isinstance(k, int) or not 0 <= k < len(features):
                raise _error("roles", f"feature index {k!r} out of range [0, {len(features)})")
        out = [roles.get(k, default[k]) for k in range(len(features))]
    else:
        out = list(roles)
        if len(out) != len(features):
            raise _error("roles", f"expected {len(features)} roles (one per feature of {label}), got {len(out)}")
    for k, r in enumerate(out):
        if r not in ROLES:
            raise _error("roles", f"feature {k}: unknown role {r!r} (expected one of {', '.join(ROLES)})")
    return out


def _resolve_origin(origin: Origin, features: List[Any], roles: List[str],
                    label: str) -> Optional[Tuple[float, float]]:
    if origin is None:
        return None
    if isinstance(origin, str):
        if origin != "outline_sw":
            raise _error("origin_lon_lat", f"expected (lon, lat), 'outline_sw' or None, got {origin!r}")
        lo = np.array([np.inf, np.inf])
        for k, (f, r) in enumerate(zip(features, roles)):
            if r != "outline":
                continue
            for poly in _polygons(f["geometry"], f"feature {k}", label):
                lo = np.minimum(lo, poly[0].min(axis=0))
        if not np.all(np.isfinite(lo)):
            raise _error("origin_lon_lat", f"{label}: 'outline_sw' needs an outline feature")
        return float(lo[0]), float(lo[1])
    try:
        lon0, lat0 = (float(v) for v in origin)
    except (TypeError, ValueError):
        raise _error("origin_lon_lat", f"expected (lon, lat) in degrees, got {origin!r}") from None
    if not (math.isfinite(lon0) and math.isfinite(lat0) and -90.0 < lat0 < 90.0):
        raise _error("origin_lon_lat", f"expected a finite (lon, lat) with |lat| < 90, got {origin!r}")
    return lon0, lat0


@reads_file("source", argument="path")
def read_geojson_floor(
    source: Source,
    *,
    floor: int = 0,
    roles: Roles = None,
    origin_lon_lat: Origin = None,
) -> GeoJsonFloor:
    """Read one floor from a GeoJSON FeatureCollection (see the module docstring).

    Parameters
    ----------
    source : path or dict
        The file, or an already parsed GeoJSON object.
    floor : int, default 0
        Floor number given to the geometry.
    roles : list of str, dict {feature index: role}, callable (index, feature) -> role, or None
        ``"outline"``, ``"obstacle"``, ``"wall"`` or ``"ignore"`` per feature; None: the
        features' ``properties.role``, or else feature 0 = outline, the rest obstacles (lines:
        walls).
    origin_lon_lat : (lon, lat) [deg], "outline_sw", or None
        None: coordinates are metres. Otherwise they are WGS84 longitude/latitude, converted
        to metres east/north of this origin.

    Returns
    -------
    GeoJsonFloor
        ``geometry`` (a :class:`indoorloc.fusion.FloorGeometry`) and the feature index of every
        ring and wall.
    """
    _check_source(source, "source")
    floor = integer(floor, "floor", lo=-(2**31), hi=2**31 - 1)
    _check_roles(roles)
    doc, label = _load(source)
    features = _features(doc, label)
    for k, f in enumerate(features):
        if not isinstance(f, Mapping) or f.get("type") != "Feature":
            raise _error("path", f"{label}: feature {k}: not a GeoJSON Feature object")
        geom = f.get("geometry")
        if not isinstance(geom, Mapping) or geom.get("type") not in _POLYGONAL + _LINEAR:
            kind = geom.get("type") if isinstance(geom, Mapping) else type(geom).__name__
            raise _error("path", f"{label}: feature {k}: unsupported geometry {kind!r} "
                                 f"(expected Polygon, MultiPolygon, LineString or MultiLineString)")
    role_list = _resolve_roles(roles, features, label)
    origin = _resolve_origin(origin_lon_lat, features, role_list, label)

    def to_m(xy: np.ndarray) -> np.ndarray:
        return xy if origin is None else lonlat_to_local(xy, origin)

    result = GeoJsonFloor(geometry=FloorGeometry(floor=int(floor)), origin_lon_lat=origin, label=label,
                          roles=role_list)
    outlines: List[np.ndarray] = []
    obstacles: List[np.ndarray] = []
    walls: List[np.ndarray] = []
    for k, (f, role) in enumerate(zip(features, role_list)):
        if role == "ignore":
            continue
        geom = f["geometry"]
        where = f"feature {k}"
        polygonal = geom["type"] in _POLYGONAL
        if role in ("outline", "obstacle") and not polygonal:
            raise _error("path", f"{label}: {where}: role {role!r} needs a Polygon or MultiPolygon, "
                                 f"got {geom['type']}")
        if role == "outline":
            for poly in _polygons(geom, where, label):
                outlines.append(to_m(poly[0]))
                result.outline_features.append(k)
                for hole in poly[1:]:
                    obstacles.append(to_m(hole))
                    result.obstacle_features.append(k)
        elif role == "obstacle":
            for poly in _polygons(geom, where, label):
                obstacles.append(to_m(poly[0]))
                result.obstacle_features.append(k)
        else:  # wall
            chains = ([np.vstack([r, r[:1]]) for poly in _polygons(geom, where, label) for r in poly]
                      if polygonal else _lines(geom, where, label))
            for chain in chains:
                xy = to_m(chain)
                seg = np.hstack([xy[:-1], xy[1:]])
                zero = np.all(seg[:, :2] == seg[:, 2:], axis=1)
                if np.any(zero):
                    j = int(np.argmax(zero))
                    raise _error("path", f"{label}: {where}: zero-length wall piece at vertex {j}")
                walls.append(seg)
                result.wall_features += [k] * len(seg)
    result.geometry.outlines = outlines
    result.geometry.obstacles = obstacles
    if walls:
        result.geometry.walls = np.vstack(walls)
    return result


_RING_REF = re.compile(r"floors\[(\d+)\]\.(outlines|obstacles)\[(\d+)\]")
_WALL_REF = re.compile(r"floors\[(\d+)\]\.walls': row (\d+)")
_WALL_ENTRY_REF = re.compile(r"floors\[(\d+)\]\.walls': entry (\d+)")
_FLOOR_REF = re.compile(r"floors\[(\d+)\]")


@reads_file("sources", argument="path")
def load_floor_plan(
    sources: Union[Source, Sequence[Source]],
    *,
    floors: Optional[Sequence[int]] = None,
    roles: Roles = None,
    origin_lon_lat: Origin = None,
    options: Optional[FloorPlanOptions] = None,
) -> FloorPlan:
    """A :class:`indoorloc.fusion.FloorPlan` from one GeoJSON file per floor.

    Parameters
    ----------
    sources : path, dict, or a list of them
        One floor per file.
    floors : list of int, optional
        Floor numbers (default 0, 1, ...).
    roles, origin_lon_lat
        As for :func:`read_geojson_floor`, applied to every file.
    options : FloorPlanOptions, optional

    Errors of the floor plan's checks (e.g. a self-intersecting ring) name the file and the
    feature as well as ``floors[i].obstacles[k]``.
    """
    if isinstance(sources, (str, os.PathLike, Mapping)):
        sources = [sources]
    if not isinstance(sources, (list, tuple)):
        raise TypeError(f"indoorloc: argument 'sources': expected a path, a GeoJSON dict or a list of them, "
                        f"got {type(sources).__name__}")
    sources = list(sources)
    for k, src in enumerate(sources):
        _check_source(src, f"sources[{k}]")
    if floors is None:
        floors = list(range(len(sources)))
    if not isinstance(floors, (list, tuple, np.ndarray)):
        raise TypeError(f"indoorloc: argument 'floors': expected a list of floor numbers, got {type(floors).__name__}")
    floors = [integer(n, f"floors[{k}]", lo=-(2**31), hi=2**31 - 1) for k, n in enumerate(floors)]
    if len(floors) != len(sources):
        raise _error("floors", f"expected {len(sources)} floor numbers (one per source), got {len(floors)}")
    _check_roles(roles)
    if options is not None and not isinstance(options, FloorPlanOptions):
        raise TypeError(f"indoorloc: argument 'options': expected None or a FloorPlanOptions, "
                        f"got {type(options).__name__}")
    read = [read_geojson_floor(s, floor=n, roles=roles, origin_lon_lat=origin_lon_lat)
            for s, n in zip(sources, floors)]
    try:
        return FloorPlan([r.geometry for r in read], options if options is not None else FloorPlanOptions())
    except ValueError as exc:
        msg = str(exc)
        m = _RING_REF.search(msg)
        if m:
            r = read[int(m.group(1))]
            index = (r.outline_features if m.group(2) == "outlines" else r.obstacle_features)[int(m.group(3))]
            raise ValueError(f"{msg} ({r.label}: feature {index})") from None
        m = _WALL_REF.search(msg) or _WALL_ENTRY_REF.search(msg)
        if m:
            r = read[int(m.group(1))]
            row = int(m.group(2)) if m.re is _WALL_REF else int(m.group(2)) // 4  # (W, 4) row-major
            if 0 <= row < len(r.wall_features):
                raise ValueError(f"{msg} ({r.label}: feature {r.wall_features[row]})") from None
        # Any other floor-level error (no outline, a repeated floor number, the index's memory):
        # the file of every floor it names.
        named = sorted({int(k) for k in _FLOOR_REF.findall(msg) if int(k) < len(read)})
        if named:
            raise ValueError(f"{msg} ({'; '.join(f'floors[{k}]: {read[k].label}' for k in named)})") from None
        raise


# ---- writing -----------------------------------------------------------------------------

def _closed(ring: np.ndarray) -> List[List[float]]:
    ring = np.asarray(ring, dtype=float)
    if len(ring) and not np.array_equal(ring[0], ring[-1]):
        ring = np.vstack([ring, ring[:1]])
    return [[float(x), float(y)] for x, y in ring]


def floor_geometry_to_geojson(
    geometry: FloorGeometry, *, origin_lon_lat: Optional[Tuple[float, float]] = None
) -> Dict[str, Any]:
    """A GeoJSON FeatureCollection of a floor: one Polygon feature per outline and obstacle ring
    and one two-vertex LineString per wall, each with ``properties.role`` (and
    ``properties.floor``). With ``origin_lon_lat`` the coordinates are converted to WGS84
    longitude/latitude (the inverse of the reader's conversion); otherwise they stay metres.
    Reading the result with :func:`read_geojson_floor` (and the same origin) gives back the
    geometry (exactly in metres; to about 1e-9 m through longitude/latitude).
    """
    if not all(hasattr(geometry, a) for a in ("floor", "outlines", "obstacles", "walls")):
        raise TypeError(f"indoorloc: argument 'geometry': expected a FloorGeometry (floor, outlines, obstacles, "
                        f"walls), got {type(geometry).__name__}")

    def conv(xy: np.ndarray) -> np.ndarray:
        xy = np.asarray(xy, dtype=float)
        return xy if origin_lon_lat is None else local_to_lonlat(xy, origin_lon_lat)

    # The readers' rule for floors (whole numbers within ±1e6): a NaN floor used to be written as
    # the token NaN and blamed on a coordinate, a numpy integer failed in json.dumps.
    floor = geometry.floor
    if isinstance(floor, (float, np.floating)) and math.isfinite(floor) and float(floor).is_integer():
        floor = int(floor)
    floor = integer(floor, "geometry.floor", lo=-10**6, hi=10**6)
    features = []
    for role, rings in (("outline", geometry.outlines), ("obstacle", geometry.obstacles)):
        for ring in rings:
            features.append({"type": "Feature", "properties": {"role": role, "floor": floor},
                             "geometry": {"type": "Polygon", "coordinates": [_closed(conv(ring))]}})
    for row in np.asarray(geometry.walls, dtype=float).reshape(-1, 4):
        xy = conv(row.reshape(2, 2))
        features.append({"type": "Feature", "properties": {"role": "wall", "floor": floor},
                         "geometry": {"type": "LineString",
                                      "coordinates": [[float(x), float(y)] for x, y in xy]}})
    return {"type": "FeatureCollection", "features": features}


def write_geojson_floor(
    path: PathLike, geometry: FloorGeometry, *, origin_lon_lat: Optional[Tuple[float, float]] = None
) -> None:
    """Write :func:`floor_geometry_to_geojson` of ``geometry`` to ``path`` (floats in Python's
    shortest round-trip form). Non-finite coordinates are refused (ValueError naming the ring):
    JSON has no NaN and the reader refuses the token. The file is written to a temporary name in
    the same folder and renamed, so ``path`` is never left half-written."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"indoorloc: argument 'path': expected a file path, got {type(path).__name__}")
    if all(hasattr(geometry, a) for a in ("outlines", "obstacles", "walls")):
        for kind in ("outlines", "obstacles"):
            for k, ring in enumerate(getattr(geometry, kind)):
                real_array(ring, f"geometry.{kind}[{k}]")
        real_array(geometry.walls, "geometry.walls")
    doc = floor_geometry_to_geojson(geometry, origin_lon_lat=origin_lon_lat)
    # allow_nan=False: a non-finite value left after the checks (a conversion overflow) raises
    # instead of writing the token NaN.
    try:
        text = json.dumps(doc, allow_nan=False)
    except ValueError as exc:
        raise ValueError(f"indoorloc: argument 'geometry': has a coordinate that is not finite ({exc})") from None
    target = Path(path)
    tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


__all__ = [
    "GeoJsonFloor",
    "ROLES",
    "WGS84_A_M",
    "WGS84_F",
    "floor_geometry_to_geojson",
    "load_floor_plan",
    "local_to_lonlat",
    "lonlat_to_local",
    "metres_per_degree",
    "read_geojson_floor",
    "write_geojson_floor",
]
