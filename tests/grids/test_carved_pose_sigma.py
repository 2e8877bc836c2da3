"""The carved grid's pose_sigma: a reading's free space ends 2σ before its band, and the default
method's range tolerance grows by 2σ; 0 (the default) is the grid as before."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.grids import CarvedGrid, CarvedGridParams, GridError
from sonarcarve.readings import Reading

BOUNDS = (-0.5, -1.0, 3.0, 1.0)


def _grid(sigma: float) -> CarvedGrid:
    """One echo at 2 m straight ahead of (0, 0), 0.1 m cells."""
    grid = CarvedGrid(0.1, BOUNDS, params=CarvedGridParams(pose_sigma=sigma))
    grid.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 2.0, math.radians(22.5)))
    return grid


def _axis_cell(grid: CarvedGrid, x: float) -> tuple[int, int]:
    xs, ys = grid.cell_centers()
    return int(np.argmin(np.abs(ys))), int(np.argmin(np.abs(xs - x)))


def test_free_space_ends_two_sigma_before_the_band() -> None:
    # Band half-width b = (h + ε) / 2 = (0.1 + 0.05) / 2 = 0.075 m: free space reaches 1.925 m
    # on the axis; with σ = 0.1 m it stops at 1.925 - 0.2 = 1.725 m. The cell centred 1.75 m
    # ahead lies between the two, the one at 1.65 m before both.
    plain, wary = _grid(0.0), _grid(0.1)
    between, before = _axis_cell(plain, 1.75), _axis_cell(plain, 1.65)
    assert plain.log_odds[between] < 0.0
    assert wary.log_odds[between] == 0.0
    assert plain.log_odds[before] < 0.0
    assert wary.log_odds[before] == plain.log_odds[before]


def test_the_default_method_widens_its_range_tolerance_by_two_sigma() -> None:
    assert _grid(0.0).method.config.range_tolerance == pytest.approx(0.05)
    assert _grid(0.03).method.config.range_tolerance == pytest.approx(0.05 + 2 * 0.03)


def test_the_default_method_carves_with_the_grid_s_own_range_tolerance() -> None:
    # grid --range-tolerance: one ε for the band and for carving (a noisy sonar widens both),
    # pose_sigma's 2σ on top.
    wide = CarvedGrid(0.1, BOUNDS, params=CarvedGridParams(range_tolerance=0.1))
    assert wide.method.config.range_tolerance == pytest.approx(0.1)
    both = CarvedGrid(0.1, BOUNDS, params=CarvedGridParams(range_tolerance=0.1, pose_sigma=0.03))
    assert both.method.config.range_tolerance == pytest.approx(0.1 + 2 * 0.03)


def test_zero_is_the_default() -> None:
    assert CarvedGridParams().pose_sigma == 0.0
    np.testing.assert_array_equal(_grid(0.0).log_odds, _default_grid().log_odds)


def _default_grid() -> CarvedGrid:
    grid = CarvedGrid(0.1, BOUNDS)
    grid.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 2.0, math.radians(22.5)))
    return grid


@pytest.mark.parametrize("sigma", [-0.01, math.nan, math.inf])
def test_pose_sigma_must_be_finite_and_not_negative(sigma: float) -> None:
    with pytest.raises(GridError, match="pose_sigma"):
        CarvedGridParams(pose_sigma=sigma)


@pytest.mark.parametrize(("tolerance", "sigma"), [(1.01, 0.0), (0.9, 0.06), (0.05, 1e9)])
def test_a_carving_tolerance_past_a_metre_is_refused_up_front(tolerance: float,
                                                              sigma: float) -> None:
    # The grid's method carves with ε + 2σ; past MAX_RANGE_TOLERANCE the method would refuse
    # it with a ConfigError, later and in its own terms.
    with pytest.raises(GridError, match="range_tolerance"):
        CarvedGridParams(range_tolerance=tolerance, pose_sigma=sigma)


def test_a_carving_tolerance_of_exactly_a_metre_is_accepted() -> None:
    params = CarvedGridParams(range_tolerance=0.8, pose_sigma=0.1)
    assert CarvedGrid(0.1, BOUNDS, params=params).method.config.range_tolerance == (
        pytest.approx(1.0))
