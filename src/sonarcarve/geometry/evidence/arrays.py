"""The arrays evidence carving's kernels work on, grouped by what they hold.

The model's state is a struct of arrays, one row per history row (``n`` rows, ``K`` bins per
arc). The caller (:class:`~sonarcarve.methods.evidence.EvidenceModel`) allocates them once and
hands them to :func:`~sonarcarve.geometry.evidence.evidence_add` and
:func:`~sonarcarve.geometry.evidence.evidence_add_many` as two bundles: the state,
:class:`EvidenceState` (the readings, :class:`ReadingRows`; each arc's geometry fixed when it
arrives, :class:`ArcShapes`; the evidence the weighing changes per bin,
:class:`BinEvidence`, and per arc, :class:`ArcEvidence`; ATM's crossing store,
:class:`CrossingArrays`), and the work arrays, :class:`AddScratch`. Inside the kernel the
work arrays are seen through :class:`GroupScratch` and :class:`NewArcScratch`, and the new
arc's running counts travel as :class:`NewArcTally`.

They are NamedTuples: numba compiles an attribute of one to the array it holds, and in the
kernels, compiled inline and without reference counting
(:func:`~sonarcarve.geometry._compiled.compiled_borrowing`), a bundle costs nothing at run time
(``docs/evidence-carving.md``, "Speed: the weighing kernel's layout"). At a call from Python
the model hands them over as plain tuples (:func:`plain`) and the kernels name them again
(:func:`named_state`, :func:`named_scratch`): numba types a plain tuple of arrays in C, a
NamedTuple field by field in Python, 7.0 µs a call for the weighing kernel's bundles against
1.7 µs as plain tuples (measured on numba 0.68), and :meth:`SonarMethod.add
<sonarcarve.methods.base.SonarMethod.add>` calls the kernels once per reading.

Every array is updated in place unless its description says otherwise; "filled for the new
arc" means the weighing writes the new reading's row and only reads the others.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.typing import BoolArray, FloatArray, Int8Array, SlotArray

__all__ = [
    "AddScratch",
    "ArcEvidence",
    "ArcShapes",
    "BinEvidence",
    "CrossingArrays",
    "EvidenceState",
    "GroupScratch",
    "NewArcScratch",
    "NewArcTally",
    "PlainBundle",
    "ReadingRows",
    "named_scratch",
    "named_state",
    "plain",
]

#: A bundle as :func:`plain` gives it: its arrays in field order, NamedTuples made tuples.
PlainBundle = tuple[Any, ...]


class ReadingRows(NamedTuple):
    """The history's readings, shape (n,) each (read only).

    Attributes
    ----------
    x, y, r : ndarray
        Origin and range of each row's reading, metres.
    theta, beam_width : ndarray
        Its axis and beam width, radians.
    sensor : ndarray of int64
        The index of the sensor that took it.
    """

    x: FloatArray
    y: FloatArray
    r: FloatArray
    theta: FloatArray
    beam_width: FloatArray
    sensor: npt.NDArray[np.int64]


class ArcShapes(NamedTuple):
    """Each arc's geometry, set when it arrives (filled for the new arc) and never changed.

    Attributes
    ----------
    cos_axis, sin_axis, cos_half : ndarray, shape (n,)
        The axis direction and ``cos(φ/2)``.
    circle : ndarray, shape (3, n)
        A circle containing the full arc (the cull's first, cheap test): rows centre x,
        centre y, radius (a row each, so that the cull reads them contiguously).
    bx, by : ndarray, shape (n, K)
        The bin centres ``p_k`` (eq. 2.1 at ``τ_k``).
    ex, ey : ndarray, shape (n, K)
        Their unit directions from the arc's origin.
    """

    cos_axis: FloatArray
    sin_axis: FloatArray
    cos_half: FloatArray
    circle: FloatArray
    bx: FloatArray
    by: FloatArray
    ex: FloatArray
    ey: FloatArray


class BinEvidence(NamedTuple):
    """What the weighing adds per bin, shape (n, K) each.

    Attributes
    ----------
    free : ndarray
        Evidence of empty space (eq. 3.2); the bin is carved once it reaches ``T``.
    support : ndarray
        Support: ``P_detect`` of each newer or older echo circle through the bin.
    located : ndarray
        Support times the sine of the angle at which the two echo circles meet there: how
        much the support says about where on the arc the echo came from (it picks the kept
        run of a split arc).
    """

    free: FloatArray
    support: FloatArray
    located: FloatArray


class ArcEvidence(NamedTuple):
    """What the weighing records per arc, shape (n,) each.

    Attributes
    ----------
    status : ndarray of int8
        ``EVIDENCE_ALIVE`` or ``EVIDENCE_CARVED``.
    touched : ndarray of bool
        The arc has received evidence (processed, Table I).
    viewpoints : ndarray
        Support from distinct viewpoints: the sum, over newer or older readings of another
        sensor or from an origin at least ``viewpoint_spacing`` away whose echo circle passes
        through the arc, of the largest ``P_detect`` of that support.
    looked : ndarray
        "Looked through" evidence: ``-log(1 - P)`` summed over distinct viewpoints whose free
        sector covers a bin still alive, ``P`` the largest detection over those bins
        *without* the incidence factor (a phantom in open space has no surface to be
        glancing at; how much this says about a real surface is left to the confidence fit).
    others : ndarray
        Support from *other sensors*: as ``viewpoints``, but only over readings of another
        sensor. A systematic phantom (crosstalk off the same wall, a multipath path) repeats
        for one sensor as the robot moves, so one sensor's repeated echoes confirm each other
        without being independent; another transducer at another mounting angle is closer to
        independent.
    occluded : ndarray
        Share of the arc's bins carved by occlusion when it arrived (the multipath flag;
        filled for the new arc).
    through : ndarray
        Per arc, set when it arrives: the largest support of an older live bin its free
        sector passed (nearer than ``r_j - 2ε``): how well heard the surface is that its echo
        would have had to cross; the graded form of the occlusion rule.
    behind : ndarray
        How far the arc's echo lies behind a surface the history holds inside its beam,
        judged only when the arc leaves the history
        (:func:`~sonarcarve.geometry.evidence.evidence_add_many`,
        :mod:`~sonarcarve.geometry.evidence.behind`): set to 0 when the arc arrives, so an
        arc in the history always has 0 (its confidence, and so the live map, do not depend
        on the feature).
    live_circle : ndarray, shape (4, n)
        A circle containing the centres of the arc's live bins (free evidence below ``T``):
        rows centre x, centre y, radius (infinite when none is live), and the live bins
        counted when it was drawn. Drawn when the arc arrives and redrawn once the weighing
        has carved some of its bins
        (:func:`~sonarcarve.geometry.evidence.beam.draw_live_circle`); bins are only ever
        carved, so a circle drawn earlier still contains them. The cull weighs only arcs
        whose live circle is within reach.
    """

    status: Int8Array
    touched: BoolArray
    viewpoints: FloatArray
    looked: FloatArray
    others: FloatArray
    occluded: FloatArray
    through: FloatArray
    behind: FloatArray
    live_circle: FloatArray


class CrossingArrays(NamedTuple):
    """ATM's crossing store, as in ``methods/atm.py``.

    Attributes
    ----------
    bearings : ndarray of float32, shape (n, C)
        The crossings of each row, bearings relative to its axis: a column per crossing the
        busiest arc has kept so far.
    counts : ndarray of int32, shape (n,)
        The crossings of each row, spilled ones included.
    spill : ndarray, shape (m, 2)
        Where crossings go that do not fit their row: ``(row, bearing)`` in the order found;
        ``m`` at least ``4 (older + 1)`` (an arc meets each older arc at most twice, and each
        crossing goes to two rows). The caller widens the store and moves them there.
    """

    bearings: npt.NDArray[np.float32]
    counts: npt.NDArray[np.int32]
    spill: FloatArray


class EvidenceState(NamedTuple):
    """The model's arrays, one row per history row: what a reading is weighed against."""

    readings: ReadingRows
    shapes: ArcShapes
    evidence: BinEvidence
    arcs: ArcEvidence
    crossings: CrossingArrays


class AddScratch(NamedTuple):
    """The work arrays of :func:`~sonarcarve.geometry.evidence.evidence_add` and
    :func:`~sonarcarve.geometry.evidence.evidence_add_many`, allocated once by the caller
    (the kernels, compiled without reference counting, allocate nothing) and overwritten
    unless said otherwise. ``G >= 1`` is the number of older arcs whose bins a group gathers.

    Attributes
    ----------
    passed : ndarray, shape (m, 6)
        For the transmission pass: one row per older live bin in the new beam's free sector
        (``m`` at least the older arcs' bins).
    trans : ndarray, shape (2 K + 3,)
        The new arc's support per bin from other sensors' older echoes (overwritten), then
        the sines of its bin edges, the beam width they are for (NaN before the first
        reading) and the scale of the guess of
        :func:`~sonarcarve.geometry.evidence.bins.bin_of_sine` (kept between readings of the
        same beam width).
    entries : ndarray, shape (11, G K)
        The bin passes' entries, one per bin to weigh of a group of up to ``G`` arcs: its
        offset from the new reading and the bin centre's direction (rows 0-4), and what
        :func:`~sonarcarve.geometry.evidence.model.detect_probability` computes of it
        (rows 5-10; :class:`GroupScratch`).
    in_beam : ndarray of bool, shape (K,)
        The older arc's bins to weigh.
    bin_index : ndarray of int64, shape (4, G K)
        Per entry its bin and the guess of
        :func:`~sonarcarve.geometry.evidence.bins.bin_of_sine`; per arc of the group its
        entries and its live bins outside the new beam.
    near, near_flags : ndarray of int64 and bool, shape (n,)
        The rows that pass the cull (then the group's rows with bins to weigh), and the
        cull's verdict per row.
    depth : ndarray, shape (n,)
        For the depth behind the newer arcs of an arc leaving the history
        (:func:`~sonarcarve.geometry.evidence.behind.depth_behind_newer`).
    """

    passed: FloatArray
    trans: FloatArray
    entries: FloatArray
    in_beam: BoolArray
    bin_index: SlotArray
    near: SlotArray
    near_flags: BoolArray
    depth: FloatArray


class GroupScratch(NamedTuple):
    """Work arrays of the bin passes over one group of older arcs (overwritten per group):
    :class:`AddScratch`'s ``entries``, ``bin_index``, ``in_beam``, ``near`` and
    ``near_flags`` by the names the passes use.

    Attributes
    ----------
    entries : ndarray, shape (11, G K)
        One column per bin to weigh: its offset from the new reading and the bin centre's
        direction (rows 0-4), then what ``P_detect`` computes of it (rows 5-10: distance,
        sine of the angle to the new axis, ``P_beam``, ``cos γ``, ``P_detect``, localised
        support).
    entry_bin, entry_guess : ndarray of int64, shape (G K,)
        Per entry its bin of its older arc, and the guess of the new arc's bin behind it.
    arc_marked, arc_alive : ndarray of int64, shape (G K,)
        Per arc of the group: its entries, and its live bins outside the new beam.
    in_beam : ndarray of bool, shape (K,)
        The bins to weigh of the arc in hand.
    near, near_flags : ndarray of int64 and bool, shape (n,)
        The rows that pass the cull (then the groups' rows), and the cull's verdict per row.
    """

    entries: FloatArray
    entry_bin: SlotArray
    entry_guess: SlotArray
    arc_marked: SlotArray
    arc_alive: SlotArray
    in_beam: BoolArray
    near: SlotArray
    near_flags: BoolArray


class NewArcScratch(NamedTuple):
    """The new arc's side of the weighing (views of :class:`AddScratch`'s ``trans`` and
    ``passed``).

    Attributes
    ----------
    other_support : ndarray, shape (K,)
        Its support per bin from other sensors' older echoes (what the transmission reads).
    edges : ndarray, shape (K + 1,)
        The sines of its bin edges relative to the axis.
    edge_scale : float
        The scale of the guess of :func:`~sonarcarve.geometry.evidence.bins.bin_of_sine`.
    passed : ndarray, shape (m, 6)
        The older live bins its sound passed, kept for the transmission pass.
    """

    other_support: FloatArray
    edges: FloatArray
    edge_scale: float
    passed: FloatArray


class NewArcTally(NamedTuple):
    """What the new arc has gathered from the older arcs weighed so far."""

    n_passed: int  # rows of NewArcScratch.passed used
    occluding: int  # its bins carved by occlusion
    top_through: float  # the largest support of an older live bin its free sector passed


def plain(bundle: PlainBundle) -> PlainBundle:
    """``bundle`` with every NamedTuple in it, itself included, a plain tuple of the same
    arrays in field order: the form numba types fastest at a call (module docstring)."""
    return tuple(plain(part) if isinstance(part, tuple) else part for part in bundle)


@compiled_inline
def named_state(state: EvidenceState | PlainBundle) -> EvidenceState:
    """:class:`EvidenceState` of ``state``'s arrays, named or :func:`plain`."""
    readings, shapes, evidence, arcs, crossings = state
    return EvidenceState(readings=ReadingRows(*readings), shapes=ArcShapes(*shapes),
                         evidence=BinEvidence(*evidence), arcs=ArcEvidence(*arcs),
                         crossings=CrossingArrays(*crossings))


@compiled_inline
def named_scratch(scratch: AddScratch | PlainBundle) -> AddScratch:
    """:class:`AddScratch` of ``scratch``'s arrays, named or :func:`plain`."""
    return AddScratch(*scratch)
