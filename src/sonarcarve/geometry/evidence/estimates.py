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
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.geometry.evidence.arrays import (
    BinEvidence,
    CrossingArrays,
    PlainBundle,
    ReadingRows,
)
from sonarcarve.geometry.evidence.model import EVIDENCE_ALIVE
from sonarcarve.geometry.evidence.placement import located_median, posterior_median
from sonarcarve.geometry.evidence.runs import (
    crossings_per_bin,
    kept_run,
    run_crossings,
    run_evidence,
)
from sonarcarve.typing import BoolArray, FloatArray, Int8Array, SlotArray

__all__ = ["EstimateRules", "PieceEstimates", "evidence_estimates"]


class EstimateRules(NamedTuple):
    """How :func:`evidence_estimates` keeps a piece, places its point and bounds it.

    Attributes
    ----------
    threshold : float
        ``T``: a bin with free evidence at or above it is carved.
    atm_bound : float
        ATM's bound of a median of crossings, eq. 5.4 times δ, metres.
    with_atm : bool
        Count the arcs' ATM crossings (without: none is read).
    place_located : bool
        Place the point by the evidence, not at the kept run's middle (eq. 3.6).
    posterior : bool
        With ``place_located``: at the median of the posterior over the run's bins, not of
        its localised support.
    posterior_uncut : bool
        With both: a beam nothing has cut is placed by the posterior too, not at its middle.
    min_crossings : int
        Crossings the kept run needs before their median may place the point.

    :func:`evidence_estimates` gives each rule's reason and measurement.
    """

    threshold: float
    atm_bound: float
    with_atm: bool
    place_located: bool
    posterior: bool = True
    posterior_uncut: bool = False
    min_crossings: int = 3


class PieceEstimates(NamedTuple):
    """What :func:`evidence_estimates` gives per slot, shape (n,) each.

    Attributes
    ----------
    has_piece : ndarray of bool
        At least one bin survives.
    bearing : ndarray
        Bearing of the point, radians (unwrapped near the axis).
    width : ndarray
        Width of the kept run, radians.
    max_error : ndarray
        Bound, metres.
    piece_support : ndarray
        Largest support of a bin in the kept run.
    is_atm : ndarray of bool
        The point is an ATM median.
    piece_crossings : ndarray
        ATM crossings inside the kept run.
    piece_free : ndarray
        Mean free evidence over the kept run, in units of ``T``.
    runs : ndarray
        Number of surviving runs.
    hull_share : ndarray
        Surviving hull width over the full beam.
    """

    has_piece: BoolArray
    bearing: FloatArray
    width: FloatArray
    max_error: FloatArray
    piece_support: FloatArray
    is_atm: BoolArray
    piece_crossings: FloatArray
    piece_free: FloatArray
    runs: FloatArray
    hull_share: FloatArray


class _KeptRun(NamedTuple):
    """An arc's kept run, ``start .. end - 1`` in bins, within its surviving hull
    ``first .. last - 1``, and its number of surviving runs (0: none, the arc is carved)."""

    start: int
    end: int
    first: int
    last: int
    runs: int


class _SlotBeam(NamedTuple):
    """An arc's beam as :func:`evidence_estimates` reads it (metres, radians): its bins are
    ``step`` wide from ``lo_axis = theta - half``."""

    r: float
    theta: float
    phi: float
    half: float
    step: float
    lo_axis: float


class _Piece(NamedTuple):
    """An arc's piece as carving leaves it: point bearing, kept run's width, the bound, the
    run's largest support and mean free evidence (in ``T``), the hull's share of the beam."""

    bearing: float
    width: float
    max_error: float
    support: float
    free: float
    hull_share: float


class _RunScratch(NamedTuple):
    """Work arrays of one arc's kept run: crossings per bin (K,), the run's crossings and
    their bins (C,), the posterior's weights (K,)."""

    in_bin: FloatArray
    values: FloatArray
    crossing_bin: SlotArray
    weights: FloatArray


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
def _placed_bearing(s: int, run: _KeptRun, lo_axis: float, step: float, located: FloatArray,
                    free: FloatArray, rules: EstimateRules, weights: FloatArray) -> float:
    """Bearing of the point on the kept ``run`` of arc ``s`` (its bins from ``lo_axis``,
    ``step`` wide): the posterior's median, the localised support's or the run's middle
    (eq. 3.6), by the rules of :func:`evidence_estimates`; ``weights`` is the posterior's
    scratch."""
    start, end = run.start, run.end
    cut = end - start < free.shape[1]  # evidence has cut the beam
    mid = 0.5 * ((lo_axis + start * step) + (lo_axis + end * step))  # eq. 3.6
    if rules.place_located and rules.posterior and (cut or rules.posterior_uncut):
        return posterior_median(located, free, weights, s, start, end, lo_axis, step, mid)
    if rules.place_located and cut:
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
def _empty_estimates(n: int) -> PieceEstimates:
    """:class:`PieceEstimates` of ``n`` slots, all zero (no piece)."""
    return PieceEstimates(
        has_piece=np.zeros(n, dtype=np.bool_), bearing=np.zeros(n), width=np.zeros(n),
        max_error=np.zeros(n), piece_support=np.zeros(n), is_atm=np.zeros(n, dtype=np.bool_),
        piece_crossings=np.zeros(n), piece_free=np.zeros(n), runs=np.zeros(n),
        hull_share=np.zeros(n),
    )


@compiled_inline
def _slot_beam(r: float, theta: float, phi: float, bins: int) -> _SlotBeam:
    """An arc's beam as its estimate reads it: range ``r``, axis ``theta``, width ``phi``."""
    half = 0.5 * phi
    return _SlotBeam(r=r, theta=theta, phi=phi, half=half, step=phi / bins,
                     lo_axis=theta - half)


@compiled_inline
def _kept_run_of(s: int, c: int, beam: _SlotBeam, status: Int8Array, evidence: BinEvidence,
                 bearings: npt.NDArray[np.float32], threshold: float,
                 in_bin: FloatArray, crossing_bin: SlotArray) -> _KeptRun:
    """:func:`~sonarcarve.geometry.evidence.runs.kept_run` of arc ``s`` after counting its
    first ``c`` crossings per bin (they weigh in which run is kept; their bins stay in
    ``work.crossing_bin``); no run (all 0) for an arc already carved."""
    if status[s] != EVIDENCE_ALIVE:
        return _KeptRun(start=0, end=0, first=0, last=0, runs=0)
    crossings_per_bin(in_bin, crossing_bin, bearings, s, c, beam.half, beam.step)
    start, end, first, last, runs = kept_run(evidence.free, evidence.located, in_bin, s,
                                             threshold)
    return _KeptRun(start=start, end=end, first=first, last=last, runs=runs)


@compiled_inline
def _carved_piece(s: int, run: _KeptRun, beam: _SlotBeam, evidence: BinEvidence,
                  rules: EstimateRules, weights: FloatArray) -> _Piece:
    """Arc ``s``'s piece as evidence carving leaves it: the point it places on the kept
    ``run`` (:func:`_placed_bearing`) with the surviving hull's bound (:func:`_hull_bound`,
    eq. 5.3), and the run's evidence."""
    hull_lo = beam.lo_axis + run.first * beam.step
    hull_hi = beam.lo_axis + run.last * beam.step
    mid = _placed_bearing(s, run, beam.lo_axis, beam.step, evidence.located, evidence.free,
                          rules, weights)
    support, free = run_evidence(evidence.support, evidence.free, s, run.start, run.end,
                                 rules.threshold)
    return _Piece(
        bearing=mid,
        width=(beam.lo_axis + run.end * beam.step) - (beam.lo_axis + run.start * beam.step),
        max_error=_hull_bound(beam.r, mid, hull_lo, hull_hi, beam.step), support=support,
        free=free, hull_share=(hull_hi - hull_lo) / beam.phi,
    )


@compiled_inline
def _atm_median(s: int, c: int, run: _KeptRun, beam: _SlotBeam,
                bearings: npt.NDArray[np.float32], rules: EstimateRules, values: FloatArray,
                crossing_bin: SlotArray) -> tuple[int, float, float]:
    """ATM's crossings of arc ``s`` (of its first ``c``) inside its kept ``run``: how many,
    their median bearing and its bound (:func:`_atm_median_bound`; infinite when fewer than
    ``min_crossings``, so that the carved point stays)."""
    kept, median_rel = run_crossings(values, crossing_bin, bearings, s, c, run.start, run.end)
    if kept > 0 and kept >= rules.min_crossings:
        median = beam.theta + median_rel
        bound = _atm_median_bound(median, run.runs, rules.atm_bound, beam.r,
                                  beam.lo_axis + run.first * beam.step,
                                  beam.lo_axis + run.last * beam.step, beam.step)
        return kept, median, bound
    return kept, 0.0, math.inf


@compiled_inline
def _store_piece(q: int, run: _KeptRun, piece: _Piece, kept: int, median: float,
                 median_bound: float, out: PieceEstimates) -> None:
    """Row ``q`` of ``out``: the carved ``piece``, its point replaced by ATM's ``median`` of
    the ``kept`` crossings where that bound is the smaller (section 4: the estimate with the
    smaller bound)."""
    use_atm = median_bound < piece.max_error
    out.has_piece[q] = True
    out.width[q] = piece.width
    out.piece_support[q] = piece.support
    out.piece_free[q] = piece.free
    out.runs[q] = run.runs
    out.hull_share[q] = piece.hull_share
    out.bearing[q] = median if use_atm else piece.bearing
    out.max_error[q] = median_bound if use_atm else piece.max_error
    out.is_atm[q] = use_atm
    out.piece_crossings[q] = kept


@compiled
def evidence_estimates(slots: SlotArray, readings: ReadingRows | PlainBundle,
                       evidence: BinEvidence | PlainBundle, status: Int8Array,
                       crossings: CrossingArrays | PlainBundle,
                       rules: EstimateRules | PlainBundle) -> PieceEstimates:
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

    Parameters
    ----------
    slots : ndarray of int64, shape (n,)
        The history rows to estimate.
    readings, evidence, crossings
        The model's readings, per-bin evidence and ATM's crossing store
        (:mod:`~sonarcarve.geometry.evidence.arrays`; only ``crossings.bearings`` and
        ``counts`` are read).
    status : ndarray of int8
        ``EVIDENCE_ALIVE`` or ``EVIDENCE_CARVED`` per row.
    rules : EstimateRules
        The threshold, ATM's bound and the placement rules above.

    Each bundle may be named or :func:`~sonarcarve.geometry.evidence.arrays.plain` (faster
    to call: the module docstring of :mod:`~sonarcarve.geometry.evidence.arrays`).

    Returns
    -------
    PieceEstimates
        Per slot: the piece, its point, width and bound, and the evidence behind it.

    Raises
    ------
    IndexError
        A slot outside ``-len(x) .. len(x) - 1`` (compiled indexing checks no bounds: such a
        slot read other memory, or crashed the process).
    """
    readings = ReadingRows(*readings)
    evidence = BinEvidence(*evidence)
    crossings = CrossingArrays(*crossings)
    rules = EstimateRules(*rules)
    n = slots.shape[0]
    bins = evidence.free.shape[1]
    columns = crossings.bearings.shape[1]
    out = _empty_estimates(n)
    work = _RunScratch(in_bin=np.zeros(bins), values=np.zeros(columns),
                       crossing_bin=np.zeros(columns, dtype=np.int64), weights=np.zeros(bins))
    storage = readings.x.shape[0]
    for q in range(n):
        s = slots[q]
        if s < -storage or s >= storage:  # compiled indexing checks no bounds
            raise IndexError("a slot is out of bounds for the history's storage")
        beam = _slot_beam(readings.r[s], readings.theta[s], readings.beam_width[s], bins)
        c = crossings.counts[s] if rules.with_atm else 0
        run = _kept_run_of(s, c, beam, status, evidence, crossings.bearings, rules.threshold,
                           work.in_bin, work.crossing_bin)
        if run.runs == 0:  # nothing survives: the whole beam's middle (eq. 3.3)
            out.bearing[q] = beam.theta
            out.width[q] = beam.phi
            out.max_error[q] = _whole_beam_bound(beam.r, beam.phi)
            continue
        piece = _carved_piece(s, run, beam, evidence, rules, work.weights)
        kept, median, median_bound = _atm_median(s, c, run, beam, crossings.bearings, rules,
                                                 work.values, work.crossing_bin)
        _store_piece(q, run, piece, kept, median, median_bound, out)
    return out
