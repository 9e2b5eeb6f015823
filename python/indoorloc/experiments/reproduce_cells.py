"""One reproduced figure of a paper: the paper's single value beside the distribution of our runs.

A paper reports one number per table cell; a Monte Carlo gives one number per run. A ``Cell``
keeps every per-run value with the seed that produced it, and summarises them the same way
everywhere in ``indoorloc reproduce``: mean ± sd, median, interquartile range, and the
percentile of our runs at which the paper's figure falls, with a one-line verdict.

Percentile convention: the share of our runs strictly below the paper's value plus half the share
equal to it, in percent (the "mid-rank" percentile, so that a paper value equal to every run is at
50 %, not at 0 or 100 %).

Verdict: "inside the IQR" when the paper's value lies within [Q1, Q3] of our runs, "above"/"below"
otherwise (the paper's value is above/below our IQR). With fewer than 4 runs the IQR is not
meaningful and the verdict says so.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

VERDICT_INSIDE = "inside the IQR"
VERDICT_ABOVE = "paper above our IQR"
VERDICT_BELOW = "paper below our IQR"
VERDICT_NO_PAPER = "no paper figure"
VERDICT_FEW_RUNS = "too few runs for an IQR"
MIN_RUNS_FOR_IQR = 4


@dataclass
class Cell:
    """One table cell: the paper's value and our per-run values.

    Attributes
    ----------
    row, column : str
        Where the cell sits in its table (e.g. row "AnFB, N = 1000", column "M = 10^5").
    values : sequence of float
        One value per run (NaN allowed for a run that produced no value: counted, not summarised).
    seeds : sequence of int
        The seed (or realisation index) of each run, same length as ``values``.
    paper : float or None
        The paper's figure for this cell (None when the paper gives none).
    unit : str
        Unit of the values ("m", "%", "" for dimensionless).
    note : str
        Anything a reader needs to interpret the cell (set-up differences, the paper's wording).
    """

    row: str
    column: str
    values: Sequence[float]
    seeds: Sequence[int]
    paper: Optional[float] = None
    unit: str = ""
    note: str = ""

    def __post_init__(self) -> None:
        self.values = [float(v) for v in self.values]
        self.seeds = [int(s) for s in self.seeds]
        if len(self.values) != len(self.seeds):
            raise ValueError(
                f"indoorloc: argument 'seeds': {len(self.seeds)} seeds for {len(self.values)} values "
                f"(cell {self.row!r} / {self.column!r})")
        if self.paper is not None:
            self.paper = float(self.paper)

    def summary(self) -> Dict[str, object]:
        """Statistics of the runs and where the paper's value falls among them (a JSON-ready dict)."""
        v = np.asarray(self.values, dtype=float)
        finite = v[np.isfinite(v)]
        out: Dict[str, object] = {
            "row": self.row, "column": self.column, "unit": self.unit, "paper": self.paper,
            "runs": int(v.size), "runs_without_value": int(v.size - finite.size),
            "seeds": list(self.seeds), "values": [None if not np.isfinite(x) else float(x) for x in v],
            "note": self.note,
        }
        if finite.size == 0:
            out.update(mean=None, sd=None, median=None, q1=None, q3=None, paper_percentile=None,
                       verdict="no runs")
            return out
        q1, median, q3 = (float(x) for x in np.percentile(finite, [25, 50, 75]))
        out.update(
            mean=float(finite.mean()),
            sd=float(finite.std(ddof=1)) if finite.size > 1 else 0.0,
            median=median, q1=q1, q3=q3,
            min=float(finite.min()), max=float(finite.max()),
        )
        if self.paper is None:
            out.update(paper_percentile=None, verdict=VERDICT_NO_PAPER)
            return out
        out["paper_percentile"] = paper_percentile(finite, self.paper)
        if finite.size < MIN_RUNS_FOR_IQR:
            out["verdict"] = VERDICT_FEW_RUNS
        elif self.paper > q3:
            out["verdict"] = VERDICT_ABOVE
        elif self.paper < q1:
            out["verdict"] = VERDICT_BELOW
        else:
            out["verdict"] = VERDICT_INSIDE
        return out


def paper_percentile(values: np.ndarray, paper: float) -> float:
    """Mid-rank percentile [%] of ``paper`` among ``values`` (finite, non-empty)."""
    values = np.asarray(values, dtype=float)
    below = np.count_nonzero(values < paper)
    equal = np.count_nonzero(values == paper)
    return float(100.0 * (below + 0.5 * equal) / values.size)


@dataclass
class Table:
    """A paper's table (or figure) as reproduced: cells plus the text that explains the set-up."""

    paper: str  # "000" .. "004", the index in shared/papers/README.md
    name: str  # "Table I", "Fig. 3", "§5.7 paths"
    title: str
    cells: List[Cell] = field(default_factory=list)
    setup: str = ""  # how the runs were made: sizes, seeds, our choices where the paper is silent
    figures: List[str] = field(default_factory=list)  # image paths written by the section

    def to_dict(self) -> Dict[str, object]:
        return {
            "paper": self.paper, "name": self.name, "title": self.title, "setup": self.setup,
            "figures": list(self.figures), "cells": [c.summary() for c in self.cells],
        }


@dataclass
class ReproduceContext:
    """What a paper's reproduce section gets from ``indoorloc reproduce``.

    Attributes
    ----------
    out_dir : Path
        Folder the section writes its figures into (PNG); created by the runner.
    runs : int or None
        Monte Carlo runs / realisations per cell; None = the section's full-size default.
    threads : int
        Threads for C++ batches (0 = all cores).
    seed : int
        Base seed; a section derives every run's seed from it (documented in its Table.setup).
    scheduler : None, str or distributed.Client
        None = in process; an address or a Client = run the section's tasks through
        ``indoorloc.sweep.run_sweep`` on that Dask cluster.
    log : callable(str)
        Prints one progress line (with the time) whether or not stdout is a terminal.
    quick : bool
        Shrink every size (runs, durations, catalogs, datasets) to a smoke test of the same code
        paths, for the tests; the figures are then not comparable with the paper's.
    """

    out_dir: Path
    runs: Optional[int] = None
    threads: int = 0
    seed: int = 0
    scheduler: object = None
    log: Callable[[str], None] = print
    quick: bool = False

    def figure_path(self, name: str) -> Path:
        """Path of a PNG figure named ``name`` inside the section's folder."""
        return Path(self.out_dir) / f"{name}.png"

    def runs_or(self, default: int) -> int:
        """The requested run count, or ``default`` (the section's full size) when none was given."""
        return int(self.runs) if self.runs is not None else int(default)
