"""Watched (geometry/evidence/watch.py): how squarely distinct readings looked at an arc.

Expected values are worked out by hand from the geometry; the random cases are checked against
a slow reference written from the module's definition with atan2 (not the kernel's dot
products and acos).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.geometry.evidence import mark_watch
from sonarcarve.methods.evidence import ConfidenceModel, EvidenceMethod, EvidenceModel
from sonarcarve.readings import ReadingBatch

SPACING = 0.25
Row = tuple[float, float, float, float, float, int]  # x, y, r, theta, beam width, sensor


def _watch(rows: list[Row], capacity: int, blocks: tuple[int, ...] | None = None,
           storage: int | None = None) -> np.ndarray:
    """``watch`` of each arc once every row is stored and marked, block by block (one block by
    default), in a ring of ``storage`` rows (twice the rows by default: nothing overwritten)."""
    n = len(rows)
    storage = 2 * n if storage is None else storage
    x, y, r, theta, width = (np.zeros(storage) for _ in range(5))
    sensor = np.full(storage, -1, dtype=np.int64)
    watch = np.full(storage, -7.0)  # garbage: every new arc must reset its own value
    first = 0
    for count in (n,) if blocks is None else blocks:
        for s in range(first, first + count):
            j = s % storage
            x[j], y[j], r[j], theta[j], width[j], sensor[j] = rows[s]
        mark_watch(first, count, capacity, x, y, r, np.cos(theta), np.sin(theta),
                   np.cos(0.5 * width), sensor, watch, SPACING)
        first += count
    return np.array([watch[s % storage] for s in range(n)])


def test_a_neighbour_looking_from_the_same_place_watches_squarely() -> None:
    # Two sensors at the origin, axes 0° and 20°. Arc 0 hears 2 m along 0°: its axis point
    # (2, 0) is 20° off sensor 1's axis, inside a 45° beam (22.5° half), outside a 30° one.
    wide, narrow = math.radians(45.0), math.radians(30.0)
    both = _watch([(0.0, 0.0, 2.0, 0.0, wide, 0), (0.0, 0.0, 2.0, math.radians(20.0), wide, 1)],
                  capacity=2)
    # Each looks at the other's point from the very same origin: angle 0 both ways.
    np.testing.assert_allclose(both, [0.0, 0.0], atol=1e-7)
    apart = _watch([(0.0, 0.0, 2.0, 0.0, narrow, 0),
                    (0.0, 0.0, 2.0, math.radians(20.0), narrow, 1)], capacity=2)
    assert np.all(np.isinf(apart))


def test_the_angle_is_between_the_two_looks_at_the_point() -> None:
    # Arc 0: sensor 0 at (0, 0) facing +y hears 1 m: point (0, 1). Arc 1: sensor 1 at (1, 0)
    # facing 135°, straight at (0, 1); its look (-1, 1) is 45° from arc 0's (0, 1). Arc 1's
    # own point, (1, 0) + (-√½, √½) = (0.293, 0.707), is 16.6° off arc 0's axis: outside
    # arc 0's 15° beam (7.5° half), so arc 1 stays unwatched.
    beam = math.radians(15.0)
    watch = _watch([(0.0, 0.0, 1.0, math.pi / 2, beam, 0),
                    (1.0, 0.0, 1.0, math.radians(135.0), beam, 1)], capacity=2)
    assert watch[0] == pytest.approx(math.radians(45.0))
    assert math.isinf(watch[1])


def test_the_same_sensor_watches_only_from_a_distinct_viewpoint() -> None:
    # Sensor 0 facing +y hears a wall 1 m away from (0, 0) and from (d, 0): the first point
    # (0, 1) is atan(d) off the second beam's axis, inside a 60° beam for d = 0.2 and 0.3.
    beam = math.radians(60.0)
    for d, watched in ((0.2, False), (0.3, True)):  # spacing 0.25 m
        watch = _watch([(0.0, 0.0, 1.0, math.pi / 2, beam, 0),
                        (d, 0.0, 1.0, math.pi / 2, beam, 0)], capacity=2)
        if watched:
            # Each looks at the other's point atan(0.3) = 16.7° off its direction.
            np.testing.assert_allclose(watch, [math.atan(d)] * 2)
        else:
            assert np.all(np.isinf(watch))


def test_only_arcs_within_the_capacity_watch_each_other_and_the_smallest_angle_wins() -> None:
    beam = math.radians(90.0)
    far: Row = (50.0, 50.0, 1.0, 0.0, beam, 9)  # looks at nothing near
    # Arc 0 hears (0, 2) from (0, 0); arc 2 looks at it from (0.5, 0) facing it (its look
    # 14.0° from arc 0's), arc 3 from (1, 0) (26.6°): with capacity 3, arc 3 is 3 arcs after
    # arc 0, out of reach.
    rows: list[Row] = [(0.0, 0.0, 2.0, math.pi / 2, beam, 0), far,
                       (0.5, 0.0, 0.5, math.atan2(2.0, -0.5), beam, 1),
                       (1.0, 0.0, 0.5, math.atan2(2.0, -1.0), beam, 2)]
    assert _watch(rows, capacity=3)[0] == pytest.approx(math.atan(0.25))
    rows[2] = far
    assert math.isinf(_watch(rows, capacity=3)[0])
    assert _watch(rows, capacity=4)[0] == pytest.approx(math.atan(0.5))


def _reference(rows: list[Row], capacity: int) -> np.ndarray:
    """The module's definition, pair by pair, with atan2."""
    def looked(at: Row, by: Row) -> float:
        px = at[0] + at[2] * math.cos(at[3])
        py = at[1] + at[2] * math.sin(at[3])
        bearing = math.atan2(py - by[1], px - by[0])
        off = abs((bearing - by[3] + math.pi) % (2 * math.pi) - math.pi)
        if off > by[4] / 2 or math.hypot(px - by[0], py - by[1]) == 0.0:
            return math.inf
        return abs((bearing - at[3] + math.pi) % (2 * math.pi) - math.pi)

    out = np.full(len(rows), math.inf)
    for j, b in enumerate(rows):
        for i in range(max(0, j - capacity + 1), j):
            a = rows[i]
            if a[5] == b[5] and math.hypot(a[0] - b[0], a[1] - b[1]) < SPACING:
                continue
            out[i] = min(out[i], looked(a, b))
            out[j] = min(out[j], looked(b, a))
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_rings_match_the_reference_whatever_the_blocks(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 60
    rows: list[Row] = [(float(rng.uniform(0, 2)), float(rng.uniform(0, 2)),
                        float(rng.uniform(0.2, 3)), float(rng.uniform(-4, 4)),
                        float(rng.uniform(0.2, 1.5)), int(rng.integers(0, 3)))
                       for _ in range(n)]
    expected = _reference(rows, capacity=8)
    assert np.isfinite(expected).sum() > 10  # the case exercises watched and unwatched arcs
    assert np.isinf(expected).sum() > 3
    np.testing.assert_allclose(_watch(rows, capacity=8), expected, atol=1e-7)
    # In blocks, in a ring of 16 rows (twice the capacity) that wraps: the same bits.
    blocks = (5, 1, 8, 3, 8, 8, 7, 8, 4, 8)
    assert sum(blocks) == n
    ring = _watch(rows, capacity=8, blocks=blocks, storage=16)
    np.testing.assert_array_equal(ring[-8:], _watch(rows, capacity=8)[-8:])


def _wall_readings(second_sensor: bool) -> ReadingBatch:
    """Sensor 0 facing +y drives along a wall 1 m away, 0.1 m and 1 s a reading (22.5° beams):
    each point is 16.7° or more off the axis of its own readings 0.3 m or more away, so none
    watches another. With ``second_sensor``, sensor 1 at the same places faces 100°, 10° from
    the first, and looks at each point from nearly the same direction."""
    n = 12
    xs = 0.1 * np.arange(n)
    sensor = np.zeros(n, dtype=int)
    theta = np.full(n, math.pi / 2)
    if second_sensor:
        xs = np.repeat(xs, 2)
        sensor = np.tile([0, 1], n)
        theta = np.tile([math.pi / 2, math.radians(100.0)], n)
    rng = np.arange(len(xs))
    return ReadingBatch.from_arrays(
        t=rng.astype(float), sensor=sensor, x=xs, y=np.zeros(len(xs)), theta=theta,
        range=1.0 / np.sin(theta), beam_width=np.full(len(xs), math.radians(22.5)))


def _committed_confidence(readings: ReadingBatch, model: ConfidenceModel) -> np.ndarray:
    method = EvidenceMethod(history_size=5, min_confidence=0.0, confidence_model=model)
    method.add_many(readings)
    method.finish()
    return method.global_map().confidence


def test_an_arc_nobody_could_confirm_keeps_the_prior() -> None:
    prior = 1.0 / (1.0 + math.exp(-ConfidenceModel().fresh))
    alone = _committed_confidence(_wall_readings(False), ConfidenceModel())
    np.testing.assert_allclose(alone, prior)
    # Without the rule the same arcs mature to the fitted logit, which reads the missing
    # confirmation as a spurious echo's.
    matured = _committed_confidence(_wall_readings(False), ConfidenceModel(watch_angle=None))
    assert np.all(matured[:6] < 0.5)  # the arcs that left the history mature (the last: fresh)
    # Watched by a second sensor, they mature too.
    watched = _committed_confidence(_wall_readings(True), ConfidenceModel())
    assert not np.allclose(watched, prior)


def test_the_watch_angle_is_checked() -> None:
    from sonarcarve.errors import ConfigError

    with pytest.raises(ConfigError, match="watch_angle"):
        ConfidenceModel(watch_angle=4.0)
    with pytest.raises(ConfigError, match="watch_angle"):
        ConfidenceModel(watch_angle=math.nan)
    assert isinstance(EvidenceMethod().models[0], EvidenceModel)
