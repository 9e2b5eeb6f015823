"""Resampling of 10^6 log-weights: indoorloc (C++) against the numpy implementations used by
the `particles` library (resampling.py: exp-normalise, cumsum, searchsorted) and, when it is
installed, `particles` itself. Single thread, same process, interleaved repetitions."""

from __future__ import annotations


import numpy as np

from timing import median_seconds

from indoorloc import core

N = 1_000_000


def numpy_systematic(lw: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Reference: the numpy code path of particles.resampling.systematic on log-weights."""
    w = np.exp(lw - lw.max())
    w /= w.sum()
    u = (rng.random() + np.arange(lw.size)) / lw.size
    return np.searchsorted(np.cumsum(w), u)


def run(quick: bool = False) -> dict:
    repeat = 5 if quick else 30
    lw = core.RandomStream(0).normal(N)
    stream = core.RandomStream(1)
    gen = np.random.default_rng(1)
    peers = {"numpy (particles' algorithm)": lambda: numpy_systematic(lw, gen)}
    try:  # the real peer, if the bench extra is installed
        from particles import resampling as pr

        peers["particles.resampling.systematic"] = lambda: pr.systematic(pr.exp_and_normalise(lw))
    except ImportError:
        pass
    rows = {}
    for scheme in core.RESAMPLING_SCHEMES:
        core.resample(lw, scheme, stream)
        rows[f"indoorloc {scheme}"] = median_seconds(lambda: core.resample(lw, scheme, stream), repeat)
    for name, fn in peers.items():
        fn()
        rows[name] = median_seconds(fn, repeat)
    base = rows["indoorloc systematic"]
    return {
        "title": f"Resampling {N:,} log-weights (median of {repeat})",
        "n": N,
        "seconds": rows,
        "speedup_vs_indoorloc_systematic": {k: v / base for k, v in rows.items()},
    }


def markdown(result: dict) -> str:
    lines = ["| method | time [ms] | time / indoorloc systematic |", "|---|---|---|"]
    for name, seconds in result["seconds"].items():
        ratio = result["speedup_vs_indoorloc_systematic"][name]
        lines.append(f"| {name} | {1e3 * seconds:.2f} | {ratio:.2f} |")
    return "\n".join(lines)
