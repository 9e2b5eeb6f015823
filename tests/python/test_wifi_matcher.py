"""WiFi fingerprints pooled along the walks and the shared-AP dissimilarity (indoorloc.wifi_matcher,
indoorloc.wifi_fixes with pooling="window"): small synthetic fixtures, checked by hand or against
a brute-force reference."""

from types import SimpleNamespace

import numpy as np
import pytest

from indoorloc import wifi_fixes as wfx
from indoorloc import wifi_matcher as wm
from indoorloc.io.ilc2020 import IlcWifi

nan = np.nan


def _wifi(scans):
    """IlcWifi from [(scan_time, [(bssid, rssi, last_seen), ...]), ...]."""
    names = sorted({b for _, rows in scans for b, _, _ in rows})
    col = {b: i for i, b in enumerate(names)}
    st, bi, rs, ls, starts = [], [], [], [], []
    for t, rows in scans:
        starts.append(len(st))
        for b, r, seen in rows:
            st.append(t)
            bi.append(col[b])
            rs.append(r)
            ls.append(seen)
    return IlcWifi(np.array(st, float), np.array(bi, np.int64), np.array(rs, float), np.full(len(st), 2412.0),
                   np.array(ls, float), names, [""] * len(names), np.array(starts, np.int64))


def _brute_force(q, x, g, beta, c):
    """d(a, b) of wifi_matcher's docstring, one pair at a time."""
    f = (lambda v: np.exp((v + 100.0) / beta)) if beta > 0 else (lambda v: 1.0)
    out = np.full((q.shape[0], x.shape[0]), np.inf)
    for i, a in enumerate(q):
        for j, b in enumerate(x):
            A, B = np.isfinite(a), np.isfinite(b)
            S = A & B
            if not S.any():
                continue
            w = np.array([g[k] * f(a[k]) for k in np.flatnonzero(S)])
            rms = np.sqrt(np.sum(w * (a[S] - b[S]) ** 2) / w.sum())
            union = sum(g[k] * f(a[k]) for k in np.flatnonzero(A)) + sum(g[k] * f(b[k]) for k in np.flatnonzero(B & ~A))
            out[i, j] = rms + c * (1.0 - w.sum() / union)
    return out


@pytest.mark.parametrize("beta", [0.0, 5.0])
def test_shared_dissimilarity_matches_brute_force(beta):
    rng = np.random.default_rng(3)
    q = rng.uniform(-95, -40, (4, 7))
    x = rng.uniform(-95, -40, (6, 7))
    q[rng.random(q.shape) < 0.4] = nan
    x[rng.random(x.shape) < 0.4] = nan
    x[0] = nan          # a reference that heard nothing: d = inf
    g = rng.uniform(0.5, 2.0, 7)
    index = wm.ReferenceIndex.build(x, g, beta)
    d = wm.shared_dissimilarity(q, index, 30.0)
    np.testing.assert_allclose(d, _brute_force(q, x, g, beta, 30.0), rtol=1e-4, atol=1e-3)
    assert np.isinf(d[:, 0]).all()
    rms, u = wm.shared_dissimilarity(q, index, 30.0, parts=True)
    np.testing.assert_allclose(rms + 30.0 * u, d, rtol=1e-6)


def test_a_query_identical_to_a_reference_matches_it_first():
    rng = np.random.default_rng(0)
    x = rng.uniform(-95, -40, (50, 30))
    x[rng.random(x.shape) < 0.5] = nan
    positions = rng.uniform(0, 100, (50, 2))
    for beta, power in ((0.0, 0.0), (5.0, 1.0)):
        s = wfx.FixSettings(k=3, strength_scale_db=beta, ap_weight_power=power)
        db = wfx.FingerprintDatabase(x, positions, [f"ap{i}" for i in range(30)], s,
                                     ap_ratio=rng.uniform(0.5, 2.0, 30))
        d = wfx.dissimilarity(x[[7, 21]], db)
        assert np.argmin(d[0]) == 7 and np.argmin(d[1]) == 21
        np.testing.assert_allclose(d[[0, 1], [7, 21]], 0.0, atol=1e-3)
        best, dist, w = wm.knn(d, 3, s.temperature_db)
        assert best[:, 0].tolist() == [7, 21] and np.all(w[:, 0] == 1.0) and np.all(np.diff(dist, axis=1) >= 0)
        np.testing.assert_allclose(wfx.locate_scans(x[[7]], db.with_settings(wfx.FixSettings(k=1))), positions[[7]])


def test_a_reading_last_seen_10_s_ago_is_used_at_its_own_time():
    # Scan at t = 20 s reports AP "b" last seen at t = 10 s (10 s old) and AP "a" fresh; the scan
    # at t = 22 s repeats both measurements (the same last-seen times): each counts once.
    wf = _wifi([(20.0, [("a", -50.0, 19.5), ("b", -60.0, 10.0)]),
                (22.0, [("a", -50.0, 19.5), ("b", -60.0, 10.0), ("a", -55.0, 21.6)])])
    meas = wm.walk_measurements(SimpleNamespace(wifi=wf))
    assert meas.n == 3
    b = meas.bssids.index("b")
    i = int(np.flatnonzero(meas.bssid_index == b)[0])
    assert meas.t_s[i] == 10.0 and meas.reported_s[i] == 20.0
    # The 2.5 s staleness filter of "fresh" pooling drops it ...
    _, fresh, names = wfx.fresh_scans(SimpleNamespace(wifi=wf), 2.5)
    assert np.isnan(fresh[:, names.index("b")]).all()
    # ... a window around its own last-seen time holds it, a window around the scan time does not.
    rss, mean_t, n = wm.pool_windows(meas.t_s, meas.bssid_index, meas.rssi_dbm, 2, [10.0, 20.0], 1.0, 1.0)
    assert rss[0, b] == -60.0 and np.isnan(rss[1, b]) and mean_t[0] == 10.0
    # Max-pooling keeps the strongest of "a"'s two measurements in [19, 22].
    a = meas.bssids.index("a")
    rss, _, n = wm.pool_windows(meas.t_s, meas.bssid_index, meas.rssi_dbm, 2, [22.0], 3.0, 0.0)
    assert rss[0, a] == -50.0 and n[0] == 2
    # Causal queries: the measurement at 21.6 s was first reported at 22 s, not by the scan at 21.7 s.
    rss, _, n = wm.pool_windows(meas.t_s, meas.bssid_index, meas.rssi_dbm, 2, [21.7], 5.0, 0.0, meas.reported_s)
    assert n[0] == 1 and rss[0, a] == -50.0


def test_query_window_and_reference_positions_on_a_straight_walk():
    # A walk along x at 1 m/s; AP "near0" heard only around x = 0..5, "near20" around 20..25.
    scans = []
    for t in np.arange(2.0, 30.0, 2.0):
        rows = [("common", -70.0, t - 0.5)]
        if t < 6:
            rows.append(("near0", -45.0, t - 0.5))
        if 20 <= t < 26:
            rows.append(("near20", -45.0, t - 0.5))
        scans.append((t, rows))
    walk = SimpleNamespace(wifi=_wifi(scans), waypoint_t_s=np.array([0.0, 30.0]),
                           waypoint_xy_m=np.array([[0.0, 0.0], [30.0, 0.0]]))

    def along(t):
        t = np.asarray(t, float)
        return np.column_stack([t, np.zeros_like(t)]), np.ones(t.size, bool)

    s = wfx.FixSettings(ref_window_s=2.0, query_window_s=2.0, min_scans=1, min_aps=1, k=1, ap_weight_power=0.0)
    db = wfx.build_database([walk], s, positions_at=[along])
    assert db.n_scans > 20 and sorted(db.bssids) == ["common", "near0", "near20"]
    t, rss = wfx.walk_queries(walk, db)
    assert np.all(np.diff(t) >= 0) and rss.shape == (t.size, 3)
    est = wfx.locate_scans(rss, db)
    heard20 = np.isfinite(rss[:, db.bssids.index("near20")])
    assert np.all(np.abs(est[heard20, 0] - 22.0) < 4.0)


def test_ap_reliability_down_weights_a_noisy_ap():
    rng = np.random.default_rng(1)
    n = 400
    xy = np.column_stack([rng.uniform(0, 20, n), np.zeros(n)])
    walk = rng.integers(0, 8, n)
    stable = -60.0 - xy[:, 0] + rng.normal(0, 1.0, n)
    noisy = -60.0 - xy[:, 0] + rng.normal(0, 8.0, n)
    g = wm.ap_reliability(np.column_stack([stable, noisy, np.full(n, nan)]), xy, walk, power=1.0)
    assert g[0] > 3 * g[1] and g[2] == pytest.approx(1.0)
    np.testing.assert_array_equal(wm.ap_reliability(np.column_stack([stable, noisy]), xy, walk, power=0.0), 1.0)


@pytest.mark.parametrize("field, value", [
    ("query_window_s", 0.0), ("ref_spacing_s", -1.0), ("ref_window_s", float("nan")), ("penalty_db", -5.0),
    ("ap_weight_power", float("inf")), ("strength_scale_db", 0.5), ("pooling", "scan"), ("query_align", "start"),
    ("metric", "cosine"), ("k", 0), ("pair_radius_m", 0.0),
])
def test_settings_validation_names_the_field(field, value):
    with pytest.raises(ValueError, match=f"FixSettings.{field}"):
        wfx.FixSettings(**{field: value}).validate()


def test_shared_dissimilarity_refuses_wrong_columns():
    index = wm.ReferenceIndex.build(np.full((3, 4), -60.0))
    with pytest.raises(ValueError, match="queries_dbm"):
        wm.shared_dissimilarity(np.full((1, 5), -60.0), index, 10.0)


def test_fix_sd_grows_with_the_best_dissimilarity():
    s = wfx.FixSettings(sd_m=4.0, sd_per_db=0.2)
    np.testing.assert_allclose(wfx.fix_sds(np.array([0.0, 10.0, np.inf]), s), [4.0, 6.0, 4.0])
    np.testing.assert_allclose(wfx.fix_sds(np.array([50.0]), wfx.FixSettings(sd_m=3.0, sd_per_db=0.0)), [3.0])
    with pytest.raises(ValueError, match="FixSettings.sd_per_db"):
        wfx.FixSettings(sd_per_db=-0.1).validate()


def test_ibeacon_readings_become_fingerprint_columns_at_their_own_time():
    # Two readings of one beacon (its advertised identity) and one whose major was damaged (-1:
    # named by its MAC); a NaN RSSI is left out. Without ``beacons`` the WiFi measurements are
    # all there is.
    wf = _wifi([(20.0, [("a", -50.0, 19.5)])])
    bc = SimpleNamespace(t_s=np.array([18.0, 19.0, 19.5, 21.0]), uuid=["U1", "U1", "U2", "U1"],
                         major=np.array([1, 1, -1, 1]), minor=np.array([7, 7, 3, 7]),
                         rssi_dbm=np.array([-70.0, -65.0, -80.0, nan]), mac=["m1", "m1", "m2", "m1"])
    walk = SimpleNamespace(wifi=wf, beacons=bc)
    assert wm.walk_measurements(walk).n == 1
    meas = wm.walk_measurements(walk, beacons=True)
    assert meas.n == 4
    assert meas.bssids[1:] == [wm.beacon_id("U1", 1, 7), "ibeacon:m2"] == ["ibeacon:u1:1:7", "ibeacon:m2"]
    rss, _, n = wm.pool_windows(meas.t_s, meas.bssid_index, meas.rssi_dbm, len(meas.bssids), [20.0], 2.5, 0.0,
                                meas.reported_s)
    assert rss[0, 1] == -65.0 and rss[0, 2] == -80.0 and n[0] == 4
