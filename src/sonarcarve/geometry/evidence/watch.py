"""Watched: could another reading have corroborated an echo at all? (beyond the paper).

Evidence carving's confidence (:class:`~sonarcarve.methods.evidence.ConfidenceModel`) weighs
most of all that *another* sensor, or the same one from elsewhere, heard an arc's surface too.
A ring gives that chance only where beams overlap: a Scout2's 16 sonars of 22.5° do almost
everywhere, but a Pioneer's 8 front sonars of 15°, 40° apart at the sides, leave a side wall
to one sensor, whose own firings (every 0.32 s) land too far apart along the wall to share a
point; 25 % of that ring's direct echoes were then judged by a silence that could not have been
anything else, and dropped (``docs/RESULTS.md``, "Another ring").

So each arc records how squarely any *distinct* reading looked at its axis point ``p_i = o_i +
r_i u(θ_i)``: over the readings ``j`` of the history that are another sensor's, or the same
sensor's from at least ``viewpoint_spacing`` away, whose beam holds ``p_i`` (``(p_i - o_j) ·
u(θ_j) >= |p_i - o_j| cos(φ_j / 2)``), the smallest angle between the two looks at it, ``p_i -
o_j`` and ``u(θ_i)``, radians; infinity when no such reading. A surface heard by ``i`` faces
``o_i`` roughly (a specular echo comes from the point nearest the sensor), so a reading looking
from further off its normal than a smooth wall's critical angle could not have heard it even
where it is real. The confidence model treats an arc whose smallest angle exceeds its
``watch_angle`` as one no evidence could reach: it keeps the prior (``fresh``) instead of
maturing to the fitted logit.

The range of ``j`` is not looked at: a reading whose beam holds ``p_i`` but heard something
nearer (its sound stopped in front of ``p_i``) still counts as a look. Echoes behind a surface
another sensor hears, multipath mostly, are so still judged by the fitted model, as before
(measured on a Pioneer ring: a lone arc only such readings cover is direct in 27 % of cases, one
that no beam covers in 93 %). No-echo readings are not looked at either (they are not arcs of
the history; their free space reaches the arcs through the ``looked`` and ``free`` evidence).

Each pair is judged once, when its newer reading arrives, from the two readings alone (both
directions: each may watch the other), so the values do not depend on how readings are batched.
What is exact: the cone and angle tests on the readings' own numbers, on the axis point (not
the kept run's point, which moves as carving goes on).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.typing import FloatArray

__all__ = ["look_angle", "mark_watch"]


@compiled_inline
def look_angle(px: float, py: float, cos_own: float, sin_own: float, xj: float, yj: float,
               cos_j: float, sin_j: float, cos_half_j: float) -> float:
    """The angle (radians) between the look from ``(xj, yj)`` at the point ``(px, py)`` and
    the direction ``(cos_own, sin_own)`` it was heard along, when the point lies in the beam
    of axis ``(cos_j, sin_j)`` and half-width of cosine ``cos_half_j``; infinity when it lies
    outside that beam or at the origin."""
    vx = px - xj
    vy = py - yj
    d = math.sqrt(vx * vx + vy * vy)
    if not d > 0.0 or vx * cos_j + vy * sin_j < d * cos_half_j:
        return math.inf
    c = (vx * cos_own + vy * sin_own) / d
    return math.acos(min(1.0, max(-1.0, c)))


@compiled
def mark_watch(first: int, count: int, capacity: int, x: FloatArray, y: FloatArray,
               r: FloatArray, cos_axis: FloatArray, sin_axis: FloatArray, cos_half: FloatArray,
               sensor: npt.NDArray[np.int64], watch: FloatArray, spacing: float) -> None:
    """Update ``watch`` for the arcs of sequence numbers ``first .. first + count - 1`` of a
    history ring (``n`` rows, arc ``s`` in row ``s % n``; ``cos_axis``, ``sin_axis`` and
    ``cos_half`` the cosine and sine of each row's axis and the cosine of its half-width,
    already set), in order: each new arc's value is reset to infinity, then each pair of it
    and one of the ``capacity - 1`` arcs before it (those still in the history) that are
    distinct (another sensor, or origins at least ``spacing`` metres apart) lowers each one's
    value to the angle at which the other looked at its axis point (:func:`look_angle`; module
    docstring). The block's rows and the up to ``capacity - 1`` before it must all be in the
    ring (as for :func:`~sonarcarve.geometry.repeats.mark_repeats`)."""
    storage = x.shape[0]
    spacing2 = spacing * spacing
    for sequence in range(first, first + count):
        j = sequence % storage
        watch[j] = math.inf
        xj = x[j]
        yj = y[j]
        cj = cos_axis[j]
        sj = sin_axis[j]
        pxj = xj + r[j] * cj
        pyj = yj + r[j] * sj
        for older in range(max(0, sequence - capacity + 1), sequence):
            i = older % storage
            ox = x[i] - xj
            oy = y[i] - yj
            if sensor[i] == sensor[j] and ox * ox + oy * oy < spacing2:
                continue  # the same look again: no chance to corroborate
            ci = cos_axis[i]
            si = sin_axis[i]
            seen = look_angle(x[i] + r[i] * ci, y[i] + r[i] * si, ci, si, xj, yj, cj, sj,
                              cos_half[j])
            watch[i] = min(watch[i], seen)
            seen = look_angle(pxj, pyj, cj, sj, x[i], y[i], ci, si, cos_half[i])
            watch[j] = min(watch[j], seen)
