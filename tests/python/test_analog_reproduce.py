"""Paper 001's `indoorloc reproduce` section on small sizes, the AnDA-style generator, the HMM prior."""

import math

import numpy as np
import pytest

from indoorloc import analog
from indoorloc.experiments import analog_reproduce as ar
from indoorloc.experiments.reproduce_cells import ReproduceContext
from indoorloc.registry import default_pdr_root
from indoorloc.simulate import lorenz63_anda

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def _check_cells(table, runs):
    assert table.cells, table.name
    for cell in table.cells:
        assert len(cell.values) == runs and len(cell.seeds) == runs, (table.name, cell.row, cell.column)
        assert all(math.isfinite(v) for v in cell.values), (table.name, cell.row, cell.column, cell.values)
        summary = cell.summary()
        assert summary["runs"] == runs and summary["mean"] is not None


@pytest.mark.skipif(not default_pdr_root().is_dir(), reason="the IMU recordings (shared/data/pdr) are not here")
def test_reproduce_tables_quick_has_every_cell(tmp_path):
    lines = []
    ctx = ReproduceContext(out_dir=tmp_path, runs=2, seed=0, log=lines.append)
    tables = ar.reproduce_tables(ctx, quick=True)
    names = [t.name for t in tables]
    assert names == ["Table 1", "Table 1 (time)", "Fig. 2", "AnDA-style sequence", "IMU missing data (Table 2 analog)"]
    by_name = {t.name: t for t in tables}
    for name in ("Table 1", "Table 1 (time)", "Fig. 2"):
        _check_cells(by_name[name], 2)
        assert by_name[name].setup
    _check_cells(by_name["AnDA-style sequence"], 1)
    _check_cells(by_name["IMU missing data (Table 2 analog)"], 2)
    # Every method / catalog-size cell of the paper's Table 1, with each AnFB variant as its own row.
    sizes = ar.Scale.quick().catalog_sizes
    cells = {(c.row, c.column) for c in by_name["Table 1"].cells}
    assert ("EnKS (Lorenz-63 equations, 100 members)", "-") in cells
    for M in sizes:
        col = f"M = {M}"
        assert ("AnEnKS (100 members)", col) in cells
        for v in ar.ANFB_VARIANTS:
            assert (v.label, col) in cells
    assert len(cells) == 1 + len(sizes) * (1 + len(ar.ANFB_VARIANTS))
    enks = next(c for c in by_name["Table 1"].cells if c.row.startswith("EnKS"))
    assert enks.paper == pytest.approx(3.7799) and enks.seeds == [0, 1]
    ratio = [c for c in by_name["IMU missing data (Table 2 analog)"].cells if c.row.startswith("AnFB / AnEnKS")]
    assert len(ratio) == 2 and all(c.paper is not None for c in ratio)
    # The figure is written and named in the tables; one progress line per part.
    assert (tmp_path / "analog_fig2.png").is_file()
    assert str(tmp_path / "analog_fig2.png") in by_name["Fig. 2"].figures
    assert len(lines) == 3 and all(" s)" in line for line in lines)


def test_table1_realisation_is_deterministic_and_seeded_by_its_index():
    settings = ar._settings(ar.Scale.quick(), seed=3)
    a = ar.table1_realisation(1, settings)
    b = ar.table1_realisation(1, settings)
    assert a["seed"] == 4
    for key, row in a["rows"].items():
        assert row["rmse"] == b["rows"][key]["rmse"], key
    c = ar.table1_realisation(0, settings)
    assert c["rows"]["EnKS|-"]["rmse"] != a["rows"]["EnKS|-"]["rmse"]


def test_sweep_path_gives_the_in_process_realisations(tmp_path):
    distributed = pytest.importorskip("distributed", reason="the sweep layer needs dask[distributed]")
    settings = ar._settings(ar.Scale.quick(), seed=0)
    local = ar.run_realisations(ReproduceContext(out_dir=tmp_path, runs=2, log=lambda s: None), 2, settings)
    with distributed.Client(processes=False, n_workers=1, threads_per_worker=2, dashboard_address=None) as client:
        ctx = ReproduceContext(out_dir=tmp_path, runs=2, scheduler=client, log=lambda s: None)
        remote = ar.run_realisations(ctx, 2, settings)
    assert [p["r"] for p in remote] == [0, 1]
    for lp, rp in zip(local, remote):
        assert lp["seed"] == rp["seed"]
        for key, row in lp["rows"].items():
            assert row["rmse"] == rp["rows"][key]["rmse"], key


def test_expected_seconds_grows_with_runs():
    assert 0 < ar.expected_seconds(2) < ar.expected_seconds(50) == ar.expected_seconds(None)


def test_reproduce_tables_rejects_zero_runs(tmp_path):
    with pytest.raises(ValueError, match="runs"):
        ar.reproduce_tables(ReproduceContext(out_dir=tmp_path, runs=0), quick=True)


def test_anda_generator_follows_the_published_settings():
    p = lorenz63_anda.anda_problem(nb_loop_test=2, nb_loop_train=3, dt_obs=40)
    assert p.truth.shape == (200, 3) and p.catalog.shape == (300, 3)
    t_obs = np.flatnonzero(np.isfinite(p.observations[:, 0]))
    assert list(t_obs) == [0, 40, 80, 120, 160]
    # Noise: the legacy stream of np.random.seed(1), drawn (T, 3) at once; x keeps column 0.
    eps = np.random.RandomState(1).multivariate_normal(np.zeros(3), 2.0 * np.eye(3), 200)
    np.testing.assert_allclose(p.observations[t_obs, 0] - p.truth[t_obs, 0], eps[t_obs, 0], rtol=0, atol=1e-12)
    assert eps[0, 0] == pytest.approx(np.sqrt(2.0) * 1.6243453636632417)
    # The catalog continues the test run; the test run starts after 5 time units from (8, 0, 30).
    np.testing.assert_allclose(p.catalog[0], p.truth[-1], rtol=0, atol=1e-12)
    assert not np.allclose(p.truth[0], lorenz63_anda.ANDA_X0)
    with pytest.raises(ValueError, match="nb_loop_train"):
        lorenz63_anda.anda_problem(nb_loop_train=0)


def test_anda_prior_weights():
    states = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [100.0, 0.0, 0.0]])
    w = lorenz63_anda.anda_prior_weights(states, [0.9, 0.0, 0.0], variance=0.1)
    assert w.argmax() == 1 and w[1] == 1.0 and w[2] == 0.0
    assert w[0] == pytest.approx(np.exp(-(0.81 - 0.01) / 0.2))
    with pytest.raises(ValueError, match="variance"):
        lorenz63_anda.anda_prior_weights(states, [0, 0, 0], variance=0.0)
    with pytest.raises(ValueError, match="states"):
        lorenz63_anda.anda_prior_weights(states[:, :2], [0, 0, 0])


def test_smooth_initial_prior_is_used_and_checked():
    a = 0.1 * np.arange(400)
    cat = analog.Catalog([np.c_[np.cos(a), np.sin(a)]], lag=1, stride=1)
    hmm = analog.AnalogHMM(cat, k=6, observed=[0], R=np.array([[0.01]]))
    obs = np.full((10, 1), np.nan)
    obs[0, 0] = 0.5  # two phases, y = +-0.87, equally likely under a uniform prior
    states = np.asarray(cat.states)
    uniform = hmm.smooth(obs)
    explicit = hmm.smooth(obs, initial=np.ones(cat.num_states))
    np.testing.assert_allclose(uniform["mean"], explicit["mean"], rtol=0, atol=1e-12)
    upper = hmm.smooth(obs, initial=(states[:, 1] > 0).astype(float))
    assert upper["filtering_mean"][0, 1] == pytest.approx(np.sqrt(0.75), abs=0.1)
    with pytest.raises(ValueError, match="initial"):
        hmm.smooth(obs, initial=np.ones(3))
    with pytest.raises(ValueError, match="initial"):
        hmm.smooth(obs, initial=-np.ones(cat.num_states))
