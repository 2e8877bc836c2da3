"""Grids by name (:func:`~sonarcarve.grids.make_grid`) and a log's extent
(:func:`~sonarcarve.grids.readings_extent`), what ``sonarcarve grid`` builds on."""

from __future__ import annotations

import math

import pytest

import sonarcarve
from sonarcarve.grids import (
    CarvedGrid,
    CarvedGridParams,
    GridError,
    OccupancyGrid,
    RangeSensorLayer,
    RangeSensorLayerParams,
    SonarConeModel,
    make_grid,
    readings_extent,
)
from sonarcarve.readings import Reading, ReadingBatch

BOUNDS = (0.0, 0.0, 2.0, 1.0)


@pytest.mark.parametrize(("name", "cls"), [
    ("carved", CarvedGrid), ("range-sensor-layer", RangeSensorLayer), ("elfes", OccupancyGrid)])
def test_each_name_builds_its_grid(name: str, cls: type) -> None:
    grid = make_grid(name, 0.5, BOUNDS)
    assert type(grid) is cls
    assert grid.shape == (2, 4)
    assert grid.bounds == BOUNDS


def test_params_reach_the_grid() -> None:
    carved = make_grid("carved", 0.5, BOUNDS, CarvedGridParams(fresh_periods=3.0))
    assert isinstance(carved, CarvedGrid)
    assert carved.params.fresh_periods == 3.0
    layer = make_grid("range-sensor-layer", 0.5, BOUNDS, RangeSensorLayerParams(max_range=2.5))
    assert isinstance(layer, RangeSensorLayer)
    assert layer.params.max_range == 2.5


@pytest.mark.parametrize(("call", "message"), [
    (lambda: make_grid("octomap", 0.5, BOUNDS),
     "unknown grid 'octomap'; choose one of carved, range-sensor-layer, elfes"),
    (lambda: make_grid("elfes", 0.5, BOUNDS, CarvedGridParams()),
     "params of the elfes grid must be a SonarConeModel, got CarvedGridParams"),
    (lambda: make_grid("carved", 0.5, BOUNDS, SonarConeModel()),
     "params of the carved grid must be a CarvedGridParams, got SonarConeModel"),
    (lambda: make_grid("elfes", 0.0, BOUNDS), "grid: resolution must be a finite number > 0"),
])
def test_refusals_name_the_parameter(call: object, message: str) -> None:
    with pytest.raises(GridError) as info:
        call()  # type: ignore[operator]
    assert message in str(info.value)
    assert "--" not in str(info.value)  # a parameter, not a command-line flag


def test_the_extent_holds_the_sensors_and_both_beam_edges() -> None:
    # Facing +y from (1, 0), range 2, 90° beam: the edges end at (1 -+ 2 sin 45°, 2 cos 45°),
    # the axis at (1, 2); the sensor itself is the lowest point.
    batch = ReadingBatch.from_readings([
        Reading(0.0, 0, 1.0, 0.0, math.pi / 2, 2.0, math.pi / 2)])
    r = 2.0 * math.sqrt(0.5)
    assert readings_extent(batch) == pytest.approx((1.0 - r, 0.0, 1.0 + r, 2.0))
    assert readings_extent(batch, margin=0.5) == pytest.approx(
        (0.5 - r, -0.5, 1.5 + r, 2.5))


def test_a_no_echo_reading_reaches_its_max_range() -> None:
    batch = ReadingBatch.from_readings([
        Reading(0.0, 0, 0.0, 0.0, 0.0, math.inf, math.radians(10.0), 3.0)])
    assert readings_extent(batch)[2] == pytest.approx(3.0)


def test_the_extent_of_no_readings_or_a_bad_margin_is_refused() -> None:
    with pytest.raises(GridError, match="no readings"):
        readings_extent(ReadingBatch.from_readings([]))
    one = ReadingBatch.from_readings([Reading(0.0, 0, 0.0, 0.0, 0.0, 1.0)])
    with pytest.raises(GridError, match="margin must be a finite number >= 0"):
        readings_extent(one, margin=-1.0)


def test_both_are_public() -> None:
    assert sonarcarve.make_grid is make_grid
    assert sonarcarve.readings_extent is readings_extent
