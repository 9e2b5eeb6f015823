"""Shared-AP matcher speed: the compiled kNN (indoorloc._core.wifi.SharedApMatcher, through
wifi_matcher.shared_knn) against the numpy/scipy implementation it replaced
(wifi_matcher.shared_dissimilarity_numpy + wifi_matcher.knn), same process, same data.

Data: a synthetic floor the size of the floor-identification database of the ILC site
(every walk of B1 and F1 but one: 3,958 references, 2,491 APs; docs/fusion_real.md): APs at
random over 200 m x 120 m, -40 dBm - 40 log10(distance) with 4 dB noise, heard above -90 dBm, so
that a fingerprint hears a few per cent of the APs, as on the real floors. 300 queries, k = 20.
Throughput is query-reference pairs per second (Q x N / seconds), best of 3.
"""

from __future__ import annotations

import numpy as np

from timing import best_seconds

from indoorloc.wifi import matcher as wifi_matcher

N_REFS = 3958
N_APS = 2491
N_QUERIES = 300


def synthetic_fingerprints(n: int, aps_xy: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """(n, K) RSS [dBm], NaN below -90 dBm, at random positions on the floor."""
    xy = rng.uniform([0, 0], [200, 120], (n, 2))
    dist = np.hypot(*(xy[:, None, :] - aps_xy[None, :, :]).transpose(2, 0, 1))
    rss = -40.0 - 40.0 * np.log10(np.maximum(dist, 1.0)) + rng.normal(0, 4.0, dist.shape)
    return np.where(rss > -90.0, rss, np.nan)


def run(quick: bool = False) -> dict:
    rng = np.random.default_rng(0)
    aps = rng.uniform([0, 0], [200, 120], (N_APS, 2))
    refs = synthetic_fingerprints(N_REFS, aps, rng)
    queries = synthetic_fingerprints(N_QUERIES, aps, rng)
    index = wifi_matcher.ReferenceIndex.build(refs, rng.uniform(0.5, 2.0, N_APS), 5.0)
    repeat = 1 if quick else 3
    pairs = N_REFS * N_QUERIES
    t_numpy = best_seconds(
        lambda: wifi_matcher.knn(wifi_matcher.shared_dissimilarity_numpy(queries, index, 160.0), 20, 3.0), repeat)
    index.matcher(160.0, 20, 3.0)  # built once per database, outside the timing (as the numpy CSR is not)
    t_one = best_seconds(lambda: wifi_matcher.shared_knn(queries, index, 160.0, 20, 3.0, num_threads=1), repeat)
    t_two = best_seconds(lambda: wifi_matcher.shared_knn(queries, index, 160.0, 20, 3.0, num_threads=2), repeat)
    t_full = best_seconds(lambda: wifi_matcher.shared_dissimilarity(queries, index, 160.0, num_threads=1), repeat)
    return {
        "title": "Shared-AP matcher: compiled kNN vs numpy/scipy (pairs per second)",
        "references": N_REFS, "aps": N_APS, "queries": N_QUERIES,
        "heard_per_reference": float(np.isfinite(refs).sum(axis=1).mean()),
        "numpy_pairs_per_s": pairs / t_numpy,
        "cpp_knn_1_thread_pairs_per_s": pairs / t_one,
        "cpp_knn_2_threads_pairs_per_s": pairs / t_two,
        "cpp_full_matrix_1_thread_pairs_per_s": pairs / t_full,
        "speedup_1_thread": t_numpy / t_one,
        "speedup_2_threads": t_numpy / t_two,
    }


def markdown(r: dict) -> str:
    return "\n".join([
        f"{r['queries']} queries x {r['references']} references, {r['aps']} APs "
        f"({r['heard_per_reference']:.0f} heard per reference), k = 20:",
        "",
        "| implementation | pairs/s | speed-up |",
        "|---|---|---|",
        f"| numpy/scipy (shared_dissimilarity_numpy + knn) | {r['numpy_pairs_per_s']:.3g} | 1 |",
        f"| compiled kNN, 1 thread | {r['cpp_knn_1_thread_pairs_per_s']:.3g} | {r['speedup_1_thread']:.1f}x |",
        f"| compiled kNN, 2 threads | {r['cpp_knn_2_threads_pairs_per_s']:.3g} | {r['speedup_2_threads']:.1f}x |",
        f"| compiled full (Q, N) matrix, 1 thread | {r['cpp_full_matrix_1_thread_pairs_per_s']:.3g} | |",
    ])


if __name__ == "__main__":
    import json
    import sys
    from pathlib import Path

    result = run(quick="--quick" in sys.argv)
    print(markdown(result))
    out = Path(__file__).resolve().parent / "results"
    tmp = out / "bench_wifi_matcher.json.tmp"
    tmp.write_text(json.dumps(result, indent=2))
    tmp.replace(out / "bench_wifi_matcher.json")
