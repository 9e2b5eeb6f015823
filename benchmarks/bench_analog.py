"""Analog HMM (paper 001) speed: indoorloc's C++ forward-backward, alone and against hmmlearn.

(a) The paper's Table 1 setting: Lorenz-63 catalog of M = 10^5 pairs, T = 1000 steps with x
    observed every 40 steps, truncated AnFB with N = 1000 and K = 10: time to build the catalog
    and the HMM (kd-tree, K nearest analogs of every state) and time of ``smooth``.
(b) Exact forward-backward on one HMM of M = 2000 states (the analog HMM of a 2000-state
    Lorenz-63 catalog, K = 10 successors per state), T = 1000 steps of log-emissions (x observed
    at every step, R = 2), uniform initial distribution: ``indoorloc.analog.forward_backward`` on
    the sparse (M, K) transitions against hmmlearn on the same model, i.e. the dense M x M matrix
    holding those entries, the same log-emissions and initial distribution. hmmlearn is called
    through its compiled kernels ``hmmlearn._hmmc.forward_scaling`` / ``backward_scaling`` (its
    default "scaling" implementation) and ``forward_log`` / ``backward_log`` (its "log" one), the
    code ``score_samples`` runs, without its input checks; if an installed version lacks them,
    through a ``BaseHMM`` subclass whose ``_compute_log_likelihood`` returns the fixed
    log-emissions. The unit is state-steps per second, M T / seconds. The posteriors of both are
    compared (max |difference|) so that the timings are of the same computation.

hmmlearn is a peer for this benchmark only (``pip install hmmlearn``); when it is missing the
table says "not installed". Same process, interleaved repetitions, median times.
"""

from __future__ import annotations

import time
from typing import Dict, Optional, Tuple

import numpy as np

from timing import median_seconds

from indoorloc.simulate import lorenz63

M_LORENZ = 100_000
M_DENSE = 2000
T = 1000
K = 10
BEAM = 1000
R = 2.0


def _sparse_transitions(hmm, states: np.ndarray, k: int) -> Tuple[np.ndarray, np.ndarray]:
    """(next_idx, prob) of the analog HMM: from the bindings when exposed, else eq. (4) here
    (K nearest analogs of each state, successors' weights exp(-d^2 / (2 sigma^2)), sigma = std of
    the K distances), for a single trajectory whose analog i has successor i + 1."""
    next_idx = getattr(hmm, "transitions_next", None)
    prob = getattr(hmm, "transitions_prob", None)
    if next_idx is not None and prob is not None:
        return np.ascontiguousarray(next_idx, dtype=np.int64), np.ascontiguousarray(prob, dtype=float)
    from scipy.spatial import cKDTree

    d, idx = cKDTree(states[:-1]).query(states, k=k)
    sigma = np.maximum(d.std(axis=1, keepdims=True), 1e-12)
    w = np.exp(-(d**2 - d[:, :1] ** 2) / (2 * sigma**2))
    return idx + 1, w / w.sum(axis=1, keepdims=True)


def dense_transmat(next_idx: np.ndarray, prob: np.ndarray, M: int) -> np.ndarray:
    """The M x M transition matrix holding the sparse (M, K) entries (repeated targets summed)."""
    A = np.zeros((M, M))
    np.add.at(A, (np.repeat(np.arange(M), next_idx.shape[1]), next_idx.ravel()), prob.ravel())
    return A


def hmmlearn_forward_backward(
    startprob: np.ndarray, transmat: np.ndarray, log_emission: np.ndarray, implementation: str = "scaling"
) -> Tuple[np.ndarray, float]:
    """Posterior (T, M) and log-likelihood by hmmlearn's compiled forward-backward kernels."""
    try:
        from hmmlearn import _hmmc
    except ImportError:
        _hmmc = None
    if implementation == "scaling" and _hmmc is not None and hasattr(_hmmc, "backward_scaling"):
        shift = log_emission.max(axis=1, keepdims=True)  # per-step rescaling; exact, avoids underflow
        frameprob = np.exp(log_emission - shift)
        log_prob, fwd, scaling = _hmmc.forward_scaling(startprob, transmat, frameprob)
        bwd = _hmmc.backward_scaling(startprob, transmat, frameprob, scaling)
        post = fwd * bwd
        post /= post.sum(axis=1, keepdims=True)
        return post, float(log_prob + shift.sum())
    if implementation == "log" and _hmmc is not None and hasattr(_hmmc, "backward_log"):
        log_prob, fwd = _hmmc.forward_log(startprob, transmat, log_emission)
        bwd = _hmmc.backward_log(startprob, transmat, log_emission)
        log_post = fwd + bwd
        log_post -= log_post.max(axis=1, keepdims=True)
        post = np.exp(log_post)
        post /= post.sum(axis=1, keepdims=True)
        return post, float(log_prob)
    return _hmmlearn_model(startprob, transmat, log_emission, implementation)


def _hmmlearn_model(startprob, transmat, log_emission, implementation) -> Tuple[np.ndarray, float]:
    """Fallback through the public model API: a BaseHMM whose emissions are the fixed table."""
    from hmmlearn.base import BaseHMM

    class FixedEmissionHMM(BaseHMM):
        def _compute_log_likelihood(self, X):
            return log_emission[X[:, 0].astype(int)]

        def _compute_likelihood(self, X):
            return np.exp(self._compute_log_likelihood(X))

        def _check_and_set_n_features(self, X):
            self.n_features = X.shape[1]

    model = FixedEmissionHMM(n_components=startprob.size, implementation=implementation)
    model.startprob_ = startprob
    model.transmat_ = transmat
    log_prob, post = model.score_samples(np.arange(log_emission.shape[0])[:, None].astype(float))
    return post, float(log_prob)


def _lorenz_anfb(analog, repeat: int, k: int = K, sigma_scale: float = 1.0, max_dropped_mass: float = 1.0,
                 beam: int = BEAM) -> Dict[str, object]:
    catalog = lorenz63.catalog_trajectory(M_LORENZ, seed=0)
    truth, observations = lorenz63.test_problem(0, T=T)
    build = []
    for _ in range(max(1, repeat // 2)):
        start = time.perf_counter()
        cat = analog.Catalog([catalog], lag=1, stride=1)
        hmm = analog.AnalogHMM(cat, k=k, observed=[0], R=np.array([[R]]), sigma_scale=sigma_scale)
        build.append(time.perf_counter() - start)

    def smooth():
        return hmm.smooth(observations, beam=beam, max_dropped_mass=max_dropped_mass)

    smooth()
    seconds = median_seconds(smooth, repeat)
    out = smooth()
    rmse = float(np.sqrt(np.mean((np.asarray(out["mean"])[:, :3] - truth) ** 2)))
    return {"M": M_LORENZ, "T": T, "K": k, "sigma_scale": sigma_scale, "max_dropped_mass": max_dropped_mass,
            "beam": beam, "build_seconds": float(np.median(build)), "smooth_seconds": seconds, "rmse": rmse}


def _exact_problem(analog) -> Dict[str, np.ndarray]:
    catalog = lorenz63.catalog_trajectory(M_DENSE - 1, seed=1)  # M_DENSE states
    cat = analog.Catalog([catalog], lag=1, stride=1)
    hmm = analog.AnalogHMM(cat, k=K, observed=[0], R=np.array([[R]]))
    states = np.asarray(cat.states)
    M = states.shape[0]
    next_idx, prob = _sparse_transitions(hmm, states, K)
    _, observations = lorenz63.test_problem(1, T=T, dt_obs=1, R=R)
    y = observations[:, 0]
    log_emission = -0.5 * (y[:, None] - states[None, :, 0]) ** 2 / R - 0.5 * np.log(2 * np.pi * R)
    initial = np.full(M, 1.0 / M)
    return {"next_idx": next_idx, "prob": prob, "log_emission": np.ascontiguousarray(log_emission),
            "initial": initial, "M": M}


def run(quick: bool = False) -> dict:
    repeat = 3 if quick else 7
    from indoorloc import analog

    result: Dict[str, object] = {"title": "Analog HMM forward-backward (paper 001)"}
    result["lorenz_anfb"] = _lorenz_anfb(analog, repeat)
    # The validated Table 1 setting (docs/analog.md): narrower kernel, mass-adaptive beam.
    result["lorenz_anfb_validated"] = _lorenz_anfb(analog, repeat, k=10, sigma_scale=0.5, max_dropped_mass=1e-3, beam=3000)

    p = _exact_problem(analog)
    M = p["M"]
    state_steps = M * T
    rows: Dict[str, Dict[str, Optional[float]]] = {}

    def fb():
        return analog.forward_backward(p["next_idx"], p["prob"], p["log_emission"], p["initial"], beam=None)

    reference = fb()
    post_ref = np.asarray(reference["posterior"])
    seconds = median_seconds(fb, repeat)
    rows["indoorloc forward_backward (sparse, exact)"] = {
        "seconds": seconds, "state_steps_per_s": state_steps / seconds, "max_abs_posterior_diff": 0.0,
        "log_likelihood_diff": 0.0,
    }
    try:
        import hmmlearn

        version = hmmlearn.__version__
    except ImportError:
        version = None
    if version is None:
        rows["hmmlearn"] = {"seconds": None, "state_steps_per_s": None, "note": "not installed"}
    else:
        transmat = dense_transmat(p["next_idx"], p["prob"], M)
        # O(T M^2): about 10 s per call for "scaling" and 50 s for "log" at M = 2000.
        for implementation, hmm_repeat in (("scaling", 1 if quick else 3), ("log", 1)):
            times = []
            for _ in range(hmm_repeat):
                start = time.perf_counter()
                post, log_prob = hmmlearn_forward_backward(p["initial"], transmat, p["log_emission"], implementation)
                times.append(time.perf_counter() - start)
            seconds = float(np.median(times))
            rows[f"hmmlearn {version} ({implementation}, dense)"] = {
                "seconds": seconds,
                "state_steps_per_s": state_steps / seconds,
                "max_abs_posterior_diff": float(np.max(np.abs(post - post_ref))),
                "log_likelihood_diff": float(log_prob - float(reference["log_likelihood"])),
            }
    base = rows["indoorloc forward_backward (sparse, exact)"]["seconds"]
    for row in rows.values():
        row["time_over_indoorloc"] = None if row["seconds"] is None else row["seconds"] / base
    result["exact_forward_backward"] = {"M": M, "T": T, "K": K, "rows": rows}
    return result


def markdown(result: dict) -> str:
    lines = []
    for key in ("lorenz_anfb", "lorenz_anfb_validated"):
        a = result.get(key)
        if a is None:
            continue
        lines += [
            f"Lorenz-63 AnFB, M = {a['M']:,} pairs, T = {a['T']}, K = {a['K']}, kernel width x{a['sigma_scale']}, "
            f"N = {a['beam']}, mass tolerance {a['max_dropped_mass']}: catalog + HMM construction "
            f"{a['build_seconds']:.2f} s, smooth {a['smooth_seconds']:.3f} s (RMSE {a['rmse']:.2f} on this realisation).",
            "",
        ]
    e = result["exact_forward_backward"]
    lines += [
        f"Exact forward-backward, M = {e['M']} states, T = {e['T']}, K = {e['K']} (hmmlearn: the same "
        "transitions as a dense matrix):",
        "",
        "| implementation | time [ms] | state-steps / s | time / indoorloc | max \\|posterior diff\\| | log-lik diff |",
        "|---|---|---|---|---|---|",
    ]
    for name, row in e["rows"].items():
        if row["seconds"] is None:
            lines.append(f"| {name} | {row.get('note', '-')} | - | - | - | - |")
            continue
        lines.append(
            f"| {name} | {1e3 * row['seconds']:.1f} | {row['state_steps_per_s']:.3g} | "
            f"{row['time_over_indoorloc']:.1f} | {row['max_abs_posterior_diff']:.1e} | "
            f"{row['log_likelihood_diff']:.1e} |"
        )
    return "\n".join(lines)


if __name__ == "__main__":
    res = run(quick=True)
    print(markdown(res))
