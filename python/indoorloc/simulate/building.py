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

The parts: :mod:`~indoorloc.simulate.building_parts` (configuration, geometry, rooms, the walk
graph's type), :mod:`~indoorloc.simulate.building_layout` (generating the layout and the graph);
every name stays importable from here.

Randomness: ``numpy.random.default_rng([seed, 0xB1D, stream])`` with streams 0 layout, 1 access
point positions, 2 radio field (powers, shadowing), 3 survey noise, so a survey can be re-drawn
with the field held fixed; walks (walker.py) use their own seed and domain.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional

import numpy as np

from indoorloc.simulate import _geometry as geo
from indoorloc.validate import integer
from indoorloc.simulate.radio import RadioConfig, RadioModel, Survey, SurveyConfig, make_radio_model, run_survey
from indoorloc.simulate.building_layout import _build_graph, _layout
from indoorloc.simulate.building_parts import (
    APPROACH,
    CORRIDOR,
    DOOR,
    JUNCTION,
    NODE_KINDS,
    ROOM,
    BuildingConfig,
    Corridor,
    Door,
    FloorGeometry,
    Room,
    WalkGraph,
)

_DOMAIN = 0xB1D
_LAYOUT_STREAM, _AP_STREAM, _RADIO_STREAM, _SURVEY_STREAM = 0, 1, 2, 3


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


#: The building's names, importable from here (the parts are defined in building_parts).
__all__ = [
    "APPROACH", "CORRIDOR", "DOOR", "JUNCTION", "NODE_KINDS", "ROOM", "Building", "BuildingConfig", "Corridor",
    "Door", "FloorGeometry", "Room", "WalkGraph", "make_building", "survey_points",
]
