"""Lorenz-63 simulator: the chaotic test system of the analog HMM paper (Lguensat et al. 2016, §3.1).

The Lorenz (1963) equations, as written in the paper (its mu is the usual sigma)::

    dx/dt = sigma (y - x),   dy/dt = x (rho - z) - y,   dz/dt = x y - beta z,

with sigma = 10, rho = 28, beta = 8/3, integrated by the classical fourth-order Runge-Kutta
scheme at dt = 0.01 (one integration step = one time step of the catalog and of the test
sequence, the paper's "unit sampling rate").

Use :func:`catalog_trajectory` for the catalog of (analog, successor) pairs and
:func:`test_problem` for a truth/observation pair of Table 1: only x is observed, with noise
variance R = 2, every ``dt_obs`` = 40 steps. Both start from a random point and discard a
spin-up of 5000 steps so that the states lie on the attractor.

Randomness is explicit: each function takes a seed and derives its own stream,
``numpy.random.default_rng([seed, purpose])``, so that a catalog and a test problem made with the
same integer seed are independent simulations (``purpose`` 0 for catalogs, 1 for test problems).
Numpy only.
"""

from __future__ import annotations

from typing import Tuple

import numpy as np

SIGMA = 10.0
RHO = 28.0
BETA = 8.0 / 3.0
DT = 0.01
SPIN_UP_STEPS = 5000

#: Climatology of the attractor (long run, symmetrised under (x, y, z) -> (-x, -y, z)): the
#: background of the ensemble smoothers. Overall std sqrt(trace(cov) / 3) = 8.5.
CLIMATOLOGY_MEAN = np.array([0.0, 0.0, 23.55])
CLIMATOLOGY_COV = np.array([[62.76, 62.76, 0.0], [62.76, 81.21, 0.0], [0.0, 0.0, 74.36]])

_CATALOG_STREAM = 0
_TEST_STREAM = 1


def derivative(X: np.ndarray) -> np.ndarray:
    """Time derivative of the Lorenz-63 system for states ``X`` (..., 3); returns (..., 3)."""
    X = np.asarray(X, dtype=float)
    x, y, z = X[..., 0], X[..., 1], X[..., 2]
    out = np.empty_like(X)
    out[..., 0] = SIGMA * (y - x)
    out[..., 1] = x * (RHO - z) - y
    out[..., 2] = x * y - BETA * z
    return out


def rk4_step(X: np.ndarray, dt: float = DT) -> np.ndarray:
    """One classical Runge-Kutta step of length ``dt`` for many states at once.

    Parameters
    ----------
    X : (n, 3) or (3,) array
        States (x, y, z).
    dt : float
        Step [model time units], 0.01 in the paper.

    Returns
    -------
    (n, 3) or (3,) array: the states at t + dt.
    """
    X = np.asarray(X, dtype=float)
    k1 = derivative(X)
    k2 = derivative(X + 0.5 * dt * k1)
    k3 = derivative(X + 0.5 * dt * k2)
    k4 = derivative(X + dt * k3)
    return X + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def _simulate_one(x0: np.ndarray, n_steps: int, dt: float) -> np.ndarray:
    # Plain floats: ~10x faster than numpy on a (1, 3) array for one long trajectory.
    # Same arithmetic as rk4_step.
    out = np.empty((n_steps + 1, 3))
    x, y, z = (float(v) for v in x0)
    out[0] = (x, y, z)
    h = 0.5 * dt
    s, r, b = SIGMA, RHO, BETA
    for i in range(1, n_steps + 1):
        a1 = s * (y - x); b1 = x * (r - z) - y; c1 = x * y - b * z  # noqa: E702
        x2 = x + h * a1; y2 = y + h * b1; z2 = z + h * c1  # noqa: E702
        a2 = s * (y2 - x2); b2 = x2 * (r - z2) - y2; c2 = x2 * y2 - b * z2  # noqa: E702
        x3 = x + h * a2; y3 = y + h * b2; z3 = z + h * c2  # noqa: E702
        a3 = s * (y3 - x3); b3 = x3 * (r - z3) - y3; c3 = x3 * y3 - b * z3  # noqa: E702
        x4 = x + dt * a3; y4 = y + dt * b3; z4 = z + dt * c3  # noqa: E702
        a4 = s * (y4 - x4); b4 = x4 * (r - z4) - y4; c4 = x4 * y4 - b * z4  # noqa: E702
        x += dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
        y += dt / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
        z += dt / 6.0 * (c1 + 2.0 * c2 + 2.0 * c3 + c4)
        out[i] = (x, y, z)
    return out


def simulate(x0: np.ndarray, n_steps: int, dt: float = DT) -> np.ndarray:
    """Integrate from ``x0`` for ``n_steps`` RK4 steps.

    Parameters
    ----------
    x0 : (3,) or (n, 3) array
        Initial state(s).
    n_steps : int
        Number of steps (>= 0).
    dt : float
        Step [model time units].

    Returns
    -------
    (n_steps + 1, 3) or (n_steps + 1, n, 3) array: the trajectory, ``x0`` first.
    """
    x0 = np.asarray(x0, dtype=float)
    if x0.shape[-1] != 3 or x0.ndim not in (1, 2):
        raise ValueError(f"indoorloc: argument 'x0': expected shape (3,) or (n, 3), got {x0.shape}")
    if int(n_steps) != n_steps or n_steps < 0:
        raise ValueError(f"indoorloc: argument 'n_steps': expected an integer >= 0, got {n_steps}")
    if not dt > 0:
        raise ValueError(f"indoorloc: argument 'dt': expected > 0, got {dt}")
    n_steps = int(n_steps)
    if x0.ndim == 1:
        return _simulate_one(x0, n_steps, dt)
    out = np.empty((n_steps + 1,) + x0.shape)
    out[0] = x0
    for i in range(n_steps):
        out[i + 1] = rk4_step(out[i], dt)
    return out


def _random_start(rng: np.random.Generator) -> np.ndarray:
    return rng.standard_normal(3) * 5.0 + np.array([0.0, 0.0, 25.0])


def catalog_trajectory(m: int, dt: float = DT, seed: int = 0) -> np.ndarray:
    """A catalog trajectory: ``m + 1`` consecutive states on the attractor, hence ``m`` pairs.

    Starts from a random point of stream ``default_rng([seed, 0])``, discards a spin-up of 5000
    steps, then records ``m + 1`` states ``dt`` apart: pair i is (states[i], states[i + 1]).

    Returns
    -------
    (m + 1, 3) array.
    """
    if int(m) != m or m < 1:
        raise ValueError(f"indoorloc: argument 'm': expected an integer >= 1, got {m}")
    rng = np.random.default_rng([int(seed), _CATALOG_STREAM])
    start = _simulate_one(_random_start(rng), SPIN_UP_STEPS, dt)[-1]
    return _simulate_one(start, int(m), dt)


def test_problem(
    seed: int, T: int = 1000, dt_obs: int = 40, R: float = 2.0, dt: float = DT
) -> Tuple[np.ndarray, np.ndarray]:
    """A test sequence of Table 1: truth and noisy, sparse observations of x.

    An independent simulation (stream ``default_rng([seed, 1])``: random start, 5000 spin-up
    steps), then ``T`` states ``dt`` apart. x is observed at t = 0, dt_obs, 2 dt_obs, ... with
    additive N(0, R) noise; every other entry is NaN.

    Parameters
    ----------
    seed : int
    T : int
        Number of time steps.
    dt_obs : int
        Steps between observations (40 in the paper).
    R : float
        Observation noise variance (2 in the paper).
    dt : float
        Integration step.

    Returns
    -------
    truth : (T, 3) array
    observations : (T, 1) array, NaN where x is not observed.
    """
    if int(T) != T or T < 1:
        raise ValueError(f"indoorloc: argument 'T': expected an integer >= 1, got {T}")
    if int(dt_obs) != dt_obs or dt_obs < 1:
        raise ValueError(f"indoorloc: argument 'dt_obs': expected an integer >= 1, got {dt_obs}")
    if not R >= 0:
        raise ValueError(f"indoorloc: argument 'R': expected a variance >= 0, got {R}")
    rng = np.random.default_rng([int(seed), _TEST_STREAM])
    start = _simulate_one(_random_start(rng), SPIN_UP_STEPS, dt)[-1]
    truth = _simulate_one(start, int(T) - 1, dt)
    observations = np.full((int(T), 1), np.nan)
    t_obs = np.arange(0, int(T), int(dt_obs))
    observations[t_obs, 0] = truth[t_obs, 0] + np.sqrt(R) * rng.standard_normal(t_obs.size)
    return truth, observations


test_problem.__test__ = False  # not a pytest test when imported into a test module
