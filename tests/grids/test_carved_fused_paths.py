"""The carved grid's compiled bookkeeping against the numpy and Python it replaced (2026-12-04,
helper rd16): the bands' intervals from the estimates (:func:`intervals`,
:func:`carving_intervals`) bit for bit, their store by slot (:func:`store_intervals`, review
rev16), which newest echoes are fresh (``_fresh``) by its definition, the model as the kernels
take it (an array, :func:`model_array`), and (2026-12-05, helper rd17) a batch's columns for the
fold (:func:`batch_columns`). The expected values come from the old code, copied here,
or from the definition, never from the new code."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from sonarcarve.geometry.fate import ALIVE
from sonarcarve.grids import CarvedGrid, CarvedGridParams
from sonarcarve.grids.carved.intervals import carving_intervals, intervals, store_intervals
from sonarcarve.grids.carved.kernels import batch_columns
from sonarcarve.grids.carved.model import Model, model_array, model_from
from sonarcarve.grids.carved.periods import FiringPeriods
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.methods.base import Estimates, arc_point
from sonarcarve.methods.carving import CarvingModel
from sonarcarve.readings import ReadingBatch
from sonarcarve.typing import FloatArray

BOUNDS = (-3.0, -3.0, 3.0, 3.0)


def _numpy_intervals(x: FloatArray, y: FloatArray, est: Estimates) -> tuple[FloatArray, ...]:
    """``intervals`` as it was written in numpy before 2026-12-04."""
    weight = np.ones(len(x)) if est.confidence is None else np.where(
        np.isnan(est.confidence), 1.0, np.clip(est.confidence, 0.0, 1.0))
    bearing = np.arctan2(est.xy[:, 1] - y, est.xy[:, 0] - x)
    half = 0.5 * est.width
    weight = np.where(est.alive, weight, 0.0)
    dead = ~(weight > 0.0) | np.isnan(bearing) | np.isnan(half)
    bearing = np.where(dead, 0.0, bearing)
    half = np.where(dead, 0.0, half)
    weight = np.where(dead, 0.0, weight)
    return bearing - half, bearing + half, weight.astype(np.float64)


def _random_estimates(n: int, seed: int, confidence: bool) -> tuple[FloatArray, FloatArray,
                                                                     Estimates]:
    """Arcs of random origins, points, widths and fates, with NaN points and widths, and (with
    ``confidence``) confidences below 0, above 1 and NaN."""
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(-5.0, 5.0, n), rng.uniform(-5.0, 5.0, n)
    xy = np.column_stack((x + rng.normal(0.0, 2.0, n), y + rng.normal(0.0, 2.0, n)))
    xy[rng.random(n) < 0.1] = np.nan
    xy[rng.random(n) < 0.05] = np.column_stack((x, y))[:1]  # some at an origin
    width = rng.uniform(0.0, 0.6, n)
    width[rng.random(n) < 0.1] = np.nan
    conf = None
    if confidence:
        conf = rng.uniform(-0.3, 1.3, n)
        conf[rng.random(n) < 0.15] = np.nan
    est = Estimates(alive=rng.random(n) < 0.8, processed=np.ones(n, dtype=bool), xy=xy,
                    width=width, max_error=np.zeros(n), source=np.zeros(n, dtype=np.int8),
                    confidence=conf)
    return x, y, est


@pytest.mark.parametrize("confidence", [False, True])
@pytest.mark.parametrize("n", [0, 1, 5, 257])
def test_intervals_are_the_numpy_versions_bits(confidence: bool, n: int) -> None:
    for seed in range(4):
        x, y, est = _random_estimates(n, seed, confidence)
        got, want = intervals(x, y, est), _numpy_intervals(x, y, est)
        for g, w in zip(got, want, strict=True):
            assert g.dtype == np.float64
            np.testing.assert_array_equal(g.view(np.int64), w.view(np.int64))  # signs of 0 too


def test_carving_intervals_are_the_numpy_intervals_of_carvings_estimates() -> None:
    rng = np.random.default_rng(3)
    n = 400
    batch = ReadingBatch.from_arrays(
        t=np.arange(n) * 0.05, sensor=rng.integers(0, 8, n), x=rng.uniform(-1.0, 1.0, n),
        y=rng.uniform(-1.0, 1.0, n), theta=rng.uniform(-math.pi, math.pi, n),
        range=rng.uniform(0.3, 2.5, n))
    method = make_method("carve", MethodConfig(history_size=120))
    method.add_many(batch)
    (model,) = method.models
    assert isinstance(model, CarvingModel)
    slots = method.history.slots()
    assert np.count_nonzero(model.status[slots] != ALIVE) > 0  # dead arcs are among them
    h = method.history
    got = carving_intervals(h, model, slots)
    want = _numpy_intervals(h.x[slots], h.y[slots], method.estimates(slots))
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(g.view(np.int64), w.view(np.int64))
    # and the point is carving's own: the interval's middle
    np.testing.assert_array_equal(method.estimates(slots).xy,
                                  arc_point(h, slots, 0.5 * (model.lo[slots] + model.hi[slots])))


def _fresh_by_definition(grid: CarvedGrid, newest: dict[int, int], periods: FiringPeriods,
                         latest_t: float) -> np.ndarray:
    """The old ``_fresh``: per sensor its newest reading's arc (-1 when it heard nothing); fresh
    if it is live, heard at or after ``latest - fresh_seconds`` and, with the period rule, after
    ``latest - fresh_periods * period``."""
    history, params = grid.method.history, grid.params
    slots = history.slots()
    first = history.appended - len(slots)
    fresh = np.zeros(len(slots), dtype=bool)
    for seq in newest.values():
        at = seq - first
        if not 0 <= at < len(slots):
            continue
        t = history.t[slots[at]]
        young = t >= latest_t - params.fresh_seconds
        if params.fresh_periods < math.inf:
            period = periods.period(int(history.sensor[slots[at]]))
            young &= t > latest_t - params.fresh_periods * period
        fresh[at] = young
    return fresh


@pytest.mark.parametrize("fresh_periods", [1.1, 3.0, math.inf])
def test_the_fresh_arcs_are_those_of_the_old_definition(fresh_periods: float) -> None:
    # Sensors on their own schedules (some silent firings, some sensors rare), batches of 1-9
    # readings, the grid asked which arcs are fresh after each.
    rng = np.random.default_rng(7)
    grid = CarvedGrid(0.1, BOUNDS, method=make_method("carve", MethodConfig(history_size=30)),
                      params=CarvedGridParams(fresh_periods=fresh_periods, fresh_seconds=0.9))
    newest: dict[int, int] = {}
    periods = FiringPeriods()
    latest, seq, t, checked = -math.inf, 0, 0.0, 0
    for _ in range(150):
        n = int(rng.integers(1, 10))
        t_batch = t + np.cumsum(rng.choice([0.0, 0.05, 0.1, 0.4], n))
        t = float(t_batch[-1])
        sensor = rng.choice([0, 1, 2, 3, 3, 3, 9, 40], n)
        r = rng.uniform(0.3, 2.0, n)
        silent = rng.random(n) < 0.15
        r[silent] = np.inf
        batch = ReadingBatch.from_arrays(
            t=t_batch, sensor=sensor, x=np.zeros(n), y=np.zeros(n),
            theta=rng.uniform(-math.pi, math.pi, n), range=r,
            max_range=np.where(silent, 2.5, np.nan))
        grid.add_many(batch)
        for s, quiet in zip(sensor.tolist(), silent.tolist(), strict=True):
            newest[s] = -1 if quiet else seq
            seq += 0 if quiet else 1
        periods.note(sensor.astype(np.int64), t_batch)
        latest = max(latest, t)
        history = grid.method.history
        slots = history.slots()
        seqs = history.appended - len(slots) + np.arange(len(slots), dtype=np.int64)
        got = grid._fresh(slots, seqs)
        want = _fresh_by_definition(grid, newest, periods, latest)
        np.testing.assert_array_equal(got, want)
        checked += int(got.sum())
    assert checked > 50


def test_the_kernels_model_array_is_the_model_field_by_field() -> None:
    # Each field a different number (and ``aware`` both ways): a field read from the wrong
    # place, or a field added to Model and not to model_from, shows.
    unpack = numba.njit(lambda v: model_from(v))
    for aware in (True, False):
        values = {name: 0.5 + k for k, name in enumerate(Model._fields)}
        model = Model(**{**values, "aware": aware})  # type: ignore[arg-type]
        back = unpack(model_array(model))
        assert tuple(back) == tuple(model)
        assert type(back.aware) is bool


def test_store_intervals_stores_the_numpy_intervals_times_the_factors_by_slot() -> None:
    # What the grid stored before (review rev16): intervals() of the estimates, then
    # lo[slots] = ..., weight[slots] = weight * chain[slots]; slots in any order, the others
    # untouched; NaN bearings and widths and dead arcs give zeros.
    rng = np.random.default_rng(4)
    storage, n = 40, 17
    slots = rng.permutation(storage)[:n]
    bearing = rng.uniform(-math.pi, math.pi, n)
    bearing[rng.random(n) < 0.15] = np.nan
    width = rng.uniform(0.0, 0.6, n)
    width[rng.random(n) < 0.15] = np.nan
    alive = rng.random(n) < 0.7
    chain = rng.uniform(0.0, 1.0, storage)
    lo, hi, weight = (np.full(storage, -7.0) for _ in range(3))
    store_intervals(slots, bearing, width, alive, chain, lo, hi, weight)
    dead = ~alive | np.isnan(bearing) | np.isnan(width)
    half = np.where(dead, 0.0, 0.5 * width)
    middle = np.where(dead, 0.0, bearing)
    want_lo, want_hi = np.full(storage, -7.0), np.full(storage, -7.0)
    want_weight = np.full(storage, -7.0)
    want_lo[slots], want_hi[slots] = middle - half, middle + half
    want_weight[slots] = np.where(dead, 0.0, 1.0) * chain[slots]
    for got, want in ((lo, want_lo), (hi, want_hi), (weight, want_weight)):
        np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))
    assert dead.any()
    assert not dead.all()


def _numpy_batch_columns(batch: ReadingBatch, default_width: float, band: float,
                         first_seq: int) -> tuple[np.ndarray, ...]:
    """``CarvedGrid.add_many``'s columns as it worked them out in numpy before 2026-12-05."""
    half = 0.5 * batch.beam_widths(default_width)
    r = batch.range
    no_echo = r == math.inf
    n_echo = len(batch) - int(np.count_nonzero(no_echo))
    if n_echo < len(batch):
        seqs = first_seq + np.cumsum((~no_echo).astype(np.int64)) - 1
        r = np.where(no_echo, batch.max_range + band, r)
    else:
        seqs = first_seq + np.arange(len(batch), dtype=np.int64)
    return half, r, seqs, no_echo, np.array(n_echo)


@pytest.mark.parametrize("n", [1, 5, 64, 257])
@pytest.mark.parametrize("step", [1, 2])
def test_batch_columns_are_the_numpy_ones(n: int, step: int) -> None:
    # Widths given and NaN (the method's default), echoes and no-echo readings (none, some,
    # all), columns with a step (a batch sliced with one), bit for bit.
    rng = np.random.default_rng(n * step)
    for share in (0.0, 0.3, 1.0):
        m = n * step
        r = rng.uniform(0.2, 5.0, m)
        r[rng.random(m) < share] = math.inf
        width = rng.uniform(0.1, 0.6, m)
        width[rng.random(m) < 0.3] = np.nan
        batch = ReadingBatch.from_arrays(
            t=np.arange(m) * 0.01, sensor=np.arange(m) % 7, x=rng.normal(size=m),
            y=rng.normal(size=m), theta=rng.uniform(-3.0, 3.0, m), range=r, beam_width=width,
            max_range=rng.uniform(5.0, 6.0, m))[::step]
        first = int(rng.integers(0, 1000))
        got = batch_columns(batch.beam_width, 0.3927, batch.range, batch.max_range, 0.075,
                            first)
        expected = _numpy_batch_columns(batch, 0.3927, 0.075, first)
        for name, a, b in zip(("half", "reach", "seqs", "no_echo", "echoes"), got, expected,
                              strict=True):
            a, b = (np.ascontiguousarray(np.atleast_1d(v)) for v in (a, b))
            assert a.dtype == b.dtype, name
            np.testing.assert_array_equal(a.view(np.uint8), b.view(np.uint8), err_msg=name)
