"""Seeded synthetic building for the fusion subsystem: floor plan, walkable graph, WiFi, survey.

Layout (the same on every floor; x east, y north, origin at the south-west corner, metres):

- the outline is a ``width_m`` x ``depth_m`` rectangle;
- a main corridor (``corridor_width_m`` wide) runs east-west across the building near y = depth/2;
  ``num_branches`` branch corridors run north-south across the whole depth, crossing it;
- the blocks between corridors hold rooms: a *front row* along the main corridor
  (``rooms_per_side`` rooms on each side in all, depth ``front_room_depth_m``), and behind it
  *back rooms* stacked along the branch corridors (depth ``back_room_depth_m``; a block with a
  branch on both sides is split into two columns, one per branch);
- every room is enclosed by thin walls (segments) with one door gap of ``door_width_m`` onto a
  corridor, and with probability ``second_door_probability`` a second one (onto another corridor
  it touches, or further along the same wall);
- ``num_shafts`` front-row rooms are closed blocks (lift/stair shafts: obstacle rings, no door)
  and ``num_pillars`` square pillars (obstacle rings) stand in large rooms.

The geometry per floor is a :class:`FloorGeometry` in the format of the fusion FloorPlan
(``cpp/include/indoorloc/fusion/floor_plan.h``): outline rings, obstacle rings, wall segments.
The walkable graph (:class:`WalkGraph`) has nodes on the corridor centre lines (ends, junctions,
the feet of doors), at doors, at approach points ``approach_m`` either side of each door on its
axis, and at room centres; its edges cross no wall and pass no pillar (checked at construction).

Randomness: ``numpy.random.default_rng([seed, 0xB1D, stream])`` with streams 0 layout, 1 access
point positions, 2 radio field (powers, shadowing), 3 survey noise, so a survey can be re-drawn
with the field held fixed; walks (walker.py) use their own seed and domain.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import List, Optional, Tuple

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, dijkstra

from indoorloc.simulate import _geometry as geo
from indoorloc.validate import integer, real_array, real_scalar
from indoorloc.simulate.radio import RadioConfig, RadioModel, Survey, SurveyConfig, make_radio_model, run_survey

_DOMAIN = 0xB1D
_LAYOUT_STREAM, _AP_STREAM, _RADIO_STREAM, _SURVEY_STREAM = 0, 1, 2, 3
_EPS = 1e-9

#: Walk-graph node kinds (``WalkGraph.kind`` holds the index into this tuple).
NODE_KINDS = ("corridor", "junction", "door", "approach", "room")
CORRIDOR, JUNCTION, DOOR, APPROACH, ROOM = range(5)


@dataclass(frozen=True)
class BuildingConfig:
    """Layout parameters. Lengths in metres; defaults give a 60 x 40 m office floor with about 50
    rooms, 4 corridors (2.5 m), 2 shafts and 6 pillars."""

    width_m: float = 60.0
    depth_m: float = 40.0
    num_floors: int = 1
    floor_height_m: float = 3.5
    corridor_width_m: float = 2.5
    num_branches: int = 3                  #: north-south corridors crossing the main one
    position_jitter_m: float = 1.5         #: random shift of the corridors from their even spacing
    rooms_per_side: int = 10               #: front-row rooms along each side of the main corridor
    front_room_depth_m: Tuple[float, float] = (5.0, 7.0)   #: uniform range, drawn per side
    back_room_depth_m: Tuple[float, float] = (4.0, 6.0)    #: nominal range of stacked back rooms
    room_size_jitter: float = 0.2          #: relative spread of room widths around their mean
    door_width_m: float = 1.0
    second_door_probability: float = 0.4
    num_shafts: int = 2
    num_pillars: int = 6
    pillar_size_m: float = 0.6
    pillar_min_room_area_m2: float = 30.0
    approach_m: float = 0.6                #: graph nodes this far from a door on either side

    def validate(self) -> None:
        # Every field, with upper bounds: the layout, the graph and one FloorGeometry per floor
        # grow with these (num_floors = 2**31 used to fill the memory in a list comprehension).
        for name, hi in (("width_m", 1e4), ("depth_m", 1e4), ("floor_height_m", 100.0),
                         ("corridor_width_m", 1e3), ("door_width_m", 1e3), ("pillar_size_m", 1e3),
                         ("approach_m", 1e3)):
            real_scalar(getattr(self, name), f"config.{name}", lo=1e-3, hi=hi)
        real_scalar(self.position_jitter_m, "config.position_jitter_m", lo=0.0, hi=1e3)
        real_scalar(self.pillar_min_room_area_m2, "config.pillar_min_room_area_m2", lo=0.0, hi=1e8)
        real_scalar(self.room_size_jitter, "config.room_size_jitter", lo=0.0, hi=0.5)
        real_scalar(self.second_door_probability, "config.second_door_probability", lo=0.0, hi=1.0)
        for name in ("front_room_depth_m", "back_room_depth_m"):
            real_array(getattr(self, name), f"config.{name}", shape=(2,), max_abs=1e4)
        integer(self.num_floors, "config.num_floors", lo=1, hi=200)
        integer(self.num_branches, "config.num_branches", lo=0, hi=1000)
        integer(self.rooms_per_side, "config.rooms_per_side", lo=1, hi=10000)
        integer(self.num_shafts, "config.num_shafts", lo=0, hi=1000)
        integer(self.num_pillars, "config.num_pillars", lo=0, hi=10000)
        if not (2 * self.approach_m + 0.2 <= self.corridor_width_m):
            raise ValueError("indoorloc: argument 'config.corridor_width_m': must exceed 2 approach_m + 0.2")
        blocks = self.num_branches + 1
        block_w = (self.width_m - self.num_branches * self.corridor_width_m) / blocks - 2 * self.position_jitter_m
        if block_w < 2 * self.door_width_m + 2.0:
            raise ValueError("indoorloc: argument 'config': building too narrow for its branches "
                             f"(blocks of {block_w:.1f} m)")
        if self.rooms_per_side < blocks:
            raise ValueError(f"indoorloc: argument 'config.rooms_per_side': needs >= {blocks} (one per block)")
        if block_w / np.ceil(self.rooms_per_side / blocks + 1) < self.door_width_m + 1.2:
            raise ValueError("indoorloc: argument 'config.rooms_per_side': rooms too narrow for their doors")
        lo, hi = self.front_room_depth_m
        half = (self.depth_m - self.corridor_width_m) / 2 - self.position_jitter_m
        if not (0 < lo <= hi) or (self.num_branches > 0 and hi > half - self.back_room_depth_m[0]):
            raise ValueError("indoorloc: argument 'config.front_room_depth_m': must be 0 < lo <= hi and leave "
                             "room for the back rooms")
        if not (self.door_width_m + 1.2 <= self.back_room_depth_m[0] <= self.back_room_depth_m[1]):
            raise ValueError("indoorloc: argument 'config.back_room_depth_m': must be ordered and fit a door")
        if not (0 <= self.room_size_jitter < 0.5) or not (0 <= self.second_door_probability <= 1):
            raise ValueError("indoorloc: argument 'config': room_size_jitter in [0, 0.5), "
                             "second_door_probability in [0, 1]")


@dataclass
class FloorGeometry:
    """One floor in the fusion FloorPlan's format (metres, floor frame)."""

    floor: int
    outlines: List[np.ndarray]     #: rings (M, 2) without closing vertex; their union is the floor
    obstacles: List[np.ndarray]    #: rings removed from the area (shafts, pillars)
    walls: np.ndarray              #: (W, 4) thin wall segments x0, y0, x1, y1

    def ring_edges(self) -> np.ndarray:
        """(R, 4) edges of all outline and obstacle rings."""
        rings = list(self.outlines) + list(self.obstacles)
        return np.vstack([geo.ring_edges(r) for r in rings]) if rings else np.zeros((0, 4))

    def obstacle_edges(self) -> np.ndarray:
        """(O, 4) edges of the obstacle rings only."""
        return np.vstack([geo.ring_edges(r) for r in self.obstacles]) if self.obstacles else np.zeros((0, 4))

    def edges(self) -> np.ndarray:
        """All wall edges (ring edges + wall segments), (E, 4): what a step must not touch."""
        return np.vstack([self.ring_edges(), self.walls])

    def is_walkable(self, points_m: np.ndarray) -> np.ndarray:
        """(N,) bool: inside an outline and inside no obstacle (the FloorPlan definition)."""
        p = np.asarray(points_m, float).reshape(-1, 2)
        inside = np.zeros(p.shape[0], bool)
        for r in self.outlines:
            inside |= geo.points_in_ring(p, r)
        for r in self.obstacles:
            inside &= ~geo.points_in_ring(p, r)
        return inside

    def crosses_wall(self, starts_m: np.ndarray, ends_m: np.ndarray) -> np.ndarray:
        """(N,) bool: the segment start -> end intersects or touches a wall edge."""
        return geo.touches_any(starts_m, ends_m, self.edges())

    def distance_to_wall(self, points_m: np.ndarray) -> np.ndarray:
        """(N,) distance [m] to the nearest wall edge."""
        return geo.distance_to_segments(points_m, self.edges())


@dataclass
class Corridor:
    index: int
    rect_m: np.ndarray      #: (4,) x0, y0, x1, y1
    axis: int               #: 0: runs along x (east-west), 1: along y (north-south)
    centre_m: float         #: centre-line coordinate across the axis (y for axis 0, x for axis 1)


@dataclass
class Door:
    index: int
    room: int
    corridor: int
    position_m: np.ndarray  #: (2,) middle of the gap, on the wall line
    normal: np.ndarray      #: (2,) unit vector from the room into the corridor
    width_m: float


@dataclass
class Room:
    index: int
    rect_m: np.ndarray      #: (4,) x0, y0, x1, y1
    kind: str               #: "room" or "shaft" (closed block, an obstacle)
    doors: List[int] = field(default_factory=list)
    pillar: int = -1        #: index into FloorGeometry.obstacles, -1 if none

    @property
    def centre_m(self) -> np.ndarray:
        r = self.rect_m
        return np.array([(r[0] + r[2]) / 2, (r[1] + r[3]) / 2])

    @property
    def area_m2(self) -> float:
        r = self.rect_m
        return float((r[2] - r[0]) * (r[3] - r[1]))

    def contains(self, points_m: np.ndarray, margin_m: float = 0.0) -> np.ndarray:
        p = np.asarray(points_m, float).reshape(-1, 2)
        r = self.rect_m
        return ((p[:, 0] > r[0] + margin_m) & (p[:, 0] < r[2] - margin_m)
                & (p[:, 1] > r[1] + margin_m) & (p[:, 1] < r[3] - margin_m))


@dataclass
class WalkGraph:
    """Where people walk: nodes on corridor centre lines, at doors and room centres."""

    nodes_m: np.ndarray     #: (N, 2)
    kind: np.ndarray        #: (N,) index into NODE_KINDS
    room: np.ndarray        #: (N,) room of room-centre and inner-approach nodes, else -1
    door: np.ndarray        #: (N,) door of door and approach nodes, else -1
    edges: np.ndarray       #: (E, 2) node indices
    room_node: np.ndarray   #: (num rooms,) centre node of each room, -1 for shafts

    @property
    def edge_lengths_m(self) -> np.ndarray:
        return np.linalg.norm(self.nodes_m[self.edges[:, 1]] - self.nodes_m[self.edges[:, 0]], axis=1)

    def segments(self) -> np.ndarray:
        """(E, 4) edges as segments."""
        return np.hstack([self.nodes_m[self.edges[:, 0]], self.nodes_m[self.edges[:, 1]]])

    def _matrix(self):
        n = self.nodes_m.shape[0]
        w = self.edge_lengths_m
        m = coo_matrix((np.r_[w, w], (np.r_[self.edges[:, 0], self.edges[:, 1]],
                                      np.r_[self.edges[:, 1], self.edges[:, 0]])), shape=(n, n))
        return m.tocsr()

    def shortest_path(self, source: int, target: int) -> np.ndarray:
        """Node indices of a shortest path source -> target (inclusive)."""
        _, pred = dijkstra(self._matrix(), indices=int(source), return_predecessors=True)
        path = [int(target)]
        while path[-1] != source:
            p = pred[path[-1]]
            if p < 0:
                raise ValueError(f"indoorloc: argument 'target': node {target} unreachable from {source}")
            path.append(int(p))
        return np.array(path[::-1])

    def is_connected(self) -> bool:
        return connected_components(self._matrix(), directed=False)[0] == 1


@dataclass
class Building:
    """A synthetic building: geometry per floor, rooms/doors/corridors, walk graph, radio, survey."""

    seed: int
    config: BuildingConfig
    radio_config: RadioConfig
    survey_config: SurveyConfig
    floors: List[FloorGeometry]
    rooms: List[Room]
    doors: List[Door]
    corridors: List[Corridor]
    graph: WalkGraph
    radio: RadioModel
    survey: Survey

    @property
    def floor_numbers(self) -> List[int]:
        return [g.floor for g in self.floors]

    def geometry(self, floor: int = 0) -> FloorGeometry:
        for g in self.floors:
            if g.floor == floor:
                return g
        raise ValueError(f"indoorloc: argument 'floor': {floor} is not a floor of the building {self.floor_numbers}")

    @property
    def plan(self) -> FloorGeometry:
        """Geometry of the first floor (all floors share the layout)."""
        return self.floors[0]

    def walkable_rooms(self) -> List[int]:
        return [r.index for r in self.rooms if r.kind == "room"]

    def room_at(self, points_m: np.ndarray) -> np.ndarray:
        """(N,) room index containing each point, -1 in corridors."""
        p = np.asarray(points_m, float).reshape(-1, 2)
        out = np.full(p.shape[0], -1)
        for r in self.rooms:
            out[r.contains(p)] = r.index
        return out

    def walls_crossed(self, points_m: np.ndarray) -> np.ndarray:
        """(Q, K) thin walls crossed by each AP -> point segment (in plan)."""
        return self.radio.walls_crossed(points_m)

    def mean_rss_dbm(self, points_m: np.ndarray, floor: int = 0) -> np.ndarray:
        """(Q, K) true mean RSS [dBm] of every AP at points on `floor` (no noise, no cut-off)."""
        return self.radio.mean_rss_dbm(points_m, floor)

    def signal_map(self, options: Optional[object] = None):
        """The wifi SignalMap built from the survey scans (never from the true field)."""
        return self.survey.to_signal_map(options)


# --------------------------------------------------------------------------------------- layout


def _split(a: float, b: float, n: int, jitter: float, rng: np.random.Generator) -> np.ndarray:
    """n + 1 cut positions from a to b, pieces of relative size 1 +- jitter."""
    w = 1.0 + rng.uniform(-jitter, jitter, n)
    cuts = a + (b - a) * np.concatenate([[0.0], np.cumsum(w) / np.sum(w)])
    cuts[-1] = b
    return cuts


def _apportion(total: int, weights: np.ndarray) -> np.ndarray:
    """Largest-remainder split of `total` into len(weights) integers >= 1."""
    share = total * weights / weights.sum()
    n = np.maximum(np.floor(share).astype(int), 1)
    while n.sum() < total:
        n[np.argmax(share - n)] += 1
    while n.sum() > total:
        n[np.argmax(np.where(n > 1, n - share, -np.inf))] -= 1
    return n


def _sides(rect: np.ndarray):
    """(orientation, line coordinate, lo, hi) of the 4 sides: 'h' lines y = c, 'v' lines x = c."""
    x0, y0, x1, y1 = rect
    return [("h", y0, x0, x1), ("h", y1, x0, x1), ("v", x0, y0, y1), ("v", x1, y0, y1)]


def _door_sides(rect: np.ndarray, corridors: List[Corridor], min_len: float):
    """Room sides lying on a corridor's boundary: (corridor, orientation, c, lo, hi, normal)."""
    out = []
    for cor in corridors:
        cx0, cy0, cx1, cy1 = cor.rect_m
        for o, c, lo, hi in _sides(rect):
            if o == "h":
                for edge, nrm in ((cy0, (0.0, 1.0)), (cy1, (0.0, -1.0))):
                    a, b = max(lo, cx0), min(hi, cx1)
                    if abs(c - edge) < _EPS and b - a >= min_len:
                        out.append((cor.index, o, c, a, b, np.array(nrm)))
            else:
                for edge, nrm in ((cx0, (1.0, 0.0)), (cx1, (-1.0, 0.0))):
                    a, b = max(lo, cy0), min(hi, cy1)
                    if abs(c - edge) < _EPS and b - a >= min_len:
                        out.append((cor.index, o, c, a, b, np.array(nrm)))
    return out


def _union(intervals: List[Tuple[float, float]]) -> List[Tuple[float, float]]:
    out: List[List[float]] = []
    for a, b in sorted(intervals):
        if out and a <= out[-1][1] + _EPS:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return [(a, b) for a, b in out]


def _subtract(intervals: List[Tuple[float, float]], cut: Tuple[float, float]) -> List[Tuple[float, float]]:
    out = []
    for a, b in intervals:
        if cut[1] <= a + _EPS or cut[0] >= b - _EPS:
            out.append((a, b))
            continue
        if cut[0] > a + _EPS:
            out.append((a, cut[0]))
        if cut[1] < b - _EPS:
            out.append((cut[1], b))
    return out


def _layout(cfg: BuildingConfig, rng: np.random.Generator):
    W, D, cw = cfg.width_m, cfg.depth_m, cfg.corridor_width_m
    nb = cfg.num_branches
    jit = cfg.position_jitter_m
    yc = D / 2 + rng.uniform(-jit, jit)
    xb = W * np.arange(1, nb + 1) / (nb + 1) + rng.uniform(-jit, jit, nb)
    corridors = [Corridor(0, np.array([0.0, yc - cw / 2, W, yc + cw / 2]), 0, yc)]
    for i, x in enumerate(xb):
        corridors.append(Corridor(i + 1, np.array([x - cw / 2, 0.0, x + cw / 2, D]), 1, x))
    # Block columns between branches.
    edges_x = np.concatenate([[0.0], np.ravel(np.column_stack([xb - cw / 2, xb + cw / 2])), [W]])
    cols = edges_x.reshape(-1, 2)
    front_counts = _apportion(cfg.rooms_per_side, cols[:, 1] - cols[:, 0])
    rects: List[np.ndarray] = []
    is_front: List[bool] = []
    back_depth_mean = 0.5 * (cfg.back_room_depth_m[0] + cfg.back_room_depth_m[1])
    for side in (-1, +1):       # south, north of the main corridor
        df = rng.uniform(*cfg.front_room_depth_m)
        edge = yc - cw / 2 if side < 0 else yc + cw / 2
        outer = 0.0 if side < 0 else D
        front_far = edge - df if side < 0 else edge + df
        if nb == 0:
            front_far = outer
        for b, (xa, xz) in enumerate(cols):
            cuts = _split(xa, xz, int(front_counts[b]), cfg.room_size_jitter, rng)
            ys = sorted((edge, front_far))
            for i in range(len(cuts) - 1):
                rects.append(np.array([cuts[i], ys[0], cuts[i + 1], ys[1]]))
                is_front.append(True)
            if nb == 0:
                continue
            # Back rooms along the branches: one column per adjacent branch.
            has_left, has_right = b > 0, b < nb
            if has_left and has_right and xz - xa >= 2 * (cfg.door_width_m + 3.0):
                mid = 0.5 * (xa + xz) + rng.uniform(-0.1, 0.1) * (xz - xa)
                columns = [(xa, mid), (mid, xz)]
            else:
                columns = [(xa, xz)]
            yb = sorted((front_far, outer))
            n_rows = max(1, int(round((yb[1] - yb[0]) / back_depth_mean)))
            for ca, cz in columns:
                ycuts = _split(yb[0], yb[1], n_rows, cfg.room_size_jitter, rng)
                for i in range(n_rows):
                    rects.append(np.array([ca, ycuts[i], cz, ycuts[i + 1]]))
                    is_front.append(False)
    rooms = [Room(i, r, "room") for i, r in enumerate(rects)]
    # Shafts: front-row rooms away from the outline.
    cand = [r.index for r, f in zip(rooms, is_front) if f and r.rect_m[0] > _EPS and r.rect_m[2] < W - _EPS]
    for i in rng.choice(cand, size=min(cfg.num_shafts, len(cand)), replace=False):
        rooms[int(i)].kind = "shaft"
    # Doors.
    margin = cfg.door_width_m / 2 + 0.5
    min_len = cfg.door_width_m + 1.0
    doors: List[Door] = []

    def add_door(room: Room, cor: int, o: str, c: float, a: float, b: float, nrm: np.ndarray) -> None:
        t = rng.uniform(a + margin, b - margin)
        pos = np.array([t, c]) if o == "h" else np.array([c, t])
        doors.append(Door(len(doors), room.index, cor, pos, nrm, cfg.door_width_m))
        room.doors.append(len(doors) - 1)

    for room in rooms:
        if room.kind != "room":
            continue
        sides = _door_sides(room.rect_m, corridors, min_len)
        if not sides:
            raise RuntimeError(f"indoorloc: internal: room {room.index} touches no corridor")
        first = int(rng.integers(len(sides)))
        second = rng.random() < cfg.second_door_probability
        cor, o, c, a, b, nrm = sides[first]
        others = [s for i, s in enumerate(sides) if i != first]
        if second and not others and b - a >= 2 * min_len + 2.0:
            mid = 0.5 * (a + b)
            add_door(room, cor, o, c, a, mid, nrm)
            add_door(room, cor, o, c, mid, b, nrm)
        else:
            add_door(room, cor, o, c, a, b, nrm)
            if second and others:
                add_door(room, *others[int(rng.integers(len(others)))])
    # Walls: union of room sides off the outline, minus door gaps and shaft faces.
    lines: dict = {}
    for room in rooms:
        for o, c, lo, hi in _sides(room.rect_m):
            on_outline = (o == "h" and (abs(c) < _EPS or abs(c - D) < _EPS)) or \
                         (o == "v" and (abs(c) < _EPS or abs(c - W) < _EPS))
            if not on_outline:
                lines.setdefault((o, round(c, 9)), []).append((lo, hi))
    lines = {k: _union(v) for k, v in lines.items()}
    for d in doors:
        o = "h" if d.normal[0] == 0.0 else "v"
        c = d.position_m[1] if o == "h" else d.position_m[0]
        t = d.position_m[0] if o == "h" else d.position_m[1]
        key = (o, round(c, 9))
        lines[key] = _subtract(lines[key], (t - d.width_m / 2, t + d.width_m / 2))
    obstacles: List[np.ndarray] = []
    for room in rooms:
        if room.kind == "shaft":
            for o, c, lo, hi in _sides(room.rect_m):
                key = (o, round(c, 9))
                if key in lines:
                    lines[key] = _subtract(lines[key], (lo, hi))
            obstacles.append(geo.rect_ring(*room.rect_m))
    walls = []
    for (o, c), ivs in sorted(lines.items()):
        for a, b in ivs:
            if b - a > _EPS:
                walls.append([a, c, b, c] if o == "h" else [c, a, c, b])
    walls_m = np.array(walls, float).reshape(-1, 4)
    # Pillars in large rooms, clear of the room's centre -> door-approach legs.
    h = cfg.pillar_size_m / 2
    big = [r.index for r in rooms if r.kind == "room" and r.area_m2 >= cfg.pillar_min_room_area_m2]
    for i in rng.permutation(big)[: cfg.num_pillars]:
        room = rooms[int(i)]
        x0, y0, x1, y1 = room.rect_m
        legs_a = np.array([room.centre_m for _ in room.doors])
        legs_b = np.array([doors[d].position_m - cfg.approach_m * doors[d].normal for d in room.doors])
        for _ in range(100):
            c = rng.uniform([x0 + 1.0 + h, y0 + 1.0 + h], [x1 - 1.0 - h, y1 - 1.0 - h])
            if np.all(geo.segment_point_distance(legs_a, legs_b, c) > h * np.sqrt(2) + 0.8):
                room.pillar = len(obstacles)
                obstacles.append(geo.rect_ring(c[0] - h, c[1] - h, c[0] + h, c[1] + h))
                break
    return rooms, doors, corridors, walls_m, obstacles


def _build_graph(cfg: BuildingConfig, rooms: List[Room], doors: List[Door], corridors: List[Corridor]) -> WalkGraph:
    nodes: List[np.ndarray] = []
    kind: List[int] = []
    room_of: List[int] = []
    door_of: List[int] = []
    edges: List[Tuple[int, int]] = []

    def node(p, k, room=-1, door=-1) -> int:
        nodes.append(np.asarray(p, float))
        kind.append(k)
        room_of.append(room)
        door_of.append(door)
        return len(nodes) - 1

    end = min(1.0, cfg.corridor_width_m / 2)
    on_line: List[List[Tuple[float, int]]] = [[] for _ in corridors]
    main = corridors[0]
    for cor in corridors:
        x0, y0, x1, y1 = cor.rect_m
        if cor.axis == 0:
            on_line[cor.index] += [(x0 + end, node([x0 + end, cor.centre_m], CORRIDOR)),
                                   (x1 - end, node([x1 - end, cor.centre_m], CORRIDOR))]
        else:
            on_line[cor.index] += [(y0 + end, node([cor.centre_m, y0 + end], CORRIDOR)),
                                   (y1 - end, node([cor.centre_m, y1 - end], CORRIDOR))]
            j = node([cor.centre_m, main.centre_m], JUNCTION)
            on_line[cor.index].append((main.centre_m, j))
            on_line[main.index].append((cor.centre_m, j))
    room_node = np.full(len(rooms), -1)
    for room in rooms:
        if room.kind == "room":
            room_node[room.index] = node(room.centre_m, ROOM, room=room.index)
    for d in doors:
        cor = corridors[d.corridor]
        foot_t = d.position_m[0] if cor.axis == 0 else d.position_m[1]
        foot = [foot_t, cor.centre_m] if cor.axis == 0 else [cor.centre_m, foot_t]
        f = node(foot, CORRIDOR)
        on_line[cor.index].append((foot_t, f))
        outer = node(d.position_m + cfg.approach_m * d.normal, APPROACH, door=d.index)
        dn = node(d.position_m, DOOR, door=d.index)
        inner = node(d.position_m - cfg.approach_m * d.normal, APPROACH, room=d.room, door=d.index)
        edges += [(f, outer), (outer, dn), (dn, inner), (inner, int(room_node[d.room]))]
    for line in on_line:
        line.sort()
        edges += [(a[1], b[1]) for a, b in zip(line[:-1], line[1:])]
    return WalkGraph(nodes_m=np.array(nodes), kind=np.array(kind, np.int8), room=np.array(room_of),
                     door=np.array(door_of), edges=np.array(edges, int), room_node=room_node)


def _place_aps(cfg: BuildingConfig, radio: RadioConfig, rooms: List[Room], corridors: List[Corridor],
               plan: FloorGeometry, rng: np.random.Generator):
    """AP positions per floor: a share in (distinct) rooms, the rest in corridors; 0.3 m off walls."""
    pos, floors, in_room = [], [], []
    open_rooms = [r for r in rooms if r.kind == "room"]
    areas = np.array([(c.rect_m[2] - c.rect_m[0]) * (c.rect_m[3] - c.rect_m[1]) for c in corridors])
    for fl in range(cfg.num_floors):
        n_room = int(round(radio.ap_room_fraction * radio.aps_per_floor))
        chosen = rng.choice(len(open_rooms), size=n_room, replace=n_room > len(open_rooms))
        for k in range(radio.aps_per_floor):
            for _ in range(100):
                if k < n_room:
                    r = open_rooms[int(chosen[k])].rect_m
                else:
                    r = corridors[int(rng.choice(len(corridors), p=areas / areas.sum()))].rect_m
                p = rng.uniform(r[:2] + 0.3, r[2:] - 0.3)
                if plan.is_walkable(p)[0] and plan.distance_to_wall(p)[0] > 0.3:
                    break
            pos.append(p)
            floors.append(fl)
            in_room.append(k < n_room)
    return np.array(pos), np.array(floors), np.array(in_room)


def survey_points(plan: FloorGeometry, config: SurveyConfig) -> np.ndarray:
    """Reference points (N, 2): grid nodes at spacing/2 + i spacing that are walkable and at least
    ``wall_clearance_m`` from every wall edge."""
    xs = np.concatenate([r[:, 0] for r in plan.outlines])
    ys = np.concatenate([r[:, 1] for r in plan.outlines])
    gx = np.arange(xs.min() + config.spacing_m / 2, xs.max(), config.spacing_m)
    gy = np.arange(ys.min() + config.spacing_m / 2, ys.max(), config.spacing_m)
    g = np.column_stack([np.repeat(gx, gy.size), np.tile(gy, gx.size)])
    g = g[plan.is_walkable(g)]
    return g[plan.distance_to_wall(g) >= config.wall_clearance_m]


def make_building(seed: int = 0, config: BuildingConfig = BuildingConfig(), radio: RadioConfig = RadioConfig(),
                  survey: SurveyConfig = SurveyConfig()) -> Building:
    """Generates a building: layout, walk graph, APs and radio field, and the survey.

    Deterministic in `seed` (see the module docstring for the streams). Raises ValueError on an
    invalid configuration.
    """
    config.validate()
    radio.validate()
    survey.validate()
    seed = integer(seed, "seed", lo=0, hi=2**64 - 1)

    def stream(k: int) -> np.random.Generator:
        return np.random.default_rng([seed, _DOMAIN, k])

    rooms, doors, corridors, walls_m, obstacles = _layout(config, stream(_LAYOUT_STREAM))
    outline = geo.rect_ring(0.0, 0.0, config.width_m, config.depth_m)
    floors = [FloorGeometry(f, [outline.copy()], [o.copy() for o in obstacles], walls_m.copy())
              for f in range(config.num_floors)]
    plan = floors[0]
    graph = _build_graph(config, rooms, doors, corridors)
    seg = graph.segments()
    if plan.crosses_wall(seg[:, :2], seg[:, 2:]).any() or not graph.is_connected():
        raise RuntimeError("indoorloc: internal: walk graph crosses a wall or is disconnected")
    ap_pos, ap_floor, ap_room = _place_aps(config, radio, rooms, corridors, plan, stream(_AP_STREAM))
    model = make_radio_model(radio, ap_pos, ap_floor, ap_room, np.arange(config.num_floors),
                             config.floor_height_m, walls_m, plan.obstacle_edges(), stream(_RADIO_STREAM))
    pts = survey_points(plan, survey)
    all_pts = np.vstack([pts] * config.num_floors)
    all_fl = np.repeat(np.arange(config.num_floors), pts.shape[0])
    surv = run_survey(model, all_pts, all_fl, survey, stream(_SURVEY_STREAM))
    return Building(seed=seed, config=config, radio_config=radio, survey_config=survey, floors=floors,
                    rooms=rooms, doors=doors, corridors=corridors, graph=graph, radio=model, survey=surv)
