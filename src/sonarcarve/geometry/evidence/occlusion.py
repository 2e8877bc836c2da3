"""Occlusion (multipath): the bins of a new arc behind an established surface are carved.

Sound does not pass through walls. A bin of an older arc that is *established* (support at
least ``S_est``, free evidence below ``T/2``) and lies in the new reading's freespace, nearer
than ``r_j - 2ε``, says that ``j``'s echo did not come from behind it: the bins of ``j`` within
that point's angular half-bin seen from ``o_j`` are carved (a multipath echo reads too long,
behind a wall its beam met at a glancing angle); the point itself takes ``j``'s evidence times
``protect``. ``docs/evidence-carving.md``, "Occlusion" (also: the ``P_detect < ½`` condition
the docstring this came from described, which the code never tested, and why it stays out).
"""

from __future__ import annotations

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.geometry.evidence.beam import Beam
from sonarcarve.geometry.evidence.bins import bin_of
from sonarcarve.typing import FloatArray

__all__ = ["occlude_behind"]


@compiled_inline
def occlude_behind(slot: int, rel: float, spread: float, beam: Beam, free: FloatArray,
                   threshold: float) -> int:
    """Carve the bins of the new arc within ``rel ± spread`` (bearings relative to its axis):
    they lie behind an established surface it looked past, and sound does not pass through
    walls. Returns the bins this carved."""
    bins = free.shape[1]
    k0 = bin_of(rel - spread, beam.half, beam.step, bins)
    k1 = bin_of(rel + spread, beam.half, beam.step, bins)
    carved = 0
    for kk in range(k0, k1 + 1):
        if free[slot, kk] < threshold:
            free[slot, kk] = threshold
            carved += 1
    return carved
