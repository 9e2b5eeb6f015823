"""Attitude filter, magnetometer step detector and step-wise positioning (paper eq. 5-9) from Python."""

import numpy as np
import pytest

from indoorloc import pdr
from indoorloc.experiments import pdr_evaluate as pe


def _rotation(n=3000, rate=100.0, seed=0):
    """A sensor yawing at 0.3 rad/s with a constant 10 deg roll, field (20, 0, -40) uT."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate
    yaw = np.where(t > 1.0, 0.3 * (t - 1.0), 0.0)
    rot = Rotation.from_euler("ZX", np.column_stack([yaw, np.full(n, np.deg2rad(10.0))]))
    body_rate = np.zeros((n, 3))
    body_rate[t > 1.0] = rot[t > 1.0].inv().apply([0.0, 0.0, 0.3])
    acc = rot.inv().apply([0.0, 0.0, 9.81]) + 0.02 * rng.normal(size=(n, 3))
    mag = rot.inv().apply([20.0, 0.0, -40.0]) + 0.2 * rng.normal(size=(n, 3))
    gyro = body_rate + 0.002 * rng.normal(size=(n, 3))
    return t, acc, gyro, mag, rot


def test_mahony_follows_a_synthetic_rotation():
    from scipy.spatial.transform import Rotation

    t, acc, gyro, mag, rot = _rotation()
    out = pdr.attitude_mahony(t, acc, gyro, mag)
    q = out["quaternions_wxyz"]
    assert q.shape == (t.size, 4) and out["mag_used"].dtype == bool and out["mag_rejected"] == 0
    est = Rotation.from_quat(q[:, [1, 2, 3, 0]])  # scipy is scalar-last
    err = np.rad2deg((est * rot.inv()).magnitude())
    assert err[500:].max() < 1.5
    no_mag = pdr.attitude_mahony(t, acc, gyro)
    assert no_mag["mag_rejected"] == 0 and not no_mag["mag_used"].any()


def test_mahony_bad_input_names_the_argument():
    t, acc, gyro, mag, _ = _rotation(200)
    with pytest.raises(ValueError, match="mag"):
        pdr.attitude_mahony(t, acc, gyro, mag[:10])
    bad = gyro.copy()
    bad[3, 0] = np.nan
    with pytest.raises(ValueError, match="gyro_radps"):
        pdr.attitude_mahony(t, acc, bad)
    with pytest.raises(ValueError, match="unit g"):
        pdr.attitude_mahony(t, acc / 9.81 / 100, gyro)


def test_magnetometer_steps_on_a_swinging_field():
    rate = 100.0
    t = np.arange(2000) / rate
    swing = (np.mod(t, 1.0) > 0.5) & (t > 1.0)  # 0.5 s swings every second after 1 s
    pitch = np.where(swing, 0.5 * (1 - np.cos(2 * np.pi * (np.mod(t, 1.0) - 0.5) / 0.5)), 0.0)
    mag = np.column_stack([30.0 * np.cos(pitch), np.full(t.size, 5.0), -40.0 + 30.0 * np.sin(pitch)])
    steps, magnitude = pdr.steps_magnetometer(mag, rate)
    assert len(steps) == int(np.sum(np.diff(swing.astype(int)) == -1))
    assert magnitude.shape == (t.size,)
    with pytest.raises(ValueError, match="mag"):
        pdr.steps_magnetometer(mag[:3], rate)


def test_step_positions_carry_a_growing_covariance():
    sl = np.full(20, 0.7)
    heading = np.linspace(0, 1.0, 20)
    tr = pdr.positions_from_strides(sl, heading, start_xy=[1.0, 2.0])
    assert tr["positions_m"].shape == (20, 2) and tr["covariances"].shape == (20, 3, 3)
    np.testing.assert_allclose(tr["positions_m"][0], [1.7, 2.0])
    trace = np.trace(tr["covariances"][:, :2, :2], axis1=1, axis2=2)
    assert np.all(np.diff(trace) > 0)
    np.testing.assert_allclose(tr["covariances"], np.transpose(tr["covariances"], (0, 2, 1)))
    inc = np.column_stack([sl * np.cos(heading), sl * np.sin(heading)])
    tr9 = pdr.positions_from_increments(inc, start_xy=[1.0, 2.0])
    np.testing.assert_allclose(tr9["positions_m"], tr["positions_m"], atol=1e-12)
    with pytest.raises(ValueError, match="headings_rad"):
        pdr.positions_from_strides(sl, heading[:3])
    with pytest.raises(ValueError, match="increments_m"):
        pdr.positions_from_increments(np.ones((3, 4)))


def test_ins_zupt_increments_of_a_straight_push():
    """A foot (sensor level, x forward) still, then 1 m forward in 0.5 s, then still."""
    rate = 200.0
    n = 400
    t = np.arange(n) / rate
    acc = np.tile([0.0, 0.0, 9.81], (n, 1))
    u = (t - 0.5) / 0.5
    moving = (u > 0) & (u < 1)
    # x(u) = u - sin(2 pi u) / (2 pi) [m] over T = 0.5 s: a = 2 pi sin(2 pi u) / T^2
    acc[moving, 0] = 2 * np.pi * np.sin(2 * np.pi * u[moving]) / 0.5 ** 2
    quats = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    out = pdr.ins_zupt_increments(t, acc, quats, [50, 300])
    assert out["increments_m"].shape == (1, 3) and out["velocities_mps"].shape == (n, 3)
    assert out["stride_lengths_m"][0] == pytest.approx(1.0, abs=0.02)
    with pytest.raises(ValueError, match="step_indices"):
        pdr.ins_zupt_increments(t, acc, quats, [300, 50])
    with pytest.raises(ValueError, match="quaternions_wxyz"):
        pdr.ins_zupt_increments(t, acc, 2 * quats, [50, 300])


def test_stance_step_samples_take_the_middle_of_each_stance():
    stance = np.array([1] * 10 + [0] * 100 + [1] * 20 + [0] * 100 + [1] * 30, dtype=bool)
    np.testing.assert_array_equal(pe.stance_step_samples(stance, 100.0), [4, 119, 244])


def test_adaptive_threshold_is_per_sensor_and_from_the_recording():
    rng = np.random.default_rng(5)
    n = 2000
    t = np.arange(n) / 200.0
    acc = np.tile([0.0, 0.0, 9.81], (n, 1)) + 0.01 * rng.normal(size=(n, 3))
    gyro = 0.001 * rng.normal(size=(n, 3))
    swing = np.mod(t, 1.0) > 0.6
    acc[swing] += 20.0 * rng.normal(size=(int(swing.sum()), 3))
    gyro[swing] += 5.0 * rng.normal(size=(int(swing.sum()), 3))
    base = dict(name="x", time_s=t, acc_mps2=acc, gyro_radps=gyro, rate_hz=200.0, truth_xy_m=None,
                stride_indices=None, closed_loop=False, distance_m=None, source_units="")
    xio = pe.ImuRecording(sensor="xio", **base)
    assert pe.adaptive_threshold(xio) == pe.default_threshold(xio) == 3e4
    pyshoe = pe.ImuRecording(sensor="pyshoe", **base)
    rule = pe.ADAPTIVE_SHOE["pyshoe"]
    assert pe.adaptive_threshold(pyshoe) in (rule["low"], rule["high"])
    pos, strides = pe.zupt_adaptive_method(pyshoe)
    assert pos.shape == (n, 3) and strides.ndim == 1
