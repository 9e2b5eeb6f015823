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
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from indoorloc.validate import integer, real_array, real_scalar


@dataclass
class ApFloorRates:
    """log(r_fa + α) (F, K) for the floors ``floors`` (F,) in that order and the K columns of a
    fingerprint database (the module docstring's r and α)."""

    floors: np.ndarray
    log_rate: np.ndarray

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


def walk_floor_log_likelihood(rates: ApFloorRates, queries_dbm: np.ndarray, ap_count: int,
                              outlier_probability: float) -> np.ndarray:
    """L_f of the module docstring (F,) [nats] for a walk's query fingerprints ``queries_dbm``
    (Q, K in the rates' columns, NaN = not heard): the ``ap_count`` strongest APs of each query
    (m), ε = ``outlier_probability``. Zeros for a walk without queries (no information)."""
    q = real_array(queries_dbm, "queries_dbm", ndim=2, finite=False)
    if q.shape[0] and q.shape[1] != rates.log_rate.shape[1]:
        raise ValueError(f"indoorloc: argument 'queries_dbm': expected {rates.log_rate.shape[1]} columns "
                         f"(the rates'), got {q.shape[1]}")
    m = integer(ap_count, "ap_count", lo=1, hi=100_000)
    eps = real_scalar(outlier_probability, "outlier_probability", lo=0.0, hi=1.0)
    total = np.zeros(rates.log_rate.shape[0])
    with np.errstate(divide="ignore"):  # ε = 0 or 1: log 0 = -inf, handled by logaddexp
        log_eps, log_keep = np.log(eps), np.log1p(-eps)
    for row in q:
        heard = np.flatnonzero(np.isfinite(row))
        if heard.size == 0:
            continue
        top = heard[np.argsort(-row[heard], kind="stable")[:m]]
        ll = rates.log_rate[:, top].sum(axis=1)
        log_p = ll - ll.max()
        log_p -= np.log(np.exp(log_p).sum())
        total += np.logaddexp(log_eps, log_keep + log_p)
    return total


__all__ = ["ApFloorRates", "walk_floor_log_likelihood"]
