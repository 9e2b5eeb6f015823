"""Live tracking (indoorloc.fusion.live, indoorloc.pdr.streaming, fusion.GridFilterSession): a walk
replayed event by event gives the batch causal filter's track bit for bit (a synthetic walk, and
every walk of the shared data's floor F8 with models from the other walks); the streaming step
detector is causal and close to the batch detector; events out of time order are refused with the
event's index, type and times, and the tracker is unchanged."""

import math
from pathlib import Path

import numpy as np
import pytest

from indoorloc import fusion
from indoorloc.pdr import handheld as ph
from indoorloc.pdr import streaming as ps
from indoorloc.fusion import wifi_fixes as wfx
from indoorloc.fusion import live
from indoorloc.io import load_floor_plan, read_ilc_floor, read_ilc_site
from indoorloc.simulate.ilc_site import make_ilc_site

from stub_fields import stub_fields

SHARED_F8 = Path(__file__).resolve().parents[3] / "shared" / "data" / "fusion" / "ilc2020_site2" / "F8"


def _hall(floors=1):
    box = np.array([[0, 0], [60, 0], [60, 40], [0, 40]], float)
    shop = np.array([[20, 20], [30, 20], [30, 30], [20, 30]], float)
    return fusion.FloorPlan([fusion.FloorGeometry(f, [box], [shop], np.zeros((0, 4))) for f in range(floors)])


def _models(train, floor_number):
    """PDR calibration on the training walks' causal steps, fingerprint database (placed by the
    batch steps: the map is built offline)."""
    causal = [ps.causal_handheld_steps(w) for w in train]
    cal = ph.calibrate_handheld(train, steps_cache=causal)
    db = wfx.build_database(train, wfx.FixSettings(), [ph.handheld_steps(w) for w in train],
                            floors=[floor_number] * len(train))
    return cal, db


def _replay(tracker, walk, cal, db, **kw):
    """Every event of the walk through a LiveTracker; the estimate after each new step."""
    lt = live.LiveTracker(tracker, cal, db, **kw)
    out = []
    for ev in live.walk_events(walk, beacons=True):
        e = lt.add_event(*ev)
        if e is not None and (not out or out[-1].steps != e.steps):
            out.append(e)
    return lt, out


def _assert_replay_equals_batch(tracker, walk, cal, db, **kw):
    batch = live.causal_track(tracker, walk, cal, db, **kw)
    lt, out = _replay(tracker, walk, cal, db, **kw)
    assert len(out) == len(batch["times_s"]) > 0, walk.walk_id
    np.testing.assert_array_equal([e.time_s for e in out], batch["times_s"])
    np.testing.assert_array_equal(np.array([e.mean_m for e in out]), batch["mean_m"])
    np.testing.assert_array_equal(np.array([e.covariance_m2 for e in out]), batch["covariance_m2"])
    np.testing.assert_array_equal(np.array([e.floor_probabilities for e in out]), batch["floor_probabilities"])
    np.testing.assert_array_equal([e.heading_offset_rad for e in out], batch["heading_offset_rad"])
    # located: False until the first fix is applied (an unknown start's prior is not a position),
    # the same per step live and in the batch.
    np.testing.assert_array_equal([e.located for e in out], batch["located"])
    assert all((e.fixes > 0) == e.located for e in out)
    assert [e.fixes for e in out] == sorted(e.fixes for e in out)
    # Every fix the batch used was applied live (the later ones wait for a step).
    assert lt.session.summary.fixes == batch["summary"].fixes
    return batch, lt


# ------------------------------------------------------------------ the C++ session from Python
def test_session_equals_batch_filter_and_refuses_out_of_order_events():
    plan = _hall(2)
    tracker = fusion.GridTracker(plan, fusion.GridTrackerOptions(heading_offset_bins=5, heading_offset_sd_rad=0.2))
    rng = np.random.default_rng(3)
    n = 40
    t = 1.0 + np.cumsum(rng.uniform(0.45, 0.6, n))
    h = 0.3 + np.cumsum(rng.normal(0, 0.15, n))
    steps = fusion.Steps.from_polar(t, rng.normal(0.7, 0.05, n), h, 0.1, 0.15)
    ft = t[3::5] - 0.1
    means = np.stack([np.column_stack([10 + 0.4 * np.arange(ft.size), 12 + 0.2 * np.arange(ft.size)]),
                      np.tile([40.0, 8.0], (ft.size, 1))], axis=1)
    fixes = fusion.Fixes.from_arrays(ft, means, np.tile([3.0, 5.0], (ft.size, 1)), np.tile([0.8, 0.2], (ft.size, 1)),
                                     np.tile([0, 1], (ft.size, 1)))
    batch = fusion.track_grid(tracker, steps, fixes=fixes, smooth=False)
    session = fusion.GridFilterSession(tracker)
    assert session.estimate() is None and session.floors == [0, 1]
    j = 0
    for k in range(n):
        while j < ft.size and ft[j] <= t[k]:
            session.add_fix(ft[j], means[j], [3.0, 5.0], [0.8, 0.2], [0, 1])
            j += 1
        e = session.add_step(t[k], steps.displacements_m[k], steps.covariances_m2[k])
        assert e.steps == k + 1
        assert e.fixes == j and e.located == (j > 0)
        np.testing.assert_array_equal(e.mean_m, batch["mean_m"][k])
        np.testing.assert_array_equal(e.covariance_m2, batch["covariance_m2"][k])
        np.testing.assert_array_equal(e.floor_probabilities, batch["floor_probabilities"][k])
    assert session.summary.log_evidence == batch["summary"].log_evidence
    before = session.estimate()
    with pytest.raises(ValueError, match=r"'step'.*out of time order.*before the previous step"):
        session.add_step(t[-1] - 1.0, [0.7, 0.0], [0.01, 0.0, 0.01])
    with pytest.raises(ValueError, match=r"'fix'.*not after the latest step.*add it before the step"):
        session.add_fix(t[-1], [[1.0, 1.0]], [3.0])
    assert session.steps == n and np.array_equal(session.estimate().mean_m, before.mean_m)
    # The batch-of-steps form gives the same as one at a time.
    s2 = fusion.GridFilterSession(tracker)
    got = s2.add_steps(steps.times_s[:3], steps.displacements_m[:3], steps.covariances_m2[:3])
    s2.add_fixes(tuple(a[:1] for a in fixes.as_arrays()))   # between steps 2 and 3
    with pytest.raises(ValueError, match=r"'step'.*before the latest fix"):
        s2.add_step(t[2], steps.displacements_m[2], steps.covariances_m2[2])
    got4 = s2.add_steps(steps.times_s[3:4], steps.displacements_m[3:4], steps.covariances_m2[3:4])
    np.testing.assert_array_equal(np.vstack([got["mean_m"], got4["mean_m"]]), batch["mean_m"][:4])
    np.testing.assert_array_equal(np.r_[got["located"], got4["located"]], [False, False, False, True])
    # A known start is a position from the first step, with no fix.
    known = fusion.GridFilterSession(tracker, {"position_m": [10.0, 12.0], "floor": 0, "heading_offset_rad": 0.0,
                                               "time_s": t[1]})
    assert all(known.add_step(t[k], steps.displacements_m[k], steps.covariances_m2[k]).located for k in range(4))
    assert known.estimate().fixes == 0


# ------------------------------------------------------------------ step detector
def test_streaming_detector_is_causal_and_close_to_the_batch_detector():
    truth = make_ilc_site(seed=1, walks_per_floor=2)
    w = truth.walks["F1"][0]
    # Through the files (the detector's real input).
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        floor = read_ilc_site(truth.write(Path(d) / "site"))["F1"]
        walk = floor.walk(w.walk_id)
        full = ps.causal_handheld_steps(walk)
        t, acc, gyro, quat = ps.imu_samples(walk)
        # Causal: the steps of a prefix of the samples are the full run's steps confirmed by then.
        cut = t.size // 2
        det = ps.StreamingStepDetector()
        for k in range(cut):
            det.add_sample(t[k], acc[k], gyro[k], quat[k])
        prefix = det.steps()
        assert 0 < prefix.n_steps < full.n_steps
        np.testing.assert_array_equal(prefix.t_s, full.t_s[:prefix.n_steps])
        np.testing.assert_array_equal(prefix.feature, full.feature[:prefix.n_steps])
        assert np.all(prefix.t_s <= t[cut - 1] - det.latency_s + 1e-9)
        # Close to the whole-walk detector: the true step count, the same headings.
        batch = ph.handheld_steps(walk)
        assert abs(full.n_steps - w.n_steps) <= 2 and abs(batch.n_steps - w.n_steps) <= 2
        m = min(full.n_steps, batch.n_steps)
        assert np.median(np.abs(ph.wrap_angle(full.heading_rad[:m] - batch.heading_rad[:m]))) < 0.05
        with pytest.raises(ValueError, match=r"not after the previous one"):
            det.add_sample(t[cut - 1], acc[0], gyro[0], quat[0])


# ------------------------------------------------------------------ replay = batch causal filter
@pytest.fixture(scope="module")
def synthetic_floor(tmp_path_factory):
    truth = make_ilc_site(seed=0, walks_per_floor=8)
    root = truth.write(tmp_path_factory.mktemp("ilc_live") / "site")
    return read_ilc_site(root)["F1"]


def test_replay_equals_the_batch_causal_filter_on_synthetic_walks(synthetic_floor):
    floor = synthetic_floor
    walks = list(floor.walks())
    plan = load_floor_plan(floor.geojson_path, floors=[1], origin_lon_lat="outline_sw")
    cal, db = _models(walks[:6], 1)
    tracker = fusion.GridTracker(plan, fusion.GridTrackerOptions(heading_offset_sd_rad=max(cal.yaw_offset_spread_rad, 1e-3)))
    for walk in walks[6:]:
        batch, lt = _assert_replay_equals_batch(tracker, walk, cal, db)
        assert batch["summary"].fixes > 0
        # And the live track is a track: within a few metres of the waypoints once fixed.
        idx = np.clip(np.searchsorted(batch["times_s"], walk.waypoint_t_s), 0, len(batch["times_s"]) - 1)
        err = np.hypot(*(batch["mean_m"][idx] - walk.waypoint_xy_m).T)
        assert np.median(err[len(err) // 2:]) < 8.0, err
        # The option that moves each fix by the PDR displacement since the time it describes.
        moved, _ = _assert_replay_equals_batch(tracker, walk, cal, db, delay_compensation=True)
        assert not np.array_equal(moved["mean_m"], batch["mean_m"])


def test_events_out_of_time_order_are_refused_naming_index_type_and_times(synthetic_floor):
    floor = synthetic_floor
    walks = list(floor.walks())
    plan = load_floor_plan(floor.geojson_path, floors=[1], origin_lon_lat="outline_sw")
    tracker = fusion.GridTracker(plan, fusion.GridTrackerOptions())
    lt = live.LiveTracker(tracker)   # no calibration, no WiFi map: defaults
    events = list(live.walk_events(walks[0]))
    for ev in events[:2000]:
        lt.add_event(*ev)
    before = lt.estimate()
    assert before is not None and lt.events == 2000
    kind, t = events[1999][0], events[1999][1]
    with pytest.raises(ValueError) as info:
        lt.add_gyroscope(t - 0.5, [0.0, 0.0, 0.0])
    msg = str(info.value)
    assert "event 2000 (gyroscope at t = " in msg and f"event 1999 ({kind} at t = {t} s)" in msg
    with pytest.raises(ValueError, match=r"event 2000 \(wifi\): time must be finite"):
        lt.add_wifi_scan(float("nan"), [], [], [])
    with pytest.raises(ValueError, match=r"unknown kind 'magnetometer'"):
        lt.add_event("magnetometer", t, [0, 0, 0])
    with pytest.raises(ValueError, match=r"argument 'acc_mps2'"):
        lt.add_accelerometer(t + 1.0, [0.0, float("nan"), 9.8])
    with pytest.raises(ValueError, match=r"one entry per reading"):
        lt.add_wifi_scan(t + 1.0, ["a", "b"], [-60.0], [t])
    assert lt.events == 2000 and lt.estimate() is before
    for ev in events[2000:]:   # continues normally
        lt.add_event(*ev)
    assert lt.estimate().steps > before.steps


@pytest.mark.skipif(not SHARED_F8.is_dir(), reason="the shared ILC 2020 data (../shared/data/fusion) is absent")
def test_replay_equals_the_batch_causal_filter_on_every_walk_of_a_real_floor():
    """Every walk of the shared site's F8 (24 walks), models from the other walks (4 folds)."""
    floor = read_ilc_floor(SHARED_F8)
    walks = list(floor.walks())
    plan = load_floor_plan(floor.geojson_path, floors=[8], origin_lon_lat="outline_sw")
    folds = np.array_split(np.arange(len(walks)), 4)
    checked = 0
    for test in folds:
        train = [w for i, w in enumerate(walks) if i not in set(test.tolist())]
        cal, db = _models(train, 8)
        tracker = fusion.GridTracker(plan, fusion.GridTrackerOptions(
            heading_offset_sd_rad=max(cal.yaw_offset_spread_rad, 1e-3)))
        for i in test:
            _assert_replay_equals_batch(tracker, walks[i], cal, db)
            checked += 1
    assert checked == len(walks) == 24


def test_live_queries_are_walk_queries_and_weighted_maps_replay_equal(synthetic_floor):
    """The live queries are wifi_fixes.walk_queries' fingerprints (timed at their scans); a map
    with lower-weight (grown) fingerprints replays equal too; a map with beacon columns is refused."""
    from dataclasses import replace

    floor = synthetic_floor
    walks = list(floor.walks())
    plan = load_floor_plan(floor.geojson_path, floors=[1], origin_lon_lat="outline_sw")
    cal, db = _models(walks[:6], 1)
    walk = walks[7]
    t_mean, rss = wfx.walk_queries(walk, db)
    scan_t, described, rss_live = live.causal_queries(walk, db)
    order = np.argsort(described, kind="stable")
    np.testing.assert_array_equal(described[order], t_mean)
    np.testing.assert_array_equal(rss_live[order], rss)
    assert np.all(scan_t >= described)
    weighted = wfx.FingerprintDatabase(db.rss_dbm, db.positions_m, db.bssids, db.settings, db.floors, db.walk_index,
                                       db.ap_ratio, np.random.default_rng(0).uniform(0.3, 1.0, db.n_scans))
    tracker = fusion.GridTracker(plan, fusion.GridTrackerOptions(heading_offset_sd_rad=max(cal.yaw_offset_spread_rad, 1e-3)))
    w_batch, _ = _assert_replay_equals_batch(tracker, walk, cal, weighted)
    plain = live.causal_track(tracker, walk, cal, db)
    assert not np.array_equal(w_batch["mean_m"], plain["mean_m"])   # the weights reached the fixes
    if hasattr(db.settings, "beacons"):
        with pytest.raises(ValueError, match=r"beacons off"):
            live.LiveTracker(tracker, cal, db.with_settings(replace(db.settings, beacons=True)))


def test_a_user_standing_still_is_located_from_wifi_alone(synthetic_floor):
    """No step (the phone lies flat): each fix no step has applied standing_after_s after its scan
    is applied at a standing step at the scan's time, so the estimate exists, is located and sits
    where the scans were made; with the option off there is no estimate at all. A recorded walk
    with standing steps (the F8 test above has them on most walks) replays equal to the batch."""
    floor = synthetic_floor
    walks = list(floor.walks())
    plan = load_floor_plan(floor.geojson_path, floors=[1], origin_lon_lat="outline_sw")
    cal, db = _models(walks[:6], 1)
    tracker = fusion.GridTracker(plan, fusion.GridTrackerOptions(heading_offset_sd_rad=max(cal.yaw_offset_spread_rad, 1e-3)))
    walk = walks[7]
    wf = walk.wifi
    t0 = float(wf.scan_time_s[wf.scan_slice(0).start])
    # The walk's first scan, sent again every 2 s by a phone that does not move.
    sl = wf.scan_slice(0)
    names = [wf.bssids[i] for i in wf.bssid_index[sl]]
    age = t0 - wf.last_seen_s[sl]

    def stand(tracker_kw, seconds=8.0):
        lt = live.LiveTracker(tracker, cal, db, **tracker_kw)
        first = None
        for i in range(int(seconds * 50)):
            t = t0 + i / 50
            lt.add_gyroscope(t, [0.0, 0.0, 0.0])
            lt.add_rotation_vector(t, [0.0, 0.0, 0.0, 1.0])
            e = lt.add_accelerometer(t, [0.0, 0.0, 9.80665])
            if i % 100 == 0:
                lt.add_wifi_scan(t, names, wf.rssi_dbm[sl], t - age)
            if e is not None and first is None:
                first = t - t0
        return lt, first

    lt, first = stand({})
    summary = lt.live_session.summary
    assert summary["steps"] == 0 and summary["standing_steps"] == 4 and summary["late_steps"] == 0
    assert first == pytest.approx(live.STANDING_AFTER_S) == 1.0
    e = lt.estimate()
    assert e.located and e.fixes == 4
    truth = walk.waypoint_xy_m[0]
    assert np.hypot(*(np.asarray(e.mean_m) - truth)) < 10.0, (e.mean_m, truth)
    off, first_off = stand({"standing_after_s": 0.0})
    assert off.estimate() is None and first_off is None and off.live_session.summary["pending_fixes"] == 4
    with pytest.raises(ValueError, match=r"standing_after_s"):
        live.LiveTracker(tracker, cal, db, standing_after_s=0.2)


# ------------------------------------------------------------------ one model: the C++ session
def test_cpp_defaults_equal_the_python_settings_they_mirror():
    """The C++ detector, fix and session options restate no default of their own: each equals the
    Python settings class where it was chosen."""
    from indoorloc._core.fusion import FingerprintFixOptions, LiveSessionOptions
    from indoorloc._core.pdr import StreamingStepOptions
    from indoorloc.fusion.site_model import TrackSettings

    h = ph.HandheldOptions()
    for name, value in StreamingStepOptions().to_dict().items():
        if name != "rate_samples":
            assert getattr(h, name) == value, name
    assert ps.RATE_SAMPLES == 25
    f, c = wfx.FixSettings(), FingerprintFixOptions()
    assert (c.query_window_s, c.min_aps, c.sd_m, c.sd_per_db) == (f.query_window_s, f.min_aps, f.sd_m, f.sd_per_db)
    assert (c.matcher.penalty_db, c.matcher.k, c.matcher.temperature_db, c.matcher.strength_scale_db) == \
        (f.penalty_db, f.k, f.temperature_db, f.strength_scale_db)
    o, t = LiveSessionOptions(), TrackSettings()
    assert (o.step_length_sd_fraction, o.step_heading_sd_rad) == (t.step_length_sd_fraction, t.step_heading_sd_rad)
    assert (o.step_length_sd_fraction, o.step_heading_sd_rad) == (live.STEP_LENGTH_SD_FRACTION, live.STEP_HEADING_SD_RAD)
    assert o.step_length_k == h.k and o.heading_source == h.heading_source


def test_bound_session_errors_name_the_argument_and_the_event(synthetic_floor):
    from indoorloc._core.fusion import LiveSession

    floor = synthetic_floor
    plan = load_floor_plan(floor.geojson_path, floors=[1], origin_lon_lat="outline_sw")
    tracker = fusion.GridTracker(plan, fusion.GridTrackerOptions())
    s = LiveSession(tracker, live.session_options())
    assert s.add_gyroscope(1.0, [0.0, 0.0, 0.0]) is None and s.events == 1
    with pytest.raises(ValueError, match=r"argument 'acc_mps2'"):
        s.add_accelerometer(2.0, [0.0, 1.0])
    with pytest.raises(ValueError, match=r"argument 't_s'"):
        s.add_beacon("soon")
    with pytest.raises(ValueError, match=r"event 1 \(beacon at t = 0.5 s\) is out of time order: before event 0 "
                                         r"\(gyroscope at t = 1.0 s\)"):
        s.add_beacon(0.5)
    with pytest.raises(ValueError, match=r"argument 'map.positions_m'"):
        LiveSession(tracker, live.session_options(), (["a"], np.zeros((2, 1)), np.zeros((3, 2)), np.zeros(2),
                                                      None, None))
    with pytest.raises(ValueError, match=r"step_length_k"):
        LiveSession(tracker, live.session_options().replace(step_length_k=-1.0))
    assert s.events == 1 and s.summary["steps"] == 0


# ------------------------------------------------------------------ the estimates' types
def test_estimates_are_typed_results_that_still_read_as_the_former_dicts_with_a_warning(synthetic_floor):
    import pickle
    import warnings
    from collections.abc import Mapping

    particle = fusion.ParticleTracker(_hall(), None, None, fusion.tracker_options(num_particles=200))
    particle.initialize_known(0.0, [5.0, 5.0])
    session = fusion.GridFilterSession(fusion.GridTracker(_hall(2), fusion.GridTrackerOptions(heading_offset_bins=5)))
    walk = next(iter(synthetic_floor.walks()))
    plan = load_floor_plan(synthetic_floor.geojson_path, floors=[1], origin_lon_lat="outline_sw")
    lt = live.LiveTracker(fusion.GridTracker(plan, fusion.GridTrackerOptions()))
    for ev in list(live.walk_events(walk))[:2000]:
        lt.add_event(*ev)
    estimates = [particle.step(0.5, [0.7, 0.0], 0.01 * np.eye(2)), particle.estimate(),
                 session.add_step(0.5, [0.7, 0.0], [0.01, 0.0, 0.01]), session.estimate(), lt.estimate()]
    assert [type(e).__name__ for e in estimates] == ["TrackerEstimate"] * 2 + ["GridFilterEstimate"] * 2 + ["LiveEstimate"]
    assert type(lt.estimate()) is live.LiveEstimate and type(estimates[0]) is fusion.TrackerEstimate
    stubs = stub_fields("fusion.pyi")
    for e in estimates:
        assert stubs[type(e).__name__] == list(type(e)._fields)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            plain = e.to_dict()
        assert isinstance(e, Mapping) and list(plain) == list(type(e)._fields)
        with pytest.raises(AttributeError):
            e.time_s = 1.0  # read-only
        with pytest.warns(DeprecationWarning, match=rf"reading a {type(e).__name__} as a dict \(result\[key\]\)"):
            np.testing.assert_array_equal(e["mean_m"], e.mean_m)
        with pytest.warns(DeprecationWarning, match=r"items\(\)"):
            assert [k for k, _ in e.items()] == list(plain)
        back = pickle.loads(pickle.dumps(e))
        assert isinstance(back, dict) and back["time_s"] == e.time_s
    assert estimates[0].mean_m.shape == (2,) and estimates[0].covariance_m2.shape == (2, 2)
    assert estimates[2].mean_m.shape == (2,) and estimates[2].covariance_m2.shape == (3,) and estimates[2].steps == 1
    e = lt.estimate()
    assert e.floors.dtype == np.int64 and list(e.floors) == [1] and e.floor == 1
    assert e.floor_probabilities.shape == (1,)
