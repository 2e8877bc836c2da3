"""Arc markers straight to a bag's bytes: rosbags' layout, without a message object per point.

The ``/sonarcarve/arcs`` MarkerArray of a long log carries millions of points (the office tour
about 4.5 M). Built as ``geometry_msgs/Point`` objects and packed one field at a time by rosbags,
they cost most of the CPU of ``sonarcarve process LOG --out X.mcap``. Here:

- :func:`arc_points` computes every point of every arc in one compiled loop, with the same
  arithmetic, operation for operation, as the Python it replaces (``np.linspace`` per arc,
  ``ox + r * math.cos(a)``): numba's ``math.cos`` and ``math.sin`` call the C library's, as
  CPython's do, so the points are the same bits (``tests/io/test_marker_bytes.py`` holds them to
  that Python);
- :class:`StripArray` lays out a ``visualization_msgs/MarkerArray`` of markers that differ only
  in their id, their style (one of a few field mappings: action, type, colour, ...) and their
  points. Each style's bytes up to the points and the bytes after them are encoded once per bag
  and frame id from the typestore's own field definitions (:class:`_Encoder`), and copied per
  marker by a compiled loop.

The byte layouts are rosbags': ROS 1 little-endian and unpadded, strings as a uint32 length and
their bytes; CDR (ROS 2) a 4-byte header ``00 01 00 00`` (little-endian CDR), then each
primitive aligned to its own size counted from the end of that header, strings as a uint32
length counting a closing NUL, their bytes and the NUL, padding bytes zero. A typestore whose
types hold anything else raises :class:`UnsupportedLayoutError`; :mod:`sonarcarve.io.bag_out` also
compares a sample message with rosbags' bytes before using this, and writes message objects
when the two differ.

This module imports numba: :mod:`sonarcarve.io.bag_out` imports it when it first writes arcs.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numba import njit

from sonarcarve.errors import SonarcarveError
from sonarcarve.typing import FloatArray, IntArray

__all__ = ["StripArray", "UnsupportedLayoutError", "arc_points"]

#: struct formats of the plain types this encoder writes (all little-endian).
_FORMATS = {"bool": "?", "int8": "b", "uint8": "B", "int16": "h", "uint16": "H", "int32": "i",
            "uint32": "I", "int64": "q", "uint64": "Q", "float32": "f", "float64": "d"}
#: CDR's encapsulation header: representation CDR_LE (0x0001), options 0.
_CDR_HEADER = b"\x00\x01\x00\x00"
#: Alignment is counted modulo this in CDR (no primitive is wider than 8 bytes).
_CDR_PHASES = 8
_INT32 = (-(2**31), 2**31 - 1)


class UnsupportedLayoutError(SonarcarveError):
    """A message type this encoder does not lay out (rosbags' objects are used instead)."""


@njit(cache=True)
def _arc_points_kernel(ox: FloatArray, oy: FloatArray, r: FloatArray, ex: FloatArray,
                       ey: FloatArray, half: FloatArray, steps: IntArray, x: FloatArray,
                       y: FloatArray) -> None:
    k = 0
    for i in range(ox.size):
        mid = math.atan2(ey[i] - oy[i], ex[i] - ox[i])
        start = mid - half[i]
        stop = mid + half[i]
        div = steps[i] - 1
        delta = stop - start
        step = delta / div
        for j in range(steps[i]):  # np.linspace(start, stop, steps[i]), its operations
            if j == div:
                a = stop  # linspace sets its endpoint exactly
            elif step == 0.0:
                a = j / div * delta + start  # linspace's branch for a step that underflows
            else:
                a = j * step + start
            x[k] = ox[i] + r[i] * math.cos(a)
            y[k] = oy[i] + r[i] * math.sin(a)
            k += 1


def arc_points(ox: FloatArray, oy: FloatArray, r: FloatArray, ex: FloatArray, ey: FloatArray,
               half: FloatArray, steps: IntArray) -> tuple[FloatArray, FloatArray]:
    """The points of arcs of radius ``r`` about ``(ox, oy)``, centred on the direction of
    ``(ex, ey)`` and ``2 * half`` wide, ``steps`` (>= 2) evenly spaced points each, all arcs'
    points one after the other: ``x``, ``y``. Bit for bit the values of::

        mid = math.atan2(ey - oy, ex - ox)
        [(ox + r * math.cos(a), oy + r * math.sin(a))
         for a in np.linspace(mid - half, mid + half, steps).tolist()]
    """
    steps = np.asarray(steps, dtype=np.int64)
    total = int(steps.sum())
    x, y = np.empty(total), np.empty(total)
    ox, oy, r, ex, ey, half = (np.ascontiguousarray(v, dtype=np.float64)
                               for v in (ox, oy, r, ex, ey, half))
    _arc_points_kernel(ox, oy, r, ex, ey, half, steps, x, y)
    return x, y


@njit(cache=True)
def _put_int(out: np.ndarray, at: int, value: int, size: int) -> None:
    for b in range(size):  # little-endian, two's complement
        out[at + b] = (value >> (8 * b)) & 0xFF


@njit(cache=True)
def _fill_strips(out: np.ndarray, origin: int, pos: int, phases: int, prefixes: np.ndarray,
                 prefix_len: IntArray, id_at: IntArray, count_at: IntArray, tails: np.ndarray,
                 tail_len: IntArray, point_align: int, style: IntArray, ids: IntArray,
                 counts: IntArray, points: np.ndarray) -> int:
    """Lay the strips out from ``pos``; alignment counted from ``origin``; returns the end.

    ``prefixes[phase * n_styles + style]`` are a style's bytes up to and with its point count,
    encoded from a position ``phase`` past an aligned one; ``tails[phase * n_styles + style]``
    its bytes after the points. ``points`` holds 24 bytes (x, y, z float64) a point, strip
    after strip.
    """
    n_styles = prefixes.shape[0] // phases
    first = 0
    for i in range(ids.size):
        row = ((pos - origin) % phases) * n_styles + style[i]
        size = prefix_len[row]
        out[pos:pos + size] = prefixes[row, :size]
        _put_int(out, pos + id_at[row], ids[i], 4)
        _put_int(out, pos + count_at[row], counts[i], 4)
        pos += size
        n = counts[i]
        if n > 0:
            pos += (origin - pos) % point_align
            out[pos:pos + 24 * n] = points[24 * first:24 * (first + n)]
            pos += 24 * n
            first += n
        row = ((pos - origin) % phases) * n_styles + style[i]
        out[pos:pos + tail_len[row]] = tails[row, :tail_len[row]]
        pos += tail_len[row]
    return pos


class _Encoder:
    """One message's bytes from field mappings (fields not given: zero), from position ``pos``
    (CDR pads to it), recording where each plain field lands (``at``, dotted paths)."""

    def __init__(self, ts: Any, ros1: bool, pos: int) -> None:
        self.ts, self.ros1, self.start = ts, ros1, pos
        self.buf = bytearray()
        self.at: dict[str, int] = {}
        self.base: dict[str, str] = {}

    @property
    def pos(self) -> int:
        return self.start + len(self.buf)

    def align(self, size: int) -> None:
        if not self.ros1:
            self.buf += bytes(-self.pos % size)

    def scalar(self, base: str, value: Any, path: str = "") -> None:
        fmt = _FORMATS.get(base)
        if fmt is None:
            msg = f"no layout for the plain type {base!r}"
            raise UnsupportedLayoutError(msg)
        size = struct.calcsize(fmt)
        self.align(size)
        self.at[path], self.base[path] = self.pos, base
        self.buf += struct.pack("<" + fmt, value)

    def string(self, value: str) -> None:
        data = value.encode()
        self.align(4)
        if self.ros1:
            self.buf += struct.pack("<I", len(data)) + data
        else:
            self.buf += struct.pack("<I", len(data) + 1) + data + b"\x00"

    def message(self, msgtype: str, fields: Mapping[str, Any], path: str = "",
                stop: str | None = None) -> None:
        """The fields of ``msgtype`` in order; with ``stop``, up to that field (a sequence),
        whose element count is left 0 at ``at[path + stop]``."""
        definition = self.ts.fielddefs.get(msgtype)
        if definition is None:
            msg = f"{path or 'the message'}: type {msgtype} is not in the typestore"
            raise UnsupportedLayoutError(msg)
        for name, (kind, detail) in definition[1]:
            if name == stop:
                self.scalar("uint32", 0, path + name)
                return
            if self.ros1 and name == "structure_needs_at_least_one_member":
                continue  # rosbags leaves ROS 2's filler of empty types out of ROS 1
            self.field(kind.name, detail, fields.get(name), path + name)
        if stop is not None:
            msg = f"{msgtype} has no field {stop!r}"
            raise UnsupportedLayoutError(msg)

    def field(self, kind: str, detail: Any, value: Any, path: str) -> None:
        if kind == "NAME":
            self.message(detail, value or {}, path + ".")
        elif kind == "BASE":
            base = detail[0]
            if base == "string":
                self.string(value or "")
            else:
                self.scalar(base, _zero(base) if value is None else value, path)
        elif kind in {"ARRAY", "SEQUENCE"}:
            (inner_kind, inner), size = detail
            if kind == "SEQUENCE":
                items = [] if value is None else value
                self.scalar("uint32", len(items), path)
            else:
                items = [None] * size if value is None else value
                if len(items) != size:
                    msg = f"{path}: {len(items)} values for an array of {size}"
                    raise UnsupportedLayoutError(msg)
            self.items(inner_kind.name, inner, items, path)
        else:
            msg = f"{path}: no layout for a field of kind {kind}"
            raise UnsupportedLayoutError(msg)

    def items(self, kind: str, inner: Any, items: Sequence[Any], path: str) -> None:
        if kind == "NAME":
            for item in items:
                self.message(inner, item or {}, path + "[].")
        elif kind == "BASE" and inner[0] in _FORMATS:
            for item in items:
                self.scalar(inner[0], _zero(inner[0]) if item is None else item)
        else:
            msg = f"{path}: no layout for elements {inner!r}"
            raise UnsupportedLayoutError(msg)


def _zero(base: str) -> Any:
    if base == "bool":
        return False
    return 0.0 if base.startswith("float") else 0


class StripArray:
    """Bytes of a MarkerArray of markers that differ only in id, style and points.

    Parameters
    ----------
    typestore : rosbags Typestore
        The bag's types (ROS 1 Noetic or ROS 2 Humble).
    ros1 : bool
        ROS 1 serialisation, else CDR.
    styles : sequence of mappings
        Each style's marker fields (not ``header``, ``id`` or ``points``): ns, type, colour...

    Raises
    ------
    UnsupportedLayoutError
        The typestore's MarkerArray is not a sequence of markers with an int32 ``id`` and
        ``points`` of three float64 each, or holds a type this encoder does not lay out.
    """

    array_type = "visualization_msgs/msg/MarkerArray"

    def __init__(self, typestore: Any, ros1: bool, styles: Sequence[Mapping[str, Any]]) -> None:
        self.ts, self.ros1, self.styles = typestore, ros1, list(styles)
        self.marker_type = self._marker_type()
        self.phases = 1 if ros1 else _CDR_PHASES
        self.point_align = 1 if ros1 else 8
        self._templates: dict[str, tuple[np.ndarray, ...]] = {}

    def _fields(self, msgtype: str) -> dict[str, Any]:
        definition = self.ts.fielddefs.get(msgtype)
        if definition is None:
            msg = f"type {msgtype} is not in the typestore"
            raise UnsupportedLayoutError(msg)
        return dict(definition[1])

    def _marker_type(self) -> str:
        kind, detail = self._fields(self.array_type).get("markers", (None, None))
        if kind is None or kind.name != "SEQUENCE" or detail[0][0].name != "NAME":
            msg = f"{self.array_type}: no sequence of markers"
            raise UnsupportedLayoutError(msg)
        marker = detail[0][1]
        fields = self._fields(marker)
        kind_id, id_detail = fields.get("id", (None, None))
        if kind_id is None or kind_id.name != "BASE" or id_detail[0] != "int32":
            msg = f"{marker}: no int32 id"
            raise UnsupportedLayoutError(msg)
        kind_points, points = fields.get("points", (None, None))
        if kind_points is None or kind_points.name != "SEQUENCE" or points[0][0].name != "NAME":
            msg = f"{marker}: no sequence of points"
            raise UnsupportedLayoutError(msg)
        point_fields = [(name, kind.name, detail)
                        for name, (kind, detail) in self._fields(points[0][1]).items()]
        if point_fields != [(axis, "BASE", ("float64", 0)) for axis in "xyz"]:
            msg = f"{points[0][1]}: not three float64 x, y, z"
            raise UnsupportedLayoutError(msg)
        return str(marker)

    def _templates_for(self, frame_id: str) -> tuple[np.ndarray, ...]:
        """Per phase and style the bytes up to the point count and those after the points,
        with where the stamp, id and count go (stamp zero)."""
        cached = self._templates.get(frame_id)
        if cached is not None:
            return cached
        header = {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": frame_id}
        prefixes, tails, bases = [], [], set()
        for phase in range(self.phases):
            for style in self.styles:
                enc = _Encoder(self.ts, self.ros1, phase)
                enc.message(self.marker_type, {**style, "header": header}, stop="points")
                prefixes.append((bytes(enc.buf), enc.at, phase))
                bases.add((enc.base.get("header.stamp.sec"), enc.base.get("header.stamp.nanosec")))
                enc = _Encoder(self.ts, self.ros1, phase)
                self._tail(enc, style)
                tails.append(bytes(enc.buf))
        width = max(len(p[0]) for p in prefixes)
        table = np.zeros((len(prefixes), width), dtype=np.uint8)
        for row, (data, _, _) in enumerate(prefixes):
            table[row, :len(data)] = np.frombuffer(data, dtype=np.uint8)
        holes = ("header.stamp.sec", "header.stamp.nanosec", "id", "points")
        if bases != {("int32", "uint32")} or any(name not in at for _, at, _ in prefixes
                                                 for name in holes):
            msg = f"{self.marker_type}: no header.stamp of int32 sec and uint32 nanosec"
            raise UnsupportedLayoutError(msg)
        offsets = {name: np.array([at[name] - phase for _, at, phase in prefixes], dtype=np.int64)
                   for name in holes}
        tail_table = np.zeros((len(tails), max(len(t) for t in tails)), dtype=np.uint8)
        for row, data in enumerate(tails):
            tail_table[row, :len(data)] = np.frombuffer(data, dtype=np.uint8)
        cached = (table, np.array([len(p[0]) for p in prefixes], dtype=np.int64),
                  offsets["header.stamp.sec"], offsets["header.stamp.nanosec"], offsets["id"],
                  offsets["points"], tail_table, np.array([len(t) for t in tails], dtype=np.int64))
        self._templates[frame_id] = cached
        return cached

    def _tail(self, enc: _Encoder, style: Mapping[str, Any]) -> None:
        """The marker's fields after ``points``, from ``style`` (zero if not given)."""
        after = False
        for name, (kind, detail) in self.ts.fielddefs[self.marker_type][1]:
            if after and not (self.ros1 and name == "structure_needs_at_least_one_member"):
                enc.field(kind.name, detail, style.get(name), name)
            after = after or name == "points"

    def serialise(self, header: Mapping[str, Any], style: IntArray, ids: IntArray,
                  counts: IntArray, x: FloatArray, y: FloatArray) -> memoryview:
        """The message: one marker per entry of ``style`` (an index into the styles), with
        header ``header``, id ``ids[i]`` and ``counts[i]`` points, the next ones of ``x``,
        ``y`` (z = 0)."""
        ids = np.asarray(ids, dtype=np.int64)
        counts = np.asarray(counts, dtype=np.int64)
        style = np.asarray(style, dtype=np.int64)
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        _check(self.styles, style, ids, counts, x, y)
        prefixes, prefix_len, sec_at, nanosec_at, id_at, count_at, tails, tail_len = (
            self._templates_for(str(header["frame_id"])))
        prefixes = prefixes.copy()
        rows = np.arange(prefixes.shape[0])[:, None]
        prefixes[rows, sec_at[:, None] + np.arange(4)] = np.frombuffer(
            struct.pack("<i", header["stamp"]["sec"]), dtype=np.uint8)
        prefixes[rows, nanosec_at[:, None] + np.arange(4)] = np.frombuffer(
            struct.pack("<I", header["stamp"]["nanosec"]), dtype=np.uint8)
        xyz = np.zeros((x.size, 3), dtype="<f8")
        xyz[:, 0], xyz[:, 1] = x, y
        start = b"" if self.ros1 else _CDR_HEADER
        head = start + struct.pack("<I", ids.size)  # the sequence's length (aligned: first)
        bound = len(head) + ids.size * (prefixes.shape[1] + tails.shape[1] + 8) + 24 * x.size
        out = np.zeros(bound, dtype=np.uint8)
        out[:len(head)] = np.frombuffer(head, dtype=np.uint8)
        end = _fill_strips(out, len(start), len(head), self.phases, prefixes, prefix_len,
                           id_at, count_at, tails, tail_len, self.point_align, style, ids,
                           counts, xyz.reshape(-1).view(np.uint8))
        return memoryview(out[:end].data).toreadonly()


def _check(styles: Sequence[Any], style: IntArray, ids: IntArray, counts: IntArray,
           x: FloatArray, y: FloatArray) -> None:
    """Refuse what would lay out other bytes than rosbags' (or write out of bounds)."""
    if not (style.shape == ids.shape == counts.shape and x.shape == y.shape
            and x.ndim == 1 and style.ndim == 1):
        msg = "a style, an id and a count per marker, and as many x as y, are needed"
        raise UnsupportedLayoutError(msg)
    if ids.size and (ids.min() < _INT32[0] or ids.max() > _INT32[1]):
        msg = f"a marker id must fit int32; got {int(ids.min())} to {int(ids.max())}"
        raise UnsupportedLayoutError(msg)
    if style.size and (style.min() < 0 or style.max() >= len(styles)):
        msg = f"marker styles are 0 to {len(styles) - 1}; got {sorted(set(style.tolist()))}"
        raise UnsupportedLayoutError(msg)
    if np.any(counts < 0) or int(counts.sum()) != x.size:
        msg = f"the markers' point counts (sum {int(counts.sum())}) are not the {x.size} points"
        raise UnsupportedLayoutError(msg)
