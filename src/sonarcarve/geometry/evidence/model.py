"""The sensor model of evidence carving: its parameters, ``P_detect`` and the threshold.

How likely a newer reading ``j`` was to hear a surface at a point ``p`` inside its beam
(``v = p - o_j``, ``d = |v|``, ``a_j`` its unit axis; ``p`` is in the beam when
``v · a_j ≥ d cos(φ_j/2)``)::

    P_detect(j, p) = P_max · B · I(γ) · A(d)
    B = 1 - (1 - g) u²,  u = sin δ / sin(φ_j/2)    beam directivity, δ the off-axis angle
    cos γ = |e_i · v| / d                          incidence on the surface the echo of i implies
    I = 1 (γ ≤ γ0), ρ (γ ≥ γ1), linear in cos γ between
    A = 1 / (1 + d / L)                            spreading and absorption

``e_i`` is the unit direction of ``p`` from the older arc's origin ``o_i`` (the implied
surface's normal; the angle of :mod:`~sonarcarve.geometry.specular`). A miss is evidence
``w = -log(1 - P_detect)`` that ``p`` is empty (eq. 3.2 with the range tolerance ε); a bin is
carved once its evidence reaches ``T = -log(1 - P_carve)``. The reasons:
``docs/evidence-carving.md``, "The detection model" and "Evidence, support and the threshold".
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from sonarcarve.geometry._compiled import compiled, compiled_inline

__all__ = [
    "EVIDENCE_ALIVE",
    "EVIDENCE_CARVED",
    "EvidenceParams",
    "detect_probability",
    "evidence_threshold",
    "incidence_gain",
]

#: Status codes of an arc in the evidence model.
EVIDENCE_ALIVE = 0
EVIDENCE_CARVED = 1  # every bin carved


class EvidenceParams(NamedTuple):
    """The sensor model of evidence carving (``docs/evidence-carving.md``), SI units, radians.

    Attributes
    ----------
    tolerance : float
        ε, metres: the freespace of a reading of range r ends at ``r - ε``.
    support_tolerance : float
        ε_s, metres: a reading whose range is within ε_s of ``|p - o_j|`` supports ``p``.
    edge_gain : float
        g in (0, 1]: sensitivity at the beam edge relative to the axis.
    incidence_full : float
        γ0, radians: below it a surface is heard fully.
    incidence_zero : float
        γ1 > γ0, radians: above it only the floor ``rough`` is left.
    rough : float
        ρ in [0, 1]: detection at glancing incidence (rough walls, edges, corners).
    max_detect : float
        P_max in (0, 1): detection on the axis, head-on, at zero range.
    range_scale : float
        L, metres: detection halves at ``d = L`` (spreading and absorption).
    threshold : float
        T > 0: evidence (log-odds of misses) that carves a bin.
    establish : float
        S_est: support that makes a bin established (occludes what lies behind it).
    cos_psi : float
        cos ψ of ATM's minimum transversal angle (crossings kept when ``|cos γ| ≤ cos ψ``).
    protect : float
        Factor in [0, 1] on a newer reading's evidence against an established bin.
    viewpoint_spacing : float
        Metres: a reading of the same sensor counts as a distinct viewpoint of an arc only when
        its origin is at least this far from the arc's (repeated looks from one place at one
        phantom do not confirm it).
    transmit : float
        Factor in [0, 1] on transmission evidence (0: off): a newer echo confirmed by other
        sensors behind a point says that the sound passed through the point
        (``docs/evidence-carving.md``, "Transmission").
    confirm : float
        Other-sensor support at which a bin of a new arc counts as fully confirmed for
        transmission.
    """

    tolerance: float
    support_tolerance: float
    edge_gain: float
    incidence_full: float
    incidence_zero: float
    rough: float
    max_detect: float
    range_scale: float
    threshold: float
    establish: float
    cos_psi: float
    protect: float
    viewpoint_spacing: float
    transmit: float
    confirm: float


def evidence_threshold(carve_probability: float) -> float:
    """``T = -log(1 - P_carve)``: the evidence of one reading with ``P_detect = P_carve``.

    Examples
    --------
    >>> round(evidence_threshold(0.9), 4)
    2.3026
    """
    return -math.log1p(-carve_probability)


@compiled_inline
def incidence_gain(cos_gamma: float, cos_full: float, cos_zero: float, rough: float) -> float:
    """``I(γ)`` (module docstring) from ``cos γ``; ``cos_full > cos_zero``. np.divide is
    ``/`` without numba's zero-divisor test (a branch that keeps a loop scalar)."""
    if cos_gamma >= cos_full:
        return 1.0
    if cos_gamma <= cos_zero:
        return rough
    return rough + float(np.divide((1.0 - rough) * (cos_gamma - cos_zero), cos_full - cos_zero))


@compiled
def detect_probability(vx: float, vy: float, ex: float, ey: float, axis_x: float, axis_y: float,
                       sin_half: float, edge_gain: float, cos_full: float, cos_zero: float,
                       rough: float, max_detect: float, range_scale: float) -> float:
    """``P_detect`` of a reading at a point ``p`` inside its beam (module docstring).

    ``v = p - o_j`` (metres), ``e`` the unit direction of ``p`` from the older arc's origin,
    ``axis`` the reading's unit axis, ``sin_half = sin(φ_j/2)``; ``cos_full = cos γ0``,
    ``cos_zero = cos γ1``.

    Examples
    --------
    Head-on on the axis at 1 m, with P_max = 0.95, L = 20 m:

    >>> p = detect_probability(1.0, 0.0, 1.0, 0.0, 1.0, 0.0, math.sin(0.2), 0.5,
    ...                        math.cos(0.2), math.cos(0.5), 0.05, 0.95, 20.0)
    >>> round(p, 4)  # 0.95 / (1 + 1/20)
    0.9048
    """
    d = math.sqrt(vx * vx + vy * vy)
    if d <= 0.0:
        return max_detect
    sin_off = abs(vx * axis_y - vy * axis_x) / d
    u = min(sin_off / sin_half, 1.0)
    beam = 1.0 - (1.0 - edge_gain) * u * u
    cos_gamma = abs(ex * vx + ey * vy) / d
    inc = incidence_gain(cos_gamma, cos_full, cos_zero, rough)
    return max_detect * beam * inc / (1.0 + d / range_scale)
