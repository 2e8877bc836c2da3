"""Late echoes: map points that are the far echo of an earlier firing (beyond the paper).

A sonar times an echo from its own firing. When an earlier firing ``j`` (``lag`` firings
before, ``Δt = t_k - t_j``) still has sound in the air, its echo off a far wall can reach
sensor ``k`` after ``k`` has fired, and ``k`` reads ``r = P/2 - c Δt / 2``, where ``P`` is the
path from ``j``'s sensor to the wall and on to ``k``'s. Its arc lies in free space, ``c Δt / 2``
(6.9 m at 0.04 s) in front of the far wall. The geometry repeats from firing to firing, so
these points form a static *ghost wall* that every consistency test of the paper's methods
keeps (the same sensor reads it again and again at consistent ranges; docs/RESULTS.md, *A car
in a car park*, the traced late echoes). The paper's Polaroid ring fired slowly enough for this
not to happen; a sensor fired faster than the round trip of its own hearing range does.

The test (:func:`late_echo_mask`) looks for the far wall that would explain a point as a late
echo: for each point of the map (at ``p``, heard by sensor ``k`` from ``o_k`` with range ``r``,
direction ``u = (p - o_k) / |p - o_k|``) and each lag 1..``lags``, the sound path of length
``L = 2 r + c Δt`` from the emitter's origin ``o_j`` to a wall and on to ``o_k`` reflects on the
ellipse with foci ``o_j`` and ``o_k``. On the line from ``o_k`` through ``p`` that ellipse lies
at distance

    s = (L² - |d|²) / (2 (L + d · u)),   d = o_k - o_j,

(``|o_k + s u - o_j| + s = L``, squared) which is ``r + c Δt / 2`` when the emitter is the
receiver. The point is a late echo when

* a *surface* point of the map (error bound at most ``surface_error``) lies at the depth of
  ``o_k + s u`` along ``u`` within ``tolerance``, and within ``half_width`` across the line,
  heard from this side (its own sensor origin on ``o_k``'s side of it along ``u``: a wall's
  back does not echo towards ``k``). Across, because a wide beam's map holds a wall's points
  sparsely (a car's 70° sensors: the far wall's nearest point 0.2-2 m from the far point, which
  lay within 0.05 m of the true wall), and a wall that sends a mirror echo back along the line
  meets it nearly square on, so its points beside the line lie at the same depth;
* that surface point is no lone point: at least :data:`FAR_SURFACE_NEIGHBOURS` other surface
  points lie within :data:`FAR_SURFACE_RADIUS` (2 m) of it. Under the rough physics a lone
  stray point stood in for the far wall and took real wall points with it (the single sonar:
  136 direct points dropped, 83 with this rule, ghosts removed the same; the losses that stay
  have a cluster of surviving ghosts for their far wall; docs/RESULTS.md); and
* that surface is visible through ``p``: no surface point lies within ``tolerance`` of the
  line between them (more than :data:`BETWEEN_MARGIN` from ``p`` and from ``tolerance`` short of
  the far point). A wall cannot echo from
  behind another wall of the map; a direct echo of a wall with walls behind it stays.

The map is the reference, not the walls: the far wall is usually mapped *after* the ghost, once
the robot comes within range of it, so the test runs on a finished map, as the other map
filters do (:mod:`sonarcarve.filters`).

**The firing schedule.** A log need not hold every firing: the simulator's logs (and many real
ones) omit the firings that heard nothing, so the previous reading of the stream may be several
firings back. So the caller names the schedule, one of two (there is no default: on the
simulator's logs, which hold no no-echo readings, taking the distinct reading times for the
firings removed none of the car park's late echoes under the amplitude physics, against 43 %
with the period; docs/RESULTS.md):

- ``firings``: the time and sensor origin of every firing (:class:`FiringSchedule`); exact
  (the ellipse) when the log has them, e.g. one that records no-echo readings
  (:meth:`FiringSchedule.from_readings`: the distinct reading times);
- ``firing_period``: the time between consecutive firings of the robot (any sensor). Then
  ``Δt = lag × period`` and the emitter is taken to sit at the receiver (the circle of radius
  ``r + c Δt / 2``). For an emitter ``b`` metres from the receiver the far point moves by about
  ``(d · u) / 2 + b² / (2 L)``: at most ``b / 2`` plus a few millimetres, so a few centimetres on
  a ring (neighbouring sensors 0.1 m apart) and up to metres on a car, whose sensors are
  metres apart.
"""

from __future__ import annotations

import math
import numbers
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.filters.checks import FilterError, check_positive, rows_of_ids
from sonarcarve.readings import ReadingBatch
from sonarcarve.typing import BoolArray, FloatArray, IntArray

__all__ = [
    "BETWEEN_MARGIN",
    "FIRING_TIME_TOLERANCE",
    "LATE_ECHO_HALF_WIDTH",
    "LATE_ECHO_LAGS",
    "LATE_ECHO_SURFACE_ERROR",
    "LATE_ECHO_TOLERANCE",
    "MAX_LATE_ECHO_LAGS",
    "SOUND_SPEED",
    "FiringSchedule",
    "LateEchoError",
    "far_echo_distance",
    "late_echo_mask",
]

#: Speed of sound in air at 20 °C, m/s (the simulator's default too; 331 m/s at 0 °C, 349 at
#: 30 °C: ±2 %, a far point off by 0.1 m at 6.9 m of ``c Δt / 2``).
SOUND_SPEED = 343.0
#: Firings looked back by default: the simulator's ``crosstalk_lookback``; two periods of a fast
#: ring already cover the round trip of a Polaroid's whole hearing range (10.7 m, 62 ms).
LATE_ECHO_LAGS = 2
#: How near the far point a surface point must lie, metres (late13's probe; docs/RESULTS.md).
LATE_ECHO_TOLERANCE = 0.1
#: How far across the line from the receiver a surface point at the far point's depth may lie,
#: metres: a map of a wide beam holds its walls' points sparsely, and a wall that returns a
#: mirror echo to the receiver meets that line nearly square on.
LATE_ECHO_HALF_WIDTH = 0.5
#: Only points whose error bound (eq. 5.3) is at most this make up the far surface and the
#: surfaces between, metres (cf. the occlusion filter's ``depth / 2``).
LATE_ECHO_SURFACE_ERROR = 0.5
#: A point stays a late echo only if at least this share of the map's points within
#: :data:`AGREEMENT_RADIUS` of it (itself included) are late echoes too: a ghost wall is all
#: late echoes, heard square on, while a real wall that another wall stands c Δt / 2 behind
#: is also heard obliquely (by a ring's other sensors), from where no far point lands on it.
AGREEMENT = 0.5
AGREEMENT_RADIUS = 0.3
#: A surface point makes a far wall only if at least this many other surface points lie within
#: :data:`FAR_SURFACE_RADIUS` of it (in any direction): a lone stray point is no wall. 0: any
#: surface point will do (the test before 2026-12-04).
FAR_SURFACE_NEIGHBOURS = 1
#: Metres around a far-wall point for :data:`FAR_SURFACE_NEIGHBOURS`: a car's wide beams map a
#: wall's points up to 2 m apart (at 0.5 and 1.0 m the car park lost 7 points of its ghosts
#: removed; docs/RESULTS.md).
FAR_SURFACE_RADIUS = 2.0
#: Surface points that must lie in the far point's window (``tolerance`` along, ``half_width``
#: across) for it to count as a far wall. Kept at 1: 2 or 3 spare more direct points but miss
#: the car park's far walls, which the map holds as single points there (docs/RESULTS.md).
FAR_SURFACE_POINTS = 1
#: Most firings looked back: each lag is one pass over the map, and 1,000 firings of even the
#: fastest ring a robot file allows (1e-4 s) are 0.1 s of flight, 34 m of extra path.
MAX_LATE_ECHO_LAGS = 1000
#: Seconds between a reading's time and its firing's in a :class:`FiringSchedule`: a schedule
#: logged by another clock, or printed with fewer digits, is a hair off (a microsecond is
#: 0.3 mm of sound).
FIRING_TIME_TOLERANCE = 1e-6
#: Surface points this near either end of the line from a point to its far surface are its own
#: surface or the far one, not a surface between, metres.
BETWEEN_MARGIN = 0.3


class LateEchoError(FilterError):
    """A parameter or array of the late-echo test outside its valid range (a
    :class:`~sonarcarve.filters.FilterError`)."""


class FiringSchedule(NamedTuple):
    """Every firing of a log: time (s, increasing) and the emitting sensor's origin (m).

    Attributes
    ----------
    t, x, y : ndarray of float64, shape (m,)
    """

    t: FloatArray
    x: FloatArray
    y: FloatArray

    @classmethod
    def from_readings(cls, readings: ReadingBatch) -> FiringSchedule:
        """The distinct times of ``readings``, each with the origin of its first reading: every
        firing when the log records no-echo readings (a firing that heard nothing and left no
        reading is missed, and the firing before it is taken in its place)."""
        times, first = np.unique(readings.t, return_index=True)
        return cls(np.asarray(times, dtype=np.float64), readings.x[first], readings.y[first])


def far_echo_distance(range_: npt.ArrayLike, delay: npt.ArrayLike, offset: npt.ArrayLike,
                      direction: npt.ArrayLike, sound_speed: float = SOUND_SPEED) -> FloatArray:
    """Distance from the receiver along ``direction`` to where a late echo reflected.

    ``s = (L² - |d|²) / (2 (L + d · u))`` with ``L = 2 r + c Δt`` (module docstring).

    Parameters
    ----------
    range_ : array-like, shape (n,)
        The reading's range r, metres.
    delay : array-like, shape (n,)
        Δt, the time from the emitting firing to the receiving one, seconds.
    offset : array-like, shape (n, 2)
        d, the receiver's origin minus the emitter's, metres.
    direction : array-like, shape (n, 2)
        u, unit vectors from the receiver.
    sound_speed : float
        c, m/s.

    Examples
    --------
    Emitter at the receiver: ``r + c Δt / 2``. Emitter 2 m behind: the ellipse's point on
    the axis, ``|(s, 0) - (-2, 0)| + s = L``:

    >>> far_echo_distance([1.0, 1.0], [0.02, 0.02], [[0, 0], [2, 0]], [[1, 0], [1, 0]],
    ...                   sound_speed=300.0).tolist()
    [4.0, 3.0]
    """
    path = 2.0 * np.asarray(range_, dtype=np.float64) + sound_speed * np.asarray(delay, float)
    d = np.asarray(offset, dtype=np.float64).reshape(-1, 2)
    u = np.asarray(direction, dtype=np.float64).reshape(-1, 2)
    along = np.einsum("ij,ij->i", d, u)
    return np.asarray((path**2 - np.einsum("ij,ij->i", d, d)) / (2.0 * (path + along)))


def _check_parameters(lags: int, tolerance: float, surface_error: float, sound_speed: float,
                      firing_period: float | None) -> None:
    if (isinstance(lags, bool) or not isinstance(lags, numbers.Integral)
            or not 1 <= lags <= MAX_LATE_ECHO_LAGS):
        msg = (f"lags must be a whole number in 1..{MAX_LATE_ECHO_LAGS} (firings looked back), "
               f"got {lags!r}")
        raise LateEchoError(msg)
    check_positive("tolerance", tolerance, "metres", LateEchoError)
    check_positive("surface_error", surface_error, "metres", LateEchoError)
    check_positive("sound_speed", sound_speed, "m/s", LateEchoError)
    if firing_period is not None:
        check_positive("firing_period", firing_period, "seconds", LateEchoError)


def _whole_numbers(name: str, values: npt.ArrayLike) -> IntArray:
    """``values`` as int64, or a :class:`LateEchoError` (a cast would read 1.5 as 1)."""
    raw = np.asarray(values).reshape(-1)
    if raw.size == 0:
        return np.zeros(0, dtype=np.int64)
    if raw.dtype.kind in "iu":
        return raw.astype(np.int64)
    if raw.dtype.kind != "f" or not np.all(raw == np.round(raw)):  # NaN is no whole number
        msg = f"{name} must be whole numbers (reading ids), got {raw.dtype} values"
        raise LateEchoError(msg)
    return raw.astype(np.int64)


def _known_ids(readings: ReadingBatch, reading_ids: npt.ArrayLike | None) -> IntArray:
    """The id of each of ``readings``: given (one each, unique) or its row."""
    if reading_ids is None:
        return np.arange(len(readings), dtype=np.int64)
    known = _whole_numbers("reading_ids", reading_ids)
    if known.shape != (len(readings),):
        msg = (f"reading_ids needs one id for each of the {len(readings)} readings, got "
               f"{known.shape[0]}")
        raise LateEchoError(msg)
    return known  # unique: rows_of_ids checks


def _check_firings(firings: FiringSchedule) -> None:
    """Refuse a schedule whose arrays differ in length, are not finite, or whose times do not
    increase (the search for a reading's firing assumes them sorted)."""
    t, x, y = (np.asarray(a, dtype=np.float64).reshape(-1) for a in firings)
    if not t.shape == x.shape == y.shape:
        msg = (f"firings: t, x and y must have the same length, got {t.shape[0]}, {x.shape[0]} "
               f"and {y.shape[0]}")
        raise LateEchoError(msg)
    if not np.all(np.isfinite(np.concatenate((t, x, y)))):
        msg = "firings: times and origins must be finite"
        raise LateEchoError(msg)
    if np.any(np.diff(t) <= 0.0):
        msg = "firings: times must be increasing (one firing per time)"
        raise LateEchoError(msg)


def _emitters(t: FloatArray, origin: FloatArray, lag: int, firings: FiringSchedule | None,
              firing_period: float | None) -> tuple[FloatArray, FloatArray]:
    """Δt (NaN: no firing that far back) and the emitter's origin for each receiving time."""
    if firing_period is not None:  # emitter taken at the receiver (module docstring)
        return np.full(len(t), lag * firing_period), origin
    assert firings is not None
    # A reading's firing is the first within FIRING_TIME_TOLERANCE of it, before or after.
    at = np.searchsorted(firings.t, t - FIRING_TIME_TOLERANCE)
    known = (at < len(firings.t)) & (np.abs(firings.t[np.minimum(at, len(firings.t) - 1)] - t)
                                     <= FIRING_TIME_TOLERANCE)
    if not known.all():
        msg = (f"reading time {t[~known][0]!r} is no firing of the schedule: pass every "
               "firing, or a firing_period")
        raise LateEchoError(msg)
    j = at - lag
    ok = j >= 0
    j = np.maximum(j, 0)
    delay = np.where(ok, t - firings.t[j], np.nan)
    return delay, np.column_stack((firings.x[j], firings.y[j]))


def _blocked(tree: object, start: FloatArray, end: FloatArray, reach: float) -> BoolArray:
    """True where a surface point (``tree``'s) lies within ``reach`` of the segment from
    ``start`` to ``end``: sampled every ``reach``, each sample's ball wide enough to cover the
    band between samples."""
    if len(start) == 0:
        return np.zeros(0, dtype=bool)
    vector = end - start
    length = np.hypot(vector[:, 0], vector[:, 1])
    steps = np.maximum(np.ceil(length / reach).astype(np.int64), 1)
    owner = np.repeat(np.arange(len(start)), steps + 1)
    first = np.concatenate(([0], np.cumsum(steps + 1)[:-1]))
    fraction = (np.arange(len(owner)) - np.repeat(first, steps + 1)) / np.repeat(steps, steps + 1)
    samples = start[owner] + fraction[:, None] * vector[owner]
    hits = tree.query_ball_point(samples, r=reach * math.sqrt(1.25),  # type: ignore[attr-defined]
                                 return_length=True)
    return np.asarray(np.bincount(owner, weights=hits, minlength=len(start)) > 0)


def late_echo_mask(xy: npt.ArrayLike, reading_id: npt.ArrayLike, max_error: npt.ArrayLike,
                   readings: ReadingBatch, *, reading_ids: npt.ArrayLike | None = None,
                   firings: FiringSchedule | None = None, firing_period: float | None = None,
                   lags: int = LATE_ECHO_LAGS, tolerance: float = LATE_ECHO_TOLERANCE,
                   half_width: float = LATE_ECHO_HALF_WIDTH,
                   surface_error: float = LATE_ECHO_SURFACE_ERROR,
                   sound_speed: float = SOUND_SPEED) -> BoolArray:
    """True where a map point is a late echo: a visible surface of the map lies where the far
    echo of one of the ``lags`` previous firings would have reflected (module docstring).

    Parameters
    ----------
    xy : array-like, shape (n, 2)
        The map's points, metres.
    reading_id : array-like of int, shape (n,)
        The id of the reading that made each point.
    max_error : array-like, shape (n,)
        Each point's error bound, metres (eq. 5.3; NaN: no surface).
    readings : ReadingBatch
        The readings the map was made from.
    reading_ids : array-like of int, optional
        The id of each of ``readings``, unique (default: its row).
    firings : FiringSchedule, optional
        Every firing's time and emitter origin (e.g. :meth:`FiringSchedule.from_readings` of a
        log with its no-echo readings). Exactly one of ``firings`` and ``firing_period``.
    firing_period : float, optional
        Seconds between consecutive firings of the robot (any sensor: a robot file's
        ``firing_period``); the emitter is then taken at the receiver.
    lags : int
        Firings looked back, 1 to :data:`MAX_LATE_ECHO_LAGS`.
    tolerance : float
        Metres between the far point and a surface point along the line (and between the line
        to it and a surface point that blocks it).
    half_width : float
        Metres between the far point and a surface point across the line.
    surface_error : float
        Largest error bound of a surface point, metres.
    sound_speed : float
        m/s.

    Raises
    ------
    LateEchoError
        A parameter out of range, both schedules or neither, arrays of different lengths, a point or
        origin not finite, ids that are no whole numbers, ``reading_ids`` not one unique id a
        reading, a reading id not among the readings, firings whose times do not increase, or a
        reading time that is no firing of ``firings``.

    Examples
    --------
    A sensor at the origin facing +x fires every 0.02 s; at c = 300 m/s a late echo of the
    previous firing reads 3 m short. A wall mapped at x = 4 makes the point at x = 1 a ghost:

    >>> wall = [[4.0, 0.1 * k - 0.5] for k in range(11)]
    >>> batch = ReadingBatch.from_arrays(t=[0.02 * k for k in range(12)], sensor=[0] * 12,
    ...     x=[0.0] * 12, y=[0.0] * 12, theta=[0.0] * 12, range=[1.0] + [4.0] * 11)
    >>> ghost = late_echo_mask([[1.0, 0.0]] + wall, range(12), [0.01] * 12, batch,
    ...                        firing_period=0.02, sound_speed=300.0)
    >>> ghost[:2].tolist()
    [True, False]
    """
    _check_parameters(lags, tolerance, surface_error, sound_speed, firing_period)
    check_positive("half_width", half_width, "metres", LateEchoError)
    if (firings is None) == (firing_period is None):
        msg = ("give either a firing_period (seconds between consecutive firings of the robot) "
               "or the firings, not both")
        raise LateEchoError(msg)
    if firings is not None:
        _check_firings(firings)
        firings = FiringSchedule(*(np.asarray(a, dtype=np.float64).reshape(-1)
                                   for a in firings))
    if not isinstance(readings, ReadingBatch):
        msg = f"readings must be a ReadingBatch (the map's log), got {type(readings).__name__}"
        raise LateEchoError(msg)
    points = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    ids = _whole_numbers("reading_id", reading_id)
    bound = np.asarray(max_error, dtype=np.float64).reshape(-1)
    if ids.shape != (len(points),) or bound.shape != (len(points),):
        msg = (f"the late-echo test needs a reading id and an error bound for each of the "
               f"{len(points)} points, got {ids.shape} and {bound.shape}")
        raise LateEchoError(msg)
    if not np.all(np.isfinite(points)):
        msg = "the late-echo test needs finite points"
        raise LateEchoError(msg)
    if len(points) == 0:
        return np.zeros(0, dtype=bool)
    rows = rows_of_ids(ids, _known_ids(readings, reading_ids), LateEchoError)
    settings = _Settings(lags, tolerance, half_width, surface_error, sound_speed)
    return _late_echoes(points, bound, rows, readings, firings, firing_period, settings)


def _surface_across(tree: object, surface: FloatArray, surface_origin: FloatArray,
                    far_point: FloatArray, u: FloatArray, tolerance: float,
                    half_width: float) -> BoolArray:
    """True where a surface point lies within ``tolerance`` of ``far_point`` along ``u`` and
    within ``half_width`` across it, heard from this side (its own sensor origin on the near
    side of it along ``u``: a wall's back does not echo towards the receiver)."""
    reach = math.hypot(tolerance, half_width)
    # Most far points lie in empty space (beyond the walls): one nearest-point query each
    # rules them out, cheaper than gathering every neighbour (on the office tour, half the cost).
    hit = np.zeros(len(far_point), dtype=bool)
    some = np.flatnonzero(np.isfinite(tree.query(  # type: ignore[attr-defined]
        far_point, distance_upper_bound=reach)[0]))
    if len(some) == 0:
        return hit
    far_point, u = far_point[some], u[some]
    near = tree.query_ball_point(far_point, r=reach)  # type: ignore[attr-defined]
    counts = np.fromiter((len(n) for n in near), dtype=np.int64, count=len(far_point))
    owner = np.repeat(np.arange(len(far_point)), counts)
    found = np.concatenate([np.asarray(n, dtype=np.int64) for n in near] or [np.zeros(0, int)])
    offset = surface[found] - far_point[owner]
    along = np.einsum("ij,ij->i", offset, u[owner])
    across = np.abs(offset[:, 0] * u[owner, 1] - offset[:, 1] * u[owner, 0])
    facing = np.einsum("ij,ij->i", surface_origin[found] - surface[found], u[owner]) < 0.0
    found_here = (np.abs(along) <= tolerance) & (across <= half_width) & facing
    hit[some] = (np.bincount(owner, weights=found_here, minlength=len(far_point))
                 >= FAR_SURFACE_POINTS)
    return hit


class _Settings(NamedTuple):
    """:func:`late_echo_mask`'s parameters of the test itself, checked."""

    lags: int
    tolerance: float
    half_width: float
    surface_error: float
    sound_speed: float


def _late_echoes(points: FloatArray, bound: FloatArray, rows: IntArray, readings: ReadingBatch,
                 firings: FiringSchedule | None, firing_period: float | None,
                 settings: _Settings) -> BoolArray:
    """:func:`late_echo_mask` on checked arrays."""
    lags, tolerance, half_width, surface_error, sound_speed = settings
    from scipy.spatial import cKDTree  # scipy.spatial costs 0.4 s to import: only when used

    origin = np.column_stack((readings.x[rows], readings.y[rows]))
    offset = points - origin
    distance = np.hypot(offset[:, 0], offset[:, 1])
    u = offset / np.maximum(distance, 1e-12)[:, None]
    surface = np.flatnonzero(bound <= surface_error)  # NaN: no surface
    late = np.zeros(len(points), dtype=bool)
    if len(surface) == 0:
        return late
    tree = cKDTree(points[surface])
    far_surface = _not_alone(tree, points, surface)
    far_tree = cKDTree(points[far_surface]) if len(far_surface) else None
    # The line's ends keep clear of the point's own surface and of the far one by more than a
    # sample's ball (:func:`_blocked`, tolerance·√1.25): else, from a tolerance of 0.27 m on,
    # a point would block its own line and no late echo would ever be found.
    margin = max(BETWEEN_MARGIN, 1.01 * tolerance * math.sqrt(1.25))
    for lag in range(1, lags + 1):
        delay, emitter = _emitters(readings.t[rows], origin, lag, firings, firing_period)
        far = far_echo_distance(readings.range[rows], delay, origin - emitter, u, sound_speed)
        far = np.where(np.isfinite(far), far, -1.0)  # no such firing: no far point
        # The far surface may lie ``tolerance`` short of the far point: the line between
        # stops ``margin`` before that, and starts ``margin`` after the point.
        short = margin + tolerance
        candidates = np.flatnonzero(~late & (far > distance + margin + short))
        far_point = origin[candidates] + far[candidates, None] * u[candidates]
        if far_tree is None:
            break
        at_wall = _surface_across(far_tree, points[far_surface], origin[far_surface], far_point,
                                  u[candidates], tolerance, half_width)
        candidates, far_point = candidates[at_wall], far_point[at_wall]
        start = points[candidates] + margin * u[candidates]
        end = far_point - short * u[candidates]
        late[candidates[~_blocked(tree, start, end, tolerance)]] = True
    return _agreed(points, late)


def _not_alone(tree: object, points: FloatArray, surface: IntArray) -> IntArray:
    """The ``surface`` points (indices into ``points``; ``tree`` holds them) with at least
    :data:`FAR_SURFACE_NEIGHBOURS` others within :data:`FAR_SURFACE_RADIUS`: those that may
    make a far wall."""
    if FAR_SURFACE_NEIGHBOURS <= 0:
        return surface
    # The nearest k + 1 (the point itself among them): cheaper than counting all within 2 m.
    distance: FloatArray = np.asarray(tree.query(  # type: ignore[attr-defined]
        points[surface], k=FAR_SURFACE_NEIGHBOURS + 1,
        distance_upper_bound=FAR_SURFACE_RADIUS)[0], dtype=np.float64)
    return surface[np.isfinite(distance[:, -1])]


def _agreed(points: FloatArray, late: BoolArray) -> BoolArray:
    """``late`` where at least :data:`AGREEMENT` of the map's points within
    :data:`AGREEMENT_RADIUS` of a point (itself included) are late too."""
    if AGREEMENT <= 0.0 or not late.any():
        return late
    from scipy.spatial import cKDTree

    tree = cKDTree(points)
    flagged = np.flatnonzero(late)
    near = tree.query_ball_point(points[flagged], r=AGREEMENT_RADIUS)
    share = np.fromiter((late[n].mean() for n in near), dtype=np.float64, count=len(flagged))
    out = np.zeros_like(late)
    out[flagged[share >= AGREEMENT]] = True
    return out
