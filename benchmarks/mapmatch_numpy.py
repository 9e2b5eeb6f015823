"""Vectorised numpy peer of the particle map-matching filter (paper 000, El Mokhtari et al.,
"Indoor Localization by Particle Map Matching", §II.C and Algorithm 1).

Benchmark-only reference: the same model as indoorloc.mapmatch.ParticleMapMatcher, written with
numpy arrays over the particles (no Python loop over particles; loops over time steps and over
the "still past an end" iterations only).

Model
-----
Network: M straight segments, ``ends`` (M, 4) = x_A, y_A, x_B, y_B [m]; ``beta`` = atan2 of A->B.
Connectivity: for each (segment, end), end 0 = A, 1 = B, the continuations (segment', enter_end')
are every other segment end within ``tol`` of this end; a U-turn (same segment, same end) only
at a dead end. Padded as ``cont_seg``/``cont_end`` (M, 2, C) and ``cont_count`` (M, 2).

Particle: segment s, direction d (+1 A->B, -1 B->A), distance u in [0, length[s]] from end A.

Time convention (as indoorloc.mapmatch.ParticleMapMatcher.run): the initial grid is the prior
at time 0; step k (k = 0..T-1) moves every particle by ``speeds[k] * dt + eta`` (the speed over
[k dt, (k + 1) dt]), weights it with ``headings[k]`` (the heading at (k + 1) dt) and records the
weighted mean, then resamples if needed. So ``estimates[k]`` estimates the position at (k + 1) dt.

Initialisation: ceil(N/2) positions at arc lengths (k + 1/2) * L / ceil(N/2) along the
concatenated segments (L = total length), each used by a forward and then a backward particle
(particle i: position i // 2, d = +1 if i is even else -1); log-weights uniform.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

MAX_JUNCTION_ITERATIONS = 100


def build_connectivity(ends: np.ndarray, tol: float = 1e-6):
    """Continuations of every (segment, end) from the geometry.

    Parameters
    ----------
    ends : (M, 4) array, x_A, y_A, x_B, y_B [m].
    tol : ends closer than this [m] are the same junction.

    Returns
    -------
    cont_seg, cont_end : (M, 2, C) int arrays (padded with -1), the segment entered and the end
        at which it is entered (0 = A: then forward, 1 = B: then backward).
    cont_count : (M, 2) int array, number of valid entries (>= 1: a dead end gets its U-turn).
    """
    ends = np.asarray(ends, dtype=float)
    m = ends.shape[0]
    points = np.concatenate([ends[:, 0:2], ends[:, 2:4]])  # row e * M + s = end e of segment s
    seg_of = np.tile(np.arange(m), 2)
    end_of = np.repeat([0, 1], m)
    neighbours = cKDTree(points).query_ball_point(points, r=tol)
    lists = [[[], []] for _ in range(m)]
    for row, near in enumerate(neighbours):
        s, e = int(seg_of[row]), int(end_of[row])
        conts = sorted((int(seg_of[j]), int(end_of[j])) for j in near if seg_of[j] != s)
        lists[s][e] = conts if conts else [(s, e)]  # U-turn only at a dead end
    c = max(len(lists[s][e]) for s in range(m) for e in range(2))
    cont_seg = np.full((m, 2, c), -1, dtype=np.int64)
    cont_end = np.full((m, 2, c), -1, dtype=np.int64)
    cont_count = np.zeros((m, 2), dtype=np.int64)
    for s in range(m):
        for e in range(2):
            conts = lists[s][e]
            cont_count[s, e] = len(conts)
            cont_seg[s, e, : len(conts)] = [q[0] for q in conts]
            cont_end[s, e, : len(conts)] = [q[1] for q in conts]
    return cont_seg, cont_end, cont_count


class Network:
    """Geometry and connectivity arrays shared by the numpy and `particles` peers."""

    def __init__(self, ends: np.ndarray, tol: float = 1e-6):
        self.ends = np.ascontiguousarray(ends, dtype=float)
        if self.ends.ndim != 2 or self.ends.shape[1] != 4 or self.ends.shape[0] == 0:
            raise ValueError(f"ends must be (M, 4) with M >= 1, got {self.ends.shape}")
        delta = self.ends[:, 2:4] - self.ends[:, 0:2]
        self.length = np.hypot(delta[:, 0], delta[:, 1])
        if not np.all(self.length > 0):
            raise ValueError(f"zero-length segment(s) at index {np.flatnonzero(self.length <= 0)}")
        self.beta = np.arctan2(delta[:, 1], delta[:, 0])
        self.unit = delta / self.length[:, None]
        self.total_length = float(self.length.sum())
        self.cont_seg, self.cont_end, self.cont_count = build_connectivity(self.ends, tol)

    def initial_states(self, n: int):
        """(s, d, u) of the uniform initial grid (see the module docstring)."""
        n_pos = (n + 1) // 2
        spacing = self.total_length / n_pos
        arc = (np.arange(n) // 2 + 0.5) * spacing
        start = np.concatenate([[0.0], np.cumsum(self.length)[:-1]])
        s = np.searchsorted(start, arc, side="right") - 1
        s = np.clip(s, 0, self.length.size - 1)
        u = np.clip(arc - start[s], 0.0, self.length[s])
        d = np.where(np.arange(n) % 2 == 0, 1, -1).astype(np.int64)
        return s.astype(np.int64), d, u

    def move(self, s, d, u, distance, rng: np.random.Generator):
        """Move particles by `distance` (N,) [m] along their direction, choosing a continuation
        uniformly at each end passed; returns new (s, d, u) (inputs are not modified).

        A negative distance (v dt + eta < 0, eq. (8)-(9) have no floor) moves a particle back
        within its segment; it stops at the end behind it (as indoorloc's filter). Past the end
        ahead, it enters the continuation travelling away from the junction (the paper's psi)."""
        u = u + d * distance
        length = self.length
        idx = np.flatnonzero((u > length[s]) | (u < 0.0))
        if idx.size == 0:
            return s.copy(), d.copy(), u
        s, d = s.copy(), d.copy()
        for _ in range(MAX_JUNCTION_ITERATIONS):
            if idx.size == 0:
                break
            si, ui = s[idx], u[idx]
            end = (ui > length[si]).astype(np.int64)  # 1: past B, 0: before A
            behind = (end == 1) != (d[idx] > 0)  # a negative step: stop at that end
            u[idx[behind]] = np.where(end[behind] == 1, length[si[behind]], 0.0)
            idx, si, ui, end = idx[~behind], si[~behind], ui[~behind], end[~behind]
            leftover = np.where(end == 1, ui - length[si], -ui)
            count = self.cont_count[si, end]
            j = (rng.random(idx.size) * count).astype(np.int64)
            new_s = self.cont_seg[si, end, j]
            enter = self.cont_end[si, end, j]
            new_d = 1 - 2 * enter  # enter at A: forward, at B: backward
            new_u = np.where(enter == 0, leftover, length[new_s] - leftover)
            s[idx], d[idx], u[idx] = new_s, new_d, new_u
            still = (new_u > length[new_s]) | (new_u < 0.0)
            idx = idx[still]
        if idx.size:  # still outside after MAX_JUNCTION_ITERATIONS (tiny segments): clamp
            u[idx] = np.clip(u[idx], 0.0, length[s[idx]])
        return s, d, u

    def headings(self, s, d):
        """Heading of each particle [rad]: beta[s] forward, beta[s] + pi backward."""
        return self.beta[s] + np.where(d < 0, np.pi, 0.0)

    def heading_log_likelihood(self, s, d, heading_rad: float, kappa: float):
        """kappa cos(phi - heading) of each particle (eq. (11) up to a constant), from a table
        of the 2M (segment, direction) values: M cosines per step instead of N."""
        table = kappa * np.cos(heading_rad - np.stack([self.beta, self.beta + np.pi], axis=1))
        return table.ravel()[2 * s + (d < 0)]

    def positions(self, s, u):
        """(N, 2) positions [m]."""
        return self.ends[s, 0:2] + u[:, None] * self.unit[s]

    def mean_position(self, s, u, w):
        """Eq. (13): sum_i w_i p_i (2,) [m], accumulated per segment (bincount) so that no
        (N, 2) array is formed: sum over segments of W_s p_A(s) + (sum w u)_s e(s)."""
        m = self.length.size
        w_seg = np.bincount(s, weights=w, minlength=m)
        wu_seg = np.bincount(s, weights=w * u, minlength=m)
        return w_seg @ self.ends[:, 0:2] + wu_seg @ self.unit


def systematic_resample(w: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Ancestor indices by systematic resampling of normalised weights w (N,)."""
    n = w.size
    positions = (rng.random() + np.arange(n)) / n
    return np.minimum(np.searchsorted(np.cumsum(w), positions), n - 1)


class MatcherSettings:
    """What both peers are built from (this one and mapmatch_particles.ParticlesMapMatcher):
    the network of segment ends (M, 4) [m], κ, the half-width a [m] of the travelled-distance
    noise, N particles, the seed and the ESS threshold (a fraction of N)."""

    def __init__(self, ends, kappa: float, noise_halfwidth_m: float, num_particles: int,
                 seed: int = 0, ess_threshold: float = 0.5):
        if num_particles < 1:
            raise ValueError("num_particles must be >= 1")
        self.network = ends if isinstance(ends, Network) else Network(ends)
        self.kappa = float(kappa)
        self.noise_halfwidth_m = float(noise_halfwidth_m)
        self.num_particles = int(num_particles)
        self.seed = seed
        self.ess_threshold = float(ess_threshold)


class NumpyMapMatcher(MatcherSettings):
    """Particle map matching with numpy (paper 000, Algorithm 1).

    Parameters
    ----------
    ends : (M, 4) segment ends [m].
    kappa : von Mises concentration of the heading likelihood (kappa_P).
    noise_halfwidth_m : a, the travelled distance per step is v dt + U(-a, a) [m].
    num_particles : N.
    seed : seed of np.random.default_rng.
    ess_threshold : resample when ESS < ess_threshold * N.
    """

    def __init__(self, ends, kappa: float, noise_halfwidth_m: float, num_particles: int,
                 seed: int = 0, ess_threshold: float = 0.5):
        MatcherSettings.__init__(self, ends, kappa, noise_halfwidth_m, num_particles, seed, ess_threshold)
        self.reset()

    def reset(self, seed=None):
        """Uniform initial grid, uniform weights, fresh generator."""
        self.rng = np.random.default_rng(self.seed if seed is None else seed)
        self.s, self.d, self.u = self.network.initial_states(self.num_particles)
        self._uniform_weights()
        self.num_resamples = 0

    def _uniform_weights(self):
        n = self.num_particles
        self.log_w = np.full(n, -np.log(n))
        self.w = np.full(n, 1.0 / n)
        self.ess = float(n)

    def particle_states(self):
        """Copies of (s (N,) int, d (N,) int +-1, u (N,) [m], normalised log-weights (N,))."""
        return self.s.copy(), self.d.copy(), self.u.copy(), self.log_w.copy()

    def set_particle_states(self, s, d, u, log_w=None):
        s = np.asarray(s, dtype=np.int64).ravel()
        self.s, self.d = s.copy(), np.asarray(d, dtype=np.int64).ravel().copy()
        self.u = np.asarray(u, dtype=float).ravel().copy()
        self.num_particles = s.size
        self._uniform_weights()
        if log_w is not None:
            self.log_w = np.asarray(log_w, dtype=float).ravel().copy()
            self.w = np.exp(self.log_w)
            self.ess = 1.0 / float(np.dot(self.w, self.w))

    def predict(self, speed_mps: float, dt_s: float):
        """Eqs. (8)-(10): move by v dt + eta, eta ~ U(-a, a), with random turns at ends."""
        distance = speed_mps * dt_s
        if self.noise_halfwidth_m > 0:
            distance = distance + self.rng.uniform(-self.noise_halfwidth_m, self.noise_halfwidth_m,
                                                   self.num_particles)
        else:
            distance = np.full(self.num_particles, distance)
        self.s, self.d, self.u = self.network.move(self.s, self.d, self.u, distance, self.rng)

    def update(self, heading_rad: float):
        """Eqs. (11)-(12): log w += kappa cos(phi - heading), normalised by log-sum-exp; ESS."""
        log_w = self.log_w + self.network.heading_log_likelihood(self.s, self.d, heading_rad, self.kappa)
        log_w -= log_w.max()
        w = np.exp(log_w)
        total = w.sum()
        self.log_w = log_w - np.log(total)
        self.w = w / total
        self.ess = 1.0 / float(np.dot(self.w, self.w))

    def estimate(self) -> np.ndarray:
        """Eq. (13): weighted mean position (2,) [m]."""
        return self.network.mean_position(self.s, self.u, self.w)

    def resample_if_needed(self):
        """Eq. (14): systematic resampling when ESS < threshold * N; weights reset to 1/N."""
        if self.ess < self.ess_threshold * self.num_particles:
            a = systematic_resample(self.w, self.rng)
            self.s, self.d, self.u = self.s[a], self.d[a], self.u[a]
            self._uniform_weights()
            self.num_resamples += 1

    def run(self, speeds, headings, dt: float) -> np.ndarray:
        """Filter a trajectory from the initial grid; returns (T, 2) estimated positions [m]."""
        speeds = np.asarray(speeds, dtype=float)
        headings = np.asarray(headings, dtype=float)
        if speeds.shape != headings.shape or speeds.ndim != 1:
            raise ValueError("speeds and headings must be 1-D arrays of the same length")
        self.reset()
        out = np.empty((headings.size, 2))
        for t in range(headings.size):
            self.predict(speeds[t], dt)
            self.update(headings[t])
            out[t] = self.estimate()
            self.resample_if_needed()
        return out
