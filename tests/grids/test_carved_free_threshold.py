"""Where the carved grid calls a cell free: below 0.35 (as much evidence as "occupied" needs,
mirrored), not map_saver's 0.196, which left most of a corridor unknown."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.grids import FREE, UNKNOWN, CarvedGrid, CarvedGridParams, trinary
from sonarcarve.grids.carved import DEFAULT_FREE_THRESHOLD
from sonarcarve.readings import Reading

BOUNDS = (-0.5, -1.0, 3.0, 1.0)


def _grid(params: CarvedGridParams | None = None) -> CarvedGrid:
    """Three echoes at 2 m straight ahead from the same pose (0, 0), 0.2 s apart."""
    grid = CarvedGrid(0.1, BOUNDS, params=params)
    for t in (0.0, 0.2, 0.4):
        grid.add(Reading(t, 0, 0.0, 0.0, 0.0, 2.0, math.radians(22.5)))
    return grid


def _cell(grid: CarvedGrid, x: float, y: float) -> tuple[int, int]:
    xs, ys = grid.cell_centers()
    return int(np.argmin(np.abs(ys - y))), int(np.argmin(np.abs(xs - x)))


def test_threshold_mirrors_the_occupied_one() -> None:
    # logit(0.35) = -logit(0.65): the same amount of evidence either way.
    params = CarvedGridParams()
    assert DEFAULT_FREE_THRESHOLD == params.free_threshold == pytest.approx(0.35)
    assert math.log(params.free_threshold / (1 - params.free_threshold)) == pytest.approx(
        -math.log(params.occupied_threshold / (1 - params.occupied_threshold)))


def test_three_misses_make_a_cell_free() -> None:
    # The cell 0.65 m ahead on the axis: each beam's free space gives it at most logit(0.4) =
    # -0.405 (on the axis, before the fade), so three give at least -1.22 > logit(0.196) = -1.41:
    # never free under map_saver's threshold; with the 0.35 threshold it is free once the three
    # beams' evidence passes -0.62 (p < 0.35).
    grid = _grid()
    row, col = _cell(grid, 0.65, 0.0)
    p = grid.probabilities()[row, col]
    assert 0.196 < p < 0.35
    assert trinary(grid)[row, col] == FREE
    assert trinary(_grid(CarvedGridParams(free_threshold=0.196)))[row, col] == UNKNOWN
