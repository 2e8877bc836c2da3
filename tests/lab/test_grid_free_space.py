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


def test_a_wall_with_a_gap_blocks_only_where_it_stands() -> None:
    # The wall along y = 0.55 stops at x = 0.45: through the gap (x > 0.45) the cells above it
    # are in sight of the path. Rows 7-9 beyond the gap: columns 6-9 (centres 0.65-0.95, their
    # nearest path points straight below them, the line clear of the wall's end at 0.45);
    # column 5 (centre 0.55) also sees its nearest point (0.55, 0.25) past the end. Truly free:
    # rows 0-3 everywhere (40) and, away from the wall's cells (row 5, columns 0-4, dilated by
    # one: rows 4-6, columns 0-5), rows 4-6 of columns 6-9 (12) and rows 7-9 of columns 5-9
    # (15): 67 cells. Mark exactly rows 7-9 free.
    short = np.array([[0.0, 0.55, 0.45, 0.55]])
    cells = np.full(GRID.shape, -1, dtype=np.int8)
    cells[7:10, :] = 0
    m = grid_measures(GRID, short, np.zeros((0, 2)), BOUNDS, cells=cells, path=PATH)
    assert m.free_near_path == pytest.approx(15 / 67)


def test_only_the_ring_marked_free_counts_its_share() -> None:
    # A path at (0.05, 0.05), no walls: the wanted cells are those within NEAR_PATH (0.75 m) of
    # it. Mark free only the cells between 0.6 and 0.75 m; counted by hand from the centres
    # (0.05 + 0.1 i, 0.05 + 0.1 j): distances 0.1 * hypot(i, j), so the wanted cells have
    # i² + j² <= 56.25: for i = 0..7, j up to 7, 7, 7, 6, 6, 5, 4, 2, that is 8 + 8 + 8 + 7 + 7
    # + 6 + 5 + 3 = 52 cells; the ring 36 < i² + j² <= 56.25 holds 1 + 2 + 2 + 1 + 2 + 2 + 4 + 3
    # = 17 of them.
    corner = np.array([[0.05, 0.05]])
    i, j = np.meshgrid(np.arange(10), np.arange(10))
    d2 = i * i + j * j
    wanted, ring = d2 <= 56.25, (d2 > 36) & (d2 <= 56.25)
    cells = np.where(ring, 0, -1).astype(np.int8)
    m = grid_measures(GRID, np.zeros((0, 4)), np.zeros((0, 2)), BOUNDS, cells=cells, path=corner)
    assert int(wanted.sum()) == 52
    assert int(ring.sum()) == 17
    assert m.free_near_path == pytest.approx(17 / 52)


def test_tiled_crossing_test_agrees_with_every_wall_against_every_segment() -> None:
    # The tiling only skips walls that cannot meet a group's segments: on random segments and
    # walls (many crossing tile borders, some on a lattice) it must give the untiled answer.
    from sonarcarve.lab.grid_measures import _crosses, _crosses_any

    rng = np.random.default_rng(7)
    for tile in (0.1, 0.37, 2.0, 7.0):
        a = rng.uniform(-3.0, 3.0, (400, 2))
        b = a + rng.uniform(-1.5, 1.5, (400, 2))
        walls = np.vstack((rng.uniform(-3.0, 3.0, (40, 4)),
                           np.column_stack((np.arange(-3.0, 3.0, 0.5), np.full(12, -3.0),
                                            np.arange(-3.0, 3.0, 0.5), np.full(12, 3.0)))))
        assert np.array_equal(_crosses_any(a, b, walls, tile=tile), _crosses(a, b, walls))
