"""indoorloc.io road-network files: GeoJSON/CSV readers, writer, packaged warehouse, test grid."""

from __future__ import annotations

import importlib
import json
from pathlib import Path
from typing import Any, Dict, List

import numpy as np
import pytest

from indoorloc.io import (
    grid_with_diagonals_segments,
    load_road_network,
    read_csv_segments,
    read_geojson_segments,
    warehouse_segments,
    write_geojson_segments,
)


def _road_network_class() -> Any:
    """indoorloc.mapmatch.RoadNetwork, or None while the binding is not built."""
    try:
        mapmatch = importlib.import_module("indoorloc.mapmatch")
    except ImportError:
        return None
    return getattr(mapmatch, "RoadNetwork", None)


def _value(attr: Any) -> Any:
    """A binding attribute exposed either as a property or as a method."""
    return attr() if callable(attr) else attr


def _feature(coords: Any, fid: Any = None, gtype: str = "LineString") -> Dict[str, Any]:
    props = {} if fid is None else {"id": fid}
    return {"type": "Feature", "properties": props,
            "geometry": {"type": gtype, "coordinates": coords}}


def _write_fc(path: Path, features: List[Dict[str, Any]]) -> Path:
    path.write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    return path


# --------------------------------------------------------------------------------------------
# Geometry helpers computed in numpy (independent of the C++ RoadNetwork).


def _end_points(segments_m: np.ndarray) -> np.ndarray:
    """(2M, 2) segment ends: rows 2k and 2k+1 are ends A and B of segment k."""
    return segments_m.reshape(-1, 2)


def _num_components(segments_m: np.ndarray, tol: float = 1e-9) -> int:
    """Connected components of segments joined where their ends coincide (union-find)."""
    ends = _end_points(segments_m)
    m = segments_m.shape[0]
    parent = list(range(m))

    def find(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    d = np.linalg.norm(ends[:, None, :] - ends[None, :, :], axis=2)
    for p, q in zip(*np.nonzero(d <= tol)):
        ra, rb = find(int(p) // 2), find(int(q) // 2)
        if ra != rb:
            parent[ra] = rb
    return len({find(k) for k in range(m)})


def _dangling_ends(segments_m: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Indices (into the 2M ends) of ends shared with no other segment's end."""
    ends = _end_points(segments_m)
    d = np.linalg.norm(ends[:, None, :] - ends[None, :, :], axis=2)
    same_segment = (np.arange(len(ends))[:, None] // 2) == (np.arange(len(ends))[None, :] // 2)
    shared = ((d <= tol) & ~same_segment).any(axis=1)
    return np.flatnonzero(~shared)


def _point_in_interior(p: np.ndarray, seg: np.ndarray, tol: float = 1e-9) -> bool:
    a, b = seg[:2], seg[2:]
    ab = b - a
    t = float(np.dot(p - a, ab) / np.dot(ab, ab))
    if t <= tol or t >= 1 - tol:
        return False
    return bool(np.linalg.norm(a + t * ab - p) <= tol)


def _interiors_cross(s: np.ndarray, r: np.ndarray) -> bool:
    """True if two segments intersect at a point interior to both (proper crossing)."""
    p, d1 = s[:2], s[2:] - s[:2]
    q, d2 = r[:2], r[2:] - r[:2]
    den = d1[0] * d2[1] - d1[1] * d2[0]
    if abs(den) < 1e-12:
        return False  # parallel: overlaps are caught by the interior-end test
    w = q - p
    t = (w[0] * d2[1] - w[1] * d2[0]) / den
    u = (w[0] * d1[1] - w[1] * d1[0]) / den
    return 1e-9 < t < 1 - 1e-9 and 1e-9 < u < 1 - 1e-9


def _assert_split_at_every_junction(segments_m: np.ndarray) -> None:
    """No segment end lies inside another segment and no two segment interiors cross."""
    ends = _end_points(segments_m)
    for k, seg in enumerate(segments_m):
        for e, p in enumerate(ends):
            if e // 2 != k:
                assert not _point_in_interior(p, seg), f"end {e} inside segment {k}"
        for r in range(k + 1, len(segments_m)):
            assert not _interiors_cross(seg, segments_m[r]), f"segments {k} and {r} cross"


# --------------------------------------------------------------------------------------------
# GeoJSON reader


def test_geojson_three_vertex_linestring_gives_two_pieces_with_piece_ids(tmp_path):
    path = _write_fc(tmp_path / "net.geojson", [
        _feature([[0, 0], [10, 0], [10, 5]], fid=3),
        _feature([[10, 5], [20, 5.5]], fid=4),
    ])
    seg, ids = read_geojson_segments(path)
    assert seg.dtype == np.float64 and seg.shape == (3, 4)
    assert ids.dtype == np.int64
    np.testing.assert_array_equal(seg, [[0, 0, 10, 0], [10, 0, 10, 5], [10, 5, 20, 5.5]])
    np.testing.assert_array_equal(ids, [301, 302, 4])


def test_geojson_multilinestring_pieces_counted_across_parts(tmp_path):
    path = _write_fc(tmp_path / "net.json", [
        _feature([[[0, 0], [1, 0]], [[5, 5], [5, 6], [5, 8]]], fid=7, gtype="MultiLineString"),
        _feature([[[2, 2], [3, 3]]], fid=8, gtype="MultiLineString"),
    ])
    seg, ids = read_geojson_segments(str(path))
    np.testing.assert_array_equal(seg, [[0, 0, 1, 0], [5, 5, 5, 6], [5, 6, 5, 8], [2, 2, 3, 3]])
    np.testing.assert_array_equal(ids, [701, 702, 703, 8])


def test_geojson_missing_ids_are_sequential_after_the_largest_given(tmp_path):
    path = _write_fc(tmp_path / "net.geojson", [
        _feature([[0, 0], [1, 0]]),                # no id -> 13
        _feature([[1, 0], [2, 0]], fid=12),
        _feature([[2, 0], [3, 0], [3, 1]]),        # no id -> 14, two pieces -> 1401, 1402
        _feature([[3, 1], [4, 1]], fid=5),
    ])
    _, ids = read_geojson_segments(path)
    np.testing.assert_array_equal(ids, [13, 12, 1401, 1402, 5])

    path = _write_fc(tmp_path / "noids.geojson",
                     [_feature([[0, 0], [1, 0]]), _feature([[1, 0], [1, 1]])])
    np.testing.assert_array_equal(read_geojson_segments(path)[1], [1, 2])


def test_geojson_top_level_feature_id_and_ignored_altitude_and_crs(tmp_path):
    doc = {"type": "FeatureCollection",
           "crs": {"type": "name", "properties": {"name": "local"}},
           "features": [{"type": "Feature", "id": 9, "properties": None,
                         "geometry": {"type": "LineString",
                                      "coordinates": [[0, 0, 2.5], [0, 4, 2.5]]}}]}
    path = tmp_path / "net.geojson"
    path.write_text(json.dumps(doc))
    seg, ids = read_geojson_segments(path)
    np.testing.assert_array_equal(seg, [[0, 0, 0, 4]])
    np.testing.assert_array_equal(ids, [9])


def test_write_then_read_geojson_round_trip_is_exact(tmp_path):
    rng = np.random.default_rng(5)
    seg = rng.normal(scale=50.0, size=(17, 4))
    ids = rng.permutation(np.arange(100, 117)).astype(np.int32)
    path = tmp_path / "out.geojson"
    write_geojson_segments(path, seg, ids)
    seg2, ids2 = read_geojson_segments(path)
    np.testing.assert_array_equal(seg2, seg)  # exact: shortest round-trip float repr
    np.testing.assert_array_equal(ids2, ids)
    assert ids2.dtype == np.int64
    doc = json.loads(path.read_text())
    assert len(doc["features"]) == 17
    assert all(f["geometry"]["type"] == "LineString" for f in doc["features"])

    write_geojson_segments(path, seg[:3])  # default ids 1..M
    np.testing.assert_array_equal(read_geojson_segments(path)[1], [1, 2, 3])

    ws, wi = warehouse_segments()
    write_geojson_segments(tmp_path / "w.geojson", ws, wi)
    ws2, wi2 = read_geojson_segments(tmp_path / "w.geojson")
    np.testing.assert_array_equal(ws2, ws)
    np.testing.assert_array_equal(wi2, wi)


@pytest.mark.parametrize("segments, ids, arg", [
    (np.zeros((3, 3)), None, "segments_m"),
    (np.zeros((0, 4)), None, "segments_m"),
    ([[0, 0, np.nan, 1]], None, "segments_m"),
    ([[0, 0, 1, 1], [1, 1, 2, 2]], [1, 1], "ids"),
    ([[0, 0, 1, 1], [1, 1, 2, 2]], [1], "ids"),
    ([[0, 0, 1, 1]], [1.5], "ids"),
])
def test_write_geojson_rejects_bad_arrays(tmp_path, segments, ids, arg):
    with pytest.raises(ValueError, match=f"argument '{arg}'"):
        write_geojson_segments(tmp_path / "x.geojson", segments, ids)
    assert not (tmp_path / "x.geojson").exists()


GEOJSON_ERRORS = {
    "invalid_json": ('{"type": "FeatureCollection", "features": [', "invalid JSON"),
    "not_collection": ('{"type": "Feature"}', "FeatureCollection"),
    "point": (_feature([1, 2], fid=1, gtype="Point"), "'Point' is not a LineString"),
    "polygon": (_feature([[[0, 0], [1, 0], [1, 1], [0, 0]]], fid=1, gtype="Polygon"),
                "not a LineString"),
    "null_geometry": ({"type": "Feature", "properties": {"id": 1}, "geometry": None},
                      "geometry is missing"),
    "one_vertex": (_feature([[0, 0]], fid=1), "at least 2 vertices"),
    "one_vertex_part": (_feature([[[0, 0], [1, 1]], [[2, 2]]], fid=1, gtype="MultiLineString"),
                        "at least 2 vertices"),
    "nan": ('{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": '
            '{"id": 1}, "geometry": {"type": "LineString", "coordinates": [[0, 0], [NaN, 1]]}}]}',
            "NaN"),
    "string_coordinate": (_feature([[0, 0], ["1", 1]], fid=1), "must be numbers"),
    "zero_length": (_feature([[0, 0], [1, 0], [1, 0]], fid=1), "zero-length"),
    "float_id": (_feature([[0, 0], [1, 0]], fid=1.5), "must be an integer"),
    "string_id": (_feature([[0, 0], [1, 0]], fid="a"), "must be an integer"),
    "empty": ('{"type": "FeatureCollection", "features": []}', "no segments"),
}


@pytest.mark.parametrize("case", sorted(GEOJSON_ERRORS))
def test_geojson_errors_name_the_path(tmp_path, case):
    content, message = GEOJSON_ERRORS[case]
    path = tmp_path / f"{case}.geojson"
    if isinstance(content, str):
        path.write_text(content)
    else:
        _write_fc(path, [content])
    with pytest.raises(ValueError, match="argument 'path'") as info:
        read_geojson_segments(path)
    assert message in str(info.value)
    assert str(path) in str(info.value)


def test_geojson_duplicate_ids_rejected(tmp_path):
    path = _write_fc(tmp_path / "dup.geojson", [
        _feature([[0, 0], [1, 0]], fid=2), _feature([[1, 0], [2, 0]], fid=2)])
    with pytest.raises(ValueError, match="argument 'path'.*duplicate segment id.*2"):
        read_geojson_segments(path)
    # A piece id colliding with a given id is a duplicate too.
    path = _write_fc(tmp_path / "dup2.geojson", [
        _feature([[0, 0], [1, 0], [2, 0]], fid=2), _feature([[2, 0], [3, 0]], fid=201)])
    with pytest.raises(ValueError, match="duplicate segment id.*201"):
        read_geojson_segments(path)


def test_missing_file_and_folder_rejected(tmp_path):
    with pytest.raises(ValueError, match="argument 'path'.*file not found"):
        read_geojson_segments(tmp_path / "absent.geojson")
    with pytest.raises(ValueError, match="argument 'path'.*file not found"):
        read_csv_segments(tmp_path / "absent.csv")
    with pytest.raises(ValueError, match="argument 'path'.*not a regular file"):
        read_csv_segments(tmp_path)
    with pytest.raises(ValueError, match="argument 'path'"):
        read_geojson_segments(123)  # type: ignore[arg-type]


# --------------------------------------------------------------------------------------------
# CSV reader

CSV_OK = """\
# warehouse aisles, metres
   # indented comment

ID, x_a ,y_a,x_b,y_b,name,width_m
1,0,0,10,0,dock,3.5
# a comment between rows
2,10,0,10,18.25,aisle #2,2
7,10,18.25,-4e1,18.25,,
"""


def test_csv_with_comments_blank_lines_and_extra_columns(tmp_path):
    path = tmp_path / "net.csv"
    path.write_text(CSV_OK)
    seg, ids = read_csv_segments(path)
    np.testing.assert_array_equal(seg, [[0, 0, 10, 0], [10, 0, 10, 18.25],
                                        [10, 18.25, -40, 18.25]])
    np.testing.assert_array_equal(ids, [1, 2, 7])
    assert seg.dtype == np.float64 and ids.dtype == np.int64


def test_csv_columns_in_any_order(tmp_path):
    path = tmp_path / "net.csv"
    path.write_text("y_b,x_b,note,id,y_a,x_a\n5,4,x,42,2,1\n")
    seg, ids = read_csv_segments(path)
    np.testing.assert_array_equal(seg, [[1, 2, 4, 5]])
    np.testing.assert_array_equal(ids, [42])


CSV_ERRORS = {
    "missing_column": ("id,x_a,y_a,x_b\n1,0,0,1\n", "lacks column"),
    "short_row": ("id,x_a,y_a,x_b,y_b\n1,0,0,1\n", "line 2"),
    "float_id": ("id,x_a,y_a,x_b,y_b\n1.5,0,0,1,0\n", "not an integer"),
    "bad_number": ("id,x_a,y_a,x_b,y_b\n1,0,zero,1,0\n", "not a number"),
    "nan": ("# c\nid,x_a,y_a,x_b,y_b\n1,0,0,nan,0\n", "line 3: x_b is NaN"),
    "inf": ("id,x_a,y_a,x_b,y_b\n1,0,0,inf,0\n", "NaN or infinite"),
    "zero_length": ("id,x_a,y_a,x_b,y_b\n1,2,3,2,3\n", "zero-length"),
    "duplicate_ids": ("id,x_a,y_a,x_b,y_b\n4,0,0,1,0\n4,1,0,2,0\n", "duplicate segment id"),
    "empty": ("# only a comment\n\n", "no header"),
    "header_only": ("id,x_a,y_a,x_b,y_b\n", "no segments"),
}


@pytest.mark.parametrize("case", sorted(CSV_ERRORS))
def test_csv_errors_name_the_path(tmp_path, case):
    content, message = CSV_ERRORS[case]
    path = tmp_path / f"{case}.csv"
    path.write_text(content)
    with pytest.raises(ValueError, match="argument 'path'") as info:
        read_csv_segments(path)
    assert message in str(info.value)
    assert str(path) in str(info.value)


def test_load_road_network_rejects_unknown_suffix_before_building(tmp_path):
    path = tmp_path / "net.txt"
    path.write_text("id,x_a,y_a,x_b,y_b\n1,0,0,1,0\n")
    with pytest.raises(ValueError, match="argument 'path'.*unknown suffix '.txt'"):
        load_road_network(path)


# --------------------------------------------------------------------------------------------
# Packaged warehouse


def test_warehouse_has_26_axis_aligned_segments_ids_1_to_26():
    seg, ids = warehouse_segments()
    assert seg.shape == (26, 4) and seg.dtype == np.float64
    np.testing.assert_array_equal(ids, np.arange(1, 27))
    horizontal = seg[:, 1] == seg[:, 3]
    vertical = seg[:, 0] == seg[:, 2]
    assert np.all(horizontal ^ vertical)
    assert horizontal.sum() == 15 and vertical.sum() == 11
    # Documented numbering: horizontals 1-15 then verticals 16-26; A is the west/south end.
    assert horizontal[:15].all() and vertical[15:].all()
    assert np.all(seg[horizontal, 0] < seg[horizontal, 2])
    assert np.all(seg[vertical, 1] < seg[vertical, 3])
    np.testing.assert_array_equal(seg[:, [1, 3]][:15].min(axis=1),
                                  [0] * 6 + [12] * 6 + [30] * 3)
    np.testing.assert_array_equal(seg[15:, 0], [0, 0, 6, 14, 14, 23, 32, 32, 44, 55, 55])
    # Hall 55 m x 30 m.
    np.testing.assert_array_equal(seg[:, [0, 2]].min(), 0)
    np.testing.assert_array_equal(seg[:, [0, 2]].max(), 55)
    np.testing.assert_array_equal(seg[:, [1, 3]].max(), 30)


def test_warehouse_total_length_and_segment_times():
    seg, _ = warehouse_segments()
    lengths = np.linalg.norm(seg[:, 2:] - seg[:, :2], axis=1)
    assert lengths.sum() == pytest.approx(3 * 55 + 4 * 30 + 3 * 12)  # 321 m
    # Irregular bays: no two neighbouring lower bays alike; at 2 m/s, 3-12 s per segment.
    assert len(set(np.round(lengths[:6], 6))) >= 4
    assert np.all((lengths / 2.0 >= 3.0) & (lengths / 2.0 <= 12.0))


def test_warehouse_connected_no_dangling_end_split_at_every_junction():
    seg, _ = warehouse_segments()
    assert _dangling_ends(seg).size == 0
    assert _num_components(seg) == 1
    _assert_split_at_every_junction(seg)


def test_warehouse_file_matches_the_resource_api():
    from importlib import resources

    text = resources.files("indoorloc.data").joinpath("warehouse.geojson").read_text()
    doc = json.loads(text)
    assert [f["properties"]["id"] for f in doc["features"]] == list(range(1, 27))


# --------------------------------------------------------------------------------------------
# Grid-with-diagonals test network


@pytest.mark.parametrize("nx, ny", [(4, 3), (1, 1), (5, 2), (2, 6)])
def test_grid_with_diagonals_structure(nx, ny):
    h = 7.5
    seg, ids = grid_with_diagonals_segments(nx=nx, ny=ny, spacing_m=h)
    n_diag = (nx * ny + 1) // 2
    m = (ny + 1) * nx + (nx + 1) * ny + n_diag
    assert seg.shape == (m, 4) and seg.dtype == np.float64
    np.testing.assert_array_equal(ids, np.arange(1, m + 1))
    # No duplicate segment, in either direction.
    keys = {tuple(sorted([(round(a, 9), round(b, 9)), (round(c, 9), round(d, 9))]))
            for a, b, c, d in seg.tolist()}
    assert len(keys) == m
    dx, dy = seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]
    diag = (dx != 0) & (dy != 0)
    assert diag.sum() == n_diag
    assert diag[-n_diag:].all()
    # Diagonals span exactly one cell and end at grid nodes.
    np.testing.assert_allclose(np.abs(dx[diag]), h)
    np.testing.assert_allclose(np.abs(dy[diag]), h)
    nodes = seg[diag].reshape(-1, 2) / h
    np.testing.assert_allclose(nodes, np.round(nodes), atol=1e-12)
    assert nodes.min() >= 0 and nodes[:, 0].max() <= nx and nodes[:, 1].max() <= ny
    # Both diagonal directions once there are two rows; grid edges all of length h.
    if ny >= 2:
        assert set(np.sign(dy[diag]).tolist()) == {-1.0, 1.0}
    np.testing.assert_allclose(np.hypot(dx[~diag], dy[~diag]), h)
    assert _num_components(seg) == 1
    _assert_split_at_every_junction(seg)


def test_grid_with_diagonals_differs_from_warehouse_and_rejects_bad_arguments():
    seg, _ = grid_with_diagonals_segments()
    assert seg.shape == (16 + 15 + 6, 4)
    for kwargs, arg in [({"nx": 0}, "nx"), ({"ny": 2.5}, "ny"), ({"nx": True}, "nx"),
                        ({"spacing_m": 0.0}, "spacing_m"), ({"spacing_m": float("nan")},
                                                            "spacing_m")]:
        with pytest.raises(ValueError, match=f"argument '{arg}'"):
            grid_with_diagonals_segments(**kwargs)


# --------------------------------------------------------------------------------------------
# With the C++ RoadNetwork (skipped only while the binding is missing)


def test_warehouse_road_network_is_one_component_of_26_segments():
    RoadNetwork = _road_network_class()
    if RoadNetwork is None:
        pytest.skip("RoadNetwork binding not built yet")
    seg, ids = warehouse_segments()
    net = RoadNetwork(seg, ids)
    assert _value(net.num_segments) == 26
    assert _value(net.num_components) == 1
    # Already split at every junction: splitting again changes nothing.
    net_split = RoadNetwork(seg, ids, split_at_intersections=True)
    assert _value(net_split.num_segments) == 26
    assert _value(net_split.num_components) == 1


def test_load_road_network_from_geojson_and_csv(tmp_path):
    RoadNetwork = _road_network_class()
    if RoadNetwork is None:
        pytest.skip("RoadNetwork binding not built yet")
    seg, ids = warehouse_segments()
    write_geojson_segments(tmp_path / "w.geojson", seg, ids)
    rows = "".join(f"{i},{a!r},{b!r},{c!r},{d!r}\n"
                   for i, (a, b, c, d) in zip(ids.tolist(), seg.tolist()))
    (tmp_path / "w.csv").write_text("id,x_a,y_a,x_b,y_b\n" + rows)
    for name in ("w.geojson", "w.csv"):
        net = load_road_network(tmp_path / name, snap_tolerance_m=1e-3)
        assert isinstance(net, RoadNetwork)
        assert _value(net.num_segments) == 26
        assert _value(net.num_components) == 1
