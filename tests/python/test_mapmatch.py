"""Python side of mapmatch: network, simulator, filter, Monte Carlo, errors, determinism."""

import numpy as np
import pytest

from indoorloc import mapmatch
from indoorloc.io.road_network import grid_with_diagonals_segments


def test_warehouse_network_and_queries():
    net = mapmatch.warehouse_network()
    assert net.num_segments == 26 and net.num_components == 1
    assert net.dangling_ends.shape == (0, 2)
    assert net.total_length_m == pytest.approx(321.0)
    seg, proj, dist, along = net.nearest(np.array([[1.0, 0.3], [55.4, 20.0]]))
    np.testing.assert_allclose(dist, [0.3, 0.4])
    assert all(0 <= s < 26 for s in seg)
    for s, e in [(0, 1), (13, 0)]:
        for t, entered in net.continuations(s, e):
            np.testing.assert_allclose(net.point_at(t, 0 if entered == 0 else net.lengths_m[t]),
                                       net.point_at(s, 0 if e == 0 else net.lengths_m[s]), atol=1e-9)


def test_filter_run_shapes_and_network_membership():
    seg, ids = grid_with_diagonals_segments()
    net = mapmatch.RoadNetwork(seg, ids)
    traj = mapmatch.simulate_trajectory(net, mapmatch.TrajectoryOptions(duration_s=30, dt_s=0.1), seed=2)
    T = len(traj["speed_mps"])
    assert traj["positions_m"].shape == (T, 2)
    pf = mapmatch.ParticleMapMatcher(net, mapmatch.FilterOptions(num_particles=2000, kappa=1.0))
    out = pf.run(traj["speed_mps"], traj["heading_rad"], 0.1)
    assert out["positions_m"].shape == (T, 2) and out["segments"].shape == (T,)
    assert np.all(net.nearest(out["positions_m"])[2] < 1e-9)  # estimates lie on the network
    assert np.all(np.isfinite(out["log_likelihood"])) and np.all(out["ess"] >= 1)
    s, d, u = pf.particle_states()
    assert np.all((u >= 0) & (u <= net.lengths_m[s])) and set(np.unique(d)) <= {-1, 1}
    assert pf.segment_posterior().sum() == pytest.approx(1.0)
    assert pf.particle_weights().sum() == pytest.approx(1.0)


def test_monte_carlo_is_deterministic_across_thread_counts():
    net = mapmatch.warehouse_network()
    traj = mapmatch.TrajectoryOptions(duration_s=20.0, dt_s=0.5)
    f = mapmatch.FilterOptions(num_particles=500)
    a = mapmatch.monte_carlo(net, traj, f, n_runs=4, seed=7, n_threads=1)
    b = mapmatch.monte_carlo(net, traj, f, n_runs=4, seed=7, n_threads=2)
    np.testing.assert_array_equal(a["error_m"], b["error_m"])
    np.testing.assert_array_equal(a["correct_segment"], b["correct_segment"])


@pytest.mark.parametrize(
    "build, message",
    [
        (lambda: mapmatch.RoadNetwork(np.zeros((0, 4))), "empty"),
        (lambda: mapmatch.RoadNetwork(np.array([[0.0, 0, 0, 0]])), "zero length"),
        (lambda: mapmatch.RoadNetwork(np.array([[0.0, 0, 1, np.nan]])), "NaN"),
        (lambda: mapmatch.RoadNetwork(np.zeros((2, 3))), r"expected shape \(any, 4\)"),
        (lambda: mapmatch.FilterOptions(num_particles=0), "num_particles must be >= 1"),
        (lambda: mapmatch.FilterOptions(junction_policy="smart"), "junction_policy"),
        (lambda: mapmatch.TrajectoryOptions(dt_s=-1.0), "dt_s"),
    ],
)
def test_bad_input_raises_value_error(build, message):
    with pytest.raises(ValueError, match=message):
        build()


def test_bad_measurements_raise_value_error():
    net = mapmatch.warehouse_network()
    pf = mapmatch.ParticleMapMatcher(net, mapmatch.FilterOptions(num_particles=10))
    with pytest.raises(ValueError, match="speed_mps"):
        pf.run(np.array([1.0, np.nan]), np.zeros(2), 0.1)
    with pytest.raises(ValueError, match="heading_rad"):
        pf.run(np.ones(2), np.array([0.0, np.nan]), 0.1)
    with pytest.raises(ValueError, match="dt_s"):
        pf.run(np.ones(2), np.zeros(2), -0.1)
    with pytest.raises(ValueError, match="heading_rad"):
        pf.run(np.ones(3), np.zeros(2), 0.1)
