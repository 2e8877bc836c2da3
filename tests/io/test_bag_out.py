"""write_map_bag and BagWriter: bags written in tmp_path, read back with rosbags' AnyReader."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from sonarcarve.io.bag_out import (
    ARCS_TOPIC,
    GRID_TOPIC,
    LOCAL_MAP_FIELDS,
    LOCAL_MAP_TOPIC,
    BagFormat,
    BagWriter,
    arc_markers,
    stamp,
    write_map_bag,
)
from sonarcarve.io.errors import OutputError
from sonarcarve.io.rosbag import RosbagError
from sonarcarve.methods import make_method
from sonarcarve.readings import ReadingBatch, ReadingsError

# One sonar at the origin facing +x hears a wall 2 m away four times, 0.4 s apart.
BATCH = ReadingBatch.from_arrays(
    t=[0.0, 0.4, 0.8, 1.2], sensor=[0, 0, 0, 0], x=[0.0, 0.0, 0.0, 0.0], y=[0.0] * 4,
    theta=[0.0] * 4, range=[2.0] * 4, beam_width=[0.3] * 4)
ODOMETRY = np.array([[0.0, 0.0, 0.0, 0.0], [1.2, 0.0, 0.0, math.pi / 2]])


def _read(path: Path) -> dict[str, list[tuple[str, Any]]]:
    """Topic -> [(msgtype, message)] in log order."""
    out: dict[str, list[tuple[str, Any]]] = {}
    with AnyReader([path]) as reader:
        for conn, _, raw in reader.messages():
            out.setdefault(conn.topic, []).append(
                (conn.msgtype, reader.deserialize(raw, conn.msgtype)))
    return out


def _cloud(message: Any) -> np.ndarray:
    return np.frombuffer(message.data.tobytes(), dtype="<f4").reshape(message.width, -1)


@pytest.mark.parametrize(("name", "storage", "kind"), [
    ("map.mcap", "mcap", BagFormat.MCAP_FILE), ("map_folder", "mcap", BagFormat.ROS2_MCAP),
    ("map_sqlite", "sqlite3", BagFormat.ROS2_SQLITE3), ("map.bag", "mcap", BagFormat.ROS1)])
def test_map_bag_reads_back_with_types_frames_and_counts(tmp_path: Path, name: str,
                                                         storage: str, kind: BagFormat) -> None:
    path = tmp_path / name
    report = write_map_bag(path, BATCH, make_method("centerline"), odometry=ODOMETRY, rate=2.0,
                           storage=storage)
    assert report.format is kind
    # Period 0.5 s: maps at 0.5 (readings 0, 1), 1.0 (0-2) and the last reading, 1.2 (0-3).
    assert report.messages == {"/odom": 2, "/tf": 2, LOCAL_MAP_TOPIC: 3, ARCS_TOPIC: 3}
    topics = _read(path)
    assert {t: {m for m, _ in msgs} for t, msgs in topics.items()} == {
        "/odom": {"nav_msgs/msg/Odometry"}, "/tf": {"tf2_msgs/msg/TFMessage"},
        LOCAL_MAP_TOPIC: {"sensor_msgs/msg/PointCloud2"},
        ARCS_TOPIC: {"visualization_msgs/msg/MarkerArray"}}
    clouds = [m for _, m in topics[LOCAL_MAP_TOPIC]]
    assert [c.width for c in clouds] == [2, 3, 4]
    assert [c.header.stamp.sec * 1e9 + c.header.stamp.nanosec for c in clouds] == [
        5e8, 1e9, 1.2e9]
    last = clouds[-1]
    assert last.header.frame_id == "odom"
    assert [f.name for f in last.fields] == list(LOCAL_MAP_FIELDS)
    assert [f.offset for f in last.fields] == [0, 4, 8, 12, 16, 20, 24]
    assert last.point_step == 28
    points = _cloud(last)
    # Centerline points at the arc centre (2, 0); error 2·r·sin(θ_d/4) (eq. 5.2, 5.3).
    np.testing.assert_allclose(points[:, :6], np.tile(
        [2.0, 0.0, 0.0, 0.0, 0.3, 2 * 2.0 * math.sin(0.3 / 4)], (4, 1)), rtol=1e-6)
    assert np.all(np.isnan(points[:, 6]))
    markers = [m for _, m in topics[ARCS_TOPIC]][-1].markers
    assert markers[0].action == 3  # DELETEALL
    assert [m.type for m in markers[1:]] == [4] * 4  # LINE_STRIP
    assert [m.id for m in markers[1:]] == [0, 1, 2, 3]
    ends = [(p.x, p.y) for p in (markers[1].points[0], markers[1].points[-1])]
    np.testing.assert_allclose(ends, [[2 * math.cos(0.15), -2 * math.sin(0.15)],
                                      [2 * math.cos(0.15), 2 * math.sin(0.15)]], atol=1e-9)
    assert (markers[1].color.r, markers[1].color.b) == (pytest.approx(0.839, abs=1e-3),
                                                        pytest.approx(0.157, abs=1e-3))
    odom = [m for _, m in topics["/odom"]][-1]
    assert (odom.header.frame_id, odom.child_frame_id) == ("odom", "base_link")
    assert odom.pose.pose.orientation.z == pytest.approx(math.sin(math.pi / 4))
    tf = next(m for _, m in topics["/tf"]).transforms[0]
    assert (tf.header.frame_id, tf.child_frame_id) == ("odom", "base_link")


def test_carving_shrinks_the_arcs_in_the_markers(tmp_path: Path) -> None:
    # Arc 0: 2 m about the origin, bearings ±0.25. A sonar at (2, 1.5) looking down hears
    # 1.3 m: its free space covers the arc's points above y ≈ 0.2 (bearings ≳ 0.1).
    batch = ReadingBatch.from_arrays(
        t=[0.0, 1.0], sensor=[0, 1], x=[0.0, 2.0], y=[0.0, 1.5], theta=[0.0, -math.pi / 2],
        range=[2.0, 1.3], beam_width=[0.5, 0.5])
    path = tmp_path / "carve.mcap"
    write_map_bag(path, batch, make_method("carve"), rate=0.5)
    markers = [m for _, m in _read(path)[ARCS_TOPIC]][-1].markers
    arc0 = next(m for m in markers[1:] if m.id == 0)
    bearings = [math.atan2(p.y, p.x) for p in arc0.points]
    assert min(bearings) == pytest.approx(-0.25)
    assert 0.05 < max(bearings) < 0.15  # the carved arc no longer reaches its left edge
    assert arc0.color.b == pytest.approx(0.706, abs=1e-3)  # carved: blue


def test_input_messages_are_copied_through(tmp_path: Path) -> None:
    first = tmp_path / "first.mcap"
    write_map_bag(first, BATCH, make_method("centerline"), odometry=ODOMETRY)
    for name in ("second.mcap", "second.bag"):
        second = tmp_path / name
        report = write_map_bag(second, BATCH, make_method("centerline"), copy_from=first)
        assert report.messages["/odom"] == 2
        assert report.messages[LOCAL_MAP_TOPIC] == 3 + 3
        odom = [m for _, m in _read(second)["/odom"]]
        assert odom[-1].pose.pose.orientation.z == pytest.approx(math.sin(math.pi / 4))


def test_nothing_is_written_on_error(tmp_path: Path) -> None:
    existing = tmp_path / "exists.mcap"
    existing.write_text("keep me")
    with pytest.raises(OutputError, match="already exists"):
        write_map_bag(existing, BATCH, make_method("centerline"))
    assert existing.read_text() == "keep me"
    with pytest.raises(OutputError, match="rate"):
        write_map_bag(tmp_path / "a.mcap", BATCH, make_method("centerline"), rate=0.0)
    broken = tmp_path / "broken.bag"
    broken.write_bytes(b"#ROSBAG V2.0\n" + b"\0" * 40)
    with pytest.raises(RosbagError) as err:
        write_map_bag(tmp_path / "b.mcap", BATCH, make_method("centerline"), copy_from=broken)
    assert "\n" not in str(err.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken.bag", "exists.mcap"]


class _StubGrid:
    """A 2 x 3 grid at 0.5 m from (-1, -0.5) whose cells are set by hand: what the bag must
    carry, laid out as ROS's OccupancyGrid (row-major from the lower-left corner)."""

    resolution = 0.5
    bounds = (-1.0, -0.5, 0.5, 0.5)

    def __init__(self) -> None:
        self.readings = 0

    def add(self, reading: object) -> None:
        self.readings += 1

    def trinary(self) -> np.ndarray:
        # Row 0 (lower, y in [-0.5, 0)): unknown, free, occupied; row 1: all free.
        return np.array([[-1, 0, 100], [0, 0, 0]], dtype=np.int8)


@pytest.mark.parametrize("name", ["grid.mcap", "grid.bag"])
def test_a_grid_is_written_as_occupancy_grids(tmp_path: Path, name: str) -> None:
    grid = _StubGrid()
    report = write_map_bag(tmp_path / name, BATCH, make_method("centerline"), rate=2.0,
                           grid=grid)
    assert grid.readings == 4
    assert report.messages[GRID_TOPIC] == 3  # with every local map
    (msgtype, last), *_ = reversed(_read(tmp_path / name)[GRID_TOPIC])
    assert msgtype == "nav_msgs/msg/OccupancyGrid"
    assert last.header.frame_id == "odom"
    assert (last.info.width, last.info.height) == (3, 2)
    assert last.info.resolution == pytest.approx(0.5)
    assert (last.info.origin.position.x, last.info.origin.position.y) == (-1.0, -0.5)
    assert last.data.tolist() == [-1, 0, 100, 0, 0, 0]


def test_given_ids_are_the_arc_markers_ids(tmp_path: Path) -> None:
    """Readings a filter kept carry their input rows (the id contract), not their positions."""
    path = tmp_path / "map.mcap"
    write_map_bag(path, BATCH, make_method("centerline"), odometry=ODOMETRY, rate=2.0,
                  ids=[0, 2, 5, 6])
    markers = [m for _, m in _read(path)[ARCS_TOPIC]][-1].markers
    assert [m.id for m in markers[1:]] == [0, 2, 5, 6]
    with pytest.raises(ReadingsError, match="must increase"):
        write_map_bag(tmp_path / "bad.mcap", BATCH, make_method("carve"), ids=[0, 2, 2, 3])
    assert not (tmp_path / "bad.mcap").exists()


def test_progress_is_reported_at_each_local_map_and_at_the_end(tmp_path: Path) -> None:
    # User review: the office tour to a bag took 33 s with nothing on screen.
    n = 30
    batch = ReadingBatch.from_arrays(t=0.1 * np.arange(n), sensor=np.zeros(n, int),
                                     x=0.05 * np.arange(n), y=np.zeros(n),
                                     theta=np.full(n, math.pi / 2), range=np.full(n, 2.0))
    done: list[int] = []
    write_map_bag(tmp_path / "p.mcap", batch, make_method("carve"), rate=2.0,
                  on_progress=done.append)
    # Local maps every 0.5 s of log time: before readings 5, 10, ..., 25, then the last.
    assert done == [5, 10, 15, 20, 25, n]


# A sensor driving along y past a wall, so that carving leaves arcs of several widths.
_DRIVE = ReadingBatch.from_arrays(
    t=0.1 * np.arange(24), sensor=np.zeros(24, int), x=np.zeros(24), y=0.1 * np.arange(24),
    theta=np.zeros(24), range=np.where(np.arange(24) % 3 == 0, 2.0, 2.4), beam_width=[0.4] * 24)


@pytest.mark.parametrize("name", ["map.mcap", "map.bag"])
def test_the_arc_markers_written_are_the_messages_built_from_their_mappings(
        tmp_path: Path, name: str) -> None:
    # Bag output CPU: write_map_bag builds each arc's points as Point messages at once and
    # shares the markers' zero-valued parts; the bytes must be those of the plain way, each
    # field from a mapping (BagWriter.message, arc_markers without `point`).
    path = tmp_path / name
    write_map_bag(path, _DRIVE, make_method("combined"), rate=2.0)
    method = make_method("combined")
    for k, reading in enumerate(_DRIVE):
        method.add(reading, k)
    header = {"stamp": stamp(float(_DRIVE.t[-1])), "frame_id": "odom"}
    mappings = arc_markers(method, header)
    assert len(mappings) > 3
    assert len({len(m.get("points", ())) for m in mappings}) > 2  # strips of several lengths
    msgtype = "visualization_msgs/msg/MarkerArray"
    with BagWriter(tmp_path / f"plain-{name}") as plain:
        message = plain.message(msgtype, {"markers": mappings})
        expected = (plain.typestore.serialize_ros1(message, msgtype) if plain.is_ros1
                    else plain.typestore.serialize_cdr(message, msgtype))
    with AnyReader([path]) as reader:
        arcs = [c for c in reader.connections if c.topic == ARCS_TOPIC]
        *_, (_, _, last) = reader.messages(connections=arcs)
    assert bytes(last) == bytes(expected)


@pytest.mark.parametrize("method_name", ["centerline", "carve", "combined"])
def test_arc_points_are_the_bits_of_the_python_loop(method_name: str) -> None:
    # The points are computed in a compiled loop now; they must be the very floats of the
    # Python loop bag_out ran before (linspace per arc, math.cos / math.sin per point).
    method = make_method(method_name)
    for k, reading in enumerate(_DRIVE):
        method.add(reading, k)
    h = method.history
    slots = h.slots()
    est = method.estimates(slots)
    expected = []
    for k in np.flatnonzero(est.alive).tolist():
        slot = int(slots[k])
        ox, oy, r = float(h.x[slot]), float(h.y[slot]), float(h.r[slot])
        mid = math.atan2(float(est.xy[k, 1]) - oy, float(est.xy[k, 0]) - ox)
        half = 0.5 * float(est.width[k])
        steps = max(2, math.ceil(2 * half / math.radians(2.0)) + 1)
        expected.append([(ox + r * math.cos(a), oy + r * math.sin(a))
                         for a in np.linspace(mid - half, mid + half, steps).tolist()])
    markers = arc_markers(method, {"stamp": stamp(1.0), "frame_id": "odom"})
    got = [[(p["x"], p["y"]) for p in m["points"]] for m in markers[1:]]
    assert len(got) == len(expected) > 3
    assert np.array_equal(np.array([p for arc in got for p in arc]).view(np.uint64),
                          np.array([p for arc in expected for p in arc]).view(np.uint64))
    assert [len(arc) for arc in got] == [len(arc) for arc in expected]


def _plain_arcs(tmp_path: Path, name: str) -> bytes:
    """The arc markers of _DRIVE's last map, serialised by rosbags from message objects."""
    method = make_method("combined")
    for k, reading in enumerate(_DRIVE):
        method.add(reading, k)
    header = {"stamp": stamp(float(_DRIVE.t[-1])), "frame_id": "odom"}
    msgtype = "visualization_msgs/msg/MarkerArray"
    with BagWriter(tmp_path / f"plain-{name}") as plain:
        message = plain.message(msgtype, {"markers": arc_markers(method, header)})
        return bytes(plain.typestore.serialize_ros1(message, msgtype) if plain.is_ros1
                     else plain.typestore.serialize_cdr(message, msgtype))


def _last_arcs(path: Path) -> bytes:
    with AnyReader([path]) as reader:
        arcs = [c for c in reader.connections if c.topic == ARCS_TOPIC]
        *_, (_, _, last) = reader.messages(connections=arcs)
    return bytes(last)


@pytest.mark.parametrize("name", ["map.mcap", "map.bag"])
@pytest.mark.parametrize("fault", ["other bytes", "unsupported types"])
def test_arcs_are_message_objects_where_the_bytes_would_not_be_rosbags(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, name: str, fault: str) -> None:
    # A typestore laid out otherwise than marker_bytes lays out (simulated: one byte changed,
    # or types it refuses) must not give a corrupt bag: the arcs go the old way.
    from sonarcarve.io import marker_bytes

    serialise = marker_bytes.StripArray.serialise

    def other_bytes(self: Any, *args: Any) -> bytes:
        data = bytearray(serialise(self, *args))
        data[-1] ^= 0xFF
        return bytes(data)

    def refuse(self: Any, *args: Any) -> None:
        msg = "a layout this encoder does not know"
        raise marker_bytes.UnsupportedLayoutError(msg)

    if fault == "other bytes":
        monkeypatch.setattr(marker_bytes.StripArray, "serialise", other_bytes)
    else:
        monkeypatch.setattr(marker_bytes.StripArray, "__init__", refuse)
    path = tmp_path / name
    write_map_bag(path, _DRIVE, make_method("combined"), rate=2.0)
    assert _last_arcs(path) == _plain_arcs(tmp_path, name)


class _StubHistory:
    def __init__(self, reading_id: int) -> None:
        self.x, self.y, self.r = np.zeros(1), np.zeros(1), np.ones(1)
        self.reading_id = np.array([reading_id])

    def slots(self) -> np.ndarray:
        return np.array([0])


class _StubMethod:
    """One live arc of the given width, source and reading id."""

    def __init__(self, width: float, source: int, reading_id: int) -> None:
        self.history = _StubHistory(reading_id)
        self._est = type("Estimates", (), {
            "alive": np.array([True]), "xy": np.array([[1.0, 0.0]]),
            "width": np.array([width]), "source": np.array([source])})

    def estimates(self, slots: np.ndarray) -> Any:
        return self._est


@pytest.mark.parametrize(("width", "source", "reading_id", "match"), [
    (math.nan, 0, 1, "width is not finite"), (math.inf, 1, 1, "width is not finite"),
    (0.3, 3, 1, "source is no PointSource"), (0.3, -1, 1, "source is no PointSource"),
    (0.3, 2, 2**31, "int32")])
def test_an_arc_that_cannot_be_drawn_is_a_one_line_error(
        width: float, source: int, reading_id: int, match: str) -> None:
    method: Any = _StubMethod(width, source, reading_id)
    with pytest.raises(OutputError, match=match) as err:
        arc_markers(method, {"stamp": stamp(0.0), "frame_id": "odom"})
    assert "\n" not in str(err.value)
