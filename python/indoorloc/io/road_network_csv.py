"""CSV road networks (:func:`read_csv_segments`); the format is described in
:mod:`indoorloc.io.road_network`."""

from __future__ import annotations

import csv
import io
import math
from typing import List, Tuple

import numpy as np

from indoorloc.io.errors import reads_file
from indoorloc.io.road_network_segments import (
    PathLike,
    _INT64_MAX,
    _check_segment,
    _finish,
    _path_error,
    _read_text,
)

#: Columns a road-network CSV file must have (header names, case-insensitive).
CSV_COLUMNS = ("id", "x_a", "y_a", "x_b", "y_b")


# ---------------------------------------------------------------------------------------------
# CSV


def _parse_csv(text: str, label: str) -> Tuple[np.ndarray, np.ndarray]:
    # Keep physical line numbers for messages: filter comment/blank lines, remember their number.
    kept = [(n, line) for n, line in enumerate(text.splitlines(), start=1)
            if line.strip() and not line.lstrip().startswith("#")]
    if not kept:
        raise _path_error(label, "empty CSV file (no header row)")
    reader = csv.reader(io.StringIO("\n".join(line for _, line in kept)))
    rows_raw = list(reader)
    header = [h.strip().lower() for h in rows_raw[0]]
    missing = [c for c in CSV_COLUMNS if c not in header]
    if missing:
        raise _path_error(label, f"line {kept[0][0]}: header {rows_raw[0]} lacks column(s) "
                                 f"{missing}; expected {','.join(CSV_COLUMNS)}")
    for c in CSV_COLUMNS:
        if header.count(c) > 1:
            raise _path_error(label, f"line {kept[0][0]}: column {c!r} appears twice")
    col = {c: header.index(c) for c in CSV_COLUMNS}
    width = max(col.values()) + 1

    rows: List[List[float]] = []
    ids: List[int] = []
    for (lineno, _), fields in zip(kept[1:], rows_raw[1:]):
        where = f"line {lineno}"
        if len(fields) < width:
            raise _path_error(label, f"{where}: {len(fields)} fields, expected at least {width}")
        try:
            sid = int(fields[col["id"]].strip())
        except ValueError:
            raise _path_error(label, f"{where}: id {fields[col['id']]!r} is not an integer") \
                from None
        if not -_INT64_MAX - 1 <= sid <= _INT64_MAX:
            raise _path_error(label, f"{where}: id {sid} does not fit in int64")
        seg = []
        for c in CSV_COLUMNS[1:]:
            cell = fields[col[c]].strip()
            try:
                v = float(cell)
            except ValueError:
                raise _path_error(label, f"{where}: {c} {cell!r} is not a number") from None
            if not math.isfinite(v):
                raise _path_error(label, f"{where}: {c} is NaN or infinite ({cell!r})")
            seg.append(v)
        _check_segment(seg, where, label)
        rows.append(seg)
        ids.append(sid)
    return _finish(rows, ids, label)


@reads_file("path")
def read_csv_segments(path: PathLike) -> Tuple[np.ndarray, np.ndarray]:
    """Read segments from a CSV file with header ``id,x_a,y_a,x_b,y_b``.

    Columns may come in any order and further columns are ignored; lines starting with ``#``
    and blank lines are skipped (format in the module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.csv`` file (UTF-8).

    Returns
    -------
    segments_m : numpy.ndarray, shape (M, 4), float64
        ``x_A, y_A, x_B, y_B`` [m] of each row, in file order.
    ids : numpy.ndarray, shape (M,), int64
        Unique segment ids.

    Raises
    ------
    ValueError
        ``indoorloc: argument 'path': ...`` for a missing file, a header without the required
        columns, a short row, a non-integer id, a non-numeric or NaN/inf coordinate, a
        zero-length segment or duplicate ids.
    """
    text, label = _read_text(path)
    return _parse_csv(text, label)
