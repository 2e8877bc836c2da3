"""The doors a demo tour approaches, and whether each method's local map showed them open.

The paper's Fig. 2: a robot about to drive through a door needs its local map to show the gap
free. For every door the tour approaches, :func:`door_candidates` picks the moment
:data:`~sonarcarve.lab.demo.scenario.APPROACH_DISTANCE` before it; :func:`measure_door` takes
every method's local map then and measures how much of the gap it leaves free.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from sonarcarve.lab import metrics
from sonarcarve.lab.analyses import GAP_DEPTH, passage_clearance
from sonarcarve.lab.demo.scenario import APPROACH_DISTANCE, CLOSEUP_METHODS
from sonarcarve.lab.instrument import ArcTable, RunRecord
from sonarcarve.sim.motion import Trajectory
from sonarcarve.sim.simulate import Simulation
from sonarcarve.typing import FloatArray

__all__ = [
    "DoorApproach",
    "DoorCandidate",
    "LocalView",
    "door_candidates",
    "doors_tell_apart",
    "local_view",
    "measure_door",
    "pick_closeup",
]

#: A door not driven through counts as approached when it is within this angle of the robot's
#: heading (head-on), or of its side (passed by), radians.
_HEAD_ON = math.radians(45.0)
_AHEAD = math.radians(75.0)


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


@dataclass(frozen=True)
class DoorCandidate:
    """A door to look at: ``world.openings[opening]``, once ``readings`` readings are in."""

    opening: int
    readings: int
    how: str


def door_candidates(sim: Simulation) -> list[DoorCandidate]:
    """The doors the tour approaches and the reading count at which to look at each.

    A door the tour drives through is looked at :data:`APPROACH_DISTANCE` metres of driving
    before the crossing; one it does not drive through, when the robot first comes within that
    straight-line distance of the gap's middle with the gap ahead (within 75° of the heading)
    and in sight (no wall in between).
    """
    found: list[DoorCandidate] = []
    for k in range(len(sim.world.openings)):
        candidate = _driven_through(sim, k) or _seen_ahead(sim, k)
        if candidate is not None:
            found.append(candidate)
    found.sort(key=lambda c: c.readings)
    return found


def _driven_through(sim: Simulation, k: int) -> DoorCandidate | None:
    """Door ``k`` looked at :data:`APPROACH_DISTANCE` of driving before the tour crosses it."""
    traj = sim.trajectory
    a, b = sim.world.openings[k]
    crossing = _first_crossing(traj, a, b)
    if crossing is None:
        return None
    goal = float(traj.distance_at(crossing)) - APPROACH_DISTANCE
    before = np.flatnonzero(traj.distance_at(sim.readings.t) <= goal)
    if not before.size:
        return None
    return DoorCandidate(k, int(before[-1]) + 1, "through")


def _seen_ahead(sim: Simulation, k: int) -> DoorCandidate | None:
    """Door ``k`` looked at when first within :data:`APPROACH_DISTANCE`, ahead and in sight."""
    t = sim.readings.t
    x, y, heading = sim.trajectory.pose_at(t)
    a, b = sim.world.openings[k]
    centre = 0.5 * (a + b)
    dx, dy = centre[0] - x, centre[1] - y
    dist = np.hypot(dx, dy)
    off = np.abs((np.arctan2(dy, dx) - heading + math.pi) % (2.0 * math.pi) - math.pi)
    near = np.flatnonzero((dist <= APPROACH_DISTANCE) & (off <= _AHEAD))
    near = near[near < len(t)]
    if not near.size:
        return None
    i = int(near[0])
    hit, _ = sim.world.cast_rays([x[i], y[i]], [math.atan2(dy[i], dx[i])], float(dist[i]))
    if np.isfinite(hit[0]):
        return None  # a wall between the robot and the door
    return DoorCandidate(k, i + 1, "head-on" if off[i] <= _HEAD_ON else "side")


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


def local_view(sim: Simulation, records: Mapping[str, RunRecord], readings: int) -> LocalView:
    """Every method's local map once ``readings`` readings have been added."""
    t = float(sim.readings.t[readings - 1])
    x, y, h = sim.trajectory.pose_at(t)
    maps = {name: rec.local_map(int(np.searchsorted(rec.sample_readings, readings)))
            for name, rec in records.items()}
    return LocalView(readings, t, (float(x), float(y), float(h)), maps)


def measure_door(sim: Simulation, records: Mapping[str, RunRecord],
                 candidate: DoorCandidate) -> DoorApproach:
    """Every method's local map at ``candidate`` and the free width it leaves in the gap."""
    jambs = np.asarray(sim.world.openings[candidate.opening], dtype=np.float64)
    region = metrics.gap_region(jambs[0], jambs[1], GAP_DEPTH)
    clearance = passage_clearance(sim.robot.robot_radius)
    view = local_view(sim, records, candidate.readings)
    free = {name: metrics.free_width(local.xy, region) for name, local in view.maps.items()}
    return DoorApproach(candidate.opening, jambs, candidate.how, view, free,
                        {name: width >= clearance for name, width in free.items()})


def pick_closeup(doors: tuple[DoorApproach, ...]) -> DoorApproach | None:
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


def doors_tell_apart(doors: tuple[DoorApproach, ...]) -> bool:
    """False when the tour approaches doors and every method fig. 4 draws leaves every one of
    them passable: then fig. 4 and the animation would show three open doors (every 1 m door of
    the office tour), and the demo shows Fig. 2's doorway instead (:func:`run_demo`). True
    when some method closes some door, or when there is no door to show."""
    if not doors:
        return True
    return not all(door.passable.get(method, True) for door in doors
                   for method in CLOSEUP_METHODS)
