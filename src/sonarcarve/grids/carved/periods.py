"""Each sensor's firing period as the log shows it, :class:`FiringPeriods`: how long the newest
echo's mark may last before the sensor has fired again (``docs/carved-grid.md``, "Stale marks").

A ring fires each sensor on a fixed schedule, so the times between two readings of one sensor
are its period, or a multiple of it where the log dropped firings that heard nothing (an
echoes-only log). The shortest such time would be the period, but one duplicated or
near-duplicated reading would make it tiny and end that sensor's marks at once. So the period
is a low rank of the sensor's recent gaps, known only after a few of them, and only while the
gaps **fit** it: nearly every one within :data:`FIT_TOLERANCE` of a whole multiple of it. A
sensor fired on an uneven schedule, one that reports several echoes a firing, a ring that is
changing its rate and a log stamped in bursts do not fit one period, and the rule then leaves
their marks to ``fresh_seconds`` (review rev10p: with the rank alone, a front sonar fired at
80 / 280 ms lost an obstacle ahead at a quarter of the reads). A log that drops most firings
makes the period a multiple of the true one, which only keeps marks longer (the safe side).

What no test of the gaps can see: a log that drops readings whose value did not change (the
roboND converter's stale repeats, naive polling) drops firings that heard something. Its gaps
may fit a period, and a robot standing before an obstacle would then lose the mark after 1.1
periods instead of ``fresh_seconds``; give such logs ``fresh_periods = inf``. Nor can it tell a
ring that slows to a whole multiple of its period from one whose log drops firings: for up to
:data:`GAP_WINDOW` firings its marks end after 1.1 old periods.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.typing import FloatArray

__all__ = ["FIT_TOLERANCE", "GAP_QUANTILE", "GAP_WINDOW", "LOOP_BATCH", "MAX_MULTIPLE", "MIN_GAPS",
           "FiringPeriods", "fitted_period", "note_kernel", "period_kernel", "row_period"]

GAP_WINDOW = 16
"""Gaps remembered per sensor: the newest, so the period follows a ring that changes its rate."""

MIN_GAPS = 4
"""Gaps a sensor needs before its period is known (until then ``fresh_seconds`` alone bounds its
marks)."""

GAP_QUANTILE = 0.25
"""The period is the remembered gap of this rank (the ``⌊q n⌋``-th shortest of ``n``, from 0): odd
short gaps (a reading duplicated a millisecond late, a stamp that jittered early) rank below
it."""

FIT_TOLERANCE = 0.1
"""A gap fits the period ``p`` when it lies within this share of ``p`` of a whole multiple ``k p``,
``k >= 1``: the jitter a fixed schedule shows (``DEFAULT_FRESH_PERIODS``, 1.1, allows the
same). At most ``⌊n/8⌋`` of ``n`` gaps may miss (2 of 16: a
duplicated reading or two); with more, the sensor has no period."""

MAX_MULTIPLE = 8
"""A gap longer than this many periods counts as a miss: within a tenth of a period, a long
enough gap fits some multiple of a tiny one by chance (two echoes a firing stamped 5 ms apart
would pass for a 5 ms period)."""


#: Batches longer than this look up each sensor once (``np.unique``) instead of each reading in
#: a Python loop: the loop is cheaper for the few readings a robot's batch holds, the lookup for
#: a whole log (0.3 µs a reading, 4 % of the carved grid's time read once per log).
LOOP_BATCH = 64


class FiringPeriods:
    """Per sensor: the time of its newest reading and its newest gaps. The period is worked out
    when it is asked for, once per sensor whose gaps changed: a read happens once per many
    readings, so each reading costs only an append.

    The state is a row of arrays per sensor (its id maps to its row), and noting and fitting
    are compiled (:func:`note_kernel`, :func:`period_kernel`): read every 5 readings, the
    per-sensor Python of the first version (a deque, a sort and a loop per fit) cost about a
    tenth of the carved grid's time (``benchmarks/grid_reads.py``)."""

    def __init__(self) -> None:
        self._rows: dict[int, int] = {}  # sensor id -> its row in the arrays
        self._last = np.full(0, math.nan)  # newest reading's time (NaN: none yet)
        self._gaps = np.zeros((0, GAP_WINDOW))  # a ring of the newest gaps
        self._count = np.zeros(0, dtype=np.int64)  # gaps ever noted
        self._period = np.full(0, math.inf)  # the fit, while not changed
        self._changed = np.zeros(0, dtype=np.bool_)

    def note(self, sensor: npt.NDArray[np.int64], t: FloatArray) -> None:
        """Take a batch's readings, in order (times do not decrease: the batch was validated). A
        reading at the same time as the sensor's previous one is no new firing and adds no gap."""
        self.note_rows(self.rows(sensor), t)

    def rows(self, sensor: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
        """The row of each of ``sensor`` (a new sensor gets the next free row, in the order of
        its first reading): the grid keeps its own per-sensor state by the same rows."""
        rows = self._rows
        if len(sensor) <= LOOP_BATCH:
            at = np.array([rows.setdefault(s, len(rows)) for s in sensor.tolist()],
                          dtype=np.int64)
        else:  # a whole log: a dict lookup per sensor, not per reading; the same rows
            ids, first, inverse = np.unique(sensor, return_index=True, return_inverse=True)
            for s in ids[np.argsort(first, kind="stable")].tolist():
                rows.setdefault(s, len(rows))
            at = np.array([rows[s] for s in ids.tolist()], dtype=np.int64)[inverse.ravel()]
        if len(rows) > len(self._last):
            self._grow(len(rows))
        return at

    @property
    def size(self) -> int:
        """Rows held (at least the sensors seen)."""
        return len(self._last)

    def note_rows(self, rows: npt.NDArray[np.int64], t: FloatArray) -> None:
        """:meth:`note` of the readings of sensor rows ``rows`` (:meth:`rows`)."""
        note_kernel(rows, np.ascontiguousarray(t, dtype=np.float64), self._last, self._gaps,
                    self._count, self._changed)

    def note_state(self) -> tuple[FloatArray, FloatArray, npt.NDArray[np.int64],
                                  npt.NDArray[np.bool_]]:
        """What :func:`note_kernel` takes besides the rows and times: the newest times, the
        gaps, their counts and the rows changed since their last fit (by row)."""
        return self._last, self._gaps, self._count, self._changed

    def fit_state(self) -> tuple[FloatArray, npt.NDArray[np.int64], npt.NDArray[np.bool_],
                                 FloatArray]:
        """What :func:`row_period` takes besides the row: the gaps, their counts, the rows
        changed since their last fit and the fitted periods (by row)."""
        return self._gaps, self._count, self._changed, self._period

    def period(self, sensor: int) -> float:
        """The sensor's firing period in seconds; ``inf`` while fewer than :data:`MIN_GAPS` gaps
        are known or when they do not fit one period."""
        return float(self.periods(np.array([sensor], dtype=np.int64))[0])

    def periods(self, sensors: npt.NDArray[np.int64]) -> FloatArray:
        """:meth:`period` of each sensor."""
        rows = self._rows
        at = np.array([rows.get(s, -1) for s in sensors.tolist()], dtype=np.int64)
        out = np.empty(len(at))
        period_kernel(at, self._gaps, self._count, self._changed, self._period, out)
        return out

    def _grow(self, n: int) -> None:
        """Rows for ``n`` sensors (at least twice as many as before: amortised appends)."""
        old = len(self._last)
        size = max(n, 2 * old, 8)
        extra = size - old
        self._last = np.concatenate((self._last, np.full(extra, math.nan)))
        self._gaps = np.concatenate((self._gaps, np.zeros((extra, GAP_WINDOW))))
        self._count = np.concatenate((self._count, np.zeros(extra, dtype=np.int64)))
        self._period = np.concatenate((self._period, np.full(extra, math.inf)))
        self._changed = np.concatenate((self._changed, np.zeros(extra, dtype=np.bool_)))


@compiled
def note_kernel(rows: npt.NDArray[np.int64], t: FloatArray, last: FloatArray,
                gaps: FloatArray, count: npt.NDArray[np.int64],
                changed: npt.NDArray[np.bool_]) -> None:
    """Each reading ``k`` of sensor row ``rows[k]`` at ``t[k]``: a gap ``t[k] - last`` into the
    row's ring (its oldest gap out once :data:`GAP_WINDOW` are held) when ``t[k]`` is later than
    the row's ``last`` (NaN, the row's first reading, is not)."""
    for k in range(rows.shape[0]):
        row, ts = rows[k], t[k]
        before = last[row]
        last[row] = ts
        if ts > before:  # False for NaN
            gaps[row, count[row] % GAP_WINDOW] = ts - before
            count[row] += 1
            changed[row] = True


@compiled
def period_kernel(rows: npt.NDArray[np.int64], gaps: FloatArray,
                  count: npt.NDArray[np.int64], changed: npt.NDArray[np.bool_],
                  period: FloatArray, out: FloatArray) -> None:
    """``out[k]``: the period of row ``rows[k]`` (``inf`` for -1, a sensor never seen)
    (:func:`row_period`)."""
    for k in range(rows.shape[0]):
        row = rows[k]
        out[k] = math.inf if row < 0 else row_period(row, gaps, count, changed, period)


@compiled_inline
def row_period(row: int, gaps: FloatArray, count: npt.NDArray[np.int64],
               changed: npt.NDArray[np.bool_], period: FloatArray) -> float:
    """The period of row ``row``, refitted (:func:`fitted_period`) if its gaps changed since it
    was last asked for."""
    if changed[row]:
        changed[row] = False
        n = min(count[row], GAP_WINDOW)
        period[row] = fitted_period(np.sort(gaps[row, :n]))
    return float(period[row])


@compiled
def fitted_period(ordered: FloatArray) -> float:
    """The gap of rank ``⌊q n⌋`` of the ``n`` gaps ``ordered`` (shortest first) if at most
    ``⌊n/8⌋`` of them miss a whole multiple ``k`` of it (``1 <= k <=`` :data:`MAX_MULTIPLE`) by
    more than :data:`FIT_TOLERANCE` of it, else ``inf`` (also for fewer than :data:`MIN_GAPS`
    gaps). ``k`` is the nearest whole number, halves to even, as Python's ``round``."""
    n = ordered.shape[0]
    if n < MIN_GAPS:
        return math.inf
    period = float(ordered[int(GAP_QUANTILE * n)])
    tolerance = FIT_TOLERANCE * period
    allowed = n // 8
    misses = 0
    for gap in ordered:
        k = max(np.rint(gap / period), 1.0)
        if k > MAX_MULTIPLE or abs(gap - k * period) > tolerance:
            misses += 1
            if misses > allowed:
                return math.inf
    return period
