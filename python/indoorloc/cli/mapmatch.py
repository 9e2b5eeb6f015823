"""`indoorloc mapmatch ...` subcommands."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from indoorloc.io.atomic_file import write_text_atomic


def cmd_reproduce(args: argparse.Namespace) -> int:
    from indoorloc import plots
    from indoorloc.experiments import mapmatch_reproduce as mr

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    report = {}
    text = []
    for variant in args.variant:
        if args.scheduler:
            results = _kappas_on_dask(args, variant)
        else:
            results = mr.run_kappas(variant, n_runs=args.runs, num_particles=args.particles, seed=args.seed,
                                    n_threads=args.threads)
        text.append(mr.markdown_tables(results, f"variant: {variant}"))
        plots.mapmatch_curves(results, out / f"mapmatch_{variant.replace(' ', '_').replace('+', 'and')}.png")
        report[variant] = [r.row() for r in results.values()]
    if args.ablation:
        # Beyond the paper, at κ_P = 1: each addition and the fixed-lag smoother, same runs.
        rows = ["| κ_P = 1 | mean error [m] | P(correct) | P after 120 s |", "|---|---|---|---|"]
        for variant in mr.VARIANTS:
            r = mr.run_kappas(variant, kappas=(1.0,), n_runs=args.runs, num_particles=args.particles, seed=args.seed,
                              n_threads=args.threads, smoothing_lag_steps=50)[1.0]
            row = r.row()
            rows.append(f"| {variant} | {row['mean_error_m']:.2f} | {row['p_correct']:.2f} | {row['p_correct_after_120s']:.2f} |")
            lag = 50
            smoothed = r.smoothed_error_m[:, :-lag]
            rows.append(f"| {variant}, fixed-lag smoothed (5 s) | {float(smoothed.mean()):.2f} (filter on the same steps: "
                        f"{float(r.error_m[:, :-lag].mean()):.2f}) | | |")
        text.append("**Ablation (beyond the paper)**\n\n" + "\n".join(rows))
    output = "\n\n".join(text)
    write_text_atomic(out / "mapmatch_tables.md", output + "\n")
    write_text_atomic(out / "mapmatch_results.json", json.dumps(report, indent=2))
    print(output)
    print(f"\nwritten to {out}")
    return 0


def _kappas_on_dask(args: argparse.Namespace, variant: str):
    """The κ of one variant as Dask tasks (one per κ, the same seed as in-process: identical results)."""
    import numpy as np

    from indoorloc import mapmatch, sweep
    from indoorloc.experiments import mapmatch_reproduce as mr
    from indoorloc.experiments import sweep_tasks

    grid = {"kappa": list(mr.KAPPAS), "variant": [variant], "n_runs": [args.runs], "num_particles": [args.particles],
            "seed": [args.seed], "threads": [max(1, args.threads)]}
    segments = np.asarray(mapmatch.warehouse_network().segments_m)
    result = sweep.run_sweep(sweep_tasks.mapmatch_kappa, grid, scheduler=args.scheduler, shared={"segments_m": segments})
    if result.failed:
        raise RuntimeError(f"indoorloc: {len(result.failed)} mapmatch tasks failed: {result.failed[0]['error']}")
    return {r["kappa"]: mr.KappaResult(r["kappa"], r["error_m"], r["correct"], r["smoothed_error_m"], r["seconds"])
            for r in result.rows}


def add_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    p = sub.add_parser("mapmatch", help="map matching with a circular particle filter (paper 000)")
    msub = p.add_subparsers(dest="mapmatch_command", required=True)
    r = msub.add_parser("reproduce", help="paper 000 §III Monte Carlo: Tables I, II, Figs. 3, 4", parents=[quiet_parent()])
    r.add_argument("--runs", type=int, default=100)
    r.add_argument("--particles", type=int, default=10_000)
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--threads", type=int, default=0, help="0: all cores (results do not depend on it)")
    r.add_argument("--variant", nargs="+", default=["paper", "bias"], help="paper, bias, 'bias + heading-aware junctions'")
    r.add_argument("--ablation", action="store_true", help="also measure each beyond-the-paper addition at κ_P = 1")
    r.add_argument("--out", default="reports/mapmatch")
    r.add_argument("--scheduler", default=None,
                   help="run the κ as Dask tasks on this scheduler (tcp://host:8786; identical results; needs the sweep extra)")
    r.set_defaults(func=cmd_reproduce)
