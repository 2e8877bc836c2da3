"""Free space measures of a grid (free near the path, walls freed) on hand-made grids: expected
values counted by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.grids import CarvedGrid
from sonarcarve.lab.grid_measures import NEAR_PATH, grid_measures

# 10 x 10 cells of 0.1 m over [0, 1]²; one wall along y = 0.55 (row 5), x from 0 to 1; the robot
# drove along y = 0.25, below it.
GRID = CarvedGrid(0.1, (0.0, 0.0, 1.0, 1.0))
WALL = np.array([[0.0, 0.55, 1.0, 0.55]])
PATH = np.column_stack((np.linspace(0.05, 0.95, 19), np.full(19, 0.25)))
ECHOES = np.column_stack((np.linspace(0.05, 0.45, 5), np.full(5, 0.55)))  # wall columns 0-5 seen
BOUNDS = (0.0, 0.0, 1.0, 1.0)


def _cells() -> np.ndarray:
    cells = np.full(GRID.shape, -1, dtype=np.int8)
    cells[0:4, 0:5] = 0  # half of the robot's side of the wall marked free
    cells[7:10, :] = 0  # the far side too: out of sight, so not counted either way
    cells[5, 2] = 0  # one seen wall cell erased
    cells[5, 8] = 0  # an unseen wall cell marked free: not counted
    return cells


def test_free_near_path_counts_truly_free_cells_in_sight() -> None:
    # Truly free cells in sight of the path: rows 0-3 (row 4 is next to the wall, rows 7-9 lie
    # behind it), 40 cells, all within NEAR_PATH (0.75 m: the farthest, row 0, is 0.2 m away).
    m = grid_measures(GRID, WALL, ECHOES, BOUNDS, cells=_cells(), path=PATH)
    assert NEAR_PATH >= 0.3
    assert m.free_near_path == pytest.approx(20 / 40)


def test_walls_freed_is_the_share_of_seen_wall_cells_marked_free() -> None:
    # Seen wall cells: columns 0-5 of row 5 (echoes at x 0.05-0.45, dilated by one cell).
    m = grid_measures(GRID, WALL, ECHOES, BOUNDS, cells=_cells(), path=PATH)
    assert m.walls_freed == pytest.approx(1 / 6)


def test_without_a_path_free_near_path_is_nan() -> None:
    m = grid_measures(GRID, WALL, ECHOES, BOUNDS, cells=_cells())
    assert math.isnan(m.free_near_path)
    assert m.walls_freed == pytest.approx(1 / 6)


def test_cells_beyond_near_path_are_not_counted() -> None:
    # A path at the grid's top-right corner, with no wall in the way: only cells within
    # NEAR_PATH of (0.95, 0.95) count. Mark exactly those free, by hand, and nothing else.
    corner = np.array([[0.95, 0.95]])
    xs = np.arange(10) * 0.1 + 0.05
    gx, gy = np.meshgrid(xs, xs)
    near = np.hypot(gx - 0.95, gy - 0.95) <= NEAR_PATH
    cells = np.where(near, 0, -1).astype(np.int8)
    m = grid_measures(GRID, np.zeros((0, 4)), np.zeros((0, 2)), BOUNDS, cells=cells, path=corner)
    assert m.free_near_path == pytest.approx(1.0)
    cells[~near] = 0
    cells[near] = -1
    m = grid_measures(GRID, np.zeros((0, 4)), np.zeros((0, 2)), BOUNDS, cells=cells, path=corner)
    assert m.free_near_path == pytest.approx(0.0)
