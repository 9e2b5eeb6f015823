"""Position fixes (fusion.Fixes, ParticleTracker.fix) and WiFi fingerprint fixes
(indoorloc.fusion.wifi_fixes): shapes, validation, the scan dissimilarity by hand, and a walk tracked
from fixes alone."""

import numpy as np
import pytest

from indoorloc import fusion
from indoorloc.fusion import wifi_fixes

HALL = [[0, 0], [40, 0], [40, 10], [0, 10]]


def test_fixes_from_arrays_shapes_and_errors():
    f = fusion.Fixes.from_arrays([0.0, 1.0], [[1.0, 2.0], [3.0, 4.0]], 2.0)
    assert f.means_m.shape == (2, 1, 2) and f.sds_m.shape == (2, 1) and f.weights.shape == (2, 1)
    assert f.floors.shape == (2, 1) and np.all(f.floors == fusion.ANY_FLOOR)
    g = fusion.Fixes.from_arrays([0.0], [[[1.0, 2.0], [3.0, 4.0]]], 2.0, floors=[[3, 4]])
    assert g.floors.tolist() == [[3, 4]]
    t, means, sds, w, floors = f.as_arrays()
    assert means.shape == (2, 2)
    with pytest.raises(ValueError, match="means_m"):
        fusion.Fixes.from_arrays([0.0], np.zeros((2, 3, 2)), 1.0)
    with pytest.raises(ValueError, match="sds_m"):
        fusion.Fixes.from_arrays([0.0], np.zeros((1, 3, 2)), [1.0, 2.0])
    with pytest.raises(ValueError, match="floors"):
        fusion.Fixes.from_arrays([0.0], np.zeros((1, 3, 2)), 1.0, floors=[1, 2])
    with pytest.raises(ValueError, match="times_s"):
        fusion.Fixes.from_arrays([1.0, 0.0], np.zeros((2, 2)), 1.0)
    plan = fusion.floor_plan_from_polygons(HALL)
    steps = fusion.Steps.from_polar([0.5], 0.7, 0.0, 0.05, 0.05)
    bad = fusion.Fixes.from_arrays([0.0], [[5.0, 5.0]], -1.0)
    with pytest.raises(ValueError, match=r"fixes\[0\].sds_m"):
        fusion.track(steps, plan=plan, fixes=bad)
    with pytest.raises(ValueError, match="fix_outlier_probability|outlier_probability"):
        fusion.tracker_options(fix_outlier_probability=1.0)


def test_padding_components_are_ignored_and_streaming_equals_batch():
    plan = fusion.floor_plan_from_polygons(HALL)
    times = 0.5 * np.arange(1, 31)
    steps = fusion.Steps.from_polar(times, 0.7, 0.0, 0.05, 0.05)
    ft = np.arange(0.0, 15.0, 2.0)
    truth_x = 3.0 + 0.7 * 2.0 * ft
    means = np.stack([np.c_[truth_x, np.full(ft.size, 5.0)], np.full((ft.size, 2), np.nan)], axis=1)
    weights = np.c_[np.ones(ft.size), np.zeros(ft.size)]  # second component: padding (NaN mean)
    fixes = fusion.Fixes.from_arrays(ft, means, [[2.0, np.nan]] * ft.size, weights)
    opts = fusion.tracker_options(num_particles=2000, seed=4, unknown_start_heading_sd_rad=0.05)
    batch = fusion.track(steps, plan=plan, fixes=fixes, options=opts, smoother=fusion.SmootherOptions(seed=2))
    assert batch["summary"].fix_updates == ft.size
    assert np.all(np.isfinite(batch["mean_m"])) and np.all(np.isfinite(batch["smoothed_m"]))
    final_truth = np.array([3.0 + 0.7 * 30, 5.0])
    assert np.linalg.norm(batch["mean_m"][-1] - final_truth) < 1.5
    # The streaming API gives the same filter (same seed, same event order).
    tr = fusion.ParticleTracker(plan, None, None, opts)
    k = 0
    est = None
    for i, t in enumerate(times):
        while k < ft.size and ft[k] < t:
            tr.fix(ft[k], means[k, :1], [2.0], [1.0])
            k += 1
        est = tr.step(t, steps.displacements_m[i], fusion.covariance_matrix(steps.covariances_m2[i]))
        while k < ft.size and ft[k] <= t:
            est = tr.fix(ft[k], means[k, :1], [2.0], [1.0])
            k += 1
    np.testing.assert_allclose(est.mean_m, batch["mean_m"][-1], rtol=0, atol=1e-12)
    assert tr.floor_areas_m2[0] == pytest.approx(400.0)


def test_fixes_with_components_on_two_floors_identify_the_floor():
    plan = fusion.floor_plan_from_geometries([
        fusion.FloorGeometry(0, [np.array(HALL, float)], [], np.zeros((0, 4))),
        fusion.FloorGeometry(1, [np.array(HALL, float)], [], np.zeros((0, 4)))])
    times = 0.5 * np.arange(1, 21)
    steps = fusion.Steps.from_polar(times, 0.7, 0.0, 0.05, 0.05)
    ft = np.arange(0.0, 10.0, 1.0)
    x = 3.0 + 0.7 * 2.0 * ft
    # Each fix: the truth on floor 1 (weight 0.6) and a wrong place on floor 0 (weight 0.4).
    means = np.stack([np.c_[x, np.full(ft.size, 5.0)], np.c_[40 - x, np.full(ft.size, 2.0)]], axis=1)
    fixes = fusion.Fixes.from_arrays(ft, means, 2.0, [[0.6, 0.4]] * ft.size, floors=[[1, 0]] * ft.size)
    opts = fusion.tracker_options(num_particles=3000, seed=1, unknown_start_heading_sd_rad=0.05)
    r = fusion.track(steps, plan=plan, fixes=fixes, options=opts)
    assert r["floor_index"][-1] == 1 and r["floor_probabilities"][-1, 1] > 0.99
    assert np.linalg.norm(r["mean_m"][-1] - [3.0 + 0.7 * 20, 5.0]) < 1.5


def test_scan_dissimilarity_by_hand():
    nan = np.nan
    q = np.array([[-50.0, -60.0, nan, nan]])
    x = np.array([[-52.0, nan, -70.0, nan],    # shared: AP0 (2 dB); one-sided: AP1, AP2 -> (2 + 2c) / 3
                  [-50.0, -60.0, nan, nan],    # identical -> 0
                  [nan, nan, nan, -40.0],      # nothing shared: (0 + 3c) / 3 = c
                  [nan, nan, nan, nan]])       # empty database scan: union {AP0, AP1} -> c
    d = wifi_fixes.scan_dissimilarity(q, x, unshared_cost_db=10.0)
    np.testing.assert_allclose(d, [[(2 + 20) / 3, 0.0, 10.0, 10.0]])
    assert np.isinf(wifi_fixes.scan_dissimilarity(np.full((1, 4), nan), np.full((1, 4), nan), 10.0))[0, 0]


def test_fix_settings_are_validated():
    with pytest.raises(ValueError, match="FixSettings.sd_m"):
        wifi_fixes.FixSettings(sd_m=0.0).validate()
    with pytest.raises(ValueError, match="FixSettings.k"):
        wifi_fixes.FixSettings(k=0).validate()


def test_strongest_ap_dissimilarity_by_hand():
    nan = np.nan
    q = np.array([[-40.0, -50.0, -90.0, nan]])
    x = np.array([[-42.0, -50.0, nan, -30.0],   # top-2 of the query: AP0, AP1 -> sqrt((4 + 0) / 2)
                  [nan, -60.0, -90.0, nan]])    # AP0 not heard -> -100: sqrt((60² + 10²) / 2)
    d = wifi_fixes.strongest_ap_dissimilarity(q, x, n=2, not_heard_dbm=-100.0)
    np.testing.assert_allclose(d, [[np.sqrt(2.0), np.sqrt((60.0 ** 2 + 10.0 ** 2) / 2)]])
    assert np.isinf(wifi_fixes.strongest_ap_dissimilarity(np.full((1, 4), nan), x, 2, -100.0)).all()
    db = wifi_fixes.FingerprintDatabase(x, np.array([[0.0, 0.0], [10.0, 0.0]]), ["a", "b", "c", "d"],
                                 wifi_fixes.FixSettings(metric="strongest", strongest_n=2, k=1))
    np.testing.assert_allclose(wifi_fixes.locate_scans(q, db), [[0.0, 0.0]])
    with pytest.raises(ValueError, match="FixSettings.metric"):
        wifi_fixes.FixSettings(metric="cosine").validate()
