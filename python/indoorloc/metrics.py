"""Error metrics shared by every subsystem's experiments (positions in metres)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from indoorloc.validate import integer, real_array, real_scalar

# Errors and positions beyond this [m] square to inf in the RMSE: not a measurement.
_MAX_ABS_M = 1e100


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
    est = real_array(estimated_m, "estimated_m", max_abs=_MAX_ABS_M)
    ref = real_array(truth_m, "truth_m", max_abs=_MAX_ABS_M)
    if est.shape != ref.shape:
        raise ValueError(
            f"indoorloc: argument 'estimated_m': shape {est.shape} differs from truth_m {ref.shape}"
        )
    if est.ndim != 2:
        raise ValueError(f"indoorloc: argument 'estimated_m': expected a 2-D array, got {est.ndim}-D")
    return np.linalg.norm(est - ref, axis=1)


def error_stats(errors_m: np.ndarray) -> ErrorStats:
    """Mean, median, 75th/90th percentile, RMSE and max of errors [m]. NaN is rejected."""
    e = real_array(errors_m, "errors_m", max_abs=_MAX_ABS_M).ravel()
    if e.size == 0:
        raise ValueError("indoorloc: argument 'errors_m': is empty")
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
    v = real_array(values, "values", max_abs=_MAX_ABS_M).ravel()
    if v.size == 0:
        raise ValueError("indoorloc: argument 'values': is empty")
    n_boot = integer(n_boot, "n_boot", lo=1, hi=10**6)
    level = real_scalar(level, "level", lo=0.0, hi=1.0)
    seed = integer(seed, "seed", lo=0, hi=2**64 - 1)
    # n_boot x N indices are drawn at once: bound the memory.
    if n_boot * v.size > 10**8:
        raise ValueError(f"indoorloc: argument 'n_boot': n_boot x len(values) = {n_boot * v.size} "
                         f"draws exceed the limit of 1e8 (about 0.8 GB)")
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, v.size, size=(n_boot, v.size))
    stats = np.apply_along_axis(statistic, 1, v[idx])
    alpha = (1.0 - level) / 2.0
    return float(np.quantile(stats, alpha)), float(np.quantile(stats, 1.0 - alpha))


def empirical_cdf(errors_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sorted errors and their cumulative probabilities (for CDF plots)."""
    e = np.sort(real_array(errors_m, "errors_m").ravel())
    return e, np.arange(1, e.size + 1) / e.size
