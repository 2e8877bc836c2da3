"""No-echo readings (range +inf) in the grids: free space up to max_range, no occupied band."""

from __future__ import annotations

import math

import numpy as np

from sonarcarve.grids import CarvedGrid, OccupancyGrid, RangeSensorLayer, RangeSensorLayerParams
from sonarcarve.readings import Reading, ReadingBatch

BOUNDS = (-0.5, -1.5, 4.5, 1.5)
SILENT = Reading(0.0, 0, 0.0, 0.0, 0.0, math.inf, math.nan, 2.0)


def _p(grid: CarvedGrid | OccupancyGrid | RangeSensorLayer, x: float) -> float:
    xs, ys = grid.cell_centers()
    return float(grid.probabilities()[int(np.argmin(np.abs(ys))), int(np.argmin(np.abs(xs - x)))])


def test_elfes_and_carved_grids_clear_the_beam_up_to_max_range() -> None:
    for grid in (OccupancyGrid(0.1, BOUNDS), CarvedGrid(0.1, BOUNDS)):
        grid.add_many(ReadingBatch.from_readings([SILENT]))
        assert _p(grid, 0.5) < 0.5  # free
        assert _p(grid, 2.5) == 0.5  # beyond max_range: untouched
        assert np.all(grid.probabilities() <= 0.5)  # no occupied band anywhere


def test_an_echo_after_a_no_echo_reading_still_marks() -> None:
    echo = Reading(1.0, 0, 0.0, 0.0, 0.0, 3.0)
    for grid in (OccupancyGrid(0.1, BOUNDS), CarvedGrid(0.1, BOUNDS)):
        grid.add_many(ReadingBatch.from_readings([SILENT, echo, SILENT._replace(t=2.0)]))
        assert _p(grid, 3.0) > 0.5
        assert _p(grid, 1.0) < 0.5


def test_the_layer_follows_ros_for_plus_inf() -> None:
    batch = ReadingBatch.from_readings([SILENT])
    dropped = RangeSensorLayer(0.1, BOUNDS)
    dropped.add_many(batch)
    assert dropped.dropped == 1
    assert dropped.readings == 0
    params = RangeSensorLayerParams(inf_is_max_reading=True, clear_on_max_reading=True,
                                    max_range=2.0)
    clearing = RangeSensorLayer(0.1, BOUNDS, params)
    clearing.add_many(batch)
    assert clearing.readings == 1
    assert _p(clearing, 1.0) < 0.5
    assert np.all(clearing.probabilities() <= 0.5)
