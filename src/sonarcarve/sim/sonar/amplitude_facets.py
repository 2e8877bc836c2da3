"""The amplitude model's small reflectors: runs of short walls that draw a convex curve.

World files draw a table leg or a column as a regular polygon of short walls. With
:attr:`~sonarcarve.sim.amplitude.AmplitudeModel.small_reflectors` on, every wall whose two ends
each meet exactly one other wall turning the same way by at most
:attr:`~sonarcarve.sim.amplitude.AmplitudeModel.facet_turn`, in a run of such walls that
closes into a loop, is a *facet* of a circle: the one through its ends with the mean turn of
its joints as the angle it subtends (a regular polygon's circumscribed circle exactly).
:class:`_Facets` holds those circles; the echo finders take a facet's mirror point on its
circle (:func:`_nearest_on_curves`) and its level from
:func:`~sonarcarve.sim.amplitude.convex_mirror_db`. An open run (a wall drawn in pieces that
bend a little the same way, a rounded corner, a curved corridor) stays plane walls, and a facet
seen from inside its circle (a round room) is a plane mirror: the convex-cylinder echo holds
only outside.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from sonarcarve.sim.sonar.wall_geometry import _touching_count, _WallGeometry
from sonarcarve.typing import BoolArray, FloatArray, IntArray


@dataclass(frozen=True, eq=False)
class _Facets:
    """The convex curves among a geometry's walls.

    ``radius`` (n,), metres, and ``center`` (n, 2) of the circle each wall is a facet of (inf
    and NaN for a flat wall); ``corner`` (m,): which of ``geometry.scatter``'s corners are
    still corners (False: a joint between two facets, not an edge).
    """

    radius: FloatArray
    center: FloatArray
    corner: BoolArray

    @property
    def curved(self) -> BoolArray:
        """Which walls are facets of a curve, shape (n,)."""
        return np.asarray(np.isfinite(self.radius))

    @classmethod
    def make(cls, geometry: _WallGeometry, max_turn: float, tol: float = 1e-9) -> _Facets:
        seg = geometry.world.segments
        n = seg.shape[0]
        radius, center = np.full(n, np.inf), np.full((n, 2), np.nan)
        corner = np.ones(geometry.scatter.shape[0], dtype=bool)
        joint, turn = _bends(seg, max_turn, tol)
        if joint.shape[0] == 0:
            return cls(radius, center, corner)
        # Each joint as seen from each of its two walls: the turn, and to which side of the
        # wall the other one bends (the side of the circle's centre).
        owner = np.arange(2 * n) % n
        end, other = joint.reshape(-1), joint[:, ::-1].reshape(-1)
        wall = owner[end]
        into_other = _inward(seg)[other]
        side = np.sign(np.sum(geometry.normals[wall] * into_other, axis=1))
        ends = np.bincount(wall, minlength=n)
        total = np.bincount(wall, weights=np.repeat(turn, 2), minlength=n)
        sides = np.bincount(wall, weights=side, minlength=n)
        curved = np.flatnonzero(_closed((ends == 2) & (np.abs(sides) == 2), owner[joint]))
        edge = seg[curved, 2:] - seg[curved, :2]
        length = np.hypot(edge[:, 0], edge[:, 1])
        rho = length / (2.0 * np.sin(total[curved] / 4.0))  # mean turn / 2
        inner = geometry.normals[curved] * np.sign(sides[curved])[:, None]
        mid = 0.5 * (seg[curved, :2] + seg[curved, 2:])
        radius[curved] = rho
        center[curved] = mid + np.sqrt(np.maximum(rho**2 - length**2 / 4.0, 0.0))[:, None] * inner
        both = np.isfinite(radius[owner[joint[:, 0]]]) & np.isfinite(radius[owner[joint[:, 1]]])
        if np.any(both) and geometry.scatter.shape[0]:
            joints = np.concatenate([seg[:, :2], seg[:, 2:]])[joint[both, 0]]
            gap, _ = cKDTree(joints).query(geometry.scatter, k=1)
            corner = np.asarray(gap > tol)
        return cls(radius, center, corner)


def _closed(candidate: BoolArray, links: IntArray) -> BoolArray:
    """The ``candidate`` walls whose runs close into loops (a leg's or a column's polygon),
    ``links`` (k, 2) the two walls of each joint. An open run is a wall drawn in pieces (a
    bowed or rounded wall, a curved corridor): it stays a plane mirror, heard from both sides.
    """
    n = candidate.shape[0]
    link = links[candidate[links[:, 0]] & candidate[links[:, 1]]]
    degree = np.bincount(link.ravel(), minlength=n)
    graph = coo_matrix((np.ones(link.shape[0]), (link[:, 0], link[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    open_runs = np.unique(label[candidate & (degree < 2)])
    return np.asarray(candidate & ~np.isin(label, open_runs))


def _inward(seg: FloatArray) -> FloatArray:
    """Unit direction from each wall end into its wall, shape (2n, 2): starts, then ends."""
    edge = seg[:, 2:] - seg[:, :2]
    unit = edge / np.maximum(np.hypot(edge[:, 0], edge[:, 1]), 1e-300)[:, None]
    return np.asarray(np.concatenate([unit, -unit]))


def _bends(seg: FloatArray, max_turn: float, tol: float) -> tuple[IntArray, FloatArray]:
    """Joints of exactly two walls turning by more than 0 and at most ``max_turn`` radians:
    the two wall ends of each (numbered as :func:`_inward`'s), shape (k, 2), and the turns."""
    n = seg.shape[0]
    if n < 2:
        return np.zeros((0, 2), dtype=np.int64), np.zeros(0)
    ends = np.concatenate([seg[:, :2], seg[:, 2:]])
    owner = np.arange(2 * n) % n
    pairs = cKDTree(ends).query_pairs(tol, output_type="ndarray")
    pairs = pairs[owner[pairs[:, 0]] != owner[pairs[:, 1]]]
    count = np.bincount(pairs.ravel(), minlength=2 * n)
    pairs = pairs[(count[pairs[:, 0]] == 1) & (count[pairs[:, 1]] == 1)]
    inward = _inward(seg)
    cosine = np.sum(inward[pairs[:, 0]] * inward[pairs[:, 1]], axis=1)
    turn = math.pi - np.arccos(np.clip(cosine, -1.0, 1.0))
    bend = (turn > 1e-6) & (turn <= max_turn)
    pairs, turn = pairs[bend], turn[bend]
    alone = _touching_count(seg, ends[pairs[:, 0]], tol) == 2  # no third wall at the joint
    return np.asarray(pairs[alone]), np.asarray(turn[alone])


_CACHE: weakref.WeakKeyDictionary[_WallGeometry, dict[float, _Facets]] = (
    weakref.WeakKeyDictionary())


def _facets_of(geometry: _WallGeometry, max_turn: float) -> _Facets:
    """The facets of ``geometry`` (made once per geometry and ``max_turn``)."""
    made = _CACHE.setdefault(geometry, {})
    if max_turn not in made:
        made[max_turn] = _Facets.make(geometry, max_turn)
    return made[max_turn]


def _nearest_on_curves(facets: _Facets, walls: IntArray, origin: FloatArray,
                       seg: FloatArray) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Mirror points of the curved ``walls`` (k,) (global indices; ``seg`` (k, 4) their ends)
    for the sensors at ``origin`` (f, 2): the point of each circle nearest the sensor, its
    distance from it (f, k) and whether it lies on that facet's arc and the sensor outside.

    The arcs of a polygon's facets tile its circle, so from every bearing exactly one facet
    echoes (a facet's own foot of the perpendicular would leave gaps at the joints).
    """
    c, rho = facets.center[walls], facets.radius[walls]
    out = origin[:, None, :] - c[None]
    far = np.hypot(out[..., 0], out[..., 1])
    unit = out / np.maximum(far, 1e-300)[..., None]
    point = c[None] + rho[None, :, None] * unit
    to_a, to_b = seg[:, :2] - c, seg[:, 2:] - c

    def cross(p: FloatArray, q: FloatArray) -> FloatArray:
        return np.asarray(p[..., 0] * q[..., 1] - p[..., 1] * q[..., 0])

    # Each arc from its start A (included) to its end B (excluded), with a rounding margin, so
    # that a bearing through a joint belongs to exactly one facet.
    turn = np.sign(cross(to_a, to_b))[None]
    margin = 1e-9 * rho[None]
    inside = ((cross(to_a[None], unit) * turn >= -margin)
              & (cross(unit, to_b[None]) * turn > margin))
    inside &= far > rho[None]
    return np.asarray(point), np.asarray(far - rho[None]), np.asarray(inside)
