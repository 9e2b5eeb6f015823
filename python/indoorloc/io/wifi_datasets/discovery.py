"""WiFi fingerprint datasets by name: which are present under a data folder
(:func:`available_datasets`) and loading one by its command-line name (:func:`load_wifi_dataset`)."""

from __future__ import annotations

from pathlib import Path
from typing import List


from indoorloc.io.wifi_datasets.dataset import FingerprintDataset, PathLike
from indoorloc.io.wifi_datasets.rss_rtt_rooms import RSS_RTT_ROOMS, load_rss_rtt_room
from indoorloc.io.wifi_datasets.surimi import SURIMI_NAMES, load_surimi
from indoorloc.io.wifi_datasets.uji_library import load_uji_library


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
