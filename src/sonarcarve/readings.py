"""Sonar readings: one echo as a value, many as a struct of arrays.

A reading is one echo heard by one sensor: time ``t`` (s), ``sensor`` index, the sensor's origin
``(x, y)`` (m) and axis ``theta`` (rad, counter-clockwise from +x) in the world frame, the measured
``range`` r (m) and the beam width φ (rad). The beam width may be NaN, meaning "the method's
default" (22.5°, the Polaroid transducer of the paper, section 2).

A *no-echo* reading (REP 117's +Inf: the sensor heard nothing) has ``range = inf`` and says the
whole beam was empty up to ``max_range``, the distance the sensor listened to (metres; NaN when
unknown). It is free space only: no arc, no point. ``range`` may be +inf only when the reading's
``max_range`` is finite and > 0, and a finite range may not exceed a known ``max_range``.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field, fields
from typing import NamedTuple, NoReturn, overload

import numpy as np
import numpy.typing as npt

from sonarcarve.constants import DEFAULT_BEAM_WIDTH, MIN_BEAM_WIDTH
from sonarcarve.errors import ReadingsError, ReadingTypeError
from sonarcarve.typing import FloatArray, IntArray

__all__ = [
    "DEFAULT_BEAM_WIDTH",
    "MAX_ANGLE",
    "MAX_POSITION",
    "MAX_READING_RANGE",
    "MAX_SENSOR",
    "MAX_TIME",
    "NO_MAX_RANGE",
    "Reading",
    "ReadingBatch",
    "ReadingsError",
    "check_reading",
    "reading_ids",
    "wrap_angle",
]

#: Largest sensor index accepted. Indices name the sensors of one robot, so anything near this
#: is a damaged file; the bound (2**31 - 1) keeps an index exact in every integer type and in
#: float64, which is how a CSV column is first parsed.
MAX_SENSOR = 2**31 - 1

# Bounds on the numbers of a reading, so that no finite value can overflow or stall the geometry.
# Positions and ranges go through squares, products and sums in float64: with |x|, |y| <= 1e6 m
# and r <= 1e4 m every intermediate stays below ~1e13, where float64 still resolves far less than
# a millimetre (it keeps millimetres exact up to ~1e9 m of magnitude), whereas a coordinate of
# 1e300 squares to inf and a range of 1.7e308 gives inf - inf = NaN map points. Angles are
# unwrapped and reduced by multiples of 2π (floor((θ - lo) / 2π), crossings of multiples of
# π/2), which needs them bounded: at 1e20 rad the multiple overflows an integer and an angle
# has no digits left below 2π. 1e6 rad (159,000 turns: an unwrapped heading of a robot
# circling one way for days) keeps 1e-10 rad of precision; 1e12 s (31,700 years) likewise for
# times, and keeps t exact to the microsecond.
#: Largest |x|, |y| of a sensor origin, metres.
MAX_POSITION = 1e6
#: Largest range and max range, metres (ultrasonic sensors reach 3-10 m).
MAX_READING_RANGE = 1e4
#: Largest |theta|, radians.
MAX_ANGLE = 1e6
#: Largest |t|, seconds.
MAX_TIME = 1e12

# The problems a reading can have, worded once for the batch and the single-reading checks.
_NOT_FINITE = "is NaN or infinite"
_NOT_POSITIVE = "must be > 0"
_NEGATIVE = "must be >= 0"
_NOT_WHOLE = "is not a whole number"
_TOO_LARGE = f"must be at most {MAX_SENSOR}"
_BAD_BEAM = f"must lie in [{MIN_BEAM_WIDTH:g}, pi) radians (22.5 degrees is 0.39)"
_BACKWARDS = "goes backwards in time"
#: The end of the error of a no-echo reading (range inf) that says how far it listened nowhere
#: (the commands add how to say it).
NO_MAX_RANGE = "is infinite but 'max_range' is not given"
_BAD_MAX_RANGE = f"must be a number in (0, {MAX_READING_RANGE:,.0f}] metres, or NaN (unknown)"
_TOO_FAR = f"must be at most {MAX_READING_RANGE:,.0f} m"
#: The bound of each column that has one, and the message of a value beyond it.
#: The hints name what loggers write there: times since 1970 in ms, µs or ns, UTM northings.
_OFF_MAP = f"must lie within ±{MAX_POSITION:,.0f} m (UTM coordinates? subtract a local origin)"
_BOUNDS = {
    "t": (MAX_TIME, "must lie within ±1e12 s (seconds: milli-, micro- or nanoseconds since "
                    "1970 are beyond it)"),
    "x": (MAX_POSITION, _OFF_MAP),
    "y": (MAX_POSITION, _OFF_MAP),
    "theta": (MAX_ANGLE, f"must lie within ±{MAX_ANGLE:,.0f} rad"),
}
_BEYOND_MAX_RANGE = "exceeds 'max_range'"


class Reading(NamedTuple):
    """One sonar echo in the world frame.

    A value only: it is checked where it enters a method (:func:`check_reading`, run by
    ``SonarMethod.add``) or a batch (:meth:`ReadingBatch.validate`), with the same rules and
    messages.

    Attributes
    ----------
    t : float
        Time of the echo, seconds.
    sensor : int
        Index of the sensor that heard it.
    x, y : float
        Sensor origin in the world frame, metres.
    theta : float
        Sensor axis, radians counter-clockwise from +x.
    range : float
        Measured range r, metres (> 0); ``inf`` for a no-echo reading (then ``max_range`` must
        be known).
    beam_width : float
        Beam width φ, radians in [:data:`~sonarcarve.constants.MIN_BEAM_WIDTH`, π); NaN means
        the method's default.
    max_range : float
        How far the sensor listened, metres (> 0); NaN: unknown.
    """

    t: float
    sensor: int
    x: float
    y: float
    theta: float
    range: float
    beam_width: float = math.nan
    max_range: float = math.nan

    @property
    def no_echo(self) -> bool:
        """The sensor heard nothing (``range`` is +inf): free space up to ``max_range``."""
        return self.range == math.inf

    def width_or(self, default: float) -> float:
        """This reading's beam width, or ``default`` (radians) where it carries none (NaN).

        Examples
        --------
        >>> Reading(0.0, 0, 0.0, 0.0, 0.0, 1.0).width_or(0.5)
        0.5
        """
        return default if math.isnan(self.beam_width) else self.beam_width


@dataclass(frozen=True, eq=False)
class ReadingBatch:
    """Many readings as a struct of arrays, each of shape (n,), in stream order.

    Build one with :meth:`from_arrays` (validates) or :meth:`from_readings`. ``max_range`` may
    be left out when constructing one directly: every row's is then unknown (NaN).
    """

    t: FloatArray
    sensor: IntArray
    x: FloatArray
    y: FloatArray
    theta: FloatArray
    range: FloatArray
    beam_width: FloatArray
    max_range: FloatArray = field(default_factory=lambda: _NO_VALUES)

    def __post_init__(self) -> None:
        if self.max_range is _NO_VALUES:
            object.__setattr__(self, "max_range", np.full(self.t.shape, math.nan))

    @classmethod
    def from_arrays(
        cls,
        *,
        t: npt.ArrayLike,
        sensor: npt.ArrayLike,
        x: npt.ArrayLike,
        y: npt.ArrayLike,
        theta: npt.ArrayLike,
        range: npt.ArrayLike,
        beam_width: npt.ArrayLike | None = None,
        max_range: npt.ArrayLike | None = None,
        source: str = "readings",
        first_line: int | None = None,
    ) -> ReadingBatch:
        """Validated batch from array-likes of equal length.

        Raises
        ------
        ReadingsError
            Naming ``source`` and the first offending row (0-based) and column; with
            ``first_line`` (the file line of row 0) it names the file line instead. A sensor
            must be a whole number in [0, :data:`MAX_SENSOR`].

        ``max_range`` (metres, NaN: unknown) defaults to unknown for every row.
        """
        t_arr = np.asarray(t, dtype=np.float64).reshape(-1)
        n = t_arr.shape[0]
        width = np.full(n, math.nan) if beam_width is None else beam_width
        limit = np.full(n, math.nan) if max_range is None else max_range
        batch = cls(
            t=t_arr,
            sensor=_sensor_indices(sensor, _Where(source, first_line)),
            x=np.asarray(x, dtype=np.float64).reshape(-1),
            y=np.asarray(y, dtype=np.float64).reshape(-1),
            theta=np.asarray(theta, dtype=np.float64).reshape(-1),
            range=np.asarray(range, dtype=np.float64).reshape(-1),
            beam_width=np.asarray(width, dtype=np.float64).reshape(-1),
            max_range=np.asarray(limit, dtype=np.float64).reshape(-1),
        )
        batch.validate(source, first_line)
        return batch

    @classmethod
    def from_readings(cls, readings: Iterable[Reading], source: str = "readings") -> ReadingBatch:
        """Validated batch from :class:`Reading` values."""
        rows = list(readings)
        columns = [np.array(c) for c in zip(*rows, strict=True)] if rows else [np.zeros(0)] * 8
        t, sensor, x, y, theta, r, width, limit = columns
        return cls.from_arrays(t=t, sensor=sensor, x=x, y=y, theta=theta, range=r,
                               beam_width=width, max_range=limit, source=source)

    @classmethod
    def empty(cls) -> ReadingBatch:
        """A batch with no readings."""
        return cls.from_readings([])

    @classmethod
    def concatenate(cls, batches: Sequence[ReadingBatch], *,
                    validate: bool = True) -> ReadingBatch:
        """The readings of ``batches`` one after the other (times must stay sorted).

        With ``validate=False`` the result is not checked (:meth:`validate`): for batches each
        checked where it came from, whose order the caller guarantees.
        """
        if not batches:
            return cls.empty()
        merged = cls(*(np.concatenate([getattr(b, f.name) for b in batches]) for f in fields(cls)))
        if validate:
            merged.validate("concatenated readings")
        return merged

    def validate(self, source: str = "readings", first_line: int | None = None,
                 *, first_id: int | None = None, previous_t: float = -math.inf) -> None:
        """Check shapes and values; raise :class:`ReadingsError` naming the first bad row.

        The rules are those of :func:`check_reading`, vectorised. The error names
        ``"{source}: row {i}"``, or ``"{source}: line {i + first_line}"`` with ``first_line``, or
        ``"reading {i + first_id}"`` with ``first_id`` (a batch fed to a method); ``previous_t``
        is the time of the reading before the batch (row 0 must not be earlier).
        """
        where = _Where(source, first_line, first_id)
        n = len(self.t)
        for f in fields(self):
            if getattr(self, f.name).shape != (n,):
                size = getattr(self, f.name).size
                msg = f"{source}: column {f.name!r} has {size} rows, expected {n}"
                raise ReadingsError(msg)
        for name, (bound, beyond) in _BOUNDS.items():
            values = getattr(self, name)
            _first_bad(where, name, ~np.isfinite(values), _NOT_FINITE)
            _first_bad(where, name, np.abs(values) > bound, beyond)
        r = self.range
        not_finite = ~np.isfinite(r)
        if not_finite.any():  # +inf is a no-echo reading, allowed where max_range is known
            no_echo = r == math.inf
            _first_bad(where, "range", not_finite & ~no_echo, _NOT_FINITE)
            _first_bad(where, "range", no_echo & ~(self.max_range > 0.0), NO_MAX_RANGE)
        _first_bad(where, "range", r <= 0.0, _NOT_POSITIVE)
        _first_bad(where, "range", (r > MAX_READING_RANGE) & (r < math.inf), _TOO_FAR)
        _first_bad(where, "sensor", self.sensor < 0, _NEGATIVE)
        _first_bad(where, "sensor", self.sensor > MAX_SENSOR, _TOO_LARGE)
        width = self.beam_width
        known = ~np.isnan(width)
        in_range = (width >= MIN_BEAM_WIDTH) & (width < math.pi)
        _first_bad(where, "beam_width", known & ~in_range, _BAD_BEAM)
        limit = self.max_range
        known = ~np.isnan(limit)
        if known.any():
            _first_bad(where, "max_range", known & ~((limit > 0.0) & (limit <= MAX_READING_RANGE)),
                       _BAD_MAX_RANGE)
            _first_bad(where, "range", (r > limit) & (r < math.inf), _BEYOND_MAX_RANGE)
        if n > 0:
            earlier = np.concatenate([[previous_t], self.t[:-1]])
            _first_bad(where, "t", self.t < earlier, _BACKWARDS)

    def __len__(self) -> int:
        return int(self.t.shape[0])

    @overload
    def __getitem__(self, index: int) -> Reading: ...
    @overload
    def __getitem__(self, index: slice | npt.NDArray[np.bool_] | IntArray) -> ReadingBatch: ...

    def __getitem__(
        self, index: int | slice | npt.NDArray[np.bool_] | IntArray
    ) -> Reading | ReadingBatch:
        if isinstance(index, int | np.integer):
            return Reading(
                float(self.t[index]), int(self.sensor[index]), float(self.x[index]),
                float(self.y[index]), float(self.theta[index]), float(self.range[index]),
                float(self.beam_width[index]), float(self.max_range[index]),
            )
        return ReadingBatch(**{f.name: getattr(self, f.name)[index] for f in fields(self)})

    def __iter__(self) -> Iterator[Reading]:
        return (self[i] for i in range(len(self)))

    @property
    def no_echo(self) -> npt.NDArray[np.bool_]:
        """Rows that heard nothing (``range`` is +inf), shape (n,)."""
        return np.asarray(self.range == math.inf)

    def with_max_range(self, default: float) -> ReadingBatch:
        """A copy where unknown (NaN) ``max_range`` values are ``default`` metres (a run-wide
        max range, e.g. the sensor's), not validated (:meth:`validate` checks it)."""
        limit = np.where(np.isnan(self.max_range), float(default), self.max_range)
        return ReadingBatch(**{**{f.name: getattr(self, f.name) for f in fields(self)},
                               "max_range": limit})

    def beam_widths(self, default: float) -> FloatArray:
        """Each row's beam width, or ``default`` radians where it carries none (NaN), shape
        (n,); a new array, the batch is not copied."""
        return np.where(np.isnan(self.beam_width), default, self.beam_width)

    def with_beam_width(self, default: float) -> ReadingBatch:
        """A copy where unknown (NaN) beam widths are replaced by ``default`` radians."""
        return ReadingBatch(**{**{f.name: getattr(self, f.name) for f in fields(self)},
                               "beam_width": self.beam_widths(default)})


@overload
def wrap_angle(angle: float) -> float: ...
@overload
def wrap_angle(angle: FloatArray) -> FloatArray: ...
def wrap_angle(angle: float | FloatArray) -> float | FloatArray:
    """``angle`` (radians; a float or an array of them) folded into [-π, π):
    ``(angle + π) mod 2π − π``.

    Examples
    --------
    >>> wrap_angle(3.0 * math.pi / 2.0) == -math.pi / 2.0
    True
    >>> wrap_angle(np.array([math.pi, -math.pi])).tolist() == [-math.pi, -math.pi]
    True
    """
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def check_reading(reading: Reading, reading_id: int, previous_t: float = -math.inf) -> None:
    """Check one reading as :meth:`ReadingBatch.validate` checks a row, with the same messages.

    ``t``, ``x``, ``y``, ``theta`` and ``range`` must be finite and within their bounds
    (|t| <= :data:`MAX_TIME` s, |x|, |y| <= :data:`MAX_POSITION` m, |theta| <=
    :data:`MAX_ANGLE` rad, ``0 < range <=`` :data:`MAX_READING_RANGE` m), ``sensor`` a whole
    number in [0, :data:`MAX_SENSOR`], ``beam_width`` in [``MIN_BEAM_WIDTH``, π) or NaN (the
    method's default), and ``t`` not earlier than ``previous_t`` (the previous reading's
    time). ``max_range`` is NaN (unknown) or in (0, :data:`MAX_READING_RANGE`]; ``range`` may
    be +inf (no echo) when it is known, and a finite ``range`` may not exceed it.

    Cheap: one chain of scalar comparisons in the common case (it runs once per echo); only a
    reading that fails it is examined field by field for the message.

    Raises
    ------
    ReadingsError
        Naming ``"reading {reading_id}"``, the column and the problem.

    Examples
    --------
    >>> check_reading(Reading(0.0, 0, 0.0, 0.0, 0.0, 1.0), 0)
    >>> check_reading(Reading(0.0, 0, 0.0, 0.0, 0.0, -1.0), 17)
    Traceback (most recent call last):
    ...
    sonarcarve.errors.ReadingsError: reading 17, column 'range' must be > 0
    >>> check_reading(Reading(0.0, 0, 0.0, 0.0, 1e20, 1.0), 18)
    Traceback (most recent call last):
    ...
    sonarcarve.errors.ReadingsError: reading 18, column 'theta' must lie within ±1,000,000 rad
    """
    try:
        t, sensor, x, y, theta, r, width, limit = reading
        if (isinstance(reading, Reading) and previous_t <= t and -MAX_TIME <= t <= MAX_TIME
                and 0.0 < r <= MAX_READING_RANGE
                and -MAX_POSITION <= x <= MAX_POSITION and -MAX_POSITION <= y <= MAX_POSITION
                and -MAX_ANGLE <= theta <= MAX_ANGLE and type(sensor) is int
                and 0 <= sensor <= MAX_SENSOR
                and (width != width or MIN_BEAM_WIDTH <= width < math.pi)
                and (limit != limit or r <= limit <= MAX_READING_RANGE)):
            return
    except (TypeError, ValueError):
        pass  # a field of the wrong type, or no 8-tuple: _check_types words it
    _explain_bad_reading(reading, _Where("", None, reading_id), previous_t)


def _check_types(reading: object, where: _Where) -> None:
    """:class:`ReadingTypeError` for something that is no :class:`Reading` or has a field that is no
    real number (``"abc"``, ``None``, ``1+2j``), naming the field.

    A bool is refused as the sensor only: an index given as ``True`` is almost always a mask or a
    flag passed in the wrong place, while a bool coordinate is the number Python says it is (the
    fast test of :func:`check_reading` and a batch's float columns take it as 0 or 1 too)."""
    if not isinstance(reading, Reading):
        size = f" of {len(reading)} values" if isinstance(reading, tuple) else ""
        msg = (f"{where.row(0)}: expected a Reading(t, sensor, x, y, theta, range[, "
               f"beam_width, max_range]), got {type(reading).__name__}{size}")
        raise ReadingTypeError(msg)
    for name, value in zip(Reading._fields, reading, strict=True):
        if (isinstance(value, bool) and name == "sensor") or not isinstance(value, numbers.Real):
            shown = repr(value) if len(repr(value)) <= 40 else repr(value)[:37] + "..."
            msg = (f"{where.row(0)}, column {name!r} must be a real number, got "
                   f"{type(value).__name__} {shown}")
            raise ReadingTypeError(msg)


def _explain_bad_reading(reading: Reading, where: _Where, previous_t: float) -> None:
    """Raise the error of the first problem of ``reading``; return if it has none after all.

    (The fast test in :func:`check_reading` also sends here a whole float or numpy sensor.)
    """
    _check_types(reading, where)
    for name, (bound, beyond) in _BOUNDS.items():
        value = getattr(reading, name)
        if not math.isfinite(value):
            _raise(where, 0, name, _NOT_FINITE)
        if abs(value) > bound:
            _raise(where, 0, name, beyond)
    limit = reading.max_range
    if not math.isfinite(reading.range):
        if reading.range != math.inf:
            _raise(where, 0, "range", _NOT_FINITE)
        if not limit > 0.0:
            _raise(where, 0, "range", NO_MAX_RANGE)
    if reading.range <= 0.0:
        _raise(where, 0, "range", _NOT_POSITIVE)
    if MAX_READING_RANGE < reading.range < math.inf:
        _raise(where, 0, "range", _TOO_FAR)
    sensor = reading.sensor
    try:
        whole = math.isfinite(sensor) and sensor == math.floor(sensor)
    except TypeError:
        whole = False
    if not whole:
        _raise(where, 0, "sensor", _NOT_WHOLE)
    if sensor < 0:
        _raise(where, 0, "sensor", _NEGATIVE)
    if sensor > MAX_SENSOR:
        _raise(where, 0, "sensor", _TOO_LARGE)
    width = reading.beam_width
    if not (math.isnan(width) or MIN_BEAM_WIDTH <= width < math.pi):
        _raise(where, 0, "beam_width", _BAD_BEAM)
    if not (math.isnan(limit) or 0.0 < limit <= MAX_READING_RANGE):
        _raise(where, 0, "max_range", _BAD_MAX_RANGE)
    if reading.range > limit and reading.range < math.inf:
        _raise(where, 0, "range", _BEYOND_MAX_RANGE)
    if reading.t < previous_t:
        _raise(where, 0, "t", _BACKWARDS)


#: The default of :attr:`ReadingBatch.max_range`: replaced by NaN per row on construction.
_NO_VALUES: FloatArray = np.zeros(0)
_NO_VALUES.flags.writeable = False


class _Where(NamedTuple):
    source: str
    first_line: int | None
    first_id: int | None = None

    def row(self, row: int) -> str:
        if self.first_id is not None:
            return f"reading {row + self.first_id}"
        if self.first_line is None:
            return f"{self.source}: row {row}"
        return f"{self.source}: line {row + self.first_line}"


def _sensor_indices(sensor: npt.ArrayLike, where: _Where) -> IntArray:
    """``sensor`` as int64, or :class:`ReadingsError` for a value that is no index.

    Checked before the cast because numpy's cast of a fractional, non-finite or huge value
    silently truncates or wraps (with a RuntimeWarning), which would report the wrong problem.
    """
    values = np.asarray(sensor).reshape(-1)
    if values.dtype.kind == "b":  # as check_reading refuses a bool sensor (see _check_types)
        msg = (f"{where.source}: column 'sensor' holds booleans (sensors are whole numbers; a "
               "mask passed in its place?)")
        raise ReadingsError(msg)
    if values.dtype.kind in "iu":
        _first_bad(where, "sensor", values < 0, _NEGATIVE)
        _first_bad(where, "sensor", values > MAX_SENSOR, _TOO_LARGE)
        return values.astype(np.int64)
    try:
        numbers = values.astype(np.float64)
    except (TypeError, ValueError):
        msg = f"{where.source}: column 'sensor' is not numeric (sensors are whole numbers)"
        raise ReadingsError(msg) from None
    with np.errstate(invalid="ignore"):
        _first_bad(where, "sensor", ~np.isfinite(numbers) | (numbers != np.floor(numbers)),
                   _NOT_WHOLE)
    _first_bad(where, "sensor", numbers < 0, _NEGATIVE)
    _first_bad(where, "sensor", numbers > MAX_SENSOR, _TOO_LARGE)
    return numbers.astype(np.int64)


def _first_bad(where: _Where, column: str, bad: npt.NDArray[np.bool_], problem: str) -> None:
    if bad.any():
        _raise(where, int(np.argmax(bad)), column, problem)


def _raise(where: _Where, row: int, column: str, problem: str) -> NoReturn:
    msg = f"{where.row(row)}, column {column!r} {problem}"
    raise ReadingsError(msg)


def reading_ids(n: int, ids: npt.ArrayLike | None = None) -> IntArray:
    """The reading id of each of ``n`` readings: ``ids`` (the input rows of readings a filter
    kept, so that the map's ids still point at the input) or, without them, 0 .. n - 1.

    Raises
    ------
    ReadingsError
        ``ids`` not one integer per reading, or not increasing (rows of one log, in order).
    """
    if ids is None:
        return np.arange(n, dtype=np.int64)
    given = np.asarray(ids)
    if given.shape != (n,) or not np.issubdtype(given.dtype, np.integer):
        msg = f"reading ids must be {n} integers, one per reading, got shape {given.shape}"
        raise ReadingsError(msg)
    if np.any(np.diff(given) <= 0):
        msg = "reading ids must increase (rows of one log, in order)"
        raise ReadingsError(msg)
    return given.astype(np.int64, copy=False)
