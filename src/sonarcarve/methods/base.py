"""What every sonar method shares: a history, per-arc models, a local and a global map.

A *model* (centerline, carving, ATM) keeps its own per-row state beside a shared
:class:`~sonarcarve.history.SonarHistory` and turns any set of rows into :class:`Estimates`. A
*method* owns one history, feeds each new reading to its models, and combines their estimates
into one point per surviving arc. Running carving and ATM on one history is then just a method
with two models (paper, section 5-A: "arc carving and ATM can be run in parallel using the same
data, without interfering with each other").

A *no-echo* reading (``range`` = +inf, :attr:`~sonarcarve.readings.Reading.no_echo`) is free
space only: it never enters the history, never yields a point, and still consumes its reading
id (ids are input rows). Each model sees it through :meth:`ArcModel.on_no_echo`: carving carves
the older arcs with its beam up to ``max_range - ε`` (eq. 3.2 with ``R = max_range - ε``; the
paper's Appendix B treats max-range readings as "no return"), evidence carving adds its
free-space evidence, centerline and ATM ignore it (it is counted in :attr:`Measures.no_echo`).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar, TypeVar

import numpy as np

from sonarcarve.constants import MIN_BEAM_WIDTH
from sonarcarve.errors import MethodStateError, ReadingTypeError
from sonarcarve.geometry import ArcFate
from sonarcarve.geometry._compiled import compiled
from sonarcarve.history import DEFAULT_HISTORY_SIZE, SonarHistory
from sonarcarve.maps import (
    CountingSink,
    GlobalMap,
    GlobalMapBuilder,
    GlobalMapSink,
    LocalMap,
    PointSource,
)
from sonarcarve.methods.config import check_beam_width
from sonarcarve.readings import (
    DEFAULT_BEAM_WIDTH,
    MAX_ANGLE,
    MAX_POSITION,
    MAX_READING_RANGE,
    MAX_SENSOR,
    MAX_TIME,
    Reading,
    ReadingBatch,
    check_reading,
)
from sonarcarve.typing import BoolArray, FloatArray, Int8Array, SlotArray

__all__ = [
    "ArcFate",
    "ArcModel",
    "CommitListener",
    "Estimates",
    "Measures",
    "SonarMethod",
    "arc_point",
    "slot_indices",
    "source_codes",
]

_M = TypeVar("_M", LocalMap, GlobalMap)


@dataclass(frozen=True, eq=False)
class Estimates:
    """One model's view of some history rows, arrays of shape (n,) (``xy``: (n, 2)).

    Attributes
    ----------
    alive : bool
        The arc still yields a point (not fully carved, not split).
    processed : bool
        The arc has interacted with another arc as the model prescribes (section 5-B): carved at
        least once for carving, at least one kept intersection for ATM, always for centerline.
        Arcs that carving removed count as processed.
    xy : float, shape (n, 2)
        The point, world frame (meaningless where not ``alive``).
    width : float
        Angular width behind the point, radians.
    max_error : float
        Upper bound on the point's error, metres.
    source : int8
        :class:`~sonarcarve.maps.PointSource` code.
    fate : int8 or None
        :class:`~sonarcarve.geometry.ArcFate` code of each arc: ``ALIVE``, or why a dead arc
        died (``FULLY_CARVED``, ``SPLIT``), where the model knows (carving and the methods that
        run it); None for models that never remove an arc (centerline, ATM).
    confidence : float or None
        Probability (0-1) that the point is a real surface, for models that estimate it; None
        otherwise (the map then holds NaN).
    """

    alive: BoolArray
    processed: BoolArray
    xy: FloatArray
    width: FloatArray
    max_error: FloatArray
    source: Int8Array
    fate: Int8Array | None = None
    confidence: FloatArray | None = None


#: Called with the history, the committed slots (oldest first) and their final estimates.
CommitListener = Callable[[SonarHistory, "SlotArray", Estimates], None]


@dataclass(frozen=True)
class Measures:
    """The paper's measures of a method at one moment (sections 5-B and 5-C).

    Attributes
    ----------
    readings : int
        Readings added so far.
    in_history : int
        Arcs currently in the history.
    unprocessed_share : float
        Share (0-1) of history arcs not yet processed (Table I's measure).
    widths : ndarray, shape (alive,)
        Angular widths θ_d of the surviving history arcs (eq. 5.1).
    fully_carved : int
        Arcs removed because carving emptied them, since the start.
    split : int
        Arcs removed because carving would have split them, since the start.
    no_echo : int
        No-echo readings among ``readings`` (free space only, never in the history).
    """

    readings: int
    in_history: int
    unprocessed_share: float
    widths: FloatArray = field(repr=False)
    fully_carved: int = 0
    split: int = 0
    no_echo: int = 0


class ArcModel(ABC):
    """Per-row state of one sonar model over a shared history.

    Subclasses keep arrays of length ``history.storage_size`` indexed by slot. They must touch
    only live slots (``history.slots()``) when a reading arrives: retired rows are frozen until
    they are committed to the global map.
    """

    def __init__(self, history: SonarHistory) -> None:
        self.history = history

    @abstractmethod
    def on_add_many(self, first: int, count: int) -> None:
        """Take in the arcs of sequence numbers ``first .. first + count - 1``, in order, each
        against the live arcs before it; they are already stored in the history
        (:meth:`~sonarcarve.history.SonarHistory.append_many`, or
        :meth:`~sonarcarve.history.SonarHistory.append` for a block of one).

        The one hook a model implements: :meth:`SonarMethod.add` calls it with a block of one
        arc, :meth:`SonarMethod.add_many` with whole blocks. A model must read no history row
        newer than the arc it is taking in, so that the result is the same whatever the blocks
        (the compiled models run the whole block in one call, with no Python between arcs).
        """

    def on_no_echo(self, reading: Reading, beam_width: float) -> None:
        """Let a no-echo reading (``range`` = +inf, free up to ``reading.max_range`` metres,
        beam width ``beam_width`` radians) act on the live arcs of the history; it adds no arc.

        This default ignores it (centerline, ATM: a beam that heard nothing places no point).
        """
        del reading, beam_width  # nothing to do: deliberately not abstract

    @abstractmethod
    def estimates(self, slots: SlotArray) -> Estimates:
        """This model's estimates for ``slots``, vectorised."""

    def check_usable(self) -> None:
        """Raise the error that stopped this model for good, if one did (its state lost
        something, e.g. crossings its store could not hold, so its maps would be wrong).

        :class:`SonarMethod` asks every model before it stores a reading and before it reads
        a map, so a stopped method refuses everything. This default never stops.
        """
        return  # deliberately not abstract: most models cannot fail

    def counters(self) -> dict[str, int]:
        """Event counts since the start (for example fully carved and split arcs)."""
        return {}


class SonarMethod(ABC):
    """A streaming sonar processing method.

    Feed it readings with :meth:`add` or :meth:`add_many`; ask for :meth:`local_map` at any time;
    call :meth:`finish` at the end of a log to get the :class:`~sonarcarve.maps.GlobalMap`.

    The global map is kept in memory unless :meth:`set_global_sink` sends it elsewhere (a file,
    a callback) as arcs leave the history; then the method holds only its history, and
    :meth:`global_map` and :meth:`finish` cannot return the points (see there).

    Every reading is checked on the way in (:func:`~sonarcarve.readings.check_reading`): a bad
    one raises :class:`~sonarcarve.readings.ReadingsError` and leaves the method as it was.

    Parameters
    ----------
    history_size : int
        Arcs kept in the history (paper: 250).
    beam_width : float
        Beam width φ in radians, used for readings whose own ``beam_width`` is NaN.

    Both are checked by :class:`~sonarcarve.methods.config.MethodConfig`'s rules (subclasses
    validate their whole configuration that way before calling this constructor).
    """

    #: Name used by the CLI (``--method``).
    name: ClassVar[str]

    def __init__(
        self, history_size: int = DEFAULT_HISTORY_SIZE, beam_width: float = DEFAULT_BEAM_WIDTH
    ) -> None:
        self.beam_width = check_beam_width(beam_width)
        self.history = SonarHistory(history_size, on_evict=self._commit)
        self._global = _GlobalFeed()
        self._readings = 0
        self._no_echo = 0  # no-echo readings among them
        self._last_t = -math.inf  # time of the newest reading: times never go backwards
        self._finished = False
        self._listeners: list[CommitListener] = []
        self._local: LocalMap | None = None  # local_map() until the next reading
        self.models: tuple[ArcModel, ...] = self._make_models()

    @abstractmethod
    def _make_models(self) -> tuple[ArcModel, ...]:
        """The models this method runs on its history."""

    def _combine(self, estimates: tuple[Estimates, ...]) -> Estimates:
        """One estimate per row from the models' estimates (same order as ``models``).

        This default is the only model's; a method with more models overrides it (or
        :meth:`_estimates`, when its estimate is not a per-model combination).
        """
        if len(estimates) != 1:
            msg = f"{type(self).__name__} runs {len(estimates)} models: override _combine"
            raise NotImplementedError(msg)
        return estimates[0]

    # -- streaming ---------------------------------------------------------------------------

    def add(self, reading: Reading, reading_id: int | None = None) -> None:
        """Process one reading; ``reading_id`` defaults to its position in the stream.

        Raises
        ------
        ReadingsError
            For a reading :func:`~sonarcarve.readings.check_reading` refuses (non-finite
            values, range ≤ 0, a sensor that is no index, a beam width outside (0, π), a time
            before the previous reading's); nothing is changed.
        SonarcarveError
            The error that stopped a model for good (:meth:`ArcModel.check_usable`, e.g.
            :class:`~sonarcarve.methods.atm.CrossingStoreError`), raised again: nothing is
            stored. Every map and measure raises it too.
        """
        self._check_open()
        self._check_usable()
        rid = self._readings if reading_id is None else reading_id
        check_reading(reading, rid, self._last_t)
        self._add_checked(reading, rid)

    def add_many(self, batch: ReadingBatch, first_id: int | None = None) -> None:
        """Process a batch in order; ids run on from ``first_id`` (default: the stream count).

        The batch is validated once, vectorised, before any reading is processed (the rules of
        :meth:`add`, and its first time not before the previous reading's): a bad batch raises
        :class:`~sonarcarve.readings.ReadingsError` naming the reading and changes nothing.

        No-echo rows are handled one by one between the blocks of ordinary readings before and
        after them (each still consumes its id), so the result is that of :meth:`add` per row.
        """
        self._check_open()
        self._check_usable()
        if not isinstance(batch, ReadingBatch):
            msg = (f"add_many needs a ReadingBatch, got {type(batch).__name__}: "
                   "ReadingBatch.from_readings(readings) builds one (or call add per Reading)")
            raise ReadingTypeError(msg)
        start = self._readings if first_id is None else first_id
        plain = _plainly_valid(batch, self._last_t)  # then no row is a no-echo reading
        if not plain:
            batch.validate(first_id=start, previous_t=self._last_t)  # the error, or a pass
        n = len(batch)
        if n == 0:
            return
        no_echo = _NO_ROWS if plain else np.flatnonzero(batch.range == math.inf)
        if not no_echo.size:
            self._add_block(batch, start)
            return
        done = 0
        for row in no_echo.tolist():
            if row > done:
                self._add_block(batch[done:row], start + done)
            self._add_no_echo(batch[row])
            done = row + 1
        if done < n:
            self._add_block(batch[done:], start + done)

    def _add_block(self, batch: ReadingBatch, start: int) -> None:
        """Ordinary (echo) readings, validated, through the models' block kernels; ids from
        ``start``."""
        n = len(batch)
        width = batch.beam_widths(self.beam_width)
        h = self.history
        done = 0
        # Blocks of at most the history's room: the arcs that retire between blocks are
        # committed exactly when add() would commit them (SonarHistory.commit_for_room).
        while done < n:
            h.commit_for_room()
            stop = min(n, done + h.room())
            whole = stop - done == n  # the common case: the columns as they are, no slicing
            part, part_width = (batch, width) if whole else (batch[done:stop], width[done:stop])
            first = h.append_many(part.x, part.y, part.range, part.theta, part.t, part.sensor,
                                  part_width, start + done)
            self._feed_block(first, stop - done)
            done = stop
        self._readings += n
        self._last_t = float(batch.t[-1])
        self._local = None

    def _check_open(self) -> None:
        if self._finished:
            msg = "this method has finished its log; make a new one for more readings"
            raise MethodStateError(msg)

    def _check_usable(self) -> None:
        """Raise the error that stopped a model for good (:meth:`ArcModel.check_usable`), if
        one did: asked before a reading is stored and before any map or measure is read, so a
        stopped method neither grows its history nor returns a map built from lost state."""
        for model in self.models:
            model.check_usable()

    def _add_checked(self, reading: Reading, reading_id: int) -> None:
        if reading.range == math.inf:
            self._add_no_echo(reading)
            return
        width = reading.width_or(self.beam_width)
        self.history.append(reading, reading_id, width)
        self._feed_block(self.history.appended - 1, 1)
        self._readings += 1
        self._last_t = reading.t
        self._local = None

    def _feed_block(self, first: int, count: int) -> None:
        """Let the models take in the arcs of sequence numbers ``first .. first + count - 1``,
        just stored (a block of one for :meth:`add`)."""
        for model in self.models:
            model.on_add_many(first, count)

    def _feed_no_echo(self, reading: Reading, beam_width: float) -> None:
        """Let the models take in a no-echo reading of beam width ``beam_width``."""
        for model in self.models:
            model.on_no_echo(reading, beam_width)

    def _add_no_echo(self, reading: Reading) -> None:
        """A validated no-echo reading: free space for the models, no arc (module docstring)."""
        width = reading.width_or(self.beam_width)
        self._feed_no_echo(reading, width)
        self._readings += 1
        self._no_echo += 1
        self._last_t = reading.t
        self._local = None

    # -- maps and measures --------------------------------------------------------------------

    def estimates(self, slots: SlotArray) -> Estimates:
        """The method's combined estimate for history ``slots``.

        Raises the error that stopped a model for good, if one did (:meth:`_check_usable`).
        """
        self._check_usable()
        return self._estimates(slots)

    def _estimates(self, slots: SlotArray) -> Estimates:
        """:meth:`estimates` of a usable method: :meth:`_combine` of the models' estimates.
        Methods whose estimate is not a per-model combination override this."""
        return self._combine(tuple(model.estimates(slots) for model in self.models))

    def local_map(self) -> LocalMap:
        """One point per surviving arc in the history, oldest first (eq. 3.6).

        Asked again with no reading added in between, it returns the same map without
        recomputing or copying anything (its arrays are read-only for that reason).
        """
        self._check_usable()
        if self._local is None:
            local = self._points(self.history.slots(), LocalMap)
            for value in vars(local).values():
                if isinstance(value, np.ndarray):
                    value.flags.writeable = False
            self._local = local
        return self._local

    def set_global_sink(self, sink: GlobalMapSink) -> None:
        """Send the global map to ``sink`` instead of keeping it in memory.

        From then on every final point is passed to ``sink.commit`` once, in reading order, as
        its arc leaves the history (the last ones at :meth:`finish`), and nothing of the global
        map stays in the method: memory no longer grows with the log.

        Raises
        ------
        MethodStateError
            The method has been fed readings already (their points would be split between two
            places).
        """
        if self._readings or self._finished:
            msg = (f"set_global_sink needs a fresh method; this {self.name} method has already "
                   f"been fed {self._readings} readings")
            raise MethodStateError(msg)
        self._global = _GlobalFeed(sink)

    @property
    def committed_points(self) -> int:
        """Points committed to the global map (its sink) so far; after :meth:`finish`, the
        size of the whole global map."""
        return self._global.points

    def global_map(self) -> GlobalMap:
        """Final points of the arcs that have left the history so far, in reading order.

        Raises
        ------
        MethodStateError
            The global map goes to a sink (:meth:`set_global_sink`): the method does not keep
            it; ask the sink.
        """
        self._check_usable()
        memory = self._memory("global_map()")
        self.history.flush_retired()
        return memory.build()

    def finish(self) -> GlobalMap:
        """End of the log: commit the arcs still in the history and return the global map.

        With a sink (:meth:`set_global_sink`) the last points go to the sink and the map
        returned is empty: the sink has the map, :attr:`committed_points` its size.
        """
        self._check_usable()
        self.history.flush()
        self._finished = True
        memory = self._global.memory
        return GlobalMap.empty() if memory is None else memory.build()

    def _memory(self, what: str) -> GlobalMapBuilder:
        memory = self._global.memory
        if memory is None:
            msg = (f"{what}: this {self.name} method sends its global map to a sink and keeps "
                   "none of it in memory")
            raise MethodStateError(msg)
        return memory

    def measures(self) -> Measures:
        """The paper's measures over the current history (Table I, Fig. 11, section 5-C)."""
        self._check_usable()
        slots = self.history.slots()
        est = self.estimates(slots)
        counters: dict[str, int] = {}
        for model in self.models:
            counters.update(model.counters())
        unprocessed = float(np.mean(~est.processed)) if len(slots) else 0.0
        return Measures(
            readings=self._readings,
            in_history=len(slots),
            unprocessed_share=unprocessed,
            widths=est.width[est.alive],
            fully_carved=counters.get("fully_carved", 0),
            split=counters.get("split", 0),
            no_echo=self._no_echo,
        )

    @property
    def readings(self) -> int:
        """Readings added so far."""
        return self._readings

    def add_commit_listener(self, listener: CommitListener) -> None:
        """Call ``listener(history, slots, estimates)`` for every block of arcs leaving the
        history (their final state), e.g. to attribute removed arcs to ground truth."""
        self._listeners.append(listener)

    def _commit(self, slots: SlotArray) -> None:
        est = self.estimates(slots)
        for listener in self._listeners:
            listener(self.history, slots, est)
        counter = self._global.counter
        if counter is not None:  # a sink that only counts needs no points made
            self._global.count(counter, est.source[est.alive])
        else:
            self._global.commit(self._points(slots, GlobalMap, est))

    def _points(self, slots: SlotArray, kind: type[_M], est: Estimates | None = None) -> _M:
        est = self.estimates(slots) if est is None else est
        keep = slots[est.alive]
        h = self.history
        return kind(  # indexing by an array copies: the history's rows are not shared
            reading_id=h.reading_id[keep],
            t=h.t[keep],
            sensor=h.sensor[keep],
            xy=est.xy[est.alive],
            source=est.source[est.alive].astype(np.int8),
            width=est.width[est.alive],
            max_error=est.max_error[est.alive],
            range=h.r[keep],
            confidence=(np.full(len(keep), np.nan) if est.confidence is None
                        else est.confidence[est.alive]),
        )


class _GlobalFeed:
    """Where a method's committed points go: ``sink`` (the in-memory builder by default),
    counted on the way."""

    def __init__(self, sink: GlobalMapSink | None = None) -> None:
        self.memory: GlobalMapBuilder | None = None
        if sink is None:
            sink = self.memory = GlobalMapBuilder()
        self.sink = sink
        self.points = 0
        #: The sink when it is exactly a :class:`~sonarcarve.maps.CountingSink` (not a
        #: subclass, which may look at the points): it gets their sources only (:meth:`count`).
        self.counter = sink if type(sink) is CountingSink else None

    def commit(self, points: GlobalMap) -> None:
        if len(points):
            self.points += len(points)
            self.sink.commit(points)

    def count(self, counter: CountingSink, source: Int8Array) -> None:
        """What :meth:`commit` does with the counting sink, from the points' sources alone."""
        if len(source):
            self.points += len(source)
            counter.count(source)


def slot_indices(slots: SlotArray) -> SlotArray:
    """``slots`` as the contiguous int64 array compiled estimates take; a float slot is an
    ``IndexError``, as numpy's indexing makes it, not truncated to the slot below (review
    rev16). Bounds are the kernels' to test: a numpy min and max here would cost 2.4 µs a
    call, once a reading when readings come one at a time."""
    slots = np.asarray(slots)
    if slots.size and slots.dtype.kind not in "iu":
        msg = f"slots must be integers, not {slots.dtype}"
        raise IndexError(msg)
    return np.ascontiguousarray(slots, dtype=np.int64)


def arc_point(history: SonarHistory, slots: SlotArray, bearing: FloatArray) -> FloatArray:
    """Points at ``bearing`` on the circles of ``slots``, shape (n, 2) (eq. 3.3 and 3.6)."""
    r = history.r[slots]
    xy = np.empty((len(r), 2))
    xy[:, 0] = history.x[slots] + r * np.cos(bearing)
    xy[:, 1] = history.y[slots] + r * np.sin(bearing)
    return xy


#: The no-echo rows of a batch :func:`_plainly_valid` passed: none.
_NO_ROWS = np.zeros(0, dtype=np.int64)

#: The array types :func:`_plainly_valid` hands to its kernel (others: the full check).
_FLOAT64 = np.dtype(np.float64)
_INT64 = np.dtype(np.int64)


def _plainly_valid(batch: ReadingBatch, previous_t: float) -> bool:
    """True if every row of ``batch`` passes :meth:`ReadingBatch.validate` with ``previous_t``,
    decided cheaply; False when that is not certain (then ``validate`` decides, and words the
    error): a row breaking a rule, a no-echo row, arrays of another type or layout.

    Why: ``validate`` costs some 25 numpy calls whatever the batch's size, about 30 µs for the
    five readings a robot adds between two reads of its costmap; this is one compiled pass.
    No batch is trusted for being a :class:`ReadingBatch`: its arrays can be changed after it
    was checked, and the rule across batches (time never goes backwards) needs the method's
    last time anyway.
    """
    columns = (batch.t, batch.x, batch.y, batch.theta, batch.range, batch.beam_width,
               batch.max_range)
    n = len(batch.t)
    for column in columns:
        if (column.dtype != _FLOAT64 or column.shape != (n,)
                or not column.flags.c_contiguous):
            return False
    sensor = batch.sensor
    if sensor.dtype != _INT64 or sensor.shape != (n,) or not sensor.flags.c_contiguous:
        return False
    return bool(_rows_plainly_valid(batch.t, sensor, batch.x, batch.y, batch.theta,
                                    batch.range, batch.beam_width, batch.max_range,
                                    float(previous_t), _ROW_BOUNDS))


#: The bounds :func:`_rows_plainly_valid` checks, passed as an argument: numba freezes a
#: global into the compiled code, and its disk cache is keyed on the kernel folders' sources only
#: (:mod:`~sonarcarve.geometry._compiled`), so a bound changed in ``readings.py`` would not reach
#: a cached kernel (review finding).
_ROW_BOUNDS = (float(MAX_TIME), float(MAX_READING_RANGE), float(MAX_POSITION), float(MAX_ANGLE),
               float(MAX_SENSOR), float(MIN_BEAM_WIDTH))


@compiled
def _rows_plainly_valid(t: FloatArray, sensor: np.ndarray, x: FloatArray, y: FloatArray,
                        theta: FloatArray, r: FloatArray, width: FloatArray, limit: FloatArray,
                        previous_t: float, bounds: tuple[float, ...]) -> bool:
    """The rules of :meth:`ReadingBatch.validate` row by row, stricter where that is simpler:
    a no-echo row (``range`` = inf, allowed when ``max_range`` is known) fails here. Every
    comparison is false for NaN, so a NaN fails wherever ``validate`` refuses it."""
    max_time, max_range, max_position, max_angle, max_sensor, min_width = bounds
    last = previous_t
    for k in range(t.shape[0]):
        tk = t[k]
        if not (last <= tk and -max_time <= tk <= max_time):
            return False
        last = tk
        rk = r[k]
        if not (0.0 < rk <= max_range):
            return False
        if not (-max_position <= x[k] <= max_position and -max_position <= y[k] <= max_position
                and -max_angle <= theta[k] <= max_angle and 0 <= sensor[k] <= max_sensor):
            return False
        w = width[k]
        if not (w != w or min_width <= w < math.pi):
            return False
        m = limit[k]
        if not (m != m or rk <= m <= max_range):
            return False
    return True


def source_codes(n: int, source: PointSource) -> Int8Array:
    """``n`` copies of one source code."""
    return np.full(n, int(source), dtype=np.int8)
