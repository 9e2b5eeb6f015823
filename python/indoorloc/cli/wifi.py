"""`indoorloc wifi ...` subcommands: evaluate on real data, simulate the paper's paths."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from indoorloc.registry import default_data_root
from indoorloc.io.atomic_file import write_text_atomic


def cmd_evaluate(args: argparse.Namespace) -> int:
    from indoorloc.experiments import wifi_evaluate as we

    root = Path(args.data_root) if args.data_root else default_data_root()
    if not root.is_dir():
        raise ValueError(f"indoorloc: argument 'data_root': {root} is not a folder")
    cases = [(name, k) for name in args.dataset for k in args.scans]
    if args.scheduler:
        # One Dask task per (dataset, scans) case; the workers read --data-root.
        from indoorloc import sweep
        from indoorloc.experiments import sweep_tasks

        res = sweep.run_sweep(sweep_tasks.wifi_case, {"case": [f"{n}/k={k}" for n, k in cases]},
                              scheduler=args.scheduler,
                              shared={"root": str(root), "cv_points": args.cv_points, "cv_seed": args.seed,
                                      "threads": args.threads, "methods": args.methods})
        if res.failed:
            raise RuntimeError(f"indoorloc: case {res.failed[0]['params']['case']} failed: {res.failed[0]['error']}")
        outputs = [(row["markdown"], row["entry"]) for row in res.rows]
    else:
        from indoorloc import progress

        outputs = []
        for i, (name, k) in enumerate(cases, 1):
            with progress.stage(f"wifi evaluate: [{i}/{len(cases)}] {name}, {k} scan(s) per estimate"):
                outputs.append(we.evaluate_case(root, name, k, args.cv_points, args.seed, args.threads,
                                                methods=args.methods))
    report = {}
    for (name, k), (text, entry) in zip(cases, outputs):
        print(text)
        print()
        report[f"{name}/k={k}"] = entry
    if args.json:
        write_text_atomic(args.json, json.dumps(report, indent=2, default=float))
    return 0


def cmd_simulate(args: argparse.Namespace) -> int:
    from indoorloc.experiments import wifi_simulation as ws
    from indoorloc.io.wifi_datasets import load_wifi_dataset

    if args.map == "paper":
        model = ws.paper_map(seed=args.seed, noise_db=args.noise_db, shadowing_db=args.shadowing_db)
        paths = ws.paper_paths()
    else:
        data_root = Path(args.data_root) if args.data_root else default_data_root()
        model = ws.fitted_map(load_wifi_dataset(args.map, data_root))
        paths = ws.paths_through(model)
    results = {name: ws.run_path(model, name, path, n_runs=args.runs, seed=args.seed) for name, path in paths.items()}
    print(ws.markdown_table(results))
    print(f"\npaper (vertical path, 27 steps): E_27 = {ws.PAPER_E27_M} m")
    return 0


def add_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    p = sub.add_parser("wifi", help="WiFi RSS localization (paper 004)")
    wsub = p.add_subparsers(dest="wifi_command", required=True)
    e = wsub.add_parser("evaluate", help="every method on real datasets", parents=[quiet_parent()])
    e.add_argument("--dataset", nargs="+", default=["uji", "lecture_theatre", "office", "corridor"])
    e.add_argument("--scans", nargs="+", type=int, default=[1, 10], help="scans per estimate")
    e.add_argument("--methods", nargs="+", default=None,
                   help="only these methods (default: all: ml mmse tracker nnss nnss_avg wknn horus shared_knn)")
    e.add_argument("--data-root", default=None, help="default: $INDOORLOC_WIFI_DATA or ../shared/data/wifi")
    e.add_argument("--cv-points", type=int, default=24, help="held-out training points for CV")
    e.add_argument("--threads", type=int, default=0, help="0: all cores (results do not depend on it)")
    e.add_argument("--seed", type=int, default=0)
    e.add_argument("--json", help="also write the results as JSON")
    e.add_argument("--scheduler", default=None,
                   help="one Dask task per (dataset, scans) case on this scheduler (tcp://host:8786; workers must see --data-root)")
    e.set_defaults(func=cmd_evaluate)
    s = wsub.add_parser("simulate", help="the paper's simulated paths (Monte Carlo)", parents=[quiet_parent()])
    s.add_argument("--runs", type=int, default=200)
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--noise-db", type=float, default=0.5, help="RSS noise sd of the synthetic map [dB]")
    s.add_argument("--shadowing-db", type=float, default=0.0, help="per-point shadowing sd [dB]")
    s.add_argument("--map", default="paper", help="paper (synthetic corridor) or a dataset name: the map fitted to its training scans")
    s.add_argument("--data-root", default=None)
    s.set_defaults(func=cmd_simulate)
