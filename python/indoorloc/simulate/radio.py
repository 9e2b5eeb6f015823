"""WiFi radio of the synthetic building: a multi-wall log-distance model with correlated shadowing.

Mean received power [dBm] at a receiver at p on floor f from access point k (at a_k on floor g_k,
mounted ``ap_height_m`` above the receiver):

    m_k(p, f) = P0_k - 10 n log10(max(d, d0) / d0) - W N_wall(a_k, p) - W_obs N_obs(a_k, p)
                - F |f - g_k| + S_{k,f}(p),
    d = sqrt(|p - a_k|² + (ap_height_m + |f - g_k| floor_height_m)²)

with N_wall the thin walls and N_obs the obstacle ring edges (shafts, pillars) crossed by the
segment a_k -> p in plan (the layout is the same on every floor, so the plan count also stands
for the other floors' walls), F the loss per floor, and S_{k,f} a zero-mean stationary Gaussian
field per AP and receiver floor with a squared-exponential covariance sd² exp(-|Δp|²/(2 ℓ²)),
drawn as random Fourier features (Rahimi & Recht 2007):

    S(p) = sd sqrt(2/M) Σ_m cos(ω_m·p + b_m),  ω_m ~ N(0, I/ℓ²),  b_m ~ U(0, 2π).

A reading is m_k + e, e ~ N(0, noise_sd_db²), rounded to whole dBm as phones report it, and
reported as not heard (NaN) below ``sensitivity_dbm`` or, independently, with probability
``miss_probability`` (a beacon lost during the channel sweep).

Defaults: P0 = -40 dBm at 1 m (sd 2 dB between APs), n = 2.5 (free space 2, plus furniture and
people, as walls are counted separately), W = 4 dB per plasterboard wall (COST 231 multi-wall
"light wall" 3.4 dB), W_obs = 8 dB per concrete face, F = 15 dB per floor (COST 231: 18 dB),
shadowing sd 4 dB with ℓ = 4 m, noise 3 dB, sensitivity -95 dBm.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from indoorloc.simulate import _geometry as geo


@dataclass(frozen=True)
class RadioConfig:
    """Access points and propagation. Units: dBm, dB, m."""

    aps_per_floor: int = 24
    ap_room_fraction: float = 0.6          #: share of the APs placed in rooms, the rest in corridors
    ap_height_m: float = 1.5               #: AP (ceiling) above the receiver (hand height)
    p0_dbm: float = -40.0                  #: mean power at d0
    p0_sd_db: float = 2.0                  #: spread of P0 between APs (transmit power, antenna)
    d0_m: float = 1.0
    exponent: float = 2.5                  #: path-loss exponent n
    wall_attenuation_db: float = 4.0       #: W, per thin wall crossed
    obstacle_attenuation_db: float = 8.0   #: W_obs, per obstacle face (shaft, pillar) crossed
    floor_attenuation_db: float = 15.0     #: F, per floor between AP and receiver
    shadowing_sd_db: float = 4.0
    shadowing_length_m: float = 4.0        #: ℓ, correlation length of the shadowing field
    shadowing_features: int = 128          #: M, random Fourier features per AP and floor
    noise_sd_db: float = 3.0               #: per-reading measurement noise
    sensitivity_dbm: float = -95.0         #: readings below are not heard (NaN)
    miss_probability: float = 0.02         #: a heard AP missing from a scan at random
    quantize_dbm: bool = True              #: round readings to whole dBm

    def validate(self) -> None:
        for name in ("ap_height_m", "d0_m", "exponent", "shadowing_length_m"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"indoorloc: argument 'radio.{name}': must be finite and > 0, got {v}")
        for name in ("p0_sd_db", "wall_attenuation_db", "obstacle_attenuation_db", "floor_attenuation_db",
                     "shadowing_sd_db", "noise_sd_db"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise ValueError(f"indoorloc: argument 'radio.{name}': must be finite and >= 0, got {v}")
        if self.aps_per_floor < 1:
            raise ValueError("indoorloc: argument 'radio.aps_per_floor': must be >= 1")
        if self.shadowing_features < 1:
            raise ValueError("indoorloc: argument 'radio.shadowing_features': must be >= 1")
        if not (0.0 <= self.ap_room_fraction <= 1.0) or not (0.0 <= self.miss_probability < 1.0):
            raise ValueError("indoorloc: argument 'radio': ap_room_fraction in [0, 1], miss_probability in [0, 1)")


@dataclass(frozen=True)
class SurveyConfig:
    """The site survey that builds the signal map: static scans on a grid of walkable points."""

    spacing_m: float = 2.0                 #: grid spacing; grid nodes at spacing/2 + i spacing
    scans_per_point: int = 10
    wall_clearance_m: float = 0.3          #: grid nodes nearer a wall or obstacle are skipped

    def validate(self) -> None:
        if not (np.isfinite(self.spacing_m) and self.spacing_m > 0):
            raise ValueError(f"indoorloc: argument 'survey.spacing_m': must be > 0, got {self.spacing_m}")
        if self.scans_per_point < 1:
            raise ValueError("indoorloc: argument 'survey.scans_per_point': must be >= 1")
        if not (self.wall_clearance_m >= 0):
            raise ValueError("indoorloc: argument 'survey.wall_clearance_m': must be >= 0")


@dataclass
class RadioModel:
    """The true radio field of a building (K access points over all floors).

    Holds the AP table and the shadowing features; evaluates mean RSS and draws readings. The
    fusion filter never sees this object: it gets the survey's signal map.
    """

    config: RadioConfig
    ap_positions_m: np.ndarray          #: (K, 2) plan position
    ap_floors: np.ndarray               #: (K,) floor number of each AP
    ap_p0_dbm: np.ndarray               #: (K,) power at d0
    ap_in_room: np.ndarray              #: (K,) True: in a room, False: in a corridor
    floor_numbers: np.ndarray           #: (F,) floors of the building, ascending
    floor_height_m: float
    walls_m: np.ndarray                 #: (W, 4) thin walls (same on every floor)
    obstacle_edges_m: np.ndarray        #: (O, 4) edges of obstacle rings
    shadow_omega: np.ndarray            #: (F, K, M, 2) [rad/m] spatial frequencies
    shadow_phase: np.ndarray            #: (F, K, M) [rad]

    @property
    def num_access_points(self) -> int:
        return int(self.ap_positions_m.shape[0])

    def _floor_index(self, floor: int) -> int:
        hits = np.flatnonzero(self.floor_numbers == int(floor))
        if hits.size == 0:
            raise ValueError(f"indoorloc: argument 'floor': {floor} is not a floor of the building "
                             f"({self.floor_numbers.tolist()})")
        return int(hits[0])

    def walls_crossed_pairs(self, points_m: np.ndarray, ap_index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Thin walls and obstacle faces crossed by AP ap_index[i] -> points_m[i] in plan. Two (N,) ints."""
        p = np.asarray(points_m, float).reshape(-1, 2)
        a = self.ap_positions_m[np.asarray(ap_index, int).reshape(-1)]
        return geo.crossing_counts(a, p, self.walls_m), geo.crossing_counts(a, p, self.obstacle_edges_m)

    def walls_crossed(self, points_m: np.ndarray) -> np.ndarray:
        """Thin walls crossed by each AP -> point segment: (Q, K) int, vectorised and chunked."""
        p = np.asarray(points_m, float).reshape(-1, 2)
        q, k = p.shape[0], self.num_access_points
        w, _ = self.walls_crossed_pairs(np.repeat(p, k, axis=0), np.tile(np.arange(k), q))
        return w.reshape(q, k)

    def shadowing_pairs_db(self, points_m: np.ndarray, floor: int, ap_index: np.ndarray) -> np.ndarray:
        """S_{k,f}(p) for pairs (points_m[i], ap_index[i]) on receiver floor `floor`. (N,) [dB]."""
        p = np.asarray(points_m, float).reshape(-1, 2)
        k = np.asarray(ap_index, int).reshape(-1)
        fi = self._floor_index(floor)
        m = self.shadow_phase.shape[2]
        amp = self.config.shadowing_sd_db * np.sqrt(2.0 / m)
        out = np.empty(p.shape[0])
        rows = max(1, (1 << 20) // m)
        for i in range(0, p.shape[0], rows):
            sl = slice(i, min(p.shape[0], i + rows))
            om = self.shadow_omega[fi, k[sl]]                     # (n, M, 2)
            arg = om[..., 0] * p[sl, 0:1] + om[..., 1] * p[sl, 1:2] + self.shadow_phase[fi, k[sl]]
            out[sl] = amp * np.cos(arg).sum(axis=1)
        return out

    def mean_rss_pairs(self, points_m: np.ndarray, floor: int, ap_index: np.ndarray) -> np.ndarray:
        """True mean RSS [dBm] m_k(p, f) for pairs (points_m[i], ap_index[i]), receiver on `floor`. (N,)."""
        c = self.config
        p = np.asarray(points_m, float).reshape(-1, 2)
        k = np.asarray(ap_index, int).reshape(-1)
        if p.shape[0] != k.shape[0]:
            raise ValueError("indoorloc: argument 'ap_index': one AP index per point expected")
        if not np.all(np.isfinite(p)):
            raise ValueError("indoorloc: argument 'points_m': NaN or infinite coordinate")
        self._floor_index(floor)
        dfloor = np.abs(int(floor) - self.ap_floors[k])
        dz = c.ap_height_m + dfloor * self.floor_height_m
        d = np.sqrt(np.sum((p - self.ap_positions_m[k]) ** 2, axis=1) + dz**2)
        n_wall, n_obs = self.walls_crossed_pairs(p, k)
        return (self.ap_p0_dbm[k] - 10.0 * c.exponent * np.log10(np.maximum(d, c.d0_m) / c.d0_m)
                - c.wall_attenuation_db * n_wall - c.obstacle_attenuation_db * n_obs
                - c.floor_attenuation_db * dfloor + self.shadowing_pairs_db(p, floor, k))

    def mean_rss_dbm(self, points_m: np.ndarray, floor: int) -> np.ndarray:
        """True mean RSS [dBm] of every AP at each point (Q, 2) on `floor`: (Q, K), no noise, no cut-off."""
        p = np.asarray(points_m, float).reshape(-1, 2)
        q, k = p.shape[0], self.num_access_points
        return self.mean_rss_pairs(np.repeat(p, k, axis=0), floor, np.tile(np.arange(k), q)).reshape(q, k)

    def measure(self, mean_dbm: np.ndarray, rng: np.random.Generator, offset_db: float = 0.0) -> np.ndarray:
        """Readings [dBm] from true means (any shape): noise, device offset, rounding, NaN = not heard."""
        c = self.config
        mean = np.asarray(mean_dbm, float)
        noise = rng.normal(0.0, c.noise_sd_db, mean.shape)
        lost = rng.random(mean.shape) < c.miss_probability
        r = mean + offset_db + noise
        if c.quantize_dbm:
            r = np.round(r)
        r[(r < c.sensitivity_dbm) | lost] = np.nan
        return r


def make_radio_model(config: RadioConfig, ap_positions_m: np.ndarray, ap_floors: np.ndarray,
                     ap_in_room: np.ndarray, floor_numbers: np.ndarray, floor_height_m: float,
                     walls_m: np.ndarray, obstacle_edges_m: np.ndarray,
                     rng: np.random.Generator) -> RadioModel:
    """Draws per-AP powers and the shadowing features from `rng` (the building's radio stream)."""
    config.validate()
    k = ap_positions_m.shape[0]
    f = len(floor_numbers)
    m = config.shadowing_features
    p0 = config.p0_dbm + config.p0_sd_db * rng.standard_normal(k)
    omega = rng.standard_normal((f, k, m, 2)) / config.shadowing_length_m
    phase = rng.uniform(0.0, 2.0 * np.pi, (f, k, m))
    return RadioModel(config=config, ap_positions_m=np.asarray(ap_positions_m, float),
                      ap_floors=np.asarray(ap_floors, int), ap_p0_dbm=p0, ap_in_room=np.asarray(ap_in_room, bool),
                      floor_numbers=np.asarray(floor_numbers, int), floor_height_m=float(floor_height_m),
                      walls_m=np.asarray(walls_m, float).reshape(-1, 4),
                      obstacle_edges_m=np.asarray(obstacle_edges_m, float).reshape(-1, 4),
                      shadow_omega=omega, shadow_phase=phase)


@dataclass
class Survey:
    """Static survey scans at reference points: the only input of the signal map.

    rss_dbm (N, S, K): S scans per point, NaN = not heard. The per-point statistics below use
    the heard readings only (NaN where there are too few); ``to_signal_map`` instead applies the
    wifi subsystem's floor-value model (not heard -> -105 dBm) through ``SignalMap.from_scans``.
    """

    config: SurveyConfig
    positions_m: np.ndarray   #: (N, 2) reference points
    floors: np.ndarray        #: (N,) floor numbers
    rss_dbm: np.ndarray       #: (N, S, K) readings, NaN = not heard

    @property
    def num_points(self) -> int:
        return int(self.positions_m.shape[0])

    @property
    def heard_counts(self) -> np.ndarray:
        """(N, K) number of scans in which each AP was heard."""
        return np.sum(np.isfinite(self.rss_dbm), axis=1)

    @property
    def detection_rate(self) -> np.ndarray:
        """(N, K) fraction of the scans in which each AP was heard."""
        return self.heard_counts / self.rss_dbm.shape[1]

    @property
    def mean_dbm(self) -> np.ndarray:
        """(N, K) mean of the heard readings [dBm]; NaN where the AP was never heard at the point."""
        n = self.heard_counts
        s = np.nansum(self.rss_dbm, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(n > 0, s / np.maximum(n, 1), np.nan)

    @property
    def variance_db2(self) -> np.ndarray:
        """(N, K) unbiased variance of the heard readings [dB²]; NaN with fewer than 2 readings."""
        n = self.heard_counts
        mu = self.mean_dbm
        dev = np.where(np.isfinite(self.rss_dbm), self.rss_dbm - mu[:, None, :], 0.0)
        ss = np.sum(dev * dev, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(n > 1, ss / np.maximum(n - 1, 1), np.nan)

    def scans(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The survey as raw scans: positions (N S, 2) [m], floors (N S,), rss (N S, K) [dBm, NaN]."""
        n, s, k = self.rss_dbm.shape
        return (np.repeat(self.positions_m, s, axis=0), np.repeat(self.floors, s),
                self.rss_dbm.reshape(n * s, k))

    def to_signal_map(self, options: Optional[object] = None):
        """``indoorloc.wifi.SignalMap.from_scans`` of the survey scans (needs the compiled core).

        Keeps every AP heard somewhere (``min_point_fraction`` 0 by default), so the map's columns
        are the building's APs minus the never-heard ones: ``access_point_indices()`` says which.
        """
        from indoorloc._core import wifi  # simulate sits below the facades (docs/architecture.md)

        pos, fl, rss = self.scans()
        opts = options if options is not None else wifi.SignalMapOptions()
        return wifi.SignalMap.from_scans(pos, fl, rss, opts)


def run_survey(radio: RadioModel, positions_m: np.ndarray, floors: np.ndarray, config: SurveyConfig,
               rng: np.random.Generator) -> Survey:
    """Survey scans at given reference points (readings from the true field plus noise)."""
    config.validate()
    pos = np.asarray(positions_m, float).reshape(-1, 2)
    fl = np.asarray(floors, int).reshape(-1)
    k = radio.num_access_points
    mean = np.empty((pos.shape[0], k))
    for f in np.unique(fl):
        sel = fl == f
        mean[sel] = radio.mean_rss_dbm(pos[sel], int(f))
    rss = radio.measure(np.repeat(mean[:, None, :], config.scans_per_point, axis=1), rng)
    return Survey(config=config, positions_m=pos, floors=fl, rss_dbm=rss)
