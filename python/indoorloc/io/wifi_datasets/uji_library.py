"""The UJI long-term WiFi library dataset (``db/MM/trnNN{rss,crd,tms,ids}.csv`` and ``tstNN*``):
:func:`load_uji_library`, with the known labelling errors of the files corrected."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from indoorloc.io.errors import reads_file
from indoorloc.io.wifi_datasets.dataset import (
    FingerprintDataset,
    PathLike,
    _bad,
    _generated_ap_names,
    _integer_floors,
    _load_matrix,
    _point_ids,
    _require_file,
    _split,
)

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
    tr_ids, te_ids = _point_ids(tr_xy, tr_floor, te_xy, te_floor)

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
