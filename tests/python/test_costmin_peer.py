"""Cost-minimisation baseline (indoorloc.fusion.costmin_baseline): WiFi fixes plus PDR
displacements by robust least squares, with an optional per-walk rotation of the PDR.

Checked on a synthetic L-shaped walk simulated here (exact displacements, fixes with Gaussian
noise and a few gross outliers): the track beats the fixes alone and PDR alone, the robust loss
beats the quadratic one, a rotated PDR is recovered, the solution is a stationary point of the
documented cost (numerical gradient), and bad input raises ValueError naming the argument."""

import numpy as np
import pytest

from indoorloc.fusion import costmin_baseline as cm

STEP_S = 0.5
STEP_M = 0.7
FIX_SD_M = 3.0
SETTINGS = dict(sigma_step_m=0.1, sigma_fix_m=FIX_SD_M)  # simulation's own noise, not tuned


def rotation(rad: float) -> np.ndarray:
    c, s = np.cos(rad), np.sin(rad)
    return np.array([[c, -s], [s, c]])


def l_walk(seed: int, pdr_rotation_rad: float = 0.0, fix_sd_m: float = FIX_SD_M, outliers: int = 3):
    """30 steps east then 30 north (0.7 m every 0.5 s) from (10, 5); fixes every 2 s between step
    times with N(0, fix_sd_m^2) noise per axis, `outliers` of them moved by 30 m per axis. The PDR
    displacements are the true ones rotated by -pdr_rotation_rad (so the rotation to recover is
    +pdr_rotation_rad)."""
    rng = np.random.default_rng(seed)
    n = 60
    step_times = np.arange(n + 1) * STEP_S
    heading = np.where(np.arange(n) < n // 2, 0.0, np.pi / 2)
    true_disp = STEP_M * np.column_stack([np.cos(heading), np.sin(heading)])
    truth = np.vstack([[0.0, 0.0], np.cumsum(true_disp, axis=0)]) + [10.0, 5.0]
    fix_times = np.arange(0.3, step_times[-1], 2.0)
    truth_at_fix = cm.evaluate_at(fix_times, step_times, truth)
    fixes = truth_at_fix + rng.normal(0.0, fix_sd_m, truth_at_fix.shape)
    bad = rng.choice(fix_times.size, outliers, replace=False)
    fixes[bad] += rng.choice([-1.0, 1.0], (outliers, 2)) * 30.0
    disp = true_disp @ rotation(-pdr_rotation_rad).T
    return step_times, disp, fix_times, fixes, truth, truth_at_fix


def mean_error(a, b) -> float:
    return float(np.mean(np.linalg.norm(a - b, axis=1)))


def test_beats_fixes_alone_and_pdr_alone_and_quadratic_loss():
    seeds = range(6)
    err = {"costmin": [], "no_rotation": [], "quadratic": [], "fixes": [], "pdr": []}
    for seed in seeds:
        st, disp, ft, fixes, truth, truth_at_fix = l_walk(seed)
        err["costmin"].append(mean_error(cm.costmin_track(st, disp, ft, fixes, **SETTINGS), truth))
        p = cm.costmin_track(st, disp, ft, fixes, estimate_rotation=False, **SETTINGS)
        err["no_rotation"].append(mean_error(p, truth))
        p = cm.costmin_track(st, disp, ft, fixes, loss="linear", estimate_rotation=False, **SETTINGS)
        err["quadratic"].append(mean_error(p, truth))
        err["fixes"].append(mean_error(fixes, truth_at_fix))
        pdr = np.vstack([[0.0, 0.0], np.cumsum(disp, axis=0)]) + fixes[0]  # PDR from the first fix
        err["pdr"].append(mean_error(pdr, truth))
    m = {k: float(np.mean(v)) for k, v in err.items()}
    assert m["costmin"] < 2.0, m
    assert m["no_rotation"] < 2.0, m
    assert m["costmin"] < 0.25 * m["fixes"], m
    assert m["costmin"] < 0.6 * m["pdr"], m
    assert m["no_rotation"] < 0.6 * m["quadratic"], m
    for seed in seeds:  # every walk, not just on average
        assert err["costmin"][seed] < err["fixes"][seed], err


def test_summary_flags_the_gross_outliers():
    st, disp, ft, fixes, truth, truth_at_fix = l_walk(0)
    p, summary = cm.costmin_track(st, disp, ft, fixes, return_summary=True, **SETTINGS)
    assert summary.converged and summary.termination == "converged"
    assert summary.n_fixes == ft.size and summary.n_steps == st.size
    far = np.linalg.norm(fixes - truth_at_fix, axis=1) > 20.0
    assert far.sum() == 3
    assert np.all(summary.robust_weights[far] < 0.2)
    assert np.median(summary.robust_weights[~far]) > 0.4
    assert "converged" in summary.report()


@pytest.mark.parametrize("method", ["joint", "alternate"])
def test_recovers_the_pdr_rotation(method):
    angle = np.radians(20.0)
    settings = dict(sigma_step_m=0.1, sigma_fix_m=0.5)  # the simulation's own noise
    st, disp, ft, fixes, truth, _ = l_walk(1, pdr_rotation_rad=angle, fix_sd_m=0.5)
    p, s = cm.costmin_track(st, disp, ft, fixes, rotation_method=method, return_summary=True, **settings)
    assert s.rotation_estimated and s.converged
    assert abs(np.degrees(s.rotation_rad - angle)) < 2.0, np.degrees(s.rotation_rad)
    assert mean_error(p, truth) < 0.5
    p_fixed = cm.costmin_track(st, disp, ft, fixes, estimate_rotation=False, **settings)
    assert mean_error(p, truth) < 0.3 * mean_error(p_fixed, truth)


def test_rotation_is_equivariant_and_methods_agree():
    """Rotating the PDR by -a moves the estimate by exactly +a and leaves the track unchanged."""
    st, disp, ft, fixes, _, _ = l_walk(2)
    p0, s0 = cm.costmin_track(st, disp, ft, fixes, return_summary=True, **SETTINGS)
    a = np.radians(35.0)
    p1, s1 = cm.costmin_track(st, disp @ rotation(-a).T, ft, fixes, return_summary=True, **SETTINGS)
    assert s1.rotation_rad - s0.rotation_rad == pytest.approx(a, abs=1e-6)
    np.testing.assert_allclose(p1, p0, atol=1e-4)
    p2, s2 = cm.costmin_track(
        st, disp, ft, fixes, rotation_method="alternate", max_iterations=200, return_summary=True, **SETTINGS
    )
    assert abs(s2.rotation_rad - s0.rotation_rad) < np.radians(0.2)
    np.testing.assert_allclose(p2, p0, atol=0.05)


@pytest.mark.parametrize("loss", ["linear", "huber", "soft_l1", "cauchy"])
def test_solution_is_a_stationary_point_of_the_documented_cost(loss):
    """Central-difference gradient of the cost in the module docstring, written out here."""
    st, disp, ft, fixes, _, _ = l_walk(3)
    st, disp = st[:21], disp[:20]
    ft, fixes = ft[:5], fixes[:5]
    weights = np.linspace(0.5, 1.5, ft.size)
    sig_s, sig_f, c = 0.2, 2.0, 1.5
    p, s = cm.costmin_track(
        st, disp, ft, fixes, weights, sigma_step_m=sig_s, sigma_fix_m=sig_f, loss=loss, loss_scale=c,
        tolerance_m=1e-9, max_iterations=500, return_summary=True,
    )
    rho = {
        "linear": lambda z: z,
        "huber": lambda z: np.where(z <= 1, z, 2 * np.sqrt(z) - 1),
        "soft_l1": lambda z: 2 * (np.sqrt(1 + z) - 1),
        "cauchy": lambda z: np.log1p(z),
    }[loss]

    def cost(x):
        q, th = x[:-1].reshape(-1, 2), x[-1]
        steps = np.sum((np.diff(q, axis=0) - disp @ rotation(th).T) ** 2) / sig_s**2
        at = np.column_stack([np.interp(ft, st, q[:, 0]), np.interp(ft, st, q[:, 1])])
        z = weights * np.sum((at - fixes) ** 2, axis=1) / (c**2 * sig_f**2)
        return steps + c**2 * np.sum(rho(z))

    x = np.concatenate([p.ravel(), [s.rotation_rad]])
    assert cost(x) == pytest.approx(s.cost, rel=1e-9)
    h = 1e-6
    grad = np.array([(cost(x + h * e) - cost(x - h * e)) / (2 * h) for e in np.eye(x.size)])
    assert np.max(np.abs(grad)) < 1e-3 * max(1.0, s.cost), grad


def test_single_fix_and_single_step_time():
    st, disp, ft, fixes, _, _ = l_walk(0)
    p, s = cm.costmin_track(st, disp, ft[:1], fixes[:1], return_summary=True, **SETTINGS)
    assert not s.rotation_estimated  # one fix: rotation unobservable, left at 0
    expected = np.vstack([[0.0, 0.0], np.cumsum(disp, axis=0)])
    expected += fixes[0] - cm.evaluate_at(ft[:1], st, expected)[0]
    np.testing.assert_allclose(p, expected, atol=1e-6)
    p1 = cm.costmin_track([0.0], np.zeros((0, 2)), [0.0, 1.0], [[1.0, 2.0], [3.0, 4.0]], loss="linear")
    np.testing.assert_allclose(p1, [[2.0, 3.0]], atol=1e-9)


def test_settings_dataclass_defaults_match_the_function():
    settings = cm.CostMinSettings()
    st, disp, ft, fixes, _, _ = l_walk(4)
    np.testing.assert_allclose(
        cm.costmin_track(st, disp, ft, fixes, **settings.kwargs()), cm.costmin_track(st, disp, ft, fixes)
    )
    assert settings.loss == "soft_l1" and settings.estimate_rotation


def test_evaluate_at_interpolates_and_holds_the_ends():
    st = np.array([0.0, 1.0, 3.0])
    pos = np.array([[0.0, 0.0], [1.0, 2.0], [5.0, 2.0]])
    out = cm.evaluate_at([-1.0, 0.5, 2.0, 9.0], st, pos)
    np.testing.assert_allclose(out, [[0, 0], [0.5, 1.0], [3.0, 2.0], [5.0, 2.0]])
    with pytest.raises(ValueError, match="positions_m"):
        cm.evaluate_at([0.5], st, pos[:2])
    with pytest.raises(ValueError, match="times_s"):
        cm.evaluate_at([np.nan], st, pos)
    with pytest.raises(ValueError, match="step_times_s"):
        cm.evaluate_at([0.5], [0.0, 2.0, 1.0], pos)


def test_bad_input_names_the_argument():
    st, disp, ft, fixes, _, _ = l_walk(0)
    call = lambda **kw: cm.costmin_track(  # noqa: E731
        kw.pop("st", st), kw.pop("disp", disp), kw.pop("ft", ft), kw.pop("fixes", fixes), kw.pop("w", None), **kw
    )
    bad_disp = disp.copy()
    bad_disp[3, 1] = np.nan
    cases = [
        (dict(disp=bad_disp), "displacements_m"),
        (dict(disp=disp[:-1]), "displacements_m"),
        (dict(disp=disp[:, :1]), "displacements_m"),
        (dict(st=st[::-1].copy()), "step_times_s"),
        (dict(st=np.where(np.arange(st.size) == 5, np.inf, st)), "step_times_s"),
        (dict(ft=ft[:-1]), "fixes_m"),
        (dict(ft=np.array([]), fixes=np.zeros((0, 2))), "fix_times_s"),
        (dict(fixes=np.where(np.arange(fixes.size).reshape(fixes.shape) == 4, np.nan, fixes)), "fixes_m"),
        (dict(w=np.zeros(ft.size)), "fix_weights"),
        (dict(w=np.ones(ft.size + 1)), "fix_weights"),
        (dict(w=-np.ones(ft.size)), "fix_weights"),
        (dict(sigma_step_m=0.0), "sigma_step_m"),
        (dict(sigma_step_m=np.ones(3)), "sigma_step_m"),
        (dict(sigma_fix_m=np.nan), "sigma_fix_m"),
        (dict(loss="l2"), "loss"),
        (dict(loss_scale=-1.0), "loss_scale"),
        (dict(rotation_method="gauss"), "rotation_method"),
        (dict(max_iterations=0), "max_iterations"),
    ]
    for kwargs, name in cases:
        with pytest.raises(ValueError, match=name):
            call(**kwargs)
