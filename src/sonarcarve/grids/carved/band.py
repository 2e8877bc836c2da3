"""An arc's occupied band: its value, and drawing, moving and taking it back in a grid.

An arc adds ``l_k = c · s · logit(p_hit)``, ``s = min(1, L / (r (θ2' - θ1')))``, to each cell of its
band (:func:`arc_value`; a fresh arc ``c · logit(p_hit)``): the cells whose centre lies within
``b`` of the circle of radius ``r`` and whose bearing lies in the carved interval widened by
``h / 2r`` (:func:`draw_arc`). A live arc whose interval or value changed is moved in one pass
(:func:`redraw`, :func:`_move_arc`): the same additions as taking it out (:func:`undraw`) and
drawing it again. ``docs/carved-grid.md``, "The sensor model" and "Following carving over time".
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.grids.carved.heard import heard_bin
from sonarcarve.grids.carved.model import Model
from sonarcarve.grids.scan import (
    SERIES_T,
    atan_series,
    bearing_off,
    cell_range,
    cos_bound,
    not_within,
    ring_columns,
    sector_box,
    within,
)
from sonarcarve.typing import FloatArray

__all__ = ["arc_value", "draw_arc", "redraw", "undraw"]


@compiled_inline
def arc_value(r: float, lo: float, hi: float, weight: float, m: Model,
              fresh: bool = False) -> float:
    """Log-odds one arc adds to each cell of its carved band: ``c · s · logit(p_hit)``; a ``fresh``
    arc (the newest reading of its sensor,
    :attr:`~sonarcarve.grids.carved.CarvedGridParams.fresh_arcs`) ``c · logit(p_hit)``, unspread."""
    if not weight > 0.0:
        return 0.0
    s = 1.0
    if m.spread > 0.0 and not fresh:
        length = r * (hi - lo)
        if length > m.unit:
            s = m.unit / length
    return weight * s * m.l_hit


# Its own function, not inlined: it is called once an arc (its loop over the band's cells is
# the work), and inlining its four copies into ``redraw`` made that one kernel take a third of
# ``sonarcarve warm``'s compile time.
@compiled
def draw_arc(grid: npt.NDArray[np.floating], clamp: bool, heard: npt.NDArray[np.uint32],
             m: Model, x: float, y: float, r: float, lo: float, hi: float,
             value: float) -> None:
    """Add ``value`` to the cells of the arc's band (clamped into ``[l_min, l_max]`` if
    ``clamp``): centre within ``band`` of the circle, bearing within ``[lo, hi]`` widened by
    ``h / 2r``. A final (``clamp``) band with ``value > 0`` also records in ``heard`` the
    bearing each cell was heard from."""
    if value == 0.0:
        return
    xmin, ymin, h, band, profile = m.xmin, m.ymin, m.h, m.band, m.profile
    ny, nx = grid.shape
    widen = 0.5 * h / r
    t1 = lo - widen
    t2 = hi + widen
    mid = 0.5 * (t1 + t2)
    half = 0.5 * (t2 - t1)
    r_in = max(0.0, r - band)
    r_out = r + band
    xlo, ylo, xhi, yhi = sector_box(x, y, t1, t2, r_in, r_out)
    j0, j1 = cell_range(xlo, xhi, xmin, h, nx)
    i0, i1 = cell_range(ylo, yhi, ymin, h, ny)
    # Only a plain live draw needs no bearing: it then takes the cheap bearing test.
    plain = not clamp and not profile > 0.0
    cos_mid, sin_mid, cos_half = math.cos(mid), math.sin(mid), cos_bound(half)
    for i in range(i0, i1 + 1):
        dy = ymin + (i + 0.5) * h - y
        a0, a1, b0, b1 = ring_columns(dy, r_in, r_out, x, xmin, h, nx, j0, j1)
        for part in range(2):
            for j in range(a0 if part == 0 else b0, (a1 if part == 0 else b1) + 1):
                dx = xmin + (j + 0.5) * h - x
                d = math.sqrt(dx * dx + dy * dy)
                if abs(d - r) > band:
                    continue
                if plain:
                    if within(dx, dy, d, mid, half, cos_mid, sin_mid, cos_half):
                        grid[i, j] += value
                    continue
                if clamp and not profile > 0.0:  # the bearing picks only the heard bin
                    if within(dx, dy, d, mid, half, cos_mid, sin_mid, cos_half):
                        grid[i, j] = min(m.l_max, max(m.l_min, grid[i, j] + value))
                        if value > 0.0:
                            heard[i, j] |= 1 << _heard_bin_of(dx, dy, mid, cos_mid, sin_mid)
                    continue
                if not_within(dx, dy, d, cos_mid, sin_mid, cos_half):
                    continue  # no arctangent for the cells clearly outside the interval
                off = bearing_off(dx, dy, mid)
                if abs(off) > half:
                    continue
                v = value
                if profile > 0.0:
                    u = off / half
                    v *= min(1.0, profile * (1.0 - u * u))
                if clamp:
                    grid[i, j] = min(m.l_max, max(m.l_min, grid[i, j] + v))
                    if v > 0.0:
                        heard[i, j] |= 1 << heard_bin(mid + off)
                else:
                    grid[i, j] += v


#: Bound used by :func:`_heard_bin_of` on how far its bearing can be from ``bearing_off``'s:
#: :data:`~sonarcarve.grids.scan.SERIES_ERROR` plus a few roundings of numbers up to 2π in
#: each (``atan2``, the rotation by ``mid``, the wrap), below 1e-14 in all.
BIN_MARGIN = 1e-12
#: Largest ``|mid|`` (radians) for which :data:`BIN_MARGIN` holds: the roundings of ``mid`` and
#: of ``mid + off`` grow with ``|mid|`` (an ulp of 64 is 1.4e-14; review rev10c found bins off
#: by one at ``|mid|`` near 2π·1e5). Carving's intervals come from ``atan2``, within a few
#: radians of zero; an interval written a thousand turns out takes the arctangent.
BIN_MID_MAX = 64.0


@compiled_inline
def _heard_bin_of(dx: float, dy: float, mid: float, cos_mid: float, sin_mid: float) -> int:
    """``heard_bin(mid + bearing_off(dx, dy, mid))``, the bin a final band records for the
    cell at ``(dx, dy)`` from the arc's origin, without an arctangent where the series
    (:func:`~sonarcarve.grids.scan.atan_series` of the cell's direction turned by ``-mid``)
    decides it: the bins of the bearings :data:`BIN_MARGIN` either side of the series' are one,
    and the bin is monotone in the bearing, so the exact bearing's is that bin too (for
    ``|mid| <=`` :data:`BIN_MID_MAX`, where that margin holds)."""
    along = dx * cos_mid + dy * sin_mid
    cross = dy * cos_mid - dx * sin_mid
    if abs(mid) <= BIN_MID_MAX and along > 0.0 and abs(cross) <= SERIES_T * along:
        off = atan_series(cross / along)
        k = heard_bin(mid + (off - BIN_MARGIN))
        if k == heard_bin(mid + (off + BIN_MARGIN)):
            return k
    return heard_bin(mid + bearing_off(dx, dy, mid))


@compiled  # its own function: inlined into the refresh loop, that loop ran 2x slower
def redraw(live: npt.NDArray[np.floating], drawn: FloatArray,
           drawn_seq: npt.NDArray[np.int64], slot: int, seq: int, x: float, y: float,
           r: float, lo: float, hi: float, value: float, heard: npt.NDArray[np.uint32],
           m: Model) -> int:
    """Make slot ``slot`` (arc ``seq``) hold ``value`` on ``[lo, hi]`` in ``live``; 1 if that
    changed anything. The same arc drawn before with another interval or value is moved in
    one pass (:func:`_move_arc`: the same additions, cell by cell, as taking it out and
    drawing it again)."""
    if (drawn_seq[slot] == seq and drawn[slot, 3] == lo and drawn[slot, 4] == hi
            and drawn[slot, 5] == value):
        return 0
    if (drawn_seq[slot] >= 0 and drawn[slot, 0] == x and drawn[slot, 1] == y
            and drawn[slot, 2] == r):
        _move_arc(live, heard, m, x, y, r, drawn[slot, 3], drawn[slot, 4], -drawn[slot, 5],
                  lo, hi, value)
    else:
        if drawn_seq[slot] >= 0:
            undraw(live, heard, m, drawn, slot)
        draw_arc(live, False, heard, m, x, y, r, lo, hi, value)
    drawn[slot, 0] = x
    drawn[slot, 1] = y
    drawn[slot, 2] = r
    drawn[slot, 3] = lo
    drawn[slot, 4] = hi
    drawn[slot, 5] = value
    drawn_seq[slot] = seq
    return 1


@compiled_inline
def _move_arc(live: npt.NDArray[np.floating], heard: npt.NDArray[np.uint32], m: Model,
              x: float, y: float, r: float,
              lo0: float, hi0: float, value0: float, lo1: float, hi1: float,
              value1: float) -> None:
    """``draw_arc(live, ..., lo0, hi0, value0)`` then ``draw_arc(live, ..., lo1, hi1,
    value1)`` for one arc (same origin and radius), in one pass over the cells: each cell of
    the band gets the same two additions in the same order (so the same sum, bit for bit), and
    its distance and bearing are computed once instead of twice."""
    if value0 == 0.0 or value1 == 0.0:  # one of the two draws nothing
        draw_arc(live, False, heard, m, x, y, r, lo0, hi0, value0)
        draw_arc(live, False, heard, m, x, y, r, lo1, hi1, value1)
        return
    xmin, ymin, h, band, profile = m.xmin, m.ymin, m.h, m.band, m.profile
    ny, nx = live.shape
    widen = 0.5 * h / r
    r_in = max(0.0, r - band)
    r_out = r + band
    ta0, tb0 = lo0 - widen, hi0 + widen
    ta1, tb1 = lo1 - widen, hi1 + widen
    mid0, half0 = 0.5 * (ta0 + tb0), 0.5 * (tb0 - ta0)
    mid1, half1 = 0.5 * (ta1 + tb1), 0.5 * (tb1 - ta1)
    xlo0, ylo0, xhi0, yhi0 = sector_box(x, y, ta0, tb0, r_in, r_out)
    xlo1, ylo1, xhi1, yhi1 = sector_box(x, y, ta1, tb1, r_in, r_out)
    j0, j1 = cell_range(min(xlo0, xlo1), max(xhi0, xhi1), xmin, h, nx)
    i0, i1 = cell_range(min(ylo0, ylo1), max(yhi0, yhi1), ymin, h, ny)
    cm0, sm0, ch0 = math.cos(mid0), math.sin(mid0), cos_bound(half0)
    cm1, sm1, ch1 = math.cos(mid1), math.sin(mid1), cos_bound(half1)
    for i in range(i0, i1 + 1):
        dy = ymin + (i + 0.5) * h - y
        a0, a1, b0, b1 = ring_columns(dy, r_in, r_out, x, xmin, h, nx, j0, j1)
        for part in range(2):
            for j in range(a0 if part == 0 else b0, (a1 if part == 0 else b1) + 1):
                dx = xmin + (j + 0.5) * h - x
                d = math.sqrt(dx * dx + dy * dy)
                if abs(d - r) > band:
                    continue
                if profile > 0.0:
                    off = bearing_off(dx, dy, mid0)
                    if abs(off) <= half0:
                        u = off / half0
                        live[i, j] += value0 * min(1.0, profile * (1.0 - u * u))
                    off = bearing_off(dx, dy, mid1)
                    if abs(off) <= half1:
                        u = off / half1
                        live[i, j] += value1 * min(1.0, profile * (1.0 - u * u))
                    continue
                if within(dx, dy, d, mid0, half0, cm0, sm0, ch0):
                    live[i, j] += value0
                if within(dx, dy, d, mid1, half1, cm1, sm1, ch1):
                    live[i, j] += value1


@compiled_inline
def undraw(live: npt.NDArray[np.floating], heard: npt.NDArray[np.uint32], m: Model,
           drawn: FloatArray, slot: int) -> None:
    """Take what slot ``slot`` drew (``drawn[slot]``: x, y, r, lo, hi, value) out of ``live``."""
    draw_arc(live, False, heard, m, drawn[slot, 0], drawn[slot, 1], drawn[slot, 2],
             drawn[slot, 3], drawn[slot, 4], -drawn[slot, 5])
