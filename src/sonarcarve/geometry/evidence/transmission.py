"""Transmission: a surface a newer beam passed obliquely, on its way to an echo that other
sensors confirm beyond it, did not stop the sound.

For each older live bin the new reading ``j`` looked past (nearer than ``r_j - ε``, its
incidence factor below 1), ``S`` the support of ``j``'s bin behind it from other sensors' older
echoes::

    P_t = transmit · P_beam · cos γ · min(1, S / S_conf),    w_t = -log(1 - P_t)

(times ``protect`` where the bin is established) replaces the bin's incidence evidence ``w``
when larger (one reading, one event). ``cos γ`` is
the share of the beam the implied surface would block (a wall the beam runs along does not);
bins of ``j`` carved by occlusion confirm nothing. ``docs/evidence-carving.md``,
"Transmission".
"""

from __future__ import annotations

import math

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.geometry.evidence.model import EVIDENCE_ALIVE, EVIDENCE_CARVED, EvidenceParams
from sonarcarve.typing import FloatArray, Int8Array

__all__ = ["weigh_transmission"]


@compiled_inline
def weigh_transmission(slot: int, passed: FloatArray, n_passed: int, trans: FloatArray,
                       free: FloatArray, status: Int8Array, params: EvidenceParams) -> int:
    """Transmission evidence of the new reading ``slot`` (module docstring).

    For each older live bin it looked past (``passed`` rows: arc, bin, the new arc's bin
    behind it, ``P_beam cos γ``, ``protect`` factor, evidence already given), the chance that
    the sound went through is ``transmit · P_beam · cos γ · min(1, S / S_conf)``, ``S`` the
    new arc's support from other sensors in the bin behind; the bin gains what that exceeds
    the incidence evidence by (one reading, one event: the larger of the two counts). Returns
    the arcs this carved fully.
    """
    threshold = params.threshold
    bins = free.shape[1]
    fully = 0
    for m in range(n_passed):
        kj = int(passed[m, 2])
        s = trans[kj]
        if s <= 0.0 or free[slot, kj] >= threshold:
            continue  # nothing confirmed behind, or that bin of the new arc is occluded
        i = int(passed[m, 0])
        k = int(passed[m, 1])
        if status[i] != EVIDENCE_ALIVE or free[i, k] >= threshold:
            continue
        p_t = params.transmit * passed[m, 3] * min(1.0, s / params.confirm)
        w_t = -math.log1p(-p_t) * passed[m, 4]
        if w_t <= passed[m, 5]:
            continue
        free[i, k] += w_t - passed[m, 5]
        if free[i, k] >= threshold:
            alive = False
            for kk in range(bins):
                if free[i, kk] < threshold:
                    alive = True
                    break
            if not alive:
                status[i] = EVIDENCE_CARVED
                fully += 1
    return fully
