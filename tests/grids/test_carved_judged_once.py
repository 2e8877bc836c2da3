"""A read judges a fresh arc again only where its reach changed (2026-12-05, helper rd17): every
cell whose ``base``, ``live`` or ``heard`` changed lies in a marked tile
(:mod:`sonarcarve.grids.carved.tiles`), the maps are those of a grid that judges every fresh arc
at every read, bit for bit, and an arc whose reach no marked tile touches is indeed not judged
again. The expected maps come from the grid with its records of past judgments wiped before each
read (the path every read took before), never from the skipping itself."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from sonarcarve.grids import CarvedGrid, CarvedGridParams
from sonarcarve.grids.carved.tiles import TILE_SHIFT, marked, next_read
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.readings import Reading, ReadingBatch

VARIANTS = {
    "default": CarvedGridParams(),
    "side lobes": CarvedGridParams(side_lobes=2.0, side_lobe_range=math.inf),
    "profile": CarvedGridParams(band_profile=1.5, mark_length=None),
}


Bounds = tuple[float, float, float, float]


@pytest.fixture(scope="module")
def log() -> tuple[ReadingBatch, Bounds]:
    """40 m of the office tour (about 1,600 readings) and the bounds of what they reach."""
    readings = run_simulation(Scenario("office", 1, max_length=40.0)).readings
    reach = 6.0
    return readings, (float(readings.x.min()) - reach, float(readings.y.min()) - reach,
                      float(readings.x.max()) + reach, float(readings.y.max()) + reach)


def _batches(batch: ReadingBatch, seed: int) -> list[ReadingBatch]:
    """``batch`` cut into blocks of 1 to 37 readings (the history of 60 arcs wraps)."""
    rng = np.random.default_rng(seed)
    parts, start = [], 0
    while start < len(batch):
        size = int(rng.choice([1, 1, 2, 3, 5, 5, 9, 37]))
        parts.append(batch[start:start + size])
        start += size
    return parts


def _grid(bounds: Bounds, params: CarvedGridParams) -> CarvedGrid:
    method = make_method("combined", MethodConfig(history_size=60,
                                                  max_incidence=math.radians(20.0)))
    return CarvedGrid(0.1, bounds, method=method, params=params)


def _state(grid: CarvedGrid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return grid._base.copy(), grid._live.copy(), grid._heard.copy()


def _assert_marked(grid: CarvedGrid, before: tuple[np.ndarray, ...]) -> int:
    """Every cell whose base, live or heard differs from ``before`` lies in a marked tile;
    returns how many changed."""
    changed = np.zeros(grid.shape, dtype=bool)
    for old, new in zip(before, _state(grid), strict=True):
        changed |= old != new
    rows, cols = np.nonzero(changed)
    assert marked(grid._tiles)[rows >> TILE_SHIFT, cols >> TILE_SHIFT].all()
    return len(rows)


@pytest.mark.parametrize("variant", VARIANTS)
def test_every_changed_cell_lies_in_a_marked_tile(log: tuple[ReadingBatch, Bounds],
                                                   variant: str) -> None:
    # Fresh arcs off: the reads redraw the live arcs and never clear the tiles, so the
    # redraws' marks are seen too; the test clears them after each check.
    batch, bounds = log
    params = VARIANTS[variant]
    for fresh in (False, True):
        grid = _grid(bounds, dataclasses.replace(params, fresh_arcs=fresh))
        changed = 0
        for k, part in enumerate(_batches(batch, 3)):
            before = _state(grid)
            grid.add_many(part)  # the fold, the arcs leaving the history
            if not fresh and k % 2:
                grid.refresh()  # the live arcs' redraws
            changed += _assert_marked(grid, before)
            if fresh and k % 2:
                grid.refresh()  # clears the tiles after judging
                assert not marked(grid._tiles).any()
            elif not fresh:
                next_read(grid._tiles)
        assert changed > 10_000


@pytest.mark.parametrize("variant", VARIANTS)
def test_the_maps_are_those_of_judging_every_fresh_arc_at_every_read(
        log: tuple[ReadingBatch, Bounds], variant: str) -> None:
    batch, bounds = log
    skipping, judging = _grid(bounds, VARIANTS[variant]), _grid(bounds, VARIANTS[variant])
    rng = np.random.default_rng(8)
    reads = 0
    for part in _batches(batch, 4):
        for grid in (skipping, judging):
            grid.add_many(part)
        if rng.random() < 0.7:
            judging._judged_seq[:] = -1  # no judgment on record: every fresh arc judged
            for grid in (skipping, judging):
                grid.refresh()
            reads += 1
            for name in ("_base", "_live", "_points", "_heard", "_pdrawn", "_pseq"):
                a, b = getattr(skipping, name), getattr(judging, name)
                np.testing.assert_array_equal(a.view(np.uint8), b.view(np.uint8), err_msg=name)
    assert reads > 100
    np.testing.assert_array_equal(skipping.trinary(), judging.trinary())


def test_a_fresh_arc_whose_reach_no_marked_tile_touches_is_not_judged_again() -> None:
    # One echo nothing explains: its point is marked. A wall written into base behind the
    # tiles' back (no tile marked) would explain it, but the read does not judge it again; once
    # the tiles say its reach changed, it is judged and its point goes.
    grid = CarvedGrid(0.1, (0.0, 0.0, 2.0, 1.0))
    grid.add(Reading(t=0.0, sensor=0, x=0.05, y=0.55, theta=0.0, range=1.0))
    assert grid.trinary()[5, 10] == 100
    point = grid.live_log_odds[5, 10]
    grid._base[4:7, 9:12] = 3.0  # occupied without the arc's own share
    grid._stale = True
    assert grid.live_log_odds[5, 10] == point  # not judged again: the point stays
    grid._tiles[:-1] = grid._tiles[-1, 0]  # every tile marked
    grid._stale = True
    assert grid.live_log_odds[5, 10] < point  # judged: explained, the point is gone
