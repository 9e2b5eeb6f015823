"""The entry points probed by property_harness.py, one group per subsystem (issue 17).

Run as ``python property_cases.py <group>`` (the tests/python/test_properties_*.py tests do so
in a child process). Each Case is a valid call; the harness spoils one argument at a time.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from property_cases_fusion import group_fusion  # noqa: E402
from property_cases_io import group_io  # noqa: E402
from property_harness import Case, main, probe, same_for_threads  # noqa: E402


def _still_imu(n: int = 120):
    rng = np.random.default_rng(0)
    acc = np.tile([0.0, 0.0, 9.81], (n, 1)) + 0.01 * rng.normal(size=(n, 3))
    gyro = 0.001 * rng.normal(size=(n, 3))
    t = np.arange(n) / 100.0
    return t, acc, gyro


def group_core() -> None:
    from indoorloc import core

    lw = np.log(np.array([0.1, 0.2, 0.3, 0.4]))
    rs = core.RandomStream(1)
    probe(Case("RandomStream", core.RandomStream, {"seed": 1, "stream": 0}))
    probe(Case("RandomStream.uniform", rs.uniform, {"size": 5}, long_work_ok=True))
    probe(Case("RandomStream.normal", rs.normal, {"size": 5}, long_work_ok=True))
    # Up to 4 GB of draws is allowed work: it must stop on Ctrl-C (the alarm) instead.
    probe(Case("RandomStream.von_mises", rs.von_mises, {"mu_rad": 0.5, "kappa": 2.0, "size": 5},
               long_work_ok=True))
    probe(Case("RandomStream.integers", rs.integers, {"n": 10, "size": 5}, long_work_ok=True))
    probe(Case("derive_seed", core.derive_seed, {"seed": 1, "stream": 2}))
    probe(Case("log_sum_exp", core.log_sum_exp, {"log_weights": lw}, minus_inf_ok=True))
    # A -inf log-weight is a zero weight and stays -inf once normalised (documented).
    probe(Case("normalize_log_weights", core.normalize_log_weights, {"log_weights": lw}, minus_inf_ok=True))
    probe(Case("effective_sample_size", core.effective_sample_size, {"log_weights": lw}))
    probe(Case("resample", core.resample,
               {"log_weights": lw, "scheme": "systematic", "rng": 3, "num_out": -1}))
    probe(Case("offspring_counts", core.offspring_counts,
               {"log_weights": lw, "scheme": "residual", "n_runs": 20, "seed": 0, "n_threads": 1},
               long_work_ok=True))
    probe(Case("resample_if_needed", core.resample_if_needed,
               {"log_weights": lw, "options": core.ResamplingOptions(), "rng": 0}, minus_inf_ok=True,
               options_fields={"options": (core.ResamplingOptions, ["ess_threshold", "scheme"])}))
    same_for_threads("offspring_counts", lambda n: core.offspring_counts(
        lw, "systematic", n_runs=50, seed=3, n_threads=n))


def group_pdr() -> None:
    from indoorloc import pdr

    t, acc, gyro = _still_imu()
    stance = np.ones(t.size, bool)
    # Each function's settings are one Options object (options=): its fields are spoiled one at a time.
    shoe = {"options": pdr.ShoeOptions(), "acc_mps2": acc, "gyro_radps": gyro}
    probe(Case("shoe_statistic", pdr.shoe_statistic, shoe,
               options_fields={"options": (pdr.ShoeOptions, ["window", "sigma_acc_mps2", "gravity_mps2"])}))
    probe(Case("shoe_detector", pdr.shoe_detector, shoe,
               options_fields={"options": (pdr.ShoeOptions, ["window", "threshold"])}))
    probe(Case("zupt_ekf", pdr.zupt_ekf, {"time_s": t, "acc_mps2": acc, "gyro_radps": gyro, "stance": stance,
                                          "options": pdr.ZuptEkfOptions()},
               options_fields={"options": (pdr.ZuptEkfOptions, ["sigma_acc_mps2", "sigma_zupt_mps", "gravity_mps2",
                                                                "init_samples"])}))
    probe(Case("steps_acceleration", pdr.steps_acceleration,
               {"acc_mps2": acc, "rate_hz": 100.0, "options": pdr.AccelerationStepOptions()},
               options_fields={"options": (pdr.AccelerationStepOptions, ["window_s"])}))
    probe(Case("steps_gyro", pdr.steps_gyro, {"gyro_radps": gyro, "rate_hz": 100.0, "options": pdr.GyroStepOptions()},
               options_fields={"options": (pdr.GyroStepOptions, ["threshold_radps"])}))
    probe(Case("butterworth_sos", pdr.butterworth_sos, {"order": 4, "cutoff_hz": 3.0, "rate_hz": 100.0}))
    sos = pdr.butterworth_sos(4, 3.0, 100.0)
    probe(Case("sos_filter", pdr.sos_filter, {"sos": sos, "x": acc[:, 2].copy(), "steady_state_start": True}))
    intervals = np.array([[10, 40], [40, 80]])
    probe(Case("weinberg_features", pdr.weinberg_features, {"acc_mps2": acc, "rate_hz": 100.0,
                                                            "intervals": intervals, "options": pdr.WeinbergOptions()},
               options_fields={"options": (pdr.WeinbergOptions, ["filter_order", "cutoff_hz"])}))
    probe(Case("weinberg_stride_lengths", pdr.weinberg_stride_lengths,
               {"acc_mps2": acc, "rate_hz": 100.0, "step_indices": np.array([20, 60, 100]),
                "options": pdr.WeinbergOptions()},
               options_fields={"options": (pdr.WeinbergOptions, ["k"])}))
    feats = np.array([1.0, 1.2, 0.9])
    probe(Case("calibrate_weinberg_k", pdr.calibrate_weinberg_k, {"features": feats,
                                                                  "lengths_m": np.array([0.7, 0.8, 0.6])}))
    probe(Case("calibrate_weinberg_k_from_distance", pdr.calibrate_weinberg_k_from_distance,
               {"features": feats, "distance_m": 2.1}))
    mag = np.tile([20.0, 0.0, -40.0], (t.size, 1))
    probe(Case("steps_magnetometer", pdr.steps_magnetometer, {"mag": mag, "rate_hz": 100.0}))
    probe(Case("attitude_mahony", pdr.attitude_mahony, {"time_s": t, "acc_mps2": acc, "gyro_radps": gyro,
                                                        "options": pdr.MahonyOptions()},
               options_fields={"options": (pdr.MahonyOptions, ["kp", "ki", "gravity_mps2"])}))
    quats = np.tile([1.0, 0.0, 0.0, 0.0], (t.size, 1))
    probe(Case("stance_headings", pdr.stance_headings, {"quaternions_wxyz": quats,
                                                        "step_indices": np.array([10, 50, 90])}))
    probe(Case("positions_from_strides", pdr.positions_from_strides,
               {"stride_lengths_m": np.array([0.7, 0.7, 0.8]), "headings_rad": np.array([0.0, 0.1, 0.2]),
                "start_xy": np.array([0.0, 0.0]), "options": pdr.StepCovarianceOptions()},
               options_fields={"options": (pdr.StepCovarianceOptions, ["sigma_stride_length_m"])}))
    probe(Case("positions_from_increments", pdr.positions_from_increments,
               {"increments_m": np.array([[0.7, 0.0], [0.7, 0.1]]), "start_xy": np.array([1.0, 2.0])}))
    probe(Case("ins_zupt_increments", pdr.ins_zupt_increments,
               {"time_s": t, "acc_mps2": acc, "quaternions_wxyz": quats, "step_indices": np.array([10, 50, 90]),
                "options": pdr.InsZuptOptions()},
               options_fields={"options": (pdr.InsZuptOptions, ["window_s", "gravity_mps2"])}))
    _handheld_cases()


def _handheld_cases() -> None:
    """The hand-held phone PDR (issue 28: internal names 'x' and 'rate_hz' leaked, a walk without
    steps raised numpy's reshape error). Results are dataclasses: probed as dicts of arrays."""
    from dataclasses import asdict

    from indoorloc.pdr import handheld as ph

    n = 400
    t = np.arange(n) / 50.0
    acc = np.tile([0.0, 0.0, 9.81], (n, 1))
    acc[:, 2] += 2.5 * np.sin(2 * np.pi * 1.8 * t) * (t > 1.0)
    gyro = np.zeros((n, 3))
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))

    def steps_of(t_s, acc_mps2, gyro_radps, quat_xyzw):
        return asdict(ph.handheld_steps(ph.HandheldArrays(t_s, acc_mps2, gyro_radps, quat_xyzw)))

    probe(Case("handheld_steps", steps_of, {"t_s": t, "acc_mps2": acc, "gyro_radps": gyro, "quat_xyzw": quat},
               nan_outputs=("options",)))
    steps = ph.handheld_steps(ph.HandheldArrays(t, acc, gyro, quat))
    probe(Case("pdr_track", ph.pdr_track, {"steps": steps, "start_xy_m": np.array([1.0, 2.0]),
                                           "t_query": np.array([1.0, 3.0, 7.0]), "heading": "gyro",
                                           "yaw_offset_rad": 0.1}, vary=["start_xy_m", "t_query", "heading",
                                                                         "yaw_offset_rad"]))
    probe(Case("vertical_acceleration", ph.vertical_acceleration, {"acc_mps2": acc, "quat_xyzw": quat}))
    probe(Case("gyro_heading", ph.gyro_heading, {"t_s": t, "gyro_radps": gyro, "quat_xyzw": quat}))
    h = np.zeros(n)
    probe(Case("complementary_heading", ph.complementary_heading,
               {"t_s": t, "heading_rv_rad": h, "heading_gyro_rad": h + 0.1, "tau_s": 10.0}))
    probe(Case("rotation_vector_heading", ph.rotation_vector_heading, {"quat_xyzw": quat}))
    wt = np.array([1.0, 4.0, 7.0])
    probe(Case("waypoint_intervals", lambda steps, waypoint_t_s, waypoint_xy_m: asdict(
        ph.waypoint_intervals(steps, waypoint_t_s, waypoint_xy_m)),
        {"steps": steps, "waypoint_t_s": wt, "waypoint_xy_m": np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]])},
        vary=["waypoint_t_s", "waypoint_xy_m"]))


def _network():
    from indoorloc import mapmatch
    from indoorloc.io import grid_with_diagonals_segments

    seg, ids = grid_with_diagonals_segments(3, 2, 10.0)
    return mapmatch.RoadNetwork(seg, ids)


def group_mapmatch() -> None:
    from indoorloc import mapmatch
    from indoorloc.io import grid_with_diagonals_segments, read_geojson_segments, write_geojson_segments  # noqa

    seg, ids = grid_with_diagonals_segments(3, 2, 10.0)
    probe(Case("RoadNetwork", mapmatch.RoadNetwork, {"segments_m": seg, "ids": ids, "snap_tolerance_m": 1e-6}))
    net = mapmatch.RoadNetwork(seg, ids)
    probe(Case("RoadNetwork.nearest", net.nearest, {"points_m": np.array([[1.0, 2.0], [15.0, 3.0]])}))
    probe(Case("RoadNetwork.point_at", net.point_at, {"segment": 1, "along_m": 2.5}))
    probe(Case("RoadNetwork.continuations", net.continuations, {"segment": 1, "end": 1}))
    probe(Case("grid_with_diagonals_segments", grid_with_diagonals_segments,
               {"nx": 3, "ny": 2, "spacing_m": 10.0}))
    topts = mapmatch.TrajectoryOptions(duration_s=5.0, dt_s=0.5)
    probe(Case("simulate_trajectory", mapmatch.simulate_trajectory,
               {"network": net, "options": topts, "seed": 1, "stream": 0},
               options_fields={"options": (lambda: mapmatch.TrajectoryOptions(duration_s=5.0, dt_s=0.5),
                                           ["duration_s", "dt_s", "speed_mps", "speed_noise_sd_mps",
                                            "speed_bias_halfwidth_mps", "heading_kappa"])}))
    fopts = mapmatch.FilterOptions(num_particles=50)
    probe(Case("FilterOptions", mapmatch.FilterOptions, {"num_particles": 50, "kappa": 1.0,
                                                         "noise_halfwidth_m": 0.6, "junction_kappa": 2.0,
                                                         "ess_threshold": 0.5}))
    pf = mapmatch.ParticleMapMatcher(net, fopts)
    probe(Case("ParticleMapMatcher.step", pf.step, {"speed_mps": 1.0, "heading_rad": 0.0, "dt_s": 0.5},
               nan_outputs=("smoothed_m",)))
    probe(Case("ParticleMapMatcher.run", pf.run, {"speed_mps": np.ones(4), "heading_rad": np.zeros(4),
                                                  "dt_s": 0.5}, nan_outputs=("smoothed_m",)))
    n = 50
    probe(Case("ParticleMapMatcher.set_particles", pf.set_particles,
               {"segments": np.zeros(n, np.int64), "directions": np.ones(n, np.int64),
                "along_m": np.full(n, 1.0)}))
    probe(Case("monte_carlo", mapmatch.monte_carlo,
               {"network": net, "trajectory": mapmatch.TrajectoryOptions(duration_s=3.0, dt_s=0.5),
                "filter": fopts, "n_runs": 2, "seed": 0, "n_threads": 1},
               vary=["trajectory", "filter", "n_runs", "seed", "n_threads"],
               nan_outputs=("smoothed_error_m",),
               options_fields={
                   "trajectory": (lambda: mapmatch.TrajectoryOptions(duration_s=3.0, dt_s=0.5),
                                  ["duration_s", "dt_s", "speed_mps", "heading_kappa"]),
                   "filter": (lambda: mapmatch.FilterOptions(num_particles=50),
                              ["num_particles", "kappa", "noise_halfwidth_m", "recovery_disagreement",
                               "smoothing_lag_steps"])},
               long_work_ok=True))
    same_for_threads("monte_carlo", lambda k: mapmatch.monte_carlo(
        net, mapmatch.TrajectoryOptions(duration_s=5.0, dt_s=0.5), fopts, n_runs=3, seed=4, n_threads=k))


def group_network() -> None:
    from indoorloc import network

    n = 60
    t = np.arange(n) * 1.0
    pos = np.c_[np.cos(t / 5) * 20, np.sin(t / 5) * 20, np.zeros(n)]
    probe(Case("find_crossovers", network.find_crossovers,
               {"time_s": t, "position_m": pos, "radius_m": 5.0, "max_height_difference_m": 50.0,
                "min_separation_s": 10.0}))
    probe(Case("normal_gravity", network.normal_gravity, {"latitude_rad": 0.8, "height_m": np.array([0.0, 100.0])}))
    probe(Case("earth_rate_enu", network.earth_rate_enu, {"latitude_rad": 0.8}))
    probe(Case("solve_folded_linear_ins_network", network.solve_folded_linear_ins_network,
               {"imu_rate_hz": 10.0, "duration_s": 20.0, "gps_rate_hz": 1.0, "num_ties": 10, "num_gupts": 2,
                "sigma_xover_mps2": 1e-5, "sigma_gupt_mps2": 1e-5, "num_threads": 1},
               long_work_ok=True, solver=True, examples=12))
    from indoorloc.simulate.flight import simulate_flight, small_config

    flight = simulate_flight(small_config(line_length_m=400.0, turn_radius_m=100.0, cross_margin_m=100.0,
                                          imu_rate_hz=10.0, gps_rate_hz=1.0), seed=1, noise=False)
    init = dict(flight.truth)
    probe(Case("solve_network", lambda initial, options, **observations: network.solve_network(
                   network.NetworkObservations(**observations), initial, options),
               {"imu_time_s": flight.imu_time_s, "acc_body_mps2": flight.acc_body_mps2,
                "gyro_body_radps": flight.gyro_body_radps, "gps_time_s": flight.gps_time_s,
                "gps_position_m": flight.gps_position_m, "initial": init,
                "options": network.flight_options(flight.config, max_iterations=3)},
               vary=["acc_body_mps2", "gyro_body_radps", "gps_time_s", "gps_position_m", "options"],
               options_fields={"options": (lambda: network.flight_options(flight.config, max_iterations=3),
                                           ["sigma_gps_m", "acc_noise_mps2_rthz", "latitude_rad",
                                            "slow_parameter_stride", "max_iterations", "num_threads"])},
               long_work_ok=True, solver=True, examples=12))

    # The state-space baseline and the flight helpers (issue 17, second pass).
    obs = dict(imu_time_s=flight.imu_time_s, acc_body_mps2=flight.acc_body_mps2,
               gyro_body_radps=flight.gyro_body_radps, gps_time_s=flight.gps_time_s,
               gps_position_m=flight.gps_position_m, zupt_epochs=flight.zupt_epochs,
               gupt_epochs=flight.gupt_epochs, gupt_gravity_mps2=flight.gupt_gravity_mps2, xover_epochs=None)
    start = network.start_state(flight, 0)
    probe(Case("kalman_smoother", lambda initial, model, options, **observations: network.kalman_smoother(
                   network.NetworkObservations(**observations), initial, model, options),
               {**obs, "initial": start, "model": network.flight_options(flight.config),
                "options": network.KalmanSmootherOptions()},
               vary=["acc_body_mps2", "gyro_body_radps", "gps_time_s", "gps_position_m", "zupt_epochs",
                     "gupt_epochs", "gupt_gravity_mps2", "xover_epochs", "initial", "model", "options"],
               options_fields={
                   "options": (network.KalmanSmootherOptions,
                               ["init_sigma_position_m", "init_sigma_velocity_mps", "init_sigma_level_rad",
                                "init_sigma_heading_rad", "init_sigma_acc_bias_mps2",
                                "init_sigma_gyro_bias_radps", "init_sigma_gravity_mps2"]),
                   "model": (lambda: network.flight_options(flight.config),
                             ["acc_noise_mps2_rthz", "gyro_noise_radps_rthz", "sigma_gps_m", "latitude_rad",
                              "gravity_walk_mps2_rts", "acc_bias_correlation_time_s"])},
               long_work_ok=True, solver=True, examples=8))
    probe(Case("start_state", network.start_state,
               {"flight": flight, "seed": 0, "level_sd_rad": 1e-3, "heading_sd_rad": 1e-2}))
    probe(Case("flight_options", lambda **kw: network.flight_options(flight.config, **kw).is_valid(),
               {"discretization": "trapezoidal", "sigma_gps_m": 0.1, "max_iterations": 3}))
    probe(Case("smooth_flight", lambda **kw: network.smooth_flight(flight, **kw)[0],
               {"options": network.flight_options(flight.config), "seed": 0, "smooth": True,
                "kalman_options": network.KalmanSmootherOptions()},
               options_fields={"kalman_options": (network.KalmanSmootherOptions,
                                                  ["init_sigma_position_m", "init_sigma_heading_rad"])},
               long_work_ok=True, solver=True, examples=6))
    probe(Case("solve_flight", lambda **kw: network.solve_flight(flight, **kw)[0],
               {"options": network.flight_options(flight.config, max_iterations=2), "xover": True, "seed": 0,
                "initial": None, "crossover_radius_m": 5.0, "min_separation_s": 30.0, "sgupt": False},
               long_work_ok=True, solver=True, examples=6))
    probe(Case("solve_repeated_pass_network", network.solve_repeated_pass_network,
               {"imu_rate_hz": 10.0, "duration_s": 20.0, "gps_rate_hz": 1.0, "num_ties": 10, "num_gupts": 2,
                "sigma_xover_mps2": 1e-5, "sigma_gupt_mps2": 1e-5, "rule": "leapfrog", "checkpoint_interval": 4,
                "keep_gravity_estimate": True, "num_threads": 1},
               long_work_ok=True, solver=True, examples=10))
    from indoorloc._core import network as cn

    def small(**fields):
        return cn.LinearInsNetworkOptions(**{"imu_rate_hz": 10.0, "duration_s": 20.0, "gps_rate_hz": 1.0, **fields})

    network_fields = {"network": (small, ["imu_rate_hz", "duration_s", "gps_rate_hz", "rule", "prior_epochs",
                                          "sigma_gps_m", "sigma_prior"])}
    probe(Case("solve_linear_ins_network", cn.solve_linear_ins_network,
               {"network": small(), "gravity_covariance": True, "checkpoint_interval": 0,
                "keep_gravity_estimate": True, "num_threads": 1},
               options_fields=network_fields, long_work_ok=True, solver=True, examples=10))
    probe(Case("solve_linear_ins_network_with_crossovers", cn.solve_linear_ins_network_with_crossovers,
               {"network": small(duration_s=60.0), "lines": 3, "cross_lines": 3, "sigma_xover_mps2": 1e-5,
                "max_iterations": 200, "relative_tolerance": 1e-8},
               options_fields={"network": (lambda: small(duration_s=60.0), network_fields["network"][1])},
               long_work_ok=True, solver=True, examples=10))
    probe(Case("solve_linear_ins_network_ceres", cn.solve_linear_ins_network_ceres,
               {"network": small(), "one_gauss_newton_step": True},
               options_fields=network_fields, long_work_ok=True, solver=True, examples=10))
    probe(Case("linear_ins_equations", cn.linear_ins_equations, {"network": small()},
               options_fields=network_fields, long_work_ok=True, examples=10))
    probe(Case("linear_ins_normal_blocks", cn.linear_ins_normal_blocks, {"network": small()},
               options_fields=network_fields, long_work_ok=True, examples=10))


def group_analog() -> None:
    from indoorloc import analog

    rng = np.random.default_rng(1)
    m, k, steps = 4, 2, 5
    nxt = np.array([rng.choice(m, size=k, replace=False) for _ in range(m)])
    prob = rng.uniform(0.2, 1, size=(m, k))
    prob /= prob.sum(axis=1, keepdims=True)
    log_b = -rng.uniform(0, 10, size=(steps, m))
    init = np.ones(m)
    base = {"next_idx": nxt, "prob": prob, "log_emission": log_b, "initial": init, "beam": None}
    probe(Case("forward_backward", analog.forward_backward, dict(base)))
    probe(Case("viterbi", analog.viterbi, dict(base)))
    a = 0.1 * np.arange(200)
    traj = np.c_[np.cos(a), np.sin(a)]
    probe(Case("Catalog", analog.Catalog, {"trajectories": [traj], "lag": 1, "stride": 1}))
    cat = analog.Catalog([traj], lag=1)
    probe(Case("Catalog.knn", cat.knn, {"queries": np.array([[1.0, 0.0]]), "k": 3}))
    probe(Case("AnalogHMM", analog.AnalogHMM, {"catalog": cat, "k": 5, "observed": [0],
                                               "R": np.array([[0.01]]), "sigma_scale": 1.0}))
    hmm = analog.AnalogHMM(cat, k=5, observed=[0], R=np.array([[0.01]]))
    obs = np.c_[np.cos(0.1 * np.arange(20))]
    probe(Case("AnalogHMM.smooth", hmm.smooth, {"observations": obs, "beam": 50, "max_dropped_mass": 1.0}))
    probe(Case("AnalogHMM.viterbi", hmm.viterbi, {"observations": obs, "beam": 50}))


def _lattice():
    pos = np.array([[x, y] for x in np.arange(0, 11, 2.0) for y in np.arange(0, 11, 2.0)])
    aps = np.array([[-1, -1], [11, -1], [-1, 11], [11, 11]])
    d = np.linalg.norm(pos[:, None, :] - aps[None], axis=2)
    return pos, -40 - 20 * np.log10(d + 0.5), 4 + 0.3 * d


def group_wifi() -> None:
    from indoorloc import wifi

    pos, mean, var = _lattice()
    floors = np.zeros(pos.shape[0])
    probe(Case("SignalMap", wifi.SignalMap, {"positions_m": pos, "floors": floors, "mean_dbm": mean,
                                             "variance_db2": var}))
    smap = wifi.SignalMap(pos, floors, mean, var)
    scans = mean[:3] + 1.0
    probe(Case("SignalMap.from_scans", wifi.SignalMap.from_scans,
               {"scan_positions_m": np.repeat(pos[:3], 4, axis=0), "scan_floors": None,
                "rss_dbm": np.repeat(mean[:3], 4, axis=0)}))
    probe(Case("SignalMap.prepare_scans", smap.prepare_scans, {"rss_dbm": scans, "not_heard_sentinel": 100.0,
                                                               "not_heard_dbm": -105.0}))
    probe(Case("DelaunayInterpolator", wifi.DelaunayInterpolator, {"positions_m": pos, "fields": mean}))
    interp = wifi.DelaunayInterpolator(pos, mean)
    q = np.array([[1.0, 1.0], [5.0, 3.0]])
    probe(Case("DelaunayInterpolator.interpolate", interp.interpolate, {"queries_m": q, "num_threads": 1}))
    probe(Case("DelaunayInterpolator.sibson", interp.sibson, {"queries_m": q}))
    probe(Case("DelaunayInterpolator.clamp_to_hull", interp.clamp_to_hull, {"z_m": np.array([20.0, 3.0])}))
    model = wifi.RssModel(smap)
    probe(Case("RssModel.evaluate", model.evaluate, {"rss_dbm": scans, "z_m": np.array([3.0, 3.0]), "floor": 0}))
    probe(Case("RssModel.neg_log_likelihood_at", model.neg_log_likelihood_at,
               {"rss_dbm": scans, "points_m": q, "floor": 0}))
    probe(Case("RssModel.mean_and_variance", model.mean_and_variance, {"points_m": q, "floor": 0}))
    probe(Case("RssModel.fisher_information", model.fisher_information, {"points_m": q, "floor": 0}))
    probe(Case("RssModel.simulate_scans", model.simulate_scans, {"points_m": q, "floor": 0, "seed": 1}))
    probe(Case("RssModel.interpolator", model.interpolator, {"floor_index": 0}))
    gp = wifi.GridPosterior(model, spacing_m=1.0)
    probe(Case("GridPosterior", wifi.GridPosterior, {"model": model, "spacing_m": 1.0,
                                                     "max_points_per_floor": 2000}))
    probe(Case("GridPosterior.grid", gp.grid, {"floor_index": 0}))
    probe(Case("GridPosterior.locate", gp.locate, {"rss_dbm": scans, "group_size": 1, "num_threads": 1}))
    probe(Case("locate_ml", wifi.locate_ml, {"model": model, "rss_dbm": scans, "group_size": 1,
                                             "num_threads": 1}))
    tracker = wifi.GradientTracker(model)
    probe(Case("GradientTracker.update", tracker.update, {"rss_dbm": scans[0]}))
    probe(Case("GradientTracker.track", tracker.track, {"rss_dbm": scans}))
    probe(Case("GradientTracker.reset_to", tracker.reset_to, {"position_m": np.array([3.0, 3.0]), "floor": 0}))
    probe(Case("FingerprintLocator", wifi.FingerprintLocator,
               {"reference_rss_dbm": mean, "reference_positions_m": pos, "reference_floors": floors,
                "method": "wknn", "k": 4}))
    loc = wifi.FingerprintLocator(mean, pos, floors)
    probe(Case("FingerprintLocator.locate", loc.locate, {"scans_dbm": scans, "num_threads": 1}))
    probe(Case("tracker_options", lambda **kw: wifi.tracker_options(**kw),
               {"max_step_m": 1.0, "iterations_per_scan": 1, "num_starts": 5, "tolerance_m": 1e-4}))
    same_for_threads("GridPosterior.locate", lambda k: gp.locate(np.repeat(scans, 4, axis=0), num_threads=k))


def group_metrics() -> None:
    from indoorloc import io as iio
    from indoorloc import metrics

    est = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 0.5]])
    truth = np.array([[0.1, 0.0], [1.0, 1.2], [2.0, 0.0]])
    probe(Case("position_errors", metrics.position_errors, {"estimated_m": est, "truth_m": truth}))
    errs = np.array([0.1, 0.2, 0.5, 1.0])
    probe(Case("error_stats", lambda errors_m: metrics.error_stats(errors_m).__dict__, {"errors_m": errs}))
    probe(Case("empirical_cdf", metrics.empirical_cdf, {"errors_m": errs}))
    probe(Case("bootstrap_interval", metrics.bootstrap_interval,
               {"values": errs, "n_boot": 200, "level": 0.95, "seed": 0}))
    probe(Case("lonlat_to_local", iio.lonlat_to_local,
               {"lon_lat_deg": np.array([[2.17, 41.38], [2.171, 41.381]]), "origin_lon_lat": (2.17, 41.38)}))
    probe(Case("local_to_lonlat", iio.local_to_lonlat,
               {"east_north_m": np.array([[10.0, 20.0]]), "origin_lon_lat": (2.17, 41.38)}))
    probe(Case("metres_per_degree", iio.metres_per_degree, {"lat_deg": 41.38}))
    rng = np.random.default_rng(0)
    acc = np.tile([0.0, 0.0, 9.81], (50, 1)) + 0.1 * rng.normal(size=(50, 3))
    gyro = 0.5 * rng.normal(size=(50, 3))
    probe(Case("check_imu_units", iio.check_imu_units, {"acc_mps2": acc, "gyro_radps": gyro}))
    seg, ids = iio.grid_with_diagonals_segments(2, 2, 5.0)
    import tempfile
    out = Path(tempfile.mkdtemp(prefix="indoorloc_write_")) / "roads.geojson"
    probe(Case("write_geojson_segments", iio.write_geojson_segments,
               {"path": str(out), "segments_m": seg, "ids": ids}))


GROUPS = {
    "metrics": group_metrics,
    "io": group_io,
    "core": group_core,
    "pdr": group_pdr,
    "mapmatch": group_mapmatch,
    "network": group_network,
    "analog": group_analog,
    "wifi": group_wifi,
    "fusion": group_fusion,
}

if __name__ == "__main__":
    sys.exit(main(GROUPS))
