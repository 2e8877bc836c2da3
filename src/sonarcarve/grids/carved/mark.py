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

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.grids.carved.band import arc_value, redraw, undraw
from sonarcarve.grids.carved.heard import HEARD_BINS, HEARD_NEAR, audibility, heard_bin
from sonarcarve.grids.carved.model import Model
from sonarcarve.grids.scan import (
    TWO_PI,
    bearing_off,
    cell_range,
    cos_bound,
    ring_columns,
    sector_box,
    within,
)
from sonarcarve.typing import FloatArray

__all__ = ["refresh_points"]

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


@compiled_inline
def refresh_points(base: npt.NDArray[np.float32], live: FloatArray,
                   points: npt.NDArray[np.float32], drawn: FloatArray,
                   drawn_seq: npt.NDArray[np.int64], pdrawn: FloatArray,
                   pseq: npt.NDArray[np.int64], slot: int, seq: int, x: FloatArray,
                   y: FloatArray, r: FloatArray, lo: FloatArray, hi: FloatArray,
                   weight: FloatArray, fresh: bool, heard: npt.NDArray[np.uint32],
                   m: Model, theta1: float, theta2: float) -> int:
    """Draw the arc in ``slot`` into ``points`` as carving's point estimate if it is
    ``fresh`` (its sensor's newest reading) and the map of spread arcs (``base + live``,
    without the arc's own spread value) does not explain it (:func:`_band_likeliest`): the
    mark's length ``m.mark`` of its carved interval around the point's bearing (the middle, or
    the most likely cell of a band whose middle the map does not favour; clipped to the
    interval) raised from
    its spread value to a whole hit, or, where the likeliest cell lies in reach of a side lobe
    (``theta1, theta2``: the beam), a whole hit around it clipped to the lobe's stretch of the
    circle; else take its point out. The spread map does not hold the
    points, so the fresh arcs' order does not matter. Returns 1 if its point changed."""
    if fresh and weight[slot] > 0.0:
        explained, at, side = _band_likeliest(base, live, heard, drawn, drawn_seq, slot, m,
                                              x[slot], y[slot], r[slot], lo[slot], hi[slot],
                                              drawn[slot, 5], theta1, theta2)
        whole = arc_value(r[slot], lo[slot], hi[slot], weight[slot], m, True)
        if not explained and side != 0.0:
            # In a side lobe: a whole hit around ``at``, clipped to the lobe's stretch of the
            # circle beyond the arc's own band (it draws no spread value there to raise).
            half = 0.5 * m.mark / r[slot]
            axis = 0.5 * (theta1 + theta2)
            axis += TWO_PI * math.floor((at - axis + math.pi) / TWO_PI)
            edge = 0.5 * (theta2 - theta1)
            reach = (1.0 + m.lobes) * edge
            # Drawn widened by half a cell, as every arc: start a cell past the beam's edge so
            # the mark never adds to the arc's own band (that would be more than a whole hit).
            inner = edge + m.h / r[slot]
            z1, z2 = (axis + inner, axis + reach) if side > 0.0 else (axis - reach, axis - inner)
            return redraw(points, pdrawn, pseq, slot, seq, x[slot], y[slot], r[slot],
                          max(z1, at - half), min(z2, at + half), whole, heard, m)
        if not explained:
            half = min(0.5 * (hi[slot] - lo[slot]), 0.5 * m.mark / r[slot])
            return redraw(points, pdrawn, pseq, slot, seq, x[slot], y[slot], r[slot],
                          max(lo[slot], at - half), min(hi[slot], at + half),
                          whole - drawn[slot, 5], heard, m)
    if pseq[slot] >= 0:
        undraw(points, heard, m, pdrawn, slot)
        pseq[slot] = -1
        return 1
    return 0


@compiled  # its own function: inlined, the refresh loop ran 4x slower (numba 0.68)
def _band_likeliest(base: npt.NDArray[np.float32], live: FloatArray,
                    heard: npt.NDArray[np.uint32], drawn: FloatArray,
                    drawn_seq: npt.NDArray[np.int64], slot: int, m: Model, x: float,
                    y: float, r: float, lo: float, hi: float, own: float, theta1: float,
                    theta2: float) -> tuple[bool, float, float]:
    """``(explained, bearing, side)`` of a fresh arc: whether a cell of its band (as
    :func:`~sonarcarve.grids.carved.band.draw_arc` draws it, without a profile) is occupied in the
    map of spread arcs without the arc's own share ``own``,
    ``clamp(base + live - own) > l_occupied``, and the bearing its point goes to: the middle of
    ``[lo, hi]``, unless that map holds no cell more likely occupied than not (above
    :data:`_LIKELY`) where the middle ``mark`` is drawn and does hold one elsewhere on the band:
    then the bearing of the band's most likely cell (of equals within :data:`_TIE`, the one nearest
    the middle). Near echoes (``r <= lobe_range``) also look past the beam's edges, ``lobes`` half
    widths, on the same circle: an occupied cell there explains the echo; when the middle is not
    favoured and a lobe's likeliest cell beats the band's, ``bearing`` is that cell's and ``side``
    its lobe (+1 counter-clockwise of the axis, -1 clockwise; 0: on the band). A lobe cell counts
    only if it was heard from near the bearing of this sensor's ray to it (:func:`_heard_near`,
    the arc's own ``slot`` aside; ``heard``, ``drawn``, ``drawn_seq``: the record of final bands and
    the live arcs); equally likely cells in both lobes explain the echo (no side is favoured)."""
    xmin, ymin, h, band = m.xmin, m.ymin, m.h, m.band
    ny, nx = base.shape
    widen = 0.5 * h / r
    t1 = lo - widen
    t2 = hi + widen
    mid = 0.5 * (t1 + t2)
    half = 0.5 * (t2 - t1)
    # Where the point would be drawn: the middle mark, widened as draw_arc widens it.
    reach = min(0.5 * (hi - lo), 0.5 * m.mark / r) + widen
    r_in, r_out = max(0.0, r - band), r + band
    # The side lobes' reach (CarvedGridParams.side_lobes): the beam [theta1, theta2], written
    # near the carved interval's middle, widened by ``lobes`` half widths past each edge.
    axis = 0.5 * (theta1 + theta2)
    axis += TWO_PI * math.floor((mid - axis + math.pi) / TWO_PI)
    e_half = 0.0
    if m.lobes > 0.0 and r <= m.lobe_range:
        e_half = 0.5 * (1.0 + m.lobes) * (theta2 - theta1) + widen
    s1, s2 = (min(t1, axis - e_half), max(t2, axis + e_half)) if e_half > 0.0 else (t1, t2)
    xlo, ylo, xhi, yhi = sector_box(x, y, s1, s2, r_in, r_out)
    j0, j1 = cell_range(xlo, xhi, xmin, h, nx)
    i0, i1 = cell_range(ylo, yhi, ymin, h, ny)
    cos_mid, sin_mid, cos_half = math.cos(mid), math.sin(mid), cos_bound(half)
    cos_ax, sin_ax, cos_e = math.cos(axis), math.sin(axis), cos_bound(e_half)
    b_half = 0.5 * (theta2 - theta1) + widen
    cos_b = cos_bound(b_half)
    best = _LIKELY
    bearing = 0.5 * (lo + hi)  # the middle, unless a likelier cell is found
    middle_likely = False
    # Per lobe (cw: clockwise of the axis, ccw: counter-clockwise): the likeliest cell and its
    # bearing (none yet: farther than any bearing). Scalars, not arrays: this runs for every
    # fresh arc at every read.
    best_cw, best_ccw = _LIKELY, _LIKELY
    at_cw = at_ccw = mid + 4.0 * math.pi
    for i in range(i0, i1 + 1):
        dy = ymin + (i + 0.5) * h - y
        a0, a1, b0, b1 = ring_columns(dy, r_in, r_out, x, xmin, h, nx, j0, j1)
        for part in range(2):
            for j in range(a0 if part == 0 else b0, (a1 if part == 0 else b1) + 1):
                # The cell's value first: most cells are not likely occupied, and need no
                # geometry. On the band it holds the arc's own share, which does not count;
                # in a side lobe's reach it does not hold it.
                spread = base[i, j] + live[i, j]
                value = min(m.l_max, max(m.l_min, spread - own))
                if not (value > _LIKELY or (e_half > 0.0 and spread > _LIKELY)):
                    continue
                dx = xmin + (j + 0.5) * h - x
                d = math.sqrt(dx * dx + dy * dy)
                if abs(d - r) > band:
                    continue
                if not within(dx, dy, d, mid, half, cos_mid, sin_mid, cos_half):
                    # Outside the carved interval, in reach of a side lobe: the echo may have
                    # come from a surface there, heard through the lobe.
                    if (e_half > 0.0
                            and within(dx, dy, d, axis, e_half, cos_ax, sin_ax, cos_e)
                            and not within(dx, dy, d, axis, b_half, cos_ax, sin_ax, cos_b)):
                        ccw = bearing_off(dx, dy, axis) > 0.0
                        value = min(m.l_max, max(m.l_min, spread))
                        off = bearing_off(dx, dy, mid)
                        occupied = value > m.l_occupied
                        likelier = (_likelier(value, off, best_ccw, at_ccw - mid) if ccw
                                    else _likelier(value, off, best_cw, at_cw - mid))
                        # Only a surface heard from near this ray's bearing could have echoed
                        # back along it (the check is costly, so only for cells that count).
                        if not (occupied or likelier) or not _heard_near(
                                heard, drawn, drawn_seq, slot, m, i, j, x + dx, y + dy,
                                heard_bin(mid + off)):
                            continue
                        if occupied:
                            return True, bearing, 0.0
                        if ccw:
                            best_ccw, at_ccw = max(best_ccw, value), mid + off
                        else:
                            best_cw, at_cw = max(best_cw, value), mid + off
                    continue
                if not value > _LIKELY:
                    continue
                if value > m.l_occupied:
                    return True, bearing, 0.0
                off = bearing_off(dx, dy, mid)
                if abs(off) <= reach:
                    middle_likely = True
                if _likelier(value, off, best, bearing - mid):
                    best = max(best, value)
                    bearing = mid + off
    if not middle_likely and max(best_cw, best_ccw) > best + _TIE:
        if abs(best_cw - best_ccw) <= _TIE:
            # Equally likely surfaces in both lobes: either may have answered, and picking one
            # would let rounding and the scan order draw a lopsided map of a symmetric scene.
            return True, bearing, 0.0
        return (False, at_ccw, 1.0) if best_ccw > best_cw else (False, at_cw, -1.0)
    return False, 0.5 * (lo + hi) if middle_likely else bearing, 0.0


@compiled_inline
def _likelier(value: float, off: float, best: float, best_off: float) -> bool:
    """Whether a cell of log-odds ``value``, ``off`` radians from the arc's middle, beats the
    likeliest so far (``best``, ``best_off`` from the middle): likelier by more than
    :data:`_TIE`, or as likely within it and nearer the middle."""
    return value > best + _TIE or (value >= best - _TIE and abs(off) < abs(best_off))


@compiled_inline
def _heard_near(heard: npt.NDArray[np.uint32], drawn: FloatArray,
                drawn_seq: npt.NDArray[np.int64], own: int, m: Model, i: int, j: int,
                cx: float, cy: float, k: int) -> bool:
    """Whether cell ``(i, j)`` (centre ``cx, cy``) was heard from within :data:`HEARD_NEAR`
    bins of bin ``k``, the bearing of a ray from a sensor to it: recorded in ``heard`` by a final
    band (audibility 1), or on the band of a live arc other than slot ``own`` (drawn in ``live``
    with a value above 0: ``drawn_seq >= 0``), its bearing from that arc's origin binned as a
    final band records it. A wall heard only across the ray (a corridor's side walls, heard by
    side sensors) would not echo back along it; a cell with no record explains nothing.
    ``docs/carved-grid.md``, "Side lobes"."""
    if audibility(heard[i, j], k) == 1.0:
        return True
    band, h = m.band, m.h
    for s in range(drawn_seq.shape[0]):
        if s == own or drawn_seq[s] < 0 or not drawn[s, 5] > 0.0:
            continue
        dx = cx - drawn[s, 0]
        dy = cy - drawn[s, 1]
        r = drawn[s, 2]
        if abs(math.sqrt(dx * dx + dy * dy) - r) > band:
            continue
        # The band as draw_arc draws it: the interval widened by half a cell.
        widen = 0.5 * h / r
        t1, t2 = drawn[s, 3] - widen, drawn[s, 4] + widen
        mid = 0.5 * (t1 + t2)
        off = bearing_off(dx, dy, mid)
        if abs(off) > 0.5 * (t2 - t1):
            continue
        apart = (heard_bin(mid + off) - k) % HEARD_BINS
        if min(apart, HEARD_BINS - apart) <= HEARD_NEAR:
            return True
    return False
