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

The parts: :mod:`~indoorloc.simulate.ilc_site_config` (the parameters),
:mod:`~indoorloc.simulate.ilc_layout` (floor, GeoJSON, routes), :mod:`~indoorloc.simulate.ilc_walk`
(one walk's sensors, WiFi and file); every name stays importable from here.

Randomness: ``numpy.random.default_rng([seed, 0x1C2, stream, ...])``; streams 0 layout, 1 radio,
2 site-wide calibration, 3 walks (per floor and walk). Writing one floor of 8 walks of 20-40 s
takes about 0.4 s.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Union

import numpy as np

from indoorloc.io.survey_layout import floor_number  # re-exported: the level fusion evaluate reads
from indoorloc.simulate.ilc_layout import IlcLayout, _geojson, make_layout
from indoorloc.simulate.ilc_site_config import IlcSiteConfig
from indoorloc.simulate.ilc_walk import GRAVITY_MPS2, IlcWalkTruth, make_walk
from indoorloc.simulate.radio import RadioModel, make_radio_model

PathLike = Union[str, Path]

_DOMAIN = 0x1C2
_LAYOUT_STREAM, _RADIO_STREAM, _SITE_STREAM, _WALK_STREAM = 0, 1, 2, 3


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
            walks.append(make_walk(site, fi, start, site_id, floor_id, stream(_WALK_STREAM, fi, wi)))
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
    "GRAVITY_MPS2",
    "IlcLayout",
    "IlcSite",
    "IlcSiteConfig",
    "IlcWalkTruth",
    "floor_number",
    "make_ilc_site",
    "make_layout",
    "write_ilc_site",
]
