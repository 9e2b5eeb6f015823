"""The fusion group of property_cases.py (run it as ``python property_cases.py fusion``): floor
plans and their GeoJSON, the tracker's options, its stateful calls and the batch API, fingerprint
fixes, and the synthetic building and walk."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from property_harness import Case, probe, same_for_threads

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
    geometry, plan, model, outline, block, walls = _room()
    _floor_plan_cases(geometry, plan, outline, block, walls)
    _geojson_cases(geometry)
    _tracker_cases(plan, model)
    _fingerprint_fix_cases()
    _simulation_cases()


def _floor_plan_cases(geometry, plan, outline, block, walls) -> None:
    """The floor plan: its geometry, options, queries (the room of _room)."""
    from indoorloc import fusion

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


def _geojson_cases(geometry) -> None:
    """Floor plans written to and read from GeoJSON."""
    from indoorloc import io as iio

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


def _tracker_cases(plan, model) -> None:
    """The tracker: its options, its stateful calls on a fresh tracker each, the steps and fixes
    containers, and the batch API with the smoother."""
    from indoorloc import fusion
    from indoorloc._core import fusion as cf

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


def _fingerprint_fix_cases() -> None:
    """Fingerprint fixes (wifi_fixes): the settings and the dissimilarities."""
    from indoorloc.fusion import wifi_fixes

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


def _simulation_cases() -> None:
    """The synthetic building and walk (seeded; small configurations)."""
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
