"""Settings and records of ``indoorloc fusion evaluate`` (:mod:`indoorloc.experiments.fusion_real`):
the methods it scores, :class:`RealSettings` (each setting fixed in advance, fitted per fold or
chosen by leave-one-floor-out), one walk's scores (:class:`WalkScore`), one floor's data
(:class:`FloorData`) and what a fold's training walks give a floor (:class:`FoldModels`)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from indoorloc import fusion
from indoorloc.fusion import crowdsourced_map as wc, wifi_fixes as wfx
from indoorloc.fusion import site_model, wifi_heading_sequence, wifi_sequence
from indoorloc.pdr import handheld as ph

FLOORS: Tuple[str, ...] = ()  #: none named: every floor folder under the data root, in building order
METHODS = (
    "wifi_knn",
    "wifi_model",
    "wifi_sequence",
    "wifi_heading_sequence",
    "pdr_only",
    "peer_costmin",
    "fusion_unknown_start",
    "fusion_live",
    "fusion_known_start",
    "fusion_smoother",
    "fusion_no_walls",
    "fusion_no_wifi",
    "fusion_no_heading_offset",
    "particle_unknown_start",
    "particle_smoother",
    "particle_known_start",
)
#: Methods whose estimate comes with a covariance: the 95 % region's coverage is reported.
COVARIANCE_METHODS = ("fusion_unknown_start", "fusion_live", "fusion_smoother", "fusion_known_start", "particle_unknown_start",
                      "particle_smoother")

#: The default method (unknown start + smoother): the objective of ``--select`` and the method
#: run with the floor not given for floor identification.
SELECT_OBJECTIVE = "fusion_smoother"


def _site_default(name: str):
    """A field whose default is the site model's ``TrackSettings.<name>`` (defined there, once)."""
    return field(default_factory=lambda: getattr(site_model.TrackSettings(), name))


@dataclass
class RealSettings:
    """Settings of ``indoorloc fusion evaluate``; each is fixed in advance (why in the comment),
    fitted per fold on the training walks (``calibrate_handheld``), or chosen by
    leave-one-floor-out cross-validation (:func:`select_settings`; marked LOFO)."""

    folds: int = 4                      #: k of the k-fold by walk (issue 15)
    seed: int = 0                       #: fold assignment and tracker seeds
    num_particles: int = 3000           #: 20000 gave the same errors on F8 (docs/fusion_real.md)
    smoother_trajectories: int = 50     #: FFBSi trajectories
    #: FFBSi cloud thinned to this many particles per step (cost O(trajectories x this x steps)).
    smoother_max_particles: int = 500
    #: Staleness limit of the WiFi-only fixes [s]: the dip of the reading-age histogram between the
    #: current scan and Android's cache (docs/fusion_data.md).
    wifi_max_age_s: float = 2.5
    grid_spacing_m: float = 2.0         #: GridPosterior spacing of the model fixes (docs/fusion_real.md)
    #: Per-step white noise of the handheld PDR given to the filter: length sd as a fraction of the
    #: stride and heading sd [rad] (LOFO: 20 deg); the systematic parts are the filter's scale and
    #: offset states. Defaults: the site model's (read from the C++ live session's options).
    step_length_sd_fraction: float = _site_default("step_length_sd_fraction")
    step_heading_sd_rad: float = _site_default("step_heading_sd_rad")
    #: LOFO: log-weight of a step through a shop wall (-inf: the particle is dropped; log 0.02 in
    #: the grid: shops are polygons without doors and 12 of 866 waypoints lie inside one). A known
    #: start inside a shop is moved to the nearest walkable point.
    wall_log_penalty: float = field(default_factory=lambda: fusion.TrackerOptions().wall_log_penalty)
    candidate_spacing_m: float = 2.0    #: unknown start and recovery on the mall floors
    #: The WiFi as fingerprint fixes (``wifi_fixes``); k, T, σ, c: LOFO.
    fixes: wfx.FixSettings = field(default_factory=wfx.FixSettings)
    #: The WiFi-only sequence tracker (``wifi_sequence``: the fixes above on the walkable grid with
    #: a random-walk motion, no PDR; its settings chosen by LOFO, ``experiments/wifi_sequence_study``).
    wifi_sequence: wifi_sequence.SequenceSettings = field(default_factory=wifi_sequence.SequenceSettings)
    #: The WiFi-only tracker with a direction-persistent motion prior (``wifi_heading_sequence``:
    #: the same fixes, modes "wander" and 8 walking directions; LOFO, ``experiments/wifi_heading_study``).
    wifi_heading_sequence: wifi_heading_sequence.HeadingSequenceSettings = field(
        default_factory=wifi_heading_sequence.HeadingSequenceSettings)
    #: Propagation-model fixes (``fusion.propagation_fixes``, a per-AP path-loss model fitted per
    #: fold) added to the fixes of ``wifi_sequence`` and of the grid engine's methods: "off" (the
    #: kNN fixes alone), "product" (both as separate fixes at the same times) or "mixture" (one
    #: fix, ``propagation_weight`` on the model's components). ``wifi_knn`` and the peer keep the
    #: kNN fixes. A study setting (docs/fusion_real.md, "A propagation model that extrapolates").
    propagation: str = "off"
    propagation_weight: float = 0.5
    propagation_fixes: Any = None        #: ``propagation_fixes.ModelFixSettings`` (None: its defaults)
    propagation_huber_sd: float = 1.5    #: ``wifi.propagation.scan_log_likelihood``'s huber_sd
    #: LOFO: ε of the fixes (the particle tracker's own default, read from TrackerOptions).
    fix_outlier_probability: float = field(default_factory=lambda: fusion.TrackerOptions().fix_outlier_probability)
    #: LOFO: τ_fix (consecutive scans share stale readings; TrackerOptions' default).
    fix_tempering: float = field(default_factory=lambda: fusion.TrackerOptions().fix_tempering)
    #: The known-start filter's own choice (LOFO on ``fusion_known_start`` over the same grid,
    #: the same point in every fold): with the start known, WiFi fixes only need to stop drift
    #: and are weighted less.
    #: "shared": the default fixes (the old choice "union" was made for single-scan fixes; with
    #: the pooled windows of wifi_matcher there is one fix source, weighted by the known start's
    #: own τ and ε below).
    known_start_fix_metric: str = "shared"
    #: (LOFO on fusion_known_start over the grid of SELECT_GRID, the same point for every held-out
    #: floor: τ 0.2 at the grid's lower edge, 0.4 within 0.02 m of it.) Defaults: the site model's.
    known_start_fix_tempering: float = _site_default("known_start_fix_tempering")
    known_start_fix_outlier_probability: float = _site_default("known_start_fix_outlier_probability")
    #: The grid engine's known start: its own wall penalty and tempering mode (LOFO on
    #: fusion_known_start, like its τ and ε).
    known_start_wall_log_penalty: float = _site_default("known_start_wall_log_penalty")
    known_start_fix_tempering_by_variance: bool = _site_default("known_start_fix_tempering_by_variance")
    #: The smoother's second pass from the located start (site model's ``second_pass_start_sd_m``;
    #: 0: one pass).
    second_pass_start_sd_m: float = _site_default("second_pass_start_sd_m")
    #: The known start's calibration of its returned covariance (a, b [m], g of
    #: GridTrackerOptions.filtered_covariance_*): the all-floor choice of
    #: ``experiments/fusion_uncertainty`` (LOFO coverage 0.951, 0.93-0.98 per floor; re-chosen
    #: after the second settings round).
    known_start_covariance_scale: float = 3.0
    known_start_covariance_floor_m: float = 0.5
    known_start_covariance_fix_gain: float = 0.0
    known_start_covariance_fix_sd_gain: float = 0.0   #: h (GridTrackerOptions.filtered_covariance_fix_sd_gain)
    known_start_covariance_fix_sd_knee_m: float = 0.0  #: s0 [m] (GridTrackerOptions.covariance_fix_sd_knee_m)
    floor_identification: bool = True   #: also run the default with the floor not given
    threads: int = 2                    #: walks tracked in parallel (results do not depend on it)
    #: Engine of the fusion_* methods: "grid" (exact filter and smoother on floor cells,
    #: ``fusion.GridTracker``) or "particle" (``fusion.track``). The other engine's default runs
    #: too, as ``particle_*`` or ``grid_*`` (docs/fusion_real.md: chosen by leave-one-floor-out).
    engine: str = "grid"
    #: The grid engine's options (the heading-offset prior sd is the fold's calibrated spread).
    grid_options: Any = field(default_factory=lambda: fusion.GridTrackerOptions())
    #: Point estimate of the grid engine's unknown-start methods: "mean" or "median" (spatial
    #: median) of the posterior (LOFO; the site model's default).
    point_estimate: str = _site_default("point_estimate")
    #: Also score the other point estimate (hidden keys): set by --select, which chooses it.
    score_both_point_estimates: bool = False
    #: Cells [m] and offset bins of the floor-identification pass (all floors, filter only).
    floor_identification_cell_m: float = 2.0
    floor_identification_offset_bins: int = 3
    #: The AP evidence of floor identification (``fusion.floor_evidence``): weight λ, strongest
    #: APs m, rate floor α, outlier probability ε; defaults: TrackSettings' (LOFO, docs/fusion_real.md).
    floor_identification_ap_weight: float = _site_default("identification_ap_weight")
    floor_identification_ap_count: int = _site_default("identification_ap_count")
    floor_identification_ap_rate_floor: float = _site_default("identification_ap_rate_floor")
    floor_identification_ap_outlier_probability: float = _site_default("identification_ap_outlier_probability")

    def tracker_options(self, **overrides) -> fusion.TrackerOptions:
        settings = dict(num_particles=self.num_particles, wall_log_penalty=self.wall_log_penalty,
                        candidate_spacing_m=self.candidate_spacing_m, seed=self.seed,
                        fix_outlier_probability=self.fix_outlier_probability, fix_tempering=self.fix_tempering)
        settings.update(overrides)
        return fusion.tracker_options(**settings)

    def track_settings(self) -> site_model.TrackSettings:
        """The settings a site model's default tracker takes (``fusion.site_model``)."""
        return site_model.TrackSettings(
            step_length_sd_fraction=self.step_length_sd_fraction, step_heading_sd_rad=self.step_heading_sd_rad,
            fixes=self.fixes, grid_options=self.grid_options, point_estimate=self.point_estimate,
            identification_cell_m=self.floor_identification_cell_m,
            identification_offset_bins=self.floor_identification_offset_bins,
            identification_ap_weight=self.floor_identification_ap_weight,
            identification_ap_count=self.floor_identification_ap_count,
            identification_ap_rate_floor=self.floor_identification_ap_rate_floor,
            identification_ap_outlier_probability=self.floor_identification_ap_outlier_probability,
            known_start_fix_tempering=self.known_start_fix_tempering,
            known_start_fix_outlier_probability=self.known_start_fix_outlier_probability,
            known_start_wall_log_penalty=self.known_start_wall_log_penalty,
            known_start_fix_tempering_by_variance=self.known_start_fix_tempering_by_variance,
            second_pass_start_sd_m=self.second_pass_start_sd_m)

    def to_dict(self) -> Dict[str, Any]:
        d = asdict(self)
        d["wall_log_penalty"] = None if math.isinf(self.wall_log_penalty) else self.wall_log_penalty
        g = self.grid_options.to_dict()
        d["grid_options"] = {k: (None if isinstance(v, float) and math.isinf(v) else v) for k, v in g.items()}
        return d


@dataclass
class WalkScore:
    floor: str
    walk: str
    t_s: np.ndarray                                  #: waypoint times since the walk's first waypoint
    errors_m: Dict[str, np.ndarray] = field(default_factory=dict)
    seconds: Dict[str, float] = field(default_factory=dict)
    floor_correct: Optional[np.ndarray] = None       #: floor identification at the waypoints
    floor_free_errors_m: Optional[np.ndarray] = None  #: position error of that run
    floor_probability: Optional[float] = None  #: the calibrated probability reported for the floor chosen
    #: Distance [m] from each waypoint to the nearest training scan of its floor (survey coverage).
    coverage_m: Optional[np.ndarray] = None
    #: Per method with a covariance: whether each waypoint lies in the estimate's 95 % ellipse.
    in_region95: Dict[str, np.ndarray] = field(default_factory=dict)
    #: Per method with a heading-offset state: final offset minus the walk's residual [rad].
    offset_error_rad: Dict[str, float] = field(default_factory=dict)
    #: The walk's heading residual measured from its waypoints [rad] (``heading_residual_rad``).
    heading_residual_rad: Optional[float] = None
    waypoint_t0: float = 0.0                          #: the first waypoint's time [s]
    waypoint_xy_m: Optional[np.ndarray] = None        #: surveyed waypoints (W, 2) [m]
    smoothed_track_m: Optional[np.ndarray] = None     #: the default's smoothed track (per step)
    #: fusion_live: time from the first waypoint to the live tracker's first located estimate [s]
    #: (None: never located, or not run) and the waypoints before it (scored with that estimate).
    live_first_position_s: Optional[float] = None
    live_waypoints_before_position: int = 0
    #: Per grid method: what the covariance calibration is fitted on (``fusion_uncertainty``):
    #: ``error_m`` (W, 2) estimate minus truth, ``posterior_covariance_m2`` (W, 3), ``fix_distance_m`` (W,),
    #: ``fix_sd_m`` (W,).
    calibration_inputs: Dict[str, Dict[str, np.ndarray]] = field(default_factory=dict)


@dataclass
class FloorData:
    """One floor's walks, plan and detected steps."""

    name: str
    number: int
    walks: List[Any]
    plan: Any
    steps: List[ph.HandheldSteps]
    geojson_path: Path
    outline_plan: Any = None   #: the outline without shops (the no-walls ablation keeps the extent)
    load_report: Optional[Dict[str, Any]] = None  #: walks skipped, fields dropped (IlcFloor.load_report)


@dataclass
class FoldModels:
    """What a fold's training walks give one floor: PDR calibration, crowdsourced cell map,
    fingerprint database; and the all-floor plan and database for floor identification."""

    floor: FloorData
    cal: ph.HandheldCalibration
    crowd: Optional[wc.CrowdMap]  #: None unless the wifi_model method runs
    database: wfx.FingerprintDatabase
    all_plan: Any = None
    all_database: Optional[wfx.FingerprintDatabase] = None
    all_ap_rates: Any = None  #: per-floor AP detection rates of all_database (fusion.floor_evidence)
    #: Every floor's calibration in building order (floor identification: site_model.identification_calibration).
    all_calibrations: Optional[List[ph.HandheldCalibration]] = None
    #: ``scipy.spatial.cKDTree`` of the floor's training scan positions (survey coverage), or None.
    coverage_tree: Any = None
    #: ``wifi.GridPosterior`` of ``crowd`` (the wifi_model method), built once per fold, or None.
    crowd_grid: Any = None
    #: (path-loss model, cells (M, 2) [m], its predictions (M, K) [dBm]) when
    #: ``RealSettings.propagation_weight`` > 0, else None.
    propagation: Any = None
    #: (``wifi_heading_sequence.HeadingGrid`` of the floor with the fold's survey positions, its
    #: motion stencils) when the ``wifi_heading_sequence`` method runs, else None.
    heading: Any = None


def default_site_root() -> Path:
    """``shared/data/fusion/ilc2020_site2`` beside the WiFi data folder."""
    from indoorloc.registry import default_data_root

    return default_data_root().parent / "fusion" / "ilc2020_site2"
