"""marker_bytes: arc points bit for bit the Python loop's; MarkerArray bytes rosbags' own.

The oracle of every layout test is rosbags: the bytes it serialises from the message objects
that BagWriter.message builds from the same fields (the path bag_out took before).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from sonarcarve.io.bag_out import BagWriter
from sonarcarve.io.marker_bytes import StripArray, UnsupportedLayoutError, arc_points

MARKER_ARRAY = "visualization_msgs/msg/MarkerArray"
SEGMENT = math.radians(2.0)


def _python_arc(ox: float, oy: float, r: float, ex: float, ey: float, half: float,
                steps: int) -> list[tuple[float, float]]:
    """The loop bag_out ran before (one math.cos and math.sin per point on Python floats)."""
    mid = math.atan2(ey - oy, ex - ox)
    tau = np.linspace(mid - half, mid + half, steps)
    return [(ox + r * math.cos(a), oy + r * math.sin(a)) for a in tau.tolist()]


def _bits(values: Any) -> np.ndarray:
    return np.asarray(values, dtype=np.float64).view(np.uint64)


def test_arc_points_are_the_bits_of_the_python_loop() -> None:
    rng = np.random.default_rng(18)
    n = 3000
    ox = rng.uniform(-50, 50, n) * rng.choice([1e-3, 1.0, 1e3], n)
    oy = rng.uniform(-50, 50, n)
    r = rng.uniform(0.02, 10.0, n)
    bearing = rng.uniform(-4.0, 4.0, n)
    ex, ey = ox + r * np.cos(bearing), oy + r * np.sin(bearing)
    half = 0.5 * rng.choice([0.0, 1e-300, 0.01, 0.3, 0.7, 2 * math.pi], n)
    ex[:3] = np.nan  # an estimate without a point: NaN all along its arc
    steps = np.maximum(2, np.ceil(2 * half / SEGMENT) + 1).astype(np.int64)
    x, y = arc_points(ox, oy, r, ex, ey, half, steps)
    expected = [p for i in range(n) for p in _python_arc(
        float(ox[i]), float(oy[i]), float(r[i]), float(ex[i]), float(ey[i]), float(half[i]),
        int(steps[i]))]
    assert x.size == len(expected) == int(steps.sum())
    assert np.array_equal(_bits(x), _bits([p[0] for p in expected]))
    assert np.array_equal(_bits(y), _bits([p[1] for p in expected]))
    assert np.isnan(x[:int(steps[:3].sum())]).all()


def test_linspace_s_branch_for_a_step_that_underflows_is_kept() -> None:
    # Half a width of the smallest subnormal over 4 steps: the step rounds to 0, and linspace
    # then spreads (j / div) * delta instead, which puts the middle point at 0, not at start.
    args = (0.0, 0.0, 1.0, 1.0, 0.0, 5e-324, 5)
    x, y = arc_points(*[np.array([v]) for v in args[:-1]], np.array([5]))
    expected = _python_arc(*args)
    assert np.array_equal(_bits(y), _bits([p[1] for p in expected]))
    assert np.array_equal(_bits(x), _bits([p[0] for p in expected]))


# Styles: a DELETEALL, two strips of other colours and poses, one that fills fields after the
# points (colors, text, mesh_resource: its bytes after the points are its own too).
STYLES: list[dict[str, Any]] = [
    {"ns": "arcs", "action": 3},
    {"ns": "arcs", "type": 4, "action": 0, "pose": {"orientation": {"w": 1.0}},
     "scale": {"x": 0.02}, "color": {"r": 0.839, "g": 0.153, "b": 0.157, "a": 1.0}},
    {"ns": "a", "type": 4, "pose": {"position": {"x": -1.5, "z": 2.0}},
     "scale": {"x": 0.5, "y": 1e-9}, "color": {"g": 0.25, "a": 0.5}, "frame_locked": True},
    {"ns": "text and more", "type": 9, "colors": [{"r": 1.0}, {"b": 0.5, "a": 1.0}],
     "text": "été", "mesh_resource": "package://x.dae", "mesh_use_embedded_materials": True},
]


def _case(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """style, ids, counts, x, y of a named case."""
    if name == "empty":
        style, ids, counts = [], [], []
    elif name == "delete all only":
        style, ids, counts = [0], [0], [0]
    elif name == "one arc":
        style, ids, counts = [1], [42], [2]
    else:  # many markers, every style, point counts 0 to 7, ids to int32's ends
        rng = np.random.default_rng(len(name))
        m = 60
        style = rng.integers(0, len(STYLES), m).tolist()
        ids = rng.integers(-(2**31), 2**31, m).tolist()
        ids[:2] = [-(2**31), 2**31 - 1]
        counts = rng.integers(0, 8, m).tolist()
    total = int(np.sum(counts, dtype=np.int64))
    rng = np.random.default_rng(7)
    x, y = rng.normal(0.0, 100.0, total), rng.normal(0.0, 1e-3, total)
    if total >= 4:
        x[:4] = [np.nan, np.inf, -0.0, -np.inf]
        y[1] = np.nan
    return (np.array(style, dtype=np.int64), np.array(ids, dtype=np.int64),
            np.array(counts, dtype=np.int64), x, y)


@pytest.fixture(params=["arcs.bag", "arcs.mcap"], ids=["ROS 1", "CDR"])
def writer(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[BagWriter]:
    with BagWriter(tmp_path / request.param) as out:
        yield out


def _rosbags_bytes(out: BagWriter, header: dict[str, Any], style: np.ndarray,
                   ids: np.ndarray, counts: np.ndarray, x: np.ndarray, y: np.ndarray) -> bytes:
    ends = np.cumsum(counts)
    markers = [{**STYLES[s], "header": header, "id": i,
                "points": [{"x": px, "y": py, "z": 0.0} for px, py in
                           zip(x[e - n:e].tolist(), y[e - n:e].tolist(), strict=True)]}
               for s, i, n, e in zip(style.tolist(), ids.tolist(), counts.tolist(),
                                     ends.tolist(), strict=True)]
    message = out.message(MARKER_ARRAY, {"markers": markers})
    ts = out.typestore
    return bytes(ts.serialize_ros1(message, MARKER_ARRAY) if out.is_ros1
                 else ts.serialize_cdr(message, MARKER_ARRAY))


@pytest.mark.parametrize("case", ["empty", "delete all only", "one arc", "many"])
@pytest.mark.parametrize("frame", ["", "o", "odom", "base_link7"])
def test_the_bytes_are_rosbags_serialisation_of_the_same_message(
        writer: BagWriter, case: str, frame: str) -> None:
    strips = StripArray(writer.typestore, writer.is_ros1, STYLES)
    for sec, nanosec in [(0, 0), (1234, 567_890_123), (2**31 - 1, 999_999_999)]:
        header = {"stamp": {"sec": sec, "nanosec": nanosec}, "frame_id": frame}
        arrays = _case(case)
        assert bytes(strips.serialise(header, *arrays)) == _rosbags_bytes(writer, header, *arrays)


def test_a_bag_of_the_bytes_reads_back(writer: BagWriter) -> None:
    header = {"stamp": {"sec": 5, "nanosec": 6}, "frame_id": "odom"}
    style, ids, counts, x, y = _case("many")
    data = StripArray(writer.typestore, writer.is_ros1, STYLES).serialise(
        header, style, ids, counts, x, y)
    message = (writer.typestore.deserialize_ros1(data, MARKER_ARRAY) if writer.is_ros1
               else writer.typestore.deserialize_cdr(data, MARKER_ARRAY))
    assert [m.id for m in message.markers] == ids.tolist()
    assert [len(m.points) for m in message.markers] == counts.tolist()
    assert [m.text for m in message.markers if m.type == 9] == ["été"] * int(np.sum(style == 3))
    xs = [p.x for m in message.markers for p in m.points]
    assert np.array_equal(xs, x, equal_nan=True)


def test_inconsistent_arrays_are_refused(writer: BagWriter) -> None:
    strips = StripArray(writer.typestore, writer.is_ros1, STYLES)
    header = {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": "odom"}
    one = np.array([1])
    with pytest.raises(UnsupportedLayoutError, match="point counts"):
        strips.serialise(header, one, one, np.array([3]), np.zeros(2), np.zeros(2))
    with pytest.raises(UnsupportedLayoutError, match="styles are 0 to 3"):
        strips.serialise(header, np.array([4]), one, np.array([0]), np.zeros(0), np.zeros(0))
    with pytest.raises(UnsupportedLayoutError, match="int32"):
        strips.serialise(header, one, np.array([2**31]), np.array([0]), np.zeros(0),
                         np.zeros(0))


def _store(**definitions: str) -> Any:
    ts = get_typestore(Stores.EMPTY)
    for name, text in definitions.items():
        ts.register(get_types_from_msg(text, name))
    return ts


@pytest.mark.parametrize(("point", "marker", "match"), [
    ("float32 x\nfloat32 y\nfloat32 z", "int32 id\ngeometry_msgs/Point[] points", "float64"),
    ("float64 x\nfloat64 y", "int32 id\ngeometry_msgs/Point[] points", "float64"),
    ("float64 x\nfloat64 y\nfloat64 z", "int64 id\ngeometry_msgs/Point[] points", "int32 id"),
    ("float64 x\nfloat64 y\nfloat64 z", "int32 id\ngeometry_msgs/Point[3] points", "sequence"),
])
def test_a_typestore_of_other_markers_is_refused(point: str, marker: str, match: str) -> None:
    ts = _store(**{"geometry_msgs/msg/Point": point, "visualization_msgs/msg/Marker": marker,
                   MARKER_ARRAY: "visualization_msgs/Marker[] markers"})
    with pytest.raises(UnsupportedLayoutError, match=match):
        StripArray(ts, False, [{}])


def test_a_field_of_a_type_not_laid_out_here_is_refused() -> None:
    ts = _store(**{"geometry_msgs/msg/Point": "float64 x\nfloat64 y\nfloat64 z",
                   "visualization_msgs/msg/Marker":
                       "char label\nint32 id\ngeometry_msgs/Point[] points",
                   MARKER_ARRAY: "visualization_msgs/Marker[] markers"})
    strips = StripArray(ts, False, [{}])
    with pytest.raises(UnsupportedLayoutError, match="'char'"):
        strips.serialise({"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""}, np.array([0]),
                         np.array([0]), np.array([0]), np.zeros(0), np.zeros(0))


@pytest.mark.parametrize("ros1", [True, False], ids=["ROS 1", "CDR"])
def test_points_after_an_unaligned_count_are_padded_as_rosbags_pads_them(ros1: bool) -> None:
    # In Humble's Marker the point count happens to end 8-aligned; here it ends 4 past (after
    # a header of an empty frame id: 8 + 5, padded to 16, then id, type and the count), so CDR
    # pads 4 bytes before the float64 points.
    ts = _store(**{"geometry_msgs/msg/Point": "float64 x\nfloat64 y\nfloat64 z",
                   "builtin_interfaces/msg/Time": "int32 sec\nuint32 nanosec",
                   "std_msgs/msg/Header": "builtin_interfaces/Time stamp\nstring frame_id",
                   "visualization_msgs/msg/Marker": "std_msgs/Header header\nint32 id\n"
                   "int32 type\ngeometry_msgs/Point[] points\nstring text",
                   MARKER_ARRAY: "visualization_msgs/Marker[] markers"})
    styles = [{"type": 1, "text": "ab"}, {"type": 2, "text": "odd"}]
    style, ids, counts = np.array([0, 1, 1, 0]), np.array([5, -6, 7, 8]), np.array([2, 0, 3, 1])
    x, y = np.arange(6.0) + 0.5, -np.arange(6.0)
    data = StripArray(ts, ros1, styles).serialise(
        {"stamp": {"sec": 3, "nanosec": 4}, "frame_id": ""}, style, ids, counts, x, y)
    point, marker = ts.types["geometry_msgs/msg/Point"], ts.types["visualization_msgs/msg/Marker"]
    header = ts.types["std_msgs/msg/Header"](
        stamp=ts.types["builtin_interfaces/msg/Time"](sec=3, nanosec=4), frame_id="")
    ends = np.cumsum(counts).tolist()
    message = ts.types[MARKER_ARRAY](markers=[
        marker(header=header, id=i, type=styles[s]["type"], text=styles[s]["text"],
               points=[point(x=x[k], y=y[k], z=0.0) for k in range(e - n, e)])
        for s, i, n, e in zip(style.tolist(), ids.tolist(), counts.tolist(), ends, strict=True)])
    expected = (ts.serialize_ros1(message, MARKER_ARRAY) if ros1
                else ts.serialize_cdr(message, MARKER_ARRAY))
    assert bytes(data) == bytes(expected)


@pytest.mark.parametrize("header", [
    "", "std_msgs/Header header\n", "std_msgs/Stamp header\n"],
    ids=["no header", "int32 sec, uint32 nanosec", "uint32 sec, int32 nanosec"])
def test_a_marker_without_the_header_stamp_patched_here_is_refused(header: str) -> None:
    ts = _store(**{"geometry_msgs/msg/Point": "float64 x\nfloat64 y\nfloat64 z",
                   "builtin_interfaces/msg/Time": "int32 sec\nuint32 nanosec",
                   "std_msgs/msg/OtherTime": "uint32 sec\nint32 nanosec",
                   "std_msgs/msg/Header": "builtin_interfaces/Time stamp\nstring frame_id",
                   "std_msgs/msg/Stamp": "std_msgs/OtherTime stamp\nstring frame_id",
                   "visualization_msgs/msg/Marker": header + "int32 id\n"
                   "geometry_msgs/Point[] points",
                   MARKER_ARRAY: "visualization_msgs/Marker[] markers"})
    strips = StripArray(ts, False, [{}])
    arrays = (np.array([0]), np.array([0]), np.array([0]), np.zeros(0), np.zeros(0))
    stamp = {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""}
    if header.startswith("std_msgs/Header"):
        assert len(strips.serialise(stamp, *arrays)) > 0  # the control: this one is laid out
        return
    with pytest.raises(UnsupportedLayoutError, match=r"header\.stamp"):
        strips.serialise(stamp, *arrays)
