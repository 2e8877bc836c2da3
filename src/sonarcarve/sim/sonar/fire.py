"""Fire the sonars: trace each firing with its echo model, add spurious echoes, keep the first.

:func:`fire_sonars` draws every random number up front, picks the echo model's tracer from
:data:`_ECHO_MODEL_TRACERS` (``SonarPhysics.echo_model``), adds floor echoes, range noise and
quantisation, and keeps the first echo heard per firing with its truth.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from sonarcarve.robot import RobotDescription
from sonarcarve.sim.scene import Scene
from sonarcarve.sim.sonar.amplitude_tracing import _amplitude_echoes
from sonarcarve.sim.sonar.draws import _Draws
from sonarcarve.sim.sonar.physics import DEFAULT_PHYSICS, SonarPhysics
from sonarcarve.sim.sonar.records import NO_ECHO, Echoes, EchoKind, Firings
from sonarcarve.sim.sonar.scenery import _Scenery
from sonarcarve.sim.sonar.specular import _specular_echoes
from sonarcarve.sim.sonar.spurious import _floor
from sonarcarve.sim.sonar.tracing import _Traced
from sonarcarve.sim.world import World
from sonarcarve.typing import BoolArray, FloatArray, IntArray

__all__ = ["fire_sonars"]


def fire_sonars(
    world: World,
    robot: RobotDescription,
    firings: Firings,
    physics: SonarPhysics | None = None,
    rng: np.random.Generator | None = None,
    on_progress: Callable[[int, int], None] | None = None,
    *,
    scene: Scene | None = None,
) -> Echoes:
    """Simulate every firing: trace its beam, add spurious echoes, keep the first one heard.

    Parameters
    ----------
    world : World
        The walls.
    robot : RobotDescription
        Beam widths, range limits, resolution and firing period of the sensors.
    firings : Firings
        Firing times and true sensor poses, in time order.
    physics : SonarPhysics, optional
        Which effects to simulate and how strongly (default :data:`DEFAULT_PHYSICS`).
    rng : numpy.random.Generator, optional
        Source of randomness (default: seeded with 0). Every random draw is made up front in
        a fixed order, so a seed fixes the output whatever the batching.
    on_progress : callable, optional
        Called as ``on_progress(done, total)`` (firings traced so far) after each batch.
    scene : Scene, optional
        Obstacles that appear, vanish or move (:mod:`sonarcarve.sim.scene`): each firing meets
        the walls plus the obstacles present at its time, at their position then. No draw
        depends on the scene, so a seed gives the same noise with or without one.

    Returns
    -------
    Echoes
        One entry per firing.
    """
    physics = DEFAULT_PHYSICS if physics is None else physics
    gen = np.random.default_rng(0) if rng is None else rng
    n = len(firings)
    draws = _Draws.make(gen, firings, physics)
    scenery = _Scenery.make(world, scene, firings)
    far_range = robot.max_range + physics.sound_speed * _max_gap(firings, physics) / 2.0
    model = _ECHO_MODEL_TRACERS[physics.echo_model]
    traced, crosstalk, multipath = model(scenery, robot, firings, physics, far_range, draws,
                                         gen, on_progress)
    floor = _floor(robot, firings, physics, draws)
    candidates = np.column_stack([traced.direct_range, crosstalk, floor, multipath])
    winner = np.argmin(candidates, axis=1)  # ties go to the lower code: direct first
    true_range = candidates[np.arange(n), winner]
    measured = _measure(true_range + physics.range_noise * draws.noise, robot, physics)
    heard = np.isfinite(true_range) & (measured >= robot.min_range) & (measured <= robot.max_range)
    reflection = _reflections(traced, heard, winner)
    obstacle = (np.full(n, -1, dtype=np.int64) if scene is None
                else scene.obstacle_hit(reflection, firings.t))
    return Echoes(
        range=np.where(heard, measured, np.nan),
        true_range=np.where(heard, true_range, np.nan),
        kind=np.where(heard, winner, NO_ECHO).astype(np.int64),
        reflection=reflection,
        obstacle=obstacle,
    )


_ECHO_MODEL_TRACERS = {"specular": _specular_echoes, "amplitude": _amplitude_echoes}


def _reflections(traced: _Traced, heard: BoolArray, winner: IntArray) -> FloatArray:
    """True reflection point of each heard direct or multipath echo, shape (n, 2), metres.

    NaN rows for floor and crosstalk echoes (no wall point) and for firings not ``heard``;
    ``winner`` is the :class:`EchoKind` code of each firing's echo.
    """
    reflection = np.full((heard.shape[0], 2), np.nan)
    direct = heard & (winner == EchoKind.DIRECT)
    bounced = heard & (winner == EchoKind.MULTIPATH)
    reflection[direct] = traced.direct_point[direct]
    reflection[bounced] = traced.multipath_point[bounced]
    return reflection


def _measure(r: FloatArray, robot: RobotDescription, physics: SonarPhysics) -> FloatArray:
    """Quantise ranges to the robot's resolution (round to nearest) when asked."""
    if physics.quantise and robot.range_resolution > 0.0:
        return np.asarray(np.round(r / robot.range_resolution) * robot.range_resolution)
    return r


def _max_gap(firings: Firings, physics: SonarPhysics) -> float:
    """Longest time back to a firing whose late echoes can still be heard (crosstalk)."""
    lag = physics.crosstalk_lookback
    if physics.crosstalk_probability <= 0.0 or lag == 0 or len(firings) <= lag:
        return 0.0
    return float(np.max(firings.t[lag:] - firings.t[:-lag]))
