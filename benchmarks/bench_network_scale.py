"""Network adjustment at scale (paper 003, Table 2): the streaming block-tridiagonal solver.

The linearised strapdown INS/GPS network (18 unknowns per IMU epoch, leap-frog dynamic
equations, CUPT at 1 Hz, alignment prior, GUPT at the end; indoorloc/network/linear_ins_network.h)
is solved

1. against peers in the same run on the same equations at sizes they handle: GTSAM's linear
   factor graph (``graph.optimize()``, default multifrontal Cholesky with COLAMD, which declares
   the network indeterminate from 30k epochs, and multifrontal QR with COLAMD, which solves it
   at every size), Ceres
   (``indoorloc._core.network.solve_linear_ins_network_ceres``: the same equations as Ceres
   residual blocks, SPARSE_NORMAL_CHOLESKY with SuiteSparse, once with Ceres' default
   Solver::Options and once as a single Gauss-Newton step, its best case on a linear problem) and
   scipy (normal equations, SuperLU with COLAMD) - all return the same solution (checked);
2. at the paper's Table 2 sizes (case 2: 50 Hz x 14,400 s, 12.96 M unknowns; case 1: 200 Hz x
   10,800 s, 38.9 M unknowns) with the covariances of every δg (selected inversion), each case in
   a child process so that its peak memory (VmHWM) is its own.

3. Table 2 case 4 (Rockies'95: 50 Hz x 11,301 s, 2 Hz GPS, 332,150 cross-overs, 1,907 GUPT) at
   full size, the cross-overs laid out as repeated passes (the flight re-flown in reverse over its
   own track) and solved exactly in the folded band order (indoorloc/network/folded_network.h).

indoorloc runs on one thread in the peer comparison (as the peers' defaults do) and also on both
cores (``num_threads=2``: the twisted order eliminates the two halves of the band as two chains
meeting in the middle, bit-identical results); Table 2 cases run on ``TABLE2_THREADS``.

Usage: python benchmarks/bench_network_scale.py [--quick] [--case 4]   (also run by benchmarks/run.py)
  --case 4 runs case 4 alone and merges it into the existing results/bench_network_scale.json;
  the standard deviation of every δg is written to results/bench_network_scale_case4_sigma.npy
  (E x 3, m/s², not committed: 13.6 MB).
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict, List

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import network_peers  # noqa: E402

# 50 Hz (the paper's case 2 rate). From about 120 s of flight GTSAM's elimination declares this
# network "indeterminate" (IndeterminateLinearSystemException; our per-unknown relative pivot is
# 3e-7 there, 7e-12 at 4 h), so the speed comparison uses the sizes where it works and the
# larger ones record its failure.
RATE_HZ = 50.0
PEER_DURATIONS_S = (20.0, 60.0, 90.0, 600.0, 2400.0)
SCIPY_MAX_DURATION_S = 600.0
CERES_MAX_DURATION_S = 2400.0
TABLE2_CASES = (
    ("case 2", 50.0, 14_400.0),
    ("case 1", 200.0, 10_800.0),
)
CHECKPOINT_INTERVAL = 2048
TABLE2_THREADS = 2  # this machine's cores
# Case 4: 565,049 intervals at 50 Hz = 565,050 epochs (the paper's 50 Hz x 11,301 s).
CASE4 = dict(imu_rate_hz=50.0, duration_s=565049.0 / 50.0, gps_rate_hz=2.0, num_ties=332150, num_gupts=1907)
PAPER_CASE4 = dict(imu_epochs=565050, gps_epochs=22602, gupts=1907, ties=332150, equations=10572763, unknowns=10170900)

_CHILD4 = """
import json, sys
import numpy as np
from indoorloc import network
r = network.solve_repeated_pass_network(**{case}, checkpoint_interval={interval}, num_threads={threads})
sig = r.gravity_sigma
np.save({sigma_path!r}, sig)
out = {{k: v for k, v in r.to_dict().items() if k not in ("gravity_sigma", "gravity_estimate")}}
out["gravity_sigma_mgal"] = {{
    axis: dict(min=float(sig[:, c].min() * 1e5), median=float(np.median(sig[:, c]) * 1e5), max=float(sig[:, c].max() * 1e5))
    for c, axis in enumerate(("x", "y", "z"))}}
out["gravity_sigma_count"] = int(np.isfinite(sig).sum())
hwm = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")][0].split()[1]
out["peak_rss_gib"] = int(hwm) / 2**20
print(json.dumps(out))
"""

_CHILD = """
import json, sys
from indoorloc._core import network
r = network.solve_linear_ins_network(network.LinearInsNetworkOptions(imu_rate_hz={rate}, duration_s={duration}),
                                     gravity_covariance=True, checkpoint_interval={interval}, num_threads={threads})
out = {{k: v for k, v in r.to_dict().items() if k not in ("gravity_sigma", "gravity_estimate")}}
out["gravity_sigma_median_mgal"] = float(__import__("numpy").median(r.gravity_sigma) * 1e5)
# VmHWM: this process's own peak (ru_maxrss would inherit the parent's peak across fork + exec).
hwm = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")][0].split()[1]
out["peak_rss_gib"] = int(hwm) / 2**20
print(json.dumps(out))
"""


def _peer_rows(durations) -> List[Dict[str, object]]:
    from indoorloc._core import network

    rows = []
    # Warm-up (first call pays page faults and lazy initialisation), so the first row compares like with like.
    first = network.LinearInsNetworkOptions(imu_rate_hz=RATE_HZ, duration_s=durations[0])
    network.solve_linear_ins_network(first, gravity_covariance=False)
    network.solve_linear_ins_network_ceres(first, one_gauss_newton_step=True)
    for duration in durations:
        net = network.LinearInsNetworkOptions(imu_rate_hz=RATE_HZ, duration_s=duration)
        eq = network.linear_ins_equations(net)
        E = int(eq.imu_epochs)
        row: Dict[str, object] = {"duration_s": duration, "epochs": E, "unknowns": 18 * E}
        start = time.perf_counter()
        ours = network.solve_linear_ins_network(net, gravity_covariance=False, keep_gravity_estimate=True)
        row["indoorloc_seconds"] = time.perf_counter() - start
        start = time.perf_counter()
        two = network.solve_linear_ins_network(net, gravity_covariance=False, keep_gravity_estimate=True,
                                               num_threads=2)
        row["indoorloc_2threads_seconds"] = time.perf_counter() - start
        assert np.array_equal(two.gravity_estimate, ours.gravity_estimate), "thread count changed the result"
        start = time.perf_counter()
        network.solve_linear_ins_network(net, gravity_covariance=True)
        row["indoorloc_with_covariance_seconds"] = time.perf_counter() - start
        try:
            g = network_peers.solve_gtsam(eq)
        except RuntimeError as exc:  # gtsam.IndeterminateLinearSystemException and kin
            g = None
            row["gtsam_error"] = str(exc).strip().splitlines()[0][:200]
        if g is not None:
            row["gtsam_seconds"] = g["assemble_seconds"] + g["solve_seconds"]
            row["gtsam_solve_seconds"] = g["solve_seconds"]
            row["gtsam_max_dg_diff"] = float(np.abs(g["x"].reshape(E, 18)[:, 15:] - ours.gravity_estimate).max())
        # GTSAM's QR elimination: not its default, but the one that solves this network at every size.
        gq = network_peers.solve_gtsam(eq, qr=True)
        if gq is not None:
            row["gtsam_qr_seconds"] = gq["assemble_seconds"] + gq["solve_seconds"]
            row["gtsam_qr_max_dg_diff"] = float(np.abs(gq["x"].reshape(E, 18)[:, 15:] - ours.gravity_estimate).max())
        if duration <= CERES_MAX_DURATION_S:
            for key, one_step in (("ceres", False), ("ceres_one_step", True)):
                c = network.solve_linear_ins_network_ceres(net, one_gauss_newton_step=one_step)
                row[f"{key}_seconds"] = c.build_seconds + c.solve_seconds
                row[f"{key}_iterations"] = c.iterations
                row[f"{key}_max_dg_diff"] = float(np.abs(c.x[:, 15:] - ours.gravity_estimate).max())
        if duration <= SCIPY_MAX_DURATION_S:
            s = network_peers.solve_scipy(eq)
            row["scipy_seconds"] = s["assemble_seconds"] + s["solve_seconds"]
            row["scipy_solve_seconds"] = s["solve_seconds"]
            row["scipy_max_dg_diff"] = float(np.abs(s["x"].reshape(E, 18)[:, 15:] - ours.gravity_estimate).max())
        rows.append(row)
    return rows


def _table2_rows(cases) -> List[Dict[str, object]]:
    rows = []
    for name, rate, duration in cases:
        code = _CHILD.format(rate=rate, duration=duration, interval=CHECKPOINT_INTERVAL, threads=TABLE2_THREADS)
        start = time.perf_counter()
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
        wall = time.perf_counter() - start
        if proc.returncode != 0:
            rows.append({"case": name, "rate_hz": rate, "duration_s": duration, "error": proc.stderr.strip()[-500:]})
            continue
        row = json.loads(proc.stdout.strip().splitlines()[-1])
        row.update({"case": name, "rate_hz": rate, "duration_s": duration, "wall_seconds": wall})
        rows.append(row)
    return rows


def _case4_row() -> Dict[str, object]:
    sigma_path = str(HERE / "results" / "bench_network_scale_case4_sigma.npy")
    (HERE / "results").mkdir(exist_ok=True)
    code = _CHILD4.format(case=CASE4, interval=CHECKPOINT_INTERVAL, sigma_path=sigma_path, threads=TABLE2_THREADS)
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        return {"case": "case 4", "error": proc.stderr.strip()[-500:]}
    row = json.loads(proc.stdout.strip().splitlines()[-1])
    row.update({"case": "case 4", "wall_seconds": wall, "paper": PAPER_CASE4, "threads": TABLE2_THREADS, **CASE4})
    return row


def run(quick: bool = False) -> dict:
    durations = PEER_DURATIONS_S[:2] if quick else PEER_DURATIONS_S
    cases = TABLE2_CASES[:1] if quick else TABLE2_CASES
    return {
        "title": "INS/GPS network adjustment at scale (paper 003, Table 2)",
        "peers": _peer_rows(durations),
        "table2": _table2_rows(cases),
        "case4": None if quick else _case4_row(),
        "checkpoint_interval": CHECKPOINT_INTERVAL,
        "threads": TABLE2_THREADS,
        "gtsam": network_peers.gtsam_available(),
    }


def markdown(result: dict) -> str:
    lines = [
        f"Same linearised network (18 unknowns per epoch, leap-frog, {RATE_HZ:.0f} Hz IMU, 1 Hz GPS), same run; "
        "indoorloc solve on one thread without / with the covariances of every δg, and on two threads; ratios are "
        "against indoorloc on one thread (on two in brackets); peers' times include building their problem "
        "(Ceres default: its default Solver::Options, LM from x = 0; Ceres 1 step: one Gauss-Newton step, exact here):",
        "",
        "| IMU epochs | unknowns | indoorloc [s] | + δg covariances [s] | 2 threads [s] | GTSAM [s] (solve only) | GTSAM / indoorloc | "
        "GTSAM QR [s] | GTSAM QR / indoorloc | "
        "Ceres default [s] (iterations) | Ceres / indoorloc | Ceres 1 step [s] | Ceres 1 step / indoorloc | "
        "scipy SuperLU [s] | max δg diff vs GTSAM, GTSAM QR, Ceres, scipy [m/s²] |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in result["peers"]:
        g = r.get("gtsam_seconds")
        s = r.get("scipy_seconds")
        c = r.get("ceres_seconds")
        c1 = r.get("ceres_one_step_seconds")
        t = r["indoorloc_seconds"]
        t2 = r.get("indoorloc_2threads_seconds", float("nan"))
        lines.append(
            f"| {r['epochs']:,} | {r['unknowns']:,} | {t:.3f} | {r['indoorloc_with_covariance_seconds']:.3f} | {t2:.3f} | "
            + (f"{g:.3f} ({r['gtsam_solve_seconds']:.3f}) | {g / t:.1f}x ({g / t2:.1f}x) | " if g
               else ("fails: indeterminate | - | " if "gtsam_error" in r else "- | - | "))
            + (f"{r['gtsam_qr_seconds']:.3f} | {r['gtsam_qr_seconds'] / t:.1f}x ({r['gtsam_qr_seconds'] / t2:.1f}x) | "
               if "gtsam_qr_seconds" in r else "- | - | ")
            + (f"{c:.3f} ({r['ceres_iterations']}) | {c / t:.0f}x ({c / t2:.0f}x) | {c1:.3f} | {c1 / t:.1f}x ({c1 / t2:.1f}x) | "
               if c else "- | - | - | - | ")
            + (f"{s:.3f} | " if s else "- | ")
            + f"{r.get('gtsam_max_dg_diff', float('nan')):.1e}, {r.get('gtsam_qr_max_dg_diff', float('nan')):.1e}, "
            f"{r.get('ceres_max_dg_diff', float('nan')):.1e}, "
            f"{r.get('scipy_max_dg_diff', float('nan')):.1e} |"
        )
    lines += [
        "",
        f"Paper Table 2 sizes, leap-frog, with the covariances of every δg (checkpoint every "
        f"{result['checkpoint_interval']} blocks), {result.get('threads', 1)} thread(s), one child process per case:",
        "",
        "| case | IMU | unknowns | equations | factor [s] | backward + selected inversion [s] | total [s] | peak memory [GiB] | max error vs truth |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in result["table2"]:
        if "error" in r:
            lines.append(f"| {r['case']} | {r['rate_hz']:.0f} Hz x {r['duration_s']:.0f} s | failed: {r['error']} |||||||")
            continue
        lines.append(
            f"| {r['case']} | {r['rate_hz']:.0f} Hz x {r['duration_s']:.0f} s | {r['unknowns']:,} | {r['equations']:,} | "
            f"{r['factor_seconds']:.1f} | {r['backward_seconds']:.1f} | {r['total_seconds']:.1f} | {r['peak_rss_gib']:.2f} | "
            f"{r['max_abs_error']:.1e} |"
        )
    c4 = result.get("case4")
    if c4:
        lines += [
            "",
            "Table 2 case 4 (Rockies'95) with all its cross-overs: the flight re-flown in reverse over its own track, "
            "scalar δg ties between the passes and GUPTs, solved exactly in the folded band order (blocks of 72), "
            f"with the standard deviation of every δg (checkpoint every {result['checkpoint_interval']} blocks, "
            f"{c4.get('threads', 1)} thread(s)):",
            "",
        ]
        if "error" in c4:
            lines.append(f"case 4 failed: {c4['error']}")
        else:
            p = c4["paper"]
            sg = c4["gravity_sigma_mgal"]
            lines += [
                "| case | IMU epochs | GPS | XOVER | GUPT | unknowns | equations (paper N*_eq) | factor [s] | backward + selected inversion [s] | total [s] | peak memory [GiB] (VmHWM) | max error vs truth | δg RMSE [m/s²] | σ(δg_z) min / median / max [mGal] |",
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
                f"| case 4 | {c4['imu_epochs']:,} ({p['imu_epochs']:,}) | {c4['gps_epochs']:,} ({p['gps_epochs']:,}) | "
                f"{c4['ties']:,} ({p['ties']:,}) | {c4['gupts']:,} ({p['gupts']:,}) | {c4['unknowns']:,} ({p['unknowns']:,}) | "
                f"{c4['equations']:,} ({p['equations']:,}) | {c4['factor_seconds']:.1f} | {c4['backward_seconds']:.1f} | "
                f"{c4['total_seconds']:.1f} | {c4['peak_rss_gib']:.2f} | {c4['max_abs_error']:.1e} | "
                f"{c4['gravity_rmse']:.1e} | {sg['z']['min']:.3f} / {sg['z']['median']:.3f} / {sg['z']['max']:.3f} |",
                "",
                f"σ(δg_x), σ(δg_y) median: {sg['x']['median']:.1f}, {sg['y']['median']:.1f} mGal (no tie or GUPT on the "
                f"horizontal components); {c4['gravity_sigma_count']:,} standard deviations computed; "
                f"{c4['folded_blocks']:,} blocks of {c4['folded_block_size']}, min relative pivot {c4['min_relative_pivot']:.1e}.",
            ]
    return "\n".join(lines)


if __name__ == "__main__":
    quick = "--quick" in sys.argv
    out = HERE / "results"
    out.mkdir(exist_ok=True)
    if "--case" in sys.argv:
        which = sys.argv[sys.argv.index("--case") + 1]
        if which != "4":
            sys.exit("--case: only 4 runs alone (cases 1 and 2 run in the full benchmark)")
        previous = out / "bench_network_scale.json"
        res = json.loads(previous.read_text()) if previous.exists() else {"peers": [], "table2": [],
                                                                           "checkpoint_interval": CHECKPOINT_INTERVAL}
        res["case4"] = _case4_row()
    else:
        res = run(quick=quick)
    (out / "bench_network_scale.json").write_text(json.dumps(res, indent=2))
    (out / "bench_network_scale.md").write_text(markdown(res) + "\n")
    print(markdown(res))
