"""`indoorloc network ...` subcommands (paper 003)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from indoorloc.io.atomic_file import write_text_atomic


def cmd_reproduce(args: argparse.Namespace) -> int:
    from indoorloc.experiments import network_reproduce as nr
    from indoorloc.simulate.flight import FlightConfig, small_config

    config = small_config() if args.small else FlightConfig()
    if args.imu_rate is not None:
        config.imu_rate_hz = args.imu_rate
    results = nr.reproduce(config, runs=args.runs, seed=args.seed, discretization=args.discretization,
                           gravity_walk_mps2_rts=args.gravity_walk, slow_stride=args.slow_stride)
    text = nr.markdown(results)
    print(text)
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        write_text_atomic(out / "network_reproduce.md", text + "\n")
        write_text_atomic(out / "network_reproduce.json", json.dumps(results, indent=1, default=float))
    return 0


def add_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    p = sub.add_parser("network", help="INS/GPS network adjustment vs Kalman smoothing (paper 003)")
    psub = p.add_subparsers(dest="network_command", required=True)
    r = psub.add_parser("reproduce", help="NA with/without cross-overs vs SSA on simulated flights",
                        parents=[quiet_parent()])
    r.add_argument("--runs", type=int, default=3, help="Monte Carlo flights (default 3)")
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--small", action="store_true", help="the small 2-minute flight of the tests and demo")
    r.add_argument("--imu-rate", type=float, default=None, help="IMU rate [Hz] (default 50)")
    r.add_argument("--discretization", choices=("trapezoidal", "leapfrog"), default="trapezoidal",
                   help="leapfrog is rejected with 1 Hz GPS on an even IMU rate (parity datum defect)")
    r.add_argument("--gravity-walk", type=float, default=2e-5, help="δg random-walk density [m/s^2/sqrt(s)]")
    r.add_argument("--slow-stride", type=int, default=1,
                   help="add NA rows with slow parameters (paper §4: biases and δg once per this many IMU epochs); "
                        "0 = IMU rate / GPS rate; 1 (default) = no slow rows")
    r.add_argument("--out", default=None, help="folder for network_reproduce.md and .json")
    r.set_defaults(func=cmd_reproduce)
