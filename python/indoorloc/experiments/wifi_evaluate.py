"""Real-data evaluation of the wifi methods (`indoorloc wifi evaluate`).

Every method runs on a dataset's train/test split:

- ``ml``: the paper's interpolated Gaussian model (Delaunay-linear means and variances), global
  maximum-likelihood fix (multi-start Fisher scoring);
- ``tracker``: the paper's gradient tracker fed the k scans of a static point in turn (global
  first fix, then Fisher steps): what the tracker converges to;
- ``mmse``: the same likelihood, posterior mean over a grid of the mapped area (beyond the paper);
- ``nnss`` (RADAR), ``nnss_avg`` (mean of the k nearest points), ``horus`` (Gaussian likelihood
  over reference points): on the signal map's per-point statistics;
- ``wknn``: weighted k nearest neighbours on the raw training scans.
- ``shared_knn``: the fusion tracker's WiFi matcher (``indoorloc.wifi_matcher``, C++
  ``SharedApMatcher``) on the raw training scans, "not heard" left out rather than replaced by a
  floor value: RMS RSS difference over the APs both heard + c x the unshared fraction, the k
  nearest weighted exp(-(d - d_min) / T), the floor by weighted vote. AP reliability weights are
  off (they need references of several walks at one place); c, β, k and T by cross-validation.

Two protocols: one scan per estimate, and k consecutive scans at a static test point (the ML
method multiplies the k likelihoods; the baselines match the averaged scan). Hyper-parameters
(variance floor and per-AP cap of the model, k of the neighbour methods; c, β, k, T of
``shared_knn``) are chosen by
leave-one-reference-point-out cross-validation on the training data only; test files never
influence them.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Dict, Iterable, List, Optional, Sequence

import numpy as np

from indoorloc import metrics, wifi
from indoorloc.wifi import matcher as wifi_matcher
from indoorloc.io.wifi_datasets import FingerprintDataset, FingerprintSplit
from indoorloc.experiments.markdown_table import titled_table
from indoorloc.progress import progress

NOT_HEARD_DBM = -105.0
METHODS = ("ml", "mmse", "tracker", "nnss", "nnss_avg", "wknn", "horus", "shared_knn")
#: Cross-validation grid of shared_knn: c [dB], β [dB], k, T [dB] (fixed in advance; the fusion
#: defaults 160 / 5 / 20 / 3 are inside it).
SHARED_GRID = {"penalty_db": (10.0, 20.0, 40.0, 80.0, 160.0), "strength_scale_db": (0.0, 5.0),
               "k": (1, 2, 3, 4, 5, 6, 8, 12, 20, 30, 50, 80, 120, 200), "temperature_db": (1.0, 3.0, 10.0, 1e3)}


def _shared_defaults() -> Dict[str, float]:
    return wifi.SharedApMatcherOptions().to_dict()


def not_heard_as_nan(rss_dbm: np.ndarray, sentinel: float) -> np.ndarray:
    """The dataset's RSS (S, K) [dBm] with its "not heard" sentinel replaced by NaN."""
    x = np.array(rss_dbm, dtype=float)
    x[x == sentinel] = np.nan
    return x


def block_mean(x: np.ndarray, k: int) -> np.ndarray:
    """Per AP, the mean of the readings heard in each block of k consecutive rows (NaN if none)."""
    if k == 1:
        return x
    b = x.reshape(-1, k, x.shape[1])
    heard = np.isfinite(b)
    n = heard.sum(axis=1)
    total = np.where(heard, b, 0.0).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > 0, total / np.maximum(n, 1), np.nan)


@dataclass
class Hyper:
    """Hyper-parameters of every method (chosen by cross-validation on training points)."""

    variance_floor_db2: float = 4.0
    max_term: float = np.inf
    k: Dict[str, int] = field(default_factory=lambda: {"nnss_avg": 4, "wknn": 5, "horus": 4})
    #: Per model-based method ("ml", "mmse"): (variance floor, cap), when they differ.
    model: Dict[str, tuple] = field(default_factory=dict)
    #: shared_knn: penalty_db, strength_scale_db, k, temperature_db (default: the C++ defaults).
    shared: Dict[str, float] = field(default_factory=_shared_defaults)

    def for_method(self, method: str) -> "Hyper":
        """These settings with the model's (variance floor, cap) chosen for ``method``."""
        if method not in self.model:
            return self
        vf, cap = self.model[method]
        return Hyper(variance_floor_db2=vf, max_term=cap, k=self.k, shared=self.shared)


@dataclass
class MethodResult:
    method: str
    errors_m: np.ndarray  # (G,) 2-D error per estimate
    floor_hit: np.ndarray  # (G,) bool
    seconds: float

    def row(self, seed: int = 0) -> dict:
        s = metrics.error_stats(self.errors_m)
        lo, hi = metrics.bootstrap_interval(self.errors_m, n_boot=1000, seed=seed)
        return {
            "method": self.method,
            "n": s.count,
            "mean_m": s.mean,
            "mean_ci95_m": (lo, hi),
            "median_m": s.median,
            "p75_m": s.p75,
            "p90_m": s.p90,
            "floor_hit_rate": float(self.floor_hit.mean()),
            "ms_per_estimate": 1e3 * self.seconds / max(1, s.count),
        }


def group_consecutive(split: FingerprintSplit, k: int) -> np.ndarray:
    """Row indices (G, k): blocks of k consecutive scans (in file order) at one test location.

    A location's scans may be spread over several files (UJI: the same route is walked in each
    test set); they are taken in file order and cut into blocks of k, the remainder dropped.
    """
    blocks: List[np.ndarray] = []
    for pid in np.unique(split.point_ids):
        run = np.flatnonzero(split.point_ids == pid)
        for b in range(len(run) // k):
            blocks.append(run[b * k : (b + 1) * k])
    return np.array(blocks, dtype=np.int64).reshape(-1, k)


def build_map(train: FingerprintSplit, sentinel: float, hyper: Hyper, rows=None) -> wifi.SignalMap:
    rows = slice(None) if rows is None else rows
    return wifi.SignalMap.from_scans(
        train.positions_m[rows],
        train.floors[rows],
        train.rss_dbm[rows],
        wifi.SignalMapOptions(
            not_heard_sentinel=sentinel, not_heard_dbm=NOT_HEARD_DBM, variance_floor_db2=hyper.variance_floor_db2
        ),
    )


class MethodSet:
    """Every method fitted on one training set (map + raw scans), ready to locate."""

    def __init__(self, train: FingerprintSplit, sentinel: float, hyper: Hyper, rows=None, num_threads: int = 1):
        self.sentinel = sentinel
        self.hyper = hyper
        self.num_threads = num_threads
        self.map = build_map(train, sentinel, hyper, rows)
        self.model = wifi.RssModel(
            self.map, wifi.RssModelOptions(variance_floor_db2=hyper.variance_floor_db2, max_term=hyper.max_term)
        )
        rows = slice(None) if rows is None else rows
        raw = self.map.prepare_scans(train.rss_dbm[rows], sentinel, NOT_HEARD_DBM)
        means, var = self.map.mean_dbm, self.map.variance_db2
        pos, floors = self.map.positions_m, self.map.floors.astype(np.float64)
        self.locators = {
            "nnss": wifi.FingerprintLocator(means, pos, floors, var, method="nnss", k=1),
            "nnss_avg": wifi.FingerprintLocator(means, pos, floors, var, method="nnss_avg", k=hyper.k["nnss_avg"]),
            "horus": wifi.FingerprintLocator(
                means, pos, floors, var, method="horus", k=hyper.k["horus"], variance_floor_db2=hyper.variance_floor_db2
            ),
            "wknn": wifi.FingerprintLocator(
                raw, train.positions_m[rows], train.floors[rows].astype(np.float64), None, method="wknn", k=hyper.k["wknn"]
            ),
        }
        self.options = wifi.tracker_options(num_starts=5, start_iterations=25)
        self.shared_index = wifi_matcher.ReferenceIndex.build(not_heard_as_nan(train.rss_dbm[rows], sentinel), None,
                                                    hyper.shared["strength_scale_db"])
        self.shared_positions = train.positions_m[rows]
        self.shared_floors = train.floors[rows]
        self._posterior = None  # built on first use (grid over the hull)

    def locate_shared(self, raw_rss_dbm: np.ndarray, k: int) -> tuple:
        """shared_knn: positions (G, 2) and floors (G,) of blocks of k consecutive raw scans
        (the dataset's sentinel for "not heard"), each block's readings averaged per AP heard."""
        h = self.hyper.shared
        q = block_mean(not_heard_as_nan(raw_rss_dbm, self.sentinel), k)
        best, _, w = wifi_matcher.shared_knn(q, self.shared_index, h["penalty_db"], int(h["k"]), h["temperature_db"],
                                   self.num_threads)
        return wifi_matcher.knn_positions(best, w, self.shared_positions, self.shared_floors)

    def prepare(self, rss_dbm: np.ndarray) -> np.ndarray:
        return self.map.prepare_scans(rss_dbm, self.sentinel, NOT_HEARD_DBM)

    def locate(self, method: str, prepared: np.ndarray, k: int) -> tuple:
        """Positions (G, 2) and floors (G,) of blocks of k consecutive prepared scans."""
        if method == "ml":
            out = wifi.locate_ml(self.model, prepared, group_size=k, options=self.options, num_threads=self.num_threads)
            return out["positions_m"], out["floors"]
        if method == "tracker":
            # What the tracker converges to at a static point: a global fix from the first
            # scan, then one Fisher-scoring step per further scan.
            tracker = wifi.GradientTracker(self.model, self.options)
            blocks = prepared.reshape(-1, k, prepared.shape[1])
            pos = np.empty((len(blocks), 2))
            floors = np.empty(len(blocks), dtype=np.int64)
            for b, block in enumerate(blocks):
                tracker.reset()
                out = tracker.track(block)
                pos[b], floors[b] = out["positions_m"][-1], out["floors"][-1]
            return pos, floors
        if method == "mmse":
            if self._posterior is None:
                self._posterior = wifi.GridPosterior(self.model)
            out = self._posterior.locate(prepared, group_size=k, num_threads=self.num_threads)
            return out["positions_m"], out["floors"]
        averaged = prepared.reshape(-1, k, prepared.shape[1]).mean(axis=1) if k > 1 else prepared
        pos, floors, _ = self.locators[method].locate(averaged, num_threads=self.num_threads)
        return pos, floors


def cross_validate(
    dataset: FingerprintDataset,
    k: int,
    max_points: int = 24,
    seed: int = 0,
    quiet_label: str = "cv",
    max_estimates_per_point: int = 24,
    num_threads: int = 1,
    methods: Optional[Sequence[str]] = None,
) -> Hyper:
    """Leave-one-reference-point-out over (a seeded subset of) the training points.

    For each held-out point, every candidate setting is fitted on the other points' scans and
    scored on the held-out point's scans (blocks of k). Returns the setting with the lowest mean
    error per method (averaged over the held-out points). ``methods``: tune only what these need
    (default: every method).
    """
    methods = METHODS if methods is None else methods
    tune_model = any(m in methods for m in ("ml", "mmse", "tracker"))
    tune_k = any(m in methods for m in ("nnss_avg", "wknn", "horus"))
    shared_err: Dict[tuple, List[float]] = {}
    train = dataset.train
    points = np.unique(train.point_ids)
    rng = np.random.default_rng(seed)
    held_out = rng.choice(points, size=min(max_points, points.size), replace=False)
    model_grid = [(vf, cap) for vf in (1.0, 4.0, 9.0, 16.0) for cap in (np.inf, 2.0, 5.0)]
    k_grid = (1, 2, 3, 4, 5, 6, 8)
    model_err = {m: {g: [] for g in model_grid} for m in ("ml", "mmse")}
    k_err = {m: {kk: [] for kk in k_grid} for m in ("nnss_avg", "wknn", "horus")}
    for p in progress(held_out, total=len(held_out), desc=quiet_label):
        rows = train.point_ids != p
        test_rows = np.flatnonzero(~rows)
        test_rows = test_rows[: min(len(test_rows) // k, max_estimates_per_point) * k]
        if test_rows.size == 0:
            continue
        truth = train.positions_m[test_rows].reshape(-1, k, 2)[:, 0]
        if "shared_knn" in methods:
            _shared_cv_point(train, rows, test_rows, k, dataset.not_heard_sentinel, truth, shared_err, num_threads)
        for vf, cap in (model_grid if tune_model else ()):
            ms = MethodSet(train, dataset.not_heard_sentinel, Hyper(vf, cap), rows=rows, num_threads=num_threads)
            prepared = ms.prepare(train.rss_dbm[test_rows])
            for m in model_err:
                pos, _ = ms.locate(m, prepared, k)
                model_err[m][(vf, cap)].append(np.linalg.norm(pos - truth, axis=1).mean())
        for kk in (k_grid if tune_k else ()):
            ms = MethodSet(train, dataset.not_heard_sentinel, Hyper(4.0, np.inf, {"nnss_avg": kk, "wknn": kk, "horus": kk}), rows=rows)
            prepared = ms.prepare(train.rss_dbm[test_rows])
            for m in k_err:
                pos, _ = ms.locate(m, prepared, k)
                k_err[m][kk].append(np.linalg.norm(pos - truth, axis=1).mean())
    default = Hyper()
    best_k = ({m: min(k_grid, key=lambda kk: np.mean(k_err[m][kk])) for m in k_err} if tune_k else default.k)
    model_best = ({m: min(model_grid, key=lambda g: np.mean(model_err[m][g])) for m in model_err} if tune_model
                  else {m: (default.variance_floor_db2, default.max_term) for m in model_err})
    shared = default.shared
    if shared_err:
        c, beta, kk, temp = min(shared_err, key=lambda g: np.mean(shared_err[g]))
        shared = {"penalty_db": c, "strength_scale_db": beta, "k": int(kk), "temperature_db": temp}
    return Hyper(variance_floor_db2=model_best["ml"][0], max_term=model_best["ml"][1], k=best_k,
                 model={m: model_best[m] for m in model_best}, shared=shared)


def _shared_cv_point(train: FingerprintSplit, rows: np.ndarray, test_rows: np.ndarray, k: int, sentinel: float,
                     truth: np.ndarray, err: Dict[tuple, List[float]], num_threads: int) -> None:
    """shared_knn's errors on one held-out point for every point of SHARED_GRID (appended to
    ``err[(c, β, k, T)]``): one (rms, u) per β, then every c, k and T from it."""
    queries = block_mean(not_heard_as_nan(train.rss_dbm[test_rows], sentinel), k)
    ref = not_heard_as_nan(train.rss_dbm[rows], sentinel)
    pos, floors = train.positions_m[rows], train.floors[rows]
    k_max = max(SHARED_GRID["k"])
    for beta in SHARED_GRID["strength_scale_db"]:
        index = wifi_matcher.ReferenceIndex.build(ref, None, beta)
        rms, u = wifi_matcher.shared_dissimilarity(queries, index, 0.0, parts=True, num_threads=num_threads)
        for c in SHARED_GRID["penalty_db"]:
            best, d, _ = wifi_matcher.knn(rms + c * u, k_max, 1.0)
            for temp in SHARED_GRID["temperature_db"]:
                with np.errstate(invalid="ignore"):
                    w = np.where(np.isfinite(d), np.exp(-(d - d[:, :1]) / temp), 0.0)
                for kk in SHARED_GRID["k"]:
                    p, _ = wifi_matcher.knn_positions(best[:, :kk], w[:, :kk], pos, floors)
                    err.setdefault((c, beta, kk, temp), []).append(float(np.linalg.norm(p - truth, axis=1).mean()))


def evaluate(
    dataset: FingerprintDataset,
    scans_per_estimate: int = 1,
    hyper: Optional[Hyper] = None,
    methods: Optional[Sequence[str]] = None,
    num_threads: int = 1,
    max_estimates: Optional[int] = None,
) -> Dict[str, MethodResult]:
    """Run ``methods`` on the test split; blocks of ``scans_per_estimate`` consecutive scans."""
    hyper = hyper or Hyper()
    k = scans_per_estimate
    if methods is None:  # the tracker equals the ML fix for a single scan
        methods = [m for m in METHODS if k > 1 or m != "tracker"]
    blocks = group_consecutive(dataset.test, k)
    if max_estimates is not None:
        blocks = blocks[:max_estimates]
    rows = blocks.ravel()
    truth = dataset.test.positions_m[blocks[:, 0]]
    truth_floor = dataset.test.floors[blocks[:, 0]]
    results = {}
    fitted: Dict[tuple, MethodSet] = {}
    for method in methods:
        h = hyper.for_method(method)
        key = (h.variance_floor_db2, h.max_term)
        if key not in fitted:
            fitted[key] = MethodSet(dataset.train, dataset.not_heard_sentinel, h, num_threads=num_threads)
        ms = fitted[key]
        if method == "shared_knn":  # raw scans: "not heard" is not replaced by a floor value
            start = time.perf_counter()
            pos, floors = ms.locate_shared(dataset.test.rss_dbm[rows], k)
        else:
            prepared = ms.prepare(dataset.test.rss_dbm[rows])
            start = time.perf_counter()
            pos, floors = ms.locate(method, prepared, k)
        elapsed = time.perf_counter() - start
        results[method] = MethodResult(
            method, np.linalg.norm(pos - truth, axis=1), np.asarray(floors) == truth_floor, elapsed
        )
    return results


def evaluate_case(root, name: str, k: int, cv_points: int, seed: int, num_threads: int = 0,
                  methods: Optional[Sequence[str]] = None):
    """One case of ``indoorloc wifi evaluate``: dataset ``name`` under ``root`` with ``k`` scans per
    estimate, hyper-parameters by cross-validation on its training points. ``methods``: a subset
    of METHODS (default: all; the tracker only with k > 1). Returns (markdown, JSON entry
    {"hyper": {"model", "k", "shared_knn"}, "results"})."""
    from indoorloc.io.wifi_datasets import load_wifi_dataset

    if methods is not None:
        unknown = [m for m in methods if m not in METHODS]
        if unknown:
            raise ValueError(f"indoorloc: argument 'methods': unknown {unknown} (choose from {', '.join(METHODS)})")
        methods = [m for m in methods if k > 1 or m != "tracker"]
    ds = load_wifi_dataset(name, root)
    hyper = cross_validate(ds, k=k, max_points=cv_points, seed=seed, quiet_label=f"cv {name} k={k}",
                           num_threads=num_threads, methods=methods)
    results = evaluate(ds, scans_per_estimate=k, hyper=hyper, num_threads=num_threads, methods=methods)
    title = (f"{ds.name}, {k} scan(s) per estimate (CV: model (variance floor, cap) {hyper.model}, k {hyper.k}, "
             f"shared_knn {_shared_text(hyper.shared)})")
    return markdown(results, title), {"hyper": {"model": hyper.model, "k": hyper.k, "shared_knn": dict(hyper.shared)},
                                      "results": [r.row() for r in results.values()]}


def _shared_text(h: Dict[str, float]) -> str:
    return f"c {h['penalty_db']:g} dB, beta {h['strength_scale_db']:g} dB, k {int(h['k'])}, T {h['temperature_db']:g} dB"


def markdown(results: Dict[str, MethodResult], title: str) -> str:
    rows = []
    for r in results.values():
        row = r.row()
        lo, hi = row["mean_ci95_m"]
        rows.append([row["method"], f"{row['n']}", f"{row['mean_m']:.2f} ({lo:.2f}-{hi:.2f})", f"{row['median_m']:.2f}",
                     f"{row['p75_m']:.2f}", f"{row['p90_m']:.2f}", f"{100 * row['floor_hit_rate']:.1f} %",
                     f"{row['ms_per_estimate']:.2f}"])
    return titled_table(title, ["method", "n", "mean [m] (95 % CI)", "median", "p75", "p90", "floor hit",
                                "ms/estimate"], rows)
