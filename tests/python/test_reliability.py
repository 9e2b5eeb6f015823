"""Regression tests for the known defects of issue 17, through the Python API.

Calls that used to crash the interpreter or hang run in a child process (``_in_child``) so
that a regression fails one test instead of killing pytest.
"""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from indoorloc import core, io, mapmatch, network, pdr, wifi


def _in_child(code: str, timeout: float = 60.0) -> str:
    """Runs `code` in a fresh interpreter; returns its stdout; fails on a crash or a hang."""
    proc = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, timeout=timeout)
    assert proc.returncode == 0, f"exit {proc.returncode}\n{proc.stdout}\n{proc.stderr[-3000:]}"
    return proc.stdout


def _lattice_model():
    pos = np.array([[x, y] for x in np.arange(0, 11, 2.0) for y in np.arange(0, 11, 2.0)])
    aps = np.array([[-1, -1], [11, -1], [-1, 11], [11, 11]])
    d = np.linalg.norm(pos[:, None, :] - aps[None], axis=2)
    return wifi.RssModel(wifi.SignalMap(pos, None, -40 - 20 * np.log10(d + 0.5), 4 + 0.3 * d))


# --------------------------------------------------------------------------------- crashes


def test_grid_posterior_grid_index_is_bounds_checked():
    out = _in_child("""
        import numpy as np
        from indoorloc import wifi
        pos = np.array([[x, y] for x in np.arange(0, 11, 2.0) for y in np.arange(0, 11, 2.0)])
        d = np.linalg.norm(pos[:, None, :] - np.array([[-1, -1], [11, -1], [-1, 11]])[None], axis=2)
        gp = wifi.GridPosterior(wifi.RssModel(wifi.SignalMap(pos, None, -40 - 20 * np.log10(d + .5), 4 + d)))
        assert gp.grid(0).shape[1] == 2
        for bad in (100000, -1, 1):
            try:
                gp.grid(bad)
            except IndexError as e:
                assert "floor_index" in str(e) and str(bad) in str(e), e
            else:
                raise SystemExit(f"grid({bad}) returned")
        print("ok")
    """)
    assert out.strip() == "ok"


def test_huge_slow_parameter_stride_does_not_abort_inside_ceres():
    out = _in_child("""
        from indoorloc import network
        from indoorloc.simulate.flight import simulate_flight, small_config
        flight = simulate_flight(small_config(line_length_m=400.0, turn_radius_m=100.0, cross_margin_m=100.0,
                                              imu_rate_hz=10.0, gps_rate_hz=1.0), seed=1, noise=False)
        for stride in (2**31 - 1, 2**31 - 2):
            o = network.flight_options(flight.config, slow_parameter_stride=stride)
            state, summary, _ = network.solve_flight(flight, o, xover=False, initial=dict(flight.truth))
            assert summary["num_slow_nodes"] == 1, summary
        print("ok")
    """, timeout=300)
    assert out.strip().endswith("ok")
    o = network.NetworkOptions()
    with pytest.raises((ValueError, TypeError)):
        o.slow_parameter_stride = 2**31  # does not fit the C++ int: refused at assignment


# --------------------------------------------------------------------------------- hangs


def test_von_mises_huge_kappa_returns_the_normal_limit():
    out = _in_child("""
        from indoorloc import core
        x = core.RandomStream(1).von_mises(0.0, 1e17, 5)
        print(x.tolist())
    """, timeout=30)
    draws = np.array(json.loads(out))
    assert draws.shape == (5,) and np.all(np.abs(draws) < 1e-6)
    x = core.RandomStream(2).von_mises(1.0, 1e12, 20000)
    assert x.var() * 1e12 == pytest.approx(1.0, rel=0.05)
    with pytest.raises(ValueError, match="mu_rad"):
        core.RandomStream(1).von_mises(np.nan, 1.0, 3)


def test_simulate_trajectory_with_huge_heading_kappa_returns():
    _in_child("""
        from indoorloc import mapmatch
        from indoorloc.io import grid_with_diagonals_segments
        net = mapmatch.RoadNetwork(*grid_with_diagonals_segments(3, 2, 10.0))
        t = mapmatch.simulate_trajectory(net, mapmatch.TrajectoryOptions(duration_s=10, heading_kappa=1e300))
        import numpy as np
        assert np.all(np.isfinite(t["heading_rad"]))
    """, timeout=30)


def test_find_crossovers_without_separation_finishes():
    # One line flown back and forth: every sample near every other (this took 29 s once, now well
    # under a second). No timing threshold (house rule): a return of that shows as a slow suite.
    n = 800
    t = np.arange(n) * 0.5
    s = np.mod(np.arange(n) * 1.3, 120.0)
    x = np.where(s < 60, s, 120 - s)
    pos = np.c_[x, np.zeros(n), np.zeros(n)]
    pairs = network.find_crossovers(t, pos, radius_m=5.0, min_separation_s=0.0)
    assert pairs.shape[1] == 2 and len(pairs) > 0
    with pytest.raises(ValueError, match="radius_m"):
        network.find_crossovers(np.arange(4600.0), np.c_[np.arange(4600.0), np.zeros((4600, 2))],
                                radius_m=1e9, max_height_difference_m=1e9, min_separation_s=0.0)


def test_iteration_counts_and_sizes_are_bounded():
    with pytest.raises(ValueError, match="iterations_per_scan"):
        wifi.tracker_options(iterations_per_scan=2**31 - 1).validate()
    with pytest.raises(ValueError, match="nx"):
        io.grid_with_diagonals_segments(10**5, 10**5, 1.0)
    net = mapmatch.RoadNetwork(*io.grid_with_diagonals_segments(3, 2, 10.0))
    with pytest.raises(ValueError, match="n_runs"):
        mapmatch.monte_carlo(net, mapmatch.TrajectoryOptions(duration_s=1e6, dt_s=0.1),
                             mapmatch.FilterOptions(num_particles=10), n_runs=10**6)
    with pytest.raises(ValueError, match="size"):
        core.RandomStream(1).normal(10**12)
    # Found by the property suite: these asked for 26 GB and were killed by the OOM killer.
    with pytest.raises(ValueError, match="'num_out'.*would need"):
        core.resample(np.zeros(3), num_out=2**31 - 1)
    with pytest.raises(ValueError, match="'n_runs'.*would need"):
        core.offspring_counts(np.zeros(1000), n_runs=2**31 - 1)
    with pytest.raises(ValueError, match="max_points_per_floor"):
        wifi.GridPosterior(_lattice_model(), max_points_per_floor=2**31 - 1)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT delivery")
@pytest.mark.parametrize("threads", [1, 2])
def test_ctrl_c_interrupts_a_long_monte_carlo(threads):
    code = f"""
        import os, signal, threading, time
        from indoorloc import mapmatch
        from indoorloc.io import grid_with_diagonals_segments
        # Python installs its KeyboardInterrupt handler only when SIGINT is not ignored at start-up,
        # and a shell without job control starts background commands (`make test &`, CI runners)
        # with SIGINT ignored, which the child inherits: os.kill would then do nothing and the run
        # would go on until the timeout. Install the handler an interactive Python has.
        signal.signal(signal.SIGINT, signal.default_int_handler)
        net = mapmatch.RoadNetwork(*grid_with_diagonals_segments(3, 2, 10.0))
        threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        start = time.time()
        try:
            mapmatch.monte_carlo(net, mapmatch.TrajectoryOptions(duration_s=1e6, dt_s=0.5),
                                 mapmatch.FilterOptions(num_particles=2000), n_runs=4, n_threads={threads})
        except KeyboardInterrupt:
            print("interrupted after", round(time.time() - start, 1))
    """
    out = _in_child(code, timeout=60)
    assert out.startswith("interrupted after")
    assert float(out.split()[-1]) < 10.0


# --------------------------------------------------------------------------------- silent NaN


@pytest.mark.parametrize("field", ["sigma_acc_mps2", "sigma_gyro_radps", "sigma_zupt_mps", "gravity_mps2"])
@pytest.mark.parametrize("value", [np.inf, 1e-300, np.nan])
def test_zupt_ekf_refuses_non_finite_or_absurd_sigmas(field, value):
    if field == "gravity_mps2" and value == 1e-300:
        value = 1e300
    rng = np.random.default_rng(0)
    acc = np.tile([0.0, 0.0, 9.81], (100, 1)) + 0.01 * rng.normal(size=(100, 3))
    gyro = 0.001 * rng.normal(size=(100, 3))
    with pytest.raises(ValueError, match=f"'options': {field} must be"):
        pdr.zupt_ekf(np.arange(100) / 100.0, acc, gyro, np.ones(100, bool), options=pdr.ZuptEkfOptions(**{field: value}))


@pytest.mark.parametrize("field", ["kp", "ki", "kp_mag", "gravity_mps2"])
def test_attitude_mahony_refuses_infinite_gains(field):
    rng = np.random.default_rng(0)
    acc = np.tile([0.0, 0.0, 9.81], (100, 1)) + 0.01 * rng.normal(size=(100, 3))
    with pytest.raises(ValueError, match=f"{field} must be in"):
        pdr.attitude_mahony(np.arange(100) / 100.0, acc, 0.001 * rng.normal(size=(100, 3)),
                            options=pdr.MahonyOptions(**{field: np.inf}))


def test_scalar_arguments_must_be_finite():
    net = mapmatch.RoadNetwork(*io.grid_with_diagonals_segments(3, 2, 10.0))
    with pytest.raises(ValueError, match="along_m"):
        net.point_at(0, np.nan)
    with pytest.raises(ValueError, match="latitude_rad"):
        network.earth_rate_enu(np.nan)
    with pytest.raises(ValueError, match="speed_noise_sd_mps"):
        mapmatch.simulate_trajectory(net, mapmatch.TrajectoryOptions(speed_noise_sd_mps=np.inf))
    with pytest.raises(ValueError, match="rate_hz"):
        pdr.butterworth_sos(4, 3.0, 1e300)


def test_sos_filter_refuses_unstable_and_pole_at_one_sections():
    x = np.ones(3000)
    with pytest.raises(ValueError, match="section 0 is not stable"):
        pdr.sos_filter(np.array([[1.0, 0.0, 0.0, 1.0, 0.0, -1.5]]), x)
    with pytest.raises(ValueError, match="not stable"):  # integer section, double pole at z = 1
        pdr.sos_filter(np.array([[1, 1, 1, 1, -2, 1]]), x, steady_state_start=True)


def test_delaunay_with_a_tiny_triangle_and_huge_rss_stay_finite_or_refuse():
    tiny = np.array([[0.0, 0.0], [1e-300, 0.0], [0.0, 1e-300]])
    try:
        interp = wifi.DelaunayInterpolator(tiny, np.ones((3, 1)))
        values = interp.interpolate(np.array([[1e-301, 1e-301]]))[0]
        assert np.all(np.isfinite(values))
    except ValueError as e:
        assert "positions_m" in str(e)
    model = _lattice_model()
    for scans in (np.full((1, 4), 1e300), np.full((1, 4), -1e300)):
        with pytest.raises(ValueError, match="'rss_dbm'.*must be in"):
            wifi.locate_ml(model, scans)
        with pytest.raises(ValueError, match="'rss_dbm'.*must be in"):
            wifi.GridPosterior(model, spacing_m=1.0).locate(scans)


def test_load_rss_rtt_room_refuses_nan_ap_positions(tmp_path):
    from test_wifi_io import write_office_room

    root = write_office_room(tmp_path / "rooms", "1,nan,15", ["0.0,1.0,4000.0,4000.0,4000.0,-50.0,-60.0,-70.0,1"])
    with pytest.raises(io.FormatError, match="AP_position.txt.*NaN or infinite AP coordinate"):
        io.load_rss_rtt_room(root, "office")


# --------------------------------------------------------------------------------- wrong values


def test_road_network_ids_beyond_32_bits_are_refused():
    seg, _ = io.grid_with_diagonals_segments(1, 1, 10.0)
    ids = np.arange(1, len(seg) + 1, dtype=np.int64)
    ids[0] = 2**31
    with pytest.raises(ValueError, match="ids.*does not fit in a 32-bit integer"):
        mapmatch.RoadNetwork(seg, ids)


@pytest.mark.parametrize("floor", [np.nan, 1e30])
def test_floors_of_nan_or_1e30_are_refused(floor, tmp_path):
    from indoorloc.io import FingerprintSplit

    with pytest.raises(ValueError, match="floors"):
        FingerprintSplit(rss_dbm=np.zeros((1, 2)), positions_m=np.zeros((1, 2)),
                         floors=np.array([floor]), point_ids=np.array([0]))
    month = tmp_path / "uji" / "db" / "01"
    month.mkdir(parents=True)
    for stem, first in (("trn01", 101100101), ("tst01", 101200101)):
        (month / f"{stem}rss.csv").write_text("-60,100\n-80,-50\n")
        (month / f"{stem}crd.csv").write_text(f"1.5,2.25,{floor!r}\n4.0,2.25,3\n".replace("nan", "NaN"))
        (month / f"{stem}tms.csv").write_text("20160602155217232\n20160602155220732\n")
        (month / f"{stem}ids.csv").write_text(f"{first}\n{first + 1}\n")
    with pytest.raises(io.FormatError, match="crd.csv"):
        io.load_uji_library(tmp_path / "uji")


def test_set_particles_refuses_bad_directions_and_fractional_segments():
    net = mapmatch.RoadNetwork(*io.grid_with_diagonals_segments(3, 2, 10.0))
    pf = mapmatch.ParticleMapMatcher(net, mapmatch.FilterOptions(num_particles=3))
    seg, along = np.zeros(3), np.ones(3)
    with pytest.raises(ValueError, match="directions.*must be \\+1 or -1, got -7"):
        pf.set_particles(seg, np.array([1, -7, 1]), along)
    with pytest.raises(ValueError, match="segments.*not an integer, got 1.5"):
        pf.set_particles(np.array([0.0, 1.5, 2.0]), np.ones(3), along)
    pf.set_particles(seg, np.array([1, -1, 1]), along)
    assert list(pf.particle_states()[1]) == [1, -1, 1]


def test_resample_num_out_minus_two_is_refused():
    lw = np.zeros(4)
    assert core.resample(lw, num_out=-1).shape == (4,)
    with pytest.raises(ValueError, match="num_out.*got -2"):
        core.resample(lw, num_out=-2)


@pytest.mark.parametrize("fn", [
    lambda a: core.log_sum_exp(a),
    lambda a: pdr.sos_filter(pdr.butterworth_sos(2, 1.0, 10.0), a),
    lambda a: network.normal_gravity(0.5, a),
])
def test_complex_arrays_are_refused_not_truncated(fn):
    with pytest.raises(ValueError, match="complex"):
        fn(np.array([1.0 + 2.0j, 3.0 + 0.0j]))


def test_write_geojson_segments_only_writes_what_the_reader_accepts(tmp_path):
    seg = np.array([[0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 1.0, 0.0]])
    with pytest.raises(ValueError, match="segments_m.*row 1 is a zero-length segment"):
        io.write_geojson_segments(tmp_path / "a.geojson", seg)
    with pytest.raises(ValueError, match="ids.*does not fit in int64"):
        io.write_geojson_segments(tmp_path / "b.geojson", seg[:1], np.array([2**64 - 1], dtype=np.uint64))
    ids = np.array([2**63 - 1], dtype=np.uint64)
    io.write_geojson_segments(tmp_path / "c.geojson", seg[:1], ids)
    back, back_ids = io.read_geojson_segments(tmp_path / "c.geojson")
    np.testing.assert_array_equal(back, seg[:1])
    assert back_ids.tolist() == [2**63 - 1]
    (tmp_path / "d.csv").write_text("id,x_a,y_a,x_b,y_b\n18446744073709551615,0,0,1,0\n")
    with pytest.raises(io.FormatError, match="d.csv.*line 2.*does not fit in int64"):
        io.read_csv_segments(tmp_path / "d.csv")


# --------------------------------------------------------------------------------- messages


def test_messages_name_the_field_or_argument():
    rng = np.random.default_rng(0)
    acc = np.tile([0.0, 0.0, 9.81], (100, 1)) + 0.01 * rng.normal(size=(100, 3))
    with pytest.raises(ValueError, match=r"sigma_acc_mps2 must be finite and in \[1e-12, 1e\+12\], got inf"):
        pdr.zupt_ekf(np.arange(100) / 100.0, acc, np.zeros((100, 3)), np.ones(100, bool),
                     options=pdr.ZuptEkfOptions(sigma_acc_mps2=np.inf))
    net = mapmatch.RoadNetwork(*io.grid_with_diagonals_segments(3, 2, 10.0))
    with pytest.raises(ValueError, match="junction_kappa must be in"):
        mapmatch.ParticleMapMatcher(net, mapmatch.FilterOptions(num_particles=10, junction_kappa=1e300))
    with pytest.raises(ValueError, match="gravity_mps2 must be in"):
        pdr.zupt_ekf(np.arange(100) / 100.0, acc, np.zeros((100, 3)), np.ones(100, bool),
                     options=pdr.ZuptEkfOptions(gravity_mps2=np.inf))
    with pytest.raises(ValueError, match="'rng'.*2\\*\\*64"):
        core.resample(np.zeros(3), rng=-1)
    with pytest.raises(ValueError, match="'size'.*would need"):
        core.RandomStream(1).uniform(2**40)


@pytest.mark.parametrize("text, match", [
    ('{"type": "FeatureCollection", "features": [' + "[" * 5000 + "]" * 5000 + "]}", "damaged file|nesting"),
    (b"\xff\xfe{}", "damaged file|cannot read|UnicodeDecodeError|invalid"),
])
def test_loaders_raise_format_error_naming_the_file(tmp_path, text, match):
    p = tmp_path / "bad.geojson"
    if isinstance(text, bytes):
        p.write_bytes(text)
    else:
        p.write_text(text)
    with pytest.raises(io.FormatError, match="bad.geojson") as info:
        io.read_geojson_segments(p)
    assert isinstance(info.value, ValueError)


def test_none_for_a_model_or_catalog_is_refused_not_dereferenced():
    # Found by the property suite: locate_ml(model=None) crashed the interpreter.
    out = _in_child("""
        import numpy as np
        from indoorloc import analog, wifi
        for call in (lambda: wifi.locate_ml(None, np.zeros((1, 4))),
                     lambda: wifi.GridPosterior(None),
                     lambda: wifi.GradientTracker(None),
                     lambda: analog.AnalogHMM(None, k=3, observed=[0], R=np.eye(1))):
            try:
                call()
            except (ValueError, TypeError) as e:
                assert "model" in str(e) or "catalog" in str(e) or "incompatible" in str(e), e
            else:
                raise SystemExit("accepted None")
        print("ok")
    """)
    assert out.strip() == "ok"


def test_loader_column_errors_are_format_errors_naming_the_file(tmp_path):
    p = tmp_path / "walk.csv"
    header = ("Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),"
              "Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)")
    rows = "\n".join(f"{0.01 * k},1e999,0,0,0,0,1" for k in range(20))
    p.write_text(header + "\n" + rows + "\n")
    with pytest.raises(io.FormatError, match="walk.csv"):
        io.load_xio(p)


def test_linear_ins_network_names_the_rate_not_the_assembler():
    # Issue 17: a rate of 1e300 made every block NaN and was reported as argument 'assemble'.
    with pytest.raises(ValueError, match="imu_rate_hz must be finite and in"):
        network.solve_folded_linear_ins_network(network.LinearInsNetworkOptions(imu_rate_hz=1e300))
    with pytest.raises(ValueError, match="duration_s"):
        network.solve_folded_linear_ins_network(network.LinearInsNetworkOptions(duration_s=np.inf))


# ------------------------------------------------------- network options (issue 17, second pass)


def test_network_scale_solver_options_use_the_validation_vocabulary():
    from indoorloc._core import network as cn

    SMALL = cn.LinearInsNetworkOptions(imu_rate_hz=10.0, duration_s=60.0, gps_rate_hz=1.0)
    # TiedSolveOptions: an iteration count of 2**31 - 1 used to be accepted (hours of PCG).
    with pytest.raises(ValueError, match=r"max_iterations must be in \[1, 1000000\], got 2147483647"):
        cn.solve_linear_ins_network_with_crossovers(SMALL, 3, 3, 1e-5, 2**31 - 1, 1e-8)
    with pytest.raises(ValueError, match=r"relative_tolerance must be in \(0, 1\), got nan"):
        cn.solve_linear_ins_network_with_crossovers(SMALL, 3, 3, 1e-5, 100, float("nan"))
    # FoldedNetworkOptions: any thread count used to pass.
    with pytest.raises(ValueError, match=r"num_threads.: must be in \[-1024, 1024\], got 1000000"):
        network.solve_repeated_pass_network(10.0, 20.0, 1.0, 10, 2, num_threads=10**6)
    with pytest.raises(ValueError, match="checkpoint_interval must be >= 0, got -1"):
        network.solve_repeated_pass_network(10.0, 20.0, 1.0, 10, 2, checkpoint_interval=-1)


def test_network_exports_refuse_more_than_the_memory_limit():
    from indoorloc._core import network as cn

    # 2e7 unknowns asked numpy for 34 GB of dense blocks.
    with pytest.raises(ValueError, match="argument 'duration_s': .* would need .* GB"):
        cn.linear_ins_normal_blocks(cn.LinearInsNetworkOptions(imu_rate_hz=18109.0, duration_s=60.0, gps_rate_hz=1.0))


# ------------------------------------------------------------- loaders (issue 17, second pass)


def test_mobgap_and_surimi_fields_raise_format_errors(tmp_path):
    from scipy.io import savemat

    from test_pdr_stride_length import _mobgap_file

    d = tmp_path / "HA" / "009"
    d.mkdir(parents=True)
    _mobgap_file(d / "data.mat")
    from scipy.io import loadmat
    doc = loadmat(d / "data.mat", simplify_cells=True)
    doc["data"]["TimeMeasure1"]["Test5"]["Trial1"]["SU"]["LowerBack"]["Timestamp"][3] = np.nan
    savemat(d / "data.mat", doc)
    with pytest.raises(io.FormatError, match="data.mat.*Timestamp: holds NaN"):  # NaN times passed through
        io.load_mobgap_trials(d / "data.mat")
    root = tmp_path / "surimi"
    root.mkdir()
    macs = np.array([[-60, 100], [100, -50]], np.int16)
    labels = np.array([[1.0, 2.0, 0.0, 0, 0], [3.0, 4.0, 0.0, 0, 0]])
    cell = np.array([np.ones(2), "x"], dtype=object)
    savemat(root / "LIB1.mat", {"database": {"trainingMacs": macs, "testMacs": macs, "trainingLabels": labels,
                                             "testLabels": cell}})
    with pytest.raises(io.FormatError, match="LIB1.mat: field database.testLabels: expected a real matrix"):
        io.load_surimi(root, "LIB1")  # named the folder only


def test_ilc_floor_origin_of_a_damaged_geojson_is_a_format_error(tmp_path):
    path = tmp_path / "geojson_map.json"
    path.write_text("")
    with pytest.raises(io.FormatError, match="geojson_map.json"):
        io.ilc_floor_origin_lonlat(path)


def test_ilc_readers_give_format_errors_also_from_their_own_module(tmp_path):
    # They used to be wrapped only in indoorloc.io: indoorloc.io.ilc2020.read_ilc_walk gave a
    # plain ValueError (or an IndexError) for the same damaged walk.
    from indoorloc.io import ilc2020

    walk = tmp_path / "walk.txt"
    walk.write_text("#\tstartTime:1574147450000\n1574147450100\tTYPE_ACCELEROMETER\t0.1\n")
    for read in (io.read_ilc_walk, ilc2020.read_ilc_walk):
        with pytest.raises(io.FormatError, match="walk.txt"):
            read(walk)
    (tmp_path / "floor" / "path_data_files").mkdir(parents=True)
    with pytest.raises(io.FormatError, match="floor"):
        ilc2020.read_ilc_floor(tmp_path / "floor")
    assert io.read_ilc_site is ilc2020.read_ilc_site


def test_network_noise_bounds_and_crossover_line_counts():
    from indoorloc._core import network as cn

    o = network.NetworkOptions()
    o.gyro_noise_radps_rthz = 2.0**31  # passed as a Scale; kalman_smoother returned NaN positions
    assert "gyro_noise_radps_rthz must be in [1e-12, 10]" in o.is_valid()
    ko = network.KalmanSmootherOptions()
    ko.init_sigma_heading_rad = 2.0**31
    with pytest.raises(ValueError, match=r"init_sigma_heading_rad must be in \[1e-12, 10\]"):
        network.kalman_smoother(network.NetworkObservations(np.arange(3.0), np.zeros((3, 3)), np.zeros((3, 3)),
                                                           np.arange(1.0), np.zeros((1, 3))), {}, options=ko)
    with pytest.raises(ValueError, match=r"argument 'lines': must be in \[1, 1000000\]"):
        cn.solve_linear_ins_network_with_crossovers(  # was bad_alloc
            cn.LinearInsNetworkOptions(imu_rate_hz=10.0, duration_s=60.0, gps_rate_hz=1.0), 2**31 - 1, 3)


def test_grid_posterior_refuses_reference_points_at_absurd_coordinates():
    from indoorloc import wifi

    pos = np.array([[x, y] for x in np.arange(0, 11, 2.0) for y in np.arange(0, 11, 2.0)])
    d = np.linalg.norm(pos[:, None, :] - np.array([[-1, -1], [11, -1], [-1, 11]])[None], axis=2)
    far = pos.copy()
    far[0] = [1e300, 0.0]
    for p in (far, pos * 1e7):
        with pytest.raises(ValueError, match="'model'.*1e7 m"):
            wifi.GridPosterior(wifi.RssModel(wifi.SignalMap(p, None, -40 - 20 * np.log10(d + .5), 4 + d)))
