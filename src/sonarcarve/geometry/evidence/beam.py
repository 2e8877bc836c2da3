"""The new reading as the weighing pass sees it, and the cull of the older arcs it cannot reach.

A new reading ``j`` (origin ``o_j``, range ``r_j``, axis ``θ_j``, beam width ``φ_j``) weighs a
point ``p`` of an older arc only inside its beam and its reach ``|p - o_j| < r_j + ε_s``:
nearer than ``r_j - ε`` it is freespace (eq. 3.2), within ``ε_s`` of ``r_j`` support. Its
constants are computed once per reading (:class:`Beam`), and every older arc whose bounding
circle lies beyond that reach or outside the beam is culled in one loop without branches
(:func:`mark_near`; ``docs/evidence-carving.md``, "Speed: the weighing kernel's layout").
"""

from __future__ import annotations

import math
from typing import NamedTuple

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.geometry.evidence.arrays import ArcShapes, ReadingRows
from sonarcarve.geometry.evidence.model import EVIDENCE_ALIVE, EvidenceParams
from sonarcarve.typing import BoolArray, FloatArray, Int8Array

__all__ = ["Beam", "beam_of", "mark_near", "new_beam"]


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
def mark_near(cx: FloatArray, cy: FloatArray, rho: FloatArray, status: Int8Array,
              beam: Beam, near_flags: BoolArray) -> None:
    """The cull, for each row ``i`` of the arrays (slices of the history's rows): ``near_flags[i]``
    is False where arc ``i`` is no longer alive or its bounding circle (centre ``(cx[i],
    cy[i])``, radius ``rho[i]``) lies beyond the reach of ``j``'s echo circle, or clear of one
    of the two half-planes whose intersection is ``j``'s beam (φ < π; as
    ``geometry/bounds.py``). No branch, and indices from 0 (no test for negative ones): the
    compiler tests several rows at once."""
    bx = beam.x
    by = beam.y
    reach = beam.reach
    e1x = beam.edge1_x
    e1y = beam.edge1_y
    e2x = beam.edge2_x
    e2y = beam.edge2_y
    for i in range(near_flags.shape[0]):
        dcx = cx[i] - bx
        dcy = cy[i] - by
        r = rho[i]
        far = dcx * dcx + dcy * dcy >= (reach + r) * (reach + r)
        below_lower_edge = e1x * dcy - e1y * dcx < -r
        above_upper_edge = dcx * e2y - dcy * e2x < -r
        near_flags[i] = (status[i] == EVIDENCE_ALIVE) & (not far) & (not below_lower_edge) & (
            not above_upper_edge)
