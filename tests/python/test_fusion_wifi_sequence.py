"""The WiFi-only sequence tracker (fusion.wifi_sequence, docs/fusion_real.md "WiFi only: the
sequence of fixes"): a walker seen by fixes whose centres are pulled towards a decoy is found by
the forward-backward smoother where the per-fix centres are not; the random-walk steps; errors
name the setting."""

import math

import numpy as np
import pytest

from indoorloc import fusion
from indoorloc.fusion import wifi_sequence as ws


def _corridor():
    outline = np.array([[0, 0], [60, 0], [60, 20], [0, 20]], float)
    return fusion.floor_plan_from_polygons(outline, [])


def _walk(seed=0):
    """A walk east along y = 5 at 1 m/s for 40 s; a fix every 2 s with two components: the truth
    plus noise (weight 0.6) and a decoy at a random place of the hall (0.4)."""
    rng = np.random.default_rng(seed)
    t = np.arange(1.0, 40.0, 2.0)
    truth = np.c_[10.0 + t, np.full(t.size, 5.0)]
    decoy = np.c_[rng.uniform(0, 60, t.size), rng.uniform(0, 20, t.size)]
    means = np.stack([truth + rng.normal(0, 2, truth.shape), decoy], axis=1)
    fixes = fusion.Fixes.from_arrays(t, means, 4.0, np.tile([0.6, 0.4], (t.size, 1)))
    return t, truth, fixes


def test_the_sequence_beats_the_per_fix_centres():
    t, truth, fixes = _walk()
    settings = ws.SequenceSettings(fix_survey_distance_factor=1.0, point_estimate="median")
    tracker = ws.sequence_tracker(_corridor(), settings)
    track = ws.track_fixes(tracker, fixes, 0.0, 41.0, settings)
    err_seq = np.hypot(*(ws.at_times(track, t) - truth).T)
    from indoorloc.fusion import wifi_fixes
    err_centre = np.hypot(*(wifi_fixes.fix_centres(fixes) - truth).T)
    assert err_seq.mean() < 0.5 * err_centre.mean(), (err_seq.mean(), err_centre.mean())
    assert err_seq.mean() < 3.0
    # Both point estimates come from the one run (a tracker built for the median); the causal
    # filter is also available.
    assert track["mean_m"].shape == track["median_m"].shape == (len(track["times_s"]), 2)
    causal = ws.track_fixes(tracker, fixes, 0.0, 41.0, ws.SequenceSettings(smooth=False, fix_survey_distance_factor=1.0))
    assert np.isfinite(causal["position_m"]).all()


def test_random_walk_steps_cover_the_span_with_the_walks_variance():
    s = ws.SequenceSettings(tick_s=0.5, speed_sd_m_per_sqrt_s=2.0)
    steps = ws.random_walk_steps(3.0, 5.2, s)
    assert steps.times_s[0] == 3.0 and steps.times_s[-1] >= 5.2
    np.testing.assert_allclose(np.diff(steps.times_s), 0.5)
    np.testing.assert_array_equal(steps.displacements_m, 0.0)
    np.testing.assert_allclose(steps.covariances_m2, np.tile([2.0, 0.0, 2.0], (len(steps), 1)))
    assert len(ws.random_walk_steps(1.0, 1.0, s)) == 2


def test_no_fix_gives_nan_not_a_guess():
    s = ws.SequenceSettings(fix_survey_distance_factor=1.0)
    tracker = ws.sequence_tracker(_corridor(), s)
    empty = fusion.Fixes.from_arrays(np.zeros(0), np.zeros((0, 1, 2)), np.zeros((0, 1)), np.zeros((0, 1)))
    track = ws.track_fixes(tracker, empty, 0.0, 10.0, s)
    assert np.isnan(track["position_m"]).all()


@pytest.mark.parametrize("field, value", [("speed_sd_m_per_sqrt_s", 0.0), ("tick_s", math.nan),
                                          ("fix_tempering", 1.5), ("fix_outlier_probability", 0.0),
                                          ("point_estimate", "mode"), ("wall_log_penalty", 1.0)])
def test_bad_settings_name_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        ws.grid_options(ws.SequenceSettings(**{field: value}))


def test_bad_span_names_the_arguments():
    with pytest.raises(ValueError, match="t_start_s"):
        ws.random_walk_steps(5.0, 1.0, ws.SequenceSettings())
