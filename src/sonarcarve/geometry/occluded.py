"""Points behind a surface of the map, on the line from their own sensor (beyond the paper).

A multipath echo reads too long: the sound glanced off a surface it met at a steep angle (a
specular reflector sends it on, not back), reached another and came back the same way, so its
point lies *behind* the first surface, on the line from the sensor. The issue that asked for
evidence carving names the test: an echo whose own free sector contains well-established
surface is suspect. Evidence carving applies it while the arc is in the history
(:mod:`~sonarcarve.geometry.evidence.occlusion`, :mod:`~sonarcarve.geometry.evidence.behind`),
but on a ring with few sensors the surface in front is mostly heard *later*, once the robot
drives past it: on a Pioneer's 8 front sonars, 8 % of the kept multipath points had such a
surface in the map when they were committed, 91 % in the finished map (``docs/RESULTS.md``,
"Points behind a surface of the map"). So this test runs on a finished point map, as the
other map filters do (:func:`sonarcarve.filters.filter_map`).

Point ``i`` (at ``p_i``, heard from the sensor origin ``o_i``, ``d_i = |p_i - o_i|``,
``u_i = (p_i - o_i) / d_i``) is *occluded* when another point ``j`` of the map that may block
(``blocks``: :mod:`sonarcarve.filters` lets only points whose error bound is at most half the
depth block, so that one displaced by its whole bound still stands in front)

* lies on the segment from ``o_i``: ``0 < (p_j - o_i) · u_i < d_i - depth`` and
  ``|(p_j - o_i) × u_i| <= reach``, so more than ``depth`` in front of ``p_i``, and
* lies on a *surface* (:func:`surface_directions` over the points that may block): at least
  ``neighbours`` other such points within ``radius`` of it, spread along a line (the larger
  eigenvalue of their scatter at least :data:`LINE_RATIO` times the smaller), a line that
* crosses the segment at ``crossing`` or more (``|t_j × u_i| >= sin(crossing)``).

Why each part: one stray point (a crosstalk echo, a floor echo) is no surface; a surface the
line runs *along* (a wall beside a corner the sensor heard) is passed beside, not through, and a
point placed anywhere in its beam (a 22.5° beam's half-width is 11°) must not make it look
crossed, hence 20°; ``depth`` (0.5 m, the depth the carved grid's ``see_through`` clears behind
a surface, an obstacle's, not a room's) keeps a point on the same surface, or just behind a
thin one, from occluding itself. The defaults live in :mod:`sonarcarve.filters`.

Exact on its numbers: the kernels visit every pair the tests can accept (for the surfaces,
points are bucketed in square cells a hair wider than a third of ``radius`` and each looks at the
7 x 7 cells around its own; for the walk, in cells of 2 ``reach``, and the segment is walked a
cell at a time, each step looking at the 3 x 3 cells around it), and
``tests/geometry/test_occluded.py`` compares them with a brute-force reference over all pairs.
The work grows with how many surface points lie near each line: with the density of the map.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled
from sonarcarve.typing import FloatArray

__all__ = ["LINE_RATIO", "occluded_points", "surface_directions"]

#: A neighbourhood is a line when the larger eigenvalue of its scatter is at least this times
#: the smaller one: its spread along the line at least three times that across it. Not twice
#: (4.0, the first choice): on a dense map, spurious and misplaced points line up that well by
#: chance, and on ``benchmarks/synthetic.py``'s corridor loop at 200,000 readings evidence
#: carving lost 1.6 % of its true echoes behind them, 0.8 % now; on the held-out floors,
#: rings and physics of ``docs/RESULTS.md`` the two ratios keep and remove the same within
#: 0.6 points, while 16 (four times) lost a run of the nine settings measured there.
LINE_RATIO = 9.0


#: At most this many cells in a table of cell starts (32 MiB): a map wider than that at its
#: cell size finds its cells by binary search over the sorted keys instead, a little slower
#: on sparse maps and the same answer (coarser cells would keep the table small but make the
#: searches of a dense map quadratic in its cells' contents).
MAX_CELLS = 1 << 22


class _Buckets(NamedTuple):
    """Points sorted by square cell of side ``cell``: cell ``key = column * rows + row`` (from
    the corner ``x0, y0``) holds the points ``order[k]`` for the ``k`` where ``sorted_keys[k]
    == key``: ``starts[key]`` to ``starts[key + 1]`` when ``starts`` is not empty (a table
    over every cell, :data:`MAX_CELLS`)."""

    order: npt.NDArray[np.int64]
    sorted_keys: npt.NDArray[np.int64]
    starts: npt.NDArray[np.int64]
    x0: float
    y0: float
    rows: int
    cell: float


def _buckets(xy: FloatArray, cell: float, spare: int = 1) -> _Buckets:
    """Bucket ``xy`` in cells of side ``cell``. ``spare`` empty rows top each column, so a look
    up to ``spare`` rows above or below a point's cell never reaches another column's points
    (below, it wraps to the previous column's spare rows)."""
    x0 = float(xy[:, 0].min()) - cell
    y0 = float(xy[:, 1].min()) - cell
    column = np.floor((xy[:, 0] - x0) / cell).astype(np.int64)
    row = np.floor((xy[:, 1] - y0) / cell).astype(np.int64)
    rows = int(row.max()) + 1 + spare
    keys = column * rows + row
    order = np.argsort(keys, kind="stable")
    cells = (int(column.max()) + 1) * rows
    starts = (np.concatenate(([0], np.cumsum(np.bincount(keys, minlength=cells))))
              if cells <= MAX_CELLS else np.zeros(0, dtype=np.int64))
    return _Buckets(order, keys[order], starts, x0, y0, rows, cell)


@compiled
def _span(sorted_keys: npt.NDArray[np.int64], starts: npt.NDArray[np.int64], first: int,
          last: int) -> tuple[int, int]:
    """The positions in the sorted order of the points of cells ``first`` to ``last``
    (inclusive; keys outside the map hold none): from the table, or by binary search."""
    if starts.shape[0] == 0:
        return (int(np.searchsorted(sorted_keys, first, side="left")),
                int(np.searchsorted(sorted_keys, last, side="right")))
    cells = starts.shape[0] - 1
    return (starts[min(max(first, 0), cells)], starts[min(max(last + 1, 0), cells)])


#: Surface neighbourhoods are bucketed in cells of a third of the radius and looked up 7 x 7
#: cells at a time: 5.4 radius² of floor searched for a disc of 3.1, where cells of one radius
#: searched 9 (the work of a dense map's surfaces is nearly all in that search).
_SURFACE_SPLIT = 3


@compiled
def _gather(x: FloatArray, y: FloatArray, order: npt.NDArray[np.int64],
            sorted_keys: npt.NDArray[np.int64], starts: npt.NDArray[np.int64], key: int,
            rows: int, span: int, gx: FloatArray, gy: FloatArray) -> int:
    """Copy the points of the (2 ``span`` + 1)² cells around cell ``key`` into ``gx``, ``gy``
    (contiguous, so every point of the cell then sums over one short array); their count."""
    m = 0
    for dc in range(-span, span + 1):
        # One column's cells are consecutive keys.
        lo, hi = _span(sorted_keys, starts, key + dc * rows - span, key + dc * rows + span)
        for k in range(lo, hi):
            j = order[k]
            gx[m] = x[j]
            gy[m] = y[j]
            m += 1
    return m


@compiled
def _directions(x: FloatArray, y: FloatArray, order: npt.NDArray[np.int64],
                sorted_keys: npt.NDArray[np.int64], starts: npt.NDArray[np.int64], rows: int,
                radius: float, neighbours: int, line_ratio: float, out: FloatArray) -> None:
    """:func:`surface_directions` on bucketed points (cells at least a hair wider than
    ``radius`` / :data:`_SURFACE_SPLIT`), a cell's neighbourhood gathered once for its points."""
    radius2 = radius * radius
    gx = np.empty(x.shape[0])
    gy = np.empty(x.shape[0])
    first = 0
    while first < order.shape[0]:  # one cell's points at a time
        last = first
        while last < order.shape[0] and sorted_keys[last] == sorted_keys[first]:
            last += 1
        m = _gather(x, y, order, sorted_keys, starts, sorted_keys[first], rows, _SURFACE_SPLIT,
                    gx, gy)
        for k in range(first, last):
            i = order[k]
            n = 0
            sx = 0.0
            sy = 0.0
            sxx = 0.0
            syy = 0.0
            sxy = 0.0
            for g in range(m):
                dx = gx[g] - x[i]  # about point i: small numbers, no cancellation
                dy = gy[g] - y[i]
                if dx * dx + dy * dy <= radius2:
                    n += 1
                    sx += dx
                    sy += dy
                    sxx += dx * dx
                    syy += dy * dy
                    sxy += dx * dy
            _direction(n, sx, sy, sxx, syy, sxy, neighbours, line_ratio, out[i])
        first = last


@compiled
def _direction(n: int, sx: float, sy: float, sxx: float, syy: float, sxy: float,
               neighbours: int, line_ratio: float, out: FloatArray) -> None:
    """The principal axis of ``n`` points (``n`` counting the point itself) from their sums
    about it, into ``out``; NaN when too few or not along a line."""
    out[0] = math.nan
    out[1] = math.nan
    if n - 1 < neighbours:
        return
    a = sxx - sx * sx / n
    c = syy - sy * sy / n
    b = sxy - sx * sy / n
    half = 0.5 * (a - c)
    root = math.sqrt(half * half + b * b)
    larger = 0.5 * (a + c) + root
    smaller = 0.5 * (a + c) - root
    if larger <= 0.0 or larger < line_ratio * smaller:
        return
    angle = 0.5 * math.atan2(2.0 * b, a - c)  # the larger eigenvector's direction
    out[0] = math.cos(angle)
    out[1] = math.sin(angle)


def surface_directions(xy: npt.ArrayLike, radius: float, neighbours: int,
                       line_ratio: float = LINE_RATIO) -> FloatArray:
    """The direction of the surface each point lies on, where its neighbourhood is a line.

    Parameters
    ----------
    xy : array-like, shape (n, 2)
        Points, metres.
    radius : float
        The neighbourhood: points within this distance (inclusive), metres, > 0.
    neighbours : int
        At least this many other points in it, or the point is on no surface.
    line_ratio : float
        :data:`LINE_RATIO`.

    Returns
    -------
    ndarray, shape (n, 2)
        A unit vector along the neighbourhood's principal axis (its sign arbitrary), or NaN
        where there are too few neighbours or they do not lie along a line.

    Examples
    --------
    Five points along a wall, and one stray point:

    >>> wall = [[0.1 * k, 0.0] for k in range(5)]
    >>> direction = surface_directions(wall + [[5.0, 5.0]], 0.25, 2)
    >>> np.abs(direction[0]).tolist(), np.isnan(direction[:, 0]).tolist()
    ([1.0, 0.0], [False, False, False, False, False, True])
    """
    pts = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
    out = np.full((pts.shape[0], 2), np.nan)
    if pts.shape[0] == 0:
        return out
    # A hair wider than a third of the radius: two points exactly ``radius`` apart must never
    # land four cells apart by rounding, or the 7 x 7 look would miss the pair.
    cells = _buckets(pts, radius / _SURFACE_SPLIT * (1.0 + 1e-9), spare=_SURFACE_SPLIT)
    _directions(np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1]), cells.order,
                cells.sorted_keys, cells.starts, cells.rows, radius, neighbours, line_ratio, out)
    return out


@compiled
def _hidden(i: int, x: FloatArray, y: FloatArray, ox: float, oy: float, bx: FloatArray,
            by: FloatArray, tx: FloatArray, ty: FloatArray, order: npt.NDArray[np.int64],
            sorted_keys: npt.NDArray[np.int64], starts: npt.NDArray[np.int64], x0: float,
            y0: float, rows: int, cell: float, depth: float, reach: float,
            sin_crossing: float) -> bool:
    """Whether a surface point ``(bx, by)[j]`` (direction ``(tx, ty)[j]``) lies on the segment
    from ``(ox, oy)`` to point ``i`` more than ``depth`` in front of it, within ``reach`` of
    it, crossing it at the angle of sine ``sin_crossing`` or more (:func:`occluded_points`).
    Point ``i`` itself, or any point where it is, lies ``d`` in front, never less than ``d -
    depth``: no self test is needed."""
    vx = x[i] - ox
    vy = y[i] - oy
    d = math.sqrt(vx * vx + vy * vy)
    if d <= depth:
        return False
    ux = vx / d
    uy = vy / d
    # Walk the segment a cell at a time: a point within ``reach`` of it lies within half a
    # cell along and ``reach`` <= half a cell across of the nearest step, so each of its
    # coordinates within a cell of that step's: in the 3 x 3 cells around it. Cells the
    # previous step's 3 x 3 already looked at are skipped (most of them, steps a cell apart).
    last_column = -10
    last_row = -10
    for step in range(int((d - depth) / cell) + 2):
        along = min(step * cell, d - depth)
        column = math.floor((ox + along * ux - x0) / cell)
        row = math.floor((oy + along * uy - y0) / cell)
        for dc in (-1, 0, 1):
            for dr in (-1, 0, 1):
                if row + dr < 0 or row + dr >= rows or column + dc < 0:
                    continue  # outside the surface points' cells: none there
                if abs(column + dc - last_column) <= 1 and abs(row + dr - last_row) <= 1:
                    continue
                key = (column + dc) * rows + row + dr
                lo, hi = _span(sorted_keys, starts, key, key)
                for k in range(lo, hi):
                    j = order[k]
                    wx = bx[j] - ox
                    wy = by[j] - oy
                    in_front = wx * ux + wy * uy
                    if (0.0 < in_front < d - depth and abs(wx * uy - wy * ux) <= reach
                            and abs(tx[j] * uy - ty[j] * ux) >= sin_crossing):
                        return True
        last_column = column
        last_row = row
    return False


@compiled
def _occluded(x: FloatArray, y: FloatArray, ox: FloatArray, oy: FloatArray, bx: FloatArray,
              by: FloatArray, tx: FloatArray, ty: FloatArray, order: npt.NDArray[np.int64],
              sorted_keys: npt.NDArray[np.int64], starts: npt.NDArray[np.int64], x0: float,
              y0: float, rows: int, cell: float, depth: float, reach: float,
              sin_crossing: float, out: npt.NDArray[np.bool_]) -> None:
    """:func:`occluded_points` with the surface points bucketed (cells of side ``cell`` = 2
    ``reach``)."""
    for i in range(x.shape[0]):
        out[i] = _hidden(i, x, y, ox[i], oy[i], bx, by, tx, ty, order, sorted_keys, starts,
                         x0, y0, rows, cell, depth, reach, sin_crossing)


def occluded_points(xy: npt.ArrayLike, origin: npt.ArrayLike, *, depth: float, reach: float,
                    radius: float, neighbours: int, crossing: float,
                    blocks: npt.ArrayLike | None = None,
                    line_ratio: float = LINE_RATIO) -> npt.NDArray[np.bool_]:
    """True where a point lies more than ``depth`` behind a surface of the map, on the line
    from its sensor (module docstring).

    Parameters
    ----------
    xy : array-like, shape (n, 2)
        The map's points, metres, finite: each is tested.
    origin : array-like, shape (n, 2)
        The sensor origin each point was heard from, metres.
    depth : float
        How far behind the surface, metres, > 0.
    reach : float
        How near the line a surface point must lie, metres, > 0.
    radius, neighbours, line_ratio
        What makes a point part of a surface (:func:`surface_directions`).
    crossing : float
        The least angle between the surface and the line, radians, in (0, π/2].
    blocks : array-like of bool, shape (n,), optional
        The points that may hide others and make up surfaces (default: all of them).

    Returns
    -------
    ndarray of bool, shape (n,)

    Raises
    ------
    ValueError
        ``origin`` or ``blocks`` not of ``xy``'s length.

    Examples
    --------
    A wall across the line from the origin to a point 2 m away hides it, not a point in front:

    >>> wall = [[1.0, 0.1 * k - 0.5] for k in range(11)]
    >>> xy = np.array(wall + [[2.0, 0.0], [0.5, 0.0]])
    >>> hidden = occluded_points(xy, np.zeros((13, 2)), depth=0.5, reach=0.05, radius=0.3,
    ...                          neighbours=3, crossing=np.radians(20))
    >>> hidden[-2:].tolist()
    [True, False]
    """
    pts = np.ascontiguousarray(np.asarray(xy, dtype=np.float64).reshape(-1, 2))
    src = np.ascontiguousarray(np.asarray(origin, dtype=np.float64).reshape(-1, 2))
    blocking = (np.ones(len(pts), dtype=bool) if blocks is None
                else np.asarray(blocks, dtype=bool).reshape(-1))
    if src.shape != pts.shape or blocking.shape != (len(pts),):
        msg = (f"origin {src.shape} and blocks {blocking.shape} must match the {len(pts)} "
               "points")
        raise ValueError(msg)
    out = np.zeros(pts.shape[0], dtype=bool)
    index = np.flatnonzero(blocking)
    direction = surface_directions(pts[index], radius, neighbours, line_ratio)
    on_surface = ~np.isnan(direction[:, 0])
    index, direction = index[on_surface], direction[on_surface]
    if not len(index):
        return out
    # The walk's cells follow the reach, not the radius: the band it searches is 3 cells
    # wide, so the narrower the cells the fewer surface points a line passes by.
    cells = _buckets(pts[index], 2.0 * reach)
    _occluded(np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1]),
              np.ascontiguousarray(src[:, 0]), np.ascontiguousarray(src[:, 1]),
              np.ascontiguousarray(pts[index, 0]), np.ascontiguousarray(pts[index, 1]),
              np.ascontiguousarray(direction[:, 0]), np.ascontiguousarray(direction[:, 1]),
              cells.order, cells.sorted_keys, cells.starts, cells.x0, cells.y0, cells.rows,
              cells.cell, depth, reach, math.sin(crossing), out)
    return out
