"""A no-echo reading in evidence carving: free-space evidence up to its maximum range, nothing else.

A reading that heard nothing up to its ``max_range`` adds the evidence of an echo's freespace
with ``r_j = max_range``: ``w = -log(1 - P_detect)`` at every bin centre of a live arc in its
beam nearer than ``max_range - ε``, and no support, occlusion, crossing or arc of its own
(``docs/evidence-carving.md``, "No-echo readings").
"""

from __future__ import annotations

import math
from typing import NamedTuple

from sonarcarve.geometry._compiled import compiled_borrowing, compiled_inline
from sonarcarve.geometry.evidence.arrays import (
    ArcShapes,
    BinEvidence,
    EvidenceState,
    PlainBundle,
    named_state,
)
from sonarcarve.geometry.evidence.beam import Beam, beam_of
from sonarcarve.geometry.evidence.model import (
    EVIDENCE_ALIVE,
    EVIDENCE_CARVED,
    EvidenceParams,
    incidence_gain,
)
from sonarcarve.typing import BoolArray, FloatArray, Int8Array, SlotArray

__all__ = ["SilentReading", "evidence_free"]


class SilentReading(NamedTuple):
    """A reading that heard nothing up to ``max_range``: origin ``(x, y)`` and ``max_range``
    (metres), axis ``theta`` and ``beam_width`` (radians), and its ``sensor``."""

    x: float
    y: float
    max_range: float
    theta: float
    beam_width: float
    sensor: int


@compiled_inline
def _silent_beam(reading: SilentReading, params: EvidenceParams) -> Beam:
    """The no-echo reading as the weighing sees it: a
    :class:`~sonarcarve.geometry.evidence.beam.Beam` whose echo circle is at ``max_range`` and
    whose reach ends with its freespace, at ``max_range - ε`` (it heard nothing, so it supports
    nothing). Its ``step`` is 0: the reading has no bins of its own."""
    free_r = reading.max_range - params.tolerance
    half = 0.5 * reading.beam_width
    return beam_of(
        x=reading.x, y=reading.y, r=reading.max_range, cos_axis=math.cos(reading.theta),
        sin_axis=math.sin(reading.theta), half=half, cos_half=math.cos(half), step=0.0,
        free_r=free_r, reach=free_r, params=params,
    )


@compiled_inline
def _out_of_reach(i: int, beam: Beam, circle: FloatArray, status: Int8Array) -> bool:
    """The cull of older arc ``i``: already carved, or its bounding circle beyond the end of
    the freespace or clear of one of the beam's two half-planes (the tests of
    :func:`~sonarcarve.geometry.evidence.beam.mark_near`, one arc at a time with early exits,
    as :func:`evidence_free` always did them)."""
    if status[i] != EVIDENCE_ALIVE:
        return True
    dcx = circle[0, i] - beam.x
    dcy = circle[1, i] - beam.y
    rho = circle[2, i]
    if dcx * dcx + dcy * dcy >= (beam.reach + rho) * (beam.reach + rho):
        return True
    below_lower_edge = beam.edge1_x * dcy - beam.edge1_y * dcx < -rho
    return bool(below_lower_edge or dcx * beam.edge2_y - dcy * beam.edge2_x < -rho)


@compiled_inline
def _weigh_silence(i: int, beam: Beam, distinct: bool, params: EvidenceParams,
                   shapes: ArcShapes, evidence: BinEvidence,
                   touched: BoolArray) -> tuple[int, float]:
    """Add the no-echo reading's free evidence to the live bins of older arc ``i`` inside its
    freespace sector (eq. 3.2; ``P_detect`` as
    :func:`~sonarcarve.geometry.evidence.model.detect_probability`). Returns the arc's live
    bins left and its largest "looked" ``P_beam`` (0 unless ``distinct``)."""
    bx, by, ex, ey = shapes.bx, shapes.by, shapes.ex, shapes.ey
    free, support = evidence.free, evidence.support
    threshold = params.threshold
    xj = beam.x
    yj = beam.y
    cj = beam.cos_axis
    sj = beam.sin_axis
    alive_bins = 0
    top_looked = 0.0
    for k in range(bx.shape[1]):
        f = free[i, k]
        if f >= threshold:
            continue
        vx = bx[i, k] - xj
        vy = by[i, k] - yj
        d2 = vx * vx + vy * vy
        along = vx * cj + vy * sj
        if d2 >= beam.reach2 or along <= 0.0 or along * along < d2 * beam.cos_half2:
            alive_bins += 1
            continue
        d = math.sqrt(d2)
        # detect_probability's formula, written out as evidence_add's passes write it (the same
        # operations, so the same bits); tests/geometry/test_evidence_passes.py checks both
        # against a plain reference.
        u = min(abs(vx * sj - vy * cj) / (d * beam.sin_half), 1.0)
        p_beam = params.max_detect * (1.0 - beam.edge_loss * u * u) / (1.0 + d * beam.inv_scale)
        cos_gamma = abs(ex[i, k] * vx + ey[i, k] * vy) / d
        p = p_beam * incidence_gain(cos_gamma, beam.cos_full, beam.cos_zero, params.rough)
        touched[i] = True
        if distinct:
            top_looked = max(top_looked, p_beam)
        established = support[i, k] >= params.establish and f < 0.5 * threshold
        f += -math.log1p(-p) * (params.protect if established else 1.0)
        free[i, k] = f
        if f < threshold:
            alive_bins += 1
    return alive_bins, top_looked


@compiled_borrowing
def evidence_free(reading: SilentReading | PlainBundle, older: SlotArray,
                  state: EvidenceState | PlainBundle, params: EvidenceParams) -> int:
    """Add the free-space evidence of a no-echo ``reading`` against every ``older`` arc.

    The reading heard nothing up to ``max_range`` metres: every bin centre of a live arc
    inside its beam nearer than ``max_range - ε`` gains ``-log(1 - P_detect)`` (times
    ``protect`` where the bin is established), as in
    :func:`~sonarcarve.geometry.evidence.evidence_add`; ``touched`` and ``looked`` are updated
    the same way. ``state`` is the model's arrays as ``evidence_add`` takes them
    (:class:`~sonarcarve.geometry.evidence.arrays.EvidenceState`, named or
    :func:`~sonarcarve.geometry.evidence.arrays.plain`; the readings, the shapes, the
    evidence, ``status``, ``touched`` and ``looked`` are read). ``reading`` may be plain too.

    Returns
    -------
    int
        Arcs whose last bin this reading carved.
    """
    reading = SilentReading(*reading)
    state = named_state(state)
    if reading.max_range - params.tolerance <= 0.0:  # no freespace at all
        return 0
    beam = _silent_beam(reading, params)
    readings, arcs = state.readings, state.arcs
    fully = 0
    for i in older:
        if _out_of_reach(i, beam, state.shapes.circle, arcs.status):
            continue
        ox = readings.x[i] - reading.x
        oy = readings.y[i] - reading.y
        distinct = readings.sensor[i] != reading.sensor or ox * ox + oy * oy >= beam.spacing2
        alive_bins, top_looked = _weigh_silence(i, beam, distinct, params, state.shapes,
                                                state.evidence, arcs.touched)
        if distinct and top_looked > 0.0:
            arcs.looked[i] += -math.log1p(-top_looked)
        if alive_bins == 0:
            arcs.status[i] = EVIDENCE_CARVED
            fully += 1
    return fully
