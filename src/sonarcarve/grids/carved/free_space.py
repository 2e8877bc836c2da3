"""One reading's free space: the beam's cells nearer than ``r - b``, final at once.

``l += γ(α) f(d) · logit(p_miss)``, ``γ(α) = 1 - (2α/φ)²``, ``f(d) = (1 - tanh(2 (d - d_f))) / 2``
(``docs/carved-grid.md``, "The sensor model"); at a cell believed occupied (``base > 0``)
``l += γ(α) (A · logit(p_heard) + (1 - A) f(d) · logit(p_miss))``, ``A`` the audibility of its
surface from the beam's bearing ("Clearing what was heard"), raised to that of the most audible such
cell at most ``see_through`` in front of it on its ray (:func:`_free_behind`, "Seen through").

A cell not believed occupied is updated with a series for ``α`` and an exponential for the fade
where their error bounds prove the stored float32 is the exact update's (:func:`_quick_update`):
the same bits for about a third of the arithmetic (an ``atan2`` and a ``tanh`` were two thirds
of the free space's CPU time).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.grids.carved.band import box_cells, clamped
from sonarcarve.grids.carved.heard import audibility, heard_bin
from sonarcarve.grids.carved.model import Model
from sonarcarve.grids.scan import EDGE, SERIES_ERROR, SERIES_T, atan_series, cell_range
from sonarcarve.typing import FloatArray

__all__ = ["HELD", "Beam", "free_space"]

#: Cells believed occupied one beam's free space can hold back for :func:`_free_behind`; the
#: rest get the plain update.
HELD = 512

#: Bound on ``|1 / (1 + exp(4(d - d_f))) - (1 - tanh(2(d - d_f))) / 2|`` as computed: the two
#: are the same function (``1 - tanh u = 2 / (1 + e^2u)``) and each is computed to a few ulp of
#: 1 (libm's ``exp`` and ``tanh``, one subtraction or addition, one division): below 1e-15
#: (measured on 0-8 m: 2.2e-16).
FADE_ERROR = 2e-15
#: Factor on the error bounds in :func:`_stored`: room for what the bounds' arithmetic left
#: out (products of two errors, the rounding of the product ``w · miss``).
MARGIN_SAFETY = 8.0
#: Relative rounding allowed for in :func:`_stored`: of the sum ``cell + w · miss`` (exact and
#: quick: half an ulp each) and of the sum's margin, well inside ``2^-50``.
SUM_ROUNDING = 2.0 ** -50


@compiled_inline
def _row_span(dy: float, reach: float, half: float, u1x: float, u1y: float, u2x: float,
              u2y: float) -> tuple[float, float]:
    """``(lo, hi)`` of ``dx`` on the line ``dy`` (relative to the apex) inside the sector of
    radius ``reach`` between the unit directions ``u1`` (clockwise edge) and ``u2``; empty
    when ``lo > hi``. The sector is the disk cut by two half-planes when ``half < π/2``."""
    rest = reach * reach - dy * dy
    if rest < 0.0:
        return 1.0, 0.0
    hi = math.sqrt(rest)
    lo = -hi
    if half >= 0.5 * math.pi:
        return lo, hi
    # Counter-clockwise of u1: u1x dy - u1y dx >= 0.
    if u1y > 0.0:
        hi = min(hi, u1x * dy / u1y)
    elif u1y < 0.0:
        lo = max(lo, u1x * dy / u1y)
    elif u1x * dy < 0.0:
        return 1.0, 0.0
    # Clockwise of u2: u2y dx - u2x dy >= 0.
    if u2y > 0.0:
        lo = max(lo, u2x * dy / u2y)
    elif u2y < 0.0:
        hi = min(hi, u2x * dy / u2y)
    elif u2x * dy > 0.0:
        return 1.0, 0.0
    return lo, hi


@compiled_inline
def _floor_and_inside(m: Model, cos_half: float) -> tuple[float, float]:
    """What lets :func:`free_space` skip a cell whose update cannot change it, with no
    arctangent and no fade: ``floor``, the stored (float32) ``l_min``, and ``inside``, a cosine
    bound that puts a cell's bearing strictly inside the beam.

    A cell at ``floor`` (< 0, not -0.0, which would equal a fresh cell's 0.0) is not believed
    occupied, so its update is
    ``min(l_max, max(l_min, floor + γ(α) f(d) · logit(p_miss)))``. Where ``γ(α) >= 0`` and
    ``logit(p_miss) <= 0`` the sum is at most ``floor``, so the clamp gives a value in
    ``[l_min, floor]`` (or ``l_min`` when ``floor < l_min``), and float32 rounding, monotone, takes
    every such value back to ``floor = float32(l_min)``: the cell keeps its bits. ``γ(α) >= 0``
    needs ``|α| <= φ/2`` for the computed ``α``; the beam's own cosine test admits cells within
    rounding of the edge, so a cell is skipped only when its cosine to the axis is above
    ``cos(φ/2)`` by :data:`~sonarcarve.grids.scan.EDGE` (far above the arctangent's
    rounding, 1e-16). ``floor`` is NaN (never equal) when ``logit(p_miss) > 0``, ``floor >= 0``
    or ``l_min > l_max``, where the argument does not hold."""
    floor = float(np.float32(m.l_min))
    if not (m.l_miss <= 0.0 and floor < 0.0 and m.l_min <= m.l_max):
        return math.nan, 2.0
    return floor, cos_half + EDGE


class Beam(NamedTuple):
    """One reading's beam, whose free space :func:`free_space` draws (metres, radians)."""

    x: float  # the apex: the sensor's position
    y: float
    theta: float  # the axis θ
    r: float  # the range heard (a no-echo reading: max_range + band)
    half: float  # half the beam's width, φ/2


class _Sector(NamedTuple):
    """What :func:`free_space` tests each cell against: the sector of radius ``reach`` about the
    beam's axis, with its edges' unit directions (:func:`_row_span`)."""

    reach: float  # r - band - free_margin: the free space ends there
    c: float  # cos θ
    s: float  # sin θ
    cos_half: float
    u1x: float  # the clockwise edge θ - φ/2
    u1y: float
    u2x: float  # the counter-clockwise edge θ + φ/2
    u2y: float


@compiled_inline
def _sector_of(m: Model, beam: Beam) -> _Sector:
    """The sector of ``beam``'s free space: nearer than ``r - band - free_margin``, so that a
    beam does not clear its own echo's band (nor, with ``pose_sigma``, an older arc a pose
    error moved)."""
    theta, half = beam.theta, beam.half
    t1, t2 = theta - half, theta + half
    return _Sector(beam.r - m.band - m.free_margin, math.cos(theta), math.sin(theta),
                   math.cos(half), math.cos(t1), math.sin(t1), math.cos(t2), math.sin(t2))


@compiled_inline
def free_space(base: npt.NDArray[np.float32], heard: npt.NDArray[np.uint32], m: Model,
               beam: Beam, held: FloatArray) -> None:
    """One reading's free space (eq. 3.2's region ``F``, ending ``band + free_margin`` short
    of the range; ``free_margin``: 2 ``pose_sigma``, 0 by default), clamped into
    ``[l_min, l_max]``: ``γ(α) f(d) · logit(p_miss)`` (``f`` the fade) on cells not believed
    occupied (``base <= 0``), and where ``aware`` on the others
    ``γ(α) (A · logit(p_heard) + (1 - A) f(d) · logit(p_miss))``, ``A`` the cell's
    :func:`~sonarcarve.grids.carved.heard.audibility` from the beam's bearing (``aware`` False: the
    fade for all). ``held``: room for the believed-occupied cells :func:`_free_behind` updates
    after the others, when ``see_through`` is on.

    A cell this brings from ``base > 0`` to ``base <= 0`` forgets the bearings it was heard
    from (``docs/carved-grid.md``, "Clearing what was heard")."""
    sector = _sector_of(m, beam)
    reach = sector.reach
    if reach <= 0.0:
        return
    x, y, half = beam.x, beam.y, beam.half
    xmin, ymin, h = m.xmin, m.ymin, m.h
    c, s = sector.c, sector.s
    nx = base.shape[1]
    i0, i1, j0, j1 = box_cells(m, base.shape, x, y, beam.theta - half, beam.theta + half, 0.0,
                               reach)
    floor, inside = _floor_and_inside(m, sector.cos_half)
    dw = _profile_error(half)
    inv_half2 = 1.0 / (half * half)
    n_held = 0
    for i in range(i0, i1 + 1):
        dy = ymin + (i + 0.5) * h - y
        # Only the row's stretch inside the sector (plus a cell each side; the exact test is
        # per cell below): most of the bounding box of a slanted beam lies outside it.
        lo, hi = _row_span(dy, reach, half, sector.u1x, sector.u1y, sector.u2x, sector.u2y)
        if lo > hi:
            continue
        ja, jb = cell_range(x + lo, x + hi, xmin, h, nx)
        for j in range(max(j0, ja), min(j1, jb) + 1):
            dx = xmin + (j + 0.5) * h - x
            d2 = dx * dx + dy * dy
            if d2 >= reach * reach:
                continue
            along = dx * c + dy * s
            if along < math.sqrt(d2) * sector.cos_half:
                continue
            cell = base[i, j]
            if cell == floor and along > math.sqrt(d2) * inside:
                continue  # at the clamp's floor, and the update provably keeps it there
            if not (m.aware and cell > 0.0):
                quick = _quick_update(cell, dy * c - dx * s, along, math.sqrt(d2), inv_half2,
                                      dw, m)
                if quick == quick:  # not NaN: decided, the exact update's very bits
                    base[i, j] = quick
                    if cell > 0.0 and quick <= 0.0:
                        heard[i, j] = 0
                    continue
            # The exact update: the arctangent, and the tanh fade.
            a, w, miss = _exact_terms(m, beam, dy * c - dx * s, along, math.sqrt(d2))
            if m.aware and cell > 0.0:
                audible = audibility(int(heard[i, j]), heard_bin(beam.theta + a))
                if m.through > 0.0 and n_held < held.shape[0]:  # for _free_behind
                    held[n_held, _ROW] = i
                    held[n_held, _COLUMN] = j
                    held[n_held, _DISTANCE] = math.sqrt(d2)
                    held[n_held, _BEARING] = a
                    held[n_held, _PROFILE] = w
                    held[n_held, _AUDIBLE] = audible
                    held[n_held, _MISS] = miss
                    n_held += 1
                    continue
                miss = audible * m.l_heard + (1.0 - audible) * miss
            base[i, j] = clamped(m, cell + w * miss)
            # Freed: the surface it was heard from is believed gone, so are its bearings (else
            # a later, different surface here would be cleared at full strength from them).
            # Now, at the crossing, and not when a band next marks the cell: the bits are read
            # only while base > 0, which only a final band restores, so the bearings kept are
            # exactly those heard since the cell was freed; forgetting them at every free-space
            # update below 0 would drop the bands that raised the cell back, and forgetting at
            # the next band would keep only that band's. The stored (float32) value decides,
            # as it does when the bits are read.
            if cell > 0.0 and base[i, j] <= 0.0:
                heard[i, j] = 0
    if n_held:
        _free_behind(base, heard, m, held, n_held)


#: Columns of :func:`free_space`'s ``held`` rows, read by :func:`_free_behind`: the cell's row
#: and column, its distance, its bearing off the axis, the profile ``γ(α)``, the audibility of
#: its surface from the beam's bearing and the faded miss ``f(d) · logit(p_miss)``.
_ROW, _COLUMN, _DISTANCE, _BEARING, _PROFILE, _AUDIBLE, _MISS = 0, 1, 2, 3, 4, 5, 6


@compiled_inline
def _exact_terms(m: Model, beam: Beam, cross: float, along: float,
                 d: float) -> tuple[float, float, float]:
    """``(α, γ(α), f(d) · logit(p_miss))`` of a cell at distance ``d``, ``(along, cross)``
    from the apex along and across the axis, computed exactly (``atan2``, ``tanh``): where the
    quick update could not tell the bits, or the cell is believed occupied. Numbers in,
    numbers out: a step handed arrays would count references to them at every cell."""
    a = math.atan2(cross, along)
    w = 1.0 - (a / beam.half) ** 2
    miss = m.l_miss
    if m.fade < math.inf:
        miss *= 0.5 * (1.0 - math.tanh(2.0 * (d - m.fade)))
    return a, w, miss


@compiled_inline
def _profile_error(half: float) -> float:
    """Bound on the error of ``w = 1 - (a / half)^2`` when ``a`` is the series' (``|a| <=
    atan(SERIES_T) < SERIES_T``, off by at most ``δa =`` :data:`SERIES_ERROR`):
    ``(2 |a| + δa) δa / half^2``, plus the roundings of either way of computing ``w`` (three
    each, below 1)."""
    da = SERIES_ERROR
    return (2.0 * SERIES_T + da) * da / (half * half) + 8.0 * 2.0 ** -53


@compiled_inline
def _quick_update(cell: float, cross: float, along: float, d: float, inv_half2: float,
                  dw: float, m: Model) -> float:
    """The stored (float32) value of :func:`free_space`'s plain update of a cell ``cell`` at
    distance ``d``, ``(along, cross)`` from the apex along and across the axis, in a beam of
    half-width ``half`` (``inv_half2 = 1 / half^2``), or NaN when
    this cannot tell it (:func:`_stored`). The arctangent is the series' (:func:`atan_series`:
    ``w`` off by at most ``dw``, :func:`_profile_error`); the fade is first
    ``1 / (1 + exp(4 (d - d_f)))`` (off by at most :data:`FADE_ERROR`), then, where that leaves
    the bits open (mostly a far cell whose faded update is below the fade's own rounding), the
    exact update's.

    Left to the exact path: a bearing past :data:`SERIES_T`, a beam of ``half >= π/2``
    (``along <= 0``), and what the margins leave open (measured: 4 of 845,000 updates, office
    log, amplitude physics, 0.10 m cells)."""
    if not (along > 0.0 and abs(cross) <= SERIES_T * along):
        return math.nan
    a = atan_series(cross / along)
    w = 1.0 - a * a * inv_half2  # no division: it lengthens the chain; the rounding is in dw
    if not m.fade < math.inf:
        return _stored(cell, w * m.l_miss, dw * abs(m.l_miss), m)
    miss = m.l_miss / (1.0 + math.exp(4.0 * (d - m.fade)))
    quick = _stored(cell, w * miss, dw * abs(miss) + (1.0 + dw) * abs(m.l_miss) * FADE_ERROR,
                    m)
    if quick == quick:
        return quick
    miss = m.l_miss * (0.5 * (1.0 - math.tanh(2.0 * (d - m.fade))))
    return _stored(cell, w * miss, dw * abs(miss), m)


@compiled_inline
def _stored(cell: float, change: float, error: float, m: Model) -> float:
    """``float32(clamp(cell + exact))``, the exact update's stored value, from ``change``, off
    ``exact`` by at most ``error``; NaN when that does not decide it.

    Decided when every sum within the margin (``error`` times :data:`MARGIN_SAFETY`, plus
    :data:`SUM_ROUNDING`) of ``cell + change`` clamps and rounds to one nonzero float32: the
    exact sum lies in that range, and clamping and rounding are monotone, so it stores the same
    bits (zero is left open: -0.0 and 0.0 compare equal)."""
    total = cell + change
    margin = MARGIN_SAFETY * error + SUM_ROUNDING * abs(total)
    low = np.float32(min(m.l_max, max(m.l_min, total - margin)))
    high = np.float32(min(m.l_max, max(m.l_min, total + margin)))
    if low == high and low != 0.0:
        return float(low)
    return math.nan


@compiled_inline
def _free_behind(base: npt.NDArray[np.float32], heard: npt.NDArray[np.uint32], m: Model,
                 held: FloatArray, n: int) -> None:
    """The free space of the cells believed occupied that one beam passed (``held``: row,
    column, distance, bearing off the axis, profile, audibility, faded miss), each as audible
    as the most audible such cell in front of it on its ray (nearer by at least a cell and by
    at most ``through``, its ray within half a cell diagonal of that cell's centre): a surface
    the beam would have heard and did not is gone, and so is what stood behind it."""
    h = m.h
    for p in range(n):
        audible = held[p, _AUDIBLE]
        d = held[p, _DISTANCE]
        for q in range(n):
            dq = held[q, _DISTANCE]
            if (held[q, _AUDIBLE] > audible and dq <= d - h and d - dq <= m.through
                    and abs(held[p, _BEARING] - held[q, _BEARING]) * dq <= 0.7072 * h):
                audible = held[q, _AUDIBLE]
        i, j = int(held[p, _ROW]), int(held[p, _COLUMN])
        cell = base[i, j]
        miss = audible * m.l_heard + (1.0 - audible) * held[p, _MISS]
        base[i, j] = clamped(m, cell + held[p, _PROFILE] * miss)
        if cell > 0.0 and base[i, j] <= 0.0:
            heard[i, j] = 0
