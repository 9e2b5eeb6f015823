"""The previous WiFi-only matcher (``wifi_matcher_study.OLD``: fresh scans, strongest 10 APs, k 8),
the ``wifi_knn`` of issue 25's baseline, on every walk of the given floors: 4-fold by walk, seed 0
(the folds of ``indoorloc fusion evaluate``), each test waypoint scored with the fix nearest in
time. Issue 25's goal "the best WiFi-only method <= 0.8x today's wifi_knn on every floor" is read
against these figures (docs/fusion_real.md, "WiFi as fixes").

``python -m indoorloc.experiments.wifi_previous_matcher [--data-root DIR] [FLOOR ...]``
"""

from __future__ import annotations

import argparse
from typing import Optional, Sequence

import numpy as np

from indoorloc.fusion import wifi_fixes as wfx
from indoorloc.experiments import fusion_real as fr
from indoorloc.experiments.wifi_matcher_study import OLD
from indoorloc import progress as _progress


def floor_errors(fl: fr.FloorData, folds: int = 4, seed: int = 0) -> np.ndarray:
    """Waypoint errors [m] of the previous matcher on one floor (walks without a fix skipped)."""
    errors = []
    for test in fr._folds(len(fl.walks), folds, seed):
        held = set(test.tolist())
        train = [w for i, w in enumerate(fl.walks) if i not in held]
        steps = [s for i, s in enumerate(fl.steps) if i not in held]
        db = wfx.build_database(train, wfx.FixSettings(**OLD), steps, floors=[fl.number] * len(train))
        for i in test:
            walk = fl.walks[i]
            fixes = wfx.fixes_for_walk(walk, db)
            if len(fixes) == 0:
                continue
            wt, wxy = np.asarray(walk.waypoint_t_s, float), np.asarray(walk.waypoint_xy_m, float)
            errors.append(np.hypot(*(fr._nearest_rows(wt, fixes.times_s, wfx.fix_centres(fixes)) - wxy).T))
    return np.concatenate(errors) if errors else np.zeros(0)


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data-root", default=None)
    ap.add_argument("floors", nargs="*")
    ap.add_argument("--quiet", action="store_true", help="no progress bars or lines")
    args = ap.parse_args(argv)
    _progress.set_quiet(args.quiet)
    _, data = fr.load_site(args.data_root, args.floors)
    print("| floor | walks | waypoints | mean [m] | median [m] | p90 [m] |\n|---|---|---|---|---|---|")
    for fl in data:
        e = floor_errors(fl)
        print(f"| {fl.name} | {len(fl.walks)} | {e.size} | {e.mean():.2f} | {np.median(e):.2f} | "
              f"{np.percentile(e, 90):.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
