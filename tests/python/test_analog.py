"""Python side of the analog HMM: bindings, brute-force agreement, errors."""

import itertools

import numpy as np
import pytest

from indoorloc import analog


def circle(n, phase=0.0, noise=0.0, seed=0):
    rng = np.random.default_rng(seed)
    a = phase + 0.1 * np.arange(n)
    return np.c_[np.cos(a), np.sin(a)] + noise * rng.normal(size=(n, 2))


def test_generic_forward_backward_matches_enumeration():
    rng = np.random.default_rng(1)
    m, k, T = 4, 2, 5
    nxt = np.array([rng.choice(m, size=k, replace=False) for _ in range(m)])
    prob = rng.uniform(0.2, 1, size=(m, k))
    prob /= prob.sum(axis=1, keepdims=True)
    A = np.zeros((m, m))
    for i in range(m):
        A[i, nxt[i]] += prob[i]
    log_b = -rng.uniform(0, 10, size=(T, m))
    init = np.ones(m)
    post = np.zeros((T, m))
    total = 0.0
    best, best_path = -1.0, None
    for path in itertools.product(range(m), repeat=T):
        p = init[path[0]] / m * np.exp(log_b[0, path[0]])
        for t in range(1, T):
            p *= A[path[t - 1], path[t]] * np.exp(log_b[t, path[t]])
        total += p
        for t, s in enumerate(path):
            post[t, s] += p
        if p > best:
            best, best_path = p, list(path)
    out = analog.forward_backward(nxt, prob, log_b, init)
    np.testing.assert_allclose(out["posterior"], post / total, atol=1e-10)
    assert out["log_likelihood"] == pytest.approx(np.log(total), rel=1e-10)
    np.testing.assert_allclose(out["posterior"].sum(axis=1), 1.0)
    path, _ = analog.viterbi(nxt, prob, log_b, init)
    assert list(path) == best_path
    full_beam = analog.forward_backward(nxt, prob, log_b, init, beam=m)
    np.testing.assert_allclose(full_beam["posterior"], out["posterior"], atol=1e-12)


def test_catalog_knn_and_smoothing_with_missing_values():
    cat = analog.Catalog([circle(2000, noise=0.01, seed=2)], lag=1)
    idx, d2 = cat.knn(np.array([[1.0, 0.0]]), 5)
    brute = np.sort(((cat.states[cat.analogs] - [1.0, 0.0]) ** 2).sum(axis=1))[:5]
    np.testing.assert_allclose(d2[0], brute)
    hmm = analog.AnalogHMM(cat, k=8, observed=[0], R=np.array([[0.01]]))
    np.testing.assert_allclose(hmm.transitions_prob.sum(axis=1), 1.0)
    truth = circle(150, phase=0.3)
    obs = np.full((150, 1), np.nan)
    obs[::5, 0] = truth[::5, 0]
    out = hmm.smooth(obs, beam=300)
    assert out["mean"].shape == (150, 2) and np.isfinite(out["log_likelihood"])
    assert np.sqrt(np.mean((out["mean"][:, 1] - truth[:, 1]) ** 2)) < 0.25
    v = hmm.viterbi(obs, beam=300)
    assert v["states"].shape == (150, 2)


def test_bad_input_gives_clear_errors():
    short = analog.Catalog([circle(6)])
    with pytest.raises(ValueError, match="needs at least K"):
        analog.AnalogHMM(short, k=10, observed=[0], R=np.eye(1))
    cat = analog.Catalog([circle(100)])
    with pytest.raises(ValueError, match="positive definite"):
        analog.AnalogHMM(cat, k=3, observed=[0], R=np.array([[-1.0]]))
    with pytest.raises(ValueError, match="k must be >= 1"):
        analog.AnalogHMM(cat, k=0, observed=[0], R=np.eye(1))
    with pytest.raises(ValueError, match="R"):
        analog.AnalogHMM(cat, k=3, observed=[0, 1], R=np.eye(1))
    hmm = analog.AnalogHMM(cat, k=3, observed=[0], R=np.eye(1))
    with pytest.raises(ValueError, match="observations"):
        hmm.smooth(np.zeros((10, 2)))
    with pytest.raises(ValueError, match="too short"):
        analog.Catalog([np.zeros((1, 2))])
    with pytest.raises(ValueError, match="sigma_scale"):
        analog.AnalogHMM(cat, k=3, observed=[0], R=np.eye(1), sigma_scale=0.0)
    with pytest.raises(ValueError, match="max_dropped_mass"):
        hmm.smooth(np.zeros((10, 1)), beam=5, max_dropped_mass=2.0)
    with pytest.raises(ValueError, match="beam_max"):
        hmm.smooth(np.zeros((10, 1)), beam=5, beam_max=-1)


def test_mass_adaptive_beam_bounds_the_dropped_mass_and_narrow_kernel_concentrates():
    cat = analog.Catalog([circle(2000, noise=0.02, seed=1)])
    wide = analog.AnalogHMM(cat, k=8, observed=[0], R=np.array([[0.01]]))
    narrow = analog.AnalogHMM(cat, k=8, observed=[0], R=np.array([[0.01]]), sigma_scale=0.5)
    first_wide = np.asarray(wide.transitions_prob)[:, 0]
    first_narrow = np.asarray(narrow.transitions_prob)[:, 0]
    assert np.all(first_narrow >= first_wide - 1e-12) and np.mean(first_narrow > first_wide) > 0.5
    truth = circle(120, phase=0.3)
    obs = np.full((120, 1), np.nan)
    obs[::4, 0] = truth[::4, 0]
    fixed = wide.smooth(obs, beam=3)
    adaptive = wide.smooth(obs, beam=3, max_dropped_mass=1e-3)
    assert np.max(adaptive["dropped_mass"]) <= 1e-3 + 1e-12
    assert np.max(fixed["dropped_mass"]) > 1e-3
    assert np.max(adaptive["support_size"]) > 3


def test_incremental_successor_rule_matches_numpy_construction():
    cat = analog.Catalog([circle(400, noise=0.03, seed=5)])
    k, scale = 6, 0.6
    base = analog.AnalogHMM(cat, k=k, observed=[0], R=np.eye(1), sigma_scale=scale)
    inc = analog.AnalogHMM(cat, k=k, observed=[0], R=np.eye(1), sigma_scale=scale, successor_rule="incremental")
    states = np.asarray(cat.states)
    analogs, successors = np.asarray(cat.analogs), np.asarray(cat.successors)
    nn, _ = cat.knn(states, k)
    # numpy: target = argmin_s ||s - (s_i + s_succ(a) - s_a)||, weights of equal targets summed
    query = states[:, None, :] + states[successors[nn]] - states[analogs[nn]]
    target = np.argmin(((query[:, :, None, :] - states[None, None, :, :]) ** 2).sum(axis=-1), axis=-1)
    dense_expected = np.zeros((len(states), len(states)))
    dense_got = np.zeros_like(dense_expected)
    rows = np.repeat(np.arange(len(states)), k)
    np.add.at(dense_expected, (rows, target.ravel()), np.asarray(base.transitions_prob).ravel())
    np.add.at(dense_got, (rows, np.asarray(inc.transitions_next).ravel()), np.asarray(inc.transitions_prob).ravel())
    np.testing.assert_allclose(dense_got, dense_expected, atol=1e-12)
    np.testing.assert_allclose(np.asarray(inc.transitions_prob).sum(axis=1), 1.0, atol=1e-12)
    with pytest.raises(ValueError, match="successor_rule"):
        analog.AnalogHMM(cat, k=k, observed=[0], R=np.eye(1), successor_rule="bogus")


def test_smooth_reports_the_posterior_std():
    cat = analog.Catalog([circle(500, noise=0.02, seed=6)])
    hmm = analog.AnalogHMM(cat, k=5, observed=[0], R=np.array([[0.05]]))
    truth = circle(60, phase=0.2)
    obs = np.full((60, 1), np.nan)
    obs[::5, 0] = truth[::5, 0]
    out = hmm.smooth(obs)
    post = analog.forward_backward(hmm.transitions_next, hmm.transitions_prob,
                                   _log_emission(cat, obs, 0.05), np.ones(cat.num_states))["posterior"]
    states = np.asarray(cat.states)
    mean = post @ states
    std = np.sqrt(post @ states**2 - mean**2)
    np.testing.assert_allclose(out["mean"], mean, atol=1e-9)
    np.testing.assert_allclose(out["std"], std, atol=1e-6)


def _log_emission(cat, obs, r):
    x = np.asarray(cat.states)[:, 0]
    log_b = -0.5 * (obs[:, :1] - x[None, :]) ** 2 / r - 0.5 * np.log(2 * np.pi * r)
    return np.where(np.isnan(log_b), 0.0, log_b)
