"""Every seeded entry point of the simulator refuses a negative seed with one WorldError line."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from sonarcarve.errors import SonarcarveError
from sonarcarve.robot import load_robot
from sonarcarve.sim import (
    explore,
    follow_waypoints,
    load_world,
    random_world,
    simulate,
    with_localisation_noise,
    with_odometry_drift,
)
from sonarcarve.sim.world import WorldError

_LINE = follow_waypoints(np.array([[0.0, 0.0], [1.0, 0.0]]))

_SEEDED: dict[str, Callable[[int], object]] = {
    "random_world": random_world,
    "load_world": lambda seed: load_world(f"random:{seed}"),
    "explore": lambda seed: explore(load_world("doorway"), 1.0, seed),
    "with_odometry_drift": lambda seed: with_odometry_drift(_LINE, seed),
    "with_localisation_noise": lambda seed: with_localisation_noise(_LINE, seed),
    "simulate": lambda seed: simulate(load_world("doorway"), load_robot("scout2"), _LINE, seed),
}


@pytest.mark.parametrize("name", sorted(_SEEDED))
def test_negative_seed_is_refused(name: str) -> None:
    with pytest.raises(WorldError) as info:
        _SEEDED[name](-1)
    assert isinstance(info.value, SonarcarveError)
    assert str(info.value).endswith("seed must be an integer >= 0, got -1")


def test_seed_zero_is_fine_for_simulate() -> None:
    result = simulate(load_world("doorway"), load_robot("scout2"), _LINE, 0)
    assert result.seed == 0
