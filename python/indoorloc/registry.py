"""The leaf of indoorloc's Python layer: the demo registry and where the real datasets are.

Every layer may import this module and it imports nothing from indoorloc, so it can never close
an import cycle (``tests/python/test_layering.py`` checks both; layers in docs/architecture.md).

- Demos: each subsystem registers one quick experiment on built-in data with
  :func:`register_demo`. The function receives a :class:`DemoContext` (output folder, seed) and
  returns a :class:`DemoSection` (markdown text and the PNG files it wrote). The runner,
  :mod:`indoorloc.demo`, imports the built-in experiment modules (which registers them) and writes
  the report.
- Data folders: :func:`default_data_root` (WiFi datasets) and :func:`default_pdr_root` (foot and
  lower-back IMU recordings), shared by the CLI and the demos.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Dict, List


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


@dataclass(frozen=True)
class DemoEntry:
    """One registered demo: subsystem name, section title and the function."""

    name: str
    title: str
    fn: Callable[[DemoContext], DemoSection]


_DEMOS: Dict[str, DemoEntry] = {}


def register_demo(name: str, title: str):
    """Decorator: register ``fn(ctx) -> DemoSection`` as the demo of subsystem ``name``."""

    def decorate(fn: Callable[[DemoContext], DemoSection]):
        if name in _DEMOS:
            raise ValueError(f"indoorloc: demo {name!r} is registered twice")
        _DEMOS[name] = DemoEntry(name, title, fn)
        return fn

    return decorate


def registered_demos() -> Dict[str, DemoEntry]:
    """The demos registered so far, by name, in registration order (a copy)."""
    return dict(_DEMOS)


def default_data_root() -> Path:
    """Where the real WiFi datasets are: $INDOORLOC_WIFI_DATA, else the first `shared/data/wifi`
    found beside the working folder or one of its parents (a clone sits next to `shared/`), else
    beside the package's own folder or one of its parents (a source tree run from elsewhere)."""
    env = os.environ.get("INDOORLOC_WIFI_DATA")
    if env:
        return Path(env)
    here = Path.cwd().resolve()
    package = Path(__file__).resolve().parent
    for folder in (here, *here.parents, *package.parents):
        candidate = folder / "shared" / "data" / "wifi"
        if candidate.is_dir():
            return candidate
    return here / "shared" / "data" / "wifi"


def default_pdr_root() -> Path:
    """Where the real IMU recordings are: the `pdr` folder beside :func:`default_data_root`."""
    return default_data_root().parent / "pdr"


__all__ = [
    "DemoContext",
    "DemoEntry",
    "DemoSection",
    "default_data_root",
    "default_pdr_root",
    "register_demo",
    "registered_demos",
]
