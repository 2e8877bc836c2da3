"""Repeats (geometry/repeats.py): two echoes of one sensor from the point on its line of motion.

Every expected value below is worked out by hand from the geometry (ε = 0.05 m, beams 22.5°
wide, so ±11.25° around the axis).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.geometry.repeats import is_repeat, mark_repeats

EPS = 0.05
HALF = math.radians(11.25)


def _pair(x1: float, y1: float, r1: float, t1: float, x2: float, y2: float, r2: float,
          t2: float) -> bool:
    return bool(is_repeat(x1, y1, r1, t1, HALF, x2, y2, r2, t2, HALF, EPS))


def test_driving_at_a_wall_head_on_is_a_repeat() -> None:
    # Sensor facing +x at (0, 0) hears 3.0 m, then at (1, 0) hears 2.0 m: |P2 - P1| = 1.0 =
    # |r1 - r2|, the circles touch at (3, 0), bearing 0 from both origins: on both axes.
    assert _pair(0.0, 0.0, 3.0, 0.0, 1.0, 0.0, 2.0, 0.0)
    # Within ε: 2.04 m (|1.0 - 0.96| = 0.04 <= 0.05), and symmetric in the two echoes.
    assert _pair(0.0, 0.0, 3.0, 0.0, 1.0, 0.0, 2.04, 0.0)
    assert _pair(1.0, 0.0, 2.04, 0.0, 0.0, 0.0, 3.0, 0.0)
    # Driving away (sensor facing -x, range grows by the distance): touch point behind, at
    # (-2, 0), bearing π from both origins, the beams' axis.
    assert _pair(0.0, 0.0, 2.0, math.pi, 1.0, 0.0, 3.0, math.pi)


def test_more_than_epsilon_off_tangency_is_no_repeat() -> None:
    # |1.0 - |3.0 - 2.1|| = 0.1 > 0.05.
    assert not _pair(0.0, 0.0, 3.0, 0.0, 1.0, 0.0, 2.1, 0.0)


def test_a_tangent_point_outside_a_beam_is_no_repeat() -> None:
    # The same ranges, the robot moving along +x, the sensor facing 30° off the motion: the
    # touch point (3, 0) is at bearing 0, 30° > 11.25° off the axis.
    assert not _pair(0.0, 0.0, 3.0, math.radians(30.0), 1.0, 0.0, 2.0, math.radians(30.0))
    # Facing 10° off: inside (10° < 11.25°).
    assert _pair(0.0, 0.0, 3.0, math.radians(10.0), 1.0, 0.0, 2.0, math.radians(10.0))
    # Inside the first beam only: the second reading turned to 15°.
    assert not _pair(0.0, 0.0, 3.0, 0.0, 1.0, 0.0, 2.0, math.radians(15.0))
    # Range shrank while facing backwards (-x): the touch point (3, 0) is behind the beam.
    assert not _pair(0.0, 0.0, 3.0, math.pi, 1.0, 0.0, 2.0, math.pi)
    # Axis wrapped: facing 359° sees bearing 0 (1° off).
    assert _pair(0.0, 0.0, 3.0, math.radians(359.0), 1.0, 0.0, 2.0, -math.radians(1.0))


def test_origins_two_epsilon_apart_or_nearer_are_no_repeat() -> None:
    # 0.08 m apart (< 2ε = 0.10): the ranges 3.00 and 2.92 touch exactly, but any range change
    # up to 0.13 would fit there: it says nothing. 0.12 m apart (> 0.10): a repeat.
    assert not _pair(0.0, 0.0, 3.0, 0.0, 0.08, 0.0, 2.92, 0.0)
    assert not _pair(0.0, 0.0, 3.0, 0.0, 0.0, 0.0, 3.0, 0.0)  # stood still, same range
    assert _pair(0.0, 0.0, 3.0, 0.0, 0.12, 0.0, 2.88, 0.0)


def test_externally_tangent_circles_are_no_repeat() -> None:
    # Origins 5 m apart, ranges 2 and 3: the circles touch from outside (|P2 - P1| = r1 + r2)
    # at (2, 0), facing each other there; internal tangency would need |r1 - r2| = 5 +- ε.
    assert not _pair(0.0, 0.0, 2.0, 0.0, 5.0, 0.0, 3.0, math.pi)


def test_nan_is_no_repeat() -> None:
    assert not _pair(0.0, 0.0, math.nan, 0.0, 1.0, 0.0, 2.0, 0.0)


def _ring(rows: list[tuple[float, float, float, float, int]]) -> tuple[np.ndarray, ...]:
    x, y, r, theta, sensor = (np.array(column) for column in zip(*rows, strict=True))
    return x, y, r, theta, np.full(len(rows), 2 * HALF), sensor.astype(np.int64)


@pytest.mark.parametrize("blocks", [(5,), (1, 1, 1, 1, 1), (2, 3), (4, 1)])
def test_marks_pairs_of_one_sensor_within_the_window_whatever_the_blocks(
        blocks: tuple[int, ...]) -> None:
    # Arcs 0-4 (storage 10, capacity 3: each arc meets the 2 before it):
    # 0: sensor 0 at (0, 0), 3.0 m facing +x
    # 1: sensor 1 at (0.5, 0), 2.5 m facing +x: tangent to 0, but another sensor
    # 2: sensor 0 at (1, 0), 2.0 m: repeats 0 (2 arcs back)
    # 3: sensor 0 at (9, 9), 1.0 m: nothing
    # 4: sensor 0 at (2, 0), 1.0 m: repeats 0 but 0 is 4 arcs back (out), and 2 is 2 back: yes
    rows = [(0.0, 0.0, 3.0, 0.0, 0), (0.5, 0.0, 2.5, 0.0, 1), (1.0, 0.0, 2.0, 0.0, 0),
            (9.0, 9.0, 1.0, 0.0, 0), (2.0, 0.0, 1.0, 0.0, 0)]
    x, y, r, theta, width, sensor = _ring(rows)
    storage = 10
    pad = [np.zeros(storage - len(rows)) for _ in range(5)]
    x, y, r, theta, width = (np.concatenate([a, b]) for a, b in zip(
        (x, y, r, theta, width), pad, strict=True))
    sensor = np.concatenate([sensor, np.full(storage - len(rows), -1, dtype=np.int64)])
    repeated = np.full(storage, 7.0)  # stale values from arcs that left
    first = 0
    pairs = 0
    for count in blocks:
        pairs += mark_repeats(first, count, 3, x, y, r, theta, width, sensor, repeated, EPS)
        first += count
    assert pairs == 2  # (0, 2) and (2, 4)
    np.testing.assert_array_equal(repeated[:5], [1.0, 0.0, 1.0, 0.0, 1.0])
