"""Properties of the size limits (issue 28), beside the per-entry-point probe of
property_harness.py:

- a floor plan of E edges builds in O(E log E): the construction's own work counters
  (``FloorPlan.build_statistics``) stay within c E log2 E for generated outlines that used to be
  quadratic or unbounded (combs, stars, zigzags), whatever their size and extent;
- every memory bound is checked before allocating: each call that asks for more than the 4 GB
  limit, by any factor, is refused with a ValueError naming its argument while the process may
  not grow by more than 1 GB (an allocation made before the check would end in MemoryError).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from indoorloc import fusion


def _comb(teeth: int, width_m: float) -> np.ndarray:
    w = width_m / (2 * teeth)
    pts = [(0.0, 0.0)]
    for t in range(teeth):
        x0, x1 = 2 * t * w, (2 * t + 1) * w
        if t > 0:
            pts.append((x0, 0.1 * width_m))
        pts += [(x0, width_m), (x1, width_m), (x1, 0.1 * width_m)]
    pts += [(width_m, 0.1 * width_m), (width_m, 0.0)]
    return np.array(pts)


def _star(n: int, r_out_m: float) -> np.ndarray:
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = np.where(np.arange(n) % 2 == 0, r_out_m, 1.0)
    return np.c_[r * np.cos(a), r * np.sin(a)]


def _zigzag(n: int, length_m: float) -> np.ndarray:
    """A saw-tooth strip: n teeth along x, long thin edges crossing many cells."""
    x = np.linspace(0.0, length_m, n + 1)
    top = np.c_[x, 1.0 + (np.arange(n + 1) % 2) * length_m / 10]
    return np.vstack([[[0.0, 0.0], [length_m, 0.0]], top[::-1]])


SHAPES = {"comb": lambda n, size: _comb(max(n // 4, 1), size),
          "star": lambda n, size: _star(n - n % 2, size),
          "zigzag": lambda n, size: _zigzag(n, size)}


@settings(max_examples=15, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(shape=st.sampled_from(sorted(SHAPES)), n=st.integers(200, 24000),
       size_m=st.sampled_from([1.0, 10.0, 100.0, 1e4]))
def test_a_floor_plan_of_e_edges_builds_in_order_e_log_e(shape, n, size_m):
    ring = SHAPES[shape](n, size_m)
    s = fusion.FloorPlan([fusion.FloorGeometry(0, [ring], [], None)]).build_statistics(0)
    e = s["edges"]
    # The sweep's exact predicates: the constant measured on combs and stars is below 4.
    assert s["self_intersection_work"] <= 6.0 * e * np.log2(e), s
    # The grid index within its budget, the walkable area's scanlines within theirs.
    assert s["index_bytes"] <= max(64e6, 1024.0 * e), s
    assert s["area_edge_visits"] <= 2e7, s


# Each entry: (label, code of one call whose size grows with the integer factor `f` >= 1). Every one
# needs more than 4 GB at f = 1.
OVER_LIMIT_CALLS = [
    ("tracker particles", "fusion.ParticleTracker(plan, None, None, fusion.tracker_options(num_particles=50_000_000 * f))"),
    ("tracker lag", "fusion.ParticleTracker(plan, None, None, fusion.tracker_options(num_particles=5_000_000, "
                    "smoothing_lag_steps=10_000 * f))"),
    ("recorded clouds", "fusion.track(steps, plan=plan, start={'position_m': [2.0, 1.5]}, "
                        "options=fusion.tracker_options(num_particles=40_000_000), smoother=fusion.SmootherOptions(), "
                        ") if f == 1 else fusion.track(fusion.Steps(0.5 * np.arange(1, 4 * f + 1), "
                        "np.tile([0.0, 0.1], (4 * f, 1)), np.tile([0.01, 0, 0.01], (4 * f, 1))), plan=plan, "
                        "start={'position_m': [2.0, 1.5]}, options=fusion.tracker_options(num_particles=40_000_000), "
                        "smoother=fusion.SmootherOptions())"),
    ("smoother options", "fusion.SmootherOptions(num_trajectories=100_000, max_particles=min(50_000_000 * f, 2**31 - 1))"),
    ("floor plan index", "fusion.FloorPlan([fusion.FloorGeometry(0, [square * f], [], None)], "
                         "fusion.FloorPlanOptions(cell_size_m=0.1, max_cells=100_000_000))"),
    ("wifi observations", "fusion.make_wifi_observations(np.arange(10_000.0), "
                          "np.broadcast_to(np.float64(-60.0), (10_000, 10_000 * f)))"),
    ("sample_walkable", "plan.sample_walkable(2**31 - 1 - f)"),
    ("random draws", "core.RandomStream(1).normal(10**12 * f)"),
    ("resample", "core.resample(np.zeros(3), num_out=2**31 - 1 - f)"),
    ("offspring_counts", "core.offspring_counts(np.zeros(1000), n_runs=2**31 - 1 - f)"),
    ("monte_carlo", "mapmatch.monte_carlo(net, mapmatch.TrajectoryOptions(duration_s=1e7, dt_s=0.1), "
                    "mapmatch.FilterOptions(num_particles=10), n_runs=10**6 * f)"),
    ("network blocks", "cn.linear_ins_normal_blocks(cn.LinearInsNetworkOptions(imu_rate_hz=18109.0 * f, gps_rate_hz=1.0))"),
    ("bootstrap", "metrics.bootstrap_interval(np.ones(1000 * f), n_boot=10**6)"),
]

_CHILD = """
import resource, time, numpy as np
from indoorloc import core, fusion, mapmatch, metrics, io
from indoorloc._core import network as cn
plan = fusion.FloorPlan([fusion.FloorGeometry(0, [np.array([[0, 0], [20, 0], [20, 10], [0, 10]], float)], [], None)])
square = np.array([[0, 0], [999.8, 0], [999.8, 999.8], [0, 999.8]], float)
steps = fusion.Steps(0.5 * np.arange(1, 5), np.tile([0.0, 0.7], (4, 1)), np.tile([0.01, 0, 0.01], (4, 1)))
net = mapmatch.RoadNetwork(*io.grid_with_diagonals_segments(3, 2, 10.0))
vm = int(open("/proc/self/statm").read().split()[0]) * resource.getpagesize()
resource.setrlimit(resource.RLIMIT_AS, (vm + 2**30, vm + 2**30))   # may grow by 1 GB at most
for label, code, f in CALLS:
    t0 = time.perf_counter()
    try:
        eval(code)
        outcome = "accepted"
    except ValueError as e:
        outcome = "refused" if "argument '" in str(e) else "unnamed: " + str(e)[:200]
    except MemoryError as e:
        outcome = "allocated first (MemoryError)"
    print(repr((label, f, outcome, time.perf_counter() - t0)), flush=True)
"""


@settings(max_examples=3, deadline=None, derandomize=True, database=None)
@given(factors=st.lists(st.integers(1, 1000), min_size=2, max_size=2, unique=True))
def test_every_memory_bound_is_checked_before_allocating(factors):
    calls = [(label, code, f) for label, code in OVER_LIMIT_CALLS for f in [1] + factors]
    code = f"CALLS = {calls!r}\n" + textwrap.dedent(_CHILD)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    import ast

    rows = [ast.literal_eval(line) for line in proc.stdout.splitlines() if line.startswith("(")]
    assert len(rows) == len(calls), proc.stdout
    bad = [r for r in rows if r[2] != "refused" or r[3] > 5.0]
    assert not bad, bad
