"""``indoorloc site ...`` and ``indoorloc track``: a site model from survey walks, and walks
tracked with it (docs/your_building.md). Parse and print only; the work is
:class:`indoorloc.fusion.Site` and :mod:`indoorloc.io.track_files`.

    indoorloc site build SURVEY_DIR -o SITE.db [--floors F1 F2] [--coverage DIR] [--lowo]
    indoorloc site add SITE.db WALK.txt ... [--floor NAME]
    indoorloc site grow SITE.db WALK.txt ... [--floor NAME|auto] [--max-sd-m M] [--weight W]
    indoorloc site info SITE.db [--json]
    indoorloc track WALK.txt ... --site SITE.db [--floor NAME|auto] [--smooth|--no-smooth] -o OUT.{geojson,csv,json} [--html VIEW.html]
    indoorloc live --site SITE.db [--floor NAME] [--events FILE|- | --walk WALK.txt] [-o OUT.ndjson]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path


def _floor_table(info: dict) -> str:
    lines = ["| floor | walks | fingerprints | APs | beacons | walkable [m²] | survey coverage (within 5 m) "
             "| survey off the plan |",
             "|---|---|---|---|---|---|---|---|"]
    for name, f in info["floors"].items():
        lines.append(f"| {name} | {f['walks']} | {f['fingerprints']} | {f['access_points']} | {f['beacons']} | "
                     f"{f['walkable_area_m2']:.0f} | {100 * f['survey_coverage']:.0f} % | "
                     f"{100 * f['survey_off_plan']:.1f} % |")
    return "\n".join(lines)


def cmd_build(args: argparse.Namespace) -> int:
    from indoorloc import progress
    from indoorloc.fusion.site import Site
    from indoorloc.io.survey_layout import survey_floors

    floors = survey_floors(Path(args.survey_dir), args.floors)
    ticker = progress.Ticker(total=sum(len(f.walk_paths) for f in floors), desc="site build: walks")
    tic = time.perf_counter()
    site = Site.build(args.survey_dir, args.output, floors=args.floors, progress=lambda _: ticker.tick())
    ticker.close()
    seconds = time.perf_counter() - tic
    info = site.info()
    print(_floor_table(info))
    print(f"\nsite {args.output}: {len(info['floors'])} floor(s), {len(info['walks'])} walks, "
          f"{info['size_bytes'] / 1e6:.1f} MB, built in {seconds:.1f} s")
    out = Path(args.coverage) if args.coverage else Path(args.output).with_suffix("").parent / (
        Path(args.output).stem + "_coverage")
    if not args.no_coverage:
        from indoorloc import plots

        out.mkdir(parents=True, exist_ok=True)
        for name in site.floors:
            lowo = None
            if args.lowo:
                t = progress.Ticker(desc=f"leave one walk out {name}")
                lowo = site.leave_one_walk_out(name, progress=lambda _: t.tick())
                t.close()
                st = lowo["stats"]
                if st:
                    print(f"{name}: leave-one-walk-out error mean {st['mean_m']:.1f} m, median {st['median_m']:.1f} m, "
                          f"p90 {st['p90_m']:.1f} m ({st['n_waypoints']} waypoints of {lowo['walks']} walks)")
            png = plots.site_coverage(site.coverage(name), out / f"coverage_{name}.png",
                                      lowo_points=None if lowo is None else lowo["points"])
            print(f"coverage map: {png}")
    return 0


def cmd_add(args: argparse.Namespace) -> int:
    from indoorloc import progress
    from indoorloc.fusion.site import Site

    site = Site.open(args.site)
    ticker = progress.Ticker(total=len(args.walks), desc="site add: walks")
    added = site.add([Path(w) for w in args.walks], floor=args.floor, progress=lambda _: ticker.tick())
    ticker.close()
    print(f"added {len(added)} walk(s) to {args.site}: {', '.join(added)}")
    print(_floor_table(site.info()))
    return 0


def cmd_grow(args: argparse.Namespace) -> int:
    from indoorloc import progress
    from indoorloc.fusion.site import Site

    site = Site.open(args.site)
    ticker = progress.Ticker(total=len(args.walks), desc="site grow: walks")
    added = site.grow([Path(w) for w in args.walks], floor=args.floor, max_sd_m=args.max_sd_m, weight=args.weight,
                      progress=lambda _: ticker.tick())
    ticker.close()
    for walk_id, n in added.items():
        print(f"{walk_id}: {n} fingerprints placed by the track")
    print(_floor_table(site.info()))
    return 0


def cmd_info(args: argparse.Namespace) -> int:
    from indoorloc.fusion.site import Site

    info = Site.open(args.site).info()
    if args.json:
        print(json.dumps(info, indent=1))
        return 0
    m = info["meta"]
    print(f"site {info['path']} ({info['size_bytes'] / 1e6:.1f} MB): format {m.get('format')} version "
          f"{m.get('format_version')}, built {m.get('built')} by indoorloc {m.get('library_version')}, "
          f"modified {m.get('modified')}, survey {m.get('survey_dir')}")
    print(_floor_table(info))
    for name, f in info["floors"].items():
        c = f["pdr_calibration"]
        if c:
            print(f"{name}: PDR K {c['k']:.3f}, yaw offset {c['yaw_offset_deg']:.1f} deg (spread "
                  f"{c['yaw_offset_spread_deg']:.1f} deg)")
    return 0


def cmd_track(args: argparse.Namespace) -> int:
    import numpy as np

    from indoorloc import progress
    from indoorloc.fusion.site import Site
    from indoorloc.io.track_files import EXTENSIONS, error_stats, wifi_fix_count, write_tracks

    if Path(args.output).suffix.lower() not in EXTENSIONS:
        raise ValueError(f"indoorloc: argument '-o/--output': {args.output}: the extension must be one of {EXTENSIONS}")
    site = Site.open(args.site)
    tracks = []
    floor = None if args.floor is None else args.floor
    failed = 0
    for w in progress.progress(args.walks, desc="track: walks"):
        try:
            tr = site.track(Path(w), floor=floor, smooth=args.smooth)
        except (ValueError, OSError) as exc:
            # One walk that cannot be tracked (unreadable, empty, a floor the site lacks) does not
            # cost the others their tracks: it is named, and the exit status says it.
            print(f"error: walk {w} not tracked: {exc}", file=sys.stderr)
            failed += 1
            continue
        tracks.append(tr)
        st = error_stats(tr.errors_m)
        line = f"{tr.walk_id}: floor {tr.floor} (p {tr.floor_probability:.3f}), {tr.times_s.size} steps"
        if tr.header_floor and tr.header_floor not in site.floors:
            line += (f" (its header says floor {tr.header_floor}, which this site does not have: the track assumes "
                     f"the walk is on one of the site's floors {site.floors}, and the floor probability is among "
                     "those only)")
        elif tr.header_floor and tr.header_floor != tr.floor:
            line += f" (its header says floor {tr.header_floor}: waypoint errors not comparable)"
        if wifi_fix_count(tr) == 0:
            # Without a fix nothing places the walk on the floor: the steps' shape is tracked, not
            # their position, and the sd written for each step is the floor-wide prior's.
            sd = float(np.median(np.sqrt(np.maximum(tr.covariance_m2[:, [0, 2]], 0.0)).max(axis=1)))
            line += (f", no WiFi fix available (no scan matched the site's fingerprints): the position is "
                     f"not located on the floor (median sd {sd:.0f} m), only the relative motion is tracked")
        if st:
            line += (f", error at {st['n_waypoints']} waypoints: mean {st['mean_m']:.2f} m, median "
                     f"{st['median_m']:.2f} m, p90 {st['p90_m']:.2f} m")
        print(line)
    if not tracks:
        print(f"error: no walk could be tracked; nothing written to {args.output}", file=sys.stderr)
        return 2
    write_tracks(args.output, tracks, str(args.site))
    print(f"written: {args.output}")
    if args.html:
        print(f"viewer: {site.write_viewer_html(args.html, tracks, title=f'indoorloc track: {Path(args.site).name}')}")
    if failed:
        print(f"error: {failed} of {len(args.walks)} walks not tracked (named above); the others are written",
              file=sys.stderr)
        return 1
    return 0


def cmd_live(args: argparse.Namespace) -> int:
    from indoorloc.fusion import live, live_stream
    from indoorloc.fusion.site import Site
    from indoorloc.io.atomic_file import write_text_atomic

    site = Site.open(args.site)
    floor = args.floor
    if floor is None:
        if len(site.floors) != 1:
            raise ValueError(f"indoorloc: argument '--floor': the site has {len(site.floors)} floors "
                             f"({', '.join(site.floors)}): name the one to track on")
        floor = site.floors[0]
    if floor not in site.floors:
        raise ValueError(f"indoorloc: argument '--floor': {floor!r} is not a floor of {args.site} "
                         f"({', '.join(site.floors)})")
    tracker = site.live(floor)
    origin = site.floor_models(floor).origin_lon_lat
    lines: list = []
    to_stdout = args.output in (None, "-")

    def write(record: dict) -> None:
        text = json.dumps(record)
        if to_stdout:
            print(text, flush=True)   # a live consumer reads each estimate as it comes
        else:
            lines.append(text)        # a file is written whole at the end (never half-written)

    def warn(message: str) -> None:
        print(f"warning: {message}", file=sys.stderr)

    # The input is opened (a walk read) before anything is written: a missing or unreadable one is
    # an error naming the argument, with no output at all.
    if args.walk is not None:
        from indoorloc.io.ilc2020 import read_ilc_walk

        walk = read_ilc_walk(args.walk)
        source = ((f"event {k}", ev, None) for k, ev in enumerate(live.walk_events(walk, beacons=True)))
        handle = None
    elif args.events in (None, "-"):
        handle = None
        source = live_stream.numbered_lines(sys.stdin)
    else:
        try:
            handle = open(args.events, encoding="utf-8")
        except OSError as exc:
            raise ValueError(f"indoorloc: argument '--events': {args.events}: {exc.strerror or exc}") from None
        source = live_stream.numbered_lines(handle)
    write(live_stream.header_record(floor, origin))
    try:
        summary = live_stream.run(tracker, source, write, origin, warn)
    finally:
        if handle is not None:
            handle.close()
    u = tracker.live_session.summary
    if summary.estimates == 0:
        # Nothing located the phone: no estimate is written rather than a file that looks like a track.
        why = ("no event could be used" if summary.events == 0 else
               f"{summary.events} events but no step detected and no WiFi fix applied (a phone that does not move "
               "needs WiFi scans that match the site's fingerprints)")
        print(f"error: no estimate: {why}" + ("" if to_stdout else f"; nothing written to {args.output}"),
              file=sys.stderr)
        return 2
    if not to_stdout:
        write_text_atomic(args.output, "".join(t + "\n" for t in lines))
    if not args.quiet:
        print(f"live: {summary.events} events, {u['steps']} steps detected and {u['standing_steps']} standing, "
              f"{u['fixes']} WiFi fixes applied ({u['pending_fixes']} pending), {summary.estimates} estimates"
              + ("" if to_stdout else f" written to {args.output}")
              + (f"; {summary.skipped} lines skipped (named above)" if summary.skipped else ""), file=sys.stderr)
    return 1 if summary.skipped else 0


def add_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    p = sub.add_parser("site", help="a site model (one SQLite file) built from survey walks")
    ssub = p.add_subparsers(dest="site_command", required=True)
    b = ssub.add_parser("build", parents=[quiet_parent()],
                        help="build SITE.db from a survey folder (ILC 2020 SITE/FLOOR/path_data_files or Kaggle "
                             "2021 train/SITE/FLOOR + metadata/SITE/FLOOR) from its walks with waypoints (others skipped, listed)")
    b.add_argument("survey_dir")
    b.add_argument("-o", "--output", required=True, help="the site file to write (replaced only on success)")
    b.add_argument("--floors", nargs="+", default=None, help="floor folders (default: every floor folder with walks and a plan, in "
                   "building order; one with walks but no plan is skipped with a warning, an error when named here)")
    b.add_argument("--coverage", default=None, metavar="DIR",
                   help="folder of the coverage map PNGs (default: SITE_coverage beside the site file)")
    b.add_argument("--no-coverage", action="store_true", help="no coverage maps")
    b.add_argument("--lowo", action="store_true",
                   help="also the expected error: each survey walk tracked on a site without it (slower)")
    b.set_defaults(func=cmd_build)
    a = ssub.add_parser("add", parents=[quiet_parent()], help="add survey walks (with waypoints) to a site")
    a.add_argument("site")
    a.add_argument("walks", nargs="+", metavar="WALK")
    a.add_argument("--floor", default=None, help="floor of the walks (default: each walk's FloorName header)")
    a.set_defaults(func=cmd_add)
    g = ssub.add_parser("grow", parents=[quiet_parent()],
                        help="add walks WITHOUT waypoints: fingerprints placed by the smoothed track where confident, "
                             "at a lower weight")
    g.add_argument("site")
    g.add_argument("walks", nargs="+", metavar="WALK")
    g.add_argument("--floor", default=None, help="floor name or 'auto' (default: each walk's FloorName header, else auto)")
    g.add_argument("--max-sd-m", type=float, default=None,
                   help="largest posterior sd [m] of a position used (default: fusion.site.GROW_MAX_SD_M)")
    g.add_argument("--weight", type=float, default=None,
                   help="weight of the grown fingerprints in (0, 1] (default: fusion.site.GROW_WEIGHT)")
    g.set_defaults(func=cmd_grow)
    i = ssub.add_parser("info", parents=[quiet_parent()], help="provenance and per-floor summary of a site")
    i.add_argument("site")
    i.add_argument("--json", action="store_true", help="print the JSON (docs/your_building.md)")
    i.set_defaults(func=cmd_info)


def add_track_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    t = sub.add_parser("track", parents=[quiet_parent()],
                       help="track walks with a site model; GeoJSON, CSV or JSON by the output's extension")
    t.add_argument("walks", nargs="+", metavar="WALK")
    t.add_argument("--site", required=True, help="the site file (indoorloc site build)")
    t.add_argument("--floor", default=None,
                   help="floor name, or 'auto' to identify it (default: the walk's FloorName header, else auto)")
    t.add_argument("--smooth", action=argparse.BooleanOptionalAction, default=True,
                   help="forward-backward smoother (default); --no-smooth: the causal filter")
    t.add_argument("-o", "--output", required=True, help="OUT.geojson, OUT.csv or OUT.json")
    t.add_argument("--html", default=None, metavar="VIEW.html",
                   help="also write the browser viewer: one offline HTML page with the tracks on the floor plan")
    t.set_defaults(func=cmd_track)


def add_live_parser(sub: argparse._SubParsersAction, quiet_parent) -> None:
    v = sub.add_parser("live", parents=[quiet_parent()],
                       help="the live tracker on a stream of phone events (NDJSON in, one estimate per step out)")
    v.add_argument("--site", required=True, help="the site file (indoorloc site build)")
    v.add_argument("--floor", default=None, help="floor name (default: the site's only floor)")
    src = v.add_mutually_exclusive_group()
    src.add_argument("--events", default=None, metavar="FILE",
                     help="events, one JSON object per line, format indoorloc-live-events 1 (docs/your_building.md); "
                          "'-' or absent: standard input")
    src.add_argument("--walk", default=None, metavar="WALK.txt",
                     help="replay a recorded walk's events (ILC 2020 text file) instead")
    v.add_argument("-o", "--output", default=None, metavar="OUT.ndjson",
                   help="write the estimates here, whole at the end (default: standard output, one line per step "
                        "as it comes)")
    v.set_defaults(func=cmd_live)
