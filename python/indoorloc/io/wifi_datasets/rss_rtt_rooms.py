"""The RSS/RTT rooms of Feng, Nguyen and Luo (``database_<room>_{train,test}.csv`` and
``AP_position.txt``): :func:`load_rss_rtt_room`."""

from __future__ import annotations

import csv
import re
from pathlib import Path
from typing import Dict, List, Optional, Tuple

import numpy as np

from indoorloc.io.errors import reads_file
from indoorloc.io.wifi_datasets.dataset import (
    FingerprintDataset,
    PathLike,
    _bad,
    _point_ids,
    _require_file,
    _split,
)

#: Room names accepted by :func:`load_rss_rtt_room`.
RSS_RTT_ROOMS = ("lecture_theatre", "office", "corridor")
#: Spacing [m] of the RSS/RTT grid: X, Y and AP_position.txt are grid indices.
RSS_RTT_GRID_M = 0.6


# --------------------------------------------------------------------------------------------
# RSS/RTT rooms (Feng, Nguyen, Luo)

_RSS_COLUMN = re.compile(r"^(AP\d+) RSS\(dBm\)$")


def _room_key(room: str) -> str:
    return re.sub(r"[\s\-]+", "_", room.strip().lower())


def _rss_rtt_csv(path: Path) -> Tuple[np.ndarray, np.ndarray, List[str]]:
    """(X, Y) grid indices (N, 2), RSS (N, K) and the K AP names of one room file."""
    _require_file(path)
    with open(path, "r", newline="", encoding="utf-8", errors="replace") as f:
        rows = list(csv.reader(f))
    if len(rows) < 2:
        raise _bad(f"file {path} holds no data rows")
    header = [h.strip() for h in rows[0]]
    if header[:2] != ["X", "Y"]:
        raise _bad(f"file {path}: header must start with X,Y, got {header[:2]}")
    matches = [(i, _RSS_COLUMN.match(h)) for i, h in enumerate(header)]
    rss_cols = [(i, m.group(1)) for i, m in matches if m]
    if not rss_cols:
        raise _bad(f"file {path}: no 'APn RSS(dBm)' column in the header")
    wanted = [0, 1] + [i for i, _ in rss_cols]
    values = np.empty((len(rows) - 1, len(wanted)), dtype=np.float64)
    for r, row in enumerate(rows[1:]):
        if len(row) != len(header):
            raise _bad(f"file {path} row {r + 2}: {len(row)} columns, header has {len(header)}")
        try:
            values[r] = [float(row[i]) for i in wanted]
        except ValueError:
            raise _bad(f"file {path} row {r + 2}: non-numeric X, Y or RSS value") from None
    if not np.all(np.isfinite(values)):
        row = int(np.argwhere(~np.isfinite(values))[0, 0])
        raise _bad(f"file {path} row {row + 2}: NaN or infinite X, Y or RSS value")
    return values[:, :2], values[:, 2:], [name for _, name in rss_cols]


def _ap_positions(path: Path) -> Dict[str, np.ndarray]:
    """AP_position.txt: a room title line, then 'AP X: ...' and 'AP Y: ...' (grid indices)."""
    _require_file(path)
    rooms: Dict[str, Dict[str, List[float]]] = {}
    current: Optional[str] = None
    with open(path, "r", encoding="utf-8", errors="replace") as f:
        for n, line in enumerate(f, start=1):
            line = line.strip()
            if not line:
                continue
            m = re.match(r"^AP\s*([XY])\s*:(.*)$", line)
            if m is None:
                current = _room_key(line)
                rooms[current] = {}
                continue
            if current is None:
                raise _bad(f"file {path} line {n}: coordinates before any room name")
            try:
                rooms[current][m.group(1)] = [float(v) for v in m.group(2).split(",")]
            except ValueError:
                raise _bad(f"file {path} line {n}: non-numeric AP coordinate") from None
    out = {}
    for room, xy in rooms.items():
        if set(xy) != {"X", "Y"} or len(xy["X"]) != len(xy["Y"]):
            raise _bad(f"file {path}: room {room!r} needs 'AP X' and 'AP Y' lines of equal length")
        pos = np.column_stack([xy["X"], xy["Y"]])
        if not np.all(np.isfinite(pos)):  # float() accepts "nan" and "inf"
            raise _bad(f"file {path}: room {room!r} has a NaN or infinite AP coordinate")
        out[room] = pos
    return out


@reads_file("root")
def load_rss_rtt_room(root: PathLike, room: str) -> FingerprintDataset:
    """Load one room of the WiFi RSS/RTT dataset of Feng, Nguyen and Luo (IEEE J-ISPIN 2024).

    Reads ``database_<room>_train.csv`` and ``database_<room>_test.csv`` (columns X, Y,
    ``APn RTT(mm)``, ``APn RSS(dBm)``, ``LOS APs``; 60 scans per reference point, train and test
    points disjoint) and ``AP_position.txt``. Only the RSS columns are loaded.

    Parameters
    ----------
    root : str or pathlib.Path
        Folder holding the CSV files and ``AP_position.txt`` (e.g. ``rss_rtt_rooms``).
    room : {"lecture_theatre", "office", "corridor"}
        Room; spaces or hyphens are accepted in place of underscores.

    Returns
    -------
    FingerprintDataset
        ``name`` is ``"rss_rtt_<room>"``; ``rss_dbm`` is (S, K) with K = 5 APs (4 in the
        corridor); positions are the grid indices X, Y times 0.6 m; floors are all 0;
        ``timestamps`` is None; ``ap_positions_m`` (K, 2) is ``AP_position.txt`` times 0.6 m.
        The sentinel is -200 dBm.

    Raises
    ------
    ValueError
        ``indoorloc: argument 'room': ...`` for an unknown room; ``indoorloc: argument 'root':
        ...`` when a file is missing or malformed (column count, NaN or non-numeric values, AP
        positions that do not match the RSS columns).

    Notes
    -----
    ``AP_position.txt`` is in grid units like X, Y: with that reading, each AP's RTT distance
    grows with slope 0.9-1.3 against its distance to the scan positions (correlation 0.93-0.99),
    while reading it in metres leaves several APs uncorrelated. The corridor files keep an AP1
    column that is never heard (-200 in every scan); it is dropped, so the corridor's four
    positions belong to AP2..AP5, as their RTT ranges confirm.
    """
    key = _room_key(room)
    if key not in RSS_RTT_ROOMS:
        raise ValueError(
            f"indoorloc: argument 'room': expected one of {RSS_RTT_ROOMS}, got {room!r}")
    root = Path(root)
    tr_xy, tr_rss, names = _rss_rtt_csv(root / f"database_{key}_train.csv")
    te_xy, te_rss, te_names = _rss_rtt_csv(root / f"database_{key}_test.csv")
    if te_names != names:
        raise _bad(f"database_{key}_test.csv has RSS columns {te_names}, database_{key}_train.csv "
                   f"has {names}")
    positions = _ap_positions(root / "AP_position.txt")
    if key not in positions:
        raise _bad(f"{root / 'AP_position.txt'} has no room {key!r} (found {sorted(positions)})")
    ap_grid = positions[key]

    keep = np.ones(len(names), dtype=bool)
    if ap_grid.shape[0] < len(names):
        # Fewer APs than columns: the extra columns must be never heard in either split.
        keep = ~(np.all(tr_rss == -200.0, axis=0) & np.all(te_rss == -200.0, axis=0))
    if ap_grid.shape[0] != int(keep.sum()):
        raise _bad(f"{root / 'AP_position.txt'} lists {ap_grid.shape[0]} APs for {key!r} but the "
                   f"files have {int(keep.sum())} heard RSS columns")
    dropped = [n for n, k in zip(names, keep) if not k]
    names = [n for n, k in zip(names, keep) if k]

    tr_floor = np.zeros(tr_xy.shape[0], dtype=np.int64)
    te_floor = np.zeros(te_xy.shape[0], dtype=np.int64)
    tr_ids, te_ids = _point_ids(tr_xy, tr_floor, te_xy, te_floor)
    description = (
        f"WiFi RSS/RTT dataset (Feng, Nguyen, Luo, IEEE J-ISPIN 2024), room {key}: RSS in dBm, "
        f"-200 = not heard; positions = grid indices x {RSS_RTT_GRID_M} m; single floor (0); "
        f"AP positions from AP_position.txt (grid units) x {RSS_RTT_GRID_M} m."
    )
    if dropped:
        description += f" Dropped never-heard column(s) {dropped}."
    return FingerprintDataset(
        name=f"rss_rtt_{key}",
        train=_split(tr_rss[:, keep], tr_xy * RSS_RTT_GRID_M, tr_floor, tr_ids, None),
        test=_split(te_rss[:, keep], te_xy * RSS_RTT_GRID_M, te_floor, te_ids, None),
        not_heard_sentinel=-200.0,
        ap_names=names,
        ap_positions_m=ap_grid * RSS_RTT_GRID_M,
        description=description,
    )
