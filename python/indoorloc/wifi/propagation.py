"""Per-AP log-distance path-loss model fitted to crowdsourced fingerprints, and the likelihood of a
scan over a floor's grid from it (docs/fusion_real.md, "A propagation model that extrapolates").

When to use: on a sparsely surveyed floor a fingerprint matcher can only return places that were
surveyed, and kernel regression of the fingerprints cannot extrapolate either. A physical model
per access point can: fitted where the AP was heard (and where it was not), it predicts the AP's
RSS anywhere on the floor, also beyond the survey.

**Model** (log-distance path loss; Rappaport, *Wireless Communications*, eq. 4.68), per AP i:

    μ_i(x) = P_i − 10 n_i log10( sqrt(|x − a_i|² + h_i²) )        [dBm]

a_i (2,) the AP's position on the floor's plane [m] (may lie outside the survey), h_i ≥ h_min its
height above (or below) the plane [m] (an AP on another floor is far above), P_i the RSS at 1 m
[dBm], n_i the path-loss exponent.

**Fit** (:func:`fit_path_loss`), per AP, batched over the APs: damped Gauss-Newton
(Levenberg-Marquardt) on

    Σ_{heard j} ρ_H((r_j − μ_i(x_j)) / 1)  +  w_c Σ_{not heard j} max(0, μ_i(x_j) − r_floor)²
      + ((n_i − n_0)/s_n)² + ((h_i − h_0)/s_h)² + ((P_i − P_0)/s_P)²

ρ_H the Huber loss (IRLS weights, δ = ``huber_db``); the second term says that a reference that did
not hear the AP saw it below the detection floor ``floor_dbm`` (censored readings: without them
an AP heard by a few references can be placed anywhere the heard ones are consistent with); the
priors keep APs with few readings well posed. Start: a at the power-weighted centroid of the
heard references, P from the linear fit given a, h_0, n_0. Each AP's residual sd σ_i is the
robust sd (1.4826 MAD) of its heard residuals, shrunk to the pooled one with ``prior_readings``
pseudo-readings, floored at ``min_sd_db``.

**Scan likelihood** (:func:`scan_log_likelihood`): for a query q over points x (M, 2),

    ℓ(x) = Σ_{i heard} −(q_i − μ_i(x))² / (2 σ_i²)  +  Σ_{i not heard} log(1 − Φ((μ_i(x) − r_floor)/s_det))

the second sum (a miss of an AP predicted strong is evidence against x) only with
``miss_weight`` > 0. Both are matrix products over the APs, so a walk's queries cost one (Q, K)
× (K, M) product each.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np
from scipy.special import log_ndtr

from indoorloc.validate import real_array

_LN10 = math.log(10.0)


@dataclass(frozen=True)
class PathLossOptions:
    """Options of :func:`fit_path_loss` and :func:`scan_log_likelihood` (units in the names)."""

    floor_dbm: float = -92.0           #: detection floor r_floor: not heard = below this [dBm]
    censored_weight: float = 0.3       #: w_c of the not-heard references' hinge term
    huber_db: float = 6.0              #: δ of the Huber loss on heard residuals [dB]
    exponent_prior: float = 2.5        #: n_0
    exponent_prior_sd: float = 1.0     #: s_n
    p0_prior_dbm: float = -40.0        #: P_0: the RSS 1 m from a WiFi AP [dBm] (typical -30 to -50)
    p0_prior_sd_db: float = 8.0        #: s_P [dB]: without it a far AP with a high P trades off a near weak one
    height_prior_m: float = 3.0        #: h_0 [m]
    height_prior_sd_m: float = 10.0    #: s_h [m]
    min_height_m: float = 1.0          #: h_min [m]
    exponent_range: tuple = (1.2, 6.0)  #: bounds of n
    margin_m: float = 60.0             #: a_i kept within the references' bounding box ± this [m]
    iterations: int = 40               #: Levenberg-Marquardt iterations
    min_heard: int = 3                 #: APs heard by fewer references are not fitted (ok False)
    min_sd_db: float = 3.0             #: floor of σ_i [dB]
    prior_readings: float = 10.0       #: pseudo-readings shrinking σ_i to the pooled sd
    miss_sd_db: float = 4.0            #: s_det of the miss term [dB]

    def validate(self) -> None:
        """ValueError naming the first invalid field."""
        checks = {
            "floor_dbm": -150 < self.floor_dbm < 0, "censored_weight": self.censored_weight >= 0,
            "huber_db": self.huber_db > 0, "exponent_prior_sd": self.exponent_prior_sd > 0, "p0_prior_sd_db": self.p0_prior_sd_db > 0,
            "height_prior_sd_m": self.height_prior_sd_m > 0, "min_height_m": self.min_height_m > 0,
            "exponent_range": 0 < self.exponent_range[0] < self.exponent_range[1],
            "margin_m": self.margin_m >= 0, "iterations": int(self.iterations) >= 1,
            "min_heard": int(self.min_heard) >= 1, "min_sd_db": self.min_sd_db > 0,
            "prior_readings": self.prior_readings >= 0, "miss_sd_db": self.miss_sd_db > 0,
        }
        for name, ok in checks.items():
            if not ok:
                raise ValueError(f"indoorloc: PathLossOptions.{name}: invalid value {getattr(self, name)!r}")


@dataclass
class PathLossModel:
    """Fitted per-AP parameters (K APs): ``ap_xy_m`` (K, 2), ``height_m`` (K,), ``p0_dbm`` (K,),
    ``exponent`` (K,), ``residual_sd_db`` (K,), ``n_heard`` (K,), ``ok`` (K,) (fitted: heard by
    at least ``min_heard`` references), and the ``options``."""

    ap_xy_m: np.ndarray
    height_m: np.ndarray
    p0_dbm: np.ndarray
    exponent: np.ndarray
    residual_sd_db: np.ndarray
    n_heard: np.ndarray
    ok: np.ndarray
    options: PathLossOptions

    def predict(self, points_m: np.ndarray) -> np.ndarray:
        """μ_i(x) (M, K) [dBm] at points (M, 2) [m]; NaN for APs not fitted."""
        x = real_array(points_m, "points_m", ndim=2)
        if x.shape[1] != 2:
            raise ValueError(f"indoorloc: argument 'points_m': expected shape (M, 2), got {x.shape}")
        d2 = ((x[:, None, :] - self.ap_xy_m[None, :, :]) ** 2).sum(axis=2) + self.height_m[None, :] ** 2
        mu = self.p0_dbm[None, :] - 5.0 * self.exponent[None, :] * np.log10(d2)
        return np.where(self.ok[None, :], mu, np.nan)


def _predict_refs(theta: np.ndarray, xy: np.ndarray):
    """μ (K, N) at references xy (N, 2) for parameters theta (K, 5) = (x, y, h, P, n), and d² (K, N)."""
    dx = xy[None, :, 0] - theta[:, 0:1]
    dy = xy[None, :, 1] - theta[:, 1:2]
    d2 = dx * dx + dy * dy + theta[:, 2:3] ** 2
    mu = theta[:, 3:4] - 5.0 * theta[:, 4:5] * np.log10(d2)
    return mu, d2, dx, dy


def _jacobian(theta: np.ndarray, d2, dx, dy) -> np.ndarray:
    """∂μ/∂theta (K, N, 5)."""
    g = -10.0 * theta[:, 4:5] / _LN10 / d2           # ∂μ/∂d² · 2
    jx = g * (-dx)                                     # ∂μ/∂x = -10n/ln10 · (x - x_j)/d²
    jy = g * (-dy)
    jh = g * theta[:, 2:3]
    jp = np.ones_like(d2)
    jn = -5.0 * np.log10(d2)
    return np.stack([jx, jy, jh, jp, jn], axis=2)


def _objective(theta, xy, rss, heard, o: PathLossOptions, huber_w):
    """Per-AP cost (K,), residuals r (K, N), weights w (K, N) of the linearised problem."""
    mu, d2, dx, dy = _predict_refs(theta, xy)
    r_h = np.where(heard, rss - mu, 0.0)
    over = np.where(heard, 0.0, np.maximum(mu - o.floor_dbm, 0.0))
    r = np.where(heard, r_h, -over)                    # residual "observed - predicted" on both
    w = np.where(heard, huber_w, np.where(over > 0, o.censored_weight, 0.0))
    cost = (w * r * r).sum(axis=1)
    cost += ((theta[:, 4] - o.exponent_prior) / o.exponent_prior_sd) ** 2
    cost += ((theta[:, 2] - o.height_prior_m) / o.height_prior_sd_m) ** 2
    cost += ((theta[:, 3] - o.p0_prior_dbm) / o.p0_prior_sd_db) ** 2
    return cost, r, w, d2, dx, dy


def _huber_weights(r: np.ndarray, heard: np.ndarray, delta: float) -> np.ndarray:
    a = np.abs(r)
    return np.where(heard, np.where(a <= delta, 1.0, delta / np.maximum(a, 1e-12)), 0.0)


def _fit_chunk(rss: np.ndarray, xy: np.ndarray, o: PathLossOptions):
    """Levenberg-Marquardt of the APs (columns) of rss (N, k): theta (k, 5), heard residuals (k, N) (NaN elsewhere)."""
    heard = np.isfinite(rss).T                            # (K, N)
    r_kn = np.where(heard, rss.T, 0.0)
    n_heard = heard.sum(axis=1)
    k = rss.shape[1]
    # Start: a at the power-weighted centroid of the heard references, h_0, n_0, P by linear fit.
    pw = np.where(heard, 10.0 ** ((r_kn - np.where(heard, r_kn, -np.inf).max(axis=1, keepdims=True)) / 10.0), 0.0)
    pw_sum = np.maximum(pw.sum(axis=1, keepdims=True), 1e-300)
    a0 = (pw @ xy) / pw_sum
    theta = np.empty((k, 5))
    theta[:, 0:2] = a0
    theta[:, 2] = o.height_prior_m
    theta[:, 4] = o.exponent_prior
    theta[:, 3] = 0.0
    mu, _, _, _ = _predict_refs(theta, xy)
    theta[:, 3] = np.where(heard, r_kn - mu, 0.0).sum(axis=1) / np.maximum(n_heard, 1)
    lo = np.array([xy[:, 0].min() - o.margin_m, xy[:, 1].min() - o.margin_m, o.min_height_m, -200.0,
                   o.exponent_range[0]])
    hi = np.array([xy[:, 0].max() + o.margin_m, xy[:, 1].max() + o.margin_m, 200.0, 100.0, o.exponent_range[1]])
    lam = np.full(k, 1e-2)
    huber_w = np.ones((k, xy.shape[0]))
    _, r, _, _, _, _ = _objective(theta, xy, r_kn, heard, o, huber_w)
    for _ in range(int(o.iterations)):
        huber_w = _huber_weights(r, heard, o.huber_db)
        cost, r, w, d2, dx, dy = _objective(theta, xy, r_kn, heard, o, huber_w)
        jac = _jacobian(theta, d2, dx, dy)             # ∂μ/∂θ; r = obs − μ on heard, −(μ − floor) on hinge
        jtw = (jac * w[:, :, None]).transpose(0, 2, 1)  # (k, 5, N)
        a = jtw @ jac
        b = (jtw @ r[:, :, None])[:, :, 0]              # descent direction for Σ w (obs − μ)²
        # Priors on h (index 2), P (3) and n (4).
        for idx, mean, sd in ((2, o.height_prior_m, o.height_prior_sd_m), (3, o.p0_prior_dbm, o.p0_prior_sd_db),
                              (4, o.exponent_prior, o.exponent_prior_sd)):
            a[:, idx, idx] += 1.0 / sd ** 2
            b[:, idx] -= (theta[:, idx] - mean) / sd ** 2
        diag = np.einsum("kii->ki", a)
        a_damped = a + (lam[:, None] * np.maximum(diag, 1e-6))[:, :, None] * np.eye(5)[None]
        step = np.linalg.solve(a_damped, b[:, :, None])[:, :, 0]
        trial = np.clip(theta + step, lo, hi)
        t_cost, *_ = _objective(trial, xy, r_kn, heard, o, huber_w)
        better = t_cost < cost
        theta = np.where(better[:, None], trial, theta)
        lam = np.where(better, lam * 0.3, lam * 10.0)
        lam = np.clip(lam, 1e-6, 1e6)
    cost, r, w, d2, dx, dy = _objective(theta, xy, r_kn, heard, o, huber_w)
    return theta, np.where(heard, r, np.nan)


def fit_path_loss(rss_dbm: np.ndarray, positions_m: np.ndarray, options: Optional[PathLossOptions] = None
                  ) -> PathLossModel:
    """Fit the log-distance model of every AP (column) of fingerprints ``rss_dbm`` (N, K) [dBm,
    NaN = not heard] recorded at ``positions_m`` (N, 2) [m] (module docstring). Deterministic."""
    o = options or PathLossOptions()
    o.validate()
    rss = real_array(rss_dbm, "rss_dbm", ndim=2, finite=False)
    xy = real_array(positions_m, "positions_m", ndim=2)
    if xy.shape != (rss.shape[0], 2):
        raise ValueError(f"indoorloc: argument 'positions_m': expected shape ({rss.shape[0]}, 2), got {xy.shape}")
    if np.isinf(rss).any():
        raise ValueError("indoorloc: argument 'rss_dbm': must hold finite RSS or NaN (not heard), got inf")
    k = rss.shape[1]
    theta = np.empty((k, 5))
    res = np.empty((k, rss.shape[0]))
    chunk = max(1, int(1_500_000 // max(1, rss.shape[0])))
    for c0 in range(0, k, chunk):
        c1 = min(k, c0 + chunk)
        theta[c0:c1], res[c0:c1] = _fit_chunk(rss[:, c0:c1], xy, o)
    heard = np.isfinite(rss).T
    n_heard = heard.sum(axis=1)
    ok = n_heard >= o.min_heard
    mad = 1.4826 * np.nanmedian(np.abs(res - np.nanmedian(res, axis=1, keepdims=True)), axis=1) \
        if np.any(ok) else np.full(k, np.nan)
    pooled = float(np.sqrt(np.nanmean(mad[ok] ** 2))) if np.any(ok) else o.min_sd_db
    m = n_heard.astype(float)
    sd = np.sqrt((m * np.nan_to_num(mad, nan=pooled) ** 2 + o.prior_readings * pooled ** 2)
                 / np.maximum(m + o.prior_readings, 1e-12))
    sd = np.maximum(sd, o.min_sd_db)
    return PathLossModel(theta[:, 0:2].copy(), theta[:, 2].copy(), theta[:, 3].copy(), theta[:, 4].copy(),
                         sd, n_heard, ok, o)


def scan_log_likelihood(model: PathLossModel, queries_dbm: np.ndarray, predicted_dbm: np.ndarray,
                        miss_weight: float = 0.0, huber_sd: float = 0.0, cap_sd: float = 0.0) -> np.ndarray:
    """ℓ (Q, M) of queries (Q, K) [dBm, NaN = not heard] at the M points whose predictions
    ``predicted_dbm`` = ``model.predict(points)`` (M, K) are given (module docstring); APs not
    fitted are ignored. ``miss_weight`` w ≥ 0 scales the not-heard term. ``huber_sd`` c > 0: each
    heard AP's term is −ρ_c(z), z = (q_i − μ_i)/σ_i, ρ_c the Huber loss (z²/2 up to |z| = c, then
    linear): a robust likelihood, for the APs whose prediction beyond the survey is off by tens
    of dB (one loop over the queries instead of three matrix products). ``cap_sd`` k > 0 (with
    huber_sd): |z| is clipped at k first, so that one AP costs at most ρ_c(k) (a redescending loss)."""
    q = real_array(queries_dbm, "queries_dbm", ndim=2, finite=False)
    mu = np.asarray(predicted_dbm, float)
    if q.shape[1] != mu.shape[1]:
        raise ValueError(f"indoorloc: argument 'predicted_dbm': expected shape (M, {q.shape[1]}), got {mu.shape}")
    ok = model.ok
    prec = np.where(ok, 1.0 / model.residual_sd_db ** 2, 0.0)       # (K,)
    mu0 = np.where(ok[None, :], mu, 0.0)
    heard = np.isfinite(q) & ok[None, :]
    qv = np.where(heard, q, 0.0)
    hp = heard * prec[None, :]
    if huber_sd > 0:
        inv_sd = (1.0 / model.residual_sd_db).astype(np.float32)
        mu32 = mu0.astype(np.float32)
        ll = np.empty((q.shape[0], mu.shape[0]))
        for j in range(q.shape[0]):
            h = np.flatnonzero(heard[j])
            z = np.abs((q[j, h].astype(np.float32)[None, :] - mu32[:, h]) * inv_sd[h][None, :])
            if cap_sd > 0:
                z = np.minimum(z, np.float32(cap_sd))
            ll[j] = -np.where(z <= huber_sd, 0.5 * z * z, huber_sd * z - 0.5 * huber_sd * huber_sd).sum(axis=1)
    else:
        # Σ_i h_i p_i (q_i − μ_i)² = Σ h p q² − 2 Σ (h p q) μ + Σ (h p) μ²
        ll = -0.5 * ((hp * qv * qv).sum(axis=1)[:, None] - 2.0 * (hp * qv) @ mu0.T + hp @ (mu0 * mu0).T)
    if miss_weight > 0:
        miss = np.where(ok[None, :], log_ndtr(-(mu0 - model.options.floor_dbm) / model.options.miss_sd_db), 0.0)
        ll += miss_weight * ((~np.isfinite(q)) & ok[None, :]).astype(float) @ miss.T
    return ll


__all__ = ["PathLossModel", "PathLossOptions", "fit_path_loss", "scan_log_likelihood"]
