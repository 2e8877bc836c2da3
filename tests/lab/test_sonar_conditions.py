"""``benchmarks/sonar_conditions.py``'s sonars: what each condition changes, and only that.

Expected values are worked by hand: the remedy's ε from σ, the piston's first null from the
first zero of J1 (3.8317) and the default transducer's 12.74° null (its docstring), the Scout2's
numbers from its YAML.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from sonarcarve import MethodConfig
from sonarcarve.lab.scenarios import Scenario
from sonarcarve.readings import ReadingBatch
from sonarcarve.robot import load_robot
from sonarcarve.sim.amplitude import AmplitudeModel, directivity_db

J1_FIRST_ZERO = 3.8317  # tables of Bessel function zeros
DEFAULT_NULL_DEG = 12.74  # AmplitudeModel's docstring: nulls 12.7° off the axis


@pytest.fixture(scope="module")
def conditions(benchmark_script: Callable[[str], ModuleType]) -> ModuleType:
    """``benchmarks/sonar_conditions.py`` as a module."""
    return benchmark_script("sonar_conditions")


def _condition(module: ModuleType, label: str) -> object:
    return next(c for c in module.CONDITIONS if c.label == label)


@pytest.mark.parametrize(("sigma", "epsilon"), [(0.01, 0.05), (0.03, 0.06), (0.05, 0.10)])
def test_the_remedy_is_the_default_epsilon_or_two_sigma(conditions: ModuleType, sigma: float,
                                                        epsilon: float) -> None:
    assert conditions.remedy_tolerance(sigma) == pytest.approx(epsilon)


def test_the_default_beam_keeps_the_default_piston(conditions: ModuleType) -> None:
    assert conditions.piston_for_beam(22.5) == AmplitudeModel()


@pytest.mark.parametrize(("beam_deg", "fan_deg", "rays"), [(15.0, 20.0, 41), (45.0, 60.0, 121)])
def test_a_wider_beam_is_a_smaller_piston_with_its_null_moved_in_proportion(
        conditions: ModuleType, beam_deg: float, fan_deg: float, rays: int) -> None:
    model = conditions.piston_for_beam(beam_deg)
    null = math.radians(DEFAULT_NULL_DEG * beam_deg / 22.5)
    assert model.ka(343.0) * math.sin(null) == pytest.approx(J1_FIRST_ZERO, rel=1e-3)
    # The null itself: the directivity floor (-30 dB); half-way to it, within 6 dB of the axis.
    assert directivity_db(model, [null])[0] == pytest.approx(model.null_depth_db)
    assert directivity_db(model, [0.5 * null])[0] > -6.0
    assert math.degrees(model.fan_half_angle) == pytest.approx(fan_deg)
    assert model.fan_rays == rays


def test_the_quantum_robot_is_the_scout2_but_for_its_range_resolution(
        conditions: ModuleType, tmp_path: Path) -> None:
    robot = load_robot(conditions.robot_with_quantum(0.001, tmp_path))
    scout = load_robot("scout2")
    assert robot.range_resolution == 0.001
    assert scout.range_resolution == 0.0254
    assert (robot.n_sensors, robot.max_range, robot.min_range) == (16, 6.477, 0.1524)
    np.testing.assert_array_equal(robot.bearing, scout.bearing)
    np.testing.assert_array_equal(robot.beam_width, scout.beam_width)


def test_the_defaults_are_the_other_benchmarks_simulations(conditions: ModuleType,
                                                           tmp_path: Path) -> None:
    defaults = _condition(conditions, "defaults")
    assert conditions.scenario("office", 1, "specular", defaults, tmp_path) == Scenario("office", 1)
    assert (conditions.scenario("office", 1, "amplitude", defaults, tmp_path)
            == Scenario("office", 1, physics=(("echo_model", "amplitude"),)))
    assert conditions.method_config(defaults) == MethodConfig()


def test_each_condition_changes_the_simulator_and_tells_the_methods(conditions: ModuleType,
                                                                    tmp_path: Path) -> None:
    beam = _condition(conditions, "beam 45°")
    specular = conditions.scenario("office", 0, "specular", beam, tmp_path)
    assert specular.beam_width_deg == 45.0
    assert specular.physics == ()
    amplitude = conditions.scenario("office", 0, "amplitude", beam, tmp_path)
    assert dict(amplitude.physics)["amplitude"] == conditions.piston_for_beam(45.0)
    assert conditions.method_config(beam).beam_width == pytest.approx(math.radians(45.0))
    noise = _condition(conditions, "noise σ 5 cm")
    assert dict(conditions.scenario("office", 0, "specular", noise, tmp_path).physics) == {
        "range_noise": 0.05}
    assert conditions.method_config(noise) == MethodConfig()  # the remedy rows widen ε
    quantum = _condition(conditions, "quantum 1 mm")
    robot = conditions.scenario("office", 0, "specular", quantum, tmp_path).robot
    assert load_robot(robot).range_resolution == 0.001
    assert conditions.method_config(quantum).range_resolution == 0.001


def test_the_told_beam_reaches_the_methods_not_the_simulator(conditions: ModuleType,
                                                             tmp_path: Path) -> None:
    told = _condition(conditions, "beam 45°, told 75°")
    assert conditions.scenario("office", 0, "specular", told, tmp_path).beam_width_deg == 45.0
    amplitude = conditions.scenario("office", 0, "amplitude", told, tmp_path)
    assert dict(amplitude.physics)["amplitude"] == conditions.piston_for_beam(45.0)
    assert conditions.method_config(told).beam_width == pytest.approx(math.radians(75.0))
    readings = ReadingBatch.from_arrays(t=[0.0, 1.0], sensor=[0, 1], x=[0.0, 0.0],
                                        y=[0.0, 0.0], theta=[0.0, 1.0], range=[1.0, 2.0],
                                        beam_width=[math.radians(45.0)] * 2)
    given = conditions.told_readings(readings, told)
    np.testing.assert_allclose(given.beam_width, math.radians(75.0))
    np.testing.assert_array_equal(given.range, readings.range)
    plain = _condition(conditions, "beam 45°")
    assert conditions.told_readings(readings, plain) is readings
