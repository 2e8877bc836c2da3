import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonarcarve.filters import (
    PAPER_MAX_RANGE,
    DropReason,
    FilterError,
    MapFilter,
    ReadingFilter,
    ReadingFilterStream,
    filter_map,
    filter_readings,
    max_error_mask,
    occlusion_mask,
    origins_by_id,
    outlier_mask,
    point_origins,
)
from sonarcarve.maps import GlobalMap, LocalMap, PointSource
from sonarcarve.methods import CenterlineMethod
from sonarcarve.pipeline import process_chunks, process_readings
from sonarcarve.readings import ReadingBatch


def _batch(sensor: list[int], r: list[float]) -> ReadingBatch:
    n = len(r)
    k = np.arange(n)
    return ReadingBatch.from_arrays(t=0.1 * k, sensor=sensor, x=0.01 * k, y=np.zeros(n),
                                    theta=0.3 * k, range=r)


def test_paper_max_range_is_150_inches() -> None:
    assert math.isclose(PAPER_MAX_RANGE, 3.81)


def test_range_filters_drop_by_hand() -> None:
    b = _batch([0, 1, 2, 3, 4], [0.1, 0.5, 3.0, 3.81, 3.82])
    out = filter_readings(b, ReadingFilter(max_range=3.81, min_range=0.2))
    assert out.ids.tolist() == [1, 2, 3]  # 3.81 itself is kept: "farther than" is strict
    assert out.reasons.tolist() == [DropReason.TOO_NEAR, 0, 0, 0, DropReason.TOO_FAR]
    r = out.report
    assert (r.total, r.too_near, r.too_far, r.jumps, r.kept) == (5, 1, 1, 0, 3)


def test_jump_filter_by_hand_with_interleaved_sensors() -> None:
    # sensor 0: 1.0 1.1 3.0 3.0 1.0 1.05   sensor 1: 2.0 2.6 2.7
    sensor = [0, 1, 0, 0, 1, 0, 0, 1, 0]
    r = [1.0, 2.0, 1.1, 3.0, 2.6, 3.0, 1.0, 2.7, 1.05]
    out = filter_readings(_batch(sensor, r), ReadingFilter(jump_threshold=0.5))
    # row 3: 1.1 -> 3.0 jumps; row 4: 2.0 -> 2.6 jumps; row 5 agrees with row 3 (kept although
    # row 3 was dropped); row 6: 3.0 -> 1.0 jumps; row 7 agrees with 2.6; row 8 with 1.0.
    assert out.ids.tolist() == [0, 1, 2, 5, 7, 8]
    assert out.report.jumps == 3


def test_isolated_spike_costs_two_readings_and_a_step_one() -> None:
    spike = filter_readings(_batch([0] * 5, [2.0, 2.0, 4.5, 2.0, 2.0]),
                            ReadingFilter(jump_threshold=1.0))
    assert spike.ids.tolist() == [0, 1, 4]
    step = filter_readings(_batch([0] * 5, [2.0, 2.0, 4.5, 4.5, 4.5]),
                           ReadingFilter(jump_threshold=1.0))
    assert step.ids.tolist() == [0, 1, 3, 4]


def test_range_dropped_reading_is_not_the_previous_for_the_jump_filter() -> None:
    # 9.0 is beyond max range: the jump filter compares 2.1 with 2.0, not with 9.0.
    out = filter_readings(_batch([0, 0, 0], [2.0, 9.0, 2.1]),
                          ReadingFilter(max_range=5.0, jump_threshold=0.5))
    assert out.ids.tolist() == [0, 2]
    assert (out.report.too_far, out.report.jumps) == (1, 0)


def _with_silence(sensor: list[int], r: list[float], listened: float = 6.5) -> ReadingBatch:
    """A batch whose ``inf`` ranges are no-echo readings that listened up to ``listened``."""
    n = len(r)
    k = np.arange(n)
    max_range = [listened if math.isinf(v) else math.nan for v in r]
    return ReadingBatch.from_arrays(t=0.1 * k, sensor=sensor, x=0.01 * k, y=np.zeros(n),
                                    theta=0.3 * k, range=r, max_range=max_range)


def _both_ways(b: ReadingBatch, spec: ReadingFilter) -> list[int]:
    """The kept rows, after checking that the stream and the batch filter agree."""
    stream = ReadingFilterStream(spec)
    reasons = [int(stream.check(reading)) for reading in b]
    out = filter_readings(b, spec)
    assert out.reasons.tolist() == reasons
    return out.ids.tolist()


def test_no_echo_readings_are_no_echo_farther_than_max_range() -> None:
    # A silent firing (free space up to 6.5 m, no point) is not an echo beyond --max-range:
    # dropping it threw away the free space of every no-echo row of a log.
    b = _with_silence([0, 0, 0], [2.0, math.inf, 9.0], listened=10.0)
    assert _both_ways(b, ReadingFilter(max_range=5.0, min_range=0.2)) == [0, 1]


def test_no_echo_reading_is_no_jump_and_not_the_previous_range() -> None:
    # sensor 0: 1.0, silence, 1.05, 3.0: only 3.0 jumps (from 1.05); the silence is kept and
    # the echo after it is compared with the echo before it.
    b = _with_silence([0, 0, 0, 0], [1.0, math.inf, 1.05, 3.0])
    assert _both_ways(b, ReadingFilter(jump_threshold=0.5)) == [0, 1, 2]
    # A jump across the silence is a jump: 3.0 after 1.0 goes (a silence that forgot the
    # echo before it would keep it), and 3.05 after it is compared with 3.0 (a review's case).
    b = _with_silence([0, 0, 0, 0], [1.0, math.inf, 3.0, 3.05])
    assert _both_ways(b, ReadingFilter(jump_threshold=0.5)) == [0, 1, 3]


def test_kept_batch_is_the_input_rows_named_by_ids() -> None:
    rng = np.random.default_rng(3)
    n = 200
    b = ReadingBatch.from_arrays(t=np.arange(n), sensor=rng.integers(0, 4, n), x=rng.normal(size=n),
                                 y=rng.normal(size=n), theta=rng.normal(size=n),
                                 range=rng.uniform(0.1, 6, n))
    out = filter_readings(b, ReadingFilter(max_range=4.0, min_range=0.3, jump_threshold=1.0))
    for name in ("t", "sensor", "x", "y", "theta", "range"):
        np.testing.assert_array_equal(getattr(out.batch, name), getattr(b, name)[out.ids])
    assert len(out.batch) == out.report.kept


@settings(max_examples=60, deadline=None)
@given(
    data=st.lists(st.tuples(st.integers(0, 3), st.floats(0.05, 6.0)), max_size=40),
    max_range=st.none() | st.floats(1.0, 6.0),
    min_range=st.none() | st.floats(0.05, 1.0),
    jump=st.none() | st.floats(0.01, 3.0),
)
def test_stream_and_batch_make_the_same_decisions(
    data: list[tuple[int, float]], max_range: float | None, min_range: float | None,
    jump: float | None,
) -> None:
    b = _batch([s for s, _ in data], [r for _, r in data])
    spec = ReadingFilter(max_range=max_range, min_range=min_range, jump_threshold=jump)
    stream = ReadingFilterStream(spec)
    reasons = [stream.check(reading) for reading in b]
    batch = filter_readings(b, spec)
    assert batch.reasons.tolist() == [int(r) for r in reasons]
    assert stream.report == batch.report


@pytest.mark.parametrize(("kwargs", "text"), [
    ({"max_range": -1.0}, "max_range must be"),
    ({"min_range": math.nan}, "min_range must be"),
    ({"jump_threshold": 0.0}, "jump_threshold must be"),
    ({"max_range": 1.0, "min_range": 2.0}, "exceeds max_range"),
    ({"max_range": True}, "max_range must be a finite number > 0 .metres., got bool"),
])
def test_bad_reading_filter_parameters(kwargs: dict[str, float], text: str) -> None:
    with pytest.raises(FilterError, match=text):
        ReadingFilter(**kwargs)


@pytest.mark.parametrize(("kwargs", "text"), [
    ({"max_error": -0.1}, "max_error must be"),
    ({"outlier_radius": math.inf}, "outlier_radius must be"),
    ({"outlier_radius": 1.0, "outlier_neighbours": 0}, "outlier_neighbours must be"),
    ({"min_confidence": -0.01}, "min_confidence must lie in"),
    ({"min_confidence": 1.01}, "min_confidence must lie in"),
    ({"occlusion_depth": 0.0}, "occlusion_depth must be"),
    ({"occlusion_depth": math.nan}, "occlusion_depth must be"),
    ({"occlusion_depth": True}, "occlusion_depth must be a finite number > 0 .metres., got bool"),
])
def test_bad_map_filter_parameters(kwargs: dict[str, float], text: str) -> None:
    with pytest.raises(FilterError, match=text):
        MapFilter(**kwargs)


def _slow_outliers(xy: np.ndarray, radius: float, k: int) -> np.ndarray:
    keep = np.zeros(len(xy), dtype=bool)
    for i in range(len(xy)):
        others = sum(1 for j in range(len(xy))
                     if j != i and math.dist(xy[i], xy[j]) <= radius)
        keep[i] = others >= k
    return keep


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(0, 60), radius=st.floats(0.05, 2.0),
       k=st.integers(1, 4))
def test_outlier_mask_matches_a_double_loop(seed: int, n: int, radius: float, k: int) -> None:
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 4, (n, 2))
    if n > 3:
        xy[1] = xy[0]  # coincident points count as neighbours of each other
    np.testing.assert_array_equal(outlier_mask(xy, radius, k), _slow_outliers(xy, radius, k))


def test_max_error_mask_keeps_the_threshold_itself() -> None:
    assert max_error_mask([0.0, 0.2, 0.2000001], 0.2).tolist() == [True, True, False]


def _points(kind: type[GlobalMap] | type[LocalMap], xy: list[list[float]],
            err: list[float]) -> GlobalMap | LocalMap:
    n = len(xy)
    return kind(reading_id=np.arange(10, 10 + n), t=np.arange(n, dtype=float),
                sensor=np.zeros(n, np.int64), xy=np.array(xy, dtype=float),
                source=np.full(n, PointSource.CARVED, np.int8), width=np.zeros(n),
                max_error=np.array(err), range=np.ones(n))


@pytest.mark.parametrize("kind", [GlobalMap, LocalMap])
def test_filter_map_thresholds_before_the_outlier_test(kind: type[GlobalMap]) -> None:
    # Point 1 is point 0's only neighbour but is too inaccurate: once it is gone, point 0 is
    # an outlier. Points 2 and 3 vouch for each other.
    pts = _points(kind, [[0, 0], [0.1, 0], [5, 5], [5.1, 5]], [0.01, 0.9, 0.02, 0.03])
    out = filter_map(pts, MapFilter(max_error=0.5, outlier_radius=0.2, outlier_neighbours=1))
    assert type(out.points) is kind
    assert out.points.reading_id.tolist() == [12, 13]
    r = out.report
    assert (r.total, r.max_error, r.outliers, r.kept) == (4, 1, 1, 2)


def test_filter_map_off_changes_nothing() -> None:
    pts = _points(GlobalMap, [[0, 0], [9, 9]], [1.0, 2.0])
    out = filter_map(pts, MapFilter())
    assert out.points.reading_id.tolist() == [10, 11]
    assert not MapFilter().active
    assert out.report.kept == 2


def test_pipeline_keeps_input_rows_as_ids() -> None:
    rng = np.random.default_rng(11)
    n = 300
    b = ReadingBatch.from_arrays(t=np.arange(n) * 0.1, sensor=rng.integers(0, 3, n),
                                 x=rng.normal(size=n), y=rng.normal(size=n),
                                 theta=rng.uniform(-3, 3, n), range=rng.uniform(0.2, 6, n))
    result = process_readings(b, CenterlineMethod(history_size=50),
                              reading_filter=ReadingFilter(max_range=4.0, jump_threshold=2.0))
    ids = result.global_map.reading_id
    expected_drops = result.reading_filter
    assert expected_drops is not None
    assert len(ids) == expected_drops.kept == result.readings
    assert np.all(b.range[ids] <= 4.0)
    assert expected_drops.too_far == int(np.sum(b.range > 4.0))
    # Each centerline point lies on the axis of the input row its id names (section 2-A).
    on_axis = np.column_stack((b.x[ids] + b.range[ids] * np.cos(b.theta[ids]),
                               b.y[ids] + b.range[ids] * np.sin(b.theta[ids])))
    np.testing.assert_allclose(result.global_map.xy, on_axis, atol=1e-9)


def test_pipeline_map_filter_reports_its_drops() -> None:
    n = 40
    k = np.arange(n)
    b = ReadingBatch.from_arrays(t=k * 0.1, sensor=np.zeros(n, int), x=0.05 * k, y=np.zeros(n),
                                 theta=np.full(n, math.pi / 2), range=np.where(k == 20, 4.0, 1.0))
    result = process_readings(b, CenterlineMethod(history_size=10),
                              map_filter=MapFilter(outlier_radius=0.2, outlier_neighbours=1))
    # The points form a row at y = 1 spaced 5 cm, except row 20, alone at y = 4.
    assert result.map_filter is not None
    assert result.map_filter.outliers == 1
    assert 20 not in result.global_map.reading_id.tolist()
    assert len(result.global_map) == n - 1


# -- boundaries, by hand (issue 8): each test fails if a strict comparison turns non-strict ------


def _stream_reasons(b: ReadingBatch, spec: ReadingFilter) -> list[DropReason]:
    stream = ReadingFilterStream(spec)
    return [stream.check(reading) for reading in b]


def test_jump_equal_to_the_threshold_is_kept() -> None:
    # Appendix B: a sensor is ignored when its range varies "by more than a threshold"; the
    # docstring: "changes by more than jump_threshold". Every step here is exactly 0.5 (exact in
    # binary), up and down, so every reading is kept; the last step, 0.5625, is a jump.
    r = [1.0, 1.5, 2.0, 2.5, 2.0, 1.5, 2.0625]
    b = _batch([0] * len(r), r)
    spec = ReadingFilter(jump_threshold=0.5)
    out = filter_readings(b, spec)
    assert out.ids.tolist() == [0, 1, 2, 3, 4, 5]
    assert out.reasons.tolist() == [0, 0, 0, 0, 0, 0, DropReason.JUMP]
    assert out.report.jumps == 1
    assert _stream_reasons(b, spec) == [DropReason.KEPT] * 6 + [DropReason.JUMP]


def test_jump_just_above_the_threshold_is_dropped() -> None:
    # 0.25 -> 0.5 is exactly the threshold 0.25 (kept); 0.5 -> 0.75000001 just above (dropped).
    b = _batch([3, 3, 3], [0.25, 0.5, 0.75000001])
    spec = ReadingFilter(jump_threshold=0.25)
    assert filter_readings(b, spec).ids.tolist() == [0, 1]
    assert _stream_reasons(b, spec) == [DropReason.KEPT, DropReason.KEPT, DropReason.JUMP]


def test_range_filters_keep_their_exact_limits_in_both_forms() -> None:
    # "farther than max_range" and "nearer than min_range" are strict: the limits are kept.
    r = [0.25, 4.0, 0.2499999, 4.0000001]
    b = _batch([0, 1, 2, 3], r)
    spec = ReadingFilter(max_range=4.0, min_range=0.25)
    out = filter_readings(b, spec)
    assert out.ids.tolist() == [0, 1]
    assert (out.report.too_near, out.report.too_far) == (1, 1)
    assert _stream_reasons(b, spec) == [DropReason.KEPT, DropReason.KEPT, DropReason.TOO_NEAR,
                                        DropReason.TOO_FAR]


def test_max_range_equal_to_min_range_keeps_only_that_range() -> None:
    b = _batch([0, 0, 0], [1.0, 0.5, 1.5])
    spec = ReadingFilter(max_range=1.0, min_range=1.0)
    assert filter_readings(b, spec).ids.tolist() == [0]
    assert _stream_reasons(b, spec) == [DropReason.KEPT, DropReason.TOO_NEAR, DropReason.TOO_FAR]


def test_outlier_filter_by_hand() -> None:
    # Seven points (ids 10-16): a square of side 0.5, a pair 0.5 apart and a loner:
    #   id 10 (0, 0)    id 11 (0.5, 0)    id 12 (0, 0.5)    id 13 (0.5, 0.5)
    #   id 14 (3, 3)    id 15 (3.5, 3)    id 16 (9, 0)
    # R = 0.5: each corner of the square has two others at exactly 0.5 (the diagonal, 0.707,
    # is out); 14 and 15 have one each; 16 none.
    xy = [[0, 0], [0.5, 0], [0, 0.5], [0.5, 0.5], [3, 3], [3.5, 3], [9, 0]]
    err = [0.0] * 7
    one = filter_map(_points(GlobalMap, xy, err), MapFilter(outlier_radius=0.5))
    assert one.points.reading_id.tolist() == [10, 11, 12, 13, 14, 15]
    assert (one.report.outliers, one.report.kept) == (1, 6)
    two = filter_map(_points(GlobalMap, xy, err),
                     MapFilter(outlier_radius=0.5, outlier_neighbours=2))
    assert two.points.reading_id.tolist() == [10, 11, 12, 13]
    assert (two.report.outliers, two.report.kept) == (3, 4)
    three = filter_map(_points(GlobalMap, xy, err),
                       MapFilter(outlier_radius=0.5, outlier_neighbours=3))
    assert len(three.points) == 0
    wider = filter_map(_points(GlobalMap, xy, err),
                       MapFilter(outlier_radius=0.75, outlier_neighbours=3))
    assert wider.points.reading_id.tolist() == [10, 11, 12, 13]  # now the diagonal counts
    assert outlier_mask(xy, 0.4999, 1).tolist() == [False] * 7  # just short of every neighbour


def test_max_error_filter_by_hand() -> None:
    pts = _points(LocalMap, [[0, 0], [1, 0], [2, 0], [3, 0]], [0.25, 0.5, 0.5000001, np.inf])
    out = filter_map(pts, MapFilter(max_error=0.5))
    assert type(out.points) is LocalMap
    assert out.points.reading_id.tolist() == [10, 11]  # the threshold itself is kept
    assert (out.report.total, out.report.max_error, out.report.outliers) == (4, 2, 0)


def test_min_confidence_filter_keeps_unknown_and_threshold() -> None:
    base = _points(LocalMap, [[0, 0], [1, 0], [2, 0], [3, 0]], [0.1] * 4)
    pts = dataclasses.replace(base, confidence=np.array([0.9, 0.5, 0.49, np.nan]))
    out = filter_map(pts, MapFilter(min_confidence=0.5))
    assert out.points.reading_id.tolist() == [10, 11, 13]  # NaN: not modelled, kept
    assert (out.report.confidence, out.report.kept) == (1, 3)
    assert MapFilter(min_confidence=0.5).active
    with pytest.raises(FilterError):
        MapFilter(min_confidence=1.5)


def test_min_confidence_accepts_both_ends_of_zero_to_one() -> None:
    # A probability threshold: 0 keeps everything, 1 keeps only certain (and unknown) points.
    pts = dataclasses.replace(_points(LocalMap, [[0, 0], [1, 0], [2, 0]], [0.1] * 3),
                              confidence=np.array([1.0, 0.999, np.nan]))
    assert filter_map(pts, MapFilter(min_confidence=1.0)).points.reading_id.tolist() == [10, 12]
    assert len(filter_map(pts, MapFilter(min_confidence=0.0)).points) == 3


def test_each_map_filter_counts_only_what_it_dropped() -> None:
    # Five points: 10 has a low confidence, 11 a large error, 13 is alone, 12 and 14 vouch for
    # each other. Confidence runs first, then max_error, then the outlier test: 1 + 1 + 1.
    pts = dataclasses.replace(
        _points(GlobalMap, [[0, 0], [0.1, 0], [5, 5], [9, 9], [5.1, 5]], [0.01, 0.9, 0.01, 0.01,
                                                                            0.01]),
        confidence=np.array([0.1, 0.9, 0.9, 0.9, 0.9]))
    out = filter_map(pts, MapFilter(min_confidence=0.5, max_error=0.5, outlier_radius=0.2))
    assert out.points.reading_id.tolist() == [12, 14]
    r = out.report
    assert (r.total, r.confidence, r.max_error, r.outliers, r.kept) == (5, 1, 1, 1, 2)


# -- the occlusion filter ------------------------------------------------------------------------

def _behind_a_wall() -> tuple[GlobalMap, np.ndarray]:
    """A wall of 21 points at x = 1 heard head-on from x = 0 (ids 10-30), and a point at x = 2
    heard from the origin through it (id 31): the multipath echo to drop."""
    wall_y = np.linspace(-0.5, 0.5, 21)
    xy = [[1.0, y] for y in wall_y] + [[2.0, 0.0]]
    pts = _points(GlobalMap, xy, [0.01] * 22)
    origins = np.array([[0.0, y] for y in wall_y] + [[0.0, 0.0]])
    return pts, origins


def test_occlusion_filter_drops_the_point_behind_a_wall() -> None:
    pts, origins = _behind_a_wall()
    out = filter_map(pts, MapFilter(occlusion_depth=0.5), origins)
    assert 31 not in out.points.reading_id.tolist()
    assert (out.report.occluded, out.report.kept) == (1, 21)
    assert MapFilter(occlusion_depth=0.5).active
    # Deeper than the point lies behind the wall (1 m): nothing dropped.
    assert filter_map(pts, MapFilter(occlusion_depth=1.0), origins).report.occluded == 0
    assert occlusion_mask(pts.xy, origins, pts.max_error).tolist() == [True] * 21 + [False]
    # A wall whose points' error bounds exceed half the depth hides nothing: such points may
    # stand anywhere within their bound.
    vague = dataclasses.replace(pts, max_error=np.r_[np.full(21, 0.26), 0.01])
    assert filter_map(vague, MapFilter(occlusion_depth=0.5), origins).report.occluded == 0
    assert filter_map(vague, MapFilter(occlusion_depth=0.6), origins).report.occluded == 1


def test_occlusion_runs_after_confidence_and_error_and_before_outliers() -> None:
    pts, origins = _behind_a_wall()
    # A wall the confidence filter drops hides nothing.
    doubtful = dataclasses.replace(pts, confidence=np.r_[np.full(21, 0.1), 0.9])
    out = filter_map(doubtful, MapFilter(min_confidence=0.5, occlusion_depth=0.5), origins)
    assert (out.report.confidence, out.report.occluded) == (21, 0)
    # The same with the error filter.
    inaccurate = dataclasses.replace(pts, max_error=np.r_[np.full(21, 0.9), 0.01])
    out = filter_map(inaccurate, MapFilter(max_error=0.5, occlusion_depth=0.5), origins)
    assert (out.report.max_error, out.report.occluded) == (21, 0)
    # A hidden point vouches for no neighbour: its only one, 0.6 m away and heard from the
    # other side (not hidden), becomes an outlier; without the occlusion filter both stay.
    pair = GlobalMap.concatenate([pts, _points(GlobalMap, [[2.0, 0.6]], [0.01])])
    pair = dataclasses.replace(pair, reading_id=np.arange(10, 33))
    both = np.vstack([origins, [[3.0, 0.6]]])
    out = filter_map(pair, MapFilter(occlusion_depth=0.5, outlier_radius=0.65), both)
    assert (out.report.occluded, out.report.outliers, out.report.kept) == (1, 1, 21)
    out = filter_map(pair, MapFilter(outlier_radius=0.65), both)
    assert (out.report.outliers, out.report.kept) == (0, 23)


def test_occlusion_filter_needs_origins_of_the_right_shape() -> None:
    pts, origins = _behind_a_wall()
    with pytest.raises(FilterError, match="needs each point's sensor origin"):
        filter_map(pts, MapFilter(occlusion_depth=0.5))
    with pytest.raises(FilterError, match=r"must have shape \(22, 2\)"):
        filter_map(pts, MapFilter(occlusion_depth=0.5), origins[:-1])
    with pytest.raises(FilterError, match=r"must have shape \(22, 2\)"):  # filter off too
        filter_map(pts, MapFilter(max_error=0.5), origins[:-1])
    bad = origins.copy()
    bad[3, 0] = math.nan
    with pytest.raises(FilterError, match="needs finite points and origins"):
        filter_map(pts, MapFilter(occlusion_depth=0.5), bad)
    with pytest.raises(FilterError, match="an error bound"):
        occlusion_mask(pts.xy, origins, pts.max_error[:-1])
    with pytest.raises(FilterError, match=r"must have shape \(22, 2\) for 22 points: "):
        filter_map(pts, MapFilter(occlusion_depth=0.5), [[0.0, 0.0], [1.0]])  # ragged
    with pytest.raises(FilterError, match="depth must be a finite number > 0"):
        occlusion_mask(pts.xy, origins, pts.max_error, depth=-0.5)
    empty = filter_map(pts.select(np.zeros(22, dtype=bool)), MapFilter(occlusion_depth=0.5), [])
    assert (empty.report.total, empty.report.kept) == (0, 0)


def test_origins_follow_their_points_through_the_earlier_filters() -> None:
    # A first point the error filter drops. The wall's last point is heard from across the
    # wall (x = 3): if the origins were not dropped with the first point, the point behind the
    # wall would take that origin, from which nothing hides it.
    pts, origins = _behind_a_wall()
    origins[20] = [3.0, 0.5]
    both = GlobalMap.concatenate([_points(GlobalMap, [[5.0, 5.0]], [0.9]), pts])
    both = dataclasses.replace(both, reading_id=np.arange(9, 32))
    out = filter_map(both, MapFilter(max_error=0.5, occlusion_depth=0.5),
                     np.vstack([[[5.0, 6.0]], origins]))
    assert out.points.reading_id.tolist() == list(range(10, 31))
    assert (out.report.max_error, out.report.occluded) == (1, 1)


def test_point_origins_looks_points_up_by_reading_id() -> None:
    n = 6
    b = ReadingBatch.from_arrays(t=np.arange(n) * 0.1, sensor=np.zeros(n, int),
                                 x=np.arange(n) * 1.0, y=-np.arange(n) * 1.0,
                                 theta=np.zeros(n), range=np.ones(n))
    pts = dataclasses.replace(_points(GlobalMap, [[0, 0], [1, 1]], [0.1, 0.1]),
                              reading_id=np.array([4, 1]), t=np.array([0.4, 0.1]))
    np.testing.assert_array_equal(point_origins(pts, b), [[4.0, -4.0], [1.0, -1.0]])
    # With ids of their own (a filtered log keeps input rows), not positions.
    renumbered = dataclasses.replace(pts, t=np.array([0.1, 0.3]))
    np.testing.assert_array_equal(point_origins(renumbered, b, reading_ids=[7, 4, 9, 1, 3, 0]),
                                  [[1.0, -1.0], [3.0, -3.0]])
    with pytest.raises(FilterError, match="reading id 4 has no reading"):
        origins_by_id([4], [0, 1, 2], [0.0, 1.0, 2.0], [0.0, 1.0, 2.0])
    with pytest.raises(FilterError, match="reading id 9 has no reading"):
        origins_by_id([9], [0, 1, 2], [0.0, 1.0, 2.0], [0.0, 1.0, 2.0])
    with pytest.raises(FilterError, match="must be unique"):
        origins_by_id([1], [0, 1, 1], [0.0, 1.0, 2.0], [0.0, 1.0, 2.0])
    # Readings the map was not made from: a point's time, or its sensor, is not its reading's.
    moved = dataclasses.replace(pts, t=np.array([0.4, 0.5]))
    with pytest.raises(FilterError, match=r"map point 1 \(reading id 1\) has another time"):
        point_origins(moved, b)
    other_sensor = dataclasses.replace(pts, sensor=np.array([0, 3]))
    with pytest.raises(FilterError, match=r"map point 1 \(reading id 1\) has another time"):
        point_origins(other_sensor, b)


def _wall_and_echo_through_it() -> ReadingBatch:
    """A sensor driving along y = 0 hears a wall at x = 1 head-on 40 times, then a reading
    from the origin reads 2 m along the x axis: through the wall (multipath)."""
    n = 40
    k = np.arange(n)
    return ReadingBatch.from_arrays(
        t=np.r_[k * 0.1, 4.0], sensor=np.r_[np.zeros(n, int), 1],
        x=np.zeros(n + 1), y=np.r_[0.025 * k - 0.5, 0.0], theta=np.zeros(n + 1),
        range=np.r_[np.ones(n), 2.0])


def test_pipeline_keeps_origins_for_the_occlusion_filter() -> None:
    b = _wall_and_echo_through_it()
    spec = MapFilter(occlusion_depth=0.5)
    result = process_readings(b, CenterlineMethod(history_size=10), map_filter=spec)
    assert result.map_filter is not None
    assert result.map_filter.occluded == 1
    assert 40 not in result.global_map.reading_id.tolist()
    # The same as filtering the unfiltered map with the readings' origins, however the log is
    # cut into chunks, and with a reading filter that drops rows (ids stay input rows).
    whole = process_readings(b, CenterlineMethod(history_size=10)).global_map
    expected = filter_map(whole, spec, point_origins(whole, b)).points
    chunked = process_chunks([b[:7], b[7:30], b[30:]], CenterlineMethod(history_size=10),
                             map_filter=spec)
    np.testing.assert_array_equal(chunked.global_map.reading_id, expected.reading_id)
    near = process_readings(b, CenterlineMethod(history_size=10), map_filter=spec,
                            reading_filter=ReadingFilter(max_range=1.5))
    assert near.map_filter is not None
    assert near.map_filter.occluded == 0
    assert len(near.global_map) == 40


@pytest.mark.parametrize("module", ["readings", "maps", "occlusion", "driven_through",
                                    "late_echoes"])
def test_the_package_re_exports_every_public_name_of_its_modules(module: str) -> None:
    # Its docstring promises "everything is importable from here"; the helpers the modules
    # share among themselves are the exception.
    import importlib

    import sonarcarve.filters as package

    shared = {"origins_array"}
    names = set(importlib.import_module(f"sonarcarve.filters.{module}").__all__) - shared
    assert sorted(names - set(package.__all__)) == []
    assert all(hasattr(package, name) for name in names)
