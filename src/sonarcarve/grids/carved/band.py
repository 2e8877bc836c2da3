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
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.grids.carved.heard import heard_bin
from sonarcarve.grids.carved.model import (
    DRAWN_HI,
    DRAWN_LO,
    DRAWN_R,
    DRAWN_VALUE,
    DRAWN_X,
    DRAWN_Y,
    Model,
)
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

__all__ = [
    "ArcBand",
    "DrawnInterval",
    "arc_value",
    "band_ring",
    "box_cells",
    "clamped",
    "draw_arc",
    "drawn_interval",
    "redraw",
    "undraw",
]


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


class ArcBand(NamedTuple):
    """Where an arc's band lies: the circle around the reading's origin and the carved
    interval on it (the kernels' scalars by name; numba passes a tuple of floats between
    compiled functions as the floats themselves)."""

    x: float  # origin, metres
    y: float
    r: float  # range: the circle's radius, metres
    lo: float  # the carved interval [lo, hi], radians (world frame)
    hi: float


class DrawnInterval(NamedTuple):
    """The bearings a band covers as :func:`draw_arc` draws it: the carved interval widened by
    ``h / 2r`` each side (half a cell at the circle), with what
    :func:`~sonarcarve.grids.scan.within` takes to test a cell's bearing against it."""

    t1: float  # clockwise edge, radians
    t2: float  # counter-clockwise edge
    mid: float
    half: float
    cos_mid: float
    sin_mid: float
    cos_half: float  # cos_bound(half)


@compiled_inline
def drawn_interval(m: Model, r: float, lo: float, hi: float) -> DrawnInterval:
    """``[lo, hi]`` widened by ``h / 2r``: a cell whose centre is on the circle within half a
    cell of the interval is drawn, so a narrow interval (a fresh arc's point) still covers the
    cells it passes through."""
    widen = 0.5 * m.h / r
    t1 = lo - widen
    t2 = hi + widen
    mid = 0.5 * (t1 + t2)
    half = 0.5 * (t2 - t1)
    return DrawnInterval(t1, t2, mid, half, math.cos(mid), math.sin(mid), cos_bound(half))


@compiled_inline
def band_ring(m: Model, r: float) -> tuple[float, float]:
    """``(r_in, r_out)``: the distances from the origin of the cells of a band, ``r ± b``."""
    return max(0.0, r - m.band), r + m.band


@compiled_inline
def box_cells(m: Model, shape: tuple[int, int], x: float, y: float, t1: float, t2: float,
              r_in: float, r_out: float) -> tuple[int, int, int, int]:
    """``(i0, i1, j0, j1)``: the rows and columns of the cells (of a grid of ``shape``) that
    may lie in the annular sector ``r_in <= d <= r_out``, bearings ``[t1, t2]``, around
    ``(x, y)``."""
    ny, nx = shape
    xlo, ylo, xhi, yhi = sector_box(x, y, t1, t2, r_in, r_out)
    j0, j1 = cell_range(xlo, xhi, m.xmin, m.h, nx)
    i0, i1 = cell_range(ylo, yhi, m.ymin, m.h, ny)
    return i0, i1, j0, j1


# Its own function, not inlined: it is called once an arc (its loop over the band's cells is
# the work), and inlining its four copies into ``redraw`` made that one kernel take a third of
# ``sonarcarve warm``'s compile time.
@compiled
def draw_arc(grid: npt.NDArray[np.floating], clamp: bool, heard: npt.NDArray[np.uint32],
             m: Model, arc: ArcBand, value: float) -> None:
    """Add ``value`` to the cells of the arc's band (clamped into ``[l_min, l_max]`` if
    ``clamp``): centre within ``band`` of the circle, bearing within ``[lo, hi]`` widened by
    ``h / 2r`` (:func:`drawn_interval`). A final (``clamp``) band with ``value > 0`` also
    records in ``heard`` the bearing each cell was heard from."""
    if value == 0.0:
        return
    x, y, r = arc.x, arc.y, arc.r
    xmin, ymin, h, band = m.xmin, m.ymin, m.h, m.band
    nx = grid.shape[1]
    iv = drawn_interval(m, r, arc.lo, arc.hi)
    r_in, r_out = band_ring(m, r)
    i0, i1, j0, j1 = box_cells(m, grid.shape, x, y, iv.t1, iv.t2, r_in, r_out)
    # Only a plain live draw needs no bearing: it then takes the cheap bearing test; a final
    # band without a profile needs the bearing only for the heard bin.
    plain = not clamp and not m.profile > 0.0
    final_flat = clamp and not m.profile > 0.0
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
                    if within(dx, dy, d, iv.mid, iv.half, iv.cos_mid, iv.sin_mid,
                              iv.cos_half):
                        grid[i, j] += value
                elif final_flat:
                    if within(dx, dy, d, iv.mid, iv.half, iv.cos_mid, iv.sin_mid,
                              iv.cos_half):
                        grid[i, j] = clamped(m, grid[i, j] + value)
                        if value > 0.0:
                            heard[i, j] |= 1 << _heard_bin_of(dx, dy, iv.mid, iv.cos_mid,
                                                              iv.sin_mid)
                else:  # under a profile, or a final band's heard bin: the bearing itself
                    v, off = _by_bearing(dx, dy, d, iv, value, m.profile)
                    if v != v:  # NaN: outside the interval
                        continue
                    if clamp:
                        grid[i, j] = clamped(m, grid[i, j] + v)
                        if v > 0.0:
                            heard[i, j] |= 1 << heard_bin(iv.mid + off)
                    else:
                        grid[i, j] += v


@compiled_inline
def clamped(m: Model, value: float) -> float:
    """``value`` clamped into the map's ``[l_min, l_max]``."""
    return min(m.l_max, max(m.l_min, value))


@compiled_inline
def _by_bearing(dx: float, dy: float, d: float, iv: DrawnInterval, value: float,
                profile: float) -> tuple[float, float]:
    """``(v, off)`` of the cell at ``(dx, dy)`` (distance ``d``) from the arc's origin: what
    :func:`draw_arc` adds to it, ``value`` times the band profile's factor at its bearing
    ``off`` from the interval's middle; NaN outside the interval. Numbers in, numbers out: a
    step handed the grids would count references to them at every cell."""
    if not_within(dx, dy, d, iv.cos_mid, iv.sin_mid, iv.cos_half):
        return math.nan, 0.0  # no arctangent for the cells clearly outside the interval
    off = bearing_off(dx, dy, iv.mid)
    if abs(off) > iv.half:
        return math.nan, off
    v = value
    if profile > 0.0:
        v *= _profile_factor(off, iv.half, profile)
    return v, off


@compiled_inline
def _profile_factor(off: float, half: float, profile: float) -> float:
    """The band profile's factor at ``off`` from the middle of an interval of half-width
    ``half``: ``min(1, profile (1 - u²))``, ``u = off / half``
    (:attr:`~sonarcarve.grids.carved.CarvedGridParams.band_profile`)."""
    u = off / half
    return min(1.0, profile * (1.0 - u * u))


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
           drawn_seq: npt.NDArray[np.int64], slot: int, seq: int, arc: ArcBand, value: float,
           heard: npt.NDArray[np.uint32], m: Model) -> int:
    """Make slot ``slot`` (arc ``seq``) hold ``value`` on ``arc``'s band in ``live``
    (``drawn, drawn_seq``: what each slot drew there,
    :class:`~sonarcarve.grids.carved.model.SlotRecord`'s fields; arrays, not the bundle: a
    bundle of arrays costs a reference count per array at each step it is handed to, and this
    runs for every arc that changed); 1 if that changed anything. The same arc drawn before
    with another interval or value is moved in one pass (:func:`_move_arc`: the same additions,
    cell by cell, as taking it out and drawing it again)."""
    if (drawn_seq[slot] == seq and drawn[slot, DRAWN_LO] == arc.lo
            and drawn[slot, DRAWN_HI] == arc.hi and drawn[slot, DRAWN_VALUE] == value):
        return 0
    if (drawn_seq[slot] >= 0 and drawn[slot, DRAWN_X] == arc.x
            and drawn[slot, DRAWN_Y] == arc.y and drawn[slot, DRAWN_R] == arc.r):
        before = ArcBand(arc.x, arc.y, arc.r, drawn[slot, DRAWN_LO], drawn[slot, DRAWN_HI])
        _move_arc(live, heard, m, before, -drawn[slot, DRAWN_VALUE], arc, value)
    else:
        if drawn_seq[slot] >= 0:
            undraw(live, heard, m, drawn, slot)
        draw_arc(live, False, heard, m, arc, value)
    drawn[slot, DRAWN_X] = arc.x
    drawn[slot, DRAWN_Y] = arc.y
    drawn[slot, DRAWN_R] = arc.r
    drawn[slot, DRAWN_LO] = arc.lo
    drawn[slot, DRAWN_HI] = arc.hi
    drawn[slot, DRAWN_VALUE] = value
    drawn_seq[slot] = seq
    return 1


@compiled_inline
def _move_arc(live: npt.NDArray[np.floating], heard: npt.NDArray[np.uint32], m: Model,
              arc0: ArcBand, value0: float, arc1: ArcBand, value1: float) -> None:
    """``draw_arc(live, ..., arc0, value0)`` then ``draw_arc(live, ..., arc1, value1)`` for
    one arc (the same origin and radius, two intervals), in one pass over the cells: each cell
    of the band gets the same two additions in the same order (so the same sum, bit for bit),
    and its distance and bearing are computed once instead of twice."""
    if value0 == 0.0 or value1 == 0.0:  # one of the two draws nothing
        draw_arc(live, False, heard, m, arc0, value0)
        draw_arc(live, False, heard, m, arc1, value1)
        return
    x, y, r = arc1.x, arc1.y, arc1.r
    xmin, ymin, h, band, profile = m.xmin, m.ymin, m.h, m.band, m.profile
    nx = live.shape[1]
    r_in, r_out = band_ring(m, r)
    iv0 = drawn_interval(m, r, arc0.lo, arc0.hi)
    iv1 = drawn_interval(m, r, arc1.lo, arc1.hi)
    # The rows and columns of both sectors' boxes together.
    a_i0, a_i1, a_j0, a_j1 = box_cells(m, live.shape, x, y, iv0.t1, iv0.t2, r_in, r_out)
    b_i0, b_i1, b_j0, b_j1 = box_cells(m, live.shape, x, y, iv1.t1, iv1.t2, r_in, r_out)
    i0, i1, j0, j1 = min(a_i0, b_i0), max(a_i1, b_i1), min(a_j0, b_j0), max(a_j1, b_j1)
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
                    off = bearing_off(dx, dy, iv0.mid)
                    if abs(off) <= iv0.half:
                        live[i, j] += value0 * _profile_factor(off, iv0.half, profile)
                    off = bearing_off(dx, dy, iv1.mid)
                    if abs(off) <= iv1.half:
                        live[i, j] += value1 * _profile_factor(off, iv1.half, profile)
                    continue
                if within(dx, dy, d, iv0.mid, iv0.half, iv0.cos_mid, iv0.sin_mid,
                          iv0.cos_half):
                    live[i, j] += value0
                if within(dx, dy, d, iv1.mid, iv1.half, iv1.cos_mid, iv1.sin_mid,
                          iv1.cos_half):
                    live[i, j] += value1


@compiled_inline
def undraw(live: npt.NDArray[np.floating], heard: npt.NDArray[np.uint32], m: Model,
           drawn: FloatArray, slot: int) -> None:
    """Take what slot ``slot`` drew (``drawn[slot]``: x, y, r, lo, hi, value) out of ``live``;
    its sequence number is the caller's to clear."""
    band = ArcBand(drawn[slot, DRAWN_X], drawn[slot, DRAWN_Y], drawn[slot, DRAWN_R],
                   drawn[slot, DRAWN_LO], drawn[slot, DRAWN_HI])
    draw_arc(live, False, heard, m, band, -drawn[slot, DRAWN_VALUE])
