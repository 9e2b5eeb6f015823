"""The fusion tracker on the synthetic building: what each source contributes.

Per seed one building and one walk (``simulate.building`` / ``simulate.walker``), then seven
methods on the same inputs, scored by the position error against the truth:

============================  =================================================================
``wifi_only``                 the wifi subsystem's best single-scan fix: the MMSE (posterior
                              mean) of paper 004's interpolated likelihood on a grid
                              (``wifi.GridPosterior``), one fix per scan, scored at scan times
``pdr_only``                  dead reckoning from the known start position and heading
``pdr_walls``                 tracker: PDR + floor plan, known start
``pdr_wifi``                  tracker: PDR + WiFi, no plan, known start
``fusion_known_start``        tracker: PDR + WiFi + plan, known start
``fusion_unknown_start``      tracker: PDR + WiFi + plan, unknown start (seeking from WiFi)
``fusion_smoother``           as unknown start, then the backward (FFBSi) smoother
============================  =================================================================

Tracker methods are scored at the step times (the causal estimate after each step). The
tracker's settings are the library defaults (``fusion.tracker_options()``), chosen on tuning
seeds disjoint from the scored ones (``TUNING_SEEDS``; see docs/fusion.md and ``tune``).
"""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Dict, Iterable, Iterator, List, Optional, Sequence

import numpy as np

from indoorloc import fusion, wifi
from indoorloc.registry import DemoContext, DemoSection, register_demo
from indoorloc.simulate.building import make_building
from indoorloc.simulate.walker import simulate_walk

METHODS = (
    "wifi_only",
    "pdr_only",
    "pdr_walls",
    "pdr_wifi",
    "fusion_known_start",
    "fusion_unknown_start",
    "fusion_smoother",
)
#: Seeds that chose the defaults; never scored by ``evaluate`` (its default seeds are 0..N-1).
TUNING_SEEDS = tuple(range(1000, 1020))
#: Error below which the unknown-start filter counts as having found the walker [m].
FOUND_RADIUS_M = 3.0


@dataclass
class WalkResult:
    """Errors of every method on one seeded walk."""

    seed: int
    errors_m: Dict[str, np.ndarray]          #: per method, errors at its evaluation times
    times_s: Dict[str, np.ndarray]           #: per method, evaluation times since the start [s]
    time_to_found_s: float                   #: unknown start: time until the error stays < 3 m
    seconds: Dict[str, float] = field(default_factory=dict)
    duration_s: float = 0.0


def time_until_within(times_s: np.ndarray, errors_m: np.ndarray, radius_m: float = FOUND_RADIUS_M) -> float:
    """First time [s] from which every later error is below ``radius_m`` (inf if never)."""
    above = np.nonzero(errors_m >= radius_m)[0]
    if above.size == 0:
        return float(times_s[0]) if times_s.size else float("inf")
    last = above[-1]
    return float(times_s[last + 1]) if last + 1 < times_s.size else float("inf")


def scenario_inputs(scenario, options: fusion.TrackerOptions):
    """The tracker's inputs from a simulated walk: plan, model, steps, observations."""
    building = scenario.building
    plan = fusion.floor_plan_from_geometries(building.floors)
    signal_map = building.signal_map()
    model = wifi.RssModel(signal_map)
    columns = np.asarray(signal_map.access_point_indices)
    scans = scenario.scans
    rss = scans.rss_dbm[:, columns]
    ages = scans.age_s[:, columns]
    observations, _ = fusion.make_wifi_observations(scans.time_s, rss, ages, options, at_own_time=True)
    steps = fusion.Steps.from_polar(scenario.steps.time_s, scenario.steps.length_m, scenario.steps.heading_rad,
                                    scenario.steps.length_sd_m, scenario.steps.heading_sd_rad)
    return plan, model, signal_map, steps, observations


def known_start(scenario) -> dict:
    """The known start: true position, floor and PDR-to-floor yaw at the first step."""
    steps = scenario.steps
    offset = -(steps.heading_bias_rad + (steps.heading_drift_rad[0] if steps.num_steps else 0.0))
    t0 = float(steps.time_s[0]) - 0.5 if steps.num_steps else 0.0
    return {"position_m": np.asarray(scenario.start_position_m, float), "floor": int(scenario.floor),
            "heading_offset_rad": float(offset), "time_s": t0}


def wifi_only_fixes(scenario, model, signal_map, options: fusion.TrackerOptions):
    """MMSE fix per scan; readings older than ``options.max_age_s`` count as not heard."""
    columns = np.asarray(signal_map.access_point_indices)
    rss = np.array(scenario.scans.rss_dbm[:, columns], float)
    ages = scenario.scans.age_s[:, columns]
    rss[np.nan_to_num(ages, nan=0.0) > options.max_age_s] = np.nan
    prepared = signal_map.prepare_scans(rss, 100.0, options.not_heard_dbm)
    posterior = wifi.GridPosterior(model, 1.0)
    fixes = posterior.locate(prepared)
    return np.asarray(fixes["positions_m"] if isinstance(fixes, dict) else fixes[0], float)


def run_walk(seed: int, options: Optional[fusion.TrackerOptions] = None, smoother_trajectories: int = 100,
             methods: Sequence[str] = METHODS) -> WalkResult:
    """Every method on the walk of ``seed`` (building and walk both from the seed)."""
    options = options or fusion.tracker_options()
    building = make_building(seed=seed)
    scenario = simulate_walk(building, seed=seed)
    plan, model, signal_map, steps, observations = scenario_inputs(scenario, options)
    truth = scenario.steps.true_position_m
    t0 = float(scenario.steps.time_s[0]) - 0.5
    step_times = scenario.steps.time_s - t0
    start = known_start(scenario)
    errors: Dict[str, np.ndarray] = {}
    times: Dict[str, np.ndarray] = {}
    seconds: Dict[str, float] = {}

    def score(name: str, estimate_m: np.ndarray, at_times: np.ndarray, true_m: np.ndarray) -> None:
        errors[name] = np.linalg.norm(np.asarray(estimate_m) - true_m, axis=1)
        times[name] = at_times

    if "wifi_only" in methods:
        tic = time.perf_counter()
        fixes = wifi_only_fixes(scenario, model, signal_map, options)
        seconds["wifi_only"] = time.perf_counter() - tic
        score("wifi_only", fixes, scenario.scans.time_s - t0, scenario.scans.true_position_m)
    if "pdr_only" in methods:
        rotated = fusion.rotate(steps.displacements_m, start["heading_offset_rad"])
        score("pdr_only", start["position_m"] + np.cumsum(rotated, axis=0), step_times, truth)

    runs = {
        "pdr_walls": dict(plan=plan, wifi_model=None, start=start),
        "pdr_wifi": dict(plan=None, wifi_model=model, start=start),
        "fusion_known_start": dict(plan=plan, wifi_model=model, start=start),
        "fusion_unknown_start": dict(plan=plan, wifi_model=model, start=None),
    }
    unknown_result = None
    for name, run in runs.items():
        want_smoother = name == "fusion_unknown_start" and "fusion_smoother" in methods
        if name not in methods and not want_smoother:
            continue
        smoother = fusion.SmootherOptions(num_trajectories=smoother_trajectories, seed=seed) if want_smoother else None
        tic = time.perf_counter()
        result = fusion.track(steps, run["wifi_model"] and observations or [], plan=run["plan"],
                              wifi_model=run["wifi_model"], start=run["start"], options=options, smoother=smoother)
        seconds[name] = time.perf_counter() - tic
        score(name, result["mean_m"], step_times, truth)
        if want_smoother:
            unknown_result = result
            score("fusion_smoother", result["smoothed_m"], step_times, truth)
            seconds["fusion_smoother"] = float(result["smoother_seconds"])
    found = (time_until_within(times["fusion_unknown_start"], errors["fusion_unknown_start"])
             if "fusion_unknown_start" in errors else float("nan"))
    del unknown_result
    return WalkResult(seed=seed, errors_m=errors, times_s=times, time_to_found_s=found, seconds=seconds,
                      duration_s=float(step_times[-1]) if step_times.size else 0.0)


def iter_walks(seeds: Iterable[int], options: Optional[fusion.TrackerOptions] = None, threads: int = 1,
               **kwargs) -> Iterator[WalkResult]:
    """run_walk over seeds on ``threads`` threads, yielded in seed order (the results do not
    depend on the number of threads: each walk is seeded by its own seed only)."""
    seeds = list(seeds)
    if threads <= 1:
        for s in seeds:
            yield run_walk(s, options, **kwargs)
        return
    with ThreadPoolExecutor(max_workers=threads) as pool:
        futures = [pool.submit(run_walk, s, options, **kwargs) for s in seeds]
        for f in futures:
            yield f.result()


def run_walks(seeds: Iterable[int], options: Optional[fusion.TrackerOptions] = None, threads: int = 1,
              **kwargs) -> List[WalkResult]:
    """All of :func:`iter_walks` as a list."""
    return list(iter_walks(seeds, options, threads, **kwargs))


def summarize(results: Sequence[WalkResult]) -> dict:
    """The JSON contract of ``indoorloc fusion synthetic``:
    ``{"methods": {NAME: {"mean_m", "p90_m", "n_walks"}}, "seeds": [...],
    "unknown_start_time_to_3m_s": median}``. ``mean_m`` is the mean over walks of each walk's
    mean error; ``p90_m`` the mean over walks of each walk's 90th percentile (both in metres).
    Extra keys (``mean_m_sd``, ``median_walk_mean_m``, ``worst_walk_mean_m``) are informative.
    """
    methods = {}
    for name in METHODS:
        per_walk = [r.errors_m[name] for r in results if name in r.errors_m and r.errors_m[name].size]
        if not per_walk:
            continue
        means = np.array([e.mean() for e in per_walk])
        p90s = np.array([np.percentile(e, 90) for e in per_walk])
        methods[name] = {"mean_m": float(means.mean()), "p90_m": float(p90s.mean()), "n_walks": len(per_walk),
                         "mean_m_sd": float(means.std(ddof=1)) if len(means) > 1 else 0.0,
                         "median_walk_mean_m": float(np.median(means)), "worst_walk_mean_m": float(means.max())}
    found = np.array([r.time_to_found_s for r in results])
    return {"methods": methods, "seeds": [int(r.seed) for r in results],
            "unknown_start_time_to_3m_s": float(np.median(found)) if found.size else float("nan"),
            "unknown_start_found_within_30s_fraction": float(np.mean(found <= 30.0)) if found.size else float("nan"),
            "mean_walk_duration_s": float(np.mean([r.duration_s for r in results])) if results else 0.0}


def markdown_table(summary: dict) -> str:
    lines = ["| method | mean error [m] | sd over walks | p90 [m] | walks |", "|---|---|---|---|---|"]
    for name, m in summary["methods"].items():
        lines.append(f"| {name} | {m['mean_m']:.2f} | {m['mean_m_sd']:.2f} | {m['p90_m']:.2f} | {m['n_walks']} |")
    lines.append("")
    lines.append(f"Unknown start: median time until the error stays below {FOUND_RADIUS_M:.0f} m: "
                 f"{summary['unknown_start_time_to_3m_s']:.1f} s "
                 f"({100 * summary['unknown_start_found_within_30s_fraction']:.0f} % of walks within 30 s; "
                 f"walks last {summary['mean_walk_duration_s']:.0f} s on average).")
    return "\n".join(lines)


def walk_snapshot(seed: int, options: Optional[fusion.TrackerOptions] = None, cloud_steps: int = 4) -> dict:
    """Everything the demo figure draws for one walk: plan edges, truth, WiFi-only fixes, PDR-only,
    the unknown-start filter (streaming API, with its particle cloud at ``cloud_steps`` times),
    the smoothed track, and each method's error over time."""
    options = options or fusion.tracker_options()
    building = make_building(seed=seed)
    scenario = simulate_walk(building, seed=seed)
    plan, model, signal_map, steps, observations = scenario_inputs(scenario, options)
    start = known_start(scenario)
    t0 = float(scenario.steps.time_s[0]) - 0.5
    tracker = fusion.ParticleTracker(plan, model, None, options)
    tracker.initialize_unknown(None)
    clouds = []
    picks = set(np.linspace(2, len(steps) - 1, cloud_steps).astype(int).tolist())
    means = np.zeros((len(steps), 2))
    k_obs = 0
    for k in range(len(steps)):
        t = steps.times_s[k]
        while k_obs < len(observations) and observations[k_obs].time_s < t:
            tracker.wifi(observations[k_obs])
            k_obs += 1
        est = tracker.step(t, steps.displacements_m[k], fusion.covariance_matrix(steps.covariances_m2[k]))
        while k_obs < len(observations) and observations[k_obs].time_s <= t:
            est = tracker.wifi(observations[k_obs])
            k_obs += 1
        means[k] = est.mean_m
        if k in picks:
            states, _, weights = tracker.particles()
            clouds.append({"t_s": float(t - t0), "xy_m": states[:, :2].copy(), "weights": weights.copy(),
                           "truth_m": scenario.steps.true_position_m[k].copy()})
    smoothed = fusion.track(steps, observations, plan=plan, wifi_model=model, options=options,
                            smoother=fusion.SmootherOptions(num_trajectories=100, seed=seed))
    rotated = fusion.rotate(steps.displacements_m, start["heading_offset_rad"])
    pdr = start["position_m"] + np.cumsum(rotated, axis=0)
    fixes = wifi_only_fixes(scenario, model, signal_map, options)
    truth_steps = scenario.steps.true_position_m
    step_t = scenario.steps.time_s - t0
    return {
        "seed": seed,
        "edges_m": plan.edges(0),
        "bounds_m": plan.bounds(0),
        "truth_m": scenario.truth.position_m,
        "aps_m": scenario.access_points_m,
        "wifi_fixes_m": fixes,
        "pdr_only_m": pdr,
        "filter_m": means,
        "smoothed_m": smoothed["smoothed_m"],
        "clouds": clouds,
        "errors": {
            "wifi_only": (scenario.scans.time_s - t0, np.linalg.norm(fixes - scenario.scans.true_position_m, axis=1)),
            "pdr_only": (step_t, np.linalg.norm(pdr - truth_steps, axis=1)),
            "fusion_unknown_start": (step_t, np.linalg.norm(means - truth_steps, axis=1)),
            "fusion_smoother": (step_t, np.linalg.norm(smoothed["smoothed_m"] - truth_steps, axis=1)),
        },
    }


@register_demo("fusion", "Fusion: PDR + WiFi + floor plan on a synthetic building")
def demo(ctx: DemoContext) -> DemoSection:
    """One synthetic walk drawn (plan, truth, WiFi-only fixes, PDR-only, the filter's track with
    its particle cloud at a few times, the smoother) with its error over time, and the table of
    every method over a few seeded walks (the full table: ``indoorloc fusion synthetic``)."""
    from indoorloc import plots

    seeds = list(range(3 if ctx.quick else 10))
    results = run_walks(seeds, threads=2)
    summary = summarize(results)
    figure = plots.fusion_walk(walk_snapshot(seeds[0]), ctx.figure_path("fusion_walk"))
    text = (markdown_table(summary) + f"\n\n{len(seeds)} seeded walks (one synthetic building each); "
            "`indoorloc fusion synthetic --walks 50` runs the full table.")
    return DemoSection(markdown=text, figures=[figure])
