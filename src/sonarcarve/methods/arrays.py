"""The arrays the paper methods' kernels work on, grouped by what they hold.

Carving (:mod:`~sonarcarve.methods.carving`), ATM (:mod:`~sonarcarve.methods.atm`) and both
together (:mod:`~sonarcarve.methods.combined`) keep one row per history slot: the history's
readings, :class:`HistoryRows`; carving's carved intervals, :class:`CarvedArcs`, with its two
rules, :class:`CarvingRules`; ATM's beam cosines and crossing store, :class:`AtmArcs`. The
kernels' work arrays are :class:`CarveScratch` (carving's) and :class:`PairScratch` (ATM's).

They are NamedTuples: numba compiles an attribute of one to the array it holds, and in the
kernels, compiled without reference counting
(:func:`~sonarcarve.geometry._compiled.compiled_borrowing`) and with their steps inlined, a
bundle costs nothing at run time. At a call from Python it does:
:meth:`SonarMethod.add <sonarcarve.methods.base.SonarMethod.add>` calls a kernel once per
reading, and a single reading costs the paper methods 5-7 µs (history 250), of which numba's
dispatcher takes a good part unboxing the arguments. A NamedTuple it types field by field in
Python (about 5 µs a call, ``docs/evidence-carving.md``, "Speed: the bundles at the call"); a
plain tuple of arrays in C, but at about twice the cost per array of separate arguments
(0.11 against 0.05 µs: the bundles as plain tuples made ``add()`` 0.3-0.6 µs slower, 5-8 %,
and so did ``*arrays`` parameters, which numba's dispatcher packs into one tuple). So the
kernels called from Python take the bundles' fields as separate parameters, in field order
(a comment names each bundle), the models pass them so (:func:`in_a_row`), and the kernels
name the bundles on their first lines; every step below them takes bundles.

Every array is updated in place unless its description says otherwise.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.typing import BoolArray, FloatArray, Int8Array, SlotArray

__all__ = [
    "AtmArcs",
    "AtmMedians",
    "CarveScratch",
    "CarvedArcs",
    "CarvingRules",
    "HistoryRows",
    "PairScratch",
    "PlainBundle",
    "PointWork",
    "history_rows",
    "in_a_row",
    "live_slots",
]

if TYPE_CHECKING:
    from sonarcarve.history import SonarHistory

#: A bundle as a kernel takes it from Python: its arrays in field order, a plain tuple.
PlainBundle = tuple[Any, ...]


class HistoryRows(NamedTuple):
    """The history's arcs (:class:`~sonarcarve.history.SonarHistory`), shape (storage,) each,
    read only.

    Attributes
    ----------
    x, y, r : ndarray
        Origin and range of each row's reading, metres.
    theta, beam_width : ndarray
        Its axis θ and beam width φ, radians.
    theta1, theta2 : ndarray
        Its full beam's edges ``θ ∓ φ/2``, radians (eq. 2.1).
    """

    x: FloatArray
    y: FloatArray
    r: FloatArray
    theta: FloatArray
    beam_width: FloatArray
    theta1: FloatArray
    theta2: FloatArray


class CarvedArcs(NamedTuple):
    """Carving's state per history row (:class:`~sonarcarve.methods.carving.CarvingModel`).

    Attributes
    ----------
    lo, hi : ndarray, shape (storage,)
        Carved interval ``[θ1', θ2']`` (eq. 3.5), radians, unwrapped.
    bounds : ndarray, shape (storage, 3)
        A circle ``(cx, cy, radius)`` containing each carved arc: a cheap first test.
    tips : ndarray, shape (storage, 4)
        ``cos lo, sin lo, cos hi, sin hi``; ``tips[:, 0]`` (``[:, 2]``) NaN when ``lo``
        (``hi``) has moved since a test needed them.
    status : ndarray of int8, shape (storage,)
        :class:`~sonarcarve.geometry.ArcFate`: ``ALIVE``, ``FULLY_CARVED`` or ``SPLIT``.
    carved : ndarray of bool, shape (storage,)
        The row has been carved at least once (shrunk or removed).
    """

    lo: FloatArray
    hi: FloatArray
    bounds: FloatArray
    tips: FloatArray
    status: Int8Array
    carved: BoolArray


class CarvingRules(NamedTuple):
    """How a reading's freespace carves (eq. 3.2).

    Attributes
    ----------
    tolerance : float
        ε ≥ 0, metres: the freespace of a reading of range r ends at ``r - ε``.
    max_incidence : float
        Critical angle β, radians: points seen at a larger incidence are not carved.
    """

    tolerance: float
    max_incidence: float


class CarveScratch(NamedTuple):
    """Carving's work arrays: the kernels count no references
    (:func:`~sonarcarve.geometry._compiled.compiled_borrowing`), so they cannot allocate them.

    Attributes
    ----------
    candidates : ndarray of int64, shape (storage,)
        The slots an index query returned.
    bearings : ndarray, shape (3, SCRATCH)
        ``cuts, starts, ends`` of the closed form
        (:func:`~sonarcarve.geometry.circular.scratch_arrays`).
    flags : ndarray of bool, shape (SCRATCH,)
        Its flags.
    """

    candidates: SlotArray
    bearings: FloatArray
    flags: BoolArray


class AtmArcs(NamedTuple):
    """ATM's state per history row (:class:`~sonarcarve.methods.atm.AtmModel`).

    Attributes
    ----------
    cos_axis, sin_axis, cos_half : ndarray, shape (storage,)
        ``cos θ``, ``sin θ`` and ``cos(φ/2)`` of each arc: its beam tests need no trig.
    bearings : ndarray of float32, shape (storage, columns)
        The crossing store: each row's kept crossings, bearings relative to its axis θ
        (replaced when it grows).
    counts : ndarray of int32, shape (storage,)
        Crossings stored per row.
    stale : ndarray of bool, shape (storage,)
        The row's crossings changed since its median was last computed.
    """

    cos_axis: FloatArray
    sin_axis: FloatArray
    cos_half: FloatArray
    bearings: npt.NDArray[np.float32]
    counts: npt.NDArray[np.int32]
    stale: BoolArray


class AtmMedians(NamedTuple):
    """ATM's points as :meth:`~sonarcarve.methods.atm.AtmModel.medians` keeps them.

    Attributes
    ----------
    bearings, counts, stale : ndarray
        :class:`AtmArcs`' crossing store, its counts and stale marks.
    median, span : ndarray, shape (storage,)
        Median and span (max − min) of each row's bearings, radians, valid where not stale.
    values : ndarray, shape (columns,)
        Work array as wide as the store, for the sort.
    """

    bearings: npt.NDArray[np.float32]
    counts: npt.NDArray[np.int32]
    stale: BoolArray
    median: FloatArray
    span: FloatArray
    values: FloatArray


class PointWork(NamedTuple):
    """The work arrays of :class:`~sonarcarve.methods.combined.CombinedMethod`'s points.

    Attributes
    ----------
    rows : ndarray, shape (8, n)
        Width, quarter, bearing, bound, cos, sin, dy, dx of each point (``_WIDTH`` ..).
    flags : ndarray of bool, shape (2, n)
        ``alive`` and ``processed``.
    codes : ndarray of int8, shape (2, n)
        The source and carving's fate.
    """

    rows: FloatArray
    flags: BoolArray
    codes: Int8Array


class PairScratch(NamedTuple):
    """ATM's work arrays.

    Attributes
    ----------
    candidates : ndarray of int64, shape (storage,)
        The older arcs to intersect with the new one.
    tally : ndarray of int32, shape (storage, 2)
        Per candidate, the crossings found and stored with it, to take them back
        (:func:`~sonarcarve.methods.atm.add_atm_arc`).
    """

    candidates: SlotArray
    tally: npt.NDArray[np.int32]


def history_rows(history: SonarHistory) -> PlainBundle:
    """``history``'s :class:`HistoryRows`, plain (its arrays in field order)."""
    return (history.x, history.y, history.r, history.theta, history.beam_width,
            history.theta1, history.theta2)


def in_a_row(*bundles: PlainBundle) -> PlainBundle:
    """The arrays (and numbers) of ``bundles``, one after the other: how the kernels take
    them from Python (module docstring)."""
    return tuple(item for bundle in bundles for item in bundle)


@compiled_inline
def live_slots(start: int, end: int, storage: int, out: SlotArray) -> int:
    """Slots of the arcs with sequence numbers ``max(0, start) .. end - 1``, written to
    ``out``; their count. What the kernels fall back on for a huge box or sector: every live
    arc."""
    found = 0
    for sequence in range(max(0, start), end):
        out[found] = sequence % storage
        found += 1
    return found
