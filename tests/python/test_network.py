"""network (paper 003): NA vs the RTS smoother on one simulated flight, cross-overs, bad input."""

import numpy as np
import pytest

from indoorloc import network
from indoorloc.simulate.flight import simulate_flight, small_config

MGAL = 1e-5


def _tiny():
    # About 80 s at 25 Hz: a couple of thousand epochs, solved in about a second.
    return small_config(line_length_m=800.0, turn_radius_m=150.0, cross_margin_m=150.0, imu_rate_hz=25.0,
                        anomaly_width_m=(400.0, 800.0))


@pytest.fixture(scope="module")
def solved():
    flight = simulate_flight(_tiny(), seed=3)
    opts = network.flight_options(flight.config)
    ssa, filtered, ssa_summary = network.smooth_flight(flight, opts, seed=3)
    na, na_summary, _ = network.solve_flight(flight, opts, xover=False, initial=ssa)
    nax, nax_summary, pairs = network.solve_flight(flight, opts, xover=True, initial=ssa)
    return dict(flight=flight, opts=opts, ssa=ssa, filtered=filtered, na=na, nax=nax, pairs=pairs,
                na_summary=na_summary, nax_summary=nax_summary, ssa_summary=ssa_summary)


def _rms(x):
    return float(np.sqrt(np.mean(np.square(x))))


def test_simulated_flight_has_crossovers_zupts_and_consistent_shapes():
    flight = simulate_flight(_tiny(), seed=3, noise=False)
    n = flight.n_epochs
    assert flight.acc_body_mps2.shape == (n, 3) and flight.gyro_body_radps.shape == (n, 3)
    assert np.all(np.diff(flight.imu_time_s) > 0)
    # Each of the 3 East-West lines crosses each of the 2 cross lines once (the transit to the
    # cross lines adds one more crossing over the end of a cross line).
    pairs = network.find_crossovers(flight.imu_time_s, flight.truth["position_m"], radius_m=5.0)
    lines = {tuple(sorted((int(flight.line_id[a]), int(flight.line_id[b])))) for a, b in pairs}
    assert {(k, c) for k in range(3) for c in (3, 4)} <= lines
    assert sum(1 for a, b in pairs if flight.line_id[a] >= 0 and flight.line_id[b] >= 0) == 6
    p = flight.truth["position_m"]
    assert np.all(np.linalg.norm(p[pairs[:, 0], :2] - p[pairs[:, 1], :2], axis=1) < 5.0)
    # Hovers: zero velocity, the IMU reads γ + δg + bias along body z.
    assert flight.zupt_epochs.size > 0
    assert np.abs(flight.truth["velocity_mps"][flight.zupt_epochs]).max() < 1e-9
    dg = flight.truth["gravity_disturbance_mps2"]
    assert 5 * MGAL < np.abs(dg).max() < 80 * MGAL


def test_na_without_xover_agrees_with_the_rts_smoother(solved):
    t = solved["flight"].truth
    na, ssa = solved["na"], solved["ssa"]
    assert solved["na_summary"]["termination"] == "converged"
    err_ssa = _rms(ssa["gravity_disturbance_mps2"] - t["gravity_disturbance_mps2"])
    diff = _rms(na["gravity_disturbance_mps2"] - ssa["gravity_disturbance_mps2"])
    # Same estimation problem (same model and weights; the EKF linearises once, the NA iterates):
    # the two estimates are much closer to each other than either is to the truth.
    assert diff < 0.35 * err_ssa, (diff / MGAL, err_ssa / MGAL)
    assert _rms(na["position_m"] - ssa["position_m"]) < 0.01
    assert _rms(na["velocity_mps"] - ssa["velocity_mps"]) < 0.005
    # Both beat the forward filter alone.
    err_filter = _rms(solved["filtered"]["gravity_disturbance_mps2"] - t["gravity_disturbance_mps2"])
    assert err_ssa < err_filter


def test_xover_ties_hold_in_the_network_solution(solved):
    pairs = solved["pairs"]
    assert pairs.shape[0] >= 6
    assert solved["nax_summary"]["num_xover"] == pairs.shape[0]
    dg_x = solved["nax"]["gravity_disturbance_mps2"]
    dg_0 = solved["na"]["gravity_disturbance_mps2"]
    misclosure_x = np.abs(dg_x[pairs[:, 0]] - dg_x[pairs[:, 1]])
    misclosure_0 = np.abs(dg_0[pairs[:, 0]] - dg_0[pairs[:, 1]])
    assert misclosure_x.mean() < 0.5 * misclosure_0.mean()


def _obs(flight):
    return dict(imu_time_s=flight.imu_time_s.copy(), acc_body_mps2=flight.acc_body_mps2.copy(),
                gyro_body_radps=flight.gyro_body_radps.copy(), gps_time_s=flight.gps_time_s.copy(),
                gps_position_m=flight.gps_position_m.copy(), zupt_epochs=flight.zupt_epochs,
                gupt_epochs=flight.gupt_epochs, gupt_gravity_mps2=flight.gupt_gravity_mps2)


@pytest.fixture(scope="module")
def small_problem():
    flight = simulate_flight(small_config(line_length_m=400.0, turn_radius_m=100.0, cross_margin_m=100.0,
                                          imu_rate_hz=10.0, gps_rate_hz=1.0), seed=1, noise=False)
    return flight, dict(flight.truth)


def _expect(match, flight, initial, options=None, **changes):
    kw = _obs(flight)
    kw.update(changes)
    with pytest.raises(ValueError, match=match):
        network.solve_network(network.NetworkObservations(**kw), initial, options=options or network.NetworkOptions())


def test_bad_input_names_the_argument(small_problem):
    flight, init = small_problem
    acc = flight.acc_body_mps2.copy()
    acc[7, 2] = np.nan
    _expect("'acc_body_mps2'.*NaN", flight, init, acc_body_mps2=acc)
    t = flight.imu_time_s.copy()
    t[10] = t[9]
    _expect("'imu_time_s'.*increasing", flight, init, imu_time_s=t)
    g = flight.gps_time_s.copy()
    g[-1] = flight.imu_time_s[-1] + 5.0
    _expect("'gps_time_s'.*outside the IMU span", flight, init, gps_time_s=g)
    _expect("'gupt_epochs'", flight, init, gupt_epochs=np.array([0.5]), gupt_gravity_mps2=np.array([9.8]))
    _expect("'xover_epochs'", flight, init, xover_epochs=np.array([[0, 10 ** 7]]))
    bad_init = {k: v for k, v in init.items() if k != "velocity_mps"}
    _expect("'initial'.*velocity_mps", flight, bad_init)
    o = network.NetworkOptions()
    o.sigma_gps_m = 0.0
    _expect("'options'.*sigma_gps_m", flight, init, options=o)
    with pytest.raises(ValueError, match="'discretization'"):
        o.discretization = "euler"


def test_datum_defects_are_reported_not_solved(small_problem):
    flight, init = small_problem
    _expect("'gps_position_m'.*datum defect", flight, init, gps_time_s=np.zeros(0), gps_position_m=np.zeros((0, 3)))
    # 1 Hz GPS on a 10 Hz IMU: every CUPT on an even epoch; leap-frog leaves the odd chain free.
    o = network.NetworkOptions()
    o.discretization = "leapfrog"
    _expect("'gps_time_s'.*datum defect.*odd-epoch chain", flight, init, options=o)


def test_kalman_smoother_rejects_bad_input(small_problem):
    flight, init = small_problem
    kw = _obs(flight)
    kw["gps_time_s"] = kw["gps_time_s"][::-1].copy()
    with pytest.raises(ValueError, match="'gps_time_s'"):
        network.kalman_smoother(network.NetworkObservations(**kw), {k: v[:1] for k, v in init.items()})


def test_observations_are_gathered_once_and_the_former_form_warns(small_problem):
    """solve_network and kalman_smoother take one NetworkObservations; the former call with the
    observation arrays as arguments (positional or keyword) still works for one release, warns,
    and gives the same state."""
    flight, init = small_problem
    kw = _obs(flight)
    observations = network.NetworkObservations(**kw)
    assert observations.num_imu_epochs == flight.imu_time_s.size and "GUPT" in repr(observations)
    start = {k: v[:1] for k, v in init.items()}
    model = network.flight_options(flight.config)
    smoothed, _, _ = network.kalman_smoother(observations, start, model=model)
    with pytest.warns(DeprecationWarning, match=r"kalman_smoother\(imu_time_s.*NetworkObservations"):
        old, _, _ = network.kalman_smoother(initial=start, model=model, **kw)
    assert all(np.array_equal(old[k], smoothed[k]) for k in smoothed)
    with pytest.warns(DeprecationWarning, match=r"solve_network\(imu_time_s"):
        positional, _ = network.solve_network(kw["imu_time_s"], kw["acc_body_mps2"], kw["gyro_body_radps"],
                                              kw["gps_time_s"], kw["gps_position_m"], smoothed, kw["zupt_epochs"],
                                              kw["gupt_epochs"], kw["gupt_gravity_mps2"], None, model)
    state, _ = network.solve_network(observations, smoothed, model)
    assert all(np.array_equal(positional[k], state[k]) for k in state)
    assert repr(network.flight_observations(flight)) == repr(observations)
    with pytest.raises(TypeError, match="incompatible constructor arguments"):  # gps_time_s, gps_position_m missing
        network.NetworkObservations(kw["imu_time_s"], kw["acc_body_mps2"], kw["gyro_body_radps"])
    with pytest.raises(TypeError, match="incompatible constructor arguments"):
        network.NetworkObservations(**kw, xover=None)


def test_normal_gravity_grs80():
    # GRS80: 9.7803267715 at the equator, 9.8321863685 at the poles; -0.3086 mGal/m.
    assert network.normal_gravity(0.0, [0.0])[0] == pytest.approx(9.7803267715, abs=1e-9)
    assert network.normal_gravity(np.pi / 2, [0.0])[0] == pytest.approx(9.8321863685, abs=1e-8)
    g = network.normal_gravity(0.7, [0.0, 100.0])
    assert (g[1] - g[0]) / 100.0 == pytest.approx(-0.3086e-5, rel=2e-3)


def test_selected_covariances_shrink_at_crossovers():
    # 5 Hz keeps the problem small for ceres::Covariance (the dense reference is in the C++ tests).
    config = small_config(line_length_m=400.0, turn_radius_m=100.0, cross_margin_m=100.0, imu_rate_hz=5.0,
                          zupt_s=3.0, accel_s=5.0)
    flight = simulate_flight(config, seed=1)
    o = network.flight_options(config)
    o.gravity_covariance = "ceres"
    na, summary, _ = network.solve_flight(flight, o, xover=False)
    nax, summary_x, pairs = network.solve_flight(flight, o, xover=True)
    assert pairs.shape[0] >= 6
    sd, sd_x = na["gravity_disturbance_sd_mps2"], nax["gravity_disturbance_sd_mps2"]
    assert sd.shape == (flight.n_epochs,) and np.all(np.isfinite(sd)) and np.all(sd > 0)
    # A tie between two epochs adds information to both: their δg sd can only go down.
    at = pairs.ravel()
    assert np.all(sd_x[at] <= sd[at] * (1 + 1e-9))
    assert sd_x[at].mean() < 0.9 * sd[at].mean()
    assert summary["seconds_covariance"] > 0 and summary["variance_factor"] > 0
    o.gravity_covariance = "none"
    assert "gravity_disturbance_sd_mps2" not in network.solve_flight(flight, o, xover=False)[0]
    with pytest.raises(ValueError, match="'gravity_covariance'"):
        o.gravity_covariance = "full"


def test_gauss_markov_biases_na_agrees_with_the_smoother():
    # The first-order Gauss-Markov bias option, in both approaches: NA without XOVER and the RTS
    # smoother still solve the same problem (and differ from the random-walk solution).
    flight = simulate_flight(_tiny(), seed=4)
    rw = network.flight_options(flight.config)
    gm = network.flight_options(flight.config, acc_bias_correlation_time_s=20.0, gyro_bias_correlation_time_s=20.0)
    ssa, _, _ = network.smooth_flight(flight, gm, seed=4)
    na, summary, _ = network.solve_flight(flight, gm, xover=False, initial=ssa)
    na_rw, _, _ = network.solve_flight(flight, rw, xover=False, initial=ssa)
    assert summary["termination"] == "converged"
    t = flight.truth["gravity_disturbance_mps2"]
    err = _rms(ssa["gravity_disturbance_mps2"] - t)
    assert _rms(na["gravity_disturbance_mps2"] - ssa["gravity_disturbance_mps2"]) < 0.35 * err
    assert _rms(na["acc_bias_mps2"] - na_rw["acc_bias_mps2"]) > 1e-7
    bad = network.flight_options(flight.config, acc_bias_correlation_time_s=-1.0)
    assert "acc_bias_correlation_time_s" in bad.is_valid()
    with pytest.raises(ValueError, match="'options'.*acc_bias_correlation_time_s"):
        network.solve_flight(flight, bad, xover=False, initial=ssa)


# Slow parameters (paper §4): biases and δg once per IMU/GPS-rate-ratio epochs.
def test_slow_parameters_halve_the_unknowns_and_keep_the_gravity_estimate(solved):
    flight, t = solved["flight"], solved["flight"].truth
    stride = int(round(flight.config.imu_rate_hz / flight.config.gps_rate_hz))
    opts = network.flight_options(flight.config, slow_parameter_stride=stride)
    assert opts.slow_parameter_stride == stride
    slow, summary, pairs = network.solve_flight(flight, opts, xover=True, initial=solved["ssa"])
    n = flight.n_epochs
    m = -(-n // stride)
    assert summary["termination"] == "converged"
    assert summary["num_slow_nodes"] == m
    assert summary["num_parameters"] == 9 * n + 7 * m
    assert summary["num_parameters"] < 0.6 * solved["nax_summary"]["num_parameters"]
    dg = slow["gravity_disturbance_mps2"]
    assert dg.shape == (n,)
    assert np.all(dg[:stride] == dg[0]) and np.all(slow["acc_bias_mps2"][stride:2 * stride] == slow["acc_bias_mps2"][stride])
    # Cross-overs refer to the δg block of their epoch's interval: the ties still hold.
    assert summary["num_xover"] == pairs.shape[0]
    assert np.abs(dg[pairs[:, 0]] - dg[pairs[:, 1]]).mean() < 0.5 * np.abs(
        solved["na"]["gravity_disturbance_mps2"][pairs[:, 0]] - solved["na"]["gravity_disturbance_mps2"][pairs[:, 1]]).mean()
    err_fast = _rms(solved["nax"]["gravity_disturbance_mps2"] - t["gravity_disturbance_mps2"])
    err_slow = _rms(dg - t["gravity_disturbance_mps2"])
    assert err_slow < 1.3 * err_fast + 0.5 * MGAL, (err_slow / MGAL, err_fast / MGAL)


def test_vupt_and_sgupt(small_problem):
    flight, init = small_problem
    o = network.NetworkOptions()
    o.discretization = "trapezoidal"
    epochs = np.arange(20, flight.n_epochs - 20, 50)
    v0 = flight.truth["velocity_mps"][epochs]
    kw = _obs(flight)
    observations = network.NetworkObservations(**kw, vupt_epochs=epochs, vupt_velocity_mps=v0,
                                               vupt_sd_mps=np.full(epochs.size, 1e-3))
    state, summary = network.solve_network(observations, init, options=o)
    assert summary["num_vupt"] == epochs.size
    # SGUPT over the hovers (ZUPT epochs): δg constant over each static period.
    z = flight.zupt_epochs
    state, summary = network.solve_network(network.NetworkObservations(**kw, sgupt_epochs=z), init, options=o)
    runs = np.split(z, np.flatnonzero(np.diff(z) > 1) + 1)
    assert summary["num_sgupt"] == z.size - len(runs)
    for run in runs:
        dg = state["gravity_disturbance_mps2"][run]
        assert dg.max() - dg.min() < 0.05 * MGAL


def test_bad_vupt_sgupt_and_slow_input_names_the_argument(small_problem):
    flight, init = small_problem
    n = flight.n_epochs
    _expect("'vupt_epochs'", flight, init, vupt_epochs=np.array([n]), vupt_velocity_mps=np.zeros((1, 3)))
    _expect("'vupt_velocity_mps'", flight, init, vupt_epochs=np.array([3]))
    _expect("'vupt_velocity_mps'.*NaN", flight, init, vupt_epochs=np.array([3]),
            vupt_velocity_mps=np.full((1, 3), np.nan))
    _expect("'vupt_sd_mps'", flight, init, vupt_epochs=np.array([3]), vupt_velocity_mps=np.zeros((1, 3)),
            vupt_sd_mps=np.array([0.0]))
    moving = int(np.flatnonzero(np.linalg.norm(flight.truth["velocity_mps"], axis=1) > 1.0)[0])
    _expect("'sgupt_epochs'.*not static", flight, init, sgupt_epochs=np.array([moving]))
    o = network.NetworkOptions()
    o.slow_parameter_stride = 0
    _expect("'options'.*slow_parameter_stride", flight, init, options=o)
    o = network.NetworkOptions()
    o.sigma_vupt_mps = -1.0
    _expect("'options'.*sigma_vupt_mps", flight, init, options=o)


def test_reproduce_adds_slow_rows():
    from indoorloc.experiments import network_reproduce as nr

    res = nr.reproduce(_tiny(), runs=1, seed=3, slow_stride=0)
    assert res["slow_stride"] == 25
    assert set(nr.slow_methods(25)) <= set(res["methods"])
    text = nr.markdown(res)
    assert "NA + XOVER, slow s=25" in text and "9 N + 7 M" in text
    assert res["info"]["unknowns_slow"][0] < 0.6 * res["info"]["unknowns"][0]


def test_kalman_smoother_refuses_absurd_times_instead_of_returning_nan(small_problem):
    flight, init = small_problem
    kw = _obs(flight)
    for times in (kw["imu_time_s"] + 1e300, kw["imu_time_s"] * 1e6):
        bad = dict(kw, imu_time_s=times, gps_time_s=times[:: max(1, len(times) // max(1, len(kw["gps_time_s"])))][
            :len(kw["gps_time_s"])])
        with pytest.raises(ValueError, match="'imu_time_s'"):
            network.kalman_smoother(network.NetworkObservations(**bad), {k: v[:1] for k, v in init.items()})
