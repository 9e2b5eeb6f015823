"""Vectorised 2-D geometry for the synthetic building (numpy only, no Python loop per point).

Segments are rows (x0, y0, x1, y1) [m]. Two predicates are used:

- *proper crossing* (radio: how many walls does the AP -> receiver segment pass through): the
  open segments intersect in one point interior to both, i.e. the ends of each lie strictly on
  opposite sides of the other: o(a, b, c) o(a, b, d) < 0 and o(c, d, a) o(c, d, b) < 0 with
  o(p, q, r) = (q - p) x (r - p). Touching a wall's end (a door jamb) does not count; that
  event has probability zero for continuous positions.
- *touching* (route checks, the FloorPlan semantics of fusion/floor_plan.h): the closed
  segments share at least one point (collinear overlaps included).

Work is chunked so that at most about ``_CHUNK_ELEMENTS`` segment pairs are held at once.
"""

from __future__ import annotations

import numpy as np

_CHUNK_ELEMENTS = 1 << 21


def _as_segments(segments: np.ndarray, name: str) -> np.ndarray:
    s = np.asarray(segments, dtype=float)
    if s.ndim != 2 or s.shape[1] != 4:
        raise ValueError(f"indoorloc: argument '{name}': expected shape (N, 4), got {s.shape}")
    return s


def _orient(px, py, qx, qy, rx, ry):
    """(q - p) x (r - p), broadcast."""
    return (qx - px) * (ry - py) - (qy - py) * (rx - px)


def _pair_blocks(n: int, m: int):
    rows = max(1, _CHUNK_ELEMENTS // max(m, 1))
    for i in range(0, n, rows):
        yield slice(i, min(n, i + rows))


def _block_orientations(a, b, blk, cx, cy, dx, dy):
    """Segment ends of a block of queries (columns) and the four orientations against every edge:
    o1, o2 of the edge ends against the query segment, o3, o4 of the query ends against the edge."""
    ax, ay = a[blk, 0:1], a[blk, 1:2]
    bx, by = b[blk, 0:1], b[blk, 1:2]
    return (ax, ay, bx, by), (_orient(ax, ay, bx, by, cx, cy), _orient(ax, ay, bx, by, dx, dy),
                              _orient(cx, cy, dx, dy, ax, ay), _orient(cx, cy, dx, dy, bx, by))


def crossing_counts(starts_m: np.ndarray, ends_m: np.ndarray, edges_m: np.ndarray) -> np.ndarray:
    """Number of edges each segment start -> end crosses properly.

    starts_m, ends_m (N, 2) [m]; edges_m (E, 4) rows (x0, y0, x1, y1) [m]. Returns (N,) int.
    """
    a = np.asarray(starts_m, float).reshape(-1, 2)
    b = np.asarray(ends_m, float).reshape(-1, 2)
    e = _as_segments(edges_m, "edges_m")
    out = np.zeros(a.shape[0], dtype=np.int64)
    if e.shape[0] == 0 or a.shape[0] == 0:
        return out
    cx, cy, dx, dy = (e[None, :, k] for k in range(4))
    for blk in _pair_blocks(a.shape[0], e.shape[0]):
        (ax, ay, bx, by), (o1, o2, o3, o4) = _block_orientations(a, b, blk, cx, cy, dx, dy)
        out[blk] = np.count_nonzero((o1 * o2 < 0.0) & (o3 * o4 < 0.0), axis=1)
    return out


def touches_any(starts_m: np.ndarray, ends_m: np.ndarray, edges_m: np.ndarray) -> np.ndarray:
    """True where the closed segment start -> end intersects or touches any edge. (N,) bool."""
    a = np.asarray(starts_m, float).reshape(-1, 2)
    b = np.asarray(ends_m, float).reshape(-1, 2)
    e = _as_segments(edges_m, "edges_m")
    out = np.zeros(a.shape[0], dtype=bool)
    if e.shape[0] == 0 or a.shape[0] == 0:
        return out
    cx, cy, dx, dy = (e[None, :, k] for k in range(4))
    for blk in _pair_blocks(a.shape[0], e.shape[0]):
        (ax, ay, bx, by), (o1, o2, o3, o4) = _block_orientations(a, b, blk, cx, cy, dx, dy)
        general = (o1 * o2 <= 0.0) & (o3 * o4 <= 0.0)
        collinear = (o1 == 0.0) & (o2 == 0.0)
        boxes = ((np.minimum(ax, bx) <= np.maximum(cx, dx)) & (np.minimum(cx, dx) <= np.maximum(ax, bx))
                 & (np.minimum(ay, by) <= np.maximum(cy, dy)) & (np.minimum(cy, dy) <= np.maximum(ay, by)))
        hit = np.where(collinear, boxes, general & boxes)
        out[blk] = hit.any(axis=1)
    return out


def points_in_ring(points_m: np.ndarray, ring_m: np.ndarray) -> np.ndarray:
    """Crossing-number test: True where a point lies inside the closed ring (M, 2). (N,) bool."""
    p = np.asarray(points_m, float).reshape(-1, 2)
    r = np.asarray(ring_m, float)
    x0, y0 = r[:, 0][None, :], r[:, 1][None, :]
    x1, y1 = np.roll(r[:, 0], -1)[None, :], np.roll(r[:, 1], -1)[None, :]
    inside = np.zeros(p.shape[0], dtype=bool)
    for blk in _pair_blocks(p.shape[0], r.shape[0]):
        px, py = p[blk, 0:1], p[blk, 1:2]
        straddles = (y0 > py) != (y1 > py)
        with np.errstate(divide="ignore", invalid="ignore"):
            x_cross = x0 + (py - y0) * (x1 - x0) / (y1 - y0)
        inside[blk] = (np.count_nonzero(straddles & (px < x_cross), axis=1) % 2) == 1
    return inside


def distance_to_segments(points_m: np.ndarray, edges_m: np.ndarray) -> np.ndarray:
    """Euclidean distance [m] from each point (N, 2) to the nearest edge (E, 4). (N,)."""
    p = np.asarray(points_m, float).reshape(-1, 2)
    e = _as_segments(edges_m, "edges_m")
    out = np.full(p.shape[0], np.inf)
    if e.shape[0] == 0:
        return out
    ax, ay = e[None, :, 0], e[None, :, 1]
    dx, dy = e[None, :, 2] - e[None, :, 0], e[None, :, 3] - e[None, :, 1]
    len2 = np.maximum(dx * dx + dy * dy, 1e-300)
    for blk in _pair_blocks(p.shape[0], e.shape[0]):
        px, py = p[blk, 0:1], p[blk, 1:2]
        t = np.clip(((px - ax) * dx + (py - ay) * dy) / len2, 0.0, 1.0)
        out[blk] = np.sqrt(np.min((ax + t * dx - px) ** 2 + (ay + t * dy - py) ** 2, axis=1))
    return out


def segment_point_distance(starts_m: np.ndarray, ends_m: np.ndarray, point_m: np.ndarray) -> np.ndarray:
    """Distance [m] from one point (2,) to each segment start -> end (N, 2). (N,)."""
    a = np.asarray(starts_m, float).reshape(-1, 2)
    d = np.asarray(ends_m, float).reshape(-1, 2) - a
    q = np.asarray(point_m, float).reshape(2)
    len2 = np.maximum(np.sum(d * d, axis=1), 1e-300)
    t = np.clip(np.sum((q - a) * d, axis=1) / len2, 0.0, 1.0)
    return np.linalg.norm(a + t[:, None] * d - q, axis=1)


def ring_edges(ring_m: np.ndarray) -> np.ndarray:
    """Edges (M, 4) of a closed ring (M, 2) given without its repeated closing vertex."""
    r = np.asarray(ring_m, float)
    return np.hstack([r, np.roll(r, -1, axis=0)])


def rect_ring(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """Counter-clockwise ring (4, 2) of an axis-aligned rectangle."""
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)
