"""Reading one Indoor Location Competition 2.0 walk file into an IlcWalk (read_ilc_walk): the
tab-separated records parsed by type into numpy arrays, damaged optional fields dropped with a
warning.

Part of :mod:`indoorloc.io.ilc2020` (the format is described there)."""

from __future__ import annotations

import io
import warnings
from dataclasses import field
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc.io.errors import RecordingWarning, reads_file
from indoorloc.io.ilc2020.walk_types import ILC_SENSOR_TYPES, IlcBeacons, IlcSensor, IlcWalk, IlcWifi, PathLike, _BEACON, _CR, _LAYOUTS, _NL, _NUMBER, _NUMBER_BYTES, _TAB, _TEXT_FIELDS, _TYPE_NAME, _WAYPOINT, _WIFI, _fallback


def _err(message: str) -> ValueError:
    return ValueError(f"indoorloc: argument 'path': {message}")


def _gather_ranges(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Concatenation of ``arange(a[i], b[i])`` over i (vectorised); b >= a."""
    lens = b - a
    total = int(lens.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    ends = np.cumsum(lens)
    return np.arange(total, dtype=np.int64) + np.repeat(a - (ends - lens), lens)


class _WalkText:
    """The raw bytes of one walk file with line and tab positions (all numpy).

    A last data line cut short (an interrupted recording, see :func:`_truncation`) is taken out
    of the data lines and kept in :attr:`truncated` as (line number, text, reason).
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        raw = path.read_bytes()
        self.raw = raw
        buf = np.frombuffer(raw, dtype=np.uint8)
        # Two sentinel bytes after the text: a tab and a newline, used as field separators when
        # gathering fields of many lines into one buffer (see _fields_bytes).
        self.bufx = np.concatenate([buf, np.array([_TAB, _NL], dtype=np.uint8)])
        self.tab_pos = len(raw)
        self.nl_pos = len(raw) + 1
        nl = np.flatnonzero(buf == _NL)
        starts = np.concatenate([[0], nl + 1]).astype(np.int64)
        ends = np.concatenate([nl, [len(raw)]]).astype(np.int64)
        if raw.startswith(b"\xef\xbb\xbf"):  # UTF-8 byte-order mark
            starts[0] = min(3, int(ends[0]))
        line_no = np.arange(1, starts.size + 1, dtype=np.int64)
        if buf.size:  # a CR before the LF (Windows line ends) is not part of the line
            ends = ends - ((ends > starts) & (buf[np.maximum(ends - 1, 0)] == _CR))
        nonempty = ends > starts
        starts, ends, line_no = starts[nonempty], ends[nonempty], line_no[nonempty]
        header = buf[starts] == ord("#")
        self.header_lines = [self.line_text(int(s), int(e))
                             for s, e in zip(starts[header], ends[header])]
        data = ~header
        # The file's last line, when a data line cut short, is an interrupted recording.
        self.truncated: Optional[Tuple[int, str, str]] = None
        if starts.size and data[-1]:
            last = self.line_text(int(starts[-1]), int(ends[-1]))
            reason = _truncation(last)
            if reason is not None:
                self.truncated = (int(line_no[-1]), last, reason)
                data[-1] = False
        self.starts, self.ends, self.line_no = starts[data], ends[data], line_no[data]
        self.tabs = np.flatnonzero(buf == _TAB).astype(np.int64)
        self.first_tab_index = np.searchsorted(self.tabs, self.starts)
        self.n_tabs = np.searchsorted(self.tabs, self.ends) - self.first_tab_index

    # -- helpers -----------------------------------------------------------------------------

    def line_text(self, start: int, end: int) -> str:
        return self.raw[start:end].decode("utf-8", errors="replace")

    def where(self, i: int) -> str:
        """``"<file>, line <n>"`` of data line i."""
        return f"{self.path}, line {int(self.line_no[i])}"

    def shown(self, i: int, limit: int = 120) -> str:
        return _shown(self.line_text(int(self.starts[i]), int(self.ends[i])), limit)

    def field_bounds(self, sel: np.ndarray, j: int) -> Tuple[np.ndarray, np.ndarray]:
        """Byte range [a, b) of field j (0 = time, 1 = type, ...) of the data lines ``sel``.

        The lines must have more than j - 1 tabs; the last field runs to the end of the line.
        """
        i0 = self.first_tab_index[sel]
        ntab = self.n_tabs[sel]
        if j == 0:
            a = self.starts[sel]
        else:
            a = self.tabs[i0 + j - 1] + 1
        last = j >= ntab
        b = np.where(last, self.ends[sel], self.tabs[np.minimum(i0 + j, self.tabs.size - 1)]
                     if self.tabs.size else self.ends[sel])
        return a, b

    def field_str(self, i: int, j: int) -> str:
        """Field j of data line i as text (Python, for a few lines only)."""
        a, b = self.field_bounds(np.array([i]), j)
        return self.line_text(int(a[0]), int(b[0]))

    def fields_bytes(self, sel: np.ndarray, fields: Sequence[int]) -> bytes:
        """Fields ``fields`` (increasing) of the lines ``sel``, tab-separated, one line per row."""
        runs: List[List[int]] = []  # consecutive fields are copied as one byte range
        for j in fields:
            if runs and j == runs[-1][-1] + 1:
                runs[-1].append(j)
            else:
                runs.append([j])
        a_parts, b_parts = [], []
        for k, run in enumerate(runs):
            a, _ = self.field_bounds(sel, run[0])
            _, b = self.field_bounds(sel, run[-1])
            sep = self.nl_pos if k == len(runs) - 1 else self.tab_pos
            a_parts += [a, np.full_like(a, sep)]
            b_parts += [b, np.full_like(a, sep + 1)]
        a = np.stack(a_parts, axis=1).ravel()
        b = np.stack(b_parts, axis=1).ravel()
        return self.bufx[_gather_ranges(a, b)].tobytes()

    # -- record types ------------------------------------------------------------------------

    def classify(self) -> Tuple[List[str], np.ndarray]:
        """Record type of every data line: (type names, (L,) index into them)."""
        if self.starts.size == 0:
            return [], np.zeros(0, dtype=np.int64)
        no_tab = self.n_tabs == 0
        if np.any(no_tab):
            i = int(np.argmax(no_tab))
            raise _err(f"{self.where(i)}: not a record (expected 'unix_ms<TAB>TYPE_...<TAB>"
                       f"values', found no tab): {self.shown(i)}")
        a, b = self.field_bounds(np.arange(self.starts.size), 1)
        length = b - a
        names: List[str] = []
        type_index = np.empty(self.starts.size, dtype=np.int64)
        buf = self.bufx
        for n in np.unique(length):
            rows = np.flatnonzero(length == n)
            if n == 0:
                raise _err(f"{self.where(int(rows[0]))}: empty record type: "
                           f"{self.shown(int(rows[0]))}")
            tokens = buf[a[rows, None] + np.arange(n)].view(f"S{n}").ravel()
            uniq, inverse = np.unique(tokens, return_inverse=True)
            type_index[rows] = inverse.reshape(-1) + len(names)
            names += [t.decode("utf-8", errors="replace") for t in uniq]
        for k, name in enumerate(names):
            if not _TYPE_NAME.fullmatch(name):
                i = int(np.argmax(type_index == k))
                raise _err(f"{self.where(i)}: record type {name!r} is not a type name "
                           f"(expected e.g. TYPE_ACCELEROMETER): {self.shown(i)}")
        return names, type_index

    def check_field_count(self, sel: np.ndarray, type_name: str,
                          allowed: Sequence[Tuple[str, ...]],
                          drops: Optional["_Drops"] = None) -> np.ndarray:
        """The lines of ``sel`` with an allowed field count. A line with another count raises,
        or, when ``drops`` is given (a record type no method needs), is dropped and counted."""
        counts = self.n_tabs[sel] + 1
        ok = np.isin(counts, [len(f) for f in allowed])
        if np.all(ok):
            return sel
        i = int(sel[np.argmax(~ok)])
        expected = " or ".join(f"{len(f)} ({', '.join(f)})" for f in allowed)
        problem = (f"{type_name} has {int(self.n_tabs[i]) + 1} tab-separated fields, expected "
                   f"{expected}")
        if drops is None:
            raise _err(f"{self.where(i)}: {problem}: {self.shown(i)}")
        drops.add(f"{type_name} line", int(np.sum(~ok)), "with a wrong field count",
                  int(self.line_no[i]), f"{problem}: {self.shown(i)}", "the lines dropped")
        return sel[ok]

    def numbers(self, sel: np.ndarray, fields: Sequence[int], names: Sequence[str],
                type_name: str, integer: Sequence[bool],
                drops: Optional["_Drops"] = None) -> Tuple[np.ndarray, np.ndarray]:
        """Numeric fields of the lines ``sel``: ``(values, dropped)``, both (len(sel),
        len(fields)); ``values`` float64, ``dropped`` True where an optional field was damaged
        (NaN in ``values``; counted in ``drops``). Damage to a needed field raises, naming the
        first such line.

        Fast path: one ``np.loadtxt`` over the fields of all the lines (``Infinity`` and
        ``NaN`` parse there, and are then dropped or refused as non-finite). Only when it
        refuses the text: the lines holding a byte that cannot be part of a number, or an empty
        field, are parsed in Python one field at a time, the others by ``np.loadtxt`` again
        (split in halves until the lines it refuses are isolated, should it refuse more).
        """
        n, k = sel.size, len(fields)
        if n == 0:
            return np.zeros((0, k), dtype=np.float64), np.zeros((0, k), dtype=bool)
        text = self.fields_bytes(sel, fields)
        values = _loadtxt(text, n, k)
        slow = np.zeros(n, dtype=bool)
        if values is None:
            values = np.full((n, k), np.nan)
            buf = np.frombuffer(text, dtype=np.uint8)
            sep = (buf == _NL) | (buf == _TAB)
            empty_field = sep & np.concatenate([[True], sep[:-1]])
            odd = np.flatnonzero(~_NUMBER_BYTES[buf] | empty_field)
            slow[np.searchsorted(np.flatnonzero(buf == _NL), odd)] = True
            pending = [np.flatnonzero(~slow)] if not np.all(slow) else []
            while pending:
                rows = pending.pop()
                parsed = _loadtxt(self.fields_bytes(sel[rows], fields), rows.size, k)
                if parsed is not None:
                    values[rows] = parsed
                elif rows.size == 1:
                    slow[rows] = True  # e.g. "1e" or "1.2.3": number bytes, not a number
                else:
                    pending += [rows[: rows.size // 2], rows[rows.size // 2:]]
        for r in np.flatnonzero(slow):  # the slow path: only the lines that need it
            for c, j in enumerate(fields):
                values[r, c] = _number(self.field_str(int(sel[r]), j))
        bad = ~np.isfinite(values)
        ints = np.asarray(integer, dtype=bool)
        if np.any(ints):
            v = values[:, ints]
            bad[:, ints] |= np.isfinite(v) & (v != np.round(v))
        if not np.any(bad):
            return values, bad
        fallbacks = [_fallback(type_name, name) for name in names]
        needed = np.array([f is None for f in fallbacks])
        if np.any(bad[:, needed]):
            r = int(np.argmax(np.any(bad[:, needed], axis=1)))
            c = int(np.flatnonzero(bad[r] & needed)[0])
            raise _err(f"{self.where(int(sel[r]))}: "
                       + _field_problem(self.field_str(int(sel[r]), fields[c]),
                                        f"{type_name} field {fields[c] + 1} ({names[c]})",
                                        bool(ints[c])))
        values[bad] = np.nan
        if drops is not None:
            for c in np.flatnonzero(np.any(bad, axis=0)):
                r = int(np.argmax(bad[:, c]))
                first = _field_problem(self.field_str(int(sel[r]), fields[c]),
                                       f"field {fields[c] + 1}", bool(ints[c]))
                drops.add(f"{type_name} {names[c]}", int(np.sum(bad[:, c])),
                          "with a damaged value", int(self.line_no[sel[r]]), first,
                          f"replaced by {fallbacks[c]}")
        return values, bad


def _loadtxt(text: bytes, n: int, k: int) -> Optional[np.ndarray]:
    """(n, k) float64 of tab-separated rows of numbers, or None when np.loadtxt refuses them."""
    try:
        values = np.loadtxt(io.BytesIO(text), delimiter="\t", comments=None, dtype=np.float64,
                            ndmin=2, encoding="utf-8")
    except ValueError:
        return None
    return values if values.shape == (n, k) else None


def _shown(text: str, limit: int = 120) -> str:
    return repr(text if len(text) <= limit else text[:limit] + "...")


def _number(s: str) -> float:
    """float(s) when s is a number in the file's notation (``Infinity``, ``nan``, ``1_0`` are
    not), else NaN."""
    s = s.strip()
    return float(s) if _NUMBER.fullmatch(s) else float("nan")


def _field_problem(s: str, what: str, integer: bool) -> str:
    """``"<what> is not a number: '...'"`` (or "is not finite", "must be an integer")."""
    if not _NUMBER.fullmatch(s.strip()):
        return f"{what} is not a number: {s!r}"
    if not np.isfinite(float(s)):
        return f"{what} is not finite: {s!r}"
    if integer:
        return f"{what} must be an integer: {s!r}"
    return f"{what} is damaged: {s!r}"


def _truncation(line: str) -> Optional[str]:
    """Why the file's last line looks cut short by an interrupted recording, or None.

    Cut short: no tab (a time stamp alone), an empty record type or one that is the beginning
    of a known type's name, fewer fields than the type's shortest layout, or a last field that
    is not a complete number where a number belongs (``""``, ``"-"``, ``"1e"``).
    """
    parts = line.split("\t")
    if len(parts) < 2 or not parts[1]:
        return "no record type"
    type_name = parts[1]
    layouts = _LAYOUTS.get(type_name)
    if layouts is None:
        if any(t.startswith(type_name) for t in _LAYOUTS):
            return f"record type {type_name!r} cut short"
        return None  # another record type: skipped and counted like every unknown type
    shortest = min(len(f) for f in layouts)
    if len(parts) < shortest:
        return f"{len(parts)} fields, {type_name} has at least {shortest}"
    layout = next((f for f in layouts if len(f) == len(parts)), None)
    if (layout is not None and layout[-1] not in _TEXT_FIELDS
            and not _NUMBER.fullmatch(parts[-1].strip())):
        return f"its last field ({layout[-1]}) is not a complete number: {parts[-1]!r}"
    return None


class _Drops:
    """What the reader dropped from one walk: counts per field and one sentence each."""

    def __init__(self) -> None:
        self.counts: Dict[str, int] = {}
        self.notes: List[str] = []

    def __bool__(self) -> bool:
        return bool(self.counts)

    def add(self, key: str, count: int, what: str, line: int, first: str, action: str) -> None:
        """``count`` lines ``what`` (e.g. "with a damaged value"), the first at ``line``
        (``first``: what was wrong there); ``action``: what the reader did."""
        self.counts[key] = self.counts.get(key, 0) + count
        self.notes.append(f"{key}: {count} line(s) {what}, first at line {line} ({first}): "
                          f"{action}")

    def warning(self, path: Path) -> str:
        what = ", ".join(f"{k} x{v}" for k, v in self.counts.items())
        return (f"indoorloc: {path}: the walk is kept, damaged data that no method needs was "
                f"dropped: {what} (lines in walk.notes, counts in walk.dropped_fields)")


def _check_sorted(text: _WalkText, sel: np.ndarray, t_ms: np.ndarray, what: str,
                  allow_unsorted: bool, notes: List[str]) -> np.ndarray:
    """Order (indices into sel) that makes t_ms non-decreasing; raise if needed and not allowed."""
    back = np.diff(t_ms) < 0
    if not np.any(back):
        return np.arange(t_ms.size)
    k = int(np.argmax(back))
    n_back = int(back.sum())
    message = (f"{what} times decrease {n_back} time(s), first at line "
               f"{int(text.line_no[sel[k + 1]])} ({int(t_ms[k + 1])} ms after "
               f"{int(t_ms[k])} ms at line {int(text.line_no[sel[k]])})")
    if not allow_unsorted:
        raise _err(f"{text.path}: {message}; pass allow_unsorted=True to sort them")
    notes.append(f"{message}: sorted by time (stable)")
    return np.argsort(t_ms, kind="stable")


def _parse_header(lines: Sequence[str]) -> Dict[str, Any]:
    meta: Dict[str, Any] = {}
    sensors: List[Dict[str, Any]] = []
    for line in lines:
        parts = [p for p in line.lstrip("#").split("\t") if p.strip()]
        pairs = [(p.split(":", 1) + [""])[:2] for p in parts]
        pairs = [(k.strip(), v.strip()) for k, v in pairs]
        if pairs and pairs[0][0] == "type":
            sensors.append({k: _header_value(v) for k, v in pairs})
        else:
            for k, v in pairs:
                meta.setdefault(k, v)
    meta["sensors"] = sensors
    return meta


def _header_value(v: str) -> Any:
    for convert in (int, float):
        try:
            return convert(v)
        except ValueError:
            pass
    return v


def _empty_sensor(type_name: str) -> IlcSensor:
    _, unit, names = ILC_SENSOR_TYPES[type_name]
    z = np.zeros(0, dtype=np.float64)
    return IlcSensor(type_name=type_name, unit=unit, t_s=z, values=np.zeros((0, 3)),
                     accuracy=np.zeros(0, dtype=np.int64),
                     bias=np.zeros((0, 3)) if len(names) == 6 else None)


def _int_or(values: np.ndarray, missing: int = -1) -> np.ndarray:
    """int64 of whole-number floats, ``missing`` where NaN (a dropped field)."""
    return np.where(np.isnan(values), missing, values).astype(np.int64)


@reads_file("path")  # a damaged walk or floor folder is a FormatError, as for every reader
def read_ilc_walk(path: PathLike, *, allow_unsorted: bool = False) -> IlcWalk:
    """Read one walk file (``path_data_files/<walk id>.txt``) into numpy arrays.

    Parameters
    ----------
    path : str or pathlib.Path
        The walk file.
    allow_unsorted : bool, default False
        When a record type's times decrease somewhere, sort that stream by time (stable) and
        say so in :attr:`IlcWalk.notes` instead of raising.

    Returns
    -------
    IlcWalk
        Sensor streams, WiFi and iBeacon readings, waypoints and header metadata; every time in
        seconds since the walk's first record (``t0_unix_ms``). Damaged optional fields (see
        the module's "Errors: nothing is lost") are dropped for their line only, with ONE
        :class:`~indoorloc.io.errors.RecordingWarning` and the counts in
        :attr:`IlcWalk.dropped_fields`; a truncated last line is dropped the same way.

    Raises
    ------
    FormatError
        (a ValueError) ``indoorloc: argument 'path': <file>, line <n>: ...`` for damage to what
        the methods need: a line with no record type, a record type that is not a name, a
        field count that does not match the type (iBeacon lines are dropped instead), a time
        stamp, sensor x/y/z, WiFi RSSI or waypoint that is not a finite number, a time stamp
        that is not an integer, an empty BSSID; and for times that decrease within a record
        type (unless ``allow_unsorted``); ``... file not found`` when there is no file.
    """
    p = Path(path)
    if not p.is_file():
        raise _err(f"file not found: {p}")
    text = _WalkText(p)
    drops = _Drops()
    if text.truncated is not None:
        line, shown, reason = text.truncated
        drops.add("truncated last line", 1, "cut short (an interrupted recording)", line,
                  f"{reason}: {_shown(shown)}", "dropped")
    names, type_index = text.classify()
    by_type = {name: np.flatnonzero(type_index == k) for k, name in enumerate(names)}
    unknown = {name: int(sel.size) for name, sel in by_type.items() if name not in _LAYOUTS}
    empty = np.zeros(0, dtype=np.int64)
    notes: List[str] = []

    def numbers(sel: np.ndarray, layout: Tuple[str, ...], fields: Sequence[int],
                type_name: str) -> np.ndarray:
        field_names = [layout[j] for j in fields]
        integer = [name in ("unix_ms", "accuracy", "major", "minor", "last_seen_unix_ms")
                   for name in field_names]
        return text.numbers(sel, fields, field_names, type_name, integer, drops)[0]

    # Numeric parse of every known type, times still in unix ms.
    parsed: Dict[str, Tuple[np.ndarray, np.ndarray]] = {}  # type -> (line indices, values)
    for type_name, (_, _, value_names) in ILC_SENSOR_TYPES.items():
        sel = by_type.get(type_name, empty)
        layouts = _LAYOUTS[type_name]
        text.check_field_count(sel, type_name, layouts)
        if type_name == "TYPE_ROTATION_VECTOR":
            layout, with_w = layouts
            has_w = text.n_tabs[sel] + 1 == len(with_w)
            rows = np.full((sel.size, len(with_w) - 1), np.nan)
            for mask, lay in ((~has_w, layout), (has_w, with_w)):
                fields = [0] + list(range(2, len(lay)))
                cols = [0, 1, 2, 3, 5] if len(lay) == len(layout) else [0, 1, 2, 3, 4, 5]
                rows[np.ix_(mask, cols)] = numbers(sel[mask], lay, fields, type_name)
            if not np.any(has_w):
                rows = rows[:, [0, 1, 2, 3, 5]]
            parsed[type_name] = (sel, rows)
        else:
            layout = layouts[0]
            parsed[type_name] = (sel, numbers(sel, layout, [0] + list(range(2, len(layout))),
                                              type_name))

    wifi_layout = _LAYOUTS[_WIFI][0]
    wifi_sel = by_type.get(_WIFI, empty)
    text.check_field_count(wifi_sel, _WIFI, (wifi_layout,))
    wifi_num = numbers(wifi_sel, wifi_layout, [0, 4, 5, 6], _WIFI)
    # A damaged last-seen time: the scan time (flagged in a 5th column, kept through sorting).
    fallback = np.isnan(wifi_num[:, 3])
    wifi_num[fallback, 3] = wifi_num[fallback, 0]
    parsed[_WIFI] = (wifi_sel, np.column_stack([wifi_num, fallback]))

    wp_layout = _LAYOUTS[_WAYPOINT][0]
    wp_sel = by_type.get(_WAYPOINT, empty)
    text.check_field_count(wp_sel, _WAYPOINT, (wp_layout,))
    parsed[_WAYPOINT] = (wp_sel, numbers(wp_sel, wp_layout, [0, 2, 3], _WAYPOINT))

    beacon_layout = _LAYOUTS[_BEACON][0]
    beacon_sel = text.check_field_count(by_type.get(_BEACON, empty), _BEACON, _LAYOUTS[_BEACON],
                                        drops)
    parsed[_BEACON] = (beacon_sel, numbers(beacon_sel, beacon_layout, [0, 3, 4, 5, 6, 7],
                                           _BEACON))

    # The walk's clock: t = 0 at its first parsed record.
    firsts = [int(v[:, 0].min()) for _, v in parsed.values() if v.shape[0]]
    if not firsts:
        raise _err(f"{p}: no sensor, WiFi, iBeacon or waypoint record")
    t0 = min(firsts)

    def seconds(ms: np.ndarray) -> np.ndarray:
        return (ms - float(t0)) / 1000.0

    def ordered(type_name: str, what: str) -> Tuple[np.ndarray, np.ndarray]:
        sel, values = parsed[type_name]
        order = _check_sorted(text, sel, values[:, 0], what, allow_unsorted, notes)
        return sel[order], values[order]

    sensors: Dict[str, IlcSensor] = {}
    for type_name, (attr, unit, value_names) in ILC_SENSOR_TYPES.items():
        _, values = ordered(type_name, type_name)
        if values.shape[0] == 0:
            sensors[attr] = _empty_sensor(type_name)
            continue
        uncal = len(value_names) == 6
        n_xyz = values.shape[1] - 2 if not uncal else 3
        sensors[attr] = IlcSensor(
            type_name=type_name, unit=unit, t_s=seconds(values[:, 0]),
            values=np.ascontiguousarray(values[:, 1:1 + n_xyz]),
            accuracy=_int_or(values[:, -1]),
            bias=np.ascontiguousarray(values[:, 4:7]) if uncal else None)

    wifi_sel, wifi_num = ordered(_WIFI, _WIFI + " scan")
    wifi = _wifi_arrays(text, wifi_sel, wifi_num, seconds)

    beacon_sel, beacon_num = ordered(_BEACON, _BEACON)
    beacons = IlcBeacons(
        t_s=seconds(beacon_num[:, 0]),
        uuid=[text.field_str(int(i), 2) for i in beacon_sel],
        major=_int_or(beacon_num[:, 1]), minor=_int_or(beacon_num[:, 2]),
        tx_power_dbm=beacon_num[:, 3], rssi_dbm=beacon_num[:, 4], distance_m=beacon_num[:, 5],
        mac=[text.field_str(int(i), 8) for i in beacon_sel])

    _, wp = ordered(_WAYPOINT, _WAYPOINT)
    if drops:
        # One warning per walk; stacklevel 3: the caller of read_ilc_walk (through reads_file).
        warnings.warn(drops.warning(p), RecordingWarning, stacklevel=3)
    return IlcWalk(
        path=p, walk_id=p.stem if p.suffix == ".txt" else p.name, t0_unix_ms=t0,
        wifi=wifi, beacons=beacons, waypoint_t_s=seconds(wp[:, 0]),
        waypoint_xy_m=np.ascontiguousarray(wp[:, 1:3]),
        metadata=_parse_header(text.header_lines), unknown_type_counts=unknown,
        notes=drops.notes + notes, dropped_fields=dict(drops.counts), **sensors)


def _wifi_arrays(text: _WalkText, sel: np.ndarray, num: np.ndarray, seconds) -> IlcWifi:
    """WiFi readings of the lines ``sel`` (scan order) with their numbers (R, 5): time, rssi,
    frequency, last seen, last-seen fallback flag."""
    if sel.size == 0:
        z = np.zeros(0, dtype=np.float64)
        return IlcWifi(scan_time_s=z, bssid_index=np.zeros(0, dtype=np.int64), rssi_dbm=z,
                       frequency_mhz=z, last_seen_s=z, bssids=[], ssids=[],
                       scan_starts=np.zeros(0, dtype=np.int64),
                       last_seen_fallback=np.zeros(0, dtype=bool))
    a, b = text.field_bounds(sel, 3)
    length = b - a
    if np.any(length == 0):
        i = int(sel[np.argmax(length == 0)])
        raise _err(f"{text.where(i)}: TYPE_WIFI field 4 (bssid) is empty: {text.shown(i)}")
    width = int(length.max())
    idx = a[:, None] + np.arange(width)
    keep = idx < b[:, None]
    gathered = np.where(keep, text.bufx[np.minimum(idx, text.bufx.size - 1)], 0)
    keys = np.ascontiguousarray(gathered.astype(np.uint8)).view(f"S{width}").ravel()
    uniq, inverse = np.unique(keys, return_inverse=True)
    bssid_index = inverse.reshape(-1).astype(np.int64)
    bssids = [u.decode("utf-8", errors="replace") for u in uniq]

    # SSID per BSSID: the first reading with a non-empty SSID (Python per BSSID, not per line).
    sa, sb = text.field_bounds(sel, 2)
    ssids = [""] * len(bssids)
    named = np.flatnonzero(sb > sa)
    if named.size:
        first_bssid, first_pos = np.unique(bssid_index[named], return_index=True)
        for v, r in zip(first_bssid, named[first_pos]):
            ssids[int(v)] = text.line_text(int(sa[r]), int(sb[r]))

    scan_ms = num[:, 0]
    scan_starts = np.flatnonzero(np.concatenate([[True], scan_ms[1:] != scan_ms[:-1]]))
    return IlcWifi(scan_time_s=seconds(scan_ms), bssid_index=bssid_index, rssi_dbm=num[:, 1],
                   frequency_mhz=num[:, 2], last_seen_s=seconds(num[:, 3]), bssids=bssids,
                   ssids=ssids, scan_starts=scan_starts.astype(np.int64),
                   last_seen_fallback=num[:, 4] > 0)


# --------------------------------------------------------------------------------------------
# BSSID vocabulary of a floor
