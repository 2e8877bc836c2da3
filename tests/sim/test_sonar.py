"""Sonar physics: specular walls, corners, range limits, spurious echoes, truth, determinism.

Expected ranges come from plane geometry worked out by hand in each test, never from the code.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest

from sonarcarve.robot import RobotDescription, load_robot
from sonarcarve.sim.sonar import (
    NO_ECHO,
    Echoes,
    EchoKind,
    Firings,
    SonarPhysics,
    SonarPhysicsError,
    fire_sonars,
    tracing,
    wall_geometry,
)
from sonarcarve.sim.world import World

#: ``random_firings(n, seed, robot)``, the fixture of tests/sim/conftest.py.
RandomFirings = Callable[[int, int, RobotDescription], Firings]

CLEAN = SonarPhysics.clean()
BEAM = math.radians(22.5)


def ring(n: int = 1, *, period: float = 0.04, max_range: float = 6.5, min_range: float = 0.15,
         resolution: float = 0.0) -> RobotDescription:
    """A ring of ``n`` sensors at the robot centre, all facing forward."""
    return RobotDescription(
        name="test", mount_x=np.zeros(n), mount_y=np.zeros(n), bearing=np.zeros(n),
        beam_width=np.full(n, BEAM), firing_order=np.arange(n), firing_period=period,
        range_resolution=resolution, min_range=min_range, max_range=max_range,
        robot_radius=0.2)


def fire_once(segments: list[list[float]], x: float, y: float, theta: float,
              physics: SonarPhysics = CLEAN, robot: RobotDescription | None = None) -> Echoes:
    firings = Firings(t=np.zeros(1), sensor=np.zeros(1, dtype=np.int64), x=np.array([x]),
                      y=np.array([y]), theta=np.array([theta]))
    return fire_sonars(World(np.array(segments, dtype=float)), robot or ring(), firings, physics,
                       np.random.default_rng(0))


LONG_WALL = [[3.0, -20.0, 3.0, 20.0]]  # x = 3, normal along x


def test_wall_at_normal_incidence_echoes_at_its_distance() -> None:
    echoes = fire_once(LONG_WALL, 0.0, 0.0, 0.0)
    assert echoes.kind[0] == EchoKind.DIRECT
    assert echoes.range[0] == pytest.approx(3.0)
    np.testing.assert_allclose(echoes.reflection[0], [3.0, 0.0], atol=1e-9)


def test_wall_at_60_degrees_incidence_is_silent() -> None:
    # The axis meets the wall 60 degrees off its normal at 3 / cos 60 = 6 m; the beam's rays
    # span 48.75..71.25 degrees of incidence, all beyond the critical angle: a mirror.
    echoes = fire_once(LONG_WALL, 0.0, 0.0, math.radians(60))
    assert echoes.kind[0] == NO_ECHO
    assert math.isnan(echoes.range[0])
    # The idealised sensor (every wall echoes) hears the nearest ray, the beam's lower edge.
    ideal = fire_once(LONG_WALL, 0.0, 0.0, math.radians(60), SonarPhysics.ideal())
    assert ideal.range[0] == pytest.approx(3.0 / math.cos(math.radians(60 - 11.25)))


def test_wall_within_critical_angle_plus_half_beam_echoes_from_the_beam_edge() -> None:
    # Axis 25 degrees off the normal: the edge ray at 13.75 degrees is inside 17.5 degrees.
    echoes = fire_once(LONG_WALL, 0.0, 0.0, math.radians(25))
    assert echoes.kind[0] == EchoKind.DIRECT
    assert echoes.range[0] == pytest.approx(3.0 / math.cos(math.radians(25 - 11.25)))


CORNER = [[3.0, -20.0, 3.0, 3.0], [3.0, 3.0, -20.0, 3.0]]  # concave room corner at (3, 3)


def test_corner_echoes_at_oblique_view() -> None:
    # Both walls are seen 33.75..56.25 degrees off their normals: only the corner answers.
    echoes = fire_once(CORNER, 0.0, 0.0, math.radians(45))
    assert echoes.kind[0] == EchoKind.DIRECT
    assert echoes.range[0] == pytest.approx(math.hypot(3.0, 3.0))
    np.testing.assert_allclose(echoes.reflection[0], [3.0, 3.0], atol=1e-9)
    silent = replace(CLEAN, corner_echoes=False, corner_radius=0.0)
    assert fire_once(CORNER, 0.0, 0.0, math.radians(45), silent).kind[0] == NO_ECHO


def test_corner_hidden_behind_a_mirror_wall_is_silent() -> None:
    # The wall y = 1.5 crosses the whole beam 33.75..56.25 degrees off its normal (a mirror)
    # and hides the corner behind it; its own ends lie outside the beam.
    hidden = [*CORNER, [-1.0, 1.5, 4.0, 1.5]]
    assert fire_once(hidden, 0.0, 0.0, math.radians(45)).kind[0] == NO_ECHO


def test_corner_radius_alone_catches_rays_landing_near_the_corner() -> None:
    only_radius = replace(CLEAN, corner_echoes=False, corner_radius=0.05)
    echoes = fire_once(CORNER, 0.0, 0.0, math.radians(45), only_radius)
    assert echoes.kind[0] == EchoKind.DIRECT
    # The axis ray lands on the corner itself; neighbours land within 5 cm and are farther.
    assert echoes.range[0] == pytest.approx(math.hypot(3.0, 3.0), abs=0.05)
    assert np.hypot(*(echoes.reflection[0] - [3.0, 3.0])) <= 0.05 + 1e-9


def test_free_wall_end_echoes_but_a_straight_joint_does_not() -> None:
    # Sensor at (0, -3) looking at 45 degrees: the wall x = 3 is seen 33.75..56.25 degrees off
    # its normal, and the beam axis passes through (3, 0).
    free_end = [[3.0, -20.0, 3.0, 0.0]]
    echoes = fire_once(free_end, 0.0, -3.0, math.radians(45))
    assert echoes.kind[0] == EchoKind.DIRECT
    np.testing.assert_allclose(echoes.reflection[0], [3.0, 0.0], atol=1e-9)
    assert echoes.range[0] == pytest.approx(3.0 * math.sqrt(2.0))
    joint = [[3.0, -20.0, 3.0, 0.0], [3.0, 0.0, 3.0, 20.0]]  # one straight wall in two pieces
    assert fire_once(joint, 0.0, -3.0, math.radians(45)).kind[0] == NO_ECHO
    t_junction = [*joint, [3.0, 0.0, 5.0, 0.0]]  # a third wall meets the joint: a corner
    assert fire_once(t_junction, 0.0, -3.0, math.radians(45)).kind[0] == EchoKind.DIRECT
    kinked = [[3.0, -20.0, 3.0, 0.0], [3.0, 0.0, 3.5, 20.0]]  # a real (convex) corner
    assert fire_once(kinked, 0.0, -3.0, math.radians(45)).kind[0] == EchoKind.DIRECT


def test_nearest_echoing_ray_wins_over_a_farther_one() -> None:
    # A short wall at 2 m fills the left half of the beam; the long wall at 3 m the rest.
    walls = [*LONG_WALL, [2.0, 0.05, 2.0, 5.0]]
    echoes = fire_once(walls, 0.0, 0.0, 0.0)
    assert echoes.range[0] == pytest.approx(2.0 / math.cos(math.atan2(0.05, 2.0)), abs=0.03)
    assert echoes.reflection[0][0] == pytest.approx(2.0)


def test_max_and_min_range() -> None:
    robot = ring(max_range=6.5, min_range=0.15)
    assert fire_once([[7.0, -20, 7.0, 20]], 0, 0, 0.0, robot=robot).kind[0] == NO_ECHO
    assert fire_once([[6.4, -20, 6.4, 20]], 0, 0, 0.0, robot=robot).range[0] == pytest.approx(6.4)
    assert fire_once([[0.1, -20, 0.1, 20]], 0, 0, 0.0, robot=robot).kind[0] == NO_ECHO


def test_quantisation_rounds_to_the_range_resolution() -> None:
    inch = 0.0254
    robot = ring(resolution=inch)
    quantised = fire_once([[3.0, -20, 3.0, 20]], 0, 0, 0.0, SonarPhysics(
        range_noise=0.0, crosstalk_probability=0.0, floor_episode_rate=0.0,
        multipath_probability=0.0), robot=robot)
    assert quantised.range[0] == pytest.approx(round(3.0 / inch) * inch)  # 118 inches
    assert quantised.true_range[0] == pytest.approx(3.0)
    raw = fire_once([[3.0, -20, 3.0, 20]], 0, 0, 0.0, robot=robot)
    assert raw.range[0] == pytest.approx(3.0)


def test_multipath_reads_the_bounced_path_length() -> None:
    # The axis at 45 degrees meets wall A (x = 2) at (2, 2), 2*sqrt(2) m away, too obliquely to
    # echo; mirrored, it heads at 135 degrees and meets wall B head-on 2 m further on, at
    # c = (2 - sqrt 2, 2 + sqrt 2). The echo retraces the path: range 2*sqrt(2) + 2.
    root2 = math.sqrt(2.0)
    c = np.array([2.0 - root2, 2.0 + root2])
    along = np.array([1.0, 1.0]) / root2 * 0.7
    walls = [[2.0, -10.0, 2.0, 10.0], [*(c - along), *(c + along)]]
    physics = replace(CLEAN, multipath_probability=1.0)
    echoes = fire_once(walls, 0.0, 0.0, math.radians(45), physics)
    assert echoes.kind[0] == EchoKind.MULTIPATH
    assert echoes.range[0] == pytest.approx(2 * root2 + 2.0, abs=1e-6)
    np.testing.assert_allclose(echoes.reflection[0], c, atol=1e-6)
    assert fire_once(walls, 0.0, 0.0, math.radians(45)).kind[0] == NO_ECHO  # switched off


def test_crosstalk_hears_the_late_echo_of_the_previous_ping() -> None:
    # Two sensors facing a wall 10 m away (beyond their 6.5 m range) fire 0.04 s apart. The
    # echo of one ping travels 20 m; the next sensor times it from its own firing, 0.04 s
    # later: 20 / 2 - 343 * 0.04 / 2 = 3.14 m.
    robot = ring(2, period=0.04)
    n = 6
    firings = Firings(t=0.04 * np.arange(n), sensor=np.arange(n) % 2, x=np.zeros(n),
                      y=np.zeros(n), theta=np.zeros(n))
    physics = replace(CLEAN, crosstalk_probability=1.0)
    world = World(np.array([[10.0, -20, 10.0, 20]]))
    echoes = fire_sonars(world, robot, firings, physics, np.random.default_rng(0))
    assert echoes.kind[0] == NO_ECHO  # nothing fired before the first ping
    np.testing.assert_array_equal(echoes.kind[1:], EchoKind.CROSSTALK)
    np.testing.assert_allclose(echoes.range[1:], 10.0 - 343.0 * 0.04 / 2)
    assert np.all(np.isnan(echoes.reflection))
    off = fire_sonars(world, robot, firings, CLEAN, np.random.default_rng(0))
    np.testing.assert_array_equal(off.kind, NO_ECHO)


def test_floor_bounce_during_tilt_episodes() -> None:
    # Tilted all the time, every sensor facing the floor: every firing hears it near 0.62 m.
    physics = replace(CLEAN, floor_episode_rate=50.0, floor_episode_duration=100.0,
                      floor_probability=1.0, floor_half_angle=math.pi)
    n = 200
    firings = Firings(t=0.04 * np.arange(n), sensor=np.zeros(n, dtype=np.int64),
                      x=np.zeros(n), y=np.zeros(n), theta=np.zeros(n))
    echoes = fire_sonars(World(np.array(LONG_WALL)), ring(), firings, physics,
                         np.random.default_rng(3))
    floor = echoes.kind == EchoKind.FLOOR
    assert floor.mean() > 0.9  # the first episode may start a moment after t = 0
    assert np.all(np.abs(echoes.range[floor] - 0.62) < 5 * 0.05)
    assert np.all(np.isnan(echoes.reflection[floor]))
    assert np.all(echoes.kind[~floor] == EchoKind.DIRECT)




def test_truth_is_consistent_with_the_readings(room: World, random_firings: RandomFirings) -> None:
    robot = load_robot("scout2")
    firings = random_firings(1500, 11, robot)
    physics = replace(SonarPhysics(), multipath_probability=1.0, crosstalk_probability=0.5)
    echoes = fire_sonars(room, robot, firings, physics, np.random.default_rng(5))
    kinds = set(echoes.kind.tolist())
    assert {EchoKind.DIRECT, EchoKind.MULTIPATH} <= kinds
    origin = np.column_stack((firings.x, firings.y))
    offset = echoes.reflection - origin
    seen_at = np.hypot(offset[:, 0], offset[:, 1])

    direct = echoes.kind == EchoKind.DIRECT
    # Range within noise (5 sigma) and half an inch of quantisation of the reflection's distance.
    assert np.all(np.abs(seen_at[direct] - echoes.range[direct]) <= 5 * 0.01 + 0.0127 + 1e-9)
    np.testing.assert_allclose(seen_at[direct], echoes.true_range[direct], atol=1e-9)
    # Inside the beam, and on a wall.
    bearing = np.arctan2(offset[direct, 1], offset[direct, 0])
    off_axis = np.abs(np.angle(np.exp(1j * (bearing - firings.theta[direct]))))
    assert np.all(off_axis <= BEAM / 2 + 1e-9)
    assert np.all(room.distance_to_walls(echoes.reflection[direct]) < 1e-9)

    bounced = echoes.kind == EchoKind.MULTIPATH
    assert np.all(room.distance_to_walls(echoes.reflection[bounced]) < 1e-9)
    assert np.all(echoes.true_range[bounced] > seen_at[bounced])  # a detour is longer
    nothing = (echoes.kind == EchoKind.FLOOR) | (echoes.kind == EchoKind.CROSSTALK)
    assert np.all(np.isnan(echoes.reflection[nothing]))
    heard = echoes.kind != NO_ECHO
    assert np.all(echoes.range[heard] >= robot.min_range)
    assert np.all(echoes.range[heard] <= robot.max_range)
    assert np.all(np.isnan(echoes.range[~heard]))


def test_wall_prefilter_and_batching_do_not_change_the_result(
        monkeypatch: pytest.MonkeyPatch, room: World, random_firings: RandomFirings) -> None:
    robot = load_robot("scout2")
    firings = random_firings(600, 2, robot)
    physics = replace(SonarPhysics(), multipath_probability=1.0, crosstalk_probability=1.0)
    fast = fire_sonars(room, robot, firings, physics, np.random.default_rng(9))

    def everything(self: object, *box: float, margin: float) -> object:
        geometry = self
        world = geometry.world  # type: ignore[attr-defined]
        return world, np.arange(len(world)), geometry.scatter  # type: ignore[attr-defined]

    monkeypatch.setattr(wall_geometry._WallGeometry, "near", everything)
    monkeypatch.setattr(tracing, "_CHUNK_FIRINGS", 37)
    slow = fire_sonars(room, robot, firings, physics, np.random.default_rng(9))
    np.testing.assert_array_equal(fast.kind, slow.kind)
    np.testing.assert_array_equal(fast.range, slow.range)
    np.testing.assert_array_equal(fast.reflection, slow.reflection)


def hall_world() -> World:
    """A 60 x 14 m hall with free-standing walls every 4 m on both sides of its middle line:
    a robot on that line hears walls from all over its 6.5 m range."""
    walls = [[0, 0, 60, 0], [60, 0, 60, 14], [60, 14, 0, 14], [0, 14, 0, 0]]
    walls += [[x, 2.0 + (x % 8) / 4, x + 1.5, 3.5] for x in range(2, 58, 4)]
    walls += [[x, 10.5, x + 1.5, 12.0 - (x % 8) / 4] for x in range(4, 58, 4)]
    return World(np.array(walls, dtype=float), name="hall")


@pytest.mark.parametrize("crosstalk", [1.0, 0.0])  # off: the direct echoes alone must agree
@pytest.mark.parametrize("echo_model", ["specular", "amplitude"])
def test_wall_prefilter_keeps_every_wall_within_range_of_a_tour(
    monkeypatch: pytest.MonkeyPatch, echo_model: str, crosstalk: float,
) -> None:
    # Firings in tour order, so each batch's box is a short stretch of the hall (the room test
    # above fires all over its room in every batch): a pre-filter margin short of max_range
    # loses the walls between it and max_range of the stretch.
    robot = load_robot("scout2")
    n = 3000
    x = np.linspace(1.0, 59.0, n)
    heading = np.full(n, 0.3)
    sensor = np.arange(n) % robot.n_sensors
    sx, sy, theta = robot.sensor_poses(x, np.full(n, 7.0), heading, sensor)
    firings = Firings(t=0.04 * np.arange(n), sensor=sensor, x=sx, y=sy, theta=theta)
    physics = replace(SonarPhysics(echo_model=echo_model), multipath_probability=1.0,
                      crosstalk_probability=crosstalk)
    fast = fire_sonars(hall_world(), robot, firings, physics, np.random.default_rng(3))

    def everything(self: object, *box: float, margin: float) -> object:
        geometry = self
        world = geometry.world  # type: ignore[attr-defined]
        return world, np.arange(len(world)), geometry.scatter  # type: ignore[attr-defined]

    monkeypatch.setattr(wall_geometry._WallGeometry, "near", everything)
    slow = fire_sonars(hall_world(), robot, firings, physics, np.random.default_rng(3))
    assert np.count_nonzero(fast.true_range > robot.max_range / 2) > 100  # far walls heard
    np.testing.assert_array_equal(fast.kind, slow.kind)
    np.testing.assert_array_equal(fast.range, slow.range)
    np.testing.assert_array_equal(fast.reflection, slow.reflection)


def test_same_seed_same_echoes_other_seed_differs(room: World,
                                                  random_firings: RandomFirings) -> None:
    robot = load_robot("scout2")
    firings = random_firings(300, 4, robot)
    runs = [fire_sonars(room, robot, firings, SonarPhysics(), np.random.default_rng(s))
            for s in (1, 1, 2)]
    np.testing.assert_array_equal(runs[0].range, runs[1].range)
    np.testing.assert_array_equal(runs[0].kind, runs[1].kind)
    assert not np.array_equal(runs[0].range, runs[2].range, equal_nan=True)


@pytest.mark.parametrize(
    "change",
    [{"rays_per_beam": 0}, {"critical_angle": -0.1}, {"crosstalk_probability": 1.5},
     {"range_noise": -1.0}, {"sound_speed": 0.0}, {"crosstalk_lookback": -1}],
)
def test_bad_physics_parameters_are_refused(change: dict[str, float]) -> None:
    with pytest.raises(SonarPhysicsError, match=next(iter(change))):
        SonarPhysics(**change)  # type: ignore[arg-type]


def test_echo_model_is_chosen_by_name_and_defaults_to_specular() -> None:
    from sonarcarve.sim.amplitude import AmplitudeModel
    from sonarcarve.sim.sonar import DEFAULT_PHYSICS

    assert DEFAULT_PHYSICS.echo_model == "specular"
    assert DEFAULT_PHYSICS.amplitude == AmplitudeModel()
    chosen = replace(SonarPhysics(), echo_model="amplitude")
    assert chosen.echo_model == "amplitude"
    # The 60 degree mirror wall is silent to both; the head-on wall at 3 m heard by both.
    assert fire_once(LONG_WALL, 0.0, 0.0, math.radians(60),
                     replace(CLEAN, echo_model="amplitude")).kind[0] == NO_ECHO
    assert fire_once(LONG_WALL, 0.0, 0.0, 0.0,
                     replace(CLEAN, echo_model="amplitude")).range[0] == pytest.approx(3.0)


@pytest.mark.parametrize("name", ["Amplitude", "arc", ""])
def test_unknown_echo_model_names_the_choices(name: str) -> None:
    with pytest.raises(SonarPhysicsError, match=r"echo_model.*'specular', 'amplitude'"):
        SonarPhysics(echo_model=name)


def test_amplitude_field_must_be_an_amplitude_model() -> None:
    with pytest.raises(SonarPhysicsError, match="amplitude"):
        SonarPhysics(amplitude=3.0)  # type: ignore[arg-type]
