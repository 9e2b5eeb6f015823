"""The layout of a synthetic building (:mod:`indoorloc.simulate.building`): corridors, rooms with
their doors, thin walls, shafts and pillars (:func:`_layout`), and the walkable graph through them
(:func:`_build_graph`)."""

from __future__ import annotations

from typing import List, Tuple

import numpy as np

from indoorloc.simulate import _geometry as geo

from indoorloc.simulate.building_parts import (
    APPROACH,
    CORRIDOR,
    DOOR,
    JUNCTION,
    ROOM,
    BuildingConfig,
    Corridor,
    Door,
    Room,
    WalkGraph,
    _EPS,
)


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
