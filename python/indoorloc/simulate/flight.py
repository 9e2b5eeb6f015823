"""Airborne gravimetry flight simulator for the network subsystem (paper 003).

A survey platform (helicopter-like: it hovers for the zero-velocity periods) flies, in the local
Earth-fixed ENU frame of ``cpp/include/indoorloc/network/gravity.h``:

1. a hover of ``zupt_s`` (ZUPT), a smooth acceleration to ``speed_mps`` heading East;
2. ``n_lines`` parallel East-West lines of ``line_length_m``, linked by 180-degree turns of radius
   ``turn_radius_m`` (line spacing = 2 radius), alternating direction;
3. two North-South cross lines over the middle of the block (crossing every East-West line, so
   cross-overs exist), linked by a 180-degree turn;
4. a smooth deceleration and a final hover (ZUPT).

Height: ``altitude_m`` plus a slow wave of ``height_wave_m`` while moving. Attitude: yaw along the
track, roll of a coordinated turn, no pitch. Heading rate and speed change smoothly (raised-cosine
ramps), so the IMU signals are continuous.

The gravity disturbance δg(x, y) is a sum of Gaussian anomalies of tens of mGal (vertical,
positive = stronger gravity, as in the C++ model); the IMU feels γ(h) + δg. The trajectory is
computed on a fine grid (``oversample`` x the IMU rate): specific force
f_b = Rᵀ (a + 2 ω_ie × v - g) and angular rate ω_ib = ω_nb + Rᵀ ω_ie are sampled at the IMU epochs
(point samples, as the network's equations use them) and corrupted with white noise and random-
walk biases of the stated densities; GPS positions at ``gps_rate_hz`` with white noise; GUPTs
(total gravity) at the first and last epoch (a ground gravity station at both hovers).

Randomness: ``numpy.random.default_rng([seed, stream])`` with stream 0 for the gravity field and
stream 1 for the sensor noise, so a field can be held fixed while the noise varies.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Tuple

import numpy as np

from indoorloc._core import network as _net

_FIELD_STREAM = 0
_NOISE_STREAM = 1


@dataclass
class FlightConfig:
    """Flight pattern, sensors and gravity field. Defaults: a 9.5-minute flight at 50 Hz
    (28,655 epochs, 9 cross-overs)."""

    imu_rate_hz: float = 50.0
    gps_rate_hz: float = 1.0
    speed_mps: float = 50.0
    line_length_m: float = 3000.0
    n_lines: int = 3
    turn_radius_m: float = 400.0
    cross_margin_m: float = 600.0      #: cross lines extend this far beyond the outer lines
    ramp_s: float = 4.0                #: heading-rate ramps at the start and end of turns
    accel_s: float = 15.0              #: speed-up and slow-down duration
    zupt_s: float = 30.0               #: hover at start and end
    altitude_m: float = 300.0
    height_wave_m: float = 3.0
    height_wave_period_s: float = 40.0
    latitude_rad: float = 0.7223
    origin_height_m: float = 0.0
    oversample: int = 8
    # Gravity field: n_anomalies Gaussian bumps, amplitude uniform in ±[min, max] mGal, width
    # uniform in [width_min, width_max] m, centres inside the survey block.
    n_anomalies: int = 6
    anomaly_amplitude_mgal: Tuple[float, float] = (10.0, 40.0)
    anomaly_width_m: Tuple[float, float] = (1000.0, 2500.0)
    # Sensors (same densities as NetworkOptions).
    acc_noise_mps2_rthz: float = 1e-4   #: 10 mGal/√Hz (strapdown gravimetry grade)
    gyro_noise_radps_rthz: float = 1e-5
    acc_bias_walk_mps2_rts: float = 1e-6
    gyro_bias_walk_radps_rts: float = 1e-7
    acc_bias_initial_mps2: Tuple[float, float, float] = (2e-4, -1e-4, 3e-4)
    gyro_bias_initial_radps: Tuple[float, float, float] = (1e-6, -2e-6, 1.5e-6)
    sigma_gps_m: float = 0.01
    sigma_gupt_mps2: float = 1e-5

    def validate(self) -> None:
        for name in ("imu_rate_hz", "gps_rate_hz", "speed_mps", "line_length_m", "turn_radius_m", "ramp_s",
                     "accel_s", "zupt_s", "height_wave_period_s"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"indoorloc: argument 'config.{name}': must be finite and > 0, got {v}")
        if self.n_lines < 2:
            raise ValueError("indoorloc: argument 'config.n_lines': needs at least 2 lines")
        ratio = self.imu_rate_hz / self.gps_rate_hz
        if abs(ratio - round(ratio)) > 1e-9:
            raise ValueError("indoorloc: argument 'config.gps_rate_hz': the IMU rate must be a multiple of it")
        if self.oversample < 2:
            raise ValueError("indoorloc: argument 'config.oversample': must be >= 2")


@dataclass
class GravityField:
    """δg(x, y) = Σ a_i exp(-|p - c_i|² / (2 w_i²)) [m/s^2]."""

    centres_m: np.ndarray
    amplitudes_mps2: np.ndarray
    widths_m: np.ndarray

    def __call__(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        x = np.asarray(x_m, float)[..., None]
        y = np.asarray(y_m, float)[..., None]
        d2 = (x - self.centres_m[:, 0]) ** 2 + (y - self.centres_m[:, 1]) ** 2
        return np.sum(self.amplitudes_mps2 * np.exp(-0.5 * d2 / self.widths_m**2), axis=-1)


@dataclass
class Flight:
    """Observations (the inputs of ``indoorloc.network.solve``) and the truth."""

    config: FlightConfig
    imu_time_s: np.ndarray
    acc_body_mps2: np.ndarray
    gyro_body_radps: np.ndarray
    gps_time_s: np.ndarray
    gps_position_m: np.ndarray
    zupt_epochs: np.ndarray
    gupt_epochs: np.ndarray
    gupt_gravity_mps2: np.ndarray
    truth: Dict[str, np.ndarray]
    field: GravityField
    line_id: np.ndarray = field(default_factory=lambda: np.zeros(0, int))  #: per epoch: -1 off-line, k line k

    @property
    def n_epochs(self) -> int:
        return int(self.imu_time_s.size)


def _ramp(t: np.ndarray, duration: float) -> np.ndarray:
    """Raised cosine from 0 (t <= 0) to 1 (t >= duration)."""
    u = np.clip(t / duration, 0.0, 1.0)
    return 0.5 * (1.0 - np.cos(np.pi * u))


def _segments(c: FlightConfig) -> List[Tuple[str, float, float, int]]:
    """(kind, duration_s, turn angle rad, line id) of the pattern; kinds: hover, accel, straight,
    turn, decel."""
    v, r, L = c.speed_mps, c.turn_radius_m, c.line_length_m
    spacing = 2.0 * r
    segs: List[Tuple[str, float, float, int]] = [("hover", c.zupt_s, 0.0, -1), ("accel", c.accel_s, 0.0, -1)]
    for k in range(c.n_lines):
        segs.append(("straight", L / v, 0.0, k))
        if k + 1 < c.n_lines:
            segs.append(("turn", np.pi * r / v, np.pi if k % 2 == 0 else -np.pi, -1))
    # Heading after the last line: East if n_lines is odd, West otherwise. Reach the block's middle
    # north of the top line: turn 90 deg toward North, 90 deg toward the middle, fly, 90 deg South.
    east = c.n_lines % 2 == 1
    s = 1.0 if east else -1.0  # +1: left turns bring us North then West
    top = (c.n_lines - 1) * spacing
    x_end = L if east else 0.0
    x_cross1 = 0.5 * L - s * r
    # After two 90-degree turns: x = x_end, heading West (east case) / East; fly to x_cross1 + s r.
    fly = abs(x_end - (x_cross1 + s * r))
    segs += [("turn", 0.5 * np.pi * r / v, s * 0.5 * np.pi, -1), ("turn", 0.5 * np.pi * r / v, s * 0.5 * np.pi, -1),
             ("straight", fly / v, 0.0, -1), ("turn", 0.5 * np.pi * r / v, s * 0.5 * np.pi, -1)]
    cross_len = top + 2.0 * r + c.cross_margin_m + (r + c.cross_margin_m)
    segs += [("straight", cross_len / v, 0.0, c.n_lines), ("turn", np.pi * r / v, s * np.pi, -1),
             ("straight", cross_len / v, 0.0, c.n_lines + 1), ("decel", c.accel_s, 0.0, -1),
             ("hover", c.zupt_s, 0.0, -1)]
    del top
    return segs


def _skew_log(r_a: np.ndarray, r_b: np.ndarray) -> np.ndarray:
    """Rotation vectors Log(R_aᵀ R_b) for stacks of rotation matrices (K, 3, 3)."""
    d = np.einsum("kji,kjl->kil", r_a, r_b)
    cos = np.clip((np.trace(d, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.arccos(cos)
    w = np.stack([d[:, 2, 1] - d[:, 1, 2], d[:, 0, 2] - d[:, 2, 0], d[:, 1, 0] - d[:, 0, 1]], axis=1)
    k = np.where(angle > 1e-12, angle / (2.0 * np.sin(np.maximum(angle, 1e-300))), 0.5)
    return w * k[:, None]


def _quaternions_wxyz(rot: np.ndarray) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    xyzw = Rotation.from_matrix(rot).as_quat()
    q = np.column_stack([xyzw[:, 3], xyzw[:, :3]])
    q[q[:, 0] < 0] *= -1.0
    return q


def simulate_flight(config: FlightConfig = FlightConfig(), seed: int = 0, noise: bool = True) -> Flight:
    """Simulates one flight. ``noise=False``: exact sensors, GPS and GUPT (biases still present)."""
    c = config
    c.validate()
    segs = _segments(c)
    dt = 1.0 / c.imu_rate_hz
    total = sum(s[1] for s in segs)
    n = int(np.floor(total / dt)) + 1
    fine_dt = dt / c.oversample
    tf = np.arange((n - 1) * c.oversample + 1) * fine_dt
    # Speed and heading rate on the fine grid.
    speed = np.zeros_like(tf)
    psi_dot = np.zeros_like(tf)
    line_fine = np.full(tf.shape, -1, dtype=int)
    t0 = 0.0
    for kind, dur, angle, line in segs:
        m = (tf >= t0) & (tf < t0 + dur + (1e-12 if t0 + dur >= total - 1e-9 else 0.0))
        tau = tf[m] - t0
        if kind == "hover":
            speed[m] = 0.0 if t0 < 1.0 else 0.0
        elif kind == "accel":
            speed[m] = c.speed_mps * _ramp(tau, dur)
        elif kind == "decel":
            speed[m] = c.speed_mps * (1.0 - _ramp(tau, dur))
        else:
            speed[m] = c.speed_mps
        if kind == "turn":
            # Constant rate in the middle with raised-cosine ramps; the integral is `angle`.
            ramp = min(c.ramp_s, 0.5 * dur)
            plateau = angle / (dur - ramp)  # ∫ = plateau (dur - 2 ramp) + 2 plateau ramp / 2
            shape = np.minimum(_ramp(tau, ramp), _ramp(dur - tau, ramp))
            psi_dot[m] = plateau * shape
        line_fine[m] = line
        t0 += dur
    speed[tf >= t0] = 0.0
    # Heading (from East, counter-clockwise), horizontal velocity, position.
    psi = np.concatenate([[0.0], np.cumsum(0.5 * (psi_dot[1:] + psi_dot[:-1]) * fine_dt)])
    env = speed / c.speed_mps
    up = c.altitude_m + c.height_wave_m * env * np.sin(2.0 * np.pi * tf / c.height_wave_period_s)
    vel = np.column_stack([speed * np.cos(psi), speed * np.sin(psi), np.gradient(up, fine_dt, edge_order=2)])
    pos = np.zeros((tf.size, 3))
    pos[1:, :2] = np.cumsum(0.5 * (vel[1:, :2] + vel[:-1, :2]) * fine_dt, axis=0)
    pos[:, 0] -= 0.5 * c.speed_mps * c.accel_s  # line 0 starts at x = 0 after the speed-up
    pos[:, 2] = up
    acc = np.gradient(vel, fine_dt, axis=0, edge_order=2)
    # Attitude: yaw psi, roll of a coordinated turn (body x forward, y left, z up).
    gamma = _net.normal_gravity(c.latitude_rad, up + c.origin_height_m)
    roll = -np.arctan2(speed * psi_dot, gamma)
    cy, sy, cr, sr = np.cos(psi), np.sin(psi), np.cos(roll), np.sin(roll)
    rot = np.zeros((tf.size, 3, 3))
    rot[:, 0, 0], rot[:, 0, 1], rot[:, 0, 2] = cy, -sy * cr, sy * sr
    rot[:, 1, 0], rot[:, 1, 1], rot[:, 1, 2] = sy, cy * cr, -cy * sr
    rot[:, 2, 1], rot[:, 2, 2] = sr, cr
    # Gravity field from stream 0.
    rng_field = np.random.default_rng([int(seed), _FIELD_STREAM])
    xmin, xmax = 0.0, c.line_length_m
    ymin, ymax = 0.0, (c.n_lines - 1) * 2.0 * c.turn_radius_m
    k = c.n_anomalies
    centres = np.column_stack([rng_field.uniform(xmin, xmax, k), rng_field.uniform(ymin - 300, ymax + 300, k)])
    amps = rng_field.uniform(*c.anomaly_amplitude_mgal, k) * rng_field.choice([-1.0, 1.0], k) * 1e-5
    widths = rng_field.uniform(*c.anomaly_width_m, k)
    gfield = GravityField(centres, amps, widths)
    # Subsample to IMU epochs.
    idx = np.arange(n) * c.oversample
    t = tf[idx]
    p, v, a, R = pos[idx], vel[idx], acc[idx], rot[idx]
    dg = gfield(p[:, 0], p[:, 1])
    wie = _net.earth_rate_enu(c.latitude_rad)
    g_n = np.zeros((n, 3))
    g_n[:, 2] = -(gamma[idx] + dg)
    f_n = a + 2.0 * np.cross(wie, v) - g_n
    f_b = np.einsum("kji,kj->ki", R, f_n)
    # ω_nb from the fine grid (central difference of the rotation over ±1 fine step).
    lo = np.maximum(idx - 1, 0)
    hi = np.minimum(idx + 1, tf.size - 1)
    w_nb = _skew_log(rot[lo], rot[hi]) / ((hi - lo) * fine_dt)[:, None]
    w_b = w_nb + np.einsum("kji,j->ki", R, wie)
    # Sensor errors from stream 1.
    rng = np.random.default_rng([int(seed), _NOISE_STREAM])
    ba = np.asarray(c.acc_bias_initial_mps2, float) + np.vstack(
        [np.zeros(3), np.cumsum(rng.normal(0.0, c.acc_bias_walk_mps2_rts * np.sqrt(dt), (n - 1, 3)), axis=0)])
    bg = np.asarray(c.gyro_bias_initial_radps, float) + np.vstack(
        [np.zeros(3), np.cumsum(rng.normal(0.0, c.gyro_bias_walk_radps_rts * np.sqrt(dt), (n - 1, 3)), axis=0)])
    acc_meas = f_b + ba
    gyro_meas = w_b + bg
    if noise:
        acc_meas = acc_meas + rng.normal(0.0, c.acc_noise_mps2_rthz / np.sqrt(dt), (n, 3))
        gyro_meas = gyro_meas + rng.normal(0.0, c.gyro_noise_radps_rthz / np.sqrt(dt), (n, 3))
    step = int(round(c.imu_rate_hz / c.gps_rate_hz))
    gps_epochs = np.arange(0, n, step)
    gps_pos = p[gps_epochs] + (rng.normal(0.0, c.sigma_gps_m, (gps_epochs.size, 3)) if noise else 0.0)
    # ZUPT: hover epochs at least 0.5 s away from any motion.
    still = (speed[idx] == 0.0).astype(float)
    half = max(1, int(round(0.5 * c.imu_rate_hz)))
    zupt = np.flatnonzero(np.convolve(still, np.ones(2 * half + 1), mode="same") >= 2 * half + 1 - 1e-9)
    gupt = np.array([0, n - 1])
    g0 = gamma[idx][gupt] + dg[gupt] + (rng.normal(0.0, c.sigma_gupt_mps2, 2) if noise else 0.0)
    truth = {
        "position_m": p,
        "velocity_mps": v,
        "attitude_wxyz": _quaternions_wxyz(R),
        "acc_bias_mps2": ba,
        "gyro_bias_radps": bg,
        "gravity_disturbance_mps2": dg,
    }
    return Flight(config=c, imu_time_s=t, acc_body_mps2=acc_meas, gyro_body_radps=gyro_meas,
                  gps_time_s=t[gps_epochs], gps_position_m=gps_pos, zupt_epochs=zupt, gupt_epochs=gupt,
                  gupt_gravity_mps2=g0, truth=truth, field=gfield, line_id=line_fine[idx])


def small_config(**overrides) -> FlightConfig:
    """A flight of about two minutes at 50 Hz for tests and the demo (seconds to solve)."""
    base = dict(line_length_m=1200.0, n_lines=3, turn_radius_m=200.0, cross_margin_m=200.0, speed_mps=40.0,
                accel_s=8.0, zupt_s=5.0, ramp_s=2.0, anomaly_width_m=(700.0, 1500.0), height_wave_period_s=30.0)
    base.update(overrides)
    return FlightConfig(**base)
