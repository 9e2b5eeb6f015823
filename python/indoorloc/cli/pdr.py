"""`indoorloc pdr ...` subcommands."""

from __future__ import annotations

import argparse
from pathlib import Path

from indoorloc.registry import default_pdr_root


def cmd_evaluate(args: argparse.Namespace) -> int:
    import json

    from indoorloc.experiments import pdr_json
    from indoorloc.experiments import pdr_report
    from indoorloc.io.atomic_file import write_text_atomic

    root = Path(args.data_root) if args.data_root else default_pdr_root()
    if not root.is_dir():
        raise ValueError(f"indoorloc: argument 'data_root': {root} is not a folder")
    doc = (pdr_json.evaluate_json_on_dask(root, args.only, args.scheduler) if args.scheduler
           else pdr_json.evaluate_json(root, only=args.only))
    if args.json:
        # temporary file + rename: an interrupted run never leaves a half-written JSON behind
        write_text_atomic(args.json, json.dumps(doc, indent=1) + "\n")
    print("\n".join(pdr_report.recommended_summary_lines(doc)))
    if args.compare:
        for text in pdr_report.comparison_report(root):
            print(text)
    return 0


def add_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    p = sub.add_parser("pdr", help="pedestrian dead reckoning, foot-mounted IMU (paper 002)")
    psub = p.add_subparsers(dest="pdr_command", required=True)
    e = psub.add_parser("evaluate", help="ZUPT EKF + RTS with the adaptive zero-velocity detector on every recording in ../shared/data/pdr", parents=[quiet_parent()])
    e.add_argument("--data-root", default=None, help="folder of the PDR datasets (default ../shared/data/pdr)")
    e.add_argument("--json", default=None, metavar="FILE",
                   help="write every recording's figures and health check as JSON (schema in docs/pdr.md)")
    e.add_argument("--only", nargs="+", default=None, choices=["pyshoe", "xio", "openshoe", "mobgap"],
                   help="evaluate only these datasets (default: every one present under the data root)")
    e.add_argument("--compare", action="store_true",
                   help="also print the comparison tables of the other methods (fixed and per-class thresholds, "
                        "paper 002's step-wise positioning, Weinberg on mobgap)")
    e.add_argument("--scheduler", default=None,
                   help="one Dask task per dataset on this scheduler (tcp://host:8786; the workers must see --data-root)")
    e.set_defaults(func=cmd_evaluate)
