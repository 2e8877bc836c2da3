""":mod:`sonarcarve.lab.demo.costmaps`: the demo's grids, measured against the true walls.

The grid table's precision and recall are checked against an oracle written here from the
definitions (exact cell squares against the wall segments with shapely, one cell at a time), on
the map the demo *wrote* (its PGM, parsed here byte by byte), so the table, the files and the
truth have to agree. The oracle itself is first checked on a 4 x 4 case worked out by hand.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest
import shapely

from sonarcarve.lab.demo import (
    GRID_KINDS,
    DemoResult,
    GridSummary,
    free_verdict,
    grid_files,
    grid_table_rows,
    grid_verdict,
    run_demo,
    write_demo_outputs,
)
from sonarcarve.lab.demo.table import grid_caption
from sonarcarve.lab.grid_measures import GridMeasures
from sonarcarve.sim.sonar import EchoKind
from sonarcarve.sim.world import World

Cells = npt.NDArray[np.int8]

#: A room whose walls lie off the cell lines of the 0.07 m grid (origin 0.5 m outside the
#: walls' box; every wall 7.14, 42.81, 79.24, 28.27 or 50.23 cells from it), so that "the cells
#: a wall passes through" has one answer (a wall on a cell line made the oracle and the demo
#: disagree): a short straight drive past a partition wall.
ROOM = World(
    segments=np.array([
        [0.013, 0.021, 5.06, 0.021], [5.06, 0.021, 5.06, 3.037],
        [5.06, 3.037, 0.013, 3.037], [0.013, 3.037, 0.013, 0.021],
        [2.51, 0.021, 2.51, 1.5],  # partition from the bottom wall, ends 0.8 m below the path
    ]),
    name="test-room", tour=np.array([[1.0, 2.3], [4.0, 2.3]]),
)
RESOLUTION = 0.07


def read_pgm(path: Path) -> npt.NDArray[np.uint8]:
    """Pixels of a binary PGM, top row first, parsed here (not with the library's reader)."""
    data = path.read_bytes()
    magic, cols, rows, maxval, body = data.split(maxsplit=4)
    assert (magic, maxval) == (b"P5", b"255")
    pixels = np.frombuffer(body, dtype=np.uint8)
    assert pixels.size == int(cols) * int(rows)
    return pixels.reshape(int(rows), int(cols))


def cells_from_pgm(path: Path) -> Cells:
    """map_saver's trinary image back to 100 / 0 / -1, row 0 the bottom."""
    pixels = read_pgm(path)[::-1]
    return np.select([pixels == 0, pixels == 254], [100, 0], -1).astype(np.int8)


def _block_boxes(rows: npt.ArrayLike, cols: npt.ArrayLike, origin: tuple[float, float],
                 h: float, reach: int) -> npt.NDArray[np.object_]:
    """Squares of the (2 reach + 1)-cell blocks centred on cells ``(rows, cols)``."""
    r, c = np.asarray(rows), np.asarray(cols)
    return shapely.box(origin[0] + (c - reach) * h, origin[1] + (r - reach) * h,
                       origin[0] + (c + reach + 1) * h, origin[1] + (r + reach + 1) * h)


def exact_precision_recall(cells: Cells, origin: tuple[float, float], h: float,
                           segments: npt.ArrayLike,
                           reflections: npt.ArrayLike) -> tuple[float, float]:
    """Occupied precision and recall from their definitions.

    precision: occupied cells whose 3 x 3 block meets a wall; recall: of the wall cells
    (squares a wall meets) whose 3 x 3 block holds a cell with a reflection point in it, the
    share whose 3 x 3 block holds an occupied cell.
    """
    walls = shapely.union_all(shapely.linestrings(
        np.asarray(segments, dtype=np.float64).reshape(-1, 2, 2)))
    occ_r, occ_c = np.nonzero(cells == 100)
    precise = shapely.intersects(_block_boxes(occ_r, occ_c, origin, h, 1), walls)
    every_r, every_c = np.indices(cells.shape).reshape(2, -1)
    on_wall = shapely.intersects(_block_boxes(every_r, every_c, origin, h, 0), walls)
    occupied = set(zip(occ_r.tolist(), occ_c.tolist(), strict=True))
    refl = np.asarray(reflections, dtype=np.float64).reshape(-1, 2)
    hit = {(math.floor((y - origin[1]) / h), math.floor((x - origin[0]) / h))
           for x, y in refl.tolist()}
    seen = marked = 0
    for r, c in zip(every_r[on_wall].tolist(), every_c[on_wall].tolist(), strict=True):
        block = {(r + dr, c + dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1)}
        if block & hit:
            seen += 1
            marked += bool(block & occupied)
    return float(np.mean(precise)), marked / seen


def test_the_oracle_on_a_case_worked_by_hand() -> None:
    # 1 m cells, 4 x 4, a wall along y = 1.5 (row 1, every column). Occupied: (1, 3) on the
    # wall, (3, 0) two rows above it: precision 1/2. Echoes at (0.5, 1.5) and (3.5, 1.5) hit
    # cells (1, 0) and (1, 3), so all four wall cells were seen; (1, 3) marks the two of them
    # next to it, (3, 0) none: recall 2/4.
    cells = np.full((4, 4), -1, dtype=np.int8)
    cells[1, 3] = cells[3, 0] = 100
    precision, recall = exact_precision_recall(
        cells, (0.0, 0.0), 1.0, [[0.2, 1.5, 3.8, 1.5]], [[0.5, 1.5], [3.5, 1.5]])
    assert (precision, recall) == (0.5, 0.5)


@pytest.fixture(scope="module")
def room() -> DemoResult:
    return run_demo(ROOM, seed=0, methods=("carve",), grid_resolution=RESOLUTION)


def test_grid_table_is_the_written_maps_against_the_true_walls(room: DemoResult,
                                                              tmp_path: Path) -> None:
    written = {p.name: p for p in write_demo_outputs(room, tmp_path)}
    truth = room.simulation.truth
    reflections = truth.reflection[truth.kind == EchoKind.DIRECT]
    assert len(reflections) > 50
    _, rows = grid_table_rows(room)
    assert [g.kind for g in room.grids] == [k.kind for k in GRID_KINDS]
    for grid, cells_row in zip(room.grids, rows, strict=True):
        yaml_name, pgm_name = grid_files(grid)
        cells = cells_from_pgm(written[pgm_name])
        assert yaml_name in written
        # The grid covers the walls plus 0.5 m, from its lower-left corner.
        assert grid.origin == pytest.approx((0.013 - 0.5, 0.021 - 0.5))
        assert cells.shape == (math.ceil((3.037 - 0.021 + 1.0) / RESOLUTION - 1e-9),
                               math.ceil((5.06 - 0.013 + 1.0) / RESOLUTION - 1e-9))
        assert np.count_nonzero(cells == 100) == grid.measures.occupied_cells > 0
        precision, recall = exact_precision_recall(cells, grid.origin, RESOLUTION,
                                                   ROOM.segments, reflections)
        assert grid.measures.precision == pytest.approx(precision, abs=1e-12)
        assert grid.measures.recall == pytest.approx(recall, abs=1e-12)
        assert cells_row[1:3] == [f"{precision:.2f}", f"{recall:.2f}"]
        assert 0.0 < grid.cpu_us_per_reading < math.inf


def test_a_demo_without_grids_writes_none(tmp_path: Path) -> None:
    result = run_demo(ROOM, seed=0, methods=("centerline",), grid_resolution=None)
    assert result.grids == ()
    names = [p.name for p in write_demo_outputs(result, tmp_path)]
    assert not [n for n in names if n.endswith((".pgm", ".yaml"))]
    assert "fig5-occupancy-grids.png" not in names


def _with_measures(result: DemoResult, carved: tuple[float, float],
                   layer: tuple[float, float]) -> DemoResult:
    """``result`` with its two grids' precision and recall replaced."""
    grids = tuple(dataclasses.replace(g, measures=GridMeasures(p, r, 0.0, 0.5, 10))
                  for g, (p, r) in zip(result.grids, (carved, layer), strict=True))
    return dataclasses.replace(result, grids=grids)


@pytest.mark.parametrize(("carved", "layer", "words"), [
    ((0.83, 0.954), (0.67, 0.947), "the carved grid is better: it is more precise "
     "(precision 0.83 against 0.67) and finds as much of the walls (recall 0.95 against 0.95)"),
    ((0.60, 0.80), (0.70, 0.90), "ROS's layer is better: the carved grid is less precise"),
    ((0.90, 0.70), (0.80, 0.80), "neither grid is better on both: the carved grid is more "
     "precise (precision 0.90 against 0.80) but finds less of the walls"),
    ((0.801, 0.7), (0.799, 0.7), "the two grids are as good"),
])
def test_the_verdict_says_which_grid_is_better(room: DemoResult, carved: tuple[float, float],
                                               layer: tuple[float, float], words: str) -> None:
    assert grid_verdict(_with_measures(room, carved, layer)).startswith(words)


@pytest.mark.parametrize(("carved", "layer", "words"), [
    (0.935, 0.970, "ROS's layer marks more of the floor near the path free (97 against 94 %)"),
    (0.80, 0.55, "the carved grid marks more of the floor near the path free (80 against 55 %)"),
    (0.801, 0.799, "both grids mark as much of the floor near the path free (80 against 80 %)"),
])
def test_the_free_verdict_says_which_grid_frees_more(room: DemoResult, carved: float,
                                                     layer: float, words: str) -> None:
    grids = tuple(dataclasses.replace(g, measures=GridMeasures(0.9, 0.9, 0.0, 0.5, 10, free))
                  for g, free in zip(room.grids, (carved, layer), strict=True))
    result = dataclasses.replace(room, grids=grids)
    assert free_verdict(result) == words
    assert grid_caption(result).endswith(words[0].upper() + words[1:] + ".")
    nan = tuple(dataclasses.replace(g, measures=GridMeasures(0.9, 0.9, 0.0, 0.5, 10))
                for g in room.grids)
    assert free_verdict(dataclasses.replace(room, grids=nan)) == ""


def test_grid_summary_as_dict_is_json_ready(room: DemoResult) -> None:
    nan = dataclasses.replace(room.grids[0], measures=GridMeasures(math.nan, 1.0, 0.0, 1.0, 0))
    row = GridSummary.as_dict(nan)
    assert row["precision"] is None
    assert (row["rows"], row["columns"]) == nan.cells.shape
