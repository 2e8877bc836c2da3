"""World generators: seeded office floors, the paper's scenes, and parametric test worlds.

Every generator returns a :class:`~sonarcarve.sim.walls.World` with walls, a collision-free
``tour`` and the ``openings`` (door and passage gaps). The built-in worlds shipped in
``sonarcarve/sim/worlds/`` are the output of :data:`BUILTIN_RECIPES`; regenerate them with
``python -c "from sonarcarve.sim.generate import write_builtin_worlds; write_builtin_worlds()"``.

Walls of generated floors lie on a 5 cm grid, so the JSON files stay short and exact.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from sonarcarve.sim.walls import World, WorldError, check_seed
from sonarcarve.sim.world_files import write_world_json
from sonarcarve.typing import FloatArray

__all__ = [
    "BUILTIN_RECIPES",
    "DOOR_WIDTH",
    "OFFICE_SEED",
    "TOUR_CLEARANCE",
    "corridor_opening_world",
    "doorway_world",
    "narrow_hallway_world",
    "office_world",
    "random_world",
    "t_junction_world",
    "write_builtin_worlds",
]


#: Door width of generated floors, metres: leaves 0.5 m either side of a door's centre line,
#: more than the 0.45 m tour clearance a 0.41 m-diameter robot needs.
DOOR_WIDTH = 1.0
#: Minimum distance, metres, from every generated tour to every wall (robot radius 0.205 m
#: plus 0.245 m margin).
TOUR_CLEARANCE = 0.45
#: Seed of the built-in ``office`` floor. Its tour is 261 m and takes 11.5 minutes with the
#: :func:`~sonarcarve.sim.motion.follow_waypoints` defaults (measured:
#: ``follow_waypoints(load_world("office").tour).duration / 60``).
OFFICE_SEED = 7
OFFICE_SIZE = (90.0, 60.0)

_GRID = 0.05             # generated coordinates are multiples of this, metres
_CORRIDOR = (1.8, 2.4)   # corridor widths, metres
_BLOCK_DEPTH = (9.0, 15.0)   # distance between horizontal corridors (two rows of rooms)
_BLOCK_LENGTH = (16.0, 32.0)  # distance between vertical corridors
_MIN_BLOCK = 3.5         # no block (and so no room row) is thinner than this
_ROW_SPLIT = 8.0         # blocks deeper than this hold two rows of rooms, back to back
_ROOM_WIDTH = (3.5, 7.0)  # room widths along a row, metres
_MIN_ROOM = 3.0          # rooms narrower than this are merged into their neighbour
_DOOR_MARGIN = 1.0       # door centre to the nearest room corner along the wall, metres
_ROOM_ENTRY = 1.0        # tour goes this far straight through a door before turning
_TOUR_END = 1.5          # tour ends this far from a corridor's end wall
_SIZE_LIMITS = (10.0, 1000.0)


def _snap(value: float) -> float:
    return round(round(value / _GRID) * _GRID, 6)


@dataclass(frozen=True)
class _Rect:
    x0: float
    y0: float
    x1: float
    y1: float

    @property
    def center(self) -> tuple[float, float]:
        return (self.x0 + self.x1) / 2, (self.y0 + self.y1) / 2

    def edges(self) -> list[tuple[str, float, float, float]]:
        """(orientation, line coordinate, start, stop) of the four sides."""
        return [("h", self.y0, self.x0, self.x1), ("h", self.y1, self.x0, self.x1),
                ("v", self.x0, self.y0, self.y1), ("v", self.x1, self.y0, self.y1)]


@dataclass(frozen=True)
class _Door:
    orientation: str    # "h": the door lies in a horizontal wall (passage along y)
    line: float         # the wall's y (for "h") or x (for "v")
    center: float       # position of the door's middle along the wall
    room: int           # index of the room it leads into (from a corridor or another room)
    to_corridor: bool

    def ends(self) -> FloatArray:
        lo, hi = self.center - DOOR_WIDTH / 2, self.center + DOOR_WIDTH / 2
        if self.orientation == "h":
            return np.array([[lo, self.line], [hi, self.line]])
        return np.array([[self.line, lo], [self.line, hi]])

    def middle(self) -> FloatArray:
        return np.asarray(self.ends().mean(axis=0))


@dataclass(frozen=True)
class _Floor:
    """An office floor plan before it becomes walls."""

    width: float
    height: float
    h_corridors: list[tuple[float, float]]   # (y0, y1) of each horizontal corridor, bottom-up
    v_corridors: list[tuple[float, float]]   # (x0, x1) of each vertical corridor, left to right
    rooms: list[_Rect]
    doors: list[_Door]


# --------------------------------------------------------------------------------------------
# Random office floors
# --------------------------------------------------------------------------------------------

def random_world(seed: int, width: float = 60.0, height: float = 40.0) -> World:
    """A seeded office floor: a grid of corridors, blocks of rooms between them, doors, a tour.

    Horizontal corridors run the full width and vertical ones the full height (1.8-2.4 m wide),
    so the corridors form one connected grid; the blocks between them are cut into one or two
    rows of rooms 3.5-7 m wide. Every room that touches a corridor gets a 1 m door to it; the
    others get a door to a neighbouring room, so every room is reachable. The tour runs along
    the corridors' centre lines in a serpentine (first horizontal corridor left to right, up a
    vertical one, the next to the left, ...) and steps through a few doors into rooms and back,
    keeping :data:`TOUR_CLEARANCE` from every wall.

    Parameters
    ----------
    seed : int
        >= 0. Same seed, same world (for a given numpy version: numpy may change its random streams
        between versions, which is why the built-in ``office`` is stored, not regenerated).
    width, height : float
        Building outline, metres, each in [10, 1000].

    Returns
    -------
    World
        Named ``random:SEED`` (``random:SEED:WxH`` when the size is not the default), with
        ``tour`` and ``openings`` (every door).

    Raises
    ------
    WorldError
        If the seed is negative or not an integer, or the size is outside [10, 1000] m.
    """
    seed = check_seed(seed)
    lo, hi = _SIZE_LIMITS
    if not (lo <= width <= hi and lo <= height <= hi):
        msg = f"random world size must lie in [{lo:g}, {hi:g}] m, got {width:g} x {height:g}"
        raise WorldError(msg)
    rng = np.random.default_rng(seed)
    floor = _floor_plan(rng, _snap(width), _snap(height))
    tour = _floor_tour(floor, rng)
    default = (width, height) == (60.0, 40.0)
    name = f"random:{seed}" if default else f"random:{seed}:{width:g}x{height:g}"
    description = (f"seeded office floor {floor.width:g} m x {floor.height:g} m: "
                   f"{len(floor.h_corridors)} + {len(floor.v_corridors)} corridors, "
                   f"{len(floor.rooms)} rooms")
    return World(_floor_walls(floor), name, tour,
                 np.array([door.ends() for door in floor.doors]).reshape(-1, 2, 2), description)


def office_world() -> World:
    """The built-in ``office``: a 90 m x 60 m floor (5,400 m²) like the paper's Fig. 7 building."""
    world = random_world(OFFICE_SEED, *OFFICE_SIZE)
    rooms = world.description.rsplit(", ", 1)[-1]
    description = (f"Fig. 7: a building floor of corridors and {rooms} with 1 m doors "
                   f"(random_world seed {OFFICE_SEED}); tour through corridors and rooms")
    return replace(world, name="office", description=description)


def _floor_plan(rng: np.random.Generator, width: float, height: float) -> _Floor:
    y_blocks, h_corridors = _split_axis(rng, height, _BLOCK_DEPTH, min_blocks=2)
    x_blocks, v_corridors = _split_axis(
        rng, width, _BLOCK_LENGTH, min_blocks=2 if len(h_corridors) >= 2 else 1)
    rooms: list[_Rect] = []
    open_sides: list[set[tuple[str, float]]] = []  # per block: block sides facing a corridor
    block_of_room: list[int] = []
    for bx0, bx1 in x_blocks:
        for by0, by1 in y_blocks:
            block = _Rect(bx0, by0, bx1, by1)
            sides = {side for side, on_outline in (
                (("v", bx0), bx0 <= 0.0), (("v", bx1), bx1 >= width),
                (("h", by0), by0 <= 0.0), (("h", by1), by1 >= height)) if not on_outline}
            for room in _split_block(rng, block):
                rooms.append(room)
                block_of_room.append(len(open_sides))
            open_sides.append(sides)
    doors = _place_doors(rng, rooms, [open_sides[b] for b in block_of_room])
    return _Floor(width, height, h_corridors, v_corridors, rooms, doors)


def _split_axis(rng: np.random.Generator, length: float, block: tuple[float, float],
                min_blocks: int) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    """Cut [0, length] into blocks separated by corridors; returns (blocks, corridors)."""
    mean_block, mean_corridor = sum(block) / 2, sum(_CORRIDOR) / 2
    count = max(min_blocks, round((length + mean_corridor) / (mean_block + mean_corridor)))
    while True:
        corridors = [_snap(rng.uniform(*_CORRIDOR)) for _ in range(count - 1)]
        weights = rng.uniform(0.8, 1.2, count)
        sizes = weights / weights.sum() * (length - sum(corridors))
        if sizes.min() >= _MIN_BLOCK:
            break
        if count <= min_blocks:
            # Tight sides: equal blocks are the best chance to keep every block thick enough.
            sizes = np.full(count, (length - sum(corridors)) / count)
            break
        count -= 1
    blocks, gaps, start = [], [], 0.0
    for i, size in enumerate(sizes):
        stop = length if i == count - 1 else _snap(start + size)
        blocks.append((start, stop))
        if i < count - 1:
            gaps.append((stop, _snap(stop + corridors[i])))
            start = gaps[-1][1]
    if min(b1 - b0 for b0, b1 in blocks) < _MIN_BLOCK:
        msg = f"a {length:g} m side is too short for {count} blocks of rooms and corridors"
        raise WorldError(msg)
    return blocks, gaps


def _split_block(rng: np.random.Generator, block: _Rect) -> list[_Rect]:
    """Rooms of one block: one or two rows along its long axis, each cut into rooms."""
    along_x = (block.x1 - block.x0) >= (block.y1 - block.y0)
    u0, u1, v0, v1 = ((block.x0, block.x1, block.y0, block.y1) if along_x
                      else (block.y0, block.y1, block.x0, block.x1))
    depth = v1 - v0
    rows = [(v0, v1)]
    if depth >= _ROW_SPLIT:
        cut = _snap(v0 + depth * rng.uniform(0.4, 0.6))
        rows = [(v0, cut), (cut, v1)]
    rooms = []
    for r0, r1 in rows:
        cuts = [u0]
        while u1 - cuts[-1] > _ROOM_WIDTH[1]:
            cuts.append(_snap(cuts[-1] + rng.uniform(*_ROOM_WIDTH)))
        if u1 - cuts[-1] < _MIN_ROOM and len(cuts) > 1:
            cuts.pop()
        cuts.append(u1)
        for a, b in itertools.pairwise(cuts):
            rooms.append(_Rect(a, r0, b, r1) if along_x else _Rect(r0, a, r1, b))
    return rooms


def _place_doors(rng: np.random.Generator, rooms: list[_Rect],
                 open_sides: list[set[tuple[str, float]]]) -> list[_Door]:
    """One corridor door per room that touches a corridor; the rest connect through neighbours."""
    doors: list[_Door] = []
    connected = set()
    for i, room in enumerate(rooms):
        choices = [edge for edge in room.edges() if edge[:2] in open_sides[i]]
        if choices:
            orientation, line, start, stop = choices[rng.integers(len(choices))]
            doors.append(_Door(orientation, line, _door_center(rng, start, stop), i, True))
            connected.add(i)
    for min_overlap in (2 * _DOOR_MARGIN, DOOR_WIDTH + 0.2):
        grew = True
        while grew and len(connected) < len(rooms):
            grew = False
            for i in range(len(rooms)):
                if i in connected:
                    continue
                for j in sorted(connected):
                    shared = _shared_wall(rooms[i], rooms[j])
                    if shared is not None and shared[3] - shared[2] >= min_overlap:
                        orientation, line, start, stop = shared
                        doors.append(_Door(orientation, line, _door_center(rng, start, stop),
                                           i, False))
                        connected.add(i)
                        grew = True
                        break
    if len(connected) < len(rooms):  # pragma: no cover - never seen with the size limits
        msg = "generated floor has a room without a door; try another seed"
        raise WorldError(msg)
    return doors


def _door_center(rng: np.random.Generator, start: float, stop: float) -> float:
    lo, hi = start + _DOOR_MARGIN, stop - _DOOR_MARGIN
    if hi <= lo:
        return _snap((start + stop) / 2)
    return _snap(rng.uniform(lo, hi))


def _shared_wall(a: _Rect, b: _Rect) -> tuple[str, float, float, float] | None:
    """The stretch of wall two rooms share, as (orientation, line, start, stop), or None."""
    for ea in a.edges():
        for eb in b.edges():
            if ea[0] == eb[0] and abs(ea[1] - eb[1]) < 1e-9:
                start, stop = max(ea[2], eb[2]), min(ea[3], eb[3])
                if stop > start:
                    return ea[0], ea[1], start, stop
    return None


def _floor_walls(floor: _Floor) -> FloatArray:
    """Walls: union of the outline and all room sides per grid line, minus the door gaps."""
    outline = _Rect(0.0, 0.0, floor.width, floor.height)
    edges = [edge for rect in (outline, *floor.rooms) for edge in rect.edges()]
    gaps = [(door.orientation, door.line, door.center - DOOR_WIDTH / 2,
             door.center + DOOR_WIDTH / 2) for door in floor.doors]
    return _walls_from_edges(edges, gaps)


def _walls_from_edges(edges: Iterable[tuple[str, float, float, float]],
                      gaps: Iterable[tuple[str, float, float, float]]) -> FloatArray:
    lines: dict[tuple[str, float], list[tuple[float, float]]] = {}
    for orientation, line, start, stop in edges:
        lines.setdefault((orientation, round(line, 6)), []).append((start, stop))
    cuts: dict[tuple[str, float], list[tuple[float, float]]] = {}
    for orientation, line, start, stop in gaps:
        cuts.setdefault((orientation, round(line, 6)), []).append((start, stop))
    walls = []
    for key in sorted(lines):
        for start, stop in _subtract(_union(lines[key]), cuts.get(key, [])):
            orientation, line = key
            walls.append([start, line, stop, line] if orientation == "h"
                         else [line, start, line, stop])
    return np.array(walls, dtype=np.float64).reshape(-1, 4)


def _union(intervals: list[tuple[float, float]]) -> list[tuple[float, float]]:
    merged: list[tuple[float, float]] = []
    for start, stop in sorted(intervals):
        if merged and start <= merged[-1][1] + 1e-9:
            merged[-1] = (merged[-1][0], max(merged[-1][1], stop))
        else:
            merged.append((start, stop))
    return merged


def _subtract(intervals: list[tuple[float, float]],
              holes: list[tuple[float, float]]) -> list[tuple[float, float]]:
    out = []
    for start, stop in intervals:
        pieces = [(start, stop)]
        for h0, h1 in holes:
            pieces = [piece for a, b in pieces
                      for piece in ((a, min(b, h0)), (max(a, h1), b)) if piece[1] - piece[0] > 1e-9]
        out.extend(pieces)
    return out


def _floor_tour(floor: _Floor, rng: np.random.Generator) -> FloatArray:
    """Serpentine along the corridor centre lines, with a few room visits through doors."""
    ys = [(y0 + y1) / 2 for y0, y1 in floor.h_corridors]
    xs = [(x0 + x1) / 2 for x0, x1 in floor.v_corridors]
    left, right = _TOUR_END, floor.width - _TOUR_END
    route: list[tuple[float, float]] = []
    x = left
    for k, y in enumerate(ys):
        going_right = k % 2 == 0
        if k == len(ys) - 1:
            end = right if going_right else left
        else:
            end = max(xs) if going_right else min(xs)
        route += [(x, y), (end, y)]
        x = end
    legs = [(np.array(a), np.array(b)) for a, b in itertools.pairwise(route)
            if a != b]
    visits = _choose_visits(floor, legs, rng)
    points: list[FloatArray] = [legs[0][0]]
    for index, (a, b) in enumerate(legs):
        for _, door in sorted(visits.get(index, []), key=lambda item: item[0]):
            points.extend(_room_visit(floor, door, a, b))
        points.append(b)
    return np.array(points, dtype=np.float64)


def _choose_visits(floor: _Floor, legs: list[tuple[FloatArray, FloatArray]],
                   rng: np.random.Generator) -> dict[int, list[tuple[float, _Door]]]:
    """Pick about one room visit per 40 m of route (2 to 8) among doors along the legs."""
    candidates: list[tuple[int, float, _Door]] = []
    for index, (a, b) in enumerate(legs):
        direction = (b - a) / np.linalg.norm(b - a)
        for door in floor.doors:
            if not door.to_corridor:
                continue
            middle = door.middle()
            along = float(np.dot(middle - a, direction))
            across = abs(float(_cross2(direction, middle - a)))
            # A door on this corridor's wall: its normal is perpendicular to the leg.
            horizontal_leg = abs(direction[0]) > 0.5
            if (door.orientation == "h") != horizontal_leg:
                continue
            if across <= 1.3 and 0.5 < along < float(np.linalg.norm(b - a)) - 0.5:
                candidates.append((index, along, door))
    length = sum(float(np.linalg.norm(b - a)) for a, b in legs)
    count = min(len(candidates), max(2, min(8, round(length / 40.0))))
    chosen = sorted(rng.choice(len(candidates), size=count, replace=False)) if count else []
    visits: dict[int, list[tuple[float, _Door]]] = {}
    for pick in chosen:
        index, along, door = candidates[int(pick)]
        visits.setdefault(index, []).append((along, door))
    return visits


def _room_visit(floor: _Floor, door: _Door, a: FloatArray, b: FloatArray) -> list[FloatArray]:
    """Corridor point -> door -> 1 m inside -> room centre, and back the same way."""
    middle = door.middle()
    direction = (b - a) / np.linalg.norm(b - a)
    on_leg = a + np.dot(middle - a, direction) * direction
    room = floor.rooms[door.room]
    inward = np.sign(np.asarray(room.center) - middle)
    normal = np.array([0.0, inward[1]]) if door.orientation == "h" else np.array([inward[0], 0.0])
    inside = middle + _ROOM_ENTRY * normal
    center = np.asarray(room.center, dtype=np.float64)
    return [on_leg, middle, inside, center, inside, middle, on_leg]


def _cross2(a: FloatArray, b: FloatArray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


# --------------------------------------------------------------------------------------------
# The paper's scenes and parametric worlds
# --------------------------------------------------------------------------------------------

def _world_from_edges(edges: list[tuple[str, float, float, float]], name: str,
                      tour: Sequence[tuple[float, float]],
                      openings: Sequence[Sequence[tuple[float, float]]], description: str) -> World:
    return World(_walls_from_edges(edges, []), name, np.array(tour, dtype=np.float64),
                 np.array(openings, dtype=np.float64).reshape(-1, 2, 2), description)


def t_junction_world(corridor_width: float = 2.0, stem_length: float = 12.0,
                     arm_length: float = 8.0) -> World:
    """Paper Fig. 4: a hallway (the stem, along +y) ending in a T junction with a crossing one.

    The stem spans x in [-w/2, w/2], y in [0, stem_length]; the crossing hallway spans
    y in [stem_length, stem_length + w] and x in [-arm_length, arm_length]; every end is closed.
    The tour drives up the stem's centre line to the junction's centre and turns right. The two
    openings are the mouths of the left and right arms, seen from the junction.
    """
    w, top = corridor_width, stem_length + corridor_width
    half = w / 2
    if not (w > 2 * TOUR_CLEARANCE and arm_length > half + _TOUR_END and stem_length > 2.0):
        msg = "t_junction_world: corridors too narrow or too short for a tour"
        raise WorldError(msg)
    edges = [("v", -half, 0.0, stem_length), ("v", half, 0.0, stem_length),
             ("h", 0.0, -half, half),
             ("h", stem_length, -arm_length, -half), ("h", stem_length, half, arm_length),
             ("h", top, -arm_length, arm_length),
             ("v", -arm_length, stem_length, top), ("v", arm_length, stem_length, top)]
    mid = stem_length + half
    tour = [(0.0, 1.0), (0.0, mid), (arm_length - _TOUR_END, mid)]
    openings = [[(-half, stem_length), (-half, top)], [(half, stem_length), (half, top)]]
    return _world_from_edges(
        edges, "t-junction", tour, openings,
        f"Fig. 4: a {w:g} m hallway ending in a T junction with a crossing one; "
        "tour up to the junction, then right")


def narrow_hallway_world(corridor_width: float = 2.0, narrow_width: float = 1.3,
                         opening_width: float = 1.5, opening_at: float = 7.0,
                         length: float = 18.0, side_depth: float = 5.0) -> World:
    """Paper Fig. 9: a corridor (along +y) that narrows just past an opening on its right.

    The left wall runs straight at x = -w/2. The right wall (x = +w/2) stops at ``opening_at``,
    where a side corridor of ``opening_width`` leads right, ``side_depth`` deep; above the
    opening the right wall steps in, leaving a hallway ``narrow_width`` wide up to the closed end
    at ``length``. The tour runs straight up the narrow part's centre line. Openings: the side
    opening (its two corners) and the mouth of the narrow part (left wall to the step corner).
    """
    half = corridor_width / 2
    left, step = -half, -half + narrow_width
    top_of_opening = opening_at + opening_width
    if not (2 * TOUR_CLEARANCE < narrow_width < corridor_width and top_of_opening + 2 < length):
        msg = "narrow_hallway_world: need 0.9 m < narrow_width < corridor_width and room above"
        raise WorldError(msg)
    far = half + side_depth
    edges = [("v", left, 0.0, length), ("h", 0.0, left, half), ("v", half, 0.0, opening_at),
             ("h", opening_at, half, far), ("v", far, opening_at, top_of_opening),
             ("h", top_of_opening, step, far), ("v", step, top_of_opening, length),
             ("h", length, left, step)]
    x = (left + step) / 2
    tour = [(x, 1.0), (x, length - _TOUR_END)]
    openings = [[(half, opening_at), (half, top_of_opening)],
                [(left, top_of_opening), (step, top_of_opening)]]
    return _world_from_edges(
        edges, "narrow-hallway", tour, openings,
        f"Fig. 9: a {corridor_width:g} m corridor narrowing to {narrow_width:g} m just past a "
        f"{opening_width:g} m opening on its right; tour straight up it")


def doorway_world(door_width: float = 0.85, distance: float = 4.0, stop: float = 1.0,
                  room_width: float = 8.0, far_depth: float = 4.0) -> World:
    """Paper Fig. 2: a wall with a door, approached head-on.

    The robot starts at the origin facing +y; the wall is the line y = ``distance`` across a
    room ``room_width`` wide (x in [-room_width/2, room_width/2], back wall at y = -1.5), with a
    door of ``door_width`` centred on x = 0 leading into a second room ``far_depth`` deep. The
    tour is the straight approach from the origin to ``stop`` metres short of the wall (a door
    narrower than 0.9 m is too tight to drive through with 0.45 m clearance). The opening is the
    door.
    """
    half_room, half_door = room_width / 2, door_width / 2
    if not (0.0 < door_width < room_width - 1.0 and 0.0 < stop < distance - 0.5):
        msg = "doorway_world: need 0 < door_width < room_width - 1 and 0 < stop < distance - 0.5"
        raise WorldError(msg)
    back, top = -1.5, distance + far_depth
    edges = [("h", back, -half_room, half_room), ("h", top, -half_room, half_room),
             ("v", -half_room, back, top), ("v", half_room, back, top),
             ("h", distance, -half_room, -half_door), ("h", distance, half_door, half_room)]
    tour = [(0.0, 0.0), (0.0, distance - stop)]
    openings = [[(-half_door, distance), (half_door, distance)]]
    return _world_from_edges(
        edges, "doorway", tour, openings,
        f"Fig. 2: a wall with a {door_width:g} m door; tour straight at it, stopping {stop:g} m "
        "short")


def corridor_opening_world(opening_width: float = 1.0, corridor_width: float = 2.0,
                           length: float = 14.0, opening_at: float = 7.0,
                           side_depth: float = 3.0) -> World:
    """A straight corridor (along +y) with one opening in its right wall into a side room.

    The corridor spans x in [-w/2, w/2], y in [0, ``length``], closed at both ends; the opening
    is centred on y = ``opening_at`` and leads into a room ``side_depth`` deep and 3 m wider than
    the opening. The tour drives the corridor's centre line from y = 1 to ``length`` - 1.5, past
    the opening. The opening is the gap in the right wall.
    """
    half, gap = corridor_width / 2, opening_width / 2
    room_lo, room_hi = opening_at - gap - 1.5, opening_at + gap + 1.5
    if not (corridor_width > 2 * TOUR_CLEARANCE and opening_width > 0.0
            and room_lo > 0.0 and room_hi < length):
        msg = "corridor_opening_world: the opening's side room must fit along the corridor"
        raise WorldError(msg)
    far = half + side_depth
    edges = [("v", -half, 0.0, length), ("h", 0.0, -half, half), ("h", length, -half, half),
             ("v", half, 0.0, opening_at - gap), ("v", half, opening_at + gap, length),
             ("h", room_lo, half, far), ("h", room_hi, half, far), ("v", far, room_lo, room_hi),
             ("v", half, room_lo, room_hi)]
    # The side room's own wall along x = half overlaps the corridor wall; the gap is cut below.
    walls = _walls_from_edges(edges, [("v", half, opening_at - gap, opening_at + gap)])
    tour = np.array([(0.0, 1.0), (0.0, length - _TOUR_END)])
    openings = np.array([[(half, opening_at - gap), (half, opening_at + gap)]])
    return World(walls, "corridor-opening", tour, openings,
                 f"a {corridor_width:g} m corridor with a {opening_width:g} m opening on its right "
                 "into a side room; tour straight past it")


#: How each built-in world in ``sonarcarve/sim/worlds/`` is made.
BUILTIN_RECIPES: dict[str, Callable[[], World]] = {
    "doorway": doorway_world,
    "narrow-hallway": narrow_hallway_world,
    "office": office_world,
    "t-junction": t_junction_world,
}


def write_builtin_worlds(directory: str | Path | None = None) -> list[Path]:
    """Regenerate the built-in world JSON files (default: the package's ``sim/worlds/``)."""
    folder = Path(directory) if directory is not None else Path(__file__).parent / "worlds"
    written = []
    for name, recipe in BUILTIN_RECIPES.items():
        path = folder / f"{name}.json"
        write_world_json(recipe(), path)
        path.chmod(0o644)  # package data: atomic writes create owner-only files
        written.append(path)
    return written
