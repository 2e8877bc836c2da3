"""ROS bags of sonar ranges: ``sensor_msgs/msg/Range`` + ``nav_msgs/msg/Odometry`` → readings.

Reads rosbag1 files (``*.bag``) and rosbag2 folders with the pure-Python ``rosbags`` library
(:class:`rosbags.highlevel.AnyReader`); no ROS installation is needed.

Sensor numbering
----------------
A sensor is one ``(topic, header.frame_id)`` pair of the Range messages, so both layouts work:
one topic per sonar, or one topic carrying every sonar with a ``frame_id`` per sensor.
Sensors are numbered ``0, 1, ...`` in this order:

1. topics in the order given by ``range_topics``, or, when the topics are found automatically
   (every topic of type Range), in *natural* sorted order of their names (digits compare as
   numbers: ``/sonar_2`` before ``/sonar_10``);
2. within one topic, ``frame_id`` values in natural sorted order.

Sensor ``i`` takes mount ``i`` of the :class:`~sonarcarve.robot.RobotDescription`
(``mount_x, mount_y, bearing``), so list the topics, or name the frames, in the robot's sensor
order. Without a robot description every sensor sits at the robot's origin facing its heading
(use this only when the odometry already gives the sensor's own pose).

Poses
-----
The robot pose at a reading's stamp is interpolated linearly in the Odometry messages (x, y and
the yaw of ``pose.pose.orientation``, yaw unwrapped first so that a turn through ±π does not
interpolate the long way round). The sensor's world pose is the robot pose composed with the
mount: ``x = X + cos(Θ)·mx − sin(Θ)·my``, ``y = Y + sin(Θ)·mx + cos(Θ)·my``,
``theta = Θ + bearing``.

Times are the messages' ``header.stamp`` (seconds), not the time the recorder logged them.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from sonarcarve.extras import require
from sonarcarve.io.errors import InputError
from sonarcarve.readings import ReadingBatch
from sonarcarve.typing import BoolArray, FloatArray, IntArray

__all__ = [
    "ODOMETRY_TYPE",
    "RANGE_TYPE",
    "RosbagError",
    "RosbagLog",
    "RosbagReport",
    "SensorMounts",
    "read_rosbag",
]


class SensorMounts(Protocol):
    """Where each sensor sits on the robot: what :func:`read_rosbag` needs of a robot
    description (:class:`~sonarcarve.robot.RobotDescription` is one)."""

    @property
    def name(self) -> str:
        """Name for messages."""

    @property
    def n_sensors(self) -> int:
        """Number of sensors."""

    @property
    def mount_x(self) -> FloatArray:
        """Sensor x in the robot frame (forward), metres, shape (n_sensors,)."""

    @property
    def mount_y(self) -> FloatArray:
        """Sensor y in the robot frame (left), metres, shape (n_sensors,)."""

    @property
    def bearing(self) -> FloatArray:
        """Sensor axis relative to the robot heading, radians, shape (n_sensors,)."""


#: Message type of sonar ranges (ROS 2 spelling; rosbags normalises ROS 1 names to it).
RANGE_TYPE = "sensor_msgs/msg/Range"
#: Message type of the robot pose.
ODOMETRY_TYPE = "nav_msgs/msg/Odometry"


class RosbagError(InputError):
    """A bag that cannot be turned into readings; the one-line message names bag and topic."""


@dataclass(frozen=True)
class RosbagReport:
    """What :func:`read_rosbag` found.

    Attributes
    ----------
    messages : dict of str to int
        Messages read per topic (Range topics and the odometry topic).
    sensors : tuple of (str, str)
        ``(topic, frame_id)`` of sensor 0, 1, ... (see the module notes for the order).
    odometry_topic : str
        The topic the robot poses came from.
    no_echo : int
        Ranges dropped as no echo: outside ``[min_range, max_range]`` of their message, not
        finite, or not > 0.
    outside_odometry : int
        Echoes dropped because their stamp lies outside the time span of the odometry.
    readings : int
        Readings produced.
    """

    messages: dict[str, int]
    sensors: tuple[tuple[str, str], ...]
    odometry_topic: str
    no_echo: int
    outside_odometry: int
    readings: int


@dataclass(frozen=True, eq=False)
class RosbagLog:
    """The readings of a bag and the counts of how they were made.

    Attributes
    ----------
    batch : ReadingBatch
        World-frame readings (s, m, rad), sorted by time then sensor.
    report : RosbagReport
        Counts.
    """

    batch: ReadingBatch
    report: RosbagReport


@dataclass(frozen=True)
class _Ranges:
    """Range messages of all topics as parallel lists (one entry per message)."""

    topic: list[str]
    frame: list[str]
    t: list[float]
    range: list[float]
    min_range: list[float]
    max_range: list[float]
    fov: list[float]


def _natural_key(text: str) -> tuple[tuple[int, int | str], ...]:
    """Sort key comparing digit runs as numbers.

    >>> sorted(["/s10", "/s2", "/s1"], key=_natural_key)
    ['/s1', '/s2', '/s10']
    """
    parts = re.split(r"(\d+)", text)
    return tuple((0, int(p)) if p.isdigit() else (1, p) for p in parts)


def _stamp(header: Any) -> float:
    return float(header.stamp.sec) + 1e-9 * float(header.stamp.nanosec)


def _yaw(q: Any) -> float:
    """Heading (rad) of a quaternion: rotation about z of the robot's x axis."""
    w, x, y, z = float(q.w), float(q.x), float(q.y), float(q.z)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _open_reader(bag: Path) -> Any:
    """An opened AnyReader, or a one-line RosbagError."""
    require("rosbags", "ros", "ROS bags")
    from rosbags.highlevel import AnyReader, AnyReaderError
    from rosbags.typesys import Stores, get_typestore

    if not bag.exists():
        msg = f"{bag}: no such file or folder"
        raise RosbagError(msg)
    # Bags without embedded definitions (some rosbag2 ones) are read with the Humble types.
    try:
        reader = AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
        reader.open()
    except (AnyReaderError, OSError, ValueError, KeyError) as err:
        reason = " ".join(str(err).split()) or type(err).__name__
        msg = f"{bag}: not a readable rosbag1 file or rosbag2 folder ({reason})"
        raise RosbagError(msg) from None
    return reader


def _topic_types(bag: Path, reader: Any) -> dict[str, str]:
    types: dict[str, str] = {}
    for connection in reader.connections:
        known = types.setdefault(connection.topic, connection.msgtype)
        if known != connection.msgtype:
            msg = (f"{bag}: topic {connection.topic!r} carries two message types "
                   f"({known}, {connection.msgtype})")
            raise RosbagError(msg)
    return types


def _check_type(bag: Path, types: dict[str, str], topic: str, expected: str) -> None:
    if topic not in types:
        msg = (f"{bag}: topic {topic!r} is not in the bag "
               f"(topics: {', '.join(sorted(types)) or 'none'})")
        raise RosbagError(msg)
    if types[topic] != expected:
        msg = f"{bag}: topic {topic!r} has type {types[topic]}, expected {expected}"
        raise RosbagError(msg)


def _choose_topics(bag: Path, types: dict[str, str], range_topics: Sequence[str] | None,
                   odom_topic: str | None) -> tuple[list[str], str]:
    if range_topics is None:
        ranges = sorted((t for t, m in types.items() if m == RANGE_TYPE), key=_natural_key)
        if not ranges:
            msg = f"{bag}: no topic of type {RANGE_TYPE} (topics: {_listing(types)})"
            raise RosbagError(msg)
    else:
        ranges = list(dict.fromkeys(range_topics))
        if not ranges:
            msg = f"{bag}: no Range topics given"
            raise RosbagError(msg)
        for topic in ranges:
            _check_type(bag, types, topic, RANGE_TYPE)
    if odom_topic is None:
        odoms = sorted(t for t, m in types.items() if m == ODOMETRY_TYPE)
        if not odoms:
            msg = f"{bag}: no topic of type {ODOMETRY_TYPE} (topics: {_listing(types)})"
            raise RosbagError(msg)
        if len(odoms) > 1:
            msg = f"{bag}: several odometry topics ({', '.join(odoms)}); choose one"
            raise RosbagError(msg)
        odom_topic = odoms[0]
    else:
        _check_type(bag, types, odom_topic, ODOMETRY_TYPE)
    return ranges, odom_topic


def _listing(types: dict[str, str]) -> str:
    return ", ".join(f"{t} [{m}]" for t, m in sorted(types.items())) or "none"


def _read_messages(bag: Path, reader: Any, range_topics: list[str],
                   odom_topic: str) -> tuple[_Ranges, FloatArray, dict[str, int]]:
    """Range fields per message, odometry rows ``(t, x, y, yaw)``, and counts per topic."""
    from rosbags.highlevel import AnyReaderError

    wanted = {*range_topics, odom_topic}
    connections = [c for c in reader.connections if c.topic in wanted]
    ranges = _Ranges([], [], [], [], [], [], [])
    odom: list[tuple[float, float, float, float]] = []
    counts = dict.fromkeys([*range_topics, odom_topic], 0)
    for connection, _, raw in reader.messages(connections=connections):
        try:
            message: Any = reader.deserialize(raw, connection.msgtype)
        except AnyReaderError as err:
            msg = f"{bag}: topic {connection.topic!r}: cannot decode a message ({err})"
            raise RosbagError(msg) from None
        counts[connection.topic] += 1
        if connection.topic == odom_topic:
            p = message.pose.pose
            odom.append((_stamp(message.header), float(p.position.x), float(p.position.y),
                         _yaw(p.orientation)))
            continue
        ranges.topic.append(connection.topic)
        ranges.frame.append(str(message.header.frame_id))
        ranges.t.append(_stamp(message.header))
        ranges.range.append(float(message.range))
        ranges.min_range.append(float(message.min_range))
        ranges.max_range.append(float(message.max_range))
        ranges.fov.append(float(message.field_of_view))
    return ranges, np.array(odom, dtype=np.float64).reshape(-1, 4), counts


def _number_sensors(bag: Path, ranges: _Ranges, range_topics: list[str],
                    robot: SensorMounts | None) -> tuple[tuple[str, str], ...]:
    rank = {topic: i for i, topic in enumerate(range_topics)}
    keys = sorted(set(zip(ranges.topic, ranges.frame, strict=True)),
                  key=lambda k: (rank[k[0]], _natural_key(k[1])))
    if robot is not None and len(keys) > robot.n_sensors:
        topic, frame = keys[robot.n_sensors]
        msg = (f"{bag}: topic {topic!r} frame {frame!r} is sensor {robot.n_sensors}, but robot "
               f"{robot.name!r} has only {robot.n_sensors} sensors")
        raise RosbagError(msg)
    return tuple(keys)


def _robot_pose(odom: FloatArray, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Robot (x, y, yaw) at times ``t`` (inside the odometry span), linear interpolation."""
    order = np.argsort(odom[:, 0], kind="stable")
    ot, ox, oy = odom[order, 0], odom[order, 1], odom[order, 2]
    yaw = np.unwrap(odom[order, 3])  # so a turn through ±π interpolates the short way
    return np.interp(t, ot, ox), np.interp(t, ot, oy), np.interp(t, ot, yaw)


def read_rosbag(
    path: str | Path,
    *,
    robot: SensorMounts | None = None,
    range_topics: Sequence[str] | None = None,
    odom_topic: str | None = None,
    beam_width: float | None = None,
) -> RosbagLog:
    """Read sonar ranges and odometry from a ROS bag into world-frame readings.

    Parameters
    ----------
    path : str or Path
        A rosbag1 file (``*.bag``) or a rosbag2 folder.
    robot : SensorMounts, optional
        Sensor mounts; sensor ``i`` (module notes) takes mount ``i``. Default: every sensor at
        the robot origin facing its heading.
    range_topics : sequence of str, optional
        Range topics, in sensor order; default: every topic of type Range, natural-sorted.
    odom_topic : str, optional
        Odometry topic; default: the only topic of type Odometry.
    beam_width : float, optional
        φ (rad) for messages whose ``field_of_view`` is not > 0; default NaN (the method's
        default). A positive ``field_of_view`` always wins.

    Returns
    -------
    RosbagLog
        Readings sorted by time, ties by sensor; ranges outside ``[min_range, max_range]`` of
        their message (no echo) or not finite, and stamps outside the odometry span, dropped.

    Raises
    ------
    RosbagError
        One line naming the bag (and topic): missing or unreadable bag, no Range topic, no (or
        several) odometry topics, a topic of the wrong type, more sensors than the robot has,
        a ``field_of_view`` of π or more.
    """
    bag = Path(path)
    topics, odom_name, ranges, odom, counts = _load_bag(bag, range_topics, odom_topic)
    sensors = _number_sensors(bag, ranges, topics, robot)
    sensor = _sensor_of_messages(ranges, sensors)
    t, r = np.array(ranges.t, dtype=np.float64), np.array(ranges.range, dtype=np.float64)
    fov = np.array(ranges.fov, dtype=np.float64)
    _check_fov(bag, ranges, fov)
    echo = _echo_mask(ranges, r)
    inside = (t >= odom[:, 0].min()) & (t <= odom[:, 0].max())
    keep = echo & inside
    order = np.lexsort((sensor[keep], t[keep]))  # time, then sensor
    default_width = math.nan if beam_width is None else beam_width
    width = np.where(fov[keep][order] > 0.0, fov[keep][order], default_width)
    batch = _world_readings(bag, robot, odom, t[keep][order], sensor[keep][order],
                            r[keep][order], width)
    report = RosbagReport(
        messages=counts, sensors=sensors, odometry_topic=odom_name,
        no_echo=int((~echo).sum()), outside_odometry=int((echo & ~inside).sum()),
        readings=len(batch),
    )
    return RosbagLog(batch=batch, report=report)


def _load_bag(bag: Path, range_topics: Sequence[str] | None, odom_topic: str | None,
              ) -> tuple[list[str], str, _Ranges, FloatArray, dict[str, int]]:
    """Every message :func:`read_rosbag` needs, the reader closed whatever happens.

    Returns
    -------
    topics : list of str
        The range topics, in sensor order.
    odom_name : str
        The odometry topic.
    ranges : _Ranges
        Range message fields, one entry per message.
    odom : ndarray, shape (m, 4)
        Odometry rows ``(t, x, y, yaw)``: seconds, metres, radians; m >= 1.
    counts : dict
        Messages per topic.

    Raises
    ------
    RosbagError
        As :func:`read_rosbag`, and for an odometry topic with no messages.
    """
    reader = _open_reader(bag)
    try:
        types = _topic_types(bag, reader)
        topics, odom_name = _choose_topics(bag, types, range_topics, odom_topic)
        ranges, odom, counts = _read_messages(bag, reader, topics, odom_name)
    finally:
        reader.close()
    if odom.shape[0] == 0:
        msg = f"{bag}: topic {odom_name!r} holds no odometry messages"
        raise RosbagError(msg)
    return topics, odom_name, ranges, odom, counts


def _sensor_of_messages(ranges: _Ranges, sensors: tuple[tuple[str, str], ...]) -> IntArray:
    """Sensor index of every range message, shape (n,): its (topic, frame_id) in ``sensors``."""
    index = {key: i for i, key in enumerate(sensors)}
    return np.array([index[k] for k in zip(ranges.topic, ranges.frame, strict=True)],
                    dtype=np.int64)


def _check_fov(bag: Path, ranges: _Ranges, fov: FloatArray) -> None:
    """Raise :class:`RosbagError` for the first ``field_of_view`` (rad, shape (n,)) of π or more.

    So wide a cone is not a sonar beam.
    """
    bad_fov = np.flatnonzero(fov >= math.pi)
    if bad_fov.size:
        k = int(bad_fov[0])
        msg = (f"{bag}: topic {ranges.topic[k]!r}: field_of_view {fov[k]:g} rad is not below "
               "π, not a sonar beam")
        raise RosbagError(msg)


def _echo_mask(ranges: _Ranges, r: FloatArray) -> BoolArray:
    """Which ranges ``r`` (metres, shape (n,)) are echoes: finite, > 0, inside their limits."""
    with np.errstate(invalid="ignore"):  # NaN ranges compare False: they are no echo too
        return np.asarray(np.isfinite(r) & (r > 0.0) & (r >= np.array(ranges.min_range))
                          & (r <= np.array(ranges.max_range)))


def _world_readings(bag: Path, robot: SensorMounts | None, odom: FloatArray, t: FloatArray,
                    sensor: IntArray, r: FloatArray, width: FloatArray) -> ReadingBatch:
    """Readings in the world frame: each sensor's mount carried along the odometry.

    Parameters
    ----------
    bag : Path
        Named as the readings' source.
    robot : SensorMounts or None
        Sensor mounts (None: every sensor at the robot origin facing its heading).
    odom : ndarray, shape (m, 4)
        Odometry rows ``(t, x, y, yaw)``: seconds, metres, radians.
    t, sensor, r, width : ndarray, shape (n,)
        Time (s, inside the odometry span), sensor index, range (m) and beam width (rad) of
        every reading, in reading order.
    """
    x, y, heading = _robot_pose(odom, t)
    mx, my, bearing = _mounts(robot, sensor)
    return ReadingBatch.from_arrays(
        t=t, sensor=sensor,
        x=x + np.cos(heading) * mx - np.sin(heading) * my,
        y=y + np.sin(heading) * mx + np.cos(heading) * my,
        theta=heading + bearing, range=r, beam_width=width, source=str(bag),
    )


def _mounts(robot: SensorMounts | None,
            sensor: npt.NDArray[np.int64]) -> tuple[FloatArray, FloatArray, FloatArray]:
    if robot is None:
        zero = np.zeros(sensor.shape, dtype=np.float64)
        return zero, zero, zero
    return robot.mount_x[sensor], robot.mount_y[sensor], robot.bearing[sensor]
