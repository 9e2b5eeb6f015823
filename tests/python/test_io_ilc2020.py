"""Indoor Location Competition 2.0 loader (indoorloc.io.ilc2020): one walk, and damaged lines.

The fixture files are written by the tests themselves in the competition's format; the tests on
the shared site (../shared/data/fusion/ilc2020_site2) skip when it is absent. The loader rule
"nothing is lost" (docs/errors.md): damage to a needed field rejects the walk naming file and
line (test_damaged_line_names_file_and_line); an optional field is dropped for its line with one
RecordingWarning (test_damaged_optional_field_is_dropped_for_its_line and after); a truncated
last line is dropped (test_truncated_last_line_is_dropped); floor readers skip a bad walk
(test_floor_readers_skip_a_bad_walk_and_report_it).

The rule "nothing is lost" is tested in test_io_ilc2020_recovery.py, floors and sites in
test_io_ilc2020_site.py; the fixture files in ilc2020_files.py.
"""

import warnings

import numpy as np
import pytest

from indoorloc.io import (
    FormatError,
    read_ilc_walk,
)

from ilc2020_files import check_walk, damage, drop_last_field, field, set_field, T0, write_walk


def test_read_walk_parses_every_record_type(tmp_path):
    p = tmp_path / "5dd38ffd27889b0006b76aca.txt"
    exp = write_walk(p)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # an undamaged walk reads without a warning
        walk = read_ilc_walk(p)
    check_walk(walk, exp)
    assert walk.walk_id == "5dd38ffd27889b0006b76aca" and walk.path == p
    assert walk.n_waypoints == 3
    assert walk.duration_s == pytest.approx(0.132 + 0.02 * 29)
    assert walk.site_id == "5dbc1d84c1eb61796cf7c010" and walk.floor_name == "F3"
    assert walk.device == "OPPO PBCM10"


def test_read_walk_header_metadata(tmp_path):
    p = tmp_path / "w.txt"
    write_walk(p)
    meta = read_ilc_walk(p).metadata
    assert meta["startTime"] == "1574142011992" and meta["SiteName"] == "杭州大悦城"
    assert meta["Model"] == "PBCM10" and meta["APILevel"] == "27"
    assert meta["VersionCode"] == "403" and meta["endTime"] == str(T0 + 132 + 20 * 29)
    assert [s["name"] for s in meta["sensors"]] == ["BMI160 Accelerometer", "BMI160 Gyroscope"]
    acc = meta["sensors"][0]
    assert acc["type"] == 1 and acc["vendor"] == "BOSCH"
    assert acc["resolution"] == pytest.approx(0.0023956299)
    assert acc["maximumRange"] == pytest.approx(39.22661)


def test_wifi_scans_and_stale_readings(tmp_path):
    p = tmp_path / "w.txt"
    write_walk(p)
    w = read_ilc_walk(p).wifi
    assert w.n_readings == 9 and w.n_scans == 3
    np.testing.assert_array_equal(w.scan_times_s, [0.25, 0.42, 0.6])
    np.testing.assert_array_equal(w.scan_index, [0, 0, 0, 1, 1, 1, 1, 2, 2])
    assert w.scan_slice(1) == slice(3, 7) and w.scan_slice(2) == slice(7, 9)
    with pytest.raises(IndexError):
        w.scan_slice(3)
    # Reading age = scan time - last seen; the 19.4 s old reading was seen before the walk began.
    np.testing.assert_allclose(w.age_s, [0.476, 0.475, 8.124, 0.012, 19.377, 0.003, 2.1, 0.1,
                                         2.28])
    assert w.last_seen_s.min() < 0
    # The last reading repeats scan 1's measurement of 00:10:f3:32:7c:ba (same last-seen time).
    np.testing.assert_array_equal(w.new_measurement_mask(), [True] * 8 + [False])
    # One BSSID twice in scan 1 (2412 and 2437 MHz), once with an empty SSID.
    dup = w.bssids.index("9c:a6:15:27:3b:29")
    assert np.sum(w.bssid_index[w.scan_slice(1)] == dup) == 2


def test_rotation_vector_with_w_and_quaternions(tmp_path):
    p = tmp_path / "w.txt"
    exp = write_walk(p, seed=3, rv_w=True)
    walk = read_ilc_walk(p)
    check_walk(walk, exp)
    assert walk.rotation_vector.values.shape == (30, 4)
    q = walk.rotation_quaternion_xyzw()
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(q[:, 3], exp["rotation_vector"]["w"], atol=1e-6)

    p3 = tmp_path / "w3.txt"
    exp3 = write_walk(p3, seed=3, rv_w=False)
    walk3 = read_ilc_walk(p3)
    assert walk3.rotation_vector.values.shape == (30, 3)
    q3 = walk3.rotation_quaternion_xyzw()
    v = exp3["rotation_vector"]["values"]
    np.testing.assert_allclose(q3[:, :3], v, atol=1e-12)
    np.testing.assert_allclose(q3[:, 3], np.sqrt(1 - np.sum(v**2, axis=1)), atol=1e-12)


def test_crlf_line_ends(tmp_path):
    p = tmp_path / "w.txt"
    exp = write_walk(p, seed=5, newline="\r\n")
    check_walk(read_ilc_walk(p), exp)


def test_walk_without_wifi_or_waypoints(tmp_path):
    p = tmp_path / "w.txt"
    p.write_text("#\tFloorName:B1\n1000\tTYPE_ACCELEROMETER\t0.1\t0.2\t9.8\t3\n"
                 "1020\tTYPE_ACCELEROMETER\t0.1\t0.2\t9.7\t3\n1030\tTYPE_BLUE\t\tAA\t-80\n")
    walk = read_ilc_walk(p)
    assert walk.t0_unix_ms == 1000 and walk.accelerometer.n_samples == 2
    assert walk.gyroscope.n_samples == 0 and walk.gyroscope.values.shape == (0, 3)
    assert walk.gyroscope_uncalibrated.bias.shape == (0, 3)
    assert walk.wifi.n_readings == 0 and walk.wifi.n_scans == 0 and walk.wifi.bssids == []
    assert walk.n_waypoints == 0 and walk.waypoint_xy_m.shape == (0, 2)
    assert walk.beacons.n_readings == 0
    assert walk.unknown_type_counts == {"TYPE_BLUE": 1}
    assert walk.duration_s == pytest.approx(0.02)


# ------------------------------------------------------------------ damaged files
def not_a_number(record, nth, k, name, value):
    """A damaged-line case: field k (0-based, named `name`) of the nth `record` line set to `value`,
    which the loader must reject as not a number, naming the field (1-based) and the value."""
    return (f"\t{record}\t", nth, set_field(k, value), rf"{record} field {k + 1} \({name}\) is not a number: '{value}'")


@pytest.mark.parametrize("needle, nth, fix, message", [
    ("\tTYPE_ACCELEROMETER\t", 4, drop_last_field,
     r"TYPE_ACCELEROMETER has 5 tab-separated fields, expected 6 \(unix_ms, type, x, y, z, "
     r"accuracy\)"),
    ("\tTYPE_GYROSCOPE_UNCALIBRATED\t", 7, lambda s: s + "\t1.0",
     "TYPE_GYROSCOPE_UNCALIBRATED has 10 tab-separated fields, expected 9"),
    not_a_number("TYPE_GYROSCOPE", 2, 3, "y", "abc"),
    not_a_number("TYPE_MAGNETIC_FIELD", 9, 4, "z", ""),
    not_a_number("TYPE_ROTATION_VECTOR", 0, 2, "x", "nan"),
    not_a_number("TYPE_ACCELEROMETER_UNCALIBRATED", 11, 3, "y", "Infinity"),
    ("\tTYPE_GYROSCOPE\t", 12, set_field(2, "1e999"),
     r"TYPE_GYROSCOPE field 3 \(x\) is not finite: '1e999'"),
    ("\tTYPE_ACCELEROMETER\t", 12, set_field(0, "1574142012377.5"),
     r"field 1 \(unix_ms\) must be an integer"),
    not_a_number("TYPE_WIFI", 2, 4, "rssi", "-7x"),
    not_a_number("TYPE_WIFI", 5, 4, "rssi", ""),
    ("\tTYPE_WIFI\t", 1, set_field(3, ""), r"TYPE_WIFI field 4 \(bssid\) is empty"),
    ("\tTYPE_WIFI\t", 0, drop_last_field, "TYPE_WIFI has 6 tab-separated fields, expected 7"),
    ("\tTYPE_WAYPOINT\t", 1, drop_last_field, "TYPE_WAYPOINT has 3 tab-separated fields"),
    ("\tTYPE_BEACON\t", 1, set_field(0, "x"), r"TYPE_BEACON field 1 \(unix_ms\) is not a number"),
    ("\tTYPE_WAYPOINT\t", 2, set_field(2, "NaN"), r"TYPE_WAYPOINT field 3 \(x\) is not a number"),
    ("\tTYPE_GYROSCOPE\t", 6, lambda s: s.replace("\t", " "), "not a record"),
    ("\tTYPE_GYROSCOPE\t", 8, set_field(1, "0.25"), "record type '0.25' is not a type name"),
    ("\tTYPE_GYROSCOPE\t", 8, set_field(1, ""), "empty record type"),
])
def test_damaged_line_names_file_and_line(tmp_path, needle, nth, fix, message):
    """Damage to what the methods need (times, IMU x/y/z, WiFi RSSI and BSSID, waypoints, the
    field count) rejects the walk with a FormatError naming the file and the line."""
    p = tmp_path / "damaged.txt"
    write_walk(p)
    n = damage(p, needle, fix, nth)
    with pytest.raises(FormatError, match=message) as info:
        read_ilc_walk(p)
    text = str(info.value)
    assert f"{p}, line {n}:" in text, text
    assert text.startswith("indoorloc: argument 'path': ")
