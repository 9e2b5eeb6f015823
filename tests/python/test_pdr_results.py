"""The pdr functions return typed read-only results that still read as the dicts they replace."""

import pickle
from collections.abc import Mapping

import numpy as np
import pytest

from indoorloc import pdr


def _still_recording(n=300, rate_hz=100.0):
    rng = np.random.default_rng(0)
    t = np.arange(n) / rate_hz
    acc = np.tile([0.0, 0.0, 9.81], (n, 1)) + 0.01 * rng.normal(size=(n, 3))
    gyro = 0.001 * rng.normal(size=(n, 3))
    return t, acc, gyro


def test_zupt_ekf_result_is_typed_and_reads_as_its_former_dict():
    t, acc, gyro = _still_recording()
    out = pdr.zupt_ekf(t, acc, gyro, np.ones(t.size, bool))
    assert type(out).__name__ == "ZuptEkfOutput" and isinstance(out, Mapping)
    assert list(out) == ["positions_m", "filtered_positions_m", "velocities_mps", "headings_rad",
                         "quaternions_wxyz", "position_sd_m", "seconds", "health"]
    np.testing.assert_array_equal(out["positions_m"], out.positions_m)
    assert out.positions_m.shape == (t.size, 3)
    assert out["health"]["n_samples"] == out.health.n_samples == t.size
    assert "health" in out and "nothing" not in out and out.get("nothing", 3) == 3
    with pytest.raises(KeyError):
        out["nothing"]
    with pytest.raises(AttributeError):
        out.seconds = 1.0  # read-only
    plain = out.to_dict()
    assert isinstance(plain, dict) and isinstance(plain["health"], dict)
    assert set(dict(out)) == set(plain)
    back = pickle.loads(pickle.dumps(out))  # pickles as its dict (Dask)
    assert isinstance(back, dict) and back["health"]["report"] == out.health.report


def test_every_pdr_result_type_lists_its_fields_once():
    t, acc, gyro = _still_recording()
    stance = np.ones(t.size, bool)
    results = [
        pdr.zero_velocity(acc, gyro, 100.0),
        pdr.count_strides(stance, 100.0),
        pdr.attitude_mahony(t, acc, gyro),
        pdr.positions_from_strides([0.7, 0.7], [0.0, 0.1]),
        pdr.calibrate_weinberg_k([1.0, 2.0, 3.0], [0.7, 1.4, 2.1]),
    ]
    for r in results:
        assert isinstance(r, Mapping)
        assert list(r.keys()) == list(type(r)._fields)
        for key, value in r.items():
            got = getattr(r, key)
            if isinstance(value, np.ndarray):
                np.testing.assert_array_equal(got, value)
            else:
                assert got == value
    assert results[1]["stride_indices"].dtype == np.int64
    assert results[4]["k"] == pytest.approx(0.7)


def test_result_stubs_list_the_bound_fields():
    from indoorloc._core import pdr as core_pdr
    from stub_fields import stub_fields

    stubs = stub_fields("pdr.pyi")
    results = {name: cls for name, cls in vars(core_pdr).items() if isinstance(cls, type) and hasattr(cls, "_fields")}
    assert len(results) == 8
    for name, cls in results.items():
        assert stubs[name] == list(cls._fields), name
