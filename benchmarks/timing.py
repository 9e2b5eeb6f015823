"""Timing helpers shared by the benchmarks (wall clock, same process)."""

from __future__ import annotations

import time
from typing import Callable, List


def run_times(fn: Callable[[], object], repeat: int) -> List[float]:
    """Seconds taken by each of `repeat` calls of fn()."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return times


def median_seconds(fn: Callable[[], object], repeat: int) -> float:
    """Median wall time of fn() over `repeat` calls [s]."""
    times = sorted(run_times(fn, repeat))
    mid = len(times) // 2
    return times[mid] if len(times) % 2 else 0.5 * (times[mid - 1] + times[mid])


def best_seconds(fn: Callable[[], object], repeat: int) -> float:
    """Fastest wall time of fn() over `repeat` calls [s] (least disturbed by other load)."""
    return min(run_times(fn, repeat))
