"""Repeats (geometry/repeats.py): two echoes of one sensor from the point on its line of motion.

Every expected value below is worked out by hand from the geometry (ε = 0.05 m, beams 22.5°
wide, so ±11.25° around the axis).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.geometry.repeats import is_repeat, mark_repeats
from sonarcarve.methods.evidence import EvidenceMethod, EvidenceModel
from sonarcarve.readings import Reading, ReadingBatch

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
    # 0.08 m apart (< 2ε = 0.10): the ranges 3.00 and 2.92 touch exactly, but so close the
    # range noise alone could give them (a robot creeping along a wall): it says nothing.
    # 0.12 m apart (> 0.10): a repeat.
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


# Review rev9: each test below fails on a mutation the ones above let through (the ring's
# wrapped run skipped, the window one arc too long, the full beam width as the half width, the
# first beam's width for both, tangency within 2ε, 2ε passed as the tolerance).

Row = tuple[float, float, float, float, float, int]  # x, y, r, theta, beam width, sensor
FULL = 2.0 * HALF
#: Sensor 1, far away: a filler that pairs with nothing.
FAR: Row = (50.0, 50.0, 1.0, 0.0, FULL, 1)


def _marks(rows: list[Row], storage: int, capacity: int, blocks: tuple[int, ...]) -> list[float]:
    """``repeated`` of every arc after storing ``rows`` in a ring of ``storage`` rows block by
    block and marking each block, read as each arc is about to be overwritten (or at the end)."""
    x, y, r, theta = (np.zeros(storage) for _ in range(4))
    width = np.full(storage, FULL)
    sensor = np.full(storage, -1, dtype=np.int64)
    repeated = np.full(storage, 7.0)  # garbage: every new arc must reset its own flag
    marks: dict[int, float] = {}
    first = 0
    for count in blocks:
        for s in range(first, first + count):
            j = s % storage
            if s >= storage:
                marks[s - storage] = float(repeated[j])
            x[j], y[j], r[j], theta[j], width[j], sensor[j] = rows[s]
        mark_repeats(first, count, capacity, x, y, r, theta, width, sensor, repeated, EPS)
        first += count
    assert first == len(rows)
    for s in range(max(0, first - storage), first):
        marks[s] = float(repeated[s % storage])
    return [marks[s] for s in range(len(rows))]


def test_the_window_is_the_capacity_minus_one_arcs_before() -> None:
    # Capacity 3: the history holds an arc and the 2 before it. Arc 3 is 3 after arc 0: out of
    # its window; arc 2 is 2 after: in. The pair (3.0 m at x 0, 2.0 m at x 1) touches head-on.
    a, b = (0.0, 0.0, 3.0, 0.0, FULL, 0), (1.0, 0.0, 2.0, 0.0, FULL, 0)
    for blocks in ((4,), (1, 1, 1, 1), (2, 2)):
        assert _marks([a, FAR, FAR, b], 6, 3, blocks) == [0.0, 0.0, 0.0, 0.0]
    for split in ((3,), (1, 1, 1), (2, 1)):
        assert _marks([a, FAR, b], 6, 3, split) == [1.0, 0.0, 1.0]


def test_pairs_are_found_across_the_ring_wrap() -> None:
    # 6 rows, capacity 3: arcs 6 and 7 sit in rows 0 and 1; arc 7's window (arcs 5, 6) wraps.
    rows = [FAR] * 6 + [(0.0, 0.0, 3.0, 0.0, FULL, 0), (1.0, 0.0, 2.0, 0.0, FULL, 0)]
    for blocks in ((6, 2), (1,) * 8, (3, 3, 1, 1)):
        assert _marks(rows, 6, 3, blocks)[6:] == [1.0, 1.0]


def test_each_echo_is_judged_with_its_own_beam_width() -> None:
    # Both axes 0.2 rad off the line of motion (the touch point at bearing 0): inside a 0.6 rad
    # beam (±0.3), outside a 0.3 rad one (±0.15).
    older = (0.0, 0.0, 3.0, 0.2, 0.6, 0)
    assert _marks([older, (1.0, 0.0, 2.0, 0.2, 0.3, 0)], 4, 2, (2,)) == [0.0, 0.0]
    assert _marks([older, (1.0, 0.0, 2.0, 0.2, 0.6, 0)], 4, 2, (2,)) == [1.0, 1.0]
    assert not is_repeat(0.0, 0.0, 3.0, 0.2, 0.3, 1.0, 0.0, 2.0, 0.2, 0.15, EPS)
    assert not is_repeat(0.0, 0.0, 3.0, 0.2, 0.15, 1.0, 0.0, 2.0, 0.2, 0.3, EPS)


def test_one_and_a_half_epsilon_off_tangency_is_no_repeat() -> None:
    # |1.0 - (3.0 - 2.075)| = 0.075: more than ε, less than 2ε.
    assert not _pair(0.0, 0.0, 3.0, 0.0, 1.0, 0.0, 2.075, 0.0)


def test_evidence_carving_marks_with_its_range_tolerance() -> None:
    # Head-on, 0.2 m a step, the range shrinking 0.125 m a step: k steps apart the circles miss
    # tangency by 0.075 k m, more than ε = 0.05 for every pair (within 2ε for neighbours).
    readings = [Reading(t=0.5 * k, sensor=3, x=0.2 * k, y=0.0, theta=0.0,
                        range=5.0 - 0.125 * k, beam_width=FULL) for k in range(8)]
    method = EvidenceMethod()
    method.add_many(ReadingBatch.from_readings(readings))
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    assert model.range_tolerance == EPS
    np.testing.assert_array_equal(model.repeated[method.history.slots()], 0.0)


def _brute_marks(rows: list[Row]) -> tuple[list[float], int]:
    """Every pair of one sensor judged by :func:`is_repeat` (the window holds every arc)."""
    marks = [0.0] * len(rows)
    pairs = 0
    for j, (xj, yj, rj, tj, wj, sj) in enumerate(rows):
        for i in range(j):
            xi, yi, ri, ti, wi, si = rows[i]
            if si == sj and is_repeat(xi, yi, ri, ti, 0.5 * wi, xj, yj, rj, tj, 0.5 * wj, EPS):
                marks[i] = marks[j] = 1.0
                pairs += 1
    return marks, pairs


def test_marks_every_pair_is_repeat_accepts_at_the_bounds_of_its_tests() -> None:
    # mark_repeats flags candidate rows by squared distances before is_repeat judges them:
    # pairs at the very bounds of is_repeat's tests (|d - |Δr|| = ε, d = 2ε, one float step
    # either side) must get the marks of judging every pair.
    rows: list[Row] = []
    for k, (r1, r2) in enumerate([(3.0, 2.0), (2.5, 2.5 - 2 * EPS), (2.0, 2.0 - 0.5 * EPS),
                                  (1.7, 1.7)]):
        change = r1 - r2
        for edge in (change + EPS, change - EPS, 2.0 * EPS):
            if edge <= 0.0:
                continue
            for d in (np.nextafter(edge, 0.0), edge, np.nextafter(edge, 9.0)):
                x0 = 20.0 * len(rows)  # each pair far from the others
                rows.append((x0, 0.0, r1, 0.0, FULL, k % 2))
                rows.append((x0 + float(d), 0.0, r2, 0.0, FULL, k % 2))
    expected, pairs = _brute_marks(rows)
    assert 0 < pairs < len(rows) // 2  # both sides of the bounds occur
    n = len(rows)
    x, y, r, theta, width = (np.array([row[c] for row in rows] * 2) for c in range(5))
    sensor = np.array([row[5] for row in rows] * 2, dtype=np.int64)
    repeated = np.full(2 * n, 7.0)
    assert mark_repeats(0, n, n, x, y, r, theta, width, sensor, repeated, EPS) == pairs
    assert repeated[:n].tolist() == expected
