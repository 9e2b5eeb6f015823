"""Baselines of the analog HMM paper (Lguensat et al., EUSIPCO 2016, Tables 1 and 2), in numpy.

Three reconstructions the paper compares its Analog Forward-Backward (AnFB) against:

- **EnKS** with the true Lorenz-63 equations (:func:`enks_lorenz63`): the model-based reference
  of Table 1 (Evensen 2003, "The ensemble Kalman filter: theoretical formulation and practical
  implementation", §4-5: stochastic EnKF with perturbed observations, and the ensemble Kalman
  smoother that updates every past state with the same ensemble weights).
- **AnEnKS** (:func:`anenks`): the same smoother with the model replaced by analog forecasting
  (Tandeo et al. 2015, "Combining analog method and ensemble data assimilation: application to
  the Lorenz-63 chaotic system"; local linear regression variant of Lguensat et al. 2017, "The
  analog data assimilation", MWR). Generic dimension: Lorenz-63 and the IMU experiment.
- **NNN** (:func:`nearest_neighbour_fill`): the naive nearest-neighbour interpolation of Table 2.

The ensemble smoother (:func:`ensemble_kalman_smoother`) is shared. With the ensemble E (N, n)
(one member per row), anomalies A' = E - mean, observed anomalies S = A'[:, obs] (N, m) and
perturbed observations D = y + eps, eps ~ N(0, R) (N, m), the analysis at time k is (Evensen
2003, eq. (45)-(49) written for member rows)::

    C = S^T S / (N - 1) + R                            (m, m)
    G = C^{-1} (D - E[:, obs])^T                       (m, N)
    E_k^a = (I + W_k)^T E_k^f,   W_k = S G / (N - 1)   (N, N)

and the EnKS applies the same transform to every earlier time j < k: E_j <- (I + W_k)^T E_j. The
smoothed ensemble at time j is therefore E_j^a transformed by all later analyses; its mean is
v_j^T E_j^a with v_j = (I + W_{j+1}) v_{j+1}, v_{T-1} = 1/N, which this module computes in one
backward sweep of O(N m) per analysis (no (T, N, N) storage, no O(T^2) re-updates).

Everything is vectorised over members (a Python loop runs over time steps only) and seeded by a
``numpy.random.default_rng(seed)`` stream. Probabilities are Gaussian here, so no log-space
weights are involved except the analog kernel weights, which are normalised after subtracting
the smallest squared distance.
"""

from __future__ import annotations

from typing import Callable, Optional, Sequence, Tuple, Union

import numpy as np

ArrayLike = Union[np.ndarray, Sequence[float], float]

#: Lorenz-63 model error of the EnKS: variance of the additive N(0, q I) noise per RK4 step.
DEFAULT_LORENZ_Q = 0.05


def _as_cov(R: ArrayLike, p: int, name: str = "R") -> np.ndarray:
    """R as a (p, p) SPD matrix from a scalar, a (p,) diagonal or a (p, p) matrix."""
    R = np.asarray(R, dtype=float)
    if R.ndim == 0:
        R = np.eye(p) * float(R)
    elif R.ndim == 1:
        if R.size != p:
            raise ValueError(f"indoorloc: argument '{name}': expected {p} variances, got {R.size}")
        R = np.diag(R)
    if R.shape != (p, p):
        raise ValueError(f"indoorloc: argument '{name}': expected shape ({p}, {p}), got {R.shape}")
    if not np.all(np.isfinite(R)) or not np.allclose(R, R.T):
        raise ValueError(f"indoorloc: argument '{name}': expected a finite symmetric matrix")
    try:
        np.linalg.cholesky(R)
    except np.linalg.LinAlgError:
        raise ValueError(f"indoorloc: argument '{name}': expected a positive definite matrix") from None
    return R


def _check_observations(observations: np.ndarray, observed: Sequence[int], n: int) -> Tuple[np.ndarray, np.ndarray]:
    obs = np.asarray(observations, dtype=float)
    if obs.ndim == 1:
        obs = obs[:, None]
    if obs.ndim != 2 or obs.shape[0] < 1:
        raise ValueError(f"indoorloc: argument 'observations': expected shape (T, p), got {obs.shape}")
    idx = np.asarray(observed, dtype=int).ravel()
    if idx.size != obs.shape[1]:
        raise ValueError(
            f"indoorloc: argument 'observed': {idx.size} indices for {obs.shape[1]} observation columns"
        )
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        raise ValueError(f"indoorloc: argument 'observed': indices must lie in [0, {n}), got {idx.tolist()}")
    if np.any(np.isinf(obs)):
        raise ValueError("indoorloc: argument 'observations': infinite values (use NaN for missing)")
    return obs, idx


def ensemble_kalman_smoother(
    forecast: Callable[[np.ndarray], np.ndarray],
    initial_ensemble: np.ndarray,
    observations: np.ndarray,
    observed: Sequence[int],
    R: ArrayLike,
    rng: np.random.Generator,
) -> Tuple[np.ndarray, np.ndarray]:
    """Stochastic EnKF over the whole window and the EnKS (Evensen 2003) on top of it.

    Parameters
    ----------
    forecast : callable
        ``forecast(E) -> E_next`` for an (N, n) ensemble, noise included (it draws from its own
        generator or from ``rng``).
    initial_ensemble : (N, n) array
        Background ensemble at t = 0, before the analysis of the first observation.
    observations : (T, p) array
        Observation y_t = x_t[observed] + N(0, R); NaN entries are missing. A row without any
        finite entry gets no analysis.
    observed : (p,) ints
        State component seen by each observation column.
    R : float, (p,) or (p, p)
        Observation noise (co)variance.
    rng : numpy Generator
        Draws the observation perturbations.

    Returns
    -------
    smoothed_mean : (T, n) array, mean of p(x_t | y_{0:T-1}) under the ensemble approximation.
    filtered_mean : (T, n) array, mean of p(x_t | y_{0:t}).
    """
    E = np.array(initial_ensemble, dtype=float)
    if E.ndim != 2 or E.shape[0] < 2:
        raise ValueError(f"indoorloc: argument 'initial_ensemble': expected (N >= 2, n), got {E.shape}")
    N, n = E.shape
    obs, idx = _check_observations(observations, observed, n)
    T, p = obs.shape
    R = _as_cov(R, p)
    history = np.empty((T, N, n))
    filtered = np.empty((T, n))
    transforms = {}  # t -> (S (N, m), G (m, N)): W_t = S G / (N - 1)
    for t in range(T):
        if t > 0:
            E = forecast(E)
            if E.shape != (N, n) or not np.all(np.isfinite(E)):
                raise RuntimeError(f"indoorloc: ensemble forecast diverged or changed shape at step {t}")
        seen = np.isfinite(obs[t])
        if seen.any():
            cols = idx[seen]
            Rt = R[np.ix_(seen, seen)]
            mean = E.mean(axis=0)
            anomalies = E - mean
            S = anomalies[:, cols]
            C = S.T @ S / (N - 1) + Rt
            eps = rng.standard_normal((N, cols.size)) @ np.linalg.cholesky(Rt).T
            innovations = obs[t, seen] + eps - E[:, cols]  # (N, m)
            G = np.linalg.solve(C, innovations.T)  # (m, N)
            # E^a[j] = E[j] + sum_i W[i, j] A'[i], W = S G / (N - 1)
            E = E + G.T @ (S.T @ anomalies) / (N - 1)  # O(N m n), W never formed
            transforms[t] = (S, G)
        history[t] = E
        filtered[t] = E.mean(axis=0)
    smoothed = np.empty((T, n))
    v = np.full(N, 1.0 / N)
    smoothed[T - 1] = v @ history[T - 1]
    for t in range(T - 2, -1, -1):
        if t + 1 in transforms:
            S, G = transforms[t + 1]
            v = v + S @ (G @ v) / (N - 1)  # v_t = (I + W_{t+1}) v_{t+1}
        smoothed[t] = v @ history[t]
    return smoothed, filtered


def _gaussian_ensemble(mean: np.ndarray, cov: np.ndarray, n_members: int, rng: np.random.Generator) -> np.ndarray:
    w, V = np.linalg.eigh(cov)
    root = V * np.sqrt(np.clip(w, 0.0, None))
    return mean + rng.standard_normal((n_members, mean.size)) @ root.T


def enks_lorenz63(
    observations: np.ndarray,
    n_members: int = 100,
    seed: int = 0,
    observed: Sequence[int] = (0,),
    R: ArrayLike = 2.0,
    Q: float = DEFAULT_LORENZ_Q,
    dt: float = 0.01,
    initial_mean: Optional[np.ndarray] = None,
    initial_cov: Optional[np.ndarray] = None,
) -> np.ndarray:
    """EnKS with the true Lorenz-63 model: the "EnKS (L63)" column of Table 1.

    Forecast: one RK4 step of ``dt`` per time step for every member, plus additive model noise
    N(0, Q I) (Q = 0.05 by default: a small model error that keeps the ensemble from collapsing
    between observations 40 steps apart). Initial ensemble: the attractor's climatology
    N(CLIMATOLOGY_MEAN, CLIMATOLOGY_COV), unless given; the analysis of the first observation
    then centres it on that observation. Analysis and smoothing: :func:`ensemble_kalman_smoother`.

    Parameters
    ----------
    observations : (T, p) array
        NaN = missing (no analysis at that step).
    n_members : int
        Ensemble size (100 in the paper).
    seed : int
        Seed of the ``default_rng`` stream (initial ensemble, model noise, perturbations).
    observed : (p,) ints
        Observed components (x only: ``(0,)``).
    R : float, (p,) or (p, p)
        Observation noise (co)variance (2 in the paper).
    Q : float
        Model noise variance per step and component.
    dt : float
        Integration step.

    Returns
    -------
    (T, 3) array: smoothed mean.
    """
    from indoorloc.simulate import lorenz63

    if int(n_members) != n_members or n_members < 2:
        raise ValueError(f"indoorloc: argument 'n_members': expected an integer >= 2, got {n_members}")
    if not Q >= 0:
        raise ValueError(f"indoorloc: argument 'Q': expected a variance >= 0, got {Q}")
    rng = np.random.default_rng(seed)
    mean = lorenz63.CLIMATOLOGY_MEAN if initial_mean is None else np.asarray(initial_mean, float)
    cov = lorenz63.CLIMATOLOGY_COV if initial_cov is None else np.asarray(initial_cov, float)
    E0 = _gaussian_ensemble(mean, cov, int(n_members), rng)
    q_std = np.sqrt(Q)

    def forecast(E: np.ndarray) -> np.ndarray:
        out = lorenz63.rk4_step(E, dt)
        if q_std > 0:
            out += q_std * rng.standard_normal(out.shape)
        return out

    smoothed, _ = ensemble_kalman_smoother(forecast, E0, observations, observed, R, rng)
    return smoothed


class AnalogForecaster:
    """Analog forecasting by weighted local linear regression on the K nearest analogs.

    For a state x with nearest analogs a_1..a_K (catalog, kd-tree built once) and their
    successors s_1..s_K, the weights are w_k ∝ exp(-d_k^2 / (2 sigma^2)), sigma adaptive (the
    median, or the standard deviation, of the K distances d_k), and the forecast is

        s_k ≈ alpha + B (a_k - x)   (weighted least squares, ridge on B)
        x_next = alpha + r_j,       r_j = s_j - alpha - B (a_j - x), j ~ Categorical(w)

    i.e. the regression evaluated at x (= alpha) plus one weighted regression residual (Tandeo
    et al. 2015; Lguensat et al. 2017 eq. (6)-(8), "local linear" with residual resampling).

    Parameters
    ----------
    analogs, successors : (M, n) arrays
        Catalog pairs: ``successors[i]`` follows ``analogs[i]`` by one time step.
    k : int
        Number of analogs.
    bandwidth : "median" or "std"
        How sigma adapts to the K distances.
    ridge : float
        Ridge on the slopes, relative to the mean weighted variance of the analogs around x.
        The K analogs are often consecutive states of a few trajectory pieces, nearly collinear:
        without it (1e-6) the slopes across the pieces blow up and the Lorenz-63 AnEnKS diverges
        at M = 10^4 with K = 50; 1e-2 keeps the RMSE at the K = 20 level.
    """

    def __init__(
        self, analogs: np.ndarray, successors: np.ndarray, k: int = 50, bandwidth: str = "median", ridge: float = 1e-2
    ):
        from scipy.spatial import cKDTree

        analogs = np.asarray(analogs, dtype=float)
        successors = np.asarray(successors, dtype=float)
        if analogs.ndim != 2 or analogs.shape != successors.shape:
            raise ValueError(
                f"indoorloc: arguments 'catalog_states', 'successor_states': expected two (M, n) arrays "
                f"of the same shape, got {analogs.shape} and {successors.shape}"
            )
        if not (np.all(np.isfinite(analogs)) and np.all(np.isfinite(successors))):
            raise ValueError("indoorloc: catalog states must be finite")
        if int(k) != k or not 2 <= k <= analogs.shape[0]:
            raise ValueError(f"indoorloc: argument 'k': expected an integer in [2, {analogs.shape[0]}], got {k}")
        if bandwidth not in ("median", "std"):
            raise ValueError(f"indoorloc: argument 'bandwidth': expected 'median' or 'std', got {bandwidth!r}")
        if not ridge >= 0:
            raise ValueError(f"indoorloc: argument 'ridge': expected >= 0, got {ridge}")
        self.analogs = analogs
        self.successors = successors
        self.k = int(k)
        self.bandwidth = bandwidth
        self.ridge = float(ridge)
        self.tree = cKDTree(analogs)

    def weights(self, distances: np.ndarray) -> np.ndarray:
        """Normalised kernel weights (N, K) from the analog distances (N, K)."""
        if self.bandwidth == "median":
            sigma = np.median(distances, axis=1)
        else:
            sigma = distances.std(axis=1)
        sigma = np.maximum(sigma, 1e-12 * (1.0 + distances[:, -1]))
        d2 = distances**2
        w = np.exp(-(d2 - d2[:, :1]) / (2.0 * sigma[:, None] ** 2))
        return w / w.sum(axis=1, keepdims=True)

    def __call__(self, E: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Forecast every member of the ensemble ``E`` (N, n) one step; returns (N, n)."""
        N, n = E.shape
        distances, index = self.tree.query(E, k=self.k)
        w = self.weights(distances)  # (N, K)
        X = np.empty((N, self.k, n + 1))
        X[..., 0] = 1.0
        X[..., 1:] = self.analogs[index] - E[:, None, :]
        Y = self.successors[index]  # (N, K, n)
        XwT = (X * w[..., None]).transpose(0, 2, 1)  # (N, n + 1, K)
        gram = XwT @ X
        diag = np.arange(1, n + 1)
        reg = self.ridge * gram[:, diag, diag].mean(axis=1) + 1e-12
        gram[:, diag, diag] += reg[:, None]
        beta = np.linalg.solve(gram, XwT @ Y)  # (N, n + 1, n)
        residuals = Y - X @ beta  # (N, K, n)
        u = rng.random(N)
        j = np.minimum((np.cumsum(w, axis=1) < u[:, None]).sum(axis=1), self.k - 1)
        return beta[:, 0, :] + residuals[np.arange(N), j]


def anenks(
    observations: np.ndarray,
    catalog_states: np.ndarray,
    successor_states: np.ndarray,
    observed: Sequence[int],
    R: ArrayLike,
    n_members: int = 100,
    k: int = 50,
    seed: int = 0,
    bandwidth: str = "median",
    Q: float = 0.0,
    initial_mean: Optional[np.ndarray] = None,
    initial_cov: Optional[np.ndarray] = None,
    forecaster: Optional[AnalogForecaster] = None,
) -> np.ndarray:
    """Analog ensemble Kalman smoother (AnEnKS): the EnKS with analog forecasting.

    Parameters
    ----------
    observations : (T, p) array
        y_t = x_t[observed] + N(0, R); NaN = missing.
    catalog_states, successor_states : (M, n) arrays
        Analogs and their successors (one time step later).
    observed : (p,) ints
        State component seen by each observation column.
    R : float, (p,) or (p, p)
        Observation noise (co)variance.
    n_members : int
        Ensemble size (100 in the paper).
    k : int
        Number of analogs of the local linear regression (needs k > n + 1 for a well-posed
        regression; a small ridge keeps smaller k usable).
    seed : int
        Seed of the ``default_rng`` stream.
    bandwidth : "median" or "std"
        Adaptive kernel scale, see :class:`AnalogForecaster`.
    Q : float
        Optional additive forecast noise variance per step and component (0: the residual
        resampling is the only forecast noise, as in Tandeo et al.).
    initial_mean, initial_cov : optional
        Background at t = 0; default the catalog's mean and covariance (climatology).
    forecaster : AnalogForecaster, optional
        Reuse a forecaster (and its kd-tree) across calls; then ``catalog_states``,
        ``successor_states``, ``k`` and ``bandwidth`` are ignored.

    Returns
    -------
    (T, n) array: smoothed mean.
    """
    if forecaster is None:
        forecaster = AnalogForecaster(catalog_states, successor_states, k=k, bandwidth=bandwidth)
    if int(n_members) != n_members or n_members < 2:
        raise ValueError(f"indoorloc: argument 'n_members': expected an integer >= 2, got {n_members}")
    if not Q >= 0:
        raise ValueError(f"indoorloc: argument 'Q': expected a variance >= 0, got {Q}")
    rng = np.random.default_rng(seed)
    states = forecaster.analogs
    mean = states.mean(axis=0) if initial_mean is None else np.asarray(initial_mean, float)
    cov = np.atleast_2d(np.cov(states.T)) if initial_cov is None else np.asarray(initial_cov, float)
    E0 = _gaussian_ensemble(mean, cov, int(n_members), rng)
    q_std = np.sqrt(Q)

    def forecast(E: np.ndarray) -> np.ndarray:
        out = forecaster(E, rng)
        if q_std > 0:
            out += q_std * rng.standard_normal(out.shape)
        return out

    smoothed, _ = ensemble_kalman_smoother(forecast, E0, observations, observed, R, rng)
    return smoothed


def nearest_neighbour_fill(
    observations: np.ndarray, catalog_states: np.ndarray, observed_mask: Optional[np.ndarray] = None
) -> np.ndarray:
    """Naive nearest-neighbour (NNN) interpolation of missing values (Table 2's NNN).

    At each time step, the catalog state nearest (Euclidean) to the observed components of
    that step, on those components only, supplies the missing components; observed values are
    kept as they are. A step with nothing observed carries the previous estimate (the catalog
    mean before the first observed step).

    Parameters
    ----------
    observations : (T, d) array
        NaN marks missing values (unless ``observed_mask`` says otherwise).
    catalog_states : (M, d) array
        Catalog states in the same units as the observations.
    observed_mask : (T, d) bool array, optional
        True where a value is observed; default ``~isnan(observations)``.

    Returns
    -------
    (T, d) array without NaN.
    """
    from scipy.spatial import cKDTree

    obs = np.asarray(observations, dtype=float)
    cat = np.asarray(catalog_states, dtype=float)
    if obs.ndim != 2 or cat.ndim != 2 or obs.shape[1] != cat.shape[1] or cat.shape[0] < 1:
        raise ValueError(
            f"indoorloc: arguments 'observations' (T, d) and 'catalog_states' (M, d) disagree: "
            f"{obs.shape} and {cat.shape}"
        )
    mask = ~np.isnan(obs) if observed_mask is None else np.asarray(observed_mask, dtype=bool)
    if mask.shape != obs.shape:
        raise ValueError(f"indoorloc: argument 'observed_mask': expected shape {obs.shape}, got {mask.shape}")
    if np.any(~np.isfinite(obs[mask])):
        raise ValueError("indoorloc: argument 'observations': observed values must be finite")
    T, d = obs.shape
    out = np.where(mask, obs, np.nan)
    nearest = np.full(T, -1)
    patterns, inverse = np.unique(mask, axis=0, return_inverse=True)
    inverse = np.asarray(inverse).ravel()
    for p, pattern in enumerate(patterns):
        if not pattern.any():
            continue
        rows = np.flatnonzero(inverse == p)
        _, nearest[rows] = cKDTree(cat[:, pattern]).query(obs[np.ix_(rows, pattern)], k=1)
    previous = cat.mean(axis=0)
    for t in range(T):
        estimate = cat[nearest[t]] if nearest[t] >= 0 else previous
        out[t] = np.where(mask[t], obs[t], estimate)
        previous = out[t]
    return out
