"""One walk of the synthetic ILC 2020 site: the walker's gait, its trajectory along a random route,
the phone's sensors (accelerometer, gyroscope, rotation vector, magnetometer), the waypoints, the
WiFi scans with Android's cache, and the lines of its file (model:
:mod:`indoorloc.simulate.ilc_site`). :func:`make_walk` draws them in a fixed order from one
generator, so a walk depends only on its seed stream.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, List, NamedTuple, Tuple

import numpy as np
from scipy.spatial.transform import Rotation

from indoorloc.simulate.ilc_layout import IlcLayout, _route
from indoorloc.simulate.ilc_site_config import IlcSiteConfig
from indoorloc.simulate.walker import Trajectory, _round_corners

GRAVITY_MPS2 = 9.80665


@dataclass
class IlcWalkTruth:
    """What one synthetic walk really did (walk clock: seconds since its first record)."""

    walk_id: str
    floor_name: str
    step_t_s: np.ndarray          #: (M,) time of each step (peak of the bounce)
    step_length_m: np.ndarray     #: (M,) true stride lengths
    yaw_offset_rad: float         #: floor-frame minus phone heading of this walk
    waypoint_t_s: np.ndarray      #: (W,)
    waypoint_xy_m: np.ndarray     #: (W, 2)
    t_s: np.ndarray               #: (N,) sensor times
    position_m: np.ndarray        #: (N, 2) true position at the sensor times
    lines: List[str] = field(repr=False, default_factory=list)  #: the file's lines

    @property
    def n_steps(self) -> int:
        return int(self.step_t_s.shape[0])


def _butterworth_gain(f_hz: float, cutoff_hz: float = 3.0, order: int = 4) -> float:
    # |H| of the analog prototype; the bilinear design at 50 Hz differs by < 0.2 % at 1.4-2.2 Hz.
    return 1.0 / math.sqrt(1.0 + (f_hz / cutoff_hz) ** (2 * order))


def _slow_error(t: np.ndarray, sd: float, rng: np.random.Generator) -> np.ndarray:
    """Zero-mean slowly varying signal (sum of 4 sinusoids, periods 5-30 s) with standard deviation ~sd."""
    periods = rng.uniform(5.0, 30.0, 4)
    phases = rng.uniform(0.0, 2 * np.pi, 4)
    return sd * np.sqrt(2.0 / 4) * np.sum(np.sin(2 * np.pi * t[:, None] / periods + phases), axis=1)


def _smooth(x: np.ndarray, n: int) -> np.ndarray:
    if n <= 1:
        return x
    pad = np.concatenate([np.full(n, x[0]), x, np.full(n, x[-1])])
    c = np.convolve(pad, np.ones(n) / n, mode="same")
    return c[n:-n]


_SENSOR_HEADER = [
    "#\ttype:1\tname:Synthetic Accelerometer\tversion:1\tvendor:indoorloc\tresolution:0.0023956299\tpower:0.18"
    "\tmaximumRange:39.22661",
    "#\ttype:4\tname:Synthetic Gyroscope\tversion:1\tvendor:indoorloc\tresolution:0.0010681152\tpower:0.9"
    "\tmaximumRange:34.906586",
    "#\ttype:2\tname:Synthetic Magnetometer\tversion:1\tvendor:indoorloc\tresolution:0.5996704\tpower:2.4"
    "\tmaximumRange:4911.9995",
]


class _Gait(NamedTuple):
    cadence_hz: float
    periods_s: np.ndarray     #: (M,) step periods
    step_t_s: np.ndarray      #: (M,) step times
    step_len_m: np.ndarray    #: (M,) stride lengths
    stand_start_s: float
    duration_s: float


def _gait(cfg: IlcSiteConfig, rng: np.random.Generator) -> _Gait:
    """Steps while walking, standing before and after: cadence, periods, times and lengths."""
    duration = rng.uniform(*cfg.walk_duration_s)
    stand0 = rng.uniform(*cfg.stand_start_s)
    stand1 = rng.uniform(*cfg.stand_end_s)
    cadence = float(np.clip(cfg.step_frequency_hz + cfg.step_frequency_walker_sd_hz * rng.standard_normal(),
                            0.8 * cfg.step_frequency_hz, 1.2 * cfg.step_frequency_hz))
    stride = cfg.step_length_m + float(np.clip(cfg.step_length_walker_sd_m * rng.standard_normal(), -0.08, 0.08))
    periods, t_end = [], stand0
    while True:
        p = (1.0 + 0.03 * rng.standard_normal()) / cadence
        if t_end + p > duration - stand1:
            break
        periods.append(p)
        t_end += p
    periods = np.array(periods)
    step_t = stand0 + np.cumsum(periods)
    step_len = stride * (1.0 + cfg.step_length_sd_fraction * rng.standard_normal(periods.size))
    return _Gait(cadence, periods, step_t, step_len, stand0, float(step_t[-1] + stand1))


class _Motion(NamedTuple):
    route: np.ndarray         #: (R, 2) corridor polyline before rounding
    path: np.ndarray          #: (P, 2) rounded path
    arc: np.ndarray           #: (P,) arc length of the path
    knot_t: np.ndarray        #: times of the arc-length knots
    knot_s: np.ndarray        #: arc lengths at the knots
    trajectory: Trajectory


def _motion(layout: IlcLayout, cfg: IlcSiteConfig, gait: _Gait, rng: np.random.Generator) -> _Motion:
    """Route and motion along it: arc length linear within each step, flat while standing."""
    step_len = gait.step_len_m
    # Rounding shortens each corner by about 0.4 corner_cut_m: ask for a margin, longer if needed.
    margin = 4.0 * cfg.corner_cut_m + 2.0
    while True:
        route = _route(layout, float(step_len.sum()) + margin, rng)
        path = _round_corners(route, np.full(route.shape[0], cfg.corner_cut_m))
        arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))]
        if arc[-1] >= step_len.sum():
            break
        margin *= 2.0
    knot_t = np.r_[0.0, gait.stand_start_s, gait.step_t_s, gait.duration_s]
    knot_s = np.r_[0.0, 0.0, np.cumsum(step_len), step_len.sum()]
    traj = Trajectory(path_m=path, path_arc_m=arc, knot_time_s=knot_t, knot_arc_m=knot_s)
    return _Motion(route, path, arc, knot_t, knot_s, traj)


def _sensor_clock_ms(duration_s: float, rate_hz: float, rng: np.random.Generator) -> np.ndarray:
    """Sensor times [ms since the first waypoint]: 50 Hz from about 130 ms on, whole milliseconds."""
    first_ms = int(rng.integers(110, 150))
    n = int(np.floor((duration_s * 1000.0 - first_ms) / (1000.0 / rate_hz))) + 1
    t_ms = first_ms + np.round(np.arange(n) * 1000.0 / rate_hz).astype(np.int64)
    # Android's 19-21 ms jitter: +-1 ms on some odd samples, so no two neighbours move.
    t_ms[1:-1] += rng.integers(-1, 2, n - 2) * ((rng.random(n - 2) < 0.1) & (np.arange(1, n - 1) % 2 == 1))
    return t_ms


class _Imu(NamedTuple):
    acc: np.ndarray           #: (N, 3) [m/s^2]
    gyro: np.ndarray          #: (N, 3) [rad/s]
    quat_xyzw: np.ndarray     #: (N, 4) rotation vector, w >= 0
    mag: np.ndarray           #: (N, 3) [uT]
    walk_offset_rad: float    #: floor-frame minus phone heading of this walk


def _imu(cfg: IlcSiteConfig, site_yaw_offset_rad: float, gait: _Gait, traj: Trajectory, t: np.ndarray,
         rng: np.random.Generator) -> _Imu:
    """The phone's inertial and magnetic sensors at times t (N,) [s] (module docstring of ilc_site)."""
    n = t.size
    rate = cfg.sample_rate_hz
    step_t, periods, m = gait.step_t_s, gait.periods_s, gait.step_t_s.size
    # Walking direction, smoothed: people turn the phone over a fraction of a second.
    heading = _smooth(np.unwrap(traj.heading_at(t)), max(1, int(round(0.4 * rate))))
    walk_offset = site_yaw_offset_rad + math.radians(cfg.yaw_offset_walk_sd_deg) * rng.standard_normal()
    phone_heading = heading - walk_offset
    # Gait phase (2 pi k at step k) and bounce amplitude from Weinberg's rule with the site's K.
    gain = _butterworth_gain(gait.cadence_hz)
    amp_k = (gait.step_len_m / cfg.weinberg_k) ** 4 / (2.0 * gain)
    ph_t = np.r_[step_t[0] - periods[0], step_t, step_t[-1] + periods[-1]]
    phase = np.interp(t, ph_t, 2 * np.pi * np.arange(-1, m + 1))
    amp = np.interp(t, ph_t, np.r_[0.0, amp_k, 0.0], left=0.0, right=0.0)
    a_up = amp * np.cos(phase)
    a_fwd = 0.35 * amp * np.sin(phase)
    a_lat = 0.25 * amp * np.sin(0.5 * phase)
    # Orientation: device +y along the phone heading, pitched up, small bob and sway.
    pitch = math.radians(rng.uniform(*cfg.pitch_deg)) + math.radians(1.5) * (amp > 0) * np.sin(phase)
    roll = math.radians(rng.normal(0.0, 2.0)) + math.radians(1.0) * (amp > 0) * np.sin(0.5 * phase)
    sway = math.radians(1.5) * (amp > 0) * np.sin(0.5 * phase + 0.3)
    r_true = Rotation.from_euler("ZXY", np.column_stack([phone_heading + sway - np.pi / 2, pitch, roll]))
    h = heading
    f_enu = np.column_stack([a_fwd * np.cos(h) - a_lat * np.sin(h), a_fwd * np.sin(h) + a_lat * np.cos(h),
                             a_up + GRAVITY_MPS2])
    acc = r_true.inv().apply(f_enu) + cfg.accel_noise_sd_mps2 * rng.standard_normal((n, 3))
    # Gyroscope: body rate of the true orientation (central differences), noise, constant bias.
    gyro = np.empty((n, 3))
    gyro[1:-1] = (r_true[:-2].inv() * r_true[2:]).as_rotvec() / (t[2:] - t[:-2])[:, None]
    gyro[0], gyro[-1] = gyro[1], gyro[-2]
    gyro += cfg.gyro_bias_sd_radps * rng.standard_normal(3) + cfg.gyro_noise_sd_radps * rng.standard_normal((n, 3))
    # Rotation vector: the true orientation with a slow heading error about the vertical.
    err = _slow_error(t, math.radians(cfg.heading_error_sd_deg), rng)
    r_rv = Rotation.from_rotvec(np.column_stack([np.zeros(n), np.zeros(n), err])) * r_true
    quat = r_rv.as_quat()                      # x, y, z, w
    quat[quat[:, 3] < 0] *= -1.0               # Android writes the w >= 0 hemisphere (w not stored)
    mag = (r_rv.inv().apply(np.asarray(cfg.magnetic_field_enu_ut, float))
           + cfg.mag_noise_sd_ut * rng.standard_normal((n, 3)))
    return _Imu(acc, gyro, quat, mag, float(walk_offset))


def _waypoints(cfg: IlcSiteConfig, gait: _Gait, motion: _Motion, rng: np.random.Generator
               ) -> Tuple[np.ndarray, np.ndarray]:
    """Waypoint times (W,) [s] and positions (W, 2) [m]: start, corners of the route, last step,
    and fill-ins 3-6 s apart."""
    step_t, stand0 = gait.step_t_s, gait.stand_start_s
    wp = [0.0, float(step_t[-1])]
    corner_s = [float(motion.arc[np.argmin(np.linalg.norm(motion.path - c, axis=1))]) for c in motion.route[1:-1]]
    corner_t = np.interp(corner_s, motion.knot_s[1:-1], motion.knot_t[1:-1], left=np.nan, right=np.nan)
    wp += [float(x) for x in corner_t if np.isfinite(x) and stand0 + 1.5 < x < step_t[-1] - 1.5]
    wp = sorted(wp)
    filled = [wp[0]]
    lo, hi = cfg.waypoint_interval_s
    for nxt in wp[1:]:
        while nxt - filled[-1] > hi:
            gap = rng.uniform(lo, hi)
            filled.append(filled[-1] + (gap if nxt - filled[-1] - gap >= lo else 0.5 * (nxt - filled[-1])))
        if nxt - filled[-1] >= 1.5 or nxt == wp[-1]:
            filled.append(nxt)
    wp_t = np.round(np.array(filled) * 1000.0) / 1000.0
    return wp_t, np.round(motion.trajectory.position_at(wp_t), 5)


def _wifi_lines(site: Any, floor_number: int, traj: Trajectory, duration_s: float, t0_unix_ms: int,
                rng: np.random.Generator, put: Callable[[int, int, str], None]) -> None:
    """TYPE_WIFI records: sweeps before each scan; the cache repeats readings missed by a sweep for
    cache_s. ``put(ms since t0, order, line)`` receives each record."""
    cfg = site.config
    scans = np.arange(rng.uniform(0.8, 2.0), duration_s, cfg.scan_interval_s)
    scans = np.maximum(scans + cfg.scan_jitter_s * np.clip(rng.standard_normal(scans.size), -2, 2), 0.05)
    scans = scans[scans < duration_s]
    sweeps = scans - rng.uniform(*cfg.sweep_lag_s, scans.size)
    pre = -np.sort(rng.uniform(0.5, cfg.cache_s - 1.0, int(rng.integers(1, 3))))[::-1]
    sweep_t = np.r_[pre, sweeps]
    k = len(site.bssids)
    where = traj.position_at(np.maximum(sweep_t, 0.0))
    mean = site.radio.mean_rss_pairs(np.repeat(where, k, axis=0), floor_number, np.tile(np.arange(k), sweep_t.size))
    rss = site.radio.measure(mean, rng).reshape(sweep_t.size, k)
    # Each BSSID's own time within the sweep (channels are swept one after another).
    seen = sweep_t[:, None] + rng.uniform(0.0, 0.25, (sweep_t.size, k))
    seen_ms = np.round(seen * 1000.0).astype(np.int64)
    scan_ms = np.round(scans * 1000.0).astype(np.int64)
    cache_rss = np.full(k, np.nan)
    cache_ms = np.zeros(k, np.int64)
    for j in range(pre.size):
        heard = np.isfinite(rss[j])
        cache_rss[heard], cache_ms[heard] = rss[j, heard], seen_ms[j, heard]
    for i, s_ms in enumerate(scan_ms.tolist()):
        j = pre.size + i
        heard = np.isfinite(rss[j])
        cache_rss[heard], cache_ms[heard] = rss[j, heard], seen_ms[j, heard]
        listed = np.isfinite(cache_rss) & (s_ms - cache_ms <= cfg.cache_s * 1000.0) & (cache_ms < s_ms)
        idx = np.flatnonzero(listed)
        idx = idx[np.argsort(-cache_rss[idx], kind="stable")]  # strongest first, as the phone lists them
        for b in idx.tolist():
            put(s_ms, 20, f"{t0_unix_ms + s_ms}\tTYPE_WIFI\t{site.ssids[b]}\t{site.bssids[b]}\t{int(cache_rss[b])}"
                          f"\t{int(site.frequencies_mhz[b])}\t{t0_unix_ms + int(cache_ms[b])}")


def make_walk(site: Any, floor_index: int, t0_unix_ms: int, site_id: str, floor_id: str,
              rng: np.random.Generator) -> IlcWalkTruth:
    """One walk on floor ``floor_index`` of ``site`` (an :class:`indoorloc.simulate.ilc_site.IlcSite`):
    its truth and the lines of its file; ``t0_unix_ms`` [ms] the time of its first waypoint."""
    cfg = site.config
    name = site.floor_names[floor_index]
    gait = _gait(cfg, rng)
    motion = _motion(site.layout, cfg, gait, rng)
    t_ms = _sensor_clock_ms(gait.duration_s, cfg.sample_rate_hz, rng)
    t = t_ms / 1000.0
    imu = _imu(cfg, site.yaw_offset_rad, gait, motion.trajectory, t, rng)
    wp_t, wp_xy = _waypoints(cfg, gait, motion, rng)
    # Records as (time [ms since t0], order within a time stamp, line with unix ms): sensors share
    # their time stamps (as in the real files), then WiFi, then waypoints.
    keys: List[int] = []
    text: List[str] = []

    def put(rel_ms: int, order: int, line: str) -> None:
        keys.append(rel_ms * 64 + order)
        text.append(line)

    _wifi_lines(site, site.floor_numbers[floor_index], motion.trajectory, gait.duration_s, t0_unix_ms, rng, put)
    abs_ms = (t0_unix_ms + t_ms).tolist()
    for order, (type_name, values) in enumerate((("TYPE_ACCELEROMETER", imu.acc), ("TYPE_MAGNETIC_FIELD", imu.mag),
                                                  ("TYPE_GYROSCOPE", imu.gyro),
                                                  ("TYPE_ROTATION_VECTOR", imu.quat_xyzw[:, :3]))):
        fmt = "%d\t" + type_name + "\t%.7g\t%.7g\t%.7g\t3"
        keys.extend((t_ms * 64 + order).tolist())
        text.extend(fmt % (ti, a, b, c) for ti, (a, b, c) in zip(abs_ms, values.tolist()))
    for tw, (x, y) in zip(wp_t.tolist(), wp_xy.tolist()):
        tw_ms = int(round(tw * 1000.0))
        put(tw_ms, 30, f"{t0_unix_ms + tw_ms}\tTYPE_WAYPOINT\t{x:.5f}\t{y:.5f}")
    acc_ms = int(t_ms[0]) - 40
    put(acc_ms, 40, f"{t0_unix_ms + acc_ms}\tTYPE_SENSOR_MAGNETIC_FIELD_ACCURACY_CHANGED\t3")
    order = np.argsort(np.array(keys, dtype=np.int64), kind="stable")
    walk_id = rng.bytes(12).hex()
    end_ms = max(int(t_ms[-1]), int(round(wp_t[-1] * 1000.0)))
    lines = [f"#\tstartTime:{t0_unix_ms - int(rng.integers(6, 24))}",
             f"#\tSiteID:{site_id}\tSiteName:indoorloc synthetic mall {site.seed}\tFloorId:{floor_id}"
             f"\tFloorName:{name}",
             "#\tBrand:indoorloc\tModel:synthetic\tAndroidName:8.1.0\tAPILevel:27\t",
             *_SENSOR_HEADER,
             "#\tVersionName:indoorloc.simulate.ilc_site\tVersionCode:1\t"]
    lines += [text[i] for i in order.tolist()]
    lines.append(f"#\tendTime:{t0_unix_ms + end_ms + int(rng.integers(20, 90))}")
    return IlcWalkTruth(walk_id=walk_id, floor_name=name, step_t_s=gait.step_t_s, step_length_m=gait.step_len_m,
                        yaw_offset_rad=imu.walk_offset_rad, waypoint_t_s=wp_t, waypoint_xy_m=wp_xy, t_s=t,
                        position_m=motion.trajectory.position_at(t), lines=lines)
