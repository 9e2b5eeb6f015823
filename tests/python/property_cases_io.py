"""The io group of property_cases.py (run it as ``python property_cases.py io``): every loader fed
damaged bytes of a valid file (hypothesis), the .mat loaders fed bad field values, and the writers
and readers of the formats several subsystems share."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from property_harness import Case, probe

def _damage():
    """Ways a file gets damaged: truncation, flipped bytes, huge numbers, bad UTF-8, nesting."""
    from hypothesis import strategies as st

    return st.one_of(
        st.tuples(st.just("truncate"), st.floats(0.0, 1.0)),
        st.tuples(st.just("flip"), st.lists(st.tuples(st.floats(0.0, 1.0), st.integers(0, 255)),
                                            min_size=1, max_size=8)),
        st.tuples(st.just("insert"), st.tuples(st.floats(0.0, 1.0), st.sampled_from(
            [b"nan", b"inf", b"-inf", b"1e999", b"9" * 400, b"\xff\xfe\x00", b",", b"\n", b"\"", b"{",
             b"[" * 5000, b"-", b" ", b"\r\n\r\n", b"18446744073709551615", b"1e-400", b"0x10"]))),
        st.just(("empty", None)),
        st.binary(max_size=300).map(lambda b: ("random", b)),
    )


def _apply(valid: bytes, how) -> bytes:
    kind, arg = how
    if kind == "truncate":
        return valid[: int(arg * len(valid))]
    if kind == "flip":
        data = bytearray(valid)
        for where, byte in arg:
            data[min(int(where * len(data)), len(data) - 1)] = byte
        return bytes(data)
    if kind == "insert":
        where, text = arg
        k = int(where * len(valid))
        return valid[:k] + text + valid[k:]
    if kind == "empty":
        return b""
    return arg


def fuzz_file(name: str, load, folder: Path, damaged: str, arg_name: str = "path") -> None:
    """Damages `folder/damaged`, calls load(); it must return finite data or raise FormatError
    naming the damaged file (`arg_name` is the loader's parameter, for the record)."""
    from hypothesis import given

    from property_harness import TALLY, Case, call

    target = folder / damaged
    valid = target.read_bytes()
    load()  # the undamaged file loads

    # The "argument" spoiled is the file: an error message must name it.
    case = Case(name, lambda **kwargs: _load_as_format_error(load), {damaged: None})
    TALLY.cases += 1

    @given(how=_damage())
    def run(how) -> None:
        target.write_bytes(_apply(valid, how))
        try:
            call(case, damaged, how)
        finally:
            target.write_bytes(valid)

    run()


def _load_as_format_error(load):
    """``load()``, a ValueError that is not a FormatError turned into a RuntimeError: the library
    promises one type for damaged files."""
    from indoorloc.io import FormatError

    try:
        return load()
    except FormatError:
        raise
    except ValueError as exc:
        raise RuntimeError(f"ValueError that is not a FormatError: {exc}") from exc


def _bad_field_values():
    """What a damaged or foreign MAT file may hold where a numeric array belongs."""
    from hypothesis import strategies as st

    return st.sampled_from([
        ("nan", lambda v: np.full(np.shape(v), np.nan)), ("inf", lambda v: np.full(np.shape(v), np.inf)),
        ("1e300", lambda v: np.full(np.shape(v), 1e300)), ("empty", lambda v: np.zeros((0, 0))),
        ("scalar", lambda v: np.array(3.0)), ("string", lambda v: "text"),
        ("transposed", lambda v: np.asarray(v).T), ("flat", lambda v: np.asarray(v).reshape(-1)),
        ("one column", lambda v: np.asarray(v).reshape(np.shape(v)[0], -1)[:, :1] if np.ndim(v) else v),
        ("int64 huge", lambda v: np.full(np.shape(v), 2**62, dtype=np.int64)),
        ("complex", lambda v: np.asarray(v, dtype=float) + 1j), ("struct", lambda v: {"a": 1.0}),
        ("cell", lambda v: np.array([np.ones(2), "x"], dtype=object)),
        ("negative", lambda v: -np.abs(np.asarray(v, dtype=float)) - 1.0),
    ])


def fuzz_mat_fields(name: str, load, target: Path, build, paths) -> None:
    """Structural damage of a MATLAB file: one field at `paths` (tuples of keys into the dict
    `build()` returns) replaced by a bad value. The loader must return or raise FormatError
    naming the file."""
    from hypothesis import given
    from hypothesis import strategies as st
    from scipy.io import savemat

    from property_harness import TALLY, Case, call

    valid = target.read_bytes()
    load()

    case = Case(name, lambda **kwargs: _load_as_format_error(load), {target.name: None})
    TALLY.cases += 1

    @given(where=st.sampled_from(paths), how=_bad_field_values())
    def run(where, how) -> None:
        doc = build()
        node = doc
        for key in where[:-1]:
            node = node[key]
        try:
            node[where[-1]] = how[1](node[where[-1]])
        except (TypeError, ValueError):
            return  # this damage does not apply to that field (e.g. "negative" of a struct)
        try:
            savemat(target, doc)
        except Exception:
            return  # scipy cannot write it: no file to read
        try:
            call(case, target.name, None, shown=f"{'.'.join(where)}={how[0]}")
        finally:
            target.write_bytes(valid)

    run()


def _mobgap_doc(n: int = 300):
    rng = np.random.default_rng(3)
    t = np.arange(n) / 100.0
    acc_g = np.column_stack([1.0 + 0.2 * np.sin(2 * np.pi * t), 0.01 * rng.normal(size=n),
                             0.01 * rng.normal(size=n)])
    gyr = 20.0 * np.sin(2 * np.pi * t)[:, None] * np.ones((1, 3))
    lb = {"Acc": acc_g, "Gyr": gyr, "Mag": np.tile([10.0, -14.0, -13.0], (n, 1)),
          "Timestamp": 1.6e9 + t, "Fs": {"Acc": 100, "Gyr": 100, "Mag": 100}}
    wb = {"Start": 1.0, "End": 2.5, "InitialContact_Event": np.array([1.0, 1.5, 2.0, np.nan]),
          "Stride_InitialContacts": np.array([[100.0, 200.0], [150.0, 250.0], [200.0, np.nan]]),
          "Stride_Length": np.array([1.1, 1.2, 1.0])}
    trial = {"SU": {"LowerBack": lb}, "Standards": {"INDIP": {"MicroWB": wb, "Fs": 100}}}
    return {"data": {"TimeMeasure1": {"Test5": {"Trial1": trial}}}}


def _surimi_doc():
    macs = np.array([[-60, 100, -70], [-61, 100, -71], [100, -50, -80], [100, -51, 100]], np.int16)
    labels = np.array([[10.0, 20.0, 3.7, 1, 0], [10.0, 20.0, 3.7, 1, 0],
                       [10.0, 20.0, 3.7, 1, 0], [15.0, 25.0, 0.0, 0, 0]])
    return {"database": {"trainingMacs": macs, "testMacs": macs[:2].astype(float),
                         "trainingLabels": labels, "testLabels": labels[[1, 3]]}}


def _ilc_floor_summary(floor):
    """What opening a floor folder reads: its size, walks and the GeoJSON origin."""
    return {"n_walks": floor.n_walks, "size": np.asarray([floor.width_m or 0.0, floor.height_m or 0.0]),
            "origin": np.asarray(floor.origin_lonlat())}


def _records(value):
    """Loader output as plain containers, so that the harness sees every array (NaN checks)."""
    import dataclasses

    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _records(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, (list, tuple)):
        return [_records(v) for v in value]
    if isinstance(value, dict):
        return {k: _records(v) for k, v in value.items()}
    return value


def group_io() -> None:
    import tempfile

    from scipy.io import savemat

    from indoorloc import io as iio

    tmp = Path(tempfile.mkdtemp(prefix="indoorloc_fuzz_"))
    seg, ids = iio.grid_with_diagonals_segments(2, 2, 5.0)
    iio.write_geojson_segments(tmp / "roads.geojson", seg, ids)
    fuzz_file("read_geojson_segments", lambda: iio.read_geojson_segments(tmp / "roads.geojson"), tmp,
              "roads.geojson")
    (tmp / "roads.csv").write_text("id,x_a,y_a,x_b,y_b\n" + "".join(
        f"{i},{r[0]},{r[1]},{r[2]},{r[3]}\n" for i, r in zip(ids, seg)))
    fuzz_file("read_csv_segments", lambda: iio.read_csv_segments(tmp / "roads.csv"), tmp, "roads.csv")
    fuzz_file("load_road_network", lambda: iio.load_road_network(tmp / "roads.geojson"), tmp,
              "roads.geojson")

    rng = np.random.default_rng(0)
    n = 40
    t = np.arange(n) * 0.0025
    gyro = rng.normal(size=(n, 3)) * 50.0
    acc = np.tile([0.0, 0.0, 1.0], (n, 1)) + 0.3 * rng.normal(size=(n, 3))
    header = ("Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),"
              "Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)")
    np.savetxt(tmp / "walk.csv", np.column_stack([t, gyro, acc]), delimiter=",", header=header,
               comments="", fmt="%.9g")
    fuzz_file("load_xio", lambda: iio.load_xio(tmp / "walk.csv"), tmp, "walk.csv")
    np.savetxt(tmp / "OpenShoeDataSet.txt", np.column_stack([acc * 9.81, np.deg2rad(gyro)]),
               delimiter=",", fmt="%.8f")
    fuzz_file("load_openshoe", lambda: iio.load_openshoe(tmp / "OpenShoeDataSet.txt"), tmp,
              "OpenShoeDataSet.txt")
    m = 60
    ts = 0.005 + np.arange(m) * 0.005
    acc_p = np.tile([0.0, 0.0, -9.81], (m, 1)) + rng.normal(size=(m, 3))
    savemat(tmp / "trial.mat", {"imu_data": np.column_stack([acc_p, rng.normal(size=(m, 3))]),
                                "timestamps_all": ts[None, :],
                                "gt": np.column_stack([np.linspace(0, 3, m), np.zeros(m)]),
                                "strideIndex": np.array([[5, 25, 45]], dtype=np.int64),
                                "timestamps": ts[[5, 25, 45]][None, :]})
    fuzz_file("load_pyshoe_trial", lambda: iio.load_pyshoe_trial(tmp / "trial.mat"), tmp, "trial.mat")

    from test_wifi_io import write_office_room  # the RSS/RTT room fixture

    rooms = write_office_room(tmp / "rooms", "1,11,15", ["0.0,1.0,4000.0,4000.0,4000.0,-50.0,-60.0,-70.0,1 3",
                                                        "2.0,3.0,4000.0,4000.0,4000.0,-55.0,-65.0,-75.0,1"])
    for damaged in ("AP_position.txt", "database_office_train.csv"):
        fuzz_file(f"load_rss_rtt_room[{damaged}]", lambda: iio.load_rss_rtt_room(rooms, "office"), rooms,
                  damaged, arg_name="root")

    from indoorloc._core.fusion import FloorGeometry

    box = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 10.0], [0.0, 10.0]])
    geometry = FloorGeometry(floor=0, outlines=[box], obstacles=[box * 0.2 + 2.0],
                             walls=np.array([[5.0, 5.0, 8.0, 5.0]]))
    iio.write_geojson_floor(tmp / "plan.geojson", geometry)
    fuzz_file("read_geojson_floor", lambda: iio.read_geojson_floor(tmp / "plan.geojson"), tmp, "plan.geojson")

    from ilc2020_files import write_walk  # the ILC walk fixture

    write_walk(tmp / "walk.txt", seed=1, n_epochs=10)
    fuzz_file("read_ilc_walk", lambda: iio.read_ilc_walk(tmp / "walk.txt"), tmp, "walk.txt")

    month = tmp / "uji" / "db" / "01"
    month.mkdir(parents=True)
    for stem, first in (("trn01", 101100101), ("tst01", 101200101)):
        (month / f"{stem}rss.csv").write_text("-60,100,-70\n-80,-50,100\n")
        (month / f"{stem}crd.csv").write_text("1.5,2.25,3\n4.0,2.25,3\n")
        (month / f"{stem}tms.csv").write_text("20160602155217232\n20160602155220732\n")
        (month / f"{stem}ids.csv").write_text(f"{first}\n{first + 1}\n")
    for damaged in ("trn01crd.csv", "trn01rss.csv", "tst01tms.csv"):
        fuzz_file(f"load_uji_library[{damaged}]", lambda: iio.load_uji_library(tmp / "uji"), month,
                  damaged, arg_name="root")

    # mobgap (lower-back IMU, MATLAB v5 structs): damaged bytes, then damaged fields.
    from scipy.io import savemat as _savemat

    subject = tmp / "mobgap" / "HA" / "009"
    subject.mkdir(parents=True)
    _savemat(subject / "data.mat", _mobgap_doc())
    load_mobgap = lambda: _records(iio.load_mobgap_trials(subject / "data.mat"))  # noqa: E731
    fuzz_file("load_mobgap_trials", load_mobgap, subject, "data.mat")
    trial = ("data", "TimeMeasure1", "Test5", "Trial1")
    lower_back = trial + ("SU", "LowerBack")
    bout = trial + ("Standards", "INDIP", "MicroWB")
    fuzz_mat_fields("load_mobgap_trials[fields]", load_mobgap, subject / "data.mat", _mobgap_doc,
                    [lower_back + (k,) for k in ("Acc", "Gyr", "Mag", "Timestamp", "Fs")]
                    + [lower_back + ("Fs", "Acc")]
                    + [bout + (k,) for k in ("Start", "End", "InitialContact_Event", "Stride_InitialContacts",
                                             "Stride_Length")]
                    + [bout[:-1], trial + ("SU",), trial, ("data", "TimeMeasure1")])
    fuzz_file("list_mobgap_files", lambda: [str(f) for f in iio.list_mobgap_files(tmp / "mobgap")], subject,
              "data.mat", arg_name="root")

    # SURIMI (.mat with struct database).
    surimi = tmp / "surimi"
    surimi.mkdir()
    _savemat(surimi / "LIB1.mat", _surimi_doc())
    load_lib1 = lambda: _records(iio.load_surimi(surimi, "LIB1"))  # noqa: E731
    fuzz_file("load_surimi", load_lib1, surimi, "LIB1.mat", arg_name="root")
    fuzz_mat_fields("load_surimi[fields]", load_lib1, surimi / "LIB1.mat", _surimi_doc,
                    [("database", k) for k in ("trainingMacs", "testMacs", "trainingLabels", "testLabels")]
                    + [("database",)])
    fuzz_file("load_wifi_dataset[surimi_LIB1]", lambda: _records(iio.load_wifi_dataset("surimi:LIB1", tmp)),
              surimi, "LIB1.mat", arg_name="root")

    # The competition's floor folder: its JSON files (the walks are fuzzed above).
    from ilc2020_files import T0, write_floor

    floor_dir = tmp / "site" / "F1"
    write_floor(floor_dir, [1], [T0])
    for damaged in ("floor_info.json", "geojson_map.json"):
        fuzz_file(f"read_ilc_floor[{damaged}]", lambda: _ilc_floor_summary(iio.read_ilc_floor(floor_dir, cache=False)),
                  floor_dir, damaged, arg_name="floor_dir")
    fuzz_file("ilc_floor_origin_lonlat", lambda: iio.ilc_floor_origin_lonlat(floor_dir / "geojson_map.json"),
              floor_dir, "geojson_map.json")
    fuzz_file("read_ilc_site", lambda: iio.read_ilc_site(tmp / "site"), floor_dir, "geojson_map.json",
              arg_name="site_dir")
