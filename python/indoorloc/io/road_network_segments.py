"""What the road-network formats of :mod:`indoorloc.io.road_network` share: reading a file's text,
the error messages naming the file, checks of numbers, ids and segments, and the final arrays
(segments (M, 4) [m], ids (M,) int64)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, List, Sequence, Tuple, Union

import numpy as np

from indoorloc.io.errors import FormatError
from indoorloc.validate import argument_error as _error
from indoorloc.validate import real_array

PathLike = Union[str, os.PathLike]

_INT64_MAX = 2**63 - 1


def _path_error(label: str, msg: str) -> ValueError:
    return FormatError(f"indoorloc: argument 'path': {label}: {msg}", path=label)


def _read_text(path: PathLike) -> Tuple[str, str]:
    """Text of ``path`` (UTF-8, BOM tolerated) and the label used in error messages."""
    if not isinstance(path, (str, os.PathLike)):
        raise _error("path", f"expected a str or os.PathLike, got {type(path).__name__}")
    p = Path(path)
    label = str(p)
    if not p.exists():
        raise _path_error(label, "file not found")
    if not p.is_file():
        raise _path_error(label, "not a regular file")
    try:
        return p.read_text(encoding="utf-8-sig"), label
    except (OSError, UnicodeDecodeError) as exc:
        raise _path_error(label, f"cannot read file ({exc})") from None


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _check_unique_ids(ids: np.ndarray, label: str, arg: str = "path") -> None:
    values, counts = np.unique(ids, return_counts=True)
    dup = values[counts > 1]
    if dup.size:
        shown = ", ".join(str(int(v)) for v in dup[:10])
        more = f" (and {dup.size - 10} more)" if dup.size > 10 else ""
        prefix = f"{label}: " if label else ""
        raise _error(arg, f"{prefix}duplicate segment id(s) {shown}{more}")


def _check_segment(seg: Sequence[float], where: str, label: str) -> None:
    if seg[0] == seg[2] and seg[1] == seg[3]:
        raise _path_error(label, f"{where}: zero-length segment at ({seg[0]!r}, {seg[1]!r})")


def _finish(rows: List[List[float]], ids: List[int], label: str) -> Tuple[np.ndarray, np.ndarray]:
    if not rows:
        raise _path_error(label, "no segments in file")
    segments_m = np.asarray(rows, dtype=np.float64).reshape(-1, 4)
    ids_arr = np.asarray(ids, dtype=np.int64)
    _check_unique_ids(ids_arr, label)
    return segments_m, ids_arr


def _as_segments(segments_m: Any, ids: Any) -> Tuple[np.ndarray, np.ndarray]:
    seg = real_array(segments_m, "segments_m")  # strings, complex, NaN, inf: refused by name
    if seg.ndim != 2 or seg.shape[1] != 4 or seg.shape[0] == 0:
        raise _error("segments_m", f"expected shape (M, 4) with M >= 1, got {seg.shape}")
    bad = np.flatnonzero(~np.isfinite(seg).all(axis=1))
    if bad.size:
        raise _error("segments_m", f"row {int(bad[0])} has a NaN or infinite coordinate")
    if ids is None:
        ids_arr = np.arange(1, seg.shape[0] + 1, dtype=np.int64)
    else:
        try:
            raw = np.asarray(ids)
        except ValueError as exc:  # ragged nested lists
            raise _error("ids", f"cannot be converted to an array ({exc})") from None
        if raw.shape != (seg.shape[0],):
            raise _error("ids", f"expected shape ({seg.shape[0]},), got {raw.shape}")
        if raw.size and not np.issubdtype(raw.dtype, np.integer):
            raise _error("ids", f"expected integers, got dtype {raw.dtype}")
        # uint64 ids above 2**63 - 1 would wrap to negative int64 (2**64 - 1 became -1).
        if raw.size and raw.dtype.kind == "u" and int(raw.max()) > _INT64_MAX:
            k = int(np.argmax(raw > _INT64_MAX))
            raise _error("ids", f"entry {k} = {int(raw[k])} does not fit in int64 "
                                f"(the readers' id type)")
        ids_arr = raw.astype(np.int64)
        _check_unique_ids(ids_arr, "", arg="ids")
    return seg, ids_arr
