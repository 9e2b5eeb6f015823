"""A synthetic foot-mounted IMU gait with known positions and strides (for the ZUPT tests).

The foot alternates a stance of ``stance_s`` seconds and a swing of ``swing_s`` seconds that moves
it ``stride_m`` metres forward along ``heading_rad`` with a raised-cosine speed profile, a lift of
``lift_m`` and a pitch of up to ``pitch_deg``; an initial and a final rest of ``rest_s`` frame
the walk. The specific force and angular rate are exact for that motion (sensor frame, body z up
at rest), plus white noise. Three knobs reproduce what real recordings do to a zero-velocity
detector:

- ``stance_rate_radps``: the foot trembles during every stance, turning about its y axis at
  this rate [rad/s] back and forth (a square wave of the rate at about ``tremor_hz``, so the
  pitch is a small triangle wave that ends at 0), and the stance is never fully still: a
  running foot (about 1 rad/s), or a walk whose rest is noisier than a detector expects
  (0.2-0.4 rad/s). The sensor turns about itself and does not translate, so the zero-velocity
  hypothesis holds.
- short ``stance_s`` with long ``stride_m`` (a run), or long stances with short, gentle swings
  (a very slow walk: the swing is above any threshold for only a fraction of its duration).
- ``noise_acc_mps2`` / ``noise_gyro_radps``: white sensor noise (sd per axis).
- ``timing_jitter`` / ``tremor_spread``: stride-to-stride variability of a real walk. Each swing
  and stance lasts its nominal duration times ``1 + timing_jitter * z`` (z standard normal,
  clipped to +-2), each stance trembles at ``stance_rate_radps`` times a factor drawn uniformly
  from ``[1 - tremor_spread, 1 + tremor_spread]``. :func:`slow_low_motion_gait` combines them
  with short, flat, slow swings: the walk on which the issue-16 swing guard traded a walk for a
  standstill (0 strides, stance 98.6 %, 30 ms "swings").

Swing kinematics (u = t / swing in [0, 1]): forward s(u) = stride (u - sin(2 pi u) / (2 pi)), up
z(u) = lift (1 - cos 2 pi u) / 2, pitch theta(u) = A sin(2 pi u) (1 - cos 2 pi u) / 2 (toe down,
then heel down; peak |theta| = pitch), all with zero rate at both ends. With R = Rz(heading) Ry(theta) (body -> nav), the body angular rate is
theta' e_y and the specific force R^T (a_nav + g e_z). Deterministic for a given ``seed``.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

from indoorloc.io.pdr_datasets import ImuRecording

__all__ = ["foot_gait", "slow_low_motion_gait"]


def _ry(theta: np.ndarray) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    r = np.zeros(theta.shape + (3, 3))
    r[..., 0, 0] = c
    r[..., 0, 2] = s
    r[..., 1, 1] = 1.0
    r[..., 2, 0] = -s
    r[..., 2, 2] = c
    return r


def foot_gait(steps: int = 20, *, stance_s: float = 0.5, swing_s: float = 0.6, stride_m: float = 1.4,
              lift_m: float = 0.1, pitch_deg: float = 30.0, stance_rate_radps: float = 0.0,
              rest_s: float = 2.0, heading_rad: float = 0.0, rate_hz: float = 200.0, tremor_hz: float = 10.0,
              noise_acc_mps2: float = 0.03, noise_gyro_radps: float = 0.003, gravity_mps2: float = 9.81,
              timing_jitter: float = 0.0, tremor_spread: float = 0.0,
              seed: int = 0, name: Optional[str] = None) -> ImuRecording:
    """A straight synthetic walk as an :class:`~indoorloc.io.ImuRecording` (sensor ``"synthetic"``).

    Parameters are in seconds, metres, degrees (pitch), rad/s and Hz as named. The recording's
    ``truth_xy_m`` is the true per-sample position (x, y) [m] in the navigation frame (x along
    ``heading_rad``), ``stride_indices`` the middle sample of each stance phase (the initial rest
    first, so ``steps + 1`` entries), ``distance_m`` = ``steps * stride_m``.
    """
    for arg, v in (("stance_s", stance_s), ("swing_s", swing_s), ("rate_hz", rate_hz), ("rest_s", rest_s)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"indoorloc: argument '{arg}': must be > 0, got {v!r}")
    if steps < 1:
        raise ValueError(f"indoorloc: argument 'steps': must be >= 1, got {steps!r}")
    for arg, v in (("timing_jitter", timing_jitter), ("tremor_spread", tremor_spread)):
        if not (math.isfinite(v) and 0.0 <= v <= 1.0):
            raise ValueError(f"indoorloc: argument '{arg}': must be in [0, 1], got {v!r}")
    # Per-stride variability from its own stream, so that timing_jitter = tremor_spread = 0
    # reproduces the recordings of earlier versions sample for sample.
    vrng = np.random.default_rng([int(seed), 0x6A17])
    jit = 1.0 + timing_jitter * np.clip(vrng.standard_normal((steps, 2)), -2.0, 2.0)
    tremor_factor = 1.0 + tremor_spread * vrng.uniform(-1.0, 1.0, steps)
    n_st = max(2, int(round(stance_s * rate_hz)))
    n_rest = max(n_st, int(round(rest_s * rate_hz)))
    phases = [("rest", n_rest, 1.0)]
    for s in range(steps):
        phases.append(("swing", max(4, int(round(swing_s * jit[s, 0] * rate_hz))), 1.0))
        if s < steps - 1:
            phases.append(("stance", max(2, int(round(stance_s * jit[s, 1] * rate_hz))), float(tremor_factor[s])))
        else:
            phases.append(("rest", n_rest, 1.0))
    n = sum(k for _, k, _ in phases)
    pos = np.zeros((n, 3))
    a_nav = np.zeros((n, 3))
    theta = np.zeros(n)
    theta_rate = np.zeros(n)
    mid = []
    k = 0
    x0 = 0.0
    max_pitch = math.radians(pitch_deg)
    for kind, m, tremor in phases:
        sl = slice(k, k + m)
        if kind == "swing":
            u = (np.arange(m) + 1.0) / m
            T = m / rate_hz
            w = 2 * math.pi
            pos[sl, 0] = x0 + stride_m * (u - np.sin(w * u) / w)
            pos[sl, 2] = lift_m * (1 - np.cos(w * u)) / 2
            a_nav[sl, 0] = stride_m * w * np.sin(w * u) / T ** 2
            a_nav[sl, 2] = lift_m * w * w * np.cos(w * u) / (2 * T ** 2)
            # toe down after toe-off, heel down before heel strike: theta = A sin(w u)(1 - cos w u)/2
            # (|theta| <= pitch, A = pitch / 0.6495), rate A pi (cos w u - cos 2 w u) / T, large
            # through mid-swing as on a real foot
            amp = max_pitch / 0.649519052838329
            theta[sl] = amp * np.sin(w * u) * (1 - np.cos(w * u)) / 2
            theta_rate[sl] = amp * math.pi * (np.cos(w * u) - np.cos(2 * w * u)) / T
            x0 += stride_m
        else:
            pos[sl, 0] = x0
            mid.append(k + m // 2)
            if kind == "stance" and stance_rate_radps > 0:
                # tremor: theta' = +-r, an even number of half periods so that theta ends at 0
                half = max(1, m // (2 * max(1, int(round(tremor_hz * m / rate_hz)))))
                sign = np.where((np.arange(m) // half) % 2 == 0, 1.0, -1.0)
                sign[(m // (2 * half)) * 2 * half:] = 0.0  # an unfinished period stays still
                theta_rate[sl] = stance_rate_radps * tremor * sign
                theta[sl] = np.cumsum(theta_rate[sl]) / rate_hz
        k += m
    # Rotate the forward axis by the heading.
    c, s = math.cos(heading_rad), math.sin(heading_rad)
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    pos = pos @ rz.T
    a_nav = a_nav @ rz.T
    r = rz @ _ry(theta)                                       # (n, 3, 3) body -> nav
    f_nav = a_nav + np.array([0.0, 0.0, gravity_mps2])
    acc = np.einsum("nji,nj->ni", r, f_nav)                   # R^T f_nav
    gyro = np.zeros((n, 3))
    gyro[:, 1] = theta_rate
    rng = np.random.default_rng([int(seed), 0xF007])
    acc += noise_acc_mps2 * rng.standard_normal((n, 3))
    gyro += noise_gyro_radps * rng.standard_normal((n, 3))
    time_s = np.arange(n) / float(rate_hz)
    return ImuRecording(name=name or f"synthetic_{steps}x{stride_m:g}m", time_s=time_s, acc_mps2=acc,
                        gyro_radps=gyro, rate_hz=float(rate_hz), truth_xy_m=pos[:, :2].copy(),
                        stride_indices=np.asarray(mid, dtype=np.int64), closed_loop=False,
                        distance_m=float(steps * stride_m), source_units="synthetic SI",
                        sensor="synthetic")


def slow_low_motion_gait(steps: int = 29, *, stride_m: float = 0.29, seed: int = 0, **overrides: float) -> ImuRecording:
    """A slow, low-motion walk (a shuffle): short strides (0.29 m), flat swings (pitch 5 deg,
    lift 2 cm) of 0.7 s, long stances (1.0 s) that tremble unevenly (0.3 rad/s +- 80 %), stride
    timing varying by 15 %. The defaults imitate the held-out PyShoe trial of 29 strides over
    8.4 m on which the swing guard of issue 16 climbed to 5.6e6 and read 0 strides. Keywords
    override any :func:`foot_gait` parameter."""
    params = dict(stance_s=1.0, swing_s=0.7, pitch_deg=5.0, lift_m=0.02, stance_rate_radps=0.3,
                  tremor_spread=0.8, timing_jitter=0.15)
    params.update(overrides)
    return foot_gait(steps, stride_m=stride_m, seed=seed, name=f"slow_low_motion_{steps}x{stride_m:g}m_s{seed}",
                     **params)
