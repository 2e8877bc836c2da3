"""Watch a method while it runs: snapshots of its history and every arc's final state.

:func:`record_run` feeds a :class:`~sonarcarve.readings.ReadingBatch` to a
:class:`~sonarcarve.methods.base.SonarMethod` and keeps two tables (struct of arrays):

* ``samples``: every arc in the history (alive or not) at chosen moments: what the robot's
  local map held and which arcs were still unprocessed (paper, section 5-B, Table I, Fig. 10;
  see :func:`unprocessed_percent` for how arcs carving removed count).
* ``final``: every arc's estimate as it left the history, through the method's commit listener
  (its final width and error bound, Fig. 11 and 12; and why it died, for the fully carved share).

Everything the experiments measure is computed from these tables afterwards, so a run is made
once and measured in many ways.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Self

import numpy as np
import numpy.typing as npt

from sonarcarve.history import SonarHistory
from sonarcarve.lab import metrics
from sonarcarve.maps import GlobalMap
from sonarcarve.methods.base import ArcFate, Estimates, SonarMethod
from sonarcarve.readings import ReadingBatch
from sonarcarve.typing import FloatArray, IntArray

__all__ = [
    "ArcTable",
    "RunRecord",
    "full_history_samples",
    "record_run",
    "sample_points",
    "unprocessed_percent",
]


#: ``removal`` code for a dead arc whose model did not say why it died.
REMOVAL_UNKNOWN = -1


@dataclass(frozen=True, eq=False)
class ArcTable:
    """Estimates of arcs as rows, arrays of shape (n,) (``xy``: (n, 2)).

    Attributes
    ----------
    sample : int64
        Snapshot index of the row (see :attr:`RunRecord.sample_readings`); -1 in ``final``.
    reading_id : int64
        The arc's reading (0-based position in the input).
    range : float64
        The arc's radius r, metres.
    alive, processed : bool
        As in :class:`~sonarcarve.methods.base.Estimates`. An arc carving removed (fully carved
        or split) is not alive but *is* processed (it was carved): the paper's history drops
        such arcs, this table keeps them (see :func:`unprocessed_percent`).
    xy : float64, shape (n, 2)
        The arc's map point (meaningless where not ``alive``).
    width, max_error : float64
        Angular width θ_d (rad, eq. 5.1) and error bound (m, eq. 5.3 or 5.4).
    source : int8
        :class:`~sonarcarve.maps.PointSource` code.
    removal : int8
        :class:`~sonarcarve.methods.base.ArcFate` code; ``REMOVAL_UNKNOWN`` (-1) for a dead arc
        whose model gives no reason.
    """

    sample: IntArray
    reading_id: IntArray
    range: FloatArray
    alive: npt.NDArray[np.bool_]
    processed: npt.NDArray[np.bool_]
    xy: FloatArray
    width: FloatArray
    max_error: FloatArray
    source: npt.NDArray[np.int8]
    removal: npt.NDArray[np.int8]

    def __len__(self) -> int:
        return int(self.reading_id.shape[0])

    @classmethod
    def from_estimates(
        cls, history: SonarHistory, slots: IntArray, est: Estimates, sample: int
    ) -> Self:
        """Rows for ``slots`` of ``history`` with their estimates ``est``."""
        n = len(slots)
        if est.fate is not None:
            removal = np.asarray(est.fate, dtype=np.int8)
        else:
            removal = np.where(est.alive, np.int8(ArcFate.ALIVE), np.int8(REMOVAL_UNKNOWN))
        return cls(
            sample=np.full(n, sample, dtype=np.int64),
            reading_id=history.reading_id[slots].copy(),
            range=history.r[slots].copy(),
            alive=np.asarray(est.alive, dtype=bool).copy(),
            processed=np.asarray(est.processed, dtype=bool).copy(),
            xy=np.asarray(est.xy, dtype=np.float64).reshape(n, 2).copy(),
            width=np.asarray(est.width, dtype=np.float64).copy(),
            max_error=np.asarray(est.max_error, dtype=np.float64).copy(),
            source=np.asarray(est.source, dtype=np.int8).copy(),
            removal=removal.astype(np.int8),
        )

    @classmethod
    def concatenate(cls, tables: list[ArcTable]) -> Self:
        """The rows of ``tables`` one after the other."""
        if not tables:
            return cls(
                sample=np.zeros(0, np.int64), reading_id=np.zeros(0, np.int64),
                range=np.zeros(0), alive=np.zeros(0, bool), processed=np.zeros(0, bool),
                xy=np.zeros((0, 2)), width=np.zeros(0), max_error=np.zeros(0),
                source=np.zeros(0, np.int8), removal=np.zeros(0, np.int8),
            )
        return cls(**{f.name: np.concatenate([getattr(t, f.name) for t in tables])
                      for f in fields(cls)})

    def select(self, mask: npt.NDArray[np.bool_] | IntArray) -> Self:
        """The rows picked by a boolean mask or index array."""
        return type(self)(**{f.name: getattr(self, f.name)[mask] for f in fields(self)})


@dataclass(frozen=True, eq=False)
class RunRecord:
    """What :func:`record_run` saw.

    Attributes
    ----------
    method : str
        The method's name.
    samples : ArcTable
        Every history arc at every snapshot (``sample`` column = snapshot index).
    sample_readings : ndarray of int64, shape (k,)
        Readings added before snapshot ``k`` (snapshot ``k`` shows the history after reading
        ``sample_readings[k] - 1``).
    final : ArcTable
        Every arc's final estimate, one row per reading, sorted by ``reading_id``.
    global_map : GlobalMap
        The method's global map.
    counters : dict
        The models' event counters at the end (for example ``fully_carved``, ``split``).
    seconds : float
        Wall time spent inside the method (snapshots excluded).
    """

    method: str
    samples: ArcTable
    sample_readings: IntArray
    final: ArcTable
    global_map: GlobalMap
    counters: dict[str, int]
    seconds: float

    def sample_times(self, batch: ReadingBatch) -> FloatArray:
        """Time of each snapshot: the time of the last reading before it, seconds."""
        return np.asarray(batch.t[self.sample_readings - 1], dtype=np.float64)

    def snapshot(self, k: int) -> ArcTable:
        """The rows of snapshot ``k``."""
        return self.samples.select(self.samples.sample == k)

    def local_map(self, k: int) -> ArcTable:
        """The local map at snapshot ``k``: its ``alive`` rows (one point per surviving arc)."""
        return self.samples.select((self.samples.sample == k) & self.samples.alive)


def record_run(
    batch: ReadingBatch,
    method: SonarMethod,
    sample_after: npt.ArrayLike | None = None,
    *,
    on_progress: Callable[[int], None] | None = None,
) -> RunRecord:
    """Run ``method`` over ``batch``, snapshotting its history after chosen readings.

    Parameters
    ----------
    batch : ReadingBatch
        The readings, in time order; reading ids are row positions.
    method : SonarMethod
        A fresh method (its commit listener list gains one entry).
    sample_after : array-like of int, optional
        Snapshot the history once ``n`` readings have been added, for each ``n`` (1-based
        counts in ``[1, len(batch)]``, any order, duplicates ignored). Default: no snapshots.
    on_progress : callable, optional
        Called with the number of readings done, now and then.

    Returns
    -------
    RunRecord
    """
    n = len(batch)
    stops = _snapshot_stops(sample_after, n)
    finals: list[ArcTable] = []

    def listener(history: SonarHistory, slots: IntArray, est: Estimates) -> None:
        finals.append(ArcTable.from_estimates(history, slots, est, -1))

    method.add_commit_listener(listener)
    snaps: list[ArcTable] = []
    seconds = 0.0
    stop_set = set(stops.tolist())
    done = 0
    for cut in _stream_cuts(stops, n):
        tic = time.perf_counter()
        method.add_many(batch[done:int(cut)], first_id=done)
        seconds += time.perf_counter() - tic
        done = int(cut)
        if done in stop_set:
            snaps.append(_snapshot(method, len(snaps)))
        if on_progress is not None:
            on_progress(done)
    # Counters are taken before finish(), which flushes the history, so they cover the stream.
    counters = _model_counters(method)
    tic = time.perf_counter()
    global_map = method.finish()
    seconds += time.perf_counter() - tic
    return RunRecord(
        method=method.name,
        samples=ArcTable.concatenate(snaps),
        sample_readings=stops,
        final=_by_reading_id(ArcTable.concatenate(finals)),
        global_map=global_map,
        counters=counters,
        seconds=seconds,
    )


#: Longest stretch of readings fed to the method between two progress calls.
_PROGRESS_EVERY = 2000


def _snapshot_stops(sample_after: npt.ArrayLike | None, n: int) -> IntArray:
    """Snapshot points of :func:`record_run`: sorted distinct counts in ``[1, n]``.

    Parameters
    ----------
    sample_after : array-like of int, optional
        Requested reading counts (1-based, any order, duplicates allowed); None for none.
    n : int
        Number of readings in the batch.

    Returns
    -------
    ndarray of int64, shape (k,)
        The requested counts inside ``[1, n]``, increasing, without duplicates.
    """
    stops = np.unique(np.asarray([] if sample_after is None else sample_after, dtype=np.int64))
    return stops[(stops >= 1) & (stops <= n)]


def _stream_cuts(stops: IntArray, n: int) -> IntArray:
    """Where :func:`record_run` cuts the stream of ``n`` readings, as reading counts.

    Parameters
    ----------
    stops : ndarray of int64, shape (k,)
        Snapshot points (from :func:`_snapshot_stops`).
    n : int
        Number of readings in the batch.

    Returns
    -------
    ndarray, shape (c,)
        Increasing distinct counts ending with ``n``: every snapshot point and every multiple
        of ``_PROGRESS_EVERY`` below ``n``, so progress is reported at least that often.
    """
    return np.unique(np.concatenate((stops, np.arange(0, n, _PROGRESS_EVERY)[1:], [n])))


def _snapshot(method: SonarMethod, k: int) -> ArcTable:
    """Every arc now in ``method``'s history with its current estimate, as snapshot ``k``."""
    slots = method.history.slots()
    return ArcTable.from_estimates(method.history, slots, method.estimates(slots), k)


def _model_counters(method: SonarMethod) -> dict[str, int]:
    """The event counters of all of ``method``'s models in one dict (later models win)."""
    counters: dict[str, int] = {}
    for model in method.models:
        counters.update(model.counters())
    return counters


def _by_reading_id(table: ArcTable) -> ArcTable:
    """``table``'s rows sorted by ``reading_id``; rows with equal ids keep their order."""
    return table.select(np.argsort(table.reading_id, kind="stable"))


def sample_points(record: RunRecord) -> ArcTable:
    """The local-map points of every snapshot: the ``alive`` rows of ``record.samples``."""
    return record.samples.select(record.samples.alive)


def full_history_samples(record: RunRecord, capacity: int, *,
                         every: int | None = None) -> ArcTable:
    """The snapshot rows Table I's unprocessed share is taken over (paper, section 5-B).

    The rows of the snapshots taken once ``capacity`` readings had been added (a full history
    of ``capacity`` arcs), or of every snapshot when the run never filled it. With ``every``,
    only snapshots taken after a multiple of ``every`` readings count (regular sampling, leaving
    out snapshots taken at chosen moments).
    """
    samples = record.samples
    if every is not None:
        samples = samples.select(record.sample_readings[samples.sample] % every == 0)
    full = samples.select(record.sample_readings[samples.sample] >= capacity)
    return full if len(full) else samples


def unprocessed_percent(rows: ArcTable, *, live_only: bool = False) -> float:
    """Share of ``rows`` not yet processed, percent (Table I's measure; NaN for no rows).

    Every row counts by default, so an arc carving removed (fully carved or split) counts as
    processed: it was carved. This is the library's measure
    (:attr:`~sonarcarve.methods.base.Measures.unprocessed_share`). The paper's history drops
    removed arcs, so with ``live_only`` only ``alive`` rows count, as the paper's would.
    """
    kept = rows.select(rows.alive) if live_only else rows
    return metrics.percent(~kept.processed)
