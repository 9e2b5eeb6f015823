"""Survey folders: where a site's walk files and floor plans are, in the two layouts of the
Indoor Location Competition (docs/your_building.md).

- ILC 2020: ``SITE/FLOOR/path_data_files/*.txt`` beside ``SITE/FLOOR/geojson_map.json`` and
  ``floor_info.json`` (pass ``SITE``);
- Kaggle 2021: ``ROOT/train/SITE/FLOOR/*.txt`` with the plans in
  ``ROOT/metadata/SITE/FLOOR/{geojson_map.json,floor_info.json}`` (pass ``ROOT`` when it holds
  one site, or ``ROOT/train/SITE``).

:func:`survey_floors` is the one definition of a site's floors: ``indoorloc site build`` and
``indoorloc fusion evaluate`` (and the studies beside it) take their floors from it;
:meth:`SurveyFloor.open` reads one with :func:`indoorloc.io.read_ilc_floor`.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import List, Optional, Sequence

from indoorloc.io.errors import RecordingWarning
from indoorloc.io.ilc2020 import IlcFloor, ilc_floor_level, read_ilc_floor


@dataclass
class SurveyFloor:
    """One floor of a survey folder: its name, building level, walk files and plan files.

    ``floor_dir`` is the floor's walk folder (ILC 2020: ``SITE/FLOOR``, the walks in its
    ``path_data_files/``; Kaggle 2021: ``ROOT/train/SITE/FLOOR``), ``plan_dir`` the folder of
    its ``geojson_map.json``, ``floor_info.json`` and ``floor_image.png`` (ILC 2020: the same
    folder; Kaggle 2021: ``ROOT/metadata/SITE/FLOOR``)."""

    name: str
    number: int
    walk_paths: List[Path]
    geojson_path: Path
    floor_info_path: Optional[Path]
    floor_dir: Path
    plan_dir: Path

    def open(self, *, cache: bool = True, allow_unsorted: bool = False) -> IlcFloor:
        """The floor read as an :class:`~indoorloc.io.IlcFloor` (walks on demand, plan from
        ``plan_dir``): ``read_ilc_floor(floor_dir, plan_dir=plan_dir, ...)``."""
        return read_ilc_floor(self.floor_dir, plan_dir=self.plan_dir, cache=cache,
                              allow_unsorted=allow_unsorted)


def floor_number(name: str) -> int:
    """Building level of a floor folder name (``ilc_floor_level``: B1 -> -1, F3 -> 3, 1F -> 1);
    for another name, its digits (none: 0)."""
    level = ilc_floor_level(name)
    if level is not None:
        return level
    digits = "".join(ch for ch in name if ch.isdigit())
    return int(digits or 0)


def _err(argument: str, msg: str) -> ValueError:
    return ValueError(f"indoorloc: argument '{argument}': {msg}")


def _kaggle_site(root: Path, argument: str) -> Optional[tuple]:
    """(walk root, plan root) of a Kaggle 2021 folder, or None for another layout."""
    if (root / "train").is_dir() and (root / "metadata").is_dir():
        sites = sorted(d.name for d in (root / "train").iterdir() if d.is_dir())
        if len(sites) != 1:
            raise _err(argument, f"{root} is a Kaggle 2021 folder with {len(sites)} sites under train/; "
                                 f"pass one site folder, e.g. {root / 'train' / (sites[0] if sites else 'SITE')}")
        return root / "train" / sites[0], root / "metadata" / sites[0]
    if root.parent.name == "train" and (root.parent.parent / "metadata" / root.name).is_dir():
        return root, root.parent.parent / "metadata" / root.name
    return None


def _walk_files(floor_dir: Path) -> List[Path]:
    """The floor's walk files as :class:`~indoorloc.io.IlcFloor` lists them."""
    walk_dir = floor_dir / "path_data_files"
    walk_dir = walk_dir if walk_dir.is_dir() else floor_dir
    return sorted(p for p in walk_dir.glob("*.txt") if p.is_file())


def survey_floors(survey_dir: Path, floors: Optional[Sequence[str]] = None, *,
                  argument: str = "survey_dir") -> List[SurveyFloor]:
    """The floors of a survey folder (either layout, module docstring), in building order
    (:func:`floor_number`), or those named in ``floors``.

    A floor is a sub-folder holding walk files (``path_data_files/*.txt`` or ``*.txt``); a
    sub-folder without any is not one (``notes/``). A floor needs its plan
    (``geojson_map.json``): when ``floors`` is not given, a floor folder with walks but no plan
    is skipped with a :class:`~indoorloc.io.errors.RecordingWarning` naming it (the other
    floors can still be used); a floor named in ``floors`` without walks or plan is an error.
    ``argument`` is the name the errors give ``survey_dir`` (a caller's own parameter, e.g.
    ``data_root``).

    Raises
    ------
    ValueError
        ``indoorloc: argument '<argument>': ...`` when the folder does not exist, holds several
        Kaggle sites, no floor with walks and a plan, a named floor without walks or plan, or two
        floors of the same level; ``argument 'floors'`` for a named floor that is not there.
    """
    root = Path(survey_dir)
    if not root.is_dir():
        raise _err(argument, f"folder not found: {root}")
    kaggle = _kaggle_site(root, argument)
    walk_root, plan_root = kaggle if kaggle else (root, root)
    names = sorted((d.name for d in walk_root.iterdir() if d.is_dir()), key=lambda n: (floor_number(n), n))
    if floors:
        missing = [f for f in floors if f not in names]
        if missing:
            raise ValueError(f"indoorloc: argument 'floors': {missing} not in {walk_root} (floors: {names})")
        names = [n for n in names if n in floors]
    out, no_plan = [], []
    for name in names:
        fdir, pdir = walk_root / name, plan_root / name
        walks = _walk_files(fdir)
        geojson = pdir / "geojson_map.json"
        if not walks:
            if floors:
                raise _err(argument, f"floor {name}: no walk file in {fdir}")
            continue
        if not geojson.is_file():
            if floors:
                raise _err(argument, f"floor {name}: no floor plan {geojson}")
            no_plan.append(name)
            warnings.warn(f"indoorloc: argument '{argument}': floor {name} skipped: {len(walks)} walk file(s) "
                          f"in {fdir} but no floor plan {geojson}", RecordingWarning, stacklevel=2)
            continue
        info = pdir / "floor_info.json"
        out.append(SurveyFloor(name, floor_number(name), walks, geojson, info if info.is_file() else None,
                               fdir, pdir))
    if not out:
        shown = no_plan if len(no_plan) <= 8 else no_plan[:8] + [f"... {len(no_plan)} in all"]
        why = f"; folders with walk files but no plan (geojson_map.json under {plan_root}): {shown}" if no_plan else ""
        raise _err(argument, f"no floor folder with walk files (path_data_files/*.txt or *.txt) and a "
                             f"floor plan under {walk_root}{why}")
    numbers = [f.number for f in out]
    if len(set(numbers)) != len(numbers):
        raise _err(argument, f"two floor folders map to the same level: {[(f.name, f.number) for f in out]}")
    return out


def floor_info_size_m(path: Optional[Path]) -> Optional[tuple]:
    """(width, height) [m] of ``floor_info.json``'s ``map_info``, or None."""
    if path is None:
        return None
    try:
        info = json.loads(Path(path).read_text())["map_info"]
        return float(info["width"]), float(info["height"])
    except (KeyError, TypeError, ValueError, json.JSONDecodeError) as exc:
        raise ValueError(f"indoorloc: {path}: malformed floor_info.json ({exc})") from None


__all__ = ["SurveyFloor", "floor_info_size_m", "floor_number", "survey_floors"]
