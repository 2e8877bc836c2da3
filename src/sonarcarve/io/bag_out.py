"""ROS bags out: a method's live map and arcs as messages Foxglove and RViz show.

:func:`write_map_bag` runs a method over readings and writes, beside the input messages copied
through (optional) and the robot's odometry and TF (optional):

- ``/sonarcarve/local_map``: ``sensor_msgs/msg/PointCloud2``, one point per surviving arc with
  float32 fields ``x, y, z, source, width, max_error, confidence`` (``source`` the
  :class:`~sonarcarve.maps.PointSource` code, ``width`` rad, ``max_error`` m, ``confidence``
  NaN where the method does not estimate it), in the odometry frame, every ``1 / rate`` seconds
  of log time;
- ``/sonarcarve/arcs``: ``visualization_msgs/msg/MarkerArray``, a ``DELETEALL`` marker then one
  ``LINE_STRIP`` per live arc (id = reading id), the arc's remaining width drawn about its
  point, coloured by source like the figures (centerline red, carved blue, ATM green);
- ``/sonarcarve/grid``: ``nav_msgs/msg/OccupancyGrid``, when a grid is given (for example
  :class:`~sonarcarve.grids.CarvedGrid`): its trinary cells (occupied 100, free 0, unknown -1),
  at the same times as the local map.

:class:`BagWriter` is the writer underneath: one class for rosbag1 (``*.bag``, Noetic message
definitions), rosbag2 folders (MCAP or sqlite3 storage) and bare ``*.mcap`` files, building
messages from plain field mappings (fields not given take their zero value, so one mapping
suits ROS 1 and ROS 2 definitions). A bag is written whole or not at all: it is built beside
the target and moved into place when complete. The arc markers (millions of points in a long
log) skip the message objects: :mod:`sonarcarve.io.marker_bytes` lays their bytes out directly,
once a sample laid out so is checked to be rosbags' own bytes for the bag's types.
"""

from __future__ import annotations

import math
import shutil
import struct
import tempfile
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import numpy.typing as npt

from sonarcarve.errors import SonarcarveError
from sonarcarve.extras import require
from sonarcarve.io.errors import OutputError
from sonarcarve.maps import LocalMap, PointSource
from sonarcarve.readings import Reading, ReadingBatch, reading_ids
from sonarcarve.typing import FloatArray, IntArray

if TYPE_CHECKING:
    from sonarcarve.io.marker_bytes import StripArray

__all__ = [
    "ARCS_TOPIC",
    "GRID_TOPIC",
    "LOCAL_MAP_FIELDS",
    "LOCAL_MAP_TOPIC",
    "ArcStrips",
    "BagFormat",
    "BagOutReport",
    "BagWriter",
    "LiveGrid",
    "LiveMethod",
    "arc_markers",
    "arc_strips",
    "bag_format",
    "copy_messages",
    "occupancy_grid_fields",
    "point_cloud_fields",
    "quaternion",
    "stamp",
    "write_map_bag",
]

#: Topic of the local map point clouds.
LOCAL_MAP_TOPIC = "/sonarcarve/local_map"
#: The occupancy grid, when one is written.
GRID_TOPIC = "/sonarcarve/grid"
#: Topic of the arc markers.
ARCS_TOPIC = "/sonarcarve/arcs"
#: Fields of every local map point, float32 each, in this order.
LOCAL_MAP_FIELDS = ("x", "y", "z", "source", "width", "max_error", "confidence")
#: Marker colours (r, g, b) by source, the figures' colours.
_SOURCE_RGB = {
    PointSource.CENTERLINE: (0.839, 0.153, 0.157),
    PointSource.CARVED: (0.122, 0.467, 0.706),
    PointSource.ATM: (0.173, 0.627, 0.173),
}
_POINTFIELD_FLOAT32 = 7
_MARKER_LINE_STRIP, _MARKER_DELETEALL = 4, 3
_ARC_SEGMENT = math.radians(2.0)  # marker polyline step along an arc
_MARKER_ARRAY = "visualization_msgs/msg/MarkerArray"
_NUMERIC = {"bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32",
            "int64", "uint64", "float32", "float64"}
_DTYPES = {"bool": np.bool_, "byte": np.uint8, "char": np.uint8, "float32": np.float32,
           "float64": np.float64}


class LiveMethod(Protocol):
    """What :func:`write_map_bag` needs of a method (every
    :class:`~sonarcarve.methods.base.SonarMethod` is one; io sits beside the methods and does
    not import them)."""

    @property
    def history(self) -> Any:
        """The ring buffer: ``slots()``, and per slot ``x``, ``y``, ``r``, ``reading_id``."""

    def add(self, reading: Reading, reading_id: int | None = None) -> None:
        """Process one reading."""

    def local_map(self) -> LocalMap:
        """The current local map."""

    def estimates(self, slots: IntArray) -> Any:
        """Per slot: ``alive``, ``xy``, ``width``, ``source``."""


class LiveGrid(Protocol):
    """What :func:`write_map_bag` needs of a grid: fed readings, read as trinary cells.

    Cell ``(i, j)`` of :meth:`trinary` (row i along y from ``bounds[1]``, column j along x from
    ``bounds[0]``) is the square of side ``resolution``: the layout of ROS's OccupancyGrid.
    """

    @property
    def resolution(self) -> float:
        """Cell side, metres."""

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)``, metres."""

    def add(self, reading: Reading) -> None:
        """Update the grid with one reading."""

    def trinary(self) -> Any:
        """Occupied 100, free 0, unknown -1 per cell, int8, shape (rows, columns)."""


class BagFormat(Enum):
    """What :class:`BagWriter` writes."""

    ROS1 = "rosbag1 (.bag)"
    ROS2_MCAP = "rosbag2 folder, MCAP storage"
    ROS2_SQLITE3 = "rosbag2 folder, sqlite3 storage"
    MCAP_FILE = "bare MCAP file (.mcap)"


def bag_format(path: str | Path, storage: str = "mcap") -> BagFormat:
    """The format a path asks for: ``*.bag`` rosbag1, ``*.mcap`` a bare MCAP file, anything
    else a rosbag2 folder with ``storage`` (``mcap`` or ``sqlite3``).

    >>> bag_format("run.bag").name, bag_format("run.mcap").name, bag_format("run").name
    ('ROS1', 'MCAP_FILE', 'ROS2_MCAP')
    """
    suffix = Path(path).suffix.lower()
    if suffix == ".bag":
        return BagFormat.ROS1
    if suffix == ".mcap":
        return BagFormat.MCAP_FILE
    if storage not in {"mcap", "sqlite3"}:
        msg = f"bag storage must be mcap or sqlite3, got {storage!r}"
        raise OutputError(msg)
    return BagFormat.ROS2_MCAP if storage == "mcap" else BagFormat.ROS2_SQLITE3


def stamp(t: float) -> dict[str, int]:
    """A ``builtin_interfaces/Time`` mapping for ``t`` seconds (>= 0)."""
    ns = round(t * 1e9)
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def quaternion(yaw: float) -> dict[str, float]:
    """A ``geometry_msgs/Quaternion`` mapping for a rotation of ``yaw`` radians about z."""
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2.0), "w": math.cos(yaw / 2.0)}


class BagWriter:
    """Write messages given as field mappings to a new bag; use as a context manager.

    Parameters
    ----------
    path : str or Path
        ``*.bag``, ``*.mcap`` or a folder name (see :func:`bag_format`); must not exist.
    storage : str
        ``mcap`` (default) or ``sqlite3``, for rosbag2 folders.

    Raises
    ------
    OutputError
        The path exists, or its folder does not.
    """

    def __init__(self, path: str | Path, storage: str = "mcap") -> None:
        require("rosbags", "ros", "ROS bags")
        from rosbags.typesys import Stores, get_typestore

        self.path = Path(path)
        self.format = bag_format(self.path, storage)
        if self.path.exists():
            msg = f"{self.path}: already exists; a bag is never overwritten"
            raise OutputError(msg)
        if not self.path.parent.is_dir():
            msg = f"{self.path}: folder {self.path.parent} does not exist"
            raise OutputError(msg)
        store = Stores.ROS1_NOETIC if self.format is BagFormat.ROS1 else Stores.ROS2_HUMBLE
        self.typestore: Any = get_typestore(store)
        if "tf2_msgs/msg/TFMessage" not in self.typestore.fielddefs:  # Noetic's store lacks it
            from rosbags.typesys import get_types_from_msg

            self.typestore.register(get_types_from_msg(
                "geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))
        self._tmp = Path(tempfile.mkdtemp(prefix=f".{self.path.name}.", dir=self.path.parent))
        self._writer: Any = None
        self._connections: dict[str, Any] = {}
        self.counts: dict[str, int] = {}
        self._arc_bytes: _ArcBytes | None = None  # see _write_arcs

    @property
    def is_ros1(self) -> bool:
        """True for rosbag1 output (ROS 1 serialisation and definitions)."""
        return self.format is BagFormat.ROS1

    def __enter__(self) -> BagWriter:
        if self.is_ros1:
            from rosbags.rosbag1 import Writer as Writer1

            self._writer = Writer1(self._tmp / "bag.bag")
        else:
            from rosbags.rosbag2 import StoragePlugin
            from rosbags.rosbag2 import Writer as Writer2

            plugin = (StoragePlugin.SQLITE3 if self.format is BagFormat.ROS2_SQLITE3
                      else StoragePlugin.MCAP)
            self._writer = Writer2(self._tmp / self.path.stem, version=9,
                                   storage_plugin=plugin)
        self._writer.open()
        return self

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None,
                 tb: TracebackType | None) -> None:
        try:
            self._writer.close()
            if kind is None:
                self._move_into_place()
        finally:
            shutil.rmtree(self._tmp, ignore_errors=True)

    def _move_into_place(self) -> None:
        if self.format is BagFormat.ROS1:
            (self._tmp / "bag.bag").replace(self.path)
        elif self.format is BagFormat.MCAP_FILE:
            (mcap,) = (self._tmp / self.path.stem).glob("*.mcap")
            mcap.replace(self.path)
        else:
            (self._tmp / self.path.stem).replace(self.path)

    def connection(self, topic: str, msgtype: str, typestore: Any = None) -> Any:
        """The connection of ``topic`` (added on first use, with ``msgtype``'s definition)."""
        conn = self._connections.get(topic)
        if conn is None:
            conn = self._writer.add_connection(topic, msgtype,
                                               typestore=typestore or self.typestore)
            self._connections[topic] = conn
            self.counts[topic] = 0
        return conn

    def write(self, topic: str, msgtype: str, t: float, fields: Mapping[str, Any]) -> None:
        """Write one message built from ``fields`` (see :meth:`message`), logged at ``t`` s."""
        # Zero-valued parts shared within the message (a marker array's thousands of unused
        # textures and lifetimes built once): it is serialised and dropped, never changed.
        message = _build(self.typestore, msgtype, fields, {})
        data = (self.typestore.serialize_ros1(message, msgtype) if self.is_ros1
                else self.typestore.serialize_cdr(message, msgtype))
        self.write_raw(topic, msgtype, t, data)

    def write_raw(self, topic: str, msgtype: str, t: float, data: bytes | memoryview,
                  typestore: Any = None) -> None:
        """Write already serialised bytes (this bag's ROS version) logged at ``t`` s."""
        conn = self.connection(topic, msgtype, typestore)
        self._writer.write(conn, max(round(t * 1e9), 0), data)
        self.counts[topic] += 1

    def message(self, msgtype: str, fields: Mapping[str, Any]) -> Any:
        """A message of ``msgtype`` in this bag's typestore: ``fields`` (nested mappings for
        nested messages, lists of mappings for message sequences) over zero values; fields the
        type does not have are ignored (so ROS 2 mappings suit ROS 1 types)."""
        return _build(self.typestore, msgtype, fields)


#: One field of a message type, its kinds as plain strings (see :func:`_plan`): name, kind
#: (``NAME``, ``ARRAY``, ``SEQUENCE`` or a base type's), the element's kind and type (a
#: message type name or a base type tuple) for a nested message or a container, the size of an
#: array, and the zero value of a plain one.
_Field = tuple[str, str, str, Any, int, Any]
#: A type's fields as (name, zero) pairs in its order, when all are plain values; else None.
_Flat = tuple[tuple[str, Any], ...] | None

#: Per typestore and message type, its fields (:data:`_Field`) and, for a type of plain fields
#: only (geometry_msgs/Point), their names and zeros (:func:`_flat`): rosbags describes each
#: field with enums, and a long log's arc markers (thousands of points per message) read those
#: enums' names some 30 million times, most of the 33 s of the office tour to a bag.
_PLANS: dict[tuple[int, str], tuple[Any, tuple[_Field, ...], _Flat]] = {}


def _planned(ts: Any, msgtype: str) -> tuple[Any, tuple[_Field, ...], _Flat]:
    key = (id(ts), msgtype)
    cached = _PLANS.get(key)
    if cached is None or cached[0] is not ts:  # an id reused by another typestore: anew
        _, defs = ts.fielddefs[msgtype]
        fields: list[_Field] = []
        for name, (kind, detail) in defs:
            if kind.name in {"ARRAY", "SEQUENCE"}:
                (inner_kind, inner), size = detail
                fields.append((name, kind.name, inner_kind.name, inner,
                               size if kind.name == "ARRAY" else 0, None))
            elif kind.name == "NAME":
                fields.append((name, "NAME", "", detail, 0, None))
            else:
                fields.append((name, kind.name, "", None, 0, _scalar_zero(detail[0])))
        plain = all(field[1] not in {"NAME", "ARRAY", "SEQUENCE"} for field in fields)
        flat = tuple((field[0], field[5]) for field in fields) if plain else None
        cached = (ts, tuple(fields), flat)
        _PLANS[key] = cached
    return cached


def _plan(ts: Any, msgtype: str) -> tuple[_Field, ...]:
    return _planned(ts, msgtype)[1]


def _flat(ts: Any, msgtype: str) -> _Flat:
    """The fields' names and zeros, in the type's order, if every field is a plain value."""
    return _planned(ts, msgtype)[2]


def _build(ts: Any, msgtype: str, fields: Mapping[str, Any] | Any,
           zeros: dict[_Field, Any] | None = None) -> Any:
    """A message of ``msgtype`` from ``fields`` (see :meth:`BagWriter.message`); with
    ``zeros``, the zero value of each field not given is built once and kept there (shared
    by every message built with the same ``zeros``)."""
    if type(fields) is not dict and not isinstance(fields, Mapping):  # dict: the usual, fast
        return fields  # already a message
    flat = _flat(ts, msgtype)
    if flat is not None:  # plain fields only (a Point, a Time): no field needs a plan
        return ts.types[msgtype](*[fields.get(name, zero) for name, zero in flat])
    values = {field[0]: _value(ts, field, fields[field[0]], zeros) if field[0] in fields
              else _zero(ts, field, zeros)
              for field in _plan(ts, msgtype)}
    return ts.types[msgtype](**values)


def _value(ts: Any, field: _Field, value: Any, zeros: dict[_Field, Any] | None) -> Any:
    _, kind, inner_kind, inner, _, _ = field
    if kind == "NAME":
        return _build(ts, inner, value, zeros)
    if kind in {"ARRAY", "SEQUENCE"}:
        if inner_kind == "NAME":
            return _build_all(ts, inner, value, zeros)
        if inner[0] in _NUMERIC:
            return np.asarray(value, dtype=_DTYPES.get(inner[0], inner[0]))
        return list(value)
    return value


def _build_all(ts: Any, msgtype: str, values: Iterable[Any],
               zeros: dict[_Field, Any] | None) -> list[Any]:
    """``[_build(ts, msgtype, v) for v in values]``, faster for a type of plain fields (an arc
    marker's points, thousands a message): the class and the fields looked up once."""
    flat = _flat(ts, msgtype)
    if flat is None:
        return [_build(ts, msgtype, v, zeros) for v in values]
    cls = ts.types[msgtype]
    return [v if type(v) is cls  # already a message (arc_markers' points)
            else cls(*[v.get(name, zero) for name, zero in flat]) if type(v) is dict
            else _build(ts, msgtype, v) for v in values]


def _zero(ts: Any, field: _Field, zeros: dict[_Field, Any] | None) -> Any:
    if zeros is None or field[1] not in {"NAME", "ARRAY", "SEQUENCE"}:  # a plain value: as is
        return _new_zero(ts, field)
    zero = zeros.get(field)
    if zero is None:
        zero = zeros[field] = _new_zero(ts, field)
    return zero


def _new_zero(ts: Any, field: _Field) -> Any:
    _, kind, inner_kind, inner, size, base = field
    if kind == "NAME":
        return _build(ts, inner, {})
    if kind in {"ARRAY", "SEQUENCE"}:
        if inner_kind == "NAME":
            return [_build(ts, inner, {}) for _ in range(size)]
        if inner[0] in _NUMERIC:
            return np.zeros(size, dtype=_DTYPES.get(inner[0], inner[0]))
        return [""] * size
    return base  # a plain value's zero, made once by _plan


def _scalar_zero(base: str) -> Any:
    """The zero value of the base type ``base`` (``float64``, ``string``, ...)."""
    if base == "string":
        return ""
    if base == "bool":
        return False
    return 0.0 if base.startswith("float") else 0


@dataclass(frozen=True)
class BagOutReport:
    """What :func:`write_map_bag` wrote.

    Attributes
    ----------
    path : Path
        The bag.
    format : BagFormat
        Its format.
    messages : dict of str to int
        Messages written per topic.
    """

    path: Path
    format: BagFormat
    messages: dict[str, int]


def write_map_bag(
    path: str | Path,
    batch: ReadingBatch,
    method: LiveMethod,
    *,
    odometry: FloatArray | None = None,
    copy_from: str | Path | None = None,
    frame: str = "odom",
    base_frame: str = "base_link",
    rate: float = 2.0,
    storage: str = "mcap",
    grid: LiveGrid | None = None,
    ids: npt.ArrayLike | None = None,
    on_progress: Callable[[int], None] | None = None,
) -> BagOutReport:
    """Run ``method`` over ``batch`` and write its live map and arcs as a ROS bag.

    Parameters
    ----------
    path : str or Path
        New bag: ``*.bag`` (ROS 1), ``*.mcap`` (bare MCAP file) or a rosbag2 folder.
    batch : ReadingBatch
        Readings in the odometry frame, time order.
    method : LiveMethod
        A fresh method (:func:`~sonarcarve.methods.make_method`); fed every reading.
    odometry : ndarray, shape (m, 4), optional
        Robot poses ``(t, x, y, yaw)`` (s, m, rad) written as ``/odom`` (nav_msgs/Odometry)
        and ``/tf`` (``frame`` → ``base_frame``). Leave out when ``copy_from`` holds them.
    copy_from : str or Path, optional
        A bag whose messages are copied through first (all topics).
    frame : str
        The odometry frame: the point clouds' and markers' ``frame_id``.
    base_frame : str
        The robot's frame (child of the odometry).
    rate : float
        Local maps (and arc markers) per second of log time, > 0.
    storage : str
        ``mcap`` or ``sqlite3`` for rosbag2 folders.
    grid : LiveGrid, optional
        A fresh occupancy grid fed the same readings and written as ``/sonarcarve/grid``
        (``nav_msgs/OccupancyGrid``) with every local map.
    ids : array-like of int, optional
        Each reading's id (the arc markers' ids): the input rows of readings a filter kept;
        default, row positions.
    on_progress : callable, optional
        Called with the number of readings mapped so far at every local map written and at
        the end (with ``len(batch)``): for a progress bar (a long log takes milliseconds per
        reading here, the local map and grid read at ``rate``).

    Returns
    -------
    BagOutReport

    Raises
    ------
    OutputError
        The path exists or its folder does not; a rate that is not > 0; a copied message type
        the output's ROS version does not know.
    RosbagError
        ``copy_from`` is no readable bag.
    ReadingsError
        ``ids`` not one increasing integer per reading (nothing written).
    """
    if not (math.isfinite(rate) and rate > 0.0):
        msg = f"the local map rate must be > 0 per second, got {rate}"
        raise OutputError(msg)
    row_ids = reading_ids(len(batch), ids)  # checked before anything is written
    with BagWriter(path, storage) as out:
        if copy_from is not None:
            copy_messages(out, Path(copy_from))
        if odometry is not None:
            _write_odometry(out, np.asarray(odometry, dtype=np.float64).reshape(-1, 4), frame,
                            base_frame)
        _write_maps(out, batch, row_ids, method, frame, rate, grid, on_progress)
    return BagOutReport(path=out.path, format=out.format, messages=dict(out.counts))


def copy_messages(out: BagWriter, source: Path, topics: Iterable[str] | None = None) -> None:
    """Copy the messages of ``source`` (all topics, or ``topics``) into ``out``, logged at their
    original times. Same ROS version: the bytes as they are; otherwise each message rebuilt in
    the output's types."""
    from sonarcarve.io.rosbag import _iterate, _open_reader

    wanted = None if topics is None else set(topics)
    reader = _open_reader(source)
    try:
        connections = [c for c in reader.connections if wanted is None or c.topic in wanted]
        same = (not reader.is2) == out.is_ros1
        if same:
            for conn, t_ns, raw in reader.messages(connections=connections):
                out.write_raw(conn.topic, conn.msgtype, t_ns * 1e-9, raw,
                              typestore=reader.typestore)
            return
        for conn, message in _iterate(source, reader, connections):
            if conn.msgtype not in out.typestore.fielddefs:
                msg = (f"{source}: topic {conn.topic!r} has type {conn.msgtype}, which "
                       f"{out.format.value} output does not know; write the same ROS version")
                raise OutputError(msg)
            fields = _fields_of(message)
            out.write(conn.topic, conn.msgtype, _header_time(message), fields)
    finally:
        reader.close()


def _fields_of(message: Any) -> Any:
    """A message as nested mappings (numpy arrays and plain values kept)."""
    names = getattr(message, "__dataclass_fields__", None)
    if names is None:
        if isinstance(message, list):
            return [_fields_of(v) for v in message]
        return message
    return {name: _fields_of(getattr(message, name)) for name in names}


def _header_time(message: Any) -> float:
    header = getattr(message, "header", None)
    if header is None:
        return 0.0
    return float(header.stamp.sec) + 1e-9 * float(header.stamp.nanosec)


def _write_odometry(out: BagWriter, odometry: FloatArray, frame: str, base_frame: str) -> None:
    for t, x, y, yaw in odometry.tolist():
        header = {"stamp": stamp(t), "frame_id": frame}
        pose = {"position": {"x": x, "y": y, "z": 0.0}, "orientation": quaternion(yaw)}
        out.write("/odom", "nav_msgs/msg/Odometry", t,
                  {"header": header, "child_frame_id": base_frame, "pose": {"pose": pose}})
        out.write("/tf", "tf2_msgs/msg/TFMessage", t, {"transforms": [{
            "header": header, "child_frame_id": base_frame,
            "transform": {"translation": {"x": x, "y": y, "z": 0.0},
                          "rotation": quaternion(yaw)}}]})


def _write_maps(out: BagWriter, batch: ReadingBatch, ids: IntArray, method: LiveMethod,
                frame: str, rate: float, grid: LiveGrid | None,
                on_progress: Callable[[int], None] | None = None) -> None:
    if len(batch) == 0:
        return
    period = 1.0 / rate
    next_t = float(batch.t[0]) + period
    for k, reading in enumerate(batch):
        while reading.t >= next_t:
            _write_snapshot(out, method, next_t, frame, grid)
            next_t += period
            if on_progress is not None:
                on_progress(k)
        method.add(reading, int(ids[k]))
        if grid is not None:
            grid.add(reading)
    _write_snapshot(out, method, float(batch.t[-1]), frame, grid)
    if on_progress is not None:
        on_progress(len(batch))


def _write_snapshot(out: BagWriter, method: LiveMethod, t: float, frame: str,
                    grid: LiveGrid | None) -> None:
    local = method.local_map()
    header = {"stamp": stamp(t), "frame_id": frame}
    out.write(LOCAL_MAP_TOPIC, "sensor_msgs/msg/PointCloud2", t,
              {"header": header, **point_cloud_fields(local)})
    _write_arcs(out, arc_strips(method), header, t)
    if grid is not None:
        out.write(GRID_TOPIC, "nav_msgs/msg/OccupancyGrid", t,
                  {"header": header, **occupancy_grid_fields(grid, t)})


def _write_arcs(out: BagWriter, strips: ArcStrips, header: Mapping[str, Any], t: float) -> None:
    """The arc markers as bytes laid out directly (:mod:`sonarcarve.io.marker_bytes`), or, for
    a typestore whose layout that does not reproduce, as message objects serialised by rosbags."""
    data = _ArcBytes.of(out).serialise(header, strips)
    if data is not None:
        out.write_raw(ARCS_TOPIC, _MARKER_ARRAY, t, data)
        return
    point = out.typestore.types["geometry_msgs/msg/Point"]  # the points as messages at once
    out.write(ARCS_TOPIC, _MARKER_ARRAY, t, {"markers": _markers(strips, header, point)})


class _ArcBytes:
    """A bag's arc markers laid out as bytes, used only where they are rosbags' own bytes.

    For each frame id, a sample message (every style, a strip of no point, a NaN point) is
    laid out both ways first; if the bytes differ, or the typestore's types are not laid out
    here at all, that bag's markers are message objects, as before: slower, never corrupt.
    """

    def __init__(self, out: BagWriter) -> None:
        from sonarcarve.io.marker_bytes import StripArray, UnsupportedLayoutError

        self.out = out
        self.checked: dict[str, bool] = {}  # per frame id: the sample's bytes were rosbags'
        self.strips: StripArray | None
        try:
            self.strips = StripArray(out.typestore, out.is_ros1, [*_STYLES, _DELETE_ALL])
        except (UnsupportedLayoutError, KeyError, TypeError, ValueError, AttributeError):
            self.strips = None

    @classmethod
    def of(cls, out: BagWriter) -> _ArcBytes:
        """The writer's own (made at its first arcs)."""
        if out._arc_bytes is None:
            out._arc_bytes = cls(out)
        return out._arc_bytes

    def serialise(self, header: Mapping[str, Any], strips: ArcStrips) -> memoryview | None:
        """The MarkerArray of ``strips`` (DELETEALL first), or None: write message objects."""
        if self.strips is None:
            return None
        frame = str(header["frame_id"])
        agrees = self.checked.get(frame)
        if agrees is None:
            agrees = self.checked[frame] = self._agrees(self.strips, frame)
        return self._bytes(self.strips, header, strips) if agrees else None

    @staticmethod
    def _bytes(layout: StripArray, header: Mapping[str, Any], strips: ArcStrips) -> memoryview:
        # DELETEALL first: the style after the strips' (id 0 and no points, as _markers' one)
        return layout.serialise(header, np.r_[len(_STYLES), strips.style], np.r_[0, strips.ids],
                                np.r_[0, strips.counts], strips.x, strips.y)

    def _agrees(self, layout: StripArray, frame: str) -> bool:
        header = {"stamp": {"sec": 1234, "nanosec": 567_890_123}, "frame_id": frame}
        counts = np.array([2, 3, 0, 1, 5, 2], dtype=np.int64)
        sample = ArcStrips(ids=np.array([7, -3, 2**31 - 1, 0, 12, 5]),
                           style=np.arange(counts.size) % len(_STYLES), counts=counts,
                           x=np.linspace(-2.0, 3.0, int(counts.sum())),
                           y=np.r_[np.nan, np.linspace(1.0, -4.0, int(counts.sum()) - 1)])
        ts, msgtype = self.out.typestore, _MARKER_ARRAY
        try:
            message = _build(ts, msgtype, {"markers": _markers(sample, header)})
            expected = (ts.serialize_ros1(message, msgtype) if self.out.is_ros1
                        else ts.serialize_cdr(message, msgtype))
            return bytes(self._bytes(layout, header, sample)) == bytes(expected)
        except (SonarcarveError, KeyError, TypeError, ValueError, AttributeError,
                struct.error):
            return False


def occupancy_grid_fields(grid: LiveGrid, t: float) -> dict[str, Any]:
    """The OccupancyGrid fields (all but the header) of ``grid``: ``info`` (resolution, width,
    height, origin at the grid's lower-left corner) and ``data``, row-major from that corner."""
    cells = np.asarray(grid.trinary(), dtype=np.int8)
    rows, columns = cells.shape
    return {
        "info": {"map_load_time": stamp(t), "resolution": float(grid.resolution),
                 "width": int(columns), "height": int(rows),
                 "origin": {"position": {"x": float(grid.bounds[0]),
                                         "y": float(grid.bounds[1]), "z": 0.0},
                            "orientation": quaternion(0.0)}},
        "data": np.ascontiguousarray(cells).reshape(-1),
    }


def point_cloud_fields(local: LocalMap) -> dict[str, Any]:
    """The PointCloud2 fields (all but the header) of a local map: float32 x, y, z = 0,
    source, width, max_error, confidence, one point per map point."""
    n = len(local)
    table = np.zeros((n, len(LOCAL_MAP_FIELDS)), dtype="<f4")
    table[:, 0], table[:, 1] = local.xy[:, 0], local.xy[:, 1]
    table[:, 3], table[:, 4] = local.source, local.width
    table[:, 5], table[:, 6] = local.max_error, local.confidence
    step = 4 * len(LOCAL_MAP_FIELDS)
    return {
        "height": 1, "width": n, "is_bigendian": False, "point_step": step,
        "row_step": step * n, "is_dense": True,
        "fields": [{"name": name, "offset": 4 * i, "datatype": _POINTFIELD_FLOAT32, "count": 1}
                   for i, name in enumerate(LOCAL_MAP_FIELDS)],
        "data": np.frombuffer(table.tobytes(), dtype=np.uint8),
    }


@dataclass(frozen=True)
class ArcStrips:
    """The live arcs of a method as marker polylines, all points of all arcs in one array.

    Attributes
    ----------
    ids : ndarray of int
        Each arc's reading id (its marker's id).
    style : ndarray of int
        Each arc's index in the marker styles, by :class:`~sonarcarve.maps.PointSource`.
    counts : ndarray of int
        Points of each arc (at least 2).
    x, y : ndarray of float
        The points, arc after arc (``counts[0]`` of the first arc, then the next...).
    """

    ids: IntArray
    style: IntArray
    counts: IntArray
    x: FloatArray
    y: FloatArray


def arc_strips(method: LiveMethod) -> ArcStrips:
    """The live arcs of ``method``'s history as polylines: radius r about the sensor origin,
    the estimate's width centred on its point, a point every 2° or less (at least 2).

    Raises
    ------
    OutputError
        An arc of a width that is not finite, of a source that is no
        :class:`~sonarcarve.maps.PointSource`, or of a reading id beyond int32.
    """
    from sonarcarve.io.marker_bytes import arc_points

    h = method.history
    slots = np.asarray(h.slots(), dtype=np.int64)
    est = method.estimates(slots)
    alive = np.flatnonzero(est.alive)
    slot = slots[alive]
    xy = np.asarray(est.xy, dtype=np.float64)[alive]
    half = 0.5 * np.asarray(est.width, dtype=np.float64)[alive]
    if not np.all(np.isfinite(half)):
        msg = "an arc's width is not finite; its marker cannot be drawn"
        raise OutputError(msg)
    source = np.asarray(est.source, dtype=np.int64)[alive]
    if source.size and (source.min() < 0 or source.max() >= _STYLE_OF_SOURCE.size
                        or np.any(_STYLE_OF_SOURCE[source] < 0)):
        msg = f"an arc's source is no PointSource code: {sorted(set(source.tolist()))}"
        raise OutputError(msg)
    ids = np.asarray(h.reading_id, dtype=np.int64)[slot]
    if ids.size and (ids.min() < -(2**31) or ids.max() >= 2**31):
        msg = f"reading ids up to {int(ids.max())} do not fit a marker's id (int32)"
        raise OutputError(msg)
    # max(2, math.ceil(2 * half / _ARC_SEGMENT) + 1), the same operations
    counts = np.maximum(2, np.ceil(2 * half / _ARC_SEGMENT) + 1).astype(np.int64)
    x, y = arc_points(np.asarray(h.x, dtype=np.float64)[slot],
                      np.asarray(h.y, dtype=np.float64)[slot],
                      np.asarray(h.r, dtype=np.float64)[slot], xy[:, 0], xy[:, 1], half, counts)
    return ArcStrips(ids=ids, style=_STYLE_OF_SOURCE[source], counts=counts, x=x, y=y)


def arc_markers(method: LiveMethod, header: Mapping[str, Any], *,
                point: Callable[[float, float, float], Any] | None = None,
                ) -> list[dict[str, Any]]:
    """Marker mappings: ``DELETEALL``, then one ``LINE_STRIP`` per live arc of ``method``'s
    history (:func:`arc_strips`), coloured by source.

    ``point(x, y, z)`` makes each point of a strip (default: a mapping); a bag writer passes
    its ``geometry_msgs/Point`` class, which skips a mapping and its reading for each of the
    millions of points of a long log.
    """
    return _markers(arc_strips(method), header, point)


def _markers(strips: ArcStrips, header: Mapping[str, Any],
             point: Callable[[float, float, float], Any] | None = None) -> list[dict[str, Any]]:
    make_point = _point_mapping if point is None else point
    markers: list[dict[str, Any]] = [{"header": header, **_DELETE_ALL}]
    xs, ys = strips.x.tolist(), strips.y.tolist()
    end = 0
    for reading_id, style, count in zip(strips.ids.tolist(), strips.style.tolist(),
                                        strips.counts.tolist(), strict=True):
        start, end = end, end + count
        markers.append({"header": header, "id": reading_id, **_strip_style(style),
                        "points": [make_point(x, y, 0.0)
                                   for x, y in zip(xs[start:end], ys[start:end], strict=True)]})
    return markers


def _strip_style(style: int) -> dict[str, Any]:
    """The fields of a strip of style ``style`` but its header, id and points."""
    r, g, b = _SOURCE_RGB[_SOURCES[style]]
    return {"ns": "arcs", "type": _MARKER_LINE_STRIP, "action": 0,
            "pose": {"orientation": {"w": 1.0}}, "scale": {"x": 0.02},
            "color": {"r": r, "g": g, "b": b, "a": 1.0}}


def _point_mapping(x: float, y: float, z: float) -> dict[str, float]:
    return {"x": x, "y": y, "z": z}


#: Marker styles: one per source, in _SOURCE_RGB's order, and each source code's style.
_SOURCES = tuple(_SOURCE_RGB)
_STYLES = tuple(_strip_style(k) for k in range(len(_SOURCES)))
#: The first marker of every array: clear what the last one drew.
_DELETE_ALL = {"ns": "arcs", "action": _MARKER_DELETEALL}
_STYLE_OF_SOURCE = np.full(max(int(s) for s in _SOURCES) + 1, -1, dtype=np.int64)
_STYLE_OF_SOURCE[[int(s) for s in _SOURCES]] = np.arange(len(_SOURCES))
