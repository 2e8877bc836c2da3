"""Fixtures of the simulator tests: one room and random firings in it, shared by the sonar
models' whole-simulation tests (specular, amplitude, small reflectors)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from sonarcarve.robot import RobotDescription
from sonarcarve.sim import World
from sonarcarve.sim.sonar import Firings

RandomFirings = Callable[[int, int, RobotDescription], Firings]


@pytest.fixture
def room() -> World:
    """A 10 x 8 m room with a pillar, a partition and a free-standing wall."""
    walls = [
        [0, 0, 10, 0], [10, 0, 10, 8], [10, 8, 0, 8], [0, 8, 0, 0],
        [4, 3, 5, 3], [5, 3, 5, 4], [5, 4, 4, 4], [4, 4, 4, 3],
        [7, 0, 7, 3], [2, 6, 3.5, 5.2],
    ]
    return World(np.array(walls, dtype=float), name="room")


@pytest.fixture
def random_firings(room: World) -> RandomFirings:
    """``random_firings(n, seed, robot)``: up to ``n`` firings of random sensors of ``robot``
    from random poses in ``room`` at least 0.35 m from every wall, 0.04 s apart."""
    def fire(n: int, seed: int, robot: RobotDescription) -> Firings:
        rng = np.random.default_rng(seed)
        points = rng.uniform([0.3, 0.3], [9.7, 7.7], (4 * n, 2))
        points = points[room.distance_to_walls(points) > 0.35][:n]
        heading = rng.uniform(-math.pi, math.pi, points.shape[0])
        sensor = rng.integers(0, robot.n_sensors, points.shape[0])
        sx, sy, theta = robot.sensor_poses(points[:, 0], points[:, 1], heading, sensor)
        return Firings(t=0.04 * np.arange(points.shape[0]), sensor=sensor, x=sx, y=sy,
                       theta=theta)
    return fire
