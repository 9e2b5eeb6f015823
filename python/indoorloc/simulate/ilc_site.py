"""A synthetic site in the Indoor Location Competition 2.0 on-disk format, for end-to-end tests.

:func:`write_ilc_site` writes ``<root>/<floor>/floor_info.json``, ``geojson_map.json`` and
``path_data_files/<walk id>.txt`` in the layout of the competition's data (docs/fusion_data.md),
so that :mod:`indoorloc.io` (``read_ilc_site``, ``load_floor_plan(..., origin_lon_lat=
"outline_sw")``), the hand-held PDR, the crowdsourced WiFi map and ``indoorloc fusion evaluate``
run on it without the shared data. :func:`make_ilc_site` returns the same site in memory with
its truth (step counts, Weinberg K, yaw offset, dense positions).

Model (x east, y north, metres from the south-west corner of the outline; every floor has the
same layout, as in :mod:`indoorloc.simulate.building`):

- **Floor.** A ``width_m`` x ``depth_m`` mall: ``ew_corridors`` east-west and ``ns_corridors``
  north-south corridors (``corridor_width_m``) cross the whole floor; every block between them
  (and the outline) is tiled by 1-3 shops, obstacle polygons without doors (as in the real
  GeoJSON, where the surveyors walk the corridors). The GeoJSON holds the outline first (a
  MultiPolygon, WGS84 lon/lat) and then one Polygon per shop, with the real files' properties.
- **Route.** A walk starts at a random point of the corridor grid between two crossings and
  follows the centre lines, turning at random at each crossing (never back), corners rounded by
  quadratic Bezier arcs (:func:`indoorloc.simulate.walker._round_corners`). The walker stands
  ``stand_start_s`` at the start (the first waypoint, t = 0) and ``stand_end_s`` after the last
  step.
- **Gait.** Per walk a cadence f ~ N(step_frequency_hz, sd) and a mean stride L ~ N(step_length_m,
  sd); per step L_k = L (1 + step_length_sd_fraction e_k) and period (1 + 0.03 e'_k) / f. The
  vertical acceleration is A(t) cos(phi(t)) with phi = 2 pi k at step k (the bounce peaks at the
  step) and the amplitude chosen so that Weinberg's rule holds with the site's K:
  L_k = K (2 A_k G(f))^(1/4) (paper 002 eq. 4; G the gain of the 4th-order 3 Hz Butterworth
  low-pass that ``pdr.weinberg_features`` applies), plus a forward surge (0.35 A at f) and a
  lateral sway (0.25 A at f / 2) and white noise.
- **Orientation.** The phone is held flat in front, portrait (+y forward), pitched up by
  6-14 deg with a small bob. Its heading (indoorloc.pdr.handheld's convention: the +y axis, east = 0,
  north = pi/2) is the walking direction (smoothed over 0.4 s) minus the walk's yaw offset:
  ``yaw_offset_deg`` (the floor frame minus the phone frame, what ``calibrate_handheld`` fits) plus
  N(0, yaw_offset_walk_sd_deg) per walk. TYPE_GYROSCOPE is the body rate of that orientation
  (central differences) plus noise and a constant bias; TYPE_ROTATION_VECTOR carries it rotated
  about the vertical by a slow heading error (a sum of random sinusoids, sd heading_error_sd_deg:
  indoor magnetic disturbance), x, y, z only with w >= 0 as Android writes it; TYPE_MAGNETIC_FIELD
  is the local field (``magnetic_field_enu_ut``) seen through the rotation vector's orientation.
- **WiFi.** ``aps_per_floor`` access points per floor (corridors and shops), each with a 2.4 GHz
  and a 5 GHz BSSID (5 GHz: ``p0_5ghz_offset_db`` weaker), through
  :class:`indoorloc.simulate.radio.RadioModel` (log-distance, shop faces as obstacles, correlated
  shadowing, noise, sensitivity, random misses; other floors attenuated). The phone sweeps the
  channels ``sweep_lag_s`` before each scan (every ``scan_interval_s``); a scan lists the BSSIDs
  heard in its sweep (fresh, last seen at the sweep) and, as Android's cache does, repeats the
  last reading of a BSSID missed by this sweep if it is at most ``cache_s`` old (same RSSI and
  last-seen time: stale readings). One or two sweeps before the walk's start fill the cache.
- **Waypoints.** TYPE_WAYPOINT at t = 0, at every corner of the route, at the last step, and in
  between so that they are 3-6 s apart: the true positions at those times.

Randomness: ``numpy.random.default_rng([seed, 0x1C2, stream, ...])``; streams 0 layout, 1 radio,
2 site-wide calibration, 3 walks (per floor and walk). Writing one floor of 8 walks of 20-40 s
takes about 0.4 s.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
from scipy.spatial.transform import Rotation

from indoorloc.io.floor_plan import local_to_lonlat
from indoorloc.simulate import _geometry as geo
from indoorloc.simulate.radio import RadioConfig, RadioModel, make_radio_model
from indoorloc.simulate.walker import Trajectory, _round_corners

PathLike = Union[str, Path]

_DOMAIN = 0x1C2
_LAYOUT_STREAM, _RADIO_STREAM, _SITE_STREAM, _WALK_STREAM = 0, 1, 2, 3
GRAVITY_MPS2 = 9.80665


def _default_radio() -> RadioConfig:
    # A mall: no thin walls; shop fronts (glass, partitions) cost less than concrete shafts;
    # phones stop reporting below about -93 dBm (the real site's minimum).
    return RadioConfig(aps_per_floor=24, p0_dbm=-38.0, exponent=2.3, obstacle_attenuation_db=5.0,
                       floor_attenuation_db=15.0, shadowing_sd_db=4.0, shadowing_length_m=5.0,
                       noise_sd_db=2.5, sensitivity_dbm=-93.0, miss_probability=0.05)


@dataclass(frozen=True)
class IlcSiteConfig:
    """Parameters of the synthetic site. Metres, seconds, Hz, degrees, dBm, uT as named."""

    # Floor layout
    width_m: float = 60.0
    depth_m: float = 40.0
    corridor_width_m: float = 4.0
    ew_corridors: int = 2                      #: east-west corridors crossing the floor
    ns_corridors: int = 3                      #: north-south corridors crossing the floor
    corridor_jitter_m: float = 1.5             #: random shift of each corridor from even spacing
    shops_per_block: Tuple[int, int] = (1, 3)  #: inclusive range of shops tiling each block
    origin_lon_lat: Tuple[float, float] = (116.3975, 39.9087)  #: south-west corner of the outline
    # Walks
    walk_duration_s: Tuple[float, float] = (20.0, 40.0)
    stand_start_s: Tuple[float, float] = (0.4, 1.0)
    stand_end_s: Tuple[float, float] = (0.5, 1.5)
    corner_cut_m: float = 1.5
    step_length_m: float = 0.7
    step_length_walker_sd_m: float = 0.03      #: spread of the mean stride between walks (clipped to +-0.08 m)
    step_length_sd_fraction: float = 0.04      #: step-to-step variability
    step_frequency_hz: float = 1.8
    step_frequency_walker_sd_hz: float = 0.08
    #: K of L = K (max - min LP|a|)^(1/4) [m / (m/s^2)^(1/4)]; with 0.62-0.78 m strides the bounce
    #: amplitude is 1.6-4 m/s^2, clear of indoorloc.pdr.handheld's 1 m/s^2 peak floor
    weinberg_k: float = 0.46
    yaw_offset_deg: float = 4.0                #: floor-frame heading minus phone heading, site mean
    yaw_offset_walk_sd_deg: float = 1.5        #: per-walk spread of that offset
    heading_error_sd_deg: float = 2.0          #: slow error of the rotation vector's heading
    pitch_deg: Tuple[float, float] = (6.0, 14.0)
    accel_noise_sd_mps2: float = 0.25
    gyro_noise_sd_radps: float = 0.015
    gyro_bias_sd_radps: float = 0.003
    mag_noise_sd_ut: float = 0.5
    magnetic_field_enu_ut: Tuple[float, float, float] = (0.0, 28.0, -40.0)
    sample_rate_hz: float = 50.0
    waypoint_interval_s: Tuple[float, float] = (3.0, 6.0)
    # WiFi
    radio: RadioConfig = field(default_factory=_default_radio)
    p0_5ghz_offset_db: float = -6.0
    scan_interval_s: float = 2.0
    scan_jitter_s: float = 0.15
    sweep_lag_s: Tuple[float, float] = (0.3, 1.2)
    cache_s: float = 10.0
    floor_height_m: float = 5.0

    def validate(self) -> None:
        """Raises ValueError naming the first invalid field."""
        def bad(name: str, why: str) -> None:
            raise ValueError(f"indoorloc: argument 'config.{name}': {why}")
        for name in ("width_m", "depth_m", "corridor_width_m", "corner_cut_m", "step_length_m",
                     "step_frequency_hz", "weinberg_k", "sample_rate_hz", "scan_interval_s", "cache_s",
                     "floor_height_m"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                bad(name, f"must be finite and > 0, got {v}")
        if self.ew_corridors < 1 or self.ns_corridors < 1:
            bad("ew_corridors", "need at least one corridor each way")
        lo, hi = self.shops_per_block
        if not 1 <= lo <= hi:
            bad("shops_per_block", f"need 1 <= lo <= hi, got {self.shops_per_block}")
        for n, extent in ((self.ns_corridors, self.width_m), (self.ew_corridors, self.depth_m)):
            block = extent / (n + 1) - self.corridor_width_m - 2 * self.corridor_jitter_m
            if block < 2.0:
                bad("corridor_width_m", f"blocks of {block:.1f} m between corridors: floor too small")
        for name in ("walk_duration_s", "stand_start_s", "stand_end_s", "pitch_deg", "waypoint_interval_s",
                     "sweep_lag_s"):
            a, b = getattr(self, name)
            if not (0 <= a <= b and math.isfinite(b)):
                bad(name, f"need 0 <= lo <= hi, got {(a, b)}")
        if self.walk_duration_s[0] < 5.0:
            bad("walk_duration_s", "walks shorter than 5 s have too few steps")
        if self.corner_cut_m > 0.45 * self.corridor_width_m + 1.0:
            bad("corner_cut_m", "rounded corners would leave the corridors")
        if not (0 < self.scan_jitter_s < 0.5 * self.scan_interval_s) or self.sweep_lag_s[1] >= self.scan_interval_s:
            bad("scan_jitter_s", "need 0 < jitter < interval / 2 and sweep lag < interval")
        self.radio.validate()


# ------------------------------------------------------------------------------------- layout


@dataclass
class IlcLayout:
    """The floor layout (metres, floor frame): outline, shops, corridor grid."""

    width_m: float
    depth_m: float
    shops: List[np.ndarray]        #: (4, 2) counter-clockwise rectangle rings
    corridor_x_m: np.ndarray       #: (ns,) centre lines of the north-south corridors
    corridor_y_m: np.ndarray       #: (ew,) centre lines of the east-west corridors
    corridor_width_m: float

    @property
    def outline(self) -> np.ndarray:
        return geo.rect_ring(0.0, 0.0, self.width_m, self.depth_m)

    def shop_edges(self) -> np.ndarray:
        """(E, 4) edges of every shop ring."""
        return np.vstack([geo.ring_edges(r) for r in self.shops])

    def is_walkable(self, points_m: np.ndarray) -> np.ndarray:
        """(N,) bool: inside the outline and inside no shop."""
        p = np.asarray(points_m, float).reshape(-1, 2)
        ok = geo.points_in_ring(p, self.outline)
        for r in self.shops:
            ok &= ~geo.points_in_ring(p, r)
        return ok

    def crossings(self) -> np.ndarray:
        """(ns * ew, 2) corridor crossings, index i * ew + j for corridor_x[i], corridor_y[j]."""
        return np.array([[x, y] for x in self.corridor_x_m for y in self.corridor_y_m])


def _cuts(a: float, b: float, n: int, rng: np.random.Generator) -> np.ndarray:
    w = 1.0 + rng.uniform(-0.25, 0.25, n)
    c = a + (b - a) * np.concatenate([[0.0], np.cumsum(w) / w.sum()])
    c[-1] = b
    return c


def make_layout(config: IlcSiteConfig, rng: np.random.Generator) -> IlcLayout:
    """Corridor grid and shops tiling the blocks (1-3 shops per block, split along its long side)."""
    W, D, cw = config.width_m, config.depth_m, config.corridor_width_m
    jit = config.corridor_jitter_m
    nx, ny = config.ns_corridors, config.ew_corridors
    xs = W * np.arange(1, nx + 1) / (nx + 1) + rng.uniform(-jit, jit, nx)
    ys = D * np.arange(1, ny + 1) / (ny + 1) + rng.uniform(-jit, jit, ny)
    bx = np.concatenate([[0.0], np.ravel(np.column_stack([xs - cw / 2, xs + cw / 2])), [W]]).reshape(-1, 2)
    by = np.concatenate([[0.0], np.ravel(np.column_stack([ys - cw / 2, ys + cw / 2])), [D]]).reshape(-1, 2)
    shops: List[np.ndarray] = []
    lo, hi = config.shops_per_block
    for x0, x1 in bx:
        for y0, y1 in by:
            n = int(rng.integers(lo, hi + 1))
            if x1 - x0 >= y1 - y0:
                c = _cuts(x0, x1, n, rng)
                shops += [geo.rect_ring(c[i], y0, c[i + 1], y1) for i in range(n)]
            else:
                c = _cuts(y0, y1, n, rng)
                shops += [geo.rect_ring(x0, c[i], x1, c[i + 1]) for i in range(n)]
    return IlcLayout(W, D, shops, xs, ys, cw)


def _geojson(layout: IlcLayout, floor_name: str, origin: Tuple[float, float], rng: np.random.Generator) -> dict:
    """The real files' structure: outline first (MultiPolygon with the floor's properties), then
    one Polygon per shop with id / name / category / point (web-mercator metres) properties."""
    def ring(xy: np.ndarray) -> List[List[float]]:
        ll = local_to_lonlat(np.vstack([xy, xy[:1]]), origin)
        return [[float(a), float(b)] for a, b in ll]

    def mercator(lon_lat: np.ndarray) -> List[float]:
        lon, lat = np.radians(lon_lat)
        return [6378137.0 * float(lon), 6378137.0 * float(np.log(np.tan(np.pi / 4 + lat / 2)))]

    centre = local_to_lonlat(np.array([[layout.width_m / 2, layout.depth_m / 2]]), origin)[0]
    features = [{"type": "Feature",
                 "properties": {"center": [float(centre[0]), float(centre[1])], "two_class": 210103, "style": 8,
                                "floor": floor_name, "poi_no": "1", "store_id": "", "name_chinese": ""},
                 "geometry": {"type": "MultiPolygon", "coordinates": [[ring(layout.outline)]]}}]
    for k, shop in enumerate(layout.shops):
        c = local_to_lonlat(shop.mean(axis=0)[None, :], origin)[0]
        features.append({"type": "Feature",
                         "properties": {"id": rng.bytes(12).hex(), "version": "2019-11-01T11:56:53.276Z",
                                        "name": f"Shop {k + 1}", "display": "", "category": [],
                                        "point": mercator(c), "points": []},
                         "geometry": {"type": "Polygon", "coordinates": [ring(shop)]}})
    return {"type": "FeatureCollection", "features": features}


# ---------------------------------------------------------------------------------------- walks


@dataclass
class IlcWalkTruth:
    """What one synthetic walk really did (walk clock: seconds since its first record)."""

    walk_id: str
    floor_name: str
    step_t_s: np.ndarray          #: (M,) time of each step (peak of the bounce)
    step_length_m: np.ndarray     #: (M,) true stride lengths
    yaw_offset_rad: float         #: floor-frame minus phone heading of this walk
    waypoint_t_s: np.ndarray      #: (W,)
    waypoint_xy_m: np.ndarray     #: (W, 2)
    t_s: np.ndarray               #: (N,) sensor times
    position_m: np.ndarray        #: (N, 2) true position at the sensor times
    lines: List[str] = field(repr=False, default_factory=list)  #: the file's lines

    @property
    def n_steps(self) -> int:
        return int(self.step_t_s.shape[0])


@dataclass
class IlcSite:
    """A synthetic site in memory: layout, radio, walks with their truth. :meth:`write` puts it on disk."""

    config: IlcSiteConfig
    seed: int
    layout: IlcLayout
    floor_names: List[str]
    floor_numbers: List[int]
    radio: RadioModel
    bssids: List[str]
    ssids: List[str]
    frequencies_mhz: np.ndarray
    walks: Dict[str, List[IlcWalkTruth]]
    geojson: Dict[str, dict]
    yaw_offset_rad: float          #: site mean of the floor-minus-phone heading offset

    @property
    def weinberg_k(self) -> float:
        return float(self.config.weinberg_k)

    def write(self, root: PathLike) -> Path:
        """Writes ``root/<floor>/{floor_info.json, geojson_map.json, path_data_files/*.txt}``; returns root."""
        root = Path(root)
        for name in self.floor_names:
            d = root / name
            (d / "path_data_files").mkdir(parents=True, exist_ok=True)
            (d / "floor_info.json").write_text(json.dumps(
                {"map_info": {"height": self.layout.depth_m, "width": self.layout.width_m}}), encoding="utf-8")
            (d / "geojson_map.json").write_text(json.dumps(self.geojson[name]), encoding="utf-8")
            for w in self.walks[name]:
                with open(d / "path_data_files" / f"{w.walk_id}.txt", "w", encoding="utf-8", newline="") as f:
                    f.write("\n".join(w.lines) + "\n")
        return root


def floor_number(name: str) -> int:
    """Floor number of a floor folder name as ``indoorloc fusion evaluate`` reads it: its digits,
    negative for a name starting with B (``"F3"`` -> 3, ``"B1"`` -> -1, no digit -> 0)."""
    n = int("".join(ch for ch in name if ch.isdigit()) or 0)
    return -n if name.upper().startswith("B") else n


def _route(layout: IlcLayout, length_m: float, rng: np.random.Generator) -> np.ndarray:
    """Polyline (R, 2) along the corridor centre lines, at least length_m long, turning at random
    at crossings and never reversing."""
    nx, ny = layout.corridor_x_m.size, layout.corridor_y_m.size
    nodes = layout.crossings()

    def neighbours(i: int) -> List[int]:
        a, b = divmod(i, ny)
        out = []
        if a > 0:
            out.append(i - ny)
        if a < nx - 1:
            out.append(i + ny)
        if b > 0:
            out.append(i - 1)
        if b < ny - 1:
            out.append(i + 1)
        return out

    edges = [(i, j) for i in range(nodes.shape[0]) for j in neighbours(i) if j > i]
    if not edges:
        raise ValueError("indoorloc: argument 'config': the corridor grid needs at least two crossings")
    a, b = edges[int(rng.integers(len(edges)))]
    if rng.random() < 0.5:
        a, b = b, a
    u = rng.uniform(0.2, 0.8)
    pts = [nodes[a] + u * (nodes[b] - nodes[a]), nodes[b]]
    total = float(np.linalg.norm(pts[1] - pts[0]))
    prev, cur = a, b
    while total < length_m:
        options = [j for j in neighbours(cur) if j != prev] or [prev]
        nxt = options[int(rng.integers(len(options)))]
        pts.append(nodes[nxt])
        total += float(np.linalg.norm(nodes[nxt] - nodes[cur]))
        prev, cur = cur, nxt
    return np.array(pts)


def _butterworth_gain(f_hz: float, cutoff_hz: float = 3.0, order: int = 4) -> float:
    # |H| of the analog prototype; the bilinear design at 50 Hz differs by < 0.2 % at 1.4-2.2 Hz.
    return 1.0 / math.sqrt(1.0 + (f_hz / cutoff_hz) ** (2 * order))


def _slow_error(t: np.ndarray, sd: float, rng: np.random.Generator) -> np.ndarray:
    """Zero-mean slowly varying signal (sum of 4 sinusoids, periods 5-30 s) with standard deviation ~sd."""
    periods = rng.uniform(5.0, 30.0, 4)
    phases = rng.uniform(0.0, 2 * np.pi, 4)
    return sd * np.sqrt(2.0 / 4) * np.sum(np.sin(2 * np.pi * t[:, None] / periods + phases), axis=1)


def _smooth(x: np.ndarray, n: int) -> np.ndarray:
    if n <= 1:
        return x
    pad = np.concatenate([np.full(n, x[0]), x, np.full(n, x[-1])])
    c = np.convolve(pad, np.ones(n) / n, mode="same")
    return c[n:-n]


_SENSOR_HEADER = [
    "#\ttype:1\tname:Synthetic Accelerometer\tversion:1\tvendor:indoorloc\tresolution:0.0023956299\tpower:0.18"
    "\tmaximumRange:39.22661",
    "#\ttype:4\tname:Synthetic Gyroscope\tversion:1\tvendor:indoorloc\tresolution:0.0010681152\tpower:0.9"
    "\tmaximumRange:34.906586",
    "#\ttype:2\tname:Synthetic Magnetometer\tversion:1\tvendor:indoorloc\tresolution:0.5996704\tpower:2.4"
    "\tmaximumRange:4911.9995",
]


def _walk(site: "IlcSite", floor_index: int, t0_unix_ms: int, site_id: str, floor_id: str,
          rng: np.random.Generator) -> IlcWalkTruth:
    """One walk on floor ``floor_index``: its truth and the lines of its file (module docstring)."""
    cfg = site.config
    name = site.floor_names[floor_index]
    number = site.floor_numbers[floor_index]
    rate = cfg.sample_rate_hz
    # Gait: steps while walking, standing before and after.
    duration = rng.uniform(*cfg.walk_duration_s)
    stand0 = rng.uniform(*cfg.stand_start_s)
    stand1 = rng.uniform(*cfg.stand_end_s)
    cadence = float(np.clip(cfg.step_frequency_hz + cfg.step_frequency_walker_sd_hz * rng.standard_normal(),
                            0.8 * cfg.step_frequency_hz, 1.2 * cfg.step_frequency_hz))
    stride = cfg.step_length_m + float(np.clip(cfg.step_length_walker_sd_m * rng.standard_normal(), -0.08, 0.08))
    periods, t_end = [], stand0
    while True:
        p = (1.0 + 0.03 * rng.standard_normal()) / cadence
        if t_end + p > duration - stand1:
            break
        periods.append(p)
        t_end += p
    periods = np.array(periods)
    m = periods.size
    step_t = stand0 + np.cumsum(periods)
    step_len = stride * (1.0 + cfg.step_length_sd_fraction * rng.standard_normal(m))
    duration = float(step_t[-1] + stand1)
    # Route and motion along it: arc length linear within each step, flat while standing.
    # Rounding shortens each corner by about 0.4 corner_cut_m: ask for a margin, longer if needed.
    margin = 4.0 * cfg.corner_cut_m + 2.0
    while True:
        route = _route(site.layout, float(step_len.sum()) + margin, rng)
        path = _round_corners(route, np.full(route.shape[0], cfg.corner_cut_m))
        arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))]
        if arc[-1] >= step_len.sum():
            break
        margin *= 2.0
    knot_t = np.r_[0.0, stand0, step_t, duration]
    knot_s = np.r_[0.0, 0.0, np.cumsum(step_len), step_len.sum()]
    traj = Trajectory(path_m=path, path_arc_m=arc, knot_time_s=knot_t, knot_arc_m=knot_s)
    # Sensor clock: 50 Hz from about 130 ms after the first waypoint, whole milliseconds.
    first_ms = int(rng.integers(110, 150))
    n = int(np.floor((duration * 1000.0 - first_ms) / (1000.0 / rate))) + 1
    t_ms = first_ms + np.round(np.arange(n) * 1000.0 / rate).astype(np.int64)
    # Android's 19-21 ms jitter: +-1 ms on some odd samples, so no two neighbours move.
    t_ms[1:-1] += rng.integers(-1, 2, n - 2) * ((rng.random(n - 2) < 0.1) & (np.arange(1, n - 1) % 2 == 1))
    t = t_ms / 1000.0
    pos = traj.position_at(t)
    # Walking direction, smoothed: people turn the phone over a fraction of a second.
    heading = _smooth(np.unwrap(traj.heading_at(t)), max(1, int(round(0.4 * rate))))
    walk_offset = site.yaw_offset_rad + math.radians(cfg.yaw_offset_walk_sd_deg) * rng.standard_normal()
    phone_heading = heading - walk_offset
    # Gait phase (2 pi k at step k) and bounce amplitude from Weinberg's rule with the site's K.
    gain = _butterworth_gain(cadence)
    amp_k = (step_len / cfg.weinberg_k) ** 4 / (2.0 * gain)
    ph_t = np.r_[step_t[0] - periods[0], step_t, step_t[-1] + periods[-1]]
    phase = np.interp(t, ph_t, 2 * np.pi * np.arange(-1, m + 1))
    amp = np.interp(t, ph_t, np.r_[0.0, amp_k, 0.0], left=0.0, right=0.0)
    a_up = amp * np.cos(phase)
    a_fwd = 0.35 * amp * np.sin(phase)
    a_lat = 0.25 * amp * np.sin(0.5 * phase)
    # Orientation: device +y along the phone heading, pitched up, small bob and sway.
    pitch = math.radians(rng.uniform(*cfg.pitch_deg)) + math.radians(1.5) * (amp > 0) * np.sin(phase)
    roll = math.radians(rng.normal(0.0, 2.0)) + math.radians(1.0) * (amp > 0) * np.sin(0.5 * phase)
    sway = math.radians(1.5) * (amp > 0) * np.sin(0.5 * phase + 0.3)
    r_true = Rotation.from_euler("ZXY", np.column_stack([phone_heading + sway - np.pi / 2, pitch, roll]))
    h = heading
    f_enu = np.column_stack([a_fwd * np.cos(h) - a_lat * np.sin(h), a_fwd * np.sin(h) + a_lat * np.cos(h),
                             a_up + GRAVITY_MPS2])
    acc = r_true.inv().apply(f_enu) + cfg.accel_noise_sd_mps2 * rng.standard_normal((n, 3))
    # Gyroscope: body rate of the true orientation (central differences), noise, constant bias.
    gyro = np.empty((n, 3))
    gyro[1:-1] = (r_true[:-2].inv() * r_true[2:]).as_rotvec() / (t[2:] - t[:-2])[:, None]
    gyro[0], gyro[-1] = gyro[1], gyro[-2]
    gyro += cfg.gyro_bias_sd_radps * rng.standard_normal(3) + cfg.gyro_noise_sd_radps * rng.standard_normal((n, 3))
    # Rotation vector: the true orientation with a slow heading error about the vertical.
    err = _slow_error(t, math.radians(cfg.heading_error_sd_deg), rng)
    r_rv = Rotation.from_rotvec(np.column_stack([np.zeros(n), np.zeros(n), err])) * r_true
    quat = r_rv.as_quat()                      # x, y, z, w
    quat[quat[:, 3] < 0] *= -1.0               # Android writes the w >= 0 hemisphere (w not stored)
    mag = (r_rv.inv().apply(np.asarray(cfg.magnetic_field_enu_ut, float))
           + cfg.mag_noise_sd_ut * rng.standard_normal((n, 3)))
    # Waypoints: start, corners of the route, last step, and fill-ins 3-6 s apart.
    wp = [0.0, float(step_t[-1])]
    corner_s = [float(arc[np.argmin(np.linalg.norm(path - c, axis=1))]) for c in route[1:-1]]
    corner_t = np.interp(corner_s, knot_s[1:-1], knot_t[1:-1], left=np.nan, right=np.nan)
    wp += [float(x) for x in corner_t if np.isfinite(x) and stand0 + 1.5 < x < step_t[-1] - 1.5]
    wp = sorted(wp)
    filled = [wp[0]]
    lo, hi = cfg.waypoint_interval_s
    for nxt in wp[1:]:
        while nxt - filled[-1] > hi:
            gap = rng.uniform(lo, hi)
            filled.append(filled[-1] + (gap if nxt - filled[-1] - gap >= lo else 0.5 * (nxt - filled[-1])))
        if nxt - filled[-1] >= 1.5 or nxt == wp[-1]:
            filled.append(nxt)
    wp_t = np.round(np.array(filled) * 1000.0) / 1000.0
    wp_xy = np.round(traj.position_at(wp_t), 5)
    # WiFi: sweeps before each scan; the cache repeats readings missed by a sweep for cache_s.
    scans = np.arange(rng.uniform(0.8, 2.0), duration, cfg.scan_interval_s)
    scans = np.maximum(scans + cfg.scan_jitter_s * np.clip(rng.standard_normal(scans.size), -2, 2), 0.05)
    scans = scans[scans < duration]
    sweeps = scans - rng.uniform(*cfg.sweep_lag_s, scans.size)
    pre = -np.sort(rng.uniform(0.5, cfg.cache_s - 1.0, int(rng.integers(1, 3))))[::-1]
    sweep_t = np.r_[pre, sweeps]
    k = len(site.bssids)
    where = traj.position_at(np.maximum(sweep_t, 0.0))
    mean = site.radio.mean_rss_pairs(np.repeat(where, k, axis=0), number, np.tile(np.arange(k), sweep_t.size))
    rss = site.radio.measure(mean, rng).reshape(sweep_t.size, k)
    # Each BSSID's own time within the sweep (channels are swept one after another).
    seen = sweep_t[:, None] + rng.uniform(0.0, 0.25, (sweep_t.size, k))
    seen_ms = np.round(seen * 1000.0).astype(np.int64)
    scan_ms = np.round(scans * 1000.0).astype(np.int64)
    # Records as (time [ms since t0], order within a time stamp, line with unix ms): sensors share
    # their time stamps (as in the real files), then WiFi, then waypoints.
    keys: List[int] = []
    text: List[str] = []

    def put(rel_ms: int, order: int, line: str) -> None:
        keys.append(rel_ms * 64 + order)
        text.append(line)

    cache_rss = np.full(k, np.nan)
    cache_ms = np.zeros(k, np.int64)
    for j in range(pre.size):
        heard = np.isfinite(rss[j])
        cache_rss[heard], cache_ms[heard] = rss[j, heard], seen_ms[j, heard]
    for i, s_ms in enumerate(scan_ms.tolist()):
        j = pre.size + i
        heard = np.isfinite(rss[j])
        cache_rss[heard], cache_ms[heard] = rss[j, heard], seen_ms[j, heard]
        listed = np.isfinite(cache_rss) & (s_ms - cache_ms <= cfg.cache_s * 1000.0) & (cache_ms < s_ms)
        idx = np.flatnonzero(listed)
        idx = idx[np.argsort(-cache_rss[idx], kind="stable")]  # strongest first, as the phone lists them
        for b in idx.tolist():
            put(s_ms, 20, f"{t0_unix_ms + s_ms}\tTYPE_WIFI\t{site.ssids[b]}\t{site.bssids[b]}\t{int(cache_rss[b])}"
                          f"\t{int(site.frequencies_mhz[b])}\t{t0_unix_ms + int(cache_ms[b])}")
    abs_ms = (t0_unix_ms + t_ms).tolist()
    for order, (type_name, values) in enumerate((("TYPE_ACCELEROMETER", acc), ("TYPE_MAGNETIC_FIELD", mag),
                                                  ("TYPE_GYROSCOPE", gyro), ("TYPE_ROTATION_VECTOR", quat[:, :3]))):
        fmt = "%d\t" + type_name + "\t%.7g\t%.7g\t%.7g\t3"
        keys.extend((t_ms * 64 + order).tolist())
        text.extend(fmt % (ti, a, b, c) for ti, (a, b, c) in zip(abs_ms, values.tolist()))
    for tw, (x, y) in zip(wp_t.tolist(), wp_xy.tolist()):
        tw_ms = int(round(tw * 1000.0))
        put(tw_ms, 30, f"{t0_unix_ms + tw_ms}\tTYPE_WAYPOINT\t{x:.5f}\t{y:.5f}")
    acc_ms = int(t_ms[0]) - 40
    put(acc_ms, 40, f"{t0_unix_ms + acc_ms}\tTYPE_SENSOR_MAGNETIC_FIELD_ACCURACY_CHANGED\t3")
    order = np.argsort(np.array(keys, dtype=np.int64), kind="stable")
    walk_id = rng.bytes(12).hex()
    end_ms = max(int(t_ms[-1]), int(round(wp_t[-1] * 1000.0)))
    lines = [f"#\tstartTime:{t0_unix_ms - int(rng.integers(6, 24))}",
             f"#\tSiteID:{site_id}\tSiteName:indoorloc synthetic mall {site.seed}\tFloorId:{floor_id}"
             f"\tFloorName:{name}",
             "#\tBrand:indoorloc\tModel:synthetic\tAndroidName:8.1.0\tAPILevel:27\t",
             *_SENSOR_HEADER,
             "#\tVersionName:indoorloc.simulate.ilc_site\tVersionCode:1\t"]
    lines += [text[i] for i in order.tolist()]
    lines.append(f"#\tendTime:{t0_unix_ms + end_ms + int(rng.integers(20, 90))}")
    return IlcWalkTruth(walk_id=walk_id, floor_name=name, step_t_s=step_t, step_length_m=step_len,
                        yaw_offset_rad=float(walk_offset), waypoint_t_s=wp_t, waypoint_xy_m=wp_xy, t_s=t,
                        position_m=pos, lines=lines)


def make_ilc_site(*, floors: Sequence[str] = ("F1",), walks_per_floor: int = 8, seed: int = 0,
                  config: Optional[IlcSiteConfig] = None) -> IlcSite:
    """A synthetic ILC 2020 site in memory, with its truth (see the module docstring).

    Parameters
    ----------
    floors : sequence of str
        Floor folder names; the floor number of each is read as ``indoorloc fusion evaluate``
        does (:func:`floor_number`: ``"F1"`` -> 1, ``"B1"`` -> -1). Every floor has the same
        layout and its own access points.
    walks_per_floor : int
        Walk files per floor (>= 1).
    seed : int
        Everything is deterministic in the seed.
    config : IlcSiteConfig, optional
        Layout, gait, sensor and radio parameters (defaults documented there).

    Raises
    ------
    ValueError
        On an invalid configuration, no floor, duplicate floor names or numbers, or
        ``walks_per_floor`` < 1.
    """
    cfg = config or IlcSiteConfig()
    cfg.validate()
    floors = [str(f) for f in floors]
    if not floors or len(set(floors)) != len(floors):
        raise ValueError(f"indoorloc: argument 'floors': need distinct floor names, got {floors}")
    numbers = [floor_number(f) for f in floors]
    if len(set(numbers)) != len(numbers):
        raise ValueError(f"indoorloc: argument 'floors': names {floors} give repeated floor numbers {numbers}")
    if int(walks_per_floor) < 1:
        raise ValueError(f"indoorloc: argument 'walks_per_floor': must be >= 1, got {walks_per_floor}")
    seed = int(seed)

    def stream(*k: int) -> np.random.Generator:
        return np.random.default_rng([seed, _DOMAIN, *k])

    layout = make_layout(cfg, stream(_LAYOUT_STREAM))
    # Access points: corridors and shops alike, 0.5 m inside; each has a 2.4 and a 5 GHz BSSID.
    rng = stream(_RADIO_STREAM)
    n_ap = cfg.radio.aps_per_floor
    ap_xy, ap_floor = [], []
    for num in numbers:
        for _ in range(n_ap):
            ap_xy.append(rng.uniform([0.5, 0.5], [layout.width_m - 0.5, layout.depth_m - 0.5]))
            ap_floor.append(num)
    ap_xy = np.repeat(np.array(ap_xy), 2, axis=0)
    ap_floor = np.repeat(np.array(ap_floor), 2)
    in_shop = ~layout.is_walkable(ap_xy)
    radio = make_radio_model(cfg.radio, ap_xy, ap_floor, in_shop, np.array(sorted(numbers)), cfg.floor_height_m,
                             np.zeros((0, 4)), layout.shop_edges(), rng)
    radio.ap_p0_dbm[1::2] += cfg.p0_5ghz_offset_db
    bssids, ssids, freqs = [], [], []
    names = ["MALL-FREE-WIFI", "MALL-STAFF", "", "CMCC-WEB"]
    for a in range(ap_xy.shape[0] // 2):
        mac = rng.bytes(5).hex()
        prefix = ":".join(mac[i:i + 2] for i in range(0, 10, 2))
        ssid = names[int(rng.integers(len(names)))] if rng.random() < 0.7 else f"shop-{a:03d}"
        bssids += [f"{prefix}:00", f"{prefix}:10"]
        ssids += [ssid, ssid]
        freqs += [int(rng.choice([2412, 2437, 2462])), int(rng.choice([5180, 5200, 5300, 5745]))]
    site_rng = stream(_SITE_STREAM)
    yaw = math.radians(cfg.yaw_offset_deg)
    site_id = site_rng.bytes(12).hex()
    site = IlcSite(config=cfg, seed=seed, layout=layout, floor_names=floors, floor_numbers=numbers, radio=radio,
                   bssids=bssids, ssids=ssids, frequencies_mhz=np.array(freqs), walks={}, geojson={},
                   yaw_offset_rad=yaw)
    t0 = 1_574_142_000_000 + int(site_rng.integers(0, 10**9))
    for fi, name in enumerate(floors):
        floor_id = site_rng.bytes(12).hex()
        site.geojson[name] = _geojson(layout, name, cfg.origin_lon_lat, stream(_LAYOUT_STREAM, fi + 1))
        walks = []
        for wi in range(int(walks_per_floor)):
            start = t0 + (fi * int(walks_per_floor) + wi) * 120_000
            walks.append(_walk(site, fi, start, site_id, floor_id, stream(_WALK_STREAM, fi, wi)))
        site.walks[name] = walks
    return site


def write_ilc_site(root: PathLike, *, floors: Sequence[str] = ("F1",), walks_per_floor: int = 8, seed: int = 0,
                   config: Optional[IlcSiteConfig] = None) -> Path:
    """Writes a synthetic site in the ILC 2020 layout under ``root`` and returns ``root``.

    ``root/<floor>/floor_info.json`` (width and height [m]), ``geojson_map.json`` (outline and
    shops in WGS84 lon/lat; the floor frame's origin is the outline's south-west corner,
    ``config.origin_lon_lat``) and ``path_data_files/<walk id>.txt`` (50 Hz accelerometer,
    gyroscope, magnetometer and rotation vector, WiFi scans every ~2 s, waypoints in floor-frame
    metres). Parameters as for :func:`make_ilc_site`, which gives the truth as well.
    """
    return make_ilc_site(floors=floors, walks_per_floor=walks_per_floor, seed=seed, config=config).write(root)


__all__ = [
    "IlcLayout",
    "IlcSite",
    "IlcSiteConfig",
    "IlcWalkTruth",
    "floor_number",
    "make_ilc_site",
    "make_layout",
    "write_ilc_site",
]
