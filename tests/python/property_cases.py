"""The entry points probed by property_harness.py, one group per subsystem (issue 17).

Run as ``python property_cases.py <group>`` (the tests/python/test_properties_*.py tests do so
in a child process). Each Case is a valid call; the harness spoils one argument at a time.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

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
    probe(Case("shoe_statistic", pdr.shoe_statistic, {"acc_mps2": acc, "gyro_radps": gyro, "window": 5,
                                                      "sigma_acc_mps2": 0.01, "gravity_mps2": 9.81}))
    probe(Case("shoe_detector", pdr.shoe_detector, {"acc_mps2": acc, "gyro_radps": gyro, "window": 5,
                                                    "threshold": 3e4}))
    probe(Case("zupt_ekf", pdr.zupt_ekf, {"time_s": t, "acc_mps2": acc, "gyro_radps": gyro, "stance": stance,
                                          "sigma_acc_mps2": 0.5, "sigma_zupt_mps": 0.01, "gravity_mps2": 9.81,
                                          "init_samples": 20}))
    probe(Case("steps_acceleration", pdr.steps_acceleration, {"acc_mps2": acc, "rate_hz": 100.0,
                                                              "window_s": 0.1}))
    probe(Case("steps_gyro", pdr.steps_gyro, {"gyro_radps": gyro, "rate_hz": 100.0, "threshold_radps": 1.0}))
    probe(Case("butterworth_sos", pdr.butterworth_sos, {"order": 4, "cutoff_hz": 3.0, "rate_hz": 100.0}))
    sos = pdr.butterworth_sos(4, 3.0, 100.0)
    probe(Case("sos_filter", pdr.sos_filter, {"sos": sos, "x": acc[:, 2].copy(), "steady_state_start": True}))
    intervals = np.array([[10, 40], [40, 80]])
    probe(Case("weinberg_features", pdr.weinberg_features, {"acc_mps2": acc, "rate_hz": 100.0,
                                                            "intervals": intervals, "filter_order": 4,
                                                            "cutoff_hz": 3.0}))
    probe(Case("weinberg_stride_lengths", pdr.weinberg_stride_lengths,
               {"acc_mps2": acc, "rate_hz": 100.0, "step_indices": np.array([20, 60, 100]), "k": 0.364}))
    feats = np.array([1.0, 1.2, 0.9])
    probe(Case("calibrate_weinberg_k", pdr.calibrate_weinberg_k, {"features": feats,
                                                                  "lengths_m": np.array([0.7, 0.8, 0.6])}))
    probe(Case("calibrate_weinberg_k_from_distance", pdr.calibrate_weinberg_k_from_distance,
               {"features": feats, "distance_m": 2.1}))
    mag = np.tile([20.0, 0.0, -40.0], (t.size, 1))
    probe(Case("steps_magnetometer", pdr.steps_magnetometer, {"mag": mag, "rate_hz": 100.0}))
    probe(Case("attitude_mahony", pdr.attitude_mahony, {"time_s": t, "acc_mps2": acc, "gyro_radps": gyro,
                                                        "kp": 1.0, "ki": 0.05, "gravity_mps2": 9.81}))
    quats = np.tile([1.0, 0.0, 0.0, 0.0], (t.size, 1))
    probe(Case("stance_headings", pdr.stance_headings, {"quaternions_wxyz": quats,
                                                        "step_indices": np.array([10, 50, 90])}))
    probe(Case("positions_from_strides", pdr.positions_from_strides,
               {"stride_lengths_m": np.array([0.7, 0.7, 0.8]), "headings_rad": np.array([0.0, 0.1, 0.2]),
                "start_xy": np.array([0.0, 0.0]), "sigma_stride_length_m": 0.1}))
    probe(Case("positions_from_increments", pdr.positions_from_increments,
               {"increments_m": np.array([[0.7, 0.0], [0.7, 0.1]]), "start_xy": np.array([1.0, 2.0])}))
    probe(Case("ins_zupt_increments", pdr.ins_zupt_increments,
               {"time_s": t, "acc_mps2": acc, "quaternions_wxyz": quats, "step_indices": np.array([10, 50, 90]),
                "window_s": 0.05, "gravity_mps2": 9.81}))
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
    probe(Case("solve_network", network.solve_network,
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
    probe(Case("kalman_smoother", network.kalman_smoother,
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

    size = {"imu_rate_hz": 10.0, "duration_s": 20.0, "gps_rate_hz": 1.0, "rule": "leapfrog"}
    probe(Case("solve_linear_ins_network", cn.solve_linear_ins_network,
               {**size, "gravity_covariance": True, "checkpoint_interval": 0, "prior_epochs": 2,
                "keep_gravity_estimate": True, "num_threads": 1},
               long_work_ok=True, solver=True, examples=10))
    probe(Case("solve_linear_ins_network_with_crossovers", cn.solve_linear_ins_network_with_crossovers,
               {**size, "duration_s": 60.0, "lines": 3, "cross_lines": 3, "sigma_xover_mps2": 1e-5,
                "max_iterations": 200, "relative_tolerance": 1e-8},
               long_work_ok=True, solver=True, examples=10))
    probe(Case("solve_linear_ins_network_ceres", cn.solve_linear_ins_network_ceres,
               {**size, "prior_epochs": 2, "one_gauss_newton_step": True},
               long_work_ok=True, solver=True, examples=10))
    probe(Case("linear_ins_equations", cn.linear_ins_equations, {**size, "prior_epochs": 2},
               long_work_ok=True, examples=10))
    probe(Case("linear_ins_normal_blocks", cn.linear_ins_normal_blocks, {**size, "prior_epochs": 2},
               long_work_ok=True, examples=10))


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


# ---------------------------------------------------------------------------------------------
# Loader fuzzing: damaged bytes of valid files.


def _damage():
    """Ways a file gets damaged: truncation, flipped bytes, huge numbers, bad UTF-8, nesting."""
    from hypothesis import strategies as st

    return st.one_of(
        st.tuples(st.just("truncate"), st.floats(0.0, 1.0)),
        st.tuples(st.just("flip"), st.lists(st.tuples(st.floats(0.0, 1.0), st.integers(0, 255)),
                                            min_size=1, max_size=8)),
        st.tuples(st.just("insert"), st.tuples(st.floats(0.0, 1.0), st.sampled_from(
            [b"nan", b"inf", b"-inf", b"1e999", b"9" * 400, b"\xff\xfe\x00", b",", b"\n", b"\"", b"{",
             b"[" * 5000, b"-", b" ", b"\r\n\r\n", b"18446744073709551615", b"1e-400", b"0x10"]))),
        st.just(("empty", None)),
        st.binary(max_size=300).map(lambda b: ("random", b)),
    )


def _apply(valid: bytes, how) -> bytes:
    kind, arg = how
    if kind == "truncate":
        return valid[: int(arg * len(valid))]
    if kind == "flip":
        data = bytearray(valid)
        for where, byte in arg:
            data[min(int(where * len(data)), len(data) - 1)] = byte
        return bytes(data)
    if kind == "insert":
        where, text = arg
        k = int(where * len(valid))
        return valid[:k] + text + valid[k:]
    if kind == "empty":
        return b""
    return arg


def fuzz_file(name: str, load, folder: Path, damaged: str, arg_name: str = "path") -> None:
    """Damages `folder/damaged`, calls load(); it must return finite data or raise FormatError
    naming the damaged file (`arg_name` is the loader's parameter, for the record)."""
    from hypothesis import given

    from property_harness import TALLY, Case, call

    target = folder / damaged
    valid = target.read_bytes()
    load()  # the undamaged file loads

    # The "argument" spoiled is the file: an error message must name it.
    case = Case(name, lambda **kwargs: _load_as_format_error(load), {damaged: None})
    TALLY.cases += 1

    @given(how=_damage())
    def run(how) -> None:
        target.write_bytes(_apply(valid, how))
        try:
            call(case, damaged, how)
        finally:
            target.write_bytes(valid)

    run()


def _load_as_format_error(load):
    """``load()``, a ValueError that is not a FormatError turned into a RuntimeError: the library
    promises one type for damaged files."""
    from indoorloc.io import FormatError

    try:
        return load()
    except FormatError:
        raise
    except ValueError as exc:
        raise RuntimeError(f"ValueError that is not a FormatError: {exc}") from exc


def _bad_field_values():
    """What a damaged or foreign MAT file may hold where a numeric array belongs."""
    from hypothesis import strategies as st

    return st.sampled_from([
        ("nan", lambda v: np.full(np.shape(v), np.nan)), ("inf", lambda v: np.full(np.shape(v), np.inf)),
        ("1e300", lambda v: np.full(np.shape(v), 1e300)), ("empty", lambda v: np.zeros((0, 0))),
        ("scalar", lambda v: np.array(3.0)), ("string", lambda v: "text"),
        ("transposed", lambda v: np.asarray(v).T), ("flat", lambda v: np.asarray(v).reshape(-1)),
        ("one column", lambda v: np.asarray(v).reshape(np.shape(v)[0], -1)[:, :1] if np.ndim(v) else v),
        ("int64 huge", lambda v: np.full(np.shape(v), 2**62, dtype=np.int64)),
        ("complex", lambda v: np.asarray(v, dtype=float) + 1j), ("struct", lambda v: {"a": 1.0}),
        ("cell", lambda v: np.array([np.ones(2), "x"], dtype=object)),
        ("negative", lambda v: -np.abs(np.asarray(v, dtype=float)) - 1.0),
    ])


def fuzz_mat_fields(name: str, load, target: Path, build, paths) -> None:
    """Structural damage of a MATLAB file: one field at `paths` (tuples of keys into the dict
    `build()` returns) replaced by a bad value. The loader must return or raise FormatError
    naming the file."""
    from hypothesis import given
    from hypothesis import strategies as st
    from scipy.io import savemat

    from property_harness import TALLY, Case, call

    valid = target.read_bytes()
    load()

    case = Case(name, lambda **kwargs: _load_as_format_error(load), {target.name: None})
    TALLY.cases += 1

    @given(where=st.sampled_from(paths), how=_bad_field_values())
    def run(where, how) -> None:
        doc = build()
        node = doc
        for key in where[:-1]:
            node = node[key]
        try:
            node[where[-1]] = how[1](node[where[-1]])
        except (TypeError, ValueError):
            return  # this damage does not apply to that field (e.g. "negative" of a struct)
        try:
            savemat(target, doc)
        except Exception:
            return  # scipy cannot write it: no file to read
        try:
            call(case, target.name, None, shown=f"{'.'.join(where)}={how[0]}")
        finally:
            target.write_bytes(valid)

    run()


def _mobgap_doc(n: int = 300):
    rng = np.random.default_rng(3)
    t = np.arange(n) / 100.0
    acc_g = np.column_stack([1.0 + 0.2 * np.sin(2 * np.pi * t), 0.01 * rng.normal(size=n),
                             0.01 * rng.normal(size=n)])
    gyr = 20.0 * np.sin(2 * np.pi * t)[:, None] * np.ones((1, 3))
    lb = {"Acc": acc_g, "Gyr": gyr, "Mag": np.tile([10.0, -14.0, -13.0], (n, 1)),
          "Timestamp": 1.6e9 + t, "Fs": {"Acc": 100, "Gyr": 100, "Mag": 100}}
    wb = {"Start": 1.0, "End": 2.5, "InitialContact_Event": np.array([1.0, 1.5, 2.0, np.nan]),
          "Stride_InitialContacts": np.array([[100.0, 200.0], [150.0, 250.0], [200.0, np.nan]]),
          "Stride_Length": np.array([1.1, 1.2, 1.0])}
    trial = {"SU": {"LowerBack": lb}, "Standards": {"INDIP": {"MicroWB": wb, "Fs": 100}}}
    return {"data": {"TimeMeasure1": {"Test5": {"Trial1": trial}}}}


def _surimi_doc():
    macs = np.array([[-60, 100, -70], [-61, 100, -71], [100, -50, -80], [100, -51, 100]], np.int16)
    labels = np.array([[10.0, 20.0, 3.7, 1, 0], [10.0, 20.0, 3.7, 1, 0],
                       [10.0, 20.0, 3.7, 1, 0], [15.0, 25.0, 0.0, 0, 0]])
    return {"database": {"trainingMacs": macs, "testMacs": macs[:2].astype(float),
                         "trainingLabels": labels, "testLabels": labels[[1, 3]]}}


def _ilc_floor_summary(floor):
    """What opening a floor folder reads: its size, walks and the GeoJSON origin."""
    return {"n_walks": floor.n_walks, "size": np.asarray([floor.width_m or 0.0, floor.height_m or 0.0]),
            "origin": np.asarray(floor.origin_lonlat())}


def _records(value):
    """Loader output as plain containers, so that the harness sees every array (NaN checks)."""
    import dataclasses

    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _records(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, (list, tuple)):
        return [_records(v) for v in value]
    if isinstance(value, dict):
        return {k: _records(v) for k, v in value.items()}
    return value


def group_io() -> None:
    import tempfile

    from scipy.io import savemat

    from indoorloc import io as iio

    tmp = Path(tempfile.mkdtemp(prefix="indoorloc_fuzz_"))
    seg, ids = iio.grid_with_diagonals_segments(2, 2, 5.0)
    iio.write_geojson_segments(tmp / "roads.geojson", seg, ids)
    fuzz_file("read_geojson_segments", lambda: iio.read_geojson_segments(tmp / "roads.geojson"), tmp,
              "roads.geojson")
    (tmp / "roads.csv").write_text("id,x_a,y_a,x_b,y_b\n" + "".join(
        f"{i},{r[0]},{r[1]},{r[2]},{r[3]}\n" for i, r in zip(ids, seg)))
    fuzz_file("read_csv_segments", lambda: iio.read_csv_segments(tmp / "roads.csv"), tmp, "roads.csv")
    fuzz_file("load_road_network", lambda: iio.load_road_network(tmp / "roads.geojson"), tmp,
              "roads.geojson")

    rng = np.random.default_rng(0)
    n = 40
    t = np.arange(n) * 0.0025
    gyro = rng.normal(size=(n, 3)) * 50.0
    acc = np.tile([0.0, 0.0, 1.0], (n, 1)) + 0.3 * rng.normal(size=(n, 3))
    header = ("Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),"
              "Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)")
    np.savetxt(tmp / "walk.csv", np.column_stack([t, gyro, acc]), delimiter=",", header=header,
               comments="", fmt="%.9g")
    fuzz_file("load_xio", lambda: iio.load_xio(tmp / "walk.csv"), tmp, "walk.csv")
    np.savetxt(tmp / "OpenShoeDataSet.txt", np.column_stack([acc * 9.81, np.deg2rad(gyro)]),
               delimiter=",", fmt="%.8f")
    fuzz_file("load_openshoe", lambda: iio.load_openshoe(tmp / "OpenShoeDataSet.txt"), tmp,
              "OpenShoeDataSet.txt")
    m = 60
    ts = 0.005 + np.arange(m) * 0.005
    acc_p = np.tile([0.0, 0.0, -9.81], (m, 1)) + rng.normal(size=(m, 3))
    savemat(tmp / "trial.mat", {"imu_data": np.column_stack([acc_p, rng.normal(size=(m, 3))]),
                                "timestamps_all": ts[None, :],
                                "gt": np.column_stack([np.linspace(0, 3, m), np.zeros(m)]),
                                "strideIndex": np.array([[5, 25, 45]], dtype=np.int64),
                                "timestamps": ts[[5, 25, 45]][None, :]})
    fuzz_file("load_pyshoe_trial", lambda: iio.load_pyshoe_trial(tmp / "trial.mat"), tmp, "trial.mat")

    from test_wifi_io import write_office_room  # the RSS/RTT room fixture

    rooms = write_office_room(tmp / "rooms", "1,11,15", ["0.0,1.0,4000.0,4000.0,4000.0,-50.0,-60.0,-70.0,1 3",
                                                        "2.0,3.0,4000.0,4000.0,4000.0,-55.0,-65.0,-75.0,1"])
    for damaged in ("AP_position.txt", "database_office_train.csv"):
        fuzz_file(f"load_rss_rtt_room[{damaged}]", lambda: iio.load_rss_rtt_room(rooms, "office"), rooms,
                  damaged, arg_name="root")

    from indoorloc._core.fusion import FloorGeometry

    box = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 10.0], [0.0, 10.0]])
    geometry = FloorGeometry(floor=0, outlines=[box], obstacles=[box * 0.2 + 2.0],
                             walls=np.array([[5.0, 5.0, 8.0, 5.0]]))
    iio.write_geojson_floor(tmp / "plan.geojson", geometry)
    fuzz_file("read_geojson_floor", lambda: iio.read_geojson_floor(tmp / "plan.geojson"), tmp, "plan.geojson")

    from test_io_ilc2020 import _write_walk  # the ILC walk fixture

    _write_walk(tmp / "walk.txt", seed=1, n_epochs=10)
    fuzz_file("read_ilc_walk", lambda: iio.read_ilc_walk(tmp / "walk.txt"), tmp, "walk.txt")

    month = tmp / "uji" / "db" / "01"
    month.mkdir(parents=True)
    for stem, first in (("trn01", 101100101), ("tst01", 101200101)):
        (month / f"{stem}rss.csv").write_text("-60,100,-70\n-80,-50,100\n")
        (month / f"{stem}crd.csv").write_text("1.5,2.25,3\n4.0,2.25,3\n")
        (month / f"{stem}tms.csv").write_text("20160602155217232\n20160602155220732\n")
        (month / f"{stem}ids.csv").write_text(f"{first}\n{first + 1}\n")
    for damaged in ("trn01crd.csv", "trn01rss.csv", "tst01tms.csv"):
        fuzz_file(f"load_uji_library[{damaged}]", lambda: iio.load_uji_library(tmp / "uji"), month,
                  damaged, arg_name="root")

    # mobgap (lower-back IMU, MATLAB v5 structs): damaged bytes, then damaged fields.
    from scipy.io import savemat as _savemat

    subject = tmp / "mobgap" / "HA" / "009"
    subject.mkdir(parents=True)
    _savemat(subject / "data.mat", _mobgap_doc())
    load_mobgap = lambda: _records(iio.load_mobgap_trials(subject / "data.mat"))  # noqa: E731
    fuzz_file("load_mobgap_trials", load_mobgap, subject, "data.mat")
    trial = ("data", "TimeMeasure1", "Test5", "Trial1")
    lower_back = trial + ("SU", "LowerBack")
    bout = trial + ("Standards", "INDIP", "MicroWB")
    fuzz_mat_fields("load_mobgap_trials[fields]", load_mobgap, subject / "data.mat", _mobgap_doc,
                    [lower_back + (k,) for k in ("Acc", "Gyr", "Mag", "Timestamp", "Fs")]
                    + [lower_back + ("Fs", "Acc")]
                    + [bout + (k,) for k in ("Start", "End", "InitialContact_Event", "Stride_InitialContacts",
                                             "Stride_Length")]
                    + [bout[:-1], trial + ("SU",), trial, ("data", "TimeMeasure1")])
    fuzz_file("list_mobgap_files", lambda: [str(f) for f in iio.list_mobgap_files(tmp / "mobgap")], subject,
              "data.mat", arg_name="root")

    # SURIMI (.mat with struct database).
    surimi = tmp / "surimi"
    surimi.mkdir()
    _savemat(surimi / "LIB1.mat", _surimi_doc())
    load_lib1 = lambda: _records(iio.load_surimi(surimi, "LIB1"))  # noqa: E731
    fuzz_file("load_surimi", load_lib1, surimi, "LIB1.mat", arg_name="root")
    fuzz_mat_fields("load_surimi[fields]", load_lib1, surimi / "LIB1.mat", _surimi_doc,
                    [("database", k) for k in ("trainingMacs", "testMacs", "trainingLabels", "testLabels")]
                    + [("database",)])
    fuzz_file("load_wifi_dataset[surimi_LIB1]", lambda: _records(iio.load_wifi_dataset("surimi:LIB1", tmp)),
              surimi, "LIB1.mat", arg_name="root")

    # The competition's floor folder: its JSON files (the walks are fuzzed above).
    from test_io_ilc2020 import T0, _write_floor

    floor_dir = tmp / "site" / "F1"
    _write_floor(floor_dir, [1], [T0])
    for damaged in ("floor_info.json", "geojson_map.json"):
        fuzz_file(f"read_ilc_floor[{damaged}]", lambda: _ilc_floor_summary(iio.read_ilc_floor(floor_dir, cache=False)),
                  floor_dir, damaged, arg_name="floor_dir")
    fuzz_file("ilc_floor_origin_lonlat", lambda: iio.ilc_floor_origin_lonlat(floor_dir / "geojson_map.json"),
              floor_dir, "geojson_map.json")
    fuzz_file("read_ilc_site", lambda: iio.read_ilc_site(tmp / "site"), floor_dir, "geojson_map.json",
              arg_name="site_dir")


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


def _room():
    """A 20 x 10 m room with a block and a wall, a 4-AP signal map over it (test_fusion.py's)."""
    from indoorloc import fusion, wifi

    outline = np.array([[0, 0], [20, 0], [20, 10], [0, 10]], float)
    block = np.array([[8, 3], [12, 3], [12, 7], [8, 7]], float)
    walls = np.array([[16, 0, 16, 7]], float)
    geometry = fusion.FloorGeometry(0, [outline], [block], walls)
    xs, ys = np.meshgrid(np.arange(21.0), np.arange(11.0))
    pos = np.c_[xs.ravel(), ys.ravel()]
    aps = np.array([[0, 0], [20, 0], [0, 10], [20, 10]], float)
    mean = -40.0 - 25.0 * np.log10(np.linalg.norm(pos[:, None, :] - aps[None], axis=2) + 1.0)
    model = wifi.RssModel(wifi.SignalMap(pos, np.zeros(len(pos)), mean, np.full_like(mean, 4.0)))
    return geometry, fusion.FloorPlan([geometry]), model, outline, block, walls


# Every TrackerOptions field as the Python facade names it (flattened), with a valid value.
TRACKER_FIELDS = {
    "num_particles": 200, "heading_offset_walk_rad": 0.02, "scale_walk": 0.01, "min_scale": 0.5,
    "max_scale": 1.8, "position_noise_m": 0.3, "tempering": 0.1, "max_term": 8.0, "max_age_s": 4.0,
    "use_not_heard": True, "not_heard_dbm": -105.0, "resampling": "systematic", "ess_threshold": 0.5,
    "fix_outlier_probability": 0.1, "fix_tempering": 0.6, "wall_log_penalty": -20.0,
    "respread_after_blocked_steps": 3, "respread_sd_m": 3.0, "start_position_sd_m": 1.0,
    "start_heading_offset_sd_rad": 0.08, "start_scale_sd": 0.1, "unknown_start_heading_sd_rad": 1.0,
    "candidate_spacing_m": 1.0, "recovery_log_ratio": 6.0, "recovery_scans": 3, "recovery_fraction": 0.2,
    "floor_change_probability": 0.0, "corridor_kappa": 2.0, "smoothing_lag_steps": 0, "num_threads": 1,
    "seed": 0,
}


def group_fusion() -> None:
    from indoorloc import fusion
    from indoorloc.fusion import wifi_fixes
    from indoorloc import io as iio
    from indoorloc._core import fusion as cf

    geometry, plan, model, outline, block, walls = _room()
    probe(Case("FloorGeometry", fusion.FloorGeometry,
               {"floor": 0, "outlines": [outline], "obstacles": [block], "walls": walls}))
    probe(Case("FloorPlanOptions", fusion.FloorPlanOptions,
               {"cell_size_m": 0.5, "target_edges_per_cell": 2.0, "max_cells": 100000,
                "check_self_intersection": True}))
    probe(Case("FloorPlan", fusion.FloorPlan, {"floors": [geometry], "options": fusion.FloorPlanOptions()},
               options_fields={"options": (fusion.FloorPlanOptions,
                                           ["cell_size_m", "target_edges_per_cell", "max_cells"])}))
    # The rings inside a FloorGeometry: spoiled through the facade that builds it.
    probe(Case("floor_plan_from_polygons", fusion.floor_plan_from_polygons,
               {"outlines": outline, "obstacles": [block], "walls": walls, "floor": 2}))
    probe(Case("floor_geometry", fusion.floor_geometry,
               {"outlines": [outline], "obstacles": [block], "walls": walls, "floor": 1}))
    probe(Case("floor_plan_from_geometries", fusion.floor_plan_from_geometries,
               {"floors": [geometry], "options": None}))
    for name in ("floor_index",):
        probe(Case(f"FloorPlan.{name}", getattr(plan, name), {"floor": 0}))
    for name in ("geometry", "num_edges", "edges", "bounds", "walkable_area", "cell_size"):
        probe(Case(f"FloorPlan.{name}", getattr(plan, name), {"floor_index": 0}))
    pts = np.array([[1.0, 1.0], [10.0, 5.0], [18.0, 2.0]])
    for name, arg, value in (("is_walkable", "points_m", pts), ("distance_to_wall", "points_m", pts),
                             ("crosses_wall", "segments_m", np.array([[1.0, 1.0, 5.0, 1.0],
                                                                      [15.0, 2.0, 17.0, 2.0]]))):
        probe(Case(f"FloorPlan.{name}", getattr(plan, name), {arg: value, "floor_indices": 0, "num_threads": 1}))
    probe(Case("FloorPlan.sample_walkable", plan.sample_walkable, {"n": 5, "floor_index": 0, "rng": 1},
               long_work_ok=True))
    same_for_threads("FloorPlan.distance_to_wall", lambda k: plan.distance_to_wall(
        np.random.default_rng(0).uniform(0, 20, size=(500, 2)), 0, k))

    # GeoJSON: writing into a temporary folder (the probe's working directory is one too).
    import tempfile
    tmp = Path(tempfile.mkdtemp(prefix="indoorloc_fusion_"))
    probe(Case("write_geojson_floor", iio.write_geojson_floor,
               {"path": str(tmp / "plan.geojson"), "geometry": geometry, "origin_lon_lat": None}))
    probe(Case("floor_geometry_to_geojson", iio.floor_geometry_to_geojson,
               {"geometry": geometry, "origin_lon_lat": (2.17, 41.38)}))
    iio.write_geojson_floor(tmp / "plan.geojson", geometry)
    probe(Case("read_geojson_floor", lambda **kw: iio.read_geojson_floor(**kw).geometry,
               {"source": str(tmp / "plan.geojson"), "floor": 3, "roles": None, "origin_lon_lat": None}))
    probe(Case("load_floor_plan", iio.load_floor_plan,
               {"sources": [str(tmp / "plan.geojson")], "floors": [0], "roles": None, "origin_lon_lat": None,
                "options": None}))

    # Options: every field of TrackerOptions and SmootherOptions, through their constructors.
    probe(Case("tracker_options", lambda **kw: fusion.tracker_options(**kw), dict(TRACKER_FIELDS)))
    probe(Case("SmootherOptions", fusion.SmootherOptions,
               {"num_trajectories": 20, "max_particles": 500, "seed": 1, "num_threads": 1}))

    def options(**kw):
        return fusion.tracker_options(**{**TRACKER_FIELDS, **kw})

    fields = [k for k in TRACKER_FIELDS if k not in ("resampling", "use_not_heard")]
    probe(Case("ParticleTracker", cf.ParticleTracker,
               {"plan": plan, "wifi_model": model, "corridors": None, "options": options()},
               options_fields={"options": (options, fields)}, examples=12))

    # The tracker is stateful: every call gets a fresh, initialised one.
    def tracker():
        t = cf.ParticleTracker(plan, model, None, options())
        t.initialize_known(0.0, np.array([2.0, 1.5]), 0, 0.0)
        return t

    probe(Case("ParticleTracker.initialize_known",
               lambda **kw: cf.ParticleTracker(plan, model, None, options()).initialize_known(**kw),
               {"time_s": 0.0, "position_m": np.array([2.0, 1.5]), "floor": 0, "heading_offset_rad": 0.1}))
    obs = fusion.WifiObservation(1.0, [0, 1, 2, 3], [-60.0, -70.0, -65.0, -75.0])
    probe(Case("ParticleTracker.initialize_unknown",
               lambda **kw: cf.ParticleTracker(plan, model, None, options()).initialize_unknown(**kw),
               {"observation": obs}))
    probe(Case("ParticleTracker.step", lambda **kw: tracker().step(**kw),
               {"time_s": 0.5, "displacement_m": np.array([0.0, 0.7]), "covariance_m2": np.eye(2) * 0.01},
               nan_outputs=("lagged_m",)))
    probe(Case("ParticleTracker.wifi", lambda **kw: tracker().wifi(**kw), {"observation": obs},
               nan_outputs=("lagged_m",)))
    probe(Case("WifiObservation", fusion.WifiObservation,
               {"time_s": 1.0, "access_points": [0, 1], "rss_dbm": [-60.0, -70.0]}))
    probe(Case("ParticleTracker.fix", lambda **kw: tracker().fix(**kw),
               {"time_s": 1.0, "means_m": np.array([[2.0, 2.0], [5.0, 5.0]]), "sds_m": np.array([2.0, 3.0]),
                "weights": np.array([0.6, 0.4]), "floors": np.array([0, fusion.ANY_FLOOR])},
               nan_outputs=("lagged_m",)))
    states = np.tile([2.0, 1.5, 0.0, 1.0], (200, 1))
    probe(Case("ParticleTracker.set_particles", lambda **kw: tracker().set_particles(**kw),
               {"states": states, "floor_indices": np.zeros(200, np.int64)}))

    rss = np.array([[-60.0, np.nan, -65.0, -75.0], [-61.0, -70.0, np.nan, -74.0]])
    probe(Case("make_wifi_observations",
               lambda **kw: [(o.time_s, o.access_points, o.rss_dbm) for o in cf.make_wifi_observations(**kw)[0]],
               {"scan_times_s": np.array([1.0, 2.0]), "rss_dbm": rss, "ages_s": np.zeros((2, 4)),
                "options": options(), "at_own_time": True}))
    probe(Case("steps_from_polar", cf.steps_from_polar,
               {"lengths_m": np.array([0.7, 0.7]), "headings_rad": np.array([0.0, 1.0]),
                "length_sd_m": np.array([0.05, 0.05]), "heading_sd_rad": np.array([0.1, 0.1])}))
    probe(Case("Steps.from_polar", lambda **kw: fusion.Steps.from_polar(**kw).__dict__,
               {"times_s": np.array([0.5, 1.0]), "lengths_m": np.array([0.7, 0.7]),
                "headings_rad": np.array([0.0, 1.0]), "length_sd_m": 0.05, "heading_sd_rad": 0.1}))
    probe(Case("Steps.from_increments", lambda **kw: fusion.Steps.from_increments(**kw).__dict__,
               {"times_s": np.array([0.5, 1.0]), "increments_m": np.array([[0.7, 0.0], [0.0, 0.7]]),
                "covariances_m2": np.array([[0.01, 0.0, 0.01], [0.01, 0.0, 0.01]])}))
    probe(Case("rotate", fusion.rotate, {"displacements_m": np.array([[0.7, 0.0]]), "angle_rad": 0.5}))
    probe(Case("covariance_matrix", fusion.covariance_matrix, {"row": np.array([0.01, 0.0, 0.02])}))
    probe(Case("Fixes.from_arrays", lambda **kw: fusion.Fixes.from_arrays(**kw).as_arrays(),
               {"times_s": np.array([1.0, 2.0]), "means_m": np.array([[2.0, 2.0], [3.0, 2.0]]),
                "sds_m": np.array([2.0, 2.0]), "weights": np.ones((2, 1)), "floors": np.array([0, 0])}))

    # The batch API, with the smoother: spoiled one argument at a time.
    n = 8
    times = 0.5 * np.arange(1, n + 1)
    disp = np.tile([0.0, 0.7], (n, 1))
    cov = np.tile([0.01, 0.0, 0.01], (n, 1))
    fix_arrays = fusion.Fixes.from_arrays([1.0], [[2.0, 2.5]], [2.0]).as_arrays()
    start = {"position_m": np.array([2.0, 1.5]), "floor": 0, "heading_offset_rad": 0.0, "time_s": 0.0}
    smoother = fusion.SmootherOptions(num_trajectories=10, max_particles=100)
    track_kwargs = {"plan": plan, "wifi_model": model, "corridors": None, "step_times_s": times,
                    "displacements_m": disp, "covariances_m2": cov, "observations": [obs], "start": start,
                    "options": options(), "smoother": smoother, "fixes": fix_arrays}
    probe(Case("track", lambda **kw: _track_arrays(cf.track(**kw)), track_kwargs,
               vary=["step_times_s", "displacements_m", "covariances_m2", "observations", "start", "smoother",
                     "fixes"],
               nan_outputs=("lagged_m",), examples=15))
    probe(Case("track(start fields)", lambda **kw: _track_arrays(cf.track(**{**track_kwargs, "start": kw})),
               dict(start), examples=15, nan_outputs=("lagged_m",)))
    probe(Case("track(smoother)", lambda **kw: _track_arrays(cf.track(**kw)), track_kwargs, vary=["smoother"],
               options_fields={"smoother": (lambda: fusion.SmootherOptions(num_trajectories=10, max_particles=100),
                                            ["num_trajectories", "max_particles", "seed", "num_threads"])},
               nan_outputs=("lagged_m",), examples=15))
    steps = fusion.Steps(times, disp, cov)
    probe(Case("fusion.track", lambda **kw: _track_arrays(fusion.track(**kw)),
               {"steps": steps, "observations": [obs], "plan": plan, "wifi_model": model, "corridors": None,
                "start": start, "options": options(), "smoother": None,
                "fixes": fusion.Fixes.from_arrays([1.0], [[2.0, 2.5]], [2.0])},
               vary=["steps", "observations", "plan", "wifi_model", "corridors", "fixes"],
               nan_outputs=("lagged_m",), examples=15))
    same_for_threads("track", lambda k: _track_arrays(cf.track(
        **{**track_kwargs, "options": options(num_threads=k),
           "smoother": fusion.SmootherOptions(num_trajectories=10, max_particles=100, num_threads=k)})))

    # Fingerprint fixes (wifi_fixes): the settings and the dissimilarities.
    q = np.array([[-60.0, np.nan, -70.0], [-50.0, -80.0, np.nan]])
    db = np.array([[-61.0, -75.0, np.nan], [np.nan, -79.0, -71.0], [-55.0, -60.0, -65.0]])
    probe(Case("FixSettings", lambda **kw: wifi_fixes.FixSettings(**kw).validate(),
               {"fresh_age_s": 2.5, "min_scans": 3, "metric": "strongest", "strongest_n": 10,
                "not_heard_dbm": -100.0, "unshared_cost_db": 20.0, "k": 8, "temperature_db": 2.0, "sd_m": 4.0,
                "min_aps": 3}))
    # +inf is their documented "nothing heard in common": only NaN counts as silent.
    probe(Case("scan_dissimilarity", lambda **kw: _posinf_documented(wifi_fixes.scan_dissimilarity(**kw)),
               {"queries_dbm": q, "database_dbm": db, "unshared_cost_db": 20.0}))
    probe(Case("strongest_ap_dissimilarity",
               lambda **kw: _posinf_documented(wifi_fixes.strongest_ap_dissimilarity(**kw)),
               {"queries_dbm": q, "database_dbm": db, "n": 2, "not_heard_dbm": -100.0}))

    # The synthetic building and walk (seeded; small configurations).
    from indoorloc.simulate.building import BuildingConfig, make_building
    from indoorloc.simulate.walker import simulate_walk

    def building(seed, **config):
        b = make_building(seed, BuildingConfig(**config))
        return b.geometry(0).outlines
    probe(Case("make_building", building,
               {"seed": 1, "width_m": 40.0, "depth_m": 30.0, "num_floors": 1, "corridor_width_m": 2.5,
                "num_branches": 2, "rooms_per_side": 6, "door_width_m": 1.0, "num_pillars": 2}, examples=6))
    b = make_building(1, BuildingConfig(width_m=40.0, depth_m=30.0, num_branches=2, rooms_per_side=6))
    probe(Case("simulate_walk", lambda **kw: simulate_walk(b, **kw).route_points_m, {"seed": 1, "floor": 0},
               examples=6))


def _posinf_documented(d):
    """A dissimilarity with its documented +inf entries (no AP in common) set to 0."""
    return np.where(np.isposinf(d), 0.0, d)


def _track_arrays(result):
    """The arrays of a track result (the summary object and timings left out)."""
    return {k: v for k, v in result.items() if isinstance(v, np.ndarray)}


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
