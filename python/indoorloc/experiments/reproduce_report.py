"""The ``indoorloc reproduce`` report: Markdown, a self-contained HTML page, and one JSON.

Input: the finished sections, each a dict as written to ``sections/<paper>.json`` by
:mod:`indoorloc.experiments.reproduce_sections` (``{"paper", "title", "seconds", "settings",
"tables": [Table.to_dict(), ...]}``). Every number of the report comes from these dicts, so the
Markdown, the HTML and the JSON cannot disagree.

The HTML page embeds the figures (PNG as base64 data URIs) and has no external resources, so it
can be mailed or archived as one file.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import json
import math
import platform
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

from indoorloc.experiments.reproduce_cells import (
    VERDICT_ABOVE,
    VERDICT_BELOW,
    VERDICT_INSIDE,
)
from indoorloc.io.atomic_file import write_text_atomic

#: The schema version of report.json (bump on an incompatible change; documented in docs/reproduce.md).
SCHEMA_VERSION = 1
COLUMNS = ("row", "column", "paper", "ours: mean ± sd", "median", "IQR", "paper's percentile",
           "runs", "verdict")


def _num(x: Optional[float], digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    ax = abs(x)
    if ax >= 1e3 and float(x).is_integer():  # counts (unknowns, equations) in full
        return f"{x:,.0f}"
    if ax != 0 and (ax >= 1e5 or ax < 1e-3):
        return f"{x:.{digits}g}"
    if ax >= 100:
        return f"{x:,.1f}" if ax < 1e4 else f"{x:,.0f}"
    return f"{x:.{digits}g}" if ax < 1 else f"{x:.{max(digits - 1, 1)}f}"


def cell_columns(c: Dict[str, Any]) -> List[str]:
    """The table columns (``COLUMNS``) of one cell summary, as text."""
    unit = f" {c['unit']}" if c.get("unit") else ""
    if c.get("mean") is None:
        ours, median, iqr = "—", "—", "—"
    else:
        ours = f"{_num(c['mean'])} ± {_num(c['sd'])}{unit}"
        median = _num(c["median"])
        iqr = f"{_num(c['q1'])} – {_num(c['q3'])}"
    pct = c.get("paper_percentile")
    missing = f" ({c['runs_without_value']} without value)" if c.get("runs_without_value") else ""
    return [
        str(c["row"]), str(c["column"]),
        "—" if c.get("paper") is None else f"{_num(c['paper'])}{unit}",
        ours, median, iqr, "—" if pct is None else f"{pct:.0f} %",
        f"{c['runs']}{missing}", str(c["verdict"]),
    ]


def _seeds_text(seeds: Sequence[int]) -> str:
    seeds = list(seeds)
    if not seeds:
        return "none"
    if seeds == list(range(seeds[0], seeds[0] + len(seeds))):
        return f"{seeds[0]}..{seeds[-1]}" if len(seeds) > 1 else str(seeds[0])
    return ", ".join(str(s) for s in seeds[:8]) + (" …" if len(seeds) > 8 else "")


def verdict_counts(sections: Sequence[Dict[str, Any]]) -> Dict[str, Dict[str, int]]:
    """Per paper: number of cells inside / above / below our IQR, without a paper figure, other."""
    out: Dict[str, Dict[str, int]] = {}
    for s in sections:
        counts = {"inside": 0, "paper above": 0, "paper below": 0, "no paper figure": 0, "other": 0}
        for t in s["tables"]:
            for c in t["cells"]:
                v = c["verdict"]
                key = {VERDICT_INSIDE: "inside", VERDICT_ABOVE: "paper above",
                       VERDICT_BELOW: "paper below"}.get(v, "no paper figure" if c.get("paper") is None else "other")
                counts[key] += 1
        out[s["paper"]] = counts
    return out


def _header(settings: Dict[str, Any]) -> List[str]:
    from indoorloc import __version__

    return [
        f"indoorloc {__version__}, Python {platform.python_version()}, {platform.machine()}, "
        f"report written {_dt.datetime.now().isoformat(timespec='seconds')}; "
        + ", ".join(f"{k} {v}" for k, v in settings.items()) + ".",
    ]


EXPLANATION = (
    "Each cell: the paper's single figure beside the distribution of our runs (one value per seeded "
    "run, realisation, recording or test point: the `runs` column). *Paper's percentile*: the share of "
    "our runs below the paper's figure (ties count half). *Verdict*: whether the paper's figure lies "
    "inside the interquartile range of our runs, above it or below it (for an error, *paper below* "
    "means the paper did better than three quarters of our runs)."
)


def markdown(sections: Sequence[Dict[str, Any]], settings: Dict[str, Any]) -> str:
    """The whole report as Markdown (figures linked relative to the report folder)."""
    lines = ["# indoorloc reproduce: the five papers' tables", ""] + _header(settings) + ["", EXPLANATION, ""]
    lines += ["## Verdicts", "", "| paper | section | cells | inside IQR | paper above | paper below | no paper figure | "
              "other (one run, or no value) | run time |", "|---|---|---|---|---|---|---|---|---|"]
    counts = verdict_counts(sections)
    for s in sections:
        k = counts[s["paper"]]
        lines.append(f"| {s['paper']} | {s['title']} | {sum(k.values())} | {k['inside']} | {k['paper above']} | "
                     f"{k['paper below']} | {k['no paper figure']} | {k['other']} | {s['seconds']:.0f} s |")
    lines.append("")
    for s in sections:
        lines += [f"## Paper {s['paper']}: {s['title']}", ""]
        for t in s["tables"]:
            lines += [f"### {t['name']}: {t['title']}", ""]
            if t.get("setup"):
                lines += [t["setup"].strip(), ""]
            lines += ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
            for c in t["cells"]:
                lines.append("| " + " | ".join(x.replace("|", "\\|") for x in cell_columns(c)) + " |")
            lines.append("")
            seeds = {(_seeds_text(c["seeds"])) for c in t["cells"]}
            lines.append("Seeds / run indices: " + "; ".join(sorted(seeds)) + ".")
            notes = [f"*{c['row']} / {c['column']}*: {c['note']}" for c in t["cells"] if c.get("note")]
            if notes:
                lines += [""] + [f"- {n}" for n in notes]
            lines.append("")
            for fig in t.get("figures", []):
                lines += [f"![{Path(fig).stem}]({fig})", ""]
    return "\n".join(lines)


_CSS = """
body{font-family:system-ui,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:1em 0;font-size:0.9em}
th,td{border:1px solid #ccc;padding:0.25em 0.5em;text-align:left;vertical-align:top}
th{background:#f0f0f0} td.inside{background:#e6f4e6} td.above,td.below{background:#fbeaea}
img{max-width:100%;border:1px solid #ddd;margin:0.5em 0} p.setup{white-space:pre-wrap}
"""


def _img_tag(path: Path) -> str:
    if not path.is_file():
        return f"<p>(figure missing: {html.escape(str(path))})</p>"
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<img alt="{html.escape(path.stem)}" src="data:image/png;base64,{data}">'


def _verdict_class(v: str) -> str:
    return {VERDICT_INSIDE: "inside", VERDICT_ABOVE: "above", VERDICT_BELOW: "below"}.get(v, "")


def html_page(sections: Sequence[Dict[str, Any]], settings: Dict[str, Any], root: Path) -> str:
    """The report as one self-contained HTML page; figure paths are relative to ``root``."""
    e = html.escape
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>indoorloc reproduce</title>",
             f"<style>{_CSS}</style></head><body>",
             "<h1>indoorloc reproduce: the five papers' tables</h1>"]
    parts += [f"<p>{e(x)}</p>" for x in _header(settings)] + [f"<p>{e(EXPLANATION)}</p>"]
    parts.append("<h2>Verdicts</h2><table><tr><th>paper</th><th>section</th><th>cells</th><th>inside IQR</th>"
                 "<th>paper above</th><th>paper below</th><th>no paper figure</th><th>other (one run, or no value)</th>"
                 "<th>run time</th></tr>")
    counts = verdict_counts(sections)
    embedded: set = set()  # a figure shared by two tables is embedded once
    for s in sections:
        k = counts[s["paper"]]
        parts.append(f"<tr><td>{e(s['paper'])}</td><td>{e(s['title'])}</td><td>{sum(k.values())}</td>"
                     f"<td>{k['inside']}</td><td>{k['paper above']}</td><td>{k['paper below']}</td>"
                     f"<td>{k['no paper figure']}</td><td>{k['other']}</td><td>{s['seconds']:.0f} s</td></tr>")
    parts.append("</table>")
    for s in sections:
        parts.append(f"<h2>Paper {e(s['paper'])}: {e(s['title'])}</h2>")
        for t in s["tables"]:
            parts.append(f"<h3>{e(t['name'])}: {e(t['title'])}</h3>")
            if t.get("setup"):
                parts.append(f"<p class='setup'>{e(t['setup'].strip())}</p>")
            parts.append("<table><tr>" + "".join(f"<th>{e(c)}</th>" for c in COLUMNS) + "</tr>")
            for c in t["cells"]:
                cols = cell_columns(c)
                cls = _verdict_class(c["verdict"])
                parts.append("<tr>" + "".join(f"<td>{e(x)}</td>" for x in cols[:-1])
                             + f"<td class='{cls}'>{e(cols[-1])}</td></tr>")
            parts.append("</table>")
            notes = [f"{c['row']} / {c['column']}: {c['note']}" for c in t["cells"] if c.get("note")]
            if notes:
                parts.append("<ul>" + "".join(f"<li>{e(n)}</li>" for n in notes) + "</ul>")
            for fig in t.get("figures", []):
                if fig in embedded:
                    parts.append(f"<p>(figure {e(Path(fig).stem)} shown above)</p>")
                    continue
                embedded.add(fig)
                parts.append(_img_tag(root / fig))
    parts.append("</body></html>")
    return "\n".join(parts)


def report_json(sections: Sequence[Dict[str, Any]], settings: Dict[str, Any]) -> Dict[str, Any]:
    """Every number of the report (schema: docs/reproduce.md)."""
    from indoorloc import __version__

    return {
        "schema_version": SCHEMA_VERSION,
        "indoorloc_version": __version__,
        "settings": dict(settings),
        "verdicts": verdict_counts(sections),
        "sections": list(sections),
    }


def write_report(out_dir: Path, sections: Sequence[Dict[str, Any]], settings: Dict[str, Any]) -> Dict[str, Path]:
    """Write ``report.md``, ``report.html`` and ``report.json`` into ``out_dir``; return their paths."""
    out_dir = Path(out_dir)
    paths = {"markdown": out_dir / "report.md", "html": out_dir / "report.html", "json": out_dir / "report.json"}
    write_text_atomic(paths["markdown"], markdown(sections, settings), encoding="utf-8")
    write_text_atomic(paths["html"], html_page(sections, settings, out_dir), encoding="utf-8")
    write_text_atomic(paths["json"], json.dumps(report_json(sections, settings), indent=1), encoding="utf-8")
    return paths
