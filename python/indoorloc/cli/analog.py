"""`indoorloc analog ...` subcommands."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from indoorloc.registry import default_pdr_root
from indoorloc.io.atomic_file import write_text_atomic


def cmd_lorenz63(args: argparse.Namespace) -> int:
    from indoorloc.experiments import analog_lorenz63 as al

    kwargs = dict(
        k=al.DEFAULT_K if args.k is None else args.k,
        n_realisations=args.realisations,
        catalog_sizes=tuple(args.catalog_sizes),
        beams=tuple(None if b == 0 else b for b in args.beams),
        seed=args.seed,
        sigma_scale=al.DEFAULT_SIGMA_SCALE if args.sigma_scale is None else args.sigma_scale,
        max_dropped_mass=args.max_dropped_mass,
        methods=tuple(args.methods),
        kernels=al.VALIDATED_KERNELS if (args.k is None and args.sigma_scale is None) else None,
        successor_rule=args.successor_rule,
        r_hmm_scale=args.r_hmm_scale,
    )
    if args.scheduler:
        # One Dask task per realisation (the experiment's own seeds: the same table as in-process).
        from indoorloc import sweep
        from indoorloc.experiments import sweep_tasks

        res = sweep.run_sweep(sweep_tasks.analog_table1_realisation, {"r": list(range(args.realisations))},
                              scheduler=args.scheduler, shared={"table1_kwargs": kwargs})
        if res.failed:
            raise RuntimeError(f"indoorloc: realisation {res.failed[0]['params']['r']} failed: {res.failed[0]['error']}")
        result = al.merge_table1([row["part"] for row in res.rows])
    else:
        result = al.run_table1(**kwargs)
    text = al.markdown_table(result)
    print(text)
    if args.json:
        write_text_atomic(args.json, json.dumps(result, indent=2, default=lambda o: getattr(o, "tolist", lambda: str(o))()))
    return 0


def cmd_lorenz63_tune(args: argparse.Namespace) -> int:
    from indoorloc.experiments import analog_lorenz63 as al

    print(f"| M | rule | K | sigma_scale | R_hmm / R | validation RMSE (mean over {args.problems}) | median | "
          "per problem | time per run [s] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for M in args.catalog_sizes:
        rows = al.run_kernel_selection(
            M, ks=tuple(args.ks), sigma_scales=tuple(args.sigma_scales), beam=None if args.beam == 0 else args.beam,
            max_dropped_mass=args.max_dropped_mass, n_problems=args.problems, seed=args.seed,
            successor_rule=args.successor_rule, r_hmm_scales=tuple(args.r_hmm_scales),
        )
        for r in rows:
            per = " ".join(f"{e:.2f}" for e in r["rmse"])
            print(f"| {M} | {r['successor_rule']} | {r['k']} | {r['sigma_scale']} | {r['r_hmm_scale']} | "
                  f"{r['rmse_mean']:.3f} | {r['rmse_median']:.3f} | {per} | {r['seconds_mean']:.2f} |", flush=True)
    return 0


def cmd_imu(args: argparse.Namespace) -> int:
    from indoorloc.experiments import analog_imu as ai

    root = Path(args.data_root) if args.data_root else default_pdr_root()
    result = ai.run_imu_experiments(root, k_anfb=args.k, beam=args.beam, seed=args.seed)
    print(ai.markdown_table(result))
    return 0


def add_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    p = sub.add_parser("analog", help="analog (exemplar-based) HMM (paper 001)")
    asub = p.add_subparsers(dest="analog_command", required=True)
    l63 = asub.add_parser("lorenz63", help="paper 001 Table 1: EnKS, AnEnKS, AnFB on Lorenz-63", parents=[quiet_parent()])
    l63.add_argument("--realisations", type=int, default=10)
    l63.add_argument("--catalog-sizes", type=int, nargs="+", default=[10**4, 10**5])
    from indoorloc.experiments import analog_lorenz63 as al

    l63.add_argument("--beams", type=int, nargs="+", default=[1000, 3000], help="N of the truncated AnFB (0: exact)")
    l63.add_argument("--k", type=int, default=None,
                     help="neighbours per state (paper: 5-15); default: the validated kernel per catalog size")
    l63.add_argument("--sigma-scale", type=float, default=None,
                     help="kernel width multiplier of eq. 4 (1 = the paper's adaptive sigma); default: validated")
    l63.add_argument("--max-dropped-mass", type=float, default=al.DEFAULT_MAX_DROPPED_MASS,
                     help="mass-adaptive beam tolerance (1 = the paper's fixed N)")
    l63.add_argument("--successor-rule", default=al.DEFAULT_SUCCESSOR_RULE, choices=list(al.SUCCESSOR_RULES),
                     help="AnFB transition target: 'catalog' (paper eq. 4) or 'incremental' (docs/analog.md)")
    l63.add_argument("--r-hmm-scale", type=float, default=1.0,
                     help="the AnFB assumes observation variance r_hmm_scale * R (1: the data's)")
    l63.add_argument("--methods", nargs="+", default=list(al.METHODS), choices=list(al.METHODS))
    l63.add_argument("--seed", type=int, default=0)
    l63.add_argument("--json")
    l63.add_argument("--scheduler", default=None,
                     help="one Dask task per realisation on this scheduler (tcp://host:8786; identical table)")
    l63.set_defaults(func=cmd_lorenz63)
    tune = asub.add_parser("lorenz63-tune", help="choose K and the kernel width on validation problems",
                           parents=[quiet_parent()])
    tune.add_argument("--catalog-sizes", type=int, nargs="+", default=[10**4, 10**5])
    tune.add_argument("--ks", type=int, nargs="+", default=[5, 10, 15])
    tune.add_argument("--sigma-scales", type=float, nargs="+", default=[0.35, 0.5, 0.7, 1.0])
    tune.add_argument("--beam", type=int, default=1000, help="N (0: exact)")
    tune.add_argument("--max-dropped-mass", type=float, default=al.DEFAULT_MAX_DROPPED_MASS)
    tune.add_argument("--problems", type=int, default=6)
    tune.add_argument("--successor-rule", default=al.DEFAULT_SUCCESSOR_RULE, choices=list(al.SUCCESSOR_RULES))
    tune.add_argument("--r-hmm-scales", type=float, nargs="+", default=[1.0],
                      help="inflations of the AnFB's observation variance (R_hmm = scale * R) tried per kernel")
    tune.add_argument("--seed", type=int, default=0)
    tune.set_defaults(func=cmd_lorenz63_tune)
    imu = asub.add_parser("imu", help="missing-data interpolation on real walking IMU data", parents=[quiet_parent()])
    imu.add_argument("--data-root", default=None, help="folder of the PDR datasets (default ../shared/data/pdr)")
    imu.add_argument("--k", type=int, default=6)
    imu.add_argument("--beam", type=int, default=500)
    imu.add_argument("--seed", type=int, default=0)
    imu.set_defaults(func=cmd_imu)
