"""A no-echo reading in evidence carving: free-space evidence up to its maximum range, nothing else.

A reading that heard nothing up to its ``max_range`` adds the evidence of an echo's freespace
with ``r_j = max_range``: ``w = -log(1 - P_detect)`` at every bin centre of a live arc in its
beam nearer than ``max_range - ε``, and no support, occlusion, crossing or arc of its own
(``docs/evidence-carving.md``, "No-echo readings").
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled_borrowing
from sonarcarve.geometry.evidence.model import (
    EVIDENCE_ALIVE,
    EVIDENCE_CARVED,
    EvidenceParams,
    incidence_gain,
)
from sonarcarve.typing import BoolArray, FloatArray, Int8Array, SlotArray

__all__ = ["evidence_free"]


@compiled_borrowing
def evidence_free(
    xj: float, yj: float, max_range: float, theta_j: float, phi_j: float, sensor_j: int,
    older: SlotArray, x: FloatArray, y: FloatArray, beam_width: FloatArray,
    sensor: npt.NDArray[np.int64], looked: FloatArray, bx: FloatArray, by: FloatArray,
    ex: FloatArray, ey: FloatArray, free: FloatArray, support: FloatArray, circle: FloatArray,
    status: Int8Array, touched: BoolArray, params: EvidenceParams,
) -> int:
    """Add the free-space evidence of a no-echo reading against every ``older`` arc.

    The reading is at ``(xj, yj)`` (metres) along ``theta_j`` with beam width ``phi_j``
    (radians), from sensor ``sensor_j``, and heard nothing up to ``max_range`` metres: every
    bin centre of a live arc inside its beam nearer than ``max_range - ε`` gains
    ``-log(1 - P_detect)`` (times ``protect`` where the bin is established), as in
    :func:`~sonarcarve.geometry.evidence.evidence_add`; ``touched`` and ``looked`` are updated
    the same way. The arrays are those of :func:`~sonarcarve.geometry.evidence.evidence_add`.

    Returns
    -------
    int
        Arcs whose last bin this reading carved.
    """
    bins = bx.shape[1]
    threshold = params.threshold
    free_r = max_range - params.tolerance
    if free_r <= 0.0:
        return 0
    half_j = 0.5 * phi_j
    cj = math.cos(theta_j)
    sj = math.sin(theta_j)
    sin_half_j = math.sin(half_j)
    cos_half_j = math.cos(half_j)
    cos_half_j2 = cos_half_j * cos_half_j
    reach2 = free_r * free_r
    edge_loss = 1.0 - params.edge_gain
    inv_scale = 1.0 / params.range_scale
    u1x = cj * cos_half_j + sj * sin_half_j
    u1y = sj * cos_half_j - cj * sin_half_j
    u2x = cj * cos_half_j - sj * sin_half_j
    u2y = sj * cos_half_j + cj * sin_half_j
    cos_full = math.cos(params.incidence_full)
    cos_zero = math.cos(params.incidence_zero)
    spacing2 = params.viewpoint_spacing * params.viewpoint_spacing
    fully = 0
    for i in older:
        if status[i] != EVIDENCE_ALIVE:
            continue
        dcx = circle[0, i] - xj
        dcy = circle[1, i] - yj
        rho = circle[2, i]
        if dcx * dcx + dcy * dcy >= (free_r + rho) * (free_r + rho):
            continue
        if u1x * dcy - u1y * dcx < -rho or dcx * u2y - dcy * u2x < -rho:
            continue
        ox = x[i] - xj
        oy = y[i] - yj
        distinct = sensor[i] != sensor_j or ox * ox + oy * oy >= spacing2
        alive_bins = 0
        top_looked = 0.0
        for k in range(bins):
            f = free[i, k]
            if f >= threshold:
                continue
            vx = bx[i, k] - xj
            vy = by[i, k] - yj
            d2 = vx * vx + vy * vy
            along = vx * cj + vy * sj
            if d2 >= reach2 or along <= 0.0 or along * along < d2 * cos_half_j2:
                alive_bins += 1
                continue
            d = math.sqrt(d2)
            u = min(abs(vx * sj - vy * cj) / (d * sin_half_j), 1.0)
            p_beam = params.max_detect * (1.0 - edge_loss * u * u) / (1.0 + d * inv_scale)
            cos_gamma = abs(ex[i, k] * vx + ey[i, k] * vy) / d
            p = p_beam * incidence_gain(cos_gamma, cos_full, cos_zero, params.rough)
            touched[i] = True
            if distinct:
                top_looked = max(top_looked, p_beam)
            established = support[i, k] >= params.establish and f < 0.5 * threshold
            f += -math.log1p(-p) * (params.protect if established else 1.0)
            free[i, k] = f
            if f < threshold:
                alive_bins += 1
        if distinct and top_looked > 0.0:
            looked[i] += -math.log1p(-top_looked)
        if alive_bins == 0:
            status[i] = EVIDENCE_CARVED
            fully += 1
    return fully
