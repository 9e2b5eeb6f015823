"""The WiFi-only matcher study (docs/fusion_real.md, "WiFi as fixes").

``python -m indoorloc.experiments.wifi_matcher_study [--data-root DIR] [--floors B1 F1 ...]
[--json FILE] [--markdown FILE] [--cache-dir DIR]``

Per floor, 4-fold cross-validation by walk (seed 0, the folds of ``indoorloc fusion evaluate``).
Each test waypoint is scored with the fix nearest in time (the protocol of ``wifi_knn``). Every
tunable setting of the matcher (query and reference windows, penalty c, AP reliability power α,
strength scale β, k, temperature T) is chosen by leave-one-floor-out over the floors given: for
each floor, the grid point with the lowest pooled mean error over the *other* floors' 4-fold
results is scored on it. Reported beside the all-floor choice: the old ``wifi_knn`` (fresh scans,
strongest-10 metric), the bound (nearest training reference in space), errors by coverage (test
waypoint to the nearest training scan position: <= 5, 5-10, > 10 m), what the tracker sees (truth
at the fix time to the nearest component and to the centre) and the component sd that makes the
mixture's 95 % region hold the truth 90 % of the time.

Parsing and placement (PDR between waypoints) are cached per walk under ``--cache-dir``.
Walks the loader refuses (e.g. ``Infinity`` in an iBeacon field, F1) are skipped and counted.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc.io.ilc2020 import IlcWifi
from indoorloc.io.atomic_file import write_text_atomic

GRID_STEP_S = 0.1   #: time step of the cached walker positions [s]


# --------------------------------------------------------------------------------------------
# Cache: one .npz per walk (WiFi arrays, waypoints, positions on a 0.1 s grid)


@dataclass
class CachedWalk:
    walk_id: str
    wifi: IlcWifi
    waypoint_t_s: np.ndarray
    waypoint_xy_m: np.ndarray
    grid_t_s: np.ndarray      #: (G,) positions grid [s]
    grid_xy_m: np.ndarray     #: (G, 2), NaN where walk_positions drops the time

    def positions_at(self, t_s: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """(Q, 2) positions and (Q,) valid, linear between grid points both valid."""
        t = np.asarray(t_s, float)
        g = self.grid_t_s
        if g.size < 2:
            return np.full((t.size, 2), np.nan), np.zeros(t.size, bool)
        i = np.clip(np.searchsorted(g, t) - 1, 0, g.size - 2)
        f = np.clip((t - g[i]) / (g[i + 1] - g[i]), 0.0, 1.0)[:, None]
        xy = (1 - f) * self.grid_xy_m[i] + f * self.grid_xy_m[i + 1]
        ok = (t >= g[0] - 1e-9) & (t <= g[-1] + 1e-9) & np.isfinite(xy).all(axis=1)
        return np.where(ok[:, None], xy, np.nan), ok


def cache_floor(root: Path, name: str, cache_dir: Path, log=print) -> Tuple[List[CachedWalk], List[str]]:
    """The floor's walks from the cache, parsing and placing the missing ones; also the ids of
    walks the loader refused (skipped)."""
    from indoorloc.fusion import crowdsourced_map
    from indoorloc.io.survey_layout import survey_floors

    (survey,) = survey_floors(Path(root), [name], argument="data_root")
    floor = survey.open()
    out, skipped = [], []
    d = Path(cache_dir) / name
    d.mkdir(parents=True, exist_ok=True)
    for wid in floor.walk_ids:
        f = d / f"{wid}.npz"
        if not f.exists():
            try:
                walk = floor.walk(wid)
            except ValueError as e:  # e.g. 'Infinity' in an iBeacon field (F1): the loader fix is pending
                write_text_atomic(d / f"{wid}.skip", str(e))
                skipped.append(wid)
                continue
            wf = walk.wifi
            wt = np.asarray(walk.waypoint_t_s, float)
            if wt.size:
                grid = np.arange(wt[0] - 3.0, wt[-1] + 3.0 + GRID_STEP_S / 2, GRID_STEP_S)
                pos = crowdsourced_map.walk_positions(walk, grid)
                gxy = np.where(pos.valid[:, None], pos.xy_m, np.nan)
            else:
                grid, gxy = np.zeros(0), np.zeros((0, 2))
            tmp = d / f"{wid}.tmp.npz"
            np.savez_compressed(tmp, scan_time_s=wf.scan_time_s, bssid_index=wf.bssid_index, rssi_dbm=wf.rssi_dbm,
                                last_seen_s=wf.last_seen_s, scan_starts=wf.scan_starts,
                                bssids=np.array(wf.bssids, dtype=str), waypoint_t_s=wt,
                                waypoint_xy_m=np.asarray(walk.waypoint_xy_m, float).reshape(-1, 2),
                                grid_t_s=grid, grid_xy_m=gxy)
            tmp.rename(f)
        if (d / f"{wid}.skip").exists() and not f.exists():
            skipped.append(wid)
            continue
        z = np.load(f)
        bssids = [str(b) for b in z["bssids"]]
        # The loader's own class on the cached arrays (frequency and SSIDs are not cached: no
        # matcher reads them).
        wf = IlcWifi(z["scan_time_s"], z["bssid_index"].astype(np.int64), z["rssi_dbm"],
                     np.full(z["rssi_dbm"].shape, np.nan), z["last_seen_s"], bssids, [""] * len(bssids),
                     z["scan_starts"].astype(np.int64))
        out.append(CachedWalk(wid, wf, z["waypoint_t_s"], z["waypoint_xy_m"], z["grid_t_s"], z["grid_xy_m"]))
    skipped = sorted(set(skipped))
    log(f"{name}: {len(out)} walks, {len(skipped)} skipped by the loader")
    return out, skipped


# --------------------------------------------------------------------------------------------
# Evaluation on cached walks

#: The grid, pruned by quick runs (docs/fusion_real.md, "WiFi as fixes"): penalties below 80 dB,
#: windows shorter than 6 / 12 s, the centred query window, "union"/"strongest" on pooled windows
#: and a per-walk diversity rule were worse or no better there and are not in it; the window
#: edges were moved out until the choice fell inside the grid.
GRID = {
    "ref_window_s": (6.0, 10.0, 14.0),
    "query_window_s": (12.0, 16.0, 24.0),
    "ap_weight_power": (0.0, 1.0),
    "strength_scale_db": (0.0, 3.0, 5.0, 10.0),
    "penalty_db": (80.0, 160.0, 320.0),
    "k": (8, 12, 20, 30),
    "temperature_db": (3.0, 10.0, 30.0),
}
BUILD_KEYS = ("ref_window_s",)
QUERY_KEYS = ("query_window_s",)
INDEX_KEYS = ("ap_weight_power", "strength_scale_db")
CHEAP_KEYS = ("penalty_db", "k", "temperature_db")
#: The previous matcher (``wifi_knn`` of ``indoorloc fusion evaluate`` before this study).
OLD = dict(pooling="fresh", metric="strongest", k=8, temperature_db=2.0, sd_m=4.0, sd_per_db=0.0)


def _folds(n: int, k: int = 4, seed: int = 0) -> List[np.ndarray]:
    from indoorloc.experiments.fusion_real import _folds as f

    return f(n, k, seed)


def _nearest_in_time(times_s: np.ndarray, row_t: np.ndarray) -> np.ndarray:
    idx = np.clip(np.searchsorted(row_t, times_s), 0, len(row_t) - 1)
    prev = np.clip(idx - 1, 0, len(row_t) - 1)
    return np.where(np.abs(row_t[prev] - times_s) < np.abs(row_t[idx] - times_s), prev, idx)


@dataclass
class FoldQueries:
    """The test walks' queries of one fold, stacked: times, fingerprints, walk of each, and the
    waypoints to score (walk of each, time, truth)."""

    t_s: np.ndarray
    rss_dbm: np.ndarray
    walk: np.ndarray
    wp_walk: np.ndarray
    wp_t_s: np.ndarray
    wp_xy_m: np.ndarray


def fold_queries(test: Sequence[CachedWalk], database) -> FoldQueries:
    from indoorloc.fusion import wifi_fixes

    ts, rs, ws, wpw, wpt, wpx = [], [], [], [], [], []
    for i, w in enumerate(test):
        t, rss = wifi_fixes.walk_queries(w, database)
        ts.append(t)
        rs.append(rss)
        ws.append(np.full(t.size, i))
        wpw.append(np.full(w.waypoint_t_s.size, i))
        wpt.append(w.waypoint_t_s)
        wpx.append(w.waypoint_xy_m)
    return FoldQueries(np.concatenate(ts), np.vstack(rs), np.concatenate(ws), np.concatenate(wpw),
                       np.concatenate(wpt), np.vstack(wpx))


def waypoint_errors(q: FoldQueries, centres: np.ndarray) -> np.ndarray:
    """Error [m] at every waypoint of the fold with the fix nearest in time (NaN: walk without fixes)."""
    err = np.full(q.wp_t_s.size, np.nan)
    for i in np.unique(q.wp_walk):
        m = q.wp_walk == i
        rows = np.flatnonzero((q.walk == i) & np.isfinite(centres).all(axis=1))
        if rows.size == 0:
            continue
        j = rows[_nearest_in_time(q.wp_t_s[m], q.t_s[rows])]
        err[m] = np.hypot(*(centres[j] - q.wp_xy_m[m]).T)
    return err


def weighted_centres(positions: np.ndarray, best: np.ndarray, w: np.ndarray) -> np.ndarray:
    ws = w.sum(axis=1, keepdims=True)
    c = (w[:, :, None] * positions[best]).sum(axis=1) / np.where(ws > 0, ws, 1.0)
    return np.where(ws > 0, c, np.nan)


def _key(d: Dict[str, Any]) -> str:
    return ",".join(f"{k}={d[k]}" for k in GRID)


def evaluate_grid(walks: Sequence[CachedWalk], grid: Dict[str, Sequence[Any]], folds: int = 4, seed: int = 0,
                  log=print) -> Tuple[Dict[str, np.ndarray], Dict[str, Any]]:
    """Waypoint errors of every grid point on one floor (4-fold by walk), concatenated in fold order;
    plus per-waypoint facts (fold, coverage distance, bound distance at the default reference
    window) and the old matcher's errors."""
    from indoorloc.wifi import matcher as wifi_matcher
    from indoorloc.fusion import wifi_fixes

    out: Dict[str, List[np.ndarray]] = {}
    extra: Dict[str, List[np.ndarray]] = {"fold": [], "coverage_m": [], "old": []}
    for j, test_idx in enumerate(_folds(len(walks), folds, seed)):
        test_set = set(test_idx.tolist())
        train = [w for i, w in enumerate(walks) if i not in test_set]
        test = [walks[i] for i in test_idx]
        pos = [w.positions_at for w in train]
        # The previous matcher, and the training scan positions (coverage).
        old_db = wifi_fixes.build_database(train, wifi_fixes.FixSettings(**OLD), positions_at=pos)
        qo = fold_queries(test, old_db)
        best, _, w = wifi_matcher.knn(wifi_fixes.dissimilarity(qo.rss_dbm, old_db), 8, 2.0)
        extra["old"].append(waypoint_errors(qo, weighted_centres(old_db.positions_m, best, w)))
        from scipy.spatial import cKDTree

        extra["coverage_m"].append(cKDTree(old_db.positions_m).query(qo.wp_xy_m)[0])
        extra["fold"].append(np.full(qo.wp_t_s.size, j))
        for bvals in itertools.product(*(grid[k] for k in BUILD_KEYS)):
            b = dict(zip(BUILD_KEYS, bvals))
            db0 = wifi_fixes.build_database(train, wifi_fixes.FixSettings(**b), positions_at=pos)
            for qvals in itertools.product(*(grid[k] for k in QUERY_KEYS)):
                qd = dict(zip(QUERY_KEYS, qvals))
                q = fold_queries(test, db0.with_settings(wifi_fixes.FixSettings(**b, **qd)))
                for ivals in itertools.product(*(grid[k] for k in INDEX_KEYS)):
                    idx = dict(zip(INDEX_KEYS, ivals))
                    db = db0.with_settings(wifi_fixes.FixSettings(**b, **qd, **idx))
                    rms, u = wifi_matcher.shared_dissimilarity(q.rss_dbm, db.index, 0.0, parts=True)
                    kmax = max(grid["k"])
                    for c in grid["penalty_db"]:
                        best, dbest, _ = wifi_matcher.knn(rms + c * u, kmax, 1.0)
                        for k in grid["k"]:
                            for temp in grid["temperature_db"]:
                                ww = np.exp(-(dbest[:, :k] - dbest[:, :1]) / temp)
                                ww[~np.isfinite(dbest[:, :k])] = 0.0
                                cen = weighted_centres(db.positions_m, best[:, :k], ww)
                                key = _key({**b, **qd, **idx, "penalty_db": c, "k": k, "temperature_db": temp})
                                out.setdefault(key, []).append(waypoint_errors(q, cen))
        log(f"  fold {j}: {len(train)} train walks, {old_db.n_scans} training scans, {db0.n_scans} references")
    return ({k: np.concatenate(v) for k, v in out.items()},
            {k: np.concatenate(v) for k, v in extra.items()})


def _stats(e: np.ndarray) -> Dict[str, float]:
    e = e[np.isfinite(e)]
    if e.size == 0:
        return {"mean_m": float("nan"), "median_m": float("nan"), "p90_m": float("nan"), "n": 0}
    return {"mean_m": float(e.mean()), "median_m": float(np.median(e)), "p90_m": float(np.percentile(e, 90)),
            "n": int(e.size)}


def lofo(errors: Dict[str, Dict[str, np.ndarray]], floors: Sequence[str]) -> Dict[str, Any]:
    """Leave-one-floor-out: per held-out floor, the grid point with the lowest pooled mean over the
    other floors, scored on it; plus the point chosen on all floors."""
    keys = list(errors[floors[0]].keys())
    sums = {f: np.array([np.nansum(errors[f][k]) for k in keys]) for f in floors}
    counts = {f: np.array([np.isfinite(errors[f][k]).sum() for k in keys]) for f in floors}
    res: Dict[str, Any] = {"per_floor": {}}
    held = []
    for f in floors:
        others = [g for g in floors if g != f]
        mean_other = sum(sums[g] for g in others) / np.maximum(sum(counts[g] for g in others), 1)
        kb = keys[int(np.argmin(mean_other))]
        res["per_floor"][f] = {"chosen": kb, **_stats(errors[f][kb])}
        held.append(errors[f][kb])
    res["pooled"] = _stats(np.concatenate(held))
    mean_all = sum(sums[g] for g in floors) / np.maximum(sum(counts[g] for g in floors), 1)
    order = np.argsort(mean_all)
    res["best_all"] = keys[int(order[0])]
    res["top_all"] = [{"point": keys[int(i)], "pooled_mean_m": float(mean_all[i])} for i in order[:10]]
    return res


def parse_key(key: str) -> Dict[str, Any]:
    out = {}
    for part in key.split(","):
        k, v = part.split("=")
        out[k] = int(v) if k == "k" else float(v)
    return out


# --------------------------------------------------------------------------------------------
# What the tracker sees, and the component sd


def mixture_hpd_coverage(truth: np.ndarray, means: np.ndarray, weights: np.ndarray, sd_m: Any,
                         level: float = 0.95, samples: int = 500, seed: int = 0) -> np.ndarray:
    """(F,) bool: whether the truth (F, 2) lies in the highest-density region of probability ``level``
    of each isotropic Gaussian mixture (means (F, k, 2), weights (F, k), sd ``sd_m``: a scalar or
    one per fix (F,)), by Monte Carlo (the region's density threshold is the (1 - level) quantile
    of the density at ``samples`` mixture samples)."""
    rng = np.random.default_rng(seed)
    f_n, k = weights.shape
    w = weights / weights.sum(axis=1, keepdims=True)
    sd_all = np.broadcast_to(np.asarray(sd_m, float), (f_n,))
    inside = np.zeros(f_n, bool)

    def density(x, mu, ww, sd):  # x (F, S, 2), mu (F, k, 2) -> (F, S); factors common to a fix dropped
        d2 = ((x[:, :, None, :] - mu[:, None, :, :]) ** 2).sum(-1)
        return (ww[:, None, :] * np.exp(-0.5 * d2 / sd[:, None, None] ** 2)).sum(-1)

    for a in range(0, f_n, 200):
        b = min(f_n, a + 200)
        mu, ww, sd = means[a:b], w[a:b], sd_all[a:b]
        comp = (rng.random((b - a, samples, 1)) > np.cumsum(ww, axis=1)[:, None, :]).sum(-1)
        comp = np.minimum(comp, k - 1)
        x = (np.take_along_axis(mu, comp[..., None].repeat(2, -1), axis=1)
             + sd[:, None, None] * rng.standard_normal((b - a, samples, 2)))
        thr = np.quantile(density(x, mu, ww, sd), 1.0 - level, axis=1)
        inside[a:b] = density(truth[a:b, None, :], mu, ww, sd)[:, 0] >= thr
    return inside


def tracker_view(walks: Sequence[CachedWalk], settings, folds: int = 4, seed: int = 0) -> Dict[str, np.ndarray]:
    """Per fix of every test walk (4-fold): truth at the fix time (waypoints interpolated linearly,
    fixes outside the waypoints' time span dropped), the fix's means and weights, and the
    bound/coverage distances of the test waypoints."""
    from scipy.spatial import cKDTree

    from indoorloc.fusion import wifi_fixes

    from indoorloc.wifi import matcher as wifi_matcher

    truth, means, weights, fold_of, d_min = [], [], [], [], []
    bound = []
    for j, test_idx in enumerate(_folds(len(walks), folds, seed)):
        ts = set(test_idx.tolist())
        train = [w for i, w in enumerate(walks) if i not in ts]
        db = wifi_fixes.build_database(train, settings, positions_at=[w.positions_at for w in train])
        tree = cKDTree(db.positions_m)
        for i in test_idx:
            w = walks[i]
            bound.append(tree.query(w.waypoint_xy_m)[0])
            t, rss = wifi_fixes.walk_queries(w, db)   # the queries of fixes_for_walk
            wt = w.waypoint_t_s
            ok = (t >= wt[0]) & (t <= wt[-1])
            if not ok.any():
                continue
            best, d, wgt = wifi_matcher.knn(wifi_fixes.dissimilarity(rss[ok], db), settings.k, settings.temperature_db)
            truth.append(np.column_stack([np.interp(t[ok], wt, w.waypoint_xy_m[:, c]) for c in range(2)]))
            means.append(db.positions_m[best])
            weights.append(wgt)
            d_min.append(d[:, 0])
            fold_of.append(np.full(int(ok.sum()), j))
    truth, means, weights = np.vstack(truth), np.vstack(means), np.vstack(weights)
    w = weights / weights.sum(axis=1, keepdims=True)
    centre = (w[:, :, None] * means).sum(axis=1)
    return {"truth": truth, "means": means, "weights": weights, "fold": np.concatenate(fold_of),
            "d_min": np.concatenate(d_min),
            "nearest_component_m": np.hypot(*(means - truth[:, None, :]).transpose(2, 0, 1)).min(axis=1),
            "centre_m": np.hypot(*(centre - truth).T), "bound_m": np.concatenate(bound)}


SD_GRID = (3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 15.0, 20.0, 25.0)   #: one σ for every fix [m]
#: σ = sd_m + sd_per_db x d_min: the grid of (sd_m [m], sd_per_db [m/dB]).
SD_LINEAR_GRID = tuple((a, b) for a in (1.0, 2.0, 3.0, 4.0, 6.0) for b in (0.1, 0.2, 0.3, 0.4, 0.5))


def time_queries(walks: Sequence[CachedWalk], settings, repeats: int = 3) -> Dict[str, float]:
    """Milliseconds per query of ``locate_scans``: the first walk's queries against a database of
    all the other walks given (here: every walk of the two largest floors, as in floor
    identification), a walk's queries at once and one query at a time."""
    from indoorloc.fusion import wifi_fixes

    test, train = walks[0], list(walks[1:])
    db = wifi_fixes.build_database(train, settings, positions_at=[w.positions_at for w in train])
    _, rss = wifi_fixes.walk_queries(test, db)
    db.index  # built once per database, outside the timing
    best = math.inf
    for _ in range(repeats):
        tic = time.perf_counter()
        wifi_fixes.locate_scans(rss, db)
        best = min(best, time.perf_counter() - tic)
    single = math.inf
    for _ in range(repeats):
        tic = time.perf_counter()
        for r in range(rss.shape[0]):
            wifi_fixes.locate_scans(rss[r:r + 1], db)
        single = min(single, time.perf_counter() - tic)
    return {"references": db.n_scans, "aps": len(db.bssids), "queries": int(rss.shape[0]),
            "ms_per_query_batch": 1e3 * best / max(1, rss.shape[0]),
            "ms_per_query_single": 1e3 * single / max(1, rss.shape[0])}


# --------------------------------------------------------------------------------------------
# The study


def run(data_root: Path, floors: Sequence[str], cache_dir: Path, grid: Optional[Dict[str, Sequence[Any]]] = None,
        log=print) -> Dict[str, Any]:
    from indoorloc.fusion import wifi_fixes

    grid = dict(GRID if grid is None else grid)
    tic = time.time()
    data, skipped = {}, {}
    for f in floors:
        data[f], skipped[f] = cache_floor(data_root, f, cache_dir, log)
    errors, extra = {}, {}
    for f in floors:
        t0 = time.time()
        errors[f], extra[f] = evaluate_grid(data[f], grid, log=log)
        log(f"{f}: grid of {len(errors[f])} points in {time.time() - t0:.0f} s")
    sel = lofo(errors, floors)
    chosen = parse_key(sel["best_all"])
    settings = wifi_fixes.FixSettings(**chosen)
    out: Dict[str, Any] = {"floors": list(floors), "grid": {k: list(v) for k, v in grid.items()},
                           "skipped_walks": {f: len(v) for f, v in skipped.items()},
                           "lofo": sel, "chosen_all_floors": chosen, "per_floor": {}}
    # Old vs new per floor, coverage split, bound, tracker view.
    views = {}
    pooled_old, pooled_new, pooled_cov = [], [], []
    for f in floors:
        e_new, e_old, cov = errors[f][sel["best_all"]], extra[f]["old"], extra[f]["coverage_m"]
        fold = extra[f]["fold"]
        views[f] = tracker_view(data[f], settings)
        v = views[f]
        row = {"old": _stats(e_old), "new_all_floor_choice": _stats(e_new), "new_lofo": sel["per_floor"][f],
               "bound": _stats(v["bound_m"]),
               "new_fold_means_m": [float(np.nanmean(e_new[fold == j])) for j in np.unique(fold)],
               "lofo_fold_means_m": [float(np.nanmean(errors[f][sel["per_floor"][f]["chosen"]][fold == j]))
                                     for j in np.unique(fold)],
               "ratio_lofo_to_old": sel["per_floor"][f]["mean_m"] / _stats(e_old)["mean_m"],
               "coverage": {}, "tracker": {"nearest_component": _stats(v["nearest_component_m"]),
                                           "centre": _stats(v["centre_m"]), "fixes": int(v["truth"].shape[0])}}
        for name, lo, hi in (("<=5m", 0, 5), ("5-10m", 5, 10), (">10m", 10, np.inf)):
            m = (cov > lo if lo else cov >= 0) & (cov <= hi)
            row["coverage"][name] = {"fraction": float(m.mean()), "old": _stats(e_old[m]), "new": _stats(e_new[m])}
        out["per_floor"][f] = row
        pooled_old.append(e_old)
        pooled_new.append(e_new)
        pooled_cov.append(cov)
    e_old, e_new, cov = map(np.concatenate, (pooled_old, pooled_new, pooled_cov))
    out["pooled"] = {"old": _stats(e_old), "new_all_floor_choice": _stats(e_new), "new_lofo": sel["pooled"],
                     "coverage": {}}
    for name, lo, hi in (("<=5m", 0, 5), ("5-10m", 5, 10), (">10m", 10, np.inf)):
        m = (cov > lo if lo else cov >= 0) & (cov <= hi)
        out["pooled"]["coverage"][name] = {"fraction": float(m.mean()), "old": _stats(e_old[m]), "new": _stats(e_new[m])}
    # Component sd: 95 % region holding the truth ~90 % of the time; all floors and LOFO.
    cover = {f: {sd: mixture_hpd_coverage(views[f]["truth"], views[f]["means"], views[f]["weights"], sd)
                 for sd in SD_GRID} for f in floors}

    def rate(names, sd):
        return float(np.mean(np.concatenate([cover[g][sd] for g in names])))

    sd_all = min(SD_GRID, key=lambda sd: abs(rate(floors, sd) - 0.9))
    out["sd_calibration"] = {"grid": list(SD_GRID),
                             "coverage_all_floors": {str(sd): rate(floors, sd) for sd in SD_GRID},
                             "coverage_per_floor": {f: {str(sd): rate([f], sd) for sd in SD_GRID} for f in floors},
                             "chosen_sd_m": sd_all, "lofo": {}}
    for f in floors:
        others = [g for g in floors if g != f]
        sd_f = min(SD_GRID, key=lambda sd: abs(rate(others, sd) - 0.9))
        out["sd_calibration"]["lofo"][f] = {"sd_m": sd_f, "held_out_coverage": rate([f], sd_f)}
    # σ growing with the fix's best dissimilarity: chosen for the most even ~90 % over the floors.
    lin = {f: {ab: mixture_hpd_coverage(views[f]["truth"], views[f]["means"], views[f]["weights"],
                                        ab[0] + ab[1] * np.where(np.isfinite(views[f]["d_min"]), views[f]["d_min"], 0.0))
               for ab in SD_LINEAR_GRID} for f in floors}

    def spread(names, ab):  # mean over the floors of |coverage - 0.9|
        return float(np.mean([abs(lin[g][ab].mean() - 0.9) for g in names]))

    ab_all = min(SD_LINEAR_GRID, key=lambda ab: spread(floors, ab))
    out["sd_linear"] = {"grid": [list(ab) for ab in SD_LINEAR_GRID], "chosen": list(ab_all),
                        "coverage_per_floor": {f: float(lin[f][ab_all].mean()) for f in floors},
                        "coverage_all_floors": float(np.mean(np.concatenate([lin[f][ab_all] for f in floors]))),
                        "lofo": {}}
    for f in floors:
        others = [g for g in floors if g != f]
        ab_f = min(SD_LINEAR_GRID, key=lambda ab: spread(others, ab))
        out["sd_linear"]["lofo"][f] = {"sd_m": ab_f[0], "sd_per_db": ab_f[1], "held_out_coverage": float(lin[f][ab_f].mean())}
    out["sd_linear"]["lofo_pooled_coverage"] = float(np.mean(np.concatenate(
        [lin[f][tuple(out["sd_linear"]["lofo"][f][k] for k in ("sd_m", "sd_per_db"))] for f in floors])))
    big = sorted(floors, key=lambda f: -len(data[f]))[:2]
    out["timing"] = {"floor": "+".join(big), **time_queries([w for f in big for w in data[f]], settings)}
    out["seconds"] = time.time() - tic
    return out


def _fmt(s: Dict[str, float]) -> str:
    return f"{s['mean_m']:.1f} / {s['median_m']:.1f} / {s['p90_m']:.1f}"


def markdown(r: Dict[str, Any]) -> str:
    fl = r["floors"]
    lines = ["# WiFi matcher study (`python -m indoorloc.experiments.wifi_matcher_study`)", "",
             "Per floor 4-fold by walk (seed 0); each waypoint scored with the fix nearest in time. "
             "Mean / median / p90 [m]. LOFO: settings chosen on the other floors' 4-fold results.", "",
             "| | " + " | ".join(fl) + " | pooled |", "|---" * (len(fl) + 2) + "|"]
    rows = [("old wifi_knn (fresh scans, strongest 10)", lambda f: r["per_floor"][f]["old"], r["pooled"]["old"]),
            ("new, LOFO (held-out floor)", lambda f: r["per_floor"][f]["new_lofo"], r["pooled"]["new_lofo"]),
            ("new, chosen on all floors", lambda f: r["per_floor"][f]["new_all_floor_choice"],
             r["pooled"]["new_all_floor_choice"]),
            ("bound: nearest training reference", lambda f: r["per_floor"][f]["bound"], None),
            ("fix: truth to nearest component", lambda f: r["per_floor"][f]["tracker"]["nearest_component"], None),
            ("fix: truth to mixture centre", lambda f: r["per_floor"][f]["tracker"]["centre"], None)]
    for name, get, pooled in rows:
        lines.append(f"| {name} | " + " | ".join(_fmt(get(f)) for f in fl) + f" | {_fmt(pooled) if pooled else ''} |")
    lines.append("| LOFO / old (mean) | " + " | ".join(f"{r['per_floor'][f]['ratio_lofo_to_old']:.2f}" for f in fl)
                 + f" | {r['pooled']['new_lofo']['mean_m'] / r['pooled']['old']['mean_m']:.2f} |")
    lines.append("| LOFO per-fold means | " + " | ".join(
        "-".join(f"{x:.1f}" for x in (min(r['per_floor'][f]['lofo_fold_means_m']), max(r['per_floor'][f]['lofo_fold_means_m'])))
        for f in fl) + " | |")
    lines += ["", "LOFO choices (held-out floor: point chosen on the others):", ""]
    for f in fl:
        lines.append(f"- {f}: `{r['lofo']['per_floor'][f]['chosen']}`")
    lines += ["", f"Chosen on all floors: `{r['lofo']['best_all']}`", "", "Top 10 on all floors (pooled mean):", ""]
    for t in r["lofo"]["top_all"]:
        lines.append(f"- {t['pooled_mean_m']:.2f} m: `{t['point']}`")
    lines += ["", "Errors by coverage (test waypoint to the nearest training scan), old -> new (all-floor choice):", "",
              "| coverage | " + " | ".join(fl) + " | pooled |", "|---" * (len(fl) + 2) + "|"]
    for name in ("<=5m", "5-10m", ">10m"):
        cells = []
        for f in fl + ["pooled"]:
            c = (r["pooled"] if f == "pooled" else r["per_floor"][f])["coverage"][name]
            cells.append(f"{100 * c['fraction']:.0f} %: {c['old']['mean_m']:.1f} -> {c['new']['mean_m']:.1f}")
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    sc = r["sd_calibration"]
    lines += ["", "Component sd: fraction of fixes whose mixture 95 % region holds the truth:", "",
              "| sd [m] | " + " | ".join(str(s) for s in sc["grid"]) + " |", "|---" * (len(sc["grid"]) + 1) + "|",
              "| all floors | " + " | ".join(f"{sc['coverage_all_floors'][str(s)]:.2f}" for s in sc["grid"]) + " |"]
    for f in fl:
        lines.append(f"| {f} | " + " | ".join(f"{sc['coverage_per_floor'][f][str(s)]:.2f}" for s in sc["grid"]) + " |")
    lines += ["", f"Chosen sd (all floors, closest to 0.90): {sc['chosen_sd_m']} m; LOFO: " +
              ", ".join(f"{f} {v['sd_m']} m -> {v['held_out_coverage']:.2f}" for f, v in sc["lofo"].items()), ""]
    sl = r["sd_linear"]
    lines += ["σ growing with the fix's best dissimilarity, σ = a + b d_min, (a, b) chosen for the most even "
              f"~90 % over the floors: a = {sl['chosen'][0]} m, b = {sl['chosen'][1]} m/dB; coverage "
              + ", ".join(f"{f} {v:.2f}" for f, v in sl["coverage_per_floor"].items())
              + f", all {sl['coverage_all_floors']:.2f}. LOFO: "
              + ", ".join(f"{f} ({v['sd_m']}, {v['sd_per_db']}) -> {v['held_out_coverage']:.2f}" for f, v in sl["lofo"].items())
              + f"; pooled held out {sl['lofo_pooled_coverage']:.2f}.", ""]
    tm = r["timing"]
    lines += [f"Timing ({tm['floor']}, {tm['references']} references, {tm['aps']} APs, {tm['queries']} queries): "
              f"{tm['ms_per_query_batch']:.2f} ms per query in a walk's batch, {tm['ms_per_query_single']:.2f} ms one "
              f"query at a time.", "",
              "Walks the loader refused (skipped): " + ", ".join(f"{f} {n}" for f, n in r["skipped_walks"].items()),
              "", f"Run time: {r['seconds']:.0f} s."]
    return "\n".join(lines) + "\n"


def main(argv: Optional[Sequence[str]] = None) -> int:
    from indoorloc.experiments.fusion_real import default_site_root
    from indoorloc.io.survey_layout import survey_floors

    p = argparse.ArgumentParser(prog="python -m indoorloc.experiments.wifi_matcher_study", description=__doc__.split("\n")[0])
    p.add_argument("--data-root", type=Path, default=None, help="site folder (default: the shared ilc2020_site2)")
    p.add_argument("--floors", nargs="+", default=None, help="floor folders (default: every floor folder "
                   "with walks and a plan, io.survey_layout.survey_floors)")
    p.add_argument("--json", type=Path, default=None, help="write the results as JSON")
    p.add_argument("--markdown", type=Path, default=None, help="write the tables as markdown")
    p.add_argument("--cache-dir", type=Path, default=Path("/tmp/wifi_cache"), help="per-walk parse/placement cache")
    p.add_argument("--quiet", action="store_true")
    a = p.parse_args(argv)
    root = a.data_root or default_site_root()
    floors = [sf.name for sf in survey_floors(root, a.floors, argument="data_root")]
    log = (lambda *x: None) if a.quiet else (lambda *x: print(*x, flush=True))
    r = run(root, floors, a.cache_dir, log=log)
    md = markdown(r)
    for path, text in ((a.json, json.dumps(r, indent=1)), (a.markdown, md)):
        if path is not None:
            tmp = path.with_suffix(path.suffix + ".tmp")
            tmp.write_text(text)
            tmp.rename(path)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
