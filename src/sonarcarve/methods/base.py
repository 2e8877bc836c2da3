"""What every sonar method shares: a history, per-arc models, a local and a global map.

A *model* (centerline, carving, ATM) keeps its own per-row state beside a shared
:class:`~sonarcarve.history.SonarHistory` and turns any set of rows into :class:`Estimates`. A
*method* owns one history, feeds each new reading to its models, and combines their estimates
into one point per surviving arc. Running carving and ATM on one history is then just a method
with two models (paper, section 5-A: "arc carving and ATM can be run in parallel using the same
data, without interfering with each other").
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import IntEnum
from typing import ClassVar, TypeVar

import numpy as np
import numpy.typing as npt

from sonarcarve.history import DEFAULT_HISTORY_SIZE, SonarHistory
from sonarcarve.maps import GlobalMap, GlobalMapBuilder, LocalMap, PointSource
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch
from sonarcarve.typing import BoolArray, FloatArray, SlotArray

__all__ = ["ArcModel", "CommitListener", "Estimates", "Measures", "Removal", "SonarMethod"]

M = TypeVar("M", LocalMap, GlobalMap)



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
    """

    alive: BoolArray
    processed: BoolArray
    xy: FloatArray
    width: FloatArray
    max_error: FloatArray
    source: npt.NDArray[np.int8]
    removal: npt.NDArray[np.int8] | None = None
    """Why a dead arc died (:class:`Removal` codes), where the model knows; None otherwise."""


class Removal(IntEnum):
    """Why an arc no longer yields a point."""

    NONE = 0  #: still alive
    FULLY_CARVED = 1  #: every point of the arc lies in newer freespace (section 3)
    SPLIT = 2  #: carving would have split the arc in two (section 3: the arc is ignored)


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
    """

    readings: int
    in_history: int
    unprocessed_share: float
    widths: FloatArray = field(repr=False)
    fully_carved: int = 0
    split: int = 0


class ArcModel(ABC):
    """Per-row state of one sonar model over a shared history.

    Subclasses keep arrays of length ``history.storage_size`` indexed by slot. They must touch
    only live slots (``history.slots()``) when a reading arrives: retired rows are frozen until
    they are committed to the global map.
    """

    def __init__(self, history: SonarHistory) -> None:
        self.history = history

    @abstractmethod
    def on_add(self, slot: int, older: SlotArray) -> None:
        """Initialise the state of the new arc in ``slot`` and let it act on the ``older`` live
        arcs (oldest first)."""

    @abstractmethod
    def estimates(self, slots: SlotArray) -> Estimates:
        """This model's estimates for ``slots``, vectorised."""

    def counters(self) -> dict[str, int]:
        """Event counts since the start (for example fully carved and split arcs)."""
        return {}


class SonarMethod(ABC):
    """A streaming sonar processing method.

    Feed it readings with :meth:`add` or :meth:`add_many`; ask for :meth:`local_map` at any time;
    call :meth:`finish` at the end of a log to get the :class:`~sonarcarve.maps.GlobalMap`.

    Parameters
    ----------
    history_size : int
        Arcs kept in the history (paper: 250).
    beam_width : float
        Beam width φ in radians, used for readings whose own ``beam_width`` is NaN.
    """

    #: Name used by the CLI (``--method``).
    name: ClassVar[str]

    def __init__(
        self, history_size: int = DEFAULT_HISTORY_SIZE, beam_width: float = DEFAULT_BEAM_WIDTH
    ) -> None:
        if not 0.0 < beam_width < math.pi:
            msg = f"beam width must lie in (0, pi) radians, got {beam_width}"
            raise ValueError(msg)
        self.history = SonarHistory(history_size, on_evict=self._commit)
        self.beam_width = beam_width
        self._global = GlobalMapBuilder()
        self._readings = 0
        self._finished = False
        self._listeners: list[CommitListener] = []
        self.models: tuple[ArcModel, ...] = self._make_models()

    @abstractmethod
    def _make_models(self) -> tuple[ArcModel, ...]:
        """The models this method runs on its history."""

    @abstractmethod
    def _combine(self, estimates: tuple[Estimates, ...]) -> Estimates:
        """One estimate per row from the models' estimates (same order as ``models``)."""

    # -- streaming ---------------------------------------------------------------------------

    def add(self, reading: Reading, reading_id: int | None = None) -> None:
        """Process one reading; ``reading_id`` defaults to its position in the stream."""
        if self._finished:
            msg = "this method has finished its log; make a new one for more readings"
            raise RuntimeError(msg)
        width = self.beam_width if math.isnan(reading.beam_width) else reading.beam_width
        rid = self._readings if reading_id is None else reading_id
        slot = self.history.append(reading, rid, width)
        older = self.history.slots()[:-1]
        for model in self.models:
            model.on_add(slot, older)
        self._readings += 1

    def add_many(self, batch: ReadingBatch, first_id: int | None = None) -> None:
        """Process a batch in order; ids run on from ``first_id`` (default: the stream count)."""
        start = self._readings if first_id is None else first_id
        for offset, reading in enumerate(batch):
            self.add(reading, start + offset)

    # -- maps and measures --------------------------------------------------------------------

    def estimates(self, slots: SlotArray) -> Estimates:
        """The method's combined estimate for history ``slots``."""
        return self._combine(tuple(model.estimates(slots) for model in self.models))

    def local_map(self) -> LocalMap:
        """One point per surviving arc in the history, oldest first (eq. 3.6)."""
        return self._points(self.history.slots(), LocalMap)

    def global_map(self) -> GlobalMap:
        """Final points of the arcs that have left the history so far, in reading order."""
        self.history.flush_retired()
        return self._global.build()

    def finish(self) -> GlobalMap:
        """End of the log: commit the arcs still in the history and return the global map."""
        self.history.flush()
        self._finished = True
        return self._global.build()

    def measures(self) -> Measures:
        """The paper's measures over the current history (Table I, Fig. 11, section 5-C)."""
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
        self._global.commit(self._points(slots, GlobalMap, est))

    def _points(self, slots: SlotArray, kind: type[M], est: Estimates | None = None) -> M:
        est = self.estimates(slots) if est is None else est
        keep = slots[est.alive]
        h = self.history
        return kind(
            reading_id=h.reading_id[keep].copy(),
            t=h.t[keep].copy(),
            sensor=h.sensor[keep].copy(),
            xy=est.xy[est.alive],
            source=est.source[est.alive].astype(np.int8),
            width=est.width[est.alive],
            max_error=est.max_error[est.alive],
            range=h.r[keep].copy(),
        )


def arc_point(history: SonarHistory, slots: SlotArray, bearing: FloatArray) -> FloatArray:
    """Points at ``bearing`` on the circles of ``slots``, shape (n, 2) (eq. 3.3 and 3.6)."""
    r = history.r[slots]
    return np.column_stack(
        (history.x[slots] + r * np.cos(bearing), history.y[slots] + r * np.sin(bearing))
    )


def source_codes(n: int, source: PointSource) -> npt.NDArray[np.int8]:
    """``n`` copies of one source code."""
    return np.full(n, int(source), dtype=np.int8)
