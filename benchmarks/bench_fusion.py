"""The fusion tracker's two inner loops (issue 14, "Speed"): indoorloc.fusion.ParticleTracker (C++)
against the same filter written here in numpy + shapely 2 (walls) and numpy + scipy (WiFi).

1. Motion + wall test: N = 10^4 particles, a 200 x 200 m hall with a lattice of 2,500 square
   pillars (1 m, 4 m pitch): 10,004 wall edges. One timed run = STEPS calls of
   `tracker.step(t, d, Σ_d)`, each the full filter step: motion of every particle with its
   heading-offset and scale states (step_motion.h), wall test of every particle's step (a blocked
   particle is dropped and stays), log-weight normalisation, ESS, systematic resampling when
   ESS < N/2, the estimate (weighted mean, covariance, circular mean offset, mean scale). Every run
   starts from the same particles (`set_particles`, untimed) and takes the same steps (0.7 m,
   random headings). Reported as particle-steps per second (N * STEPS / s). The split into
   motion + weights and wall test is measured from Python only: the same tracker with no plan,
   with the bare hall (4 edges) and with the pillars; plus the batch wall test alone
   (`plan.crosses_wall` on 10^4 step segments) and the per-call overhead (N = 1).
2. WiFi update with 100 APs: a signal map of 100 APs on 2,501 reference points (60 x 40 m, 1 m grid
   jittered by up to 0.2 m so that the Delaunay triangulation is unique and CGAL and qhull agree),
   log-distance means, variances 4-10 dB². One timed call = `tracker.wifi(obs)` with all 100 APs
   on 10^4 particles spread uniformly over the floor (set untimed before each call): interpolation
   of the 100 means and 100 variances at every particle, the tempered capped Gaussian
   log-likelihood (wifi_likelihood.h), normalisation, ESS, resampling, the estimate. Reported as
   particle-APs per second (N * 100 / s). Recovery is switched off (it evaluates a candidate grid,
   not the particles).
3. Both with num_threads = 2 for information (the machine has 2 shared cores).

Checks that the peers do the same work (in the JSON and the table): the peer's wall test equals
`plan.crosses_wall` on random segments; the blocked fraction per step agrees with indoorloc's
within noise; the WiFi log-likelihood increment (log-sum-exp of the particles' tempered
log-likelihoods, uniform weights before) agrees to ~1e-9 relative, on the whole cloud and per
particle (a one-particle tracker per particle).

Timing: wall clock, same process, the implementations interleaved in every repetition, best of
the repetitions. Peers (shapely, scipy; fusion_peers.py) come from the `bench` extra, never at run time.
"""

from __future__ import annotations

import os
import time

import numpy as np

from indoorloc import fusion, wifi

from fusion_peers import NumpyTracker, ScipyInterpolator, ShapelyWalls

N = 10_000
SEED = 0
# Motion benchmark: the hall and its pillars.
HALL_M = 200.0
PITCH_M = 4.0
PILLAR_M = 1.0
STEP_LENGTH_M = 0.7
STEP_LENGTH_SD_M = 0.1
STEP_HEADING_SD_RAD = 0.1
START_SD_M = 20.0
# WiFi benchmark: the signal map.
MAP_W_M, MAP_H_M = 60.0, 40.0
NUM_APS = 100
JITTER_M = 0.2

CPP = "indoorloc (C++)"
CPP2 = "indoorloc (C++), 2 threads"
PEER_WALLS = "numpy + shapely 2"
PEER_WIFI = "numpy + scipy"


def _best(fn, state: dict, key: str, cpu: dict | None = None) -> None:
    """Keeps the fastest wall time of fn() in state[key] and that run's process CPU time in
    cpu[key] (for one thread a load-independent check on the wall time: the machine is shared)."""
    start, start_cpu = time.perf_counter(), time.process_time()
    fn()
    sec, sec_cpu = time.perf_counter() - start, time.process_time() - start_cpu
    if sec < state.get(key, np.inf):
        state[key] = sec
        if cpu is not None:
            cpu[key] = sec_cpu


# --------------------------------------------------------------------------- geometry

def _square(cx: float, cy: float, half: float) -> np.ndarray:
    return np.array([[cx - half, cy - half], [cx + half, cy - half], [cx + half, cy + half], [cx - half, cy + half]])


def pillar_hall(with_pillars: bool = True) -> fusion.FloorPlan:
    """The 200 x 200 m hall, with the lattice of square pillars (10,004 edges) or bare (4 edges)."""
    outline = np.array([[0.0, 0.0], [HALL_M, 0.0], [HALL_M, HALL_M], [0.0, HALL_M]])
    k = int(round(HALL_M / PITCH_M))
    pillars = ([_square(PITCH_M * (i + 0.5), PITCH_M * (j + 0.5), 0.5 * PILLAR_M) for i in range(k) for j in range(k)]
               if with_pillars else [])
    return fusion.FloorPlan([fusion.FloorGeometry(0, [outline], pillars, None)])


def signal_map(seed: int = SEED):
    """(positions (P, 2), mean (P, K), variance (P, K), AP positions (K, 2)): 60 x 40 m at 1 m,
    jittered; log-distance means (-35 dBm at 1 m, exponent 2.5) with 2 dB shadowing."""
    rng = np.random.default_rng(seed)
    gx, gy = np.meshgrid(np.arange(0.0, MAP_W_M + 0.5), np.arange(0.0, MAP_H_M + 0.5))
    pos = np.column_stack([gx.ravel(), gy.ravel()]) + rng.uniform(-JITTER_M, JITTER_M, (gx.size, 2))
    aps = np.column_stack([rng.uniform(-5.0, MAP_W_M + 5.0, NUM_APS), rng.uniform(-5.0, MAP_H_M + 5.0, NUM_APS)])
    dist = np.maximum(np.hypot(*(pos[:, None, :] - aps[None, :, :]).transpose(2, 0, 1)), 1.0)
    mean = -35.0 - 25.0 * np.log10(dist) + rng.normal(0.0, 2.0, dist.shape)
    var = rng.uniform(4.0, 10.0, dist.shape)
    return pos, mean, var, aps


# --------------------------------------------------------------------------- the benchmark

def _steps(count: int, seed: int):
    rng = np.random.default_rng(seed)
    headings = rng.uniform(-np.pi, np.pi, count)
    disp, cov3 = fusion.steps_from_polar(np.full(count, STEP_LENGTH_M), headings, np.full(count, STEP_LENGTH_SD_M),
                                         np.full(count, STEP_HEADING_SD_RAD))
    return disp, [fusion.covariance_matrix(c) for c in cov3]


def _motion_agreement(a: dict, b: dict) -> dict:
    """The motion models agree: after the run's steps without walls, the mean displacement of the
    particles of indoorloc (a) and the peer (b) (difference in standard errors) and the spread of
    displacement [m], offset [deg] and scale."""
    da, db = a["displacement_m"], b["displacement_m"]
    se = np.sqrt(da.var(axis=0) / N + db.var(axis=0) / N)
    return {
        "mean_displacement_m": {"cpp": da.mean(axis=0).tolist(), "peer": db.mean(axis=0).tolist()},
        "mean_displacement_difference_in_se": (np.abs(da.mean(axis=0) - db.mean(axis=0)) / se).tolist(),
        "sd_displacement_m": {"cpp": da.std(axis=0).tolist(), "peer": db.std(axis=0).tolist()},
        "sd_offset_deg": {"cpp": float(np.degrees(a["offset_rad"].std())),
                          "peer": float(np.degrees(b["offset_rad"].std()))},
        "sd_scale": {"cpp": float(a["scale"].std()), "peer": float(b["scale"].std())},
    }


def _per_call_seconds(one, states0, floors0, disp, covs, calls: int = 2000) -> float:
    """Per-call overhead [s] of tracker.step with one particle (checks, the StepMotion, the estimate object):
    `one` is a one-particle tracker, set to the first particle of the common start."""
    steps = len(disp)
    one.set_particles(states0[:1], floors0[:1])
    overhead = {}
    for r in range(3):
        _best(lambda r=r: [one.step(r * calls + k, disp[k % steps], covs[k % steps]) for k in range(calls)],
              overhead, "n1")
    return overhead["n1"] / calls


def _motion(quick: bool) -> dict:
    steps = 30 if quick else 100
    repeat = 1 if quick else 3
    plans = {"pillars": pillar_hall(True), "bare hall": pillar_hall(False), "no plan": None}
    edges = plans["pillars"].edges(0)

    def options(threads: int, n: int = N):
        return fusion.tracker_options(num_particles=n, num_threads=threads, start_position_sd_m=START_SD_M, seed=SEED)

    # The common start: the known-start prior around the hall's centre, truncated to walkable.
    init = fusion.ParticleTracker(plans["pillars"], None, None, options(1))
    init.initialize_known(0.0, [0.5 * HALL_M, 0.5 * HALL_M], 0, 0.0)
    states0, floors0, _ = init.particles()
    disp, covs = _steps(steps, SEED + 1)

    # The peer's wall test: both shapely methods checked against plan.crosses_wall on random
    # segments (up to 3 m, so that many touch pillars), and timed alone on the first step's segments.
    rng = np.random.default_rng(SEED + 2)
    p = rng.uniform(0.0, HALL_M, (500, 2))
    a, length = rng.uniform(-np.pi, np.pi, 500), rng.uniform(0.0, 3.0, 500)
    random_segments = np.column_stack([p, p + length[:, None] * np.column_stack([np.cos(a), np.sin(a)])])
    expected = plans["pillars"].crosses_wall(random_segments)
    methods = {m: ShapelyWalls(edges, m) for m in ("strtree", "prepared")}
    mismatches = {m: int((w.crosses(random_segments) != expected).sum()) for m, w in methods.items()}
    heads = rng.uniform(-np.pi, np.pi, N)
    step_segments = np.column_stack([states0[:, :2], states0[:, :2] + STEP_LENGTH_M * np.column_stack(
        [np.cos(heads), np.sin(heads)])])
    wall_only = {}
    for _ in range(max(3, 2 * repeat)):
        _best(lambda: plans["pillars"].crosses_wall(step_segments), wall_only, "indoorloc crosses_wall (batch)")
        for m, w in methods.items():
            _best(lambda w=w: w.crosses(step_segments), wall_only, f"shapely {m}")
    best_method = min(methods, key=lambda m: wall_only[f"shapely {m}"])
    walls = methods[best_method]

    # The filters: (tracker or peer, plan name, threads).
    runs = {
        f"{CPP}, pillars": ("cpp", "pillars", 1),
        f"{CPP}, bare hall": ("cpp", "bare hall", 1),
        f"{CPP}, no plan": ("cpp", "no plan", 1),
        f"{CPP2}, pillars": ("cpp", "pillars", 2),
        f"{PEER_WALLS}, pillars": ("peer", "pillars", 1),
        f"{PEER_WALLS}, no plan": ("peer", "no plan", 1),
    }
    filters = {}
    for name, (kind, plan_name, threads) in runs.items():
        if kind == "cpp":
            filters[name] = fusion.ParticleTracker(plans[plan_name], None, None, options(threads))
        else:
            filters[name] = NumpyTracker(states0, options(1), walls if plan_name == "pillars" else None,
                                           seed=SEED)
    blocked = {name: [] for name in runs}
    seconds, cpu_seconds = {}, {}
    clock = {name: 0.0 for name in runs}  # step times must not go back

    def run_one(name: str, record: bool) -> None:
        f = filters[name]
        if isinstance(f, NumpyTracker):
            f.set_particles(states0)

            def go():
                for k in range(steps):
                    out = f.step(disp[k], covs[k])
                    if record:
                        blocked[name].append(out["blocked_fraction"])
        else:
            f.set_particles(states0, floors0)
            t0 = clock[name]
            clock[name] += steps

            def go():
                for k in range(steps):
                    out = f.step(t0 + k, disp[k], covs[k])
                    if record:
                        blocked[name].append(out.blocked_fraction)
        _best(go, seconds, name, cpu_seconds)

    for name in runs:  # warm-up, untimed
        f = filters[name]
        if isinstance(f, NumpyTracker):
            f.set_particles(states0)
            f.step(disp[0], covs[0])
        else:
            f.set_particles(states0, floors0)
            f.step(clock[name], disp[0], covs[0])
            clock[name] += 1.0
    motion_check = {}
    for rep in range(repeat):
        for name in runs:
            run_one(name, record=rep == 0)
            if rep == 0 and name.endswith("no plan"):  # no walls: no resampling, particle i stays particle i
                f = filters[name]
                st = f.particles()[0] if not isinstance(f, NumpyTracker) else np.column_stack(
                    [f.x, f.y, f.offset, f.scale])
                motion_check[name] = {"displacement_m": st[:, :2] - states0[:, :2], "offset_rad": st[:, 2],
                                      "scale": st[:, 3]}
    motion_agreement = _motion_agreement(motion_check[f"{CPP}, no plan"], motion_check[f"{PEER_WALLS}, no plan"])

    per_call_s = _per_call_seconds(fusion.ParticleTracker(plans["pillars"], None, None, options(1, 1)),
                                   states0, floors0, disp, covs)

    rates = {name: N * steps / sec for name, sec in seconds.items()}
    us_per_step = {name: 1e6 * sec / steps for name, sec in seconds.items()}
    ns = {name: 1e9 * sec / (N * steps) for name, sec in seconds.items()}
    frac = {name: {"mean": float(np.mean(b)), "se": float(np.std(b, ddof=1) / np.sqrt(len(b)))}
            for name, b in blocked.items() if b and "pillars" in name}
    cpp_b, peer_b = frac[f"{CPP}, pillars"], frac[f"{PEER_WALLS}, pillars"]
    return {
        "plan": {"edges": int(plans["pillars"].num_edges(0)), "report": plans["pillars"].report(),
                 "bare_hall_edges": int(plans["bare hall"].num_edges(0))},
        "particles": N,
        "steps_per_run": steps,
        "repeat": repeat,
        "seconds": seconds,
        "cpu_seconds": cpu_seconds,
        "particle_steps_per_s": rates,
        "ns_per_particle_step": ns,
        "us_per_step_call": us_per_step,
        "split_ns_per_particle_step": {
            "per-call overhead (N = 1 step), spread over N": 1e9 * per_call_s / N,
            "motion + weights + resampling + estimate (no plan)": ns[f"{CPP}, no plan"],
            "wall test, bare hall (grid walk, 4 edges)": ns[f"{CPP}, bare hall"] - ns[f"{CPP}, no plan"],
            "wall test, 10^4 edges": ns[f"{CPP}, pillars"] - ns[f"{CPP}, no plan"],
            "wall test alone, batch crosses_wall": 1e9 * wall_only["indoorloc crosses_wall (batch)"] / N,
            "peer: motion + weights (no plan)": ns[f"{PEER_WALLS}, no plan"],
            "peer: wall test, 10^4 edges": ns[f"{PEER_WALLS}, pillars"] - ns[f"{PEER_WALLS}, no plan"],
        },
        "per_call_overhead_us": 1e6 * per_call_s,
        "wall_test_alone_seconds_1e4_segments": wall_only,
        "peer_wall_method": best_method,
        "checks": {
            "random_segments": len(random_segments),
            "random_segments_crossing": int(expected.sum()),
            "peer_vs_crosses_wall_mismatches": mismatches,
            "blocked_fraction": frac,
            "motion_without_walls": motion_agreement,
            "blocked_fraction_difference_in_se": abs(cpp_b["mean"] - peer_b["mean"]) / np.hypot(cpp_b["se"], peer_b["se"]),
        },
        "cpp_over_peer": rates[f"{CPP}, pillars"] / rates[f"{PEER_WALLS}, pillars"],
        # The same ratio from each side's process CPU time (independent of the load's waiting).
        "cpp_over_peer_per_cpu_s": cpu_seconds[f"{PEER_WALLS}, pillars"] / cpu_seconds[f"{CPP}, pillars"],
    }


def _wifi(quick: bool) -> dict:
    repeat = 3 if quick else 15
    pos, mean, var, _ = signal_map()
    model = wifi.RssModel(wifi.SignalMap(pos, None, mean, var))
    interp = ScipyInterpolator(pos, mean, var, variance_floor_db2=4.0)
    rng = np.random.default_rng(SEED + 3)
    margin = 0.5
    states = np.column_stack([rng.uniform(margin, MAP_W_M - margin, N), rng.uniform(margin, MAP_H_M - margin, N),
                              np.zeros(N), np.ones(N)])
    floors = np.zeros(N, dtype=np.int32)
    # The scan: the map's fields at a true position (the peer's interpolation), 3 dB noise.
    truth = np.array([[31.3, 17.7]])
    true_mean, _ = interp.mean_and_variance(truth)
    rss = true_mean[0] + rng.normal(0.0, 3.0, NUM_APS)
    obs = fusion.WifiObservation(1.0, list(range(NUM_APS)), rss.tolist())

    def options(threads: int, n: int = N):
        return fusion.tracker_options(num_particles=n, num_threads=threads, recovery_log_ratio=0.0, seed=SEED)

    trackers = {CPP: fusion.ParticleTracker(None, model, None, options(1)),
                CPP2: fusion.ParticleTracker(None, model, None, options(2))}
    peer = NumpyTracker(states, options(1), seed=SEED)
    # For information: the same particles in spatial order (1 m rows, then x), as after
    # resampling a compact cloud; and the interpolation of the 200 fields alone (with gradients),
    # from the coarse grid hint (random order) or from the previous query's triangle.
    order = np.lexsort((states[:, 0], np.floor(states[:, 1])))
    sorted_states = states[order]
    interpolator = model.interpolator(0)
    points = np.ascontiguousarray(states[:, :2])
    sorted_name = f"{CPP}, particles in spatial order"
    interp_grid = "interpolation alone (C++ batch, grid hint, with gradients)"
    interp_prev = "interpolation alone (C++ batch, previous-query hint, with gradients)"
    seconds, cpu_seconds, estimates = {}, {}, {}

    def tracker_update(tr, st, name):
        tr.set_particles(st, floors)  # untimed
        holder = {}
        _best(lambda: holder.setdefault("e", tr.wifi(obs)), seconds, name, cpu_seconds)
        estimates[name] = holder["e"].to_dict()  # a TrackerEstimate; the peer's estimate is a dict

    def peer_update():
        peer.set_particles(states)  # untimed
        holder = {}
        _best(lambda: holder.setdefault("e", peer.wifi(interp, rss)), seconds, PEER_WIFI, cpu_seconds)
        estimates[PEER_WIFI] = holder["e"]

    for rep in range(repeat + 1):  # the first round is the warm-up
        if rep == 1:
            seconds.clear()
            cpu_seconds.clear()
        tracker_update(trackers[CPP], states, CPP)
        tracker_update(trackers[CPP2], states, CPP2)
        peer_update()
        tracker_update(trackers[CPP], sorted_states, sorted_name)
        _best(lambda: interpolator.interpolate(points, False), seconds, interp_grid, cpu_seconds)
        _best(lambda: interpolator.interpolate(points, True), seconds, interp_prev, cpu_seconds)

    # Agreement: the log-likelihood increment of the whole cloud, and per particle on 300
    # particles (a one-particle tracker: its increment is that particle's log-likelihood).
    trackers[CPP].set_particles(states, floors)
    estimates[CPP] = trackers[CPP].wifi(obs).to_dict()
    peer.set_particles(states)
    estimates[PEER_WIFI] = peer.wifi(interp, rss)
    ll_cpp = estimates[CPP]["log_likelihood"]
    ll_peer = estimates[PEER_WIFI]["log_likelihood"]
    one = fusion.ParticleTracker(None, model, None, options(1, 1))
    peer.set_particles(states)
    per_peer = peer.wifi_log_likelihood(interp, rss)[:300]
    per_cpp = np.empty(300)
    for i in range(300):
        one.set_particles(states[i:i + 1], floors[i:i + 1])
        per_cpp[i] = one.wifi(obs).log_likelihood
    per_rel = np.abs(per_cpp - per_peer) / np.abs(per_peer)
    rates = {name: N * NUM_APS / sec for name, sec in seconds.items()}
    return {
        "map": {"points": int(len(pos)), "aps": NUM_APS, "size_m": [MAP_W_M, MAP_H_M], "jitter_m": JITTER_M},
        "particles": N,
        "repeat": repeat,
        "seconds": seconds,
        "cpu_seconds": cpu_seconds,
        "particle_aps_per_s": rates,
        "ns_per_particle": {name: 1e9 * sec / N for name, sec in seconds.items()},
        "checks": {
            "log_likelihood_cpp": ll_cpp,
            "log_likelihood_peer": ll_peer,
            "log_likelihood_relative_difference": abs(ll_cpp - ll_peer) / abs(ll_peer),
            "per_particle_max_relative_difference": float(per_rel.max()),
            "per_particle_count": 300,
            "mean_m": {name: np.asarray(e["mean_m"]).tolist() for name, e in estimates.items()},
            "resampled": {name: bool(e["resampled"]) for name, e in estimates.items()},
        },
        "cpp_over_peer": rates[CPP] / rates[PEER_WIFI],
    }


def run(quick: bool = False) -> dict:
    load_before = os.getloadavg()[0]
    motion = _motion(quick)
    wifi_result = _wifi(quick)
    return {
        "load_average_1min": {"before": load_before, "after": os.getloadavg()[0], "cpus": os.cpu_count()},
        "title": f"Fusion tracker: motion + wall test and WiFi update, N = {N:,} (best of the repetitions)",
        "motion": motion,
        "wifi": wifi_result,
        "goals": {"motion_particle_steps_per_s": 2e7, "wifi_particle_aps_per_s": 5e6, "over_peer": 20.0},
    }


def _rate_rows(rates: dict, cpu_seconds: dict, seconds: dict, middle) -> list:
    """Table rows "| name | rate | middle(name) | CPU / wall | rate per CPU-s |" per implementation
    (the last column empty for the 2-thread runs)."""
    rows = []
    for name, rate in rates.items():
        cpu = cpu_seconds[name]
        per_cpu = "" if "2 threads" in name else f"{rate * seconds[name] / cpu:,.0f}"
        rows.append(f"| {name} | {rate:,.0f} | {middle(name)} | {cpu / seconds[name]:.2f} | {per_cpu} |")
    return rows


def markdown(result: dict) -> str:
    m, w = result["motion"], result["wifi"]
    mc, wc = m["checks"], w["checks"]
    mw = mc["motion_without_walls"]
    lines = [
        f"**Motion + wall test.** {m['plan']['report']} (200 x 200 m hall, 2,500 pillars); N = {m['particles']:,}, "
        f"{m['steps_per_run']} steps of 0.7 m per run, every run from the same particles, best of {m['repeat']}. "
        "Each step is the full filter step (motion with heading-offset and scale states, wall test, weights, "
        f"ESS, resampling, estimate). Peer wall test: shapely `{m['peer_wall_method']}` (the faster of STRtree "
        "query and prepared MultiLineString).",
        "",
        "| implementation | particle-steps/s | ns / particle-step | µs / step call | CPU / wall | "
        "particle-steps per CPU-s |",
        "|---|---|---|---|---|---|",
    ]
    lines += _rate_rows(m["particle_steps_per_s"], m["cpu_seconds"], m["seconds"],
                        lambda name: f"{m['ns_per_particle_step'][name]:.1f} | {m['us_per_step_call'][name]:.0f}")
    per_cpu = m.get("cpp_over_peer_per_cpu_s")
    per_cpu_text = f"**{per_cpu:.1f}x** per CPU-second, " if per_cpu is not None else ""
    cpp_cpu_rate = N * m["steps_per_run"] / m["cpu_seconds"][CPP + ", pillars"]
    lines += ["", f"C++ / peer (pillars, 1 thread): {per_cpu_text}{m['cpp_over_peer']:.1f}x by wall clock (goal 20x); "
              f"goal 2e7 particle-steps/s: {m['particle_steps_per_s'][CPP + ', pillars']:.3g} by wall clock, "
              f"{cpp_cpu_rate:.3g} per CPU-second.", "",
              "Where the time goes (ns per particle-step, from Python: the same filter without plan, with the "
              "bare hall, with the pillars; the batch wall test alone; the per-call cost at N = 1):", "",
              "| part | ns / particle-step |", "|---|---|"]
    for part, v in m["split_ns_per_particle_step"].items():
        lines.append(f"| {part} | {v:.1f} |")
    wall = m["wall_test_alone_seconds_1e4_segments"]
    lines += ["", "Wall test alone on 10^4 step segments: " + ", ".join(
        f"{k} {1e3 * v:.2f} ms" for k, v in wall.items()) + ".", ""]
    b_cpp, b_peer = mc["blocked_fraction"][CPP + ", pillars"], mc["blocked_fraction"][PEER_WALLS + ", pillars"]
    lines += [
        "Same work: peer wall test vs `plan.crosses_wall` on "
        f"{mc['random_segments']} random segments ({mc['random_segments_crossing']} crossing): mismatches "
        + ", ".join(f"{k} {v}" for k, v in mc["peer_vs_crosses_wall_mismatches"].items())
        + f"; blocked weight fraction per step: indoorloc {b_cpp['mean']:.4f} ± {b_cpp['se']:.4f}, peer "
        f"{b_peer['mean']:.4f} ± {b_peer['se']:.4f} (difference {mc['blocked_fraction_difference_in_se']:.1f} se); "
        f"motion without walls after {m['steps_per_run']} steps: mean displacement differs by "
        + " and ".join(f"{v:.1f}" for v in mw["mean_displacement_difference_in_se"])
        + " se (x, y), sd of displacement "
        + f"{mw['sd_displacement_m']['cpp'][0]:.3f} / {mw['sd_displacement_m']['cpp'][1]:.3f} m vs "
        + f"{mw['sd_displacement_m']['peer'][0]:.3f} / {mw['sd_displacement_m']['peer'][1]:.3f} m, of the offset "
        + f"{mw['sd_offset_deg']['cpp']:.2f} vs {mw['sd_offset_deg']['peer']:.2f} deg, of the scale "
        + f"{mw['sd_scale']['cpp']:.4f} vs {mw['sd_scale']['peer']:.4f} (indoorloc vs peer).",
        "",
        f"**WiFi update, {w['map']['aps']} APs.** Signal map of {w['map']['points']:,} reference points "
        f"({w['map']['size_m'][0]:.0f} x {w['map']['size_m'][1]:.0f} m, 1 m grid jittered by "
        f"{w['map']['jitter_m']} m), N = {w['particles']:,} particles spread over the floor, one "
        f"`tracker.wifi(obs)` per timing (interpolation of 200 fields, tempered capped log-likelihood, "
        f"normalisation, ESS, resampling, estimate), best of {w['repeat']}.",
        "",
        "| implementation | particle-APs/s | ns / particle (100 APs) | ms / update | CPU / wall | "
        "particle-APs per CPU-s |",
        "|---|---|---|---|---|---|",
    ]
    lines += _rate_rows(w["particle_aps_per_s"], w["cpu_seconds"], w["seconds"],
                        lambda name: f"{w['ns_per_particle'][name]:.0f} | {1e3 * w['seconds'][name]:.2f}")
    lines += [
        "", f"C++ / peer (1 thread): **{w['cpp_over_peer']:.1f}x**; goal 5e6 particle-APs/s: "
        f"{w['particle_aps_per_s'][CPP]:.3g}.", "",
        "Where the time goes: the same update with the particles sorted in space (rows of 1 m, then x) is "
        f"{w['seconds'][CPP] / w['seconds'][CPP + ', particles in spatial order']:.1f}x faster than in random "
        "order: the tracker locates each particle's triangle by walking from the previous particle's. The "
        "interpolation alone (the batch interpolator, which also computes the 200 gradients) costs "
        f"{1e3 * w['seconds']['interpolation alone (C++ batch, grid hint, with gradients)']:.1f} ms from its "
        "coarse grid hint and "
        f"{1e3 * w['seconds']['interpolation alone (C++ batch, previous-query hint, with gradients)']:.1f} ms "
        "from the previous query's triangle.", "",
        f"Same work: log-likelihood increment indoorloc {wc['log_likelihood_cpp']:.10g}, peer "
        f"{wc['log_likelihood_peer']:.10g} (relative difference {wc['log_likelihood_relative_difference']:.1e}); "
        f"per particle on {wc['per_particle_count']} particles: max relative difference "
        f"{wc['per_particle_max_relative_difference']:.1e}.",
    ]
    load = result["load_average_1min"]
    lines += ["", "Wall clock, best of the repetitions; CPU / wall is the process CPU time of that run over its wall "
              "time (below 1 for one thread: the process waited for a core); \"per CPU-s\" divides the work by that "
              "CPU time instead (one thread only): the speed with a core of its own, as far as the shared caches "
              f"allow. Load average (1 min) {load['before']:.1f} before, {load['after']:.1f} after, on "
              f"{load['cpus']} CPUs."]
    lines += ["", (
        "Against the machine (docs/performance.md): about 110 flops and 250 bytes per particle-step with the "
        "pillars (about 90 without a plan); one core's limit is about 5 ns (21 Gflop/s SSE2) or 10 ns if every "
        "byte came from memory. What bounds the loop now: the wall test's exact grid walk for the steps near an "
        "edge (about one in ten here) and its mispredicted branches (quarter blocks, masks, exact), the "
        "ziggurat's slow path (about 2.7 % of the normals) and the weights' scalar sums, not the hardware."
    )]
    return "\n".join(lines)
