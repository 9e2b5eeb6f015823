"""Fixture files of the Indoor Location Competition 2.0 format, written by the tests themselves:
a walk (every record type the loader reads; ``write_walk``), the records it is made of
(``walk_records``) and what the loader must read from them (``check_walk``), floors and sites of
such walks (``write_floor``, ``write_site``), and one field of one line damaged (``damage``).
Shared by the test_io_ilc2020*.py tests and the io property group (property_cases_io.py)."""

import json

import numpy as np
import pytest

from indoorloc.io import (
    ILC_SENSOR_TYPES,
    IlcWalk,
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


def field(x):
    return repr(float(x))


def walk_records(rng, *, n_epochs=30, rv_w=False, t0=T0):
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
            vals = [field(v) for v in values[i]]
            if attr == "gyroscope" and i == 3:
                vals[1] = "5.0354004E-4"
            if w is not None:
                vals.append(field(w[i]))
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


def write_walk(path, seed=0, *, n_epochs=30, rv_w=False, t0=T0, newline="\n"):
    rng = np.random.default_rng(seed)
    lines, exp = walk_records(rng, n_epochs=n_epochs, rv_w=rv_w, t0=t0)
    end = max(int(r.split("\t")[0]) for r in lines)
    text = HEADER + lines + [f"#\tendTime:{end}"]
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", encoding="utf-8", newline="") as f:
        f.write(newline.join(text) + newline)
    return exp


def check_walk(walk, exp, t0=T0):
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



LON0, LAT0 = 120.13013631761804, 30.301143552356766


def write_floor(floor_dir, walk_seeds, t0s):
    for seed, t0 in zip(walk_seeds, t0s):
        write_walk(floor_dir / "path_data_files" / f"walk{seed:02d}.txt", seed, t0=t0)
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


def write_site(tmp_path):
    site = tmp_path / "site9"
    write_floor(site / "F1", [2, 1], [T0, T0 + 10_000_000])
    write_floor(site / "B1", [7], [T0 + 5])
    (site / "notes").mkdir()  # not a floor: no path_data_files/
    return site


# Damaging a fixture file: one field of one line.
def line_of(lines, needle, nth=0):
    """1-based number of the nth line containing needle."""
    hits = [i for i, ln in enumerate(lines) if needle in ln]
    return hits[nth] + 1


def damage(path, needle, fix, nth=0):
    lines = path.read_text(encoding="utf-8").split("\n")
    n = line_of(lines, needle, nth)
    lines[n - 1] = fix(lines[n - 1])
    path.write_text("\n".join(lines), encoding="utf-8")
    return n


def drop_last_field(line):
    return line.rsplit("\t", 1)[0]


def set_field(k, value):
    def fix(line):
        parts = line.split("\t")
        parts[k] = value
        return "\t".join(parts)
    return fix
