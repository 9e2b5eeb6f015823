"""Fusion: one particle filter that tracks a walking person from PDR steps, a WiFi signal map and
a floor plan (the "future work" of papers 000 §IV and 002 §VI).

- :class:`FloorPlan` / :class:`FloorGeometry` / :class:`FloorPlanOptions`: walkable space per
  floor (outlines minus obstacles, thin walls) with indexed batch queries: walkable points, wall
  crossings of steps, distance to the nearest wall, uniform sampling;
  :func:`floor_plan_from_polygons` (one floor from rings or shapely-like polygons),
  :func:`floor_plan_from_geometries` (from any objects with ``floor``, ``outlines``,
  ``obstacles``, ``walls``, e.g. ``simulate.building``'s floors); GeoJSON plans through
  :func:`indoorloc.io.load_floor_plan`.
- :class:`ParticleTracker`: the streaming filter (``initialize_known`` / ``initialize_unknown``,
  ``step``, ``wifi``, ``fix``: each returns a :class:`TrackerEstimate`), state (x, y, floor,
  heading offset, stride scale), walls, WiFi (paper 004's interpolated Gaussian model, tempered,
  stale readings handled), corridor mode (paper 000's particles on a RoadNetwork), recovery,
  fixed-lag smoothing.
- :func:`track`: the batch API over a recording, with the backward (FFBSi) smoother.
- :func:`make_wifi_observations`: scans (NaN = not heard, per-reading ages) to observations.
- :class:`Steps`: steps as displacements with covariances, from polar steps or ZUPT increments.
- :class:`Fixes`: position fixes from any external locator (e.g. fingerprint kNN on a
  crowdsourced map): per fix a Gaussian mixture plus an outlier floor (docs/fusion.md).

The model, its equations and how each default was chosen: docs/fusion.md. Example::

    from indoorloc import fusion, wifi
    plan = fusion.FloorPlan([fusion.FloorGeometry(0, [outline], [shop1, shop2])])
    model = wifi.RssModel(signal_map)
    obs, counts = fusion.make_wifi_observations(scan_t, rss, ages)
    steps = fusion.Steps.from_polar(step_t, lengths, headings, 0.05, 0.05)
    result = fusion.track(steps, obs, plan=plan, wifi_model=model, smoother=fusion.SmootherOptions())
    track_m = result["smoothed_m"]
"""

from __future__ import annotations

import math
from typing import Any, Iterable, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc._core.fusion import (
    ANY_FLOOR,
    FloorGeometry,
    FloorPlan,
    FloorPlanOptions,
    ParticleTracker,
    SmootherOptions,
    TrackerEstimate,
    TrackerOptions,
    TrackerSummary,
    WifiObservation,
    make_wifi_observations,
    steps_from_polar,
)
from indoorloc._core.fusion import track as _core_track
from indoorloc.fusion.fixes import Fixes
from indoorloc.fusion.steps import Steps, rotate
from indoorloc.validate import argument_error as _error
from indoorloc.validate import integer, real_array


def _ring_array(obj: Any, name: str) -> np.ndarray:
    try:
        raw = np.asarray(obj)
        if raw.dtype.kind == "c":  # never cast: the imaginary part would be dropped silently
            raise _error(name, f"is complex (dtype {raw.dtype}), expected real vertices")
        ring = np.asarray(obj, dtype=float)
    except (TypeError, ValueError) as exc:
        if str(exc).startswith("indoorloc:"):
            raise
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
        arr = np.asarray(_coords(obj))
    except (TypeError, ValueError):
        return False
    return arr.ndim == 2 and arr.dtype.kind in "biufc"  # complex is refused by _ring_array, by name


def _split_polygons(obj: Any, name: str) -> Tuple[List[np.ndarray], List[np.ndarray]]:
    """Rings and holes of a ring, a polygon-like object, or a list of them."""
    if obj is None:
        return [], []
    if isinstance(obj, (str, bytes)):  # list("x") == ["x"]: recursed until RecursionError
        raise TypeError(f"indoorloc: argument '{name}': expected a ring (M, 2), a polygon, or a list of them, "
                        f"got {type(obj).__name__}")
    if isinstance(obj, np.ndarray) and obj.dtype.kind not in "biufc":
        raise TypeError(f"indoorloc: argument '{name}': expected real vertices, got an array of {obj.dtype}")
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
        walls = real_array(walls, "walls", finite=False)  # NaN is named by FloorGeometry
        if walls.size == 0:
            walls = None
    floor = integer(floor, "floor", lo=-(2**31), hi=2**31 - 1)
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



def floor_plan_from_geometries(floors: Iterable[object], options: Optional[FloorPlanOptions] = None) -> FloorPlan:
    """A FloorPlan from objects with ``floor`` (int), ``outlines`` and ``obstacles`` (lists of
    (M, 2) rings [m]) and ``walls`` ((W, 4) segments [m] or None): FloorGeometry instances, the
    synthetic building's floors, or your own records."""
    try:
        items = list(floors)
    except TypeError:
        raise TypeError(f"indoorloc: argument 'floors': expected an iterable of floor geometries, "
                        f"got {type(floors).__name__}") from None
    if options is not None and not isinstance(options, FloorPlanOptions):
        raise TypeError(f"indoorloc: argument 'options': expected None or a FloorPlanOptions, "
                        f"got {type(options).__name__}")
    geometries = []
    for k, g in enumerate(items):
        if isinstance(g, FloorGeometry):
            geometries.append(g)
            continue
        if not (hasattr(g, "floor") and hasattr(g, "outlines")):
            raise TypeError(f"indoorloc: argument 'floors[{k}]': expected an object with floor, outlines "
                            f"(and obstacles, walls), got {type(g).__name__}")
        walls = getattr(g, "walls", None)
        if walls is not None and np.asarray(walls).size == 0:
            walls = None
        name = f"floors[{k}]"
        floor = g.floor
        if isinstance(floor, (float, np.floating)) and math.isfinite(floor) and float(floor).is_integer():
            floor = int(floor)  # a whole number given as a float (2.0); 1.7 is refused below
        if isinstance(floor, (str, bytes)):
            raise TypeError(f"indoorloc: argument '{name}.floor': expected an integer floor number, "
                            f"got {type(floor).__name__} {floor!r}")
        floor = integer(floor, f"{name}.floor", lo=-1_000_000, hi=1_000_000)
        rings = {}
        for kind in ("outlines", "obstacles"):
            value = g.outlines if kind == "outlines" else getattr(g, "obstacles", [])
            if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
                raise TypeError(f"indoorloc: argument '{name}.{kind}': expected a list of (M, 2) rings, "
                                f"got {type(value).__name__}")
            rings[kind] = [real_array(r, f"{name}.{kind}[{m}]", shape=(None, 2)) for m, r in enumerate(value)]
        if walls is not None:
            walls = real_array(walls, f"{name}.walls", ndim=2)
        geometries.append(FloorGeometry(floor, rings["outlines"], rings["obstacles"], walls))
    return FloorPlan(geometries, options if options is not None else FloorPlanOptions())


def covariance_matrix(row) -> np.ndarray:
    """(xx, xy, yy) -> the symmetric 2 x 2 matrix [m²]."""
    xx, xy, yy = real_array(row, "row", shape=(3,))
    return np.array([[xx, xy], [xy, yy]])


# --------------------------------------------------------------------------- the tracker

def tracker_options(**settings) -> TrackerOptions:
    """TrackerOptions with the library defaults and the given fields set, validated.

    Fields (flattened; units in the names): num_particles, heading_offset_walk_rad, scale_walk,
    min_scale, max_scale, position_noise_m, tempering, max_term, max_age_s, use_not_heard,
    not_heard_dbm, resampling, ess_threshold, wall_log_penalty, respread_after_blocked_steps,
    respread_sd_m, start_position_sd_m, start_heading_offset_sd_rad, start_scale_sd,
    candidate_spacing_m, recovery_log_ratio, recovery_scans, recovery_fraction,
    floor_change_probability, corridor_kappa, smoothing_lag_steps, num_threads, seed.
    Raises ValueError naming an unknown field or an invalid value.
    """
    return TrackerOptions(**settings)


def track(steps: Steps, observations: Sequence[WifiObservation] = (), *, plan=None, wifi_model=None,
          corridors=None, start: Optional[dict] = None, options: Optional[TrackerOptions] = None,
          smoother: Optional[SmootherOptions] = None, fixes: Optional[Fixes] = None) -> dict:
    """Track one recording (the batch API; C++ with the GIL released).

    Parameters
    ----------
    steps : Steps
        Detected steps (see :class:`Steps`).
    observations : list of WifiObservation
        From :func:`make_wifi_observations` (sorted by time); empty without WiFi.
    plan : FloorPlan or None
    wifi_model : indoorloc.wifi.RssModel or None
    corridors : indoorloc.mapmatch.RoadNetwork or None
        Corridor mode (particles on the network, paper 000's heading likelihood).
    start : dict or None
        None: unknown start (seeking from the first scan). Known start:
        ``{"position_m": (2,), "floor": int, "heading_offset_rad": float, "time_s": float}``.
    options : TrackerOptions or None
        Library defaults when None (:func:`tracker_options`).
    smoother : SmootherOptions or None
        Run the backward smoother (FFBSi) when given.
    fixes : Fixes or None
        Position fixes from an external locator, merged with the WiFi observations in time
        (WiFi first at equal times); an unknown start is placed by the first scan or fix.

    Returns
    -------
    dict
        Per-step arrays: ``times_s`` (M,), ``mean_m`` (M, 2), ``covariance_m2`` (M, 3),
        ``floor_probabilities`` (M, F), ``floor_index`` (M,), ``heading_offset_rad``, ``scale``,
        ``ess``, ``log_likelihood``, ``blocked_fraction``, ``resampled``, ``recovered``,
        ``lagged_m`` (M, 2); ``summary`` (TrackerSummary); with a smoother ``smoothed_m`` (M, 2),
        ``smoothed_covariance_m2`` (M, 3), ``smoothed_floor_index`` (M,),
        ``smoothed_trajectories_m`` (M, 2T), ``smoother_seconds``.
    """
    if not isinstance(steps, Steps):
        raise TypeError(f"indoorloc: argument 'steps': expected indoorloc.fusion.Steps, got {type(steps).__name__}")
    if fixes is not None and not isinstance(fixes, Fixes):
        raise TypeError(f"indoorloc: argument 'fixes': expected None or indoorloc.fusion.Fixes, "
                        f"got {type(fixes).__name__}")
    if options is not None and not isinstance(options, TrackerOptions):
        raise TypeError(f"indoorloc: argument 'options': expected None or a TrackerOptions, "
                        f"got {type(options).__name__}")
    try:
        observations = list(observations)
    except TypeError:
        raise TypeError(f"indoorloc: argument 'observations': expected a list of WifiObservation, "
                        f"got {type(observations).__name__}") from None
    for k, o in enumerate(observations):
        if not isinstance(o, WifiObservation):
            raise TypeError(f"indoorloc: argument 'observations[{k}]': expected a WifiObservation, "
                            f"got {type(o).__name__}")
    return _core_track(plan, wifi_model, corridors, steps.times_s, steps.displacements_m, steps.covariances_m2,
                       observations, start, options if options is not None else TrackerOptions(), smoother,
                       None if fixes is None or len(fixes) == 0 else fixes.as_arrays())


from indoorloc.fusion.grid import (  # noqa: E402
    GridFilterEstimate,
    GridFilterSession,
    GridTracker,
    GridTrackerOptions,
    GridTrackSummary,
    region95_contains,
    track_grid,
)



def __getattr__(name: str):  # noqa: ANN202 - module attribute hook
    # Site (fusion/site.py) reads walk files and site folders through indoorloc.io: imported on
    # first use, so that `import indoorloc` stays computational (docs/architecture.md, "Layers").
    if name == "Site":
        from indoorloc.fusion.site import Site

        return Site
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "ANY_FLOOR",
    "GridFilterEstimate",
    "GridFilterSession",
    "GridTracker",
    "GridTrackerOptions",
    "GridTrackSummary",
    "region95_contains",
    "track_grid",
    "Fixes",
    "FloorGeometry",
    "FloorPlan",
    "FloorPlanOptions",
    "ParticleTracker",
    "Site",
    "SmootherOptions",
    "Steps",
    "TrackerEstimate",
    "TrackerOptions",
    "TrackerSummary",
    "WifiObservation",
    "covariance_matrix",
    "floor_geometry",
    "floor_plan_from_geometries",
    "floor_plan_from_polygons",
    "make_wifi_observations",
    "rotate",
    "steps_from_polar",
    "track",
    "tracker_options",
]

