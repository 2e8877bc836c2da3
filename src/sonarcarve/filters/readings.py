"""Reading filters and map filters (paper, Appendix B and Fig. 13b).

Reading filters drop sonar readings before they reach a method:

- **maximum range**: echoes farther than ``max_range`` (the paper uses 150 inches, 3.81 m, on
  its Scout2, whose sensors sit 10.25 inches above the floor: see :data:`PAPER_MAX_RANGE`);
- **minimum range**: echoes nearer than ``min_range`` (ringing, the robot's own body);
- **jump filter**: a sensor whose range changes by more than ``jump_threshold`` between two of
  its successive readings is ignored for one cycle. Here a *cycle* is precisely *that sensor's
  next reading*: the reading that jumped is dropped. The comparison is always with the same
  sensor's previous reading that passed the range filters, whether the jump filter kept it or
  not, so a lasting change (a new wall comes into view) costs exactly one reading and an isolated
  spike (cross-talk, a floor bounce) costs two: the spike and the reading after it, which jumps
  back. A sensor's first reading is always kept.

A no-echo reading (``range`` inf: the sensor heard nothing up to its ``max_range``) is no echo
that any of them judges: every reading filter keeps it, and the jump filter compares a sensor's
echoes across it.

Each reading is dropped by the first filter, in that order, that rejects it, and counted under
it. The batch form (:func:`filter_readings`) and the streaming form
(:class:`ReadingFilterStream`, one reading at a time) make the same decisions. Dropping readings
must not renumber them: :class:`FilteredReadings` keeps the input row of every kept reading so
that the ids in a map still point at the input file.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np
import numpy.typing as npt

from sonarcarve.constants import INCH
from sonarcarve.filters.checks import FilterError, check_positive
from sonarcarve.readings import Reading, ReadingBatch
from sonarcarve.typing import FloatArray, IntArray

__all__ = ["PAPER_MAX_RANGE", "DropReason", "FilteredReadings", "ReadingFilter",
           "ReadingFilterReport", "ReadingFilterStream", "filter_readings"]

#: The paper's maximum range (Appendix B): 150 inches, in metres. Specific to the Scout2's
#: sensors and mounting height; not a default anywhere.
PAPER_MAX_RANGE = 150 * INCH


class DropReason(IntEnum):
    """Why a reading filter dropped a reading (``KEPT`` if it did not)."""

    KEPT = 0
    TOO_FAR = 1  #: an echo's range > max_range (a no-echo reading never is)
    TOO_NEAR = 2  #: range < min_range
    JUMP = 3  #: range jumped by more than jump_threshold since the sensor's previous reading



@dataclass(frozen=True)
class ReadingFilter:
    """Which reading filters to apply; ``None`` switches a filter off.

    Attributes
    ----------
    max_range : float or None
        Drop echoes with range > ``max_range``, metres (paper: :data:`PAPER_MAX_RANGE`). A
        no-echo reading is kept with its own ``max_range``, even a longer one: the filter is
        for long echoes, which are the likelier crosstalk and multipath, and a silence is
        none of those (a decision; clipping its free space to this value would be the
        other).
    min_range : float or None
        Drop readings with range < ``min_range``, metres.
    jump_threshold : float or None
        Drop a reading whose range differs from its sensor's previous (range-filtered) reading
        by more than this, metres.

    Raises
    ------
    FilterError
        A value that is not a finite positive number, or ``min_range > max_range``.
    """

    max_range: float | None = None
    min_range: float | None = None
    jump_threshold: float | None = None

    def __post_init__(self) -> None:
        check_positive("max_range", self.max_range)
        check_positive("min_range", self.min_range)
        check_positive("jump_threshold", self.jump_threshold)
        if (self.max_range is not None and self.min_range is not None
                and self.min_range > self.max_range):
            msg = f"min_range ({self.min_range}) exceeds max_range ({self.max_range})"
            raise FilterError(msg)

    @property
    def active(self) -> bool:
        """True if at least one filter is on."""
        return any(v is not None for v in (self.max_range, self.min_range, self.jump_threshold))


@dataclass(frozen=True)
class ReadingFilterReport:
    """How many readings each reading filter dropped.

    Attributes
    ----------
    total : int
        Readings in.
    too_far, too_near, jumps : int
        Readings dropped by the maximum-range, minimum-range and jump filters.
    """

    total: int
    too_far: int = 0
    too_near: int = 0
    jumps: int = 0

    @property
    def kept(self) -> int:
        """Readings out."""
        return self.total - self.too_far - self.too_near - self.jumps

    @classmethod
    def from_reasons(cls, reasons: npt.NDArray[np.int8]) -> ReadingFilterReport:
        """Counts from an array of :class:`DropReason` codes."""
        counts = np.bincount(reasons.astype(np.int64), minlength=len(DropReason))
        return cls(total=int(reasons.shape[0]), too_far=int(counts[DropReason.TOO_FAR]),
                   too_near=int(counts[DropReason.TOO_NEAR]), jumps=int(counts[DropReason.JUMP]))


@dataclass(frozen=True, eq=False)
class FilteredReadings:
    """The result of :func:`filter_readings`.

    Attributes
    ----------
    batch : ReadingBatch
        The kept readings, in input order.
    ids : ndarray of int64, shape (len(batch),)
        Input row (0-based) of each kept reading: feed these as reading ids so that map ids
        still point at the input.
    reasons : ndarray of int8, shape (n_in,)
        :class:`DropReason` code of every input reading.
    report : ReadingFilterReport
        Counts per filter.
    """

    batch: ReadingBatch
    ids: IntArray
    reasons: npt.NDArray[np.int8]
    report: ReadingFilterReport


def _range_reasons(r: FloatArray, spec: ReadingFilter) -> npt.NDArray[np.int8]:
    reasons = np.zeros(r.shape[0], dtype=np.int8)
    if spec.min_range is not None:
        reasons[r < spec.min_range] = DropReason.TOO_NEAR
    if spec.max_range is not None:  # a no-echo reading (inf) is free space, not a far echo
        reasons[(r > spec.max_range) & np.isfinite(r)] = DropReason.TOO_FAR
    return reasons


def filter_readings(batch: ReadingBatch, spec: ReadingFilter) -> FilteredReadings:
    """Apply the reading filters of ``spec`` to a whole log (vectorised).

    Parameters
    ----------
    batch : ReadingBatch
        The log in stream order; row ``i`` is reading id ``i``.
    spec : ReadingFilter
        Which filters, with which thresholds.

    Returns
    -------
    FilteredReadings
        Kept readings, their input rows, and per-filter counts.

    Examples
    --------
    >>> from sonarcarve.readings import ReadingBatch
    >>> b = ReadingBatch.from_arrays(t=[0, 1, 2, 3], sensor=[0, 0, 0, 0], x=[0] * 4, y=[0] * 4,
    ...                              theta=[0] * 4, range=[1.0, 1.1, 3.0, 3.0])
    >>> out = filter_readings(b, ReadingFilter(jump_threshold=0.5))
    >>> out.ids.tolist(), out.report.jumps  # 3.0 jumped; the second 3.0 agrees with it
    ([0, 1, 3], 1)
    """
    reasons = _range_reasons(batch.range, spec)
    if spec.jump_threshold is not None:  # among echoes only: a silence is no range to jump
        passed = np.flatnonzero((reasons == DropReason.KEPT) & np.isfinite(batch.range))
        sensors = batch.sensor[passed]
        # Stable sort by sensor keeps each sensor's readings in stream order, so a difference
        # between neighbours of one sensor's run is the change since its previous reading.
        order = np.argsort(sensors, kind="stable")
        r = batch.range[passed][order]
        same_sensor = np.concatenate(([False], sensors[order][1:] == sensors[order][:-1]))
        jumped = same_sensor & (np.abs(np.diff(r, prepend=0.0)) > spec.jump_threshold)
        reasons[passed[order[jumped]]] = DropReason.JUMP
    keep = np.flatnonzero(reasons == DropReason.KEPT).astype(np.int64)
    return FilteredReadings(batch=batch[keep], ids=keep, reasons=reasons,
                            report=ReadingFilterReport.from_reasons(reasons))


class ReadingFilterStream:
    """The reading filters of ``spec`` applied one reading at a time (same decisions as
    :func:`filter_readings`).

    Examples
    --------
    >>> from sonarcarve.readings import Reading
    >>> stream = ReadingFilterStream(ReadingFilter(max_range=3.81))
    >>> stream.check(Reading(0.0, 0, 0.0, 0.0, 0.0, 5.0)).name
    'TOO_FAR'
    >>> stream.report.too_far
    1
    """

    def __init__(self, spec: ReadingFilter) -> None:
        self.spec = spec
        self._previous: dict[int, float] = {}  # sensor -> its previous range-filtered range
        self._counts = np.zeros(len(DropReason), dtype=np.int64)

    def check(self, reading: Reading) -> DropReason:
        """Decide on the next reading of the stream (and remember it for the jump filter)."""
        spec = self.spec
        reason = DropReason.KEPT
        if reading.no_echo:  # free space up to its own max_range: no echo to judge
            self._counts[reason] += 1
            return reason
        if spec.max_range is not None and reading.range > spec.max_range:
            reason = DropReason.TOO_FAR
        elif spec.min_range is not None and reading.range < spec.min_range:
            reason = DropReason.TOO_NEAR
        else:
            previous = self._previous.get(reading.sensor)
            self._previous[reading.sensor] = reading.range
            if (spec.jump_threshold is not None and previous is not None
                    and abs(reading.range - previous) > spec.jump_threshold):
                reason = DropReason.JUMP
        self._counts[reason] += 1
        return reason

    def accept(self, reading: Reading) -> bool:
        """True if the next reading of the stream is kept."""
        return self.check(reading) is DropReason.KEPT

    @property
    def report(self) -> ReadingFilterReport:
        """Counts since the start of the stream."""
        c = self._counts
        return ReadingFilterReport(total=int(c.sum()), too_far=int(c[DropReason.TOO_FAR]),
                                   too_near=int(c[DropReason.TOO_NEAR]),
                                   jumps=int(c[DropReason.JUMP]))

