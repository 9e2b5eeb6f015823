"""Floor identification across fold partitions: which walks fail at each seed and which deciders
generalise (docs/fusion_real.md, "Floor identification across fold seeds").

``python -m indoorloc.experiments.floor_generalization_study --cache DIR [--seed 0 1 2 3]
[--choose-seeds 0 1] [--json FILE] [--markdown FILE]``

Step 1 (slow, cached per seed in ``--cache``): the folds of ``indoorloc fusion evaluate --seed s``
(``floor_identification_study.walk_evidence``: the grid filter's floor evidence, the AP rates',
the classifier's as ``fusion evaluate`` computes them) plus, per test walk, what the deciders below
need: the classifier's per-query log posteriors for every C of :data:`L2_SCALES`, the per-query
AP-rate posteriors, the per-query fingerprint distance to each floor's closest reference, and
diagnostics (queries, APs heard, share of them the survey hears on several floors, distance of the
walk's waypoints to each floor's training references).

Step 2 (seconds): deciders of :data:`DECIDERS` scored per seed. Settings are chosen (most
waypoints right; ties: mean log probability of the true floor) on the walks of ``--choose-seeds``
and scored on the other seeds' walks (held out by partition), and by leave-one-floor-out over all
seeds pooled (held out by floor). A walk of seed 2 and the same walk of seed 0 are the same
recording tested against different training walks: the held-out seeds share the walks, not the
training sets, with the seeds chosen on.
"""

from __future__ import annotations

import argparse
import json
import math
import pickle
import time
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from indoorloc.fusion import floor_classifier, floor_evidence
from indoorloc.experiments import floor_identification_study as fis
from indoorloc.io.atomic_file import write_text_atomic

#: Classifier L2 scales C cached per walk (the study's grid 0.1, 1 and two between/above).
L2_SCALES = (0.1, 0.3, 1.0, 3.0)
#: A floor "hears" an AP when this fraction of its references do (the several-floors diagnostic).
HEARD_RATE = 0.02


def _fold_context(db, plan_floors, classifiers) -> dict:
    """Per fold: the classifiers by C (the study's fits reused), the default rates, the reference
    positions per floor and which APs several floors hear."""
    clf = dict(classifiers)
    for c in L2_SCALES:
        if c not in clf:
            clf[c] = floor_classifier.FloorClassifier.fit(db.rss_dbm, db.floors, plan_floors, c)
    rates = floor_evidence.ApFloorRates.from_references(db.rss_dbm, db.floors, plan_floors, 0.1)
    heard = np.stack([np.isfinite(db.rss_dbm[db.floors == f]).mean(axis=0) if (db.floors == f).any()
                      else np.zeros(db.rss_dbm.shape[1]) for f in plan_floors])
    with np.errstate(all="ignore"):
        top = np.stack([np.nanmax(np.where(np.isfinite(db.rss_dbm[db.floors == f]), db.rss_dbm[db.floors == f], -np.inf),
                                  axis=0) if (db.floors == f).any() else np.full(db.rss_dbm.shape[1], -np.inf)
                        for f in plan_floors])
    return {"classifiers": clf, "rates": rates, "floors": plan_floors, "floors_hearing": (heard >= HEARD_RATE).sum(axis=0),
            "heard_rate": heard, "max_dbm": top,
            "positions": {f: db.positions_m[db.floors == f] for f in plan_floors}}


def _query_floor_distances(db, plan_floors, q: np.ndarray) -> np.ndarray:
    """(Q', F) per query hearing an AP, the ``walk_match_distance_db`` distance to the closest
    reference of each floor [dB] (the median of a column is the walk's match distance)."""
    out = []
    rows = {f: np.flatnonzero(db.floors == f) for f in plan_floors}
    for row in q:
        heard = np.flatnonzero(np.isfinite(row))
        if heard.size == 0:
            continue
        top = heard[np.argsort(-row[heard], kind="stable")[:floor_evidence.MATCH_AP_COUNT]]
        d = []
        for f in plan_floors:
            if rows[f].size == 0:
                d.append(floor_evidence.MATCH_UNHEARD_DB)
                continue
            ref = db.rss_dbm[np.ix_(rows[f], top)]
            d.append(np.where(np.isfinite(ref), np.abs(ref - row[top]), floor_evidence.MATCH_UNHEARD_DB)
                     .mean(axis=1).min())
        out.append(d)
    return np.asarray(out, float).reshape(-1, len(plan_floors))


def _walk_features(rec: dict, walk, q: np.ndarray, db, ctx: dict) -> None:
    """Adds the per-query evidences and diagnostics of a walk (module docstring) to ``rec``."""
    rec["clf_query_logp"] = {c: clf.query_log_posteriors(q)[0] for c, clf in ctx["classifiers"].items()}
    rec["rates_query_logp"] = floor_evidence.query_floor_log_posteriors(ctx["rates"], q, 20)[0]
    rec["query_distance_db"] = _query_floor_distances(db, ctx["floors"], q)
    heard = np.isfinite(q).any(axis=0)
    rec["n_queries"] = int(np.isfinite(q).any(axis=1).sum())
    rec["n_aps"] = int(heard.sum())
    rec["several_floor_ap_share"] = float((ctx["floors_hearing"][heard] >= 2).mean()) if heard.any() else math.nan
    rec["strongest_dbm"] = float(np.nanmax(q)) if np.isfinite(q).any() else math.nan
    # Per AP the walk hears: its strongest reading, and per floor the survey's strongest reading
    # (-inf: never heard) and detection rate (for AP-level deciders without re-running step 1).
    cols = np.flatnonzero(heard)
    rec["ap_walk_max_dbm"] = np.nanmax(q[:, cols], axis=0) if cols.size else np.zeros(0)
    rec["ap_floor_max_dbm"] = ctx["max_dbm"][:, cols]
    rec["ap_floor_rate"] = ctx["heard_rate"][:, cols]
    wp = np.asarray(walk.waypoint_xy_m, float)
    cover = []
    for f in ctx["floors"]:
        pos = ctx["positions"][f]
        cover.append(float(np.median(np.min(np.hypot(*(wp[:, None, :] - pos[None, :, :]).transpose(2, 0, 1)), axis=1)))
                     if len(pos) else math.inf)
    rec["coverage_m"] = np.asarray(cover)
    rec["duration_s"] = float(np.ptp(np.asarray(walk.waypoint_t_s, float))) if len(walk.waypoint_t_s) else 0.0


def cached_evidence(data_root, floors: Sequence[str], seed: int, cache: Path) -> dict:
    """Step 1 for one seed, read from ``cache/seed{seed}.pkl`` when present (written atomically)."""
    path = Path(cache) / f"seed{seed}.pkl"
    if path.exists():
        with open(path, "rb") as fh:
            return pickle.load(fh)
    ev = fis.walk_evidence(data_root, floors, seed=seed, per_fold=_fold_context, per_walk=_walk_features)
    for w in ev["walks"]:
        w["seed"] = seed
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    with open(tmp, "wb") as fh:
        pickle.dump(ev, fh)
    tmp.replace(path)
    return ev


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data-root", default=None)
    ap.add_argument("--floors", nargs="*", default=[])
    ap.add_argument("--cache", required=True, help="directory of the per-seed evidence (step 1)")
    ap.add_argument("--seed", type=int, nargs="+", default=[0, 1, 2, 3])
    ap.add_argument("--choose-seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--only-cache", action="store_true", help="compute the cache and stop")
    ap.add_argument("--json", default=None)
    ap.add_argument("--markdown", default=None)
    args = ap.parse_args(argv)
    if not set(args.choose_seeds) <= set(args.seed):
        ap.error(f"argument --choose-seeds: {args.choose_seeds} not all in --seed {args.seed}")
    tic = time.perf_counter()
    parts = [cached_evidence(args.data_root, args.floors, s, Path(args.cache)) for s in args.seed]
    if args.only_cache:
        return 0
    from indoorloc.experiments import floor_generalization_select as sel
    result = sel.study(parts, args.choose_seeds)
    result["seconds"] = round(time.perf_counter() - tic, 1)
    text = sel.markdown(result)
    print(text)
    if args.json:
        write_text_atomic(args.json, json.dumps(fis._jsonable(result), indent=1) + "\n")
    if args.markdown:
        write_text_atomic(args.markdown, text + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
