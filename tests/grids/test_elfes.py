"""Tests of the occupancy-grid baseline: hand-checked cone updates and a brute-force reference."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pytest

from sonarcarve.errors import SonarcarveError
from sonarcarve.grids.elfes import (
    MAX_CELLS,
    GridError,
    OccupancyGrid,
    SonarConeModel,
    _update_numpy,
)
from sonarcarve.grids.scan import sector_box
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch
from sonarcarve.sim.world import World

#: No distance fade, so that a cell's update is exactly w(α) · logit(p) (Elfes' cone).
ELFES = SonarConeModel(fade_range=math.inf)
H = 0.05


def logit(p: float) -> float:
    return math.log(p / (1.0 - p))


def reading(x: float, y: float, theta: float, r: float, width: float = math.nan) -> Reading:
    return Reading(0.0, 0, x, y, theta, r, width)


def cell_of(grid: OccupancyGrid, x: float, y: float) -> tuple[int, int]:
    """Row and column of the cell that contains ``(x, y)``."""
    return (math.floor((y - grid.bounds[1]) / grid.resolution),
            math.floor((x - grid.bounds[0]) / grid.resolution))


def polar(grid: OccupancyGrid, x: float, y: float,
          theta: float) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Distance and bearing off ``theta`` of every cell centre, seen from ``(x, y)``."""
    xs, ys = grid.cell_centers()
    cx, cy = np.meshgrid(xs, ys)
    d = np.hypot(cx - x, cy - y)
    a = np.angle(np.exp(1j * (np.arctan2(cy - y, cx - x) - theta)))
    return d, a


# -- one reading, by hand ----------------------------------------------------------------------

def test_one_reading_at_a_wall_marks_the_arc_clears_the_cone_and_leaves_the_rest() -> None:
    # Sensor at a cell centre looking along +x at a wall 2 m away: the axis runs through centres.
    grid = OccupancyGrid(H, (-1.0, -1.0, 3.0, 1.0), ELFES)
    x, y, r = 0.025, 0.025, 2.0
    grid.add(reading(x, y, 0.0, r))
    p = grid.probabilities()
    # On the axis w = 1: the cell at the range gets exactly p_hit, a nearer one exactly p_miss.
    assert p[cell_of(grid, x + r, y)] == pytest.approx(0.7, abs=1e-6)
    assert p[cell_of(grid, x + 1.0, y)] == pytest.approx(0.4, abs=1e-6)
    d, a = polar(grid, x, y, 0.0)
    band = (H + ELFES.range_tolerance) / 2  # occupied band half-width (module docstring)
    half = DEFAULT_BEAM_WIDTH / 2
    inner = np.abs(a) < 0.9 * half  # away from the beam's edges, where w -> 0
    on_arc = inner & (np.abs(d - r) < band - 1e-6)
    free = inner & (d < r - band - 1e-6) & (d > 0.0)
    assert on_arc.sum() > 10
    assert free.sum() > 100
    assert np.all(p[on_arc] > 0.5)
    assert np.all(p[free] < 0.5)
    outside = (np.abs(a) > half + 1e-6) | (d > r + band + 1e-6)
    assert np.all(grid.log_odds[outside] == 0.0)
    # The arc's cells are weighted by the angle off the axis, 1 - (2α/φ)², not spread evenly.
    arc_a, arc_l = np.abs(a[on_arc]), grid.log_odds[on_arc]
    np.testing.assert_allclose(arc_l, logit(0.7) * (1 - (arc_a / half) ** 2), rtol=1e-5)


def test_the_ros_distance_fade_scales_an_update_by_the_cells_distance() -> None:
    model = SonarConeModel(fade_range=1.2)
    grid = OccupancyGrid(H, (-1.0, -1.0, 4.0, 1.0), model)
    x, y = 0.025, 0.025
    grid.add(reading(x, y, 0.0, 3.0))
    for distance, p in ((0.5, 0.4), (1.2, 0.4), (3.0, 0.7)):
        fade = 0.5 * (1.0 - math.tanh(2.0 * (distance - 1.2)))
        assert grid.log_odds[cell_of(grid, x + distance, y)] == pytest.approx(
            fade * logit(p), rel=1e-5, abs=1e-7)
    assert model == SonarConeModel()  # the default model is ROS's fade


def test_a_reading_uses_its_own_beam_width_when_it_has_one() -> None:
    narrow, default = (OccupancyGrid(H, (-1.0, -1.0, 3.0, 1.0), ELFES) for _ in range(2))
    narrow.add(reading(0.025, 0.025, 0.0, 2.0, width=0.1))
    default.add(reading(0.025, 0.025, 0.0, 2.0))
    off_axis = cell_of(narrow, 0.025 + 1.0, 0.025 + 0.1)  # 0.1 rad off the axis
    assert narrow.log_odds[off_axis] == 0.0
    assert default.log_odds[off_axis] < 0.0


def test_readings_outside_the_grid_change_only_the_cells_inside() -> None:
    grid = OccupancyGrid(H, (0.0, 0.0, 1.0, 1.0), ELFES)
    grid.add(reading(5.0, 5.0, 0.0, 1.0))  # far away, looking away
    assert not grid.log_odds.any()
    grid.add(reading(-1.0, 0.5, 0.0, 1.5))  # from outside, arc inside
    assert grid.log_odds.max() > 0.0
    assert grid.readings == 2


# -- many readings -----------------------------------------------------------------------------

def test_repeated_readings_converge_monotonically_to_the_clamps() -> None:
    grid = OccupancyGrid(H, (-1.0, -1.0, 3.0, 1.0), ELFES)
    wall, free = cell_of(grid, 2.025, 0.025), cell_of(grid, 1.025, 0.025)
    history = []
    for _ in range(12):
        grid.add(reading(0.025, 0.025, 0.0, 2.0))
        p = grid.probabilities()
        history.append((p[wall], p[free]))
    walls, frees = np.array(history).T
    assert np.all(np.diff(walls) >= 0.0)
    assert np.all(np.diff(frees) <= 0.0)
    # logit(0.97) = 3.48 is reached after 5 hits of logit(0.7) = 0.85; logit(0.12) = -1.99
    # after 5 misses of logit(0.4) = -0.41: both then stay at their clamp.
    assert walls[-1] == pytest.approx(0.97, abs=1e-6)
    assert frees[-1] == pytest.approx(0.12, abs=1e-6)
    assert walls[3] < 0.97
    assert grid.log_odds.max() == pytest.approx(logit(0.97), abs=1e-6)
    assert grid.log_odds.min() == pytest.approx(logit(0.12), abs=1e-6)


def test_readings_through_a_door_clear_the_cells_a_wall_reading_marked() -> None:
    # A wall along y = 2 with a door between x = -0.5 and 0.5 (Fig. 2). From (0, 0) the beam's
    # edge rays meet the jambs, so the echo's arc spans the door. Later readings through the door,
    # from nearer, reach the far wall at y = 5 and their cones cover the door's middle.
    grid = OccupancyGrid(H, (-2.0, -1.0, 2.0, 6.0), ELFES)
    up = math.pi / 2
    grid.add(reading(0.025, 0.0, up, 2.0))
    door = cell_of(grid, 0.025, 2.0)
    assert grid.probabilities()[door] > 0.5
    for y in np.linspace(0.5, 1.2, 8):
        grid.add(reading(0.025, float(y), up, 5.0 - float(y)))
    p = grid.probabilities()
    assert p[door] < 0.5
    xs, _ = grid.cell_centers()
    gap_row = grid.log_odds[cell_of(grid, 0.0, 2.0)[0]]
    assert np.all(gap_row[np.abs(xs - 0.025) < 0.15] < 0.0)  # the middle of the door is free
    assert p[cell_of(grid, 0.025, 5.0)] > 0.5  # the far wall is marked


def test_add_equals_add_many_of_one_reading() -> None:
    one, many = (OccupancyGrid(H, (-1.0, -1.0, 3.0, 1.0)) for _ in range(2))
    r = reading(0.1, -0.2, 0.3, 1.7)
    one.add(r)
    many.add_many(ReadingBatch.from_readings([r]))
    np.testing.assert_array_equal(one.log_odds, many.log_odds)
    many.add_many(ReadingBatch.empty())
    assert many.readings == 1


def _reference(resolution: float, bounds: tuple[float, float, float, float],
               model: SonarConeModel, batch: ReadingBatch) -> npt.NDArray[np.float64]:
    """Every cell of the grid against every reading, straight from the model's definition."""
    grid = OccupancyGrid(resolution, bounds, model)
    # Cell centres from the grid's definition, not from the grid under test.
    rows, cols = grid.shape
    xs = bounds[0] + (np.arange(cols) + 0.5) * resolution
    ys = bounds[1] + (np.arange(rows) + 0.5) * resolution
    band = (resolution + model.range_tolerance) / 2
    l_hit, l_miss, l_min, l_max = (logit(p) for p in (model.p_hit, model.p_miss, model.p_min,
                                                      model.p_max))
    out = np.zeros(grid.shape)
    for x, y, theta, r, phi in zip(batch.x, batch.y, batch.theta, batch.range,
                                   batch.beam_width, strict=True):
        half = (model.beam_width if math.isnan(phi) else phi) / 2
        for i, cy in enumerate(ys):
            for j, cx in enumerate(xs):
                d = math.hypot(cx - x, cy - y)
                a = math.remainder(math.atan2(cy - y, cx - x) - theta, 2 * math.pi)
                if abs(a) > half or d > r + band:
                    continue
                w = (1 - (a / half) ** 2) * 0.5 * (1 - math.tanh(2 * (d - model.fade_range)))
                out[i, j] = min(l_max, max(l_min, out[i, j] + w * (l_miss if d < r - band
                                                                   else l_hit)))
    return out


@pytest.mark.parametrize("resolution", [0.1, 0.27])
def test_compiled_and_numpy_updates_match_a_brute_force_reference(resolution: float) -> None:
    # Wide beams too (up to 2.5 rad), whose bounding box reaches past both arc ends.
    rng = np.random.default_rng(7)
    n = 60
    batch = ReadingBatch.from_arrays(
        t=np.arange(n, dtype=float), sensor=np.zeros(n), x=rng.uniform(-2, 4, n),
        y=rng.uniform(-2, 3, n), theta=rng.uniform(-2 * np.pi, 2 * np.pi, n),
        range=rng.uniform(0.2, 4.0, n),
        beam_width=np.where(rng.random(n) < 0.4, np.nan, rng.uniform(0.05, 2.5, n)))
    bounds = (-1.0, -1.0, 3.0, 2.0)
    for model in (ELFES, SonarConeModel(), SonarConeModel(p_hit=0.9, p_miss=0.2,
                                                           range_tolerance=0.0)):
        expected = _reference(resolution, bounds, model, batch)
        grid = OccupancyGrid(resolution, bounds, model)
        grid.add_many(batch)
        np.testing.assert_allclose(grid.log_odds, expected, atol=1e-5)
        numpy_grid = OccupancyGrid(resolution, bounds, model)
        phi = np.where(np.isnan(batch.beam_width), model.beam_width, batch.beam_width)
        _update_numpy(numpy_grid.log_odds, bounds[0], bounds[1], resolution, batch.x, batch.y,
                      batch.theta, batch.range, phi, numpy_grid.band, model.fade_range,
                      *model.log_odds)
        np.testing.assert_allclose(numpy_grid.log_odds, expected, atol=1e-5)
        assert np.count_nonzero(expected) > 50


def test_the_beam_box_is_the_bounding_box_of_the_sector() -> None:
    # The grid scans the box of the sector r_in = 0 (the beam with its apex) around each beam.
    rng = np.random.default_rng(11)
    for _ in range(300):
        x, y = rng.uniform(-3, 3, 2)
        theta, phi, reach = rng.uniform(-4 * np.pi, 4 * np.pi), rng.uniform(0.01, 3.1), 2.0
        tau = np.linspace(theta - phi / 2, theta + phi / 2, 20001)
        px = np.concatenate(([x], x + reach * np.cos(tau)))
        py = np.concatenate(([y], y + reach * np.sin(tau)))
        expected = (px.min(), py.min(), px.max(), py.max())
        # Sampled every 0.16 mrad: the true extremes lie at most 1e-8 m beyond the samples.
        box = sector_box(float(x), float(y), float(theta - phi / 2), float(theta + phi / 2),
                         0.0, reach)
        np.testing.assert_allclose(box, expected, atol=1e-7)


# -- reading the map ---------------------------------------------------------------------------

def test_occupied_points_are_the_centres_of_the_cells_above_the_threshold() -> None:
    rng = np.random.default_rng(3)
    grid = OccupancyGrid(0.1, (-1.0, -1.0, 3.0, 2.0), ELFES)
    for _ in range(60):
        x, y = rng.uniform(-1, 2, 2).tolist()
        grid.add(reading(x, y, float(rng.uniform(-np.pi, np.pi)), float(rng.uniform(0.3, 2.5))))
    p = grid.probabilities()
    for threshold in (0.5, 0.65, 0.8):
        points = grid.occupied_points(threshold)
        assert points.shape == (np.count_nonzero(p > threshold), 2)
        assert points.shape[0] > 0
        rows = np.floor((points[:, 1] - grid.bounds[1]) / grid.resolution).astype(int)
        cols = np.floor((points[:, 0] - grid.bounds[0]) / grid.resolution).astype(int)
        assert np.all(p[rows, cols] > threshold)
        assert len(set(zip(rows.tolist(), cols.tolist(), strict=True))) == points.shape[0]
        centre_x = grid.bounds[0] + (cols + 0.5) * grid.resolution
        centre_y = grid.bounds[1] + (rows + 0.5) * grid.resolution
        gap = np.hypot(points[:, 0] - centre_x, points[:, 1] - centre_y)
        assert np.all(gap <= grid.resolution * math.sqrt(2) / 2)
    assert grid.occupied_points(0.999).shape == (0, 2)


def test_shape_memory_and_world_bounds() -> None:
    grid = OccupancyGrid(0.1, (0.0, 0.0, 1.0, 0.55))
    assert grid.shape == (6, 10)  # 0.55 m needs 6 rows; exactly 1 m needs 10 columns
    assert grid.nbytes == 6 * 10 * 4
    assert grid.extent == pytest.approx((0.0, 0.0, 1.0, 0.6))
    world = World(np.array([[0.0, 0.0, 4.0, 0.0], [0.0, 0.0, 0.0, 3.0]]))
    fitted = OccupancyGrid.around(world.bounds, 0.25, margin=0.5)
    assert fitted.bounds == (-0.5, -0.5, 4.5, 3.5)
    assert fitted.shape == (16, 20)
    assert "20 x 16 cells" in repr(fitted)
    grid.add(reading(0.05, 0.25, 0.0, 0.6))
    grid.reset()
    assert not grid.log_odds.any()
    assert grid.readings == 0


# -- errors ------------------------------------------------------------------------------------

@pytest.mark.parametrize(("resolution", "bounds"), [
    (0.0, (0, 0, 1, 1)), (-0.1, (0, 0, 1, 1)), (math.nan, (0, 0, 1, 1)),
    (math.inf, (0, 0, 1, 1)), (True, (0, 0, 1, 1)), ("0.1", (0, 0, 1, 1)),
    (0.1, (0, 0, 0, 1)), (0.1, (0, 1, 1, 1)), (0.1, (1, 0, 0, 1)), (0.1, (0, 0, math.nan, 1)),
    (0.1, (0, 0, 1)), (0.1, ("a", 0, 1, 1)), (0.1, None),
    (1e-4, (0, 0, 1000, 1000)),  # 10**14 cells
])
def test_bad_resolution_or_bounds_raise_one_line_grid_errors(resolution: object,
                                                             bounds: object) -> None:
    with pytest.raises(GridError) as info:
        OccupancyGrid(resolution, bounds)  # type: ignore[arg-type]
    assert isinstance(info.value, SonarcarveError)
    assert "\n" not in str(info.value)
    assert str(info.value).startswith("grid: ")


def test_the_cell_limit_is_exact() -> None:
    side = math.isqrt(MAX_CELLS)  # 2**14
    assert OccupancyGrid(1.0, (0, 0, side, side)).shape == (side, side)
    with pytest.raises(GridError, match="MAX_CELLS"):
        OccupancyGrid(1.0, (0, 0, side + 1, side))


@pytest.mark.parametrize("kwargs", [
    {"beam_width": 0.0}, {"beam_width": math.pi}, {"beam_width": math.nan},
    {"range_tolerance": -0.01}, {"range_tolerance": math.inf}, {"range_tolerance": math.nan},
    {"range_tolerance": 1.01},
    {"p_hit": 0.5}, {"p_hit": 1.0}, {"p_miss": 0.5}, {"p_miss": 0.0},
    {"p_min": 0.5}, {"p_max": 0.5}, {"p_max": 1.0}, {"fade_range": 0.0},
    {"fade_range": math.nan},
])
def test_bad_model_parameters_raise_grid_errors(kwargs: dict[str, float]) -> None:
    with pytest.raises(GridError, match=next(iter(kwargs))):
        SonarConeModel(**kwargs)


@pytest.mark.parametrize("name", ["p_hit", "p_miss", "p_min", "p_max"])
def test_a_probability_that_is_no_number_raises_a_grid_error(name: str) -> None:
    # The carved grid's check (one copy, grids/cells.py): a string was a TypeError here.
    with pytest.raises(GridError, match=f"^grid: {name} must lie in .*got '0.3'$"):
        SonarConeModel(**{name: "0.3"})  # type: ignore[arg-type]
    with pytest.raises(GridError, match=r"^grid: threshold must lie in"):
        OccupancyGrid(0.1, (0, 0, 1, 1)).occupied_points("0.5")  # type: ignore[arg-type]


def test_bad_threshold_margin_and_readings_raise() -> None:
    grid = OccupancyGrid(0.1, (0, 0, 1, 1))
    for threshold in (0.0, 1.0, math.nan, 1.5):
        with pytest.raises(GridError, match="threshold"):
            grid.occupied_points(threshold)
    world = World(np.array([[0.0, 0.0, 1.0, 0.0]]))
    with pytest.raises(GridError, match="margin"):
        OccupancyGrid.around(world.bounds, 0.1, margin=-1.0)
    with pytest.raises(GridError, match="ymax > ymin"):
        OccupancyGrid.around(world.bounds, 0.1, margin=0.0)  # a flat world needs a margin
    with pytest.raises(SonarcarveError, match="range"):
        grid.add(reading(0.5, 0.5, 0.0, -1.0))
