"""The runner behind ``indoorloc demo``.

The registry itself (``register_demo``, :class:`DemoContext`, :class:`DemoSection`) lives in the
leaf module :mod:`indoorloc.registry`, so that experiments register into it without importing
this module. This module imports the built-in experiment modules (which registers their demos),
runs them and writes ``report.md`` that links every section and figure.
"""

from __future__ import annotations

import datetime as _dt
import platform
import time
from pathlib import Path
from typing import List, Optional, Sequence

from indoorloc import __version__
from indoorloc import progress
from indoorloc.registry import DemoContext, DemoSection, registered_demos


def _load_builtin_demos() -> None:
    # The table of built-in demos: importing an experiment module registers its demo in
    # indoorloc.registry. A new subsystem adds its demo module here.
    from indoorloc.experiments import analog_demo  # noqa: F401
    from indoorloc.experiments import core_resampling  # noqa: F401
    from indoorloc.experiments import fusion_synthetic  # noqa: F401
    from indoorloc.experiments import mapmatch_reproduce  # noqa: F401
    from indoorloc.experiments import network_reproduce  # noqa: F401
    from indoorloc.experiments import pdr_demo  # noqa: F401
    from indoorloc.experiments import wifi_simulation  # noqa: F401


def available_demos() -> List[str]:
    """Names of the registered demos, in registration order."""
    _load_builtin_demos()
    return list(registered_demos())


def run_demos(out_dir: Path, names: Optional[Sequence[str]] = None, seed: int = 0, quick: bool = False) -> Path:
    """Run the demos ``names`` (default: all) and write ``out_dir/report.md``; return its path."""
    _load_builtin_demos()
    demos = registered_demos()
    selected = list(demos) if not names else list(names)
    unknown = [n for n in selected if n not in demos]
    if unknown:
        raise ValueError(
            f"indoorloc: argument 'names': unknown demo(s) {unknown}; available: {list(demos)}"
        )
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    ctx = DemoContext(out_dir=out_dir, seed=seed, quick=quick)
    parts = [
        "# indoorloc demo report",
        "",
        f"indoorloc {__version__}, Python {platform.python_version()}, "
        f"{platform.machine()}, {_dt.datetime.now().isoformat(timespec='seconds')}, seed {seed}"
        + (" (quick mode: fewer Monte Carlo runs)." if quick else "."),
        "",
    ]
    progress.log(f"demo: {len(selected)} sections ({', '.join(selected)}), report in {out_dir}")
    for i, name in enumerate(selected, 1):
        entry = demos[name]
        progress.log(f"demo: [{i}/{len(selected)}] {name} started")
        start = time.perf_counter()
        section: DemoSection = entry.fn(ctx)
        elapsed = time.perf_counter() - start
        progress.log(f"demo: [{i}/{len(selected)}] {name} done in {elapsed:.1f} s")
        parts += [f"## {entry.title} (`{name}`)", "", section.markdown.strip(), ""]
        for fig in section.figures:
            parts += [f"![{fig.stem}]({fig.name})", ""]
        parts += [f"_Section ran in {elapsed:.1f} s._", ""]
    report = out_dir / "report.md"
    report.write_text("\n".join(parts), encoding="utf-8")
    return report
