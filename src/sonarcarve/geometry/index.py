"""A spatial index over the live arcs of a history: which arcs can a reading touch?

Carving and ATM are ``O(mn)`` when every new reading is checked against every arc of the history
(paper, section 5-C). Most of those checks are wasted: a reading's freespace sector (eq. 3.2), or
its arc for ATM (eq. 2.1), only reaches the arcs near it. This index finds those arcs without any
trigonometry, so the exact kernels run on a few candidates instead of the whole history.

The index is a uniform grid of square cells of side ``cell_size`` over the plane, hashed into a
fixed number of buckets (the plane is unbounded, the table is not). Each arc is entered, once,
in every cell that its *full beam's* bounding box (:func:`arc_box`, padded) overlaps; an arc
whose box spans more than :data:`MAX_CELLS` cells (a huge range) goes to one *overflow* list
that every query visits. Buckets are intrusive doubly linked lists over per-arc entries, so that
inserting and removing an arc costs one step per cell (at most :data:`MAX_CELLS`), independent
of the history's length, and the index never allocates after it is made.

Why the result is exact. The full beam contains every carved interval of the arc (carving only
shrinks, section 3), so the box contains the arc at every moment of its life. A query visits
every cell that meets the query region (a sector, or a box), hence every arc that has a point in
it; an arc it misses is farther than the padding (:func:`box_pad`, about 1e-7 of the
coordinates' size) from the region, far beyond the rounding of the closed forms, which then
carve nothing of it / keep no crossing with it, exactly as the all-pairs kernels would. Queries
return each arc once (a per-arc stamp), in no particular order; carving treats arcs
independently, and ATM's medians do not depend on the order of an arc's crossings.

The all-pairs kernels stay (:func:`~sonarcarve.geometry.carve_arcs`), as the reference for the
tests and for ``benchmarks/speed.py``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled_borrowing, compiled_inline
from sonarcarve.geometry.bounds import circle_clear_of_sector
from sonarcarve.geometry.sector import Sector
from sonarcarve.typing import FloatArray, IntArray

__all__ = [
    "DEFAULT_CELL_SIZE",
    "MAX_CELLS",
    "MAX_QUERY_CELLS",
    "ArcIndex",
    "IndexArrays",
    "arc_box",
    "arc_box_of_ends",
    "box_pad",
    "index_arrays",
    "index_insert",
    "index_remove",
    "make_index",
    "query_box",
    "query_sector",
    "query_sector_circles",
]

#: Side of a grid cell, metres: about the chord of a 3 m sonar arc of 22.5°, so that most arcs
#: enter a handful of cells and a reading's sector spans tens.
DEFAULT_CELL_SIZE = 1.0

#: Most cells an arc is entered in; an arc whose box spans more goes to the overflow list.
MAX_CELLS = 16

#: Most cells a query visits; a larger region (a huge range) scans the live arcs instead.
MAX_QUERY_CELLS = 1024

_I32 = npt.NDArray[np.int32]


class ArcIndex(NamedTuple):
    """The index's arrays (all fixed-size; see the module docstring).

    Attributes
    ----------
    head : ndarray of int32, shape (buckets + 1,)
        First entry of each bucket's list, -1 if empty; the last is the overflow list.
    next, prev : ndarray of int32, shape (storage * MAX_CELLS,)
        Links of entry ``slot * MAX_CELLS + k`` (the arc's ``k``-th cell) in its bucket's list;
        ``prev`` is -2 - bucket for the first entry of a list.
    entries : ndarray of int32, shape (storage,)
        Entries in use by each slot's arc: 0 if the arc is not indexed.
    stamp : ndarray of int64, shape (storage,)
        Last query that returned each slot (so a query returns an arc once).
    bucket_stamp : ndarray of int64, shape (buckets + 1,)
        Last query that visited each bucket.
    tick : ndarray of int64, shape (1,)
        Queries made so far.
    cell_size : ndarray of float64, shape (1,)
        Side of a cell, metres.
    """

    head: _I32
    next: _I32
    prev: _I32
    entries: _I32
    stamp: IntArray
    bucket_stamp: IntArray
    tick: IntArray
    cell_size: npt.NDArray[np.float64]


#: An :class:`ArcIndex` as a plain tuple, ``tuple(index)``, for kernels called from Python:
#: numba's dispatcher types a tuple of arrays in about 0.1 µs an array, a NamedTuple in several
#: µs; the kernel rebuilds the index with ``ArcIndex(*arrays)``.
IndexArrays = tuple[_I32, _I32, _I32, _I32, IntArray, IntArray, IntArray, npt.NDArray[np.float64]]


def index_arrays(index: ArcIndex) -> IndexArrays:
    """``index`` as a plain tuple (:data:`IndexArrays`), to pass to a kernel."""
    return (index.head, index.next, index.prev, index.entries, index.stamp, index.bucket_stamp,
            index.tick, index.cell_size)


def make_index(storage: int, cell_size: float = DEFAULT_CELL_SIZE) -> ArcIndex:
    """An empty index for a history of ``storage`` rows (``SonarHistory.storage_size``).

    The table has a power of two of buckets, at least twice the live arcs' typical cell count.
    """
    buckets = 1 << max(6, math.ceil(math.log2(max(storage, 1))) + 1)
    return ArcIndex(
        head=np.full(buckets + 1, -1, dtype=np.int32),
        next=np.full(storage * MAX_CELLS, -1, dtype=np.int32),
        prev=np.full(storage * MAX_CELLS, -1, dtype=np.int32),
        entries=np.zeros(storage, dtype=np.int32),
        stamp=np.full(storage, -1, dtype=np.int64),
        bucket_stamp=np.full(buckets + 1, -1, dtype=np.int64),
        tick=np.zeros(1, dtype=np.int64),
        cell_size=np.full(1, float(cell_size)),
    )


@compiled_inline
def box_pad(ox: float, oy: float, r: float) -> float:
    """Padding of boxes and regions, metres: far above the rounding of the closed forms."""
    return 1e-7 * (1.0 + abs(ox) + abs(oy) + r)


@compiled_inline
def arc_box(ox: float, oy: float, r: float, lo: float,
            hi: float) -> tuple[float, float, float, float]:
    """Box ``(xmin, xmax, ymin, ymax)`` of the arc ``o + r e(τ)``, ``τ ∈ [lo, hi]``, padded.

    The extremes are at the ends and where ``τ`` crosses a multiple of π/2: at most four
    crossings matter (four consecutive multiples already reach every side), so the loop runs at
    most four times whatever the angles; an unbounded ``while`` never ended for ``lo`` = 1e20,
    where ``ceil(lo / (π/2))`` overflows int64 (and ``k + 1 == k`` in float64 beyond 2**53).
    """
    return arc_box_of_ends(ox, oy, r, lo, hi, math.cos(lo), math.sin(lo), math.cos(hi),
                           math.sin(hi))


@compiled_inline
def arc_box_of_ends(ox: float, oy: float, r: float, lo: float, hi: float, c1: float, s1: float,
                    c2: float, s2: float) -> tuple[float, float, float, float]:
    """:func:`arc_box` given ``(c1, s1) = e(lo)`` and ``(c2, s2) = e(hi)``, which a caller may
    already have (a reading's sector has those of its full beam): the same box, bit for bit,
    without computing them again."""
    xmin = min(c1, c2)
    xmax = max(c1, c2)
    ymin = min(s1, s2)
    ymax = max(s1, s2)
    quarter = 0.5 * math.pi
    k = math.ceil(lo / quarter)
    for _ in range(4):
        if k * quarter > hi:
            break
        m = k % 4
        if m == 0:
            xmax = 1.0
        elif m == 1:
            ymax = 1.0
        elif m == 2:
            xmin = -1.0
        else:
            ymin = -1.0
        k += 1
    pad = box_pad(ox, oy, r)
    return (ox + r * xmin - pad, ox + r * xmax + pad, oy + r * ymin - pad, oy + r * ymax + pad)


@compiled_inline
def _bucket(ix: int, iy: int, mask: int) -> int:
    return ((ix * 73856093) ^ (iy * 19349663)) & mask


@compiled_inline
def _link(index: ArcIndex, entry: int, bucket: int) -> None:
    first = index.head[bucket]
    index.next[entry] = first
    index.prev[entry] = -2 - bucket
    if first >= 0:
        index.prev[first] = entry
    index.head[bucket] = entry


@compiled_borrowing
def index_insert(index: ArcIndex, slot: int, xmin: float, xmax: float, ymin: float,
                 ymax: float) -> None:
    """Enter the arc of ``slot`` in the cells its box overlaps (or the overflow list)."""
    size = index.cell_size[0]
    mask = index.head.shape[0] - 2
    ix0 = math.floor(xmin / size)
    ix1 = math.floor(xmax / size)
    iy0 = math.floor(ymin / size)
    iy1 = math.floor(ymax / size)
    base = slot * MAX_CELLS
    if (ix1 - ix0 + 1) * (iy1 - iy0 + 1) > MAX_CELLS:
        _link(index, base, mask + 1)
        index.entries[slot] = 1
        return
    k = 0
    for ix in range(int(ix0), int(ix1) + 1):
        for iy in range(int(iy0), int(iy1) + 1):
            _link(index, base + k, _bucket(ix, iy, mask))
            k += 1
    index.entries[slot] = k


@compiled_borrowing
def index_remove(index: ArcIndex, slot: int) -> None:
    """Take the arc of ``slot`` out of the index (nothing if it is not in it)."""
    base = slot * MAX_CELLS
    for entry in range(base, base + index.entries[slot]):
        after = index.next[entry]
        before = index.prev[entry]
        if before >= 0:
            index.next[before] = after
        else:
            index.head[-2 - before] = after
        if after >= 0:
            index.prev[after] = before
    index.entries[slot] = 0


@compiled_inline
def _visit(index: ArcIndex, bucket: int, tick: int, out: IntArray, count: int) -> int:
    """Append the arcs of ``bucket`` not yet returned by query ``tick`` to ``out``."""
    if index.bucket_stamp[bucket] == tick:
        return count
    index.bucket_stamp[bucket] = tick
    entry = index.head[bucket]
    while entry >= 0:
        slot = entry // MAX_CELLS
        if index.stamp[slot] != tick:
            index.stamp[slot] = tick
            out[count] = slot
            count += 1
        entry = index.next[entry]
    return count


@compiled_borrowing
def query_box(index: ArcIndex, xmin: float, xmax: float, ymin: float, ymax: float,
              out: IntArray) -> int:
    """Slots of the indexed arcs whose cells meet the box, written to ``out``; their count.

    Returns -1 (``out`` untouched) when the box spans more than :data:`MAX_QUERY_CELLS` cells:
    the caller scans the live arcs instead.
    """
    size = index.cell_size[0]
    mask = index.head.shape[0] - 2
    ix0 = math.floor(xmin / size)
    ix1 = math.floor(xmax / size)
    iy0 = math.floor(ymin / size)
    iy1 = math.floor(ymax / size)
    if (ix1 - ix0 + 1) * (iy1 - iy0 + 1) > MAX_QUERY_CELLS:
        return -1
    index.tick[0] += 1
    tick = index.tick[0]
    count = 0
    for ix in range(int(ix0), int(ix1) + 1):
        for iy in range(int(iy0), int(iy1) + 1):
            count = _visit(index, _bucket(ix, iy, mask), tick, out, count)
    return _visit(index, mask + 1, tick, out, count)


@compiled_inline
def _sector_cells(index: ArcIndex,
                  sector: Sector) -> tuple[int, int, int, int, float, float, bool]:
    """The cells a query for ``sector`` scans, ``ix0, ix1, iy0, iy1``, the padded half-diagonal
    ``rho`` of a cell and ``reach2`` (see :func:`query_sector`); False when they are more than
    :data:`MAX_QUERY_CELLS`."""
    fx = sector.fx
    fy = sector.fy
    radius = sector.radius
    pad = box_pad(fx, fy, radius)
    # The sector's box: the origin, both edge ends and the axis directions inside the wedge
    # (the edges' directions are the sector's own u1, u2: cos and sin of a1, a2).
    xmin, xmax, ymin, ymax = arc_box_of_ends(fx, fy, radius, sector.a1, sector.a2, sector.u1x,
                                             sector.u1y, sector.u2x, sector.u2y)
    xmin = min(xmin, fx - pad)
    xmax = max(xmax, fx + pad)
    ymin = min(ymin, fy - pad)
    ymax = max(ymax, fy + pad)
    size = index.cell_size[0]
    ix0 = math.floor(xmin / size)
    ix1 = math.floor(xmax / size)
    iy0 = math.floor(ymin / size)
    iy1 = math.floor(ymax / size)
    rho = 0.5 * math.sqrt(2.0) * size * (1.0 + 1e-9) + pad
    reach2 = (radius + rho) * (radius + rho)
    return ix0, ix1, iy0, iy1, rho, reach2, (ix1 - ix0 + 1) * (iy1 - iy0 + 1) <= MAX_QUERY_CELLS


@compiled_inline
def _cell_meets(ix: int, iy: int, size: float, rho: float, reach2: float,
                sector: Sector) -> bool:
    """Whether the circumscribed circle of cell ``(ix, iy)``, padded to ``rho``, is neither
    clear of the sector's disk nor of one of its half-planes."""
    dx = (ix + 0.5) * size - sector.fx
    dy = (iy + 0.5) * size - sector.fy
    if sector.u1x * dy - sector.u1y * dx < -rho:
        return False
    if dx * sector.u2y - dy * sector.u2x < -rho:
        return False
    return dx * dx + dy * dy < reach2


@compiled_borrowing
def query_sector(index: ArcIndex, sector: Sector, out: IntArray) -> int:
    """Slots of the indexed arcs whose cells meet ``sector`` (radius > 0), written to ``out``;
    their count, or -1 for a sector spanning more than :data:`MAX_QUERY_CELLS` cells.

    A cell is visited when its circumscribed circle, padded, is neither clear of the disk nor
    of one of the wedge's half-planes (the tests of
    :func:`~sonarcarve.geometry.bounds.circle_against_sector`).
    """
    ix0, ix1, iy0, iy1, rho, reach2, fits = _sector_cells(index, sector)
    if not fits:
        return -1
    size = index.cell_size[0]
    mask = index.head.shape[0] - 2
    index.tick[0] += 1
    tick = index.tick[0]
    count = 0
    for ix in range(ix0, ix1 + 1):
        for iy in range(iy0, iy1 + 1):
            if _cell_meets(ix, iy, size, rho, reach2, sector):
                count = _visit(index, _bucket(ix, iy, mask), tick, out, count)
    return _visit(index, mask + 1, tick, out, count)


@compiled_inline
def _visit_circles(index: ArcIndex, bucket: int, tick: int, sector: Sector, bounds: FloatArray,
                   out: IntArray, count: int) -> int:
    """:func:`_visit`, keeping only the arcs whose circle ``bounds[slot]`` the sector does not
    leave clear (:func:`~sonarcarve.geometry.bounds.circle_clear_of_sector`)."""
    if index.bucket_stamp[bucket] == tick:
        return count
    index.bucket_stamp[bucket] = tick
    entry = index.head[bucket]
    while entry >= 0:
        slot = entry // MAX_CELLS
        if index.stamp[slot] != tick:
            index.stamp[slot] = tick
            if not circle_clear_of_sector(bounds[slot, 0], bounds[slot, 1], bounds[slot, 2],
                                          sector):
                out[count] = slot
                count += 1
        entry = index.next[entry]
    return count


@compiled_inline
def query_sector_circles(index: ArcIndex, sector: Sector, bounds: FloatArray,
                         out: IntArray) -> int:
    """:func:`query_sector` without the arcs whose circle ``bounds[slot]`` (``cx, cy,
    radius``, containing the arc) is clear of the sector: those the sector leaves unchanged,
    as :func:`~sonarcarve.geometry.bounds.circle_against_sector` would say next.

    Why: with a long history most returned arcs are such (236 a reading, 27 kept, at history
    10,000 on the benchmark stream); testing them while walking the buckets lets the processor
    do the tests while it waits for the next entry of a list, and skips a second pass. Inlined
    into the carving kernel, so that it borrows ``bounds`` as the kernel does.
    """
    ix0, ix1, iy0, iy1, rho, reach2, fits = _sector_cells(index, sector)
    if not fits:
        return -1
    size = index.cell_size[0]
    mask = index.head.shape[0] - 2
    index.tick[0] += 1
    tick = index.tick[0]
    count = 0
    for ix in range(ix0, ix1 + 1):
        for iy in range(iy0, iy1 + 1):
            if _cell_meets(ix, iy, size, rho, reach2, sector):
                count = _visit_circles(index, _bucket(ix, iy, mask), tick, sector, bounds, out,
                                       count)
    return _visit_circles(index, mask + 1, tick, sector, bounds, out, count)
