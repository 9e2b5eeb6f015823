"""The in-memory layout of a WiFi RSS fingerprint dataset (:class:`FingerprintDataset`, two
:class:`FingerprintSplit`) and the parsing helpers the loaders of :mod:`indoorloc.io.wifi_datasets`
share (numeric CSV files, integer floors, reference-point ids)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import List, Optional, Tuple, Union

import numpy as np

from indoorloc.io.errors import FormatError
PathLike = Union[str, Path]

# Coordinates are grouped into reference points after rounding to 1 um, so that the same
# location written twice never splits into two ids because of a last-bit difference.
_POINT_KEY_DECIMALS = 6


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


def _point_ids(train_xy: np.ndarray, train_floors: np.ndarray, test_xy: np.ndarray,
               test_floors: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Ids of the (x, y, floor) reference points of both splits, numbered by first appearance."""
    train_key = np.column_stack([train_xy, train_floors])
    test_key = np.column_stack([test_xy, test_floors])
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
