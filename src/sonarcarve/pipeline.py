"""Run a method over a whole log: the library call behind ``sonarcarve process``."""

from __future__ import annotations

import math
import time
from array import array
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from sonarcarve.errors import ReadingTypeError, SonarcarveError
from sonarcarve.filters import (
    DropReason,
    MapFilter,
    MapFilterReport,
    ReadingFilter,
    ReadingFilterReport,
    filter_map,
    filter_readings,
    origins_by_id,
)
from sonarcarve.maps import GlobalMap, GlobalMapSink
from sonarcarve.methods.base import SonarMethod
from sonarcarve.readings import ReadingBatch
from sonarcarve.typing import FloatArray, IntArray

__all__ = [
    "FINE_SAMPLES",
    "MIN_SAMPLE_EVERY",
    "ProcessError",
    "ProcessResult",
    "default_sample_every",
    "process_chunks",
    "process_readings",
]

#: Fewest readings between two samples of the unprocessed share by default. A sample stops the
#: method's block kernels and computes every history arc's estimate (about 0.3 ms at history
#: 250): sampled every 25 readings (a tenth of the history, the old default) that halved
#: carving's rate; every thousand or so readings it costs under 0.5 µs a reading.
MIN_SAMPLE_EVERY = 1_000

#: Samples taken at the fine step (a tenth of the history, at least one reading) before the
#: default switches to :func:`default_sample_every`: a log shorter than about this many
#: tenths of a history past the first full one (25,000 readings at history 250) gets exactly
#: the share it always got, and a long one pays the fine step's cost on its first few per cent.
FINE_SAMPLES = 1_000


class ProcessError(SonarcarveError, ValueError):
    """A bad argument to :func:`process_readings` or :func:`process_chunks` (a sampling step
    < 1, a used method, a sink with map filters)."""


@dataclass(frozen=True)
class ProcessResult:
    """What a whole-log run produced and measured.

    Attributes
    ----------
    global_map : GlobalMap
        One point per surviving reading (the ``process`` output); empty when the map went to
        a ``sink``.
    points : int
        Points in the global map (after the map filters, if any), whether kept here or sent to
        a sink.
    readings : int
        Readings processed (after the reading filters, if any).
    mean_unprocessed_share : float
        Mean over the run of the share of history arcs still unprocessed (Table I), sampled
        once the history is full: every ``sample_every`` readings, or by default every tenth
        of the history for the first :data:`FINE_SAMPLES` samples and then every
        :func:`default_sample_every` readings, weighted by step.
    fully_carved, split : int
        Arcs removed by carving, by cause.
    seconds : float
        Wall time spent in the method (sampling for the measures and a sink's time excluded).
    reading_filter : ReadingFilterReport or None
        What the reading filters dropped (None if none ran).
    map_filter : MapFilterReport or None
        What the map filters dropped from the global map (None if none ran).
    """

    global_map: GlobalMap
    points: int
    readings: int
    mean_unprocessed_share: float
    fully_carved: int
    split: int
    seconds: float
    reading_filter: ReadingFilterReport | None = None
    map_filter: MapFilterReport | None = None

    @property
    def readings_per_second(self) -> float:
        """Throughput of the method on this log."""
        return self.readings / self.seconds if self.seconds > 0 else float("inf")


def process_readings(
    batch: ReadingBatch,
    method: SonarMethod,
    *,
    sample_every: int | None = None,
    on_progress: Callable[[int], None] | None = None,
    reading_filter: ReadingFilter | None = None,
    map_filter: MapFilter | None = None,
    sink: GlobalMapSink | None = None,
) -> ProcessResult:
    """Feed ``batch`` to ``method``, finish it, and return the global map with the measures.

    Parameters
    ----------
    batch : ReadingBatch
        The log, in time order; reading ids are row positions.
    method : SonarMethod
        A fresh method.
    sample_every : int, optional
        How often (in readings) to sample the unprocessed share. By default every tenth of
        the history (25 readings for 250 arcs) for the first :data:`FINE_SAMPLES` samples,
        then every :func:`default_sample_every` readings (1,009), each sample weighted by its
        step: short logs get the fine estimate, long ones do not pay for it.
    on_progress : callable, optional
        Called with the number of input rows done after each chunk.
    reading_filter : ReadingFilter, optional
        Reading filters applied before the method; kept readings keep their input row as id.
    map_filter : MapFilter, optional
        Map filters applied to the finished global map.
    sink : GlobalMapSink, optional
        Where the global map goes, a block at a time as arcs leave the history
        (:meth:`SonarMethod.set_global_sink`), instead of :attr:`ProcessResult.global_map`
        (then empty; :attr:`ProcessResult.points` counts the points). Memory then stays flat
        however long the log. The map filters need the whole map, so not with ``map_filter``.

    Raises
    ------
    ProcessError
        ``sample_every`` < 1, a method that has already been fed readings, or both ``sink``
        and ``map_filter``.
    """
    if not isinstance(batch, ReadingBatch):
        msg = (f"process_readings needs a ReadingBatch, got {type(batch).__name__}: build one "
               "with ReadingBatch.from_readings or read_readings_csv")
        raise ReadingTypeError(msg)
    return process_chunks([batch], method, sample_every=sample_every, on_progress=on_progress,
                          reading_filter=reading_filter, map_filter=map_filter, sink=sink)


def process_chunks(
    chunks: Iterable[ReadingBatch],
    method: SonarMethod,
    *,
    sample_every: int | None = None,
    on_progress: Callable[[int], None] | None = None,
    reading_filter: ReadingFilter | None = None,
    map_filter: MapFilter | None = None,
    sink: GlobalMapSink | None = None,
) -> ProcessResult:
    """:func:`process_readings` over a log that comes in consecutive batches.

    The result is the same as :func:`process_readings` on the batches joined, however the log
    is cut: reading ids count rows from the first batch's first row, the jump filter compares a
    sensor's reading with its previous one across batch boundaries, and the unprocessed share
    is sampled at the same readings. Only one batch (and the method's state) is held at a time,
    so a log read with :func:`~sonarcarve.io.readings_csv.iter_readings_csv` is mapped in
    bounded memory, the global map aside; with a ``sink``, the map too (what stays is 8 bytes
    per unprocessed-share sample). The late-echo and driven-through map filters are the
    exception: they look at the whole log, so with them every batch is kept to the end.

    Parameters
    ----------
    chunks : iterable of ReadingBatch
        The log in time order, cut anywhere. A batch is validated as it is fed to the method
        (against the time of the reading before it); an error raised by the iterable itself
        (a bad line of a file) passes through.
    method, sample_every, on_progress, reading_filter, map_filter, sink
        As :func:`process_readings`.

    Raises
    ------
    ProcessError
        As :func:`process_readings`.
    """
    _check_run(method, sample_every, map_filter, sink)
    timed = None if sink is None else _TimedSink(sink)
    if timed is not None:
        method.set_global_sink(timed)
    run = _Run(method, _schedule(method, sample_every), on_progress)
    chunk_filter = None if reading_filter is None else _ChunkFilter(reading_filter)
    origins = (_Origins() if map_filter is not None and map_filter.occlusion_depth is not None
               else None)
    # Every reading, the dropped ones' too (a reading the filters refuse was still taken where
    # the robot stood), for the filters that look at the whole log: ids are their rows.
    log: list[ReadingBatch] | None = (
        [] if map_filter is not None and (map_filter.driven_through is not None
                                          or map_filter.late_echo_period is not None)
        else None)
    rows = 0
    for chunk in chunks:
        ids = np.arange(rows, rows + len(chunk), dtype=np.int64)
        rows += len(chunk)
        if log is not None:
            log.append(chunk)
        if chunk_filter is not None:
            keep = chunk_filter.keep(chunk)
            chunk, ids = chunk[keep], ids[keep]
        if origins is not None:
            origins.note(chunk, ids)
        run.feed(chunk, ids)
    run.flush()
    filter_report = None
    if chunk_filter is not None:
        filter_report = chunk_filter.report
        if on_progress is not None:
            on_progress(filter_report.total)
    readings = None if log is None else ReadingBatch.concatenate(log, validate=False)
    return _finish(run, timed, filter_report, map_filter, origins, readings)


def _check_run(method: SonarMethod, sample_every: int | None, map_filter: MapFilter | None,
               sink: GlobalMapSink | None) -> None:
    """Refuse what :func:`process_chunks` cannot do (its ``Raises``)."""
    if not isinstance(method, SonarMethod):
        # A method name is refused rather than accepted: its parameters would then need a
        # second way in (MethodConfig goes to make_method), and the slip is easy to name.
        made = (f"make_method({method!r})" if isinstance(method, str)
                else "make_method(name, MethodConfig(...))")
        msg = (f"process_readings needs a method object, got {type(method).__name__} "
               f"{method!r:.40}: pass {made}")
        raise ProcessError(msg)
    if sample_every is not None and sample_every < 1:
        # 0 would silently mean the default, and a negative step would process nothing.
        msg = f"sample_every must be at least 1 reading, got {sample_every}"
        raise ProcessError(msg)
    if method.readings:
        msg = (f"process_readings needs a fresh method; this {method.name} method has "
               f"already been fed {method.readings} readings")
        raise ProcessError(msg)
    if sink is not None and map_filter is not None:
        msg = "the map filters need the whole global map; run without a sink to filter the map"
        raise ProcessError(msg)


def _schedule(method: SonarMethod, sample_every: int | None) -> _Schedule:
    """``sample_every`` throughout, or by default a tenth of the history, then coarser."""
    if sample_every is not None:
        return _Schedule(fine=sample_every, coarse=sample_every)
    return _Schedule(fine=max(1, method.history.capacity // 10),
                     coarse=default_sample_every(method.history.capacity))


def _finish(run: _Run, timed: _TimedSink | None, filter_report: ReadingFilterReport | None,
            map_filter: MapFilter | None, origins: _Origins | None = None,
            readings: ReadingBatch | None = None) -> ProcessResult:
    """Finish the run's method and gather what it measured (the map filtered last)."""
    method = run.method
    measures = method.measures()
    mean_share = run.mean_share() if run.shares else measures.unprocessed_share
    tic = time.perf_counter()
    global_map = method.finish()
    seconds = run.seconds + time.perf_counter() - tic
    if timed is not None:  # the method's time: writing the map is the sink's
        seconds = max(0.0, seconds - timed.seconds)
    points = method.committed_points
    map_report = None
    if map_filter is not None:
        kept = filter_map(global_map, map_filter,
                          None if origins is None else origins.of(global_map.reading_id), readings)
        global_map, map_report = kept.points, kept.report
        points = len(global_map)
    return ProcessResult(
        global_map=global_map,
        points=points,
        readings=run.readings,
        mean_unprocessed_share=mean_share,
        fully_carved=measures.fully_carved,
        split=measures.split,
        seconds=seconds,
        reading_filter=filter_report,
        map_filter=map_report,
    )


def default_sample_every(history_size: int) -> int:
    """Readings between two samples of the unprocessed share by default: the first prime at
    least :data:`MIN_SAMPLE_EVERY` and a tenth of ``history_size``.

    A tenth of the history keeps the cost of a sample (which grows with the history) a fixed
    share of the run. Prime, so that a ring of sensors firing in turn is sampled after each of
    its sensors alike: every 1,000 readings, a ring of 8 or 16 sensors would always be sampled
    after the same one or two sensors, and the share, which varies with the sensor that fired
    last, would be biased (on the benchmark's 16-sensor ring corridor, 0.2 points below
    sampling every 25 readings over 200,000 readings). Fewer samples make the mean a noisier
    estimate on short logs: a few tenths of a point at 50,000 readings (docs/RESULTS.md).

    Examples
    --------
    >>> default_sample_every(250), default_sample_every(10_000), default_sample_every(100_000)
    (1009, 1009, 10007)
    """
    every = max(MIN_SAMPLE_EVERY, history_size // 10)
    while not _is_prime(every):
        every += 1
    return every


def _is_prime(n: int) -> bool:
    if n < 2:
        return False
    return all(n % k for k in range(2, math.isqrt(n) + 1))


class _TimedSink:
    """A sink passed through, the time spent in it counted (not the method's time)."""

    def __init__(self, sink: GlobalMapSink) -> None:
        self.sink = sink
        self.seconds = 0.0

    def commit(self, points: GlobalMap) -> None:
        tic = time.perf_counter()
        self.sink.commit(points)
        self.seconds += time.perf_counter() - tic


@dataclass(frozen=True)
class _Schedule:
    """Readings between samples of the unprocessed share: ``fine`` for the first
    :data:`FINE_SAMPLES` samples, then ``coarse``."""

    fine: int
    coarse: int

    def step(self, samples: int) -> int:
        return self.fine if samples < FINE_SAMPLES else self.coarse


class _Origins:
    """The sensor origin of every reading fed, by id, for the occlusion filter (24 bytes a
    reading, id and origin, kept only when that filter is on: a map does not hold its points'
    origins)."""

    def __init__(self) -> None:
        self._ids: list[IntArray] = []
        self._xy: list[tuple[FloatArray, FloatArray]] = []

    def note(self, batch: ReadingBatch, ids: IntArray) -> None:
        """Remember the origins of ``batch``, whose reading ids are ``ids``."""
        self._ids.append(ids)
        self._xy.append((batch.x, batch.y))

    def of(self, reading_id: IntArray) -> FloatArray:
        """The origins of the readings ``reading_id``, shape (n, 2)."""
        if not self._ids:
            return np.zeros((0, 2))
        return origins_by_id(reading_id, np.concatenate(self._ids),
                             np.concatenate([x for x, _ in self._xy]),
                             np.concatenate([y for _, y in self._xy]))


class _Run:
    """Feeds readings to a method in steps of exactly the schedule's length, whatever the
    batches they come in, sampling the unprocessed share and reporting progress after each
    step."""

    def __init__(self, method: SonarMethod, schedule: _Schedule,
                 on_progress: Callable[[int], None] | None) -> None:
        self.method = method
        self.schedule = schedule
        self.on_progress = on_progress
        # 8 bytes a sample (one per step), not a Python float each: a long run stays flat.
        self.shares = array("d")
        self.weights = array("d")  # the step each sample stands for
        self.seconds = 0.0
        self.readings = 0
        self._held: list[tuple[ReadingBatch, IntArray]] = []  # less than one step
        self._held_count = 0

    @property
    def every(self) -> int:
        """Readings in the current step."""
        return self.schedule.step(len(self.shares))

    def mean_share(self) -> float:
        """The run's mean unprocessed share, each sample weighted by the step it stands for
        (the last, shorter step by the step it would have been)."""
        shares, weights = np.frombuffer(self.shares), np.frombuffer(self.weights)
        if np.all(weights == weights[0]):  # one step throughout: the plain mean, bit for bit
            return float(np.mean(shares))
        return float(np.average(shares, weights=weights))

    def feed(self, batch: ReadingBatch, ids: IntArray) -> None:
        """Queue ``batch`` (reading ids ``ids``); run every whole step."""
        start = 0
        if self._held:
            start = min(len(batch), self.every - self._held_count)
            self._hold(batch[:start], ids[:start])
            if self._held_count < self.every:
                return
            self.flush()
        while len(batch) - start >= (every := self.every):
            self._step(batch[start : start + every], ids[start : start + every])
            start += every
        self._hold(batch[start:], ids[start:])

    def flush(self) -> None:
        """Run what is queued as one step (the last, shorter step of the log)."""
        if self._held:
            held, self._held, self._held_count = self._held, [], 0
            batch = held[0][0] if len(held) == 1 else ReadingBatch.concatenate(
                [b for b, _ in held], validate=False)  # each was checked where it came from
            self._step(batch, np.concatenate([i for _, i in held]))

    def _hold(self, batch: ReadingBatch, ids: IntArray) -> None:
        if len(batch):
            self._held.append((batch, ids))
            self._held_count += len(batch)

    def _step(self, batch: ReadingBatch, ids: IntArray) -> None:
        method = self.method
        tic = time.perf_counter()
        first_id, last_id = int(ids[0]), int(ids[-1])
        if last_id - first_id == len(ids) - 1:  # no gap (ids increase): one call
            method.add_many(batch, first_id=first_id)
        else:
            # Runs of consecutive ids go in one call; the reading filter left gaps between them.
            cuts = np.flatnonzero(np.diff(ids) != 1) + 1
            for run in np.split(np.arange(len(ids)), cuts):
                first, stop = int(run[0]), int(run[-1]) + 1
                if stop - first == 1:
                    method.add(batch[first], int(ids[first]))
                else:
                    method.add_many(batch[first:stop], first_id=int(ids[first]))
        self.seconds += time.perf_counter() - tic
        self.readings += len(batch)
        if self.readings >= method.history.capacity:
            self.weights.append(self.every)  # the nominal step, the last shorter one included
            self.shares.append(method.measures().unprocessed_share)
        if self.on_progress is not None:  # progress counts input rows, dropped ones included
            self.on_progress(last_id + 1)


class _ChunkFilter:
    """:func:`~sonarcarve.filters.filter_readings` over a log cut into batches.

    Each batch is filtered together with, in front of it, the last reading that passed the
    range filters of every sensor it shares with the log so far, so that the jump filter
    compares across the cut exactly as it would on the whole log.
    """

    def __init__(self, spec: ReadingFilter) -> None:
        self.spec = spec
        self._previous: dict[int, float] = {}  # sensor -> its last range-filtered range
        self._reasons = np.zeros(len(DropReason), dtype=np.int64)

    def keep(self, batch: ReadingBatch) -> IntArray:
        """Rows of ``batch`` kept (the log's next rows)."""
        if self.spec.jump_threshold is None:
            lead_sensor, lead_range = np.zeros(0, np.int64), np.zeros(0)
        else:
            sensors = np.unique(batch.sensor).tolist()
            lead = [(s, self._previous[s]) for s in sensors if s in self._previous]
            lead_sensor = np.array([s for s, _ in lead], dtype=np.int64)
            lead_range = np.array([r for _, r in lead], dtype=np.float64)
        m = len(lead_sensor)
        zeros = np.zeros(m)
        joined = ReadingBatch(
            t=np.concatenate([zeros, batch.t]), sensor=np.concatenate([lead_sensor, batch.sensor]),
            x=np.concatenate([zeros, batch.x]), y=np.concatenate([zeros, batch.y]),
            theta=np.concatenate([zeros, batch.theta]),
            range=np.concatenate([lead_range, batch.range]),
            beam_width=np.concatenate([zeros, batch.beam_width]),
        )
        reasons = filter_readings(joined, self.spec).reasons[m:]
        self._reasons += np.bincount(reasons.astype(np.int64), minlength=len(DropReason))
        passed = np.flatnonzero((reasons == DropReason.KEPT) | (reasons == DropReason.JUMP))
        if self.spec.jump_threshold is not None and passed.size:
            # Each sensor's last reading that passed the range filters, jumped or not.
            last = len(passed) - 1 - np.unique(batch.sensor[passed][::-1], return_index=True)[1]
            rows = passed[last]
            self._previous.update(zip(batch.sensor[rows].tolist(), batch.range[rows].tolist(),
                                      strict=True))
        return np.flatnonzero(reasons == DropReason.KEPT).astype(np.int64)

    @property
    def report(self) -> ReadingFilterReport:
        """Counts since the first batch."""
        c = self._reasons
        return ReadingFilterReport(total=int(c.sum()), too_far=int(c[DropReason.TOO_FAR]),
                                   too_near=int(c[DropReason.TOO_NEAR]),
                                   jumps=int(c[DropReason.JUMP]))
