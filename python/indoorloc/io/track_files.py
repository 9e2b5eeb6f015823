"""Track files written by ``indoorloc track`` (docs/your_building.md, "Track files"), chosen by
the output's extension:

- ``.geojson``: a FeatureCollection, one LineString feature per walk in WGS84 (lon, lat, RFC 7946)
  with properties ``walk``, ``source``, ``floor``, ``floor_number``, ``floor_probability``,
  ``t0_unix_ms``, ``times_s`` (per vertex, since the walk's first record), ``xy_m`` (the same
  vertices in the floor frame [m]), ``sd_m`` (per vertex sd_x, sd_y [m]), ``smoothed`` and
  ``wifi_fixes`` (the number of WiFi fixes used; 0: the walk is not located on the floor);
- ``.csv``: one row per step: ``walk, t_s, unix_ms, x_m, y_m, floor, sd_x_m, sd_y_m,
  floor_probability, lon, lat``;
- ``.json``: ``{"format": "indoorloc.track", "version": 1, "site": path, "walks": [{"walk",
  "source", "floor", "floor_number", "floor_probability", "floor_probabilities", "smoothed",
  "t0_unix_ms", "origin_lon_lat", "t_s", "x_m", "y_m", "sd_x_m", "sd_y_m", "cov_xy_m2",
  "header_floor", "wifi_fixes" (as in the GeoJSON), "waypoints": {"t_s", "x_m", "y_m", "error_m"
  (null when the tracked floor is not the header's)} or null, "errors": {"mean_m", "median_m", "p90_m", "n_waypoints"} or null}]}``.

``floor_probability`` is the calibrated probability of the walk's floor (1 when the floor was
given; with ``--floor auto`` at most 1 − δ (F − 1) / F, ``fusion.floor_evidence.FloorCalibration``).

Every file is written to a temporary name and renamed (never half-written).
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from indoorloc.io.atomic_file import write_text_atomic
from indoorloc.io.floor_plan import local_to_lonlat

TRACK_FORMAT_VERSION = 1
EXTENSIONS = (".geojson", ".csv", ".json")


def error_stats(errors_m: Optional[np.ndarray]) -> Optional[Dict[str, float]]:
    """Mean, median and 90th percentile [m] of waypoint errors, or None."""
    if errors_m is None or np.size(errors_m) == 0:
        return None
    e = np.asarray(errors_m, float)
    return {"mean_m": float(np.mean(e)), "median_m": float(np.median(e)), "p90_m": float(np.percentile(e, 90)),
            "n_waypoints": int(e.size)}


def wifi_fix_count(track) -> int:
    """Number of WiFi fixes the track used (0: no scan matched the site's fingerprints, so the
    walk is not located on its floor and its sds are the floor-wide prior's)."""
    return 0 if getattr(track, "fix_t_s", None) is None else int(np.size(track.fix_t_s))


def _sd(track) -> np.ndarray:
    c = np.asarray(track.covariance_m2, float)
    return np.sqrt(np.maximum(c[:, [0, 2]], 0.0))


def _lonlat(track) -> np.ndarray:
    return local_to_lonlat(np.asarray(track.xy_m, float), tuple(track.origin_lon_lat))


def _round(a: np.ndarray, nd: int) -> List:
    return np.round(np.asarray(a, float), nd).tolist()


def geojson_document(tracks: Sequence[Any]) -> Dict[str, Any]:
    feats = []
    for tr in tracks:
        feats.append({"type": "Feature",
                      "geometry": {"type": "LineString", "coordinates": _round(_lonlat(tr), 8)},
                      "properties": {"walk": tr.walk_id, "source": tr.source, "floor": tr.floor,
                                     "floor_number": tr.floor_number, "floor_probability": tr.floor_probability,
                                     "t0_unix_ms": tr.t0_unix_ms, "times_s": _round(tr.times_s, 3),
                                     "xy_m": _round(tr.xy_m, 3), "sd_m": _round(_sd(tr), 3),
                                     "smoothed": tr.smoothed, "wifi_fixes": wifi_fix_count(tr)}})
    return {"type": "FeatureCollection", "indoorloc_track_version": TRACK_FORMAT_VERSION, "features": feats}


def json_document(tracks: Sequence[Any], site_path: str = "") -> Dict[str, Any]:
    walks = []
    for tr in tracks:
        sd = _sd(tr)
        wp = None
        if tr.waypoint_t_s.size:
            wp = {"t_s": _round(tr.waypoint_t_s, 3), "x_m": _round(tr.waypoint_xy_m[:, 0], 3),
                  "y_m": _round(tr.waypoint_xy_m[:, 1], 3),
                  "error_m": None if tr.errors_m is None else _round(tr.errors_m, 3)}
        walks.append({"walk": tr.walk_id, "source": tr.source, "floor": tr.floor, "floor_number": tr.floor_number,
                      "floor_probability": tr.floor_probability, "floor_probabilities": tr.floor_probabilities,
                      "smoothed": tr.smoothed, "t0_unix_ms": tr.t0_unix_ms, "origin_lon_lat": list(tr.origin_lon_lat),
                      "t_s": _round(tr.times_s, 3), "x_m": _round(tr.xy_m[:, 0], 3), "y_m": _round(tr.xy_m[:, 1], 3),
                      "sd_x_m": _round(sd[:, 0], 3), "sd_y_m": _round(sd[:, 1], 3),
                      "cov_xy_m2": _round(np.asarray(tr.covariance_m2)[:, 1], 4),
                      "header_floor": tr.header_floor, "wifi_fixes": wifi_fix_count(tr), "waypoints": wp,
                      "errors": error_stats(tr.errors_m)})
    return {"format": "indoorloc.track", "version": TRACK_FORMAT_VERSION, "site": site_path, "walks": walks}


def csv_text(tracks: Sequence[Any]) -> str:
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["walk", "t_s", "unix_ms", "x_m", "y_m", "floor", "sd_x_m", "sd_y_m", "floor_probability", "lon", "lat"])
    for tr in tracks:
        sd, ll = _sd(tr), _lonlat(tr)
        for i, t in enumerate(tr.times_s):
            w.writerow([tr.walk_id, f"{t:.3f}", int(round(tr.t0_unix_ms + 1000.0 * t)), f"{tr.xy_m[i, 0]:.3f}",
                        f"{tr.xy_m[i, 1]:.3f}", tr.floor, f"{sd[i, 0]:.3f}", f"{sd[i, 1]:.3f}",
                        f"{tr.floor_probability:.4f}", f"{ll[i, 0]:.8f}", f"{ll[i, 1]:.8f}"])
    return out.getvalue()


def write_tracks(path: os.PathLike, tracks: Sequence[Any], site_path: str = "") -> Path:
    """Write tracks (``fusion.WalkTrack``) to ``path`` in the format of its extension (module
    docstring). ValueError naming the argument for another extension."""
    path = Path(path)
    ext = path.suffix.lower()
    if ext == ".geojson":
        text = json.dumps(geojson_document(tracks)) + "\n"
    elif ext == ".json":
        text = json.dumps(json_document(tracks, site_path), allow_nan=False) + "\n"
    elif ext == ".csv":
        text = csv_text(tracks)
    else:
        raise ValueError(f"indoorloc: argument 'output': {path}: unknown extension {ext!r} (one of {EXTENSIONS})")
    write_text_atomic(path, text)
    return path


__all__ = ["EXTENSIONS", "TRACK_FORMAT_VERSION", "error_stats", "geojson_document", "json_document", "write_tracks"]
