"""Drive a robot through a world and record its sonar readings, each with its ground truth.

By default only the firings that heard an echo become readings. With ``no_echo=True`` every
firing does: one that heard nothing is a *no-echo* reading (``range`` = inf, ``max_range`` =
the robot's), whose truth kind is :data:`~sonarcarve.sim.sonar.NO_ECHO` (label ``none``).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from sonarcarve.readings import ReadingBatch
from sonarcarve.robot import RobotDescription
from sonarcarve.sim.motion import Trajectory
from sonarcarve.sim.scene import Scene
from sonarcarve.sim.sonar import (
    DEFAULT_PHYSICS,
    NO_ECHO,
    Echoes,
    EchoKind,
    Firings,
    SonarPhysics,
    fire_sonars,
)
from sonarcarve.sim.world import World, check_seed
from sonarcarve.typing import BoolArray, FloatArray, IntArray

__all__ = ["NO_ECHO_LABEL", "Simulation", "SonarTruth", "simulate"]

#: Truth label of a no-echo reading (kind code :data:`~sonarcarve.sim.sonar.NO_ECHO`).
NO_ECHO_LABEL = "none"



@dataclass(frozen=True, eq=False)
class SonarTruth:
    """Ground truth of each reading, struct of arrays aligned with the readings.

    Attributes
    ----------
    kind : ndarray of int64, shape (n,)
        :class:`~sonarcarve.sim.sonar.EchoKind` code: what produced the reading;
        :data:`~sonarcarve.sim.sonar.NO_ECHO` (-1) for a no-echo reading.
    reflection : ndarray, shape (n, 2)
        True reflection point in the world frame, metres; NaN rows for floor and crosstalk
        echoes, which have none.
    true_range : ndarray, shape (n,)
        Noise-free range of the echo, metres (before noise and quantisation).
    firing : ndarray of int64, shape (n,)
        Row of the reading's firing in :attr:`Simulation.firings`.
    obstacle : ndarray of int64, shape (n,)
        Index in :attr:`Simulation.scene` of the obstacle the echo came from; -1 for a static
        wall, an echo without a reflection point (floor, crosstalk), or no scene.
    """

    kind: IntArray
    reflection: FloatArray
    true_range: FloatArray
    firing: IntArray
    obstacle: IntArray

    def __len__(self) -> int:
        return int(self.kind.shape[0])

    @property
    def labels(self) -> list[str]:
        """Kind of each reading as text: ``direct``, ``crosstalk``, ``floor``, ``multipath``,
        or ``none`` (no echo)."""
        names = {int(kind): kind.label for kind in EchoKind} | {NO_ECHO: NO_ECHO_LABEL}
        return [names[code] for code in self.kind.tolist()]

    @property
    def no_echo(self) -> BoolArray:
        """Readings that heard nothing (kind :data:`~sonarcarve.sim.sonar.NO_ECHO`)."""
        return np.asarray(self.kind == NO_ECHO)

    def counts(self) -> dict[str, int]:
        """Readings per kind, every kind listed (zero included), in :class:`EchoKind` order;
        ``none`` last, only when there are no-echo readings."""
        found = Counter(self.kind.tolist())
        counts = {kind.label: int(found.get(int(kind), 0)) for kind in EchoKind}
        if NO_ECHO in found:
            counts[NO_ECHO_LABEL] = int(found[NO_ECHO])
        return counts


@dataclass(frozen=True, eq=False)
class Simulation:
    """A simulated sonar log and everything needed to judge a map made from it.

    Attributes
    ----------
    readings : ReadingBatch
        One row per echo heard (per firing with ``no_echo``), in time order; origin and axis
        from the true trajectory, or from ``odometry`` when one was given (what the robot
        believes).
    truth : SonarTruth
        Per reading: kind, true reflection point, true range, firing row.
    world, robot, trajectory : World, RobotDescription, Trajectory
        What was simulated; ``trajectory`` is the true motion.
    firings : Firings
        Every firing, heard or not, with its true time and true sensor pose.
    echoes : Echoes
        What each firing heard (NaN range where nothing).
    odometry : Trajectory or None
        The dead-reckoned poses the readings were stamped with, if any.
    physics : SonarPhysics
        The sensor model used.
    seed : int
        The seed: the same seed and inputs give the same simulation.
    scene : Scene or None
        The obstacles that appeared, vanished or moved during the run, if any.
    """

    readings: ReadingBatch
    truth: SonarTruth
    world: World
    robot: RobotDescription
    trajectory: Trajectory
    firings: Firings
    echoes: Echoes
    odometry: Trajectory | None
    physics: SonarPhysics
    seed: int
    scene: Scene | None = None

    def kind_counts(self) -> dict[str, int]:
        """Readings per echo kind (``direct``, ``crosstalk``, ``floor``, ``multipath``)."""
        return self.truth.counts()

    def firings_behind_walls(self) -> int:
        """Firings whose sensor sat on the far side of a wall from the robot's centre.

        The simulator keeps the robot's *disc* (``robot_radius``) clear of walls; a sensor
        mounted outside it (a car's bumper sensors, 2.3 m from its centre, around a 0.9 m
        disc that lets it drive a lane) can pass through a wall, and then fires from inside or
        behind it: readings no real sonar gives. 0 when every mount lies within the disc.
        """
        robot = self.robot
        if float(np.max(np.hypot(robot.mount_x, robot.mount_y))) <= robot.robot_radius:
            return 0
        f = self.firings
        cx, cy, _ = self.trajectory.pose_at(f.t)
        reach = np.hypot(f.x - cx, f.y - cy)
        distance, _ = self.world.cast_rays(np.column_stack((cx, cy)),
                                           np.arctan2(f.y - cy, f.x - cx))
        return int(np.count_nonzero(distance < reach))

    @property
    def firing_reading(self) -> IntArray:
        """Row in :attr:`readings` of each firing's echo, or -1 where it heard nothing."""
        rows = np.full(len(self.firings), -1, dtype=np.int64)
        rows[self.truth.firing] = np.arange(len(self.truth), dtype=np.int64)
        return rows


def simulate(
    world: World,
    robot: RobotDescription,
    trajectory: Trajectory,
    seed: int,
    physics: SonarPhysics = DEFAULT_PHYSICS,
    odometry: Trajectory | None = None,
    *,
    on_progress: Callable[[int, int], None] | None = None,
    scene: Scene | None = None,
    no_echo: bool = False,
) -> Simulation:
    """Fire the robot's sonar ring along a trajectory and record what it hears.

    The sensors fire one at a time in the robot's firing order, one every
    ``robot.firing_period`` seconds, from the trajectory's first time to its last. Each echo
    becomes a reading stamped with the firing time and the sensor's world pose at that time.

    Parameters
    ----------
    world : World
        The walls.
    robot : RobotDescription
        The sonar ring.
    trajectory : Trajectory
        The true motion; echoes are computed from these poses.
    seed : int
        >= 0. Seeds every random draw (noise, spurious echoes): same inputs and seed, same
        output.
    physics : SonarPhysics
        The sensor model (see :class:`~sonarcarve.sim.sonar.SonarPhysics`).
    odometry : Trajectory, optional
        Dead-reckoned poses: when given, readings are stamped with these (what a robot with
        odometry drift would record) while echoes still come from the true poses.
    on_progress : callable, optional
        ``on_progress(done, total)`` in firings, called as the simulation advances.
    scene : Scene, optional
        Obstacles that appear, vanish or move (:mod:`sonarcarve.sim.scene`); each reading's
        truth names the obstacle it came from (:attr:`SonarTruth.obstacle`).
    no_echo : bool
        Also record the firings that heard nothing, as no-echo readings: ``range`` = inf,
        ``max_range`` = ``robot.max_range`` (free space up to there), truth kind
        :data:`~sonarcarve.sim.sonar.NO_ECHO`. Off (the default): echoes only, as before.

    Returns
    -------
    Simulation

    Raises
    ------
    WorldError
        A seed that is not an integer >= 0 (:func:`~sonarcarve.sim.world.check_seed`).
    RobotError
        A trajectory longer than :data:`~sonarcarve.robot.MAX_FIRINGS` firings.
    """
    seed = check_seed(seed)
    times, sensors = robot.firing_schedule(float(trajectory.t[0]), float(trajectory.t[-1]))
    firings = _firings(robot, trajectory, times, sensors)
    echoes = fire_sonars(world, robot, firings, physics, np.random.default_rng(seed), on_progress,
                         scene=scene)
    heard = (np.arange(len(firings), dtype=np.int64) if no_echo
             else np.flatnonzero(echoes.heard))
    # Echoes come from the true poses; readings carry the poses the robot believes it had.
    stamped = firings if odometry is None else _firings(robot, odometry, times, sensors)
    readings = _heard_readings(robot, stamped, echoes, heard, f"simulation of {world.name}")
    return Simulation(readings=readings, truth=_heard_truth(echoes, heard), world=world,
                      robot=robot,
                      trajectory=trajectory, firings=firings, echoes=echoes, odometry=odometry,
                      physics=physics, seed=seed, scene=scene)


def _heard_readings(robot: RobotDescription, stamped: Firings, echoes: Echoes, heard: IntArray,
                   source: str) -> ReadingBatch:
    """The readings of the firings that heard an echo.

    Parameters
    ----------
    robot : RobotDescription
        Supplies each sensor's beam width, radians.
    stamped : Firings
        Time, sensor and sensor pose (metres, radians) to stamp each firing's reading with.
    echoes : Echoes
        What every firing heard; ``range`` in metres.
    heard : ndarray of int64, shape (readings,)
        Indices of the firings to record, increasing: those that heard something, or all
        (a firing that heard nothing becomes a no-echo reading, range inf, ``max_range`` the
        robot's).
    source : str
        Description of where the readings came from.
    """
    sensors = stamped.sensor[heard]
    silent = echoes.kind[heard] == NO_ECHO
    r = echoes.range[heard]
    limit = None
    if silent.any():
        r = np.where(silent, np.inf, r)
        limit = np.where(silent, robot.max_range, np.nan)
    return ReadingBatch.from_arrays(
        t=stamped.t[heard], sensor=sensors, x=stamped.x[heard], y=stamped.y[heard],
        theta=stamped.theta[heard], range=r, beam_width=robot.beam_width[sensors],
        max_range=limit, source=source,
    )


def _heard_truth(echoes: Echoes, heard: IntArray) -> SonarTruth:
    """The ground truth of the firings ``heard`` (indices, shape (readings,)), row per reading."""
    return SonarTruth(kind=echoes.kind[heard], reflection=echoes.reflection[heard],
                      true_range=echoes.true_range[heard], firing=heard.astype(np.int64),
                      obstacle=echoes.obstacle[heard])


def _firings(robot: RobotDescription, trajectory: Trajectory, times: FloatArray,
             sensors: IntArray) -> Firings:
    x, y, heading = trajectory.pose_at(times)
    sx, sy, theta = robot.sensor_poses(x, y, heading, sensors)
    return Firings(t=times, sensor=sensors, x=sx, y=sy, theta=theta)
