"""Which floor a walk is on at each WiFi query, for walks that may change floor: a hidden Markov
chain over the floors.

``site_model.identify_floor`` gives one floor per walk, and the trackers keep a walk on one floor.
A walk that takes a lift or a stair is then tracked on one of its floors. This module says where
that assumption fails: the floor is a Markov chain over the query times t_1 < ... < t_Q; between
two queries dt apart it changes with probability 1 − exp(−r dt) (r = ``change_rate_per_s``), to
any floor uniformly (the same floor included, so r = 0 is a walk on one floor):

    P(f_{k+1} = g | f_k = f) = exp(−r dt) [g = f] + (1 − exp(−r dt)) / F;

each query q_k is seen with the robust AP likelihood of ``floor_evidence``,
e_k(f) = ε + (1 − ε) p(f | q_k), under a uniform prior on the first floor. Forward-backward gives
each query's floor posterior and Viterbi the most probable sequence (Rabiner 1989, eqs. (19)-(25)
and (30)-(35), in log space). With r = 0 every query's posterior is the walk's
∝ Π_k e_k(f) (the normalised L_f of ``floor_evidence``).
"""

from __future__ import annotations

from typing import Dict

import numpy as np
from scipy.special import logsumexp

from indoorloc.validate import real_array, real_scalar


def _log_transitions(dt_s: np.ndarray, n_floors: int, rate_per_s: float) -> tuple:
    """Per step (Q − 1,) each: log exp(−r dt), log (1 − exp(−r dt)) / F (the move to any one
    floor) and log P(stay) = the log of their sum."""
    keep = np.exp(-rate_per_s * dt_s)
    move = (1.0 - keep) / n_floors
    with np.errstate(divide="ignore"):
        return np.log(keep), np.log(move), np.log(keep + move)


def floor_sequence(log_likelihoods: np.ndarray, t_s: np.ndarray, change_rate_per_s: float) -> Dict[str, np.ndarray]:
    """The floor posterior of each query and the most probable floor sequence.

    Parameters
    ----------
    log_likelihoods : (Q, F) array
        log e_k(f) of each query [nats] (``floor_evidence.robust_query_log_likelihoods``), finite
        or -inf, at least one finite per row.
    t_s : (Q,) array
        Query times [s], non-decreasing.
    change_rate_per_s : float
        r >= 0 [1/s], the rate of floor changes (module docstring).

    Returns
    -------
    dict
        ``posterior`` (Q, F) p(f_k | all queries); ``path`` (Q,) floor indices of the Viterbi
        sequence (ties: the lowest index); ``changes`` the number of floor changes along it;
        ``log_evidence`` log p(all queries) [nats].
    """
    e = real_array(log_likelihoods, "log_likelihoods", ndim=2, finite=False)
    q_count, n_floors = e.shape
    if n_floors == 0 or np.isnan(e).any() or np.isposinf(e).any() or (q_count and not np.isfinite(e).any(axis=1).all()):
        raise ValueError("indoorloc: argument 'log_likelihoods': expected (Q, F) log-likelihoods, F >= 1, finite or "
                         "-inf, at least one finite per query")
    t = real_array(t_s, "t_s", ndim=1)
    if t.shape != (q_count,):
        raise ValueError(f"indoorloc: argument 't_s': expected shape ({q_count},), got {t.shape}")
    if np.any(np.diff(t) < 0):
        raise ValueError("indoorloc: argument 't_s': must be non-decreasing")
    r = real_scalar(change_rate_per_s, "change_rate_per_s", lo=0.0)
    if q_count == 0:
        return {"posterior": np.zeros((0, n_floors)), "path": np.zeros(0, int), "changes": 0, "log_evidence": 0.0}
    log_keep, log_move, log_stay = _log_transitions(np.diff(t), n_floors, r)
    prior = np.full(n_floors, -np.log(n_floors))
    alpha = np.empty_like(e)
    alpha[0] = prior + e[0]
    # P(g | f) = keep [g = f] + move: each sum over f is keep alpha(g) + move sum_f alpha(f).
    for k in range(1, q_count):  # eq. (20): alpha_k(g) = e_k(g) sum_f alpha_{k-1}(f) P(g | f)
        total = logsumexp(alpha[k - 1])
        alpha[k] = e[k] + np.logaddexp(alpha[k - 1] + log_keep[k - 1],
                                       total + log_move[k - 1] if np.isfinite(log_move[k - 1]) else -np.inf)
    beta = np.zeros_like(e)
    for k in range(q_count - 2, -1, -1):  # eq. (25): beta_k(f) = sum_g P(g | f) e_{k+1}(g) beta_{k+1}(g)
        nxt = e[k + 1] + beta[k + 1]
        total = logsumexp(nxt)
        beta[k] = np.logaddexp(nxt + log_keep[k], total + log_move[k] if np.isfinite(log_move[k]) else -np.inf)
    log_evidence = float(logsumexp(alpha[-1]))
    posterior = np.exp(alpha + beta - log_evidence)
    posterior /= posterior.sum(axis=1, keepdims=True)
    path = _viterbi(e, prior, log_stay, log_move)
    return {"posterior": posterior, "path": path, "changes": int(np.count_nonzero(np.diff(path))),
            "log_evidence": log_evidence}


def _viterbi(e: np.ndarray, prior: np.ndarray, log_stay: np.ndarray, log_move: np.ndarray) -> np.ndarray:
    """Eqs. (32)-(35): the most probable floor sequence (ties: the lowest floor index)."""
    q_count, n_floors = e.shape
    delta = prior + e[0]
    back = np.zeros((q_count, n_floors), int)
    for k in range(1, q_count):
        trans = np.full((n_floors, n_floors), log_move[k - 1])  # [from, to]
        np.fill_diagonal(trans, log_stay[k - 1])
        cand = delta[:, None] + trans
        back[k] = np.argmax(cand, axis=0)
        delta = cand[back[k], np.arange(n_floors)] + e[k]
    path = np.empty(q_count, int)
    path[-1] = int(np.argmax(delta))
    for k in range(q_count - 1, 0, -1):
        path[k - 1] = back[k, path[k]]
    return path


__all__ = ["floor_sequence"]
