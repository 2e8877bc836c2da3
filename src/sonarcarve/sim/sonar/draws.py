"""The random draws of a simulation, made up front in one fixed order.

Drawing everything before any tracing makes a seed fix the output whatever the batching, and
lets the amplitude model add its own draws after these without moving them (its per-candidate
noise is counter-based: :mod:`~sonarcarve.sim.sonar.amplitude_hearing`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sonarcarve.sim.sonar.physics import SonarPhysics
from sonarcarve.sim.sonar.records import Firings
from sonarcarve.typing import FloatArray


@dataclass(frozen=True)
class _Draws:
    """Every random number of a simulation, drawn in one fixed order.

    ``tilt`` is the robot-frame direction the robot tilts towards at each firing (NaN: level).
    """

    noise: FloatArray
    crosstalk: FloatArray
    multipath: FloatArray
    floor_gate: FloatArray
    floor_range: FloatArray
    tilt: FloatArray

    @classmethod
    def make(cls, rng: np.random.Generator, firings: Firings, physics: SonarPhysics) -> _Draws:
        n = len(firings)
        noise = rng.standard_normal(n)
        crosstalk = rng.random(n)
        multipath = rng.random(n)
        floor_gate = rng.random(n)
        floor_range = physics.floor_range + physics.floor_range_sd * rng.standard_normal(n)
        t0, t1 = (float(firings.t[0]), float(firings.t[-1])) if n else (0.0, 0.0)
        count = int(rng.poisson(physics.floor_episode_rate * (t1 - t0)))
        starts = rng.uniform(t0, t1, count)
        ends = starts + rng.exponential(physics.floor_episode_duration, count)
        directions = rng.uniform(-math.pi, math.pi, count)
        tilt = np.full(n, np.nan)
        for start, end, direction in zip(starts, ends, directions, strict=True):
            lo, hi = np.searchsorted(firings.t, [start, end], side="left")
            tilt[lo:hi] = direction
        return cls(noise, crosstalk, multipath, floor_gate, floor_range, tilt)
