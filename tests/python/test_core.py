"""Python side of indoorloc.core: numpy in/out, clear ValueErrors, determinism, unbiasedness."""

import numpy as np
import pytest

import indoorloc
from indoorloc import core


def test_version_is_single_source():
    import re
    from pathlib import Path

    cmake = (Path(__file__).resolve().parents[2] / "CMakeLists.txt").read_text()
    expected = re.search(r"project\(indoorloc VERSION ([0-9.]+)", cmake).group(1)
    assert indoorloc.__version__ == expected


def test_log_sum_exp_and_normalize():
    lw = np.array([1.0, 2.0, 3.0, -np.inf])
    expected = np.log(np.exp(1) + np.exp(2) + np.exp(3))
    assert core.log_sum_exp(lw) == pytest.approx(expected, rel=1e-14)
    norm, log_z = core.normalize_log_weights(lw)
    assert log_z == pytest.approx(expected, rel=1e-14)
    assert np.exp(norm).sum() == pytest.approx(1.0, abs=1e-14)
    assert lw[0] == 1.0  # input untouched
    assert core.effective_sample_size(np.zeros(40)) == pytest.approx(40.0)


def test_resample_deterministic_and_sorted():
    lw = np.linspace(-3, 0, 1000)
    a = core.resample(lw, "systematic", rng=core.RandomStream(7))
    b = core.resample(lw, "systematic", rng=core.RandomStream(7))
    np.testing.assert_array_equal(a, b)
    assert a.dtype == np.int64 and a.shape == (1000,)
    assert np.all(np.diff(a) >= 0)
    # A stream advances: two calls on the same stream differ.
    s = core.RandomStream(7)
    assert not np.array_equal(core.resample(lw, "multinomial", s), core.resample(lw, "multinomial", s))
    assert core.resample(lw, "residual", rng=3, num_out=10).shape == (10,)


@pytest.mark.parametrize("scheme", core.RESAMPLING_SCHEMES)
def test_every_scheme_is_unbiased(scheme):
    lw = np.log(np.array([0.05, 0.1, 0.15, 0.2, 0.5]))
    w = np.exp(lw)
    n_runs = 20000
    counts = core.offspring_counts(lw, scheme=scheme, n_runs=n_runs, seed=11)
    assert counts.shape == (n_runs, 5)
    assert np.all(counts.sum(axis=1) == 5)
    se = np.sqrt(5 * w * (1 - w) / n_runs)
    np.testing.assert_array_less(np.abs(counts.mean(axis=0) - 5 * w), 5 * se)


def test_offspring_counts_do_not_depend_on_thread_count():
    lw = np.linspace(-2, 0, 50)
    one = core.offspring_counts(lw, "stratified", n_runs=64, seed=3, n_threads=1)
    two = core.offspring_counts(lw, "stratified", n_runs=64, seed=3, n_threads=2)
    many = core.offspring_counts(lw, "stratified", n_runs=64, seed=3, n_threads=8)
    np.testing.assert_array_equal(one, two)
    np.testing.assert_array_equal(one, many)


def test_resample_if_needed():
    opts = core.ResamplingOptions(scheme="residual", ess_threshold=0.5)
    anc, lw, summary = core.resample_if_needed(np.linspace(-50, 0, 100), opts, rng=1)
    assert summary.resampled and summary.num_particles == 100
    assert summary.ess_before < 50
    np.testing.assert_allclose(lw, -np.log(100))
    assert "resampled" in summary.brief_report()
    anc, lw, summary = core.resample_if_needed(np.zeros(10), opts, rng=1)
    assert not summary.resampled
    np.testing.assert_array_equal(anc, np.arange(10))
    with pytest.raises(ValueError, match="ess_threshold"):
        core.ResamplingOptions(scheme="systematic", ess_threshold=2.0)


def test_random_stream_distributions():
    r = core.RandomStream(5)
    u = r.uniform(100000)
    assert 0 <= u.min() and u.max() < 1 and abs(u.mean() - 0.5) < 0.01
    z = r.normal(100000)
    assert abs(z.mean()) < 0.02 and abs(z.std() - 1) < 0.02
    th = r.von_mises(0.5, 4.0, 50000)
    assert np.all(th > -np.pi) and np.all(th <= np.pi)
    assert abs(np.angle(np.mean(np.exp(1j * th))) - 0.5) < 0.02
    k = r.integers(6, 60000)
    assert set(np.unique(k)) == set(range(6))
    assert core.derive_seed(1, 2) == core.derive_seed(1, 2) != core.derive_seed(1, 3)


@pytest.mark.parametrize(
    "bad, message",
    [
        (np.array([0.0, np.nan, 1.0]), "argument 'log_weights': entry 1 is NaN"),
        (np.array([0.0, np.inf]), "argument 'log_weights': entry 1 is \\+inf"),
        (np.zeros((3, 2)), "argument 'log_weights': expected a 1-D array, got 2-D"),
        (np.array([]), "argument 'log_weights': is empty"),
        (np.full(3, -np.inf), "all weights are zero"),
        ("abc", "argument 'log_weights': cannot be converted to a float64 array"),
        (None, "argument 'log_weights': is None"),
    ],
)
def test_bad_input_raises_value_error_and_interpreter_survives(bad, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        core.resample(bad)
    # The interpreter (and the module) keep working afterwards.
    assert core.resample(np.zeros(3)).shape == (3,)


def test_bad_scheme_and_rng():
    with pytest.raises(ValueError, match="unknown resampling scheme 'bootstrap'"):
        core.resample(np.zeros(3), scheme="bootstrap")
    with pytest.raises(ValueError, match="argument 'rng'"):
        core.resample(np.zeros(3), rng="seed")
    with pytest.raises(ValueError, match="argument 'kappa'"):
        core.RandomStream(0).von_mises(0.0, -1.0, 3)


def test_input_is_not_modified_and_non_contiguous_input_works():
    base = np.linspace(-1, 0, 20)
    view = base[::2]  # non-contiguous
    before = view.copy()
    core.normalize_log_weights(view)
    core.resample(view)
    np.testing.assert_array_equal(view, before)
    ints = np.arange(5)  # integer input converts
    assert core.effective_sample_size(ints) > 1
