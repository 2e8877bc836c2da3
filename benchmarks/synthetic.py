"""A fixed, seeded synthetic sonar stream for the benchmarks: a robot circling a ring corridor.

The world is a 12 m x 8 m building with a 8 m x 4 m block in the middle, leaving a 2 m wide ring
corridor. The robot drives around the corridor's centre line at 0.3 m/s with a ring of 16
sensors (radius 0.2 m, 22.5° beams, one reading every 10 ms in turn). Each echo is the nearest
wall over 30 rays spread across the beam (the first return), plus Gaussian range noise, quantised
to one inch; beams that hit nothing within ``max_range`` give no reading. A share of readings can
be replaced by *spurious* echoes (cross-talk: a uniform range short of the true one), which
arc carving should remove.

This is deliberately small and independent of the full simulator in ``sonarcarve.sim``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sonarcarve import DEFAULT_BEAM_WIDTH, ReadingBatch
from sonarcarve.sim.world import World

SENSORS = 16
RING_RADIUS = 0.2  # m, sensor origins around the robot centre
SPEED = 0.3  # m/s
PERIOD = 0.01  # s between readings
RAYS = 30  # rays per beam for the first-return echo
INCH = 0.0254


def ring_corridor() -> World:
    """Outer walls 12 m x 8 m, inner block 8 m x 4 m: a 2 m wide loop."""
    outer = [(0, 0, 12, 0), (12, 0, 12, 8), (12, 8, 0, 8), (0, 8, 0, 0)]
    inner = [(2, 2, 10, 2), (10, 2, 10, 6), (10, 6, 2, 6), (2, 6, 2, 2)]
    return World(np.array(outer + inner, dtype=np.float64), name="ring-corridor")


@dataclass(frozen=True)
class Stream:
    """A synthetic log and its ground truth."""

    batch: ReadingBatch
    world: World
    spurious: npt.NDArray[np.bool_]  # shape (n,): the echo is cross-talk, not a wall


def _loop_pose(distance: npt.NDArray[np.float64]) -> tuple[npt.NDArray[np.float64], ...]:
    """Pose on the corridor's centre line (rectangle 1..11 x 1..7) after ``distance`` metres."""
    corners = np.array([(1.0, 1.0), (11.0, 1.0), (11.0, 7.0), (1.0, 7.0), (1.0, 1.0)])
    legs = np.linalg.norm(np.diff(corners, axis=0), axis=1)
    s = np.mod(distance, legs.sum())
    edges = np.concatenate(([0.0], np.cumsum(legs)))
    leg = np.clip(np.searchsorted(edges, s, side="right") - 1, 0, 3)
    u = (s - edges[leg]) / legs[leg]
    start = corners[leg]
    stop = corners[leg + 1]
    xy = start + u[:, None] * (stop - start)
    heading = np.arctan2(stop[:, 1] - start[:, 1], stop[:, 0] - start[:, 0])
    return xy[:, 0], xy[:, 1], heading


def corridor_stream(
    n_readings: int = 20_000,
    *,
    noise: float = 0.01,
    spurious_share: float = 0.0,
    max_range: float = 6.0,
    seed: int = 0,
    beam_width: float = DEFAULT_BEAM_WIDTH,
) -> Stream:
    """About ``n_readings`` readings (beams with no echo are dropped) of the ring corridor.

    Parameters
    ----------
    noise : float
        Standard deviation of the Gaussian range noise, metres (before 1-inch quantisation).
    spurious_share : float
        Share of readings replaced by a uniform range in ``[0.15 m, true range)``.
    """
    rng = np.random.default_rng(seed)
    world = ring_corridor()
    k = np.arange(n_readings)
    t = k * PERIOD
    sensor = k % SENSORS
    cx, cy, heading = _loop_pose(SPEED * t)
    mount = 2.0 * math.pi * sensor / SENSORS
    theta = heading + mount
    x = cx + RING_RADIUS * np.cos(theta)
    y = cy + RING_RADIUS * np.sin(theta)
    true_range = np.empty(n_readings)
    spread = np.linspace(-0.5 * beam_width, 0.5 * beam_width, RAYS)
    for start in range(0, n_readings, 2000):
        part = slice(start, min(start + 2000, n_readings))
        angles = (theta[part, None] + spread[None, :]).reshape(-1)
        origins = np.repeat(np.column_stack((x[part], y[part])), RAYS, axis=0)
        distance, _ = world.cast_rays(origins, angles, max_range)
        true_range[part] = distance.reshape(-1, RAYS).min(axis=1)
    echo = np.isfinite(true_range)
    # Draw the noise even when σ = 0 so that every noise level gets the same spurious readings.
    measured = true_range + noise * rng.standard_normal(n_readings)
    spurious = echo & (rng.random(n_readings) < spurious_share)
    low = 0.15
    measured[spurious] = rng.uniform(low, np.maximum(true_range[spurious], low + 1e-3))
    measured = np.maximum(np.round(measured / INCH) * INCH, INCH)
    batch = ReadingBatch.from_arrays(
        t=t[echo], sensor=sensor[echo], x=x[echo], y=y[echo], theta=theta[echo],
        range=measured[echo], source="synthetic corridor",
    )
    return Stream(batch=batch, world=world, spurious=spurious[echo])
