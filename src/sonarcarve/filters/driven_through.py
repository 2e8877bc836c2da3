"""The driven-through filter (beyond the paper, off by default): drop points that the robot's
body covered at a later pose. Whatever made them was no static obstacle there: ghost walls of
late echoes (a far wall's echo of the previous firing, heard short), floor echoes, a person
who has since left. It needs the readings themselves, for the body's path.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sonarcarve.filters.checks import FilterError, check_positive
from sonarcarve.readings import ReadingBatch
from sonarcarve.typing import BoolArray, FloatArray, IntArray

__all__ = ["DISC_SIDES", "DRIVEN_MARGIN", "DRIVEN_MAX_GAP", "DRIVEN_STEP", "BodyFootprint",
           "driven_through_mask", "swept_poses"]

#: A pose counts as *later* than a point's reading only this many seconds after it: the
#: reading's own pose, and the poses of the same instant from the other sensors, never drop it.
DRIVEN_MARGIN = 0.25
#: Two consecutive poses of a track further apart in time than this, seconds, are not joined:
#: the log has a hole and the body's path through it is unknown.
DRIVEN_MAX_GAP = 2.0
#: Most distance between two poses of the swept path, metres (and half the body's reach for
#: a small body): with poses this close the footprints drawn at them overlap into the swept
#: strip, whose edges they miss by at most step² / (8 x radius): 1.5 mm for the Scout2's
#: body, 1.6 mm for a 0.05 m disc around a sensor.
DRIVEN_STEP = 0.05
#: Poses of the path paired with the map's points at once, and pairs tested against the
#: outline at once (each costs a row of the outline's corners): a robot that comes back to the
#: same place, a patrol or a long log, pairs each point with the poses of every visit, and all
#: pairs at once ran out of memory (45,000 points of a car circling a 3 m ring for 40 minutes).
_PATH_BLOCK = 256
_PAIR_BLOCK = 1 << 16
#: Sides of the regular polygon inscribed in a round body (inscribed: never larger than the
#: body; at 16 sides it loses at most 1.9 % of the radius).
DISC_SIDES = 16


@dataclass(frozen=True, eq=False)
class BodyFootprint:
    """The robot's footprint, for :func:`driven_through_mask`: a convex polygon in the frame
    of a reference point (x forward, y left, metres), and how to find that point from a
    reading's sensor pose.

    Attributes
    ----------
    outline : ndarray, shape (k, 2)
        The polygon's corners, counter-clockwise, in the reference frame.
    mount_x, mount_y, bearing : ndarray, shape (n,), or None
        Sensor mounts in the robot frame (as :class:`~sonarcarve.robot.RobotDescription`'s):
        the reference is the robot's centre, found from each reading's sensor pose. ``None``:
        the outline rides on every sensor's own origin (x along its axis), one track a sensor.

    Build one with :meth:`of_robot` or :meth:`around_sensors`.
    """

    outline: FloatArray
    mount_x: FloatArray | None = None
    mount_y: FloatArray | None = None
    bearing: FloatArray | None = None

    def __post_init__(self) -> None:
        # Built directly, an outline must be what the inside test assumes: a convex polygon,
        # counter-clockwise (a clockwise one would silently cover nothing).
        outline = np.asarray(self.outline, dtype=np.float64)
        if (outline.ndim != 2 or outline.shape[0] < 3 or outline.shape[1] != 2
                or not np.all(np.isfinite(outline))):
            msg = (f"a body outline needs at least three finite (x, y) corners, got shape "
                   f"{outline.shape}")
            raise FilterError(msg)
        edge = np.roll(outline, -1, axis=0) - outline
        after = np.roll(edge, -1, axis=0)
        turn = edge[:, 0] * after[:, 1] - edge[:, 1] * after[:, 0]  # left turns: positive
        if not np.all(turn > 0.0):
            msg = ("a body outline must be convex and run counter-clockwise (build one with "
                   "BodyFootprint.of_robot or BodyFootprint.around_sensors)")
            raise FilterError(msg)
        object.__setattr__(self, "outline", outline)

    @classmethod
    def of_robot(cls, mount_x: npt.ArrayLike, mount_y: npt.ArrayLike, bearing: npt.ArrayLike,
                 radius: float) -> BodyFootprint:
        """The body of a robot description: the convex hull of its round body (``radius``,
        ``robot_radius``) and its sensor mounts. Sensors sit on the body's surface, so for a
        convex body their hull lies inside it; for the car (a 0.9 m radius, half its width)
        the bumper and side sensors make the hull a 4.5 x 1.8 m box with cut corners, where the
        disc alone would miss both ends. A radius of 0 (a robot file may give one) leaves the
        sensors' hull alone.

        Raises
        ------
        FilterError
            A radius that is not a finite number >= 0, mounts of different lengths, or a body
            without area (radius 0 and fewer than three sensors off one line).
        """
        if (isinstance(radius, bool) or not isinstance(radius, numbers.Real)
                or not (math.isfinite(radius) and radius >= 0.0)):
            msg = (f"body radius must be a finite number >= 0 (metres; 0: the sensors' hull "
                   f"alone), got {radius!r}")
            raise FilterError(msg)
        mx, my, bear = (np.asarray(a, dtype=np.float64).reshape(-1)
                        for a in (mount_x, mount_y, bearing))
        if not mx.shape == my.shape == bear.shape or not np.all(np.isfinite(mx + my + bear)):
            msg = (f"sensor mounts need finite x, y and bearing for each sensor, got "
                   f"{mx.shape[0]}, {my.shape[0]} and {bear.shape[0]} values")
            raise FilterError(msg)
        mounts = np.column_stack([mx, my])
        hull = _convex_hull(mounts if radius == 0.0 else np.vstack([_disc_polygon(radius),
                                                                     mounts]))
        if hull.shape[0] < 3:  # the corners span no area
            msg = ("the body has no area: with a robot_radius of 0 it is the hull of the "
                   "sensor mounts, which needs three sensors off one line")
            raise FilterError(msg)
        return cls(outline=hull, mount_x=mx, mount_y=my, bearing=bear)

    @classmethod
    def around_sensors(cls, radius: float) -> BodyFootprint:
        """Without a robot description: a disc of ``radius`` around every sensor's origin.
        The transducer and its housing are solid, so whatever a sensor itself later passed
        through was no obstacle. A sensor sits on the body's rim, so the disc reaches
        ``radius`` beyond the body on the outside: keep it to the size of the sensor's mount
        (docs/RESULTS.md, *The body drove through it*, measured 0.05 and 0.1 m). It misses
        what only the body's middle passed over: ghost walls straight ahead of a single
        front sonar, whose path the sensor itself does sweep, are caught; a lane a car's
        middle drove down is not.

        Raises
        ------
        FilterError
            A radius that is not a finite number > 0.
        """
        check_positive("clearance radius", radius)
        return cls(outline=_disc_polygon(radius))

    @property
    def reach(self) -> float:
        """The farthest corner from the reference point, metres."""
        return float(np.max(np.hypot(self.outline[:, 0], self.outline[:, 1])))

    def tracks(self, t: FloatArray, sensor: IntArray, x: FloatArray, y: FloatArray,
               theta: FloatArray) -> list[FloatArray]:
        """The reference point's poses from the sensor poses of readings: a list of tracks,
        each shape (m, 4) (t, x, y, heading) in time order. One track, the robot's centre,
        with mounts; one a sensor without.

        Raises
        ------
        FilterError
            A sensor index without a mount.
        """
        if self.mount_x is None or self.mount_y is None or self.bearing is None:
            order = np.lexsort((t, sensor))  # by sensor, then time
            poses = np.column_stack([t, x, y, theta])[order]
            cuts = np.flatnonzero(np.diff(sensor[order])) + 1
            return list(np.split(poses, cuts))
        if sensor.size and int(sensor.max()) >= self.mount_x.shape[0]:
            msg = (f"reading of sensor {int(sensor.max())}, but the body has mounts for "
                   f"{self.mount_x.shape[0]} sensors only: is it the robot that made the log?")
            raise FilterError(msg)
        heading = theta - self.bearing[sensor]
        c, s = np.cos(heading), np.sin(heading)
        mx, my = self.mount_x[sensor], self.mount_y[sensor]
        centre_x, centre_y = x - (c * mx - s * my), y - (s * mx + c * my)
        order = np.argsort(t, kind="stable")
        return [np.column_stack([t, centre_x, centre_y, heading])[order]]


def _disc_polygon(radius: float) -> FloatArray:
    """A regular :data:`DISC_SIDES`-gon inscribed in a circle of ``radius``, counter-clockwise."""
    angle = np.arange(DISC_SIDES) * (2.0 * math.pi / DISC_SIDES)
    return np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])


def _convex_hull(corners: FloatArray) -> FloatArray:
    """The convex hull of ``corners`` (shape (k, 2)), counter-clockwise, without corners on
    its edges; shape (0, 2) when they span no area."""
    from scipy.spatial import ConvexHull, QhullError  # only when a body is built

    try:
        hull = ConvexHull(corners)
    except QhullError:  # fewer than three corners off one line
        return np.zeros((0, 2))
    return np.asarray(corners[hull.vertices])  # counter-clockwise in 2-D


def swept_poses(track: FloatArray, step: float, reach: float = 0.0,
                max_gap: float = DRIVEN_MAX_GAP) -> FloatArray:
    """``track`` (shape (m, 4): t, x, y, heading) with poses added between consecutive ones,
    so that neither the reference point nor a corner ``reach`` metres from it moves more than
    ``step`` metres from one pose to the next: a fast robot (or a sparse log) skips past a
    point between two readings, and the segment between them is what the body swept. Time,
    position and heading (the short way round) are interpolated linearly. Two poses more than
    ``max_gap`` seconds apart are not joined.

    Returns
    -------
    ndarray, shape (m', 4)
        The poses in time order, the original ones among them.

    Examples
    --------
    >>> swept_poses(np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 1.0, 0.0, 0.0]]), 0.25)[:, 1].tolist()
    [0.0, 0.25, 0.5, 0.75, 1.0]
    """
    if track.shape[0] < 2:
        return track
    start, end = track[:-1], track[1:]
    turn = np.angle(np.exp(1j * (end[:, 3] - start[:, 3])))  # wrapped to [-pi, pi]
    moved = np.hypot(end[:, 1] - start[:, 1], end[:, 2] - start[:, 2])
    # A corner moves by the translation plus its arc of the turn (they add where they point
    # the same way): the larger alone let it move up to twice ``step`` a piece.
    pieces = np.maximum(np.ceil((moved + np.abs(turn) * reach) / step), 1)
    pieces = np.where(end[:, 0] - start[:, 0] > max_gap, 1, pieces).astype(np.int64)
    segment = np.repeat(np.arange(start.shape[0]), pieces)
    # Each added pose's fraction of the way along its segment: 0, 1/k, ..., (k-1)/k.
    first = np.repeat(np.cumsum(pieces) - pieces, pieces)
    fraction = (np.arange(segment.shape[0]) - first) / pieces[segment]
    delta = end[segment] - start[segment]
    delta[:, 3] = turn[segment]
    # A gap not joined keeps fraction 0: its start pose only, no made-up path.
    return np.vstack([start[segment] + fraction[:, None] * delta, track[-1:]])


def driven_through_mask(xy: npt.ArrayLike, t: npt.ArrayLike, poses: ReadingBatch,
                        body: BodyFootprint, margin: float = DRIVEN_MARGIN) -> BoolArray:
    """True where the robot's body covered a point at some pose more than ``margin`` seconds
    after the point's reading: the point cannot be a static obstacle (a ghost wall of late
    echoes in front of a real wall, a floor echo, a person who has since left).

    The body's path is known from the readings' sensor poses: with mounts
    (:meth:`BodyFootprint.of_robot`) the robot's centre and heading are recovered from each
    reading; without (:meth:`BodyFootprint.around_sensors`) every sensor's own origin carries
    a small disc. Consecutive poses of the path are joined (:func:`swept_poses`), so the
    body's whole sweep counts, not only where a reading was taken. The point tested is the
    map's placed point, never the reading's axis: a wide beam's axis may well run down the
    lane the robot then drives (docs/RESULTS.md, *The body drove through it*).

    Why these choices: the footprint errs small (an inscribed polygon; the sensors' hull, which
    lies inside a convex body), since a wall dropped is worse than a ghost kept. Only poses
    more than ``margin`` after the reading count, so the reading's own pose and its cycle's
    never do. The test trusts the poses: a revisit under odometry drift puts the body where
    the old map is wrong, and can drop a real wall there.

    Parameters
    ----------
    xy : array-like, shape (n, 2)
        The map's points, metres.
    t : array-like, shape (n,)
        The time of each point's reading, seconds.
    poses : ReadingBatch
        The readings of the whole log (their ranges unused), which give the path.
    body : BodyFootprint
        The footprint and how to find it from a sensor pose.
    margin : float
        Seconds after a point's reading before a pose counts.

    Raises
    ------
    FilterError
        ``poses`` that are no ReadingBatch, arrays of different lengths, points or times that
        are not finite, a ``margin`` that is no finite number >= 0, or a sensor the body has no
        mount for.

    Examples
    --------
    A disc of 0.2 m around the one sensor, driven from x = 0 to x = 2 m in 2 s: a point at
    x = 1 m heard at t = 0 is driven through, the same point heard at t = 1.9 s is not (the
    sensor has passed), nor is one 0.3 m off the path:

    >>> drive = ReadingBatch.from_arrays(t=[0.0, 2.0], sensor=[0, 0], x=[0.0, 2.0], y=[0.0, 0.0],
    ...                                  theta=[0.0, 0.0], range=[1.0, 1.0])
    >>> body = BodyFootprint.around_sensors(0.2)
    >>> driven_through_mask([[1.0, 0.0], [1.0, 0.0], [1.0, 0.3]], [0.0, 1.9, 0.0], drive,
    ...                     body).tolist()
    [True, False, False]
    """
    if not isinstance(poses, ReadingBatch):
        msg = f"poses must be a ReadingBatch (the map's log), got {type(poses).__name__}"
        raise FilterError(msg)
    pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    heard = np.asarray(t, dtype=np.float64).reshape(-1)
    if (heard.shape != (pts.shape[0],) or not np.all(np.isfinite(pts))
            or not np.all(np.isfinite(heard))):
        msg = (f"the driven-through filter needs a finite point and a time for each point, got "
               f"{pts.shape[0]} points and {heard.shape[0]} times")
        raise FilterError(msg)
    # NaN would make no pose later (nothing dropped, silently), a negative margin would let
    # the reading's own pose drop its point.
    if (isinstance(margin, bool) or not isinstance(margin, numbers.Real)
            or not (math.isfinite(margin) and margin >= 0.0)):
        msg = f"margin must be a finite number >= 0 (seconds), got {margin!r}"
        raise FilterError(msg)
    covered = np.zeros(pts.shape[0], dtype=bool)
    if pts.shape[0] == 0 or len(poses) == 0:
        return covered
    reach = body.reach
    step = min(DRIVEN_STEP, 0.5 * reach)
    tracks = body.tracks(poses.t, poses.sensor, poses.x, poses.y, poses.theta)
    path = np.vstack([swept_poses(_thinned(track, step, reach, margin), step, reach)
                      for track in tracks])
    return _covered(pts, heard, path, body.outline, reach, margin)


def _covered(pts: FloatArray, heard: FloatArray, path: FloatArray, outline: FloatArray,
             reach: float, margin: float) -> BoolArray:
    """:func:`driven_through_mask` on checked arrays: the path a block of
    :data:`_PATH_BLOCK` poses at a time, the points a block already covered left out after."""
    from scipy.spatial import cKDTree  # scipy.spatial costs 0.4 s to import: only when used

    covered = np.zeros(pts.shape[0], dtype=bool)
    points = cKDTree(pts)
    for first in range(0, path.shape[0], _PATH_BLOCK):
        block = path[first:first + _PATH_BLOCK]
        pairs = cKDTree(block[:, 1:3]).sparse_distance_matrix(points, reach,
                                                              output_type="ndarray")
        pose, point = pairs["i"], pairs["j"]
        open_later = ~covered[point] & (block[pose, 0] > heard[point] + margin)
        pose, point = pose[open_later], point[open_later]
        for at in range(0, point.shape[0], _PAIR_BLOCK):
            near, where = point[at:at + _PAIR_BLOCK], pose[at:at + _PAIR_BLOCK]
            covered[near[_inside_outline(pts[near], block[where], outline)]] = True
    return covered


def _thinned(track: FloatArray, step: float, reach: float, margin: float) -> FloatArray:
    """``track`` without the poses that moved it less than half a ``step`` (a corner
    ``reach`` out included) and less than ``margin`` seconds on: a fast ring or a slow robot
    logs many poses a centimetre apart, and the cost grows with the poses near each point. The
    first and last pose, and both ends of a gap longer than :data:`DRIVEN_MAX_GAP`, stay."""
    if track.shape[0] < 3:
        return track
    turn = np.abs(np.angle(np.exp(1j * np.diff(track[:, 3]))))
    travel = np.concatenate(([0.0], np.cumsum(np.hypot(np.diff(track[:, 1]),
                                                       np.diff(track[:, 2])) + reach * turn)))
    place = np.floor(travel / (0.5 * step))
    clock = np.floor((track[:, 0] - track[0, 0]) / max(margin, 1e-9))
    gap = np.diff(track[:, 0]) > DRIVEN_MAX_GAP
    keep = np.ones(track.shape[0], dtype=bool)
    keep[1:] = (place[1:] != place[:-1]) | (clock[1:] != clock[:-1]) | gap
    keep[:-1] |= gap
    keep[-1] = True
    return track[keep]


def _inside_outline(q: FloatArray, pose: FloatArray, outline: FloatArray) -> BoolArray:
    """True where world point ``q[i]`` lies inside the convex ``outline`` (counter-clockwise)
    placed at ``pose[i]`` (t, x, y, heading): left of (or on) every edge in the body frame."""
    c, s = np.cos(pose[:, 3]), np.sin(pose[:, 3])
    dx, dy = q[:, 0] - pose[:, 1], q[:, 1] - pose[:, 2]
    bx, by = c * dx + s * dy, -s * dx + c * dy  # world -> body frame
    edge = np.roll(outline, -1, axis=0) - outline
    left = (edge[:, 0] * (by[:, None] - outline[:, 1])
            - edge[:, 1] * (bx[:, None] - outline[:, 0]))
    return np.asarray(np.all(left >= 0.0, axis=1))
