"""Sonar polling: position stamping without hardware support (paper, Appendix A).

Some robots (the paper's Scout2) only let the host *poll* each sensor's latest value: no firing
time stamps. Stamping a changed value with the pose at the poll time (:func:`naive_stamps`) puts
the arc where the robot was when the host looked, not where it was when the sensor fired, and it
misses every firing that happened to read the same value as before.

Sonar polling uses what is known about the firing schedule. Assumptions:

- **A1** the sensors fire one at a time in a known cyclic ``order``; the firing after sensor
  ``s`` comes between ``min_interval`` and ``timeout[s]`` seconds after ``s`` fired;
- **A2** a polled value is the value of that sensor's latest firing (it changes at the firing);
- **A3** no sensor fires twice between two successive polls (poll faster than once a cycle).

The poller keeps each sensor's last value and ``l``, the last firing known for sure, with an
interval ``[lo_l, hi_l]`` that must contain its time. At each poll (time ``p_j``, previous poll
``p_{j-1}``):

1. a sensor ``i`` whose value changed fired in ``(p_{j-1}, p_j]`` (A2, A3), and so did every
   sensor between ``l`` and ``i`` in firing order, changed or not;
2. the new firings ``l+1 .. i`` get intervals from the chain of difference constraints
   ``T_k + min_interval <= T_{k+1} <= T_k + timeout[s_k]`` with ``T_l ∈ [lo_l, hi_l]``,
   ``T_k <= p_j`` and ``T_k > p_{j-1}`` for the changed ones: a forward pass then a backward pass
   give the tightest bounds this chain allows;
3. if even the latest possible time of ``l`` plus its timeout has passed
   (``hi_l + timeout[s_l] <= p_j``), the next sensor must have fired: it becomes ``l``, with
   interval ``[lo_l + min_interval, hi_l + timeout[s_l]]``; repeat.

Each inferred firing is stamped at the middle of its interval; half the interval's width is an
upper bound on the stamp's error (under A1-A3), and :func:`position_error_bound` turns it into
metres given the robot's speed. The value of an inferred firing is the sensor's value at the
poll that revealed it (A2, A3).

Start-up: before ``l`` is known, a poll where one sensor changed anchors ``l``; a poll where
several changed anchors it only if one order of them fits in the poll interval (with
``min_interval > 0``); otherwise each changed sensor is stamped with ``[p_{j-1}, p_j]`` alone.
If the observations contradict A1-A3 (an empty interval), the poller counts it and starts over
from the same poll. A firing that A1-A3 do not reveal (after the last change, before its
predecessor's timeout ran out) is stamped later or, at the end of a log, not at all.

Limit: a changed sensor is taken to be the *first* firing of that sensor after ``l``. That is
true while fewer than ``n`` firings have happened since ``l``, which holds when the firing
interval is fixed (``timeout`` equal to it) and the host polls more often than once every
``n - 1`` firings. When intervals vary, each firing inferred from a timeout widens the interval
by ``timeout - min_interval``; after a long run of unchanged values the poller could lose count
of a whole cycle, and then its bounds can fail. Keep ``timeout - min_interval`` small.

The batch form (:func:`poll_readings`) takes a :class:`PolledLog`; :func:`simulate_polls` makes
one from true firing times and values, for tests and experiments.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from enum import IntEnum
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.errors import SonarcarveError
from sonarcarve.readings import ReadingBatch, wrap_angle
from sonarcarve.typing import FloatArray, IntArray

__all__ = [
    "FiringCause",
    "PolledLog",
    "PolledReadings",
    "PollingError",
    "SonarPoller",
    "StampedFiring",
    "StampedFirings",
    "heading_error_bound",
    "naive_firings",
    "naive_stamps",
    "poll_firings",
    "poll_readings",
    "position_error_bound",
    "readings_from_firings",
    "sequential_firings",
    "simulate_polls",
]

PoseFunction = Callable[[FloatArray], tuple[FloatArray, FloatArray, FloatArray]]

#: Slack for rounding when checking that an interval is not empty, seconds.
_EPS = 1e-9


class PollingError(SonarcarveError, ValueError):
    """Bad polling parameters or a malformed polled log."""


class FiringCause(IntEnum):
    """How the poller knows that a sensor fired."""

    CHANGED = 0  #: its polled value changed
    BETWEEN = 1  #: it lies between the last known firing and a changed sensor in firing order
    TIMEOUT = 2  #: its predecessor's timeout ran out


class StampedFiring(NamedTuple):
    """One firing the poller inferred.

    Attributes
    ----------
    sensor : int
        The sensor.
    value : float
        Its polled value (the caller's units).
    t : float
        Estimated firing time, seconds: the middle of ``[t_low, t_high]``.
    t_low, t_high : float
        The interval that must contain the true firing time (NaN: unknown).
    cause : FiringCause
        How the firing was inferred.
    poll : int
        0-based index of the poll that revealed it.
    x, y, heading : float
        Robot pose at ``t`` (metres, radians), interpolated between polls.
    """

    sensor: int
    value: float
    t: float
    t_low: float
    t_high: float
    cause: FiringCause
    poll: int
    x: float
    y: float
    heading: float

    @property
    def error_bound(self) -> float:
        """Upper bound on ``|t - true time|``, seconds: half the interval."""
        return 0.5 * (self.t_high - self.t_low)


@dataclass(frozen=True, eq=False)
class StampedFirings:
    """Many :class:`StampedFiring` as a struct of arrays, shape (n,) each, in inference order."""

    sensor: IntArray
    value: FloatArray
    t: FloatArray
    t_low: FloatArray
    t_high: FloatArray
    cause: npt.NDArray[np.int8]
    poll: IntArray
    x: FloatArray
    y: FloatArray
    heading: FloatArray

    @classmethod
    def from_firings(cls, firings: Sequence[StampedFiring]) -> StampedFirings:
        """Struct of arrays from a list of firings."""
        columns = list(zip(*firings, strict=True)) if firings else [()] * 10
        dtypes = {"sensor": np.int64, "cause": np.int8, "poll": np.int64}
        return cls(**{f.name: np.asarray(col, dtype=dtypes.get(f.name, np.float64))
                      for f, col in zip(fields(cls), columns, strict=True)})

    def __len__(self) -> int:
        return int(self.t.shape[0])

    @property
    def error_bound(self) -> FloatArray:
        """Upper bound on each stamp's error, seconds (NaN where unknown)."""
        return np.asarray(0.5 * (self.t_high - self.t_low))


def _as_timeouts(timeout: float | npt.ArrayLike, n_sensors: int) -> FloatArray:
    arr = np.asarray(timeout, dtype=np.float64)
    if arr.ndim == 0:
        arr = np.full(n_sensors, float(arr))
    arr = arr.reshape(-1)
    if arr.shape[0] < n_sensors:
        msg = f"timeout has {arr.shape[0]} entries, expected one per sensor (>= {n_sensors})"
        raise PollingError(msg)
    return arr


def _check_order(order: Sequence[int] | npt.ArrayLike) -> IntArray:
    arr = np.asarray(order, dtype=np.int64).reshape(-1)
    if arr.shape[0] == 0 or np.any(arr < 0) or len(np.unique(arr)) != arr.shape[0]:
        msg = f"firing order must list distinct sensor indices >= 0, got {arr.tolist()}"
        raise PollingError(msg)
    return arr


class SonarPoller:
    """Streaming sonar polling (Appendix A): feed polls, get stamped firings.

    Parameters
    ----------
    order : sequence of int
        Sensor indices in firing order (cyclic), each once.
    timeout : float or array-like, shape (n_sensors,)
        Longest time from a firing of sensor ``s`` to the next firing, seconds, per sensor index
        (a scalar applies to all).
    min_interval : float
        Shortest time between two successive firings, seconds (0 if unknown).

    Examples
    --------
    Two sensors, 0 then 1, each firing 0.1 s after the other; the host polls every 0.04 s:

    >>> poller = SonarPoller([0, 1], timeout=0.1)
    >>> poller.feed(0.00, [1.0, 2.0])
    []
    >>> f = poller.feed(0.04, [1.5, 2.0])  # sensor 0 changed: it fired in (0.00, 0.04]
    >>> [(s.sensor, s.t_low, s.t_high) for s in f]
    [(0, 0.0, 0.04)]
    >>> f = poller.feed(0.16, [1.5, 2.0])  # 0.04 + 0.1 <= 0.16: sensor 1 must have fired
    >>> [(s.sensor, s.cause.name, s.t_low, round(s.t_high, 9)) for s in f]
    [(1, 'TIMEOUT', 0.0, 0.14)]
    """

    def __init__(self, order: Sequence[int] | npt.ArrayLike, timeout: float | npt.ArrayLike,
                 min_interval: float = 0.0) -> None:
        self.order = _check_order(order)
        self.timeout = _as_timeouts(timeout, int(self.order.max()) + 1)
        used = self.timeout[self.order]
        if not np.all(np.isfinite(used) & (used > 0.0)):
            msg = f"timeouts must be finite and > 0 seconds, got {used.tolist()}"
            raise PollingError(msg)
        if not (math.isfinite(min_interval) and 0.0 <= min_interval <= float(used.min())):
            msg = (f"min_interval must lie in [0, smallest timeout {float(used.min())}] seconds, "
                   f"got {min_interval}")
            raise PollingError(msg)
        self.min_interval = float(min_interval)
        self._position = np.full(int(self.order.max()) + 1, -1, dtype=np.int64)
        self._position[self.order] = np.arange(self.order.shape[0])
        self._values: FloatArray | None = None
        self._polls = 0
        self._last_time = -math.inf
        self._anchor: int | None = None  # position in `order` of l, the last known firing
        self._lo = math.nan
        self._hi = math.nan
        self._track_t: list[float] = []
        self._track_pose: list[tuple[float, float, float]] = []
        #: Polls whose observations contradicted A1-A3 (the poller restarted there).
        self.contradictions = 0

    @property
    def last_known(self) -> tuple[int, float, float] | None:
        """``(sensor, lo, hi)`` of the last firing known for sure, or None before start-up."""
        if self._anchor is None:
            return None
        return int(self.order[self._anchor]), self._lo, self._hi

    def feed(self, t: float, values: npt.ArrayLike,
             pose: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> list[StampedFiring]:
        """Take one poll and return the firings it reveals, in firing order.

        Parameters
        ----------
        t : float
            Poll time, seconds, strictly after the previous poll.
        values : array-like, shape (n_sensors,)
            Every sensor's current value, indexed by sensor (NaN allowed: "no value yet").
        pose : (x, y, heading)
            Robot pose at ``t``, metres and radians.
        """
        new = np.asarray(values, dtype=np.float64).reshape(-1)
        self._check_poll(t, new)
        self._add_pose(t, pose)
        previous, p_prev = self._values, self._last_time
        self._values, self._last_time = new.copy(), float(t)
        self._polls += 1
        if previous is None:
            return []
        ordered_new, ordered_old = new[self.order], previous[self.order]
        same = (ordered_new == ordered_old) | (np.isnan(ordered_new) & np.isnan(ordered_old))
        changed = np.flatnonzero(~same)  # positions in `order`
        spans: list[tuple[int, int, float, float, FiringCause]] = []
        if len(changed):
            spans = self._chain(changed, p_prev, float(t))
        spans += self._timeouts(float(t), {pos for pos, *_ in spans})
        self._trim_track()
        return [self._firing(pos, lo, hi, cause, new) for pos, _, lo, hi, cause in spans]

    # -- inference ----------------------------------------------------------------------------

    def _chain(self, changed: IntArray, p_prev: float, t: float,
               ) -> list[tuple[int, int, float, float, FiringCause]]:
        """Firings revealed by changed sensors: (position, offset, lo, hi, cause) each."""
        n = self.order.shape[0]
        if self._anchor is not None:
            offsets = (changed - self._anchor) % n
            offsets[offsets == 0] = n  # l's own sensor changed again: a whole cycle
            chain = self._bounded_chain(self._anchor, int(offsets.max()), set(offsets.tolist()),
                                        self._lo, self._hi, p_prev, t)
            if chain is not None:
                return chain
            self.contradictions += 1
            self._anchor = None
        start = self._unambiguous_start(changed, t - p_prev)
        if start is None:
            # Order unknown: each changed sensor fired in (p_prev, t], nothing more is certain.
            return [(int(pos), 0, p_prev, t, FiringCause.CHANGED) for pos in changed]
        offsets = (changed - start) % n
        chain = self._bounded_chain(start - 1, int(offsets.max()) + 1,
                                    set((offsets + 1).tolist()), -math.inf, math.inf, p_prev, t)
        if chain is None:  # contradicts min_interval: fall back to the bare intervals
            self.contradictions += 1
            return [(int(pos), 0, p_prev, t, FiringCause.CHANGED) for pos in changed]
        return chain

    def _unambiguous_start(self, changed: IntArray, interval: float) -> int | None:
        """Position of the first firing among ``changed`` if only one firing order of them fits
        in one poll interval (A3 and ``min_interval``); None if ambiguous."""
        n = self.order.shape[0]
        if len(changed) == 1:
            return int(changed[0])
        if self.min_interval <= 0.0:
            return None
        most = math.floor(interval / self.min_interval + _EPS) + 1  # firings that fit
        fits = [int(s) for s in changed if int(((changed - s) % n).max()) + 1 <= most]
        return fits[0] if len(fits) == 1 else None

    def _bounded_chain(self, anchor: int, length: int, changed_offsets: set[int], lo0: float,
                       hi0: float, p_prev: float, t: float,
                       ) -> list[tuple[int, int, float, float, FiringCause]] | None:
        """Bounds of firings ``anchor+1 .. anchor+length`` (positions mod n) by a forward and a
        backward pass over the chain's difference constraints; None if any interval is empty.
        Moves the anchor to the chain's last firing."""
        n = self.order.shape[0]
        g = self.min_interval
        pos = [(anchor + k) % n for k in range(length + 1)]
        tau = [float(self.timeout[self.order[p]]) for p in pos]
        lo = [lo0] + [p_prev if k in changed_offsets else -math.inf for k in range(1, length + 1)]
        hi = [hi0] + [t] * length
        for k in range(1, length + 1):
            lo[k] = max(lo[k], lo[k - 1] + g)
            hi[k] = min(hi[k], hi[k - 1] + tau[k - 1])
        for k in range(length - 1, 0, -1):
            hi[k] = min(hi[k], hi[k + 1] - g)
            lo[k] = max(lo[k], lo[k + 1] - tau[k])
        if any(lo[k] > hi[k] + _EPS for k in range(1, length + 1)):
            return None
        self._anchor, self._lo, self._hi = pos[length], lo[length], hi[length]
        return [(pos[k], k, lo[k], hi[k],
                 FiringCause.CHANGED if k in changed_offsets else FiringCause.BETWEEN)
                for k in range(1, length + 1)]

    def _timeouts(self, t: float, emitted: set[int],
                  ) -> list[tuple[int, int, float, float, FiringCause]]:
        """Firings that must have happened because their predecessor's timeout ran out."""
        out: list[tuple[int, int, float, float, FiringCause]] = []
        n = self.order.shape[0]
        while self._anchor is not None:
            tau = float(self.timeout[self.order[self._anchor]])
            if self._hi + tau > t:
                break
            nxt = (self._anchor + 1) % n
            if nxt in emitted:  # it would be its second firing since the last poll (A3)
                break
            emitted.add(nxt)
            self._anchor, self._lo, self._hi = nxt, self._lo + self.min_interval, self._hi + tau
            out.append((nxt, 0, self._lo, self._hi, FiringCause.TIMEOUT))
        return out

    # -- bookkeeping --------------------------------------------------------------------------

    def _check_poll(self, t: float, values: FloatArray) -> None:
        if not math.isfinite(t) or t <= self._last_time:
            msg = f"poll {self._polls}: time {t} is not after the previous poll {self._last_time}"
            raise PollingError(msg)
        need = self._position.shape[0]
        if values.shape[0] < need or (self._values is not None
                                      and values.shape[0] != self._values.shape[0]):
            expected = need if self._values is None else self._values.shape[0]
            msg = f"poll {self._polls}: {values.shape[0]} values, expected {expected}"
            raise PollingError(msg)

    def _add_pose(self, t: float, pose: tuple[float, float, float]) -> None:
        x, y, heading = (float(v) for v in pose)
        if self._track_pose:  # unwrap so that interpolation turns the short way
            heading = self._track_pose[-1][2] + wrap_angle(heading - self._track_pose[-1][2])
        self._track_t.append(t)
        self._track_pose.append((x, y, heading))

    def _trim_track(self) -> None:
        # Future stamps are never earlier than min(lo_l, last poll): keep one pose before that.
        oldest = self._last_time if self._anchor is None else min(self._lo, self._last_time)
        cut = int(np.searchsorted(self._track_t, oldest, side="right")) - 1
        if cut > 0:
            del self._track_t[:cut]
            del self._track_pose[:cut]

    def _firing(self, pos: int, lo: float, hi: float, cause: FiringCause,
                values: FloatArray) -> StampedFiring:
        sensor = int(self.order[pos])
        stamp = 0.5 * (lo + hi)
        track = np.asarray(self._track_pose)
        x, y, heading = (float(np.interp(stamp, self._track_t, track[:, i])) for i in range(3))
        return StampedFiring(sensor, float(values[sensor]), stamp, lo, hi, cause,
                             self._polls - 1, x, y, heading)


# -- batch forms -----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class PolledLog:
    """What a polling host records: every sensor's value and the robot pose at each poll.

    Attributes
    ----------
    t : ndarray, shape (m,)
        Poll times, seconds, strictly increasing.
    values : ndarray, shape (m, n_sensors)
        Each sensor's current value at each poll (NaN: no value yet).
    x, y, heading : ndarray, shape (m,)
        Robot pose at each poll, metres and radians.
    """

    t: FloatArray
    values: FloatArray
    x: FloatArray
    y: FloatArray
    heading: FloatArray

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=np.float64).reshape(-1)
        values = np.asarray(self.values, dtype=np.float64)
        if values.ndim != 2 or values.shape[0] != t.shape[0]:
            msg = f"values must have shape (polls, sensors) = ({t.shape[0]}, n), got {values.shape}"
            raise PollingError(msg)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "values", values)
        for name in ("x", "y", "heading"):
            arr = np.asarray(getattr(self, name), dtype=np.float64).reshape(-1)
            if arr.shape != t.shape:
                msg = f"{name} has {arr.shape[0]} polls, expected {t.shape[0]}"
                raise PollingError(msg)
            object.__setattr__(self, name, arr)
        bad = np.flatnonzero(~np.isfinite(t[1:]) | (np.diff(t) <= 0.0))
        if t.shape[0] and not np.isfinite(t[0]):
            bad = np.array([-1])
        if bad.size:
            msg = f"poll {int(bad[0]) + 1}: poll times must be finite and strictly increasing"
            raise PollingError(msg)

    def __len__(self) -> int:
        return int(self.t.shape[0])


@dataclass(frozen=True, eq=False)
class PolledReadings:
    """Readings made from stamped firings.

    Attributes
    ----------
    batch : ReadingBatch
        One reading per firing with an echo, sorted by stamp.
    stamp_error : ndarray, shape (len(batch),)
        Upper bound on each reading's time-stamp error, seconds (NaN: unknown, naive stamps).
    firing : ndarray of int64, shape (len(batch),)
        Index of each reading's firing in the :class:`StampedFirings` it came from.
    """

    batch: ReadingBatch
    stamp_error: FloatArray
    firing: IntArray

    def stamp_bounds(self, speed: float, *, turn_rate: float = 0.0,
                     sensor_offset: float = 0.0) -> tuple[float, float]:
        """The run-wide stamping bounds of these readings for a method's certainty (section 6:
        "upper bounds on position stamping error (Appendix A)"): the sensor origin's position
        error, metres, and its axis error, radians, from the largest stamp error bound
        (:func:`position_error_bound`, :func:`heading_error_bound`). They are evidence
        carving's ``MethodConfig(stamp_error=..., stamp_heading_error=...)``; the largest,
        because one value stands for the run (docs/evidence-carving.md, "Certainty per
        point").

        Raises
        ------
        PollingError
            No reading has a bound (naive stamps give none, or there are no readings).

        Examples
        --------
        One reading stamped to within 0.1 s, the robot at up to 0.5 m/s and 2 rad/s, the
        sensor 0.2 m from its centre: 0.05 + 0.04 m and 0.2 rad.

        >>> from sonarcarve.readings import ReadingBatch
        >>> one = ReadingBatch.from_arrays(t=[0.0], sensor=[0], x=[0.0], y=[0.0],
        ...                                theta=[0.0], range=[1.0])
        >>> polled = PolledReadings(one, np.array([0.1]), np.array([0]))
        >>> [round(b, 6) for b in polled.stamp_bounds(0.5, turn_rate=2.0, sensor_offset=0.2)]
        [0.09, 0.2]
        """
        for name, value in (("speed", speed), ("turn_rate", turn_rate),
                            ("sensor_offset", sensor_offset)):
            if not (math.isfinite(value) and value >= 0.0):
                msg = f"{name} must be finite and >= 0 (the largest), got {value!r}"
                raise PollingError(msg)
        known = self.stamp_error[~np.isnan(self.stamp_error)]  # NaN: unknown; inf stays
        if known.size == 0:
            msg = ("these readings have no stamp error bound (naive stamps give none): poll "
                   "them with poll_readings")
            raise PollingError(msg)
        worst = float(known.max())
        if not (math.isfinite(worst) and worst >= 0.0):
            msg = f"a stamp error bound is {worst!r} seconds: no finite bound holds for the run"
            raise PollingError(msg)
        position = position_error_bound(worst, speed, turn_rate=turn_rate,
                                        sensor_offset=sensor_offset)
        return float(position), float(heading_error_bound(worst, turn_rate))


def poll_firings(log: PolledLog, order: Sequence[int] | npt.ArrayLike,
                 timeout: float | npt.ArrayLike, *, min_interval: float = 0.0) -> StampedFirings:
    """Run a :class:`SonarPoller` over a whole polled log (same parameters)."""
    poller = SonarPoller(order, timeout, min_interval)
    out: list[StampedFiring] = []
    for j in range(len(log)):
        out += poller.feed(float(log.t[j]), log.values[j],
                           (float(log.x[j]), float(log.y[j]), float(log.heading[j])))
    return StampedFirings.from_firings(out)


def naive_firings(log: PolledLog) -> StampedFirings:
    """Stamp every changed value with its poll time and pose (no bounds: NaN intervals).

    This is what a host does without sonar polling: firings that repeat a value are missed
    and the stamp is late by up to a poll interval (more, with slow hosts).
    """
    values = log.values
    same = (values[1:] == values[:-1]) | (np.isnan(values[1:]) & np.isnan(values[:-1]))
    poll, sensor = np.nonzero(~same)
    poll = poll + 1
    n = poll.shape[0]
    return StampedFirings(
        sensor=sensor.astype(np.int64), value=values[poll, sensor], t=log.t[poll],
        t_low=np.full(n, math.nan), t_high=np.full(n, math.nan),
        cause=np.full(n, FiringCause.CHANGED, dtype=np.int8), poll=poll.astype(np.int64),
        x=log.x[poll], y=log.y[poll], heading=log.heading[poll],
    )


def readings_from_firings(
    firings: StampedFirings,
    mounts: npt.ArrayLike,
    *,
    value_scale: float = 1.0,
    no_echo: float | None = None,
    beam_width: float = math.nan,
) -> PolledReadings:
    """Readings in the world frame from stamped firings and the sensor mounts.

    Parameters
    ----------
    firings : StampedFirings
        From :func:`poll_firings` or :func:`naive_firings`.
    mounts : array-like, shape (n_sensors, 3)
        Per sensor index: ``(x, y, bearing)`` in the robot frame (metres, x forward, y left;
        radians from the heading).
    value_scale : float
        Metres per value unit (0.001 for millimetres, 0.0254 for inches).
    no_echo : float, optional
        The value meaning "no echo"; such firings (and NaN or non-positive values) make no
        reading.
    beam_width : float
        φ recorded with each reading, radians (NaN: the method's default).
    """
    mount = np.asarray(mounts, dtype=np.float64).reshape(-1, 3)
    if len(firings) and int(firings.sensor.max()) >= mount.shape[0]:
        msg = f"mounts has {mount.shape[0]} rows but sensor {int(firings.sensor.max())} fired"
        raise PollingError(msg)
    echo = np.isfinite(firings.value) & (firings.value > 0.0)
    if no_echo is not None:
        echo &= firings.value != no_echo
    index = np.flatnonzero(echo)
    index = index[np.argsort(firings.t[index], kind="stable")]
    s = firings.sensor[index]
    h = firings.heading[index]
    mx, my, bearing = mount[s, 0], mount[s, 1], mount[s, 2]
    batch = ReadingBatch.from_arrays(
        t=firings.t[index], sensor=s,
        x=firings.x[index] + np.cos(h) * mx - np.sin(h) * my,
        y=firings.y[index] + np.sin(h) * mx + np.cos(h) * my,
        theta=h + bearing, range=firings.value[index] * value_scale,
        beam_width=np.full(index.shape[0], beam_width), source="polled readings",
    )
    return PolledReadings(batch=batch, stamp_error=firings.error_bound[index],
                          firing=index.astype(np.int64))


def poll_readings(
    log: PolledLog,
    order: Sequence[int] | npt.ArrayLike,
    timeout: float | npt.ArrayLike,
    mounts: npt.ArrayLike,
    *,
    min_interval: float = 0.0,
    value_scale: float = 1.0,
    no_echo: float | None = None,
    beam_width: float = math.nan,
) -> PolledReadings:
    """Sonar polling over a polled log: readings plus a bound on each one's stamp error.

    Parameters are those of :class:`SonarPoller` and :func:`readings_from_firings`.
    """
    firings = poll_firings(log, order, timeout, min_interval=min_interval)
    return readings_from_firings(firings, mounts, value_scale=value_scale, no_echo=no_echo,
                                 beam_width=beam_width)


def naive_stamps(
    log: PolledLog,
    mounts: npt.ArrayLike,
    *,
    value_scale: float = 1.0,
    no_echo: float | None = None,
    beam_width: float = math.nan,
) -> PolledReadings:
    """Readings stamped the naive way: the pose at the poll where a value changed.

    ``stamp_error`` is NaN: the naive method gives no bound.
    """
    return readings_from_firings(naive_firings(log), mounts, value_scale=value_scale,
                                 no_echo=no_echo, beam_width=beam_width)


def position_error_bound(stamp_error: npt.ArrayLike, speed: float, *, turn_rate: float = 0.0,
                         sensor_offset: float = 0.0) -> FloatArray:
    """Bound on a sensor origin's position error from a stamp error bound, metres.

    ``speed * dt + |turn_rate| * dt * sensor_offset``: the robot centre moves at most
    ``speed * dt`` and a sensor ``sensor_offset`` metres from the centre swings at most that
    times the heading change.

    Parameters
    ----------
    stamp_error : array-like
        Stamp error bounds, seconds.
    speed : float
        Largest robot speed, metres per second.
    turn_rate : float
        Largest turn rate, radians per second.
    sensor_offset : float
        Distance of the sensor from the robot centre, metres.

    Examples
    --------
    >>> float(position_error_bound(0.02, speed=0.5))
    0.01
    """
    dt = np.asarray(stamp_error, dtype=np.float64)
    return np.asarray(dt * (abs(speed) + abs(turn_rate) * abs(sensor_offset)))


def heading_error_bound(stamp_error: npt.ArrayLike, turn_rate: float) -> FloatArray:
    """Bound on a sensor axis's error from a stamp error bound, radians (``|turn_rate| * dt``)."""
    return np.asarray(np.asarray(stamp_error, dtype=np.float64) * abs(turn_rate))


# -- simulation -------------------------------------------------------------------------------


def sequential_firings(
    order: Sequence[int] | npt.ArrayLike,
    interval: float | npt.ArrayLike,
    count: int,
    *,
    t0: float = 0.0,
    jitter: float = 0.0,
    rng: np.random.Generator | None = None,
) -> tuple[FloatArray, IntArray]:
    """True firing times of sensors firing one after another in ``order``, cyclically.

    The firing after sensor ``s`` comes ``interval[s] - u`` seconds later, ``u`` uniform in
    ``[0, jitter]`` (0 without jitter: a fixed period). So A1 holds with
    ``timeout = interval`` and ``min_interval = min(interval) - jitter``.

    Returns
    -------
    t : ndarray, shape (count,)
        Firing times, seconds, starting at ``t0``.
    sensor : ndarray of int64, shape (count,)
        Sensor of each firing.
    """
    seq = _check_order(order)
    gaps = _as_timeouts(interval, int(seq.max()) + 1)
    sensor = seq[np.arange(count) % seq.shape[0]]
    step = gaps[sensor]
    if jitter > 0.0:
        step = step - (rng or np.random.default_rng()).uniform(0.0, jitter, count)
    if np.any(step[:-1] <= 0.0):
        msg = "intervals minus jitter must stay > 0 seconds"
        raise PollingError(msg)
    t = t0 + np.concatenate(([0.0], np.cumsum(step[:-1])))
    return t, sensor


def simulate_polls(
    firing_t: npt.ArrayLike,
    firing_sensor: npt.ArrayLike,
    firing_value: npt.ArrayLike,
    poll_t: npt.ArrayLike,
    n_sensors: int,
    *,
    pose_at: PoseFunction | None = None,
) -> PolledLog:
    """What a host polling at ``poll_t`` sees: each sensor's latest value (A2), NaN before its
    first firing.

    Parameters
    ----------
    firing_t, firing_sensor, firing_value : array-like, shape (k,)
        True firings, in time order: time (s), sensor, value. A value equal to the sensor's
        previous one produces no change to see.
    poll_t : array-like, shape (m,)
        Poll times, seconds, strictly increasing.
    n_sensors : int
        Number of sensors (columns of the log).
    pose_at : callable, optional
        ``times -> (x, y, heading)`` arrays (for example ``Trajectory.pose_at``); default: the
        robot stands at the origin facing +x.
    """
    ft = np.asarray(firing_t, dtype=np.float64).reshape(-1)
    fs = np.asarray(firing_sensor, dtype=np.int64).reshape(-1)
    fv = np.asarray(firing_value, dtype=np.float64).reshape(-1)
    pt = np.asarray(poll_t, dtype=np.float64).reshape(-1)
    if not ft.shape == fs.shape == fv.shape:
        msg = "firing times, sensors and values must have the same length"
        raise PollingError(msg)
    if np.any(np.diff(ft) < 0.0):
        msg = "firing times must be in time order"
        raise PollingError(msg)
    values = np.full((pt.shape[0], n_sensors), math.nan)
    for s in range(n_sensors):
        mine = fs == s
        latest = np.searchsorted(ft[mine], pt, side="right") - 1  # A2: latest firing <= poll
        seen = latest >= 0
        values[seen, s] = fv[mine][latest[seen]]
    if pose_at is None:
        zeros = np.zeros(pt.shape[0])
        return PolledLog(t=pt, values=values, x=zeros, y=zeros.copy(), heading=zeros.copy())
    x, y, heading = pose_at(pt)
    return PolledLog(t=pt, values=values, x=x, y=y, heading=heading)
