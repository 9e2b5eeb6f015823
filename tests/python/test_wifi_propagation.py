"""The per-AP path-loss model (indoorloc.wifi.propagation) and the fixes built from it
(indoorloc.fusion.propagation_fixes)."""

import numpy as np
import pytest

from indoorloc.fusion import propagation_fixes as pf
from indoorloc.fusion.fixes import Fixes
from indoorloc.wifi import propagation as pr


def _synthetic(seed=0, noise_db=2.0):
    """Three APs (one beyond the references' extent), references on an L-shaped path."""
    rng = np.random.default_rng(seed)
    path = np.r_[np.c_[np.linspace(0, 40, 81), np.zeros(81)], np.c_[np.zeros(60), np.linspace(0.5, 30, 60)]]
    aps = np.array([[10.0, 5.0], [30.0, -8.0], [55.0, 10.0]])
    p0 = np.array([-35.0, -40.0, -38.0])
    n = np.array([2.5, 3.0, 2.2])
    h = np.array([3.0, 3.0, 3.0])
    d = np.sqrt(((path[:, None, :] - aps[None]) ** 2).sum(2) + h ** 2)
    rss = p0 - 10 * n * np.log10(d) + noise_db * rng.standard_normal(d.shape)
    rss[rss < -92.0] = np.nan
    return path, rss, aps, p0, n


def test_fit_recovers_the_aps_and_predicts_beyond_the_survey():
    xy, rss, aps, p0, n = _synthetic()
    m = pr.fit_path_loss(rss, xy)
    assert m.ok.all()
    err = np.hypot(*(m.ap_xy_m - aps).T)
    assert err[0] < 2.0 and err[1] < 3.0      # inside / near the survey
    assert err[2] < 20.0                      # 15 m beyond the end of the survey: poorly determined
    # Predictions 20 m off the survey path, against the true field (no noise): the extrapolation.
    far = np.array([[25.0, 20.0], [45.0, 5.0]])
    true = p0 - 10 * n * np.log10(np.sqrt(((far[:, None] - aps[None]) ** 2).sum(2) + 9.0))
    assert np.all(np.abs(m.predict(far) - true) < 5.0)
    assert np.all((m.residual_sd_db >= m.options.min_sd_db) & (m.residual_sd_db < 4.0))


def test_fit_is_deterministic_and_leaves_inputs_alone():
    xy, rss, *_ = _synthetic(1)
    before = rss.copy()
    a, b = pr.fit_path_loss(rss, xy), pr.fit_path_loss(rss, xy)
    np.testing.assert_array_equal(a.ap_xy_m, b.ap_xy_m)
    np.testing.assert_array_equal(rss, before)


def test_scan_log_likelihood_matches_brute_force():
    xy, rss, *_ = _synthetic(2)
    m = pr.fit_path_loss(rss, xy)
    pts = np.array([[0.0, 0.0], [20.0, 0.0], [0.0, 20.0], [35.0, 15.0]])
    mu = m.predict(pts)
    q = np.array([[-60.0, np.nan, -75.0], [np.nan, -70.0, np.nan]])
    for w in (0.0, 0.5):
        ll = pr.scan_log_likelihood(m, q, mu, miss_weight=w)
        ref = np.zeros((2, 4))
        for i in range(2):
            for j in range(4):
                for a in range(3):
                    if np.isfinite(q[i, a]):
                        ref[i, j] -= 0.5 * (q[i, a] - mu[j, a]) ** 2 / m.residual_sd_db[a] ** 2
                    elif w:
                        from scipy.stats import norm
                        ref[i, j] += w * norm.logcdf(-(mu[j, a] - m.options.floor_dbm) / m.options.miss_sd_db)
        np.testing.assert_allclose(ll, ref, rtol=1e-9, atol=1e-9)
    # The best point of a query simulated at (20, 0) is the nearest of the four.
    assert np.argmax(pr.scan_log_likelihood(m, mu[1:2], mu)[0]) == 1


def test_bad_arguments_are_named():
    xy, rss, *_ = _synthetic()
    with pytest.raises(ValueError, match="positions_m"):
        pr.fit_path_loss(rss, xy[:-1])
    with pytest.raises(ValueError, match="rss_dbm"):
        pr.fit_path_loss(np.where(np.isnan(rss), np.inf, rss), xy)
    with pytest.raises(ValueError, match="huber_db"):
        pr.fit_path_loss(rss, xy, pr.PathLossOptions(huber_db=0.0))
    m = pr.fit_path_loss(rss, xy)
    with pytest.raises(ValueError, match="points_m"):
        m.predict(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="predicted_dbm"):
        pr.scan_log_likelihood(m, np.zeros((1, 3)), np.zeros((4, 2)))


def test_model_fixes_take_the_best_cells():
    cells = np.c_[np.arange(10.0), np.zeros(10)]
    ll = -np.abs(np.arange(10.0) - np.array([[2.0], [7.0]])) * 5.0
    f = pf.model_fixes(np.array([1.0, 2.0]), ll, cells, pf.ModelFixSettings(k=3, temperature=5.0, sd_m=2.0), 0)
    assert f.means_m.shape == (2, 3, 2) and np.all(f.sds_m == 2.0)
    assert set(f.means_m[0, :, 0]) == {1.0, 2.0, 3.0} and set(f.means_m[1, :, 0]) == {6.0, 7.0, 8.0}
    w0 = f.weights[0] / f.weights[0].max()
    np.testing.assert_allclose(sorted(w0), sorted([np.exp(-1.0), 1.0, np.exp(-1.0)]))
    with pytest.raises(ValueError, match="log_likelihood"):
        pf.model_fixes(np.array([1.0]), ll, cells, pf.ModelFixSettings())
    with pytest.raises(ValueError, match="temperature"):
        pf.model_fixes(np.array([1.0, 2.0]), ll, cells, pf.ModelFixSettings(temperature=0.0))


def test_mix_fixes_weights():
    a = Fixes.from_arrays([0.0, 1.0], np.zeros((2, 2, 2)), 1.0, np.array([[1.0, 3.0], [1.0, 1.0]]))
    b = Fixes.from_arrays([0.0, 1.0], np.ones((2, 1, 2)), 2.0)
    m = pf.mix_fixes(a, b, 0.25)
    np.testing.assert_allclose(m.weights, [[0.1875, 0.5625, 0.25], [0.375, 0.375, 0.25]])
    np.testing.assert_allclose(m.sds_m[:, 2], 2.0)
    with pytest.raises(ValueError, match="weight_b"):
        pf.mix_fixes(a, b, 1.5)
    with pytest.raises(ValueError, match="same times"):
        pf.mix_fixes(a, Fixes.from_arrays([0.0, 2.0], np.ones((2, 1, 2)), 2.0), 0.5)


def test_block_fixes_match_brute_force():
    rng = np.random.default_rng(3)
    gx, gy = np.meshgrid(np.arange(0.0, 20.0, 2.0) + 1, np.arange(0.0, 12.0, 2.0) + 1)
    cells = np.c_[gx.ravel(), gy.ravel()]
    ll = rng.normal(scale=5.0, size=(3, cells.shape[0]))
    s = pf.ModelFixSettings(k=4, temperature=2.0, sd_m=3.0, block_m=6.0)
    f = pf.model_fixes(np.arange(3.0), ll, cells, s)
    key = np.floor((cells - cells.min(0)) / 6.0).astype(int)
    blocks = {}
    for i, kk in enumerate(map(tuple, key)):
        blocks.setdefault(kk, []).append(i)
    for j in range(3):
        cand = []
        for idx in blocks.values():
            x = ll[j, idx] / 2.0
            cand.append((np.log(np.exp(x).sum()), tuple(cells[idx[int(np.argmax(x))]])))
        cand.sort(reverse=True)
        want = {c for _, c in cand[:4]}
        assert {tuple(m) for m in f.means_m[j]} == want
        w = np.array([m for m, _ in cand[:4]])
        got = dict(zip(map(tuple, f.means_m[j]), f.weights[j]))
        np.testing.assert_allclose([got[c] for _, c in cand[:4]], np.exp(w - w.max()), rtol=1e-9)


def test_stack_fixes_interleaves_in_time():
    a = Fixes.from_arrays([0.0, 2.0], np.zeros((2, 2, 2)), 1.0)
    b = Fixes.from_arrays([1.0, 2.0], np.ones((2, 3, 2)), 2.0)
    s = pf.stack_fixes(a, b)
    np.testing.assert_array_equal(s.times_s, [0.0, 1.0, 2.0, 2.0])
    assert s.means_m.shape == (4, 3, 2)
    np.testing.assert_array_equal(s.weights[0], [1.0, 1.0, 0.0])   # a's fix padded
    np.testing.assert_array_equal(s.sds_m[1], [2.0, 2.0, 2.0])     # b's fix


def test_gate_fixes_flattens_where_the_gate_is_closed():
    f = Fixes.from_arrays([0.0, 1.0], np.array([[[0.0, 0.0], [2.0, 0.0]], [[4.0, 4.0], [6.0, 4.0]]]), 3.0,
                          np.array([[1.0, 3.0], [1.0, 1.0]]))
    g = pf.gate_fixes(f, np.array([0.0, 0.25]))
    assert g.means_m.shape == (2, 3, 2)
    np.testing.assert_allclose(g.weights, [[0.0, 0.0, 1.0], [0.125, 0.125, 0.75]])
    np.testing.assert_allclose(g.means_m[:, 2], [[1.5, 0.0], [5.0, 4.0]])
    assert np.all(g.sds_m[:, 2] == 1e3)
    with pytest.raises(ValueError, match="gate"):
        pf.gate_fixes(f, np.array([0.5, 1.5]))


def test_capped_huber_likelihood_matches_brute_force():
    xy, rss, *_ = _synthetic(4)
    m = pr.fit_path_loss(rss, xy)
    pts = np.array([[0.0, 0.0], [20.0, 0.0], [35.0, 15.0]])
    mu = m.predict(pts)
    q = np.array([[-60.0, np.nan, -45.0], [-90.0, -50.0, np.nan]])
    for cap in (0.0, 2.0):
        ll = pr.scan_log_likelihood(m, q, mu, huber_sd=1.5, cap_sd=cap)
        ref = np.zeros((2, 3))
        for i in range(2):
            for j in range(3):
                for a in range(3):
                    if np.isfinite(q[i, a]):
                        z = abs(q[i, a] - mu[j, a]) / m.residual_sd_db[a]
                        z = min(z, cap) if cap else z
                        ref[i, j] -= 0.5 * z * z if z <= 1.5 else 1.5 * z - 1.125
        np.testing.assert_allclose(ll, ref, rtol=1e-5, atol=1e-4)   # float32 inside
