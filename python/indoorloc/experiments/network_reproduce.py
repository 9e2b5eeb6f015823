"""NA (network adjustment, with and without cross-overs) against SSA (EKF + RTS smoother) on
simulated gravimetry flights (paper 003). ``indoorloc network reproduce`` and the demo part.

Every Monte Carlo run simulates a flight with seed ``seed + run`` (gravity field and sensor noise
both change), runs SSA, then NA from the SSA's smoothed states as initial values (NA's optimum
does not depend on them; they only save iterations), without and with XOVER. Cross-overs are
found on the SSA trajectory (5 m radius). Metrics against the simulator's truth:

- δg RMSE [mGal] over the survey-line epochs (straight lines, turns and hovers excluded) and
  over the cross-over epochs;
- accelerometer bias RMSE [mGal], gyro bias RMSE [deg/h], position [m] and velocity [m/s] RMSE
  over all epochs;
- run time [s]: SSA filter + smoother; NA: datum check + Ceres solve (the SSA that gives its
  initial values is not included).

With ``slow_stride`` > 1 two more rows solve NA and NA + XOVER with slow parameters (paper §4:
accelerometer bias, gyro bias and δg once per ``slow_stride`` IMU epochs, e.g. the IMU/GPS rate
ratio) on the same flights and cross-overs.
"""

from __future__ import annotations

import time
from dataclasses import asdict
from typing import Dict, List, Optional

import numpy as np

from indoorloc import network
from indoorloc.registry import DemoContext, DemoSection, register_demo
from indoorloc.simulate.flight import FlightConfig, simulate_flight, small_config

MGAL = 1e-5
DEG_PER_H = np.pi / 180.0 / 3600.0
METHODS = ("SSA (EKF + RTS)", "NA", "NA + XOVER")


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x)))) if x.size else float("nan")


def score(flight, state: Dict[str, np.ndarray], xover_epochs: np.ndarray) -> Dict[str, float]:
    t = flight.truth
    e_dg = state["gravity_disturbance_mps2"] - t["gravity_disturbance_mps2"]
    on_line = flight.line_id >= 0
    x_epochs = np.unique(xover_epochs.ravel()) if xover_epochs.size else np.zeros(0, int)
    return {
        "dg_rmse_line_mgal": _rms(e_dg[on_line]) / MGAL,
        "dg_rmse_xover_mgal": _rms(e_dg[x_epochs]) / MGAL,
        "acc_bias_rmse_mgal": _rms(state["acc_bias_mps2"] - t["acc_bias_mps2"]) / MGAL,
        "gyro_bias_rmse_degph": _rms(state["gyro_bias_radps"] - t["gyro_bias_radps"]) / DEG_PER_H,
        "position_rmse_m": _rms(state["position_m"] - t["position_m"]),
        "velocity_rmse_mps": _rms(state["velocity_mps"] - t["velocity_mps"]),
    }


def slow_methods(stride: int) -> tuple:
    """Row names of the slow-parameter NA rows."""
    return (f"NA, slow s={stride}", f"NA + XOVER, slow s={stride}")


def run_once(config: FlightConfig, seed: int, discretization: str = "trapezoidal",
             gravity_walk_mps2_rts: float = 2e-5, slow_stride: int = 1) -> Dict[str, object]:
    """One flight, three methods (five with ``slow_stride`` > 1). Returns {'flight', 'states',
    'scores', 'xover', 'summaries'}."""
    flight = simulate_flight(config, seed=seed)
    opts = network.flight_options(config, discretization=discretization, gravity_walk_mps2_rts=gravity_walk_mps2_rts)
    t0 = time.perf_counter()
    ssa, _, ssa_summary = network.smooth_flight(flight, opts, seed=seed)
    ssa_s = time.perf_counter() - t0
    pairs = network.find_crossovers(flight.imu_time_s, ssa["position_m"], radius_m=5.0, min_separation_s=30.0)
    states = {METHODS[0]: ssa}
    seconds = {METHODS[0]: ssa_s}
    summaries = {METHODS[0]: ssa_summary}
    runs = [(METHODS[1], False, opts), (METHODS[2], True, opts)]
    if slow_stride > 1:
        slow = network.flight_options(config, discretization=discretization,
                                      gravity_walk_mps2_rts=gravity_walk_mps2_rts, slow_parameter_stride=slow_stride)
        names = slow_methods(slow_stride)
        runs += [(names[0], False, slow), (names[1], True, slow)]
    for name, use, o in runs:
        st, summ = network.solve_network(network.flight_observations(flight, xover_epochs=pairs if use else None), ssa,
                                         options=o)
        states[name] = st
        seconds[name] = summ["seconds_datum_check"] + summ["seconds_solve"]
        summaries[name] = summ
    scores = {}
    for name, st in states.items():
        s = score(flight, st, pairs)
        s["seconds"] = seconds[name]
        scores[name] = s
    return {"flight": flight, "states": states, "scores": scores, "xover": pairs, "summaries": summaries}


def reproduce(config: Optional[FlightConfig] = None, runs: int = 3, seed: int = 0, discretization: str = "trapezoidal",
              gravity_walk_mps2_rts: float = 2e-5, slow_stride: int = 1) -> Dict[str, object]:
    """Monte Carlo over ``runs`` flights; per method and metric the list of values.
    ``slow_stride`` > 1 adds the slow-parameter NA rows (``0``: the IMU/GPS rate ratio)."""
    from indoorloc.progress import progress

    config = config or FlightConfig()
    if slow_stride == 0:
        slow_stride = int(round(config.imu_rate_hz / config.gps_rate_hz))
    if slow_stride < 1:
        raise ValueError("indoorloc: argument 'slow_stride': must be >= 0 (0: IMU rate / GPS rate, 1: no slow rows)")
    names = METHODS + (slow_methods(slow_stride) if slow_stride > 1 else ())
    per_method: Dict[str, Dict[str, List[float]]] = {m: {} for m in names}
    info = {"epochs": [], "gps": [], "xovers": [], "unknowns": [], "iterations": [], "unknowns_slow": [],
            "slow_nodes": [], "iterations_slow": []}
    for r in progress(range(runs), total=runs, desc="network runs"):
        out = run_once(config, seed + r, discretization, gravity_walk_mps2_rts, slow_stride)
        for m, s in out["scores"].items():
            for k, v in s.items():
                per_method[m].setdefault(k, []).append(v)
        info["epochs"].append(out["flight"].n_epochs)
        info["gps"].append(int(out["flight"].gps_time_s.size))
        info["xovers"].append(int(out["xover"].shape[0]))
        info["unknowns"].append(int(out["summaries"][METHODS[2]]["num_parameters"]))
        info["iterations"].append(int(out["summaries"][METHODS[2]]["iterations"]))
        if slow_stride > 1:
            summ = out["summaries"][slow_methods(slow_stride)[1]]
            info["unknowns_slow"].append(int(summ["num_parameters"]))
            info["slow_nodes"].append(int(summ["num_slow_nodes"]))
            info["iterations_slow"].append(int(summ["iterations"]))
    return {"config": asdict(config), "runs": runs, "seed": seed, "discretization": discretization,
            "gravity_walk_mps2_rts": gravity_walk_mps2_rts, "slow_stride": slow_stride, "methods": per_method,
            "info": info}


_COLUMNS = (("dg_rmse_line_mgal", "δg RMSE lines [mGal]", 2), ("dg_rmse_xover_mgal", "δg RMSE cross-overs [mGal]", 2),
            ("acc_bias_rmse_mgal", "acc bias RMSE [mGal]", 2), ("gyro_bias_rmse_degph", "gyro bias RMSE [deg/h]", 3),
            ("position_rmse_m", "position RMSE [m]", 4), ("velocity_rmse_mps", "velocity RMSE [m/s]", 5),
            ("seconds", "run time [s]", 2))


def markdown(results: Dict[str, object]) -> str:
    """Mean ± standard deviation over the runs, one row per method."""
    head = "| method | " + " | ".join(c[1] for c in _COLUMNS) + " |"
    lines = [head, "|" + "---|" * (len(_COLUMNS) + 1)]
    for m, metrics in results["methods"].items():
        cells = []
        for key, _, digits in _COLUMNS:
            v = np.asarray(metrics[key], float)
            cells.append(f"{v.mean():.{digits}f} ± {v.std(ddof=1) if v.size > 1 else 0.0:.{digits}f}")
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    info = results["info"]
    lines.append("")
    lines.append(f"{results['runs']} flights (seeds {results['seed']}..{results['seed'] + results['runs'] - 1}), "
                 f"{results['discretization']} rule, {np.mean(info['epochs']):.0f} epochs "
                 f"({np.mean(info['unknowns']):.0f} unknowns), {np.mean(info['xovers']):.1f} cross-overs per flight, "
                 f"NA + XOVER iterations {np.mean(info['iterations']):.1f}; mean ± sd over flights.")
    if info.get("unknowns_slow"):
        n, m = np.mean(info["epochs"]), np.mean(info["slow_nodes"])
        g = np.mean(info["gps"])
        lines.append("")
        lines.append(f"Slow parameters (s = {results['slow_stride']} IMU epochs): {np.mean(info['unknowns_slow']):.0f} "
                     f"unknowns = 9 N + 7 M with M = {m:.0f} slow nodes, against {np.mean(info['unknowns']):.0f} = 16 N "
                     f"({np.mean(info['unknowns_slow']) / np.mean(info['unknowns']):.3f}); the paper's count with a "
                     f"3-vector δg, 9 N_IMU + 9 N_GPS = {9 * n + 9 * g:.0f} against 18 N_IMU = {18 * n:.0f} "
                     f"({(9 * n + 9 * g) / (18 * n):.3f}). NA + XOVER iterations (slow) "
                     f"{np.mean(info['iterations_slow']):.1f}.")
    return "\n".join(lines)


@register_demo("network", "network: gravity disturbance from a simulated flight, NA vs SSA (paper 003)")
def demo(ctx: DemoContext) -> DemoSection:
    from indoorloc import plots

    out = run_once(small_config(), seed=ctx.seed)
    flight = out["flight"]
    line = 1
    m = flight.line_id == line
    x = flight.truth["position_m"][m, 0]
    series = {name: st["gravity_disturbance_mps2"][m] / MGAL for name, st in out["states"].items()}
    fig = plots.network_gravity_line(x, flight.truth["gravity_disturbance_mps2"][m] / MGAL, series,
                                     ctx.figure_path("network_gravity_line"))
    res = {"runs": 1, "seed": ctx.seed, "discretization": "trapezoidal",
           "methods": {k: {kk: [vv] for kk, vv in v.items()} for k, v in out["scores"].items()},
           "info": {"epochs": [flight.n_epochs], "xovers": [int(out["xover"].shape[0])],
                    "unknowns": [int(out["summaries"][METHODS[2]]["num_parameters"])],
                    "iterations": [int(out["summaries"][METHODS[2]]["iterations"])]}}
    text = ("One small simulated flight (3 East-West lines + 2 cross lines, 50 Hz IMU, 1 Hz GPS). "
            "Gravity disturbance along line 1: truth, SSA (EKF + RTS smoother), NA without and with "
            "cross-over ties.\n\n" + markdown(res) + "\n\nMonte Carlo comparison: `indoorloc network reproduce`.")
    return DemoSection(markdown=text, figures=[fig])


# ---------------------------------------------------------------------------------------------
# `indoorloc reproduce`, paper 003

#: Paper 003 Table 2: (name, IMU rate [Hz], duration [s], GPS rate [Hz], N*_eq, N_par, rule, method).
#: Case 3 (200 Hz x 14,400 s, 5 Hz GPS) is solved with method "qr": the streaming Householder QR
#: of the whitened observation equations (square-root information form), not the Cholesky of the
#: normal equations. Why (measured 2026-11-26, docs/network_scale.md "Case 3"): the heading error
#: ψ_z is tied to the data only through the small horizontal specific force, and the normal
#: equations square the condition of that mode. With the Cholesky (trapezoidal, 5 Hz GPS) the
#: error of ψ_z at the last epoch grows from 4e-5 (600 s) to 8e-4 (1800 s), and from 3,600 s on the
#: Schur complement of the middle block is no longer positive definite (round-off, not a datum
#: defect: its smallest true relative pivot there is 5e-11); the full case failed in the bottom
#: chain at block 1,837,575. Lowering the rank tolerance does not help (the Cholesky itself breaks
#: down), nor does any diagonal scaling (Cholesky is invariant to it). The QR keeps the square
#: root of the condition: max error 2.4e-9 at 1 h; case 3 in 119 s on one thread, 0.24 GiB, max
#: error 4.1e-9 (ψ_z), δg RMSE 3e-14 m/s². With leap-frog the 5 Hz GPS alternates parity
#: (GpsEpoch), so both chains have a datum; its Cholesky fails for the same round-off reason at the
#: middle block, and the leap-frog QR solves case 3 too (393 s, max error 3.0e-8). Cases 1 and 2
#: stay on the (3.3x faster, two-thread) Cholesky: their δg are exact, but case 1's ψ_z carries a
#: 1.2e-2 round-off error there (QR: 5.2e-8 in 318 s).
PAPER_TABLE2 = (
    ("case 1 (Applanix)", 200.0, 10_800.0, 1.0, 38_912_400, 38_880_000, "leapfrog", "cholesky"),
    ("case 2 (CASI)", 50.0, 14_400.0, 1.0, 13_033_200, 12_960_000, "leapfrog", "cholesky"),
    ("case 3 (GeoMobil)", 200.0, 14_400.0, 5.0, 52_056_000, 51_840_000, "trapezoidal", "qr"),
)
#: Case 4 (Rockies'95): 565,050 epochs at 50 Hz, 2 Hz GPS, 332,150 cross-overs, 1,907 GUPT.
PAPER_CASE4 = dict(imu_rate_hz=50.0, duration_s=565049.0 / 50.0, gps_rate_hz=2.0, num_ties=332150, num_gupts=1907)
PAPER_CASE4_SIZES = (10_572_763, 10_170_900)  # N*_eq, N_par
FULL_FLIGHTS = 10
SLOW_STRIDE = 50  # the default flight's IMU / GPS rate ratio (paper §4: slow parameters at the GPS rate)
_METRICS = (("dg_rmse_line_mgal", "δg RMSE on the lines", "mGal"),
            ("dg_rmse_xover_mgal", "δg RMSE at the cross-overs", "mGal"),
            ("position_rmse_m", "position RMSE", "m"),
            ("seconds", "run time", "s"))

_SCALE_CHILD = """
import json
import numpy as np
from indoorloc import network
from indoorloc._core import network as core_network
kind, args = {kind!r}, {args!r}
if kind == "linear":
    method = args.pop("method", "cholesky")
    r = core_network.solve_linear_ins_network(core_network.LinearInsNetworkOptions(**args), gravity_covariance=True,
                                              checkpoint_interval=2048, num_threads={threads}, method=method)
else:
    r = network.solve_repeated_pass_network(**args, checkpoint_interval=2048, num_threads={threads})
sigma = np.asarray(r.gravity_sigma)
out = {{k: v for k, v in r.to_dict().items() if isinstance(v, (int, float, str))}}
out["sigma_count"] = int(np.isfinite(sigma).sum())
hwm = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")][0].split()[1]
out["peak_rss_gib"] = int(hwm) / 2**20
print(json.dumps(out))
"""


def tiny_config() -> "FlightConfig":
    """A flight of well under a minute at 25 Hz: the reproduce section's smoke test (--quick)."""
    from indoorloc.simulate.flight import small_config

    return small_config(line_length_m=600.0, n_lines=2, turn_radius_m=150.0, cross_margin_m=150.0, imu_rate_hz=25.0)


def flight_task(params, seed: int, slow_stride: int = SLOW_STRIDE, small: bool = False) -> Dict[str, float]:
    """One Monte Carlo flight for ``indoorloc.sweep`` (its seed is the experiment's ``seed + run``,
    given as the ``flight_seed`` parameter, so that a cluster run equals the in-process run).
    Returns ``"<method>|<metric>"`` -> value."""
    from indoorloc.simulate.flight import FlightConfig

    out = run_once(tiny_config() if small else FlightConfig(), int(params["flight_seed"]), slow_stride=slow_stride)
    return {f"{m}|{k}": float(v) for m, s in out["scores"].items() for k, v in s.items()}


def flight_runs(seeds, slow_stride: int = SLOW_STRIDE, small: bool = False, scheduler=None) -> list:
    """:func:`flight_task` for every seed, in process or (``scheduler``) as Dask tasks through
    ``indoorloc.sweep.run_sweep``; the same list of per-flight dicts either way."""
    from indoorloc.progress import progress

    if scheduler is None:
        return [flight_task({"flight_seed": s}, s, slow_stride, small)
                for s in progress(seeds, total=len(seeds), desc="network flights")]
    from indoorloc import sweep

    res = sweep.run_sweep(flight_task, {"flight_seed": list(seeds)}, scheduler=scheduler,
                          shared={"slow_stride": slow_stride, "small": small})
    if res.failed:
        raise RuntimeError(f"indoorloc: network flights failed on the cluster: {res.failed[:3]}")
    return [{k: v for k, v in row.items() if "|" in k} for row in res.rows]


def _scale_case(kind: str, args: Dict[str, float], threads: int) -> Dict[str, object]:
    """Solve one Table 2 case in a child process (its own peak memory, VmHWM)."""
    import json
    import subprocess
    import sys

    code = _SCALE_CHILD.format(kind=kind, args=args, threads=threads if threads > 0 else 2)
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"indoorloc: Table 2 {kind} network {args} failed: {proc.stderr.strip()[-400:]}")
    row = json.loads(proc.stdout.strip().splitlines()[-1])
    row["wall_seconds"] = time.perf_counter() - start
    return row


def expected_seconds(runs: Optional[int]) -> float:
    """Full-size run time on 2 cores [s]: ~25 s per flight (SSA, NA, NA + XOVER, two slow rows)
    and ~5 min for the four Table 2 cases (case 3's QR alone about 2 min on one thread)."""
    return 25.0 * (runs or FULL_FLIGHTS) + 300.0


def reproduce_tables(ctx) -> list:
    """Paper 003 for ``indoorloc reproduce``: NA vs SSA with and without XOVER (and slow
    parameters, §4) over Monte Carlo flights, and the Table 2 cases solved at full size."""
    from indoorloc.experiments.reproduce_cells import Cell, Table
    from indoorloc.simulate.flight import FlightConfig

    runs = ctx.runs_or(FULL_FLIGHTS)
    seeds = [ctx.seed + r for r in range(runs)]
    slow_stride = 5 if ctx.quick else SLOW_STRIDE
    start = time.perf_counter()
    per_run = flight_runs(seeds, slow_stride, bool(ctx.quick), ctx.scheduler)
    ctx.log(f"paper 003: {runs} flights (SSA, NA, NA + XOVER, slow s = {slow_stride}) in {time.perf_counter() - start:.0f} s")
    config = tiny_config() if ctx.quick else FlightConfig()
    methods = METHODS + slow_methods(slow_stride)
    mc = Table("003", "§3-4 NA vs SSA", "network adjustment (with and without cross-overs, slow parameters) "
               "against the Kalman smoother on simulated flights")
    for m in methods:
        for key, label, unit in _METRICS:
            mc.cells.append(Cell(m, label, [r[f"{m}|{key}"] for r in per_run], seeds, None, unit))
    mc.setup = (
        f"{runs} simulated gravimetry flights (seeds {seeds[0]}..{seeds[-1]}; gravity field and sensor noise "
        f"change with the seed): {'a tiny smoke-test flight' if ctx.quick else 'the default flight'} "
        f"({config.imu_rate_hz:g} Hz IMU, {config.gps_rate_hz:g} Hz GPS; docs/network.md). SSA = EKF + RTS smoother; "
        "NA = the network solved by Ceres from the SSA states; XOVER = cross-overs found on the SSA track (5 m "
        f"radius, 30 s apart); slow = biases and δg once per {slow_stride} IMU epochs (paper §4). The paper reports "
        "no accuracy figures: it argues that NA equals SSA on the same model and can add cross-overs, which a "
        "filter cannot use. Run time: NA = datum check + solve (the SSA that gives its initial values excluded)."
    )
    # Table 2: the network sizes of the paper's operational cases, solved by the streaming
    # block-tridiagonal Cholesky with every δg variance (docs/network_scale.md).
    t2 = Table("003", "Table 2", "the operational network sizes, solved at full size with every δg variance")
    cases = [(n, "linear", dict(imu_rate_hz=r, duration_s=d, gps_rate_hz=g, rule=rule, method=method), eq, par)
             for n, r, d, g, eq, par, rule, method in PAPER_TABLE2]
    cases.append(("case 4 (Rockies'95, 332,150 cross-overs)", "repeated", dict(PAPER_CASE4), *PAPER_CASE4_SIZES))
    if ctx.quick:  # the same solvers on two-minute networks
        cases = [(f"{n} at 2 min", k, {**a, "duration_s": 120.0, **({"num_ties": 1000, "num_gupts": 10} if k == "repeated" else {})},
                  None, None) for n, k, a, _, _ in cases[1:4:2]]
    for name, kind, args, paper_eq, paper_par in cases:
        try:
            row = _scale_case(kind, args, ctx.threads)
        except RuntimeError as exc:
            # A case the solver refuses is a result too: reported in its row, not hidden.
            reason = str(exc).split("RuntimeError: ")[-1].strip()
            ctx.log(f"paper 003: Table 2 {name} not solved: {reason}")
            t2.cells += [Cell(name, "unknowns N_par", [float("nan")], [0], paper_par, "", f"not solved: {reason}"),
                         Cell(name, "equations N*_eq", [float("nan")], [0], paper_eq, "")]
            continue
        ctx.log(f"paper 003: Table 2 {name}: {row['unknowns']:,} unknowns in {row['wall_seconds']:.0f} s, "
                f"{row['peak_rss_gib']:.2f} GiB")
        note = (f"{args['rule']} rule, {args['method']} ({'Householder QR of the observation equations' if args['method'] == 'qr' else 'normal-equation Cholesky'}); "
                "18 unknowns per IMU epoch (the paper's), equations without the "
                "alignment/GUPT extras the paper lists as N_al" if kind == "linear" else
                "the flight re-flown in reverse over its own track; ties on the vertical δg")
        t2.cells += [
            Cell(name, "unknowns N_par", [row["unknowns"]], [0], paper_par, "", note),
            Cell(name, "equations N*_eq", [row["equations"]], [0], paper_eq, ""),
            Cell(name, "solve with every δg variance", [row["wall_seconds"]], [0], None, "s",
                 ("1 thread (the QR runs one way)" if args.get("method") == "qr" else
                  f"{max(1, ctx.threads) if ctx.threads else 2} threads") +
                 ", child process, checkpoint every 2048 blocks"),
            Cell(name, "peak memory", [row["peak_rss_gib"]], [0], None, "GiB"),
            Cell(name, "largest error of any unknown vs the noise-free truth", [row["max_abs_error"]], [0], None, ""),
        ]
    t2.setup = (
        "Each case is the linearised strapdown INS/GPS network of the paper's size (IMU rate x duration, GPS "
        "rate; case 4 with its cross-overs and GUPTs), noise-free, solved once in its own process (sizes are "
        "deterministic: one run, so no spread). The paper gives sizes only; the point is that the network "
        "fits in bounded memory and solves in minutes on 2 cores. The paper's case-2 30,000 cross-overs are "
        "not in the case-2 network here."
    )
    return [mc, t2]
