"""WiFi fingerprint fixes for the fusion tracker: each query fingerprint of a walk matched against the
fingerprints of a crowdsourced training set, its best matches turned into a Gaussian-mixture
position fix (``indoorloc.fusion.Fixes``) with an outlier floor (docs/fusion_real.md, "WiFi as fixes").

Fingerprints (``FixSettings.pooling``):

- ``"window"`` (default; :mod:`indoorloc.wifi_matcher`): every distinct measurement at its own
  last-seen time, whatever its age when reported. References every ``ref_spacing_s`` along each
  training walk, max-pooled over ``ref_window_s`` centred on that time and placed where the walker
  was then (``crowdsourced_map.walk_positions``, PDR between the waypoints). A query per scan of
  the walk, max-pooled over the ``query_window_s`` before the scan (causal), timed at the mean
  last-seen time of its measurements.
- ``"fresh"`` (the previous matcher): one fingerprint per scan from its readings at most
  ``fresh_age_s`` old, at the scan's measurement epoch (median last-seen time of those readings,
  ``crowdsourced_map.scan_epochs``).

Dissimilarities of a query a against a fingerprint b (``FixSettings.metric``):

- ``"shared"`` (default): the RMS RSS difference over the APs both heard plus c times the
  weighted fraction of APs heard by one only, each AP weighted by its reliability in training
  and its strength: see :func:`indoorloc.wifi_matcher.shared_dissimilarity`.
- ``"strongest"``: the RMS difference over the query's n strongest APs, an AP the training scan
  did not hear counting at the floor value v₀:
  d(a, b) = sqrt(mean_{i ∈ top_n(a)} (a_i - b̃_i)²), b̃_i = b_i or v₀  [dB].
- ``"union"``: the mean absolute difference over the union of the APs heard, an AP heard in one
  scan only costing c: d(a, b) = (Σ_{i ∈ A∩B} |a_i - b_i| + c |A Δ B|) / |A ∪ B|  [dB].

The k best training fingerprints become the components of the fix, at the positions where they
were recorded, with weights exp(-(d_j - d_min) / T) and sd σ; the tracker adds the outlier floor ε
(``TrackerOptions.fix_outlier_probability``). The matcher's settings are chosen by
leave-one-floor-out cross-validation (``python -m indoorloc.experiments.wifi_matcher_study``); the
tracker's ε and τ_fix by ``indoorloc fusion evaluate --select``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc.pdr import handheld
from indoorloc.fusion import crowdsourced_map
from indoorloc.fusion.fixes import Fixes
from indoorloc.wifi import matcher as wifi_matcher
from indoorloc._core.wifi import SharedApMatcherOptions
from indoorloc.validate import integer, real_array, real_scalar

METRICS = ("shared", "strongest", "union")
#: The compiled matcher's defaults (C++ SharedApMatcherOptions): c, β, k and T of the "shared"
#: metric are read from there, not restated (one definition per option).
_SHARED = SharedApMatcherOptions()
POOLINGS = ("window", "fresh")
ALIGNS = ("end", "centre")


@dataclass
class FixSettings:
    """Settings of the fingerprint fixes.

    Defaults: the leave-one-floor-out choice of ``python -m indoorloc.experiments.wifi_matcher_study``
    over the six floors of the competition site (docs/fusion_real.md, "WiFi as fixes"); how each
    was chosen is said beside it (LOFO: the point chosen on all six floors; the held-out figures
    are in docs/fusion_real.md). ``FixSettings(pooling="fresh", metric="strongest", k=8,
    temperature_db=2.0, sd_m=4.0, sd_per_db=0.0)`` is the previous matcher (fresh scans, strongest 10 APs)."""

    #: "window": fingerprints max-pooled over time windows of distinct measurements at their
    #: last-seen time (wifi_matcher); "fresh": one fingerprint per scan from its readings at most
    #: ``fresh_age_s`` old (the previous matcher). "window" was ahead or level on every floor in the quick runs.
    pooling: str = "window"
    ref_spacing_s: float = 1.0      #: a reference every this along each training walk [s] (fixed in advance: ~1.2 m of walking)
    #: Full width of a reference's window, centred on its time [s]. LOFO over {6, 10, 14}: 14 on
    #: four of six held-out floors; 10 is 0.02 m behind on all floors.
    ref_window_s: float = 14.0
    #: A query at scan time t pools the measurements last seen in [t - w, t] [s]. LOFO over
    #: {12, 16, 24} (after 2-12 in the quick runs): 16 on every held-out floor.
    query_window_s: float = 16.0
    #: "end": the query window ends at the scan time and uses only measurements reported by then
    #: (causal); "centre": [t - w/2, t + w/2], also measurements that later scans report. Fixed
    #: "end": "centre" was no better in the quick runs and would delay the fixes.
    query_align: str = "end"
    fresh_age_s: float = 2.5        #: "fresh" pooling: readings at most this old make a scan's fingerprint [s]
    min_scans: int = 3              #: keep a BSSID heard in at least this many training fingerprints (fixed in advance)
    metric: str = "shared"          #: "shared", "strongest" or "union" (wifi_matcher and module docstrings)
    #: c of "shared": d = weighted RMS over shared APs + c x weighted unshared fraction [dB]. LOFO
    #: over {80, 160, 320}: 160 on every held-out floor (the C++ default).
    penalty_db: float = _SHARED.penalty_db
    #: α of the per-AP reliability weights (σ̄²/σ_i²)^α of "shared"; 0 = off. LOFO over {0, 1}: 1 on
    #: four of six held-out floors (within 0.05 m of 0 on all floors).
    ap_weight_power: float = 1.0
    #: β of the strength weights exp((rss + 100)/β) of "shared" [dB]; 0 = off. LOFO over
    #: {0, 3, 5, 10}: 5 on four of six held-out floors, 10 on F4 and F8; 0 never (the C++ default: 5).
    strength_scale_db: float = _SHARED.strength_scale_db
    pair_radius_m: float = 2.0      #: references of two walks this close estimate an AP's noise [m] (fixed in advance)
    strongest_n: int = 10           #: n of "strongest" (fixed in advance: a scan's near APs)
    not_heard_dbm: float = -100.0   #: v₀ of "strongest" (the issue's floor value)
    unshared_cost_db: float = 20.0  #: c of "union": cost of an AP heard in one scan only [dB]
    k: int = _SHARED.k              #: components per fix (best references; 20). LOFO over {8, 12, 20, 30}: 20 or 30
    #: T of the component weights exp(-(d - d_min)/T) [dB]. LOFO over {3, 10, 30}: 3 on five of six (the C++ default).
    temperature_db: float = _SHARED.temperature_db
    #: σ of each component of a fix [m]: σ = sd_m + sd_per_db x d_min, d_min the fix's best
    #: dissimilarity [dB] (a poor best match is a wide fix). Calibrated on the six floors so that
    #: the mixture's 95 % region holds the truth at the fix time for ~90 % of the fixes, evenly
    #: over the floors: grid a {1, 2, 3, 4, 6} m x b {0.1 ... 0.5} m/dB, (3, 0.3) on four of six
    #: held-out floors; coverage 0.88-0.97 per floor (one σ of 12 m: 0.71-1.00). sd_per_db = 0
    #: gives one σ for every fix.
    sd_m: float = 3.0
    sd_per_db: float = 0.3          #: [m/dB], see sd_m (calibrated for the "shared" metric)
    min_aps: int = 3                #: fingerprints with fewer APs known to the database give no fix
    #: iBeacon readings as extra columns of the fingerprints (``wifi_matcher.beacon_id``), pooled
    #: like WiFi measurements ("window" pooling only). Off: on the six shared floors (beacons
    #: sparse: 185-2,004 readings a floor against 75-469 k WiFi readings) the 4-fold WiFi-only
    #: error was 12.34 m without and 12.39 m with them (F7, the floor with most: 16.30 -> 16.67 m;
    #: the others within 0.05 m). Untested on a building with dense beacons.
    beacons: bool = False

    def validate(self) -> None:
        """Raises ValueError naming the first invalid field."""
        if self.metric not in METRICS:
            raise ValueError(f"indoorloc: FixSettings.metric must be one of {METRICS}, got {self.metric!r}")
        if self.query_align not in ALIGNS:
            raise ValueError(f"indoorloc: FixSettings.query_align must be one of {ALIGNS}, got {self.query_align!r}")
        if self.pooling not in POOLINGS:
            raise ValueError(f"indoorloc: FixSettings.pooling must be one of {POOLINGS}, got {self.pooling!r}")
        if not (isinstance(self.not_heard_dbm, (int, float)) and -300 < self.not_heard_dbm < 50):
            raise ValueError(f"indoorloc: FixSettings.not_heard_dbm must be in (-300, 50) dBm, got {self.not_heard_dbm!r}")
        for name in ("fresh_age_s", "unshared_cost_db", "temperature_db", "sd_m", "ref_spacing_s",
                     "query_window_s", "pair_radius_m"):
            v = getattr(self, name)
            if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"indoorloc: FixSettings.{name} must be finite and > 0, got {v!r}")
        for name in ("ref_window_s", "penalty_db", "ap_weight_power", "strength_scale_db", "sd_per_db"):
            v = getattr(self, name)
            if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(v) and 0 <= v <= 1e4):
                raise ValueError(f"indoorloc: FixSettings.{name} must be finite and in [0, 1e4], got {v!r}")
        if 0 < self.strength_scale_db < 1:
            raise ValueError(f"indoorloc: FixSettings.strength_scale_db must be 0 (off) or >= 1 dB, "
                             f"got {self.strength_scale_db!r}")
        for name in ("min_scans", "k", "min_aps", "strongest_n"):
            v = getattr(self, name)
            if isinstance(v, bool) or not (isinstance(v, (int, np.integer)) and 1 <= v <= 10_000):
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
    epochs = crowdsourced_map.scan_epochs(wf, fresh_age_s)
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
    """Training fingerprints (N, K) [dBm, NaN = not heard] at positions (N, 2) [m], the floor
    number (N,) and training walk (N,) of each, and the BSSID of each column.

    ``ap_ratio`` (K,): σ̄²/σ_i² of each AP (``wifi_matcher.ap_reliability`` with power 1); the
    "shared" metric weighs AP i by ``ap_ratio[i] ** settings.ap_weight_power``."""

    rss_dbm: np.ndarray
    positions_m: np.ndarray
    bssids: List[str]
    settings: FixSettings
    floors: Optional[np.ndarray] = None
    walk_index: Optional[np.ndarray] = None
    ap_ratio: Optional[np.ndarray] = None
    #: Weight (N,) of each fingerprint in (0, 1] (None: all 1): a fix component from a fingerprint
    #: of a walk placed by the tracker (``fusion.Site.grow``) counts less than a surveyed one.
    weights: Optional[np.ndarray] = None

    def __post_init__(self) -> None:
        if self.floors is None:
            self.floors = np.zeros(self.positions_m.shape[0], dtype=np.int64)
        if self.walk_index is None:
            self.walk_index = np.zeros(self.positions_m.shape[0], dtype=np.int64)
        if self.ap_ratio is None:
            self.ap_ratio = np.ones(self.rss_dbm.shape[1])
        self._index: Optional[wifi_matcher.ReferenceIndex] = None

    def with_settings(self, settings: FixSettings) -> "FingerprintDatabase":
        """The same fingerprints with other fix settings. What was fixed at the build stays: the
        pooling, the reference spacing and window, ``min_scans``, ``pair_radius_m`` and the AP
        reliabilities (computed when built with the "shared" metric, else all 1). The query
        window, the metric and its constants, k, T and σ are the new ones."""
        settings.validate()
        return FingerprintDatabase(self.rss_dbm, self.positions_m, self.bssids, settings, self.floors,
                                   self.walk_index, self.ap_ratio, self.weights)

    @property
    def n_scans(self) -> int:
        """Number of fingerprints N (scans for "fresh" pooling, path references for "window")."""
        return int(self.positions_m.shape[0])

    @property
    def index(self) -> wifi_matcher.ReferenceIndex:
        """The fingerprints prepared for the "shared" metric (built once)."""
        if self._index is None:
            s = self.settings
            g = self.ap_ratio ** s.ap_weight_power if s.ap_weight_power else None
            self._index = wifi_matcher.ReferenceIndex.build(self.rss_dbm, g, s.strength_scale_db)
        return self._index


def _walk_fingerprints(walk: Any, s: FixSettings, positions_at: Callable[[np.ndarray], Tuple[np.ndarray, np.ndarray]],
                       span_s: Optional[Tuple[float, float]] = None
                       ) -> Optional[Tuple[np.ndarray, np.ndarray, List[str], np.ndarray]]:
    """The training fingerprints of one walk: (rss (n, V), xy (n, 2), the walk's BSSIDs, times (n,) [s]), or None."""
    if s.pooling == "fresh":
        t, rss, names = fresh_scans(walk, s.fresh_age_s)
        if t.size == 0:
            return None
    else:
        meas = wifi_matcher.walk_measurements(walk, beacons=s.beacons)
        names = list(meas.bssids)
        wt = np.asarray(walk.waypoint_t_s, float) if span_s is None else np.asarray(span_s, float)
        if meas.n == 0 or wt.size == 0:
            return None
        # Reference times along the surveyed part of the walk (positions_at drops what it cannot place).
        t = np.arange(wt[0], wt[-1] + 1e-9, s.ref_spacing_s)
        rss, _, n_used = wifi_matcher.pool_windows(meas.t_s, meas.bssid_index, meas.rssi_dbm, len(names), t,
                                         s.ref_window_s / 2, s.ref_window_s / 2)
        t, rss = t[n_used > 0], rss[n_used > 0]
        if t.size == 0:
            return None
    xy, valid = positions_at(t)
    if not np.any(valid):
        return None
    return rss[valid], xy[valid], names, t[valid]


def build_database(train_walks: Sequence[Any], settings: Optional[FixSettings] = None,
                   steps: Optional[Sequence[handheld.HandheldSteps]] = None,
                   map_settings: Optional[crowdsourced_map.CrowdMapSettings] = None,
                   floors: Optional[Sequence[int]] = None,
                   positions_at: Optional[Sequence[Callable[[np.ndarray], Tuple[np.ndarray, np.ndarray]]]] = None
                   ) -> FingerprintDatabase:
    """The training fingerprints of the walks, placed by PDR between waypoints
    (``crowdsourced_map.walk_positions``); BSSIDs heard in fewer than ``min_scans`` fingerprints
    dropped.

    ``settings.pooling == "window"``: one fingerprint every ``ref_spacing_s`` between the first
    and last waypoint of each walk, max-pooled over the distinct measurements last seen within
    ``ref_window_s / 2`` of it (``wifi_matcher``); "fresh": every scan's fresh readings at the
    scan's epoch. ``floors``: the floor number of each walk (default 0), for fixes over several
    floors. ``positions_at``: per walk, a function t (Q,) [s] -> (xy (Q, 2), valid (Q,)) to use
    instead of ``walk_positions`` (e.g. positions cached by a study). Raises ValueError when no
    fingerprint can be placed."""
    s = settings or FixSettings()
    s.validate()
    if floors is not None and len(floors) != len(train_walks):
        raise ValueError(f"indoorloc: argument 'floors': expected {len(train_walks)} floor numbers (one per walk), "
                         f"got {len(floors)}")
    if positions_at is not None and len(positions_at) != len(train_walks):
        raise ValueError(f"indoorloc: argument 'positions_at': expected {len(train_walks)} functions (one per walk), "
                         f"got {len(positions_at)}")
    per_walk = []
    for i, walk in enumerate(train_walks):
        if positions_at is not None:
            where = positions_at[i]
        else:
            def where(t, walk=walk, i=i):
                pos = crowdsourced_map.walk_positions(walk, t, map_settings, None if steps is None else steps[i])
                return pos.xy_m, pos.valid
        got = _walk_fingerprints(walk, s, where)
        if got is not None:
            fl = 0 if floors is None else int(floors[i])
            rss, xy, names, _ = got
            per_walk.append((rss, xy, names, np.full(xy.shape[0], fl), np.full(xy.shape[0], i)))
    return assemble_database(per_walk, s)


def walk_fingerprints(walk: Any, settings: FixSettings, steps: Optional[handheld.HandheldSteps] = None,
                      positions_at: Optional[Callable[[np.ndarray], Tuple[np.ndarray, np.ndarray]]] = None,
                      span_s: Optional[Tuple[float, float]] = None
                      ) -> Optional[Tuple[np.ndarray, np.ndarray, List[str], np.ndarray]]:
    """The training fingerprints of one survey walk before any vocabulary filter: ``(rss_dbm (n, V)
    [NaN = not heard], xy_m (n, 2) placed by PDR between the waypoints, the walk's V BSSIDs, times
    (n,) [s, walk clock])``, or
    None when none can be placed. :func:`assemble_database` of several walks' fingerprints equals
    :func:`build_database` of the walks (what lets a site file grow walk by walk).

    A walk without waypoints: ``positions_at`` t (Q,) [s] -> (xy (Q, 2), valid (Q,)) places the
    references (e.g. a tracked walk's smoothed positions where confident) and ``span_s`` = (first,
    last) [s] is the part of the walk they cover (instead of the waypoints')."""
    settings.validate()

    def where(t):
        pos = crowdsourced_map.walk_positions(walk, t, None, steps)
        return pos.xy_m, pos.valid
    return _walk_fingerprints(walk, settings, positions_at or where, span_s)


def assemble_database(per_walk: Sequence[Tuple[np.ndarray, np.ndarray, List[str], np.ndarray, np.ndarray]],
                      s: FixSettings, weights: Optional[Sequence[np.ndarray]] = None) -> FingerprintDatabase:
    """A database from per-walk fingerprints ``(rss (n, V), xy (n, 2), bssids (V), floors (n,),
    walk index (n,))``: BSSIDs heard in fewer than ``min_scans`` fingerprints dropped, columns in
    sorted BSSID order, AP reliabilities computed for the "shared" metric."""
    if not per_walk:
        raise ValueError("indoorloc: argument 'train_walks': no WiFi fingerprint could be placed (no readings "
                         "between waypoints)")
    counts: Dict[str, int] = {}
    for rss, _, names, _, _ in per_walk:
        heard = np.isfinite(rss).sum(axis=0)
        for name, c in zip(names, heard):
            if c:
                counts[name] = counts.get(name, 0) + int(c)
    vocab = sorted(b for b, c in counts.items() if c >= s.min_scans)
    col = {b: i for i, b in enumerate(vocab)}
    blocks = []
    for rss, xy, names, _, _ in per_walk:
        out = np.full((rss.shape[0], len(vocab)), np.nan)
        src = np.array([i for i, b in enumerate(names) if b in col], dtype=np.int64)
        dst = np.array([col[names[i]] for i in src], dtype=np.int64)
        if src.size:
            out[:, dst] = rss[:, src]
        blocks.append(out)
    rss_all = np.vstack(blocks)
    xy_all = np.vstack([p[1] for p in per_walk])
    walk_idx = np.concatenate([p[4] for p in per_walk])
    floors_all = np.concatenate([p[3] for p in per_walk])
    ratio = None
    if s.metric == "shared":  # also when α = 0, so that with_settings can turn the weights on
        # Pairs of references only within a floor: floors' frames share coordinates, and an AP
        # heard strongly on its own floor and weakly above it is a floor's signature, not noise.
        where = np.c_[xy_all, 1e6 * floors_all.astype(float)]
        ratio = wifi_matcher.ap_reliability(rss_all, where, walk_idx, 1.0, s.pair_radius_m)
    w_all = None
    if weights is not None and any(np.any(np.asarray(w) != 1.0) for w in weights):
        w_all = np.concatenate([np.asarray(w, float) for w in weights])
    return FingerprintDatabase(rss_all, xy_all, vocab, s, floors_all, walk_idx, ratio, w_all)


def walk_queries(walk: Any, database: FingerprintDatabase) -> Tuple[np.ndarray, np.ndarray]:
    """The query fingerprints of a walk in the database's columns: ``(t_s (Q,), rss_dbm (Q, K))``,
    one per scan, sorted by time, with at least ``min_aps`` known APs.

    "window" pooling: the query of the scan at time t max-pools the distinct measurements last
    seen in [t - query_window_s, t] and reported by scans up to t (causal); its time is the mean
    last-seen time of those measurements (the time the fingerprint describes). "fresh": the
    scan's readings at most ``fresh_age_s`` old, timed at their median last-seen time."""
    s = database.settings
    if s.pooling == "fresh":
        t, rss, _ = fresh_scans(walk, s.fresh_age_s, database.bssids)
    else:
        meas = wifi_matcher.walk_measurements(walk, beacons=s.beacons)
        cols = meas.columns({b: i for i, b in enumerate(database.bssids)})
        scan_t = np.unique(np.asarray(walk.wifi.scan_times_s, float))
        if s.query_align == "end":
            rss, t, _ = wifi_matcher.pool_windows(meas.t_s, cols, meas.rssi_dbm, len(database.bssids), scan_t,
                                        s.query_window_s, 0.0, meas.reported_s)
        else:
            rss, t, _ = wifi_matcher.pool_windows(meas.t_s, cols, meas.rssi_dbm, len(database.bssids), scan_t,
                                        s.query_window_s / 2, s.query_window_s / 2)
    ok = np.isfinite(rss).sum(axis=1) >= s.min_aps
    t, rss = t[ok], rss[ok]
    order = np.argsort(t, kind="stable")
    return t[order], rss[order]


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


def dissimilarity(queries_dbm: np.ndarray, database: "FingerprintDatabase", num_threads: int = 1) -> np.ndarray:
    """The database's metric (``settings.metric``) of every query (Q, K) to every fingerprint: (Q, N) [dB].
    ``num_threads``: threads of the compiled "shared" matcher (<= 0: all cores; results do not
    depend on it)."""
    s = database.settings
    if s.metric == "shared":
        return wifi_matcher.shared_dissimilarity(queries_dbm, database.index, s.penalty_db, num_threads=num_threads)
    if s.metric == "strongest":
        return strongest_ap_dissimilarity(queries_dbm, database.rss_dbm, s.strongest_n, s.not_heard_dbm)
    return scan_dissimilarity(queries_dbm, database.rss_dbm, s.unshared_cost_db)


def nearest(queries_dbm: np.ndarray, database: "FingerprintDatabase", num_threads: int = 1
            ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ``settings.k`` most similar fingerprints of every query (Q, K), best first, with the
    weights exp(-(d - d_min) / T): ``(index (Q, k), d (Q, k) [dB], weights (Q, k))``. The
    "shared" metric runs in one compiled pass (``wifi_matcher.shared_knn``), the others through
    the (Q, N) matrix (``wifi_matcher.knn``)."""
    s = database.settings
    if s.metric == "shared":
        return wifi_matcher.shared_knn(queries_dbm, database.index, s.penalty_db, s.k, s.temperature_db, num_threads)
    return wifi_matcher.knn(dissimilarity(queries_dbm, database), s.k, s.temperature_db)


def fixes_for_walk(walk: Any, database: FingerprintDatabase, with_floors: bool = True,
                   queries: Optional[Tuple[np.ndarray, np.ndarray]] = None) -> Fixes:
    """One fix per query fingerprint of the walk (``walk_queries``): the ``k`` most similar
    training fingerprints as components (module docstring), each on the floor of its training
    walk (``with_floors``; else on any floor). ``queries``: ``walk_queries(walk, database)`` when
    the caller has it already (the same fixes, without pooling the walk's readings again)."""
    s = database.settings
    t, rss = walk_queries(walk, database) if queries is None else queries
    k = min(s.k, database.n_scans)
    if t.size == 0:
        return Fixes.from_arrays(np.zeros(0), np.zeros((0, k, 2)), np.zeros((0, k)), np.zeros((0, k)))
    best, d_best, weights = nearest(rss, database)
    if database.weights is not None:  # grown fingerprints count less
        weights = weights * database.weights[best]
    floors = database.floors[best] if with_floors else None
    return Fixes.from_arrays(t, database.positions_m[best], fix_sds(d_best[:, 0], s), weights, floors)


def fix_sds(d_min: np.ndarray, settings: FixSettings) -> np.ndarray:
    """σ (F,) [m] of the components of fixes whose best dissimilarity is ``d_min`` (F,) [dB]:
    ``sd_m + sd_per_db * d_min`` (``sd_m`` where d_min is not finite)."""
    d = np.asarray(d_min, float)
    return np.where(np.isfinite(d), settings.sd_m + settings.sd_per_db * np.where(np.isfinite(d), d, 0.0),
                    settings.sd_m)


def fix_centres(fixes: Fixes) -> np.ndarray:
    """The weighted mean position (F, 2) [m] of each fix's components: the kNN estimate of the
    scan (the WiFi-only baseline on this metric)."""
    w = fixes.weights / np.maximum(fixes.weights.sum(axis=1, keepdims=True), 1e-300)
    return (w[:, :, None] * np.where(fixes.weights[:, :, None] > 0, fixes.means_m, 0.0)).sum(axis=1)


def locate_scans(rss_dbm: np.ndarray, database: FingerprintDatabase, num_threads: int = 1) -> np.ndarray:
    """WiFi-only positions (Q, 2) [m] of fingerprints (Q, K in the database's columns, NaN = not
    heard): the weight-averaged position of each one's fix components (the kNN estimate). A
    fingerprint that shares no AP with any reference cannot be placed: its row is NaN (documented
    result, not an error, so that a batch keeps its rows aligned)."""
    s = database.settings
    q = np.asarray(rss_dbm, dtype=np.float64)
    if q.ndim != 2 or q.shape[1] != len(database.bssids):
        raise ValueError(f"indoorloc: argument 'rss_dbm': expected shape (Q, {len(database.bssids)}) (the "
                         f"database's columns), got {q.shape}")
    if np.isinf(q).any():
        raise ValueError("indoorloc: argument 'rss_dbm': holds an infinite value (NaN marks 'not heard')")
    best, db, w = nearest(q, database, num_threads)
    w_sum = w.sum(axis=1, keepdims=True)
    pos = (w[:, :, None] * database.positions_m[best]).sum(axis=1) / np.where(w_sum > 0, w_sum, 1.0)
    return np.where(w_sum > 0, pos, np.nan)


__all__ = [
    "FingerprintDatabase",
    "FixSettings",
    "METRICS",
    "POOLINGS",
    "build_database",
    "dissimilarity",
    "fix_centres",
    "fix_sds",
    "fixes_for_walk",
    "fresh_scans",
    "locate_scans",
    "nearest",
    "scan_dissimilarity",
    "strongest_ap_dissimilarity",
    "walk_queries",
]
