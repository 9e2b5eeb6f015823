"""Progress bars for long Python-level loops (Monte Carlo runs, sweeps, dataset evaluation).

Shown on an interactive terminal only: off under ``--quiet`` (``set_quiet(True)``), when the
``CI`` environment variable is set, or when stderr is not a terminal.
"""

from __future__ import annotations

import os
import sys
from typing import Iterable, Optional, TypeVar

from tqdm import tqdm

T = TypeVar("T")
_quiet = False


def set_quiet(quiet: bool) -> None:
    """Turn every progress bar of this process off (True) or back to automatic (False)."""
    global _quiet
    _quiet = bool(quiet)


def enabled() -> bool:
    """True when progress bars are shown."""
    return not _quiet and not os.environ.get("CI") and sys.stderr.isatty()


def progress(iterable: Iterable[T], total: Optional[int] = None, desc: str = "") -> Iterable[T]:
    """Wrap ``iterable`` in a progress bar when bars are enabled."""
    return tqdm(iterable, total=total, desc=desc, disable=not enabled(), leave=False)
