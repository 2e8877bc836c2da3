"""Grid measures against truth, on hand-made grids (expected values counted by hand)."""

from __future__ import annotations

import numpy as np
import pytest

from sonarcarve.grids import CarvedGrid
from sonarcarve.lab.grid_measures import dilate, grid_free_width, grid_measures, wall_cells
from sonarcarve.lab.metrics import gap_region

# 10 x 10 cells of 0.1 m over [0, 1]²; one wall along y = 0.55 (row 5), x from 0 to 1.
GRID = CarvedGrid(0.1, (0.0, 0.0, 1.0, 1.0))
WALL = np.array([[0.0, 0.55, 1.0, 0.55]])


def test_wall_cells_and_dilation() -> None:
    walls = wall_cells(WALL, GRID.shape, (0.0, 0.0), 0.1)
    assert walls.sum() == 10
    assert walls[5].all()
    near = dilate(walls)
    assert near[4:7].all()
    assert near.sum() == 30


def test_precision_recall_phantoms_and_coverage() -> None:
    cells = np.full(GRID.shape, -1, dtype=np.int8)
    cells[5, 0:4] = 100  # on the wall: right
    cells[6, 8] = 100  # one cell off the wall: still right
    cells[1, 1] = 100  # a phantom
    # Direct echoes saw the wall at x = 0.05 .. 0.45 only (cells 0-4, and 5 by dilation).
    reflections = np.column_stack((np.linspace(0.05, 0.45, 5), np.full(5, 0.55)))
    m = grid_measures(GRID, WALL, reflections, (0.0, 0.0, 1.0, 1.0), cells=cells)
    assert m.occupied_cells == 6
    assert m.precision == pytest.approx(5 / 6)
    # Seen wall cells: columns 0-5; an occupied cell within one cell: columns 0-4.
    assert m.recall == pytest.approx(5 / 6)
    # Truly free: the 70 cells more than a cell from the wall; one is occupied.
    assert m.phantoms == pytest.approx(1 / 70)
    # Wall samples every 0.025 m; seen: the 28 at x = 0 .. 0.675 (within 0.25 m of an echo,
    # 0.70 falls just outside in floating point); covered: the 20 with x < 0.5 (columns 0-4).
    assert m.wall_covered == pytest.approx(20 / 28)


def test_free_width_of_an_opening() -> None:
    region = gap_region([0.0, 0.55], [1.0, 0.55], 0.15)
    cells = np.zeros(GRID.shape, dtype=np.int8)  # all free
    assert grid_free_width(GRID, region, cells=cells) == pytest.approx(1.0)
    cells[5, 3] = 100  # blocks x in [0.3, 0.4]
    cells[7, 8] = 100  # centre 0.2 m off the line: its square reaches 0.15 m, the depth
    assert grid_free_width(GRID, region, cells=cells) == pytest.approx(0.4)
    cells[7, 8] = 0
    assert grid_free_width(GRID, region, cells=cells) == pytest.approx(0.6)
    cells[5, 8] = -1  # unknown blocks only the strict reading
    assert grid_free_width(GRID, region, cells=cells) == pytest.approx(0.6)
    assert grid_free_width(GRID, region, strict=True, cells=cells) == pytest.approx(0.4)
