"""The demo registry behind ``indoorloc demo``.

Each subsystem registers one quick experiment on built-in data with ``@register_demo``. The
function receives a :class:`DemoContext` (output folder, seed) and returns a
:class:`DemoSection` (markdown text and the PNG files it wrote). ``run_demos`` runs them all and
writes ``report.md`` that links every section and figure.
"""

from __future__ import annotations

import datetime as _dt
import platform
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence

from indoorloc import __version__


@dataclass
class DemoContext:
    """What a demo gets: the folder to write figures into and a base seed."""

    out_dir: Path
    seed: int = 0
    #: Fewer Monte Carlo runs and cross-validation folds (tests, smoke runs); same code paths.
    quick: bool = False

    def figure_path(self, name: str) -> Path:
        """Path of a PNG figure named ``name`` inside the report folder."""
        return self.out_dir / f"{name}.png"


@dataclass
class DemoSection:
    """What a demo returns: a markdown body (no heading) and the figures it saved."""

    markdown: str
    figures: List[Path] = field(default_factory=list)


@dataclass
class _Entry:
    name: str
    title: str
    fn: Callable[[DemoContext], DemoSection]


_REGISTRY: Dict[str, _Entry] = {}


def register_demo(name: str, title: str):
    """Decorator: register ``fn(ctx) -> DemoSection`` as the demo of subsystem ``name``."""

    def decorate(fn: Callable[[DemoContext], DemoSection]):
        if name in _REGISTRY:
            raise ValueError(f"indoorloc: demo {name!r} is registered twice")
        _REGISTRY[name] = _Entry(name, title, fn)
        return fn

    return decorate


def _load_builtin_demos() -> None:
    # Importing the experiment modules registers their demos.
    from indoorloc.experiments import analog_demo  # noqa: F401
    from indoorloc.experiments import core_resampling  # noqa: F401
    from indoorloc.experiments import mapmatch_reproduce  # noqa: F401
    from indoorloc.experiments import network_reproduce  # noqa: F401
    from indoorloc.experiments import pdr_demo  # noqa: F401
    from indoorloc.experiments import wifi_simulation  # noqa: F401


def available_demos() -> List[str]:
    """Names of the registered demos, in registration order."""
    _load_builtin_demos()
    return list(_REGISTRY)


def run_demos(out_dir: Path, names: Optional[Sequence[str]] = None, seed: int = 0, quick: bool = False) -> Path:
    """Run the demos ``names`` (default: all) and write ``out_dir/report.md``; return its path."""
    _load_builtin_demos()
    selected = list(_REGISTRY) if not names else list(names)
    unknown = [n for n in selected if n not in _REGISTRY]
    if unknown:
        raise ValueError(
            f"indoorloc: argument 'names': unknown demo(s) {unknown}; available: {list(_REGISTRY)}"
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
    for name in selected:
        entry = _REGISTRY[name]
        start = time.perf_counter()
        section = entry.fn(ctx)
        elapsed = time.perf_counter() - start
        parts += [f"## {entry.title} (`{name}`)", "", section.markdown.strip(), ""]
        for fig in section.figures:
            parts += [f"![{fig.stem}]({fig.name})", ""]
        parts += [f"_Section ran in {elapsed:.1f} s._", ""]
    report = out_dir / "report.md"
    report.write_text("\n".join(parts), encoding="utf-8")
    return report
