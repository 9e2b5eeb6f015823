"""A crowdsourced WiFi signal map from walks with waypoints (issue 15, "A crowdsourced signal map").

Surveyors' walks (the Indoor Location Competition 2.0 format, :mod:`indoorloc.io`) carry WiFi
readings and a few surveyed waypoints; nobody stood still at reference points. This module turns
such walks into a :class:`indoorloc.wifi.SignalMap` (paper 004's per-point Gaussian model) and
into the scan matrices the fusion filter reads:

1. **Where was each reading measured?** (:func:`walk_positions`, :func:`reading_positions`).
   A reading's RSSI was measured at its last-seen time, not at the scan time (Android reports a
   cache, docs/fusion_data.md), so each distinct measurement (``new_measurement_mask``) is placed
   at the walker's position at its last-seen time. Between consecutive waypoints j, j+1 the
   position is the hand-held PDR path (:func:`indoorloc.pdr.handheld.handheld_steps`), mapped by
   the 2-D similarity (rotation + scale, one complex factor)

       s_j = (w_{j+1} - w_j) / (p(t_{j+1}) - p(t_j)),   x(t) = w_j + s_j (p(t) - p(t_j)),

   which makes the PDR segment start at waypoint j and end at waypoint j+1 (p the PDR path in
   the phone's frame, complex numbers for 2-D points). The fix absorbs the stride-length scale
   and the yaw offset, so no calibration is needed. An interval with fewer than
   ``min_interval_steps`` steps, a PDR displacement shorter than ``min_pdr_displacement_m`` or
   a scale outside ``max_scale_ratio`` falls back to linear interpolation in time. Before the
   first and after the last waypoint, positions are extrapolated for at most
   ``max_extrapolation_s`` (PDR with the neighbouring interval's similarity, or the neighbouring
   interval's constant velocity in ``"linear"`` mode); readings further out, or before the
   phone's first sensor sample (no motion is known before the recording starts), are dropped
   and counted.
2. **The map** (:func:`build_signal_map`): reference points are the visited cells of a square
   grid (``cell_size_m``), placed at the centroid of the positions that fell in the cell. Per
   cell and BSSID: the heard readings; the passes (scans whose measurement epoch, the median
   last-seen time of the scan's fresh readings, fell in the cell). An AP not heard on a pass
   enters at ``not_heard_dbm`` (the floor-value model of :class:`indoorloc.wifi.SignalMap`,
   the same as ``SignalMap.from_scans``): with n heard readings r_i among N = max(passes, n)
   passes, the mean is (Σ r_i + (N - n) f) / N and the variance the unbiased sample variance
   of those N values, shrunk towards the map's pooled variance of heard readings with
   ``variance_prior_weight`` pseudo-readings and floored at ``variance_floor_db2``. A cell that
   never heard the AP gets mean f and the floor variance. BSSIDs heard in fewer than
   ``min_walks`` training walks or ``min_cells`` cells are dropped.
3. **Scans of a walk as map columns** (:func:`scan_matrix`): per scan, the RSS of each map
   BSSID (NaN = not heard) and its age (scan time - last-seen time), unknown BSSIDs ignored,
   each measurement reported once (at the first scan that lists it) unless ``dedup=False``;
   ready for :func:`indoorloc.fusion.make_wifi_observations`.

How the defaults were chosen, and the cross-validated WiFi-only accuracy on the shared site:
docs/fusion_real.md ("Crowdsourced signal map"); the experiment is
:mod:`indoorloc.experiments.ilc_signal_map`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc.pdr import handheld
from indoorloc import wifi

POSITIONING = ("pdr", "linear")


@dataclass
class CrowdMapSettings:
    """Settings of the crowdsourced map and of the scan matrices (defaults: docs/fusion_real.md)."""

    positioning: str = "pdr"            #: "pdr" (similarity-corrected PDR) or "linear" (in time) between waypoints
    heading_source: str = "rotation_vector"  #: PDR heading (pdr.handheld.HEADING_SOURCES)
    min_interval_steps: float = 2.0     #: fewer steps in a waypoint interval -> linear interpolation
    min_pdr_displacement_m: float = 0.5 #: PDR displacement below this over an interval -> linear
    max_scale_ratio: float = 3.0        #: |s_j| outside [1/r, r] -> linear (PDR inconsistent with the waypoints)
    max_extrapolation_s: float = 3.0    #: before the first / after the last waypoint, at most this [s]
    cell_size_m: float = 3.0            #: grid cell of the reference points [m]
    fresh_age_s: float = 2.5            #: readings at most this old form a scan's current measurement epoch [s]
    min_walks: int = 2                  #: keep a BSSID heard in at least this many training walks
    min_cells: int = 2                  #: ... and in at least this many cells
    not_heard_dbm: float = -105.0       #: floor value of an AP not heard (SignalMapOptions.not_heard_dbm)
    variance_floor_db2: float = 4.0     #: minimum variance [dB^2] (SignalMapOptions.variance_floor_db2)
    variance_prior_weight: float = 2.0  #: pseudo-readings of the pooled variance in each cell's variance
    max_age_s: float = 2.5              #: staleness limit of a located scan (scan_matrix users; WiFi-only fixes)

    def validate(self) -> None:
        """Raises ValueError naming the first invalid field."""
        def bad(name: str, why: str) -> None:
            raise ValueError(f"indoorloc: CrowdMapSettings.{name}: {why}")
        if self.positioning not in POSITIONING:
            bad("positioning", f"{self.positioning!r} is not one of {POSITIONING}")
        if self.heading_source not in handheld.HEADING_SOURCES:
            bad("heading_source", f"{self.heading_source!r} is not one of {handheld.HEADING_SOURCES}")
        for name in ("cell_size_m", "fresh_age_s", "max_age_s", "max_scale_ratio"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                bad(name, f"must be finite and > 0, got {v}")
        for name in ("min_interval_steps", "min_pdr_displacement_m", "max_extrapolation_s",
                     "variance_prior_weight"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                bad(name, f"must be finite and >= 0, got {v}")
        # The ranges of the options they feed (RssModelOptions, TrackerOptions): outside them the
        # map's variances overflowed and were refused under the internal name 'variance_db2'.
        if not (math.isfinite(self.variance_floor_db2) and 1e-12 <= self.variance_floor_db2 <= 1e12):
            bad("variance_floor_db2", f"must be finite and in [1e-12, 1e12] dB^2, got {self.variance_floor_db2}")
        if not (math.isfinite(self.not_heard_dbm) and -300 < self.not_heard_dbm < 50):
            bad("not_heard_dbm", f"must be in (-300, 50) dBm, got {self.not_heard_dbm}")
        if not 1e-3 <= self.cell_size_m <= 1e6:
            bad("cell_size_m", f"must be in [0.001, 1e6] m, got {self.cell_size_m}")
        if self.max_scale_ratio < 1:
            bad("max_scale_ratio", "must be >= 1")
        if int(self.min_walks) < 1 or int(self.min_cells) < 1:
            bad("min_walks", "min_walks and min_cells must be >= 1")


# --------------------------------------------------------------------------------------------
# 1. Positions along a walk


@dataclass
class WalkPositions:
    """Positions at query times along one walk and how each was obtained."""

    xy_m: np.ndarray        #: (Q, 2) floor frame [m]; NaN where dropped
    valid: np.ndarray       #: (Q,) bool
    source: np.ndarray      #: (Q,) int8: 0 dropped, 1 PDR (similarity), 2 linear, 3 extrapolated
    n_intervals_pdr: int = 0      #: waypoint intervals placed by corrected PDR
    n_intervals_linear: int = 0   #: ... by linear interpolation (fallback or "linear" mode)

    @property
    def n_dropped(self) -> int:
        return int(np.count_nonzero(~self.valid))


def _similarities(p_at_wp: np.ndarray, wxy: np.ndarray, n_steps: np.ndarray,
                  s: CrowdMapSettings) -> Tuple[np.ndarray, np.ndarray]:
    """Per interval j: complex factor s_j and whether PDR is usable there."""
    dp = p_at_wp[1:] - p_at_wp[:-1]
    dw = wxy[1:] - wxy[:-1]
    zp = dp[:, 0] + 1j * dp[:, 1]
    zw = dw[:, 0] + 1j * dw[:, 1]
    ok = (n_steps >= s.min_interval_steps) & (np.abs(zp) >= s.min_pdr_displacement_m)
    fac = np.where(ok, zw / np.where(ok, zp, 1.0), 0.0)
    mag = np.abs(fac)
    ok &= (mag >= 1.0 / s.max_scale_ratio) & (mag <= s.max_scale_ratio)
    return fac, ok


def walk_positions(walk: Any, t_query_s: np.ndarray, settings: Optional[CrowdMapSettings] = None,
                   steps: Optional[handheld.HandheldSteps] = None) -> WalkPositions:
    """The walker's position at the query times (walk clock [s]) from the waypoints and PDR.

    Parameters
    ----------
    walk : IlcWalk
        Needs ``waypoint_t_s`` (W,), ``waypoint_xy_m`` (W, 2) and, for ``positioning="pdr"``,
        the sensor streams (or pass ``steps``).
    t_query_s : (Q,) array
    settings : CrowdMapSettings, optional
    steps : HandheldSteps, optional
        Steps of the walk (detected with ``HandheldOptions(heading_source=...)`` when absent).

    Returns
    -------
    WalkPositions
        See the module docstring for the method; queries outside
        [first waypoint - max_extrapolation_s, last + max_extrapolation_s], or before the first
        sensor sample in PDR mode, are dropped (NaN, ``valid`` False).
    """
    s = settings or CrowdMapSettings()
    s.validate()
    t = np.asarray(t_query_s, dtype=np.float64).reshape(-1)
    wt = np.asarray(walk.waypoint_t_s, dtype=np.float64)
    wxy = np.asarray(walk.waypoint_xy_m, dtype=np.float64)
    if wt.ndim != 1 or wxy.shape != (wt.shape[0], 2):  # a (2, 3) array was reshaped to (3, 2)
        raise ValueError(f"indoorloc: argument 'walk': waypoint_xy_m has shape {wxy.shape}, expected "
                         f"({wt.size}, 2) for its {wt.size} waypoint_t_s")
    q = t.shape[0]
    xy = np.full((q, 2), np.nan)
    source = np.zeros(q, dtype=np.int8)
    if wt.shape[0] == 0:
        return WalkPositions(xy, np.zeros(q, bool), source)
    if wt.shape[0] == 1:
        near = np.abs(t - wt[0]) <= s.max_extrapolation_s
        xy[near] = wxy[0]
        source[near] = 3
        return WalkPositions(xy, near, source)
    n_int = wt.shape[0] - 1
    # Interval of each query: j with wt[j] <= t < wt[j+1] (clipped to the ends).
    j = np.clip(np.searchsorted(wt, t, side="right") - 1, 0, n_int - 1)
    dt = np.diff(wt)
    vel = (wxy[1:] - wxy[:-1]) / np.where(dt > 0, dt, 1.0)[:, None]
    inside = (t >= wt[0]) & (t <= wt[-1])
    before = (t < wt[0]) & (t >= wt[0] - s.max_extrapolation_s)
    after = (t > wt[-1]) & (t <= wt[-1] + s.max_extrapolation_s)
    # Linear interpolation in time (and constant-velocity extrapolation).
    lin = wxy[j] + vel[j] * (t - wt[j])[:, None]
    # Before the first sensor sample the walker's motion is unknown (both modes).
    acc = getattr(walk, "accelerometer", None)
    t0_sensor = float(acc.t_s[0]) if acc is not None and acc.t_s.size else -np.inf
    before &= t >= t0_sensor - 1e-9
    use_pdr = np.zeros(n_int, dtype=bool)
    if s.positioning == "pdr":
        if steps is None:
            steps = handheld.handheld_steps(walk, handheld.HandheldOptions(heading_source=s.heading_source))
        disp = handheld.step_displacements(steps, s.heading_source)
        ones_disp = np.column_stack([np.ones(steps.n_steps), disp])
        at_wp = handheld.cumulative_at(steps, ones_disp, wt)
        fac, use_pdr = _similarities(at_wp[:, 1:], wxy, np.diff(at_wp[:, 0]), s)
        p = handheld.cumulative_at(steps, disp, t)
        # Extrapolation uses the nearest usable interval's similarity.
        jj = j.copy()
        if use_pdr.any():
            usable = np.flatnonzero(use_pdr)
            jj[before] = usable[0]
            jj[after] = usable[-1]
        anchor = np.where(t[:, None] < wt[0], wxy[0], np.where(t[:, None] > wt[-1], wxy[-1], wxy[j]))
        anchor_t = np.where(t < wt[0], wt[0], np.where(t > wt[-1], wt[-1], wt[j]))
        p_anchor = handheld.cumulative_at(steps, disp, anchor_t)
        d = p - p_anchor
        z = fac[jj] * (d[:, 0] + 1j * d[:, 1])
        pdr_xy = anchor + np.column_stack([z.real, z.imag])
        pdr_ok = use_pdr[jj]
        # Interior: PDR where usable, else linear.
        m = inside & pdr_ok
        xy[m], source[m] = pdr_xy[m], 1
        m = inside & ~pdr_ok
        xy[m], source[m] = lin[m], 2
        # Outside: PDR with the neighbouring usable interval; needs sensor data at t.
        m = (before | after) & use_pdr.any()
        xy[m], source[m] = pdr_xy[m], 3
    else:
        xy[inside], source[inside] = lin[inside], 2
        m = before | after
        xy[m], source[m] = lin[m], 3
    return WalkPositions(xy, source > 0, source, int(use_pdr.sum()), int(n_int - use_pdr.sum()))


@dataclass
class PlacedReadings:
    """The distinct WiFi measurements of one walk placed at their last-seen time."""

    bssids: List[str]          #: the walk's BSSID vocabulary (IlcWifi.bssids)
    bssid_index: np.ndarray    #: (P,) into bssids
    rssi_dbm: np.ndarray       #: (P,)
    t_s: np.ndarray            #: (P,) last-seen time [s]
    xy_m: np.ndarray           #: (P, 2)
    epoch_xy_m: np.ndarray     #: (E, 2) positions of the scans' measurement epochs (passes)
    n_measurements: int        #: distinct measurements of the walk
    n_dropped: int             #: ... dropped (outside the waypoints + extrapolation, no IMU)
    n_epochs_dropped: int
    n_intervals_pdr: int
    n_intervals_linear: int


def scan_epochs(wf: Any, fresh_age_s: float) -> np.ndarray:
    """(S,) measurement time of each scan: the median last-seen time of its readings at most
    ``fresh_age_s`` old, NaN for a scan without such a reading (documented: that scan has no
    epoch)."""
    if not (isinstance(fresh_age_s, (int, float, np.floating, np.integer)) and math.isfinite(fresh_age_s)
            and fresh_age_s >= 0):
        raise ValueError(f"indoorloc: argument 'fresh_age_s': must be a finite number >= 0 [s], got {fresh_age_s!r}")
    age = wf.age_s
    fresh = age <= fresh_age_s
    sid = wf.scan_index
    out = np.full(wf.n_scans, np.nan)
    if not fresh.any():
        return out
    order = np.lexsort((wf.last_seen_s[fresh], sid[fresh]))
    ss, ls = sid[fresh][order], wf.last_seen_s[fresh][order]
    starts = np.flatnonzero(np.r_[True, ss[1:] != ss[:-1]])
    ends = np.r_[starts[1:], ss.shape[0]]
    for a, b in zip(starts, ends):  # one per scan (a few dozen per walk)
        out[ss[a]] = np.median(ls[a:b])
    return out


def reading_positions(walk: Any, settings: Optional[CrowdMapSettings] = None,
                      steps: Optional[handheld.HandheldSteps] = None) -> PlacedReadings:
    """Places every distinct WiFi measurement of a walk (``new_measurement_mask``) at the
    walker's position at its last-seen time (:func:`walk_positions`); also the scans' epochs."""
    s = settings or CrowdMapSettings()
    wf = walk.wifi
    new = wf.new_measurement_mask()
    t_read = wf.last_seen_s[new]
    epochs = scan_epochs(wf, s.fresh_age_s)
    epochs = epochs[np.isfinite(epochs)]
    if s.positioning == "pdr" and steps is None and (t_read.size or epochs.size):
        steps = handheld.handheld_steps(walk, handheld.HandheldOptions(heading_source=s.heading_source))
    pos = walk_positions(walk, np.concatenate([t_read, epochs]), s, steps)
    r = t_read.shape[0]
    ok_r, ok_e = pos.valid[:r], pos.valid[r:]
    return PlacedReadings(
        bssids=list(wf.bssids), bssid_index=wf.bssid_index[new][ok_r], rssi_dbm=wf.rssi_dbm[new][ok_r],
        t_s=t_read[ok_r], xy_m=pos.xy_m[:r][ok_r], epoch_xy_m=pos.xy_m[r:][ok_e],
        n_measurements=int(r), n_dropped=int(np.count_nonzero(~ok_r)),
        n_epochs_dropped=int(np.count_nonzero(~ok_e)),
        n_intervals_pdr=pos.n_intervals_pdr, n_intervals_linear=pos.n_intervals_linear)


# --------------------------------------------------------------------------------------------
# 2. The map


@dataclass
class CrowdMapSummary:
    """Diagnostics of :func:`build_signal_map`."""

    n_walks: int
    n_cells: int
    n_bssids_heard: int
    n_bssids_kept: int
    n_readings_used: int
    n_readings_dropped: int
    pooled_variance_db2: float
    detection_rate: np.ndarray = field(repr=False)   #: (N, K) heard readings / passes, capped at 1
    passes: np.ndarray = field(repr=False)           #: (N,) passes per cell
    heard_counts: np.ndarray = field(repr=False)     #: (N, K) heard readings per cell and BSSID

    def brief_report(self) -> str:
        return (f"crowd map: {self.n_walks} walks, {self.n_cells} cells, {self.n_bssids_kept} of "
                f"{self.n_bssids_heard} BSSIDs kept, {self.n_readings_used} readings placed "
                f"({self.n_readings_dropped} dropped), pooled sd {math.sqrt(self.pooled_variance_db2):.1f} dB")


def _cell_keys(xy: np.ndarray, cell: float) -> np.ndarray:
    ij = np.floor(xy / cell).astype(np.int64)
    return ij[:, 0] * 1_000_003 + ij[:, 1]


def map_statistics(placed: Sequence[PlacedReadings], settings: Optional[CrowdMapSettings] = None
                   ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, List[str], CrowdMapSummary]:
    """(positions (N, 2), mean (N, K), variance (N, K), bssids (K), summary) from placed readings.

    See the module docstring for the estimator. Raises ValueError when no BSSID or fewer than 3
    cells remain (a SignalMap / RssModel needs them).
    """
    s = settings or CrowdMapSettings()
    s.validate()
    # Global BSSID vocabulary over the walks.
    names = sorted({b for p in placed for b in p.bssids})
    index = {b: k for k, b in enumerate(names)}
    xy_r, b_r, rss_r, walk_r, xy_e = [], [], [], [], []
    for w, p in enumerate(placed):
        lut = np.array([index[b] for b in p.bssids], dtype=np.int64) if p.bssids else np.zeros(0, np.int64)
        xy_r.append(p.xy_m)
        b_r.append(lut[p.bssid_index])
        rss_r.append(p.rssi_dbm)
        walk_r.append(np.full(p.rssi_dbm.shape[0], w))
        xy_e.append(p.epoch_xy_m)
    xy_r = np.concatenate(xy_r) if xy_r else np.zeros((0, 2))
    b_r = np.concatenate(b_r).astype(np.int64) if b_r else np.zeros(0, np.int64)
    rss_r = np.concatenate(rss_r) if rss_r else np.zeros(0)
    walk_r = np.concatenate(walk_r) if walk_r else np.zeros(0, np.int64)
    xy_e = np.concatenate(xy_e) if xy_e else np.zeros((0, 2))
    # Cells: every cell with a reading or a pass.
    keys_r = _cell_keys(xy_r, s.cell_size_m)
    keys_e = _cell_keys(xy_e, s.cell_size_m)
    cells, inv = np.unique(np.concatenate([keys_r, keys_e]), return_inverse=True)
    c_r, c_e = inv[: keys_r.shape[0]], inv[keys_r.shape[0]:]
    n_cells = cells.shape[0]
    # BSSID selection: walks and cells in which it is heard.
    v = len(names)
    walks_of = np.zeros(v, np.int64)
    if b_r.size:
        # Distinct (BSSID, walk) and (BSSID, cell) pairs, each as one integer key (a row-wise
        # np.unique sorts rows as opaque bytes, several times slower; the counts are the same).
        n_w = int(walk_r.max()) + 1
        walks_of = np.bincount(np.unique(b_r * n_w + walk_r) // n_w, minlength=v)
        cells_of = np.bincount(np.unique(b_r * n_cells + c_r) // n_cells, minlength=v)
    else:
        cells_of = np.zeros(v, np.int64)
    keep = (walks_of >= int(s.min_walks)) & (cells_of >= int(s.min_cells))
    kept = np.flatnonzero(keep)
    if kept.size == 0:
        raise ValueError("indoorloc: build_signal_map: no BSSID heard in enough walks and cells "
                         f"(min_walks={s.min_walks}, min_cells={s.min_cells})")
    if n_cells < 3:
        raise ValueError(f"indoorloc: build_signal_map: {n_cells} cells; need at least 3")
    col = np.full(v, -1, np.int64)
    col[kept] = np.arange(kept.size)
    k = kept.size
    sel = col[b_r] >= 0 if b_r.size else np.zeros(0, bool)
    flat = c_r[sel] * k + col[b_r[sel]]
    cnt = np.bincount(flat, minlength=n_cells * k).reshape(n_cells, k).astype(np.float64)
    sm = np.bincount(flat, weights=rss_r[sel], minlength=n_cells * k).reshape(n_cells, k)
    sq = np.bincount(flat, weights=rss_r[sel] ** 2, minlength=n_cells * k).reshape(n_cells, k)
    passes = np.bincount(c_e, minlength=n_cells).astype(np.float64)
    # Pooled within-cell variance of heard readings (cells with >= 2 readings).
    m2 = cnt >= 2
    dev = np.where(m2, sq - sm * sm / np.maximum(cnt, 1), 0.0)
    dof = np.where(m2, cnt - 1, 0.0).sum()
    pooled = float(dev.sum() / dof) if dof > 0 else s.variance_floor_db2
    pooled = max(pooled, s.variance_floor_db2)
    # Floor-value model over N = max(passes, heard) values per (cell, AP).
    n_tot = np.maximum(passes[:, None], cnt)
    n_tot = np.maximum(n_tot, 1.0)
    f = s.not_heard_dbm
    n_nh = n_tot - cnt
    s1 = sm + n_nh * f
    s2 = sq + n_nh * f * f
    mean = s1 / n_tot
    ss = np.maximum(s2 - s1 * s1 / n_tot, 0.0)
    heard_any = cnt > 0
    w0 = s.variance_prior_weight
    denom = (n_tot - 1) + w0
    var = np.where(denom > 0, (ss + w0 * pooled) / np.where(denom > 0, denom, 1.0), s.variance_floor_db2)
    var = np.where(heard_any, var, s.variance_floor_db2)
    var = np.maximum(var, s.variance_floor_db2)
    # Cell position: centroid of the passes, else of the readings.
    pos = np.zeros((n_cells, 2))
    ne = np.bincount(c_e, minlength=n_cells)
    for d in range(2):
        se = np.bincount(c_e, weights=xy_e[:, d], minlength=n_cells)
        sr = np.bincount(c_r, weights=xy_r[:, d], minlength=n_cells)
        nr = np.bincount(c_r, minlength=n_cells)
        pos[:, d] = np.where(ne > 0, se / np.maximum(ne, 1), sr / np.maximum(nr, 1))
    det = np.minimum(cnt / np.maximum(passes[:, None], 1.0), 1.0)
    summary = CrowdMapSummary(
        n_walks=len(placed), n_cells=n_cells, n_bssids_heard=int(np.count_nonzero(walks_of)),
        n_bssids_kept=k, n_readings_used=int(sel.sum()),
        n_readings_dropped=int(sum(p.n_dropped for p in placed)), pooled_variance_db2=pooled,
        detection_rate=det, passes=passes, heard_counts=cnt)
    return pos, mean, var, [names[i] for i in kept], summary


@dataclass
class CrowdMap:
    """What :func:`build_crowd_map` returns: the map, its model, the BSSID of each column."""

    signal_map: Any            #: wifi.SignalMap
    model: Any                 #: wifi.RssModel
    bssids: List[str]          #: (K,) map column -> BSSID
    summary: CrowdMapSummary
    settings: CrowdMapSettings


def build_crowd_map(train_walks: Sequence[Any], settings: Optional[CrowdMapSettings] = None, floor: int = 0,
                    placed: Optional[Sequence[PlacedReadings]] = None,
                    model_options: Optional[Any] = None) -> CrowdMap:
    """:class:`CrowdMap` from training walks (or their :class:`PlacedReadings`, computed once)."""
    s = settings or CrowdMapSettings()
    s.validate()
    if placed is None:
        placed = [reading_positions(w, s) for w in train_walks]
    pos, mean, var, bssids, summary = map_statistics(placed, s)
    m = wifi.SignalMap(pos, np.full(pos.shape[0], int(floor), dtype=np.int32), mean, var)
    model = wifi.RssModel(m, model_options if model_options is not None
                          else wifi.RssModelOptions(variance_floor_db2=s.variance_floor_db2))
    return CrowdMap(m, model, bssids, summary, s)


def build_signal_map(train_walks: Sequence[Any], floor_info: Any = None,
                     settings: Optional[CrowdMapSettings] = None) -> Tuple[Any, Any, List[str]]:
    """(SignalMap, RssModel, bssids) from the training walks of one floor.

    Parameters
    ----------
    train_walks : sequence of IlcWalk
        Walks with waypoints, WiFi and sensor streams.
    floor_info : IlcFloor, int or None
        The floor: its ``floor_number`` attribute or the int itself is the SignalMap's floor
        number (0 when absent), so that the map agrees with a multi-floor FloorPlan.
    settings : CrowdMapSettings, optional

    Returns
    -------
    signal_map : wifi.SignalMap
        Cells (N) x kept BSSIDs (K): mean [dBm], variance [dB^2].
    model : wifi.RssModel
    bssids : list of str
        Map column -> BSSID, for :func:`scan_matrix`.
    """
    floor = floor_info if isinstance(floor_info, (int, np.integer)) else int(getattr(floor_info, "floor_number", 0) or 0)
    cm = build_crowd_map(train_walks, settings, int(floor))
    return cm.signal_map, cm.model, cm.bssids


# --------------------------------------------------------------------------------------------
# 3. Scans of a walk in the map's columns


def scan_matrix(walk: Any, bssids: Sequence[str], settings: Optional[CrowdMapSettings] = None,
                dedup: bool = True, max_age_s: Optional[float] = None
                ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per scan of a walk, the readings in the map's columns with their ages.

    Parameters
    ----------
    walk : IlcWalk
    bssids : sequence of str, length K
        Map column -> BSSID (from :func:`build_signal_map`); BSSIDs of the walk not in it are
        ignored.
    settings : CrowdMapSettings, optional
        Unused except for ``max_age_s`` when ``max_age_s`` is "settings" (see below).
    dedup : bool
        True (for the fusion filter): a measurement (BSSID, last-seen time) repeated by later
        scans appears once, at the first scan that reports it. False: every scan as listed.
    max_age_s : float or None
        Readings older than this are left out (NaN); None keeps every age (the filter re-times
        them with ``at_own_time``).

    Returns
    -------
    scan_times_s : (S,) float64
    rss_dbm : (S, K) float64, NaN = not heard
    ages_s : (S, K) float64, scan time - last-seen time [s] (>= 0), NaN where not heard

    When a scan lists one BSSID twice (two channels), the freshest reading is kept (the
    stronger at equal age).
    """
    wf = walk.wifi
    times = wf.scan_times_s.astype(np.float64)
    k = len(bssids)
    rss = np.full((wf.n_scans, k), np.nan)
    ages = np.full((wf.n_scans, k), np.nan)
    if wf.n_readings == 0 or k == 0:
        return times, rss, ages
    index = {b: i for i, b in enumerate(bssids)}
    lut = np.array([index.get(b, -1) for b in wf.bssids], dtype=np.int64)
    colr = lut[wf.bssid_index]
    age = np.maximum(wf.age_s, 0.0)
    sel = colr >= 0
    if dedup:
        sel &= wf.new_measurement_mask()
    if max_age_s is not None:
        sel &= age <= max_age_s
    idx = np.flatnonzero(sel)
    if idx.size == 0:  # the walk heard none of the map's APs (or none fresh enough): all NaN
        return times, rss, ages
    sid = wf.scan_index[idx]
    # Order so that for each (scan, column) the preferred reading comes last: older first,
    # then weaker first; assignment keeps the last.
    order = np.lexsort((wf.rssi_dbm[idx], -age[idx], colr[idx], sid))
    idx, sid = idx[order], sid[order]
    c = colr[idx]
    last = np.r_[(sid[1:] != sid[:-1]) | (c[1:] != c[:-1]), True]
    idx, sid = idx[last], sid[last]
    rss[sid, colr[idx]] = wf.rssi_dbm[idx]
    ages[sid, colr[idx]] = age[idx]
    return times, rss, ages


def prepare(rss_dbm: np.ndarray, not_heard_dbm: float) -> np.ndarray:
    """NaN (not heard) -> the floor value ``not_heard_dbm`` (finite) [dBm]: the prepared scans of
    the locators. An infinite RSS is refused (NaN is the only 'not heard')."""
    v = float(not_heard_dbm)
    if not (math.isfinite(v) and -300 < v < 50):
        raise ValueError(f"indoorloc: argument 'not_heard_dbm': must be in (-300, 50) dBm, got {not_heard_dbm!r}")
    r = np.asarray(rss_dbm, dtype=np.float64)
    if np.isinf(r).any():
        raise ValueError("indoorloc: argument 'rss_dbm': holds an infinite value (NaN marks 'not heard')")
    return np.where(np.isnan(r), v, r)


__all__ = [
    "POSITIONING",
    "CrowdMap",
    "CrowdMapSettings",
    "CrowdMapSummary",
    "PlacedReadings",
    "WalkPositions",
    "build_crowd_map",
    "build_signal_map",
    "map_statistics",
    "prepare",
    "reading_positions",
    "scan_epochs",
    "scan_matrix",
    "walk_positions",
]
