"""The grid tracker's forward filter written in numpy + scipy: the peer of ``fusion.GridTracker``
in benchmarks/bench_fusion.py and its independent check in tests/python/test_fusion_grid.py.

Same model, same discretisation and the same decisions as cpp/src/fusion/grid_tracker.cc
(whole-cell shifts with a sub-cell remainder, the Gaussian blur deferred until its variance
reaches a quarter of a cell² or a fix arrives, the walkable-fraction wall factor, fixes as
tempered Gaussian mixtures over an outlier floor evaluated at the cell centres and resampled
bilinearly at the layer's remainder, normalisation with values below 1e-30 flushed), written the
obvious way: one numpy array per layer, ``scipy.ndimage.correlate1d`` for the blur. Filter only,
unknown start, one floor; the layers' mixture as in C++.
"""

from __future__ import annotations

import math
from typing import Dict

import numpy as np
from scipy import ndimage


def _kernel(var_cells2: float) -> np.ndarray:
    radius = max(1, int(math.ceil(3.0 * math.sqrt(var_cells2))))
    j = np.arange(-radius, radius + 1)
    k = np.exp(-0.5 * j * j / var_cells2)
    return (k / k.sum()).astype(np.float32)


def _shift(g: np.ndarray, sx: int, sy: int) -> np.ndarray:
    out = np.zeros_like(g)
    ny, nx = g.shape
    ys, yd = (slice(0, ny - sy), slice(sy, ny)) if sy >= 0 else (slice(-sy, ny), slice(0, ny + sy))
    xs, xd = (slice(0, nx - sx), slice(sx, nx)) if sx >= 0 else (slice(-sx, nx), slice(0, nx + sx))
    out[yd, xd] = g[ys, xs]
    return out


def _resample(g: np.ndarray, fx: float, fy: float) -> np.ndarray:
    """g at (x + fx, y + fy) cells, bilinear, edges clamped (as ResampleAt)."""
    dx, dy = (1 if fx >= 0 else -1), (1 if fy >= 0 else -1)
    ax, ay = np.float32(abs(fx)), np.float32(abs(fy))
    ix = np.clip(np.arange(g.shape[1]) + dx, 0, g.shape[1] - 1)
    iy = np.clip(np.arange(g.shape[0]) + dy, 0, g.shape[0] - 1)
    h = (np.float32(1) - ax) * g + ax * g[:, ix]
    return (np.float32(1) - ay) * h + ay * h[iy, :]


def fix_factor(fixes: tuple, j: int, x_m: np.ndarray, y_m: np.ndarray, floor_density: float, eps: float, tau: float,
               by_variance: bool) -> np.ndarray:
    """log of Π L^τ for fix j (as ComputeFixFactor; the 6 sd truncation kept)."""
    times, means, sds, weights, _ = fixes
    k = sds.shape[1]
    w = weights[j] / weights[j].sum()
    acc = np.zeros(x_m.shape)
    for c in range(k):
        if w[c] <= 0:
            continue
        sd = sds[j, c] / math.sqrt(tau) if by_variance else sds[j, c]
        mx, my = means[j, 2 * c], means[j, 2 * c + 1]
        d2 = (x_m - mx) ** 2 + (y_m - my) ** 2
        near = (np.abs(x_m - mx) <= 6 * sd + 1e-9) & (np.abs(y_m - my) <= 6 * sd + 1e-9)
        acc += np.where(near, (1 - eps) * w[c] / (2 * math.pi * sd * sd) * np.exp(-d2 / (2 * sd * sd)), 0.0)
    return (1.0 if by_variance else tau) * np.log(floor_density + acc)


def forward_filter(grid: Dict, steps: tuple, fixes: tuple, options: Dict) -> Dict[str, np.ndarray]:
    """The filtered mean (M, 2) [m] of an unknown-start walk on one floor.

    ``grid``: x0, y0 [m], cell [m], wall_factor (ny, nx) float32, area_m2 (walkable area);
    ``steps``: (times (M,), displacements (M, 2), covariances (M, 3)); ``fixes``: the
    ``Fixes.as_arrays()`` tuple; ``options``: offsets (H,) [rad] with log_prior (H,) and
    bin_width [rad], position_noise_m, eps, tau, by_variance."""
    t, disp, cov = steps
    c = grid["cell"]
    wall = grid["wall_factor"]
    ny, nx = wall.shape
    x_m = grid["x0"] + (np.arange(nx) + 0.5) * c
    y_m = grid["y0"] + (np.arange(ny) + 0.5) * c
    X, Y = np.meshgrid(x_m, y_m)
    # Fixes attached to the first step at or after them (the last step for later ones).
    attach = np.minimum(np.searchsorted(t, fixes[0], side="left"), len(t) - 1) if len(fixes[0]) else np.zeros(0, int)
    factors = {}
    for k in np.unique(attach):
        log_l = sum(fix_factor(fixes, j, X, Y, options["eps"] / grid["area_m2"], options["eps"], options["tau"],
                               options["by_variance"]) for j in np.flatnonzero(attach == k))
        top = log_l.max()
        factors[int(k)] = (np.exp(log_l - top).astype(np.float32), top)
    layers = []
    for off, lp in zip(options["offsets"], options["log_prior"]):
        g = wall.astype(np.float32).copy()
        g /= np.float32(g.sum(dtype=np.float64))
        co, so = math.cos(off), math.sin(off)
        rx = ry = pending = log_z = 0.0
        means, logz = [], []
        for k in range(len(t)):
            d = disp[k]
            rx += co * d[0] - so * d[1]
            ry += so * d[0] + co * d[1]
            length = float(np.hypot(*d))
            pending += 0.5 * (cov[k, 0] + cov[k, 2]) + options["position_noise_m"] ** 2 + \
                length ** 2 * options["bin_width"] ** 2 / 12.0
            sx, sy = int(round(rx / c)), int(round(ry / c))
            # C++ rounds half away from zero (std::lround); Python's round is to even.
            sx = int(math.copysign(math.floor(abs(rx / c) + 0.5), rx))
            sy = int(math.copysign(math.floor(abs(ry / c) + 0.5), ry))
            rx -= sx * c
            ry -= sy * c
            g = _shift(g, sx, sy)
            if pending >= 0.25 * c * c or k in factors:
                if pending / (c * c) > 1e-6:
                    kern = _kernel(pending / (c * c))
                    g = ndimage.correlate1d(g, kern, axis=0, mode="constant")
                    g = ndimage.correlate1d(g, kern, axis=1, mode="constant")
                pending = 0.0
            g = g * wall
            if k in factors:
                g = g * _resample(factors[k][0], rx / c, ry / c)
            s = float(g.sum(dtype=np.float64))
            log_z += math.log(s) + (factors[k][1] if k in factors else 0.0)
            g = (g.astype(np.float64) / s)
            g = np.where(g < 1e-30, 0.0, g).astype(np.float32)
            m = g.sum(dtype=np.float64)
            means.append(((g * X).sum(dtype=np.float64) / m + rx, (g * Y).sum(dtype=np.float64) / m + ry))
            logz.append(log_z + lp)
        layers.append((np.array(means), np.array(logz)))
    logz = np.stack([lz for _, lz in layers])          # (H, M)
    w = np.exp(logz - logz.max(axis=0))
    w /= w.sum(axis=0)
    mean = sum(w[h][:, None] * layers[h][0] for h in range(len(layers)))
    return {"mean_m": mean, "layer_weights": w}
