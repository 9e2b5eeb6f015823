"""The peers of benchmarks/bench_fusion.py: the fusion tracker's step and WiFi update written in
numpy + shapely 2 (walls) and numpy + scipy (WiFi interpolation over qhull's Delaunay).

- :class:`ShapelyWalls`: the wall test of ``FloorPlan.crosses_wall`` with shapely (STRtree or a
  prepared MultiLineString).
- :class:`NumpyTracker`: the C++ tracker's step and WiFi update vectorised in numpy (one floor).
- :class:`ScipyInterpolator`: linear interpolation of a signal map's means and variances.

Peers of the benchmark only: never imported by the library; shapely and scipy come from the
``bench`` extra.
"""

from __future__ import annotations

import numpy as np

from indoorloc import fusion

# --------------------------------------------------------------------------- peer: motion + walls

class ShapelyWalls:
    """The wall test of FloorPlan.CrossesWall with shapely 2: a step crosses a wall when its
    segment intersects (or touches) any wall edge. method "strtree": STRtree over the edges as
    LineStrings, tree.query(steps, predicate="intersects"); "prepared": shapely.intersects
    against one prepared MultiLineString of all edges."""

    def __init__(self, edges_m: np.ndarray, method: str = "strtree"):
        import shapely

        self._shapely = shapely
        self.method = method
        lines = shapely.linestrings(np.asarray(edges_m, float).reshape(-1, 2, 2))
        if method == "strtree":
            self._tree = shapely.STRtree(lines)
        elif method == "prepared":
            self._multi = shapely.multilinestrings(lines)
            shapely.prepare(self._multi)
        else:
            raise ValueError(f"unknown method {method!r}")

    def crosses(self, segments_m: np.ndarray) -> np.ndarray:
        """segments (Q, 4) rows (x0, y0, x1, y1) [m] -> (Q,) bool."""
        segs = self._shapely.linestrings(np.ascontiguousarray(segments_m, dtype=float).reshape(-1, 2, 2))
        if self.method == "prepared":
            return self._shapely.intersects(self._multi, segs)
        hit = np.zeros(len(segments_m), dtype=bool)
        hit[self._tree.query(segs, predicate="intersects")[0]] = True
        return hit


class NumpyTracker:
    """The C++ tracker's step and WiFi update, vectorised in numpy (one floor, walls dropped,
    systematic resampling at ESS < N/2). The same model as step_motion.h and wifi_likelihood.h;
    its own random numbers (numpy's PCG64), so agreement is statistical for steps."""

    def __init__(self, states: np.ndarray, options: fusion.TrackerOptions, walls: ShapelyWalls | None = None,
                 *, seed: int):
        self.o = options
        self.walls = walls
        self.rng = np.random.default_rng(seed)
        self.set_particles(states)

    def set_particles(self, states: np.ndarray) -> None:
        s = np.asarray(states, float)
        self.x, self.y = s[:, 0].copy(), s[:, 1].copy()
        self.offset, self.scale = s[:, 2].copy(), s[:, 3].copy()
        self.n = len(s)
        self.log_w = np.full(self.n, -np.log(self.n))

    def step(self, displacement_m: np.ndarray, covariance_m2: np.ndarray) -> dict:
        o, n, rng = self.o, self.n, self.rng
        # Motion (step_motion.h): offset random walk, scale random walk clamped, correlated noise.
        offset = self.offset + o.heading_offset_walk_rad * rng.standard_normal(n)
        offset = np.where(offset > np.pi, offset - 2 * np.pi, np.where(offset <= -np.pi, offset + 2 * np.pi, offset))
        scale = np.clip(self.scale + o.scale_walk * rng.standard_normal(n), o.min_scale, o.max_scale)
        chol = np.linalg.cholesky(np.asarray(covariance_m2, float) + o.position_noise_m ** 2 * np.eye(2))
        e = rng.standard_normal((2, n))
        dx = displacement_m[0] + chol[0, 0] * e[0]
        dy = displacement_m[1] + chol[1, 0] * e[0] + chol[1, 1] * e[1]
        c, sn = np.cos(offset), np.sin(offset)
        qx = self.x + scale * (c * dx - sn * dy)
        qy = self.y + scale * (sn * dx + c * dy)
        self.offset, self.scale = offset, scale
        # Walls: a blocked particle is dropped (weight 0) and stays where it was.
        if self.walls is not None:
            blocked = self.walls.crosses(np.stack([self.x, self.y, qx, qy], axis=1))
        else:
            blocked = np.zeros(n, dtype=bool)
        blocked_fraction = min(1.0, float(np.exp(self.log_w[blocked]).sum()))
        if blocked.all():  # the C++ tracker ignores such a step (never happens here)
            return {"blocked_fraction": 1.0, "resampled": False}
        keep = ~blocked
        self.x = np.where(keep, qx, self.x)
        self.y = np.where(keep, qy, self.y)
        old = self.log_w
        self.log_w = np.where(keep, old, -np.inf)
        out = self._finish()
        out["blocked_fraction"] = blocked_fraction
        return out

    def wifi_log_likelihood(self, interp, observation_rss: np.ndarray) -> np.ndarray:
        """Tempered capped log-likelihood of the scan at every particle (wifi_likelihood.h)."""
        mean, var = interp.mean_and_variance(np.stack([self.x, self.y], axis=1))
        var = np.maximum(var, interp.variance_floor_db2)
        r = observation_rss[None, :] - mean
        term = np.minimum(0.5 * r * r / var, self.o.max_term)
        return -self.o.tempering * (0.5 * np.log(2 * np.pi) * var.shape[1] + (0.5 * np.log(var) + term).sum(axis=1))

    def wifi(self, interp, observation_rss: np.ndarray) -> dict:
        self.log_w = self.log_w + self.wifi_log_likelihood(interp, observation_rss)
        return self._finish()

    def _finish(self) -> dict:
        """Log-sum-exp normalisation, ESS, systematic resampling, the estimate (FinishUpdate)."""
        n = self.n
        m = self.log_w.max()
        w = np.exp(self.log_w - m)
        total = w.sum()
        log_z = m + np.log(total)
        ess = total * total / np.dot(w, w)
        w /= total
        resampled = ess < self.o.ess_threshold * n
        if resampled:
            u = (self.rng.random() + np.arange(n)) / n
            anc = np.minimum(np.searchsorted(np.cumsum(w), u), n - 1)
            self.x, self.y, self.offset, self.scale = self.x[anc], self.y[anc], self.offset[anc], self.scale[anc]
            self.log_w = np.full(n, -np.log(n))
            w = np.full(n, 1.0 / n)
        else:
            self.log_w = self.log_w - log_z
        mx, my = np.dot(w, self.x), np.dot(w, self.y)
        ddx, ddy = self.x - mx, self.y - my
        cov = np.array([[np.dot(w, ddx * ddx), np.dot(w, ddx * ddy)], [0.0, np.dot(w, ddy * ddy)]])
        cov[1, 0] = cov[0, 1]
        return {"mean_m": np.array([mx, my]), "covariance_m2": cov,
                "heading_offset_rad": float(np.arctan2(np.dot(w, np.sin(self.offset)), np.dot(w, np.cos(self.offset)))),
                "scale": float(np.dot(w, self.scale)), "ess": float(ess), "log_likelihood": float(log_z),
                "resampled": bool(resampled)}


# --------------------------------------------------------------------------- peer: WiFi interpolation

class ScipyInterpolator:
    """Linear interpolation of the map's means and variances over scipy's Delaunay triangulation
    (qhull) of the reference points: find_simplex + barycentric weights (one floor, queries
    inside the hull)."""

    def __init__(self, positions_m: np.ndarray, mean_dbm: np.ndarray, variance_db2: np.ndarray,
                 variance_floor_db2: float = 4.0):
        from scipy.spatial import Delaunay

        self.tri = Delaunay(np.asarray(positions_m, float))
        self.fields = np.ascontiguousarray(np.concatenate([mean_dbm, variance_db2], axis=1))  # (P, 2K)
        self.k = mean_dbm.shape[1]
        self.variance_floor_db2 = variance_floor_db2

    def mean_and_variance(self, points_m: np.ndarray):
        simplex = self.tri.find_simplex(points_m)
        if (simplex < 0).any():
            raise ValueError("query outside the reference points' hull (the C++ model projects it)")
        t = self.tri.transform[simplex]                       # (Q, 3, 2)
        b = np.einsum("qij,qj->qi", t[:, :2], points_m - t[:, 2])
        bary = np.column_stack([b, 1.0 - b.sum(axis=1)])      # (Q, 3)
        vert = self.tri.simplices[simplex]                    # (Q, 3)
        f = self.fields
        values = bary[:, 0:1] * f[vert[:, 0]] + bary[:, 1:2] * f[vert[:, 1]] + bary[:, 2:3] * f[vert[:, 2]]
        return values[:, :self.k], values[:, self.k:]
