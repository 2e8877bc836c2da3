"""Spurious echoes: the specular model's crosstalk, and floor echoes (both models).

Crosstalk: the late echo of a previous ping, heard while another sensor listens. Floor: while
the robot tilts, sensors facing down the tilt hear the floor. (The amplitude model follows its
crosstalk paths by level: :mod:`~sonarcarve.sim.sonar.amplitude_paths`.)
"""

from __future__ import annotations

import numpy as np

from sonarcarve.robot import RobotDescription
from sonarcarve.sim.sonar.draws import _Draws
from sonarcarve.sim.sonar.physics import SonarPhysics
from sonarcarve.sim.sonar.records import Firings
from sonarcarve.sim.sonar.tracing import _Traced
from sonarcarve.typing import FloatArray


def _crosstalk(robot: RobotDescription, firings: Firings, physics: SonarPhysics,
               traced: _Traced) -> FloatArray:
    """Apparent range of the first late echo of a recent ping, per firing (inf: none).

    Sensor k fires at t_k; the ping of an earlier firing j reflects (diffusely) at P on a wall
    at distance d_j and reaches sensor k after travelling d_j + |P − o_k|. Sensor k times it
    from its own firing, so it reads (d_j + |P − o_k|)/2 − c (t_k − t_j)/2.
    """
    n = len(firings)
    best = np.full(n, np.inf)
    if physics.crosstalk_probability <= 0.0:
        return best
    c = physics.sound_speed
    for lag in range(1, min(physics.crosstalk_lookback, n - 1) + 1):
        k = np.arange(lag, n)
        j = k - lag
        px = traced.echo_point[j, :, 0] - firings.x[k, None]
        py = traced.echo_point[j, :, 1] - firings.y[k, None]
        back = np.hypot(px, py)
        apparent = (traced.echo_distance[j] + back) / 2.0 - c * (firings.t[k] - firings.t[j])[
            :, None] / 2.0
        arrival = np.abs(np.angle(np.exp(1j * (np.arctan2(py, px) - firings.theta[k, None]))))
        ok = (np.isfinite(apparent) & (apparent >= robot.min_range)
              & (apparent <= robot.max_range) & (arrival <= physics.crosstalk_acceptance))
        best[k] = np.minimum(best[k], np.min(np.where(ok, apparent, np.inf), axis=1))
    return best


def _floor(robot: RobotDescription, firings: Firings, physics: SonarPhysics,
           draws: _Draws) -> FloatArray:
    """Floor echo range per firing (inf: none): sensors facing down a tilt hear the floor."""
    off = np.abs(np.angle(np.exp(1j * (robot.bearing[firings.sensor] - draws.tilt))))
    facing = np.isfinite(draws.tilt) & (off <= physics.floor_half_angle)
    heard = facing & (draws.floor_gate < physics.floor_probability)
    return np.asarray(np.where(heard, np.maximum(draws.floor_range, 0.0), np.inf))
