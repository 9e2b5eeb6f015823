"""The ``indoorloc`` command line.

    indoorloc --version
    indoorloc demo [--out DIR] [--only NAME ...] [--seed N] [--quiet]
    indoorloc core resample-bench [--n N] [--repeat R]
    indoorloc analog lorenz63 [--realisations 10] | analog imu
    indoorloc mapmatch reproduce [--runs 100] [--variant paper bias] [--ablation]
    indoorloc pdr evaluate
    indoorloc wifi evaluate [--dataset uji office ...] [--scans 1 10]
    indoorloc wifi simulate [--runs R] [--noise-db S]
    indoorloc reproduce [--papers 000 ...] [--out DIR] [--runs N] [--quick]
    indoorloc site build SURVEY_DIR -o SITE.db [--floors ...] | site add SITE.db WALK... | site info SITE.db
    indoorloc track WALK... --site SITE.db [--floor NAME|auto] [--no-smooth] -o OUT.{geojson,csv,json}
    indoorloc live --site SITE.db [--floor NAME] [--events FILE|- | --walk WALK.txt] [-o OUT.ndjson]
    indoorloc sweep FILE.toml [--scheduler tcp://host:8786] [--out results.jsonl]

Each subsystem's subcommands live in ``indoorloc/cli/<subsystem>.py`` with an
``add_parser(subparsers, quiet_parent)`` function, added to ``_SUBCOMMANDS`` below. CLI modules
may import experiments, io, simulate and the facades; nothing imports them but this package
(docs/architecture.md, "Layers").
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path
from typing import Callable, List, Optional

import indoorloc
from indoorloc import progress


def _cmd_demo(args: argparse.Namespace) -> int:
    from indoorloc.demo import run_demos

    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="indoorloc-demo-"))
    report = run_demos(out, names=args.only, seed=args.seed, quick=args.quick)
    print(f"indoorloc demo report: {report}")
    return 0


def _cmd_core_resample_bench(args: argparse.Namespace) -> int:
    from indoorloc.experiments import core_resampling

    print(json.dumps(core_resampling.resampling_timings(args.n, args.repeat, args.seed), indent=2))
    return 0


def quiet_parent() -> argparse.ArgumentParser:
    """Parent parser giving every subcommand a --quiet flag (also accepted before it)."""
    parent = argparse.ArgumentParser(add_help=False)
    parent.add_argument(
        "--quiet", action="store_true", default=argparse.SUPPRESS, help="no progress bars"
    )
    return parent


def _add_core(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("core", help="shared core utilities")
    core_sub = p.add_subparsers(dest="core_command", required=True)
    b = core_sub.add_parser(
        "resample-bench", help="time each resampling scheme", parents=[quiet_parent()]
    )
    b.add_argument("--n", type=int, default=1_000_000, help="number of log-weights")
    b.add_argument("--repeat", type=int, default=20)
    b.add_argument("--seed", type=int, default=0)
    b.set_defaults(func=_cmd_core_resample_bench)


def _add_analog(sub: argparse._SubParsersAction) -> None:
    from indoorloc.cli import analog

    analog.add_parser(sub, quiet_parent)


def _add_fusion(sub: argparse._SubParsersAction) -> None:
    from indoorloc.cli import fusion

    fusion.add_parser(sub, quiet_parent)


def _add_mapmatch(sub: argparse._SubParsersAction) -> None:
    from indoorloc.cli import mapmatch

    mapmatch.add_parser(sub, quiet_parent)


def _add_network(sub: argparse._SubParsersAction) -> None:
    from indoorloc.cli import network

    network.add_parser(sub, quiet_parent)


def _add_pdr(sub: argparse._SubParsersAction) -> None:
    from indoorloc.cli import pdr

    pdr.add_parser(sub, quiet_parent)


def _add_reproduce(sub: argparse._SubParsersAction) -> None:
    from indoorloc.cli import reproduce

    reproduce.add_parser(sub, quiet_parent)


def _add_site(sub: argparse._SubParsersAction) -> None:
    from indoorloc.cli import site

    site.add_parser(sub, quiet_parent)
    site.add_track_parser(sub, quiet_parent)
    site.add_live_parser(sub, quiet_parent)


def _add_sweep(sub: argparse._SubParsersAction) -> None:
    from indoorloc.cli import sweep

    sweep.add_parser(sub, quiet_parent)


def _add_wifi(sub: argparse._SubParsersAction) -> None:
    from indoorloc.cli import wifi

    wifi.add_parser(sub, quiet_parent)


# Subsystems register `add(subparsers)` functions here.
_SUBCOMMANDS: List[Callable[[argparse._SubParsersAction], None]] = [_add_core, _add_analog, _add_fusion, _add_mapmatch, _add_network, _add_pdr, _add_reproduce, _add_site, _add_sweep, _add_wifi]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="indoorloc",
        description="Indoor localization and inertial estimation (indoorloc).",
    )
    parser.add_argument("--version", action="version", version=f"indoorloc {indoorloc.__version__}")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    sub = parser.add_subparsers(dest="command", required=True)

    demo = sub.add_parser(
        "demo", help="run every subsystem's quick experiment, write a report", parents=[quiet_parent()]
    )
    demo.add_argument("--out", help="report folder (default: a new temporary folder)")
    demo.add_argument("--only", nargs="+", help="run only these demos")
    demo.add_argument("--seed", type=int, default=0)
    demo.add_argument("--quick", action="store_true", help="fewer Monte Carlo runs (smoke test)")
    demo.set_defaults(func=_cmd_demo)

    for add in _SUBCOMMANDS:
        add(sub)
    return parser


def main(argv: Optional[List[str]] = None) -> int:
    args = build_parser().parse_args(argv)
    # Bars on a terminal, progress lines when output goes to a file or pipe (or under CI).
    progress.configure(quiet=args.quiet, lines=True)
    try:
        return int(args.func(args) or 0)
    except (ValueError, OSError) as exc:
        # Bad arguments and paths (a missing folder, an unreadable file) are the user's to fix:
        # one line naming the argument, no traceback.
        print(f"error: {exc}", file=sys.stderr)
        return 2
