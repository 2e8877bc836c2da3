"""A circle around an arc, and the cheap test of that circle against a freespace sector."""

from __future__ import annotations

import math

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.geometry.fate import FULLY_CARVED, UNCHANGED
from sonarcarve.geometry.sector import Sector

__all__ = [
    "UNDECIDED",
    "arc_bounding_circle",
    "arc_clear_of_disk",
    "arc_clear_of_wedge",
    "circle_against_sector",
    "circle_clear_of_sector",
]

#: :func:`circle_against_sector` could not decide: the exact carving must.
UNDECIDED = -1


@compiled
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

    Examples
    --------
    >>> cx, cy, radius = arc_bounding_circle(0.0, 0.0, 1.0, -math.pi / 4, math.pi / 4)
    >>> round(cx, 9), round(cy, 9), round(radius, 9)  # the chord x = cos 45°, half-length sin 45°
    (0.707106781, 0.0, 0.707106782)
    """
    half = 0.5 * (hi - lo)
    if half > 0.5 * math.pi:
        return ox, oy, r * (1.0 + 1e-9)
    mid = 0.5 * (lo + hi)
    reach = r * math.cos(half)
    return (ox + reach * math.cos(mid), oy + reach * math.sin(mid),
            r * math.sin(half) + 1e-9 * r)


@compiled_inline
def circle_clear_of_sector(cx: float, cy: float, rho: float, sector: Sector) -> bool:
    """Whether the circle ``(cx, cy, rho)`` is clear of the sector's disk or of one of its
    bounding half-planes: :func:`circle_against_sector`'s ``UNCHANGED``, the same arithmetic,
    for a caller that needs nothing else (the index's filtered query)."""
    dx = cx - sector.fx
    dy = cy - sector.fy
    left = sector.u1x * dy - sector.u1y * dx
    right = dx * sector.u2y - dy * sector.u2x
    if left < -rho or right < -rho:
        return True
    radius = sector.radius
    return dx * dx + dy * dy >= (radius + rho) * (radius + rho)


@compiled_inline
def circle_against_sector(cx: float, cy: float, rho: float, ox: float, oy: float, r: float,
                          sector: Sector) -> int:
    """What a sector does to an arc, judged from a circle ``(cx, cy, rho)`` that contains it.

    ``UNCHANGED`` when the circle is clear of the disk or of one bounding half-plane;
    ``FULLY_CARVED`` when it lies inside the sector (with ``β < π/2``: and every point ``p`` of
    the arc is certain to have ``sin γ(p) ≤ sin β``, which holds when ``D = |o_i - o_j| ≤ r sin β``
    (:mod:`~sonarcarve.geometry.specular`) or, since ``sin γ ≤ D / |p - o_j|`` (law of sines),
    when ``D ≤ sin β`` times the circle's least distance from ``o_j``); :data:`UNDECIDED`
    otherwise. Both verdicts are exact because the circle contains the arc ``(ox, oy, r)``.
    """
    radius = sector.radius
    dx = cx - sector.fx
    dy = cy - sector.fy
    left = sector.u1x * dy - sector.u1y * dx  # u1 × (c - o_j): > 0 left of the f_lo ray
    right = dx * sector.u2y - dy * sector.u2x  # (c - o_j) × u2: > 0 right of the f_hi ray
    if left < -rho or right < -rho:
        return UNCHANGED
    dist2 = dx * dx + dy * dy
    if dist2 >= (radius + rho) * (radius + rho):
        return UNCHANGED
    inside = left > rho and right > rho and radius > rho and dist2 < (radius - rho) ** 2
    sin_beta = sector.sin_beta
    if inside and sin_beta < 1.0:
        sb2 = sin_beta * sin_beta
        ex = ox - sector.fx
        ey = oy - sector.fy
        origins2 = ex * ex + ey * ey  # D²
        if origins2 > sb2 * r * r:
            clearance = math.sqrt(dist2) - rho
            inside = clearance > 0.0 and origins2 <= sb2 * clearance * clearance
    return FULLY_CARVED if inside else UNDECIDED


@compiled_inline
def arc_clear_of_disk(ox: float, oy: float, r: float, clo: float, slo: float, chi: float,
                      shi: float, sector: Sector) -> bool:
    """Whether the arc ``o + r e(τ)``, ``τ ∈ [lo, hi]`` (``hi - lo < π``), is clear of the
    sector's open disk ``|p - o_j| < R`` by a margin: then carving leaves it unchanged.

    ``(clo, slo)``, ``(chi, shi)`` are ``e(lo)`` and ``e(hi)``. The point of the circle nearest
    ``o_j`` is in the direction ``d = o_j - o_i``: if ``d`` lies between ``e(lo)`` and ``e(hi)``
    the arc's least distance from ``o_j`` is ``|D - r|``, else it is at an end (the distance
    ``D² + r² - 2 r D cos(τ - α)`` grows with ``|τ - α|``). No trigonometry: a cheap test before
    the closed form, for the arcs whose bounding circle reaches into the disk.

    Exact: with every point of the arc at least ``R + pad`` from ``o_j``, the closed form's
    membership test ``cos(m - α) > k`` (eq. 3.2) fails at every sub-interval's middle by at least
    ``(2 R pad + pad²) / 2rD`` in ``cos``. ``pad`` = 1e-6 of the coordinates' size makes that
    margin (``pad²`` alone, for any ``R``) far above the rounding of ``k``, of ``cos`` and
    ``sin`` and of this test, so :func:`~sonarcarve.geometry.carve_arc` finds nothing to carve
    and returns ``UNCHANGED``, as this test says.
    """
    dx = sector.fx - ox
    dy = sector.fy - oy
    radius = sector.radius
    reach = radius + 1e-6 * (1.0 + abs(ox) + abs(oy) + r + radius)
    if clo * dy - slo * dx >= 0.0 and dx * shi - dy * chi >= 0.0:
        gap = math.sqrt(dx * dx + dy * dy) - r
        return gap * gap >= reach * reach
    ax = r * clo - dx
    ay = r * slo - dy
    bx = r * chi - dx
    by = r * shi - dy
    return min(ax * ax + ay * ay, bx * bx + by * by) >= reach * reach


@compiled_inline
def _beyond_edge(ox: float, oy: float, r: float, clo: float, slo: float, chi: float, shi: float,
                 fx: float, fy: float, ux: float, uy: float, margin: float) -> bool:
    """Whether every point of the arc has ``u × (p - o_j) < -margin``: the arc lies right of
    the line through ``o_j`` along the unit vector ``u``, by ``margin``.

    ``u × (p(τ) - o_j) = u × (o_i - o_j) + r sin(τ - a)`` (``u = e(a)``) is largest at the
    left normal ``n = (-u_y, u_x)``: the largest value on the arc is there if ``n`` is strictly
    between ``e(lo)`` and ``e(hi)`` (``hi - lo < π``), else at an end.
    """
    nx = -uy
    ny = ux
    if clo * ny - slo * nx > 0.0 and nx * shi - ny * chi > 0.0:  # the normal is inside
        return ux * (oy - fy) - uy * (ox - fx) + r < -margin
    at_lo = ux * (oy + r * slo - fy) - uy * (ox + r * clo - fx)
    at_hi = ux * (oy + r * shi - fy) - uy * (ox + r * chi - fx)
    return max(at_lo, at_hi) < -margin


@compiled_inline
def arc_clear_of_wedge(ox: float, oy: float, r: float, clo: float, slo: float, chi: float,
                       shi: float, sector: Sector) -> bool:
    """Whether the arc ``o + r e(τ)``, ``τ ∈ [lo, hi]`` (``hi - lo < π``), lies outside one of
    the sector's two bounding half-planes by a margin: then carving leaves it unchanged.

    ``(clo, slo)``, ``(chi, shi)`` are ``e(lo)`` and ``e(hi)``. The companion of
    :func:`arc_clear_of_disk` for the wedge: a bounding circle (:func:`arc_bounding_circle`)
    is as wide as the arc's chord across it, so it often reaches over an edge ray that the
    arc itself stays clear of; no trigonometry, where the closed form needs atan2, acos, asin
    and a sincos per sub-interval.

    Exact: every point of the arc is at least ``pad`` = 1e-6 of the coordinates' size outside
    the half-plane, so the closed form's membership test of that half-plane (eq. 3.2,
    ``sin(m - a1) ≥ s1``, or the one of ``a2``) fails at every sub-interval's middle by at
    least ``pad / r``, far above the rounding of ``s``, of ``cos`` and ``sin`` and of this
    test; the closed form carves nothing (``β < π/2`` only carves less) and returns
    ``UNCHANGED``, as this test says.
    """
    fx = sector.fx
    fy = sector.fy
    pad = 1e-6 * (1.0 + abs(ox) + abs(oy) + r + abs(fx) + abs(fy))
    # Carved points have u1 × (p - o_j) ≥ 0 and (p - o_j) × u2 ≥ 0, i.e. (-u2) × (p - o_j) ≥ 0.
    return (_beyond_edge(ox, oy, r, clo, slo, chi, shi, fx, fy, sector.u1x, sector.u1y, pad)
            or _beyond_edge(ox, oy, r, clo, slo, chi, shi, fx, fy, -sector.u2x, -sector.u2y,
                            pad))
