"""Changing scenes measured: how fast each map follows obstacles that appear, vanish or move.

Every method (its *local map*: one point per surviving arc in the history) and every grid (its
*occupied cells*, :func:`~sonarcarve.grids.trinary`) is fed the readings of a simulation with a
:class:`~sonarcarve.sim.scene.Scene`, and read every :data:`SNAPSHOT_PERIOD` seconds (a
snapshot at time τ holds every reading up to τ). Against the truth at τ (static walls plus the
obstacles present at τ, where they are at τ):

- a map point is **explained** when it lies within ``tol`` of a wall or an obstacle present at
  τ: ``tol`` = :data:`POINT_TOLERANCE` (0.1 m) for a method's points, 1.5 cells for a grid's
  occupied cells (a cell next to a cell a wall passes through; :func:`grid_tolerance`);
- the **phantom share** at τ is the share of the map's points that are not explained (NaN for
  an empty map); reported over time and as its mean over the snapshots.

The **changes** come from the scene (:func:`scene_changes`):

- a static obstacle's ``appear`` (after the start) is an **appeared** change, its ``vanish``
  (before the end) a **gone** change; the *place* is its outline;
- a moving obstacle (the person) *appears* when the robot first sees it (a sensor's beam holds a
  point of its outline within range and in sight of the static walls) and is *gone* when the
  robot last sees it (it has left the corridor); the place of the gone change is every outline
  it had while seen (its trail), the appeared change follows its outline at each τ.

Each change has a **reference time** from which its latency counts: the change itself, or, if
later, the first firing after it whose beam could see the place (a point of it within range,
inside the beam, in sight of the static walls): a box removed while the robot is away counts
from when the robot is back in sight of where the box was. For gone changes the time the robot
passes the place (its closest approach after the reference) is kept too: the target of issue 10
("a removed obstacle cleared within 3 s of the robot driving past it") reads the clearing time
from there.

The map is **right** again, at a snapshot:

- after a gone change, when no unexplained point lies within :data:`PLACE_RADIUS` (0.25 m) of
  the place (points near a wall the box stood against are explained by the wall);
- after an appeared change, when at least one point lies within 0.25 m of the obstacle (where
  it is at τ) and farther than ``tol`` from every static wall (a door's jambs do not mark it).

**Latency**: for a gone change, the time from the reference to the first snapshot from which
the map stays right until the end of the run (a place cleared and marked again is not cleared);
for an appeared change, to the first snapshot at which it is right, while the obstacle is still
there (or seen, for a moving one). NaN when that never happens.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple, Protocol

import numpy as np
import numpy.typing as npt

from sonarcarve.grids import (
    OCCUPIED,
    Grid,
    RangeSensorLayerParams,
    make_grid,
    trinary,
)
from sonarcarve.methods import make_method
from sonarcarve.methods.base import SonarMethod
from sonarcarve.plotting import plot_walls
from sonarcarve.readings import ReadingBatch
from sonarcarve.robot import load_robot
from sonarcarve.sim.motion import follow_waypoints
from sonarcarve.sim.scene import ChangingScene, DynamicObstacle, Scene, changing_scene
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import DEFAULT_PHYSICS, SonarPhysics
from sonarcarve.sim.world import World
from sonarcarve.typing import BoolArray, FloatArray

if TYPE_CHECKING:
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

__all__ = [
    "GRID_KINDS",
    "METHOD_NAMES",
    "PLACE_RADIUS",
    "POINT_TOLERANCE",
    "SNAPSHOT_PERIOD",
    "Change",
    "MapTrack",
    "SceneRun",
    "change_latency",
    "grid_tolerance",
    "measure_track",
    "plot_changing_scene",
    "run_changing_scene",
    "scene_changes",
    "simulate_changing_scene",
    "snapshot_right",
]

#: Seconds between two snapshots of every map.
SNAPSHOT_PERIOD = 0.2
#: A point this close to where an obstacle was (gone) or is (appeared) counts, metres.
PLACE_RADIUS = 0.25
#: A method's point this close to a present wall or obstacle is explained, metres.
POINT_TOLERANCE = 0.1
#: Outline sample spacing for visibility and trails, metres.
_SAMPLE_STEP = 0.05
#: The methods measured, by :func:`~sonarcarve.methods.make_method` name.
METHOD_NAMES = ("centerline", "carve", "atm", "combined", "evidence")


#: Metres added to :func:`grid_tolerance`: a wall along a cell boundary lies exactly 1.5 cells
#: from the centres of the cells beside the two it touches, and the rounding of those centres
#: (1e-16) decided whether they were explained (at 0.10 m the box scene's wall at x = -1.2 is
#: 0.15000000000000013 from the centre of column -1.05, the tolerance was 0.15000000000000002).
_ROUNDING = 1e-9


def grid_tolerance(resolution: float) -> float:
    """How close an occupied cell's centre must be to a wall or obstacle to be explained:
    1.5 cells (a cell beside one the wall passes through, also when the wall runs along a
    cell boundary), metres."""
    return 1.5 * resolution + _ROUNDING


Bounds = tuple[float, float, float, float]


def _grid(name: str) -> Callable[[float, Bounds], Grid]:
    """The factory ``(resolution, bounds) -> grid`` of :func:`~sonarcarve.grids.make_grid`'s
    grid ``name``, with its defaults."""
    return lambda h, bounds: make_grid(name, h, bounds)


def _layer_clearing(h: float, bounds: Bounds) -> Grid:
    # +Inf as a max-range reading that clears (the Scout2's max range), ROS's opt-in.
    return make_grid("range-sensor-layer", h, bounds, RangeSensorLayerParams(
        max_range=load_robot("scout2").max_range, inf_is_max_reading=True,
        clear_on_max_reading=True))


#: The grids measured: label -> factory ``(resolution, bounds) -> grid`` (defaults each). A
#: new grid joins every table and figure by an entry here.
GRID_KINDS: dict[str, Callable[[float, Bounds], Grid]] = {
    "carved grid": _grid("carved"),
    "range sensor layer": _grid("range-sensor-layer"),
    "elfes grid": _grid("elfes"),
}

#: Grids that only differ from :data:`GRID_KINDS` on no-echo readings, measured with them:
#: the range sensor layer with ``inf_is_max_reading`` and ``clear_on_max_reading`` (+Inf
#: clears the cone up to the robot's max range; ROS's default drops +Inf).
NO_ECHO_GRID_KINDS: dict[str, Callable[[float, Bounds], Grid]] = {
    "range sensor layer, +Inf clears": _layer_clearing,
}


class Change(NamedTuple):
    """One change of a scene and when the map can be expected to follow it.

    Attributes
    ----------
    obstacle : int
        Its index in the scene.
    label : str
        ``"<obstacle name> <kind>"``, e.g. ``"box gone"``.
    kind : str
        ``"appeared"`` or ``"gone"``.
    t : float
        When it happened, seconds.
    t_ref : float
        From when its latency counts: ``t``, or the first firing after ``t`` that could see the
        place, seconds (``inf``: never seen).
    t_end : float
        Until when the map is checked, seconds: the end of the run for gone changes; the
        obstacle's vanishing (last sighting, moving) for appeared ones.
    t_past : float
        Gone changes: when the robot is closest to the place between ``t_ref`` and the end;
        NaN for appeared changes.
    place : ndarray, shape (m, 4)
        Segments where the obstacle was (gone) or is at ``t`` (appeared), metres.
    moving : bool
        An appeared change of a moving obstacle: the map is checked against where it is at τ.
    """

    obstacle: int
    label: str
    kind: str
    t: float
    t_ref: float
    t_end: float
    t_past: float
    place: FloatArray
    moving: bool


# --------------------------------------------------------------------------------------------
# Visibility and changes
# --------------------------------------------------------------------------------------------


def _samples(segments: FloatArray, step: float = _SAMPLE_STEP) -> FloatArray:
    """Points along each segment at most ``step`` apart, ends included, shape (n, 2)."""
    out = []
    for x1, y1, x2, y2 in np.asarray(segments, dtype=np.float64).reshape(-1, 4):
        n = max(1, math.ceil(math.hypot(x2 - x1, y2 - y1) / step))
        s = np.linspace(0.0, 1.0, n + 1)
        out.append(np.column_stack((x1 + s * (x2 - x1), y1 + s * (y2 - y1))))
    return np.vstack(out) if out else np.zeros((0, 2))


def _seen_points(sim: Simulation, rows: npt.NDArray[np.int64],
                 points: Sequence[FloatArray]) -> BoolArray:
    """Whether firing ``rows[i]`` could see one of ``points[i]`` (shape (m_i, 2)): in range,
    inside its beam and in sight of the static walls."""
    f = sim.firings
    seen = np.zeros(rows.shape[0], dtype=bool)
    if rows.size == 0:
        return seen
    counts = np.array([p.shape[0] for p in points])
    owner = np.repeat(np.arange(rows.shape[0]), counts)
    p = np.vstack(points)
    fr = rows[owner]
    ox, oy = f.x[fr], f.y[fr]
    d = np.hypot(p[:, 0] - ox, p[:, 1] - oy)
    bearing = np.arctan2(p[:, 1] - oy, p[:, 0] - ox)
    off = np.abs(np.angle(np.exp(1j * (bearing - f.theta[fr]))))
    half = 0.5 * sim.robot.beam_width[f.sensor[fr]]
    cand = np.flatnonzero((d <= sim.robot.max_range) & (d >= sim.robot.min_range)
                          & (off <= half))
    if cand.size:
        hit, _ = sim.world.cast_rays(np.column_stack((ox[cand], oy[cand])), bearing[cand],
                                     max_range=sim.robot.max_range + 1.0)
        clear = hit >= d[cand] - 1e-6
        seen[np.unique(owner[cand[clear]])] = True
    return seen


def _first_seen(sim: Simulation, place: FloatArray, after: float) -> float:
    """First firing time at or after ``after`` whose beam could see a point of ``place``."""
    f = sim.firings
    samples = _samples(place)
    rows = np.flatnonzero(f.t >= after)
    for lo in range(0, rows.shape[0], 512):
        chunk = rows[lo:lo + 512]
        seen = _seen_points(sim, chunk, [samples] * chunk.shape[0])
        if np.any(seen):
            return float(f.t[chunk[np.argmax(seen)]])
    return math.inf


def _closest_approach(sim: Simulation, place: FloatArray, lo: float, hi: float) -> float:
    """Time in ``[lo, hi]`` at which the robot is closest to ``place`` (NaN if empty)."""
    tr = sim.trajectory
    t = tr.t[(tr.t >= lo) & (tr.t <= hi)]
    if t.size == 0:
        return math.nan
    x, y, _ = tr.pose_at(t)
    d = World(place).distance_to_walls(np.column_stack((x, y)))
    return float(t[int(np.argmin(d))])


def scene_changes(sim: Simulation) -> list[Change]:
    """The changes of the simulation's scene, in time order (module docstring).

    Raises
    ------
    ValueError
        A simulation without a scene.
    """
    if sim.scene is None:
        msg = "scene_changes needs a simulation with a scene"
        raise ValueError(msg)
    t_start, t_stop = float(sim.trajectory.t[0]), float(sim.trajectory.t[-1])
    out: list[Change] = []
    for i, o in enumerate(sim.scene.obstacles):
        if o.moves:
            out += _moving_changes(sim, i, o, t_stop)
            continue
        if t_start < o.appear <= t_stop:
            t_ref = _first_seen(sim, o.segments, o.appear)
            out.append(Change(i, f"{o.name} appeared", "appeared", o.appear, t_ref,
                              min(o.vanish, t_stop), math.nan, o.segments, False))
        if t_start < o.vanish <= t_stop:
            t_ref = _first_seen(sim, o.segments, o.vanish)
            past = _closest_approach(sim, o.segments, t_ref, t_stop)
            out.append(Change(i, f"{o.name} gone", "gone", o.vanish, t_ref, t_stop, past,
                              o.segments, False))
    return sorted(out, key=lambda c: c.t)


def _moving_changes(sim: Simulation, i: int, o: DynamicObstacle, t_stop: float) -> list[Change]:
    f = sim.firings
    rows = np.flatnonzero(o.present(f.t))
    outlines = [o.segments + np.tile(o.offset(float(f.t[r]))[0], 2) for r in rows]
    seen = _seen_points(sim, rows, [_samples(s) for s in outlines])
    if not np.any(seen):
        return []
    first, last = np.flatnonzero(seen)[[0, -1]]
    t_in, t_out = float(f.t[rows[first]]), float(f.t[rows[last]])
    trail = np.vstack([outlines[k] for k in range(first, last + 1)])
    past = _closest_approach(sim, trail, t_out, t_stop)
    return [Change(i, f"{o.name} appeared", "appeared", t_in, t_in, t_out, math.nan,
                   outlines[first], True),
            Change(i, f"{o.name} gone", "gone", t_out, t_out, t_stop, past, trail, False)]


# --------------------------------------------------------------------------------------------
# Maps over time
# --------------------------------------------------------------------------------------------


class _Map(Protocol):
    def feed(self, batch: ReadingBatch) -> None: ...

    def points(self) -> FloatArray: ...


class _MethodMap:
    """A method's local map points."""

    def __init__(self, method: SonarMethod) -> None:
        self.method = method

    def feed(self, batch: ReadingBatch) -> None:
        self.method.add_many(batch)

    def points(self) -> FloatArray:
        return np.asarray(self.method.local_map().xy, dtype=np.float64).reshape(-1, 2)


class _GridMap:
    """A grid's occupied cell centres."""

    def __init__(self, grid: Grid) -> None:
        self.grid = grid

    def feed(self, batch: ReadingBatch) -> None:
        self.grid.add_many(batch)

    def points(self) -> FloatArray:
        rows, cols = np.nonzero(trinary(self.grid) == OCCUPIED)
        xs, ys = self.grid.cell_centers()
        return np.column_stack((xs[cols], ys[rows])).astype(np.float64)


@dataclass(frozen=True, eq=False)
class MapTrack:
    """One map's snapshots over a run.

    Attributes
    ----------
    label : str
        The method's name or the grid's label.
    tolerance : float
        How close to a present surface a point is explained, metres.
    points : list of ndarray, shape (n_k, 2)
        The map's points at each snapshot.
    phantom : ndarray, shape (k,)
        Phantom share at each snapshot (NaN: an empty map).
    latency : ndarray, shape (changes,)
        Seconds from each change's reference time until the map is right (NaN: never).
    cleared_at : ndarray, shape (changes,)
        The time the map became right for good (gone) or first (appeared), seconds (NaN:
        never).
    """

    label: str
    tolerance: float
    points: list[FloatArray]
    phantom: FloatArray
    latency: FloatArray
    cleared_at: FloatArray

    @property
    def mean_phantom(self) -> float:
        """Mean of the phantom share over the snapshots with points."""
        share = self.phantom[np.isfinite(self.phantom)]
        return float(share.mean()) if share.size else math.nan


@dataclass(frozen=True, eq=False)
class SceneRun:
    """A changing scene simulated and mapped by every method and grid.

    Attributes
    ----------
    scene : ChangingScene
    sim : Simulation
    changes : list of Change
    times : ndarray, shape (k,)
        Snapshot times, seconds.
    tracks : list of MapTrack
    resolution : float
        The grids' cell side, metres.
    """

    scene: ChangingScene
    sim: Simulation
    changes: list[Change]
    times: FloatArray
    tracks: list[MapTrack]
    resolution: float

    def track(self, label: str) -> MapTrack:
        """The track of one map by label."""
        for t in self.tracks:
            if t.label == label:
                return t
        msg = f"no map {label!r} in this run"
        raise KeyError(msg)


def simulate_changing_scene(name: str, seed: int, robot: str = "scout2", *,
                            no_echo: bool = False, physics: SonarPhysics = DEFAULT_PHYSICS
                            ) -> tuple[ChangingScene, Simulation]:
    """A built-in changing scene (:func:`~sonarcarve.sim.scene.changing_scene`) driven at the
    default speed and simulated with ``physics`` (default: the default physics); ``no_echo``
    also records the firings that heard nothing (:func:`~sonarcarve.sim.simulate.simulate`)."""
    cs = changing_scene(name)
    sim = simulate(cs.world, load_robot(robot), follow_waypoints(cs.waypoints), seed, physics,
                   scene=cs.scene, no_echo=no_echo)
    return cs, sim


def run_changing_scene(name: str, seed: int, resolution: float = 0.1,
                       methods: Sequence[str] = METHOD_NAMES,
                       grids: Sequence[str] = tuple(GRID_KINDS),
                       period: float = SNAPSHOT_PERIOD, *, no_echo: bool = False,
                       physics: SonarPhysics = DEFAULT_PHYSICS) -> SceneRun:
    """Simulate a changing scene and measure every map on it (module docstring).

    ``no_echo`` feeds the maps the no-echo readings too (free space up to the robot's max
    range); ``grids`` may then also name :data:`NO_ECHO_GRID_KINDS`. ``physics``: the sonar
    model simulated (e.g. ``SonarPhysics(echo_model="amplitude")``, the second model).
    """
    cs, sim = simulate_changing_scene(name, seed, no_echo=no_echo, physics=physics)
    kinds = GRID_KINDS | NO_ECHO_GRID_KINDS
    changes = scene_changes(sim)
    xmin, ymin, xmax, ymax = sim.world.bounds
    bounds = (xmin - 0.5, ymin - 0.5, xmax + 0.5, ymax + 0.5)
    maps: list[tuple[str, float, _Map]] = [
        (m, POINT_TOLERANCE, _MethodMap(make_method(m))) for m in methods]
    maps += [(g, grid_tolerance(resolution), _GridMap(kinds[g](resolution, bounds)))
             for g in grids]
    t0, t1 = float(sim.trajectory.t[0]), float(sim.trajectory.t[-1])
    times = np.asarray(t0 + period * np.arange(1, math.floor((t1 - t0) / period + 1e-9) + 1),
                       dtype=np.float64)
    cut = np.searchsorted(sim.readings.t, times, side="right")
    snaps: list[list[FloatArray]] = [[] for _ in maps]
    lo = 0
    for hi in cut.tolist():
        batch = sim.readings[lo:hi]
        for k, (_, _, m) in enumerate(maps):
            if len(batch):
                m.feed(batch)
            snaps[k].append(m.points())
        lo = hi
    assert sim.scene is not None
    tracks = [measure_track(label, tol, snaps[k], times, sim.world, sim.scene, changes)
              for k, (label, tol, _) in enumerate(maps)]
    return SceneRun(cs, sim, changes, times, tracks, resolution)


def measure_track(label: str, tol: float, points: list[FloatArray], times: FloatArray,
                  world: World, scene: Scene, changes: list[Change]) -> MapTrack:
    """Measure one map's snapshots: phantom share at each, latency of each change.

    Parameters
    ----------
    label : str
        Names the map.
    tol : float
        How close to a present wall or obstacle a point is explained, metres.
    points : list of ndarray, shape (n_k, 2)
        The map's points at each snapshot, metres.
    times : ndarray, shape (k,)
        Snapshot times, increasing, seconds.
    world, scene : World, Scene
        The static walls and the obstacles.
    changes : list of Change
        What to time (:func:`scene_changes`).
    """
    phantom = np.full(times.shape[0], np.nan)
    right = np.zeros((len(changes), times.shape[0]), dtype=bool)
    for k, (tau, p) in enumerate(zip(times.tolist(), points, strict=True)):
        near_wall = world.distance_to_walls(p) <= tol
        explained = near_wall | (scene.distance(p, tau) <= tol)
        if p.shape[0]:
            phantom[k] = float(np.mean(~explained))
        for c, change in enumerate(changes):
            right[c, k] = snapshot_right(change, p, explained, near_wall, scene, tau)
    latency = np.full(len(changes), np.nan)
    cleared = np.full(len(changes), np.nan)
    for c, change in enumerate(changes):
        cleared[c] = change_latency(change, times, right[c])
        latency[c] = cleared[c] - change.t_ref
    return MapTrack(label, tol, points, phantom, np.maximum(latency, 0.0), cleared)


def snapshot_right(change: Change, points: FloatArray, explained: BoolArray,
                   near_wall: BoolArray, scene: Scene, t: float) -> bool:
    """Whether a map's ``points`` (n, 2) are right about ``change`` at time ``t``.

    ``explained``: each point within the tolerance of a wall or obstacle present at ``t``;
    ``near_wall``: of a static wall.

    Examples
    --------
    >>> gone = Change(0, "box gone", "gone", 1.0, 1.0, 9.0, 5.0,
    ...               np.array([[0.0, 0.0, 1.0, 0.0]]), False)
    >>> pts = np.array([[0.5, 0.2], [3.0, 3.0]])
    >>> snapshot_right(gone, pts, np.array([False, True]), np.array([False, True]), Scene(), 2.0)
    False
    >>> snapshot_right(gone, pts, np.array([True, True]), np.array([True, True]), Scene(), 2.0)
    True
    """
    if points.shape[0] == 0:
        return change.kind == "gone"
    if change.kind == "gone":
        suspect = ~explained
        if not np.any(suspect):
            return True
        return not bool(np.any(World(change.place).distance_to_walls(points[suspect])
                               <= PLACE_RADIUS))
    place = scene.obstacles[change.obstacle].segments_at(t) if change.moving else change.place
    if place.shape[0] == 0:
        return False
    mark = ~near_wall
    return bool(np.any(World(place).distance_to_walls(points[mark]) <= PLACE_RADIUS))


def change_latency(change: Change, times: FloatArray, right: BoolArray) -> float:
    """When the map got right about ``change`` (seconds; NaN: never), from snapshots at
    ``times`` (k,) with ``right`` (k,) (module docstring: for good for gone changes, first for
    appeared ones; snapshots from ``t_ref`` to ``t_end``).

    Examples
    --------
    >>> c = Change(0, "box gone", "gone", 1.0, 2.0, 9.0, 5.0, np.zeros((1, 4)), False)
    >>> t = np.arange(0.0, 6.0)
    >>> change_latency(c, t, np.array([1, 1, 0, 1, 0, 1], dtype=bool))
    5.0
    >>> change_latency(c, t, np.array([1, 1, 0, 1, 1, 0], dtype=bool))
    nan
    >>> change_latency(c._replace(kind="appeared"), t, np.array([1, 1, 0, 1, 0, 1], dtype=bool))
    3.0
    """
    window = np.flatnonzero((times >= change.t_ref) & (times <= change.t_end))
    if window.size == 0:
        return math.nan
    ok = right[window]
    if change.kind == "appeared":
        return float(times[window[np.argmax(ok)]]) if np.any(ok) else math.nan
    if not ok[-1]:
        return math.nan
    wrong = np.flatnonzero(~ok)
    k = 0 if wrong.size == 0 else int(wrong[-1]) + 1
    return float(times[window[k]])


# --------------------------------------------------------------------------------------------
# Figure
# --------------------------------------------------------------------------------------------


def plot_changing_scene(run: SceneRun, labels: Sequence[str], change: int,
                        after: float = 3.0) -> Figure:
    """Map snapshots before and after one change, and the phantom share over time.

    Top rows: for each map of ``labels``, its points just before the change and ``after``
    seconds after the robot passes the place (gone changes) or after the change's reference
    (appeared), over the true walls (grey), the obstacle where it was (red dashed) and now.
    Bottom: the phantom share of every map of ``labels`` over the run, the change marked.
    """
    c = run.changes[change]
    scene = run.sim.scene
    assert scene is not None
    t_before = c.t - 0.5 * SNAPSHOT_PERIOD
    start = c.t_past if c.kind == "gone" and math.isfinite(c.t_past) else c.t_ref
    t_after = start + after
    k_before = int(np.clip(np.searchsorted(run.times, t_before, side="right") - 1, 0,
                           run.times.shape[0] - 1))
    k_after = int(np.clip(np.searchsorted(run.times, t_after), 0, run.times.shape[0] - 1))
    import matplotlib.pyplot as plt

    x_lo, y_lo, x_hi, y_hi = run.sim.world.bounds
    aspect = (y_hi - y_lo + 0.6) / (x_hi - x_lo + 0.6)
    panel = 2.6
    fig = plt.figure(figsize=(panel * len(labels), 2 * min(panel * aspect, 6.0) + 2.2),
                     layout="constrained")
    grid = fig.add_gridspec(3, len(labels), height_ratios=[3, 3, 1.4])
    for j, label in enumerate(labels):
        track = run.track(label)
        for i, k in enumerate((k_before, k_after)):
            ax = fig.add_subplot(grid[i, j])
            tau = float(run.times[k])
            plot_walls(run.sim.world.segments, ax, colors="0.45", linewidths=1.0)
            ax.add_collection(_lines(c.place, "#d62728", "--"))
            now, _ = scene.segments_at(tau)
            if now.shape[0]:
                ax.add_collection(_lines(now, "#ff7f0e", "-"))
            p = track.points[k]
            ax.scatter(p[:, 0], p[:, 1], s=4, c="#1f77b4", linewidths=0, zorder=3)
            x, y, _ = run.sim.trajectory.pose_at(tau)
            ax.plot([float(x)], [float(y)], "k^", markersize=5, zorder=4)
            ax.set_xlim(x_lo - 0.3, x_hi + 0.3)
            ax.set_ylim(y_lo - 0.3, y_hi + 0.3)
            ax.set_aspect("equal")
            ax.tick_params(labelsize=7)
            when = "before" if i == 0 else "after"
            ax.set_title(f"{label}: t = {tau:.1f} s ({when})", fontsize=8)
    bottom = fig.add_subplot(grid[2, :])
    for label in labels:
        track = run.track(label)
        bottom.plot(run.times, 100.0 * track.phantom, lw=0.9, label=label)
    for ch in run.changes:
        bottom.axvline(ch.t, color="0.5", lw=0.7, ls=":")
    bottom.set_xlabel("time (s)")
    bottom.set_ylabel("phantom share (%)")
    bottom.legend(fontsize=7, ncol=len(labels), loc="upper left")
    fig.suptitle(f"{run.scene.name}: {c.label} at t = {c.t:.1f} s "
                 f"(seed {run.sim.seed}, grids at {run.resolution:g} m)", fontsize=10)
    return fig


def _lines(segments: FloatArray, color: str, style: str) -> LineCollection:
    from matplotlib.collections import LineCollection

    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 2, 2)
    return LineCollection(list(seg), colors=color, linewidths=1.6, linestyles=style, zorder=2)
