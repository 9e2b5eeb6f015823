"""The compiled shared-AP matcher against the numpy/scipy version it replaced, on the ILC site.

``python -m indoorloc.experiments.wifi_matcher_agreement [--data-root DIR] [--floors B1 F1 ...]``

Per floor, every 4th walk is a test walk and the others build the fix database (default
``FixSettings``). For every query of the test walks: the k nearest by the numpy path
(``wifi_matcher.shared_dissimilarity_numpy`` + ``wifi_matcher.knn``, the code before the compiled
matcher) and by the compiled path (``wifi_fixes.nearest``), and the fixes of
``wifi_fixes.fixes_for_walk`` against fixes built from the numpy kNN. Prints a JSON summary:
largest differences in d [dB], weights and σ [m]; fixes whose components differ only in order
(exact ties), fixes where a tied reference at the k-th place differs; time of each path.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Dict, Optional, Sequence

import numpy as np

from indoorloc import fusion
from indoorloc.fusion import wifi_fixes
from indoorloc.wifi import matcher as wifi_matcher
from indoorloc import progress as _progress


def compare_floor(root: Path, name: str, out: Dict[str, float]) -> None:
    """Adds floor ``name``'s comparison to the running summary ``out``."""
    from indoorloc.experiments import fusion_real as fr

    fl = fr.load_floor(root, name)
    test = set(range(0, len(fl.walks), 4))
    train = [w for i, w in enumerate(fl.walks) if i not in test]
    steps = [s for i, s in enumerate(fl.steps) if i not in test]
    db = wifi_fixes.build_database(train, wifi_fixes.FixSettings(), steps, floors=[fl.number] * len(train))
    s = db.settings
    for i in sorted(test):
        t, rss = wifi_fixes.walk_queries(fl.walks[i], db)
        if t.size == 0:
            continue
        tic = time.perf_counter()
        d_numpy = wifi_matcher.shared_dissimilarity_numpy(rss, db.index, s.penalty_db)
        b0, d0, w0 = wifi_matcher.knn(d_numpy, s.k, s.temperature_db)
        toc = time.perf_counter()
        b1, d1, w1 = wifi_fixes.nearest(rss, db)
        out["numpy_s"] += toc - tic
        out["compiled_s"] += time.perf_counter() - toc
        out["pairs"] += rss.shape[0] * db.n_scans
        fin = np.isfinite(d0)
        if not np.array_equal(fin, np.isfinite(d1)):
            raise RuntimeError(f"indoorloc: {name} walk {i}: the two paths disagree on which d are finite")
        out["max_d_diff_db"] = max(out["max_d_diff_db"], float(np.abs(np.where(fin, d0 - d1, 0.0)).max()))
        fx = wifi_fixes.fixes_for_walk(fl.walks[i], db).as_arrays()
        ref = fusion.Fixes.from_arrays(t, db.positions_m[b0], wifi_fixes.fix_sds(d0[:, 0], s), w0, db.floors[b0]).as_arrays()
        wa, wb = np.asarray(fx[3]), np.asarray(ref[3])
        out["max_weight_diff"] = max(out["max_weight_diff"], float(np.abs(wa - wb).max()))
        out["max_sd_diff_m"] = max(out["max_sd_diff_m"], float(np.abs(np.asarray(fx[2]) - np.asarray(ref[2])).max()))
        n = wa.shape[0]
        ma, mb = np.asarray(fx[1]).reshape(n, -1, 2), np.asarray(ref[1]).reshape(n, -1, 2)
        for r in range(n):
            ka = sorted(zip(np.round(wa[r], 6), map(tuple, np.round(ma[r], 6))))
            kb = sorted(zip(np.round(wb[r], 6), map(tuple, np.round(mb[r], 6))))
            if ka != kb:
                out["fixes_other_tied_reference"] += 1
            elif not np.array_equal(ma[r], mb[r]):
                out["fixes_reordered_ties"] += 1
        out["fixes"] += n
        out["walks"] += 1


def run(data_root: Optional[Path] = None, floors: Sequence[str] = ("B1", "F1", "F3", "F4", "F7", "F8")) -> dict:
    from indoorloc.experiments import fusion_real as fr

    root = Path(data_root) if data_root else fr.default_site_root()
    out = {k: 0.0 for k in ("numpy_s", "compiled_s", "pairs", "max_d_diff_db", "max_weight_diff", "max_sd_diff_m")}
    out.update({k: 0 for k in ("fixes", "walks", "fixes_reordered_ties", "fixes_other_tied_reference")})
    for name in floors:
        compare_floor(root, name, out)
    out["numpy_pairs_per_s"] = out["pairs"] / max(out["numpy_s"], 1e-12)
    out["compiled_pairs_per_s"] = out["pairs"] / max(out["compiled_s"], 1e-12)
    out["floors"] = list(floors)
    return out


def main(argv: Optional[Sequence[str]] = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--data-root", default=None)
    p.add_argument("--floors", nargs="+", default=["B1", "F1", "F3", "F4", "F7", "F8"])
    p.add_argument("--quiet", action="store_true", help="no progress bars or lines")
    args = p.parse_args(argv)
    _progress.set_quiet(args.quiet)
    print(json.dumps(run(args.data_root, args.floors), indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
