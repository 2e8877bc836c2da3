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
from sonarcarve.methods import CarvingMethod, CarvingModel, Estimates, MethodConfig, make_method
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch
from sonarcarve.typing import SlotArray

H = 0.05
BOUNDS = (-0.5, -1.5, 3.5, 1.5)
L_HIT = math.log(0.7 / 0.3)
PHI = DEFAULT_BEAM_WIDTH


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
    grid = CarvedGrid(H, BOUNDS)
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
    grid = CarvedGrid(H, BOUNDS, method=method)
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
    expected = rows * cols * (4 + 8) + 2 * 50 * (6 * 8 + 8)
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
    assert np.array_equal(trinary(elfes) == 0, p < 0.196)
