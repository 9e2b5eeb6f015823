"""Floors and sites of the Indoor Location Competition 2.0 data: a floor folder (IlcFloor,
read_ilc_floor) with its walks loaded on demand, the floors of a site in building order
(ilc_floor_names, read_ilc_site) and the floor frame's origin (ilc_floor_origin_lonlat).

Part of :mod:`indoorloc.io.ilc2020` (the format is described there)."""

from __future__ import annotations

import io
import json
import re
import warnings
from dataclasses import field
from pathlib import Path
from typing import Any, Dict, Iterable, Iterator, List, Optional, Set, Tuple, Union

import numpy as np

from indoorloc.io.errors import RecordingWarning, format_error, reads_file
from indoorloc.io.ilc2020.walk_types import IlcWalk, PathLike
from indoorloc.io.ilc2020.walk_reader import read_ilc_walk
from indoorloc.io.ilc2020.vocabulary import BssidVocabulary


class UnknownWalkError(KeyError):
    """No walk with the id asked for on a floor (a KeyError whose message reads plainly)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class IlcFloor:
    """One floor: its walk files and its plan files (``floor_info.json``, ``geojson_map.json``,
    ``floor_image.png``).

    The walks are ``path_data_files/*.txt`` (the competition's 2020 layout) or, when that folder
    is absent, ``*.txt`` in the floor folder itself (the Kaggle 2021 layout). They are read on
    demand (:meth:`walk`, :meth:`walks`) and kept when ``cache`` is True.

    The plan files are in the floor folder (ILC 2020) unless ``plan_dir`` names another folder:
    the Kaggle 2021 data keeps them in ``ROOT/metadata/SITE/FLOOR`` beside the walks'
    ``ROOT/train/SITE/FLOOR`` (:func:`indoorloc.io.survey_layout.survey_floors` finds both).

    :meth:`walk` raises for a walk that cannot be read; the readers that iterate over walks
    (:meth:`walks`, :meth:`bssid_vocabulary`, :func:`describe_ilc_floor`) skip it instead, with a
    :class:`~indoorloc.io.errors.RecordingWarning` naming the file and the reason, and list it in
    :attr:`skipped_walks`. :meth:`load_report` counts what was skipped or dropped.

    Attributes
    ----------
    name : str
        Floor folder name (e.g. ``"F3"``).
    floor_dir : pathlib.Path
        The floor folder (the walks' folder).
    plan_dir : pathlib.Path
        The folder of the plan files: ``plan_dir`` when given, else ``floor_dir``.
    width_m, height_m : float or None
        ``map_info.width`` / ``map_info.height`` of ``floor_info.json`` [m] (the floor frame's
        extent); None when the file is absent.
    geojson_path : pathlib.Path or None
        ``geojson_map.json`` (read it with :mod:`indoorloc.io.floor_plan`); None when absent.
    image_path : pathlib.Path or None
        ``floor_image.png`` when present.
    walk_paths : list of pathlib.Path
        The walk files, sorted by name.
    """

    def __init__(self, floor_dir: PathLike, *, plan_dir: Optional[PathLike] = None, cache: bool = True,
                 allow_unsorted: bool = False) -> None:
        d = Path(floor_dir)
        walk_dir = d / "path_data_files"
        if not d.is_dir():
            raise ValueError(f"indoorloc: argument 'floor_dir': no folder {d}")
        plans = d if plan_dir is None else Path(plan_dir)
        # The argument the plan files' errors name: the floor folder's unless they are elsewhere.
        plan_arg = "floor_dir" if plan_dir is None else "plan_dir"
        if not plans.is_dir():
            raise ValueError(f"indoorloc: argument 'plan_dir': no folder {plans}")
        if not walk_dir.is_dir():
            walk_dir = d
        self.name = d.name
        self.floor_dir = d
        self.plan_dir = plans
        self.walk_paths = sorted(p for p in walk_dir.glob("*.txt") if p.is_file())
        if not self.walk_paths:
            where = (f"{d} (and no folder {d / 'path_data_files'})" if walk_dir == d
                     else str(walk_dir))
            raise ValueError(f"indoorloc: argument 'floor_dir': no *.txt walk file in {where}")
        self.width_m: Optional[float] = None
        self.height_m: Optional[float] = None
        info = plans / "floor_info.json"
        if info.is_file():
            self.width_m, self.height_m = _floor_info(info, plan_arg)
        geo = plans / "geojson_map.json"
        self.geojson_path: Optional[Path] = geo if geo.is_file() else None
        image = plans / "floor_image.png"
        self.image_path: Optional[Path] = image if image.is_file() else None
        self._cache = cache
        self._allow_unsorted = allow_unsorted
        self._walks: Dict[int, IlcWalk] = {}
        self._vocabulary: Optional[BssidVocabulary] = None
        self._skipped: Dict[int, str] = {}       # walk index -> why it could not be read
        self._dropped: Dict[int, Dict[str, int]] = {}  # walk index -> IlcWalk.dropped_fields
        self._read: Set[int] = set()             # walk indices read at least once

    def __repr__(self) -> str:
        return (f"IlcFloor({self.name!r}, {self.n_walks} walks, width_m={self.width_m}, "
                f"height_m={self.height_m})")

    @property
    def n_walks(self) -> int:
        """Number of walk files (readable or not)."""
        return len(self.walk_paths)

    @property
    def walk_ids(self) -> List[str]:
        """Walk ids (file names without ``.txt``), in :attr:`walk_paths` order."""
        return [p.stem for p in self.walk_paths]

    @property
    def skipped_walks(self) -> Dict[str, str]:
        """``{walk id: reason}`` of the walks the iterating readers skipped so far (in walk
        order): files that cannot be read (the reason is the FormatError's message)."""
        ids = self.walk_ids
        return {ids[k]: self._skipped[k] for k in sorted(self._skipped)}

    def _index(self, key: Union[int, str]) -> int:
        if isinstance(key, str):
            ids = self.walk_ids
            if key not in ids:
                raise UnknownWalkError(
                    f"indoorloc: argument 'key': no walk {key!r} on floor {self.name} (its "
                    f"{self.n_walks} walks are the *.txt files of {self.walk_paths[0].parent}; "
                    f"IlcFloor.walk_ids lists them)")
            return ids.index(key)
        if isinstance(key, bool) or not isinstance(key, (int, np.integer)):
            raise TypeError(f"indoorloc: argument 'key': a walk index (int) or walk id (str), "
                            f"got {key!r} ({type(key).__name__})")
        k = int(key)
        if not 0 <= k < self.n_walks:
            raise IndexError(f"indoorloc: argument 'key': walk {k} outside "
                             f"0..{self.n_walks - 1} (floor {self.name} has {self.n_walks} walks)")
        return k

    def _load(self, k: int) -> IlcWalk:
        if k in self._walks:
            return self._walks[k]
        w = read_ilc_walk(self.walk_paths[k], allow_unsorted=self._allow_unsorted)
        self._read.add(k)
        self._skipped.pop(k, None)
        if w.dropped_fields:
            self._dropped[k] = dict(w.dropped_fields)
        if self._cache:
            self._walks[k] = w
        return w

    def walk(self, key: Union[int, str]) -> IlcWalk:
        """Walk number ``key`` (in :attr:`walk_paths` order) or the walk with id ``key``.

        Raises
        ------
        TypeError
            ``key`` is neither an int nor a str (``1.5``, ``True``).
        IndexError
            An index outside ``0 .. n_walks - 1``.
        KeyError
            (:class:`UnknownWalkError`) no walk has the id ``key``; the message names it and
            says how many walks the floor has.
        FormatError
            The walk file cannot be read (damage to what the methods need): the file and line.
        """
        return self._load(self._index(key))

    def walks(self, keys: Optional[Iterable[Union[int, str]]] = None) -> Iterator[IlcWalk]:
        """Iterate over the walks (all, or those of ``keys``), reading each on demand.

        A walk that cannot be read (a FormatError) is skipped with a RecordingWarning naming the
        file and the reason (once per walk) and listed in :attr:`skipped_walks`; a wrong key
        raises as in :meth:`walk`.
        """
        indices = range(self.n_walks) if keys is None else [self._index(k) for k in keys]
        for k in indices:
            if k in self._skipped:
                continue
            try:
                w = self._load(k)
            except ValueError as exc:  # FormatError: the file's fault, not the caller's
                self._skipped[k] = str(exc)
                self._read.add(k)
                warnings.warn(f"indoorloc: floor {self.name}: walk {self.walk_paths[k]} skipped: "
                              f"{exc}", RecordingWarning, stacklevel=2)
                continue
            yield w

    def load_report(self) -> Dict[str, Any]:
        """What reading the walks so far skipped or dropped (all of them after :meth:`walks`).

        Returns ``{"floor", "n_walks" (files), "n_read", "n_loaded", "n_skipped",
        "skipped_walks": {walk id: reason}, "n_walks_with_dropped_fields",
        "dropped_fields": {"<TYPE> <field>": lines, summed over the walks},
        "walks_with_dropped_fields": {walk id: {field: lines}}, "n_warnings"}``:
        ``n_warnings`` is the number of RecordingWarnings those reads gave (one per walk with
        dropped fields, one per skipped walk).
        """
        ids = self.walk_ids
        total: Dict[str, int] = {}
        for counts in self._dropped.values():
            for key, n in counts.items():
                total[key] = total.get(key, 0) + n
        return {
            "floor": self.name,
            "n_walks": self.n_walks,
            "n_read": len(self._read),
            "n_loaded": len(self._read) - len(self._skipped),
            "n_skipped": len(self._skipped),
            "skipped_walks": self.skipped_walks,
            "n_walks_with_dropped_fields": len(self._dropped),
            "dropped_fields": total,
            "walks_with_dropped_fields": {ids[k]: dict(self._dropped[k])
                                          for k in sorted(self._dropped)},
            "n_warnings": len(self._dropped) + len(self._skipped),
        }

    def bssid_vocabulary(self, keys: Optional[Iterable[Union[int, str]]] = None
                         ) -> BssidVocabulary:
        """The BSSID vocabulary of all the floor's walks (cached) or of the walks ``keys``;
        walks that cannot be read are skipped as in :meth:`walks`."""
        if keys is not None:
            return BssidVocabulary.from_walks(self.walks(keys))
        if self._vocabulary is None:
            self._vocabulary = BssidVocabulary.from_walks(self.walks())
        return self._vocabulary

    def map_wifi(self, walk: IlcWalk) -> np.ndarray:
        """(R,) int64: the walk's readings' BSSIDs as indices into the floor vocabulary (-1 if
        the floor's walks never heard it)."""
        return self.bssid_vocabulary().map_walk(walk)

    def origin_lonlat(self) -> Tuple[float, float]:
        """(lon, lat) [deg] of the floor frame's origin: see :func:`ilc_floor_origin_lonlat`."""
        if self.geojson_path is None:
            arg = "floor_dir" if self.plan_dir == self.floor_dir else "plan_dir"
            raise ValueError(f"indoorloc: argument '{arg}': no geojson_map.json in {self.plan_dir}")
        return ilc_floor_origin_lonlat(self.geojson_path)


def _floor_info(path: Path, argument: str = "floor_dir") -> Tuple[float, float]:
    try:
        info = json.loads(path.read_text(encoding="utf-8"))
        width, height = float(info["map_info"]["width"]), float(info["map_info"]["height"])
    except (ValueError, KeyError, TypeError) as exc:
        raise format_error(path, f"expected {{'map_info': {{'width': ..., 'height': ...}}}} ({exc})",
                           argument=argument) from None
    if not (np.isfinite(width) and np.isfinite(height) and width > 0 and height > 0):
        raise format_error(path, f"width and height must be positive, got {width}, {height}",
                           argument=argument)
    return width, height


@reads_file("floor_dir")  # a damaged walk or floor folder is a FormatError, as for every reader
def read_ilc_floor(floor_dir: PathLike, *, plan_dir: Optional[PathLike] = None, cache: bool = True,
                   allow_unsorted: bool = False) -> IlcFloor:
    """Open one floor: its walks (``<floor>/path_data_files/*.txt`` or ``<floor>/*.txt``, read on
    demand) and its plan files (``floor_info.json``, ``geojson_map.json``, ``floor_image.png``)
    in ``plan_dir``, by default the floor folder itself (ILC 2020); the Kaggle 2021 data keeps
    them in ``ROOT/metadata/SITE/FLOOR``. See :class:`IlcFloor`; to find a site's floors in
    either layout, :func:`indoorloc.io.survey_layout.survey_floors` (``SurveyFloor.open()``).

    Raises
    ------
    ValueError
        ``indoorloc: argument 'floor_dir': ...`` when the folder does not exist or holds no
        walk file; ``argument 'plan_dir'`` (``'floor_dir'`` without one) when that folder does
        not exist or its ``floor_info.json`` is malformed.
    """
    return IlcFloor(floor_dir, plan_dir=plan_dir, cache=cache, allow_unsorted=allow_unsorted)


_FLOOR_LEVEL = (  # (pattern of a floor name, sign of its level)
    (re.compile(r"B(\d+)|(\d+)B", re.IGNORECASE), -1),
    (re.compile(r"[FL](\d+)|(\d+)F", re.IGNORECASE), 1),
)


def ilc_floor_level(name: str) -> Optional[int]:
    """Building level of a floor folder name: ``B2`` / ``2B`` -> -2, ``G`` / ``GF`` -> 0,
    ``F3`` / ``3F`` / ``L3`` -> 3; None for another name."""
    if name.upper() in ("G", "GF"):
        return 0
    for pattern, sign in _FLOOR_LEVEL:
        m = pattern.fullmatch(name)
        if m:
            return sign * int(m.group(1) or m.group(2))
    return None


def _is_floor_dir(d: Path, with_plan: bool) -> bool:
    if not d.is_dir() or (with_plan and not (d / "geojson_map.json").is_file()):
        return False
    if (d / "path_data_files").is_dir():
        return True
    return any(p.is_file() for p in d.glob("*.txt"))


def ilc_floor_names(site_dir: PathLike, *, with_plan: bool = False,
                    argument: str = "site_dir") -> List[str]:
    """The floor folders of a site folder in the ILC 2020 layout, in building order (B2, B1, G,
    F1, F2, ...; names that are not levels (:func:`ilc_floor_level`) last, by name). For a
    survey folder of either competition layout (Kaggle 2021 keeps the plans apart), use
    :func:`indoorloc.io.survey_layout.survey_floors`.

    A floor folder is a sub-folder holding ``path_data_files/`` or ``*.txt`` walk files, and,
    with ``with_plan=True`` (what a tracker needs), ``geojson_map.json``. ``argument`` is the
    name the error messages give the folder (a caller's own parameter, e.g. ``data_root``).

    Raises
    ------
    ValueError
        ``indoorloc: argument '<argument>': ...`` when the folder does not exist or holds no
        floor folder.
    """
    d = Path(site_dir)
    if not d.is_dir():
        raise ValueError(f"indoorloc: argument '{argument}': folder not found: {d}")
    names = [f.name for f in d.iterdir() if _is_floor_dir(f, with_plan)]
    if not names:
        need = " and geojson_map.json" if with_plan else ""
        raise ValueError(f"indoorloc: argument '{argument}': no floor folder with "
                         f"path_data_files/ or *.txt walk files{need} in {d}")

    def order(name: str) -> Tuple[int, int, str]:
        level = ilc_floor_level(name)
        return (0, level, name) if level is not None else (1, 0, name)

    return sorted(names, key=order)


@reads_file("site_dir")  # a damaged walk or floor folder is a FormatError, as for every reader
def read_ilc_site(site_dir: PathLike, *, cache: bool = True,
                  allow_unsorted: bool = False) -> Dict[str, IlcFloor]:
    """Open every floor of a site folder: ``{floor folder name: IlcFloor}`` in building order
    (:func:`ilc_floor_names`: B2, B1, F1, F2, ...).

    A floor is any sub-folder holding ``path_data_files/`` or ``*.txt`` walk files.

    Raises
    ------
    ValueError
        ``indoorloc: argument 'site_dir': ...`` when the folder does not exist or has no floor.
    """
    d = Path(site_dir)
    return {name: IlcFloor(d / name, cache=cache, allow_unsorted=allow_unsorted)
            for name in ilc_floor_names(d)}


def _lonlat_points(coords: Any) -> Iterator[Tuple[float, float]]:
    if (isinstance(coords, (list, tuple)) and len(coords) >= 2
            and all(isinstance(c, (int, float)) for c in coords[:2])):
        yield float(coords[0]), float(coords[1])
        return
    if isinstance(coords, (list, tuple)):
        for c in coords:
            yield from _lonlat_points(c)


@reads_file("geojson_path")  # a damaged geojson_map.json is a FormatError, as for every reader
def ilc_floor_origin_lonlat(geojson_path: PathLike) -> Tuple[float, float]:
    """(min lon, min lat) [deg] of the first feature's bounding box in ``geojson_map.json``.

    The competition's floor frame is metres east and north of this south-west corner of the
    floor outline's bounding box (the first feature).

    Raises
    ------
    ValueError
        ``indoorloc: argument 'geojson_path': ...`` when the file is missing, not JSON, or its
        first feature has no coordinates or a coordinate that is not a finite number (NaN,
        Infinity: JSON readers accept them).
    """
    p = Path(geojson_path)
    if not p.is_file():
        raise ValueError(f"indoorloc: argument 'geojson_path': file not found: {p}")
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
        coords = doc["features"][0]["geometry"]["coordinates"]
    except (ValueError, KeyError, IndexError, TypeError) as exc:
        raise ValueError(f"indoorloc: argument 'geojson_path': {p}: expected a FeatureCollection "
                         f"whose first feature has geometry coordinates ({exc!r})") from None
    points = list(_lonlat_points(coords))
    if not points:
        raise ValueError(f"indoorloc: argument 'geojson_path': {p}: the first feature has no "
                         f"coordinates")
    bad = [pt for pt in points if not (np.isfinite(pt[0]) and np.isfinite(pt[1]))]
    if bad:
        raise ValueError(f"indoorloc: argument 'geojson_path': {p}: the first feature has "
                         f"{len(bad)} coordinate(s) that are not finite numbers, first "
                         f"{list(bad[0])} (the origin would be NaN)")
    lon = min(pt[0] for pt in points)
    lat = min(pt[1] for pt in points)
    return lon, lat


# --------------------------------------------------------------------------------------------
# Data facts
