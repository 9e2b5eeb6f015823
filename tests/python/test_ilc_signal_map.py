"""Crowdsourced WiFi signal map (indoorloc.fusion.crowdsourced_map) and its experiment.

The fixture walk is written by the test itself in the Indoor Location Competition 2.0 format;
the test on the shared site (../shared/data/fusion/ilc2020_site2) skips when it is absent.
"""

import numpy as np
import pytest

from indoorloc.pdr import handheld as ph
from indoorloc import wifi
from indoorloc.fusion import crowdsourced_map
from indoorloc.io import read_ilc_walk

T0 = 1574142012005
WAYPOINTS = [(0, 0.0, 0.0), (5000, 6.0, 0.0), (10000, 6.0, 6.0)]  # (ms after T0, x, y)


def _write(path, wifi_rows, waypoints=WAYPOINTS, duration_ms=10400):
    """An ILC walk: 50 Hz sensors from T0 + 20 ms, the waypoints, WiFi rows
    (scan ms, bssid, rssi, last-seen ms), all times after T0."""
    recs = []
    for t in range(20, duration_ms, 20):
        ts = T0 + t
        recs.append((ts, 0, f"{ts}\tTYPE_ACCELEROMETER\t0.0\t0.0\t9.80665\t3"))
        recs.append((ts, 1, f"{ts}\tTYPE_GYROSCOPE\t0.0\t0.0\t0.0\t3"))
        recs.append((ts, 2, f"{ts}\tTYPE_ROTATION_VECTOR\t0.0\t0.0\t0.0\t3"))
    for t, x, y in waypoints:
        recs.append((T0 + t, 3, f"{T0 + t}\tTYPE_WAYPOINT\t{x!r}\t{y!r}"))
    for t, b, r, ls in wifi_rows:
        recs.append((T0 + t, 4, f"{T0 + t}\tTYPE_WIFI\tnet\t{b}\t{r}\t2437\t{T0 + ls}"))
    recs.sort(key=lambda r: (r[0], r[1]))
    path.write_text("#\tstartTime:%d\n" % (T0 - 10) + "\n".join(r[2] for r in recs) + "\n")
    return read_ilc_walk(path)


def _steps(rotation_rad=0.5, length_m=0.7):
    """Hand-made PDR steps in a frame rotated by rotation_rad, stride length_m: five steps east
    in 0.5-2.5 s (then the walker stands), a zero step at 5 s, ten steps north in 5.5-10 s."""
    t = np.r_[0.5 * np.arange(1, 6), 5.0, 5.0 + 0.5 * np.arange(1, 11)]
    heading = np.r_[np.zeros(5), 0.0, np.full(10, np.pi / 2)] + rotation_rad
    length = np.r_[np.full(5, length_m), 0.0, np.full(10, length_m)]
    m = t.size
    z = np.zeros(m)
    return ph.HandheldSteps(t_s=t, index=np.arange(m), length_m=length, heading_rad=heading,
                            length_sd_m=z, heading_sd_rad=z, feature=length, heading_rotation_vector_rad=heading,
                            heading_gyro_rad=heading, heading_complementary_rad=heading, start_t_s=0.0)


def test_walk_positions_pdr_similarity_and_linear(tmp_path):
    walk = _write(tmp_path / "w.txt", [])
    q = np.array([2.5, 4.0, 7.5, 10.0, 11.0, 14.0, -1.0])
    lin = crowdsourced_map.walk_positions(walk, q, crowdsourced_map.CrowdMapSettings(positioning="linear"))
    np.testing.assert_allclose(lin.xy_m[:5], [[3, 0], [4.8, 0], [6, 3], [6, 6], [6, 7.2]], atol=1e-9)
    # 14 s is > 3 s after the end; -1 s is before the first sensor sample (motion unknown)
    assert lin.valid.tolist() == [True] * 5 + [False, False]
    pdr = crowdsourced_map.walk_positions(walk, q, crowdsourced_map.CrowdMapSettings(positioning="pdr"), steps=_steps())
    # The walker covered the 6 m east by 2.5 s and stood: PDR, rotated and scaled onto the
    # waypoints, puts t = 2.5 s and 4 s at the second waypoint; north at constant cadence.
    np.testing.assert_allclose(pdr.xy_m[:4], [[6, 0], [6, 0], [6, 3], [6, 6]], atol=1e-9)
    assert pdr.n_intervals_pdr == 2 and pdr.n_intervals_linear == 0
    # No step after the last waypoint: the extrapolation stays there; before the first sensor
    # sample (t < 0.02 s) nothing is known: dropped.
    np.testing.assert_allclose(pdr.xy_m[4], [6, 6], atol=1e-9)
    assert pdr.valid.tolist() == [True] * 5 + [False, False]


def test_interval_with_too_few_steps_falls_back_to_linear(tmp_path):
    walk = _write(tmp_path / "w.txt", [])
    st = _steps()
    st.length_m[:5] = 0.0  # no PDR motion in the first interval
    pos = crowdsourced_map.walk_positions(walk, np.array([2.5, 7.5]), crowdsourced_map.CrowdMapSettings(), steps=st)
    np.testing.assert_allclose(pos.xy_m, [[3, 0], [6, 3]], atol=1e-9)
    assert pos.source.tolist() == [2, 1]
    assert pos.n_intervals_pdr == 1 and pos.n_intervals_linear == 1


def test_readings_land_where_they_were_measured(tmp_path):
    rows = [(4000, "aa:00", -60, 2500),       # measured at 2.5 s, reported at 4 s
            (4000, "bb:00", -70, -2000),      # measured before the walk: dropped
            (9000, "aa:00", -60, 2500),       # the same measurement again: used once
            (9000, "bb:00", -75, 7500)]       # measured at 7.5 s
    walk = _write(tmp_path / "w.txt", rows)
    lin = crowdsourced_map.reading_positions(walk, crowdsourced_map.CrowdMapSettings(positioning="linear"))
    assert lin.n_measurements == 3 and lin.n_dropped == 1
    got = {(lin.bssids[b], float(t)): xy.tolist() for b, t, xy in zip(lin.bssid_index, lin.t_s, lin.xy_m)}
    assert got == {("aa:00", 2.5): [3.0, 0.0], ("bb:00", 7.5): [6.0, 3.0]}
    pdr = crowdsourced_map.reading_positions(walk, crowdsourced_map.CrowdMapSettings(), steps=_steps())
    got = {(pdr.bssids[b], float(t)): xy for b, t, xy in zip(pdr.bssid_index, pdr.t_s, pdr.xy_m)}
    np.testing.assert_allclose(got[("aa:00", 2.5)], [6.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(got[("bb:00", 7.5)], [6.0, 3.0], atol=1e-9)
    # Scan epochs: median last-seen time of each scan's fresh readings (<= 2.5 s old).
    np.testing.assert_allclose(crowdsourced_map.scan_epochs(walk.wifi, 2.5), [2.5, 7.5])


def _placed(bssids, readings, epochs):
    b = np.array([bssids.index(r[0]) for r in readings], dtype=np.int64)
    return crowdsourced_map.PlacedReadings(bssids=bssids, bssid_index=b, rssi_dbm=np.array([r[1] for r in readings], float),
                             t_s=np.zeros(len(readings)), xy_m=np.array([r[2] for r in readings], float),
                             epoch_xy_m=np.array(epochs, float).reshape(-1, 2), n_measurements=len(readings),
                             n_dropped=0, n_epochs_dropped=0, n_intervals_pdr=0, n_intervals_linear=0)


def test_map_statistics_hand_computed():
    a = _placed(["a", "b"], [("a", -60, (1, 1)), ("a", -62, (1, 1)), ("b", -80, (1, 1)), ("a", -70, (3, 1))],
                [(1, 1), (1, 1), (3, 1)])
    b = _placed(["a", "c"], [("a", -64, (1.5, 1.5)), ("c", -90, (5, 1))], [(1.5, 1.5), (5, 1)])
    s = crowdsourced_map.CrowdMapSettings(cell_size_m=2.0, min_walks=1, min_cells=1, variance_prior_weight=0.0,
                            not_heard_dbm=-105.0, variance_floor_db2=4.0)
    pos, mean, var, bssids, summ = crowdsourced_map.map_statistics([a, b], s)
    assert bssids == ["a", "b", "c"]
    np.testing.assert_allclose(pos, [[7 / 6, 7 / 6], [3, 1], [5, 1]])
    # Cell 0: 3 passes; a heard 3 times (-60, -62, -64): mean -62, variance 4 (= the floor);
    # b heard once: values (-80, -105, -105), mean -96.67, unbiased variance 208.33; c never: -105.
    np.testing.assert_allclose(mean[0], [-62, -290 / 3, -105])
    np.testing.assert_allclose(var[0], [4, 625 / 3, 4])
    # Cell 1: one pass, one reading: the unbiased variance is undefined -> the floor.
    np.testing.assert_allclose(mean[1], [-70, -105, -105])
    np.testing.assert_allclose(var[1], [4, 4, 4])
    np.testing.assert_allclose(mean[2], [-105, -105, -90])
    np.testing.assert_allclose(summ.detection_rate[0], [1, 1 / 3, 0])
    np.testing.assert_allclose(summ.passes, [3, 1, 1])
    # With 2 walks required only "a" stays; "a" is in 2 cells.
    _, mean2, _, bssids2, _ = crowdsourced_map.map_statistics([a, b], crowdsourced_map.CrowdMapSettings(cell_size_m=2.0, min_walks=2, min_cells=2))
    assert bssids2 == ["a"] and mean2.shape == (3, 1)
    # Shrinkage towards the pooled variance of heard readings (cell 0's a: 8 over 2 dof = 4).
    _, _, var3, _, summ3 = crowdsourced_map.map_statistics([a, b], crowdsourced_map.CrowdMapSettings(
        cell_size_m=2.0, min_walks=1, min_cells=1, variance_prior_weight=2.0, variance_floor_db2=1.0))
    assert summ3.pooled_variance_db2 == pytest.approx(4.0)
    assert var3[0, 0] == pytest.approx((8 + 2 * 4) / (2 + 2))
    assert var3[1, 0] == pytest.approx(4.0)  # one reading: the pooled variance


def test_build_signal_map_and_model(tmp_path):
    a = _placed(["a", "b"], [("a", -60, (1, 1)), ("b", -80, (1, 9)), ("a", -70, (9, 1)), ("b", -50, (9, 9))],
                [(1, 1), (1, 9), (9, 1), (9, 9)])
    cm = crowdsourced_map.build_crowd_map([], crowdsourced_map.CrowdMapSettings(cell_size_m=2.0, min_walks=1, min_cells=1), floor=3, placed=[a])
    assert isinstance(cm.signal_map, wifi.SignalMap) and isinstance(cm.model, wifi.RssModel)
    assert cm.signal_map.num_points == 4 and cm.bssids == ["a", "b"]
    assert cm.model.floors == [3]


def test_scan_matrix_dedups_and_ignores_unknown_bssids(tmp_path):
    rows = [(1000, "aa", -60, 500), (1000, "bb", -70, 800), (1000, "zz", -50, 900),
            (3000, "aa", -60, 500),     # repeats scan 0's measurement
            (3000, "aa", -65, 2600),    # the same AP, a fresh measurement (listed twice)
            (3000, "bb", -70, 800),     # repeat
            (3000, "cc", -80, 2900)]
    walk = _write(tmp_path / "w.txt", rows)
    t, rss, age = crowdsourced_map.scan_matrix(walk, ["cc", "aa", "bb"])
    np.testing.assert_allclose(t, [1.0, 3.0])
    np.testing.assert_allclose(rss, [[np.nan, -60, -70], [-80, -65, np.nan]])
    np.testing.assert_allclose(age, [[np.nan, 0.5, 0.2], [0.1, 0.4, np.nan]], atol=1e-9)
    _, rss_all, age_all = crowdsourced_map.scan_matrix(walk, ["cc", "aa", "bb"], dedup=False)
    np.testing.assert_allclose(rss_all[1], [-80, -65, -70])     # freshest aa; bb as listed
    np.testing.assert_allclose(age_all[1], [0.1, 0.4, 2.2], atol=1e-9)
    _, rss_fresh, _ = crowdsourced_map.scan_matrix(walk, ["cc", "aa", "bb"], dedup=False, max_age_s=1.0)
    np.testing.assert_allclose(rss_fresh[1], [-80, -65, np.nan])
    # Ready for the fusion filter.
    from indoorloc import fusion
    obs, counts = fusion.make_wifi_observations(t, rss, age)
    assert sum(o.num_heard for o in obs) == 4


def test_settings_are_validated():
    with pytest.raises(ValueError, match="positioning"):
        crowdsourced_map.CrowdMapSettings(positioning="spline").validate()
    with pytest.raises(ValueError, match="cell_size_m"):
        crowdsourced_map.CrowdMapSettings(cell_size_m=0.0).validate()


def test_shared_site_map_and_scans(shared_data):
    root = shared_data / "fusion" / "ilc2020_site2"
    if not root.is_dir():
        pytest.skip(f"ILC site not found at {root}")
    from indoorloc.io import read_ilc_floor
    floor = read_ilc_floor(root / "F8")
    walks = list(floor.walks(range(8)))
    smap, model, bssids = crowdsourced_map.build_signal_map(walks[:6], floor, crowdsourced_map.CrowdMapSettings())
    assert smap.num_access_points == len(bssids) > 50 and smap.num_points > 20
    assert np.all(smap.variance_db2 >= 4.0) and np.all(smap.mean_dbm >= -105.0)
    t, rss, ages = crowdsourced_map.scan_matrix(walks[7], bssids)
    assert rss.shape == (walks[7].wifi.n_scans, len(bssids)) and np.isfinite(rss).any()
    assert np.all(ages[np.isfinite(rss)] >= 0)
    from indoorloc import fusion
    obs, _ = fusion.make_wifi_observations(t, rss, ages)
    assert len(obs) > 0


def test_settings_outside_the_maps_ranges_are_named_not_variance_db2(tmp_path):
    # not_heard_dbm = 1e300 overflowed the floor-value variance, refused by SignalMap as
    # 'variance_db2'; 1e20 as 'mean_dbm'. APs heard in part of the walk only (cells that did not hear them).
    rows = [(t, b, -50 - 3 * i, t - 100) for t in range(1000, 10000, 1000) for i, b in enumerate(["aa", "bb", "cc"])
            if not (b == "aa" and t > 4000) and not (b == "cc" and t < 6000)]
    walk = _write(tmp_path / "w.txt", rows)
    kw = dict(positioning="linear", min_walks=1, min_cells=1, cell_size_m=2.0)
    cm = wc.build_crowd_map([walk], wc.CrowdMapSettings(**kw))
    assert np.isfinite(cm.signal_map.variance_db2).all()
    for field, value in (("not_heard_dbm", 1e300), ("not_heard_dbm", 1e20), ("not_heard_dbm", 60.0),
                         ("variance_floor_db2", 1e300), ("cell_size_m", 1e-300)):
        with pytest.raises(ValueError, match=f"CrowdMapSettings.{field}"):
            wc.build_crowd_map([walk], wc.CrowdMapSettings(**dict(kw, **{field: value})))
    with pytest.raises(ValueError, match="'not_heard_dbm'"):
        wc.prepare(np.array([[-60.0, np.nan]]), 1e300)


def test_walk_positions_refuses_waypoints_of_the_wrong_shape(tmp_path):
    from types import SimpleNamespace

    walk = _write(tmp_path / "w.txt", [])
    w = SimpleNamespace(accelerometer=walk.accelerometer, waypoint_t_s=walk.waypoint_t_s,
                        waypoint_xy_m=np.asarray(walk.waypoint_xy_m).T)  # (2, 3): was reshaped to (3, 2)
    with pytest.raises(ValueError, match=r"waypoint_xy_m has shape \(2, 3\), expected \(3, 2\)"):
        wc.walk_positions(w, np.array([walk.waypoint_t_s[0] + 1.0]), wc.CrowdMapSettings(positioning="linear"))


def test_walk_positions_of_a_walk_without_steps(tmp_path):
    # The fixture's phone lies still (no step): PDR mode fell over in cumulative_at's reshape.
    walk = _write(tmp_path / "w.txt", [])
    q = np.array([walk.waypoint_t_s[0] + 2.5])
    pos = wc.walk_positions(walk, q, wc.CrowdMapSettings(positioning="pdr"))
    np.testing.assert_allclose(pos.xy_m, [[3.0, 0.0]])  # linear: PDR unusable without steps
