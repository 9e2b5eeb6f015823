"""The direction-persistent WiFi-only tracker (fusion.wifi_heading_sequence, docs/fusion_real.md
"WiFi only: a direction-persistent motion prior"): a walker seen only at the start of a corridor
is carried along it where the random walk stays put; zero headings is wifi_sequence's random walk;
the smoother equals a dense forward-backward on a small grid; its walls and fixes are the C++
grid tracker's (components on other floors ignored); errors name the argument."""

import dataclasses

import numpy as np
import pytest

from indoorloc import fusion
from indoorloc.fusion import wifi_heading_sequence as whs
from indoorloc.fusion import wifi_sequence as ws


def _corridor(s, floor=0):
    """The states of a corridor 100 m long and 6 m wide (x 2-102 m, y 2-8 m) on floor ``floor``."""
    outline = np.array([[2, 2], [102, 2], [102, 8], [2, 8]], float)
    plan = fusion.floor_plan_from_polygons(outline, [], floor=floor)
    return whs.heading_grid(plan, s)


def _fixes_at_start():
    """Four one-component fixes, t = 0..6 s, of a walker going east at 1.2 m/s from x = 10 m
    along the corridor's centre line (y = 5 m)."""
    t = np.arange(0.0, 8.0, 2.0)
    means = np.c_[10.0 + 1.2 * t, np.full(t.size, 5.0)]
    return fusion.Fixes.from_arrays(t, means, 2.0)


def test_a_walker_seen_only_at_the_start_is_carried_along_the_corridor():
    fixes = _fixes_at_start()
    moving = whs.HeadingSequenceSettings(headings=8, fix_sd_scale=1.0, fix_survey_distance_factor=1.0)
    still = dataclasses.replace(moving, headings=0)
    x_at_30 = {}
    for name, s in (("moving", moving), ("still", still)):
        grid = _corridor(s)
        track = whs.track_fixes(grid, fixes, 0.0, 30.0, s)
        assert np.isfinite(track["position_m"]).all()
        x_at_30[name] = float(ws.at_times(track, [30.0])[0, 0])
    # The truth at 30 s is x = 46 m; the last fix said 17.2 m.
    assert x_at_30["moving"] > 33.0, x_at_30
    assert x_at_30["still"] < 22.0, x_at_30


def test_zero_headings_is_the_random_walk_of_wifi_sequence():
    outline = np.array([[0, 0], [60, 0], [60, 20], [0, 20]], float)
    plan = fusion.floor_plan_from_polygons(outline, [])
    rng = np.random.default_rng(1)
    t = np.arange(1.0, 40.0, 2.0)
    truth = np.c_[10.0 + t, np.full(t.size, 5.0)]
    decoy = np.c_[rng.uniform(0, 60, t.size), rng.uniform(0, 20, t.size)]
    fixes = fusion.Fixes.from_arrays(t, np.stack([truth + rng.normal(0, 2, truth.shape), decoy], 1), 4.0,
                                     np.tile([0.6, 0.4], (t.size, 1)))
    seq = ws.SequenceSettings(fix_survey_distance_factor=1.0)
    reference = ws.track_fixes(ws.sequence_tracker(plan, seq), fixes, 0.0, 41.0, seq)
    s = whs.HeadingSequenceSettings(headings=0, fix_survey_distance_factor=1.0)
    mine = whs.track_fixes(whs.heading_grid(plan, s), fixes, 0.0, 41.0, s)
    np.testing.assert_allclose(mine["times_s"], reference["times_s"])
    gap = np.hypot(*(mine["position_m"] - reference["position_m"]).T)
    assert gap.mean() < 0.1 and gap.max() < 0.5, (gap.mean(), gap.max())


def test_the_smoother_is_the_dense_forward_backward():
    s = whs.HeadingSequenceSettings(headings=4, speed_m_per_s=1.5, heading_blur_sd_m=0.8, margin_cells=0)
    outline = np.array([[0, 0], [8, 0], [8, 6], [0, 6]], float)
    shop = np.array([[3, 2], [5, 2], [5, 4], [3, 4]], float)   # half of four cells: partial walls
    grid = whs.heading_grid(fusion.floor_plan_from_polygons(outline, [shop]), s)
    assert 4 <= grid.cells_m.shape[0] <= 30 and grid.wall_factor.min() < 1.0
    kernels = whs.motion_kernels(grid, s)
    trans = whs.mode_transition(s)
    np.testing.assert_allclose(trans.sum(1), 1.0)
    rng = np.random.default_rng(0)
    n, n_modes, m = grid.cells_m.shape[0], trans.shape[0], 6
    emit = [grid.wall_factor * rng.uniform(0.05, 1.0, n) for _ in range(m)]
    # The joint transition over (mode, cell): P[(m, i), (m', j)] = T[m, m'] K_m'[i, j].
    k_dense = [kd.toarray().T for kd in kernels]
    joint = np.block([[trans[a, b] * k_dense[b] for b in range(n_modes)] for a in range(n_modes)])
    alphas = [np.full(n_modes * n, 1.0 / (n_modes * n)) * np.tile(emit[0], n_modes)]
    for k in range(1, m):
        alphas.append(alphas[-1] @ joint * np.tile(emit[k], n_modes))
    beta = np.ones(n_modes * n)
    post = [None] * m
    for k in range(m - 1, -1, -1):
        g = alphas[k] * beta
        post[k] = (g / g.sum()).reshape(n_modes, n).sum(0)
        beta = joint @ (np.tile(emit[k], n_modes) * beta) if k > 0 else beta
    np.testing.assert_allclose(whs._smooth(kernels, trans, emit), np.array(post), rtol=1e-4, atol=1e-6)


def test_errors_name_the_argument():
    with pytest.raises(ValueError, match="headings"):
        whs.HeadingSequenceSettings(headings=-1).validate()
    with pytest.raises(ValueError, match="to_wander_probability"):
        whs.HeadingSequenceSettings(keep_heading_probability=0.99, to_wander_probability=0.05).validate()
    with pytest.raises(ValueError, match="speed_m_per_s"):
        whs.HeadingSequenceSettings(speed_m_per_s=float("nan")).validate()
    s = whs.HeadingSequenceSettings()
    outline = np.array([[0, 0], [20, 0], [20, 6], [0, 6]], float)
    plan = fusion.floor_plan_from_polygons(outline, [])
    with pytest.raises(ValueError, match="survey_positions_m"):
        whs.heading_grid(plan, s, np.array([[np.inf, 0.0]]))
    with pytest.raises(ValueError, match="tracker"):   # a tracker of another cell size
        whs.grid_from_tracker(fusion.GridTracker(plan, s.grid_options().replace(cell_size_m=1.0)), s)
    grid = _corridor(s)
    with pytest.raises(ValueError, match="t_start_s"):
        whs.track_fixes(grid, _fixes_at_start(), 5.0, 1.0, s)
    with pytest.raises(ValueError, match="kernels"):
        whs.track_fixes(grid, _fixes_at_start(), 0.0, 10.0, s, kernels=[])
    # No fix: NaN, not a guess.
    empty = fusion.Fixes.from_arrays(np.zeros(0), np.zeros((0, 2)), np.zeros(0))
    assert np.isnan(whs.track_fixes(grid, empty, 0.0, 10.0, s)["position_m"]).all()


def test_fix_components_on_other_floors_are_ignored():
    s = whs.HeadingSequenceSettings(fix_survey_distance_factor=1.0, fix_sd_scale=1.0)
    grid = _corridor(s, floor=3)
    t = np.arange(0.0, 10.0, 2.0)
    means = np.stack([np.c_[np.full(t.size, 20.0), np.full(t.size, 5.0)],    # on floor 3
                      np.c_[np.full(t.size, 80.0), np.full(t.size, 5.0)]], 1)  # on floor 7
    fixes = fusion.Fixes.from_arrays(t, means, 2.0, floors=np.tile([3, 7], (t.size, 1)))
    x = whs.track_fixes(grid, fixes, 0.0, 8.0, s)["position_m"][:, 0]
    assert np.all(np.abs(x - 20.0) < 3.0), x
    # Components without a floor count on every floor: the mean then lies between them.
    anywhere = fusion.Fixes.from_arrays(t, means, 2.0)
    x_all = whs.track_fixes(grid, anywhere, 0.0, 8.0, s)["position_m"][:, 0]
    assert np.all(x_all > 35.0), x_all
