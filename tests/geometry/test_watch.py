"""Watched (geometry/evidence/watch.py): did a distinct reading look squarely at an arc?

Expected values are worked out by hand from the geometry; the random cases are checked against
a slow reference written from the module's definition with atan2 (not the kernel's dot
products and acos).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.geometry.evidence import mark_watch
from sonarcarve.methods.evidence import (
    CONFIDENCE_FEATURES,
    ConfidenceModel,
    EvidenceMethod,
    SensorModel,
)
from sonarcarve.readings import ReadingBatch

SPACING = 0.25
Row = tuple[float, float, float, float, float, int]  # x, y, r, theta, beam width, sensor


def _flags(rows: list[Row], capacity: int, angle_deg: float,
           blocks: tuple[int, ...] | None = None,
           storage: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``watched`` (looks within ``angle_deg``) and ``covered`` of each arc once every row is
    stored and marked, block by block (one block by default), in a ring of ``storage`` rows
    (twice the rows by default: nothing overwritten), each read just before its row is reused
    or at the end."""
    n = len(rows)
    storage = 2 * n if storage is None else storage
    x, y, r, theta, width = (np.zeros(storage) for _ in range(5))
    sensor = np.full(storage, -1, dtype=np.int64)
    # Stale: every new arc must reset its own flags.
    watched = np.ones(storage, dtype=bool)
    covering = np.full(storage, 7.0)
    flags: dict[int, tuple[bool, bool]] = {}
    first = 0
    for count in (n,) if blocks is None else blocks:
        for s in range(first, first + count):
            j = s % storage
            if s >= storage:  # the arc this row held is gone: read its flags first
                flags[s - storage] = (bool(watched[j]), float(covering[j]))
            x[j], y[j], r[j], theta[j], width[j], sensor[j] = rows[s]
        mark_watch(first, count, capacity, x, y, r, np.cos(theta), np.sin(theta),
                   np.cos(0.5 * width), sensor, watched, covering, SPACING,
                   math.radians(angle_deg))
        first += count
    for s in range(max(0, n - storage), n):
        flags[s] = (bool(watched[s % storage]), float(covering[s % storage]))
    return (np.array([flags[s][0] for s in range(n)]),
            np.array([flags[s][1] for s in range(n)]))


def _watched(rows: list[Row], capacity: int, angle_deg: float,
             blocks: tuple[int, ...] | None = None, storage: int | None = None) -> np.ndarray:
    """``watched`` of each arc (:func:`_flags`)."""
    return _flags(rows, capacity, angle_deg, blocks, storage)[0]


def _covered(rows: list[Row], capacity: int, blocks: tuple[int, ...] | None = None,
             storage: int | None = None) -> np.ndarray:
    """``covering`` of each arc (:func:`_flags`; it does not depend on the look angle)."""
    return _flags(rows, capacity, 30.0, blocks, storage)[1]


def test_a_neighbour_looking_from_the_same_place_watches_squarely() -> None:
    # Two sensors at the origin, axes 0° and 20°. Arc 0 hears 2 m along 0°: its axis point
    # (2, 0) is 20° off sensor 1's axis, inside a 45° beam (22.5° half), outside a 30° one.
    # Each looks at the other's point from the very same origin: at 0°.
    wide, narrow = math.radians(45.0), math.radians(30.0)
    rows: list[Row] = [(0.0, 0.0, 2.0, 0.0, wide, 0),
                       (0.0, 0.0, 2.0, math.radians(20.0), wide, 1)]
    assert _watched(rows, 2, 1.0).tolist() == [True, True]
    rows = [(0.0, 0.0, 2.0, 0.0, narrow, 0), (0.0, 0.0, 2.0, math.radians(20.0), narrow, 1)]
    assert _watched(rows, 2, 89.0).tolist() == [False, False]


def test_the_angle_is_between_the_two_looks_at_the_point() -> None:
    # Arc 0: sensor 0 at (0, 0) facing +y hears 1 m: point (0, 1). Arc 1: sensor 1 at (1, 0)
    # facing 135°, straight at (0, 1); its look (-1, 1) is 45° from arc 0's (0, 1). Arc 1's
    # own point, (1, 0) + (-√½, √½) = (0.293, 0.707), is 16.6° off arc 0's axis: outside
    # arc 0's 15° beam (7.5° half), so arc 1 is never watched.
    beam = math.radians(15.0)
    rows: list[Row] = [(0.0, 0.0, 1.0, math.pi / 2, beam, 0),
                       (1.0, 0.0, 1.0, math.radians(135.0), beam, 1)]
    assert _watched(rows, 2, 44.0).tolist() == [False, False]
    assert _watched(rows, 2, 46.0).tolist() == [True, False]


def test_the_same_sensor_watches_only_from_a_distinct_viewpoint() -> None:
    # Sensor 0 facing +y hears a wall 1 m away from (0, 0) and from (d, 0): each point is
    # atan(d) off the other beam's axis (inside a 60° beam) and looked at atan(d) off its own
    # direction: 16.7° for d = 0.3, 11.3° for d = 0.2 (nearer than the 0.25 m spacing).
    beam = math.radians(60.0)
    far: list[Row] = [(0.0, 0.0, 1.0, math.pi / 2, beam, 0), (0.3, 0.0, 1.0, math.pi / 2, beam, 0)]
    assert _watched(far, 2, 17.0).tolist() == [True, True]
    assert _watched(far, 2, 16.0).tolist() == [False, False]
    near: list[Row] = [(0.0, 0.0, 1.0, math.pi / 2, beam, 0), (0.2, 0.0, 1.0, math.pi / 2, beam, 0)]
    assert _watched(near, 2, 89.0).tolist() == [False, False]
    # Exactly the spacing apart (0.25 m, exact in binary) is distinct: "at least".
    at: list[Row] = [(0.0, 0.0, 1.0, math.pi / 2, beam, 0), (0.25, 0.0, 1.0, math.pi / 2, beam, 0)]
    assert _watched(at, 2, 89.0).tolist() == [True, True]
    near[1] = (0.2, 0.0, 1.0, math.pi / 2, beam, 1)  # another sensor there: distinct
    assert _watched(near, 2, 12.0).tolist() == [True, True]


def test_only_arcs_within_the_capacity_watch_each_other() -> None:
    beam = math.radians(90.0)
    far: Row = (50.0, 50.0, 1.0, 0.0, beam, 9)  # looks at nothing near
    # Arc 0 hears (0, 2) from (0, 0); arc 2 looks at it from (0.5, 0), facing it (14.0° from
    # arc 0's look), arc 3 from (1, 0) (26.6°): with capacity 3, arc 3 is 3 arcs after arc 0,
    # out of reach.
    rows: list[Row] = [(0.0, 0.0, 2.0, math.pi / 2, beam, 0), far,
                       (0.5, 0.0, 0.5, math.atan2(2.0, -0.5), beam, 1),
                       (1.0, 0.0, 0.5, math.atan2(2.0, -1.0), beam, 2)]
    assert _watched(rows, 3, 20.0)[0]
    rows[2] = far
    assert not _watched(rows, 3, 60.0)[0]
    assert not _watched(rows, 4, 26.0)[0]
    assert _watched(rows, 4, 27.0)[0]


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


def _random_rows(seed: int, n: int) -> list[Row]:
    """``n`` readings of 3 sensors at random in a 2 m square, seeded."""
    rng = np.random.default_rng(seed)
    return [(float(rng.uniform(0, 2)), float(rng.uniform(0, 2)), float(rng.uniform(0.2, 3)),
             float(rng.uniform(-4, 4)), float(rng.uniform(0.2, 1.5)), int(rng.integers(0, 3)))
            for _ in range(n)]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_rings_match_the_reference_whatever_the_blocks(seed: int) -> None:
    n = 60
    rows = _random_rows(seed, n)
    angles = _reference(rows, capacity=8)
    for angle in (20.0, 30.0, 60.0):
        expected = angles <= math.radians(angle)
        assert 5 < expected.sum() < n - 3  # watched and unwatched arcs
        assert np.array_equal(_watched(rows, 8, angle), expected)
    # In blocks, in a ring of 16 rows (twice the capacity) that wraps: the same flags for
    # every arc (review rev7: comparing the last 8 let a kernel skipping the wrapped run pass).
    blocks = (5, 1, 8, 3, 8, 8, 7, 8, 4, 8)
    assert sum(blocks) == n
    for angle in (30.0, 60.0):
        ring = _watched(rows, 8, angle, blocks=blocks, storage=16)
        np.testing.assert_array_equal(ring, angles <= math.radians(angle))


def _wall_readings(second_sensor: bool, step: float = 0.1) -> ReadingBatch:
    """Sensor 0 facing +y drives along a wall 1 m away, ``step`` metres and 1 s a reading, 10°
    beams. Its readings 0.3 m or more apart (distinct: at least 0.25 m) have each other's point
    16.7° or more off their axis, outside the beam, so none watches another; 0.1 m apart they
    support each other (the same sensor heard the wall again), 0.3 m apart they do not. With
    ``second_sensor``, sensor 1, mounted 0.5 m ahead, faces the same wall point at 116.6°: the
    two look at each other's points 26.6° off their direction, and sensor 1 at the other
    places looks at sensor 0's points 21.8-31.0° off (0.4-0.6 m away along the wall)."""
    n = 30 if step < 0.3 else 12
    xs = step * np.arange(n)
    sensor = np.zeros(n, dtype=int)
    theta = np.full(n, math.pi / 2)
    if second_sensor:
        xs = np.column_stack((xs, xs + 0.5)).ravel()
        sensor = np.tile([0, 1], n)
        theta = np.tile([math.pi / 2, math.atan2(1.0, -0.5)], n)
    return ReadingBatch.from_arrays(
        t=np.arange(len(xs), dtype=float), sensor=sensor, x=xs, y=np.zeros(len(xs)),
        theta=theta, range=1.0 / np.sin(theta), beam_width=np.full(len(xs), math.radians(10.0)))


def _committed_confidence(readings: ReadingBatch, model: ConfidenceModel,
                          sensor: SensorModel | None = None) -> np.ndarray:
    method = EvidenceMethod(history_size=5, beam_width=math.radians(10.0), min_confidence=0.0,
                            confidence_model=model, sensor=sensor)
    method.add_many(readings)
    method.finish()
    return method.global_map().confidence


def test_an_arc_nobody_could_confirm_keeps_the_prior() -> None:
    prior = 1.0 / (1.0 + math.exp(-ConfidenceModel().fresh))
    alone = _committed_confidence(_wall_readings(False), ConfidenceModel())
    assert len(alone) == 30
    np.testing.assert_allclose(alone, prior)
    # Never heard again either (0.3 m steps): judged by the fitted model, which drops them.
    unheard = _committed_confidence(_wall_readings(False, step=0.3), ConfidenceModel())
    assert len(unheard) == 12
    assert np.all(unheard[:6] < 0.5)
    # Without the rule the same arcs mature to the fitted logit, which reads the missing
    # confirmation as a spurious echo's (the last ones stay young: the log ends).
    matured = _committed_confidence(_wall_readings(False),
                                    ConfidenceModel(unwatched_prior=False))
    assert np.all(matured[:6] < 0.5)
    # Watched by a second sensor 26.6° off, within the sensor model's 30°, they mature too;
    # not when the model gives a smooth wall nothing past 15°.
    watched = _committed_confidence(_wall_readings(True), ConfidenceModel())
    assert not np.allclose(watched[:10], prior)
    narrow = SensorModel(incidence_full=math.radians(5.0), incidence_zero=math.radians(15.0))
    np.testing.assert_allclose(
        _committed_confidence(_wall_readings(True), ConfidenceModel(), narrow), prior)


def test_a_silent_look_watches_within_its_range() -> None:
    """Sensor 1, 0.5 m ahead, fires silently at each wall point (116.6°, 26.6° off the echo's
    direction, 1.118 m away): a look, when its maximum range reaches the point."""
    prior = 1.0 / (1.0 + math.exp(-ConfidenceModel().fresh))
    echoes = _wall_readings(False)

    def with_silence(max_range: float) -> np.ndarray:
        n = len(echoes)
        rows = {name: np.column_stack((getattr(echoes, name), silent)).ravel()
                for name, silent in (("x", echoes.x + 0.5), ("y", np.zeros(n)),
                                     ("theta", np.full(n, math.atan2(1.0, -0.5))),
                                     ("range", np.full(n, math.inf)),
                                     ("sensor", np.ones(n, dtype=int)),
                                     ("max_range", np.full(n, max_range)))}
        rows["max_range"][::2] = 5.0
        batch = ReadingBatch.from_arrays(
            t=np.arange(2 * n, dtype=float), beam_width=np.full(2 * n, math.radians(10.0)),
            **rows)
        return _committed_confidence(batch, ConfidenceModel())

    assert not np.allclose(with_silence(5.0)[:10], prior)
    np.testing.assert_allclose(with_silence(1.0), prior)  # 1.118 m is beyond its reach


def test_another_sensors_beam_covers_at_any_angle_and_range() -> None:
    # Two sensors at the origin, axes 0° and 20°; arc 0 hears 2 m along 0°, arc 1 0.5 m along
    # 20°. Arc 0's axis point (2, 0) is 20° off sensor 1's axis: inside a 45° beam (22.5°
    # half), beyond arc 1's own range (0.5 m: a covering beam's echo may be nearer); outside a
    # 30° beam (15° half). Arc 1's point is 20° off arc 0's axis likewise.
    wide, narrow = math.radians(45.0), math.radians(30.0)
    rows: list[Row] = [(0.0, 0.0, 2.0, 0.0, wide, 0),
                       (0.0, 0.0, 0.5, math.radians(20.0), wide, 1)]
    assert _covered(rows, 2).tolist() == [True, True]
    rows = [(0.0, 0.0, 2.0, 0.0, narrow, 0), (0.0, 0.0, 0.5, math.radians(20.0), narrow, 1)]
    assert _covered(rows, 2).tolist() == [False, False]
    # One beam wide, one narrow: only the wide one covers the other's point.
    rows = [(0.0, 0.0, 2.0, 0.0, narrow, 0), (0.0, 0.0, 0.5, math.radians(20.0), wide, 1)]
    assert _covered(rows, 2).tolist() == [True, False]


def test_only_another_sensor_covers() -> None:
    # The same sensor 1 m further on, facing the same way with a 90° beam, holds the point in
    # its beam and looks at it squarely (watched), but covers nothing: it is the same sensor.
    beam = math.radians(90.0)
    rows: list[Row] = [(0.0, 0.0, 2.0, math.pi / 2, beam, 0),
                       (1.0, 0.0, 2.0, math.pi / 2, beam, 0)]
    assert _watched(rows, 2, 30.0).tolist() == [True, True]
    assert _covered(rows, 2).tolist() == [False, False]
    rows[1] = (1.0, 0.0, 2.0, math.pi / 2, beam, 1)
    assert _covered(rows, 2).tolist() == [1.0, 1.0]
    # A third reading, of sensor 2, between them: each arc covered by both others' beams.
    rows.append((0.5, 0.0, 2.0, math.pi / 2, beam, 2))
    assert _covered(rows, 3).tolist() == [2.0, 2.0, 2.0]
    assert _covered(rows, 2).tolist() == [1.0, 2.0, 1.0]  # arcs 0 and 2 too far apart


def _covered_reference(rows: list[Row], capacity: int) -> np.ndarray:
    """The module's definition of ``covering``, pair by pair, with atan2."""
    def holds(at: Row, by: Row) -> bool:
        px = at[0] + at[2] * math.cos(at[3])
        py = at[1] + at[2] * math.sin(at[3])
        off = math.atan2(py - by[1], px - by[0]) - by[3]
        return abs((off + math.pi) % (2 * math.pi) - math.pi) <= by[4] / 2

    out = np.zeros(len(rows))
    for j, b in enumerate(rows):
        for i in range(max(0, j - capacity + 1), j):
            a = rows[i]
            if a[5] != b[5]:
                out[i] += holds(a, b)
                out[j] += holds(b, a)
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_rings_cover_as_the_reference_whatever_the_blocks(seed: int) -> None:
    n = 60
    rows = _random_rows(seed, n)
    expected = _covered_reference(rows, capacity=8)
    assert 5 < np.count_nonzero(expected) < n - 3  # covered and lone arcs
    assert expected.max() > 1.0  # some covered more than once
    np.testing.assert_array_equal(_covered(rows, 8), expected)
    blocks = (5, 1, 8, 3, 8, 8, 7, 8, 4, 8)
    np.testing.assert_array_equal(_covered(rows, 8, blocks=blocks, storage=16), expected)


def _alone(readings: ReadingBatch) -> np.ndarray:
    """The ``alone`` feature of every arc of ``readings`` in the history (capacity 100)."""
    method = EvidenceMethod(history_size=100, beam_width=math.radians(10.0), min_confidence=0.0)
    method.add_many(readings)
    slots = method.history.slots()
    return method.features(slots)[:, CONFIDENCE_FEATURES.index("alone")]


def test_the_alone_feature_is_set_where_no_other_sensor_covered_the_arc() -> None:
    # One sensor along the wall: every arc alone. Sensor 1, 0.5 m ahead at 116.6°, looks at
    # each wall point sensor 0 heard (its beam holds it): none alone.
    np.testing.assert_array_equal(_alone(_wall_readings(False)), 1.0)
    np.testing.assert_array_equal(_alone(_wall_readings(True)), 0.0)


def test_a_silent_look_of_another_sensor_covers_within_its_range() -> None:
    echoes = _wall_readings(False)
    n = len(echoes)

    def with_silence(max_range: float, sensor: int) -> np.ndarray:
        rows = {name: np.column_stack((getattr(echoes, name), silent)).ravel()
                for name, silent in (("x", echoes.x + 0.5), ("y", np.zeros(n)),
                                     ("theta", np.full(n, math.atan2(1.0, -0.5))),
                                     ("range", np.full(n, math.inf)),
                                     ("sensor", np.full(n, sensor)),
                                     ("max_range", np.full(n, max_range)))}
        rows["max_range"][::2] = 5.0
        batch = ReadingBatch.from_arrays(
            t=np.arange(2 * n, dtype=float), beam_width=np.full(2 * n, math.radians(10.0)),
            **rows)
        return _alone(batch)

    np.testing.assert_array_equal(with_silence(5.0, 1), 0.0)
    np.testing.assert_array_equal(with_silence(1.0, 1), 1.0)  # 1.118 m is beyond its reach
    np.testing.assert_array_equal(with_silence(5.0, 0), 1.0)  # its own sensor: no cover
