"""The grid tracker: exact filter and forward-backward smoother of a walk on floor cells
(``cpp/include/indoorloc/fusion/grid_tracker.h``; docs/fusion.md, "Grid tracker").

Why beside the particle tracker: with an unknown start the posterior over a building is
multi-modal for the first tens of seconds (a WiFi fix's components are spread over the mall). A
grid keeps every mode until motion, walls and later fixes resolve it; its smoother is exact and
its spread is the posterior's own, so the returned covariance can be trusted.

Example::

    from indoorloc import fusion
    tracker = fusion.GridTracker(plan, fusion.GridTrackerOptions(cell_size_m=1.0))
    result = fusion.track_grid(tracker, steps, fixes=fixes)          # unknown start, smoothed
    track_m, cov_m2 = result["smoothed_m"], result["smoothed_covariance_m2"]
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from indoorloc._core.fusion import GridFilterEstimate, GridFilterSession, GridTracker, GridTrackerOptions, GridTrackSummary


def track_grid(tracker: GridTracker, steps, *, fixes=None, start: Optional[dict] = None, smooth: bool = True,
               filtered: bool = True) -> dict:
    """Track one walk with a :class:`GridTracker` (C++, GIL released).

    Parameters
    ----------
    tracker : GridTracker
        Built once per plan and options.
    steps : indoorloc.fusion.Steps
        Detected steps: times [s], displacements [m] in the PDR frame, covariances [m²].
    fixes : indoorloc.fusion.Fixes or None
        Position fixes (Gaussian mixtures with the options' outlier floor).
    start : dict or None
        None: unknown start (uniform over every floor's walkable area, heading-offset prior
        centred on 0). Known: ``{"position_m": (2,), "floor": int, "heading_offset_rad": float,
        "time_s": float}`` (the offset prior is centred on its heading offset).
    smooth : bool
        Also run the backward pass.
    filtered : bool
        With ``smooth``: False skips the causal filter's per-step position estimates (for a
        caller that reads the smoother only; about a quarter of the run with spatial medians):
        ``mean_m``, ``covariance_m2``, ``posterior_covariance_m2`` and ``fix_distance_m`` are NaN
        after a known start, ``median_m`` is absent; everything else is bit for bit the same.

    Returns
    -------
    dict
        Per step (M): ``times_s``, ``mean_m`` (M, 2) and ``covariance_m2`` (M, 3) of the causal
        filter [m, m²], ``floor_probabilities`` (M, F), ``heading_offset_rad`` (M,); with
        ``smooth`` ``smoothed_m`` (M, 2) and ``smoothed_covariance_m2`` (M, 3); given the whole
        walk ``smoothed_floor_probabilities`` (F,), ``heading_offset_bins_rad`` and
        ``heading_offset_probabilities`` (H,), ``scale_bins`` and ``scale_probabilities`` (S,),
        ``walk_heading_offset_rad``, ``walk_heading_offset_sd_rad``, ``walk_scale``; ``summary``.
    """
    if not isinstance(tracker, GridTracker):
        raise TypeError(f"indoorloc: argument 'tracker': expected a GridTracker, got {type(tracker).__name__}")
    # Steps and Fixes by their fields (the fusion package's own classes, or look-alikes).
    if not all(hasattr(steps, a) for a in ("times_s", "displacements_m", "covariances_m2")):
        raise TypeError(f"indoorloc: argument 'steps': expected indoorloc.fusion.Steps, got {type(steps).__name__}")
    if fixes is not None and not hasattr(fixes, "as_arrays"):
        raise TypeError(f"indoorloc: argument 'fixes': expected None or indoorloc.fusion.Fixes, "
                        f"got {type(fixes).__name__}")
    arrays = None if fixes is None or len(fixes) == 0 else fixes.as_arrays()
    return tracker.run(steps.times_s, steps.displacements_m, steps.covariances_m2, arrays, start, bool(smooth),
                       bool(filtered))


def region95_contains(means_m: np.ndarray, covariances_m2: np.ndarray, truth_m: np.ndarray) -> np.ndarray:
    """Whether each truth (N, 2) [m] lies in the 95 % ellipse of the Gaussian with the given means
    (N, 2) [m] and covariances (N, 3) = (xx, xy, yy) [m²]: the squared Mahalanobis distance is at
    most 5.991 (the chi-square 95 % point with 2 degrees of freedom)."""
    d = np.asarray(truth_m, float) - np.asarray(means_m, float)
    c = np.asarray(covariances_m2, float)
    det = c[:, 0] * c[:, 2] - c[:, 1] ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        m2 = (c[:, 2] * d[:, 0] ** 2 - 2.0 * c[:, 1] * d[:, 0] * d[:, 1] + c[:, 0] * d[:, 1] ** 2) / det
    return np.where(det > 0, m2 <= 5.991, False)


__all__ = ["GridFilterEstimate", "GridFilterSession", "GridTracker", "GridTrackerOptions", "GridTrackSummary",
           "region95_contains", "track_grid"]
