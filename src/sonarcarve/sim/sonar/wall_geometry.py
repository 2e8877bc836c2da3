"""A world's walls with what tracing needs precomputed: normals, boxes, corners.

:class:`_WallGeometry` (both echo models) holds the walls' unit normals and bounding boxes and
the corners and free wall ends that scatter sound; :class:`_Corners` adds what the amplitude
model needs of those corners (which are right-angled retro-reflectors, and their walls'
directions).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial import cKDTree

from sonarcarve.sim.world import World
from sonarcarve.typing import BoolArray, FloatArray, IntArray


@dataclass(frozen=True, eq=False)
class _WallGeometry:
    """A world with what tracing needs precomputed: unit normals, bounding boxes, corners.

    ``scatter`` holds the corners and free wall ends (shape (m, 2)): every segment endpoint
    except where exactly two collinear walls continue each other (a wall split in two is still
    one smooth wall there).
    """

    world: World
    normals: FloatArray
    boxes: FloatArray
    scatter: FloatArray
    tree: cKDTree | None

    @classmethod
    def make(cls, world: World) -> _WallGeometry:
        seg = world.segments
        edge = seg[:, 2:] - seg[:, :2]
        length = np.maximum(np.hypot(edge[:, 0], edge[:, 1]), 1e-300)
        normals = np.column_stack((-edge[:, 1], edge[:, 0])) / length[:, None]
        xs, ys = seg[:, [0, 2]], seg[:, [1, 3]]
        boxes = np.column_stack((xs.min(axis=1), ys.min(axis=1), xs.max(axis=1), ys.max(axis=1)))
        scatter = _scatter_points(seg)
        tree = cKDTree(scatter) if scatter.shape[0] else None
        return cls(world, normals, boxes, scatter, tree)

    def near(self, xmin: float, ymin: float, xmax: float, ymax: float,
             margin: float) -> tuple[World, IntArray, FloatArray]:
        """Walls (as a world, plus their global indices) and corners in a box grown by margin."""
        b = self.boxes
        keep = ((b[:, 2] >= xmin - margin) & (b[:, 0] <= xmax + margin)
                & (b[:, 3] >= ymin - margin) & (b[:, 1] <= ymax + margin))
        index = np.flatnonzero(keep)
        s = self.scatter
        corner_keep = ((s[:, 0] >= xmin - margin) & (s[:, 0] <= xmax + margin)
                       & (s[:, 1] >= ymin - margin) & (s[:, 1] <= ymax + margin))
        return replace(self.world, segments=self.world.segments[index]), index, s[corner_keep]

    def near_corner(self, points: FloatArray, radius: float) -> BoolArray:
        """Which points, shape (k, 2), lie within ``radius`` of a corner or free wall end."""
        if self.tree is None or radius <= 0.0 or points.shape[0] == 0:
            return np.zeros(points.shape[0], dtype=bool)
        distance, _ = self.tree.query(points, k=1, distance_upper_bound=radius * (1 + 1e-12))
        return np.asarray(np.isfinite(distance))


def _scatter_points(seg: FloatArray, tol: float = 1e-9) -> FloatArray:
    """Corners and free ends of the walls ``seg`` (n, 4), duplicates merged; shape (m, 2).

    An endpoint is *not* a corner only where exactly one other wall ends at it and continues
    it in a straight line, with no third wall touching the point.
    """
    n = seg.shape[0]
    if n == 0:
        return np.zeros((0, 2))
    ends = np.concatenate([seg[:, :2], seg[:, 2:]])  # end k belongs to wall k % n
    owner = np.arange(2 * n) % n
    pairs = cKDTree(ends).query_pairs(tol, output_type="ndarray")
    pairs = pairs[owner[pairs[:, 0]] != owner[pairs[:, 1]]]
    count = np.bincount(pairs.ravel(), minlength=2 * n)
    partner = np.full(2 * n, -1)
    single = pairs[(count[pairs[:, 0]] == 1) & (count[pairs[:, 1]] == 1)]
    partner[single[:, 0]], partner[single[:, 1]] = single[:, 1], single[:, 0]
    candidates = np.flatnonzero(partner >= 0)
    edge = seg[:, 2:] - seg[:, :2]
    # Direction from each end into its own wall.
    inward = np.where((np.arange(2 * n) < n)[:, None], edge[owner], -edge[owner])
    a, b = inward[candidates], inward[partner[candidates]]
    cross = np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    scale = np.hypot(a[:, 0], a[:, 1]) * np.hypot(b[:, 0], b[:, 1])
    straight = (cross <= 1e-9 * scale) & (np.sum(a * b, axis=1) < 0.0)
    candidates = candidates[straight]
    crowded = _touching_count(seg, ends[candidates], tol) > 2  # a third wall meets the joint
    keep = np.ones(2 * n, dtype=bool)
    keep[candidates[~crowded]] = False
    points = ends[keep]
    return np.asarray(np.unique(np.round(points, 9), axis=0)) if points.size else points


def _touching_count(seg: FloatArray, points: FloatArray, tol: float) -> IntArray:
    """How many walls pass within ``tol`` of each point, shape (k,); blocks bound memory."""
    counts = np.zeros(points.shape[0], dtype=np.int64)
    a, edge = seg[:, :2], seg[:, 2:] - seg[:, :2]
    length2 = np.maximum(np.sum(edge * edge, axis=1), 1e-300)
    step = max(1, (1 << 18) // max(seg.shape[0], 1))
    for lo in range(0, points.shape[0], step):
        p = points[lo:lo + step]
        u = np.clip(np.einsum("kwj,wj->kw", p[:, None, :] - a[None], edge) / length2, 0.0, 1.0)
        near = a[None] + u[:, :, None] * edge[None]
        gap = np.hypot(p[:, None, 0] - near[..., 0], p[:, None, 1] - near[..., 1])
        counts[lo:lo + step] = np.sum(gap <= tol, axis=1)
    return counts


@dataclass(frozen=True, eq=False)
class _Corners:
    """The corners and free wall ends of a world (``_WallGeometry.scatter``), with what the
    amplitude model needs: which are right-angled two-wall corners (retro-reflectors seen from
    inside) and the directions ``u1``, ``u2`` (m, 2) of their two walls away from the corner.
    """

    points: FloatArray
    right: BoolArray
    u1: FloatArray
    u2: FloatArray

    @classmethod
    def make(cls, geometry: _WallGeometry, tolerance: float, tol: float = 1e-9) -> _Corners:
        points = geometry.scatter
        m = points.shape[0]
        u1, u2 = np.full((m, 2), np.nan), np.full((m, 2), np.nan)
        right = np.zeros(m, dtype=bool)
        seg = geometry.world.segments
        if m == 0 or seg.shape[0] == 0:
            return cls(points, right, u1, u2)
        ends = np.concatenate([seg[:, :2], seg[:, 2:]])
        others = np.concatenate([seg[:, 2:], seg[:, :2]])  # the far end of the same wall
        touching = _touching_count(seg, points, tol)
        for i, near in enumerate(cKDTree(ends).query_ball_point(points, tol)):
            if len(near) != 2 or touching[i] != 2:
                continue
            away = others[near] - points[i]
            away /= np.hypot(away[:, 0], away[:, 1])[:, None]
            if abs(float(away[0] @ away[1])) <= math.sin(tolerance) + 1e-12:
                right[i] = True
                u1[i], u2[i] = away
        return cls(points, right, u1, u2)
