"""The fusion tracker from Python: bindings, batch API, bad input, determinism, synthetic accuracy."""

import math

import numpy as np
import pytest

from indoorloc import fusion, wifi
from indoorloc.experiments import fusion_synthetic as fs
from indoorloc.simulate.building import make_building
from indoorloc.simulate.walker import simulate_walk


def room_plan():
    outline = np.array([[0, 0], [20, 0], [20, 10], [0, 10]], float)
    block = np.array([[8, 3], [12, 3], [12, 7], [8, 7]], float)
    return fusion.FloorPlan([fusion.FloorGeometry(0, [outline], [block], np.array([[16, 0, 16, 7]], float))])


def room_model(floor=0):
    xs, ys = np.meshgrid(np.arange(21.0), np.arange(11.0))
    pos = np.c_[xs.ravel(), ys.ravel()]
    aps = np.array([[0, 0], [20, 0], [0, 10], [20, 10]], float)
    d = np.linalg.norm(pos[:, None, :] - aps[None], axis=2)
    mean = -40.0 - 25.0 * np.log10(d + 1.0)
    return wifi.RssModel(wifi.SignalMap(pos, np.full(len(pos), floor), mean, np.full_like(mean, 4.0))), aps


@pytest.fixture(scope="module")
def scenario():
    building = make_building(seed=3)
    return simulate_walk(building, seed=3)


def test_tracker_options_keywords_and_validation():
    o = fusion.tracker_options(num_particles=123, tempering=0.5)
    assert o.num_particles == 123 and o.tempering == 0.5
    with pytest.raises(ValueError, match="not_a_field"):
        fusion.tracker_options(not_a_field=1)
    with pytest.raises(ValueError, match="tempering"):
        fusion.tracker_options(tempering=2.0)
    with pytest.raises(ValueError, match="num_particles"):
        fusion.tracker_options(num_particles=0)


def test_steps_from_polar_and_rotation():
    steps = fusion.Steps.from_polar([0.5, 1.0], [0.7, 0.7], [0.0, math.pi / 2], 0.05, 0.1)
    np.testing.assert_allclose(steps.displacements_m, [[0.7, 0.0], [0.0, 0.7]], atol=1e-12)
    np.testing.assert_allclose(steps.covariances_m2[0], [0.05 ** 2, 0.0, 0.07 ** 2], atol=1e-12)
    np.testing.assert_allclose(fusion.rotate(steps.displacements_m, math.pi / 2), [[0.0, 0.7], [-0.7, 0.0]], atol=1e-12)


def test_steps_from_zupt_increments():
    inc = np.array([[0.7, 0.0, 0.01], [0.0, 0.7, -0.02]])
    cov = np.stack([np.eye(2) * 0.01, np.array([[0.02, 0.005], [0.005, 0.03]])])
    steps = fusion.Steps.from_increments([0.5, 1.0], inc, cov)
    np.testing.assert_array_equal(steps.displacements_m, inc[:, :2])
    np.testing.assert_array_equal(steps.covariances_m2, [[0.01, 0.0, 0.01], [0.02, 0.005, 0.03]])
    with pytest.raises(ValueError, match="increments_m"):
        fusion.Steps.from_increments([0.5], np.zeros((1, 4)), np.zeros((1, 3)))


def test_streaming_tracker_follows_perfect_steps_and_never_enters_obstacles():
    plan = room_plan()
    tracker = fusion.ParticleTracker(plan, options=fusion.tracker_options(num_particles=1500, seed=2,
                                                                           start_position_sd_m=0.2))
    tracker.initialize_known(0.0, [2.0, 1.5], 0, 0.0)
    truth = np.array([2.0, 1.5])
    cov = np.eye(2) * 0.02 ** 2
    for k in range(10):
        truth += [0.0, 0.7]
        est = tracker.step(0.5 * (k + 1), [0.0, 0.7], cov)
    for k in range(20):
        truth += [0.7, 0.0]
        est = tracker.step(5.0 + 0.5 * (k + 1), [0.7, 0.0], cov)
        states, floors, weights = tracker.particles()
        assert plan.is_walkable(states[:, :2]).all()
        assert np.isfinite(weights).all() and abs(weights.sum() - 1) < 1e-9
    assert np.linalg.norm(est.mean_m - truth) < 1.0
    assert tracker.summary.steps == 30


def test_bad_input_gives_clear_errors_and_no_ops():
    plan = room_plan()
    model, _ = room_model()
    tracker = fusion.ParticleTracker(plan, model, None, fusion.tracker_options(num_particles=200))
    with pytest.raises(ValueError, match="position_m.*not walkable"):
        tracker.initialize_known(0.0, [10.0, 5.0], 0, 0.0)  # inside the block
    with pytest.raises(ValueError, match="position_m.*not walkable"):
        tracker.initialize_known(0.0, [50.0, 5.0], 0, 0.0)  # outside the outline
    tracker.initialize_known(1.0, [3.0, 3.0], 0, 0.0)
    with pytest.raises(ValueError, match="displacement_m"):
        tracker.step(2.0, [np.nan, 0.0], np.eye(2) * 0.01)
    with pytest.raises(ValueError, match="displacement_m"):
        tracker.step(2.0, [0.1, 0.2, 0.3], np.eye(2) * 0.01)
    with pytest.raises(ValueError, match="negative time step"):
        tracker.step(0.5, [0.5, 0.0], np.eye(2) * 0.01)
    with pytest.raises(ValueError, match="access_points"):
        tracker.wifi(fusion.WifiObservation(2.0, [9], [-50.0]))
    # A scan whose APs are all unknown to the map: after the caller's mapping it has no reading.
    before = tracker.particles()[2].copy()
    est = tracker.wifi(fusion.WifiObservation(2.0, [], []))
    assert np.array_equal(tracker.particles()[2], before) and tracker.summary.empty_wifi_updates == 1
    assert np.isfinite(est.mean_m).all()
    # A signal map on a floor the plan does not have.
    other, _ = room_model(floor=4)
    with pytest.raises(ValueError, match="floor 0"):
        fusion.ParticleTracker(plan, other, None, fusion.tracker_options(num_particles=10))
    with pytest.raises(ValueError, match="FloorPlan"):
        fusion.ParticleTracker("not a plan")
    # The user's arrays are not modified.
    rss = np.array([[-50.0, np.nan, -70.0, -80.0]])
    ages = np.array([[0.0, np.nan, 9.0, 0.0]])
    rss0, ages0 = rss.copy(), ages.copy()
    fusion.make_wifi_observations([1.0], rss, ages)
    assert np.array_equal(rss, rss0, equal_nan=True) and np.array_equal(ages, ages0, equal_nan=True)
    with pytest.raises(ValueError, match="ages_s"):
        fusion.make_wifi_observations([1.0], rss, -ages0)


def test_stale_readings_dropped_or_retimed():
    rss = np.array([[-50.0, -60.0, np.nan]])
    ages = np.array([[0.5, 9.0, np.nan]])
    opts = fusion.tracker_options(max_age_s=4.0, use_not_heard=False)
    scan_time, counts = fusion.make_wifi_observations([10.0], rss, ages, opts, at_own_time=False)
    assert counts["dropped_stale"] == 1 and [o.access_points for o in scan_time] == [[0]]
    own_time, _ = fusion.make_wifi_observations([10.0], rss, ages, opts, at_own_time=True)
    assert [(o.time_s, o.access_points) for o in own_time] == [(1.0, [1]), (9.5, [0])]


def _track_scenario(scenario, threads, seed=4):
    options = fusion.tracker_options(num_particles=3000, num_threads=threads, seed=seed)
    plan, model, _, steps, obs = fs.scenario_inputs(scenario, options)
    return fusion.track(steps, obs, plan=plan, wifi_model=model, options=options,
                        smoother=fusion.SmootherOptions(num_trajectories=20, num_threads=threads))


def test_same_seed_same_track_for_any_thread_count(scenario):
    one = _track_scenario(scenario, 1)
    two = _track_scenario(scenario, 2)
    for key in ("mean_m", "covariance_m2", "floor_probabilities", "ess", "smoothed_m"):
        assert np.array_equal(one[key], two[key]), key


def test_batch_track_outputs_and_accuracy_on_one_synthetic_walk(scenario):
    result = _track_scenario(scenario, 2)
    m = len(scenario.steps.time_s)
    assert result["mean_m"].shape == (m, 2) and result["smoothed_m"].shape == (m, 2)
    assert result["floor_probabilities"].shape == (m, 1)
    assert np.all(np.isfinite(result["mean_m"])) and np.all(result["ess"] >= 1)
    err = np.linalg.norm(result["smoothed_m"] - scenario.steps.true_position_m, axis=1)
    assert err.mean() < 2.0
    assert result["summary"].steps == m


def test_walk_comparison_has_every_method(scenario):
    r = fs.run_walk(5, fusion.tracker_options(num_particles=2000), smoother_trajectories=20)
    assert set(r.errors_m) == set(fs.METHODS)
    summary = fs.summarize([r])
    assert set(summary) >= {"methods", "seeds", "unknown_start_time_to_3m_s"}
    for name in fs.METHODS:
        assert set(summary["methods"][name]) >= {"mean_m", "p90_m", "n_walks"}
    # The full filter beats both single sources on this walk.
    assert summary["methods"]["fusion_known_start"]["mean_m"] < summary["methods"]["pdr_only"]["mean_m"]
    assert summary["methods"]["fusion_known_start"]["mean_m"] < summary["methods"]["wifi_only"]["mean_m"]


def test_floor_plan_queries_from_python():
    plan = room_plan()
    assert plan.is_walkable([[1, 1], [10, 5], [25, 5]]).tolist() == [True, False, False]
    assert plan.crosses_wall([[15, 1, 17, 1], [15, 8, 17, 8]]).tolist() == [True, False]
    np.testing.assert_allclose(plan.distance_to_wall([[1.0, 5.0]]), [1.0])
    with pytest.raises(ValueError, match="points_m"):
        plan.is_walkable([[np.nan, 1.0]])
    with pytest.raises(ValueError, match="floor"):
        plan.is_walkable([[1.0, 1.0]], floor_indices=3)


_TRACKER_SIMD_SCRIPT = """
import sys
import numpy as np
from indoorloc import fusion
square = lambda x0, y0, x1, y1: np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)
plan = fusion.FloorPlan([fusion.FloorGeometry(0, [square(0, 0, 40, 30)],
                                              [square(4 * i + 1.5, 4 * j + 1.5, 4 * i + 2.5, 4 * j + 2.5)
                                               for i in range(10) for j in range(7)], None)])
# 2,500 particles: two full blocks and a partial one (not a multiple of the eight lanes).
opts = fusion.tracker_options(num_particles=2500, start_position_sd_m=3.0, seed=4, heading_offset_walk_rad=0.06)
tracker = fusion.ParticleTracker(plan, None, None, opts)
tracker.initialize_known(0.0, [20.0, 15.0], 0, 0.0)
rng = np.random.default_rng(1)
out = []
for k in range(60):
    h = rng.uniform(-np.pi, np.pi)
    est = tracker.step(1.0 + k, [0.7 * np.cos(h), 0.7 * np.sin(h)], [[0.01, 0.0], [0.0, 0.01]])
    out.append([est.mean_m[0], est.mean_m[1], est.blocked_fraction, est.ess])
states, floors, log_w = tracker.particles()
np.save(sys.argv[1], np.concatenate([np.ravel(out), states.ravel(), log_w]))
"""


def test_particle_tracker_gives_the_same_numbers_with_and_without_avx2(tmp_path):
    """The free-space step's normals (RandomLanes.FillNormal: gathers and the fast test on four
    lanes) and motion loop (compiled for AVX2 and for the baseline) do the same IEEE operations in
    the same order as the portable versions: bit-identical particles, weights and estimates. The
    offset walk of 0.06 rad makes some increments exceed the Taylor rotation's 0.1 rad."""
    from simd_check import outputs_with_and_without_avx2

    results = outputs_with_and_without_avx2(_TRACKER_SIMD_SCRIPT, tmp_path, fusion.__file__)
    assert results[0].size > 10000 and np.all(np.isfinite(results[0][:240]))
    np.testing.assert_array_equal(results[0], results[1])
