"""Python side of pdr: detectors and the ZUPT EKF on a synthetic still-then-move recording."""

import numpy as np
import pytest

from indoorloc import pdr


def still(n, rng):
    acc = np.tile([0.0, 0.0, 9.81], (n, 1)) + 0.01 * rng.normal(size=(n, 3))
    gyro = 0.001 * rng.normal(size=(n, 3))
    return acc, gyro


def test_detectors_and_ekf_shapes_on_a_still_recording():
    rng = np.random.default_rng(0)
    acc, gyro = still(400, rng)
    t = np.arange(400) / 200.0
    stance = pdr.shoe_detector(acc, gyro, options=pdr.ShoeOptions(threshold=1e4))
    assert stance.dtype == bool and stance.shape == (400,) and stance.all()
    out = pdr.zupt_ekf(t, acc, gyro, stance, options=pdr.ZuptEkfOptions(smooth=True))
    assert out["positions_m"].shape == (400, 3) and np.abs(out["positions_m"]).max() < 1e-3
    steps, sigma = pdr.steps_acceleration(acc, 200.0)
    assert steps == [] and sigma.shape == (400,)
    assert pdr.steps_gyro(gyro, 200.0) == []


def test_bad_input_raises_value_error():
    rng = np.random.default_rng(1)
    acc, gyro = still(100, rng)
    t = np.arange(100) / 100.0
    with pytest.raises(ValueError, match="gyro_radps"):
        pdr.shoe_detector(acc, gyro[:50])
    bad = acc.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        pdr.zupt_ekf(t, bad, gyro, np.ones(100, bool))
    with pytest.raises(ValueError, match="shorter than one window"):
        pdr.shoe_detector(acc[:3], gyro[:3], options=pdr.ShoeOptions(window=5))
    with pytest.raises(ValueError, match="unit g"):
        pdr.zupt_ekf(t, acc / 9.81 / 100, gyro, np.ones(100, bool))
    with pytest.raises(ValueError, match="rate_hz"):
        pdr.steps_gyro(gyro, -1.0)
