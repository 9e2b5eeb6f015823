"""Python side of mapmatch: network, simulator, filter, Monte Carlo, errors, determinism."""

from pathlib import Path

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


# --- indoorloc reproduce, paper 000 section (experiments/mapmatch_reproduce_tables.py) ---------


def _quick_tables(tmp_path, scheduler=None):
    from indoorloc.experiments import mapmatch_reproduce_tables as mrt
    from indoorloc.experiments.reproduce_cells import ReproduceContext

    lines = []
    ctx = ReproduceContext(out_dir=tmp_path, runs=2, threads=1, seed=3, scheduler=scheduler, log=lines.append)
    return mrt.reproduce_tables(ctx, duration_s=20.0, num_particles=500), lines


def test_reproduce_tables_quick_every_cell_present_and_finite(tmp_path):
    from indoorloc.experiments import mapmatch_reproduce as mr
    from indoorloc.experiments import mapmatch_reproduce_tables as mrt

    tables, lines = _quick_tables(tmp_path)
    assert [t.name for t in tables] == ["Table I", "Table II", "Figs. 3-4"]
    columns = {f"κ_P = {k:g}" for k in mr.KAPPAS}
    for table, per_filter in zip(tables, (1, 1, 4)):
        assert table.paper == "000" and table.setup
        assert len(table.cells) == len(mrt.VARIANTS) * len(mr.KAPPAS) * per_filter
        assert {c.column for c in table.cells} == columns
        for cell in table.cells:
            assert cell.seeds == [0, 1] and len(cell.values) == 2
            assert np.all(np.isfinite(cell.values)), (table.name, cell.row, cell.column)
            summary = cell.summary()
            assert summary["runs"] == 2 and summary["mean"] is not None
    table1 = {(c.row, c.column): c for c in tables[0].cells}
    assert table1[(mrt.VARIANTS["paper"], "κ_P = 1")].paper == 3.3
    assert all(v >= 0 for c in tables[0].cells for v in c.values)
    assert all(0 <= v <= 1 for c in tables[1].cells for v in c.values)
    assert len(tables[2].figures) == 2 and all(Path(f).is_file() for f in tables[2].figures)
    assert len(lines) == len(mrt.VARIANTS) * len(mr.KAPPAS)  # one line per finished part
    assert mrt.expected_seconds(2) < mrt.expected_seconds(None)


def test_reproduce_tables_same_result_through_the_scheduler(tmp_path):
    pytest.importorskip("distributed", reason="the sweep layer needs the sweep extra (dask[distributed])")
    from distributed import Client

    local, _ = _quick_tables(tmp_path / "local")
    with Client(processes=False, n_workers=1, threads_per_worker=2, dashboard_address=None) as client:
        remote, lines = _quick_tables(tmp_path / "dask", scheduler=client)
    assert len(lines) == 2 * 5 + 1  # one line per filter and κ_P, one for the sweep
    for a, b in zip(local, remote):
        assert [(c.row, c.column, c.seeds) for c in a.cells] == [(c.row, c.column, c.seeds) for c in b.cells]
        for ca, cb in zip(a.cells, b.cells):
            np.testing.assert_array_equal(ca.values, cb.values)


def test_settle_time_is_the_last_epoch_above_the_threshold():
    from indoorloc.experiments.mapmatch_reproduce_tables import settle_time_s

    t = np.arange(1, 6, dtype=float)
    err = np.array([[5, 3, 1, 1, 1], [1, 1, 1, 1, 1], [5, 1, 3, 1, 4.0]])
    np.testing.assert_array_equal(settle_time_s(err, t), [2.0, 0.0, 5.0])  # never -> duration


_SIMD_SCRIPT = """
import sys, numpy as np
from indoorloc import mapmatch
net = mapmatch.warehouse_network()
traj = mapmatch.simulate_trajectory(net, mapmatch.TrajectoryOptions(duration_s=60.0, dt_s=0.5), seed=4)
out = []
for kw in ({}, {"junction_policy": "heading_aware"}, {"estimate_speed_bias": True, "smoothing_lag_steps": 3}):
    f = mapmatch.ParticleMapMatcher(net, mapmatch.FilterOptions(num_particles=1001, seed=2, **kw))
    r = f.run(traj["speed_mps"], traj["heading_rad"], 0.5)
    out += [np.asarray(r[k], dtype=float).ravel() for k in sorted(r)]
np.save(sys.argv[1], np.concatenate(out))
"""


def test_filter_gives_the_same_numbers_with_and_without_avx2(tmp_path):
    """The AVX2 loops (random lanes, in-segment move, weights and sums) and their portable versions
    perform the same operations in the same order: bit-identical results (same seed, any machine).
    1001 particles: whole groups of four and a remainder."""
    from simd_check import outputs_with_and_without_avx2

    results = outputs_with_and_without_avx2(_SIMD_SCRIPT, tmp_path, mapmatch.__file__)
    assert results[0].size > 1000
    np.testing.assert_array_equal(results[0], results[1])
