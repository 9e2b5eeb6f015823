"""Grid tracker (fusion.GridTracker) against the same forward filter in numpy + scipy
(grid_filter_numpy.py), one walk on a mall-sized floor, in the same run.

A 230 x 210 m floor (the competition mall's extent) with 48 shops, 1 m cells (48,300 cells), one
minute of walking (120 steps of 0.7 m, a turn every 30 steps) and a WiFi fix every 4 steps (two
components, one a decoy); 9 heading-offset layers. Timed: the C++ filter, the C++ filter with the
smoother, and the numpy + scipy filter (the same model and decisions; the test
tests/python/test_fusion_grid.py checks that the two agree). Reported: cell-steps per second
(layers x cells x steps / s), seconds per minute of walking and the ratio to the peer; the
filtered means of the two are compared.
"""

from __future__ import annotations

import math
import os
import time

import numpy as np

from indoorloc import fusion
from indoorloc.fusion import site_model

import grid_filter_numpy

SEED = 0
WIDTH_M, HEIGHT_M = 230.0, 210.0


def mall_plan() -> fusion.FloorPlan:
    outline = np.array([[0, 0], [WIDTH_M, 0], [WIDTH_M, HEIGHT_M], [0, HEIGHT_M]], float)
    shops = []
    for i in range(8):
        for j in range(6):
            x0, y0 = 10 + 27.5 * i, 10 + 33 * j
            shops.append(np.array([[x0, y0], [x0 + 20, y0], [x0 + 20, y0 + 25], [x0, y0 + 25]], float))
    return fusion.floor_plan_from_polygons(outline, shops)


def walk(seed: int = SEED):
    rng = np.random.default_rng(seed)
    n = 120
    t = 0.5 * np.arange(1, n + 1)
    heading = (np.arange(n) // 30) * (math.pi / 2)
    steps = fusion.Steps.from_polar(t, np.full(n, 0.7), heading - 0.05, 0.1, 0.15)
    truth = np.cumsum(np.c_[0.7 * np.cos(heading), 0.7 * np.sin(heading)], axis=0) + [33.5, 4.0]
    ft = t[3::4]
    idx = np.searchsorted(t, ft)
    means = np.stack([truth[idx] + rng.normal(0, 3, (idx.size, 2)),
                      rng.uniform([0, 0], [WIDTH_M, HEIGHT_M], (idx.size, 2))], axis=1)
    fixes = fusion.Fixes.from_arrays(ft, means, 4.0, np.tile([0.7, 0.3], (idx.size, 1)))
    return steps, fixes, truth


def _best(fn, repeat: int, cpu: dict, name: str) -> float:
    """Best wall time [s] of `repeat` calls; the best CPU time (user + sys of the process) into cpu[name]."""
    best, best_cpu = math.inf, math.inf
    for _ in range(repeat):
        tic, cpu_tic = time.perf_counter(), time.process_time()
        fn()
        best = min(best, time.perf_counter() - tic)
        best_cpu = min(best_cpu, time.process_time() - cpu_tic)
    cpu[name] = best_cpu
    return best


def run(quick: bool = False) -> dict:
    load_before = os.getloadavg()[0]
    plan = mall_plan()
    options = fusion.GridTrackerOptions(heading_offset_bins=9, heading_offset_sd_rad=0.15,
                                        fix_tempering_by_variance=True, spatial_median=False)
    tracker = fusion.GridTracker(plan, options)
    steps, fixes, truth = walk()
    x0, y0, nx, ny = tracker.grid_geometry(0)
    a = tracker.walkable_fraction(0)
    wall = (a + (1 - a) * math.exp(options.wall_log_penalty)).astype(np.float32)
    probe = fusion.track_grid(tracker, steps, fixes=fixes, smooth=False)
    offsets = np.asarray(probe["heading_offset_bins_rad"])
    span = options.heading_offset_span_sd * options.heading_offset_sd_rad
    peer_args = ({"x0": x0, "y0": y0, "cell": options.cell_size_m, "wall_factor": wall, "area_m2": plan.walkable_area(0)},
                 (steps.times_s, steps.displacements_m, steps.covariances_m2), fixes.as_arrays(),
                 {"offsets": offsets, "log_prior": -0.5 * (offsets / options.heading_offset_sd_rad) ** 2,
                  "bin_width": 2 * span / offsets.size, "position_noise_m": options.position_noise_m,
                  "eps": options.fix_outlier_probability, "tau": options.fix_tempering, "by_variance": True})
    repeat = 1 if quick else 5
    # The site model's smoothed track: the smoother and its second pass from the located start
    # (fusion.site_model.run_default with TrackSettings' second_pass_start_sd_m).
    settings = site_model.TrackSettings()
    second = tracker.with_options(site_model.second_pass_options(options, settings))
    cpu_seconds: dict = {}
    seconds = {
        "indoorloc filter (C++)": _best(lambda: fusion.track_grid(tracker, steps, fixes=fixes, smooth=False), repeat,
                                        cpu_seconds, "indoorloc filter (C++)"),
        "indoorloc filter + smoother (C++)": _best(lambda: fusion.track_grid(tracker, steps, fixes=fixes), repeat,
                                                   cpu_seconds, "indoorloc filter + smoother (C++)"),
        "indoorloc filter + smoother + second pass (C++)": _best(
            lambda: site_model.run_default(tracker, steps, fixes, second_pass=second, floor=plan.floors[0],
                                           median=False), repeat, cpu_seconds,
            "indoorloc filter + smoother + second pass (C++)"),
        "numpy + scipy filter": _best(lambda: grid_filter_numpy.forward_filter(*peer_args), 1 if quick else 2,
                                      cpu_seconds, "numpy + scipy filter"),
    }
    ref = grid_filter_numpy.forward_filter(*peer_args)
    layers, cells, m = offsets.size, int(nx * ny), len(steps)
    minutes = (steps.times_s[-1] - steps.times_s[0]) / 60.0
    return {
        "load_average_1min": {"before": load_before, "after": os.getloadavg()[0], "cpus": os.cpu_count()},
        "title": "Grid tracker: exact filter and smoother on 1 m cells of a mall-sized floor, against numpy + scipy",
        "cells": cells, "layers": layers, "steps": m, "fixes": len(fixes), "minutes_walked": minutes,
        "seconds": seconds, "cpu_seconds": cpu_seconds,
        "cell_steps_per_s": {k: layers * cells * m / v for k, v in seconds.items()},
        "seconds_per_minute_walked": {k: v / minutes for k, v in seconds.items()},
        "filter_over_peer": seconds["numpy + scipy filter"] / seconds["indoorloc filter (C++)"],
        "filter_over_peer_cpu": cpu_seconds["numpy + scipy filter"] / cpu_seconds["indoorloc filter (C++)"],
        "max_mean_difference_m": float(np.abs(probe["mean_m"] - ref["mean_m"]).max()),
        "final_error_m": float(np.hypot(*(probe["mean_m"][-1] - truth[-1]))),
        "goals": {"seconds_per_minute_walked_filter_and_smoother": 0.2},
    }


def markdown(result: dict) -> str:
    r = result
    load = r["load_average_1min"]
    lines = [f"{r['cells']:,} cells x {r['layers']} heading-offset layers, {r['steps']} steps "
             f"({r['minutes_walked']:.1f} min of walking), {r['fixes']} fixes; 1 thread, best of the repetitions; "
             f"load average {load['before']:.1f} -> {load['after']:.1f} on {load['cpus']} CPUs (wall time suffers "
             "from the load, CPU time = user + sys of the process much less).", "",
             "| implementation | s per walk (wall) | s per walk (CPU) | s per minute walked (wall) | cell-steps/s (wall) |",
             "|---|---|---|---|---|"]
    for k, v in r["seconds"].items():
        cpu = r.get("cpu_seconds", {}).get(k, float("nan"))
        lines.append(f"| {k} | {v:.3f} | {cpu:.3f} | {r['seconds_per_minute_walked'][k]:.3f} | "
                     f"{r['cell_steps_per_s'][k]:.3g} |")
    lines += ["", f"C++ filter / numpy + scipy filter: **{r['filter_over_peer']:.1f}x** wall, "
              f"{r.get('filter_over_peer_cpu', float('nan')):.1f}x CPU; filtered means differ by at most "
              f"{1e3 * r['max_mean_difference_m']:.2f} mm; goal {r['goals']['seconds_per_minute_walked_filter_and_smoother']} "
              "s per minute walked for filter + smoother (the site model's smoothed track adds its second pass: "
              f"{r['seconds_per_minute_walked'].get('indoorloc filter + smoother + second pass (C++)', float('nan')):.3f} "
              "s per minute walked in all)."]
    return "\n".join(lines)


if __name__ == "__main__":
    res = run()
    print(markdown(res))
