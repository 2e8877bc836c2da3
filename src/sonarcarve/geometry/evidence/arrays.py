"""The arrays evidence carving's kernels work on, grouped by what they hold.

The model's state is a struct of arrays, one row per history row (``n`` rows, ``K`` bins per
arc). :func:`~sonarcarve.geometry.evidence.evidence_add` takes them one by one (the order of
its callers) and bundles them here, so that each pass names what it reads: the readings
(:class:`ReadingRows`), each arc's geometry fixed when it arrives (:class:`ArcShapes`), the
evidence the weighing changes per bin (:class:`BinEvidence`) and per arc
(:class:`ArcEvidence`), ATM's crossing store (:class:`CrossingArrays`), all of it as one
:class:`EvidenceState`; and the weighing's own work arrays (:class:`GroupScratch`,
:class:`NewArcScratch`) and running counts (:class:`NewArcTally`).

They are NamedTuples: numba compiles an attribute of one to the array it holds, and in the
kernels, compiled inline and without reference counting
(:func:`~sonarcarve.geometry._compiled.compiled_borrowing`), a bundle costs nothing at run time
(``docs/evidence-carving.md``, "Speed: the weighing kernel's layout").
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.typing import BoolArray, FloatArray, Int8Array, SlotArray

__all__ = [
    "ArcEvidence",
    "ArcShapes",
    "BinEvidence",
    "CrossingArrays",
    "EvidenceState",
    "GroupScratch",
    "NewArcScratch",
    "NewArcTally",
    "ReadingRows",
]


class ReadingRows(NamedTuple):
    """The history's readings, shape (n,) each: origin ``(x, y)`` and range ``r`` (metres),
    axis ``theta`` and ``beam_width`` (radians), ``sensor`` index (int64)."""

    x: FloatArray
    y: FloatArray
    r: FloatArray
    theta: FloatArray
    beam_width: FloatArray
    sensor: npt.NDArray[np.int64]


class ArcShapes(NamedTuple):
    """Each arc's geometry, set when it arrives and never changed.

    Attributes
    ----------
    cos_axis, sin_axis, cos_half : ndarray, shape (n,)
        The axis direction and ``cos(φ/2)``.
    circle : ndarray, shape (3, n)
        A circle containing the full arc (the cull's first test): rows centre x, centre y,
        radius (a row each, so that the cull reads them contiguously).
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
    """What the weighing adds per bin, shape (n, K) each: free-space evidence (eq. 3.2; carved
    at ``T``), support, and localised support (support times the sine of the angle at which
    the two echo circles meet: it picks the kept run of a split arc)."""

    free: FloatArray
    support: FloatArray
    located: FloatArray


class ArcEvidence(NamedTuple):
    """What the weighing records per arc, shape (n,) each (as
    :func:`~sonarcarve.geometry.evidence.evidence_add` documents them).

    Attributes
    ----------
    status : ndarray of int8
        ``EVIDENCE_ALIVE`` or ``EVIDENCE_CARVED``.
    touched : ndarray of bool
        The arc has received evidence (processed, Table I).
    viewpoints, looked, others : ndarray
        Support from distinct viewpoints, "looked through" evidence, support from other
        sensors: sums over the readings weighed against the arc.
    occluded, through, behind : ndarray
        Set when the arc arrives (``behind`` when it leaves): its share of bins carved by
        occlusion, the largest support its free sector passed, its depth behind the newer
        arcs.
    live_circle : ndarray, shape (4, n)
        A circle containing the centres of the arc's live bins (free evidence below ``T``):
        rows centre x, centre y, radius (infinite when none is live), and the live bins
        counted when it was drawn. Bins are only ever carved, so a circle drawn earlier
        still contains them; the weighing redraws it once it has carved some
        (:func:`~sonarcarve.geometry.evidence.beam.draw_live_circle`).
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
    """ATM's crossing store (``methods/atm.py``): ``bearings`` (n, C) float32 relative to the
    axis, ``counts`` (n,) int32 crossings per row (spilled ones included), and ``spill``
    (m, 2), the ``(row, bearing)`` of crossings that did not fit their row."""

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


class GroupScratch(NamedTuple):
    """Work arrays of the bin passes over one group of older arcs (overwritten per group).

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
    """The new arc's side of the weighing (scratch of ``evidence_add``'s ``trans`` and
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
