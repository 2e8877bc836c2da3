"""Changing scenes: obstacles that appear, vanish and move, with their truth over time.

A :class:`Scene` is a set of :class:`DynamicObstacle` objects added to a world's static walls.
Each obstacle is a set of segments (a closed polygon for a box or a disc, one segment for a
door), present during ``[appear, vanish)`` and, optionally, moving in a straight line: shifted
by ``shift * clip((t - t0) / (t1 - t0), 0, 1)`` from where its segments were given. A disc is
a regular polygon of :data:`DISC_SIDES` sides inscribed in the circle (its facets lie within
``r (1 - cos(π / n))``, 1.7 mm for a 0.2 m radius, of the true circle); its
vertices are corners to the sonar simulator, so it echoes from any side like the convex
scatterer a person is.

The sonar simulator (:func:`~sonarcarve.sim.sonar.fire_sonars`, :func:`~sonarcarve.sim.simulate`
with ``scene=``) traces each firing against the static walls plus the obstacles present at that
firing's time, at their position at that time (exactly: firings are grouped into runs during
which no obstacle changes, :meth:`Scene.epochs`; a moving obstacle makes every firing its own
run), and each reading's truth says which obstacle, if any, it came from
(:meth:`Scene.obstacle_hit`).

Three built-in changing scenes (:func:`changing_scene`, names in :data:`CHANGING_SCENES`):

- ``person``: a 0.4 m disc crosses a 2 m corridor at 1 m/s, 3.2-4.2 m in front of the robot;
- ``door``: a door (one segment across a 1.2 m doorway) closes while the robot approaches it
  head-on and opens again before the robot drives through;
- ``box``: a 0.5 m box against a corridor wall, driven past, removed while the robot is in a
  side room out of its sight, and driven past again on the way back.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from sonarcarve.sim.walls import World, WorldError
from sonarcarve.typing import BoolArray, FloatArray, IntArray

__all__ = [
    "CHANGING_SCENES",
    "DISC_SIDES",
    "ChangingScene",
    "DynamicObstacle",
    "Scene",
    "changing_scene",
]

#: Sides of the regular polygon that stands for a disc.
DISC_SIDES = 24

#: A reflection point this close to an obstacle's outline (metres) came from that obstacle.
_ON_OUTLINE = 1e-6


def _float_pair(value: npt.ArrayLike, what: str) -> tuple[float, float]:
    pair = np.asarray(value, dtype=np.float64).reshape(-1)
    if pair.shape != (2,) or not np.all(np.isfinite(pair)):
        msg = f"{what} must be 2 finite numbers, got {value!r}"
        raise WorldError(msg)
    return float(pair[0]), float(pair[1])


@dataclass(frozen=True, eq=False)
class DynamicObstacle:
    """An obstacle with a presence interval and an optional straight-line motion.

    Attributes
    ----------
    segments : ndarray, shape (m, 4)
        Its outline ``(x1, y1, x2, y2)`` per segment, metres, where it stands at ``t <= t0``.
    name : str
        What it is (``"person"``, ``"door"``...).
    appear, vanish : float
        Present for ``appear <= t < vanish``, seconds (default: always).
    shift : tuple of 2 floats
        Displacement reached at ``t1``, metres (default none: a static obstacle).
    t0, t1 : float
        The motion runs linearly from ``t0`` to ``t1``, seconds (``t1 > t0`` when it moves).
    center : tuple of 2 floats
        A reference point (the disc's centre, the box's centre, the door's middle) at ``t <= t0``.
    """

    segments: FloatArray
    name: str = "obstacle"
    appear: float = -math.inf
    vanish: float = math.inf
    shift: tuple[float, float] = (0.0, 0.0)
    t0: float = 0.0
    t1: float = 0.0
    center: tuple[float, float] = field(default=(math.nan, math.nan))

    def __post_init__(self) -> None:
        seg = np.asarray(self.segments, dtype=np.float64).reshape(-1, 4)
        if seg.shape[0] == 0 or not np.all(np.isfinite(seg)):
            msg = f"obstacle {self.name!r}: needs at least one segment, all coordinates finite"
            raise WorldError(msg)
        if np.any(np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]) <= 1e-9):
            msg = f"obstacle {self.name!r}: a segment of zero length"
            raise WorldError(msg)
        object.__setattr__(self, "segments", seg)
        object.__setattr__(self, "shift",
                           _float_pair(self.shift, f"obstacle {self.name!r}: shift"))
        if not self.appear < self.vanish:
            msg = (f"obstacle {self.name!r}: appear {self.appear} must be before vanish "
                   f"{self.vanish}")
            raise WorldError(msg)
        if self.moves and not (math.isfinite(self.t0) and math.isfinite(self.t1)
                               and self.t1 > self.t0):
            msg = f"obstacle {self.name!r}: a motion needs finite t0 < t1, got {self.t0}, {self.t1}"
            raise WorldError(msg)
        if math.isnan(self.center[0]):
            ends = seg.reshape(-1, 2)
            object.__setattr__(self, "center", (float(ends[:, 0].mean()),
                                                float(ends[:, 1].mean())))
        else:
            object.__setattr__(self, "center",
                               _float_pair(self.center, f"obstacle {self.name!r}: center"))

    @classmethod
    def disc(cls, center: npt.ArrayLike, radius: float, name: str = "disc",
             sides: int = DISC_SIDES, *, appear: float = -math.inf, vanish: float = math.inf,
             shift: tuple[float, float] = (0.0, 0.0), t0: float = 0.0, t1: float = 0.0
             ) -> DynamicObstacle:
        """A disc of ``radius`` metres about ``center``: a regular polygon of ``sides`` sides
        with its vertices on the circle. ``appear``, ``vanish``, ``shift``, ``t0``, ``t1`` as
        the class attributes.

        Examples
        --------
        >>> d = DynamicObstacle.disc((0.0, 0.0), 0.2, sides=4)
        >>> d.segments.round(3).tolist()[0]
        [0.2, 0.0, 0.0, 0.2]
        """
        cx, cy = _float_pair(center, f"obstacle {name!r}: center")
        if not (math.isfinite(radius) and radius > 0.0 and sides >= 3):
            msg = f"obstacle {name!r}: a disc needs radius > 0 and sides >= 3"
            raise WorldError(msg)
        a = 2.0 * math.pi * np.arange(sides + 1) / sides
        x, y = cx + radius * np.cos(a), cy + radius * np.sin(a)
        seg = np.column_stack((x[:-1], y[:-1], x[1:], y[1:]))
        return cls(seg, name, appear, vanish, shift, t0, t1, center=(cx, cy))

    @classmethod
    def box(cls, xmin: float, ymin: float, xmax: float, ymax: float, name: str = "box", *,
            appear: float = -math.inf, vanish: float = math.inf,
            shift: tuple[float, float] = (0.0, 0.0), t0: float = 0.0, t1: float = 0.0
            ) -> DynamicObstacle:
        """An axis-aligned rectangle (its four sides); the rest as :meth:`disc`."""
        corners = [(xmin, ymin), (xmax, ymin), (xmax, ymax), (xmin, ymax), (xmin, ymin)]
        seg = [(*a, *b) for a, b in itertools.pairwise(corners)]
        return cls(np.array(seg, dtype=np.float64), name, appear, vanish, shift, t0, t1)

    @classmethod
    def wall(cls, a: npt.ArrayLike, b: npt.ArrayLike, name: str = "door", *,
             appear: float = -math.inf, vanish: float = math.inf,
             shift: tuple[float, float] = (0.0, 0.0), t0: float = 0.0, t1: float = 0.0
             ) -> DynamicObstacle:
        """One segment from ``a`` to ``b`` (a door); the rest as :meth:`disc`."""
        seg = np.array([[*_float_pair(a, "a"), *_float_pair(b, "b")]])
        return cls(seg, name, appear, vanish, shift, t0, t1)

    @property
    def moves(self) -> bool:
        """Whether the obstacle has a motion (a non-zero shift)."""
        return self.shift != (0.0, 0.0)

    def present(self, times: npt.ArrayLike) -> BoolArray:
        """Whether it is there at each time, shape of ``times``."""
        t = np.asarray(times, dtype=np.float64)
        return np.asarray((t >= self.appear) & (t < self.vanish))

    def offset(self, times: npt.ArrayLike) -> FloatArray:
        """Its displacement from where its segments were given at each time, shape (n, 2)."""
        t = np.atleast_1d(np.asarray(times, dtype=np.float64))
        if not self.moves:
            return np.zeros((t.shape[0], 2))
        s = np.clip((t - self.t0) / (self.t1 - self.t0), 0.0, 1.0)
        return np.asarray(s[:, None] * np.asarray(self.shift)[None, :])

    def segments_at(self, t: float) -> FloatArray:
        """Its segments at time ``t``, shape (m, 4); shape (0, 4) while it is absent."""
        if not bool(self.present(t)):
            return np.zeros((0, 4))
        dx, dy = self.offset(t)[0]
        return np.asarray(self.segments + np.array([dx, dy, dx, dy]))

    def center_at(self, times: npt.ArrayLike) -> FloatArray:
        """Its reference point at each time, shape (n, 2) (where it would be while absent)."""
        return np.asarray(np.asarray(self.center)[None, :] + self.offset(times))


@dataclass(frozen=True, eq=False)
class Scene:
    """Obstacles added to a world's walls over time (the module docstring).

    Attributes
    ----------
    obstacles : tuple of DynamicObstacle
        Obstacle ``i`` is the ``i`` of :meth:`obstacle_hit` and the readings' truth.
    """

    obstacles: tuple[DynamicObstacle, ...] = ()

    def __len__(self) -> int:
        return len(self.obstacles)

    @property
    def names(self) -> list[str]:
        """The obstacles' names, in order."""
        return [o.name for o in self.obstacles]

    def segments_at(self, t: float) -> tuple[FloatArray, IntArray]:
        """The obstacles' segments at time ``t``, shape (m, 4), and the obstacle of each, (m,).

        Examples
        --------
        >>> door = DynamicObstacle.wall((0, 0), (1, 0), appear=2.0, vanish=5.0)
        >>> [Scene((door,)).segments_at(t)[1].tolist() for t in (1.0, 2.0, 5.0)]
        [[], [0], []]
        """
        parts = [o.segments_at(t) for o in self.obstacles]
        owner = [np.full(p.shape[0], i, dtype=np.int64) for i, p in enumerate(parts)]
        if not parts:
            return np.zeros((0, 4)), np.zeros(0, dtype=np.int64)
        return np.vstack(parts), np.concatenate(owner)

    def world_at(self, world: World, t: float) -> World:
        """``world`` with the obstacles present at ``t`` appended to its walls (tour kept)."""
        seg, _ = self.segments_at(t)
        return World(np.vstack((world.segments, seg)), world.name, world.tour, world.openings,
                     world.description)

    def epochs(self, times: npt.ArrayLike) -> IntArray:
        """Starts of the runs of ``times`` (sorted) during which no obstacle changes.

        Returns the index of each run's first time, increasing, starting with 0 (empty for no
        times): an obstacle appearing or vanishing starts a run, and while one moves every time
        starts its own.

        Examples
        --------
        >>> door = DynamicObstacle.wall((0, 0), (1, 0), appear=2.0, vanish=5.0)
        >>> Scene((door,)).epochs([0.0, 1.0, 2.0, 3.0, 5.0, 6.0]).tolist()
        [0, 2, 4]
        """
        t = np.asarray(times, dtype=np.float64).reshape(-1)
        if t.shape[0] == 0:
            return np.zeros(0, dtype=np.int64)
        new = np.zeros(t.shape[0], dtype=bool)
        new[0] = True
        for o in self.obstacles:
            present = o.present(t)
            offset = o.offset(t)
            new[1:] |= present[1:] != present[:-1]
            new[1:] |= present[1:] & np.any(offset[1:] != offset[:-1], axis=1)
        return np.flatnonzero(new).astype(np.int64)

    def distance(self, points: npt.ArrayLike, t: float) -> FloatArray:
        """Distance from each point, shape (n, 2), to the obstacles present at ``t``, (n,)
        (``inf`` when none is)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        seg, _ = self.segments_at(t)
        if seg.shape[0] == 0 or p.shape[0] == 0:
            return np.full(p.shape[0], np.inf)
        return World(seg).distance_to_walls(p)

    def obstacle_hit(self, points: npt.ArrayLike, times: npt.ArrayLike) -> IntArray:
        """Which obstacle each reflection point lies on at its time, -1 for none (a static
        wall, or NaN: no reflection point), shape (n,).

        A point on two outlines (a door's end on a box) goes to the lower index.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        t = np.asarray(times, dtype=np.float64).reshape(-1)
        out = np.full(p.shape[0], -1, dtype=np.int64)
        finite = np.all(np.isfinite(p), axis=1)
        for i in range(len(self.obstacles) - 1, -1, -1):
            o = self.obstacles[i]
            rows = np.flatnonzero(finite & o.present(t))
            if rows.size == 0:
                continue
            moved = o.segments[None, :, :] + np.tile(o.offset(t[rows]), 2)[:, None, :]
            gap = _distance_each(p[rows], moved)
            out[rows[gap <= _ON_OUTLINE]] = i
        return out


def _distance_each(points: FloatArray, segments: FloatArray) -> FloatArray:
    """Distance from point ``k`` (k, 2) to the nearest of its own segments (k, m, 4), (k,)."""
    a = segments[..., :2]
    edge = segments[..., 2:] - a
    length2 = np.maximum(np.sum(edge * edge, axis=2), 1e-24)
    u = np.clip(np.sum((points[:, None, :] - a) * edge, axis=2) / length2, 0.0, 1.0)
    near = a + u[..., None] * edge
    gap = np.hypot(points[:, None, 0] - near[..., 0], points[:, None, 1] - near[..., 1])
    return np.asarray(gap.min(axis=1))


# --------------------------------------------------------------------------------------------
# Built-in changing scenes
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class ChangingScene:
    """A world, its changing obstacles and the robot's drive through them.

    Attributes
    ----------
    name : str
        ``person``, ``door`` or ``box``.
    world : World
        The static walls (with the drive as its tour).
    scene : Scene
        The obstacles.
    waypoints : ndarray, shape (k, 2)
        The drive, metres (:func:`~sonarcarve.sim.motion.follow_waypoints`).
    description : str
        One line saying what happens.
    """

    name: str
    world: World
    scene: Scene
    waypoints: FloatArray
    description: str


def _walls(edges: list[tuple[float, float, float, float]]) -> FloatArray:
    return np.array(edges, dtype=np.float64)


def _person_scene() -> ChangingScene:
    # A 2 m corridor (x in [-1, 1], y in [0, 16]) crossed at y = 8 by a 2 m cross corridor.
    w = _walls([(-1, 0, 1, 0), (-1, 16, 1, 16),
                (-1, 0, -1, 7), (-1, 9, -1, 16), (1, 0, 1, 7), (1, 9, 1, 16),
                (-4, 7, -1, 7), (-4, 9, -1, 9), (1, 7, 4, 7), (1, 9, 4, 9),
                (-4, 7, -4, 9), (4, 7, 4, 9)])
    path = np.array([(0.0, 1.0), (0.0, 14.5)])
    world = World(w, "cross-corridor", path, np.array([[(-1, 7), (-1, 9)], [(1, 7), (1, 9)]]),
                  "a 2 m corridor crossed by another at y = 8")
    # Robot at 0.4 m/s from y = 1: at y = 3.8-4.8 while the person is in the corridor (|x| <
    # 1.2 at t in [7.3, 9.7]), the person 3.2-4.2 m ahead. It steps out of a side door at
    # x = 3.5 at t = 5 s and through another at x = -3.5 at t = 12 s, both out of the robot's
    # sight.
    person = DynamicObstacle.disc((3.5, 8.0), 0.2, "person", appear=5.0, vanish=12.0,
                                  shift=(-7.0, 0.0), t0=5.0, t1=12.0)
    return ChangingScene("person", world, Scene((person,)), path,
                         "a person (0.4 m disc) crosses the corridor at 1 m/s, 3.2-4.2 m ahead "
                         "of the robot")


def _door_scene() -> ChangingScene:
    # A room with a 1.2 m doorway at y = 6 into a second room; the robot drives at it head-on
    # from y = 0 and through it.
    w = _walls([(-4, -1.5, 4, -1.5), (-4, 10, 4, 10), (-4, -1.5, -4, 10), (4, -1.5, 4, 10),
                (-4, 6, -0.6, 6), (0.6, 6, 4, 6)])
    path = np.array([(0.0, 0.0), (0.0, 8.5)])
    world = World(w, "door", path, np.array([[(-0.6, 6), (0.6, 6)]]),
                  "a wall with a 1.2 m doorway, approached head-on and driven through")
    # Robot at y = 0.4 t: the door is shut for t in [3, 9) (robot 4.8 m to 2.4 m from it).
    door = DynamicObstacle.wall((-0.6, 6.0), (0.6, 6.0), "door", appear=3.0, vanish=9.0)
    return ChangingScene("door", world, Scene((door,)), path,
                         "a door shuts 4.8 m ahead of the approaching robot and opens again "
                         "when it is 2.4 m away")


def _box_scene() -> ChangingScene:
    # A 2.4 m corridor (x in [-1.2, 1.2], y in [0, 16]) with a side room on the right at
    # y = 11.4-12.6; a 0.5 m box against the left wall at y = 6-6.5.
    w = _walls([(-1.2, 0, 1.2, 0), (-1.2, 16, 1.2, 16), (-1.2, 0, -1.2, 16),
                (1.2, 0, 1.2, 11.4), (1.2, 12.6, 1.2, 16),
                (1.2, 9.9, 5.2, 9.9), (1.2, 14.1, 5.2, 14.1), (5.2, 9.9, 5.2, 14.1),
                (1.2, 9.9, 1.2, 11.4), (1.2, 12.6, 1.2, 14.1)])
    w = np.unique(w, axis=0)
    path = np.array([(0.3, 1.0), (0.3, 12.0), (3.6, 12.0), (0.3, 12.0), (0.3, 1.0)])
    world = World(w, "box-corridor", path, np.zeros((0, 2, 2)),
                  "a 2.4 m corridor with a side room near its end")
    # The robot is in the side room (out of sight of the box) from about t = 33 s to 47 s.
    box = DynamicObstacle.box(-1.2, 6.0, -0.7, 6.5, "box", vanish=40.0)
    return ChangingScene("box", world, Scene((box,)), path,
                         "a 0.5 m box against the wall, driven past, removed while the robot is "
                         "in a side room, driven past again")


#: Built-in changing scenes by name.
CHANGING_SCENES: dict[str, Callable[[], ChangingScene]] = {
    "box": _box_scene,
    "door": _door_scene,
    "person": _person_scene,
}


def changing_scene(name: str) -> ChangingScene:
    """A built-in changing scene by name (:data:`CHANGING_SCENES`: ``box``, ``door``,
    ``person``).

    Raises
    ------
    WorldError
        An unknown name.
    """
    try:
        make = CHANGING_SCENES[name]
    except KeyError:
        msg = f"unknown changing scene {name!r}; choose from {', '.join(sorted(CHANGING_SCENES))}"
        raise WorldError(msg) from None
    return make()
