""":mod:`sonarcarve.lab.demo.doors`: the moment each door is looked at."""

from __future__ import annotations

import numpy as np
import pytest

from sonarcarve.lab.demo import APPROACH_DISTANCE, DEMO_METHODS, DemoResult, run_demo


def _robot_y(result: DemoResult, reading: int) -> float:
    """The robot's y when reading ``reading`` (0-based) was taken."""
    sim = result.simulation
    return float(sim.trajectory.pose_at(sim.readings.t[reading])[1])


def test_doorway_closeup_looks_from_the_approach_distance(doorway: DemoResult) -> None:
    # The tour drives from (0, 0) to (0, 3) straight at the door centred on (0, 4): head-on, and
    # the view is taken at the first reading with the robot past y = 4 - 1.5 = 2.5.
    door = doorway.closeup
    assert door is not None
    assert door.how == "head-on"
    x, y, _ = door.view.robot
    assert x == pytest.approx(0.0, abs=1e-9)
    last = door.view.readings - 1
    assert y == _robot_y(doorway, last)
    assert _robot_y(doorway, last - 1) < 4.0 - APPROACH_DISTANCE <= y
    assert door.distance <= APPROACH_DISTANCE
    assert set(door.view.maps) == set(DEMO_METHODS)
    # The doorway world's local maps at that moment hold only readings already made.
    for local in door.view.maps.values():
        assert np.all(local.reading_id < door.view.readings)


def test_door_driven_through_is_seen_1_5_m_of_driving_before_it() -> None:
    # T junction: up x = 0 from y = 1 to y = 13, turn right, through the opening at x = 1
    # (jambs (1, 12) and (1, 14)). 1.5 m of driving before the crossing is (0, 12.5).
    # The view is the last reading before the robot passes that point.
    result = run_demo("t-junction", seed=0, methods=("centerline",))
    through = [d for d in result.doors if d.how == "through"]
    assert [d.opening for d in through] == [1]
    x, y, _ = through[0].view.robot
    last = through[0].view.readings - 1
    assert x == pytest.approx(0.0, abs=1e-9)
    assert y == _robot_y(result, last)
    assert y <= 12.5 < _robot_y(result, last + 1)
    assert result.closeup is through[0]
