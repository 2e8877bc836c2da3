"""The demo: one simulated tour, every method over the same readings, a table and three figures.

:func:`run_demo` simulates the built-in tour of a world with a Scout2-like sonar ring, runs
centerline, ATM, arc carving and the combined method over the same readings, and measures each
against the ground truth the simulator knows:

* how much of the history is still unprocessed (the paper's Table I, section 5-B; arcs carving
  removed count as processed, see :func:`~sonarcarve.lab.instrument.unprocessed_percent`),
* how far the global map's points lie from the true walls (median and 90th percentile),
* which readings carving removed, split by what really produced them (direct echoes against
  crosstalk, floor and multipath echoes; section 3 and 5-C),
* whether each door the tour approaches is open in the local map 1.5 m of driving before it
  (the paper's Fig. 2).

:func:`write_demo_outputs` turns a :class:`DemoResult` into ``summary.md``, ``summary.json`` and
three PNG figures, all rendered in memory first and then written atomically, so a failure never
leaves half an output folder. Nothing here prints; the CLI (``sonarcarve demo``) does.
"""

from __future__ import annotations

import io
import json
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from sonarcarve.errors import SonarcarveError
from sonarcarve.io.atomic import atomic_path, make_output_dir
from sonarcarve.lab import metrics
from sonarcarve.lab.analyses import GAP_DEPTH, passage_clearance, removal_summary
from sonarcarve.lab.analyses import METHOD_LABELS as EXPERIMENT_LABELS
from sonarcarve.lab.drawing import METHOD_COLORS as EXPERIMENT_COLORS
from sonarcarve.lab.instrument import (
    ArcTable,
    RunRecord,
    full_history_samples,
    record_run,
    unprocessed_percent,
)
from sonarcarve.lab.output import json_ready
from sonarcarve.lab.scenarios import cut_polyline
from sonarcarve.maps import GlobalMap
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.robot import load_robot
from sonarcarve.sim.motion import Trajectory, follow_waypoints
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.world import World, WorldError, load_world
from sonarcarve.typing import FloatArray

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "APPROACH_DISTANCE",
    "DEMO_METHODS",
    "FIGURE_FILES",
    "FIGURE_TEXT",
    "METHOD_COLORS",
    "METHOD_LABELS",
    "TABLE_COLUMNS",
    "DemoError",
    "DemoResult",
    "DoorApproach",
    "LocalView",
    "MethodSummary",
    "caption",
    "check_output_dir",
    "demo_config",
    "load_demo_world",
    "run_demo",
    "summary_json",
    "summary_markdown",
    "table_rows",
    "write_demo_outputs",
]


#: The methods of the demo (CLI names), in table order: the baseline first, the paper's last.
DEMO_METHODS = ("centerline", "atm", "carve", "combined")
#: Row labels of the table and legends.
METHOD_LABELS = {"centerline": "centerline", "atm": "ATM", "carve": "carving",
                 "combined": "combined"}
#: One colour per method: the colour of the point source it stands for (``SOURCE_COLORS``);
#: combined, which mixes carved and ATM points, in purple (as in the experiments' figures).
METHOD_COLORS = {name: EXPERIMENT_COLORS[label] for name, label in EXPERIMENT_LABELS.items()}
#: Methods shown in the doorway close-up (the brief of Fig. 2: centerline against carving).
CLOSEUP_METHODS = ("centerline", "carve", "combined")

#: How far before a door the close-up and the door counts look at the local map: metres of
#: driving before the tour passes through the door (or, for doors it does not pass through,
#: the straight-line distance from the robot to the middle of the gap).
APPROACH_DISTANCE = 1.5
#: Readings between two snapshots of the history for the unprocessed share (16 = one cycle of
#: the Scout2 ring, 0.64 s; the experiments use the same).
SAMPLE_EVERY = 16
#: A door not driven through counts as approached when it is within this angle of the robot's
#: heading (head-on), or of its side (passed by), radians.
_HEAD_ON = math.radians(45.0)
_AHEAD = math.radians(75.0)

#: Readings each method processes once, untimed, before its run (see :func:`run_demo`).
_WARM_UP = 64

#: Output files, in the order a reader should look at them.
FIGURE_FILES = {
    "global_maps": "fig1-global-maps.png",
    "map_zoom": "fig2-global-maps-zoom.png",
    "error_by_range": "fig3-error-vs-range.png",
    "door_closeup": "fig4-door-local-maps.png",
}
#: What each figure shows, in a few words (printed by the CLI, listed in ``summary.md``).
FIGURE_TEXT = {
    "global_maps": "each method's final map over the true walls",
    "map_zoom": "a close-up of those maps (dashed box of fig. 1)",
    "error_by_range": "map error against the range of the reading",
    "door_closeup": "the robot's local maps just before a door",
}
#: Size of the zoomed window of :func:`plot_map_zoom`, metres (at most the whole map).
ZOOM_SIZE = (16.0, 11.0)
SUMMARY_MD = "summary.md"
SUMMARY_JSON = "summary.json"

ProgressCallback = Callable[[str, int, int], None]


class DemoError(SonarcarveError):
    """A demo request that cannot run: bad option value, world without a tour, bad output path."""


# ============================================================================ results


@dataclass(frozen=True)
class MethodSummary:
    """One row of the demo table: one method over the whole tour.

    Attributes
    ----------
    method : str
        CLI name (``centerline``, ``atm``, ``carve``, ``combined``).
    readings : int
        Readings the method processed.
    unprocessed_pct : float
        Mean share of the history not yet processed, percent (Table I): over snapshots every
        :data:`SAMPLE_EVERY` readings once the history is full (all snapshots if it never is).
        Arcs carving removed stay in the history and count as processed (the library's
        measure); the paper's history drops them.
    median_error_m, p90_error_m : float
        Median and 90th percentile distance of the global map's points to the true walls, m.
    fully_carved_pct : float
        Share of all readings whose arc carving emptied completely, percent (section 5-C).
    spurious_removed_pct : float
        Of the spurious readings (crosstalk, floor and multipath echoes), the share the method
        left out of its map (fully carved, or split and dropped), percent; NaN if there were no
        spurious readings.
    true_lost_pct : float
        Of the direct readings (true echoes off a wall), the share left out the same way,
        percent; NaN if there were none.
    map_points : int
        Points in the global map.
    seconds : float
        Time spent inside the method (snapshots excluded), seconds.
    """

    method: str
    readings: int
    unprocessed_pct: float
    median_error_m: float
    p90_error_m: float
    fully_carved_pct: float
    spurious_removed_pct: float
    true_lost_pct: float
    map_points: int
    seconds: float

    @property
    def label(self) -> str:
        """The method's display name."""
        return METHOD_LABELS.get(self.method, self.method)

    @property
    def readings_per_second(self) -> float:
        """Throughput of the method on this tour."""
        return self.readings / self.seconds if self.seconds > 0.0 else math.inf

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (NaN and inf become None)."""
        row: dict[str, Any] = {"method": self.method, "label": self.label}
        for name in ("readings", "unprocessed_pct", "median_error_m", "p90_error_m",
                     "fully_carved_pct", "spurious_removed_pct", "true_lost_pct", "map_points",
                     "seconds", "readings_per_second"):
            row[name] = json_ready(getattr(self, name))
        return row


@dataclass(frozen=True, eq=False)
class LocalView:
    """The local maps of several methods at one moment of the tour.

    Attributes
    ----------
    readings : int
        Readings added when the maps were taken (the maps show the history after reading
        ``readings - 1``).
    t : float
        Time of that reading, seconds.
    robot : tuple of float
        ``(x, y, heading)`` of the robot then, metres and radians.
    maps : dict of str to ArcTable
        Method -> its local map: the surviving arcs of its history (``alive`` rows only).
    """

    readings: int
    t: float
    robot: tuple[float, float, float]
    maps: dict[str, ArcTable]


@dataclass(frozen=True, eq=False)
class DoorApproach:
    """A door the tour approaches, and whether each method's local map showed it open.

    Attributes
    ----------
    opening : int
        Index of the door in ``world.openings``.
    jambs : ndarray, shape (2, 2)
        The door's two jambs (wall ends), metres.
    how : str
        ``through`` (the tour drives through it), ``head-on`` (drives towards it, within 45°
        of its heading) or ``side`` (passes it, within 75°).
    view : LocalView
        Every method's local map at the moment.
    free_width : dict of str to float
        Method -> widest stretch of the gap with no map point within ``GAP_DEPTH`` of the gap
        line, metres (:func:`~sonarcarve.lab.metrics.free_width`).
    passable : dict of str to bool
        Method -> free width at least
        :func:`~sonarcarve.lab.analyses.passage_clearance` (the robot's diameter plus a
        margin).
    """

    opening: int
    jambs: FloatArray
    how: str
    view: LocalView
    free_width: dict[str, float]
    passable: dict[str, bool]

    @property
    def distance(self) -> float:
        """Straight-line distance from the robot to the middle of the gap then, metres."""
        centre = self.jambs.mean(axis=0)
        return float(math.hypot(centre[0] - self.view.robot[0], centre[1] - self.view.robot[1]))


@dataclass(frozen=True, eq=False)
class DemoResult:
    """Everything :func:`run_demo` measured, ready for the table and the figures.

    Attributes
    ----------
    world : World
        The simulated world.
    seed : int
        Simulation seed.
    config : MethodConfig
        The methods' parameters.
    simulation : Simulation
        The readings and their ground truth.
    methods : tuple of MethodSummary
        One row per method, in :data:`DEMO_METHODS` order.
    global_maps : dict of str to GlobalMap
        Method -> its global map.
    map_errors : dict of str to ndarray
        Method -> distance of each global map point to the true walls, metres, shape (points,).
    doors : tuple of DoorApproach
        Every door the tour approaches, in tour order.
    closeup : DoorApproach or None
        The door shown in the close-up figure (None when the tour approaches none).
    fallback_view : LocalView or None
        Local maps at mid-tour, for the close-up when there is no door.
    seconds : dict of str to float
        Wall time per step (``simulate``, each method incl. its snapshots, ``measure``).
    """

    world: World
    seed: int
    config: MethodConfig
    simulation: Simulation
    methods: tuple[MethodSummary, ...]
    global_maps: dict[str, GlobalMap]
    map_errors: dict[str, FloatArray]
    doors: tuple[DoorApproach, ...]
    closeup: DoorApproach | None
    fallback_view: LocalView | None
    seconds: dict[str, float]

    def summary(self, method: str) -> MethodSummary:
        """The table row of ``method``."""
        for row in self.methods:
            if row.method == method:
                return row
        msg = f"no method {method!r} in this demo"
        raise KeyError(msg)


# ============================================================================ running


def run_demo(
    world: str | World = "office",
    seed: int = 0,
    *,
    history_size: int = 250,
    robot: str = "scout2",
    max_length: float | None = None,
    methods: tuple[str, ...] = DEMO_METHODS,
    on_progress: ProgressCallback | None = None,
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
    on_progress : callable, optional
        ``on_progress(step, done, total)``: ``step`` is ``simulate`` (firings) or a method name
        (readings).

    Returns
    -------
    DemoResult

    Raises
    ------
    WorldError
        Unknown or unreadable world, or a world without a tour.
    DemoError
        Bad ``history_size``, ``max_length`` or method name.
    """
    config = demo_config(history_size, methods, max_length)
    the_world = load_demo_world(world)
    the_robot = load_robot(robot)
    seconds: dict[str, float] = {}

    tic = time.perf_counter()
    tour = the_world.tour
    assert tour is not None  # load_demo_world checked it
    trajectory = follow_waypoints(cut_polyline(tour, max_length))
    sim = simulate(the_world, the_robot, trajectory, seed, on_progress=(
        None if on_progress is None else lambda done, total: on_progress("simulate", done, total)))
    seconds["simulate"] = time.perf_counter() - tic
    if len(sim.readings) == 0:
        msg = f"the tour of {the_world.name!r} produced no sonar readings"
        raise DemoError(msg)

    n = len(sim.readings)
    candidates = _door_candidates(sim)
    mid = max(1, n // 2)
    stops = np.concatenate((np.arange(SAMPLE_EVERY, n + 1, SAMPLE_EVERY),
                            [c.readings for c in candidates], [mid])).astype(np.int64)
    records: dict[str, RunRecord] = {}
    for name in methods:
        tic = time.perf_counter()
        # Load (or compile) the method's numba kernels on a few readings first, so that the
        # readings-per-second column measures processing, not one-off start-up.
        make_method(name, config).add_many(sim.readings[:_WARM_UP])
        records[name] = record_run(sim.readings, make_method(name, config), stops, on_progress=(
            None if on_progress is None else _reporter(on_progress, name, n)))
        seconds[name] = time.perf_counter() - tic

    tic = time.perf_counter()
    errors = {name: metrics.segment_distance(rec.global_map.xy, the_world.segments)[0]
              for name, rec in records.items()}
    doors = tuple(_measure_door(sim, records, c) for c in candidates)
    rows = tuple(_summarise(sim, records[name], errors[name], history_size)
                 for name in methods)
    closeup = _pick_closeup(doors)
    fallback = None if closeup is not None else _view(sim, records, mid)
    seconds["measure"] = time.perf_counter() - tic
    return DemoResult(
        world=the_world, seed=seed, config=config, simulation=sim, methods=rows,
        global_maps={name: rec.global_map for name, rec in records.items()},
        map_errors=errors, doors=doors, closeup=closeup, fallback_view=fallback,
        seconds=seconds,
    )


def _reporter(callback: ProgressCallback, step: str, total: int) -> Callable[[int], None]:
    """``done -> callback(step, done, total)`` (record_run reports readings done only)."""
    def report(done: int) -> None:
        callback(step, done, total)
    return report


def load_demo_world(world: str | World) -> World:
    """The world of a demo: loaded (:func:`~sonarcarve.sim.world.load_world`) and with a tour.

    Raises
    ------
    WorldError
        Unknown or unreadable world, or one without a tour.
    """
    the_world = world if isinstance(world, World) else load_world(world)
    if the_world.tour is None:
        msg = f"world {the_world.name!r} has no tour to drive; the demo needs one"
        raise WorldError(msg)
    return the_world


def demo_config(history_size: int = 250, methods: tuple[str, ...] = DEMO_METHODS,
                max_length: float | None = None) -> MethodConfig:
    """The methods' parameters of a demo, after checking the options.

    Raises
    ------
    DemoError
        ``history_size`` below 1, an unknown method, or a ``max_length`` that is not > 0.
    """
    if history_size < 1:
        msg = f"--history must be at least 1, got {history_size}"
        raise DemoError(msg)
    unknown = [m for m in methods if m not in DEMO_METHODS]
    if unknown or not methods:
        msg = f"unknown demo method(s) {unknown}; choose from {', '.join(DEMO_METHODS)}"
        raise DemoError(msg)
    if max_length is not None and not (math.isfinite(max_length) and max_length > 0.0):
        msg = f"max_length must be a positive number of metres, got {max_length}"
        raise DemoError(msg)
    return MethodConfig(history_size=history_size)


def _summarise(sim: Simulation, record: RunRecord, err: FloatArray,
               capacity: int) -> MethodSummary:
    # Table I's measure over the regular snapshots only (the door moments would bias it).
    unprocessed = unprocessed_percent(full_history_samples(record, capacity, every=SAMPLE_EVERY))
    removal = removal_summary(record.final, sim.truth.kind)
    summary = metrics.error_summary(err)
    return MethodSummary(
        method=record.method,
        readings=len(sim.readings),
        unprocessed_pct=unprocessed,
        median_error_m=summary.median,
        p90_error_m=summary.p90,
        fully_carved_pct=removal["share"],
        spurious_removed_pct=removal["spurious_removed_or_split"],
        true_lost_pct=removal["true_lost_or_split"],
        map_points=len(record.global_map),
        seconds=record.seconds,
    )


# ============================================================================ doors


@dataclass(frozen=True)
class _Candidate:
    opening: int
    readings: int
    how: str


def _door_candidates(sim: Simulation) -> list[_Candidate]:
    """The doors the tour approaches and the reading count at which to look at each.

    A door the tour drives through is looked at :data:`APPROACH_DISTANCE` metres of driving
    before the crossing; one it does not drive through, when the robot first comes within that
    straight-line distance of the gap's middle with the gap ahead (within 75° of the heading)
    and in sight (no wall in between).
    """
    world, traj = sim.world, sim.trajectory
    t = sim.readings.t
    n = len(t)
    x, y, heading = traj.pose_at(t)
    travelled = traj.distance_at(t)
    found: list[_Candidate] = []
    for k, (a, b) in enumerate(world.openings):
        crossing = _first_crossing(traj, a, b)
        if crossing is not None:
            goal = float(traj.distance_at(crossing)) - APPROACH_DISTANCE
            before = np.flatnonzero(travelled <= goal)
            if before.size:
                found.append(_Candidate(k, int(before[-1]) + 1, "through"))
                continue
        centre = 0.5 * (a + b)
        dx, dy = centre[0] - x, centre[1] - y
        dist = np.hypot(dx, dy)
        off = np.abs((np.arctan2(dy, dx) - heading + math.pi) % (2.0 * math.pi) - math.pi)
        near = np.flatnonzero((dist <= APPROACH_DISTANCE) & (off <= _AHEAD))
        near = near[near < n]
        if not near.size:
            continue
        i = int(near[0])
        hit, _ = world.cast_rays([x[i], y[i]], [math.atan2(dy[i], dx[i])], float(dist[i]))
        if np.isfinite(hit[0]):
            continue  # a wall between the robot and the door
        found.append(_Candidate(k, i + 1, "head-on" if off[i] <= _HEAD_ON else "side"))
    found.sort(key=lambda c: c.readings)
    return found


def _first_crossing(traj: Trajectory, a: FloatArray, b: FloatArray) -> float | None:
    """Time the robot's centre first crosses the segment ``a``-``b``, or None."""
    p = np.column_stack((traj.x, traj.y))
    u = b - a
    side = u[0] * (p[:, 1] - a[1]) - u[1] * (p[:, 0] - a[0])
    change = np.flatnonzero(np.sign(side[:-1]) * np.sign(side[1:]) < 0)
    for i in change.tolist():
        share = side[i] / (side[i] - side[i + 1])
        q = p[i] + share * (p[i + 1] - p[i])
        along = float(np.dot(q - a, u) / np.dot(u, u))
        if 0.0 <= along <= 1.0:
            return float(traj.t[i] + share * (traj.t[i + 1] - traj.t[i]))
    return None


def _view(sim: Simulation, records: Mapping[str, RunRecord], readings: int) -> LocalView:
    """Every method's local map once ``readings`` readings have been added."""
    t = float(sim.readings.t[readings - 1])
    x, y, h = sim.trajectory.pose_at(t)
    maps = {name: rec.local_map(int(np.searchsorted(rec.sample_readings, readings)))
            for name, rec in records.items()}
    return LocalView(readings, t, (float(x), float(y), float(h)), maps)


def _measure_door(sim: Simulation, records: Mapping[str, RunRecord],
                  candidate: _Candidate) -> DoorApproach:
    jambs = np.asarray(sim.world.openings[candidate.opening], dtype=np.float64)
    region = metrics.gap_region(jambs[0], jambs[1], GAP_DEPTH)
    clearance = passage_clearance(sim.robot.robot_radius)
    view = _view(sim, records, candidate.readings)
    free = {name: metrics.free_width(local.xy, region) for name, local in view.maps.items()}
    return DoorApproach(candidate.opening, jambs, candidate.how, view, free,
                        {name: width >= clearance for name, width in free.items()})


def _pick_closeup(doors: tuple[DoorApproach, ...]) -> DoorApproach | None:
    """The door the close-up shows.

    Doors the tour drives through come first, then doors it heads at, then doors it passes;
    within a group, the door where carving's or combined's local map leaves the most more of
    the gap free than centerline's (the example that shows the difference best; every door's
    numbers are in ``summary.json``), then the earliest.
    """
    if not doors:
        return None
    tier = {"through": 0, "head-on": 1, "side": 2}

    def gain(d: DoorApproach) -> float:
        best = max(d.free_width.get("carve", 0.0), d.free_width.get("combined", 0.0))
        return best - d.free_width.get("centerline", 0.0)

    return min(doors, key=lambda d: (tier.get(d.how, 3), -round(gain(d), 3), d.view.readings))


# ============================================================================ text


def _pct(value: float) -> str:
    return "–" if math.isnan(value) else f"{value:.1f}"


def _rate(value: float) -> str:
    if not math.isfinite(value):
        return "–"
    return f"{value / 1000.0:,.0f}k" if value >= 10_000.0 else f"{value:,.0f}"


def _cm(value: float) -> str:
    return "–" if math.isnan(value) else f"{100.0 * value:.1f}"


#: Table columns: (key, header as printed with line breaks, unit-free description).
TABLE_COLUMNS = (
    ("method", "method", "sonar processing method"),
    ("readings", "readings", "sonar readings processed"),
    ("unprocessed_pct", "unpro-\ncessed\n%",
     "mean share of the history not yet processed (arcs carving removed count as processed)"),
    ("median_error_m", "median\nerror\ncm", "median distance of map points to the true walls"),
    ("p90_error_m", "p90\nerror\ncm", "90th percentile of that distance"),
    ("fully_carved_pct", "fully\ncarved\n%", "readings whose whole arc was carved away"),
    ("spurious_removed_pct", "spurious\nremoved\n%",
     "of the spurious readings, share left out of the map"),
    ("true_lost_pct", "true\nlost\n%", "of the true wall echoes, share left out of the map"),
    ("map_points", "map\npoints", "points in the final map"),
    ("readings_per_second", "readings\nper s", "processing speed"),
)


def table_rows(result: DemoResult) -> tuple[list[str], list[list[str]]]:
    """Header (with line breaks) and cells of the demo table, as printed and in ``summary.md``."""
    header = [title for _, title, _ in TABLE_COLUMNS]
    rows = [[row.label, f"{row.readings:,}", _pct(row.unprocessed_pct), _cm(row.median_error_m),
             _cm(row.p90_error_m), _pct(row.fully_carved_pct), _pct(row.spurious_removed_pct),
             _pct(row.true_lost_pct), f"{row.map_points:,}", _rate(row.readings_per_second)]
            for row in result.methods]
    return header, rows


def caption(result: DemoResult) -> str:
    """How to read the table, in plain words, with this run's numbers (one paragraph)."""
    sim = result.simulation
    kinds = sim.kind_counts()
    spurious = sum(v for k, v in kinds.items() if k != "direct")
    parts = [
        f"How to read: every method mapped the same {len(sim.readings):,} readings "
        f"({spurious:,} of them spurious echoes) of a {sim.trajectory.path_length:.0f} m "
        f"simulated tour of '{result.world.name}'. Error is the distance from a map point to "
        "the true walls; unprocessed is the share of the history still waiting for a later "
        "reading to refine it (latency). Lower is better for both."
    ]
    names = {row.method for row in result.methods}
    if "centerline" in names:
        base = result.summary("centerline")
        for method, name in (("carve", "Carving"), ("atm", "ATM"), ("combined", "Combined")):
            if method in names:
                parts.append(_compare(name, result.summary(method), base))
    carve = result.summary("carve") if "carve" in names else None
    if carve is not None and math.isfinite(carve.spurious_removed_pct + carve.true_lost_pct):
        parts.append(f"Carving left out {carve.spurious_removed_pct:.0f}% of the spurious "
                     f"readings, but also {carve.true_lost_pct:.0f}% of the true ones.")
    return " ".join(parts)


def _compare(name: str, row: MethodSummary, base: MethodSummary) -> str:
    """"Carving: points 2.0x closer to the walls than centerline (...), 22% unprocessed."."""
    ratio = base.median_error_m / row.median_error_m if row.median_error_m > 0.0 else math.nan
    if not math.isfinite(ratio):
        how = "no points to compare"
    elif ratio >= 1.05:
        how = f"points {ratio:.1f}x closer to the walls than centerline's"
    elif ratio <= 1.0 / 1.05:
        how = f"points {1.0 / ratio:.1f}x FARTHER from the walls than centerline's"
    else:
        how = "points as close to the walls as centerline's"
    return (f"{name}: {how} (median {_cm(row.median_error_m)} against "
            f"{_cm(base.median_error_m)} cm), {row.unprocessed_pct:.0f}% of the history "
            "unprocessed.")


def summary_markdown(result: DemoResult) -> str:
    """``summary.md``: the table, its caption, the figures and how the run was made."""
    sim = result.simulation
    header, rows = table_rows(result)
    header = [title.replace("-\n", "").replace("\n", " ") for title in header]
    lines = [f"# sonarcarve demo: {result.world.name}, seed {result.seed}", ""]
    lines.append("| " + " | ".join(header) + " |")
    lines.append("|" + "|".join(["---"] + ["---:"] * (len(header) - 1)) + "|")
    lines += ["| " + " | ".join(cells) + " |" for cells in rows]
    lines += ["", caption(result), "", "Columns:", ""]
    lines += [f"- {title.replace('-' + chr(10), '').replace(chr(10), ' ')}: {text}"
              for _, title, text in TABLE_COLUMNS[1:]]
    lines += ["", "## Figures", ""]
    for key, name in FIGURE_FILES.items():
        lines.append(f"- [{name}]({name}): {FIGURE_TEXT[key]}")
    lines += ["", "## Run", "",
              f"- world: {result.world.name}; seed {result.seed}; history "
              f"{result.config.history_size} arcs; tour {sim.trajectory.path_length:.0f} m in "
              f"{sim.trajectory.duration:.0f} s",
              f"- robot: {sim.robot.name}; readings per kind: "
              + ", ".join(f"{k} {v:,}" for k, v in sim.kind_counts().items()),
              "- seconds: " + ", ".join(f"{k} {v:.2f}" for k, v in result.seconds.items()), ""]
    return "\n".join(lines)


def summary_json(result: DemoResult) -> str:
    """``summary.json``: settings, one record per method, the doors, timings."""
    sim = result.simulation
    data: dict[str, Any] = {
        "world": result.world.name,
        "seed": result.seed,
        "robot": sim.robot.name,
        "history_size": result.config.history_size,
        "tour_m": sim.trajectory.path_length,
        "tour_s": sim.trajectory.duration,
        "readings": len(sim.readings),
        "readings_by_kind": sim.kind_counts(),
        "methods": [row.as_dict() for row in result.methods],
        "approach_distance_m": APPROACH_DISTANCE,
        "doors": [{"opening": d.opening, "how": d.how, "jambs": d.jambs.tolist(),
                   "readings": d.view.readings, "t": d.view.t,
                   "distance_m": d.distance,
                   "free_width_m": d.free_width, "passable": d.passable} for d in result.doors],
        "closeup_opening": None if result.closeup is None else result.closeup.opening,
        "caption": caption(result),
        "figures": list(FIGURE_FILES.values()),
        "seconds": result.seconds,
    }
    return json.dumps(json_ready(data), indent=2, allow_nan=False) + "\n"


# ============================================================================ outputs


def write_demo_outputs(result: DemoResult, out: str | Path) -> list[Path]:
    """Write the figures, ``summary.md`` and ``summary.json`` into ``out``.

    Everything is rendered in memory first; only then is ``out`` created (with its parents)
    and each file written atomically, so an error leaves no half-written output.

    Returns
    -------
    list of Path
        The files written, figures first.

    Raises
    ------
    DemoError
        ``out`` exists and is not a directory.
    """
    from sonarcarve.lab.demo_figures import (
        plot_door_closeup,
        plot_error_by_range,
        plot_global_maps,
        plot_map_zoom,
    )

    target = Path(out)
    check_output_dir(target)
    files: dict[str, bytes] = {
        FIGURE_FILES["global_maps"]: _png(plot_global_maps(result)),
        FIGURE_FILES["map_zoom"]: _png(plot_map_zoom(result)),
        FIGURE_FILES["error_by_range"]: _png(plot_error_by_range(result)),
        FIGURE_FILES["door_closeup"]: _png(plot_door_closeup(result)),
        SUMMARY_MD: summary_markdown(result).encode(),
        SUMMARY_JSON: summary_json(result).encode(),
    }
    make_output_dir(target)  # atomic_path creates no folders
    written = []
    for name, content in files.items():
        with atomic_path(target / name) as tmp:
            tmp.write_bytes(content)
        written.append(target / name)
    return written


def check_output_dir(out: Path) -> None:
    """Raise :class:`DemoError` if ``out`` (or an ancestor) exists and is not a directory."""
    for path in (out, *out.parents):
        if path.exists():
            if not path.is_dir():
                msg = f"--out {out}: {path} exists and is not a directory"
                raise DemoError(msg)
            return


def _png(fig: Figure) -> bytes:
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    try:
        fig.savefig(buffer, format="png", dpi=120)
    finally:
        plt.close(fig)
    return buffer.getvalue()
