"""WKNN with its k chosen over shared_knn's wider k grid: how much of shared_knn's gain over WKNN
in ``indoorloc wifi evaluate`` is the larger k (docs/wifi.md, "Shared-AP kNN").

``python -m indoorloc.experiments.wifi_wknn_wide_k [--data-root DIR] DATASET ...``

Per dataset, one scan per estimate: WKNN (``wifi.FingerprintLocator``, method "wknn", on the
prepared raw training scans) with k chosen by leave-one-reference-point-out over 24 seeded
training points (seed 0, the first 24 scans of each, as the command's CV) over
``wifi_evaluate.SHARED_GRID["k"]``, then scored on the test split. Prints one JSON line per dataset.
"""

from __future__ import annotations

import argparse
import json
from typing import Optional, Sequence

import numpy as np

from indoorloc import wifi
from indoorloc.experiments import wifi_evaluate as we
from indoorloc import progress as _progress


def wide_k_wknn(ds, cv_points: int = 24, seed: int = 0) -> dict:
    """{"k", "mean_m", "median_m", "p90_m", "floor_hit_rate"} of WKNN with k chosen by CV."""
    tr = ds.train
    points = np.unique(tr.point_ids)
    held = np.random.default_rng(seed).choice(points, size=min(cv_points, points.size), replace=False)
    grid = we.SHARED_GRID["k"]
    err = {k: [] for k in grid}
    for p in held:
        rows = tr.point_ids != p
        test_rows = np.flatnonzero(~rows)[:24]
        ms = we.MethodSet(tr, ds.not_heard_sentinel, we.Hyper(), rows=rows)
        raw, q = ms.prepare(tr.rss_dbm[rows]), ms.prepare(tr.rss_dbm[test_rows])
        for k in grid:
            loc = wifi.FingerprintLocator(raw, tr.positions_m[rows], tr.floors[rows].astype(float), None,
                                          method="wknn", k=k)
            pos, _, _ = loc.locate(q)
            err[k].append(float(np.linalg.norm(pos - tr.positions_m[test_rows], axis=1).mean()))
    best = min(grid, key=lambda k: np.mean(err[k]))
    hyper = we.Hyper()
    hyper.k = dict(hyper.k, wknn=best)
    row = we.evaluate(ds, 1, hyper, methods=["wknn"])["wknn"].row()
    return {"k": int(best), **{key: row[key] for key in ("mean_m", "median_m", "p90_m", "floor_hit_rate")}}


def main(argv: Optional[Sequence[str]] = None) -> int:
    from indoorloc.io.wifi_datasets import load_wifi_dataset
    from indoorloc.registry import default_data_root

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("datasets", nargs="+")
    p.add_argument("--data-root", default=None)
    p.add_argument("--quiet", action="store_true", help="no progress bars or lines")
    args = p.parse_args(argv)
    _progress.set_quiet(args.quiet)
    root = args.data_root or default_data_root()
    for name in args.datasets:
        print(json.dumps({"dataset": name, **wide_k_wknn(load_wifi_dataset(name, root))}), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
