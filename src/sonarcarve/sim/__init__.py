"""A sonar simulator with ground truth: worlds, robots, sonar physics and motion."""

from sonarcarve.sim.generate import corridor_opening_world, doorway_world, random_world
from sonarcarve.sim.motion import (
    ROBOT_RADIUS,
    Trajectory,
    explore,
    follow_waypoints,
    with_odometry_drift,
)
from sonarcarve.sim.robot import BUILTIN_ROBOTS, RobotDescription, RobotError, load_robot
from sonarcarve.sim.simulate import Simulation, SonarTruth, simulate
from sonarcarve.sim.sonar import (
    DEFAULT_PHYSICS,
    NO_ECHO,
    Echoes,
    EchoKind,
    Firings,
    SonarPhysics,
    SonarPhysicsError,
    fire_sonars,
)
from sonarcarve.sim.world import World, WorldError, builtin_worlds, load_world

__all__ = [
    "BUILTIN_ROBOTS",
    "DEFAULT_PHYSICS",
    "NO_ECHO",
    "ROBOT_RADIUS",
    "EchoKind",
    "Echoes",
    "Firings",
    "RobotDescription",
    "RobotError",
    "Simulation",
    "SonarPhysics",
    "SonarPhysicsError",
    "SonarTruth",
    "Trajectory",
    "World",
    "WorldError",
    "builtin_worlds",
    "corridor_opening_world",
    "doorway_world",
    "explore",
    "fire_sonars",
    "follow_waypoints",
    "load_robot",
    "load_world",
    "random_world",
    "simulate",
    "with_odometry_drift",
]
