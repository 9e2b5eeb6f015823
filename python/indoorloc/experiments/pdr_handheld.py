"""Hand-held phone PDR on the Indoor Location Competition 2.0 data, cross-validated by walk.

``evaluate(data_root, floors, folds, seed)`` runs three protocols on the walks of
``ilc2020_site2`` (docs/pdr_handheld.md):

- ``per_floor``: k-fold by walk inside each floor (training walks of the same floor);
- ``pooled``: k-fold by walk over all floors together;
- ``leave_one_floor_out``: train on the other floors, test on the whole floor.

In every fold the detector settings (a small grid), K, the mean yaw offset and the per-step sds
are chosen on the training walks only; the held-out walks are scored between their waypoints:
step-count proxy, path-length error, direction error (raw, after the training mean yaw offset,
after the walk's own best offset), and PDR-only position error at the waypoints from the first
waypoint. ``markdown(result)`` prints the tables; ``main()`` does both.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from indoorloc.pdr import handheld as ph
from indoorloc.progress import progress

PathLike = Union[str, Path]

#: Detector grid searched on the training folds: (signal, threshold_fraction, min_peak_mps2,
#: min_step_interval_s). The band-pass (0.5-3 Hz, order 2, forward-backward) and the 2 s RMS
#: window are fixed (the step rate of walking, 1.5-2.2 Hz, lies inside).
GRID: Dict[str, Sequence[Any]] = {
    "signal": ("magnitude", "vertical"),
    "threshold_fraction": (0.3, 0.5, 0.8),
    "min_peak_mps2": (0.6, 1.0, 1.5, 2.0),
    "min_step_interval_s": (0.35, 0.4, 0.45, 0.5),
}
#: Time constants of the complementary heading searched on the training folds [s].
TAU_GRID: Tuple[float, ...] = (1.0, 3.0, 10.0, 30.0, 100.0)
MIN_DISTANCE_M = 1.0    # intervals shorter than this are left out of K and the distance errors
MIN_DIRECTION_M = 2.0   # ... and shorter than this out of the direction errors
HEADINGS = ph.HEADING_SOURCES


@dataclass
class _Walk:
    floor: str
    walk_id: str
    wt: np.ndarray
    wxy: np.ndarray
    steps: Dict[Tuple, ph.HandheldSteps]  # detector key -> steps computed with k = 1
    t_s: np.ndarray                       # sensor times
    comp: Dict[float, np.ndarray]         # tau -> per-sample complementary heading

    def steps_with(self, key: Tuple, tau: float) -> ph.HandheldSteps:
        st = self.steps[key]
        return replace(st, heading_complementary_rad=ph.step_headings(self.t_s, self.comp[tau], st))


def _key(o: ph.HandheldOptions) -> Tuple:
    return (o.method, o.signal, o.threshold_fraction, o.min_peak_mps2, o.min_step_interval_s)


def _grid_options() -> List[ph.HandheldOptions]:
    out = []
    for sig, tf, mp, mi in itertools.product(*GRID.values()):
        out.append(ph.HandheldOptions(signal=sig, threshold_fraction=tf, min_peak_mps2=mp,
                                      min_step_interval_s=mi, k=1.0))
    return out


VARIANCE_OPTIONS = ph.HandheldOptions(method="variance", min_step_interval_s=0.3, k=1.0)


def load_walks(data_root: PathLike, floors: Optional[Sequence[str]] = None) -> List[_Walk]:
    """Reads the walks and runs every detector setting once (the detectors need no training)."""
    from indoorloc.io import read_ilc_site  # io sits below; experiments may import it anywhere

    site = read_ilc_site(data_root)
    floors = list(floors) if floors else sorted(site)
    options = _grid_options() + [VARIANCE_OPTIONS]
    out: List[_Walk] = []
    items = [(f, i) for f in floors for i in range(site[f].n_walks)]
    for f, i in progress(items, desc="walks"):
        w = next(site[f].walks([i]), None)  # a walk that cannot be read: skipped with a RecordingWarning
        if w is None:
            continue
        arrays = ph.as_arrays(w)
        steps = {_key(o): ph.handheld_steps(arrays, o) for o in options}
        h_rv = np.unwrap(ph.rotation_vector_heading(arrays.quat_xyzw))
        h_gy = ph.gyro_heading(arrays.t_s, arrays.gyro_radps, arrays.quat_xyzw)
        comp = {tau: ph.complementary_heading(arrays.t_s, h_rv, h_gy, tau) for tau in TAU_GRID}
        out.append(_Walk(f, w.walk_id, np.asarray(w.waypoint_t_s, float), np.asarray(w.waypoint_xy_m, float), steps,
                         arrays.t_s, comp))
    return out


class _W:  # duck-typed walk for calibrate_handheld
    def __init__(self, w: _Walk) -> None:
        self.waypoint_t_s, self.waypoint_xy_m = w.wt, w.wxy


def _fit(train: List[_Walk], options: ph.HandheldOptions, heading: str) -> ph.HandheldCalibration:
    key = _key(options)
    return ph.calibrate_handheld([_W(w) for w in train], replace(options, heading_source=heading),
                                 min_distance_m=MIN_DISTANCE_M,
                                 steps_cache=[w.steps_with(key, options.complementary_tau_s) for w in train])


def _select_tau(train: List[_Walk], options: ph.HandheldOptions) -> float:
    """The complementary time constant with the smallest mean |direction error| on the training
    intervals after the training mean yaw offset (what PDR without a per-walk offset sees)."""
    best, best_err = TAU_GRID[0], math.inf
    for tau in TAU_GRID:
        o = replace(options, complementary_tau_s=tau)
        cal = _fit(train, o, "complementary")
        errs = []
        for w in train:
            iv = ph.waypoint_intervals(w.steps_with(_key(o), tau), w.wt, w.wxy)
            d = iv.disp_comp_m
            ok = (iv.distance_m >= MIN_DIRECTION_M) & (np.hypot(d[:, 0], d[:, 1]) > 0)
            errs.append(np.abs(ph.wrap_angle(iv.direction_rad[ok] - np.arctan2(d[ok, 1], d[ok, 0]) - cal.yaw_offset_rad)))
        err = float(np.mean(np.concatenate(errs)))
        if err < best_err:
            best, best_err = tau, err
    return best


def _select(train: List[_Walk]) -> ph.HandheldOptions:
    """The grid setting whose K fit leaves the smallest RMS residual on the training intervals."""
    best, best_rms = None, math.inf
    for o in _grid_options():
        key = _key(o)
        F, D = [], []
        for w in train:
            iv = ph.waypoint_intervals(w.steps[key], w.wt, w.wxy)
            F.append(iv.feature_sum)
            D.append(iv.distance_m)
        F, D = np.concatenate(F), np.concatenate(D)
        m = D >= MIN_DISTANCE_M
        if not np.any(F[m] > 0):
            continue
        k = float(np.dot(F[m], D[m]) / np.dot(F[m], F[m]))
        rms = float(np.sqrt(np.mean((k * F[m] - D[m]) ** 2)))
        if rms < best_rms:
            best, best_rms = o, rms
    assert best is not None
    return best


def _score(test: List[_Walk], cals: Dict[str, ph.HandheldCalibration], fold: int) -> Dict[str, List[np.ndarray]]:
    """Per held-out interval / waypoint errors, as lists of arrays to concatenate."""
    rec: Dict[str, List[np.ndarray]] = {}

    def add(name: str, v: Any) -> None:
        rec.setdefault(name, []).append(np.atleast_1d(np.asarray(v, dtype=np.float64)))

    cal_rv = cals["rotation_vector"]
    opts = cal_rv.options
    key = _key(opts)
    median_stride = cals["median_stride_m"]
    for w in test:
        st = ph.rescale(w.steps_with(key, opts.complementary_tau_s), opts)
        iv = ph.waypoint_intervals(st, w.wt, w.wxy)
        m = iv.distance_m >= MIN_DISTANCE_M
        expected = iv.distance_m / median_stride
        add("count_err", (iv.n_steps - expected)[m])
        add("count_rel", ((iv.n_steps - expected) / expected)[m])
        add("dist_err_m", (iv.path_m - iv.distance_m)[m])
        add("dist_rel", ((iv.path_m - iv.distance_m) / iv.distance_m)[m])
        # Baseline without steps: the training median speed times the interval's duration.
        add("const_speed_err_m", (cals["median_speed_mps"] * np.diff(w.wt) - iv.distance_m)[m])
        add("distance_m", iv.distance_m[m])
        add("fold", np.full(int(m.sum()), fold))
        # Coverage of the per-step length sd: |r_j| <= 2 f sqrt(sum L^2).
        add("len_cov2", (np.abs(iv.path_m - iv.distance_m) <= 2 * opts.length_sd_fraction * np.sqrt(iv.length_sq_sum))[m])
        md = iv.distance_m >= MIN_DIRECTION_M
        add("fold_dir", np.full(int(md.sum()), fold))
        for h in HEADINGS:
            cal = cals[h]
            disp = iv.displacement(h)
            ok = md & (np.hypot(disp[:, 0], disp[:, 1]) > 0)
            pdir = np.arctan2(disp[:, 1], disp[:, 0])
            raw = ph.wrap_angle(iv.direction_rad - pdir)
            add(f"{h}:dir_raw", np.where(ok, raw, np.nan)[md])
            add(f"{h}:dir_train", np.where(ok, ph.wrap_angle(raw - cal.yaw_offset_rad), np.nan)[md])
            if ok.sum() >= 1:
                own = ph.best_yaw_offset(iv.direction_rad[ok], disp[ok])
            else:
                own = 0.0
            e_own = ph.wrap_angle(raw - own)
            add(f"{h}:dir_own", np.where(ok, e_own, np.nan)[md])
            sd = cal.heading_sd_rad / np.sqrt(np.maximum(iv.n_steps, 1.0))
            add(f"{h}:dir_cov2", np.where(ok, np.abs(e_own) <= 2 * sd, np.nan)[md])
            # PDR-only from waypoint 0: (a) rotation-vector / gyro heading + training mean offset;
            # (b) the 'pdr_only': initial heading known (offset aligning the first interval).
            tq = w.wt[1:]
            pos = ph.pdr_track(st, w.wxy[0], tq, h, cal.yaw_offset_rad)
            add(f"{h}:pos_train", np.hypot(*(pos - w.wxy[1:]).T))
            first = np.hypot(disp[0, 0], disp[0, 1]) > 0 and iv.distance_m[0] > 0
            off0 = float(ph.wrap_angle(iv.direction_rad[0] - pdir[0])) if first else cal.yaw_offset_rad
            pos0 = ph.pdr_track(st, w.wxy[0], tq, h, off0)
            add(f"{h}:pos_init", np.hypot(*(pos0 - w.wxy[1:]).T))
        add("pos_t", w.wt[1:] - w.wt[0])
        add("fold_pos", np.full(len(w.wt) - 1, fold))
    return rec


def _folds(walks: List[_Walk], protocol: str, k: int, seed: int) -> List[Tuple[List[int], List[int]]]:
    n = len(walks)
    if protocol == "leave_one_floor_out":
        floors = sorted({w.floor for w in walks})
        return [([i for i in range(n) if walks[i].floor != f], [i for i in range(n) if walks[i].floor == f])
                for f in floors]
    rng = np.random.default_rng(seed)
    if protocol == "pooled":
        perm = rng.permutation(n)
        fold_of = np.empty(n, int)
        fold_of[perm] = np.arange(n) % k
        return [([i for i in range(n) if fold_of[i] != j], [i for i in range(n) if fold_of[i] == j]) for j in range(k)]
    # per_floor: fold j of every floor, trained on the other folds of the same floor.
    out = []
    floors = sorted({w.floor for w in walks})
    fold_of = np.empty(n, int)
    for f in floors:
        idx = np.array([i for i in range(n) if walks[i].floor == f])
        perm = rng.permutation(idx.size)
        fold_of[idx[perm]] = np.arange(idx.size) % k
    for f in floors:
        for j in range(k):
            test = [i for i in range(n) if walks[i].floor == f and fold_of[i] == j]
            train = [i for i in range(n) if walks[i].floor == f and fold_of[i] != j]
            out.append((train, test))
    return out


def _run_protocol(walks: List[_Walk], protocol: str, k: int, seed: int, detector: str = "grid") -> Dict[str, Any]:
    folds = _folds(walks, protocol, k, seed)
    rec: Dict[str, List[np.ndarray]] = {}
    chosen: List[Dict[str, Any]] = []
    floor_of_fold: List[str] = []
    for fi, (train_i, test_i) in enumerate(folds):
        train = [walks[i] for i in train_i]
        test = [walks[i] for i in test_i]
        opts = _select(train) if detector == "grid" else VARIANCE_OPTIONS
        opts = replace(opts, complementary_tau_s=_select_tau(train, opts))
        cals: Dict[str, Any] = {h: _fit(train, opts, h) for h in HEADINGS}
        key = _key(opts)
        feats = np.concatenate([w.steps[key].feature for w in train])
        cals["median_stride_m"] = float(np.median(cals["rotation_vector"].k * feats))
        speeds = np.concatenate([np.hypot(*np.diff(w.wxy, axis=0).T) / np.diff(w.wt) for w in train])
        cals["median_speed_mps"] = float(np.median(speeds))
        c = cals["rotation_vector"]
        chosen.append({"signal": opts.signal, "threshold_fraction": opts.threshold_fraction,
                       "min_peak_mps2": opts.min_peak_mps2, "min_step_interval_s": opts.min_step_interval_s,
                       "method": opts.method, "k": c.k, "complementary_tau_s": opts.complementary_tau_s, "median_stride_m": cals["median_stride_m"],
                       "length_sd_fraction": c.length_sd_fraction,
                       **{f"{h}:yaw_offset_deg": math.degrees(cals[h].yaw_offset_rad) for h in HEADINGS},
                       **{f"{h}:yaw_spread_deg": math.degrees(cals[h].yaw_offset_spread_rad) for h in HEADINGS},
                       **{f"{h}:heading_sd_deg": math.degrees(cals[h].heading_sd_rad) for h in HEADINGS}})
        group = fi % k if protocol == "per_floor" else fi  # per_floor: fold j of all floors together
        for name, vals in _score(test, cals, group).items():
            rec.setdefault(name, []).extend(vals)
        floor_of_fold.append(test[0].floor if test else "")
    arrays = {name: np.concatenate(v) if v else np.zeros(0) for name, v in rec.items()}
    # floor per record (per_floor / lofo): rebuild from the test walks
    floors = []
    for (train_i, test_i) in folds:
        for i in test_i:
            iv_m = walks[i].wxy
            d = np.hypot(*np.diff(iv_m, axis=0).T)
            floors.append((walks[i].floor, int((d >= MIN_DISTANCE_M).sum()), int((d >= MIN_DIRECTION_M).sum()), len(d)))
    arrays["floor"] = np.concatenate([np.full(a, f) for f, a, _, _ in floors]) if floors else np.zeros(0, str)
    arrays["floor_dir"] = np.concatenate([np.full(b, f) for f, _, b, _ in floors]) if floors else np.zeros(0, str)
    arrays["floor_pos"] = np.concatenate([np.full(c, f) for f, _, _, c in floors]) if floors else np.zeros(0, str)
    return {"arrays": arrays, "chosen": chosen, "n_folds": len(folds)}


def _stats(v: np.ndarray, fold: Optional[np.ndarray] = None, absolute: bool = True) -> Dict[str, float]:
    v = np.asarray(v, float)
    ok = np.isfinite(v)
    x = np.abs(v[ok]) if absolute else v[ok]
    if x.size == 0:
        return {"n": 0, "mean": math.nan, "median": math.nan, "p90": math.nan, "fold_sd_mean": math.nan}
    out = {"n": int(x.size), "mean": float(np.mean(x)), "median": float(np.median(x)),
           "p90": float(np.percentile(x, 90)), "fold_sd_mean": math.nan, "fold_sd_median": math.nan,
           "fold_sd_p90": math.nan}
    if fold is not None:
        f = np.asarray(fold)[ok]
        groups = [x[f == g] for g in np.unique(f) if np.any(f == g)]
        if len(groups) > 1:
            out["fold_sd_mean"] = float(np.std([np.mean(g) for g in groups], ddof=1))
            out["fold_sd_median"] = float(np.std([np.median(g) for g in groups], ddof=1))
            out["fold_sd_p90"] = float(np.std([np.percentile(g, 90) for g in groups], ddof=1))
    return out


def _summaries(run: Dict[str, Any]) -> Dict[str, Any]:
    a = run["arrays"]
    floors = sorted(set(a["floor"].tolist()))
    out: Dict[str, Any] = {}
    for scope in ["all"] + floors:
        sel = np.ones(a["floor"].size, bool) if scope == "all" else a["floor"] == scope
        seld = np.ones(a["floor_dir"].size, bool) if scope == "all" else a["floor_dir"] == scope
        selp = np.ones(a["floor_pos"].size, bool) if scope == "all" else a["floor_pos"] == scope
        s: Dict[str, Any] = {
            "count_err": _stats(a["count_err"][sel], a["fold"][sel]),
            "count_rel": _stats(a["count_rel"][sel], a["fold"][sel]),
            "dist_err_m": _stats(a["dist_err_m"][sel], a["fold"][sel]),
            "dist_rel": _stats(a["dist_rel"][sel], a["fold"][sel]),
            "const_speed_err_m": _stats(a["const_speed_err_m"][sel], a["fold"][sel]),
            "dist_bias_m": float(np.mean(a["dist_err_m"][sel])) if sel.any() else math.nan,
            "len_cov2": float(np.mean(a["len_cov2"][sel])) if sel.any() else math.nan,
        }
        for h in HEADINGS:
            for m in ("dir_raw", "dir_train", "dir_own"):
                s[f"{h}:{m}_deg"] = _stats(np.degrees(a[f"{h}:{m}"][seld]), a["fold_dir"][seld])
            cov = a[f"{h}:dir_cov2"][seld]
            s[f"{h}:dir_cov2"] = float(np.nanmean(cov)) if np.isfinite(cov).any() else math.nan
            for m in ("pos_train", "pos_init"):
                s[f"{h}:{m}_m"] = _stats(a[f"{h}:{m}"][selp], a["fold_pos"][selp])
        out[scope] = s
    return out


def evaluate(data_root: PathLike, floors: Optional[Sequence[str]] = None, folds: int = 4, seed: int = 0,
             protocols: Sequence[str] = ("per_floor", "pooled", "leave_one_floor_out")) -> Dict[str, Any]:
    """Cross-validated hand-held PDR on the ILC walks of ``data_root``; see the module docstring.

    Returns ``{"settings", "protocols": {name: {"summary": {scope: ...}, "chosen": [per fold]}},
    "variance_detector": {...}, "seconds"}``; ``markdown(result)`` renders it.
    """
    t0 = time.perf_counter()
    walks = load_walks(data_root, floors)
    t_load = time.perf_counter() - t0
    result: Dict[str, Any] = {
        "settings": {"data_root": str(data_root), "floors": sorted({w.floor for w in walks}), "folds": folds,
                     "seed": seed, "grid": {k: list(v) for k, v in GRID.items()},
                     "min_distance_m": MIN_DISTANCE_M, "min_direction_m": MIN_DIRECTION_M,
                     "n_walks": len(walks), "n_waypoints": int(sum(len(w.wt) for w in walks))},
        "protocols": {},
    }
    for p in protocols:
        run = _run_protocol(walks, p, folds, seed)
        result["protocols"][p] = {"summary": _summaries(run), "chosen": run["chosen"], "n_folds": run["n_folds"]}
    run = _run_protocol(walks, "per_floor", folds, seed, detector="variance")
    result["variance_detector"] = {"summary": _summaries(run), "chosen": run["chosen"]}
    result["seconds"] = {"load_and_detect": t_load, "total": time.perf_counter() - t0}
    return result


def _f(s: Dict[str, float], key: str, fmt: str = "{:.2f}") -> str:
    v, sd = s[key], s.get(f"fold_sd_{key}", math.nan)
    return fmt.format(v) + ("" if not math.isfinite(sd) else " ± " + fmt.format(sd))


def _row(label: str, s: Dict[str, float], fmt: str = "{:.2f}") -> str:
    return f"| {label} | {s['n']} | {_f(s, 'mean', fmt)} | {_f(s, 'median', fmt)} | {_f(s, 'p90', fmt)} |"


def _counts(values: Sequence[Any]) -> Dict[Any, int]:
    out: Dict[Any, int] = {}
    for v in values:
        out[v] = out.get(v, 0) + 1
    return out


def markdown(result: Dict[str, Any]) -> str:
    lines: List[str] = []
    st = result["settings"]
    lines.append(f"Hand-held PDR, {st['n_walks']} walks, {st['n_waypoints']} waypoints, floors "
                 f"{', '.join(st['floors'])}, {st['folds']} folds by walk, seed {st['seed']}. "
                 "Errors are absolute; ± is the sd over folds.")
    head = "| | n | mean | median | p90 |\n|---|---:|---:|---:|---:|"
    for p, r in result["protocols"].items():
        lines.append(f"\n### {p}\n")
        ch = r["chosen"]
        ks = np.array([c["k"] for c in ch])
        sig = {}
        for c in ch:
            t = (c["signal"], c["threshold_fraction"], c["min_peak_mps2"], c["min_step_interval_s"])
            sig[t] = sig.get(t, 0) + 1
        lines.append("Chosen on training folds: K " + f"{ks.mean():.3f} (range {ks.min():.3f}-{ks.max():.3f}); "
                     "detector (signal, threshold fraction, min peak, min interval) x folds: "
                     + "; ".join(f"{t} x{n}" for t, n in sorted(sig.items(), key=lambda kv: -kv[1])) + "; "
                     + "complementary tau x folds: " + ", ".join(
                         f"{t:g} s x{n}" for t, n in sorted(_counts([c["complementary_tau_s"] for c in ch]).items()))
                     + "; median stride {:.2f} m; length sd {:.3f} L; ".format(
                         np.mean([c["median_stride_m"] for c in ch]), np.mean([c["length_sd_fraction"] for c in ch]))
                     + "; ".join(f"{h}: yaw offset {np.mean([c[f'{h}:yaw_offset_deg'] for c in ch]):.1f}° "
                                 f"(per-walk spread {np.mean([c[f'{h}:yaw_spread_deg'] for c in ch]):.1f}°), "
                                 f"step heading sd {np.mean([c[f'{h}:heading_sd_deg'] for c in ch]):.1f}°"
                                 for h in HEADINGS) + ".")
        for scope, s in r["summary"].items():
            lines.append(f"\n**{p}, {scope}**\n")
            lines.append(head)
            lines.append(_row("step count - distance / median stride [steps]", s["count_err"]))
            lines.append(_row("  same, relative", s["count_rel"]))
            lines.append(_row("path length - straight distance [m]", s["dist_err_m"]))
            lines.append(_row("  same, relative", s["dist_rel"]))
            lines.append(_row("baseline: training median speed x duration - distance [m]", s["const_speed_err_m"]))
            for h in HEADINGS:
                lines.append(_row(f"{h}: direction, raw [°]", s[f"{h}:dir_raw_deg"], "{:.1f}"))
                lines.append(_row(f"{h}: direction, training mean offset [°]", s[f"{h}:dir_train_deg"], "{:.1f}"))
                lines.append(_row(f"{h}: direction, walk's best offset [°]", s[f"{h}:dir_own_deg"], "{:.1f}"))
                lines.append(_row(f"{h}: PDR-only position, RV heading + training offset [m]", s[f"{h}:pos_train_m"]))
                lines.append(_row(f"{h}: PDR-only position, true initial heading [m]", s[f"{h}:pos_init_m"]))
            lines.append(f"\nsigned mean path error {s['dist_bias_m']:+.2f} m; intervals inside ±2 sd: length "
                         f"{100 * s['len_cov2']:.0f} %, direction " + ", ".join(
                             f"{h} {100 * s[f'{h}:dir_cov2']:.0f} %" for h in HEADINGS))
    v = result["variance_detector"]["summary"]["all"]
    g = result["protocols"].get("per_floor", {}).get("summary", {}).get("all")
    lines.append("\n### Detectors compared (per_floor protocol, all floors; K fitted per fold)\n")
    lines.append("| detector | interval count rel. error mean / median / p90 | path error [m] mean / median / p90 |")
    lines.append("|---|---|---|")
    for name, s in (("band-passed peaks (grid on training folds)", g), ("paper 002 variance detector", v)):
        if s is None:
            continue
        lines.append(f"| {name} | {s['count_rel']['mean']:.3f} / {s['count_rel']['median']:.3f} / "
                     f"{s['count_rel']['p90']:.3f} | {s['dist_err_m']['mean']:.2f} / "
                     f"{s['dist_err_m']['median']:.2f} / {s['dist_err_m']['p90']:.2f} |")
    lines.append(f"\n{result['seconds']['total']:.1f} s in all ({result['seconds']['load_and_detect']:.1f} s "
                 "loading and detection).")
    return "\n".join(lines)


def main(data_root: Optional[PathLike] = None, floors: Optional[Sequence[str]] = None, folds: int = 4,
         seed: int = 0) -> Dict[str, Any]:
    """Runs :func:`evaluate` and prints :func:`markdown`; the data root defaults to
    ``shared/data/fusion/ilc2020_site2`` beside the WiFi data folder."""
    if data_root is None:
        from indoorloc.registry import default_data_root
        data_root = default_data_root().parent / "fusion" / "ilc2020_site2"
    result = evaluate(data_root, floors, folds, seed)
    print(markdown(result))
    return result


if __name__ == "__main__":
    main()
