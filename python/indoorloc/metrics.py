"""Error metrics shared by every subsystem's experiments (positions in metres)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np


@dataclass(frozen=True)
class ErrorStats:
    """Summary of a set of position errors [m]."""

    count: int
    mean: float
    median: float
    p75: float
    p90: float
    rmse: float
    max: float

    def as_dict(self) -> dict:
        return asdict(self)


def position_errors(estimated_m: np.ndarray, truth_m: np.ndarray) -> np.ndarray:
    """Euclidean errors [m] between (N, d) estimated and true positions, shape (N,)."""
    est = np.asarray(estimated_m, dtype=float)
    ref = np.asarray(truth_m, dtype=float)
    if est.shape != ref.shape:
        raise ValueError(
            f"indoorloc: argument 'estimated_m': shape {est.shape} differs from truth_m {ref.shape}"
        )
    if est.ndim != 2:
        raise ValueError(f"indoorloc: argument 'estimated_m': expected a 2-D array, got {est.ndim}-D")
    return np.linalg.norm(est - ref, axis=1)


def error_stats(errors_m: np.ndarray) -> ErrorStats:
    """Mean, median, 75th/90th percentile, RMSE and max of errors [m]. NaN is rejected."""
    e = np.asarray(errors_m, dtype=float).ravel()
    if e.size == 0:
        raise ValueError("indoorloc: argument 'errors_m': is empty")
    if not np.all(np.isfinite(e)):
        raise ValueError("indoorloc: argument 'errors_m': contains NaN or inf")
    return ErrorStats(
        count=int(e.size),
        mean=float(e.mean()),
        median=float(np.median(e)),
        p75=float(np.percentile(e, 75)),
        p90=float(np.percentile(e, 90)),
        rmse=float(np.sqrt(np.mean(e**2))),
        max=float(e.max()),
    )


def bootstrap_interval(
    values: np.ndarray, statistic=np.mean, n_boot: int = 2000, level: float = 0.95, seed: int = 0
) -> tuple[float, float]:
    """Percentile bootstrap interval of ``statistic(values)`` at confidence ``level``."""
    v = np.asarray(values, dtype=float).ravel()
    if v.size == 0:
        raise ValueError("indoorloc: argument 'values': is empty")
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, v.size, size=(n_boot, v.size))
    stats = np.apply_along_axis(statistic, 1, v[idx])
    alpha = (1.0 - level) / 2.0
    return float(np.quantile(stats, alpha)), float(np.quantile(stats, 1.0 - alpha))


def empirical_cdf(errors_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sorted errors and their cumulative probabilities (for CDF plots)."""
    e = np.sort(np.asarray(errors_m, dtype=float).ravel())
    return e, np.arange(1, e.size + 1) / e.size
