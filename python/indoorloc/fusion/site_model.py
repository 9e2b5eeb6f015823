"""What a site model holds per floor, and the default tracker run on one walk with it.

A floor's model is built from survey walks with waypoints (docs/your_building.md):

- the handheld-PDR calibration (Weinberg K, the yaw offset between the phone's rotation-vector
  heading and the floor frame, its spread over walks: :func:`indoorloc.pdr.handheld.calibrate_handheld`);
- the WiFi fingerprint database (:func:`indoorloc.fusion.wifi_fixes.build_database`);
- the walkable plan (:func:`indoorloc.io.load_floor_plan`, origin at the outline's south-west corner).

A walk is then tracked by the default tracker of docs/fusion_real.md: the grid tracker from an
unknown start with the forward-backward smoother (``fusion.GridTracker``), its steps rotated by
the calibrated yaw offset and its WiFi turned into fingerprint fixes. ``indoorloc fusion
evaluate`` (experiments/fusion_real.py) and :class:`indoorloc.fusion.Site` both call this module,
so the figures of the study are the figures of a site file.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc.pdr import handheld as ph
from indoorloc.fusion import wifi_fixes, floor_evidence
from indoorloc.fusion.floor_classifier import FloorClassifier
from indoorloc.fusion.floor_sequence import floor_sequence
from indoorloc.fusion.steps import Steps
from indoorloc.fusion.grid import GridTracker, GridTrackerOptions, track_grid
from indoorloc._core.fusion import LiveSessionOptions

#: The C++ live session's defaults: the one definition of the per-step PDR noise.
_LIVE_DEFAULTS = LiveSessionOptions()


#: The floor classifier's defaults (TrackSettings.identification_classifier_*).
CLASSIFIER_WEIGHT = 10.0
CLASSIFIER_L2_SCALE = 1.0
CLASSIFIER_OUTLIER_PROBABILITY = 0.2


@dataclass
class TrackSettings:
    """The default tracker's settings on real walks (how each was chosen: docs/fusion_real.md).

    The heading-offset prior sd of the grid is not here: it is each floor's calibrated spread."""

    #: Per-step white noise of the handheld PDR: length sd as a fraction of the stride (fixed in
    #: advance), heading sd [rad] (leave-one-floor-out: 20 deg); the systematic parts are the
    #: tracker's scale and offset states. Both read from the C++ live session's options.
    step_length_sd_fraction: float = _LIVE_DEFAULTS.step_length_sd_fraction
    step_heading_sd_rad: float = _LIVE_DEFAULTS.step_heading_sd_rad
    #: The fingerprint fixes (``wifi_fixes.FixSettings``; leave-one-floor-out defaults).
    fixes: wifi_fixes.FixSettings = field(default_factory=wifi_fixes.FixSettings)
    #: The grid tracker's options (``fusion.GridTrackerOptions``, defaults read from C++).
    grid_options: Any = field(default_factory=GridTrackerOptions)
    #: "mean" or "median" (spatial median) of the posterior as the point estimate (leave-one-floor-
    #: out: "median", which flips with "mean" from floor to floor within 0.3 m).
    point_estimate: str = "median"
    #: Floor identification (``--floor auto``): cells [m] and offset bins of the all-floor filter.
    identification_cell_m: float = 2.0
    identification_offset_bins: int = 3
    #: ε of the fixes in the identification pass: 0.1, the value its AP-evidence weight below was
    #: chosen with (the tracker's own ε went to 0.01 later; with it the pass fell from 98.6 to
    #: 97.4 % of waypoints, because the weight balances the two evidences).
    identification_fix_outlier_probability: float = 0.1
    #: The AP detection rates' evidence added to the filter's (``fusion.floor_evidence``): weight λ
    #: (0: not added), m strongest APs per query, rate floor α, outlier probability ε. m, α, ε as
    #: chosen by ``experiments.floor_identification_study`` before the classifier (m over 1-50, α
    #: 0.001-0.1, ε 0.05-0.6; the floor sequence uses them too); λ chosen with the classifier below
    #: (docs/fusion_real.md, "Floor identification").
    identification_ap_weight: float = 2.0
    identification_ap_count: int = 20
    identification_ap_rate_floor: float = 0.1
    identification_ap_outlier_probability: float = 0.1
    #: The floor classifier's evidence added to the filter's (``fusion.floor_classifier``): weight
    #: μ (0: no classifier), its L2 scale C and outlier probability ε. The point chosen on all six
    #: floors of the competition site, the walks of fold seeds 0-3 pooled, by
    #: ``experiments.floor_identification_study --seed 0 1 2 3`` (C 0.1-1, ε 0.01-0.2, μ 0-10,
    #: jointly with λ above); held out by floor, the same for five of six floors
    #: (docs/fusion_real.md, "Floor identification").
    identification_classifier_weight: float = CLASSIFIER_WEIGHT
    identification_classifier_l2_scale: float = CLASSIFIER_L2_SCALE
    identification_classifier_outlier_probability: float = CLASSIFIER_OUTLIER_PROBABILITY
    #: Calibration of the reported floor probabilities (``floor_evidence.FloorCalibration``):
    #: temperature T of the combined score, δ_10 the probability that the evidence misleads at a
    #: match distance of 10 dB on the chosen floor, and b the slope of logit δ in the log of that
    #: distance. Chosen by leave-one-floor-out log loss over walks with
    #: ``experiments.floor_identification_study --seed 0 1 2 3`` (on the score with the classifier);
    #: they change the probabilities, never the floor.
    identification_temperature: float = 0.5
    identification_error_probability: float = 0.01
    identification_error_slope: float = 3.0
    #: Rate r [1/s] of floor changes of the AP evidence's floor sequence (``fusion.floor_sequence``),
    #: which tells a walk that seems to change floor (the tracker keeps it on one). Chosen by
    #: leave-one-floor-out with ``experiments.floor_change_study`` (real and spliced walks).
    identification_floor_change_rate_per_s: float = 1.0 / 1200.0
    #: How a walk whose start is known weighs its fixes (``fusion evaluate``'s known start, and the
    #: smoother's second pass below): τ, ε and the wall penalty λ, chosen by leave-one-floor-out on
    #: the known start's own error (the same point for every held-out floor; docs/fusion_real.md):
    #: with the start known, the fixes only need to stop the PDR's drift.
    known_start_fix_tempering: float = 0.2
    known_start_fix_outlier_probability: float = 0.3
    known_start_wall_log_penalty: float = -3.0
    known_start_fix_tempering_by_variance: bool = False
    #: "Locate, then track": the smoothed track is a second smoother pass, started from the first
    #: pass's smoothed estimate at the first step (with this sd [m] and the first pass's heading
    #: offset) and weighing its fixes as a known start does (above). Why: an unknown start needs
    #: strong fixes to find the walker, but once found, the steps and walls place it better than
    #: fixes that are metres off. 0: one pass (the smoother of the unknown start). Chosen over
    #: {0, 0.5, 1, 2, 3} m on the six floors of the competition site and fold seeds 0-3: 1 m has
    #: the lowest mean (8.06 against 8.29 m for one pass) and is chosen for five of six held-out
    #: floors (held out 8.16 m; docs/fusion_real.md, "Locate, then track").
    second_pass_start_sd_m: float = 1.0

    def validate(self) -> None:
        """Raises ValueError naming the first invalid field."""
        for name in ("step_length_sd_fraction", "step_heading_sd_rad", "identification_cell_m"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"indoorloc: TrackSettings.{name} must be finite and > 0, got {v!r}")
        if not (math.isfinite(self.identification_ap_weight) and self.identification_ap_weight >= 0):
            raise ValueError(f"indoorloc: TrackSettings.identification_ap_weight must be finite and >= 0, "
                             f"got {self.identification_ap_weight!r}")
        if not (isinstance(self.identification_ap_count, int) and self.identification_ap_count >= 1):
            raise ValueError(f"indoorloc: TrackSettings.identification_ap_count must be an integer >= 1, "
                             f"got {self.identification_ap_count!r}")
        if not 0 < self.identification_ap_rate_floor <= 1:
            raise ValueError(f"indoorloc: TrackSettings.identification_ap_rate_floor must be in (0, 1], "
                             f"got {self.identification_ap_rate_floor!r}")
        if not 0 < self.identification_fix_outlier_probability < 1:
            raise ValueError(f"indoorloc: TrackSettings.identification_fix_outlier_probability must be in (0, 1), "
                             f"got {self.identification_fix_outlier_probability!r}")
        if not (math.isfinite(self.identification_classifier_weight) and self.identification_classifier_weight >= 0):
            raise ValueError(f"indoorloc: TrackSettings.identification_classifier_weight must be finite and >= 0, "
                             f"got {self.identification_classifier_weight!r}")
        if not (math.isfinite(self.identification_classifier_l2_scale) and self.identification_classifier_l2_scale > 0):
            raise ValueError(f"indoorloc: TrackSettings.identification_classifier_l2_scale must be finite and > 0, "
                             f"got {self.identification_classifier_l2_scale!r}")
        if not 0 <= self.identification_classifier_outlier_probability <= 1:
            raise ValueError(f"indoorloc: TrackSettings.identification_classifier_outlier_probability must be in "
                             f"[0, 1], got {self.identification_classifier_outlier_probability!r}")
        if not 0 <= self.identification_ap_outlier_probability <= 1:
            raise ValueError(f"indoorloc: TrackSettings.identification_ap_outlier_probability must be in [0, 1], "
                             f"got {self.identification_ap_outlier_probability!r}")
        if not (math.isfinite(self.identification_temperature) and self.identification_temperature > 0):
            raise ValueError(f"indoorloc: TrackSettings.identification_temperature must be finite and > 0, "
                             f"got {self.identification_temperature!r}")
        if not 0 <= self.identification_error_probability < 1:
            raise ValueError(f"indoorloc: TrackSettings.identification_error_probability must be in [0, 1), "
                             f"got {self.identification_error_probability!r}")
        if not (math.isfinite(self.identification_error_slope) and self.identification_error_slope >= 0):
            raise ValueError(f"indoorloc: TrackSettings.identification_error_slope must be finite and >= 0, "
                             f"got {self.identification_error_slope!r}")
        if not (math.isfinite(self.identification_floor_change_rate_per_s)
                and self.identification_floor_change_rate_per_s >= 0):
            raise ValueError(f"indoorloc: TrackSettings.identification_floor_change_rate_per_s must be finite and >= 0, "
                             f"got {self.identification_floor_change_rate_per_s!r}")
        if not (isinstance(self.known_start_fix_tempering, (int, float)) and 0 < self.known_start_fix_tempering <= 1):
            raise ValueError(f"indoorloc: TrackSettings.known_start_fix_tempering must be in (0, 1], "
                             f"got {self.known_start_fix_tempering!r}")
        if not (isinstance(self.known_start_fix_outlier_probability, (int, float))
                and 0 < self.known_start_fix_outlier_probability < 1):
            raise ValueError(f"indoorloc: TrackSettings.known_start_fix_outlier_probability must be in (0, 1), "
                             f"got {self.known_start_fix_outlier_probability!r}")
        if not (isinstance(self.known_start_wall_log_penalty, (int, float)) and self.known_start_wall_log_penalty <= 0
                and not math.isnan(self.known_start_wall_log_penalty)):
            raise ValueError(f"indoorloc: TrackSettings.known_start_wall_log_penalty must be <= 0 (-inf: hard walls), "
                             f"got {self.known_start_wall_log_penalty!r}")
        if not (isinstance(self.second_pass_start_sd_m, (int, float)) and math.isfinite(self.second_pass_start_sd_m)
                and self.second_pass_start_sd_m >= 0):
            raise ValueError(f"indoorloc: TrackSettings.second_pass_start_sd_m must be finite and >= 0 (0: one pass), "
                             f"got {self.second_pass_start_sd_m!r}")
        if self.point_estimate not in ("mean", "median"):
            raise ValueError(f"indoorloc: TrackSettings.point_estimate must be 'mean' or 'median', "
                             f"got {self.point_estimate!r}")
        self.fixes.validate()

    def to_dict(self) -> Dict[str, Any]:
        """JSON-ready (an infinite wall penalty becomes None)."""
        d: Dict[str, Any] = {k: getattr(self, k) for k in ("step_length_sd_fraction", "step_heading_sd_rad",
                                                          "point_estimate", "identification_cell_m",
                                                          "identification_offset_bins", "identification_ap_weight",
                                                          "identification_ap_count", "identification_ap_rate_floor",
                                                          "identification_ap_outlier_probability",
                                                          "identification_classifier_weight",
                                                          "identification_classifier_l2_scale",
                                                          "identification_classifier_outlier_probability",
                                                          "identification_fix_outlier_probability",
                                                          "identification_temperature",
                                                          "identification_error_probability",
                                                          "identification_error_slope",
                                                          "identification_floor_change_rate_per_s",
                                                          "known_start_fix_tempering",
                                                          "known_start_fix_outlier_probability",
                                                          "known_start_fix_tempering_by_variance",
                                                          "second_pass_start_sd_m")}
        # An infinite (hard) wall penalty is stored as None, as the grid options' own.
        d["known_start_wall_log_penalty"] = (None if math.isinf(self.known_start_wall_log_penalty)
                                             else self.known_start_wall_log_penalty)
        d["fixes"] = asdict(self.fixes)
        d["grid_options"] = {k: (None if isinstance(v, float) and math.isinf(v) else v)
                             for k, v in self.grid_options.to_dict().items()}
        return d

    def floor_calibration(self) -> floor_evidence.FloorCalibration:
        """The calibration of the reported floor probabilities (``identification_temperature``,
        ``identification_error_probability``, ``identification_error_slope``)."""
        return floor_evidence.FloorCalibration(self.identification_temperature, self.identification_error_probability,
                                               self.identification_error_slope)

    @classmethod
    def from_dict(cls, d: Dict[str, Any]) -> "TrackSettings":
        """Inverse of :meth:`to_dict`; unknown keys raise ValueError naming them."""
        d = dict(d)
        if "known_start_wall_log_penalty" in d and d["known_start_wall_log_penalty"] is None:
            d["known_start_wall_log_penalty"] = -math.inf
        fixes = wifi_fixes.FixSettings(**d.pop("fixes", {}))
        g = {k: (-math.inf if k == "wall_log_penalty" and v is None else v) for k, v in d.pop("grid_options", {}).items()}
        known = {f for f in cls.__dataclass_fields__}
        unknown = sorted(set(d) - known)
        if unknown:
            raise ValueError(f"indoorloc: tracker settings: unknown keys {unknown}")
        return cls(fixes=fixes, grid_options=GridTrackerOptions().replace(**g), **d)


def calibrate_floor(walks: Sequence[Any], steps: Sequence[ph.HandheldSteps]) -> ph.HandheldCalibration:
    """The floor's handheld-PDR calibration from its survey walks (with waypoints) and their
    detected steps (same order)."""
    return ph.calibrate_handheld(walks, steps_cache=steps)


def build_fingerprints(walks: Sequence[Any], steps: Sequence[ph.HandheldSteps], floor_number: int,
                       settings: wifi_fixes.FixSettings) -> wifi_fixes.FingerprintDatabase:
    """The floor's fingerprint database from its survey walks, each fingerprint placed by PDR
    between the waypoints (``wifi_fixes.build_database``)."""
    return wifi_fixes.build_database(walks, settings, steps, floors=[floor_number] * len(walks))


def tracker_steps(steps_raw: ph.HandheldSteps, cal: ph.HandheldCalibration, settings: TrackSettings) -> Steps:
    """A walk's detected steps as the tracker takes them: lengths with the calibrated K, headings
    rotated into the floor frame by the calibrated yaw offset [rad], per-step sds from
    ``settings``."""
    steps = ph.rescale(steps_raw, cal.options)
    heading = steps.heading_rad + cal.yaw_offset_rad
    return Steps.from_polar(steps.t_s, steps.length_m, heading, settings.step_length_sd_fraction * steps.length_m,
                            settings.step_heading_sd_rad)


def offset_spread_rad(cal: ph.HandheldCalibration) -> float:
    """The heading-offset prior sd of the floor [rad]: the calibrated spread over the survey
    walks, at least 1e-3 (a single walk has no spread)."""
    spread = cal.yaw_offset_spread_rad
    return max(spread if math.isfinite(spread) else 0.0, 1e-3)


def identification_calibration(calibrations: Sequence[ph.HandheldCalibration]) -> tuple:
    """What floor identification rotates a walk's steps with, the walk's floor being unknown:
    ``(calibration, offset_spread_rad)``, the first floor's calibration (floors in building
    order, as ``Site.floors``) and the widest offset spread of the floors (:func:`offset_spread_rad`).
    ``indoorloc track --floor auto`` and ``fusion evaluate`` both use it, so that neither uses the
    calibration of the walk's true floor."""
    cals = list(calibrations)
    if not cals:
        raise ValueError("indoorloc: argument 'calibrations': expected the calibration of at least one floor")
    return cals[0], max(offset_spread_rad(c) for c in cals)


def floor_grid_options(settings: TrackSettings, cal: ph.HandheldCalibration, spatial_median: Optional[bool] = None,
                       **changes) -> Any:
    """The grid options of a floor: the settings' options with the floor's offset spread
    (``spatial_median`` default: whether the point estimate is the median)."""
    median = settings.point_estimate == "median" if spatial_median is None else bool(spatial_median)
    return settings.grid_options.replace(heading_offset_sd_rad=offset_spread_rad(cal), spatial_median=median,
                                         **changes)


def identification_grid_options(settings: TrackSettings, spread_rad: float, spatial_median: bool = False) -> Any:
    """Grid options of the all-floor floor-identification filter (coarser cells, fewer offset bins)."""
    return settings.grid_options.replace(heading_offset_sd_rad=spread_rad, spatial_median=spatial_median,
                                         cell_size_m=settings.identification_cell_m,
                                         heading_offset_bins=settings.identification_offset_bins,
                                         fix_outlier_probability=settings.identification_fix_outlier_probability)


def uses_survey_positions(options: GridTrackerOptions) -> bool:
    """Whether a grid tracker with ``options`` reads the survey positions: fixes anchored to them
    (``fix_survey_distance_factor`` < 1) or cells near them opened (``survey_walkable_radius_m`` > 0)."""
    return options.fix_survey_distance_factor < 1.0 or options.survey_walkable_radius_m > 0.0


def survey_anchored(tracker: GridTracker, plan: Any, database: wifi_fixes.FingerprintDatabase) -> GridTracker:
    """The tracker (on ``plan``) whose fixes are evaluated at survey-anchored positions: the
    fingerprint positions of ``database`` (``GridTrackerOptions.fix_survey_distance_factor``,
    ``GridTracker.with_survey_positions``), with the cells within ``survey_walkable_radius_m`` of
    the positions of ``survey_walkable_min_walks`` distinct surveyed walks open (a database without
    ``walk_index``: each position a walk of its own; fingerprints of weight < 1, placed by the
    tracker, anchor but open nothing); the tracker itself when it reads no survey
    position (:func:`uses_survey_positions`). A floor's own database may leave its floor numbers at
    0: on a one-floor plan every position is on its floor."""
    if not uses_survey_positions(tracker.options):
        return tracker
    positions = np.asarray(database.positions_m, dtype=float).reshape(-1, 2)
    floors = np.asarray(database.floors, dtype=np.int64)
    if len(plan.floors) == 1:
        floors = np.full(positions.shape[0], plan.floors[0], dtype=np.int64)
    walks = getattr(database, "walk_index", None)  # None: each position a walk of its own
    if walks is not None:
        walks = np.asarray(walks, dtype=np.int64).copy()
        weights = getattr(database, "weights", None)
        if weights is not None:  # fingerprints of walks placed by the tracker (Site.grow) open no cell
            walks[np.asarray(weights, float) < 1.0] = -1
    return tracker.with_survey_positions(positions, floors, walks)


def second_pass_options(options: GridTrackerOptions, settings: TrackSettings) -> GridTrackerOptions:
    """The grid options of the smoother's second pass (``TrackSettings.second_pass_start_sd_m``):
    ``options`` with the start sd and the known start's fix weighting and walls, without the
    spatial median: its posterior is one mode around the located start, whose mean is its point
    estimate (the median gave the same errors within 0.004 m on fold seeds 0-1, at about twice the
    pass's cost)."""
    return options.replace(start_position_sd_m=settings.second_pass_start_sd_m, spatial_median=False,
                           fix_tempering=settings.known_start_fix_tempering,
                           fix_outlier_probability=settings.known_start_fix_outlier_probability,
                           wall_log_penalty=settings.known_start_wall_log_penalty,
                           fix_tempering_by_variance=settings.known_start_fix_tempering_by_variance)


def located_start(first_pass: dict, steps: Steps, floor: int, median: bool) -> dict:
    """The known start of the second pass: the first pass's smoothed point estimate at the first
    step (``median``: its spatial median, else its mean) [m], at that step's time [s] (the step
    itself then does not move the walker), on ``floor`` (a floor number of the plan), with the
    first pass's posterior heading offset of the walk [rad]."""
    key = "smoothed_median_m" if median and "smoothed_median_m" in first_pass else "smoothed_m"
    return {"position_m": np.asarray(first_pass[key], float)[0], "floor": int(floor),
            "heading_offset_rad": float(first_pass["walk_heading_offset_rad"]), "time_s": float(steps.times_s[0])}


#: The smoothed keys of a run that the second pass replaces, both by its posterior mean (its
#: covariances stay the first pass's: they are calibrated for a walker whose start was not given,
#: which is the case).
SECOND_PASS_KEYS = ("smoothed_m", "smoothed_median_m")


def run_default(tracker: GridTracker, steps: Steps, fixes, smooth: bool = True,
                second_pass: Optional[GridTracker] = None, floor: int = 0, median: bool = True) -> dict:
    """The default tracker on one walk: unknown start, filter and (``smooth``) smoother
    (:func:`indoorloc.fusion.track_grid`'s dict). With ``second_pass`` (a tracker of the same plan
    with :func:`second_pass_options`) and ``smooth``: the smoothed track (``SECOND_PASS_KEYS``) is
    that tracker's smoother from the first pass's :func:`located_start` on ``floor``; the first
    pass's run is kept under ``"first_pass"``."""
    r = dict(track_grid(tracker, steps, fixes=fixes, start=None, smooth=smooth))
    if not (smooth and second_pass is not None and len(steps)):
        return r
    r2 = run_second_pass(second_pass, r, steps, fixes, floor, median)
    first = dict(r)
    for key in SECOND_PASS_KEYS:
        if key in r:
            r[key] = np.asarray(r2["smoothed_m"])
    r["first_pass"] = first
    return r


def run_second_pass(second_pass: GridTracker, first_pass: dict, steps: Steps, fixes, floor: int,
                    median: bool) -> dict:
    """The smoother's second pass on one walk (``TrackSettings.second_pass_start_sd_m``): the
    smoother of ``second_pass`` (a tracker with :func:`second_pass_options`) from the first pass's
    :func:`located_start` (``track_grid``'s dict; its filtered estimates are not computed)."""
    return dict(track_grid(second_pass, steps, fixes=fixes, start=located_start(first_pass, steps, floor, median),
                           smooth=True, filtered=False))


def ap_floor_rates(database: wifi_fixes.FingerprintDatabase, floors: Sequence[int], settings: TrackSettings
                   ) -> floor_evidence.ApFloorRates:
    """The per-floor AP detection rates of an all-floor fingerprint database (rows in the order of
    ``floors``, the identification tracker's), for :func:`identify_floor`; with the floor
    classifier fitted on the same database attached (``classifier``) when its weight
    (``identification_classifier_weight``) is > 0."""
    rates = floor_evidence.ApFloorRates.from_references(database.rss_dbm, database.floors, floors,
                                                        settings.identification_ap_rate_floor)
    if settings.identification_classifier_weight > 0:
        rates.classifier = FloorClassifier.fit(database.rss_dbm, database.floors, floors,
                                               settings.identification_classifier_l2_scale)
    return rates


def walk_ap_log_likelihood(walk: Any, database: wifi_fixes.FingerprintDatabase, rates: floor_evidence.ApFloorRates,
                           settings: TrackSettings) -> np.ndarray:
    """The walk's AP evidence per floor (F,) [nats] (``floor_evidence.walk_floor_log_likelihood``
    on the walk's query fingerprints in the database's columns)."""
    return walk_floor_evidence(walk, database, rates, settings)["ap_log_likelihood"]


def walk_floor_evidence(walk: Any, database: wifi_fixes.FingerprintDatabase, rates: floor_evidence.ApFloorRates,
                        settings: TrackSettings,
                        queries: Optional[Tuple[np.ndarray, np.ndarray]] = None) -> Dict[str, Any]:
    """What :func:`identify_floor` takes from the walk's WiFi, per floor of ``rates`` (F,):
    ``ap_log_likelihood`` [nats] (``floor_evidence.walk_floor_log_likelihood``) and
    ``match_distance_db`` [dB] (``floor_evidence.walk_match_distance_db``), both on the walk's
    query fingerprints in the database's columns; ``classifier_log_likelihood`` [nats] (F,), the
    floor classifier's evidence (``fusion.floor_classifier``; None when ``rates`` has no
    classifier); and the AP evidence's floor sequence
    (``fusion.floor_sequence`` at ``identification_floor_change_rate_per_s``): ``query_t_s``
    (Q,) [s], ``query_floors`` (Q,) floor numbers, ``floor_changes`` the changes along it.
    ``queries``: ``wifi_fixes.walk_queries(walk, database)`` when the caller has it already."""
    t, queries = wifi_fixes.walk_queries(walk, database) if queries is None else queries
    log_p, used = floor_evidence.query_floor_log_posteriors(rates, queries, settings.identification_ap_count)
    per_query = floor_evidence.robust_query_log_likelihoods(log_p, settings.identification_ap_outlier_probability)
    seq = floor_sequence(per_query, t[used], settings.identification_floor_change_rate_per_s)
    dist = np.array([floor_evidence.walk_match_distance_db(database.rss_dbm, database.floors, int(f), queries)
                     for f in rates.floors])
    classifier = None
    if rates.classifier is not None:
        classifier = rates.classifier.walk_log_likelihood(queries, settings.identification_classifier_outlier_probability)
    return {"ap_log_likelihood": per_query.sum(axis=0), "match_distance_db": dist,
            "classifier_log_likelihood": classifier, "query_t_s": t[used],
            "query_floors": np.asarray(rates.floors)[seq["path"]], "floor_changes": seq["changes"]}


def identify_floor(tracker_all: GridTracker, floors: Sequence[int], steps: Steps, fixes,
                   ap_log_likelihood: Optional[np.ndarray] = None, ap_weight: float = 0.0,
                   calibration: Optional[floor_evidence.FloorCalibration] = None,
                   match_distance_db: Optional[np.ndarray] = None,
                  classifier_log_likelihood: Optional[np.ndarray] = None,
                  classifier_weight: float = 0.0) -> Dict[str, Any]:
    """The floor of a walk (a walk stays on one floor): the floor with the most evidence, the
    all-floor filter's log-evidence per floor plus ``ap_weight`` x the walk's AP evidence
    ``ap_log_likelihood`` (F,) (:func:`walk_floor_evidence`; None: the filter alone) plus
    ``classifier_weight`` x the floor classifier's evidence ``classifier_log_likelihood`` (F,)
    (:func:`walk_floor_evidence`; None: none).

    Returns ``{"floor": int, "probabilities": {floor: p}, "score": {floor: nats},
    "match_distance_db": float or None, "error_probability": δ, "grid_probabilities": {floor: p},
    "result": dict}``: ``score`` the combined log-evidence (0 for the best floor),
    ``probabilities`` its calibrated version (``calibration``, a ``floor_evidence.FloorCalibration``,
    with δ from the walk's match distance on the chosen floor, ``match_distance_db`` (F,) from
    :func:`walk_floor_evidence`; None: T = 1, δ = 0, the plain normalised evidence, which is
    overconfident; ``TrackSettings.floor_calibration()`` holds the calibrated values)."""
    r = dict(track_grid(tracker_all, steps, fixes=fixes, smooth=False))
    p_grid = np.asarray(r["smoothed_floor_probabilities"], float)
    score = np.log(np.maximum(p_grid, 1e-300))
    if ap_log_likelihood is not None and ap_weight > 0:
        ap = np.asarray(ap_log_likelihood, float)
        if ap.shape != score.shape:
            raise ValueError(f"indoorloc: argument 'ap_log_likelihood': expected shape {score.shape}, got {ap.shape}")
        score = score + ap_weight * ap
    if classifier_log_likelihood is not None and classifier_weight > 0:
        k = np.asarray(classifier_log_likelihood, float)
        if k.shape != score.shape:
            raise ValueError(f"indoorloc: argument 'classifier_log_likelihood': expected shape {score.shape}, "
                             f"got {k.shape}")
        score = score + classifier_weight * k
    best = int(np.argmax(score))
    dist = None
    if match_distance_db is not None:
        d = np.asarray(match_distance_db, float)
        if d.shape != score.shape:
            raise ValueError(f"indoorloc: argument 'match_distance_db': expected shape {score.shape}, got {d.shape}")
        dist = float(d[best])
    cal = calibration or floor_evidence.FloorCalibration()
    delta = float(cal.error_probability(dist))
    p = floor_evidence.calibrated_floor_probabilities(score, cal.temperature, delta)
    return {"floor": int(floors[best]), "probabilities": {int(f): float(v) for f, v in zip(floors, p)},
            "score": {int(f): float(v) for f, v in zip(floors, score - score.max())},
            "match_distance_db": dist, "error_probability": delta,
            "grid_probabilities": {int(f): float(v) for f, v in zip(floors, p_grid)}, "result": r}


def walk_errors_m(track_t_s: np.ndarray, track_m: np.ndarray, waypoint_t_s: np.ndarray,
                  waypoint_xy_m: np.ndarray) -> np.ndarray:
    """Error [m] at each waypoint of the track interpolated linearly to the waypoint times."""
    t = np.asarray(track_t_s, float)
    xy = np.asarray(track_m, float)
    wt = np.asarray(waypoint_t_s, float)
    if t.size == 0:
        return np.full(wt.size, np.nan)
    est = np.stack([np.interp(wt, t, xy[:, 0]), np.interp(wt, t, xy[:, 1])], axis=1)
    return np.hypot(*(est - np.asarray(waypoint_xy_m, float)).T)


__all__ = ["TrackSettings", "ap_floor_rates", "build_fingerprints", "calibrate_floor", "floor_grid_options",
           "identification_calibration", "identification_grid_options", "identify_floor", "offset_spread_rad", "run_default", "tracker_steps",
           "walk_ap_log_likelihood", "walk_errors_m", "walk_floor_evidence"]
