"""read_rosbag: bags written here with rosbags' writers; expectations computed by hand."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from sonarcarve.cli import main
from sonarcarve.io import read_readings_csv
from sonarcarve.io.rosbag import RosbagError, read_rosbag
from sonarcarve.robot import parse_robot

TS = get_typestore(Stores.ROS2_HUMBLE)
RANGE = "sensor_msgs/msg/Range"
ODOM = "nav_msgs/msg/Odometry"
TF = "tf2_msgs/msg/TFMessage"
INF = float("inf")

# Two sonars: sensor 0 at (0.1, 0.2) facing left, sensor 1 at (0.3, -0.1) facing 45° right.
ROBOT_YAML = """
name: two
robot_radius: 0.3
range_resolution: 0.0
min_range: 0.1
max_range: 5.0
firing_period: 0.05
sensors:
  - {x: 0.1, y: 0.2, bearing_deg: 90.0}
  - {x: 0.3, y: -0.1, bearing_deg: -45.0}
"""
ROBOT = parse_robot(ROBOT_YAML, "two")


class Msg(NamedTuple):
    """One message to write: topic, header stamp (s), and its fields."""

    topic: str
    t: float
    fields: dict[str, Any]


def _header(t: float, frame: str = "") -> Any:
    sec = math.floor(t)
    stamp = TS.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=round((t - sec) * 1e9))
    return TS.types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)


def _range(topic: str, t: float, r: float, *, fov: float = 0.3, frame: str = "",
           lo: float = 0.1, hi: float = 4.0, radiation: int = 0) -> Msg:
    return Msg(topic, t, {"frame": frame, "range": r, "field_of_view": fov, "min_range": lo,
                          "max_range": hi, "radiation": radiation})


def _tf(t: float, *transforms: tuple[str, str, float, float, float],
        topic: str = "/tf_static") -> Msg:
    """A TFMessage: each transform ``(parent, child, x, y, yaw)``."""
    return Msg(topic, t, {"tf": transforms})


def _odom(t: float, x: float, y: float, yaw: float, topic: str = "/odom") -> Msg:
    return Msg(topic, t, {"x": x, "y": y, "yaw": yaw})


def _build(msg: Msg, msgtype: str) -> Any:
    f = msg.fields
    geo = "geometry_msgs/msg/"
    if msgtype == TF:
        return TS.types[TF](transforms=[TS.types[geo + "TransformStamped"](
            header=_header(msg.t, parent), child_frame_id=child,
            transform=TS.types[geo + "Transform"](
                translation=TS.types[geo + "Vector3"](x=x, y=y, z=0.1),
                rotation=TS.types[geo + "Quaternion"](x=0.0, y=0.0, z=math.sin(yaw / 2),
                                                      w=math.cos(yaw / 2))))
            for parent, child, x, y, yaw in f["tf"]])
    if msgtype == RANGE:
        return TS.types[RANGE](header=_header(msg.t, f["frame"]),
                               radiation_type=f["radiation"],
                               field_of_view=f["field_of_view"], min_range=f["min_range"],
                               max_range=f["max_range"], range=f["range"])
    pose = TS.types[geo + "Pose"](
        position=TS.types[geo + "Point"](x=f["x"], y=f["y"], z=0.0),
        orientation=TS.types[geo + "Quaternion"](x=0.0, y=0.0, z=math.sin(f["yaw"] / 2),
                                                 w=math.cos(f["yaw"] / 2)))
    zero = TS.types[geo + "Vector3"](x=0.0, y=0.0, z=0.0)
    return TS.types[ODOM](
        header=_header(msg.t, "odom"), child_frame_id="base_link",
        pose=TS.types[geo + "PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
        twist=TS.types[geo + "TwistWithCovariance"](
            twist=TS.types[geo + "Twist"](linear=zero, angular=zero), covariance=np.zeros(36)))


def write_bag(path: Path, messages: Sequence[Msg], types: dict[str, str]) -> Path:
    """Write ``messages`` (in list order, logged at 1 ms steps): rosbag1 if ``*.bag``, a
    rosbag2 folder with MCAP storage if the name ends in ``mcap``, else rosbag2 sqlite3."""
    if path.suffix == ".bag":
        from rosbags.rosbag1 import Writer as Writer1

        with Writer1(path) as w1:
            conns = {t: w1.add_connection(t, m, typestore=TS) for t, m in types.items()}
            for k, msg in enumerate(messages):
                mtype = types[msg.topic]
                w1.write(conns[msg.topic], (k + 1) * 1_000_000,
                         TS.serialize_ros1(_build(msg, mtype), mtype))
        return path
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2

    mcap = path.name.endswith("mcap")
    with Writer2(path, version=9 if mcap else 8,
                 storage_plugin=StoragePlugin.MCAP if mcap else StoragePlugin.SQLITE3) as w2:
        conns = {t: w2.add_connection(t, m, typestore=TS) for t, m in types.items()}
        for k, msg in enumerate(messages):
            mtype = types[msg.topic]
            w2.write(conns[msg.topic], (k + 1) * 1_000_000,
                     TS.serialize_cdr(_build(msg, mtype), mtype))
    return path


# Robot drives along +x at 0.5 m/s from (1, 2), heading 0, for t in [0, 4] s.
STRAIGHT_ODOM = [_odom(t, 1.0 + 0.5 * t, 2.0, 0.0) for t in (0.0, 1.0, 2.0, 3.0, 4.0)]
# /sonar_2 is sensor 0 and /sonar_10 sensor 1 (natural order). Logged out of stamp order.
STRAIGHT_RANGES = [
    _range("/sonar_10", 2.5, 1.5, fov=0.0),
    _range("/sonar_2", 1.5, 2.0),
    _range("/sonar_2", 0.5, 1.0),
    _range("/sonar_10", 0.5, 3.0, fov=0.0),
    _range("/sonar_10", 1.0, 4.5, fov=0.0),        # beyond max_range 4.0: no echo
    _range("/sonar_2", 2.0, float("nan")),         # not a number: no echo
    _range("/sonar_2", 3.0, 0.05),                 # below min_range 0.1: no echo
    _range("/sonar_2", 3.5, float("inf")),         # no echo
    _range("/sonar_10", 5.0, 1.0, fov=0.0),        # after the odometry ends
]
STRAIGHT_TYPES = {"/sonar_2": RANGE, "/sonar_10": RANGE, "/odom": ODOM}


def _expected_straight() -> list[tuple[float, int, float, float, float, float, float]]:
    """(t, sensor, x, y, theta, range, width) worked out by hand: heading 0, so a sensor is
    at robot + mount and faces its bearing; robot x = 1 + 0.5 t, y = 2."""
    s0 = (0.1, 0.2, math.pi / 2, 0.3)
    s1 = (0.3, -0.1, -math.pi / 4, math.nan)
    rows = []
    for t, sensor, r in ((0.5, 0, 1.0), (0.5, 1, 3.0), (1.5, 0, 2.0), (2.5, 1, 1.5)):
        mx, my, bearing, width = (s0, s1)[sensor]
        rows.append((t, sensor, 1.0 + 0.5 * t + mx, 2.0 + my, bearing, r, width))
    return rows


def _rows(batch: Any) -> list[tuple[float, ...]]:
    return [tuple(reading)[:7] for reading in batch]  # without max_range (NaN here)


FORMATS = ["ros2_sqlite3", "ros2_mcap", "ros1.bag"]


@pytest.mark.parametrize("name", FORMATS)
def test_straight_drive_gives_hand_computed_world_poses(tmp_path: Path, name: str) -> None:
    bag = write_bag(tmp_path / name, [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    log = read_rosbag(bag, robot=ROBOT)
    np.testing.assert_allclose(np.array(_rows(log.batch)), np.array(_expected_straight()),
                               atol=1e-9)
    assert np.all(np.diff(log.batch.t) >= 0.0)
    report = log.report
    assert report.sensors == (("/sonar_2", ""), ("/sonar_10", ""))
    assert report.messages == {"/sonar_2": 5, "/sonar_10": 4, "/odom": 5}
    # +Inf and 4.5 > max_range: no echo; 0.05 < min_range: too close; NaN: invalid.
    assert (report.no_echo, report.too_close, report.invalid) == (2, 1, 1)
    assert (report.outside_odometry, report.readings) == (1, 4)
    assert report.odometry_topic == "/odom"
    assert report.odometry_frames == ("odom", "base_link")
    assert [s.mount for s in report.sources] == ["robot two[0]", "robot two[1]"]


def test_no_echo_beams_are_kept_with_their_poses(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    free = read_rosbag(bag, robot=ROBOT).no_echo
    # t = 1.0, /sonar_10 (sensor 1, mount (0.3, -0.1), -45°) read 4.5 > 4.0: robot at (1.5, 2);
    # t = 3.5, /sonar_2 (sensor 0, mount (0.1, 0.2), 90°) read +Inf: robot at (2.75, 2).
    assert free.sensor.tolist() == [1, 0]
    np.testing.assert_allclose(free.t, [1.0, 3.5])
    np.testing.assert_allclose(free.x, [1.8, 2.85])
    np.testing.assert_allclose(free.y, [1.9, 2.2])
    np.testing.assert_allclose(free.theta, [-math.pi / 4, math.pi / 2])
    np.testing.assert_allclose(free.max_range, [4.0, 4.0])
    np.testing.assert_allclose(free.beam_width, [math.nan, 0.3])


def test_rep117_infinities_and_nan(tmp_path: Path) -> None:
    odom = [_odom(0.0, 0.0, 0.0, 0.0), _odom(1.0, 1.0, 0.0, 0.0)]
    mounts = _tf(0.0, ("base_link", "s", 0.0, 0.0, 0.0))
    ranges = [_range("/r", 0.1, INF, frame="s", hi=3.0), _range("/r", 0.2, -INF, frame="s"),
              _range("/r", 0.3, math.nan, frame="s"), _range("/r", 0.4, INF, frame="s", hi=3.0),
              _range("/r", 0.5, 2.0, frame="s")]
    bag = write_bag(tmp_path / "bag_mcap", [*odom, mounts, *ranges],
                    {"/r": RANGE, "/odom": ODOM, "/tf_static": TF})
    log = read_rosbag(bag)
    r = log.report
    assert (r.no_echo, r.too_close, r.invalid, r.readings) == (2, 1, 1, 1)
    assert log.batch.range.tolist() == [2.0]
    np.testing.assert_allclose(log.no_echo.x, [0.1, 0.4])
    np.testing.assert_allclose(log.no_echo.max_range, [3.0, 3.0])


def test_a_range_at_max_range_is_a_silent_firing(tmp_path: Path) -> None:
    """Gazebo's range and sonar plugins publish ``range = max_range`` for a ray that hit
    nothing (and drivers clamp late echoes to it): nothing heard, free space, no arc at
    max_range. Just below max_range is an echo."""
    odom = [_odom(0.0, 0.0, 0.0, 0.0), _odom(1.0, 1.0, 0.0, 0.0)]
    mounts = _tf(0.0, ("base_link", "s", 0.0, 0.0, 0.0))
    ranges = [_range("/r", 0.1, 3.0, frame="s", hi=3.0), _range("/r", 0.2, 2.99, frame="s", hi=3.0),
              _range("/r", 0.3, 5.0, frame="s", hi=5.0)]
    bag = write_bag(tmp_path / "bag_mcap", [*odom, mounts, *ranges],
                    {"/r": RANGE, "/odom": ODOM, "/tf_static": TF})
    log = read_rosbag(bag)
    assert (log.report.no_echo, log.report.readings) == (2, 1)
    np.testing.assert_allclose(log.batch.range, [2.99], rtol=1e-6)  # float32 in the message
    np.testing.assert_allclose(log.no_echo.t, [0.1, 0.3])
    np.testing.assert_allclose(log.no_echo.max_range, [3.0, 5.0])


def test_a_sensor_that_reports_inf_keeps_its_max_range_echoes(tmp_path: Path) -> None:
    """A publisher that says "nothing heard" with +Inf (REP 117, as sonarcarve's simulated bags
    do) means an echo when it reports max_range itself: a Scout2's 6.477 m is a whole number of
    its range steps, and a bag must give back the CSV's readings. The rule is per sensor."""
    odom = [_odom(0.0, 0.0, 0.0, 0.0), _odom(1.0, 1.0, 0.0, 0.0)]
    mounts = _tf(0.0, ("base_link", "a", 0.0, 0.0, 0.0), ("base_link", "b", 0.0, 0.0, 1.0))
    ranges = [_range("/a", 0.1, 3.0, frame="a", hi=3.0), _range("/a", 0.2, INF, frame="a", hi=3.0),
              _range("/b", 0.3, 3.0, frame="b", hi=3.0)]
    bag = write_bag(tmp_path / "bag_mcap", [*odom, mounts, *ranges],
                    {"/a": RANGE, "/b": RANGE, "/odom": ODOM, "/tf_static": TF})
    log = read_rosbag(bag)
    assert (log.report.no_echo, log.report.readings) == (2, 1)
    np.testing.assert_allclose(log.batch.t, [0.1])  # /a's 3.0: an echo, /a says silence with +Inf
    np.testing.assert_allclose(log.no_echo.t, [0.2, 0.3])  # /a's +Inf, /b's 3.0


# TF mounts: base_link -> sonar_ring at (0.1, 0) turned 90°; the ring carries sonar_front at
# (0.2, 0) turned -90° and sonar_left at (0, -0.15) turned 0; sonar_rear hangs off base_link
# on /tf at (-0.25, 0.05) turned 180°. In base_link, worked by hand:
#   front (0.1, 0.2, 0°), left (0.25, 0.0, 90°), rear (-0.25, 0.05, 180°).
TF_MOUNTS = [
    _tf(0.0, ("sonar_ring", "sonar_left", 0.0, -0.15, 0.0),
        ("base_link", "sonar_ring", 0.1, 0.0, math.pi / 2)),
    _tf(0.0, ("sonar_ring", "sonar_front", 0.2, 0.0, -math.pi / 2)),
    _tf(0.0, ("base_link", "sonar_rear", -0.25, 0.05, math.pi), topic="/tf"),
]
# Robot at (2, 1) heading 90°, then (2, 3): at t = 1 it is at (2, 2), heading 90°, so a mount
# (mx, my, b) lies at (2 - my, 2 + mx) facing 90° + b.
TF_ODOM = [_odom(0.0, 2.0, 1.0, math.pi / 2), _odom(2.0, 2.0, 3.0, math.pi / 2)]
# Topics in natural order a, b, c carry the rear, front and left sonars: list position and
# TF order differ, frames decide.
TF_RANGES = [_range("/sonar_a", 1.0, 3.0, frame="sonar_rear"),
             _range("/sonar_b", 1.0, 1.0, frame="sonar_front", radiation=1),
             _range("/sonar_c", 1.0, 2.0, frame="sonar_left")]
TF_TYPES = {"/sonar_a": RANGE, "/sonar_b": RANGE, "/sonar_c": RANGE, "/odom": ODOM,
            "/tf": TF, "/tf_static": TF}


@pytest.mark.parametrize("name", FORMATS)
def test_tf_mounted_sensors_read_at_their_origins(tmp_path: Path, name: str) -> None:
    bag = write_bag(tmp_path / name, [*TF_ODOM, *TF_MOUNTS, *TF_RANGES], TF_TYPES)
    log = read_rosbag(bag)
    b = log.batch
    assert b.sensor.tolist() == [0, 1, 2]
    np.testing.assert_allclose(b.range, [3.0, 1.0, 2.0])
    np.testing.assert_allclose(b.x, [1.95, 1.8, 2.0], atol=1e-9)
    np.testing.assert_allclose(b.y, [1.75, 2.1, 2.25], atol=1e-9)
    np.testing.assert_allclose(np.remainder(b.theta, 2 * math.pi),
                               [3 * math.pi / 2, math.pi / 2, math.pi], atol=1e-9)
    sources = log.report.sources
    assert [(s.topic, s.frame, s.mount) for s in sources] == [
        ("/sonar_a", "sonar_rear", "tf"), ("/sonar_b", "sonar_front", "tf"),
        ("/sonar_c", "sonar_left", "tf")]
    assert [s.radiation for s in sources] == ["ultrasound", "infrared", "ultrasound"]
    assert sources[2].x == pytest.approx(0.25)
    assert sources[2].bearing == pytest.approx(math.pi / 2)


def test_one_topic_told_apart_by_frame_id_with_tf(tmp_path: Path) -> None:
    ranges = [Msg("/sonars", m.t, m.fields) for m in TF_RANGES]
    bag = write_bag(tmp_path / "bag", [*TF_ODOM, *TF_MOUNTS, *ranges],
                    {"/sonars": RANGE, "/odom": ODOM, "/tf": TF, "/tf_static": TF})
    log = read_rosbag(bag)
    # Frames in natural order: sonar_front, sonar_left, sonar_rear.
    assert log.report.sensors == (("/sonars", "sonar_front"), ("/sonars", "sonar_left"),
                                  ("/sonars", "sonar_rear"))
    np.testing.assert_allclose(log.batch.x, [1.8, 2.0, 1.95], atol=1e-9)
    np.testing.assert_allclose(log.batch.range, [1.0, 2.0, 3.0])


def test_odometry_from_tf_when_no_odometry_topic(tmp_path: Path) -> None:
    tf_odom = [_tf(t, ("odom", "base_link", 2.0 * t, 0.0, 0.0), topic="/tf") for t in (0, 1)]
    mounts = _tf(0.0, ("base_link", "sonar_front", 0.1, 0.2, 0.0))
    bag = write_bag(tmp_path / "bag.bag",
                    [*tf_odom, mounts, _range("/r", 0.25, 1.0, frame="sonar_front")],
                    {"/tf": TF, "/tf_static": TF, "/r": RANGE})
    log = read_rosbag(bag)
    assert log.report.odometry_topic == "/tf"
    assert log.report.odometry_frames == ("odom", "base_link")
    # t = 0.25: robot at (0.5, 0) heading 0; mount (0.1, 0.2).
    assert (log.batch.x[0], log.batch.y[0]) == (pytest.approx(0.6), pytest.approx(0.2))


def test_frame_override_names_the_base_frame(tmp_path: Path) -> None:
    tf_odom = [_tf(t, ("odom", "chassis", 2.0 * t, 0.0, 0.0), topic="/tf") for t in (0, 1)]
    mounts = _tf(0.0, ("chassis", "s", 0.1, 0.0, 0.0))
    bag = write_bag(tmp_path / "bag", [*tf_odom, mounts, _range("/r", 0.5, 1.0, frame="s")],
                    {"/tf": TF, "/tf_static": TF, "/r": RANGE})
    with pytest.raises(RosbagError) as err:
        read_rosbag(bag)
    _assert_one_line(err, str(bag), "no odometry", "'base_link'")
    log = read_rosbag(bag, base_frame="chassis")
    assert log.batch.x[0] == pytest.approx(1.1)


def test_one_topic_with_frame_ids_turning_robot(tmp_path: Path) -> None:
    # Heading goes from 170° to 190° (logged as -170°): unwrapped, 180° at t = 0.5 s.
    odom = [_odom(0.0, 0.0, 0.0, math.radians(170)), _odom(1.0, 0.0, 0.0, math.radians(-170)),
            _odom(2.0, 0.0, 2.0, math.pi / 2)]
    ranges = [_range("/sonars", 0.5, 1.0, frame="sonar_b"),
              _range("/sonars", 1.5, 2.0, frame="sonar_a")]
    bag = write_bag(tmp_path / "bag", [*odom, *ranges], {"/sonars": RANGE, "/odom": ODOM})
    log = read_rosbag(bag, robot=ROBOT)
    assert log.report.sensors == (("/sonars", "sonar_a"), ("/sonars", "sonar_b"))
    b, a = log.batch[0], log.batch[1]
    # t = 0.5: robot at the origin heading π; sensor 1 mount (0.3, -0.1) turns to (-0.3, 0.1).
    assert (b.sensor, b.x, b.y) == (1, pytest.approx(-0.3), pytest.approx(0.1))
    assert math.remainder(b.theta - (math.pi - math.pi / 4), 2 * math.pi) == pytest.approx(0)
    # t = 1.5: robot at (0, 1); heading halfway from 190° to 90°: 140°.
    h = math.radians(140)
    assert a.sensor == 0
    assert a.x == pytest.approx(0.1 * math.cos(h) - 0.2 * math.sin(h))
    assert a.y == pytest.approx(1.0 + 0.1 * math.sin(h) + 0.2 * math.cos(h))
    assert math.remainder(a.theta - (h + math.pi / 2), 2 * math.pi) == pytest.approx(0)


def _assert_one_line(err: pytest.ExceptionInfo[RosbagError], *parts: str) -> None:
    text = str(err.value)
    assert "\n" not in text
    for part in parts:
        assert part in text


def test_without_tf_or_robot_the_error_asks_for_mounts(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    with pytest.raises(RosbagError) as err:
        read_rosbag(bag)
    _assert_one_line(err, str(bag), "no TF mount", "--robot")
    # A frame TF does not know is named.
    ranges = [*TF_RANGES, _range("/sonar_d", 1.0, 1.0, frame="sonar_top")]
    bag = write_bag(tmp_path / "tf", [*TF_ODOM, *TF_MOUNTS, *ranges],
                    {**TF_TYPES, "/sonar_d": RANGE})
    with pytest.raises(RosbagError) as err:
        read_rosbag(bag)
    _assert_one_line(err, "'sonar_top'", "--robot")


def test_without_odometry_the_error_says_so(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [*TF_MOUNTS, *TF_RANGES],
                    {k: v for k, v in TF_TYPES.items() if v != ODOM})
    with pytest.raises(RosbagError) as err:
        read_rosbag(bag)
    _assert_one_line(err, str(bag), "no odometry", ODOM, "/tf")


def test_a_robot_that_does_not_fit_the_bag_is_refused(tmp_path: Path) -> None:
    four = [_range(f"/sonar_{i}", 0.5, 1.0) for i in range(4)]
    bag = write_bag(tmp_path / "four", [*STRAIGHT_ODOM, *four],
                    {**{f"/sonar_{i}": RANGE for i in range(4)}, "/odom": ODOM})
    with pytest.raises(RosbagError) as err:
        read_rosbag(bag, robot=ROBOT)
    _assert_one_line(err, "robot 'two' has 2 sensors but the bag has 4", "does not fit")
    # TF places the three sonars; a three-sonar robot with other mounts is refused.
    three = parse_robot(ROBOT_YAML.replace(
        "sensors:\n", "sensors:\n  - {x: -0.25, y: 0.05, bearing_deg: 180.0}\n").replace(
        "name: two", "name: three"), "three")
    tf_bag = write_bag(tmp_path / "tf", [*TF_ODOM, *TF_MOUNTS, *TF_RANGES], TF_TYPES)
    with pytest.raises(RosbagError) as err:
        read_rosbag(tf_bag, robot=three)
    _assert_one_line(err, "robot 'three' does not fit", "sensor 1", "'sonar_front'")


def test_a_robot_that_agrees_with_tf_is_accepted(tmp_path: Path) -> None:
    yaml = ROBOT_YAML.split("sensors:")[0] + (
        "sensors:\n  - {x: -0.25, y: 0.05, bearing_deg: 180.0}\n"
        "  - {x: 0.1, y: 0.2, bearing_deg: 0.0}\n  - {x: 0.26, y: 0.0, bearing_deg: 92.0}\n")
    robot = parse_robot(yaml, "same")
    bag = write_bag(tmp_path / "tf", [*TF_ODOM, *TF_MOUNTS, *TF_RANGES], TF_TYPES)
    log = read_rosbag(bag, robot=robot)
    # TF wins where it exists (the robot's 0.26 is within 5 cm, 92° within 5°).
    np.testing.assert_allclose(log.batch.x, [1.95, 1.8, 2.0], atol=1e-9)


def test_not_a_bag(tmp_path: Path) -> None:
    fake = tmp_path / "fake.bag"
    fake.write_text("hello\n")
    with pytest.raises(RosbagError) as err:
        read_rosbag(fake)
    _assert_one_line(err, str(fake), "not a ROS bag")
    junk = tmp_path / "junk.bag"  # the codec's "can't decode byte 0xbd" leaked (UX review)
    junk.write_bytes(b"\xbd" + bytes(range(256)) * 4)
    with pytest.raises(RosbagError) as err:
        read_rosbag(junk)
    assert str(err.value) == (f"{junk}: not a ROS bag: it does not start as an MCAP, rosbag1 "
                              "or rosbag2 SQLite file does")
    folder = tmp_path / "folder"
    folder.mkdir()
    with pytest.raises(RosbagError) as err:
        read_rosbag(folder)
    assert str(err.value) == (f"{folder}: a folder, but not a rosbag2 folder (no metadata.yaml "
                              "in it)")
    with pytest.raises(RosbagError) as err:
        read_rosbag(tmp_path / "missing")
    _assert_one_line(err, "missing", "no such")


def _truncate(path: Path, keep: float) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * keep)])


@pytest.mark.parametrize("name", ["ros1.bag", "ros2_mcap", "ros2_sqlite3"])
@pytest.mark.parametrize("keep", [0.3, 0.7, 0.95])
def test_truncated_bags_give_one_line(tmp_path: Path, name: str, keep: float) -> None:
    bag = write_bag(tmp_path / name, [*TF_ODOM, *TF_MOUNTS, *TF_RANGES] * 20, TF_TYPES)
    files = [bag] if bag.is_file() else sorted(p for p in bag.iterdir()
                                               if p.suffix in {".mcap", ".db3"})
    _truncate(files[0], keep)
    with pytest.raises(RosbagError) as err:
        read_rosbag(bag)
    _assert_one_line(err, str(bag))


def test_a_bare_mcap_file_reads(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "run_mcap", [*TF_ODOM, *TF_MOUNTS, *TF_RANGES], TF_TYPES)
    (mcap,) = bag.glob("*.mcap")
    assert len(read_rosbag(mcap).batch) == 3


def test_missing_topics_and_wrong_types(tmp_path: Path) -> None:
    only_odom = write_bag(tmp_path / "odom", STRAIGHT_ODOM, {"/odom": ODOM})
    with pytest.raises(RosbagError) as err:
        read_rosbag(only_odom)
    _assert_one_line(err, str(only_odom), RANGE, "/odom")
    only_ranges = write_bag(tmp_path / "ranges", STRAIGHT_RANGES[:2],
                            {"/sonar_2": RANGE, "/sonar_10": RANGE})
    with pytest.raises(RosbagError) as err:
        read_rosbag(only_ranges, robot=ROBOT)
    _assert_one_line(err, str(only_ranges), ODOM)
    full = write_bag(tmp_path / "full", [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    with pytest.raises(RosbagError) as err:
        read_rosbag(full, range_topics=["/odom"])
    _assert_one_line(err, str(full), "'/odom'", ODOM, "expected " + RANGE)
    with pytest.raises(RosbagError) as err:
        read_rosbag(full, odom_topic="/sonar_2")
    _assert_one_line(err, str(full), "'/sonar_2'", "expected " + ODOM)
    with pytest.raises(RosbagError) as err:
        read_rosbag(full, range_topics=["/nope"])
    _assert_one_line(err, str(full), "'/nope'", "not in the bag")


def test_cli_convert_rosbag_with_tf(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "run_mcap", [*TF_ODOM, *TF_MOUNTS, *TF_RANGES], TF_TYPES)
    out = tmp_path / "readings.csv"
    assert main(["convert", "rosbag", str(bag), "--out", str(out)]) == 0
    batch = read_readings_csv(out)
    np.testing.assert_allclose(batch.x, [1.95, 1.8, 2.0], atol=1e-9)
    text = capsys.readouterr().out
    assert "sonar_rear" in text
    assert "/sonar_a" in text
    assert "infrared" in text
    assert "readings written" in text


def test_cli_convert_rosbag_with_robot(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    robot = tmp_path / "two.yaml"
    robot.write_text(ROBOT_YAML)
    out = tmp_path / "readings.csv"
    assert main(["convert", "rosbag", str(bag), "--robot", str(robot), "--out",
                 str(out)]) == 0
    batch = read_readings_csv(out)
    assert batch.sensor.tolist() == [0, 1, 0, 1]
    assert (batch.x[0], batch.y[0]) == (pytest.approx(1.25 + 0.1), pytest.approx(2.2))



def test_cli_convert_rosbag_names_sensors_without_a_field_of_view(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # User review: a driver that leaves field_of_view 0 got a silent 22.5° cone in process and
    # grid; convert, the step that checks a bag, now shows each sensor's beam and says so.
    bag = write_bag(tmp_path / "bag", [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    robot = tmp_path / "two.yaml"
    robot.write_text(ROBOT_YAML)
    out = tmp_path / "readings.csv"
    capsys.readouterr()
    assert main(["convert", "rosbag", str(bag), "--robot", str(robot), "--out",
                 str(out)]) == 0
    captured = capsys.readouterr()
    assert captured.err == ("sonarcarve: warning: sensor 1 (/sonar_10): field_of_view 0, so no "
                            "beam_width is written and process and grid will assume 22.5°; "
                            "give the sensors' cone with --beam-width DEGREES\n")
    lines = captured.out.splitlines()
    assert lines[0].endswith(f", beam {math.degrees(0.3):.1f}°")  # /sonar_2's 0.3 rad
    assert lines[1].endswith(", beam not given")
    assert main(["convert", "rosbag", str(bag), "--robot", str(robot), "--beam-width", "30",
                 "--out", str(tmp_path / "given.csv")]) == 0
    captured = capsys.readouterr()
    assert captured.err == ""
    assert captured.out.splitlines()[1].endswith(", beam 30.0°")

def test_cli_convert_rosbag_errors_are_one_line(tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "bag", [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    out = tmp_path / "r.csv"
    assert main(["convert", "rosbag", str(bag), "--odom-topic", "/sonar_2", "--out",
                 str(out)]) == 2
    assert main(["convert", "rosbag", "--out", str(out)]) == 2
    assert main(["convert", "roboND", "--robot", "scout2", "--out", str(out)]) == 2
    # p3dx-front has 8 sonars, the bag 2: refused, not used.
    assert main(["convert", "rosbag", str(bag), "--robot", "p3dx-front", "--out",
                 str(out)]) == 2
    # No TF and no --robot.
    assert main(["convert", "rosbag", str(bag), "--out", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err
    assert "/sonar_2" in err
    assert "does not fit" in err
    assert "--robot" in err
    assert all(line.startswith("sonarcarve: error:") for line in err.strip().splitlines())


@pytest.mark.parametrize(("name", "kind"), [
    ("ros1.bag", "truncated or corrupt rosbag1 file (its index cannot be read: was the "
                 "recording cut short?)"),
    ("run.mcap", "truncated or corrupt MCAP file (no end marker: was the recording cut short?)"),
])
def test_a_cut_short_bag_says_so_in_plain_words(tmp_path: Path, name: str, kind: str) -> None:
    # UX review, finding 11: "File end magic is invalid." and a Python tuple repr.
    source = write_bag(tmp_path / ("ros2_mcap" if name.endswith(".mcap") else name),
                       [*TF_ODOM, *TF_MOUNTS, *TF_RANGES] * 20, TF_TYPES)
    data = (source if source.is_file() else next(source.glob("*.mcap"))).read_bytes()
    bag = tmp_path / f"cut-{name}"
    bag.write_bytes(data[: len(data) // 2])
    with pytest.raises(RosbagError) as err:
        read_rosbag(bag)
    assert str(err.value) == f"{bag}: {kind}"


def test_two_odometry_topics_name_the_parameter_or_the_option(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The library names its parameter (odom_topic), the command its option (review finding
    3): a Python caller never typed --odom-topic."""
    second = [_odom(m.t, 0.0, 0.0, 0.0, topic="/odom2") for m in STRAIGHT_ODOM]
    bag = write_bag(tmp_path / "two_odoms", [*STRAIGHT_ODOM, *second, *STRAIGHT_RANGES],
                    {**STRAIGHT_TYPES, "/odom2": ODOM})
    with pytest.raises(RosbagError) as err:
        read_rosbag(bag, robot=ROBOT)
    _assert_one_line(err, str(bag), "several odometry topics (/odom, /odom2)",
                     "choose one with odom_topic")
    assert "--odom-topic" not in str(err.value)
    robot = tmp_path / "two.yaml"
    robot.write_text(ROBOT_YAML)
    assert main(["convert", "rosbag", str(bag), "--robot", str(robot), "--out",
                 str(tmp_path / "r.csv")]) == 2
    assert "choose one with --odom-topic" in capsys.readouterr().err
