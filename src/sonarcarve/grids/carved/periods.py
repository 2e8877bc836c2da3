"""Each sensor's firing period as the log shows it, :class:`FiringPeriods`: how long the newest
echo's mark may last before the sensor has fired again (``docs/carved-grid.md``, "Stale marks").

A ring fires each sensor on a fixed schedule, so the times between two readings of one sensor
are its period, or a multiple of it where the log dropped firings that heard nothing (an
echoes-only log). The shortest such time would be the period, but one duplicated or
near-duplicated reading would make it tiny and end that sensor's marks at once. So the period
is a low quantile of the sensor's recent gaps, and is known only after a few of them: a few
odd gaps cannot shorten it, and a log that drops many firings makes it a multiple of the true
period, which only keeps marks longer (the safe side).
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np
import numpy.typing as npt

from sonarcarve.typing import FloatArray

__all__ = ["GAP_QUANTILE", "GAP_WINDOW", "MIN_GAPS", "FiringPeriods"]

GAP_WINDOW = 16
"""Gaps remembered per sensor: the newest, so the period follows a ring that changes its rate."""

MIN_GAPS = 4
"""Gaps a sensor needs before its period is known (until then ``fresh_seconds`` alone bounds its
marks)."""

GAP_QUANTILE = 0.25
"""The period is the remembered gap of this rank (the ``⌊q n⌋``-th shortest of ``n``, from 0): up
to a quarter of odd short gaps (duplicated readings, a stamp that jittered early) cannot shorten
it."""


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
        """The sensor's firing period in seconds, ``inf`` while fewer than :data:`MIN_GAPS`
        gaps are known."""
        if sensor in self._changed:
            self._changed.discard(sensor)
            ordered = sorted(self._gaps[sensor])
            if len(ordered) >= MIN_GAPS:
                self._period[sensor] = ordered[int(GAP_QUANTILE * len(ordered))]
        return self._period.get(sensor, math.inf)

    def periods(self, sensors: npt.NDArray[np.int64]) -> FloatArray:
        """:meth:`period` of each sensor."""
        return np.array([self.period(s) for s in sensors.tolist()], dtype=np.float64)
