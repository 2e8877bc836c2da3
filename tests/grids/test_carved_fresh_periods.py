"""A newest echo's mark lasts until its sensor would have fired again (``fresh_periods``): an
echoes-only log then marks what a log with its silent firings would (docs/carved-grid.md, "Stale
marks"), and odd gaps in the log cannot end marks early."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.errors import ReadingsError
from sonarcarve.grids import OCCUPIED, CarvedGrid, CarvedGridParams, GridError, trinary
from sonarcarve.grids.carved.periods import FiringPeriods
from sonarcarve.readings import Reading, ReadingBatch

H = 0.05
BOUNDS = (-0.5, -1.5, 3.5, 1.5)
ROW_Y, FACE_X = 0.025, 1.825  # a cell centre straight ahead of sensor 0
PERIOD = 0.5


def _mid(grid: CarvedGrid) -> tuple[int, int]:
    xs, ys = grid.cell_centers()
    return int(abs(ys - ROW_Y).argmin()), int(abs(xs - FACE_X).argmin())


def _ahead(t: float) -> Reading:
    """Sensor 0 hears the face straight ahead."""
    return Reading(t, 0, 0.0, ROW_Y, 0.0, FACE_X)


def _behind(t: float) -> Reading:
    """Sensor 4 looks the other way: it only moves the log's clock."""
    return Reading(t, 4, 0.0, ROW_Y, math.pi, 0.3)


def _turned(t: float) -> Reading:
    """Sensor 0 fires while the robot faces the other way (it hears something near)."""
    return Reading(t, 0, 0.0, ROW_Y, math.pi, 0.3)


def _sensor0_fires_every_period(times: list[float],
                                params: CarvedGridParams | None = None) -> CarvedGrid:
    """Sensor 0 fires at ``times`` (its period PERIOD) facing away, then hears the face at the
    next period: its firing period is known from the log when the echo comes."""
    grid = CarvedGrid(H, BOUNDS, params=params)
    grid.add_many(ReadingBatch.from_readings(_turned(t) for t in times))
    grid.add(_ahead(times[-1] + PERIOD))
    return grid


FIVE_FIRINGS = [PERIOD * k for k in range(5)]  # 4 gaps of 0.5 s: the period is known
ECHO_AT = 5 * PERIOD


def _occupied(grid: CarvedGrid) -> bool:
    return bool(trinary(grid)[_mid(grid)] == OCCUPIED)


# -- the period as the log shows it -------------------------------------------------------------

def _periods(times: list[float], sensor: int = 0) -> FiringPeriods:
    periods = FiringPeriods()
    periods.note(np.full(len(times), sensor, dtype=np.int64), np.array(times))
    return periods


def test_a_period_is_unknown_until_four_gaps_are_seen() -> None:
    assert _periods([0.0, 0.5, 1.0, 1.5]).period(0) == math.inf  # three gaps
    assert _periods([0.0, 0.5, 1.0, 1.5, 2.0]).period(0) == pytest.approx(0.5)
    assert _periods([0.0, 0.5, 1.0, 1.5, 2.0]).period(1) == math.inf  # another sensor


def test_readings_at_the_same_time_add_no_gap() -> None:
    # A duplicated reading is no new firing: the four real gaps of 0.5 s give the period.
    assert _periods([0.0, 0.0, 0.5, 0.5, 1.0, 1.5, 1.5, 2.0]).period(0) == pytest.approx(0.5)
    assert _periods([0.0, 0.0, 0.5, 0.5, 1.0, 1.5]).period(0) == math.inf  # only three


def test_a_quarter_of_odd_short_gaps_cannot_shorten_the_period() -> None:
    # 16 firings every 0.5 s, four of them also logged 1 ms late: of the 16 newest gaps, 4 are
    # 1 ms (the rest 0.499 s after a late one, or 0.5 s); the period stays a real gap.
    times: list[float] = []
    for k in range(16):
        times.append(0.5 * k)
        if k in (3, 7, 11, 15):  # four of the sixteen newest gaps
            times.append(0.5 * k + 0.001)
    assert _periods(times).period(0) == pytest.approx(0.499)


def test_a_log_that_drops_firings_shows_a_multiple_of_the_period() -> None:
    # Fired every 0.5 s, heard something at 8 firings: gaps 1.0 1.5 0.5 1.0 1.0 0.5 1.5. The
    # second shortest of 7 (rank floor(7 / 4) = 1): 0.5, the true period.
    assert _periods([0.0, 1.0, 2.5, 3.0, 4.0, 5.0, 5.5, 7.0]).period(0) == pytest.approx(0.5)
    # Heard only every other firing or less: the period looks longer, marks last longer.
    assert _periods([0.0, 1.0, 2.0, 3.5, 4.5]).period(0) == pytest.approx(1.0)


def test_the_period_follows_the_newest_sixteen_gaps() -> None:
    # A ring that slows from 0.5 s to 1.0 s: after 16 gaps of 1.0 s the old ones are forgotten.
    times = [0.5 * k for k in range(17)] + [8.0 + k for k in range(1, 17)]
    assert _periods(times).period(0) == pytest.approx(1.0)
    assert _periods(times[:-10]).period(0) == pytest.approx(0.5)  # 6 new gaps, 10 old ones


# -- the mark ----------------------------------------------------------------------------------

def test_a_mark_stays_until_its_sensor_would_have_fired_again() -> None:
    grid = _sensor0_fires_every_period(FIVE_FIRINGS)
    assert _occupied(grid)
    grid.add(_behind(ECHO_AT + 0.54))  # 1.08 periods: the sensor may still fire, a bit late
    assert _occupied(grid)


def test_a_mark_ends_once_its_sensor_has_fired_again_and_the_log_shows_no_echo() -> None:
    # At 1.2 periods sensor 0 has fired again and heard nothing; an echoes-only log drops that
    # firing, and the lone echo, spread (0.236 of a hit), is not occupied.
    grid = _sensor0_fires_every_period(FIVE_FIRINGS)
    grid.add(_behind(ECHO_AT + 0.6))
    assert not _occupied(grid)
    # The old rule, fresh_seconds alone, keeps it for 2 s: this test fails without the period.
    old = _sensor0_fires_every_period(FIVE_FIRINGS, CarvedGridParams(fresh_periods=math.inf))
    old.add(_behind(ECHO_AT + 0.6))
    assert _occupied(old)


def test_before_its_period_is_known_fresh_seconds_bounds_a_mark() -> None:
    grid = _sensor0_fires_every_period(FIVE_FIRINGS[:3])  # two gaps: period unknown
    grid.add(_behind(2 * PERIOD + 0.5 + 1.9))
    assert _occupied(grid)
    grid.add(_behind(2 * PERIOD + 0.5 + 2.1))
    assert not _occupied(grid)


def test_a_sensor_that_keeps_hearing_an_obstacle_keeps_it_marked_through_jitter() -> None:
    # The obstacle stays; sensor 0 fires every 0.5 s +- 5 %, and the log's clock moves on between
    # its firings: occupied at every read.
    rng = np.random.default_rng(7)
    grid = _sensor0_fires_every_period(FIVE_FIRINGS)
    t = ECHO_AT
    for _ in range(20):
        step = PERIOD * (1.0 + rng.uniform(-0.05, 0.05))
        grid.add(_behind(t + 0.9 * step))
        assert _occupied(grid), t
        t += step
        grid.add(_ahead(t))
        assert _occupied(grid), t


def test_duplicated_readings_do_not_end_marks_early() -> None:
    # Every reading of sensor 0 logged twice, and two of them again 2 ms late: of its 10 gaps
    # two are 2 ms, and the period is the third shortest, 0.498 s (0.5 s after a late one): the
    # mark holds to 0.548 s after the echo.
    times = sorted([PERIOD * k for k in range(8)] * 2 + [PERIOD * k + 0.002 for k in (2, 5)])
    grid = _sensor0_fires_every_period(times)
    grid.add(_behind(times[-1] + PERIOD + 0.5))
    assert _occupied(grid)


def test_a_refused_batch_teaches_no_period() -> None:
    grid = _sensor0_fires_every_period(FIVE_FIRINGS[:3])  # two gaps, and the echo: three
    echo_at = 3 * PERIOD
    # A batch from the past (before the echo): the method refuses it, and the grid with it.
    past = ReadingBatch.from_readings(_turned(1.2 + 0.01 * k) for k in range(4))
    with pytest.raises(ReadingsError):
        grid.add_many(past)
    # Had its 10 ms gaps counted, the period would be 10 ms and the mark would end at once.
    grid.add(_behind(echo_at + 0.52))
    assert _occupied(grid)


@pytest.mark.parametrize("bad", [0.0, 0.99, -1.0, math.nan, True, "2"])
def test_fresh_periods_must_be_at_least_one_period(bad: object) -> None:
    with pytest.raises(GridError, match="fresh_periods"):
        CarvedGridParams(fresh_periods=bad)  # type: ignore[arg-type]


def test_fresh_periods_may_be_off() -> None:
    assert CarvedGridParams(fresh_periods=math.inf).fresh_periods == math.inf
