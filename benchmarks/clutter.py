"""Held out: cluttered rooms (table and chair legs, columns, boxes): does carving delete them?

Run from the repository root (on a shared machine, with ``nice``)::

    nice .venv/bin/python benchmarks/clutter.py                       # seeds 0-2, both physics
    nice .venv/bin/python benchmarks/clutter.py --diagnose --trace    # + evidence parts off, traces
    nice .venv/bin/python benchmarks/clutter.py --physics specular --seeds 1 --skip-grids
    nice .venv/bin/python benchmarks/clutter.py --physics amplitude-thin "amplitude-thin, 5 m"
    .venv/bin/python benchmarks/clutter.py --write-world              # worlds/clutter.json only

Every world sonarcarve was developed and held out on is walls. A table leg or a pole answers
only the beams that meet it near normal incidence; the beams of other bearings pass beside it
and free the part of its arc they cover, so carving may erase it. This script measures that on
a world nothing was tuned on: the held-out generated floor ``random:1`` (its walls, doors and
tour unchanged) with clutter added by the rule below, fixed before any run.

**The clutter** (:func:`clutter`, seeded with :data:`CLUTTER_SEED`). Discs are regular
24-gons (:meth:`~sonarcarve.sim.scene.DynamicObstacle.disc`), boxes axis-aligned squares.

- In each room the tour enters (its turning points: a waypoint whose neighbours coincide is a
  room's centre; the room is the rectangle of the nearest walls along ±x and ±y from it), in
  this order: a *table* of 4 legs (radius 2.5 cm) at the corners of a 0.8 x 1.2 m rectangle,
  its long side along x or y (a coin), with a *chair* on each long side (4 legs, radius 2 cm,
  on a 0.45 m square, 0.3 m from the table's edge); two *boxes* (0.5 x 0.5 m); a 10 cm and a
  20 cm radius *column*. Each group's centre is drawn uniformly in the room until its outline
  keeps :data:`WALL_GAP` from the walls, :data:`PATH_CLEARANCE` (the generator's tour
  clearance, 0.45 m) from the tour, and :data:`WALL_GAP` from the groups already placed.
- Along every corridor leg of the tour (legs of 3 m or more; a room visit's legs are shorter),
  every :data:`COLUMN_SPACING` m from 3.5 m in, a column of radius 0.10 and 0.20 m in turn,
  on the left and right side in turn, :data:`CORRIDOR_GAP` from the corridor wall on that side
  (found by a ray across the leg); left out where that wall is more than 1.5 m from the leg
  (a junction, a door), the column would come within :data:`PATH_CLEARANCE` of the tour, or
  within 1 m of a doorway.

**Measures**, for each seed and physics (``specular``, ``amplitude``: :mod:`heldout`'s; or
``amplitude-thin``, :data:`CLUTTER_PHYSICS`), the Scout2 ring (``--robot``: another) driving
the tour:

- the point measures of :func:`evidence.map_row` (direct kept, spurious removed per kind,
  median and p90 error ratios to centerline's) for centerline, paper carving (``carve``),
  ``combined`` (the ``process`` default), ``evidence``, and evidence with the occlusion map
  filter (``--occlusion-depth 0.5``);
- **obstacles found**: an obstacle is *heard* when a direct echo's true reflection point lies
  within 2 cm of its outline. A map point *belongs* to an obstacle when it lies within
  :data:`FOUND_DISTANCE` (0.10 m) of its outline and nearer to it than to any wall or other
  obstacle (a wall's points never count for a column beside it). A heard obstacle is
  *found at the end* when the global map has a point belonging to it; *found while near* when,
  at some moment the robot was within :data:`NEAR` (2 m) of its outline, the map it had then
  (the local map plus the points already committed to the global map) did (snapshots every
  :data:`SNAPSHOT_EVERY` readings; the occlusion filter works on the finished map only, so
  that row has no "while near");
- for the grids (carved grid and ``RangeSensorLayer`` with ROS's defaults at 0.05 and 0.10 m,
  as :mod:`heldout` builds them): occupied precision and recall against every outline
  (:func:`~sonarcarve.lab.grid_measures.grid_measures`), and an obstacle *found* when an
  occupied cell lies within one cell of a cell its outline passes through but not within one
  cell of a wall's cell (end of the run, and while near as above);
- **fate of the obstacles' direct echoes**: the share of the direct echoes from each kind of
  obstacle (and from walls) that ended as a map point on their obstacle, as a point elsewhere,
  fully carved, split, or dropped otherwise (evidence carving: confidence below its threshold;
  the occlusion filter): which rule removed them; beside it the share whose reflection lies
  outside the beam the reading declares by more than 5 cm of arc (``lab.metrics.off_beam``:
  the arc does not hold it);
- **heard**: per kind, how many were heard, by how many direct echoes, and how many readings
  of the whole run had the obstacle's centre in their freespace (beam, range minus ε: a beam
  that passed over it without hearing it, what could carve a heard one away).

``--diagnose`` adds point rows of evidence carving without its occlusion rule and without its
confidence filter (which part loses the legs; a diagnosis, nothing is tuned on it);
``--trace`` prints, for seed 0 of each physics, every direct echo of each heard leg and column
that ``carve`` or ``evidence`` lost: where its point went or which rule removed it (for paper
carving the reading that fully carved or split it, replayed with
:func:`~sonarcarve.geometry.carve_arc`; for evidence, its fate in the ``--diagnose`` rows).
"""

from __future__ import annotations

import argparse
import functools
import itertools
import math
import shlex
import sys
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from evidence import KINDS, Factory, _all_with, map_row
from heldout import GRIDS, MARGIN, PHYSICS, RESOLUTIONS
from sonarcarve import make_method
from sonarcarve.filters import OCCLUSION_DEPTH, MapFilter, filter_map, point_origins
from sonarcarve.geometry import carve_arc
from sonarcarve.geometry.fate import ArcFate
from sonarcarve.grids import OCCUPIED, OccupancyMap, trinary
from sonarcarve.lab.grid_measures import dilate, grid_measures, wall_cells
from sonarcarve.lab.instrument import RunRecord, record_run
from sonarcarve.lab.metrics import off_beam, segment_distance
from sonarcarve.maps import GlobalMap
from sonarcarve.methods import MethodConfig, SonarMethod
from sonarcarve.pipeline import ProcessResult
from sonarcarve.robot import load_robot
from sonarcarve.sim.generate import TOUR_CLEARANCE
from sonarcarve.sim.motion import follow_waypoints
from sonarcarve.sim.scene import DynamicObstacle
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import EchoKind, named_physics
from sonarcarve.sim.world import World, load_world, write_world_json

BASE_WORLD = "random:1"
CLUTTER_SEED = 12
TABLE_LEG, TABLE_SIZE = 0.025, (1.2, 0.8)  # leg radius; leg centres' rectangle (long, short)
CHAIR_LEG, CHAIR_SIDE, CHAIR_GAP = 0.02, 0.45, 0.3
BOX_SIDE = 0.5
COLUMN_RADII = (0.10, 0.20)
WALL_GAP = 0.3          # room clutter to walls and to other groups, metres
PATH_CLEARANCE = TOUR_CLEARANCE
CORRIDOR_LEG, COLUMN_SPACING, CORRIDOR_GAP = 3.0, 3.5, 0.2
DOOR_KEEPOUT, CORRIDOR_REACH = 0.5, 1.5
HEARD_DISTANCE, FOUND_DISTANCE, NEAR = 0.02, 0.10, 2.0
SNAPSHOT_EVERY = 25
TYPES = ("table leg", "chair leg", "column 10 cm", "column 20 cm", "box")
WORLD_FILE = Path(__file__).resolve().parent / "worlds" / "clutter.json"
#: The sensor models of ``--physics``: :mod:`heldout`'s two shipped ones; the amplitude model
#: with small reflectors (legs and columns echo as convex cylinders:
#: :attr:`~sonarcarve.sim.amplitude.AmplitudeModel.small_reflectors`); and that model on a
#: sonar 25.3 dB less sensitive (a wall head-on heard to 5 m, not 10.7), a stress case in which
#: a leg of 2 cm radius is heard on the axis only within about 1.8 m, so many beams that reach a leg
#: pass over it.
_THIN = named_physics("amplitude-thin", PHYSICS["amplitude"])
CLUTTER_PHYSICS = {"specular": PHYSICS["specular"], "amplitude": PHYSICS["amplitude"],
                   "amplitude-thin": _THIN,
                   "amplitude-thin, 5 m": replace(_THIN, amplitude=replace(
                       _THIN.amplitude, detection_range=5.0))}


class Obstacle(NamedTuple):
    """One piece of clutter: its type (one of :data:`TYPES`) and its outline."""

    type: str
    outline: DynamicObstacle

    @property
    def segments(self) -> np.ndarray:
        return self.outline.segments


def _disc(kind: str, center: npt.ArrayLike, radius: float) -> Obstacle:
    return Obstacle(kind, DynamicObstacle.disc(center, radius, kind))


def _box(center: npt.ArrayLike, side: float = BOX_SIDE) -> Obstacle:
    (x, y), s = np.asarray(center, dtype=np.float64), side / 2.0
    return Obstacle("box", DynamicObstacle.box(x - s, y - s, x + s, y + s))


def _table_group(center: np.ndarray, along_x: bool) -> list[Obstacle]:
    """A table's 4 legs and a chair on each of its long sides (module docstring)."""
    long, short = TABLE_SIZE
    half = np.array([long / 2, short / 2]) if along_x else np.array([short / 2, long / 2])
    out = [_disc("table leg", center + half * np.array(s), TABLE_LEG)
           for s in itertools.product((-1, 1), repeat=2)]
    across = np.array([0.0, 1.0]) if along_x else np.array([1.0, 0.0])
    offset = short / 2 + CHAIR_GAP + CHAIR_SIDE / 2
    for side in (-1, 1):
        chair = center + side * offset * across
        out += [_disc("chair leg", chair + CHAIR_SIDE / 2 * np.array(s), CHAIR_LEG)
                for s in itertools.product((-1, 1), repeat=2)]
    return out


def _vertices(group: Sequence[Obstacle]) -> np.ndarray:
    return np.vstack([o.segments[:, :2] for o in group])


def _tour_segments(world: World) -> np.ndarray:
    assert world.tour is not None
    return np.hstack((world.tour[:-1], world.tour[1:]))


def _fits(group: Sequence[Obstacle], world: World, placed: Sequence[Obstacle]) -> bool:
    points = _vertices(group)
    if world.distance_to_walls(points).min() < WALL_GAP:
        return False
    if segment_distance(points, _tour_segments(world))[0].min() < PATH_CLEARANCE:
        return False
    if placed:
        others = np.vstack([o.segments for o in placed])
        return bool(segment_distance(points, others)[0].min() >= WALL_GAP)
    return True


def visited_rooms(world: World) -> list[tuple[float, float, float, float]]:
    """The rooms the tour enters, ``(x0, y0, x1, y1)``: around each waypoint whose neighbours
    coincide (a room's centre), the nearest walls along ±x and ±y."""
    assert world.tour is not None
    tour = world.tour
    rooms = []
    for i in range(1, len(tour) - 1):
        if np.allclose(tour[i - 1], tour[i + 1]):
            d, _ = world.cast_rays(tour[i], [0.0, math.pi / 2, math.pi, 3 * math.pi / 2])
            x, y = tour[i]
            rooms.append((float(x - d[2]), float(y - d[3]), float(x + d[0]), float(y + d[1])))
    return rooms


Room = tuple[float, float, float, float]
GroupMaker = Callable[[np.ndarray], list[Obstacle]]


def _place(make: GroupMaker, room: Room, world: World,
           placed: list[Obstacle], rng: np.random.Generator) -> list[Obstacle]:
    x0, y0, x1, y1 = room
    for _ in range(2000):
        center = rng.uniform((x0, y0), (x1, y1))
        group = make(center)
        if _fits(group, world, placed):
            return group
    msg = f"no place for clutter in room {room}"
    raise RuntimeError(msg)


def _room_clutter(world: World, rng: np.random.Generator) -> list[Obstacle]:
    placed: list[Obstacle] = []
    for room in visited_rooms(world):
        along_x = bool(rng.integers(2))
        makers: list[GroupMaker] = [
                  functools.partial(_table_group, along_x=along_x), lambda c: [_box(c)],
                  lambda c: [_box(c)],
                  lambda c: [_disc("column 10 cm", c, COLUMN_RADII[0])],
                  lambda c: [_disc("column 20 cm", c, COLUMN_RADII[1])]]
        for make in makers:
            placed += _place(make, room, world, placed, rng)
    return placed


def _corridor_column(world: World, foot: np.ndarray, normal: np.ndarray,
                     radius: float) -> Obstacle | None:
    """The column of ``radius`` beside the tour at ``foot``, towards ``normal``, or None where
    the rule of the module docstring leaves it out."""
    wall, _ = world.cast_rays(foot, [math.atan2(normal[1], normal[0])])
    if wall[0] > CORRIDOR_REACH:
        return None
    column = _disc(f"column {round(100 * radius)} cm",
                   foot + (wall[0] - CORRIDOR_GAP - radius) * normal, radius)
    points = column.segments[:, :2]
    doors = world.openings.reshape(-1, 4)
    if segment_distance(points, _tour_segments(world))[0].min() < PATH_CLEARANCE:
        return None
    if len(doors) and segment_distance(points, doors)[0].min() < DOOR_KEEPOUT:
        return None
    return column


def _corridor_columns(world: World) -> list[Obstacle]:
    assert world.tour is not None
    out: list[Obstacle] = []
    turn = 0
    for a, b in itertools.pairwise(world.tour):
        length = float(np.hypot(*(b - a)))
        if length < CORRIDOR_LEG:
            continue
        direction = (b - a) / length
        for along in np.arange(COLUMN_SPACING / 2, length, COLUMN_SPACING):
            side = 1 if turn % 2 == 0 else -1
            normal = side * np.array([-direction[1], direction[0]])
            radii = COLUMN_RADII[::-1] if turn % 2 == 0 else COLUMN_RADII[:1]
            turn += 1
            for radius in radii:  # the 20 cm column where it fits, else a 10 cm one
                column = _corridor_column(world, a + along * direction, normal, radius)
                if column is not None:
                    out.append(column)
                    break
    return out


def clutter(world: World | None = None) -> list[Obstacle]:
    """The clutter of the module docstring on ``world`` (default :data:`BASE_WORLD`)."""
    base = load_world(BASE_WORLD) if world is None else world
    rng = np.random.default_rng(CLUTTER_SEED)
    return _room_clutter(base, rng) + _corridor_columns(base)


def cluttered_world() -> tuple[World, World, list[Obstacle]]:
    """The base world, the world with its clutter (same tour and doors), and the clutter."""
    base = load_world(BASE_WORLD)
    obstacles = clutter(base)
    segments = np.vstack([base.segments, *[o.segments for o in obstacles]])
    counts = {t: sum(o.type == t for o in obstacles) for t in TYPES}
    listed = ", ".join(f"{counts[t]} {t}s" for t in ("table leg", "chair leg"))
    world = World(segments, "clutter", base.tour, base.openings,
                  description=f"held-out {BASE_WORLD} with clutter (benchmarks/clutter.py): "
                  f"{listed}, {counts['column 10 cm']} columns of 10 cm and "
                  f"{counts['column 20 cm']} of 20 cm radius, {counts['box']} boxes")
    return base, world, obstacles


# -- measures ------------------------------------------------------------------------------------

POINT_ROWS = ("centerline", "carve", "combined", "evidence", "evidence, occluded points dropped")
OCCLUDED = "evidence, occluded points dropped"
#: ``--diagnose``: evidence carving with one part off (which part loses the legs; not tuning).
DIAGNOSTIC_ROWS: dict[str, Factory] = {
    "evidence, no occlusion rule": _all_with(occlusion=False),
    "evidence, no confidence filter": lambda c: _all_with()(replace(c, min_confidence=0.0)),
}
FATES = ("on its obstacle", "elsewhere", "fully carved", "split", "dropped otherwise")
MapKey = tuple[str, float]  # (map name, resolution; 0.0 for point maps)


class Truth(NamedTuple):
    """What the measures compare against, for one simulation."""

    segments: np.ndarray     # walls then every obstacle's outline, shape (m, 4)
    owner: np.ndarray        # per segment: obstacle index, -1 for a wall
    types: np.ndarray        # per obstacle: its type (one of TYPES)
    heard: np.ndarray        # per obstacle: some direct echo reflected from it
    passed_over: np.ndarray  # per obstacle: readings whose freespace holds its centre
    source: np.ndarray       # per reading: obstacle index it reflected from, -1 wall, -2 none
    outside: np.ndarray      # per reading: its reflection lies outside the beam it declares
    robot: np.ndarray        # per reading: the sensor's position, shape (n, 2)
    near: np.ndarray         # per (snapshot, obstacle): robot within NEAR of it
    stops: np.ndarray        # snapshot reading counts


class Run(NamedTuple):
    """One simulation's measures."""

    readings: int
    points: dict[str, dict[str, float]]
    grids: dict[MapKey, dict[str, float]]
    found: dict[MapKey, np.ndarray]    # per obstacle: found at the end
    near: dict[MapKey, np.ndarray]     # per obstacle: found while near (NaN: not measured)
    fates: dict[str, np.ndarray]       # per reading: index into FATES (-1: not a direct echo)
    truth: Truth


def _truth(sim: Simulation, base: World, obstacles: Sequence[Obstacle]) -> Truth:
    segments = np.vstack([base.segments, *[o.segments for o in obstacles]])
    owner = np.concatenate([np.full(len(base.segments), -1),
                            *[np.full(len(o.segments), i) for i, o in enumerate(obstacles)]])
    direct = sim.truth.kind == EchoKind.DIRECT
    source = np.full(len(sim.readings), -2)
    dist, nearest = segment_distance(sim.truth.reflection[direct], segments)
    source[direct] = np.where(dist <= HEARD_DISTANCE, owner[nearest], -1)
    heard = np.isin(np.arange(len(obstacles)), source)
    robot = np.column_stack((sim.readings.x, sim.readings.y))
    stops = np.arange(SNAPSHOT_EVERY, len(robot) + 1, SNAPSHOT_EVERY)
    near = np.column_stack([segment_distance(robot[stops - 1], o.segments)[0] <= NEAR
                            for o in obstacles])
    keep = near.any(axis=1)
    types = np.array([o.type for o in obstacles])
    passed = np.array([len(saw_through(sim, -1, np.asarray(o.outline.center), MethodConfig(),
                                       len(robot) + 1)) for o in obstacles])
    return Truth(segments, owner, types, heard, passed, source, outside_beam(sim), robot,
                 near[keep], stops[keep])


def outside_beam(sim: Simulation) -> np.ndarray:
    """Per reading: its true reflection point lies outside the beam the reading declares, by
    more than 5 cm of arc (:func:`~sonarcarve.lab.metrics.off_beam`: the arc does not hold it,
    no method can place it there); False without a reflection."""
    r = sim.readings
    return off_beam(np.column_stack([r.x, r.y]), r.theta, r.beam_width, sim.truth.reflection)


def belongs(points: np.ndarray, truth: Truth) -> np.ndarray:
    """Per point: the obstacle it belongs to (module docstring), -1 for none."""
    if not len(points):
        return np.zeros(0, dtype=np.int64)
    dist, nearest = segment_distance(points, truth.segments)
    return np.where(dist <= FOUND_DISTANCE, truth.owner[nearest], -1)


def _found(points: np.ndarray, truth: Truth) -> np.ndarray:
    return np.isin(np.arange(len(truth.heard)), belongs(points, truth))


def _found_while_near(record: RunRecord, truth: Truth) -> np.ndarray:
    gmap = record.global_map
    seen = np.zeros(len(truth.heard), dtype=bool)
    for k in range(len(truth.stops)):
        local = record.local_map(k)
        committed = gmap.xy[gmap.reading_id < record.snapshot(k).reading_id.min()]
        found = _found(np.vstack((local.xy, committed)), truth)
        seen |= found & truth.near[k]
    return seen


def _fates(record: RunRecord, gmap: GlobalMap, truth: Truth) -> np.ndarray:
    """Per reading, the index into :data:`FATES` of what became of it (-1 when no direct
    echo); ``gmap`` the map as output (after any map filter)."""
    out = np.full(len(truth.source), -1)
    final = record.final
    fate = np.full(len(truth.source), int(ArcFate.ALIVE))
    fate[final.reading_id] = final.removal
    direct = truth.source >= -1
    out[direct] = 4
    out[direct & (fate == ArcFate.FULLY_CARVED)] = 2
    out[direct & (fate == ArcFate.SPLIT)] = 3
    owner = np.full(len(truth.source), -3)
    owner[gmap.reading_id] = belongs(gmap.xy, truth)
    walls = segment_distance(gmap.xy, truth.segments)[0] <= FOUND_DISTANCE
    on_wall = np.zeros(len(truth.source), dtype=bool)
    on_wall[gmap.reading_id] = walls & (truth.owner[segment_distance(
        gmap.xy, truth.segments)[1]] == -1)
    in_map = np.zeros(len(truth.source), dtype=bool)
    in_map[gmap.reading_id] = True
    on_own = np.where(truth.source >= 0, owner == truth.source, on_wall)
    out[direct & in_map] = np.where(on_own[direct & in_map], 0, 1)
    return out


def _process_result(record: RunRecord, gmap: GlobalMap, readings: int) -> ProcessResult:
    """A :class:`ProcessResult` of ``record`` for :func:`evidence.map_row` (no unprocessed
    share: the columns printed here do not use it)."""
    return ProcessResult(gmap, len(gmap), readings, math.nan,
                         record.counters.get("fully_carved", 0), record.counters.get("split", 0),
                         record.seconds)


def _make(name: str, config: MethodConfig) -> SonarMethod:
    if name in DIAGNOSTIC_ROWS:
        return DIAGNOSTIC_ROWS[name](config)
    return make_method(name, config)


def _point_maps(sim: Simulation, truth: Truth, run: Run, rows: Sequence[str]) -> None:
    config = MethodConfig()
    center_err = np.full(len(sim.readings), np.nan)
    center_p90 = math.nan
    record: RunRecord | None = None
    for name in rows:
        if name == OCCLUDED:  # the evidence row's map, filtered
            assert record is not None
            assert record.method == "evidence"
            gmap = filter_map(record.global_map, MapFilter(occlusion_depth=OCCLUSION_DEPTH),
                              point_origins(record.global_map, sim.readings)).points
            run.near[name, 0.0] = np.full(len(truth.heard), np.nan)
        else:
            record = record_run(sim.readings, _make(name, config), truth.stops)
            gmap = record.global_map
            run.near[name, 0.0] = _found_while_near(record, truth)
        if name == "centerline":
            center_err[gmap.reading_id] = segment_distance(gmap.xy, sim.world.segments)[0]
            center_p90 = float(np.nanpercentile(center_err, 90.0))
        run.points[name] = map_row(sim, _process_result(record, gmap, len(sim.readings)),
                                   center_err, center_p90)
        run.found[name, 0.0] = _found(gmap.xy, truth)
        run.fates[name] = _fates(record, gmap, truth)


def _grid_found(grid: OccupancyMap, obstacles: Sequence[Obstacle], walls: np.ndarray
                ) -> np.ndarray:
    occupied = trinary(grid) == OCCUPIED
    h, origin = grid.resolution, (grid.bounds[0], grid.bounds[1])
    free_of_walls = ~dilate(wall_cells(walls, grid.shape, origin, h))
    near_occupied = dilate(occupied) & free_of_walls
    return np.array([bool((wall_cells(o.segments, grid.shape, origin, h)
                           & near_occupied).any()) for o in obstacles])


def _grids(sim: Simulation, base: World, obstacles: Sequence[Obstacle], truth: Truth,
           run: Run) -> None:
    xmin, ymin, xmax, ymax = sim.world.bounds
    bounds = (xmin - MARGIN, ymin - MARGIN, xmax + MARGIN, ymax + MARGIN)
    reflections = sim.truth.reflection[sim.truth.kind == EchoKind.DIRECT]
    for h in RESOLUTIONS:
        for name, make in GRIDS.items():
            grid = make(h, bounds)
            done, seen = 0, np.zeros(len(obstacles), dtype=bool)
            for k, stop in enumerate(truth.stops):
                grid.add_many(sim.readings[done:int(stop)])
                done = int(stop)
                seen |= _grid_found(grid, obstacles, base.segments) & truth.near[k]
            grid.add_many(sim.readings[done:])
            m = grid_measures(grid, sim.world.segments, reflections, sim.world.bounds)
            run.grids[name, h] = {"precision": m.precision, "recall": m.recall}
            run.found[name, h] = _grid_found(grid, obstacles, base.segments)
            run.near[name, h] = seen


def measure(sim: Simulation, base: World, obstacles: Sequence[Obstacle],
            with_grids: bool = True, rows: Sequence[str] = POINT_ROWS) -> Run:
    """Every measure of the module docstring for one simulation of the cluttered world (the
    point maps of ``rows``)."""
    truth = _truth(sim, base, obstacles)
    run = Run(len(sim.readings), {}, {}, {}, {}, {}, truth)
    _point_maps(sim, truth, run, rows)
    if with_grids:
        _grids(sim, base, obstacles, truth, run)
    return run


def _simulate(world: World, seed: int, physics_name: str, robot: str = "scout2") -> Simulation:
    assert world.tour is not None
    return simulate(world, load_robot(robot), follow_waypoints(world.tour), seed,
                    physics=CLUTTER_PHYSICS[physics_name])


# -- tracing a loss ------------------------------------------------------------------------------

def saw_through(sim: Simulation, reading: int, point: np.ndarray, config: MethodConfig,
                within: int | None = None) -> np.ndarray:
    """The readings after ``reading``, within ``within`` readings of it (default one
    history), whose freespace (beam and range minus the tolerance ε, eq. 3.2) contains
    ``point``: beams that passed over it."""
    r = sim.readings
    within = config.history_size if within is None else within
    j = np.arange(reading + 1, min(len(r), reading + within))
    bearing = np.arctan2(point[1] - r.y[j], point[0] - r.x[j])
    off = np.abs((bearing - r.theta[j] + math.pi) % (2 * math.pi) - math.pi)
    inside = (off <= r.beam_width[j] / 2) & (
        np.hypot(point[0] - r.x[j], point[1] - r.y[j]) < r.range[j] - config.range_tolerance)
    return np.asarray(j[inside])


def carved_by(sim: Simulation, reading: int, config: MethodConfig) -> tuple[int, int]:
    """Replay paper carving (eq. 3.5) of ``reading``'s arc by the newer readings of its
    history: the first one that fully carves or splits it and the fate, or (-1, ALIVE)."""
    r = sim.readings
    half = r.beam_width[reading] / 2
    lo, hi = r.theta[reading] - half, r.theta[reading] + half
    for j in range(reading + 1, min(len(r), reading + config.history_size)):
        fate, lo, hi = carve_arc(r.x[reading], r.y[reading], r.range[reading], lo, hi, r.x[j],
                                 r.y[j], r.range[j], r.theta[j] - r.beam_width[j] / 2,
                                 r.theta[j] + r.beam_width[j] / 2, config.range_tolerance,
                                 config.max_incidence)
        if fate in (ArcFate.FULLY_CARVED, ArcFate.SPLIT):
            return j, fate
    return -1, int(ArcFate.ALIVE)


def _echo_line(sim: Simulation, truth: Truth, j: int) -> str:
    kind = EchoKind(int(sim.truth.kind[j])).label
    if truth.source[j] >= 0:
        kind += f" from {truth.types[truth.source[j]]} #{truth.source[j]}"
    elif truth.source[j] == -1:
        kind += " from a wall"
    return f"reading {j} (range {sim.readings.range[j]:.2f} m, {kind})"


def trace_losses(sim: Simulation, run: Run, obstacles: Sequence[Obstacle],
                 methods: Sequence[str] = ("carve", "evidence")) -> None:
    """Print, for each heard leg or column a method lost (no point at the end), what became
    of each of its direct echoes: the point's distance to it, or the rule that removed it
    (for paper carving, the reading that fully carved or split the arc, replayed), and how
    many newer readings of the history passed over the obstacle's centre."""
    config, truth = MethodConfig(), run.truth
    for name in methods:
        lost = np.flatnonzero(truth.heard & ~run.found[name, 0.0]
                              & ~np.isin(truth.types, ("box",)))
        print(f"\n{name}: {len(lost)} heard legs and columns lost")
        for k in lost:
            center = np.asarray(obstacles[int(k)].outline.center)
            echoes = np.flatnonzero(truth.source == k)
            print(f"- {truth.types[k]} #{k} at ({center[0]:.2f}, {center[1]:.2f}), "
                  f"{len(echoes)} direct echoes:")
            for i in echoes:
                fate = FATES[run.fates[name][i]]
                over = saw_through(sim, int(i), center, config)
                line = f"  {_echo_line(sim, truth, int(i))}: {fate}"
                if name == "carve" and fate in ("fully carved", "split"):
                    j, _ = carved_by(sim, int(i), config)
                    line += f" by {_echo_line(sim, truth, j)}"
                if truth.outside[i]:
                    line += " (from outside the declared beam)"
                if name == "evidence":  # with one part off, when --diagnose ran those rows
                    line += "".join(f"; {other}: {FATES[run.fates[other][i]]}"
                                    for other in DIAGNOSTIC_ROWS if other in run.fates)
                print(f"{line}; {len(over)} newer readings passed over its centre")


# -- tables --------------------------------------------------------------------------------------

def _nanmean(values: Sequence[float]) -> float:
    """Mean of the values that are not NaN; NaN when none is (no echo of that kind)."""
    kept = [v for v in values if not math.isnan(v)]
    return float(np.mean(kept)) if kept else math.nan


def _pct(value: float) -> str:
    return "–" if math.isnan(value) else f"{value:.1f}"


def _points_table(runs: Sequence[Run]) -> None:
    print("\n| method | direct kept (%) | crosstalk removed (%) | floor removed (%) | "
          "multipath removed (%) | spurious removed (%) | median / centerline's | "
          "p90 / centerline's |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for name in runs[0].points:
        m = {c: _nanmean([run.points[name][c] for run in runs])
             for c in ("direct_kept", *[k.label for k in KINDS], "spurious", "median_ratio",
                       "p90_ratio")}
        kinds = " | ".join(_pct(m[k.label]) for k in KINDS)
        print(f"| {name} | {m['direct_kept']:.1f} | {kinds} | {m['spurious']:.1f} | "
              f"{m['median_ratio']:.2f} | {m['p90_ratio']:.2f} |")


def _share(runs: Sequence[Run], key: MapKey, kind: str, when: str) -> str:
    """Found share of the heard obstacles of ``kind`` over all runs, "a of b"."""
    hits = heard = 0
    for run in runs:
        table = run.found if when == "end" else run.near
        mask = run.truth.heard & (run.truth.types == kind)
        values = table[key][mask]
        if np.isnan(values.astype(float)).any():
            return "–"
        hits += int(np.count_nonzero(values))
        heard += int(np.count_nonzero(mask))
    return f"{100 * hits / heard:.0f} ({hits}/{heard})" if heard else "–"


def _map_label(key: MapKey) -> str:
    name, h = key
    return name if h == 0.0 else f"{name} {h:.2f} m"


def _found_table(runs: Sequence[Run]) -> None:
    head = " | ".join(f"{t}: end, while near" for t in TYPES)
    print(f"\n| map | {head} |")
    print("|---|" + "---|" * len(TYPES))
    for key in runs[0].found:
        cells = [f"{_share(runs, key, t, 'end')}, {_share(runs, key, t, 'near')}"
                 for t in TYPES]
        print(f"| {_map_label(key)} | " + " | ".join(cells) + " |")


def _grids_table(runs: Sequence[Run]) -> None:
    print("\n| resolution (m) | grid | precision | recall |")
    print("|---:|---|---:|---:|")
    for h in RESOLUTIONS:
        for name in GRIDS:
            rows = [run.grids[name, h] for run in runs]
            print(f"| {h:.2f} | {name} | "
                  f"{float(np.nanmean([r['precision'] for r in rows])):.3f} | "
                  f"{float(np.nanmean([r['recall'] for r in rows])):.3f} |")


def _fates_table(runs: Sequence[Run]) -> None:
    groups = {"walls": ("wall",), "legs": ("table leg", "chair leg"),
              "columns": ("column 10 cm", "column 20 cm"), "boxes": ("box",)}
    print("\n| method | echoes from | direct echoes | from outside the declared beam (%) | "
          + " | ".join(f"{f} (%)" for f in FATES) + " |")
    print("|---|---|---:|---:|" + "---:|" * len(FATES))
    for name in runs[0].fates:
        for group, types in groups.items():
            counts, outside = np.zeros(len(FATES)), 0
            for run in runs:
                t = run.truth
                kind = np.where(t.source >= 0, t.types[np.maximum(t.source, 0)], "wall")
                sel = np.isin(kind, types) & (t.source >= -1)
                counts += np.bincount(run.fates[name][sel], minlength=len(FATES))
                outside += int(np.count_nonzero(t.outside[sel]))
            total = counts.sum()
            shares = " | ".join(f"{100 * c / total:.1f}" for c in counts)
            print(f"| {name} | {group} | {total:,.0f} | {100 * outside / total:.1f} | {shares} |")


def _heard_table(runs: Sequence[Run], obstacles: Sequence[Obstacle]) -> None:
    print("\n| obstacle | placed | heard (mean over seeds) | direct echoes per heard one, "
          "median | beams over its centre in the whole run, mean per obstacle |")
    print("|---|---:|---:|---:|---:|")
    for kind in TYPES:
        heard, echoes, over = [], [], []
        for run in runs:
            t = run.truth
            mine = np.flatnonzero(t.types == kind)
            heard.append(np.count_nonzero(t.heard[mine]))
            echoes += [int(np.count_nonzero(t.source == k)) for k in mine if t.heard[k]]
            over += t.passed_over[mine].tolist()
        print(f"| {kind} | {sum(o.type == kind for o in obstacles)} | {np.mean(heard):.1f} | "
              f"{np.median(echoes):.0f} | {np.mean(over):.1f} |")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..n-1")
    parser.add_argument("--physics", nargs="+", default=["specular", "amplitude"],
                        choices=list(CLUTTER_PHYSICS),
                        help="sensor models (default: the two shipped ones); amplitude-thin: "
                             "amplitude with small reflectors, legs and columns as cylinders")
    parser.add_argument("--skip-grids", action="store_true")
    parser.add_argument("--robot", default="scout2",
                        help="the sonars (a built-in robot or a robot YAML), as heldout.py: "
                             "p3dx-front (8 front sonars, 15° beams) or p3dx (its 16)")
    parser.add_argument("--diagnose", action="store_true",
                        help="add point rows: evidence carving without its occlusion rule, and "
                             "without its confidence filter (which part loses the legs)")
    parser.add_argument("--trace", action="store_true",
                        help="also print, for seed 0, what became of the echoes of every heard "
                             "leg and column carve and evidence lost")
    parser.add_argument("--write-world", action="store_true",
                        help=f"only write the cluttered world to {WORLD_FILE.name} and stop")
    args = parser.parse_args(argv)
    base, world, obstacles = cluttered_world()
    if args.write_world:
        WORLD_FILE.parent.mkdir(exist_ok=True)
        write_world_json(world, WORLD_FILE)
        print(f"wrote {WORLD_FILE}")
        return 0
    command = "nice .venv/bin/python benchmarks/clutter.py " + shlex.join(
        argv if argv is not None else sys.argv[1:])
    print(f"`{command.strip()}`\n\n{world.description}")
    for physics_name in args.physics:
        runs = []
        for seed in range(args.seeds):
            sim = _simulate(world, seed, physics_name, args.robot)
            rows = (*POINT_ROWS, *DIAGNOSTIC_ROWS) if args.diagnose else POINT_ROWS
            runs.append(measure(sim, base, obstacles, not args.skip_grids, rows))
            print(f"  {physics_name}, seed {seed}: {len(sim.readings):,} readings", flush=True)
            if args.trace and seed == 0:
                trace_losses(sim, runs[-1], obstacles)
        where = f"{world.name}, {args.robot}; seeds 0-{args.seeds - 1}; physics: {physics_name}"
        print(f"\nobstacles heard, {where}")
        _heard_table(runs, obstacles)
        print(f"\npoints, {where}; mean over seeds")
        _points_table(runs)
        print(f"\nobstacles found, {where}: % of the heard ones (found/heard, summed over "
              "seeds), at the end of the run and while the robot was within 2 m")
        _found_table(runs)
        if not args.skip_grids:
            print(f"\ngrids, {where}; mean over seeds")
            _grids_table(runs)
        print(f"\nfate of the direct echoes, {where}; summed over seeds")
        _fates_table(runs)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
