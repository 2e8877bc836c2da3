"""Reading filters and map filters (paper, Appendix B and Fig. 13b).

Reading filters drop sonar readings before they reach a method:

- **maximum range**: echoes farther than ``max_range`` (the paper uses 150 inches, 3.81 m, on
  its Scout2, whose sensors sit 10.25 inches above the floor: see :data:`PAPER_MAX_RANGE`);
- **minimum range**: echoes nearer than ``min_range`` (ringing, the robot's own body);
- **jump filter**: a sensor whose range changes by more than ``jump_threshold`` between two of
  its successive readings is ignored for one cycle. Here a *cycle* is precisely *that sensor's
  next reading*: the reading that jumped is dropped. The comparison is always with the same
  sensor's previous reading that passed the range filters, whether the jump filter kept it or
  not, so a lasting change (a new wall comes into view) costs exactly one reading and an isolated
  spike (cross-talk, a floor bounce) costs two: the spike and the reading after it, which jumps
  back. A sensor's first reading is always kept.

A no-echo reading (``range`` inf: the sensor heard nothing up to its ``max_range``) is no echo
that any of them judges: every reading filter keeps it, and the jump filter compares a sensor's
echoes across it.

Each reading is dropped by the first filter, in that order, that rejects it, and counted under
it. The batch form (:func:`filter_readings`) and the streaming form
(:class:`ReadingFilterStream`, one reading at a time) make the same decisions. Dropping readings
must not renumber them: :class:`FilteredReadings` keeps the input row of every kept reading so
that the ids in a map still point at the input file.

Map filters drop points from a :class:`~sonarcarve.maps.LocalMap` or
:class:`~sonarcarve.maps.GlobalMap`: maximum-error thresholding (Fig. 13b: points whose
``max_error`` bound, eq. 5.3, exceeds a threshold) and then the outlier test (a point needs at
least ``k`` other points within radius ``R``). Thresholding runs first so that inaccurate points
do not vouch for their neighbours. Between the two, beyond the paper, the **occlusion** filter
drops points that lie more than ``occlusion_depth`` behind a surface of the map on the line
from their own sensor (multipath echoes mostly; :mod:`sonarcarve.geometry.occluded`); only points
whose error bound is at most half that depth make up the surfaces. It needs the sensor origin of
every point, which a map does not hold, so :func:`filter_map` takes them (:func:`point_origins`
looks them up in the readings). Before it, also beyond the paper and also off by default, the
**driven-through** filter drops points that the robot's body covered at a later pose
(:func:`driven_through_mask`, :class:`BodyFootprint`): ghost walls of late echoes, floor
echoes, whatever has moved away. It needs the readings themselves, for the body's path.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from enum import IntEnum
from typing import Generic, TypeVar

import numpy as np
import numpy.typing as npt

from sonarcarve.constants import INCH
from sonarcarve.errors import SonarcarveError
from sonarcarve.geometry.occluded import occluded_points
from sonarcarve.maps import GlobalMap, LocalMap
from sonarcarve.readings import Reading, ReadingBatch
from sonarcarve.typing import BoolArray, FloatArray, IntArray

__all__ = [
    "DISC_SIDES",
    "DRIVEN_MARGIN",
    "DRIVEN_MAX_GAP",
    "DRIVEN_STEP",
    "OCCLUSION_CROSSING",
    "OCCLUSION_DEPTH",
    "OCCLUSION_REACH",
    "PAPER_MAX_RANGE",
    "SURFACE_NEIGHBOURS",
    "SURFACE_RADIUS",
    "BodyFootprint",
    "DropReason",
    "FilterError",
    "FilteredMap",
    "FilteredReadings",
    "MapFilter",
    "MapFilterReport",
    "ReadingFilter",
    "ReadingFilterReport",
    "ReadingFilterStream",
    "confidence_mask",
    "driven_through_mask",
    "filter_map",
    "filter_readings",
    "max_error_mask",
    "occlusion_mask",
    "origins_by_id",
    "outlier_mask",
    "point_origins",
    "swept_poses",
]

#: The paper's maximum range (Appendix B): 150 inches, in metres. Specific to the Scout2's
#: sensors and mounting height; not a default anywhere.
PAPER_MAX_RANGE = 150 * INCH

_M = TypeVar("_M", LocalMap, GlobalMap)


class FilterError(SonarcarveError, ValueError):
    """A filter parameter outside its valid range."""


class DropReason(IntEnum):
    """Why a reading filter dropped a reading (``KEPT`` if it did not)."""

    KEPT = 0
    TOO_FAR = 1  #: an echo's range > max_range (a no-echo reading never is)
    TOO_NEAR = 2  #: range < min_range
    JUMP = 3  #: range jumped by more than jump_threshold since the sensor's previous reading


def _check_positive(name: str, value: float | None) -> None:
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        msg = f"{name} must be a finite number > 0 (metres), got {type(value).__name__} {value!r}"
        raise FilterError(msg)
    if not (math.isfinite(value) and value > 0.0):
        msg = f"{name} must be a finite number > 0 (metres), got {value}"
        raise FilterError(msg)


@dataclass(frozen=True)
class ReadingFilter:
    """Which reading filters to apply; ``None`` switches a filter off.

    Attributes
    ----------
    max_range : float or None
        Drop echoes with range > ``max_range``, metres (paper: :data:`PAPER_MAX_RANGE`). A
        no-echo reading is kept with its own ``max_range``, even a longer one: the filter is
        for long echoes, which are the likelier crosstalk and multipath, and a silence is
        none of those (a decision; clipping its free space to this value would be the
        other).
    min_range : float or None
        Drop readings with range < ``min_range``, metres.
    jump_threshold : float or None
        Drop a reading whose range differs from its sensor's previous (range-filtered) reading
        by more than this, metres.

    Raises
    ------
    FilterError
        A value that is not a finite positive number, or ``min_range > max_range``.
    """

    max_range: float | None = None
    min_range: float | None = None
    jump_threshold: float | None = None

    def __post_init__(self) -> None:
        _check_positive("max_range", self.max_range)
        _check_positive("min_range", self.min_range)
        _check_positive("jump_threshold", self.jump_threshold)
        if (self.max_range is not None and self.min_range is not None
                and self.min_range > self.max_range):
            msg = f"min_range ({self.min_range}) exceeds max_range ({self.max_range})"
            raise FilterError(msg)

    @property
    def active(self) -> bool:
        """True if at least one filter is on."""
        return any(v is not None for v in (self.max_range, self.min_range, self.jump_threshold))


@dataclass(frozen=True)
class ReadingFilterReport:
    """How many readings each reading filter dropped.

    Attributes
    ----------
    total : int
        Readings in.
    too_far, too_near, jumps : int
        Readings dropped by the maximum-range, minimum-range and jump filters.
    """

    total: int
    too_far: int = 0
    too_near: int = 0
    jumps: int = 0

    @property
    def kept(self) -> int:
        """Readings out."""
        return self.total - self.too_far - self.too_near - self.jumps

    @classmethod
    def from_reasons(cls, reasons: npt.NDArray[np.int8]) -> ReadingFilterReport:
        """Counts from an array of :class:`DropReason` codes."""
        counts = np.bincount(reasons.astype(np.int64), minlength=len(DropReason))
        return cls(total=int(reasons.shape[0]), too_far=int(counts[DropReason.TOO_FAR]),
                   too_near=int(counts[DropReason.TOO_NEAR]), jumps=int(counts[DropReason.JUMP]))


@dataclass(frozen=True, eq=False)
class FilteredReadings:
    """The result of :func:`filter_readings`.

    Attributes
    ----------
    batch : ReadingBatch
        The kept readings, in input order.
    ids : ndarray of int64, shape (len(batch),)
        Input row (0-based) of each kept reading: feed these as reading ids so that map ids
        still point at the input.
    reasons : ndarray of int8, shape (n_in,)
        :class:`DropReason` code of every input reading.
    report : ReadingFilterReport
        Counts per filter.
    """

    batch: ReadingBatch
    ids: IntArray
    reasons: npt.NDArray[np.int8]
    report: ReadingFilterReport


def _range_reasons(r: FloatArray, spec: ReadingFilter) -> npt.NDArray[np.int8]:
    reasons = np.zeros(r.shape[0], dtype=np.int8)
    if spec.min_range is not None:
        reasons[r < spec.min_range] = DropReason.TOO_NEAR
    if spec.max_range is not None:  # a no-echo reading (inf) is free space, not a far echo
        reasons[(r > spec.max_range) & np.isfinite(r)] = DropReason.TOO_FAR
    return reasons


def filter_readings(batch: ReadingBatch, spec: ReadingFilter) -> FilteredReadings:
    """Apply the reading filters of ``spec`` to a whole log (vectorised).

    Parameters
    ----------
    batch : ReadingBatch
        The log in stream order; row ``i`` is reading id ``i``.
    spec : ReadingFilter
        Which filters, with which thresholds.

    Returns
    -------
    FilteredReadings
        Kept readings, their input rows, and per-filter counts.

    Examples
    --------
    >>> from sonarcarve.readings import ReadingBatch
    >>> b = ReadingBatch.from_arrays(t=[0, 1, 2, 3], sensor=[0, 0, 0, 0], x=[0] * 4, y=[0] * 4,
    ...                              theta=[0] * 4, range=[1.0, 1.1, 3.0, 3.0])
    >>> out = filter_readings(b, ReadingFilter(jump_threshold=0.5))
    >>> out.ids.tolist(), out.report.jumps  # 3.0 jumped; the second 3.0 agrees with it
    ([0, 1, 3], 1)
    """
    reasons = _range_reasons(batch.range, spec)
    if spec.jump_threshold is not None:  # among echoes only: a silence is no range to jump
        passed = np.flatnonzero((reasons == DropReason.KEPT) & np.isfinite(batch.range))
        sensors = batch.sensor[passed]
        # Stable sort by sensor keeps each sensor's readings in stream order, so a difference
        # between neighbours of one sensor's run is the change since its previous reading.
        order = np.argsort(sensors, kind="stable")
        r = batch.range[passed][order]
        same_sensor = np.concatenate(([False], sensors[order][1:] == sensors[order][:-1]))
        jumped = same_sensor & (np.abs(np.diff(r, prepend=0.0)) > spec.jump_threshold)
        reasons[passed[order[jumped]]] = DropReason.JUMP
    keep = np.flatnonzero(reasons == DropReason.KEPT).astype(np.int64)
    return FilteredReadings(batch=batch[keep], ids=keep, reasons=reasons,
                            report=ReadingFilterReport.from_reasons(reasons))


class ReadingFilterStream:
    """The reading filters of ``spec`` applied one reading at a time (same decisions as
    :func:`filter_readings`).

    Examples
    --------
    >>> from sonarcarve.readings import Reading
    >>> stream = ReadingFilterStream(ReadingFilter(max_range=3.81))
    >>> stream.check(Reading(0.0, 0, 0.0, 0.0, 0.0, 5.0)).name
    'TOO_FAR'
    >>> stream.report.too_far
    1
    """

    def __init__(self, spec: ReadingFilter) -> None:
        self.spec = spec
        self._previous: dict[int, float] = {}  # sensor -> its previous range-filtered range
        self._counts = np.zeros(len(DropReason), dtype=np.int64)

    def check(self, reading: Reading) -> DropReason:
        """Decide on the next reading of the stream (and remember it for the jump filter)."""
        spec = self.spec
        reason = DropReason.KEPT
        if reading.no_echo:  # free space up to its own max_range: no echo to judge
            self._counts[reason] += 1
            return reason
        if spec.max_range is not None and reading.range > spec.max_range:
            reason = DropReason.TOO_FAR
        elif spec.min_range is not None and reading.range < spec.min_range:
            reason = DropReason.TOO_NEAR
        else:
            previous = self._previous.get(reading.sensor)
            self._previous[reading.sensor] = reading.range
            if (spec.jump_threshold is not None and previous is not None
                    and abs(reading.range - previous) > spec.jump_threshold):
                reason = DropReason.JUMP
        self._counts[reason] += 1
        return reason

    def accept(self, reading: Reading) -> bool:
        """True if the next reading of the stream is kept."""
        return self.check(reading) is DropReason.KEPT

    @property
    def report(self) -> ReadingFilterReport:
        """Counts since the start of the stream."""
        c = self._counts
        return ReadingFilterReport(total=int(c.sum()), too_far=int(c[DropReason.TOO_FAR]),
                                   too_near=int(c[DropReason.TOO_NEAR]),
                                   jumps=int(c[DropReason.JUMP]))


# -- map filters --------------------------------------------------------------------------------


@dataclass(frozen=True)
class MapFilter:
    """Which map filters to apply; ``None`` switches a filter off.

    Attributes
    ----------
    max_error : float or None
        Drop points whose ``max_error`` (eq. 5.3) exceeds this, metres (Fig. 13b).
    outlier_radius : float or None
        Radius R of the outlier test, metres.
    outlier_neighbours : int
        k: a point is kept only with at least k *other* points within R (distance <= R).
    min_confidence : float or None
        Drop points whose ``confidence`` (probability of a real surface, section 6) is below
        this, in [0, 1]; points without one (NaN: the paper's methods) are kept.
    occlusion_depth : float or None
        Drop points lying more than this far behind a surface of the map, metres, on the line
        from the sensor that heard them (:func:`occlusion_mask`; 0.5 m is
        :data:`OCCLUSION_DEPTH`). Only points whose error bound is at most half of it make up
        surfaces, so a small depth blocks little. Needs the points' sensor origins
        (:func:`filter_map`). Not for centerline maps (docs/RESULTS.md, *Points behind a
        surface of the map*).
    driven_through : BodyFootprint or None
        Drop points that this body covered at a later pose (:func:`driven_through_mask`): not
        static obstacles, whatever made them (late echoes forming a ghost wall in front of a
        real one, floor echoes, a person who has since left). Needs the readings' poses
        (:func:`filter_map`). It judges after the fact, so the map is the *current* one: a
        door that stood shut and that the robot later drove through is dropped too.

    Raises
    ------
    FilterError
        A radius or threshold that is not a finite positive number, k < 1, or a
        ``driven_through`` that is not a :class:`BodyFootprint`.
    """

    max_error: float | None = None
    outlier_radius: float | None = None
    outlier_neighbours: int = 1
    min_confidence: float | None = None
    occlusion_depth: float | None = None
    driven_through: BodyFootprint | None = None

    def __post_init__(self) -> None:
        _check_positive("max_error", self.max_error)
        if self.driven_through is not None and not isinstance(self.driven_through,
                                                              BodyFootprint):
            msg = (f"driven_through must be a BodyFootprint (BodyFootprint.of_robot or "
                   f"BodyFootprint.around_sensors), got {type(self.driven_through).__name__}")
            raise FilterError(msg)
        _check_positive("occlusion_depth", self.occlusion_depth)
        if self.min_confidence is not None and not 0.0 <= self.min_confidence <= 1.0:
            msg = f"min_confidence must lie in [0, 1], got {self.min_confidence!r}"
            raise FilterError(msg)
        _check_positive("outlier_radius", self.outlier_radius)
        if self.outlier_neighbours < 1:
            msg = f"outlier_neighbours must be at least 1, got {self.outlier_neighbours}"
            raise FilterError(msg)

    @property
    def active(self) -> bool:
        """True if at least one filter is on."""
        return (self.max_error is not None or self.outlier_radius is not None
                or self.min_confidence is not None or self.occlusion_depth is not None
                or self.driven_through is not None)


@dataclass(frozen=True)
class MapFilterReport:
    """How many points each map filter dropped (``total`` points in)."""

    total: int
    max_error: int = 0
    outliers: int = 0
    confidence: int = 0
    occluded: int = 0
    driven_through: int = 0

    @property
    def kept(self) -> int:
        """Points out."""
        return (self.total - self.max_error - self.outliers - self.confidence - self.occluded
                - self.driven_through)


@dataclass(frozen=True, eq=False)
class FilteredMap(Generic[_M]):
    """The result of :func:`filter_map`: the kept points and the counts."""

    points: _M
    report: MapFilterReport


def max_error_mask(max_error: npt.ArrayLike, threshold: float) -> BoolArray:
    """True where a point's error bound is at most ``threshold`` metres (Fig. 13b).

    Examples
    --------
    >>> max_error_mask([0.1, 0.3, np.nan], 0.2).tolist()
    [True, False, False]
    """
    return np.asarray(np.asarray(max_error, dtype=np.float64) <= threshold)


def outlier_mask(xy: npt.ArrayLike, radius: float, neighbours: int) -> BoolArray:
    """True where a point has at least ``neighbours`` other points within ``radius``.

    Parameters
    ----------
    xy : array-like, shape (n, 2)
        Points, metres.
    radius : float
        R, metres; a point at distance exactly R counts.
    neighbours : int
        k, the number of other points required.

    Examples
    --------
    >>> outlier_mask([[0, 0], [0.1, 0], [5, 5]], radius=0.2, neighbours=1).tolist()
    [True, True, False]
    """
    pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    if pts.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    from scipy.spatial import cKDTree  # scipy.spatial costs 0.4 s to import: only when used

    counts = cKDTree(pts).query_ball_point(pts, r=radius, return_length=True)
    return np.asarray(counts - 1 >= neighbours)  # the point itself is in its own ball


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
    _check_positive("depth", depth)
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
    rows = _rows_of(points.reading_id, ids)
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
    rows = _rows_of(point_ids, ids)
    return np.column_stack([np.asarray(x, dtype=np.float64)[rows],
                            np.asarray(y, dtype=np.float64)[rows]])


def _rows_of(point_ids: npt.ArrayLike, ids: npt.ArrayLike) -> IntArray:
    """The position in ``ids`` of each of ``point_ids`` (:func:`origins_by_id`'s errors)."""
    wanted = np.asarray(point_ids, dtype=np.int64)
    known = np.asarray(ids, dtype=np.int64)
    order = np.argsort(known, kind="stable")
    sorted_ids = known[order]
    if np.any(sorted_ids[1:] == sorted_ids[:-1]):
        msg = "reading ids must be unique to look up a point's reading"
        raise FilterError(msg)
    at = np.searchsorted(sorted_ids, wanted)
    found = at < len(known)
    found[found] = sorted_ids[at[found]] == wanted[found]
    if not found.all():
        msg = (f"map point of reading id {int(wanted[~found][0])} has no reading among the "
               f"{len(known):,} given: pass the readings the map was made from")
        raise FilterError(msg)
    return np.asarray(order[at])


def _origins_array(origins: npt.ArrayLike, total: int) -> FloatArray:
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


def confidence_mask(confidence: npt.ArrayLike, threshold: float) -> BoolArray:
    """True where a point's confidence is at least ``threshold`` or unknown (NaN).

    Examples
    --------
    >>> confidence_mask([0.9, 0.3, np.nan], 0.5).tolist()
    [True, False, True]
    """
    c = np.asarray(confidence, dtype=np.float64)
    return np.asarray(np.isnan(c) | (c >= threshold))


def filter_map(points: _M, spec: MapFilter, origins: npt.ArrayLike | None = None,
               poses: ReadingBatch | None = None) -> FilteredMap[_M]:
    """Apply the map filters of ``spec``: confidence, max-error thresholding, driven through,
    occlusion, then the outlier test.

    Parameters
    ----------
    points : LocalMap or GlobalMap
        The map to filter.
    spec : MapFilter
        Which filters, with which thresholds.
    origins : array-like, shape (n, 2), optional
        The sensor origin of each point (:func:`point_origins`); needed by the occlusion filter.
    poses : ReadingBatch, optional
        The readings of the whole log, for their sensor poses (the body's path); needed by the
        driven-through filter.

    Returns
    -------
    FilteredMap
        The kept points (same type as ``points``) and how many each filter dropped.

    Raises
    ------
    FilterError
        The occlusion filter without ``origins``, ``origins`` of the wrong shape, or the
        driven-through filter without ``poses``.
    """
    total = len(points)
    if spec.occlusion_depth is not None and origins is None:
        msg = ("the occlusion filter needs each point's sensor origin: pass "
               "origins=point_origins(points, readings)")
        raise FilterError(msg)
    if spec.driven_through is not None and poses is None:
        msg = "the driven-through filter needs the body's path: pass poses=the map's readings"
        raise FilterError(msg)
    origin = None if origins is None else _origins_array(origins, total)
    dropped = {"confidence": 0, "max_error": 0, "driven_through": 0, "occluded": 0,
               "outliers": 0}

    def drop(name: str, keep: BoolArray) -> None:
        nonlocal points, origin
        dropped[name] = len(points) - int(keep.sum())
        points = points.select(keep)
        origin = None if origin is None else origin[keep]

    if spec.min_confidence is not None:
        drop("confidence", confidence_mask(points.confidence, spec.min_confidence))
    if spec.max_error is not None:
        drop("max_error", max_error_mask(points.max_error, spec.max_error))
    if spec.driven_through is not None:
        # Before the occlusion filter, so that a ghost wall hides nothing behind it, and
        # before the outlier test, so that it vouches for no neighbour.
        assert poses is not None  # checked above
        drop("driven_through", ~driven_through_mask(points.xy, points.t, poses,
                                                     spec.driven_through))
    if spec.occlusion_depth is not None:
        # After the confidence and error filters, so that only points the map keeps hide
        # others; before the outlier test, so that a hidden point vouches for no neighbour.
        assert origin is not None  # checked above
        drop("occluded", occlusion_mask(points.xy, origin, points.max_error,
                                        spec.occlusion_depth))
    if spec.outlier_radius is not None:
        drop("outliers", outlier_mask(points.xy, spec.outlier_radius, spec.outlier_neighbours))
    return FilteredMap(points=points, report=MapFilterReport(total=total, **dropped))


# -- the body drove through it ------------------------------------------------------------------

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

    @classmethod
    def of_robot(cls, mount_x: npt.ArrayLike, mount_y: npt.ArrayLike, bearing: npt.ArrayLike,
                 radius: float) -> BodyFootprint:
        """The body of a robot description: the convex hull of its round body (``radius``,
        ``robot_radius``) and its sensor mounts. Sensors sit on the body's surface, so for a
        convex body their hull lies inside it; for the car (a 0.9 m radius, half its width)
        the bumper and side sensors make the hull a 4.5 x 1.8 m box with cut corners, where the
        disc alone would miss both ends.

        Raises
        ------
        FilterError
            A radius that is not a finite number > 0, or mounts of different lengths.
        """
        _check_positive("body radius", radius)
        mx, my, bear = (np.asarray(a, dtype=np.float64).reshape(-1)
                        for a in (mount_x, mount_y, bearing))
        if not mx.shape == my.shape == bear.shape or not np.all(np.isfinite(mx + my + bear)):
            msg = (f"sensor mounts need finite x, y and bearing for each sensor, got "
                   f"{mx.shape[0]}, {my.shape[0]} and {bear.shape[0]} values")
            raise FilterError(msg)
        corners = np.vstack([_disc_polygon(radius), np.column_stack([mx, my])])
        return cls(outline=_convex_hull(corners), mount_x=mx, mount_y=my, bearing=bear)

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
        _check_positive("clearance radius", radius)
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
    """The convex hull of ``corners`` (shape (k, 2)), counter-clockwise (monotone chain)."""
    pts = np.unique(corners, axis=0)  # sorted by x, then y

    def half(points: FloatArray) -> list[FloatArray]:
        chain: list[FloatArray] = []
        for p in points:
            while len(chain) >= 2 and _cross(chain[-2], chain[-1], p) <= 0.0:
                chain.pop()
            chain.append(p)
        return chain[:-1]

    return np.array(half(pts) + half(pts[::-1]))


def _cross(o: FloatArray, a: FloatArray, b: FloatArray) -> float:
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


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
    pieces = np.maximum(np.ceil(np.maximum(moved, np.abs(turn) * reach) / step), 1)
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
        Arrays of different lengths, points that are not finite, or a sensor the body has no
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
    pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    heard = np.asarray(t, dtype=np.float64).reshape(-1)
    if heard.shape != (pts.shape[0],) or not np.all(np.isfinite(pts)):
        msg = (f"the driven-through filter needs a finite point and a time for each point, got "
               f"{pts.shape[0]} points and {heard.shape[0]} times")
        raise FilterError(msg)
    covered = np.zeros(pts.shape[0], dtype=bool)
    if pts.shape[0] == 0 or len(poses) == 0:
        return covered
    reach = body.reach
    step = min(DRIVEN_STEP, 0.5 * reach)
    tracks = body.tracks(poses.t, poses.sensor, poses.x, poses.y, poses.theta)
    path = np.vstack([swept_poses(_thinned(track, step, reach, margin), step, reach)
                      for track in tracks])
    from scipy.spatial import cKDTree  # scipy.spatial costs 0.4 s to import: only when used

    pairs = cKDTree(pts).sparse_distance_matrix(cKDTree(path[:, 1:3]), reach,
                                                output_type="ndarray")
    point, pose = pairs["i"], pairs["j"]
    later = path[pose, 0] > heard[point] + margin
    point, pose = point[later], pose[later]
    inside = _inside_outline(pts[point], path[pose], body.outline)
    covered[point[inside]] = True
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
