"""ROS bags of sonar ranges: ``sensor_msgs/msg/Range`` + odometry + TF → readings.

Reads rosbag1 files (``*.bag``), rosbag2 folders (sqlite3 or MCAP storage) and bare ``*.mcap``
/ ``*.db3`` files with the pure-Python ``rosbags`` library
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

Mounts
------
Where a sensor sits on the robot comes from TF, matched by frame id: the transforms of
``/tf_static`` (and the latest of each on ``/tf``, other than the odometry's own) are chained
from the Range message's ``header.frame_id`` up to the robot's base frame (``base_frame``; by
default the odometry's ``child_frame_id``, else ``base_link`` or ``base_footprint``). The
Range's beam points along the x axis of its frame (the message's convention). A sensor whose
frame has no TF path to the base frame takes mount ``i`` of the ``robot`` description (the
fallback for bags recorded without TF); then the robot must have exactly as many sensors as
the bag. A robot given for a bag whose TF places every sensor must agree with TF (within
5 cm and 5°): a robot that does not fit the bag is refused, never silently used. A sensor
with neither is an error that says to give the mounts.

Poses
-----
The robot pose at a reading's stamp is interpolated linearly in the odometry: a
``nav_msgs/msg/Odometry`` topic, or, when the bag has none, the ``/tf`` transforms whose child is
the base frame (``odom → base_link``). x, y and the yaw of the orientation are interpolated,
yaw unwrapped first so that a turn through ±π does not interpolate the long way round. The
sensor's world pose is the robot pose composed with the mount:
``x = X + cos(Θ)·mx − sin(Θ)·my``, ``y = Y + sin(Θ)·mx + cos(Θ)·my``, ``theta = Θ + bearing``.
Times are the messages' ``header.stamp`` (seconds), not the time the recorder logged them.

Range values (REP 117)
----------------------
- finite, from ``min_range`` up to ``max_range`` (``max_range`` itself: below): an echo, one
  reading;
- ``+Inf``, or a finite range beyond ``max_range``: nothing within range, free space up to
  ``max_range``; kept apart in :attr:`RosbagLog.no_echo` with their poses, and counted
  (:meth:`RosbagLog.with_no_echo` merges them in as no-echo readings);
- a range equal to ``max_range``: nothing heard too, from a sensor that never reports +Inf or
  beyond ``max_range`` in the bag, because that is how such publishers say it: Gazebo's range
  and sonar plugins publish ``range = max_range`` for a ray that hit nothing, drivers clamp a
  late echo to it (ROS's range-sensor layer calls it a *max reading*, its
  ``clear_on_max_reading``). From a sensor that does report +Inf (REP 117, as sonarcarve's
  simulated bags do) it is an echo at ``max_range``: a Scout2's 6.477 m is 255 range steps, and
  the office tour has 15 such echoes, which a bag must give back as its CSV does;
- ``-Inf`` (or finite below ``min_range``): an object too close to measure; counted, dropped;
- NaN (or finite ≤ 0): invalid; counted, dropped.

``field_of_view`` is the beam width φ; ``radiation_type`` (0 ultrasound, 1 infrared) is kept in
the report.
"""

from __future__ import annotations

import math
import re
import sqlite3
import struct
from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from sonarcarve.extras import require
from sonarcarve.io.errors import InputError
from sonarcarve.readings import ReadingBatch
from sonarcarve.typing import BoolArray, FloatArray, IntArray

__all__ = [
    "MOUNT_TOLERANCE",
    "ODOMETRY_TYPE",
    "RANGE_TYPE",
    "TF_TYPE",
    "NoEchoReadings",
    "RosbagError",
    "RosbagLog",
    "RosbagReport",
    "SensorMounts",
    "SensorSource",
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
#: Message type of ``/tf`` and ``/tf_static``.
TF_TYPE = "tf2_msgs/msg/TFMessage"
#: How far a robot description's mount may lie from the bag's TF mount: (metres, radians).
MOUNT_TOLERANCE = (0.05, math.radians(5.0))
#: ``radiation_type`` values of sensor_msgs/Range.
_RADIATION = {0: "ultrasound", 1: "infrared"}
#: Base frame names tried, in order, when neither ``base_frame`` nor the odometry names one.
_BASE_FRAMES = ("base_link", "base_footprint")
#: Longest chain of transforms followed from a sensor frame to the base frame.
_MAX_TF_DEPTH = 64


class RosbagError(InputError):
    """A bag that cannot be turned into readings; the one-line message names bag and topic."""


@dataclass(frozen=True)
class SensorSource:
    """Where one sensor's readings and mount came from.

    Attributes
    ----------
    topic, frame : str
        The Range topic and ``header.frame_id``.
    mount : str
        ``tf`` (chained from ``/tf_static`` or ``/tf``) or ``robot NAME[i]`` (the fallback).
    x, y, bearing : float
        The mount in the base frame: metres, metres, radians.
    radiation : str
        ``ultrasound``, ``infrared`` or ``type N``; several values joined by ``/``.
    """

    topic: str
    frame: str
    mount: str
    x: float
    y: float
    bearing: float
    radiation: str


@dataclass(frozen=True)
class RosbagReport:
    """What :func:`read_rosbag` found.

    Attributes
    ----------
    messages : dict of str to int
        Messages read per topic (Range topics, the odometry topic, TF topics).
    sensors : tuple of (str, str)
        ``(topic, frame_id)`` of sensor 0, 1, ... (see the module notes for the order).
    sources : tuple of SensorSource
        Per sensor: topic, frame, where its mount came from, the mount, radiation type.
    odometry_topic : str
        The topic the robot poses came from (an Odometry topic, or the TF topic).
    odometry_frames : tuple of (str, str)
        ``(parent, child)`` frames of the odometry (``odom``, ``base_link``).
    no_echo : int
        +Inf ranges, finite ones beyond ``max_range``, and ones equal to it from a sensor that
        never reports beyond it (module notes): nothing heard within range.
    too_close : int
        −Inf ranges, or finite ones below ``min_range``.
    invalid : int
        NaN ranges, or finite ones ≤ 0.
    outside_odometry : int
        Echoes and no-echo messages dropped because their stamp lies outside the odometry span.
    readings : int
        Readings produced.
    """

    messages: dict[str, int]
    sensors: tuple[tuple[str, str], ...]
    odometry_topic: str
    no_echo: int
    outside_odometry: int
    readings: int
    too_close: int = 0
    invalid: int = 0
    sources: tuple[SensorSource, ...] = ()
    odometry_frames: tuple[str, str] = ("", "")


@dataclass(frozen=True, eq=False)
class NoEchoReadings:
    """Beams that heard nothing up to ``max_range`` (REP 117 ``+Inf``): free space, no point.

    Struct of arrays, shape (n,) each, in time order (ties by sensor).

    Attributes
    ----------
    t : ndarray
        Header stamp, seconds.
    sensor : ndarray of int64
        Sensor index (as in the readings).
    x, y, theta : ndarray
        Sensor origin (m) and axis (rad) in the odometry frame.
    max_range : ndarray
        How far the beam looked, metres.
    beam_width : ndarray
        φ, radians (NaN where the message gave none).
    """

    t: FloatArray
    sensor: IntArray
    x: FloatArray
    y: FloatArray
    theta: FloatArray
    max_range: FloatArray
    beam_width: FloatArray

    def __len__(self) -> int:
        return int(self.t.shape[0])


@dataclass(frozen=True, eq=False)
class RosbagLog:
    """The readings of a bag and the counts of how they were made.

    Attributes
    ----------
    batch : ReadingBatch
        World-frame (odometry frame) echoes (s, m, rad), sorted by time then sensor.
    report : RosbagReport
        Counts and where each sensor's mount came from.
    no_echo : NoEchoReadings
        The +Inf readings inside the odometry span, posed like the echoes.
    """

    batch: ReadingBatch
    report: RosbagReport
    no_echo: NoEchoReadings = field(default_factory=lambda: _no_echo_rows(
        *(np.zeros(0) for _ in range(7))))

    def with_no_echo(self) -> ReadingBatch:
        """The echoes and the no-echo readings in one batch, sorted by time then sensor (ties:
        echoes first): a no-echo row has ``range`` = inf and its ``max_range``, the methods
        and grids take it as free space only. Row positions (reading ids) are those of the
        merged batch, not of :attr:`batch`."""
        e, f = self.batch, self.no_echo
        t = np.concatenate([e.t, f.t])
        sensor = np.concatenate([e.sensor, f.sensor])
        order = np.lexsort((sensor, t))
        return ReadingBatch.from_arrays(
            t=t[order], sensor=sensor[order],
            x=np.concatenate([e.x, f.x])[order], y=np.concatenate([e.y, f.y])[order],
            theta=np.concatenate([e.theta, f.theta])[order],
            range=np.concatenate([e.range, np.full(len(f), np.inf)])[order],
            beam_width=np.concatenate([e.beam_width, f.beam_width])[order],
            max_range=np.concatenate([e.max_range, f.max_range])[order],
            source="bag readings with no-echo readings",
        )


@dataclass
class _Ranges:
    """Range messages of all topics as parallel lists (one entry per message)."""

    topic: list[str] = field(default_factory=list)
    frame: list[str] = field(default_factory=list)
    t: list[float] = field(default_factory=list)
    range: list[float] = field(default_factory=list)
    min_range: list[float] = field(default_factory=list)
    max_range: list[float] = field(default_factory=list)
    fov: list[float] = field(default_factory=list)
    radiation: list[int] = field(default_factory=list)


@dataclass
class _Tf:
    """Transforms read: static ones by child, dynamic ones as rows."""

    static: dict[str, tuple[str, float, float, float]] = field(default_factory=dict)
    dynamic: list[tuple[float, str, str, float, float, float]] = field(default_factory=list)


@dataclass
class _Messages:
    """Everything :func:`read_rosbag` takes from a bag."""

    ranges: _Ranges
    odom: list[tuple[float, float, float, float]]
    odom_frames: Counter[tuple[str, str]]
    tf: _Tf
    counts: dict[str, int]


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
    """Heading (rad) of a quaternion: rotation about z of the frame's x axis."""
    w, x, y, z = float(q.w), float(q.x), float(q.y), float(q.z)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _read_errors() -> tuple[type[BaseException], ...]:
    """Exceptions a damaged bag raises while it is opened or read."""
    from rosbags.highlevel import AnyReaderError
    from rosbags.rosbag1 import ReaderError as Reader1Error
    from rosbags.rosbag2 import ReaderError as Reader2Error

    errors: tuple[type[BaseException], ...] = (
        AnyReaderError, Reader1Error, Reader2Error, OSError, ValueError, KeyError, IndexError,
        EOFError, struct.error, AssertionError, sqlite3.Error,
        MemoryError, OverflowError)  # a corrupt MCAP record size: an absurd read
    try:  # rosbags reads sqlite3 storage through apsw where it is installed
        import apsw
    except ImportError:
        return errors
    return (*errors, apsw.Error)


def _reason(err: BaseException) -> str:
    """The library's reason in plain words: no tuple repr (rosbags wraps its causes' args),
    no codec jargon, at most 200 characters."""
    args = err.args
    while len(args) == 1 and isinstance(args[0], tuple | BaseException):
        args = args[0] if isinstance(args[0], tuple) else args[0].args
    if isinstance(err, UnicodeDecodeError):
        text = f"not UTF-8 text where text was expected (byte 0x{err.object[err.start]:02x})"
    else:
        text = ": ".join(str(a) for a in args) if args else str(err)
    plain = " ".join(text.replace("(", "").replace(")", "").split()).rstrip(".")
    return plain[:200] or type(err).__name__


#: The first bytes of an MCAP file and of a rosbag1 file.
_MCAP_MAGIC = b"\x89MCAP0\r\n"
_ROSBAG1_MAGIC = b"#ROSBAG V2.0\n"
_SQLITE_MAGIC = b"SQLite format 3\x00"


def _unreadable(bag: Path, err: BaseException) -> str:
    """One plain line for a bag the reader cannot open, saying what kind of file it looks
    like (an MCAP file, a rosbag1 file, a folder) and what is wrong with it."""
    reason = _reason(err)
    if bag.is_dir():
        if not (bag / "metadata.yaml").is_file():
            return f"{bag}: a folder, but not a rosbag2 folder (no metadata.yaml in it)"
        return f"{bag}: not a readable rosbag2 folder ({reason})"
    try:
        with bag.open("rb") as handle:
            head = handle.read(len(_SQLITE_MAGIC))
    except OSError as os_err:
        return f"{bag}: cannot read ({os_err.strerror})"
    if head.startswith(_MCAP_MAGIC):
        if "end magic" in reason.lower():
            return (f"{bag}: truncated or corrupt MCAP file (no end marker: was the recording "
                    "cut short?)")
        return f"{bag}: corrupt MCAP file ({reason})"
    if head.startswith(_ROSBAG1_MAGIC):
        if "index" in reason.lower() or "header" in reason.lower():
            return (f"{bag}: truncated or corrupt rosbag1 file (its index cannot be read: was "
                    "the recording cut short?)")
        return f"{bag}: corrupt rosbag1 file ({reason})"
    if head.startswith(_SQLITE_MAGIC):
        return f"{bag}: not a readable rosbag2 SQLite file ({reason})"
    return (f"{bag}: not a ROS bag: it does not start as an MCAP, rosbag1 or rosbag2 SQLite "
            "file does")


def _open_reader(bag: Path) -> Any:
    """An opened AnyReader, or a one-line RosbagError."""
    require("rosbags", "ros", "ROS bags")
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    if not bag.exists():
        msg = f"{bag}: no such file or folder"
        raise RosbagError(msg)
    # Bags without embedded definitions (some rosbag2 ones) are read with the Humble types.
    try:
        reader = AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
        reader.open()
    except _read_errors() as err:
        raise RosbagError(_unreadable(bag, err)) from None
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
                   odom_topic: str | None) -> tuple[list[str], str | None]:
    """Range topics in sensor order, and the odometry topic (None: odometry from TF)."""
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
    if odom_topic is not None:
        _check_type(bag, types, odom_topic, ODOMETRY_TYPE)
        return ranges, odom_topic
    odoms = sorted(t for t, m in types.items() if m == ODOMETRY_TYPE)
    if len(odoms) > 1:
        msg = f"{bag}: several odometry topics ({', '.join(odoms)}); choose one with odom_topic"
        raise RosbagError(msg)
    return ranges, odoms[0] if odoms else None


def _listing(types: dict[str, str]) -> str:
    return ", ".join(f"{t} [{m}]" for t, m in sorted(types.items())) or "none"


def _iterate(bag: Path, reader: Any, connections: list[Any]) -> Iterator[tuple[Any, Any]]:
    """``(connection, message)`` in log order; a damaged bag gives a one-line RosbagError."""
    errors = _read_errors()
    it = iter(reader.messages(connections=connections))
    while True:
        try:
            item = next(it, None)
        except errors as err:
            msg = f"{bag}: truncated or corrupt bag ({_reason(err)})"
            raise RosbagError(msg) from None
        if item is None:
            return
        connection, _, raw = item
        try:
            message = reader.deserialize(raw, connection.msgtype)
        except errors as err:
            msg = f"{bag}: topic {connection.topic!r}: cannot decode a message ({_reason(err)})"
            raise RosbagError(msg) from None
        yield connection, message


def _read_messages(bag: Path, reader: Any, types: dict[str, str], range_topics: list[str],
                   odom_topic: str | None) -> _Messages:
    """Range fields per message, odometry rows ``(t, x, y, yaw)``, TF, counts per topic."""
    tf_topics = sorted(t for t, m in types.items() if m == TF_TYPE)
    wanted = [*range_topics, *([odom_topic] if odom_topic else []), *tf_topics]
    connections = [c for c in reader.connections if c.topic in set(wanted)]
    out = _Messages(_Ranges(), [], Counter(), _Tf(), dict.fromkeys(wanted, 0))
    for connection, message in _iterate(bag, reader, connections):
        topic = connection.topic
        out.counts[topic] += 1
        if topic == odom_topic:
            p = message.pose.pose
            out.odom.append((_stamp(message.header), float(p.position.x), float(p.position.y),
                             _yaw(p.orientation)))
            out.odom_frames[(_frame(message.header.frame_id),
                             _frame(message.child_frame_id))] += 1
        elif topic in tf_topics:
            _add_transforms(out.tf, message, static=topic.rstrip("/").endswith("tf_static"))
        else:
            r = out.ranges
            r.topic.append(topic)
            r.frame.append(_frame(message.header.frame_id))
            r.t.append(_stamp(message.header))
            r.range.append(float(message.range))
            r.min_range.append(float(message.min_range))
            r.max_range.append(float(message.max_range))
            r.fov.append(float(message.field_of_view))
            r.radiation.append(int(message.radiation_type))
    return out


def _frame(name: object) -> str:
    """A frame id without the leading ``/`` some ROS 1 bags carry."""
    return str(name).lstrip("/")


def _add_transforms(tf: _Tf, message: Any, *, static: bool) -> None:
    for ts in message.transforms:
        tr = ts.transform
        row = (_frame(ts.header.frame_id), float(tr.translation.x), float(tr.translation.y),
               _yaw(tr.rotation))
        child = _frame(ts.child_frame_id)
        if static:
            tf.static[child] = row
        else:
            tf.dynamic.append((_stamp(ts.header), row[0], child, row[1], row[2], row[3]))


def _number_sensors(ranges: _Ranges, range_topics: list[str]) -> tuple[tuple[str, str], ...]:
    rank = {topic: i for i, topic in enumerate(range_topics)}
    return tuple(sorted(set(zip(ranges.topic, ranges.frame, strict=True)),
                        key=lambda k: (rank[k[0]], _natural_key(k[1]))))


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
    base_frame: str | None = None,
    beam_width: float | None = None,
) -> RosbagLog:
    """Read sonar ranges, odometry and TF from a ROS bag into world-frame readings.

    Parameters
    ----------
    path : str or Path
        A rosbag1 file (``*.bag``), a rosbag2 folder (sqlite3 or MCAP), or a bare ``*.mcap``.
    robot : SensorMounts, optional
        Fallback mounts for sensors whose frame TF does not place: sensor ``i`` (module notes)
        takes mount ``i``. Checked against the bag (sensor count, and TF where it exists).
    range_topics : sequence of str, optional
        Range topics, in sensor order; default: every topic of type Range, natural-sorted.
    odom_topic : str, optional
        Odometry topic; default: the only topic of type Odometry, else TF.
    base_frame : str, optional
        The robot's frame (the child of the odometry); default: the odometry's
        ``child_frame_id``, else ``base_link`` or ``base_footprint``.
    beam_width : float, optional
        φ (rad) for messages whose ``field_of_view`` is not > 0; default NaN (the method's
        default). A positive ``field_of_view`` always wins.

    Returns
    -------
    RosbagLog
        Echoes sorted by time, ties by sensor, and the no-echo beams beside them (REP 117,
        module notes); stamps outside the odometry span dropped.

    Raises
    ------
    RosbagError
        One line naming the bag (and topic or frame): missing, unreadable, truncated or corrupt
        bag; no Range topic; no odometry (neither an Odometry topic nor a TF path to the base
        frame); several odometry topics; a topic of the wrong type; a sensor without a mount
        (neither TF nor ``robot``); a ``robot`` that does not fit the bag; a ``field_of_view``
        of π or more.
    """
    bag = Path(path)
    reader = _open_reader(bag)
    try:
        types = _topic_types(bag, reader)
        topics, odom_name = _choose_topics(bag, types, range_topics, odom_topic)
        found = _read_messages(bag, reader, types, topics, odom_name)
    finally:
        reader.close()
    base = _base_frame(found, base_frame)
    odom, odom_source, odom_frames = _odometry(bag, found, odom_name, base)
    sensors = _number_sensors(found.ranges, topics)
    sources = _mount_sensors(bag, found, sensors, base, robot)
    return _assemble(bag, found, sensors, sources, odom, (odom_source, odom_frames), beam_width)


def _base_frame(found: _Messages, base_frame: str | None) -> str:
    if base_frame is not None:
        return base_frame.lstrip("/")
    if found.odom_frames:
        child = found.odom_frames.most_common(1)[0][0][1]
        if child:
            return child
    children = {row[2] for row in found.tf.dynamic} | set(found.tf.static)
    parents = {row[1] for row in found.tf.dynamic} | {v[0] for v in found.tf.static.values()}
    for name in _BASE_FRAMES:
        if name in children or name in parents:
            return name
    return _BASE_FRAMES[0]


def _odometry(bag: Path, found: _Messages, odom_name: str | None,
              base: str) -> tuple[FloatArray, str, tuple[str, str]]:
    """Odometry rows ``(t, x, y, yaw)`` (m >= 1), their topic, and ``(parent, child)``."""
    if odom_name is not None:
        if not found.odom:
            msg = f"{bag}: topic {odom_name!r} holds no odometry messages"
            raise RosbagError(msg)
        frames = found.odom_frames.most_common(1)[0][0]
        return np.array(found.odom, dtype=np.float64).reshape(-1, 4), odom_name, frames
    rows = [r for r in found.tf.dynamic if r[2] == base]
    if not rows:
        msg = (f"{bag}: no odometry: no {ODOMETRY_TYPE} topic and no transform to {base!r} on "
               "/tf (give --odom-topic, or --frame for the robot's frame)")
        raise RosbagError(msg)
    parents = Counter(r[1] for r in rows)
    parent = parents.most_common(1)[0][0]
    odom = np.array([(r[0], r[3], r[4], r[5]) for r in rows if r[1] == parent],
                    dtype=np.float64).reshape(-1, 4)
    return odom, "/tf", (parent, base)


def _mount_in_base(frame: str, base: str, edges: dict[str, tuple[str, float, float, float]],
                   ) -> tuple[float, float, float] | None:
    """Pose ``(x, y, yaw)`` of ``frame`` in ``base`` by chaining ``edges`` (child → parent)."""
    x = y = yaw = 0.0
    current = frame
    for _ in range(_MAX_TF_DEPTH):
        if current == base:
            return x, y, yaw
        edge = edges.get(current)
        if edge is None:
            return None
        parent, ex, ey, eyaw = edge
        c, s = math.cos(eyaw), math.sin(eyaw)
        x, y, yaw = ex + c * x - s * y, ey + s * x + c * y, eyaw + yaw
        current = parent
    return None


def _mount_sensors(bag: Path, found: _Messages, sensors: tuple[tuple[str, str], ...], base: str,
                   robot: SensorMounts | None) -> tuple[SensorSource, ...]:
    """Each sensor's mount: TF by frame id, else the robot's mount of the same index."""
    edges: dict[str, tuple[str, float, float, float]] = {}
    for _, parent, child, x, y, yaw in found.tf.dynamic:  # the latest of each wins
        if child != base:  # the odometry's own transform is no mount
            edges[child] = (parent, x, y, yaw)
    edges.update(found.tf.static)
    radiation = _radiation(found.ranges, sensors)
    tf_mounts = [_mount_in_base(frame, base, edges) if frame else None for _, frame in sensors]
    missing = [i for i, m in enumerate(tf_mounts) if m is None]
    if robot is not None:
        _check_robot(bag, robot, sensors, tf_mounts, base)
    elif missing:
        frames = ", ".join(repr(sensors[i][1]) for i in missing[:4])
        more = f" and {len(missing) - 4} more" if len(missing) > 4 else ""
        msg = (f"{bag}: no TF mount for sensor frame{'s' if len(missing) > 1 else ''} "
               f"{frames}{more} (no /tf_static or /tf path to {base!r}); give the sensor "
               "mounts with --robot NAME|ROBOT.yaml")
        raise RosbagError(msg)
    out = []
    for i, ((topic, frame), mount) in enumerate(zip(sensors, tf_mounts, strict=True)):
        if mount is not None:
            out.append(SensorSource(topic, frame, "tf", *mount, radiation[i]))
        else:
            assert robot is not None  # checked above
            out.append(SensorSource(topic, frame, f"robot {robot.name}[{i}]",
                                    float(robot.mount_x[i]), float(robot.mount_y[i]),
                                    float(robot.bearing[i]), radiation[i]))
    return tuple(out)


def _check_robot(bag: Path, robot: SensorMounts, sensors: tuple[tuple[str, str], ...],
                 tf_mounts: list[tuple[float, float, float] | None], base: str) -> None:
    """Refuse a robot description that does not fit the bag (count, or TF mounts)."""
    if robot.n_sensors != len(sensors):
        listed = ", ".join(f"{t}{' ' + f if f else ''}" for t, f in sensors[:4])
        more = ", ..." if len(sensors) > 4 else ""
        msg = (f"{bag}: robot {robot.name!r} has {robot.n_sensors} sensors but the bag has "
               f"{len(sensors)} ({listed}{more}); it does not fit this bag")
        raise RosbagError(msg)
    dist_tol, angle_tol = MOUNT_TOLERANCE
    for i, mount in enumerate(tf_mounts):
        if mount is None:
            continue
        x, y, yaw = mount
        rx, ry, rb = float(robot.mount_x[i]), float(robot.mount_y[i]), float(robot.bearing[i])
        if (math.hypot(x - rx, y - ry) > dist_tol
                or abs(math.remainder(yaw - rb, math.tau)) > angle_tol):
            msg = (f"{bag}: robot {robot.name!r} does not fit the bag: sensor {i} (frame "
                   f"{sensors[i][1]!r}) is at ({x:.3f}, {y:.3f}, {math.degrees(yaw):.1f}°) in "
                   f"{base!r} by TF, ({rx:.3f}, {ry:.3f}, {math.degrees(rb):.1f}°) in the robot")
            raise RosbagError(msg)


def _radiation(ranges: _Ranges, sensors: tuple[tuple[str, str], ...]) -> list[str]:
    seen: dict[tuple[str, str], set[int]] = {key: set() for key in sensors}
    for key, value in zip(zip(ranges.topic, ranges.frame, strict=True), ranges.radiation,
                          strict=True):
        seen[key].add(value)
    return ["/".join(_RADIATION.get(v, f"type {v}") for v in sorted(seen[key]))
            for key in sensors]


def _assemble(bag: Path, found: _Messages, sensors: tuple[tuple[str, str], ...],
              sources: tuple[SensorSource, ...], odom: FloatArray,
              odometry: tuple[str, tuple[str, str]], beam_width: float | None) -> RosbagLog:
    ranges = found.ranges
    index = {key: i for i, key in enumerate(sensors)}
    sensor = np.array([index[k] for k in zip(ranges.topic, ranges.frame, strict=True)],
                      dtype=np.int64)
    t, r = np.array(ranges.t, dtype=np.float64), np.array(ranges.range, dtype=np.float64)
    lo = np.array(ranges.min_range, dtype=np.float64)
    hi = np.array(ranges.max_range, dtype=np.float64)
    fov = np.array(ranges.fov, dtype=np.float64)
    _check_fov(bag, ranges, fov)
    with np.errstate(invalid="ignore"):  # NaN compares False everywhere: it is invalid
        invalid = np.isnan(r) | (np.isfinite(r) & (r <= 0.0))
        beyond = ~invalid & (r > hi)
        no_echo = beyond | (~invalid & (r == hi) & ~_follows_rep117(sensor, beyond))
        too_close = ~invalid & (r < lo)
    echo = ~(invalid | no_echo | too_close)
    inside = (t >= odom[:, 0].min()) & (t <= odom[:, 0].max())
    default_width = math.nan if beam_width is None else beam_width
    width = np.where(fov > 0.0, fov, default_width)
    x, y, theta = _sensor_poses(odom, t, sensor, sources)
    order = np.lexsort((sensor, t))  # time, then sensor
    keep = order[(echo & inside)[order]]
    batch = ReadingBatch.from_arrays(t=t[keep], sensor=sensor[keep], x=x[keep], y=y[keep],
                                     theta=theta[keep], range=r[keep], beam_width=width[keep],
                                     source=str(bag))
    free = order[(no_echo & inside)[order]]
    report = RosbagReport(
        messages=found.counts, sensors=sensors, odometry_topic=odometry[0],
        no_echo=int(no_echo.sum()), outside_odometry=int(((echo | no_echo) & ~inside).sum()),
        readings=len(batch), too_close=int(too_close.sum()), invalid=int(invalid.sum()),
        sources=sources, odometry_frames=odometry[1],
    )
    no_echo_rows = _no_echo_rows(t[free], sensor[free], x[free], y[free], theta[free], hi[free],
                                 width[free])
    return RosbagLog(batch=batch, report=report, no_echo=no_echo_rows)


def _follows_rep117(sensor: npt.NDArray[np.int64], beyond: BoolArray) -> BoolArray:
    """Per message: whether its sensor ever reports silence as REP 117 asks (+Inf, or a range
    beyond ``max_range``); then a range equal to ``max_range`` is an echo there (module notes)."""
    says_inf = np.zeros(int(sensor.max(initial=-1)) + 1, dtype=bool)
    says_inf[sensor[beyond]] = True
    return says_inf[sensor]


def _no_echo_rows(t: FloatArray, sensor: Any, x: FloatArray, y: FloatArray, theta: FloatArray,
                  max_range: FloatArray, beam_width: FloatArray) -> NoEchoReadings:
    return NoEchoReadings(
        t=np.asarray(t, dtype=np.float64), sensor=np.asarray(sensor, dtype=np.int64),
        x=np.asarray(x, dtype=np.float64), y=np.asarray(y, dtype=np.float64),
        theta=np.asarray(theta, dtype=np.float64),
        max_range=np.asarray(max_range, dtype=np.float64),
        beam_width=np.asarray(beam_width, dtype=np.float64))


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


def _sensor_poses(odom: FloatArray, t: FloatArray, sensor: IntArray,
                  sources: tuple[SensorSource, ...]) -> tuple[FloatArray, FloatArray, FloatArray]:
    """World (odometry-frame) pose of every message's sensor, shape (n,) each.

    Stamps outside the odometry span get the end poses (``np.interp`` clamps); the caller drops
    them.
    """
    heading_x, heading_y, heading = _robot_pose(odom, t)
    mx = np.array([s.x for s in sources], dtype=np.float64)[sensor]
    my = np.array([s.y for s in sources], dtype=np.float64)[sensor]
    bearing = np.array([s.bearing for s in sources], dtype=np.float64)[sensor]
    c, s = np.cos(heading), np.sin(heading)
    return heading_x + c * mx - s * my, heading_y + s * mx + c * my, heading + bearing
