"""Python side of the fusion floor plan: bindings against numpy (and shapely) brute force, bad
input, the GeoJSON reader/writer, and the ILC 2020 floor in ../shared/data."""

import json
import math

import numpy as np
import pytest

from indoorloc import core
from indoorloc.fusion import (
    FloorGeometry,
    FloorPlan,
    FloorPlanOptions,
    floor_geometry,
    floor_plan_from_polygons,
)
from indoorloc.io import (
    floor_geometry_to_geojson,
    load_floor_plan,
    local_to_lonlat,
    lonlat_to_local,
    metres_per_degree,
    read_geojson_floor,
    write_geojson_floor,
)


def box(x0, y0, x1, y1):
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def random_plan_geometry(n_polygons=250, n_walls=150, seed=0):
    rng = np.random.default_rng(seed)
    obstacles = []
    for k in range(n_polygons):
        c = rng.uniform([-2, -2], [82, 52])
        n = int(rng.integers(3, 9))
        a = np.sort(rng.uniform(0, 2 * np.pi, n))
        r = rng.uniform(0.3, 2.5)
        ring = c + r * np.column_stack([np.cos(a), np.sin(a)])
        obstacles.append(ring if k % 2 else ring[::-1])
    p = rng.uniform([0, 0], [80, 50], size=(n_walls, 2))
    a = rng.uniform(0, 2 * np.pi, n_walls)
    length = rng.uniform(0.5, 6, n_walls)
    walls = np.column_stack([p, p + length[:, None] * np.column_stack([np.cos(a), np.sin(a)])])
    return FloorGeometry(floor=1, outlines=[box(0, 0, 80, 50)], obstacles=obstacles, walls=walls)


# ---- numpy brute force --------------------------------------------------------------------

def brute_crosses(edges, segs):
    """(Q,) bool: does segment q intersect or touch any edge (all pairs, plain float64)."""
    p, q = segs[:, None, :2], segs[:, None, 2:]
    u, v = edges[None, :, :2], edges[None, :, 2:]

    def orient(a, b, c):
        return np.sign((b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
                       - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0]))

    o1, o2, o3, o4 = orient(p, q, u), orient(p, q, v), orient(u, v, p), orient(u, v, q)
    return ((o1 * o2 <= 0) & (o3 * o4 <= 0)).any(axis=1)  # random reals: no collinear cases


def brute_in_ring(ring, pts):
    x, y = pts[:, 0:1], pts[:, 1:2]
    xi, yi = ring[:, 0], ring[:, 1]
    xj, yj = np.roll(xi, 1), np.roll(yi, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        hit = ((yi > y) != (yj > y)) & (x < (xj - xi) * (y - yi) / (yj - yi) + xi)
    return hit.sum(axis=1) % 2 == 1


def brute_walkable(g, pts):
    inside = np.zeros(len(pts), bool)
    for r in g.outlines:
        inside |= brute_in_ring(r, pts)
    for r in g.obstacles:
        inside &= ~brute_in_ring(r, pts)
    return inside


def brute_distance(edges, pts):
    a, b = edges[None, :, :2], edges[None, :, 2:]
    ab = b - a
    t = np.clip(((pts[:, None] - a) * ab).sum(-1) / (ab * ab).sum(-1), 0, 1)
    return np.linalg.norm(a + t[..., None] * ab - pts[:, None], axis=-1).min(axis=1)


@pytest.fixture(scope="module")
def random_plan():
    g = random_plan_geometry()
    return g, FloorPlan([g])


def random_queries(n, seed, max_len=3.0):
    rng = np.random.default_rng(seed)
    pts = rng.uniform([-5, -5], [85, 55], size=(n, 2))
    a = rng.uniform(0, 2 * np.pi, n)
    length = rng.uniform(0, max_len, n)
    segs = np.column_stack([pts, pts + length[:, None] * np.column_stack([np.cos(a), np.sin(a)])])
    return pts, segs


# ---- queries ------------------------------------------------------------------------------

def test_random_plan_matches_numpy_brute_force(random_plan):
    g, plan = random_plan
    assert plan.num_floors == 1 and plan.floors == [1] and plan.floor_index(1) == 0
    edges = plan.edges()
    assert edges.shape == (plan.num_edges(), 4)
    assert plan.num_edges() == sum(len(r) for r in g.outlines + g.obstacles) + len(g.walls)
    pts, segs = random_queries(3000, 1)
    walk = plan.is_walkable(pts)
    assert walk.dtype == np.bool_ and walk.shape == (3000,)
    np.testing.assert_array_equal(walk, brute_walkable(plan.geometry(0), pts))
    cross = plan.crosses_wall(segs)
    np.testing.assert_array_equal(cross, brute_crosses(edges, segs))
    assert 0.1 < cross.mean() < 0.9 and 0.2 < walk.mean() < 0.9
    np.testing.assert_allclose(plan.distance_to_wall(pts), brute_distance(edges, pts), rtol=1e-12, atol=1e-12)


def test_hand_made_square_with_hole_and_wall():
    plan = floor_plan_from_polygons(box(0, 0, 10, 10), obstacles=[box(4, 4, 6, 6)], walls=[[2, 0, 2, 3]])
    assert plan.walkable_area() == pytest.approx(96.0, abs=1e-9)
    np.testing.assert_array_equal(plan.bounds(), [0, 0, 10, 10])
    np.testing.assert_array_equal(plan.is_walkable([[1, 1], [5, 5], [11, 1]]), [True, False, False])
    segs = [[1, 5, 9, 5],   # through the hole
            [1, 1, 3, 1],   # through the wall
            [1, 4, 3, 4],   # above the wall's end
            [1, 3, 3, 3],   # touching the wall's end
            [3, 3, 4, 4]]   # touching the hole's corner
    np.testing.assert_array_equal(plan.crosses_wall(segs), [True, True, False, True, True])
    np.testing.assert_allclose(plan.distance_to_wall([[3, 5], [1, 1]]), [1.0, 1.0])
    assert "walkable area 96.0" in plan.report() and repr(plan).startswith("<FloorPlan")


def test_polygon_like_objects_and_holes():
    class Ring:
        def __init__(self, xy):
            self.coords = xy

    class Polygon:  # the shapely interface: exterior / interiors (with .coords)
        def __init__(self, shell, holes=()):
            self.exterior = Ring(shell)
            self.interiors = [Ring(h) for h in holes]

    g = floor_geometry(Polygon(box(0, 0, 10, 10), [box(1, 1, 2, 2)]), obstacles=[box(5, 5, 6, 6)], floor=3)
    assert g.floor == 3 and len(g.outlines) == 1 and len(g.obstacles) == 2
    plan = FloorPlan(g)
    assert plan.walkable_area() == pytest.approx(98.0, abs=1e-9)
    assert not plan.is_walkable([[1.5, 1.5]])[0]


def test_multi_floor_indices_and_threads(random_plan):
    g, _ = random_plan
    other = FloorGeometry(floor=4, outlines=[box(0, 0, 30, 30)])
    plan = FloorPlan([g, other], FloorPlanOptions(cell_size_m=1.5))
    assert plan.floors == [1, 4] and plan.cell_size(0) == 1.5
    pts, segs = random_queries(20000, 2)
    floors = np.arange(len(pts)) % 2
    one = plan.is_walkable(pts, floors, num_threads=1)
    np.testing.assert_array_equal(plan.is_walkable(pts, floors, num_threads=2), one)
    np.testing.assert_array_equal(plan.is_walkable(pts, floors, num_threads=0), one)
    np.testing.assert_array_equal(plan.crosses_wall(segs, floors, 2), plan.crosses_wall(segs, floors, 1))
    np.testing.assert_array_equal(plan.distance_to_wall(pts, floors, 2), plan.distance_to_wall(pts, floors, 1))
    # Floor 4 (index 1) is the plain square.
    inside = (pts >= 0).all(axis=1) & (pts <= 30).all(axis=1)
    np.testing.assert_array_equal(plan.is_walkable(pts, 1), inside)


def test_sample_walkable(random_plan):
    _, plan = random_plan
    s = plan.sample_walkable(4000, 0, core.RandomStream(5))
    assert s.shape == (4000, 2) and plan.is_walkable(s).all()
    np.testing.assert_array_equal(s, plan.sample_walkable(4000, 0, 5))  # int seed = stream (5, 0)
    rng = core.RandomStream(7)
    a, b = plan.sample_walkable(10, 0, rng), plan.sample_walkable(10, 0, rng)
    assert not np.array_equal(a, b)  # the stream advances
    # Uniform: the share of samples left of x = 40 matches that part's area.
    left = FloorPlan(FloorGeometry(outlines=[box(0, 0, 40, 50)], obstacles=plan.geometry().obstacles))
    assert np.mean(s[:, 0] < 40) == pytest.approx(left.walkable_area() / plan.walkable_area(), abs=0.03)


# ---- shapely ------------------------------------------------------------------------------

def test_against_shapely(random_plan):
    shapely = pytest.importorskip("shapely")
    from shapely.geometry import MultiLineString, Polygon
    from shapely.ops import unary_union

    g, plan = random_plan
    walkable = unary_union([Polygon(r) for r in g.outlines]).difference(
        unary_union([Polygon(r) for r in g.obstacles]))
    assert plan.walkable_area() == pytest.approx(walkable.area, rel=1e-4)
    pts, segs = random_queries(3000, 3)
    np.testing.assert_array_equal(plan.is_walkable(pts), shapely.contains_xy(walkable, pts[:, 0], pts[:, 1]))
    walls = MultiLineString([e.reshape(2, 2) for e in plan.edges()])
    lines = shapely.linestrings(segs.reshape(-1, 2, 2))
    np.testing.assert_array_equal(plan.crosses_wall(segs), shapely.intersects(lines, walls))
    np.testing.assert_allclose(plan.distance_to_wall(pts), shapely.distance(shapely.points(pts), walls),
                               rtol=1e-9, atol=1e-9)


# ---- bad input ----------------------------------------------------------------------------

def expect_error(fn, *parts, exc=ValueError):
    with pytest.raises(exc) as info:
        fn()
    for p in parts:
        assert p in str(info.value), str(info.value)


def test_bad_input_names_the_argument(random_plan):
    _, plan = random_plan
    sq = box(0, 0, 10, 10)
    expect_error(lambda: FloorGeometry(outlines=[[[0, 0], [1, np.nan], [1, 1]]]), "'outlines[0]'", "NaN")
    expect_error(lambda: FloorGeometry(outlines=[np.zeros((4, 3))]), "'outlines[0]'", "(any, 2)")
    expect_error(lambda: FloorGeometry(outlines=sq), "'outlines'", "wrap it in a list")
    expect_error(lambda: FloorGeometry(outlines=[sq], walls=[[0, 0, 1]]), "'walls'", "(W, 4)")
    expect_error(lambda: FloorPlan([]), "'floors'", "at least one floor")
    expect_error(lambda: FloorPlan([1]), "'floors[0]'", "FloorGeometry")
    expect_error(lambda: FloorPlan([FloorGeometry(outlines=[sq]), FloorGeometry(outlines=[sq])]),
                 "'floors[1].floor'", "repeated")
    expect_error(lambda: FloorPlan(FloorGeometry(outlines=[sq], obstacles=[[[1, 1], [2, 2], [3, 3]]])),
                 "'floors[0].obstacles[0]'", "zero area")
    expect_error(lambda: floor_plan_from_polygons(sq, obstacles=[[[1, 1], [3, 3], [3, 1], [1, 2]]]),
                 "'floors[0].obstacles[0]'", "self-intersecting")
    expect_error(lambda: floor_plan_from_polygons(sq, obstacles=[box(-1, -1, 11, 11)]),
                 "'floors[0]'", "no walkable area")
    expect_error(lambda: floor_plan_from_polygons([]), "'floors[0].outlines'", "at least one outline")
    expect_error(lambda: FloorPlanOptions(target_edges_per_cell=0), "'options'", "target_edges_per_cell")
    expect_error(lambda: floor_plan_from_polygons(sq, options=FloorPlanOptions(), cell_size_m=1.0), "'options'")
    expect_error(lambda: plan.is_walkable([1, 2]), "'points_m'", "2-D")
    expect_error(lambda: plan.is_walkable([[1, 2, 3]]), "'points_m'", "(any, 2)")
    expect_error(lambda: plan.crosses_wall([[0, 0, 1, np.inf]]), "'segments_m'", "infinite")
    expect_error(lambda: plan.distance_to_wall([[1, 2]], floor_indices=1), "'floor_indices'", "out of range")
    expect_error(lambda: plan.is_walkable([[1, 2], [3, 4]], [0, 0, 0]), "'floor_indices'", "one entry per query")
    expect_error(lambda: plan.is_walkable([[1, 2]], [0.5]), "'floor_indices'", "not an integer")
    expect_error(lambda: plan.sample_walkable(-1), "'n'")
    expect_error(lambda: plan.sample_walkable(1, 0, "seed"), "'rng'")
    expect_error(lambda: plan.floor_index(9), "'floor'", "no floor number 9")
    expect_error(lambda: plan.edges(3), "'floor_index'")


# ---- GeoJSON ------------------------------------------------------------------------------

ORIGIN = (120.13, 30.30)


def lonlat_fixture():
    """A small floor in lon/lat: outline with a hole, a MultiPolygon of two shops, a wall."""
    outline = box(0, 0, 40, 30)
    hole = box(18, 12, 22, 16)
    shop_a, shop_b = box(2, 2, 8, 8), box(30, 20, 36, 28)
    wall = np.array([[10, 0], [10, 20]], float)

    def ll(xy, close=True):
        xy = local_to_lonlat(xy, ORIGIN)
        if close:
            xy = np.vstack([xy, xy[:1]])
        return xy.tolist()

    doc = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"name": "floor"},
         "geometry": {"type": "Polygon", "coordinates": [ll(outline), ll(hole[::-1])]}},
        {"type": "Feature", "properties": {},
         "geometry": {"type": "MultiPolygon", "coordinates": [[ll(shop_a)], [ll(shop_b, close=False)]]}},
        {"type": "Feature", "properties": None,
         "geometry": {"type": "LineString", "coordinates": ll(wall, close=False)}},
    ]}
    return doc, (outline, hole, shop_a, shop_b, wall)


def test_metres_per_degree_matches_reference_values():
    # WGS84: 1 deg of latitude is 110574.3 m at the equator and 111132.0 m at 45 deg; 1 deg of
    # longitude 111319.5 m at the equator and 78846.8 m at 45 deg.
    kx, ky = metres_per_degree(0.0)
    assert kx == pytest.approx(111319.49, rel=1e-6) and ky == pytest.approx(110574.27, rel=1e-6)
    kx, ky = metres_per_degree(45.0)
    assert kx == pytest.approx(78846.8, rel=1e-5) and ky == pytest.approx(111131.75, rel=1e-6)
    xy = np.array([[0.0, 0.0], [123.4, -56.7]])
    np.testing.assert_allclose(lonlat_to_local(local_to_lonlat(xy, ORIGIN), ORIGIN), xy, atol=1e-9)


def test_read_geojson_lonlat_roles_and_holes(tmp_path):
    doc, (outline, hole, shop_a, shop_b, wall) = lonlat_fixture()
    path = tmp_path / "floor.geojson"
    path.write_text(json.dumps(doc))
    f = read_geojson_floor(path, floor=2, origin_lon_lat=ORIGIN)
    g = f.geometry
    assert g.floor == 2 and f.label == str(path) and f.roles == ["outline", "obstacle", "wall"]
    assert f.outline_features == [0] and f.obstacle_features == [0, 1, 1] and f.wall_features == [2]
    np.testing.assert_allclose(g.outlines[0], outline, atol=1e-8)
    np.testing.assert_allclose(g.obstacles[0], hole[::-1], atol=1e-8)
    np.testing.assert_allclose(g.obstacles[2], shop_b, atol=1e-8)
    np.testing.assert_allclose(g.walls, wall.reshape(1, 4), atol=1e-8)
    plan = FloorPlan(g)
    assert plan.walkable_area() == pytest.approx(1200 - 16 - 36 - 48, rel=1e-9)
    # The SW corner of the outline's lon/lat box is (0, 0) in metres here.
    g2 = read_geojson_floor(path, origin_lon_lat="outline_sw").geometry
    np.testing.assert_allclose(g2.outlines[0].min(axis=0), [0, 0], atol=1e-9)
    # Roles given by the caller: everything but the outline ignored.
    g3 = read_geojson_floor(doc, roles=["outline", "ignore", "ignore"], origin_lon_lat=ORIGIN).geometry
    assert len(g3.obstacles) == 1 and g3.walls.shape == (0, 4)
    g4 = read_geojson_floor(doc, roles={1: "wall"}, origin_lon_lat=ORIGIN).geometry
    assert len(g4.obstacles) == 1 and g4.walls.shape == (1 + 8, 4)  # two shops' edges + the wall
    g5 = read_geojson_floor(doc, roles=lambda k, feat: "outline" if k == 0 else "ignore",
                            origin_lon_lat=ORIGIN).geometry
    assert len(g5.outlines) == 1 and len(g5.obstacles) == 1


def test_geojson_round_trip_metres_and_lonlat(tmp_path):
    g = random_plan_geometry(20, 10, seed=4)
    path = tmp_path / "plan.geojson"
    write_geojson_floor(path, g)
    back = read_geojson_floor(path, floor=g.floor)
    assert back.roles.count("outline") == 1 and back.roles.count("wall") == 10
    for a, b in zip(back.geometry.outlines + back.geometry.obstacles, g.outlines + g.obstacles):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(back.geometry.walls, g.walls)
    ll = floor_geometry_to_geojson(g, origin_lon_lat=ORIGIN)
    back = read_geojson_floor(ll, origin_lon_lat=ORIGIN).geometry
    for a, b in zip(back.obstacles, g.obstacles):
        np.testing.assert_allclose(a, b, atol=1e-8)
    plan = load_floor_plan([path, ll], floors=[1, 2], origin_lon_lat=None)
    assert plan.floors == [1, 2]


def test_geojson_damaged_input_names_file_and_feature(tmp_path):
    doc, _ = lonlat_fixture()

    def write(d, name="bad.geojson"):
        p = tmp_path / name
        p.write_text(d if isinstance(d, str) else json.dumps(d))
        return p

    expect_error(lambda: read_geojson_floor(tmp_path / "missing.geojson"), "missing.geojson", "not found")
    expect_error(lambda: read_geojson_floor(write("{ nope")), "bad.geojson", "invalid JSON")
    expect_error(lambda: read_geojson_floor(write({"type": "Feature"})), "bad.geojson", "FeatureCollection")
    bad = json.loads(json.dumps(doc))
    bad["features"][2]["geometry"] = {"type": "Point", "coordinates": [1, 2]}
    expect_error(lambda: read_geojson_floor(write(bad)), "bad.geojson", "feature 2", "Point")
    bad = json.loads(json.dumps(doc))
    bad["features"][1]["geometry"]["coordinates"][1][0][2] = [float("nan"), 1.0]
    expect_error(lambda: read_geojson_floor(write(bad)), "feature 1", "polygon 1", "not finite")
    bad = json.loads(json.dumps(doc))
    bad["features"][1]["geometry"]["coordinates"][0][0] = [[0, 0], [1, 1], [0, 0], [1, 1]]
    expect_error(lambda: read_geojson_floor(write(bad)), "feature 1", "3 distinct vertices")
    bad = json.loads(json.dumps(doc))
    bad["features"][0]["geometry"]["coordinates"][0][1] = ["a", 2]
    expect_error(lambda: read_geojson_floor(write(bad)), "feature 0", "position 1")
    bad = json.loads(json.dumps(doc))
    bad["features"][2]["geometry"]["coordinates"] = [[5, 5], [5, 5]]
    expect_error(lambda: read_geojson_floor(write(bad)), "feature 2", "zero-length")
    expect_error(lambda: read_geojson_floor(doc, roles=["outline"]), "'roles'", "expected 3 roles")
    expect_error(lambda: read_geojson_floor(doc, roles=["outline", "shop", "wall"]), "'roles'", "feature 1", "shop")
    expect_error(lambda: read_geojson_floor(doc, roles=["wall", "outline", "outline"]), "feature 2",
                 "needs a Polygon")
    expect_error(lambda: read_geojson_floor(doc, origin_lon_lat=(0, 95)), "'origin_lon_lat'")
    # The floor plan's own checks are mapped back to the file and the feature.
    bad = json.loads(json.dumps(doc))
    bad["features"].append({"type": "Feature", "properties": {}, "geometry": {
        "type": "Polygon", "coordinates": [local_to_lonlat([[1, 1], [3, 3], [3, 1], [1, 2], [1, 1]], ORIGIN).tolist()]}})
    expect_error(lambda: load_floor_plan(write(bad, "selfx.geojson"), origin_lon_lat=ORIGIN),
                 "floors[0].obstacles[3]", "self-intersecting", "selfx.geojson: feature 3")



def test_load_floor_plan_names_the_file_for_every_floor_plan_error(tmp_path):
    # Only ring errors named the file; a wall's coordinates, a floor without an outline, a repeated
    # floor number and the index's memory named floors[i] alone.
    def write(name, features):
        p = tmp_path / name
        p.write_text(json.dumps({"type": "FeatureCollection", "features": [
            {"type": "Feature", "properties": {"role": role}, "geometry": {"type": kind, "coordinates": c}}
            for role, kind, c in features]}))
        return p

    square = ("outline", "Polygon", [[[0, 0], [20, 0], [20, 10], [0, 10], [0, 0]]])
    good = write("good.geojson", [square])
    wall = write("wall.geojson", [square, ("wall", "LineString", [[1, 1], [1e9, 1]])])
    expect_error(lambda: load_floor_plan(wall), "floors[0].walls", "wall.geojson: feature 1")
    bare = write("bare.geojson", [("wall", "LineString", [[1, 1], [2, 2]])])
    expect_error(lambda: load_floor_plan(bare), "at least one outline", "bare.geojson")
    expect_error(lambda: load_floor_plan([good, bare], floors=[3, 3]), "repeated", "floors[1]: ")
    big = write("big.geojson", [("outline", "Polygon", [[[0, 0], [9000, 0], [9000, 9000], [0, 9000], [0, 0]]])])
    expect_error(lambda: load_floor_plan(big, options=FloorPlanOptions(cell_size_m=1.0, max_cells=100_000_000)),
                 "options.cell_size_m", "GB", "big.geojson")


def test_write_geojson_floor_checks_the_floor_number(tmp_path):
    from types import SimpleNamespace

    ring = box(0, 0, 5, 5)
    nan_floor = SimpleNamespace(floor=float("nan"), outlines=[ring], obstacles=[], walls=np.zeros((0, 4)))
    expect_error(lambda: write_geojson_floor(tmp_path / "a.geojson", nan_floor), "'geometry.floor'")  # was "a coordinate"
    assert not (tmp_path / "a.geojson").exists()
    numpy_floor = SimpleNamespace(floor=np.int64(2), outlines=[ring], obstacles=[], walls=np.zeros((0, 4)))
    write_geojson_floor(tmp_path / "b.geojson", numpy_floor)  # was json's "int64 is not JSON serializable"
    assert json.loads((tmp_path / "b.geojson").read_text())["features"][0]["properties"]["floor"] == 2


# ---- the ILC 2020 floor in ../shared/data -------------------------------------------------

def test_ilc2020_site2_floor3(shared_data):
    folder = shared_data / "fusion" / "ilc2020_site2" / "F3"
    f = read_geojson_floor(folder / "geojson_map.json", floor=3, origin_lon_lat="outline_sw")
    g = f.geometry
    assert len(g.outlines) == 1 and len(g.obstacles) == 275
    extent = g.outlines[0].max(axis=0) - g.outlines[0].min(axis=0)
    np.testing.assert_allclose(extent, [236.9, 218.8], atol=0.05)  # README: 236.9 x 218.8 m
    info = json.loads((folder / "floor_info.json").read_text())["map_info"]
    np.testing.assert_allclose(extent, [info["width"], info["height"]], atol=1.0)
    waypoints = []
    for path in sorted((folder / "path_data_files").glob("*.txt")):
        for line in path.read_text().splitlines():
            cols = line.split("\t")
            if len(cols) >= 4 and cols[1] == "TYPE_WAYPOINT":
                waypoints.append((float(cols[2]), float(cols[3])))
    waypoints = np.array(waypoints)
    assert len(waypoints) > 100
    outline_only = FloorPlan(FloorGeometry(floor=3, outlines=g.outlines))
    assert outline_only.is_walkable(waypoints).all()  # README: every waypoint inside the outline
    plan = load_floor_plan(folder / "geojson_map.json", floors=[3], origin_lon_lat="outline_sw")
    in_shops = ~plan.is_walkable(waypoints)
    assert in_shops.sum() <= 12  # README: 12 of 866 waypoints (4 floors) fall inside a shop
    assert 0 < plan.walkable_area() < outline_only.walkable_area()
