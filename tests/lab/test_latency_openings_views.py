"""``benchmarks/latency_openings.py --hold-back``: the live view that holds back the points of
uncut beams with a wide bound (Fig. 13's max-error thresholding on the local map), measured as
a view of a recorded run."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from types import ModuleType

import numpy as np
import pytest

from sonarcarve.lab.instrument import record_run
from sonarcarve.maps import PointSource
from sonarcarve.methods import make_method
from sonarcarve.readings import Reading, ReadingBatch

PHI = math.radians(22.5)


@pytest.fixture(scope="module")
def script(benchmark_script: Callable[[str], ModuleType]) -> ModuleType:
    """``benchmarks/latency_openings.py`` as a module."""
    return benchmark_script("latency_openings")


def test_only_uncut_points_over_the_bound_are_held(script: ModuleType) -> None:
    source = [PointSource.CENTERLINE, PointSource.CENTERLINE, PointSource.CARVED,
              PointSource.ATM]
    bound = [0.30, 0.10, 0.30, 0.30]
    assert script.live_held_back(source, bound, 0.2).tolist() == [True, False, False, False]
    assert script.live_held_back(source, bound, 0.2, uncut_only=False).tolist() == [
        True, False, True, True]


def _far_and_near() -> ReadingBatch:
    # An echo at 3 m and one at 1 m, nothing looking through either: both uncut, bounds
    # 2 r sin(e/2) with e = φ/2 plus half a bin (eq. 5.3, binned ends): 0.61 and 0.20 m.
    return ReadingBatch.from_readings([
        Reading(t=0.0, sensor=0, x=0.0, y=0.0, theta=0.0, range=3.0, beam_width=PHI),
        Reading(t=0.01, sensor=1, x=0.0, y=0.0, theta=math.pi, range=1.0, beam_width=PHI)])


def test_a_held_view_hides_the_far_uncut_point_and_keeps_the_rest(script: ModuleType) -> None:
    record = record_run(_far_and_near(), make_method("evidence"), [2])
    held = script._held(record, 0.4, True)
    base = record.local_map(0)
    assert sorted(base.reading_id.tolist()) == [0, 1]
    assert held.local_map(0).reading_id.tolist() == [1]
    assert held.global_map is record.global_map  # the committed map is not a view
    unchanged = [f.name for f in dataclasses.fields(held.samples) if f.name != "alive"]
    for name in unchanged:
        assert np.array_equal(getattr(held.samples, name), getattr(record.samples, name))
