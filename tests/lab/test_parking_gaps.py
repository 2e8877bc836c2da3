"""``benchmarks/parking.py``'s parking question: a gap's free length read from a hand-made map.

Expected values are the car park's lengths as designed (``benchmarks/car_park.py``'s layout:
gaps of 0.8, 6.0, 1.0, 4.5 and 0.9 m in the parallel row, an empty 2.5 m bay leaving 3.2 m
between car sides) and sums done by hand, not values computed by the code under test.
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType

import numpy as np
import pytest

from sonarcarve.grids import CarvedGrid


@pytest.fixture(scope="module")
def parking(benchmark_script: Callable[[str], ModuleType]) -> ModuleType:
    """``benchmarks/parking.py`` as a module."""
    return benchmark_script("parking")


def _outline_points(segments: np.ndarray, step: float = 0.05) -> np.ndarray:
    """Points every ``step`` metres along every wall: a perfect point map."""
    out = []
    for x1, y1, x2, y2 in segments:
        n = max(1, int(np.ceil(np.hypot(x2 - x1, y2 - y1) / step)))
        s = np.linspace(0.0, 1.0, n + 1)[:, None]
        out.append(np.hstack((x1 + s * (x2 - x1), y1 + s * (y2 - y1))))
    return np.vstack(out)


def test_the_layout_has_the_gaps_it_was_designed_with(parking: ModuleType) -> None:
    lengths = [round(g.length, 9) for g in parking.all_gaps()]
    assert lengths[:5] == [0.8, 6.0, 1.0, 4.5, 0.9]  # the parallel row, west to east
    assert lengths[5:] == [0.7] * 5 + [3.2] + [0.7] * 8  # bays of 2.5 m, 1.8 m cars, bay 6 empty


def test_a_perfect_map_reads_every_gap_exactly(parking: ModuleType) -> None:
    points = _outline_points(parking.car_park.segments())
    expected = [0.8, 6.0, 1.0, 4.5, 0.9] + [0.7] * 5 + [3.2] + [0.7] * 8
    read = [parking.read_gap(g, points=points) for g in parking.all_gaps()]
    np.testing.assert_allclose(read, expected, atol=1e-9)


def test_an_empty_map_reads_the_gap_one_reach_long_past_each_car(parking: ModuleType) -> None:
    slot = parking.all_gaps()[1]  # 10.8 .. 16.8
    assert parking.read_gap(slot, points=np.zeros((0, 2))) == pytest.approx(6.0 + 2 * 1.0)


def test_points_in_the_gap_shorten_it_and_points_off_the_row_do_not(
        parking: ModuleType) -> None:
    slot = parking.all_gaps()[1]  # the 6 m slot, 10.8 .. 16.8 on the lane side y = 3.0
    ends = np.array([[10.8, 3.0], [16.8, 3.0]])
    assert parking.read_gap(slot, points=ends) == pytest.approx(6.0)
    # A smeared echo 2.2 m into the gap: the longest free stretch is 16.8 - 13.0 = 3.8 m.
    assert parking.read_gap(slot, points=np.vstack((ends, [[13.0, 2.5]]))) == pytest.approx(3.8)
    # The kerb behind the slot (y 1.0, the row's band starts at y 1.5) and a point in the lane
    # (y 3.5, the band ends 0.3 m into it, at 3.3) leave the slot whole.
    off_row = np.vstack((ends, [[13.0, 1.0], [14.0, 3.5]]))
    assert parking.read_gap(slot, points=off_row) == pytest.approx(6.0)
    # Only one car end seen (the east one): the stretch runs on 1 m into the west car.
    assert parking.read_gap(slot, points=ends[1:]) == pytest.approx(7.0)


def test_slot_judgement_needs_5_2_m_parallel_and_2_4_m_perpendicular(
        parking: ModuleType) -> None:
    gaps = parking.all_gaps()
    assert parking.slot_needed(gaps[1]) == 5.2
    assert parking.slot_needed(gaps[10]) == 2.4  # the empty bay


def test_grid_cells_block_the_gap_where_their_squares_project(parking: ModuleType) -> None:
    slot = parking.all_gaps()[1]
    grid = CarvedGrid(0.1, (0.0, 0.0, 52.0, 24.0))
    cells = np.zeros(grid.shape, dtype=np.int8)  # all free
    cells[29, 107] = 100  # x 10.7-10.8, y 2.9-3.0: the west car's lane-side corner
    cells[29, 168] = 100  # x 16.8-16.9: the east car's
    assert parking.read_gap(slot, grid=grid, cells=cells) == pytest.approx(6.0)
    cells[25, 130] = 100  # x 13.0-13.1, y 2.5-2.6, in the gap: 16.8 - 13.1 = 3.7 m left
    assert parking.read_gap(slot, grid=grid, cells=cells) == pytest.approx(3.7)
    cells[25, 130] = 0
    cells[12, 130] = 100  # y 1.2-1.3: below the row's band (1.5 .. 3.3), does not block
    cells[29, 140] = -1  # unknown does not block
    assert parking.read_gap(slot, grid=grid, cells=cells) == pytest.approx(6.0)


def test_the_checked_in_world_file_is_the_layout(parking: ModuleType) -> None:
    from sonarcarve.sim.world import load_world

    world = load_world(parking.car_park.WORLD_FILE)
    np.testing.assert_array_equal(world.segments, parking.car_park.segments())
    assert world.tour is not None
    np.testing.assert_array_equal(world.tour, [[3.0, 4.9], [47.5, 4.9], [47.5, 21.0]])
