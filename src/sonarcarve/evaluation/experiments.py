"""The paper's experiments (section 5) regenerated on the simulator, and the ones it could not run.

Each experiment is a plan of *jobs* (one sonar method on one simulated log, then one analysis of
what it did, see :mod:`sonarcarve.evaluation.instrument`) and a summary of the jobs' outputs:

* ``office``: the paper's Table I, Fig. 10, 11, 12 and 13 and the fully carved share (section
  5-B, 5-C) on the simulated ``office`` tour, several seeds; plus what the paper could not
  measure without ground truth: the true error of every local map point and, per wall patch, how
  long after it came into view the local map had it right (latency against accuracy).
* ``t-junction``: Fig. 4, how far before the facing wall each method's local map first shows it.
* ``openings``: Fig. 2 and 9, whether each local map shows narrow doors and side openings
  passable when the robot is 1, 2 and 3 m away.
* ``sensitivity``: history length, range tolerance ε, beam width φ, minimum transversal angle ψ,
  speed and range noise against error, latency and the fully carved share.

Simulations are made once per distinct scenario and shared by every job that needs them (and
across parameters that do not change the simulation); jobs can run in worker processes.
"""

from __future__ import annotations

import math
import multiprocessing
import time
import warnings
from collections import defaultdict
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.errors import SonarcarveError
from sonarcarve.evaluation import metrics
from sonarcarve.evaluation.appendix import APPENDIX_EXPERIMENTS, experiment_summariser
from sonarcarve.evaluation.instrument import ArcTable, RunRecord, record_run, sample_points
from sonarcarve.maps import PointSource
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.methods.atm import atm_error_bound
from sonarcarve.methods.base import Removal
from sonarcarve.methods.carving import DEFAULT_RANGE_TOLERANCE
from sonarcarve.sim.motion import DEFAULT_SPEED
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import EchoKind, SonarPhysics
from sonarcarve.sim.world import World

__all__ = [
    "EXPERIMENTS",
    "METHOD_LABELS",
    "ExperimentError",
    "ExperimentResults",
    "Scenario",
    "Settings",
    "run_experiments",
    "run_simulation",
]

FloatArray = npt.NDArray[np.float64]
JsonDict = dict[str, Any]

#: Method CLI name -> the label used in results (the paper's names).
METHOD_LABELS = {"centerline": "centerline", "carve": "carving", "atm": "atm",
                 "combined": "combined"}
#: Every method, in the order tables list them.
ALL_METHODS = ("atm", "carve", "combined", "centerline")

#: Range bins of Fig. 10-12, metres: 0.5 m wide up to the Scout2's 6.477 m maximum range.
RANGE_EDGES = tuple(np.round(np.arange(0.0, 7.0 + 1e-9, 0.5), 3).tolist())
#: Fig. 4: the facing wall "shows" once this many local-map points lie within the radius of it.
WALL_POINTS = 3
WALL_RADIUS = 0.10
#: Fig. 2 and 9: clearance the robot needs (Scout2 diameter 0.41 m + 5 cm margin) and how far
#: either side of the gap line a map point blocks the gap, metres.
CLEARANCE_MARGIN = 0.05
GAP_DEPTH = 0.25
OPENING_DISTANCES = (1.0, 2.0, 3.0)
#: The narrow hallway (Fig. 9) needs its narrow part wider than the tour's 0.9 m clearance.
NARROW_MIN_WIDTH = 0.9
#: Width of the example run of each opening world whose local maps the figure shows.
EXAMPLE_WIDTH = {"doorway": 0.8, "corridor-opening": 0.8, "narrow-hallway": 1.0}
#: Latency against accuracy: wall patches of this length, and the error tolerances, metres.
PATCH_LENGTH = 0.5
PATCH_TOLERANCES = (0.05, 0.10)


class ExperimentError(SonarcarveError):
    """A bad experiment request: unknown experiment name, bad setting."""


# ============================================================================ settings


@dataclass(frozen=True)
class Settings:
    """How big the experiments are. :meth:`full` is what ``make experiments`` runs.

    Attributes
    ----------
    quick : bool
        Small runs (for the test suite): short tours, few openings, short sweeps.
    seeds : int
        Simulation seeds 0..seeds-1 for the office tour, the T junction and the openings.
    jobs : int
        Worker processes (1: everything in this process).
    history_size : int
        History length of the paper-style runs (paper, section 5-C: 250).
    speed : float
        Robot speed, m/s.
    sample_every : int
        Readings between two snapshots of the history (16 = one Scout2 ring cycle, 0.64 s).
    office_length : float or None
        Metres of the office tour to drive (None: all of it).
    sweep_length : float or None
        Metres of the office tour driven by each sensitivity run (None: all of it).
    opening_widths : tuple of float
        Door and side-opening widths, metres.
    """

    quick: bool = False
    seeds: int = 3
    jobs: int = 1
    history_size: int = 250
    speed: float = DEFAULT_SPEED
    sample_every: int = 16
    office_length: float | None = None
    sweep_length: float | None = None
    opening_widths: tuple[float, ...] = (0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2)
    door_headings_deg: tuple[float, ...] = (0.0, 20.0, -35.0, 45.0)
    door_offsets: tuple[float, ...] = (0.0, 0.15, -0.15)
    corridor_offsets: tuple[float, ...] = (-0.4, 0.0, 0.4)
    sweep_sample_every: int = 32
    sweeps: tuple[tuple[str, tuple[float, ...]], ...] = (
        ("history", (50, 100, 250, 500, 1000, 2000)),
        ("range_tolerance", (0.0, 0.01, 0.025, 0.05, 0.1)),
        ("beam_width_deg", (15.0, 22.5, 30.0)),
        ("min_transversal_deg", (10.0, 20.0, 30.0, 45.0, 60.0)),
        ("speed", (0.2, 0.4, 0.8)),
        ("range_noise", (0.0, 0.01, 0.03, 0.05)),
    )

    def __post_init__(self) -> None:
        if self.seeds < 1:
            msg = f"--seeds must be at least 1, got {self.seeds}"
            raise ExperimentError(msg)
        if self.jobs < 1:
            msg = f"--jobs must be at least 1, got {self.jobs}"
            raise ExperimentError(msg)

    @classmethod
    def make(cls, *, quick: bool = False, seeds: int | None = None, jobs: int = 1) -> Settings:
        """The full settings, or the quick ones (small enough for the test suite)."""
        if not quick:
            return cls(seeds=3 if seeds is None else seeds, jobs=jobs)
        return cls(
            quick=True, seeds=1 if seeds is None else seeds, jobs=jobs, office_length=30.0,
            sweep_length=12.0, opening_widths=(0.6, 1.2), door_headings_deg=(0.0,),
            door_offsets=(0.0,), corridor_offsets=(0.0,), sweep_sample_every=32,
            sweeps=(("history", (50, 250)), ("range_tolerance", (0.0, 0.025)),
                    ("beam_width_deg", (22.5, 30.0)), ("min_transversal_deg", (20.0, 30.0)),
                    ("speed", (0.4, 0.8)), ("range_noise", (0.01, 0.03))),
        )

    def method_config(self, **changes: Any) -> MethodConfig:
        """The paper-style configuration: history 250, φ 22.5°, ψ 30°, δ one inch, and carving's
        measured default ε (:data:`~sonarcarve.methods.carving.DEFAULT_RANGE_TOLERANCE`)."""
        base = MethodConfig(history_size=self.history_size,
                            range_tolerance=DEFAULT_RANGE_TOLERANCE)
        return replace(base, **changes)


# ============================================================================ scenarios


@dataclass(frozen=True)
class Scenario:
    """Everything that fixes a simulation (hashable: it keys the simulation cache).

    Attributes
    ----------
    world : str
        A :func:`~sonarcarve.sim.world.load_world` spec, or ``doorway:WIDTH``,
        ``corridor-opening:WIDTH`` or ``narrow-hallway:WIDTH`` for the generated opening worlds.
    seed : int
        Simulation seed.
    path : tuple of (x, y), optional
        Waypoints to drive; default the world's tour.
    max_length : float, optional
        Drive only the first ``max_length`` metres of the path.
    speed : float
        m/s.
    beam_width_deg : float, optional
        Override every sensor's beam width, degrees.
    physics : tuple of (name, value)
        Overrides of :class:`~sonarcarve.sim.sonar.SonarPhysics` fields.
    robot : str
        Robot name.
    """

    world: str
    seed: int
    path: tuple[tuple[float, float], ...] | None = None
    max_length: float | None = None
    speed: float = DEFAULT_SPEED
    beam_width_deg: float | None = None
    physics: tuple[tuple[str, float], ...] = ()
    robot: str = "scout2"


def build_world(spec: str) -> World:
    """The world of a scenario (see :attr:`Scenario.world`)."""
    from sonarcarve.sim.generate import (
        corridor_opening_world,
        doorway_world,
        narrow_hallway_world,
    )
    from sonarcarve.sim.world import load_world

    kind, _, width = spec.partition(":")
    if kind == "doorway" and width:
        # Room wide and deep enough for slanted approaches from 4.3 m away.
        return doorway_world(float(width), distance=4.5, stop=0.8, room_width=10.0)
    if kind == "corridor-opening" and width:
        return corridor_opening_world(float(width))
    if kind == "narrow-hallway" and width:
        return narrow_hallway_world(narrow_width=float(width))
    return load_world(spec)


def cut_polyline(points: npt.ArrayLike, length: float | None) -> FloatArray:
    """The first ``length`` metres of a polyline, shape (k, 2) (all of it for None).

    Examples
    --------
    >>> cut_polyline([[0, 0], [2, 0], [2, 2]], 3.0).tolist()
    [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0]]
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if length is None:
        return p
    steps = np.hypot(*np.diff(p, axis=0).T)
    travelled = np.concatenate(([0.0], np.cumsum(steps)))
    if length >= travelled[-1]:
        return p
    k = int(np.searchsorted(travelled, length, side="right"))  # first vertex beyond the cut
    share = (length - travelled[k - 1]) / steps[k - 1]
    if share <= 0.0:  # the cut falls on a vertex
        return p[:k]
    end = p[k - 1] + share * (p[k] - p[k - 1])
    return np.vstack((p[:k], end))


def run_simulation(scenario: Scenario) -> Simulation:
    """Simulate ``scenario``: drive its path at its speed and fire the robot's sonar ring."""
    from sonarcarve.sim.motion import follow_waypoints
    from sonarcarve.sim.robot import load_robot

    world = build_world(scenario.world)
    robot = load_robot(scenario.robot)
    if scenario.beam_width_deg is not None:
        robot = replace(robot, beam_width=np.full(robot.n_sensors,
                                                  math.radians(scenario.beam_width_deg)))
    path = world.tour if scenario.path is None else np.asarray(scenario.path, dtype=np.float64)
    if path is None:
        msg = f"world {scenario.world!r} has no tour; give the scenario a path"
        raise ExperimentError(msg)
    trajectory = follow_waypoints(cut_polyline(path, scenario.max_length), speed=scenario.speed)
    physics: SonarPhysics = replace(SonarPhysics(), **dict[str, Any](scenario.physics))
    return simulate(world, robot, trajectory, scenario.seed, physics=physics)


# ============================================================================ jobs


@dataclass(frozen=True)
class Job:
    """One method on one scenario, then one analysis (a function of :data:`ANALYSES`)."""

    key: tuple[Any, ...]
    scenario: Scenario
    method: str
    config: MethodConfig
    analysis: str
    sample_every: int = 16
    options: tuple[tuple[str, Any], ...] = ()


def run_job(job: Job, sim: Simulation) -> JsonDict:
    """Run ``job`` on its simulation and return the analysis' output (small, picklable)."""
    n = len(sim.readings)
    stops = _sample_stops(n, job.sample_every, job.analysis, sim, dict(job.options))
    record = record_run(sim.readings, make_method(job.method, job.config), stops)
    out = ANALYSES[job.analysis](sim, record, job, **dict(job.options))
    out["seconds"] = record.seconds
    out["readings"] = n
    return out


def _sample_stops(n: int, every: int, analysis: str, sim: Simulation,
                  options: dict[str, Any]) -> npt.NDArray[np.int64]:
    stops = np.arange(every, n + 1, every, dtype=np.int64)
    if analysis == "opening":
        # Snapshot exactly when the robot first comes within each distance of the gap.
        extra = [_first_reading_within(sim, options["opening"], d) for d in OPENING_DISTANCES]
        stops = np.concatenate((stops, [e for e in extra if e > 0]))
    return stops


def _run_one(args: tuple[Job, Simulation]) -> JsonDict:
    return run_job(*args)


# ============================================================================ analyses


def analyse_office(sim: Simulation, record: RunRecord, job: Job,
                   detail: bool = False) -> JsonDict:
    """Table I, Fig. 10-12, fully carved, true error, latency-vs-accuracy for one run."""
    edges = np.asarray(RANGE_EDGES)
    capacity = job.config.history_size
    samples = record.samples
    full = samples.select(record.sample_readings[samples.sample] >= capacity)
    alive_full = full.select(full.alive)
    out: JsonDict = {
        "unprocessed": metrics.percent(~full.processed),
        "unprocessed_alive": metrics.percent(~alive_full.processed),
        "unprocessed_by_range": metrics.binned(
            (~full.processed).astype(float) * 100.0, full.range, edges).as_dict(),
    }
    final = record.final
    live = final.select(final.alive)
    carved = live.select(live.source == PointSource.CARVED)
    out["width_by_range"] = metrics.binned(np.degrees(live.width), live.range, edges).as_dict()
    out["carved_width_by_range"] = metrics.binned(
        np.degrees(carved.width), carved.range, edges).as_dict()
    out["max_error_by_range"] = metrics.binned(live.max_error, live.range, edges).as_dict()
    out["removal"] = removal_summary(final, sim.truth.kind)
    # True error of every local-map point at every snapshot (what the robot navigated on).
    points = sample_points(record)
    err = metrics.segment_distance(points.xy, sim.world.segments)[0]
    out["true_error"] = metrics.error_summary(err).as_dict()
    out["true_error_by_range"] = metrics.binned(err, points.range, edges).as_dict()
    gmap = record.global_map
    gerr = metrics.segment_distance(gmap.xy, sim.world.segments)[0]
    kept = fig13_keep(gmap.source, gmap.max_error, job.method, fig13_threshold(job.config))
    out["global_error"] = metrics.error_summary(gerr).as_dict()
    out["global_points"] = len(gmap)
    out["thresholded_points"] = int(np.count_nonzero(kept))
    out["thresholded_error"] = metrics.error_summary(gerr[kept]).as_dict()
    out["latency_accuracy"] = latency_accuracy(sim, record, points, err)
    out["truth_breakdown"] = truth_breakdown(sim, final, gmap.reading_id, gerr)
    out["duration"] = sim.trajectory.duration
    if detail:
        out["global_map"] = {"xy": gmap.xy[kept], "source": gmap.source[kept],
                             "world": sim.world.segments}
    return out


def truth_breakdown(sim: Simulation, final: ArcTable, map_reading: npt.NDArray[np.int64],
                    map_error: FloatArray) -> JsonDict:
    """Why a map's error is what it is: what it kept and lost, judged by the simulator's truth.

    Returns the global map's share of spurious points (percent) and the true error of its
    points from direct readings only (so maps that keep different readings can be compared);
    the median range and centerline error (metres) of the direct readings the method removed
    and of those it kept; and, for arcs placed by carving, the share (percent) whose final
    interval still contains the bearing of the true reflection.
    """
    kind = sim.truth.kind
    direct_map = kind[map_reading] == EchoKind.DIRECT
    b = sim.readings
    axis = np.column_stack((b.x + b.range * np.cos(b.theta), b.y + b.range * np.sin(b.theta)))
    rid = final.reading_id
    direct = kind[rid] == EchoKind.DIRECT
    lost = direct & ~final.alive
    kept = direct & final.alive
    centerline_err = metrics.segment_distance(axis[rid[lost | kept]], sim.world.segments)[0]
    err_of = dict(zip(rid[lost | kept].tolist(), centerline_err.tolist(), strict=True))
    carved = kept & (final.source == PointSource.CARVED)
    truth = sim.truth.reflection[rid[carved]]
    origin = np.column_stack((b.x[rid[carved]], b.y[rid[carved]]))
    true_bearing = np.arctan2(truth[:, 1] - origin[:, 1], truth[:, 0] - origin[:, 0])
    point = final.xy[carved]
    centre = np.arctan2(point[:, 1] - origin[:, 1], point[:, 0] - origin[:, 0])
    off = np.abs(np.angle(np.exp(1j * (true_bearing - centre))))
    return {
        "spurious_share": metrics.percent(~direct_map),
        "direct_error": metrics.error_summary(map_error[direct_map]).as_dict(),
        "lost_direct_median_range": _median_or_none(final.range[lost]),
        "kept_direct_median_range": _median_or_none(final.range[kept]),
        "lost_direct_centerline_error": _median_or_none(
            np.array([err_of[i] for i in rid[lost].tolist()])),
        "kept_direct_centerline_error": _median_or_none(
            np.array([err_of[i] for i in rid[kept].tolist()])),
        "carved_contains_truth": metrics.percent(off <= 0.5 * final.width[carved] + 1e-9),
    }


def fig13_threshold(config: MethodConfig) -> float:
    """Fig. 13's max-error threshold, metres: ATM's own guaranteed bound (eq. 5.4 times δ).

    A carved point is kept when its bound (eq. 5.3) is no worse than what ATM guarantees for
    its crossings, so the two maps promise the same accuracy.
    """
    return atm_error_bound(config.min_transversal, config.range_resolution)


def fig13_keep(source: npt.NDArray[np.int8], max_error: FloatArray, method: str,
               threshold: float) -> npt.NDArray[np.bool_]:
    """Points of a global map shown in Fig. 13.

    ATM's map (a) shows the medians of transversal intersections only (no centerline
    fallbacks); every other map (b) keeps the points whose bound is within ``threshold``.
    """
    if method == "atm":
        return np.asarray(source == PointSource.ATM)
    return np.asarray(max_error <= threshold)


def removal_summary(final: ArcTable, kind: npt.NDArray[np.int64]) -> JsonDict:
    """Shares (percent) of arcs removed by carving, split by what produced the reading.

    ``share`` is the fully carved share of all arcs (paper, section 5-C: "over 20 percent");
    ``spurious_removed`` the share of spurious readings (any kind but direct) that were fully
    carved; ``true_lost`` the share of direct readings that were; ``spurious_of_removed`` the
    share of fully carved arcs that were spurious.
    """
    k = kind[final.reading_id]
    fully = final.removal == Removal.FULLY_CARVED
    split = final.removal == Removal.SPLIT
    direct = k == EchoKind.DIRECT
    return {
        "share": metrics.percent(fully),
        "split_share": metrics.percent(split),
        "spurious_removed": metrics.percent(fully[~direct]),
        "true_lost": metrics.percent(fully[direct]),
        "spurious_of_removed": metrics.percent(~direct[fully]),
        "spurious_removed_or_split": metrics.percent((fully | split)[~direct]),
        "true_lost_or_split": metrics.percent((fully | split)[direct]),
        "spurious_readings": metrics.percent(~direct),
        "unknown_removal": int(np.count_nonzero(final.removal < 0)),
    }


def latency_accuracy(sim: Simulation, record: RunRecord, points: ArcTable,
                     err: FloatArray) -> JsonDict:
    """Per 0.5 m wall patch: delay from first view to a local map within 5 and 10 cm.

    A patch is seen at the first direct reading whose true reflection lies on it; it is right
    at the first snapshot where at least half of its local-map points (points of readings that
    reflected off it) are within the tolerance of the true walls (see
    :func:`~sonarcarve.evaluation.metrics.patch_latency`). Delays are in seconds and in metres
    travelled; patches never right count as never (inf) and keep the curves below 100 %.
    """
    segments = sim.world.segments
    patches = metrics.patch_index(segments, PATCH_LENGTH)
    reflection = np.where((sim.truth.kind == EchoKind.DIRECT)[:, None], sim.truth.reflection,
                          np.nan)
    reading_patch = metrics.patch_of_points(reflection, segments, patches)
    sample_t = record.sample_times(sim.readings)
    grid_s = np.asarray(LATENCY_GRID_S)
    grid_m = np.asarray(LATENCY_GRID_M)
    out: JsonDict = {"patches_seen": 0}
    for tol in PATCH_TOLERANCES:
        seen, resolved = metrics.patch_latency(
            reading_patch=reading_patch, reading_t=sim.readings.t, sample_t=sample_t,
            row_sample=points.sample, row_reading=points.reading_id, row_error=err,
            n_patches=len(patches), tolerance=tol)
        mask = np.isfinite(seen)
        ok = np.isfinite(resolved[mask])
        delay_s = np.full(ok.shape, np.inf)
        delay_s[ok] = resolved[mask][ok] - seen[mask][ok]
        dist = sim.trajectory.distance_at
        delay_m = np.full(delay_s.shape, np.inf)
        delay_m[ok] = dist(resolved[mask][ok]) - dist(seen[mask][ok])
        out["patches_seen"] = int(mask.sum())
        out[f"{tol:g}"] = {
            "resolved_share": metrics.percent(ok),
            "median_s": _median_or_none(delay_s[ok]),
            "median_m": _median_or_none(delay_m[ok]),
            "curve_s": metrics.resolved_share_curve(delay_s, grid_s).tolist(),
            "curve_m": metrics.resolved_share_curve(delay_m, grid_m).tolist(),
        }
    return out


LATENCY_GRID_S = tuple(np.round(np.linspace(0.0, 60.0, 121), 3).tolist())
LATENCY_GRID_M = tuple(np.round(np.linspace(0.0, 20.0, 101), 3).tolist())


def analyse_t_junction(sim: Simulation, record: RunRecord, job: Job,
                       detail: bool = False) -> JsonDict:
    """Fig. 4: robot-to-facing-wall distance when the local map first shows the wall.

    The facing wall is the wall hit by a ray from the start of the drive along its heading. The
    wall *shows* once at least :data:`WALL_POINTS` local-map points lie within
    :data:`WALL_RADIUS` of it; counted over all the method's points, and over its *refined*
    points only (not ``centerline``: carved or ATM), which is what the paper's Fig. 4(a) shows.
    """
    traj = sim.trajectory
    start = np.array([traj.x[0], traj.y[0]])
    _, wall_index = sim.world.cast_rays(start, [traj.heading[0]])
    facing = sim.world.segments[int(wall_index[0])]
    points = sample_points(record)
    near = metrics.segment_distance(points.xy, facing[None, :])[0] <= WALL_RADIUS
    k = len(record.sample_readings)
    all_counts = np.bincount(points.sample[near], minlength=k)
    refined = near & (points.source != PointSource.CENTERLINE)
    refined_counts = np.bincount(points.sample[refined], minlength=k)
    sample_t = record.sample_times(sim.readings)
    x, y, _ = traj.pose_at(sample_t)
    wall_distance = metrics.segment_distance(np.column_stack((x, y)), facing[None, :])[0]
    out: JsonDict = {"end_distance": float(wall_distance[-1]) if k else None}
    for name, counts in (("all", all_counts), ("refined", refined_counts)):
        first = metrics.first_at_least(counts, WALL_POINTS)
        out[name] = None if first < 0 else float(wall_distance[first])
    if detail:
        # The local maps when the robot is about 4 m from the wall (the paper's Fig. 4 moment).
        moment = int(np.argmin(np.abs(wall_distance - 4.0)))
        snap = points.select(points.sample == moment)
        out["snapshot"] = {"xy": snap.xy, "source": snap.source,
                           "robot": [float(x[moment]), float(y[moment])],
                           "wall_distance": float(wall_distance[moment]),
                           "world": sim.world.segments}
    return out


def _first_reading_within(sim: Simulation, opening: Sequence[Sequence[float]],
                          distance: float) -> int:
    """Readings added when the robot is first within ``distance`` of being level with the gap.

    The distance is measured along the robot's heading: ``(c - p) · (cos h, sin h)`` for gap
    centre ``c``, robot position ``p`` and heading ``h``, i.e. how far it still has to drive to
    reach the door (head-on) or to come abreast of a side opening. 0 when it never gets there.
    """
    centre = 0.5 * (np.asarray(opening[0]) + np.asarray(opening[1]))
    x, y, heading = sim.trajectory.pose_at(sim.readings.t)
    ahead = (centre[0] - x) * np.cos(heading) + (centre[1] - y) * np.sin(heading)
    within = np.flatnonzero(ahead <= distance)
    return int(within[0]) + 1 if within.size else 0


def analyse_opening(sim: Simulation, record: RunRecord, job: Job,
                    opening: Sequence[Sequence[float]] = (), detail: bool = False) -> JsonDict:
    """Fig. 2 and 9: is the opening passable in the local map 1, 2 and 3 m before it?

    Distances are along the drive (see :func:`_first_reading_within`).

    Passable: some stretch of the gap at least the robot's diameter plus
    :data:`CLEARANCE_MARGIN` wide has no map point within :data:`GAP_DEPTH` of the gap line
    (see :func:`~sonarcarve.evaluation.metrics.free_width`). ``None`` where the drive never
    comes that close.
    """
    region = metrics.gap_region(opening[0], opening[1], GAP_DEPTH)
    clearance = 2.0 * sim.robot.robot_radius + CLEARANCE_MARGIN
    points = sample_points(record)
    out: JsonDict = {"width": region.width}
    for d in OPENING_DISTANCES:
        stop = _first_reading_within(sim, opening, d)
        if stop <= 0:
            out[f"{d:g}"] = None
            continue
        k = int(np.searchsorted(record.sample_readings, stop))
        snap = points.select(points.sample == k)
        out[f"{d:g}"] = bool(metrics.is_passable(snap.xy, region, clearance))
        if detail and d == 2.0:
            x, y, _ = sim.trajectory.pose_at(sim.readings.t[stop - 1])
            out["snapshot"] = {"xy": snap.xy, "source": snap.source,
                               "robot": [float(x), float(y)], "world": sim.world.segments,
                               "opening": np.asarray(opening)}
    return out


def analyse_sweep(sim: Simulation, record: RunRecord, job: Job) -> JsonDict:
    """One point of a sensitivity curve: true error, unprocessed share, fully carved share."""
    capacity = job.config.history_size
    samples = record.samples
    filled = min(capacity, len(sim.readings))
    full = samples.select(record.sample_readings[samples.sample] >= filled)
    points = sample_points(record)
    err = metrics.segment_distance(points.xy, sim.world.segments)[0]
    summary = metrics.error_summary(err)
    fully = record.final.removal == Removal.FULLY_CARVED
    return {"error_median": summary.median, "error_p90": summary.p90,
            "unprocessed": metrics.percent(~full.processed), "fully_carved": metrics.percent(fully)}


ANALYSES: dict[str, Callable[..., JsonDict]] = {
    "office": analyse_office,
    "t-junction": analyse_t_junction,
    "opening": analyse_opening,
    "sweep": analyse_sweep,
}


def _median_or_none(a: FloatArray) -> float | None:
    return float(np.median(a)) if a.size else None


# ============================================================================ experiments


class Experiment(NamedTuple):
    """A named experiment: its jobs and how to summarise their outputs."""

    name: str
    title: str
    plan: Callable[[Settings], list[Job]]
    summarise: Callable[[Settings, dict[tuple[Any, ...], JsonDict]], tuple[JsonDict, JsonDict]]


# -- office ------------------------------------------------------------------------------------

def _plan_office(s: Settings) -> list[Job]:
    return [Job(("office", seed, m), Scenario("office", seed, max_length=s.office_length,
                                              speed=s.speed),
                m, s.method_config(), "office", s.sample_every,
                (("detail", seed == 0),))
            for seed in range(s.seeds) for m in ALL_METHODS]


def _spread(values: Iterable[float | None]) -> JsonDict:
    v = np.array([np.nan if x is None else x for x in values], dtype=np.float64)
    ok = v[np.isfinite(v)]
    if not ok.size:
        return {"mean": None, "min": None, "max": None, "std": None, "per_seed": []}
    return {"mean": float(ok.mean()), "min": float(ok.min()), "max": float(ok.max()),
            "std": float(ok.std()), "per_seed": [None if not math.isfinite(x) else float(x)
                                                 for x in v]}


def _binned_over_seeds(outs: list[JsonDict], key: str, stat: str = "mean") -> JsonDict:
    rows = np.array([[np.nan if x is None else x for x in o[key][stat]] for o in outs])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns: empty range bins
        mean = np.nanmean(rows, axis=0)
        lo = np.nanmin(rows, axis=0)
        hi = np.nanmax(rows, axis=0)
    counts = np.sum([o[key]["count"] for o in outs], axis=0)
    return {"edges": outs[0][key]["edges"], "value": _nan_list(mean), "min": _nan_list(lo),
            "max": _nan_list(hi), "count": [int(c) for c in counts]}


def _nan_list(a: FloatArray) -> list[float | None]:
    return [None if not math.isfinite(float(x)) else float(x) for x in a]


def _summarise_office(s: Settings, outs: dict[tuple[Any, ...], JsonDict]) -> tuple[JsonDict,
                                                                                   JsonDict]:
    by_method = {m: [outs[("office", seed, m)] for seed in range(s.seeds)] for m in ALL_METHODS}
    label = METHOD_LABELS
    res: JsonDict = {}
    res["table1"] = {label[m]: _spread(o["unprocessed"] for o in by_method[m])["mean"]
                     for m in ALL_METHODS}
    res["table1_spread"] = {label[m]: _spread(o["unprocessed"] for o in by_method[m])
                            for m in ALL_METHODS}
    res["table1_alive_only"] = {
        label[m]: _spread(o["unprocessed_alive"] for o in by_method[m])["mean"]
        for m in ALL_METHODS}
    res["fig10"] = {label[m]: _binned_over_seeds(by_method[m], "unprocessed_by_range")
                    for m in ALL_METHODS}
    carve = by_method["carve"]
    res["fig11"] = {
        "all_surviving": {"mean": _binned_over_seeds(carve, "width_by_range", "mean"),
                          "median": _binned_over_seeds(carve, "width_by_range", "median")},
        "carved_only": {"mean": _binned_over_seeds(carve, "carved_width_by_range", "mean"),
                        "median": _binned_over_seeds(carve, "carved_width_by_range", "median")},
    }
    config = s.method_config()
    res["fig12"] = {
        "carving": _binned_over_seeds(carve, "max_error_by_range"),
        "centerline": _binned_over_seeds(by_method["centerline"], "max_error_by_range"),
        "atm_measured": _binned_over_seeds(by_method["atm"], "max_error_by_range"),
        "combined": _binned_over_seeds(by_method["combined"], "max_error_by_range"),
        "atm_bound": atm_error_bound(config.min_transversal, config.range_resolution),
    }
    removal_keys = carve[0]["removal"].keys()
    res["fully_carved"] = {k: _spread(o["removal"][k] for o in carve)["mean"]
                           for k in removal_keys}
    res["fully_carved_spread"] = {k: _spread(o["removal"][k] for o in carve)
                                  for k in ("share", "spurious_removed", "true_lost")}
    res["fully_carved_combined"] = {k: _spread(o["removal"][k] for o in by_method["combined"])
                                    ["mean"] for k in ("share", "spurious_removed", "true_lost")}
    res["true_error"] = {label[m]: {q: _spread(o["true_error"][q] for o in by_method[m])["mean"]
                                    for q in ("median", "p90", "mean")} for m in ALL_METHODS}
    res["true_error_spread"] = {
        label[m]: {q: _spread(o["true_error"][q] for o in by_method[m]) for q in ("median", "p90")}
        for m in ALL_METHODS}
    res["true_error_by_range"] = {
        label[m]: {"median": _binned_over_seeds(by_method[m], "true_error_by_range", "median"),
                   "p90": _binned_over_seeds(by_method[m], "true_error_by_range", "p90")}
        for m in ALL_METHODS}
    res["true_error_global"] = {
        label[m]: {q: _spread(o["global_error"][q] for o in by_method[m])["mean"]
                   for q in ("median", "p90")} for m in ALL_METHODS}
    res["fig13"] = {
        "threshold_m": fig13_threshold(config),
        **{label[m]: {
            "points": _spread(o["global_points"] for o in by_method[m])["mean"],
            "kept": _spread(o["thresholded_points"] for o in by_method[m])["mean"],
            "kept_error_median": _spread(o["thresholded_error"]["median"]
                                         for o in by_method[m])["mean"],
            "kept_error_p90": _spread(o["thresholded_error"]["p90"] for o in by_method[m])["mean"],
        } for m in ALL_METHODS}}
    res["latency_accuracy"] = {"grid_s": list(LATENCY_GRID_S), "grid_m": list(LATENCY_GRID_M),
                               "patch_length_m": PATCH_LENGTH}
    for m in ALL_METHODS:
        entry: JsonDict = {}
        for tol in PATCH_TOLERANCES:
            key = f"{tol:g}"
            per = [o["latency_accuracy"][key] for o in by_method[m]]
            entry[key] = {
                "resolved_share": _spread(p["resolved_share"] for p in per)["mean"],
                "median_s": _spread(p["median_s"] for p in per)["mean"],
                "median_m": _spread(p["median_m"] for p in per)["mean"],
                "curve_s": np.mean([p["curve_s"] for p in per], axis=0).tolist(),
                "curve_m": np.mean([p["curve_m"] for p in per], axis=0).tolist(),
            }
        entry["patches_seen"] = _spread(o["latency_accuracy"]["patches_seen"]
                                        for o in by_method[m])["mean"]
        res["latency_accuracy"][label[m]] = entry
    res["truth_breakdown"] = {}
    for m in ALL_METHODS:
        per = [o["truth_breakdown"] for o in by_method[m]]
        entry = {k: _spread(p[k] for p in per)["mean"] for k in per[0] if k != "direct_error"}
        entry["direct_error"] = {q: _spread(p["direct_error"][q] for p in per)["mean"]
                                 for q in ("median", "p90")}
        res["truth_breakdown"][label[m]] = entry
    first = {m: by_method[m][0] for m in ALL_METHODS}
    res["office_runs"] = {
        "seeds": s.seeds, "readings": _spread(o["readings"] for o in by_method["carve"])["mean"],
        "duration_s": _spread(o["duration"] for o in by_method["carve"])["mean"],
        "method_seconds": {label[m]: _spread(o["seconds"] for o in by_method[m])["mean"]
                           for m in ALL_METHODS}}
    artifacts = {"fig13": {label[m]: first[m].get("global_map") for m in ("atm", "carve")}}
    return res, artifacts


# -- T junction --------------------------------------------------------------------------------

def _t_junction_scenario(s: Settings, seed: int) -> Scenario:
    from sonarcarve.sim.world import load_world

    tour = load_world("t-junction").tour
    assert tour is not None
    # Only the drive up the stem, towards the facing wall (the tour's first leg).
    stem = tuple((float(x), float(y)) for x, y in tour[:2])
    return Scenario("t-junction", seed, path=stem, speed=s.speed)


def _plan_t_junction(s: Settings) -> list[Job]:
    return [Job(("t-junction", seed, m), _t_junction_scenario(s, seed), m, s.method_config(),
                "t-junction", 4, (("detail", seed == 0),))
            for seed in range(s.seeds) for m in ALL_METHODS]


def _summarise_t_junction(s: Settings, outs: dict[tuple[Any, ...], JsonDict]) -> tuple[JsonDict,
                                                                                      JsonDict]:
    res: JsonDict = {"points": WALL_POINTS, "radius_m": WALL_RADIUS, "all": {}, "refined": {},
                     "end_distance_m": outs[("t-junction", 0, "carve")]["end_distance"]}
    for m in ALL_METHODS:
        per = [outs[("t-junction", seed, m)] for seed in range(s.seeds)]
        for kind in ("all", "refined"):
            res[kind][METHOD_LABELS[m]] = _spread(o[kind] for o in per)
    artifacts = {"snapshots": {METHOD_LABELS[m]: outs[("t-junction", 0, m)].get("snapshot")
                               for m in ALL_METHODS}}
    return {"t_junction": res}, artifacts


# -- openings ----------------------------------------------------------------------------------

def _opening_runs(s: Settings) -> list[tuple[str, float, float, float, int]]:
    """(kind, width, heading_deg, offset, seed) of every opening run."""
    runs = []
    for seed in range(s.seeds):
        for w in s.opening_widths:
            runs += [("doorway", w, h, o, seed) for h in s.door_headings_deg
                     for o in s.door_offsets]
            runs += [("corridor-opening", w, 0.0, o, seed) for o in s.corridor_offsets]
            if w > NARROW_MIN_WIDTH:
                runs.append(("narrow-hallway", w, 0.0, 0.0, seed))
    return runs


def _opening_scenario(s: Settings, kind: str, width: float, heading_deg: float,
                      offset: float, seed: int) -> tuple[Scenario, list[list[float]]]:
    world = build_world(f"{kind}:{width:g}")
    # The narrow hallway's second opening is the mouth of its narrow part (paper, Fig. 9).
    gap = world.openings[1 if kind == "narrow-hallway" else 0]
    if kind == "doorway":
        # A straight drive aimed at the door (shifted ``offset`` along the wall), at
        # ``heading_deg`` from the wall's normal, from 4.3 m to 0.8 m short of the aim point.
        aim = 0.5 * (gap[0] + gap[1]) + np.array([offset, 0.0])
        h = math.radians(heading_deg)
        direction = np.array([math.sin(h), math.cos(h)])
        path = (aim - 4.3 * direction, aim - 0.8 * direction)
    else:
        # Along the corridor, ``offset`` metres right of the tour, past or into the opening.
        assert world.tour is not None
        path = (world.tour[0] + [offset, 0.0], world.tour[-1] + [offset, 0.0])
    points = tuple((float(p[0]), float(p[1])) for p in path)
    return Scenario(f"{kind}:{width:g}", seed, path=points, speed=s.speed), gap.tolist()


def _plan_openings(s: Settings) -> list[Job]:
    jobs = []
    for run in _opening_runs(s):
        scenario, gap = _opening_scenario(s, *run)
        # One run per world kind keeps its local maps at 2 m for the figure.
        example = run[1] == EXAMPLE_WIDTH[run[0]] and run[2] == 0.0 and run[3] == 0.0 \
            and run[4] == 0
        jobs += [Job(("opening", *run, m), scenario, m, s.method_config(), "opening", 4,
                     (("opening", tuple(map(tuple, gap))), ("detail", example)))
                 for m in ALL_METHODS]
    return jobs


def _summarise_openings(s: Settings, outs: dict[tuple[Any, ...], JsonDict]) -> tuple[JsonDict,
                                                                                    JsonDict]:
    runs = _opening_runs(s)
    res: JsonDict = {}
    detail: JsonDict = {}
    for m in ALL_METHODS:
        label = METHOD_LABELS[m]
        res[label] = {}
        detail[label] = {}
        for d in OPENING_DISTANCES:
            key = f"{d:g}"
            flags = [outs[("opening", *run, m)][key] for run in runs]
            res[label][key] = metrics.percent([f for f in flags if f is not None])
            by: dict[str, list[bool]] = defaultdict(list)
            for run, f in zip(runs, flags, strict=True):
                if f is not None:
                    by[f"{run[0]} {run[1]:g}"].append(f)
            detail[label][key] = {k: metrics.percent(v) for k, v in sorted(by.items())}
    artifacts: JsonDict = {"snapshots": {}}
    for job_key, out in outs.items():
        if "snapshot" in out:
            world, method = str(job_key[1]), str(job_key[-1])
            artifacts["snapshots"].setdefault(world, {})[METHOD_LABELS[method]] = out["snapshot"]
    definition = {"clearance_m": 0.41 + CLEARANCE_MARGIN, "gap_depth_m": GAP_DEPTH,
                  "distances_m": list(OPENING_DISTANCES), "runs": len(runs),
                  "widths_m": list(s.opening_widths),
                  "door_headings_deg": list(s.door_headings_deg),
                  "door_offsets_m": list(s.door_offsets),
                  "corridor_offsets_m": list(s.corridor_offsets)}
    return {"openings": res, "openings_by_world": detail, "openings_definition": definition}, \
        artifacts


# -- sensitivity -------------------------------------------------------------------------------

#: Sweep parameter -> (methods it matters to, unit).
SWEEP_METHODS = {
    "history": (("carve", "atm", "combined"), "arcs"),
    "range_tolerance": (("carve", "combined"), "m"),
    "beam_width_deg": (("carve", "atm", "combined", "centerline"), "deg"),
    "min_transversal_deg": (("atm", "combined"), "deg"),
    "speed": (("carve", "atm", "combined", "centerline"), "m/s"),
    "range_noise": (("carve", "atm", "combined", "centerline"), "m"),
}


def _sweep_job(s: Settings, param: str, value: float, method: str) -> Job:
    scenario = Scenario("office", 0, max_length=s.sweep_length, speed=s.speed)
    config = s.method_config()
    if param == "history":
        config = replace(config, history_size=int(value))
    elif param == "range_tolerance":
        config = replace(config, range_tolerance=float(value))
    elif param == "beam_width_deg":
        scenario = replace(scenario, beam_width_deg=float(value))
        config = replace(config, beam_width=math.radians(value))
    elif param == "min_transversal_deg":
        config = replace(config, min_transversal=math.radians(value))
    elif param == "speed":
        scenario = replace(scenario, speed=float(value))
    elif param == "range_noise":
        scenario = replace(scenario, physics=(("range_noise", float(value)),))
    return Job(("sweep", param, value, method), scenario, method, config, "sweep",
               s.sweep_sample_every)


def _plan_sensitivity(s: Settings) -> list[Job]:
    return [_sweep_job(s, param, value, m) for param, values in s.sweeps
            for value in values for m in SWEEP_METHODS[param][0]]


def _summarise_sensitivity(s: Settings, outs: dict[tuple[Any, ...], JsonDict]) -> tuple[
        JsonDict, JsonDict]:
    res: JsonDict = {}
    for param, values in s.sweeps:
        methods, unit = SWEEP_METHODS[param]
        entry: JsonDict = {"values": list(values), "unit": unit}
        for m in methods:
            per = [outs[("sweep", param, v, m)] for v in values]
            entry[METHOD_LABELS[m]] = {
                q: [None if p[q] is None or not math.isfinite(p[q]) else float(p[q]) for p in per]
                for q in ("error_median", "error_p90", "unprocessed", "fully_carved")}
        res[param] = entry
    res["scenario"] = {"world": "office", "seed": 0, "length_m": s.sweep_length,
                       "sample_every": s.sweep_sample_every}
    return {"sensitivity": res}, {}


EXPERIMENTS: dict[str, Experiment] = {
    "office": Experiment("office", "Table I, Fig. 10-13, fully carved, true error, latency",
                         _plan_office, _summarise_office),
    "t-junction": Experiment("t-junction", "Fig. 4: when the facing wall appears",
                             _plan_t_junction, _summarise_t_junction),
    "openings": Experiment("openings", "Fig. 2 and 9: narrow openings passable",
                           _plan_openings, _summarise_openings),
    "sensitivity": Experiment("sensitivity", "history, ε, φ, ψ, speed, noise sweeps",
                              _plan_sensitivity, _summarise_sensitivity),
}
# The appendix experiments (polling, real-log, odometry) plan no jobs: they run in summarise.
EXPERIMENTS.update({name: Experiment(name, title, lambda s: [], experiment_summariser(name))
                    for name, (title, _) in APPENDIX_EXPERIMENTS.items()})


# ============================================================================ running


@dataclass
class ExperimentResults:
    """What :func:`run_experiments` produced.

    Attributes
    ----------
    results : dict
        JSON-ready numbers (written to ``results.json``).
    artifacts : dict
        Arrays for the figures (maps), per experiment; not written to JSON.
    """

    results: JsonDict = field(default_factory=dict)
    artifacts: JsonDict = field(default_factory=dict)


ProgressCallback = Callable[[str, int, int], None]


def run_experiments(
    settings: Settings,
    only: Sequence[str] | None = None,
    on_progress: ProgressCallback | None = None,
) -> ExperimentResults:
    """Run the chosen experiments (all by default) and summarise them.

    Parameters
    ----------
    settings : Settings
        Sizes, seeds and worker count.
    only : sequence of str, optional
        Experiment names (keys of :data:`EXPERIMENTS`).
    on_progress : callable, optional
        ``on_progress(stage, done, total)`` with stage ``"simulating"`` or ``"mapping"``.

    Raises
    ------
    ExperimentError
        For an unknown experiment name.
    """
    names = list(EXPERIMENTS) if not only else list(only)
    for name in names:
        if name not in EXPERIMENTS:
            msg = f"unknown experiment {name!r}; choose from {', '.join(EXPERIMENTS)}"
            raise ExperimentError(msg)
    tic = time.perf_counter()
    plans = {name: EXPERIMENTS[name].plan(settings) for name in names}
    jobs = [job for name in names for job in plans[name]]
    scenarios = list(dict.fromkeys(job.scenario for job in jobs))
    report = on_progress or (lambda stage, done, total: None)

    pool = None
    if settings.jobs > 1:
        pool = ProcessPoolExecutor(max_workers=settings.jobs,
                                   mp_context=multiprocessing.get_context("spawn"))
    try:
        sims: dict[Scenario, Simulation] = {}
        report("simulating", 0, len(scenarios))
        sim_list = (pool.map(run_simulation, scenarios, chunksize=1) if pool is not None
                    else map(run_simulation, scenarios))
        for i, (scenario, sim) in enumerate(zip(scenarios, sim_list, strict=True)):
            sims[scenario] = sim
            report("simulating", i + 1, len(scenarios))
        report("mapping", 0, len(jobs))
        args = [(job, sims[job.scenario]) for job in jobs]
        out_list = (pool.map(_run_one, args, chunksize=1) if pool is not None
                    else map(_run_one, args))
        outputs: dict[tuple[Any, ...], JsonDict] = {}
        for i, (job, out) in enumerate(zip(jobs, out_list, strict=True)):
            outputs[job.key] = out
            report("mapping", i + 1, len(jobs))
    finally:
        if pool is not None:
            pool.shutdown()

    results = ExperimentResults()
    for name in names:
        own = {job.key: outputs[job.key] for job in plans[name]}
        res, art = EXPERIMENTS[name].summarise(settings, own)
        results.results.update(res)
        results.artifacts[name] = art
    results.results["meta"] = {
        "experiments": names,
        "settings": _settings_json(settings),
        "seconds": time.perf_counter() - tic,
        "simulations": len(scenarios),
        "jobs": len(jobs),
        "readings_simulated": int(sum(len(sim.readings) for sim in sims.values())),
    }
    return results


def _settings_json(s: Settings) -> JsonDict:
    out = asdict(s)
    out["sweeps"] = {k: list(v) for k, v in s.sweeps}
    config = s.method_config()
    out["method_config"] = {"history_size": config.history_size,
                            "beam_width_deg": math.degrees(config.beam_width),
                            "range_tolerance_m": config.range_tolerance,
                            "min_transversal_deg": math.degrees(config.min_transversal),
                            "range_resolution_m": config.range_resolution}
    return out
