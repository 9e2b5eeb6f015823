"""WiFi fingerprints pooled along the walks and the shared-AP dissimilarity (indoorloc.wifi.matcher,
indoorloc.fusion.wifi_fixes with pooling="window"): small synthetic fixtures, checked by hand or against
a brute-force reference."""

from types import SimpleNamespace

import numpy as np
import pytest

from indoorloc.fusion import wifi_fixes
from indoorloc.io.ilc2020 import IlcWifi
from indoorloc.wifi import matcher as wifi_matcher

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
    index = wifi_matcher.ReferenceIndex.build(x, g, beta)
    d = wifi_matcher.shared_dissimilarity(q, index, 30.0)
    np.testing.assert_allclose(d, _brute_force(q, x, g, beta, 30.0), rtol=1e-4, atol=1e-3)
    assert np.isinf(d[:, 0]).all()
    rms, u = wifi_matcher.shared_dissimilarity(q, index, 30.0, parts=True)
    np.testing.assert_allclose(rms + 30.0 * u, d, rtol=1e-6)


def test_a_query_identical_to_a_reference_matches_it_first():
    rng = np.random.default_rng(0)
    x = rng.uniform(-95, -40, (50, 30))
    x[rng.random(x.shape) < 0.5] = nan
    positions = rng.uniform(0, 100, (50, 2))
    for beta, power in ((0.0, 0.0), (5.0, 1.0)):
        s = wifi_fixes.FixSettings(k=3, strength_scale_db=beta, ap_weight_power=power)
        db = wifi_fixes.FingerprintDatabase(x, positions, [f"ap{i}" for i in range(30)], s,
                                     ap_ratio=rng.uniform(0.5, 2.0, 30))
        d = wifi_fixes.dissimilarity(x[[7, 21]], db)
        assert np.argmin(d[0]) == 7 and np.argmin(d[1]) == 21
        np.testing.assert_allclose(d[[0, 1], [7, 21]], 0.0, atol=1e-3)
        best, dist, w = wifi_matcher.knn(d, 3, s.temperature_db)
        assert best[:, 0].tolist() == [7, 21] and np.all(w[:, 0] == 1.0) and np.all(np.diff(dist, axis=1) >= 0)
        np.testing.assert_allclose(wifi_fixes.locate_scans(x[[7]], db.with_settings(wifi_fixes.FixSettings(k=1))), positions[[7]])


def test_a_reading_last_seen_10_s_ago_is_used_at_its_own_time():
    # Scan at t = 20 s reports AP "b" last seen at t = 10 s (10 s old) and AP "a" fresh; the scan
    # at t = 22 s repeats both measurements (the same last-seen times): each counts once.
    wf = _wifi([(20.0, [("a", -50.0, 19.5), ("b", -60.0, 10.0)]),
                (22.0, [("a", -50.0, 19.5), ("b", -60.0, 10.0), ("a", -55.0, 21.6)])])
    meas = wifi_matcher.walk_measurements(SimpleNamespace(wifi=wf))
    assert meas.n == 3
    b = meas.bssids.index("b")
    i = int(np.flatnonzero(meas.bssid_index == b)[0])
    assert meas.t_s[i] == 10.0 and meas.reported_s[i] == 20.0
    # The 2.5 s staleness filter of "fresh" pooling drops it ...
    _, fresh, names = wifi_fixes.fresh_scans(SimpleNamespace(wifi=wf), 2.5)
    assert np.isnan(fresh[:, names.index("b")]).all()
    # ... a window around its own last-seen time holds it, a window around the scan time does not.
    rss, mean_t, n = wifi_matcher.pool_windows(meas.t_s, meas.bssid_index, meas.rssi_dbm, 2, [10.0, 20.0], 1.0, 1.0)
    assert rss[0, b] == -60.0 and np.isnan(rss[1, b]) and mean_t[0] == 10.0
    # Max-pooling keeps the strongest of "a"'s two measurements in [19, 22].
    a = meas.bssids.index("a")
    rss, _, n = wifi_matcher.pool_windows(meas.t_s, meas.bssid_index, meas.rssi_dbm, 2, [22.0], 3.0, 0.0)
    assert rss[0, a] == -50.0 and n[0] == 2
    # Causal queries: the measurement at 21.6 s was first reported at 22 s, not by the scan at 21.7 s.
    rss, _, n = wifi_matcher.pool_windows(meas.t_s, meas.bssid_index, meas.rssi_dbm, 2, [21.7], 5.0, 0.0,
                                          meas.reported_s)
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

    s = wifi_fixes.FixSettings(ref_window_s=2.0, query_window_s=2.0, min_scans=1, min_aps=1, k=1, ap_weight_power=0.0)
    db = wifi_fixes.build_database([walk], s, positions_at=[along])
    assert db.n_scans > 20 and sorted(db.bssids) == ["common", "near0", "near20"]
    t, rss = wifi_fixes.walk_queries(walk, db)
    assert np.all(np.diff(t) >= 0) and rss.shape == (t.size, 3)
    est = wifi_fixes.locate_scans(rss, db)
    heard20 = np.isfinite(rss[:, db.bssids.index("near20")])
    assert np.all(np.abs(est[heard20, 0] - 22.0) < 4.0)


def test_ap_reliability_down_weights_a_noisy_ap():
    rng = np.random.default_rng(1)
    n = 400
    xy = np.column_stack([rng.uniform(0, 20, n), np.zeros(n)])
    walk = rng.integers(0, 8, n)
    stable = -60.0 - xy[:, 0] + rng.normal(0, 1.0, n)
    noisy = -60.0 - xy[:, 0] + rng.normal(0, 8.0, n)
    g = wifi_matcher.ap_reliability(np.column_stack([stable, noisy, np.full(n, nan)]), xy, walk, power=1.0)
    assert g[0] > 3 * g[1] and g[2] == pytest.approx(1.0)
    g = wifi_matcher.ap_reliability(np.column_stack([stable, noisy]), xy, walk, power=0.0)
    np.testing.assert_array_equal(g, 1.0)


def _dense_ap_reliability(x, positions_m, walk_index, power, pair_radius_m=2.0, prior_pairs=10.0):
    """ap_reliability as first written: (P, K) blocks of differences summed over the pairs."""
    from scipy.spatial import cKDTree

    pairs = cKDTree(positions_m).query_pairs(pair_radius_m, output_type="ndarray")
    pairs = pairs[walk_index[pairs[:, 0]] != walk_index[pairs[:, 1]]]
    sq, n = np.zeros(x.shape[1]), np.zeros(x.shape[1])
    for a in range(0, pairs.shape[0], 20_000):
        p = pairs[a:a + 20_000]
        diff = x[p[:, 0]] - x[p[:, 1]]
        both = np.isfinite(diff)
        sq += np.where(both, diff * diff, 0.0).sum(axis=0)
        n += both.sum(axis=0)
    pooled = sq.sum() / (2.0 * n.sum())
    return (pooled / ((sq / 2.0 + prior_pairs * pooled) / (n + prior_pairs))) ** power


def test_ap_reliability_equals_the_dense_sums_bit_for_bit():
    # More than one block of 20,000 pairs, a sparse (N, K) matrix with APs heard by none or one.
    rng = np.random.default_rng(3)
    n, k = 700, 60
    xy = rng.uniform(0, 10, (n, 2))
    walk = rng.integers(0, 12, n)
    x = np.where(rng.random((n, k)) < 0.3, rng.normal(-70, 9, (n, k)).round(), nan)
    x[:, 5] = nan
    x[:, 7] = nan
    x[3, 7] = -50.0
    got = wifi_matcher.ap_reliability(x, xy, walk, power=1.0, max_pairs=10**9)
    want = _dense_ap_reliability(x, xy, walk, 1.0)
    assert got.tobytes() == want.tobytes()


@pytest.mark.parametrize("field, value", [
    ("query_window_s", 0.0), ("ref_spacing_s", -1.0), ("ref_window_s", float("nan")), ("penalty_db", -5.0),
    ("ap_weight_power", float("inf")), ("strength_scale_db", 0.5), ("pooling", "scan"), ("query_align", "start"),
    ("metric", "cosine"), ("k", 0), ("pair_radius_m", 0.0),
])
def test_settings_validation_names_the_field(field, value):
    with pytest.raises(ValueError, match=f"FixSettings.{field}"):
        wifi_fixes.FixSettings(**{field: value}).validate()


def test_shared_dissimilarity_refuses_wrong_columns():
    index = wifi_matcher.ReferenceIndex.build(np.full((3, 4), -60.0))
    with pytest.raises(ValueError, match="queries_dbm"):
        wifi_matcher.shared_dissimilarity(np.full((1, 5), -60.0), index, 10.0)


def test_fix_sd_grows_with_the_best_dissimilarity():
    s = wifi_fixes.FixSettings(sd_m=4.0, sd_per_db=0.2)
    np.testing.assert_allclose(wifi_fixes.fix_sds(np.array([0.0, 10.0, np.inf]), s), [4.0, 6.0, 4.0])
    np.testing.assert_allclose(wifi_fixes.fix_sds(np.array([50.0]), wifi_fixes.FixSettings(sd_m=3.0, sd_per_db=0.0)), [3.0])
    with pytest.raises(ValueError, match="FixSettings.sd_per_db"):
        wifi_fixes.FixSettings(sd_per_db=-0.1).validate()


def test_ibeacon_readings_become_fingerprint_columns_at_their_own_time():
    # Two readings of one beacon (its advertised identity) and one whose major was damaged (-1:
    # named by its MAC); a NaN RSSI is left out. Without ``beacons`` the WiFi measurements are
    # all there is.
    wf = _wifi([(20.0, [("a", -50.0, 19.5)])])
    bc = SimpleNamespace(t_s=np.array([18.0, 19.0, 19.5, 21.0]), uuid=["U1", "U1", "U2", "U1"],
                         major=np.array([1, 1, -1, 1]), minor=np.array([7, 7, 3, 7]),
                         rssi_dbm=np.array([-70.0, -65.0, -80.0, nan]), mac=["m1", "m1", "m2", "m1"])
    walk = SimpleNamespace(wifi=wf, beacons=bc)
    assert wifi_matcher.walk_measurements(walk).n == 1
    meas = wifi_matcher.walk_measurements(walk, beacons=True)
    assert meas.n == 4
    assert meas.bssids[1:] == [wifi_matcher.beacon_id("U1", 1, 7), "ibeacon:m2"] == ["ibeacon:u1:1:7", "ibeacon:m2"]
    rss, _, n = wifi_matcher.pool_windows(meas.t_s, meas.bssid_index, meas.rssi_dbm, len(meas.bssids), [20.0], 2.5, 0.0,
                                meas.reported_s)
    assert rss[0, 1] == -65.0 and rss[0, 2] == -80.0 and n[0] == 4


# --- the compiled matcher (indoorloc._core.wifi.SharedApMatcher) against the numpy reference ---


def _sparse_fingerprints(rng, rows, aps, heard):
    x = rng.uniform(-95, -30, (rows, aps))
    x[rng.random(x.shape) > heard] = nan
    return x


@pytest.mark.parametrize("beta", [0.0, 5.0])
def test_compiled_dissimilarity_equals_the_numpy_reference(beta):
    rng = np.random.default_rng(11)
    x = _sparse_fingerprints(rng, 400, 60, 0.12)
    q = _sparse_fingerprints(rng, 50, 60, 0.15)
    q[3] = nan                                   # a query that heard nothing: d = inf everywhere
    index = wifi_matcher.ReferenceIndex.build(x, rng.uniform(0.3, 2.0, 60), beta)
    rms_c, u_c = wifi_matcher.shared_dissimilarity(q, index, 0.0, parts=True)
    rms_n, u_n = wifi_matcher.shared_dissimilarity_numpy(q, index, 0.0, parts=True)
    assert np.array_equal(np.isinf(rms_c), np.isinf(rms_n)) and np.isinf(rms_c[3]).all()
    fin = np.isfinite(rms_n)
    assert fin.mean() > 0.3                      # the comparison is not vacuous
    np.testing.assert_allclose(rms_c[fin], rms_n[fin], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(u_c, u_n, rtol=0, atol=1e-12)
    d = wifi_matcher.shared_dissimilarity(q, index, 160.0)
    np.testing.assert_allclose(d[fin], (rms_n + 160.0 * u_n)[fin], rtol=1e-9, atol=1e-9)


def test_compiled_knn_equals_numpy_knn_and_does_not_depend_on_threads():
    rng = np.random.default_rng(12)
    x = _sparse_fingerprints(rng, 600, 80, 0.1)
    q = _sparse_fingerprints(rng, 70, 80, 0.12)
    index = wifi_matcher.ReferenceIndex.build(x, rng.uniform(0.3, 2.0, 80), 5.0)
    best_n, d_n, w_n = wifi_matcher.knn(wifi_matcher.shared_dissimilarity_numpy(q, index, 160.0), 20, 3.0)
    best_c, d_c, w_c = wifi_matcher.shared_knn(q, index, 160.0, 20, 3.0)
    assert best_c.shape == (70, 20) and best_c.dtype == np.int64
    fin = np.isfinite(d_n)
    assert np.array_equal(fin, np.isfinite(d_c)) and fin.mean() > 0.5
    np.testing.assert_allclose(d_c[fin], d_n[fin], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(w_c, w_n, rtol=0, atol=1e-9)
    assert np.array_equal(best_c[fin], best_n[fin])  # random RSS: no exact ties
    assert np.all(w_c[~fin] == 0) and np.all((best_c >= 0) & (best_c < 600))
    for threads in (2, 3, 0):
        b, d, w = wifi_matcher.shared_knn(q, index, 160.0, 20, 3.0, num_threads=threads)
        assert np.array_equal(b, best_c) and np.array_equal(d, d_c) and np.array_equal(w, w_c)
        assert np.array_equal(wifi_matcher.shared_dissimilarity(q, index, 160.0, num_threads=threads),
                              wifi_matcher.shared_dissimilarity(q, index, 160.0))


def test_fixes_for_walk_components_equal_the_numpy_knn():
    """The fixes fusion uses (compiled kNN) hold the components the numpy kNN gives."""
    rng = np.random.default_rng(13)
    x = _sparse_fingerprints(rng, 300, 40, 0.2)
    positions = rng.uniform(0, 60, (300, 2))
    db = wifi_fixes.FingerprintDatabase(x, positions, [f"ap{i}" for i in range(40)], wifi_fixes.FixSettings(),
                                 ap_ratio=rng.uniform(0.5, 2.0, 40))
    q = _sparse_fingerprints(rng, 25, 40, 0.25)
    s = db.settings
    d_numpy = wifi_matcher.shared_dissimilarity_numpy(q, db.index, s.penalty_db)
    best_n, d_n, w_n = wifi_matcher.knn(d_numpy, s.k, s.temperature_db)
    best_c, d_c, w_c = wifi_fixes.nearest(q, db)
    np.testing.assert_allclose(w_c, w_n, atol=1e-9)
    np.testing.assert_allclose(wifi_fixes.fix_sds(d_c[:, 0], s), wifi_fixes.fix_sds(d_n[:, 0], s), atol=1e-9)
    np.testing.assert_allclose(positions[best_c][w_n > 0], positions[best_n][w_n > 0])
    expected = (w_n[:, :, None] * positions[best_n]).sum(1) / w_n.sum(1, keepdims=True)
    np.testing.assert_allclose(wifi_fixes.locate_scans(q, db), expected, atol=1e-9)


def test_fix_settings_defaults_are_the_compiled_matcher_defaults():
    from indoorloc.wifi import SharedApMatcherOptions

    o, s = SharedApMatcherOptions(), wifi_fixes.FixSettings()
    assert (s.penalty_db, s.strength_scale_db, s.k, s.temperature_db) == (
        o.penalty_db, o.strength_scale_db, o.k, o.temperature_db) == (160.0, 5.0, 20, 3.0)
    assert o.replace(k=5).k == 5 and o.to_dict()["penalty_db"] == 160.0
    with pytest.raises(ValueError, match="temperature_db"):
        o.replace(temperature_db=0.0)
    with pytest.raises(ValueError, match="strength_scale_db"):
        SharedApMatcherOptions(strength_scale_db=0.5)


@pytest.mark.parametrize("bad, match", [
    (np.full((2, 3), np.inf), "reference_rss_dbm"),
    (np.full((2, 3), 5e3), "reference_rss_dbm"),
    ("abc", "reference_rss_dbm"),
])
def test_compiled_matcher_rejects_bad_references(bad, match):
    from indoorloc.wifi import SharedApMatcher

    with pytest.raises(ValueError, match=match):
        SharedApMatcher(bad)


def test_compiled_matcher_rejects_bad_queries_and_weights():
    from indoorloc.wifi import SharedApMatcher

    x = np.full((4, 3), -60.0)
    m = SharedApMatcher(x)
    with pytest.raises(ValueError, match="queries_dbm"):
        m.nearest(np.full((1, 4), -60.0))
    with pytest.raises(ValueError, match="queries_dbm"):
        m.parts(np.array([[-60.0, np.inf, nan]]))
    with pytest.raises(ValueError, match="ap_weights"):
        SharedApMatcher(x, np.array([1.0, -1.0, 1.0]))
    with pytest.raises(ValueError, match="num_threads"):
        m.nearest(x, num_threads=1.5)
    q = x.copy()
    m.nearest(q, num_threads=2)
    assert np.array_equal(q, x)                   # inputs not modified


# --- the WiFi-only baseline of `indoorloc wifi evaluate` ("shared_knn") ---


def test_knn_positions_votes_the_floor_then_averages_on_it():
    positions = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0], [5.0, 5.0]])
    floors = np.array([1, 2, 2, 1])
    best = np.array([[0, 1, 2, 3], [3, 0, 1, 2], [1, 2, 0, 3]])
    w = np.array([[1.0, 0.4, 0.4, 0.1],        # floor 1: 1.1, floor 2: 0.8 -> floor 1, mean of refs 0 and 3
                  [0.0, 0.0, 0.0, 0.0],        # nothing shared: mean position, the commonest floor (tie: lowest)
                  [1.0, 1.0, 0.5, 0.5]])       # floor 2: 2.0
    pos, fl = wifi_matcher.knn_positions(best, w, positions, floors)
    np.testing.assert_allclose(pos[0], (1.0 * positions[0] + 0.1 * positions[3]) / 1.1)
    np.testing.assert_allclose(pos[1], positions.mean(axis=0))
    np.testing.assert_allclose(pos[2], (positions[1] + positions[2]) / 2)
    assert fl.tolist() == [1, 1, 2] and fl.dtype == np.int64


def test_block_mean_averages_only_the_readings_heard():
    from indoorloc.experiments import wifi_evaluate as we

    x = np.array([[-50.0, nan, nan], [-60.0, -70.0, nan], [nan, nan, nan], [-40.0, nan, nan]])
    out = we.block_mean(x, 2)
    np.testing.assert_allclose(out[0, :2], [-55.0, -70.0])
    assert np.isnan(out[0, 2]) and np.isnan(out[1, 1:]).all() and out[1, 0] == -40.0


def test_shared_knn_in_wifi_evaluate_on_a_synthetic_two_floor_dataset():
    """Evaluation of "shared_knn" beside "wknn": same test scans, CV on the training points only."""
    from indoorloc.experiments import wifi_evaluate as we
    from indoorloc.io.wifi_datasets import FingerprintDataset, FingerprintSplit

    rng = np.random.default_rng(5)
    aps = rng.uniform(0, 30, (12, 2))
    ap_floor = np.repeat([0, 1], 6)

    def scans(points, floors, reps):
        xy = np.repeat(points, reps, axis=0)
        fl = np.repeat(floors, reps)
        d = np.hypot(*(xy[:, None] - aps[None]).transpose(2, 0, 1))
        rss = -40 - 25 * np.log10(np.maximum(d, 1)) - 15 * (fl[:, None] != ap_floor[None]) + rng.normal(0, 2, d.shape)
        rss = np.where(rss > -85, rss, 100.0)          # UJI-style sentinel for "not heard"
        ids = np.repeat(np.arange(len(points)), reps)
        return FingerprintSplit(rss, xy, fl, ids)

    grid = np.array([[x, y] for x in range(0, 30, 5) for y in range(0, 30, 5)], float)
    train_pts = np.vstack([grid, grid])
    train_fl = np.repeat([0, 1], len(grid))
    test_pts = rng.uniform(0, 25, (20, 2))
    test_fl = rng.integers(0, 2, 20)
    ds = FingerprintDataset("synthetic", scans(train_pts, train_fl, 4), scans(test_pts, test_fl, 2), 100.0,
                            [f"ap{i}" for i in range(12)])
    hyper = we.cross_validate(ds, k=1, max_points=6, methods=["shared_knn"])
    assert hyper.shared["k"] in we.SHARED_GRID["k"] and hyper.shared["penalty_db"] in we.SHARED_GRID["penalty_db"]
    res = we.evaluate(ds, 1, hyper, methods=["wknn", "shared_knn"])
    assert set(res) == {"wknn", "shared_knn"}
    r = res["shared_knn"]
    assert r.errors_m.shape == (40,) and np.isfinite(r.errors_m).all()
    assert r.errors_m.mean() < 6.0 and r.floor_hit.mean() > 0.9     # points 5 m apart, floors 15 dB apart
    assert "shared_knn" in we.markdown(res, "t")


def test_wifi_evaluate_cli_reports_shared_knn_beside_wknn(shared_data, tmp_path, capsys):
    """`indoorloc wifi evaluate --methods wknn shared_knn --json`: the old keys stay, shared_knn is added."""
    import json

    from indoorloc import cli

    root = shared_data / "wifi"
    if not root.is_dir():
        pytest.skip(f"no WiFi datasets under {root}")
    out = tmp_path / "w.json"
    assert cli.main(["wifi", "evaluate", "--data-root", str(root), "--dataset", "corridor", "--scans", "1",
                     "--cv-points", "4", "--threads", "1", "--quiet", "--methods", "wknn", "shared_knn",
                     "--json", str(out)]) == 0
    entry = json.loads(out.read_text())["corridor/k=1"]
    assert set(entry["hyper"]) == {"model", "k", "shared_knn"}
    assert set(entry["hyper"]["shared_knn"]) == {"penalty_db", "strength_scale_db", "k", "temperature_db"}
    rows = {r["method"]: r for r in entry["results"]}
    assert set(rows) == {"wknn", "shared_knn"}
    assert {"n", "mean_m", "median_m", "p90_m", "floor_hit_rate"} <= set(rows["shared_knn"])
    assert rows["shared_knn"]["n"] == rows["wknn"]["n"] and 0 < rows["shared_knn"]["mean_m"] < 5
    assert "| shared_knn |" in capsys.readouterr().out
    assert cli.main(["wifi", "evaluate", "--data-root", str(root), "--dataset", "corridor", "--scans", "1",
                     "--quiet", "--methods", "nope"]) != 0
    assert "argument 'methods': unknown ['nope']" in capsys.readouterr().err


def test_a_database_with_its_compiled_matcher_pickles_and_copies():
    import copy
    import pickle

    rss = np.array([[-50.0, -60.0], [-70.0, nan], [-55.0, -65.0], [-52.0, -61.0]])
    xy = np.array([[0.0, 0.0], [5.0, 0.0], [10.0, 0.0], [0.5, 0.0]])
    db = wifi_fixes.assemble_database([(rss, xy, ["a", "b"], np.zeros(4, int), np.arange(4))], wifi_fixes.FixSettings(k=2))
    q = np.array([[-51.0, -60.5]])
    before = wifi_fixes.locate_scans(q, db)  # builds the compiled matcher
    for other in (pickle.loads(pickle.dumps(db)), copy.deepcopy(db)):
        np.testing.assert_array_equal(wifi_fixes.locate_scans(q, other), before)

