"""Behind: how far an echo lies behind a surface the history holds with confidence inside its
beam, judged when the arc leaves the history (issue 9: "multipath echoes read too long, behind
surfaces the map already holds").

A multipath echo's sound met a wall at a glancing angle, went on to another surface and came
back: its range is too long, and a surface the ring hears directly lies inside its beam, nearer
than its echo. Often that wall is not yet established when the echo arrives (the occlusion rule,
:mod:`~sonarcarve.geometry.evidence.occlusion`, then carves nothing): the readings that hear it
squarely come later. So the depth is taken when the arc leaves the history
(:func:`depth_behind_newer`, called by
:func:`~sonarcarve.geometry.evidence.evidence_add_many`), over the :data:`NEWER_ARCS` arcs that
came right after it (those the ring fired from about where it stood, and which have had the
longest to be confirmed): each one's axis point ``o_i + r_i u(θ_i)`` where the arc is still
alive and heard from distinct viewpoints (``viewpoints`` at least ``S_est``), inside the arc's
beam nearer than ``r_j - 2ε``.

The depth is ``r_j - d`` for the nearest such point, ``d = |p_i - o_j|`` its distance from the
leaving arc's origin, metres; 0 when there is none. A direct echo heard by one sensor alone (a
door jamb) has nothing nearer in its beam, so the depth is 0 there, while the features it lacks
(other sensors, crossings) would otherwise make it look like a spurious echo.

Only on leaving, never on arrival: an arc in the history has depth 0, so its confidence, and
with it the live (local) map, is what it was without the feature. Taken on arrival too (over
the older arcs' established bins, the first version), it made the map forget a person who left
slowly: the wall heard once the person had gone lay behind the person's still-established
echoes. Arcs still in the history when a log ends are committed with depth 0 (never judged).
``docs/evidence-carving.md``, "Behind".
"""

from __future__ import annotations

import math

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.geometry.evidence.model import EVIDENCE_ALIVE
from sonarcarve.typing import FloatArray, Int8Array

__all__ = ["NEWER_ARCS", "depth_behind_newer"]

#: The arcs after a leaving arc that it is judged against (fewer when the history is shorter).
#: A bound on the work per reading, which would otherwise grow with the history (every arc
#: leaving scans the others: 14 % of evidence carving's throughput at a history of 1,000); on
#: the held-out floors under specular physics 64 removed as many spurious echoes as the whole
#: history of 250 did, 82.1 % (measured on the first version, depth also taken on arrival;
#: ``docs/evidence-carving.md``, "Behind").
NEWER_ARCS = 64


@compiled_inline
def _in_beam_distances(xj: float, yj: float, cj: float, sj: float, cos_half2: float,
                       x: FloatArray, y: FloatArray, r: FloatArray, cos_axis: FloatArray,
                       sin_axis: FloatArray, status: Int8Array, viewpoints: FloatArray,
                       establish: float, out: FloatArray) -> None:
    """``out[i]`` for each row of the arrays (slices of the history's rows): the squared
    distance from ``(xj, yj)`` to row ``i``'s axis point where the arc is alive, heard from
    distinct viewpoints and the point inside the beam (axis ``(cj, sj)``, ``cos²(φ/2)``),
    else infinity. No branch, no reduction and indices from 0 (no test for negative ones),
    so the compiler runs it on several rows at once."""
    for i in range(out.shape[0]):
        px = x[i] + r[i] * cos_axis[i] - xj
        py = y[i] + r[i] * sin_axis[i] - yj
        d2 = px * px + py * py
        along = px * cj + py * sj
        ok = ((status[i] == EVIDENCE_ALIVE) & (viewpoints[i] >= establish) & (along > 0.0)
              & (along * along >= d2 * cos_half2))
        out[i] = d2 if ok else math.inf


@compiled_inline
def _smallest(best: float, values: FloatArray) -> float:
    """The smallest of ``best`` and ``values``."""
    for i in range(values.shape[0]):
        if values[i] < best:
            best = values[i]
    return best


@compiled_inline
def depth_behind_newer(j: int, first: int, n_newer: int, x: FloatArray, y: FloatArray,
                       r: FloatArray, cos_axis: FloatArray, sin_axis: FloatArray,
                       cos_half: FloatArray, status: Int8Array, viewpoints: FloatArray,
                       establish: float, margin: float, scratch: FloatArray) -> float:
    """``r_j - d`` for the nearest axis point of the ``n_newer`` arcs from row ``first`` on
    (wrapping at the end of the rows) that is alive, heard from distinct viewpoints
    (``viewpoints >= establish``) and inside arc ``j``'s beam nearer than ``r_j - margin``;
    0 when there is none (module docstring). ``scratch``: one value per row, overwritten."""
    near = r[j] - margin
    if near <= 0.0:
        return 0.0
    storage = x.shape[0]
    limit = near * near
    end = first + n_newer
    xj = x[j]
    yj = y[j]
    cj = cos_axis[j]
    sj = sin_axis[j]
    cos_half2 = cos_half[j] * cos_half[j]
    best = limit
    for lo, hi in ((first, min(end, storage)), (0, max(end - storage, 0))):
        _in_beam_distances(xj, yj, cj, sj, cos_half2, x[lo:hi], y[lo:hi], r[lo:hi],
                           cos_axis[lo:hi], sin_axis[lo:hi], status[lo:hi], viewpoints[lo:hi],
                           establish, scratch[lo:hi])
        best = _smallest(best, scratch[lo:hi])
    return r[j] - math.sqrt(best) if best < limit else 0.0
