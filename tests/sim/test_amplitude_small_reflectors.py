"""The amplitude model's small reflectors: legs and columns as convex cylinders (opt-in).

Expected levels are worked out by hand from the formula of :mod:`sonarcarve.sim.amplitude`
(module docstring, small reflectors): a cylinder of radius ρ whose surface is d from the sensor
echoes 10 log10(ρ / (ρ + d)) below a plane wall at d, which is −20 log10 d − 2 · 1.64 (d − 1)
(absorption 1.64 dB/m, no diffuse share). Threshold T = −52.40 dB (``test_amplitude``).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest

from sonarcarve.robot import RobotDescription, load_robot
from sonarcarve.sim.amplitude import AmplitudeModel, convex_mirror_db, mirror_echo_db
from sonarcarve.sim.scene import DynamicObstacle, Scene
from sonarcarve.sim.sonar import (
    DEFAULT_PHYSICS,
    NO_ECHO,
    PHYSICS_NAMES,
    Echoes,
    EchoKind,
    Firings,
    SonarPhysics,
    SonarPhysicsError,
    fire_sonars,
    named_physics,
)
from sonarcarve.sim.sonar.amplitude_facets import _Facets, _nearest_on_curves
from sonarcarve.sim.sonar.wall_geometry import _WallGeometry
from sonarcarve.sim.world import World

#: ``random_firings(n, seed, robot)``, the fixture of tests/sim/conftest.py.
RandomFirings = Callable[[int, int, RobotDescription], Firings]

#: Mirror-only walls, no noise: every decision is a deterministic threshold test.
SMOOTH = AmplitudeModel(diffuse_fraction=0.0, noise_db=0.0)
THIN = replace(SMOOTH, small_reflectors=True)
LEG = 0.02


# The helpers of test_amplitude (importlib mode: test modules do not import each other).
def physics(model: AmplitudeModel) -> SonarPhysics:
    """No range noise, no quantisation, no spurious echoes; the amplitude model ``model``."""
    return replace(SonarPhysics.clean(), echo_model="amplitude", amplitude=model)


def ring() -> RobotDescription:
    """One sensor at the robot's centre, 22.5 degree beam, 0.15-6.5 m."""
    return RobotDescription(
        name="test", mount_x=np.zeros(1), mount_y=np.zeros(1), bearing=np.zeros(1),
        beam_width=np.full(1, math.radians(22.5)), firing_order=np.arange(1),
        firing_period=0.04, range_resolution=0.0, min_range=0.15, max_range=6.5,
        robot_radius=0.2)


def fire(segments: list[list[float]], x: float, y: float, theta: float, phys: SonarPhysics,
         n: int = 1) -> Echoes:
    """``n`` firings of one sensor from the same pose."""
    firings = Firings(t=0.04 * np.arange(n), sensor=np.zeros(n, dtype=np.int64),
                      x=np.full(n, x), y=np.full(n, y), theta=np.full(n, theta))
    return fire_sonars(World(np.array(segments, dtype=float)), ring(), firings, phys,
                       np.random.default_rng(0))




def leg() -> list[list[float]]:
    """A 2 cm chair leg about the origin, drawn as world files draw it: a regular 24-gon."""
    return DynamicObstacle.disc((0.0, 0.0), LEG).segments.tolist()


def facing(d: float, bearing: float) -> tuple[float, float, float]:
    """A sensor pose ``d`` from the leg's surface, at ``bearing`` from its centre, facing it."""
    r = LEG + d
    return r * math.cos(bearing), r * math.sin(bearing), bearing + math.pi


# --------------------------------------------------------------------------- the equation


def test_leg_echo_against_a_wall_by_hand() -> None:
    # 1 m: 10 log10(0.02 / 1.02) = -17.08 dB; the wall is 0 dB, so the leg is -17.08 dB.
    # 3 m: 10 log10(0.02 / 3.02) = -21.79 dB under the wall's -9.54 - 6.56 = -16.10 dB: -37.89.
    np.testing.assert_allclose(convex_mirror_db(LEG, [1.0, 3.0]), [-17.076, -21.790], atol=1e-3)
    wall = mirror_echo_db(SMOOTH, np.array([1.0, 3.0]), 0.0)
    np.testing.assert_allclose(wall + convex_mirror_db(LEG, [1.0, 3.0]), [-17.076, -37.892],
                               atol=1e-3)
    # A 20 cm column at 1 m: 10 log10(0.2 / 1.2) = -7.78 dB; a plane (inf radius): 0 dB.
    np.testing.assert_allclose(convex_mirror_db([0.2, np.inf], 1.0), [-7.782, 0.0], atol=1e-3)


def test_a_24_gon_is_a_circle_and_a_box_is_not() -> None:
    box = DynamicObstacle.box(3.0, 3.0, 3.5, 3.5).segments
    disc = DynamicObstacle.disc((1.0, 2.0), 0.1).segments
    geometry = _WallGeometry.make(World(np.concatenate([disc, box, [[9.0, 0.0, 9.0, 5.0]]])))
    facets = _Facets.make(geometry, math.radians(30.0))
    np.testing.assert_allclose(facets.radius[:24], 0.1, rtol=1e-9)
    np.testing.assert_allclose(facets.center[:24], np.tile([1.0, 2.0], (24, 1)), atol=1e-12)
    assert not np.any(facets.curved[24:])
    # The disc's 24 joints are no corners; the box's 4 and the wall's 2 ends still are.
    assert facets.corner.sum() == 6
    assert geometry.scatter.shape[0] == 30


def test_every_bearing_belongs_to_exactly_one_facet() -> None:
    # Sensors 1 m out on every joint's bearing (exactly, where rounding decides) and on random
    # bearings: one facet's arc holds each, never none (a gap) nor two (a doubled echo).
    geometry = _WallGeometry.make(World(DynamicObstacle.disc((3.0, -1.0), 0.1).segments))
    facets = _Facets.make(geometry, math.radians(30.0))
    bearing = np.concatenate([2 * np.pi * np.arange(24) / 24,
                              np.random.default_rng(1).uniform(-np.pi, np.pi, 200)])
    origin = np.array([3.0, -1.0]) + 1.1 * np.column_stack((np.cos(bearing), np.sin(bearing)))
    walls = np.arange(24)
    _, distance, inside = _nearest_on_curves(facets, walls, origin, geometry.world.segments)
    assert inside.sum(axis=1).tolist() == [1] * origin.shape[0]
    np.testing.assert_allclose(distance[inside], 1.0, atol=1e-12)


# --------------------------------------------------------------------------- echoes


@pytest.mark.parametrize(("d", "quieter", "louder"), [(1.0, 3.1430, 3.1762),
                                                      (3.0, 7.2690, 7.3138)])
def test_leg_level_through_the_simulator(d: float, quieter: float, louder: float) -> None:
    # The leg's level read through the whole simulator, to 0.1 dB: heard with the threshold
    # 0.1 dB under it, not with the threshold 0.1 dB over it. Threshold of a detection range R:
    # -20 log10 R - 3.28 (R - 1); R = 3.1430 gives -16.976 and 3.1762 gives -17.176 (leg at
    # 1 m: -17.076 dB); R = 7.2690 gives -37.792 and 7.3138 gives -37.992 (at 3 m: -37.892).
    pose = facing(d, math.radians(40.0))
    over = replace(THIN, detection_range=quieter)
    under = replace(THIN, detection_range=louder)
    assert fire(leg(), *pose, physics(over)).kind[0] == NO_ECHO
    assert fire(leg(), *pose, physics(under)).kind[0] == EchoKind.DIRECT


def test_a_leg_facing_a_facet_is_heard_far_only_as_a_wall() -> None:
    # Facing the middle of a facet (bearing 7.5 degrees), the default model hears the facet as
    # a wall: at 5.5 m -29.57 dB, far above T. As a cylinder: -29.57 - 24.41 = -53.98 dB,
    # under T (-52.40): silent. At 4.5 m: -24.54 - 23.54 = -48.09 dB, heard at 4.5 m.
    bearing = math.radians(7.5)
    far = facing(5.5, bearing)
    assert fire(leg(), *far, physics(SMOOTH)).kind[0] == EchoKind.DIRECT
    assert fire(leg(), *far, physics(THIN)).kind[0] == NO_ECHO
    near = fire(leg(), *facing(4.5, bearing), physics(THIN))
    assert near.kind[0] == EchoKind.DIRECT
    assert near.range[0] == pytest.approx(4.5)


@pytest.mark.parametrize("bearing_deg", [0.0, 3.0, 7.5, 11.0, 15.0, 101.0, 200.0, 311.0])
def test_the_leg_echoes_from_its_circle_whatever_the_bearing(bearing_deg: float) -> None:
    # At 1 m the leg (-17.08 dB) is heard from every bearing, from the circle's point nearest
    # the sensor. The default model hears a facet's foot or, between two facets' arcs
    # (bearing 0: a vertex), the vertex as an edge.
    b = math.radians(bearing_deg)
    echoes = fire(leg(), *facing(1.0, b), physics(THIN))
    assert echoes.kind[0] == EchoKind.DIRECT
    assert echoes.range[0] == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(echoes.reflection[0], [LEG * math.cos(b), LEG * math.sin(b)],
                               atol=1e-12)


def test_the_joints_of_a_leg_are_no_edges() -> None:
    # With no mirror at all (reflectivity 0) the default model still hears the vertex facing
    # the sensor at 1 m as an edge (-10 dB); a cylinder has no vertices.
    bearing = 0.0  # a vertex of the 24-gon
    mute = replace(SMOOTH, reflectivity=0.0)
    edge = fire(leg(), *facing(1.0, bearing), physics(mute))
    assert edge.kind[0] == EchoKind.DIRECT
    np.testing.assert_allclose(edge.reflection[0], [LEG, 0.0], atol=1e-12)
    thin = replace(mute, small_reflectors=True)
    assert fire(leg(), *facing(1.0, bearing), physics(thin)).kind[0] == NO_ECHO


def test_a_rough_leg_scatters_from_its_width_only() -> None:
    # All diffuse (no mirror), 5 m, the axis ray meeting a facet head-on (the only ray that
    # hits: rays 1 degree apart are 8.7 cm apart there), sigma = 1 / pi, Psi ~ 0.14 rad:
    # as a wall A = (r Psi)^2 = 0.49 m^2: 6 - 8.07 - 27.96 - 13.12 = -43.1 dB, heard;
    # as a cylinder A = r Psi * 2 rho = 0.028 m^2: 6 - 20.5 - 27.96 - 13.12 = -55.6 dB, not.
    rough = AmplitudeModel(diffuse_fraction=1.0, noise_db=0.0, small_reflectors=True)
    assert fire(leg(), *facing(5.0, math.radians(7.5)), physics(rough)).kind[0] == NO_ECHO
    # The same 4 cm seen as part of a wall is heard (its diffuse echo, the facet's foot lying
    # off its 5 mm).
    wide = replace(rough, small_reflectors=False, edge_db=-60.0)
    assert fire(leg(), *facing(5.0, math.radians(7.5)), physics(wide)).kind[0] == EchoKind.DIRECT


def test_detection_of_a_leg_falls_with_range_as_the_normal_tail() -> None:
    # 2 dB noise, one draw per firing. Levels by hand (see the module docstring):
    # 4.0 m: -21.88 - 23.03 = -44.91 dB, margin +7.49: P = Phi(3.75) = 1.000
    # 4.8 m: -26.09 - 23.82 = -49.91 dB, margin +2.49: P = Phi(1.25) = 0.894
    # 5.6 m: -30.05 - 24.49 = -54.54 dB, margin -2.14: P = Phi(-1.07) = 0.143
    # 2000 firings each: standard deviation of a share at most 0.011.
    noisy = physics(AmplitudeModel(diffuse_fraction=0.0, noise_db=2.0, small_reflectors=True))
    bearing = math.radians(40.0)
    shares = [(fire(leg(), *facing(d, bearing), noisy, n=2000).kind == EchoKind.DIRECT).mean()
              for d in (4.0, 4.8, 5.6)]
    np.testing.assert_allclose(shares, [1.0, 0.894, 0.143], atol=0.04)


def test_a_moving_column_of_a_scene_echoes_as_a_cylinder_where_it_is() -> None:
    # A 20 cm column moving from (2, 3) to (2, -3) over 6 s, a wall at x = 5 behind it. At
    # t = 3 s it is on the axis: its circle's nearest point is (1.8, 0), level
    # -20 log 1.8 - 3.28 * 0.8 + 10 log10(0.2 / 2.0) = -5.11 - 2.62 - 10.00 = -17.73 dB, heard.
    # At t = 1 and 5 s it is 26.6 degrees off the axis (two-way directivity about -48 dB):
    # silent, and the wall is heard head-on at 5 m (-13.98 - 13.12 = -27.10 dB).
    column = DynamicObstacle.disc((2.0, 3.0), 0.2, "column", shift=(0.0, -6.0), t0=0.0, t1=6.0)
    firings = Firings(t=np.array([1.0, 3.0, 5.0]), sensor=np.zeros(3, dtype=np.int64),
                      x=np.zeros(3), y=np.zeros(3), theta=np.zeros(3))
    echoes = fire_sonars(World(np.array([[5.0, -10.0, 5.0, 10.0]])), ring(), firings,
                         physics(THIN), np.random.default_rng(0), scene=Scene((column,)))
    np.testing.assert_allclose(echoes.range, [5.0, 1.8, 5.0], atol=1e-9)
    assert echoes.obstacle.tolist() == [-1, 0, -1]
    np.testing.assert_allclose(echoes.reflection[1], [1.8, 0.0], atol=1e-9)


# --------------------------------------------------------------------------- the default


def digest(kind: np.ndarray, ranges: np.ndarray) -> str:
    h = hashlib.sha256()
    h.update(np.asarray(kind).tobytes())
    h.update(np.round(np.nan_to_num(ranges, nan=-1.0, posinf=-2.0), 9).tobytes())
    return h.hexdigest()[:16]


def room_with_discs(room: World) -> World:
    discs = [DynamicObstacle.disc(c, r).segments
             for c, r in (((2.0, 2.0), 0.02), ((7.5, 5.5), 0.2), ((8.5, 2.0), 0.1))]
    return World(np.concatenate([room.segments, *discs]), name="room+discs")


@pytest.mark.parametrize(("model", "expected"), [
    (AmplitudeModel(), "8605cd75c3c04ae3"),
    (AmplitudeModel(diffuse_fraction=0.5, noise_db=4.0), "a5807ccb483eae5b"),
])
def test_default_amplitude_echoes_are_unchanged(model: AmplitudeModel, expected: str,
                                                room: World,
                                                random_firings: RandomFirings) -> None:
    # Digests recorded at commit 5d87d34, before small reflectors existed: the option is off by
    # default and every amplitude run stays bit for bit what it was.
    assert not AmplitudeModel().small_reflectors
    robot = load_robot("scout2")
    firings = random_firings(1500, 11, robot)
    echoes = fire_sonars(room_with_discs(room), robot, firings,
                         SonarPhysics(echo_model="amplitude", amplitude=model),
                         np.random.default_rng(5))
    assert digest(echoes.kind, echoes.range) == expected


def test_small_reflectors_change_nothing_in_a_world_of_walls(room: World,
                                                             random_firings: RandomFirings) -> None:
    robot = load_robot("scout2")
    firings = random_firings(800, 3, robot)
    runs = [fire_sonars(room, robot, firings, SonarPhysics(
        echo_model="amplitude", amplitude=AmplitudeModel(small_reflectors=on)),
        np.random.default_rng(2)) for on in (False, True)]
    np.testing.assert_array_equal(runs[0].kind, runs[1].kind)
    np.testing.assert_array_equal(runs[0].range, runs[1].range)
    thin = fire_sonars(room_with_discs(room), robot, firings, SonarPhysics(
        echo_model="amplitude", amplitude=AmplitudeModel(small_reflectors=True)),
        np.random.default_rng(2))
    assert not np.array_equal(thin.range, fire_sonars(
        room_with_discs(room), robot, firings, SonarPhysics(echo_model="amplitude"),
        np.random.default_rng(2)).range, equal_nan=True)


@pytest.mark.parametrize("turn", [0.0, -0.1, 2.0, float("nan")])
def test_bad_facet_turn_is_refused(turn: float) -> None:
    with pytest.raises(SonarPhysicsError, match="facet_turn"):
        AmplitudeModel(facet_turn=turn)


@pytest.mark.parametrize("flag", ["no", 1, None])
def test_small_reflectors_must_be_a_bool(flag: object) -> None:
    with pytest.raises(SonarPhysicsError, match="small_reflectors must be True or False"):
        AmplitudeModel(small_reflectors=flag)  # type: ignore[arg-type]



def test_named_sensor_models() -> None:
    assert PHYSICS_NAMES == ("specular", "amplitude", "amplitude-thin")
    assert named_physics("specular") == DEFAULT_PHYSICS
    assert named_physics("amplitude") == replace(DEFAULT_PHYSICS, echo_model="amplitude")
    thin = named_physics("amplitude-thin", SonarPhysics.clean())
    assert thin == replace(SonarPhysics.clean(), echo_model="amplitude",
                           amplitude=AmplitudeModel(small_reflectors=True))
    # Each name sets the option, whatever the base had: amplitude from a thin base is plain.
    assert not named_physics("amplitude", thin).amplitude.small_reflectors
    assert named_physics("amplitude", thin).echo_model == "amplitude"
    with pytest.raises(SonarPhysicsError, match="unknown sensor model 'thin'"):
        named_physics("thin")


# --------------------------------------------------------------------------- walls, not legs


def _bowed_wall(x: float) -> list[list[float]]:
    """A straight wall 4 m long at ``x`` drawn in 4 pieces whose joints bend 1 mm away from
    the origin (rounded coordinates): each joint turns the same way, by far less than 30°."""
    xs = x + np.array([0.0, 0.0007, 0.001, 0.0007, 0.0])
    ys = np.linspace(-2.0, 2.0, 5)
    return [[xs[i], ys[i], xs[i + 1], ys[i + 1]] for i in range(4)]


@pytest.mark.parametrize(("segments", "x"), [
    (_bowed_wall(2.0), 0.0),  # its middle pieces bend about a circle of 2 km, concave here
    (_bowed_wall(5.0), 0.0),
    (DynamicObstacle.disc((0.0, 0.0), 3.0).segments.tolist(), 0.5),  # a round room, inside
])
def test_walls_drawn_in_pieces_are_heard_as_walls(segments: list[list[float]], x: float) -> None:
    # A wall in pieces and a round room seen from inside are no legs: their mirror echo is a
    # plane wall's, as with small reflectors off (it was lost: the sensor is inside the circle).
    plain = fire(segments, x, 0.0, 0.0, physics(SMOOTH))
    thin = fire(segments, x, 0.0, 0.0, physics(THIN))
    assert plain.kind.tolist() == [EchoKind.DIRECT]
    np.testing.assert_array_equal(thin.range, plain.range)
    assert thin.kind.tolist() == plain.kind.tolist()


def test_only_closed_runs_are_curves() -> None:
    # A bowed wall and a rounded corner (three 30° turns) are open runs: no facets; a leg is.
    corner = [[-5.0, 2.0, 1.0, 2.0], [1.0, 2.0, 1.5, 1.866], [1.5, 1.866, 1.866, 1.5],
              [1.866, 1.5, 2.0, 1.0], [2.0, 1.0, 2.0, -5.0]]
    world = World(np.array(_bowed_wall(2.0) + corner + leg()))
    facets = _Facets.make(_WallGeometry.make(world), math.radians(30.0))
    assert facets.curved.tolist() == [False] * 9 + [True] * 24
