"""The freespace sector ``F_j`` of a newer reading (paper, eq. 3.2), prepared for the kernels."""

from __future__ import annotations

import math
from typing import NamedTuple

from sonarcarve.geometry._compiled import compiled
from sonarcarve.geometry.specular import incidence_sine

__all__ = ["Sector", "make_sector", "point_in_sector"]


class Sector(NamedTuple):
    """``F_j = {p : |p - o_j| < R, bearing(p - o_j) ∈ [a1, a2]}`` with its trigonometry hoisted.

    Attributes
    ----------
    fx, fy : float
        Origin ``o_j`` of the newer reading, metres.
    radius : float
        ``R = r_j - ε``, metres (``≤ 0``: no freespace).
    a1, u1x, u1y : float
        Lower bounding bearing ``f_lo`` (radians) and its unit vector.
    a2, u2x, u2y : float
        Upper bounding bearing ``f_hi`` (radians) and its unit vector; ``0 ≤ a2 - a1 < π``.
    sin_beta : float
        ``sin β`` of specular-aware carving (:func:`~sonarcarve.geometry.specular.
        incidence_sine`); 1: the paper.
    """

    fx: float
    fy: float
    radius: float
    a1: float
    u1x: float
    u1y: float
    a2: float
    u2x: float
    u2y: float
    sin_beta: float


@compiled
def make_sector(fx: float, fy: float, fr: float, f_lo: float, f_hi: float, tolerance: float,
                max_incidence: float) -> Sector:
    """The sector of a reading at ``(fx, fy)`` with range ``fr`` and full beam ``[f_lo, f_hi]``.

    ``tolerance`` is ε (metres), ``max_incidence`` β (radians); see
    :func:`~sonarcarve.geometry.carve_arc`.
    """
    return Sector(fx, fy, fr - tolerance, f_lo, math.cos(f_lo), math.sin(f_lo),
                  f_hi, math.cos(f_hi), math.sin(f_hi), incidence_sine(max_incidence))


@compiled
def point_in_sector(px: float, py: float, sector: Sector) -> bool:
    """Whether ``p`` is in the sector (open disk, closed wedge narrower than π)."""
    vx = px - sector.fx
    vy = py - sector.fy
    radius = sector.radius
    return (vx * vx + vy * vy < radius * radius and sector.u1x * vy - sector.u1y * vx >= 0.0
            and vx * sector.u2y - vy * sector.u2x >= 0.0)
