"""Which floor a walk is on, from the access points it hears: per-floor detection rates of the APs.

The all-floor grid filter (``site_model.identify_floor``) weighs each floor by how well the walk's
motion and WiFi fixes fit that floor's plan. It fails where the walk's own floor was not surveyed
near it: the fixes' best matches are then the references of the floor above or below, which hear
the same APs more weakly. What still tells the floors apart is *which* APs a floor's survey hears
at all. On a floor f, AP a is heard in a fraction r_fa of the floor's reference fingerprints; the
strongest APs of a scan are near the phone, so they are heard often on its floor and rarely on
the others. Per query fingerprint q (its m strongest APs A_q), a naive-Bayes floor posterior

    p(f | q) ∝ Π_{a ∈ A_q} (r_fa + α),

taken robustly, because consecutive queries share most of their readings and one odd scan must
not decide a walk: the walk's log-likelihood of floor f is

    L_f = Σ_q log(ε + (1 − ε) p(f | q)).

``site_model.identify_floor`` adds λ L_f to the grid's per-floor log-evidence and takes the best
floor. m, α, ε and λ were chosen by leave-one-floor-out over the six floors of the competition
site (docs/fusion_real.md, "Floor identification"); the 2021 competition's winners used per-floor
classifiers on the strongest APs in the same spirit.

The combined score s_f is a log-evidence that counts correlated readings as independent: its
softmax says 1.00 for walks it gets wrong. The floor probabilities the library reports are
calibrated (:class:`FloorCalibration`):

    p_f = (1 − δ) softmax(s / T)_f + δ / F,

T a temperature and δ the probability that the evidence misleads altogether, spread evenly over
the F floors. It misleads where the walk's own floor was not surveyed near it (the APs and fixes
of the floor above or below then fit best), and such a walk is matched poorly by the survey of the
floor it is put on: δ grows with the walk's match distance D on the chosen floor
(:func:`walk_match_distance_db`, the median over the walk's queries of the RSS distance to the
closest reference of that floor),

    logit δ(D) = logit δ_10 + b ln(D / 10 dB).

T, δ_10 and b are chosen by leave-one-floor-out log loss over walks (docs/fusion_real.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional, Sequence

import numpy as np

from indoorloc.validate import integer, real_array, real_scalar


@dataclass
class ApFloorRates:
    """log(r_fa + α) (F, K) for the floors ``floors`` (F,) in that order and the K columns of a
    fingerprint database (the module docstring's r and α)."""

    floors: np.ndarray
    log_rate: np.ndarray
    #: The floor classifier fitted on the same database (``fusion.floor_classifier.FloorClassifier``,
    #: same floors and columns), or None: ``site_model.ap_floor_rates`` attaches it when its
    #: weight is > 0, so that what a site or a fold keeps for floor identification is one object.
    classifier: Optional[Any] = None

    @classmethod
    def from_references(cls, rss_dbm: np.ndarray, reference_floors: np.ndarray, floors: Sequence[int],
                        rate_floor: float) -> "ApFloorRates":
        """From reference fingerprints ``rss_dbm`` (N, K) [dBm, NaN = not heard] on floors
        ``reference_floors`` (N,); rows in the order of ``floors`` (a floor without references
        has every rate 0). ``rate_floor``: α, the rate given to an AP a floor never heard (> 0)."""
        x = real_array(rss_dbm, "rss_dbm", ndim=2, finite=False)
        f_ref = np.asarray(reference_floors)
        if f_ref.shape != (x.shape[0],):
            raise ValueError(f"indoorloc: argument 'reference_floors': expected shape ({x.shape[0]},), got {f_ref.shape}")
        alpha = real_scalar(rate_floor, "rate_floor", lo=1e-12, hi=1.0)
        counts = np.zeros((len(floors), x.shape[1]))
        n = np.zeros(len(floors))
        # By blocks of rows: a site's database can be gigabytes, its heard-mask as well.
        for a in range(0, x.shape[0], 4096):
            heard, f_block = np.isfinite(x[a:a + 4096]), f_ref[a:a + 4096]
            for i, f in enumerate(floors):
                rows = f_block == f
                counts[i] += heard[rows].sum(axis=0)
                n[i] += rows.sum()
        rate = counts / np.maximum(n, 1)[:, None]
        return cls(np.asarray(list(floors)), np.log(rate + alpha))


def query_floor_log_posteriors(rates: ApFloorRates, queries_dbm: np.ndarray, ap_count: int) -> tuple:
    """log p(f | q) of the module docstring for each query fingerprint that hears an AP:
    ``(log_posterior (Q', F), used (Q,) bool)``, ``used`` marking the rows of ``queries_dbm``
    (Q, K in the rates' columns, NaN = not heard) that hear at least one AP (the others carry no
    evidence); the ``ap_count`` strongest APs of each query (m)."""
    q = real_array(queries_dbm, "queries_dbm", ndim=2, finite=False)
    if q.shape[0] and q.shape[1] != rates.log_rate.shape[1]:
        raise ValueError(f"indoorloc: argument 'queries_dbm': expected {rates.log_rate.shape[1]} columns "
                         f"(the rates'), got {q.shape[1]}")
    m = integer(ap_count, "ap_count", lo=1, hi=100_000)
    used = np.isfinite(q).any(axis=1)
    out = np.zeros((int(used.sum()), rates.log_rate.shape[0]))
    for i, row in enumerate(q[used]):
        heard = np.flatnonzero(np.isfinite(row))
        top = heard[np.argsort(-row[heard], kind="stable")[:m]]
        ll = rates.log_rate[:, top].sum(axis=1)
        log_p = ll - ll.max()
        out[i] = log_p - np.log(np.exp(log_p).sum())
    return out, used


def robust_query_log_likelihoods(log_posteriors: np.ndarray, outlier_probability: float) -> np.ndarray:
    """log(ε + (1 − ε) p(f | q)) (Q, F) of per-query log posteriors (Q, F): what one query says
    about the floor, bounded by ε = ``outlier_probability`` (module docstring)."""
    lp = real_array(log_posteriors, "log_posteriors", ndim=2, finite=False)
    eps = real_scalar(outlier_probability, "outlier_probability", lo=0.0, hi=1.0)
    with np.errstate(divide="ignore"):  # ε = 0 or 1: log 0 = -inf, handled by logaddexp
        return np.logaddexp(np.log(eps), np.log1p(-eps) + lp)


def walk_floor_log_likelihood(rates: ApFloorRates, queries_dbm: np.ndarray, ap_count: int,
                              outlier_probability: float) -> np.ndarray:
    """L_f of the module docstring (F,) [nats] for a walk's query fingerprints ``queries_dbm``
    (Q, K in the rates' columns, NaN = not heard): the ``ap_count`` strongest APs of each query
    (m), ε = ``outlier_probability``. Zeros for a walk without queries (no information)."""
    real_scalar(outlier_probability, "outlier_probability", lo=0.0, hi=1.0)
    log_p, _ = query_floor_log_posteriors(rates, queries_dbm, ap_count)
    return robust_query_log_likelihoods(log_p, outlier_probability).sum(axis=0)


#: The match distance's fixed constants (set in advance, not tuned): the query's strongest APs
#: compared, and the cost [dB] of one of them that a reference did not hear.
MATCH_AP_COUNT = 10
MATCH_UNHEARD_DB = 30.0


def walk_match_distance_db(rss_dbm: np.ndarray, reference_floors: np.ndarray, floor: int, queries_dbm: np.ndarray,
                           ap_count: int = MATCH_AP_COUNT, unheard_db: float = MATCH_UNHEARD_DB) -> float:
    """How well floor ``floor``'s references explain a walk [dB]: per query (a row of
    ``queries_dbm`` (Q, K), NaN = not heard), the distance to a reference is the mean over the
    query's ``ap_count`` strongest APs of |RSS difference|, or ``unheard_db`` for an AP the
    reference did not hear; the query's distance is that of its closest reference of the floor;
    the walk's is the median over queries. ``unheard_db`` when there is nothing to compare (no
    query hears an AP, or the floor has no reference). ``rss_dbm`` (N, K) and
    ``reference_floors`` (N,) as in :meth:`ApFloorRates.from_references`."""
    x = real_array(rss_dbm, "rss_dbm", ndim=2, finite=False)
    q = real_array(queries_dbm, "queries_dbm", ndim=2, finite=False)
    f_ref = np.asarray(reference_floors)
    if f_ref.shape != (x.shape[0],):
        raise ValueError(f"indoorloc: argument 'reference_floors': expected shape ({x.shape[0]},), got {f_ref.shape}")
    if q.shape[0] and q.shape[1] != x.shape[1]:
        raise ValueError(f"indoorloc: argument 'queries_dbm': expected {x.shape[1]} columns (the references'), "
                         f"got {q.shape[1]}")
    m = integer(ap_count, "ap_count", lo=1, hi=100_000)
    cost = real_scalar(unheard_db, "unheard_db", lo=0.0, hi=1e3)
    rows = np.flatnonzero(f_ref == floor)
    per_query = []
    for row in q if rows.size else ():
        heard = np.flatnonzero(np.isfinite(row))
        if heard.size == 0:
            continue
        top = heard[np.argsort(-row[heard], kind="stable")[:m]]
        ref = x[np.ix_(rows, top)]
        d = np.where(np.isfinite(ref), np.abs(ref - row[top]), cost).mean(axis=1)
        per_query.append(d.min())
    return float(np.median(per_query)) if per_query else cost


@dataclass(frozen=True)
class FloorCalibration:
    """The calibration of the reported floor probabilities (module docstring): temperature T
    (> 0), δ_10 = ``error_probability_at_10db`` in [0, 1) and the slope b = ``error_slope`` (>= 0;
    0: δ = δ_10 for every walk). T = 1, δ_10 = 0: the plain normalised evidence."""

    temperature: float = 1.0
    error_probability_at_10db: float = 0.0
    error_slope: float = 0.0

    def __post_init__(self) -> None:
        real_scalar(self.temperature, "temperature", lo=1e-12, hi=1e12)
        d = real_scalar(self.error_probability_at_10db, "error_probability_at_10db", lo=0.0, hi=1.0)
        if d >= 1.0:
            raise ValueError("indoorloc: argument 'error_probability_at_10db': must be < 1, got 1.0")
        real_scalar(self.error_slope, "error_slope", lo=0.0, hi=1e3)

    def error_probability(self, match_distance_db) -> np.ndarray:
        """δ(D) for match distances D [dB] (scalar or array; None or NaN: δ_10)."""
        d10 = self.error_probability_at_10db
        dist = np.asarray(np.nan if match_distance_db is None else match_distance_db, float)
        if d10 == 0.0 or self.error_slope == 0.0:
            return np.full(dist.shape, d10)
        dist = np.where(np.isfinite(dist), np.maximum(dist, 1e-3), 10.0)
        logit = math.log(d10 / (1.0 - d10)) + self.error_slope * np.log(dist / 10.0)
        return 1.0 / (1.0 + np.exp(-logit))

    def probabilities(self, score: np.ndarray, match_distance_db=None) -> np.ndarray:
        """Calibrated floor probabilities of combined scores ``score`` (F,) or (W, F) [nats]
        (:func:`calibrated_floor_probabilities` with δ = :meth:`error_probability` of
        ``match_distance_db``, scalar or (W,): the walk's match distance on its chosen floor)."""
        return calibrated_floor_probabilities(score, self.temperature, self.error_probability(match_distance_db))


def calibrated_floor_probabilities(score: np.ndarray, temperature: float, error_probability) -> np.ndarray:
    """Floor probabilities (F,) from a walk's combined floor score ``score`` (F,) [nats, a
    log-evidence up to a constant], or (W, F) from W walks': (1 − δ) softmax(score / T) + δ / F
    with T = ``temperature`` (> 0) and δ = ``error_probability`` in [0, 1) (a scalar, or (W,)
    one per walk). The argmax is the score's; the largest probability is at most
    1 − δ (F − 1) / F. A score of -inf (a floor ruled out) gets δ / F."""
    s = real_array(score, "score", finite=False)
    if s.ndim not in (1, 2) or s.shape[-1] == 0 or np.isnan(s).any() or np.isposinf(s).any() \
            or not np.isfinite(s).any(axis=-1).all():
        raise ValueError("indoorloc: argument 'score': expected (F,) or (W, F) log-evidences, F >= 1, finite or "
                         "-inf, at least one finite per walk")
    t = real_scalar(temperature, "temperature", lo=1e-12, hi=1e12)
    d = np.asarray(error_probability, float)
    if d.shape not in ((), s.shape[:-1]) or not np.all((d >= 0) & (d < 1)):
        raise ValueError(f"indoorloc: argument 'error_probability': expected values in [0, 1), a scalar or one per "
                         f"walk {s.shape[:-1]}, got {error_probability!r}")
    top = np.max(np.where(np.isfinite(s), s, -np.inf), axis=-1, keepdims=True)
    p = np.exp((s - top) / t)
    d = d[..., None] if d.ndim else d
    return (1.0 - d) * p / p.sum(axis=-1, keepdims=True) + d / s.shape[-1]


#: Bins of the reported probability of the chosen floor in a reliability table.
RELIABILITY_BINS = (0.0, 0.5, 0.8, 0.9, 0.95, 0.98, 0.99, 0.999, 1.0)


def reliability_table(reported: np.ndarray, right: np.ndarray, bins: Sequence[float] = RELIABILITY_BINS) -> list:
    """How often a reported floor probability comes true: per bin [lo, hi) of ``reported`` (W,)
    (the probability each walk's chosen floor was given; the last bin includes 1), the walks,
    their mean reported probability and the fraction whose chosen floor was right (``right``
    (W,) bool). Empty bins are left out."""
    p = real_array(reported, "reported", ndim=1)
    ok = np.asarray(right, bool)
    if ok.shape != p.shape:
        raise ValueError(f"indoorloc: argument 'right': expected shape {p.shape}, got {ok.shape}")
    rows = []
    for lo, hi in zip(bins[:-1], bins[1:]):
        sel = (p >= lo) & ((p < hi) if hi < bins[-1] else (p <= hi))
        if sel.any():
            rows.append({"from": float(lo), "to": float(hi), "walks": int(sel.sum()),
                         "mean_reported": float(p[sel].mean()), "fraction_right": float(ok[sel].mean())})
    return rows


__all__ = ["ApFloorRates", "FloorCalibration", "MATCH_AP_COUNT", "MATCH_UNHEARD_DB", "RELIABILITY_BINS",
           "calibrated_floor_probabilities", "query_floor_log_posteriors", "reliability_table",
           "robust_query_log_likelihoods",
           "walk_floor_log_likelihood", "walk_match_distance_db"]
