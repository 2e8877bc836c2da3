"""Side lobes, heard from where: a surface in reach of a side lobe explains a near echo, or takes
its mark, only if it was heard from near the bearing of the sensor's ray to it, by an arc that
left the history or by one still live (docs/carved-grid.md, *Side lobes*). Values by hand as in
test_carved_side_lobes.py, whose scenes these reuse."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from sonarcarve.grids import OCCUPIED, CarvedGrid, CarvedGridParams, trinary
from sonarcarve.grids.carved import DEFAULT_SPREAD_LENGTH
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch

H = 0.05
BOUNDS = (-0.5, -1.5, 3.5, 2.5)
ROW_Y, FACE_X = 0.025, 1.825
L_HIT = math.log(0.7 / 0.3)  # 0.847
#: Sensor 0's echo at FACE_X straight ahead, spread over its whole 22.5° beam.
SPREAD = DEFAULT_SPREAD_LENGTH / (FACE_X * DEFAULT_BEAM_WIDTH) * L_HIT  # 0.236
#: A cell of sensor 0's circle past its beam's edge, in reach of its upper side lobe: 1.8264 m
#: from (0, ROW_Y), bearing 19.2° (the nominal beam ends at 11.25°, the lobe at 22.5°).
LOBE_X, LOBE_Y = 1.725, 0.625
#: History long enough that no arc of these scenes leaves it: every arc stays live, and the
#: grid's record of final bands' bearings stays empty.
LONG = MethodConfig(history_size=400)
#: The rule is opt-in (see the last test): these scenes turn it on, one lobe of one half width.
LOBES = CarvedGridParams(side_lobes=1.0)

pytestmark = pytest.mark.usefixtures("carving_alone_under_the_grid")


def _cell(grid: CarvedGrid, x: float, y: float) -> tuple[int, int]:
    xs, ys = grid.cell_centers()
    return int(np.argmin(np.abs(ys - y))), int(np.argmin(np.abs(xs - x)))


def _grid() -> CarvedGrid:
    return CarvedGrid(H, BOUNDS, method=make_method("carve", LONG), params=LOBES)


def test_a_surface_heard_from_near_the_rays_bearing_by_live_arcs_explains_a_near_echo() -> None:
    """Sensors 1-3 at sensor 0's place, turned 30°, hear a surface at FACE_X (live arcs: 3 x
    0.236 = 0.709, occupied) on bearings 18.75..41.25°: cell (LOBE_X, LOBE_Y) was heard from
    19.2°, the bearing of sensor 0's ray to it. Sensor 0's echo at FACE_X straight ahead may
    have come from there through its side lobe: its spread value, no mark (a rule that read
    only the bearings of final bands, written ~20 s later on a tour, marked the middle)."""
    grid = _grid()
    grid.add_many(ReadingBatch.from_readings(
        Reading(1.0 + k, 1 + k, 0.0, ROW_Y, math.radians(30.0), FACE_X) for k in range(3)))
    grid.add(Reading(5.0, 0, 0.0, ROW_Y, 0.0, FACE_X))
    assert trinary(grid)[_cell(grid, LOBE_X, LOBE_Y)] == OCCUPIED
    middle = _cell(grid, FACE_X, ROW_Y)
    assert grid.live_log_odds[middle] == pytest.approx(SPREAD)
    assert trinary(grid)[middle] != OCCUPIED


def _heard_from_above(grid: CarvedGrid, reach: float) -> None:
    """Sensor 5 above the lobe cell, aimed straight down, hears it from ``reach`` metres
    (bearing -90°: across sensor 0's ray at 19.2°, ten bins of 11.25° away) and then fires
    upwards at 0.3 m, so its echo is a spread value, not its newest. At 0.5 m its arc is 0.196
    m long, a whole hit (0.847, occupied); at 1.0 m 0.393 m, 0.431 (likely, not occupied)."""
    grid.add(Reading(1.0, 5, LOBE_X, LOBE_Y + reach, -math.pi / 2, reach))
    grid.add(Reading(1.1, 5, LOBE_X, LOBE_Y + reach, math.pi / 2, 0.3))
    grid.add(Reading(1.2, 0, 0.0, ROW_Y, 0.0, FACE_X))


@pytest.mark.parametrize(("reach", "occupied"), [(0.5, True), (1.0, False)],
                         ids=["occupied: would explain", "likely: would take the mark"])
def test_a_surface_heard_only_across_the_ray_neither_explains_nor_takes_the_mark(
        reach: float, occupied: bool) -> None:
    """The surface in sensor 0's side lobe was heard only from above, across the ray: a wall
    met at that angle does not echo back along the ray, so it does not explain sensor 0's echo
    (occupied) nor draw its mark into the lobe (likely): the mark stays in the middle, a whole
    hit (without the heard condition: the echo's spread value only, 0.236)."""
    grid = _grid()
    _heard_from_above(grid, reach)
    lobe = _cell(grid, LOBE_X, LOBE_Y)
    assert (trinary(grid)[lobe] == OCCUPIED) == occupied
    assert grid.log_odds[lobe] > 0.4
    middle = _cell(grid, FACE_X, ROW_Y)
    assert grid.live_log_odds[middle] == pytest.approx(L_HIT)
    assert trinary(grid)[middle] == OCCUPIED


def _live_corridor(h: float, half_width: float) -> CarvedGrid:
    """Side sensors at y = ROW_Y map both walls of a corridor (y = ±half_width) head-on,
    x = -0.8 .. 3.8, with every arc still live."""
    grid = CarvedGrid(h, (-1.0, -1.5, 4.0, 1.5), method=make_method("carve", LONG),
                      params=LOBES)
    walls, t = [], 0.0
    for k in range(47):
        x = -0.8 + 0.1 * k
        walls.append(Reading(t, 1, x, ROW_Y, math.pi / 2, half_width - ROW_Y))
        walls.append(Reading(t + 0.005, 2, x, ROW_Y, -math.pi / 2, half_width + ROW_Y))
        t += 0.01
    grid.add_many(ReadingBatch.from_readings(walls))
    return grid


def _wall_on_the_band_in_the_beam(grid: CarvedGrid, r: float) -> bool:
    """As in test_carved_side_lobes.py: an occupied cell on the band of an echo at ``r``
    straight ahead, inside the beam widened by half a cell (the map explains it there)."""
    xs, ys = grid.cell_centers()
    dx, dy = xs[None, :], ys[:, None] - ROW_Y
    on_band = np.abs(np.hypot(dx, dy) - r) <= grid.band
    in_beam = np.abs(np.arctan2(dy, dx)) <= DEFAULT_BEAM_WIDTH / 2 + 0.5 * grid.resolution / r
    return bool((on_band & in_beam & (trinary(grid) == OCCUPIED)).any())


@pytest.mark.parametrize("h", [0.05, 0.10])
@pytest.mark.parametrize("half_width", [0.5, 0.6])
def test_walls_heard_by_live_side_sensors_never_hide_an_obstacle_ahead(
        h: float, half_width: float) -> None:
    """test_carved_side_lobes.py's every-range corridor sweep with the walls' arcs still live
    (no final band has recorded where they were heard from): walls heard only from ±90° do not
    explain an echo straight ahead, at any range from 1 to 2 m (the side-lobe rule without the
    heard condition left the obstacle unmarked at 1.07-1.59 m, 0.05 m cells, and at 1.0-1.54 m,
    0.10 m cells, with its walls final; an earlier try that read only final bands' bearings was
    blind to these walls)."""
    walls = _live_corridor(h, half_width)
    assert trinary(walls)[_cell(walls, 1.0, ROW_Y + half_width)] == OCCUPIED
    tested = 0
    for r in np.arange(1.0, 2.0001, 0.01):
        if _wall_on_the_band_in_the_beam(walls, float(r)):
            continue
        grid = copy.deepcopy(walls)
        grid.add(Reading(10.0, 0, 0.0, ROW_Y, 0.0, float(r)))
        assert trinary(grid)[_cell(grid, float(r), ROW_Y)] == OCCUPIED, f"r = {r:.2f} m"
        tested += 1
    assert tested >= 40


def _corridor_heard_diagonally(params: CarvedGridParams) -> CarvedGrid:
    """A 1.0 m corridor (walls y = ±0.5, 0.05 m cells) whose walls are heard, every 0.1 m from
    x = -0.8 to 3.8, by side sensors (±90°, head-on) and by sensors turned ±22.5°, at the nearest
    point of the wall in their beam (its edge, 33.75° off the robot's axis, as a diffuse wall
    answers first there); history of one: every band final."""
    grid = CarvedGrid(H, (-1.0, -1.5, 4.0, 1.5),
                      method=make_method("carve", MethodConfig(history_size=1)), params=params)
    walls, t = [], 0.0
    edge = DEFAULT_BEAM_WIDTH / 2
    for k in range(47):
        x = -0.8 + 0.1 * k
        for sensor, heading in enumerate((math.pi / 2, math.radians(22.5))):
            for side, sign in enumerate((1.0, -1.0)):
                off = 0.5 - sign * ROW_Y
                r = off if heading == math.pi / 2 else off / math.sin(heading + edge)
                walls.append(Reading(t, 1 + 2 * sensor + side, x, ROW_Y, sign * heading, r))
                t += 0.001
    grid.add_many(ReadingBatch.from_readings(walls))
    return grid


def test_by_default_walls_heard_by_diagonal_sensors_do_not_hide_an_obstacle_ahead() -> None:
    """Why the rule stays opt-in (helper lobe10s): sensors turned 22.5° hear a corridor's walls at
    their beam's edge, 33.75° off the axis, one 11.25° sector from a lobe ray at 22.5°, so the
    walls count as heard from near the rays of sensor 0's lobe and explain an obstacle straight
    ahead (with side_lobes=1 it went unmarked at most ranges from 1 to 2 m). The default grid
    marks it at every range where no occupied wall cell lies on the echo's band in the beam."""
    walls = _corridor_heard_diagonally(CarvedGridParams())
    tested = 0
    for r in np.arange(1.0, 2.0001, 0.01):
        if _wall_on_the_band_in_the_beam(walls, float(r)):
            continue
        grid = copy.deepcopy(walls)
        grid.add(Reading(10.0, 0, 0.0, ROW_Y, 0.0, float(r)))
        assert trinary(grid)[_cell(grid, float(r), ROW_Y)] == OCCUPIED, f"r = {r:.2f} m"
        tested += 1
    assert tested >= 40
