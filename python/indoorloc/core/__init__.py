"""Shared core: seeded random streams, log-space weights and resampling (C++).

Every function validates its arguments in C++ and raises ``ValueError`` naming the argument
(e.g. ``indoorloc: argument 'log_weights': entry 3 is NaN``). Inputs are never modified.

Examples
--------
>>> import numpy as np, indoorloc
>>> lw = np.log([0.1, 0.2, 0.7])
>>> indoorloc.core.effective_sample_size(lw)  # doctest: +ELLIPSIS
1.851...
>>> indoorloc.core.resample(lw, scheme="systematic", rng=42).shape
(3,)
"""

from indoorloc._core.core import (
    RandomStream,
    ResamplingOptions,
    ResamplingSummary,
    derive_seed,
    effective_sample_size,
    log_sum_exp,
    normalize_log_weights,
    offspring_counts,
    resample,
    resample_if_needed,
)

#: Names accepted by ``resample(..., scheme=...)``.
RESAMPLING_SCHEMES = ("multinomial", "stratified", "systematic", "residual")

__all__ = [
    "RESAMPLING_SCHEMES",
    "RandomStream",
    "ResamplingOptions",
    "ResamplingSummary",
    "derive_seed",
    "effective_sample_size",
    "log_sum_exp",
    "normalize_log_weights",
    "offspring_counts",
    "resample",
    "resample_if_needed",
]
