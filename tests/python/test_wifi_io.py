"""indoorloc.io WiFi loaders: small fixtures in the exact file formats, then the real datasets."""

from __future__ import annotations

import datetime as dt
from pathlib import Path
from typing import Dict, List, Sequence, Tuple

import numpy as np
import pytest
import scipy.io

from indoorloc.io import (
    RSS_RTT_ROOMS,
    FingerprintSplit,
    available_datasets,
    load_rss_rtt_room,
    load_surimi,
    load_uji_library,
)

# --------------------------------------------------------------------------------------------
# UJI library fixture: db/01/{trn,tst}NN{rss,crd,tms,ids}.csv, 4 APs, +100 = not heard.

A = (1.5, 2.25, 3)
B = (4.0, 2.25, 3)
C = (1.5, 2.25, 5)  # same x, y as A on another floor: a different point
D = (2.0, 3.0, 5)  # test-only location

UjiRow = Tuple[Tuple[float, float, int], List[float]]


def _write_uji_set(folder: Path, stem: str, rows: Sequence[UjiRow], first_id: int,
                   start: str = "20160602155217232") -> None:
    folder.mkdir(parents=True, exist_ok=True)
    t0 = int(start)
    (folder / f"{stem}rss.csv").write_text(
        "".join(",".join(f"{v:g}" for v in rss) + "\n" for _, rss in rows))
    (folder / f"{stem}crd.csv").write_text(
        "".join(f"{x!r},{y!r},{f}\n" for (x, y, f), _ in rows))
    # Consecutive scans 3.5 s apart, written as yyyymmddHHMMSSfff like the originals.
    (folder / f"{stem}tms.csv").write_text(
        "".join(f"{t0 + 3500 * i}\n" for i in range(len(rows))))
    (folder / f"{stem}ids.csv").write_text(
        "".join(f"{first_id + i}\n" for i in range(len(rows))))


def _uji_fixture(root: Path) -> Path:
    month = root / "db" / "01"
    _write_uji_set(month, "trn01", [(A, [-60, 100, -70, 100]), (A, [-61, 100, -71, 100]),
                                    (B, [-80, -50, 100, 100]), (C, [100, 100, -55, -66])],
                   101100101)
    _write_uji_set(month, "trn02", [(A, [-62, 100, -72, 100]), (B, [-81, -51, 100, 100]),
                                    (B, [-82, -52, 100, 100]), (C, [100, 100, -56, -67])],
                   102100101)
    _write_uji_set(month, "tst01", [(A, [-63, 100, -73, 100]), (C, [100, 100, -57, -68]),
                                    (D, [100, -90, -60, -70])], 101200101)
    return root


def test_uji_library_fixture_shapes_floors_points_and_times(tmp_path: Path) -> None:
    ds = load_uji_library(_uji_fixture(tmp_path / "uji"))
    assert ds.name == "uji_library_month01" and ds.not_heard_sentinel == 100.0
    assert ds.train.rss_dbm.shape == (8, 4) and ds.test.rss_dbm.shape == (3, 4)
    assert ds.train.rss_dbm.dtype == np.float64
    assert ds.ap_names == ["AP001", "AP002", "AP003", "AP004"]
    # Sentinel kept as stored, not replaced.
    assert np.count_nonzero(ds.train.rss_dbm == 100.0) == 16
    assert ds.train.floors.dtype == np.int64 and set(ds.train.floors) == {3, 5}
    np.testing.assert_array_equal(ds.test.floors, [3, 5, 5])
    np.testing.assert_allclose(ds.train.positions_m[2], [4.0, 2.25])
    # Point ids: same (x, y, floor) -> same id, across sets and across splits.
    tr, te = ds.train.point_ids, ds.test.point_ids
    assert tr[0] == tr[1] == tr[4] == te[0]  # A
    assert tr[2] == tr[5] == tr[6] != tr[0]  # B
    assert tr[3] == tr[7] == te[1] not in (tr[0], tr[2])  # C: A's x, y on floor 5
    assert te[2] not in set(tr)  # D
    assert len(set(tr)) == 3
    # Times: yyyymmddHHMMSSfff -> seconds since 1970 with millisecond resolution.
    t0 = dt.datetime(2016, 6, 2, 15, 52, 17, 232000, tzinfo=dt.timezone.utc).timestamp()
    assert ds.train.timestamps[0] == pytest.approx(t0, abs=1e-6)
    assert ds.train.timestamps[1] - ds.train.timestamps[0] == pytest.approx(3.5, abs=1e-6)
    assert ds.ap_positions_m is None


def test_uji_library_fixture_set_selection(tmp_path: Path) -> None:
    root = _uji_fixture(tmp_path / "uji")
    ds = load_uji_library(root, month=1, train_sets=[2], test_sets=[1])
    assert ds.train.rss_dbm.shape == (4, 4)
    np.testing.assert_array_equal(ds.train.rss_dbm[0], [-62, 100, -72, 100])
    with pytest.raises(ValueError, match="argument 'train_sets'"):
        load_uji_library(root, train_sets=[0])


def test_uji_library_fixture_rejects_missing_and_malformed_files(tmp_path: Path) -> None:
    root = _uji_fixture(tmp_path / "uji")
    folder = root / "db" / "01"
    with pytest.raises(ValueError, match="argument 'root'.*month folder"):
        load_uji_library(root, month="02")
    with pytest.raises(ValueError, match="argument 'root'.*trn03rss.csv"):
        load_uji_library(root, train_sets=[1, 3])

    crd = (folder / "trn02crd.csv").read_text()
    (folder / "trn02crd.csv").unlink()
    with pytest.raises(ValueError, match="argument 'root'.*missing file.*trn02crd.csv"):
        load_uji_library(root)
    (folder / "trn02crd.csv").write_text(crd.replace("4.0,2.25,3", "nan,2.25,3", 1))
    with pytest.raises(ValueError, match="argument 'root'.*trn02crd.csv.*NaN"):
        load_uji_library(root)
    (folder / "trn02crd.csv").write_text(crd.replace("4.0,2.25,3", "4.0,2.25", 1))
    with pytest.raises(ValueError, match="argument 'root'.*trn02crd.csv"):
        load_uji_library(root)
    (folder / "trn02crd.csv").write_text(crd)

    rss = (folder / "tst01rss.csv").read_text().splitlines()
    (folder / "tst01rss.csv").write_text("\n".join(rss[:1] + ["-60,100,-70"] + rss[2:]) + "\n")
    with pytest.raises(ValueError, match="argument 'root'.*tst01rss.csv"):
        load_uji_library(root)
    (folder / "tst01rss.csv").write_text("\n".join(r + ",100" for r in rss) + "\n")
    with pytest.raises(ValueError, match="argument 'root'.*tst01rss.csv has 5 columns, expected 4"):
        load_uji_library(root)
    (folder / "tst01rss.csv").write_text("\n".join(rss[:2]) + "\n")
    with pytest.raises(ValueError, match="argument 'root'.*tst01crd.csv has 3 rows"):
        load_uji_library(root)


def test_uji_library_known_error_of_month01_trn14(tmp_path: Path) -> None:
    # The first route stop of month 01's trn14 is labelled floor 0 at y = 16.7 m in the files.
    wrong, right = (12.91385188, 16.69981527, 0), (12.91385188, 29.21654402, 3)
    rows = [(wrong, [-60, 100, -70, 100])] * 6 + [(right, [-61, 100, -71, 100])] * 6
    folder = tmp_path / "uji" / "db" / "01"
    _write_uji_set(folder, "trn14", rows, 114100101)
    _write_uji_set(folder, "tst01", [(right, [-60, 100, -70, 100])], 101200101)
    fixed = load_uji_library(tmp_path / "uji")
    np.testing.assert_array_equal(fixed.train.floors, [3] * 12)
    assert len(set(fixed.train.point_ids)) == 1 and "corrected" in fixed.description
    raw = load_uji_library(tmp_path / "uji", fix_known_errors=False)
    np.testing.assert_array_equal(raw.train.floors, [0] * 6 + [3] * 6)


# --------------------------------------------------------------------------------------------
# RSS/RTT rooms fixture: database_<room>_{train,test}.csv + AP_position.txt, -200 = not heard.

_HEADER = ("X,Y,AP1 RTT(mm),AP2 RTT(mm),AP3 RTT(mm),AP4 RTT(mm),AP5 RTT(mm),AP1 RSS(dBm),"
           "AP2 RSS(dBm),AP3 RSS(dBm),AP4 RSS(dBm),AP5 RSS(dBm),LOS APs")
_AP_POSITIONS = """lecture theatre
AP X: 3,10,18.8,3,19
AP Y: 9,9,9,21,21

office
AP X: 1,11,15,20,25
AP Y: 5,-1,6,-1,5

corridor
AP X:2,17,38,48
AP Y:7.5,6.8,9,5
"""


def _room_line(x: int, y: int, rss: Sequence[float], los: str = "1 3 4") -> str:
    rtt = ",".join("100000.0" if r == -200 else "4000.0" for r in rss)
    return f"{x:.1f},{y:.1f},{rtt}," + ",".join(f"{r:.1f}" for r in rss) + f",{los}\n"


def write_office_room(root: Path, ap_x: str, rows: Sequence[str]) -> Path:
    """A three-AP office of the RSS/RTT format under ``root``: AP_position.txt with the x line
    ``ap_x`` (e.g. "1,11,15") and both splits holding ``rows`` ("X,Y,3 RTTs,3 RSSs,LOS")."""
    root.mkdir(parents=True)
    (root / "AP_position.txt").write_text(f"office\nAP X: {ap_x}\nAP Y: 5,-1,6\n")
    head = "X,Y,AP1 RTT(mm),AP2 RTT(mm),AP3 RTT(mm),AP1 RSS(dBm),AP2 RSS(dBm),AP3 RSS(dBm),LOS APs\n"
    for split in ("train", "test"):
        (root / f"database_office_{split}.csv").write_text(head + "".join(r + "\n" for r in rows))
    return root


def _rss_rtt_fixture(root: Path) -> Path:
    root.mkdir(parents=True)
    (root / "AP_position.txt").write_text(_AP_POSITIONS)
    train = [(0, 1, [-50, -60, -200, -70, -80]), (0, 1, [-51, -61, -200, -71, -81]),
             (2, 3, [-55, -65, -75, -200, -85])]
    test = [(1, 0, [-52, -62, -72, -82, -200]), (1, 0, [-53, -63, -73, -83, -200])]
    for split, rows in (("train", train), ("test", test)):
        (root / f"database_office_{split}.csv").write_text(
            _HEADER + "\n" + "".join(_room_line(x, y, r) for x, y, r in rows))
        # Corridor: AP1 never heard, empty LOS field, 4 APs in AP_position.txt.
        (root / f"database_corridor_{split}.csv").write_text(
            _HEADER + "\n" + "".join(_room_line(x, y, [-200] + r[1:], "") for x, y, r in rows))
    return root


def test_rss_rtt_fixture_metres_sentinel_points_and_ap_positions(tmp_path: Path) -> None:
    ds = load_rss_rtt_room(_rss_rtt_fixture(tmp_path / "rooms"), "office")
    assert ds.name == "rss_rtt_office" and ds.not_heard_sentinel == -200.0
    assert ds.train.rss_dbm.shape == (3, 5) and ds.test.rss_dbm.shape == (2, 5)
    assert ds.ap_names == ["AP1", "AP2", "AP3", "AP4", "AP5"]
    np.testing.assert_array_equal(ds.train.rss_dbm[2], [-55, -65, -75, -200, -85])  # RSS, not RTT
    np.testing.assert_allclose(ds.train.positions_m, [[0, 0.6], [0, 0.6], [1.2, 1.8]])
    np.testing.assert_allclose(ds.test.positions_m, [[0.6, 0], [0.6, 0]])
    np.testing.assert_allclose(ds.ap_positions_m[:, 0], np.array([1, 11, 15, 20, 25]) * 0.6)
    np.testing.assert_allclose(ds.ap_positions_m[:, 1], np.array([5, -1, 6, -1, 5]) * 0.6)
    np.testing.assert_array_equal(ds.train.floors, [0, 0, 0])
    tr, te = ds.train.point_ids, ds.test.point_ids
    assert tr[0] == tr[1] != tr[2] and te[0] == te[1] and te[0] not in set(tr)
    assert ds.train.timestamps is None


def test_rss_rtt_fixture_corridor_drops_never_heard_column(tmp_path: Path) -> None:
    ds = load_rss_rtt_room(_rss_rtt_fixture(tmp_path / "rooms"), "Corridor")
    assert ds.ap_names == ["AP2", "AP3", "AP4", "AP5"] and ds.train.rss_dbm.shape == (3, 4)
    grid = np.array([[2, 7.5], [17, 6.8], [38, 9], [48, 5]])
    np.testing.assert_allclose(ds.ap_positions_m, grid * 0.6)
    assert "AP1" in ds.description


def test_rss_rtt_fixture_rejects_bad_input(tmp_path: Path) -> None:
    root = _rss_rtt_fixture(tmp_path / "rooms")
    with pytest.raises(ValueError, match="argument 'room'"):
        load_rss_rtt_room(root, "kitchen")
    with pytest.raises(ValueError, match="'root'.*missing file.*database_lecture_theatre_train"):
        load_rss_rtt_room(root, "lecture_theatre")
    path = root / "database_office_test.csv"
    good = path.read_text()
    lines = good.splitlines(keepends=True)
    path.write_text(lines[0] + lines[1].replace("1.0,0.0,", "1.0,", 1) + lines[2])
    with pytest.raises(ValueError, match="'root'.*database_office_test.csv row 2: 12 columns"):
        load_rss_rtt_room(root, "office")
    path.write_text(lines[0] + lines[1].replace("1.0,0.0,", "nan,0.0,", 1) + lines[2])
    with pytest.raises(ValueError, match="argument 'root'.*row 2: NaN"):
        load_rss_rtt_room(root, "office")
    path.write_text(good)
    short = _AP_POSITIONS.replace("AP X: 1,11,15,20,25", "AP X: 1,11,15,20")
    (root / "AP_position.txt").write_text(short)
    with pytest.raises(ValueError, match="argument 'root'.*AP_position.txt"):
        load_rss_rtt_room(root, "office")
    (root / "AP_position.txt").unlink()
    with pytest.raises(ValueError, match="argument 'root'.*missing file.*AP_position.txt"):
        load_rss_rtt_room(root, "office")


# --------------------------------------------------------------------------------------------
# SURIMI fixture: <NAME>.mat with struct database, labels (x, y, z, floor, building).


def _write_surimi(root: Path, name: str, fields: Dict[str, np.ndarray]) -> None:
    root.mkdir(parents=True, exist_ok=True)
    scipy.io.savemat(str(root / f"{name}.mat"), {"database": fields})


def _surimi_fields(buildings: Sequence[int]) -> Dict[str, np.ndarray]:
    macs = np.array([[-60, 100, -70], [-61, 100, -71], [100, -50, -80], [100, -51, 100]], np.int16)
    b = np.asarray(buildings, dtype=float)
    labels = np.array([[10.0, 20.0, 3.7, 1, 0], [10.0, 20.0, 3.7, 1, 0],
                       [10.0, 20.0, 3.7, 1, 0], [15.0, 25.0, 0.0, 0, 0]])
    labels[:, 4] = b
    return {"trainingMacs": macs, "testMacs": macs[:2].astype(float),
            "trainingLabels": labels, "testLabels": labels[[1, 3]]}


def test_surimi_fixture_single_building(tmp_path: Path) -> None:
    _write_surimi(tmp_path / "surimi", "DSI1", _surimi_fields([0, 0, 0, 0]))
    ds = load_surimi(tmp_path / "surimi", "dsi1")
    assert ds.name == "surimi_DSI1" and ds.not_heard_sentinel == 100.0
    assert ds.train.rss_dbm.shape == (4, 3) and ds.train.rss_dbm.dtype == np.float64
    assert np.count_nonzero(ds.train.rss_dbm == 100) == 5
    np.testing.assert_array_equal(ds.train.floors, [1, 1, 1, 0])
    np.testing.assert_allclose(ds.train.positions_m[3], [15.0, 25.0])
    tr, te = ds.train.point_ids, ds.test.point_ids
    assert tr[0] == tr[1] == tr[2] == te[0] != tr[3] == te[1]
    assert ds.ap_names == ["AP001", "AP002", "AP003"] and ds.train.timestamps is None


def test_surimi_fixture_buildings_encoded_into_floors(tmp_path: Path) -> None:
    # Same x, y and floor in buildings 0 and 2: must stay two points on two floors.
    _write_surimi(tmp_path / "surimi", "UJI1", _surimi_fields([0, 0, 2, 2]))
    ds = load_surimi(tmp_path / "surimi", "UJI1")
    np.testing.assert_array_equal(ds.train.floors, [1, 1, 21, 20])
    assert ds.train.point_ids[0] == ds.train.point_ids[1] != ds.train.point_ids[2]


def test_surimi_fixture_rejects_bad_input(tmp_path: Path) -> None:
    root = tmp_path / "surimi"
    with pytest.raises(ValueError, match="argument 'name'"):
        load_surimi(root, "MAN1")
    with pytest.raises(ValueError, match="argument 'root'.*missing file.*LIB1.mat"):
        load_surimi(root, "LIB1")
    fields = _surimi_fields([0, 0, 0, 0])
    fields["testLabels"] = fields["testLabels"].copy()
    fields["testLabels"][1, 0] = np.nan
    _write_surimi(root, "LIB1", fields)
    with pytest.raises(ValueError, match="argument 'root'.*testLabels.*NaN"):
        load_surimi(root, "LIB1")
    fields = _surimi_fields([0, 0, 0, 0])
    del fields["testMacs"]
    _write_surimi(root, "LIB1", fields)
    with pytest.raises(ValueError, match="argument 'root'.*testMacs"):
        load_surimi(root, "LIB1")
    fields = _surimi_fields([0, 0, 0, 0])
    fields["trainingLabels"] = fields["trainingLabels"][:, :4]
    _write_surimi(root, "LIB1", fields)
    with pytest.raises(ValueError, match="argument 'root'.*trainingLabels"):
        load_surimi(root, "LIB1")
    (root / "LIB1.mat").write_bytes(b"not a mat file")
    with pytest.raises(ValueError, match="argument 'root'.*LIB1.mat"):
        load_surimi(root, "LIB1")


def test_available_datasets_on_fixtures(tmp_path: Path) -> None:
    assert available_datasets(tmp_path / "nowhere") == []
    _uji_fixture(tmp_path / "uji_library_month01")
    _rss_rtt_fixture(tmp_path / "rss_rtt_rooms")
    _write_surimi(tmp_path / "surimi", "TUT2", _surimi_fields([1, 1, 1, 1]))
    assert available_datasets(tmp_path) == [
        "uji_library_month01", "rss_rtt_office", "rss_rtt_corridor", "surimi_TUT2"]


def test_split_rejects_inconsistent_shapes() -> None:
    with pytest.raises(ValueError, match="positions_m"):
        FingerprintSplit(np.zeros((3, 2)), np.zeros((2, 2)), np.zeros(3), np.zeros(3))


# --------------------------------------------------------------------------------------------
# Real datasets (../shared/data/wifi); skipped with a reason when absent.


def _check_split(split: FingerprintSplit, sentinel: float) -> None:
    s = split.rss_dbm.shape[0]
    assert split.positions_m.shape == (s, 2) and np.all(np.isfinite(split.positions_m))
    assert split.floors.shape == (s,) and split.point_ids.shape == (s,)
    assert np.any(split.rss_dbm == sentinel)
    heard = split.rss_dbm[split.rss_dbm != sentinel]
    assert heard.size and heard.max() <= 0 and heard.min() >= -110


def test_real_uji_library_month01(shared_data: Path) -> None:
    ds = load_uji_library(shared_data / "wifi" / "uji_library_month01")
    assert ds.train.rss_dbm.shape == (15 * 48 * 12, 620)  # 8640 scans
    assert ds.test.rss_dbm.shape == (3120, 620)
    for split in (ds.train, ds.test):
        _check_split(split, 100.0)
        assert set(np.unique(split.floors)) == {3, 5}
        assert np.all(np.isfinite(split.timestamps))
    # 48 reference points with 15 x 12 = 180 scans each; 212 test locations.
    _, counts = np.unique(ds.train.point_ids, return_counts=True)
    assert counts.size == 48 and np.all(counts == 180)
    assert np.unique(ds.test.point_ids).size == 212
    assert "corrected" in ds.description  # the trn14 labelling error


@pytest.mark.parametrize("room, n_train, n_test, n_aps, n_points", [
    ("lecture_theatre", 5280, 1920, 5, (88, 32)),
    ("office", 4860, 1620, 5, (81, 27)),
    ("corridor", 5100, 1740, 4, (85, 29)),
])
def test_real_rss_rtt_rooms(shared_data: Path, room: str, n_train: int, n_test: int,
                            n_aps: int, n_points: Tuple[int, int]) -> None:
    assert room in RSS_RTT_ROOMS
    ds = load_rss_rtt_room(shared_data / "wifi" / "rss_rtt_rooms", room)
    assert ds.train.rss_dbm.shape == (n_train, n_aps) and ds.test.rss_dbm.shape == (n_test, n_aps)
    assert ds.ap_positions_m.shape == (n_aps, 2)
    for split in (ds.train, ds.test):
        _check_split(split, -200.0)
        np.testing.assert_array_equal(split.floors, 0)
        # Grid indices x 0.6 m.
        assert np.allclose(split.positions_m / 0.6, np.round(split.positions_m / 0.6))
    _, counts = np.unique(ds.train.point_ids, return_counts=True)
    assert (counts.size, np.unique(ds.test.point_ids).size) == n_points
    assert np.all(counts == 60)
    assert not set(ds.train.point_ids) & set(ds.test.point_ids)  # disjoint train/test points


def test_real_surimi_lib1_and_dsi1(shared_data: Path) -> None:
    lib = load_surimi(shared_data / "wifi" / "surimi", "LIB1")
    assert lib.train.rss_dbm.shape == (576, 174) and lib.test.rss_dbm.shape == (3120, 174)
    assert np.unique(lib.train.point_ids).size == 48
    assert set(np.unique(lib.train.floors)) == {3, 5}
    dsi = load_surimi(shared_data / "wifi" / "surimi", "DSI1")
    assert dsi.train.rss_dbm.shape == (1369, 157) and dsi.test.rss_dbm.shape == (348, 157)
    assert np.unique(dsi.train.point_ids).size == 230
    np.testing.assert_array_equal(dsi.train.floors, 1)
    for ds in (lib, dsi):
        _check_split(ds.train, 100.0)
        _check_split(ds.test, 100.0)


def test_real_available_datasets(shared_data: Path) -> None:
    names = available_datasets(shared_data)
    assert names[:4] == ["uji_library_month01", "rss_rtt_lecture_theatre", "rss_rtt_office",
                         "rss_rtt_corridor"]
    assert {"surimi_LIB1", "surimi_DSI1", "surimi_UJI1"} <= set(names)
