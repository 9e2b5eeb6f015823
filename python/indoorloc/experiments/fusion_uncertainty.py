"""Honest uncertainty of the grid tracker: the calibration of its returned covariances, chosen by
leave-one-floor-out on the shared mall (docs/fusion_real.md, "Honest uncertainty").

The posterior's own spread is that of the model, which knows nothing of its misfits: on the six
shared floors (4-fold by walk) its 95 % ellipse holds the truth at 43 % of the smoother's waypoints
and 55 % of the causal filter's. The tracker returns instead (``GridTrackerOptions``)

    Σ' = a Σ + (b² + (g d)²) I,

Σ the posterior covariance and d [m] the distance from the estimate to the centre of the WiFi fix
nearest in time (the filter: the last fix applied): a track far from its fixes is less certain
than its posterior says. For each method (causal filter, smoother, known start) this study
scores every waypoint once (``indoorloc fusion evaluate``'s folds and settings), then for each
held-out floor chooses (a, b, g) on the other five floors over :data:`GRID` as the smallest median
region (area) whose coverage on those floors is at least :data:`TARGET`, and reports the held-out
floor's coverage with it; the all-floor choice is what the defaults take.

Run: ``python -m indoorloc.experiments.fusion_uncertainty [--data-root DIR] [--floors ...]
[--out benchmarks/results/fusion_uncertainty]`` (about 3 minutes on 2 cores for the six floors).
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

#: The methods whose returned covariance is calibrated (the grid engine's).
METHODS = ("fusion_unknown_start", "fusion_smoother", "fusion_known_start")
#: The target coverage of the 95 % region on the training floors.
TARGET = 0.95
#: χ²₂(0.95): the 95 % ellipse is e' Σ'⁻¹ e <= this.
CHI2_95 = 5.991464547107979
#: Candidate (a, b [m], g): scales of the posterior, floors of the sd, gains of the fix distance.
GRID = {
    "scale": (1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0, 64.0),
    "floor_m": (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0),
    "fix_gain": (0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5),
}


def calibrated(cov: np.ndarray, d: np.ndarray, scale: float, floor_m: float, fix_gain: float) -> np.ndarray:
    """Σ' (N, 3) = a Σ + (b² + (g d)²) I of posterior covariances ``cov`` (N, 3) = (xx, xy, yy) [m²]
    and fix distances ``d`` (N,) [m] (the formula of ``GridTrackerOptions``)."""
    iso = floor_m ** 2 + (fix_gain * d) ** 2
    return np.stack([scale * cov[:, 0] + iso, scale * cov[:, 1], scale * cov[:, 2] + iso], axis=1)


def coverage_and_area(error_m: np.ndarray, cov: np.ndarray) -> tuple:
    """(inside (N,) bool: the error in the 95 % ellipse of cov (N, 3); area (N,) of the ellipse [m²])."""
    xx, xy, yy = cov[:, 0], cov[:, 1], cov[:, 2]
    det = np.maximum(xx * yy - xy * xy, 1e-300)
    ex, ey = error_m[:, 0], error_m[:, 1]
    mahalanobis2 = (yy * ex * ex - 2.0 * xy * ex * ey + xx * ey * ey) / det
    return mahalanobis2 <= CHI2_95, math.pi * CHI2_95 * np.sqrt(det)


def choose(error_m: np.ndarray, cov: np.ndarray, d: np.ndarray, target: float = TARGET) -> Dict[str, float]:
    """The (a, b, g) of :data:`GRID` with the smallest median 95 % region whose coverage is at
    least ``target`` (the largest coverage if none reaches it)."""
    best, fallback = None, None
    for a, b, g in itertools.product(GRID["scale"], GRID["floor_m"], GRID["fix_gain"]):
        inside, area = coverage_and_area(error_m, calibrated(cov, d, a, b, g))
        cover, size = float(inside.mean()), float(np.median(area))
        if cover >= target and (best is None or size < best[0]):
            best = (size, a, b, g)
        if fallback is None or cover > fallback[0]:
            fallback = (cover, a, b, g)
    _, a, b, g = best if best is not None else fallback
    return {"scale": a, "floor_m": b, "fix_gain": g}


def _summary(error_m: np.ndarray, cov: np.ndarray) -> Dict[str, float]:
    inside, area = coverage_and_area(error_m, cov)
    return {"coverage": float(inside.mean()), "median_radius_m": float(np.sqrt(np.median(area) / math.pi)),
            "waypoints": int(inside.size)}


def study(scores: Sequence[fusion_real.WalkScore], methods: Sequence[str] = METHODS) -> dict:
    """Leave-one-floor-out choice and held-out coverage per method, from walk scores with
    ``calibration_inputs`` (``fusion_real.evaluate_floors``)."""
    out: Dict[str, dict] = {}
    for name in methods:
        rows = [(s.floor, s.calibration_inputs[name]) for s in scores if name in s.calibration_inputs]
        if not rows:
            continue
        floor = np.concatenate([np.full(len(r["fix_distance_m"]), f) for f, r in rows])
        e = np.concatenate([r["error_m"] for _, r in rows])
        cov = np.concatenate([r["posterior_covariance_m2"] for _, r in rows])
        d = np.concatenate([r["fix_distance_m"] for _, r in rows])
        held_inside = np.zeros(floor.size, bool)
        held_area = np.zeros(floor.size)
        per_floor = {}
        for f in sorted(set(floor.tolist())):
            train, test = floor != f, floor == f
            if not train.any():
                continue
            c = choose(e[train], cov[train], d[train])
            inside, area = coverage_and_area(e[test], calibrated(cov[test], d[test], **c))
            held_inside[test], held_area[test] = inside, area
            per_floor[f] = {"chosen": c, **_summary(e[test], calibrated(cov[test], d[test], **c))}
        chosen = choose(e, cov, d)
        out[name] = {
            "posterior": _summary(e, cov),
            "lofo": {"coverage": float(held_inside.mean()),
                     "median_radius_m": float(np.sqrt(np.median(held_area) / math.pi)),
                     "coverage_min_floor": min(v["coverage"] for v in per_floor.values()),
                     "coverage_max_floor": max(v["coverage"] for v in per_floor.values()),
                     "floors": per_floor},
            "all_floors": {"chosen": chosen, **_summary(e, calibrated(cov, d, **chosen))},
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
    return {"study": "fusion_uncertainty", "version": 1, "floors": [fl.name for fl in data],
            "folds": settings.folds, "seed": settings.seed, "target": TARGET,
            "grid": {k: list(v) for k, v in GRID.items()}, "methods": result,
            "seconds": time.perf_counter() - tic}


def markdown(result: dict) -> str:
    lines = [f"# Calibration of the grid tracker's covariance (leave-one-floor-out, floors "
             f"{' '.join(result['floors'])}, {result['folds']}-fold by walk)", "",
             "Σ' = a Σ + (b² + (g d)²) I; per held-out floor (a, b, g) chosen on the other floors as the "
             f"smallest median 95 % region with coverage >= {result['target']:.2f} there.", "",
             "| method | posterior's own coverage | LOFO coverage (min-max floor) | LOFO median radius [m] "
             "| all-floor choice (a, b, g) | its coverage |", "|---|---|---|---|---|---|"]
    for name, m in result["methods"].items():
        c = m["all_floors"]["chosen"]
        lines.append(f"| {name} | {m['posterior']['coverage']:.3f} | {m['lofo']['coverage']:.3f} "
                     f"({m['lofo']['coverage_min_floor']:.2f}-{m['lofo']['coverage_max_floor']:.2f}) | "
                     f"{m['lofo']['median_radius_m']:.1f} | ({c['scale']:g}, {c['floor_m']:g}, {c['fix_gain']:g}) | "
                     f"{m['all_floors']['coverage']:.3f} |")
    lines += ["", "Per held-out floor: coverage (a, b, g chosen without it)", ""]
    for name, m in result["methods"].items():
        cells = [f"{f} {v['coverage']:.2f} ({v['chosen']['scale']:g}, {v['chosen']['floor_m']:g}, "
                 f"{v['chosen']['fix_gain']:g})" for f, v in m["lofo"]["floors"].items()]
        lines.append(f"- {name}: " + "; ".join(cells))
    lines += ["", f"{result['seconds']:.0f} s."]
    return "\n".join(lines) + "\n"


def main(argv: Optional[List[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m indoorloc.experiments.fusion_uncertainty", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data-root", type=Path, default=None, help="ILC site folder (default: the shared one)")
    ap.add_argument("--floors", nargs="*", default=[], help="floor folders (default: every one)")
    ap.add_argument("--out", type=Path, default=None, help="write OUT.json and OUT.md")
    args = ap.parse_args(argv)
    result = run(args.data_root, args.floors)
    text = markdown(result)
    print(text)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        tmp = args.out.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(result, indent=1))
        tmp.replace(args.out.with_suffix(".json"))
        args.out.with_suffix(".md").write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
