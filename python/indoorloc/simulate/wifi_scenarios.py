"""Synthetic WiFi scenarios of paper 004 (§5.4-5.8): the corridor signal map and the paths.

The paper's map (§5.4): 57 reference points in 3 rows of 19, 0.6 m apart across the corridor
(x) and 0.9 m along it (y), 6 access points, 150 samples per point, λ = (N-1)/(N δ). The paper
does not give the AP positions or the propagation parameters, so this module states its own:
a log-distance path-loss model

    RSS(d) = P0 - 10 n log10(max(d, d0) / d0) + S(point, AP) + e,   e ~ N(0, σ(d)²)

with P0 = -40 dBm at d0 = 1 m, exponent n = 3.0, a per-(point, AP) shadowing S ~ N(0, 2 dB)
fixed for the map (walls, furniture), and a measurement noise σ(d) = 2 + 0.1 d dB. The six APs
stand on both sides of the first quarter of the corridor, where the paper's paths run (Fig. 6).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: AP positions [m] around the corridor's first quarter (x across: 0..1.2 m, y along: 0..16.2 m).
PAPER_LIKE_APS_M = np.array(
    [[-3.0, 0.5], [4.0, 1.5], [-2.5, 4.5], [4.5, 6.0], [-3.5, 9.0], [3.0, 12.5]]
)


@dataclass(frozen=True)
class PathLossModel:
    """Log-distance path loss with shadowing and distance-dependent noise (dBm, m)."""

    p0_dbm: float = -40.0
    exponent: float = 3.0
    d0_m: float = 1.0
    shadowing_db: float = 2.0
    noise_db: float = 2.0
    noise_per_m_db: float = 0.1

    def mean_dbm(self, points_m: np.ndarray, aps_m: np.ndarray) -> np.ndarray:
        d = np.linalg.norm(points_m[:, None, :] - aps_m[None, :, :], axis=2)
        return self.p0_dbm - 10.0 * self.exponent * np.log10(np.maximum(d, self.d0_m) / self.d0_m)

    def noise_sd_db(self, points_m: np.ndarray, aps_m: np.ndarray) -> np.ndarray:
        d = np.linalg.norm(points_m[:, None, :] - aps_m[None, :, :], axis=2)
        return self.noise_db + self.noise_per_m_db * d


def corridor_lattice(rows: int = 3, cols: int = 19, dx_m: float = 0.6, dy_m: float = 0.9) -> np.ndarray:
    """Reference positions (rows*cols, 2) [m]: `rows` across the corridor (x), `cols` along (y)."""
    xs = np.arange(rows) * dx_m
    ys = np.arange(cols) * dy_m
    return np.array([[x, y] for y in ys for x in xs])


def synthetic_scans(
    seed: int = 0,
    samples_per_point: int = 150,
    aps_m: np.ndarray = PAPER_LIKE_APS_M,
    model: PathLossModel = PathLossModel(),
) -> tuple[np.ndarray, np.ndarray]:
    """Survey of the paper-like corridor: positions (57*N, 2) [m] and RSS (57*N, 6) [dBm]."""
    rng = np.random.default_rng(seed)
    points = corridor_lattice()
    mean = model.mean_dbm(points, aps_m) + rng.normal(0.0, model.shadowing_db, size=(len(points), len(aps_m)))
    sd = model.noise_sd_db(points, aps_m)
    rss = mean[:, None, :] + sd[:, None, :] * rng.normal(size=(len(points), samples_per_point, len(aps_m)))
    positions = np.repeat(points, samples_per_point, axis=0)
    return positions, rss.reshape(-1, len(aps_m))


def vertical_path(start_m=(0.6, 0.0), step_m: float = 0.18, steps: int = 27) -> np.ndarray:
    """§5.7.1: X constant, Y += 0.18 m per 1 s step; (steps + 1, 2) positions including the start."""
    t = np.arange(steps + 1)
    return np.c_[np.full(t.size, start_m[0]), start_m[1] + step_m * t]


def complex_rectilinear_path(speed_m: float = 0.47) -> np.ndarray:
    """§5.8: two oblique phases at 0.47 m/s, (0.12, 0.12) -> (1.2, 2.7) -> (0.6, 4.0).

    The text gives slopes ±2.47 and a per-step shift of 0.47 m (its W_x = 0.25 contradicts the
    other numbers); we keep the end points and the speed, so the path has 1 s steps of 0.47 m.
    """
    corners = np.array([[0.12, 0.12], [1.2, 2.7], [0.6, 4.0]])
    points = [corners[0]]
    for a, b in zip(corners[:-1], corners[1:]):
        length = np.linalg.norm(b - a)
        n = int(np.ceil(length / speed_m))
        for k in range(1, n + 1):
            points.append(a + (b - a) * min(1.0, k * speed_m / length))
    return np.array(points)


def circle_path(center_m=(0.6, 4.0), radius_m: float = 0.5, speed_m: float = 0.18, laps: float = 2.0) -> np.ndarray:
    """Uniform circular motion (the paper's third case): 1 s steps of ``speed_m`` on a circle."""
    omega = speed_m / radius_m
    t = np.arange(int(np.ceil(laps * 2 * np.pi / omega)) + 1)
    return np.c_[center_m[0] + radius_m * np.cos(omega * t), center_m[1] + radius_m * np.sin(omega * t)]
