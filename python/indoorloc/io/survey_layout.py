"""Survey folders: where a site's walk files and floor plans are, in the two layouts of the
Indoor Location Competition (docs/your_building.md).

- ILC 2020: ``SITE/FLOOR/path_data_files/*.txt`` beside ``SITE/FLOOR/geojson_map.json`` and
  ``floor_info.json`` (pass ``SITE``);
- Kaggle 2021: ``ROOT/train/SITE/FLOOR/*.txt`` with the plans in
  ``ROOT/metadata/SITE/FLOOR/{geojson_map.json,floor_info.json}`` (pass ``ROOT`` when it holds
  one site, or ``ROOT/train/SITE``).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import List, Optional, Sequence

from indoorloc.io.ilc2020 import ilc_floor_level


@dataclass
class SurveyFloor:
    """One floor of a survey folder: its name, building level, walk files and plan files."""

    name: str
    number: int
    walk_paths: List[Path]
    geojson_path: Path
    floor_info_path: Optional[Path]


def floor_number(name: str) -> int:
    """Building level of a floor folder name (``ilc_floor_level``: B1 -> -1, F3 -> 3, 1F -> 1);
    for another name, its digits (none: 0)."""
    level = ilc_floor_level(name)
    if level is not None:
        return level
    digits = "".join(ch for ch in name if ch.isdigit())
    return int(digits or 0)


def _err(msg: str) -> ValueError:
    return ValueError(f"indoorloc: argument 'survey_dir': {msg}")


def _kaggle_site(root: Path) -> Optional[tuple]:
    """(walk root, plan root) of a Kaggle 2021 folder, or None for another layout."""
    if (root / "train").is_dir() and (root / "metadata").is_dir():
        sites = sorted(d.name for d in (root / "train").iterdir() if d.is_dir())
        if len(sites) != 1:
            raise _err(f"{root} is a Kaggle 2021 folder with {len(sites)} sites under train/; pass one site "
                       f"folder, e.g. {root / 'train' / (sites[0] if sites else 'SITE')}")
        return root / "train" / sites[0], root / "metadata" / sites[0]
    if root.parent.name == "train" and (root.parent.parent / "metadata" / root.name).is_dir():
        return root, root.parent.parent / "metadata" / root.name
    return None


def survey_floors(survey_dir: Path, floors: Optional[Sequence[str]] = None) -> List[SurveyFloor]:
    """The floors of a survey folder (both layouts), in building order, or those named.

    Raises ValueError naming the folder when it does not exist, a named floor is absent, or a
    floor has no plan (``geojson_map.json``) or no walk file."""
    root = Path(survey_dir)
    if not root.is_dir():
        raise _err(f"folder not found: {root}")
    kaggle = _kaggle_site(root)
    walk_root, plan_root = kaggle if kaggle else (root, root)
    names = sorted((d.name for d in walk_root.iterdir() if d.is_dir()), key=lambda n: (floor_number(n), n))
    if floors:
        missing = [f for f in floors if f not in names]
        if missing:
            raise ValueError(f"indoorloc: argument 'floors': {missing} not in {walk_root} (floors: {names})")
        names = [n for n in names if n in floors]
    out = []
    for name in names:
        fdir = walk_root / name
        walks = sorted((fdir / "path_data_files").glob("*.txt")) if (fdir / "path_data_files").is_dir() \
            else sorted(fdir.glob("*.txt"))
        geojson = plan_root / name / "geojson_map.json"
        if not walks:
            if floors:
                raise _err(f"floor {name}: no walk file in {fdir}")
            continue
        if not geojson.is_file():
            raise _err(f"floor {name}: no floor plan {geojson}")
        info = plan_root / name / "floor_info.json"
        out.append(SurveyFloor(name, floor_number(name), walks, geojson, info if info.is_file() else None))
    if not out:
        raise _err(f"no floor folder with walk files under {walk_root}")
    numbers = [f.number for f in out]
    if len(set(numbers)) != len(numbers):
        raise _err(f"two floor folders map to the same level: {[(f.name, f.number) for f in out]}")
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
