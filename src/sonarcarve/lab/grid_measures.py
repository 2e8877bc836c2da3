"""Occupancy grids measured against the true walls (lab side: truth comes from the simulator).

Every grid of :mod:`sonarcarve.grids` is judged the same way, on its trinary map
(:func:`~sonarcarve.grids.trinary`: occupied, free, unknown) at its own resolution:

- the true walls are rasterised at the grid's resolution (:func:`wall_cells`: every cell a wall
  segment passes through);
- **occupied precision**: the share of occupied cells within one cell (the 3 x 3 block around
  them) of a wall cell;
- **occupied recall**: the share of *seen* wall cells (within one cell of the true reflection
  point of a direct echo) with an occupied cell within one cell;
- **phantoms**: the share of truly free cells (inside the world's bounds, farther than one cell
  from every wall cell) marked occupied;
- **wall covered**: the share of the seen wall length (wall samples every h/4 with a direct
  echo's reflection point within :data:`SEEN_RADIUS`) that has an occupied cell within one cell;
- **free near the path**: the share of the truly free cells a planner needs, those within
  :data:`NEAR_PATH` of the robot's path and in sight of it (no wall between the cell and the
  nearest path point), that the grid marks free: a corridor left unknown is one a planner with
  ``track_unknown_space`` must not enter, and a local controller scores as unsafe;
- **walls freed**: the share of seen wall cells marked free (what users of ROS's layer report as
  obstacles it erased);
- for openings, the **free width** read from the grid (:func:`grid_free_width`): the widest
  stretch of the gap whose cells, within :data:`~sonarcarve.lab.analyses.GAP_DEPTH` of the gap
  line, are all left open (not occupied, or strictly: free).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree

from sonarcarve.grids import OCCUPIED, OccupancyMap, trinary
from sonarcarve.grids.carved import FREE
from sonarcarve.lab.metrics import GapRegion
from sonarcarve.typing import BoolArray, FloatArray

__all__ = [
    "NEAR_PATH",
    "SEEN_RADIUS",
    "GridMeasures",
    "dilate",
    "grid_free_width",
    "grid_measures",
    "wall_cells",
]

#: A wall sample counts as seen when a direct echo's reflection point lies this close, metres
#: (half the 0.5 m wall patch of :mod:`benchmarks.grid_baseline`).
SEEN_RADIUS = 0.25

#: Free space is judged within this distance of the robot's path, metres: the corridor a
#: planner routes the robot through (Scout2's 0.2 m radius plus about half a metre).
NEAR_PATH = 0.75


class GridMeasures(NamedTuple):
    """One grid against the truth (shares in [0, 1]; NaN where the denominator is empty)."""

    precision: float
    recall: float
    phantoms: float
    wall_covered: float
    occupied_cells: int
    free_near_path: float = math.nan
    walls_freed: float = math.nan


def _cell_of(points: FloatArray, origin: tuple[float, float], h: float,
             shape: tuple[int, int]) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64],
                                               BoolArray]:
    """Row, column and in-grid flag of each point."""
    col = np.floor((points[:, 0] - origin[0]) / h).astype(np.int64)
    row = np.floor((points[:, 1] - origin[1]) / h).astype(np.int64)
    inside = (row >= 0) & (row < shape[0]) & (col >= 0) & (col < shape[1])
    return row, col, inside


def _wall_samples(segments: FloatArray, step: float) -> FloatArray:
    """Points along every segment, at most ``step`` apart, ends included, shape (n, 2)."""
    out = []
    for x1, y1, x2, y2 in np.asarray(segments, dtype=np.float64).reshape(-1, 4):
        n = max(1, math.ceil(math.hypot(x2 - x1, y2 - y1) / step))
        s = np.linspace(0.0, 1.0, n + 1)
        out.append(np.column_stack((x1 + s * (x2 - x1), y1 + s * (y2 - y1))))
    return np.vstack(out) if out else np.zeros((0, 2))


def wall_cells(segments: npt.ArrayLike, shape: tuple[int, int], origin: tuple[float, float],
               resolution: float) -> BoolArray:
    """Cells that a wall passes through, shape ``shape`` (rows along y from ``origin``).

    Each segment ``[x1, y1, x2, y2]`` is sampled every ``resolution / 8``.

    Examples
    --------
    >>> wall_cells([[0.0, 0.5, 2.0, 0.5]], (2, 3), (0.0, 0.0), 1.0).astype(int).tolist()
    [[1, 1, 1], [0, 0, 0]]
    """
    h = float(resolution)
    points = _wall_samples(np.asarray(segments, dtype=np.float64), h / 8.0)
    mask = np.zeros(shape, dtype=bool)
    row, col, inside = _cell_of(points, origin, h, shape)
    mask[row[inside], col[inside]] = True
    return mask


def dilate(mask: npt.ArrayLike, cells: int = 1) -> BoolArray:
    """Cells within ``cells`` of a True cell (Chebyshev distance: the square block).

    Examples
    --------
    >>> dilate(np.eye(3, dtype=bool)[:, ::-1][:1]).astype(int).tolist()
    [[0, 1, 1]]
    """
    m = np.asarray(mask, dtype=bool)
    out = m.copy()
    for _ in range(cells):
        grown = out.copy()
        grown[1:, :] |= out[:-1, :]
        grown[:-1, :] |= out[1:, :]
        grown[:, 1:] |= grown[:, :-1].copy()
        grown[:, :-1] |= grown[:, 1:].copy()
        out = grown
    return out


def _share(part: int, whole: int) -> float:
    return part / whole if whole else math.nan


def grid_measures(grid: OccupancyMap, segments: npt.ArrayLike, reflections: npt.ArrayLike,
                  world_bounds: tuple[float, float, float, float],
                  cells: npt.ArrayLike | None = None,
                  path: npt.ArrayLike | None = None) -> GridMeasures:
    """The measures of the module docstring for ``grid`` against ``segments``.

    Parameters
    ----------
    grid : OccupancyMap
        Any grid of :mod:`sonarcarve.grids`.
    segments : array-like, shape (n, 4)
        True walls ``[x1, y1, x2, y2]``, metres.
    reflections : array-like, shape (m, 2)
        True reflection points of the direct echoes (what the readings saw), metres.
    world_bounds : tuple of 4 floats
        ``(xmin, ymin, xmax, ymax)`` of the world: truly free cells are counted inside it.
    cells : array-like of int8, shape grid.shape, optional
        The grid's trinary map if already computed (default: :func:`~sonarcarve.grids.trinary`).
    path : array-like, shape (k, 2), optional
        Where the robot's sensors were (the readings' x and y), metres; without it
        ``free_near_path`` is NaN.
    """
    tri = trinary(grid) if cells is None else np.asarray(cells)
    occupied = tri == OCCUPIED
    h = grid.resolution
    origin = (grid.bounds[0], grid.bounds[1])
    walls = wall_cells(segments, grid.shape, origin, h)
    near_wall = dilate(walls)
    refl = np.asarray(reflections, dtype=np.float64).reshape(-1, 2)
    row, col, inside = _cell_of(refl, origin, h, grid.shape)
    hit = np.zeros(grid.shape, dtype=bool)
    hit[row[inside], col[inside]] = True
    seen_walls = walls & dilate(hit)
    near_occupied = dilate(occupied)
    xs, ys = grid.cell_centers()
    in_world = ((ys[:, None] >= world_bounds[1]) & (ys[:, None] <= world_bounds[3])
                & (xs[None, :] >= world_bounds[0]) & (xs[None, :] <= world_bounds[2]))
    truly_free = in_world & ~near_wall
    # Wall length: samples every h/4; seen within SEEN_RADIUS of a reflection.
    samples = _wall_samples(np.asarray(segments, dtype=np.float64), h / 4.0)
    seen = _near_any(samples, refl, SEEN_RADIUS)
    srow, scol, sin = _cell_of(samples, origin, h, grid.shape)
    covered = np.zeros(len(samples), dtype=bool)
    covered[sin] = near_occupied[srow[sin], scol[sin]]
    n_occ = int(np.count_nonzero(occupied))
    freed = int(np.count_nonzero(seen_walls & (tri == FREE)))
    near_path = math.nan
    if path is not None:
        wanted = truly_free & _in_sight_of_path(grid, segments, path)
        near_path = _share(int(np.count_nonzero(wanted & (tri == FREE))),
                           int(np.count_nonzero(wanted)))
    return GridMeasures(
        precision=_share(int(np.count_nonzero(occupied & near_wall)), n_occ),
        recall=_share(int(np.count_nonzero(seen_walls & near_occupied)),
                      int(np.count_nonzero(seen_walls))),
        phantoms=_share(int(np.count_nonzero(occupied & truly_free)),
                        int(np.count_nonzero(truly_free))),
        wall_covered=_share(int(np.count_nonzero(covered & seen)), int(np.count_nonzero(seen))),
        occupied_cells=n_occ,
        free_near_path=near_path,
        walls_freed=_share(freed, int(np.count_nonzero(seen_walls))),
    )


def _in_sight_of_path(grid: OccupancyMap, segments: npt.ArrayLike,
                      path: npt.ArrayLike) -> BoolArray:
    """Cells within :data:`NEAR_PATH` of a path point whose centre sees the nearest one (the
    straight line between them crosses no wall), shape ``grid.shape``."""
    xs, ys = grid.cell_centers()
    gx, gy = np.meshgrid(xs, ys)
    centres = np.column_stack((gx.ravel(), gy.ravel()))
    points = np.asarray(path, dtype=np.float64).reshape(-1, 2)
    out = np.zeros(len(centres), dtype=bool)
    if not len(points):
        return out.reshape(grid.shape)
    distance, nearest = cKDTree(points).query(centres, k=1,
                                              distance_upper_bound=NEAR_PATH * (1 + 1e-12))
    near = np.flatnonzero(distance <= NEAR_PATH)
    walls = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    blocked = _crosses_any(centres[near], points[nearest[near]], walls)
    out[near[~blocked]] = True
    return out.reshape(grid.shape)


def _crosses_any(a: FloatArray, b: FloatArray, walls: FloatArray,
                 tile: float = 2.0) -> BoolArray:
    """Whether each segment ``a[i]``-``b[i]`` properly crosses any wall (touching does not
    count). The segments are grouped by the ``tile``-metre square their ``a`` end lies in, and
    each group is tested only against the walls whose bounding box meets the group's (the
    office at 0.05 m: 180,000 segments against 290 walls, 9 s untiled)."""
    out = np.zeros(len(a), dtype=bool)
    if not len(a) or not len(walls):
        return out
    wall_lo = np.minimum(walls[:, :2], walls[:, 2:])
    wall_hi = np.maximum(walls[:, :2], walls[:, 2:])
    keys = np.floor(a / tile).astype(np.int64)
    _, group = np.unique(keys, axis=0, return_inverse=True)
    order = np.argsort(group.ravel(), kind="stable")
    starts = np.flatnonzero(np.diff(group.ravel()[order], prepend=-1))
    for members in np.split(order, starts[1:]):
        ends = np.vstack((a[members], b[members]))
        lo, hi = ends.min(axis=0), ends.max(axis=0)
        near = np.all((wall_lo <= hi) & (wall_hi >= lo), axis=1)
        if near.any():
            out[members] = _crosses(a[members], b[members], walls[near])
    return out


def _crosses(a: FloatArray, b: FloatArray, walls: FloatArray) -> BoolArray:
    """Whether each segment ``a[i]``-``b[i]`` properly crosses any of ``walls``."""
    p1, p2 = walls[None, :, :2], walls[None, :, 2:]
    q1, q2 = a[:, None, :], b[:, None, :]
    d1, d2 = _cross(p1, p2, q1), _cross(p1, p2, q2)
    d3, d4 = _cross(q1, q2, p1), _cross(q1, q2, p2)
    return np.asarray(((d1 * d2 < 0.0) & (d3 * d4 < 0.0)).any(axis=1))


def _cross(o: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """z of (a - o) x (b - o), broadcast: which side of the line o-a the point b lies on."""
    return ((a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1])
            - (a[..., 1] - o[..., 1]) * (b[..., 0] - o[..., 0]))


def _near_any(points: FloatArray, targets: FloatArray, radius: float) -> BoolArray:
    """Whether each point has a target within ``radius`` (a k-d tree over the targets)."""
    if not len(points) or not len(targets):
        return np.zeros(len(points), dtype=bool)
    # One nearest-neighbour query per point, bounded by the radius: a point with none within
    # it gets an infinite distance. (A Python loop over lattice buckets took half a second
    # per office grid.)
    distance, _ = cKDTree(targets).query(points, k=1, distance_upper_bound=radius * (1 + 1e-12))
    return np.asarray(distance <= radius)


def grid_free_width(grid: OccupancyMap, region: GapRegion, *, strict: bool = False,
                    cells: npt.ArrayLike | None = None) -> float:
    """Widest stretch of an opening left open by the grid, metres.

    Every cell whose square meets the ``region`` (the gap thickened by ``region.depth``) and
    that blocks (occupied; with ``strict``, anything not free: occupied or unknown) closes the
    stretch of the gap its square covers when projected on the gap line; the free width is
    the longest stretch no blocking cell covers, the jambs included as ends.

    Examples
    --------
    >>> from sonarcarve.grids import CarvedGrid
    >>> from sonarcarve.lab.metrics import gap_region
    >>> g = CarvedGrid(0.1, (0.0, 0.0, 1.0, 1.0))
    >>> region = gap_region([0.0, 0.5], [1.0, 0.5], 0.2)
    >>> grid_free_width(g, region), round(grid_free_width(g, region, strict=True), 9)
    (1.0, 0.0)
    """
    tri = trinary(grid) if cells is None else np.asarray(cells)
    blocking = tri != FREE if strict else tri == OCCUPIED
    xs, ys = grid.cell_centers()
    h = grid.resolution
    cx, cy = np.meshgrid(xs, ys)
    p = np.column_stack((cx[blocking], cy[blocking])) - region.a
    s = p @ region.u
    n = p @ region.n
    # Half the square's extent along the gap line and across it.
    reach_u = 0.5 * h * (abs(region.u[0]) + abs(region.u[1]))
    reach_n = 0.5 * h * (abs(region.n[0]) + abs(region.n[1]))
    meets = ((s + reach_u >= 0.0) & (s - reach_u <= region.width)
             & (np.abs(n) - reach_n <= region.depth))
    lo = np.clip(s[meets] - reach_u, 0.0, region.width)
    hi = np.clip(s[meets] + reach_u, 0.0, region.width)
    order = np.argsort(lo)
    best, reach = 0.0, 0.0
    for a, b in zip(lo[order].tolist(), hi[order].tolist(), strict=True):
        best = max(best, a - reach)
        reach = max(reach, b)
    return float(max(best, region.width - reach))
