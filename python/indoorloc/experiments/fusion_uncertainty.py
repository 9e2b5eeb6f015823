"""Honest uncertainty of the grid tracker: the calibration of its returned covariances, chosen by
leave-one-floor-out on the shared mall (docs/fusion_real.md, "Honest uncertainty").

The posterior's own spread is that of the model, which knows nothing of its misfits: on the six
shared floors (4-fold by walk) its 95 % ellipse holds the truth at 50 % of the smoother's waypoints
and 58 % of the causal filter's. The tracker returns instead (``GridTrackerOptions``)

    Σ' = a Σ + (b² + (g d)² + (h max(0, s - s0))²) I,

Σ the posterior covariance, d [m] the distance from the estimate to the centre of the WiFi fix
nearest in time (the filter: the last fix applied) and s [m] that fix's own sd (for fingerprint
fixes it grows with the best match's dissimilarity): a track far from its fixes, or whose fixes
match no surveyed fingerprint well, is less certain than its posterior says. For each method
(causal filter, smoother, known start) this study scores every waypoint once (``indoorloc fusion
evaluate``'s folds and settings), then for each held-out floor chooses (a, b, g, h, s0) on the
other five floors over :data:`GRID` as the smallest median region (area) whose coverage on those
floors is at least :data:`TARGET` pooled and at least :data:`FLOOR_TARGET` on each of them, and
reports the held-out floor's coverage with it; the all-floor choice is what the defaults take.
The same study restricted to h = 0 (the distance-only calibration of before) is reported beside.

Run: ``python -m indoorloc.experiments.fusion_uncertainty [--data-root DIR] [--floors ...]
[--out benchmarks/results/fusion_uncertainty]`` (701 s for the six floors on 2 cores shared with
other jobs; the grid search dominates).
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import time
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

from indoorloc.experiments import fusion_real
from indoorloc import progress as _progress

#: The methods whose returned covariance is calibrated (the grid engine's).
METHODS = ("fusion_unknown_start", "fusion_smoother", "fusion_known_start")
#: The target coverage of the 95 % region on the training floors, pooled.
TARGET = 0.95
#: ... and on each training floor (the goal is 85-97 % on every floor: a margin above 0.85).
FLOOR_TARGET = 0.90
#: χ²₂(0.95): the 95 % ellipse is e' Σ'⁻¹ e <= this.
CHI2_95 = 5.991464547107979
#: Candidate (a, b [m], g, h, s0 [m]): scales of the posterior, floors of the sd, gains of the fix
#: distance, gains of the fix sd above its knee s0.
GRID = {
    "scale": (1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0),
    "floor_m": (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0),
    "fix_gain": (0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5),
    "fix_sd_gain": (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0),
    "fix_sd_knee_m": (4.0, 6.0, 8.0, 10.0, 12.0),
}
#: The grid of the distance-only calibration (h = 0), reported beside.
DISTANCE_ONLY = {**GRID, "fix_sd_gain": (0.0,), "fix_sd_knee_m": (0.0,)}
KEYS = ("scale", "floor_m", "fix_gain", "fix_sd_gain", "fix_sd_knee_m")
_CHUNK = 512


def calibrated(cov: np.ndarray, d: np.ndarray, s: np.ndarray, scale: float, floor_m: float, fix_gain: float,
               fix_sd_gain: float = 0.0, fix_sd_knee_m: float = 0.0) -> np.ndarray:
    """Σ' (N, 3) = a Σ + (b² + (g d)² + (h max(0, s - s0))²) I of posterior covariances ``cov``
    (N, 3) = (xx, xy, yy) [m²], fix distances ``d`` (N,) [m] and fix sds ``s`` (N,) [m] (the
    formula of ``GridTrackerOptions``)."""
    iso = floor_m ** 2 + (fix_gain * d) ** 2 + (fix_sd_gain * np.maximum(0.0, s - fix_sd_knee_m)) ** 2
    return np.stack([scale * cov[:, 0] + iso, scale * cov[:, 1], scale * cov[:, 2] + iso], axis=1)


def coverage_and_area(error_m: np.ndarray, cov: np.ndarray) -> tuple:
    """(inside (N,) bool: the error in the 95 % ellipse of cov (N, 3); area (N,) of the ellipse [m²])."""
    xx, xy, yy = cov[:, 0], cov[:, 1], cov[:, 2]
    det = np.maximum(xx * yy - xy * xy, 1e-300)
    ex, ey = error_m[:, 0], error_m[:, 1]
    mahalanobis2 = (yy * ex * ex - 2.0 * xy * ex * ey + xx * ey * ey) / det
    return mahalanobis2 <= CHI2_95, math.pi * CHI2_95 * np.sqrt(det)


def choose(error_m: np.ndarray, cov: np.ndarray, d: np.ndarray, s: np.ndarray, floor: np.ndarray,
           grid: Optional[Dict[str, Sequence[float]]] = None, target: float = TARGET,
           floor_target: float = FLOOR_TARGET) -> Dict[str, float]:
    """The point of ``grid`` (default :data:`GRID`) with the smallest median 95 % region whose
    coverage is at least ``target`` pooled and at least ``floor_target`` on every floor of
    ``floor`` (N,) (the largest pooled coverage if none reaches both; ties: the first in grid
    order). Vectorised over blocks of grid points."""
    grid = grid or GRID
    labels = sorted(set(floor.tolist()))
    member = np.stack([floor == f for f in labels])               # F x N
    points = [p + (knee,) for knee in grid["fix_sd_knee_m"] for p in
              itertools.product(grid["scale"], grid["floor_m"], grid["fix_gain"], grid["fix_sd_gain"])]
    best, fallback = None, None
    for lo in range(0, len(points), _CHUNK):  # blocks of grid points: memory stays ~ _CHUNK x N
        block = points[lo:lo + _CHUNK]
        a, b, g, h, knee = (np.array(col)[:, None] for col in zip(*block))
        iso = b * b + (g * d[None]) ** 2 + (h * np.maximum(0.0, s[None] - knee)) ** 2
        xx, xy, yy = a * cov[None, :, 0] + iso, a * cov[None, :, 1], a * cov[None, :, 2] + iso
        det = np.maximum(xx * yy - xy * xy, 1e-300)
        ex, ey = error_m[None, :, 0], error_m[None, :, 1]
        inside = (yy * ex * ex - 2.0 * xy * ex * ey + xx * ey * ey) / det <= CHI2_95
        pooled = inside.mean(axis=1)
        per_floor = (inside.astype(np.float64) @ member.T.astype(np.float64)) / member.sum(axis=1)
        ok = (pooled >= target) & (per_floor.min(axis=1) >= floor_target)
        if ok.any():
            size = np.median(det[ok], axis=1)                     # the area grows with sqrt(det)
            j = int(np.flatnonzero(ok)[np.argmin(size)])
            if best is None or size.min() < best[0]:
                best = (float(size.min()), block[j])
        j = int(np.argmax(pooled))
        if fallback is None or pooled[j] > fallback[0]:
            fallback = (float(pooled[j]), block[j])
    return dict(zip(KEYS, (best or fallback)[1]))


#: Edges [m] of the fix-sd bins of :func:`error_by_fix_sd`.
FIX_SD_BINS_M = (0.0, 5.0, 7.0, 9.0, 11.0, 14.0, math.inf)


def error_by_fix_sd(error_m: np.ndarray, s: np.ndarray) -> List[Optional[float]]:
    """Median error [m] per bin of the fix sd ``s`` (N,) [m] (:data:`FIX_SD_BINS_M`; None when
    empty): why the calibration has a knee (docs/fusion_real.md, "Honest uncertainty")."""
    err = np.hypot(error_m[:, 0], error_m[:, 1])
    out: List[Optional[float]] = []
    for lo, hi in zip(FIX_SD_BINS_M[:-1], FIX_SD_BINS_M[1:]):
        m = (s >= lo) & (s < hi)
        out.append(float(np.median(err[m])) if m.any() else None)
    return out


def _summary(error_m: np.ndarray, cov: np.ndarray) -> Dict[str, float]:
    inside, area = coverage_and_area(error_m, cov)
    return {"coverage": float(inside.mean()), "median_radius_m": float(np.sqrt(np.median(area) / math.pi)),
            "waypoints": int(inside.size)}


def _lofo(e, cov, d, s, floor, grid) -> dict:
    """Per held-out floor: the choice on the other floors and its coverage there; pooled."""
    held_inside = np.zeros(floor.size, bool)
    held_area = np.zeros(floor.size)
    per_floor = {}
    for f in sorted(set(floor.tolist())):
        train, test = floor != f, floor == f
        if not train.any():
            continue
        c = choose(e[train], cov[train], d[train], s[train], floor[train], grid)
        cal = calibrated(cov[test], d[test], s[test], **c)
        held_inside[test], held_area[test] = coverage_and_area(e[test], cal)
        per_floor[f] = {"chosen": c, **_summary(e[test], cal)}
    if not per_floor:
        return {}
    return {"coverage": float(held_inside.mean()), "median_radius_m": float(np.sqrt(np.median(held_area) / math.pi)),
            "coverage_min_floor": min(v["coverage"] for v in per_floor.values()),
            "coverage_max_floor": max(v["coverage"] for v in per_floor.values()), "floors": per_floor}


def study(scores: Sequence[fusion_real.WalkScore], methods: Sequence[str] = METHODS) -> dict:
    """Leave-one-floor-out choice and held-out coverage per method, from walk scores with
    ``calibration_inputs`` (``fusion_real.evaluate_floors``); beside it the distance-only
    calibration (h = 0) chosen the same way."""
    out: Dict[str, dict] = {}
    for name in methods:
        rows = [(s.floor, s.calibration_inputs[name]) for s in scores if name in s.calibration_inputs]
        if not rows:
            continue
        floor = np.concatenate([np.full(len(r["fix_distance_m"]), f) for f, r in rows])
        e = np.concatenate([r["error_m"] for _, r in rows])
        cov = np.concatenate([r["posterior_covariance_m2"] for _, r in rows])
        d = np.concatenate([r["fix_distance_m"] for _, r in rows])
        s = np.concatenate([r["fix_sd_m"] for _, r in rows])
        chosen = choose(e, cov, d, s, floor)
        cal = calibrated(cov, d, s, **chosen)
        all_floors = {"chosen": chosen, **_summary(e, cal),
                      "floors": {f: _summary(e[floor == f], cal[floor == f]) for f in sorted(set(floor.tolist()))}}
        labels = sorted(set(floor.tolist()))
        out[name] = {
            "error_by_fix_sd": {f: {"median_error_m": error_by_fix_sd(e[floor == f], s[floor == f]),
                                    "waypoints": [int(((s[floor == f] >= lo) & (s[floor == f] < hi)).sum())
                                                  for lo, hi in zip(FIX_SD_BINS_M[:-1], FIX_SD_BINS_M[1:])]}
                                for f in labels},
            "posterior": {**_summary(e, cov),
                          "floors": {f: _summary(e[floor == f], cov[floor == f]) for f in sorted(set(floor.tolist()))}},
            "lofo": _lofo(e, cov, d, s, floor, GRID),
            "lofo_distance_only": _lofo(e, cov, d, s, floor, DISTANCE_ONLY),
            "all_floors": all_floors,
        }
    return out


def run(data_root: Optional[Path] = None, floors: Sequence[str] = (),
        settings: Optional[fusion_real.RealSettings] = None) -> dict:
    """Scores the floors once (4-fold by walk) and runs :func:`study`."""
    settings = settings or fusion_real.RealSettings(floor_identification=False)
    tic = time.perf_counter()
    _, data = fusion_real.load_site(data_root, floors)
    scores = fusion_real.evaluate_floors(data, settings, None, None, METHODS)
    result = study(scores)
    return {"study": "fusion_uncertainty", "version": 2, "floors": [fl.name for fl in data],
            "folds": settings.folds, "seed": settings.seed, "target": TARGET, "floor_target": FLOOR_TARGET,
            "grid": {k: list(v) for k, v in GRID.items()}, "methods": result,
            "seconds": time.perf_counter() - tic}


def _choice(c: Dict[str, float]) -> str:
    return (f"({c['scale']:g}, {c['floor_m']:g}, {c['fix_gain']:g}, {c['fix_sd_gain']:g}, "
            f"{c['fix_sd_knee_m']:g})")


def markdown(result: dict) -> str:
    """The study's tables: per method pooled, then per floor (LOFO)."""
    floors = result["floors"]
    lines = [f"# Calibration of the grid tracker's covariance (leave-one-floor-out, floors "
             f"{' '.join(floors)}, {result['folds']}-fold by walk)", "",
             "Σ' = a Σ + (b² + (g d)² + (h max(0, s - s0))²) I; per held-out floor (a, b, g, h, s0) chosen on the "
             f"other floors as the smallest median 95 % region with coverage >= {result['target']:.2f} pooled and "
             f">= {result['floor_target']:.2f} on each of them. Distance only: the same with h = 0.", "",
             "| method | posterior's own coverage | LOFO coverage (min-max floor) | LOFO median radius [m] "
             "| distance only: LOFO coverage (min-max) | all-floor choice (a, b, g, h, s0) | its coverage |",
             "|---|---|---|---|---|---|---|"]
    for name, m in result["methods"].items():
        lo, ld = m["lofo"], m["lofo_distance_only"]
        lines.append(f"| {name} | {m['posterior']['coverage']:.3f} | {lo['coverage']:.3f} "
                     f"({lo['coverage_min_floor']:.2f}-{lo['coverage_max_floor']:.2f}) | "
                     f"{lo['median_radius_m']:.1f} | {ld['coverage']:.3f} ({ld['coverage_min_floor']:.2f}-"
                     f"{ld['coverage_max_floor']:.2f}) | {_choice(m['all_floors']['chosen'])} | "
                     f"{m['all_floors']['coverage']:.3f} |")
    lines += ["", "Per floor, coverage of the 95 % region (LOFO: chosen without the floor; median radius [m] "
              "in brackets)", "", "| method | calibration | " + " | ".join(floors) + " |",
              "|---|---|" + "---|" * len(floors)]
    for name, m in result["methods"].items():
        for label, part in (("posterior's own", m["posterior"]["floors"]),
                            ("distance only, LOFO", m["lofo_distance_only"]["floors"]),
                            ("**with fix sd, LOFO**", m["lofo"]["floors"]),
                            ("with fix sd, all-floor choice", m["all_floors"]["floors"])):
            cells = [f"{part[f]['coverage']:.2f} ({part[f]['median_radius_m']:.1f})" if f in part else "-"
                     for f in floors]
            lines.append(f"| {name} | {label} | " + " | ".join(cells) + " |")
    edges = FIX_SD_BINS_M
    heads = [f"{lo:g}-{hi:g}" if math.isfinite(hi) else f">= {lo:g}" for lo, hi in zip(edges[:-1], edges[1:])]
    for name, m in result["methods"].items():
        lines += ["", f"{name}: median error [m] (waypoints) by the sd s [m] of the fix nearest in time", "",
                  "| floor | " + " | ".join(heads) + " |", "|---|" + "---|" * len(heads)]
        for f, v in m["error_by_fix_sd"].items():
            cells = ["-" if e is None else f"{e:.1f} ({n})" for e, n in zip(v["median_error_m"], v["waypoints"])]
            lines.append(f"| {f} | " + " | ".join(cells) + " |")
    lines += ["", "Chosen per held-out floor (a, b, g, h, s0):", ""]
    for name, m in result["methods"].items():
        cells = [f"{f} {_choice(v['chosen'])}" for f, v in m["lofo"]["floors"].items()]
        lines.append(f"- {name}: " + "; ".join(cells))
    lines += ["", f"{result['seconds']:.0f} s."]
    return "\n".join(lines) + "\n"


def main(argv: Optional[List[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m indoorloc.experiments.fusion_uncertainty", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data-root", type=Path, default=None, help="ILC site folder (default: the shared one)")
    ap.add_argument("--floors", nargs="*", default=[], help="floor folders (default: every one)")
    ap.add_argument("--out", type=Path, default=None, help="write OUT.json and OUT.md")
    ap.add_argument("--quiet", action="store_true", help="no progress bars or lines")
    args = ap.parse_args(argv)
    _progress.set_quiet(args.quiet)
    result = run(args.data_root, args.floors)
    text = markdown(result)
    print(text)
    if args.out:
        from indoorloc.io.atomic_file import write_text_atomic

        args.out.parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(args.out.with_suffix(".json"), json.dumps(result, indent=1))
        write_text_atomic(args.out.with_suffix(".md"), text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
