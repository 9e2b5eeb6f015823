"""Python side of the wifi subsystem: bindings, numpy shapes, errors, and model sanity."""

import numpy as np
import pytest

from indoorloc import wifi


def lattice_map(variance_slope=0.3):
    pos = np.array([[x, y] for x in np.arange(0, 11, 2.0) for y in np.arange(0, 11, 2.0)])
    aps = np.array([[-1, -1], [11, -1], [-1, 11], [11, 11]])
    d = np.linalg.norm(pos[:, None, :] - aps[None], axis=2)
    return pos, -40 - 20 * np.log10(d + 0.5), 4 + variance_slope * d


def test_signal_map_from_scans_and_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    pts = np.repeat(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), 20, axis=0)
    rss = rng.normal(-60, 2, size=(60, 3))
    rss[:, 2] = 100.0  # never heard: dropped
    rss[:5, 1] = np.nan  # not heard sometimes
    m = wifi.SignalMap.from_scans(pts, None, rss, wifi.SignalMapOptions(not_heard_sentinel=100.0))
    assert m.num_points == 3 and m.num_access_points == 2
    np.testing.assert_array_equal(m.access_point_indices, [0, 1])
    np.testing.assert_allclose(m.mean_dbm[0, 0], rss[:20, 0].mean())
    np.testing.assert_allclose(m.variance_db2[0, 0], max(rss[:20, 0].var(ddof=1), 4.0))
    assert m.detection_rate[0, 1] == pytest.approx(15 / 20)
    path = str(tmp_path / "map.txt")
    m.save(path)
    back = wifi.SignalMap.load(path)
    np.testing.assert_array_equal(back.mean_dbm, m.mean_dbm)
    prepared = m.prepare_scans(rss[:5], 100.0, -105.0)
    assert prepared.shape == (5, 2) and np.all(prepared[:, 1] == -105.0)


def test_interpolator_exact_for_affine_fields_and_outside_flag():
    rng = np.random.default_rng(1)
    pos = rng.uniform(0, 10, size=(300, 2))
    fields = np.c_[2 * pos[:, 0] - pos[:, 1] + 3, np.sin(pos[:, 0])]
    interp = wifi.DelaunayInterpolator(pos, fields)
    q = rng.uniform(1, 9, size=(500, 2))
    values, grads, inside, at = interp.interpolate(q)
    assert values.shape == (500, 2) and grads.shape == (500, 2, 2) and inside.dtype == bool
    ok = inside
    np.testing.assert_allclose(values[ok, 0], 2 * q[ok, 0] - q[ok, 1] + 3, atol=1e-9)
    np.testing.assert_allclose(grads[ok, 0], np.tile([2.0, -1.0], (ok.sum(), 1)), atol=1e-9)
    v2, _, inside2, at2 = interp.interpolate(np.array([[50.0, 5.0]]))
    assert not inside2[0] and at2[0, 0] < 10.0
    sib = interp.sibson(q[:20])
    np.testing.assert_allclose(sib[:, 0], 2 * q[:20, 0] - q[:20, 1] + 3, atol=1e-8)
    seq = interp.interpolate(q, sequential=True, num_threads=1)[0]
    par = interp.interpolate(q, sequential=False, num_threads=2)[0]
    np.testing.assert_allclose(seq, par, atol=1e-12)


@pytest.mark.parametrize(
    "positions, message",
    [
        (np.array([[0.0, 0.0], [1.0, 1.0]]), "at least 3 points"),
        (np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]]), "collinear"),
        (np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 0.0]]), "duplicate positions"),
        (np.array([[0.0, 0.0], [1.0, np.nan], [0.0, 1.0]]), "NaN"),
        (np.zeros((3, 3)), r"expected shape \(any, 2\)"),
    ],
)
def test_interpolator_bad_input(positions, message):
    with pytest.raises(ValueError, match=message):
        wifi.DelaunayInterpolator(positions, np.zeros((positions.shape[0], 1)))


def test_model_gradient_matches_numerical_and_bad_scans():
    pos, mean, var = lattice_map()
    model = wifi.RssModel(wifi.SignalMap(pos, None, mean, var))
    scan = model.simulate_scans(np.array([[4.1, 6.3]]), seed=3)
    z = np.array([4.9, 5.3])
    l0, g, fisher, inside = model.evaluate(scan, z)
    h = 1e-6
    num = [
        (model.evaluate(scan, z + h * e)[0] - model.evaluate(scan, z - h * e)[0]) / (2 * h)
        for e in np.eye(2)
    ]
    np.testing.assert_allclose(g, num, rtol=1e-5, atol=1e-8)
    assert inside and np.all(np.linalg.eigvalsh(fisher) > 0)
    with pytest.raises(ValueError, match="rss_dbm"):
        model.evaluate(scan[:, :3], z)
    bad = scan.copy()
    bad[0, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        wifi.locate_ml(model, bad)
    with pytest.raises(ValueError, match="floor 7 is not in the map"):
        model.evaluate(scan, z, floor=7)


def test_tracker_and_ml_fix_on_noiseless_map():
    pos, mean, var = lattice_map(variance_slope=0.0)
    model = wifi.RssModel(wifi.SignalMap(pos, None, mean, var))
    truth = np.array([[3.3, 7.2], [8.1, 1.7]])
    mu, _ = model.mean_and_variance(truth)
    fixes = wifi.locate_ml(model, mu)
    np.testing.assert_allclose(fixes["positions_m"], truth, atol=1e-3)
    assert fixes["covariances_m2"].shape == (2, 2, 2)
    tracker = wifi.GradientTracker(model, wifi.tracker_options(max_step_m=0.5))
    path = np.c_[np.linspace(1, 9, 40), np.linspace(2, 8, 40)]
    mu_path, _ = model.mean_and_variance(path)
    tracker.reset_to(path[0])
    out = tracker.track(mu_path)
    assert np.linalg.norm(out["positions_m"][-1] - path[-1]) < 0.02
    with pytest.raises(ValueError, match="max_step_m"):
        wifi.tracker_options(max_step_m=-1.0)
    with pytest.raises(ValueError, match="not a GradientTrackerOptions field"):
        wifi.tracker_options(speed=3)


def test_simulated_scans_follow_the_model():
    pos, mean, var = lattice_map()
    model = wifi.RssModel(wifi.SignalMap(pos, None, mean, var))
    pts = np.tile([[5.0, 5.0]], (20000, 1))
    scans = model.simulate_scans(pts, seed=9)
    mu, v = model.mean_and_variance(pts[:1])
    np.testing.assert_allclose(scans.mean(axis=0), mu[0], atol=0.1)
    np.testing.assert_allclose(scans.var(axis=0), v[0], rtol=0.05)
    np.testing.assert_array_equal(scans, model.simulate_scans(pts, seed=9))  # seeded


def test_grid_posterior_mean_is_near_truth_and_covariance_shrinks_with_scans():
    pos, mean, var = lattice_map(variance_slope=0.0)
    model = wifi.RssModel(wifi.SignalMap(pos, None, mean, var))
    gp = wifi.GridPosterior(model, spacing_m=0.1)
    truth = np.array([[4.4, 5.6]])
    one = gp.locate(model.simulate_scans(truth, seed=1))
    many = gp.locate(model.simulate_scans(np.repeat(truth, 20, axis=0), seed=2), group_size=20)
    assert np.linalg.norm(many["positions_m"][0] - truth[0]) < 0.5
    assert np.trace(many["covariances_m2"][0]) < np.trace(one["covariances_m2"][0])
    # The noiseless mean scan: posterior mean close to the truth (symmetric likelihood).
    mu, _ = model.mean_and_variance(truth)
    np.testing.assert_allclose(gp.locate(np.repeat(mu, 50, axis=0), group_size=50)["positions_m"][0], truth[0], atol=0.05)
    with pytest.raises(ValueError, match="group_size"):
        gp.locate(mu, group_size=0)
