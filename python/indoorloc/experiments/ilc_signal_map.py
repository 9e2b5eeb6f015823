"""WiFi-only baselines on held-out walks of the Indoor Location Competition 2.0 data, with the
crowdsourced signal map of :mod:`indoorloc.fusion.crowdsourced_map` (issue 15, item 1 of
``fusion evaluate``).

Protocol (docs/fusion_real.md, "Crowdsourced signal map"): per floor, ``folds``-fold
cross-validation by walk (fixed seed). In each outer fold the map is built from the training
walks only. Every tuned setting is chosen by an inner ``inner_folds``-fold CV on the training
walks (mean waypoint error), separately for each locator:

- ``wifi_knn``: weighted kNN (``wifi.FingerprintLocator``, ``"wknn"``) on the map's reference
  points (cell means); grid ``KNN_GRID`` (cell size, min walks per BSSID, k, not-heard value);
- ``wifi_model``: paper 004's interpolated Gaussian model, posterior mean on a grid
  (``wifi.GridPosterior``, spacing ``GRID_SPACING_M``); grid ``MODEL_GRID`` (cell size, min
  walks per BSSID); not-heard value -105 dBm (the wifi subsystem's default, fixed).

Fixed in advance: the staleness limit (2.5 s, the trough of the bimodal reading-age histogram
of docs/fusion_data.md), min cells per BSSID (2), the variance floor (4 dB^2) and prior weight
(2), the PDR positioning guards, 3 s of extrapolation. For each test waypoint the scan nearest
in time is located, its readings older than the staleness limit dropped, and the error at the
waypoint scored. Both placements of the training readings (``"pdr"``: similarity-corrected
hand-held PDR, ``"linear"``: linear in time) are run on the same folds.

``evaluate(data_root, floors, folds, seed)`` -> result dict; ``markdown(result)``; ``main()``.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from indoorloc.pdr import handheld
from indoorloc import wifi
from indoorloc.fusion import crowdsourced_map
from indoorloc.progress import progress
from indoorloc import progress as _progress
from indoorloc.io.atomic_file import write_text_atomic

PathLike = Union[str, Path]

FLOORS = ("F3", "F4", "F7", "F8")
MAX_AGE_S = 2.5
GRID_SPACING_M = 2.0
KNN_GRID: Dict[str, Sequence[Any]] = {
    "cell_size_m": (2.0, 3.0, 4.0),
    "min_walks": (2, 4, 8),
    "k": (3, 5, 8),
    "not_heard_dbm": (-100.0, -105.0),
}
MODEL_GRID: Dict[str, Sequence[Any]] = {
    "cell_size_m": (2.0, 3.0, 4.0),
    "min_walks": (2, 4, 8),
}
#: The lead's quick look (issue 15): 5-NN on raw scans placed linearly, mean / median / p90 [m].
LEAD_QUICK_LOOK = {"F3": (25.0, 9.0, 90.0), "F4": (35.0, 18.0, 94.0), "F8": (23.0, 13.0, 69.0)}


def default_fusion_root() -> Path:
    """The ILC site folder beside the WiFi data folder (``shared/data/fusion/ilc2020_site2``)."""
    from indoorloc.registry import default_data_root
    return default_data_root().parent / "fusion" / "ilc2020_site2"


@dataclass
class _Walk:
    walk_id: str
    wt: np.ndarray                         # (W,) waypoint times
    wxy: np.ndarray                        # (W, 2)
    placed: Dict[str, crowdsourced_map.PlacedReadings]   # positioning -> placed readings
    scan_bssids: List[List[str]]           # per waypoint: BSSIDs of the nearest scan (fresh)
    scan_rssi: List[np.ndarray]            # per waypoint: their RSSI


def _nearest_scans(walk: Any, max_age_s: float) -> Tuple[List[List[str]], List[np.ndarray]]:
    wf = walk.wifi
    names, values = [], []
    st = wf.scan_times_s
    for t in walk.waypoint_t_s:
        if wf.n_scans == 0:
            names.append([]); values.append(np.zeros(0)); continue
        s = int(np.argmin(np.abs(st - t)))
        sl = wf.scan_slice(s)
        age = wf.age_s[sl]
        ok = age <= max_age_s
        b = wf.bssid_index[sl][ok]
        r = wf.rssi_dbm[sl][ok]
        a = age[ok]
        # One value per BSSID: the freshest (stronger at equal age).
        order = np.lexsort((-r, a, b))
        b, r = b[order], r[order]
        first = np.r_[True, b[1:] != b[:-1]][: b.size]
        names.append([wf.bssids[i] for i in b[first]])
        values.append(r[first])
    return names, values


def load_floor(floor: Any, positionings: Sequence[str] = crowdsourced_map.POSITIONING, max_age_s: float = MAX_AGE_S,
               settings: Optional[crowdsourced_map.CrowdMapSettings] = None) -> List[_Walk]:
    """Reads the walks of a floor, places their readings once per positioning (the placement
    uses only the walk's own waypoints and IMU, no training) and extracts the test scans."""
    out = []
    base = settings or crowdsourced_map.CrowdMapSettings()
    for w in floor.walks():
        steps = handheld.handheld_steps(w, handheld.HandheldOptions(heading_source=base.heading_source))
        placed = {p: crowdsourced_map.reading_positions(w, replace(base, positioning=p), steps) for p in positionings}
        names, values = _nearest_scans(w, max_age_s)
        out.append(_Walk(w.walk_id, np.asarray(w.waypoint_t_s, float), np.asarray(w.waypoint_xy_m, float),
                         placed, names, values))
    return out


def _test_matrix(walks: Sequence[_Walk], bssids: Sequence[str]) -> Tuple[np.ndarray, np.ndarray]:
    index = {b: i for i, b in enumerate(bssids)}
    rows, truth = [], []
    for w in walks:
        for names, vals, xy in zip(w.scan_bssids, w.scan_rssi, w.wxy):
            row = np.full(len(bssids), np.nan)
            for b, v in zip(names, vals):
                i = index.get(b)
                if i is not None:
                    row[i] = v
            rows.append(row)
            truth.append(xy)
    return np.array(rows).reshape(-1, len(bssids)), np.array(truth).reshape(-1, 2)


def _locate(method: str, cm: crowdsourced_map.CrowdMap, rss: np.ndarray, params: Dict[str, Any]) -> np.ndarray:
    nh = cm.settings.not_heard_dbm
    q = crowdsourced_map.prepare(rss, nh)
    if method == "wifi_knn":
        m = cm.signal_map
        loc = wifi.FingerprintLocator(m.mean_dbm, m.positions_m, m.floors, method="wknn", k=int(params["k"]))
        return np.asarray(loc.locate(q)[0])
    gp = wifi.GridPosterior(cm.model, GRID_SPACING_M)
    return np.asarray(gp.locate(q)["positions_m"])


def _grid(method: str) -> List[Dict[str, Any]]:
    g = KNN_GRID if method == "wifi_knn" else MODEL_GRID
    return [dict(zip(g, v)) for v in itertools.product(*g.values())]


def _map_key(p: Dict[str, Any]) -> Tuple:
    return (p["cell_size_m"], p["min_walks"], p.get("not_heard_dbm", -105.0))


def _errors(method: str, train: Sequence[_Walk], test: Sequence[_Walk], positioning: str,
            params_list: Sequence[Dict[str, Any]], base: crowdsourced_map.CrowdMapSettings) -> List[np.ndarray]:
    """Waypoint errors of each parameter set (maps shared between sets that differ only in k)."""
    maps: Dict[Tuple, Optional[crowdsourced_map.CrowdMap]] = {}
    out = []
    for p in params_list:
        key = _map_key(p)
        if key not in maps:
            s = replace(base, positioning=positioning, cell_size_m=key[0], min_walks=key[1], not_heard_dbm=key[2])
            try:
                maps[key] = crowdsourced_map.build_crowd_map([], s, placed=[w.placed[positioning] for w in train])
            except ValueError:
                maps[key] = None
        cm = maps[key]
        rss, truth = _test_matrix(test, cm.bssids if cm else [])
        if cm is None:
            out.append(np.full(truth.shape[0], np.inf))
            continue
        est = _locate(method, cm, rss, p)
        out.append(np.hypot(*(est - truth).T))
    return out


def _folds(n: int, k: int, rng: np.random.Generator) -> List[np.ndarray]:
    perm = rng.permutation(n)
    return [perm[i::k] for i in range(k)]


def _select(method: str, train: Sequence[_Walk], positioning: str, inner_folds: int, seed: int,
            base: crowdsourced_map.CrowdMapSettings) -> Dict[str, Any]:
    grid = _grid(method)
    rng = np.random.default_rng(seed)
    errs = [[] for _ in grid]
    for idx in _folds(len(train), inner_folds, rng):
        te = [train[i] for i in idx]
        tr = [train[i] for i in range(len(train)) if i not in set(idx.tolist())]
        for g, e in enumerate(_errors(method, tr, te, positioning, grid, base)):
            errs[g].append(e)
    means = [float(np.mean(np.concatenate(e))) for e in errs]
    return grid[int(np.argmin(means))]


def _stats(e: np.ndarray) -> Dict[str, float]:
    e = np.asarray(e, float)
    return {"mean_m": float(np.mean(e)), "median_m": float(np.median(e)),
            "p90_m": float(np.percentile(e, 90)), "n_waypoints": int(e.size)}


def evaluate(data_root: Optional[PathLike] = None, floors: Sequence[str] = FLOORS, folds: int = 4,
             inner_folds: int = 3, seed: int = 0, positionings: Sequence[str] = crowdsourced_map.POSITIONING,
             methods: Sequence[str] = ("wifi_knn", "wifi_model")) -> Dict[str, Any]:
    """Runs the protocol of the module docstring; returns per (positioning, method, floor) the
    pooled statistics, the per-fold statistics, the chosen settings per fold and the placement
    counts."""
    from indoorloc.io import read_ilc_site

    t_start = time.perf_counter()
    site = read_ilc_site(data_root or default_fusion_root())
    base = crowdsourced_map.CrowdMapSettings(max_age_s=MAX_AGE_S)
    result: Dict[str, Any] = {"settings": {"folds": folds, "inner_folds": inner_folds, "seed": seed,
                                           "max_age_s": MAX_AGE_S, "grid_spacing_m": GRID_SPACING_M,
                                           "knn_grid": {k: list(v) for k, v in KNN_GRID.items()},
                                           "model_grid": {k: list(v) for k, v in MODEL_GRID.items()},
                                           "fixed": {k: v for k, v in base.__dict__.items()}},
                              "floors": {}, "placement": {}}
    errors: Dict[Tuple[str, str], List[np.ndarray]] = {}
    for f in floors:
        walks = load_floor(site[f], positionings, MAX_AGE_S, base)
        result["placement"][f] = {
            p: {"measurements": sum(w.placed[p].n_measurements for w in walks),
                "dropped": sum(w.placed[p].n_measurements - w.placed[p].t_s.size for w in walks),
                "intervals_pdr": sum(w.placed[p].n_intervals_pdr for w in walks),
                "intervals_linear": sum(w.placed[p].n_intervals_linear for w in walks)}
            for p in positionings}
        fold_idx = _folds(len(walks), folds, np.random.default_rng(seed))
        for pos in positionings:
            for method in methods:
                per_fold, chosen, all_e = [], [], []
                for i, idx in enumerate(progress(fold_idx, desc=f"{f} {pos} {method}")):
                    test = [walks[j] for j in idx]
                    train = [walks[j] for j in range(len(walks)) if j not in set(idx.tolist())]
                    params = _select(method, train, pos, inner_folds, seed + 1 + i, base)
                    e = _errors(method, train, test, pos, [params], base)[0]
                    per_fold.append(_stats(e))
                    chosen.append(params)
                    all_e.append(e)
                e = np.concatenate(all_e)
                errors.setdefault((pos, method), []).append(e)
                result["floors"].setdefault(f, {}).setdefault(pos, {})[method] = {
                    **_stats(e), "folds": per_fold, "chosen": chosen}
    result["all"] = {pos: {m: _stats(np.concatenate(errors[(pos, m)])) for m in methods} for pos in positionings}
    result["all_fold_spread"] = {}
    result["seconds"] = time.perf_counter() - t_start
    return result


def _fmt(st: Dict[str, float]) -> str:
    return f"{st['mean_m']:.1f} / {st['median_m']:.1f} / {st['p90_m']:.1f}"


def _spread(folds: List[Dict[str, float]]) -> str:
    m = [x["mean_m"] for x in folds]
    return f"{min(m):.1f}-{max(m):.1f}"


def markdown(result: Dict[str, Any]) -> str:
    """The CV tables (per floor and over the floors, both placements)."""
    lines = []
    floors = list(result["floors"])
    positionings = list(result["all"])
    methods = list(next(iter(result["all"].values())))
    lines.append("| placement | method | " + " | ".join(floors) + " | all floors |")
    lines.append("|---|---|" + "---|" * (len(floors) + 1))
    for pos in positionings:
        for m in methods:
            cells = []
            for f in floors:
                r = result["floors"][f][pos][m]
                cells.append(f"{_fmt(r)} (fold means {_spread(r['folds'])})")
            cells.append(_fmt(result["all"][pos][m]))
            lines.append(f"| {pos} | {m} | " + " | ".join(cells) + " |")
    lines.append("")
    lines.append("Mean / median / p90 waypoint error [m]; in brackets the range of the per-fold means.")
    lines.append("")
    lines.append("| floor | placement | measurements | dropped | intervals PDR / linear |")
    lines.append("|---|---|---|---|---|")
    for f in floors:
        for pos, c in result["placement"][f].items():
            lines.append(f"| {f} | {pos} | {c['measurements']} | {c['dropped']} "
                         f"({100.0 * c['dropped'] / max(1, c['measurements']):.1f} %) | "
                         f"{c['intervals_pdr']} / {c['intervals_linear']} |")
    lines.append("")
    lines.append("Settings chosen by the inner CV (per outer fold):")
    lines.append("")
    for f in floors:
        for pos in positionings:
            for m in methods:
                ch = result["floors"][f][pos][m]["chosen"]
                lines.append(f"- {f} {pos} {m}: " + "; ".join(
                    ", ".join(f"{k}={v:g}" for k, v in c.items()) for c in ch))
    lines.append("")
    lines.append(f"Run time {result['seconds']:.0f} s.")
    return "\n".join(lines)


def main(argv: Optional[Sequence[str]] = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data-root", default=None)
    ap.add_argument("--floors", nargs="*", default=list(FLOORS))
    ap.add_argument("--folds", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", default=None)
    ap.add_argument("--quiet", action="store_true", help="no progress bars or lines")
    a = ap.parse_args(argv)
    _progress.set_quiet(a.quiet)
    r = evaluate(a.data_root, a.floors, a.folds, seed=a.seed)
    print(markdown(r))
    if a.json:
        write_text_atomic(a.json, json.dumps(r, indent=1, default=float))


if __name__ == "__main__":
    main()
