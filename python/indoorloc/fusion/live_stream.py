"""The live tracker as a stream of text lines: phone sensor events in as NDJSON (one JSON object per
line), the live estimates out as NDJSON (``indoorloc live``, docs/your_building.md "Tracking live").

When to use: a process that receives a phone's events (a socket bridge, a log being replayed) and
wants positions as they come, without writing Python against :class:`fusion.live.LiveTracker`.

Input, format ``indoorloc-live-events`` version 1, one event per line in non-decreasing time (a
blank line or one starting with ``#`` is skipped):

- ``{"kind": "accelerometer", "t_s": T, "values": [x, y, z]}`` specific force [m/s²], device frame;
- ``{"kind": "gyroscope", "t_s": T, "values": [x, y, z]}`` angular rate [rad/s];
- ``{"kind": "rotation_vector", "t_s": T, "values": [x, y, z(, w(, accuracy))]}`` (Android's);
- ``{"kind": "wifi", "t_s": T, "bssids": [...], "rssi_dbm": [...], "last_seen_s": [...]}`` one
  scan, three lists of the same length;
- ``{"kind": "beacon", "t_s": T}`` (accepted and ignored: no beacon map yet).

T is seconds on one clock for every event (a phone's elapsed time, or Unix time). Extra keys are
ignored. A line that is not such an event, or that the tracker refuses (out of time order, a
non-finite value), is reported with its line number and skipped; the tracker is then unchanged.

Output, format ``indoorloc-live`` version 1: a header line ``{"format": "indoorloc-live",
"version": 1, "floor": NAME, "origin_lon_lat": [lon, lat] or null}``, then one line after each
event that added a filter step (detected or standing; one event can add two): ``t_s`` [s] of the
latest step, ``steps`` (filter steps so far),
``fixes`` (WiFi fixes applied so far), ``located`` (false until the first fix: the position is
then the floor's middle, not a position), ``position_m`` [x, y] in the floor frame,
``covariance_m2`` [xx, xy, yy] (the calibrated 95 % region's covariance), ``lon_lat`` [lon, lat]
(null without an origin), ``heading_offset_rad``. Names are stable; a change that removes or
renames one raises ``version``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Iterable, Iterator, List, Optional, Sequence, Tuple

import numpy as np

EVENTS_FORMAT = "indoorloc-live-events"
OUTPUT_FORMAT = "indoorloc-live"
VERSION = 1

_VECTOR_KINDS = {"accelerometer": (3, 3), "gyroscope": (3, 3), "rotation_vector": (3, 5)}


def _number(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{what} must be a number, got {value!r}")
    if not math.isfinite(float(value)):
        raise ValueError(f"{what} must be finite, got {value!r}")
    return float(value)


def _numbers(value: Any, what: str, lo: int, hi: int) -> List[float]:
    if not isinstance(value, list) or not lo <= len(value) <= hi:
        n = f"{lo}" if lo == hi else f"{lo} to {hi}"
        raise ValueError(f"{what} must be a list of {n} numbers, got {value!r}")
    return [_number(v, f"{what}[{k}]") for k, v in enumerate(value)]


def parse_event(line: str) -> Optional[Tuple]:
    """One input line (module docstring) as a :meth:`LiveTracker.add_event` tuple
    ``(kind, t_s, *values)``; None for a blank or ``#`` line. ValueError naming the field and the
    problem for anything else."""
    text = line.strip()
    if not text or text.startswith("#"):
        return None
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"not JSON ({exc.msg} at column {exc.colno})") from None
    if not isinstance(obj, dict):
        raise ValueError(f"expected a JSON object, got {type(obj).__name__}")
    kind = obj.get("kind")
    if kind not in (*_VECTOR_KINDS, "wifi", "beacon"):
        raise ValueError(f"'kind' must be one of accelerometer, gyroscope, rotation_vector, wifi, beacon; got {kind!r}")
    if "t_s" not in obj:
        raise ValueError("'t_s' is missing")
    t = _number(obj["t_s"], "'t_s'")
    if kind in _VECTOR_KINDS:
        lo, hi = _VECTOR_KINDS[kind]
        return (kind, t, np.asarray(_numbers(obj.get("values"), "'values'", lo, hi)))
    if kind == "beacon":
        return (kind, t)
    names = obj.get("bssids")
    if not isinstance(names, list) or not all(isinstance(b, str) for b in names):
        raise ValueError(f"'bssids' must be a list of strings, got {names!r}")
    n = len(names)
    rssi = _numbers(obj.get("rssi_dbm"), "'rssi_dbm'", n, n)
    seen = _numbers(obj.get("last_seen_s"), "'last_seen_s'", n, n)
    return (kind, t, names, np.asarray(rssi), np.asarray(seen))


def event_record(kind: str, t_s: float, *values: Any) -> Dict[str, Any]:
    """The input line's object of a :meth:`LiveTracker.add_event` tuple (the inverse of
    :func:`parse_event`), e.g. to write a recorded walk's :func:`fusion.live.walk_events` as NDJSON."""
    rec: Dict[str, Any] = {"kind": kind, "t_s": float(t_s)}
    if kind in _VECTOR_KINDS:
        rec["values"] = [float(v) for v in np.asarray(values[0], float).ravel()]
    elif kind == "wifi":
        names, rssi, seen = values[:3]
        rec.update(bssids=[str(b) for b in names], rssi_dbm=[float(v) for v in np.asarray(rssi, float)],
                   last_seen_s=[float(v) for v in np.asarray(seen, float)])
    return rec


def header_record(floor: str, origin_lon_lat: Optional[Sequence[float]]) -> Dict[str, Any]:
    """The output's first line (module docstring)."""
    return {"format": OUTPUT_FORMAT, "version": VERSION, "floor": str(floor),
            "origin_lon_lat": None if origin_lon_lat is None else [float(v) for v in origin_lon_lat]}


def estimate_record(estimate: Any, origin_lon_lat: Optional[Sequence[float]]) -> Dict[str, Any]:
    """One output line of a ``LiveEstimate`` (module docstring): metres in the floor frame, and
    longitude/latitude [deg] when the floor's origin is known."""
    xy = np.asarray(estimate.mean_m, float)
    lon_lat = None
    if origin_lon_lat is not None:
        from indoorloc.io.floor_plan import local_to_lonlat

        lon_lat = [float(v) for v in local_to_lonlat(xy[None, :], tuple(origin_lon_lat))[0]]
    return {"t_s": float(estimate.time_s), "steps": int(estimate.steps), "fixes": int(estimate.fixes),
            "located": bool(estimate.located), "position_m": [float(xy[0]), float(xy[1])],
            "covariance_m2": [float(v) for v in np.asarray(estimate.covariance_m2, float)],
            "lon_lat": lon_lat, "heading_offset_rad": float(estimate.heading_offset_rad)}


@dataclass
class StreamSummary:
    """What :func:`run` did: events given to the tracker, lines skipped (with the reason of each,
    ``problems``: (label, message)), estimates written."""

    events: int = 0
    skipped: int = 0
    estimates: int = 0
    problems: List[Tuple[str, str]] = field(default_factory=list)


def numbered_lines(lines: Iterable[str]) -> Iterator[Tuple[str, Optional[Tuple], Optional[str]]]:
    """``(label "line N", event or None, problem or None)`` per input line (:func:`parse_event`)."""
    for k, line in enumerate(lines, start=1):
        try:
            yield f"line {k}", parse_event(line), None
        except ValueError as exc:
            yield f"line {k}", None, str(exc)


def run(tracker: Any, events: Iterable[Tuple[str, Optional[Tuple], Optional[str]]],
        write: Callable[[Dict[str, Any]], None], origin_lon_lat: Optional[Sequence[float]] = None,
        warn: Optional[Callable[[str], None]] = None) -> StreamSummary:
    """Feed ``events`` ((label, event tuple or None, problem or None), e.g. :func:`numbered_lines`)
    to ``tracker`` (a :class:`fusion.live.LiveTracker`) and ``write`` each new estimate's
    :func:`estimate_record` (one per filter step). A problem, or an event the tracker refuses
    (ValueError: the tracker is unchanged), is passed to ``warn`` with its label and skipped."""
    summary = StreamSummary()
    last_steps = 0

    def skip(label: str, message: str) -> None:
        summary.skipped += 1
        summary.problems.append((label, message))
        if warn is not None:
            warn(f"{label}: skipped: {message}")

    for label, event, problem in events:
        if problem is not None:
            skip(label, problem)
            continue
        if event is None:
            continue
        try:
            estimate = tracker.add_event(*event)
        except ValueError as exc:
            skip(label, str(exc))
            continue
        summary.events += 1
        if estimate is not None and estimate.steps != last_steps:
            last_steps = estimate.steps
            write(estimate_record(estimate, origin_lon_lat))
            summary.estimates += 1
    return summary


__all__ = ["EVENTS_FORMAT", "OUTPUT_FORMAT", "StreamSummary", "VERSION", "estimate_record", "event_record",
           "header_record", "numbered_lines", "parse_event", "run"]
