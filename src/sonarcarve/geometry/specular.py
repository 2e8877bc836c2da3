"""Specular-aware carving, the incidence cut (beyond the paper; opt-in).

On smooth walls an echo comes back only when the beam meets the wall close to its normal. An
echo of reading ``i`` at ``p`` therefore implies a surface through ``p`` whose normal points
back at ``o_i``; reading ``j`` would see that surface at the incidence angle ``γ(p)``, the angle
``o_i``-``p``-``o_j`` of the triangle folded into ``[0, π/2]`` (a thin wall reflects from both
faces; this is the same angle as ATM's transversal angle). If ``γ(p)`` exceeds a critical angle
``β``, reading ``j`` could not have heard that surface, so its freespace is no evidence against
``p``. The carved set becomes ::

    Z_ij^β = {p ∈ C_i ∩ F_j : γ(p) ≤ β},       β = π/2: Z_ij^β = Z_ij (the paper, eq. 3.4),

a fourth condition on the circle, beside the three of :mod:`sonarcarve.geometry.intervals`. With
``w = p - o_i`` and ``v = p - o_j``, ``sin γ = |w × v| / (|w| |v|)`` (folding keeps the sine),
so for ``β < π/2`` the condition is ``(w × v)² ≤ sin²β |w|² |v|²``. On circle ``i``
(``w = r e(τ)``, ``c = cos(τ - α)``) it reads ::

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

With ``sin β = 1`` (:data:`NO_INCIDENCE_LIMIT`) every helper here says "no cut", so the paper's
path runs unchanged.
"""

from __future__ import annotations

import math

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.geometry.circular import ALL, SOME, add_cut
from sonarcarve.typing import FloatArray

__all__ = [
    "NO_INCIDENCE_LIMIT",
    "add_incidence_cuts",
    "incidence_member",
    "incidence_mode",
    "incidence_ok",
    "incidence_sine",
]

#: ``max_incidence`` that switches specular-aware carving off: every incidence is at most π/2,
#: so ``Z_ij^β = Z_ij`` and carving is the paper's (eq. 3.4).
NO_INCIDENCE_LIMIT = 0.5 * math.pi


@compiled
def incidence_sine(max_incidence: float) -> float:
    """``sin β`` for the kernels; 1.0 (no limit) when ``β ≥ π/2``.

    The kernels test ``sin γ ≤ sin β`` only when this is below 1, so ``β = π/2`` runs exactly
    the paper's code path (rounding at ``γ = π/2`` cannot flip a point).
    """
    if max_incidence >= NO_INCIDENCE_LIMIT:
        return 1.0
    return math.sin(max(max_incidence, 0.0))


@compiled
def incidence_ok(ox: float, oy: float, px: float, py: float, fx: float, fy: float,
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


@compiled_inline
def incidence_mode(sin_beta: float, r: float, dist2: float) -> int:
    """Whether the incidence condition holds on ``ALL`` of circle ``i`` or on ``SOME`` of it.

    Everywhere when ``D ≤ r sin β`` (module docstring), never nowhere: the points in line with
    ``o_i`` and ``o_j`` have ``γ = 0``. ``dist2 = D²``.
    """
    rsb2 = r * r * sin_beta * sin_beta
    return SOME if sin_beta < 1.0 and dist2 > rsb2 else ALL


@compiled_inline
def add_incidence_cuts(cuts: FloatArray, count: int, r: float, dist2: float, alpha: float,
                       sin_beta: float, lo: float, hi: float) -> int:
    """Append the four boundary bearings ``α ± acos c±`` of the incidence condition.

    ``c±`` are the roots of ``q(c) = 0`` (module docstring); only bearings strictly inside
    ``(lo, hi)`` are kept (:func:`~sonarcarve.geometry.circular.add_cut`). Returns the new count.
    Requires ``incidence_mode(...) == SOME``.
    """
    rsb2 = r * r * sin_beta * sin_beta
    dist = math.sqrt(dist2)
    cos_beta = math.sqrt((1.0 - sin_beta) * (1.0 + sin_beta))
    root = cos_beta * math.sqrt(dist2 - rsb2)
    for c in ((r * sin_beta * sin_beta + root) / dist, (r * sin_beta * sin_beta - root) / dist):
        half = math.acos(min(max(c, -1.0), 1.0))
        count = add_cut(cuts, count, alpha - half, lo, hi)
        count = add_cut(cuts, count, alpha + half, lo, hi)
    return count


@compiled_inline
def incidence_member(cm: float, sm: float, r: float, dx: float, dy: float,
                     sin_beta: float) -> bool:
    """Whether the point at bearing ``m`` of circle ``i`` has ``sin γ ≤ sin β``.

    ``(cm, sm) = (cos m, sin m)``, ``(dx, dy) = o_j - o_i``. With ``w = r e(m)`` and
    ``v = w - d``, ``w × v = -r (e(m) × d)`` and ``sin²γ = (w × v)² / (|w|² |v|²)``, so the test
    is ``(e(m) × d)² ≤ sin²β |v|²``.
    """
    cross = cm * dy - sm * dx
    vx = r * cm - dx
    vy = r * sm - dy
    return cross * cross <= sin_beta * sin_beta * (vx * vx + vy * vy)
