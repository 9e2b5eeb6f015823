"""indoorloc.sweep on Dask: the same results in-process and on a LocalCluster with two worker
processes, seeds from the task keys, failed tasks reported, interrupted sweeps resumed."""

import json

import numpy as np
import pytest

pytest.importorskip("distributed", reason="the sweep layer needs the sweep extra (dask[distributed])")

from distributed import Client, LocalCluster  # noqa: E402

from indoorloc import sweep  # noqa: E402
from indoorloc.experiments import sweep_tasks as st  # noqa: E402

MAPMATCH_GRID = {"kappa": [1.0, 4.0], "num_particles": [300], "duration_s": [30.0]}
ANALOG_GRID = {"m": [1500], "k": [10, 20], "T": [200]}


def _flaky(params, seed):
    if params["x"] == 2:
        raise RuntimeError("x = 2 is not allowed")
    return {"y": params["x"] * 10 + seed % 7}


def test_task_seeds_depend_only_on_the_key():
    a = sweep.make_tasks({"a": [1, 2], "b": ["u"]}, runs=2, base_seed=5)
    b = sweep.make_tasks({"b": ["u"], "a": [2, 1]}, runs=2, base_seed=5)
    assert {t.key: t.seed for t in a} == {t.key: t.seed for t in b}
    assert len({t.seed for t in a}) == 4
    assert sweep.make_tasks({"a": [1]}, base_seed=6)[0].seed != sweep.make_tasks({"a": [1]}, base_seed=5)[0].seed
    with pytest.raises(ValueError, match="runs"):
        sweep.make_tasks({"a": [1]}, runs=0)
    with pytest.raises(ValueError, match="grid"):
        sweep.make_tasks({"a": [[1, 2]]})
    with pytest.raises(ValueError, match="grid"):
        sweep.make_tasks({"a": []})


def test_local_cluster_gives_the_in_process_results():
    local_mm = sweep.run_sweep(st.mapmatch_run, MAPMATCH_GRID, runs=2, base_seed=3)
    local_an = sweep.run_sweep(st.analog_run, ANALOG_GRID, runs=1, base_seed=3)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        from indoorloc import mapmatch

        dist_mm = sweep.run_sweep(st.mapmatch_run, MAPMATCH_GRID, runs=2, base_seed=3, scheduler=client,
                                  shared={"segments_m": np.asarray(mapmatch.warehouse_network().segments_m)})
        dist_an = sweep.run_sweep(st.analog_run, ANALOG_GRID, runs=1, base_seed=3, scheduler=client)
    assert local_mm.rows == dist_mm.rows and len(local_mm.rows) == 4
    assert local_an.rows == dist_an.rows and len(local_an.rows) == 2
    assert all(np.isfinite(r["mean_error_m"]) for r in local_mm.rows)
    assert local_mm.to_structured()["kappa"].tolist() == [1.0, 1.0, 4.0, 4.0]


def test_failed_tasks_are_reported_and_an_interrupted_sweep_resumes(tmp_path):
    out = tmp_path / "sweep.jsonl"
    grid = {"x": [0, 1, 2, 3]}
    first = sweep.run_sweep(_flaky, grid, runs=2, out=out, max_tasks=3)
    assert first.n_run == 3 and len(first.rows) == 3 and first.n_cached == 0
    lines = [json.loads(s) for s in out.read_text().splitlines()]
    assert len(lines) == 3
    # Resume: the three finished tasks are read back, the rest run; x = 2 fails and is reported.
    second = sweep.run_sweep(_flaky, grid, runs=2, out=out)
    assert second.n_cached == 3 and second.n_run == 5
    assert [f["params"]["x"] for f in second.failed] == [2, 2] and "x = 2" in second.failed[0]["error"]
    assert [r["x"] for r in second.rows] == [0, 0, 1, 1, 3, 3]
    fresh = sweep.run_sweep(_flaky, grid, runs=2)
    assert fresh.rows == second.rows
    # A line cut by an interruption is ignored (its task runs again).
    with out.open("a") as f:
        f.write('{"key": "trunc')
    third = sweep.run_sweep(_flaky, grid, runs=2, out=out)
    assert third.n_cached == 6 and third.rows == second.rows


def test_cli_runs_a_toml_sweep_and_resumes(tmp_path, capsys):
    from indoorloc import cli

    spec = tmp_path / "s.toml"
    spec.write_text('experiment = "mapmatch_run"\nruns = 2\nbase_seed = 1\n[grid]\nkappa = [1.0, 5.0]\n'
                    'num_particles = 300\nduration_s = [20.0]\n')
    out, js = tmp_path / "r.jsonl", tmp_path / "r.json"
    assert cli.main(["sweep", str(spec), "--out", str(out), "--max-tasks", "1", "--quiet"]) == 0
    assert cli.main(["sweep", str(spec), "--out", str(out), "--json", str(js), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "4 of 4 tasks done (3 run now, 1 read from" in text
    data = json.loads(js.read_text())
    assert [e["runs"] for e in data["summary"]] == [2, 2] and "mean_error_m_mean" in data["summary"][0]
    bad = tmp_path / "bad.toml"
    bad.write_text('experiment = "nope"\n[grid]\nx = [1]\n')
    assert cli.main(["sweep", str(bad), "--quiet"]) == 2
    assert "'experiment' must be one of" in capsys.readouterr().err


def test_mapmatch_reproduce_on_a_cluster_equals_the_in_process_command(tmp_path):
    from indoorloc import cli

    args = ["mapmatch", "reproduce", "--runs", "2", "--particles", "300", "--variant", "bias", "--threads", "1",
            "--quiet"]
    assert cli.main(args + ["--out", str(tmp_path / "local")]) == 0
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        assert cli.main(args + ["--out", str(tmp_path / "dask"), "--scheduler", cluster.scheduler_address]) == 0
    local = json.loads((tmp_path / "local" / "mapmatch_results.json").read_text())
    dist = json.loads((tmp_path / "dask" / "mapmatch_results.json").read_text())
    for a, b in zip(local["bias"], dist["bias"]):
        a.pop("seconds"), b.pop("seconds")
        assert a == b


def test_fusion_evaluate_on_a_cluster_equals_in_process(tmp_path):
    from indoorloc.experiments import fusion_real as fr
    from indoorloc.simulate.ilc_site import write_ilc_site

    site = write_ilc_site(tmp_path / "site", floors=("F1",), walks_per_floor=6, seed=5)
    settings = fr.RealSettings(num_particles=300, folds=2, smoother_trajectories=5)
    local = fr.evaluate(site, ["F1"], settings)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        dist = fr.evaluate(site, ["F1"], settings, scheduler=client)
    assert dist["methods"] == local["methods"]
    assert sorted(map(json.dumps, dist["waypoints"])) == sorted(map(json.dumps, local["waypoints"]))


def test_analog_table1_merged_from_realisation_tasks_equals_one_run():
    from indoorloc.experiments import analog_lorenz63 as al
    from indoorloc.experiments import sweep_tasks

    kwargs = dict(n_realisations=3, catalog_sizes=(1500,), beams=(None, 300), methods=("anfb",),
                  setting=al.Lorenz63Setting(T=200), k=10)
    whole = al.run_table1(**kwargs)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        res = sweep.run_sweep(sweep_tasks.analog_table1_realisation, {"r": [0, 1, 2]}, scheduler=client,
                              shared={"table1_kwargs": kwargs})
    merged = al.merge_table1([row["part"] for row in res.rows])
    assert merged["realisations"] == [0, 1, 2]
    assert [(r["method"], r["M"], r["beam"], r["rmse"]) for r in merged["rows"]] == \
        [(r["method"], r["M"], r["beam"], r["rmse"]) for r in whole["rows"]]
    assert [r["rmse_mean"] for r in merged["rows"]] == [r["rmse_mean"] for r in whole["rows"]]


def test_pdr_evaluate_on_a_cluster_equals_in_process(shared_data):
    from indoorloc.experiments import pdr_evaluate as pe

    root = shared_data / "pdr"
    if not (root / pe.DATASETS["xio"]).is_dir():
        pytest.skip(f"the x-io recordings are not under {root}")
    local = pe.evaluate_json(root, only=["xio"])
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        dist = pe.evaluate_json_on_dask(root, ["xio"], client)
    for doc in (dist, local):  # timings differ from run to run
        for rec in doc["recordings"]:
            rec["health"].pop("seconds", None)
    assert json.dumps(dist, sort_keys=True) == json.dumps(local, sort_keys=True)
    with pytest.raises(ValueError, match="only"):
        pe.evaluate_json_on_dask(root, ["nope"], client)


def test_wifi_evaluate_on_a_cluster_equals_in_process(shared_data, tmp_path, capsys):
    from indoorloc import cli

    root = shared_data / "wifi"
    if not root.is_dir():
        pytest.skip(f"no WiFi datasets under {root}")
    args = ["wifi", "evaluate", "--data-root", str(root), "--dataset", "corridor", "--scans", "1", "--cv-points", "4",
            "--threads", "1", "--quiet"]
    assert cli.main(args + ["--json", str(tmp_path / "local.json")]) == 0
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        assert cli.main(args + ["--json", str(tmp_path / "dask.json"), "--scheduler", cluster.scheduler_address]) == 0

    def strip(doc):  # timings differ from run to run
        for entry in doc.values():
            for row in entry["results"]:
                for key in [k for k in row if "second" in k or k.startswith("ms_") or k.endswith("_ms")]:
                    row.pop(key)
        return doc

    local = strip(json.loads((tmp_path / "local.json").read_text()))
    dist = strip(json.loads((tmp_path / "dask.json").read_text()))
    assert "corridor/k=1" in local
    assert json.dumps(local, sort_keys=True) == json.dumps(dist, sort_keys=True)  # NaN-safe comparison


def test_network_reproduce_flights_on_a_cluster_equal_in_process():
    """`indoorloc reproduce --scheduler`: paper 003's Monte Carlo flights as Dask tasks."""
    from indoorloc.experiments import network_reproduce as nr

    local = nr.flight_runs([3], slow_stride=5, small=True)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        remote = nr.flight_runs([3], slow_stride=5, small=True, scheduler=client)
    assert len(remote) == 1 and set(remote[0]) == set(local[0])
    for key, value in local[0].items():
        if not key.endswith("|seconds"):
            assert remote[0][key] == value, key


def test_consecutive_sweeps_on_one_client_share_inputs_safely():
    """Two sweeps with the same shared input on one client: the second used to fail with "lost
    dependencies" (the scattered input had the same content-hash key as the first sweep's, whose
    release was pending)."""
    from indoorloc.experiments import sweep_tasks

    segments = np.array([[0.0, 0.0, 10.0, 0.0], [10.0, 0.0, 10.0, 10.0]])
    grid = {"kappa": [1.0], "num_particles": [200], "duration_s": [5.0]}
    with Client(processes=False, n_workers=1, threads_per_worker=2, dashboard_address=None) as client:
        results = [sweep.run_sweep(sweep_tasks.mapmatch_run, grid, runs=2, scheduler=client,
                                   shared={"segments_m": segments}) for _ in range(3)]
    for r in results:
        assert not r.failed and len(r.rows) == 2
    assert [row["mean_error_m"] for row in results[0].rows] == [row["mean_error_m"] for row in results[2].rows]
