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
from sonarcarve.geometry._compiled import compiled_borrowing, compiled_inline
from sonarcarve.geometry.fate import ALIVE
from sonarcarve.geometry.index import (
    ArcIndex,
    arc_box,
    index_arrays,
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
from sonarcarve.methods.arrays import (
    AtmArcs,
    AtmMedians,
    CarvedArcs,
    CarveScratch,
    CarvingRules,
    HistoryRows,
    PairScratch,
    PointWork,
    history_rows,
    in_a_row,
    live_slots,
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
    # HistoryRows
    x: FloatArray, y: FloatArray, r: FloatArray, theta: FloatArray, beam_width: FloatArray,
    theta1: FloatArray, theta2: FloatArray,
    # CarvedArcs, CarvingRules, CarveScratch
    lo: FloatArray, hi: FloatArray, bounds: FloatArray, tips: FloatArray, status: Int8Array,
    carved: BoolArray, tolerance: float, max_incidence: float,
    candidates: SlotArray, bearings: FloatArray, flags: BoolArray,
    # AtmArcs, cos ψ, PairScratch
    cos_axis: FloatArray, sin_axis: FloatArray, cos_half: FloatArray,
    crossings: npt.NDArray[np.float32], counts: npt.NDArray[np.int32], stale: BoolArray,
    cos_psi: float, pair_candidates: SlotArray, tally: npt.NDArray[np.int32],
    # ArcIndex
    head: I32Array, next_entry: I32Array, prev_entry: I32Array, entries: I32Array,
    stamp: IntArray, bucket_stamp: IntArray, tick: IntArray, cell_size: FloatArray,
) -> tuple[int, int, int, int, int]:
    """Arcs ``first .. first + count - 1`` (sequence numbers) through ATM and carving, in
    order, with one index of every live arc for both: per arc what ATM's ``_add_arcs`` does
    (its crossings with the live arcs whose boxes meet its own, :func:`_cross_arc`), then what
    carving's does (its freespace carves the older alive arcs; the arcs carving removed are in
    the index and skipped, :func:`_carve_by_arc`), and the arc enters the index once. The two
    models touch disjoint state, so each ends exactly as when run alone.

    The arguments after ``capacity``: the history's, carving's
    (:meth:`~sonarcarve.methods.carving.CarvingModel.kernel_state`), ATM's
    (:meth:`~sonarcarve.methods.atm.AtmModel.kernel_state`) and the index's arrays. numba's
    dispatcher unboxes separate arguments fastest (about 0.05 µs an array, twice that in a
    tuple, several µs for NamedTuples), and a single ``add()`` costs 5-7 µs, so the bundles of
    :mod:`~sonarcarve.methods.arrays` come as their fields, one after the other (the comments
    say which), and are named on the first lines. The kernel counts no references
    (:func:`~sonarcarve.geometry._compiled.compiled_borrowing`), so it cannot allocate its work
    arrays: both scratch bundles.

    Returns ``(crossings kept, fully carved, split, done, needed)``: ``done`` is the sequence
    number after the last arc done and ``needed``, when it stops early, the columns ATM's store
    needs for arc ``done``, which neither model has taken in (ATM took its crossings back; an
    arc that left the history at its start is out of the index, and taking it out again does
    nothing), so the caller grows the store and calls again from ``done``.
    """
    history = HistoryRows(x, y, r, theta, beam_width, theta1, theta2)
    carved_arcs = CarvedArcs(lo, hi, bounds, tips, status, carved)
    rules = CarvingRules(tolerance, max_incidence)
    carve_scratch = CarveScratch(candidates, bearings, flags)
    atm = AtmArcs(cos_axis, sin_axis, cos_half, crossings, counts, stale)
    pairs = PairScratch(pair_candidates, tally)
    index = ArcIndex(head, next_entry, prev_entry, entries, stamp, bucket_stamp, tick,
                     cell_size)
    storage = history.x.shape[0]
    kept = 0
    fully = 0
    split = 0
    for sequence in range(first, first + count):
        slot = sequence % storage
        if sequence >= capacity:
            index_remove(index, (sequence - capacity) % storage)  # it left the history
        xmin, xmax, ymin, ymax = arc_box(history.x[slot], history.y[slot], history.r[slot],
                                         history.theta1[slot], history.theta2[slot])
        arc_kept, needed = _cross_arc(sequence, capacity, (xmin, xmax, ymin, ymax), history,
                                      atm, cos_psi, index, pairs)
        if needed:
            return kept, fully, split, sequence, needed
        kept += arc_kept
        arcs_fully, arcs_split = _carve_by_arc(sequence, capacity, history, carved_arcs, rules,
                                               index, carve_scratch)
        fully += arcs_fully
        split += arcs_split
        index_insert(index, slot, xmin, xmax, ymin, ymax)
    return kept, fully, split, first + count, 0


@compiled_inline
def _cross_arc(sequence: int, capacity: int, box: tuple[float, float, float, float],
               history: HistoryRows, atm: AtmArcs, cos_psi: float, index: ArcIndex,
               scratch: PairScratch) -> tuple[int, int]:
    """ATM's step for arc ``sequence`` (section 2-D): a new arc with no crossings, intersected
    with the live arcs whose boxes meet its ``box`` (:func:`~sonarcarve.methods.atm.
    add_atm_arc`); ``(kept, needed)`` as that returns."""
    storage = history.x.shape[0]
    slot = sequence % storage
    start_atm_arc(slot, history, atm)
    xmin, xmax, ymin, ymax = box
    found = query_box(index, xmin, xmax, ymin, ymax, scratch.candidates)
    if found < 0:  # a huge box: every live arc before this one
        found = live_slots(sequence - capacity + 1, sequence, storage, scratch.candidates)
    return add_atm_arc(slot, found, cos_psi, history, atm, scratch)


@compiled_inline
def _carve_by_arc(sequence: int, capacity: int, history: HistoryRows, arcs: CarvedArcs,
                  rules: CarvingRules, index: ArcIndex, scratch: CarveScratch) -> tuple[int, int]:
    """Carving's step for arc ``sequence``: a new arc as its full beam (section 3), whose
    freespace sector (eq. 3.2) carves the older live arcs near it (eq. 3.5; the removed ones
    stay in the shared index, :func:`~sonarcarve.methods.carving.carve_found` skips them);
    ``(fully carved, split)``."""
    storage = history.x.shape[0]
    sector = start_carved_arc(sequence % storage, history, arcs, rules)
    if not sector.radius > 0.0:
        return 0, 0
    found = query_sector(index, sector, scratch.candidates)
    if found < 0:  # a huge sector
        found = live_slots(sequence - capacity + 1, sequence, storage, scratch.candidates)
    return carve_found(found, history, arcs, sector, index, False, scratch)


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
    slots: SlotArray, rows: FloatArray, flags: BoolArray, codes: Int8Array,
    # the history's ranges and axes, carving's fates
    r: FloatArray, theta: FloatArray, status: Int8Array, carved: BoolArray,
    # ATM's bound, then AtmMedians
    error_bound: float, bearings: npt.NDArray[np.float32], counts: npt.NDArray[np.int32],
    stale: BoolArray, median: FloatArray, span: FloatArray, values: FloatArray,
) -> None:
    """:func:`combine_carving_atm`, row by row, in place: row ``k`` (``slots[k]``) comes with
    carving's point bearing, width and the sine of a quarter of the width in ``rows``, which
    becomes carving's bound (:func:`_carving_choice`); where ATM's point wins (the row has kept
    a crossing and ``error_bound`` is below carving's bound), ATM's bearing, width, bound and
    source replace them (:func:`_atm_choice`). ``flags`` gets ``alive`` and ``processed``,
    ``codes`` the source and carving's fate.

    The bundles' fields come as separate parameters (the comments say whose), as for the
    kernels that add arcs (:mod:`~sonarcarve.methods.arrays`): the carved grid asks at every
    read.
    """
    work = PointWork(rows, flags, codes)
    medians = AtmMedians(bearings, counts, stale, median, span, values)
    for k in range(slots.shape[0]):
        s = slots[k]
        _carving_choice(k, s, r, status, carved, counts, work)
        if counts[s] == 0 or not rows[_BOUND, k] > error_bound:
            continue
        _atm_choice(k, s, theta, error_bound, medians, work)


@compiled_inline
def _carving_choice(k: int, s: int, r: FloatArray, status: Int8Array, carved: BoolArray,
                    counts: npt.NDArray[np.int32], work: PointWork) -> None:
    """Row ``k`` as carving places slot ``s``: its bound ``2 r sin(θ_d / 4)`` (eq. 5.3,
    :func:`~sonarcarve.maps.chord_error`) from the sine in ``rows[_BOUND]``, ``alive``,
    ``processed`` by either model (carved, removed, or with ``counts`` of kept crossings), the
    source (``carved`` or ``centerline``) and carving's fate."""
    rows, flags, codes = work
    rows[_BOUND, k] = 2.0 * r[s] * rows[_BOUND, k]
    alive = status[s] == ALIVE
    flags[0, k] = alive
    flags[1, k] = carved[s] or not alive or counts[s] > 0
    codes[0, k] = SOURCE_CARVED if carved[s] else SOURCE_CENTERLINE
    codes[1, k] = status[s]


@compiled_inline
def _atm_choice(k: int, s: int, theta: FloatArray, error_bound: float, medians: AtmMedians,
                work: PointWork) -> None:
    """Row ``k`` as ATM places slot ``s`` (section 2-D): its bearing ``θ + median``, width (the
    span), bound (eq. 5.4) and source. The median is sorted again only for a row whose
    crossings changed (``stale``, as :meth:`~sonarcarve.methods.atm.AtmModel.medians`
    does)."""
    rows, _, codes = work
    if medians.stale[s]:
        row_median(medians.bearings, medians.counts, s, medians.median, medians.span,
                   medians.values)
        medians.stale[s] = False
    rows[_BEARING, k] = theta[s] + medians.median[s]
    rows[_WIDTH, k] = medians.span[s]
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
        anew was a good part of a single ``add()``. Carving's state comes as
        :meth:`CarvingModel.kernel_state` gives it, ATM's as :meth:`AtmModel.kernel_state`."""
        if self._arguments is None:
            h = self.history
            atm, cos_psi, pairs = self._atm.kernel_state()
            self._arguments = (h.capacity, *in_a_row(
                history_rows(h), *self._carving.kernel_state(), atm, (cos_psi,), pairs,
                index_arrays(self._atm.index)))
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
        _choose(slots, rows, flags, codes, h.r, h.theta, carving.status, carving.carved,
                *atm.median_state())
        np.cos(rows[_BEARING], out=rows[_COS])
        np.sin(rows[_BEARING], out=rows[_SIN])
        return rows, flags, codes
