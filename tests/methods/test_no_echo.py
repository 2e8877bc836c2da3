"""No-echo readings (range +inf): free space only, in every method."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.methods import METHODS, make_method
from sonarcarve.methods.carving import CarvingMethod
from sonarcarve.methods.evidence import EvidenceMethod
from sonarcarve.readings import Reading, ReadingBatch

WALL = Reading(0.0, 0, 0.0, 0.0, 0.0, 2.0)  # an echo 2 m ahead
SILENT = Reading(1.0, 1, 0.0, 0.0, 0.1, math.inf, math.nan, 4.0)  # heard nothing up to 4 m
LATER = Reading(2.0, 2, 0.5, 1.0, -0.5, 1.2)


def _batch(readings: list[Reading]) -> ReadingBatch:
    return ReadingBatch.from_readings(readings)


@pytest.mark.parametrize("name", list(METHODS))
def test_a_no_echo_reading_adds_no_point_and_consumes_its_id(name: str) -> None:
    one_by_one = make_method(name)
    for reading in (WALL, SILENT, LATER):
        one_by_one.add(reading)
    in_a_batch = make_method(name)
    in_a_batch.add_many(_batch([WALL, SILENT, LATER]))
    for method in (one_by_one, in_a_batch):
        assert method.readings == 3
        assert method.measures().no_echo == 1
        assert method.history.appended == 2
        assert 1 not in method.local_map().reading_id.tolist()
    a, b = one_by_one.finish(), in_a_batch.finish()
    assert 1 not in a.reading_id.tolist()
    np.testing.assert_array_equal(a.reading_id, b.reading_id)
    np.testing.assert_array_equal(a.xy, b.xy)


@pytest.mark.parametrize("name", ["centerline", "atm"])
def test_centerline_and_atm_ignore_no_echo_readings(name: str) -> None:
    with_silence = make_method(name)
    with_silence.add_many(_batch([WALL, SILENT, LATER]))
    without = make_method(name)
    without.add(WALL, 0)
    without.add(LATER, 2)
    np.testing.assert_array_equal(with_silence.finish().xy, without.finish().xy)


def test_carving_uses_the_beam_up_to_max_range_like_a_reading_of_that_range() -> None:
    silent = CarvingMethod()
    silent.add_many(_batch([WALL, SILENT]))
    echo = CarvingMethod()
    echo.add_many(_batch([WALL, SILENT._replace(range=4.0)]))
    slot = silent.history.slots()[0]
    model, reference = silent.models[0], echo.models[0]
    assert model.carved[slot]
    assert (model.lo[slot], model.hi[slot]) == (reference.lo[slot], reference.hi[slot])
    # Looking past the arc's end carves nothing: the sector stops at max_range - ε.
    short = CarvingMethod()
    short.add_many(_batch([WALL, SILENT._replace(max_range=1.0)]))
    assert not short.models[0].carved[slot]


def test_a_no_echo_reading_straight_through_an_arc_removes_it() -> None:
    method = make_method("carve")
    method.add_many(_batch([WALL, SILENT._replace(theta=0.0)]))
    assert len(method.local_map().xy) == 0
    assert method.measures().fully_carved == 1


def test_evidence_gains_free_space_evidence() -> None:
    method = EvidenceMethod(min_confidence=0.0)
    method.add(WALL)
    slot = method.history.slots()[0]
    model = method.models[0]
    before = model.free[slot].copy()
    method.add(SILENT._replace(theta=0.0))
    assert np.all(model.free[slot] >= before)
    assert model.free[slot].sum() > before.sum()
    assert model.touched[slot]
