"""The particle map-matching filter (paper 000, §II.C, Algorithm 1) written with the `particles`
library (N. Chopin, https://particles-sequential-monte-carlo-in-python.readthedocs.io): a
`StateSpaceModel` run through `particles.SMC` (bootstrap filter, systematic resampling when
ESS < 0.5 N). Benchmark-only peer of indoorloc.mapmatch.ParticleMapMatcher.

The model and the time convention are those of mapmatch_numpy (see its docstring); the network
geometry, connectivity and the move along the network are shared with it, so that the two peers
differ only in the SMC machinery.

State: an (N, 3) float array with columns s (segment index), d (+1 / -1), u [m] from end A.
The speed is a known control stored in the model: X_t | X_{t-1} moves by speeds[t] dt + eta, and
X_0 is the uniform grid moved by speeds[0] dt + eta (the time convention of the numpy peer and of
indoorloc: step k moves with speeds[k], then weighs with headings[k]).
Observation: heading phi_t ~ von Mises(heading(X_t), kappa), log-density
kappa cos(phi - heading) - log(2 pi I0(kappa)), with log I0(kappa) = log(i0e(kappa)) + kappa.

Randomness: the move draws from the model's own np.random.Generator (seeded); `particles` draws
its resampling uniforms from numpy's global generator, which `run` seeds and restores afterwards.
"""

from __future__ import annotations

import numpy as np
import particles
from particles import collectors
from particles import distributions as dists
from particles import state_space_models as ssm
from scipy.special import i0e

from mapmatch_numpy import MatcherSettings, Network


class _MoveOnNetwork(dists.ProbDist):
    """X_t | X_{t-1} = xp: move by distance_m + U(-a, a) with random turns at segment ends."""

    dim = 3

    def __init__(self, network: Network, xp: np.ndarray, distance_m: float, halfwidth_m: float,
                 rng: np.random.Generator):
        self.network, self.xp, self.distance_m = network, xp, distance_m
        self.halfwidth_m, self.rng = halfwidth_m, rng

    def rvs(self, size=None):
        n = self.xp.shape[0] if size is None else int(size)
        dist = np.full(n, self.distance_m)
        if self.halfwidth_m > 0:
            dist += self.rng.uniform(-self.halfwidth_m, self.halfwidth_m, n)
        s, d, u = self.network.move(self.xp[:, 0].astype(np.int64), self.xp[:, 1].astype(np.int64),
                                    self.xp[:, 2], dist, self.rng)
        return np.column_stack([s, d, u]).astype(float)


class _HeadingVonMises(dists.ProbDist):
    """Y_t | X_t: compass heading, von Mises around the particle's heading (eq. (11)).

    logpdf uses the numpy peer's table of the 2M (segment, direction) values of
    kappa cos(phi - heading) (M cosines per step instead of N)."""

    def __init__(self, network: Network, x: np.ndarray, kappa: float):
        self.network, self.x, self.kappa = network, x, kappa
        self.log_norm = np.log(2.0 * np.pi * i0e(kappa)) + kappa  # log(2 pi I0(kappa))

    def logpdf(self, y):
        s, d = self.x[:, 0].astype(np.int64), self.x[:, 1]
        return self.network.heading_log_likelihood(s, d, y, self.kappa) - self.log_norm

    def rvs(self, size=None):
        loc = self.network.headings(self.x[:, 0].astype(np.int64), self.x[:, 1])
        return np.random.vonmises(loc, self.kappa, size=size)


class MapMatchingSSM(ssm.StateSpaceModel):
    """Particle map matching as a state-space model; speeds (T,) [m/s] are a known control."""

    def __init__(self, network: Network, speeds: np.ndarray, dt: float, kappa: float,
                 noise_halfwidth_m: float, rng: np.random.Generator):
        self.network, self.speeds, self.dt = network, np.asarray(speeds, dtype=float), float(dt)
        self.kappa, self.noise_halfwidth_m, self.rng = float(kappa), float(noise_halfwidth_m), rng

    def _grid(self, n: int) -> np.ndarray:
        s, d, u = self.network.initial_states(n)
        return np.column_stack([s, d, u]).astype(float)

    def PX0(self):
        # The deterministic uniform grid at time 0, moved over [0, dt] (rvs(size=N) builds it).
        return _InitialMove(self)

    def PX(self, t, xp):
        return _MoveOnNetwork(self.network, xp, self.speeds[t] * self.dt,
                              self.noise_halfwidth_m, self.rng)

    def PY(self, t, xp, x):
        return _HeadingVonMises(self.network, x, self.kappa)


class _InitialMove(dists.ProbDist):
    """X_0: the uniform grid of the numpy peer moved by speeds[0] dt + eta."""

    dim = 3

    def __init__(self, model: MapMatchingSSM):
        self.model = model

    def rvs(self, size=None):
        m = self.model
        grid = m._grid(int(size))
        return _MoveOnNetwork(m.network, grid, m.speeds[0] * m.dt, m.noise_halfwidth_m, m.rng).rvs()


class ParticlesMapMatcher(MatcherSettings):
    """Same constructor and `run` as mapmatch_numpy.NumpyMapMatcher, on `particles.SMC`."""

    def __init__(self, ends, kappa: float, noise_halfwidth_m: float, num_particles: int,
                 seed: int = 0, ess_threshold: float = 0.5):
        super().__init__(ends, kappa, noise_halfwidth_m, num_particles, seed, ess_threshold)
        self.smc = None

    def _mean_position(self, W, X):
        return self.network.mean_position(X[:, 0].astype(np.int64), X[:, 2], W)

    def run(self, speeds, headings, dt: float) -> np.ndarray:
        """Returns the (T, 2) filtering means of the position [m] (after each heading)."""
        headings = np.asarray(headings, dtype=float)
        model = MapMatchingSSM(self.network, speeds, dt, self.kappa, self.noise_halfwidth_m,
                               np.random.default_rng(self.seed))
        fk = ssm.Bootstrap(ssm=model, data=headings)
        self.smc = particles.SMC(fk=fk, N=self.num_particles, resampling="systematic",
                                 ESSrmin=self.ess_threshold,
                                 collect=[collectors.Moments(mom_func=self._mean_position)])
        saved = np.random.get_state()
        np.random.seed(self.seed)
        try:
            self.smc.run()
        finally:
            np.random.set_state(saved)
        return np.asarray(self.smc.summaries.moments)
