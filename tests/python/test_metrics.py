import numpy as np
import pytest

from indoorloc import metrics


def test_error_stats_and_cdf():
    est = np.array([[0.0, 0.0], [3.0, 4.0], [1.0, 0.0]])
    ref = np.zeros((3, 2))
    e = metrics.position_errors(est, ref)
    np.testing.assert_allclose(e, [0.0, 5.0, 1.0])
    s = metrics.error_stats(e)
    assert s.mean == pytest.approx(2.0) and s.median == pytest.approx(1.0) and s.max == 5.0
    assert s.rmse == pytest.approx(np.sqrt(26 / 3))
    x, p = metrics.empirical_cdf(e)
    np.testing.assert_allclose(x, [0, 1, 5])
    np.testing.assert_allclose(p, [1 / 3, 2 / 3, 1])
    lo, hi = metrics.bootstrap_interval(np.arange(100.0), n_boot=500)
    assert lo < 49.5 < hi


def test_metrics_reject_bad_input():
    with pytest.raises(ValueError, match="estimated_m"):
        metrics.position_errors(np.zeros((3, 2)), np.zeros((2, 2)))
    with pytest.raises(ValueError, match="NaN"):
        metrics.error_stats(np.array([1.0, np.nan]))
    with pytest.raises(ValueError, match="empty"):
        metrics.error_stats(np.array([]))
