"""indoorloc.fusion.Site: the site file (SQLite) built from survey walks, grown walk by walk,
used to track walks; ``indoorloc site ...`` and ``indoorloc track``.

Real walks of the shared site (one floor, a few walks, to stay fast); the tests skip with a
reason when the shared data is absent."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

FLOOR = "F8"
N_SURVEY = 4


@pytest.fixture
def floor_dir(shared_data) -> Path:
    d = shared_data / "fusion" / "ilc2020_site2" / FLOOR
    if not d.is_dir():
        pytest.skip(f"shared site floor not found at {d}")
    return d


def _walk_paths(floor_dir: Path):
    return sorted((floor_dir / "path_data_files").glob("*.txt"))


def _survey(tmp: Path, floor_dir: Path, walks, kaggle: bool = False) -> Path:
    """A survey folder with the given walk files: ILC 2020 layout (SITE/F8/path_data_files) or
    Kaggle 2021 (ROOT/train/SITE/F8/*.txt, ROOT/metadata/SITE/F8/)."""
    if kaggle:
        root = tmp / "kaggle"
        wdir, pdir = root / "train" / "site2" / FLOOR, root / "metadata" / "site2" / FLOOR
    else:
        root = tmp / "ilc"
        wdir, pdir = root / FLOOR / "path_data_files", root / FLOOR
    wdir.mkdir(parents=True)
    pdir.mkdir(parents=True, exist_ok=True)
    for name in ("geojson_map.json", "floor_info.json"):
        (pdir / name).write_bytes((floor_dir / name).read_bytes())
    for w in walks:
        (wdir / w.name).symlink_to(w)
    return root


@pytest.fixture
def built(tmp_path, floor_dir):
    from indoorloc.fusion.site import Site

    paths = _walk_paths(floor_dir)
    survey = _survey(tmp_path, floor_dir, paths[:N_SURVEY])
    site = Site.build(survey, tmp_path / "site.db")
    return site, paths


def test_round_trip_equals_in_memory_models(built, floor_dir):
    """A site saved and re-opened tracks a held-out walk exactly as the models built in memory
    from the same walks (fusion.site_model, what fusion evaluate uses)."""
    from indoorloc.pdr import handheld as ph
    from indoorloc.fusion import wifi_fixes
    from indoorloc.fusion import GridTracker, site_model
    from indoorloc.fusion.site import Site
    from indoorloc.io import load_floor_plan
    from indoorloc.io.ilc2020 import read_ilc_walk

    site, paths = built
    walks = [read_ilc_walk(p) for p in paths[:N_SURVEY]]
    steps = [ph.handheld_steps(w) for w in walks]
    settings = site_model.TrackSettings()
    cal = site_model.calibrate_floor(walks, steps)
    db = site_model.build_fingerprints(walks, steps, 8, settings.fixes)
    plan = load_floor_plan(floor_dir / "geojson_map.json", floors=[8], origin_lon_lat="outline_sw")
    tracker = site_model.survey_anchored(GridTracker(plan, site_model.floor_grid_options(settings, cal)), plan, db)
    second = tracker.with_options(site_model.second_pass_options(tracker.options, settings))
    test = read_ilc_walk(paths[N_SURVEY + 2])
    test_steps = site_model.tracker_steps(ph.handheld_steps(test), cal, settings)
    test_fixes = wifi_fixes.fixes_for_walk(test, db)
    median = settings.point_estimate == "median"
    r = site_model.run_default(tracker, test_steps, test_fixes, second_pass=second, floor=8, median=median)
    # "Locate, then track": the smoothed track is the second pass's, from the first pass's
    # smoothed estimate at the first step; the covariance stays the first pass's.
    first = r["first_pass"]
    one_pass = site_model.run_default(tracker, test_steps, test_fixes)
    np.testing.assert_array_equal(first["smoothed_median_m"], one_pass["smoothed_median_m"])
    start = site_model.located_start(first, test_steps, 8, median)
    np.testing.assert_array_equal(start["position_m"], first["smoothed_median_m"][0])
    assert start["time_s"] == test_steps.times_s[0] and start["floor"] == 8
    assert not np.array_equal(r["smoothed_median_m"], first["smoothed_median_m"])
    np.testing.assert_array_equal(r["smoothed_covariance_m2"], first["smoothed_covariance_m2"])
    np.testing.assert_array_equal(r["smoothed_median_m"], r["smoothed_m"])  # the second pass's mean
    assert np.hypot(*(r["smoothed_median_m"][0] - start["position_m"])) < 3 * settings.second_pass_start_sd_m
    reopened = Site.open(site.path)
    track = reopened.track(test, floor=FLOOR)
    key = "smoothed_median_m" if settings.point_estimate == "median" else "smoothed_m"
    np.testing.assert_array_equal(track.xy_m, r[key])
    np.testing.assert_array_equal(track.covariance_m2, r["smoothed_covariance_m2"])
    assert track.errors_m is not None and track.errors_m.size == test.waypoint_t_s.size
    assert np.all(np.isfinite(track.errors_m))
    # The floor's header names it: the default floor is the header's.
    np.testing.assert_array_equal(reopened.track(test).xy_m, track.xy_m)


def test_add_equals_build_with_the_walk(tmp_path, floor_dir):
    from indoorloc.fusion.site import Site
    from indoorloc.io.ilc2020 import read_ilc_walk

    paths = _walk_paths(floor_dir)
    small = Site.build(_survey(tmp_path / "a", floor_dir, paths[:N_SURVEY - 1]), tmp_path / "small.db")
    assert small.add([paths[N_SURVEY - 1]]) == [paths[N_SURVEY - 1].stem]
    full = Site.build(_survey(tmp_path / "b", floor_dir, paths[:N_SURVEY]), tmp_path / "full.db")
    a, b = Site.open(small.path).floor_models(FLOOR), full.floor_models(FLOOR)
    np.testing.assert_array_equal(a.database.rss_dbm, b.database.rss_dbm)
    np.testing.assert_array_equal(a.database.positions_m, b.database.positions_m)
    assert a.database.bssids == b.database.bssids
    np.testing.assert_array_equal(a.database.ap_ratio, b.database.ap_ratio)
    # The stored map columns (what the C++ reader uses) follow the add: equal to the models'.
    for site, m in ((small, a), (full, b)):
        with sqlite3.connect(site.path) as con:
            rows = con.execute("SELECT bssid, ap_ratio FROM fingerprint_columns WHERE floor = ? ORDER BY col",
                               (FLOOR,)).fetchall()
        assert [r[0] for r in rows] == m.database.bssids
        np.testing.assert_array_equal([r[1] for r in rows], m.database.ap_ratio)
    assert (a.calibration.k, a.calibration.yaw_offset_rad) == (b.calibration.k, b.calibration.yaw_offset_rad)
    test = read_ilc_walk(paths[N_SURVEY + 1])
    np.testing.assert_array_equal(Site.open(small.path).track(test).xy_m, full.track(test).xy_m)
    # A walk already in the site is refused, and the file keeps its content.
    with pytest.raises(ValueError, match="already in the site"):
        small.add([paths[0]])
    assert len(Site.open(small.path).info()["walks"]) == N_SURVEY


def test_leave_one_walk_out_and_auto_floor(built):
    site, paths = built
    lowo = site.leave_one_walk_out(FLOOR)
    assert lowo["walks"] == N_SURVEY and not lowo["missing"]
    assert lowo["points"].shape == (lowo["stats"]["n_waypoints"], 3) and np.all(np.isfinite(lowo["points"]))
    cov = site.coverage(FLOOR)
    assert 0 < cov["fraction_within_5m"] < 1 and cov["fingerprints_m"].shape[1] == 2
    auto = site.track(paths[-1], floor="auto")
    assert auto.floor == FLOOR and auto.floor_probabilities == {FLOOR: pytest.approx(1.0)}
    np.testing.assert_array_equal(auto.xy_m, site.track(paths[-1], floor=FLOOR).xy_m)
    filt = site.track(paths[-1], smooth=False)
    assert not filt.smoothed and filt.xy_m.shape == auto.xy_m.shape


def test_kaggle_layout(tmp_path, floor_dir):
    from indoorloc.fusion.site import Site
    from indoorloc.io.errors import RecordingWarning

    paths = _walk_paths(floor_dir)[:2]
    survey = _survey(tmp_path, floor_dir, paths, kaggle=True)
    # A floor folder with walks but no plan in metadata/: skipped with a warning naming it (as
    # fusion evaluate does, one function: survey_floors), an error when it is named.
    (survey / "train" / "site2" / "F9").mkdir()
    (survey / "train" / "site2" / "F9" / paths[0].name).symlink_to(paths[0])
    with pytest.raises(ValueError, match=r"argument 'survey_dir': floor F9: no floor plan"):
        Site.build(survey, tmp_path / "k.db", floors=["F9"])
    with pytest.warns(RecordingWarning, match="floor F9 skipped: 1 walk file"):
        site = Site.build(survey, tmp_path / "k.db")
    info = site.info()
    assert list(info["floors"]) == [FLOOR]
    assert info["floors"][FLOOR]["walks"] == 2 and info["floors"][FLOOR]["fingerprints"] > 0
    assert info["meta"]["format_version"] == "1"
    assert [w["id"] for w in info["walks"]] == [p.stem for p in paths]


def test_info_reports_the_survey_off_the_plan(built):
    """``survey_off_plan``: the fraction of surveyed fingerprints the plan puts outside walkable
    space, as counted from the floor's plan and fingerprint positions; shown in the CLI table."""
    from indoorloc.cli.site import _floor_table

    site, _ = built
    info = site.info()
    m = site.floor_models(FLOOR)
    xy = np.asarray(m.database.positions_m, float)
    off = float(np.mean(~np.asarray(m.plan.is_walkable(xy, 0), bool)))
    assert info["floors"][FLOOR]["survey_off_plan"] == round(off, 4)
    assert 0.0 <= off < 0.2
    assert f"{100 * off:.1f} % |" in _floor_table(info) and "survey off the plan" in _floor_table(info)


def test_bad_files_give_clear_errors(built, tmp_path):
    from indoorloc.fusion.site import Site
    from indoorloc.fusion.site_store import SiteFileError

    site, _ = built
    text = tmp_path / "notes.db"
    text.write_text("not a database\n")
    with pytest.raises(SiteFileError, match="notes.db: not an SQLite file"):
        Site.open(text)
    foreign = tmp_path / "foreign.db"
    con = sqlite3.connect(foreign)
    con.execute("CREATE TABLE t (x)")
    con.commit()
    con.close()
    with pytest.raises(SiteFileError, match="foreign.db: an SQLite file of another application"):
        Site.open(foreign)
    old = tmp_path / "old.db"
    old.write_bytes(site.path.read_bytes())
    con = sqlite3.connect(old)
    con.execute("PRAGMA user_version = 99")
    con.close()
    with pytest.raises(SiteFileError, match="old.db: format version 99"):
        Site.open(old)
    cut = tmp_path / "cut.db"
    data = site.path.read_bytes()
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(SiteFileError, match="cut.db: damaged"):
        Site.open(cut).floor_models(FLOOR)
    with pytest.raises(SiteFileError, match="missing.db: not found"):
        Site.open(tmp_path / "missing.db")


def test_unknown_floor_and_walk_without_waypoints(built, tmp_path, floor_dir):
    from indoorloc.fusion.site import Site
    from indoorloc.io.ilc2020 import read_ilc_walk

    site, paths = built
    with pytest.raises(ValueError, match="'F3' is not in site"):
        site.track(paths[-1], floor="F3")
    other = read_ilc_walk(next((floor_dir.parent / "F1" / "path_data_files").glob("*.txt")))
    with pytest.raises(ValueError, match=r"its floor 'F1' is not in site .*floor='auto'"):
        site.track(other)
    from indoorloc.io.errors import RecordingWarning

    # A floor whose only walk has no waypoints: build refuses, naming the floor and the file; the
    # old site stays.
    bare = tmp_path / "bare" / FLOOR / "path_data_files"
    bare.mkdir(parents=True)
    for name in ("geojson_map.json", "floor_info.json"):
        (bare.parent / name).write_bytes((floor_dir / name).read_bytes())
    lines = paths[0].read_text().splitlines(keepends=True)
    (bare / "nowaypoints.txt").write_text("".join(l for l in lines if "TYPE_WAYPOINT" not in l))
    before = site.path.read_bytes()
    with pytest.warns(RecordingWarning, match="nowaypoints.txt skipped"):
        with pytest.raises(ValueError, match=rf"floor {FLOOR} has no survey walk .*nowaypoints.txt: 0 waypoint\(s\); "
                                             r"a survey walk needs at least 2"):
            Site.build(tmp_path / "bare", site.path)
    assert site.path.read_bytes() == before
    with pytest.raises(ValueError, match="nowaypoints.txt: 0 waypoint"):
        site.add([bare / "nowaypoints.txt"])
    # An unreadable walk file, or one cut short before its second waypoint, is skipped with a
    # warning and listed (the loader rule), not fatal.
    good = tmp_path / "good" / FLOOR / "path_data_files"
    good.mkdir(parents=True)
    for name in ("geojson_map.json", "floor_info.json"):
        (good.parent / name).write_bytes((floor_dir / name).read_bytes())
    (good / paths[0].name).symlink_to(paths[0])
    (good / paths[1].name).symlink_to(paths[1])
    (good / "broken.txt").write_text("1574231797021\tTYPE_ACCELEROMETER\tnot-a-number\t1\t2\t3\n")
    first_waypoint = next(i for i, l in enumerate(lines) if "TYPE_WAYPOINT" in l)
    (good / "cut_short.txt").write_text("".join(lines[:first_waypoint + 1]))  # one waypoint, then the end
    with pytest.warns(RecordingWarning) as said:
        g = Site.build(tmp_path / "good", tmp_path / "good.db")
    assert sorted(str(w.message).split(" skipped:")[0].rsplit("/", 1)[1] for w in said) == ["broken.txt", "cut_short.txt"]
    skipped = g.info()["meta"]["skipped_walks"]
    assert "broken.txt" in skipped and "cut_short.txt: 1 waypoint(s)" in skipped and len(g.info()["walks"]) == 2
    # ... but it can be tracked (no errors printed for it).
    track = site.track(bare / "nowaypoints.txt")
    assert track.errors_m is None and track.xy_m.shape[1] == 2


def test_grow_places_walks_without_waypoints(built, tmp_path):
    """site grow: a walk's fingerprints placed by the track where confident, stored as 'grown' at
    the given weight; the grown site tracks; bad arguments and a failing walk leave the file as it was."""
    from indoorloc.fusion.site import Site

    site, paths = built
    walk = paths[N_SURVEY + 3]
    bare = tmp_path / "bare.txt"
    bare.write_text("".join(l for l in walk.read_text().splitlines(keepends=True) if "TYPE_WAYPOINT" not in l))
    before = site.info()
    with pytest.raises(ValueError, match="argument 'weight'"):
        site.grow([bare], weight=0.0)
    with pytest.raises(ValueError, match="already in the site"):
        site.grow([bare, paths[0]])
    assert site.info()["walks"] == before["walks"]
    added = site.grow([bare], max_sd_m=1e6, weight=0.25)
    assert list(added) == ["bare"] and added["bare"] > 0
    info = Site.open(site.path).info()
    assert info["walks"][-1]["kind"] == "grown" and info["walks"][-1]["weight"] == 0.25
    assert info["floors"][FLOOR]["fingerprints"] == before["floors"][FLOOR]["fingerprints"] + added["bare"]
    db = Site.open(site.path).floor_models(FLOOR).database
    assert db.weights is not None and set(np.unique(db.weights)) == {0.25, 1.0}
    # A strict threshold places fewer fingerprints than a loose one.
    strict = tmp_path / "strict.db"
    strict.write_bytes(site.path.read_bytes())
    bare2 = tmp_path / "bare2.txt"
    bare2.write_text(bare.read_text())
    assert Site.open(strict).grow([bare2], max_sd_m=0.5)["bare2"] < added["bare"]
    assert np.all(np.isfinite(Site.open(site.path).track(paths[-1]).xy_m))


_KILLED_ADD = """
import sys, time
from pathlib import Path
from indoorloc.fusion.site import Site
site = Site.open(sys.argv[1])
def hold(walk_id):  # inside the transaction, after the first walk's rows are written
    Path(sys.argv[2]).write_text(walk_id)
    time.sleep(60)
site.add([Path(p) for p in sys.argv[3:]], progress=hold)
"""


def test_killed_add_leaves_the_old_content(built, tmp_path):
    from indoorloc.fusion.site import Site

    site, paths = built
    before = site.info()
    flag = tmp_path / "inside"
    # The child imports the package this test imported (installed, or the source tree with its
    # built module), not the source tree alone, which has no compiled _core after a plain install.
    import indoorloc

    package_root = str(Path(indoorloc.__file__).resolve().parents[1])
    env = dict(os.environ, PYTHONPATH=package_root + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-c", _KILLED_ADD, str(site.path), str(flag),
                             str(paths[N_SURVEY]), str(paths[N_SURVEY + 1])], env=env)
    try:
        deadline = time.monotonic() + 120
        while not flag.exists():
            assert proc.poll() is None, "the add process ended before writing"
            assert time.monotonic() < deadline, "the add process did not reach the write"
            time.sleep(0.1)
        assert Path(str(site.path) + "-journal").exists()  # mid-transaction
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    after = Site.open(site.path)
    assert after.info()["walks"] == before["walks"]
    assert after.info()["floors"] == before["floors"]
    np.testing.assert_array_equal(after.track(paths[-1]).xy_m, site.track(paths[-1]).xy_m)


def test_cli_build_info_track(tmp_path, floor_dir, capsys):
    from indoorloc.cli import main

    paths = _walk_paths(floor_dir)
    survey = _survey(tmp_path, floor_dir, paths[:3])
    db = tmp_path / "s.db"
    assert main(["--quiet", "site", "build", str(survey), "-o", str(db), "--coverage", str(tmp_path / "cov")]) == 0
    assert (tmp_path / "cov" / f"coverage_{FLOOR}.png").stat().st_size > 0
    assert "| F8 | 3 |" in capsys.readouterr().out
    assert main(["site", "info", str(db), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["floors"][FLOOR]["walks"] == 3
    out = tmp_path / "t.json"
    assert main(["--quiet", "track", str(paths[5]), "--site", str(db), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "error at" in printed and "mean" in printed and "p90" in printed
    doc = json.loads(out.read_text())
    assert doc["format"] == "indoorloc.track" and doc["version"] == 1
    w = doc["walks"][0]
    assert w["floor"] == FLOOR and len(w["t_s"]) == len(w["x_m"]) == len(w["sd_x_m"]) > 0
    assert w["errors"]["n_waypoints"] == len(w["waypoints"]["t_s"])
    gj = tmp_path / "t.geojson"
    assert main(["--quiet", "track", str(paths[5]), "--site", str(db), "--no-smooth", "-o", str(gj)]) == 0
    feat = json.loads(gj.read_text())["features"][0]
    lon, lat = np.asarray(feat["geometry"]["coordinates"]).T
    assert 120.0 < lon.min() < lon.max() < 120.2 and 30.2 < lat.min() < lat.max() < 30.4
    assert feat["properties"]["smoothed"] is False and feat["properties"]["floor"] == FLOOR
    csv = tmp_path / "t.csv"
    html = tmp_path / "view.html"
    assert main(["--quiet", "track", str(paths[5]), str(paths[6]), "--site", str(db), "-o", str(csv),
                 "--html", str(html)]) == 0
    page = html.read_text()
    # One offline page (the viewer's own browser test drives it): both walks and the floor in it.
    assert page.startswith("<!DOCTYPE html>") or "<html" in page[:500]
    assert FLOOR in page and "surveyed waypoints" in page and "WiFi fixes" in page
    assert 'src="http' not in page
    head = csv.read_text().splitlines()
    assert head[0].startswith("walk,t_s,unix_ms,x_m,y_m,floor,sd_x_m,sd_y_m,floor_probability")
    assert main(["--quiet", "track", str(paths[5]), "--site", str(db), "-o", str(tmp_path / "t.txt")]) == 2
    assert "extension" in capsys.readouterr().err
    # A walk that cannot be tracked (an empty file) is named and costs the others nothing: their
    # tracks are written, and the exit status is 1; with none tracked, nothing is written and it is 2.
    empty = tmp_path / "empty.txt"
    empty.write_text("")
    both = tmp_path / "both.json"
    assert main(["--quiet", "track", str(paths[5]), str(empty), "--site", str(db), "-o", str(both)]) == 1
    err = capsys.readouterr().err
    assert f"walk {empty} not tracked" in err and "1 of 2 walks not tracked" in err
    assert [w["source"] for w in json.loads(both.read_text())["walks"]] == [str(paths[5])]
    none = tmp_path / "none.json"
    assert main(["--quiet", "track", str(empty), "--site", str(db), "-o", str(none)]) == 2
    assert "nothing written" in capsys.readouterr().err and not none.exists()


def test_cli_track_says_when_no_wifi_fix_was_available(tmp_path, floor_dir, capsys):
    """A walk without a WiFi fix (its first 20 s, cut before any scan was reported) is tracked but
    not located: the summary line and the JSON say that no fix was available, and the sds written
    are the floor-wide prior's (large), not a located track's."""
    from indoorloc.cli import main

    paths = _walk_paths(floor_dir)
    survey = _survey(tmp_path, floor_dir, paths[:3])
    db = tmp_path / "s.db"
    assert main(["--quiet", "site", "build", str(survey), "-o", str(db)]) == 0
    lines = paths[5].read_text().splitlines(keepends=True)
    t0 = next(int(ln.split("\t")[0]) for ln in lines if ln[:1].isdigit())
    cut = [ln for ln in lines if not ln[:1].isdigit()
           or (int(ln.split("\t")[0]) < t0 + 20_000 and "TYPE_WIFI" not in ln)]
    walk = tmp_path / "no_wifi.txt"
    walk.write_text("".join(cut))
    out = tmp_path / "t.json"
    capsys.readouterr()
    assert main(["--quiet", "track", str(walk), "--site", str(db), "--floor", FLOOR, "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "no WiFi fix available" in printed and "not located" in printed
    w = json.loads(out.read_text())["walks"][0]
    assert w["wifi_fixes"] == 0 and len(w["t_s"]) > 0
    assert np.median(w["sd_x_m"]) > 10.0   # the floor-wide prior's (F8: about 17 m)
    # A walk with WiFi: its fixes counted, and no such note.
    assert main(["--quiet", "track", str(paths[5]), "--site", str(db), "--floor", FLOOR, "-o", str(out)]) == 0
    assert "no WiFi fix" not in capsys.readouterr().out
    assert json.loads(out.read_text())["walks"][0]["wifi_fixes"] > 0


def test_site_live_replays_the_causal_track(built):
    """Site.live(): a held-out walk replayed event by event gives the causal track of the site's
    own models (fusion.live.causal_track), step for step, bit for bit."""
    from indoorloc.fusion import live
    from indoorloc.io import read_ilc_walk

    site, paths = built
    walk = read_ilc_walk(paths[-1])
    m = site.floor_models(FLOOR)
    batch = live.causal_track(m.tracker, walk, m.calibration, m.database,
                              step_length_sd_fraction=site.settings.step_length_sd_fraction,
                              step_heading_sd_rad=site.settings.step_heading_sd_rad)
    tracker = site.live(FLOOR)
    out = []
    for ev in live.walk_events(walk, beacons=True):
        e = tracker.add_event(*ev)
        if e is not None and (not out or out[-1].steps != e.steps):
            out.append(e)
    assert len(out) == len(batch["times_s"]) > 10
    np.testing.assert_array_equal(np.array([e.mean_m for e in out]), batch["mean_m"])
    np.testing.assert_array_equal(np.array([e.covariance_m2 for e in out]), batch["covariance_m2"])
    with pytest.raises(ValueError, match="floor"):
        site.live("F99")


def test_cli_live_streams_the_live_track_from_events_or_a_walk(built, tmp_path, capsys):
    """``indoorloc live``: a recorded walk (--walk) and the same walk's events as NDJSON lines
    (--events) give the same estimates, those of the live tracker (the causal track, one line per
    filter step, bit for bit through JSON); a line that is not an event, or an event out of time
    order, is named with its line number and skipped, the estimates unchanged, exit status 1."""
    from indoorloc.cli import main
    from indoorloc.fusion import live, live_stream
    from indoorloc.io import read_ilc_walk

    site, paths = built
    db = str(site.path)
    walk = read_ilc_walk(paths[-1])
    m = site.floor_models(FLOOR)
    batch = live.causal_track(m.tracker, walk, m.calibration, m.database,
                              step_length_sd_fraction=site.settings.step_length_sd_fraction,
                              step_heading_sd_rad=site.settings.step_heading_sd_rad)
    out_walk = tmp_path / "walk.ndjson"
    assert main(["--quiet", "live", "--site", db, "--walk", str(paths[-1]), "-o", str(out_walk)]) == 0
    rows = [json.loads(line) for line in out_walk.read_text().splitlines()]
    assert rows[0] == {"format": "indoorloc-live", "version": 1, "floor": FLOOR,
                       "origin_lon_lat": list(m.origin_lon_lat)}
    est = rows[1:]
    assert len(est) == len(batch["times_s"]) > 10
    np.testing.assert_array_equal([r["position_m"] for r in est], batch["mean_m"])
    np.testing.assert_array_equal([r["t_s"] for r in est], batch["times_s"])
    np.testing.assert_array_equal([r["located"] for r in est], batch["located"])
    assert set(est[-1]) == {"t_s", "steps", "fixes", "located", "position_m", "covariance_m2", "lon_lat",
                            "heading_offset_rad"}
    # The same events as lines, with a broken line and an event out of time order among them.
    events = [json.dumps(live_stream.event_record(*ev)) for ev in live.walk_events(walk, beacons=True)]
    k = len(events) // 2
    late = json.dumps({"kind": "gyroscope", "t_s": -1.0, "values": [0, 0, 0]})
    lines = events[:k] + ["{not json", late, "", "# a comment"] + events[k:]
    src = tmp_path / "events.ndjson"
    src.write_text("\n".join(lines) + "\n")
    out_events = tmp_path / "events_out.ndjson"
    assert main(["live", "--site", db, "--events", str(src), "-o", str(out_events)]) == 1
    err = capsys.readouterr().err
    assert f"line {k + 1}: skipped: not JSON" in err and f"line {k + 2}: skipped:" in err
    assert "out of time order" in err and "2 lines skipped" in err
    assert out_events.read_text() == out_walk.read_text()
    # Malformed fields are named.
    for bad, why in [({"kind": "wifi", "t_s": 1.0, "bssids": ["a"], "rssi_dbm": [], "last_seen_s": [1.0]}, "'rssi_dbm'"),
                     ({"kind": "magnetometer", "t_s": 1.0}, "'kind'"),
                     ({"kind": "accelerometer", "t_s": float("nan"), "values": [0, 0, 9.8]}, "'t_s'"),
                     ({"kind": "accelerometer", "t_s": 1.0, "values": [0, 9.8]}, "'values'")]:
        with pytest.raises(ValueError, match=why):
            live_stream.parse_event(json.dumps(bad))
    assert main(["--quiet", "live", "--site", db, "--floor", "F99", "--walk", str(paths[-1])]) != 0
    assert "F99" in capsys.readouterr().err
    # Events that cannot place the phone (IMU lying still, no scan): exit 2, no file that looks
    # like a track; a missing events file names the argument.
    still = tmp_path / "still.ndjson"
    still.write_text("".join(json.dumps(live_stream.event_record(kind, 1.0 + i / 50, np.array(v))) + "\n"
                             for i in range(200) for kind, v in (("gyroscope", [0, 0, 0]),
                                                                 ("rotation_vector", [0, 0, 0, 1]),
                                                                 ("accelerometer", [0, 0, 9.81]))))
    none = tmp_path / "none.ndjson"
    assert main(["--quiet", "live", "--site", db, "--events", str(still), "-o", str(none)]) == 2
    assert not none.exists() and "no estimate" in capsys.readouterr().err
    assert main(["--quiet", "live", "--site", db, "--events", str(tmp_path / "absent.ndjson")]) == 2
    assert "argument '--events'" in capsys.readouterr().err

