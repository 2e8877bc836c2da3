"""Sonar ring descriptions: where each sensor sits on the robot, how it fires, what it measures.

A robot is described in YAML (built-in ones live in ``sonarcarve/robots/``)::

    name: scout2
    description: free text
    robot_radius: 0.205        # m, body radius
    range_resolution: 0.0254   # m, the range quantum (0: not quantised)
    min_range: 0.15            # m, echoes closer than this are not heard (blanking)
    max_range: 6.477           # m, echoes farther than this time out
    firing_period: 0.04        # s between two successive firings of the ring
    firing_order: [1, 0]       # optional: each sensor once, in firing order (default: as listed)
    beam_width_deg: 22.5       # default beam width φ of every sensor, degrees
    sensors:                   # one entry per sensor, in index order
      - {x: 0.205, y: 0.0, bearing_deg: 0.0}                        # robot frame, m and degrees
      - {x: 0.0, y: 0.205, bearing_deg: 90.0, beam_width_deg: 15.0} # per-sensor beam override

Robot frame: x forward, y to the left, bearings counter-clockwise from x. Degrees appear only
in the file (``_deg`` fields) because people write them; everything in memory is radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import numpy.typing as npt

from sonarcarve.constants import MIN_BEAM_WIDTH
from sonarcarve.errors import SonarcarveError
from sonarcarve.io.errors import MAX_YAML_BYTES, finite_number, parse_yaml, read_text, shorten
from sonarcarve.typing import FloatArray, IntArray

__all__ = [
    "BUILTIN_ROBOTS",
    "FIRING_PERIOD_RANGE",
    "MAX_FIRINGS",
    "MAX_LENGTH",
    "MAX_SENSORS",
    "RobotDescription",
    "RobotError",
    "load_robot",
    "parse_robot",
]


#: Names of the robots shipped with the package (``sonarcarve/robots/<name>.yaml``).
BUILTIN_ROBOTS = ("car-parking-12", "p3dx", "p3dx-front", "roboND-8", "scout2")
#: Most firings :meth:`RobotDescription.firing_schedule` makes: 11 hours of a ring firing every
#: 0.04 s. The simulator holds every ray of every firing at once (31 rays, about 1 kB a
#: firing), so this bounds a simulation's memory to about a gigabyte.
MAX_FIRINGS = 1_000_000
#: Most sensors on one ring (real rings have 8 to 48).
MAX_SENSORS = 1024
#: Documented ranges of a robot's numbers, checked when a description is built (file or API):
#: firing period in seconds, lengths in metres (ranges, body radius, sensor mounts).
FIRING_PERIOD_RANGE = (1e-4, 3600.0)
MAX_LENGTH = 1000.0
_MIN_BEAM_DEGREES = math.degrees(MIN_BEAM_WIDTH)  # for messages

_TOP_FIELDS = {
    "name", "description", "robot_radius", "range_resolution", "min_range", "max_range",
    "firing_period", "firing_order", "beam_width_deg", "sensors",
}
_SENSOR_FIELDS = {"x", "y", "bearing_deg", "beam_width_deg"}


class RobotError(SonarcarveError, ValueError):
    """A robot description that cannot be loaded: unknown name, bad file, bad field."""


@dataclass(frozen=True, eq=False)
class RobotDescription:
    """A sonar ring: sensor mounts (struct of arrays, shape (n,)) and firing parameters.

    Attributes
    ----------
    name : str
        Built-in name or file the description came from.
    mount_x, mount_y : ndarray, shape (n,)
        Sensor positions in the robot frame (x forward, y left), metres.
    bearing : ndarray, shape (n,)
        Sensor axes relative to the robot heading, radians counter-clockwise.
    beam_width : ndarray, shape (n,)
        Full beam width φ of each sensor, radians in (0, π).
    firing_order : ndarray of int64, shape (n,)
        Sensor indices in the order the ring fires them, each sensor once; the sequence
        repeats.
    firing_period : float
        Seconds between two successive firings (one sensor at a time).
    range_resolution : float
        Range quantum, metres; 0 means ranges are not quantised.
    min_range, max_range : float
        Shortest and longest range the sensors report, metres.
    robot_radius : float
        Radius of the robot body, metres.
    description : str
        Free text: where the numbers come from.
    source : str
        The file (or built-in name) it was loaded from; names the place in errors.
    """

    name: str
    mount_x: FloatArray
    mount_y: FloatArray
    bearing: FloatArray
    beam_width: FloatArray
    firing_order: IntArray
    firing_period: float
    range_resolution: float
    min_range: float
    max_range: float
    robot_radius: float
    description: str = ""
    source: str = ""

    def __post_init__(self) -> None:
        for field in ("mount_x", "mount_y", "bearing", "beam_width"):
            value = np.asarray(getattr(self, field), dtype=np.float64).reshape(-1)
            object.__setattr__(self, field, value)
        order = np.asarray(self.firing_order, dtype=np.int64).reshape(-1)
        object.__setattr__(self, "firing_order", order)
        n = self.mount_x.shape[0]
        where = self.source or self.name
        if n == 0:
            _fail(where, "sensors", "needs at least one sensor")
        for field in ("mount_y", "bearing", "beam_width"):
            if getattr(self, field).shape != (n,):
                _fail(where, field, f"has {getattr(self, field).size} values, expected {n}")
        if n > MAX_SENSORS:
            _fail(where, "sensors", f"has {n} sensors, more than the limit of {MAX_SENSORS}")
        if not np.all(np.isfinite(np.concatenate([self.mount_x, self.mount_y, self.bearing]))):
            _fail(where, "sensors", "positions and bearings must be finite")
        if np.any(np.abs(np.concatenate([self.mount_x, self.mount_y])) > MAX_LENGTH):
            _fail(where, "sensors", f"positions must lie within ±{MAX_LENGTH:g} m of the centre")
        if np.any(np.abs(self.bearing) > 2.0 * math.pi):
            _fail(where, "sensors", "bearings must lie in [-360, 360] degrees")
        if not np.all((self.beam_width >= MIN_BEAM_WIDTH) & (self.beam_width < math.pi)):
            _fail(where, "beam_width", f"must lie in [{_MIN_BEAM_DEGREES:g}, 180) degrees")
        if order.size == 0 or np.any((order < 0) | (order >= n)):
            _fail(where, "firing_order", f"must list sensor indices in 0..{n - 1}")
        _check_firing_order(where, order, n)
        _check_positive(where, "firing_period", self.firing_period, strict=True)
        _check_positive(where, "range_resolution", self.range_resolution, strict=False)
        _check_positive(where, "min_range", self.min_range, strict=False)
        _check_positive(where, "max_range", self.max_range, strict=True)
        _check_positive(where, "robot_radius", self.robot_radius, strict=False)
        low, high = FIRING_PERIOD_RANGE
        if not low <= self.firing_period <= high:
            _fail(where, "firing_period", f"must lie in [{low:g}, {high:g}] s, got "
                                          f"{self.firing_period:g}")
        for field in ("range_resolution", "min_range", "max_range", "robot_radius"):
            if getattr(self, field) > MAX_LENGTH:
                _fail(where, field, f"must be at most {MAX_LENGTH:g} m, got "
                                    f"{getattr(self, field):g}")
        if not self.min_range < self.max_range:
            _fail(where, "min_range", f"{self.min_range} must be below max_range {self.max_range}")

    @property
    def n_sensors(self) -> int:
        """Number of sensors on the ring."""
        return int(self.mount_x.shape[0])

    @property
    def cycle_time(self) -> float:
        """Seconds for the ring to fire its whole ``firing_order`` once."""
        return self.firing_period * int(self.firing_order.shape[0])

    def firing_schedule(self, t_start: float, t_end: float) -> tuple[FloatArray, IntArray]:
        """Times and sensors of every firing in ``[t_start, t_end]``.

        Firing ``k`` happens at ``t_start + k * firing_period`` and uses sensor
        ``firing_order[k % len(firing_order)]``.

        Raises
        ------
        RobotError
            If the span holds more than :data:`MAX_FIRINGS` firings, or is not finite.

        Returns
        -------
        times : ndarray, shape (k,)
            Firing times, seconds, increasing.
        sensors : ndarray of int64, shape (k,)
            Sensor index of each firing.
        """
        span = (t_end - t_start) / self.firing_period
        if not math.isfinite(span) or span + 1 > MAX_FIRINGS:
            where = self.source or self.name
            msg = (f"{where}: firing every {self.firing_period:g} s from t = {t_start:g} s to "
                   f"{t_end:g} s takes {span + 1:.4g} firings, more than the limit of "
                   f"{MAX_FIRINGS:,} (MAX_FIRINGS)")
            raise RobotError(msg)
        count = math.floor(span + 1e-9) + 1
        k = np.arange(max(count, 0), dtype=np.int64)
        times = np.asarray(t_start + k * self.firing_period, dtype=np.float64)
        return times, np.asarray(self.firing_order[k % self.firing_order.shape[0]])

    def sensor_poses(
        self, x: npt.ArrayLike, y: npt.ArrayLike, heading: npt.ArrayLike, sensor: npt.ArrayLike
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """World poses of sensors given robot poses (all arguments broadcast together).

        Parameters
        ----------
        x, y, heading : array-like
            Robot centre (m) and heading (rad) in the world frame.
        sensor : array-like of int
            Sensor indices.

        Returns
        -------
        sx, sy, theta : ndarray
            Sensor origin (m) and axis (rad, counter-clockwise from +x) in the world frame.
        """
        s = np.asarray(sensor, dtype=np.int64)
        h = np.asarray(heading, dtype=np.float64)
        c, si = np.cos(h), np.sin(h)
        mx, my = self.mount_x[s], self.mount_y[s]
        sx = np.asarray(x, dtype=np.float64) + c * mx - si * my
        sy = np.asarray(y, dtype=np.float64) + si * mx + c * my
        return np.asarray(sx), np.asarray(sy), np.asarray(h + self.bearing[s])


def load_robot(spec: str | Path) -> RobotDescription:
    """A robot by built-in name (see :data:`BUILTIN_ROBOTS`) or from a YAML file.

    Raises
    ------
    RobotError
        One line naming the file (or the unknown name) and the offending field.
    """
    text_spec = str(spec)
    if text_spec in BUILTIN_ROBOTS and not Path(text_spec).exists():
        source = resources.files("sonarcarve").joinpath("robots", f"{text_spec}.yaml")
        return parse_robot(source.read_text(encoding="utf-8"), text_spec)
    path = Path(spec)
    looks_like_name = path.suffix.lower() not in {".yaml", ".yml"} and path.parent == Path()
    if looks_like_name and not path.exists():
        msg = (f"unknown robot {text_spec!r}; built-in robots: {', '.join(BUILTIN_ROBOTS)} "
               "(or give a YAML file)")
        raise RobotError(msg)
    return parse_robot(read_text(path, RobotError, MAX_YAML_BYTES), str(path))


def parse_robot(text: str, source: str = "robot") -> RobotDescription:
    """A robot from YAML text; ``source`` names it in errors (file name or built-in name)."""
    data = parse_yaml(text, source, RobotError)
    if not isinstance(data, dict):
        msg = f"{source}: expected a mapping of fields at the top level"
        raise RobotError(msg)
    unknown = sorted(set(map(str, data)) - _TOP_FIELDS)
    if unknown:
        _fail(source, shorten(unknown[0], 40),
              f"unknown field (known: {', '.join(sorted(_TOP_FIELDS))})")
    sensors = data.get("sensors")
    if not isinstance(sensors, list) or not sensors:
        _fail(source, "sensors", "must be a non-empty list of {x, y, bearing_deg}")
    if len(sensors) > MAX_SENSORS:
        _fail(source, "sensors", f"has {len(sensors)} sensors, more than the limit of "
                                 f"{MAX_SENSORS}")
    default_width = _number(source, "beam_width_deg", data.get("beam_width_deg", 22.5))
    mounts = [_sensor(source, i, entry, default_width) for i, entry in enumerate(sensors)]
    order = data.get("firing_order", list(range(len(mounts))))
    if not isinstance(order, list) or not all(
        isinstance(i, int) and not isinstance(i, bool) for i in order
    ):
        _fail(source, "firing_order", "must be a list of sensor indices")
    if len(order) > MAX_SENSORS:
        _fail(source, "firing_order", f"has {len(order)} entries, more than the limit of "
                                      f"{MAX_SENSORS}")
    if any(not 0 <= i < len(mounts) for i in order):  # before numpy, which overflows on 10**20
        _fail(source, "firing_order", f"must list sensor indices in 0..{len(mounts) - 1}")
    fields = {name: _number(source, name, _required(source, data, name)) for name in
              ("robot_radius", "range_resolution", "min_range", "max_range", "firing_period")}
    return RobotDescription(
        name=str(data.get("name", source)),
        mount_x=np.array([m[0] for m in mounts]),
        mount_y=np.array([m[1] for m in mounts]),
        bearing=np.radians([m[2] for m in mounts]),
        beam_width=np.radians([m[3] for m in mounts]),
        firing_order=np.array(order, dtype=np.int64),
        description=str(data.get("description", "")).strip(),
        source=source,
        **fields,
    )


def _sensor(source: str, index: int, entry: object,
            default_width: float) -> tuple[float, float, float, float]:
    field = f"sensors[{index}]"
    if not isinstance(entry, dict):
        _fail(source, field, "must be a mapping {x, y, bearing_deg[, beam_width_deg]}")
    unknown = sorted(set(map(str, entry)) - _SENSOR_FIELDS)
    if unknown:
        _fail(source, f"{field}.{shorten(unknown[0], 40)}",
              f"unknown field (known: {', '.join(sorted(_SENSOR_FIELDS))})")
    values = [_number(source, f"{field}.{name}", _required(source, entry, name, field))
              for name in ("x", "y", "bearing_deg")]
    width = _number(source, f"{field}.beam_width_deg", entry.get("beam_width_deg", default_width))
    if not MIN_BEAM_WIDTH <= math.radians(width) < math.pi:  # as the robot will check it
        name = f"{field}.beam_width_deg" if "beam_width_deg" in entry else "beam_width_deg"
        _fail(source, name, f"must lie in [{_MIN_BEAM_DEGREES:g}, 180) degrees, got {width}")
    return values[0], values[1], values[2], width


def _required(source: str, data: dict[Any, Any], name: str, parent: str = "") -> object:
    if name not in data:
        _fail(source, f"{parent}.{name}" if parent else name, "is missing")
    return data[name]


def _number(source: str, field: str, value: object) -> float:
    number = finite_number(value)
    if number is None:
        _fail(source, field, f"must be a finite number, got {shorten(repr(value), 40)}")
    return number


def _check_firing_order(source: str, order: IntArray, n: int) -> None:
    """Each of the n sensors exactly once: a ring that skips a sensor or fires one twice per
    cycle is almost always a typo, and the polling model assumes one firing per sensor."""
    counts = np.bincount(order, minlength=n)
    twice = np.flatnonzero(counts > 1)
    if twice.size:
        _fail(source, "firing_order",
              f"lists sensor {twice[0]} {counts[twice[0]]} times; list each of 0..{n - 1} once")
    missing = np.flatnonzero(counts == 0)
    if missing.size:
        _fail(source, "firing_order",
              f"leaves out sensor{'s' if missing.size > 1 else ''} "
              f"{', '.join(map(str, missing.tolist()))}; list each of 0..{n - 1} once")


def _check_positive(source: str, field: str, value: float, *, strict: bool) -> None:
    ok = value > 0.0 if strict else value >= 0.0
    if not (math.isfinite(value) and ok):
        _fail(source, field, f"must be {'> 0' if strict else '>= 0'}, got {value}")


def _fail(source: str, field: str, problem: str) -> NoReturn:
    msg = f"{source}: field {field!r} {problem}"
    raise RobotError(msg)
