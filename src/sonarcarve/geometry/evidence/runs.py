"""The surviving runs of an arc's profile: which run is kept, its evidence and its crossings.

The bins whose free evidence is below ``T`` form runs; with several (a *split* arc) the run
with the most ATM crossings plus the largest localised support is kept (ties: the longest,
then the first), and only the crossings inside it count (``docs/evidence-carving.md``,
"Split arcs and the kept run").
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.geometry.evidence.bins import bin_of
from sonarcarve.typing import FloatArray, SlotArray

__all__ = ["crossings_per_bin", "kept_run", "run_crossings", "run_evidence"]


@compiled_inline
def crossings_per_bin(in_bin: FloatArray, crossing_bin: SlotArray,
                       bearings: npt.NDArray[np.float32], s: int, c: int, half: float,
                       step: float) -> None:
    """Count arc ``s``'s first ``c`` ATM crossings into ``in_bin`` (shape (K,), overwritten),
    and keep each crossing's bin in ``crossing_bin`` (for :func:`run_crossings`)."""
    bins = in_bin.shape[0]
    for k in range(bins):
        in_bin[k] = 0.0
    for m in range(c):
        kb = bin_of(float(bearings[s, m]), half, step, bins)
        crossing_bin[m] = kb
        in_bin[kb] += 1.0


@compiled_inline
def kept_run(free: FloatArray, located: FloatArray, in_bin: FloatArray, s: int,
              threshold: float) -> tuple[int, int, int, int, int]:
    """The surviving runs of arc ``s`` (bins with free evidence below ``T``), and the one kept:
    the most ATM crossings plus the largest localised support; ties, the longest, then the
    first.

    Returns
    -------
    start, end, first, last, runs
        Bins ``start .. end - 1`` of the kept run, ``first .. last - 1`` of the surviving hull
        (-1 when nothing survives), and the number of runs.
    """
    bins = free.shape[1]
    best_score = -1.0
    best_start = -1
    best_end = -1
    first = -1
    last = -1
    runs = 0
    k = 0
    while k < bins:
        if not free[s, k] < threshold:  # carved; a NaN counts as carved (else no progress)
            k += 1
            continue
        start = k
        score = 0.0
        top = 0.0
        while k < bins and free[s, k] < threshold:
            score += in_bin[k]
            top = max(top, located[s, k])
            k += 1
        score += top
        runs += 1
        if first < 0:
            first = start
        last = k
        better = score > best_score or (
            score == best_score and k - start > best_end - best_start)
        if better:
            best_score = score
            best_start = start
            best_end = k
    return best_start, best_end, first, last, runs


@compiled_inline
def run_evidence(support: FloatArray, free: FloatArray, s: int, start: int, end: int,
                  threshold: float) -> tuple[float, float]:
    """Largest support of a bin in run ``start .. end - 1`` of arc ``s``, and the run's mean
    free evidence in units of ``T``."""
    top = 0.0
    mean_free = 0.0
    for k in range(start, end):
        top = max(top, support[s, k])
        mean_free += free[s, k]
    return top, mean_free / ((end - start) * threshold)


#: numba's sort (``numba/misc/quicksort.py``) sorts this many values or fewer by insertion.
_INSERTION_SORT_MAX = 15


@compiled_inline
def _sort_in_place(values: FloatArray, n: int) -> None:
    """Sort ``values[:n]`` in place, in exactly the order ``np.sort`` would leave them: up to
    :data:`_INSERTION_SORT_MAX` values by numba's own insertion sort, with its comparison
    (NaN last), written out here; more by ``ndarray.sort``. ``np.sort`` allocated a copy (and
    numba's sort a stack) for every arc with crossings, a third of the estimates' time."""
    if n > _INSERTION_SORT_MAX:
        values[:n].sort()
        return
    for i in range(1, n):
        v = values[i]
        j = i
        while j > 0 and (v < values[j - 1] or (
                math.isnan(values[j - 1]) and not math.isnan(v))):
            values[j] = values[j - 1]
            j -= 1
        values[j] = v


@compiled_inline
def run_crossings(values: FloatArray, crossing_bin: SlotArray,
                   bearings: npt.NDArray[np.float32], s: int, c: int, start: int, end: int,
                   ) -> tuple[int, float]:
    """ATM's crossings of arc ``s`` inside bins ``start .. end - 1`` (copied into ``values``),
    and their median bearing relative to the axis (0 when there are none). ``crossing_bin``
    holds the bins of its first ``c`` crossings (:func:`crossings_per_bin`: one division a
    crossing, not two)."""
    kept = 0
    for m in range(c):
        kb = crossing_bin[m]
        if start <= kb < end:
            values[kept] = float(bearings[s, m])
            kept += 1
    if kept == 0:
        return 0, 0.0
    _sort_in_place(values, kept)
    return kept, 0.5 * (values[(kept - 1) // 2] + values[kept // 2])
