"""Circular intervals of bearings inside an arc: the bookkeeping of the carving kernels.

Each condition that makes up a freespace sector holds on :data:`NONE`, :data:`ALL` or
:data:`SOME` (one circular interval) of an arc's circle. The kernels collect the boundary
bearings that fall strictly inside the arc (:func:`add_cut`), sort them (:func:`sort_prefix`) and
classify the sub-intervals between them as runs (:func:`merge_runs`); see
:mod:`sonarcarve.geometry.intervals`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.typing import BoolArray, FloatArray

__all__ = [
    "ALL",
    "NONE",
    "SCRATCH",
    "SOME",
    "Scratch",
    "add_cut",
    "merge_runs",
    "new_scratch",
    "scratch_arrays",
    "sort_prefix",
    "unwrap_above",
]

# Modes of one condition on the circle.
NONE = 0  #: no point of the circle satisfies it
ALL = 1  #: every point does
SOME = 2  #: a circular interval does

#: Room in the scratch arrays: lo, hi and at most 2 + 2 + 2 + 4 boundaries inside (disk, two
#: half-planes, incidence), so at most 11 sub-intervals.
SCRATCH = 12

_TWO_PI = 2.0 * math.pi


class Scratch(NamedTuple):
    """Work arrays of one carving call, each with room for :data:`SCRATCH` values.

    ``cuts`` holds sorted boundary bearings; run ``i`` is ``[starts[i], ends[i]]`` and
    ``flags[i]`` says whether it is carved (inside the freespace).
    """

    cuts: FloatArray
    starts: FloatArray
    ends: FloatArray
    flags: BoolArray


@compiled
def new_scratch() -> Scratch:
    """Fresh (uninitialised) work arrays; allocate once per batch, not per arc."""
    bearings = np.empty((3, SCRATCH))  # one allocation for the three float arrays
    return Scratch(bearings[0], bearings[1], bearings[2], np.empty(SCRATCH, dtype=np.bool_))


def scratch_arrays() -> tuple[FloatArray, BoolArray]:
    """Work arrays for a kernel that cannot allocate (:func:`~sonarcarve.geometry._compiled.
    compiled_borrowing`): ``bearings`` of shape (3, :data:`SCRATCH`), whose rows are the
    ``cuts, starts, ends`` of a :class:`Scratch`, and its ``flags``. Made once per model."""
    return np.empty((3, SCRATCH)), np.empty(SCRATCH, dtype=np.bool_)


@compiled
def unwrap_above(angle: float, lo: float) -> float:
    """The representative of ``angle`` (mod 2π) in ``[lo, lo + 2π)``."""
    return angle - math.floor((angle - lo) / _TWO_PI) * _TWO_PI


@compiled
def add_cut(cuts: FloatArray, count: int, angle: float, lo: float, hi: float) -> int:
    """Append ``angle`` to ``cuts`` if its representative lies strictly inside ``(lo, hi)``."""
    t = unwrap_above(angle, lo)
    if lo < t < hi:
        cuts[count] = t
        return count + 1
    return count


@compiled_inline
def sort_prefix(values: FloatArray, count: int) -> None:
    """Insertion sort of ``values[:count]`` (at most 12 values: cheaper than a library sort)."""
    for i in range(1, count):
        v = values[i]
        j = i - 1
        while j >= 0 and values[j] > v:
            values[j + 1] = values[j]
            j -= 1
        values[j + 1] = v


@compiled_inline
def merge_runs(starts: FloatArray, ends: FloatArray, flags: BoolArray, count: int) -> int:
    """Merge neighbouring runs with equal flags in place; return the new count."""
    if count == 0:
        return 0
    out = 0
    for i in range(1, count):
        if flags[i] == flags[out]:
            ends[out] = ends[i]
        else:
            out += 1
            starts[out] = starts[i]
            ends[out] = ends[i]
            flags[out] = flags[i]
    return out + 1
