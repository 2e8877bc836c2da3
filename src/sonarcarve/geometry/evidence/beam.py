"""The new reading as the weighing pass sees it, and the cull of the older arcs it cannot reach.

A new reading ``j`` (origin ``o_j``, range ``r_j``, axis ``θ_j``, beam width ``φ_j``) weighs a
point ``p`` of an older arc only inside its beam and its reach ``|p - o_j| < r_j + ε_s``:
nearer than ``r_j - ε`` it is freespace (eq. 3.2), within ``ε_s`` of ``r_j`` support. Its
constants are computed once per reading (:class:`Beam`), and the older arcs are culled in one
loop without branches (:func:`mark_near`; ``docs/evidence-carving.md``, "Speed: the weighing
kernel's layout"): an arc whose bounding circle lies beyond that reach or outside the beam
is left alone; of the others, ATM's crossings are sought only where the bounding circle meets
``j``'s echo circle (a crossing lies on it), and bins are weighed only where the circle of
the arc's *live* bins (:func:`draw_live_circle`) is within reach too. Both tests only drop
arcs that would have got nothing: every map stays bit for bit the same.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.geometry.bounds import arc_bounding_circle
from sonarcarve.geometry.evidence.arrays import ArcShapes, ReadingRows
from sonarcarve.geometry.evidence.model import EVIDENCE_ALIVE, EvidenceParams
from sonarcarve.geometry.index import box_pad
from sonarcarve.typing import BoolArray, FloatArray, Int8Array

__all__ = ["Beam", "beam_of", "clear_of_beam", "draw_live_circle", "mark_near",
           "meets_echo_circle", "new_beam"]


class Beam(NamedTuple):
    """The new reading ``j`` as the weighing pass sees it (metres, radians)."""

    x: float
    y: float
    r: float
    cos_axis: float
    sin_axis: float
    half: float  # φ_j / 2
    step: float  # Δ_j = φ_j / K
    sin_half: float
    cos_half2: float  # cos²(φ_j / 2): beam membership without a root
    free_r: float  # r_j - ε: the end of the freespace sector F_j (eq. 3.2)
    reach: float  # r_j + ε_s: beyond it a point is neither free nor supported
    reach2: float
    edge1_x: float  # unit vectors of the beam's lower and upper edges
    edge1_y: float
    edge2_x: float
    edge2_y: float
    # The sensor model's derived constants, computed once per reading, not per older arc.
    edge_loss: float  # 1 - g
    inv_scale: float  # 1 / L
    cos_full: float  # cos γ0
    cos_zero: float  # cos γ1
    spacing2: float  # viewpoint_spacing²


@compiled_inline
def beam_of(x: float, y: float, r: float, cos_axis: float, sin_axis: float, half: float,
            cos_half: float, step: float, free_r: float, reach: float,
            params: EvidenceParams) -> Beam:
    """A :class:`Beam` from its origin, range, axis ``(cos_axis, sin_axis)``, half-width
    ``half`` (and its cosine), bin width ``step``, the end of its freespace and its reach;
    the rest is derived here (call it with keywords: the scalars are easily swapped)."""
    sin_half = math.sin(half)
    return Beam(
        x=x, y=y, r=r, cos_axis=cos_axis, sin_axis=sin_axis, half=half, step=step,
        sin_half=sin_half, cos_half2=cos_half * cos_half, free_r=free_r, reach=reach,
        reach2=reach * reach,
        edge1_x=cos_axis * cos_half + sin_axis * sin_half,
        edge1_y=sin_axis * cos_half - cos_axis * sin_half,
        edge2_x=cos_axis * cos_half - sin_axis * sin_half,
        edge2_y=sin_axis * cos_half + cos_axis * sin_half,
        edge_loss=1.0 - params.edge_gain, inv_scale=1.0 / params.range_scale,
        cos_full=math.cos(params.incidence_full), cos_zero=math.cos(params.incidence_zero),
        spacing2=params.viewpoint_spacing * params.viewpoint_spacing,
    )


@compiled_inline
def new_beam(slot: int, readings: ReadingRows, shapes: ArcShapes,
             params: EvidenceParams) -> Beam:
    """The new reading's :class:`Beam`, from its row (once
    :func:`~sonarcarve.geometry.evidence.evidence_add` has set its shape): its echo circle at
    ``r_j``, its freespace to ``r_j - ε``, its reach to ``r_j + ε_s``."""
    rj = readings.r[slot]
    bins = shapes.bx.shape[1]
    return beam_of(
        x=readings.x[slot], y=readings.y[slot], r=rj, cos_axis=shapes.cos_axis[slot],
        sin_axis=shapes.sin_axis[slot], half=0.5 * readings.beam_width[slot],
        cos_half=shapes.cos_half[slot], step=readings.beam_width[slot] / bins,
        free_r=rj - params.tolerance, reach=rj + params.support_tolerance, params=params,
    )


@compiled_inline
def clear_of_beam(cx: float, cy: float, rho: float, beam: Beam) -> bool:
    """Whether the circle ``(cx, cy, rho)`` lies beyond ``j``'s reach or clear of one of the
    two half-planes whose intersection is ``j``'s beam (φ < π; as ``geometry/bounds.py``).
    No branch."""
    dcx = cx - beam.x
    dcy = cy - beam.y
    far = dcx * dcx + dcy * dcy >= (beam.reach + rho) * (beam.reach + rho)
    below_lower_edge = beam.edge1_x * dcy - beam.edge1_y * dcx < -rho
    above_upper_edge = dcx * beam.edge2_y - dcy * beam.edge2_x < -rho
    return far | below_lower_edge | above_upper_edge


@compiled_inline
def mark_near(cx: FloatArray, cy: FloatArray, rho: FloatArray, status: Int8Array,
              beam: Beam, near_flags: BoolArray) -> None:
    """The cull, for each row ``i`` of the arrays (slices of the history's rows): ``near_flags[i]``
    is False where arc ``i`` is no longer alive or its bounding circle (centre ``(cx[i],
    cy[i])``, radius ``rho[i]``) is clear of ``j``'s beam (:func:`clear_of_beam`). No branch,
    and indices from 0 (no test for negative ones): the compiler tests several rows at once."""
    for i in range(near_flags.shape[0]):
        near_flags[i] = (status[i] == EVIDENCE_ALIVE) & (
            not clear_of_beam(cx[i], cy[i], rho[i], beam))


@compiled_inline
def meets_echo_circle(cx: float, cy: float, rho: float, beam: Beam) -> bool:
    """Whether the circle ``(cx, cy, rho)``, an arc's bounding circle, meets ``j``'s echo
    circle (radius ``r_j`` about ``o_j``), widened by
    :func:`~sonarcarve.geometry.index.box_pad`: where it does not, ATM can keep no crossing of
    the two arcs (a kept crossing lies on the echo circle and on the arc, so inside the
    bounding circle; the pad is far above the rounding of the crossing's closed form)."""
    dcx = cx - beam.x
    dcy = cy - beam.y
    d2 = dcx * dcx + dcy * dcy
    rj = beam.r
    ring = rho + box_pad(beam.x, beam.y, rj)
    beyond = d2 > (rj + ring) * (rj + ring)
    within = (rj > ring) & (d2 < (rj - ring) * (rj - ring))
    return not (beyond | within)


@compiled_inline
def draw_live_circle(i: int, readings: ReadingRows, free: FloatArray, threshold: float,
                     live_circle: FloatArray) -> None:
    """Column ``i`` of ``live_circle``: a circle containing the centres of arc ``i``'s live
    bins (free evidence not at ``T``: what pass 1 would weigh), and how many there are.

    The circle is that of the arc (eq. 3.1, :func:`~sonarcarve.geometry.bounds.arc_bounding_circle`)
    from the first live bin's centre to the last's, at the angles ``τ_k = θ - φ/2 + (k + ½) Δ``
    written as ``evidence_add`` computes the centres (rounding is monotone in ``k``, so every
    live bin's ``τ_k`` lies between the two), its radius widened by
    :func:`~sonarcarve.geometry.index.box_pad`. No live bin: an infinite radius (the cull then
    leaves the arc to pass 1, which carves it)."""
    bins = free.shape[1]
    first = bins
    last = -1
    count = 0
    for k in range(bins):
        alive = not free[i, k] >= threshold
        first = min(first, k if alive else bins)
        last = max(last, k if alive else -1)
        count += alive
    x = readings.x[i]
    y = readings.y[i]
    r = readings.r[i]
    live_circle[3, i] = count
    if count == 0:
        live_circle[0, i] = x
        live_circle[1, i] = y
        live_circle[2, i] = math.inf
        return
    theta = readings.theta[i]
    half = 0.5 * readings.beam_width[i]
    step = readings.beam_width[i] / bins
    cx, cy, rho = arc_bounding_circle(x, y, r, theta - half + (first + 0.5) * step,
                                      theta - half + (last + 0.5) * step)
    live_circle[0, i] = cx
    live_circle[1, i] = cy
    live_circle[2, i] = rho + box_pad(x, y, r)
