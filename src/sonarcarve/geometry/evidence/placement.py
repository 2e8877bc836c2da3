"""Where on a surviving run of an arc's bins the echo came from (beyond eq. 3.6's middle).

Two rules, both over bins ``start .. end - 1`` of one arc's profile:

* the median of a posterior: bin ``k`` weighs ``exp(-F_k)`` (the chance that every newer
  reading that looked there missed a surface there, ``F_k`` its free evidence) times its
  localised support ``L_k`` when the run has any, uniform inside a bin, so equal weights give
  the run's middle (eq. 3.6): :func:`posterior_median`;
* the bin at the median of the localised support alone (the rule before it):
  :func:`located_median`.

Which one :func:`~sonarcarve.geometry.evidence.evidence_estimates` uses, and the measurements
behind that choice, are in its docstring (``docs/evidence-carving.md``, "Placing the point").
"""

from __future__ import annotations

import math

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.typing import FloatArray

__all__ = ["located_median", "posterior_median"]


@compiled_inline
def located_median(located: FloatArray, s: int, start: int, end: int, lo_axis: float,
                    step: float, mid: float) -> float:
    """Bearing of the median of the localised support over bins ``start .. end - 1`` of arc
    ``s`` (``mid`` where there is none)."""
    total = 0.0
    for k in range(start, end):
        total += located[s, k]
    if total <= 0.0:
        return mid
    acc = 0.0
    for k in range(start, end):
        acc += located[s, k]
        if acc >= 0.5 * total:
            return lo_axis + (k + 0.5) * step
    return mid


@compiled_inline
def _posterior_weight(located: float, free: float, with_located: bool) -> float:
    """Unnormalised posterior that the echo came from a bin: ``exp(-F)``, the probability
    that every newer reading that looked there missed a surface there (``F = Σ -log(1 - P)``,
    the bin's free evidence; strictly, of the evidence left after the ``protect`` factor and
    with transmission's share added, so a likelihood in that model's sense), times the bin's
    localised support when the run has any."""
    w = math.exp(-free)
    return w * located if with_located else w


@compiled_inline
def posterior_median(located: FloatArray, free: FloatArray, weights: FloatArray, s: int,
                      start: int, end: int, lo_axis: float, step: float, mid: float) -> float:
    """Bearing of the median of the posterior over bins ``start .. end - 1`` of arc ``s``
    (:func:`_posterior_weight`; uniform inside a bin, so the median is interpolated: a run
    with equal weights gives its middle, eq. 3.6, to rounding). ``mid`` where every weight is
    0. Where the weight reaches exactly half at the end of a bin followed by bins of weight 0,
    every point of those bins is a median: their middle is taken (the lower end would depend on
    the direction of the scan: a mirror-image profile would not give the mirror-image point).
    ``weights`` (shape (K,), overwritten) keeps each bin's weight between the sum and the
    median: one ``exp`` a bin, not two."""
    with_located = False
    for k in range(start, end):
        if located[s, k] > 0.0:
            with_located = True
    total = 0.0
    for k in range(start, end):
        weights[k] = _posterior_weight(located[s, k], free[s, k], with_located)
        total += weights[k]
    if not total > 0.0:
        return mid
    half = 0.5 * total
    acc = 0.0
    for k in range(start, end):
        w = float(weights[k])
        if w > 0.0 and acc + w >= half:
            # At most the whole bin: a weight below an ulp of ``half`` can round acc + w up to
            # it while half - acc is still larger than the weight.
            point = k + min((half - acc) / w, 1.0)
            if acc + w == half:  # flat at one half over the zero-weight bins after k
                after = k + 1
                while after < end and not weights[after] > 0.0:
                    after += 1
                if after < end:
                    point = 0.5 * (k + 1 + after)
            return lo_axis + point * step
        acc += w
    return mid
