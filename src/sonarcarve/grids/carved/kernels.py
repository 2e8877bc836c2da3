"""The compiled entry points :class:`~sonarcarve.grids.carved.CarvedGrid` calls.

A batch's final updates in reading order (:func:`fold_kernel`: the final band of each arc that left
the history, then the reading's free space, into ``base``); the live contribution of the arcs
leaving the history taken out (:func:`retire_kernel`); a read's refresh of ``live`` and of the
marks, arc by arc where its interval or value changed (:func:`refresh_kernel`), asking for the
estimates of only the arcs whose carving state changed (:func:`stale_slots`); and the trinary map,
``clamp(base + live)`` against the thresholds' logits (:func:`trinary_kernel`).
``docs/carved-grid.md``, "Following carving over time" and "Reading the map".
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.grids.carved.band import ArcBand, arc_value, draw_arc, redraw, undraw
from sonarcarve.grids.carved.free_space import HELD, Beam, free_space
from sonarcarve.grids.carved.mark import FreshArc, refresh_points
from sonarcarve.grids.carved.model import (
    DRAWN_HI,
    DRAWN_LO,
    DRAWN_VALUE,
    Model,
    model_from,
)
from sonarcarve.grids.carved.periods import note_kernel, row_period
from sonarcarve.grids.occupancy import FREE, OCCUPIED, UNKNOWN, Int8Grid
from sonarcarve.typing import BoolArray, FloatArray, SlotArray

__all__ = [
    "Finals",
    "batch_columns",
    "fold_kernel",
    "fresh_kernel",
    "keep_chain",
    "mark_fresh",
    "note_newest",
    "refresh_kernel",
    "retire_kernel",
    "stale_slots",
    "trinary_kernel",
]


class Finals(NamedTuple):
    """Arcs that left the history in a batch, in order: where to draw their final band."""

    x: FloatArray
    y: FloatArray
    r: FloatArray
    lo: FloatArray
    hi: FloatArray
    weight: FloatArray
    seq: npt.NDArray[np.int64]


@compiled
def batch_columns(beam_width: FloatArray, default_width: float, r: FloatArray,
                  max_range: FloatArray, band: float, first_seq: int
                  ) -> tuple[FloatArray, FloatArray, npt.NDArray[np.int64], BoolArray, int]:
    """What the fold and the bookkeeping take from a batch, in one pass: each reading's half
    beam width (its ``beam_width``, or ``default_width`` where it is NaN, halved), the range
    its free space reaches (``r``; ``max_range + band`` for a reading that heard nothing,
    ``r = inf``), its arc's sequence number from ``first_seq`` (a no-echo reading's: the
    newest arc before it, as it has none), whether it heard nothing, and how many did hear.
    Before 2026-12-05 about 6 µs of numpy for a 5-reading batch (``benchmarks/grid_reads.py``,
    a read every 5 readings). The width rule is
    :meth:`~sonarcarve.readings.ReadingBatch.beam_widths`'s, written again here to stay in one
    compiled pass; ``tests/grids/test_carved_fused_paths.py`` holds the two to the same bits."""
    n = r.shape[0]
    half = np.empty(n)
    reach = np.empty(n)
    seqs = np.empty(n, dtype=np.int64)
    no_echo = np.empty(n, dtype=np.bool_)
    seq = first_seq - 1
    for k in range(n):
        width = beam_width[k]
        half[k] = 0.5 * (default_width if math.isnan(width) else width)
        no_echo[k] = r[k] == math.inf
        if no_echo[k]:
            reach[k] = max_range[k] + band
        else:
            reach[k] = r[k]
            seq += 1
        seqs[k] = seq
    return half, reach, seqs, no_echo, seq + 1 - first_seq


@compiled
def fold_kernel(base: npt.NDArray[np.float32], heard: npt.NDArray[np.uint32], model: FloatArray,
                x: FloatArray, y: FloatArray, theta: FloatArray, r: FloatArray,
                half: FloatArray, seqs: npt.NDArray[np.int64], capacity: int,
                final_x: FloatArray, final_y: FloatArray, final_r: FloatArray,
                final_lo: FloatArray, final_hi: FloatArray, final_weight: FloatArray,
                final_seq: npt.NDArray[np.int64]) -> None:
    """The final updates of a batch in reading order: before the free space of reading ``k``
    (arc sequence number ``seqs[k]``; for a no-echo reading, the newest arc before it), the
    final band of every arc it pushed out of the history (:class:`Finals`, its fields one by
    one: ``final_seq + capacity <= seq``). ``model``:
    :func:`~sonarcarve.grids.carved.model.model_array` (named tuples cost numba's dispatcher
    1-1.5 µs each)."""
    m = model_from(model)
    finals = Finals(final_x, final_y, final_r, final_lo, final_hi, final_weight, final_seq)
    p = 0
    nf = finals.seq.shape[0]
    held = np.empty((HELD if m.through > 0.0 else 0, 7), dtype=np.float64)
    for k in range(x.shape[0]):
        while p < nf and finals.seq[p] + capacity <= seqs[k]:
            _draw_final(base, heard, m, finals, p)
            p += 1
        free_space(base, heard, m, Beam(x[k], y[k], theta[k], r[k], half[k]), held)
    while p < nf:
        _draw_final(base, heard, m, finals, p)
        p += 1


@compiled_inline
def _draw_final(base: npt.NDArray[np.float32], heard: npt.NDArray[np.uint32], m: Model,
                finals: Finals, p: int) -> None:
    """Arc ``p`` of ``finals`` into ``base``, for good."""
    value = arc_value(finals.r[p], finals.lo[p], finals.hi[p], finals.weight[p], m)
    arc = ArcBand(finals.x[p], finals.y[p], finals.r[p], finals.lo[p], finals.hi[p])
    draw_arc(base, True, heard, m, arc, value)


@compiled
def retire_kernel(live: FloatArray, drawn: FloatArray, drawn_seq: npt.NDArray[np.int64],
                  points: npt.NDArray[np.float32], pdrawn: FloatArray,
                  pseq: npt.NDArray[np.int64], slots: SlotArray, seqs: npt.NDArray[np.int64],
                  heard: npt.NDArray[np.uint32], model: FloatArray) -> None:
    """Take the drawn contribution of the arcs ``seqs`` (in ``slots``) leaving the history out
    of ``live`` and then out of ``points`` (one call: two cost 2 µs more a batch; ``drawn,
    drawn_seq`` and ``pdrawn, pseq``: the two :class:`~sonarcarve.grids.carved.model.SlotRecord`
    bundles, field by field as the grid passes them)."""
    m = model_from(model)
    _retire(live, drawn, drawn_seq, slots, seqs, heard, m)
    _retire(points, pdrawn, pseq, slots, seqs, heard, m)


@compiled_inline
def _retire(grid: npt.NDArray[np.floating], drawn: FloatArray,
            drawn_seq: npt.NDArray[np.int64], slots: SlotArray, seqs: npt.NDArray[np.int64],
            heard: npt.NDArray[np.uint32], m: Model) -> None:
    """Take what the arcs ``seqs`` (in ``slots``) drew into ``grid`` (``drawn, drawn_seq``)
    out, if they drew it."""
    for k in range(slots.shape[0]):
        slot = slots[k]
        if drawn_seq[slot] == seqs[k]:
            undraw(grid, heard, m, drawn, slot)
            drawn_seq[slot] = -1


@compiled
def keep_chain(chain: FloatArray, batch_chain: FloatArray, first: int, first_live: int,
               storage: int) -> None:
    """The factors ``batch_chain`` of a batch's arcs ``first, first + 1, ...`` that are still
    live (sequence number ``>= first_live``) into their slots of ``chain``."""
    for k in range(max(0, first_live - first), batch_chain.shape[0]):
        chain[(first + k) % storage] = batch_chain[k]


@compiled
def refresh_kernel(base: npt.NDArray[np.float32], live: FloatArray,
                   points: npt.NDArray[np.float32], heard: npt.NDArray[np.uint32],
                   drawn: FloatArray, drawn_seq: npt.NDArray[np.int64], pdrawn: FloatArray,
                   pseq: npt.NDArray[np.int64], x: FloatArray, y: FloatArray, r: FloatArray,
                   theta1: FloatArray, theta2: FloatArray, t: FloatArray, lo: FloatArray,
                   hi: FloatArray, weight: FloatArray, slots: SlotArray,
                   seqs: npt.NDArray[np.int64], model: FloatArray, with_points: bool,
                   newest: npt.NDArray[np.int64], latest: float, seconds: float,
                   periods: float, gaps: FloatArray, count: npt.NDArray[np.int64],
                   refit: BoolArray, period: FloatArray) -> int:
    """Bring ``live`` (and, ``with_points``, ``points``) up to date with the live arcs ``slots``
    (arcs ``seqs``): first every arc whose interval or value changed is redrawn into ``live``
    (:func:`_redraw_changed`), then the points are judged on the whole updated spread map
    (:func:`_refresh_marks`), each sensor's newest arc as fresh as :func:`mark_fresh` says.
    Returns how many arcs and points changed.

    The arrays, in groups: the grid's cells ``base, live, points, heard``; what each slot drew
    into ``live`` (``drawn, drawn_seq``) and into ``points`` (``pdrawn, pseq``), each a
    :class:`~sonarcarve.grids.carved.model.SlotRecord`; the history's rows ``x, y, r`` (origin
    and range), ``theta1, theta2`` (the beam, eq. 2.1) and ``t``; each live arc's band at the
    last read ``lo, hi, weight`` (:func:`~sonarcarve.grids.carved.intervals.intervals`); all
    but the cells by slot. ``model``: :func:`~sonarcarve.grids.carved.model.model_array`;
    ``newest .. period``: :func:`mark_fresh`'s arguments after ``first``, which is ``seqs[0]``.

    Why separate arrays and not named bundles of them: the grid calls this once a read from
    Python (a NamedTuple costs numba's dispatcher microseconds a call, ``model.py``), and inside
    this kernel, which counts references (it allocates), a bundle of arrays costs an atomic
    increment and decrement per array each time it is built or passed to a step (2026-12-05,
    this kernel on an unchanged office map at 0.10 m, arguments captured from
    ``benchmarks/grid_reads.py``'s stream: 7.6 µs a read with separate arrays, 8.2 with the
    cells, slot records, rows and intervals as bundles). Bundles of numbers
    (:class:`~sonarcarve.grids.carved.band.ArcBand`,
    :class:`~sonarcarve.grids.carved.mark.FreshArc`) cost nothing. One call a read: the fresh
    arcs worked out in their own kernel cost a dispatch and an array more."""
    m = model_from(model)
    changed = _redraw_changed(live, heard, drawn, drawn_seq, x, y, r, lo, hi, weight, slots,
                              seqs, m)
    if with_points:
        fresh = np.zeros(slots.shape[0], dtype=np.bool_)
        if slots.shape[0]:
            mark_fresh(newest, seqs[0], slots, t, latest, seconds, periods, gaps, count, refit,
                       period, fresh)
        changed += _refresh_marks(base, live, points, heard, drawn, drawn_seq, pdrawn, pseq,
                                  x, y, r, theta1, theta2, lo, hi, weight, slots, seqs, fresh,
                                  m)
    return changed


@compiled_inline
def _redraw_changed(live: FloatArray, heard: npt.NDArray[np.uint32], drawn: FloatArray,
                    drawn_seq: npt.NDArray[np.int64], x: FloatArray, y: FloatArray,
                    r: FloatArray, lo: FloatArray, hi: FloatArray, weight: FloatArray,
                    slots: SlotArray, seqs: npt.NDArray[np.int64], m: Model) -> int:
    """Redraw into ``live`` each live arc whose interval or value changed since it was drawn
    (:func:`~sonarcarve.grids.carved.band.redraw`); returns how many."""
    changed = 0
    for k in range(slots.shape[0]):
        s = slots[k]
        value = arc_value(r[s], lo[s], hi[s], weight[s], m)
        # redraw's own test first, written out: most arcs did not change, and the call costs
        # more.
        if (drawn_seq[s] == seqs[k] and drawn[s, DRAWN_LO] == lo[s]
                and drawn[s, DRAWN_HI] == hi[s] and drawn[s, DRAWN_VALUE] == value):
            continue
        arc = ArcBand(x[s], y[s], r[s], lo[s], hi[s])
        changed += redraw(live, drawn, drawn_seq, s, seqs[k], arc, value, heard, m)
    return changed


@compiled_inline
def _refresh_marks(base: npt.NDArray[np.float32], live: FloatArray,
                   points: npt.NDArray[np.float32], heard: npt.NDArray[np.uint32],
                   drawn: FloatArray, drawn_seq: npt.NDArray[np.int64], pdrawn: FloatArray,
                   pseq: npt.NDArray[np.int64], x: FloatArray, y: FloatArray, r: FloatArray,
                   theta1: FloatArray, theta2: FloatArray, lo: FloatArray, hi: FloatArray,
                   weight: FloatArray, slots: SlotArray, seqs: npt.NDArray[np.int64],
                   fresh: BoolArray, m: Model) -> int:
    """Mark each ``fresh`` arc the spread map does not explain, and take the marks of the
    others out (:func:`~sonarcarve.grids.carved.mark.refresh_points`); returns how many
    changed."""
    changed = 0
    for k in range(slots.shape[0]):
        s = slots[k]
        if not fresh[k] and pseq[s] < 0:  # no point, and none to draw
            continue
        arc = FreshArc(s, seqs[k], ArcBand(x[s], y[s], r[s], lo[s], hi[s]), weight[s],
                       theta1[s], theta2[s], fresh[k])
        changed += refresh_points(base, live, points, heard, drawn, drawn_seq, pdrawn, pseq,
                                  arc, m)
    return changed


@compiled
def stale_slots(slots: SlotArray, seqs: npt.NDArray[np.int64], lo: FloatArray,
                hi: FloatArray, status: npt.NDArray[np.int8],
                crossings: npt.NDArray[np.int32], seen: FloatArray,
                seen_crossings: npt.NDArray[np.int32], seen_seq: npt.NDArray[np.int64],
                out: SlotArray) -> int:
    """Positions ``k`` (into ``out``, returns how many) of the live arcs whose state differs
    from ``seen`` (``seen_seq``: the arc it was recorded for), recording the new state: the
    carving state ``lo, hi, status`` of :class:`~sonarcarve.methods.carving.CarvingModel` and,
    for combined carving, the number of ATM crossings the arc keeps (``crossings``, all zero
    for carving alone; indexed by slot). An arc whose state is as seen has the same estimate
    (ATM's point is the median of the arc's kept crossings, which only grow), so its interval
    need not be asked for again."""
    count = 0
    for k in range(slots.shape[0]):
        s = slots[k]
        if (seen_seq[s] != seqs[k] or seen[s, 0] != lo[s] or seen[s, 1] != hi[s]
                or seen[s, 2] != status[s] or seen_crossings[s] != crossings[s]):
            seen_seq[s] = seqs[k]
            seen[s, 0] = lo[s]
            seen[s, 1] = hi[s]
            seen[s, 2] = status[s]
            seen_crossings[s] = crossings[s]
            out[count] = k
            count += 1
    return count


@compiled
def trinary_kernel(base: npt.NDArray[np.float32], live: FloatArray,
                   points: npt.NDArray[np.float32], l_min: float, l_max: float,
                   l_occupied: float, l_free: float, out: Int8Grid) -> None:
    """Occupied (100) where ``clamp(base + (live + points)) > l_occupied``, free (0) below
    ``l_free``, else unknown (-1)."""
    ny, nx = base.shape
    for i in range(ny):
        for j in range(nx):
            lo = min(l_max, max(l_min, base[i, j] + (live[i, j] + points[i, j])))
            if lo > l_occupied:
                out[i, j] = OCCUPIED
            elif lo < l_free:
                out[i, j] = FREE
            else:
                out[i, j] = UNKNOWN


@compiled
def note_newest(newest: npt.NDArray[np.int64], rows: npt.NDArray[np.int64],
                seqs: npt.NDArray[np.int64], no_echo: BoolArray, t: FloatArray,
                with_times: bool, last: FloatArray, gaps: FloatArray,
                count: npt.NDArray[np.int64], refit: BoolArray) -> None:
    """Each sensor's newest reading, in order (the last of a sensor's readings wins):
    ``newest[rows[k]]`` the arc ``seqs[k]``, or -1 when reading ``k`` heard nothing (its arc is
    then no sensor's newest); and, ``with_times``, the readings' times ``t`` noted in the rows'
    firing periods (:func:`~sonarcarve.grids.carved.periods.note_kernel`, ``last .. refit``)."""
    for k in range(rows.shape[0]):
        newest[rows[k]] = -1 if no_echo[k] else seqs[k]
    if with_times:
        note_kernel(rows, t, last, gaps, count, refit)


@compiled
def fresh_kernel(newest: npt.NDArray[np.int64], first: int, slots: SlotArray, t: FloatArray,
                 latest: float, seconds: float, periods: float, gaps: FloatArray,
                 count: npt.NDArray[np.int64], refit: BoolArray, period: FloatArray,
                 fresh: BoolArray) -> None:
    """:func:`mark_fresh` on its own (the grid's reads run it inside :func:`refresh_kernel`)."""
    mark_fresh(newest, first, slots, t, latest, seconds, periods, gaps, count, refit, period,
               fresh)


@compiled_inline
def mark_fresh(newest: npt.NDArray[np.int64], first: int, slots: SlotArray, t: FloatArray,
               latest: float, seconds: float, periods: float, gaps: FloatArray,
               count: npt.NDArray[np.int64], refit: BoolArray, period: FloatArray,
               fresh: BoolArray) -> None:
    """``fresh[k]`` for the live arc ``first + k`` (in ``slots[k]``; ``t`` the history's times)
    that is its sensor's newest (``newest``, by sensor row) and was heard at or after ``latest -
    seconds`` and, when ``periods`` is finite, after ``latest - periods * p``, ``p`` its
    sensor's firing period (:func:`~sonarcarve.grids.carved.periods.row_period`, by the same
    row: ``gaps .. period``)."""
    n = slots.shape[0]
    for row in range(newest.shape[0]):
        at = newest[row] - first
        if at < 0 or at >= n:
            continue
        heard = t[slots[at]]
        young = heard >= latest - seconds
        if young and periods < math.inf:
            young = heard > latest - periods * row_period(row, gaps, count, refit, period)
        if young:
            fresh[at] = True
