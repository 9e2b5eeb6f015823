"""Lorenz-63 simulator, the EnKS / AnEnKS / NNN baselines of paper 001 and its experiment runners.

Fast (a few seconds): short test problems, a 10^4 catalog, brute-force references (RTS smoother
for the EnKS on a linear-Gaussian model, exact linear maps for the analog regression). Tests of
the AnFB runners skip only when the analog bindings are missing.
"""

import sys
import types

import numpy as np
import pytest

from indoorloc.experiments import analog_baselines as baselines
from indoorloc.experiments import analog_imu, analog_lorenz63
from indoorloc.simulate import lorenz63

CLIMATOLOGY_STD = float(np.sqrt(np.trace(lorenz63.CLIMATOLOGY_COV) / 3))  # 8.5


def rmse(a, b):
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


@pytest.fixture(scope="module")
def catalog_1e4():
    return lorenz63.catalog_trajectory(10**4, seed=0)


# ---------------------------------------------------------------------------------------------
# Lorenz-63 simulator


def test_rk4_matches_solve_ivp():
    from scipy.integrate import solve_ivp

    x0 = np.array([1.0, 2.0, 20.0])
    trajectory = lorenz63.simulate(x0, 100, dt=0.01)
    assert trajectory.shape == (101, 3)
    ref = solve_ivp(
        lambda t, x: lorenz63.derivative(x), (0.0, 1.0), x0, t_eval=np.linspace(0.0, 1.0, 101), rtol=1e-11, atol=1e-11
    )
    assert np.max(np.abs(ref.y.T - trajectory)) < 1e-3  # RK4 at dt = 0.01: ~2e-4 over one time unit
    # The vectorised step and the scalar single-trajectory path agree.
    batch = lorenz63.simulate(np.stack([x0, x0 + 1.0]), 100)
    assert batch.shape == (101, 2, 3)
    np.testing.assert_allclose(batch[:, 0], trajectory, rtol=0, atol=1e-12)
    np.testing.assert_allclose(lorenz63.rk4_step(x0[None], 0.01)[0], trajectory[1], rtol=0, atol=1e-14)


def test_test_problem_shapes_and_observation_pattern():
    truth, obs = lorenz63.test_problem(3, T=1000, dt_obs=40, R=2.0)
    assert truth.shape == (1000, 3) and obs.shape == (1000, 1)
    seen = np.flatnonzero(np.isfinite(obs[:, 0]))
    np.testing.assert_array_equal(seen, np.arange(0, 1000, 40))
    noise = obs[seen, 0] - truth[seen, 0]
    assert 0.3 < noise.std() < 3.0  # variance 2
    again_truth, again_obs = lorenz63.test_problem(3, T=1000)
    np.testing.assert_array_equal(truth, again_truth)
    np.testing.assert_array_equal(obs, again_obs)
    other, _ = lorenz63.test_problem(4, T=1000)
    assert np.abs(other - truth).max() > 1.0
    # On the attractor after the spin-up.
    assert np.all((truth[:, 2] > 0) & (truth[:, 2] < 55)) and np.abs(truth[:, 0]).max() < 25


def test_catalog_is_independent_of_test_problem_with_same_seed():
    catalog = lorenz63.catalog_trajectory(500, seed=3)
    assert catalog.shape == (501, 3)
    truth, _ = lorenz63.test_problem(3, T=500)
    assert np.abs(catalog[:500] - truth).max() > 1.0
    # The 10^4 catalog is the beginning of the 10^5 one (same seed).
    np.testing.assert_array_equal(lorenz63.catalog_trajectory(200, seed=3), catalog[:201])
    with pytest.raises(ValueError, match="'m'"):
        lorenz63.catalog_trajectory(0)


# ---------------------------------------------------------------------------------------------
# Ensemble Kalman smoother


def _rts_smoother(F, Q, H, R, m0, P0, obs):
    """Exact Kalman filter + Rauch-Tung-Striebel smoother (NaN rows: no update)."""
    T, n = obs.shape[0], m0.size
    mf, Pf, ma, Pa = (np.empty((T, n)), np.empty((T, n, n)), np.empty((T, n)), np.empty((T, n, n)))
    m, P = m0, P0
    for t in range(T):
        if t > 0:
            m, P = F @ m, F @ P @ F.T + Q
        mf[t], Pf[t] = m, P
        if np.isfinite(obs[t, 0]):
            S = H @ P @ H.T + R
            K = P @ H.T @ np.linalg.inv(S)
            m = m + K @ (obs[t] - H @ m)
            P = P - K @ H @ P
        ma[t], Pa[t] = m, P
    ms = ma.copy()
    for t in range(T - 2, -1, -1):
        G = Pa[t] @ F.T @ np.linalg.inv(Pf[t + 1])
        ms[t] = ma[t] + G @ (ms[t + 1] - mf[t + 1])
    return ms, ma


def test_enks_matches_rts_smoother_on_linear_gaussian_model():
    rng = np.random.default_rng(5)
    c, s = np.cos(0.3), np.sin(0.3)
    F = 0.95 * np.array([[c, -s], [s, c]])
    Q = 0.1 * np.eye(2)
    H = np.array([[1.0, 0.0]])
    R = np.array([[0.5]])
    m0, P0 = np.array([1.0, -1.0]), np.eye(2)
    T = 30
    x = rng.multivariate_normal(m0, P0)
    obs = np.full((T, 1), np.nan)
    for t in range(T):
        if t > 0:
            x = F @ x + rng.multivariate_normal(np.zeros(2), Q)
        if t % 3 == 0:
            obs[t, 0] = x[0] + np.sqrt(R[0, 0]) * rng.standard_normal()
    exact_smooth, exact_filter = _rts_smoother(F, Q, H, R, m0, P0, obs)

    N = 4000
    gen = np.random.default_rng(0)
    E0 = gen.multivariate_normal(m0, P0, size=N)
    smooth, filt = baselines.ensemble_kalman_smoother(
        lambda E: E @ F.T + gen.standard_normal(E.shape) * np.sqrt(0.1), E0, obs, [0], R, gen
    )
    assert np.abs(filt - exact_filter).max() < 0.1
    assert np.abs(smooth - exact_smooth).max() < 0.1
    # The smoother uses later observations: closer to the exact smoother than the filter is.
    assert rmse(smooth, exact_smooth) < 0.5 * rmse(exact_filter, exact_smooth)


def test_enks_lorenz63_well_below_climatology():
    truth, obs = lorenz63.test_problem(0, T=200, dt_obs=8)
    est = baselines.enks_lorenz63(obs, n_members=100, seed=0)
    assert est.shape == (200, 3)
    assert rmse(est, truth) < 0.3 * CLIMATOLOGY_STD
    np.testing.assert_array_equal(est, baselines.enks_lorenz63(obs, n_members=100, seed=0))  # seeded


def test_enks_without_observations_stays_climatological():
    obs = np.full((20, 1), np.nan)
    est = baselines.enks_lorenz63(obs, n_members=50, seed=1)
    assert np.all(np.isfinite(est))
    with pytest.raises(ValueError, match="observed"):
        baselines.enks_lorenz63(np.zeros((20, 2)), observed=[0])
    with pytest.raises(ValueError, match="'R'"):
        baselines.enks_lorenz63(np.zeros((20, 1)), R=-1.0)


# ---------------------------------------------------------------------------------------------
# Analog forecasting and AnEnKS


def test_local_linear_analog_forecast_is_exact_on_a_linear_map():
    rng = np.random.default_rng(2)
    A = np.array([[0.9, 0.2, 0.0], [-0.1, 0.8, 0.3], [0.0, 0.1, 1.1]])
    b = np.array([0.5, -1.0, 2.0])
    analogs = rng.normal(size=(3000, 3))
    forecaster = baselines.AnalogForecaster(analogs, analogs @ A.T + b, k=20, ridge=0.0)
    members = rng.normal(size=(50, 3)) * 0.8
    np.testing.assert_allclose(forecaster(members, rng), members @ A.T + b, atol=1e-8)
    w = forecaster.weights(np.array([[0.0, 1.0, 2.0, 3.0]]))
    assert w.shape == (1, 4) and w.sum() == pytest.approx(1.0) and np.all(np.diff(w[0]) < 0)


def test_anenks_with_1e4_catalog_well_below_climatology(catalog_1e4):
    truth, obs = lorenz63.test_problem(0, T=200, dt_obs=8)
    est = baselines.anenks(obs, catalog_1e4[:-1], catalog_1e4[1:], observed=[0], R=2.0, n_members=100, k=50, seed=0)
    assert est.shape == (200, 3)
    assert rmse(est, truth) < 0.3 * CLIMATOLOGY_STD


def test_anenks_paper_setting_beats_climatology(catalog_1e4):
    # Table 1 setting (x every 40 steps), shortened: still well below the climatological spread.
    forecaster = baselines.AnalogForecaster(catalog_1e4[:-1], catalog_1e4[1:], k=50)
    errors = []
    for seed in range(2):
        truth, obs = lorenz63.test_problem(seed, T=400)
        est = baselines.anenks(obs, None, None, observed=[0], R=2.0, seed=seed, forecaster=forecaster)
        errors.append(rmse(est, truth))
    assert np.mean(errors) < 0.8 * CLIMATOLOGY_STD


# ---------------------------------------------------------------------------------------------
# Naive nearest neighbour


def test_nearest_neighbour_fill_exact_on_a_catalog_trajectory(catalog_1e4):
    rng = np.random.default_rng(0)
    truth = catalog_1e4[3000:3300]
    mask = rng.random(truth.shape) < 0.5
    mask[np.arange(300), rng.integers(0, 3, 300)] = True  # at least one value seen per step
    obs = np.where(mask, truth, np.nan)
    filled = baselines.nearest_neighbour_fill(obs, catalog_1e4)
    np.testing.assert_allclose(filled, truth, rtol=0, atol=1e-12)


def test_nearest_neighbour_fill_carries_previous_estimate():
    catalog = np.array([[0.0, 0.0], [1.0, 10.0], [2.0, 20.0]])
    obs = np.array([[np.nan, np.nan], [1.1, np.nan], [np.nan, np.nan], [np.nan, 19.0]])
    filled = baselines.nearest_neighbour_fill(obs, catalog)
    np.testing.assert_allclose(filled, [[1.0, 10.0], [1.1, 10.0], [1.1, 10.0], [2.0, 19.0]])
    with pytest.raises(ValueError, match="disagree"):
        baselines.nearest_neighbour_fill(obs, np.zeros((3, 3)))


# ---------------------------------------------------------------------------------------------
# Experiment runners


def test_table1_runner_without_anfb_and_markdown():
    result = analog_lorenz63.run_table1(
        n_realisations=2, catalog_sizes=(2000,), methods=("enks", "anenks"),
        setting=analog_lorenz63.Lorenz63Setting(T=150, dt_obs=8)
    )
    names = [(row["method"], row["M"]) for row in result["rows"]]
    assert names == [("EnKS", None), ("AnEnKS", 2000)]
    for row in result["rows"]:
        assert len(row["rmse"]) == 2 and row["rmse_mean"] < CLIMATOLOGY_STD
    table = analog_lorenz63.markdown_table(result)
    assert "| EnKS | - | - |" in table and "3.78" in table


def test_anfb_runner_reports_missing_bindings(monkeypatch):
    import indoorloc

    bare = types.ModuleType("indoorloc.analog")
    monkeypatch.setitem(sys.modules, "indoorloc.analog", bare)
    monkeypatch.setattr(indoorloc, "analog", bare, raising=False)
    assert not analog_lorenz63.analog_available()
    with pytest.raises(ImportError, match="not built"):
        analog_lorenz63.run_table1(n_realisations=1, methods=("anfb",))


SHORT_PROBLEM = analog_lorenz63.Lorenz63Setting(T=200, dt_obs=8)


def test_lorenz63_setting_holds_the_papers_defaults_and_the_old_keywords_still_work():
    """The paper's setting (§3.1) is written once; the former keywords T, dt_obs, R, n_members,
    anenks_k warn and give the same result as the setting; a misspelt one is a TypeError."""
    assert analog_lorenz63.PAPER_SETTING == analog_lorenz63.Lorenz63Setting(T=1000, dt_obs=40, R=2.0, n_members=100,
                                                                            anenks_k=50)
    args = dict(n_realisations=1, catalog_sizes=(2000,), methods=("enks",))
    new = analog_lorenz63.run_table1(**args, setting=analog_lorenz63.Lorenz63Setting(T=120, dt_obs=8, n_members=20))
    with pytest.warns(DeprecationWarning, match=r"run_table1\(T=.*setting=Lorenz63Setting"):
        old = analog_lorenz63.run_table1(**args, T=120, dt_obs=8, n_members=20)
    assert old["rows"][0]["rmse"] == new["rows"][0]["rmse"]
    assert (old["settings"]["T"], old["settings"]["n_members"]) == (120, 20)
    with pytest.raises(TypeError, match="'dt_ob'"):
        analog_lorenz63.run_table1(**args, dt_ob=8)


def test_anfb_lorenz63_below_climatology():
    result = analog_lorenz63.run_table1(
        n_realisations=1, catalog_sizes=(10**4,), beams=(None, 1000), methods=("anfb",), setting=SHORT_PROBLEM
    )
    assert [row["beam"] for row in result["rows"]] == ["exact", "1000"]
    for row in result["rows"]:
        assert row["rmse_mean"] < 0.3 * CLIMATOLOGY_STD
    example = analog_lorenz63.reconstruction_example(M=10**4, methods=("anfb",), setting=SHORT_PROBLEM)
    assert example["estimates"]["AnFB"].shape == (200, 3)


def test_kernel_selection_uses_validation_problems_and_sorts():
    rows = analog_lorenz63.run_kernel_selection(
        2000, ks=(5,), sigma_scales=(0.5, 1.0), beam=200, n_problems=2,
        setting=analog_lorenz63.Lorenz63Setting(T=120, dt_obs=8)
    )
    assert [r["k"] for r in rows] == [5, 5] and sorted(r["sigma_scale"] for r in rows) == [0.5, 1.0]
    assert rows[0]["rmse_mean"] <= rows[1]["rmse_mean"]
    assert all(len(r["rmse"]) == 2 and np.isfinite(r["rmse_mean"]) for r in rows)
    # The validation streams are not the Table 1 test problems (seeds 0 .. 9).
    assert analog_lorenz63.VALIDATION_SEED >= 1000


def test_kernel_selection_with_incremental_rule_and_inflated_r():
    rows = analog_lorenz63.run_kernel_selection(
        2000, ks=(5,), sigma_scales=(0.5,), beam=200, n_problems=1,
        setting=analog_lorenz63.Lorenz63Setting(T=120, dt_obs=8), successor_rule="incremental", r_hmm_scales=(1.0, 2.0),
    )
    assert sorted(r["r_hmm_scale"] for r in rows) == [1.0, 2.0]
    assert all(r["successor_rule"] == "incremental" and r["rmse_mean"] < 0.5 * CLIMATOLOGY_STD for r in rows)


def test_error_anatomy_splits_the_squared_error():
    truth = np.zeros((40, 3))
    mean = np.zeros((40, 3))
    mean[5, 0] = 10.0  # one burst, between observations
    mean[10:20, 2] = 1.0
    obs = np.full((40, 1), np.nan)
    obs[::20, 0] = 0.0
    a = analog_lorenz63.error_anatomy(truth, obs, mean, std=np.ones((40, 3)))
    np.testing.assert_allclose(a["mse_per_variable"], [100 / 40, 0, 10 / 40])
    assert a["burst_fraction_steps"] == 1 / 40 and abs(a["burst_fraction_se"] - 100 / 110) < 1e-12
    assert a["rmse_by_phase"]["0"] == 0.0
    assert abs(a["coverage_2sd"] - (1 - 1 / 120)) < 1e-12
    assert abs(a["rmse"] ** 2 - np.mean(a["mse_per_variable"])) < 1e-12


def test_imu_runner_needs_the_data_root(tmp_path):
    with pytest.raises(ValueError, match="data_root"):
        analog_imu.prepare_split(tmp_path)
    with pytest.raises(ValueError, match="data_root"):
        analog_imu.run_imu_experiments(None)


def test_imu_observation_patterns():
    truth = np.zeros((1000, 6))
    obs, erased, var = analog_imu.make_observations(truth, "A", seed=0)
    assert erased.sum() == 3000 and var == 0.5
    np.testing.assert_array_equal(np.isnan(obs), erased)
    obs, erased, var = analog_imu.make_observations(truth, "B", seed=0)
    assert var == 0.1 and erased[100:300].all() and erased[600:700].all() and erased.sum() == 300 * 6
    pairs = analog_imu.lagged_pairs([np.arange(10.0)[:, None]], lag=2)
    np.testing.assert_array_equal(pairs[0][0], [1.0, 0.0])  # (x_t, x_{t-1})
    np.testing.assert_array_equal(pairs[1][0], [2.0, 1.0])


@pytest.fixture
def imu_split(shared_data):
    return analog_imu.prepare_split(
        shared_data / "pdr",
        test_trial="2017-12-15-17-59-19",
        catalog_trials=analog_imu.PYSHOE_WALKING_TRIALS[:3],
        n_samples=800,
    )


def test_imu_split_and_baselines_on_real_walk(imu_split):
    assert imu_split.test.shape == (800, 6) and imu_split.rate_hz == 50.0
    stacked = imu_split.catalog_states
    np.testing.assert_allclose(stacked.mean(axis=0), 0.0, atol=1e-9)
    np.testing.assert_allclose(stacked.std(axis=0), 1.0, atol=1e-9)
    result = analog_imu.run_imu_experiments(split=imu_split, methods=("nnn", "linear"))
    rmses = {(r["experiment"], r["method"]): r["rmse"] for r in result["rows"]}
    assert set(rmses) == {(e, m) for e in "AB" for m in ("NNN", "linear interpolation")}
    assert all(np.isfinite(v) and 0.0 < v < 3.0 for v in rmses.values())
    assert "| A | NNN |" in analog_imu.markdown_table(result)


def test_imu_anfb_on_real_walk(imu_split):
    result = analog_imu.run_imu_experiments(split=imu_split, methods=("anfb", "linear"), experiments=("A",))
    rmses = {r["method"]: r["rmse"] for r in result["rows"]}
    assert rmses["AnFB"] < 1.0  # standardised units; 50 % erased, noise variance 0.5
