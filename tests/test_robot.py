"""Robot descriptions: the built-in rings match their documented layouts; bad files fail clearly."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.errors import SonarcarveError
from sonarcarve.robot import BUILTIN_ROBOTS, RobotDescription, RobotError, load_robot

GOOD_YAML = """\
name: two-eyes
robot_radius: 0.2
range_resolution: 0.01
min_range: 0.1
max_range: 4.0
firing_period: 0.05
beam_width_deg: 30
sensors:
  - {x: 0.2, y: 0.0, bearing_deg: 0}
  - {x: 0.0, y: 0.2, bearing_deg: 90, beam_width_deg: 10}
"""


@pytest.mark.parametrize("name", BUILTIN_ROBOTS)
def test_every_builtin_robot_loads(name: str) -> None:
    robot = load_robot(name)
    assert robot.n_sensors > 0
    assert robot.max_range > robot.min_range >= 0.0
    assert np.all((robot.beam_width > 0) & (robot.beam_width < math.pi))
    assert sorted(set(robot.firing_order.tolist())) == list(range(robot.n_sensors))
    assert robot.description


def test_scout2_is_the_papers_ring() -> None:
    robot = load_robot("scout2")
    assert robot.n_sensors == 16
    # Equally spaced 22.5 degrees apart, on a 0.41 m diameter body, 22.5 degree beams.
    steps = np.diff(np.unwrap(robot.bearing))
    np.testing.assert_allclose(np.mod(steps, 2 * math.pi), math.radians(22.5), atol=1e-12)
    np.testing.assert_allclose(np.hypot(robot.mount_x, robot.mount_y), 0.41 / 2, atol=1e-3)
    np.testing.assert_allclose(np.arctan2(robot.mount_y, robot.mount_x),
                               np.angle(np.exp(1j * robot.bearing)), atol=1e-3)
    np.testing.assert_allclose(robot.beam_width, math.radians(22.5))
    assert robot.range_resolution == pytest.approx(0.0254)  # one inch
    np.testing.assert_array_equal(robot.firing_order, np.arange(16))


def test_p3dx_and_robond_bearings() -> None:
    p3dx = load_robot("p3dx-front")
    assert sorted(np.round(np.degrees(p3dx.bearing), 9)) == [-90, -50, -30, -10, 10, 30, 50, 90]
    nd = load_robot("roboND-8")
    np.testing.assert_allclose(np.degrees(nd.bearing),
                               [-90, -37.5, -22.5, -7.5, 7.5, 22.5, 37.5, 90])
    np.testing.assert_array_equal(nd.mount_x, 0.0)
    np.testing.assert_array_equal(nd.mount_y, 0.0)
    assert (nd.min_range, nd.max_range) == (0.17, 5.0)


def test_p3dx_full_ring_is_arias_sonar_units() -> None:
    # Expected values typed from ARIA's params/p3dx.p, "SonarUnit <n> <x mm> <y mm> <heading>":
    # SonarUnit 8 -157 -136 -90, 11 -255 -27 -170, 12 -255 27 170, 15 -157 136 90.
    robot = load_robot("p3dx")
    assert robot.n_sensors == 16
    for sensor, (x_mm, y_mm, heading) in {8: (-157, -136, -90), 11: (-255, -27, -170),
                                          12: (-255, 27, 170), 15: (-157, 136, 90)}.items():
        assert robot.mount_x[sensor] == pytest.approx(x_mm / 1000)
        assert robot.mount_y[sensor] == pytest.approx(y_mm / 1000)
        assert math.degrees(robot.bearing[sensor]) == pytest.approx(heading)
    # Rear bank 8-15: -90, -130, -150, -170, 170, 150, 130, 90 degrees, every mount behind the
    # centre; the front bank is p3dx-front's ring, sensor for sensor.
    np.testing.assert_allclose(np.degrees(robot.bearing[8:]),
                               [-90, -130, -150, -170, 170, 150, 130, 90])
    assert np.all(robot.mount_x[8:] < 0.0)
    front = load_robot("p3dx-front")
    for field in ("mount_x", "mount_y", "bearing", "beam_width"):
        np.testing.assert_array_equal(getattr(robot, field)[:8], getattr(front, field))
    # The banks alternate, 20 ms apart: each sensor fires every 0.32 s, as the firmware's two
    # banks firing together every 40 ms do.
    times, sensors = robot.firing_schedule(0.0, 0.02 * 31)
    np.testing.assert_allclose(np.diff(times), 0.02)
    np.testing.assert_array_equal(sensors[:4], [0, 8, 1, 9])
    for sensor in range(16):
        np.testing.assert_allclose(np.diff(times[sensors == sensor]), 0.32)


def test_car_parking_12_is_a_car_with_bumper_and_side_sensors() -> None:
    # Expected values from the YAML's sources and stated choices, not from the loader: a
    # 4.5 x 1.8 m car, 4 front + 4 rear + 2 per side, 70 degree beams, 0.15..5.5 m in 1 cm
    # steps, 0.035 s per firing, body disc of half the width.
    car = load_robot("car-parking-12")
    assert car.n_sensors == 12
    np.testing.assert_allclose(car.beam_width, math.radians(70.0))
    assert (car.min_range, car.max_range, car.range_resolution) == (0.15, 5.5, 0.01)
    assert car.firing_period == pytest.approx(0.035)
    assert car.cycle_time == pytest.approx(0.42)
    assert car.robot_radius == pytest.approx(1.8 / 2)
    # Every sensor on the body outline: |x| <= 2.25 (half the length), |y| <= 0.9 (half width).
    assert np.all(np.abs(car.mount_x) <= 4.5 / 2 + 1e-9)
    assert np.all(np.abs(car.mount_y) <= 1.8 / 2 + 1e-9)
    ahead = np.cos(car.bearing) > 0.5   # within 60 degrees of straight ahead
    behind = np.cos(car.bearing) < -0.5
    side = np.abs(np.cos(car.bearing)) < 1e-9
    assert (ahead.sum(), behind.sum()) == (4, 4)
    np.testing.assert_array_equal(car.mount_x[ahead] > 2.0, True)   # in the front bumper
    np.testing.assert_array_equal(car.mount_x[behind] < -2.0, True)  # in the rear bumper
    # Two per side, aimed sideways, near the corners, on the car's flank.
    assert (np.sin(car.bearing[side]) > 0).sum() == 2
    assert (np.sin(car.bearing[side]) < 0).sum() == 2
    np.testing.assert_allclose(np.abs(car.mount_y[side]), 0.9)
    assert np.all(np.abs(car.mount_x[side]) > 1.5)
    # The side sensors are spread through the firing order: every 3rd firing is a side one.
    side_slots = np.flatnonzero(side[car.firing_order])
    np.testing.assert_array_equal(side_slots, [0, 3, 6, 9])


def test_yaml_file_loads_with_defaults_and_overrides(tmp_path: Path) -> None:
    path = tmp_path / "two.yaml"
    path.write_text(GOOD_YAML)
    robot = load_robot(path)
    assert robot.name == "two-eyes"
    np.testing.assert_allclose(robot.beam_width, np.radians([30, 10]))
    np.testing.assert_array_equal(robot.firing_order, [0, 1])
    assert robot.cycle_time == pytest.approx(0.1)


def test_firing_schedule_cycles_through_the_order() -> None:
    robot = load_robot("p3dx-front")
    times, sensors = robot.firing_schedule(1.0, 1.0 + 0.04 * 20)
    assert times.shape == (21,)
    np.testing.assert_allclose(np.diff(times), 0.04)
    assert times[0] == 1.0
    np.testing.assert_array_equal(sensors, np.arange(21) % 8)


def test_sensor_poses_rotate_mounts_with_the_heading() -> None:
    robot = RobotDescription(
        name="t", mount_x=np.array([0.2]), mount_y=np.array([0.1]), bearing=np.array([0.5]),
        beam_width=np.array([0.3]), firing_order=np.array([0]), firing_period=0.1,
        range_resolution=0.0, min_range=0.1, max_range=5.0, robot_radius=0.25)
    # Heading 90 degrees: robot-frame x points to world +y, robot-frame y to world -x.
    sx, sy, theta = robot.sensor_poses(1.0, 2.0, math.pi / 2, 0)
    assert float(sx) == pytest.approx(1.0 - 0.1)
    assert float(sy) == pytest.approx(2.0 + 0.2)
    assert float(theta) == pytest.approx(math.pi / 2 + 0.5)


@pytest.mark.parametrize(
    ("text", "field"),
    [
        (GOOD_YAML.replace("max_range: 4.0\n", ""), "max_range"),
        (GOOD_YAML.replace("max_range: 4.0", "max_range: far"), "max_range"),
        (GOOD_YAML.replace("bearing_deg: 90,", "bearing: 90,"), "sensors[1].bearing"),
        (GOOD_YAML.replace("{x: 0.2, y: 0.0, ", "{x: 0.2, "), "sensors[0].y"),
        (GOOD_YAML.replace("firing_period: 0.05", "firing_period: 0"), "firing_period"),
        (GOOD_YAML.replace("min_range: 0.1", "min_range: 5.0"), "min_range"),
        (GOOD_YAML + "firing_order: [0, 7]\n", "firing_order"),
        (GOOD_YAML + "colour: red\n", "colour"),
        (GOOD_YAML.replace("beam_width_deg: 30", "beam_width_deg: 200"), "beam_width_deg"),
        (GOOD_YAML.replace("beam_width_deg: 10", "beam_width_deg: 0"), "sensors[1].beam_width_deg"),
        (GOOD_YAML.replace("beam_width_deg: 10", "beam_width_deg: 1e-9"),
         "sensors[1].beam_width_deg"),
    ],
)
def test_bad_robot_yaml_names_file_and_field(tmp_path: Path, text: str, field: str) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(RobotError) as info:
        load_robot(path)
    message = str(info.value)
    assert "\n" not in message
    assert str(path) in message
    assert repr(field) in message
    assert isinstance(info.value, SonarcarveError)


def test_broken_yaml_syntax_names_the_line(tmp_path: Path) -> None:
    path = tmp_path / "broken.yaml"
    path.write_text("name: x\nsensors: [\n  - {x: 1\n")
    with pytest.raises(RobotError, match=r"broken\.yaml: line \d+"):
        load_robot(path)


def test_unknown_name_and_missing_file() -> None:
    with pytest.raises(RobotError, match=r"unknown robot 'nomad'.*scout2"):
        load_robot("nomad")
    with pytest.raises(RobotError, match=r"missing/robot\.yaml: no such file"):
        load_robot("missing/robot.yaml")


@pytest.mark.parametrize(
    ("order", "problem"),
    [
        ("[0, 1, 0]", "lists sensor 0 2 times; list each of 0..1 once"),
        ("[1, 1]", "lists sensor 1 2 times; list each of 0..1 once"),
        ("[1]", "leaves out sensor 0; list each of 0..1 once"),
    ],
)
def test_firing_order_must_fire_each_sensor_once(tmp_path: Path, order: str,
                                                 problem: str) -> None:
    path = tmp_path / "ring.yaml"
    path.write_text(GOOD_YAML + f"firing_order: {order}\n")
    with pytest.raises(RobotError) as info:
        load_robot(path)
    assert str(info.value) == f"{path}: field 'firing_order' {problem}"


def test_firing_order_lists_every_sensor_left_out() -> None:
    with pytest.raises(RobotError) as info:
        RobotDescription(
            name="ring", mount_x=np.zeros(5), mount_y=np.zeros(5), bearing=np.zeros(5),
            beam_width=np.full(5, 0.3), firing_order=np.array([3, 0]), firing_period=0.1,
            range_resolution=0.0, min_range=0.1, max_range=5.0, robot_radius=0.2)
    assert str(info.value) == ("ring: field 'firing_order' leaves out sensors 1, 2, 4; list each "
                               "of 0..4 once")


def test_robot_file_problems_use_the_shared_wording(tmp_path: Path) -> None:
    with pytest.raises(RobotError) as info:
        load_robot(tmp_path)
    assert str(info.value) == f"{tmp_path}: is a directory"
    with pytest.raises(RobotError) as info:
        load_robot(tmp_path / "robot.yml")
    assert str(info.value) == f"{tmp_path / 'robot.yml'}: no such file"
    path = tmp_path / "big.yaml"
    path.write_text(GOOD_YAML.replace("max_range: 4.0", f"max_range: {10**400}"))
    with pytest.raises(RobotError, match=r"field 'max_range' must be a finite number, got 1000"):
        load_robot(path)


def test_firing_schedule_refuses_more_than_max_firings() -> None:
    robot = load_robot("scout2")  # fires every 0.04 s
    # One week: 604,800 s / 0.04 s = 15,120,000 intervals, 15,120,001 firings > 1e6.
    with pytest.raises(RobotError) as info:
        robot.firing_schedule(0.0, 604_800.0)
    assert str(info.value) == ("scout2: firing every 0.04 s from t = 0 s to 604800 s takes "
                               "1.512e+07 firings, more than the limit of 1,000,000 "
                               "(MAX_FIRINGS)")
    with pytest.raises(RobotError, match="MAX_FIRINGS"):
        robot.firing_schedule(0.0, math.inf)


@pytest.mark.parametrize(
    ("line", "field", "problem"),
    [
        ("firing_period: 1.0e-9", "firing_period", "must lie in [0.0001, 3600] s, got 1e-09"),
        ("firing_period: 1.0e+9", "firing_period", "must lie in [0.0001, 3600] s, got 1e+09"),
        ("max_range: 1.0e+300", "max_range", "must be at most 1000 m, got 1e+300"),
        ("firing_order: [99999999999999999999, 1]", "firing_order",
         "must list sensor indices in 0..1"),
    ],
)
def test_absurd_numbers_get_one_line_with_the_documented_range(
        tmp_path: Path, line: str, field: str, problem: str) -> None:
    key = line.split(":")[0]
    text = "\n".join(row for row in GOOD_YAML.splitlines() if not row.startswith(key + ":"))
    path = tmp_path / "r.yaml"
    path.write_text(text + "\n" + line + "\n")
    with pytest.raises(RobotError) as info:
        load_robot(path)
    assert str(info.value) == f"{path}: field {field!r} {problem}"


def test_firing_order_longer_than_any_ring_is_refused_before_it_is_built(tmp_path: Path) -> None:
    path = tmp_path / "r.yaml"
    path.write_text(GOOD_YAML + "firing_order: [" + "0, " * 2000 + "1]\n")
    with pytest.raises(RobotError, match="has 2001 entries, more than the limit of 1024"):
        load_robot(path)


def test_a_yaml_bomb_is_refused_fast(tmp_path: Path) -> None:
    levels = "".join(f"{k}: &{k} [{', '.join([f'*{p}'] * 9)}]\n"
                     for p, k in zip("abcdefgh", "bcdefghi", strict=True))
    path = tmp_path / "bomb.yaml"
    path.write_text('a: &a ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]\n'
                    + levels + "name: *i\n")
    with pytest.raises(RobotError) as info:
        load_robot(path)
    assert str(info.value) == f"{path}: invalid YAML (aliases expand to more than 100,000 nodes)"


def test_a_robot_file_larger_than_any_ring_is_refused_unread(tmp_path: Path) -> None:
    path = tmp_path / "r.yaml"
    path.write_text(GOOD_YAML + "firing_order: [" + "0, " * 2_000_000 + "1]\n")
    with pytest.raises(RobotError, match="larger than the limit of 262,144 bytes"):
        load_robot(path)
