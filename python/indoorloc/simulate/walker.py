"""A person walking through the synthetic building: route, steps, PDR errors, WiFi scans.

Route. Rooms are visited in random order (each next room uniform among the other open rooms);
between two rooms the walker follows a shortest path of the building's walk graph (corridor
centre lines, door axes). Inside a visited room it walks to two random points at least
``room_margin_m`` from the walls (clear of the pillar, turning at most ``max_room_turn_rad``) and may stand still at the first for
``pause_s`` seconds (probability ``pause_probability``; no steps then, scans go on). Corners of
the polyline are rounded by quadratic Bézier arcs that start ``corner_cut_m`` before the corner
(at most 45 % of either leg, approach_m - 5 cm at door approach points), so the curve stays within the
triangle of each corner and never reaches a door jamb.

Gait. Per walk: mean step length L̄ ~ N(step_length_m, step_length_walker_sd_m²) and cadence
f̄ ~ N(step_frequency_hz, step_frequency_walker_sd_hz²); per step: length L̄ (1 + 0.05 ε) and
period (1 + 0.03 ε) / f̄. The true step is the chord between consecutive true positions on the
path: length ℓ_k and heading θ_k = atan2(Δy, Δx) (x east, counter-clockwise, as in pdr's eq. 8),
so dead reckoning with the true (ℓ, θ) reproduces the true positions exactly.

PDR errors (walker.PdrErrorConfig):
    length_k  = s ℓ_k + σ_L ε_k,                      s ~ N(1, scale_sd²) per walk
    heading_k = θ_k + b + δ_k + σ_ψ η_k,              b ~ U(-b_max, b_max) per walk,
    δ_k = δ_{k-1} + σ_δ ζ_k                          (gyro drift, a random walk per step),
a true step is not reported with probability ``missed_step_probability`` and a false step
(length ≈ s L̄, the current heading) is reported between two true steps with probability
``extra_step_probability``. The reported sds are σ_L and σ_ψ: the white part; s, b and δ are
what a filter's scale and heading-offset states (with σ_δ as process noise) must absorb.

Scans. One scan every ``interval_s`` (random phase, jitter ``jitter_s``). Each AP's reading
carries a "last seen" age: fresh (U(0, fresh_age_max_s)) or, with probability
``stale_probability``, stale (U(stale_age_s)): such a reading is measured at the walker's true
position at time t - age (a phone reports cached results of an earlier sweep). Readings follow
the building's radio model (noise, rounding, sensitivity, random misses) plus ``device_offset_db``.

Randomness: ``numpy.random.default_rng([seed, 0x3A1C, stream])``, streams 0 route, 1 gait,
2 PDR errors, 3 scans, independent of the building's seed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional, Tuple

import numpy as np

from indoorloc.simulate import _geometry as geo
from indoorloc.simulate.building import APPROACH, Building
from indoorloc.validate import integer

_DOMAIN = 0x3A1C
_ROUTE_STREAM, _GAIT_STREAM, _PDR_STREAM, _SCAN_STREAM = 0, 1, 2, 3


@dataclass(frozen=True)
class WalkConfig:
    """The walk: duration, gait, route shape. Seconds, metres, Hz."""

    duration_s: float = 90.0
    step_length_m: float = 0.7
    step_length_walker_sd_m: float = 0.05     #: spread of the mean step length between walks
    step_length_sd_fraction: float = 0.05     #: step-to-step variability
    step_frequency_hz: float = 1.8
    step_frequency_walker_sd_hz: float = 0.1
    step_period_sd_fraction: float = 0.03
    corner_cut_m: float = 1.0
    pause_probability: float = 0.5            #: per visited room
    pause_s: Tuple[float, float] = (2.0, 6.0)
    room_margin_m: float = 0.7
    max_room_turn_rad: float = float(np.deg2rad(110.0))  #: turn limit at the points visited in a room
    dense_rate_hz: float = 10.0               #: rate of the dense truth

    def validate(self) -> None:
        for name in ("duration_s", "step_length_m", "step_frequency_hz", "corner_cut_m", "room_margin_m",
                     "dense_rate_hz"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"indoorloc: argument 'walk.{name}': must be finite and > 0, got {v}")
        if not (0 <= self.pause_probability <= 1) or not (0 <= self.pause_s[0] <= self.pause_s[1]):
            raise ValueError("indoorloc: argument 'walk': pause_probability in [0, 1], pause_s ordered and >= 0")


@dataclass(frozen=True)
class PdrErrorConfig:
    """Errors of the measured steps (see the module docstring for the model)."""

    scale_sd: float = 0.08
    heading_bias_max_rad: float = float(np.deg2rad(20.0))
    heading_drift_sd_rad: float = float(np.deg2rad(0.7))    #: σ_δ per √step
    length_noise_sd_m: float = 0.05                          #: σ_L
    heading_noise_sd_rad: float = float(np.deg2rad(3.0))     #: σ_ψ
    missed_step_probability: float = 0.02
    extra_step_probability: float = 0.01

    def validate(self) -> None:
        for name in ("scale_sd", "heading_bias_max_rad", "heading_drift_sd_rad", "length_noise_sd_m",
                     "heading_noise_sd_rad"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise ValueError(f"indoorloc: argument 'pdr.{name}': must be finite and >= 0, got {v}")
        if not (0 <= self.missed_step_probability < 1 and 0 <= self.extra_step_probability < 1):
            raise ValueError("indoorloc: argument 'pdr': step probabilities must be in [0, 1)")


@dataclass(frozen=True)
class ScanConfig:
    """WiFi scans along the walk."""

    interval_s: float = 2.0
    jitter_s: float = 0.1
    fresh_age_max_s: float = 0.5
    stale_probability: float = 0.2
    stale_age_s: Tuple[float, float] = (1.0, 10.0)
    device_offset_db: float = 0.0             #: walker's phone against the survey device

    def validate(self) -> None:
        if not (np.isfinite(self.interval_s) and self.interval_s > 0) or not (0 <= self.jitter_s < self.interval_s / 2):
            raise ValueError("indoorloc: argument 'scans': interval_s > 0 and 0 <= jitter_s < interval_s / 2")
        if not (0 <= self.stale_probability <= 1) or not (0 <= self.stale_age_s[0] <= self.stale_age_s[1]):
            raise ValueError("indoorloc: argument 'scans': stale_probability in [0, 1], stale_age_s ordered")
        if not (self.fresh_age_max_s >= 0):
            raise ValueError("indoorloc: argument 'scans.fresh_age_max_s': must be >= 0")


@dataclass
class Trajectory:
    """The true motion: a dense path and the arc length travelled as a function of time."""

    path_m: np.ndarray         #: (P, 2) dense polyline (about 5 cm spacing)
    path_arc_m: np.ndarray     #: (P,) arc length along it
    knot_time_s: np.ndarray    #: (Kn,) increasing times ...
    knot_arc_m: np.ndarray     #: (Kn,) ... and arc lengths (linear in between; flat while standing)

    def arc_at(self, time_s: np.ndarray) -> np.ndarray:
        return np.interp(np.asarray(time_s, float), self.knot_time_s, self.knot_arc_m)

    def position_at(self, time_s: np.ndarray) -> np.ndarray:
        """True position(s) [m] at time(s) [s]; shape (..., 2)."""
        s = self.arc_at(time_s)
        return np.stack([np.interp(s, self.path_arc_m, self.path_m[:, 0]),
                         np.interp(s, self.path_arc_m, self.path_m[:, 1])], axis=-1)

    def heading_at(self, time_s: np.ndarray) -> np.ndarray:
        """Direction of the path tangent [rad] at time(s) [s] (held while standing)."""
        s = self.arc_at(time_s)
        i = np.clip(np.searchsorted(self.path_arc_m, s, side="right") - 1, 0, self.path_m.shape[0] - 2)
        d = self.path_m[i + 1] - self.path_m[i]
        return np.arctan2(d[..., 1], d[..., 0])


@dataclass
class TrueSteps:
    """The steps actually taken (M). Step k moves from position_m[k-1] (start_position for k=0)."""

    start_time_s: np.ndarray   #: (M,) foot lift
    time_s: np.ndarray         #: (M,) step completed
    position_m: np.ndarray     #: (M, 2) position after the step
    length_m: np.ndarray       #: (M,) chord length
    heading_rad: np.ndarray    #: (M,) chord direction
    missed: np.ndarray         #: (M,) bool: not reported by the PDR


@dataclass
class PdrSteps:
    """Measured steps (M' = M - missed + extra), sorted by time: what the filter gets."""

    time_s: np.ndarray
    length_m: np.ndarray
    heading_rad: np.ndarray        #: in (-π, π]
    length_sd_m: np.ndarray        #: reported sd of length (σ_L)
    heading_sd_rad: np.ndarray     #: reported sd of heading (σ_ψ)
    true_position_m: np.ndarray    #: (M', 2) true position at time_s
    true_step: np.ndarray          #: (M',) index into TrueSteps, -1 for a false step
    heading_drift_rad: np.ndarray  #: (M',) drift δ at that step
    scale: float                   #: per-walk stride-length scale s
    heading_bias_rad: float        #: per-walk heading bias b

    @property
    def is_extra(self) -> np.ndarray:
        return self.true_step < 0

    @property
    def num_steps(self) -> int:
        return int(self.time_s.size)


@dataclass
class Scans:
    """WiFi scans along the walk (S scans, K APs of the whole building)."""

    floor: int
    time_s: np.ndarray              #: (S,) scan time
    rss_dbm: np.ndarray             #: (S, K) NaN = not heard
    age_s: np.ndarray               #: (S, K) how old each reading is at scan time; NaN where not heard
    true_position_m: np.ndarray     #: (S, 2) true position at scan time
    reading_position_m: np.ndarray  #: (S, K, 2) true position where each reading was measured

    @property
    def last_seen_s(self) -> np.ndarray:
        """(S, K) time each reading was measured (scan time - age); NaN where not heard."""
        return self.time_s[:, None] - self.age_s


@dataclass
class Truth:
    """Dense truth at ``dense_rate_hz``."""

    time_s: np.ndarray
    position_m: np.ndarray
    heading_rad: np.ndarray
    floor: int


@dataclass
class Scenario:
    """Everything of one walk in one building: inputs of the filter and the truth."""

    building: Building
    seed: int
    floor: int
    duration_s: float
    walk_config: WalkConfig
    pdr_config: PdrErrorConfig
    scan_config: ScanConfig
    route_rooms: np.ndarray          #: rooms in visiting order (the first is the start room)
    route_points_m: np.ndarray       #: (R, 2) route polyline before corner rounding
    trajectory: Trajectory
    start_position_m: np.ndarray     #: (2,)
    start_heading_rad: float         #: heading of the first true step
    true_steps: TrueSteps
    steps: PdrSteps
    scans: Scans
    truth: Truth

    @property
    def geometry(self):
        """List of FloorGeometry (the fusion FloorPlan's input)."""
        return self.building.floors

    @property
    def access_points_m(self) -> np.ndarray:
        return self.building.radio.ap_positions_m

    @property
    def survey(self):
        return self.building.survey


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Angle(s) wrapped to (-π, π]."""
    return np.pi - np.mod(np.pi - np.asarray(a, float), 2.0 * np.pi)


def dead_reckon(length_m: np.ndarray, heading_rad: np.ndarray, start_m: np.ndarray,
                scale: float = 1.0, heading_offset_rad: float = 0.0) -> np.ndarray:
    """PDR positions (M + 1, 2) [m]: p_k = p_{k-1} + scale ℓ_k (cos, sin)(θ_k + offset)."""
    h = np.asarray(heading_rad, float) + heading_offset_rad
    d = scale * np.asarray(length_m, float)[:, None] * np.column_stack([np.cos(h), np.sin(h)])
    return np.vstack([np.asarray(start_m, float).reshape(1, 2), np.asarray(start_m, float) + np.cumsum(d, axis=0)])


# ----------------------------------------------------------------------------------------- route


def _clear_of(points: np.ndarray, pillar: Optional[np.ndarray], clearance: float) -> bool:
    if pillar is None or points.shape[0] < 2:
        return True
    c = pillar.mean(axis=0)
    r = 0.5 * np.linalg.norm(pillar[2] - pillar[0])
    return bool(np.all(geo.segment_point_distance(points[:-1], points[1:], c) > r + clearance))


def _turn(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> float:
    u, v = b - a, c - b
    cosang = np.dot(u, v) / max(np.linalg.norm(u) * np.linalg.norm(v), 1e-12)
    return float(np.arccos(np.clip(cosang, -1.0, 1.0)))


def _wander(building: Building, room: int, entry: np.ndarray, exit_: Optional[np.ndarray], n: int,
            cfg: WalkConfig, rng: np.random.Generator) -> List[np.ndarray]:
    """n (1 or 2) random points in a room, reachable in straight lines entry -> ... -> exit."""
    r = building.rooms[room]
    pillar = building.plan.obstacles[r.pillar] if r.pillar >= 0 else None
    lo, hi = r.rect_m[:2] + cfg.room_margin_m, r.rect_m[2:] - cfg.room_margin_m
    if np.any(hi <= lo):
        return [r.centre_m]
    best, best_turn = None, np.inf
    for _ in range(300):
        pts = [rng.uniform(lo, hi) for _ in range(n)]
        if n == 2 and np.linalg.norm(pts[1] - pts[0]) < 1.5:
            continue
        chain = [p for p in [entry] + pts + [exit_] if p is not None]
        if not _clear_of(np.array(chain), pillar, 0.5):
            continue
        turn = max([_turn(chain[i - 1], chain[i], chain[i + 1]) for i in range(1, len(chain) - 1)], default=0.0)
        if turn < best_turn:
            best, best_turn = pts, turn
        if turn <= cfg.max_room_turn_rad:
            break
    return best if best is not None else [r.centre_m]


def _route(building: Building, target_m: float, cfg: WalkConfig, rng: np.random.Generator):
    """Polyline points (R, 2), per-point corner-cut limit (R,), pause points, visited rooms."""
    g = building.graph
    rooms = building.walkable_rooms()
    seq = [int(rng.choice(rooms))]
    legs: List[np.ndarray] = []
    total = 0.0
    while total < target_m:
        nxt = int(rng.choice([r for r in rooms if r != seq[-1]]))
        nodes = g.shortest_path(int(g.room_node[seq[-1]]), int(g.room_node[nxt]))
        legs.append(nodes)
        total += float(np.sum(np.linalg.norm(np.diff(g.nodes_m[nodes], axis=0), axis=1)))
        seq.append(nxt)
    pts: List[np.ndarray] = []
    cut: List[float] = []
    pauses: List[Tuple[np.ndarray, float]] = []
    # At a door's approach point the arc must not reach the wall line (door jambs 0.5 m aside).
    approach_cut = building.config.approach_m - 0.05
    first_exit = g.nodes_m[legs[0][1]]
    start = _wander(building, seq[0], None, first_exit, 1, cfg, rng)[0]
    pts.append(start)
    cut.append(cfg.corner_cut_m)
    for i, nodes in enumerate(legs):
        inner = nodes[1:-1]
        for v in inner:
            pts.append(g.nodes_m[v])
            cut.append(min(cfg.corner_cut_m, approach_cut) if g.kind[v] == APPROACH else cfg.corner_cut_m)
        exit_ = g.nodes_m[legs[i + 1][1]] if i + 1 < len(legs) else None
        wander = _wander(building, seq[i + 1], pts[-1], exit_, 2, cfg, rng)
        pause = rng.random() < cfg.pause_probability
        duration = rng.uniform(*cfg.pause_s)
        if pause:
            pauses.append((wander[0], duration))
        for p in wander:
            pts.append(p)
            cut.append(cfg.corner_cut_m)
    return np.array(pts), np.array(cut), pauses, np.array(seq)


def _simplify(points: np.ndarray, cut: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Drops repeated points and the middle of collinear triples."""
    keep_p, keep_c = [points[0]], [cut[0]]
    for p, c in zip(points[1:], cut[1:]):
        if np.linalg.norm(p - keep_p[-1]) > 1e-6:
            keep_p.append(p)
            keep_c.append(c)
    p, c = np.array(keep_p), np.array(keep_c)
    out_p, out_c = [p[0]], [c[0]]
    for i in range(1, p.shape[0] - 1):
        u, v = p[i] - out_p[-1], p[i + 1] - p[i]
        if abs(u[0] * v[1] - u[1] * v[0]) > 1e-9 * np.linalg.norm(u) * np.linalg.norm(v) or np.dot(u, v) < 0:
            out_p.append(p[i])
            out_c.append(c[i])
    out_p.append(p[-1])
    out_c.append(c[-1])
    return np.array(out_p), np.array(out_c)


def _round_corners(points: np.ndarray, cut: np.ndarray, spacing_m: float = 0.05) -> np.ndarray:
    """Dense polyline with each interior corner replaced by a quadratic Bézier T1 -> P -> T2."""
    out = [points[0]]
    n = points.shape[0]
    for i in range(1, n - 1):
        u, v = points[i] - points[i - 1], points[i + 1] - points[i]
        lu, lv = np.linalg.norm(u), np.linalg.norm(v)
        L = min(cut[i], 0.45 * lu, 0.45 * lv)
        t1, t2 = points[i] - u / lu * L, points[i] + v / lv * L
        m = max(4, int(np.ceil(2 * L / spacing_m)))
        s = np.linspace(0.0, 1.0, m + 1)[:, None]
        out.extend((1 - s) ** 2 * t1 + 2 * s * (1 - s) * points[i] + s**2 * t2)
    out.append(points[-1])
    p = np.array(out)
    # Densify straight parts.
    dense = [p[0:1]]
    for a, b in zip(p[:-1], p[1:]):
        k = max(1, int(np.ceil(np.linalg.norm(b - a) / spacing_m)))
        dense.append(a + (b - a) * (np.arange(1, k + 1) / k)[:, None])
    p = np.vstack(dense)
    keep = np.r_[True, np.linalg.norm(np.diff(p, axis=0), axis=1) > 1e-9]
    return p[keep]


# ------------------------------------------------------------------------------------- simulate


def simulate_walk(building: Building, seed: int = 0, floor: int = 0, walk: WalkConfig = WalkConfig(),
                  pdr: PdrErrorConfig = PdrErrorConfig(), scans: ScanConfig = ScanConfig()) -> Scenario:
    """Simulates one walk on one floor of `building`: route, true steps, PDR steps, scans, truth.

    Deterministic in `seed` (independent of the building's seed). Raises ValueError on an invalid
    configuration or a floor the building does not have.
    """
    walk.validate()
    pdr.validate()
    scans.validate()
    plan = building.geometry(integer(floor, "floor", lo=-(2**31), hi=2**31 - 1))
    seed = integer(seed, "seed", lo=0, hi=2**64 - 1)

    def stream(k: int) -> np.random.Generator:
        return np.random.default_rng([seed, _DOMAIN, k])

    rng_gait = stream(_GAIT_STREAM)
    step_len = max(0.3, walk.step_length_m + walk.step_length_walker_sd_m * rng_gait.standard_normal())
    cadence = float(np.clip(walk.step_frequency_hz + walk.step_frequency_walker_sd_hz * rng_gait.standard_normal(),
                            0.5 * walk.step_frequency_hz, 1.5 * walk.step_frequency_hz))
    target = walk.duration_s * step_len * cadence * 1.1 + 10.0
    raw, cut, pause_pts, seq = _route(building, target, walk, stream(_ROUTE_STREAM))
    pts, cut = _simplify(raw, cut)
    path = _round_corners(pts, cut)
    edges = plan.edges()
    if geo.touches_any(path[:-1], path[1:], edges).any():
        raise RuntimeError("indoorloc: internal: the rounded route touches a wall")
    arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))]
    pause_arc = [(float(arc[np.argmin(np.linalg.norm(path - p, axis=1))]), d) for p, d in pause_pts]
    pause_arc.sort()
    # Steps along the path.
    t, s, ip = 0.0, 0.0, 0
    starts, ends, arcs = [], [], []
    while True:
        while ip < len(pause_arc) and s >= pause_arc[ip][0]:
            t += pause_arc[ip][1]
            ip += 1
        length = step_len * (1.0 + walk.step_length_sd_fraction * rng_gait.standard_normal())
        period = (1.0 + walk.step_period_sd_fraction * rng_gait.standard_normal()) / cadence
        if s + length > arc[-1] or t + period > walk.duration_s:
            break
        starts.append(t)
        t += period
        s += length
        ends.append(t)
        arcs.append(s)
    starts, ends, arcs = np.array(starts), np.array(ends), np.array(arcs)
    kt, ks = [0.0], [0.0]
    for a, b, sk in zip(starts, ends, arcs):
        if a > kt[-1] + 1e-12:
            kt.append(a)
            ks.append(ks[-1])
        kt.append(b)
        ks.append(sk)
    if walk.duration_s > kt[-1] + 1e-12:
        kt.append(walk.duration_s)
        ks.append(ks[-1])
    traj = Trajectory(path_m=path, path_arc_m=arc, knot_time_s=np.array(kt), knot_arc_m=np.array(ks))
    start = path[0].copy()
    pos = traj.position_at(ends).reshape(-1, 2)
    prev = np.vstack([start[None, :], pos[:-1]])
    if geo.touches_any(prev, pos, edges).any():
        raise RuntimeError("indoorloc: internal: a true step touches a wall")
    d = pos - prev
    true_len = np.linalg.norm(d, axis=1)
    true_head = np.arctan2(d[:, 1], d[:, 0])
    m = ends.size
    # PDR errors.
    r = stream(_PDR_STREAM)
    scale = 1.0 + pdr.scale_sd * r.standard_normal()
    bias = r.uniform(-pdr.heading_bias_max_rad, pdr.heading_bias_max_rad)
    drift = np.cumsum(pdr.heading_drift_sd_rad * r.standard_normal(m))
    len_noise = pdr.length_noise_sd_m * r.standard_normal(m)
    head_noise = pdr.heading_noise_sd_rad * r.standard_normal(m)
    missed = r.random(m) < pdr.missed_step_probability
    extra = r.random(m) < pdr.extra_step_probability
    extra_frac = r.uniform(0.3, 0.7, m)
    extra_len = step_len * scale * (1.0 + 0.15 * r.standard_normal(m))
    extra_head = pdr.heading_noise_sd_rad * r.standard_normal(m)
    meas_t = ends.copy()
    meas_len = np.maximum(0.0, scale * true_len + len_noise)
    meas_head = true_head + bias + drift + head_noise
    next_start = np.r_[starts[1:], min(walk.duration_s, ends[-1] + 0.5)] if m else np.zeros(0)
    xt = ends + extra_frac * (next_start - ends)
    times = np.r_[meas_t[~missed], xt[extra]]
    order = np.argsort(times, kind="stable")
    idx = np.r_[np.flatnonzero(~missed), -np.ones(int(extra.sum()), int)][order]
    steps = PdrSteps(
        time_s=times[order],
        length_m=np.r_[meas_len[~missed], np.maximum(0.1, extra_len[extra])][order],
        heading_rad=wrap_angle(np.r_[meas_head[~missed], (true_head + bias + drift + extra_head)[extra]][order]),
        length_sd_m=np.full(times.size, pdr.length_noise_sd_m),
        heading_sd_rad=np.full(times.size, pdr.heading_noise_sd_rad),
        true_position_m=traj.position_at(times[order]).reshape(-1, 2),
        true_step=idx,
        heading_drift_rad=np.r_[drift[~missed], drift[extra]][order],
        scale=float(scale), heading_bias_rad=float(bias))
    true_steps = TrueSteps(start_time_s=starts, time_s=ends, position_m=pos, length_m=true_len,
                           heading_rad=true_head, missed=missed)
    # Scans.
    r = stream(_SCAN_STREAM)
    n_scans = int(np.floor(walk.duration_s / scans.interval_s)) + 1
    st = r.uniform(0.0, scans.interval_s) + scans.interval_s * np.arange(n_scans) \
        + scans.jitter_s * np.clip(r.standard_normal(n_scans), -2.0, 2.0)
    st = st[(st >= 0.0) & (st <= walk.duration_s)]
    k = building.radio.num_access_points
    stale = r.random((st.size, k)) < scans.stale_probability
    age = np.where(stale, r.uniform(*scans.stale_age_s, (st.size, k)), r.uniform(0.0, scans.fresh_age_max_s, (st.size, k)))
    age = np.minimum(age, st[:, None])
    read_pos = traj.position_at(st[:, None] - age).reshape(st.size, k, 2)
    mean = building.radio.mean_rss_pairs(read_pos.reshape(-1, 2), floor, np.tile(np.arange(k), st.size))
    rss = building.radio.measure(mean, r, scans.device_offset_db).reshape(st.size, k)
    scan = Scans(floor=floor, time_s=st, rss_dbm=rss, age_s=np.where(np.isnan(rss), np.nan, age),
                 true_position_m=traj.position_at(st).reshape(-1, 2), reading_position_m=read_pos)
    tt = np.arange(0.0, walk.duration_s + 1e-9, 1.0 / walk.dense_rate_hz)
    truth = Truth(time_s=tt, position_m=traj.position_at(tt).reshape(-1, 2), heading_rad=traj.heading_at(tt),
                  floor=floor)
    return Scenario(building=building, seed=seed, floor=floor, duration_s=walk.duration_s, walk_config=walk,
                    pdr_config=pdr, scan_config=scans, route_rooms=seq, route_points_m=pts, trajectory=traj,
                    start_position_m=start, start_heading_rad=float(true_head[0]) if m else 0.0,
                    true_steps=true_steps, steps=steps, scans=scan, truth=truth)
