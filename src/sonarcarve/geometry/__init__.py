"""Exact arc and sector geometry: carving an arc by a newer reading's freespace (paper, section 3).

An *arc* ``C_i`` (eq. 3.1) is the set of points ``o_i + r_i (cos τ, sin τ)`` for bearings ``τ`` in
``[lo, hi]``, stored unwrapped with ``lo ≤ hi`` and ``hi - lo < 2π`` (a sonar arc has
``hi - lo ≤ φ < π``). The *freespace* ``F_j`` of a reading ``j`` (eq. 3.2) is the sector of its full
beam, with the range shortened by a tolerance ``ε ≥ 0``::

    F_j = {p : |p - o_j| < R_j,  bearing(p - o_j) ∈ [f_lo, f_hi]},   R_j = r_j - ε,

with ``0 ≤ f_hi - f_lo < π``. ``ε = 0`` is the paper's set exactly (the open disk makes an arc
that merely *touches* the echo circle of ``j`` survive; the paper's closed ``≤ r`` differs only on
that measure-zero set).

Everything is closed form, never sampled. On circle ``i``, each of the three conditions that make
up ``F_j`` is one *circular interval* of ``τ``:

* the open disk ``|p - o_j| < R_j``: with ``d = o_j - o_i``, ``D = |d|``, ``α = atan2(d)``,
  ``|p(τ) - o_j|² = D² + r² - 2 r D cos(τ - α)``, so the condition is
  ``cos(τ - α) > k``, ``k = (D² + r² - R²) / (2 r D)``: bounded by ``α ± acos k`` when ``|k| < 1``,
  the whole circle when ``k ≤ -1``, nothing when ``k ≥ 1``;
* the half-plane left of the ray at ``f_lo`` (unit vector ``u``): ``u × (p - o_j) ≥ 0``, i.e.
  ``sin(τ - f_lo) ≥ s`` with ``s = -u × (o_i - o_j) / r``, bounded by ``f_lo + asin s`` and
  ``f_lo + π - asin s``;
* the half-plane right of the ray at ``f_hi``: ``sin(τ - f_hi) ≤ -u' × (o_i - o_j) / r``.

Because the beam is narrower than π, the wedge is exactly the intersection of the two half-planes,
so ``Z_ij = C_i ∩ F_j`` (eq. 3.4) is the intersection of the three intervals with ``[lo, hi]``.
Rather than intersect circular intervals case by case (each may wrap and give two pieces inside
``[lo, hi]``), :func:`carve_arc` collects the at most six boundary bearings that fall strictly
inside ``(lo, hi)``, sorts them with ``lo`` and ``hi``, and tests the middle of each sub-interval
against the three conditions: membership is constant between consecutive boundaries, so this is
exact, and it is robust to every coincidence of boundaries. The remainder ``[lo, hi] \\ Z_ij`` is
then read off as runs of non-member sub-intervals (eq. 3.5, one ``j`` at a time).

Degenerate cases, decided deliberately:

* *Slivers.* Runs (carved or remaining) shorter than :data:`MIN_PIECE` radians are rounding
  noise at tangencies and coincident boundaries: a carved sliver is ignored (a touch is not a
  cut) and so is a remaining sliver (an arc carved down to a sliver is fully carved). So a carved
  interval is never shorter than :data:`MIN_PIECE`.
* *Coincident origins* (``D = 0``): the circle is inside the disk iff ``r < R`` (no boundary);
  only the two half-planes cut it. An arc read again from the same place with the same range
  therefore survives (open disk), with a shorter range it is carved where the beams overlap.
* *Tangency* (``|k| = 1`` or ``|s| = 1``): the interval is a single point or empty; treated as
  empty (a measure-zero set carves nothing).
* *Zero-length arcs* (``hi - lo < MIN_PIECE``): the arc is a point, fully carved iff that point
  is in ``F_j``, otherwise unchanged.
* *No freespace* (``R ≤ 0``, a range within the tolerance): nothing is carved.

Specular-aware carving (beyond the paper; opt-in)
-------------------------------------------------
On smooth walls an echo comes back only when the beam meets the wall close to its normal. An
echo of reading ``i`` at ``p`` therefore implies a surface through ``p`` whose normal points
back at ``o_i``; reading ``j`` would see that surface at the incidence angle ``γ(p)``, the angle
``o_i``-``p``-``o_j`` of the triangle folded into ``[0, π/2]`` (a thin wall reflects from both
faces; this is the same angle as ATM's transversal angle). If ``γ(p)`` exceeds a critical angle
``β``, reading ``j`` could not have heard that surface, so its freespace is no evidence against
``p``. The carved set becomes ::

    Z_ij^β = {p ∈ C_i ∩ F_j : γ(p) ≤ β},       β = π/2: Z_ij^β = Z_ij (the paper),

a fourth condition on the circle. With ``w = p - o_i`` and ``v = p - o_j``,
``sin γ = |w × v| / (|w| |v|)`` (folding keeps the sine), so for ``β < π/2`` the condition is
``(w × v)² ≤ sin²β |w|² |v|²``. On circle ``i`` (``w = r e(τ)``, ``c = cos(τ - α)``) it reads ::

    q(c) = D² c² - 2 r D sin²β c + r² sin²β - D² cos²β ≥ 0,

an upward parabola with roots ``c± = (r sin²β ± cos β sqrt(D² - r² sin²β)) / D``: it holds for
``c ≤ c-`` or ``c ≥ c+``, bounded by the four bearings ``α ± acos c±``, and everywhere when
``D ≤ r sin β`` (including ``D = 0``: from the same place every incidence is 0). Geometrically
the boundary ``γ = β`` is the pair of circles of radius ``D / (2 sin β)`` through ``o_i`` and
``o_j`` (inscribed angle theorem: their major arcs see ``o_i o_j`` at ``β``, their minor arcs at
``π - β``), and these are its crossings with circle ``i``. The four bearings join the
breakpoints and the condition joins the midpoint test, so the result stays exact; the remainder
may now have up to six pieces (ten boundaries inside the arc).

``β`` is a trade-off, not necessarily the sensor's critical angle: a real echo only says the
wall's normal is within that critical angle of the line of sight, and corners echo from every
direction, so a small ``β`` also spares spurious arcs (``benchmarks/specular.py`` measures it).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from enum import IntEnum
from typing import Any, NamedTuple, TypeVar, cast

import numpy as np
import numpy.typing as npt
from numba import njit

from sonarcarve.typing import FloatArray

__all__ = [
    "MIN_PIECE",
    "NO_INCIDENCE_LIMIT",
    "ArcStatus",
    "CarveOutcome",
    "arc_bounding_circle",
    "arc_remainder",
    "carve_arc",
    "carve_arcs",
]


#: Shortest carved or remaining piece of an arc that counts, radians (shorter ones are slivers of
#: rounding at tangencies; 1e-12 rad is a picometre on a metre-range arc).
MIN_PIECE = 1e-12

#: ``max_incidence`` that switches specular-aware carving off: every incidence is at most π/2,
#: so ``Z_ij^β = Z_ij`` and carving is the paper's (eq. 3.4).
NO_INCIDENCE_LIMIT = 0.5 * math.pi

_TWO_PI = 2.0 * math.pi

# Room in the scratch arrays: lo, hi and at most 2 + 2 + 2 + 4 boundaries inside (disk, two
# half-planes, incidence), so at most 11 sub-intervals.
_SCRATCH = 12

_F = TypeVar("_F", bound=Callable[..., Any])


def _compiled(func: _F) -> _F:
    """``numba.njit(cache=True)``, typed so that mypy keeps the function's signature."""
    return cast(_F, njit(cache=True)(func))


# Outcome codes as plain ints, for the compiled kernels (same values as CarveOutcome).
_UNCHANGED = 0
_SHRUNK = 1
_FULLY_CARVED = 2
_SPLIT = 3

# Modes of one of the three conditions on the circle.
_NONE = 0  # no point of the circle satisfies it
_ALL = 1  # every point does
_SOME = 2  # a circular interval does


class CarveOutcome(IntEnum):
    """What carving one arc by one freespace sector did (section 3)."""

    UNCHANGED = _UNCHANGED  #: the sector does not overlap the arc (beyond a sliver)
    SHRUNK = _SHRUNK  #: the remainder is one shorter interval
    FULLY_CARVED = _FULLY_CARVED  #: the sector covers the whole arc: C'_i is empty
    SPLIT = _SPLIT  #: the remainder is two or more pieces: the arc is dropped (section 3)


class ArcStatus(IntEnum):
    """Whether an arc still yields a point, and if not why (codes match :class:`CarveOutcome`)."""

    ALIVE = _UNCHANGED  #: still in the local map
    FULLY_CARVED = _FULLY_CARVED  #: removed: carving emptied it
    SPLIT = _SPLIT  #: removed: carving would have split it


# -- compiled core -----------------------------------------------------------------------------


@_compiled
def _unwrap_above(angle: float, lo: float) -> float:
    """The representative of ``angle`` (mod 2π) in ``[lo, lo + 2π)``."""
    return angle - math.floor((angle - lo) / _TWO_PI) * _TWO_PI


@_compiled
def _add_cut(cuts: FloatArray, count: int, angle: float, lo: float, hi: float) -> int:
    """Append ``angle`` to ``cuts`` if its representative lies strictly inside ``(lo, hi)``."""
    t = _unwrap_above(angle, lo)
    if lo < t < hi:
        cuts[count] = t
        return count + 1
    return count


@_compiled
def _incidence_sine(max_incidence: float) -> float:
    """``sin β`` for the kernels; 1.0 (no limit) when ``β ≥ π/2``.

    The kernels test ``sin γ ≤ sin β`` only when this is below 1, so ``β = π/2`` runs exactly
    the paper's code path (rounding at ``γ = π/2`` cannot flip a point).
    """
    if max_incidence >= NO_INCIDENCE_LIMIT:
        return 1.0
    return math.sin(max(max_incidence, 0.0))


@_compiled
def _incidence_ok(ox: float, oy: float, px: float, py: float, fx: float, fy: float,
                  sin_beta: float) -> bool:
    """Whether reading ``j`` at ``o_j = f`` sees the surface implied at ``p`` within ``β``.

    ``sin γ ≤ sin β`` with ``γ`` the angle ``o``-``p``-``f`` folded into ``[0, π/2]``, written
    without division: ``(w × v)² ≤ sin²β |w|² |v|²`` for ``w = p - o``, ``v = p - f``.
    """
    if sin_beta >= 1.0:
        return True
    wx = px - ox
    wy = py - oy
    vx = px - fx
    vy = py - fy
    cross = wx * vy - wy * vx
    return cross * cross <= sin_beta * sin_beta * (wx * wx + wy * wy) * (vx * vx + vy * vy)


@_compiled
def _sort_prefix(values: FloatArray, count: int) -> None:
    """Insertion sort of ``values[:count]`` (at most 12 values: cheaper than a library sort)."""
    for i in range(1, count):
        v = values[i]
        j = i - 1
        while j >= 0 and values[j] > v:
            values[j + 1] = values[j]
            j -= 1
        values[j + 1] = v


@_compiled
def _merge_runs(starts: FloatArray, ends: FloatArray, flags: npt.NDArray[np.bool_],
                count: int) -> int:
    """Merge neighbouring runs with equal flags in place; return the new count."""
    if count == 0:
        return 0
    out = 0
    for i in range(1, count):
        if flags[i] == flags[out]:
            ends[out] = ends[i]
        else:
            out += 1
            starts[out] = starts[i]
            ends[out] = ends[i]
            flags[out] = flags[i]
    return out + 1


@_compiled
def _remainder_core(
    ox: float, oy: float, r: float, lo: float, hi: float,
    fx: float, fy: float, radius: float,
    a1: float, u1x: float, u1y: float, a2: float, u2x: float, u2y: float, sin_beta: float,
    cuts: FloatArray, starts: FloatArray, ends: FloatArray, flags: npt.NDArray[np.bool_],
) -> int:
    """Pieces of ``[lo, hi]`` outside ``Z_ij^β``, written to ``starts``/``ends``; their count.

    ``radius`` is the freespace radius ``R = r_j - ε``; ``(u1x, u1y)`` and ``(u2x, u2y)`` are the
    unit vectors of the sector's bounding bearings ``a1 = f_lo`` and ``a2 = f_hi`` (hoisted so a
    batch computes them once); ``sin_beta`` is :func:`_incidence_sine` of the critical angle
    (1: the paper). Scratch arrays need room for ``_SCRATCH`` values. Requires ``r > 0``,
    ``hi - lo ≥ MIN_PIECE``.
    """
    # The arc as one remaining run, for the early exits.
    starts[0] = lo
    ends[0] = hi
    if radius <= 0.0:
        return 1
    dx = fx - ox
    dy = fy - oy
    # Disk condition |p(τ) - o_j| < R  <=>  cos(τ - α) > k.
    disk = _SOME
    k = 0.0
    dist2 = dx * dx + dy * dy
    if dist2 == 0.0:
        disk = _ALL if r < radius else _NONE
    else:
        dist = math.sqrt(dist2)
        k = (dist2 + r * r - radius * radius) / (2.0 * r * dist)
        if k >= 1.0:
            disk = _NONE
        elif k <= -1.0:
            disk = _ALL
    if disk == _NONE:
        return 1
    # Half-plane conditions, in the form sin(τ - a1) ≥ s1 and sin(τ - a2) ≤ s2 (p - o_j written
    # as (o_i - o_j) + r e(τ), so u × (p - o_j) = u × (o_i - o_j) + r sin(τ - a)).
    s1 = (u1x * dy - u1y * dx) / r  # = -u1 × (o_i - o_j) / r
    s2 = (u2x * dy - u2y * dx) / r
    hp1 = _ALL if s1 <= -1.0 else (_NONE if s1 >= 1.0 else _SOME)
    hp2 = _ALL if s2 >= 1.0 else (_NONE if s2 <= -1.0 else _SOME)
    if hp1 == _NONE or hp2 == _NONE:
        return 1
    # Incidence condition sin γ ≤ sin β: everywhere on the circle when D ≤ r sin β (module
    # docstring), never nowhere: the points in line with o_i and o_j have γ = 0.
    rsb2 = r * r * sin_beta * sin_beta
    incidence = _SOME if sin_beta < 1.0 and dist2 > rsb2 else _ALL

    cuts[0] = lo
    n = 1
    # Direction of o_j from o_i (cos α, sin α), for the disk test below without more trig.
    ca = 0.0
    sa = 0.0
    alpha = 0.0
    if disk == _SOME or incidence == _SOME:
        dist = math.sqrt(dist2)
        ca = dx / dist
        sa = dy / dist
        alpha = math.atan2(dy, dx)
    if disk == _SOME:
        half = math.acos(k)
        n = _add_cut(cuts, n, alpha - half, lo, hi)
        n = _add_cut(cuts, n, alpha + half, lo, hi)
    if incidence == _SOME:
        # Roots c± of q(c) = 0 (module docstring): four bearings α ± acos c±.
        cos_beta = math.sqrt((1.0 - sin_beta) * (1.0 + sin_beta))
        root = cos_beta * math.sqrt(dist2 - rsb2)
        for c in ((r * sin_beta * sin_beta + root) / dist, (r * sin_beta * sin_beta - root) / dist):
            half = math.acos(min(max(c, -1.0), 1.0))
            n = _add_cut(cuts, n, alpha - half, lo, hi)
            n = _add_cut(cuts, n, alpha + half, lo, hi)
    if hp1 == _SOME:
        b = math.asin(s1)
        n = _add_cut(cuts, n, a1 + b, lo, hi)
        n = _add_cut(cuts, n, a1 + math.pi - b, lo, hi)
    if hp2 == _SOME:
        b = math.asin(s2)
        n = _add_cut(cuts, n, a2 + b, lo, hi)
        n = _add_cut(cuts, n, a2 + math.pi - b, lo, hi)
    cuts[n] = hi
    n += 1
    _sort_prefix(cuts, n)

    # Membership is constant between consecutive cuts: test each sub-interval's middle m, with
    # cos(m - α) and sin(m - a) expanded over (cos m, sin m) so each test costs one sin/cos pair.
    runs = n - 1
    for i in range(runs):
        m = 0.5 * (cuts[i] + cuts[i + 1])
        cm = math.cos(m)
        sm = math.sin(m)
        inside = True
        if disk == _SOME:
            inside = cm * ca + sm * sa > k
        if inside and hp1 == _SOME:
            inside = sm * u1x - cm * u1y >= s1
        if inside and hp2 == _SOME:
            inside = sm * u2x - cm * u2y <= s2
        if inside and incidence == _SOME:
            # sin²γ = (w × v)² / (|w|² |v|²) with w = r e(m), v = w - d: w × v = -r (e(m) × d).
            cross = cm * dy - sm * dx
            vx = r * cm - dx
            vy = r * sm - dy
            inside = cross * cross <= sin_beta * sin_beta * (vx * vx + vy * vy)
        starts[i] = cuts[i]
        ends[i] = cuts[i + 1]
        flags[i] = inside
    runs = _merge_runs(starts, ends, flags, runs)
    # Slivers: first ignore carved slivers (a touch is not a cut), then remaining slivers.
    for i in range(runs):
        if flags[i] and ends[i] - starts[i] < MIN_PIECE:
            flags[i] = False
    runs = _merge_runs(starts, ends, flags, runs)
    for i in range(runs):
        if not flags[i] and ends[i] - starts[i] < MIN_PIECE:
            flags[i] = True
    runs = _merge_runs(starts, ends, flags, runs)
    count = 0
    for i in range(runs):
        if not flags[i]:
            starts[count] = starts[i]
            ends[count] = ends[i]
            count += 1
    return count


@_compiled
def _point_in_sector(px: float, py: float, fx: float, fy: float, radius: float,
                     u1x: float, u1y: float, u2x: float, u2y: float) -> bool:
    """Whether ``p`` is in the sector (open disk, closed wedge narrower than π)."""
    vx = px - fx
    vy = py - fy
    return (vx * vx + vy * vy < radius * radius and u1x * vy - u1y * vx >= 0.0
            and vx * u2y - vy * u2x >= 0.0)


@_compiled
def _carve_core(
    ox: float, oy: float, r: float, lo: float, hi: float,
    fx: float, fy: float, radius: float,
    a1: float, u1x: float, u1y: float, a2: float, u2x: float, u2y: float, sin_beta: float,
    cuts: FloatArray, starts: FloatArray, ends: FloatArray, flags: npt.NDArray[np.bool_],
) -> tuple[int, float, float]:
    """:func:`carve_arc` with the sector's unit vectors hoisted and scratch arrays supplied."""
    if hi - lo < MIN_PIECE:
        m = 0.5 * (lo + hi)
        px = ox + r * math.cos(m)
        py = oy + r * math.sin(m)
        if (radius > 0.0 and _point_in_sector(px, py, fx, fy, radius, u1x, u1y, u2x, u2y)
                and _incidence_ok(ox, oy, px, py, fx, fy, sin_beta)):
            return _FULLY_CARVED, lo, hi
        return _UNCHANGED, lo, hi
    count = _remainder_core(ox, oy, r, lo, hi, fx, fy, radius, a1, u1x, u1y, a2, u2x, u2y,
                            sin_beta, cuts, starts, ends, flags)
    if count == 0:
        return _FULLY_CARVED, lo, hi
    if count >= 2:
        return _SPLIT, lo, hi
    if starts[0] == lo and ends[0] == hi:
        return _UNCHANGED, lo, hi
    return _SHRUNK, starts[0], ends[0]


@_compiled
def carve_arc(
    ox: float, oy: float, r: float, lo: float, hi: float,
    fx: float, fy: float, fr: float, f_lo: float, f_hi: float,
    tolerance: float = 0.0, max_incidence: float = NO_INCIDENCE_LIMIT,
) -> tuple[int, float, float]:
    """Carve arc ``i`` by the freespace of a newer reading ``j``: ``C_i - Z_ij`` (eq. 3.4, 3.5).

    With ``max_incidence = β < π/2`` only ``Z_ij^β`` is carved: the points of ``Z_ij`` whose
    implied surface reading ``j`` would see within ``β`` of its normal (specular-aware carving,
    beyond the paper; see the module docstring).

    Parameters
    ----------
    ox, oy, r : float
        Arc ``i``: circle centre (sensor origin, metres) and radius ``r > 0`` (range, metres).
    lo, hi : float
        Its current bearings ``[θ1, θ2]`` (eq. 3.1), radians, ``0 ≤ hi - lo < 2π``.
    fx, fy, fr : float
        Reading ``j``: origin and range, metres.
    f_lo, f_hi : float
        Its full beam ``[θ_j - φ_j/2, θ_j + φ_j/2]``, radians, ``0 ≤ f_hi - f_lo < π``.
    tolerance : float
        Range tolerance ε ≥ 0, metres: the freespace (eq. 3.2) ends at ``fr - ε``.
    max_incidence : float
        Critical angle β in ``[0, π/2]``, radians: points whose incidence ``γ`` seen from
        ``o_j`` exceeds it are not carved. :data:`NO_INCIDENCE_LIMIT` (π/2, the default): the
        paper.

    Returns
    -------
    status : int
        A :class:`CarveOutcome` code.
    new_lo, new_hi : float
        The remaining interval if ``SHRUNK``; ``lo, hi`` unchanged otherwise (also when the arc
        is fully carved or split: the caller drops it).

    Examples
    --------
    A reading from the same place with a longer range fully carves an arc (eq. 3.2):

    >>> status, _, _ = carve_arc(0.0, 0.0, 1.0, -0.2, 0.2, 0.0, 0.0, 2.0, -0.3, 0.3)
    >>> CarveOutcome(status).name
    'FULLY_CARVED'

    A beam overlapping half of it shrinks it to the other half:

    >>> status, lo, hi = carve_arc(0.0, 0.0, 1.0, -0.2, 0.2, 0.0, 0.0, 2.0, 0.0, 0.3)
    >>> CarveOutcome(status).name, round(lo, 12), round(hi, 12)
    ('SHRUNK', -0.2, 0.0)

    A wall seen head-on from the origin at 1 m, then from (0, 0.9) at a glancing angle by a
    reading that heard nothing up to 3 m: the paper carves the arc away, a 20° critical angle
    keeps it (from (0, 0.9) the implied wall is seen at 39°-45° incidence):

    >>> args = (0.0, 0.0, 1.0, -0.1, 0.1, 0.0, 0.9, 3.0, -0.9, -0.5)
    >>> CarveOutcome(carve_arc(*args)[0]).name
    'FULLY_CARVED'
    >>> CarveOutcome(carve_arc(*args, 0.0, math.radians(20.0))[0]).name
    'UNCHANGED'
    """
    cuts = np.empty(_SCRATCH)
    starts = np.empty(_SCRATCH)
    ends = np.empty(_SCRATCH)
    flags = np.empty(_SCRATCH, dtype=np.bool_)
    return _carve_core(ox, oy, r, lo, hi, fx, fy, fr - tolerance,
                       f_lo, math.cos(f_lo), math.sin(f_lo), f_hi, math.cos(f_hi), math.sin(f_hi),
                       _incidence_sine(max_incidence), cuts, starts, ends, flags)


@_compiled
def _remainder_pieces(
    ox: float, oy: float, r: float, lo: float, hi: float,
    fx: float, fy: float, fr: float, f_lo: float, f_hi: float, tolerance: float,
    max_incidence: float,
) -> FloatArray:
    cuts = np.empty(_SCRATCH)
    starts = np.empty(_SCRATCH)
    ends = np.empty(_SCRATCH)
    flags = np.empty(_SCRATCH, dtype=np.bool_)
    radius = fr - tolerance
    u1x, u1y, u2x, u2y = math.cos(f_lo), math.sin(f_lo), math.cos(f_hi), math.sin(f_hi)
    sin_beta = _incidence_sine(max_incidence)
    if hi - lo < MIN_PIECE:
        status, _, _ = _carve_core(ox, oy, r, lo, hi, fx, fy, radius, f_lo, u1x, u1y, f_hi, u2x,
                                   u2y, sin_beta, cuts, starts, ends, flags)
        count = 0 if status == _FULLY_CARVED else 1
        starts[0] = lo
        ends[0] = hi
    else:
        count = _remainder_core(ox, oy, r, lo, hi, fx, fy, radius, f_lo, u1x, u1y, f_hi, u2x,
                                u2y, sin_beta, cuts, starts, ends, flags)
    out = np.empty((count, 2))
    for i in range(count):
        out[i, 0] = starts[i]
        out[i, 1] = ends[i]
    return out


def arc_remainder(
    ox: float, oy: float, r: float, lo: float, hi: float,
    fx: float, fy: float, fr: float, f_lo: float, f_hi: float,
    tolerance: float = 0.0, max_incidence: float = NO_INCIDENCE_LIMIT,
) -> FloatArray:
    """Every piece of the remainder ``[lo, hi] \\ Z_ij`` (eq. 3.4, 3.5), split or not.

    Same parameters as :func:`carve_arc` (with ``max_incidence < π/2``: ``[lo, hi] \\
    Z_ij^β``). Returns an array of shape (n, 2), n in 0..6 (0..4 in the paper's mode), of
    ``[start, end]`` bearings in increasing order; n = 0 means fully carved, n ≥ 2 split.

    Examples
    --------
    A beam across the middle of a wide arc, from a closer origin, splits it:

    >>> arc_remainder(0.0, 0.0, 2.0, -0.4, 0.4, 1.0, 0.0, 5.0, -0.05, 0.05).round(3).tolist()
    [[-0.4, -0.025], [0.025, 0.4]]
    """
    return np.asarray(_remainder_pieces(float(ox), float(oy), float(r), float(lo), float(hi),
                                        float(fx), float(fy), float(fr), float(f_lo),
                                        float(f_hi), float(tolerance), float(max_incidence)))


@_compiled
def arc_bounding_circle(ox: float, oy: float, r: float, lo: float,
                        hi: float) -> tuple[float, float, float]:
    """A circle that contains the arc ``o + r e(τ)``, ``τ ∈ [lo, hi]`` (eq. 3.1).

    For a half-width ``β = (hi - lo)/2 ≤ π/2`` it is the circle on the chord: centre
    ``o + r cos β e(mid)``, radius ``r sin β`` (every point of the arc is within half a chord of
    the chord's middle because the sagitta ``r (1 - cos β)`` is at most ``r sin β``). Wider arcs
    get the arc's own circle, radius ``r``. The radius is padded by ``1e-9 r`` so that tests
    against it stay conservative under rounding.

    Returns
    -------
    cx, cy, radius : float
        Centre and radius, metres.
    """
    half = 0.5 * (hi - lo)
    if half > 0.5 * math.pi:
        return ox, oy, r * (1.0 + 1e-9)
    mid = 0.5 * (lo + hi)
    reach = r * math.cos(half)
    return (ox + reach * math.cos(mid), oy + reach * math.sin(mid),
            r * math.sin(half) + 1e-9 * r)


@_compiled
def carve_arcs(
    slots: npt.NDArray[np.int64],
    x: FloatArray, y: FloatArray, r: FloatArray,
    lo: FloatArray, hi: FloatArray, bounds: FloatArray,
    status: npt.NDArray[np.int8], carved: npt.NDArray[np.bool_],
    fx: float, fy: float, fr: float, f_lo: float, f_hi: float,
    tolerance: float, max_incidence: float = NO_INCIDENCE_LIMIT,
) -> tuple[int, int]:
    """Carve many arcs by one newer reading's freespace, in place (eq. 3.5, section 5-A).

    Each arc is first tested against the sector through its bounding circle (kept in
    ``bounds``): a circle clear of the disk or of one bounding half-plane leaves the arc
    unchanged, a circle inside the sector means the arc is fully carved; only the remaining arcs
    need :func:`carve_arc`'s exact, trigonometric path (5 % of the live arcs on the ring-corridor
    stream of ``benchmarks/synthetic.py``, counted over 600 readings at history 250). Both
    shortcuts are exact: the circle contains the arc. With ``max_incidence = β < π/2`` a circle
    inside the sector fully carves the arc only if every point ``p`` of the arc also has
    ``sin γ(p) ≤ sin β``; that is certain when ``D = |o_i - o_j| ≤ r_i sin β`` (module
    docstring) or, since ``sin γ ≤ D / |p - o_j|`` (law of sines), when ``D ≤ sin β`` times the
    circle's least distance from ``o_j``. Otherwise the exact path decides.

    Parameters
    ----------
    slots : ndarray of int64, shape (m,)
        Rows to carve; rows whose ``status`` is not ``ALIVE`` are skipped.
    x, y, r : ndarray, shape (n,)
        Arc origins and radii by row, metres.
    lo, hi : ndarray, shape (n,)
        Current carved intervals by row, radians; updated in place.
    bounds : ndarray, shape (n, 3)
        ``arc_bounding_circle(x, y, r, lo, hi)`` by row; updated in place with ``lo, hi``.
    status : ndarray of int8, shape (n,)
        :class:`ArcStatus` by row; set to ``FULLY_CARVED`` or ``SPLIT`` when an arc is removed.
    carved : ndarray of bool, shape (n,)
        Set where carving changed an arc (shrunk or removed).
    fx, fy, fr, f_lo, f_hi, tolerance : float
        The newer reading's origin, range, full beam and the range tolerance ε (see
        :func:`carve_arc`).
    max_incidence : float
        Critical angle β, radians (see :func:`carve_arc`; π/2, the default: the paper).

    Returns
    -------
    fully_carved, split : int
        Arcs removed by this call, by cause.
    """
    cuts = np.empty(_SCRATCH)
    starts = np.empty(_SCRATCH)
    ends = np.empty(_SCRATCH)
    flags = np.empty(_SCRATCH, dtype=np.bool_)
    radius = fr - tolerance
    if radius <= 0.0:
        return 0, 0
    sin_beta = _incidence_sine(max_incidence)
    sb2 = sin_beta * sin_beta
    u1x = math.cos(f_lo)
    u1y = math.sin(f_lo)
    u2x = math.cos(f_hi)
    u2y = math.sin(f_hi)
    fully = 0
    split = 0
    for slot in slots:
        if status[slot] != _UNCHANGED:
            continue
        # The bounding circle against the two half-planes and the disk.
        rho = bounds[slot, 2]
        dx = bounds[slot, 0] - fx
        dy = bounds[slot, 1] - fy
        left = u1x * dy - u1y * dx  # u1 × (c - o_j): > 0 left of the f_lo ray
        right = dx * u2y - dy * u2x  # (c - o_j) × u2: > 0 right of the f_hi ray
        if left < -rho or right < -rho:
            continue
        dist2 = dx * dx + dy * dy
        if dist2 >= (radius + rho) * (radius + rho):
            continue
        inside = left > rho and right > rho and radius > rho and dist2 < (radius - rho) ** 2
        if inside and sin_beta < 1.0:
            ex = x[slot] - fx
            ey = y[slot] - fy
            origins2 = ex * ex + ey * ey  # D²
            if origins2 > sb2 * r[slot] * r[slot]:
                clearance = math.sqrt(dist2) - rho
                inside = clearance > 0.0 and origins2 <= sb2 * clearance * clearance
        if inside:
            outcome = _FULLY_CARVED
            new_lo = lo[slot]
            new_hi = hi[slot]
        else:
            outcome, new_lo, new_hi = _carve_core(
                x[slot], y[slot], r[slot], lo[slot], hi[slot], fx, fy, radius,
                f_lo, u1x, u1y, f_hi, u2x, u2y, sin_beta, cuts, starts, ends, flags,
            )
        if outcome == _UNCHANGED:
            continue
        carved[slot] = True
        if outcome == _SHRUNK:
            lo[slot] = new_lo
            hi[slot] = new_hi
            bounds[slot, 0], bounds[slot, 1], bounds[slot, 2] = arc_bounding_circle(
                x[slot], y[slot], r[slot], new_lo, new_hi)
        elif outcome == _FULLY_CARVED:
            status[slot] = _FULLY_CARVED
            fully += 1
        else:
            status[slot] = _SPLIT
            split += 1
    return fully, split


# --- circle-circle intersections (ATM) ---
#
# Two circles (o1, r1), (o2, r2) with d = |o2 - o1| meet iff |r1 - r2| ≤ d ≤ r1 + r2 (d > 0).
# The common chord crosses the line of centres at a = (d² + r1² - r2²) / 2d from o1, with
# half-length h = sqrt(r1² - a²); the angle γ between the radii at either point follows from
# the law of cosines in the triangle o1 o2 p: cos γ = (r1² + r2² - d²) / (2 r1 r2). The ATM
# transversal angle is γ folded into [0, π/2], i.e. acos |cos γ| (paper, section 2-D).

__all__ += ["CircleIntersections", "circle_intersections", "circle_pair", "common_chord"]


class CircleIntersections(NamedTuple):
    """Intersections of pairs of circles, arrays with the pair axis first.

    Point ``k`` of pair ``i`` is ``o1 + r1 (cos b1, sin b1)`` with ``b1 = bearing1[i, k]`` and is
    the same point as ``o2 + r2 (cos b2, sin b2)`` with ``b2 = bearing2[i, k]``.

    Attributes
    ----------
    meets : ndarray of bool, shape (n,)
        Whether the circles meet (tangent circles give two equal points). Concentric circles
        never meet here, even when they coincide: they never cross.
    bearing1, bearing2 : ndarray, shape (n, 2)
        Bearings of the two points seen from each centre, radians, not wrapped (NaN where
        they do not meet).
    transversal : ndarray, shape (n,)
        Angle between the two radii at the points, folded into ``[0, π/2]`` (the same at both
        points, by symmetry about the line of centres), radians; NaN where they do not meet.
    """

    meets: npt.NDArray[np.bool_]
    bearing1: FloatArray
    bearing2: FloatArray
    transversal: FloatArray


@_compiled
def common_chord(d2: float, r1: float, r2: float) -> tuple[float, float]:
    """``(a, h)`` of the common chord of two circles whose centres are ``sqrt(d2) > 0`` apart.

    The chord crosses the line of centres at ``a = (d² + r1² - r2²) / 2d`` from centre 1 and has
    half-length ``h = sqrt(r1² - a²)`` (0 if the circles only touch); the crossings are
    ``o1 + a u ± h u⊥`` with ``u`` the unit vector from centre 1 to centre 2. Only meaningful
    where the circles meet.
    """
    d = math.sqrt(d2)
    a = (d2 + r1 * r1 - r2 * r2) / (2.0 * d)
    return a, math.sqrt(max(r1 * r1 - a * a, 0.0))


@_compiled
def circle_pair(
    x1: float, y1: float, r1: float, x2: float, y2: float, r2: float
) -> tuple[bool, float, float, float, float]:
    """Closed-form crossing of circles 1 and 2 (compiled scalar kernel).

    Returns ``(meets, α, β1, β2, |cos γ|)``: ``α`` is the bearing of centre 2 from centre 1;
    the two points are at bearings ``α ± β1`` from centre 1 and ``α + π ∓ β2`` from centre 2
    (same sign order); ``γ`` is the angle between the radii at either point. Where the circles
    do not meet (or are concentric) ``meets`` is False and the rest is ``(0, 0, 0, 1)``.
    """
    dx = x2 - x1
    dy = y2 - y1
    d2 = dx * dx + dy * dy
    d = math.sqrt(d2)
    if d == 0.0 or d > r1 + r2 or d < abs(r1 - r2):
        return False, 0.0, 0.0, 0.0, 1.0
    a, h = common_chord(d2, r1, r2)
    cos_gamma = (r1 * r1 + r2 * r2 - d2) / (2.0 * r1 * r2)
    return True, math.atan2(dy, dx), math.atan2(h, a), math.atan2(h, d - a), abs(cos_gamma)


@_compiled
def _circle_pairs(
    x1: FloatArray, y1: FloatArray, r1: FloatArray, x2: FloatArray, y2: FloatArray, r2: FloatArray
) -> tuple[npt.NDArray[np.bool_], FloatArray, FloatArray, FloatArray]:
    n = x1.shape[0]
    meets = np.zeros(n, dtype=np.bool_)
    b1 = np.full((n, 2), np.nan)
    b2 = np.full((n, 2), np.nan)
    transversal = np.full(n, np.nan)
    for i in range(n):
        meet, alpha, beta1, beta2, abs_cos = circle_pair(x1[i], y1[i], r1[i], x2[i], y2[i], r2[i])
        if not meet:
            continue
        meets[i] = True
        b1[i, 0] = alpha + beta1
        b1[i, 1] = alpha - beta1
        b2[i, 0] = alpha + math.pi - beta2
        b2[i, 1] = alpha + math.pi + beta2
        transversal[i] = math.acos(min(abs_cos, 1.0))
    return meets, b1, b2, transversal


def circle_intersections(
    o1: npt.ArrayLike, r1: npt.ArrayLike, o2: npt.ArrayLike, r2: npt.ArrayLike
) -> CircleIntersections:
    """Closed-form intersections of circles ``(o1, r1)`` and ``(o2, r2)``, pair by pair.

    See the comment above :class:`CircleIntersections` for the formulas (ATM, section 2-D).

    Parameters
    ----------
    o1, o2 : array-like, shape (n, 2) or (2,)
        Centres, metres.
    r1, r2 : array-like, shape (n,) or scalar
        Radii, metres (> 0).

    Examples
    --------
    >>> hit = circle_intersections([0.0, 0.0], 1.0, [1.0, 0.0], 1.0)
    >>> hit.meets.tolist(), np.round(np.degrees(hit.bearing1), 6).tolist()
    ([True], [[60.0, -60.0]])
    >>> round(float(np.degrees(hit.transversal[0])), 6)  # radii meet at 120°, folded to 60°
    60.0
    >>> circle_intersections([0.0, 0.0], 1.0, [3.0, 0.0], 1.0).meets.tolist()  # too far apart
    [False]
    """
    c1 = np.atleast_2d(np.asarray(o1, dtype=np.float64))
    c2 = np.atleast_2d(np.asarray(o2, dtype=np.float64))
    a1 = np.atleast_1d(np.asarray(r1, dtype=np.float64))
    a2 = np.atleast_1d(np.asarray(r2, dtype=np.float64))
    n = max(c1.shape[0], c2.shape[0], a1.shape[0], a2.shape[0])
    c1, c2 = np.broadcast_to(c1, (n, 2)), np.broadcast_to(c2, (n, 2))
    a1, a2 = np.broadcast_to(a1, (n,)), np.broadcast_to(a2, (n,))
    meets, b1, b2, transversal = _circle_pairs(
        np.ascontiguousarray(c1[:, 0]), np.ascontiguousarray(c1[:, 1]), np.ascontiguousarray(a1),
        np.ascontiguousarray(c2[:, 0]), np.ascontiguousarray(c2[:, 1]), np.ascontiguousarray(a2),
    )
    return CircleIntersections(meets, b1, b2, transversal)
