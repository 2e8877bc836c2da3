"""What evidence carving estimates of each arc: the surviving piece, its point and its bound.

Per arc: the kept run of surviving bins (:mod:`~sonarcarve.geometry.evidence.runs`), its point
(the run's middle, eq. 3.6, or where the evidence places the echo:
:mod:`~sonarcarve.geometry.evidence.placement`), replaced by ATM's median of the crossings in
the run where that bound is the smaller (section 4), and a bound covering every surviving run,
widened by half a bin at each end (``E_s = 2 r sin(e/2)``, eq. 5.3;
``docs/evidence-carving.md``, "What is exact and what is binned").
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.geometry.evidence.model import EVIDENCE_ALIVE
from sonarcarve.geometry.evidence.placement import located_median, posterior_median
from sonarcarve.geometry.evidence.runs import (
    crossings_per_bin,
    kept_run,
    run_crossings,
    run_evidence,
)
from sonarcarve.typing import BoolArray, FloatArray, Int8Array, SlotArray

__all__ = ["evidence_estimates"]


@compiled_inline
def _whole_beam_bound(r: float, phi: float) -> float:
    """``E_s = 2 r sin(φ/4)`` (eq. 5.3): the bound of a point at the middle of the full beam."""
    return 2.0 * r * math.sin(0.25 * phi)


@compiled_inline
def _hull_bound(r: float, point: float, hull_lo: float, hull_hi: float, step: float) -> float:
    """``2 r sin(e/2)`` (eq. 5.3), ``e`` the largest angle from the point's bearing to an end of
    the surviving hull ``[hull_lo, hull_hi]`` plus half a bin (the binned ends), at most π."""
    e = max(point - hull_lo, hull_hi - point) + 0.5 * step
    return 2.0 * r * math.sin(0.5 * min(e, math.pi))


@compiled_inline
def _placed_bearing(located: FloatArray, free: FloatArray, weights: FloatArray, s: int,
                    start: int, end: int, lo_axis: float, step: float, cut: bool,
                    place_located: bool, posterior: bool, posterior_uncut: bool) -> float:
    """Bearing of the point on the kept run ``start .. end - 1`` of arc ``s``: the posterior's
    median, the localised support's or the run's middle (eq. 3.6), by the rules of
    :func:`evidence_estimates`; ``cut`` where evidence has cut the beam."""
    mid = 0.5 * ((lo_axis + start * step) + (lo_axis + end * step))  # eq. 3.6
    if place_located and posterior and (cut or posterior_uncut):
        return posterior_median(located, free, weights, s, start, end, lo_axis, step, mid)
    if place_located and cut:
        return located_median(located, s, start, end, lo_axis, step, mid)
    return mid


@compiled_inline
def _atm_median_bound(median: float, runs: int, atm_bound: float, r: float, hull_lo: float,
                      hull_hi: float, step: float) -> float:
    """Bound of ATM's median of the kept run's crossings: eq. 5.4 times δ (``atm_bound``) when
    the run is all that survives, else the surviving hull's (:func:`_hull_bound`: the echo may
    be in any run)."""
    return atm_bound if runs == 1 else _hull_bound(r, median, hull_lo, hull_hi, step)


@compiled_inline
def _kept_run_of(s: int, status: Int8Array, free: FloatArray, located: FloatArray,
                 in_bin: FloatArray, crossing_bin: SlotArray, bearings: npt.NDArray[np.float32],
                 c: int, half: float, step: float, threshold: float,
                 ) -> tuple[int, int, int, int, int]:
    """:func:`~sonarcarve.geometry.evidence.runs.kept_run` of arc ``s`` after counting its
    first ``c`` crossings per bin (they weigh in which run is kept); no run (all 0) for an arc
    already carved."""
    if status[s] != EVIDENCE_ALIVE:
        return 0, 0, 0, 0, 0
    crossings_per_bin(in_bin, crossing_bin, bearings, s, c, half, step)
    return kept_run(free, located, in_bin, s, threshold)


@compiled
def evidence_estimates(
    slots: SlotArray, x: FloatArray, y: FloatArray, r: FloatArray, theta: FloatArray,
    beam_width: FloatArray, free: FloatArray, support: FloatArray, located: FloatArray,
    status: Int8Array,
    bearings: npt.NDArray[np.float32], counts: npt.NDArray[np.int32], threshold: float,
    atm_bound: float, with_atm: bool, place_located: bool, posterior: bool = True,
    posterior_uncut: bool = False, min_crossings: int = 3,
) -> tuple[BoolArray, FloatArray, FloatArray, FloatArray, FloatArray, BoolArray,
           FloatArray, FloatArray, FloatArray, FloatArray]:
    """Per slot: the surviving piece, its point, width and bound, and the evidence behind it.

    The surviving bins form runs; with several (a *split* arc), the run with the most
    localised support (``located``) plus ATM crossings is kept (ties: the longest, then the
    first). Where on the run the echo came from (eq. 3.3 knows only that it is somewhere in
    the beam, eq. 3.6 takes the middle of what carving left):

    * with ``place_located`` and ``posterior`` (the default), once evidence has cut the beam,
      at the median of a posterior over the run's bins: bin ``k`` weighs ``exp(-F_k)``, the
      probability that every newer reading that looked there missed a surface there
      (``F_k = Σ -log(1 - P_detect)``, its free evidence: the misses' likelihood), times its
      localised support ``L_k`` (echo circles crossing the arc there, each by its
      ``P_detect`` and the sine of the angle between the circles) when the run has any. The
      weight is taken as uniform inside a bin, so the median is interpolated and equal
      weights give the run's middle (eq. 3.6). A beam nothing has cut keeps its middle
      unless ``posterior_uncut``: there the misses say nothing, the localised support alone
      would place the point, and crossings on a whole beam may be ghosts (two jambs' echo
      circles meet in the doorway between them). Measured (issue 9): on the simulator's
      truth placing uncut beams by the posterior too is more accurate (t-junction median
      0.52 / 0.56 of the centreline's instead of 0.66 / 0.56, doorway p90 0.36 / 0.21 instead
      of 0.47 / 0.29, specular / amplitude physics), but the Fig. 2/9 openings lose doorway
      approaches (specular: 93.5 / 85.2 / 82.7 % passable at 1 / 2 / 3 m -> 92.0 / 83.0 /
      79.3 %): the ghosts are real. So it is an option, off;
    * with ``place_located`` alone (the rule before it), once evidence has cut the beam, the
      bin at the median of the run's localised support (the middle where it has none); an
      uncut beam keeps its middle;
    * without ``place_located``, the run's middle (eq. 3.6).

    The ATM median of the crossings inside the run replaces that point where the run holds at
    least ``min_crossings`` of them (the median of one or two crossings is those crossings:
    one ghost moves it anywhere; from three, one cannot move it outside the others) and its
    bound (eq. 5.4 times δ, ``atm_bound``, for a single run; else the hull's, below) is smaller
    than the point's (section 4: the estimate with the smaller bound). The bound covers every
    surviving run (the echo may be in any of them), widened by half a bin on each side:
    ``2 r sin(e/2)`` with ``e`` the largest angle from the point to the far end of the surviving
    hull plus ``Δ/2`` (eq. 5.3).

    Returns
    -------
    has_piece : bool
        At least one bin survives.
    bearing : float
        Bearing of the point, radians (unwrapped near the axis).
    width : float
        Width of the kept run, radians.
    max_error : float
        Bound, metres.
    piece_support : float
        Largest support of a bin in the kept run.
    is_atm : bool
        The point is an ATM median.
    piece_crossings : float
        ATM crossings inside the kept run.
    piece_free : float
        Mean free evidence over the kept run, in units of ``T``.
    runs : float
        Number of surviving runs.
    hull_share : float
        Surviving hull width over the full beam.

    Raises
    ------
    IndexError
        A slot outside ``-len(x) .. len(x) - 1`` (compiled indexing checks no bounds: such a
        slot read other memory, or crashed the process).
    """
    n = slots.shape[0]
    bins = free.shape[1]
    has_piece = np.zeros(n, dtype=np.bool_)
    bearing = np.zeros(n)
    width = np.zeros(n)
    max_error = np.zeros(n)
    piece_support = np.zeros(n)
    is_atm = np.zeros(n, dtype=np.bool_)
    piece_crossings = np.zeros(n)
    piece_free = np.zeros(n)
    run_count = np.zeros(n)
    hull_share = np.zeros(n)
    in_bin = np.zeros(bins)
    values = np.zeros(bearings.shape[1])
    crossing_bin = np.zeros(bearings.shape[1], dtype=np.int64)
    weights = np.zeros(bins)
    for q in range(n):
        s = slots[q]
        if s < -x.shape[0] or s >= x.shape[0]:  # compiled indexing checks no bounds
            raise IndexError("a slot is out of bounds for the history's storage")
        phi = beam_width[s]
        half = 0.5 * phi
        step = phi / bins
        lo_axis = theta[s] - half
        c = counts[s] if with_atm else 0
        start, end, first, last, runs = _kept_run_of(s, status, free, located, in_bin,
                                                      crossing_bin, bearings, c, half, step,
                                                      threshold)
        if runs == 0:  # nothing survives: the whole beam's middle (eq. 3.3)
            bearing[q] = theta[s]
            width[q] = phi
            max_error[q] = _whole_beam_bound(r[s], phi)
            continue
        has_piece[q] = True
        hull_lo = lo_axis + first * step
        hull_hi = lo_axis + last * step
        mid = _placed_bearing(located, free, weights, s, start, end, lo_axis, step,
                              end - start < bins, place_located, posterior, posterior_uncut)
        width[q] = (lo_axis + end * step) - (lo_axis + start * step)
        piece_support[q], piece_free[q] = run_evidence(support, free, s, start, end, threshold)
        run_count[q] = runs
        hull_share[q] = (hull_hi - hull_lo) / phi
        carved_bound = _hull_bound(r[s], mid, hull_lo, hull_hi, step)
        bearing[q] = mid
        max_error[q] = carved_bound
        kept, median_rel = run_crossings(values, crossing_bin, bearings, s, c, start, end)
        piece_crossings[q] = kept
        if kept > 0 and kept >= min_crossings:  # section 4: the estimate with the smaller bound
            median = theta[s] + median_rel
            bound = _atm_median_bound(median, runs, atm_bound, r[s], hull_lo, hull_hi, step)
            if bound < carved_bound:
                bearing[q] = median
                max_error[q] = bound
                is_atm[q] = True
    return (has_piece, bearing, width, max_error, piece_support, is_atm, piece_crossings,
            piece_free, run_count, hull_share)
