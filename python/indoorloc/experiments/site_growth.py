"""What growing a site map with walks without waypoints buys (``fusion.Site.grow``; issue 26).

Per floor of a survey folder, the walks are split by a seeded permutation into a quarter with
waypoints (the survey), a half used without their waypoints (grown) and a last quarter (scored):

- ``quarter``: the site built from the survey quarter alone;
- ``quarter_grown``: that site grown with the half (placed by the smoothed track where its largest
  posterior sd is at most the threshold; threshold chosen by leave-one-floor-out over
  :data:`THRESHOLDS_M`: for each floor, the threshold with the lowest pooled mean error on the
  other floors);
- ``quarter_plus_half``: the survey quarter plus the half *with* its waypoints (``site add``): the
  ceiling.

The scored quarter is tracked with the floor given; errors at its waypoints (mean / median / p90).
Run: ``python -m indoorloc.experiments.site_growth [SURVEY_DIR] [--floors ...] [--json FILE]``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

from indoorloc.fusion.site import GROW_WEIGHT, Site
from indoorloc.io.survey_layout import survey_floors
from indoorloc import progress as _progress
from indoorloc.io.atomic_file import write_text_atomic

THRESHOLDS_M = (2.0, 4.0, 8.0, 16.0, 32.0)


def _stats(e: np.ndarray) -> Dict[str, float]:
    return {"mean_m": float(np.mean(e)), "median_m": float(np.median(e)), "p90_m": float(np.percentile(e, 90)),
            "n_waypoints": int(e.size)}


def _errors(site: Site, floor: str, walks: Sequence[Path]) -> np.ndarray:
    return np.concatenate([site.track(w, floor=floor).errors_m for w in walks])


def floor_runs(survey_dir: Path, floor: str, seed: int, work: Path, thresholds=THRESHOLDS_M) -> Dict[str, np.ndarray]:
    """The scored quarter's errors [m] per configuration (``grown@T`` per threshold T) on one floor."""
    (fl,) = survey_floors(survey_dir, [floor])
    paths = list(fl.walk_paths)
    perm = np.random.default_rng(seed).permutation(len(paths))
    q = len(paths) // 4
    survey = [paths[i] for i in perm[:q]]
    grow = [paths[i] for i in perm[q:q + len(paths) // 2]]
    test = [paths[i] for i in perm[q + len(paths) // 2:]]
    src = work / floor / "survey" / floor / "path_data_files"
    src.mkdir(parents=True)
    for name in ("geojson_map.json", "floor_info.json"):
        if (fl.plan_dir / name).is_file():
            shutil.copy(fl.plan_dir / name, src.parent / name)
    for p in survey:
        (src / p.name).symlink_to(p.resolve())
    base = Site.build(work / floor / "survey", work / floor / "quarter.db", floors=[floor])
    out = {"quarter": _errors(base, floor, test)}
    for t in thresholds:
        db = work / floor / f"grown_{t:g}.db"
        shutil.copy(base.path, db)
        grown = Site.open(db)
        grown.grow(grow, floor=floor, max_sd_m=t)
        out[f"grown@{t:g}"] = _errors(grown, floor, test)
    db = work / floor / "plus_half.db"
    shutil.copy(base.path, db)
    full = Site.open(db)
    full.add(grow, floor=floor)
    out["quarter_plus_half"] = _errors(full, floor, test)
    return out


def run(survey_dir: Path, floors: Optional[Sequence[str]] = None, seed: int = 0,
        thresholds=THRESHOLDS_M, progress=None) -> dict:
    """Every floor's runs, the leave-one-floor-out threshold and the three figures (module docstring)."""
    names = [f.name for f in survey_floors(survey_dir, floors)]
    per_floor: Dict[str, Dict[str, np.ndarray]] = {}
    with tempfile.TemporaryDirectory(prefix="indoorloc-growth-") as tmp:
        for name in names:
            per_floor[name] = floor_runs(survey_dir, name, seed, Path(tmp), thresholds)
            if progress:
                progress(name)
    chosen, grown = {}, []
    for name in names:
        others = [n for n in names if n != name] or [name]
        best = min(thresholds, key=lambda t: float(np.mean(np.concatenate([per_floor[n][f"grown@{t:g}"] for n in others]))))
        chosen[name] = best
        grown.append(per_floor[name][f"grown@{best:g}"])
    pooled = {k: np.concatenate([per_floor[n][k] for n in names]) for k in per_floor[names[0]]}
    return {"seed": seed, "weight": GROW_WEIGHT, "thresholds_m": list(thresholds), "chosen_threshold_m": chosen,
            "figures": {"quarter": _stats(pooled["quarter"]), "quarter_grown": _stats(np.concatenate(grown)),
                        "quarter_plus_half": _stats(pooled["quarter_plus_half"])},
            "by_threshold": {k: _stats(v) for k, v in pooled.items() if k.startswith("grown@")},
            "per_floor": {n: {k: _stats(v) for k, v in r.items()} for n, r in per_floor.items()}}


def markdown(result: dict) -> str:
    lines = ["| map | mean [m] | median [m] | p90 [m] | waypoints |", "|---|---|---|---|---|"]
    for k, s in list(result["figures"].items()) + [(f"(grown, threshold {k[6:]} m on all floors)", v)
                                                   for k, v in result["by_threshold"].items()]:
        lines.append(f"| {k} | {s['mean_m']:.2f} | {s['median_m']:.2f} | {s['p90_m']:.2f} | {s['n_waypoints']} |")
    lines.append("")
    lines.append("Threshold chosen per held-out floor (leave one floor out): " +
                 ", ".join(f"{k} {v:g} m" for k, v in result["chosen_threshold_m"].items()))
    return "\n".join(lines)


def main(argv: Optional[List[str]] = None) -> int:
    from indoorloc.experiments.fusion_real import default_site_root

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("survey_dir", nargs="?", default=None)
    ap.add_argument("--floors", nargs="+", default=None)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", default=None)
    ap.add_argument("--quiet", action="store_true", help="no progress bars or lines")
    args = ap.parse_args(argv)
    _progress.set_quiet(args.quiet)
    root = Path(args.survey_dir) if args.survey_dir else default_site_root()
    result = run(root, args.floors, args.seed, progress=lambda n: print(f"floor {n} done", flush=True))
    print(markdown(result))
    if args.json:
        write_text_atomic(args.json, json.dumps(result, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
