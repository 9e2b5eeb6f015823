"""Loaders for public WiFi RSS fingerprint datasets (numpy only).

Three on-disk formats are read into one in-memory layout, :class:`FingerprintDataset`:

- the UJI long-term library dataset (``db/MM/trnNN{rss,crd,tms,ids}.csv`` and ``tstNN*``),
  :func:`load_uji_library`;
- the RSS/RTT rooms of Feng, Nguyen and Luo (``database_<room>_{train,test}.csv`` and
  ``AP_position.txt``), :func:`load_rss_rtt_room`;
- the SURIMI collection in the common ``.mat`` format of Torres-Sospedra et al.
  (``<NAME>.mat`` holding ``database``), :func:`load_surimi`.

RSS values are returned exactly as stored, "not heard" sentinel included: how a missing reading
is modelled is the estimator's decision, so :attr:`FingerprintDataset.not_heard_sentinel` tells
it which value to look for. Every loader raises ``ValueError("indoorloc: argument 'root': ...")``
naming the file when a file is missing or malformed.

Examples
--------
>>> from indoorloc.io import load_rss_rtt_room
>>> ds = load_rss_rtt_room("../shared/data/wifi/rss_rtt_rooms", "office")  # doctest: +SKIP
>>> ds.train.rss_dbm.shape, ds.not_heard_sentinel  # doctest: +SKIP
((4860, 5), -200.0)
"""

from __future__ import annotations

import csv
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from indoorloc.io.errors import FormatError, reads_file
PathLike = Union[str, Path]

#: Room names accepted by :func:`load_rss_rtt_room`.
RSS_RTT_ROOMS = ("lecture_theatre", "office", "corridor")
#: Dataset names accepted by :func:`load_surimi`.
SURIMI_NAMES = ("DSI1", "DSI2", "LIB1", "TUT1", "TUT2", "UJI1")

#: Spacing [m] of the RSS/RTT grid: X, Y and AP_position.txt are grid indices.
RSS_RTT_GRID_M = 0.6

# Coordinates are grouped into reference points after rounding to 1 um, so that the same
# location written twice never splits into two ids because of a last-bit difference.
_POINT_KEY_DECIMALS = 6

# Known labelling errors of the UJI library files, keyed by (month, "trn"/"tst", set). Each entry
# lists the scan identifiers (ids file), the coordinates the files hold and the corrected ones.
# Month 01, trn14: the first route stop (ids 114100101..106) is labelled (12.91, 16.70) on floor
# 0, a floor the library does not have; in all 14 other training sets that stop is
# (12.91, 29.22) on floor 3, the only location trn14 otherwise visits 6 times instead of 12, and
# the scans' RSS matches floor 3 near y = 29 m, not y = 16.7 m.
_Erratum = Tuple[Tuple[int, ...], Tuple[float, float, float], Tuple[float, float, float]]
_UJI_LIB_ERRATA: Dict[Tuple[str, str, int], _Erratum] = {
    ("01", "trn", 14): (
        tuple(range(114100101, 114100107)),
        (12.91385188, 16.69981527, 0.0),
        (12.91385188, 29.21654402, 3.0),
    ),
}


def _as_int64(values: object, name: str) -> np.ndarray:
    """An integer array; NaN, inf, fractions and values beyond int64 are refused (a plain cast
    would turn NaN and 1e30 into INT64_MIN without a word)."""
    a = np.asarray(values)
    if a.dtype.kind in "iub":
        return a.astype(np.int64)
    if a.dtype.kind != "f":
        raise ValueError(f"indoorloc: argument '{name}': expected integers, got dtype {a.dtype}")
    bad = ~np.isfinite(a) | (a != np.rint(a)) | (np.abs(a) > 2.0**62)
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(f"indoorloc: argument '{name}': entry {k} = {a.flat[k]!r} is not a "
                         f"whole number within +-2**62")
    return a.astype(np.int64)


@dataclass
class FingerprintSplit:
    """One split (training or test) of a fingerprint dataset; S scans, K access points.

    Attributes
    ----------
    rss_dbm : numpy.ndarray, shape (S, K), float64
        Received signal strength [dBm] as stored in the files; "not heard" readings keep the
        dataset's sentinel (:attr:`FingerprintDataset.not_heard_sentinel`).
    positions_m : numpy.ndarray, shape (S, 2), float64
        Ground-truth x, y [m] of each scan.
    floors : numpy.ndarray, shape (S,), int64
        Floor of each scan; 0 when the dataset has no floor information.
    point_ids : numpy.ndarray, shape (S,), int64
        Reference/test location id: scans taken at the same (x, y, floor) share an id. Ids are
        numbered 0, 1, ... in order of first appearance over train then test, so one location
        has the same id in both splits of a dataset.
    timestamps : numpy.ndarray, shape (S,), float64, or None
        Scan times [s] since 1970-01-01 of the recording device's clock, when the files have them.
    """

    rss_dbm: np.ndarray
    positions_m: np.ndarray
    floors: np.ndarray
    point_ids: np.ndarray
    timestamps: Optional[np.ndarray] = None

    def __post_init__(self) -> None:
        self.rss_dbm = np.asarray(self.rss_dbm, dtype=np.float64)
        self.positions_m = np.asarray(self.positions_m, dtype=np.float64)
        self.floors = _as_int64(self.floors, "floors")
        self.point_ids = _as_int64(self.point_ids, "point_ids")
        if self.timestamps is not None:
            self.timestamps = np.asarray(self.timestamps, dtype=np.float64)
        s = self.rss_dbm.shape[0] if self.rss_dbm.ndim == 2 else -1
        shapes_ok = (
            self.rss_dbm.ndim == 2
            and self.positions_m.shape == (s, 2)
            and self.floors.shape == (s,)
            and self.point_ids.shape == (s,)
            and (self.timestamps is None or self.timestamps.shape == (s,))
        )
        if not shapes_ok:
            raise ValueError(
                "indoorloc: argument 'rss_dbm': FingerprintSplit needs rss_dbm (S, K), "
                f"positions_m (S, 2), floors (S,), point_ids (S,) and timestamps (S,) or None; "
                f"got {self.rss_dbm.shape}, {self.positions_m.shape}, {self.floors.shape}, "
                f"{self.point_ids.shape}, "
                f"{None if self.timestamps is None else self.timestamps.shape}"
            )

    @property
    def n_scans(self) -> int:
        """Number of scans S."""
        return int(self.rss_dbm.shape[0])


@dataclass
class FingerprintDataset:
    """A fingerprint dataset: training and test splits over the same K access points.

    Attributes
    ----------
    name : str
        Short name, e.g. ``"uji_library_month01"``, ``"rss_rtt_office"``, ``"surimi_LIB1"``
        (the names listed by :func:`available_datasets`).
    train, test : FingerprintSplit
        The splits as the dataset's authors define them.
    not_heard_sentinel : float
        RSS value [dBm] that codes "access point not heard": +100 for UJI and SURIMI, -200 for
        the RSS/RTT rooms.
    ap_names : list of str, length K
        Access-point names from the files, or generated ``"AP001"``, ``"AP002"``, ...
    ap_positions_m : numpy.ndarray, shape (K, 2), float64, or None
        Access-point x, y [m] in the frame of the scan positions, when known.
    description : str
        Source, units and any correction the loader applied.
    """

    name: str
    train: FingerprintSplit
    test: FingerprintSplit
    not_heard_sentinel: float
    ap_names: List[str]
    ap_positions_m: Optional[np.ndarray] = None
    description: str = ""

    @property
    def n_aps(self) -> int:
        """Number of access points K."""
        return int(self.train.rss_dbm.shape[1])


# --------------------------------------------------------------------------------------------
# Shared helpers


def _bad(msg: str) -> FormatError:
    return FormatError(f"indoorloc: argument 'root': {msg}")


def _require_file(path: Path) -> Path:
    if not path.is_file():
        raise _bad(f"missing file {path}")
    return path


def _load_matrix(path: Path, dtype: type = np.float64, ncols: Optional[int] = None) -> np.ndarray:
    """A comma-separated numeric file as an (N, C) array; malformed content -> ValueError."""
    _require_file(path)
    try:
        with warnings.catch_warnings():
            # An empty file only warns in np.loadtxt; it is rejected just below.
            warnings.simplefilter("ignore", UserWarning)
            a = np.loadtxt(path, delimiter=",", dtype=dtype, ndmin=2)
    except ValueError as exc:
        raise _bad(f"malformed file {path}: {exc}") from None
    if a.shape[0] == 0:
        raise _bad(f"file {path} holds no rows")
    if ncols is not None and a.shape[1] != ncols:
        raise _bad(f"file {path} has {a.shape[1]} columns, expected {ncols}")
    if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
        row = int(np.argwhere(~np.isfinite(a))[0, 0])
        raise _bad(f"file {path} has a NaN or infinite value in row {row + 1}")
    return a


_MAX_FLOOR = 10**6  # far beyond any building; keeps floors exact in float64 and int64


def _integer_floors(values: np.ndarray, path: Path) -> np.ndarray:
    # A tolerance, because some files store floors computed as z / 3.7 (TUT1: 3.0000000000000004).
    nearest = np.rint(values)
    # NaN or 1e30 would cast to INT64_MIN: a floor must be a finite, plausible whole number.
    bad = ~(np.abs(values - nearest) <= 1e-6) | ~(np.abs(nearest) <= _MAX_FLOOR)
    if np.any(bad):
        row = int(np.argwhere(bad)[0, 0])
        raise _bad(f"file {path} row {row + 1}: floor {values.flat[np.flatnonzero(bad)[0]]!r} is not an "
                   f"integer within +-{_MAX_FLOOR}")
    return nearest.astype(np.int64)


def _point_ids(train_key: np.ndarray, test_key: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Ids of the (x, y, floor) rows of both splits, numbered by first appearance."""
    key = np.round(np.vstack([train_key, test_key]), _POINT_KEY_DECIMALS)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    rank = np.empty(first.size, dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(first.size, dtype=np.int64)
    ids = rank[inverse]
    return ids[: train_key.shape[0]], ids[train_key.shape[0] :]


def _generated_ap_names(k: int) -> List[str]:
    width = max(3, len(str(k)))
    return [f"AP{i:0{width}d}" for i in range(1, k + 1)]


def _split(rss: np.ndarray, xy: np.ndarray, floors: np.ndarray, ids: np.ndarray,
           times: Optional[np.ndarray]) -> FingerprintSplit:
    return FingerprintSplit(rss_dbm=rss, positions_m=xy, floors=floors, point_ids=ids,
                            timestamps=times)


# --------------------------------------------------------------------------------------------
# UJI long-term library dataset


def _uji_month_dir(root: Path, month: str) -> Path:
    for candidate in (root / "db" / month, root / month):
        if candidate.is_dir():
            return candidate
    raise _bad(f"no month folder {root / 'db' / month} (nor {root / month})")


def _uji_set_numbers(folder: Path, kind: str) -> List[int]:
    pattern = re.compile(rf"^{kind}(\d\d)rss\.csv$")
    found = sorted(int(m.group(1)) for m in (pattern.match(p.name) for p in folder.iterdir()) if m)
    if not found:
        raise _bad(f"no {kind}NNrss.csv files in {folder}")
    return found


def _uji_timestamps(path: Path) -> np.ndarray:
    """yyyymmddHHMMSSfff integers -> seconds since 1970-01-01 (wall clock, no time zone)."""
    _require_file(path)
    with open(path, "r", encoding="ascii", errors="replace") as f:
        lines = [ln.strip() for ln in f if ln.strip()]
    if not lines:
        raise _bad(f"file {path} holds no rows")
    iso = []
    for i, s in enumerate(lines):
        if len(s) != 17 or not s.isdigit():
            raise _bad(f"file {path} row {i + 1}: expected a yyyymmddHHMMSSfff time, got {s!r}")
        iso.append(f"{s[0:4]}-{s[4:6]}-{s[6:8]}T{s[8:10]}:{s[10:12]}:{s[12:14]}.{s[14:17]}")
    try:
        ms = np.array(iso, dtype="datetime64[ms]").astype(np.int64)
    except ValueError as exc:
        raise _bad(f"file {path} holds an invalid date: {exc}") from None
    # Integer milliseconds first: the raw 17-digit numbers exceed float64's exact range.
    return ms.astype(np.float64) / 1000.0


def _uji_read_set(folder: Path, kind: str, number: int, month: str, fix_known_errors: bool,
                  n_aps: Optional[int]
                  ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    stem = f"{kind}{number:02d}"
    rss = _load_matrix(folder / f"{stem}rss.csv", np.float64, n_aps)
    crd = _load_matrix(folder / f"{stem}crd.csv", np.float64, 3)
    tms = _uji_timestamps(folder / f"{stem}tms.csv")
    ids = _load_matrix(folder / f"{stem}ids.csv", np.int64, 1)[:, 0]
    for what, n in (("crd", crd.shape[0]), ("tms", tms.shape[0]), ("ids", ids.shape[0])):
        if n != rss.shape[0]:
            raise _bad(f"{folder / (stem + what + '.csv')} has {n} rows but "
                       f"{stem}rss.csv has {rss.shape[0]}")
    n_fixed = 0
    erratum = _UJI_LIB_ERRATA.get((month, kind, number))
    if fix_known_errors and erratum is not None:
        bad_ids, wrong, right = erratum
        rows = np.isin(ids, bad_ids) & np.all(crd == np.asarray(wrong), axis=1)
        crd[rows] = right
        n_fixed = int(rows.sum())
    floors = _integer_floors(crd[:, 2], folder / f"{stem}crd.csv")
    return rss, crd[:, :2], floors, tms, n_fixed


def _uji_read_split(folder: Path, kind: str, numbers: Sequence[int], month: str,
                    fix_known_errors: bool, n_aps: Optional[int]
                    ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
    parts = []
    n_fixed = 0
    for number in numbers:
        *arrays, fixed = _uji_read_set(folder, kind, number, month, fix_known_errors, n_aps)
        n_aps = arrays[0].shape[1]  # every set of a month has the same AP columns
        parts.append(arrays)
        n_fixed += fixed
    rss, xy, floors, tms = (np.concatenate([p[i] for p in parts]) for i in range(4))
    return rss, xy, floors, tms, n_fixed


def _uji_set_list(value: Optional[Sequence[int]], available: List[int], arg: str) -> List[int]:
    if value is None:
        return available
    try:
        numbers = [int(v) for v in value]
    except (TypeError, ValueError):
        numbers = []
    if not numbers or any(n < 1 or n > 99 for n in numbers):
        raise ValueError(
            f"indoorloc: argument '{arg}': expected set numbers in 1..99, got {value!r}")
    return numbers


@reads_file("root")
def load_uji_library(
    root: PathLike,
    month: Union[str, int] = "01",
    train_sets: Optional[Sequence[int]] = None,
    test_sets: Optional[Sequence[int]] = None,
    *,
    fix_known_errors: bool = True,
) -> FingerprintDataset:
    """Load one month of the UJI long-term WiFi library dataset (Mendoza-Silva et al., 2018).

    Each set NN of the month folder is four row-aligned files: ``trnNNrss.csv`` (RSS [dBm],
    one column per AP, +100 = not heard), ``trnNNcrd.csv`` (x [m], y [m], floor),
    ``trnNNtms.csv`` (time as yyyymmddHHMMSSfff) and ``trnNNids.csv`` (scan ids); test sets
    are ``tstNN*``. In month 01 each of the 15 training sets is 48 reference points x 12 scans
    (576 scans) and the 5 test sets hold 3,120 scans at 212 locations, over 620 APs.

    Parameters
    ----------
    root : str or pathlib.Path
        Dataset folder holding ``db/MM/`` (e.g. ``uji_library_month01``), or ``db`` itself.
    month : str or int, default "01"
        Collection month, the name of the folder under ``db``.
    train_sets, test_sets : sequence of int, optional
        Set numbers (1-based) to concatenate into each split; default: every set in the folder.
    fix_known_errors : bool, default True
        Correct labelling errors verified in the files (see Notes). False keeps every label raw.

    Returns
    -------
    FingerprintDataset
        ``name`` is ``"uji_library_monthMM"``; ``rss_dbm`` is (S, K) with K = 620 in month 01;
        floors are the library floors (3 and 5); timestamps are seconds since 1970-01-01 of the
        phone's wall clock (the files carry no time zone). AP names are generated ``"AP001"``...

    Raises
    ------
    ValueError
        ``indoorloc: argument 'root': ...`` when a file is missing or malformed (column count,
        row counts that differ between the four files of a set, NaN values, bad times);
        ``indoorloc: argument 'train_sets'`` (or ``'test_sets'``) for set numbers outside 1..99.

    Notes
    -----
    In month 01, ``trn14crd.csv`` labels its first 6 scans (ids 114100101..114100106) as
    (12.91385188, 16.69981527) on floor 0; every other training set has that route stop at
    (12.91385188, 29.21654402) on floor 3, where trn14 otherwise has only 6 of the usual 12 scans.
    With ``fix_known_errors`` those 6 labels are replaced and ``description`` says so.
    """
    root = Path(root)
    month = f"{int(month):02d}" if str(month).isdigit() else str(month)
    folder = _uji_month_dir(root, month)
    trn = _uji_set_list(train_sets, _uji_set_numbers(folder, "trn"), "train_sets")
    tst = _uji_set_list(test_sets, _uji_set_numbers(folder, "tst"), "test_sets")

    tr_rss, tr_xy, tr_floor, tr_t, fixed_tr = _uji_read_split(
        folder, "trn", trn, month, fix_known_errors, None)
    te_rss, te_xy, te_floor, te_t, fixed_te = _uji_read_split(
        folder, "tst", tst, month, fix_known_errors, tr_rss.shape[1])
    tr_ids, te_ids = _point_ids(np.column_stack([tr_xy, tr_floor]),
                                np.column_stack([te_xy, te_floor]))

    description = (
        f"UJI long-term WiFi library dataset (Mendoza-Silva et al., Data 3(1):3, 2018), month "
        f"{month}: training sets {trn}, test sets {tst}. RSS in dBm, +100 = not heard; x, y in "
        f"metres; floors 3 and 5 of the library; times in s of the phone's wall clock."
    )
    n_fixed = fixed_tr + fixed_te
    if n_fixed:
        description += (f" {n_fixed} scan labels corrected from a known labelling error "
                        f"(see load_uji_library Notes).")
    return FingerprintDataset(
        name=f"uji_library_month{month}",
        train=_split(tr_rss, tr_xy, tr_floor, tr_ids, tr_t),
        test=_split(te_rss, te_xy, te_floor, te_ids, te_t),
        not_heard_sentinel=100.0,
        ap_names=_generated_ap_names(tr_rss.shape[1]),
        ap_positions_m=None,
        description=description,
    )


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
    tr_ids, te_ids = _point_ids(np.column_stack([tr_xy, tr_floor]),
                                np.column_stack([te_xy, te_floor]))
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


# --------------------------------------------------------------------------------------------
# SURIMI collection (.mat, common format of Torres-Sospedra et al.)

_SURIMI_FIELDS = ("trainingMacs", "testMacs", "trainingLabels", "testLabels")


@reads_file("root")
def load_surimi(root: PathLike, name: str) -> FingerprintDataset:
    """Load one dataset of the SURIMI collection (common ``.mat`` format).

    ``<root>/<name>.mat`` holds a struct ``database`` with ``trainingMacs`` / ``testMacs``
    (RSS [dBm], one column per AP, +100 = not heard) and ``trainingLabels`` / ``testLabels``
    (columns x [m], y [m], z [m], floor, building).

    Parameters
    ----------
    root : str or pathlib.Path
        Folder holding the ``.mat`` files (e.g. ``surimi``).
    name : {"DSI1", "DSI2", "LIB1", "TUT1", "TUT2", "UJI1"}
        Dataset name (case-insensitive).

    Returns
    -------
    FingerprintDataset
        ``name`` is ``"surimi_<NAME>"``; ``rss_dbm`` is (S, K); positions are label columns x, y;
        floors are the integer floor labels, except in datasets with more than one building
        (only UJI1, 3 buildings) where ``floors = 10 * building + floor`` so that floors of
        different buildings never merge (UJI1: building 0..2, floor 0..4). ``timestamps`` is
        None; AP names are generated ``"AP001"``...; the sentinel is +100 dBm.

    Raises
    ------
    ValueError
        ``indoorloc: argument 'name': ...`` for an unknown name; ``indoorloc: argument 'root':
        ...`` when the file is missing, unreadable, lacks a field, or has inconsistent shapes,
        NaN coordinates or non-integer floors.

    Notes
    -----
    UJI1 positions are the UJIIndoorLoc coordinates (Web Mercator, EPSG:3857, metres of the
    projection, about 1.3 times ground metres at that latitude). TUT1/TUT2 training fingerprints
    hold non-integer (averaged) RSS values; they are kept as stored. TUT1 stores floor 3 as
    3.0000000000000004; floors within 1e-6 of an integer are rounded to it.
    """
    key = str(name).strip().upper()
    if key not in SURIMI_NAMES:
        raise ValueError(
            f"indoorloc: argument 'name': expected one of {SURIMI_NAMES}, got {name!r}")
    path = _require_file(Path(root) / f"{key}.mat")
    import scipy.io  # deferred: only this loader needs scipy

    try:
        mat = scipy.io.loadmat(str(path))
    except Exception as exc:  # scipy raises several types for a damaged file
        raise _bad(f"cannot read {path}: {exc}") from None
    db = mat.get("database")
    if db is None or getattr(db, "dtype", None) is None or db.dtype.names is None:
        raise _bad(f"{path} has no struct 'database'")
    missing = [f for f in _SURIMI_FIELDS if f not in db.dtype.names]
    if missing:
        raise _bad(f"{path}: struct 'database' lacks field(s) {missing}")
    arrays = {}
    for f in _SURIMI_FIELDS:
        raw = np.asarray(db[f].flat[0])
        if raw.dtype.kind not in "biuf":  # cell arrays, text, structs, complex: named, not cast
            raise _bad(f"{path}: field database.{f}: expected a real matrix, got {raw.dtype} data")
        arrays[f] = raw.astype(np.float64)

    macs = {}
    labels = {}
    for split in ("training", "test"):
        m, lab = arrays[f"{split}Macs"], arrays[f"{split}Labels"]
        if m.ndim != 2 or lab.ndim != 2 or lab.shape[1] != 5 or m.shape[0] != lab.shape[0]:
            raise _bad(f"{path}: {split}Macs {m.shape} and {split}Labels {lab.shape} must be "
                       f"(S, K) and (S, 5)")
        if m.shape[0] == 0:
            raise _bad(f"{path}: {split} split is empty")
        if not np.all(np.isfinite(lab)):
            raise _bad(f"{path}: {split}Labels has NaN or infinite coordinates")
        if not np.all(np.isfinite(m)):
            raise _bad(f"{path}: {split}Macs has NaN or infinite RSS")
        macs[split], labels[split] = m, lab
    if macs["training"].shape[1] != macs["test"].shape[1]:
        raise _bad(f"{path}: trainingMacs has {macs['training'].shape[1]} APs, testMacs "
                   f"{macs['test'].shape[1]}")

    floor_b = {s: _integer_floors(labels[s][:, 3:5], path) for s in labels}
    buildings = np.unique(np.concatenate([floor_b[s][:, 1] for s in floor_b]))
    multi_building = buildings.size > 1
    floors = {s: (10 * fb[:, 1] + fb[:, 0]) if multi_building else fb[:, 0]
              for s, fb in floor_b.items()}
    tr_ids, te_ids = _point_ids(np.column_stack([labels["training"][:, :2], floors["training"]]),
                                np.column_stack([labels["test"][:, :2], floors["test"]]))

    description = (
        f"SURIMI collection ({key}.mat, common format of Torres-Sospedra et al.): RSS in dBm, "
        f"+100 = not heard; x, y from the labels in metres"
        + (" (UJIIndoorLoc Web Mercator EPSG:3857)" if key == "UJI1" else "")
        + "; floors "
        + ("encoded 10 * building + floor." if multi_building else "as labelled.")
    )
    return FingerprintDataset(
        name=f"surimi_{key}",
        train=_split(macs["training"], labels["training"][:, :2], floors["training"], tr_ids, None),
        test=_split(macs["test"], labels["test"][:, :2], floors["test"], te_ids, None),
        not_heard_sentinel=100.0,
        ap_names=_generated_ap_names(macs["training"].shape[1]),
        ap_positions_m=None,
        description=description,
    )


# --------------------------------------------------------------------------------------------
# Discovery


def available_datasets(data_root: PathLike) -> List[str]:
    """Names of the datasets present under ``data_root`` (file existence only, nothing parsed).

    Parameters
    ----------
    data_root : str or pathlib.Path
        Folder holding ``uji_library_month*/``, ``rss_rtt_rooms/`` and ``surimi/``, or its
        parent when that holds them under ``wifi/`` (e.g. ``../shared/data``).

    Returns
    -------
    list of str
        Dataset names equal to the ``name`` the loaders give: ``"uji_library_monthMM"`` for
        ``load_uji_library(data_root / "uji_library_month..", MM)``, ``"rss_rtt_<room>"`` for
        ``load_rss_rtt_room(data_root / "rss_rtt_rooms", room)`` and ``"surimi_<NAME>"`` for
        ``load_surimi(data_root / "surimi", NAME)``. Empty when nothing is found.
    """
    root = Path(data_root)
    if (root / "wifi").is_dir():
        root = root / "wifi"
    if not root.is_dir():
        return []
    names: List[str] = []
    for folder in sorted(root.glob("uji_library*")):
        db = folder / "db"
        if not db.is_dir():
            continue
        for month in sorted(p for p in db.iterdir() if p.is_dir()):
            if any(month.glob("trn??rss.csv")) and any(month.glob("tst??rss.csv")):
                names.append(f"uji_library_month{month.name}")
    rooms = root / "rss_rtt_rooms"
    if (rooms / "AP_position.txt").is_file():
        for room in RSS_RTT_ROOMS:
            if all((rooms / f"database_{room}_{s}.csv").is_file() for s in ("train", "test")):
                names.append(f"rss_rtt_{room}")
    for key in SURIMI_NAMES:
        if (root / "surimi" / f"{key}.mat").is_file():
            names.append(f"surimi_{key}")
    return names


def load_wifi_dataset(name: str, data_root: PathLike) -> FingerprintDataset:
    """Dataset by its command-line name (``indoorloc wifi evaluate --dataset``).

    Parameters
    ----------
    name : str
        ``"uji"`` (UJI library, month 01), a room of :data:`RSS_RTT_ROOMS` or
        ``"surimi:<NAME>"`` with NAME in :data:`SURIMI_NAMES`.
    data_root : str or pathlib.Path
        Folder holding ``uji_library_month01/``, ``rss_rtt_rooms/`` and ``surimi/``
        (:func:`indoorloc.registry.default_data_root`).

    Raises
    ------
    ValueError
        ``indoorloc: argument 'dataset': ...`` for an unknown name, and whatever the loader
        raises for a missing or malformed file.
    """
    data_root = Path(data_root)
    if name == "uji":
        return load_uji_library(data_root / "uji_library_month01")
    if name in RSS_RTT_ROOMS:
        return load_rss_rtt_room(data_root / "rss_rtt_rooms", name)
    if name.startswith("surimi:"):
        return load_surimi(data_root / "surimi", name.split(":", 1)[1])
    raise ValueError(
        f"indoorloc: argument 'dataset': unknown dataset {name!r} "
        f"(uji, {', '.join(RSS_RTT_ROOMS)}, surimi:<NAME>)"
    )
