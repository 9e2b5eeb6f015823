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
        st, summ = network.solve_network(
            imu_time_s=flight.imu_time_s, acc_body_mps2=flight.acc_body_mps2, gyro_body_radps=flight.gyro_body_radps,
            gps_time_s=flight.gps_time_s, gps_position_m=flight.gps_position_m, initial=ssa,
            zupt_epochs=flight.zupt_epochs, gupt_epochs=flight.gupt_epochs, gupt_gravity_mps2=flight.gupt_gravity_mps2,
            xover_epochs=pairs if (use and pairs.size) else None, options=o)
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
