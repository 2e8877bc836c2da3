"""maps: the chord error bound, point maps, the global-map sinks and ``global_map()``.

Expected values are written out by hand (or from the paper's formulas with the numbers put in),
never computed by the function under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.maps import (
    CallbackSink,
    CountingSink,
    GlobalMap,
    GlobalMapBuilder,
    LocalMap,
    PointSource,
    chord_error,
)
from sonarcarve.methods import METHODS, CenterlineMethod, MethodConfig, make_method
from sonarcarve.readings import Reading, ReadingBatch

# -- chord_error (eq. 5.2: E_m = θd / 2; eq. 5.3: E_s = 2 r sin(E_m / 2)) -------------------


@pytest.mark.parametrize(("r", "width", "expected"), [
    (2.0, 0.0, 0.0),  # a point: no error
    (1.0, math.pi, 1.4142135623730951),  # E_m = π/2: chord of a quarter circle, √2
    (5.0, 2 * math.pi / 3, 5.0),  # E_m = π/3: 2·5·sin(π/6) = 5
    (2.0, math.pi / 2, 1.5307337294603591),  # E_m = π/4: 4 sin(π/8)
    (3.0, math.pi / 8, 0.5881028419773636),  # the 22.5° Polaroid beam: E_m = π/16, 6 sin(π/32)
    (0.5, math.pi / 3, 0.25881904510252074),  # E_m = π/6: sin(π/12)
])
def test_chord_error_by_hand(r: float, width: float, expected: float) -> None:
    assert float(chord_error(r, width)) == pytest.approx(expected, rel=1e-12, abs=1e-15)


def test_chord_error_is_vectorised_and_linear_in_range() -> None:
    out = chord_error([1.0, 2.0, 4.0], [2 * math.pi / 3] * 3)
    assert out.shape == (3,)
    assert out.dtype == np.float64
    np.testing.assert_allclose(out, [1.0, 2.0, 4.0], rtol=1e-12)


# -- point maps ---------------------------------------------------------------------------------


def _points(kind: type[GlobalMap] | type[LocalMap], ids: list[int],
            sources: list[PointSource] | None = None) -> GlobalMap | LocalMap:
    """A map whose every field is a different function of the id, so mix-ups show."""
    a = np.array(ids, dtype=np.int64)
    src = [PointSource.CENTERLINE] * len(ids) if sources is None else sources
    return kind(reading_id=a, t=0.5 * a, sensor=a % 3, xy=np.column_stack((a + 0.25, -a - 0.5)),
                source=np.array([int(s) for s in src], dtype=np.int8), width=0.01 * a,
                max_error=0.001 * a, range=1.0 + a)


def _assert_ids(points: GlobalMap | LocalMap, ids: list[int]) -> None:
    """Every field of ``points`` is what :func:`_points` gives for ``ids``."""
    assert points.reading_id.tolist() == ids
    assert points.t.tolist() == [0.5 * i for i in ids]
    assert points.sensor.tolist() == [i % 3 for i in ids]
    assert points.xy.tolist() == [[i + 0.25, -i - 0.5] for i in ids]
    assert points.width.tolist() == [0.01 * i for i in ids]
    assert points.max_error.tolist() == [0.001 * i for i in ids]
    assert points.range.tolist() == [1.0 + i for i in ids]


@pytest.mark.parametrize("kind", [GlobalMap, LocalMap])
def test_empty_map_has_every_field_empty(kind: type[GlobalMap]) -> None:
    empty = kind.empty()
    assert type(empty) is kind
    assert len(empty) == 0
    assert empty.xy.shape == (0, 2)
    for name in ("reading_id", "t", "sensor", "source", "width", "max_error", "range"):
        assert getattr(empty, name).shape == (0,)
    assert empty.reading_id.dtype == np.int64
    assert empty.sensor.dtype == np.int64
    assert empty.source.dtype == np.int8
    assert empty.source_labels() == []
    assert empty.count(PointSource.CARVED) == 0


@pytest.mark.parametrize("kind", [GlobalMap, LocalMap])
def test_concatenate_keeps_order_and_type(kind: type[GlobalMap]) -> None:
    joined = kind.concatenate([_points(kind, [4, 5]), _points(kind, []), _points(kind, [0, 9, 2])])
    assert type(joined) is kind
    _assert_ids(joined, [4, 5, 0, 9, 2])
    nothing = kind.concatenate([])
    assert type(nothing) is kind
    assert len(nothing) == 0
    assert nothing.xy.shape == (0, 2)


@pytest.mark.parametrize("kind", [GlobalMap, LocalMap])
def test_select_by_mask_and_by_index(kind: type[GlobalMap]) -> None:
    pts = _points(kind, [10, 11, 12, 13])
    by_mask = pts.select(np.array([True, False, False, True]))
    assert type(by_mask) is kind
    _assert_ids(by_mask, [10, 13])
    by_index = pts.select(np.array([2, 0], dtype=np.int64))
    _assert_ids(by_index, [12, 10])
    _assert_ids(pts, [10, 11, 12, 13])  # the original is untouched


def test_source_labels_and_counts() -> None:
    c, k, a = PointSource.CENTERLINE, PointSource.CARVED, PointSource.ATM
    pts = _points(GlobalMap, [0, 1, 2, 3, 4], [k, c, a, k, k])
    assert pts.source_labels() == ["carved", "centerline", "atm", "carved", "carved"]
    assert (pts.count(c), pts.count(k), pts.count(a)) == (1, 3, 1)


def test_point_source_codes_and_labels_are_the_file_contract() -> None:
    # The codes are stored in arrays and the labels written in the map CSV: both are frozen.
    assert [(int(s), s.label) for s in PointSource] == [
        (0, "centerline"), (1, "carved"), (2, "atm")]


# -- GlobalMapBuilder ---------------------------------------------------------------------------


def test_builder_returns_every_committed_chunk_in_order() -> None:
    builder = GlobalMapBuilder()
    builder.commit(_points(GlobalMap, [0, 1]))
    builder.commit(_points(GlobalMap, [2]))
    builder.commit(_points(GlobalMap, [3, 4, 5]))
    built = builder.build()
    assert type(built) is GlobalMap
    _assert_ids(built, [0, 1, 2, 3, 4, 5])


def test_builder_does_not_forget_on_build() -> None:
    builder = GlobalMapBuilder()
    builder.commit(_points(GlobalMap, [0, 1]))
    builder.commit(_points(GlobalMap, [2]))
    _assert_ids(builder.build(), [0, 1, 2])
    _assert_ids(builder.build(), [0, 1, 2])  # building again gives the same map
    builder.commit(_points(GlobalMap, [3]))
    builder.commit(_points(GlobalMap, [4, 5]))
    _assert_ids(builder.build(), [0, 1, 2, 3, 4, 5])  # later chunks join the earlier ones
    _assert_ids(builder.build(), [0, 1, 2, 3, 4, 5])


def test_builder_ignores_empty_commits() -> None:
    builder = GlobalMapBuilder()
    assert len(builder.build()) == 0
    builder.commit(GlobalMap.empty())
    nothing = builder.build()
    assert type(nothing) is GlobalMap
    assert len(nothing) == 0
    builder.commit(_points(GlobalMap, [7]))
    builder.commit(GlobalMap.empty())
    builder.commit(_points(GlobalMap, [8]))
    builder.commit(GlobalMap.empty())
    _assert_ids(builder.build(), [7, 8])


def test_builder_makes_a_global_map_of_local_points() -> None:
    builder = GlobalMapBuilder()
    builder.commit(_points(LocalMap, [1, 2]))
    built = builder.build()
    assert type(built) is GlobalMap
    _assert_ids(built, [1, 2])


# -- SonarMethod.global_map() mid-stream ----------------------------------------------------


def _reading(k: int) -> Reading:
    """Reading k: sensor at (k, 0); even k look along +x at 1 m, odd k along +y at 2 m."""
    if k % 2 == 0:
        return Reading(t=0.1 * k, sensor=0, x=float(k), y=0.0, theta=0.0, range=1.0)
    return Reading(t=0.1 * k, sensor=1, x=float(k), y=0.0, theta=math.pi / 2, range=2.0)


def _expected_xy(k: int) -> list[float]:
    """Centerline point of :func:`_reading` (eq. 3.3), by hand."""
    return [k + 1.0, 0.0] if k % 2 == 0 else [float(k), 2.0]


def test_global_map_mid_stream_has_the_arcs_that_left_the_history() -> None:
    history = 4
    method = CenterlineMethod(history_size=history)
    assert len(method.global_map()) == 0
    for k in range(3):
        method.add(_reading(k))
    assert len(method.global_map()) == 0  # nothing has left a history that is not yet full
    for k in range(3, 7):
        method.add(_reading(k))
    early = method.global_map()  # 7 readings, 4 kept: readings 0, 1, 2 have left
    assert type(early) is GlobalMap
    assert early.reading_id.tolist() == [0, 1, 2]
    np.testing.assert_allclose(early.xy, [[1.0, 0.0], [1.0, 2.0], [3.0, 0.0]], atol=1e-12)
    for k in range(7, 10):
        method.add(_reading(k))
    n = 10
    mid = method.global_map()  # exactly the first n − h readings, the earlier ones included
    assert mid.reading_id.tolist() == list(range(n - history))
    np.testing.assert_allclose(mid.xy, [[1.0, 0.0], [1.0, 2.0], [3.0, 0.0], [3.0, 2.0],
                                        [5.0, 0.0], [5.0, 2.0]], atol=1e-12)
    assert mid.t.tolist() == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4, 0.5])
    assert mid.sensor.tolist() == [0, 1, 0, 1, 0, 1]
    assert mid.range.tolist() == [1.0, 2.0, 1.0, 2.0, 1.0, 2.0]
    assert method.global_map().reading_id.tolist() == list(range(n - history))  # idempotent
    final = method.finish()
    assert final.reading_id.tolist() == list(range(n))
    np.testing.assert_allclose(final.xy, [_expected_xy(k) for k in range(n)], atol=1e-12)
    assert final.source_labels() == ["centerline"] * n


def test_global_map_across_many_history_turnovers() -> None:
    # Far more readings than the history's storage (2h rows): blocks are committed as rows are
    # reused, and the global map must still hold every one of them once, in order.
    history = 3
    method = CenterlineMethod(history_size=history)
    seen: list[int] = []
    for k in range(40):
        method.add(_reading(k))
        if k % 5 == 4:
            seen = method.global_map().reading_id.tolist()
            assert seen == list(range(max(0, k + 1 - history)))
    final = method.finish()
    assert final.reading_id.tolist() == list(range(40))
    np.testing.assert_allclose(final.xy, [_expected_xy(k) for k in range(40)], atol=1e-12)


# -- other sinks: SonarMethod.set_global_sink ---------------------------------------------------


def test_callback_and_counting_sinks() -> None:
    blocks: list[GlobalMap] = []
    callback, counting = CallbackSink(blocks.append), CountingSink()
    for sink in (callback, counting):
        sink.commit(_points(GlobalMap, [0, 1]))
        sink.commit(GlobalMap.empty())
        sink.commit(_points(GlobalMap, [2]))
    assert [b.reading_id.tolist() for b in blocks] == [[0, 1], [2]]  # no empty block passed on
    assert callback.points == counting.points == 3
    assert counting.by_source.tolist() == [3, 0, 0]  # _points places centerline points


def _room_log(n: int, seed: int = 0) -> ReadingBatch:
    """A robot crossing a 6 m x 4 m room, 8 sensors, ranges to the walls plus noise: enough
    overlap for carving and ATM to act."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    sensor = k % 8
    x, y = 1.0 + 4.0 * k / n, 2.0 + 0.3 * np.sin(k / 50)
    theta = 2 * np.pi * sensor / 8 + 0.1 * rng.standard_normal(n)
    c, s = np.cos(theta), np.sin(theta)
    with np.errstate(divide="ignore"):
        to_x = np.where(c > 0, (6.0 - x) / c, np.where(c < 0, -x / c, np.inf))
        to_y = np.where(s > 0, (4.0 - y) / s, np.where(s < 0, -y / s, np.inf))
    r = np.minimum(to_x, to_y) + 0.01 * rng.standard_normal(n)
    return ReadingBatch.from_arrays(t=0.01 * k, sensor=sensor, x=x, y=y, theta=theta,
                                    range=np.maximum(r, 0.1))


@pytest.mark.parametrize("name", sorted(METHODS))
def test_a_sink_gets_every_point_once_in_reading_order(name: str) -> None:
    batch = _room_log(600)
    config = MethodConfig(history_size=40)
    expected = make_method(name, config)
    expected.add_many(batch[:250])
    expected.add_many(batch[250:])
    whole = expected.finish()
    blocks: list[GlobalMap] = []
    method = make_method(name, config)
    method.set_global_sink(CallbackSink(blocks.append))
    method.add_many(batch[:250])
    for k in range(250, 300):
        method.add(batch[k])
    method.add_many(batch[300:])
    assert type(method.finish()) is GlobalMap
    assert method.committed_points == len(whole) > 0
    streamed = GlobalMap.concatenate(blocks)
    assert np.all(np.diff(streamed.reading_id) > 0)  # once each, in reading order
    for field in ("reading_id", "t", "sensor", "xy", "source", "width", "max_error", "range",
                  "confidence"):
        np.testing.assert_array_equal(getattr(streamed, field), getattr(whole, field), field)


def test_with_a_sink_the_method_keeps_no_map(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(self: GlobalMapBuilder, points: GlobalMap) -> None:
        raise AssertionError("the in-memory builder was used")

    monkeypatch.setattr(GlobalMapBuilder, "commit", refuse)
    method = CenterlineMethod(history_size=3)
    sink = CountingSink()
    method.set_global_sink(sink)
    for k in range(20):
        method.add(_reading(k))
    with pytest.raises(RuntimeError, match="sends its global map to a sink"):
        method.global_map()
    final = method.finish()
    assert len(final) == 0  # the sink has the map
    assert sink.points == method.committed_points == 20


def test_sink_only_before_the_first_reading() -> None:
    method = CenterlineMethod(history_size=3)
    method.add(_reading(0))
    with pytest.raises(RuntimeError, match="fresh method"):
        method.set_global_sink(CountingSink())
    assert method.global_map().reading_id.tolist() == []  # still the in-memory map
    assert method.finish().reading_id.tolist() == [0]
    assert method.committed_points == 1


def test_counting_sink_counts_each_source_apart() -> None:
    counting = CountingSink()
    counting.commit(_points(GlobalMap, [0, 1, 2, 3], [PointSource.CARVED, PointSource.ATM,
                                                      PointSource.ATM, PointSource.CENTERLINE]))
    counting.count(np.array([2, 1, 1, 1], dtype=np.int8))
    # by_source is indexed by code: centerline 0, carved 1, atm 2.
    assert counting.by_source.tolist() == [1, 4, 3]
    assert counting.points == 8


def test_a_confidence_of_the_wrong_length_is_refused() -> None:
    base = _points(LocalMap, [0, 1, 2])
    fields = {name: getattr(base, name) for name in (
        "reading_id", "t", "sensor", "xy", "source", "width", "max_error", "range")}
    with pytest.raises(ValueError, match="confidence has 2 values for 3 points"):
        LocalMap(**fields, confidence=np.array([0.5, 0.5]))
    assert np.isnan(LocalMap(**fields).confidence).tolist() == [True] * 3  # left out: unknown
