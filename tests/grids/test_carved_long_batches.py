"""A whole log in one batch takes the carved grid's vectorised bookkeeping (more than LOOP_BATCH
readings), a robot's few readings the loop: both must leave the same state and the same map."""

from __future__ import annotations

import math

import numpy as np

from sonarcarve.grids import CarvedGrid
from sonarcarve.grids.carved.periods import LOOP_BATCH, FiringPeriods
from sonarcarve.readings import ReadingBatch


def _stream(n: int = 400, seed: int = 3) -> ReadingBatch:
    """A ring of 12 sensors firing in a shuffled order every 0.02 s (give or take 1 ms), some
    silent: each sensor fires every 0.24 s, a period the fit finds."""
    rng = np.random.default_rng(seed)
    order = rng.permutation(12)
    sensor = order[np.arange(n) % 12]
    t = 0.02 * np.arange(n) + rng.uniform(-0.001, 0.001, n)
    theta = 2.0 * math.pi * sensor / 12
    x = 0.01 * np.arange(n) + 0.2 * np.cos(theta)
    y = 0.2 * np.sin(theta)
    r = rng.uniform(0.5, 3.0, n)
    r[rng.random(n) < 0.1] = math.inf
    return ReadingBatch.from_arrays(t=t, sensor=sensor, x=x, y=y, theta=theta, range=r,
                                    max_range=np.full(n, 4.0))


def test_periods_are_the_same_noted_at_once_or_one_by_one() -> None:
    batch = _stream()
    assert len(batch) > LOOP_BATCH
    whole, singles = FiringPeriods(), FiringPeriods()
    whole.note(batch.sensor, batch.t)
    for k in range(len(batch)):
        singles.note(batch.sensor[k:k + 1], batch.t[k:k + 1])
    sensors = np.arange(14, dtype=np.int64)  # 12 and 13 never fired
    np.testing.assert_array_equal(whole.periods(sensors), singles.periods(sensors))
    np.testing.assert_allclose(whole.periods(sensors[:12]), 0.24, atol=0.01)
    assert np.isinf(whole.periods(sensors[12:])).all()


def test_the_grid_is_the_same_fed_whole_or_in_small_blocks() -> None:
    batch = _stream()
    bounds = (-5.0, -5.0, 9.0, 5.0)
    whole, blocks = CarvedGrid(0.1, bounds), CarvedGrid(0.1, bounds)
    whole.add_many(batch)
    for start in range(0, len(batch), 5):
        blocks.add_many(batch[start:start + 5])
    np.testing.assert_array_equal(whole.log_odds, blocks.log_odds)
    np.testing.assert_array_equal(whole.trinary(), blocks.trinary())
