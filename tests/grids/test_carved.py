"""The carved grid: occupied bands follow carving over time (values computed by hand)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.grids import (
    OCCUPIED,
    CarvedGrid,
    CarvedGridParams,
    GridError,
    OccupancyGrid,
    RangeSensorLayer,
    trinary,
)
from sonarcarve.grids.carved import DEFAULT_SPREAD_LENGTH
from sonarcarve.methods import (
    CarvingMethod,
    CarvingModel,
    CombinedMethod,
    Estimates,
    MethodConfig,
    make_method,
)
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch
from sonarcarve.typing import SlotArray

H = 0.05
BOUNDS = (-0.5, -1.5, 3.5, 1.5)
L_HIT = math.log(0.7 / 0.3)
PHI = DEFAULT_BEAM_WIDTH
#: The spread rule alone: the tests of how arcs are spread and follow carving read arcs that are
#: their sensor's newest reading, which the default draws as a point (the fresh-arc tests).
SPREAD_ONLY = CarvedGridParams(fresh_arcs=False)


pytestmark = pytest.mark.usefixtures("carving_alone_under_the_grid")


def _reading(t: float, theta: float, r: float, x: float = 0.0, y: float = 0.0) -> Reading:
    return Reading(t=t, sensor=0, x=x, y=y, theta=theta, range=r)


def _band(grid: CarvedGrid, r: float, lo: float, hi: float) -> np.ndarray:
    """Cells the grid's rule puts in the band of an arc from (0, 0): centre within
    (h + ε)/2 of radius r, bearing within [lo, hi] widened by h / 2r."""
    xs, ys = grid.cell_centers()
    cx, cy = np.meshgrid(xs, ys)
    d = np.hypot(cx, cy)
    bearing = np.arctan2(cy, cx)
    widen = 0.5 * grid.resolution / r
    return (np.abs(d - r) <= grid.band) & (bearing >= lo - widen) & (bearing <= hi + widen)


def test_an_arc_carved_narrower_takes_back_exactly_what_it_gave_outside() -> None:
    grid = CarvedGrid(H, BOUNDS, params=SPREAD_ONLY)
    # A: a wall 2 m ahead, head-on; its arc spans the whole beam, 2 * φ = 0.785 m long.
    grid.add(_reading(0.0, 0.0, 2.0))
    old = _band(grid, 2.0, -PHI / 2, PHI / 2)
    value_old = DEFAULT_SPREAD_LENGTH / (2.0 * PHI) * L_HIT  # s = L / (r width) = 0.2546
    live = grid.live_log_odds
    assert live[old] == pytest.approx(value_old)
    assert np.all(live[~old] == 0.0)
    # B: the same sensor turned 0.25 rad left hears nothing nearer than 3 m; its free space
    # carves A down to [-φ/2, 0.25 - φ/2]: 0.25 rad, 0.5 m long.
    grid.add(_reading(1.0, 0.25, 3.0))
    model = grid.method.models[0]
    slot = int(grid.method.history.slots()[0])
    assert isinstance(model, CarvingModel)
    assert (model.lo[slot], model.hi[slot]) == pytest.approx((-PHI / 2, 0.25 - PHI / 2))
    new = _band(grid, 2.0, -PHI / 2, 0.25 - PHI / 2)
    value_new = DEFAULT_SPREAD_LENGTH / (2.0 * 0.25) * L_HIT  # s = 0.4: sharper
    live = grid.live_log_odds
    lost = old & ~new
    assert lost.sum() >= 8
    np.testing.assert_allclose(live[lost], 0.0, atol=1e-12)  # exactly what they had gained
    assert live[new] == pytest.approx(value_new)
    assert value_new > value_old


def test_a_fully_carved_arc_leaves_no_occupied_cell() -> None:
    grid = CarvedGrid(H, BOUNDS, params=CarvedGridParams(spread_length=1.0))
    grid.add(_reading(0.0, 0.0, 2.0))  # a phantom 2 m ahead: a whole hit with L = 1 m ...
    band = _band(grid, 2.0, -PHI / 2, PHI / 2)
    assert np.any(trinary(grid)[band] == OCCUPIED)
    grid.add(_reading(1.0, 0.0, 3.0))  # ... that the next reading sees through
    assert grid.method.measures().fully_carved == 1
    np.testing.assert_allclose(grid.live_log_odds[band], 0.0, atol=1e-12)
    assert not np.any(trinary(grid)[band] == OCCUPIED)


def test_an_arc_leaving_the_history_makes_its_band_final() -> None:
    method = make_method("carve", MethodConfig(history_size=1))
    grid = CarvedGrid(H, BOUNDS, method=method, params=SPREAD_ONLY)
    grid.add(_reading(0.0, 0.0, 2.0))
    band = _band(grid, 2.0, -PHI / 2, PHI / 2)
    before = grid.log_odds[band]
    grid.add(_reading(1.0, math.pi, 0.3))  # behind: touches nothing of A, pushes it out
    assert np.all(grid.live_log_odds[band] == 0.0)
    np.testing.assert_allclose(grid.log_odds[band], before, atol=1e-6)


def test_batches_do_not_change_the_map() -> None:
    rng = np.random.default_rng(3)
    n = 120
    batch = ReadingBatch.from_readings(
        _reading(0.1 * k, float(rng.uniform(-0.6, 0.6)), float(rng.uniform(0.5, 2.8)),
                 x=float(rng.uniform(-0.2, 0.2)), y=float(rng.uniform(-0.3, 0.3)))
        for k in range(n))
    whole = CarvedGrid(H, BOUNDS, method=make_method("carve", MethodConfig(history_size=20)))
    whole.add_many(batch)
    pieces = CarvedGrid(H, BOUNDS, method=make_method("carve", MethodConfig(history_size=20)))
    for start in range(0, n, 7):
        pieces.add_many(batch[start : start + 7])
        pieces.probabilities()  # reading the map in between changes nothing either
    np.testing.assert_allclose(pieces.log_odds, whole.log_odds, atol=1e-5)


def test_memory_is_bounded_by_the_map_and_the_history() -> None:
    method = make_method("carve", MethodConfig(history_size=50))
    grid = CarvedGrid(0.1, BOUNDS, method=method)
    rows, cols = grid.shape
    # base, live, points, heard bins; per slot what was drawn (spread and point: 6 numbers and
    # the arc), its interval, weight and repeat factor, the carving state they came from (3
    # numbers and the arc), the ATM crossings they came from (and a zero count for carving
    # alone, two int32) and a position buffer for the arcs that changed; per live arc a buffer
    # for the arcs a batch's repeats marked
    expected = rows * cols * (4 + 8 + 4 + 4) + 2 * 50 * (2 * (6 * 8 + 8) + 4 * 8 + 4 * 8 + 2 * 4
                                                         + 8) + 50 * 8
    assert grid.nbytes == expected
    rng = np.random.default_rng(0)
    for block in range(5):
        batch = ReadingBatch.from_readings(
            _reading(block * 100 + 0.1 * k, float(rng.uniform(-1, 1)),
                     float(rng.uniform(0.5, 3))) for k in range(100))
        grid.add_many(batch)
        assert grid.nbytes == expected
        with pytest.raises(RuntimeError, match="keeps none of it"):
            method.global_map()  # the method's growing map is not kept, only counted
    assert grid.readings == 500


def test_confidence_weighs_the_band() -> None:
    class HalfSure(CarvingMethod):
        def estimates(self, slots: SlotArray) -> Estimates:
            est = super().estimates(slots)
            return Estimates(est.alive, est.processed, est.xy, est.width, est.max_error,
                             est.source, est.fate, np.full(len(slots), 0.5))

    sure = CarvedGrid(H, BOUNDS)
    half = CarvedGrid(H, BOUNDS, method=HalfSure())
    for g in (sure, half):
        g.add(_reading(0.0, 0.0, 2.0))
    band = _band(sure, 2.0, -PHI / 2, PHI / 2)
    np.testing.assert_allclose(half.live_log_odds[band], 0.5 * sure.live_log_odds[band])


def test_bad_parameters_and_used_methods_are_refused() -> None:
    with pytest.raises(GridError, match="p_hit"):
        CarvedGridParams(p_hit=0.4)
    with pytest.raises(GridError, match="free_threshold"):
        CarvedGridParams(free_threshold=0.7)
    with pytest.raises(GridError, match="spread_length"):
        CarvedGridParams(spread_length=-1.0)
    with pytest.raises(GridError, match="resolution"):
        CarvedGrid(0.0, BOUNDS)
    with pytest.raises(GridError, match="bounds"):
        CarvedGrid(0.1, (0.0, 0.0, 0.0, 1.0))
    used = make_method("carve")
    used.add(_reading(0.0, 0.0, 1.0))
    with pytest.raises(GridError, match="fresh"):
        CarvedGrid(0.1, BOUNDS, method=used)


def test_trinary_follows_each_grids_rule() -> None:
    reading = _reading(0.0, 0.0, 1.0)
    layer = RangeSensorLayer(0.1, BOUNDS)
    layer.add(reading)
    costs = layer.costs()
    tri = trinary(layer)
    assert np.array_equal(tri == 100, costs == 254)
    assert np.array_equal(tri == 0, costs == 0)
    assert np.array_equal(tri == -1, costs == 255)
    elfes = OccupancyGrid(0.1, BOUNDS)
    elfes.add(reading)
    p = elfes.probabilities()
    assert np.array_equal(trinary(elfes) == 100, p > 0.65)
    assert np.array_equal(trinary(elfes) == 0, p < 0.35)  # DEFAULT_FREE_THRESHOLD


def _silent(t: float, theta: float, x: float, y: float, max_range: float = 4.0) -> Reading:
    return Reading(t, 0, x, y, theta, math.inf, math.nan, max_range)


def _cell(grid: CarvedGrid, x: float, y: float) -> tuple[int, int]:
    xs, ys = grid.cell_centers()
    return int(np.argmin(np.abs(ys - y))), int(np.argmin(np.abs(xs - x)))


def _box_face_seen_head_on(params: CarvedGridParams) -> CarvedGrid:
    """A face at x = 2 heard head-on 30 times from (0, 0), every arc final (history of 1)."""
    grid = CarvedGrid(0.1, BOUNDS, method=make_method("carve", MethodConfig(history_size=1)),
                      params=params)
    grid.add_many(ReadingBatch.from_readings(_reading(0.1 * k, 0.0, 2.0) for k in range(30)))
    return grid


def test_beams_through_a_vanished_box_clear_it() -> None:
    face = (2.0, 0.0)
    for aware, cleared in ((True, True), (False, False)):
        grid = _box_face_seen_head_on(CarvedGridParams(surface_aware=aware))
        i, j = _cell(grid, *face)
        assert grid.log_odds[i, j] == pytest.approx(math.log(0.97 / 0.03), abs=1e-5)
        # The box is gone: three beams from where it was heard pass it and hear the wall at 4 m.
        grid.add_many(ReadingBatch.from_readings(_reading(5.0 + k, 0.0, 4.0) for k in range(3)))
        # Surface-aware: each beam that would have heard the face gives γ(α) logit(0.2), γ the
        # angular profile at the cell centre's bearing: 3.476 - 3 x 0.984 x 1.386 = -0.62, no
        # longer occupied. Faded (ROS's 1.2 m fade, 0.04 x logit(0.4) a beam) it stays.
        xs, ys = grid.cell_centers()
        d, alpha = math.hypot(xs[j], ys[i]), math.atan2(ys[i], xs[j])
        gamma = 1.0 - (alpha / (PHI / 2)) ** 2
        per_beam = (math.log(0.2 / 0.8) if aware else
                    0.5 * (1 - math.tanh(2 * (d - 1.2))) * math.log(0.4 / 0.6))
        expected = math.log(0.97 / 0.03) + 3 * gamma * per_beam
        assert grid.log_odds[i, j] == pytest.approx(expected, abs=0.02)
        assert (trinary(grid)[i, j] == OCCUPIED) is not cleared


def test_a_glancing_silent_beam_does_not_clear_a_wall() -> None:
    # A wall along y = 1 heard head-on from below by readings every 5 cm, all final.
    grid = CarvedGrid(0.1, BOUNDS, method=make_method("carve", MethodConfig(history_size=1)))
    grid.add_many(ReadingBatch.from_readings(
        _reading(0.1 * k, math.pi / 2, 1.0, x=0.5 + 0.05 * k) for k in range(40)))
    i, j = _cell(grid, 1.5, 1.0)
    assert trinary(grid)[i, j] == OCCUPIED
    before = grid.log_odds[i, j]
    # Ten silent beams along the wall (incidence about 86°): a smooth wall would not have
    # answered them, so they say little about it (ROS's fade only, about 0.03 a beam here).
    grid.add_many(ReadingBatch.from_readings(
        _silent(10.0 + k, 0.0, -0.5, 0.9) for k in range(10)))
    assert trinary(grid)[i, j] == OCCUPIED
    assert before - grid.log_odds[i, j] < 0.5
    # Ten silent beams from below, where the wall was heard from: it is gone.
    grid.add_many(ReadingBatch.from_readings(
        _silent(30.0 + k, math.pi / 2, 1.5, 0.0) for k in range(10)))
    assert trinary(grid)[i, j] != OCCUPIED


def test_a_jamb_arc_carved_away_leaves_the_door_open() -> None:
    # A door 0.8 m wide in a wall at x = 2 (jambs at y = ±0.4). A sensor at (0, 0.6) looking
    # at the upper jamb hears it at its distance; its uncarved arc sweeps over the doorway.
    grid = CarvedGrid(0.05, BOUNDS, params=SPREAD_ONLY)
    jamb = (2.0, 0.4)
    r = math.hypot(jamb[0], jamb[1] - 0.6)
    grid.add(_reading(0.0, math.atan2(jamb[1] - 0.6, jamb[0]), r, y=0.6))
    axis = math.atan2(jamb[1] - 0.6, jamb[0])
    xs, ys = grid.cell_centers()
    cx, cy = np.meshgrid(xs, ys)
    on_arc = ((np.abs(np.hypot(cx, cy - 0.6) - r) <= grid.band)
              & (np.abs(np.arctan2(cy - 0.6, cx) - axis) <= PHI / 2 - 0.02))
    door = on_arc & (cy < 0.3)  # the flank more than 0.1 m inside the doorway
    assert door.sum() >= 3
    assert np.all(grid.live_log_odds[door] > 0.0)  # the arc's flank lies over the doorway
    # Beams through the doorway (from the same place) hear the room beyond at 3.4 m: carving
    # cuts the flank, and the doorway's cells lose what it gave them.
    grid.add_many(ReadingBatch.from_readings(
        _reading(1.0 + k, math.atan2(-0.1 - 0.6 + 0.1 * k, 2.0), 3.4, y=0.6)
        for k in range(3)))
    np.testing.assert_allclose(grid.live_log_odds[door], 0.0, atol=1e-12)
    assert not np.any(trinary(grid)[door] == OCCUPIED)


def test_free_space_covers_exactly_the_beams_cells_whatever_its_bearing() -> None:
    # One silent beam on a fresh grid: every cell whose centre lies in the sector (nearer than
    # max_range, within φ/2 of the axis) gets γ(α) f(d) logit(0.4), every other cell nothing;
    # computed here over all cells, against the kernel that visits only each row's stretch.
    rng = np.random.default_rng(7)
    l_miss = math.log(0.4 / 0.6)
    for _ in range(25):
        grid = CarvedGrid(0.1, BOUNDS)
        x, y = rng.uniform(0.0, 3.0), rng.uniform(-1.0, 1.0)
        theta, reach = rng.uniform(-math.pi, math.pi), rng.uniform(0.3, 3.0)
        grid.add_many(ReadingBatch.from_readings([_silent(0.0, theta, x, y, reach)]))
        xs, ys = grid.cell_centers()
        cx, cy = np.meshgrid(xs, ys)
        d = np.hypot(cx - x, cy - y)
        alpha = np.angle(np.exp(1j * (np.arctan2(cy - y, cx - x) - theta)))
        inside = (d < reach) & (np.abs(alpha) <= PHI / 2)
        fade = 0.5 * (1.0 - np.tanh(2.0 * (d - 1.2)))
        expected = np.where(inside, (1.0 - (alpha / (PHI / 2)) ** 2) * fade * l_miss, 0.0)
        edge = (np.abs(d - reach) < 1e-6) | (np.abs(np.abs(alpha) - PHI / 2) < 1e-6)
        np.testing.assert_allclose(grid.log_odds[~edge], expected[~edge], atol=1e-6)


def test_a_freed_cell_forgets_the_bearings_it_was_heard_from() -> None:
    # A cell heard from the south, then freed by silent beams from the south, then heard only
    # from the east (a different surface). A silent beam from the south would not have heard
    # the new surface: it must give the faded update γ f(d) logit(0.4), not γ logit(0.2).
    grid = CarvedGrid(0.1, BOUNDS, method=make_method("carve", MethodConfig(history_size=1)))
    cx, cy = 1.55, 0.05  # a cell centre
    i, j = _cell(grid, cx, cy)
    south, east = (cx, cy - 1.0), (cx + 1.0, cy)

    def heard_from(origin: tuple[float, float], theta: float, t0: float) -> None:
        aside = _reading(t0 + 5.0, math.pi, 0.5, x=-0.3, y=1.3)  # far off: pushes the last
        grid.add_many(ReadingBatch.from_readings(  # arc out, every band final
            [*(_reading(t0 + 0.1 * k, theta, 1.0, *origin) for k in range(10)), aside]))

    heard_from(south, math.pi / 2, 0.0)
    assert grid.log_odds[i, j] == pytest.approx(math.log(0.97 / 0.03), abs=1e-5)
    grid.add_many(ReadingBatch.from_readings(
        _silent(10.0 + k, math.pi / 2, *south) for k in range(3)))
    assert grid.log_odds[i, j] <= 0.0  # freed (3.476 - 3 x 1.386 = -0.68, each beam audible)
    heard_from(east, math.pi, 20.0)
    assert np.all(grid.live_log_odds[i - 1 : i + 2, j - 1 : j + 2] == 0.0)
    before = grid.log_odds[i, j]
    assert before > 0.0  # believed occupied again
    grid.add_many(ReadingBatch.from_readings([_silent(30.0, math.pi / 2, *south)]))
    alpha = math.atan2(cx - south[0], cy - south[1])  # off the beam's axis (0 up to rounding)
    gamma = 1.0 - (alpha / (PHI / 2)) ** 2
    d = math.hypot(cx - south[0], cy - south[1])
    faded = gamma * 0.5 * (1.0 - math.tanh(2.0 * (d - 1.2))) * math.log(0.4 / 0.6)  # -0.28
    assert grid.log_odds[i, j] - before == pytest.approx(faded, abs=1e-5)



L_MAX = math.log(0.97 / 0.03)
L_HEARD = math.log(0.2 / 0.8)


def _face_and_cell_behind(params: CarvedGridParams, behind: tuple[float, float]) -> CarvedGrid:
    """A box's face at x = 2 heard head-on from (0, 0), and the cell ``behind`` heard only
    from the north (bearing -90°, another face of the box), every band final at the clamp."""
    grid = CarvedGrid(0.1, BOUNDS, method=make_method("carve", MethodConfig(history_size=1)),
                      params=params)
    north = (behind[0], behind[1] + 1.0)
    grid.add_many(ReadingBatch.from_readings(
        [*(_reading(0.1 * k, 0.0, 2.0) for k in range(30)),
         *(_reading(5.0 + 0.1 * k, -math.pi / 2, 1.0, *north) for k in range(30)),
         _reading(9.0, math.pi, 0.5, x=-0.3, y=1.3)]))  # far off: the last arc goes final
    return grid


def test_a_beam_through_a_vanished_face_clears_what_stood_behind_it() -> None:
    # The box is gone: three beams from (0, 0) along x hear the far wall at 4 m. The face's
    # cell (2.05, 0.05) would have answered them (heard from their bearing): γ logit(0.2) a
    # beam. The cell (2.45, 0.05) behind it was heard only from the north: from the west it is
    # inaudible, so alone it gets ROS's fade at 2.45 m (f = 0.0082, nothing). Seen through the
    # face (0.4 m in front of it on the same ray, within see_through), it gets what the face
    # gets: 3.476 - 3 x 0.989 x 1.386 = -0.64, cleared. Off (0): it stays at the clamp.
    face, behind = (2.05, 0.05), (2.45, 0.05)
    for depth, cleared in ((0.5, True), (0.0, False), (0.3, False)):
        grid = _face_and_cell_behind(CarvedGridParams(see_through=depth), behind)
        fi, fj = _cell(grid, *face)
        bi, bj = _cell(grid, *behind)
        assert grid.log_odds[fi, fj] == pytest.approx(L_MAX, abs=1e-5)
        assert grid.log_odds[bi, bj] == pytest.approx(L_MAX, abs=1e-5)
        grid.add_many(ReadingBatch.from_readings(_reading(20.0 + k, 0.0, 4.0) for k in range(3)))
        d = math.hypot(*behind)
        gamma = 1.0 - (math.atan2(behind[1], behind[0]) / (PHI / 2)) ** 2
        fade = 0.5 * (1.0 - math.tanh(2.0 * (d - 1.2))) * math.log(0.4 / 0.6)
        expected = L_MAX + 3 * gamma * (L_HEARD if cleared else fade)
        assert grid.log_odds[bi, bj] == pytest.approx(expected, abs=1e-4)
        assert (trinary(grid)[bi, bj] == OCCUPIED) is not cleared
        assert trinary(grid)[fi, fj] != OCCUPIED  # the face itself, cleared in every case


def test_a_beam_that_would_not_have_heard_the_face_clears_nothing_behind_it() -> None:
    # The box still there; silent beams from the south-west meet the face at 46° (it was
    # heard from bearings within 11° of 0: three sectors or more away, inaudible) and pass
    # through its cell (2.05, 0.05) to a cell 0.4 m behind it on the same ray: a smooth face
    # would not have answered them, so they say nothing about the face, nor about what is
    # behind it: each gives the cell ROS's fade at 2.0 m only.
    origin, face, behind = (0.95, -1.1), (2.05, 0.05), (2.35, 0.35)
    grid = _face_and_cell_behind(CarvedGridParams(see_through=math.inf), behind)
    bi, bj = _cell(grid, *behind)
    assert grid.log_odds[bi, bj] == pytest.approx(L_MAX, abs=1e-5)
    theta = math.atan2(face[1] - origin[1], face[0] - origin[0])
    grid.add_many(ReadingBatch.from_readings(
        _silent(20.0 + k, theta, *origin, max_range=4.0) for k in range(10)))
    d_face, d_behind = math.dist(origin, face), math.dist(origin, behind)
    off = math.atan2(behind[1] - origin[1], behind[0] - origin[0]) - theta
    gamma = 1.0 - (off / (PHI / 2)) ** 2
    fade = 0.5 * (1.0 - math.tanh(2.0 * (d_behind - 1.2))) * math.log(0.4 / 0.6)  # -0.015
    assert grid.log_odds[bi, bj] == pytest.approx(L_MAX + 10 * gamma * fade, abs=1e-4)
    assert trinary(grid)[bi, bj] == OCCUPIED
    # Had the face been audible, these beams would have cleared the cell (10 x logit(0.2)):
    # it is on their ray, 0.4 m behind the face's cell (what _free_behind asks of a cell in
    # front: a cell nearer, its centre within half a cell's diagonal of the ray).
    assert 0.1 <= d_behind - d_face <= 0.5
    assert abs(off) * d_face <= 0.7072 * 0.1


@pytest.mark.parametrize("bad", [-0.1, math.nan, True, "0.5"])
def test_see_through_must_be_a_number_of_metres(bad: object) -> None:
    with pytest.raises(GridError, match="see_through"):
        CarvedGridParams(see_through=bad)  # type: ignore[arg-type]


# -- fresh arcs: each sensor's newest echo marks at once ----------------------------------------

#: A row of cell centres (y = 0.025 at H = 0.05) and a column (x = 1.825) on it.
ROW_Y, FACE_X = 0.025, 1.825
L_OCCUPIED = math.log(0.65 / 0.35)  # 0.619
L_MISS = math.log(0.4 / 0.6)
#: An echo at FACE_X spread over the whole beam: s = 0.2 / (1.825 x 0.3927) = 0.2791 of a hit.
SPREAD_AT_FACE = DEFAULT_SPREAD_LENGTH / (FACE_X * PHI) * L_HIT  # 0.236
#: One silent on-axis beam's free space at FACE_X, ROS's fade: 0.0759 x logit(0.4) = -0.031.
FREE_AT_FACE = 0.5 * (1.0 - math.tanh(2.0 * (FACE_X - 1.2))) * L_MISS


def _ring_hears_nothing(grid: CarvedGrid) -> None:
    """Eight sensors 45° apart at (0, ROW_Y) fire once and hear nothing within 3 m."""
    grid.add_many(ReadingBatch.from_readings(
        Reading(0.1 * k, k, 0.0, ROW_Y, k * math.pi / 4, math.inf, math.nan, 3.0)
        for k in range(8)))


def _front(t: float, r: float = FACE_X, sensor: int = 0) -> Reading:
    return Reading(t, sensor, 0.0, ROW_Y, 0.0, r)


def test_a_disc_stepping_in_front_of_a_ring_is_occupied_after_one_reading() -> None:
    face = (FACE_X, ROW_Y)
    for params, marked in ((CarvedGridParams(), True), (SPREAD_ONLY, False)):
        grid = CarvedGrid(H, BOUNDS, params=params)
        _ring_hears_nothing(grid)
        i, j = _cell(grid, *face)
        assert grid.log_odds[i, j] == pytest.approx(FREE_AT_FACE, abs=1e-6)
        # A person (a 0.4 m disc) steps in front of sensor 0; its face is 1.825 m away.
        grid.add(_front(1.0))
        # The newest echo of sensor 0, explained by nothing on the map: a whole hit on its
        # middle, -0.031 + 0.847 = 0.816 > logit(0.65) = 0.619. Spread over the beam it would
        # be -0.031 + 0.236 = 0.206: unsure, and the robot would drive into the person.
        expected = FREE_AT_FACE + (L_HIT if marked else SPREAD_AT_FACE)
        assert grid.log_odds[i, j] == pytest.approx(expected, abs=1e-6)
        assert bool(trinary(grid)[i, j] == OCCUPIED) is marked


@pytest.mark.parametrize("repeat_weight", [0.0, 1.0])
def test_a_person_standing_still_stays_marked_reading_after_reading(
        repeat_weight: float) -> None:
    grid = CarvedGrid(H, BOUNDS, params=CarvedGridParams(repeat_weight=repeat_weight))
    _ring_hears_nothing(grid)
    i, j = _cell(grid, FACE_X, ROW_Y)
    for k in range(6):
        grid.add(_front(1.0 + k))
        # Echoes from the same place are no repeats (origins within 2ε say nothing about
        # where the echo came from), so with either repeat_weight: k older arcs spread (0.236
        # each) plus the newest: a whole hit while they leave the face unsure (k <= 2: at most
        # 0.44), its own spread once they mark it (k >= 3: 3 x 0.236 - 0.031 = 0.68 > 0.619).
        newest = L_HIT if k * SPREAD_AT_FACE + FREE_AT_FACE <= L_OCCUPIED else SPREAD_AT_FACE
        expected = FREE_AT_FACE + k * SPREAD_AT_FACE + newest
        assert grid.log_odds[i, j] == pytest.approx(expected, abs=1e-6), k
        assert trinary(grid)[i, j] == OCCUPIED, k  # occupied after every reading: no flicker
    # The person walks away: the sensor hears the wall behind at 3 m; carving removes every
    # arc at 1.825 m, and the cell keeps only free space: the ring's beam and this one (-0.031
    # each; the echoes' own free space stopped short of their band).
    grid.add(_front(10.0, 3.0))
    assert grid.log_odds[i, j] == pytest.approx(2 * FREE_AT_FACE, abs=1e-6)


def test_the_mark_is_the_middle_of_the_arc_and_leaves_when_its_sensor_fires_again() -> None:
    grid = CarvedGrid(H, BOUNDS)
    _ring_hears_nothing(grid)
    mid, side = _cell(grid, FACE_X, ROW_Y), _cell(grid, 1.816, ROW_Y + 0.175)
    # The side cell lies on the arc (1.8244 m, 0.0955 rad off the axis, inside φ/2 = 0.196)
    # but off its middle: the whole hit covers ±(0.05 / (2 x 1.825)) = ±0.0137 rad (the
    # default mark, the point's own cell, widened by half a cell; ±0.068 with the 0.2 m mark).
    grid.add(_front(1.0))
    live = grid.live_log_odds
    assert live[mid] == pytest.approx(L_HIT)
    assert live[side] == pytest.approx(SPREAD_AT_FACE)  # the rest of the arc: spread
    # Another sensor firing elsewhere changes nothing: sensor 0's echo is still its newest.
    grid.add(Reading(1.1, 4, 0.0, ROW_Y, math.pi, 0.3))
    assert grid.live_log_odds[mid] == pytest.approx(L_HIT)
    # Sensor 0 fires again, backwards: its first echo is no longer its newest, and is spread.
    grid.add(Reading(1.2, 0, 0.0, ROW_Y, math.pi, 0.3))
    live = grid.live_log_odds
    assert live[mid] == pytest.approx(SPREAD_AT_FACE)
    assert live[side] == pytest.approx(SPREAD_AT_FACE)
    assert trinary(grid)[mid] != OCCUPIED  # one spread echo: unsure


@pytest.mark.parametrize(("params", "beside_marked"),
                         [(CarvedGridParams(mark_length=None), True),
                          (CarvedGridParams(mark_length=0.1), True),
                          (CarvedGridParams(mark_length=0.0), False),
                          (CarvedGridParams(), False)],
                         ids=["None (0.2 m)", "0.1 m", "0", "default"])
def test_mark_length_sets_how_much_of_the_arc_the_mark_covers(params: CarvedGridParams,
                                                              beside_marked: bool) -> None:
    grid = CarvedGrid(H, BOUNDS, params=params)
    _ring_hears_nothing(grid)
    # The cell one cell beside the middle along the arc: centre (1.825, 0.075), 1.8257 m from
    # the sensor (inside the band, ±0.05), 0.05 / 1.825 = 0.0274 rad off the axis. The mark
    # covers ±(mark_length / 2 + h / 2) / 1.825 rad: None (0.2 m) ±0.068, 0.1 m ±0.041,
    # 0 (the default: the point's cell) ±0.0137, which leaves this cell its spread value.
    mid, beside = _cell(grid, FACE_X, ROW_Y), _cell(grid, FACE_X, ROW_Y + H)
    grid.add(_front(1.0))
    live = grid.live_log_odds
    assert live[mid] == pytest.approx(L_HIT)
    assert live[beside] == pytest.approx(L_HIT if beside_marked else SPREAD_AT_FACE)
    assert trinary(grid)[mid] == OCCUPIED  # the point is marked whatever its length


@pytest.mark.parametrize("bad", [-0.1, math.nan, math.inf, "0.1"])
def test_mark_length_must_be_a_finite_length_or_none(bad: object) -> None:
    with pytest.raises(GridError, match="mark_length"):
        CarvedGridParams(mark_length=bad)  # type: ignore[arg-type]


def test_a_mark_expires_when_its_sensor_stays_silent_past_fresh_seconds() -> None:
    # A log without silent firings never shows sensor 0 firing again: its last echo must not
    # stay a whole hit for as long as the arc is in the history (review finding: 20 s).
    grid = CarvedGrid(H, BOUNDS, params=CarvedGridParams(fresh_seconds=2.0))
    _ring_hears_nothing(grid)
    mid = _cell(grid, FACE_X, ROW_Y)
    grid.add(_front(1.0))
    assert grid.live_log_odds[mid] == pytest.approx(L_HIT)
    # Sensor 4 looks backwards, away from the face; at t = 3.0 the echo is 2.0 s old: fresh.
    grid.add(Reading(3.0, 4, 0.0, ROW_Y, math.pi, 0.3))
    assert grid.live_log_odds[mid] == pytest.approx(L_HIT)
    # At t = 3.1 it is 2.1 s old: spread, one echo's worth (0.236), and unsure.
    grid.add(Reading(3.1, 4, 0.0, ROW_Y, math.pi, 0.3))
    assert grid.live_log_odds[mid] == pytest.approx(SPREAD_AT_FACE)
    assert trinary(grid)[mid] != OCCUPIED


@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, math.inf, True, "2"])
def test_fresh_seconds_must_be_a_finite_positive_number(bad: object) -> None:
    with pytest.raises(GridError, match="fresh_seconds"):
        CarvedGridParams(fresh_seconds=bad)  # type: ignore[arg-type]


def test_an_echo_the_map_already_explains_is_only_spread() -> None:
    grid = CarvedGrid(H, BOUNDS, method=make_method("carve", MethodConfig(history_size=1)))
    _ring_hears_nothing(grid)
    i, j = _cell(grid, FACE_X, ROW_Y)
    # Sensors 1-3 (turned to face the same way) hear the face; with a history of one arc,
    # each pushes the one before it out, final: 2 x 0.236 - 0.031 = 0.44, then the third
    # reading's push makes it 0.68 > 0.619, occupied.
    grid.add_many(ReadingBatch.from_readings(_front(1.0 + k, sensor=1 + k) for k in range(3)))
    grid.add(_front(5.0))
    # Sensor 0's echo lies on a band the map marks already: it gets its spread value only.
    assert grid.live_log_odds[i, j] == pytest.approx(SPREAD_AT_FACE)
    assert grid.log_odds[i, j] == pytest.approx(FREE_AT_FACE + 4 * SPREAD_AT_FACE, abs=1e-6)


def test_the_mark_goes_where_the_map_makes_the_echo_likely_when_its_middle_is_not() -> None:
    """Fig. 2's door: a sensor hears a jamb near the edge of its beam; the arc's middle lies in
    the doorway, where the map holds nothing, while the jamb is already likely (not yet
    occupied) from another sensor's echo. The mark goes to the jamb, not into the doorway.
    (Without side lobes: with them the likeliest cells of this scene lie past the beam's edge,
    ``test_carved_side_lobes.py``.) With the 0.2 m mark (``mark_length=None``), for which
    these numbers were worked out."""
    grid = CarvedGrid(H, BOUNDS, params=CarvedGridParams(side_lobes=0.0, mark_length=None))
    _ring_hears_nothing(grid)
    # Sensor 1, turned 20° up, hears something at FACE_X; it fires again (backwards), so this
    # echo is spread only: 0.236 on its band, bearings 8.75..31.25° widened by half a cell at
    # 1.825 m (0.785°). It overlaps sensor 0's band (|bearing| <= 12.03°) at 7.96..12.03°.
    grid.add(Reading(1.0, 1, 0.0, ROW_Y, math.radians(20.0), FACE_X))
    grid.add(Reading(1.1, 1, 0.0, ROW_Y, math.pi, 0.3))
    # Sensor 0 hears the same range straight ahead: its newest echo, explained by no occupied
    # cell (0.236 < 0.619 on the overlap). Its middle unit (±3.14°, ±3.92° widened) holds only
    # the ring's free space (< 0), the overlap 0.236 minus the ring's faded free space: the
    # whole hit goes to the overlap's most likely cell (bearing 7.96..12.03°), drawn over
    # ±3.14° around it, clipped at the interval's end (11.25°), widened by 0.785°.
    grid.add(Reading(1.2, 0, 0.0, ROW_Y, 0.0, FACE_X))
    live = grid.live_log_odds
    middle = _cell(grid, FACE_X, ROW_Y)
    # The middle keeps sensor 0's spread value (it held a whole hit, 0.847, before).
    assert live[middle] == pytest.approx(SPREAD_AT_FACE)
    assert trinary(grid)[middle] != OCCUPIED
    # Cell (1.775, 0.325): 1.8002 m from the sensor (on both bands: |1.8002 - 1.825| <= 0.05),
    # bearing atan(0.3 / 1.775) = 9.593°, inside the mark for any bearing of the likeliest
    # cell in 7.96..12.03° (its lower end at most 12.03 - 3.14 - 0.785 = 8.1°). Both echoes'
    # spread values plus the mark's rise to a whole hit: 0.236 + 0.236 + (0.847 - 0.236).
    jamb = _cell(grid, 1.775, 0.325)
    assert live[jamb] == pytest.approx(L_HIT + SPREAD_AT_FACE)
    # The ring's sensor 0 passed it: γ = 1 - (2 x 9.593 / 22.5)², fade at 1.8002 m.
    alpha = math.atan2(0.3, 1.775)
    d = math.hypot(1.775, 0.3)
    ring = (1.0 - (2.0 * alpha / PHI) ** 2) * 0.5 * (1.0 - math.tanh(2.0 * (d - 1.2))) * L_MISS
    assert grid.log_odds[jamb] == pytest.approx(L_HIT + SPREAD_AT_FACE + ring, abs=1e-6)
    assert trinary(grid)[jamb] == OCCUPIED
    # Clipped at the interval's end: cell (1.775, 0.425), bearing atan(0.4 / 1.775) = 12.70°,
    # 1.8195 m away, lies on sensor 1's band only (sensor 0's ends at 12.03° widened) and keeps
    # its spread value; an unclipped mark (±3.14° around a cell at 9.6-12°) would reach it (review
    # rev10).
    assert live[_cell(grid, 1.775, 0.425)] == pytest.approx(SPREAD_AT_FACE)


def test_the_default_point_mark_also_goes_to_the_jamb_not_into_the_doorway() -> None:
    """The scene above with the default mark, the point's own cell (``DEFAULT_MARK_LENGTH``):
    the whole hit still leaves the doorway's middle for the overlap of the two bands (bearings
    7.96..12.03°), and covers no more than the likeliest cell and its neighbour (the point is
    drawn half a cell wider each side: ±0.785° at 1.825 m, under one cell's 1.57°)."""
    grid = CarvedGrid(H, BOUNDS, params=CarvedGridParams(side_lobes=0.0))
    _ring_hears_nothing(grid)
    grid.add(Reading(1.0, 1, 0.0, ROW_Y, math.radians(20.0), FACE_X))
    grid.add(Reading(1.1, 1, 0.0, ROW_Y, math.pi, 0.3))
    grid.add(Reading(1.2, 0, 0.0, ROW_Y, 0.0, FACE_X))
    live = grid.live_log_odds
    assert live[_cell(grid, FACE_X, ROW_Y)] == pytest.approx(SPREAD_AT_FACE)
    # The cells holding sensor 0's whole hit over sensor 1's spread value.
    marked = np.argwhere(np.isclose(live, L_HIT + SPREAD_AT_FACE))
    assert 1 <= len(marked) <= 2
    xs, ys = grid.cell_centers()
    for row, col in marked:
        bearing = math.degrees(math.atan2(ys[row] - ROW_Y, xs[col]))
        assert 7.96 - 0.8 <= bearing <= 12.03 + 0.8  # the overlap, widened by half a cell
    # Nothing else ahead is a whole hit (sensor 1's backward echo at 0.3 m, a whole hit as any
    # arc shorter than L, lies behind): a mark of 0.2 m would cover 3-4 cells.
    ahead = xs[None, :] > 1.0
    assert np.count_nonzero((live >= L_HIT - 1e-9) & ahead) == len(marked)


# -- frequent reads: the same map, cheaper ------------------------------------------------------

def _random_batches(readings: list[Reading], rng: np.random.Generator,
                    largest: int) -> list[ReadingBatch]:
    """``readings`` in order, in batches of 1 to ``largest`` readings drawn by ``rng``."""
    batches, start = [], 0
    while start < len(readings):
        size = int(rng.integers(1, largest + 1))
        batches.append(ReadingBatch.from_readings(readings[start:start + size]))
        start += size
    return batches


def _ring_stream(n: int, seed: int, no_echo: bool = False,
                 spin: float = 0.0) -> list[ReadingBatch]:
    """A ring of 8 sensors on a robot driving along a corridor (walls at y = ±1.2 m, an end wall
    at x = 3.3 m), ranges jittered; batches of 1-7 readings. With ``no_echo`` some firings
    hear nothing (range +inf, max range 3 m); ``spin`` turns the ring by that many radians a
    reading (so that arcs cross at angles ATM keeps)."""
    rng = np.random.default_rng(seed)
    readings = []
    for k in range(n):
        sensor = k % 8
        x = -0.3 + 0.02 * k / 8
        theta = sensor * math.pi / 4 + spin * k + float(rng.normal(0.0, 0.02))
        c, s = math.cos(theta), math.sin(theta)
        hits = [d for d in ((1.2 / s) if s > 1e-9 else math.inf,
                            (-1.2 / s) if s < -1e-9 else math.inf,
                            ((3.3 - x) / c) if c > 1e-9 else math.inf) if d > 0]
        r = min(hits) + float(rng.normal(0.0, 0.01))
        if no_echo and (r > 3.0 or rng.random() < 0.1):
            readings.append(Reading(t=0.04 * k, sensor=sensor, x=x, y=0.0, theta=theta,
                                    range=math.inf, max_range=3.0))
        else:
            readings.append(Reading(t=0.04 * k, sensor=sensor, x=x, y=0.0, theta=theta,
                                    range=min(r, 3.4)))
    return _random_batches(readings, rng, 7)


class _AskEveryArc(CarvingMethod):
    """Plain carving, but a subclass: the grid asks its estimates for every live arc at every
    read (it cannot know that they depend on the carving state alone)."""


class _AskEveryArcCombined(CombinedMethod):
    """Combined carving, but a subclass: asked for every live arc at every read."""


@pytest.mark.parametrize(("seed", "no_echo", "profile", "name"),
                         [(0, False, 0.0, "carve"), (1, True, 0.0, "carve"),
                          (2, False, 1.0, "carve"), (0, False, 0.0, "combined"),
                          (1, True, 0.0, "combined")])
def test_reading_only_the_changed_arcs_gives_the_map_of_asking_every_arc(
        seed: int, no_echo: bool, profile: float, name: str) -> None:
    params = CarvedGridParams(band_profile=profile)
    config = MethodConfig(history_size=40, max_incidence=math.radians(30.0))
    asker = {"carve": _AskEveryArc, "combined": _AskEveryArcCombined}[name]
    fast = CarvedGrid(H, BOUNDS, method=make_method(name, config), params=params)
    full = CarvedGrid(H, BOUNDS, method=asker(
        history_size=40, max_incidence=math.radians(30.0)), params=params)
    assert fast._carving is not None  # the two read paths
    assert full._carving is None
    for batch in _ring_stream(600, seed, no_echo):
        fast.add_many(batch)
        full.add_many(batch)
        assert np.array_equal(fast.log_odds, full.log_odds)  # bit for bit, at every read
    assert np.count_nonzero(fast.trinary() == OCCUPIED) > 20  # the walls are there


def _wandering_stream(n: int, seed: int) -> list[ReadingBatch]:
    """A ring of 8 sensors on a robot wandering in a 4.3 m x 2.4 m room (its heading a random
    walk, 2 cm a reading), some firings silent; batches of 1-40 readings. Its arcs cross at the
    angles ATM keeps, so combined carving places many points by ATM."""
    rng = np.random.default_rng(seed)
    readings, x, y, heading = [], 0.0, 0.0, 0.0
    for k in range(n):
        heading += float(rng.normal(0.0, 0.15))
        x = min(max(x + 0.02 * math.cos(heading), -0.8), 2.5)
        y = min(max(y + 0.02 * math.sin(heading), -0.8), 0.8)
        theta = heading + (k % 8) * math.pi / 4 + float(rng.normal(0.0, 0.02))
        c, s = math.cos(theta), math.sin(theta)
        hits = [d for d in ((1.2 - y) / s if s > 1e-9 else math.inf,
                            (-1.2 - y) / s if s < -1e-9 else math.inf,
                            (3.3 - x) / c if c > 1e-9 else math.inf,
                            (-1.0 - x) / c if c < -1e-9 else math.inf) if d > 0]
        r = min(hits) + float(rng.normal(0.0, 0.01))
        silent = r > 3.0 or rng.random() < 0.15
        readings.append(Reading(t=0.04 * k, sensor=k % 8, x=x, y=y, theta=theta,
                                range=math.inf if silent else min(max(r, 0.2), 3.4),
                                max_range=3.0))
    return _random_batches(readings, rng, 40)


def test_reading_only_the_changed_arcs_of_combined_carving_with_atm_points(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Combined carving's read shortcut where ATM places points and its crossing store has to
    grow (one column to start with): an arc whose carving state and kept crossings did not change
    keeps its interval, bit for bit the map of asking every arc."""
    from sonarcarve.maps import PointSource
    from sonarcarve.methods import atm

    monkeypatch.setattr(atm, "INITIAL_COLUMNS", 1)
    config = MethodConfig(history_size=40, max_incidence=math.radians(20.0))
    fast = CarvedGrid(H, (-1.5, -1.5, 3.5, 1.5), method=make_method("combined", config))
    full = CarvedGrid(H, (-1.5, -1.5, 3.5, 1.5), method=_AskEveryArcCombined(
        history_size=40, max_incidence=math.radians(20.0)))
    by_atm = 0
    for batch in _wandering_stream(800, 0):
        fast.add_many(batch)
        full.add_many(batch)
        assert np.array_equal(fast.log_odds, full.log_odds)
        slots = full.method.history.slots()
        by_atm += int(np.count_nonzero(full.method.estimates(slots).source == PointSource.ATM))
    assert by_atm > 100  # ATM's points were read, not only carving's
    assert fast.method.models[1].bearings.shape[1] > 1  # the store grew


@pytest.mark.parametrize(("no_echo", "fresh"), [(False, True), (True, True), (True, False)])
def test_a_map_read_after_every_batch_is_the_map_read_once(no_echo: bool, fresh: bool) -> None:
    batches = _ring_stream(600, 3, no_echo)
    config = MethodConfig(history_size=40, max_incidence=math.radians(30.0))
    params = CarvedGridParams(fresh_arcs=fresh)
    often = CarvedGrid(H, BOUNDS, method=make_method("carve", config), params=params)
    once = CarvedGrid(H, BOUNDS, method=make_method("carve", config), params=params)
    for batch in batches:
        often.add_many(batch)
        often.refresh()
        once.add_many(batch)
    # The overlays are sums of additions and removals, in another order: equal up to rounding
    # (float64 for the spread arcs, float32 for the points), and the classification the same.
    tolerance = 1e-6 if fresh else 1e-12
    assert np.allclose(often.log_odds, once.log_odds, rtol=0.0, atol=tolerance)
    assert np.array_equal(often.trinary(), once.trinary())


def test_the_cheap_bearing_test_decides_as_the_arctangent() -> None:
    from sonarcarve.grids.scan import bearing_off, cos_bound, within

    rng = np.random.default_rng(0)
    cases = 0
    for _ in range(3000):
        mid = float(rng.uniform(-2 * math.pi, 2 * math.pi))
        half = float(rng.choice([rng.uniform(0.001, 0.4), rng.uniform(0.4, 3.2)]))
        # Points at random bearings, and at the interval's edges give or take 1e-17..1e-6 rad.
        edge = mid + float(rng.choice([-1.0, 1.0])) * half
        bearings = [float(rng.uniform(-math.pi, math.pi))] + [
            edge + float(rng.choice([-1.0, 1.0])) * 10.0 ** float(rng.uniform(-17, -6))
            for _ in range(4)]
        for bearing in bearings:
            d = float(rng.uniform(0.1, 6.0))
            dx, dy = d * math.cos(bearing), d * math.sin(bearing)
            d = math.sqrt(dx * dx + dy * dy)
            exact = abs(bearing_off(dx, dy, mid)) <= half
            assert within(dx, dy, d, mid, half, math.cos(mid), math.sin(mid),
                           cos_bound(half)) == exact
            cases += 1
    assert cases == 15000


def test_the_default_method_is_combined_carving(monkeypatch: pytest.MonkeyPatch) -> None:
    """Made without a method, the grid runs carving and ATM together (combined) with
    specular-aware carving at 20°, the measured choice of
    :data:`~sonarcarve.grids.carved.DEFAULT_METHOD`."""
    monkeypatch.undo()  # the module's own defaults, not those of the carving_alone fixture
    grid = CarvedGrid(H, BOUNDS)
    assert isinstance(grid.method, CombinedMethod)
    assert grid.method.max_incidence == pytest.approx(math.radians(20.0), abs=1e-15)


def _mark_scene(sign: float) -> CarvedGrid:
    """The scene above without the ring (review rev10): sensor 1's echo, turned ``sign`` x 20°,
    spread only; then sensor 0's echo straight ahead. Every likely cell of sensor 0's band
    holds the same spread value (0.236), up to rounding."""
    grid = CarvedGrid(H, BOUNDS)
    grid.add(Reading(1.0, 1, 0.0, ROW_Y, sign * math.radians(20.0), FACE_X))
    grid.add(Reading(1.1, 1, 0.0, ROW_Y, math.pi, 0.3))
    grid.add(Reading(1.2, 0, 0.0, ROW_Y, 0.0, FACE_X))
    return grid


def test_the_mark_among_equally_likely_cells_does_not_depend_on_the_grids_orientation() -> None:
    # The two scenes are mirror images about the row y = ROW_Y (row 30: centres -1.475 + 0.05 i),
    # so their maps must be too. Among cells equally likely the mark goes to the one nearest the
    # middle; taking the first cell the scan meets put it at the lowest row of the overlap, 4
    # cells off the mirror image (+4.70..+11.15° above, -11.15..-7.80° below).
    above, below = _mark_scene(+1.0).log_odds, _mark_scene(-1.0).log_odds
    centre = 30
    rows = np.arange(1, above.shape[0])
    np.testing.assert_allclose(above[rows], below[2 * centre - rows], atol=1e-6)


def test_the_mark_does_not_depend_on_when_the_map_is_read() -> None:
    # Review rev10's case: a third sensor's echoes cross sensor 0's band at 7-13°, leaving cells
    # equal up to the rounding of live's additions and removals, which depends on the reads.
    # Read after every reading or once at the end: the same map up to that rounding.
    readings = [
        Reading(1.0, 1, 0.0, ROW_Y, 0.3490658503988659, 1.825),
        Reading(1.1, 1, 0.0, ROW_Y, math.pi, 0.3),
        Reading(1.2, 2, 2.7923609711293373, -0.7872433751161301, 2.454722562987415,
                1.4331160031221999),
        Reading(1.3, 2, 2.7923609711293373, -0.7872433751161301, 2.454722562987415,
                1.485792877820878),
        Reading(1.4, 2, 2.7923609711293373, -0.7872433751161301, 5.596315216577208, 0.3),
        Reading(1.5, 0, 0.0, ROW_Y, 0.0, 1.825),
    ]
    config = MethodConfig(max_incidence=math.radians(20.0))
    often = CarvedGrid(H, BOUNDS, method=make_method("carve", config))
    once = CarvedGrid(H, BOUNDS, method=make_method("carve", config))
    for reading in readings:
        often.add(reading)
        often.refresh()
    once.add_many(ReadingBatch.from_readings(readings))
    np.testing.assert_allclose(often.log_odds, once.log_odds, atol=1e-6)
    np.testing.assert_array_equal(often.trinary(), once.trinary())

