"""Network adjustment (paper 003) scale: time and peak memory of NA vs SSA against network size.

Simulated flights of the default pattern (3 East-West lines + 2 cross lines, 50 Hz IMU, 1 Hz GPS)
with longer lines give networks of increasing size. Each size runs in its own Python process so
that the peak resident memory (ru_maxrss) belongs to that size alone: simulate, SSA (EKF + RTS
smoother, which also gives the NA's initial values), NA + XOVER (datum check + Ceres
SPARSE_NORMAL_CHOLESKY with SuiteSparse). The equation count is checked against the paper's
Table 2 formula adapted to a scalar δg: N_eq* = 16 N_IMU + 3 N_GPS (the paper's 18 counts a
3-vector δg), plus ZUPT, GUPT and XOVER rows. No peer (GTSAM, Ceres defaults) is timed yet.
Usage: python benchmarks/bench_network.py [--quick]
"""

from __future__ import annotations

import json
import subprocess
import sys
from typing import Dict, List

_CHILD = r"""
import json, resource, sys, time
import numpy as np
from indoorloc import network
from indoorloc.simulate.flight import FlightConfig, simulate_flight
line = float(sys.argv[1])
c = FlightConfig(line_length_m=line)
t = time.perf_counter(); fl = simulate_flight(c, seed=0); t_sim = time.perf_counter() - t
o = network.flight_options(c)
t = time.perf_counter(); ssa, _, _ = network.smooth_flight(fl, o); t_ssa = time.perf_counter() - t
t = time.perf_counter(); st, s, pairs = network.solve_flight(fl, o, xover=True, initial=ssa); t_na = time.perf_counter() - t
n_imu, n_gps = fl.n_epochs, fl.gps_time_s.size
static = 3 * fl.zupt_epochs.size + fl.gupt_epochs.size + pairs.shape[0]
print(json.dumps(dict(line_length_m=line, epochs=n_imu, gps=n_gps, xovers=int(pairs.shape[0]),
    unknowns=int(s["num_parameters"]), residuals=int(s["num_residuals"]),
    residuals_formula=int(16 * (n_imu - 1) + 3 * n_gps + static),
    seconds_simulate=t_sim, seconds_ssa=t_ssa, seconds_na=t_na, seconds_na_solve=s["seconds_solve"],
    seconds_datum_check=s["seconds_datum_check"], iterations=int(s["iterations"]),
    peak_rss_gib=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20)))
"""


def run(quick: bool = False) -> Dict[str, object]:
    lines = [1500.0, 3000.0] if quick else [1500.0, 3000.0, 6000.0, 12000.0]
    rows: List[dict] = []
    for line in lines:
        out = subprocess.run([sys.executable, "-c", _CHILD, str(line)], check=True, capture_output=True, text=True)
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
    return {"title": "network: NA (Ceres) vs SSA (EKF + RTS) against network size", "rows": rows}


def markdown(result: Dict[str, object]) -> str:
    head = ("| line [m] | epochs | unknowns | residuals (formula) | cross-overs | SSA [s] | NA datum check [s] | "
            "NA solve [s] | NA iterations | peak RSS [GiB] |")
    out = [head, "|" + "---|" * 10]
    for r in result["rows"]:
        out.append(f"| {r['line_length_m']:.0f} | {r['epochs']} | {r['unknowns']} | {r['residuals']} "
                   f"({r['residuals_formula']}) | {r['xovers']} | {r['seconds_ssa']:.2f} | "
                   f"{r['seconds_datum_check']:.2f} | {r['seconds_na_solve']:.2f} | {r['iterations']} | "
                   f"{r['peak_rss_gib']:.2f} |")
    return "\n".join(out)


if __name__ == "__main__":
    res = run(quick="--quick" in sys.argv)
    print(markdown(res))
