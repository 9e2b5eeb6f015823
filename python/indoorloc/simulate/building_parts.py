"""The parts of a synthetic building (:mod:`indoorloc.simulate.building`): its configuration, a
floor's geometry in the fusion FloorPlan's format, corridors, doors, rooms and the walkable graph."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import List, Tuple

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, dijkstra

from indoorloc.simulate import _geometry as geo
from indoorloc.validate import integer, real_array, real_scalar

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
