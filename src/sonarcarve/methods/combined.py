"""Arc carving and ATM on one history (paper, sections 4 and 5-A).

Storing the 6-tuple ``(x, y, r, θ, θ1, θ2)`` lets the two run "in parallel using the same data,
without interfering with each other" (section 5-A): here they are two models over one
:class:`~sonarcarve.history.SonarHistory`, each with its own per-row state, and the map keeps,
for every arc, "the most accurate data available from each technique" (section 4).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from sonarcarve.constants import DEFAULT_BEAM_WIDTH, POLAROID_RANGE_RESOLUTION
from sonarcarve.geometry import NO_INCIDENCE_LIMIT
from sonarcarve.geometry._compiled import compiled_borrowing
from sonarcarve.geometry.circular import scratch_arrays
from sonarcarve.geometry.fate import ALIVE
from sonarcarve.geometry.index import (
    ArcIndex,
    arc_box,
    index_insert,
    index_remove,
    query_box,
    query_sector,
)
from sonarcarve.history import DEFAULT_HISTORY_SIZE
from sonarcarve.maps import (
    SOURCE_ATM,
    SOURCE_CARVED,
    SOURCE_CENTERLINE,
)
from sonarcarve.methods.atm import AtmModel, add_atm_arc, row_median, start_atm_arc
from sonarcarve.methods.base import Estimates, SonarMethod, slot_indices
from sonarcarve.methods.carving import CarvingModel, carve_found, start_carved_arc
from sonarcarve.methods.config import (
    DEFAULT_MIN_TRANSVERSAL,
    DEFAULT_RANGE_TOLERANCE,
    MethodConfig,
)
from sonarcarve.readings import Reading
from sonarcarve.typing import BoolArray, FloatArray, Int8Array, IntArray, SlotArray

I32Array = npt.NDArray[np.int32]

__all__ = ["CombinedMethod", "combine_carving_atm"]



@compiled_borrowing
def _add_joint(
    first: int, count: int, capacity: int,
    x: FloatArray, y: FloatArray, r: FloatArray, theta: FloatArray, beam_width: FloatArray,
    theta1: FloatArray, theta2: FloatArray,
    lo: FloatArray, hi: FloatArray, bounds: FloatArray, tips: FloatArray, status: Int8Array,
    carved: BoolArray, tolerance: float, max_incidence: float,
    cos_axis: FloatArray, sin_axis: FloatArray, cos_half: FloatArray, cos_psi: float,
    bearings: npt.NDArray[np.float32], counts: npt.NDArray[np.int32],
    tally: npt.NDArray[np.int32], stale: BoolArray,
    head: I32Array, next_entry: I32Array, prev_entry: I32Array, entries: I32Array,
    stamp: IntArray, bucket_stamp: IntArray, tick: IntArray, cell_size: FloatArray,
    candidates: SlotArray, scratch_bearings: FloatArray, scratch_flags: BoolArray,
) -> tuple[int, int, int, int, int]:
    """Arcs ``first .. first + count - 1`` (sequence numbers) through ATM and carving, in
    order, with one index of every live arc for both: per arc what ATM's ``_add_arcs`` does
    (its crossings with the live arcs whose boxes meet its own), then what carving's does (its
    freespace carves the older alive arcs; the arcs carving removed are in the index and
    skipped), and the arc enters the index once. The two models touch disjoint state, so each
    ends exactly as when run alone.

    Returns ``(crossings kept, fully carved, split, done, needed)``: ``done`` is the sequence
    number after the last arc done and ``needed``, when it stops early, the columns ATM's store
    needs for arc ``done``, which neither model has taken in (ATM took its crossings back; an
    arc that left the history at its start is out of the index, and taking it out again does
    nothing), so the caller grows the store and calls again from ``done``.

    The index comes as its eight arrays (``*index``) and one ``candidates`` buffer serves both
    queries: numba's dispatcher unboxes every array argument (about 0.1 µs each, more inside a
    tuple), which is most of a single ``add()``'s cost. ``scratch_bearings, scratch_flags``
    are carving's work arrays (:func:`~sonarcarve.geometry.circular.scratch_arrays`): the
    kernel counts no references (:func:`~sonarcarve.geometry._compiled.compiled_borrowing`),
    so it cannot allocate them.
    """
    storage = x.shape[0]
    index = ArcIndex(head, next_entry, prev_entry, entries, stamp, bucket_stamp, tick, cell_size)
    cuts = scratch_bearings[0]
    starts = scratch_bearings[1]
    ends = scratch_bearings[2]
    flags = scratch_flags
    kept = 0
    fully = 0
    split = 0
    for sequence in range(first, first + count):
        slot = sequence % storage
        if sequence >= capacity:
            index_remove(index, (sequence - capacity) % storage)  # it has left the history
        start_atm_arc(slot, theta, beam_width, cos_axis, sin_axis, cos_half, counts, stale)
        xmin, xmax, ymin, ymax = arc_box(x[slot], y[slot], r[slot], theta1[slot], theta2[slot])
        found = query_box(index, xmin, xmax, ymin, ymax, candidates)
        if found < 0:  # a huge box: every live arc before this one
            found = _live_before(sequence, capacity, storage, candidates)
        arc_kept, needed = add_atm_arc(x, y, r, cos_axis, sin_axis, cos_half, slot, candidates,
                                       found, cos_psi, bearings, counts, tally, stale)
        if needed:
            return kept, fully, split, sequence, needed
        kept += arc_kept
        sector = start_carved_arc(slot, x, y, r, theta1, theta2, lo, hi, bounds, tips, status,
                                  carved, tolerance, max_incidence)
        if sector.radius > 0.0:
            found = query_sector(index, sector, candidates)
            if found < 0:  # a huge sector
                found = _live_before(sequence, capacity, storage, candidates)
            arcs_fully, arcs_split = carve_found(
                found, candidates, x, y, r, lo, hi, bounds, tips, status, carved, sector, index,
                False, cuts, starts, ends, flags)
            fully += arcs_fully
            split += arcs_split
        index_insert(index, slot, xmin, xmax, ymin, ymax)
    return kept, fully, split, first + count, 0


@compiled_borrowing
def _live_before(sequence: int, capacity: int, storage: int, out: SlotArray) -> int:
    """Slots of the live arcs before arc ``sequence``, written to ``out``; their count."""
    found = 0
    for older in range(max(0, sequence - capacity + 1), sequence):
        out[found] = older % storage
        found += 1
    return found


#: Rows of the work array of :meth:`CombinedMethod._point_rows`: the width, a quarter of it
#: (eq. 5.2's ``E_m / 2``), the point's bearing, carving's bound (first the sine of the quarter),
#: the bearing's cosine and sine, and (:meth:`CombinedMethod.point_bearings`) the point seen
#: from the sensor, ``dy`` and ``dx``.
_WIDTH, _QUARTER, _BEARING, _BOUND, _COS, _SIN, _DY, _DX = range(8)


@compiled_borrowing
def _carving_rows(slots: SlotArray, lo: FloatArray, hi: FloatArray, rows: FloatArray) -> int:
    """Carving's interval of each of ``slots`` into ``rows`` (:data:`_WIDTH` ...): its width
    ``hi - lo``, a quarter of it and its middle, the operations of
    :meth:`~sonarcarve.methods.carving.CarvingModel.estimates` and
    :func:`~sonarcarve.maps.chord_error`.

    Returns -1, or the position of the first slot outside ``lo`` (the rows then unfinished):
    numba does not check its indices, and the passes after this one index the history's and
    the models' arrays, all as long as ``lo``, by the same slots (a slot outside them read
    other memory, or crashed the process: review rev16)."""
    storage = lo.shape[0]
    for k in range(slots.shape[0]):
        s = slots[k]
        if not -storage <= s < storage:  # a negative slot counts back, as numpy's index does
            return k
        width = hi[s] - lo[s]
        rows[_WIDTH, k] = width
        rows[_QUARTER, k] = 0.5 * (0.5 * width)
        rows[_BEARING, k] = 0.5 * (lo[s] + hi[s])
    return -1


@compiled_borrowing
def _choose(
    slots: SlotArray, status: Int8Array, carved: BoolArray, counts: npt.NDArray[np.int32],
    r: FloatArray, rows: FloatArray, flags: BoolArray, codes: Int8Array, error_bound: float,
    theta: FloatArray, bearings: npt.NDArray[np.float32], stale: BoolArray, median: FloatArray,
    span: FloatArray, values: FloatArray,
) -> None:
    """:func:`combine_carving_atm`, row by row, in place: row ``k`` (``slots[k]``) comes with
    carving's point bearing, width and the sine of a quarter of the width in ``rows``, which
    becomes carving's bound ``2 r sin(θ_d / 4)`` (:func:`~sonarcarve.maps.chord_error`); where
    ATM's point wins (the row has kept a crossing and ``error_bound`` is below carving's
    bound), ATM's bearing ``θ + median``, width (the span), bound and source replace them.
    ``flags`` gets ``alive`` and ``processed``, ``codes`` the source and carving's fate. A
    median is sorted again only for a row whose crossings changed (``stale``, as
    :meth:`~sonarcarve.methods.atm.AtmModel.medians` does)."""
    for k in range(slots.shape[0]):
        s = slots[k]
        rows[_BOUND, k] = 2.0 * r[s] * rows[_BOUND, k]
        alive = status[s] == ALIVE
        flags[0, k] = alive
        flags[1, k] = carved[s] or not alive or counts[s] > 0
        codes[0, k] = SOURCE_CARVED if carved[s] else SOURCE_CENTERLINE
        codes[1, k] = status[s]
        if counts[s] == 0 or not rows[_BOUND, k] > error_bound:
            continue
        if stale[s]:
            row_median(bearings, counts, s, median, span, values)
            stale[s] = False
        rows[_BEARING, k] = theta[s] + median[s]
        rows[_WIDTH, k] = span[s]
        rows[_BOUND, k] = error_bound
        codes[0, k] = SOURCE_ATM


@compiled_borrowing
def _place(slots: SlotArray, x: FloatArray, y: FloatArray, r: FloatArray, rows: FloatArray,
           xy: FloatArray) -> None:
    """The points on the arcs ``slots`` at the bearings whose cosine and sine are in ``rows``
    (eq. 3.3 and 3.6), the operations of :func:`~sonarcarve.methods.base.arc_point`."""
    for k in range(slots.shape[0]):
        s = slots[k]
        xy[k, 0] = x[s] + r[s] * rows[_COS, k]
        xy[k, 1] = y[s] + r[s] * rows[_SIN, k]


@compiled_borrowing
def _seen_from_sensor(slots: SlotArray, x: FloatArray, y: FloatArray, r: FloatArray,
                      rows: FloatArray) -> None:
    """``rows[_DY], rows[_DX]``: the points :func:`_place` places, less the sensor's position
    (the same operations as :func:`_place` and then the carved grid's
    :func:`~sonarcarve.grids.carved.intervals.intervals`)."""
    for k in range(slots.shape[0]):
        s = slots[k]
        px = x[s] + r[s] * rows[_COS, k]
        py = y[s] + r[s] * rows[_SIN, k]
        rows[_DY, k] = py - y[s]
        rows[_DX, k] = px - x[s]


def combine_carving_atm(carving: Estimates, atm: Estimates) -> Estimates:
    """Per arc, the better of carving's and ATM's estimates (section 4).

    * ``alive``: carving's. An arc that carving removed (fully carved or split) is gone from the
      combined map even if ATM has crossings for it: the freespace of a newer reading says the
      echo did not come from anywhere on the arc (or from one connected piece of it), and that
      evidence is newer than any crossing, which may also be a spurious coincidence of two
      circles. Dropping it is what makes carving remove spurious returns (section 5-C).
    * the point, ``width``, ``max_error`` and ``source``: those of the estimate with the smaller
      ``max_error``, ATM's only where it has at least one kept crossing (its fallback is the
      centerline point, never better than carving's). Ties go to carving. ``source`` thus names
      the model that placed the point: ``carved``, ``atm`` or ``centerline`` (neither helped).
    * ``processed``: processed by either model, so the combined unprocessed share is at most the
      smaller of the two (Table I: 7.68 % against 31.75 % and 55.59 %).

    Parameters
    ----------
    carving, atm : Estimates
        The two models' estimates for the same rows.
    """
    use_atm = atm.processed & (atm.max_error < carving.max_error)
    return Estimates(
        alive=carving.alive,
        processed=carving.processed | atm.processed,
        xy=np.where(use_atm[:, None], atm.xy, carving.xy),
        width=np.where(use_atm, atm.width, carving.width),
        max_error=np.where(use_atm, atm.max_error, carving.max_error),
        source=np.where(use_atm, atm.source, carving.source).astype(np.int8),
        fate=carving.fate,
    )


class CombinedMethod(SonarMethod):
    """Carving and ATM on one shared history; each point from the model with the smaller bound.

    Parameters
    ----------
    history_size : int
        Arcs kept in the history (paper: 250).
    beam_width : float
        Default beam width φ, radians.
    range_tolerance : float
        Carving's ε ≥ 0, metres (see :class:`~sonarcarve.methods.carving.CarvingModel`).
    min_transversal : float
        ATM's ψ, radians (see :class:`~sonarcarve.methods.atm.AtmModel`).
    range_resolution : float
        ATM's δ, metres (see :func:`~sonarcarve.methods.atm.atm_error_bound`).
    max_incidence : float
        Carving's critical angle β, radians (see
        :class:`~sonarcarve.methods.carving.CarvingModel`; π/2, the default: the paper).

    Notes
    -----
    The rule is :func:`combine_carving_atm`. ``models`` is ``(CarvingModel, AtmModel)``; the
    counters of both are reported (``fully_carved``, ``split``, ``atm_crossings``). Both models
    are fed by one compiled call per reading or block (:func:`_add_joint`) over ATM's index of
    every live arc, which leaves each exactly as it would be alone (carving's own ``index`` then
    stays empty).
    """

    name = "combined"

    def __init__(
        self,
        history_size: int = DEFAULT_HISTORY_SIZE,
        beam_width: float = DEFAULT_BEAM_WIDTH,
        range_tolerance: float = DEFAULT_RANGE_TOLERANCE,
        min_transversal: float = DEFAULT_MIN_TRANSVERSAL,
        range_resolution: float = POLAROID_RANGE_RESOLUTION,
        max_incidence: float = NO_INCIDENCE_LIMIT,
    ) -> None:
        self.config = MethodConfig(
            history_size=history_size, beam_width=beam_width, range_tolerance=range_tolerance,
            min_transversal=min_transversal, range_resolution=range_resolution,
            max_incidence=max_incidence,
        )
        self.range_tolerance = self.config.range_tolerance
        self.max_incidence = self.config.max_incidence
        self.min_transversal = self.config.min_transversal
        self.range_resolution = self.config.range_resolution
        self._joint: bool | None = None  # decided at the first reading (_uses_joint_kernel)
        self._arguments: tuple[Any, ...] | None = None  # _joint_arguments
        super().__init__(history_size, beam_width)

    def _make_models(self) -> tuple[CarvingModel, AtmModel]:
        self._carving = CarvingModel(self.history, self.range_tolerance, self.max_incidence)
        self._atm = AtmModel(self.history, self.min_transversal, self.range_resolution)
        return self._carving, self._atm

    def _uses_joint_kernel(self) -> bool:
        """Whether both models run in :func:`_add_joint` over ATM's index (every live arc).

        Not when ATM scans every pair (ψ below
        :data:`~sonarcarve.methods.atm.MIN_INDEXED_TRANSVERSAL`, or switched off as the tests'
        oracle does): then each model runs alone, carving with its own index. Fixed at the
        first reading, since only one of the two indexes is kept up to date.
        """
        if self._joint is None:
            self._joint = self._atm.uses_index
        return self._joint

    def _feed_block(self, first: int, count: int) -> None:
        if not self._uses_joint_kernel():
            super()._feed_block(first, count)
            return
        carving, atm = self._carving, self._atm
        self._check_usable()
        end = first + count
        stopped_at = -1
        while first < end:
            kept, fully, split, first, needed = _add_joint(first, end - first,
                                                           *self._joint_arguments())
            atm.count_kept(kept)
            carving.count_removed(fully, split)
            if first < end:
                # The kernel stopped at an arc whose crossings did not fit. After the store
                # grows that arc fits, so stopping at it twice means the kernel never saw the
                # grown store: fail, rather than loop for ever.
                if first == stopped_at:
                    msg = ("combined: the joint kernel stopped twice at the same arc; ATM's "
                           "grown crossing store did not reach it")
                    raise RuntimeError(msg)
                stopped_at = first
                atm.make_room(needed)
                self._arguments = None  # the crossing store is a new array

    def _joint_arguments(self) -> tuple[Any, ...]:
        """The arguments of :func:`_add_joint` after ``first, count``, made once: the arrays
        stay the same (ATM's store is replaced only when it grows), and building the tuple
        anew was a good part of a single ``add()``. The last three are the kernel's candidate
        buffer and work arrays (scratch: new ones after a growth are as good)."""
        if self._arguments is None:
            h, carving, atm = self.history, self._carving, self._atm
            self._arguments = (
                h.capacity, h.x, h.y, h.r, h.theta, h.beam_width, h.theta1, h.theta2,
                carving.lo, carving.hi, carving.bounds, carving.tips, carving.status,
                carving.carved, carving.range_tolerance, carving.max_incidence,
                *atm.kernel_state(), *atm.index, np.zeros(h.storage_size, dtype=np.int64),
                *scratch_arrays(),
            )
        return self._arguments

    def _feed_no_echo(self, reading: Reading, beam_width: float) -> None:
        self._check_usable()  # a stopped ATM stops the method: no carving from the no-echo
        if self._uses_joint_kernel():
            # Carving finds its arcs in the joint index (removed arcs stay in it); ATM ignores
            # no-echo readings.
            self._carving.carve_free(reading, beam_width, self._atm.index, prune=False)
            self._atm.on_no_echo(reading, beam_width)
        else:
            super()._feed_no_echo(reading, beam_width)

    def _estimates(self, slots: SlotArray) -> Estimates:
        """:func:`combine_carving_atm` of the two models' estimates, bit for bit, each part
        computed only where it is chosen.

        Carving's interval gives every row's bearing, width and bound (eq. 3.6, 5.3, as
        :meth:`CarvingModel.estimates` computes them); ATM's point wins where it has a kept
        crossing and its bound is below carving's, and :func:`_choose` puts its median, span
        and bound there. The point is then placed once, at the chosen bearing, and ATM's
        fallback (the centerline, never chosen) is not computed. The trigonometry stays
        numpy's, on the same arrays as :func:`~sonarcarve.maps.chord_error` and
        :func:`~sonarcarve.methods.base.arc_point` give it: numba's libm sine may differ from
        numpy's vectorised one in the last bit. The rest is three compiled passes over one work
        array (:func:`_carving_rows`, :func:`_choose`, :func:`_place`), and the fields returned
        are rows of it. Why: the carved grid asks for a few arcs at every read and at every
        retiring block; the two models' full estimates with the selection between them cost
        about 40 numpy calls (45-50 µs for 5 arcs), the numpy version of this 30 numpy calls
        (about 18 µs, two calls a batch: a tenth of the grid's CPU time at 5 readings a read,
        office, 0.10 m; ``benchmarks/grid_reads.py``).
        """
        h = self.history
        slots = slot_indices(slots)
        rows, flags, codes = self._point_rows(slots)
        xy = np.empty((len(slots), 2))
        _place(slots, h.x, h.y, h.r, rows, xy)
        return Estimates(alive=flags[0], processed=flags[1], xy=xy, width=rows[_WIDTH],
                         max_error=rows[_BOUND], source=codes[0], fate=codes[1])

    def point_bearings(self, slots: SlotArray) -> tuple[FloatArray, FloatArray, BoolArray]:
        """For the arcs in ``slots``: the bearing of each point seen from its sensor
        (``arctan2`` of the point less the sensor's position), its width and whether it is
        alive: what the carved grid reads from :meth:`estimates` for its bands
        (:func:`~sonarcarve.grids.carved.intervals.intervals`), the same numbers, without the
        estimates' other fields (one compiled pass and numpy's ``arctan2`` in place of about ten
        array operations and the :class:`Estimates`; the grid asks at every read).

        Returns ``(bearing, width, alive)``, each of shape (len(slots),): radians, radians
        (eq. 5.1), bool.

        Raises the error that stopped a model for good, if one did, as :meth:`estimates`;
        ``IndexError`` for a slot outside the history's storage or not an integer, as
        :meth:`estimates`.
        """
        self._check_usable()
        h = self.history
        slots = slot_indices(slots)
        rows, flags, _ = self._point_rows(slots)
        _seen_from_sensor(slots, h.x, h.y, h.r, rows)
        return np.arctan2(rows[_DY], rows[_DX]), rows[_WIDTH], flags[0]

    def _point_rows(self, slots: SlotArray) -> tuple[FloatArray, BoolArray, Int8Array]:
        """The work array of :meth:`_estimates` (rows :data:`_WIDTH` .. :data:`_SIN` filled,
        eight rows), ``alive, processed`` and ``source, fate`` of the int64 ``slots``."""
        carving, atm, h = self._carving, self._atm, self.history
        n = len(slots)
        rows = np.empty((8, n))
        flags = np.empty((2, n), dtype=bool)
        codes = np.empty((2, n), dtype=np.int8)
        outside = _carving_rows(slots, carving.lo, carving.hi, rows)
        if outside >= 0:
            msg = (f"slot {slots[outside]} is out of bounds for the history's "
                   f"{len(carving.lo)} slots")
            raise IndexError(msg)
        np.sin(rows[_QUARTER], out=rows[_BOUND])
        _choose(slots, carving.status, carving.carved, atm.counts, h.r, rows, flags, codes,
                *atm.median_state())
        np.cos(rows[_BEARING], out=rows[_COS])
        np.sin(rows[_BEARING], out=rows[_SIN])
        return rows, flags, codes
