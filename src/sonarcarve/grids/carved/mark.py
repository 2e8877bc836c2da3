"""The newest echo's mark: a whole hit ``c · logit(p_hit)`` for each sensor's newest arc that the
map does not explain (:func:`refresh_points`).

Explained: a cell of the arc's band, or for a near echo of a side lobe past its beam's edges, is
occupied in the map of spread arcs without the arc's own share (:func:`_band_likeliest`); a lobe
cell counts only if it was heard from near the bearing of the ray to it (:func:`_heard_near`).
The mark covers the middle ``mark_length`` of the carved interval (by default 0: the point's
own cell; ``L``, ``spread_length``, when None, the rule before 2026-12-04), unless that map
favours another part of the band, or a side lobe, and not the middle: then it goes around the
likeliest cell there. ``docs/carved-grid.md``, "The newest echoes mark at once", "Where the mark
goes", "The mark's length" and "Side lobes".
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.grids.carved.band import (
    ArcBand,
    arc_value,
    band_ring,
    box_cells,
    clamped,
    drawn_interval,
    redraw,
    undraw,
)
from sonarcarve.grids.carved.heard import HEARD_BINS, HEARD_NEAR, audibility, heard_bin
from sonarcarve.grids.carved.model import (
    DRAWN_HI,
    DRAWN_LO,
    DRAWN_R,
    DRAWN_VALUE,
    DRAWN_X,
    DRAWN_Y,
    Model,
    SlotRecord,
)
from sonarcarve.grids.scan import TWO_PI, bearing_off, cos_bound, ring_columns, within
from sonarcarve.typing import FloatArray

__all__ = ["FreshArc", "refresh_points"]

#: Log-odds above which a cell counts as more likely occupied than not where a fresh arc's
#: point is placed (:func:`_band_likeliest`): 0, up to the rounding of ``live``'s sums of
#: additions and removals (about 1e-15) and of float32 ``base``.
_LIKELY = 1e-6
#: Log-odds within which two cells are equally likely where a fresh arc's point is placed: far
#: above ``live``'s rounding (1e-15), which depends on when the map was read. Cells covered by
#: the same arcs are equal up to that rounding; a strict ``>`` let the rounding, and the scan
#: order, pick among them (review rev10: the mark moved with the read schedule and with the
#: grid's orientation), so equals go to the cell nearest the middle.
_TIE = 1e-9


class Likeliest(NamedTuple):
    """The likeliest cell found so far on a stretch of the circle (the band, or one side
    lobe): its log-odds, at least :data:`_LIKELY`, and its bearing, radians."""

    value: float
    at: float


class LobeReach(NamedTuple):
    """Where a near echo may have come from through a side lobe
    (:attr:`~sonarcarve.grids.carved.CarvedGridParams.side_lobes`): bearings within ``reach``
    of the beam's axis and not within ``beam`` of it, both widened by half a cell at the
    circle as every band is (:func:`~sonarcarve.grids.carved.band.drawn_interval`)."""

    axis: float  # the beam's axis, written near the carved interval's middle
    reach: float  # (1 + lobes) half beam widths + the widening; 0.0: no lobes for this echo
    beam: float  # half the beam's width + the widening
    cos_axis: float
    sin_axis: float
    cos_reach: float  # cos_bound(reach)
    cos_beam: float  # cos_bound(beam)


class FreshArc(NamedTuple):
    """One live arc as :func:`refresh_points` judges its mark: numbers only (a bundle of
    numbers costs nothing; one of arrays counts a reference per array at every step,
    :func:`~sonarcarve.grids.carved.kernels.refresh_kernel`)."""

    slot: int  # its history slot
    seq: int  # its sequence number
    band: ArcBand  # where its band lies: origin, range, carved interval
    weight: float  # its band's weight (0: none)
    theta1: float  # its beam's edges θ ∓ φ/2, radians (eq. 2.1)
    theta2: float
    fresh: bool  # its sensor's newest reading (kernels.mark_fresh)


@compiled_inline
def refresh_points(base: npt.NDArray[np.float32], live: FloatArray,
                   points: npt.NDArray[np.float32], heard: npt.NDArray[np.uint32],
                   drawn: FloatArray, drawn_seq: npt.NDArray[np.int64], pdrawn: FloatArray,
                   pseq: npt.NDArray[np.int64], arc: FreshArc, m: Model) -> int:
    """Draw ``arc`` into ``points`` as carving's point estimate if it is ``fresh`` (its
    sensor's newest reading) and the map of spread arcs (``base + live``, without the arc's
    own spread value) does not explain it (:func:`_band_likeliest`): the mark's length
    ``m.mark`` of its carved interval around the point's bearing (the middle, eq. 3.6, or the
    most likely cell of a band whose middle the map does not favour; clipped to the interval)
    raised from its spread value to a whole hit, or, where the likeliest cell lies in reach of
    a side lobe, a whole hit around it clipped to the lobe's stretch of the circle
    (:func:`_lobe_mark`); else take its point out. ``drawn, drawn_seq`` and ``pdrawn, pseq``:
    what each slot drew into ``live`` and into ``points``
    (:class:`~sonarcarve.grids.carved.model.SlotRecord`). The spread map does not hold the
    points, so the fresh arcs' order does not matter. Returns 1 if its point changed."""
    slot = arc.slot
    if arc.fresh and arc.weight > 0.0:
        x, y, r, lo, hi = arc.band
        own = drawn[slot, DRAWN_VALUE]
        explained, at, side = _band_likeliest(base, live, heard, SlotRecord(drawn, drawn_seq),
                                              slot, m, arc.band, own, arc.theta1, arc.theta2)
        if not explained:
            whole = arc_value(r, lo, hi, arc.weight, m, True)
            if side != 0.0:
                z1, z2 = _lobe_mark(m, r, at, side, arc.theta1, arc.theta2)
                return redraw(points, pdrawn, pseq, slot, arc.seq, ArcBand(x, y, r, z1, z2),
                              whole, heard, m)
            half = min(0.5 * (hi - lo), 0.5 * m.mark / r)
            mark = ArcBand(x, y, r, max(lo, at - half), min(hi, at + half))
            return redraw(points, pdrawn, pseq, slot, arc.seq, mark, whole - own, heard, m)
    if pseq[slot] >= 0:
        undraw(points, heard, m, pdrawn, slot)
        pseq[slot] = -1
        return 1
    return 0


@compiled_inline
def _lobe_mark(m: Model, r: float, at: float, side: float, theta1: float,
               theta2: float) -> tuple[float, float]:
    """The interval of a mark in a side lobe (``side``: +1 counter-clockwise of the beam's
    axis, -1 clockwise): ``m.mark`` long around the likeliest cell's bearing ``at``, clipped to
    the lobe's stretch of the circle beyond the arc's own band (which draws no spread value
    there to raise)."""
    half = 0.5 * m.mark / r
    axis = 0.5 * (theta1 + theta2)
    axis += TWO_PI * math.floor((at - axis + math.pi) / TWO_PI)
    edge = 0.5 * (theta2 - theta1)
    reach = (1.0 + m.lobes) * edge
    # Drawn widened by half a cell, as every arc: start a cell past the beam's edge so the
    # mark never adds to the arc's own band (that would be more than a whole hit).
    inner = edge + m.h / r
    z1, z2 = (axis + inner, axis + reach) if side > 0.0 else (axis - reach, axis - inner)
    return max(z1, at - half), min(z2, at + half)


@compiled_inline
def _lobe_reach(m: Model, r: float, mid: float, theta1: float, theta2: float) -> LobeReach:
    """The side lobes' reach of an echo at range ``r`` whose beam is ``[theta1, theta2]``,
    its axis written near ``mid`` (the carved interval's middle); ``reach`` 0.0 unless side
    lobes are on and the echo is near (``r <= lobe_range``)."""
    widen = 0.5 * m.h / r
    axis = 0.5 * (theta1 + theta2)
    axis += TWO_PI * math.floor((mid - axis + math.pi) / TWO_PI)
    reach = 0.0
    if m.lobes > 0.0 and r <= m.lobe_range:
        reach = 0.5 * (1.0 + m.lobes) * (theta2 - theta1) + widen
    beam = 0.5 * (theta2 - theta1) + widen
    return LobeReach(axis, reach, beam, math.cos(axis), math.sin(axis), cos_bound(reach),
                     cos_bound(beam))


@compiled_inline
def _in_lobe(dx: float, dy: float, d: float, lobes: LobeReach) -> bool:
    """Whether the cell at ``(dx, dy)`` (distance ``d``) from the arc's origin lies in reach
    of a side lobe and outside the beam."""
    return (lobes.reach > 0.0
            and within(dx, dy, d, lobes.axis, lobes.reach, lobes.cos_axis, lobes.sin_axis,
                       lobes.cos_reach)
            and not within(dx, dy, d, lobes.axis, lobes.beam, lobes.cos_axis, lobes.sin_axis,
                           lobes.cos_beam))


@compiled  # its own function: inlined, the refresh loop ran 4x slower (numba 0.68)
def _band_likeliest(base: npt.NDArray[np.float32], live: FloatArray,
                    heard: npt.NDArray[np.uint32], record: SlotRecord, slot: int, m: Model,
                    arc: ArcBand, own: float, theta1: float,
                    theta2: float) -> tuple[bool, float, float]:
    """``(explained, bearing, side)`` of a fresh arc: whether a cell of its band (as
    :func:`~sonarcarve.grids.carved.band.draw_arc` draws it, without a profile) is occupied in the
    map of spread arcs without the arc's own share ``own``,
    ``clamp(base + live - own) > l_occupied``, and the bearing its point goes to: the middle of
    ``[lo, hi]`` (eq. 3.6), unless that map holds no cell more likely occupied than not (above
    :data:`_LIKELY`) where the middle ``mark`` is drawn and does hold one elsewhere on the band:
    then the bearing of the band's most likely cell (of equals within :data:`_TIE`, the one nearest
    the middle). Near echoes (``r <= lobe_range``) also look past the beam's edges
    ``[theta1, theta2]``, ``lobes`` half widths, on the same circle (:func:`_lobe_reach`): an
    occupied cell there explains the echo; when the middle is not favoured and a lobe's likeliest
    cell beats the band's, ``bearing`` is that cell's and ``side`` its lobe (+1 counter-clockwise
    of the axis, -1 clockwise; 0: on the band; :func:`_verdict`). A lobe cell counts only if it
    was heard from near the bearing of this sensor's ray to it (:func:`_heard_near`, the arc's own
    ``slot`` aside; ``heard`` and ``record``: the record of final bands and the live arcs)."""
    x, y, r = arc.x, arc.y, arc.r
    xmin, ymin, h, band = m.xmin, m.ymin, m.h, m.band
    nx = base.shape[1]
    iv = drawn_interval(m, r, arc.lo, arc.hi)
    mid = iv.mid
    # Where the point would be drawn: the middle mark, widened as draw_arc widens it.
    reach = min(0.5 * (arc.hi - arc.lo), 0.5 * m.mark / r) + 0.5 * h / r
    r_in, r_out = band_ring(m, r)
    lobes = _lobe_reach(m, r, mid, theta1, theta2)
    s1, s2 = ((min(iv.t1, lobes.axis - lobes.reach), max(iv.t2, lobes.axis + lobes.reach))
              if lobes.reach > 0.0 else (iv.t1, iv.t2))
    i0, i1, j0, j1 = box_cells(m, base.shape, x, y, s1, s2, r_in, r_out)
    # The likeliest cells so far (none yet in a lobe: farther than any bearing). Scalars, not
    # arrays: this runs for every fresh arc at every read.
    on_band = Likeliest(_LIKELY, 0.5 * (arc.lo + arc.hi))  # the middle, unless a likelier cell
    middle_likely = False
    cw = ccw = Likeliest(_LIKELY, mid + 4.0 * math.pi)
    for i in range(i0, i1 + 1):
        dy = ymin + (i + 0.5) * h - y
        a0, a1, b0, b1 = ring_columns(dy, r_in, r_out, x, xmin, h, nx, j0, j1)
        for part in range(2):
            for j in range(a0 if part == 0 else b0, (a1 if part == 0 else b1) + 1):
                # The cell's value first: most cells are not likely occupied, and need no
                # geometry. On the band it holds the arc's own share, which does not count;
                # in a side lobe's reach it does not hold it.
                spread = base[i, j] + live[i, j]
                value = clamped(m, spread - own)
                if not (value > _LIKELY or (lobes.reach > 0.0 and spread > _LIKELY)):
                    continue
                dx = xmin + (j + 0.5) * h - x
                d = math.sqrt(dx * dx + dy * dy)
                if abs(d - r) > band:
                    continue
                if not within(dx, dy, d, mid, iv.half, iv.cos_mid, iv.sin_mid, iv.cos_half):
                    # Outside the carved interval, in reach of a side lobe: the echo may have
                    # come from a surface there, heard through the lobe.
                    if not _in_lobe(dx, dy, d, lobes):
                        continue
                    is_ccw = bearing_off(dx, dy, lobes.axis) > 0.0
                    value = clamped(m, spread)
                    off = bearing_off(dx, dy, mid)
                    occupied = value > m.l_occupied
                    likelier = _likelier(value, off, ccw if is_ccw else cw, mid)
                    # Only a surface heard from near this ray's bearing could have echoed back
                    # along it (the check is costly, so only for cells that count).
                    if not (occupied or likelier) or not _heard_near(
                            heard, record, slot, m, i, j, x + dx, y + dy, heard_bin(mid + off)):
                        continue
                    if occupied:
                        return True, on_band.at, 0.0
                    if is_ccw:
                        ccw = Likeliest(max(ccw.value, value), mid + off)
                    else:
                        cw = Likeliest(max(cw.value, value), mid + off)
                    continue
                if not value > _LIKELY:
                    continue
                if value > m.l_occupied:
                    return True, on_band.at, 0.0
                off = bearing_off(dx, dy, mid)
                if abs(off) <= reach:
                    middle_likely = True
                if _likelier(value, off, on_band, mid):
                    on_band = Likeliest(max(on_band.value, value), mid + off)
    return _verdict(on_band, middle_likely, cw, ccw, 0.5 * (arc.lo + arc.hi))


@compiled_inline
def _verdict(on_band: Likeliest, middle_likely: bool, cw: Likeliest, ccw: Likeliest,
             middle: float) -> tuple[bool, float, float]:
    """:func:`_band_likeliest`'s answer once no cell was occupied: the point's bearing and
    side. A lobe's likeliest cell wins only where the middle is not favoured and it beats the
    band's by more than :data:`_TIE`."""
    if not middle_likely and max(cw.value, ccw.value) > on_band.value + _TIE:
        if abs(cw.value - ccw.value) <= _TIE:
            # Equally likely surfaces in both lobes: either may have answered, and picking one
            # would let rounding and the scan order draw a lopsided map of a symmetric scene.
            return True, on_band.at, 0.0
        return (False, ccw.at, 1.0) if ccw.value > cw.value else (False, cw.at, -1.0)
    return False, middle if middle_likely else on_band.at, 0.0


@compiled_inline
def _likelier(value: float, off: float, best: Likeliest, mid: float) -> bool:
    """Whether a cell of log-odds ``value``, ``off`` radians from the arc's middle ``mid``,
    beats the likeliest so far ``best``: likelier by more than :data:`_TIE`, or as likely
    within it and nearer the middle."""
    return (value > best.value + _TIE
            or (value >= best.value - _TIE and abs(off) < abs(best.at - mid)))


@compiled_inline
def _heard_near(heard: npt.NDArray[np.uint32], record: SlotRecord, own: int, m: Model, i: int,
                j: int, cx: float, cy: float, k: int) -> bool:
    """Whether cell ``(i, j)`` (centre ``cx, cy``) was heard from within :data:`HEARD_NEAR`
    bins of bin ``k``, the bearing of a ray from a sensor to it: recorded in ``heard`` by a final
    band (audibility 1), or on the band of a live arc other than slot ``own`` (drawn in ``live``
    with a value above 0: ``record``), its bearing from that arc's origin binned as a final band
    records it. A wall heard only across the ray (a corridor's side walls, heard by side sensors)
    would not echo back along it; a cell with no record explains nothing.
    ``docs/carved-grid.md``, "Side lobes"."""
    if audibility(heard[i, j], k) == 1.0:
        return True
    drawn, drawn_seq = record
    band, h = m.band, m.h
    for s in range(drawn_seq.shape[0]):
        if s == own or drawn_seq[s] < 0 or not drawn[s, DRAWN_VALUE] > 0.0:
            continue
        dx = cx - drawn[s, DRAWN_X]
        dy = cy - drawn[s, DRAWN_Y]
        r = drawn[s, DRAWN_R]
        if abs(math.sqrt(dx * dx + dy * dy) - r) > band:
            continue
        # The band as draw_arc draws it: the interval widened by half a cell.
        widen = 0.5 * h / r
        t1, t2 = drawn[s, DRAWN_LO] - widen, drawn[s, DRAWN_HI] + widen
        mid = 0.5 * (t1 + t2)
        off = bearing_off(dx, dy, mid)
        if abs(off) > 0.5 * (t2 - t1):
            continue
        apart = (heard_bin(mid + off) - k) % HEARD_BINS
        if min(apart, HEARD_BINS - apart) <= HEARD_NEAR:
            return True
    return False
