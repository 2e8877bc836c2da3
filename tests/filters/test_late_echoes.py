"""The late-echo test on hand-built maps: every expected value from the geometry by hand.

Sound at 300 m/s and a firing every 0.02 s: a late echo of the previous firing reads
300 × 0.02 / 2 = 3 m short (6 m for two firings back). The sensor sits at the origin facing +x
unless a case says otherwise; the ghost point is at x = 1.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.errors import SonarcarveError
from sonarcarve.filters.late_echoes import (
    FiringSchedule,
    LateEchoError,
    far_echo_distance,
    late_echo_mask,
)
from sonarcarve.readings import ReadingBatch

C, PERIOD = 300.0, 0.02


def wall(x: float) -> list[tuple[float, float]]:
    """A wall across the x axis at ``x``: 11 points 0.1 m apart."""
    return [(x, 0.1 * k - 0.5) for k in range(11)]


def scene(points: list[tuple[float, float]], origins: list[tuple[float, float]] | None = None,
          max_error: float = 0.01) -> tuple[np.ndarray, np.ndarray, np.ndarray, ReadingBatch]:
    """One reading per map point, from its origin (default the sensor at 0, 0) towards it,
    at times 0.02 s apart: the map's arrays and the readings."""
    xy = np.array(points, dtype=float)
    src = np.zeros_like(xy) if origins is None else np.array(origins, dtype=float)
    offset = xy - src
    n = len(xy)
    batch = ReadingBatch.from_arrays(
        t=PERIOD * np.arange(1, n + 1), sensor=np.zeros(n, int), x=src[:, 0], y=src[:, 1],
        theta=np.arctan2(offset[:, 1], offset[:, 0]), range=np.hypot(offset[:, 0], offset[:, 1]))
    return xy, np.arange(n), np.full(n, max_error), batch


def ghost_flag(points: list[tuple[float, float]], **kwargs: object) -> bool:
    """Whether the first point (the ghost candidate) is flagged, with the firing period."""
    origins = kwargs.pop("origins", None)
    max_error = kwargs.pop("max_error", 0.01)
    xy, ids, bound, batch = scene(points, origins, max_error)  # type: ignore[arg-type]
    options = {"firing_period": PERIOD, "sound_speed": C, **kwargs}
    return bool(late_echo_mask(xy, ids, bound, batch, **options)[0])  # type: ignore[arg-type]


def test_far_wall_behind_a_near_point_makes_it_a_ghost() -> None:
    xy, ids, bound, batch = scene([(1.0, 0.0), *wall(4.0)])
    late = late_echo_mask(xy, ids, bound, batch, firing_period=PERIOD, sound_speed=C)
    # The ghost's far point is at 1 + 3 = 4, on the wall; the wall's own far points (7 m and
    # more away) lie on nothing.
    assert late.tolist() == [True] + [False] * 11


def test_a_mapped_wall_in_between_hides_the_far_wall() -> None:
    assert not ghost_flag([(1.0, 0.0), *wall(4.0), *wall(2.5)])


def test_a_direct_echo_with_no_far_wall_is_kept() -> None:
    assert not ghost_flag([(1.0, 0.0), *wall(6.0)])  # 6 is neither 4 nor, at lag 2, 7


def test_two_firings_back() -> None:
    points = [(1.0, 0.0), *wall(7.0)]  # 1 + 2 × 3
    assert ghost_flag(points, lags=2)
    assert not ghost_flag(points, lags=1)


def test_the_far_surface_must_have_been_heard_from_this_side() -> None:
    behind = [(10.0, 0.0)] * 11  # the wall at x = 4 heard from beyond it: its back
    assert not ghost_flag([(1.0, 0.0), *wall(4.0)], origins=[(0.0, 0.0), *behind])


def test_only_points_with_a_small_error_bound_are_surfaces() -> None:
    assert not ghost_flag([(1.0, 0.0), *wall(4.0)], max_error=0.6)
    assert ghost_flag([(1.0, 0.0), *wall(4.0)], max_error=0.6, surface_error=0.7)


def test_a_point_beside_the_far_point_is_outside_the_tolerance() -> None:
    assert not ghost_flag([(1.0, 0.0), *wall(4.15)])  # 0.15 m from the far point
    assert ghost_flag([(1.0, 0.0), *wall(4.15)], tolerance=0.2)


def test_a_wall_point_beside_the_line_counts_within_the_half_width() -> None:
    # Only the wall's points 0.26 m or more off the line from the sensor through the ghost
    # (the x axis), at the far point's depth.
    side = [(4.0, 0.26), (4.0, 0.3), (4.0, -0.3)]
    assert ghost_flag([(1.0, 0.0), *side])  # within 0.5 m across
    assert not ghost_flag([(1.0, 0.0), *side], half_width=0.25)


def test_a_point_of_a_wall_also_heard_obliquely_is_kept() -> None:
    # Three more points of a wall at x = 1, heard from (0, 3): their far points, 3 m further
    # along lines slanting down to the right, land on nothing, so only 1 of the 4 points
    # within 0.3 m of the first is a late echo.
    points = [(1.0, 0.0), (1.0, 0.1), (1.0, -0.1), (1.0, 0.2), *wall(4.0)]
    origins = [(0.0, 0.0), *[(0.0, 3.0)] * 3, *[(0.0, 0.0)] * 11]
    assert not ghost_flag(points, origins=origins)
    # With one oblique neighbour, half the points near it are late: it stays one.
    assert ghost_flag([*points[:2], *points[4:]], origins=[*origins[:2], *origins[4:]])


def test_a_ghost_wall_heard_square_on_is_flagged_whole() -> None:
    # The same four points, each heard from straight behind it: every far point is on the wall.
    points = [(1.0, 0.0), (1.0, 0.1), (1.0, -0.1), (1.0, 0.2), *wall(4.0)]
    origins = [(0.0, 0.0), (0.0, 0.1), (0.0, -0.1), (0.0, 0.2), *[(0.0, 0.0)] * 11]
    xy, ids, bound, batch = scene(points, origins)
    late = late_echo_mask(xy, ids, bound, batch, firing_period=PERIOD, sound_speed=C)
    assert late.tolist() == [True] * 4 + [False] * 11


def test_the_exact_path_from_another_sensor() -> None:
    # Emitter at (-2, 0) fires at t = 0, the receiver at the origin at 0.02 and reads 1 m:
    # L = 2 + 6 = 8, and the reflection on the axis is at s with (s + 2) + s = 8, s = 3.
    xy, ids, bound, batch = scene([(1.0, 0.0), *wall(3.0)])
    firings = FiringSchedule(np.array([0.0, *batch.t]), np.array([-2.0, *batch.x]),
                             np.array([0.0, *batch.y]))
    exact = late_echo_mask(xy, ids, bound, batch, firings=firings, sound_speed=C)
    assert exact[0]
    # With the period alone the emitter is taken at the receiver: the far point is at 4.
    assert not late_echo_mask(xy, ids, bound, batch, firing_period=PERIOD, sound_speed=C)[0]


def test_far_echo_distance_on_a_slanted_line() -> None:
    # Emitter at (0, -1), receiver at the origin, looking along +y, r = 1, c Δt = 4: L = 6 and
    # (s + 1) + s = 6 gives s = 2.5.
    s = far_echo_distance([1.0], [4.0 / C], [[0.0, 1.0]], [[0.0, 1.0]], sound_speed=C)
    assert s.tolist() == pytest.approx([2.5])


def test_the_firings_of_a_log_are_its_reading_times() -> None:
    # The readings are 0.02 s apart: the ghost's previous firing is the reading before it.
    xy, ids, bound, batch = scene([(5.0, 5.0), (1.0, 0.0), *wall(4.0)])
    firings = FiringSchedule.from_readings(batch)
    assert late_echo_mask(xy, ids, bound, batch, firings=firings, sound_speed=C)[1]


def test_empty_map() -> None:
    _, _, _, batch = scene([(1.0, 0.0)])
    assert late_echo_mask(np.zeros((0, 2)), [], [], batch, firing_period=PERIOD).shape == (0,)


def test_a_schedule_is_required() -> None:
    xy, ids, bound, batch = scene([(1.0, 0.0)])
    with pytest.raises(LateEchoError, match="firing_period"):
        late_echo_mask(xy, ids, bound, batch)


@pytest.mark.parametrize(("options", "words"), [
    ({"tolerance": -0.1}, "tolerance"),
    ({"tolerance": math.nan}, "tolerance"),
    ({"lags": 0}, "lags"),
    ({"lags": 1.5}, "lags"),
    ({"surface_error": 0.0}, "surface_error"),
    ({"half_width": -0.5}, "half_width"),
    ({"firing_period": -1.0}, "firing_period"),
    ({"firings": FiringSchedule(np.zeros(1), np.zeros(1), np.zeros(1))}, "not both"),
])
def test_bad_parameters(options: dict[str, object], words: str) -> None:
    xy, ids, bound, batch = scene([(1.0, 0.0)])
    options = {"firing_period": PERIOD, **options}
    with pytest.raises(LateEchoError, match=words):
        late_echo_mask(xy, ids, bound, batch, **options)  # type: ignore[arg-type]


def test_bad_arrays() -> None:
    xy, ids, bound, batch = scene([(1.0, 0.0), (2.0, 0.0)])
    with pytest.raises(LateEchoError, match="finite"):
        late_echo_mask([[math.nan, 0.0], [2.0, 0.0]], ids, bound, batch, firing_period=PERIOD)
    with pytest.raises(LateEchoError, match="reading id"):
        late_echo_mask(xy, [0, 7], bound, batch, firing_period=PERIOD)
    with pytest.raises(LateEchoError, match="error bound"):
        late_echo_mask(xy, ids, bound[:1], batch, firing_period=PERIOD)
    with pytest.raises(LateEchoError, match="no firing"):
        late_echo_mask(xy, ids, bound, batch, firings=FiringSchedule(
            np.array([0.5]), np.zeros(1), np.zeros(1)))
    assert issubclass(LateEchoError, SonarcarveError)


def test_map_filter_refuses_a_bad_period_and_a_missing_log() -> None:
    from sonarcarve.filters import FilterError, MapFilter, filter_map
    from sonarcarve.maps import GlobalMap

    for bad in (0.0, -0.04, math.inf, math.nan):
        with pytest.raises(FilterError, match="late_echo_period must be a finite number > 0 "
                                              r"\(seconds\)"):
            MapFilter(late_echo_period=bad)
    assert MapFilter(late_echo_period=0.04).active
    with pytest.raises(FilterError, match="late-echo filter needs the map's readings"):
        filter_map(GlobalMap.empty(), MapFilter(late_echo_period=0.04))


def _two_points() -> tuple[np.ndarray, np.ndarray, np.ndarray, ReadingBatch]:
    return scene([(1.0, 0.0), (2.0, 0.0)])


@pytest.mark.parametrize(("reading_ids", "words"), [
    ([0, 1, 2], "one id for each of the 2 readings"),  # was an IndexError
    ([0, 0], "unique"),  # the second point was matched to the first reading, silently
    ([0.0, 1.5], "whole numbers"),  # 1.5 was read as 1, silently
])
def test_bad_reading_ids(reading_ids: list[float], words: str) -> None:
    xy, ids, bound, batch = _two_points()
    with pytest.raises(LateEchoError, match=words):
        late_echo_mask(xy, ids, bound, batch, reading_ids=reading_ids, firing_period=PERIOD)


def test_a_point_id_that_is_no_whole_number_is_refused() -> None:
    xy, _, bound, batch = _two_points()
    with pytest.raises(LateEchoError, match="whole numbers"):
        late_echo_mask(xy, [0.0, 0.7], bound, batch, firing_period=PERIOD)


@pytest.mark.parametrize(("firings", "words"), [
    # Lengths that differ were read as far as the shortest, silently.
    (FiringSchedule(np.array([0.02, 0.04]), np.zeros(1), np.zeros(3)), "same length"),
    (FiringSchedule(np.array([0.02, 0.04]), np.array([math.nan, 0.0]), np.zeros(2)), "finite"),
    # Out of order, the search for a reading's firing failed with a misleading message.
    (FiringSchedule(np.array([0.04, 0.02]), np.zeros(2), np.zeros(2)), "increasing"),
])
def test_bad_firing_schedules(firings: FiringSchedule, words: str) -> None:
    xy, ids, bound, batch = _two_points()
    with pytest.raises(LateEchoError, match=words):
        late_echo_mask(xy, ids, bound, batch, firings=firings)


def test_lags_beyond_the_limit_are_refused() -> None:
    # Each lag is one pass over the map: a billion lags ran for hours.
    xy, ids, bound, batch = _two_points()
    with pytest.raises(LateEchoError, match=r"lags must be a whole number in 1\.\.1000"):
        late_echo_mask(xy, ids, bound, batch, firing_period=PERIOD, lags=10**9)


def test_readings_that_are_no_batch_are_refused() -> None:
    xy, ids, bound, _ = _two_points()
    with pytest.raises(LateEchoError, match="ReadingBatch"):
        late_echo_mask(xy, ids, bound, [(0.0, 1.0)], firing_period=PERIOD)  # type: ignore[arg-type]


@pytest.mark.parametrize("shift", [-5e-7, 5e-7])
def test_firing_times_match_the_readings_within_a_microsecond_either_way(shift: float) -> None:
    # A schedule logged by another clock (or printed with fewer digits) is a hair off the
    # readings' times; it was found only when late, never when early.
    xy, ids, bound, batch = scene([(5.0, 5.0), (1.0, 0.0), *wall(4.0)])
    firings = FiringSchedule(batch.t + shift, batch.x, batch.y)
    assert late_echo_mask(xy, ids, bound, batch, firings=firings, sound_speed=C)[1]


def test_the_pipeline_finds_each_points_reading_past_dropped_rows_and_chunk_cuts() -> None:
    # One sensor at the origin facing +x (a 0.05 rad beam), firing every 0.02 s at c = 343
    # m/s: five echoes beyond the 5 m max range (dropped before mapping), ten of a wall at
    # 4 m, ten late echoes of it read 343 × 0.02 / 2 = 3.43 m short. The map's ids are input
    # rows, so the late-echo test must look them up in the whole log, not the kept readings.
    from sonarcarve.filters import MapFilter, ReadingFilter
    from sonarcarve.methods import CenterlineMethod
    from sonarcarve.pipeline import process_chunks

    r = np.concatenate([np.full(5, 5.5), np.full(10, 4.0), np.full(10, 4.0 - 3.43)])
    n = len(r)
    batch = ReadingBatch.from_arrays(t=0.02 * np.arange(n), sensor=np.zeros(n, int),
                                     x=np.zeros(n), y=np.zeros(n), theta=np.zeros(n), range=r,
                                     beam_width=np.full(n, 0.05))
    result = process_chunks([batch[:3], batch[3:17], batch[17:]],
                            CenterlineMethod(history_size=10),
                            reading_filter=ReadingFilter(max_range=5.0),
                            map_filter=MapFilter(late_echo_period=0.02))
    assert result.global_map.reading_id.tolist() == list(range(5, 15))
    assert result.map_filter is not None
    assert result.map_filter.late_echoes == 10


def test_a_surface_point_within_the_tolerance_of_the_line_blocks_it_between_samples() -> None:
    # The line from the ghost runs from x = 1.3 to 3.6 (0.3 m past the ghost, 0.3 + 0.1 m short
    # of the far point at 4), sampled every 0.1 m: x = 2.55 lies midway between two samples.
    assert not ghost_flag([(1.0, 0.0), *wall(4.0), (2.55, 0.095)])  # 0.095 m off the line
    assert ghost_flag([(1.0, 0.0), *wall(4.0), (2.55, 0.105)])  # 0.105 m: clear of it


@pytest.mark.parametrize("tolerance", [0.1, 0.3, 0.5])
def test_a_wide_tolerance_still_finds_the_ghost(tolerance: float) -> None:
    # The ghost's far point lies on the wall whatever the tolerance; from 0.27 m on the line's
    # first sample used to reach back to the ghost itself, which then blocked its own line.
    assert ghost_flag([(1.0, 0.0), *wall(4.0)], tolerance=tolerance)


def test_a_lone_far_point_is_no_far_wall() -> None:
    # One surface point at the far point (4, 0) and nothing else within 2 m of it.
    assert not ghost_flag([(1.0, 0.0), (4.0, 0.0)])
    assert not ghost_flag([(1.0, 0.0), (4.0, 0.0), (4.0, 2.05)])  # 2.05 m: still alone


def test_a_far_point_with_a_surface_neighbour_within_2_m_is_a_far_wall() -> None:
    # The neighbour lies 1.95 m across the line, outside the 0.5 m window: it only vouches
    # that the point at the far point is part of something, not alone.
    assert ghost_flag([(1.0, 0.0), (4.0, 0.0), (4.0, 1.95)])


def test_the_neighbour_must_itself_be_a_surface_point() -> None:
    xy, ids, bound, batch = scene([(1.0, 0.0), (4.0, 0.0), (4.0, 1.0)])
    bound[2] = 0.6  # above surface_error (0.5)
    late = late_echo_mask(xy, ids, bound, batch, firing_period=PERIOD, sound_speed=C)
    assert not late[0]
