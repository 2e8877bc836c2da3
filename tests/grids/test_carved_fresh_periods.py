"""A newest echo's mark lasts until its sensor would have fired again (``fresh_periods``): an
echoes-only log then marks what a log with its silent firings would (docs/carved-grid.md, "Stale
marks"), and odd gaps in the log cannot end marks early."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

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


def _late_copies(n: int, late: tuple[int, ...], lag: float = 0.001) -> list[float]:
    """Sensor 0 fires every 0.5 s, n times; the firings in ``late`` are logged twice, the second
    time ``lag`` seconds late."""
    times: list[float] = []
    for k in range(n):
        times.append(0.5 * k)
        if k in late:
            times.append(0.5 * k + lag)
    return times


def test_two_odd_short_gaps_of_sixteen_cannot_shorten_the_period() -> None:
    # Of the 16 newest gaps, 2 are 1 ms, 2 are 0.499 s (after a late copy), the rest 0.5 s: the
    # period is the fifth shortest (rank 16 / 4 = 4), 0.5 s; the two short ones miss it.
    times = _late_copies(16, (11, 13))
    assert _periods(times).period(0) == pytest.approx(0.5)


def test_gaps_that_do_not_fit_one_period_give_no_period() -> None:
    # Three odd gaps of sixteen: more than 16 / 8 miss, so the log is not a fixed schedule.
    assert _periods(_late_copies(16, (9, 11, 13))).period(0) == math.inf
    # A front sonar fired twice a cycle, unevenly (80 / 280 ms; review rev10p): the 280 ms gaps
    # are no multiple of 80 ms. With the rank alone the period was 80 ms and the mark of an
    # obstacle ahead ended 88 ms after each echo heard 280 ms before the next.
    uneven = np.cumsum([0.0] + [0.08, 0.28] * 8)
    assert _periods(list(uneven)).period(0) == math.inf
    # Two echoes a firing, each stamped on arrival: 4.7 ms, then the rest of a 0.32 s cycle.
    double = np.cumsum([0.0] + [0.0047, 0.3153] * 8)
    assert _periods(list(double)).period(0) == math.inf
    # ... even where the rest of the cycle is a whole multiple of the short gap (64 x 5 ms):
    # gaps of more than 8 periods miss.
    exact = np.cumsum([0.0] + [0.005, 0.32] * 8)
    assert _periods(list(exact)).period(0) == math.inf
    # A ring slowing from 0.5 to 0.7 s a firing: while its gaps mix the two, no period.
    slowing = [0.5 * k for k in range(11)] + [5.0 + 0.7 * k for k in range(1, 9)]
    assert _periods(slowing).period(0) == math.inf


def test_jitter_within_a_tenth_of_the_period_still_fits() -> None:
    rng = np.random.default_rng(3)
    times = np.cumsum([0.0, *(0.5 * (1.0 + rng.uniform(-0.04, 0.04, 16)))])
    period = _periods(list(times)).period(0)
    assert 0.48 <= period <= 0.52


def test_a_log_that_drops_firings_shows_a_multiple_of_the_period() -> None:
    # Fired every 0.5 s, heard something at 8 firings: gaps 1.0 1.5 0.5 1.0 1.0 0.5 1.5. The
    # second shortest of 7 (rank floor(7 / 4) = 1): 0.5, the true period, and every gap fits.
    assert _periods([0.0, 1.0, 2.5, 3.0, 4.0, 5.0, 5.5, 7.0]).period(0) == pytest.approx(0.5)
    # Heard only every other firing: the period looks longer, marks last longer.
    assert _periods([0.0, 1.0, 2.0, 3.0, 4.0]).period(0) == pytest.approx(1.0)


def test_the_period_follows_the_newest_sixteen_gaps() -> None:
    # A ring that slows from 0.5 s to 1.0 s: after 16 gaps of 1.0 s the old ones are forgotten.
    times = [0.5 * k for k in range(17)] + [8.0 + k for k in range(1, 17)]
    assert _periods(times).period(0) == pytest.approx(1.0)
    # 6 new gaps and 10 old ones: 1.0 s is twice 0.5 s, which a log dropping every other
    # firing shows too (the limit the module docstring states).
    assert _periods(times[:-10]).period(0) == pytest.approx(0.5)


def test_the_period_is_worked_out_again_after_it_was_read() -> None:
    # (review rev10p: a mutant that kept the first period survived the tests)
    periods = _periods([0.5 * k for k in range(6)])
    assert periods.period(0) == pytest.approx(0.5)
    periods.note(np.zeros(16, dtype=np.int64), 2.5 + np.arange(1, 17, dtype=float))
    assert periods.period(0) == pytest.approx(1.0)


def _reference_period(gaps: list[float]) -> float:
    """The period by its definition, in plain Python (the oracle of the compiled fit): the
    ``⌊n/4⌋``-th shortest of the newest 16 gaps if at most ``⌊n/8⌋`` of them lie farther than a
    tenth of it from a whole multiple 1-8 of it; ``inf`` otherwise or for fewer than 4 gaps."""
    newest = sorted(gaps[-16:])
    n = len(newest)
    if n < 4:
        return math.inf
    period = newest[n // 4]
    misses = sum(1 for gap in newest
                 if not any(abs(gap - k * period) <= 0.1 * period for k in range(1, 9)))
    return period if misses <= n // 8 else math.inf


@pytest.mark.parametrize("seed", range(6))
def test_the_compiled_periods_agree_with_their_definition(seed: int) -> None:
    # Several sensors on schedules that fit, drop firings, jitter, repeat a stamp or drift,
    # noted in batches of 1-7 readings and asked for between batches (some sensors never seen).
    rng = np.random.default_rng(seed)
    n_sensors = 5
    base = rng.uniform(0.05, 0.6, n_sensors)
    jitter = np.array([0.0, 0.03, 0.06, 0.09, 0.3])  # a fixed schedule ... an erratic one
    clock = np.zeros(n_sensors)
    log: dict[int, list[float]] = {s: [] for s in range(n_sensors)}
    periods, checked = FiringPeriods(), 0
    for _ in range(120):
        sensors, times = [], []
        for _ in range(int(rng.integers(1, 8))):
            s = int(rng.integers(n_sensors))
            step = base[s] * (rng.choice([0, 1, 1, 1, 1, 1, 2, 3, 9])
                              * (1 + rng.uniform(-jitter[s], jitter[s])))
            clock[s] += step
            sensors.append(s)
            times.append(float(clock[s]))
        order = np.argsort(times, kind="stable")  # a batch's times do not decrease
        sensor, t = np.array(sensors)[order], np.array(times)[order]
        periods.note(sensor.astype(np.int64), t)
        for s, ts in zip(sensor.tolist(), t.tolist(), strict=True):
            log[s].append(ts)
        asked = rng.choice(n_sensors + 2, size=3)
        got = periods.periods(asked.astype(np.int64))
        for s, value in zip(asked.tolist(), got.tolist(), strict=True):
            times_s = log.get(s, [])
            gaps = [b - a for a, b in itertools.pairwise(times_s) if b > a]
            assert value == _reference_period(gaps), (s, gaps[-16:])
            checked += math.isfinite(value)
    assert checked > 20  # the logs do give periods, not only inf

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


@pytest.mark.parametrize("read_after", [lambda step: 0.9 * step, lambda step: step - 0.001],
                         ids=["at 0.9 of each step", "just before each next echo"])
def test_a_sensor_that_keeps_hearing_an_obstacle_keeps_it_marked_through_jitter(
        read_after: Callable[[float], float]) -> None:
    # The obstacle stays; sensor 0 fires every 0.5 s +- 5 %, and the log's clock moves on between
    # its firings: occupied at every read, also just before each next echo (review rev10p:
    # reading at 0.9 of each step alone let fresh_periods 1.0 pass).
    rng = np.random.default_rng(7)
    grid = _sensor0_fires_every_period(FIVE_FIRINGS)
    t = ECHO_AT
    for _ in range(20):
        step = PERIOD * (1.0 + rng.uniform(-0.05, 0.05))
        grid.add(_behind(t + read_after(step)))
        assert _occupied(grid), t
        t += step
        grid.add(_ahead(t))
        assert _occupied(grid), t


def test_each_sensor_keeps_its_own_period() -> None:
    # Sensor 0 fires every 0.1 s facing away; sensor 7 hears the face every 0.5 s: 0.54 s after
    # sensor 7's echo the face is still marked (review rev10p: one period for all survived).
    grid = CarvedGrid(H, BOUNDS)
    readings = [_turned(0.1 * k) for k in range(1, 31)]
    readings += [Reading(0.5 * k + 0.05, 7, 0.0, ROW_Y, math.pi, 0.3) for k in range(5)]
    readings.append(Reading(2.55, 7, 0.0, ROW_Y, 0.0, FACE_X))
    grid.add_many(ReadingBatch.from_readings(sorted(readings, key=lambda r: r.t)))
    grid.add(_turned(2.55 + 0.54))
    assert _occupied(grid)


def test_fresh_seconds_still_bounds_a_mark_whose_period_is_long() -> None:
    # Sensor 0 fires every 2 s: 1.1 periods is 2.2 s, but fresh_seconds (2 s) ends it first.
    grid = CarvedGrid(H, BOUNDS)
    grid.add_many(ReadingBatch.from_readings(_turned(2.0 * k) for k in range(5)))
    grid.add(_ahead(10.0))
    grid.add(_behind(11.9))
    assert _occupied(grid)
    grid.add(_behind(12.1))
    assert not _occupied(grid)


@pytest.mark.parametrize(("gaps", "post"), [((0.08, 0.28), False), ((0.3142, 0.0058), True)],
                         ids=["fired twice a cycle, unevenly", "two echoes a firing"])
def test_a_log_that_drops_no_firing_marks_what_the_old_rule_did(
        gaps: tuple[float, float], post: bool) -> None:
    # The robot drives at 0.3 m/s towards a face; sensor 0 hears it at every firing (with
    # ``post``, each firing hears a post 1 m away first, stamped 5.8 ms before the face), so no
    # firing is missing and the rule has nothing to end. Another sensor's reading in the middle
    # of every gap reads the map: the face is marked exactly when it is with fresh_periods off
    # (review rev10p: with the rank alone it was lost at 26 / 60 % of such reads).
    t = 0.0
    readings = []
    for k in range(24):
        t += gaps[k % 2]
        x0 = -0.4 + 0.3 * t
        r = 1.0 if post and k % 2 == 0 else FACE_X - x0
        readings.append(Reading(t, 0, x0, ROW_Y, 0.0, r))
        readings.append(Reading(t + 0.5 * gaps[(k + 1) % 2], 4, x0, ROW_Y, math.pi, 0.3))
    grids = [CarvedGrid(H, BOUNDS, params=CarvedGridParams(fresh_periods=fp))
             for fp in (math.inf, 1.1)]
    marked: list[list[bool]] = [[], []]
    for reading in readings:
        for grid, seen in zip(grids, marked, strict=True):
            grid.add(reading)
            seen.append(_occupied(grid))
    assert marked[1] == marked[0]
    assert sum(marked[0]) >= 10  # the face is marked at many of the reads: the test can fail


def test_duplicated_readings_do_not_end_marks_early() -> None:
    # Every reading of sensor 0 logged twice, and two of them again 1 ms late: the period stays
    # 0.5 s (two odd gaps of the newest 16), so the mark holds until just before the next firing
    # and ends after it.
    times = sorted(_late_copies(16, (11, 13)) * 2)
    grid = _sensor0_fires_every_period(times)
    echo_at = times[-1] + PERIOD
    grid.add(_behind(echo_at + 0.54))
    assert _occupied(grid)
    grid.add(_behind(echo_at + 0.6))
    assert not _occupied(grid)


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
