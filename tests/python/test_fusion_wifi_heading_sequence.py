"""The direction-persistent WiFi-only tracker (fusion.wifi_heading_sequence, docs/fusion_real.md
"WiFi only: a direction-persistent motion prior"): a walker seen only at the start of a corridor
is carried along it where the random walk stays put; zero headings is wifi_sequence's random walk;
the C++ smoother equals the numpy forward-backward it replaced (kept here as the oracle), which
equals a dense forward-backward on a small grid; its walls and fixes are the C++ grid tracker's
(components on other floors ignored); errors name the argument."""

import dataclasses
import warnings

import numpy as np
import pytest

from indoorloc import fusion
from indoorloc._core.fusion import smooth_mode_sequence
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


def _kernels(grid, s):
    """The oracle's per-mode K^T (N, N) of motion_stencils(s): the library's deprecated
    motion_kernels, the matrix form of the same stencils (moves onto non-states dropped)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        return whs.motion_kernels(grid, s)


def _numpy_smooth(kernels, trans, emit):
    """The oracle: the numpy forward-backward the C++ smoother replaced (posterior summed over
    modes, (M ticks, N)): per-tick normalisation, the restart from the tick's evidence when
    everything is walled off, the backward pass normalised by its max, the forward pass kept in
    float32."""
    n_modes, m = trans.shape[0], len(emit)
    n = emit[0].size
    back = [k.T.tocsr() for k in kernels]
    alpha = np.empty((m, n_modes, n), dtype=np.float32)
    post = np.empty((m, n))
    a = np.full((n_modes, n), 1.0 / (n_modes * n)) * emit[0]
    prev = a / a.sum()
    alpha[0] = prev
    for k in range(1, m):
        mixed = trans.T @ prev
        a = np.stack([kernels[i] @ mixed[i] for i in range(n_modes)]) * emit[k]
        s = a.sum()
        if not s > 0:
            a = np.ones((n_modes, n)) * emit[k]
            s = a.sum()
        prev = a / s
        alpha[k] = prev
    b = np.ones((n_modes, n))
    post[m - 1] = prev.sum(0) / prev.sum()
    for k in range(m - 2, -1, -1):
        be = b * emit[k + 1]
        b = trans @ np.stack([back[i] @ be[i] for i in range(n_modes)])
        mx = b.max()
        b /= mx if mx > 0 else 1.0
        g = alpha[k] * b
        s = g.sum()
        post[k] = g.sum(0) / s if s > 0 else alpha[k].sum(0)
    return post


def _emissions(grid, rng, m, fix_ticks):
    """Per tick the wall factor, times a random fix factor on ``fix_ticks``: (list of (N,), the
    fix factors (F, N))."""
    n = grid.cells_m.shape[0]
    fix = rng.uniform(0.01, 1.0, (len(fix_ticks), n)) ** 4
    emit = [grid.wall_factor.copy() for _ in range(m)]
    for j, k in enumerate(fix_ticks):
        emit[k] = grid.wall_factor * fix[j]
    return emit, fix


def test_the_numpy_oracle_is_the_dense_forward_backward():
    s = whs.HeadingSequenceSettings(headings=4, speed_m_per_s=1.5, heading_blur_sd_m=0.8, margin_cells=0)
    outline = np.array([[0, 0], [8, 0], [8, 6], [0, 6]], float)
    shop = np.array([[3, 2], [5, 2], [5, 4], [3, 4]], float)   # half of four cells: partial walls
    grid = whs.heading_grid(fusion.floor_plan_from_polygons(outline, [shop]), s)
    assert 4 <= grid.cells_m.shape[0] <= 30 and grid.wall_factor.min() < 1.0
    kernels = _kernels(grid, s)
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
    np.testing.assert_allclose(_numpy_smooth(kernels, trans, emit), np.array(post), rtol=1e-4, atol=1e-6)
    # The C++ smoother on the same chain (every tick with its own factor).
    got = smooth_mode_sequence(grid.index, grid.cells_m, whs.motion_stencils(s), trans, np.ones(n), np.arange(m),
                               np.array(emit), m, keep_posterior=True)
    np.testing.assert_allclose(got.posterior, np.array(post), rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize("headings", [0, 8])
def test_the_cpp_smoother_is_the_numpy_oracle(headings):
    # A hall with shops (walls: lost mass, partial cells) and two margin rings; fixes on a third
    # of the ticks, random factors; the default motion model.
    s = whs.HeadingSequenceSettings(headings=headings)
    outline = np.array([[0, 0], [60, 0], [60, 40], [0, 40]], float)
    shops = [np.array([[x, y], [x + 9, y], [x + 9, y + 7], [x, y + 7]], float) + 0.5
             for x in (6, 24, 42) for y in (6, 24)]
    grid = whs.heading_grid(fusion.floor_plan_from_polygons(outline, shops), s)
    rng = np.random.default_rng(3)
    m = 80
    fix_ticks = np.sort(rng.choice(m, m // 3, replace=False))
    emit, fix = _emissions(grid, rng, m, fix_ticks)
    stencils = whs.motion_stencils(s)
    trans = whs.mode_transition(s)
    want = _numpy_smooth(_kernels(grid, s), trans, emit)
    got = smooth_mode_sequence(grid.index, grid.cells_m, stencils, trans, grid.wall_factor, fix_ticks, fix, m,
                               keep_posterior=True)
    assert got.restarts == 0 and np.isfinite(got.log_evidence)
    np.testing.assert_allclose(got.posterior, want, rtol=1e-6, atol=1e-6 * want.max())
    np.testing.assert_allclose(got.mean_m, want @ grid.cells_m, rtol=0, atol=1e-6)
    # Without the posterior: the same means.
    again = smooth_mode_sequence(grid.index, grid.cells_m, stencils, trans, grid.wall_factor, fix_ticks, fix, m)
    assert again.posterior.shape == (0, grid.cells_m.shape[0])
    np.testing.assert_array_equal(again.mean_m, got.mean_m)


def test_track_fixes_is_the_numpy_oracle_on_a_walk():
    # track_fixes (fixes through the grid tracker's fix model) against the oracle fed the same
    # factors: the C++ path changes no figure.
    s = whs.HeadingSequenceSettings()
    grid = _corridor(s)
    fixes = _fixes_at_start()
    track = whs.track_fixes(grid, fixes, 0.0, 30.0, s)
    times = track["times_s"]
    factors = whs.fix_factors(grid, fixes, times, s)
    emit = [grid.wall_factor * factors[k] if k in factors else grid.wall_factor for k in range(times.size)]
    kernels = _kernels(grid, s)
    want = _numpy_smooth(kernels, whs.mode_transition(s), emit) @ grid.cells_m
    np.testing.assert_allclose(track["position_m"], want, rtol=0, atol=1e-6)


def test_the_cpp_smoother_names_bad_arguments():
    s = whs.HeadingSequenceSettings(headings=2)
    grid = _corridor(s)
    n = grid.cells_m.shape[0]
    stencils = whs.motion_stencils(s)
    trans = whs.mode_transition(s)
    args = dict(state_index=grid.index, cells_m=grid.cells_m, stencils=stencils, mode_transition=trans,
                wall_factor=grid.wall_factor, fix_ticks=np.array([0]), fix_factors=np.ones((1, n)), num_ticks=5)
    smooth_mode_sequence(**args)
    bad_weights = [stencils[0], (stencils[1][0], -stencils[1][1]), stencils[2]]
    nan_weights = [stencils[0], stencils[1], (stencils[2][0], np.full(len(stencils[2][1]), np.nan))]
    for key, value, match in [
        ("stencils", bad_weights, r"stencils\[1\]"),
        ("stencils", nan_weights, r"stencils\[2\] weights"),
        ("stencils", stencils[:2], "mode_transition"),
        ("stencils", [(stencils[0][0][:, :1], stencils[0][1])] + stencils[1:], r"stencils\[0\] offsets"),
        ("stencils", [(stencils[0][0] + 0.5, stencils[0][1])] + stencils[1:], "32-bit integer"),
        ("mode_transition", np.full((3, 3), np.nan), "mode_transition"),
        ("wall_factor", grid.wall_factor[:-1], "wall_factor"),
        ("cells_m", grid.cells_m[:, :1], "cells_m"),
        ("state_index", np.zeros_like(grid.index), "state_index"),
        ("fix_ticks", np.array([7]), "fix_ticks"),
        ("fix_factors", np.ones((2, n)), "fix_factors"),
        ("fix_factors", np.zeros((1, n)), "zero on every state"),
        ("num_ticks", 0, "num_ticks"),
    ]:
        with pytest.raises(ValueError, match=match):
            smooth_mode_sequence(**{**args, key: value})
    before = [(o.copy(), w.copy()) for o, w in stencils]
    smooth_mode_sequence(**args)
    for (o, w), (o0, w0) in zip(stencils, before):   # inputs not modified
        np.testing.assert_array_equal(o, o0)
        np.testing.assert_array_equal(w, w0)


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
    with pytest.raises(ValueError, match="stencils"):
        whs.track_fixes(grid, _fixes_at_start(), 0.0, 10.0, s, stencils=[])
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


def test_motion_kernels_are_deprecated_and_ignored():
    s = whs.HeadingSequenceSettings(headings=4)
    grid = _corridor(s)
    with pytest.warns(DeprecationWarning, match="motion_stencils"):
        kernels = whs.motion_kernels(grid, s)
    assert len(kernels) == 5 and kernels[0].shape == (grid.cells_m.shape[0],) * 2
    fixes = _fixes_at_start()
    with pytest.warns(DeprecationWarning, match="ignored"):
        old = whs.track_fixes(grid, fixes, 0.0, 12.0, s, kernels)
    np.testing.assert_array_equal(old["position_m"], whs.track_fixes(grid, fixes, 0.0, 12.0, s)["position_m"])


_SIMD_SCRIPT = """
import sys
import numpy as np
sys.path.insert(0, sys.argv[2])
import test_fusion_wifi_heading_sequence as t
from indoorloc import fusion
from indoorloc._core.fusion import smooth_mode_sequence
from indoorloc.fusion import wifi_heading_sequence as whs
s = whs.HeadingSequenceSettings()
outline = np.array([[0, 0], [61, 0], [61, 41], [0, 41]], float)
shops = [np.array([[x, y], [x + 9, y], [x + 9, y + 7], [x, y + 7]], float) + 0.5 for x in (6, 24, 42) for y in (6, 24)]
grid = whs.heading_grid(fusion.floor_plan_from_polygons(outline, shops), s)
rng = np.random.default_rng(5)
m = 40
ticks = np.sort(rng.choice(m, 15, replace=False))
_, fix = t._emissions(grid, rng, m, ticks)
r = smooth_mode_sequence(grid.index, grid.cells_m, whs.motion_stencils(s), whs.mode_transition(s), grid.wall_factor,
                         ticks, fix, m, keep_posterior=True)
np.save(sys.argv[1], np.concatenate([r.posterior.ravel(), r.mean_m.ravel(), [r.log_evidence]]))
"""


def test_the_smoother_gives_the_same_bits_with_and_without_avx2(tmp_path):
    """The AVX2 and portable builds of the smoother's passes (mode_sequence_smoother_passes.h) do the same
    operations per entry in the same order: bit-identical posteriors (runs of states of every
    length, not multiples of the vector width)."""
    from pathlib import Path

    from simd_check import outputs_with_and_without_avx2

    results = outputs_with_and_without_avx2(_SIMD_SCRIPT, tmp_path, fusion.__file__,
                                            [str(Path(__file__).resolve().parent)])
    assert results[0].size > 10000 and np.all(np.isfinite(results[0]))
    np.testing.assert_array_equal(results[0], results[1])


def test_fix_factors_in_one_call_equal_the_tracker_factor_per_tick():
    """GridTracker.fix_log_likelihoods (one call for every tick, read at the states' cells) equals
    fix_log_likelihood called per group of fixes; bad groups and cells are named."""
    s = whs.HeadingSequenceSettings(headings=2)
    grid = _corridor(s)
    rng = np.random.default_rng(4)
    t = np.sort(rng.uniform(0.0, 20.0, 12))
    means = np.stack([np.c_[rng.uniform(5, 95, t.size), rng.uniform(3, 7, t.size)] for _ in range(3)], 1)
    fixes = fusion.Fixes.from_arrays(t, means, 3.0, np.tile([0.5, 0.3, 0.2], (t.size, 1)))
    ticks = np.arange(0.0, 21.0, 4.0)     # several fixes per tick, and ticks without a fix
    got = whs.fix_factors(grid, fixes, ticks, s)
    times, m, sd, w, fl = fixes.as_arrays()
    sd = sd * s.fix_sd_scale
    at = np.clip(np.searchsorted(ticks, times - 1e-9), 0, ticks.size - 1)
    assert sorted(got) == sorted(set(at.tolist())) and len(got) < ticks.size
    for k, factor in got.items():
        j = np.nonzero(at == k)[0]
        log_l = grid.tracker.fix_log_likelihood(grid.floor_index, (times[j], m[j], sd[j], w[j], fl[j]))
        one = np.asarray(log_l).reshape(-1)[grid.lattice_cell]
        np.testing.assert_array_equal(factor, np.exp(one - one.max()))
    arrays = (times, m, sd, w, fl)
    empty = grid.tracker.fix_log_likelihoods(grid.floor_index, arrays, [0, 0, t.size], grid.lattice_cell[:3])
    assert empty.shape == (2, 3) and np.all(empty[0] == 0.0)
    with pytest.raises(ValueError, match="group_starts"):
        grid.tracker.fix_log_likelihoods(grid.floor_index, arrays, [0, 5, 3, t.size], grid.lattice_cell)
    with pytest.raises(ValueError, match="group_starts"):
        grid.tracker.fix_log_likelihoods(grid.floor_index, arrays, [0, 5], grid.lattice_cell)
    with pytest.raises(ValueError, match="cells"):
        grid.tracker.fix_log_likelihoods(grid.floor_index, arrays, [0, t.size], [grid.nx * grid.ny])
