"""Progress for long Python-level work (Monte Carlo runs, sweeps, dataset evaluation, reports).

Two forms, one switch:

- a bar (tqdm) on an interactive terminal;
- plain lines when output goes to a file or a pipe (``make demo > log``, CI logs, ``nohup``):
  a loop prints a line at most every ``LINE_INTERVAL_S`` seconds and one when it ends, each
  with the elapsed time, and :func:`log` / :func:`stage` print a line per finished part.

Lines are printed only when the command line turned them on (``configure(lines=True)``, done by
``indoorloc`` itself), so that library calls from a user's script or notebook stay silent.
Everything is off under ``--quiet`` (``set_quiet(True)``). Bars are also off when the ``CI``
environment variable is set. All output goes to stderr, so stdout stays clean for ``--json -``.
"""

from __future__ import annotations

import os
import sys
import time
from contextlib import contextmanager
from typing import Iterable, Iterator, Optional, TypeVar

from tqdm import tqdm

T = TypeVar("T")
_quiet = False
_lines = False
#: At most one line per this many seconds from a loop in line mode (plus the final line).
LINE_INTERVAL_S = 30.0


def set_quiet(quiet: bool) -> None:
    """Turn every progress bar and line of this process off (True) or back to automatic (False)."""
    global _quiet
    _quiet = bool(quiet)


def configure(quiet: bool = False, lines: bool = True) -> None:
    """Set by the command line: ``quiet`` silences everything, ``lines`` prints progress lines
    when no bar can be shown (stderr not a terminal, or ``CI`` set)."""
    global _lines
    set_quiet(quiet)
    _lines = bool(lines)


def enabled() -> bool:
    """True when progress bars are shown."""
    return not _quiet and not os.environ.get("CI") and sys.stderr.isatty()


def lines_enabled() -> bool:
    """True when progress is printed as plain lines (no bar possible, lines turned on)."""
    return not _quiet and _lines and not enabled()


def _format_seconds(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.1f} s"
    return f"{seconds / 60:.1f} min"


def log(message: str) -> None:
    """Print one progress line (a finished part, with its time) unless quiet.

    Shown as a line in both modes (through ``tqdm.write`` so that a running bar is not broken);
    in a library call outside the command line it is shown only on a terminal."""
    if _quiet or not (_lines or enabled()):
        return
    stamp = time.strftime("%H:%M:%S")
    tqdm.write(f"[{stamp}] {message}", file=sys.stderr)
    sys.stderr.flush()


@contextmanager
def stage(description: str) -> Iterator[None]:
    """Time a part of a long command and log ``"<description>: done in <time>"`` when it ends."""
    start = time.perf_counter()
    yield
    log(f"{description}: done in {_format_seconds(time.perf_counter() - start)}")


def _lines_progress(iterable: Iterable[T], total: Optional[int], desc: str) -> Iterator[T]:
    start = last = time.perf_counter()
    count = 0
    label = desc or "progress"
    for item in iterable:
        yield item
        count += 1
        now = time.perf_counter()
        if now - last >= LINE_INTERVAL_S and (total is None or count < total):
            of = f"/{total}" if total is not None else ""
            log(f"{label}: {count}{of} after {_format_seconds(now - start)}")
            last = now
    log(f"{label}: {count} done in {_format_seconds(time.perf_counter() - start)}")


def progress(iterable: Iterable[T], total: Optional[int] = None, desc: str = "") -> Iterable[T]:
    """Wrap ``iterable`` in a bar (terminal) or in progress lines (command line, no terminal)."""
    if lines_enabled():
        if total is None:
            try:
                total = len(iterable)  # type: ignore[arg-type]
            except TypeError:
                total = None
        return _lines_progress(iterable, total, desc)
    return tqdm(iterable, total=total, desc=desc, disable=not enabled(), leave=False)


class Ticker:
    """Progress for work that reports completions by callback (Dask tasks, walks of an evaluation):
    call :meth:`tick` once per finished item and :meth:`close` at the end. A bar on a terminal,
    lines (at most one per ``LINE_INTERVAL_S`` plus a final one) in line mode, nothing otherwise."""

    def __init__(self, total: Optional[int] = None, desc: str = "") -> None:
        self.total, self.desc, self.count = total, desc or "progress", 0
        self._start = self._last = time.perf_counter()
        self._bar = tqdm(total=total, desc=desc, leave=False) if enabled() else None
        self._lines = lines_enabled()

    def tick(self) -> None:
        self.count += 1
        if self._bar is not None:
            self._bar.update(1)
        elif self._lines:
            now = time.perf_counter()
            if now - self._last >= LINE_INTERVAL_S:
                of = f"/{self.total}" if self.total is not None else ""
                log(f"{self.desc}: {self.count}{of} after {_format_seconds(now - self._start)}")
                self._last = now

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        elif self._lines:
            log(f"{self.desc}: {self.count} done in {_format_seconds(time.perf_counter() - self._start)}")
            self._lines = False
