"""The SURIMI collection in the common ``.mat`` format of Torres-Sospedra et al. (``<NAME>.mat``
holding ``database``): :func:`load_surimi`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from indoorloc.io.errors import reads_file
from indoorloc.io.wifi_datasets.dataset import (
    FingerprintDataset,
    PathLike,
    _bad,
    _generated_ap_names,
    _integer_floors,
    _point_ids,
    _require_file,
    _split,
)

#: Dataset names accepted by :func:`load_surimi`.
SURIMI_NAMES = ("DSI1", "DSI2", "LIB1", "TUT1", "TUT2", "UJI1")


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
    tr_ids, te_ids = _point_ids(labels["training"][:, :2], floors["training"], labels["test"][:, :2],
                                floors["test"])

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
