"""The carved grid's newest-echo mark and side lobes: a near echo may come from past its beam's
edge (values computed by hand from the rule in ``carved.py``'s docstring)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.grids import OCCUPIED, CarvedGrid, CarvedGridParams, GridError, trinary
from sonarcarve.grids.carved import DEFAULT_SPREAD_LENGTH
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch

H = 0.05
BOUNDS = (-0.5, -1.5, 3.5, 1.5)
ROW_Y, FACE_X = 0.025, 1.825
L_HIT = math.log(0.7 / 0.3)  # 0.847
#: An echo at FACE_X spread over the whole 22.5° beam: 0.2 / (1.825 x 0.3927) of a hit.
SPREAD = DEFAULT_SPREAD_LENGTH / (FACE_X * DEFAULT_BEAM_WIDTH) * L_HIT  # 0.236

pytestmark = pytest.mark.usefixtures("carving_alone_under_the_grid")


def _cell(grid: CarvedGrid, x: float, y: float) -> tuple[int, int]:
    xs, ys = grid.cell_centers()
    return int(np.argmin(np.abs(ys - y))), int(np.argmin(np.abs(xs - x)))


def _ring_hears_nothing(grid: CarvedGrid) -> None:
    """Eight sensors 45° apart at (0, ROW_Y) fire once and hear nothing within 3 m."""
    grid.add_many(ReadingBatch.from_readings(
        Reading(0.1 * k, k, 0.0, ROW_Y, k * math.pi / 4, math.inf, math.nan, 3.0)
        for k in range(8)))


def _surface_past_the_beams_edge(params: CarvedGridParams) -> CarvedGrid:
    """Sensors 1-3, turned 30° up, hear a surface at FACE_X; with a history of one arc each
    pushes the one before out, and sensor 0's echo (below) pushes the third: their band
    (bearings 18.75..41.25°, widened by half a cell, 0.785°) is final at 3 x 0.236 = 0.709 >
    logit(0.65) = 0.619, occupied, wholly outside sensor 0's beam (|bearing| <= 11.25°, 12.03°
    widened) and inside the reach of its side lobes (one more half width: 22.5°, 23.3°
    widened). The ring's free space covers no cell of it (its beams at 0° and 45° end at
    11.25° and begin at 33.75°, and the band's cells below 33.75° are the ones that count)."""
    grid = CarvedGrid(H, BOUNDS, method=make_method("carve", MethodConfig(history_size=1)),
                      params=params)
    _ring_hears_nothing(grid)
    grid.add_many(ReadingBatch.from_readings(
        Reading(1.0 + k, 1 + k, 0.0, ROW_Y, math.radians(30.0), FACE_X) for k in range(3)))
    # Sensor 0 hears the same range straight ahead (its newest echo).
    grid.add(Reading(5.0, 0, 0.0, ROW_Y, 0.0, FACE_X))
    return grid


def test_an_occupied_surface_in_reach_of_a_side_lobe_explains_a_near_echo() -> None:
    grid = _surface_past_the_beams_edge(CarvedGridParams())
    middle = _cell(grid, FACE_X, ROW_Y)
    surface = _cell(grid, 1.725, 0.625)  # 1.8264 m away, bearing 19.2°
    assert grid.log_odds[surface] == pytest.approx(3 * SPREAD, abs=1e-6)
    assert trinary(grid)[surface] == OCCUPIED
    # Its echo may have come from that surface through a side lobe: it gets its spread value,
    # no mark, and the doorway-like middle of its arc stays unsure.
    assert grid.live_log_odds[middle] == pytest.approx(SPREAD)
    assert trinary(grid)[middle] != OCCUPIED


@pytest.mark.parametrize("params", [CarvedGridParams(side_lobes=0.0),
                                    CarvedGridParams(side_lobe_range=1.8)],
                         ids=["no side lobes", "echo beyond side_lobe_range"])
def test_without_side_lobes_or_beyond_their_range_the_echo_is_marked(
        params: CarvedGridParams) -> None:
    # The rule before: nothing on the echo's own band explains it, a whole hit on its middle.
    # Beyond side_lobe_range (1.825 > 1.8 m) the lobes are too weak to have heard anything.
    grid = _surface_past_the_beams_edge(params)
    middle = _cell(grid, FACE_X, ROW_Y)
    assert grid.live_log_odds[middle] == pytest.approx(L_HIT)
    assert trinary(grid)[middle] == OCCUPIED


def test_the_mark_goes_to_a_likely_surface_in_reach_of_a_side_lobe() -> None:
    """The scene of ``test_carved.py::test_the_mark_goes_where_the_map_makes_the_echo_likely_
    when_its_middle_is_not`` with side lobes: the likeliest cells lie past the beam's edge."""
    grid = CarvedGrid(H, BOUNDS)
    _ring_hears_nothing(grid)
    # Sensor 1, turned 20° up, hears something at FACE_X and fires again (backwards): spread
    # only, 0.236 on bearings 8.75..31.25° (widened by 0.785°).
    grid.add(Reading(1.0, 1, 0.0, ROW_Y, math.radians(20.0), FACE_X))
    grid.add(Reading(1.1, 1, 0.0, ROW_Y, math.pi, 0.3))
    # Sensor 0 hears FACE_X straight ahead. Nothing is occupied. On its band the overlap with
    # sensor 1's (7.96..12.03°) holds 0.236 less the ring's faded free space; past its beam's
    # edge (12.03..23.3°, in reach of a side lobe) sensor 1's band holds 0.236 and no free
    # space: likelier. Of those equal cells the one nearest the middle is (1.825, 0.425),
    # bearing atan(0.4 / 1.825) = 12.36°: the whole hit goes around it, ±0.1 / 1.825 rad
    # (3.14°), clipped to the lobe's stretch (11.25..22.5°): 11.25..15.50°, drawn widened by
    # 0.785°: 10.47..16.28°. The arc's own band there holds no spread value to raise: a
    # whole hit is added.
    grid.add(Reading(1.2, 0, 0.0, ROW_Y, 0.0, FACE_X))
    live = grid.live_log_odds
    assert live[_cell(grid, FACE_X, ROW_Y)] == pytest.approx(SPREAD)  # the middle: spread
    in_lobe = _cell(grid, 1.775, 0.475)  # 1.8311 m, 14.23°: sensor 1's band and the mark
    assert live[in_lobe] == pytest.approx(SPREAD + L_HIT)
    assert trinary(grid)[in_lobe] == OCCUPIED
    assert live[_cell(grid, 1.775, 0.575)] == pytest.approx(SPREAD)  # 17.22°: past the mark
    # 9.59°, on both bands (1.8002 m): both spread values, no mark (the rule without side
    # lobes put the mark here).
    assert live[_cell(grid, 1.775, 0.325)] == pytest.approx(2 * SPREAD)
    # 11.15° (1.8092 m): on both bands; the mark starts a cell past the arc's own band, so
    # the echo counts its spread value here and not a whole hit on top of it.
    assert live[_cell(grid, 1.775, 0.375)] == pytest.approx(2 * SPREAD)


def _lobe_scene(sign: float, read_often: bool = False) -> CarvedGrid:
    """The scene above, sensor 1 turned ``sign`` x 20°; read after every reading if
    ``read_often``."""
    grid = CarvedGrid(H, BOUNDS)
    _ring_hears_nothing(grid)
    for reading in (Reading(1.0, 1, 0.0, ROW_Y, sign * math.radians(20.0), FACE_X),
                    Reading(1.1, 1, 0.0, ROW_Y, math.pi, 0.3),
                    Reading(1.2, 0, 0.0, ROW_Y, 0.0, FACE_X)):
        grid.add(reading)
        if read_often:
            grid.refresh()
    return grid


def test_the_mark_in_a_side_lobe_does_not_depend_on_orientation_or_when_the_map_is_read() -> None:
    # Mirror images about the row y = ROW_Y (row 30 of centres -1.475 + 0.05 i; the ring is
    # symmetric too): the lobe cells of sensor 1's band are equally likely (0.236), and the mark
    # goes to the one nearest the middle, whichever side and whatever the scan order (taking the
    # first the scan meets puts it at 12.4° above and at the lobe's far end, -23°, below).
    above, below = _lobe_scene(+1.0).log_odds, _lobe_scene(-1.0).log_odds
    centre = 30
    rows = np.arange(1, above.shape[0])
    np.testing.assert_allclose(above[rows], below[2 * centre - rows], atol=1e-6)
    often = _lobe_scene(+1.0, read_often=True)
    np.testing.assert_allclose(often.log_odds, above, rtol=0.0, atol=1e-6)
    assert np.array_equal(trinary(often), trinary(_lobe_scene(+1.0)))


@pytest.mark.parametrize(("name", "bad"), [
    ("side_lobes", -1.0), ("side_lobes", math.nan), ("side_lobes", math.inf),
    ("side_lobes", True), ("side_lobes", "1"), ("side_lobe_range", -0.5),
    ("side_lobe_range", math.nan), ("side_lobe_range", False), ("side_lobe_range", "2")])
def test_side_lobe_parameters_must_be_numbers_in_range(name: str, bad: object) -> None:
    with pytest.raises(GridError, match=name):
        CarvedGridParams(**{name: bad})  # type: ignore[arg-type]
