"""The carved grid's opt-in spread over the side lobes (``CarvedGridParams.side_lobe_spread``): a
near newest echo that an occupied cell in reach of its side lobes explains, and no cell of its own
band, holds half its spread value over its carved interval plus the lobes (docs/carved-grid.md,
*Side lobes, spread*). Expected values are worked out by hand, or by the plain-Python oracle
below, from the rule as the docs state it."""

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
ORIGIN = (0.0, 0.025)  # a cell centre
#: The jambs' range: the sensor ahead's uncarved 22.5° arc there is 0.247 m long, so one echo
#: gives its band 0.2 / 0.247 of a hit, 0.685 in log-odds: occupied (above logit(0.65) = 0.619)
#: from one echo, across the doorway between the jambs.
R = 0.63
L_HIT = math.log(0.7 / 0.3)
L_OCCUPIED = math.log(0.65 / 0.35)
SPREAD = DEFAULT_SPREAD_LENGTH / (R * DEFAULT_BEAM_WIDTH) * L_HIT  # 0.685
LOBES = CarvedGridParams(side_lobes=1.0)
SPREAD_LOBES = CarvedGridParams(side_lobes=1.0, side_lobe_spread=True)
#: The jambs' sensors are turned this far off the sensor ahead: their beams (18.75..41.25°,
#: their bands widened by half a cell, 2.27° at R) lie wholly outside its band (±11.25°, ±13.52°
#: widened) and partly inside its lobes' reach (±22.5°, ±24.77° widened).
JAMB_TURN = math.radians(30.0)

pytestmark = pytest.mark.usefixtures("carving_alone_under_the_grid")


def _doorway(params: CarvedGridParams) -> CarvedGrid:
    """Jambs each side of a doorway ahead, at range R from one point: sensors turned
    ``±JAMB_TURN`` each hear their jamb three times (a history of one arc: each echo pushes the
    one before out, final, heard from that bearing; 3 x 0.685 > occupied), then the sensor
    straight ahead hears range R (its newest echo, live), whose only reflectors are the jambs,
    past its beam's edge."""
    grid = CarvedGrid(H, BOUNDS, method=make_method("carve", MethodConfig(history_size=1)),
                      params=params)
    t = 0.0
    for sensor, side in ((1, 1.0), (2, -1.0)):
        for _ in range(3):
            t += 0.1
            grid.add(Reading(t, sensor, *ORIGIN, side * JAMB_TURN, R))
    grid.add(Reading(t + 0.1, 0, *ORIGIN, 0.0, R))
    return grid


def _cells_on_circle(grid: CarvedGrid, r: float, bearing_max: float) -> list[tuple[int, int]]:
    """Cells whose centre lies within the band's half-width of the circle of radius ``r`` about
    ORIGIN and within ``bearing_max`` of straight ahead (plain Python)."""
    xs, ys = grid.cell_centers()
    out = []
    for i, cy in enumerate(ys.tolist()):
        for j, cx in enumerate(xs.tolist()):
            dx, dy = cx - ORIGIN[0], cy - ORIGIN[1]
            if (abs(math.hypot(dx, dy) - r) <= grid.band
                    and abs(math.atan2(dy, dx)) <= bearing_max):
                out.append((i, j))
    return out


def _doorway_cells(grid: CarvedGrid) -> list[tuple[int, int]]:
    """The opening: cells on the echo's circle within 13° of straight ahead, inside its band
    (±13.52°) and short of the jambs' bands (from 16.48°)."""
    return _cells_on_circle(grid, R, math.radians(13.0))


@pytest.mark.parametrize(("params", "blocked"), [(CarvedGridParams(), "some"), (LOBES, "all"),
                                                 (SPREAD_LOBES, "none")],
                         ids=["default", "side lobes", "side lobes spread"])
def test_the_jamb_heard_through_a_lobe_blocks_the_doorway_without_the_spread(
        params: CarvedGridParams, blocked: str) -> None:
    grid = _doorway(params)
    map_ = trinary(grid)
    jambs = [c for c in _cells_on_circle(grid, R, math.radians(24.0))
             if c not in _cells_on_circle(grid, R, math.radians(17.0))]
    assert sum(map_[c] == OCCUPIED for c in jambs) >= 4
    doorway = [map_[c] == OCCUPIED for c in _doorway_cells(grid)]
    assert len(doorway) >= 9
    if blocked == "some":
        # Nothing on its band explains the echo: its middle takes a whole hit.
        assert any(doorway)
    elif blocked == "all":
        # The jambs explain it, no mark, but the short arc's spread value alone (0.685) is
        # occupied across the whole opening.
        assert all(doorway)
    else:
        # Spread over the lobes at half that value (0.342): none is.
        assert not any(doorway)


def test_the_spread_cells_are_the_interval_plus_the_lobes_at_half_the_value() -> None:
    grid = _doorway(SPREAD_LOBES)
    live = grid.live_log_odds
    # Oracle: the uncarved arc's interval is its beam, ±11.25°; plus one half width each side,
    # ±22.5°; drawn as every arc, widened by half a cell (h / 2R rad) and within the band's
    # half-width of the circle. Every such cell holds SPREAD / 2, every other cell nothing.
    reach = DEFAULT_BEAM_WIDTH + 0.5 * H / R
    expected = np.zeros(grid.shape)
    xs, ys = grid.cell_centers()
    for i, j in _cells_on_circle(grid, R, reach):
        expected[i, j] = 0.5 * SPREAD
        # No cell near an edge, where rounding could decide it.
        dx, dy = float(xs[j]) - ORIGIN[0], float(ys[i]) - ORIGIN[1]
        assert abs(abs(math.atan2(dy, dx)) - reach) > 1e-6
    for cy in ys.tolist():
        for cx in xs.tolist():
            assert abs(abs(math.hypot(cx - ORIGIN[0], cy - ORIGIN[1]) - R) - grid.band) > 1e-6
    assert np.count_nonzero(expected) > 20
    np.testing.assert_allclose(live, expected, atol=1e-6)


def test_without_the_spread_the_echo_keeps_its_band_at_its_spread_value() -> None:
    grid = _doorway(LOBES)
    live = grid.live_log_odds
    band = _cells_on_circle(grid, R, DEFAULT_BEAM_WIDTH / 2 + 0.5 * H / R)
    assert all(live[c] == pytest.approx(SPREAD) for c in band)
    assert float(live.sum()) == pytest.approx(len(band) * SPREAD)
    assert SPREAD > L_OCCUPIED > 0.5 * SPREAD


def test_the_spread_is_off_by_default() -> None:
    assert CarvedGridParams().side_lobe_spread is False
    assert CarvedGridParams(side_lobes=1.0).side_lobe_spread is False
    # The default grid with side lobes draws what it drew before the rule.
    np.testing.assert_array_equal(_doorway(CarvedGridParams(side_lobes=1.0)).log_odds,
                                  _doorway(CarvedGridParams(side_lobes=1.0,
                                                            side_lobe_spread=False)).log_odds)


@pytest.mark.parametrize("lobes", [0.0, 0.5, 2.0, 3.0])
def test_the_spread_needs_one_side_lobe_of_one_half_width(lobes: float) -> None:
    with pytest.raises(GridError, match="side_lobe_spread needs side_lobes 1"):
        CarvedGridParams(side_lobes=lobes, side_lobe_spread=True)


@pytest.mark.parametrize("bad", [1, 0, "yes", None])
def test_the_spread_is_true_or_false(bad: object) -> None:
    with pytest.raises(GridError, match="side_lobe_spread must be True or False"):
        CarvedGridParams(side_lobes=1.0, side_lobe_spread=bad)  # type: ignore[arg-type]


def test_an_echo_its_band_explains_is_not_spread() -> None:
    # A third sensor straight ahead heard the opening's circle three times: its band is final
    # and occupied, so the newest echo ahead is explained by its own band: nothing changes.
    grid = CarvedGrid(H, BOUNDS, method=make_method("carve", MethodConfig(history_size=1)),
                      params=SPREAD_LOBES)
    for k, (sensor, turn) in enumerate([(1, JAMB_TURN)] * 3 + [(3, 0.0)] * 3):
        grid.add(Reading(0.1 * k, sensor, *ORIGIN, turn, R))
    grid.add(Reading(1.0, 0, *ORIGIN, 0.0, R))
    live = grid.live_log_odds
    band = _cells_on_circle(grid, R, DEFAULT_BEAM_WIDTH / 2 + 0.5 * H / R)
    assert all(live[c] == pytest.approx(SPREAD) for c in band)
    assert float(np.abs(live).sum()) == pytest.approx(len(band) * SPREAD)


def test_an_echo_beyond_side_lobe_range_is_not_spread() -> None:
    params = CarvedGridParams(side_lobes=1.0, side_lobe_spread=True, side_lobe_range=0.6)
    grid = _doorway(params)
    # Not looked at past its band: unexplained, its middle takes a whole hit (clipped to the
    # interval, here the 0.2 m around the middle).
    assert grid.live_log_odds[_middle(grid)] == pytest.approx(L_HIT)


def _middle(grid: CarvedGrid) -> tuple[int, int]:
    xs, ys = grid.cell_centers()
    return int(np.argmin(np.abs(ys - ORIGIN[1]))), int(np.argmin(np.abs(xs - R)))


def test_the_spread_ends_when_its_echo_leaves_the_history() -> None:
    grid = _doorway(SPREAD_LOBES)
    assert np.abs(grid.live_log_odds).max() == pytest.approx(0.5 * SPREAD)
    # Another sensor's echo behind pushes the echo ahead out of a history of one arc: neither
    # its band nor its overlay is left ahead of the sensor.
    grid.add(Reading(5.0, 4, *ORIGIN, math.pi, 0.3))
    xs, _ = grid.cell_centers()
    np.testing.assert_allclose(grid.live_log_odds[:, xs > 0.2], 0.0, atol=1e-6)


def test_a_live_echo_keeps_its_spread_after_its_sensor_fires_again() -> None:
    grid = CarvedGrid(H, BOUNDS, method=make_method("carve", MethodConfig(history_size=2)),
                      params=SPREAD_LOBES)
    for k in range(6):  # each jamb echo pushes the one two before it out
        grid.add(Reading(0.1 * k, 1 + k % 2, *ORIGIN, (1 - 2 * (k % 2)) * JAMB_TURN, R))
    grid.add(Reading(1.0, 0, *ORIGIN, 0.0, R))
    assert grid.live_log_odds[_middle(grid)] == pytest.approx(0.5 * SPREAD)
    # It fires again, backwards: its echo ahead is no longer its newest but still live, and
    # still explained by the jambs alone: spread over its lobes, as every near live arc.
    grid.add(Reading(1.1, 0, *ORIGIN, math.pi, 0.3))
    live = grid.live_log_odds
    assert live[_middle(grid)] == pytest.approx(0.5 * SPREAD)
    xs, _ = grid.cell_centers()
    wide = _cells_on_circle(grid, R, DEFAULT_BEAM_WIDTH + 0.5 * H / R)
    assert float(live[:, xs > 0.2].sum()) == pytest.approx(len(wide) * 0.5 * SPREAD)
    # Without the spread the same echo holds its whole spread value on its band.
    grid = CarvedGrid(H, BOUNDS, method=make_method("carve", MethodConfig(history_size=2)),
                      params=LOBES)
    for k in range(6):
        grid.add(Reading(0.1 * k, 1 + k % 2, *ORIGIN, (1 - 2 * (k % 2)) * JAMB_TURN, R))
    grid.add(Reading(1.0, 0, *ORIGIN, 0.0, R))
    grid.add(Reading(1.1, 0, *ORIGIN, math.pi, 0.3))
    assert grid.live_log_odds[_middle(grid)] == pytest.approx(SPREAD)


def test_reading_the_map_often_or_once_gives_the_same_spread() -> None:
    once = _doorway(SPREAD_LOBES)
    often = CarvedGrid(H, BOUNDS, method=make_method("carve", MethodConfig(history_size=1)),
                       params=SPREAD_LOBES)
    batch = ReadingBatch.from_readings(
        [Reading(0.1 * (k + 1), 1 + k // 3, *ORIGIN, (1 - 2 * (k // 3)) * JAMB_TURN, R)
         for k in range(6)] + [Reading(0.7, 0, *ORIGIN, 0.0, R)])
    for start in range(len(batch)):
        often.add_many(batch[start:start + 1])
        often.refresh()
    np.testing.assert_allclose(often.log_odds, once.log_odds, atol=1e-6)
