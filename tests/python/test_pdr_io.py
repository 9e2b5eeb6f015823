"""Foot-IMU loaders (indoorloc.io.pdr_datasets) and the PDR evaluation helpers."""

import math

import numpy as np
import pytest

from indoorloc.experiments import pdr_evaluate as pe
from indoorloc.pdr import metrics
from indoorloc.io import (
    ImuRecording,
    check_imu_units,
    list_pyshoe_trials,
    load_openshoe,
    load_pyshoe_trial,
    load_xio,
)

G = 9.80665


def _walk_like(n, rng, scale_gyro=1.0):
    """n samples of a foot: still first, then swinging (acc m/s^2, gyro rad/s)."""
    acc = np.tile([0.0, 0.0, G], (n, 1)) + 0.02 * rng.standard_normal((n, 3))
    gyro = 0.005 * rng.standard_normal((n, 3))
    k = np.arange(n // 2, n)
    acc[k] += 8.0 * np.sin(k[:, None] * 0.7 + np.array([0.0, 1.0, 2.0]))
    gyro[k] += 5.0 * np.sin(k[:, None] * 0.5 + np.array([0.0, 1.0, 2.0]))
    return acc, gyro * scale_gyro


def _write_xio(path, rng, n=50, repeat_row=10):
    acc, gyro = _walk_like(n, rng)
    t = np.arange(n) * 0.0025
    rows = np.column_stack([t, np.rad2deg(gyro), acc / G])
    rows = np.insert(rows, repeat_row + 1, rows[repeat_row], axis=0)  # exact repeat
    header = ("Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),"
              "Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)")
    np.savetxt(path, rows, delimiter=",", header=header, comments="", fmt="%.9g")
    return acc, gyro, t


# ------------------------------------------------------------------ loaders on generated files
def test_load_xio_converts_units_and_drops_repeated_rows(tmp_path):
    rng = np.random.default_rng(0)
    acc, gyro, t = _write_xio(tmp_path / "short_walk.csv", rng)
    rec = load_xio(tmp_path / "short_walk.csv")
    assert isinstance(rec, ImuRecording)
    assert rec.n_samples == 50 and rec.acc_mps2.shape == (50, 3) and rec.gyro_radps.shape == (50, 3)
    assert np.all(np.diff(rec.time_s) > 0)
    np.testing.assert_allclose(rec.time_s, t, atol=1e-9)
    np.testing.assert_allclose(rec.acc_mps2, acc, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(rec.gyro_radps, gyro, rtol=1e-6, atol=1e-7)
    assert rec.rate_hz == pytest.approx(400.0)
    assert rec.closed_loop and rec.distance_m == 25.0 and rec.truth_xy_m is None
    assert rec.sensor == "xio" and "deg/s" in rec.source_units


def test_load_xio_rejects_repeated_timestamp_with_different_data(tmp_path):
    rng = np.random.default_rng(1)
    p = tmp_path / "w.csv"
    _write_xio(p, rng)
    lines = p.read_text().splitlines()
    fields = lines[12].split(",")
    fields[1] = "123.0"
    lines[12] = ",".join(fields)
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match="not strictly increasing"):
        load_xio(p)


def test_load_openshoe_builds_time_from_rate(tmp_path):
    rng = np.random.default_rng(2)
    acc, gyro = _walk_like(40, rng)
    np.savetxt(tmp_path / "OpenShoeDataSet.txt", np.column_stack([acc, gyro]), delimiter=",",
               fmt="%.8f")
    rec = load_openshoe(tmp_path / "OpenShoeDataSet.txt")
    assert rec.n_samples == 40 and rec.rate_hz == 820.0
    np.testing.assert_allclose(rec.time_s, np.arange(40) / 820.0)
    np.testing.assert_allclose(rec.acc_mps2, acc, atol=1e-7)
    assert rec.closed_loop and rec.distance_m == 81.0
    with pytest.raises(ValueError, match="rate_hz"):
        load_openshoe(tmp_path / "OpenShoeDataSet.txt", rate_hz=0.0)


def _write_pyshoe(path, rng, n=60, acc_scale=1.0, gyro_scale=1.0):
    from scipy.io import savemat

    acc, gyro = _walk_like(n, rng)
    acc[:, 2] *= -1.0  # PyShoe's z points down
    t = 0.005 + np.arange(n) * 0.005
    gt = np.column_stack([np.linspace(0, 3, n), np.zeros(n)])
    savemat(path, {"imu_data": np.column_stack([acc * acc_scale, gyro * gyro_scale]),
                   "timestamps_all": t[None, :], "gt": gt,
                   "strideIndex": np.array([[5, 25, 45]], dtype=np.int64),
                   "timestamps": t[[5, 25, 45]][None, :]})
    return acc, gyro, t, gt


def test_load_pyshoe_trial_and_list(tmp_path):
    rng = np.random.default_rng(3)
    acc, gyro, t, gt = _write_pyshoe(tmp_path / "2017-11-22-11-22-03_LLIO.mat", rng)
    _write_pyshoe(tmp_path / "2017-11-22-11-23-25_LLIO.mat", rng)
    trials = list_pyshoe_trials(tmp_path)
    assert [p.name for p in trials] == ["2017-11-22-11-22-03_LLIO.mat", "2017-11-22-11-23-25_LLIO.mat"]
    rec = load_pyshoe_trial(trials[0])
    assert rec.name == "2017-11-22-11-22-03" and rec.sensor == "pyshoe" and not rec.closed_loop
    np.testing.assert_allclose(rec.acc_mps2, acc)
    np.testing.assert_allclose(rec.time_s, t)
    np.testing.assert_allclose(rec.truth_xy_m, gt)
    np.testing.assert_array_equal(rec.stride_indices, [5, 25, 45])
    assert rec.rate_hz == pytest.approx(200.0)
    assert rec.distance_m == pytest.approx(gt[45, 0] - gt[5, 0])
    with pytest.raises(ValueError, match="root"):
        list_pyshoe_trials(tmp_path / "absent")


# ------------------------------------------------------------------ unit checks
def test_pyshoe_gyro_in_degps_declared_radps_is_rejected(tmp_path):
    _write_pyshoe(tmp_path / "t.mat", np.random.default_rng(4), gyro_scale=180.0 / math.pi)
    with pytest.raises(ValueError, match=r"gyro.*deg/s"):
        load_pyshoe_trial(tmp_path / "t.mat")


def test_openshoe_acc_in_g_declared_mps2_is_rejected(tmp_path):
    acc, gyro = _walk_like(40, np.random.default_rng(5))
    np.savetxt(tmp_path / "o.txt", np.column_stack([acc / G, gyro]), delimiter=",")
    with pytest.raises(ValueError, match=r"acc.*look like g"):
        load_openshoe(tmp_path / "o.txt")


def test_check_imu_units_names_argument_and_unit():
    acc, gyro = _walk_like(200, np.random.default_rng(6))
    check_imu_units(acc, gyro)  # plausible: no error
    with pytest.raises(ValueError, match=r"'gyro_radps'.*deg/s"):
        check_imu_units(acc, np.rad2deg(gyro))
    with pytest.raises(ValueError, match=r"'acc_mps2'.*look like g"):
        check_imu_units(acc / G, gyro)
    with pytest.raises(ValueError, match=r"'acc_mps2'.*multiplied by g"):
        check_imu_units(acc * G, gyro)
    with pytest.raises(ValueError, match=r"'gyro_radps'.*converted to rad/s twice"):
        check_imu_units(acc, np.deg2rad(gyro))
    with pytest.raises(ValueError, match="NaN"):
        check_imu_units(np.full((3, 3), np.nan), gyro[:3])


# ------------------------------------------------------------------ metrics
def test_align_2d_recovers_rotated_translated_path():
    rng = np.random.default_rng(7)
    truth = np.cumsum(rng.standard_normal((100, 2)), axis=0)
    theta = 0.83
    c, s = math.cos(theta), math.sin(theta)
    est = (truth - truth[0]) @ np.array([[c, -s], [s, c]]).T + np.array([5.0, -3.0])
    est3 = np.column_stack([est, rng.standard_normal(100)])  # z is ignored
    aligned, angle = metrics.align_2d(est3, truth, n_align=10, return_angle=True)
    np.testing.assert_allclose(aligned, truth, atol=1e-10)
    assert angle == pytest.approx(-theta)
    assert metrics.armse(aligned, truth) == pytest.approx(0.0, abs=1e-10)
    still = np.zeros((5, 2))
    np.testing.assert_allclose(metrics.align_2d(still, still + 1.0, 5), still + 1.0)
    with pytest.raises(ValueError, match="n_align"):
        metrics.align_2d(est, truth, 1)


def test_armse_known_case():
    truth = np.zeros((4, 2))
    est = np.array([[3.0, 4.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])  # errors 5, 0, 0, 0
    assert metrics.armse(est, truth) == pytest.approx(math.sqrt(25.0 / 4.0))
    with pytest.raises(ValueError, match="truth_xy"):
        metrics.armse(est, truth[:3])


def test_strides_from_stance_merges_flicker():
    rate = 100.0
    s = np.ones(200, dtype=bool)
    s[20:60] = False      # stride 1 ends at 60
    s[80:120] = False     # stride 2 ends at 120
    s[100] = True         # 10 ms stance flicker inside a swing: ignored
    s[150:152] = False    # 20 ms swing flicker inside a stance: ignored
    np.testing.assert_array_equal(pe.strides_from_stance(s, rate), [60, 120])


def test_strides_from_stance_splits_a_swing_with_a_missed_stance():
    rate = 100.0
    s = np.ones(1000, dtype=bool)
    for a in (100, 200, 300, 500, 600):  # 40-sample swings; 300-380 is a double swing (missed stance)
        s[a:a + 40] = False
    s[300:380] = False
    np.testing.assert_array_equal(pe.strides_from_stance(s, rate, long_swing_factor=None), [140, 240, 380, 540, 640])
    np.testing.assert_array_equal(pe.strides_from_stance(s, rate), [140, 240, 340, 380, 540, 640])
    with pytest.raises(ValueError, match="long_swing_factor"):
        pe.strides_from_stance(s, rate, long_swing_factor=0.5)


def test_evaluations_with_a_fake_method(tmp_path):
    rng = np.random.default_rng(8)
    recs = []
    for i in range(2):
        _write_pyshoe(tmp_path / f"t{i}.mat", rng)
        recs.append(load_pyshoe_trial(tmp_path / f"t{i}.mat"))

    def fake(rec, threshold=1.0):
        xy = rec.truth_xy_m[:, ::-1] * [1.0, -1.0] + 2.0  # truth rotated by -90 deg, shifted
        xy = xy + (threshold - 1.0) * 0.1 * np.arange(rec.n_samples)[:, None] / rec.n_samples
        return np.column_stack([xy, np.zeros(rec.n_samples)]), np.array([10, 30])

    res = pe.evaluate_recordings(recs, fake)
    assert res["median_armse_m"] == pytest.approx(0.0, abs=1e-9)
    assert res["trials"][0]["stride_count_error"] == 0
    best, scores = pe.tune_threshold(recs, fake, [3.0, 1.0, 2.0])
    assert best == 1.0 and scores[1.0] < scores[2.0] < scores[3.0]
    loop = pe.score_closed_loop(recs[0], fake(recs[0]))
    assert loop["final_error_2d_m"] == pytest.approx(3.0)
    assert loop["final_error_2d_pct"] == pytest.approx(100.0)
    md = pe.markdown(pyshoe=res, closed_loops={"recordings": [loop], "samples_per_s": 1.0})
    assert "0.38" in md and "| t0 |" in md


# ------------------------------------------------------------------ real data (small)
def _static_acc_norm(rec, n=50):
    return float(np.linalg.norm(rec.acc_mps2[:n].mean(axis=0)))


def test_real_xio_files(shared_data):
    root = shared_data / "pdr" / "xio_gait_tracking"
    if not root.is_dir():
        pytest.skip(f"{root} not found")
    for name, n_rows, n_repeats in (("short_walk", 16539, 205), ("long_walk", 28132, 252)):
        rec = load_xio(root / f"{name}.csv")
        assert rec.n_samples == n_rows - n_repeats
        assert rec.acc_mps2.shape == (rec.n_samples, 3) and rec.gyro_radps.shape == (rec.n_samples, 3)
        assert rec.rate_hz == pytest.approx(398.0, abs=3.0)
        assert _static_acc_norm(rec) == pytest.approx(9.8, abs=0.2)
        assert np.all(np.diff(rec.time_s) > 0)


def test_real_openshoe_file(shared_data):
    p = shared_data / "pdr" / "openshoe_figure8" / "OpenShoeDataSet.txt"
    if not p.is_file():
        pytest.skip(f"{p} not found")
    rec = load_openshoe(p)
    assert rec.acc_mps2.shape == (51055, 3) and rec.rate_hz == 820.0
    assert rec.duration_s == pytest.approx(62.3, abs=0.5)
    assert _static_acc_norm(rec) == pytest.approx(9.8, abs=0.2)


def test_real_pyshoe_trials(shared_data):
    root = shared_data / "pdr" / "pyshoe_vicon"
    if not root.is_dir():
        pytest.skip(f"{root} not found")
    trials = list_pyshoe_trials(root)
    assert len(trials) == 21
    for path in trials[:2]:
        rec = load_pyshoe_trial(path)
        n = rec.n_samples
        assert rec.acc_mps2.shape == (n, 3) and rec.truth_xy_m.shape == (n, 2)
        assert rec.rate_hz == pytest.approx(200.0, abs=1.0)
        assert _static_acc_norm(rec) == pytest.approx(9.8, abs=0.2)
        assert rec.acc_mps2[:50, 2].mean() < -8.0  # sensor z down
        assert rec.stride_indices[0] > 0 and rec.stride_indices[-1] < n
        assert np.linalg.norm(rec.truth_xy_m[rec.stride_indices[0]]) < 0.05  # rest at start


def test_zupt_ekf_method_on_a_real_trial(shared_data):
    try:
        from indoorloc import pdr
        pdr.zupt_ekf  # noqa: B018
        pdr.shoe_detector  # noqa: B018
    except (ImportError, AttributeError):
        pytest.skip("pdr bindings not built yet")
    root = shared_data / "pdr" / "pyshoe_vicon"
    if not root.is_dir():
        pytest.skip(f"{root} not found")
    rec = load_pyshoe_trial(list_pyshoe_trials(root)[0])
    res = pe.evaluate_recordings([rec], pe.zupt_ekf_method)
    row = res["trials"][0]
    assert math.isfinite(row["armse_m"]) and row["armse_m"] < 2.0
    assert row["strides_detected"] is not None
