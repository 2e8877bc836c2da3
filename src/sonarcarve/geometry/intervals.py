"""Carving an arc by a newer reading's freespace, in closed form (paper, eq. 3.2-3.5).

An *arc* ``C_i`` (eq. 3.1) is the set of points ``o_i + r_i (cos τ, sin τ)`` for bearings ``τ`` in
``[lo, hi]``, stored unwrapped with ``lo ≤ hi`` and ``hi - lo < 2π`` (a sonar arc has
``hi - lo ≤ φ < π``). The *freespace* ``F_j`` of a reading ``j`` (eq. 3.2) is the sector of its full
beam, with the range shortened by a tolerance ``ε ≥ 0``::

    F_j = {p : |p - o_j| < R_j,  bearing(p - o_j) ∈ [f_lo, f_hi]},   R_j = r_j - ε,

with ``0 ≤ f_hi - f_lo < π``. ``ε = 0`` is the paper's set exactly (the open disk makes an arc
that merely *touches* the echo circle of ``j`` survive; the paper's closed ``≤ r`` differs only on
that measure-zero set).

Everything is closed form, never sampled. On circle ``i``, each of the three conditions that make
up ``F_j`` is one *circular interval* of ``τ`` (:func:`_conditions`):

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
inside ``(lo, hi)`` (:func:`_collect_cuts`), sorts them with ``lo`` and ``hi``, and tests the
middle of each sub-interval against the three conditions (:func:`_midpoint_inside`): membership
is constant between consecutive boundaries, so this is exact, and it is robust to every
coincidence of boundaries. The remainder ``[lo, hi] \\ Z_ij`` is then read off as runs of
non-member sub-intervals (eq. 3.5, one ``j`` at a time). Specular-aware carving adds a fourth
condition (:mod:`sonarcarve.geometry.specular`), with its own cuts and membership test beside
the paper's.

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
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.geometry.bounds import UNDECIDED, arc_bounding_circle, circle_against_sector
from sonarcarve.geometry.circular import (
    ALL,
    NONE,
    SOME,
    add_cut,
    merge_runs,
    new_scratch,
    sort_prefix,
)
from sonarcarve.geometry.fate import FULLY_CARVED, SHRUNK, SPLIT, UNCHANGED
from sonarcarve.geometry.sector import Sector, make_sector, point_in_sector
from sonarcarve.geometry.specular import (
    NO_INCIDENCE_LIMIT,
    add_incidence_cuts,
    incidence_member,
    incidence_mode,
    incidence_ok,
)
from sonarcarve.typing import BoolArray, FloatArray, Int8Array, IntArray

__all__ = ["MIN_PIECE", "arc_remainder", "carve_arc", "carve_arcs", "carve_core"]

#: Shortest carved or remaining piece of an arc that counts, radians (shorter ones are slivers of
#: rounding at tangencies; 1e-12 rad is a picometre on a metre-range arc).
MIN_PIECE = 1e-12


# -- the conditions of a sector on circle i ----------------------------------------------------


class _Conditions(NamedTuple):
    """The sector's conditions on circle ``i`` (module docstring): modes and their constants."""

    dx: float  # d = o_j - o_i
    dy: float
    dist2: float  # D²
    disk: int  # cos(τ - α) > k
    k: float
    hp1: int  # sin(τ - f_lo) ≥ s1
    s1: float
    hp2: int  # sin(τ - f_hi) ≤ s2
    s2: float
    incidence: int  # sin γ ≤ sin β (specular.py)
    ca: float  # (cos α, sin α) and α, the direction of o_j from o_i (0 unless needed)
    sa: float
    alpha: float


@compiled_inline
def _disk_condition(dist2: float, r: float, radius: float) -> tuple[int, float]:
    """Mode of ``|p(τ) - o_j| < R`` on circle ``i`` and its ``k`` (``cos(τ - α) > k``)."""
    if dist2 == 0.0:
        return (ALL if r < radius else NONE), 0.0
    dist = math.sqrt(dist2)
    k = (dist2 + r * r - radius * radius) / (2.0 * r * dist)
    if k >= 1.0:
        return NONE, k
    if k <= -1.0:
        return ALL, k
    return SOME, k


@compiled_inline
def _conditions(ox: float, oy: float, r: float, sector: Sector) -> _Conditions:
    """The conditions of ``sector`` on the circle ``(ox, oy, r)``; stops at the first ``NONE``."""
    dx = sector.fx - ox
    dy = sector.fy - oy
    dist2 = dx * dx + dy * dy
    disk, k = _disk_condition(dist2, r, sector.radius)
    if disk == NONE:
        return _Conditions(dx, dy, dist2, disk, k, NONE, 0.0, NONE, 0.0, ALL, 0.0, 0.0, 0.0)
    # Half-planes in the form sin(τ - a1) ≥ s1 and sin(τ - a2) ≤ s2 (p - o_j written as
    # (o_i - o_j) + r e(τ), so u × (p - o_j) = u × (o_i - o_j) + r sin(τ - a)).
    s1 = (sector.u1x * dy - sector.u1y * dx) / r  # = -u1 × (o_i - o_j) / r
    s2 = (sector.u2x * dy - sector.u2y * dx) / r
    hp1 = ALL if s1 <= -1.0 else (NONE if s1 >= 1.0 else SOME)
    hp2 = ALL if s2 >= 1.0 else (NONE if s2 <= -1.0 else SOME)
    if hp1 == NONE or hp2 == NONE:
        return _Conditions(dx, dy, dist2, disk, k, hp1, s1, hp2, s2, ALL, 0.0, 0.0, 0.0)
    incidence = incidence_mode(sector.sin_beta, r, dist2)
    ca = 0.0
    sa = 0.0
    alpha = 0.0
    if disk == SOME or incidence == SOME:
        # For the disk test without more trig (see _midpoint_inside) and for the cuts.
        dist = math.sqrt(dist2)
        ca = dx / dist
        sa = dy / dist
        alpha = math.atan2(dy, dx)
    return _Conditions(dx, dy, dist2, disk, k, hp1, s1, hp2, s2, incidence, ca, sa, alpha)


@compiled_inline
def _collect_cuts(cond: _Conditions, r: float, lo: float, hi: float, sector: Sector,
                  cuts: FloatArray) -> int:
    """``lo``, the conditions' boundary bearings inside ``(lo, hi)`` and ``hi``, sorted; count."""
    cuts[0] = lo
    n = 1
    if cond.disk == SOME:
        half = math.acos(cond.k)
        n = add_cut(cuts, n, cond.alpha - half, lo, hi)
        n = add_cut(cuts, n, cond.alpha + half, lo, hi)
    if cond.incidence == SOME:
        n = add_incidence_cuts(cuts, n, r, cond.dist2, cond.alpha, sector.sin_beta, lo, hi)
    if cond.hp1 == SOME:
        b = math.asin(cond.s1)
        n = add_cut(cuts, n, sector.a1 + b, lo, hi)
        n = add_cut(cuts, n, sector.a1 + math.pi - b, lo, hi)
    if cond.hp2 == SOME:
        b = math.asin(cond.s2)
        n = add_cut(cuts, n, sector.a2 + b, lo, hi)
        n = add_cut(cuts, n, sector.a2 + math.pi - b, lo, hi)
    cuts[n] = hi
    n += 1
    sort_prefix(cuts, n)
    return n


@compiled_inline
def _midpoint_inside(m: float, cond: _Conditions, r: float, sector: Sector) -> bool:
    """Whether the point at bearing ``m`` of circle ``i`` is in ``Z_ij`` (or ``Z_ij^β``).

    ``cos(m - α)`` and ``sin(m - a)`` are expanded over ``(cos m, sin m)`` so that each test
    costs one sin/cos pair.
    """
    cm = math.cos(m)
    sm = math.sin(m)
    inside = True
    if cond.disk == SOME:
        inside = cm * cond.ca + sm * cond.sa > cond.k
    if inside and cond.hp1 == SOME:
        inside = sm * sector.u1x - cm * sector.u1y >= cond.s1
    if inside and cond.hp2 == SOME:
        inside = sm * sector.u2x - cm * sector.u2y <= cond.s2
    if inside and cond.incidence == SOME:
        inside = incidence_member(cm, sm, r, cond.dx, cond.dy, sector.sin_beta)
    return inside


@compiled_inline
def _drop_slivers(starts: FloatArray, ends: FloatArray, flags: BoolArray, runs: int) -> int:
    """Ignore carved slivers (a touch is not a cut), then remaining ones; the new run count."""
    for i in range(runs):
        if flags[i] and ends[i] - starts[i] < MIN_PIECE:
            flags[i] = False
    runs = merge_runs(starts, ends, flags, runs)
    for i in range(runs):
        if not flags[i] and ends[i] - starts[i] < MIN_PIECE:
            flags[i] = True
    return merge_runs(starts, ends, flags, runs)


@compiled_inline
def _remainder_core(ox: float, oy: float, r: float, lo: float, hi: float, sector: Sector,
                    cuts: FloatArray, starts: FloatArray, ends: FloatArray,
                    flags: BoolArray) -> int:
    """Pieces of ``[lo, hi]`` outside ``Z_ij^β``, written to ``starts``/``ends``; their count.

    ``cuts, starts, ends, flags`` are the arrays of a :class:`~sonarcarve.geometry.circular.
    Scratch`, passed one by one: the kernels are inlined into their callers and arrays taken
    apart from a record cost reference counting in the hot loop. Requires ``r > 0`` and
    ``hi - lo ≥ MIN_PIECE``.
    """
    # The arc as one remaining run, for the early exits.
    starts[0] = lo
    ends[0] = hi
    if sector.radius <= 0.0:
        return 1
    cond = _conditions(ox, oy, r, sector)
    if cond.disk == NONE or cond.hp1 == NONE or cond.hp2 == NONE:
        return 1
    runs = _collect_cuts(cond, r, lo, hi, sector, cuts) - 1
    # Membership is constant between consecutive cuts: test each sub-interval's middle.
    for i in range(runs):
        starts[i] = cuts[i]
        ends[i] = cuts[i + 1]
        flags[i] = _midpoint_inside(0.5 * (cuts[i] + cuts[i + 1]), cond, r, sector)
    runs = _drop_slivers(starts, ends, flags, merge_runs(starts, ends, flags, runs))
    count = 0
    for i in range(runs):
        if not flags[i]:
            starts[count] = starts[i]
            ends[count] = ends[i]
            count += 1
    return count


# -- one arc -----------------------------------------------------------------------------------


@compiled
def _carve_point(ox: float, oy: float, r: float, m: float, sector: Sector) -> int:
    """Fate of a zero-length arc, the point at bearing ``m``: fully carved iff it is carved."""
    px = ox + r * math.cos(m)
    py = oy + r * math.sin(m)
    if (sector.radius > 0.0 and point_in_sector(px, py, sector)
            and incidence_ok(ox, oy, px, py, sector.fx, sector.fy, sector.sin_beta)):
        return FULLY_CARVED
    return UNCHANGED


@compiled_inline
def carve_core(ox: float, oy: float, r: float, lo: float, hi: float, sector: Sector,
               cuts: FloatArray, starts: FloatArray, ends: FloatArray,
               flags: BoolArray) -> tuple[int, float, float]:
    """:func:`carve_arc` for a prepared sector and supplied scratch arrays (see
    :func:`_remainder_core`)."""
    if hi - lo < MIN_PIECE:
        return _carve_point(ox, oy, r, 0.5 * (lo + hi), sector), lo, hi
    count = _remainder_core(ox, oy, r, lo, hi, sector, cuts, starts, ends, flags)
    if count == 0:
        return FULLY_CARVED, lo, hi
    if count >= 2:
        return SPLIT, lo, hi
    if starts[0] == lo and ends[0] == hi:
        return UNCHANGED, lo, hi
    return SHRUNK, starts[0], ends[0]


@compiled
def carve_arc(
    ox: float, oy: float, r: float, lo: float, hi: float,
    fx: float, fy: float, fr: float, f_lo: float, f_hi: float,
    tolerance: float = 0.0, max_incidence: float = NO_INCIDENCE_LIMIT,
) -> tuple[int, float, float]:
    """Carve arc ``i`` by the freespace of a newer reading ``j``: ``C_i - Z_ij`` (eq. 3.4, 3.5).

    With ``max_incidence = β < π/2`` only ``Z_ij^β`` is carved: the points of ``Z_ij`` whose
    implied surface reading ``j`` would see within ``β`` of its normal (specular-aware carving,
    beyond the paper; see :mod:`sonarcarve.geometry.specular`).

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
    fate : int
        An :class:`~sonarcarve.geometry.ArcFate` code.
    new_lo, new_hi : float
        The remaining interval if ``SHRUNK``; ``lo, hi`` unchanged otherwise (also when the arc
        is fully carved or split: the caller drops it).

    Examples
    --------
    A reading from the same place with a longer range fully carves an arc (eq. 3.2):

    >>> from sonarcarve.geometry import ArcFate
    >>> fate, _, _ = carve_arc(0.0, 0.0, 1.0, -0.2, 0.2, 0.0, 0.0, 2.0, -0.3, 0.3)
    >>> ArcFate(fate).name
    'FULLY_CARVED'

    A beam overlapping half of it shrinks it to the other half:

    >>> fate, lo, hi = carve_arc(0.0, 0.0, 1.0, -0.2, 0.2, 0.0, 0.0, 2.0, 0.0, 0.3)
    >>> ArcFate(fate).name, round(lo, 12), round(hi, 12)
    ('SHRUNK', -0.2, 0.0)

    A wall seen head-on from the origin at 1 m, then from (0, 0.9) at a glancing angle by a
    reading that heard nothing up to 3 m: the paper carves the arc away, a 20° critical angle
    keeps it (from (0, 0.9) the implied wall is seen at 39°-45° incidence):

    >>> args = (0.0, 0.0, 1.0, -0.1, 0.1, 0.0, 0.9, 3.0, -0.9, -0.5)
    >>> ArcFate(carve_arc(*args)[0]).name
    'FULLY_CARVED'
    >>> ArcFate(carve_arc(*args, 0.0, math.radians(20.0))[0]).name
    'UNCHANGED'
    """
    sector = make_sector(fx, fy, fr, f_lo, f_hi, tolerance, max_incidence)
    cuts, starts, ends, flags = new_scratch()
    return carve_core(ox, oy, r, lo, hi, sector, cuts, starts, ends, flags)


@compiled
def _remainder_pieces(
    ox: float, oy: float, r: float, lo: float, hi: float,
    fx: float, fy: float, fr: float, f_lo: float, f_hi: float, tolerance: float,
    max_incidence: float,
) -> FloatArray:
    scratch = new_scratch()
    sector = make_sector(fx, fy, fr, f_lo, f_hi, tolerance, max_incidence)
    if hi - lo < MIN_PIECE:
        fate = _carve_point(ox, oy, r, 0.5 * (lo + hi), sector)
        count = 0 if fate == FULLY_CARVED else 1
        scratch.starts[0] = lo
        scratch.ends[0] = hi
    else:
        count = _remainder_core(ox, oy, r, lo, hi, sector, scratch.cuts, scratch.starts,
                                scratch.ends, scratch.flags)
    out = np.empty((count, 2))
    for i in range(count):
        out[i, 0] = scratch.starts[i]
        out[i, 1] = scratch.ends[i]
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


# -- many arcs ---------------------------------------------------------------------------------


@compiled
def carve_arcs(
    slots: IntArray,
    x: FloatArray, y: FloatArray, r: FloatArray,
    lo: FloatArray, hi: FloatArray, bounds: FloatArray,
    status: Int8Array, carved: BoolArray,
    fx: float, fy: float, fr: float, f_lo: float, f_hi: float,
    tolerance: float, max_incidence: float = NO_INCIDENCE_LIMIT,
) -> tuple[int, int]:
    """Carve many arcs by one newer reading's freespace, in place (eq. 3.5, section 5-A).

    Each arc is first tested against the sector through its bounding circle (kept in ``bounds``;
    :func:`~sonarcarve.geometry.bounds.circle_against_sector`): a circle clear of the disk or of
    one bounding half-plane leaves the arc unchanged, a circle inside the sector means the arc is
    fully carved; only the remaining arcs need :func:`carve_arc`'s exact, trigonometric path (5 %
    of the live arcs on the ring-corridor stream of ``benchmarks/synthetic.py``, counted over 600
    readings at history 250). Both shortcuts are exact: the circle contains the arc.

    Parameters
    ----------
    slots : ndarray of int64, shape (m,)
        Rows to carve; rows whose ``status`` is not ``ArcFate.ALIVE`` are skipped.
    x, y, r : ndarray, shape (n,)
        Arc origins and radii by row, metres.
    lo, hi : ndarray, shape (n,)
        Current carved intervals by row, radians; updated in place.
    bounds : ndarray, shape (n, 3)
        ``arc_bounding_circle(x, y, r, lo, hi)`` by row; updated in place with ``lo, hi``.
    status : ndarray of int8, shape (n,)
        :class:`~sonarcarve.geometry.ArcFate` by row; set to ``FULLY_CARVED`` or ``SPLIT`` when
        an arc is removed.
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
    cuts, starts, ends, flags = new_scratch()
    sector = make_sector(fx, fy, fr, f_lo, f_hi, tolerance, max_incidence)
    if sector.radius <= 0.0:
        return 0, 0
    fully = 0
    split = 0
    for slot in slots:
        if status[slot] != UNCHANGED:
            continue
        fate = circle_against_sector(bounds[slot, 0], bounds[slot, 1], bounds[slot, 2],
                                     x[slot], y[slot], r[slot], sector)
        if fate == UNCHANGED:
            continue
        new_lo = lo[slot]
        new_hi = hi[slot]
        if fate == UNDECIDED:
            fate, new_lo, new_hi = carve_core(x[slot], y[slot], r[slot], new_lo, new_hi,
                                              sector, cuts, starts, ends, flags)
            if fate == UNCHANGED:
                continue
        carved[slot] = True
        if fate == SHRUNK:
            lo[slot] = new_lo
            hi[slot] = new_hi
            bounds[slot, 0], bounds[slot, 1], bounds[slot, 2] = arc_bounding_circle(
                x[slot], y[slot], r[slot], new_lo, new_hi)
        else:
            status[slot] = fate
            if fate == FULLY_CARVED:
                fully += 1
            else:
                split += 1
    return fully, split
