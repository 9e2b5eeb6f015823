"""Indoor Location Competition 2.0 loader: floors and sites (folders of walks, the BSSID
vocabulary, floor names and origins, a bad walk skipped and reported), and the shared site
(../shared/data/fusion/ilc2020_site2; skipped when absent). Fixture files: ilc2020_files.py."""

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
    RecordingWarning,
    describe_ilc_floor,
    ilc_floor_level,
    ilc_floor_names,
    ilc_floor_origin_lonlat,
    read_ilc_floor,
    read_ilc_site,
)

from ilc2020_files import damage, field, LAT0, LON0, set_field, T0, write_floor, write_site, write_walk


def test_read_site_and_floor(tmp_path):
    site = read_ilc_site(write_site(tmp_path))
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
    site = write_site(tmp_path)
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
    write_walk(floor / "path_data_files" / "a.txt")
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
    floor = read_ilc_floor(write_site(tmp_path) / "F1")
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
    write_floor(d, [1, 2, 3], [T0, T0 + 5_000_000, T0 + 9_000_000])
    bad = d / "path_data_files" / "walk02.txt"
    n = damage(bad, "\tTYPE_GYROSCOPE\t", set_field(3, "abc"), 4)
    damage(d / "path_data_files" / "walk03.txt", "\tTYPE_BEACON\t", set_field(7, "Infinity"), 1)
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
    write_floor(d, [1], [T0])
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
        write_floor(site / name, [1], [T0])
    (site / "notes").mkdir()  # no walk file: not a floor
    (site / "notes" / "readme.md").write_text("x")
    # Kaggle 2021 layout: the walks in the floor folder itself; no plan.
    write_walk(site / "3F" / "5d8f0954f0ba1b0006e6ed10.txt")
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


def test_plan_dir_and_survey_floors_of_both_layouts(tmp_path):
    """The plan files in another folder than the walks (Kaggle 2021's metadata/), and
    survey_floors giving each floor's walk and plan folders in either layout."""
    from indoorloc.io.survey_layout import survey_floors

    site = write_site(tmp_path)
    ilc = survey_floors(site)
    assert [(f.name, f.number) for f in ilc] == [("B1", -1), ("F1", 1)]
    assert ilc[1].floor_dir == ilc[1].plan_dir == site / "F1"
    assert ilc[1].open().walk_ids == read_ilc_floor(site / "F1").walk_ids
    # Kaggle 2021: ROOT/train/SITE/F1/*.txt, ROOT/metadata/SITE/F1/{floor_info,geojson_map}.json
    root = tmp_path / "kaggle"
    walks, plans = root / "train" / "site9" / "F1", root / "metadata" / "site9" / "F1"
    walks.mkdir(parents=True)
    plans.mkdir(parents=True)
    for p in (site / "F1" / "path_data_files").glob("*.txt"):
        (walks / p.name).write_bytes(p.read_bytes())
    for name in ("floor_info.json", "geojson_map.json"):
        (plans / name).write_bytes((site / "F1" / name).read_bytes())
    (kaggle,) = survey_floors(root, argument="data_root")
    assert (kaggle.floor_dir, kaggle.plan_dir, kaggle.number) == (walks, plans, 1)
    f = kaggle.open()
    assert f.plan_dir == plans and f.walk_ids == ["walk01", "walk02"]
    assert f.width_m == pytest.approx(236.71181213998395) and f.origin_lonlat() == (LON0, LAT0)
    assert read_ilc_floor(walks).geojson_path is None  # without plan_dir: the walks' folder only
    with pytest.raises(ValueError, match="argument 'data_root': folder not found"):
        survey_floors(tmp_path / "none", argument="data_root")
    # Errors about the plan files name plan_dir.
    with pytest.raises(ValueError, match="argument 'plan_dir': no folder"):
        read_ilc_floor(walks, plan_dir=tmp_path / "none")
    empty = tmp_path / "empty_plans"
    empty.mkdir()
    with pytest.raises(ValueError, match=r"argument 'plan_dir': no geojson_map.json in .*empty_plans"):
        read_ilc_floor(walks, plan_dir=empty).origin_lonlat()
    (empty / "floor_info.json").write_text('{"map_info": {"width": 10}}')
    with pytest.raises(FormatError, match=r"argument 'plan_dir': .*floor_info.json: expected"):
        read_ilc_floor(walks, plan_dir=empty)


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
    floor = read_ilc_floor(write_site(tmp_path) / "F1")
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
