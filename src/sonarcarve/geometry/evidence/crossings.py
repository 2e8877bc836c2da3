"""ATM's transversal crossings (section 6, integration), found in evidence carving's weighing pass.

For each pair of arcs the weighing pass does not cull, the crossings of their echo circles
(eq. 2.1) that meet at least ATM's minimum transversal angle ψ and lie in both beams are
stored per arc as bearings relative to its axis, in ATM's store (``methods/atm.py``). A row
that is full sends its crossings to a spill buffer; the caller widens the store and moves them
(``docs/evidence-carving.md``, "ATM inside evidence carving").
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.geometry.circles import common_chord
from sonarcarve.geometry.evidence.arrays import ArcShapes, CrossingArrays, ReadingRows
from sonarcarve.typing import FloatArray

__all__ = ["transversal_crossings"]


@compiled_inline
def _store_crossing(bearings: npt.NDArray[np.float32], counts: npt.NDArray[np.int32],
                    spill: FloatArray, spilled: int, slot: int, value: float) -> int:
    """Append ``value`` to row ``slot`` of the crossing store; when the row is full, to
    ``spill`` instead (``(slot, value)`` at row ``spilled``). ``counts[slot]`` counts both, so
    the spilled crossings of a row are its last ones, in order. Returns the spilled rows."""
    if counts[slot] < bearings.shape[1]:
        bearings[slot, counts[slot]] = value
    else:
        spill[spilled, 0] = slot
        spill[spilled, 1] = value
        spilled += 1
    counts[slot] += 1
    return spilled


@compiled_inline
def transversal_crossings(j: int, i: int, readings: ReadingRows, shapes: ArcShapes,
                          cos_psi: float, store: CrossingArrays, spilled: int,
                          ) -> tuple[int, int]:
    """ATM's transversal crossings of arcs ``j`` and ``i`` (as ``methods/atm.py``), stored
    (:func:`_store_crossing`). Returns the crossings kept and the rows of ``store.spill``
    used."""
    x, y, r = readings.x, readings.y, readings.r
    cos_axis, sin_axis, cos_half = shapes.cos_axis, shapes.sin_axis, shapes.cos_half
    bearings, counts, spill = store.bearings, store.counts, store.spill
    xj = x[j]
    yj = y[j]
    rj = r[j]
    ri = r[i]
    dx = x[i] - xj
    dy = y[i] - yj
    d2 = dx * dx + dy * dy
    if abs(rj * rj + ri * ri - d2) > 2.0 * rj * ri * cos_psi or d2 == 0.0:
        return 0, spilled
    a, h = common_chord(d2, rj, ri)
    d = math.sqrt(d2)
    ux = dx / d
    uy = dy / d
    kept = 0
    cj = cos_axis[j]
    sj = sin_axis[j]
    for sign in (1.0, -1.0):
        px = a * ux - sign * h * uy
        py = a * uy + sign * h * ux
        along_j = px * cj + py * sj
        if along_j < rj * cos_half[j]:
            continue
        qx = px - dx
        qy = py - dy
        along_i = qx * cos_axis[i] + qy * sin_axis[i]
        if along_i < ri * cos_half[i]:
            continue
        spilled = _store_crossing(bearings, counts, spill, spilled, j,
                                  math.atan2(cj * py - sj * px, along_j))
        spilled = _store_crossing(bearings, counts, spill, spilled, i,
                                  math.atan2(cos_axis[i] * qy - sin_axis[i] * qx, along_i))
        kept += 1
    return kept, spilled
