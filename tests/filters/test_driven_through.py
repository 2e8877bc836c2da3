"""The driven-through map filter: points the robot's body covered later are dropped."""

import math

import numpy as np
import pytest

from sonarcarve.filters import (
    DRIVEN_MARGIN,
    BodyFootprint,
    FilterError,
    MapFilter,
    ReadingFilter,
    driven_through_mask,
    filter_map,
    swept_poses,
)
from sonarcarve.maps import GlobalMap, PointSource
from sonarcarve.methods import CenterlineMethod
from sonarcarve.pipeline import process_chunks, process_readings
from sonarcarve.readings import ReadingBatch


def _drive(t: list[float], x: list[float], y: list[float] | None = None,
           theta: float = 0.0, sensor: int = 0) -> ReadingBatch:
    """One sensor's poses along a path (its ranges do not matter to the filter)."""
    n = len(t)
    return ReadingBatch.from_arrays(t=t, sensor=[sensor] * n, x=x,
                                    y=[0.0] * n if y is None else y, theta=[theta] * n,
                                    range=[1.0] * n)


DISC = BodyFootprint.around_sensors(0.2)
#: Along +x at 1 m/s from x = 0 to x = 4, a pose every 0.5 s.
STRAIGHT = _drive([0.5 * k for k in range(9)], [0.5 * k for k in range(9)])


def test_a_point_the_body_passes_later_is_dropped_and_one_passed_before_kept() -> None:
    # The body covers x = 2 from t = 1.8 to 2.2 s: heard at 0 s, then passed; heard at 3 s,
    # passed already.
    mask = driven_through_mask([[2.0, 0.0], [2.0, 0.0]], [0.0, 3.0], STRAIGHT, DISC)
    assert mask.tolist() == [True, False]


def test_a_point_just_outside_the_footprint_is_kept() -> None:
    # The disc's inscribed 16-gon reaches 0.2 cos(π/16) = 0.196 m to the side at its flats.
    mask = driven_through_mask([[2.0, 0.19], [2.0, 0.21], [4.21, 0.0], [-0.21, 0.0]],
                               [0.0] * 4, STRAIGHT, DISC)
    assert mask.tolist() == [True, False, False, False]


def test_the_segment_between_two_far_apart_poses_counts() -> None:
    # Two readings 1 s and 4 m apart: no pose near x = 2, but the body swept it.
    fast = _drive([0.0, 1.0], [0.0, 4.0])
    assert driven_through_mask([[2.0, 0.1]], [-1.0], fast, DISC).tolist() == [True]


def test_poses_further_apart_than_the_longest_gap_are_not_joined() -> None:
    hole = _drive([0.0, 3.0], [0.0, 4.0])  # 3 s > DRIVEN_MAX_GAP: the path is unknown
    assert driven_through_mask([[2.0, 0.0]], [-1.0], hole, DISC).tolist() == [False]


def test_the_readings_own_pose_and_the_next_within_the_margin_never_count() -> None:
    # The body stands still over the point from its reading to just inside the margin.
    still = _drive([0.0, 0.9 * DRIVEN_MARGIN], [0.0, 0.0])
    assert driven_through_mask([[0.1, 0.0]], [0.0], still, DISC).tolist() == [False]
    later = _drive([0.0, 1.1 * DRIVEN_MARGIN], [0.0, 0.0])
    assert driven_through_mask([[0.1, 0.0]], [0.0], later, DISC).tolist() == [True]


def test_each_sensor_is_its_own_track_without_mounts() -> None:
    # Sensor 0 stays at x = 0, sensor 1 at x = 4: joining their poses would sweep x = 2.
    poses = ReadingBatch.from_arrays(t=[0.0, 0.5, 1.0, 1.5], sensor=[0, 1, 0, 1],
                                     x=[0.0, 4.0, 0.0, 4.0], y=[0.0] * 4, theta=[0.0] * 4,
                                     range=[1.0] * 4)
    mask = driven_through_mask([[2.0, 0.0], [4.0, 0.0]], [-1.0, -1.0], poses, DISC)
    assert mask.tolist() == [False, True]


def test_dense_poses_thinned_still_follow_a_corner_and_a_long_stop() -> None:
    # An L at 4 m/s, a pose every 0.01 s: the thinned path keeps the corner at (2.1, 0), which
    # the body covers 0.15 m beyond, and never drove the diagonal ...
    t = np.arange(103) * 0.01
    x, y = np.minimum(4.0 * t, 2.1), np.maximum(4.0 * t - 2.1, 0.0)
    corner = _drive(t.tolist(), x.tolist(), y.tolist())
    mask = driven_through_mask([[1.0, 1.0], [2.25, 0.0]], [-1.0, -1.0], corner, DISC)
    assert mask.tolist() == [False, True]
    # ... and a stop: standing still from 0 to 10 s, the robot covers what it heard at 5 s
    # 0.19 m behind its sensor (then it drives off, away from it).
    t = np.arange(1101) * 0.01
    stop = _drive(t.tolist(), np.maximum(t - 10.0, 0.0).tolist())
    assert driven_through_mask([[-0.19, 0.0]], [5.0], stop, DISC).tolist() == [True]


# A car-like body: sensors at both ends, 4 m apart, and a round middle of 0.5 m radius.
CAR = BodyFootprint.of_robot([2.0, -2.0], [0.0, 0.0], [0.0, math.pi], 0.5)


def _car_north(seconds: int = 10) -> ReadingBatch:
    """The car driving north (heading π/2) at 1 m/s from (0, 0); its front sensor's poses."""
    t = np.arange(seconds + 1, dtype=np.float64)
    return _drive(t.tolist(), [0.0] * t.size, (t + 2.0).tolist(), theta=math.pi / 2)


def test_the_robot_centre_and_heading_come_from_the_mounts() -> None:
    poses = _car_north()
    # The front sensor is 2 m ahead of the centre, which drives x = 0 from y 0 to 10. The
    # body is 1 m wide (the disc) and 5 m long (the disc and the sensors' hull).
    points = [[0.0, 5.0], [0.3, 5.0], [0.7, 5.0], [0.0, 11.9], [0.0, 12.1], [0.0, -1.9]]
    mask = driven_through_mask(points, [-1.0] * 6, poses, CAR)
    assert mask.tolist() == [True, True, False, True, False, True]


def test_the_rear_sensor_gives_the_same_centre() -> None:
    t = np.arange(11, dtype=np.float64)
    rear = _drive(t.tolist(), [0.0] * t.size, (t - 2.0).tolist(), theta=-math.pi / 2, sensor=1)
    points = [[0.0, 11.9], [0.0, 12.1], [0.3, 5.0], [0.7, 5.0]]
    assert driven_through_mask(points, [-1.0] * 4, rear, CAR).tolist() == [True, False, True,
                                                                            False]


def test_a_turn_in_place_sweeps_the_ends_of_a_long_body() -> None:
    # A quarter turn in one step: the long body's ends sweep a quarter disc of 2 m (its tips
    # are points: 1.8 m out the body is still 10 cm wide).
    turn = ReadingBatch.from_arrays(t=[0.0, 1.0], sensor=[0, 0], x=[2.0, 0.0], y=[0.0, 2.0],
                                    theta=[0.0, math.pi / 2], range=[1.0, 1.0])
    corner = [[1.8 * math.cos(math.pi / 4), 1.8 * math.sin(math.pi / 4)]]
    assert driven_through_mask(corner, [-1.0], turn, CAR).tolist() == [True]
    assert driven_through_mask([[2.2, 2.2]], [-1.0], turn, CAR).tolist() == [False]


def test_swept_poses_interpolate_time_place_and_the_short_way_round() -> None:
    track = np.array([[0.0, 0.0, 0.0, math.radians(170)], [1.0, 0.2, 0.0, math.radians(-170)]])
    swept = swept_poses(track, step=0.1)
    np.testing.assert_allclose(swept[:, 0], [0.0, 0.5, 1.0])
    np.testing.assert_allclose(swept[:, 1], [0.0, 0.1, 0.2])
    assert math.isclose(abs(swept[1, 3]), math.pi)  # through 180°, not through 0°


def test_bad_bodies_and_sensors_are_filter_errors() -> None:
    with pytest.raises(FilterError, match="clearance radius must be a finite number > 0"):
        BodyFootprint.around_sensors(0.0)
    with pytest.raises(FilterError, match="body radius must be"):
        BodyFootprint.of_robot([0.1], [0.0], [0.0], math.nan)
    with pytest.raises(FilterError, match="sensor mounts need finite x, y and bearing"):
        BodyFootprint.of_robot([0.1, 0.2], [0.0], [0.0], 0.2)
    with pytest.raises(FilterError, match="mounts for 2 sensors only"):
        driven_through_mask([[0.0, 0.0]], [0.0], _drive([0.0], [0.0], sensor=2), CAR)
    with pytest.raises(FilterError, match="a finite point and a time for each point"):
        driven_through_mask([[0.0, 0.0]], [0.0, 1.0], STRAIGHT, DISC)
    with pytest.raises(FilterError, match="driven_through must be a BodyFootprint"):
        MapFilter(driven_through=0.1)  # type: ignore[arg-type]


def _map(xy: list[list[float]], t: list[float]) -> GlobalMap:
    n = len(xy)
    pts = np.asarray(xy, dtype=np.float64)
    return GlobalMap(reading_id=np.arange(n), t=np.asarray(t), sensor=np.zeros(n, np.int64),
                     xy=pts, source=np.full(n, PointSource.CENTERLINE, dtype=np.int8),
                     width=np.zeros(n), max_error=np.full(n, 0.01), range=np.ones(n))


def test_filter_map_drops_and_counts_driven_through_points() -> None:
    points = _map([[2.0, 0.0], [2.0, 1.0], [3.0, 0.0]], [0.0, 0.0, 3.5])
    spec = MapFilter(driven_through=DISC)
    with pytest.raises(FilterError, match="driven-through filter needs the map's readings"):
        filter_map(points, spec)
    out = filter_map(points, spec, readings=STRAIGHT)
    assert out.points.reading_id.tolist() == [1, 2]
    assert out.report.driven_through == 1
    assert out.report.kept == 2


def test_driven_through_runs_before_the_outlier_test() -> None:
    # Two points 0.1 m apart vouch for each other; once the body dropped one, the other is alone.
    points = _map([[2.0, 0.0], [2.0, 0.29]], [0.0, 0.0])
    out = filter_map(points, MapFilter(driven_through=DISC, outlier_radius=0.3),
                     readings=STRAIGHT)
    assert out.report.driven_through == 1
    assert out.report.outliers == 1


def _forward_and_left(n: int = 60) -> ReadingBatch:
    """Driving +x at 0.5 m/s; even rows look left at a wall 1.5 m away, odd rows look ahead
    0.52 m at something the sensor reaches about a second later."""
    k = np.arange(n)
    odd = k % 2 == 1
    return ReadingBatch.from_arrays(t=0.1 * k, sensor=np.zeros(n, int), x=0.05 * k,
                                    y=np.zeros(n), theta=np.where(odd, 0.0, math.pi / 2),
                                    range=np.where(odd, 0.52, 1.5))


def test_the_pipeline_filters_as_filter_map_does_however_the_log_is_cut() -> None:
    b = _forward_and_left()
    spec = MapFilter(driven_through=BodyFootprint.around_sensors(0.1))
    whole = process_readings(b, CenterlineMethod(history_size=10)).global_map
    expected = filter_map(whole, spec, readings=b).points
    # The sensor reaches x = 2.95; a point ahead is passed within 0.1 m up to row 49.
    dropped = list(range(1, 50, 2))
    assert sorted(set(whole.reading_id.tolist()) - set(expected.reading_id.tolist())) == dropped
    result = process_chunks([b[:7], b[7:30], b[30:]], CenterlineMethod(history_size=10),
                            map_filter=spec)
    np.testing.assert_array_equal(result.global_map.reading_id, expected.reading_id)
    assert result.map_filter is not None
    assert result.map_filter.driven_through == len(dropped)


def test_readings_the_reading_filters_drop_still_give_the_path() -> None:
    # The left-looking rows (1.5 m) are beyond max_range 1 m, but were taken where the body
    # went. The log ends with one at x = 2.40, which alone passes within 0.1 m of the point
    # that row 39 placed ahead at x = 2.47 (the last kept row stands at x = 2.35).
    b = _forward_and_left(49)
    spec = MapFilter(driven_through=BodyFootprint.around_sensors(0.1))
    near = ReadingFilter(max_range=1.0)
    result = process_readings(b, CenterlineMethod(history_size=10), map_filter=spec,
                              reading_filter=near)
    unfiltered = process_readings(b, CenterlineMethod(history_size=10), reading_filter=near)
    only_kept = filter_map(unfiltered.global_map, spec, readings=b[1::2])
    assert 39 in only_kept.points.reading_id.tolist()
    assert 39 not in result.global_map.reading_id.tolist()
    assert result.map_filter is not None
    assert result.map_filter.driven_through == only_kept.report.driven_through + 1


@pytest.mark.parametrize("margin", [math.nan, -0.1, math.inf])
def test_a_margin_that_is_no_finite_number_at_least_zero_is_refused(margin: float) -> None:
    # NaN made no pose later (nothing dropped, silently); a negative margin let the reading's
    # own pose drop it.
    with pytest.raises(FilterError, match="margin must be a finite number >= 0"):
        driven_through_mask([[2.0, 0.0]], [0.0], STRAIGHT, DISC, margin=margin)


def test_a_point_time_that_is_not_finite_is_refused() -> None:
    with pytest.raises(FilterError, match="a finite point and a time for each point"):
        driven_through_mask([[2.0, 0.0]], [math.nan], STRAIGHT, DISC)


def test_swept_poses_move_no_corner_more_than_a_step() -> None:
    # 1 m forward while turning 1 rad: a corner 1 m out moves up to 1 + 1 = 2 m along the
    # segment (the translation and the turn add up where they point the same way), so at
    # step 0.1 it takes 20 pieces; 10 (the larger of the two alone) moved it 0.2 m a piece.
    track = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 1.0, 1.0]])
    swept = swept_poses(track, step=0.1, reach=1.0)
    for angle in np.linspace(0.0, 2.0 * math.pi, 64, endpoint=False):
        heading = swept[:, 3] + angle
        corner = swept[:, 1:3] + np.column_stack([np.cos(heading), np.sin(heading)])
        moves = np.hypot(*np.diff(corner, axis=0).T)
        assert moves.max() <= 0.1 + 1e-9


def test_a_body_of_radius_zero_is_the_sensors_hull() -> None:
    square = BodyFootprint.of_robot([1.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, -1.0],
                                    [0.0, 0.5 * math.pi, math.pi, -0.5 * math.pi], 0.0)
    assert square.reach == pytest.approx(1.0)
    assert len(square.outline) == 4
    with pytest.raises(FilterError, match="the body has no area"):
        BodyFootprint.of_robot([1.0, -1.0], [0.0, 0.0], [0.0, math.pi], 0.0)
    with pytest.raises(FilterError, match="body radius must be a finite number >= 0"):
        BodyFootprint.of_robot([1.0], [0.0], [0.0], -0.1)


def test_a_side_sensor_gives_the_centre_through_its_bearing() -> None:
    # One sensor on the left rim (bearing +90°) of a 0.5 m disc, driving +x along y = 0: the
    # sensor rides at y = 0.5 looking +y. The heading is its axis minus its bearing (0); plus
    # (180°) would put the centre at y = 1 and cover the wrong strip.
    left = BodyFootprint.of_robot([0.0], [0.5], [0.5 * math.pi], 0.5)
    t = np.arange(9, dtype=np.float64)
    poses = _drive(t.tolist(), t.tolist(), [0.5] * t.size, theta=0.5 * math.pi)
    mask = driven_through_mask([[4.0, -0.4], [4.0, 0.9]], [-1.0, -1.0], poses, left)
    assert mask.tolist() == [True, False]


def test_a_small_body_is_swept_at_half_its_reach() -> None:
    # A 0.02 m disc driven 1 m in one step: poses 0.05 m apart (DRIVEN_STEP) would leave
    # x = 0.525 0.025 m from the nearest, outside the disc; at half the reach they do not.
    tiny = BodyFootprint.around_sensors(0.02)
    assert driven_through_mask([[0.525, 0.0]], [-1.0], _drive([0.0, 1.0], [0.0, 1.0]),
                               tiny).tolist() == [True]


def test_poses_that_are_no_batch_are_refused() -> None:
    # A list of poses failed with "'list' object has no attribute 't'".
    with pytest.raises(FilterError, match="poses must be a ReadingBatch"):
        driven_through_mask([[2.0, 0.0]], [0.0], [(0.0, 0.0, 0.0)], DISC)  # type: ignore[arg-type]


def test_a_path_that_comes_back_many_times_is_paired_with_the_map_a_block_at_a_time(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # A sensor circling a 1 m ring at 1 m/s for 100 s (16 times) pairs each of 2,000 points on
    # the ring with the poses of every lap: about 160,000 pairs. All at once (with a row of
    # the outline's corners each) took 2.5 GB on a car's 10-minute loop log.
    import sonarcarve.filters.driven_through as module

    sizes: list[int] = []
    inside = module._inside_outline

    def spy(q: np.ndarray, pose: np.ndarray, outline: np.ndarray) -> np.ndarray:
        sizes.append(len(q))
        return inside(q, pose, outline)

    monkeypatch.setattr(module, "_inside_outline", spy)
    t = np.arange(0.0, 100.0, 0.04)
    loop = _drive(t.tolist(), np.cos(t).tolist(), np.sin(t).tolist())
    angle = np.linspace(0.0, 2.0 * math.pi, 1000, endpoint=False)
    on_ring = np.column_stack([np.cos(angle), np.sin(angle)])
    points = np.vstack([on_ring, 1.5 * on_ring])  # the second 0.5 m off the ring: kept
    mask = driven_through_mask(points, np.full(2000, -1.0), loop, DISC)
    assert mask.tolist() == [True] * 1000 + [False] * 1000
    assert max(sizes) <= 1 << 16


@pytest.mark.parametrize(("outline", "words"), [
    (np.zeros((0, 2)), "at least three finite"),
    (np.array([[0.0, 0.0], [1.0, 0.0]]), "at least three finite"),
    (np.array([[0.0, 0.0], [1.0, 0.0], [np.nan, 1.0]]), "at least three finite"),
    (np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]]), "counter-clockwise"),  # clockwise
    (np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 0.2], [2.0, 1.0], [0.0, 1.0]]), "convex"),
])
def test_an_outline_built_directly_is_checked(outline: np.ndarray, words: str) -> None:
    with pytest.raises(FilterError, match=words):
        BodyFootprint(outline=outline)


def test_a_counter_clockwise_square_built_directly_sweeps_its_width() -> None:
    # A 0.6 m square riding on the sensor along y = 0 covers |y| < 0.3 behind it.
    body = BodyFootprint(outline=np.array([[-0.3, -0.3], [0.3, -0.3], [0.3, 0.3], [-0.3, 0.3]]))
    mask = driven_through_mask([[2.0, 0.25], [2.0, -0.25], [2.0, 0.35]], [0.0] * 3, STRAIGHT,
                               body)
    assert mask.tolist() == [True, True, False]


def test_the_last_pose_before_a_gap_survives_thinning() -> None:
    # Creeping 4.9 cm in 0.45 s (every pose within half a step and a margin of the one at 0.3 s,
    # so thinned away), then nothing for 2.55 s (> DRIVEN_MAX_GAP: the two ends are not joined).
    # Only the last pose before the gap, at x = 0.049, covers the point 0.19 m ahead of it.
    creep = _drive([0.0, 0.30, 0.40, 0.45, 3.0, 3.1], [0.0, 0.030, 0.040, 0.049, 5.0, 5.1])
    assert driven_through_mask([[0.239, 0.0]], [0.0], creep, DISC).tolist() == [True]
