"""Laws every registered sonar method must obey, run over every name in ``METHODS``.

New methods are checked the moment they are registered. The stream is a robot driving down a
corridor with a 16-sensor ring (ranges from exact ray casting, plus noise and a few spurious short
echoes), small enough to run every method in well under a second.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve import (
    DEFAULT_BEAM_WIDTH,
    METHODS,
    MethodConfig,
    PointSource,
    ReadingBatch,
    SonarMethod,
    make_method,
    process_readings,
)
from sonarcarve.maps import LocalMap
from sonarcarve.sim.world import World

HISTORY = 120
PHI = DEFAULT_BEAM_WIDTH
NAMES = sorted(METHODS)


def _corridor_stream(seed: int, n: int = 500) -> ReadingBatch:
    """Readings of a robot driving along +x in a 2 m corridor with a doorway on the left."""
    world = World(np.array([[-1.0, -1.0, 12.0, -1.0], [-1.0, 1.0, 4.0, 1.0],
                            [5.0, 1.0, 12.0, 1.0], [4.0, 1.0, 4.0, 3.0], [5.0, 1.0, 5.0, 3.0],
                            [4.0, 3.0, 5.0, 3.0], [-1.0, -1.0, -1.0, 1.0]]))
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    sensor = k % 16
    cx = 0.005 * k
    theta = 0.3 * np.sin(0.05 * k) + 2.0 * math.pi * sensor / 16  # a weaving heading
    x = cx + 0.2 * np.cos(theta)
    y = 0.2 * np.sin(theta)
    distance, _ = world.cast_rays(np.column_stack((x, y)), theta, 6.0)
    r = distance + rng.normal(0.0, 0.01, n)
    spurious = rng.random(n) < 0.05
    r[spurious] = rng.uniform(0.2, 0.6, np.count_nonzero(spurious))
    echo = np.isfinite(r)
    return ReadingBatch.from_arrays(t=0.01 * k[echo], sensor=sensor[echo], x=x[echo], y=y[echo],
                                    theta=theta[echo], range=r[echo])


@pytest.fixture(scope="module")
def stream() -> ReadingBatch:
    return _corridor_stream(0)


def _method(name: str) -> SonarMethod:
    return make_method(name, MethodConfig(history_size=HISTORY))


def _check_points_on_arcs(points: LocalMap, batch: ReadingBatch) -> None:
    """Each point lies on its reading's circle (|p - o| = r) and within its full beam."""
    ids = points.reading_id
    assert np.all(np.isfinite(points.xy))
    dx = points.xy[:, 0] - batch.x[ids]
    dy = points.xy[:, 1] - batch.y[ids]
    np.testing.assert_allclose(np.hypot(dx, dy), batch.range[ids], rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(points.range, batch.range[ids])
    off = np.mod(np.arctan2(dy, dx) - batch.theta[ids] + math.pi, 2.0 * math.pi) - math.pi
    assert np.all(np.abs(off) <= PHI / 2 + 1e-9)
    assert np.all(points.width >= 0.0)
    assert np.all(points.width <= PHI + 1e-9)
    assert np.all(np.isfinite(points.max_error) & (points.max_error >= 0.0))
    assert set(points.source.tolist()) <= {int(s) for s in PointSource}


@pytest.mark.parametrize("name", NAMES)
def test_points_lie_on_their_arcs_within_the_beam(name: str, stream: ReadingBatch) -> None:
    method = _method(name)
    for start in range(0, len(stream), 53):
        method.add_many(stream[start : start + 53], first_id=start)
        _check_points_on_arcs(method.local_map(), stream)
    _check_points_on_arcs(method.finish(), stream)


@pytest.mark.parametrize("name", NAMES)
def test_history_keeps_the_newest_n_in_order(name: str, stream: ReadingBatch) -> None:
    method = _method(name)
    for k in range(len(stream)):
        method.add(stream[k])
        if k % 37 == 0 or k == len(stream) - 1:
            live = method.history.reading_id[method.history.slots()].tolist()
            assert live == list(range(max(0, k + 1 - HISTORY), k + 1))
            local = method.local_map().reading_id
            assert set(local.tolist()) <= set(live)
            assert np.all(np.diff(local) > 0)


@pytest.mark.parametrize("name", NAMES)
def test_global_map_has_one_row_per_surviving_reading_in_order(
    name: str, stream: ReadingBatch
) -> None:
    method = _method(name)
    died: list[int] = []
    method.add_commit_listener(
        lambda history, slots, est: died.extend(history.reading_id[slots[~est.alive]].tolist()))
    method.add_many(stream)
    measures = method.measures()
    global_map = method.finish()
    ids = global_map.reading_id.tolist()
    assert ids == sorted(set(range(len(stream))) - set(died))
    assert len(ids) == len(stream) - measures.fully_carved - measures.split


@pytest.mark.parametrize("name", NAMES)
def test_blocks_give_the_map_of_one_reading_at_a_time(name: str, stream: ReadingBatch) -> None:
    """Blocks of 53 readings (prime to the history's 120, so the history's storage wraps inside
    blocks and blocks straddle every commit) map the stream exactly as one reading at a time:
    the same readings in the same global map, at the same points."""
    single = _method(name)
    for k in range(len(stream)):
        single.add(stream[k])
    blocks = _method(name)
    for start in range(0, len(stream), 53):
        blocks.add_many(stream[start : start + 53], first_id=start)
    one, many = single.finish(), blocks.finish()
    np.testing.assert_array_equal(many.reading_id, one.reading_id)
    np.testing.assert_array_equal(many.xy, one.xy)
    np.testing.assert_array_equal(many.width, one.width)


@pytest.mark.parametrize("name", NAMES)
def test_shares_are_within_zero_and_one(name: str, stream: ReadingBatch) -> None:
    method = _method(name)
    for start in range(0, len(stream), 29):
        method.add_many(stream[start : start + 29], first_id=start)
        assert 0.0 <= method.measures().unprocessed_share <= 1.0
    result = process_readings(stream, _method(name))
    assert 0.0 <= result.mean_unprocessed_share <= 1.0
    assert result.fully_carved + result.split <= len(stream)


@pytest.mark.parametrize("name", NAMES)
def test_a_slot_outside_the_history_or_not_an_integer_is_an_index_error(
        name: str, stream: ReadingBatch) -> None:
    # numpy's rules for every method: compiled estimates do not check their indices, and a slot
    # far past the storage crashed evidence carving's (segmentation fault, review rev16).
    method = _method(name)
    method.add_many(stream[:200])
    storage = method.history.storage_size
    for slot in (storage, storage + 3, 10**7, -storage - 1):
        with pytest.raises(IndexError):
            method.estimates(np.array([0, slot]))
    with pytest.raises(IndexError):
        method.estimates(np.array([1.5]))
    assert len(method.estimates(np.array([0, 1])).xy) == 2


def test_centerline_processes_everything_at_once(stream: ReadingBatch) -> None:
    method = _method("centerline")
    for k in range(60):
        method.add(stream[k])
        assert method.measures().unprocessed_share == 0.0


def _intervals(points: LocalMap, batch: ReadingBatch) -> dict[int, tuple[float, float]]:
    """Each point's carved interval, from its bearing (the middle, eq. 3.6) and width (5.1)."""
    ids = points.reading_id
    bearing = np.arctan2(points.xy[:, 1] - batch.y[ids], points.xy[:, 0] - batch.x[ids])
    # Unwrap next to the sensor axis so that intervals of one arc compare.
    bearing = batch.theta[ids] + np.mod(bearing - batch.theta[ids] + math.pi, 2 * math.pi) - math.pi
    return {int(i): (b - w / 2, b + w / 2)
            for i, b, w in zip(ids, bearing, points.width, strict=True)}


def test_carving_never_widens_an_interval(stream: ReadingBatch) -> None:
    method = _method("carve")
    before: dict[int, tuple[float, float]] = {}
    gone: set[int] = set()
    shrunk = 0
    for k in range(len(stream)):
        method.add(stream[k])
        now = _intervals(method.local_map(), stream)
        live = set(method.history.reading_id[method.history.slots()].tolist())
        for i, (lo, hi) in now.items():
            assert i not in gone  # a removed arc never comes back
            if i in before:
                assert before[i][0] - 1e-9 <= lo <= hi <= before[i][1] + 1e-9
                shrunk += hi - lo < before[i][1] - before[i][0] - 1e-9
        gone |= (set(before) & live) - set(now)
        before = now
    assert shrunk > 0  # the stream does carve
