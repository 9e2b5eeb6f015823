"""WiFi fingerprint fixes for the fusion tracker: each scan of a walk matched against the scans
of a crowdsourced training set, its best matches turned into a Gaussian-mixture position fix
(``fusion.Fixes``) with an outlier floor (docs/fusion_real.md, "WiFi as fixes").

Why scans and not the cell map: on the competition mall the per-cell model of paper 004 and
Euclidean kNN over every AP with a floor value are 20-30 m off on average
(docs/fusion_real.md). Two dissimilarities of a query scan a against a training scan b do
better there (``FixSettings.metric``):

- ``"strongest"``: the RMS difference over the query's n strongest APs, an AP the training scan
  did not hear counting at the floor value v₀:
  d(a, b) = sqrt(mean_{i ∈ top_n(a)} (a_i - b̃_i)²), b̃_i = b_i or v₀  [dB]. Strong readings are
  the ones that locate (near APs); weak ones come and go with the body and the crowd.
- ``"union"``: the mean absolute difference over the union of the APs heard, an AP heard in one
  scan only costing c: d(a, b) = (Σ_{i ∈ A∩B} |a_i - b_i| + c |A Δ B|) / |A ∪ B|  [dB].

The k best training scans become the components of the fix, at the positions where they were
recorded, with weights exp(-(d_j - d_min) / T) and sd σ; the tracker adds the outlier floor ε
(``TrackerOptions.fix_outlier_probability``). The metric and the tracker's ε and τ_fix are chosen
by leave-one-floor-out cross-validation (``indoorloc fusion evaluate --select``).

Training scans are placed at their measurement epoch (the median last-seen time of their fresh
readings, ``wifi_crowdsource.scan_epochs``) by ``wifi_crowdsource.walk_positions`` (PDR between
the waypoints); the fixes of a walk are timed the same way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc import fusion
from indoorloc import pdr_handheld as ph
from indoorloc import wifi_crowdsource as wc
from indoorloc.validate import integer, real_array, real_scalar

METRICS = ("strongest", "union")


@dataclass
class FixSettings:
    """Settings of the fingerprint fixes (defaults: leave-one-floor-out choice, docs/fusion_real.md)."""

    fresh_age_s: float = 2.5        #: readings at most this old make a scan's fingerprint [s]
    min_scans: int = 3              #: keep a BSSID heard in at least this many training scans
    metric: str = "strongest"       #: "strongest" or "union" (module docstring; LOFO)
    strongest_n: int = 10           #: n of "strongest" (fixed in advance: a scan's near APs)
    not_heard_dbm: float = -100.0   #: v₀ of "strongest" (the issue's floor value)
    unshared_cost_db: float = 20.0  #: c of "union": cost of an AP heard in one scan only [dB]
    k: int = 8                      #: components per fix (best training scans)
    temperature_db: float = 2.0     #: T of the component weights [dB]
    sd_m: float = 4.0               #: σ of each component [m]
    min_aps: int = 3                #: scans with fewer APs known to the database give no fix

    def validate(self) -> None:
        """Raises ValueError naming the first invalid field."""
        if self.metric not in METRICS:
            raise ValueError(f"indoorloc: FixSettings.metric must be one of {METRICS}, got {self.metric!r}")
        if not (isinstance(self.not_heard_dbm, (int, float)) and -300 < self.not_heard_dbm < 50):
            raise ValueError(f"indoorloc: FixSettings.not_heard_dbm must be in (-300, 50) dBm, got {self.not_heard_dbm!r}")
        for name in ("fresh_age_s", "unshared_cost_db", "temperature_db", "sd_m"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"indoorloc: FixSettings.{name} must be finite and > 0, got {v!r}")
        for name in ("min_scans", "k", "min_aps", "strongest_n"):
            v = getattr(self, name)
            if not (isinstance(v, (int, np.integer)) and 1 <= v <= 10_000):
                raise ValueError(f"indoorloc: FixSettings.{name} must be an integer in [1, 10000], got {v!r}")


def fresh_scans(walk: Any, fresh_age_s: float, bssids: Optional[Sequence[str]] = None
                ) -> Tuple[np.ndarray, np.ndarray, List[str]]:
    """The fresh fingerprint of every scan of a walk.

    Returns ``(epochs_s (S,), rss_dbm (S, K), bssids)``: per scan with at least one reading at
    most ``fresh_age_s`` old, its epoch (median last-seen time of those readings, walk clock [s])
    and the readings (NaN = not heard; a BSSID listed twice: the stronger). Columns are
    ``bssids`` when given (others dropped), else the walk's own vocabulary."""
    wf = walk.wifi
    names = list(wf.bssids) if bssids is None else list(bssids)
    index = {b: i for i, b in enumerate(names)}
    epochs = wc.scan_epochs(wf, fresh_age_s)
    keep = np.flatnonzero(np.isfinite(epochs))
    rss = np.full((keep.size, len(names)), np.nan)
    if wf.n_readings and keep.size:
        row_of_scan = np.full(wf.n_scans, -1, dtype=np.int64)
        row_of_scan[keep] = np.arange(keep.size)
        col = np.array([index.get(b, -1) for b in wf.bssids], dtype=np.int64)[wf.bssid_index]
        row = row_of_scan[wf.scan_index]
        sel = (wf.age_s <= fresh_age_s) & (col >= 0) & (row >= 0)
        order = np.argsort(wf.rssi_dbm[sel], kind="stable")  # stronger last: it wins the assignment
        r, c, v = row[sel][order], col[sel][order], wf.rssi_dbm[sel][order]
        rss[r, c] = v
    return epochs[keep], rss, names


@dataclass
class FingerprintDatabase:
    """Training scans: fingerprints (N, K) [dBm, NaN = not heard], positions (N, 2) [m], floor
    number of each scan (N,) and the BSSID of each column."""

    rss_dbm: np.ndarray
    positions_m: np.ndarray
    bssids: List[str]
    settings: FixSettings
    floors: Optional[np.ndarray] = None

    def __post_init__(self) -> None:
        if self.floors is None:
            self.floors = np.zeros(self.positions_m.shape[0], dtype=np.int64)

    def with_settings(self, settings: FixSettings) -> "FingerprintDatabase":
        """The same scans with other fix settings (``min_scans`` and ``fresh_age_s`` are those
        the database was built with)."""
        settings.validate()
        return FingerprintDatabase(self.rss_dbm, self.positions_m, self.bssids, settings, self.floors)

    @property
    def n_scans(self) -> int:
        return int(self.positions_m.shape[0])


def build_database(train_walks: Sequence[Any], settings: Optional[FixSettings] = None,
                   steps: Optional[Sequence[ph.HandheldSteps]] = None,
                   map_settings: Optional[wc.CrowdMapSettings] = None,
                   floors: Optional[Sequence[int]] = None) -> FingerprintDatabase:
    """Every fresh scan of the training walks, placed at its epoch by PDR between waypoints
    (``wifi_crowdsource.walk_positions``); BSSIDs heard in fewer than ``min_scans`` scans dropped.
    ``floors``: the floor number of each walk (default 0), for fixes over several floors.
    Raises ValueError when no scan can be placed."""
    s = settings or FixSettings()
    s.validate()
    if floors is not None and len(floors) != len(train_walks):
        raise ValueError(f"indoorloc: argument 'floors': expected {len(train_walks)} floor numbers (one per walk), "
                         f"got {len(floors)}")
    per_walk = []
    for i, walk in enumerate(train_walks):
        t, rss, names = fresh_scans(walk, s.fresh_age_s)
        if t.size == 0:
            continue
        pos = wc.walk_positions(walk, t, map_settings, None if steps is None else steps[i])
        if pos.valid.any():
            fl = 0 if floors is None else int(floors[i])
            per_walk.append((rss[pos.valid], pos.xy_m[pos.valid], names, np.full(int(pos.valid.sum()), fl)))
    if not per_walk:
        raise ValueError("indoorloc: argument 'train_walks': no WiFi scan could be placed (no fresh readings "
                         "between waypoints)")
    counts: Dict[str, int] = {}
    for rss, _, names, _ in per_walk:
        heard = np.isfinite(rss).sum(axis=0)
        for name, c in zip(names, heard):
            if c:
                counts[name] = counts.get(name, 0) + int(c)
    vocab = sorted(b for b, c in counts.items() if c >= s.min_scans)
    col = {b: i for i, b in enumerate(vocab)}
    blocks, positions, scan_floors = [], [], []
    for rss, xy, names, fl in per_walk:
        out = np.full((rss.shape[0], len(vocab)), np.nan)
        src = np.array([i for i, b in enumerate(names) if b in col], dtype=np.int64)
        dst = np.array([col[names[i]] for i in src], dtype=np.int64)
        if src.size:
            out[:, dst] = rss[:, src]
        blocks.append(out)
        positions.append(xy)
        scan_floors.append(fl)
    return FingerprintDatabase(np.vstack(blocks), np.vstack(positions), vocab, s, np.concatenate(scan_floors))


def _rss_pair(queries_dbm: Any, database_dbm: Any) -> Tuple[np.ndarray, np.ndarray]:
    """(Q, K) and (N, K) RSS [dBm], NaN = not heard; any other value a real RSS within +-1000 dBm
    (1e300 made the dissimilarities inf)."""
    q = real_array(queries_dbm, "queries_dbm", ndim=2, finite=False, max_abs=1e3)
    x = real_array(database_dbm, "database_dbm", ndim=2, finite=False, max_abs=1e3)
    for a, name in ((q, "queries_dbm"), (x, "database_dbm")):
        if np.isinf(a).any():
            raise ValueError(f"indoorloc: argument '{name}': must hold finite RSS or NaN (not heard), got inf")
    if q.shape[1] != x.shape[1]:
        raise ValueError(f"indoorloc: argument 'database_dbm': expected shape (N, {q.shape[1]}) "
                         f"(the columns of 'queries_dbm'), got {x.shape}")
    return q, x


def scan_dissimilarity(queries_dbm: np.ndarray, database_dbm: np.ndarray, unshared_cost_db: float
                       ) -> np.ndarray:
    """d(a, b) of the module docstring for every query (Q, K) against every database scan (N, K)
    (NaN = not heard): (Q, N) [dB]; +inf where the union of heard APs is empty."""
    q, x = _rss_pair(queries_dbm, database_dbm)
    unshared_cost_db = real_scalar(unshared_cost_db, "unshared_cost_db", lo=0.0, hi=1e3)
    qh, xh = ~np.isnan(q), ~np.isnan(x)
    q0, x0 = np.where(qh, q, 0.0), np.where(xh, x, 0.0)
    qh_f, xh_f = qh.astype(float), xh.astype(float)
    shared = qh_f @ xh_f.T                                           # |A ∩ B|
    union = qh_f.sum(1)[:, None] + xh_f.sum(1)[None, :] - shared      # |A ∪ B|
    # Σ over shared APs of |a - b|, by chunks of queries to bound memory (Q x N x K).
    abs_sum = np.empty(shared.shape)
    chunk = max(1, int(2e7 // max(1, x.shape[0] * x.shape[1])))
    for a in range(0, q.shape[0], chunk):
        b = min(q.shape[0], a + chunk)
        diff = np.abs(q0[a:b, None, :] - x0[None, :, :])
        both = qh[a:b, None, :] & xh[None, :, :]
        abs_sum[a:b] = np.where(both, diff, 0.0).sum(axis=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        d = (abs_sum + unshared_cost_db * (union - shared)) / union
    return np.where(union > 0, d, np.inf)


def strongest_ap_dissimilarity(queries_dbm: np.ndarray, database_dbm: np.ndarray, n: int,
                               not_heard_dbm: float) -> np.ndarray:
    """d(a, b) of ``"strongest"`` (module docstring) for every query (Q, K) against every
    database scan (N, K) (NaN = not heard): (Q, N) [dB]; +inf for a query that heard nothing."""
    q, x = _rss_pair(queries_dbm, database_dbm)
    n = integer(n, "n", lo=1, hi=10_000)
    not_heard_dbm = real_scalar(not_heard_dbm, "not_heard_dbm", lo=-300.0, hi=50.0)
    x = np.where(np.isnan(x), not_heard_dbm, x)
    out = np.full((q.shape[0], x.shape[0]), np.inf)
    for r in range(q.shape[0]):  # one small (N, n) block per query scan
        heard = np.flatnonzero(np.isfinite(q[r]))
        if heard.size == 0:
            continue
        top = heard[np.argsort(-q[r, heard], kind="stable")[:n]]
        out[r] = np.sqrt(np.mean((x[:, top] - q[r, top]) ** 2, axis=1))
    return out


def dissimilarity(queries_dbm: np.ndarray, database: "FingerprintDatabase") -> np.ndarray:
    """The database's metric (``settings.metric``) of every query (Q, K) to every scan: (Q, N) [dB]."""
    s = database.settings
    if s.metric == "strongest":
        return strongest_ap_dissimilarity(queries_dbm, database.rss_dbm, s.strongest_n, s.not_heard_dbm)
    return scan_dissimilarity(queries_dbm, database.rss_dbm, s.unshared_cost_db)


def fixes_for_walk(walk: Any, database: FingerprintDatabase, with_floors: bool = True) -> fusion.Fixes:
    """One fix per fresh scan of the walk with at least ``min_aps`` APs of the database: the
    ``k`` most similar training scans as components (module docstring), each on the floor of
    its training scan (``with_floors``; else on any floor)."""
    s = database.settings
    t, rss, _ = fresh_scans(walk, s.fresh_age_s, database.bssids)
    ok = np.isfinite(rss).sum(axis=1) >= s.min_aps
    t, rss = t[ok], rss[ok]
    k = min(s.k, database.n_scans)
    if t.size == 0:
        return fusion.Fixes.from_arrays(np.zeros(0), np.zeros((0, k, 2)), np.zeros((0, k)), np.zeros((0, k)))
    d = dissimilarity(rss, database)
    best = np.argsort(d, axis=1, kind="stable")[:, :k]
    db = np.take_along_axis(d, best, axis=1)
    weights = np.exp(-(db - db[:, :1]) / s.temperature_db)
    weights[~np.isfinite(db)] = 0.0
    order = np.argsort(t, kind="stable")
    floors = database.floors[best[order]] if with_floors else None
    return fusion.Fixes.from_arrays(t[order], database.positions_m[best[order]], s.sd_m, weights[order], floors)


def fix_centres(fixes: fusion.Fixes) -> np.ndarray:
    """The weighted mean position (F, 2) [m] of each fix's components: the kNN estimate of the
    scan (the WiFi-only baseline on this metric)."""
    w = fixes.weights / np.maximum(fixes.weights.sum(axis=1, keepdims=True), 1e-300)
    return (w[:, :, None] * np.where(fixes.weights[:, :, None] > 0, fixes.means_m, 0.0)).sum(axis=1)


def locate_scans(rss_dbm: np.ndarray, database: FingerprintDatabase) -> np.ndarray:
    """WiFi-only positions (Q, 2) [m] of scans (Q, K in the database's columns): the
    weight-averaged position of each scan's fix components (the kNN baseline on this metric)."""
    s = database.settings
    d = dissimilarity(rss_dbm, database)
    k = min(s.k, database.n_scans)
    best = np.argsort(d, axis=1, kind="stable")[:, :k]
    db = np.take_along_axis(d, best, axis=1)
    w = np.exp(-(db - db[:, :1]) / s.temperature_db)
    w = np.where(np.isfinite(db), w, 0.0)
    w_sum = w.sum(axis=1, keepdims=True)
    pos = (w[:, :, None] * database.positions_m[best]).sum(axis=1) / np.where(w_sum > 0, w_sum, 1.0)
    return np.where(w_sum > 0, pos, np.nan)


__all__ = [
    "FingerprintDatabase",
    "FixSettings",
    "METRICS",
    "build_database",
    "dissimilarity",
    "fix_centres",
    "fixes_for_walk",
    "fresh_scans",
    "locate_scans",
    "scan_dissimilarity",
    "strongest_ap_dissimilarity",
]
