"""How the fusion tracker's defaults were chosen: a grid search on tuning seeds.

The synthetic table (``indoorloc fusion synthetic``) scores seeds 0..N-1; the defaults were chosen
here on seeds 1000..1019 (``fusion_synthetic.TUNING_SEEDS``), disjoint from them. The criterion
is the mean over walks of the per-walk mean error of the two causal filters (known and unknown
start, plan + WiFi); the smoother and the ablations are not looked at.
"""

from __future__ import annotations

import itertools
from typing import Dict, List, Sequence

import numpy as np

from indoorloc import fusion
from indoorloc.experiments import fusion_synthetic as fs

#: The grids, searched in turn (the rest of TrackerOptions at its defaults at the time). Round 1
#: found its best at the grid's edges (smallest τ, largest σ_o and σ_p); round 2 extends past
#: them and adds the stride-scale walk.
GRIDS: Dict[int, Dict[str, Sequence[float]]] = {
    1: {
        "tempering": (0.1, 0.2, 0.4, 0.7),
        "heading_offset_walk_rad": tuple(np.deg2rad([0.25, 0.5, 1.0])),
        "position_noise_m": (0.05, 0.15),
    },
    2: {
        "tempering": (0.05, 0.1),
        "heading_offset_walk_rad": tuple(np.deg2rad([1.0, 2.0])),
        "position_noise_m": (0.15, 0.3),
        "scale_walk": (0.003, 0.01),
    },
}
GRID = GRIDS[1]
CRITERION = ("fusion_known_start", "fusion_unknown_start")


def grid_search(seeds: Sequence[int] = fs.TUNING_SEEDS, threads: int = 2, grid: Dict[str, Sequence[float]] = GRID) -> List[dict]:
    """Every grid point on every seed; rows sorted by the criterion (best first)."""
    names = list(grid)
    rows = []
    for values in itertools.product(*(grid[n] for n in names)):
        settings = dict(zip(names, (float(v) for v in values)))
        options = fusion.tracker_options(**settings)
        results = fs.run_walks(seeds, options, threads=threads, methods=CRITERION)
        per_method = {m: float(np.mean([r.errors_m[m].mean() for r in results])) for m in CRITERION}
        rows.append({**settings, **{f"{m}_mean_m": v for m, v in per_method.items()},
                     "criterion_m": float(np.mean(list(per_method.values())))})
    rows.sort(key=lambda r: r["criterion_m"])
    return rows


def markdown_table(rows: List[dict]) -> str:
    names = [k for k in rows[0] if not k.endswith("_mean_m") and k != "criterion_m"] if rows else []
    head = "| " + " | ".join(names) + " | known start [m] | unknown start [m] | criterion [m] |"
    lines = [head, "|" + "---|" * (len(names) + 3)]
    for r in rows:
        cells = [f"{r[n]:.4g}" for n in names]
        lines.append("| " + " | ".join(cells) + f" | {r['fusion_known_start_mean_m']:.3f} | "
                     f"{r['fusion_unknown_start_mean_m']:.3f} | {r['criterion_m']:.3f} |")
    return "\n".join(lines)
