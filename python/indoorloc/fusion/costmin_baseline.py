"""Cost-minimisation baseline of the fusion tracker: robust least squares of WiFi fixes and PDR
(the peer that ``indoorloc fusion evaluate`` scores as ``peer_costmin``; users compare against it).

The cost minimisation post-processing of the public Kaggle Indoor Location & Navigation 2021
notebooks: per walk, WiFi gives absolute fixes f_j at scan times t_j (noisy, sometimes gross),
PDR gives displacements Δ_k between consecutive step times s_k -> s_{k+1}; the track is the
positions p_0 .. p_{M-1} at the step times that minimise

    C(p, θ) = Σ_k ||p_{k+1} - p_k - R(θ) Δ_k||² / σ_Δ,k²
            + Σ_j c² ρ( w_j ||p(t_j) - f_j||² / (c² σ_f²) )
            [ + θ² / σ_θ²  when a rotation prior is given ]

- p(t_j) = (1 - a_j) p_k + a_j p_{k+1} with s_k <= t_j <= s_{k+1}, a_j = (t_j - s_k)/(s_{k+1} - s_k)
  (linear interpolation between the unknown positions; a fix outside [s_0, s_{M-1}] is attached
  to the nearest end position);
- ρ(z) the loss on the squared, scaled norm of the 2-D fix residual (scipy's conventions):
  "linear" z, "huber" z if z <= 1 else 2 sqrt(z) - 1, "soft_l1" 2 (sqrt(1 + z) - 1),
  "cauchy" log(1 + z); c = ``loss_scale`` (in units of σ_f: a fix further than about c σ_f from the
  track is down-weighted); w_j the optional per-fix weights (w_j = 1: standard deviation σ_f);
- R(θ) an optional per-walk rotation of the PDR displacements (the unknown yaw offset of the PDR
  heading), estimated jointly; θ = 0 when ``estimate_rotation`` is False.

Solver. The step terms stay quadratic and only the fix terms are robust, so the cost is minimised
by iteratively reweighted sparse linear least squares (majorise-minimise: fix j gets weight
ρ'(z_j) w_j / σ_f² from the current residual; each iteration is one sparse normal-equation solve
with scipy.sparse, SuperLU, over the 2 M coordinates). The rotation enters through one more
unknown: a Newton step on positions and θ together with backtracking on the true cost
(``rotation_method="joint"``, the default; plain Gauss-Newton, which drops the second derivative
of R(θ), can diverge when the fixes pull the path far from the rotated PDR), or, as several public
notebooks did, by alternation (``rotation_method="alternate"``): solve the positions with θ
fixed, then set θ to the closed-form best rotation of Δ onto the solved path's increments d_k,
θ = atan2(Σ_k (Δ_k × d_k) / σ_k², Σ_k (Δ_k · d_k) / σ_k²), and repeat. Alternation is the same
cost but converges slowly when σ_Δ << σ_f (the path is nearly rigid, so each increment fit moves
θ only a little); the joint step does not have that problem. Both start from a robust rigid
alignment (rotation + translation, or translation only) of the dead-reckoned PDR track to the
fixes, the σ_Δ -> 0 limit of the same cost.

Usage: ``positions = costmin_track(step_times_s, displacements_m, fix_times_s, fixes_m,
**CostMinSettings(...).kwargs())``, then ``evaluate_at(waypoint_times_s, step_times_s,
positions)``; ``return_summary=True`` adds a :class:`CostMinSummary` (rotation, iterations,
termination, cost, robust weights of the fixes, time) with a one-line ``report()``.

Settings (σ_Δ, σ_f, loss, c) are inputs: choose them on training walks, never on test walks.
Benchmark peer only (numpy + scipy): never imported by the ``indoorloc`` package.
"""

from __future__ import annotations


import time
from dataclasses import asdict, dataclass, field
from typing import Optional, Tuple, Union

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

__all__ = ['CostMinSettings', 'CostMinSummary', 'costmin_track', 'evaluate_at']

LOSSES = ("linear", "huber", "soft_l1", "cauchy")
ROTATION_METHODS = ("joint", "alternate")


@dataclass
class CostMinSettings:
    """Settings of :func:`costmin_track` (pass as ``costmin_track(..., **settings.kwargs())``).

    Attributes
    ----------
    sigma_step_m : 0.3. Standard deviation [m] of each axis of a PDR displacement between
        consecutive step times (about 0.2-0.4 of a 0.7 m step: stride-length and heading noise).
    sigma_fix_m : 5.0. Standard deviation [m] of each axis of a WiFi fix of weight 1.
    loss : "soft_l1". Robust loss on the fix terms: "linear" (quadratic cost), "huber",
        "soft_l1" or "cauchy".
    loss_scale : 1.0. c: the loss bends at a fix residual of about c * sigma_fix_m.
    estimate_rotation : True. Estimate a per-walk rotation of the PDR displacements.
    rotation_method : "joint". "joint" (Newton steps on positions and rotation together) or
        "alternate" (positions, then best rotation of Δ to the path's increments, repeated).
    sigma_rotation_rad : None. Standard deviation of a zero-mean prior on the rotation; None: no
        prior (the rotation is free).
    max_iterations : 50. Maximum reweighting (and, when "alternate", alternation) iterations.
    tolerance_m : 1e-4. Stop when no position moves more than this [m] (and θ less than
        tolerance_m / 100 rad) between iterations.
    """

    sigma_step_m: float = 0.3
    sigma_fix_m: float = 5.0
    loss: str = "soft_l1"
    loss_scale: float = 1.0
    estimate_rotation: bool = True
    rotation_method: str = "joint"
    sigma_rotation_rad: Optional[float] = None
    max_iterations: int = 50
    tolerance_m: float = 1e-4

    def kwargs(self) -> dict:
        """The settings as keyword arguments of :func:`costmin_track`."""
        return asdict(self)


@dataclass
class CostMinSummary:
    """What :func:`costmin_track` did (returned with ``return_summary=True``)."""

    rotation_rad: float = 0.0
    rotation_estimated: bool = False
    iterations: int = 0
    converged: bool = False
    termination: str = ""
    cost: float = float("nan")
    n_steps: int = 0
    n_fixes: int = 0
    n_fixes_downweighted: int = 0  # robust weight rho'(z) < 0.5
    robust_weights: np.ndarray = field(default_factory=lambda: np.zeros(0))
    seconds: float = 0.0

    def report(self) -> str:
        return (
            f"costmin: {self.termination}, {self.iterations} iterations, cost {self.cost:.4g}, "
            f"rotation {np.degrees(self.rotation_rad):+.2f} deg"
            f"{'' if self.rotation_estimated else ' (fixed)'}, {self.n_fixes} fixes "
            f"({self.n_fixes_downweighted} down-weighted), {self.n_steps} step times, "
            f"{self.seconds * 1e3:.1f} ms"
        )


# --------------------------------------------------------------------------- checks


def _array(name: str, value, ndim: int, cols: Optional[int] = None) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: not a numeric array ({exc})") from None
    if a.ndim != ndim or (cols is not None and a.shape[1] != cols):
        want = "(N,)" if ndim == 1 else f"(N, {cols})"
        raise ValueError(f"{name} must have shape {want}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinite values")
    return a


def _positive(name: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number, got {value!r}") from None
    if not (np.isfinite(v) and v > 0):
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return v


def _sigma_steps(sigma_step_m, m: int) -> np.ndarray:
    s = np.asarray(sigma_step_m, dtype=float)
    if s.ndim == 0:
        return np.full(max(m - 1, 0), _positive("sigma_step_m", s))
    if s.shape != (m - 1,):
        raise ValueError(f"sigma_step_m must be a scalar or have shape ({m - 1},), got {s.shape}")
    if not np.all(np.isfinite(s) & (s > 0)):
        raise ValueError("sigma_step_m must be positive and finite")
    return s


def _check_times(name: str, t: np.ndarray, strict: bool) -> None:
    d = np.diff(t)
    if strict and np.any(d <= 0):
        raise ValueError(f"{name} must be strictly increasing")


# --------------------------------------------------------------------------- model pieces


def _rho_prime(loss: str, z: np.ndarray) -> np.ndarray:
    """dρ/dz of the losses (the IRLS weight)."""
    if loss == "linear":
        return np.ones_like(z)
    if loss == "huber":
        return np.where(z <= 1.0, 1.0, 1.0 / np.sqrt(np.maximum(z, 1.0)))
    if loss == "soft_l1":
        return 1.0 / np.sqrt(1.0 + z)
    return 1.0 / (1.0 + z)  # cauchy


def _rho(loss: str, z: np.ndarray) -> np.ndarray:
    if loss == "linear":
        return z
    if loss == "huber":
        return np.where(z <= 1.0, z, 2.0 * np.sqrt(np.maximum(z, 1.0)) - 1.0)
    if loss == "soft_l1":
        return 2.0 * (np.sqrt(1.0 + z) - 1.0)
    return np.log1p(z)


def _rot(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def _interp_weights(step_times_s: np.ndarray, t: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Index k and fraction a with p(t) = (1 - a) p_k + a p_{k+1}; clamped to the ends."""
    m = step_times_s.size
    if m == 1:
        return np.zeros(t.size, dtype=np.int64), np.zeros(t.size)
    k = np.clip(np.searchsorted(step_times_s, t, side="right") - 1, 0, m - 2)
    a = (t - step_times_s[k]) / (step_times_s[k + 1] - step_times_s[k])
    return k, np.clip(a, 0.0, 1.0)


def _robust_alignment(q_fix, fixes, w_fix, sigma_fix, loss, scale, rotate, iterations=30):
    """Rigid alignment R(θ) q + t of the dead-reckoned points q_fix (J, 2) to the fixes, by IRLS
    on the same robust fix cost (σ_Δ -> 0 limit). Returns θ, t."""
    theta, t = 0.0, np.zeros(2)
    robust = np.ones(len(fixes))
    for _ in range(iterations):
        w = w_fix * robust
        wsum = w.sum()
        qc = q_fix - (w @ q_fix) / wsum
        fc = fixes - (w @ fixes) / wsum
        new_theta = theta
        if rotate:
            cross = np.sum(w * (qc[:, 0] * fc[:, 1] - qc[:, 1] * fc[:, 0]))
            dot = np.sum(w * np.sum(qc * fc, axis=1))
            new_theta = float(np.arctan2(cross, dot))
        rq = q_fix @ _rot(new_theta).T
        new_t = (w @ (fixes - rq)) / wsum
        settled = abs(new_theta - theta) < 1e-9 and np.allclose(new_t, t, atol=1e-9)
        theta, t = new_theta, new_t
        z = w_fix * np.sum((rq + t - fixes) ** 2, axis=1) / (scale**2 * sigma_fix**2)
        robust = _rho_prime(loss, z)
        if settled:
            break
    return theta, t


class _Problem:
    """Sparse structure of the cost: unknowns x = [x_0, y_0, x_1, y_1, ..., (θ increment)]."""

    def __init__(self, step_times, disp, fix_times, fixes, w_fix, sigma_steps, sigma_fix):
        self.m = step_times.size
        self.disp, self.fixes, self.w_fix = disp, fixes, w_fix
        self.info_step = 1.0 / sigma_steps**2  # (M-1,)
        self.sigma_fix = sigma_fix
        k, a = _interp_weights(step_times, fix_times)
        self.fix_k, self.fix_a = k, a
        j = fixes.shape[0]
        # Fix rows: row 2 j + axis = (1 - a) p_k[axis] + a p_{k+1}[axis] (k + 1 clamped for M = 1).
        k1 = np.minimum(k + 1, self.m - 1)
        rows = np.repeat(np.arange(2 * j), 2)
        cols = np.empty(4 * j, dtype=np.int64)
        vals = np.empty(4 * j)
        for axis in (0, 1):
            cols[axis * 2 :: 4] = 2 * k + axis
            cols[axis * 2 + 1 :: 4] = 2 * k1 + axis
            vals[axis * 2 :: 4] = 1.0 - a
            vals[axis * 2 + 1 :: 4] = a
        self.A_fix = sp.csr_matrix((vals, (rows, cols)), shape=(2 * j, 2 * self.m))
        # Step rows: row 2 k + axis = p_{k+1}[axis] - p_k[axis].
        n = self.m - 1
        r = np.repeat(np.arange(2 * n), 2)
        c = np.empty(4 * n, dtype=np.int64)
        v = np.tile([-1.0, 1.0], 2 * n)
        kk = np.arange(n)
        for axis in (0, 1):
            c[axis * 2 :: 4] = 2 * kk + axis
            c[axis * 2 + 1 :: 4] = 2 * (kk + 1) + axis
        self.A_step = sp.csr_matrix((v, (r, c)), shape=(2 * n, 2 * self.m))
        self.w_step = np.repeat(self.info_step, 2)
        self.AtW_step = (self.A_step.T @ sp.diags(self.w_step)).tocsr()  # constant over iterations
        self.N_step = (self.AtW_step @ self.A_step).tocsc()

    def fix_z(self, p: np.ndarray, scale: float) -> np.ndarray:
        k1 = np.minimum(self.fix_k + 1, self.m - 1)
        at = (1.0 - self.fix_a)[:, None] * p[self.fix_k] + self.fix_a[:, None] * p[k1]
        return self.w_fix * np.sum((at - self.fixes) ** 2, axis=1) / (scale**2 * self.sigma_fix**2)

    def cost(self, p, theta, loss, scale, sigma_rot) -> float:
        rd = self.disp @ _rot(theta).T
        step = np.sum(self.info_step * np.sum((np.diff(p, axis=0) - rd) ** 2, axis=1))
        fix = scale**2 * np.sum(_rho(loss, self.fix_z(p, scale)))
        prior = 0.0 if sigma_rot is None else (theta / sigma_rot) ** 2
        return float(step + fix + prior)

    def solve(self, theta, robust, with_rotation, sigma_rot, p=None):
        """One weighted linear least-squares solve (rotation: one Newton step of the reweighted
        cost about (p, θ)). Returns positions (M, 2) and the θ increment."""
        m = self.m
        rd = self.disp @ _rot(theta).T  # (M-1, 2)
        w_s = self.w_step
        w_f = np.repeat(self.w_fix * robust / self.sigma_fix**2, 2)
        A_f = self.A_fix
        N = (self.N_step + A_f.T @ sp.diags(w_f) @ A_f).tocsc()
        b = self.AtW_step @ rd.ravel() + A_f.T @ (w_f * self.fixes.ravel())
        if not with_rotation:
            x = spsolve(N, b)
            return np.asarray(x).reshape(m, 2), 0.0
        # d(R(θ) Δ)/dθ = R(θ) J Δ, J = [[0, -1], [1, 0]]: step row p_{k+1} - p_k - g_k δ = R Δ_k.
        g = (self.disp @ np.array([[0.0, 1.0], [-1.0, 0.0]])) @ _rot(theta).T  # rows R J Δ_k
        g = g.ravel()
        col = -(self.AtW_step @ g)  # coupling of positions with δ
        corner = np.sum(w_s * g * g) + (0.0 if sigma_rot is None else 1.0 / sigma_rot**2)
        # Second-order term of R(θ) (d²(RΔ)/dθ² = -RΔ), which Gauss-Newton drops: ½ ∂²/∂θ² of
        # Σ w ||d - RΔ||² is Σ w |g|² + Σ w (d - RΔ)·RΔ. Kept when the corner stays positive (an
        # exact Newton step: Gauss-Newton alone diverges when the fixes pull the path far from
        # the rotated PDR); the right-hand side is unchanged because it multiplies δ only.
        if p is not None:
            extra = np.sum(w_s * (np.diff(p, axis=0) - rd).ravel() * rd.ravel())
            if corner + extra > 0.1 * corner:
                corner += extra
        # Step row residual (p_{k+1} - p_k) - R Δ_k - g_k δ; the δ normal equation:
        # -gᵀ W A_s p + (gᵀ W g + 1/σ_θ²) δ = -gᵀ W R Δ - θ_0 / σ_θ² (prior on θ = θ_0 + δ).
        rhs_t = -np.sum(w_s * g * rd.ravel())
        if sigma_rot is not None:
            rhs_t -= theta / sigma_rot**2
        col_m = sp.csc_matrix(col[:, None])
        Nf = sp.bmat([[N, col_m], [col_m.T, sp.csc_matrix([[corner]])]]).tocsc()
        x = np.asarray(spsolve(Nf, np.concatenate([b, [rhs_t]])))
        return x[:-1].reshape(m, 2), float(x[-1])


# --------------------------------------------------------------------------- public API


def _checked_fixes(fix_times_s, fixes_m, fix_weights) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The fixes' times (J,), positions (J, 2) [m] and weights (J,) (all 1 when None), checked:
    ValueError naming the argument."""
    fix_times = _array("fix_times_s", fix_times_s, 1)
    if fix_times.size == 0:
        raise ValueError("fix_times_s / fixes_m: no fixes (at least one WiFi fix is needed)")
    fixes = _array("fixes_m", fixes_m, 2, 2)
    if fixes.shape[0] != fix_times.size:
        raise ValueError(
            f"fixes_m must have shape ({fix_times.size}, 2) to match fix_times_s, got {fixes.shape}"
        )
    if fix_weights is None:
        return fix_times, fixes, np.ones(fix_times.size)
    w_fix = _array("fix_weights", fix_weights, 1)
    if w_fix.size != fix_times.size:
        raise ValueError(f"fix_weights must have shape ({fix_times.size},), got {w_fix.shape}")
    if np.any(w_fix < 0) or not np.any(w_fix > 0):
        raise ValueError("fix_weights must be non-negative and not all zero")
    return fix_times, fixes, w_fix


def _best_rotation(disp: np.ndarray, increments: np.ndarray, w: np.ndarray, sigma_rot: Optional[float]) -> float:
    """The rotation [rad] that best maps the PDR displacements (M - 1, 2) onto the solved
    increments (M - 1, 2) under step weights w (M - 1,): the alternation's rotation update; with a
    prior σ_θ it maximises dot cos θ + cross sin θ - θ² / (2 σ²) by a few Newton steps."""
    cross = np.sum(w * (disp[:, 0] * increments[:, 1] - disp[:, 1] * increments[:, 0]))
    dot = np.sum(w * np.sum(disp * increments, axis=1))
    theta = float(np.arctan2(cross, dot))
    if sigma_rot is not None:
        for _ in range(10):
            g1 = -dot * np.sin(theta) + cross * np.cos(theta) - theta / sigma_rot**2
            g2 = -dot * np.cos(theta) - cross * np.sin(theta) - 1.0 / sigma_rot**2
            theta -= g1 / g2
    return theta


def costmin_track(
    step_times_s,
    displacements_m,
    fix_times_s,
    fixes_m,
    fix_weights=None,
    *,
    sigma_step_m: Union[float, np.ndarray] = CostMinSettings.sigma_step_m,
    sigma_fix_m: float = CostMinSettings.sigma_fix_m,
    loss: str = CostMinSettings.loss,
    loss_scale: float = CostMinSettings.loss_scale,
    estimate_rotation: bool = CostMinSettings.estimate_rotation,
    rotation_method: str = CostMinSettings.rotation_method,
    sigma_rotation_rad: Optional[float] = CostMinSettings.sigma_rotation_rad,
    max_iterations: int = CostMinSettings.max_iterations,
    tolerance_m: float = CostMinSettings.tolerance_m,
    return_summary: bool = False,
):
    """Positions at the step times minimising the WiFi-fix + PDR-displacement cost (module doc).

    Parameters
    ----------
    step_times_s : (M,) strictly increasing times [s] of the unknown positions (M >= 1).
    displacements_m : (M - 1, 2) PDR displacement [m] from step time k to k + 1 (PDR frame).
    fix_times_s : (J,) times [s] of the WiFi fixes (J >= 1; any order; outside the step times a
        fix is attached to the nearest end position).
    fixes_m : (J, 2) WiFi fixes [m] in the world frame.
    fix_weights : (J,) non-negative weights (information multipliers: σ_j = σ_f / sqrt(w_j)),
        not all zero; None: all 1.
    sigma_step_m : scalar or (M - 1,) per-axis standard deviation [m] of each displacement.
    sigma_fix_m, loss, loss_scale, estimate_rotation, rotation_method, sigma_rotation_rad,
    max_iterations, tolerance_m : see :class:`CostMinSettings` (defaults there).
    return_summary : also return a :class:`CostMinSummary`.

    Returns
    -------
    positions_m : (M, 2) positions at the step times [m] (and the summary if asked).

    Raises
    ------
    ValueError naming the argument: wrong shape, NaN / inf, non-increasing step times, no fixes,
    bad weights, non-positive σ, unknown loss or rotation method.
    """
    t0 = time.perf_counter()
    step_times = _array("step_times_s", step_times_s, 1)
    m = step_times.size
    if m == 0:
        raise ValueError("step_times_s is empty: need at least one step time")
    _check_times("step_times_s", step_times, strict=True)
    if m == 1 and np.size(displacements_m) == 0:
        displacements_m = np.zeros((0, 2))
    disp = _array("displacements_m", displacements_m, 2, 2)
    if disp.shape[0] != m - 1:
        raise ValueError(
            f"displacements_m must have shape ({m - 1}, 2) (one per pair of consecutive "
            f"step_times_s), got {disp.shape}"
        )
    fix_times, fixes, w_fix = _checked_fixes(fix_times_s, fixes_m, fix_weights)
    sigma_steps = _sigma_steps(sigma_step_m, m)
    sigma_fix = _positive("sigma_fix_m", sigma_fix_m)
    scale = _positive("loss_scale", loss_scale)
    if loss not in LOSSES:
        raise ValueError(f"loss must be one of {LOSSES}, got {loss!r}")
    if rotation_method not in ROTATION_METHODS:
        raise ValueError(f"rotation_method must be one of {ROTATION_METHODS}, got {rotation_method!r}")
    sigma_rot = None if sigma_rotation_rad is None else _positive("sigma_rotation_rad", sigma_rotation_rad)
    if int(max_iterations) < 1:
        raise ValueError(f"max_iterations must be >= 1, got {max_iterations!r}")
    tol = _positive("tolerance_m", tolerance_m)

    problem = _Problem(step_times, disp, fix_times, fixes, w_fix, sigma_steps, sigma_fix)
    summary = CostMinSummary(n_steps=m, n_fixes=fix_times.size)

    # Rotation observable only if the fixes of positive weight sit at >= 2 distinct PDR points;
    # otherwise it is left at 0 and the summary says so (rotation_estimated False).
    dead_reckoned = np.vstack([np.zeros((1, 2)), np.cumsum(disp, axis=0)])
    k, a = problem.fix_k, problem.fix_a
    k1 = np.minimum(k + 1, m - 1)
    q_fix = (1.0 - a)[:, None] * dead_reckoned[k] + a[:, None] * dead_reckoned[k1]
    used = w_fix > 0
    spread = np.ptp(q_fix[used], axis=0).max() if used.sum() > 1 else 0.0
    rotate = bool(estimate_rotation) and spread > 1e-6
    summary.rotation_estimated = rotate

    # Start: robust rigid alignment of the dead-reckoned track (σ_Δ -> 0 limit of the cost).
    theta, shift = _robust_alignment(q_fix, fixes, w_fix, sigma_fix, loss, scale, rotate)
    p = dead_reckoned @ _rot(theta).T + shift
    summary.termination = "max_iterations"
    for it in range(1, int(max_iterations) + 1):
        robust = _rho_prime(loss, problem.fix_z(p, scale))
        if rotate and rotation_method == "joint":
            new_p, dtheta = problem.solve(theta, robust, True, sigma_rot, p)
            # Backtracking on the true cost: the Newton direction of the reweighted (majorising)
            # cost is a descent direction of the robust cost, the full step may overshoot.
            current = problem.cost(p, theta, loss, scale, sigma_rot)
            alpha = 1.0
            while alpha > 1e-6:
                trial_p, trial_theta = p + alpha * (new_p - p), theta + alpha * dtheta
                if problem.cost(trial_p, trial_theta, loss, scale, sigma_rot) <= current * (1 + 1e-12):
                    break
                alpha *= 0.5
            else:
                summary.iterations = it
                summary.converged = True
                summary.termination = "no further decrease"
                break
            new_p, new_theta = trial_p, trial_theta
        else:
            new_p, _ = problem.solve(theta, robust, False, sigma_rot)
            new_theta = theta
            if rotate:  # alternation: best rotation of Δ onto the solved increments
                new_theta = _best_rotation(disp, np.diff(new_p, axis=0), problem.info_step, sigma_rot)
        moved = np.max(np.abs(new_p - p))
        turned = abs(new_theta - theta)
        p, theta = new_p, new_theta
        summary.iterations = it
        if moved < tol and turned < tol * 1e-2:
            summary.converged = True
            summary.termination = "converged"
            break
    theta = float(np.arctan2(np.sin(theta), np.cos(theta)))
    robust = _rho_prime(loss, problem.fix_z(p, scale))
    summary.rotation_rad = theta
    summary.cost = problem.cost(p, theta, loss, scale, sigma_rot)
    summary.robust_weights = robust
    summary.n_fixes_downweighted = int(np.sum(robust < 0.5))
    summary.seconds = time.perf_counter() - t0
    return (p, summary) if return_summary else p


def evaluate_at(times_s, step_times_s, positions_m) -> np.ndarray:
    """The track at arbitrary times (e.g. waypoint times) by linear interpolation.

    Parameters
    ----------
    times_s : (N,) query times [s]; outside the step times the end positions are held.
    step_times_s : (M,) strictly increasing step times [s] of the track (M >= 1).
    positions_m : (M, 2) positions [m] at the step times (e.g. from :func:`costmin_track`).

    Returns
    -------
    (N, 2) positions [m].
    """
    times = _array("times_s", times_s, 1)
    st = _array("step_times_s", step_times_s, 1)
    if st.size == 0:
        raise ValueError("step_times_s is empty: need at least one step time")
    _check_times("step_times_s", st, strict=True)
    pos = _array("positions_m", positions_m, 2, 2)
    if pos.shape[0] != st.size:
        raise ValueError(f"positions_m must have shape ({st.size}, 2) to match step_times_s, got {pos.shape}")
    return np.column_stack([np.interp(times, st, pos[:, 0]), np.interp(times, st, pos[:, 1])])
