"""Map filters drop points from a :class:`~sonarcarve.maps.LocalMap` or
:class:`~sonarcarve.maps.GlobalMap`: maximum-error thresholding (Fig. 13b: points whose
``max_error`` bound, eq. 5.3, exceeds a threshold) and then the outlier test (a point needs at
least ``k`` other points within radius ``R``). Thresholding runs first so that inaccurate points
do not vouch for their neighbours.

Beyond the paper, each off by default:

- the **late-echo** filter, first of all, drops points that are the far echo of an earlier
  firing off a surface of the map (:func:`~sonarcarve.filters.late_echoes.late_echo_mask`:
  ghost walls); it runs before any drop, since it looks for the far walls;
- between thresholding and the outlier test, the **driven-through** filter drops points that
  the robot's body covered at a later pose (:func:`~sonarcarve.filters.driven_through_mask`:
  ghost walls, floor echoes, whatever has moved away); both need the readings the map was
  made from;
- then the **occlusion** filter drops points that lie more than ``occlusion_depth`` behind a
  surface of the map on the line from their own sensor (multipath echoes mostly;
  :mod:`sonarcarve.geometry.occluded`); only points whose error bound is at most half that
  depth make up the surfaces. It needs the sensor origin of every point, which a map does not
  hold, so :func:`filter_map` takes them
  (:func:`~sonarcarve.filters.occlusion.point_origins` looks them up in the readings).
"""


from __future__ import annotations

from dataclasses import dataclass
from typing import Generic, TypeVar

import numpy as np
import numpy.typing as npt

from sonarcarve.filters.checks import FilterError, check_positive
from sonarcarve.filters.driven_through import BodyFootprint, driven_through_mask
from sonarcarve.filters.late_echoes import late_echo_mask
from sonarcarve.filters.occlusion import occlusion_mask, origins_array
from sonarcarve.maps import GlobalMap, LocalMap
from sonarcarve.readings import ReadingBatch
from sonarcarve.typing import BoolArray

__all__ = ["FilteredMap", "MapFilter", "MapFilterReport", "confidence_mask", "filter_map",
           "max_error_mask", "outlier_mask"]

_M = TypeVar("_M", LocalMap, GlobalMap)


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
    late_echo_period : float or None
        Drop points that are the late echo of one of the previous two firings off a surface
        of the map (:func:`~sonarcarve.filters.late_echoes.late_echo_mask`: ghost walls in
        front of a real wall, heard when a sensor fires faster than the round trip of its
        hearing range). The value is the robot's firing period: seconds between consecutive
        firings of any of its sensors (a robot file's ``firing_period``). Needs each point's
        reading (:func:`filter_map`). Off by default (docs/RESULTS.md, *Late echoes: a test
        against the map*).
    driven_through : BodyFootprint or None
        Drop points that this body covered at a later pose (:func:`driven_through_mask`): not
        static obstacles, whatever made them (late echoes forming a ghost wall in front of a
        real one, floor echoes, a person who has since left). Needs the readings' poses
        (:func:`filter_map`). It judges after the fact, so the map is the *current* one: a
        door that stood shut and that the robot later drove through is dropped too.

    Raises
    ------
    FilterError
        A radius, period or threshold that is not a finite positive number, k < 1, or a
        ``driven_through`` that is not a :class:`BodyFootprint`.
    """

    max_error: float | None = None
    outlier_radius: float | None = None
    outlier_neighbours: int = 1
    min_confidence: float | None = None
    occlusion_depth: float | None = None
    late_echo_period: float | None = None
    driven_through: BodyFootprint | None = None

    def __post_init__(self) -> None:
        check_positive("max_error", self.max_error)
        check_positive("late_echo_period", self.late_echo_period, unit="seconds")
        if self.driven_through is not None and not isinstance(self.driven_through,
                                                              BodyFootprint):
            msg = (f"driven_through must be a BodyFootprint (BodyFootprint.of_robot or "
                   f"BodyFootprint.around_sensors), got {type(self.driven_through).__name__}")
            raise FilterError(msg)
        check_positive("occlusion_depth", self.occlusion_depth)
        if self.min_confidence is not None and not 0.0 <= self.min_confidence <= 1.0:
            msg = f"min_confidence must lie in [0, 1], got {self.min_confidence!r}"
            raise FilterError(msg)
        check_positive("outlier_radius", self.outlier_radius)
        if self.outlier_neighbours < 1:
            msg = f"outlier_neighbours must be at least 1, got {self.outlier_neighbours}"
            raise FilterError(msg)

    @property
    def active(self) -> bool:
        """True if at least one filter is on."""
        return (self.max_error is not None or self.outlier_radius is not None
                or self.min_confidence is not None or self.occlusion_depth is not None
                or self.late_echo_period is not None or self.driven_through is not None)


@dataclass(frozen=True)
class MapFilterReport:
    """How many points each map filter dropped (``total`` points in)."""

    total: int
    max_error: int = 0
    outliers: int = 0
    confidence: int = 0
    occluded: int = 0
    late_echoes: int = 0
    driven_through: int = 0

    @property
    def kept(self) -> int:
        """Points out."""
        return (self.total - self.max_error - self.outliers - self.confidence - self.occluded
                - self.late_echoes - self.driven_through)


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
               readings: ReadingBatch | None = None,
               reading_ids: npt.ArrayLike | None = None) -> FilteredMap[_M]:
    """Apply the map filters of ``spec``: late echoes, confidence, max-error thresholding,
    driven through, occlusion, then the outlier test.

    Parameters
    ----------
    points : LocalMap or GlobalMap
        The map to filter.
    spec : MapFilter
        Which filters, with which thresholds.
    origins : array-like, shape (n, 2), optional
        The sensor origin of each point (:func:`point_origins`); needed by the occlusion filter.
    readings : ReadingBatch, optional
        The readings the map was made from, the whole log (those the reading filters dropped
        too: they were taken where the robot stood): the body's path for the driven-through
        filter, each point's reading for the late-echo filter.
    reading_ids : array-like of int, optional
        The id of each of ``readings`` (default: its row, as
        :func:`~sonarcarve.pipeline.process_readings` numbers them).

    Returns
    -------
    FilteredMap
        The kept points (same type as ``points``) and how many each filter dropped.

    Raises
    ------
    FilterError
        The occlusion filter without ``origins``, ``origins`` of the wrong shape, or the
        late-echo or driven-through filter without ``readings``.
    """
    total = len(points)
    _check_inputs(spec, origins, readings)
    origin = None if origins is None else origins_array(origins, total)
    dropped = {"late_echoes": 0, "confidence": 0, "max_error": 0, "driven_through": 0,
               "occluded": 0, "outliers": 0}

    def drop(name: str, keep: BoolArray) -> None:
        nonlocal points, origin
        dropped[name] = len(points) - int(keep.sum())
        points = points.select(keep)
        origin = None if origin is None else origin[keep]

    # Late echoes first: its test looks for the far walls, which the map holds whole only
    # before any drop (a --max-error below its own surface limit would take some away).
    if spec.late_echo_period is not None:
        assert readings is not None  # checked above
        drop("late_echoes", ~late_echo_mask(points.xy, points.reading_id, points.max_error,
                                            readings, reading_ids=reading_ids,
                                            firing_period=spec.late_echo_period))
    if spec.min_confidence is not None:
        drop("confidence", confidence_mask(points.confidence, spec.min_confidence))
    if spec.max_error is not None:
        drop("max_error", max_error_mask(points.max_error, spec.max_error))
    # The ghost filters before the occlusion filter, so that a ghost wall hides nothing
    # behind it, and before the outlier test, so that it vouches for no neighbour.
    if spec.driven_through is not None:
        assert readings is not None  # checked above
        drop("driven_through", ~driven_through_mask(points.xy, points.t, readings,
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


def _check_inputs(spec: MapFilter, origins: npt.ArrayLike | None,
                  readings: ReadingBatch | None) -> None:
    """Refuse a filter of ``spec`` without what it needs, naming what to pass."""
    if spec.occlusion_depth is not None and origins is None:
        msg = ("the occlusion filter needs each point's sensor origin: pass "
               "origins=point_origins(points, readings)")
        raise FilterError(msg)
    for name, on in (("late-echo", spec.late_echo_period is not None),
                     ("driven-through", spec.driven_through is not None)):
        if on and readings is None:
            msg = f"the {name} filter needs the map's readings: pass readings=the whole log"
            raise FilterError(msg)
