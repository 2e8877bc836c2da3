"""The sonar history: a fixed-capacity ring buffer of arcs (paper, sections 5-A and 5-B).

Each row is the paper's 6-tuple ``(x, y, r, θ, θ1, θ2)`` plus the reading's time, sensor, beam
width and id (its 0-based position in the input stream). ``θ1, θ2`` here are the arc's *full
beam* ``θ ∓ φ/2``; each method keeps its own per-row state (a carved interval, ATM
intersections) in arrays of the same capacity, indexed by the same slot, so that several methods
can share one history without interfering (section 5-A).

Memory is fixed by the capacity and never grows with the length of the log.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt
from numba import njit

from sonarcarve.errors import ConfigError
from sonarcarve.readings import Reading

__all__ = ["DEFAULT_HISTORY_SIZE", "MAX_HISTORY_SIZE", "SonarHistory", "check_history_size"]

#: The paper's history length (section 5-C: "a history of 250 arcs").
DEFAULT_HISTORY_SIZE = 250

#: Largest history accepted, arcs: 400 times the paper's. The history itself costs about 100
#: bytes an arc (10 MB here), so the bound only stops a mistyped size from exhausting memory;
#: methods whose state grows faster bound it themselves (ATM's crossing store grows on demand
#: and stops at :data:`~sonarcarve.methods.atm.MAX_ATM_STATE_BYTES`).
MAX_HISTORY_SIZE = 100_000


def check_history_size(value: object) -> int:
    """``value`` if it is a valid history size (a whole number, not a bool, in
    [1, :data:`MAX_HISTORY_SIZE`]), else :class:`~sonarcarve.errors.ConfigError`.

    The one rule for :class:`SonarHistory` and
    :class:`~sonarcarve.methods.config.MethodConfig`.
    """
    if (not isinstance(value, int | np.integer) or isinstance(value, bool)
            or not 1 <= value <= MAX_HISTORY_SIZE):
        msg = (f"history_size must be a whole number of arcs in [1, {MAX_HISTORY_SIZE:,}], "
               f"got {value!r}")
        raise ConfigError(msg)
    return int(value)


class SonarHistory:
    """Ring buffer of the newest ``capacity`` arcs, stored as one numpy array per field.

    Arcs leave the history in arrival order. An arc that leaves is *retired*: its row (and every
    method's per-row state beside it) stays frozen in storage until ``on_evict`` has been called
    with it. Rows are handed to ``on_evict`` in blocks, oldest first, so that committing final
    points to a global map is one vectorised call per block rather than one per reading. To make
    that possible the storage holds ``2 * capacity`` rows; memory is still fixed by the capacity
    and never grows with the length of the log.

    Parameters
    ----------
    capacity : int
        Number of arcs kept live (the paper's history length, 250 by default), in
        [1, :data:`MAX_HISTORY_SIZE`] (:func:`check_history_size`).
    on_evict : callable, optional
        Called with an int64 array of retired slots, oldest first, before those rows are reused
        and from :meth:`flush`.

    Attributes
    ----------
    x, y, r, theta, theta1, theta2, t, beam_width : ndarray of float64, shape (2 * capacity,)
        The arcs, by slot. ``theta1 = theta - beam_width/2`` and ``theta2 = theta + beam_width/2``:
        the full beam; methods keep carved intervals in their own state.
    sensor, reading_id : ndarray of int64, shape (2 * capacity,)
        Sensor index and input position of each arc; ``reading_id`` is -1 in unused slots.
    """

    def __init__(
        self,
        capacity: int = DEFAULT_HISTORY_SIZE,
        on_evict: Callable[[npt.NDArray[np.int64]], None] | None = None,
    ) -> None:
        self.capacity = check_history_size(capacity)
        self.storage_size = 2 * capacity
        self._on_evict = on_evict
        self.x = np.zeros(self.storage_size)
        self.y = np.zeros(self.storage_size)
        self.r = np.zeros(self.storage_size)
        self.theta = np.zeros(self.storage_size)
        self.theta1 = np.zeros(self.storage_size)
        self.theta2 = np.zeros(self.storage_size)
        self.t = np.zeros(self.storage_size)
        self.beam_width = np.zeros(self.storage_size)
        self.sensor = np.zeros(self.storage_size, dtype=np.int64)
        self.reading_id = np.full(self.storage_size, -1, dtype=np.int64)
        # Slot numbers laid out twice, so that any window of live slots is one contiguous slice.
        self._wrapped = np.arange(2 * self.storage_size, dtype=np.int64) % self.storage_size
        self._wrapped.flags.writeable = False
        self._appended = 0  # arcs appended so far; arc k lives in slot k % storage_size
        self._committed = 0  # arcs handed to on_evict so far

    def __len__(self) -> int:
        """Number of live arcs (at most ``capacity``)."""
        return min(self._appended, self.capacity)

    @property
    def appended(self) -> int:
        """Number of arcs appended since the history was made."""
        return self._appended

    def append(self, reading: Reading, reading_id: int, beam_width: float) -> int:
        """Store ``reading`` as the newest arc and return its slot (amortised O(1)).

        The oldest live arc retires when the history is full.
        """
        sequence = self._appended
        if sequence - self._committed >= self.storage_size:
            # The row about to be reused holds a retired arc nobody has committed yet.
            self._evict_upto(sequence - self.capacity)
        slot = sequence % self.storage_size
        half = 0.5 * beam_width
        self.x[slot] = reading.x
        self.y[slot] = reading.y
        self.r[slot] = reading.range
        self.theta[slot] = reading.theta
        self.theta1[slot] = reading.theta - half
        self.theta2[slot] = reading.theta + half
        self.t[slot] = reading.t
        self.beam_width[slot] = beam_width
        self.sensor[slot] = reading.sensor
        self.reading_id[slot] = reading_id
        self._appended = sequence + 1
        return slot

    def room(self) -> int:
        """Arcs :meth:`append_many` can store before a retired row must be committed (≥ 0)."""
        return self._committed + self.storage_size - self._appended

    def commit_for_room(self) -> None:
        """Hand the retired arcs to ``on_evict`` when :meth:`room` is 0, as :meth:`append`
        would before reusing their rows (same blocks, same moments)."""
        if self.room() <= 0:
            self._evict_upto(self._appended - self.capacity)

    def append_many(self, x: npt.NDArray[np.float64], y: npt.NDArray[np.float64],
                    r: npt.NDArray[np.float64], theta: npt.NDArray[np.float64],
                    t: npt.NDArray[np.float64], sensor: npt.NDArray[np.int64],
                    beam_width: npt.NDArray[np.float64], first_id: int) -> int:
        """Store ``len(x)`` arcs at once (at most :meth:`room`), ids from ``first_id``; return
        the sequence number of the first (its slot is that modulo ``storage_size``).

        The vectorised twin of :meth:`append` for a batch of validated readings: the rows are
        written exactly as :meth:`append` writes them, but no arc retires through ``on_evict``
        here (the caller calls :meth:`commit_for_room` between batches), so the models must
        then process the arcs in order, as if they had been appended one by one. The rows are
        written in one compiled pass (:func:`_store_block`).
        """
        n = len(x)
        if n > self.room():
            msg = f"append_many of {n} arcs with room for {self.room()}"
            raise ValueError(msg)
        first = self._appended
        _store_block(x, y, r, theta, t, sensor, beam_width, first_id,
                     first % self.storage_size, self.x, self.y, self.r, self.theta,
                     self.theta1, self.theta2, self.t, self.beam_width, self.sensor,
                     self.reading_id)
        self._appended = first + n
        return first

    def slots(self) -> npt.NDArray[np.int64]:
        """Live slots from oldest to newest, shape (len(self),) (a read-only view)."""
        first = (self._appended - len(self)) % self.storage_size
        return self._wrapped[first : first + len(self)]

    def window(self, sequence: int) -> npt.NDArray[np.int64]:
        """Slots of the arcs that were live right after arc ``sequence`` was appended, oldest
        first, ending with that arc's own slot (a read-only view)."""
        count = min(sequence + 1, self.capacity)
        first = (sequence + 1 - count) % self.storage_size
        return self._wrapped[first : first + count]

    def flush_retired(self) -> None:
        """Hand every retired, uncommitted arc to ``on_evict``."""
        self._evict_upto(self._appended - len(self))

    def flush(self) -> None:
        """Hand every uncommitted arc, live ones included, to ``on_evict`` (end of a log)."""
        self._evict_upto(self._appended)

    def _evict_upto(self, end: int) -> None:
        if end <= self._committed:
            return
        slots = np.arange(self._committed, end, dtype=np.int64) % self.storage_size
        self._committed = end
        if self._on_evict is not None:
            self._on_evict(slots)


# numba's own per-file cache, not sonarcarve.geometry._compiled's (the history and the geometry
# are independent layers of the package, pyproject.toml's import contract): the kernel calls no
# other kernel and none calls it, so its own file keys its cache soundly (one of the exceptions
# _compiled's docstring names).
@njit(cache=True)
def _store_block(x: npt.NDArray[np.float64], y: npt.NDArray[np.float64],
                 r: npt.NDArray[np.float64], theta: npt.NDArray[np.float64],
                 t: npt.NDArray[np.float64], sensor: npt.NDArray[np.int64],
                 beam_width: npt.NDArray[np.float64], first_id: int, start: int,
                 to_x: npt.NDArray[np.float64], to_y: npt.NDArray[np.float64],
                 to_r: npt.NDArray[np.float64], to_theta: npt.NDArray[np.float64],
                 to_theta1: npt.NDArray[np.float64], to_theta2: npt.NDArray[np.float64],
                 to_t: npt.NDArray[np.float64], to_beam_width: npt.NDArray[np.float64],
                 to_sensor: npt.NDArray[np.int64],
                 to_reading_id: npt.NDArray[np.int64]) -> None:
    """Arcs ``k = 0, 1, ...`` of a block into the rows ``(start + k) mod storage`` of the
    history's columns ``to_x .. to_reading_id``, as :meth:`SonarHistory.append` writes one
    (``theta1, theta2 = theta -/+ beam_width / 2``, id ``first_id + k``), wrapping past the
    end of the storage. One pass: the numpy version (a slice assignment per column, two for
    a block that wraps) took 6.8 µs for a 5-arc block, most of it per-call overhead.
    """
    storage = to_x.shape[0]
    row = start
    for k in range(x.shape[0]):
        if row == storage:
            row = 0
        half = 0.5 * beam_width[k]
        to_x[row] = x[k]
        to_y[row] = y[k]
        to_r[row] = r[k]
        to_theta[row] = theta[k]
        to_theta1[row] = theta[k] - half
        to_theta2[row] = theta[k] + half
        to_t[row] = t[k]
        to_beam_width[row] = beam_width[k]
        to_sensor[row] = sensor[k]
        to_reading_id[row] = first_id + k
        row += 1
