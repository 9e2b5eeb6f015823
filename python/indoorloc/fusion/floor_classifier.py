"""Which floor a walk is on: a floor classifier on the set of access points a scan hears.

The AP detection rates of ``fusion.floor_evidence`` treat the APs of a scan as independent: an AP
heard on two floors counts for both, whatever else the scan hears. A discriminative classifier
weighs each AP by what it adds given the others, so the APs that only one floor's survey hears
(its own weak APs as much as its strong ones) decide, and the APs every floor hears cancel out. Per
query fingerprint q with presence vector x (x_a = 1 if AP a is heard), a multinomial logistic
regression

    p(f | q) = softmax_f(x · W_f + b_f),

fitted on the reference fingerprints of the all-floor database (each labelled with its floor),
each floor weighing the same in the loss (a uniform floor prior, as the grid filter's), with an
L2 penalty ||W||² / (2 C) (C = ``l2_scale``: larger C, weaker penalty) and fitted by L-BFGS
(scipy). As for the rates, one query must not decide a walk, and consecutive queries share most
of their readings; the walk's log-likelihood of floor f is

    K_f = Σ_q log(ε + (1 − ε) p(f | q)).

``site_model.identify_floor`` adds μ K_f to the grid's and the rates' evidence. C, ε and μ were
chosen by leave-one-floor-out over the six floors of the competition site, the walks of four fold
assignments pooled (docs/fusion_real.md, "Floor identification"); a fit takes about 8 s of CPU
on that site's all-floor database (7,000 references x 3,700 APs); the 2021 competition's winners used per-floor classifiers on the APs in
the same spirit.

Presence only, not the RSS: a weak reading of an AP says "this AP reaches here", which is
floor-specific; its level depends on the distance, which the survey may not have covered.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence, Tuple

import numpy as np
import scipy.sparse as sp
from scipy.optimize import minimize
from scipy.special import logsumexp
from threadpoolctl import threadpool_limits

from indoorloc.validate import integer, real_array, real_scalar


def _presence(rss_dbm: np.ndarray) -> sp.csr_matrix:
    """The 0/1 heard matrix, sparse (built from the heard mask: no dense float copy)."""
    rows, cols = np.nonzero(np.isfinite(rss_dbm))
    return sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=rss_dbm.shape)


@dataclass
class FloorClassifier:
    """Logistic-regression floor classifier (module docstring): ``floors`` (F,) in the order of
    the columns of ``weights`` (K, F) (K: the database's AP columns) and ``bias`` (F,);
    ``trained`` (F,) False for a floor without a reference fingerprint (its p(f | q) is 1/F)."""

    floors: np.ndarray
    weights: np.ndarray
    bias: np.ndarray
    trained: np.ndarray

    @classmethod
    def fit(cls, rss_dbm: np.ndarray, reference_floors: np.ndarray, floors: Sequence[int], l2_scale: float,
            max_iterations: int = 500) -> "FloorClassifier":
        """Fitted on reference fingerprints ``rss_dbm`` (N, K) [dBm, NaN = not heard] on floors
        ``reference_floors`` (N,), classes in the order of ``floors``; ``l2_scale``: C (> 0);
        ``max_iterations`` of L-BFGS. Deterministic (no random start, single-threaded sums: L-BFGS-B's
        BLAS calls run on one thread, whatever the machine's core count)."""
        x = real_array(rss_dbm, "rss_dbm", ndim=2, finite=False)
        f_ref = np.asarray(reference_floors)
        if f_ref.shape != (x.shape[0],):
            raise ValueError(f"indoorloc: argument 'reference_floors': expected shape ({x.shape[0]},), got {f_ref.shape}")
        c = real_scalar(l2_scale, "l2_scale", lo=1e-12, hi=1e12)
        iters = integer(max_iterations, "max_iterations", lo=1, hi=100_000)
        floors = np.asarray(list(floors))
        if floors.size == 0 or len(set(floors.tolist())) != floors.size:
            raise ValueError(f"indoorloc: argument 'floors': expected distinct floor numbers, got {floors.tolist()}")
        counts = np.array([(f_ref == f).sum() for f in floors])
        trained = counts > 0
        k, n_floors = x.shape[1], floors.size
        weights, bias = np.zeros((k, n_floors)), np.zeros(n_floors)
        cls_idx = np.flatnonzero(trained)
        if cls_idx.size >= 2:
            rows = np.flatnonzero(np.isin(f_ref, floors[cls_idx]))
            position = {f: i for i, f in enumerate(floors[cls_idx].tolist())}
            y = np.array([position[f] for f in f_ref[rows].tolist()], dtype=np.int64)
            w, b = _fit_softmax(_presence(x[rows]), y, cls_idx.size, c, iters)
            weights[:, cls_idx], bias[cls_idx] = w, b
        return cls(floors, weights, bias, trained)

    def query_log_posteriors(self, queries_dbm: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """log p(f | q) (Q', F) of each query fingerprint that hears an AP, and ``used`` (Q,) bool
        marking those rows of ``queries_dbm`` (Q, K in the classifier's columns, NaN = not
        heard), as ``floor_evidence.query_floor_log_posteriors``."""
        q = real_array(queries_dbm, "queries_dbm", ndim=2, finite=False)
        if q.shape[0] and q.shape[1] != self.weights.shape[0]:
            raise ValueError(f"indoorloc: argument 'queries_dbm': expected {self.weights.shape[0]} columns "
                             f"(the classifier's), got {q.shape[1]}")
        used = np.isfinite(q).any(axis=1)
        n_floors = self.floors.size
        out = np.full((int(used.sum()), n_floors), -np.log(n_floors))
        have = np.flatnonzero(self.trained)
        if have.size >= 2 and out.shape[0]:
            z = _presence(q[used]) @ self.weights[:, have] + self.bias[have]
            share = have.size / n_floors  # the untrained floors keep 1/F each
            out[:, have] = z - logsumexp(z, axis=1, keepdims=True) + np.log(share)
        return out, used

    def walk_log_likelihood(self, queries_dbm: np.ndarray, outlier_probability: float) -> np.ndarray:
        """K_f of the module docstring (F,) [nats] for a walk's query fingerprints ``queries_dbm``
        (Q, K), ε = ``outlier_probability`` in [0, 1]; zeros for a walk without a query."""
        eps = real_scalar(outlier_probability, "outlier_probability", lo=0.0, hi=1.0)
        log_p, _ = self.query_log_posteriors(queries_dbm)
        with np.errstate(divide="ignore"):
            return np.logaddexp(np.log(eps), np.log1p(-eps) + log_p).sum(axis=0)


def _fit_softmax(x: sp.csr_matrix, y: np.ndarray, n_classes: int, l2_scale: float, max_iterations: int
                 ) -> Tuple[np.ndarray, np.ndarray]:
    """Class-balanced multinomial logistic regression, L2 on the weights only: (W (K, C), b (C,))."""
    n, k = x.shape
    counts = np.bincount(y, minlength=n_classes)
    sample_w = (n / (n_classes * counts))[y]
    onehot = np.eye(n_classes)[y]
    xt = x.T.tocsr()

    def loss_grad(v: np.ndarray) -> Tuple[float, np.ndarray]:
        w, b = v[:k * n_classes].reshape(k, n_classes), v[k * n_classes:]
        z = x @ w + b
        lse = logsumexp(z, axis=1)
        loss = -(sample_w * ((z * onehot).sum(axis=1) - lse)).sum() + 0.5 / l2_scale * (w * w).sum()
        resid = (np.exp(z - lse[:, None]) - onehot) * sample_w[:, None]
        grad_w = xt @ resid + w / l2_scale
        return float(loss), np.concatenate([np.asarray(grad_w).ravel(), resid.sum(axis=0)])

    # L-BFGS-B's vector operations (22,000 parameters on the shared site) call BLAS, whose
    # threads would split its sums by the machine's core count (other bits on another machine) and
    # spin between calls (7x the CPU of the fit on two cores): one BLAS thread, the same result
    # everywhere.
    with threadpool_limits(limits=1, user_api="blas"):
        res = minimize(loss_grad, np.zeros(k * n_classes + n_classes), jac=True, method="L-BFGS-B",
                       options={"maxiter": max_iterations})
    return res.x[:k * n_classes].reshape(k, n_classes), res.x[k * n_classes:]


__all__ = ["FloorClassifier"]
