"""The pdr functions take their settings as one ``options=`` argument (an Options class bound once,
defaults read from the C++ struct); the former separate keywords still work for one release with a
DeprecationWarning and give the same result (docs/api_changes.md)."""

import warnings

import numpy as np
import pytest

from indoorloc import pdr
from indoorloc.simulate.foot_gait import foot_gait


@pytest.fixture(scope="module")
def walk():
    return foot_gait(4, seed=3)


def _stance(rec):
    return np.asarray(pdr.shoe_detector(rec.acc_mps2, rec.gyro_radps, pdr.ShoeOptions(threshold=1e5)), dtype=bool)


def _same(a, b):
    """Two results (arrays, tuples, typed results) hold equal values."""
    if hasattr(a, "to_dict"):
        a, b = a.to_dict(), b.to_dict()
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a:
            if key not in ("seconds", "report"):  # timings differ run to run
                _same(a[key], b[key])
    elif isinstance(a, tuple):
        assert len(a) == len(b)
        for x, y in zip(a, b):
            _same(x, y)
    elif isinstance(a, (str, bool)) or a is None:
        assert a == b
    else:
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def _cases(rec):
    """(function, data arguments, Options class, changed fields) for every pdr function with options."""
    t, acc, gyro, rate = rec.time_s, rec.acc_mps2, rec.gyro_radps, rec.rate_hz
    stance = _stance(rec)
    steps = np.flatnonzero(stance[1:] & ~stance[:-1]) + 1
    quats = np.asarray(pdr.attitude_mahony(t, acc, gyro)["quaternions_wxyz"])
    inc = np.asarray(pdr.ins_zupt_increments(t, acc, quats, steps)["increments_m"])
    intervals = np.column_stack([np.maximum(steps - 20, 0), np.minimum(steps + 20, len(t) - 1)])
    return [
        (pdr.shoe_statistic, (acc, gyro), pdr.ShoeOptions, {"window": 7, "sigma_acc_mps2": 0.02}),
        (pdr.shoe_detector, (acc, gyro), pdr.ShoeOptions, {"threshold": 2e5, "window": 3}),
        (pdr.zero_velocity, (acc, gyro, rate), pdr.ZeroVelocityOptions,
         {"rule": "stance_guard", "threshold": 3e4, "min_stance_fraction": 0.4}),
        (pdr.count_strides, (stance, rate), pdr.StrideCountOptions, {"min_stance_s": 0.6}),
        (pdr.steps_acceleration, (acc, rate), pdr.AccelerationStepOptions, {"adaptive": False, "window_s": 0.15}),
        (pdr.steps_gyro, (gyro, rate), pdr.GyroStepOptions, {"threshold_radps": 0.5}),
        (pdr.steps_magnetometer, (gyro * 30.0, rate), pdr.MagneticStepOptions, {"highpass_hz": 1.0}),
        (pdr.weinberg_features, (acc, rate, intervals), pdr.WeinbergOptions, {"cutoff_hz": 2.0}),
        (pdr.weinberg_stride_lengths, (acc, rate, steps), pdr.WeinbergOptions, {"k": 0.5, "window_s": 0.2}),
        (pdr.attitude_mahony, (t, acc, gyro), pdr.MahonyOptions, {"kp": 2.0, "init_samples": 10}),
        (pdr.positions_from_strides, (np.full(5, 0.7), np.linspace(0, 1, 5)), pdr.StepCovarianceOptions,
         {"sigma_heading_step_rad": 0.1}),
        (pdr.positions_from_increments, (inc,), pdr.StepCovarianceOptions, {"stride_length_sd_fraction": 0.2}),
        (pdr.ins_zupt_increments, (t, acc, quats, steps), pdr.InsZuptOptions, {"window_s": 0.1}),
        (pdr.zupt_ekf, (t, acc, gyro, stance), pdr.ZuptEkfOptions, {"smooth": True, "sigma_zupt_mps": 0.02}),
    ]


def test_options_form_and_deprecated_keyword_form_agree(walk):
    for fn, args, cls, fields in _cases(walk):
        name = fn.__name__
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # the options form never warns
            default = fn(*args)
            new = fn(*args, options=cls(**fields))
            assert _is_same(fn(*args, options=None), default), name
            assert _is_same(fn(*args, options=cls()), default), name
        with pytest.warns(DeprecationWarning, match=rf"{name}\(\.\.\., .*\) is deprecated; pass options={cls.__name__}"):
            old = fn(*args, **fields)
        _same(new, old)
        assert not _is_same(new, default), f"{name}: {fields} changed nothing (the test would prove nothing)"
        # Keywords change a copy of the given options; the given object is left alone.
        base = cls(**fields)
        with pytest.warns(DeprecationWarning):
            mixed = fn(*args, options=base, **{k: v for k, v in list(fields.items())[:1]})
        _same(mixed, new)
        assert base == cls(**fields)


def _is_same(a, b):
    try:
        _same(a, b)
    except AssertionError:
        return False
    return True


def test_options_are_checked_by_name(walk):
    acc, gyro, rate = walk.acc_mps2, walk.gyro_radps, walk.rate_hz
    with pytest.raises(TypeError, match="got an unexpected keyword argument 'no_such_field'"):
        pdr.zero_velocity(acc, gyro, rate, no_such_field=1)
    with pytest.raises(TypeError, match="argument 'options': zupt_ekf needs a ZuptEkfOptions"):
        pdr.zupt_ekf(walk.time_s, acc, gyro, np.ones(len(acc), bool), options=pdr.ShoeOptions())
    with pytest.raises(TypeError, match="argument 'options'"):
        pdr.shoe_detector(acc, gyro, {"threshold": 1e5})
    with pytest.raises(ValueError, match="rule.*'swing_guard', 'stance_guard' or 'fixed'"):
        pdr.ZeroVelocityOptions(rule="magic")
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="min_stance_fraction"):
        pdr.zero_velocity(acc, gyro, rate, min_stance_fraction=1.5)
    # Options changed by attribute after construction are validated by the algorithm.
    bad = pdr.ZuptEkfOptions()
    bad.sigma_acc_mps2 = float("inf")
    with pytest.raises(ValueError, match="sigma_acc_mps2"):
        pdr.zupt_ekf(walk.time_s, acc, gyro, np.ones(len(acc), bool), options=bad)


def test_zero_velocity_options_flatten_the_shoe_fields():
    o = pdr.ZeroVelocityOptions(threshold=2e4, window=7)
    assert o.threshold == 2e4 and o.window == 7
    # The adaptive detector's own base threshold (1e4, chosen by cross-validation) differs from SHOE's.
    assert pdr.ZeroVelocityOptions().threshold == 1e4 and pdr.ShoeOptions().threshold == 3e4
    assert pdr.ZeroVelocityOptions().rule == "swing_guard"
    assert {"threshold", "window", "sigma_acc_mps2", "sigma_gyro_radps", "gravity_mps2"} <= set(o.to_dict())
