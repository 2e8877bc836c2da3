"""Where the spread map changed since the last read, by tiles of cells: what lets a read skip
judging again a fresh arc whose reach nothing touched (``docs/carved-grid.md``, "Reading the
map").

A tile is :data:`TILE` x :data:`TILE` cells. Everything that writes ``base``, ``live`` or
``heard`` (the fold's free space and final bands, the live arcs' redraws and retirements) marks
the tiles of the cells it may have changed (:func:`mark_cells`; a band marks each row's stretch of
the ring it scans, the free space each cell whose value changed); a read judges the fresh arcs
and then starts a new round of marks (:func:`next_read`). The judgment of a fresh arc
(:func:`~sonarcarve.grids.carved.mark.refresh_points`) reads those three arrays only inside its
reach box (:func:`~sonarcarve.grids.carved.mark.reach_box`), and the live arcs' records only where
their bands (drawn in ``live``, so marked) cross it: an arc with the same interval and weight
whose box meets no marked tile would be judged to the same mark, bit for bit.

A tile holds the number of the read its last mark was made for; the grid's last row holds the
current read's number: a tile is marked when it holds that number, so a new round costs one
addition, where clearing every tile cost 5-10 µs a read at 0.05 m on the office (135,000
tiles).

Measured (office, seed 0, a read every 5 readings): of 13 fresh arcs judged a read, 8 were judged
at the read before with the same interval and weight, and 6.7-7.0 of those had no cell of their
box changed; tiles of 4 cells keep 6.3-6.8 of them, of 8 cells 5.6-6.5, of 16 cells 4.2-5.8.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled_inline

__all__ = [
    "TILE",
    "TILE_SHIFT",
    "Tiles",
    "any_marked",
    "mark_cells",
    "marked",
    "next_read",
    "tile_grid",
]

#: log2 of a tile's side in cells.
TILE_SHIFT = 2
#: A tile's side, cells.
TILE = 1 << TILE_SHIFT

#: Tiles, by tile row and column, then one more row whose first entry is the current read's
#: number (:func:`tile_grid`). A grid of shape (0, 0) records nothing: what the marks' own draws
#: (``points``) pass.
Tiles = npt.NDArray[np.int64]


def tile_grid(shape: tuple[int, int]) -> Tiles:
    """The tiles of a grid of ``shape`` (rows, columns) cells, none marked:
    ``ceil(rows / TILE) + 1`` rows of ``ceil(columns / TILE)``, the read's number 1."""
    ny, nx = shape
    tiles = np.zeros((((ny + TILE - 1) >> TILE_SHIFT) + 1, (nx + TILE - 1) >> TILE_SHIFT),
                     dtype=np.int64)
    tiles[-1, 0] = 1
    return tiles


def marked(tiles: Tiles) -> npt.NDArray[np.bool_]:
    """Which tiles are marked, by tile row and column (for the tests)."""
    return np.asarray(tiles[:-1] == tiles[-1, 0])


@compiled_inline
def mark_cells(tiles: Tiles, i: int, j0: int, j1: int) -> None:
    """Mark the tiles of the cells ``j0..j1`` of row ``i`` (none when ``j0 > j1``, or when
    ``tiles`` records nothing)."""
    if j0 > j1 or tiles.shape[0] == 0:
        return
    read = tiles[tiles.shape[0] - 1, 0]
    row = i >> TILE_SHIFT
    for t in range(j0 >> TILE_SHIFT, (j1 >> TILE_SHIFT) + 1):
        tiles[row, t] = read


@compiled_inline
def any_marked(tiles: Tiles, i0: int, i1: int, j0: int, j1: int) -> bool:
    """Whether a tile of the cells ``i0..i1`` x ``j0..j1`` is marked."""
    read = tiles[tiles.shape[0] - 1, 0]
    for ti in range(i0 >> TILE_SHIFT, (i1 >> TILE_SHIFT) + 1):
        for tj in range(j0 >> TILE_SHIFT, (j1 >> TILE_SHIFT) + 1):
            if tiles[ti, tj] == read:
                return True
    return False


@compiled_inline
def next_read(tiles: Tiles) -> None:
    """Unmark every tile: marks from now on are for the next read."""
    tiles[tiles.shape[0] - 1, 0] += 1
