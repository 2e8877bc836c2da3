"""Running the demo: simulate the tour, run every method over its readings, measure each.

:func:`run_demo` measures each method against the ground truth the simulator knows:

* how much of the history is still unprocessed (the paper's Table I, section 5-B; arcs carving
  removed count as processed, see :func:`~sonarcarve.lab.instrument.unprocessed_percent`),
* how far the global map's points lie from the true walls (median and 90th percentile),
* which readings each method left out of its map, split by what really produced them (direct
  echoes against crosstalk, floor and multipath echoes; section 3 and 5-C),
* whether each door the tour approaches is open in the local map 1.5 m of driving before it
  (the paper's Fig. 2; :mod:`~sonarcarve.lab.demo.doors`);

and builds the occupancy grids of the same readings, the carved grid beside ROS's range sensor
layer, measured against the true walls (:mod:`~sonarcarve.lab.demo.costmaps`).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from sonarcarve.filters import OCCLUSION_DEPTH, MapFilter, filter_map, point_origins
from sonarcarve.history import DEFAULT_HISTORY_SIZE
from sonarcarve.lab import metrics
from sonarcarve.lab.analyses import removal_summary
from sonarcarve.lab.demo.costmaps import run_grids
from sonarcarve.lab.demo.doors import (
    DoorCandidate,
    door_candidates,
    doors_tell_apart,
    local_view,
    measure_door,
    pick_closeup,
)
from sonarcarve.lab.demo.results import DemoResult, FilterSummary, MethodSummary
from sonarcarve.lab.demo.scenario import (
    CLOSEUP_METHODS,
    DEMO_METHODS,
    GRID_RESOLUTION,
    SAMPLE_EVERY,
    DemoError,
    ProgressCallback,
    demo_config,
    load_demo_world,
)
from sonarcarve.lab.instrument import (
    RunRecord,
    full_history_samples,
    record_run,
    unprocessed_percent,
)
from sonarcarve.lab.scenarios import cut_polyline
from sonarcarve.maps import GlobalMap
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.robot import RobotDescription, load_robot
from sonarcarve.sim.motion import follow_waypoints
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import EchoKind
from sonarcarve.sim.world import World
from sonarcarve.typing import FloatArray, IntArray

__all__ = ["run_demo"]

#: Readings beyond its history size each method processes once, untimed, before its run (see
#: :func:`run_demo`).
_WARM_UP = 64


#: The world whose door fig. 4 and the animation show when the tour's doors tell the methods
#: nothing apart: the paper's Fig. 2, a 0.85 m door driven at head-on.
DOOR_SCENE_WORLD = "doorway"


def run_demo(
    world: str | World = "office",
    seed: int = 0,
    *,
    history_size: int = DEFAULT_HISTORY_SIZE,
    robot: str = "scout2",
    max_length: float | None = None,
    methods: tuple[str, ...] = DEMO_METHODS,
    grid_resolution: float | None = GRID_RESOLUTION,
    on_progress: ProgressCallback | None = None,
    door_scene: bool = True,
) -> DemoResult:
    """Simulate a world's tour and map it with every method; measure each against the truth.

    Parameters
    ----------
    world : str or World
        A :func:`~sonarcarve.sim.world.load_world` spec (built-in name, ``random:SEED``, a
        ``.json`` or ROS ``.yaml`` file) or a world; it must have a tour.
    seed : int
        Simulation seed (noise and spurious echoes): same seed, same numbers.
    history_size : int
        Arcs kept in each method's history (paper: 250).
    robot : str
        Sonar ring (:func:`~sonarcarve.robot.load_robot`).
    max_length : float, optional
        Drive only the first ``max_length`` metres of the tour (default: all of it).
    methods : tuple of str
        Methods to run, CLI names; the table follows this order.
    grid_resolution : float or None
        Cell side of the carved grid and the range sensor layer built from the same readings,
        metres; None builds no grids.
    on_progress : callable, optional
        ``on_progress(step, done, total)``: ``step`` is ``simulate`` (firings), a method name,
        ``grid:KIND`` (readings) or ``door scene`` (0 or 1 of 1).
    door_scene : bool
        When the tour approaches doors and every method of fig. 4 leaves each one passable
        (:func:`~sonarcarve.lab.demo.doors.doors_tell_apart`; every 1 m door of the office
        tour), also drive at the doorway world's 0.85 m door (:data:`DOOR_SCENE_WORLD`, the
        paper's Fig. 2, about 170 readings) with fig. 4's methods, for fig. 4 and the animation
        (:attr:`DemoResult.door_scene`): a figure of three open doors shows nothing of what
        carving does. False: never.

    Returns
    -------
    DemoResult

    Raises
    ------
    WorldError
        Unknown or unreadable world, or a world without a tour.
    ConfigError
        Bad ``history_size`` (:func:`~sonarcarve.lab.demo.scenario.demo_config`).
    DemoError
        Bad ``max_length``, ``grid_resolution`` or method name.
    """
    config = demo_config(history_size, methods, max_length, grid_resolution)
    the_world = load_demo_world(world)
    the_robot = load_robot(robot)
    seconds: dict[str, float] = {}

    tic = time.perf_counter()
    sim = _simulate_tour(the_world, the_robot, seed, max_length, on_progress)
    seconds["simulate"] = time.perf_counter() - tic
    if len(sim.readings) == 0:
        msg = f"the tour of {the_world.name!r} produced no sonar readings"
        raise DemoError(msg)

    candidates = door_candidates(sim)
    mid = max(1, len(sim.readings) // 2)
    stops = _snapshot_stops(len(sim.readings), candidates, mid)
    records = _run_methods(sim, methods, config, stops, seconds, on_progress)

    tic = time.perf_counter()
    errors = {name: metrics.segment_distance(rec.global_map.xy, the_world.segments)[0]
              for name, rec in records.items()}
    doors = tuple(measure_door(sim, records, c) for c in candidates)
    rows = tuple(_summarise(sim, records[name], errors[name], history_size)
                 for name in methods)
    closeup = pick_closeup(doors)
    fallback = None if closeup is not None else local_view(sim, records, mid)
    seconds["measure"] = time.perf_counter() - tic
    grids = () if grid_resolution is None else run_grids(sim, grid_resolution, on_progress,
                                                         seconds)
    scene = None
    if door_scene and not doors_tell_apart(doors) and the_world.name != DOOR_SCENE_WORLD:
        scene = _door_scene(seed, history_size, robot, seconds, on_progress)
    return DemoResult(
        world=the_world, seed=seed, config=config, simulation=sim, methods=rows,
        global_maps={name: rec.global_map for name, rec in records.items()},
        map_errors=errors, doors=doors, closeup=closeup, fallback_view=fallback,
        grids=grids, seconds=seconds, door_scene=scene,
        occlusion=_occlusion(sim, records["evidence"]) if "evidence" in records else None,
    )


def _occlusion(sim: Simulation, record: RunRecord) -> FilterSummary:
    """``record``'s global map after the occlusion map filter: what it leaves out."""
    points = record.global_map
    kept = filter_map(points, MapFilter(occlusion_depth=OCCLUSION_DEPTH),
                      point_origins(points, sim.readings)).points
    spurious_removed, true_lost = _left_out(sim, kept)
    return FilterSummary(record.method, OCCLUSION_DEPTH, spurious_removed, true_lost, len(kept))


def _left_out(sim: Simulation, points: GlobalMap) -> tuple[float, float]:
    """Of the spurious and of the direct readings, the shares with no point in ``points``,
    percent: left out whatever the reason (fully carved or split, below the confidence a
    method keeps, a map filter), so read off the map itself."""
    kept = np.zeros(len(sim.readings), dtype=bool)
    kept[points.reading_id] = True
    direct = sim.truth.kind == EchoKind.DIRECT
    spurious = sim.truth.kind > EchoKind.DIRECT  # no-echo readings (NO_ECHO, -1) are neither
    return metrics.percent(~kept[spurious]), metrics.percent(~kept[direct])


def _door_scene(seed: int, history_size: int, robot: str, seconds: dict[str, float],
                on_progress: ProgressCallback | None) -> DemoResult | None:
    """The doorway world's approach with fig. 4's methods (``run_demo``'s ``door_scene``), or
    None when its door does not tell them apart either (a short ``history_size`` can leave it
    open in every map: a figure of three open doors again, and a wrong sentence under it)."""
    tic = time.perf_counter()
    if on_progress is not None:
        on_progress("door scene", 0, 1)
    scene = run_demo(DOOR_SCENE_WORLD, seed, history_size=history_size, robot=robot,
                     methods=CLOSEUP_METHODS, grid_resolution=None, door_scene=False)
    if on_progress is not None:
        on_progress("door scene", 1, 1)
    seconds["door scene"] = time.perf_counter() - tic
    return scene if scene.doors and doors_tell_apart(scene.doors) else None


def _simulate_tour(world: World, robot: RobotDescription, seed: int, max_length: float | None,
                   on_progress: ProgressCallback | None) -> Simulation:
    """The readings of ``robot`` driving the first ``max_length`` metres of the world's tour."""
    tour = world.tour
    assert tour is not None  # load_demo_world checked it
    trajectory = follow_waypoints(cut_polyline(tour, max_length))
    return simulate(world, robot, trajectory, seed, on_progress=(
        None if on_progress is None else lambda done, total: on_progress("simulate", done, total)))


def _snapshot_stops(n: int, candidates: list[DoorCandidate], mid: int) -> IntArray:
    """Reading counts at which to keep a copy of the history: every :data:`SAMPLE_EVERY`
    readings (the unprocessed share), at each door and at mid-tour (the close-up)."""
    return np.concatenate((np.arange(SAMPLE_EVERY, n + 1, SAMPLE_EVERY),
                           [c.readings for c in candidates], [mid])).astype(np.int64)


def _run_methods(sim: Simulation, methods: tuple[str, ...], config: MethodConfig,
                 stops: IntArray, seconds: dict[str, float],
                 on_progress: ProgressCallback | None) -> dict[str, RunRecord]:
    """Each method over all readings, its history kept at ``stops``; its wall time in
    ``seconds[method]``."""
    n = len(sim.readings)
    records: dict[str, RunRecord] = {}
    for name in methods:
        tic = time.perf_counter()
        # Load (or compile) the method's numba kernels on a few readings first, so that the
        # readings-per-second column measures processing, not one-off start-up: enough of them
        # to fill the history and push arcs out of it, then finish (both have kernels too).
        warm = make_method(name, config)
        warm.add_many(sim.readings[:config.history_size + _WARM_UP])
        warm.finish()
        records[name] = record_run(sim.readings, make_method(name, config), stops, on_progress=(
            None if on_progress is None else _reporter(on_progress, name, n)))
        seconds[name] = time.perf_counter() - tic
    return records


def _reporter(callback: ProgressCallback, step: str, total: int) -> Callable[[int], None]:
    """``done -> callback(step, done, total)`` (record_run reports readings done only)."""
    def report(done: int) -> None:
        callback(step, done, total)
    return report


def _summarise(sim: Simulation, record: RunRecord, err: FloatArray,
               capacity: int) -> MethodSummary:
    # Table I's measure over the regular snapshots only (the door moments would bias it).
    unprocessed = unprocessed_percent(full_history_samples(record, capacity, every=SAMPLE_EVERY))
    removal = removal_summary(record.final, sim.truth.kind)
    spurious_removed, true_lost = _left_out(sim, record.global_map)
    summary = metrics.error_summary(err)
    return MethodSummary(
        method=record.method,
        readings=len(sim.readings),
        unprocessed_pct=unprocessed,
        median_error_m=summary.median,
        p90_error_m=summary.p90,
        fully_carved_pct=removal["share"],
        spurious_removed_pct=spurious_removed,
        true_lost_pct=true_lost,
        map_points=len(record.global_map),
        seconds=record.seconds,
    )
