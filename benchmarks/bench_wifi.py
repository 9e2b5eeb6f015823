"""WiFi speed benchmarks, single thread, indoorloc against its peers in the same process.

1. Locate + linearly interpolate 12 fields and their gradients at 10^6 random-order queries on
   a 10^5-point map: indoorloc.wifi.DelaunayInterpolator vs scipy.spatial.Delaunay
   (find_simplex + barycentric transform + numpy gathers) and matplotlib.tri
   (LinearTriInterpolator on each field, with gradients). Peers are timed on a 10^5-query subset
   and reported as queries per second (they scale linearly).
2. Build of a 10^6-point triangulation: indoorloc vs scipy (Qhull).
3. Streaming tracker update (6 APs): the C++ loop (GradientTracker.track) and one Python call
   per scan (GradientTracker.update).
"""

from __future__ import annotations

import time

import numpy as np

from timing import best_seconds

from indoorloc import wifi

N_MAP = 100_000
N_FIELDS = 12
N_QUERIES = 1_000_000
N_PEER_QUERIES = 100_000


def scipy_interpolate(tri, fields: np.ndarray, q: np.ndarray):
    """Values (Q, F) and gradients (Q, F, 2) with scipy's point location and numpy."""
    s = tri.find_simplex(q)
    t = tri.transform[s]  # (Q, 3, 2): inverse affine map and offset
    b12 = np.einsum("qij,qj->qi", t[:, :2], q - t[:, 2])
    b = np.c_[b12, 1 - b12.sum(axis=1)]
    verts = tri.simplices[s]
    f = fields[verts]  # (Q, 3, F)
    values = np.einsum("qj,qjf->qf", b, f)
    # grad b_j: rows of T for j = 0, 1; grad b_2 = -(sum); grad f = Σ_j f_j grad b_j.
    gb = np.concatenate([t[:, :2], -t[:, :2].sum(axis=1, keepdims=True)], axis=1)  # (Q, 3, 2)
    grads = np.einsum("qjf,qjd->qfd", f, gb)
    return values, grads, s >= 0


def run(quick: bool = False) -> dict:
    import matplotlib.tri as mtri
    from scipy.spatial import Delaunay

    rng = np.random.default_rng(0)
    pos = rng.uniform(0, 1000, size=(N_MAP, 2))
    fields = rng.normal(size=(N_MAP, N_FIELDS))
    q = rng.uniform(0, 1000, size=(N_QUERIES, 2))
    q_peer = q[:N_PEER_QUERIES]
    repeat = 1 if quick else 3

    interp = wifi.DelaunayInterpolator(pos, fields)
    tri = Delaunay(pos)
    mpl = mtri.Triangulation(pos[:, 0], pos[:, 1], triangles=tri.simplices)
    mpl_interps = [mtri.LinearTriInterpolator(mpl, fields[:, k]) for k in range(N_FIELDS)]

    # Agreement check on a few queries before timing (same values, same gradients).
    v_ours, g_ours, inside, _ = interp.interpolate(q[:1000])
    v_sp, g_sp, inside_sp = scipy_interpolate(tri, fields, q[:1000])
    ok = inside & inside_sp
    max_diff = float(max(np.abs(v_ours[ok] - v_sp[ok]).max(), np.abs(g_ours[ok] - g_sp[ok]).max()))

    t_ours = best_seconds(lambda: interp.interpolate(q, num_threads=1), repeat)
    t_scipy = best_seconds(lambda: scipy_interpolate(tri, fields, q_peer), repeat)

    def mpl_run():
        for k in range(N_FIELDS):
            mpl_interps[k](q_peer[:, 0], q_peer[:, 1])
            mpl_interps[k].gradient(q_peer[:, 0], q_peer[:, 1])

    t_mpl = best_seconds(mpl_run, 1)
    rates = {
        "indoorloc DelaunayInterpolator": N_QUERIES / t_ours,
        "scipy Delaunay.find_simplex + numpy": N_PEER_QUERIES / t_scipy,
        "matplotlib LinearTriInterpolator": N_PEER_QUERIES / t_mpl,
    }

    pos6 = rng.uniform(0, 1000, size=(1_000_000, 2))
    f6 = np.zeros((1_000_000, 1))
    build_ours = best_seconds(lambda: wifi.DelaunayInterpolator(pos6, f6), 1 if quick else 2)
    build_scipy = best_seconds(lambda: Delaunay(pos6), 1)

    from indoorloc.experiments import wifi_simulation as ws

    model = ws.paper_map(0)
    n_scans = 200_000
    path = np.c_[np.full(n_scans, 0.6), np.linspace(0.5, 15, n_scans)]
    scans = model.simulate_scans(path, seed=1)
    tracker = wifi.GradientTracker(model, wifi.tracker_options(paper_mode=True))

    def track():
        tracker.reset_to(path[0])
        tracker.track(scans)

    t_track = best_seconds(track, repeat)
    tracker.reset_to(path[0])
    n_calls = 50_000
    start = time.perf_counter()
    for i in range(n_calls):
        tracker.update(scans[i])
    t_update = time.perf_counter() - start

    return {
        "title": "WiFi: interpolation, triangulation and tracker speed (single thread)",
        "interpolation_queries_per_s": rates,
        "speedup_vs_scipy": rates["indoorloc DelaunayInterpolator"] / rates["scipy Delaunay.find_simplex + numpy"],
        "max_abs_difference_vs_scipy": max_diff,
        "build_1e6_s": {"indoorloc": build_ours, "scipy (Qhull)": build_scipy},
        "tracker_updates_per_s": {"C++ loop (track)": n_scans / t_track, "Python call per scan (update)": n_calls / t_update},
    }


def markdown(result: dict) -> str:
    lines = [
        f"Locate + interpolate {N_FIELDS} fields + gradients, random-order queries, {N_MAP:,}-point map "
        f"(indoorloc on {N_QUERIES:,} queries, peers on {N_PEER_QUERIES:,}); results agree to "
        f"{result['max_abs_difference_vs_scipy']:.1e}.",
        "",
        "| method | queries/s |",
        "|---|---|",
    ]
    for name, rate in result["interpolation_queries_per_s"].items():
        lines.append(f"| {name} | {rate:,.0f} |")
    lines += ["", f"indoorloc / scipy: **{result['speedup_vs_scipy']:.1f}x**", "", "| 10^6-point triangulation | s |", "|---|---|"]
    for name, sec in result["build_1e6_s"].items():
        lines.append(f"| {name} | {sec:.2f} |")
    lines += ["", "| tracker (6 APs) | updates/s |", "|---|---|"]
    for name, rate in result["tracker_updates_per_s"].items():
        lines.append(f"| {name} | {rate:,.0f} |")
    return "\n".join(lines)
