"""Synthetic ILC 2020 sites (indoorloc.simulate.ilc_site): the files load through indoorloc.io, the
plan is valid, the hand-held PDR, the crowdsourced map, the WiFi fixes and ``indoorloc fusion
evaluate`` run on them end to end and recover what the generator put in."""

import json
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from indoorloc.pdr import handheld as ph
from indoorloc.fusion import crowdsourced_map
from indoorloc.fusion import wifi_fixes
from indoorloc.experiments import fusion_real as fr
from indoorloc.io import ilc_floor_origin_lonlat, load_floor_plan, read_ilc_site
from indoorloc.simulate.ilc_site import IlcSiteConfig, floor_number, make_ilc_site, write_ilc_site


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The default 1-floor, 8-walk site, in memory (truth) and on disk."""
    truth = make_ilc_site(seed=0)
    root = truth.write(tmp_path_factory.mktemp("ilc") / "site")
    return truth, root, read_ilc_site(root)["F1"]


def _walks(floor, truth):
    """(IlcWalk, IlcWalkTruth) pairs; the floor lists its files by name, the truth by generation."""
    return [(floor.walk(t.walk_id), t) for t in truth.walks["F1"]]


# ------------------------------------------------------------------ files, plan, format
def test_site_loads_with_a_valid_plan_and_walkable_waypoints(site):
    truth, root, floor = site
    assert sorted(p.name for p in root.iterdir()) == ["F1"]
    assert floor.n_walks == 8
    assert (floor.width_m, floor.height_m) == (60.0, 40.0)
    assert floor.origin_lonlat() == pytest.approx(IlcSiteConfig().origin_lon_lat, abs=1e-12)
    assert ilc_floor_origin_lonlat(floor.geojson_path) == floor.origin_lonlat()
    doc = json.loads(floor.geojson_path.read_text())
    kinds = [f["geometry"]["type"] for f in doc["features"]]
    assert kinds[0] == "MultiPolygon" and set(kinds[1:]) == {"Polygon"} and len(kinds) > 10
    plan = load_floor_plan(floor.geojson_path, floors=[1], origin_lon_lat="outline_sw")
    assert plan.bounds() == pytest.approx((0.0, 0.0, 60.0, 40.0), abs=1e-6)
    # Corridors only: the shops take most of the floor.
    assert 0.2 * 60 * 40 < plan.walkable_area() < 0.6 * 60 * 40
    shop_centres = np.array([t.mean(axis=0) for t in truth.layout.shops])
    assert not plan.is_walkable(shop_centres).any()
    for w, t in _walks(floor, truth):
        assert plan.is_walkable(w.waypoint_xy_m).all(), w.walk_id
        assert plan.is_walkable(t.position_m[::10]).all(), w.walk_id   # the whole path, not only waypoints
        np.testing.assert_allclose(w.waypoint_xy_m, t.waypoint_xy_m, atol=1e-5)
        d = np.hypot(*np.diff(w.waypoint_xy_m, axis=0).T)
        assert w.waypoint_t_s[0] == 0.0 and w.n_waypoints >= 4
        assert np.all(np.diff(w.waypoint_t_s) >= 1.0) and np.all(np.diff(w.waypoint_t_s) <= 6.5)
        assert np.all(d < 10.0)


def test_walk_files_look_like_the_competition_data(site):
    truth, root, floor = site
    w = floor.walk(0)
    assert w.site_id == truth.walks["F1"][0].lines[1].split("SiteID:")[1].split("\t")[0]
    assert w.floor_name == "F1" and "startTime" in w.metadata and "endTime" in w.metadata
    assert int(w.metadata["startTime"]) < w.t0_unix_ms
    for walk, t in _walks(floor, truth):
        assert 20.0 <= walk.duration_s <= 40.5
        # 50 Hz streams sharing their time stamps, as in the real files.
        acc = walk.accelerometer
        assert acc.rate_hz == pytest.approx(50.0, rel=1e-3)
        dt_ms = np.round(np.diff(acc.t_s) * 1000.0)
        assert dt_ms.min() >= 19 and dt_ms.max() <= 21
        for s in (walk.gyroscope, walk.magnetometer, walk.rotation_vector):
            np.testing.assert_array_equal(s.t_s, acc.t_s)
        assert walk.rotation_vector.values.shape[1] == 3        # x, y, z only, like the real files
        g = np.linalg.norm(acc.values, axis=1)
        assert 9.3 < np.median(g) < 10.3
        assert walk.unknown_type_counts == {"TYPE_SENSOR_MAGNETIC_FIELD_ACCURACY_CHANGED": 1}
        # WiFi: scans every ~2 s, strongest first, some stale readings repeating an earlier one.
        wf = walk.wifi
        assert np.median(np.diff(wf.scan_times_s)) == pytest.approx(2.0, abs=0.15)
        assert np.all(wf.age_s > 0) and wf.age_s.max() <= 10.0
        stale = wf.age_s > 2.0
        assert 0.05 < stale.mean() < 0.6
        repeats = ~wf.new_measurement_mask()
        assert repeats.any() and np.all(stale[repeats] | (wf.age_s[repeats] > 1.0))
        for s in range(wf.n_scans):
            r = wf.rssi_dbm[wf.scan_slice(s)]
            assert np.all(np.diff(r) <= 0)
        assert np.all((wf.rssi_dbm >= -93) & (wf.rssi_dbm <= -20))
        assert set(np.unique(wf.frequency_mhz)) <= {2412, 2437, 2462, 5180, 5200, 5300, 5745}
    assert 30 <= floor.bssid_vocabulary().size <= 60


def test_deterministic_and_small(tmp_path):
    # No timing threshold here (house rule: timings live in benchmarks/, a loaded machine made
    # this flaky); the size bound keeps the fixture cheap.
    a = write_ilc_site(tmp_path / "a", seed=5)
    b = write_ilc_site(tmp_path / "b", seed=5)
    c = write_ilc_site(tmp_path / "c", seed=6, walks_per_floor=2)
    files_a = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    assert files_a == sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
    assert len(files_a) == 2 + 8
    for rel in files_a:
        assert (a / rel).read_bytes() == (b / rel).read_bytes()
    assert sorted(p.name for p in (c / "F1" / "path_data_files").iterdir()) != \
        sorted(p.name for p in (a / "F1" / "path_data_files").iterdir())
    assert sum((a / rel).stat().st_size for rel in files_a) < 8e6


def test_floors_names_and_arguments(tmp_path):
    assert [floor_number(n) for n in ("F1", "F12", "B2", "G")] == [1, 12, -2, 0]
    s = make_ilc_site(floors=("F1", "F2"), walks_per_floor=2, seed=1)
    assert s.floor_numbers == [1, 2] and s.radio.ap_floors.tolist().count(2) == 48
    root = s.write(tmp_path / "two")
    site = read_ilc_site(root)
    assert list(site) == ["F1", "F2"]
    # The floors share the layout and hear each other's access points (weaker).
    f2 = site["F2"].walk(0)
    own = {b for b, fl in zip(s.bssids, s.radio.ap_floors) if fl == 2}
    heard = [b in own for b in (f2.wifi.bssids[i] for i in f2.wifi.bssid_index)]
    assert 0.5 < np.mean(heard) < 1.0
    with pytest.raises(ValueError, match="floors"):
        make_ilc_site(floors=("F1", "F1"))
    with pytest.raises(ValueError, match="floors"):
        make_ilc_site(floors=("F1", "L1"))           # both floor 1
    with pytest.raises(ValueError, match="walks_per_floor"):
        make_ilc_site(walks_per_floor=0)
    with pytest.raises(ValueError, match="config.width_m"):
        make_ilc_site(config=IlcSiteConfig(width_m=-1.0))
    with pytest.raises(ValueError, match="floor too small"):
        make_ilc_site(config=IlcSiteConfig(width_m=20.0))


# ------------------------------------------------------------------ hand-held PDR
def test_handheld_steps_and_calibration_recover_the_truth(site):
    truth, _, floor = site
    pairs = _walks(floor, truth)
    for w, t in pairs:
        st = ph.handheld_steps(w)
        assert abs(st.n_steps - t.n_steps) <= max(1, 0.05 * t.n_steps), w.walk_id
        # The detected steps are the true ones (peak of the bounce), within a sample or two.
        near = np.min(np.abs(st.t_s[:, None] - t.step_t_s[None, :]), axis=1)
        assert np.median(near) < 0.05
        # The gyroscope turns with the rotation vector (up to its constant bias and the rotation
        # vector's slow heading error, sd 2 deg); the magnetometer is the site's field seen
        # through the rotation vector's orientation.
        a = ph.as_arrays(w)
        diff = ph.gyro_heading(a.t_s, a.gyro_radps, a.quat_xyzw) - np.unwrap(ph.rotation_vector_heading(a.quat_xyzw))
        resid = diff - np.polyval(np.polyfit(a.t_s, diff, 1), a.t_s)
        assert math.degrees(np.sqrt(np.mean(resid ** 2))) < 4.0
        field_enu = Rotation.from_quat(a.quat_xyzw).apply(w.magnetometer.values)
        np.testing.assert_allclose(field_enu.mean(axis=0), IlcSiteConfig().magnetic_field_enu_ut, atol=0.3)
        assert np.all(field_enu.std(axis=0) < 1.0)
    cal = ph.calibrate_handheld([w for w, _ in pairs])
    assert cal.k == pytest.approx(truth.weinberg_k, rel=0.05)
    mean_offset = np.angle(np.mean(np.exp(1j * np.array([t.yaw_offset_rad for _, t in pairs]))))
    assert abs(math.degrees(cal.yaw_offset_rad - mean_offset)) < 1.0
    assert abs(math.degrees(cal.yaw_offset_rad - truth.yaw_offset_rad)) < 2.0
    assert math.degrees(cal.yaw_offset_spread_rad) < 5.0
    # Calibrated PDR from the first waypoint stays within a couple of metres on these clean walks.
    for w, _ in pairs:
        st = ph.rescale(ph.handheld_steps(w), cal.options)
        est = ph.pdr_track(st, w.waypoint_xy_m[0], w.waypoint_t_s, yaw_offset_rad=cal.yaw_offset_rad)
        assert np.max(np.hypot(*(est - w.waypoint_xy_m).T)) < 3.0, w.walk_id


# ------------------------------------------------------------------ WiFi pipeline
def test_crowd_map_and_wifi_fixes_run_and_are_accurate(site):
    truth, _, floor = site
    walks = [w for w, _ in _walks(floor, truth)]
    train, test = walks[:6], walks[6:]
    crowd = crowdsourced_map.build_crowd_map(train, crowdsourced_map.CrowdMapSettings(), 1)
    m = crowd.signal_map
    assert m.positions_m.shape[0] >= 15 and len(crowd.bssids) >= 20
    assert np.all(np.asarray(m.floors) == 1)
    db = wifi_fixes.build_database(train, floors=[1] * len(train))
    assert db.n_scans >= 50 and np.all(db.floors == 1)
    errors = []
    for w in test:
        fixes = wifi_fixes.fixes_for_walk(w, db)
        assert len(fixes) >= 0.8 * w.wifi.n_scans
        assert np.all(fixes.floors[fixes.weights > 0] == 1)
        t, rss = wifi_fixes.walk_queries(w, db)   # the query fingerprints the fixes are made of
        np.testing.assert_allclose(t, fixes.times_s)
        est = wifi_fixes.locate_scans(rss, db)
        at = np.column_stack([np.interp(t, w.waypoint_t_s, w.waypoint_xy_m[:, i]) for i in range(2)])
        inside = (t >= w.waypoint_t_s[0]) & (t <= w.waypoint_t_s[-1])
        errors.append(np.hypot(*(est - at).T)[inside])
    e = np.concatenate(errors)
    assert np.all(np.isfinite(e)) and e.size >= 20
    assert np.mean(e) < 4.0


# ------------------------------------------------------------------ indoorloc fusion evaluate
def test_fusion_evaluate_end_to_end(site):
    truth, root, floor = site
    settings = fr.RealSettings(num_particles=500, folds=2, smoother_trajectories=10)
    result = fr.evaluate(data_root=root, floors=["F1"], settings=settings)
    assert set(result) >= {"methods", "waypoints", "settings"}
    expected = set(fr.METHODS)
    assert set(result["methods"]) == expected
    n_wp = sum(floor.walk(i).n_waypoints for i in range(floor.n_walks))
    for name, stats in result["methods"].items():
        assert {"mean_m", "median_m", "p90_m", "n_waypoints"} <= set(stats)  # issue 15's keys (more beside)
        assert stats["n_waypoints"] == n_wp, name
        assert all(math.isfinite(stats[k]) for k in ("mean_m", "median_m", "p90_m")), name
    assert len(result["waypoints"]) == n_wp * len(expected)
    assert result["settings"]["num_particles"] == 500 and result["settings"]["folds"] == 2
    m = result["methods"]
    assert m["pdr_only"]["mean_m"] < 1.5
    assert m["fusion_known_start"]["mean_m"] < 3.0
    assert m["fusion_smoother"]["mean_m"] < 4.0
    assert m["wifi_knn"]["mean_m"] < 5.0
