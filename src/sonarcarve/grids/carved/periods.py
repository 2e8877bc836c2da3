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
from collections import deque

import numpy as np
import numpy.typing as npt

from sonarcarve.typing import FloatArray

__all__ = ["FIT_TOLERANCE", "GAP_QUANTILE", "GAP_WINDOW", "MAX_MULTIPLE", "MIN_GAPS",
           "FiringPeriods"]

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


class FiringPeriods:
    """Per sensor: the time of its newest reading and its newest gaps. The period is worked out
    when it is asked for, once per sensor whose gaps changed: a read happens once per many
    readings, so each reading costs only an append."""

    def __init__(self) -> None:
        self._last: dict[int, float] = {}
        self._gaps: dict[int, deque[float]] = {}
        self._changed: set[int] = set()
        self._period: dict[int, float] = {}

    def note(self, sensor: npt.NDArray[np.int64], t: FloatArray) -> None:
        """Take a batch's readings, in order (times do not decrease: the batch was validated). A
        reading at the same time as the sensor's previous one is no new firing and adds no gap."""
        last, gaps, changed = self._last, self._gaps, self._changed
        for s, ts in zip(sensor.tolist(), t.tolist(), strict=True):
            before = last.get(s)
            last[s] = ts
            if before is not None and ts > before:
                if s not in gaps:
                    gaps[s] = deque(maxlen=GAP_WINDOW)
                gaps[s].append(ts - before)
                changed.add(s)

    def period(self, sensor: int) -> float:
        """The sensor's firing period in seconds; ``inf`` while fewer than :data:`MIN_GAPS` gaps
        are known or when they do not fit one period."""
        if sensor in self._changed:
            self._changed.discard(sensor)
            self._period[sensor] = _fitted_period(sorted(self._gaps[sensor]))
        return self._period.get(sensor, math.inf)

    def periods(self, sensors: npt.NDArray[np.int64]) -> FloatArray:
        """:meth:`period` of each sensor."""
        return np.array([self.period(s) for s in sensors.tolist()], dtype=np.float64)


def _fitted_period(ordered: list[float]) -> float:
    """The gap of rank ``⌊q n⌋`` of the ``n`` gaps ``ordered`` (shortest first) if at most
    ``⌊n/8⌋`` of them miss a whole multiple ``k`` of it (``1 <= k <=`` :data:`MAX_MULTIPLE`) by
    more than :data:`FIT_TOLERANCE` of it, else ``inf`` (also for fewer than :data:`MIN_GAPS`
    gaps)."""
    n = len(ordered)
    if n < MIN_GAPS:
        return math.inf
    period = ordered[int(GAP_QUANTILE * n)]
    # Plain Python, run once per reading when the map is read often: the tolerance once, no
    # builtin calls in the loop, and out at the first miss too many (the same answer).
    tolerance = FIT_TOLERANCE * period
    allowed = n // 8
    misses = 0
    for gap in ordered:
        k = round(gap / period)
        if k < 1:
            k = 1
        if k > MAX_MULTIPLE or abs(gap - k * period) > tolerance:
            misses += 1
            if misses > allowed:
                return math.inf
    return period
