"""Indoor Location Competition 2.0 loader, the rule "nothing is lost" (docs/errors.md): an
optional field damaged is dropped for its line with one RecordingWarning, a truncated last line is
dropped, damage to a needed field still rejects the walk. Fixture files: ilc2020_files.py."""

import copy
import dataclasses
import warnings

import numpy as np
import pytest

from indoorloc.io import (
    FormatError,
    RecordingWarning,
    read_ilc_walk,
)

from ilc2020_files import (
    damage,
    drop_last_field,
    field,
    HEADER,
    line_of,
    set_field,
    T0,
    walk_records,
    write_walk,
)


def _assert_same(a, b, path="walk"):
    """Every field of two loader results equal (NaN equal to NaN), notes and paths aside."""
    if dataclasses.is_dataclass(a):
        for f in dataclasses.fields(a):
            if f.name not in ("path", "walk_id", "notes", "dropped_fields"):
                _assert_same(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype, path
        np.testing.assert_array_equal(a, b, err_msg=path)
    else:
        assert a == b, path


def _read_warned(p, n_warnings=1):
    """read_ilc_walk(p) and the RecordingWarnings it gave (exactly n_warnings)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        walk = read_ilc_walk(p)
    got = [w for w in caught if issubclass(w.category, RecordingWarning)]
    assert len(got) == len(caught) == n_warnings, [str(w.message) for w in caught]
    for w in got:
        assert str(p) in str(w.message)
    return walk, [str(w.message) for w in got]


def _nan_at(attr, index):
    def edit(walk):
        obj = walk
        for a in attr.split("."):
            obj = getattr(obj, a)
        obj[index] = -1 if obj.dtype.kind == "i" else np.nan
    return edit


def _last_seen_is_scan_time(r):
    def edit(walk):
        walk.wifi.last_seen_s[r] = walk.wifi.scan_time_s[r]
        walk.wifi.last_seen_fallback[r] = True
    return edit


@pytest.mark.parametrize("needle, nth, k, bad, key, edit, rv_w", [
    ("\tTYPE_BEACON\t", 1, 7, "Infinity", "TYPE_BEACON distance", _nan_at("beacons.distance_m", 1), False),
    ("\tTYPE_BEACON\t", 0, 5, "", "TYPE_BEACON tx_power", _nan_at("beacons.tx_power_dbm", 0), False),
    ("\tTYPE_BEACON\t", 1, 6, "-9e999", "TYPE_BEACON rssi", _nan_at("beacons.rssi_dbm", 1), False),
    ("\tTYPE_BEACON\t", 0, 3, "x", "TYPE_BEACON major", _nan_at("beacons.major", 0), False),
    ("\tTYPE_BEACON\t", 1, 4, "2.5", "TYPE_BEACON minor", _nan_at("beacons.minor", 1), False),
    ("\tTYPE_WIFI\t", 4, 5, "abc", "TYPE_WIFI frequency", _nan_at("wifi.frequency_mhz", 4), False),
    ("\tTYPE_WIFI\t", 5, 6, "", "TYPE_WIFI last_seen_unix_ms", _last_seen_is_scan_time(5), False),
    ("\tTYPE_WIFI\t", 2, 6, "1574142O12000", "TYPE_WIFI last_seen_unix_ms", _last_seen_is_scan_time(2),
     False),
    ("\tTYPE_ACCELEROMETER\t", 11, 5, "2.5", "TYPE_ACCELEROMETER accuracy",
     _nan_at("accelerometer.accuracy", 11), False),
    ("\tTYPE_GYROSCOPE\t", 3, 5, "NaN", "TYPE_GYROSCOPE accuracy", _nan_at("gyroscope.accuracy", 3), False),
    ("\tTYPE_GYROSCOPE_UNCALIBRATED\t", 7, 5, "nan", "TYPE_GYROSCOPE_UNCALIBRATED bias x",
     _nan_at("gyroscope_uncalibrated.bias", (7, 0)), False),
    ("\tTYPE_ROTATION_VECTOR\t", 2, 5, "Infinity", "TYPE_ROTATION_VECTOR w",
     _nan_at("rotation_vector.values", (2, 3)), True),
])
def test_damaged_optional_field_is_dropped_for_its_line(tmp_path, needle, nth, k, bad, key, edit, rv_w):
    """Loader rule: an optional field's damage drops that field for that line (NaN, -1 or the
    reading's fallback), with one RecordingWarning and the count in the walk's notes."""
    clean = tmp_path / "clean.txt"
    write_walk(clean, rv_w=rv_w)
    p = tmp_path / "damaged.txt"
    write_walk(p, rv_w=rv_w)
    n = damage(p, needle, set_field(k, bad), nth)
    walk, messages = _read_warned(p)
    assert key in messages[0] and "kept" in messages[0]
    assert walk.dropped_fields == {key: 1}
    assert len(walk.notes) == 1 and walk.notes[0].startswith(key) and f"line {n} " in walk.notes[0]
    assert repr(bad) in walk.notes[0]
    expected = copy.deepcopy(read_ilc_walk(clean))
    edit(expected)
    _assert_same(walk, expected)


def test_fallback_rotation_w_is_completed(tmp_path):
    p = tmp_path / "w.txt"
    write_walk(p, rv_w=True)
    damage(p, "\tTYPE_ROTATION_VECTOR\t", set_field(5, "Infinity"), 2)
    walk, _ = _read_warned(p)
    q = walk.rotation_quaternion_xyzw()
    assert np.all(np.isfinite(q))
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)


def test_many_damaged_fields_give_one_warning_with_counts(tmp_path):
    p = tmp_path / "w.txt"
    write_walk(p)
    damage(p, "\tTYPE_BEACON\t", set_field(7, "Infinity"), 0)
    damage(p, "\tTYPE_BEACON\t", set_field(7, "Infinity"), 1)
    damage(p, "\tTYPE_WIFI\t", set_field(5, ""), 3)
    damage(p, "\tTYPE_MAGNETIC_FIELD\t", set_field(5, "x"), 0)
    walk, messages = _read_warned(p, 1)
    assert walk.dropped_fields == {"TYPE_BEACON distance": 2, "TYPE_WIFI frequency": 1,
                                   "TYPE_MAGNETIC_FIELD accuracy": 1}
    assert "TYPE_BEACON distance x2" in messages[0]
    assert len(walk.notes) == 3
    assert np.all(np.isnan(walk.beacons.distance_m))
    assert walk.magnetometer.accuracy[0] == -1 and np.all(walk.magnetometer.accuracy[1:] >= 0)


def test_needed_damage_still_rejects_when_optional_damage_is_present(tmp_path):
    p = tmp_path / "w.txt"
    write_walk(p)
    damage(p, "\tTYPE_BEACON\t", set_field(7, "Infinity"), 0)
    n = damage(p, "\tTYPE_WIFI\t", set_field(4, "Infinity"), 6)
    with pytest.raises(FormatError, match=rf"line {n}: TYPE_WIFI field 5 \(rssi\) is not a number"):
        read_ilc_walk(p)


def test_beacon_line_with_wrong_field_count_is_dropped(tmp_path):
    """No method reads iBeacons: a beacon line that cannot be split into its fields is dropped,
    not the walk."""
    clean = tmp_path / "clean.txt"
    write_walk(clean)
    p = tmp_path / "w.txt"
    write_walk(p)
    n = damage(p, "\tTYPE_BEACON\t", drop_last_field, 0)
    n = damage(p, "\tTYPE_BEACON\t", drop_last_field, 0)  # 8 fields
    walk, _ = _read_warned(p)
    assert walk.dropped_fields == {"TYPE_BEACON line": 1}
    assert f"line {n} " in walk.notes[0] and "8 tab-separated fields" in walk.notes[0]
    assert walk.beacons.n_readings == 1
    np.testing.assert_array_equal(walk.beacons.t_s, read_ilc_walk(clean).beacons.t_s[1:])


LAST_T = T0 + 900  # after every record of the fixture
FULL_LAST = {
    "acc": f"{LAST_T}\tTYPE_ACCELEROMETER\t0.125\t-0.5\t9.75\t3",
    "wifi": f"{LAST_T}\tTYPE_WIFI\tguest\t00:10:f3:32:7c:ba\t-80\t2462\t{LAST_T - 10}",
    "wp": f"{LAST_T}\tTYPE_WAYPOINT\t158.5\t91.25",
    "beacon": f"{LAST_T}\tTYPE_BEACON\tE6E7\t0\t0\t0\t-79\t1.5\tF7:9F:CE:70:3B:60\t{LAST_T}",
}


@pytest.mark.parametrize("kind, cut", [
    ("acc", lambda s: s[:8]),                                   # the time stamp only
    ("acc", lambda s: s[:s.index("TYPE")]),                     # "<time>\t"
    ("acc", lambda s: s[:s.index("TYPE") + 8]),                 # record type cut short
    ("acc", lambda s: s[:s.index("-0.5") + 2]),                 # fewer fields
    ("acc", lambda s: s[:-1]),                                  # empty accuracy
    ("acc", lambda s: s[:-2]),                                  # 5 fields
    ("wifi", lambda s: s[:s.index("00:10") + 5]),               # cut in the BSSID
    ("wifi", lambda s: s[:s.rindex("\t") + 1] + "15741e"),      # partial number
    ("wp", lambda s: s[:-5] + "-"),                             # partial y
    ("wp", lambda s: s[:-5]),                                   # empty y
    ("beacon", lambda s: s[:s.rindex("\t") + 1]),               # empty time
])
def test_truncated_last_line_is_dropped(tmp_path, kind, cut):
    """An interrupted recording: the file's last line cut short is dropped with a warning."""
    lines = HEADER + walk_records(np.random.default_rng(0))[0]
    clean = tmp_path / "clean.txt"
    clean.write_text("\n".join(lines), encoding="utf-8")
    p = tmp_path / "cut.txt"
    p.write_text("\n".join(lines + [cut(FULL_LAST[kind])]), encoding="utf-8")
    walk, messages = _read_warned(p)
    assert walk.dropped_fields == {"truncated last line": 1}
    assert "truncated last line" in messages[0]
    assert f"line {len(lines) + 1} " in walk.notes[0]
    _assert_same(walk, read_ilc_walk(clean))
    # The same line complete is read, and a cut line followed by more text is damage.
    p.write_text("\n".join(lines + [FULL_LAST[kind]]) + "\n", encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_ilc_walk(p).duration_s == pytest.approx(0.9)


def test_cut_line_before_the_end_is_damage(tmp_path):
    lines = HEADER + walk_records(np.random.default_rng(0))[0]
    p = tmp_path / "w.txt"
    p.write_text("\n".join(lines + [FULL_LAST["acc"][:-2], "#\tendTime:1"]), encoding="utf-8")
    with pytest.raises(FormatError, match=rf"line {len(lines) + 1}: TYPE_ACCELEROMETER has 5"):
        read_ilc_walk(p)


def test_decreasing_times_raise_or_are_sorted(tmp_path):
    p = tmp_path / "w.txt"
    exp = write_walk(p)
    lines = p.read_text(encoding="utf-8").split("\n")
    a = line_of(lines, "\tTYPE_GYROSCOPE\t", 10)
    b = line_of(lines, "\tTYPE_GYROSCOPE\t", 11)
    t_a, t_b = lines[a - 1].split("\t")[0], lines[b - 1].split("\t")[0]
    lines[a - 1], lines[b - 1] = lines[b - 1], lines[a - 1]  # the later sample first
    p.write_text("\n".join(lines), encoding="utf-8")
    with pytest.raises(ValueError, match=rf"TYPE_GYROSCOPE times decrease 1 time\(s\), first at "
                                         rf"line {b} \({t_a} ms after {t_b} ms at line {a}\)"):
        read_ilc_walk(p)
    walk = read_ilc_walk(p, allow_unsorted=True)
    np.testing.assert_array_equal(walk.gyroscope.t_s, exp["gyroscope"]["t_s"])
    np.testing.assert_array_equal(walk.gyroscope.values, exp["gyroscope"]["values"])
    assert len(walk.notes) == 1 and "TYPE_GYROSCOPE" in walk.notes[0] and "sorted" in walk.notes[0]


def test_missing_and_empty_files(tmp_path):
    with pytest.raises(ValueError, match="file not found"):
        read_ilc_walk(tmp_path / "none.txt")
    p = tmp_path / "empty.txt"
    p.write_text("#\tstartTime:1\n\n")
    with pytest.raises(ValueError, match="no sensor, WiFi, iBeacon or waypoint record"):
        read_ilc_walk(p)
