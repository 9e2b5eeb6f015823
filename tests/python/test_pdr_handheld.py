"""Hand-held phone PDR (indoorloc.pdr.handheld): synthetic steps, K calibration, headings, one
real walk of the ILC 2020 data when present."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from indoorloc.pdr import handheld as ph

RATE = 50.0
G = ph.GRAVITY_MPS2


def _synthetic(n_steps: int = 40, f_hz: float = 1.8, amp: float = 2.5, still_s: float = 4.0,
               heading_rad: float = math.pi / 2, seed: int = 0, amp_sd: float = 0.0):
    """Phone flat (z up), +y towards heading_rad; still, n_steps bounce cycles, still."""
    rng = np.random.default_rng(seed)
    walk_s = n_steps / f_hz
    t = np.arange(0.0, 2 * still_s + walk_s, 1.0 / RATE)
    tw = t - still_s
    walking = (tw >= 0) & (tw < walk_s)
    # One cycle per step, peak at (k + 0.25) / f; amplitude per step (for varying features).
    amps = amp * (1.0 + amp_sd * rng.standard_normal(max(n_steps, 1)))
    k = np.clip(np.floor(tw * f_hz).astype(int), 0, max(n_steps - 1, 0))
    bounce = np.where(walking, amps[k] * np.sin(2 * np.pi * f_hz * tw), 0.0)
    acc = np.column_stack([np.zeros_like(t), np.zeros_like(t), G + bounce]) + 0.03 * rng.standard_normal((t.size, 3))
    q = Rotation.from_euler("z", heading_rad - math.pi / 2).as_quat()  # xyzw
    quat = np.tile(q, (t.size, 1))
    gyro = 0.002 * rng.standard_normal((t.size, 3))
    peaks = still_s + (np.arange(n_steps) + 0.25) / f_hz
    return ph.HandheldArrays(t, acc, gyro, quat), peaks


def test_detector_finds_exactly_the_steps_and_none_when_still():
    arrays, peaks = _synthetic()
    opts = ph.HandheldOptions()
    idx = ph.detect_steps_handheld(arrays, opts)
    assert idx.size == peaks.size
    np.testing.assert_allclose(arrays.t_s[idx], peaks, atol=0.03)
    # A faster walker with a weaker bounce: the threshold follows the signal.
    arrays, peaks = _synthetic(n_steps=30, f_hz=2.2, amp=1.6, seed=1)
    idx = ph.detect_steps_handheld(arrays, opts)
    assert idx.size == peaks.size
    # Still phone only: no step (the absolute floor), also on the vertical signal.
    arrays, _ = _synthetic(n_steps=0)
    assert ph.detect_steps_handheld(arrays, opts).size == 0
    assert ph.detect_steps_handheld(arrays, ph.HandheldOptions(signal="vertical")).size == 0
    st = ph.handheld_steps(arrays, opts)
    assert st.n_steps == 0 and st.length_m.shape == (0,)


def test_handheld_steps_outputs_and_vertical_signal():
    arrays, peaks = _synthetic(heading_rad=0.3)
    st = ph.handheld_steps(arrays, ph.HandheldOptions(signal="vertical", k=0.4, length_sd_fraction=0.1,
                                                      heading_sd_rad=0.2))
    assert st.n_steps == peaks.size
    assert np.all(st.length_m > 0) and np.allclose(st.length_sd_m, 0.1 * st.length_m)
    np.testing.assert_allclose(st.heading_rad, 0.3, atol=0.02)
    np.testing.assert_allclose(st.heading_gyro_rad, 0.3, atol=0.05)
    np.testing.assert_allclose(st.heading_complementary_rad, 0.3, atol=0.05)
    np.testing.assert_allclose(st.heading_sd_rad, 0.2)
    assert "steps" in st.brief_report()


def _fake_walk(arrays: ph.HandheldArrays, wt: np.ndarray, wxy: np.ndarray):
    sensor = lambda v: SimpleNamespace(t_s=arrays.t_s, values=v)  # noqa: E731
    return SimpleNamespace(accelerometer=sensor(arrays.acc_mps2), gyroscope=sensor(arrays.gyro_radps),
                           rotation_vector=sensor(arrays.quat_xyzw[:, :3]),
                           rotation_quaternion_xyzw=lambda: arrays.quat_xyzw, waypoint_t_s=wt, waypoint_xy_m=wxy)


def test_weinberg_k_and_yaw_offset_recovered():
    k_true, floor_dir = 0.43, math.radians(25.0)
    opts = ph.HandheldOptions(k=1.0)
    walks = []
    for seed in range(3):
        arrays, _ = _synthetic(n_steps=36, amp_sd=0.2, seed=seed)  # phone heading north
        st = ph.handheld_steps(arrays, opts)
        assert np.ptp(st.feature) > 0.01  # the features vary from step to step
        wt = np.array([0.0, 6.0, 11.0, 16.0, arrays.t_s[-1]])
        s = k_true * ph.cumulative_at(st, st.feature, wt)  # distance walked at each waypoint
        wxy = np.column_stack([s * math.cos(floor_dir), s * math.sin(floor_dir)]) + [10.0, 5.0]
        walks.append(_fake_walk(arrays, wt, wxy))
    cal = ph.calibrate_handheld(walks, opts)
    assert cal.k == pytest.approx(k_true, rel=1e-9)
    assert cal.k_rms_residual_m < 1e-9
    assert cal.yaw_offset_rad == pytest.approx(floor_dir - math.pi / 2, abs=0.02)
    assert cal.length_sd_fraction < 1e-6
    assert cal.options.k == cal.k and "K 0.430" in cal.brief_report()
    # PDR-only from the first waypoint with the learned offset reaches the last waypoint.
    w = walks[0]
    st = ph.handheld_steps(w, cal.options)
    pos = ph.pdr_track(st, w.waypoint_xy_m[0], w.waypoint_t_s, yaw_offset_rad=cal.yaw_offset_rad)
    np.testing.assert_allclose(pos, w.waypoint_xy_m, atol=0.3)


def test_rotation_vector_heading_of_known_quaternions():
    # Identity: device +y points north.
    assert ph.rotation_vector_heading(np.array([[0.0, 0.0, 0.0, 1.0]]))[0] == pytest.approx(math.pi / 2)
    yaws = np.radians([-170.0, -90.0, 0.0, 30.0, 135.0])
    for pitch_deg, roll_deg in ((0.0, 0.0), (20.0, 0.0), (15.0, -10.0)):
        # R = Rz(yaw) Rx(pitch) Ry(roll): roll about +y leaves +y, pitch lifts it, yaw turns it.
        q = Rotation.from_euler("ZXY", np.column_stack([yaws, np.full(yaws.size, math.radians(pitch_deg)),
                                                        np.full(yaws.size, math.radians(roll_deg))])).as_quat()
        h = ph.rotation_vector_heading(q)
        np.testing.assert_allclose(ph.wrap_angle(h - (math.pi / 2 + yaws)), 0.0, atol=1e-9)
    # Android stores x, y, z only; w = sqrt(1 - |v|^2) reproduces the same heading.
    q = Rotation.from_euler("z", 1.0).as_quat()
    w = math.sqrt(1 - np.sum(q[:3] ** 2))
    assert ph.rotation_vector_heading(np.array([[*q[:3], w]]))[0] == pytest.approx(math.pi / 2 + 1.0)


def test_gyro_heading_integrates_the_vertical_rate_of_a_tilted_phone():
    t = np.arange(0.0, 10.0, 1.0 / RATE)
    rate = 0.3  # rad/s about up
    tilt = Rotation.from_euler("x", math.radians(25.0))
    r = Rotation.from_euler("z", (rate * t)[:, None]) * tilt  # device -> ENU
    gyro = r.inv().apply(np.tile([0.0, 0.0, rate], (t.size, 1)))  # body-frame rate
    h = ph.gyro_heading(t, gyro, r.as_quat())
    np.testing.assert_allclose(h, math.pi / 2 + rate * t, atol=1e-9)
    np.testing.assert_allclose(ph.wrap_angle(ph.rotation_vector_heading(r.as_quat()) - h), 0.0, atol=1e-9)


def test_options_are_checked():
    with pytest.raises(ValueError, match="signal"):
        ph.HandheldOptions(signal="x").validate()
    with pytest.raises(ValueError, match="highpass_hz"):
        ph.HandheldOptions(highpass_hz=5.0).validate()
    with pytest.raises(ValueError, match="acc_mps2"):
        ph.HandheldArrays(np.arange(5.0), np.zeros((4, 3)), np.zeros((5, 3)), np.zeros((5, 4)))


def test_one_real_walk(shared_data: Path):
    from indoorloc.io import read_ilc_floor

    floor_dir = shared_data / "fusion" / "ilc2020_site2" / "F3"
    if not floor_dir.is_dir():
        pytest.skip(f"ILC 2020 site 2 not found at {floor_dir}")
    walk = read_ilc_floor(floor_dir).walk(1)
    st = ph.handheld_steps(walk)
    cadence = 1.0 / np.median(np.diff(st.t_s))
    assert 1.5 < cadence < 2.3
    assert 0.5 < np.median(st.length_m) < 0.9
    iv = ph.waypoint_intervals(st, walk.waypoint_t_s, walk.waypoint_xy_m)
    truth = iv.distance_m.sum()
    assert abs(iv.path_m.sum() - truth) < 0.25 * truth
    # The rotation-vector frame is the floor frame up to a small offset on this site.
    off = ph.best_yaw_offset(iv.direction_rad, iv.disp_rv_m)
    assert abs(math.degrees(off)) < 30


# --------------------------------------------------------------------------------------------
# Non-finite input and wrong names: a ValueError naming the argument (issue 28's probe)


def _steps():
    arrays, _ = _synthetic(n_steps=10)
    st = ph.handheld_steps(arrays, ph.HandheldOptions())
    assert st.n_steps == 10
    return st


def test_pdr_track_refuses_non_finite_input():
    st = _steps()
    t = np.linspace(st.start_t_s, st.t_s[-1], 5)
    assert np.all(np.isfinite(ph.pdr_track(st, [0.0, 0.0], t)))
    from dataclasses import replace

    bad = replace(st, length_m=np.where(np.arange(st.n_steps) == 3, np.nan, st.length_m))
    with pytest.raises(ValueError, match="steps.length_m"):
        ph.pdr_track(bad, [0.0, 0.0], t)
    with pytest.raises(ValueError, match="t_query"):
        ph.pdr_track(st, [0.0, 0.0], np.array([t[0], np.nan]))
    with pytest.raises(ValueError, match="yaw_offset_rad"):
        ph.pdr_track(st, [0.0, 0.0], t, yaw_offset_rad=math.inf)
    with pytest.raises(ValueError, match="start_xy_m"):
        ph.pdr_track(st, [np.nan, 0.0], t)
    with pytest.raises(ValueError, match="'heading'.*'north'"):
        ph.pdr_track(st, [0.0, 0.0], t, heading="north")


def test_rescale_refuses_a_nan_k():
    st = _steps()
    with pytest.raises(ValueError, match="HandheldOptions.k"):
        ph.rescale(st, ph.HandheldOptions(k=math.nan))
    assert np.all(np.isfinite(ph.rescale(st, ph.HandheldOptions(k=0.5)).length_m))


def test_rotation_vector_heading_refuses_nan():
    with pytest.raises(ValueError, match="quat_xyzw"):
        ph.rotation_vector_heading(np.array([0.0, 0.0, np.nan, 1.0]))
    with pytest.raises(ValueError, match="quat_xyzw"):
        ph.rotation_vector_heading(np.zeros(3))
    assert ph.rotation_vector_heading(np.array([0.0, 0.0, 0.0, 1.0]))[0] == pytest.approx(math.pi / 2)


def test_waypoint_intervals_refuses_nan_times():
    st = _steps()
    xy = np.array([[0.0, 0.0], [5.0, 0.0], [5.0, 5.0]])
    t = np.array([st.start_t_s, st.t_s[4], st.t_s[-1]])
    assert ph.waypoint_intervals(st, t, xy).distance_m.shape == (2,)
    with pytest.raises(ValueError, match="waypoint_t_s"):
        ph.waypoint_intervals(st, np.array([t[0], np.nan, t[2]]), xy)
    with pytest.raises(ValueError, match="waypoint_xy_m"):
        ph.waypoint_intervals(st, t, xy[:2])


def test_huge_windows_are_refused_by_name():
    for name in ("rms_window_s", "min_step_interval_s", "max_step_half_window_s", "complementary_tau_s"):
        with pytest.raises(ValueError, match=f"HandheldOptions.{name}"):
            ph.HandheldOptions(**{name: 1e300}).validate()
    arrays, _ = _synthetic(n_steps=4)
    with pytest.raises(ValueError, match="rms_window_s"):
        ph.handheld_steps(arrays, ph.HandheldOptions(rms_window_s=1e300))


def test_calibrate_handheld_refuses_no_walks():
    with pytest.raises(ValueError, match="'walks'"):
        ph.calibrate_handheld([])


def test_absurd_sensor_values_are_named_by_the_user_argument():
    # 1e160 m/s^2 reached the step filter and was refused as its internal argument 'x'; times at
    # 1e300 (or 1e-300 apart) as the filter's 'rate_hz'; a zero quaternion gave a constant heading.
    arrays, _ = _synthetic(n_steps=4)
    t, acc, gyro, q = arrays.t_s, arrays.acc_mps2, arrays.gyro_radps, arrays.quat_xyzw
    spoiled = acc.copy()
    spoiled[10, 2] = 1e160
    with pytest.raises(ValueError, match=r"'acc_mps2': entry \(10, 2\)"):
        ph.HandheldArrays(t, spoiled, gyro, q)
    spoiled = gyro.copy()
    spoiled[3, 0] = -1e300
    with pytest.raises(ValueError, match=r"'gyro_radps': entry \(3, 0\)"):
        ph.HandheldArrays(t, acc, spoiled, q)
    with pytest.raises(ValueError, match=r"'t_s': times must be within"):
        ph.HandheldArrays(t * 1e300, acc, gyro, q)
    with pytest.raises(ValueError, match=r"'t_s': the mean sample interval"):
        ph.HandheldArrays(t * 1e-300, acc, gyro, q)
    with pytest.raises(ValueError, match=r"'quat_xyzw': row 0 has norm 0"):
        ph.HandheldArrays(t, acc, gyro, np.zeros_like(q))
    with pytest.raises(ValueError, match=r"'quat_xyzw'.*complex"):
        ph.HandheldArrays(t, acc, gyro, q.astype(complex))
    # A sample rate the band-pass cannot run at names the option and the times, not 'cutoff_hz'.
    slow = ph.HandheldArrays(t * 60.0, acc, gyro, q)  # 100 Hz -> 1.7 Hz
    with pytest.raises(ValueError, match=r"HandheldOptions.highpass_hz.*t_s"):
        ph.handheld_steps(slow, ph.HandheldOptions(highpass_hz=1.0))


def test_orientation_helpers_refuse_nan_and_name_their_arguments():
    arrays, _ = _synthetic(n_steps=4)
    t, acc, gyro, q = arrays.t_s, arrays.acc_mps2, arrays.gyro_radps, arrays.quat_xyzw
    with pytest.raises(ValueError, match="'acc_mps2'"):
        ph.vertical_acceleration(np.full_like(acc, np.nan), q)  # returned NaN silently
    with pytest.raises(ValueError, match="'gyro_radps'"):
        ph.gyro_heading(t, np.full_like(gyro, np.nan), q)  # returned NaN silently
    with pytest.raises(ValueError, match="'quat_xyzw'"):
        ph.gyro_heading(t, gyro, q[:-1])
    h = np.zeros(t.size)
    with pytest.raises(ValueError, match="'t_s'"):
        ph.complementary_heading(np.zeros(5), np.zeros(5), np.zeros(5), 1.0)  # was 'rate_hz'
    with pytest.raises(ValueError, match="'tau_s'"):
        ph.complementary_heading(t, h, h, math.nan)  # was 'cutoff_hz'
    with pytest.raises(ValueError, match="'heading_gyro_rad'"):
        ph.complementary_heading(t, h, h[:-1], 1.0)
    assert np.all(np.isfinite(ph.complementary_heading(t, h, h, 10.0)))
    assert np.all(np.isfinite(ph.gyro_heading(t, gyro, q)))


def test_a_walk_without_steps_gives_positions_instead_of_a_reshape_error():
    # cumulative_at reshaped (0,) values to (0, -1): numpy's "cannot reshape array of size 0",
    # which ended build_crowd_map for any training walk of a phone held still.
    arrays, _ = _synthetic(n_steps=0)
    st = ph.handheld_steps(arrays)
    assert st.n_steps == 0
    t = np.array([arrays.t_s[0], arrays.t_s[-1]])
    np.testing.assert_array_equal(ph.pdr_track(st, [1.0, 2.0], t), [[1.0, 2.0], [1.0, 2.0]])
    assert ph.cumulative_at(st, np.zeros((0, 3)), t).shape == (2, 3)
    with pytest.raises(ValueError, match="'values'"):
        ph.cumulative_at(st, np.ones(3), t)
