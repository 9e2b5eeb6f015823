"""The grid tracker (fusion.GridTracker, docs/fusion.md "Grid tracker"): its forward filter equals
an independent numpy + scipy implementation of the same model (benchmarks/grid_filter_numpy.py),
the Options protocol (defaults from C++, kwargs, replace, pickling), the region test and the
errors a user sees."""

import math
import pickle
import sys
from pathlib import Path

import numpy as np
import pytest

from indoorloc import fusion

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import grid_filter_numpy  # noqa: E402


def _hall():
    outline = np.array([[0, 0], [40, 0], [40, 30], [0, 30]], float)
    shop = np.array([[15, 10], [25, 10], [25, 20], [15, 20]], float)
    return fusion.floor_plan_from_polygons(outline, [shop])


def _walk(seed=0):
    """A walk east along y = 5 then north along x = 35, PDR rotated by 0.1 rad, and noisy fixes
    with two components (one of them a far decoy)."""
    rng = np.random.default_rng(seed)
    n = 40
    t = 0.5 * np.arange(1, n + 1)
    heading = np.where(np.arange(n) < 25, 0.0, math.pi / 2)
    steps = fusion.Steps.from_polar(t, np.full(n, 0.7), heading - 0.1, 0.1, 0.1)
    truth = np.cumsum(np.c_[0.7 * np.cos(heading), 0.7 * np.sin(heading)], axis=0) + [18.0, 5.0]
    ft = t[3::4]
    idx = np.searchsorted(t, ft)
    means = np.stack([truth[idx] + rng.normal(0, 2, (idx.size, 2)), np.tile([5.0, 25.0], (idx.size, 1))], axis=1)
    fixes = fusion.Fixes.from_arrays(ft, means, 4.0, np.tile([0.7, 0.3], (idx.size, 1)))
    return steps, fixes, truth


def test_forward_filter_equals_the_numpy_reference():
    plan = _hall()
    options = fusion.GridTrackerOptions(heading_offset_bins=3, heading_offset_sd_rad=0.1, fix_tempering=0.7,
                                        fix_tempering_by_variance=True, wall_log_penalty=-1.5, spatial_median=False)
    tracker = fusion.GridTracker(plan, options)
    steps, fixes, truth = _walk()
    result = fusion.track_grid(tracker, steps, fixes=fixes, smooth=False)
    x0, y0, nx, ny = tracker.grid_geometry(0)
    a = tracker.walkable_fraction(0)
    wall = (a + (1 - a) * math.exp(options.wall_log_penalty)).astype(np.float32)
    offsets = np.asarray(result["heading_offset_bins_rad"])
    span = options.heading_offset_span_sd * options.heading_offset_sd_rad
    ref = grid_filter_numpy.forward_filter(
        {"x0": x0, "y0": y0, "cell": options.cell_size_m, "wall_factor": wall, "area_m2": plan.walkable_area(0)},
        (steps.times_s, steps.displacements_m, steps.covariances_m2), fixes.as_arrays(),
        {"offsets": offsets, "log_prior": -0.5 * (offsets / options.heading_offset_sd_rad) ** 2,
         "bin_width": 2 * span / offsets.size, "position_noise_m": options.position_noise_m,
         "eps": options.fix_outlier_probability, "tau": options.fix_tempering, "by_variance": True})
    np.testing.assert_allclose(result["mean_m"], ref["mean_m"], atol=2e-3)
    # And the filter found the walk: the last estimates are near the truth.
    assert np.hypot(*(result["mean_m"][-5:] - truth[-5:]).T).max() < 3.0


def test_smoother_is_honest_and_learns_the_offset():
    plan = _hall()
    tracker = fusion.GridTracker(plan, fusion.GridTrackerOptions(heading_offset_bins=11, heading_offset_sd_rad=0.15,
                                                                fix_tempering_by_variance=True, spatial_median=True))
    steps, fixes, truth = _walk(1)
    r = fusion.track_grid(tracker, steps, fixes=fixes)
    err = np.hypot(*(r["smoothed_m"] - truth).T)
    assert err.mean() < 2.0
    # On data from the model itself the posterior's own spread is honest; the returned
    # covariance (calibrated for real walks' misfits, GridTrackerOptions) only widens it.
    inside = fusion.region95_contains(r["smoothed_m"], r["smoothed_posterior_covariance_m2"], truth)
    assert inside.mean() > 0.8
    assert fusion.region95_contains(r["smoothed_m"], r["smoothed_covariance_m2"], truth).mean() >= inside.mean()
    # PDR headings were 0.1 rad low: the offset posterior moves from its prior (0) towards +0.1
    # and holds it within two of its own sd (ten fixes of sd 4 m with a decoy leave it broad).
    assert r["walk_heading_offset_rad"] > 0.02
    assert abs(r["walk_heading_offset_rad"] - 0.1) < 2.0 * r["walk_heading_offset_sd_rad"]
    assert np.isclose(np.sum(r["heading_offset_probabilities"]), 1.0)
    assert r["smoothed_median_m"].shape == r["smoothed_m"].shape


def test_options_protocol_reads_defaults_from_cpp():
    o = fusion.GridTrackerOptions()
    assert o.cell_size_m == 1.0 and o.wall_log_penalty == -1.0 and o.fix_tempering == 1.0  # the C++ defaults
    p = o.replace(cell_size_m=1.5)
    assert p.cell_size_m == 1.5 and o.cell_size_m == 1.0
    assert pickle.loads(pickle.dumps(p)) == p and p != o
    assert set(o.to_dict()) >= {"cell_size_m", "fix_tempering", "fix_outlier_probability", "heading_offset_bins"}
    with pytest.raises(ValueError, match="cell_size_mm"):
        fusion.GridTrackerOptions(cell_size_mm=1.0)
    with pytest.raises(ValueError, match="heading_offset_bins"):
        fusion.GridTrackerOptions(heading_offset_bins=0)
    with pytest.raises(ValueError, match="fix tempering"):
        o.replace(fix_tempering=float("nan"))


def test_errors_name_the_argument():
    tracker = fusion.GridTracker(_hall())
    steps, fixes, _ = _walk()
    with pytest.raises(TypeError, match="steps"):
        fusion.track_grid(tracker, np.zeros((3, 2)))
    with pytest.raises(ValueError, match="step_times_s"):
        tracker.run(steps.times_s[::-1], steps.displacements_m, steps.covariances_m2)
    with pytest.raises(ValueError, match="floor"):
        fusion.track_grid(tracker, steps, start={"position_m": [5, 5], "floor": 3, "heading_offset_rad": 0.0,
                                                 "time_s": 0.0})
    with pytest.raises(ValueError, match="max_memory_bytes"):
        fusion.GridTracker(_hall(), fusion.GridTrackerOptions(cell_size_m=0.05, max_memory_bytes=1e6))


def test_region95_contains():
    means = np.zeros((3, 2))
    cov = np.tile([1.0, 0.0, 1.0], (3, 1))
    truth = np.array([[0.5, 0.5], [2.0, 2.0], [0.0, 2.4]])
    assert fusion.region95_contains(means, cov, truth).tolist() == [True, False, True]


def test_wall_margin_erodes_obstacles_by_the_margin_only():
    """wall_margin_m: cells within the margin of the shop's edges become walkable, the shop's
    core stays an obstacle, and 0 leaves the plan as drawn."""
    plan = _hall()
    drawn = fusion.GridTracker(plan, fusion.GridTrackerOptions()).walkable_fraction(0)
    eroded = fusion.GridTracker(plan, fusion.GridTrackerOptions(wall_margin_m=1.0)).walkable_fraction(0)
    assert fusion.GridTrackerOptions().wall_margin_m == 0.0
    # 1 m cells, the shop spans cells x 15..24, y 10..19 (row-major y, x).
    assert drawn[15, 20] == 0.0 and eroded[15, 20] == 0.0          # the shop's core
    assert drawn[10, 20] == 0.0 and eroded[10, 20] == 1.0          # the row just inside its south edge
    assert drawn[5, 5] == 1.0 and eroded[5, 5] == 1.0              # open floor
    assert (eroded >= drawn).all() and eroded.sum() > drawn.sum()
    with pytest.raises(ValueError, match="wall_margin_m"):
        fusion.GridTracker(plan, fusion.GridTrackerOptions(wall_margin_m=-1.0))


def test_returned_covariance_is_the_calibration_formula_of_the_study():
    """The tracker's returned covariances are Σ' = a Σ + (b² + (g d)² + (h max(0, s - s0))²) I of
    its own Σ, d and s (GridTrackerOptions), the formula the study chooses (a, b, g, h, s0) with
    (experiments.fusion_uncertainty.calibrated); s is the fix's weighted component sd."""
    from indoorloc.experiments import fusion_uncertainty as fu

    plan = _hall()
    options = fusion.GridTrackerOptions(heading_offset_bins=3, heading_offset_sd_rad=0.1, filtered_covariance_scale=2.0,
                                        filtered_covariance_floor_m=1.0, filtered_covariance_fix_gain=0.5,
                                        filtered_covariance_fix_sd_gain=3.0, smoothed_covariance_scale=1.5,
                                        smoothed_covariance_floor_m=0.5, smoothed_covariance_fix_gain=0.25,
                                        smoothed_covariance_fix_sd_gain=2.0, covariance_fix_sd_knee_m=5.0)
    steps, fixes, _ = _walk(2)
    # Half the fixes poor (component sds 9 and 13 m): above the knee.
    sds = np.where(np.arange(len(fixes.times_s))[:, None] % 2 == 0, [[4.0, 4.0]], [[9.0, 13.0]])
    fixes = fusion.Fixes.from_arrays(fixes.times_s, fixes.means_m, sds, fixes.weights)
    r = fusion.track_grid(fusion.GridTracker(plan, options), steps, fixes=fixes)
    s = np.asarray(r["fix_sd_m"])
    assert set(np.round(s[s > 0], 9)) == {4.0, 10.2}  # 0.7 * 9 + 0.3 * 13
    for prefix, a, b, g, h in (("", 2.0, 1.0, 0.5, 3.0), ("smoothed_", 1.5, 0.5, 0.25, 2.0)):
        expect = fu.calibrated(np.asarray(r[prefix + "posterior_covariance_m2"]), np.asarray(r[prefix + "fix_distance_m"]),
                               np.asarray(r[prefix + "fix_sd_m"]), a, b, g, h, 5.0)
        np.testing.assert_allclose(r[prefix + "covariance_m2"], expect, rtol=1e-12, atol=1e-9)
    poor = s > 5.0
    assert poor.any() and (~poor).any()
    extra = np.asarray(r["covariance_m2"])[:, 0] - fu.calibrated(np.asarray(r["posterior_covariance_m2"]),
                                                                  np.asarray(r["fix_distance_m"]), s, 2.0, 1.0, 0.5)[:, 0]
    np.testing.assert_allclose(extra[poor], (3.0 * (s[poor] - 5.0)) ** 2, rtol=1e-9)
    assert np.all(np.abs(extra[~poor]) < 1e-9)


def test_study_chooses_the_fix_sd_term_where_poor_matches_are_lost():
    """experiments.fusion_uncertainty.choose on synthetic errors: where the fix sd s is above 8 m
    the error grows (sd 1 + 3 (s - 8) m), elsewhere the posterior (sd 1 m) is right; floor C has
    most of the poor matches. The choice takes the fix-sd term with its knee at 8 m, covers
    >= 95 % pooled and >= 90 % on every floor, and its median region is smaller than the best
    choice without the term."""
    from indoorloc.experiments import fusion_uncertainty as fu

    rng = np.random.default_rng(3)
    n = 3000
    floor = np.repeat(np.array(["A", "B", "C"]), n // 3)
    s = np.where(floor == "C", rng.uniform(2.0, 16.0, n), rng.uniform(2.0, 10.0, n))
    err = rng.normal(size=(n, 2)) * (1.0 + 3.0 * np.maximum(0.0, s - 8.0))[:, None]
    cov = np.tile([1.0, 0.0, 1.0], (n, 1))
    d = np.abs(rng.normal(0, 3, n))
    grid = {"scale": (1.0, 2.0, 4.0), "floor_m": (0.0, 1.0, 2.0), "fix_gain": (0.0, 0.5),
            "fix_sd_gain": (0.0, 1.0, 3.0, 4.0, 8.0), "fix_sd_knee_m": (4.0, 8.0, 12.0)}
    c = fu.choose(err, cov, d, s, floor, grid)
    assert c["fix_sd_gain"] > 0 and c["fix_sd_knee_m"] == 8.0
    inside, area = fu.coverage_and_area(err, fu.calibrated(cov, d, s, **c))
    assert inside.mean() >= 0.95
    assert all(inside[floor == f].mean() >= 0.90 for f in "ABC")
    c0 = fu.choose(err, cov, d, s, floor, {**grid, "fix_sd_gain": (0.0,), "fix_sd_knee_m": (0.0,)})
    _, area0 = fu.coverage_and_area(err, fu.calibrated(cov, d, s, **c0))
    assert np.median(area) < np.median(area0)


def test_survey_anchored_fixes_reach_beyond_the_survey():
    """Fixes anchored to a survey of the western half (fix_survey_distance_factor < 1) let a walk
    seen at the survey's edge lie beyond it; the factor 1 is the plain tracker; bad positions are
    refused naming the argument (docs/fusion.md, "Survey-anchored fixes")."""
    from indoorloc.fusion import site_model

    plan = _hall()
    xs, ys = np.meshgrid(np.arange(0.5, 12.0, 1.0), np.arange(0.5, 30.0, 1.0))
    survey = np.c_[xs.ravel(), ys.ravel()]
    floors = np.zeros(len(survey), dtype=np.int64)
    steps = fusion.Steps.from_polar([0.5], [0.0], [0.0], 0.01, 0.01)
    fix = fusion.Fixes.from_arrays([0.5], np.array([[[11.5, 25.0]]]), 2.0, np.ones((1, 1)))
    plain = fusion.GridTracker(plan, fusion.GridTrackerOptions(heading_offset_sd_rad=0.0, fix_survey_distance_factor=1.0,
                                                               survey_walkable_radius_m=0.0))
    anchored = fusion.GridTracker(plan, fusion.GridTrackerOptions(heading_offset_sd_rad=0.0, fix_survey_distance_factor=0.0)
                                  ).with_survey_positions(survey, floors)
    x_plain = fusion.track_grid(plain, steps, fixes=fix, smooth=False)["mean_m"][0, 0]
    x_anchored = fusion.track_grid(anchored, steps, fixes=fix, smooth=False)["mean_m"][0, 0]
    assert abs(x_plain - 11.5) < 0.5
    assert x_anchored > x_plain + 5.0
    # The factor 1 and no cell to open: the same tracker back (no survey position to use).
    assert site_model.survey_anchored(plain, plan, type("Db", (), {"positions_m": survey, "floors": floors})) is plain
    with pytest.raises(ValueError, match="positions_m"):
        anchored.with_survey_positions(np.zeros((3, 3)), np.zeros(3, dtype=np.int64))
    with pytest.raises(ValueError, match="floor_numbers"):
        anchored.with_survey_positions(survey, floors[:-1])
    with pytest.raises(ValueError, match="positions_m.*NaN"):
        anchored.with_survey_positions(np.full((2, 2), np.nan), np.zeros(2, dtype=np.int64))
    # Not arrays of numbers: a ValueError naming the argument (pybind11's own Eigen caster crashed
    # on a string).
    with pytest.raises(ValueError, match="positions_m"):
        anchored.with_survey_positions("abc", [0])
    with pytest.raises(ValueError, match="floor_numbers"):
        anchored.with_survey_positions(survey[:1], [0.5])
    with pytest.raises(ValueError, match="fix_survey_distance_factor"):
        fusion.GridTrackerOptions(fix_survey_distance_factor=1.5)



def test_survey_opens_the_cells_it_walked_through():
    """A survey line through the hall's shop (y = 15, x 10..30): with survey_walkable_radius_m the
    walk along it crosses the shop instead of going round it; with survey_walkable_min_walks 2
    only two walks' lines open it; walk_ids of the wrong length or type are refused naming the
    argument (docs/fusion.md, "Walls the survey walked through")."""
    from indoorloc.fusion import site_model

    plan = _hall()
    line = np.c_[np.arange(10.0, 31.0), np.full(21, 15.0)]
    survey, floors = np.vstack([line, line]), np.zeros(42, dtype=np.int64)
    one_walk, two_walks = np.zeros(42, dtype=np.int64), np.repeat([0, 1], 21)
    steps = fusion.Steps.from_polar(0.5 * np.arange(1, 21), np.ones(20), np.zeros(20), 0.05, 0.05)
    fixes = fusion.Fixes.from_arrays([0.4, 10.1], np.array([[[10.0, 15.0]], [[30.0, 15.0]]]), 1.0, np.ones((2, 1)))
    assert fusion.GridTrackerOptions().survey_walkable_radius_m == 0.75
    base = fusion.GridTrackerOptions(heading_offset_sd_rad=0.0, wall_log_penalty=-3.0, fix_survey_distance_factor=1.0,
                                     survey_walkable_radius_m=0.0)
    assert not site_model.uses_survey_positions(base)

    def run(options, walk_ids):
        tracker = fusion.GridTracker(plan, options).with_survey_positions(survey, floors, walk_ids)
        r = fusion.track_grid(tracker, steps, fixes=fixes, smooth=True)
        return r["smoothed_posterior_covariance_m2"][10], r["summary"].log_evidence

    # Mid-walk, inside the shop: drawn, the walk goes round it on either side (a wide spread in y,
    # the mean between the two); opened, it crosses on the line.
    drawn, z_drawn = run(base, one_walk)
    opened, z_opened = run(base.replace(survey_walkable_radius_m=1.0), one_walk)
    assert opened[2] < 1.0 and drawn[2] > 9.0
    assert z_opened > z_drawn + 10.0
    two = base.replace(survey_walkable_radius_m=1.0, survey_walkable_min_walks=2)
    assert site_model.uses_survey_positions(two)
    assert run(two, one_walk)[1] == z_drawn
    assert run(two, two_walks)[1] == z_opened
    # Negative walk ids (positions placed by the tracker, not surveyed) anchor but open nothing; so
    # do fingerprints of weight < 1 in a database (Site.grow).
    assert run(base.replace(survey_walkable_radius_m=1.0), np.full(42, -1))[1] == z_drawn
    grown = type("Db", (), {"positions_m": survey, "floors": floors, "walk_index": two_walks, "weights": np.full(42, 0.5)})
    tracker = site_model.survey_anchored(fusion.GridTracker(plan, base.replace(survey_walkable_radius_m=1.0)), plan, grown)
    assert fusion.track_grid(tracker, steps, fixes=fixes, smooth=True)["summary"].log_evidence == z_drawn
    tracker = fusion.GridTracker(plan, two)
    with pytest.raises(ValueError, match="walk_ids"):
        tracker.with_survey_positions(survey, floors, one_walk[:-1])
    with pytest.raises(ValueError, match="walk_ids"):
        tracker.with_survey_positions(survey, floors, "abc")
    with pytest.raises(ValueError, match="survey_walkable_radius_m"):
        fusion.GridTrackerOptions(survey_walkable_radius_m=-1.0)
    with pytest.raises(ValueError, match="survey_walkable_min_walks"):
        fusion.GridTrackerOptions(survey_walkable_min_walks=0)

_SIMD_SCRIPT = """
import sys
import numpy as np
sys.path.insert(0, sys.argv[2])
import test_fusion_grid as t
from indoorloc import fusion
plan = t._hall()
steps, fixes, _ = t._walk()
out = []
# Cells of 0.9 m: 45 x 34 cells, rows not a multiple of the AVX2 path's eight, columns not of four.
for median in (True, False):
    tracker = fusion.GridTracker(plan, fusion.GridTrackerOptions(cell_size_m=0.9, heading_offset_bins=3,
                                                                  heading_offset_sd_rad=0.1, spatial_median=median))
    for start in (None, {"position_m": (18.0, 5.0), "floor": 0, "heading_offset_rad": 0.0, "time_s": 0.0}):
        r = fusion.track_grid(tracker, steps, fixes=fixes, start=start, smooth=True)
        out += [np.asarray(r[k], dtype=float).ravel() for k in sorted(r) if k != "summary"]
np.save(sys.argv[1], np.concatenate(out))
"""


def test_grid_tracker_gives_the_same_numbers_with_and_without_avx2(tmp_path):
    """The AVX2 versions of the grid's passes (the double moments and block sums of the spatial
    median, core/simd_dispatch.h) do the same operations in the same order as the portable ones:
    bit-identical results, medians on and off, known and unknown start."""
    from simd_check import outputs_with_and_without_avx2

    results = outputs_with_and_without_avx2(_SIMD_SCRIPT, tmp_path, fusion.__file__,
                                            [str(Path(__file__).resolve().parent)])
    assert results[0].size > 1000 and np.all(np.isfinite(results[0]))
    np.testing.assert_array_equal(results[0], results[1])


def test_smoother_only_run_skips_the_filtered_estimates_and_changes_nothing_else():
    """filtered=False (a caller reading the smoother only): the filter's position estimates are
    NaN or absent, every other output equals the full run's bit for bit (medians on and off,
    known and unknown start)."""
    plan = _hall()
    steps, fixes, _ = _walk()
    known = {"position_m": (18.0, 5.0), "floor": 0, "heading_offset_rad": 0.0, "time_s": 0.0}
    skipped = {"mean_m", "covariance_m2", "posterior_covariance_m2", "fix_distance_m", "median_m"}
    for median in (True, False):
        tracker = fusion.GridTracker(plan, fusion.GridTrackerOptions(heading_offset_bins=3, heading_offset_sd_rad=0.1,
                                                                      spatial_median=median))
        for start in (None, known):
            full = fusion.track_grid(tracker, steps, fixes=fixes, start=start, smooth=True)
            part = fusion.track_grid(tracker, steps, fixes=fixes, start=start, smooth=True, filtered=False)
            assert "median_m" not in part and ("median_m" in full) == median
            assert np.all(np.isnan(part["mean_m"])) and np.all(np.isnan(part["covariance_m2"]))
            for key in set(full) - skipped - {"summary"}:
                np.testing.assert_array_equal(np.asarray(part[key]), np.asarray(full[key]), err_msg=key)
            assert part["summary"].log_evidence == full["summary"].log_evidence
            # Without smoothing the option does nothing: the filter is the result.
            alone = fusion.track_grid(tracker, steps, fixes=fixes, start=start, smooth=False, filtered=False)
            np.testing.assert_array_equal(alone["mean_m"], full["mean_m"])


def test_with_options_equals_a_fresh_tracker_and_kept_memory_is_released():
    """GridTracker.with_options: another tracker on the same grid, bit for bit the one built
    afresh (walls and survey anchoring changed too); release_kept_memory frees the buffers runs
    keep for later runs, and results do not depend on them."""
    plan = _hall()
    steps, fixes, _ = _walk()
    survey = np.array([[x, y] for x in np.arange(1.0, 30.0, 3.0) for y in np.arange(1.0, 30.0, 3.0)])
    base_options = fusion.GridTrackerOptions(heading_offset_bins=3, heading_offset_sd_rad=0.1,
                                             fix_survey_distance_factor=0.75)
    base = fusion.GridTracker(plan, base_options).with_survey_positions(survey, np.zeros(len(survey), int))
    other = base_options.replace(wall_log_penalty=-1.0, fix_survey_distance_factor=0.4, heading_offset_bins=5)
    fresh = fusion.GridTracker(plan, other).with_survey_positions(survey, np.zeros(len(survey), int))
    a = fusion.track_grid(base.with_options(other), steps, fixes=fixes)
    b = fusion.track_grid(fresh, steps, fixes=fixes)
    for key in ("mean_m", "smoothed_m", "heading_offset_probabilities"):
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    with pytest.raises(ValueError, match="grid"):
        base.with_options(base_options.replace(cell_size_m=2.0))
    assert fusion.GridTracker.kept_memory_bytes() > 0
    assert 0 < fusion.GridTracker.kept_memory_bytes() <= fusion.GridTracker.kept_memory_limit_bytes
    kept = fusion.GridTracker.kept_memory_bytes()
    assert fusion.GridTracker.release_kept_memory() == kept
    assert fusion.GridTracker.kept_memory_bytes() == 0
    c = fusion.track_grid(fresh, steps, fixes=fixes)
    np.testing.assert_array_equal(c["smoothed_m"], b["smoothed_m"])


@pytest.mark.parametrize("bad", ["x", None, 3, {"cell_size_m": 1.0}])
def test_with_options_of_another_type_is_a_value_error_naming_options(bad):
    """A wrong type crashed the interpreter (pybind11's conversion of the reference parameter)
    before the binding checked it itself."""
    tracker = fusion.GridTracker(_hall(), fusion.GridTrackerOptions())
    with pytest.raises(ValueError, match="options"):
        tracker.with_options(bad)
