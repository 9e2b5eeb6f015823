"""Indoor Location Competition 2.0 loader (indoorloc.io.ilc2020).

The fixture files are written by the tests themselves in the competition's format; the tests on
the shared site (../shared/data/fusion/ilc2020_site2) skip when it is absent. The loader rule
"nothing is lost" (docs/errors.md): damage to a needed field rejects the walk naming file and
line (test_damaged_line_names_file_and_line); an optional field is dropped for its line with one
RecordingWarning (test_damaged_optional_field_is_dropped_for_its_line and after); a truncated
last line is dropped (test_truncated_last_line_is_dropped); floor readers skip a bad walk
(test_floor_readers_skip_a_bad_walk_and_report_it).
"""

import copy
import dataclasses
import json
import time
import warnings

import numpy as np
import pytest

from indoorloc.io import (
    ILC_SENSOR_TYPES,
    BssidVocabulary,
    FormatError,
    IlcFloor,
    IlcWalk,
    RecordingWarning,
    describe_ilc_floor,
    ilc_floor_level,
    ilc_floor_names,
    ilc_floor_origin_lonlat,
    read_ilc_floor,
    read_ilc_site,
    read_ilc_walk,
)

T0 = 1574142012005  # unix ms of the fixture walk's first parsed record
HEADER = [
    "#\tstartTime:1574142011992",
    "#\tSiteID:5dbc1d84c1eb61796cf7c010\tSiteName:杭州大悦城\tFloorId:5dbc1d8\tFloorName:F3",
    "#\tBrand:OPPO\tModel:PBCM10\tAndroidName:8.1.0\tAPILevel:27\t",
    "#\ttype:1\tname:BMI160 Accelerometer\tversion:2062600\tvendor:BOSCH\t"
    "resolution:0.0023956299\tpower:0.18\tmaximumRange:39.22661",
    "#\ttype:4\tname:BMI160 Gyroscope\tversion:2062600\tvendor:BOSCH\tresolution:0.0010681152"
    "\tpower:0.9\tmaximumRange:34.906586",
    "#\tVersionName:v20191105-nightly-16-gcd7805b\tVersionCode:403\t",
]


def _f(x):
    return repr(float(x))


def _walk_records(rng, *, n_epochs=30, rv_w=False, t0=T0):
    """Records of a fixture walk as (unix_ms, line) plus the expected arrays.

    Sensors at 50 Hz (every 20 ms) from t0 + 132 ms, three WiFi scans with stale last-seen
    times (one BSSID heard twice in a scan, once with an empty SSID), two iBeacon readings,
    three waypoints, and unknown types (TYPE_BLUE, TYPE_BLU4, TYPE_DIST1, TYPE_DIST2,
    TYPE_SENSOR_MAGNETIC_FIELD_ACCURACY_CHANGED).
    """
    recs = []  # (unix_ms, order, line)
    exp = {}
    sensor_t = t0 + 132 + 20 * np.arange(n_epochs)
    for k, (type_name, (attr, _, names)) in enumerate(ILC_SENSOR_TYPES.items()):
        n_val = len(names)
        values = np.round(rng.normal(0.0, 3.0, (n_epochs, n_val)), 7)
        if attr == "gyroscope":
            values[3, 1] = 5.0354004e-4  # written in Java's E notation below
        w = None
        if attr == "rotation_vector":
            values = np.round(rng.uniform(-0.5, 0.5, (n_epochs, 3)), 7)
            if rv_w:
                w = np.round(np.sqrt(1.0 - np.sum(values**2, axis=1)), 7)
        acc = rng.integers(0, 4, n_epochs)
        for i in range(n_epochs):
            vals = [_f(v) for v in values[i]]
            if attr == "gyroscope" and i == 3:
                vals[1] = "5.0354004E-4"
            if w is not None:
                vals.append(_f(w[i]))
            recs.append((int(sensor_t[i]), k,
                         "\t".join([str(sensor_t[i]), type_name, *vals, str(acc[i])])))
        exp[attr] = dict(t_s=(sensor_t - t0) / 1000.0, values=values[:, :3],
                         bias=values[:, 3:6] if n_val == 6 else None, accuracy=acc, w=w)

    # WiFi: scan time, then (ssid, bssid, rssi, freq, last_seen offset from scan [ms])
    scans = [
        (t0 + 250, [("JOY CITY", "04:40:a9:a1:89:00", -49, 5300, -476),
                    ("", "04:40:a9:a1:89:01", -50, 5300, -475),
                    ("大悦城", "9c:a6:15:27:3b:29", -71, 2437, -8124)]),
        (t0 + 420, [("", "9c:a6:15:27:3b:29", -76, 2412, -12),
                    ("TP-LINK", "9c:a6:15:27:3b:29", -71, 2437, -19377),
                    ("JOY CITY", "04:40:a9:a1:89:00", -52, 5300, -3),
                    ("guest", "00:10:f3:32:7c:ba", -88, 2462, -2100)]),
        (t0 + 600, [("", "04:40:a9:a1:89:01", -60, 5300, -100),
                    ("guest", "00:10:f3:32:7c:ba", -88, 2462, -2280)]),  # repeats scan 1's
    ]
    wifi_rows = []
    for t_scan, readings in scans:
        for ssid, bssid, rssi, freq, age in readings:
            wifi_rows.append((t_scan, ssid, bssid, rssi, freq, t_scan + age))
            recs.append((t_scan, 20, "\t".join([str(t_scan), "TYPE_WIFI", ssid, bssid, str(rssi),
                                                 str(freq), str(t_scan + age)])))
    bssids = sorted({r[2] for r in wifi_rows})
    exp["wifi"] = dict(
        scan_time_s=np.array([(r[0] - t0) / 1000.0 for r in wifi_rows]),
        bssid=[r[2] for r in wifi_rows], bssids=bssids,
        ssids={"04:40:a9:a1:89:00": "JOY CITY", "04:40:a9:a1:89:01": "",
               "9c:a6:15:27:3b:29": "大悦城", "00:10:f3:32:7c:ba": "guest"},
        rssi_dbm=np.array([r[3] for r in wifi_rows], float),
        frequency_mhz=np.array([r[4] for r in wifi_rows], float),
        last_seen_s=np.array([(r[5] - t0) / 1000.0 for r in wifi_rows]),
        scan_starts=np.array([0, 3, 7]),
    )

    beacons = [(t0 + 388, "9195B3AD-A9D0-4500-85FF-9FB0F65A5201", 0, 0, -54, -93,
                59.575296141470595, "78:A5:04:90:BA:10"),
               (t0 + 540, "9195B3AD-A9D0-4500-85FF-9FB0F65A5201", 10, 7, -59, -96, 76.06,
                "78:A5:04:90:BA:11")]
    for b in beacons:
        recs.append((b[0], 21, "\t".join([str(b[0]), "TYPE_BEACON", b[1], str(b[2]), str(b[3]),
                                          str(b[4]), str(b[5]), repr(b[6]), b[7], str(b[0])])))
    exp["beacons"] = beacons

    waypoints = [(t0, 165.0072, 100.43866), (t0 + 300, 160.12474, 97.64365),
                 (t0 + 650, 159.73796, 92.13583)]
    for t, x, y in waypoints:
        recs.append((t, 22, f"{t}\tTYPE_WAYPOINT\t{x!r}\t{y!r}"))
    exp["waypoint_t_s"] = np.array([(w[0] - t0) / 1000.0 for w in waypoints])
    exp["waypoint_xy_m"] = np.array([[w[1], w[2]] for w in waypoints])

    # Unknown types, one of them earlier than every parsed record (not the walk's t = 0).
    recs.append((t0 - 4, 30, f"{t0 - 4}\tTYPE_DIST1\t11.64856\t-6.5689087\t6.311035"))
    recs.append((t0 - 4, 31, f"{t0 - 4}\tTYPE_DIST2\t0.9941608\t0.9300582\t1.088228"))
    recs.append((t0 + 88, 32, f"{t0 + 88}\tTYPE_SENSOR_MAGNETIC_FIELD_ACCURACY_CHANGED\t3"))
    for i in range(5):
        t = t0 + 95 + 40 * i
        recs.append((t, 33, f"{t}\tTYPE_BLUE\t\t0D:F0:25:2D:E9:E{i}\t-88"))
        recs.append((t, 34, f"{t}\tTYPE_BLU4\t4872\t63831\t-88"))
    exp["unknown"] = {"TYPE_DIST1": 1, "TYPE_DIST2": 1, "TYPE_BLUE": 5, "TYPE_BLU4": 5,
                      "TYPE_SENSOR_MAGNETIC_FIELD_ACCURACY_CHANGED": 1}
    recs.sort(key=lambda r: (r[0], r[1]))
    return [r[2] for r in recs], exp


def _write_walk(path, seed=0, *, n_epochs=30, rv_w=False, t0=T0, newline="\n"):
    rng = np.random.default_rng(seed)
    lines, exp = _walk_records(rng, n_epochs=n_epochs, rv_w=rv_w, t0=t0)
    end = max(int(r.split("\t")[0]) for r in lines)
    text = HEADER + lines + [f"#\tendTime:{end}"]
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", encoding="utf-8", newline="") as f:
        f.write(newline.join(text) + newline)
    return exp


def _check_walk(walk, exp, t0=T0):
    assert isinstance(walk, IlcWalk)
    assert walk.t0_unix_ms == t0
    for type_name, (attr, unit, names) in ILC_SENSOR_TYPES.items():
        s, e = getattr(walk, attr), exp[attr]
        assert s.type_name == type_name and s.unit == unit
        np.testing.assert_array_equal(s.t_s, e["t_s"])
        np.testing.assert_array_equal(s.values[:, :3], e["values"])
        np.testing.assert_array_equal(s.accuracy, e["accuracy"])
        assert s.accuracy.dtype == np.int64
        if e["bias"] is None:
            assert s.bias is None
        else:
            np.testing.assert_array_equal(s.bias, e["bias"])
        if e["w"] is None:
            assert s.values.shape[1] == 3
        else:
            np.testing.assert_array_equal(s.values[:, 3], e["w"])
        assert s.rate_hz == pytest.approx(50.0)
    w, e = walk.wifi, exp["wifi"]
    np.testing.assert_array_equal(w.scan_time_s, e["scan_time_s"])
    assert [w.bssids[i] for i in w.bssid_index] == e["bssid"]
    assert w.bssids == e["bssids"]
    assert dict(zip(w.bssids, w.ssids)) == e["ssids"]
    np.testing.assert_array_equal(w.rssi_dbm, e["rssi_dbm"])
    np.testing.assert_array_equal(w.frequency_mhz, e["frequency_mhz"])
    np.testing.assert_array_equal(w.last_seen_s, e["last_seen_s"])
    np.testing.assert_array_equal(w.scan_starts, e["scan_starts"])
    b = walk.beacons
    eb = exp["beacons"]
    np.testing.assert_array_equal(b.t_s, [(r[0] - t0) / 1000.0 for r in eb])
    assert b.uuid == [r[1] for r in eb] and b.mac == [r[7] for r in eb]
    np.testing.assert_array_equal(b.major, [r[2] for r in eb])
    np.testing.assert_array_equal(b.minor, [r[3] for r in eb])
    np.testing.assert_array_equal(b.tx_power_dbm, [r[4] for r in eb])
    np.testing.assert_array_equal(b.rssi_dbm, [r[5] for r in eb])
    np.testing.assert_array_equal(b.distance_m, [r[6] for r in eb])
    np.testing.assert_array_equal(walk.waypoint_t_s, exp["waypoint_t_s"])
    np.testing.assert_array_equal(walk.waypoint_xy_m, exp["waypoint_xy_m"])
    assert walk.unknown_type_counts == exp["unknown"]
    assert walk.notes == [] and walk.dropped_fields == {}
    assert not np.any(walk.wifi.last_seen_fallback)


# ------------------------------------------------------------------ one walk
def test_read_walk_parses_every_record_type(tmp_path):
    p = tmp_path / "5dd38ffd27889b0006b76aca.txt"
    exp = _write_walk(p)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # an undamaged walk reads without a warning
        walk = read_ilc_walk(p)
    _check_walk(walk, exp)
    assert walk.walk_id == "5dd38ffd27889b0006b76aca" and walk.path == p
    assert walk.n_waypoints == 3
    assert walk.duration_s == pytest.approx(0.132 + 0.02 * 29)
    assert walk.site_id == "5dbc1d84c1eb61796cf7c010" and walk.floor_name == "F3"
    assert walk.device == "OPPO PBCM10"


def test_read_walk_header_metadata(tmp_path):
    p = tmp_path / "w.txt"
    _write_walk(p)
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
    _write_walk(p)
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
    exp = _write_walk(p, seed=3, rv_w=True)
    walk = read_ilc_walk(p)
    _check_walk(walk, exp)
    assert walk.rotation_vector.values.shape == (30, 4)
    q = walk.rotation_quaternion_xyzw()
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(q[:, 3], exp["rotation_vector"]["w"], atol=1e-6)

    p3 = tmp_path / "w3.txt"
    exp3 = _write_walk(p3, seed=3, rv_w=False)
    walk3 = read_ilc_walk(p3)
    assert walk3.rotation_vector.values.shape == (30, 3)
    q3 = walk3.rotation_quaternion_xyzw()
    v = exp3["rotation_vector"]["values"]
    np.testing.assert_allclose(q3[:, :3], v, atol=1e-12)
    np.testing.assert_allclose(q3[:, 3], np.sqrt(1 - np.sum(v**2, axis=1)), atol=1e-12)


def test_crlf_line_ends(tmp_path):
    p = tmp_path / "w.txt"
    exp = _write_walk(p, seed=5, newline="\r\n")
    _check_walk(read_ilc_walk(p), exp)


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
def _line_of(lines, needle, nth=0):
    """1-based number of the nth line containing needle."""
    hits = [i for i, ln in enumerate(lines) if needle in ln]
    return hits[nth] + 1


def _damage(path, needle, fix, nth=0):
    lines = path.read_text(encoding="utf-8").split("\n")
    n = _line_of(lines, needle, nth)
    lines[n - 1] = fix(lines[n - 1])
    path.write_text("\n".join(lines), encoding="utf-8")
    return n


def _drop_last_field(line):
    return line.rsplit("\t", 1)[0]


def _set_field(k, value):
    def fix(line):
        parts = line.split("\t")
        parts[k] = value
        return "\t".join(parts)
    return fix


@pytest.mark.parametrize("needle, nth, fix, message", [
    ("\tTYPE_ACCELEROMETER\t", 4, _drop_last_field,
     r"TYPE_ACCELEROMETER has 5 tab-separated fields, expected 6 \(unix_ms, type, x, y, z, "
     r"accuracy\)"),
    ("\tTYPE_GYROSCOPE_UNCALIBRATED\t", 7, lambda s: s + "\t1.0",
     "TYPE_GYROSCOPE_UNCALIBRATED has 10 tab-separated fields, expected 9"),
    ("\tTYPE_GYROSCOPE\t", 2, _set_field(3, "abc"),
     r"TYPE_GYROSCOPE field 4 \(y\) is not a number: 'abc'"),
    ("\tTYPE_MAGNETIC_FIELD\t", 9, _set_field(4, ""),
     r"TYPE_MAGNETIC_FIELD field 5 \(z\) is not a number: ''"),
    ("\tTYPE_ROTATION_VECTOR\t", 0, _set_field(2, "nan"),
     r"TYPE_ROTATION_VECTOR field 3 \(x\) is not a number: 'nan'"),
    ("\tTYPE_ACCELEROMETER_UNCALIBRATED\t", 11, _set_field(3, "Infinity"),
     r"TYPE_ACCELEROMETER_UNCALIBRATED field 4 \(y\) is not a number: 'Infinity'"),
    ("\tTYPE_GYROSCOPE\t", 12, _set_field(2, "1e999"),
     r"TYPE_GYROSCOPE field 3 \(x\) is not finite: '1e999'"),
    ("\tTYPE_ACCELEROMETER\t", 12, _set_field(0, "1574142012377.5"),
     r"field 1 \(unix_ms\) must be an integer"),
    ("\tTYPE_WIFI\t", 2, _set_field(4, "-7x"),
     r"TYPE_WIFI field 5 \(rssi\) is not a number: '-7x'"),
    ("\tTYPE_WIFI\t", 5, _set_field(4, ""), r"TYPE_WIFI field 5 \(rssi\) is not a number: ''"),
    ("\tTYPE_WIFI\t", 1, _set_field(3, ""), r"TYPE_WIFI field 4 \(bssid\) is empty"),
    ("\tTYPE_WIFI\t", 0, _drop_last_field, "TYPE_WIFI has 6 tab-separated fields, expected 7"),
    ("\tTYPE_WAYPOINT\t", 1, _drop_last_field, "TYPE_WAYPOINT has 3 tab-separated fields"),
    ("\tTYPE_BEACON\t", 1, _set_field(0, "x"), r"TYPE_BEACON field 1 \(unix_ms\) is not a number"),
    ("\tTYPE_WAYPOINT\t", 2, _set_field(2, "NaN"), r"TYPE_WAYPOINT field 3 \(x\) is not a number"),
    ("\tTYPE_GYROSCOPE\t", 6, lambda s: s.replace("\t", " "), "not a record"),
    ("\tTYPE_GYROSCOPE\t", 8, _set_field(1, "0.25"), "record type '0.25' is not a type name"),
    ("\tTYPE_GYROSCOPE\t", 8, _set_field(1, ""), "empty record type"),
])
def test_damaged_line_names_file_and_line(tmp_path, needle, nth, fix, message):
    """Damage to what the methods need (times, IMU x/y/z, WiFi RSSI and BSSID, waypoints, the
    field count) rejects the walk with a FormatError naming the file and the line."""
    p = tmp_path / "damaged.txt"
    _write_walk(p)
    n = _damage(p, needle, fix, nth)
    with pytest.raises(FormatError, match=message) as info:
        read_ilc_walk(p)
    text = str(info.value)
    assert f"{p}, line {n}:" in text, text
    assert text.startswith("indoorloc: argument 'path': ")


# ------------------------------------------------------------------ nothing is lost
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
    _write_walk(clean, rv_w=rv_w)
    p = tmp_path / "damaged.txt"
    _write_walk(p, rv_w=rv_w)
    n = _damage(p, needle, _set_field(k, bad), nth)
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
    _write_walk(p, rv_w=True)
    _damage(p, "\tTYPE_ROTATION_VECTOR\t", _set_field(5, "Infinity"), 2)
    walk, _ = _read_warned(p)
    q = walk.rotation_quaternion_xyzw()
    assert np.all(np.isfinite(q))
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)


def test_many_damaged_fields_give_one_warning_with_counts(tmp_path):
    p = tmp_path / "w.txt"
    _write_walk(p)
    _damage(p, "\tTYPE_BEACON\t", _set_field(7, "Infinity"), 0)
    _damage(p, "\tTYPE_BEACON\t", _set_field(7, "Infinity"), 1)
    _damage(p, "\tTYPE_WIFI\t", _set_field(5, ""), 3)
    _damage(p, "\tTYPE_MAGNETIC_FIELD\t", _set_field(5, "x"), 0)
    walk, messages = _read_warned(p, 1)
    assert walk.dropped_fields == {"TYPE_BEACON distance": 2, "TYPE_WIFI frequency": 1,
                                   "TYPE_MAGNETIC_FIELD accuracy": 1}
    assert "TYPE_BEACON distance x2" in messages[0]
    assert len(walk.notes) == 3
    assert np.all(np.isnan(walk.beacons.distance_m))
    assert walk.magnetometer.accuracy[0] == -1 and np.all(walk.magnetometer.accuracy[1:] >= 0)


def test_needed_damage_still_rejects_when_optional_damage_is_present(tmp_path):
    p = tmp_path / "w.txt"
    _write_walk(p)
    _damage(p, "\tTYPE_BEACON\t", _set_field(7, "Infinity"), 0)
    n = _damage(p, "\tTYPE_WIFI\t", _set_field(4, "Infinity"), 6)
    with pytest.raises(FormatError, match=rf"line {n}: TYPE_WIFI field 5 \(rssi\) is not a number"):
        read_ilc_walk(p)


def test_beacon_line_with_wrong_field_count_is_dropped(tmp_path):
    """No method reads iBeacons: a beacon line that cannot be split into its fields is dropped,
    not the walk."""
    clean = tmp_path / "clean.txt"
    _write_walk(clean)
    p = tmp_path / "w.txt"
    _write_walk(p)
    n = _damage(p, "\tTYPE_BEACON\t", _drop_last_field, 0)
    n = _damage(p, "\tTYPE_BEACON\t", _drop_last_field, 0)  # 8 fields
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
    lines = HEADER + _walk_records(np.random.default_rng(0))[0]
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
    lines = HEADER + _walk_records(np.random.default_rng(0))[0]
    p = tmp_path / "w.txt"
    p.write_text("\n".join(lines + [FULL_LAST["acc"][:-2], "#\tendTime:1"]), encoding="utf-8")
    with pytest.raises(FormatError, match=rf"line {len(lines) + 1}: TYPE_ACCELEROMETER has 5"):
        read_ilc_walk(p)


def test_decreasing_times_raise_or_are_sorted(tmp_path):
    p = tmp_path / "w.txt"
    exp = _write_walk(p)
    lines = p.read_text(encoding="utf-8").split("\n")
    a = _line_of(lines, "\tTYPE_GYROSCOPE\t", 10)
    b = _line_of(lines, "\tTYPE_GYROSCOPE\t", 11)
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


# ------------------------------------------------------------------ floors and sites
LON0, LAT0 = 120.13013631761804, 30.301143552356766


def _write_floor(floor_dir, walk_seeds, t0s):
    for seed, t0 in zip(walk_seeds, t0s):
        _write_walk(floor_dir / "path_data_files" / f"walk{seed:02d}.txt", seed, t0=t0)
    (floor_dir / "floor_info.json").write_text(
        json.dumps({"map_info": {"height": 219.74676479990106, "width": 236.71181213998395}}))
    outline = {"type": "Feature", "properties": {},
               "geometry": {"type": "MultiPolygon", "coordinates": [
                   [[[LON0 + 0.002, LAT0 + 0.0001], [LON0, LAT0 + 0.001],
                     [LON0 + 0.0012, LAT0], [LON0 + 0.002, LAT0 + 0.0001]]],
                   [[[LON0 + 0.0005, LAT0 + 0.0005], [LON0 + 0.0006, LAT0 + 0.0005],
                     [LON0 + 0.0006, LAT0 + 0.0006], [LON0 + 0.0005, LAT0 + 0.0005]]]]}}
    shop = {"type": "Feature", "properties": {"name": "shop"},
            "geometry": {"type": "Polygon", "coordinates": [
                [[LON0 - 1, LAT0 - 1], [LON0 - 0.5, LAT0 - 1], [LON0 - 0.5, LAT0 - 0.5],
                 [LON0 - 1, LAT0 - 1]]]}}  # outside the outline: must not move the origin
    (floor_dir / "geojson_map.json").write_text(
        json.dumps({"type": "FeatureCollection", "features": [outline, shop]}))


def _site(tmp_path):
    site = tmp_path / "site9"
    _write_floor(site / "F1", [2, 1], [T0, T0 + 10_000_000])
    _write_floor(site / "B1", [7], [T0 + 5])
    (site / "notes").mkdir()  # not a floor: no path_data_files/
    return site


def test_read_site_and_floor(tmp_path):
    site = read_ilc_site(_site(tmp_path))
    assert list(site) == ["B1", "F1"]
    f1 = site["F1"]
    assert isinstance(f1, IlcFloor) and f1.name == "F1" and f1.n_walks == 2
    assert f1.walk_ids == ["walk01", "walk02"]  # sorted file names
    assert f1.width_m == pytest.approx(236.71181213998395)
    assert f1.height_m == pytest.approx(219.74676479990106)
    assert f1.geojson_path.name == "geojson_map.json" and f1.image_path is None
    assert f1.origin_lonlat() == (LON0, LAT0)
    assert ilc_floor_origin_lonlat(f1.geojson_path) == (LON0, LAT0)
    w = f1.walk("walk02")
    assert w is f1.walk(1)  # cached
    assert w.t0_unix_ms == T0 and f1.walk(0).t0_unix_ms == T0 + 10_000_000
    assert [x.walk_id for x in f1.walks()] == ["walk01", "walk02"]
    assert [x.walk_id for x in f1.walks(["walk02"])] == ["walk02"]
    with pytest.raises(KeyError):
        f1.walk("nope")
    with pytest.raises(IndexError):
        f1.walk(2)
    assert f1.walk(np.int64(1)) is w
    uncached = read_ilc_floor(tmp_path / "site9" / "F1", cache=False)
    assert uncached.walk(0) is not uncached.walk(0)
    assert "F1" in repr(f1)


def test_floor_bssid_vocabulary(tmp_path):
    site = _site(tmp_path)
    floor = read_ilc_floor(site / "F1")
    voc = floor.bssid_vocabulary()
    assert isinstance(voc, BssidVocabulary)
    assert voc.bssids == sorted(voc.bssids) and voc.size == 4
    assert voc.total_walks == 2 and voc.total_scans == 6
    k = voc.bssids.index("9c:a6:15:27:3b:29")
    # Per walk: 3 readings in 2 scans (twice in one scan).
    assert voc.n_readings[k] == 6 and voc.n_scans[k] == 4 and voc.n_walks[k] == 2
    assert voc.ssids[k] == "大悦城"
    np.testing.assert_array_equal(voc.n_readings[voc.indices(["04:40:a9:a1:89:01"])], [4])
    np.testing.assert_allclose(voc.scan_fraction[k], 4 / 6)
    np.testing.assert_array_equal(voc.frequent(0.5), np.flatnonzero(voc.n_scans >= 3))
    walk = floor.walk(0)
    mapped = floor.map_wifi(walk)
    assert [voc.bssids[i] for i in mapped] == [walk.wifi.bssids[i] for i in walk.wifi.bssid_index]

    # A vocabulary of a subset (e.g. training walks) maps unseen BSSIDs to -1.
    sub = BssidVocabulary(bssids=["04:40:a9:a1:89:00"], ssids=["JOY CITY"],
                          n_readings=np.array([2]), n_scans=np.array([2]), n_walks=np.array([1]),
                          total_scans=3, total_walks=1)
    m = sub.map_walk(walk)
    names = [walk.wifi.bssids[i] for i in walk.wifi.bssid_index]
    np.testing.assert_array_equal(m, [0 if b == "04:40:a9:a1:89:00" else -1 for b in names])
    assert floor.bssid_vocabulary(["walk01"]).total_walks == 1
    np.testing.assert_array_equal(sub.indices(["x", "04:40:a9:a1:89:00"]), [-1, 0])


def test_site_and_floor_errors(tmp_path):
    with pytest.raises(ValueError, match="argument 'site_dir': folder not found"):
        read_ilc_site(tmp_path / "none")
    (tmp_path / "empty_site" / "F1").mkdir(parents=True)
    with pytest.raises(ValueError, match="no floor folder with path_data_files"):
        read_ilc_site(tmp_path / "empty_site")
    with pytest.raises(ValueError, match="argument 'floor_dir': no folder"):
        read_ilc_floor(tmp_path / "empty_site" / "F9")
    with pytest.raises(ValueError, match=r"no \*.txt walk file in .*F1 \(and no folder"):
        read_ilc_floor(tmp_path / "empty_site" / "F1")
    (tmp_path / "empty_site" / "F1" / "path_data_files").mkdir()
    with pytest.raises(ValueError, match=r"no \*.txt walk file"):
        read_ilc_floor(tmp_path / "empty_site" / "F1")
    floor = tmp_path / "s" / "F2"
    _write_walk(floor / "path_data_files" / "a.txt")
    f = read_ilc_floor(floor)  # floor_info.json and geojson_map.json are optional
    assert f.width_m is None and f.geojson_path is None
    with pytest.raises(ValueError, match="no geojson_map.json"):
        f.origin_lonlat()
    (floor / "floor_info.json").write_text('{"map_info": {"width": 10}}')
    with pytest.raises(ValueError, match="floor_info.json: expected"):
        read_ilc_floor(floor)
    (floor / "geojson_map.json").write_text('{"features": []}')
    with pytest.raises(ValueError, match="argument 'geojson_path'"):
        ilc_floor_origin_lonlat(floor / "geojson_map.json")


def test_walk_keys_are_checked(tmp_path):
    """Issue 28: walk(1.5) used to return walk 1; walk('nope') raised a bare KeyError."""
    floor = read_ilc_floor(_site(tmp_path) / "F1")
    for key in (1.5, 1.0, True, None, [0]):
        with pytest.raises(TypeError, match=r"argument 'key': a walk index \(int\) or walk id \(str\)"):
            floor.walk(key)
    with pytest.raises(KeyError) as info:
        floor.walk("nope")
    text = str(info.value)
    assert text == ("indoorloc: argument 'key': no walk 'nope' on floor F1 (its 2 walks are the *.txt "
                    f"files of {floor.walk_paths[0].parent}; IlcFloor.walk_ids lists them)")
    with pytest.raises(IndexError, match="walk -1 outside 0..1"):
        floor.walk(-1)
    with pytest.raises(TypeError, match="argument 'key'"):
        list(floor.walks([0.5]))


def test_floor_readers_skip_a_bad_walk_and_report_it(tmp_path):
    d = tmp_path / "site" / "F2"
    _write_floor(d, [1, 2, 3], [T0, T0 + 5_000_000, T0 + 9_000_000])
    bad = d / "path_data_files" / "walk02.txt"
    n = _damage(bad, "\tTYPE_GYROSCOPE\t", _set_field(3, "abc"), 4)
    _damage(d / "path_data_files" / "walk03.txt", "\tTYPE_BEACON\t", _set_field(7, "Infinity"), 1)
    floor = read_ilc_floor(d)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ids = [w.walk_id for w in floor.walks()]
    assert ids == ["walk01", "walk03"]
    assert all(issubclass(w.category, RecordingWarning) for w in caught) and len(caught) == 2
    skipped = [str(w.message) for w in caught if "skipped" in str(w.message)]
    assert len(skipped) == 1 and str(bad) in skipped[0]
    assert f"line {n}: TYPE_GYROSCOPE field 4 (y) is not a number: 'abc'" in skipped[0]
    assert list(floor.skipped_walks) == ["walk02"]
    assert f"line {n}:" in floor.skipped_walks["walk02"]
    report = floor.load_report()
    assert report == {
        "floor": "F2", "n_walks": 3, "n_read": 3, "n_loaded": 2, "n_skipped": 1,
        "skipped_walks": floor.skipped_walks, "n_walks_with_dropped_fields": 1,
        "dropped_fields": {"TYPE_BEACON distance": 1},
        "walks_with_dropped_fields": {"walk03": {"TYPE_BEACON distance": 1}}, "n_warnings": 2}
    # Once reported, a skipped walk is not read (nor reported) again; walk() still raises.
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert [w.walk_id for w in floor.walks()] == ids
        assert floor.bssid_vocabulary().total_walks == 2
    with pytest.raises(FormatError, match=rf"walk02.txt, line {n}:"):
        floor.walk("walk02")
    d_facts = describe_ilc_floor(floor)
    assert d_facts["n_walks"] == 2 and d_facts["load_report"]["n_skipped"] == 1
    # A fresh floor object: the vocabulary and the description skip the walk themselves.
    for fresh in (lambda: read_ilc_floor(d).bssid_vocabulary().total_walks,
                  lambda: describe_ilc_floor(read_ilc_floor(d, cache=False))["n_walks"]):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            assert fresh() == 2
        assert all(issubclass(w.category, RecordingWarning) for w in caught)
        assert sum("walk02.txt skipped" in str(w.message) for w in caught) == 1  # once per floor


def test_origin_refuses_non_finite_coordinates(tmp_path):
    """Issue 28: a NaN coordinate gave a NaN origin."""
    d = tmp_path / "F1"
    _write_floor(d, [1], [T0])
    doc = json.loads((d / "geojson_map.json").read_text())
    for bad in (float("nan"), float("inf")):
        doc["features"][0]["geometry"]["coordinates"][0][0][1][1] = bad
        (d / "geojson_map.json").write_text(json.dumps(doc))  # writes NaN / Infinity
        with pytest.raises(FormatError, match=r"argument 'geojson_path': .*geojson_map.json: the first "
                                              r"feature has 1 coordinate\(s\) that are not finite"):
            ilc_floor_origin_lonlat(d / "geojson_map.json")
        with pytest.raises(ValueError, match="not finite"):
            read_ilc_floor(d).origin_lonlat()


def test_floor_folders_in_building_order_and_the_kaggle_layout(tmp_path):
    site = tmp_path / "site"
    for name in ("F10", "B1", "F2", "annex", "B2", "G", "F1"):
        _write_floor(site / name, [1], [T0])
    (site / "notes").mkdir()  # no walk file: not a floor
    (site / "notes" / "readme.md").write_text("x")
    # Kaggle 2021 layout: the walks in the floor folder itself; no plan.
    _write_walk(site / "3F" / "5d8f0954f0ba1b0006e6ed10.txt")
    assert ilc_floor_names(site) == ["B2", "B1", "G", "F1", "F2", "3F", "F10", "annex"]
    assert ilc_floor_names(site, with_plan=True) == ["B2", "B1", "G", "F1", "F2", "F10", "annex"]
    assert list(read_ilc_site(site)) == ilc_floor_names(site)
    kaggle = read_ilc_floor(site / "3F")
    assert kaggle.walk_ids == ["5d8f0954f0ba1b0006e6ed10"] and kaggle.geojson_path is None
    assert kaggle.walk(0).n_waypoints == 3
    assert [ilc_floor_level(n) for n in ("B2", "2B", "b1", "G", "GF", "F3", "3F", "L3", "M", "F")] == [
        -2, -2, -1, 0, 0, 3, 3, 3, None, None]
    with pytest.raises(ValueError, match="argument 'site_dir': no floor folder with path_data_files/ or "
                                         r"\*.txt walk files and geojson_map.json"):
        ilc_floor_names(site / "notes", with_plan=True)
    with pytest.raises(ValueError, match="argument 'site_dir': folder not found"):
        ilc_floor_names(site / "none")


# ------------------------------------------------------------------ the shared site
# Per floor of the shared site, counted with grep on the files (e.g. grep -c $'\tTYPE_WIFI\t'):
# walks, waypoints, samples per sensor type, WiFi readings, iBeacon readings, and the loader's
# BSSID vocabulary size.
SHARED_FLOORS = {
    "B1": (65, 444, 102_253, 149_017, 1_499, 1_031),
    "F1": (82, 639, 159_295, 468_661, 2_004, 2_405),
    "F3": (37, 224, 49_255, 113_739, 185, 1_800),
    "F4": (26, 193, 46_514, 105_214, 214, 1_958),
    "F7": (32, 256, 61_948, 156_346, 1_448, 1_622),
    "F8": (24, 193, 44_483, 74_633, 467, 840),
}


def _shared_site(shared_data):
    site_dir = shared_data / "fusion" / "ilc2020_site2"
    if not site_dir.is_dir():
        pytest.skip(f"Indoor Location Competition data not found at {site_dir}")
    return site_dir


def test_shared_site_loads_with_readme_counts(shared_data):
    """The six floors of the data's README; every walk loads (F1's Infinity distances are
    dropped fields, not rejected walks)."""
    site_dir = _shared_site(shared_data)
    start = time.perf_counter()
    site = read_ilc_site(site_dir, cache=False)
    assert list(site) == list(SHARED_FLOORS)  # building order
    unknown_types = {"TYPE_BLUE", "TYPE_BLU4", "TYPE_DIST1", "TYPE_DIST2",
                     "TYPE_SENSOR_MAGNETIC_FIELD_ACCURACY_CHANGED"}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RecordingWarning)  # F1's (counted below)
        for name, floor in site.items():
            n_walks, n_wp, n_samples, n_wifi, n_beacons, n_bssids = SHARED_FLOORS[name]
            counts = np.zeros(4, dtype=np.int64)
            samples = {attr: 0 for attr, _, _ in ILC_SENSOR_TYPES.values()}
            for w in floor.walks():
                counts += [1, w.n_waypoints, w.wifi.n_readings, w.beacons.n_readings]
                for attr in samples:
                    samples[attr] += getattr(w, attr).n_samples
                assert w.floor_name == name and w.device == "OPPO PBCM10"
                assert bool(w.notes) == bool(w.dropped_fields) == (name == "F1" and w.walk_id in
                                                                   floor.load_report()["walks_with_dropped_fields"])
                # B1 has 4 walks under 5 s and 5 with one WiFi scan, F1 one with one scan.
                assert w.duration_s > 2.0 and w.wifi.n_scans >= 1 and w.n_waypoints >= 2
                assert w.waypoint_t_s[0] == 0.0  # every walk starts at a waypoint
                assert len({s.n_samples for s in w.sensors.values()}) == 1
                assert np.all(w.wifi.age_s > 0) and not np.any(w.wifi.last_seen_fallback)
                assert set(w.unknown_type_counts) <= unknown_types
                xy = w.waypoint_xy_m
                assert np.all((xy >= 0) & (xy <= [floor.width_m, floor.height_m]))
            assert counts.tolist() == [n_walks, n_wp, n_wifi, n_beacons], name
            assert set(samples.values()) == {n_samples}, name
            assert floor.load_report()["n_skipped"] == 0
            assert floor.bssid_vocabulary().size == n_bssids, name
    elapsed = time.perf_counter() - start
    # Printed, not asserted (house rule: no timing thresholds in tests; under load it took 78 s).
    print(f"\nshared site: 266 walks loaded in {elapsed:.1f} s")


def test_shared_f1_keeps_the_walks_with_infinity_distances(shared_data):
    """Issue 25 item 8: F1's 27 walks whose iBeacon distance is the text Infinity (341 lines)
    used to be rejected whole; now all 82 load and the 27 carry one warning each."""
    floor = read_ilc_floor(_shared_site(shared_data) / "F1", cache=False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        nan_per_walk = {w.walk_id: int(np.sum(np.isnan(w.beacons.distance_m))) for w in floor.walks()}
    assert len(nan_per_walk) == 82 == floor.n_walks
    assert all(issubclass(w.category, RecordingWarning) for w in caught) and len(caught) == 27
    assert all("TYPE_BEACON distance" in str(w.message) for w in caught)
    report = floor.load_report()
    assert report["n_loaded"] == 82 and report["n_skipped"] == 0 and report["n_warnings"] == 27
    assert report["dropped_fields"] == {"TYPE_BEACON distance": 341}
    assert report["walks_with_dropped_fields"] == {
        k: {"TYPE_BEACON distance": v} for k, v in nan_per_walk.items() if v}


def test_describe_floor_measures_the_fixture(tmp_path):
    floor = read_ilc_floor(_site(tmp_path) / "F1")
    d = describe_ilc_floor(floor)
    assert d["floor"] == "F1" and d["n_walks"] == 2 and d["total_scans"] == 6
    assert d["duration_s"]["p50"] == pytest.approx(0.712)
    assert d["scans_per_walk"]["p50"] == 3 and d["readings_per_scan"]["p100"] == 4
    assert d["readings_per_scan"]["p0"] == 2
    np.testing.assert_allclose([d["scan_interval_s"][k] for k in ("p0", "p100")], [0.17, 0.18])
    assert d["scans_with_repeated_bssid"] == pytest.approx(1 / 3)
    assert d["n_readings"] == 18 and d["n_bssids"] == 4 and d["n_bssids_in_one_walk"] == 0
    # Per walk, ages [s]: 0.476 0.475 8.124 | 0.012 19.377 0.003 2.1 | 0.1 2.28
    assert d["age_s"]["p0"] == pytest.approx(0.003) and d["age_s"]["p100"] == pytest.approx(19.377)
    assert d["age_fraction_over_s"]["2"] == pytest.approx(4 / 9)
    assert d["age_fraction_over_s"]["10"] == pytest.approx(1 / 9)
    assert d["repeated_measurement_fraction"] == pytest.approx(1 / 9)
    assert sum(d["age_histogram"]) == pytest.approx(1.0)
    # Fresh (<= 2 s) readings: scan 0: 2, scan 1: 2, scan 2: 1; BSSIDs heard fresh in >= 10 %
    # of the 6 scans (at least once): 89:00, 89:01, 9c:a6 (00:10 is 2.1 s old).
    np.testing.assert_allclose([d["fresh_readings_per_scan"][k] for k in ("p0", "p100")], [1, 2])
    assert d["n_bssids_frequent"] == 4 and d["n_bssids_frequent_fresh"] == 3
    assert d["total_waypoints"] == 6 and d["first_waypoint_s"]["p100"] == 0.0
    assert d["after_last_waypoint_s"]["p50"] == pytest.approx(0.062)
    assert d["waypoint_interval_s"]["p0"] == pytest.approx(0.3)
    assert d["rate_hz"]["TYPE_ACCELEROMETER"]["p50"] == pytest.approx(50.0)
    assert d["max_gap_s"]["TYPE_GYROSCOPE"] == pytest.approx(0.02)
    assert d["n_beacon_readings"] == 4 and d["unknown_type_counts"]["TYPE_BLUE"] == 10


def test_describe_ilc_floor_refuses_a_folder_path_by_name(tmp_path):
    """describe_ilc_floor(path) raised AttributeError ('PosixPath' object has no attribute 'walks')."""
    with pytest.raises(TypeError, match="argument 'floor': expected an IlcFloor"):
        describe_ilc_floor(tmp_path)
