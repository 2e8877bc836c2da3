"""The carved grid, :class:`CarvedGrid`: its state (``base``, ``live``, the marks, the heard
bearings, a record per history slot), folding readings in, and reading the map
``l = clamp(base + live)``. ``docs/carved-grid.md``, "Following carving over time", "Memory" and
"Reading the map".
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.grids.carved.heard import HEARD_DTYPE
from sonarcarve.grids.carved.intervals import (
    carving_intervals,
    intervals,
    known_models,
    store_intervals,
)
from sonarcarve.grids.carved.kernels import (
    Finals,
    batch_columns,
    fold_kernel,
    fresh_kernel,
    keep_chain,
    note_newest,
    refresh_kernel,
    retire_kernel,
    stale_slots,
    trinary_kernel,
)
from sonarcarve.grids.carved.model import model_array, model_of
from sonarcarve.grids.carved.params import (
    DEFAULT_MAX_INCIDENCE,
    DEFAULT_METHOD,
    POSE_MARGIN_SIGMAS,
    CarvedGridParams,
)
from sonarcarve.grids.carved.periods import FiringPeriods
from sonarcarve.grids.carved.repeats import repeat_kernel
from sonarcarve.grids.cells import CellGrid, GridError, bounds_around, check_probability, logit
from sonarcarve.grids.elfes import MAX_CELLS
from sonarcarve.grids.occupancy import Int8Grid
from sonarcarve.history import SonarHistory
from sonarcarve.maps import CountingSink
from sonarcarve.methods import MethodConfig, SonarMethod, make_method
from sonarcarve.methods.base import Estimates
from sonarcarve.methods.combined import CombinedMethod
from sonarcarve.readings import Reading, ReadingBatch
from sonarcarve.typing import BoolArray, FloatArray, SlotArray

__all__ = ["CarvedGrid"]

class CarvedGrid(CellGrid):
    """Log-odds occupancy grid whose occupied bands are the carved arcs (``docs/carved-grid.md``).

    Parameters
    ----------
    resolution : float
        Cell side h, metres (> 0).
    bounds : tuple of 4 floats
        ``(xmin, ymin, xmax, ymax)`` of the mapped rectangle, metres; the grid has
        ``ceil((xmax - xmin) / h)`` columns and ``ceil((ymax - ymin) / h)`` rows.
    method : SonarMethod, optional
        The carving method the grid runs, fresh (no readings yet); it becomes the grid's own.
        Default: combined carving and ATM with specular-aware carving at 20°,
        ``make_method(DEFAULT_METHOD, MethodConfig(max_incidence=DEFAULT_MAX_INCIDENCE))``
        (:data:`DEFAULT_METHOD`; specular-aware carving alone, the default before, is
        ``make_method("carve", MethodConfig(max_incidence=math.radians(30)))``, paper carving
        ``make_method("carve")``). Any method works: the band is drawn ``width`` wide around the
        point's bearing (:class:`~sonarcarve.methods.Estimates` ``xy``; for evidence carving, whose
        point is off its kept run's middle, a measured choice:
        :func:`~sonarcarve.grids.carved.intervals.intervals`); its ``confidence``, where given,
        weighs the occupied band.
    params : CarvedGridParams, optional
        The sensor model (default: :class:`~sonarcarve.grids.carved.CarvedGridParams` defaults).

    Attributes
    ----------
    readings : int
        Readings folded in so far.

    Raises
    ------
    GridError
        A resolution or bounds that are not finite, not positive, or need more than
        :data:`~sonarcarve.grids.elfes.MAX_CELLS` cells; a method that has readings already.

    Examples
    --------
    >>> g = CarvedGrid(0.1, (0.0, 0.0, 2.0, 1.0))
    >>> g.add(Reading(t=0.0, sensor=0, x=0.05, y=0.55, theta=0.0, range=1.0))
    >>> p = g.probabilities()
    >>> float(p[5, 10].round(3)), float(p[5, 5].round(3))  # the arc's middle, free space
    (0.7, 0.406)
    >>> g.trinary()[5, [0, 5, 10, 15]].tolist()  # the newest echo, unexplained: marked now
    [-1, -1, 100, -1]
    >>> g.add(Reading(t=0.1, sensor=0, x=0.05, y=0.55, theta=math.pi, range=0.3))
    >>> float(g.probabilities()[5, 10].round(3))  # no longer the sensor's newest: spread
    0.606
    """

    def __init__(self, resolution: float, bounds: tuple[float, float, float, float],
                 method: SonarMethod | None = None, params: CarvedGridParams | None = None
                 ) -> None:
        super().__init__("carved grid", resolution, bounds, MAX_CELLS, "MAX_CELLS")
        (xmin, ymin, _, _), (ny, nx) = self._bounds, self._shape
        self._params = params if params is not None else CarvedGridParams()
        if method is None:
            method = make_method(DEFAULT_METHOD, _default_method_config(self._params))
        elif method.readings:
            msg = (f"carved grid: the method must be fresh, it has {method.readings} readings "
                   f"already")
            raise GridError(msg)
        self._method = method
        self._model = model_of(self._params, xmin, ymin, self._resolution, self.band)
        self._model_array = model_array(self._model)  # as the kernels take it
        self._l_min, self._l_max = self._model.l_min, self._model.l_max
        self._init_cells(ny, nx)
        self._init_slots(method.history.storage_size)
        self._init_reads(method)
        self._stale = False
        self.readings = 0
        method.add_commit_listener(self._on_commit)
        # A global map would grow with the log; the grid is the map, so only count the points.
        method.set_global_sink(CountingSink())

    def _init_cells(self, ny: int, nx: int) -> None:
        """The cell arrays (:class:`~sonarcarve.grids.carved.model.Maps`), all zero."""
        self._base = np.zeros((ny, nx), dtype=np.float32)
        self._live = np.zeros((ny, nx), dtype=np.float64)
        # The points of the fresh arcs (CarvedGridParams.fresh_arcs), apart from ``live`` so
        # that whether an echo is explained is judged on the spread arcs alone.
        self._points = np.zeros((ny, nx), dtype=np.float32)
        # Per cell, the bearings (HEARD_BINS sectors, one bit each) it was heard from.
        self._heard = np.zeros((ny, nx), dtype=HEARD_DTYPE)

    def _init_slots(self, size: int) -> None:
        """The record per history slot (``size`` of them): what it drew, its interval and
        weight at the last read, its repeats' factor."""
        # Per slot, what was drawn into ``live``: x, y, r, lo, hi, value; and the arc's
        # sequence number (its position in the stream of arcs), -1 for nothing
        # (model.SlotRecord).
        self._drawn = np.zeros((size, 6), dtype=np.float64)
        self._drawn_seq = np.full(size, -1, dtype=np.int64)
        self._pdrawn = np.zeros((size, 6), dtype=np.float64)  # the same for the points
        self._pseq = np.full(size, -1, dtype=np.int64)
        # Per slot, the interval and weight (intervals) of the live arc at the last read.
        self._lo = np.zeros(size)
        self._hi = np.zeros(size)
        self._weight = np.zeros(size)
        # Per slot, the factor of the arc's weight: repeat_weight if a later echo of its sensor
        # repeats it (geometry.repeats.is_repeat), else 1.
        self._chain = np.ones(size)
        # While a batch is folded in: its arcs' factors, by sequence number from _batch_first.
        self._batch_first = 0
        self._batch_chain = np.ones(0)

    def _init_reads(self, method: SonarMethod) -> None:
        """What the reads keep between them: the carving state seen, the arcs pending their
        final band, the sensors' newest arcs and firing periods."""
        size = method.history.storage_size
        # Plain carving or combined: per slot, the carving state (lo, hi, status) and the
        # number of ATM crossings those were computed from, and for which arc (-1: none); a
        # read asks only for the estimates of the arcs whose state changed since
        # (stale_slots). Any other method is asked for every live arc.
        self._carving, self._atm = known_models(method)
        # Combined carving's points, asked for their bearings alone (_update_intervals).
        self._combined = (method if self._atm is not None and isinstance(method, CombinedMethod)
                          else None)
        self._seen = np.zeros((size, 3), dtype=np.float64)
        self._seen_crossings = np.zeros(size, dtype=np.int32)
        self._no_crossings = np.zeros(size, dtype=np.int32)  # carving alone keeps none
        self._seen_seq = np.full(size, -1, dtype=np.int64)
        self._changed = np.zeros(size, dtype=np.int64)
        self._marked = np.empty(method.history.capacity, dtype=np.int64)  # _mark_repeats
        self._pending: list[Finals] = []
        self._next_final = 0  # sequence number of the next arc to leave the history
        # How long until a sensor has fired again; its rows number the sensors for _newest too.
        self._periods = FiringPeriods()
        # Per sensor row, the sequence number of its newest reading's arc (-1: it heard nothing,
        # or none yet).
        self._newest = np.full(0, -1, dtype=np.int64)
        self._latest_t = -math.inf  # time of the newest reading seen (fresh_seconds counts back)

    def __repr__(self) -> str:
        ny, nx = self.shape
        return (f"CarvedGrid({self._resolution:g} m, {nx} x {ny} cells, "
                f"bounds={self._bounds}, {self.readings} readings)")

    @classmethod
    def around(cls, extent: tuple[float, float, float, float], resolution: float,
               margin: float = 0.5, method: SonarMethod | None = None,
               params: CarvedGridParams | None = None) -> CarvedGrid:
        """A grid over ``extent = (xmin, ymin, xmax, ymax)`` grown by ``margin`` metres on
        every side.

        Raises
        ------
        GridError
            A negative or non-finite margin; a flat extent and no margin.
        """
        return cls(resolution, bounds_around("carved grid", extent, margin), method, params)

    # -- geometry ----------------------------------------------------------------------------

    @property
    def params(self) -> CarvedGridParams:
        """The sensor model."""
        return self._params

    @property
    def method(self) -> SonarMethod:
        """The carving method the grid runs (read it, do not feed it)."""
        return self._method

    @property
    def band(self) -> float:
        """Half-width b of the occupied band, metres: ``(h + ε) / 2``."""
        return 0.5 * (self._resolution + self._params.range_tolerance)

    @property
    def nbytes(self) -> int:
        """Memory of the grid's own state (the cell arrays and the per-slot record), bytes;
        the method's history and state come on top, fixed by its history size."""
        per_slot = (self._drawn, self._drawn_seq, self._pdrawn, self._pseq, self._lo, self._hi,
                    self._weight, self._chain, self._seen, self._seen_crossings,
                    self._no_crossings, self._seen_seq, self._changed, self._marked)
        return int(self._base.nbytes + self._live.nbytes + self._points.nbytes
                   + self._heard.nbytes + sum(a.nbytes for a in per_slot))

    # -- updates -----------------------------------------------------------------------------

    def add(self, reading: Reading) -> None:
        """Fold one reading in (validated as by the method's ``add``)."""
        self.add_many(ReadingBatch.from_readings([reading]))

    def add_many(self, batch: ReadingBatch) -> None:
        """Fold every reading of ``batch`` in, in order.

        The method checks the whole batch first (:meth:`~sonarcarve.methods.SonarMethod.add_many`):
        a bad batch raises :class:`~sonarcarve.readings.ReadingsError` and changes nothing.
        """
        n = len(batch)
        if not n:
            return
        method = self._method
        history = method.history
        first_seq = history.appended
        # A no-echo reading's free space reaches max_range, and it has no arc of its own.
        half, r, seqs, no_echo, n_echo = batch_columns(
            batch.beam_width, method.beam_width, batch.range, batch.max_range, self.band,
            first_seq)
        # The kernels take C-contiguous columns (a batch sliced with a step has none).
        x, y, theta = (np.ascontiguousarray(c) for c in (batch.x, batch.y, batch.theta))
        # Before the method runs: the arcs it retires during the batch are made final (their
        # weight read) as they retire, and an echo later in the batch may repeat them.
        marked = self._mark_repeats(batch, x, y, theta, seqs, no_echo, n_echo, half, first_seq)
        try:
            method.add_many(batch)
        except BaseException:  # a bad batch changes nothing
            self._chain[marked] = 1.0
            self._batch_chain = _NO_CHAIN
            raise
        self._note_newest(batch, seqs, no_echo)
        history.flush_retired()  # every arc that left the history is final now
        self._keep_batch_chain(history)
        finals = self._take_pending()
        # The batch's newest time is its last: the method checked that times never go back.
        self._latest_t = max(self._latest_t, float(batch.t[-1]))
        fold_kernel(self._base, self._heard, self._model_array, x, y, theta,
                    r, half, seqs, history.capacity, *finals)
        self.readings += n
        self._stale = True

    def _note_newest(self, batch: ReadingBatch, seqs: npt.NDArray[np.int64],
                     no_echo: BoolArray) -> None:
        """Remember each sensor's newest reading of the batch (by the sensor's row of the firing
        periods): its arc's sequence number, or -1 when it heard nothing (its arc is then no
        sensor's newest); and, when the rule reads them, note the firings' times
        (:class:`~sonarcarve.grids.carved.periods.FiringPeriods`). One compiled call
        (:func:`~sonarcarve.grids.carved.kernels.note_newest`), after the method took the batch
        (a bad batch changes nothing)."""
        periods = self._periods
        rows = periods.rows(batch.sensor)
        if len(self._newest) < periods.size:  # new sensors: rows for them
            self._newest = np.concatenate(
                (self._newest, np.full(periods.size - len(self._newest), -1, dtype=np.int64)))
        note_newest(self._newest, rows, seqs, no_echo, np.ascontiguousarray(batch.t),
                    self._params.fresh_periods < math.inf, *periods.note_state())

    def _mark_repeats(self, batch: ReadingBatch, x: FloatArray, y: FloatArray,
                      theta: FloatArray, seqs: npt.NDArray[np.int64], no_echo: BoolArray,
                      n_echo: int, half: FloatArray, first_seq: int) -> SlotArray:
        """Give the arcs that the batch's echoes repeat
        (:func:`~sonarcarve.geometry.repeats.is_repeat`) the weight factor
        :attr:`~sonarcarve.grids.carved.CarvedGridParams.repeat_weight`: those of the history in
        ``_chain`` (by slot; the next read recomputes their weights), the batch's own in
        ``_batch_chain`` (by sequence number from ``first_seq``: a long batch reuses slots). Returns
        the slots of the history's arcs it marked (their factor was 1): a view of a buffer the
        next batch reuses."""
        history = self._method.history
        self._batch_first = first_seq
        self._batch_chain = np.ones(n_echo)
        if self._params.repeat_weight >= 1.0:
            return self._marked[:0]
        marked = self._marked  # each live arc marked once at most
        count = repeat_kernel(self._chain, self._batch_chain, self._seen_seq, marked, seqs,
                              first_seq, no_echo, np.ascontiguousarray(batch.sensor), x, y,
                              np.ascontiguousarray(batch.range), theta, half,
                              history.sensor, history.x, history.y, history.r, history.theta,
                              history.beam_width, history.capacity,
                              self._params.range_tolerance, self._params.repeat_weight)
        return marked[:count]

    def _keep_batch_chain(self, history: SonarHistory) -> None:
        """The batch's arcs still in the history take their factors into their slots."""
        chain = self._batch_chain
        if len(chain):
            keep_chain(self._chain, chain, self._batch_first, history.appended - len(history),
                       history.storage_size)
        self._batch_first = history.appended
        self._batch_chain = _NO_CHAIN

    def _chain_of(self, slots: SlotArray, seqs: npt.NDArray[np.int64]) -> FloatArray:
        """Weight factors of the arcs ``seqs`` (in ``slots``): the batch's own from
        ``_batch_chain``, older ones from ``_chain``."""
        own = seqs >= self._batch_first
        out = self._chain[slots]
        if own.any():
            out = np.where(own, self._batch_chain[np.where(own, seqs - self._batch_first, 0)],
                           out)
        return out

    def _on_commit(self, history: SonarHistory, slots: SlotArray, est: Estimates) -> None:
        """Arcs leaving the history: their live contribution out, their final one pending."""
        seqs = self._next_final + np.arange(len(slots), dtype=np.int64)
        self._next_final += len(slots)
        retire_kernel(self._live, self._drawn, self._drawn_seq, self._points, self._pdrawn,
                      self._pseq, slots, seqs, self._heard, self._model_array)
        # Indexing by an array copies: the history's rows are reused.
        x, y, r = history.x[slots], history.y[slots], history.r[slots]
        lo, hi, weight = intervals(x, y, est)
        weight *= self._chain_of(slots, seqs)
        self._pending.append(Finals(x, y, r, lo, hi, weight, seqs))

    def _take_pending(self) -> Finals:
        """The arcs that left the history since the last call, in order (at a few readings a
        batch, one block: no copy)."""
        pending, self._pending = self._pending, []
        if len(pending) == 1:
            return pending[0]
        if not pending:
            return _NO_FINALS
        return Finals._make(np.concatenate(column) for column in zip(*pending, strict=True))

    def _sync(self) -> None:
        """Bring ``live`` (and the points) up to date with the method's current carved
        intervals: only the arcs whose interval or value changed since the last read are
        redrawn, and with plain carving only those arcs' estimates are asked for."""
        if not self._stale:
            return
        history = self._method.history
        slots = np.ascontiguousarray(history.slots())
        if len(slots):
            seqs = history.appended - len(slots) + np.arange(len(slots), dtype=np.int64)
            self._update_intervals(history, slots, seqs)
            params = self._params
            # The kernel's bundles field by field (refresh_kernel says why), in its order:
            # the maps, the two slot records, the history's rows, the intervals.
            refresh_kernel(self._base, self._live, self._points, self._heard,
                           self._drawn, self._drawn_seq, self._pdrawn, self._pseq,
                           history.x, history.y, history.r, history.theta1, history.theta2,
                           history.t, self._lo, self._hi, self._weight,
                           slots, seqs, self._model_array, params.fresh_arcs,
                           self._newest, self._latest_t, params.fresh_seconds,
                           params.fresh_periods, *self._periods.fit_state())
        self._stale = False

    def _update_intervals(self, history: SonarHistory, slots: SlotArray,
                          seqs: npt.NDArray[np.int64]) -> None:
        """``_lo, _hi, _weight`` of the live ``slots`` (arcs ``seqs``) as
        :func:`~sonarcarve.grids.carved.intervals.intervals` gives them from the method's
        estimates. With plain carving an estimate is a function of the arc's row and its model's
        ``lo, hi, status`` alone (:meth:`~sonarcarve.methods.carving.CarvingModel.estimates`), with
        combined carving of those and the arc's kept ATM crossings, so only the arcs whose state
        changed since the last read are computed: for carving alone from the model's state as its
        estimates would (:func:`~sonarcarve.grids.carved.intervals.carving_intervals`), for
        combined by asking the method for those arcs' point bearings alone
        (:meth:`~sonarcarve.methods.combined.CombinedMethod.point_bearings`: the numbers its
        estimates give, without building them; stored by
        :func:`~sonarcarve.grids.carved.intervals.store_intervals`). Measured for combined
        (``benchmarks/grid_reads.py``, office, a read every 5 readings): the grid's CPU per
        reading 4.32x -> 3.87x the range sensor layer's at 0.10 m, 1.98x -> 1.97x at 0.05 m."""
        carving = self._carving
        if carving is None:
            stale = slots
            lo, hi, weight = intervals(history.x[slots], history.y[slots],
                                       self._method.estimates(slots))
        else:
            crossings = self._no_crossings if self._atm is None else self._atm.counts
            count = stale_slots(slots, seqs, carving.lo, carving.hi, carving.status, crossings,
                                self._seen, self._seen_crossings, self._seen_seq, self._changed)
            if not count:
                return
            stale = slots[self._changed[:count]]
            combined = self._combined
            if combined is not None:  # its points' bearings alone, stored in one pass
                bearing, width, alive = combined.point_bearings(stale)
                store_intervals(stale, bearing, width, alive, self._chain, self._lo, self._hi,
                                self._weight)
                return
            lo, hi, weight = carving_intervals(history, carving, stale)
        self._lo[stale] = lo
        self._hi[stale] = hi
        self._weight[stale] = weight * self._chain[stale]

    def _fresh(self, slots: SlotArray, seqs: npt.NDArray[np.int64]) -> BoolArray:
        """Which of the live arcs ``seqs`` (consecutive, in ``slots``) is its sensor's newest
        reading, heard at most ``fresh_seconds`` before the newest reading seen, and less than
        ``fresh_periods`` of its sensor's firing periods before it. The reads work this out
        inside :func:`~sonarcarve.grids.carved.kernels.refresh_kernel` (the same
        :func:`~sonarcarve.grids.carved.kernels.mark_fresh`, one call a read); this is its
        seam for the tests."""
        fresh = np.zeros(len(seqs), dtype=bool)
        params = self._params
        fresh_kernel(self._newest, int(seqs[0]), slots, self._method.history.t, self._latest_t,
                     params.fresh_seconds, params.fresh_periods, *self._periods.fit_state(),
                     fresh)
        return fresh

    # -- reading the map ---------------------------------------------------------------------

    def refresh(self) -> None:
        """Bring the map up to date with the method's current carved intervals without
        reading it (every read does this first): what a costmap layer does when it is asked
        for its update, before the cells are read."""
        self._sync()

    @property
    def log_odds(self) -> FloatArray:
        """Each cell's log-odds of occupancy, ``clamp(base + live)``, shape :attr:`shape`
        (a new float64 array)."""
        self._sync()
        return np.asarray(np.clip(self._base + (self._live + self._points), self._l_min,
                                  self._l_max))

    @property
    def live_log_odds(self) -> FloatArray:
        """The live arcs' summed contribution (unclamped), shape :attr:`shape` (a copy)."""
        self._sync()
        return np.asarray(self._live + self._points)

    def probabilities(self) -> FloatArray:
        """Occupancy probability of every cell, shape :attr:`shape`: ``1 / (1 + exp(-l))``."""
        return np.asarray(1.0 / (1.0 + np.exp(-self.log_odds)))

    def trinary(self) -> Int8Grid:
        """:data:`~sonarcarve.grids.OCCUPIED` (100) where the log-odds :attr:`log_odds` is above
        ``logit(`` :attr:`~sonarcarve.grids.carved.CarvedGridParams.occupied_threshold` ``)``,
        :data:`~sonarcarve.grids.FREE` (0) below ``logit(free_threshold)``, else
        :data:`~sonarcarve.grids.UNKNOWN` (-1).

        Compared in log-odds, one pass, no temporary grids. The logistic is monotone, so this
        is comparing :meth:`probabilities` with the thresholds, up to rounding: a cell whose
        log-odds lies within a few ulp of a threshold's logit may land in the other class.
        """
        self._sync()
        out = np.empty(self.shape, dtype=np.int8)
        trinary_kernel(self._base, self._live, self._points, self._l_min, self._l_max,
                       logit(self._params.occupied_threshold),
                       logit(self._params.free_threshold), out)
        return out

    def occupied_mask(self, threshold: float | None = None) -> BoolArray:
        """Cells whose log-odds is above ``logit(threshold)`` (default
        :attr:`~sonarcarve.grids.carved.CarvedGridParams.occupied_threshold`), shape :attr:`shape`:
        the probability above ``threshold`` up to rounding, as :meth:`trinary`."""
        limit = self._params.occupied_threshold if threshold is None else check_probability(
            "carved grid", "threshold", threshold, 0.0, 1.0)
        return np.asarray(self.log_odds > logit(limit))

    def occupied_points(self, threshold: float | None = None) -> FloatArray:
        """Centres of the occupied cells (:meth:`occupied_mask`), shape (n, 2), row-major."""
        rows, cols = np.nonzero(self.occupied_mask(threshold))
        xs, ys = self.cell_centers()
        return np.column_stack((xs[cols], ys[rows])).astype(np.float64)


#: No arcs leaving the history (:meth:`CarvedGrid._take_pending`), no factors of a batch.
_NO_FINALS = Finals(np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0),
                    np.zeros(0, dtype=np.int64))
_NO_CHAIN = np.ones(0)


def _default_method_config(params: CarvedGridParams) -> MethodConfig:
    """The default method's configuration: specular-aware at :data:`DEFAULT_MAX_INCIDENCE`, its
    range tolerance ε the grid's own (one ε for the band and for carving, so that a user who
    widens it for a noisy sonar widens both), plus :data:`POSE_MARGIN_SIGMAS` ``pose_sigma``
    when one is given (a newer reading's free space then stops short of an older arc a pose
    error moved)."""
    return MethodConfig(max_incidence=DEFAULT_MAX_INCIDENCE,
                        range_tolerance=params.range_tolerance
                        + POSE_MARGIN_SIGMAS * params.pose_sigma)
