"""A 2-D world of walls as line segments, with its tour and openings, and exact ray casting.

A world is a set of zero-thickness walls (segments), plus two optional annotations that
experiments use: a *tour* (a collision-free waypoint path that shows the world off) and the
*openings* (door or passage gaps, each given by its two jamb endpoints).

No :class:`World` has a wall of zero length, nor a tour with fewer than two distinct waypoints.
A world read from a file has at least one wall, and its tour stays inside the walls' bounding
box and meets no wall (:func:`geometry_problem`, checked by the loaders only: a world made of
some of another's walls, as the sonar simulator makes, keeps the whole tour).

This module is the bottom of the simulator's worlds: files (:mod:`~sonarcarve.sim.world_files`),
generators (:mod:`~sonarcarve.sim.generate`) and :func:`~sonarcarve.sim.world.load_world` build
on it. Import these names from :mod:`sonarcarve.sim.world` or :mod:`sonarcarve.sim`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from sonarcarve.errors import SonarcarveError
from sonarcarve.typing import FloatArray

__all__ = ["MAX_WALLS", "MAX_WORLD_COORDINATE", "World", "WorldError", "check_seed",
           "first_wall_crossing", "geometry_problem"]

#: Largest |x| or |y| of a wall, tour waypoint or opening, metres: 100 km, as for waypoints
#: (:data:`sonarcarve.sim.motion.MAX_COORDINATE`); any building fits, and squared distances
#: stay far from overflow and keep millimetres exact.
MAX_WORLD_COORDINATE = 1e5
#: Most walls in a world: a large building traced from a 4096 x 4096 map has a few hundred
#: thousand; ray casting cost grows with the count.
MAX_WALLS = 1_000_000


#: Ray/wall (or point/wall) pairs evaluated at once; bounds the temporaries to a few tens of MB.
_PAIRS_PER_CHUNK = 1 << 19

#: Lengths and distances at or below this, metres, count as zero (walls, tour legs, contacts).
_TINY = 1e-9


class WorldError(SonarcarveError):
    """A world that cannot be loaded or built (bad file, unknown name, degenerate walls, a tour
    through a wall), or a simulation parameter out of range (seed, speed, duration)."""


def check_seed(seed: object, where: str = "seed") -> int:
    """``seed`` as an int if it can seed the simulator's random generator: an integer >= 0.

    Every seeded function of :mod:`sonarcarve.sim` calls this first, so a bad seed gives a
    one-line error instead of numpy's traceback.

    Parameters
    ----------
    seed : object
        The seed to check.
    where : str
        Names the seed in the message (e.g. ``"random:-1: seed"``).

    Raises
    ------
    WorldError
        ``<where> must be an integer >= 0, got <seed>``.

    Examples
    --------
    >>> check_seed(7)
    7
    >>> check_seed(-1)
    Traceback (most recent call last):
    ...
    sonarcarve.sim.walls.WorldError: seed must be an integer >= 0, got -1
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        msg = f"{where} must be an integer >= 0, got {seed!r}"
        raise WorldError(msg)
    return int(seed)


def _no_openings() -> FloatArray:
    return np.zeros((0, 2, 2), dtype=np.float64)


@dataclass(frozen=True, eq=False)
class World:
    """Walls as segments, with an optional tour and the world's openings.

    Attributes
    ----------
    segments : ndarray, shape (n, 4)
        Wall ``i`` runs from ``(x1, y1)`` to ``(x2, y2)`` = ``segments[i]``, metres.
    name : str
        Where the world came from (built-in name or file).
    tour : ndarray, shape (k, 2), or None
        Waypoints of a collision-free path through the world (at least 2 distinct), metres;
        loaders check that it stays inside the walls' bounding box and meets no wall; for the
        built-in worlds every point of the polyline is at least 0.45 m from every wall.
    openings : ndarray, shape (k, 2, 2)
        Door or passage gaps: ``openings[i, 0]`` and ``openings[i, 1]`` are the two ends (jambs)
        of gap ``i``, metres. Empty, shape (0, 2, 2), when unknown.
    description : str
        One line saying what the world is.
    """

    segments: FloatArray
    name: str = "world"
    tour: FloatArray | None = None
    openings: FloatArray = field(default_factory=_no_openings)
    description: str = ""

    def __post_init__(self) -> None:
        seg = np.asarray(self.segments, dtype=np.float64).reshape(-1, 4)
        if not np.all(np.isfinite(seg)):
            msg = f"{self.name}: wall coordinates must be finite"
            raise WorldError(msg)
        object.__setattr__(self, "segments", seg)
        if self.tour is not None:
            tour = np.asarray(self.tour, dtype=np.float64)
            if tour.ndim != 2 or tour.shape[1] != 2 or tour.shape[0] < 2:
                msg = f"{self.name}: tour must have shape (k >= 2, 2), got {tour.shape}"
                raise WorldError(msg)
            if not np.all(np.isfinite(tour)):
                msg = f"{self.name}: tour coordinates must be finite"
                raise WorldError(msg)
            object.__setattr__(self, "tour", tour)
        openings = np.asarray(self.openings, dtype=np.float64)
        if openings.size == 0:
            openings = _no_openings()
        if openings.ndim != 3 or openings.shape[1:] != (2, 2):
            msg = f"{self.name}: openings must have shape (k, 2, 2), got {openings.shape}"
            raise WorldError(msg)
        if not np.all(np.isfinite(openings)):
            msg = f"{self.name}: opening coordinates must be finite"
            raise WorldError(msg)
        if np.any(np.abs(openings) > MAX_WORLD_COORDINATE):
            msg = (f"{self.name}: opening coordinates must lie within "
                   f"±{MAX_WORLD_COORDINATE:g} m (MAX_WORLD_COORDINATE)")
            raise WorldError(msg)
        object.__setattr__(self, "openings", openings)
        problem = geometry_problem(seg, self.tour, against_walls=False)
        if problem is not None:
            msg = f"{self.name}: {problem}"
            raise WorldError(msg)

    def __len__(self) -> int:
        return int(self.segments.shape[0])

    def __repr__(self) -> str:
        width, height = self.size
        tour = "yes" if self.tour is not None else "no"
        return (f"World({self.name!r}, {len(self)} walls, {width:.1f} m x {height:.1f} m, "
                f"{self.openings.shape[0]} openings, tour={tour})")

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` of all walls, metres."""
        if not len(self):
            return 0.0, 0.0, 0.0, 0.0
        xs = self.segments[:, [0, 2]]
        ys = self.segments[:, [1, 3]]
        return float(xs.min()), float(ys.min()), float(xs.max()), float(ys.max())

    @property
    def size(self) -> tuple[float, float]:
        """``(width, height)`` of the walls' bounding box, metres."""
        xmin, ymin, xmax, ymax = self.bounds
        return xmax - xmin, ymax - ymin

    @property
    def area(self) -> float:
        """Area of the walls' bounding box, m² (the building's footprint for a rectangular plan)."""
        width, height = self.size
        return width * height

    @property
    def tour_length(self) -> float:
        """Length of the tour polyline, metres (0 without a tour)."""
        if self.tour is None:
            return 0.0
        return float(np.sum(np.hypot(*np.diff(self.tour, axis=0).T)))

    @property
    def start_pose(self) -> tuple[float, float, float] | None:
        """``(x, y, heading)`` at the tour's start, heading towards its next distinct waypoint."""
        if self.tour is None:
            return None
        steps = self.tour[1:] - self.tour[0]
        moving = np.flatnonzero(np.hypot(steps[:, 0], steps[:, 1]) > 1e-9)
        dx, dy = steps[moving[0]] if moving.size else (1.0, 0.0)
        return float(self.tour[0, 0]), float(self.tour[0, 1]), math.atan2(dy, dx)

    def cast_rays(
        self, origins: npt.ArrayLike, angles: npt.ArrayLike, max_range: float = np.inf
    ) -> tuple[FloatArray, npt.NDArray[np.int64]]:
        """Distance to the first wall along each ray, exactly (no sampling).

        A ray that passes exactly through a wall's end point hits that wall; a ray parallel to a
        wall never hits it (not even when it runs along it); a wall through the origin itself is
        ignored (hits at distance <= 1e-9 m do not count).

        Parameters
        ----------
        origins : array-like, shape (n, 2) or (2,)
            Ray starts, metres (one origin broadcast to every ray if shape (2,)).
        angles : array-like, shape (n,)
            Ray directions, radians counter-clockwise from +x.
        max_range : float
            Rays that hit nothing closer return ``inf``.

        Returns
        -------
        distance : ndarray, shape (n,)
            Distance to the first hit, or ``inf``.
        wall : ndarray of int64, shape (n,)
            Index of the wall hit, or -1.

        Examples
        --------
        >>> w = World(np.array([[1.0, -1.0, 1.0, 1.0]]))
        >>> d, i = w.cast_rays([0.0, 0.0], [0.0, np.pi])
        >>> d.tolist(), i.tolist()
        ([1.0, inf], [0, -1])
        """
        angle = np.atleast_1d(np.asarray(angles, dtype=np.float64))
        origin = np.broadcast_to(np.asarray(origins, dtype=np.float64), (angle.shape[0], 2))
        distance = np.full(angle.shape[0], np.inf)
        wall = np.full(angle.shape[0], -1, dtype=np.int64)
        if not len(self):
            return distance, wall
        step = max(1, _PAIRS_PER_CHUNK // len(self))
        for lo in range(0, angle.shape[0], step):
            hi = lo + step
            distance[lo:hi], wall[lo:hi] = _cast_chunk(
                self.segments, origin[lo:hi], angle[lo:hi], max_range)
        return distance, wall

    def distance_to_walls(self, points: npt.ArrayLike) -> FloatArray:
        """Euclidean distance from each point, shape (n, 2), to the nearest wall, shape (n,).

        ``inf`` for a world without walls.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if not len(self):
            return np.full(p.shape[0], np.inf)
        out = np.empty(p.shape[0])
        step = max(1, _PAIRS_PER_CHUNK // len(self))
        for lo in range(0, p.shape[0], step):
            out[lo:lo + step] = _point_segment_distance(p[lo:lo + step], self.segments).min(axis=1)
        return out


def _cast_chunk(segments: FloatArray, origin: FloatArray, angle: FloatArray,
                max_range: float) -> tuple[FloatArray, npt.NDArray[np.int64]]:
    direction = np.column_stack((np.cos(angle), np.sin(angle)))
    a = segments[:, :2]
    edge = segments[:, 2:] - a
    # Solve origin + s * direction = a + u * edge for every (ray, wall) pair (Cramer's rule).
    denom = _cross(direction[:, None, :], edge[None, :, :])
    delta = a[None, :, :] - origin[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        s = _cross(delta, edge[None, :, :]) / denom
        u = _cross(delta, direction[:, None, :]) / denom
    hit = (np.abs(denom) > 1e-12) & (s > 1e-9) & (u >= 0.0) & (u <= 1.0) & (s <= max_range)
    s = np.where(hit, s, np.inf)
    wall = np.argmin(s, axis=1)
    distance = s[np.arange(angle.shape[0]), wall]
    return distance, np.where(np.isfinite(distance), wall, -1).astype(np.int64)


def _point_segment_distance(points: FloatArray, segments: FloatArray) -> FloatArray:
    """Distances, shape (n, m), from points (n, 2) to segments (m, 4)."""
    a = segments[None, :, :2]
    edge = segments[None, :, 2:] - a
    length2 = np.maximum(np.sum(edge * edge, axis=2), 1e-24)
    u = np.clip(np.sum((points[:, None, :] - a) * edge, axis=2) / length2, 0.0, 1.0)
    nearest = a + u[:, :, None] * edge
    return np.asarray(np.hypot(points[:, None, 0] - nearest[..., 0],
                               points[:, None, 1] - nearest[..., 1]))


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.asarray(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])


# --------------------------------------------------------------------------------------------
# Consistency of walls and tour
# --------------------------------------------------------------------------------------------

def geometry_problem(segments: FloatArray, tour: FloatArray | None, *,
                      against_walls: bool = True) -> str | None:
    """What is wrong with the walls and the tour, as the tail of a message, or None.

    Checks that there are at most :data:`MAX_WALLS` walls, that every coordinate lies within
    ±:data:`MAX_WORLD_COORDINATE` metres, that no wall has zero length and that a tour has two
    distinct waypoints; with ``against_walls`` (and walls to check against), also that the tour
    stays inside the walls' bounding box and meets no wall.
    """
    if segments.shape[0] > MAX_WALLS:
        return f"{segments.shape[0]:,} walls, more than the limit of {MAX_WALLS:,} (MAX_WALLS)"
    for key, points in (("segments", segments), ("tour", tour)):
        if points is None:
            continue
        far = np.flatnonzero(np.any(np.abs(points) > MAX_WORLD_COORDINATE, axis=1))
        if far.size:
            row = ", ".join(f"{v:g}" for v in points[far[0]])
            return (f"{key}[{far[0]}] [{row}] lies beyond ±{MAX_WORLD_COORDINATE:g} m "
                    "(MAX_WORLD_COORDINATE) from the origin in x or y")
    lengths = np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
    short = np.flatnonzero(lengths <= _TINY)
    if short.size:
        x, y = segments[short[0], :2]
        return f"segments[{short[0]}] is a wall of zero length (both ends at ({x:g}, {y:g}))"
    if tour is None:
        return None
    if not np.any(np.hypot(*(tour[1:] - tour[0]).T) > _TINY):
        x, y = tour[0]
        return (f"tour needs at least 2 distinct waypoints, all {tour.shape[0]} are "
                f"({x:g}, {y:g})")
    if not (against_walls and segments.shape[0]):
        return None
    low, high = segments.reshape(-1, 2).min(axis=0), segments.reshape(-1, 2).max(axis=0)
    outside = np.flatnonzero(np.any((tour < low - _TINY) | (tour > high + _TINY), axis=1))
    if outside.size:
        i = int(outside[0])
        return (f"tour[{i}] ({tour[i, 0]:g}, {tour[i, 1]:g}) lies outside the walls' bounding "
                f"box x in [{low[0]:g}, {high[0]:g}], y in [{low[1]:g}, {high[1]:g}]")
    crossing = _first_crossing(tour, segments)
    if crossing is not None:
        leg, wall, (x, y) = crossing
        return (f"tour leg {leg} (tour[{leg}] -> tour[{leg + 1}]) runs into wall "
                f"segments[{wall}] at ({x:g}, {y:g})")
    return None


def first_wall_crossing(path: FloatArray, segments: FloatArray
                        ) -> tuple[int, tuple[float, float]] | None:
    """``(leg, (x, y))``: the first leg of the polyline ``path`` (from ``path[leg]`` to
    ``path[leg + 1]``) that meets a wall of ``segments``, and where; None if none does."""
    if not segments.shape[0]:
        return None
    crossing = _first_crossing(path, segments)
    return None if crossing is None else (crossing[0], crossing[2])


def _first_crossing(tour: FloatArray, segments: FloatArray
                    ) -> tuple[int, int, tuple[float, float]] | None:
    """The first place, in tour order, where the tour polyline meets a wall.

    Returns ``(leg, wall, (x, y))``: leg ``i`` runs from ``tour[i]`` to ``tour[i + 1]``; touching
    a wall (an end point on it, or running along it) counts as meeting it. None if it meets none.
    Walls must have non-zero length.
    """
    start, step = tour[:-1], np.diff(tour, axis=0)
    rows = max(1, _PAIRS_PER_CHUNK // segments.shape[0])
    for lo in range(0, start.shape[0], rows):
        contact = _leg_contacts(start[lo:lo + rows], step[lo:lo + rows], segments)
        legs = np.flatnonzero(np.isfinite(contact).any(axis=1))
        if legs.size:
            leg = int(legs[0])
            wall = int(np.argmin(contact[leg]))
            x, y = start[lo + leg] + contact[leg, wall] * step[lo + leg]
            return lo + leg, wall, (float(x), float(y))
    return None


def _leg_contacts(start: FloatArray, step: FloatArray, segments: FloatArray) -> FloatArray:
    """Per (leg, wall) pair, shape (k, n): the leg parameter in [0, 1] of the first point the leg
    shares with the wall (within 1e-9 m), or ``inf`` where they share none.

    Leg ``i`` is ``start[i] + t * step[i]``, wall ``j`` is ``a[j] + u * edge[j]``, t and u in
    [0, 1]. Crossing legs solve both equations by Cramer's rule; parallel legs meet a wall only
    when they lie on its line, from where its overlap with the wall is read off directly.
    """
    a, edge = segments[:, :2], segments[:, 2:] - segments[:, :2]
    edge_len = np.hypot(edge[:, 0], edge[:, 1])[None, :]
    step_len = np.hypot(step[:, 0], step[:, 1])[:, None]
    tol_t = _TINY / np.maximum(step_len, _TINY)    # metres of slack as parameters
    tol_u = _TINY / edge_len
    denom = _cross(step[:, None, :], edge[None, :, :])
    delta = a[None, :, :] - start[:, None, :]
    off_line = _cross(delta, edge[None, :, :])     # edge_len times the start's distance to it
    parallel = np.abs(denom) <= 1e-12 * step_len * edge_len
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = off_line / denom
        u = _cross(delta, step[:, None, :]) / denom
        crossing = (~parallel & (t >= -tol_t) & (t <= 1 + tol_t)
                    & (u >= -tol_u) & (u <= 1 + tol_u))
        # Parallel: where the leg's ends fall along the wall (0 and 1 are the wall's ends).
        u0 = -np.sum(delta * edge[None, :, :], axis=2) / edge_len**2
        u1 = u0 + (step @ edge.T) / edge_len**2
        on_line = parallel & (np.abs(off_line) <= _TINY * edge_len)
        overlap = on_line & (np.maximum(u0, u1) >= -tol_u) & (np.minimum(u0, u1) <= 1 + tol_u)
        inside = (u0 >= -tol_u) & (u0 <= 1 + tol_u)
        reach = np.where(inside, 0.0, (np.where(u0 < 0.0, 0.0, 1.0) - u0) / (u1 - u0))
    contact = np.full(denom.shape, np.inf)
    contact[crossing] = np.clip(t[crossing], 0.0, 1.0)
    contact[overlap] = np.clip(reach[overlap], 0.0, 1.0)
    return contact
