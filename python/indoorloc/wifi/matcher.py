"""WiFi fingerprints pooled in time along the walks, and the shared-AP dissimilarity that matches them
(docs/fusion_real.md, "WiFi as fixes").

When to use: to turn a crowdsourced set of walks (waypoints + WiFi, the Indoor Location Competition
2.0 format) into reference fingerprints and to match the fingerprints of another walk against
them. :mod:`indoorloc.fusion.wifi_fixes` builds the tracker's position fixes on top of this.

1. **Measurements, not scans** (:func:`walk_measurements`). A reading's RSSI was measured at its
   last-seen time; Android repeats cached measurements in later scans. Each distinct
   (BSSID, last-seen time) is one measurement (``IlcWifi.new_measurement_mask``), used at its
   own last-seen time whatever its age when reported (the 2.5 s staleness limit threw away
   24-28 % of the measurements).
2. **Max-pooling in a time window** (:func:`pool_windows`). The fingerprint of time t is, per
   BSSID, the strongest measurement last seen in [t - before, t + after]. References are pooled
   in a window centred on times every ``ref_spacing_s`` along each training walk and placed at
   the walker's position at that time (PDR between the waypoints,
   ``crowdsourced_map.walk_positions``): "fingerprints interpolated along the survey paths",
   several per waypoint interval instead of one per scan. A query at scan time t pools the
   measurements last seen in [t - w, t] that scans up to t have reported (causal), and is timed
   at the mean last-seen time of those measurements.
3. **Dissimilarity on shared APs** (:func:`shared_dissimilarity`). With A, B the APs heard by a
   query a and a reference b, per-AP reliability weights g_i (:func:`ap_reliability`) and
   strength weights f(x) = exp((x + 100 dBm) / β) (1 when β = 0: off), in dB:

       w_i = g_i f(a_i)                                                (the query's weight of AP i)
       rms(a, b) = sqrt( Σ_{A∩B} w_i (a_i - b_i)² / Σ_{A∩B} w_i )
       u(a, b)   = 1 - Σ_{A∩B} w_i / ( Σ_A g_i f(a_i) + Σ_{B∖A} g_i f(b_i) )
       d(a, b)   = rms(a, b) + c · u(a, b)

   u is the weighted fraction of the APs heard by only one of the two (0: same AP set, 1: no AP
   in common, d = inf then). Every sum runs over the references that heard one of the query's
   APs (per-AP posting lists, :class:`ReferenceIndex`), in the compiled matcher
   ``indoorloc._core.wifi.SharedApMatcher`` (C++ ``wifi/shared_ap_matcher.h``), which also gives
   the k nearest references (:func:`shared_knn`) without the (Q, N) matrix. The WiFi-only
   baseline of ``indoorloc wifi evaluate`` ("shared_knn") is the same matcher.
4. **Per-AP reliability** g_i = (σ̄² / σ_i²)^α: σ_i² is the variance of AP i's RSS between
   references of *different* training walks within ``pair_radius_m`` of each other (half the
   mean squared difference; the revisiting noise a query meets), shrunk towards the pooled σ̄²
   with ``prior_pairs`` pseudo-pairs; α = 0 switches it off. An AP heard by few pairs keeps
   g ≈ 1.

References: the Kaggle "Indoor Location & Navigation" 2021 winners' WiFi features (measurements
at their last-seen time, fingerprints along the paths, shared-AP counts weighted by the RSS
difference); Bahl & Padmanabhan, RADAR (INFOCOM 2000) for weighted kNN.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc.validate import integer, real_array, real_scalar

#: RSS offset used inside the matcher [dB]: values are stored as rss + 100 (0..100 for real RSS),
#: which keeps float32 sums of squares accurate.
RSS_OFFSET_DB = 100.0


@dataclass
class Measurements:
    """The distinct WiFi measurements of one walk (M of them).

    ``bssids``: vocabulary; ``bssid_index`` (M,) into it; ``rssi_dbm`` (M,); ``t_s`` (M,) last-seen
    time (walk clock [s]); ``reported_s`` (M,) time of the first scan that reported it [s]."""

    bssids: List[str]
    bssid_index: np.ndarray
    rssi_dbm: np.ndarray
    t_s: np.ndarray
    reported_s: np.ndarray

    @property
    def n(self) -> int:
        return int(self.t_s.shape[0])

    def columns(self, index: dict) -> np.ndarray:
        """(M,) column of each measurement in a vocabulary {bssid: column}, -1 if unknown."""
        col_of_bssid = np.array([index.get(b, -1) for b in self.bssids], dtype=np.int64)
        return col_of_bssid[self.bssid_index] if self.n else np.zeros(0, np.int64)


def walk_measurements(walk: Any, beacons: bool = False) -> Measurements:
    """Every distinct (BSSID, last-seen time) measurement of a walk, at its first report.

    ``walk.wifi`` is an ``IlcWifi`` (or anything with its arrays and ``new_measurement_mask``).
    ``beacons``: also the walk's iBeacon readings (``walk.beacons``, an ``IlcBeacons``), each a
    measurement of a pseudo-BSSID :func:`beacon_id` at its own time, so that a fingerprint holds
    beacon RSS beside WiFi RSS (readings without a finite RSSI are left out)."""
    wf = walk.wifi
    if wf.n_readings == 0:
        z = np.zeros(0)
        meas = Measurements(list(wf.bssids), np.zeros(0, np.int64), z, z, z)
    else:
        first = wf.new_measurement_mask()  # first report of each measurement (readings are in scan order)
        meas = Measurements(list(wf.bssids), np.asarray(wf.bssid_index)[first].astype(np.int64),
                            np.asarray(wf.rssi_dbm, float)[first], np.asarray(wf.last_seen_s, float)[first],
                            np.asarray(wf.scan_time_s, float)[first])
    bc = getattr(walk, "beacons", None) if beacons else None
    if bc is None or len(bc.t_s) == 0:
        return meas
    rssi = np.asarray(bc.rssi_dbm, float)
    t = np.asarray(bc.t_s, float)
    keep = np.flatnonzero(np.isfinite(rssi) & np.isfinite(t))
    if keep.size == 0:
        return meas
    ids = [beacon_id(bc.uuid[i], int(bc.major[i]), int(bc.minor[i]), bc.mac[i]) for i in keep]
    names = list(meas.bssids)
    column = {b: i for i, b in enumerate(names)}
    index = np.empty(keep.size, np.int64)
    for j, b in enumerate(ids):
        if b not in column:
            column[b] = len(names)
            names.append(b)
        index[j] = column[b]
    return Measurements(names, np.r_[meas.bssid_index, index], np.r_[meas.rssi_dbm, rssi[keep]],
                        np.r_[meas.t_s, t[keep]], np.r_[meas.reported_s, t[keep]])


def beacon_id(uuid: str, major: int, minor: int, mac: str = "") -> str:
    """The pseudo-BSSID of an iBeacon in a fingerprint: ``ibeacon:UUID:MAJOR:MINOR`` (its
    advertised identity), or ``ibeacon:MAC`` where major or minor was damaged (-1)."""
    if major < 0 or minor < 0 or not uuid:
        return f"ibeacon:{mac}"
    return f"ibeacon:{uuid.lower()}:{major}:{minor}"


def pool_windows(t_s: np.ndarray, columns: np.ndarray, rssi_dbm: np.ndarray, n_columns: int,
                 centres_s: np.ndarray, before_s: float, after_s: float,
                 reported_s: Optional[np.ndarray] = None) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Max-pooled fingerprints of measurements in time windows.

    Parameters
    ----------
    t_s, columns, rssi_dbm : (M,) arrays
        Last-seen time [s], column (-1: ignored) and RSS [dBm] of each measurement.
    n_columns : int
    centres_s : (Q,) array
        Window reference times [s]; window q is [centres_s[q] - before_s, centres_s[q] + after_s].
    before_s, after_s : float
        Window extent [s] (>= 0).
    reported_s : (M,) array, optional
        When given, window q only uses measurements reported at or before centres_s[q] (causal).

    Returns
    -------
    rss_dbm : (Q, n_columns) float64, NaN = not heard (the strongest measurement otherwise)
    mean_t_s : (Q,) mean last-seen time of the pooled measurements [s] (NaN if none)
    n_used : (Q,) int, measurements pooled
    """
    t = np.asarray(t_s, float)
    col = np.asarray(columns, np.int64)
    rss = np.asarray(rssi_dbm, float)
    c = np.asarray(centres_s, float).reshape(-1)
    q_n = c.shape[0]
    out = np.full((q_n, int(n_columns)), np.nan)
    keep = col >= 0
    t, col, rss = t[keep], col[keep], rss[keep]
    rep = None if reported_s is None else np.asarray(reported_s, float)[keep]
    order = np.argsort(t, kind="stable")
    t, col, rss = t[order], col[order], rss[order]
    if rep is not None:
        rep = rep[order]
    lo = np.searchsorted(t, c - before_s, side="left")
    hi = np.searchsorted(t, c + after_s, side="right")
    counts = np.maximum(hi - lo, 0)
    qi = np.repeat(np.arange(q_n), counts)
    mi = (np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)) + np.repeat(lo, counts)
    if rep is not None and qi.size:
        ok = rep[mi] <= c[qi] + 1e-9
        qi, mi = qi[ok], mi[ok]
    n_used = np.bincount(qi, minlength=q_n)
    sum_t = np.bincount(qi, weights=t[mi], minlength=q_n)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_t = np.where(n_used > 0, sum_t / np.maximum(n_used, 1), np.nan)
    if qi.size:
        # Strongest per (window, column): sort by (q, col, rss); the last of each group wins.
        cc, vv = col[mi], rss[mi]
        o = np.lexsort((vv, cc, qi))
        qi, cc, vv = qi[o], cc[o], vv[o]
        last = np.r_[(qi[1:] != qi[:-1]) | (cc[1:] != cc[:-1]), True]
        out[qi[last], cc[last]] = vv[last]
    return out, mean_t, n_used


def ap_reliability(rss_dbm: np.ndarray, positions_m: np.ndarray, walk_index: np.ndarray, power: float,
                   pair_radius_m: float = 2.0, prior_pairs: float = 10.0, max_pairs: int = 200_000,
                   seed: int = 0) -> np.ndarray:
    """Per-AP weights g (K,) = (σ̄² / σ_i²)^power from the references (module docstring, 4).

    ``rss_dbm`` (N, K) NaN = not heard, ``positions_m`` (N, D) (x, y [m], and e.g. a large floor
    offset so that pairs stay within a floor), ``walk_index`` (N,) the training
    walk of each reference. Pairs of references of different walks within ``pair_radius_m`` [m]
    (at most ``max_pairs``, drawn with ``seed``) give σ_i² = Σ (a_i - b_i)² / (2 n_i) over the
    pairs that heard AP i, shrunk to the pooled σ̄² with ``prior_pairs`` pseudo-pairs."""
    x = np.asarray(rss_dbm, float)
    k = x.shape[1]
    if power == 0 or x.shape[0] < 2:
        return np.ones(k)
    from scipy.spatial import cKDTree

    pairs = cKDTree(np.asarray(positions_m, float)).query_pairs(pair_radius_m, output_type="ndarray")
    w = np.asarray(walk_index)
    if pairs.size:
        pairs = pairs[w[pairs[:, 0]] != w[pairs[:, 1]]]
    if pairs.shape[0] == 0:
        return np.ones(k)
    if pairs.shape[0] > max_pairs:
        pairs = pairs[np.random.default_rng(seed).choice(pairs.shape[0], max_pairs, replace=False)]
    from scipy import sparse

    # Which references heard which APs (a few per cent of the (N, K) entries), so that a pair
    # visits only the APs both heard instead of all K (dense (P, K) blocks took most of the time
    # of building a site's databases).
    heard_r, heard_c = np.nonzero(np.isfinite(x))
    heard = sparse.csr_matrix((np.ones(heard_r.size), (heard_r, heard_c)), shape=x.shape)
    sq = np.zeros(k)
    n = np.zeros(k)
    for a in range(0, pairs.shape[0], 20_000):  # per block of pairs, as the sums were always formed
        p = pairs[a:a + 20_000]
        both = heard[p[:, 0]].multiply(heard[p[:, 1]]).tocsr()
        both.sort_indices()
        rows = np.repeat(np.arange(p.shape[0]), np.diff(both.indptr))
        cols = both.indices
        diff = x[p[rows, 0], cols] - x[p[rows, 1], cols]
        # Per AP the pairs' squared differences added in pair order (bincount adds its entries
        # in order, here pair-major): the additions of the dense column sums without their zeros.
        sq += np.bincount(cols, weights=diff * diff, minlength=k)
        n += np.bincount(cols, minlength=k)
    if n.sum() == 0:
        return np.ones(k)
    pooled = sq.sum() / (2.0 * n.sum())
    var = (sq / 2.0 + prior_pairs * pooled) / (n + prior_pairs)
    return (pooled / var) ** power


@dataclass
class ReferenceIndex:
    """References prepared for :func:`shared_dissimilarity` and :func:`shared_knn`: the compiled
    matcher (``indoorloc._core.wifi.SharedApMatcher``: per-AP posting lists, so that a query
    touches only the references that heard one of its APs; a reference hears a few per cent of a
    floor's APs).

    ``rss_dbm`` (N, K) [dBm, NaN = not heard]; ``g`` (K,) AP weights; ``strength_scale_db`` β
    (0: off); ``n`` = N. Matchers for other (c, k, T) are built on demand and kept."""

    rss_dbm: np.ndarray
    g: np.ndarray
    strength_scale_db: float
    n: int

    @classmethod
    def build(cls, rss_dbm: np.ndarray, g: Optional[np.ndarray] = None, strength_scale_db: float = 0.0
              ) -> "ReferenceIndex":
        x = np.asarray(rss_dbm, float)
        g = np.ones(x.shape[1]) if g is None else np.asarray(g, float)
        index = cls(x, g, float(strength_scale_db), int(x.shape[0]))
        index.matcher()  # validates the references and weights now (ValueError naming them)
        return index

    def __getstate__(self) -> dict:
        """Pickling and copying (Dask, copy.deepcopy) keep the references; the compiled matchers
        are not picklable and are rebuilt on demand."""
        state = dict(self.__dict__)
        state.pop("_matchers", None)
        return state

    def matcher(self, penalty_db: Optional[float] = None, k: Optional[int] = None,
                temperature_db: Optional[float] = None) -> Any:
        """The compiled matcher with these options (None: the C++ default), built once per
        (c, k, T) and kept."""
        from indoorloc._core.wifi import SharedApMatcher, SharedApMatcherOptions

        cache = self.__dict__.setdefault("_matchers", {})
        default = SharedApMatcherOptions()
        key = (default.penalty_db if penalty_db is None else float(penalty_db),
               default.k if k is None else int(k),
               default.temperature_db if temperature_db is None else float(temperature_db))
        if key not in cache:
            options = default.replace(strength_scale_db=self.strength_scale_db, penalty_db=key[0], k=key[1],
                                      temperature_db=key[2])
            cache[key] = SharedApMatcher(self.rss_dbm, self.g, options)
        return cache[key]


#: f is evaluated as exp((rss - STRENGTH_PIVOT_DBM) / β): the same ratios as exp((rss + 100) / β), kept
#: finite for β >= 1 (rss up to -13 dBm in the data). The C++ matcher uses the same pivot.
STRENGTH_PIVOT_DBM = -40.0


def _strength(value_db: np.ndarray, scale_db: float) -> np.ndarray:
    """f of the module docstring on rss + 100 values (1 when the scale is 0)."""
    if scale_db <= 0:
        return np.ones_like(value_db)
    return np.exp((value_db - (STRENGTH_PIVOT_DBM + RSS_OFFSET_DB)) / scale_db)


def _checked_queries(queries_dbm: np.ndarray, index: ReferenceIndex) -> np.ndarray:
    q = real_array(queries_dbm, "queries_dbm", ndim=2, finite=False, max_abs=1e3)
    if q.shape[1] != index.rss_dbm.shape[1]:
        raise ValueError(f"indoorloc: argument 'queries_dbm': expected {index.rss_dbm.shape[1]} columns "
                         f"(the references' APs), got {q.shape[1]}")
    return q


def shared_dissimilarity(queries_dbm: np.ndarray, index: ReferenceIndex, penalty_db: float,
                         parts: bool = False, num_threads: int = 1):
    """d(a, b) of the module docstring (3) for every query (Q, K) against every reference: (Q, N) [dB],
    +inf where no AP is shared. With ``parts=True`` returns ``(rms, u)`` instead (d = rms + c u),
    for evaluating several c at once.

    Computed by the compiled matcher (GIL released; ``num_threads`` <= 0: all cores, results
    independent of it); :func:`shared_dissimilarity_numpy` is the same in numpy (the reference
    of the tests). Timing: docs/fusion_real.md, "WiFi as fixes"."""
    q = _checked_queries(queries_dbm, index)
    penalty_db = real_scalar(penalty_db, "penalty_db", lo=0.0, hi=1e4)
    rms, u = index.matcher().parts(q, num_threads)
    if parts:
        return rms, u
    return rms + penalty_db * u


def shared_knn(queries_dbm: np.ndarray, index: ReferenceIndex, penalty_db: float, k: int,
               temperature_db: float, num_threads: int = 1) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`knn` of :func:`shared_dissimilarity` in one compiled pass, without the (Q, N) matrix:
    ``(index (Q, k'), d (Q, k') [dB], weights (Q, k'))``, k' = min(k, N), best first (ties: lower
    reference index). Where fewer than k' references share an AP with a query, the rest are other
    references at d = inf, weight 0."""
    q = _checked_queries(queries_dbm, index)
    penalty_db = real_scalar(penalty_db, "penalty_db", lo=0.0, hi=1e4)
    k = integer(k, "k", lo=1, hi=10**9)
    temperature_db = real_scalar(temperature_db, "temperature_db", lo=1e-12, hi=1e12)
    return index.matcher(penalty_db, k, temperature_db).nearest(q, num_threads)


def knn_positions(best: np.ndarray, weights: np.ndarray, positions_m: np.ndarray,
                  floors: Optional[np.ndarray] = None) -> Tuple[np.ndarray, np.ndarray]:
    """WiFi-only estimates from neighbours (:func:`shared_knn`): per query the floor with the
    largest summed weight among its neighbours (a tie: the floor of the best-ranked of the tied),
    then the weight-averaged position of the neighbours on that floor.

    ``best``, ``weights`` (Q, k); ``positions_m`` (N, 2) [m]; ``floors`` (N,) int or None (all 0).
    Returns ``(positions_m (Q, 2), floors (Q,) int64)``. A query that shares no AP with any
    reference (all weights 0) gets the mean reference position and the most common floor."""
    best = np.asarray(best, np.int64)
    w = np.asarray(weights, float)
    pos = np.asarray(positions_m, float)
    fl = np.zeros(pos.shape[0], np.int64) if floors is None else np.asarray(floors, np.int64)
    q_n = best.shape[0]
    if q_n == 0:
        return np.zeros((0, 2)), np.zeros(0, np.int64)
    nf = fl[best]                                                    # (Q, k) neighbour floors
    # Summed weight of each neighbour's floor, per query; the first (best-ranked) maximum wins.
    same = nf[:, :, None] == nf[:, None, :]
    votes = (same * w[:, None, :]).sum(axis=2)                       # (Q, k)
    pick = np.argmax(votes, axis=1)
    floor = nf[np.arange(q_n), pick]
    ww = np.where(nf == floor[:, None], w, 0.0)
    total = ww.sum(axis=1, keepdims=True)
    out = (ww[:, :, None] * pos[best]).sum(axis=1) / np.where(total > 0, total, 1.0)
    none = total[:, 0] <= 0
    if none.any():
        vals, counts = np.unique(fl, return_counts=True)
        out[none] = pos.mean(axis=0)
        floor[none] = vals[np.argmax(counts)]
    return out, floor.astype(np.int64)


def shared_dissimilarity_numpy(queries_dbm: np.ndarray, index: ReferenceIndex, penalty_db: float,
                               parts: bool = False):
    """:func:`shared_dissimilarity` in numpy/scipy (the implementation before the compiled
    matcher; kept as the reference of the tests and of the speed comparison): one pass per query,
    a few sparse (C,) by (C, N) products over the references' rows of the query's own APs."""
    from scipy import sparse

    q = _checked_queries(queries_dbm, index)
    penalty_db = real_scalar(penalty_db, "penalty_db", lo=0.0, hi=1e4)
    x = index.rss_dbm
    n, k_aps = x.shape
    ref, ap = np.nonzero(np.isfinite(x.T).T)          # entries in (reference, AP) order
    v = x[ref, ap] + RSS_OFFSET_DB
    gf_entries = index.g[ap] * _strength(v, index.strength_scale_db)

    def csr(data):
        return sparse.csr_matrix((np.asarray(data, np.float64), (ap, ref)), shape=(k_aps, n))

    heard, value, value2, gf = csr(np.ones_like(v)), csr(v), csr(v * v), csr(gf_entries)
    total_b = np.bincount(ref, weights=gf_entries, minlength=n)
    rms = np.full((q.shape[0], n), np.inf)
    u = np.ones((q.shape[0], n))
    beta = index.strength_scale_db
    for r in range(q.shape[0]):  # one query at a time: only its own APs' rows are touched
        cols = np.flatnonzero(np.isfinite(q[r]))
        if cols.size == 0 or n == 0:
            continue
        a = q[r, cols] + RSS_OFFSET_DB
        w = index.g[cols] * _strength(a, beta)                       # w_i = g_i f(a_i)
        # (1, C) x (C, N) sparse products: Σ_{A∩B} of w, w a², w a b, w b² and g f(b).
        sw, s_aa = heard[cols].T.dot(np.column_stack([w, w * a * a])).T
        s_ab = value[cols].T.dot(w * a)
        s_bb = value2[cols].T.dot(w)
        shared_fb = np.asarray(gf[cols].sum(axis=0)).ravel()         # Σ_{A∩B} g f(b)
        ms = s_aa - 2.0 * s_ab + s_bb                                # Σ_{A∩B} w (a - b)²
        union = float(w.sum()) + total_b - shared_fb                 # Σ_A + Σ_{B∖A}
        ok = sw > 0
        rms[r, ok] = np.sqrt(np.maximum(ms[ok] / sw[ok], 0.0))
        u[r, ok] = np.clip(1.0 - sw[ok] / union[ok], 0.0, 1.0)
    if parts:
        return rms, u
    return rms + penalty_db * u


def knn(d: np.ndarray, k: int, temperature_db: float) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The k smallest dissimilarities per row of d (Q, N), in order: ``(index (Q, k), d (Q, k),
    weights (Q, k))`` with weights exp(-(d_j - d_min) / T) (0 where d is inf)."""
    k = min(int(k), d.shape[1])
    if k < d.shape[1]:
        part = np.argpartition(d, k - 1, axis=1)[:, :k]
    else:
        part = np.tile(np.arange(d.shape[1]), (d.shape[0], 1))
    dp = np.take_along_axis(d, part, axis=1)
    o = np.argsort(dp, axis=1, kind="stable")
    best = np.take_along_axis(part, o, axis=1)
    db = np.take_along_axis(dp, o, axis=1)
    with np.errstate(invalid="ignore"):
        w = np.exp(-(db - db[:, :1]) / temperature_db)
    w[~np.isfinite(db)] = 0.0
    return best, db, w


__all__ = [
    "Measurements",
    "RSS_OFFSET_DB",
    "ReferenceIndex",
    "ap_reliability",
    "knn",
    "knn_positions",
    "pool_windows",
    "shared_dissimilarity",
    "shared_dissimilarity_numpy",
    "shared_knn",
    "walk_measurements",
    "beacon_id",
]
