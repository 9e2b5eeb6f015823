"""``indoorloc fusion evaluate --seed S1 S2 ...``: the evaluation over several fold partitions and
the spread of each figure across them. Why: which walks of a floor train and which are scored
changes the survey coverage of the scored waypoints, and on the shared site one partition
(seed 0) is the most favourable of four for the default tracker (docs/fusion_real.md); a figure
from one partition says little without the others.

The JSON document of several seeds (:func:`seeds_document`, docs/fusion_real.md, "Several fold
seeds"): ``{"schema": "indoorloc.fusion_evaluate_seeds", "version": 1, "seeds": [...],
"spread": {...}, "runs": {"<seed>": <the one-seed document>}}``; one seed keeps the one-seed
document unchanged."""

from __future__ import annotations

from typing import Dict, List, Mapping

import numpy as np

SCHEMA = "indoorloc.fusion_evaluate_seeds"
VERSION = 1


def _spread(values: List[float]) -> Dict[str, object]:
    a = np.asarray(values, dtype=float)
    return {"per_seed": [float(v) for v in a], "mean": float(a.mean()),
            "sd": float(a.std(ddof=1)) if a.size > 1 else 0.0, "min": float(a.min()), "max": float(a.max())}


def seed_spread(runs: Mapping[int, dict]) -> dict:
    """Per method the pooled mean error [m] of every seed's run (``runs``: seed -> the one-seed
    document of :func:`indoorloc.experiments.fusion_real.summarize`), with its mean, sample sd,
    min and max over the seeds; the same for each floor's mean and for the floor-identification
    accuracy (fraction of waypoints) where present. Methods missing from a run are left out."""
    seeds = sorted(runs)
    if not seeds:
        raise ValueError("indoorloc: argument 'runs': needs at least one seed's result")
    first = runs[seeds[0]]
    methods = [m for m in first["methods"] if all(m in runs[s]["methods"] for s in seeds)]
    out: Dict[str, object] = {
        "seeds": seeds,
        "methods": {m: {"mean_m": _spread([runs[s]["methods"][m]["mean_m"] for s in seeds])} for m in methods},
        "per_floor": {},
    }
    for m in methods:
        floors = [f for f in first["per_floor"] if all(m in runs[s]["per_floor"].get(f, {}) for s in seeds)]
        out["per_floor"][m] = {f: _spread([runs[s]["per_floor"][f][m]["mean_m"] for s in seeds]) for f in floors}
    if all("floor_identification" in runs[s] for s in seeds):
        out["floor_identification_accuracy"] = _spread([runs[s]["floor_identification"]["accuracy"] for s in seeds])
    return out


def seeds_document(runs: Mapping[int, dict]) -> dict:
    """The JSON document of an evaluation over several seeds (module docstring)."""
    return {"schema": SCHEMA, "version": VERSION, "seeds": sorted(runs), "spread": seed_spread(runs),
            "runs": {str(s): runs[s] for s in sorted(runs)}}


def spread_markdown(spread: dict) -> str:
    """The spread over seeds as Markdown: per method the mean [m] of each seed and their mean ± sd."""
    seeds = spread["seeds"]
    lines = ["Mean error [m] per fold seed (which walks train and which are scored):", "",
             "| method | " + " | ".join(f"seed {s}" for s in seeds) + " | mean ± sd | range |",
             "|---|" + "---|" * (len(seeds) + 2)]
    for name, m in spread["methods"].items():
        v = m["mean_m"]
        lines.append(f"| {name} | " + " | ".join(f"{x:.2f}" for x in v["per_seed"])
                     + f" | {v['mean']:.2f} ± {v['sd']:.2f} | {v['min']:.2f}-{v['max']:.2f} |")
    fi = spread.get("floor_identification_accuracy")
    if fi:
        lines += ["", "Floor identification per seed: " + ", ".join(f"{100 * x:.1f} %" for x in fi["per_seed"])
                  + f" (mean {100 * fi['mean']:.1f} %)."]
    return "\n".join(lines)


__all__ = ["SCHEMA", "VERSION", "seed_spread", "seeds_document", "spread_markdown"]
