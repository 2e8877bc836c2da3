"""A sonar simulator with ground truth: worlds, sonar physics and motion (robots are
:mod:`sonarcarve.robot`, shared with the product for sensor mounts)."""

from sonarcarve.sim.amplitude import AmplitudeModel
from sonarcarve.sim.generate import corridor_opening_world, doorway_world, random_world
from sonarcarve.sim.motion import (
    ROBOT_RADIUS,
    Trajectory,
    explore,
    follow_waypoints,
    with_localisation_noise,
    with_odometry_drift,
)
from sonarcarve.sim.scene import (
    CHANGING_SCENES,
    ChangingScene,
    DynamicObstacle,
    Scene,
    changing_scene,
)
from sonarcarve.sim.simulate import Simulation, SonarTruth, simulate
from sonarcarve.sim.sonar import (
    DEFAULT_PHYSICS,
    ECHO_MODELS,
    NO_ECHO,
    PHYSICS_NAMES,
    Echoes,
    EchoKind,
    Firings,
    SonarPhysics,
    SonarPhysicsError,
    fire_sonars,
    named_physics,
)
from sonarcarve.sim.world import World, WorldError, builtin_worlds, load_world

__all__ = [
    "CHANGING_SCENES",
    "DEFAULT_PHYSICS",
    "ECHO_MODELS",
    "NO_ECHO",
    "PHYSICS_NAMES",
    "ROBOT_RADIUS",
    "AmplitudeModel",
    "ChangingScene",
    "DynamicObstacle",
    "EchoKind",
    "Echoes",
    "Firings",
    "Scene",
    "Simulation",
    "SonarPhysics",
    "SonarPhysicsError",
    "SonarTruth",
    "Trajectory",
    "World",
    "WorldError",
    "builtin_worlds",
    "changing_scene",
    "corridor_opening_world",
    "doorway_world",
    "explore",
    "fire_sonars",
    "follow_waypoints",
    "load_world",
    "named_physics",
    "random_world",
    "simulate",
    "with_localisation_noise",
    "with_odometry_drift",
]
