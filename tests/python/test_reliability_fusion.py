"""Regression tests of issue 17 for the fusion subsystem (found by test_properties_fusion.py):
options checked through the core validation vocabulary, argument names in every message, size
limits, and the batch API's dict/tuple arguments."""

import re

import numpy as np
import pytest

from indoorloc import fusion
from indoorloc._core import fusion as cf


def _plan():
    outline = np.array([[0, 0], [20, 0], [20, 10], [0, 10]], float)
    block = np.array([[8, 3], [12, 3], [12, 7], [8, 7]], float)
    return fusion.FloorPlan([fusion.FloorGeometry(0, [outline], [block])])


def _track(**changes):
    n = 4
    kwargs = dict(plan=_plan(), wifi_model=None, corridors=None, step_times_s=0.5 * np.arange(1, n + 1),
                  displacements_m=np.tile([0.0, 0.7], (n, 1)), covariances_m2=np.tile([0.01, 0.0, 0.01], (n, 1)),
                  observations=[], start={"position_m": np.array([2.0, 1.5])},
                  options=fusion.tracker_options(num_particles=100), smoother=None, fixes=None)
    kwargs.update(changes)
    return cf.track(**kwargs)


@pytest.mark.parametrize("field, value, rule", [
    ("position_noise_m", 1e-300, "position_noise_m must be in"),   # 1/σ² was inf
    ("position_noise_m", float("nan"), "position_noise_m must be in"),
    ("min_scale", 2.0, "min_scale must be <= max_scale"),
    ("tempering", float("nan"), "tempering must be in (0, 1]"),
    ("max_term", float("nan"), "max_term must be > 0"),
    ("fix_tempering", 2.0, "fix_tempering must be in (0, 1]"),       # was "fix: tempering ..."
    ("fix_outlier_probability", 1.0, "fix_outlier_probability must be in (0, 1)"),
    ("ess_threshold", float("nan"), "ess_threshold must be in [0, 1]"),
    ("respread_sd_m", 1e300, "respread_sd_m must be finite and in"),
    ("start_position_sd_m", 1e300, "start_position_sd_m must be 0 or in"),
    ("start_scale_sd", 1e300, "start_scale_sd must be in [0, 100]"),
    ("unknown_start_heading_sd_rad", float("nan"), "unknown_start_heading_sd_rad must be in"),
    ("recovery_log_ratio", 1e300, "recovery_log_ratio must be in"),
    ("recovery_scans", 2**31 - 1, "recovery_scans must be in [1, 1000000]"),
    ("respread_after_blocked_steps", 2**31 - 1, "respread_after_blocked_steps must be in"),
])
def test_tracker_options_name_the_flattened_field_value_and_rule(field, value, rule):
    with pytest.raises(ValueError) as info:
        fusion.tracker_options(**{field: value})
    assert rule in str(info.value)
    assert "got" in str(info.value)


def test_tracker_options_wrong_type_names_the_field():
    with pytest.raises(TypeError, match="argument 'num_particles'"):
        fusion.tracker_options(num_particles="many")


def test_floor_plan_and_smoother_options_limits():
    with pytest.raises(ValueError, match="cell_size_m must be <= 0 .automatic. or in"):
        fusion.FloorPlanOptions(cell_size_m=1e300)
    with pytest.raises(ValueError, match="options.cell_size_m.*more than options.max_cells"):
        fusion.FloorPlan([fusion.FloorGeometry(0, [np.array([[0, 0], [20, 0], [20, 10], [0, 10]], float)])],
                         fusion.FloorPlanOptions(cell_size_m=1e-300))
    with pytest.raises(ValueError, match="target_edges_per_cell must be in"):
        fusion.FloorPlanOptions(target_edges_per_cell=1e300)
    with pytest.raises(ValueError, match=r"max_cells must be in \[1, 100000000\]"):
        fusion.FloorPlanOptions(max_cells=2**31 - 1)
    with pytest.raises(ValueError, match="max_particles"):
        fusion.SmootherOptions(num_trajectories=100000, max_particles=50000000)


def test_sample_walkable_refuses_more_than_the_memory_limit():
    with pytest.raises(ValueError, match="argument 'n': .* points would need .* GB"):
        _plan().sample_walkable(2**31 - 1)


def test_track_start_smoother_and_fixes_arguments_are_named():
    with pytest.raises(ValueError, match="argument 'start': expected None or a dict"):
        _track(start="here")
    with pytest.raises(ValueError, match="argument 'start': a known start needs 'position_m'"):
        _track(start={"floor": 0})  # was KeyError
    with pytest.raises(ValueError, match="argument 'start': unknown key 'postion_m'"):
        _track(start={"postion_m": [2.0, 1.5]})
    with pytest.raises(ValueError, match=r"argument 'start\['time_s'\]': expected a real number"):
        _track(start={"position_m": [2.0, 1.5], "time_s": "soon"})  # was RuntimeError (cast)
    with pytest.raises(ValueError, match=r"argument 'start\['time_s'\]': must be finite"):
        _track(start={"position_m": [2.0, 1.5], "time_s": float("nan")})
    with pytest.raises(ValueError, match=r"argument 'start\['floor'\]'"):
        _track(start={"position_m": [2.0, 1.5], "floor": 2**40})
    with pytest.raises(ValueError, match="argument 'smoother': expected None or a SmootherOptions"):
        _track(smoother=3)  # was RuntimeError (cast)
    with pytest.raises(ValueError, match="argument 'fixes': expected None or"):
        _track(fixes=[1.0])  # was RuntimeError (cast)
    with pytest.raises(ValueError, match="argument 'plan': must be None or a FloorPlan"):
        _track(plan="a plan")
    result = _track()
    assert np.isfinite(result["mean_m"]).all()


def _in_child(code: str, timeout: float = 60.0) -> str:
    """Runs `code` in a fresh interpreter (these calls used to hang or fill the memory)."""
    import subprocess
    import sys
    import textwrap

    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                          timeout=timeout)
    assert proc.returncode == 0, f"exit {proc.returncode}\n{proc.stdout}\n{proc.stderr[-3000:]}"
    return proc.stdout


def test_floor_plan_coordinates_are_bounded_instead_of_hanging():
    # An outline vertex at 1e300 made the grid registration walk ~1e150 cells.
    out = _in_child("""
        import numpy as np
        from indoorloc import fusion
        ring = np.array([[0.0, 0.0], [1e300, 0.0], [1.0, 1.0], [0.0, 1.0]])
        try:
            fusion.floor_plan_from_polygons(ring)
        except ValueError as e:
            assert "outlines" in str(e) and "1e+07" in str(e) and "1e+300" in str(e), e
            print("ok")
    """, timeout=30.0)
    assert out.strip() == "ok"


def test_synthetic_building_bounds_its_counts():
    # num_floors = 2**31 built one FloorGeometry per floor until the memory ran out.
    out = _in_child("""
        from indoorloc.simulate.building import BuildingConfig, make_building
        for field, value in (("num_floors", 2**31), ("num_pillars", 10**9), ("position_jitter_m", float("nan"))):
            try:
                make_building(1, BuildingConfig(**{field: value}))
            except ValueError as e:
                assert f"config.{field}" in str(e), e
            else:
                raise SystemExit(field)
        print("ok")
    """, timeout=60.0)
    assert out.strip() == "ok"


def test_polygon_helpers_refuse_strings_instead_of_recursing():
    for bad in ("x", np.array(["a"] * 8)):
        with pytest.raises(TypeError, match="argument 'outlines'"):
            fusion.floor_geometry(bad)  # was RecursionError
    with pytest.raises(ValueError, match="argument 'outlines'.*complex"):
        fusion.floor_geometry(np.array([[0, 0], [1, 0], [1, 1]], complex))  # was a silent cast


def test_python_helpers_name_their_arguments():
    with pytest.raises(ValueError, match="argument 'means_m': must be finite where the weight is > 0"):
        fusion.Fixes.from_arrays([1.0], [[np.nan, 2.0]], [2.0])
    with pytest.raises(TypeError, match="argument 'steps'"):
        fusion.track("steps")
    with pytest.raises(TypeError, match="argument 'floors'"):
        fusion.floor_plan_from_geometries(3.0)
    with pytest.raises(ValueError, match=r"argument 'fix.sds_m': entry 0 must be finite and in \[1e-12"):
        t = cf.ParticleTracker(_plan(), None, None, fusion.tracker_options(num_particles=50))
        t.initialize_known(0.0, [2.0, 1.5], 0, 0.0)
        t.fix(1.0, np.array([[2.0, 2.0]]), np.array([1e-300]), np.array([1.0]))  # 1/sd² was inf: NaN mean


# ---- Issue 28 ------------------------------------------------------------------------------

def _comb(teeth):
    w = 1.0 / (2 * teeth)
    pts = [(0.0, 0.0)]
    for t in range(teeth):
        x0, x1 = 2 * t * w, (2 * t + 1) * w
        if t > 0:
            pts.append((x0, 0.1))
        pts += [(x0, 1.0), (x1, 1.0), (x1, 0.1)]
    pts += [(1.0, 0.1), (1.0, 0.0)]
    return np.array(pts)


def _star(n, r_out, r_in=1.0):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = np.where(np.arange(n) % 2 == 0, r_out, r_in)
    return np.c_[r * np.cos(a), r * np.sin(a)]


@pytest.mark.parametrize("shape", ["comb", "star"])
def test_floor_plan_construction_work_is_e_log_e(shape):
    # Work is counted, not timed (build_statistics): the self-intersection sweep's exact
    # predicate evaluations stay within c E log2 E over a 16x range of sizes, and the index
    # (registrations) within its budget, where the old per-cell test was quadratic (a comb of
    # 1e5 teeth in 1 m: 135 s) and a star registered every long edge in hundreds of cells.
    ratios = []
    for n in (1000, 4000, 16000):
        ring = _comb(n // 4) if shape == "comb" else _star(n, 50.0)
        plan = fusion.FloorPlan([fusion.FloorGeometry(0, [ring], [], None)])
        s = plan.build_statistics(0)
        e = s["edges"]
        ratios.append(s["self_intersection_work"] / (e * np.log2(e)))
        assert s["index_bytes"] <= max(64e6, 1024 * e)
        assert s["area_edge_visits"] <= 2e7
    assert max(ratios) <= 6.0
    assert ratios[-1] <= 1.5 * ratios[0]  # no growth beyond log E


def test_floor_plan_index_memory_is_refused_with_the_bytes():
    square = np.array([[0, 0], [999.8, 0], [999.8, 999.8], [0, 999.8]], float)
    opts = fusion.FloorPlanOptions(cell_size_m=0.1, max_cells=100_000_000)
    with pytest.raises(ValueError, match=r"options.cell_size_m.*GB \(limit 4 GB\)"):
        fusion.FloorPlan([fusion.FloorGeometry(0, [square], [], None)], opts)


def test_memory_bounds_are_checked_before_allocating():
    plan = _plan()
    with pytest.raises(ValueError, match=r"'options'.*particles.*GB \(limit 4 GB\)"):
        fusion.ParticleTracker(plan, None, None, fusion.tracker_options(num_particles=50_000_000))
    with pytest.raises(ValueError, match=r"smoothing_lag_steps = 10000.*TB"):
        fusion.ParticleTracker(plan, None, None,
                               fusion.tracker_options(num_particles=5_000_000, smoothing_lag_steps=10_000))
    with pytest.raises(ValueError, match=r"recorded particles.*GB"):
        _track(options=fusion.tracker_options(num_particles=40_000_000), smoother=fusion.SmootherOptions())
    # 1e8 readings: refused from the shape (a zero-stride view: nothing is copied first).
    rss = np.broadcast_to(np.float64(-60.0), (10_000, 10_000))
    with pytest.raises(ValueError, match=r"'rss_dbm'.*1e\+08 readings.*GB"):
        fusion.make_wifi_observations(np.arange(10_000.0), rss)


def test_streaming_events_must_not_go_back_in_time():
    t = fusion.ParticleTracker(_plan(), None, None, fusion.tracker_options(num_particles=50))
    with pytest.raises(RuntimeError, match="not initialised"):
        t.estimate()
    t.initialize_known(1.0, np.array([2.0, 2.0]), 0, 0.0)
    assert t.estimate().time_s == 1.0
    with pytest.raises(ValueError, match=r"'fix.time_s'.*back in time"):
        t.fix(0.5, np.array([[2.0, 2.0]]), np.array([1.0]), np.array([1.0]))
    t.step(2.0, np.array([0.5, 0.0]), 0.01 * np.eye(2))
    t.fix(3.0, np.array([[2.5, 2.0]]), np.array([1.0]), np.array([1.0]))
    with pytest.raises(ValueError, match=r"'step.time_s'"):
        t.step(2.5, np.array([0.5, 0.0]), 0.01 * np.eye(2))


def test_wifi_observation_refuses_non_finite_time_and_rss():
    with pytest.raises(ValueError, match="'time_s'"):
        fusion.WifiObservation(float("nan"), [0], [-50.0])
    with pytest.raises(ValueError, match="'time_s'"):
        fusion.WifiObservation(float("inf"), [0], [-50.0])
    with pytest.raises(ValueError, match=r"'rss_dbm'.*entry 1"):
        fusion.WifiObservation(1.0, [0, 1], [-50.0, float("nan")])
    with pytest.raises(ValueError, match=r"'access_points'"):
        fusion.WifiObservation(1.0, [-1], [-50.0])


def test_set_particles_refuses_absurd_states():
    t = fusion.ParticleTracker(_plan(), None, None, fusion.tracker_options(num_particles=10))
    good = np.array([[3.0, 3.0, 0.0, 1.0], [4.0, 3.0, 0.1, 1.0]])
    floors = np.zeros(2, np.int32)
    t.set_particles(good, floors)
    for row, col, value, words in [(1, 0, 1e300, "entry (1, 0)"), (0, 2, 1e300, "heading offset"),
                                   (1, 3, 1e6, "scale"), (0, 3, 0.0, "scale")]:
        bad = good.copy()
        bad[row, col] = value
        with pytest.raises(ValueError, match=r"'states'.*" + re.escape(words)):
            t.set_particles(bad, floors)
    inside = good.copy()
    inside[0, :2] = (10.0, 5.0)  # inside the block, hard walls
    with pytest.raises(ValueError, match=r"'states'.*not walkable"):
        t.set_particles(inside, floors)
    assert np.all(np.isfinite(t.estimate().covariance_m2))


def test_track_skips_steps_before_a_known_start():
    n = 8
    times = 0.5 * np.arange(1, n + 1)
    start = {"position_m": np.array([2.0, 1.5]), "time_s": 2.2}
    r = _track(step_times_s=times, displacements_m=np.tile([0.0, 0.7], (n, 1)),
               covariances_m2=np.tile([0.01, 0.0, 0.01], (n, 1)), start=start,
               smoother=fusion.SmootherOptions(num_trajectories=10))
    assert r["summary"].steps == n - 4
    np.testing.assert_allclose(r["mean_m"][:4], np.tile([2.0, 1.5], (4, 1)), atol=0.2)
    np.testing.assert_allclose(r["smoothed_m"][:4], r["mean_m"][:4])
    assert r["smoothed_m"].shape == (n, 2)
    assert abs(r["mean_m"][-1, 1] - (1.5 + 0.7 * (n - 4))) < 0.4


def test_floor_plan_from_geometries_refuses_lossy_conversions():
    from types import SimpleNamespace
    ring = [[0, 0], [5, 0], [5, 5], [0, 5]]
    ok = fusion.floor_plan_from_geometries([SimpleNamespace(floor=2.0, outlines=[ring], obstacles=[], walls=None)])
    assert ok.floors == [2]
    with pytest.raises(ValueError, match=r"'floors\[0\].floor'"):
        fusion.floor_plan_from_geometries([SimpleNamespace(floor=1.7, outlines=[ring], obstacles=[], walls=None)])
    with pytest.raises(TypeError, match=r"'floors\[0\].floor'"):
        fusion.floor_plan_from_geometries([SimpleNamespace(floor="2", outlines=[ring], obstacles=[], walls=None)])
    complex_ring = np.array(ring, complex) + 1j
    with pytest.raises(ValueError, match=r"'floors\[0\].outlines\[0\]'.*complex"):
        fusion.floor_plan_from_geometries([SimpleNamespace(floor=0, outlines=[complex_ring], obstacles=[],
                                                           walls=None)])


def test_write_geojson_floor_refuses_nan_and_writes_atomically(tmp_path):
    from indoorloc.io.floor_plan import read_geojson_floor, write_geojson_floor
    ring = np.array([[0, 0], [5, 0], [5, 5], [0, 5]], float)
    path = tmp_path / "floor.geojson"
    write_geojson_floor(path, fusion.FloorGeometry(0, [ring], [], None))
    before = path.read_bytes()
    bad = ring.copy()
    bad[1, 0] = np.nan

    class Geometry:  # FloorGeometry itself refuses NaN: a record with the same fields
        floor, outlines, obstacles, walls = 0, [bad], [], np.zeros((0, 4))

    with pytest.raises(ValueError, match=r"'geometry.outlines\[0\]'.*NaN"):
        write_geojson_floor(path, Geometry())
    assert path.read_bytes() == before  # the old file is untouched
    assert [p.name for p in tmp_path.iterdir()] == ["floor.geojson"]  # no temporary left
    read_geojson_floor(path)


def test_wifi_helpers_refuse_non_finite_arguments_and_name_the_query():
    from types import SimpleNamespace

    from indoorloc.fusion import crowdsourced_map, wifi_fixes

    with pytest.raises(ValueError, match="not_heard_dbm"):
        crowdsourced_map.prepare(np.array([[-60.0, np.nan]]), np.nan)
    with pytest.raises(ValueError, match="rss_dbm"):
        crowdsourced_map.prepare(np.array([[-np.inf, -50.0]]), -100.0)
    assert crowdsourced_map.prepare(np.array([[np.nan, -50.0]]), -100.0).tolist() == [[-100.0, -50.0]]
    for bad in (np.nan, -1.0, "2"):
        with pytest.raises(ValueError, match="fresh_age_s"):
            crowdsourced_map.scan_epochs(SimpleNamespace(), bad)
    rss = np.array([[-50.0, -60.0], [-70.0, np.nan], [-55.0, -65.0], [-52.0, -61.0]])
    xy = np.array([[0.0, 0.0], [5.0, 0.0], [10.0, 0.0], [0.5, 0.0]])
    db = wifi_fixes.assemble_database([(rss, xy, ["a", "b"], np.zeros(4, int), np.arange(4))],
                                      wifi_fixes.FixSettings(k=2))
    with pytest.raises(ValueError, match="'rss_dbm'.*\\(Q, 2\\)"):
        wifi_fixes.locate_scans(np.array([[-50.0, -60.0, -70.0]]), db)
    with pytest.raises(ValueError, match="rss_dbm"):
        wifi_fixes.locate_scans(np.array([[np.inf, -60.0]]), db)
    # A scan that heard none of the database's APs cannot be placed: NaN (documented), the rest finite.
    out = wifi_fixes.locate_scans(np.array([[-50.0, -60.0], [np.nan, np.nan]]), db)
    assert np.isfinite(out[0]).all() and np.isnan(out[1]).all()


def test_scan_matrix_of_a_walk_that_heard_none_of_the_maps_aps_is_all_nan():
    from types import SimpleNamespace

    from indoorloc.fusion import crowdsourced_map
    from indoorloc.io.ilc2020 import IlcWifi

    wf = IlcWifi(np.array([1.0, 1.0, 3.0]), np.array([0, 1, 0]), np.array([-50.0, -60.0, -55.0]),
                 np.full(3, 2412.0), np.array([0.9, 0.5, 2.9]), ["a", "b"], ["", ""], np.array([0, 2]))
    walk = SimpleNamespace(wifi=wf)
    for bssids, kw in ((["zz"], {}), (["a"], {"max_age_s": 1e-9})):
        t, rss, ages = crowdsourced_map.scan_matrix(walk, bssids, **kw)
        assert t.tolist() == [1.0, 3.0] and rss.shape == (2, 1) and np.isnan(rss).all() and np.isnan(ages).all()
    t, rss, _ = crowdsourced_map.scan_matrix(walk, ["a", "b"])
    assert rss.tolist() == [[-50.0, -60.0], [-55.0, np.nan]] or np.allclose(np.nan_to_num(rss), [[-50, -60], [-55, 0]])
