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
           lo: float = 0.1, hi: float = 4.0) -> Msg:
    return Msg(topic, t, {"frame": frame, "range": r, "field_of_view": fov, "min_range": lo,
                          "max_range": hi})


def _odom(t: float, x: float, y: float, yaw: float, topic: str = "/odom") -> Msg:
    return Msg(topic, t, {"x": x, "y": y, "yaw": yaw})


def _build(msg: Msg, msgtype: str) -> Any:
    f = msg.fields
    if msgtype == RANGE:
        return TS.types[RANGE](header=_header(msg.t, f["frame"]), radiation_type=0,
                               field_of_view=f["field_of_view"], min_range=f["min_range"],
                               max_range=f["max_range"], range=f["range"])
    geo = "geometry_msgs/msg/"
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
    """Write ``messages`` (in list order, logged at 1 ms steps) as rosbag1 if ``*.bag``."""
    if path.suffix == ".bag":
        from rosbags.rosbag1 import Writer as Writer1

        with Writer1(path) as w1:
            conns = {t: w1.add_connection(t, m, typestore=TS) for t, m in types.items()}
            for k, msg in enumerate(messages):
                mtype = types[msg.topic]
                w1.write(conns[msg.topic], (k + 1) * 1_000_000,
                         TS.serialize_ros1(_build(msg, mtype), mtype))
        return path
    from rosbags.rosbag2 import Writer as Writer2

    with Writer2(path, version=8) as w2:
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
    return [tuple(reading) for reading in batch]


@pytest.mark.parametrize("name", ["bag2", "straight.bag"])
def test_straight_drive_gives_hand_computed_world_poses(tmp_path: Path, name: str) -> None:
    bag = write_bag(tmp_path / name, [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    log = read_rosbag(bag, robot=ROBOT)
    np.testing.assert_allclose(np.array(_rows(log.batch)), np.array(_expected_straight()),
                               atol=1e-9)
    assert np.all(np.diff(log.batch.t) >= 0.0)
    report = log.report
    assert report.sensors == (("/sonar_2", ""), ("/sonar_10", ""))
    assert report.messages == {"/sonar_2": 5, "/sonar_10": 4, "/odom": 5}
    assert (report.no_echo, report.outside_odometry, report.readings) == (4, 1, 4)
    assert report.odometry_topic == "/odom"


def test_topic_order_given_numbers_the_sensors(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    log = read_rosbag(bag, robot=ROBOT, range_topics=["/sonar_10", "/sonar_2"],
                      odom_topic="/odom", beam_width=0.25)
    # /sonar_10 is now sensor 0: its 0.5 s echo of 3.0 m sits at mount 0 and sorts first.
    first = log.batch[0]
    assert (first.sensor, first.range) == (0, 3.0)
    assert first.x == pytest.approx(1.25 + 0.1)
    assert first.y == pytest.approx(2.2)
    assert first.beam_width == 0.25  # field_of_view 0: the given default


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


def test_without_robot_sensors_take_the_odometry_pose(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "bag", [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    batch = read_rosbag(bag).batch
    np.testing.assert_allclose(batch.x, 1.0 + 0.5 * batch.t)
    np.testing.assert_allclose(batch.y, 2.0)
    np.testing.assert_allclose(batch.theta, 0.0)


def _assert_one_line(err: pytest.ExceptionInfo[RosbagError], *parts: str) -> None:
    text = str(err.value)
    assert "\n" not in text
    for part in parts:
        assert part in text


def test_not_a_bag(tmp_path: Path) -> None:
    fake = tmp_path / "fake.bag"
    fake.write_text("hello\n")
    with pytest.raises(RosbagError) as err:
        read_rosbag(fake)
    _assert_one_line(err, str(fake), "not a readable")
    folder = tmp_path / "folder"
    folder.mkdir()
    with pytest.raises(RosbagError) as err:
        read_rosbag(folder)
    _assert_one_line(err, str(folder))
    with pytest.raises(RosbagError) as err:
        read_rosbag(tmp_path / "missing")
    _assert_one_line(err, "missing", "no such")


def test_missing_topics_and_wrong_types(tmp_path: Path) -> None:
    only_odom = write_bag(tmp_path / "odom", STRAIGHT_ODOM, {"/odom": ODOM})
    with pytest.raises(RosbagError) as err:
        read_rosbag(only_odom)
    _assert_one_line(err, str(only_odom), RANGE, "/odom")
    only_ranges = write_bag(tmp_path / "ranges", STRAIGHT_RANGES[:2],
                            {"/sonar_2": RANGE, "/sonar_10": RANGE})
    with pytest.raises(RosbagError) as err:
        read_rosbag(only_ranges)
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


def test_more_sensors_than_the_robot_has(tmp_path: Path) -> None:
    one = parse_robot(ROBOT_YAML.split("  - {x: 0.3")[0], "one")
    bag = write_bag(tmp_path / "bag", [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    with pytest.raises(RosbagError) as err:
        read_rosbag(bag, robot=one)
    _assert_one_line(err, str(bag), "'/sonar_10'", "only 1 sensors")


def test_cli_convert_rosbag(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "bag", [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    out = tmp_path / "readings.csv"
    assert main(["convert", "rosbag", str(bag), "--robot", "p3dx-front", "--out",
                 str(out)]) == 0
    batch = read_readings_csv(out)
    assert batch.sensor.tolist() == [0, 1, 0, 1]
    # p3dx-front sensor 0: (0.069, 0.136) at 90° (its YAML); heading 0 at t = 0.5, x = 1.25.
    assert (batch.x[0], batch.y[0]) == (pytest.approx(1.25 + 0.069), pytest.approx(2.136))
    assert batch.theta[0] == pytest.approx(math.pi / 2)
    assert "readings written" in capsys.readouterr().out


def test_cli_convert_rosbag_errors_are_one_line(tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_bag(tmp_path / "bag", [*STRAIGHT_ODOM, *STRAIGHT_RANGES], STRAIGHT_TYPES)
    out = tmp_path / "r.csv"
    assert main(["convert", "rosbag", str(bag), "--odom-topic", "/sonar_2", "--out",
                 str(out)]) == 2
    assert main(["convert", "rosbag", "--out", str(out)]) == 2
    assert main(["convert", "roboND", "--robot", "scout2", "--out", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err
    assert "/sonar_2" in err
