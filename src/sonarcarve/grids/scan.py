"""Which cells an annular sector covers, and whether a cell's bearing lies in an interval.

The scans the grids' kernels share (the Elfes grid's beam is the sector with ``r_in = 0``; the
carved grid's kernels use all of them): the cells of the box around the sector
``r_in <= d <= r_out``, bearings ``[t1, t2]`` (:func:`sector_box`, :func:`cell_range`) and, row by
row, only the columns of the ring (:func:`ring_columns`), each with a cell of slack (the exact test
is the caller's); and the bearing test ``|wrap(atan2(dy, dx) - mid)| <= half``
(:func:`bearing_off`), done with a dot product except within :data:`EDGE` of the edge
(:func:`within`: the same answer, bit for bit); and the short series for the arctangent of a
bearing near an axis (:func:`atan_series`), with a bound on its error for the callers that prove
from it that the exact arctangent would give the same result. Metres and radians;
``docs/carved-grid.md``, "The sensor model".
"""

from __future__ import annotations

import math

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.geometry.arctan import SERIES_ERROR, SERIES_T, atan_series

__all__ = [
    "EDGE",
    "SERIES_ERROR",
    "SERIES_T",
    "TWO_PI",
    "atan_series",
    "bearing_off",
    "cell_range",
    "cos_bound",
    "not_within",
    "ring_columns",
    "sector_box",
    "within",
]

TWO_PI = 2.0 * math.pi
#: Margin of :func:`within`'s dot-product test: far above its rounding (about 1e-15)
#: and that of the bearing test it stands for, so the two never disagree outside it.
EDGE = 1e-9


@compiled_inline
def cell_range(lo: float, hi: float, origin: float, h: float, n: int) -> tuple[int, int]:
    """Indices ``k0..k1`` of the cells whose centres may lie in ``[lo, hi]`` (one cell of
    slack each side; the exact test is the caller's)."""
    k0 = max(0, math.floor((lo - origin) / h - 0.5) - 1)
    k1 = min(n - 1, math.ceil((hi - origin) / h - 0.5) + 1)
    return k0, k1


@compiled_inline
def sector_box(x: float, y: float, t1: float, t2: float, r_in: float,
               r_out: float) -> tuple[float, float, float, float]:
    """Bounding box of the annular sector ``r_in <= d <= r_out``, bearings ``[t1, t2]``."""
    xlo = min(x + r_in * math.cos(t1), x + r_in * math.cos(t2),
              x + r_out * math.cos(t1), x + r_out * math.cos(t2))
    xhi = max(x + r_in * math.cos(t1), x + r_in * math.cos(t2),
              x + r_out * math.cos(t1), x + r_out * math.cos(t2))
    ylo = min(y + r_in * math.sin(t1), y + r_in * math.sin(t2),
              y + r_out * math.sin(t1), y + r_out * math.sin(t2))
    yhi = max(y + r_in * math.sin(t1), y + r_in * math.sin(t2),
              y + r_out * math.sin(t1), y + r_out * math.sin(t2))
    # The outer circle's extreme points at the cardinal bearings inside the interval.
    for k in range(4):
        a = 0.5 * math.pi * k
        a += TWO_PI * math.ceil((t1 - a) / TWO_PI)
        if a <= t2:
            if k == 0:
                xhi = x + r_out
            elif k == 1:
                yhi = y + r_out
            elif k == 2:
                xlo = x - r_out
            else:
                ylo = y - r_out
    return xlo, ylo, xhi, yhi


@compiled_inline
def bearing_off(dx: float, dy: float, mid: float) -> float:
    """Bearing of ``(dx, dy)`` minus ``mid``, wrapped into ``[-π, π)``."""
    off = math.atan2(dy, dx) - mid
    off -= TWO_PI * math.floor((off + math.pi) / TWO_PI)
    return off


@compiled_inline
def within(dx: float, dy: float, d: float, mid: float, half: float, cos_mid: float,
           sin_mid: float, cos_half: float) -> bool:
    """``|bearing_off(dx, dy, mid)| <= half``, the bearing test of
    :func:`~sonarcarve.grids.carved.band.draw_arc`, with the arctangent only near the interval's
    edges: ``(dx, dy)`` (length ``d``) is within ``half`` of the direction ``(cos_mid, sin_mid)``
    when its cosine to it is above ``cos_half`` (-2 when ``half >= π``: every bearing), and the
    cosine decides wherever it is more than :data:`EDGE` from ``cos_half``: there both tests'
    rounding (1e-15) cannot change the answer, so the answer is the same bit for bit."""
    if d > 0.0:
        q = (dx * cos_mid + dy * sin_mid) / d - cos_half
        if q > EDGE:
            return True
        if q < -EDGE:
            return False
    return abs(bearing_off(dx, dy, mid)) <= half


@compiled_inline
def not_within(dx: float, dy: float, d: float, cos_mid: float, sin_mid: float,
               cos_half: float) -> bool:
    """True only where :func:`within` is False by its cosine alone (more than :data:`EDGE`
    below ``cos_half``): there ``|bearing_off(dx, dy, mid)| > half`` too, so a caller that needs
    the bearing itself can skip the arctangent for such cells and get the same answer."""
    return d > 0.0 and (dx * cos_mid + dy * sin_mid) / d - cos_half < -EDGE


@compiled_inline
def cos_bound(half: float) -> float:
    """``cos(half)`` for :func:`within`; -2 (every bearing) when ``half >= π``."""
    return math.cos(half) if half < math.pi else -2.0


@compiled_inline
def ring_columns(dy: float, r_in: float, r_out: float, x: float, xmin: float, h: float,
                 nx: int, j0: int, j1: int) -> tuple[int, int, int, int]:
    """The columns ``a0..a1`` and ``b0..b1`` (disjoint, left then right; empty when the first
    index is larger) of the row ``dy`` (relative to the centre ``x``) whose cell centres may
    lie in the ring ``r_in <= d <= r_out``, within ``j0..j1``: one cell of slack each side, the
    exact test is the caller's."""
    rest = r_out * r_out - dy * dy
    if rest < 0.0:
        return 1, 0, 1, 0
    outer = math.sqrt(rest)
    inner = math.sqrt(max(0.0, r_in * r_in - dy * dy))
    a0, a1 = cell_range(x - outer, x - inner, xmin, h, nx)
    b0, b1 = cell_range(x + inner, x + outer, xmin, h, nx)
    a0, a1, b0, b1 = max(a0, j0), min(a1, j1), max(b0, j0), min(b1, j1)
    if b0 <= a1 + 1:  # the two stretches touch: one
        return min(a0, b0), max(a1, b1), 1, 0
    return a0, a1, b0, b1

