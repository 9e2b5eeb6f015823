"""The command line the floor studies share (``floor_identification_study``, ``floor_change_study``):
``--data-root``, ``--floors``, ``--seed`` (the fold assignment, as ``fusion evaluate --seed``; one or
several: a study may pool the walks of several fold assignments), ``--json``, ``--markdown``; the
study computed, timed, its Markdown
printed, and the JSON and Markdown written atomically (``io.atomic_file.write_text_atomic``)."""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any, Callable, Dict, List, Optional, Sequence

from indoorloc.io.atomic_file import write_text_atomic
from indoorloc import progress as _progress


def run_study(argv: Optional[Sequence[str]], description: str,
              compute: Callable[[Optional[str], Sequence[str], List[int]], Dict[str, Any]],
              markdown: Callable[[Dict[str, Any]], str],
              jsonable: Callable[[Dict[str, Any]], Any] = lambda result: result) -> int:
    """Parses ``argv``, runs ``compute(data_root, floors, seeds)`` (``seeds`` the list of ``--seed``
    values; its result gains ``seconds``, the wall time [s], and ``seeds``), prints ``markdown(result)`` and writes ``--json`` (``jsonable(result)``) and
    ``--markdown`` if given. Returns the exit status: 0, or 2 after one ``error:`` line on stderr
    when ``compute`` raised ValueError or OSError (a missing folder or floor)."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--data-root", default=None)
    ap.add_argument("--floors", nargs="*", default=[])
    ap.add_argument("--json", default=None)
    ap.add_argument("--markdown", default=None)
    ap.add_argument("--seed", type=int, nargs="+", default=[0],
                    help="fold assignment seed(s) (default 0, as fusion evaluate); several: their walks pooled")
    ap.add_argument("--quiet", action="store_true", help="no progress bars or lines")
    args = ap.parse_args(argv)
    _progress.set_quiet(args.quiet)
    if any(v < 0 for v in args.seed) or len(set(args.seed)) != len(args.seed):
        ap.error(f"argument --seed: expected distinct seeds >= 0, got {args.seed}")
    tic = time.perf_counter()
    try:
        result = compute(args.data_root, args.floors, list(args.seed))
    except (ValueError, OSError) as exc:  # a bad folder or floor: one line, as the indoorloc CLI
        print(f"error: {exc}", file=sys.stderr)
        return 2
    result["seeds"] = list(args.seed)
    result["seconds"] = round(time.perf_counter() - tic, 1)
    text = markdown(result)
    print(text)
    if args.json:
        write_text_atomic(args.json, json.dumps(jsonable(result), indent=1) + "\n")
    if args.markdown:
        write_text_atomic(args.markdown, text + "\n")
    return 0
