"""WiFi-only sequence tracking with a direction-persistent motion prior: the forward-backward
(hidden Markov) smoother of a walk's WiFi fixes on the floor's walkable grid whose state is
(cell, motion mode), the modes "wander" (the random walk of :mod:`indoorloc.fusion.wifi_sequence`)
and D walking directions (docs/fusion_real.md, "WiFi only: a direction-persistent motion prior").

Why: surveyors walk steadily (about 1.1-1.2 m/s) along corridors, turning now and then. A random
walk gives the smoother no reason to carry a walker beyond the surveyed corridor where the fixes
only say "near the survey"; a walker that keeps its direction does. Like ``wifi_sequence`` this
uses the scans, their timestamps, the fingerprint database and the floor plan, and nothing from
the phone's motion sensors.

Model, per tick of ``tick_s`` seconds (state (c, m): cell c, mode m in {wander, heading 1..D}):
  mode:     P(m' | m) (:func:`mode_transition`): a heading is kept with probability p_keep, turns
            to a neighbouring bin, to any bin, or starts wandering; wandering ends into any heading
  move:     p(c' | c, m') = K_m'(c, c'): heading θ_m': the displacement v·tick (cos θ, sin θ)
            (bilinear on the lattice, so its mean is exact) blurred by N(0, σ_b² I); wander: the
            random walk N(0, σ_w² tick I). Mass moved off the grid's cells is lost (a wall).
  walls:    m(c) = a(c) + (1 - a(c)) e^λ, a(c) the cell's walkable fraction
  fixes:    L_j(c) = ε / A + (1 - ε) Σ_k w_k N(q(c); μ_k, (κ σ_k)² I) at the survey-anchored
            point q(c) = s(c) + β (c - s(c))
The cells, the walls and the fixes are the C++ grid tracker's, read from a ``GridTracker`` with
these settings (``wall_factors``, ``fix_log_likelihood``: the one implementation of that model,
grid_fix_factor.cc, grid_survey_anchors.cc). The model of the motion is defined here
(:func:`motion_stencils`, :func:`mode_transition`); its forward-backward runs in C++
(``indoorloc._core.fusion.smooth_mode_sequence``, mode_sequence_smoother.cc).
The states are the cells with a walkable fraction > 0 and ``margin_cells`` rings around them
(the rest of the floor's bounding box, which the grid tracker also holds, pays λ every tick and
carries almost no mass). With ``headings`` = 0 the model is ``wifi_sequence``'s.

Example::

    from indoorloc.fusion import wifi_heading_sequence as whs, wifi_sequence as ws
    s = whs.HeadingSequenceSettings()
    grid = whs.heading_grid(plan, s, database.positions_m)
    track = whs.track_fixes(grid, fixes, 0.0, walk.duration_s, s)
    xy = ws.at_times(track, waypoint_times_s)
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np


@dataclass(frozen=True)
class HeadingSequenceSettings:
    """Settings of the direction-persistent WiFi-only tracker (units in the names). Defaults: the
    leave-one-floor-out choice over the six floors of the competition mall (seed 0, the folds of
    ``fusion evaluate``; ``experiments/wifi_heading_study``; docs/fusion_real.md, "WiFi only: a
    direction-persistent motion prior"), the all-floor choice of the final grid."""

    tick_s: float = 1.0                  #: time between motion steps [s] (wifi_sequence's; fixed)
    cell_size_m: float = 2.0             #: grid cell [m] (wifi_sequence's; fixed)
    #: D walking directions (0: the wander mode alone, wifi_sequence's random walk). LOFO over
    #: {0, 8, 16}: 8 on all six floors (16 within 0.01 m pooled, chosen for four held-out floors).
    headings: int = 8
    #: Walking speed of a heading mode [m/s] (LOFO over {1.0, 1.2}, first {1.0, 1.2, 1.4}: 1.2;
    #: within 0.02 m pooled: the error hardly depends on it).
    speed_m_per_s: float = 1.2
    #: Blur of a heading mode's move per tick [m] (LOFO over {0.5, 1.0}: 0.5, 0.05 m ahead).
    heading_blur_sd_m: float = 0.5
    #: p_keep per tick (LOFO over {0.9, 0.97}, first {0.85, 0.9, 0.95}: 0.9, within 0.04 m).
    keep_heading_probability: float = 0.9
    #: Of the turns (probability 1 - p_keep - to_wander), the share to a neighbouring bin (the
    #: rest uniform over all bins). Fixed in advance, not tuned.
    neighbour_turn_share: float = 0.5
    #: Per tick, from a heading to the wander mode (LOFO over {0.005, 0.02}: 0.02, within 0.01 m).
    to_wander_probability: float = 0.02
    from_wander_probability: float = 0.1  #: per tick, from the wander mode to a heading (fixed, not tuned)
    wander_sd_m_per_sqrt_s: float = 2.0  #: the wander mode's random walk [m/√s] (wifi_sequence's; fixed)
    #: κ, each fix component's sd multiplied by this (LOFO over {0.25, 0.35}, first {0.35, 0.5,
    #: 0.75}: 0.35 on all six floors and every held-out floor, as wifi_sequence).
    fix_sd_scale: float = 0.35
    #: ε (LOFO over {0.001, 0.01}: level within 0.01 m; 0.001, wifi_sequence's).
    fix_outlier_probability: float = 0.001
    #: β of the survey-anchored fixes (1: off). LOFO over {0.15, 0.25}, first {0, 0.15, 0.25} and
    #: {0.15, 0.5}: 0.15 on all six floors and five held-out floors (0.25 with F4 held out).
    fix_survey_distance_factor: float = 0.15
    #: λ per tick in obstacle cells (LOFO over {-1, -3}: -1 on all six floors, wifi_sequence's).
    wall_log_penalty: float = -1.0
    #: Rings of obstacle cells kept around the walkable ones (fixed: enough for D = 0 to match
    #: the C++ grid tracker, whose grid is the whole bounding box, within 0.07 m on five floors).
    margin_cells: int = 2

    def grid_options(self):
        """The C++ grid tracker's options whose grid, walls and fixes these settings use (ε, β, λ,
        the cell size; τ 1, no survey-open cells: wifi_sequence's)."""
        from indoorloc.fusion.grid import GridTrackerOptions

        self.validate()
        return GridTrackerOptions().replace(cell_size_m=self.cell_size_m, wall_log_penalty=self.wall_log_penalty,
                                            fix_outlier_probability=self.fix_outlier_probability, fix_tempering=1.0,
                                            fix_tempering_by_variance=False,
                                            fix_survey_distance_factor=self.fix_survey_distance_factor,
                                            survey_walkable_radius_m=0.0)

    def validate(self) -> None:
        """ValueError naming the field for a setting out of range."""
        finite_pos = lambda v: math.isfinite(v) and v > 0  # noqa: E731
        checks = {
            "tick_s": finite_pos(self.tick_s),
            "cell_size_m": finite_pos(self.cell_size_m),
            "headings": isinstance(self.headings, (int, np.integer)) and 0 <= self.headings <= 64,
            "speed_m_per_s": math.isfinite(self.speed_m_per_s) and self.speed_m_per_s >= 0,
            "heading_blur_sd_m": math.isfinite(self.heading_blur_sd_m) and self.heading_blur_sd_m >= 0,
            "keep_heading_probability": 0 <= self.keep_heading_probability <= 1,
            "neighbour_turn_share": 0 <= self.neighbour_turn_share <= 1,
            "to_wander_probability": 0 <= self.to_wander_probability <= 1 - self.keep_heading_probability,
            "from_wander_probability": 0 <= self.from_wander_probability <= 1,
            "wander_sd_m_per_sqrt_s": finite_pos(self.wander_sd_m_per_sqrt_s),
            "fix_sd_scale": finite_pos(self.fix_sd_scale),
            "fix_outlier_probability": 0 < self.fix_outlier_probability < 1,
            "fix_survey_distance_factor": 0 <= self.fix_survey_distance_factor <= 1,
            "wall_log_penalty": self.wall_log_penalty <= 0 and not math.isnan(self.wall_log_penalty),
            "margin_cells": isinstance(self.margin_cells, (int, np.integer)) and 0 <= self.margin_cells <= 20,
        }
        for name, ok in checks.items():
            if not ok:
                raise ValueError(f"indoorloc: HeadingSequenceSettings.{name}: invalid value {getattr(self, name)!r}")


@dataclass
class HeadingGrid:
    """A floor's states for the tracker: ``tracker`` the C++ ``GridTracker`` (floor
    ``floor_index``) whose lattice (nx, ny) of ``cell_size_m`` cells from origin (x0, y0) [m], wall
    factors and fix model the states use; ``index`` (ny, nx) the state index of each lattice cell
    or -1; ``lattice_cell`` (N,) each state's row-major lattice index; ``cells_m`` (N, 2) the
    states' centres [m]; ``wall_factor`` (N,) the tracker's."""

    tracker: Any
    floor_index: int
    x0: float
    y0: float
    nx: int
    ny: int
    cell_size_m: float
    index: np.ndarray
    lattice_cell: np.ndarray
    cells_m: np.ndarray
    wall_factor: np.ndarray


def grid_from_tracker(tracker: Any, settings: HeadingSequenceSettings, floor_index: int = 0) -> HeadingGrid:
    """The states on floor ``floor_index`` of a ``GridTracker`` built with ``settings.grid_options()``
    (and, for anchored fixes, ``with_survey_positions``): its cells with a walkable fraction > 0
    and ``settings.margin_cells`` rings around them."""
    from scipy.ndimage import binary_dilation

    settings.validate()
    if abs(float(tracker.options.cell_size_m) - settings.cell_size_m) > 1e-12:
        raise ValueError(f"indoorloc: argument 'tracker': its cell size {tracker.options.cell_size_m} m is not "
                         f"settings.cell_size_m = {settings.cell_size_m} m (build it with settings.grid_options())")
    x0, y0, nx, ny = (float(v) for v in tracker.grid_geometry(floor_index))
    nx, ny = int(nx), int(ny)
    a = np.asarray(tracker.walkable_fraction(floor_index), dtype=float)
    keep = a > 0
    if settings.margin_cells > 0:
        keep = binary_dilation(keep, np.ones((3, 3), bool), iterations=settings.margin_cells)
    index = np.full((ny, nx), -1, dtype=np.int64)
    rows, cols = np.nonzero(keep)
    index[rows, cols] = np.arange(rows.size)
    c = settings.cell_size_m
    cells = np.stack([x0 + (cols + 0.5) * c, y0 + (rows + 0.5) * c], axis=1)
    wall = np.asarray(tracker.wall_factors(floor_index), dtype=float)[rows, cols]
    return HeadingGrid(tracker, int(floor_index), x0, y0, nx, ny, c, index, rows * nx + cols, cells, wall)


def heading_grid(plan: Any, settings: HeadingSequenceSettings, survey_positions_m: Optional[np.ndarray] = None,
                 floor_index: int = 0) -> HeadingGrid:
    """The tracker's states on floor ``floor_index`` of ``plan`` (an ``indoorloc.fusion`` floor
    plan), the fixes anchored to ``survey_positions_m`` (P, 2) [m] (None or empty: read at the
    cells)."""
    from indoorloc.fusion.grid import GridTracker

    tracker = GridTracker(plan, settings.grid_options())
    if survey_positions_m is not None and len(survey_positions_m) and settings.fix_survey_distance_factor < 1:
        pts = np.asarray(survey_positions_m, dtype=float).reshape(-1, 2)
        if not np.all(np.isfinite(pts)):
            raise ValueError("indoorloc: argument 'survey_positions_m': must be finite")
        tracker = tracker.with_survey_positions(pts, np.full(pts.shape[0], int(plan.floors[floor_index]), np.int64))
    return grid_from_tracker(tracker, settings, floor_index)


def mode_transition(settings: HeadingSequenceSettings) -> np.ndarray:
    """P(m' | m) per tick, (D + 1, D + 1), mode 0 the wander mode, 1..D the headings θ = 2π(m-1)/D."""
    d = settings.headings
    t = np.zeros((d + 1, d + 1))
    if d == 0:
        t[0, 0] = 1.0
        return t
    t[0, 0] = 1.0 - settings.from_wander_probability
    t[0, 1:] = settings.from_wander_probability / d
    turn = 1.0 - settings.keep_heading_probability - settings.to_wander_probability
    for h in range(d):
        row = t[h + 1]
        row[0] = settings.to_wander_probability
        row[1 + h] += settings.keep_heading_probability
        row[1:] += turn * (1.0 - settings.neighbour_turn_share) / d
        for nb in ((h - 1) % d, (h + 1) % d):
            row[1 + nb] += turn * settings.neighbour_turn_share / 2
    return t


def _stencil(shift_cells: np.ndarray, sd_cells: float):
    """Lattice offsets (K, 2) (dx, dy) and weights (K,) summing to 1: the bilinear splat of the
    shift convolved with a sampled Gaussian of sd_cells (mean exactly the shift)."""
    fx, fy = math.floor(shift_cells[0]), math.floor(shift_cells[1])
    rx, ry = shift_cells[0] - fx, shift_cells[1] - fy
    splat = {(fx, fy): (1 - rx) * (1 - ry), (fx + 1, fy): rx * (1 - ry), (fx, fy + 1): (1 - rx) * ry, (fx + 1, fy + 1): rx * ry}
    if sd_cells > 1e-6:
        r = int(math.ceil(3.0 * sd_cells))
        o = np.arange(-r, r + 1)
        g1 = np.exp(-0.5 * (o / sd_cells) ** 2)
        g1 /= g1.sum()
        blur = {(int(i), int(j)): g1[a] * g1[b] for a, i in enumerate(o) for b, j in enumerate(o)}
    else:
        blur = {(0, 0): 1.0}
    out: Dict[tuple, float] = {}
    for (sx, sy), ws in splat.items():
        if ws <= 0:
            continue
        for (bx, by), wb in blur.items():
            out[(sx + bx, sy + by)] = out.get((sx + bx, sy + by), 0.0) + ws * wb
    keys = [k for k, v in out.items() if v > 1e-4]  # below: < 0.3 % of the mass in all
    w = np.array([out[k] for k in keys])
    return np.array(keys, dtype=np.int64).reshape(-1, 2), w / w.sum()


def motion_stencils(settings: HeadingSequenceSettings) -> List[Tuple[np.ndarray, np.ndarray]]:
    """Per mode m the move per tick on the lattice, (offsets (K, 2) int (dx, dy) [cells], weights
    (K,) summing to 1): mode 0 the random walk, 1..D the headings (:func:`mode_transition`). The
    smoother moves a state by offset i with weight i; a move onto a cell that is not a state is
    lost (a wall)."""
    settings.validate()
    c = settings.cell_size_m
    out = [_stencil(np.zeros(2), settings.wander_sd_m_per_sqrt_s * math.sqrt(settings.tick_s) / c)]
    step = settings.speed_m_per_s * settings.tick_s / c
    for h in range(settings.headings):
        th = 2 * math.pi * h / settings.headings
        out.append(_stencil(step * np.array([math.cos(th), math.sin(th)]), settings.heading_blur_sd_m / c))
    return out


def motion_kernels(grid: HeadingGrid, settings: HeadingSequenceSettings) -> List[Any]:
    """Deprecated (docs/api_changes.md): the smoother runs :func:`motion_stencils` on the lattice
    in C++ and needs no matrix. Per mode the transposed move kernel K_m^T (N, N) as a
    ``scipy.sparse.csr_matrix`` (K[i, j] the probability of moving from state i to state j)."""
    import scipy.sparse as sp

    warnings.warn("indoorloc: wifi_heading_sequence.motion_kernels is deprecated since house (C++ smoother): "
                  "track_fixes needs no kernels; use motion_stencils(settings) for the motion model",
                  DeprecationWarning, stacklevel=2)
    rows, cols = np.nonzero(grid.index >= 0)
    src = grid.index[rows, cols]
    n = grid.cells_m.shape[0]
    out = []
    for offsets, weights in motion_stencils(settings):
        ii, jj, vv = [], [], []
        for (dx, dy), w in zip(offsets, weights):
            r2, c2 = rows + dy, cols + dx
            ok = (r2 >= 0) & (r2 < grid.ny) & (c2 >= 0) & (c2 < grid.nx)
            dst = np.full(src.size, -1, dtype=np.int64)
            dst[ok] = grid.index[r2[ok], c2[ok]]
            ok = dst >= 0
            ii.append(dst[ok])
            jj.append(src[ok])
            vv.append(np.full(int(ok.sum()), w))
        out.append(sp.csr_matrix((np.concatenate(vv), (np.concatenate(ii), np.concatenate(jj))), shape=(n, n)))
    return out


def fix_factors(grid: HeadingGrid, fixes: Any, tick_times_s: np.ndarray, settings: HeadingSequenceSettings
                ) -> Dict[int, np.ndarray]:
    """tick index -> Π_j L_j (N,) over the fixes applied at that tick (the first tick at or after
    a fix's time; before the first tick: the first; after the last: the last), scaled to max 1:
    the grid tracker's fix model (``GridTracker.fix_log_likelihood``) with each component's sd x κ."""
    times, means, sds, weights, floors = fixes.as_arrays()
    sds = np.asarray(sds, float) * settings.fix_sd_scale
    ticks = np.clip(np.searchsorted(tick_times_s, np.asarray(times) - 1e-9), 0, len(tick_times_s) - 1)
    # One C++ call for every tick: the fixes grouped by tick (stable: each group in the fixes' order).
    order = np.argsort(ticks, kind="stable")
    groups, starts = np.unique(ticks[order], return_index=True)
    sub = (times[order], means[order], sds[order], weights[order], None if floors is None else floors[order])
    log_l = np.asarray(grid.tracker.fix_log_likelihoods(grid.floor_index, sub, np.r_[starts, order.size],
                                                          grid.lattice_cell), float)
    return {int(k): np.exp(row - row.max()) for k, row in zip(groups, log_l)}


def track_fixes(grid: HeadingGrid, fixes: Any, t_start_s: float, t_end_s: float,
                settings: HeadingSequenceSettings, stencils: Optional[Sequence[Any]] = None
                ) -> Dict[str, np.ndarray]:
    """The walk's smoothed position [m] every ``tick_s`` from t_start_s to t_end_s [s] from its
    WiFi fixes alone: ``{"times_s" (M,), "position_m" (M, 2), "mean_m" (M, 2)}``, the posterior
    mean (NaN when there is no fix). ``stencils``: the motion model, :func:`motion_stencils` of
    ``settings`` (None: built here; a list of the former ``motion_kernels`` matrices is deprecated
    and ignored). The forward-backward runs in C++ (``indoorloc._core.fusion.smooth_mode_sequence``:
    per-tick normalisation, the forward pass in float32). Read at other times with
    ``wifi_sequence.at_times``."""
    from indoorloc._core.fusion import smooth_mode_sequence

    settings.validate()
    if not (math.isfinite(t_start_s) and math.isfinite(t_end_s)) or t_end_s < t_start_s:
        raise ValueError(f"indoorloc: arguments 't_start_s', 't_end_s': need finite t_start_s <= t_end_s, "
                         f"got {t_start_s}, {t_end_s}")
    m = max(2, int(math.ceil((t_end_s - t_start_s) / settings.tick_s)) + 1)
    times = t_start_s + settings.tick_s * np.arange(m)
    if stencils is not None and len(stencils) and not isinstance(stencils[0], (tuple, list)):
        warnings.warn("indoorloc: passing motion_kernels to wifi_heading_sequence.track_fixes is deprecated since "
                      "house (C++ smoother): they are ignored; pass motion_stencils(settings) or nothing",
                      DeprecationWarning, stacklevel=2)
        stencils = None
    stencils = list(stencils) if stencils is not None else motion_stencils(settings)
    if len(stencils) != settings.headings + 1:
        raise ValueError(f"indoorloc: argument 'stencils': expected {settings.headings + 1} (headings + 1), "
                         f"got {len(stencils)}")
    if fixes is None or len(fixes) == 0:
        nan = np.full((m, 2), np.nan)
        return {"times_s": times, "position_m": nan, "mean_m": nan}
    factors = fix_factors(grid, fixes, times, settings)
    ticks = np.array(sorted(factors), dtype=np.int64)
    rows = np.stack([factors[k] for k in ticks]) if ticks.size else np.zeros((0, grid.cells_m.shape[0]))
    result = smooth_mode_sequence(grid.index, grid.cells_m, stencils, mode_transition(settings), grid.wall_factor,
                                  ticks, rows, m)
    mean = result.mean_m
    return {"times_s": times, "position_m": mean, "mean_m": mean}


__all__ = ["HeadingGrid", "HeadingSequenceSettings", "fix_factors", "grid_from_tracker", "heading_grid",
           "mode_transition", "motion_kernels", "motion_stencils", "track_fixes"]
