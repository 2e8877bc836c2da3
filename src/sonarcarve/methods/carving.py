"""Arc carving (paper, section 3; implementation as in section 5-A).

Every arc starts as its full beam ``[θ - φ/2, θ + φ/2]``. When a reading arrives, its freespace
sector (eq. 3.2) carves every older live arc that is still alive: the newer reading is
authoritative (eq. 3.5), so the new arc itself is never carved by older ones. An arc the sector
covers entirely is *fully carved*; an arc that would fall apart in two or more pieces is *split*;
both are removed from the map (section 3) and counted separately. The point of a surviving arc
is the middle of its carved interval (eq. 3.6), labelled ``carved`` once it has been carved and
``centerline`` before (then it is exactly the centerline point, eq. 3.3).

Opt-in, beyond the paper: with a critical angle ``max_incidence = β < π/2`` a newer reading
carves only the points of an older arc whose implied (specular) surface it would have seen
within ``β`` of the normal (``Z_ij^β``, see :mod:`sonarcarve.geometry`): on smooth walls a beam
that meets a wall at a glancing angle hears nothing, so its freespace is no evidence against
echoes from that wall. The default, :data:`~sonarcarve.geometry.NO_INCIDENCE_LIMIT` (π/2), is
the paper.

A no-echo reading (range +inf, :mod:`sonarcarve.methods.base`) carves the older live arcs with
its freespace up to ``max_range - ε`` exactly as a reading of range ``max_range`` would (eq. 3.2
with ``R = max_range - ε``), and adds no arc.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry import NO_INCIDENCE_LIMIT, arc_bounding_circle
from sonarcarve.geometry._compiled import compiled_borrowing, compiled_inline
from sonarcarve.geometry.bounds import (
    UNDECIDED,
    arc_clear_of_disk,
    arc_clear_of_wedge,
    circle_against_sector,
)
from sonarcarve.geometry.circular import scratch_arrays
from sonarcarve.geometry.fate import ALIVE, FULLY_CARVED, SHRUNK, UNCHANGED
from sonarcarve.geometry.index import (
    ArcIndex,
    arc_box_of_ends,
    index_arrays,
    index_insert,
    index_remove,
    make_index,
    query_sector,
    query_sector_circles,
)
from sonarcarve.geometry.intervals import carve_core
from sonarcarve.geometry.sector import Sector, make_sector
from sonarcarve.history import DEFAULT_HISTORY_SIZE, SonarHistory
from sonarcarve.maps import PointSource, chord_error
from sonarcarve.methods.arrays import (
    CarvedArcs,
    CarveScratch,
    CarvingRules,
    HistoryRows,
    PlainBundle,
    history_rows,
    in_a_row,
    live_slots,
)
from sonarcarve.methods.base import ArcModel, Estimates, SonarMethod, arc_point
from sonarcarve.methods.config import (
    DEFAULT_RANGE_TOLERANCE,
    MethodConfig,
    check_max_incidence,
    check_range_tolerance,
)
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading
from sonarcarve.typing import BoolArray, FloatArray, Int8Array, IntArray, SlotArray

I32Array = npt.NDArray[np.int32]


__all__ = [
    "DEFAULT_RANGE_TOLERANCE",
    "CarvingMethod",
    "CarvingModel",
    "carve_found",
    "start_carved_arc",
]



@compiled_inline
def _clear_of_sector(i: int, history: HistoryRows, arcs: CarvedArcs, sector: Sector) -> bool:
    """The sector leaves arc ``i`` unchanged, by a test without trigonometry: the arc is clear
    of its disk (:func:`~sonarcarve.geometry.bounds.arc_clear_of_disk`) or of one of its
    half-planes (:func:`~sonarcarve.geometry.bounds.arc_clear_of_wedge`).

    ``tips[i]`` caches ``e(lo), e(hi)``, each end NaN when that end moved: most arcs are tested
    many times between changes, and carving mostly moves one end of an arc (cos and sin of the
    same double: the same values whenever they are computed).
    """
    tips = arcs.tips
    if math.isnan(tips[i, 0]):
        # The angle read once: a store into ``tips`` between reads of ``lo[i]`` (which it might
        # alias, for the compiler) kept cos and sin of one angle from becoming one sincos call.
        start = arcs.lo[i]
        cos_start = math.cos(start)
        sin_start = math.sin(start)
        tips[i, 0] = cos_start
        tips[i, 1] = sin_start
    if math.isnan(tips[i, 2]):
        end = arcs.hi[i]
        cos_end = math.cos(end)
        sin_end = math.sin(end)
        tips[i, 2] = cos_end
        tips[i, 3] = sin_end
    ox = history.x[i]
    oy = history.y[i]
    radius = history.r[i]
    clo = tips[i, 0]
    slo = tips[i, 1]
    chi = tips[i, 2]
    shi = tips[i, 3]
    return (arc_clear_of_disk(ox, oy, radius, clo, slo, chi, shi, sector)
            or arc_clear_of_wedge(ox, oy, radius, clo, slo, chi, shi, sector))


@compiled_inline
def start_carved_arc(slot: int, history: HistoryRows, arcs: CarvedArcs,
                     rules: CarvingRules) -> Sector:
    """A new arc in ``slot``: alive, not carved, its full beam (section 3) and the circle around
    it; returns its freespace sector (eq. 3.2), which carves the older arcs. The arc's
    ``tips`` are its beam's edge directions, which the sector has computed: ``e(θ1), e(θ2)``
    of the same angles, the values :func:`_clear_of_sector` would compute."""
    x, y, r = history.x, history.y, history.r
    start = history.theta1[slot]
    end = history.theta2[slot]
    arcs.lo[slot] = start
    arcs.hi[slot] = end
    cx, cy, radius = arc_bounding_circle(x[slot], y[slot], r[slot], start, end)
    arcs.bounds[slot, 0] = cx
    arcs.bounds[slot, 1] = cy
    arcs.bounds[slot, 2] = radius
    arcs.status[slot] = ALIVE
    arcs.carved[slot] = False
    sector = make_sector(x[slot], y[slot], r[slot], start, end, rules.tolerance,
                         rules.max_incidence)
    arcs.tips[slot, 0] = sector.u1x
    arcs.tips[slot, 1] = sector.u1y
    arcs.tips[slot, 2] = sector.u2x
    arcs.tips[slot, 3] = sector.u2y
    return sector


@compiled_inline
def _shrink(i: int, new_lo: float, new_hi: float, history: HistoryRows,
            arcs: CarvedArcs) -> None:
    """Arc ``i`` carved to ``[new_lo, new_hi]``: the end that moved loses its cached
    direction, and its bounding circle is drawn again."""
    if new_lo != arcs.lo[i]:
        arcs.tips[i, 0] = math.nan
    if new_hi != arcs.hi[i]:
        arcs.tips[i, 2] = math.nan
    arcs.lo[i] = new_lo
    arcs.hi[i] = new_hi
    arcs.bounds[i, 0], arcs.bounds[i, 1], arcs.bounds[i, 2] = arc_bounding_circle(
        history.x[i], history.y[i], history.r[i], new_lo, new_hi)


@compiled_inline
def carve_found(found: int, history: HistoryRows, arcs: CarvedArcs, sector: Sector,
                index: ArcIndex, prune: bool, scratch: CarveScratch) -> tuple[int, int]:
    """Carve the arcs ``scratch.candidates[:found]`` by ``sector``: the step of
    :func:`~sonarcarve.geometry.carve_arcs`, arc by arc, for the arcs the index returned (the
    others it leaves unchanged). Arcs already removed are skipped; an arc it removes leaves
    ``index`` too when ``prune`` (an index of the alive arcs; a shared index keeps every live
    arc). Returns ``(fully carved, split)``."""
    x, y, r, lo, hi, bounds = history.x, history.y, history.r, arcs.lo, arcs.hi, arcs.bounds
    cuts, starts, ends = scratch.bearings[0], scratch.bearings[1], scratch.bearings[2]
    fully = 0
    split = 0
    for k in range(found):
        i = scratch.candidates[k]
        if arcs.status[i] != ALIVE:
            continue
        # Cheapest test first: the arc's bounding circle, then its ends, then the closed form.
        # (The tests stay in this loop: a step returning the fate made carving 4-8 % slower.)
        fate = circle_against_sector(bounds[i, 0], bounds[i, 1], bounds[i, 2], x[i], y[i],
                                     r[i], sector)
        if fate == UNCHANGED:
            continue
        new_lo = lo[i]
        new_hi = hi[i]
        if fate == UNDECIDED:
            if _clear_of_sector(i, history, arcs, sector):
                continue
            fate, new_lo, new_hi = carve_core(x[i], y[i], r[i], new_lo, new_hi, sector, cuts,
                                              starts, ends, scratch.flags)
            if fate == UNCHANGED:
                continue
        arcs.carved[i] = True
        if fate == SHRUNK:
            _shrink(i, new_lo, new_hi, history, arcs)
            continue
        arcs.status[i] = fate
        if prune:
            index_remove(index, i)
        if fate == FULLY_CARVED:
            fully += 1
        else:
            split += 1
    return fully, split


@compiled_borrowing
def _add_arcs(
    first: int, count: int, capacity: int,
    # HistoryRows
    x: FloatArray, y: FloatArray, r: FloatArray, theta: FloatArray, beam_width: FloatArray,
    theta1: FloatArray, theta2: FloatArray,
    # CarvedArcs, CarvingRules, CarveScratch
    lo: FloatArray, hi: FloatArray, bounds: FloatArray, tips: FloatArray, status: Int8Array,
    carved: BoolArray, tolerance: float, max_incidence: float,
    candidates: SlotArray, bearings: FloatArray, flags: BoolArray,
    # ArcIndex
    head: I32Array, next_entry: I32Array, prev_entry: I32Array, entries: I32Array,
    stamp: IntArray, bucket_stamp: IntArray, tick: IntArray, cell_size: FloatArray,
) -> tuple[int, int]:
    """Arcs ``first .. first + count - 1`` (sequence numbers; slot = sequence mod storage), in
    order: initialise each as its full beam (section 3), carve the live arcs before it by its
    freespace (eq. 3.5), then enter it in the index. The arguments after ``capacity``: the
    history's, carving's (:meth:`CarvingModel.kernel_state`) and the index's arrays:
    numba's dispatcher unboxes separate arguments fastest (about 0.05 µs an
    array, twice that in a tuple, several µs for NamedTuples), and a single ``add()`` costs
    5-7 µs, so the bundles of :mod:`~sonarcarve.methods.arrays` come as their fields, one after
    the other (the comments say which), and are named on the first lines.

    ``index`` holds exactly the live, alive arcs: the arc leaving the history and the arcs
    carving removes are taken out. Each reading carves only the arcs the index returns for its
    sector whose bounding circles it does not leave clear
    (:func:`~sonarcarve.geometry.index.query_sector_circles`), the same arcs the all-pairs
    :func:`~sonarcarve.geometry.carve_arcs` would change, with the same step, so the results
    are identical. One compiled call per block: Python between readings cost more than the
    carving.

    The kernel counts no references
    (:func:`~sonarcarve.geometry._compiled.compiled_borrowing`, half of its time before), so
    it cannot allocate its work arrays: :class:`~sonarcarve.methods.arrays.CarveScratch`.
    """
    history = HistoryRows(x, y, r, theta, beam_width, theta1, theta2)
    arcs = CarvedArcs(lo, hi, bounds, tips, status, carved)
    rules = CarvingRules(tolerance, max_incidence)
    scratch = CarveScratch(candidates, bearings, flags)
    index = ArcIndex(head, next_entry, prev_entry, entries, stamp, bucket_stamp, tick,
                     cell_size)
    storage = history.x.shape[0]
    fully = 0
    split = 0
    for sequence in range(first, first + count):
        slot = sequence % storage
        if sequence >= capacity:
            index_remove(index, (sequence - capacity) % storage)  # it left the history
        sector = start_carved_arc(slot, history, arcs, rules)
        if sector.radius > 0.0:
            arcs_fully, arcs_split = _carve_older(sequence, capacity, history, arcs, sector,
                                                  index, scratch)
            fully += arcs_fully
            split += arcs_split
        _enter(slot, history, sector, index)
    return fully, split


@compiled_inline
def _carve_older(sequence: int, capacity: int, history: HistoryRows, arcs: CarvedArcs,
                 sector: Sector, index: ArcIndex, scratch: CarveScratch) -> tuple[int, int]:
    """Carve the live arcs before arc ``sequence`` by its ``sector`` (eq. 3.5): those near the
    sector whose circles it does not leave clear; the removed ones leave ``index``."""
    found = query_sector_circles(index, sector, arcs.bounds, scratch.candidates)
    if found < 0:  # a huge sector: every live arc before this one
        found = live_slots(sequence - capacity + 1, sequence, history.x.shape[0],
                           scratch.candidates)
    return carve_found(found, history, arcs, sector, index, True, scratch)


@compiled_inline
def _enter(slot: int, history: HistoryRows, sector: Sector, index: ArcIndex) -> None:
    """Enter the new arc in ``slot`` in ``index``, by the box of its full beam, from the edge
    directions its sector has computed."""
    xmin, xmax, ymin, ymax = arc_box_of_ends(
        history.x[slot], history.y[slot], history.r[slot], history.theta1[slot],
        history.theta2[slot], sector.u1x, sector.u1y, sector.u2x, sector.u2y)
    index_insert(index, slot, xmin, xmax, ymin, ymax)


@compiled_borrowing
def _carve_free(
    fx: float, fy: float, fr: float, f_lo: float, f_hi: float, appended: int, capacity: int,
    prune: bool,
    # HistoryRows
    x: FloatArray, y: FloatArray, r: FloatArray, theta: FloatArray, beam_width: FloatArray,
    theta1: FloatArray, theta2: FloatArray,
    # CarvedArcs, CarvingRules, CarveScratch
    lo: FloatArray, hi: FloatArray, bounds: FloatArray, tips: FloatArray, status: Int8Array,
    carved: BoolArray, tolerance: float, max_incidence: float,
    candidates: SlotArray, bearings: FloatArray, flags: BoolArray,
    # ArcIndex
    head: I32Array, next_entry: I32Array, prev_entry: I32Array, entries: I32Array,
    stamp: IntArray, bucket_stamp: IntArray, tick: IntArray, cell_size: FloatArray,
) -> tuple[int, int]:
    """Carve the live arcs (the ``appended`` arcs so far, the newest ``capacity`` of them live)
    by the freespace of a no-echo reading at ``(fx, fy)`` over ``[f_lo, f_hi]`` that listened
    to ``fr`` metres (its sector ends at ``fr - tolerance``). The carving step of
    :func:`_add_arcs`, without a new arc, on the same arrays; returns
    ``(fully carved, split)``. ``prune``: the index holds only the alive arcs
    (:func:`carve_found`)."""
    history = HistoryRows(x, y, r, theta, beam_width, theta1, theta2)
    arcs = CarvedArcs(lo, hi, bounds, tips, status, carved)
    rules = CarvingRules(tolerance, max_incidence)
    scratch = CarveScratch(candidates, bearings, flags)
    index = ArcIndex(head, next_entry, prev_entry, entries, stamp, bucket_stamp, tick,
                     cell_size)
    sector = make_sector(fx, fy, fr, f_lo, f_hi, rules.tolerance, rules.max_incidence)
    if sector.radius <= 0.0:
        return 0, 0
    found = query_sector(index, sector, scratch.candidates)
    if found < 0:  # a huge sector: every live arc
        found = live_slots(appended - capacity, appended, history.x.shape[0],
                           scratch.candidates)
    return carve_found(found, history, arcs, sector, index, prune, scratch)


class CarvingModel(ArcModel):
    """Per-arc carved intervals over a shared history (section 5-A).

    Parameters
    ----------
    history : SonarHistory
        The history whose rows this model carves.
    range_tolerance : float
        ε ≥ 0, metres: the freespace of a reading of range r ends at ``r - ε`` (0: the paper).
    max_incidence : float
        Critical angle β in ``[0, π/2]``, radians: a newer reading does not carve points of an
        older arc whose implied surface it would see at a larger incidence (π/2: the paper).

    Attributes
    ----------
    lo, hi : ndarray of float64, shape (history.storage_size,)
        Carved interval ``[θ1', θ2']`` of each row (eq. 3.5), radians, unwrapped.
    status : ndarray of int8, shape (history.storage_size,)
        :class:`~sonarcarve.geometry.ArcFate` of each row: ``ALIVE``, ``FULLY_CARVED`` or
        ``SPLIT`` (removed).
    carved : ndarray of bool, shape (history.storage_size,)
        The row has been carved at least once (shrunk or removed).
    bounds : ndarray of float64, shape (history.storage_size, 3)
        A circle ``(cx, cy, radius)`` containing each carved arc
        (:func:`~sonarcarve.geometry.arc_bounding_circle`): a cheap first test in carving.
    tips : ndarray of float64, shape (history.storage_size, 4)
        ``cos lo, sin lo, cos hi, sin hi`` of each carved interval; ``tips[:, 0]`` (``[:, 2]``)
        is NaN when ``lo`` (``hi``) has moved since a test needed them
        (:func:`~sonarcarve.geometry.bounds.arc_clear_of_disk`, ``arc_clear_of_wedge``: cheap
        tests before the closed form).
    index : ArcIndex
        The live arcs that carving has not removed, by place
        (:mod:`sonarcarve.geometry.index`): a reading carves only those near its sector.
    """

    def __init__(self, history: SonarHistory, range_tolerance: float,
                 max_incidence: float = NO_INCIDENCE_LIMIT) -> None:
        super().__init__(history)
        self.range_tolerance = check_range_tolerance(range_tolerance)
        self.max_incidence = check_max_incidence(max_incidence)
        size = history.storage_size
        self.lo = np.zeros(size)
        self.hi = np.zeros(size)
        self.bounds = np.zeros((size, 3))
        self.tips = np.full((size, 4), np.nan)
        self.status = np.full(size, ALIVE, dtype=np.int8)
        self.carved = np.zeros(size, dtype=bool)
        self.index = make_index(size)
        self.arcs = CarvedArcs(self.lo, self.hi, self.bounds, self.tips, self.status,
                               self.carved)
        self.rules = CarvingRules(self.range_tolerance, self.max_incidence)
        self.scratch = CarveScratch(np.zeros(size, dtype=np.int64), *scratch_arrays())
        # The bundles as the kernels take them from Python (the arrays module's docstring).
        self._plain = (tuple(self.arcs), tuple(self.rules), tuple(self.scratch))
        self._arrays_without_index = in_a_row(*self._plain)
        self._arrays = self._arrays_without_index + index_arrays(self.index)
        self._fully_carved = 0
        self._split = 0

    def on_add_many(self, first: int, count: int) -> None:
        """Start each new arc ``first .. first + count - 1`` as its full beam and carve the
        older live arcs by its freespace, in one compiled call (the spatial index finds the arcs
        to carve)."""
        fully, split = _add_arcs(first, count, self.history.capacity,
                                 *history_rows(self.history), *self._arrays)
        self.count_removed(fully, split)

    def kernel_state(self) -> tuple[PlainBundle, PlainBundle, PlainBundle]:
        """What a kernel carving this model's arcs takes, plain: its
        :class:`~sonarcarve.methods.arrays.CarvedArcs`, :class:`~sonarcarve.methods.arrays.
        CarvingRules` and :class:`~sonarcarve.methods.arrays.CarveScratch`."""
        return self._plain

    def count_removed(self, fully: int, split: int) -> None:
        """Add arcs removed by a kernel that the method ran for this model."""
        self._fully_carved += fully
        self._split += split

    def on_no_echo(self, reading: Reading, beam_width: float) -> None:
        """Carve the live arcs by the no-echo reading's beam up to ``max_range - ε``."""
        self.carve_free(reading, beam_width, self.index, prune=True)

    def carve_free(self, reading: Reading, beam_width: float, index: ArcIndex, *,
                   prune: bool) -> None:
        """:meth:`on_no_echo` with the arcs to carve found in ``index``: this model's own index
        of the alive arcs (``prune``: the arcs it removes leave it) or, without ``prune``, an
        index of every live arc that the method keeps (combined's joint kernel)."""
        h = self.history
        half = 0.5 * beam_width
        fully, split = _carve_free(
            reading.x, reading.y, reading.max_range, reading.theta - half, reading.theta + half,
            h.appended, h.capacity, prune,
            *history_rows(h), *(self._arrays_without_index + index_arrays(index)))
        self.count_removed(fully, split)

    def estimates(self, slots: SlotArray) -> Estimates:
        """Points at the middle of the carved intervals (eq. 3.6) and their bounds (5.1-5.3).

        ``processed`` is "carved at least once": an arc removed by carving (fully carved or
        split) was carved too, so it counts as processed. This makes Table I's unprocessed share
        comparable across methods (an arc only leaves the unprocessed pool by interacting).
        """
        status = self.status[slots]
        alive = status == ALIVE  # the int: comparing with the enum member took 3 µs
        carved = self.carved[slots]
        lo = self.lo[slots]
        hi = self.hi[slots]
        width = hi - lo
        return Estimates(
            alive=alive,
            processed=carved | ~alive,
            xy=arc_point(self.history, slots, 0.5 * (lo + hi)),
            width=width,
            max_error=chord_error(self.history.r[slots], width),
            source=np.where(carved, np.int8(PointSource.CARVED),
                            np.int8(PointSource.CENTERLINE)).astype(np.int8),
            fate=status,
        )

    def counters(self) -> dict[str, int]:
        """Arcs removed since the start: ``{"fully_carved": n, "split": m}``."""
        return {"fully_carved": self._fully_carved, "split": self._split}


class CarvingMethod(SonarMethod):
    """Arc carving as a streaming method (sections 3 and 5-A).

    Parameters
    ----------
    history_size : int
        Arcs kept in the history (paper: 250).
    beam_width : float
        Default beam width φ, radians.
    range_tolerance : float
        ε ≥ 0, metres (0 is the paper exactly; the default is measured, see
        :data:`DEFAULT_RANGE_TOLERANCE`).
    max_incidence : float
        Critical angle β in ``[0, π/2]``, radians, of specular-aware carving (beyond the paper;
        see :class:`CarvingModel`). π/2, the default: off, the paper.
    """

    name = "carve"

    def __init__(
        self,
        history_size: int = DEFAULT_HISTORY_SIZE,
        beam_width: float = DEFAULT_BEAM_WIDTH,
        range_tolerance: float = DEFAULT_RANGE_TOLERANCE,
        max_incidence: float = NO_INCIDENCE_LIMIT,
    ) -> None:
        self.config = MethodConfig(history_size=history_size, beam_width=beam_width,
                                   range_tolerance=range_tolerance, max_incidence=max_incidence)
        self.range_tolerance = self.config.range_tolerance
        self.max_incidence = self.config.max_incidence
        super().__init__(history_size, beam_width)

    def _make_models(self) -> tuple[CarvingModel]:
        return (CarvingModel(self.history, self.range_tolerance, self.max_incidence),)

    def _combine(self, estimates: tuple[Estimates, ...]) -> Estimates:
        return estimates[0]
