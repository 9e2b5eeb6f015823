"""A titled Markdown table, as the studies print their results: the bold title, a blank line, the
header row, the rule and one line per row."""

from __future__ import annotations

from typing import List, Sequence


def titled_table(title: str, columns: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """The lines ``**title**``, blank, ``| c1 | c2 | ... |``, ``|---|---|...|`` and one ``| ... |``
    line per row (each a sequence of cell strings, as many as ``columns``), joined by newlines."""
    lines: List[str] = [f"**{title}**", "", "| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)
