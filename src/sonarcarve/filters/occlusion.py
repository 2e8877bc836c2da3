"""The occlusion filter (beyond the paper, off by default): drop points that lie more than
``occlusion_depth`` behind a surface of the map on the line from their own sensor (multipath
echoes mostly; :mod:`sonarcarve.geometry.occluded`); only points whose error bound is at most half
that depth make up the surfaces. It needs the sensor origin of every point, which a map does not
hold: :func:`point_origins` looks them up in the readings.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.filters.checks import FilterError, check_positive, rows_of_ids
from sonarcarve.geometry.occluded import occluded_points
from sonarcarve.maps import GlobalMap, LocalMap
from sonarcarve.readings import ReadingBatch
from sonarcarve.typing import BoolArray, FloatArray

__all__ = ["OCCLUSION_CROSSING", "OCCLUSION_DEPTH", "OCCLUSION_REACH", "SURFACE_NEIGHBOURS",
           "SURFACE_RADIUS", "occlusion_mask", "origins_array", "origins_by_id", "point_origins"]


#: The occlusion filter's depth when a user asks for it without one (``process
#: --occlusion-depth``'s suggestion), metres: the depth the carved grid's ``see_through`` clears
#: behind a surface, an obstacle's (box, person, chair), not a room's.
OCCLUSION_DEPTH = 0.5
#: How near the line from the sensor a surface point must lie to block it, metres.
OCCLUSION_REACH = 0.05
#: A point is part of a surface with at least :data:`SURFACE_NEIGHBOURS` other points within
#: :data:`SURFACE_RADIUS` metres lying along a line
#: (:func:`~sonarcarve.geometry.occluded.surface_directions`).
SURFACE_RADIUS = 0.3
SURFACE_NEIGHBOURS = 3
#: The least angle between that surface and the line it blocks: a line running along a
#: surface passes beside it (a 22.5° beam's half-width, 11°, plus slack), radians.
OCCLUSION_CROSSING = math.radians(20.0)


def occlusion_mask(xy: npt.ArrayLike, origin: npt.ArrayLike, max_error: npt.ArrayLike,
                   depth: float = OCCLUSION_DEPTH) -> BoolArray:
    """True where a point is *not* hidden: no surface of the map (a line of at least
    :data:`SURFACE_NEIGHBOURS` other points within :data:`SURFACE_RADIUS`) crosses the line
    from its sensor origin, at :data:`OCCLUSION_CROSSING` or more and within
    :data:`OCCLUSION_REACH` of it, more than ``depth`` metres in front of it
    (:func:`~sonarcarve.geometry.occluded.occluded_points`). Only points whose error bound is
    at most ``depth / 2`` hide others or make up surfaces: displaced by its whole bound, such a
    point still stands more than half the depth in front. (Without that, a dense map's
    misplaced points, the middles of uncut beams in a corridor, made up surfaces in free space:
    on 50,000 readings of ``benchmarks/synthetic.py``'s corridor loop combined carving lost 18 %
    of its true echoes to them; docs/RESULTS.md, *Points behind a surface of the map*.)

    Parameters
    ----------
    xy : array-like, shape (n, 2)
        The map's points, metres.
    origin : array-like, shape (n, 2)
        The sensor origin each point was heard from, metres.
    max_error : array-like, shape (n,)
        Each point's error bound, metres (the map's ``max_error``; NaN: it hides nothing).
    depth : float
        Metres behind the surface.

    Raises
    ------
    FilterError
        Arrays of different lengths, or a point or origin that is not finite.

    Examples
    --------
    A wall 1 m ahead of the sensor at the origin hides a point 2 m away, not one 0.5 m away:

    >>> wall = [[1.0, 0.1 * k - 0.5] for k in range(11)]
    >>> keep = occlusion_mask(wall + [[2.0, 0.0], [0.5, 0.0]], np.zeros((13, 2)),
    ...                       np.full(13, 0.01))
    >>> keep[-2:].tolist()
    [False, True]
    """
    check_positive("depth", depth)
    pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    src = np.asarray(origin, dtype=np.float64)
    if src.size == 0:
        src = src.reshape(0, 2)  # an empty list for an empty map
    bound = np.asarray(max_error, dtype=np.float64)
    if src.shape != pts.shape or bound.shape != (len(pts),):
        msg = (f"the occlusion filter needs an origin (n, 2) and an error bound (n,) for each of "
               f"the {len(pts)} points, got {src.shape} and {bound.shape}")
        raise FilterError(msg)
    if not (np.all(np.isfinite(pts)) and np.all(np.isfinite(src))):
        msg = "the occlusion filter needs finite points and origins"
        raise FilterError(msg)
    blocks = bound <= 0.5 * depth  # NaN: False
    return np.asarray(~occluded_points(pts, src, depth=depth, reach=OCCLUSION_REACH,
                                       radius=SURFACE_RADIUS, neighbours=SURFACE_NEIGHBOURS,
                                       crossing=OCCLUSION_CROSSING, blocks=blocks))


def point_origins(points: LocalMap | GlobalMap, readings: ReadingBatch,
                  reading_ids: npt.ArrayLike | None = None) -> FloatArray:
    """The sensor origin ``(x, y)`` of each point's reading, shape (n, 2): for the occlusion
    filter, which needs them and a map does not hold them.

    Parameters
    ----------
    points : LocalMap or GlobalMap
        The map.
    readings : ReadingBatch
        The readings the map was made from.
    reading_ids : array-like of int, optional
        The id of each of ``readings``, unique (default: its row, as
        :func:`~sonarcarve.pipeline.process_readings` numbers them).

    Raises
    ------
    FilterError
        A point whose reading id is not among the readings, or whose time or sensor is not its
        reading's: the map was not made from these readings.
    """
    ids = (np.arange(len(readings), dtype=np.int64) if reading_ids is None
           else np.asarray(reading_ids, dtype=np.int64))
    rows = rows_of_ids(points.reading_id, ids)
    # Times loosely: a tool that rewrote a file may have rounded them.
    same = ((np.abs(readings.t[rows] - points.t) <= 1e-6)
            & (readings.sensor[rows] == points.sensor))
    if not same.all():
        bad = int(np.argmin(same))
        msg = (f"map point {bad} (reading id {int(points.reading_id[bad])}) has another time or "
               "sensor than its reading: pass the readings the map was made from")
        raise FilterError(msg)
    return np.column_stack([readings.x[rows], readings.y[rows]])


def origins_by_id(point_ids: npt.ArrayLike, ids: npt.ArrayLike, x: npt.ArrayLike,
                  y: npt.ArrayLike) -> FloatArray:
    """:func:`point_origins` from arrays, without the time and sensor check: the ``(x[k],
    y[k])`` of the reading ``k`` whose id ``ids[k]`` (unique) is each of ``point_ids``, shape
    (n, 2).

    Raises
    ------
    FilterError
        An id of ``point_ids`` not in ``ids``, or ``ids`` not unique.
    """
    rows = rows_of_ids(point_ids, ids)
    return np.column_stack([np.asarray(x, dtype=np.float64)[rows],
                            np.asarray(y, dtype=np.float64)[rows]])


def origins_array(origins: npt.ArrayLike, total: int) -> FloatArray:
    """``origins`` as a (total, 2) float array, or a :class:`FilterError` naming the shape."""
    try:
        array = np.asarray(origins, dtype=np.float64)
    except ValueError as exc:  # ragged
        msg = f"origins must have shape ({total}, 2) for {total} points: {exc}"
        raise FilterError(msg) from None
    if total == 0 and array.size == 0:
        return array.reshape(0, 2)
    if array.shape != (total, 2):
        msg = f"origins must have shape ({total}, 2) for {total} points, got {array.shape}"
        raise FilterError(msg)
    return array

