"""Evidence carving: free-space *evidence* on arcs instead of a veto (beyond the paper).

The paper's carving (eq. 3.5) removes every point of an older arc ``C_i`` that lies in the
freespace sector ``F_j`` of *one* newer reading. Real beams miss surfaces (a smooth wall met at
a glancing angle, the beam's weak edges, far surfaces), so here each arc carries an *evidence
profile*: ``K`` equal bins across its full beam ``[θ_i - φ_i/2, θ_i + φ_i/2]``, bin ``k``
represented by its centre ``p_k`` at bearing ``τ_k = θ1_i + (k + ½) Δ_i``, ``Δ_i = φ_i / K``.

A newer reading ``j`` adds to each bin centre in its beam, ``d = |p_k - o_j|``:

* ``w = -log(1 - P_detect)`` of free-space evidence where ``d < r_j - ε`` (eq. 3.2), with
  ``P_detect = P_max · B · I(γ) · A(d)`` (beam edge, incidence, range;
  :mod:`~sonarcarve.geometry.evidence.model`); the bin is carved at ``T = -log(1 - P_carve)``;
* ``+ P_detect`` of support where ``|d - r_j| ≤ ε_s``, to both arcs;
* occlusion, transmission and ATM's crossings (section 6) in the same pass.

The surviving bins give each arc a piece, a point and a bound
(:func:`evidence_estimates`). The model, every rule's reason and the measurements behind the
kernels' layout: ``docs/evidence-carving.md``.

Modules, from the model up:

* :mod:`~sonarcarve.geometry.evidence.model`: the parameters, ``P_detect``, the threshold;
* :mod:`~sonarcarve.geometry.evidence.bins`: the bin of a bearing or of a direction's sine;
* :mod:`~sonarcarve.geometry.evidence.beam`: the new reading's beam and the cull;
* :mod:`~sonarcarve.geometry.evidence.crossings`: ATM's crossings and their store;
* :mod:`~sonarcarve.geometry.evidence.occlusion`, :mod:`~sonarcarve.geometry.evidence.transmission`:
  the two rules about sound passing (or not) through a surface;
* :mod:`~sonarcarve.geometry.evidence.behind`: how far an arc leaving the history lies behind
  surfaces the arcs after it confirm (a feature of the confidence, not a carving rule);
* :mod:`~sonarcarve.geometry.evidence.watch`: whether a distinct reading, echo or silent, looked
  squarely at an arc (whether its confidence can mature at all; not a carving rule);
* :mod:`~sonarcarve.geometry.evidence.add`: an echo weighed against the older arcs
  (:func:`evidence_add`, :func:`evidence_add_many`);
* :mod:`~sonarcarve.geometry.evidence.free`: a no-echo reading (:func:`evidence_free`);
* :mod:`~sonarcarve.geometry.evidence.runs`, :mod:`~sonarcarve.geometry.evidence.placement`,
  :mod:`~sonarcarve.geometry.evidence.estimates`: the kept run, its point and its bound.
"""

from __future__ import annotations

from sonarcarve.geometry.evidence.add import evidence_add, evidence_add_many
from sonarcarve.geometry.evidence.estimates import (
    EstimateRules,
    PieceEstimates,
    evidence_estimates,
)
from sonarcarve.geometry.evidence.free import SilentReading, evidence_free
from sonarcarve.geometry.evidence.model import (
    EVIDENCE_ALIVE,
    EVIDENCE_CARVED,
    EvidenceParams,
    detect_probability,
    evidence_threshold,
)
from sonarcarve.geometry.evidence.watch import mark_watch, mark_watched_by_silence

__all__ = [
    "EVIDENCE_ALIVE",
    "EVIDENCE_CARVED",
    "EstimateRules",
    "EvidenceParams",
    "PieceEstimates",
    "SilentReading",
    "detect_probability",
    "evidence_add",
    "evidence_add_many",
    "evidence_estimates",
    "evidence_free",
    "evidence_threshold",
    "mark_watch",
    "mark_watched_by_silence",
]
