"""The amplitude sonar model: levels and echo probabilities on hand-made geometries.

Every expected level is worked out by hand in the test from the model's equations
(:mod:`sonarcarve.sim.amplitude`, module docstring) and textbook constants, never taken from
the code under test. Defaults used in the hand sums: f = 49.4 kHz, a = 19.2 mm, c = 343 m/s
(ka = 2π f a / c = 17.374), absorption 1.64 dB/m, detection range 10.7 m, so the threshold is
T = −20 log10(10.7) − 2 · 1.64 · 9.7 = −20.59 − 31.82 = −52.41 dB.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from sonarcarve.robot import RobotDescription, load_robot
from sonarcarve.sim.amplitude import (
    AmplitudeModel,
    detection_probability,
    diffuse_echo_db,
    directivity_db,
    equivalent_beam_width,
    mirror_echo_db,
    point_echo_db,
)
from sonarcarve.sim.sonar import (
    NO_ECHO,
    Echoes,
    EchoKind,
    Firings,
    SonarPhysics,
    SonarPhysicsError,
    fire_sonars,
    tracing,
)
from sonarcarve.sim.world import World

#: ``random_firings(n, seed, robot)``, the fixture of tests/sim/conftest.py.
RandomFirings = Callable[[int, int, RobotDescription], Firings]

KA = 2 * math.pi * 49_400 * 0.0192 / 343  # 17.374
THRESHOLD = -20 * math.log10(10.7) - 2 * 1.64 * 9.7  # -52.41 dB
#: Mirror-only walls, no noise: every decision is a deterministic threshold test.
SMOOTH = AmplitudeModel(diffuse_fraction=0.0, noise_db=0.0)
#: 3.8317 and 5.1356: first zero of J1 and first maximum of |2 J1(x)/x| beyond it.
FIRST_NULL = math.asin(3.8317 / KA)  # 12.74 degrees
SIDE_LOBE = math.asin(5.1356 / KA)  # 17.18 degrees; the lobe peaks at -17.57 dB


def physics(model: AmplitudeModel = SMOOTH, **changes: float) -> SonarPhysics:
    """No range noise, no quantisation, no spurious echoes; the amplitude model ``model``."""
    return replace(SonarPhysics.clean(), echo_model="amplitude", amplitude=model, **changes)


def ring(max_range: float = 6.5, n: int = 1) -> RobotDescription:
    return RobotDescription(
        name="test", mount_x=np.zeros(n), mount_y=np.zeros(n), bearing=np.zeros(n),
        beam_width=np.full(n, math.radians(22.5)), firing_order=np.arange(n),
        firing_period=0.04, range_resolution=0.0, min_range=0.15, max_range=max_range,
        robot_radius=0.2)


def fire(segments: list[list[float]], x: float, y: float, theta: float,
         phys: SonarPhysics, robot: RobotDescription | None = None, n: int = 1,
         seed: int = 0) -> Echoes:
    """``n`` firings of one sensor from the same pose."""
    firings = Firings(t=0.04 * np.arange(n), sensor=np.zeros(n, dtype=np.int64),
                      x=np.full(n, x), y=np.full(n, y), theta=np.full(n, theta))
    return fire_sonars(World(np.array(segments, dtype=float)), robot or ring(), firings, phys,
                       np.random.default_rng(seed))


def wall_at(d: float) -> list[list[float]]:
    """A long wall x = d, its normal along x, its ends far outside every beam."""
    return [[d, -50.0, d, 50.0]]


# --------------------------------------------------------------------------- the equations


def test_threshold_is_a_perfect_wall_head_on_at_the_detection_range() -> None:
    assert AmplitudeModel().threshold_db == pytest.approx(THRESHOLD, abs=1e-9)
    # Rough walls answer less loudly; the sensor's threshold does not move.
    assert AmplitudeModel(diffuse_fraction=0.9).threshold_db == pytest.approx(THRESHOLD)


def test_piston_directivity_at_its_landmarks() -> None:
    m = AmplitudeModel()
    level = directivity_db(m, [0.0, SIDE_LOBE, -SIDE_LOBE, FIRST_NULL, math.pi])
    assert level[0] == pytest.approx(0.0)
    assert level[1] == pytest.approx(-17.57, abs=0.02)  # the textbook first side lobe
    assert level[2] == level[1]  # symmetric
    assert level[3] == pytest.approx(-30.0)  # a null, filled to null_depth_db
    assert level[4] == pytest.approx(-30.0)  # behind the sensor
    # The -3 dB half-width of a piston: 2 J1(x)/x = 0.7071 at x = 1.6163.
    assert float(directivity_db(m, math.asin(1.6163 / KA))) == pytest.approx(-3.01, abs=0.02)


def test_equivalent_beam_width_matches_the_gaussian_approximation() -> None:
    # Near the axis 2 J1(x)/x ~ exp(-x^2 / 8), so b^4 ~ exp(-(ka psi)^2 / 2) and the integral
    # is sqrt(2 pi) / ka = 0.1443 rad; side lobes and the null floor change it by a few percent.
    assert equivalent_beam_width(AmplitudeModel()) == pytest.approx(
        math.sqrt(2 * math.pi) / KA, rel=0.05)


def test_mirror_echo_level_by_hand() -> None:
    # Head-on at 1 m is the reference: 0 dB. At 2 m: -20 log 2 - 2 * 1.64 * 1 = -9.30 dB.
    assert float(mirror_echo_db(SMOOTH, 1.0, 0.0)) == pytest.approx(0.0, abs=1e-12)
    assert float(mirror_echo_db(SMOOTH, 2.0, 0.0)) == pytest.approx(-9.301, abs=1e-3)
    # 2 % diffuse: each specular reflection keeps 98 %: 10 log 0.98 = -0.088 dB.
    two = AmplitudeModel(diffuse_fraction=0.02)
    assert float(mirror_echo_db(two, 1.0, 0.0)) == pytest.approx(-0.0877, abs=1e-4)
    assert float(mirror_echo_db(two, 1.0, 0.0, 2)) == pytest.approx(-0.1755, abs=1e-4)


def test_diffuse_level_of_a_rough_wall_at_60_degrees_by_hand() -> None:
    # Half the energy scattered by Lambert's law; the axis meets the wall at r = 2 m, 60 degrees
    # from its normal. sigma = 0.5 cos^2 60 / pi = 0.03979; pulse depth c tau / 2 =
    # 343 * 16 / 49400 / 2 = 0.05555 m; across = min(Psi, 0.05555 / (2 tan 60)) = 0.016035;
    # A = 2 Psi * (2 / cos 60) * 0.016035 = 0.12828 Psi; with Psi = sqrt(2 pi) / ka = 0.1443,
    # sigma A = 7.366e-4: strength 6 + 10 log = -25.33 dB; spreading -40 log 2 = -12.04;
    # absorption -3.28: level -40.65 dB, well above the threshold.
    rough = AmplitudeModel(diffuse_fraction=0.5)
    level = float(diffuse_echo_db(rough, 2.0, 0.0, math.radians(60)))
    assert level == pytest.approx(-40.65, abs=0.25)  # Psi's approximation is good to 5 %
    assert level > THRESHOLD
    assert float(diffuse_echo_db(SMOOTH, 2.0, 0.0, math.radians(60))) == -math.inf


@given(st.floats(0.2, 15.0), st.floats(0.01, 3.0), st.floats(0.0, 1.2), st.floats(0.0, 1.5))
def test_every_level_falls_with_range(r: float, more: float, alpha: float,
                                      gamma: float) -> None:
    m = AmplitudeModel(diffuse_fraction=0.3)
    for level in (lambda d: mirror_echo_db(m, d, alpha),
                  lambda d: point_echo_db(m, d, alpha, m.edge_db),
                  lambda d: diffuse_echo_db(m, d, alpha, gamma)):
        assert float(level(r + more)) < float(level(r))


def test_detection_probability_is_the_normal_tail_of_the_margin() -> None:
    m = AmplitudeModel(noise_db=2.0)
    p = detection_probability(m, [THRESHOLD, THRESHOLD + 2.0, THRESHOLD - 4.0])
    np.testing.assert_allclose(p, [0.5, 0.8413, 0.0228], atol=1e-4)  # Phi(0), Phi(1), Phi(-2)
    quiet = AmplitudeModel(noise_db=0.0)
    assert detection_probability(quiet, [THRESHOLD - 1e-6, THRESHOLD + 1e-6]).tolist() == [
        0.0, 1.0]


# --------------------------------------------------------------------------- hand-made worlds


def test_wall_head_on_at_1_m_is_heard_at_its_distance() -> None:
    echoes = fire(wall_at(1.0), 0.0, 0.0, 0.0, physics())
    assert echoes.kind[0] == EchoKind.DIRECT
    assert echoes.range[0] == pytest.approx(1.0)
    np.testing.assert_allclose(echoes.reflection[0], [1.0, 0.0], atol=1e-12)


def test_smooth_wall_at_60_degrees_is_silent_a_rough_one_is_heard() -> None:
    # Smooth: the mirror point (1, 0) lies 60 degrees off the axis, in the filled null region:
    # 2 * -30 - 0 = -60 dB < -52.4. No corner in sight, no diffuse part: silence.
    assert fire(wall_at(1.0), 0.0, 0.0, math.radians(60), physics()).kind[0] == NO_ECHO
    # Rough: the axis ray alone is heard (-40.65 dB at r = 2 m, above); rays nearer the normal
    # come back sooner but fainter, and the fan's near edge (30 degrees off axis, r = 1.155 m)
    # is far below: 2 * D(30 deg) ~ -48 dB before any wall loss.
    rough = physics(AmplitudeModel(diffuse_fraction=0.5, noise_db=0.0))
    echoes = fire(wall_at(1.0), 0.0, 0.0, math.radians(60), rough)
    assert echoes.kind[0] == EchoKind.DIRECT
    assert 1.0 / math.cos(math.radians(30)) < echoes.range[0] <= 2.0 + 1e-9
    assert echoes.reflection[0][0] == pytest.approx(1.0)


def test_wall_outside_the_nominal_beam_is_heard_through_the_side_lobe_when_loud_enough() -> None:
    # The wall's normal is 17.2 degrees off the axis: outside the 11.25 degree half-beam, at the
    # first side lobe. At 2 m: 2 * -17.57 - 20 log 2 - 3.28 = -44.44 dB > -52.41: heard, at the
    # mirror point (2, 0), 17.2 degrees off the axis.
    echoes = fire(wall_at(2.0), 0.0, 0.0, SIDE_LOBE, physics())
    assert echoes.kind[0] == EchoKind.DIRECT
    assert echoes.range[0] == pytest.approx(2.0)
    np.testing.assert_allclose(echoes.reflection[0], [2.0, 0.0], atol=1e-12)
    # At 5 m: -35.14 - 13.98 - 13.12 = -62.24 dB: silent.
    assert fire(wall_at(5.0), 0.0, 0.0, SIDE_LOBE, physics()).kind[0] == NO_ECHO
    # In the null between main lobe and side lobe, even 1 m is too far: -60 dB.
    assert fire(wall_at(1.0), 0.0, 0.0, FIRST_NULL, physics()).kind[0] == NO_ECHO


def test_head_on_wall_at_the_detection_range_is_heard_half_the_time() -> None:
    # Level = threshold exactly; 2 dB noise, one draw per firing: P = Phi(0) = 0.5. Over 4000
    # firings the share has standard deviation 0.008.
    phys = physics(AmplitudeModel(diffuse_fraction=0.0, noise_db=2.0))
    echoes = fire(wall_at(10.7), 0.0, 0.0, 0.0, phys, robot=ring(max_range=12.0), n=4000)
    heard = echoes.kind == EchoKind.DIRECT
    assert heard.mean() == pytest.approx(0.5, abs=0.04)
    assert np.all(echoes.range[heard] == pytest.approx(10.7))
    # The wall at 9.95 m: -19.96 - 29.36 = -49.31 dB, 3.10 dB above: P = Phi(1.55) = 0.94.
    nearer = fire(wall_at(9.95), 0.0, 0.0, 0.0, phys, robot=ring(max_range=12.0), n=4000)
    assert (nearer.kind == EchoKind.DIRECT).mean() == pytest.approx(0.94, abs=0.03)


def test_right_angled_corner_retro_reflects_a_free_end_diffracts() -> None:
    # Room corner (5, 5) seen from the origin along its diagonal: both walls' mirror points lie
    # 45 degrees off the axis (-60 - 13.98 - 13.12 = -87 dB), but the corner sends the sound
    # straight back like a wall at its distance: -20 log 7.071 - 2 * 1.64 * 6.071 = -36.90 dB.
    # As a mere edge it would be -10 - 40 log 7.071 - 19.91 = -63.9 dB: silent.
    far = ring(max_range=9.0)
    corner = [[5.0, -20.0, 5.0, 5.0], [5.0, 5.0, -20.0, 5.0]]
    echoes = fire(corner, 0.0, 0.0, math.radians(45), physics(), robot=far)
    assert echoes.kind[0] == EchoKind.DIRECT
    assert echoes.range[0] == pytest.approx(math.hypot(5.0, 5.0))
    np.testing.assert_allclose(echoes.reflection[0], [5.0, 5.0], atol=1e-12)
    # A free wall end on the axis at 4.243 m: -10 - 40 log 4.243 - 10.64 = -45.75 dB, heard;
    # at 7.07 m (from (-2, -5)): -63.9 dB, silent. The wall's mirror points are 45 degrees off.
    free_end = [[3.0, -20.0, 3.0, 0.0]]
    near = fire(free_end, 0.0, -3.0, math.radians(45), physics(), robot=far)
    assert near.kind[0] == EchoKind.DIRECT
    np.testing.assert_allclose(near.reflection[0], [3.0, 0.0], atol=1e-12)
    assert fire(free_end, -2.0, -5.0, math.radians(45), physics(), robot=far).kind[0] == NO_ECHO


def test_corner_hidden_behind_a_silent_wall_is_not_heard() -> None:
    # The corner (3, 3) alone is heard (-23.19 dB). The wall y = 1.5 crosses the line of sight at
    # (1.5, 1.5); its mirror point (0, 1.5) is 45 degrees off the axis and its ends lie at 24 and
    # 79 degrees, near a null and behind the lobes: itself silent, it hides the corner.
    corner = [[3.0, -20.0, 3.0, 3.0], [3.0, 3.0, -20.0, 3.0]]
    assert fire(corner, 0.0, 0.0, math.radians(45), physics()).kind[0] == EchoKind.DIRECT
    hidden = [*corner, [-1.0, 1.5, 4.0, 1.5]]
    assert fire(hidden, 0.0, 0.0, math.radians(45), physics()).kind[0] == NO_ECHO


# --------------------------------------------------------------------------- whole simulations




AMPLITUDE = SonarPhysics(echo_model="amplitude",
                         amplitude=AmplitudeModel(diffuse_fraction=0.3))


def test_truth_of_amplitude_echoes_is_consistent(room: World,
                                                 random_firings: RandomFirings) -> None:
    robot = load_robot("scout2")
    firings = random_firings(1500, 11, robot)
    echoes = fire_sonars(room, robot, firings, AMPLITUDE, np.random.default_rng(5))
    direct = echoes.kind == EchoKind.DIRECT
    assert direct.mean() > 0.5
    origin = np.column_stack((firings.x, firings.y))
    seen_at = np.hypot(*(echoes.reflection - origin).T)
    np.testing.assert_allclose(seen_at[direct], echoes.true_range[direct], atol=1e-9)
    assert np.all(room.distance_to_walls(echoes.reflection[direct]) < 1e-9)
    bounced = echoes.kind == EchoKind.MULTIPATH
    assert np.all(echoes.true_range[bounced] > seen_at[bounced])
    # Some direct echoes come from outside the nominal 22.5 degree beam (side lobes).
    bearing = np.arctan2(*(echoes.reflection[direct] - origin[direct]).T[::-1])
    off_axis = np.abs(np.angle(np.exp(1j * (bearing - firings.theta[direct]))))
    assert np.any(off_axis > math.radians(11.25) + 0.01)
    heard = echoes.kind != NO_ECHO
    assert np.all((echoes.range[heard] >= robot.min_range)
                  & (echoes.range[heard] <= robot.max_range))


def test_same_seed_same_echoes_whatever_the_batching(monkeypatch: pytest.MonkeyPatch, room: World,
                                                     random_firings: RandomFirings) -> None:
    robot = load_robot("scout2")
    firings = random_firings(400, 4, robot)
    runs = [fire_sonars(room, robot, firings, AMPLITUDE, np.random.default_rng(s))
            for s in (1, 1, 2)]
    np.testing.assert_array_equal(runs[0].kind, runs[1].kind)
    np.testing.assert_array_equal(runs[0].range, runs[1].range)
    assert not np.array_equal(runs[0].range, runs[2].range, equal_nan=True)
    monkeypatch.setattr(tracing, "_CHUNK_FIRINGS", 37)
    rebatched = fire_sonars(room, robot, firings, AMPLITUDE, np.random.default_rng(1))
    np.testing.assert_array_equal(runs[0].kind, rebatched.kind)
    np.testing.assert_array_equal(runs[0].range, rebatched.range)


def test_the_two_models_hear_differently(room: World, random_firings: RandomFirings) -> None:
    robot = load_robot("scout2")
    firings = random_firings(400, 6, robot)
    specular = fire_sonars(room, robot, firings, SonarPhysics(),
                           np.random.default_rng(3))
    amplitude = fire_sonars(room, robot, firings, replace(
        SonarPhysics(), echo_model="amplitude"), np.random.default_rng(3))
    assert not np.array_equal(specular.range, amplitude.range, equal_nan=True)


@pytest.mark.parametrize(
    "change",
    [{"frequency": 0.0}, {"transducer_radius": -0.01}, {"absorption_db_per_m": -1.0},
     {"reflectivity": 1.5}, {"diffuse_fraction": -0.1}, {"null_depth_db": 3.0},
     {"detection_range": 0.0}, {"noise_db": float("nan")}, {"fan_rays": 0},
     {"fan_half_angle": 2.0}],
)
def test_bad_amplitude_parameters_are_refused(change: dict[str, float]) -> None:
    with pytest.raises(SonarPhysicsError, match=next(iter(change))):
        AmplitudeModel(**change)  # type: ignore[arg-type]
