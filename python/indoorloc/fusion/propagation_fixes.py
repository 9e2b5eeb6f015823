"""Position fixes from a per-AP propagation model (:mod:`indoorloc.wifi.propagation`): each query
fingerprint's likelihood over the floor's walkable cells, its best cells as the components of a
Gaussian-mixture fix (``indoorloc.fusion.Fixes``), alone or mixed with the fingerprint kNN fix
(docs/fusion_real.md, "A propagation model that extrapolates").

Why: the kNN fix of :mod:`indoorloc.fusion.wifi_fixes` can only point at surveyed places; the
model's likelihood also reaches the floor beyond the survey.

Example::

    from indoorloc.wifi import propagation
    from indoorloc.fusion import propagation_fixes as pf
    model = propagation.fit_path_loss(db.rss_dbm, db.positions_m)
    cells = pf.walkable_cells(tracker, 0)
    t, q = wifi_fixes.walk_queries(walk, db)
    fixes = pf.model_fixes(t, propagation.scan_log_likelihood(model, q, model.predict(cells)), cells,
                           pf.ModelFixSettings())
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from indoorloc.fusion.fixes import Fixes


@dataclass(frozen=True)
class ModelFixSettings:
    """How a likelihood over cells becomes a fix: the ``k`` cells of highest likelihood, weights
    ∝ exp(ℓ / T) (T = ``temperature``, a tempering of the scan likelihood: the APs' errors are
    correlated, so their product is overconfident), each a Gaussian of sd ``sd_m`` [m]."""

    k: int = 20
    temperature: float = 10.0
    sd_m: float = 3.0
    #: Block size [m] (0: off): each block of the floor contributes at most one component, at its
    #: best cell, weighted by the block's likelihood mass Σ exp(ℓ / T): the k components then
    #: spread over the modes of the likelihood instead of crowding around its peak.
    block_m: float = 0.0

    def validate(self) -> None:
        """ValueError naming the first invalid field."""
        if not (isinstance(self.k, (int, np.integer)) and self.k >= 1):
            raise ValueError(f"indoorloc: ModelFixSettings.k: invalid value {self.k!r}")
        if not (math.isfinite(self.block_m) and self.block_m >= 0):
            raise ValueError(f"indoorloc: ModelFixSettings.block_m: invalid value {self.block_m!r}")
        for name in ("temperature", "sd_m"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"indoorloc: ModelFixSettings.{name}: invalid value {v!r}")


def walkable_cells(tracker, floor_index: int = 0) -> np.ndarray:
    """Centres (M, 2) [m] of a grid tracker's cells with a walkable fraction > 0 on a floor."""
    x0, y0, nx, ny = tracker.grid_geometry(floor_index)
    c = tracker.options.cell_size_m
    rows, cols = np.nonzero(np.asarray(tracker.walkable_fraction(floor_index)) > 0)
    return np.c_[x0 + (cols + 0.5) * c, y0 + (rows + 0.5) * c]


def model_fixes(times_s: np.ndarray, log_likelihood: np.ndarray, cells_m: np.ndarray, settings: ModelFixSettings,
                floor: int | None = None) -> Fixes:
    """One fix per query: times_s (Q,) [s], log_likelihood (Q, M) over cells_m (M, 2) [m]; the
    ``k`` best cells with weights exp((ℓ − ℓ_max) / T) and sd ``sd_m`` (module docstring)."""
    settings.validate()
    ll = np.asarray(log_likelihood, float)
    t = np.asarray(times_s, float)
    if ll.ndim != 2 or ll.shape[0] != t.size or ll.shape[1] != cells_m.shape[0]:
        raise ValueError(f"indoorloc: argument 'log_likelihood': expected shape ({t.size}, {cells_m.shape[0]}), "
                         f"got {ll.shape}")
    if settings.block_m > 0:
        return _block_fixes(t, ll, np.asarray(cells_m, float), settings, floor)
    k = min(settings.k, ll.shape[1])
    if t.size == 0:
        return Fixes.from_arrays(t, np.zeros((0, k, 2)), np.zeros((0, k)), np.zeros((0, k)))
    best = np.argpartition(-ll, k - 1, axis=1)[:, :k]
    top = np.take_along_axis(ll, best, axis=1)
    w = np.exp((top - top.max(axis=1, keepdims=True)) / settings.temperature)
    return Fixes.from_arrays(t, cells_m[best], np.full(w.shape, settings.sd_m), w, floor)


def _block_fixes(t: np.ndarray, ll: np.ndarray, cells: np.ndarray, s: ModelFixSettings, floor) -> Fixes:
    """model_fixes with ``block_m`` > 0: one candidate per block (its best cell, its mass)."""
    key = np.floor((cells - cells.min(axis=0)) / s.block_m).astype(np.int64)
    _, block = np.unique(key[:, 0] * (key[:, 1].max() + 1) + key[:, 1], return_inverse=True)
    nb = int(block.max()) + 1
    k = min(s.k, nb)
    means = np.zeros((t.size, k, 2))
    logw = np.zeros((t.size, k))
    order = np.argsort(block, kind="stable")
    starts = np.r_[0, np.flatnonzero(np.diff(block[order])) + 1]
    for j in range(t.size):
        x = ll[j, order] / s.temperature
        top = np.maximum.reduceat(x, starts)                       # per block: best tempered ℓ
        mass = top + np.log(np.add.reduceat(np.exp(x - np.repeat(top, np.diff(np.r_[starts, x.size]))), starts))
        best_blocks = np.argpartition(-mass, k - 1)[:k]
        # The best cell of each chosen block.
        for c, b in enumerate(best_blocks):
            seg = slice(starts[b], starts[b + 1] if b + 1 < nb else x.size)
            means[j, c] = cells[order[seg][np.argmax(x[seg])]]
        logw[j] = mass[best_blocks]
    w = np.exp(logw - logw.max(axis=1, keepdims=True)) if t.size else logw
    return Fixes.from_arrays(t, means, np.full(w.shape, s.sd_m), w, floor)


def mix_fixes(a: Fixes, b: Fixes, weight_b: float) -> Fixes:
    """The mixture (1 − weight_b) a + weight_b b of two sets of fixes at the same times [s]:
    each fix's components concatenated, each set's weights normalised per fix first."""
    if not 0 <= weight_b <= 1:
        raise ValueError(f"indoorloc: argument 'weight_b': must be in [0, 1], got {weight_b!r}")
    if a.times_s.shape != b.times_s.shape or not np.allclose(a.times_s, b.times_s):
        raise ValueError("indoorloc: arguments 'a', 'b': the fixes must be at the same times")
    wa = a.weights / np.maximum(a.weights.sum(axis=1, keepdims=True), 1e-300) * (1 - weight_b)
    wb = b.weights / np.maximum(b.weights.sum(axis=1, keepdims=True), 1e-300) * weight_b
    return Fixes.from_arrays(a.times_s, np.concatenate([a.means_m, b.means_m], axis=1),
                             np.concatenate([a.sds_m, b.sds_m], axis=1), np.concatenate([wa, wb], axis=1),
                             np.concatenate([a.floors, b.floors], axis=1))


def gate_fixes(fixes: Fixes, gate: np.ndarray, flat_sd_m: float = 1e3) -> Fixes:
    """Each fix j with its components' weights times g_j (F,) in [0, 1] plus one flat component
    (sd ``flat_sd_m`` [m], at the fix's centre) of weight 1 − g_j: g_j = 0 makes the fix
    uninformative over a floor (its product with another fix changes nothing), g_j = 1 leaves it."""
    g = np.asarray(gate, float).reshape(-1)
    if g.shape != (len(fixes),) or np.any(~np.isfinite(g)) or np.any((g < 0) | (g > 1)):
        raise ValueError(f"indoorloc: argument 'gate': expected ({len(fixes)},) values in [0, 1]")
    w = fixes.weights / np.maximum(fixes.weights.sum(axis=1, keepdims=True), 1e-300)
    used = fixes.weights > 0
    centre = (np.where(used[:, :, None], fixes.means_m, 0.0) * w[:, :, None]).sum(axis=1)
    return Fixes.from_arrays(fixes.times_s, np.concatenate([fixes.means_m, centre[:, None, :]], axis=1),
                             np.concatenate([fixes.sds_m, np.full((len(fixes), 1), flat_sd_m)], axis=1),
                             np.concatenate([w * g[:, None], (1.0 - g)[:, None]], axis=1),
                             np.concatenate([fixes.floors, fixes.floors[:, :1]], axis=1))


def stack_fixes(a: Fixes, b: Fixes) -> Fixes:
    """Both sets of fixes as separate fixes, in time order (a's first at equal times): the
    tracker multiplies the likelihoods of fixes at the same step (a product of the two sources
    instead of :func:`mix_fixes`' mixture). Components padded to the larger K with weight 0."""
    k = max(a.sds_m.shape[1], b.sds_m.shape[1])

    def pad(f: Fixes):
        n = k - f.sds_m.shape[1]
        if n == 0:
            return f.means_m, f.sds_m, f.weights, f.floors
        z = np.zeros((len(f), n))
        return (np.concatenate([f.means_m, np.zeros((len(f), n, 2))], axis=1), np.concatenate([f.sds_m, z + 1], axis=1),
                np.concatenate([f.weights, z], axis=1), np.concatenate([f.floors, f.floors[:, :1].repeat(n, 1)], axis=1))
    pa, pb = pad(a), pad(b)
    t = np.concatenate([a.times_s, b.times_s])
    order = np.argsort(t, kind="stable")
    return Fixes.from_arrays(t[order], *(np.concatenate([x, y])[order] for x, y in zip(pa, pb)))


__all__ = ["ModelFixSettings", "gate_fixes", "mix_fixes", "model_fixes", "stack_fixes", "walkable_cells"]
