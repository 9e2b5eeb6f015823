"""The Lorenz-63 data of AnDA's published script, regenerated: one test sequence and its catalog.

The authors of paper 001 published their Lorenz-63 generator with the Analog Data Assimilation
library (``ptandeo/AnDA``, ``AnDA_codes/AnDA_generate_data.py``, called by ``test_AnDA``). Its
data are one fixed realisation, which is very likely what the paper's Table 1 and Fig. 2 show
(one figure per cell, no spread). This module rewrites that generator with the published
settings (it is not their code):

- the legacy numpy generator seeded once, ``np.random.seed(1)``: here a private
  ``numpy.random.RandomState(1)`` (same Mersenne-Twister stream, no global state touched);
- Lorenz-63 with sigma = 10, rho = 28, beta = 8/3 integrated by ``scipy.integrate.odeint``
  (LSODA, default tolerances) on a grid of dt_integration = 0.01, as theirs;
- spin-up: from x0 = (8, 0, 30) over ``np.arange(0, 5 + 1e-6, 0.01)`` (5 time units); the test
  sequence starts at the spin-up's last state and covers ``np.arange(0.01, nb_loop_test + 1e-6,
  0.01)`` (T = 100 nb_loop_test states, the first being the start itself: odeint returns the
  initial value first); dt_states = 1;
- observation noise: ``multivariate_normal(0, sigma2_obs I_3, T)`` drawn once for all three
  components and every step; x (``var_obs = [0]``) is kept at t = 0, dt_obs, 2 dt_obs, ...;
- the catalog continues the test run: odeint from the test sequence's last state over
  ``np.arange(0.01, nb_loop_train + 1e-6, 0.01)`` (100 nb_loop_train states, hence
  100 nb_loop_train - 1 (analog, successor) pairs), plus ``multivariate_normal(0, sigma2_catalog
  I_3, ·)`` noise (0 in their Lorenz-63 example, drawn anyway so the stream stays aligned).

Their script uses dt_obs = 8, nb_loop_train = 10^2; paper 001's Table 1 has dt_obs = 40 and
M = 10^4 / 10^5 pairs (nb_loop_train = 100 / 1000). The smoothers of their script start from
``xb = xt[0]`` (the true first state) with ``B = 0.1 I``: :func:`anda_prior_weights` gives that
prior on the catalog states for the analog HMM.

What is matched and what not (see docs/analog.md): the random stream is numpy's legacy
MT19937 with the same calls in the same order, so the noise values are those of their script
(numpy keeps the legacy stream fixed across versions); the states come from the same LSODA
solver with the same tolerances and time grid, so they agree up to floating-point differences
between SciPy/LAPACK builds (amplified by the chaos over the 15 time units of spin-up and test).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from indoorloc.simulate.lorenz63 import BETA, RHO, SIGMA

ANDA_X0 = np.array([8.0, 0.0, 30.0])
ANDA_SEED = 1
ANDA_SPIN_UP_TIME = 5.0
ANDA_DT_INTEGRATION = 0.01
#: Background covariance of AnDA's smoothers at t = 0 (``B = 0.1 I`` around the true x_0).
ANDA_PRIOR_VARIANCE = 0.1


@dataclass
class AndaProblem:
    """One AnDA-style data set: truth (T, 3), observations (T, 1) with NaN where x is not
    observed, and the catalog trajectory (100 nb_loop_train, 3) whose consecutive states are the
    (analog, successor) pairs."""

    truth: np.ndarray
    observations: np.ndarray
    catalog: np.ndarray


def _lorenz63(state, t, sigma, rho, beta):
    x, y, z = state
    return [sigma * (y - x), x * (rho - z) - y, x * y - beta * z]


def anda_problem(nb_loop_test: int = 10, nb_loop_train: int = 1000, dt_obs: int = 40, sigma2_obs: float = 2.0,
                 sigma2_catalog: float = 0.0, seed: int = ANDA_SEED) -> AndaProblem:
    """AnDA's Lorenz-63 generator with paper 001's Table 1 settings by default.

    Parameters
    ----------
    nb_loop_test : int
        Length of the test sequence in model time units (T = 100 nb_loop_test steps of 0.01).
    nb_loop_train : int
        Length of the catalog run in model time units (100 nb_loop_train states): 100 gives
        M = 10^4 - 1 pairs, 1000 gives 10^5 - 1.
    dt_obs : int
        Steps between observations of x (40 in paper 001's Table 1; 8 in AnDA's example).
    sigma2_obs, sigma2_catalog : float
        Variances of the observation noise and of the catalog noise [state units^2].
    seed : int
        Seed of the legacy numpy generator (1 in AnDA).

    Returns
    -------
    AndaProblem
    """
    from scipy.integrate import odeint

    for name, value in (("nb_loop_test", nb_loop_test), ("nb_loop_train", nb_loop_train), ("dt_obs", dt_obs)):
        if int(value) != value or value < 1:
            raise ValueError(f"indoorloc: argument '{name}': expected an integer >= 1, got {value}")
    if not sigma2_obs >= 0:
        raise ValueError(f"indoorloc: argument 'sigma2_obs': expected a variance >= 0, got {sigma2_obs}")
    if not sigma2_catalog >= 0:
        raise ValueError(f"indoorloc: argument 'sigma2_catalog': expected a variance >= 0, got {sigma2_catalog}")
    rng = np.random.RandomState(int(seed))
    dt = ANDA_DT_INTEGRATION
    args = (SIGMA, RHO, BETA)
    spin = odeint(_lorenz63, ANDA_X0, np.arange(0, ANDA_SPIN_UP_TIME + 0.000001, dt), args=args)
    test = odeint(_lorenz63, spin[-1], np.arange(0.01, int(nb_loop_test) + 0.000001, dt), args=args)
    T = test.shape[0]
    eps = rng.multivariate_normal(np.zeros(3), float(sigma2_obs) * np.eye(3), T)
    observations = np.full((T, 1), np.nan)
    t_obs = np.arange(0, T, int(dt_obs))
    observations[t_obs, 0] = test[t_obs, 0] + eps[t_obs, 0]
    train = odeint(_lorenz63, test[-1], np.arange(0.01, int(nb_loop_train) + 0.000001, dt), args=args)
    eta = rng.multivariate_normal(np.zeros(3), float(sigma2_catalog) * np.eye(3), train.shape[0])
    return AndaProblem(truth=test, observations=observations, catalog=train + eta)


def anda_prior_weights(states: np.ndarray, x0: np.ndarray, variance: float = ANDA_PRIOR_VARIANCE) -> np.ndarray:
    """Prior weights P(X_1 = s_j) ∝ N(s_j; x0, variance I) on catalog states (M, 3).

    AnDA's smoothers start from N(x_0, 0.1 I) around the true first state; on the analog HMM's
    discrete states this is a Gaussian weight per state. Shifted by the nearest state's squared
    distance before exp(), so that a start far from every state does not underflow to 0.
    """
    states = np.asarray(states, dtype=float)
    x0 = np.asarray(x0, dtype=float).reshape(-1)
    if states.ndim != 2 or states.shape[1] != x0.size:
        raise ValueError(f"indoorloc: argument 'states': expected shape (M, {x0.size}), got {states.shape}")
    if not variance > 0:
        raise ValueError(f"indoorloc: argument 'variance': expected > 0, got {variance}")
    d2 = ((states - x0) ** 2).sum(axis=1)
    return np.exp(-(d2 - d2.min()) / (2.0 * float(variance)))
