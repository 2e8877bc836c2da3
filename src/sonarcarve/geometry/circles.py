"""Circle-circle intersections, for the Arc Transversal Median (paper, section 2-D).

Two circles (o1, r1), (o2, r2) with d = |o2 - o1| meet iff |r1 - r2| ≤ d ≤ r1 + r2 (d > 0).
The common chord crosses the line of centres at a = (d² + r1² - r2²) / 2d from o1, with
half-length h = sqrt(r1² - a²); the angle γ between the radii at either point follows from
the law of cosines in the triangle o1 o2 p: cos γ = (r1² + r2² - d²) / (2 r1 r2). The ATM
transversal angle is γ folded into [0, π/2], i.e. acos |cos γ|.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled
from sonarcarve.typing import BoolArray, FloatArray

__all__ = ["CircleIntersections", "circle_intersections", "circle_pair", "common_chord"]


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

    meets: BoolArray
    bearing1: FloatArray
    bearing2: FloatArray
    transversal: FloatArray


@compiled
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


@compiled
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


@compiled
def _circle_pairs(
    x1: FloatArray, y1: FloatArray, r1: FloatArray, x2: FloatArray, y2: FloatArray, r2: FloatArray
) -> tuple[BoolArray, FloatArray, FloatArray, FloatArray]:
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

    See the module docstring for the formulas (ATM, section 2-D).

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
