"""Weinberg stride length: the Butterworth filter against scipy.signal, K calibration, and the
mobgap loader on a tiny generated file."""

import numpy as np
import pytest
from scipy import signal
from scipy.io import savemat

from indoorloc import pdr
from indoorloc.io import load_mobgap_trials


@pytest.mark.parametrize("order,cutoff,rate,highpass", [(4, 3.0, 100.0, False), (3, 0.5, 100.0, True),
                                                        (5, 20.0, 200.0, False)])
def test_butterworth_and_filter_match_scipy(order, cutoff, rate, highpass):
    rng = np.random.default_rng(0)
    x = 9.81 + rng.normal(size=700)
    sos = pdr.butterworth_sos(order, cutoff, rate, highpass)
    b, a = signal.butter(order, cutoff, fs=rate, btype="high" if highpass else "low")
    np.testing.assert_allclose(pdr.sos_filter(sos, x), signal.lfilter(b, a, x), rtol=1e-9, atol=1e-10)
    ref_sos = signal.butter(order, cutoff, fs=rate, btype="high" if highpass else "low", output="sos")
    zi = signal.sosfilt_zi(ref_sos) * x[0]
    np.testing.assert_allclose(pdr.sos_filter(sos, x, steady_state_start=True),
                               signal.sosfilt(ref_sos, x, zi=zi)[0], rtol=1e-9, atol=1e-9)


def test_weinberg_lengths_follow_eq_4_and_k_calibrates():
    rate = 100.0
    t = np.arange(1500) / rate
    acc = np.zeros((t.size, 3))
    acc[:, 2] = 9.81 + 1.5 * np.sin(2 * np.pi * 1.0 * t)
    steps = np.arange(150, 1400, 100)
    lengths = pdr.weinberg_stride_lengths(acc, rate, steps, options=pdr.WeinbergOptions(k=0.5, window_s=0.5))
    np.testing.assert_allclose(lengths, 0.5 * 3.0 ** 0.25, rtol=0.01)
    iv = np.column_stack([steps - 50, steps + 50])
    f = pdr.weinberg_features(acc, rate, iv)
    np.testing.assert_allclose(0.5 * f, lengths, rtol=1e-12)
    cal = pdr.calibrate_weinberg_k(f, 0.7 * f)
    assert cal["k"] == pytest.approx(0.7) and cal["n_strides"] == f.size
    assert pdr.calibrate_weinberg_k_from_distance(f, 0.7 * f.sum())["k"] == pytest.approx(0.7)


def test_weinberg_bad_input_names_the_argument():
    acc = np.tile([0.0, 0.0, 9.81], (200, 1))
    with pytest.raises(ValueError, match="step_indices"):
        pdr.weinberg_stride_lengths(acc, 100.0, [50, 20])
    with pytest.raises(ValueError, match="acc_mps2"):
        pdr.weinberg_stride_lengths(acc[:10], 100.0, [5])
    bad = acc.copy()
    bad[4, 2] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        pdr.weinberg_stride_lengths(bad, 100.0, [50])
    with pytest.raises(ValueError, match="intervals"):
        pdr.weinberg_features(acc, 100.0, [[10, 500]])
    with pytest.raises(ValueError, match="cutoff_hz"):
        pdr.butterworth_sos(4, 80.0, 100.0)
    with pytest.raises(ValueError, match="lengths_m"):
        pdr.calibrate_weinberg_k([1.0, 1.0], [1.0])


def _mobgap_file(path, n=600):
    rng = np.random.default_rng(3)
    t = np.arange(n) / 100.0
    acc_g = np.column_stack([1.0 + 0.2 * np.sin(2 * np.pi * t), 0.01 * rng.normal(size=n), 0.01 * rng.normal(size=n)])
    gyr = 20.0 * np.sin(2 * np.pi * t)[:, None] * np.ones((1, 3))
    lb = {"Acc": acc_g, "Gyr": gyr, "Mag": np.tile([10.0, -14.0, -13.0], (n, 1)),
          "Timestamp": 1.6e9 + t, "Fs": {"Acc": 100, "Gyr": 100, "Mag": 100}}
    wb = {"Start": 1.0, "End": 5.0, "InitialContact_Event": np.array([1.0, 1.5, 2.0, 2.5, np.nan]),
          "Stride_InitialContacts": np.array([[100.0, 200.0], [150.0, 250.0], [200.0, np.nan]]),
          "Stride_Length": np.array([1.1, 1.2, 1.0])}
    trial = {"SU": {"LowerBack": lb}, "Standards": {"INDIP": {"MicroWB": wb, "Fs": 100}}}
    savemat(path, {"data": {"TimeMeasure1": {"Test5": {"Trial1": trial}}}})


def test_load_mobgap_converts_units_and_drops_unresolved_strides(tmp_path):
    d = tmp_path / "HA" / "009"
    d.mkdir(parents=True)
    _mobgap_file(d / "data.mat")
    (trial,) = load_mobgap_trials(d / "data.mat")
    rec = trial.recording
    assert trial.name == "HA/009 Test5 Trial1" and rec.sensor == "mobgap"
    np.testing.assert_allclose(np.median(rec.acc_mps2[:, 0]), 9.80665, rtol=0.05)
    assert rec.time_s[0] == 0.0 and rec.rate_hz == pytest.approx(100.0)
    assert rec.mag_uT.shape == (600, 3)
    np.testing.assert_array_equal(trial.stride_intervals, [[100, 200], [150, 250]])
    np.testing.assert_allclose(trial.stride_lengths_m, [1.1, 1.2])
    assert trial.bout_initial_contacts[0].tolist() == [100, 150, 200, 250]


def test_load_mobgap_rejects_a_missing_file(tmp_path):
    with pytest.raises(ValueError, match="path"):
        load_mobgap_trials(tmp_path / "nope.mat")


def test_mobgap_evaluations_on_a_generated_subject(tmp_path):
    from indoorloc.experiments import pdr_stride_length as ps

    d = tmp_path / "HA" / "009"
    d.mkdir(parents=True)
    _mobgap_file(d / "data.mat")
    det = ps.evaluate_step_detectors_mobgap(tmp_path)
    assert det["reference_steps"] == 4 and det["n_bouts"] == 1
    res = ps.evaluate_weinberg_mobgap(tmp_path, eval_test="Test5")
    assert res["rows"][0]["n_strides"] == 2 and res["pooled_k"] > 0
    with pytest.raises(ValueError, match="root"):
        ps.evaluate_weinberg_mobgap(tmp_path / "nothing")
