"""``indoorloc sweep FILE.toml``: a user's own grid of one of the shipped task functions on Dask.

The file::

    experiment = "mapmatch_run"      # a function of indoorloc.experiments.sweep_tasks
    runs = 20                        # runs per grid point (Monte Carlo)
    base_seed = 0
    [grid]
    kappa = [1.0, 5.0, 10.0]
    num_particles = [2000, 10000]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any, Dict
from indoorloc.io.atomic_file import write_text_atomic


def load_sweep_file(path: Path) -> Dict[str, Any]:
    """Reads and checks a sweep file; ValueError naming the file and the key on a bad one."""
    import tomllib

    from indoorloc.experiments import sweep_tasks

    try:
        spec = tomllib.loads(Path(path).read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ValueError(f"indoorloc: argument 'file': {path}: {exc}") from None
    name = spec.get("experiment")
    if name not in sweep_tasks.__all__:
        raise ValueError(f"indoorloc: argument 'file': {path}: 'experiment' must be one of {sweep_tasks.__all__}, "
                         f"got {name!r}")
    grid = spec.get("grid")
    if not isinstance(grid, dict) or not grid:
        raise ValueError(f"indoorloc: argument 'file': {path}: a [grid] table of parameter = [values] is required")
    grid = {k: (v if isinstance(v, list) else [v]) for k, v in grid.items()}
    runs, base_seed = spec.get("runs", 1), spec.get("base_seed", 0)
    if not isinstance(runs, int) or not isinstance(base_seed, int):
        raise ValueError(f"indoorloc: argument 'file': {path}: 'runs' and 'base_seed' must be integers")
    return {"fn": getattr(sweep_tasks, name), "experiment": name, "grid": grid, "runs": runs, "base_seed": base_seed}


def summarize_rows(rows, grid_names) -> list:
    """Per grid point: runs and the mean and sd of every numeric result over the runs."""
    import numpy as np

    groups: Dict[str, list] = {}
    for r in rows:
        groups.setdefault(json.dumps({k: r[k] for k in grid_names}, sort_keys=True), []).append(r)
    out = []
    for key, rs in groups.items():
        entry = dict(json.loads(key), runs=len(rs))
        for field in rs[0]:
            if field in grid_names or field in ("run", "seed"):
                continue
            vals = np.array([r[field] for r in rs], dtype=float)
            entry[f"{field}_mean"] = float(vals.mean())
            entry[f"{field}_sd"] = float(vals.std(ddof=1)) if vals.size > 1 else 0.0
        out.append(entry)
    return out


def cmd_sweep(args: argparse.Namespace) -> int:
    from indoorloc import progress, sweep

    spec = load_sweep_file(Path(args.file))
    n_tasks = len(sweep.make_tasks(spec["grid"], spec["runs"], spec["base_seed"]))
    ticker = progress.Ticker(total=n_tasks, desc="sweep tasks")
    result = sweep.run_sweep(spec["fn"], spec["grid"], runs=spec["runs"], base_seed=spec["base_seed"], out=args.out,
                             scheduler=args.scheduler, workers=args.workers, max_tasks=args.max_tasks,
                             progress=ticker.tick)
    ticker.close()
    table = summarize_rows(result.rows, list(spec["grid"]))
    if table:
        heads = list(table[0])
        print("| " + " | ".join(heads) + " |")
        print("|" + "---|" * len(heads))
        for e in table:
            print("| " + " | ".join(f"{v:.4g}" if isinstance(v, float) else str(v) for v in e.values()) + " |")
    print(f"\n{spec['experiment']}: {len(result.rows)} of {n_tasks} tasks done ({result.n_run} run now, "
          f"{result.n_cached} read from {args.out or '-'}), {len(result.failed)} failed, {result.seconds:.1f} s.")
    for f in result.failed:
        print(f"failed: {f['params']} run {f['run']} seed {f['seed']}: {f['error']}")
    if args.json:
        write_text_atomic(args.json, json.dumps({"experiment": spec["experiment"], "grid": spec["grid"],
                                               "runs": spec["runs"], "base_seed": spec["base_seed"],
                                               "summary": table, "rows": result.rows, "failed": result.failed},
                                              indent=1) + "\n")
    return 1 if result.failed else 0


def add_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    s = sub.add_parser("sweep", help="a grid of a task function on Dask (in-process or on a cluster)",
                       parents=[quiet_parent()], description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    s.add_argument("file", help="TOML sweep file (experiment, runs, base_seed, [grid])")
    s.add_argument("--scheduler", default=None, help="Dask scheduler address, e.g. tcp://host:8786 (default: in-process)")
    s.add_argument("--workers", type=int, default=None, help="threads of the in-process client (default 2)")
    s.add_argument("--out", default=None, help="JSON-lines file of task results (resume: finished tasks are skipped)")
    s.add_argument("--max-tasks", type=int, default=None, help="stop after this many new tasks")
    s.add_argument("--json", default=None, help="write the summary and rows here")
    s.set_defaults(func=cmd_sweep)
