"""The Arc Transversal Median (ATM) model (paper, section 2-D; error bound eq. 5.4).

Every new arc is intersected with every live arc of the history. An intersection of the two
*circles* is kept when it lies inside *both* arcs' full beams (eq. 2.1: ``τ`` in
``[θ − φ/2, θ + φ/2]``, not a carved interval) and the two arcs cross there transversally, at an
angle of at least ψ. Kept intersections are stored with both arcs, as bearings relative to each
arc's axis θ; an arc's ATM point is on its circle at the median of its stored bearings, and an arc
with none falls back to its centerline point.

Two facts shape the model and the choice of ψ:

* Two arcs with origins ``D`` apart and equal range ``r`` cross at ``2 asin(D / 2r)``, so a
  crossing at ψ or more needs ``D ≥ D_min = 2 r sin(ψ/2)`` of travel (eq. 2.2): latency grows
  with range and with ψ.
* At a point inside both beams the radii point along the two bearings, so the angle between them
  is within ``φ`` of the angle between the two sensor axes. Two readings of one sensor on a
  translating robot therefore never cross at more than ``φ`` (22.5° for the Polaroid): with
  ``ψ > φ`` only pairs of *different* sensors (or of one sensor after the robot turned) can meet.
  The same argument shows that with ``ψ > φ`` the *mirror* crossing of two arcs that share a
  point reflector (its reflection in the line of the origins) is never kept; below φ it can be.

Choosing ψ (default 20°, :class:`~sonarcarve.methods.config.MethodConfig`). Smaller ψ cuts
latency (eq. 2.2: ``D_min`` = 0.17 r at 10°, 0.35 r at 20°, 0.52 r at 30°, 0.77 r at 45°) and
loosens the noise bound (eq. 5.4: 11.4, 5.7, 3.7, 2.4 range quanta). Measured with
``benchmarks/min_transversal.py`` (5 synthetic corridor logs, 13,540 readings, 1 cm range
noise, one-inch quantum, history 250), the median distance of ATM points to the walls was
0.054 / 0.049 / 0.053 / 0.064 m and the mean unprocessed share 14 / 22 / 29 / 39 % for
ψ = 10 / 20 / 30 / 45°: the bound is loose in practice (medians of many crossings), while
large ψ only crosses arcs from far-apart origins, whose reflectors on a wall differ. 20° had the
lowest error with a quarter less latency than 30°.

The circle–circle intersection geometry is in :mod:`sonarcarve.geometry`
(:func:`~sonarcarve.geometry.circle_intersections`).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.constants import DEFAULT_BEAM_WIDTH, POLAROID_RANGE_RESOLUTION
from sonarcarve.errors import SonarcarveError
from sonarcarve.geometry import common_chord
from sonarcarve.geometry._compiled import compiled, compiled_borrowing, compiled_inline
from sonarcarve.geometry.arctan import SERIES_ERROR, SERIES_T, atan_series
from sonarcarve.geometry.index import (
    ArcIndex,
    arc_box,
    index_arrays,
    index_insert,
    index_remove,
    make_index,
    query_box,
)
from sonarcarve.history import DEFAULT_HISTORY_SIZE, SonarHistory
from sonarcarve.maps import PointSource, chord_error
from sonarcarve.methods.arrays import (
    AtmArcs,
    HistoryRows,
    PairScratch,
    PlainBundle,
    history_rows,
    live_slots,
)
from sonarcarve.methods.base import ArcModel, Estimates, SonarMethod, arc_point
from sonarcarve.methods.config import (
    DEFAULT_MIN_TRANSVERSAL,
    MethodConfig,
    check_min_transversal,
    check_range_resolution,
)
from sonarcarve.typing import BoolArray, FloatArray, IntArray, SlotArray

I32Array = npt.NDArray[np.int32]

__all__ = [
    "BEARING_MARGIN",
    "INITIAL_COLUMNS",
    "MAX_ATM_STATE_BYTES",
    "MIN_INDEXED_TRANSVERSAL",
    "AtmMethod",
    "AtmModel",
    "CrossingStore",
    "CrossingStoreError",
    "add_atm_arc",
    "atm_error_bound",
    "grown_columns",
    "row_median",
    "start_atm_arc",
]


#: Most memory ATM's crossing store may take, bytes (1 GiB). The store grows on demand (see
#: :class:`AtmModel`): as many columns as the busiest arc has kept crossings, rounded up to a
#: power of two (512 at a history of 10,000 on the benchmark stream: 41 MB), or to what is left
#: of the 1 GiB. Only an arc with more crossings than 1 GiB leaves room for (1,342 at the
#: largest history, 100,000 arcs in 200,000 rows) stops the method with
#: :class:`CrossingStoreError`, and then for good: the arcs of the block that needed the room
#: are in the history but not all intersected, so every later call raises it again.
MAX_ATM_STATE_BYTES = 2**30

#: Columns of the crossing store when a model starts (it doubles when an arc needs more).
INITIAL_COLUMNS = 32


#: Smallest ψ (radians) for which ATM uses its spatial index: below it the crossings of
#: nearly tangent circles are too ill-conditioned to be sure they fall in the padded boxes of
#: :mod:`sonarcarve.geometry.index` (with ψ ≥ 1e-4 they are off by at most about 1e-12 r).
MIN_INDEXED_TRANSVERSAL = 1e-4


#: Margin of :func:`_bearing32` around the series' bearing: its error bound, four times over.
BEARING_MARGIN = 4.0 * SERIES_ERROR


class CrossingStoreError(SonarcarveError, MemoryError):
    """ATM's crossing store would exceed :data:`MAX_ATM_STATE_BYTES`: some arc has more
    transversal crossings than that much memory holds. The method cannot go on (the readings of
    the block that needed the room are in the history but not all intersected); a shorter
    history bounds the crossings an arc can collect."""


def grown_columns(rows: int, columns: int, needed: int, most: int, owner: str = "ATM's") -> int:
    """Columns of a crossing store of ``rows`` rows and ``columns`` columns after it grows to
    hold ``needed`` crossings in one row: doubled until enough, never more than ``most`` (every
    crossing an arc can have) nor than :data:`MAX_ATM_STATE_BYTES` holds (a last step short of a
    doubling uses what is left), and :class:`CrossingStoreError` (naming the store's ``owner``)
    when even that is fewer than ``needed``."""
    while columns < needed:
        columns *= 2
    budget = MAX_ATM_STATE_BYTES // (4 * rows)  # float32 bearings
    columns = min(columns, max(most, needed), budget)
    if columns < needed:
        msg = (f"{owner} crossing store would take {rows * needed * 4 / 2**30:.1f} GiB for "
               f"{needed} crossings of one arc (at most {MAX_ATM_STATE_BYTES / 2**30:.0f} GiB); "
               "use a shorter history_size")
        raise CrossingStoreError(msg)
    return columns


class CrossingStore:
    """The kept transversal crossings of each history row, as ATM's model and evidence carving
    keep them: ``bearings`` (float32, relative to the row's arc axis) and their ``counts``.

    It starts with :data:`INITIAL_COLUMNS` columns (at most ``most``) and grows on demand
    (:meth:`grow`, :func:`grown_columns`). A growth past :data:`MAX_ATM_STATE_BYTES` stops it
    for good: crossings were lost, so :meth:`check_usable` raises the error from then on.

    Parameters
    ----------
    rows : int
        Rows, one per history slot (``storage_size``).
    most : int
        Columns no arc can outgrow (every crossing it can have): the store never grows past.
    owner : str
        Whose store it is, for the error message (``"ATM's"``).
    """

    def __init__(self, rows: int, most: int, owner: str) -> None:
        self.most = most
        self.owner = owner
        self.bearings = np.zeros((rows, min(INITIAL_COLUMNS, most)), dtype=np.float32)
        self.counts = np.zeros(rows, dtype=np.int32)
        self.failed: CrossingStoreError | None = None

    def grow(self, needed: int) -> None:
        """Widen the store to hold ``needed`` crossings in one row, keeping every bearing.

        If it cannot (:class:`CrossingStoreError`), the store stops for good: the error is
        kept for :meth:`check_usable`, no row's count is left past the store's end, and it is
        raised.
        """
        rows, old = self.bearings.shape
        try:
            columns = grown_columns(rows, old, needed, self.most, self.owner)
        except CrossingStoreError as error:
            self.failed = error
            np.minimum(self.counts, old, out=self.counts)
            raise
        wider = np.zeros((rows, columns), dtype=np.float32)
        wider[:, :old] = self.bearings
        self.bearings = wider

    def check_usable(self) -> None:
        """Raise the :class:`CrossingStoreError` that stopped the store, if one did."""
        if self.failed is not None:
            raise CrossingStoreError(str(self.failed))


def atm_error_bound(min_transversal: float, range_resolution: float) -> float:
    """Error bound of one ATM point, metres: ``δ (1/sin ψ + 1/tan ψ)`` (eq. 5.4 times δ).

    Eq. 5.4 is dimensionless: it is the error in units of the range uncertainty δ (the sensor's
    range quantum, one inch for the Polaroid). A range known to ``δ`` makes each arc an annulus
    of width δ; two annuli crossing at angle ψ overlap in a rhombus of side ``δ / sin ψ``, and
    ``δ (1/sin ψ + 1/tan ψ) = δ cot(ψ/2)`` is that rhombus's extent along either arc (one side
    plus the projection of the adjacent one): the azimuth uncertainty of the crossing. The
    rhombus's long diagonal is ``δ / sin(ψ/2)``, larger by ``1 / cos(ψ/2)``; but with each range
    within ``±δ/2`` of the truth the crossing is at most *half* that diagonal,
    ``δ / (2 sin(ψ/2))``, from the true reflector (to first order in δ/r), and
    ``δ cot(ψ/2)`` exceeds that by ``2 cos(ψ/2) ≥ √2``, so it is a safe bound for a common point
    reflector. It does not cover specular walls, where two arcs' reflectors differ. With exact
    ranges (δ = 0) the bound is 0; with ψ = 0 (tangent crossings kept) there is none (``inf``).

    Examples
    --------
    >>> round(atm_error_bound(math.radians(90.0), 1.0), 12)
    1.0
    >>> round(atm_error_bound(math.radians(30.0), 0.0254), 4)  # 3.732 inches
    0.0948
    >>> atm_error_bound(0.0, 0.0254)  # ψ = 0 keeps tangent crossings: no bound
    inf
    """
    if range_resolution == 0.0:
        return 0.0  # exact ranges: every crossing of arcs sharing a reflector is the reflector
    if min_transversal == 0.0:
        return math.inf
    return range_resolution * (1.0 / math.sin(min_transversal) + 1.0 / math.tan(min_transversal))


@compiled_inline
def _bearing32(cross: float, along: float) -> float:
    """``atan2(cross, along)`` as the crossing store keeps it (float32), from
    :func:`atan_series` where every value within :data:`BEARING_MARGIN` of the series' rounds
    to one nonzero float32 (rounding is monotone, so the exact bearing rounds to it too: the
    same bits; zero is left open, -0.0 and 0.0 compare equal), else from ``atan2``. A kept
    crossing lies inside the beam, so ``|cross| / along`` is at most ``tan(φ/2)``, 0.199 for
    the Polaroid's 22.5°."""
    if along > 0.0 and abs(cross) <= SERIES_T * along:
        a = atan_series(cross / along)
        low = np.float32(a - BEARING_MARGIN)
        if low == np.float32(a + BEARING_MARGIN) and low != 0.0:
            return float(low)
    return math.atan2(cross, along)


@compiled_inline
def _crosses_at_psi(rj: float, ri: float, d2: float, cos_psi: float) -> bool:
    """Whether two circles of radii ``rj, ri``, centres ``√d2`` apart, cross at an angle of at
    least ψ. With ``cos γ = (rj² + ri² − d²) / (2 rj ri)`` the test reads
    ``|rj² + ri² − d²| ≤ 2 rj ri cos ψ``: no square root or trig, and for ψ > 0 it also implies
    that the circles cross (``|cos γ| < 1``). Both crossings of a pair share one transversal
    angle, so it rejects the pair at once. (``d2 = 0`` passes only for equal, concentric
    circles at ψ = 0: they never cross.)"""
    return not (abs(rj * rj + ri * ri - d2) > 2.0 * rj * ri * cos_psi or d2 == 0.0)


@compiled_inline
def _store_crossing(slot: int, i: int, px: float, py: float, along_j: float, qx: float,
                    qy: float, along_i: float, atm: AtmArcs) -> None:
    """Append a kept crossing to the rows of the new arc ``slot`` and of the older arc ``i``,
    as bearings relative to each one's axis (:func:`_bearing32`; ``p``, ``q``: the crossing
    relative to their origins, ``along_*`` its component along their axes), and mark row
    ``i`` stale (its median must be computed again)."""
    cos_axis, sin_axis, bearings, counts = atm.cos_axis, atm.sin_axis, atm.bearings, atm.counts
    bearings[slot, counts[slot]] = _bearing32(cos_axis[slot] * py - sin_axis[slot] * px,
                                              along_j)
    counts[slot] += 1
    bearings[i, counts[i]] = _bearing32(cos_axis[i] * qy - sin_axis[i] * qx, along_i)
    counts[i] += 1
    atm.stale[i] = True


@compiled_inline
def _take_back(slot: int, found: int, kept: int, atm: AtmArcs, scratch: PairScratch) -> int:
    """Undo :func:`add_atm_arc` for the arc in ``slot``, whose crossings did not all fit: its
    partners lose the crossings stored with it and its row is emptied. Returns the columns the
    store needs to hold them all."""
    counts, tally = atm.counts, scratch.tally
    needed = kept
    for k in range(found):
        i = scratch.candidates[k]
        counts[i] -= tally[k, 1]
        needed = max(needed, counts[i] + tally[k, 0])
    counts[slot] = 0
    return needed


@compiled_inline
def add_atm_arc(slot: int, found: int, cos_psi: float, history: HistoryRows, atm: AtmArcs,
                scratch: PairScratch) -> tuple[int, int]:
    """Intersect the arc in ``slot`` with the ``scratch.candidates[:found]`` older arcs and
    store the kept crossings.

    Kept: ``|cos γ| ≤ cos ψ`` (transversal angle ≥ ψ) and inside both full beams (eq. 2.1). Each
    kept crossing is appended to both rows of ``atm.bearings`` as a bearing relative to that
    arc's axis, and both rows are marked ``stale`` (their medians must be computed again).
    Returns ``(kept, 0)``: the number of crossings kept.

    When a row is full, nothing of this arc stays: its partners' rows lose the crossings stored
    with it (the last ones of each row; ``scratch.tally[k]`` counts, for ``candidates[k]``, the
    crossings found and stored) and the call returns ``(0, needed)``, the columns the store
    needs to hold them all (:func:`_take_back`); the caller grows it and calls again.

    Most pairs fail the transversal test (ψ of eq. 2.2 and 5.4), so it comes first and costs
    no square root or trig (:func:`_crosses_at_psi`). The beam test compares ``(p − o)·axis`` with
    ``r cos(φ/2)`` (``|τ − θ| ≤ φ/2`` for ``φ < π``); only kept crossings pay for an arctangent
    (:func:`_bearing32`).
    """
    x, y, r = history.x, history.y, history.r
    cos_axis, sin_axis, cos_half, counts = atm.cos_axis, atm.sin_axis, atm.cos_half, atm.counts
    tally = scratch.tally
    width = atm.bearings.shape[1]
    xj, yj, rj = x[slot], y[slot], r[slot]
    cj, sj, hj = cos_axis[slot], sin_axis[slot], cos_half[slot]
    kept = 0
    full = False
    for k in range(found):
        tally[k, 0] = 0
        tally[k, 1] = 0
        i = scratch.candidates[k]
        ri = r[i]
        dx = x[i] - xj
        dy = y[i] - yj
        d2 = dx * dx + dy * dy
        if not _crosses_at_psi(rj, ri, d2, cos_psi):
            continue
        a, h = common_chord(d2, rj, ri)
        d = math.sqrt(d2)
        ux = dx / d
        uy = dy / d
        for sign in (1.0, -1.0):
            # The crossing relative to o_j (p) and to o_i (q), and the two beam tests.
            px = a * ux - sign * h * uy
            py = a * uy + sign * h * ux
            along_j = px * cj + py * sj
            if along_j < rj * hj:
                continue
            qx = px - dx
            qy = py - dy
            along_i = qx * cos_axis[i] + qy * sin_axis[i]
            if along_i < ri * cos_half[i]:
                continue
            kept += 1
            tally[k, 0] += 1
            full = full or counts[slot] >= width or counts[i] >= width
            if full:
                continue  # only counted from now on: see the docstring
            _store_crossing(slot, i, px, py, along_j, qx, qy, along_i, atm)
            tally[k, 1] += 1
    if not full:
        return kept, 0
    return 0, _take_back(slot, found, kept, atm, scratch)


@compiled_inline
def start_atm_arc(slot: int, history: HistoryRows, atm: AtmArcs) -> None:
    """A new arc in ``slot``: no crossings yet, and its axis and half-beam cosines for the beam
    tests of :func:`add_atm_arc`."""
    atm.counts[slot] = 0
    atm.stale[slot] = True
    axis = history.theta[slot]  # read once, so that cos and sin become one sincos call
    atm.cos_axis[slot] = math.cos(axis)
    atm.sin_axis[slot] = math.sin(axis)
    atm.cos_half[slot] = math.cos(0.5 * history.beam_width[slot])


@compiled_borrowing
def _add_arcs(
    first: int, count: int, capacity: int, cos_psi: float, use_index: bool,
    # HistoryRows
    x: FloatArray, y: FloatArray, r: FloatArray, theta: FloatArray, beam_width: FloatArray,
    theta1: FloatArray, theta2: FloatArray,
    # AtmArcs, PairScratch
    cos_axis: FloatArray, sin_axis: FloatArray, cos_half: FloatArray,
    crossings: npt.NDArray[np.float32], counts: npt.NDArray[np.int32], stale: BoolArray,
    pair_candidates: SlotArray, tally: npt.NDArray[np.int32],
    # ArcIndex
    head: I32Array, next_entry: I32Array, prev_entry: I32Array, entries: I32Array,
    stamp: IntArray, bucket_stamp: IntArray, tick: IntArray, cell_size: FloatArray,
) -> tuple[int, int, int]:
    """Arcs ``first .. first + count - 1`` (sequence numbers; slot = sequence mod storage), in
    order: reset each one's crossings and intersect it with the live arcs before it
    (:func:`add_atm_arc`).

    The arguments after ``use_index``: the history's, ATM's (:meth:`AtmModel.kernel_state`) and
    the index's arrays: numba's dispatcher unboxes separate arguments fastest (about 0.05 µs an
    array, twice that in a tuple, several µs for NamedTuples), and a single ``add()`` costs
    5-7 µs, so the bundles of :mod:`~sonarcarve.methods.arrays` come as their fields, one after
    the other (the comments say which), and are named on the first lines. With ``use_index``
    only the arcs the index returns for the new arc's box
    (:func:`~sonarcarve.geometry.index.query_box`) are intersected: a kept crossing lies on both
    full beams, so both boxes contain it. ``index`` holds the live arcs (ATM removes none).
    Off (ψ < :data:`MIN_INDEXED_TRANSVERSAL`), every live arc is: the crossings of nearly
    tangent circles are too ill-conditioned for the boxes' padding.

    Returns ``(kept, done, needed)``: the crossings kept, the sequence number after the last arc
    done (``first + count`` when all are) and, when it stops early, the columns the crossing
    store needs for arc ``done`` (0 otherwise). It stops at an arc whose crossings do not fit,
    having taken them back (:func:`add_atm_arc`) and changed nothing else of that arc that a
    second call would not redo the same way, so the caller grows the store and calls again from
    ``done``.

    Compiled without reference counting
    (:func:`~sonarcarve.geometry._compiled.compiled_borrowing`): it only borrows its arrays.
    """
    history = HistoryRows(x, y, r, theta, beam_width, theta1, theta2)
    atm = AtmArcs(cos_axis, sin_axis, cos_half, crossings, counts, stale)
    pairs = PairScratch(pair_candidates, tally)
    index = ArcIndex(head, next_entry, prev_entry, entries, stamp, bucket_stamp, tick,
                     cell_size)
    storage = history.x.shape[0]
    kept = 0
    for sequence in range(first, first + count):
        slot = sequence % storage
        if sequence >= capacity:
            index_remove(index, (sequence - capacity) % storage)  # it left the history
        start_atm_arc(slot, history, atm)
        xmin, xmax, ymin, ymax = arc_box(history.x[slot], history.y[slot], history.r[slot],
                                         history.theta1[slot], history.theta2[slot])
        found = -1
        if use_index:
            found = query_box(index, xmin, xmax, ymin, ymax, pairs.candidates)
        if found < 0:
            found = live_slots(sequence - capacity + 1, sequence, storage, pairs.candidates)
        arc_kept, needed = add_atm_arc(slot, found, cos_psi, history, atm, pairs)
        if needed:
            return kept, sequence, needed
        kept += arc_kept
        if use_index:
            index_insert(index, slot, xmin, xmax, ymin, ymax)
    return kept, first + count, 0


@compiled_inline
def _shell_sort(values: FloatArray, count: int) -> None:
    """Sort ``values[:count]`` in place (Shell's sort, Knuth's gaps 1, 4, 13, ...).

    Not ``np.sort``: numba's quicksort took a second to compile, for lists of a few crossings.
    Any correct sort gives the same order statistics, so the medians are unchanged.
    """
    gap = 1
    while gap < count // 3:
        gap = 3 * gap + 1
    while gap > 0:
        for i in range(gap, count):
            v = values[i]
            j = i
            while j >= gap and values[j - gap] > v:
                values[j] = values[j - gap]
                j -= gap
            values[j] = v
        gap //= 3


@compiled_inline
def row_median(bearings: npt.NDArray[np.float32], counts: npt.NDArray[np.int32], s: int,
               median: FloatArray, span: FloatArray, values: FloatArray) -> None:
    """Median and span (max − min) of row ``s``'s stored bearings, written to ``median[s]``
    and ``span[s]``; 0 where it has none. ``values`` is a work array of the store's width."""
    c = counts[s]
    median[s] = 0.0
    span[s] = 0.0
    if c == 0:
        return
    for i in range(c):
        values[i] = bearings[s, i]
    _shell_sort(values, c)
    median[s] = 0.5 * (values[(c - 1) // 2] + values[c // 2])
    span[s] = values[c - 1] - values[0]


@compiled
def _medians(
    bearings: npt.NDArray[np.float32], counts: npt.NDArray[np.int32], slots: SlotArray,
    median: FloatArray, span: FloatArray,
) -> None:
    """:func:`row_median` of each of ``slots`` (``median`` and ``span`` are by slot)."""
    values = np.empty(bearings.shape[1])
    for k in range(slots.shape[0]):
        row_median(bearings, counts, slots[k], median, span, values)


class AtmModel(ArcModel):
    """ATM over a shared history (section 2-D): the median of transversal crossings per arc.

    State does not grow with the length of the log: ``bearings`` has one row per history slot
    and a column per crossing the busiest arc has kept (``counts``). It starts with
    :data:`INITIAL_COLUMNS` and doubles when a crossing does not fit (the arc being added is
    then taken back and added again). An arc meets at most ``capacity − 1`` older arcs when it
    arrives and ``capacity − 1`` newer ones while it is live, and two circles cross at most
    twice, so it never needs more than ``4 (capacity − 1)`` (both crossings of one pair can lie
    in both beams when two sensors face each other), and in practice far fewer: on the benchmark
    stream at a history of 10,000 arcs the busiest arc keeps 378, a store of 41 MB (512 columns)
    where room for every possible crossing would take 3.2 GB.

    Crossings found with a partner that later leaves the history stay with the arc: they were
    found while both were live. A row is reset only when its slot is reused by a new arc.

    Parameters
    ----------
    history : SonarHistory
        The shared history.
    min_transversal : float
        ψ, radians in ``[0, π/2]``: crossings at a smaller angle are dropped (eq. 2.2, 5.4);
        at 0 every crossing is kept and the error bound is infinite.
    range_resolution : float
        δ, metres (≥ 0): the range quantum that scales eq. 5.4 (see :func:`atm_error_bound`).

    Notes
    -----
    :meth:`estimates` gives, per arc: ``processed`` = at least one kept crossing (Table I);
    ``alive`` always (ATM removes nothing); ``width`` = span of the kept bearings (0 for a single
    crossing), or the beam width φ for a centerline fallback; ``max_error`` =
    :func:`atm_error_bound` for ATM points, ``chord_error(r, φ)`` (eq. 5.3) for fallbacks.
    """

    def __init__(self, history: SonarHistory, min_transversal: float, range_resolution: float):
        super().__init__(history)
        self.min_transversal = check_min_transversal(min_transversal)
        self.range_resolution = check_range_resolution(range_resolution)
        self.error_bound = atm_error_bound(min_transversal, range_resolution)
        self._cos_psi = math.cos(min_transversal)
        # Columns no arc can outgrow (module docstring): the store never grows beyond them.
        self.store = CrossingStore(history.storage_size, max(1, 4 * (history.capacity - 1)),
                                   "ATM's")
        # Per-slot cos θ, sin θ and cos(φ/2), so the pair loop needs no trig for its beam tests.
        self._cos_axis = np.zeros(history.storage_size)
        self._sin_axis = np.zeros(history.storage_size)
        self._cos_half = np.zeros(history.storage_size)
        self._use_index = self.min_transversal >= MIN_INDEXED_TRANSVERSAL
        self.index = make_index(history.storage_size)
        self._index = index_arrays(self.index)
        # The older arcs to intersect, and the crossings found and stored with each, to take
        # them back (add_atm_arc); plain, as the kernels take it from Python.
        self._scratch = tuple(PairScratch(
            np.zeros(history.storage_size, dtype=np.int64),
            np.zeros((history.storage_size, 2), dtype=np.int32)))
        # Median and span of each row's bearings, valid where the row is not stale.
        self._median = np.zeros(history.storage_size)
        self._span = np.zeros(history.storage_size)
        self._stale = np.ones(history.storage_size, dtype=bool)
        self._values = np.zeros(0)  # median_state's work array
        self._kept = 0

    @property
    def bearings(self) -> npt.NDArray[np.float32]:
        """The crossing store's bearings (:class:`CrossingStore`); replaced when it grows."""
        return self.store.bearings

    @bearings.setter
    def bearings(self, value: npt.NDArray[np.float32]) -> None:
        self.store.bearings = value

    @property
    def counts(self) -> npt.NDArray[np.int32]:
        """Crossings stored per row (:class:`CrossingStore`)."""
        return self.store.counts

    def on_add_many(self, first: int, count: int) -> None:
        """Reset the crossings of each new arc ``first .. first + count - 1``, then intersect it
        with the older live arcs, in one compiled call."""
        self.check_usable()
        h = self.history
        end = first + count
        while first < end:
            atm, cos_psi, scratch = self.kernel_state()
            kept, first, needed = _add_arcs(
                first, end - first, h.capacity, cos_psi, self._use_index,
                *(history_rows(h) + atm + scratch + self._index))
            self._kept += kept
            if first < end:
                self.make_room(needed)

    def check_usable(self) -> None:
        """Raise the :class:`CrossingStoreError` that stopped the model, if one did."""
        self.store.check_usable()

    def make_room(self, needed: int) -> None:
        """Grow the store to ``needed`` columns (:meth:`CrossingStore.grow`), or stop the
        model for good."""
        self.store.grow(needed)

    @property
    def uses_index(self) -> bool:
        """Whether the spatial index finds each new arc's partners (ψ ≥
        :data:`MIN_INDEXED_TRANSVERSAL`), rather than a scan of every live arc."""
        return self._use_index

    def kernel_state(self) -> tuple[PlainBundle, float, PlainBundle]:
        """What a kernel adding arcs to this model takes (:func:`add_atm_arc`), plain: its
        :class:`~sonarcarve.methods.arrays.AtmArcs` (``cos θ, sin θ, cos(φ/2)`` per slot, the
        crossing store, its counts and the stale marks; the store is replaced when it grows, so
        ask again after :meth:`make_room`), ``cos ψ``, and its
        :class:`~sonarcarve.methods.arrays.PairScratch` (the candidates and their tally)."""
        atm = (self._cos_axis, self._sin_axis, self._cos_half, self.bearings, self.counts,
               self._stale)
        return atm, self._cos_psi, self._scratch

    def count_kept(self, kept: int) -> None:
        """Add crossings kept by a kernel that the method ran for this model."""
        self._kept += kept

    def estimates(self, slots: SlotArray) -> Estimates:
        """ATM's estimates for ``slots`` (refused once the model has stopped:
        :meth:`check_usable`)."""
        self.check_usable()
        h = self.history
        median, span = self.medians(slots)
        has = self.counts[slots] > 0
        beam = h.beam_width[slots]
        return Estimates(
            alive=np.ones(len(slots), dtype=bool),
            processed=has,
            xy=arc_point(h, slots, h.theta[slots] + median),
            width=np.where(has, span, beam),
            max_error=np.where(has, self.error_bound, chord_error(h.r[slots], beam)),
            source=np.where(has, int(PointSource.ATM), int(PointSource.CENTERLINE)).astype(
                np.int8
            ),
        )

    def medians(self, slots: SlotArray) -> tuple[FloatArray, FloatArray]:
        """Median and span (max − min) of the kept bearings of each of ``slots``, radians
        relative to its axis; 0 for a row with none.

        Sorted again only for the rows whose crossings changed since they were last asked for
        (a writable int64 array: one compiled version of :func:`_medians`, whatever the caller
        passes): ``local_map()`` at a history of 10,000 re-sorted every arc's crossings.
        """
        stale = self._stale[slots]
        if stale.any():
            rows = np.array(slots[stale], dtype=np.int64)
            _medians(self.bearings, self.counts, rows, self._median, self._span)
            self._stale[rows] = False
        return self._median[slots], self._span[slots]

    def median_state(self) -> tuple[float, npt.NDArray[np.float32], npt.NDArray[np.int32],
                                    BoolArray, FloatArray, FloatArray, FloatArray]:
        """What a kernel placing ATM's points takes (:func:`row_median`): the error bound, then
        :class:`~sonarcarve.methods.arrays.AtmMedians`' arrays (the crossing store, its counts,
        the stale marks, the cached medians and spans, and a work array as wide as the
        store)."""
        if self._values.shape[0] != self.bearings.shape[1]:
            self._values = np.zeros(self.bearings.shape[1])
        return (self.error_bound, self.bearings, self.counts, self._stale, self._median,
                self._span, self._values)

    def counters(self) -> dict[str, int]:
        """``atm_crossings``: transversal crossings kept since the start (each counted once)."""
        return {"atm_crossings": self._kept}


class AtmMethod(SonarMethod):
    """ATM as a streaming method (section 2-D).

    Parameters
    ----------
    history_size, beam_width
        As for :class:`~sonarcarve.methods.base.SonarMethod`.
    min_transversal : float
        ψ, radians (see :class:`AtmModel`).
    range_resolution : float
        δ, metres (see :func:`atm_error_bound`).
    """

    name = "atm"

    def __init__(
        self,
        history_size: int = DEFAULT_HISTORY_SIZE,
        beam_width: float = DEFAULT_BEAM_WIDTH,
        min_transversal: float = DEFAULT_MIN_TRANSVERSAL,
        range_resolution: float = POLAROID_RANGE_RESOLUTION,
    ) -> None:
        self.config = MethodConfig(history_size=history_size, beam_width=beam_width,
                                   min_transversal=min_transversal,
                                   range_resolution=range_resolution)
        self.min_transversal = self.config.min_transversal
        self.range_resolution = self.config.range_resolution
        super().__init__(history_size, beam_width)

    def _make_models(self) -> tuple[AtmModel]:
        return (AtmModel(self.history, self.min_transversal, self.range_resolution),)
