"""Study: interpolated WiFi references on sparsely surveyed floors (issue 25, "the best WiFi-only
method <= 0.8x today's wifi_knn on every floor"; docs/fusion_real.md, "Interpolated references").

``python -m indoorloc.experiments.wifi_interpolated_refs [--data-root DIR] [--floors B1 F1 ...]
[--cache-dir DIR] [--json FILE] [--markdown FILE]``

Per floor, 4-fold cross-validation by walk (seed 0, the folds of ``indoorloc fusion evaluate``);
every test waypoint is scored with the WiFi-only fix nearest in time (the ``wifi_knn`` protocol:
the weighted centre of the k best references of the default matcher, ``wifi_fixes.FixSettings()``).

Candidate: extra references on a lattice over the walkable plan, where the survey is absent
(between ``min_gap_m`` and ``reach_m`` from every training reference), each AP's RSS predicted by
Gaussian-kernel regression over the training references (length scale ``scale_m``): heard where
the kernel-weighted fraction of references that heard it is >= 1/2, its RSS the kernel-weighted
mean of theirs. They join the matcher's references; in the centre each counts ``weight`` times a
surveyed one. The lattice, the kernel and the weight are chosen by leave-one-floor-out over the
floors given (per held-out floor the grid point with the lowest pooled mean error over the other
floors, scored on it); the baseline (no extra reference) is one point of the grid, so LOFO can
refuse the idea. Reported: per floor the baseline, the LOFO choice and its error, pooled and by
coverage (test waypoint to the nearest training reference <= 5, 5-10, > 10 m).
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

from indoorloc import progress as _progress

import numpy as np
from indoorloc.io.atomic_file import write_text_atomic

GRID = {
    "scale_m": (2.0, 3.0, 6.0),      #: kernel length scale [m]
    "reach_m": (8.0, 15.0, 25.0),    #: extra references at most this far from the survey [m]
    "weight": (0.5, 1.0),            #: an extra reference's weight in the centre (a surveyed one: 1)
}
SPACING_M = 2.0    #: lattice step of the extra references [m] (fixed in advance: the grid tracker's 2 m fix grid)
MIN_GAP_M = 2.0    #: no extra reference closer than this to a training one [m] (fixed: the lattice step)
BASELINE = "baseline"


def lattice(plan, positions_m: np.ndarray, reach_m: float) -> np.ndarray:
    """Walkable lattice points (M, 2) [m] between MIN_GAP_M and reach_m from every reference."""
    from scipy.spatial import cKDTree

    lo = positions_m.min(axis=0) - reach_m
    hi = positions_m.max(axis=0) + reach_m
    xs = np.arange(lo[0], hi[0] + 1e-9, SPACING_M)
    ys = np.arange(lo[1], hi[1] + 1e-9, SPACING_M)
    g = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    d = cKDTree(positions_m).query(g)[0]
    g = g[(d >= MIN_GAP_M) & (d <= reach_m)]
    if g.size == 0:
        return g.reshape(0, 2)
    return g[np.asarray(plan.is_walkable(g), bool)]


def interpolated_refs(rss_dbm: np.ndarray, positions_m: np.ndarray, points_m: np.ndarray, scale_m: float,
                      min_aps: int = 3):
    """(rss (M', K), points (M', 2)): the kernel-regression fingerprints of the points with at least
    min_aps APs heard (module docstring)."""
    from scipy import sparse
    from scipy.spatial import cKDTree

    if points_m.shape[0] == 0:
        return np.zeros((0, rss_dbm.shape[1])), points_m
    pairs = cKDTree(points_m).sparse_distance_matrix(cKDTree(positions_m), 3.0 * scale_m, output_type="coo_matrix")
    w = sparse.csr_matrix((np.exp(-0.5 * (pairs.data / scale_m) ** 2), (pairs.row, pairs.col)),
                          shape=(points_m.shape[0], positions_m.shape[0]))
    heard = np.isfinite(rss_dbm)
    h = sparse.csr_matrix(heard.astype(float))
    v = sparse.csr_matrix(np.where(heard, rss_dbm, 0.0))
    total = np.asarray(w.sum(axis=1)).ravel()
    wh = (w @ h).toarray()
    wv = (w @ v).toarray()
    frac = wh / np.maximum(total, 1e-300)[:, None]
    out = np.where((frac >= 0.5) & (wh > 0), wv / np.maximum(wh, 1e-300), np.nan)
    keep = np.isfinite(out).sum(axis=1) >= min_aps
    return out[keep], points_m[keep]


def _centres(positions_m, weight_of_ref, best, w):
    from indoorloc.experiments.wifi_matcher_study import weighted_centres

    return weighted_centres(positions_m, best, w * weight_of_ref[best])


def floor_errors(walks, plan, log=print) -> Dict[str, Any]:
    """Waypoint errors of the baseline and every grid point on one floor (4-fold), with coverage."""
    from scipy.spatial import cKDTree

    from indoorloc._core.wifi import SharedApMatcher
    from indoorloc.experiments.wifi_matcher_study import _folds, fold_queries, waypoint_errors
    from indoorloc.fusion import wifi_fixes

    s = wifi_fixes.FixSettings()
    out: Dict[str, List[np.ndarray]] = {}
    coverage, extra_counts = [], []
    for j, test_idx in enumerate(_folds(len(walks), 4, 0)):
        test_set = set(test_idx.tolist())
        train = [w for i, w in enumerate(walks) if i not in test_set]
        test = [walks[i] for i in test_idx]
        db = wifi_fixes.build_database(train, s, positions_at=[w.positions_at for w in train])
        q = fold_queries(test, db)
        matcher = db.index.matcher(s.penalty_db, s.k, s.temperature_db)
        best, _, w = matcher.nearest(q.rss_dbm, 2)
        ones = np.ones(db.n_scans)
        out.setdefault(BASELINE, []).append(waypoint_errors(q, _centres(db.positions_m, ones, best, w)))
        coverage.append(cKDTree(db.positions_m).query(q.wp_xy_m)[0])
        opts = matcher.options
        for reach in GRID["reach_m"]:
            pts = lattice(plan, db.positions_m, reach)
            for scale in GRID["scale_m"]:
                rss_x, pts_x = interpolated_refs(db.rss_dbm, db.positions_m, pts, scale, s.min_aps)
                extra_counts.append(rss_x.shape[0])
                m2 = SharedApMatcher(np.vstack([db.rss_dbm, rss_x]), np.asarray(db.index.g, float), opts)
                best2, _, w2 = m2.nearest(q.rss_dbm, 2)
                pos2 = np.vstack([db.positions_m, pts_x])
                for weight in GRID["weight"]:
                    wr = np.r_[ones, np.full(rss_x.shape[0], weight)]
                    key = f"reach_m={reach},scale_m={scale},weight={weight}"
                    out.setdefault(key, []).append(waypoint_errors(q, _centres(pos2, wr, best2, w2)))
        log(f"  fold {j}: {len(train)} train walks, {db.n_scans} references, extra {extra_counts[-9:]}")
    return {"errors": {k: np.concatenate(v) for k, v in out.items()}, "coverage_m": np.concatenate(coverage)}


def _stats(e):
    e = e[np.isfinite(e)]
    return {"mean_m": float(e.mean()), "median_m": float(np.median(e)), "p90_m": float(np.percentile(e, 90)),
            "n": int(e.size)} if e.size else {"mean_m": float("nan"), "n": 0}


def run(data_root: Path, floors: Sequence[str], cache_dir: Path, log=print) -> Dict[str, Any]:
    from indoorloc.experiments.wifi_matcher_study import cache_floor
    from indoorloc.io import load_floor_plan
    from indoorloc.io.survey_layout import survey_floors

    per: Dict[str, Any] = {}
    for name in floors:
        walks, skipped = cache_floor(data_root, name, cache_dir, log=log)
        (survey,) = survey_floors(Path(data_root), [name], argument="data_root")
        plan = load_floor_plan(survey.geojson_path, floors=[survey.number], origin_lon_lat="outline_sw")
        per[name] = floor_errors(walks, plan, log=log)
    keys = list(per[floors[0]]["errors"].keys())
    sums = {f: np.array([np.nansum(per[f]["errors"][k]) for k in keys]) for f in floors}
    counts = {f: np.array([np.isfinite(per[f]["errors"][k]).sum() for k in keys]) for f in floors}
    res: Dict[str, Any] = {"grid": {k: list(v) for k, v in GRID.items()}, "per_floor": {}}
    held, base = [], []
    for f in floors:
        others = [g for g in floors if g != f]
        mean_other = sum(sums[g] for g in others) / np.maximum(sum(counts[g] for g in others), 1)
        kb = keys[int(np.argmin(mean_other))]
        e, b, cov = per[f]["errors"][kb], per[f]["errors"][BASELINE], per[f]["coverage_m"]
        by_cov = {}
        for label, m in (("<=5m", cov <= 5), ("5-10m", (cov > 5) & (cov <= 10)), (">10m", cov > 10)):
            by_cov[label] = {"baseline": _stats(b[m]), "chosen": _stats(e[m])}
        res["per_floor"][f] = {"chosen": kb, "lofo": _stats(e), "baseline": _stats(b), "by_coverage": by_cov,
                               "all_points": {k: _stats(per[f]["errors"][k])["mean_m"] for k in keys}}
        held.append(e)
        base.append(b)
    res["pooled"] = {"lofo": _stats(np.concatenate(held)), "baseline": _stats(np.concatenate(base))}
    return res


def markdown(r: Dict[str, Any]) -> str:
    lines = ["| floor | baseline (default matcher) | LOFO choice | held-out error | ratio | > 10 m from survey: baseline -> chosen |",
             "|---|---|---|---|---|---|"]
    for f, d in r["per_floor"].items():
        b, e = d["baseline"], d["lofo"]
        far = d["by_coverage"][">10m"]
        lines.append(f"| {f} | {b['mean_m']:.2f} / {b['median_m']:.2f} / {b['p90_m']:.2f} | {d['chosen']} | "
                     f"{e['mean_m']:.2f} / {e['median_m']:.2f} / {e['p90_m']:.2f} | {e['mean_m'] / b['mean_m']:.3f} | "
                     f"{far['baseline'].get('mean_m', float('nan')):.2f} -> {far['chosen'].get('mean_m', float('nan')):.2f} "
                     f"(n {far['baseline']['n']}) |")
    p = r["pooled"]
    lines.append(f"| pooled | {p['baseline']['mean_m']:.2f} | | {p['lofo']['mean_m']:.2f} | "
                 f"{p['lofo']['mean_m'] / p['baseline']['mean_m']:.3f} | |")
    lines += ["", "Every grid point's mean error per floor [m]:", "",
              "| point | " + " | ".join(r["per_floor"]) + " |", "|---|" + "---|" * len(r["per_floor"])]
    keys = list(next(iter(r["per_floor"].values()))["all_points"])
    for k in keys:
        lines.append(f"| {k} | " + " | ".join(f"{d['all_points'][k]:.2f}" for d in r["per_floor"].values()) + " |")
    return "\n".join(lines)


def main(argv: Optional[Sequence[str]] = None) -> int:
    here = Path(__file__).resolve()
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--data-root", type=Path, default=here.parents[4] / "shared" / "data" / "fusion" / "ilc2020_site2")
    p.add_argument("--floors", nargs="+", default=["B1", "F1", "F3", "F4", "F7", "F8"])
    p.add_argument("--cache-dir", type=Path, default=Path("/tmp/indoorloc_wifi_study_cache"))
    p.add_argument("--json", type=Path)
    p.add_argument("--markdown", type=Path)
    p.add_argument("--quiet", action="store_true", help="no progress bars or lines")
    a = p.parse_args(argv)
    _progress.set_quiet(a.quiet)
    r = run(a.data_root, a.floors, a.cache_dir, log=lambda m: print(m, file=sys.stderr, flush=True))
    md = markdown(r)
    print(md)
    if a.json:
        write_text_atomic(a.json, json.dumps(r, indent=2))
    if a.markdown:
        write_text_atomic(a.markdown, md + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
