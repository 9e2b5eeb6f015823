"""`indoorloc fusion ...` subcommands: the fusion tracker's experiments.

``indoorloc fusion synthetic [--walks N] [--seed S] [--json FILE]`` prints the synthetic-building table
and writes its JSON contract: ``{"methods": {NAME: {"mean_m", "p90_m", "n_walks", ...}},
"seeds": [...], "unknown_start_time_to_3m_s": ...}`` with NAME one of ``wifi_only``,
``pdr_only``, ``pdr_walls``, ``pdr_wifi``, ``fusion_known_start``, ``fusion_unknown_start``,
``fusion_smoother`` (docs/fusion.md documents every key).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from indoorloc.io.atomic_file import write_text_atomic


def cmd_synthetic(args: argparse.Namespace) -> int:
    from indoorloc import progress
    from indoorloc.experiments import fusion_synthetic as fs

    seeds = list(range(args.seed, args.seed + args.walks))
    overlap = sorted(set(seeds) & set(fs.TUNING_SEEDS))
    if overlap:
        print(f"note: seeds {overlap[0]}..{overlap[-1]} chose the defaults (tuning seeds): their figures are training figures")
    tic = time.perf_counter()
    results = []
    for result in progress.progress(fs.iter_walks(seeds, threads=args.threads), total=len(seeds), desc="walks"):
        results.append(result)
    summary = fs.summarize(results)
    summary["seconds"] = round(time.perf_counter() - tic, 2)
    print(fs.markdown_table(summary))
    print(f"\n{len(seeds)} walks (seeds {seeds[0]}..{seeds[-1]}) in {summary['seconds']:.1f} s")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(args.json, json.dumps(summary, indent=2) + "\n")
        print(f"JSON written to {args.json}")
    return 0


def _json_grid(text: str) -> dict:
    """--select-grid: a JSON object of setting -> list of values."""
    try:
        grid = json.loads(text)
    except json.JSONDecodeError as e:
        raise argparse.ArgumentTypeError(f"not JSON: {e}") from None
    if not isinstance(grid, dict) or not all(isinstance(v, list) and v for v in grid.values()):
        raise argparse.ArgumentTypeError("expected a JSON object of setting -> non-empty list of values")
    return grid


def cmd_evaluate(args: argparse.Namespace) -> int:
    from indoorloc import progress
    from indoorloc.experiments import fusion_real as fr

    # --lowo: leave one walk out (folds = 0); floor identification is then skipped (it would
    # rebuild every floor's database once per walk).
    seeds = list(args.seed)
    if any(v < 0 for v in seeds) or len(set(seeds)) != len(seeds):
        raise ValueError(f"indoorloc: argument '--seed': expected distinct seeds >= 0, got {seeds}")
    if len(seeds) > 1 and (args.select or args.lowo):
        raise ValueError("indoorloc: argument '--seed': several seeds only for the k-fold evaluation "
                         "(not with --select or --lowo)")
    settings = fr.RealSettings(folds=0 if args.lowo else args.folds, seed=seeds[0], threads=args.threads,
                               floor_identification=not args.lowo)
    # The site's floors (either competition layout), checked before any work: those named, or
    # every floor folder with walks and a plan (one without a plan is skipped with a warning).
    root, found = fr.site_floors(args.data_root, args.floors)
    floors = [sf.name for sf in found]
    if args.select_grid is not None and not args.select:
        raise ValueError("indoorloc: argument '--select-grid': only with --select (the grid of the "
                         "leave-one-floor-out choice); without it nothing would be selected")
    # A batch run to completion: freed buffers are kept for the next walk instead of being faulted
    # in again (indoorloc.allocator; no result depends on it).
    from indoorloc.allocator import retain_freed_memory

    retain_freed_memory()
    ticker = progress.Ticker(desc="fusion evaluate: walks")
    if args.select:
        result = fr.select_settings(root, floors, settings, grid=args.select_grid, progress=ticker.tick)
        ticker.close()
        print(fr.select_markdown(result))
    elif len(seeds) == 1:
        result = fr.evaluate(root, floors, settings, progress=ticker.tick, scheduler=args.scheduler)
        ticker.close()
        print(fr.markdown(result))
    else:
        from dataclasses import replace

        from indoorloc.experiments import fusion_real_seeds

        runs = {}
        for seed in seeds:
            runs[seed] = fr.evaluate(root, floors, replace(settings, seed=seed), progress=ticker.tick,
                                     scheduler=args.scheduler)
            print(f"## Fold seed {seed}\n\n{fr.markdown(runs[seed])}\n")
        ticker.close()
        result = fusion_real_seeds.seeds_document(runs)
        print(fusion_real_seeds.spread_markdown(result["spread"]))
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(args.json, json.dumps(result, indent=1) + "\n")
        print(f"JSON written to {args.json}")
    if args.plots and not args.select:
        from indoorloc import plots

        out = Path(args.plots)
        out.mkdir(parents=True, exist_ok=True)
        errors = {}
        first = result["runs"][str(seeds[0])] if len(seeds) > 1 else result  # plots of the first seed
        for row in first["waypoints"]:
            errors.setdefault(row["method"], []).append(row["error_m"])
        written = [plots.error_cdfs(errors, out / "fusion_real_error_cdfs.png", xmax_m=60.0,
                                    title=f"Waypoint errors, floors {' '.join(floors)}")]
        if first.get("heading_offsets"):
            written.append(plots.heading_offsets(first["heading_offsets"], out / "fusion_real_heading_offsets.png"))
        for floor in floors:
            written.append(plots.fusion_real_walk(fr.walk_snapshot(root, floor, args.plot_walk, settings),
                                                  out / f"fusion_real_walk_{floor}.png"))
        print("plots: " + ", ".join(str(p) for p in written))
    return 0


def cmd_tune(args: argparse.Namespace) -> int:
    from indoorloc.experiments import fusion_tuning as ft

    rows = ft.grid_search(seeds=list(range(args.seed, args.seed + args.walks)), threads=args.threads,
                          grid=ft.GRIDS[args.round])
    print(ft.markdown_table(rows))
    if args.json:
        write_text_atomic(args.json, json.dumps(rows, indent=2) + "\n")
    return 0


def add_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    p = sub.add_parser("fusion", help="particle-filter fusion of PDR, WiFi and a floor plan")
    fsub = p.add_subparsers(dest="fusion_command", required=True)
    s = fsub.add_parser("synthetic", parents=[quiet_parent()],
                        help="what each source contributes on seeded synthetic buildings and walks")
    s.add_argument("--walks", type=int, default=50, help="number of seeded walks (one building per seed)")
    s.add_argument("--seed", type=int, default=0, help="first seed (the defaults were tuned on seeds 1000-1019)")
    s.add_argument("--threads", type=int, default=2, help="walks run in parallel (results do not depend on it)")
    s.add_argument("--json", default=None, help="write the JSON summary here")
    s.set_defaults(func=cmd_synthetic)
    e = fsub.add_parser("evaluate", parents=[quiet_parent()],
                        help="real phone walks (ILC 2020 or Kaggle 2021 layout): k-fold by walk, every method "
                             "scored at the waypoints")
    e.add_argument("--data-root", default=None,
                   help="a site's survey folder (default: shared data): ILC 2020 SITE (SITE/FLOOR/path_data_files/*.txt "
                        "beside SITE/FLOOR/geojson_map.json), or Kaggle 2021 ROOT/train/SITE or a one-site ROOT "
                        "(walks ROOT/train/SITE/FLOOR/*.txt, plans ROOT/metadata/SITE/FLOOR/)")
    e.add_argument("--floors", nargs="+", default=None,
                   help="floor folders to evaluate (default: every floor folder with walk files and a floor plan "
                        "geojson_map.json, in building order B2, B1, F1, F2, ...; one with walks but no plan is "
                        "skipped with a warning, an error when named here)")
    e.add_argument("--folds", type=int, default=4, help="k of the k-fold by walk within each floor")
    e.add_argument("--lowo", action="store_true",
                   help="leave one walk out instead of k-fold (no floor identification)")
    e.add_argument("--seed", type=int, nargs="+", default=[0],
                   help="fold assignment seed (default 0); several: one evaluation per seed and the spread of "
                        "each figure across them (JSON: docs/fusion_real.md, 'Several fold seeds')")
    e.add_argument("--threads", type=int, default=2, help="walks tracked in parallel (results do not depend on it)")
    e.add_argument("--json", default=None, help="write the JSON (schema: docs/fusion_real.md)")
    e.add_argument("--select", action="store_true",
                   help="leave-one-floor-out choice of the settings over fusion_real.SELECT_GRID instead")
    e.add_argument("--select-grid", type=_json_grid, default=None, metavar="JSON",
                   help="with --select: the grid as JSON, e.g. '{\"grid.wall_margin_m\": [0, 1]}' (keys: "
                        "RealSettings fields, fixes.X, grid.X; default fusion_real.SELECT_GRID)")
    e.add_argument("--plots", default=None, metavar="DIR",
                   help="write error CDFs of all methods and one walk per floor on its floor image here")
    e.add_argument("--plot-walk", type=int, default=0, help="index of the walk drawn per floor (default 0)")
    e.add_argument("--scheduler", default=None,
                   help="one Dask task per fold on this scheduler (tcp://host:8786; the workers must see --data-root)")
    e.set_defaults(func=cmd_evaluate)
    t = fsub.add_parser("tune", parents=[quiet_parent()],
                        help="grid search of the tracker's settings on tuning seeds (how the defaults were chosen)")
    t.add_argument("--walks", type=int, default=20)
    t.add_argument("--seed", type=int, default=1000)
    t.add_argument("--threads", type=int, default=2)
    t.add_argument("--round", type=int, default=2, choices=sorted((1, 2)), help="which grid (docs/fusion.md)")
    t.add_argument("--json", default=None)
    t.set_defaults(func=cmd_tune)
