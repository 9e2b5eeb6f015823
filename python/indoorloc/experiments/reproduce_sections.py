"""The sections of ``indoorloc reproduce``: one per paper, run once, kept on disk, resumed.

Each paper's experiment module provides

    reproduce_tables(ctx: ReproduceContext) -> List[Table]
    expected_seconds(runs: Optional[int]) -> float   # full size on 2 cores, for the start banner

A finished section is written to ``<out>/sections/<paper>.json`` with the settings it ran with
(runs, seed, quick). It is not run again while those settings are unchanged, unless the caller
asks (``rerun``); a section that failed leaves no file and runs again next time. Figures go to
``<out>/figures/<paper>/``.
"""

from __future__ import annotations

import importlib
import json
import os
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence

from indoorloc.experiments.reproduce_cells import ReproduceContext, Table


@dataclass(frozen=True)
class Section:
    """One paper's section: its index in shared/papers/README.md, title and experiment module."""

    paper: str
    title: str
    module: str


SECTIONS: Dict[str, Section] = {
    s.paper: s for s in (
        Section("000", "mapmatch: indoor localization by particle map matching (El Mokhtari et al.)",
                "indoorloc.experiments.mapmatch_reproduce_tables"),
        Section("001", "analog: exemplar-based HMM (Lguensat et al., EUSIPCO 2016)",
                "indoorloc.experiments.analog_reproduce"),
        Section("002", "pdr: pedestrian dead-reckoning with a foot-mounted MEMS IMU (Jiménez et al., WISP 2009)",
                "indoorloc.experiments.pdr_reproduce"),
        Section("003", "network: network approach vs state-space approach for INS/GPS gravimetry (Térmens, Colomina)",
                "indoorloc.experiments.network_reproduce"),
        Section("004", "wifi: indoor positioning using the IEEE 802.11 infrastructure (Jacquet et al., RR-7294)",
                "indoorloc.experiments.wifi_reproduce"),
    )
}


def _module(section: Section):
    # Imported on demand: a section's module (and its data) is loaded only when it runs.
    return importlib.import_module(section.module)


def check_papers(papers: Optional[Sequence[str]]) -> List[str]:
    """The papers to run, in index order; raises ValueError naming an unknown one."""
    if not papers:
        return list(SECTIONS)
    unknown = [p for p in papers if p not in SECTIONS]
    if unknown:
        raise ValueError(f"indoorloc: argument 'papers': unknown paper(s) {unknown}; expected some of {list(SECTIONS)}")
    return [p for p in SECTIONS if p in set(papers)]


def expected_seconds(paper: str, runs: Optional[int], quick: bool = False) -> float:
    """The section's own estimate of its run time on 2 cores [s] (quick runs: a few seconds)."""
    if quick:
        return 10.0
    return float(_module(SECTIONS[paper]).expected_seconds(runs))


def section_path(out_dir: Path, paper: str) -> Path:
    return Path(out_dir) / "sections" / f"{paper}.json"


def load_finished(out_dir: Path, paper: str, settings: Dict[str, Any]) -> Optional[Dict[str, Any]]:
    """The section's result on disk if it ran with the same ``settings``; else None."""
    path = section_path(out_dir, paper)
    if not path.is_file():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if data.get("settings") == settings else None


def run_section(paper: str, out_dir: Path, settings: Dict[str, Any], *, threads: int = 0, scheduler: Any = None,
                log: Callable[[str], None] = print) -> Dict[str, Any]:
    """Run one paper's section now and write ``sections/<paper>.json`` (atomically).

    ``settings``: ``{"runs": int or None, "seed": int, "quick": bool}``. Returns the section dict.
    Exceptions propagate (the caller reports them; nothing is written for a failed section)."""
    section = SECTIONS[paper]
    figure_dir = Path(out_dir) / "figures" / paper
    figure_dir.mkdir(parents=True, exist_ok=True)
    ctx = ReproduceContext(out_dir=figure_dir, runs=settings.get("runs"), threads=threads,
                           seed=int(settings.get("seed", 0)), scheduler=scheduler, log=log,
                           quick=bool(settings.get("quick", False)))
    start = time.perf_counter()
    tables: List[Table] = _module(section).reproduce_tables(ctx)
    seconds = time.perf_counter() - start
    root = Path(out_dir).resolve()
    dicts = []
    for t in tables:
        d = t.to_dict()
        # Figure paths relative to the report folder, so that the folder can be moved.
        d["figures"] = [os.path.relpath(Path(f).resolve(), root) for f in t.figures]
        dicts.append(d)
    data = {"paper": paper, "title": section.title, "seconds": seconds, "settings": settings, "tables": dicts}
    path = section_path(out_dir, paper)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(data, indent=1), encoding="utf-8")
    tmp.replace(path)
    return data


def run_all(papers: Sequence[str], out_dir: Path, settings: Dict[str, Any], *, rerun: Sequence[str] = (),
            threads: int = 0, scheduler: Any = None, log: Callable[[str], None] = print) -> Dict[str, Any]:
    """Run (or resume) the sections ``papers``; returns ``{"sections": [...], "failed": {paper: error}}``.

    A failed section is reported and the others still run, so that one broken dataset does not
    cost the whole report."""
    sections, failed = [], {}
    for i, paper in enumerate(papers, 1):
        tag = f"reproduce: [{i}/{len(papers)}] paper {paper}"
        done = None if paper in rerun else load_finished(out_dir, paper, settings)
        if done is not None:
            log(f"{tag}: finished earlier ({done['seconds']:.0f} s), kept (--rerun {paper} to run it again)")
            sections.append(done)
            continue
        log(f"{tag} ({SECTIONS[paper].title.split(':')[0]}) started")
        start = time.perf_counter()
        try:
            data = run_section(paper, out_dir, settings, threads=threads, scheduler=scheduler, log=log)
        except Exception as exc:  # noqa: BLE001 - reported, the other sections still run
            failed[paper] = f"{type(exc).__name__}: {exc}"
            log(f"{tag} FAILED after {time.perf_counter() - start:.0f} s: {failed[paper]}")
            log(traceback.format_exc(limit=8))
            continue
        log(f"{tag} done in {data['seconds']:.0f} s")
        sections.append(data)
    return {"sections": sections, "failed": failed}
