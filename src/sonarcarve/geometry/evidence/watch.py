"""Watched: could another reading have corroborated an echo at all? (beyond the paper).

Evidence carving's confidence (:class:`~sonarcarve.methods.evidence.ConfidenceModel`) weighs
most of all that *another* sensor, or the same one from elsewhere, heard an arc's surface too.
A ring gives that chance only where beams overlap: a Scout2's 16 sonars of 22.5° do almost
everywhere, but a Pioneer's 8 front sonars of 15°, 40° apart at the sides, leave a side wall
to one sensor, whose own firings (every 0.32 s) land too far apart along the wall to share a
point; 25 % of that ring's direct echoes were then judged by a silence that could not have been
anything else, and dropped (``docs/RESULTS.md``, "Another ring").

So each arc records whether any *distinct* reading looked squarely at its axis point ``p_i =
o_i + r_i u(θ_i)``: a reading ``j`` of the history that is another sensor's, or the same
sensor's from at least ``viewpoint_spacing`` away, whose beam holds ``p_i`` (``(p_i - o_j) ·
u(θ_j) >= |p_i - o_j| cos(φ_j / 2)``) and whose look at it, ``p_i - o_j``, lies within the
sensor model's ``incidence_zero`` (30°) of the direction ``u(θ_i)`` it was heard along. A
surface heard by ``i`` faces ``o_i`` roughly (a specular echo comes from the point nearest the
sensor), so a look from further off its normal than the angle past which the detection model
gives a smooth wall nothing (``incidence_zero``: the simulator's specular critical angle is
17.5°, 25° for rough walls; the rest is slack for where on its beam the surface lies) could
not have heard it even where it is real. The confidence model treats an arc no such reading
looked at, but that something supported (its own sensor heard it again), as one no other
evidence could reach: it keeps the prior (``fresh``) instead of maturing to the fitted logit
(:class:`~sonarcarve.methods.evidence.ConfidenceModel`).

The range of ``j`` is not looked at: a reading whose beam holds ``p_i`` but heard something
nearer (its sound stopped in front of ``p_i``) still counts as a look. Echoes behind a surface
another sensor hears, multipath mostly, are so still judged by the fitted model, as before
(measured on a Pioneer ring: a lone arc only such readings cover is direct in 27 % of cases, one
that no beam covers in 93 %). A no-echo reading looks too (:func:`mark_watched_by_silence`):
its beam held the point within its maximum range and heard nothing, evidence the fitted model
reads through ``free`` and ``looked``; it is no arc, so nothing watches it.

Each pair is judged once, when its newer reading arrives, from the two readings alone (both
directions: each may watch the other), so the values do not depend on how readings are batched.
What is exact: the cone and angle tests on the readings' own numbers, on the axis point (not
the kept run's point, which moves as carving goes on).

Covered by another sensor (``covering``, the confidence's ``alone`` feature): the same pairs
also count the readings of *another sensor* whose beam held an arc's axis point, at any angle
and any range of its echo (nearer, farther or none: :func:`mark_watched_by_silence` counts a
silent reading too, where the point lies within its maximum range; each pair once, both
ways). The support of other sensors (``others``, the confidence's heaviest
weight) comes from such beams: on a ring whose beams do not overlap (15° beams 22.5° apart) a
wall one sensor faces is covered by no other, and the fitted model would read the missing
support as a phantom's (``docs/RESULTS.md``, "The ``others`` feature on other rings"). The axis
point stands for the arc: support can still reach an arc whose axis point no other beam held.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.typing import FloatArray

__all__ = ["holds", "looks_squarely", "mark_watch", "mark_watched_by_silence", "watch_pairs"]


@compiled_inline
def looks_squarely(vx: float, vy: float, v2: float, cj: float, sj: float, cos_half_j2: float,
                   ci: float, si: float, cos_look2: float) -> bool:
    """Whether a look ``v = p_i - o_j`` (``v2 = |v|²``) from a beam of axis ``(cj, sj)`` and
    half-width of squared cosine ``cos_half_j2`` holds the point and meets it within the angle
    of squared cosine ``cos_look2`` of the direction ``(ci, si)`` it was heard along (module
    docstring). Squared comparisons of dot products (the angles are below 90°): no square
    root, no division, no branch. A point at the looking origin fails ``along > 0``."""
    along = vx * cj + vy * sj
    square = vx * ci + vy * si
    return ((along > 0.0) & (along * along >= v2 * cos_half_j2)
            & (square > 0.0) & (square * square >= v2 * cos_look2))


@compiled_inline
def holds(vx: float, vy: float, v2: float, cj: float, sj: float, cos_half_j2: float) -> bool:
    """Whether a beam of axis ``(cj, sj)`` and half-width of squared cosine ``cos_half_j2``
    holds the point at ``v`` from its origin (``v2 = |v|²``); no range limit. A point at the
    origin fails ``along > 0``."""
    along = vx * cj + vy * sj
    return (along > 0.0) & (along * along >= v2 * cos_half_j2)


@compiled_inline
def watch_pairs(x: FloatArray, y: FloatArray, r: FloatArray, cos_axis: FloatArray,
                sin_axis: FloatArray, cos_half: FloatArray, sensor: npt.NDArray[np.int64],
                xj: float, yj: float, rj: float, cj: float, sj: float, cos_half_j: float,
                sensor_j: int, spacing2: float, cos_look2: float,
                watched: npt.NDArray[np.bool_],
                covering: FloatArray) -> tuple[int, int]:
    """For the rows of the arrays (slices of the history's rows) against the reading ``j``
    (origin ``(xj, yj)``, range ``rj``, axis ``(cj, sj)``, half-width of cosine
    ``cos_half_j``): set ``watched[i]`` where ``j`` looked squarely at row ``i``'s axis point
    (:func:`looks_squarely`, the two distinct) and add 1 to ``covering[i]`` where ``j`` is
    another sensor's and its beam holds that point (:func:`holds`); return how many rows looked
    squarely at ``j``'s axis point and how many rows of other sensors hold it in their beams.
    No branch and indices from 0: the compiler runs it on several rows at once."""
    pxj = xj + rj * cj
    pyj = yj + rj * sj
    cos_half_j2 = cos_half_j * cos_half_j
    looked_at_j = 0
    held_j = 0
    for i in range(watched.shape[0]):
        ox = x[i] - xj
        oy = y[i] - yj
        other = sensor[i] != sensor_j
        distinct = other | (ox * ox + oy * oy >= spacing2)
        ci = cos_axis[i]
        si = sin_axis[i]
        # j looks at i's point: v = p_i - o_j, against j's axis and i's.
        vx = ox + r[i] * ci
        vy = oy + r[i] * si
        v2 = vx * vx + vy * vy
        watched[i] |= distinct & looks_squarely(vx, vy, v2, cj, sj, cos_half_j2, ci, si,
                                                cos_look2)
        covering[i] += 1.0 * (other & holds(vx, vy, v2, cj, sj, cos_half_j2))
        # i looks at j's point: w = p_j - o_i, against i's axis and j's.
        wx = pxj - x[i]
        wy = pyj - y[i]
        w2 = wx * wx + wy * wy
        cos_half_i2 = cos_half[i] * cos_half[i]
        looked_at_j += distinct & looks_squarely(wx, wy, w2, ci, si, cos_half_i2, cj, sj,
                                                 cos_look2)
        held_j += other & holds(wx, wy, w2, ci, si, cos_half_i2)
    return looked_at_j, held_j


@compiled
def mark_watch(first: int, count: int, capacity: int, x: FloatArray, y: FloatArray,
               r: FloatArray, cos_axis: FloatArray, sin_axis: FloatArray, cos_half: FloatArray,
               sensor: npt.NDArray[np.int64], watched: npt.NDArray[np.bool_],
               covering: FloatArray, spacing: float, look_angle: float) -> None:
    """Mark ``watched`` for the arcs of sequence numbers ``first .. first + count - 1`` of a
    history ring (``n`` rows, arc ``s`` in row ``s % n``; ``cos_axis``, ``sin_axis`` and
    ``cos_half`` the cosine and sine of each row's axis and the cosine of its half-width,
    already set), in order: each new arc's flag is reset, then each pair of it and one of the
    ``capacity - 1`` arcs before it (those still in the history) that are distinct (another
    sensor, or origins at least ``spacing`` metres apart) marks each one the other looked at
    squarely, within ``look_angle`` radians (< π/2) of its axis, and counts in ``covering`` the
    readings of another sensor whose beam held each one's axis point (:func:`watch_pairs`; each
    new arc's count set from the older arcs). The block's rows and the up to ``capacity - 1``
    before it must all be in the ring (as for
    :func:`~sonarcarve.geometry.repeats.mark_repeats`)."""
    storage = x.shape[0]
    spacing2 = spacing * spacing
    cos_look = math.cos(look_angle)
    cos_look2 = cos_look * cos_look
    for sequence in range(first, first + count):
        j = sequence % storage
        looked = 0
        held = 0
        oldest = max(0, sequence - capacity + 1)
        start = oldest % storage
        end = start + sequence - oldest
        for lo, hi in ((start, min(end, storage)), (0, max(end - storage, 0))):
            pair_looked, pair_held = watch_pairs(
                x[lo:hi], y[lo:hi], r[lo:hi], cos_axis[lo:hi], sin_axis[lo:hi],
                cos_half[lo:hi], sensor[lo:hi], x[j], y[j], r[j], cos_axis[j], sin_axis[j],
                cos_half[j], sensor[j], spacing2, cos_look2, watched[lo:hi], covering[lo:hi])
            looked += pair_looked
            held += pair_held
        watched[j] = looked > 0
        covering[j] = held


@compiled
def mark_watched_by_silence(slots: npt.NDArray[np.int64], x: FloatArray, y: FloatArray,
                            r: FloatArray, cos_axis: FloatArray, sin_axis: FloatArray,
                            sensor: npt.NDArray[np.int64], xj: float, yj: float, theta_j: float,
                            beam_width_j: float, max_range_j: float, sensor_j: int,
                            watched: npt.NDArray[np.bool_], covering: FloatArray,
                            spacing: float, look_angle: float) -> None:
    """Mark ``watched`` for the history rows ``slots`` whose axis point a no-echo reading
    (origin ``(xj, yj)``, axis ``theta_j``, beam ``beam_width_j``, of sensor ``sensor_j``)
    looked at squarely (:func:`looks_squarely`) within its ``max_range_j`` (not finite: no
    bound), when the two are distinct; and add 1 to ``covering`` of those whose axis point its
    beam held within that range (:func:`holds`) when it is another sensor's."""
    cj = math.cos(theta_j)
    sj = math.sin(theta_j)
    cos_half_j = math.cos(0.5 * beam_width_j)
    cos_half_j2 = cos_half_j * cos_half_j
    cos_look = math.cos(look_angle)
    cos_look2 = cos_look * cos_look
    reach2 = max_range_j * max_range_j if math.isfinite(max_range_j) else math.inf
    spacing2 = spacing * spacing
    for q in range(slots.shape[0]):
        i = slots[q]
        ox = x[i] - xj
        oy = y[i] - yj
        other = sensor[i] != sensor_j
        if not other and ox * ox + oy * oy < spacing2:
            continue  # its own look again
        vx = ox + r[i] * cos_axis[i]
        vy = oy + r[i] * sin_axis[i]
        v2 = vx * vx + vy * vy
        if v2 > reach2:
            continue
        if looks_squarely(vx, vy, v2, cj, sj, cos_half_j2, cos_axis[i], sin_axis[i],
                          cos_look2):
            watched[i] = True
        if other and holds(vx, vy, v2, cj, sj, cos_half_j2):
            covering[i] += 1.0
