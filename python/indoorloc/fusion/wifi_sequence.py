"""WiFi-only sequence tracking: the forward-backward (hidden Markov) smoother of a walk's WiFi
fixes on the floor's walkable grid, with a random-walk motion prior and no PDR or IMU
(docs/fusion_real.md, "WiFi only: the sequence of fixes").

Why: a single fix is the weighted centre of one scan window's best fingerprint matches; scan
after scan, the right place is often among a fix's components while the centre is not. A walker
moves at most a few metres per second, so the fixes before and after a scan, and the walls,
decide between the components. This is the standard WiFi-only tracker (an HMM over positions with
a walking-speed motion model); it uses the scan sequence and the scans' timestamps (and, when
smoothed, the scans after the estimate's time), the floor plan and the fingerprint database, and
nothing from the phone's motion sensors.

It runs on the grid tracker (:class:`indoorloc.fusion.GridTracker`, C++): "steps" of zero
displacement every ``tick_s`` seconds whose covariance is the random walk's, (``speed_sd`` ² ·
``tick_s``) I, one heading-offset layer, one scale layer.

Example::

    from indoorloc.fusion import wifi_sequence
    tracker = wifi_sequence.sequence_tracker(plan, wifi_sequence.SequenceSettings(), database)
    track = wifi_sequence.track_fixes(tracker, fixes, 0.0, walk.duration_s, wifi_sequence.SequenceSettings())
    xy = wifi_sequence.at_times(track, waypoint_times_s)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Dict, Optional

import numpy as np

from indoorloc.fusion.grid import GridTracker, GridTrackerOptions, track_grid
from indoorloc.fusion.steps import Steps


@dataclass(frozen=True)
class SequenceSettings:
    """Settings of the WiFi-only sequence tracker. Defaults: the choice of leave-one-floor-out
    cross-validation over the six floors of the competition mall (docs/fusion_real.md)."""

    tick_s: float = 1.0                  #: time between motion steps [s] (fixed: below the fixes' spacing)
    #: Random-walk sd per √s [m/√s] (LOFO over {1, 2, 3}, then {1.5, 2}: 2 on every floor).
    speed_sd_m_per_sqrt_s: float = 2.0
    fix_tempering: float = 1.0           #: τ of the fixes (LOFO over {0.25, 0.5, 1}: 1 on every floor)
    #: ε of the fixes (LOFO, final grid {0.001, 0.01}: 0.001 on every floor, 0.06 m ahead pooled).
    fix_outlier_probability: float = 0.001
    #: Each fix component's sd multiplied by this: the matcher's sd is calibrated for a single
    #: fix's 95 % region to hold the truth ~90 % of the time; in a sequence, the motion prior and
    #: the neighbouring fixes resolve the mixture, and sharper components pay (LOFO, final grid
    #: {0.35, 0.5}: 0.35 on every floor; an earlier grid with β = 0.5 preferred 0.5 to 0.25).
    fix_sd_scale: float = 0.35
    #: λ per step outside walkable space (-inf: hard walls; LOFO over {0, -1, -3} with β 0.15-0.35:
    #: -1 on every floor, the fused tracker's).
    wall_log_penalty: float = -1.0
    #: β of the survey-anchored fixes (GridTrackerOptions.fix_survey_distance_factor; 1: off).
    #: LOFO, final grid {0.5, 0.25, 0.15, 0}: 0.15 on five of six floors, 0.25 with F4 held out.
    #: Smaller than the fused tracker's 0.75: without PDR nothing else carries the walker beyond
    #: the survey.
    fix_survey_distance_factor: float = 0.15
    #: Cells within this distance [m] of a survey position pay no wall penalty
    #: (GridTrackerOptions.survey_walkable_radius_m; 0: the plan as drawn). LOFO over {0, 1, 2}:
    #: 0 on all six floors and four held-out floors (the fused tracker's 0.75 helps walks that
    #: follow the survey step by step; a random walk does not).
    survey_walkable_radius_m: float = 0.0
    #: Grid cell [m] (fixed in advance, not tuned: a tenth of the fixes' typical error, and 4x
    #: fewer cells than the fused tracker's 1 m, which the study's grid could not afford).
    cell_size_m: float = 2.0
    #: "mean" or "median" (spatial median) of the posterior (LOFO: "mean" on every floor, 0.1 m ahead).
    point_estimate: str = "mean"
    smooth: bool = True                  #: forward-backward (whole walk) or the causal filter

    def validate(self) -> None:
        """ValueError naming the field for a setting out of range."""
        checks = {
            "tick_s": self.tick_s > 0 and math.isfinite(self.tick_s),
            "speed_sd_m_per_sqrt_s": self.speed_sd_m_per_sqrt_s > 0 and math.isfinite(self.speed_sd_m_per_sqrt_s),
            "fix_tempering": 0 < self.fix_tempering <= 1,
            "fix_outlier_probability": 0 < self.fix_outlier_probability < 1,
            "fix_sd_scale": self.fix_sd_scale > 0 and math.isfinite(self.fix_sd_scale),
            "wall_log_penalty": self.wall_log_penalty <= 0 and not math.isnan(self.wall_log_penalty),
            "fix_survey_distance_factor": 0 <= self.fix_survey_distance_factor <= 1,
            "survey_walkable_radius_m": 0 <= self.survey_walkable_radius_m <= 100,
            "cell_size_m": self.cell_size_m > 0 and math.isfinite(self.cell_size_m),
            "point_estimate": self.point_estimate in ("mean", "median"),
        }
        for name, ok in checks.items():
            if not ok:
                raise ValueError(f"indoorloc: SequenceSettings.{name}: invalid value {getattr(self, name)!r}")


def grid_options(settings: SequenceSettings, base: Optional[GridTrackerOptions] = None) -> GridTrackerOptions:
    """The grid tracker's options for the sequence tracker: one offset and one scale layer, no
    process noise beyond the random walk's, the settings' fixes, walls and anchoring."""
    settings.validate()
    base = base if base is not None else GridTrackerOptions()
    return base.replace(cell_size_m=settings.cell_size_m, heading_offset_bins=1, heading_offset_sd_rad=0.0,
                        scale_bins=1, position_noise_m=0.0, wall_log_penalty=settings.wall_log_penalty,
                        fix_outlier_probability=settings.fix_outlier_probability,
                        fix_tempering=settings.fix_tempering,
                        fix_survey_distance_factor=settings.fix_survey_distance_factor,
                        survey_walkable_radius_m=settings.survey_walkable_radius_m,
                        spatial_median=settings.point_estimate == "median")


def sequence_tracker(plan: Any, settings: SequenceSettings, database: Any = None,
                     base: Optional[GridTrackerOptions] = None) -> GridTracker:
    """A grid tracker on ``plan`` for :func:`track_fixes`; with a fingerprint ``database`` its
    fixes are anchored to the database's survey positions (``fix_survey_distance_factor``)."""
    from indoorloc.fusion import site_model

    tracker = GridTracker(plan, grid_options(settings, base))
    return tracker if database is None else site_model.survey_anchored(tracker, plan, database)


def random_walk_steps(t_start_s: float, t_end_s: float, settings: SequenceSettings) -> Steps:
    """Zero-displacement steps every ``tick_s`` from t_start_s to t_end_s [s] (at least two),
    each with the random walk's covariance (speed_sd² · tick_s) I [m²]."""
    if not (math.isfinite(t_start_s) and math.isfinite(t_end_s)) or t_end_s < t_start_s:
        raise ValueError(f"indoorloc: arguments 't_start_s', 't_end_s': need finite t_start_s <= t_end_s, "
                         f"got {t_start_s}, {t_end_s}")
    n = max(2, int(math.ceil((t_end_s - t_start_s) / settings.tick_s)) + 1)
    times = t_start_s + settings.tick_s * np.arange(n)
    var = settings.speed_sd_m_per_sqrt_s ** 2 * settings.tick_s
    cov = np.tile([var, 0.0, var], (n, 1))
    return Steps(times, np.zeros((n, 2)), cov)


def track_fixes(tracker: GridTracker, fixes: Any, t_start_s: float, t_end_s: float,
                settings: SequenceSettings) -> Dict[str, np.ndarray]:
    """The walk's position [m] every ``tick_s`` from t_start_s to t_end_s [s] from its WiFi fixes
    alone: ``{"times_s" (M,), "position_m" (M, 2), "covariance_m2" (M, 3)}`` (smoothed or filtered
    per ``settings.smooth``, the point estimate per ``settings.point_estimate``; also ``mean_m``
    and, when the tracker computes it, ``median_m``, the two point estimates). NaN positions when
    there is no fix."""
    steps = random_walk_steps(t_start_s, t_end_s, settings)
    if fixes is None or len(fixes) == 0:
        n = len(steps)
        nan = np.full((n, 2), np.nan)
        return {"times_s": steps.times_s, "position_m": nan, "mean_m": nan, "median_m": nan,
                "covariance_m2": np.full((n, 3), np.nan)}
    if settings.fix_sd_scale != 1.0:
        fixes = replace(fixes, sds_m=np.asarray(fixes.sds_m) * settings.fix_sd_scale)
    r = track_grid(tracker, steps, fixes=fixes, start=None, smooth=settings.smooth)
    prefix = "smoothed_" if settings.smooth else ""
    mean_key, median_key = ("smoothed_m", "smoothed_median_m") if settings.smooth else ("mean_m", "median_m")
    out = {"times_s": np.asarray(r["times_s"]), "mean_m": np.asarray(r[mean_key]),
           "covariance_m2": np.asarray(r[prefix + "covariance_m2"])}
    if median_key in r:
        out["median_m"] = np.asarray(r[median_key])
    if settings.point_estimate == "median" and "median_m" not in out:
        raise ValueError("indoorloc: argument 'tracker': its options do not compute the spatial median "
                         "(point_estimate 'median' needs a tracker from sequence_tracker with these settings)")
    out["position_m"] = out["median_m"] if settings.point_estimate == "median" else out["mean_m"]
    return out


def at_times(track: Dict[str, np.ndarray], times_s: np.ndarray, key: str = "position_m") -> np.ndarray:
    """The track's positions (``key``: ``position_m``, ``mean_m`` or ``median_m``) interpolated
    linearly at times_s (W,) [s]: (W, 2) [m]."""
    t = np.asarray(times_s, float)
    p = track[key]
    return np.stack([np.interp(t, track["times_s"], p[:, 0]), np.interp(t, track["times_s"], p[:, 1])], axis=1)


__all__ = ["SequenceSettings", "at_times", "grid_options", "random_walk_steps", "sequence_tracker", "track_fixes"]
