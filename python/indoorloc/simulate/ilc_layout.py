"""The floor of the synthetic ILC 2020 site: a mall of corridors crossing the floor and shops tiling
the blocks between them (:func:`make_layout`), its GeoJSON in the real files' structure, and the
random routes along the corridor centre lines that walks follow (model:
:mod:`indoorloc.simulate.ilc_site`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import List, Tuple

import numpy as np

from indoorloc.io.floor_plan import local_to_lonlat
from indoorloc.simulate import _geometry as geo
from indoorloc.simulate.ilc_site_config import IlcSiteConfig


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
