"""The direction-persistent WiFi-only smoother (fusion.wifi_heading_sequence): its C++
forward-backward (``_core.fusion.smooth_mode_sequence``) against the numpy + scipy.sparse one it
replaced (the oracle of tests/python/test_fusion_wifi_heading_sequence.py, one BLAS thread as the
library ran it), in the same run, on real floors.

The floors: B1 (the largest) and F3 of the competition mall (shared/data/fusion/ilc2020_site2),
on ``wifi_heading_sequence``'s default grid (2 m cells, 8 headings + wander: 9 modes, 1 s ticks).
The walk: five minutes (301 ticks), a synthetic walker on the floor's walkable cells, a two-component
fix (one a decoy) every 3 s through the grid tracker's fix model. Timed: the smoother alone (the
same emissions into both), and ``track_fixes`` end to end (the fix factors, then the smoother;
the numpy path with its kernels built beforehand, as ``fusion evaluate`` cached them per floor).
Reported: best-of wall and CPU seconds, the ratio numpy / C++, and the largest difference of the
two tracks' means.

    PYTHONPATH=python python benchmarks/bench_wifi_heading_sequence.py [--quick] [--data-root DIR] [--json OUT]
(also run by benchmarks/run.py).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from indoorloc import fusion
from indoorloc._core.fusion import smooth_mode_sequence
from indoorloc.fusion import wifi_heading_sequence as whs

# The numpy forward-backward lives once, as the test's oracle.
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "python"))
from test_fusion_wifi_heading_sequence import _kernel_matrix, _numpy_smooth  # noqa: E402

SEED = 0
FLOORS = ("B1", "F3")
WALK_S = 300.0


def _plan(root: Path, name: str):
    from indoorloc.io import load_floor_plan
    from indoorloc.io.survey_layout import survey_floors

    (survey,) = survey_floors(root, [name], argument="data_root")
    return load_floor_plan(survey.open().geojson_path, floors=[survey.number], origin_lon_lat="outline_sw")


def _walk(grid: whs.HeadingGrid, seed: int = SEED):
    """Fixes of a walker that goes from walkable cell to walkable cell at 1.2 m/s: every 3 s a
    two-component fix, 0.7 at the walker + N(0, 4 m), 0.3 at a random walkable cell."""
    rng = np.random.default_rng(seed)
    walkable = grid.cells_m[grid.wall_factor > 0.99]
    t = np.arange(0.0, WALK_S + 1e-9, 3.0)
    pos, goal = walkable[rng.integers(len(walkable))], walkable[rng.integers(len(walkable))]
    truth = []
    for _ in t:
        d = goal - pos
        if np.hypot(*d) < 3.6:
            pos, goal = goal, walkable[rng.integers(len(walkable))]
        else:
            pos = pos + 3.6 * d / np.hypot(*d)
        truth.append(pos)
    truth = np.array(truth)
    means = np.stack([truth + rng.normal(0, 4.0, truth.shape), walkable[rng.integers(len(walkable), size=t.size)]], 1)
    return fusion.Fixes.from_arrays(t, means, 6.0, np.tile([0.7, 0.3], (t.size, 1)))


def _best(fn, repeat: int):
    """(best wall [s], best CPU [s]) of `repeat` calls."""
    best, best_cpu = math.inf, math.inf
    for _ in range(repeat):
        tic, cpu = time.perf_counter(), time.process_time()
        fn()
        best, best_cpu = min(best, time.perf_counter() - tic), min(best_cpu, time.process_time() - cpu)
    return best, best_cpu


def floor_case(plan, s: whs.HeadingSequenceSettings, repeat: int) -> dict:
    from threadpoolctl import threadpool_limits

    grid = whs.heading_grid(plan, s)
    fixes = _walk(grid)
    times = np.arange(0.0, WALK_S + 1e-9, s.tick_s)
    stencils, trans = whs.motion_stencils(s), whs.mode_transition(s)
    kernels = [_kernel_matrix(grid, *st) for st in stencils]
    factors = whs.fix_factors(grid, fixes, times, s)
    ticks = np.array(sorted(factors))
    rows = np.stack([factors[k] for k in ticks])
    emit = [grid.wall_factor * factors[k] if k in factors else grid.wall_factor for k in range(times.size)]

    def numpy_smooth():
        with threadpool_limits(limits=1):
            return _numpy_smooth(kernels, trans, emit)

    def numpy_track():
        f = whs.fix_factors(grid, fixes, times, s)
        e = [grid.wall_factor * f[k] if k in f else grid.wall_factor for k in range(times.size)]
        with threadpool_limits(limits=1):
            return _numpy_smooth(kernels, trans, e) @ grid.cells_m

    def cpp_smooth():
        return smooth_mode_sequence(grid.index, grid.cells_m, stencils, trans, grid.wall_factor, ticks, rows,
                                    times.size)

    seconds = {
        "smoother, numpy + scipy": _best(numpy_smooth, repeat),
        "smoother, C++": _best(cpp_smooth, repeat),
        "track_fixes, numpy + scipy": _best(numpy_track, repeat),
        "track_fixes, C++": _best(lambda: whs.track_fixes(grid, fixes, 0.0, WALK_S, s), repeat),
    }
    want = numpy_smooth() @ grid.cells_m
    got = whs.track_fixes(grid, fixes, 0.0, WALK_S, s)["position_m"]
    return {
        "states": int(grid.cells_m.shape[0]), "lattice": [grid.ny, grid.nx], "modes": len(stencils),
        "ticks": int(times.size), "fix_ticks": int(ticks.size),
        "wall_s": {k: v[0] for k, v in seconds.items()}, "cpu_s": {k: v[1] for k, v in seconds.items()},
        "smoother_ratio": seconds["smoother, numpy + scipy"][0] / seconds["smoother, C++"][0],
        "smoother_ratio_cpu": seconds["smoother, numpy + scipy"][1] / seconds["smoother, C++"][1],
        "track_ratio": seconds["track_fixes, numpy + scipy"][0] / seconds["track_fixes, C++"][0],
        "max_mean_difference_m": float(np.abs(got - want).max()),
    }


def run(quick: bool = False, data_root: Path | None = None) -> dict:
    from indoorloc.experiments.fusion_real_settings import default_site_root

    root = Path(data_root) if data_root else default_site_root()
    load_before = os.getloadavg()[0]
    s = whs.HeadingSequenceSettings()
    floors = {name: floor_case(_plan(root, name), s, 2 if quick else 5) for name in FLOORS}
    return {
        "title": "wifi_heading_sequence: the C++ forward-backward against the numpy + scipy one it replaced",
        "load_average_1min": {"before": load_before, "after": os.getloadavg()[0], "cpus": os.cpu_count()},
        "walk_s": WALK_S, "floors": floors,
    }


def markdown(result: dict) -> str:
    r = result
    load = r["load_average_1min"]
    lines = [f"A {r['walk_s']:.0f} s walk (1 s ticks, a fix every 3 s), defaults (9 modes); one thread, best of the "
             f"repetitions; load average {load['before']:.1f} -> {load['after']:.1f} on {load['cpus']} CPUs.", "",
             "| floor | states (lattice) | smoother numpy [s] | smoother C++ [s] | numpy / C++ (wall, CPU) | "
             "track_fixes numpy [s] | track_fixes C++ [s] | numpy / C++ | max mean difference [m] |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, f in r["floors"].items():
        w = f["wall_s"]
        lines.append(f"| {name} | {f['states']:,} ({f['lattice'][0]} x {f['lattice'][1]}) | "
                     f"{w['smoother, numpy + scipy']:.3f} | {w['smoother, C++']:.3f} | "
                     f"**{f['smoother_ratio']:.1f}x**, {f['smoother_ratio_cpu']:.1f}x | "
                     f"{w['track_fixes, numpy + scipy']:.3f} | {w['track_fixes, C++']:.3f} | {f['track_ratio']:.1f}x | "
                     f"{f['max_mean_difference_m']:.1e} |")
    return "\n".join(lines)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--data-root", type=Path, default=None)
    ap.add_argument("--json", type=Path, default=None, help="also write the result here (atomically)")
    a = ap.parse_args()
    res = run(a.quick, a.data_root)
    print(f"# {res['title']}\n\n{markdown(res)}")
    if a.json:
        import json

        tmp = a.json.with_suffix(a.json.suffix + ".tmp")
        tmp.write_text(json.dumps(res, indent=1))
        tmp.replace(a.json)
