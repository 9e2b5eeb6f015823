"""`indoorloc analog ...` subcommands."""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def cmd_lorenz63(args: argparse.Namespace) -> int:
    from indoorloc.experiments import analog_lorenz63 as al

    result = al.run_table1(
        n_realisations=args.realisations,
        catalog_sizes=tuple(args.catalog_sizes),
        beams=tuple(args.beams),
        k=args.k,
        seed=args.seed,
    )
    text = al.markdown_table(result)
    print(text)
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2, default=lambda o: getattr(o, "tolist", lambda: str(o))()))
    return 0


def cmd_imu(args: argparse.Namespace) -> int:
    from indoorloc.cli_wifi import default_data_root
    from indoorloc.experiments import analog_imu as ai

    root = Path(args.data_root) if args.data_root else default_data_root().parent / "pdr"
    result = ai.run_imu_experiments(root, k_anfb=args.k, beam=args.beam, seed=args.seed)
    print(ai.markdown_table(result))
    return 0


def add_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    p = sub.add_parser("analog", help="analog (exemplar-based) HMM (paper 001)")
    asub = p.add_subparsers(dest="analog_command", required=True)
    l63 = asub.add_parser("lorenz63", help="paper 001 Table 1: EnKS, AnEnKS, AnFB on Lorenz-63", parents=[quiet_parent()])
    l63.add_argument("--realisations", type=int, default=10)
    l63.add_argument("--catalog-sizes", type=int, nargs="+", default=[10**4, 10**5])
    l63.add_argument("--beams", type=int, nargs="+", default=[1000, 3000, 10000])
    l63.add_argument("--k", type=int, default=5, help="neighbours per state (paper: 5-15)")
    l63.add_argument("--seed", type=int, default=0)
    l63.add_argument("--json")
    l63.set_defaults(func=cmd_lorenz63)
    imu = asub.add_parser("imu", help="missing-data interpolation on real walking IMU data", parents=[quiet_parent()])
    imu.add_argument("--data-root", default=None, help="folder of the PDR datasets (default ../shared/data/pdr)")
    imu.add_argument("--k", type=int, default=6)
    imu.add_argument("--beam", type=int, default=500)
    imu.add_argument("--seed", type=int, default=0)
    imu.set_defaults(func=cmd_imu)
