"""`indoorloc reproduce`: every table of the five papers in one report (docs/reproduce.md).

    indoorloc reproduce [--papers 000 001 002 003 004] [--out DIR] [--runs N] [--threads T]
                        [--seed S] [--rerun PAPER ... | --rerun all] [--quick] [--scheduler ADDR]

Writes ``DIR/report.md``, ``DIR/report.html`` (self-contained, figures embedded) and
``DIR/report.json`` (schema: docs/reproduce.md), plus ``DIR/sections/<paper>.json`` and
``DIR/figures/<paper>/``. A finished section is kept and not run again with the same settings
(resume after an interruption); ``--rerun`` runs sections again.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path


def cmd_reproduce(args: argparse.Namespace) -> int:
    from indoorloc import progress
    from indoorloc.experiments import reproduce_report, reproduce_sections

    papers = reproduce_sections.check_papers(args.papers)
    if args.runs is not None and args.runs < 2:
        raise ValueError(f"indoorloc: argument '--runs': need at least 2 runs for a spread, got {args.runs}")
    if args.threads < 0:
        raise ValueError(f"indoorloc: argument '--threads': must be >= 0 (0 = all cores), got {args.threads}")
    if not args.rerun:
        rerun = []
    elif "all" in args.rerun:
        rerun = list(papers)
    else:
        rerun = reproduce_sections.check_papers(args.rerun)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    settings = {"runs": args.runs, "seed": args.seed, "quick": bool(args.quick)}

    def log(message: str) -> None:
        # Always printed (a line per finished part, with its time), terminal or not; --quiet silences it.
        if not progress._quiet:  # noqa: SLF001 - the CLI owns the switch
            print(f"[{time.strftime('%H:%M:%S')}] {message}", file=sys.stderr, flush=True)

    todo = [p for p in papers if p in rerun or reproduce_sections.load_finished(out, p, settings) is None]
    estimate = {p: reproduce_sections.expected_seconds(p, args.runs, args.quick) for p in todo}
    total = sum(estimate.values())
    log(f"reproduce: papers {', '.join(papers)} into {out}; to run: {', '.join(todo) or 'none (all finished earlier)'}"
        + (f"; expected run time on 2 cores about {total / 60:.0f} min ("
           + ", ".join(f"{p} {s / 60:.1f} min" for p, s in estimate.items()) + ")" if todo else ""))
    result = reproduce_sections.run_all(papers, out, settings, rerun=rerun, threads=args.threads,
                                        scheduler=args.scheduler, log=log)
    paths = reproduce_report.write_report(out, result["sections"], settings)
    log(f"reproduce: report {paths['markdown']}, {paths['html']}, {paths['json']}")
    print(paths["markdown"])
    if result["failed"]:
        for paper, error in result["failed"].items():
            print(f"error: paper {paper} failed: {error}", file=sys.stderr)
        return 1
    return 0


def add_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    p = sub.add_parser("reproduce", parents=[quiet_parent()],
                       help="run every table of the five papers and write one report (Markdown, HTML, JSON)")
    p.add_argument("--papers", nargs="+", default=None, metavar="PAPER",
                   help="paper indices to run (000 mapmatch, 001 analog, 002 pdr, 003 network, 004 wifi; default all)")
    p.add_argument("--out", default="reports/reproduce", help="report folder (default reports/reproduce)")
    p.add_argument("--runs", type=int, default=None,
                   help="Monte Carlo runs / realisations per cell (default: each paper's full size)")
    p.add_argument("--threads", type=int, default=0, help="C++ threads (0 = all cores)")
    p.add_argument("--seed", type=int, default=0, help="base seed of every section")
    p.add_argument("--rerun", nargs="+", default=None, metavar="PAPER",
                   help="run these sections again even if they finished earlier ('all' for every one)")
    p.add_argument("--quick", action="store_true",
                   help="tiny sizes (a smoke test of every code path; figures not comparable with the papers)")
    p.add_argument("--scheduler", default=None,
                   help="run the Monte Carlo tasks on this Dask scheduler (tcp://host:8786; identical results; "
                        "needs the sweep extra)")
    p.set_defaults(func=cmd_reproduce)
