"""Scenarios of the experiments: which world, which drive, which robot, and their simulation.

A :class:`Scenario` is a hashable value that fixes one simulation, so the experiments make each
distinct simulation once (:func:`run_simulation`) and share it between every method run that
needs it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import numpy.typing as npt

from sonarcarve.errors import SonarcarveError
from sonarcarve.robot import load_robot
from sonarcarve.sim.motion import (
    DEFAULT_SPEED,
    follow_waypoints,
    with_localisation_noise,
    with_odometry_drift,
)
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import SonarPhysics
from sonarcarve.sim.world import World
from sonarcarve.typing import FloatArray

__all__ = ["ExperimentError", "Scenario", "build_world", "cut_polyline", "run_simulation"]



class ExperimentError(SonarcarveError):
    """A bad experiment request: unknown experiment name, bad setting."""


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
        Overrides of :class:`~sonarcarve.sim.sonar.SonarPhysics` fields: numbers, or a string
        for ``echo_model`` (``("echo_model", "amplitude")`` simulates the amplitude sonar).
    robot : str
        Robot name.
    odometry_drift : bool
        Stamp the readings with dead-reckoned poses
        (:func:`~sonarcarve.sim.motion.with_odometry_drift` of the path, seeded with ``seed``)
        while echoes still come from the true poses.
    localisation_noise : (position_sigma, heading_sigma, correlation_time), optional
        Stamp the readings with a localiser's poses: the true path plus the Gauss-Markov error
        of :func:`~sonarcarve.sim.motion.with_localisation_noise` (metres, radians, seconds;
        seeded with ``seed``), added on top of the drift when ``odometry_drift`` is set too.
        Echoes still come from the true poses.
    """

    world: str
    seed: int
    path: tuple[tuple[float, float], ...] | None = None
    max_length: float | None = None
    speed: float = DEFAULT_SPEED
    beam_width_deg: float | None = None
    physics: tuple[tuple[str, float | str], ...] = ()
    robot: str = "scout2"
    odometry_drift: bool = False
    localisation_noise: tuple[float, float, float] | None = None


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
    """Simulate ``scenario``: drive its path at its speed and fire the robot's sonar ring.

    Raises
    ------
    ExperimentError
        When the scenario gives no path and its world has no tour.
    """
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
    odometry = with_odometry_drift(trajectory, scenario.seed) if scenario.odometry_drift else None
    if scenario.localisation_noise is not None:
        position_sigma, heading_sigma, correlation_time = scenario.localisation_noise
        odometry = with_localisation_noise(odometry or trajectory, scenario.seed, position_sigma,
                                           heading_sigma, correlation_time)
    return simulate(world, robot, trajectory, scenario.seed, physics=physics, odometry=odometry)
