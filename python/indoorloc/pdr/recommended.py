"""The recommended foot-mounted PDR pipeline: stance detection, ZUPT EKF + RTS smoother, strides,
and a health check that flags every physically implausible result.

:func:`run_recommended` on an :class:`~indoorloc.io.ImuRecording`:

1. :func:`detect_stance`: the SHOE statistic (window and noise sds :data:`SHOE_WINDOW`,
   :data:`SHOE_SIGMA_ACC_MPS2`, :data:`SHOE_SIGMA_GYRO_RADPS`) with the swing guard of
   :func:`indoorloc.pdr.zero_velocity` (:data:`ZUPT_DETECTOR`): the threshold climbs a ladder until
   the gait looks whole, never onto a rung whose swings are shorter than a human swing, and a
   low-motion rule for slow, flat walks (docs/pdr.md, "Low-motion walks");
2. :func:`indoorloc.pdr.zupt_ekf` with the RTS smoother, and :func:`indoorloc.pdr.count_strides`;
3. the health check: the EKF's own (divergence, missing stances, stretched paths) plus
   :func:`gait_plausibility`, which compares the result with the gait the IMU shows (swing
   durations, stride lengths, path length against the step rhythm of the gyroscope). Its limits
   are :data:`HEALTH_LIMITS` (calibrated in :mod:`indoorloc.experiments.pdr_low_motion`;
   docs/errors.md, "implausible").

Every constant was chosen by cross-validation over the PyShoe Vicon trials and synthetic gaits
(docs/pdr.md). Moved here from ``indoorloc.experiments.pdr_evaluate`` (docs/api_changes.md).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Dict, List, Optional

import numpy as np

from indoorloc._core import pdr as _pdr
from indoorloc.pdr.metrics import path_length

if TYPE_CHECKING:  # `import indoorloc` loads no file-format module (CONVENTIONS rule 11)
    from indoorloc.io.pdr_datasets import ImuRecording

__all__ = ["DEFAULT_METHOD", "HEALTH_LIMITS", "SHOE_SIGMA_ACC_MPS2", "SHOE_SIGMA_GYRO_RADPS", "SHOE_WINDOW",
           "MIN_SWING_SHARE", "SPLIT_SWING_SHARE", "STANCE_CORE_DECADES", "ZUPT_DETECTOR", "detect_stance",
           "LOW_MOTION_FALLBACK", "bimodal_threshold", "drop_mid_swing_stances", "onset_speed_share", "stance_cores",
           "gait_evidence", "gait_plausibility", "run_recommended", "stance_motion_ratio", "swing_floor"]

#: SHOE window [samples] and noise settings (the statistic's scale depends on them: T ~ 1/sigma^2).
SHOE_WINDOW = 5
SHOE_SIGMA_ACC_MPS2 = 0.01
SHOE_SIGMA_GYRO_RADPS = 0.1 * math.pi / 180.0

#: Settings of :func:`indoorloc.pdr.zero_velocity` used by :func:`detect_stance` for every sensor
#: (one parameter set; the swing guard adapts the threshold per recording). Chosen by
#: leave-one-trial-out cross-validation over the 21 PyShoe trials (``python -m
#: indoorloc.experiments.pdr_zupt_cv``; docs/pdr.md "Zero-velocity detection"): threshold 1e4
#: (grid 1e4-10^4.5), max_swing_s 2.0 (grid 1.25-3; 1.5-3 tie) and max_swing_ratio 1.5 (grid
#: 1.3-2; 1.5-2 tie). The ladder step (0.25 decade), the cap (1e7) and the stance floor (15 %)
#: were fixed beforehand. min_plausible_swing_s (0.2 s) and low_motion_min_stance_s (0.08 s):
#: leave-one-recording-out CV over the 21 trials and 12 synthetic slow low-motion gaits
#: (``python -m indoorloc.experiments.pdr_low_motion``; docs/pdr.md "Low-motion walks"). With the
#: rhythm floor of :data:`MIN_SWING_SHARE` on, min_plausible_swing_s 0.15-0.35 s tie in that CV
#: (the folds take the first, 0.15); 0.2 s is kept: it is the floor when the IMU shows no rhythm.
ZUPT_DETECTOR = {"rule": "swing_guard", "threshold": 1e4, "max_swing_s": 2.0, "max_swing_ratio": 1.5,
                 "ladder_step_decades": 0.25, "min_stance_share": 0.15, "max_threshold": 1e7,
                 "min_plausible_swing_s": 0.2, "low_motion_min_stance_s": 0.08}

#: Name of the recommended method in ``indoorloc pdr evaluate --json`` (``default_method``).
DEFAULT_METHOD = "zupt_rts_swing_guard"

#: Limits of :func:`gait_plausibility` (they flag, they never change the estimate). Calibrated in
#: :mod:`indoorloc.experiments.pdr_low_motion` (the table is in docs/errors.md): no good run of
#: the shared recordings is flagged, every synthetic failure is.
#: - min_swing_s: a median swing shorter than this is no human gait [s] (good runs >= 0.66 s);
#: - min_stride_m: a median stride shorter than this while the IMU shows walking [m];
#: - min_path_per_rhythm_stride_m: path length / strides of the gyroscope's rhythm [m];
#: - min_stride_count_ratio: detected strides / rhythm strides;
#: - max_stance_motion_ratio: the 90th percentile of ||f| - g| over the samples the EKF holds
#:   still (``zupt_stance``), divided by the walk's (95th percentile over all samples), while
#:   walking. A foot at rest reads sensor noise; when the threshold lets the slow ends of swings
#:   into stance the ratio climbs (the path then comes out uniformly short). 0.12: the least grid
#:   value above every good run of the other recordings, leave one recording out (32 of 33
#:   folds, on the stance before the stance core; with the core the same rule gives 0.09, kept
#:   at 0.12: docs/errors.md);
#: - walking_energy_mps2: the IMU "shows walking" when the 95th percentile of ||f| - g| exceeds
#:   this [m/s^2] and the rhythm's autocorrelation exceeds walking_rhythm_strength.
#: - max_onset_speed_share: the speed the filter had integrated when stance began (median over
#:   the stances, ``speed_at_stance_median_mps``) over the mean swing speed (median stride /
#:   median swing), while walking: a foot at rest does not move; a large share means "stance"
#:   was declared while the foot still moved (a blip in a swing, a threshold far too high) and
#:   that stride was cut short. 0.65: the least grid value (0.05 steps) above every good run of
#:   the other recordings, leave one recording out (27 of 28 folds; docs/errors.md);
HEALTH_LIMITS = {"min_swing_s": 0.15, "min_stride_m": 0.1, "min_path_per_rhythm_stride_m": 0.1,
                 "min_stride_count_ratio": 0.5, "max_stance_motion_ratio": 0.12, "max_onset_speed_share": 0.65,
                 "walking_energy_mps2": 0.3, "walking_rhythm_strength": 0.15}

_GRAVITY_MPS2 = 9.81

#: Keywords of :func:`detect_stance` that are not options of :func:`indoorloc.pdr.zero_velocity`.
_PIPELINE_KEYWORDS = ("min_swing_share", "split_swing_share", "stance_core_decades", "low_motion_fallback")


#: The least share of the gyroscope's stride period a swing may take (:func:`detect_stance`): a
#: rung of the swing guard's ladder whose median swing is shorter than this times the period is
#: refused, as are rungs shorter than ``min_plausible_swing_s``. A human swing is about 40 % of
#: the gait cycle (more when running); SHOE's swings on the PyShoe trials are 50-92 % of the
#: rhythm's period. Chosen by leave-one-recording-out cross-validation over the PyShoe trials,
#: the synthetic slow shuffles and a sweep of synthetic gaits (speed, cadence, stance stillness,
#: sensor noise): ``python -m indoorloc.experiments.pdr_gait_sweep`` chose 0.25 (docs/pdr.md,
#: "Swings against the step rhythm"); re-chosen with the stance rules below and together with
#: :data:`LOW_MOTION_FALLBACK` (``--study low_motion_fallback``): 0.2 in 356 of 357 folds.
MIN_SWING_SHARE = 0.2

#: A stance run with less motion than this times the swing floor (:func:`swing_floor`) on both
#: sides, and shorter than that motion, is a mid-swing blip of SHOE and is removed
#: (:func:`drop_mid_swing_stances`). Chosen by leave-one-recording-out cross-validation over the
#: PyShoe trials, the synthetic slow shuffles and the gait sweep (``python -m
#: indoorloc.experiments.pdr_gait_sweep --study stance_rules``: 1.5 in all 357 folds; docs/pdr.md).
SPLIT_SWING_SHARE = 1.5

#: The ZUPT is applied only over the core of each stance phase: from its first to its last
#: sample whose SHOE statistic is below the threshold used / 10^STANCE_CORE_DECADES
#: (:func:`stance_cores`). A threshold raised for a trembling stance also admits the slow ends of
#: the swings; zeroing a foot that still moves makes the filter and the RTS smoother take that
#: speed for integration error and shorten the whole stride. Chosen with
#: :data:`SPLIT_SWING_SHARE` by the same cross-validation (1.0 in all 357 folds).
STANCE_CORE_DECADES = 1.0

#: When the swing guard finds no rung with a plausible gait (``guard_satisfied`` false), the
#: threshold used: ``"most_regular"``, the detector's own choice (the plausible rung with the
#: most regular swings), or ``"bimodal_split"``, :func:`bimodal_threshold` of the recording's
#: SHOE statistic. Chosen with :data:`MIN_SWING_SHARE` by the same cross-validation (``--study
#: low_motion_fallback``: the bimodal split in all 357 folds; docs/pdr.md, "Mid-swing blips").
LOW_MOTION_FALLBACK = "bimodal_split"
_FALLBACKS = ("most_regular", "bimodal_split")


def swing_floor(evidence: Dict[str, float], min_plausible_swing_s: float = ZUPT_DETECTOR["min_plausible_swing_s"],
                min_swing_share: float = MIN_SWING_SHARE, max_swing_s: float = ZUPT_DETECTOR["max_swing_s"]) -> float:
    """The least median swing [s] a rung of the swing guard's ladder may have: ``min_plausible_swing_s``
    or, when the IMU shows walking (``evidence``: :func:`gait_evidence`; :data:`HEALTH_LIMITS`
    ``walking_*``), ``min_swing_share`` times the gyroscope's stride period if that is longer (at
    most half of ``max_swing_s``, which the detector's options require above it). A rung whose
    swings are a small fraction of the step rhythm has traded the walk for a standstill."""
    if not (math.isfinite(min_swing_share) and 0.0 <= min_swing_share < 1.0):
        raise ValueError(f"indoorloc: argument 'min_swing_share': must be in [0, 1), got {min_swing_share!r}")
    walking = (evidence["energy_mps2"] >= HEALTH_LIMITS["walking_energy_mps2"]
               and evidence["strength"] >= HEALTH_LIMITS["walking_rhythm_strength"]
               and math.isfinite(evidence["period_s"]))
    floor = float(min_plausible_swing_s)
    if walking and min_swing_share > 0.0:
        floor = max(floor, min(min_swing_share * float(evidence["period_s"]), 0.5 * float(max_swing_s)))
    return floor


def drop_mid_swing_stances(stance: np.ndarray, rate_hz: float, max_piece_s: float):
    """Stance runs that split a swing, removed: SHOE's mid-swing blind spot (the angular rate
    crosses zero while ||f|| is near g) can call a few samples in the middle of a swing stance,
    and the EKF then zeroes a foot moving at up to 1-2 m/s and loses most of that stride. A run
    is such a blip when the motion on both sides is shorter than ``max_piece_s`` [s] (neither
    side is a whole swing) and the run is shorter than the motion on either side (a stance
    fragment between two tremor flicks, or a stance longer than the motion around it, is kept).
    The first and last runs (the rests) are always kept. ``stance`` (N,) bool is not modified.
    Returns ``(stance without the blips (N,) bool, number of runs removed)``."""
    if not (math.isfinite(rate_hz) and rate_hz > 0):
        raise ValueError(f"indoorloc: argument 'rate_hz': must be a positive finite rate in Hz, got {rate_hz!r}")
    if not (math.isfinite(max_piece_s) and max_piece_s >= 0):
        raise ValueError(f"indoorloc: argument 'max_piece_s': must be a finite duration >= 0 s, got {max_piece_s!r}")
    flags = np.asarray(stance, dtype=bool)
    edges = np.diff(np.concatenate(([0], flags.astype(np.int8), [0])))
    begin, end = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    out = flags.copy()
    if begin.size < 3:
        return out, 0
    limit = max_piece_s * rate_hz
    before = begin[1:-1] - end[:-2]           # motion samples before each inner run
    after = begin[2:] - end[1:-1]             # ... and after it
    length = end[1:-1] - begin[1:-1]
    blip = (before < limit) & (after < limit) & (length < np.minimum(before, after))
    for b, e in zip(begin[1:-1][blip], end[1:-1][blip]):
        out[b:e] = False
    return out, int(blip.sum())


def stance_cores(stance: np.ndarray, statistic: np.ndarray, core_threshold: float) -> np.ndarray:
    """Each run of ``stance`` (N,) bool shrunk to the span from its first to its last sample whose
    ``statistic`` (N,) is below ``core_threshold`` (runs with no such sample are kept whole).
    Tremor inside the span stays stance; only the run's ends, where the foot was still moving
    slowly, are given up. Returns the core stance (N,) bool; the inputs are not modified."""
    flags = np.asarray(stance, dtype=bool)
    stat = np.asarray(statistic, dtype=float)
    if stat.shape != flags.shape:
        raise ValueError(f"indoorloc: argument 'statistic': shape {stat.shape} differs from the stance's {flags.shape}")
    if not core_threshold > 0:
        raise ValueError(f"indoorloc: argument 'core_threshold': must be > 0, got {core_threshold!r}")
    edges = np.diff(np.concatenate(([0], flags.astype(np.int8), [0])))
    out = flags.copy()
    for b, e in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
        below = np.flatnonzero(stat[b:e] < core_threshold)
        if below.size:
            out[b:b + below[0]] = False
            out[b + below[-1] + 1:e] = False
    return out


def bimodal_threshold(statistic: np.ndarray, bins: int = 200) -> float:
    """The statistic's own split between rest and motion: Otsu's threshold (the cut that
    maximises the between-class variance) of log10 of the SHOE statistic (N,) over ``bins``
    histogram bins, returned as a statistic value; NaN when the statistic takes a single value.
    A walk is stance and swing, so log T is bimodal even when no threshold of the ladder gives a
    plausible gait."""
    t = np.asarray(statistic, dtype=float)
    t = t[np.isfinite(t)]
    if t.size < 2:
        return float("nan")
    x = np.log10(np.maximum(t, 1e-3))
    if not x.max() > x.min():
        return float("nan")
    counts, edges = np.histogram(x, bins=bins)
    centres = 0.5 * (edges[:-1] + edges[1:])
    w = counts / counts.sum()
    w0 = np.cumsum(w)[:-1]                       # class "below" holds bins 0..i-1 for cut i = 1..bins-1
    m0 = np.cumsum(w * centres)[:-1]
    total = float((w * centres).sum())
    valid = (w0 > 0) & (w0 < 1)
    between = np.zeros_like(w0)
    between[valid] = (total * w0[valid] - m0[valid]) ** 2 / (w0[valid] * (1.0 - w0[valid]))
    cut = int(np.argmax(between)) + 1
    return float(10.0 ** edges[cut])


def detect_stance(recording: ImuRecording, evidence: Optional[Dict[str, float]] = None,
                  min_swing_share: float = MIN_SWING_SHARE, split_swing_share: float = SPLIT_SWING_SHARE,
                  stance_core_decades: float = STANCE_CORE_DECADES, low_motion_fallback: str = LOW_MOTION_FALLBACK,
                  **overrides: Any) -> Dict[str, Any]:
    """:func:`indoorloc.pdr.zero_velocity` on a recording with :data:`ZUPT_DETECTOR` (keywords
    override it) and the SHOE window and noise sds of this module, then
    :func:`drop_mid_swing_stances` and :func:`stance_cores`. Returns its result as a dict (stance,
    statistic, threshold, guard_raised, guard_satisfied, low_motion_rule, stance fractions,
    report), with ``mid_swing_stances_dropped`` and ``zupt_stance`` (N,) bool: the samples the
    EKF should hold still (the core of each stance phase; ``stance`` itself delimits the strides).

    With the swing guard, the ladder's swing floor is :func:`swing_floor` (``evidence``:
    :func:`gait_evidence` of the recording, computed when None): ``min_swing_share`` of the
    gyroscope's stride period when that is longer than ``min_plausible_swing_s``; 0 turns it off.
    A stance run is a mid-swing blip when the motion on both sides is shorter than
    ``split_swing_share`` times the swing floor (with any rule); 0 turns that off. The stance
    core's threshold is the threshold used / 10^``stance_core_decades``; 0 turns it off. When the
    guard finds no plausible rung, ``low_motion_fallback`` (:data:`LOW_MOTION_FALLBACK`) decides
    the threshold; ``bimodal_split`` in the result says whether :func:`bimodal_threshold` was used."""
    opts = dict(ZUPT_DETECTOR)
    opts.update(overrides)
    if not (math.isfinite(split_swing_share) and split_swing_share >= 0.0):
        raise ValueError(f"indoorloc: argument 'split_swing_share': must be finite and >= 0, got {split_swing_share!r}")
    if not (math.isfinite(stance_core_decades) and stance_core_decades >= 0.0):
        raise ValueError(f"indoorloc: argument 'stance_core_decades': must be finite and >= 0, got {stance_core_decades!r}")
    ev = gait_evidence(recording) if evidence is None else evidence
    floor = swing_floor(ev, float(opts.get("min_plausible_swing_s", ZUPT_DETECTOR["min_plausible_swing_s"])),
                        min_swing_share, float(opts.get("max_swing_s", ZUPT_DETECTOR["max_swing_s"])))
    if low_motion_fallback not in _FALLBACKS:
        raise ValueError(f"indoorloc: argument 'low_motion_fallback': must be one of {_FALLBACKS}, got {low_motion_fallback!r}")
    if opts.get("rule", "swing_guard") == "swing_guard":
        opts["min_plausible_swing_s"] = floor
    options = _pdr.ZeroVelocityOptions(window=SHOE_WINDOW, sigma_acc_mps2=SHOE_SIGMA_ACC_MPS2,
                                       sigma_gyro_radps=SHOE_SIGMA_GYRO_RADPS, **opts)
    det = _pdr.zero_velocity(recording.acc_mps2, recording.gyro_radps, recording.rate_hz, options=options)
    out = {k: det[k] for k in det.keys()}
    out["bimodal_split"] = False
    if (opts.get("rule", "swing_guard") == "swing_guard" and not out["guard_satisfied"]
            and low_motion_fallback == "bimodal_split"):
        split = bimodal_threshold(out["statistic"])
        if math.isfinite(split) and split > 0:
            fixed = options.replace(rule="fixed", threshold=split, max_threshold=10.0 * split)
            again = _pdr.zero_velocity(recording.acc_mps2, recording.gyro_radps, recording.rate_hz, options=fixed)
            for key in ("stance", "threshold", "stance_fraction", "walking_stance_fraction", "report"):
                out[key] = again[key]
            out["bimodal_split"] = True
    out["mid_swing_stances_dropped"] = 0
    if split_swing_share > 0.0:
        out["stance"], out["mid_swing_stances_dropped"] = drop_mid_swing_stances(
            np.asarray(out["stance"], dtype=bool), float(recording.rate_hz), split_swing_share * floor)
    out["zupt_stance"] = (stance_cores(out["stance"], out["statistic"], float(out["threshold"]) / 10.0 ** stance_core_decades)
                          if stance_core_decades > 0.0 else np.asarray(out["stance"], dtype=bool).copy())
    return out


def gait_evidence(recording: ImuRecording, active_radps: float = 1.0, lo_s: float = 0.4,
                  hi_s: float = 2.5) -> Dict[str, float]:
    """What the IMU alone says about the gait, whatever the detector made of it.

    - ``energy_mps2``: 95th percentile of ||f| - g| [m/s^2] (a foot at rest: noise, < 0.1;
      walking: several m/s^2);
    - ``active_s``: time from the first to the last sample whose angular rate exceeds
      ``active_radps`` [s] (a swinging foot turns at 2-10 rad/s);
    - ``period_s`` / ``strength``: the stride period, the lag (``lo_s`` to ``hi_s``) of the highest
      local maximum of the autocorrelation of |omega| over that span, and its normalised height
      (0..1; NaN / 0 when there is no peak);
    - ``rhythm_strides``: ``active_s / period_s`` (0 without a rhythm).
    """
    acc = np.asarray(recording.acc_mps2, dtype=float)
    w = np.linalg.norm(np.asarray(recording.gyro_radps, dtype=float), axis=1)
    rate = float(recording.rate_hz)
    energy = float(np.percentile(np.abs(np.linalg.norm(acc, axis=1) - _GRAVITY_MPS2), 95)) if acc.size else 0.0
    active = np.flatnonzero(w > active_radps)
    out = {"energy_mps2": energy, "active_s": 0.0, "period_s": float("nan"), "strength": 0.0, "rhythm_strides": 0.0}
    if active.size < 2:
        return out
    a, b = int(active[0]), int(active[-1]) + 1
    out["active_s"] = (b - a) / rate
    x = w[a:b] - w[a:b].mean()
    n = x.size
    lo, hi = max(1, int(lo_s * rate)), min(n - 2, int(hi_s * rate))
    if hi <= lo + 1 or not np.any(x):
        return out
    f = np.fft.rfft(x, 2 * n)
    ac = np.fft.irfft(f * np.conj(f))[:n]
    k = np.arange(lo, hi)
    peaks = k[(ac[k] > ac[k - 1]) & (ac[k] >= ac[k + 1])]
    if peaks.size == 0 or ac[0] <= 0:
        return out
    best = int(peaks[int(np.argmax(ac[peaks]))])
    # unbiased: the lag-k sum has n - k terms
    out["strength"] = float(ac[best] / ac[0] * n / (n - best))
    out["period_s"] = best / rate
    out["rhythm_strides"] = out["active_s"] / out["period_s"]
    return out


def stance_motion_ratio(recording: ImuRecording, stance: np.ndarray, energy_mps2: float) -> float:
    """90th percentile of ||f| - g| [m/s^2] over the samples of ``stance`` (N,) bool, divided by
    ``energy_mps2`` (the walk's 95th percentile, :func:`gait_evidence`). Near 0 when the stance
    samples are a foot at rest; NaN without stance or without energy."""
    stance = np.asarray(stance, dtype=bool)
    if not stance.any() or not energy_mps2 > 0:
        return float("nan")
    a = np.abs(np.linalg.norm(np.asarray(recording.acc_mps2, dtype=float)[stance], axis=1) - _GRAVITY_MPS2)
    return float(np.percentile(a, 90) / energy_mps2)


def onset_speed_share(health: Dict[str, Any]) -> float:
    """The speed the EKF had integrated when stance began (median over the stances) over the mean
    swing speed (median stride / median swing), from a health dict; NaN when either is missing or
    zero. Near 0 when stance starts with the foot at rest."""
    speed = float(health.get("speed_at_stance_median_mps", float("nan")))
    stride = float(health.get("median_stride_m", float("nan")))
    swing = float(health.get("swing_median_s", float("nan")))
    if not (stride > 0 and swing > 0 and math.isfinite(speed)):
        return float("nan")
    return speed / (stride / swing)


def gait_plausibility(health: Dict[str, Any], evidence: Dict[str, float], path_m: float, n_strides: int,
                      limits: Dict[str, float] = HEALTH_LIMITS) -> List[str]:
    """Reasons (one sentence each) why a foot-mounted PDR result cannot be the walk the IMU shows;
    empty when plausible. ``health``: the EKF health dict (``swing_median_s``,
    ``median_stride_m``, ``n_stance_phases``) with the detector's ``guard_satisfied``;
    ``evidence``: :func:`gait_evidence`; ``path_m``: the estimate's 2-D path length [m];
    ``n_strides``: strides counted. Limits: :data:`HEALTH_LIMITS`."""
    reasons: List[str] = []
    walking = (evidence["energy_mps2"] >= limits["walking_energy_mps2"]
               and evidence["strength"] >= limits["walking_rhythm_strength"])
    swing = float(health.get("swing_median_s", 0.0))
    if int(health.get("n_stance_phases", 0)) >= 2 and swing < limits["min_swing_s"]:
        reasons.append(f"the median swing lasts {swing:.3f} s (limit {limits['min_swing_s']} s): no human swing is "
                       "that short, the stance detector has eaten the swings")
    if not health.get("guard_satisfied", True):
        reasons.append("the stance detector found no threshold with a plausible gait")
    if walking:
        stride = float(health.get("median_stride_m", 0.0))
        if stride < limits["min_stride_m"]:
            reasons.append(f"the median stride is {stride:.3f} m (limit {limits['min_stride_m']} m) while the "
                           f"accelerometer shows walking ({evidence['energy_mps2']:.1f} m/s^2)")
        rhythm = evidence["rhythm_strides"]
        if rhythm > 0 and path_m / rhythm < limits["min_path_per_rhythm_stride_m"]:
            reasons.append(f"the path ({path_m:.2f} m) is far below what the step rhythm implies ({rhythm:.0f} strides "
                           f"of {evidence['period_s']:.2f} s: at least "
                           f"{limits['min_path_per_rhythm_stride_m'] * rhythm:.1f} m)")
        if rhythm > 0 and n_strides < limits["min_stride_count_ratio"] * rhythm:
            reasons.append(f"{n_strides} strides counted where the step rhythm shows about {rhythm:.0f}")
        share = onset_speed_share(health)
        if share > limits.get("max_onset_speed_share", math.inf):
            reasons.append(f"the foot still moved at {float(health['speed_at_stance_median_mps']):.2f} m/s when stance "
                           f"began ({share:.2f} of the swing speed, limit {limits['max_onset_speed_share']}): stance is "
                           "declared inside swings and the strides come out short")
        ratio = float(health.get("stance_motion_ratio", float("nan")))
        if ratio > limits.get("max_stance_motion_ratio", math.inf):
            reasons.append(f"the samples called stance move: their ||f| - g| reaches {ratio:.2f} of the walk's "
                           f"(limit {limits['max_stance_motion_ratio']}), so the detector let swings into stance "
                           "and the path comes out short")
    return reasons


def run_recommended(recording: ImuRecording, smooth: bool = True, **overrides: Any) -> Dict[str, Any]:
    """The recommended pipeline on one recording: :func:`detect_stance`, the ZUPT EKF (+ RTS
    smoother when ``smooth``, zero velocity over ``zupt_stance``) and
    :func:`indoorloc.pdr.count_strides` (over ``stance``). Returns ``{"positions_m" (N, 3) [m],
    "stride_indices" (S,), "stance" (N,), "zupt_stance" (N,), "detector" (the detector's dict
    without the arrays), "health" (the EKF's health check, the detector threshold and stride counts, the gait
    evidence, and ``implausible`` / ``reasons`` including :func:`gait_plausibility`)}``.
    ``overrides`` go to :func:`detect_stance`."""
    evidence = gait_evidence(recording)
    det = detect_stance(recording, evidence=evidence, **overrides)
    opts = dict(ZUPT_DETECTOR, **{k: v for k, v in overrides.items() if k not in _PIPELINE_KEYWORDS})
    floor = (swing_floor(evidence, float(opts["min_plausible_swing_s"]), overrides.get("min_swing_share", MIN_SWING_SHARE),
                         float(opts["max_swing_s"])) if opts["rule"] == "swing_guard" else float("nan"))
    stance = np.asarray(det["stance"], dtype=bool)
    out = _pdr.zupt_ekf(recording.time_s, recording.acc_mps2, recording.gyro_radps, det["zupt_stance"],
                        options=_pdr.ZuptEkfOptions(smooth=smooth))
    count = _pdr.count_strides(stance, recording.rate_hz)
    positions = np.asarray(out["positions_m"], dtype=float)
    strides = np.asarray(count["stride_indices"], dtype=np.int64)
    health = dict(out["health"])
    health.update({"shoe_threshold": float(det["threshold"]), "guard_raised": bool(det["guard_raised"]),
                   "guard_satisfied": bool(det.get("guard_satisfied", True)),
                   "low_motion_rule": bool(det.get("low_motion_rule", False)),
                   "stride_median_swing_s": float(count["median_swing_s"]),
                   "stride_median_stance_s": float(count["median_stance_s"]),
                   "split_strides": int(count["n_split_strides"]), "swing_floor_s": floor,
                   "mid_swing_stances_dropped": int(det["mid_swing_stances_dropped"]),
                   "bimodal_split": bool(det.get("bimodal_split", False))})
    health.update({"gait_energy_mps2": evidence["energy_mps2"], "rhythm_period_s": evidence["period_s"],
                   "rhythm_strength": evidence["strength"], "rhythm_strides": evidence["rhythm_strides"],
                   "stance_motion_ratio": stance_motion_ratio(recording, det["zupt_stance"], evidence["energy_mps2"])})
    health["onset_speed_share"] = onset_speed_share(health)
    extra = gait_plausibility(health, evidence, path_length(positions[:, :2]), int(strides.size))
    if extra:
        health["reasons"] = list(health.get("reasons", [])) + extra
        health["implausible"] = True
        health["report"] = str(health.get("report", "")).replace(": plausible", ": IMPLAUSIBLE") + "".join(
            "; " + r for r in extra)
    return {"positions_m": positions, "stride_indices": strides, "stance": stance,
            "zupt_stance": np.asarray(det["zupt_stance"], dtype=bool),
            "detector": {k: v for k, v in det.items() if k not in ("stance", "statistic", "zupt_stance")},
            "health": health}
