"""``indoorloc fusion evaluate`` (experiments.fusion_real) on a synthetic site written in the
competition's format by the test itself (simulate.ilc_site): floor identification over two
floors, the leave-one-floor-out choice of settings, the plots and the CLI's JSON contract."""

import json
import math

import numpy as np
import pytest

from indoorloc import cli
from indoorloc.experiments import fusion_real as fr
from indoorloc.simulate.ilc_site import write_ilc_site

FAST = dict(num_particles=400, folds=2, smoother_trajectories=8)


@pytest.fixture(scope="module")
def two_floor_site(tmp_path_factory):
    return write_ilc_site(tmp_path_factory.mktemp("ilc2") / "site", floors=("F1", "F2"), walks_per_floor=6, seed=3)


def test_floor_identification_and_error_against_time(two_floor_site):
    result = fr.evaluate(two_floor_site, ["F1", "F2"], fr.RealSettings(**FAST))
    fi = result["floor_identification"]
    n_wp = result["methods"]["fusion_smoother"]["n_waypoints"]
    assert fi["n_waypoints"] == n_wp and fi["n_walks"] == 12
    assert set(fi["per_floor"]) == {"F1", "F2"}
    assert 0.0 <= fi["accuracy"] <= 1.0 and fi["accuracy"] >= 0.9  # the two floors' radios differ
    # Calibrated floor probabilities: each walk's, binned; never 1 on two floors (δ > 0).
    rel = fi["reliability"]
    assert sum(b["walks"] for b in rel["bins"]) == 12 and 0.5 < rel["mean_reported"] < 1.0
    assert "Calibrated floor probability reported" in fr.markdown(result)
    assert set(result["per_floor"]) == {"F1", "F2"}
    bins = result["error_vs_time"]["pdr_only"]
    assert sum(b["n_waypoints"] for b in bins) == result["methods"]["pdr_only"]["n_waypoints"]
    assert bins[0]["from_s"] == 0.0 and bins[-1]["to_s"] is None
    # Waypoint rows carry the contract's keys, one per method and waypoint.
    row = result["waypoints"][0]
    assert set(row) == {"floor", "walk", "method", "t_s", "error_m"}
    assert "| fusion_smoother |" in fr.markdown(result) and "Floor identification" in fr.markdown(result)
    # The WiFi-only sequence tracker is scored beside wifi_knn, at the same waypoints.
    assert result["methods"]["wifi_sequence"]["n_waypoints"] == result["methods"]["wifi_knn"]["n_waypoints"]
    assert math.isfinite(result["methods"]["wifi_sequence"]["mean_m"])
    # And the direction-persistent one, on the same fixes and waypoints.
    assert result["methods"]["wifi_heading_sequence"]["n_waypoints"] == result["methods"]["wifi_knn"]["n_waypoints"]
    assert math.isfinite(result["methods"]["wifi_heading_sequence"]["mean_m"])


def test_leave_one_floor_out_choice_never_looks_at_the_held_out_floor(two_floor_site):
    grid = {"grid.fix_tempering": (0.3, 1.0), "fixes.sd_m": (3.0,)}
    result = fr.select_settings(two_floor_site, ["F1", "F2"], fr.RealSettings(**FAST), grid)
    # Two runs, each scored with both point estimates (mean and spatial median).
    assert len(result["points"]) == 4 and result["held_out"] is True
    assert {p["values"]["point_estimate"] for p in result["points"]} == {"mean", "median"}
    for held_out, chosen in result["lofo"].items():
        other = "F2" if held_out == "F1" else "F1"
        means = [p["per_floor"][other]["fusion_smoother"]["mean_m"] for p in result["points"]]
        best = result["points"][int(np.argmin(means))]["values"]
        assert chosen["chosen"] == best
        # The held-out figure is the chosen point's own figure on the held-out floor.
        point = next(p for p in result["points"] if p["values"] == best)
        assert chosen["stats"]["mean_m"] == pytest.approx(point["per_floor"][held_out]["fusion_smoother"]["mean_m"])
    assert result["lofo_overall"]["n_waypoints"] == sum(
        result["points"][0]["per_floor"][f]["fusion_smoother"]["n_waypoints"] for f in ("F1", "F2"))
    ks = result["known_start"]
    for held_out, chosen in ks["lofo"].items():
        other = "F2" if held_out == "F1" else "F1"
        means = [p["per_floor"][other]["fusion_known_start"]["mean_m"] for p in result["points"]]
        assert chosen["chosen"] == result["points"][int(np.argmin(means))]["values"]
    assert "known-start filter" in fr.select_markdown(result)


def test_walk_snapshot_and_plots(two_floor_site, tmp_path):
    snap = fr.walk_snapshot(two_floor_site, "F2", 1, fr.RealSettings(**FAST))
    assert snap["waypoints_m"].shape[1] == 2 and snap["smoothed_m"].shape[1] == 2
    assert snap["extent_m"] is not None
    assert np.all(np.isfinite(snap["errors"]["fusion_smoother"]))
    # The track viewer's inputs: the track's times, its smoothed covariances, the fixes' times.
    assert snap["track_t_s"].shape == (len(snap["smoothed_m"]),) and np.all(np.diff(snap["track_t_s"]) >= 0)
    assert snap["smoothed_covariance_m2"].shape == (len(snap["smoothed_m"]), 3)
    assert snap["fix_t_s"].shape == (len(snap["fix_centres_m"]),)
    from indoorloc import plots

    png = plots.fusion_real_walk(snap, tmp_path / "walk.png")
    assert png.stat().st_size > 10_000
    with pytest.raises(ValueError, match="walk_index"):
        fr.walk_snapshot(two_floor_site, "F2", 99, fr.RealSettings(**FAST))


def test_cli_writes_the_json_contract_and_plots(two_floor_site, tmp_path, monkeypatch, capsys):
    # The CLI builds RealSettings(folds, seed, threads): give it the fast tracker settings.
    monkeypatch.setattr(fr, "RealSettings", _fast_settings)
    out = tmp_path / "r.json"
    code = cli.main(["fusion", "evaluate", "--data-root", str(two_floor_site), "--floors", "F1", "--folds", "2",
                     "--json", str(out), "--plots", str(tmp_path / "plots"), "--quiet"])
    assert code == 0
    data = json.loads(out.read_text())
    assert set(data) >= {"methods", "waypoints", "settings"}
    for stats in data["methods"].values():
        # Issue 15's names stay; the keys added beside them are documented in docs/fusion_real.md.
        assert {"mean_m", "median_m", "p90_m", "n_waypoints"} <= set(stats)
        assert set(stats) - {"mean_m", "median_m", "p90_m", "n_waypoints"} <= {
            "first_10s_mean_m", "by_coverage", "region95_coverage", "offset_error_deg", "first_position"}
        assert all(math.isfinite(stats[k]) for k in ("mean_m", "median_m", "p90_m"))
        assert set(stats["by_coverage"]) == {"within_5m", "5_to_10m", "beyond_10m"}
    smoother = data["methods"]["fusion_smoother"]
    assert 0.0 <= smoother["region95_coverage"] <= 1.0
    # Per floor too (one floor here: the pooled figure); "| fusion_smoother |" row in the coverage table.
    assert data["per_floor"]["F1"]["fusion_smoother"]["region95_coverage"] == smoother["region95_coverage"]
    text = fr.markdown(data)
    assert "inside the estimate's 95 % region" in text
    # The Markdown carries the coverage split, the offset error and the loader's report too.
    within = smoother["by_coverage"]["within_5m"]
    assert f"| fusion_smoother | {within['mean_m']:.2f} |" in text and "by survey coverage" in text
    assert f"| fusion_smoother | {smoother['offset_error_deg']['n_walks']} | {smoother['offset_error_deg']['mean_abs']:.1f} |" in text
    assert "Loader: F1 " in text and " of " in text
    # The live tracker: scored from its first located estimate, which comes after the first waypoint.
    first = data["methods"]["fusion_live"]["first_position"]
    assert set(first) == {"median_s", "p90_s", "max_s", "waypoints_before", "walks_never_located"}
    assert 0.0 < first["median_s"] <= first["p90_s"] <= first["max_s"] and first["waypoints_before"] >= 1
    assert first["walks_never_located"] == 0   # every synthetic walk has scans
    assert data["methods"]["fusion_live"]["n_waypoints"] == data["methods"]["fusion_unknown_start"]["n_waypoints"]
    assert smoother["offset_error_deg"]["n_walks"] >= 1
    # Per walk, the final offset beside the residual; the mean |difference| is offset_error_deg's.
    rows = [r for r in data["heading_offsets"] if "fusion_smoother" in r["final_deg"]]
    assert len(rows) == smoother["offset_error_deg"]["n_walks"]
    diff = [abs((r["final_deg"]["fusion_smoother"] - r["residual_deg"] + 180.0) % 360.0 - 180.0) for r in rows]
    assert math.isclose(sum(diff) / len(diff), smoother["offset_error_deg"]["mean_abs"], abs_tol=0.01)
    assert (tmp_path / "plots" / "fusion_real_heading_offsets.png").is_file()
    assert (tmp_path / "plots" / "fusion_real_error_cdfs.png").is_file()
    assert (tmp_path / "plots" / "fusion_real_walk_F1.png").is_file()
    assert "| method |" in capsys.readouterr().out


def test_cli_several_seeds_gives_each_run_and_their_spread(two_floor_site, tmp_path, monkeypatch, capsys):
    """``--seed 0 1``: one evaluation per fold seed, each the one-seed document, and the spread of
    every method's mean across them; seed 0's run equals a one-seed run."""
    monkeypatch.setattr(fr, "RealSettings", _fast_settings)
    args = ["fusion", "evaluate", "--data-root", str(two_floor_site), "--floors", "F1", "--folds", "2", "--quiet"]
    one, many = tmp_path / "one.json", tmp_path / "many.json"
    assert cli.main(args + ["--seed", "0", "--json", str(one)]) == 0
    assert cli.main(args + ["--seed", "0", "1", "--json", str(many)]) == 0
    single, doc = json.loads(one.read_text()), json.loads(many.read_text())
    assert "schema" not in single and "methods" in single  # one seed: the one-seed document as before
    assert doc["schema"] == "indoorloc.fusion_evaluate_seeds" and doc["version"] == 1 and doc["seeds"] == [0, 1]
    assert set(doc["runs"]) == {"0", "1"}
    assert doc["runs"]["0"]["methods"] == single["methods"]
    for name, m in doc["spread"]["methods"].items():
        per_seed = [doc["runs"][s]["methods"][name]["mean_m"] for s in ("0", "1")]
        assert m["mean_m"]["per_seed"] == per_seed
        assert math.isclose(m["mean_m"]["mean"], sum(per_seed) / 2)
        assert m["mean_m"]["min"] <= m["mean_m"]["mean"] <= m["mean_m"]["max"]
    assert "mean ± sd" in capsys.readouterr().out
    for bad in (["--seed", "1", "1"], ["--seed", "-1"], ["--seed", "0", "1", "--lowo"]):
        assert cli.main(args + bad) == 2


_RealSettings = fr.RealSettings


def _fast_settings(**kw):
    return _RealSettings(**{**FAST, **kw})


def test_default_floors_are_every_floor_of_the_site(two_floor_site, tmp_path, monkeypatch, capsys):
    """Issue 28: ``--data-root OTHER_SITE`` needs no ``--floors``: every floor folder with walks
    and geojson_map.json, in building order."""
    seen = []

    def fake_evaluate(root, floors, settings, progress=None, scheduler=None):
        seen.append(list(floors))
        return {}

    monkeypatch.setattr(fr, "evaluate", fake_evaluate)
    monkeypatch.setattr(fr, "markdown", lambda result: "table")
    assert cli.main(["fusion", "evaluate", "--data-root", str(two_floor_site), "--quiet"]) == 0
    assert cli.main(["fusion", "evaluate", "--data-root", str(two_floor_site), "--floors", "F2", "--quiet"]) == 0
    assert seen == [["F1", "F2"], ["F2"]]
    (tmp_path / "B1" / "path_data_files").mkdir(parents=True)  # no walk, no plan: not a floor
    # A folder that does not exist: one error line naming the argument, exit code 2.
    assert cli.main(["fusion", "evaluate", "--data-root", str(tmp_path / "nowhere"), "--quiet"]) == 2
    assert "error: indoorloc: argument 'data_root'" in capsys.readouterr().err
    assert cli.main(["fusion", "evaluate", "--data-root", str(tmp_path), "--quiet"]) == 2
    assert "error: indoorloc: argument 'data_root': no floor folder" in capsys.readouterr().err
    # The library default is the same rule.
    assert fr.FLOORS == ()
    root, data = fr.load_site(two_floor_site, fr.FLOORS)
    assert [fl.name for fl in data] == ["F1", "F2"] and root == two_floor_site


def test_missing_site_and_floor_are_clear_errors(tmp_path, two_floor_site):
    with pytest.raises(FileNotFoundError, match="data_root"):
        fr.evaluate(tmp_path / "nowhere", ["F1"])
    with pytest.raises(ValueError, match=r"argument 'floors': \['F9'\] not in .*floors: \['F1', 'F2'\]"):
        fr.evaluate(two_floor_site, ["F9"])


def _kaggle_layout(site, root, floors, plans=None):
    """The ILC 2020 site's walks laid out as the Kaggle 2021 data (symlinks): walks in
    ``root/train/site3/FLOOR/*.txt``, plans in ``root/metadata/site3/FLOOR/`` (for ``plans``,
    default every floor)."""
    for name in floors:
        walks = root / "train" / "site3" / name
        walks.mkdir(parents=True)
        for p in sorted((site / name / "path_data_files").glob("*.txt")):
            (walks / p.name).symlink_to(p)
        if name in (floors if plans is None else plans):
            plan = root / "metadata" / "site3" / name
            plan.mkdir(parents=True)
            for f in ("geojson_map.json", "floor_info.json"):
                (plan / f).symlink_to(site / name / f)
    (root / "metadata").mkdir(exist_ok=True)
    return root


def test_kaggle_layout_evaluates_as_the_ilc_layout(two_floor_site, tmp_path, monkeypatch):
    """The same walks and plans laid out as Kaggle 2021 (plans apart from the walks): ``fusion
    evaluate --data-root ROOT`` finds the floor and gives exactly the figures of the ILC layout."""
    kaggle = _kaggle_layout(two_floor_site, tmp_path / "kaggle", ["F1"])
    # ROOT of a one-site folder and ROOT/train/SITE are the same site.
    for root in (kaggle, kaggle / "train" / "site3"):
        _, (sf,) = fr.site_floors(root, ())
        assert (sf.name, sf.number, sf.floor_dir, sf.plan_dir) == (
            "F1", 1, kaggle / "train" / "site3" / "F1", kaggle / "metadata" / "site3" / "F1")
        assert sf.open().width_m is not None and sf.open().geojson_path == sf.plan_dir / "geojson_map.json"
    ilc = fr.evaluate(two_floor_site, ["F1"], fr.RealSettings(**FAST))
    monkeypatch.setattr(fr, "RealSettings", _fast_settings)
    out = tmp_path / "k.json"
    assert cli.main(["fusion", "evaluate", "--data-root", str(kaggle), "--folds", "2", "--json", str(out),
                     "--quiet"]) == 0  # no --floors: every floor of the site (here F1)
    got = json.loads(out.read_text())
    expected = json.loads(json.dumps(ilc))  # as the CLI writes it (tuples as lists)
    assert got["methods"]["fusion_smoother"]["n_waypoints"] > 0
    for key in ("methods", "per_floor", "waypoints", "heading_offsets", "loader"):
        assert got[key] == expected[key], key


def test_floor_without_plan_is_skipped_unless_named(two_floor_site, tmp_path, monkeypatch, capsys):
    """A floor folder with walks but no geojson_map.json: skipped with a RecordingWarning naming it
    when the floors are not named, an error naming it when it is named (as ``site build``)."""
    from indoorloc.io.errors import RecordingWarning

    kaggle = _kaggle_layout(two_floor_site, tmp_path / "kaggle", ["F1", "F2"], plans=["F1"])
    with pytest.warns(RecordingWarning, match=r"argument 'data_root': floor F2 skipped: 6 walk file\(s\) .*"
                                              r"no floor plan .*metadata/site3/F2/geojson_map.json"):
        _, found = fr.site_floors(kaggle, ())
    assert [sf.name for sf in found] == ["F1"]
    with pytest.raises(ValueError, match=r"argument 'data_root': floor F2: no floor plan .*site3/F2/geojson_map"):
        fr.site_floors(kaggle, ["F2"])
    seen = []
    monkeypatch.setattr(fr, "evaluate", lambda root, floors, *a, **k: seen.append(list(floors)) or {})
    monkeypatch.setattr(fr, "markdown", lambda result: "table")
    with pytest.warns(RecordingWarning, match="floor F2 skipped"):
        assert cli.main(["fusion", "evaluate", "--data-root", str(kaggle), "--quiet"]) == 0
    assert seen == [["F1"]]
    assert cli.main(["fusion", "evaluate", "--data-root", str(kaggle), "--floors", "F2", "--quiet"]) == 2
    assert "error: indoorloc: argument 'data_root': floor F2: no floor plan" in capsys.readouterr().err
    # No floor with a plan at all: the error says which floors lack one.
    bare = _kaggle_layout(two_floor_site, tmp_path / "bare", ["F1"], plans=[])
    with pytest.warns(RecordingWarning), pytest.raises(ValueError, match=r"no floor folder .*folders with walk files but no plan"):
        fr.site_floors(bare, ())


def test_leave_one_walk_out_scores_every_walk_once(two_floor_site, tmp_path, monkeypatch):
    monkeypatch.setattr(fr, "RealSettings", _fast_settings)
    out = tmp_path / "lowo.json"
    assert cli.main(["fusion", "evaluate", "--data-root", str(two_floor_site), "--floors", "F1", "--lowo",
                     "--json", str(out), "--quiet"]) == 0
    data = json.loads(out.read_text())
    walks = {(w["floor"], w["walk"]) for w in data["waypoints"] if w["method"] == "fusion_smoother"}
    assert len(walks) == 6  # every walk of F1, each its own fold
    assert data["settings"]["folds"] == 0 and "floor_identification" not in data


def test_select_grid_is_checked_before_any_walk_is_tracked(two_floor_site, capsys):
    """--select-grid: an unknown setting or an empty value list is a ValueError naming 'grid'
    (before the site is even read); bad JSON is a usage error of the CLI."""
    with pytest.raises(ValueError, match="argument 'grid'.*no_such_setting"):
        fr.select_settings(two_floor_site, ["F1"], fr.RealSettings(**FAST), {"no_such_setting": [1]})
    with pytest.raises(ValueError, match="argument 'grid'.*grid.wall_margin_m"):
        fr.select_settings(two_floor_site, ["F1"], fr.RealSettings(**FAST), {"grid.wall_margin_m": []})
    with pytest.raises(SystemExit):
        cli.main(["fusion", "evaluate", "--data-root", str(two_floor_site), "--select", "--select-grid", "{not json"])
    assert "--select-grid" in capsys.readouterr().err
    # Without --select the grid would be ignored: refused, no walk tracked.
    assert cli.main(["fusion", "evaluate", "--data-root", str(two_floor_site), "--select-grid",
                     '{"grid.wall_margin_m": [1]}']) != 0
    assert "only with --select" in capsys.readouterr().err


def test_survey_coverage_with_the_fold_tree_equals_the_brute_force_minimum():
    """The KD-tree shortcut of the coverage distance gives the brute-force values bit for bit,
    ties included (half the training positions on whole metres, waypoints on them too)."""
    from scipy.spatial import cKDTree

    from indoorloc.experiments.fusion_real_walk import survey_coverage_m

    rng = np.random.default_rng(1)
    for n in (1, 7, 3000):
        train = rng.uniform(0, 200, (n, 2))
        train[n // 2:] = np.round(train[n // 2:])
        way = np.r_[rng.uniform(-20, 220, (40, 2)), train[:3], np.round(rng.uniform(0, 200, (20, 2)))]
        brute = survey_coverage_m(way, train)
        assert np.array_equal(survey_coverage_m(way, train, cKDTree(train)), brute)
        assert np.allclose(brute, np.hypot(*(way[:, None, :] - train[None, :, :]).T).min(axis=0))


def test_evaluate_scores_do_not_depend_on_the_worker_count(two_floor_site):
    """Fold models built while the previous fold's walks run: the scores equal a serial run's."""
    data = fr.load_site(two_floor_site, ["F1", "F2"])[1]
    one = fr.evaluate_floors(data, fr.RealSettings(**FAST, threads=1), methods=("wifi_knn", "fusion_smoother"))
    two = fr.evaluate_floors(data, fr.RealSettings(**FAST, threads=2), methods=("wifi_knn", "fusion_smoother"))
    assert [(s.floor, s.walk) for s in one] == [(s.floor, s.walk) for s in two]
    for a, b in zip(one, two):
        assert a.errors_m.keys() == b.errors_m.keys()
        for k in a.errors_m:
            assert np.array_equal(a.errors_m[k], b.errors_m[k])
        assert np.array_equal(a.coverage_m, b.coverage_m)


def test_fold_models_from_the_walk_cache_equal_the_direct_construction(two_floor_site):
    """WalkTrainingCache: each training walk's fingerprints and placed readings computed once for
    every fold; the databases and crowdsourced maps equal build_database / build_crowd_map's."""
    from indoorloc.experiments import fusion_real_folds as ff
    from indoorloc.fusion import crowdsourced_map as wc, site_model, wifi_fixes as wfx

    data = fr.load_site(two_floor_site, ["F1", "F2"])[1]
    settings = fr.RealSettings(**FAST)
    all_plan = fr._all_floor_plan(data)
    fold_of = {fl.name: fr._folds(len(fl.walks), 2, 0) for fl in data}
    cache = ff.WalkTrainingCache()
    for j in range(2):
        models = fr._fold_models(data, fold_of, j, settings, all_plan, True, cache)
        all_walks, all_steps, all_numbers = [], [], []
        for fl in data:
            test = set(fold_of[fl.name][j].tolist())
            train = [w for i, w in enumerate(fl.walks) if i not in test]
            steps = [s for i, s in enumerate(fl.steps) if i not in test]
            direct = site_model.build_fingerprints(train, steps, fl.number, settings.fixes)
            crowd = wc.build_crowd_map(train, wc.CrowdMapSettings(), fl.number)
            got = models[fl.name]
            assert got.database.bssids == direct.bssids and got.crowd.bssids == crowd.bssids
            for name in ("rss_dbm", "positions_m", "floors", "walk_index", "ap_ratio"):
                assert np.array_equal(getattr(got.database, name), getattr(direct, name), equal_nan=True), name
            for name in ("positions_m", "mean_dbm", "variance_db2"):
                assert np.array_equal(np.asarray(getattr(got.crowd.signal_map, name)),
                                      np.asarray(getattr(crowd.signal_map, name)), equal_nan=True), name
            all_walks += train
            all_steps += steps
            all_numbers += [fl.number] * len(train)
        direct_all = wfx.build_database(all_walks, settings.fixes, all_steps, floors=all_numbers)
        for name in ("rss_dbm", "positions_m", "floors", "walk_index", "ap_ratio"):
            assert np.array_equal(getattr(models["F1"].all_database, name), getattr(direct_all, name),
                                  equal_nan=True), name


def test_propagation_fixes_setting(two_floor_site):
    """RealSettings.propagation: the path-loss fixes reach wifi_sequence and the smoother only;
    wifi_knn keeps the kNN fixes; a bad mode is named."""
    from dataclasses import replace

    data = fr.load_site(two_floor_site, ["F2"])[1]
    methods = ("wifi_knn", "wifi_sequence", "fusion_smoother")
    base = fr.RealSettings(**FAST, threads=1, floor_identification=False)
    off = fr.evaluate_floors(data, base, methods=methods)
    on = fr.evaluate_floors(data, replace(base, propagation="product"), methods=methods)
    changed = False
    for a, b in zip(off, on):
        assert np.array_equal(a.errors_m["wifi_knn"], b.errors_m["wifi_knn"])
        assert np.all(np.isfinite(b.errors_m["wifi_sequence"])) and np.all(np.isfinite(b.errors_m["fusion_smoother"]))
        changed |= not np.array_equal(a.errors_m["wifi_sequence"], b.errors_m["wifi_sequence"])
    assert changed
    with pytest.raises(ValueError, match="propagation"):
        fr.evaluate_floors(data, replace(base, propagation="sum"), methods=methods)


def test_select_scores_each_point_estimate_with_its_own_second_pass(two_floor_site):
    """--select's "mean" and "median" of the default method are two real runs: the second smoother
    pass started from the first pass's mean or spatial median, each equal to the run with that
    point estimate as the setting (before, both keys held the setting's run: the choice was void)."""
    from dataclasses import replace

    data = fr.load_site(two_floor_site, ["F1"])[1]
    base = fr.RealSettings(**FAST, floor_identification=False)
    both = fr.evaluate_floors(data, replace(base, score_both_point_estimates=True), methods=("fusion_smoother",))
    for pe in ("mean", "median"):
        alone = fr.evaluate_floors(data, replace(base, point_estimate=pe), methods=("fusion_smoother",))
        for a, b in zip(both, alone):
            assert np.allclose(a.errors_m[f"_alt/fusion_smoother/{pe}"], b.errors_m["fusion_smoother"], atol=1e-9)
    main = [s.errors_m["fusion_smoother"] for s in both]
    chosen = [s.errors_m[f"_alt/fusion_smoother/{base.point_estimate}"] for s in both]
    assert all(np.array_equal(a, b) for a, b in zip(main, chosen))


def test_select_on_one_floor_says_its_figures_are_in_sample(two_floor_site):
    """With one floor nothing can be held out: the result says so ("held_out": false, a warning,
    the Markdown's titles) instead of printing an in-sample figure as a held-out one."""
    with pytest.warns(UserWarning, match="in-sample"):
        result = fr.select_settings(two_floor_site, ["F1"], fr.RealSettings(**FAST),
                                    grid={"grid.wall_log_penalty": [-1.0]})
    assert result["held_out"] is False
    text = fr.select_markdown(result)
    assert "IN SAMPLE" in text and "Held-out floors pooled" not in text
